//! Newton's cradle in a World: five equal balls in a row, touching, e = 1, no gravity. The
//! impacts of continuous detection, resolved one after the other at their common instant with
//! the current relative velocity, pass the whole velocity along the row, as the real cradle
//! does: one ball in, one ball out; two in, two out. (Momentum and energy conservation alone
//! allow other outcomes; a simultaneous solve spreads the velocity over the row instead.)
//!
//! Closed form: the arriving ball(s) meet the row at t* = gap / v and stop there; as many
//! balls leave the far end at v, so at time T the balls that left are at x + v (T − t*) and
//! the others rest where they were at t*; nothing is lost.

mod common;

use kinema::ode::Method;
use kinema::world::CollisionParams;

const N: usize = 5;
const DT: f64 = 1e-3;
const STEPS: usize = 100;
/// The arriving balls' gap to the row, m: met at t* = 23.4375 steps at 1 m/s (exact in binary).
const GAP: f64 = 0.0234375;

/// Runs the row: radius 0.5 m, 1 kg, balls `k` at x = `x[k]` (touching neighbours 1 m apart)
/// with velocities `vx`, listed in the order `order` (World index p holds ball order[p]);
/// returns each ball's x and v_x after STEPS steps, and the collision books.
fn swing(x: [f64; N], vx: [f64; N], order: [usize; N]) -> ([f64; N], [f64; N], kinema::world::CollisionStats) {
    let collisions = CollisionParams {
        restitution: 1.0,
        ..CollisionParams::default()
    };
    let mut w = common::impulse_world(3, Method::Verlet, DT, collisions);
    let xs: Vec<f64> = order.iter().flat_map(|&k| [x[k], 0.0, 0.0]).collect();
    let vs: Vec<f64> = order.iter().flat_map(|&k| [vx[k], 0.0, 0.0]).collect();
    w.add_particles(&xs, &vs, &[1.0; N], &[0.5; N], &[false; N]).unwrap();
    for _ in 0..STEPS {
        w.step().unwrap();
    }
    let p = w.particles();
    let (mut x_out, mut v_out) = ([0.0; N], [0.0; N]);
    for (i, &k) in order.iter().enumerate() {
        x_out[k] = p.x[3 * i];
        v_out[k] = p.v[3 * i];
        assert_eq!((p.v[3 * i + 1], p.v[3 * i + 2]), (0.0, 0.0), "ball {k} left the line");
        assert_eq!((p.x[3 * i + 1], p.x[3 * i + 2]), (0.0, 0.0), "ball {k} left the line");
    }
    (x_out, v_out, w.collision_stats().unwrap().1)
}

fn assert_row(what: &str, got: [f64; N], want: [f64; N]) {
    for i in 0..N {
        assert!((got[i] - want[i]).abs() < 1e-12, "{what} of ball {i}: {got:?} vs {want:?}");
    }
}

/// The time left after the impact at t*.
fn after_impact() -> f64 {
    STEPS as f64 * DT - GAP
}

#[test]
fn one_ball_in_one_ball_out() {
    // Ball 0 at −1 − gap arrives at 1 m/s; the row rests at 0, 1, 2, 3. At t* ball 0 stops
    // at −1 and ball 4 leaves from 3 at 1 m/s: four impacts, each handing the velocity on.
    let (x, v, total) = swing([-1.0 - GAP, 0.0, 1.0, 2.0, 3.0], [1.0, 0.0, 0.0, 0.0, 0.0], [0, 1, 2, 3, 4]);
    assert_row("v", v, [0.0, 0.0, 0.0, 0.0, 1.0]);
    assert_row("x", x, [-1.0, 0.0, 1.0, 2.0, 3.0 + after_impact()]);
    assert_eq!(total.impacts, 4, "{total:?}");
    // Σ of the impulses between the balls: zero by action = reaction (scale: m v = 1 N·s)
    assert!(total.impulse_balance.iter().all(|s| s.abs() < 1e-12), "{total:?}");
    assert!(total.energy_lost.abs() < 1e-15, "e = 1 loses nothing: {total:?}");
}

#[test]
fn two_balls_in_two_balls_out() {
    // Balls 0 and 1, touching, arrive together at 1 m/s; at t* they stop at −2 and −1 and
    // balls 3 and 4 leave from 1 and 2 at 1 m/s.
    let (x, v, total) = swing(
        [-2.0 - GAP, -1.0 - GAP, 0.0, 1.0, 2.0],
        [1.0, 1.0, 0.0, 0.0, 0.0],
        [0, 1, 2, 3, 4],
    );
    assert_row("v", v, [0.0, 0.0, 0.0, 1.0, 1.0]);
    assert_row("x", x, [-2.0, -1.0, 0.0, 1.0 + after_impact(), 2.0 + after_impact()]);
    assert!(total.impulse_balance.iter().all(|s| s.abs() < 1e-12), "{total:?}");
    assert!(total.energy_lost.abs() < 1e-15, "e = 1 loses nothing: {total:?}");
}

#[test]
fn the_order_of_the_particles_does_not_change_the_outcome() {
    // The row listed from the far end (the arriving ball last): the same outcome.
    let (x, v, _) = swing([-1.0 - GAP, 0.0, 1.0, 2.0, 3.0], [1.0, 0.0, 0.0, 0.0, 0.0], [4, 3, 2, 1, 0]);
    assert_row("v", v, [0.0, 0.0, 0.0, 0.0, 1.0]);
    assert_row("x", x, [-1.0, 0.0, 1.0, 2.0, 3.0 + after_impact()]);
    let (x, v, _) = swing(
        [-2.0 - GAP, -1.0 - GAP, 0.0, 1.0, 2.0],
        [1.0, 1.0, 0.0, 0.0, 0.0],
        [3, 1, 4, 0, 2],
    );
    assert_row("v", v, [0.0, 0.0, 0.0, 1.0, 1.0]);
    assert_row("x", x, [-2.0, -1.0, 0.0, 1.0 + after_impact(), 2.0 + after_impact()]);
    // and from the other side: the last ball swings in, the first leaves
    let (x, v, _) = swing([0.0, 1.0, 2.0, 3.0, 4.0 + GAP], [0.0, 0.0, 0.0, 0.0, -1.0], [0, 1, 2, 3, 4]);
    assert_row("v", v, [-1.0, 0.0, 0.0, 0.0, 0.0]);
    assert_row("x", x, [-after_impact(), 1.0, 2.0, 3.0, 4.0]);
}
