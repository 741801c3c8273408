//! Coulomb friction at impacts in a World (impulse model, continuous detection): a sliding
//! contact's tangential impulse is μ j (the cone's edge), a sticking one stops the tangential
//! relative motion exactly, and either conserves the pair's momentum and removes kinetic
//! energy.
//!
//! Closed forms: normal impulse j = −(1 + e) u_n / (w₁ + w₂); the impulse that stops the
//! sliding is |u_t| / (w₁ + w₂) (no rotation: the effective mass is the same across the
//! normal as along it); the applied one is j_t = min(|u_t| / (w₁ + w₂), μ j), against u_t.
//! The kinetic energy lost is ½ (1 − e²) u_n² / (w₁ + w₂) + j_t (|u_t| − ½ (w₁ + w₂) j_t).
//! Each body starts a small gap from its partner and meets it inside a step.

mod common;

use kinema::collide::{Plane, Surface};
use kinema::ode::Method;
use kinema::world::CollisionParams;
use kinema::World;

const DT: f64 = 1e-2;
/// The impact's time inside the first step.
const T_HIT: f64 = 0.37 * DT;

fn close(a: f64, b: f64, scale: f64) -> bool {
    (a - b).abs() <= 1e-14 * scale
}

fn world(e: f64, mu: f64) -> World {
    let collisions = CollisionParams {
        restitution: e,
        friction: mu,
        ..CollisionParams::default()
    };
    common::impulse_world(3, Method::Verlet, DT, collisions)
}

/// A ball of mass `m` and radius 0.1 m with velocity `v` (v_z < 0) that meets the floor z = 0
/// (with `surface`) at T_HIT, after one step.
fn ball_on_floor(e: f64, mu: f64, surface: Surface, m: f64, v: [f64; 3]) -> World {
    let mut w = world(e, mu);
    w.add_collider(Plane::new([0.0; 3], [0.0, 0.0, 1.0], surface).unwrap())
        .unwrap();
    w.add_particles(&[0.0, 0.0, 0.1 - v[2] * T_HIT], &v, &[m], &[0.1], &[false])
        .unwrap();
    w.step().unwrap();
    let (_, total) = w.collision_stats().unwrap();
    assert_eq!(total.impacts, 1, "{total:?}");
    w
}

#[test]
fn sliding_on_a_floor_is_clamped_at_mu_j() {
    // m = 2 kg, v = (3, 0, −1), e = 0.5: j = 1.5 · 1 · 2 = 3 N·s. Stopping the 3 m/s slide
    // needs 6 N·s; μ = 0.2 allows μ j = 0.6 N·s, so it slides on at 3 − 0.6/2 = 2.7 m/s and
    // leaves at e · 1 = 0.5 m/s.
    let w = ball_on_floor(0.5, 0.2, Surface::default(), 2.0, [3.0, 0.0, -1.0]);
    let v = &w.particles().v;
    assert!(close(v[0], 2.7, 3.0) && v[1] == 0.0 && close(v[2], 0.5, 1.0), "{v:?}");
    // KE lost: normal ½ (1 − e²) m u_n² = 0.75 J, tangential j_t (|u_t| − ½ w j_t) = 1.71 J
    let closed = 0.75 + 0.6 * (3.0 - 0.5 * 0.5 * 0.6);
    let (_, total) = w.collision_stats().unwrap();
    assert!(close(total.energy_lost, closed, 10.0), "{} vs {closed}", total.energy_lost);
    let measured = 0.5 * 2.0 * (10.0 - (v[0] * v[0] + v[2] * v[2]));
    assert!(close(measured, closed, 10.0), "measured {measured} vs {closed}");
}

#[test]
fn sticking_stops_the_tangential_motion() {
    // μ = 10: the cone allows 30 N·s, the 10 N·s that stop |u_t| = 5 m/s of 2 kg are applied:
    // the ball leaves straight up at e · 1 = 0.5 m/s. KE lost: 0.75 J + ½ m |u_t|² = 25 J.
    let w = ball_on_floor(0.5, 10.0, Surface::default(), 2.0, [3.0, -4.0, -1.0]);
    let v = &w.particles().v;
    assert!(v[0].abs() < 1e-15 && v[1].abs() < 1e-15 && close(v[2], 0.5, 1.0), "{v:?}");
    let (_, total) = w.collision_stats().unwrap();
    assert!(close(total.energy_lost, 25.75, 30.0), "{}", total.energy_lost);
}

#[test]
fn particle_pairs_slide_and_stick_with_the_reduced_mass() {
    // m₁ = 1, m₂ = 4 kg (w = 1.25 /kg), normal x at the impact, u_n = −2, u_t = (0, 3, 0),
    // e = 0.5: j = 1.5 · 2 / 1.25 = 2.4 N·s, and stopping the slide needs 3 / 1.25 = 2.4 N·s.
    // μ = 0.5 slides (j_t = μ j = 1.2), μ = 1.5 sticks (2.4), μ = 1 is the edge (2.4).
    let v0 = [-1.0, 2.0, 0.5, 1.0, -1.0, 0.5];
    let m = [1.0, 4.0];
    let u = [v0[0] - v0[3], v0[1] - v0[4], v0[2] - v0[5]];
    let r = [0.3, 0.2];
    // at T_HIT the centres are r₁ + r₂ apart along x: the contact normal is x
    let x1 = [0.1, -0.3, 0.2];
    let x2 = [
        x1[0] - (r[0] + r[1]) + u[0] * T_HIT,
        x1[1] + u[1] * T_HIT,
        x1[2] + u[2] * T_HIT,
    ];
    for (mu, j_t) in [(0.5, 1.2), (1.5, 2.4), (1.0, 2.4)] {
        let mut w = world(0.5, mu);
        w.add_particles(&[x1, x2].concat(), &v0, &m, &r, &[false; 2]).unwrap();
        w.step().unwrap();
        let v = &w.particles().v;
        let (_, total) = w.collision_stats().unwrap();
        assert_eq!(total.impacts, 1, "μ = {mu}: {total:?}");
        // relative normal velocity −e u_n = 1; relative tangential velocity falls by w j_t
        assert!(close(v[0] - v[3], 1.0, 3.0), "μ = {mu}: {v:?}");
        let u_t = v[1] - v[4];
        assert!(close(u_t, 3.0 - 1.25 * j_t, 3.0), "μ = {mu}: u_t = {u_t}");
        // each body's change is its share, ±J/m: the normal impulse 2.4 N·s along x, j_t
        // against the slide along y; z untouched
        let jv = [2.4, -j_t, 0.0];
        for k in 0..3 {
            assert!(close(v[k], v0[k] + jv[k] / m[0], 5.0), "μ = {mu}: {v:?}");
            assert!(close(v[3 + k], v0[3 + k] - jv[k] / m[1], 5.0), "μ = {mu}: {v:?}");
            assert!(total.impulse_balance[k].abs() <= 1e-14 * 10.0, "{total:?}");
        }
        let closed = 0.5 * 0.75 * 4.0 / 1.25 + j_t * (3.0 - 0.5 * 1.25 * j_t);
        assert!(
            close(total.energy_lost, closed, 10.0),
            "μ = {mu}: {} vs {closed}",
            total.energy_lost
        );
    }
}

#[test]
fn a_collider_surface_overrides_the_particles_friction() {
    // global e = 0, μ = 1 would take the bounce and 1 m/s of the 3 m/s slide (μ j = 1 N·s
    // for 1 kg); the floor's own μ = 0 lets it slide freely, and its e = 1 bounces it fully:
    // v = (3, 0, −1) → (3, 0, 1), nothing lost.
    let w = ball_on_floor(0.0, 1.0, Surface::new(Some(1.0), Some(0.0)).unwrap(), 1.0, [3.0, 0.0, -1.0]);
    assert_eq!(w.particles().v, vec![3.0, 0.0, 1.0]);
    let (_, total) = w.collision_stats().unwrap();
    assert!(total.energy_lost.abs() < 1e-15, "{total:?}");
    // the floor's μ = 0.1 instead: j = 1 N·s (e = 0 from the particles), j_t = μ j = 0.1 N·s
    let w = ball_on_floor(0.0, 1.0, Surface::new(None, Some(0.1)).unwrap(), 1.0, [3.0, 0.0, -1.0]);
    let v = &w.particles().v;
    assert!(close(v[0], 2.9, 3.0) && v[1] == 0.0 && v[2].abs() < 1e-15, "{v:?}");
}
