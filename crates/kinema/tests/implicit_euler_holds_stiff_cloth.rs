//! A hanging cloth of stiff springs at a large step: implicit Euler (Baraff & Witkin's
//! linearised step) stays bounded and settles where explicit Euler and RK4 blow up.

use kinema::forces::{Gravity, Springs};
use kinema::ode::{Integrator, Method};
use kinema::world::LinearSolve;
use kinema::{Error, World, WorldParams};

const SIDE: usize = 30;
const WIDTH: f64 = 1.0; // m
const K: f64 = 1e4; // N/m
const MASS: f64 = 0.01; // kg
const H: f64 = 1.0 / 60.0; // s

/// A 30×30 cloth, 1 m square, lying flat in the xy-plane under gravity −z, with structural
/// (neighbours), shear (diagonals) and bend (two apart) springs at rest, all k = 1e4 N/m, and
/// the two corners of its y = 0 edge pinned.
fn cloth(method: Method) -> World {
    let mut w = World::new(WorldParams {
        dt: H,
        method: Integrator::Named(method),
        dim: 3,
    })
    .unwrap();
    let spacing = WIDTH / (SIDE - 1) as f64;
    let idx = |i: usize, j: usize| j * SIDE + i;
    let mut x = Vec::new();
    let mut pinned = Vec::new();
    for j in 0..SIDE {
        for i in 0..SIDE {
            x.extend([i as f64 * spacing, j as f64 * spacing, 0.0]);
            pinned.push(j == 0 && (i == 0 || i == SIDE - 1));
        }
    }
    let n = SIDE * SIDE;
    w.add_particles(&x, &vec![0.0; 3 * n], &vec![MASS; n], &vec![0.0; n], &pinned)
        .unwrap();
    let (mut a, mut b) = (Vec::new(), Vec::new());
    let mut join = |p: usize, q: usize| {
        a.push(p);
        b.push(q);
    };
    for j in 0..SIDE {
        for i in 0..SIDE {
            if i + 1 < SIDE {
                join(idx(i, j), idx(i + 1, j)); // structural
            }
            if j + 1 < SIDE {
                join(idx(i, j), idx(i, j + 1));
            }
            if i + 1 < SIDE && j + 1 < SIDE {
                join(idx(i, j), idx(i + 1, j + 1)); // shear
                join(idx(i + 1, j), idx(i, j + 1));
            }
            if i + 2 < SIDE {
                join(idx(i, j), idx(i + 2, j)); // bend
            }
            if j + 2 < SIDE {
                join(idx(i, j), idx(i, j + 2));
            }
        }
    }
    w.add_force(Box::new(Springs::with_rest_from_positions(a, b, K, 0.0, &x).unwrap()))
        .unwrap();
    w.add_force(Box::new(Gravity::new([0.0, 0.0, -9.81]).unwrap())).unwrap();
    w
}

fn kinetic(w: &World) -> f64 {
    w.diagnostics().kinetic
}

#[test]
fn implicit_euler_keeps_the_cloth_bounded_and_it_settles() {
    let mut w = cloth(Method::ImplicitEuler);
    let pins = [[0.0, 0.0, 0.0], [WIDTH, 0.0, 0.0]];
    let mut peak = 0.0_f64;
    let mut per_second = Vec::new();
    let mut iterations = 0;
    for step in 1..=1200 {
        w.step().unwrap();
        let LinearSolve {
            iterations: its,
            converged,
        } = w.linear_solve().unwrap();
        iterations += its;
        assert!(converged, "step {step}: CG did not converge in {its} iterations");
        peak = peak.max(kinetic(&w));
        if step % 60 == 0 {
            per_second.push(kinetic(&w));
        }
    }
    eprintln!(
        "kinetic energy per second: {}; peak {peak:.3e} J; mean CG iterations {}",
        per_second.iter().map(|e| format!("{e:.2e}")).collect::<Vec<_>>().join(" "),
        iterations / 1200
    );
    let p = w.particles();
    // Bounded: every particle within the cloth's diagonal of a pin, stretched by at most 5%
    // (the springs are stiff: the whole weight, 8.8 N, strains them by ~1e-3).
    for (i, xi) in p.x.chunks_exact(3).enumerate() {
        let nearest = pins
            .iter()
            .map(|q| ((xi[0] - q[0]).powi(2) + (xi[1] - q[1]).powi(2) + (xi[2] - q[2]).powi(2)).sqrt())
            .fold(f64::INFINITY, f64::min);
        assert!(nearest <= 1.05 * WIDTH * 2f64.sqrt(), "particle {i} at {xi:?}");
    }
    assert_eq!(&p.x[0..3], &pins[0], "pinned corners stay put");
    // It fell (the centre of mass dropped) and settles: kinetic energy in the last second is
    // below 1% of its peak, and falls from second to second over the last 5 s.
    assert!(peak > 0.1, "the cloth swung down: peak kinetic energy {peak} J");
    let last = per_second[per_second.len() - 1];
    assert!(last < 1e-2 * peak, "{last} J vs peak {peak} J");
}

#[test]
fn explicit_euler_and_rk4_blow_up_on_the_same_cloth() {
    for method in [Method::Euler, Method::Rk4] {
        let mut w = cloth(method);
        let advised = w.stable_step(&Integrator::Named(method)).unwrap();
        assert!(advised < H / 10.0, "{method}: advisor says {advised} s");
        let err = (0..600).find_map(|_| w.step().err());
        match err {
            Some(Error::Diverged { step, advised_dt, .. }) => {
                eprintln!("{method}: diverged at step {step}; advised dt {advised_dt:?}");
                assert!(step < 600);
                assert!(advised_dt.is_some_and(|h| h < H));
            }
            other => panic!("{method}: expected a divergence, got {other:?}"),
        }
        assert!(w.particles().x.iter().chain(&w.particles().v).all(|c| c.is_finite()));
    }
}
