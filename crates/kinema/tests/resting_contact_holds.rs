//! Resting contact under the impulse model (the end-of-step soft step, `collide/soft_step.rs`):
//! bodies that should rest do rest, exactly, and the books stay honest.
//!
//! Theory used: a ball dropped from height H with restitution e < 1 bounces in a geometric
//! series and comes to rest at t = t₀ (1 + e)/(1 − e), t₀ = √(2H/g) (the sum of its flight
//! times); a body at rest has constant energy, so a resting contact takes none; Coulomb's law
//! holds a block on a slope of angle θ when μ > tan θ, and on a floor pulled sideways by a
//! force below μ m g.

mod common;

use kinema::collide::{BoxContainer, Plane, Surface};
use kinema::forces::Gravity;
use kinema::ode::Method;
use kinema::world::CollisionParams;
use kinema::World;

const G: f64 = 9.81;

/// A world whose islands never sleep: what holds them at rest here is the soft step alone
/// (sleeping would stop a resting body after 0.5 s and hide it; `sleeping_islands.rs`).
fn world(dim: usize, method: Method, e: f64, mu: f64) -> World {
    world_sleeping(dim, method, e, mu, None)
}

fn world_sleeping(dim: usize, method: Method, e: f64, mu: f64, sleep_time: Option<f64>) -> World {
    let collisions = CollisionParams {
        restitution: e,
        friction: mu,
        sleep_time,
        ..CollisionParams::default()
    };
    common::impulse_world(dim, method, 1e-3, collisions)
}

fn ball_on_floor(method: Method, e: f64, height: f64, g: [f64; 3], mu: f64) -> World {
    let mut w = world(3, method, e, mu);
    w.add_particles(&[0.0, 0.0, 0.1 + height], &[0.0; 3], &[1.0], &[0.1], &[false])
        .unwrap();
    w.add_force(Box::new(Gravity::new(g).unwrap())).unwrap();
    w.add_collider(Plane::new([0.0; 3], [0.0, 0.0, 1.0], Surface::default()).unwrap())
        .unwrap();
    w
}

#[test]
fn a_dropped_ball_comes_to_rest_in_finite_time_for_every_e_below_one() {
    // 5 restitutions × 3 heights: by the closed-form time to rest (plus 0.1 s) the ball lies
    // on the floor, z = r to rounding, v = 0 exactly; and the collisions booked exactly the
    // potential energy m g H it had (the rest of the energy is where it was: nothing created).
    for e in [0.0, 0.3, 0.5, 0.7, 0.9] {
        for height in [0.05, 0.3, 1.0] {
            let mut w = ball_on_floor(Method::Verlet, e, height, [0.0, 0.0, -G], 0.0);
            let t_rest = (2.0 * height / G).sqrt() * (1.0 + e) / (1.0 - e);
            let steps = ((t_rest + 0.1) / 1e-3).ceil() as usize;
            for _ in 0..steps {
                w.step().unwrap();
            }
            let p = w.particles();
            assert!((p.x[2] - 0.1).abs() < 1e-12, "e {e}, H {height}: z − r = {}", p.x[2] - 0.1);
            assert_eq!(&p.v[..], &[0.0; 3], "e {e}, H {height}");
            let lost = w.collision_stats().unwrap().1.energy_lost;
            assert!(
                (lost - G * height).abs() < 1e-9 * G * height,
                "e {e}, H {height}: booked {lost} J"
            );
        }
    }
}

#[test]
fn a_resting_ball_books_nothing_with_every_method() {
    // A ball placed on the floor at rest, 10 s: it never moves, and the collisions book less
    // than 1e-9 J, whatever the method (each ends its step where it began).
    for method in Method::ALL {
        let mut w = ball_on_floor(method, 0.7, 0.0, [0.0, 0.0, -G], 0.0);
        for _ in 0..10_000 {
            w.step().unwrap();
        }
        let p = w.particles();
        let lost = w.collision_stats().unwrap().1.energy_lost;
        assert!(lost.abs() < 1e-9, "{method:?}: booked {lost} J");
        assert!(
            (p.x[2] - 0.1).abs() < 1e-12 && p.v[2] == 0.0,
            "{method:?}: z {}, v {}",
            p.x[2],
            p.v[2]
        );
    }
}

#[test]
fn an_elastic_stack_keeps_its_energy_and_no_step_creates_any() {
    // A column of 10 touching balls on a floor with e = 1, placed at rest. Its first step
    // solves its contacts from nothing (no warm start): a cold island gets ten times the
    // sweeps, and the whole column moves by symplectic Euler from that first step on, so the
    // first step's totals hold it in the next (collide/islands.rs, end_of_step.rs). It keeps
    // its energy to 1e-9 relative from its first step: while the solve converges and over 2 s
    // after. No step books a negative loss beyond what the solver's tolerance allows: each of
    // the n contacts below a ball may leave it 1e-9 m/s, so the column's weight M g moves by
    // at most h · n · 1e-9 m in a step: |loss| ≤ M g h n · 1e-9 J. (The edge: columns of 15
    // hold 3e-10 of their energy from a cold start; of 20, 3.6e-8; of 30, 1.4e-6, booked as
    // lost while the solve, whose sweeps carry a load one contact further each, converges
    // over the first 50 steps. docs/collisions.md.)
    let (r, n) = (0.05, 10);
    let mut w = world(3, Method::Verlet, 1.0, 0.0);
    let x: Vec<f64> = (0..n).flat_map(|k| [0.0, 0.0, r + 2.0 * r * k as f64]).collect();
    w.add_particles(&x, &vec![0.0; 3 * n], &vec![0.2; n], &vec![r; n], &vec![false; n])
        .unwrap();
    w.add_force(Box::new(Gravity::new([0.0, 0.0, -G]).unwrap())).unwrap();
    w.add_collider(Plane::new([0.0; 3], [0.0, 0.0, 1.0], Surface::default()).unwrap())
        .unwrap();
    let e_start = w.diagnostics().total_energy();
    let mut warm_up = 0;
    while w.collision_stats().unwrap().0.unconverged > 0 || warm_up == 0 {
        w.step().unwrap();
        warm_up += 1;
        assert!(warm_up < 500, "not converged after {warm_up} steps");
    }
    let (_, total) = w.collision_stats().unwrap();
    assert!(total.energy_lost.abs() <= 1e-9 * e_start, "{total:?}");
    let e0 = w.diagnostics().total_energy();
    let bound = (0.2 * n as f64) * G * 1e-3 * n as f64 * 1e-9;
    for _ in 0..2000 {
        w.step().unwrap();
        let lost = w.collision_stats().unwrap().0.energy_lost;
        assert!(lost >= -bound, "a step booked {lost} J");
    }
    let e1 = w.diagnostics().total_energy();
    assert!((e1 - e0).abs() <= 1e-9 * e0.abs(), "{e0} J became {e1} J");
}

#[test]
fn static_friction_sticks() {
    // μ = 0.8 on a 30° slope (tan 30° = 0.577 < μ), and μ = 0.5 on a floor pulled sideways at
    // 3 m/s² (< μ g = 4.9 m/s²): placed at rest, the ball moves less than 1 µm in 10 s, with
    // every method.
    let theta = 30f64.to_radians();
    let slope = [G * theta.sin(), 0.0, -G * theta.cos()]; // gravity in the slope's frame
    for (g, mu) in [(slope, 0.8), ([3.0, 0.0, -G], 0.5)] {
        for method in Method::ALL {
            let mut w = ball_on_floor(method, 0.0, 0.0, g, mu);
            for _ in 0..10_000 {
                w.step().unwrap();
            }
            let p = w.particles();
            let moved = (p.x[0].powi(2) + p.x[1].powi(2) + (p.x[2] - 0.1).powi(2)).sqrt();
            assert!(moved < 1e-6, "{method:?}, μ {mu}: moved {moved} m");
        }
    }
}

#[test]
fn a_frictional_pile_of_discs_comes_to_rest() {
    // 300 discs (radii 2.5–4 cm, e = 0.7, μ = 0.5) on a staggered lattice, dropped into a 1 m
    // box in 2D: after 3 s every disc is at rest (|v| < 1e-6 m/s), the overlaps stay below 1 %
    // of the mean radius (measured by brute force), and the solver converged in the last step.
    // Held by the soft step alone, and asleep (then the overlap reported is the islands').
    for sleep_time in [None, Some(0.5)] {
        frictional_pile(sleep_time);
    }
}

fn frictional_pile(sleep_time: Option<f64>) {
    let mut w = world_sleeping(2, Method::Verlet, 0.7, 0.5, sleep_time);
    let n = 300;
    let (mut x, mut radius) = (Vec::new(), Vec::new());
    for k in 0..n {
        let (row, col) = (k / 11, k % 11);
        let shift = if row % 2 == 1 { 0.04 } else { 0.0 };
        x.extend([0.06 + 0.085 * col as f64 + shift, 0.05 + 0.085 * row as f64, 0.0]);
        radius.push(0.025 + 0.015 * ((k * 7919) % 101) as f64 / 100.0);
    }
    w.add_particles(&x, &vec![0.0; 3 * n], &vec![1.0; n], &radius, &vec![false; n])
        .unwrap();
    w.add_force(Box::new(Gravity::new([0.0, -G, 0.0]).unwrap())).unwrap();
    w.add_collider(BoxContainer::new([0.0, 0.0, f64::NEG_INFINITY], [1.0, 10.0, f64::INFINITY], Surface::default()).unwrap())
        .unwrap();
    for _ in 0..3000 {
        w.step().unwrap();
    }
    let p = w.particles();
    let fastest = p.v.iter().fold(0.0_f64, |m, u| m.max(u.abs()));
    let mean_r = radius.iter().sum::<f64>() / n as f64;
    let mut overlap: f64 = 0.0;
    for i in 0..n {
        for j in i + 1..n {
            let d = ((p.x[3 * i] - p.x[3 * j]).powi(2) + (p.x[3 * i + 1] - p.x[3 * j + 1]).powi(2)).sqrt();
            overlap = overlap.max(radius[i] + radius[j] - d);
        }
        overlap = overlap.max(radius[i] - p.x[3 * i + 1]);
    }
    let (last, _) = w.collision_stats().unwrap();
    assert!(fastest < 1e-6, "still moving at {fastest} m/s ({last:?})");
    assert_eq!(last.asleep, if sleep_time.is_some() { n } else { 0 }, "{last:?}");
    assert!(overlap < 0.01 * mean_r, "overlap {overlap} m");
    assert_eq!(last.unconverged, 0, "{last:?}");
    // the reported overlap is the real one (within 1 %)
    assert!(
        (last.max_overlap - overlap).abs() <= 0.01 * overlap,
        "{} vs {overlap}",
        last.max_overlap
    );
}
