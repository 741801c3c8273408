//! Worlds whose particle count changes: removing particles between steps leaves exactly the
//! world one would build from the survivors (same state, forces, springs among survivors,
//! colliders), bit for bit over the steps that follow, for both contact models and the
//! integrators; ids are never reused; springs die with an end.

use kinema::collide::{BoxContainer, Collider, Surface};
use kinema::forces::{Gravity, Springs};
use kinema::ode::{Integrator, Method};
use kinema::world::{CollisionParams, ContactModel};
use kinema::{World, WorldParams};

/// A small deterministic generator (no dependency), uniform in [lo, hi).
struct Lcg(u64);
impl Lcg {
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
}

struct Setup {
    method: Method,
    model: Option<ContactModel>,
    springs: bool,
}

/// `n` particles on a jittered lattice in a 1 m box under gravity; with `springs`, a spring
/// from each particle to the next one.
fn build(s: &Setup, x: &[f64], v: &[f64], m: &[f64], r: &[f64], springs: &[(usize, usize)]) -> World {
    let mut w = World::new(WorldParams {
        dt: 2e-4,
        method: Integrator::Named(s.method),
        dim: 3,
    })
    .unwrap();
    if let Some(model) = s.model {
        w.set_collisions(CollisionParams {
            model,
            restitution: 0.7,
            ..CollisionParams::default()
        })
        .unwrap();
        w.add_collider(BoxContainer::new([0.0; 3], [1.0; 3], Surface::default()).unwrap())
            .unwrap();
    }
    w.add_particles(x, v, m, r, &vec![false; m.len()]).unwrap();
    w.add_force(Box::new(Gravity::new([0.0, 0.0, -9.81]).unwrap())).unwrap();
    if s.springs && !springs.is_empty() {
        let (i, j): (Vec<usize>, Vec<usize>) = springs.iter().copied().unzip();
        w.add_force(Box::new(Springs::with_rest_from_positions(i, j, 50.0, 0.01, x).unwrap()))
            .unwrap();
    }
    w
}

fn lattice(n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut rng = Lcg(7);
    let side = (n as f64).cbrt().ceil() as usize;
    let (mut x, mut v, mut m, mut r) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for p in 0..n {
        let (a, b, c) = (p % side, (p / side) % side, p / (side * side));
        for (k, q) in [a, b, c].into_iter().enumerate() {
            let _ = k;
            x.push(0.1 + 0.8 * (q as f64 + 0.5) / side as f64 + rng.uniform(-0.005, 0.005));
        }
        for _ in 0..3 {
            v.push(rng.uniform(-0.5, 0.5));
        }
        m.push(rng.uniform(0.5, 2.0) * 1e-3);
        r.push(0.3 * 0.8 / side as f64);
    }
    (x, v, m, r)
}

#[test]
fn a_world_after_removal_steps_as_the_world_built_from_its_survivors() {
    let n = 600; // above the size from which spring–dashpot worlds sort along space
    let setups = [
        Setup {
            method: Method::Verlet,
            model: Some(ContactModel::SpringDashpot {
                stiffness: 2e3,
                damping: None,
            }),
            springs: false,
        },
        Setup {
            method: Method::Verlet,
            model: Some(ContactModel::Impulse),
            springs: false,
        },
        Setup {
            method: Method::Rk4,
            model: None,
            springs: true,
        },
        Setup {
            method: Method::ImplicitEuler,
            model: None,
            springs: true,
        },
    ];
    for s in &setups {
        let (x, v, m, r) = lattice(n);
        let chain: Vec<(usize, usize)> = (0..n - 1).map(|p| (p, p + 1)).collect();
        let mut a = build(s, &x, &v, &m, &r, &chain);
        a.advance(40).unwrap();
        // Remove every third particle and a few more (repeats allowed).
        let gone: Vec<usize> = (0..n).filter(|p| p % 3 == 0).chain([1, 1, n - 1]).collect();
        a.remove_particles(&gone).unwrap();
        let kept: Vec<usize> = (0..n).filter(|p| !gone.contains(p)).collect();
        assert_eq!(a.particles().len(), kept.len());
        let ids: Vec<u64> = kept.iter().map(|&p| p as u64).collect();
        assert_eq!(a.particles().id, ids, "the survivors keep their ids, in order");

        // The survivors' world: their state now, springs between two survivors renumbered.
        let p = a.particles();
        let new_of: std::collections::HashMap<usize, usize> = kept.iter().enumerate().map(|(new, &old)| (old, new)).collect();
        let survivors: Vec<(usize, usize)> = chain
            .iter()
            .filter_map(|(i, j)| Some((*new_of.get(i)?, *new_of.get(j)?)))
            .collect();
        // rest lengths from the original positions, as the springs in `a` have them
        let x0: Vec<f64> = kept.iter().flat_map(|&q| x[3 * q..3 * q + 3].to_vec()).collect();
        let mut b = build(s, &x0, &p.v, &p.mass, &p.radius, &survivors);
        b.particles_mut().x.copy_from_slice(&p.x);
        b.particles_mut().v.copy_from_slice(&p.v);
        a.advance(60).unwrap();
        b.advance(60).unwrap();
        assert_eq!(a.particles().x, b.particles().x, "{:?} / {:?}: positions", s.method, s.model);
        assert_eq!(a.particles().v, b.particles().v, "{:?} / {:?}: velocities", s.method, s.model);
        if s.springs {
            assert!(survivors.len() < chain.len() / 3, "most springs lost an end");
        }
    }
}

#[test]
fn ids_are_never_reused_and_bad_indices_are_named() {
    let mut w = World::new(WorldParams::default()).unwrap();
    w.add_particles(&[0.0; 9], &[0.0; 9], &[1.0; 3], &[0.0; 3], &[false; 3])
        .unwrap();
    w.remove_particles(&[2]).unwrap();
    w.add_particles(&[0.0; 3], &[0.0; 3], &[1.0], &[0.0], &[false]).unwrap();
    assert_eq!(w.particles().id, vec![0, 1, 3]);
    let e = w.remove_particles(&[0, 3]).unwrap_err().to_string();
    assert!(e.contains("index[1] = 3") && e.contains("< 3"), "{e}");
    assert_eq!(w.particles().len(), 3, "a refused removal removes nothing");
    w.remove_particles(&[0, 1, 2]).unwrap();
    w.advance(3).unwrap(); // an empty world steps
    assert_eq!(w.steps(), 3);
}

/// A world of the particles (x, v, m, r, `pinned`) in `dim` dimensions with spring–dashpot
/// contacts (k_n = 2e3 N/m, e = 0.7), `collider`, gravity g (m/s²) and drag, stepped by
/// velocity Verlet with dt = 2e-4 s.
#[allow(clippy::too_many_arguments)]
fn contact_world(
    dim: usize,
    collider: Collider,
    g: [f64; 3],
    x: &[f64],
    v: &[f64],
    m: &[f64],
    r: &[f64],
    pinned: &[bool],
) -> World {
    let mut w = World::new(WorldParams {
        dt: 2e-4,
        method: Integrator::Named(Method::Verlet),
        dim,
    })
    .unwrap();
    w.set_collisions(CollisionParams {
        model: ContactModel::SpringDashpot {
            stiffness: 2e3,
            damping: None,
        },
        restitution: 0.7,
        ..CollisionParams::default()
    })
    .unwrap();
    w.add_collider(collider).unwrap();
    w.add_particles(x, v, m, r, pinned).unwrap();
    w.add_force(Box::new(Gravity::new(g).unwrap())).unwrap();
    w.add_force(Box::new(kinema::forces::Drag::new(1e-4, 1e-5).unwrap())).unwrap();
    w
}

/// [`contact_world`] in 3D in a 4 m box under g = 9.81 m/s² downwards (−z), nothing pinned;
/// with `springs`, a spring between particles 0 and 1 too.
fn verlet_world(x: &[f64], v: &[f64], m: &[f64], r: &[f64], springs: bool) -> World {
    let bounds = BoxContainer::new([0.0; 3], [4.0, 4.0, 4.0], Surface::default()).unwrap();
    let mut w = contact_world(3, bounds.into(), [0.0, 0.0, -9.81], x, v, m, r, &vec![false; m.len()]);
    if springs {
        w.add_force(Box::new(
            Springs::with_rest_from_positions(vec![0], vec![1], 50.0, 0.0, x).unwrap(),
        ))
        .unwrap();
    }
    w
}

/// `n` particles on the lattice, then 20 loners high above them, in free flight, none
/// touching another (positions, velocities, masses, radii).
fn heap_and_loners(n: usize) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
    let (mut x, mut v, mut m, mut r) = lattice(n);
    for k in 0..20 {
        x.extend([0.2 + 0.18 * k as f64, 2.0, 3.0]);
        v.extend([0.0, 0.1, 0.0]);
        m.push(1e-3);
        r.push(0.02);
    }
    (x, v, m, r)
}

/// Two equal spring–dashpot worlds of these particles ([`verlet_world`], no spring), 30
/// steps on.
fn twins(x: &[f64], v: &[f64], m: &[f64], r: &[f64]) -> (World, World) {
    let mut pair = (verlet_world(x, v, m, r, false), verlet_world(x, v, m, r, false));
    pair.0.advance(30).unwrap();
    pair.1.advance(30).unwrap();
    pair
}

/// Particle i's position and velocity (6 values).
fn state_of(w: &World, i: usize) -> Vec<f64> {
    let p = w.particles();
    [&p.x[3 * i..3 * i + 3], &p.v[3 * i..3 * i + 3]].concat()
}

#[test]
fn a_birth_or_death_that_touches_nothing_keeps_verlets_acceleration() {
    // Under per-particle forces (gravity, drag) and the contact force, a removal of
    // particles that touch no survivor, and a birth of particles that touch nothing, leave
    // every other particle's force as it was: the world keeps velocity Verlet's
    // acceleration (the next step evaluates the forces once, not twice), and every particle
    // moves, bit for bit, as in a world without the change. The drag makes that a test of the
    // kept acceleration itself: Verlet's a_n is evaluated at the predictor v + h a (the
    // dashpot's and the drag's velocity), so an acceleration evaluated afresh at the state
    // would differ (by about h γ a / m: 2e-5 of g here). A change that touches, or a force
    // between particles (a spring), drops it as before.
    let (x, v, m, r) = heap_and_loners(300);
    let n = m.len();
    let (mut a, mut same) = twins(&x, &v, &m, &r); // `same` is never changed
    let evals = |w: &World| w.stats().nfev;

    // A death among the loners: one evaluation for the next step (its kick), not two.
    let gone: Vec<usize> = (n - 20..n).step_by(2).collect();
    a.remove_particles(&gone).unwrap();
    let before = evals(&a);
    a.advance(1).unwrap();
    assert_eq!(evals(&a) - before, 1, "the kept acceleration: one evaluation per step");
    a.advance(40).unwrap();
    same.advance(41).unwrap();
    let stayed: Vec<usize> = (0..n).filter(|i| !gone.contains(i)).collect();
    for (now, &i) in stayed.iter().enumerate() {
        assert_eq!(state_of(&a, now), state_of(&same, i), "after a death: particle {i}");
    }

    // A birth in free space: the newborns' acceleration from the per-particle forces alone;
    // they move as they would alone in a world of their own, the others as before.
    let born = [1.0, 3.0, 3.5, 2.0, 3.0, 3.5, 3.0, 3.0, 3.5];
    let (vb, mb, rb, pinned) = (
        [0.0, 0.0, -1.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0],
        [2e-3, 1e-3, 1e-3],
        [0.03, 0.02, 0.02],
        [false, false, true],
    );
    a.add_particles(&born, &vb, &mb, &rb, &pinned).unwrap();
    let bounds = BoxContainer::new([0.0; 3], [4.0, 4.0, 4.0], Surface::default()).unwrap();
    let mut alone = contact_world(3, bounds.into(), [0.0, 0.0, -9.81], &born, &vb, &mb, &rb, &pinned);
    let before = evals(&a);
    a.advance(1).unwrap();
    assert_eq!(evals(&a) - before, 1, "a birth that touches nothing keeps it too");
    a.advance(40).unwrap();
    same.advance(41).unwrap();
    alone.advance(41).unwrap();
    for (now, &i) in stayed.iter().enumerate() {
        assert_eq!(state_of(&a, now), state_of(&same, i), "after a birth: particle {i}");
    }
    for k in 0..3 {
        assert_eq!(state_of(&a, stayed.len() + k), state_of(&alone, k), "newborn {k}");
    }
    assert!(state_of(&a, stayed.len())[2] < 3.5 - 0.005, "the newborn falls");

    // A birth of two that overlap, and then the death of one of them while they still do:
    // evaluated afresh.
    let pair = [3.0, 1.0, 1.0, 3.05, 1.0, 1.0];
    a.add_particles(&pair, &[0.0; 6], &[1e-3; 2], &[0.03; 2], &[false; 2])
        .unwrap();
    let before = evals(&a);
    a.advance(1).unwrap();
    assert_eq!(evals(&a) - before, 2, "newborns that touch: afresh");
    let last = a.particles().len() - 1;
    a.remove_particles(&[last]).unwrap();
    let before = evals(&a);
    a.advance(1).unwrap();
    assert_eq!(evals(&a) - before, 2, "a death that touched a survivor: afresh");

    // A spring between particles: any change evaluates afresh.
    let mut s = verlet_world(&x, &v, &m, &r, true);
    s.advance(5).unwrap();
    s.remove_particles(&[n - 1]).unwrap();
    let before = evals(&s);
    s.advance(1).unwrap();
    assert_eq!(evals(&s) - before, 2, "with a spring: afresh");
}

#[test]
fn in_a_world_sorted_along_space_a_death_keeps_verlets_acceleration_too() {
    // 5,000 particles with spring–dashpot contacts and Verlet: the world sorts them along a
    // Morton curve inside a run and restores the user's order before a removal, the kept
    // acceleration with them. A death among loners flying apart from the heap costs no
    // evaluation, and the others move as in the world without it, bit for bit; with the
    // acceleration evaluated afresh after the death (the cache dropped, as before), the
    // positions 40 steps on differ by up to 7.9e-15 m (measured), so the comparison is exact.
    let (x, v, m, r) = heap_and_loners(5000);
    let n = m.len();
    let (mut a, mut same) = twins(&x, &v, &m, &r);
    assert!(a.sorts() > 0, "the world sorted its particles along space");
    let gone: Vec<usize> = (n - 20..n).step_by(2).collect();
    a.remove_particles(&gone).unwrap();
    let before = a.stats().nfev;
    a.advance(1).unwrap();
    assert_eq!(a.stats().nfev - before, 1, "the kept acceleration: one evaluation per step");
    a.advance(40).unwrap();
    same.advance(41).unwrap();
    let stayed: Vec<usize> = (0..n).filter(|i| !gone.contains(i)).collect();
    let mut worst = 0.0_f64;
    for (now, &i) in stayed.iter().enumerate() {
        let (p, q) = (state_of(&a, now), state_of(&same, i));
        for k in 0..6 {
            worst = worst.max((p[k] - q[k]).abs());
        }
    }
    assert_eq!(worst, 0.0, "the survivors' states differ by up to {worst:e}");
}

#[test]
fn in_2d_a_birth_or_death_that_touches_nothing_keeps_verlets_acceleration() {
    // The same in the xy-plane (a_z = 0 for the newborns too): discs on a floor line under
    // gravity and drag, 20 loners above them; a death of loners and a birth in free space
    // cost no evaluation, and every particle moves as without the change, bit for bit.
    let disc_world = |x: &[f64], v: &[f64], m: &[f64], r: &[f64]| {
        let floor = kinema::collide::Plane::new([0.0; 3], [0.0, 1.0, 0.0], Surface::default()).unwrap();
        contact_world(2, floor.into(), [0.0, -9.81, 0.0], x, v, m, r, &vec![false; m.len()])
    };
    let (mut x, mut v, mut m, mut r) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for k in 0..60 {
        // a row of discs resting just into the floor (touching it), and loners up high
        let loner = k >= 40;
        let (px, py) = if loner {
            (0.3 * (k - 40) as f64, 2.0)
        } else {
            (0.05 * k as f64, 0.0099)
        };
        x.extend([px, py, 0.0]);
        v.extend([if loner { 0.1 } else { 0.0 }, 0.0, 0.0]);
        m.push(1e-3);
        r.push(0.01);
    }
    let n = m.len();
    let (mut a, mut same) = (disc_world(&x, &v, &m, &r), disc_world(&x, &v, &m, &r));
    a.advance(30).unwrap();
    same.advance(30).unwrap();
    let gone: Vec<usize> = (n - 20..n).step_by(2).collect();
    a.remove_particles(&gone).unwrap();
    let before = a.stats().nfev;
    a.advance(1).unwrap();
    assert_eq!(a.stats().nfev - before, 1, "a death: one evaluation");
    let born = [0.5, 3.0, 0.0, 1.5, 3.0, 0.0];
    let (vb, mb, rb) = ([0.2, 0.3, 0.0, 0.0, 0.0, 0.0], [2e-3, 1e-3], [0.02, 0.01]);
    a.add_particles(&born, &vb, &mb, &rb, &[false; 2]).unwrap();
    let mut alone = disc_world(&born, &vb, &mb, &rb);
    let before = a.stats().nfev;
    a.advance(1).unwrap();
    assert_eq!(a.stats().nfev - before, 1, "a birth: one evaluation");
    a.advance(40).unwrap();
    same.advance(42).unwrap();
    alone.advance(41).unwrap();
    let stayed: Vec<usize> = (0..n).filter(|i| !gone.contains(i)).collect();
    for (now, &i) in stayed.iter().enumerate() {
        assert_eq!(state_of(&a, now), state_of(&same, i), "particle {i}");
    }
    for k in 0..2 {
        let s = state_of(&a, stayed.len() + k);
        assert_eq!(s, state_of(&alone, k), "newborn {k}");
        assert!(s[2] == 0.0 && s[5] == 0.0, "in the plane");
    }
    assert!(state_of(&a, 0)[1] != 0.0099, "the row moved against the floor");
}
