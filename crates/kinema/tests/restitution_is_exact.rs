//! Impulse response against the closed form of a collision along the contact normal.
//!
//! Two bodies of masses m₁, m₂ with normal velocities u₁, u₂ (n from body 2 towards body 1)
//! leave with Newton's restitution law and momentum conservation,
//!
//! ```text
//!   u₁' = (m₁u₁ + m₂u₂ + m₂ e (u₂ − u₁)) / (m₁ + m₂),   u₂' = (m₁u₁ + m₂u₂ + m₁ e (u₁ − u₂)) / (m₁ + m₂)
//! ```
//!
//! their tangential velocities untouched without friction, and a kinetic energy loss of
//! ½ (1 − e²) μ (u₁ − u₂)², μ = m₁m₂/(m₁ + m₂). Against an immovable body (pinned particle,
//! collider) the limit m₂ → ∞ gives u₁' = −e u₁.

use kinema::collide::{
    apply_impulse, collider_contacts, resolve, sphere_contacts, Collider, Contact, Domain, Material, MaterialTable, Partner,
    Plane, ResolveParams, Surface,
};

const RTOL: f64 = 1e-12;

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn axpy(a: f64, x: [f64; 3], y: [f64; 3]) -> [f64; 3] {
    [a * x[0] + y[0], a * x[1] + y[1], a * x[2] + y[2]]
}

fn assert_vec_close(got: &[f64], want: &[f64], scale: f64, what: &str) {
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        assert!((g - w).abs() <= RTOL * scale, "{what}[{k}]: {g} vs {w} (scale {scale})");
    }
}

fn kinetic(v: &[f64], mass: &[f64]) -> f64 {
    mass.iter()
        .enumerate()
        .map(|(i, m)| 0.5 * m * dot(get(v, i), get(v, i)))
        .sum()
}

fn get(v: &[f64], i: usize) -> [f64; 3] {
    [v[3 * i], v[3 * i + 1], v[3 * i + 2]]
}

/// Two overlapping spheres along `n` (body 2 on the −n side of body 1), resolved once; returns
/// the contact, the velocities after and the stats.
fn collide_pair(mass: [f64; 2], v: [[f64; 3]; 2], n: [f64; 3], e: f64) -> (Contact, Vec<f64>, kinema::collide::ResolveStats) {
    let radius = [0.4, 0.25];
    let x1 = [0.3, -0.2, 0.5];
    let x2 = axpy(-(radius[0] + radius[1] - 0.01), n, x1);
    let x = [x1, x2].concat();
    let mut vel = [v[0], v[1]].concat();
    let mut contacts = Vec::new();
    let domain = Domain::open(3).unwrap();
    sphere_contacts(&x, &vel, &radius, &[(0, 1)], &domain, 0.0, &mut contacts).unwrap();
    assert_eq!(contacts.len(), 1);
    let inv_mass = [1.0 / mass[0], 1.0 / mass[1]];
    let table = MaterialTable::uniform(Material::new(e, 0.0).unwrap());
    let stats = resolve(&contacts, &mut vel, &inv_mass, &table, &ResolveParams::default()).unwrap();
    (contacts[0], vel, stats)
}

#[test]
fn head_on_and_oblique_collisions_of_unequal_masses_match_the_closed_form() {
    let oblique = [1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0];
    let cases = [
        // head-on along x
        ([1.0, 0.0, 0.0], [[-3.0, 0.0, 0.0], [1.5, 0.0, 0.0]]),
        // oblique normal, with tangential components on both bodies
        (
            oblique,
            [axpy(-3.0, oblique, [0.7, -0.2, -0.3]), axpy(1.5, oblique, [0.0, 1.0, -1.0])],
        ),
    ];
    for (n, v) in cases {
        for e in [0.0, 0.3, 0.7, 1.0] {
            let (m1, m2) = (2.0, 5.0);
            let (c, after, stats) = collide_pair([m1, m2], v, n, e);
            let n = c.normal;
            let (u1, u2) = (dot(v[0], n), dot(v[1], n));
            assert!(u1 - u2 < 0.0, "the test pair must approach");
            let p = m1 * u1 + m2 * u2;
            let u1_after = (p + m2 * e * (u2 - u1)) / (m1 + m2);
            let u2_after = (p + m1 * e * (u1 - u2)) / (m1 + m2);
            let want = [axpy(u1_after - u1, n, v[0]), axpy(u2_after - u2, n, v[1])].concat();
            let scale = v.iter().flatten().fold(0.0, |m: f64, c| m.max(c.abs()));
            assert_vec_close(&after, &want, scale, &format!("v after, e = {e}, n = {n:?}"));

            // tangential velocities untouched (no friction)
            for (b, &vb) in v.iter().enumerate() {
                let t_before = axpy(-dot(vb, n), n, vb);
                let t_after = axpy(-dot(get(&after, b), n), n, get(&after, b));
                assert_vec_close(&t_after, &t_before, scale, "tangential velocity");
            }
            // momentum, from the velocities
            let before = [0, 1, 2].map(|k| m1 * v[0][k] + m2 * v[1][k]);
            let now = [0, 1, 2].map(|k| m1 * after[k] + m2 * after[3 + k]);
            assert_vec_close(&now, &before, (m1 + m2) * scale, "momentum");
            assert_vec_close(&stats.particle_impulse_sum, &[0.0; 3], (m1 + m2) * scale, "impulse sum");

            // energy: the stat and the measured loss both equal ½ (1 − e²) μ (u₁ − u₂)²
            let mu = m1 * m2 / (m1 + m2);
            let closed = 0.5 * (1.0 - e * e) * mu * (u1 - u2) * (u1 - u2);
            let ke = kinetic(&[v[0], v[1]].concat(), &[m1, m2]);
            let measured = ke - kinetic(&after, &[m1, m2]);
            assert!(
                (stats.kinetic_energy_lost - closed).abs() <= RTOL * ke,
                "{} vs {closed}",
                stats.kinetic_energy_lost
            );
            assert!((measured - closed).abs() <= RTOL * ke, "measured {measured} vs {closed}");
            assert_eq!((stats.impulses, stats.iterations, stats.converged), (1, 2, true));
        }
    }
}

#[test]
fn an_immovable_partner_reflects_the_normal_velocity_times_e() {
    let floor = [Collider::Plane(
        Plane::new([0.0; 3], [0.0, 0.0, 1.0], Surface::default()).unwrap(),
    )];
    for e in [0.0, 0.3, 0.7, 1.0] {
        // a collider: u_n' = −e u_n, tangential (2, 1) unchanged; the collider's impulse is m Δv
        let mass = 3.0;
        let mut v = vec![2.0, 1.0, -4.0];
        let mut contacts = Vec::new();
        collider_contacts(&floor, &[0.0, 0.0, 0.45], &v, &[0.5], 0.0, &mut contacts).unwrap();
        let table = MaterialTable::uniform(Material::new(e, 0.0).unwrap()).with_colliders(&floor);
        let stats = resolve(&contacts, &mut v, &[1.0 / mass], &table, &ResolveParams::default()).unwrap();
        assert_vec_close(&v, &[2.0, 1.0, 4.0 * e], 4.0, "after the floor");
        assert_vec_close(
            &stats.collider_impulse_sum,
            &[0.0, 0.0, mass * 4.0 * (1.0 + e)],
            4.0 * mass,
            "floor impulse",
        );
        let closed = 0.5 * (1.0 - e * e) * mass * 16.0;
        assert!((stats.kinetic_energy_lost - closed).abs() <= RTOL * closed.max(1.0));

        // a pinned particle acts the same; it keeps its (zero) velocity
        let x = [0.0, 0.0, 0.45, 0.0, 0.0, -0.5];
        let mut v = vec![2.0, 1.0, -4.0, 0.0, 0.0, 0.0];
        let mut contacts = Vec::new();
        sphere_contacts(&x, &v, &[0.5, 0.5], &[(0, 1)], &Domain::open(3).unwrap(), 0.0, &mut contacts).unwrap();
        let table = MaterialTable::uniform(Material::new(e, 0.0).unwrap());
        let stats = resolve(&contacts, &mut v, &[1.0 / mass, 0.0], &table, &ResolveParams::default()).unwrap();
        assert_vec_close(&v, &[2.0, 1.0, 4.0 * e, 0.0, 0.0, 0.0], 4.0, "after the pinned ball");
        let from_pinned = [0.0, 0.0, mass * 4.0 * (1.0 + e)];
        assert_vec_close(&stats.pinned_impulse_sum, &from_pinned, 4.0 * mass, "pinned impulse");
        assert_eq!(stats.collider_impulse_sum, [0.0; 3]);
    }
}

#[test]
fn slow_approaches_below_the_threshold_do_not_bounce() {
    // e = 0.8 with a threshold of 0.5 m/s: approaching at 0.3 m/s stops (e = 0), at 0.7 m/s
    // rebounds at 0.56 m/s.
    let floor = Collider::Plane(Plane::new([0.0; 3], [0.0, 1.0, 0.0], Surface::default()).unwrap());
    let material = Material::new(0.8, 0.0).unwrap();
    for (speed, rebound, e_used) in [(0.3, 0.0, 0.0), (0.7, 0.56, 0.8)] {
        let c = Contact {
            i: 0,
            other: Partner::Collider(0),
            normal: [0.0, 1.0, 0.0],
            overlap: 0.0,
            u_n: -speed,
        };
        let mut v = [0.0, -speed, 0.0];
        let imp = apply_impulse(&c, &mut v, &[1.0], material, 0.5).unwrap();
        assert_eq!(imp.restitution, e_used);
        assert!((v[1] - rebound).abs() < 1e-15, "{speed}: {v:?}");
        // the same through the resolver
        let mut v = [0.0, -speed, 0.0];
        let params = ResolveParams {
            restitution_threshold: 0.5,
            ..ResolveParams::default()
        };
        let floors = [floor.clone()];
        resolve(
            &[c],
            &mut v,
            &[1.0],
            &MaterialTable::uniform(material).with_colliders(&floors),
            &params,
        )
        .unwrap();
        assert!((v[1] - rebound).abs() < 1e-15, "{speed}: {v:?}");
    }
    // separating contacts get nothing
    let c = Contact {
        i: 0,
        other: Partner::Collider(0),
        normal: [0.0, 1.0, 0.0],
        overlap: 0.1,
        u_n: 1.0,
    };
    assert!(apply_impulse(&c, &mut [0.0, 1.0, 0.0], &[1.0], material, 0.0).is_none());
}
