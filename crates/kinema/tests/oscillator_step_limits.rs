//! The stable step on the damped oscillator x'' = −ω²x − 2ζω v is where the one-step map's
//! spectral radius reaches 1: proven by behaviour, 2% below the computed limit the motion
//! stays bounded for 10,000 steps and 2% above it grows without bound, for explicit, implicit
//! and symplectic methods alike.

use kinema::ode::{oscillator_max_step, solve_second_order, FnSecondOrder, Integrator, Method, SolveOptions, Termination};

const OMEGA: f64 = 10.0;

/// max |x| over the first and the last 1,000 of `steps` steps (inf if the solve overflowed).
fn amplitudes(method: Method, zeta: f64, h: f64, steps: usize) -> (f64, f64) {
    let gamma = 2.0 * zeta * OMEGA;
    let mut sys = FnSecondOrder::new(1, move |_t, x: &[f64], v: &[f64], a: &mut [f64]| {
        a[0] = -OMEGA * OMEGA * x[0] - gamma * v[0];
        Ok(())
    });
    let opts = SolveOptions {
        t_span: (0.0, steps as f64 * h),
        h: Some(h),
        ..SolveOptions::default()
    };
    let sol = solve_second_order(&mut sys, &[1.0], &[0.0], &Integrator::Named(method), &opts).unwrap();
    if matches!(sol.termination, Some(Termination::NonFinite { .. })) {
        return (1.0, f64::INFINITY);
    }
    let xs: Vec<f64> = (0..sol.t.len()).map(|i| sol.state(i)[0].abs()).collect();
    let first = xs[..1000].iter().fold(0.0_f64, |m, &v| m.max(v));
    let last = xs[xs.len() - 1000..].iter().fold(0.0_f64, |m, &v| m.max(v));
    (first, last)
}

#[test]
fn two_percent_below_the_limit_is_bounded_and_two_percent_above_grows() {
    for method in [
        Method::Verlet,
        Method::SymplecticEuler,
        Method::Euler,
        Method::Rk4,
        Method::Midpoint,
    ] {
        for zeta in [0.1, 0.5, 2.0] {
            let h = oscillator_max_step(&Integrator::Named(method), OMEGA, zeta);
            assert!(h > 0.0 && h.is_finite(), "{method} ζ = {zeta}: {h}");
            let (first, last) = amplitudes(method, zeta, 0.98 * h, 10_000);
            assert!(
                last <= first,
                "{method} ζ = {zeta}, h = 0.98 × {h}: grew from {first} to {last}"
            );
            // Above it ρ > 1 and the amplitude grows like ρ^N; 2% past the limit ρ is only a
            // little above 1 for the gentlest case (Euler, ζ = 0.1: ×40 in 10,000 steps).
            let (first, last) = amplitudes(method, zeta, 1.02 * h, 10_000);
            assert!(last > 10.0 * first, "{method} ζ = {zeta}, h = 1.02 × {h}: {first} → {last}");
            eprintln!("{method:>16} ζ = {zeta}: stable for h ω ≤ {:.5}", h * OMEGA);
        }
    }
}

#[test]
fn damping_lowers_the_verlet_limit_below_two_over_omega() {
    // For ζ = 0.1 (x'' = −100x − 2v) the limit lies between the steps observed to stay bounded
    // (h = 0.16) and to diverge (h = 0.17), below the undamped 2/ω = 0.2.
    let h = oscillator_max_step(&Integrator::Named(Method::Verlet), OMEGA, 0.1);
    assert!(h > 0.16 && h < 0.17, "{h}");
    let h_se = oscillator_max_step(&Integrator::Named(Method::SymplecticEuler), OMEGA, 0.1);
    assert!(h_se > 0.178 && h_se < 0.185, "{h_se}");
}

#[test]
fn implicit_euler_has_no_limit_and_bad_input_gives_nan() {
    assert!(oscillator_max_step(&Integrator::Named(Method::ImplicitEuler), OMEGA, 0.1).is_infinite());
    assert!(oscillator_max_step(&Integrator::Named(Method::Verlet), -1.0, 0.1).is_nan());
    assert!(oscillator_max_step(&Integrator::Named(Method::Verlet), 1.0, -0.1).is_nan());
}
