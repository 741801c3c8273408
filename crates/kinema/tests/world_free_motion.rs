//! A World moves particles by Newton's second law through any integrator: closed forms for
//! free fall and projectiles, pinned particles, 2D worlds, the energy behaviour of each method
//! on an oscillator, momentum conservation under internal forces, and divergence reported
//! without losing the state.

use kinema::collide::{BoxContainer, Plane, SphereObstacle, Surface};
use kinema::error::CallbackError;
use kinema::forces::{Force, Properties, State};
use kinema::ode::{ButcherTableau, Integrator, Method};
use kinema::{Error, World, WorldParams};

/// Uniform gravity F = m g (a local copy, so that these tests do not depend on the catalogue).
struct UniformField([f64; 3]);

impl Force for UniformField {
    fn name(&self) -> &str {
        "field"
    }
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        for i in 0..s.len() {
            for k in 0..3 {
                f[3 * i + k] += s.mass[i] * self.0[k];
            }
        }
        Ok(())
    }
    fn potential_energy(&self, s: &State) -> Option<f64> {
        Some(
            -(0..s.len())
                .map(|i| s.mass[i] * (0..3).map(|k| self.0[k] * s.x[3 * i + k]).sum::<f64>())
                .sum::<f64>(),
        )
    }
}

/// A spring to the origin, F = −k x, U = ½ k |x|².
struct Anchor(f64);

impl Force for Anchor {
    fn name(&self) -> &str {
        "anchor"
    }
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        for (fi, xi) in f.iter_mut().zip(s.x) {
            *fi -= self.0 * xi;
        }
        Ok(())
    }
    fn potential_energy(&self, s: &State) -> Option<f64> {
        Some(0.5 * self.0 * s.x.iter().map(|x| x * x).sum::<f64>())
    }
}

/// Springs between consecutive particles, F_i = k (x_{i+1} − x_i) = −F_{i+1}, with
/// rest length 0: internal, equal and opposite.
struct Chain(f64);

impl Force for Chain {
    fn name(&self) -> &str {
        "chain"
    }
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        for i in 0..s.len().saturating_sub(1) {
            for k in 0..3 {
                let fk = self.0 * (s.x[3 * (i + 1) + k] - s.x[3 * i + k]);
                f[3 * i + k] += fk;
                f[3 * (i + 1) + k] -= fk;
            }
        }
        Ok(())
    }
    fn properties(&self) -> Properties {
        Properties {
            internal: true,
            ..Properties::UNKNOWN
        }
    }
}

fn world(method: Method, dt: f64) -> World {
    World::new(WorldParams {
        dt,
        method: Integrator::Named(method),
        dim: 3,
    })
    .unwrap()
}

#[test]
fn a_projectile_follows_the_parabola_exactly_with_rk4_and_verlet() {
    // x(t) = x0 + v0 t + ½ g t²: quadratic in t, integrated exactly by methods of order ≥ 2
    // whose position update is the Taylor polynomial (Verlet) or that are exact for
    // polynomials of degree ≤ 4 (RK4); Euler is off by O(dt).
    let g = [0.0, 0.0, -9.81];
    let (x0, v0) = ([1.0, 2.0, 3.0], [4.0, -1.0, 12.0]);
    for (method, tol) in [
        (Method::Rk4, 1e-12),
        (Method::Verlet, 1e-12),
        (Method::Midpoint, 1e-12),
        (Method::Euler, 0.1),
    ] {
        let mut w = world(method, 0.01);
        w.add_particles(&x0, &v0, &[2.0], &[0.0], &[false]).unwrap();
        w.add_force(Box::new(UniformField(g))).unwrap();
        for _ in 0..200 {
            w.step().unwrap();
        }
        let t = w.time();
        assert!((t - 2.0).abs() < 1e-15);
        for k in 0..3 {
            let exact = x0[k] + v0[k] * t + 0.5 * g[k] * t * t;
            assert!(
                (w.particles().x[k] - exact).abs() <= tol * (1.0 + exact.abs()),
                "{method}: {k}"
            );
            let exact_v = v0[k] + g[k] * t;
            assert!(
                (w.particles().v[k] - exact_v).abs() <= tol * (1.0 + exact_v.abs()),
                "{method}: v{k}"
            );
        }
    }
}

#[test]
fn verlet_in_a_world_evaluates_the_forces_once_per_step() {
    // The world keeps its stepper, so Verlet's last acceleration is reused (first same as last).
    let mut w = world(Method::Verlet, 0.01);
    w.add_particles(&[1.0, 0.0, 0.0], &[0.0; 3], &[1.0], &[0.0], &[false])
        .unwrap();
    w.add_force(Box::new(Anchor(4.0))).unwrap();
    for _ in 0..100 {
        w.step().unwrap();
    }
    assert_eq!(w.stats().nfev, 101);
}

#[test]
fn pinned_particles_stay_put_and_2d_worlds_stay_in_the_plane() {
    let mut w = World::new(WorldParams {
        dt: 0.01,
        method: Integrator::Named(Method::Rk4),
        dim: 2,
    })
    .unwrap();
    w.add_particles(
        &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
        &[0.0, 1.0, 0.0, 0.0, 0.0, 0.0],
        &[1.0, 1.0],
        &[0.0, 0.0],
        &[false, true],
    )
    .unwrap();
    w.add_force(Box::new(UniformField([0.3, -9.81, 5.0]))).unwrap(); // a z component, ignored in 2D
    for _ in 0..100 {
        w.step().unwrap();
    }
    let p = w.particles();
    assert_eq!(&p.x[3..6], &[1.0, 0.0, 0.0]);
    assert_eq!(p.x[2], 0.0);
    assert_eq!(p.v[2], 0.0);
    let e = World::new(WorldParams {
        dim: 2,
        ..WorldParams::default()
    })
    .unwrap()
    .add_particles(&[0.0, 0.0, 1.0], &[0.0; 3], &[1.0], &[0.0], &[false]);
    assert!(e
        .unwrap_err()
        .to_string()
        .contains("position[0][2] = 1 is invalid: a 2D world keeps z = 0"));
}

/// A 2D world's colliders stay in the plane: the engine refuses a plane whose normal leaves
/// the xy-plane, an obstacle off it and a box closed along z, whoever adds them (the Python
/// binding checks the same rule, from the same engine function, on the values as given).
#[test]
fn a_2d_world_refuses_colliders_out_of_its_plane() {
    let flat = || {
        World::new(WorldParams {
            dim: 2,
            ..WorldParams::default()
        })
        .unwrap()
    };
    let s = Surface::default();
    let plane = Plane::new([0.0; 3], [0.0, 0.0, 1.0], s).unwrap();
    let e = flat().add_collider(plane).unwrap_err().to_string();
    assert!(e.contains("normal[2] = 1 is invalid: a 2D world keeps z = 0"), "{e}");
    let ball = SphereObstacle::new([0.0, 0.0, 0.5], 1.0, s).unwrap();
    let e = flat().add_collider(ball).unwrap_err().to_string();
    assert!(e.contains("center[2] = 0.5 is invalid: a 2D world keeps z = 0"), "{e}");
    let cube = BoxContainer::new([0.0; 3], [1.0; 3], s).unwrap();
    let e = flat().add_collider(cube.clone()).unwrap_err().to_string();
    assert!(e.contains("lo[2] = 0 is invalid: a 2D world keeps z = 0"), "{e}");
    // What does fit: an in-plane normal, a centre on z = 0, a rectangle; and any of them in 3D.
    let mut w = flat();
    w.add_collider(Plane::new([0.0; 3], [0.0, 1.0, 0.0], s).unwrap()).unwrap();
    w.add_collider(SphereObstacle::new([0.0, 2.0, 0.0], 1.0, s).unwrap()).unwrap();
    w.add_collider(BoxContainer::rect([-5.0, -5.0], [5.0, 5.0], s).unwrap())
        .unwrap();
    assert_eq!(w.colliders().len(), 3);
    world(Method::Verlet, 0.01).add_collider(cube).unwrap();
}

/// Relative energy error (E − E₀)/E₀ of a unit oscillator (k = m = 1, period 2π, 100 steps
/// per period): for each period, its value at the end of the period and its largest magnitude
/// over the period's steps.
fn energy_per_period(method: Method, periods: usize) -> Vec<(f64, f64)> {
    let steps_per_period = 100;
    let dt = 2.0 * std::f64::consts::PI / steps_per_period as f64;
    let mut w = world(method, dt);
    w.add_particles(&[1.0, 0.0, 0.0], &[0.0; 3], &[1.0], &[0.0], &[false])
        .unwrap();
    w.add_force(Box::new(Anchor(1.0))).unwrap();
    let e0 = w.diagnostics().total_energy();
    (0..periods)
        .map(|_| {
            let mut worst = 0.0_f64;
            for _ in 0..steps_per_period {
                w.step().unwrap();
                worst = worst.max((w.diagnostics().total_energy() / e0 - 1.0).abs());
            }
            (w.diagnostics().total_energy() / e0 - 1.0, worst)
        })
        .collect()
}

#[test]
fn over_1000_periods_each_method_treats_energy_as_its_theory_says() {
    // Forward Euler multiplies the energy by |1 + ih|² = 1 + h² per step: it grows. Backward
    // Euler by 1/(1 + h²): it decays. Symplectic Euler and Verlet conserve a modified energy,
    // so the true energy oscillates in a band of width O(h) and O(h²) without drifting: the
    // largest error over a period is the same in the last periods as in the first.
    let h: f64 = 2.0 * std::f64::consts::PI / 100.0;
    let euler: Vec<f64> = energy_per_period(Method::Euler, 1000).iter().map(|e| e.0).collect();
    assert!(euler.windows(2).all(|w| w[1] > w[0]));
    let growth = (1.0 + h * h).powi(100_000) - 1.0;
    assert!((euler[999] / growth - 1.0).abs() < 1e-6, "{} vs {growth}", euler[999]);
    let implicit: Vec<f64> = energy_per_period(Method::ImplicitEuler, 1000).iter().map(|e| e.0).collect();
    assert!(implicit.windows(2).all(|w| w[1] <= w[0]));
    for (p, e) in implicit.iter().enumerate().take(20) {
        let decay = (1.0 + h * h).powi(-100 * (p as i32 + 1)) - 1.0;
        assert!((e - decay).abs() < 1e-6, "period {p}: {e} vs {decay}");
    }
    for (method, band) in [(Method::SymplecticEuler, h), (Method::Verlet, h * h)] {
        let worst: Vec<f64> = energy_per_period(method, 1000).iter().map(|e| e.1).collect();
        let overall = worst.iter().fold(0.0_f64, |m, &v| m.max(v));
        assert!(overall < band, "{method}: {overall} vs band {band}");
        let first = worst[..10].iter().fold(0.0_f64, |m, &v| m.max(v));
        let last = worst[990..].iter().fold(0.0_f64, |m, &v| m.max(v));
        assert!((last - first).abs() <= 0.1 * first, "{method} drifts: {first} → {last}");
    }
}

#[test]
fn internal_forces_conserve_momentum() {
    // Equal and opposite pair forces change no total momentum (Newton's third law); every
    // method conserves it exactly up to rounding, as each stage adds forces that sum to zero.
    for method in [Method::Verlet, Method::Rk4, Method::SymplecticEuler] {
        let mut w = world(method, 1e-3);
        let x: Vec<f64> = (0..30).map(|c| (c as f64 * 0.37).sin()).collect();
        let v: Vec<f64> = (0..30).map(|c| (c as f64 * 1.3).cos()).collect();
        let m: Vec<f64> = (0..10).map(|i| 1.0 + 0.1 * i as f64).collect();
        w.add_particles(&x, &v, &m, &[0.0; 10], &[false; 10]).unwrap();
        w.add_force(Box::new(Chain(50.0))).unwrap();
        let p0 = w.diagnostics().momentum;
        let scale: f64 = (0..10)
            .map(|i| m[i] * (v[3 * i].powi(2) + v[3 * i + 1].powi(2) + v[3 * i + 2].powi(2)).sqrt())
            .sum();
        for _ in 0..10_000 {
            w.step().unwrap();
        }
        let p = w.diagnostics().momentum;
        for k in 0..3 {
            assert!((p[k] - p0[k]).abs() <= 1e-12 * scale, "{method}: {:?} vs {:?}", p, p0);
        }
    }
}

#[test]
fn a_diverging_step_is_reported_and_the_state_before_it_is_kept() {
    // Forward Euler on a stiff anchor (ω = 1000/s) at dt = 0.01 s: |1 + i ω dt| = 10 per step,
    // so the state overflows after ~300 steps.
    let mut w = world(Method::Euler, 0.01);
    w.add_particles(&[1.0, 0.0, 0.0], &[0.0; 3], &[1.0], &[0.0], &[false])
        .unwrap();
    w.add_force(Box::new(Anchor(1e6))).unwrap();
    let mut before = w.particles().clone();
    let err = loop {
        match w.step() {
            Ok(()) => before = w.particles().clone(),
            Err(e) => break e,
        }
    };
    match &err {
        Error::Diverged { step, particle, .. } => {
            assert_eq!(*step, w.steps() + 1);
            assert_eq!(*particle, Some(0));
        }
        other => panic!("{other}"),
    }
    assert_eq!(w.particles(), &before);
    assert!(w.particles().x.iter().all(|x| x.is_finite()));
    assert!(err.to_string().contains("diverged at step"));
}

#[test]
fn every_integrator_runs_a_world() {
    // rk45 substeps adaptively inside each world step; a user tableau runs like rk4.
    let ralston = ButcherTableau::new(
        "ralston",
        vec![vec![0.0, 0.0], vec![2.0 / 3.0, 0.0]],
        vec![0.25, 0.75],
        vec![0.0, 2.0 / 3.0],
        2,
    )
    .unwrap();
    let mut methods: Vec<Integrator> = Method::ALL.iter().map(|m| Integrator::Named(*m)).collect();
    methods.push(Integrator::Tableau(ralston));
    for method in methods {
        let mut w = World::new(WorldParams {
            dt: 0.01,
            method: method.clone(),
            dim: 3,
        })
        .unwrap();
        w.add_particles(&[1.0, 0.0, 0.0], &[0.0; 3], &[1.0], &[0.0], &[false])
            .unwrap();
        w.add_force(Box::new(Anchor(1.0))).unwrap();
        for _ in 0..100 {
            w.step().unwrap();
        }
        // x = cos t at t = 1; the least accurate (first-order) methods are within O(dt)
        assert!(
            (w.particles().x[0] - 1f64.cos()).abs() < 0.01,
            "{}: {}",
            method.name(),
            w.particles().x[0]
        );
    }
}
