//! The impulse model's candidate list in a World: a list built for a fast step is rebuilt
//! tight once the particles are slow again (`impulse/impacts.rs`, `prepare`'s `loose`), and
//! the impact search passes over only the candidates that cannot meet within the step
//! (`events::SweepBound`).

use super::Rng;
use crate::collide::{BoxContainer, Surface};
use crate::forces::Gravity;
use crate::ode::{Integrator, Method};
use crate::world::CollisionParams;
use crate::{World, WorldParams};

#[test]
fn a_pile_at_rest_keeps_no_skin_from_its_fall() {
    // 27 balls (r = 2 cm) dropped 1 m into a box at 60 Hz: falling at up to 4.4 m/s they sweep
    // 7 cm a step, so the list's skin is four of that, 30 cm (the whole box: every ball a
    // candidate of every other). At rest the skin a rebuild chooses is 0.6 r = 1.2 cm: the
    // list must come back to it (within its hysteresis of 4), not keep the fall's.
    let dt = 1.0 / 60.0;
    let mut w = World::new(WorldParams {
        dt,
        method: Integrator::Named(Method::Verlet),
        dim: 3,
    })
    .unwrap();
    let (mut x, r) = (Vec::new(), 0.02);
    for k in 0..27 {
        x.extend([
            0.05 + 0.06 * (k % 3) as f64,
            0.05 + 0.06 * (k / 3 % 3) as f64,
            1.0 + 0.06 * (k / 9) as f64,
        ]);
    }
    let v = vec![0.0; x.len()];
    w.add_particles(&x, &v, &[1.0; 27], &[r; 27], &[false; 27]).unwrap();
    w.add_force(Box::new(Gravity::new([0.0, 0.0, -9.81]).unwrap())).unwrap();
    w.add_collider(BoxContainer::new([0.0; 3], [0.2, 0.2, 2.0], Surface::default()).unwrap())
        .unwrap();
    w.set_collisions(CollisionParams {
        restitution: 0.3,
        friction: 0.5,
        sleep_time: None,
        ..CollisionParams::default()
    })
    .unwrap();
    let skin = |w: &World| w.impulse_list_skin().unwrap();
    let mut largest: f64 = 0.0;
    for _ in 0..(4.0 / dt) as usize {
        w.step().unwrap();
        largest = largest.max(skin(&w));
    }
    assert!(largest > 0.2, "the fall's skin: {largest} m");
    let speed = w.particles().v.iter().fold(0.0_f64, |m, c| m.max(c.abs()));
    assert!(speed < 0.05, "at rest: {speed} m/s");
    assert!(skin(&w) <= 4.0 * 0.6 * r * 1.0000001, "the skin at rest: {} m", skin(&w));
}

#[test]
fn a_lattice_too_fast_for_a_list_of_four_sweeps_is_stepped_on_one_of_two_and_a_half() {
    // 125 balls (r = 3 cm) on a 10 cm lattice thrown down at 10 m/s, at 60 Hz: each sweeps
    // 16.8 cm in the step (v h + g h²/2, and the parabola's bulge g h²/8), so a skin of four
    // sweeps lists nearly every pair. With the list's bound between what that skin and one of
    // 2.5 sweeps need, the step must be taken on the smaller list, not refused.
    let dt = 1.0 / 60.0;
    let (r, v0, g) = (0.03, 10.0, 9.81);
    let mut x = Vec::new();
    for k in 0..125 {
        x.extend([0.1 * (k % 5) as f64, 0.1 * (k / 5 % 5) as f64, 1.0 + 0.1 * (k / 25) as f64]);
    }
    let largest = v0 * dt + 0.5 * g * dt * dt + 0.125 * g * dt * dt;
    // the pairs a list of skin s holds (both sides: a full list), counted by brute force
    let entries = |s: f64| {
        let mut count = 0;
        for i in 0..125 {
            for j in 0..125 {
                let d: f64 = (0..3).map(|k| (x[3 * i + k] - x[3 * j + k]).powi(2)).sum::<f64>().sqrt();
                count += usize::from(i != j && d < 2.0 * r + s);
            }
        }
        count
    };
    let limit = entries(2.6 * largest);
    assert!(
        entries(3.9 * largest) > limit,
        "the test needs a list of four sweeps to pass the bound"
    );
    let mut w = World::new(WorldParams {
        dt,
        method: Integrator::Named(Method::Verlet),
        dim: 3,
    })
    .unwrap();
    let v: Vec<f64> = (0..125).flat_map(|_| [0.0, 0.0, -v0]).collect();
    w.add_particles(&x, &v, &[1.0; 125], &[r; 125], &[false; 125]).unwrap();
    w.add_force(Box::new(Gravity::new([0.0, 0.0, -g]).unwrap())).unwrap();
    w.set_collisions(CollisionParams::default()).unwrap();
    w.set_impulse_list_limit(limit);
    w.step().unwrap();
    let skin = w.impulse_list_skin().unwrap();
    assert!(
        skin < 3.0 * largest && skin >= 2.5 * largest,
        "skin {skin} m, sweep {largest} m"
    );
}

/// One member of the class the sweep bound's check must leave unchanged (`events::SweepBound`).
struct Heap {
    dim: usize,
    n: usize,
    dt: f64,
    /// Radii in [r, ratio · r].
    r: f64,
    ratio: f64,
    /// Speeds up to this, m/s; particle 0 is thrown at `fast` m/s.
    speed: f64,
    fast: f64,
    gravity: bool,
    periodic: bool,
    seed: u64,
}

impl Heap {
    /// The world: particles placed apart at random in a box of side 1 m (a tall one under
    /// gravity), restitution 0.6, friction 0.3; with `unbounded`, the search without the check.
    fn world(&self, unbounded: bool) -> World {
        let mut rng = Rng(self.seed);
        let (mut x, mut radius): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
        let height = if self.gravity { 3.0 } else { 1.0 };
        while radius.len() < self.n {
            let r = rng.uniform(self.r, self.ratio * self.r);
            let p = [
                rng.uniform(r, 1.0 - r),
                rng.uniform(r, height - r),
                if self.dim == 3 { rng.uniform(r, 1.0 - r) } else { 0.0 },
            ];
            let clear = radius.iter().enumerate().all(|(k, &rk)| {
                let d: f64 = (0..3).map(|c| (p[c] - x[3 * k + c]).powi(2)).sum::<f64>().sqrt();
                d > r + rk
            });
            if clear {
                x.extend(p);
                radius.push(r);
            }
        }
        let mut v: Vec<f64> = (0..3 * self.n)
            .map(|c| {
                if c % 3 == 2 && self.dim == 2 {
                    0.0
                } else {
                    rng.uniform(-self.speed, self.speed)
                }
            })
            .collect();
        v[0] = self.fast;
        let mut w = World::new(WorldParams {
            dt: self.dt,
            method: Integrator::Named(Method::Verlet),
            dim: self.dim,
        })
        .unwrap();
        let mass: Vec<f64> = radius.iter().map(|r| 1e3 * r.powi(3)).collect();
        w.add_particles(&x, &v, &mass, &radius, &vec![false; self.n]).unwrap();
        if self.gravity {
            w.add_force(Box::new(Gravity::new([0.0, -9.81, 0.0]).unwrap())).unwrap();
        }
        // (in 2D a rectangle: open along z)
        let (lo_z, hi_z) = if self.dim == 3 {
            (0.0, 1.0)
        } else {
            (f64::NEG_INFINITY, f64::INFINITY)
        };
        w.add_collider(BoxContainer::new([0.0, 0.0, lo_z], [1.0, height, hi_z], Surface::default()).unwrap())
            .unwrap();
        w.set_collisions(CollisionParams {
            restitution: 0.6,
            friction: 0.3,
            ..CollisionParams::default()
        })
        .unwrap();
        if self.periodic {
            w.set_periodic([true, false, false]).unwrap();
        }
        if unbounded {
            w.search_unbounded();
        }
        w
    }
}

#[test]
fn the_sweep_bound_passes_over_only_pairs_that_meet_nothing() {
    // The impact search passes over a candidate pair farther apart at the list's build than
    // their radii and both particles' sweep bounds (`events::SweepBound`): such a pair cannot
    // meet within the step, so the step must be bit for bit the one that solves every
    // candidate's time of impact. Checked on heaps of other dimensions, sizes, radii (1:1 to
    // 1:4), speeds (one particle thrown at up to 200 m/s: lists rebuilt inside a step),
    // steps (1 ms to 1/30 s), a force-free periodic gas (one bound for all, from the meeting
    // times) and piles under gravity that come to rest and fall asleep.
    let heaps = [
        (3, 300, 1.0 / 60.0, 0.03, 1.0, 2.0, 40.0, true, false, 1),
        (3, 200, 1e-3, 0.02, 4.0, 1.0, 200.0, true, false, 2),
        (2, 400, 1.0 / 120.0, 0.015, 2.0, 3.0, 60.0, true, true, 3),
        (2, 300, 1.0 / 30.0, 0.02, 1.0, 0.5, 5.0, true, false, 4),
        (3, 400, 1e-2, 0.03, 1.5, 2.0, 30.0, false, true, 5),
        (2, 500, 5e-3, 0.01, 3.0, 4.0, 100.0, false, false, 6),
    ];
    for (dim, n, dt, r, ratio, speed, fast, gravity, periodic, seed) in heaps {
        let heap = Heap {
            dim,
            n,
            dt,
            r,
            ratio,
            speed,
            fast,
            gravity,
            periodic,
            seed,
        };
        let (mut bounded, mut every) = (heap.world(false), heap.world(true));
        let steps = (2.0 / dt).min(300.0) as usize;
        for k in 0..steps {
            bounded.step().unwrap();
            every.step().unwrap();
            let (a, b) = (bounded.particles(), every.particles());
            assert!(
                a.x == b.x && a.v == b.v,
                "heap {seed} ({dim}D, {n}, dt {dt}): the states part at step {k}"
            );
        }
        let (a, b) = (bounded.collision_stats().unwrap().1, every.collision_stats().unwrap().1);
        assert_eq!(a.impacts, b.impacts, "heap {seed}");
        assert!(a.impacts > n, "heap {seed}: the heap has impacts to find ({})", a.impacts);
    }
}
