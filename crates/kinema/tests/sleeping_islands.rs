//! Sleeping (`collide/sleep.rs`): islands at rest on a collider sleep (velocities exactly 0,
//! no contacts solved, no impacts searched), and wake when something reaches them: an
//! impact, a touch, a user's write, a new force, a collider.
//!
//! Theory used: a body at rest on a floor has constant energy, so putting it to sleep books
//! only what it still moved with (nothing, at rest); a particle moving freely under no net
//! force keeps its velocity (Newton's first law), so nothing unsupported may sleep.

mod common;

use kinema::collide::{BoxContainer, Plane, Surface};
use kinema::forces::{Gravity, Springs};
use kinema::ode::Method;
use kinema::world::{CollisionParams, CollisionStats};
use kinema::World;

const G: f64 = 9.81;

fn world(e: f64, mu: f64) -> World {
    let collisions = CollisionParams {
        restitution: e,
        friction: mu,
        ..CollisionParams::default()
    };
    common::impulse_world(3, Method::Verlet, 1e-3, collisions)
}

fn last(w: &World) -> CollisionStats {
    w.collision_stats().unwrap().0
}

fn total(w: &World) -> CollisionStats {
    w.collision_stats().unwrap().1
}

/// 5 × 5 × 6 balls (radii 2.5–4 cm, 1 kg) on a lattice, 1 cm apart at least, above the floor
/// of a 0.45 m box, thrown about: they settle into one heap.
fn pile(e: f64, mu: f64) -> World {
    let mut w = world(e, mu);
    let (mut x, mut v, mut radius) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..150 {
        // thrown about at up to 0.5 m/s, so that the columns fall into one heap
        let u = |s: usize| 0.5 * (((k * s) % 89) as f64 / 44.0 - 1.0);
        v.extend([u(7907), u(7919), u(7927)]);
        let (a, b, c) = (k % 5, (k / 5) % 5, k / 25);
        let jitter = 0.004 * (((k * 7919) % 101) as f64 / 100.0 - 0.5);
        x.extend([
            0.045 + 0.09 * a as f64 + jitter,
            0.045 + 0.09 * b as f64 - jitter,
            0.05 + 0.09 * c as f64,
        ]);
        radius.push(0.025 + 0.015 * ((k * 104_729) % 97) as f64 / 96.0);
    }
    let n = radius.len();
    w.add_particles(&x, &v, &vec![1.0; n], &radius, &vec![false; n]).unwrap();
    w.add_force(Box::new(Gravity::new([0.0, 0.0, -G]).unwrap())).unwrap();
    w.add_collider(BoxContainer::new([0.0; 3], [0.45, 0.45, 5.0], Surface::default()).unwrap())
        .unwrap();
    w
}

/// Steps until every particle sleeps (at most `limit` steps); returns the steps taken.
///
/// Checks the books on the way: the collisions took energy in all (Σ ≥ 0), and no step whose
/// solver converged booked a negative loss beyond what its tolerance allows (1e-9 m/s per
/// contact, n contacts at most in a chain under a ball: the pile's weight M g moves by at
/// most h n 1e-9 m; `resting_contact_holds.rs` derives the same bound). A step stopped at the
/// solver's sweep cap may book a little more (−4e-8 J measured on this pile,
/// docs/collisions.md).
fn until_asleep(w: &mut World, limit: usize) -> usize {
    let n = w.particles().len() as f64;
    let bound = n * G * 1e-3 * n * 1e-9;
    for k in 1..=limit {
        w.step().unwrap();
        let step = last(w);
        if step.unconverged == 0 {
            assert!(step.energy_lost >= -bound, "step {k} booked {} J", step.energy_lost);
        }
        if step.asleep == w.particles().len() {
            assert!(total(w).energy_lost >= 0.0, "{:?}", total(w));
            return k;
        }
    }
    panic!("not asleep after {limit} steps: {:?}", last(w));
}

#[test]
fn a_ball_at_rest_on_a_floor_sleeps_after_the_sleep_time() {
    // Placed at rest: calm from the first step, asleep once it has been calm 0.5 s, exactly
    // where it was, v = 0, nothing booked.
    let mut w = world(0.5, 0.0);
    w.add_particles(&[0.0, 0.0, 0.1], &[0.0; 3], &[1.0], &[0.1], &[false])
        .unwrap();
    w.add_force(Box::new(Gravity::new([0.0, 0.0, -G]).unwrap())).unwrap();
    w.add_collider(Plane::new([0.0; 3], [0.0, 0.0, 1.0], Surface::default()).unwrap())
        .unwrap();
    for _ in 0..499 {
        w.step().unwrap();
        assert_eq!(last(&w).asleep, 0);
    }
    w.step().unwrap();
    assert_eq!(last(&w).asleep, 1, "{:?}", last(&w));
    for _ in 0..1000 {
        w.step().unwrap();
    }
    let p = w.particles();
    assert_eq!((p.x[2], &p.v[..]), (0.1, &[0.0; 3][..]));
    let books = total(&w);
    assert_eq!((books.slept, books.woke, books.energy_lost), (1, 0, 0.0));
}

#[test]
fn a_settled_pile_sleeps_does_no_work_and_wakes_when_a_ball_lands_on_it() {
    let mut w = pile(0.5, 0.5);
    until_asleep(&mut w, 6000);
    let n = w.particles().len();
    let x_asleep = w.particles().x.clone();
    // Asleep: nothing moves, no contact is solved, no impact searched, velocities exactly 0;
    // the overlap reported is that of the islands, measured by brute force (within 1 %).
    for _ in 0..200 {
        w.step().unwrap();
    }
    let step = last(&w);
    assert_eq!((step.contacts, step.impacts, step.solver_sweeps, step.asleep), (0, 0, 0, n));
    assert!(step.asleep_contacts > n, "{step:?}");
    let p = w.particles();
    assert_eq!(p.x, x_asleep);
    assert!(p.v.iter().all(|&v| v == 0.0));
    let (mut deepest, r) = (0.0_f64, &p.radius);
    for i in 0..n {
        for j in i + 1..n {
            let d: f64 = (0..3).map(|k| (p.x[3 * i + k] - p.x[3 * j + k]).powi(2)).sum::<f64>().sqrt();
            deepest = deepest.max(r[i] + r[j] - d);
        }
        deepest = deepest.max(r[i] - p.x[3 * i + 2]);
    }
    assert!(
        deepest > 0.0 && (step.max_overlap - deepest).abs() <= 0.01 * deepest,
        "{} vs {deepest}",
        step.max_overlap
    );

    // A ball dropped onto the middle of it: its impact wakes the island it hits, which takes
    // the blow, settles and sleeps again.
    let top = (0..n).map(|q| p.x[3 * q + 2]).fold(0.0, f64::max);
    w.add_particles(&[0.225, 0.225, top + 0.3], &[0.0; 3], &[1.0], &[0.03], &[false])
        .unwrap();
    assert_eq!(last(&w).asleep, n, "adding a particle wakes nothing by itself");
    let woke_before = total(&w).woke;
    let mut woken = false;
    for _ in 0..400 {
        w.step().unwrap();
        woken |= last(&w).asleep < n;
    }
    assert!(woken && total(&w).woke > woke_before, "{:?}", total(&w));
    let moved = (0..3 * n)
        .map(|c| (w.particles().x[c] - x_asleep[c]).abs())
        .fold(0.0, f64::max);
    assert!(moved > 0.0, "the pile took the blow");
    until_asleep(&mut w, 6000);
}

#[test]
fn what_the_user_changes_wakes_every_island() {
    type Change = fn(&mut World);
    let changes: [(&str, Change); 4] = [
        ("a velocity written", |w| w.particles_mut().v[0] = 0.1),
        ("a force added", |w| {
            w.add_force(Box::new(Gravity::new([0.1, 0.0, 0.0]).unwrap())).unwrap()
        }),
        ("a collider added", |w| {
            w.add_collider(Plane::new([0.0, 0.0, 3.0], [0.0, 0.0, -1.0], Surface::default()).unwrap())
                .map(|_| ())
                .unwrap()
        }),
        ("the settings set", |w| {
            let p = w.collision_params().unwrap();
            w.set_collisions(p).unwrap()
        }),
    ];
    for (what, change) in changes {
        let mut w = pile(0.3, 0.5);
        until_asleep(&mut w, 6000);
        change(&mut w);
        w.step().unwrap();
        assert_eq!(last(&w).asleep, 0, "{what}");
    }
}

#[test]
fn nothing_unsupported_sleeps_and_no_spring_pulls_a_sleeper() {
    // Two touching balls drifting at 1 mm/s under a zero field (calm, but on nothing): they
    // never sleep, and keep their momentum exactly (Newton's first law).
    let mut w = world(0.5, 0.0);
    w.add_particles(
        &[0.0, 0.0, 0.0, 0.2, 0.0, 0.0],
        &[1e-3, 0.0, 0.0, 1e-3, 0.0, 0.0],
        &[1.0, 1.0],
        &[0.1, 0.1],
        &[false, false],
    )
    .unwrap();
    w.add_force(Box::new(Gravity::new([0.0; 3]).unwrap())).unwrap();
    for _ in 0..2000 {
        w.step().unwrap();
        assert_eq!(last(&w).asleep, 0);
    }
    assert_eq!(w.particles().v[0], 1e-3);

    // A ball at rest on a floor, tied by a spring to a point: a force that depends on the
    // positions keeps every island awake.
    let mut w = world(0.5, 0.0);
    w.add_particles(
        &[0.0, 0.0, 0.1, 0.0, 0.0, 1.0],
        &[0.0; 6],
        &[1.0, 1.0],
        &[0.1, 0.1],
        &[false, true],
    )
    .unwrap();
    w.add_force(Box::new(Gravity::new([0.0, 0.0, -G]).unwrap())).unwrap();
    w.add_force(Box::new(
        Springs::new(vec![0], vec![1], vec![1.0], vec![0.9], vec![0.0]).unwrap(),
    ))
    .unwrap();
    w.add_collider(Plane::new([0.0; 3], [0.0, 0.0, 1.0], Surface::default()).unwrap())
        .unwrap();
    for _ in 0..2000 {
        w.step().unwrap();
        assert_eq!(last(&w).asleep, 0);
    }
}

#[test]
fn with_sleep_time_none_nothing_sleeps() {
    let mut w = pile(0.5, 0.5);
    let mut params = w.collision_params().unwrap();
    params.sleep_time = None;
    w.set_collisions(params).unwrap();
    for _ in 0..4000 {
        w.step().unwrap();
        assert_eq!(last(&w).asleep, 0);
    }
    assert_eq!(total(&w).slept, 0);
}

#[test]
fn a_heap_on_pinned_particles_sleeps_and_stays_asleep() {
    // A floor of 6 × 6 pinned balls and no collider: 16 balls settle on it and sleep, and the
    // pinned floor (which touches them, but never moves) wakes nothing: no island is woken in
    // the next 2 s, and none falls asleep again.
    let mut w = world(0.3, 0.5);
    let (mut x, mut pinned) = (Vec::new(), Vec::new());
    for k in 0..36 {
        x.extend([0.1 * (k % 6) as f64, 0.1 * (k / 6) as f64, 0.0]);
        pinned.push(true);
    }
    for k in 0..16 {
        x.extend([0.07 + 0.11 * (k % 4) as f64, 0.07 + 0.11 * (k / 4) as f64, 0.3]);
        pinned.push(false);
    }
    let n = pinned.len();
    w.add_particles(&x, &vec![0.0; 3 * n], &vec![1.0; n], &vec![0.05; n], &pinned)
        .unwrap();
    w.add_force(Box::new(Gravity::new([0.0, 0.0, -G]).unwrap())).unwrap();
    let mut steps = 0;
    while last_or_default(&w).asleep < 16 {
        w.step().unwrap();
        steps += 1;
        assert!(steps < 5000, "not asleep: {:?}", last(&w));
    }
    let slept = total(&w).slept;
    let x_asleep = w.particles().x.clone();
    for _ in 0..2000 {
        w.step().unwrap();
        assert_eq!(last(&w).asleep, 16);
    }
    assert_eq!((total(&w).slept, total(&w).woke), (slept, 0));
    assert_eq!(w.particles().x, x_asleep);
}

fn last_or_default(w: &World) -> CollisionStats {
    w.collision_stats().map(|s| s.0).unwrap_or_default()
}
