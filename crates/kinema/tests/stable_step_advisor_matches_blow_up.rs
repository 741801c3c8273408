//! The stable-step advisor's limit matches the step at which methods are observed to blow up.

use kinema::forces::Springs;
use kinema::ode::{Integrator, Method};
use kinema::{World, WorldParams};

const N: usize = 20; // free masses
const K: f64 = 400.0; // N/m
const M: f64 = 0.5; // kg
const ZETA: f64 = 0.1; // damping ratio of the highest mode
const REST: f64 = 0.1; // m

/// ω of the highest mode of a chain of N equal masses between two fixed walls:
/// ω² = 4 (k/m) sin²(Nπ / (2(N + 1))) (the discrete string).
fn omega_top() -> f64 {
    let s = (N as f64 * std::f64::consts::PI / (2.0 * (N as f64 + 1.0))).sin();
    (4.0 * K / M * s * s).sqrt()
}

/// The chain, N masses plus two pinned ends, springs at rest with dashpots in proportion to
/// the stiffness (c = 2ζk/ω_top, so the highest mode has damping ratio ζ = 0.1: with C = (c/k) K
/// every mode has 2ζ_i ω_i = (c/k) ω_i²). The masses start displaced along the chain by a
/// pseudo-random 1e-4 m, which excites every mode.
fn chain(method: Method, dt: f64) -> World {
    let mut w = World::new(WorldParams {
        dt,
        method: Integrator::Named(method),
        dim: 3,
    })
    .unwrap();
    let count = N + 2;
    let mut x = Vec::new();
    for p in 0..count {
        let wobble = if p == 0 || p == count - 1 {
            0.0
        } else {
            1e-4 * ((p as f64 * 12.9898).sin() * 43758.5453).fract()
        };
        x.extend([p as f64 * REST + wobble, 0.0, 0.0]);
    }
    let pinned: Vec<bool> = (0..count).map(|p| p == 0 || p == count - 1).collect();
    w.add_particles(&x, &vec![0.0; 3 * count], &vec![M; count], &vec![0.0; count], &pinned)
        .unwrap();
    let c = 2.0 * ZETA * K / omega_top();
    let i: Vec<usize> = (0..count - 1).collect();
    let j: Vec<usize> = (1..count).collect();
    w.add_force(Box::new(Springs::uniform(i, j, K, REST, c).unwrap())).unwrap();
    w
}

/// Whether the chain blows up within 20,000 steps of `dt`: its largest displacement grows
/// a hundredfold, or the world refuses a step as divergent.
fn blows_up(method: Method, dt: f64) -> bool {
    let mut w = chain(method, dt);
    let rest: Vec<f64> = (0..N + 2).map(|p| p as f64 * REST).collect();
    let amplitude = |w: &World| {
        w.particles()
            .x
            .chunks_exact(3)
            .zip(&rest)
            .map(|(xi, r)| (xi[0] - r).abs())
            .fold(0.0_f64, f64::max)
    };
    let start = amplitude(&w);
    for _ in 0..20_000 {
        if w.step().is_err() || amplitude(&w) > 100.0 * start {
            return true;
        }
    }
    false
}

#[test]
fn the_advisor_finds_the_highest_mode() {
    // Theory: ω_top from the discrete string, ζ = 0.1 by construction; the closed-form bound
    // (Gershgorin, 4k/m) lies above.
    let mut w = chain(Method::Verlet, 1e-3);
    let rates = w.rates().unwrap();
    assert!(
        (rates.omega / omega_top() - 1.0).abs() < 1e-3,
        "{} vs {}",
        rates.omega,
        omega_top()
    );
    assert!((rates.zeta - ZETA).abs() < 1e-3, "ζ = {}", rates.zeta);
    let bound = rates.bound.unwrap();
    assert!(bound.omega_squared >= rates.omega * rates.omega);
    assert!(bound.omega_squared <= 4.0 * K / M * (1.0 + 1e-12));
}

#[test]
fn the_advisor_limit_matches_the_observed_blow_up_within_10_percent() {
    for method in [Method::Euler, Method::Rk4, Method::Verlet] {
        let advised = chain(method, 1e-3).stable_step(&Integrator::Named(method)).unwrap();
        // Bisect the observed threshold between half and twice the advice.
        let (mut stable, mut unstable) = (0.5 * advised, 2.0 * advised);
        assert!(!blows_up(method, stable), "{method}: blows up at half the advised step");
        assert!(blows_up(method, unstable), "{method}: stable at twice the advised step");
        for _ in 0..12 {
            let mid = 0.5 * (stable + unstable);
            if blows_up(method, mid) {
                unstable = mid;
            } else {
                stable = mid;
            }
        }
        let observed = 0.5 * (stable + unstable);
        eprintln!(
            "{method}: advised {advised:.6e} s, observed {observed:.6e} s, ratio {:.4}",
            observed / advised
        );
        assert!(
            (observed / advised - 1.0).abs() < 0.1,
            "{method}: advised {advised}, observed {observed}"
        );
    }
}
