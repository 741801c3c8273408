use super::super::colliders::{Plane, Surface};
use super::*;
use crate::collide::contact_solver::{hold, separate, HoldParams, SeparateParams};

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
    let e = resolve(
        &[on(0)],
        &mut [0.0; 6],
        &[1.0; 2],
        &MaterialTable::uniform(m(0.5, 0.2)),
        &ResolveParams::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.starts_with("contacts[0].other = Collider(0) is invalid"), "{e}");
}

#[test]
fn separation_moves_in_inverse_mass_proportion() {
    // masses 1 and 3 kg, radii 0.5 each, centres 0.8 apart along x: overlap 0.2 m, shared
    // 3 : 1 (the light one moves 0.15 m, the heavy one 0.05 m); Σ m x is unchanged.
    let mut x = [0.8, 0.0, 0.0, 0.0, 0.0, 0.0];
    let inv_mass = [1.0, 1.0 / 3.0];
    let mut c = [pair(0, 1, [1.0, 0.0, 0.0], 0.2)];
    let stats = separate(&mut c, &mut x, &inv_mass, &SeparateParams::default()).unwrap();
    assert!((x[0] - 0.95).abs() < 1e-15 && (x[3] + 0.05).abs() < 1e-15, "{x:?}");
    assert!((x[0] * 1.0 + x[3] * 3.0 - 0.8).abs() < 1e-15);
    assert!(c[0].overlap.abs() < 1e-15, "{c:?}");
    assert!((stats.max_overlap_before - 0.2).abs() < 1e-15 && stats.max_overlap_after < 1e-15);

    // a pinned partner does not move; half of the overlap per push with fraction 0.5 and
    // a slop of 0.01: after 3 sweeps 0.01 + 0.19/8 is left.
    let mut x = [0.8, 0.0, 0.0, 0.0, 0.0, 0.0];
    let mut c = [pair(0, 1, [1.0, 0.0, 0.0], 0.2)];
    let params = SeparateParams {
        iterations: 3,
        fraction: 0.5,
        slop: 0.01,
    };
    let stats = separate(&mut c, &mut x, &[2.0, 0.0], &params).unwrap();
    assert_eq!(&x[3..], &[0.0; 3]);
    assert!((stats.max_overlap_after - (0.01 + 0.19 / 8.0)).abs() < 1e-15, "{stats:?}");
    assert!((x[0] - (0.8 + 0.19 * 7.0 / 8.0)).abs() < 1e-15, "{x:?}");
}

#[test]
fn a_stack_on_a_floor_separates_over_the_sweeps() {
    // three unit balls of radius 0.5 stacked on the floor z = 0, each sunk 0.1 into the
    // one below (the first into the floor): pushing the middle contact up pushes the top
    // one in deeper, so it takes sweeps; the floor takes everything from the first ball.
    let floor = [Collider::Plane(
        Plane::new([0.0; 3], [0.0, 0.0, 1.0], Surface::default()).unwrap(),
    )];
    let mut x = vec![0.0, 0.0, 0.4, 0.0, 0.0, 1.3, 0.0, 0.0, 2.2];
    let v = [0.0; 9];
    let radius = [0.5; 3];
    let d = super::super::domain::Domain::open(3).unwrap();
    let mut contacts = Vec::new();
    super::super::narrow_phase::sphere_contacts(&x, &v, &radius, &[(0, 1), (1, 2)], &d, 0.0, &mut contacts).unwrap();
    super::super::colliders::collider_contacts(&floor, &x, &v, &radius, 0.0, &mut contacts).unwrap();
    assert_eq!(contacts.len(), 3);
    let mut few = contacts.clone();
    let stats = separate(&mut few, &mut x.clone(), &[1.0; 3], &SeparateParams::default()).unwrap();
    assert!(
        stats.max_overlap_after > 1e-3 && stats.max_overlap_after < stats.max_overlap_before,
        "{stats:?}"
    );
    let params = SeparateParams {
        iterations: 200,
        ..SeparateParams::default()
    };
    let stats = separate(&mut contacts, &mut x, &[1.0; 3], &params).unwrap();
    assert!(stats.max_overlap_after < 1e-12, "{stats:?}");
    for (k, z) in [0.5, 1.5, 2.5].iter().enumerate() {
        assert!((x[3 * k + 2] - z).abs() < 1e-12, "{x:?}");
    }
}

#[test]
fn hold_carries_a_stack_exactly() {
    // Three 1 kg balls stacked on the floor, all given −g h by a step of gravity: the holds
    // are the weights above each contact, 3, 2 and 1 × g h, and every ball ends at rest.
    // Gauss–Seidel converges geometrically along the chain (the contacts are listed top
    // first); given the sweeps, it ends where a sweep changes nothing, and started from
    // those totals the next step takes one sweep.
    let floor = [Collider::Plane(
        Plane::new([0.0; 3], [0.0, 0.0, 1.0], Surface::default()).unwrap(),
    )];
    let up = [0.0, 0.0, 1.0];
    let contacts = [
        pair(2, 1, up, 0.0),
        pair(1, 0, up, 0.0),
        Contact {
            i: 0,
            other: Partner::Collider(0),
            normal: up,
            overlap: 0.0,
            u_n: 0.0,
        },
    ];
    let gh = 9.81e-3;
    let mut v = [0.0, 0.0, -gh, 0.0, 0.0, -gh, 0.0, 0.0, -gh];
    let table = MaterialTable::uniform(m(0.5, 0.0)).with_colliders(&floor);
    let mut impulses = Vec::new();
    let many = HoldParams {
        max_iterations: 1000,
        ..HoldParams::default()
    };
    let stats = hold(&contacts, &[0.0; 3], &mut v, &[1.0; 3], &table, &many, &mut impulses).unwrap();
    assert!(stats.converged && stats.active == 3 && stats.iterations > 50, "{stats:?}");
    assert!(v.iter().all(|c| c.abs() < 1e-17), "{v:?}");
    for (p, load) in impulses.iter().zip([1.0, 2.0, 3.0]) {
        assert!((p[2] - load * gh).abs() < 1e-17 && p[0] == 0.0 && p[1] == 0.0, "{impulses:?}");
    }
    assert!((stats.collider_impulse_sum[2] - 3.0 * gh).abs() < 1e-17);
    let mut v = [0.0, 0.0, -gh, 0.0, 0.0, -gh, 0.0, 0.0, -gh];
    let stats = hold(
        &contacts,
        &[0.0; 3],
        &mut v,
        &[1.0; 3],
        &table,
        &HoldParams::default(),
        &mut impulses,
    )
    .unwrap();
    assert_eq!((stats.iterations, stats.converged), (1, true));
    assert!(v.iter().all(|c| c.abs() < 1e-17), "{v:?}");
}

#[test]
fn hold_totals_shrink_and_stay_in_the_cone() {
    // A 2 kg ball on a floor, v = (3, 0, −1): the normal total is 2 N·s (it stops the
    // approach), friction μ = 0.5 caps the tangential one at 1 N·s against the slide:
    // v = (2.5, 0, 0). Started from 10 N·s upwards (an earlier, heavier load) the total
    // shrinks back to 2: unlike sequential impulses, a hold never keeps pushing a pair
    // apart. A target b = −0.4 lets the ball keep approaching at 0.4 m/s.
    let floor = [Collider::Plane(
        Plane::new([0.0; 3], [0.0, 0.0, 1.0], Surface::default()).unwrap(),
    )];
    let c = [Contact {
        i: 0,
        other: Partner::Collider(0),
        normal: [0.0, 0.0, 1.0],
        overlap: 0.0,
        u_n: 0.0,
    }];
    let table = MaterialTable::uniform(m(0.0, 0.5)).with_colliders(&floor);
    for start in [vec![], vec![[0.0, 0.0, 10.0]]] {
        let mut v = [3.0, 0.0, -1.0];
        let mut impulses = start;
        let stats = hold(&c, &[0.0], &mut v, &[0.5], &table, &HoldParams::default(), &mut impulses).unwrap();
        assert!(stats.converged, "{stats:?}");
        assert!(
            (impulses[0][2] - 2.0).abs() < 1e-15 && (impulses[0][0] + 1.0).abs() < 1e-15,
            "{impulses:?}"
        );
        assert!((v[0] - 2.5).abs() < 1e-15 && v[2].abs() < 1e-15, "{v:?}");
    }
    let mut v = [0.0, 0.0, -1.0];
    let mut impulses = Vec::new();
    hold(&c, &[-0.4], &mut v, &[0.5], &table, &HoldParams::default(), &mut impulses).unwrap();
    assert!(
        (v[2] + 0.4).abs() < 1e-15 && (impulses[0][2] - 1.2).abs() < 1e-15,
        "{v:?} {impulses:?}"
    );
    let e = hold(&c, &[f64::NAN], &mut v, &[0.5], &table, &HoldParams::default(), &mut impulses)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("targets[0] = NaN is invalid"), "{e}");
    let e = hold(&c, &[], &mut v, &[0.5], &table, &HoldParams::default(), &mut impulses)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("targets = 0 values is invalid"), "{e}");
}

#[test]
fn bad_contacts_and_settings_are_named() {
    let table = MaterialTable::uniform(m(0.5, 0.0));
    let p = ResolveParams::default();
    let e = resolve(&[pair(0, 2, [1.0, 0.0, 0.0], 0.0)], &mut [0.0; 6], &[1.0; 2], &table, &p)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("contacts[0] = particle 0 with Particle(2) is invalid"), "{e}");
    let e = resolve(&[], &mut [0.0; 5], &[1.0; 2], &table, &p).unwrap_err().to_string();
    assert!(e.starts_with("v = 5 values is invalid"), "{e}");
    let bad = ResolveParams { max_iterations: 0, ..p };
    let e = resolve(&[], &mut [0.0; 6], &[1.0; 2], &table, &bad).unwrap_err().to_string();
    assert!(e.starts_with("max_iterations = 0 is invalid"), "{e}");
    let bad = ResolveParams {
        restitution_threshold: -1.0,
        ..p
    };
    let e = resolve(&[], &mut [0.0; 6], &[1.0; 2], &table, &bad).unwrap_err().to_string();
    assert!(e.starts_with("restitution_threshold = -1 is invalid"), "{e}");
    let e = Material::new(0.5, f64::NAN).unwrap_err().to_string();
    assert!(e.starts_with("friction = NaN is invalid"), "{e}");
    let bad = SeparateParams {
        fraction: 0.0,
        ..SeparateParams::default()
    };
    let e = separate(&mut [], &mut [0.0; 6], &[1.0; 2], &bad).unwrap_err().to_string();
    assert!(e.starts_with("fraction = 0 is invalid"), "{e}");
}
