//! A crowd of particles with random velocities, run by a World (impulse model: impacts found
//! inside the steps, then the end-of-step contact solve, with restitution and friction),
//! keeps the books of classical mechanics over many steps:
//! - impulses between particles are equal and opposite (action = reaction), so Σ m v of the
//!   movable particles changes only through the walls and pinned particles: exactly (to
//!   rounding) constant over any step in which no movable particle comes near either, and
//!   constant throughout in a periodic box without them;
//! - the books' impulse balance (Σ m Δv minus what walls and pinned particles gave) is 0 to
//!   rounding;
//! - with e ≤ 1 and friction the kinetic energy, measured from the velocities, never rises
//!   (no forces act), and what it lost is the energy the books say the collisions took.

use kinema::collide::{BoxContainer, Surface};
use kinema::ode::{Integrator, Method};
use kinema::world::CollisionParams;
use kinema::{World, WorldParams};

mod common;
use common::Rng;

const DT: f64 = 1e-3;

struct Crowd {
    x: Vec<f64>,
    v: Vec<f64>,
    mass: Vec<f64>,
    radius: Vec<f64>,
}

/// `side`^dim particles on a lattice of spacing 0.2 m from `origin`, jittered by ±0.02 m,
/// radii 0.05–0.08 m (apart at the start, so that every collision is an impact or a contact
/// of the run), masses 0.5–5 kg, velocity components up to ±2 m/s.
fn crowd(dim: usize, side: usize, origin: f64, seed: u64) -> Crowd {
    let mut rng = Rng(seed);
    let n = side.pow(dim as u32);
    let mut c = Crowd {
        x: Vec::with_capacity(3 * n),
        v: Vec::with_capacity(3 * n),
        mass: Vec::with_capacity(n),
        radius: Vec::with_capacity(n),
    };
    for p in 0..n {
        let cell = [p % side, (p / side) % side, p / (side * side)];
        for (k, &at) in cell.iter().enumerate() {
            if k < dim {
                c.x.push(origin + 0.2 * (at as f64 + 0.5) + 0.04 * (rng.next() - 0.5));
                c.v.push(4.0 * (rng.next() - 0.5));
            } else {
                c.x.push(0.0);
                c.v.push(0.0);
            }
        }
        c.mass.push(0.5 + 4.5 * rng.next());
        c.radius.push(0.05 + 0.03 * rng.next());
    }
    c
}

fn world(dim: usize) -> World {
    let mut w = World::new(WorldParams {
        dt: DT,
        method: Integrator::Named(Method::Verlet),
        dim,
    })
    .unwrap();
    w.set_collisions(CollisionParams {
        restitution: 0.6,
        friction: 0.3,
        ..CollisionParams::default()
    })
    .unwrap();
    w
}

/// Σ m v over the movable particles.
fn momentum(w: &World) -> [f64; 3] {
    let p = w.particles();
    let mut s = [0.0; 3];
    for (i, m) in p.mass.iter().enumerate() {
        if p.inv_mass[i] > 0.0 {
            for (k, sk) in s.iter_mut().enumerate() {
                *sk += m * p.v[3 * i + k];
            }
        }
    }
    s
}

fn kinetic(w: &World) -> f64 {
    let p = w.particles();
    p.mass
        .iter()
        .enumerate()
        .map(|(i, m)| 0.5 * m * (p.v[3 * i].powi(2) + p.v[3 * i + 1].powi(2) + p.v[3 * i + 2].powi(2)))
        .sum()
}

/// Σ m |v| over the particles: the scale of the momentum's rounding.
fn momentum_scale(w: &World) -> f64 {
    let p = w.particles();
    (0..p.len())
        .map(|i| p.mass[i] * (p.v[3 * i].powi(2) + p.v[3 * i + 1].powi(2) + p.v[3 * i + 2].powi(2)).sqrt())
        .sum()
}

fn fastest(w: &World) -> f64 {
    let v = &w.particles().v;
    (0..v.len() / 3)
        .map(|i| (v[3 * i].powi(2) + v[3 * i + 1].powi(2) + v[3 * i + 2].powi(2)).sqrt())
        .fold(0.0, f64::max)
}

#[test]
fn a_2d_crowd_in_a_box_changes_momentum_only_through_the_walls() {
    // 12 × 12 discs in the middle of the box [0, 4]², and four pinned posts near its corners:
    // the crowd first collides only within itself (Σ m v exactly constant), then spreads
    // onto the walls and posts (Σ m v changes, and only in steps where a particle is near
    // one: a particle can reach a wall or a post within a step only from closer than its
    // radius plus the distance the fastest particle covers in it).
    let side = 4.0;
    let c = crowd(2, 12, 0.8, 7);
    let mut w = world(2);
    w.add_collider(BoxContainer::rect([0.0, 0.0], [side, side], Surface::default()).unwrap())
        .unwrap();
    w.add_particles(&c.x, &c.v, &c.mass, &c.radius, &vec![false; c.mass.len()])
        .unwrap();
    let posts = [[0.3, 0.3], [3.7, 0.3], [0.3, 3.7], [3.7, 3.7]];
    let post_r = 0.1;
    let post_x: Vec<f64> = posts.iter().flat_map(|p| [p[0], p[1], 0.0]).collect();
    w.add_particles(&post_x, &[0.0; 12], &[1.0; 4], &[post_r; 4], &[true; 4])
        .unwrap();
    let n = c.mass.len();

    let scale = momentum_scale(&w);
    let e0 = kinetic(&w);
    let (mut quiet_steps, mut quiet_impacts, mut wall_steps) = (0, 0, 0);
    let mut moved_by_walls = false;
    let mut e_prev = e0;
    for _ in 0..3000 {
        let p0 = momentum(&w);
        let near_before = near_outside(&w, n, side, &posts, post_r);
        w.step().unwrap();
        let near = near_before || near_outside(&w, n, side, &posts, post_r);
        let p1 = momentum(&w);
        let dp = (0..3).map(|k| (p1[k] - p0[k]).abs()).fold(0.0, f64::max);
        let (last, _) = w.collision_stats().unwrap();
        if near {
            wall_steps += 1;
            moved_by_walls |= dp > 1e-6 * scale;
        } else {
            quiet_steps += 1;
            quiet_impacts += last.impacts;
            assert!(
                dp <= 1e-13 * scale,
                "step {}: Σ m v changed by {dp} with nothing outside near",
                w.steps()
            );
        }
        // Energy never rises (e ≤ 1, friction, no forces).
        let e1 = kinetic(&w);
        assert!(
            e1 <= e_prev + 1e-13 * e0,
            "step {}: kinetic energy rose {e_prev} → {e1}",
            w.steps()
        );
        e_prev = e1;
    }
    let (_, total) = w.collision_stats().unwrap();
    eprintln!(
        "2D: {} impacts, {quiet_steps} quiet steps ({quiet_impacts} impacts in them), {wall_steps} near walls, energy {e0} → {e_prev}",
        total.impacts
    );
    // The test means something: collisions inside the crowd while it is alone, and the
    // walls and posts taking momentum later.
    assert!(
        quiet_steps > 100 && quiet_impacts > 100,
        "{quiet_steps} quiet steps, {quiet_impacts} impacts"
    );
    assert!(wall_steps > 100 && moved_by_walls, "the walls never acted");
    assert!(e_prev < 0.9 * e0, "e = 0.6 and μ = 0.3 take energy: {e0} → {e_prev}");
    for k in 0..3 {
        assert!(total.impulse_balance[k].abs() <= 1e-12 * scale, "{total:?}");
    }
    assert!(
        ((e0 - e_prev) - total.energy_lost).abs() <= 1e-9 * e0,
        "measured loss {} vs the books' {}",
        e0 - e_prev,
        total.energy_lost
    );
    let p = w.particles();
    assert!(p.x.iter().skip(2).step_by(3).all(|z| *z == 0.0), "2D stays in the plane");
    assert!(p.v.iter().skip(2).step_by(3).all(|z| *z == 0.0), "2D stays in the plane");
    assert_eq!(&p.x[3 * n..], &post_x[..], "a pinned post moved");
    assert_eq!(&p.v[3 * n..], &[0.0; 12], "a pinned post moved");
}

/// Whether a movable particle (the first `n`) is within reach of a wall of the box [0, side]²
/// or of a pinned post in the coming or past step: closer than its radius plus the distance
/// the fastest particle covers in two steps, plus the speculative margin of the end-of-step
/// contacts (0.05 of the sizes; 0.1 taken).
fn near_outside(w: &World, n: usize, side: f64, posts: &[[f64; 2]], post_r: f64) -> bool {
    let p = w.particles();
    let reach = 2.0 * fastest(w) * DT;
    (0..n).any(|i| {
        let (x, y, r) = (p.x[3 * i], p.x[3 * i + 1], p.radius[i]);
        let margin = reach + 0.1 * 2.0 * r;
        let wall = [x, side - x, y, side - y].iter().any(|d| *d < r + margin);
        let post = posts.iter().any(|q| {
            let d = ((x - q[0]).powi(2) + (y - q[1]).powi(2)).sqrt();
            d < r + post_r + margin + 0.1 * (r + post_r)
        });
        wall || post
    })
}

#[test]
fn a_periodic_3d_crowd_conserves_momentum() {
    // 6³ balls filling the periodic cell [0, 1.2]³: no walls, no pinned particles, so Σ m v
    // is the same after every step to rounding, also through the pairs that meet across
    // the cell's faces.
    let side = 1.2;
    let c = crowd(3, 6, 0.0, 11);
    let mut w = world(3);
    w.add_collider(BoxContainer::new([0.0; 3], [side; 3], Surface::default()).unwrap())
        .unwrap();
    w.add_particles(&c.x, &c.v, &c.mass, &c.radius, &vec![false; c.mass.len()])
        .unwrap();
    w.set_periodic([true; 3]).unwrap();
    let scale = momentum_scale(&w);
    let (p0, e0) = (momentum(&w), kinetic(&w));
    let mut e_prev = e0;
    let mut across = 0;
    for _ in 0..1000 {
        w.step().unwrap();
        let p1 = momentum(&w);
        for k in 0..3 {
            assert!(
                (p1[k] - p0[k]).abs() <= 1e-12 * scale,
                "step {}: momentum {k} {} → {}",
                w.steps(),
                p0[k],
                p1[k]
            );
        }
        let e1 = kinetic(&w);
        assert!(
            e1 <= e_prev + 1e-13 * e0,
            "step {}: kinetic energy rose {e_prev} → {e1}",
            w.steps()
        );
        e_prev = e1;
        // contacts whose partners lie on opposite sides of the cell (met across a face)
        let x = &w.particles().x;
        across += w
            .contacts()
            .iter()
            .filter(|k| {
                k.partner_particle()
                    .is_some_and(|j| (0..3).any(|d| (x[3 * k.i + d] - x[3 * j + d]).abs() > 0.5 * side))
            })
            .count();
    }
    let (_, total) = w.collision_stats().unwrap();
    eprintln!(
        "3D periodic: {} impacts, {across} contacts across the faces, energy {e0} → {e_prev}",
        total.impacts
    );
    assert!(total.impacts > 200, "{total:?}");
    assert!(across > 5, "only {across} contacts across the cell's faces");
    assert!(e_prev < 0.9 * e0, "e = 0.6 and μ = 0.3 take energy: {e0} → {e_prev}");
    for k in 0..3 {
        assert!(total.impulse_balance[k].abs() <= 1e-12 * scale, "{total:?}");
    }
    assert!(
        ((e0 - e_prev) - total.energy_lost).abs() <= 1e-9 * e0,
        "measured loss {} vs the books' {}",
        e0 - e_prev,
        total.energy_lost
    );
    assert!(w.particles().x.iter().all(|c| (0.0..side).contains(c)), "outside the cell");
}
