use super::super::colliders::{Plane, Surface};
use super::*;

fn m(e: f64, mu: f64) -> Material {
    Material::new(e, mu).unwrap()
}

fn pair(i: usize, j: usize, normal: [f64; 3], overlap: f64) -> Contact {
    Contact {
        i,
        other: Partner::Particle(j),
        normal,
        overlap,
        u_n: 0.0,
        wall_velocity: [0.0; 3],
    }
}

#[test]
fn the_pair_rule_is_max_restitution_and_geometric_mean_friction() {
    let (a, b) = (m(0.2, 0.64), m(0.8, 0.25));
    let ab = Material::combine(a, b);
    assert_eq!((ab.restitution(), ab.friction()), (0.8, 0.4));
    assert_eq!(ab, Material::combine(b, a));
    assert_eq!(Material::combine(b, b), b);
    assert_eq!(Material::combine(a, m(0.0, 0.0)).friction(), 0.0);
}

#[test]
fn colliders_override_only_what_they_set() {
    let floor = |s| Collider::Plane(Plane::new([0.0; 3], [0.0, 0.0, 1.0], s).unwrap());
    let colliders = [floor(Surface::new(Some(0.0), None).unwrap()), floor(Surface::default())];
    let own = [m(0.9, 0.5), m(0.3, 0.1)];
    let table = MaterialTable::uniform(m(0.5, 0.2))
        .with_colliders(&colliders)
        .with_particles(&own);
    let on = |k| Contact {
        other: Partner::Collider(k),
        ..pair(0, 1, [0.0, 0.0, 1.0], 0.0)
    };
    assert_eq!(table.pair(&on(0)), m(0.0, 0.5));
    assert_eq!(table.pair(&on(1)), m(0.9, 0.5));
    assert_eq!(
        table.pair(&pair(0, 1, [1.0, 0.0, 0.0], 0.0)),
        Material::combine(own[0], own[1])
    );
    let global = MaterialTable::uniform(m(0.5, 0.2)).with_colliders(&colliders);
    assert_eq!(global.pair(&on(1)), m(0.5, 0.2));
}

#[test]
fn bad_materials_are_named() {
    let e = Material::new(0.5, f64::NAN).unwrap_err().to_string();
    assert!(e.starts_with("friction = NaN is invalid"), "{e}");
    let e = Material::new(1.5, 0.0).unwrap_err().to_string();
    assert!(e.starts_with("restitution = 1.5 is invalid"), "{e}");
}

#[test]
fn restitution_impulse_follows_newtons_law_and_coulombs_cone() {
    // m_i = 1, m_j = 4 kg (w = 1.25 /kg), normal x, u_n = −2, u_t = (0, 3, 0), e = 0.5,
    // μ = 0.2: j = 1.5 · 2 / 1.25 = 2.4 N·s; stopping the slide needs 3 / 1.25 = 2.4 N·s, the
    // cone allows μ j = 0.48 N·s. Energy: ½ (1 − e²) u_n² / w + j_t (|u_t| − ½ w j_t).
    let c = pair(0, 1, [1.0, 0.0, 0.0], 0.0);
    let v = [-1.0, 2.0, 0.0, 1.0, -1.0, 0.0];
    let imp = restitution_impulse(&c, &v, &[1.0, 0.25], m(0.5, 0.2), 0.0, None).unwrap();
    assert!(
        (imp.normal - 2.4).abs() < 1e-15 && (imp.tangent - 0.48).abs() < 1e-15,
        "{imp:?}"
    );
    assert!(
        (imp.vector[0] - 2.4).abs() < 1e-15 && (imp.vector[1] + 0.48).abs() < 1e-15,
        "{imp:?}"
    );
    let lost = 0.5 * 0.75 * 4.0 / 1.25 + 0.48 * (3.0 - 0.5 * 1.25 * 0.48);
    assert!((imp.energy_lost - lost).abs() < 1e-14, "{imp:?}");
    assert_eq!(imp.restitution, 0.5);
    // below the threshold: e = 0; separating, or both immovable: nothing
    let slow = restitution_impulse(&c, &v, &[1.0, 0.25], m(0.5, 0.0), 2.5, None).unwrap();
    assert_eq!(slow.restitution, 0.0);
    assert!((slow.normal - 1.6).abs() < 1e-15, "{slow:?}");
    let apart = [1.0, 0.0, 0.0, -1.0, 0.0, 0.0];
    assert!(restitution_impulse(&c, &apart, &[1.0, 0.25], m(0.5, 0.2), 0.0, None).is_none());
    assert!(restitution_impulse(&c, &v, &[0.0, 0.0], m(0.5, 0.2), 0.0, None).is_none());
}
