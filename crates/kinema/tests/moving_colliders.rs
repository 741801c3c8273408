//! Colliders with a prescribed motion (impulse model) against closed forms.
//!
//! Theory used: a wall of infinite mass moving at V hits a body at rest along its normal;
//! in the wall's frame the body approaches at −V and leaves at e V (Newton's law), so it
//! leaves at (1 + e) V: its momentum gain m (1 + e) V is the wall's loss, the wall does
//! the work J·V = m (1 + e) V², and the pair dissipates ½ m (1 − e²) V² (the loss of the
//! wall's frame). A body that sticks by friction to a wall moves with the wall's surface at
//! the contact point; a body on a wall that turns at ω about an axis through c is carried
//! up while tan θ < μ (θ from the bottom) — its momentum changes only by what gravity and
//! the wall give it.

mod common;

use kinema::collide::{Motion, Plane, Surface, TriangleMesh};
use kinema::forces::Gravity;
use kinema::ode::Method;
use kinema::world::CollisionParams;
use kinema::World;

fn world(e: f64, mu: f64, dt: f64) -> World {
    let collisions = CollisionParams {
        restitution: e,
        friction: mu,
        sleep_time: None,
        ..CollisionParams::default()
    };
    common::impulse_world(3, Method::Verlet, dt, collisions)
}

#[test]
fn a_moving_wall_throws_a_ball_at_one_plus_e_times_its_speed() {
    // A plane x = 0 with normal +x moving at V = 3 m/s along +x into a ball at rest at
    // x = 1 (r = 0.1): the ball leaves at (1 + e) V; the wall's books: momentum −m (1 + e) V,
    // work m (1 + e) V²; the particles' energy "lost" is −½ m (1 + e)² V², so that work +
    // lost = ½ m (1 − e²) V², the dissipation of the wall's frame. Also with the wall turned
    // into the motion's direction by a keyframed translation (the same speed from 0 to 1 s).
    let (m, v_wall) = (2.0, 3.0);
    for e in [1.0, 0.6, 0.0] {
        for keyed in [false, true] {
            let mut w = world(e, 0.0, 1e-3);
            w.add_particles(&[1.0, 0.0, 0.0], &[0.0; 3], &[m], &[0.1], &[false]).unwrap();
            let k = w
                .add_collider(Plane::new([0.0; 3], [1.0, 0.0, 0.0], Surface::default()).unwrap())
                .unwrap();
            let motion = if keyed {
                Motion::keyframes(
                    vec![0.0, 1.0],
                    vec![[0.0; 3], [v_wall, 0.0, 0.0]],
                    vec![[1.0, 0.0, 0.0, 0.0]; 2],
                    [0.0; 3],
                )
                .unwrap()
            } else {
                Motion::steady([v_wall, 0.0, 0.0], [0.0; 3], [0.0; 3]).unwrap()
            };
            w.set_collider_motion(k, Some(motion)).unwrap();
            for _ in 0..500 {
                w.step().unwrap();
            }
            let v = w.particles().v[0];
            let want = (1.0 + e) * v_wall;
            // e = 0: the ball rides with the wall (u_n⁺ = 0): v = V
            assert!((v - want).abs() < 1e-9, "e {e}, keyed {keyed}: v {v} vs {want}");
            let books = w.collider_books(false)[k];
            assert!(
                (books.momentum[0] + m * want).abs() < 1e-9,
                "e {e}: momentum {:?}",
                books.momentum
            );
            assert!((books.work - m * want * v_wall).abs() < 1e-9, "e {e}: work {}", books.work);
            let lost = w.collision_stats().unwrap().1.energy_lost;
            let dissipated = 0.5 * m * (1.0 - e * e) * v_wall * v_wall;
            assert!(
                (lost + books.work - dissipated).abs() < 1e-9,
                "e {e}: lost {lost} + work {} vs {dissipated}",
                books.work
            );
            // the ball is never behind the wall
            let wall_x = v_wall * w.time().min(if keyed { 1.0 } else { f64::INFINITY });
            assert!(
                w.particles().x[0] >= wall_x + 0.1 - 1e-9,
                "e {e}: x {} wall {wall_x}",
                w.particles().x[0]
            );
        }
    }
}

/// A closed cylinder of radius `r` and length `len` about the y axis, centred at the
/// origin, `segments` around.
fn drum(r: f64, len: f64, segments: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let mut v = Vec::new();
    for side in [-0.5 * len, 0.5 * len] {
        for s in 0..segments {
            let a = std::f64::consts::TAU * s as f64 / segments as f64;
            v.push([r * a.cos(), side, r * a.sin()]);
        }
    }
    let (c0, c1) = (v.len() as u32, v.len() as u32 + 1);
    v.push([0.0, -0.5 * len, 0.0]);
    v.push([0.0, 0.5 * len, 0.0]);
    let n = segments as u32;
    let mut f = Vec::new();
    for s in 0..n {
        let t = (s + 1) % n;
        f.push([s, t, n + t]);
        f.push([s, n + t, n + s]);
        f.push([c0, t, s]);
        f.push([c1, n + s, n + t]);
    }
    (v, f)
}

#[test]
fn a_turning_drum_carries_a_ball_with_its_wall_until_it_slips() {
    // A drum of radius 0.5 m turning at ω = 0.5 rad/s about y, μ = 1 (slip at tan θ = 1,
    // θ = 45° from the bottom), a ball (r = 0.05) at rest at its bottom under gravity. While
    // it sticks, its velocity is the wall's at the contact point, ω × (x_c − c), to the
    // solver's tolerance, and it climbs at ω; it first slips at 45° (to the facets' tilt,
    // π/256, and a step's turn); its momentum change is gravity's impulse plus the wall's,
    // which the wall's books hold with the opposite sign.
    let (radius, r, omega, g, m) = (0.5, 0.05, 0.5, 9.81, 0.3);
    let (v, f) = drum(radius, 0.4, 256);
    let mut w = world(0.0, 1.0, 1e-3);
    let k = w
        .add_collider(TriangleMesh::new(v, f, true, Surface::default()).unwrap())
        .unwrap();
    w.set_collider_motion(k, Some(Motion::steady([0.0; 3], [0.0, omega, 0.0], [0.0; 3]).unwrap()))
        .unwrap();
    w.add_particles(
        &[0.0, 0.0, -(radius - r) * (std::f64::consts::PI / 256.0).cos()],
        &[0.0; 3],
        &[m],
        &[r],
        &[false],
    )
    .unwrap();
    w.add_force(Box::new(Gravity::new([0.0, 0.0, -g]).unwrap())).unwrap();
    let facet = 2.0 * radius * (std::f64::consts::PI / 256.0).sin();
    let (mut checked, mut exact) = (0, 0);
    let mut slip: Option<f64> = None;
    for step in 0..2000 {
        w.step().unwrap();
        let p = w.particles();
        let (x, vel) = ([p.x[0], p.x[1], p.x[2]], [p.v[0], p.v[1], p.v[2]]);
        // θ from the bottom (ω along +y carries the bottom towards −x)
        let theta = x[0].atan2(-x[2]);
        if step > 100 && slip.is_none() {
            // the wall's velocity at the contact point on its facet, x_c = x − (r − δ) n:
            // ω × x_c (the drum turns about the origin); the facet it rests on is the
            // deepest contact (the others are its neighbours within the speculative margin)
            let c = *w.contacts().iter().max_by(|a, b| a.overlap.total_cmp(&b.overlap)).unwrap();
            let xc = [0, 1, 2].map(|q| x[q] - (r - c.overlap) * c.normal[q]);
            let u = [omega * xc[2], 0.0, -omega * xc[0]];
            let off = (0..3).map(|q| (vel[q] - c.wall_velocity[q]).abs()).fold(0.0, f64::max);
            if off >= 0.5 * omega * facet {
                // beyond what a crease explains: sliding, whose speed grows from 0 as
                // g (sin θ − μ cos θ) ≈ √2 g (θ − 45°): detected within about 1° of the onset
                slip = Some(theta.abs());
                continue;
            }
            for q in 0..3 {
                // (the contact was detected before the solve moved the ball by its overlap)
                assert!(
                    (c.wall_velocity[q] - u[q]).abs() <= omega * 2.0 * c.overlap.abs() + 1e-15,
                    "step {step}: {:?} vs ω × x_c {u:?}",
                    c.wall_velocity
                );
                // sticking: within ω s / 2 of the wall's velocity there (s the facet's width:
                // at a crease it rests on two facets whose surface velocities differ by ω s)
                assert!(
                    (vel[q] - c.wall_velocity[q]).abs() < 0.5 * omega * facet,
                    "step {step}: v {vel:?} vs wall {:?}",
                    c.wall_velocity
                );
            }
            // and on one facet, to the end-of-step solver's tolerance (1e-9 m/s a contact)
            if off < 1e-8 {
                exact += 1;
            }
            checked += 1;
        }
    }
    assert!(checked > 500, "it stuck for {checked} steps");
    eprintln!("stuck {checked} steps, {exact} to 1e-8 m/s");
    assert!(
        exact as f64 > 0.8 * checked as f64,
        "on one facet: {exact} of {checked} steps"
    );
    let slip = slip.expect("it slips").to_degrees();
    eprintln!("slips at {slip}°");
    // the onset within a facet's tilt (π/256 rad = 0.7°) of 45°; detected when the sliding speed,
    // u ≈ √2 g ω t² / 2 after it, reaches ω s / 2: 0.03 s, 0.85° of turn later
    assert!(slip > 45.0 - 0.7 && slip < 45.0 + 0.7 + 1.0, "slips at {slip}°");
    // momentum: m v(t) − 0 = m g t + J_wall, J_wall = −books.momentum
    let p = w.particles();
    let t = w.time();
    let books = w.collider_books(false)[k];
    let want = [m * p.v[0], m * p.v[1], m * p.v[2] + m * g * t];
    for c in 0..3 {
        assert!(
            (-books.momentum[c] - want[c]).abs() < 1e-9,
            "{c}: wall gave {:?}, change {want:?}",
            books.momentum.map(|q| -q)
        );
    }
}

#[test]
fn a_box_only_translates_and_a_2d_motion_keeps_the_plane() {
    let mut w = world(1.0, 0.0, 1e-3);
    let k = w
        .add_collider(kinema::collide::BoxContainer::new([0.0; 3], [1.0; 3], Surface::default()).unwrap())
        .unwrap();
    let e = w
        .set_collider_motion(k, Some(Motion::steady([0.0; 3], [0.0, 0.0, 1.0], [0.5; 3]).unwrap()))
        .unwrap_err()
        .to_string();
    assert!(e.contains("a box collider stays axis-aligned"), "{e}");
    assert!(
        w.colliders()[k]
            == kinema::collide::Collider::Box(
                kinema::collide::BoxContainer::new([0.0; 3], [1.0; 3], Surface::default()).unwrap()
            )
    );
    let mut w2 = common::impulse_world(2, Method::Verlet, 1e-3, CollisionParams::default());
    let k = w2
        .add_collider(Plane::new([0.0; 3], [1.0, 0.0, 0.0], Surface::default()).unwrap())
        .unwrap();
    let e = w2
        .set_collider_motion(k, Some(Motion::steady([0.0, 0.0, 1.0], [0.0; 3], [0.0; 3]).unwrap()))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("velocity[2] = 1 is invalid: a 2D world keeps z = 0"), "{e}");
}
