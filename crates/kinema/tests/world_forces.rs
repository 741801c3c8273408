//! Worlds under the force catalogue, against theory: momentum of a free spring network is
//! conserved (Newton's third law), and the Kepler problem shows the symplectic/non-symplectic
//! split (Verlet's energy error bounded, RK4's drifting at fourth order).

use kinema::forces::{Attractor, Springs};
use kinema::ode::{Integrator, Method};
use kinema::{World, WorldParams};

#[test]
fn a_free_spring_network_conserves_momentum_over_10000_steps() {
    // 4 × 4 × 2 lattice, springs to the neighbours (structural and diagonals), masses and
    // velocities varied; no external force, so Σ m v is constant: to 1e-12 of Σ m |v|.
    let (nx, ny, nz) = (4, 4, 2);
    let idx = |a: usize, b: usize, c: usize| (c * ny + b) * nx + a;
    let mut x = Vec::new();
    for c in 0..nz {
        for b in 0..ny {
            for a in 0..nx {
                x.extend_from_slice(&[a as f64 * 0.1, b as f64 * 0.1, c as f64 * 0.1]);
            }
        }
    }
    let n = nx * ny * nz;
    let v: Vec<f64> = (0..3 * n).map(|k| ((k as f64) * 0.731).sin()).collect();
    let m: Vec<f64> = (0..n).map(|p| 0.01 * (1.0 + (p % 3) as f64)).collect();
    let (mut si, mut sj) = (Vec::new(), Vec::new());
    for c in 0..nz {
        for b in 0..ny {
            for a in 0..nx {
                for (da, db, dc) in [(1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 1, 0)] {
                    let (a2, b2, c2) = (a + da, b + db, c + dc);
                    if a2 < nx && b2 < ny && c2 < nz {
                        si.push(idx(a, b, c));
                        sj.push(idx(a2, b2, c2));
                    }
                }
            }
        }
    }
    for method in [Method::Verlet, Method::Rk4, Method::SymplecticEuler] {
        let mut w = World::new(WorldParams {
            dt: 1e-4,
            method: Integrator::Named(method),
            dim: 3,
        })
        .unwrap();
        w.add_particles(&x, &v, &m, &vec![0.0; n], &vec![false; n]).unwrap();
        w.add_force(Box::new(
            Springs::with_rest_from_positions(si.clone(), sj.clone(), 100.0, 0.05, &x).unwrap(),
        ))
        .unwrap();
        let p0 = w.diagnostics().momentum;
        let scale: f64 = (0..n)
            .map(|p| m[p] * (v[3 * p].powi(2) + v[3 * p + 1].powi(2) + v[3 * p + 2].powi(2)).sqrt())
            .sum();
        for _ in 0..10_000 {
            w.step().unwrap();
        }
        let p = w.diagnostics().momentum;
        for k in 0..3 {
            assert!((p[k] - p0[k]).abs() <= 1e-12 * scale, "{method}: {p:?} vs {p0:?}");
        }
    }
}

/// Relative energy error |E(t)/E₀ − 1| after every step of a Kepler orbit with eccentricity
/// 0.5 (GM = 1, semi-major axis 1, period 2π), started at perihelion.
fn kepler_energy_errors(method: Method, steps_per_period: usize, periods: usize) -> Vec<f64> {
    let e: f64 = 0.5;
    let (r0, v0) = (1.0 - e, ((1.0 + e) / (1.0 - e)).sqrt()); // vis-viva at perihelion
    let dt = 2.0 * std::f64::consts::PI / steps_per_period as f64;
    let mut w = World::new(WorldParams {
        dt,
        method: Integrator::Named(method),
        dim: 2,
    })
    .unwrap();
    w.add_particles(&[r0, 0.0, 0.0], &[0.0, v0, 0.0], &[1.0], &[0.0], &[false])
        .unwrap();
    w.add_force(Box::new(Attractor::new([0.0; 3], 1.0, 0.0).unwrap())).unwrap();
    let e0 = w.diagnostics().total_energy();
    assert!((e0 + 0.5).abs() < 1e-12); // E = −GM m / (2a)
    (0..steps_per_period * periods)
        .map(|_| {
            w.step().unwrap();
            (w.diagnostics().total_energy() / e0 - 1.0).abs()
        })
        .collect()
}

#[test]
fn kepler_verlet_energy_error_is_bounded_and_rk4_drifts_at_fourth_order() {
    let spp = 200;
    let verlet = kepler_energy_errors(Method::Verlet, spp, 100);
    let worst = verlet.iter().fold(0.0_f64, |m, &v| m.max(v));
    assert!(worst < 3e-3, "{worst}");
    let first = verlet[..10 * spp].iter().fold(0.0_f64, |m, &v| m.max(v));
    let last = verlet[90 * spp..].iter().fold(0.0_f64, |m, &v| m.max(v));
    assert!((last - first).abs() <= 0.1 * first, "Verlet: {first} → {last}");

    // RK4 is not symplectic: its energy error accumulates period after period.
    let rk4 = kepler_energy_errors(Method::Rk4, spp, 100);
    let per_period: Vec<f64> = (1..=100).map(|p| rk4[p * spp - 1]).collect();
    assert!(per_period.windows(2).all(|w| w[1] > w[0]), "RK4's drift is not monotone");
    assert!(per_period[99] < 1e-4, "{}", per_period[99]);
    let halved = kepler_energy_errors(Method::Rk4, 2 * spp, 100);
    let ratio = per_period[99] / halved[100 * 2 * spp - 1];
    assert!(ratio >= 16.0, "halving the step reduced RK4's drift only {ratio}×");
    eprintln!(
        "Verlet max |ΔE/E| {worst:.2e}; RK4 after 100 periods {:.2e}, ratio at half step {ratio:.1}",
        per_period[99]
    );
}
