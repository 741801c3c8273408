//! Newton's restitution law in a World (impulse model, continuous detection) against the
//! closed form of a collision along the contact normal.
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
//! collider) the limit m₂ → ∞ gives u₁' = −e u₁. The bodies start a small gap apart, so that
//! the impact falls inside a step and is found there by continuous detection.

mod common;

use kinema::collide::{Plane, Surface};
use kinema::ode::Method;
use kinema::world::CollisionParams;
use kinema::World;

const RTOL: f64 = 1e-12;
const DT: f64 = 1e-2;

fn world(e: f64, restitution_threshold: Option<f64>) -> World {
    let collisions = CollisionParams {
        restitution: e,
        friction: 0.0,
        ccd: true,
        restitution_threshold,
        ..CollisionParams::default()
    };
    common::impulse_world(3, Method::Verlet, DT, collisions)
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn axpy(a: f64, x: [f64; 3], y: [f64; 3]) -> [f64; 3] {
    [a * x[0] + y[0], a * x[1] + y[1], a * x[2] + y[2]]
}

fn get(v: &[f64], i: usize) -> [f64; 3] {
    [v[3 * i], v[3 * i + 1], v[3 * i + 2]]
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

#[test]
fn head_on_and_oblique_collisions_of_unequal_masses_match_the_closed_form() {
    // Closed form: u₁', u₂' of the module doc (Newton's law + momentum), tangential parts
    // unchanged, loss ½ (1 − e²) μ (u₁ − u₂)²; positions: free flight to the impact time t*,
    // then free flight with the velocities after.
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
    let (m1, m2) = (2.0, 5.0);
    let radius = [0.4, 0.25];
    let reach = radius[0] + radius[1];
    let steps = 10;
    for (n, v) in cases {
        for e in [0.0, 0.3, 0.7, 1.0] {
            // Placed so that the centres are r₁ + r₂ apart along n at t* = 0.37 h: at the
            // impact the line of centres, the contact normal, is n.
            let u = [v[0][0] - v[1][0], v[0][1] - v[1][1], v[0][2] - v[1][2]];
            let t_hit = 0.37 * DT;
            let x1 = [0.3, -0.2, 0.5];
            let x2 = axpy(-1.0, axpy(-t_hit, u, [reach * n[0], reach * n[1], reach * n[2]]), x1);
            let mut w = world(e, None);
            w.add_particles(&[x1, x2].concat(), &v.concat(), &[m1, m2], &radius, &[false; 2])
                .unwrap();
            for _ in 0..steps {
                w.step().unwrap();
            }

            let (u1, u2) = (dot(v[0], n), dot(v[1], n));
            assert!(u1 - u2 < 0.0, "the test pair must approach");
            let p = m1 * u1 + m2 * u2;
            let u1_after = (p + m2 * e * (u2 - u1)) / (m1 + m2);
            let u2_after = (p + m1 * e * (u1 - u2)) / (m1 + m2);
            let want_v = [axpy(u1_after - u1, n, v[0]), axpy(u2_after - u2, n, v[1])];
            let scale = v.iter().flatten().fold(0.0, |m: f64, c| m.max(c.abs()));
            let after = w.particles().v.clone();
            assert_vec_close(&after, &want_v.concat(), scale, &format!("v after, e = {e}, n = {n:?}"));

            // tangential velocities untouched (no friction)
            for (b, &vb) in v.iter().enumerate() {
                let t_before = axpy(-dot(vb, n), n, vb);
                let t_after = axpy(-dot(get(&after, b), n), n, get(&after, b));
                assert_vec_close(&t_after, &t_before, scale, "tangential velocity");
            }
            // positions: x(T) = x₀ + v t* + v' (T − t*)
            let t_end = steps as f64 * DT;
            let want_x: Vec<f64> = [(x1, v[0], want_v[0]), (x2, v[1], want_v[1])]
                .iter()
                .flat_map(|(x, v0, v1)| axpy(t_end - t_hit, *v1, axpy(t_hit, *v0, *x)))
                .collect();
            assert_vec_close(&w.particles().x, &want_x, 1.0, &format!("x after, e = {e}, n = {n:?}"));

            // momentum, from the velocities; the books' impulse balance
            let before = [0, 1, 2].map(|k| m1 * v[0][k] + m2 * v[1][k]);
            let now = [0, 1, 2].map(|k| m1 * after[k] + m2 * after[3 + k]);
            assert_vec_close(&now, &before, (m1 + m2) * scale, "momentum");
            let (_, total) = w.collision_stats().unwrap();
            assert_vec_close(&total.impulse_balance, &[0.0; 3], (m1 + m2) * scale, "impulse balance");

            // energy: the stat and the measured loss both equal ½ (1 − e²) μ (u₁ − u₂)²
            let mu = m1 * m2 / (m1 + m2);
            let closed = 0.5 * (1.0 - e * e) * mu * (u1 - u2) * (u1 - u2);
            let ke = kinetic(&v.concat(), &[m1, m2]);
            let measured = ke - kinetic(&after, &[m1, m2]);
            assert!(
                (total.energy_lost - closed).abs() <= RTOL * ke,
                "{} vs {closed}",
                total.energy_lost
            );
            assert!((measured - closed).abs() <= RTOL * ke, "measured {measured} vs {closed}");
            assert_eq!(total.impacts, 1, "one impact, found inside its step");
        }
    }
}

#[test]
fn an_immovable_partner_reflects_the_normal_velocity_times_e() {
    // Closed form (m₂ → ∞): u_n' = −e u_n, the tangential (2, 1) unchanged, loss
    // ½ (1 − e²) m u_n²; the immovable side does not move.
    let mass = 3.0;
    let v0 = [2.0, 1.0, -4.0];
    let t_hit = 0.37 * DT;
    for e in [0.0, 0.3, 0.7, 1.0] {
        let want_v = [2.0, 1.0, 4.0 * e];
        let closed = 0.5 * (1.0 - e * e) * mass * 16.0;

        // a plane collider, the floor z = 0: the ball of radius 0.5 touches it at t*
        let mut w = world(e, None);
        w.add_collider(Plane::new([0.0; 3], [0.0, 0.0, 1.0], Surface::default()).unwrap())
            .unwrap();
        w.add_particles(&[0.0, 0.0, 0.5 + 4.0 * t_hit], &v0, &[mass], &[0.5], &[false])
            .unwrap();
        w.step().unwrap();
        assert_vec_close(&w.particles().v, &want_v, 4.0, &format!("after the floor, e = {e}"));
        let z = 0.5 + want_v[2] * (DT - t_hit);
        assert!(
            (w.particles().x[2] - z).abs() <= RTOL,
            "e = {e}: z = {} vs {z}",
            w.particles().x[2]
        );
        let (_, total) = w.collision_stats().unwrap();
        assert_eq!(total.impacts, 1);
        assert!((total.energy_lost - closed).abs() <= RTOL * closed.max(1.0), "{total:?}");
        // the floor's impulse is outside the particles: the balance of the rest is zero
        assert_vec_close(&total.impulse_balance, &[0.0; 3], 4.0 * mass, "impulse balance");

        // a pinned particle below, touched at t* along z (the ball at the origin then): the
        // same, and it stays where it is
        let mut w = world(e, None);
        let x = [-2.0 * t_hit, -t_hit, 4.0 * t_hit, 0.0, 0.0, -1.0];
        w.add_particles(&x, &[v0, [0.0; 3]].concat(), &[mass, 1.0], &[0.5, 0.5], &[false, true])
            .unwrap();
        w.step().unwrap();
        let p = w.particles();
        assert_vec_close(
            &p.v,
            &[want_v, [0.0; 3]].concat(),
            4.0,
            &format!("after the pinned ball, e = {e}"),
        );
        assert_eq!(&p.x[3..], &[0.0, 0.0, -1.0], "the pinned ball moved");
        let (_, total) = w.collision_stats().unwrap();
        assert_eq!(total.impacts, 1);
        assert!((total.energy_lost - closed).abs() <= RTOL * closed.max(1.0), "{total:?}");
        assert_vec_close(&total.impulse_balance, &[0.0; 3], 4.0 * mass, "impulse balance");
    }
}

#[test]
fn slow_approaches_below_the_threshold_do_not_bounce() {
    // e = 0.8 with a threshold of 0.5 m/s: a ball approaching the wall y = 0 at 0.3 m/s
    // comes to rest on it (e = 0: u_n' = 0, at the wall), at 0.7 m/s it rebounds at
    // e · 0.7 = 0.56 m/s; the x velocity 0.2 m/s is untouched either way (no friction).
    for (speed, rebound, impacts) in [(0.3, 0.0, 0), (0.7, 0.56, 1)] {
        let mut w = world(0.8, Some(0.5));
        w.add_collider(Plane::new([0.0; 3], [0.0, 1.0, 0.0], Surface::default()).unwrap())
            .unwrap();
        let r = 0.1;
        // reaches the wall after 3.37 steps
        w.add_particles(
            &[0.0, r + 3.37 * speed * DT, 0.0],
            &[0.2, -speed, 0.0],
            &[1.0],
            &[r],
            &[false],
        )
        .unwrap();
        for _ in 0..10 {
            w.step().unwrap();
        }
        let p = w.particles();
        assert!((p.v[1] - rebound).abs() < 1e-12, "{speed} m/s: v = {:?}", p.v);
        assert!((p.v[0] - 0.2).abs() < 1e-15 && p.v[2] == 0.0, "{speed} m/s: v = {:?}", p.v);
        if rebound == 0.0 {
            assert!((p.x[1] - r).abs() < 1e-12, "{speed} m/s: not resting on the wall: {:?}", p.x);
        } else {
            let y = r + rebound * (10.0 - 3.37) * DT;
            assert!((p.x[1] - y).abs() < 1e-12, "{speed} m/s: y = {} vs {y}", p.x[1]);
        }
        let (_, total) = w.collision_stats().unwrap();
        assert_eq!(total.impacts, impacts, "{speed} m/s: {total:?}");
        // loss: ½ m (u² − u'²) either way
        let closed = 0.5 * (speed * speed - rebound * rebound);
        assert!(
            (total.energy_lost - closed).abs() < 1e-12,
            "{speed} m/s: {total:?} vs {closed}"
        );
    }
}
