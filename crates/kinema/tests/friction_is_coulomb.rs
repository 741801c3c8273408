//! Coulomb friction in the impulse response: a sliding contact's tangential impulse is μ j
//! (the cone's edge), a sticking one stops the tangential relative motion exactly, and either
//! conserves the pair's momentum and removes kinetic energy.
//!
//! Closed forms: normal impulse j = −(1 + e) u_n / (w₁ + w₂); the impulse that stops the
//! sliding is |u_t| / (w₁ + w₂) (no rotation: the effective mass is the same across the
//! normal as along it); the applied one is the smaller of that and μ j.

use kinema::collide::{
    apply_impulse, collider_contacts, resolve, Collider, Contact, Material, MaterialTable, Partner, Plane, ResolveParams, Surface,
};

fn close(a: f64, b: f64, scale: f64) -> bool {
    (a - b).abs() <= 1e-14 * scale
}

fn on_floor(u_n: f64) -> Contact {
    Contact {
        i: 0,
        other: Partner::Collider(0),
        normal: [0.0, 0.0, 1.0],
        overlap: 0.0,
        u_n,
    }
}

#[test]
fn sliding_on_a_floor_is_clamped_at_mu_j() {
    // m = 2 kg, v = (3, 0, −1), e = 0.5: j = 1.5 · 1 · 2 = 3 N·s. Stopping the 3 m/s slide
    // needs 6 N·s; μ = 0.2 allows 0.6 N·s, so it slides on at 3 − 0.6/2 = 2.7 m/s.
    let mut v = [3.0, 0.0, -1.0];
    let imp = apply_impulse(&on_floor(-1.0), &mut v, &[0.5], Material::new(0.5, 0.2).unwrap(), 0.0).unwrap();
    assert!(close(imp.normal, 3.0, 3.0));
    assert!(
        close(imp.tangent, 0.2 * imp.normal, 1.0),
        "j_t = {} vs μ j = {}",
        imp.tangent,
        0.2 * imp.normal
    );
    assert!(close(v[0], 2.7, 3.0) && v[1] == 0.0 && close(v[2], 0.5, 1.0), "{v:?}");
    // KE lost: normal ½ (1 − e²) m u_n² = 0.75 J, tangential j_t (|u_t| − ½ w j_t) = 1.71 J
    assert!(
        close(imp.energy_lost, 0.75 + 0.6 * (3.0 - 0.5 * 0.5 * 0.6), 1.0),
        "{}",
        imp.energy_lost
    );
    let measured = 0.5 * 2.0 * (10.0 - (2.7 * 2.7 + 0.25));
    assert!(close(imp.energy_lost, measured, 10.0));
}

#[test]
fn sticking_stops_the_tangential_motion() {
    // μ = 10: the cone allows 30 N·s, the 6 N·s that stop the slide are applied.
    let mut v = [3.0, -4.0, -1.0];
    let imp = apply_impulse(&on_floor(-1.0), &mut v, &[0.5], Material::new(0.5, 10.0).unwrap(), 0.0).unwrap();
    assert!(
        close(imp.tangent, 10.0, 10.0),
        "stopping |u_t| = 5 m/s of 2 kg: {}",
        imp.tangent
    );
    assert!(imp.tangent < 10.0 * imp.normal);
    assert!(v[0].abs() < 1e-15 && v[1].abs() < 1e-15 && close(v[2], 0.5, 1.0), "{v:?}");
}

#[test]
fn particle_pairs_slide_and_stick_with_the_reduced_mass() {
    // m₁ = 1, m₂ = 4 kg (w = 1.25 /kg), normal x, u_n = −2, u_t = (0, 3, 0), e = 0:
    // j = 2 / 1.25 = 1.6 N·s, stopping needs 3 / 1.25 = 2.4 N·s.
    let c = Contact {
        i: 0,
        other: Partner::Particle(1),
        normal: [1.0, 0.0, 0.0],
        overlap: 0.01,
        u_n: -2.0,
    };
    let v0 = [-1.0, 2.0, 0.5, 1.0, -1.0, 0.5];
    let inv_mass = [1.0, 0.25];
    for (mu, j_t) in [(0.5, 0.8), (1.5, 2.4), (2.4 / 1.6, 2.4)] {
        let mut v = v0;
        let imp = apply_impulse(&c, &mut v, &inv_mass, Material::new(0.0, mu).unwrap(), 0.0).unwrap();
        assert!(
            close(imp.normal, 1.6, 2.0) && close(imp.tangent, j_t, 3.0),
            "μ = {mu}: {imp:?}"
        );
        // relative tangential velocity falls by w j_t, from 3
        let u_t = v[1] - v[4];
        assert!(close(u_t, 3.0 - 1.25 * j_t, 3.0), "μ = {mu}: u_t = {u_t}");
        // momentum unchanged; relative normal velocity 0 (e = 0); z untouched
        for k in 0..3 {
            assert!(close(v[k] + 4.0 * v[3 + k], v0[k] + 4.0 * v0[3 + k], 5.0), "momentum {k}");
        }
        assert!(close(v[0], v[3], 2.0) && v[2] == 0.5 && v[5] == 0.5, "{v:?}");
    }
}

#[test]
fn a_collider_surface_overrides_the_particles_friction() {
    // global μ = 1 would stop the slide; the floor's own μ = 0 lets it slide freely, and
    // its e = 1 bounces it fully.
    let floor = [Collider::Plane(
        Plane::new([0.0; 3], [0.0, 0.0, 1.0], Surface::new(Some(1.0), Some(0.0)).unwrap()).unwrap(),
    )];
    let mut v = vec![3.0, 0.0, -1.0];
    let mut contacts = Vec::new();
    collider_contacts(&floor, &[0.0, 0.0, 0.09], &v, &[0.1], 0.0, &mut contacts).unwrap();
    let table = MaterialTable::uniform(Material::new(0.0, 1.0).unwrap()).with_colliders(&floor);
    let stats = resolve(&contacts, &mut v, &[1.0], &table, &ResolveParams::default()).unwrap();
    assert_eq!(v, vec![3.0, 0.0, 1.0]);
    assert!(stats.kinetic_energy_lost.abs() < 1e-15);
}
