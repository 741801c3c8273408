//! The stability analysis is right, as formulas and as behaviour. Formulas: the stability
//! functions R(z) of the test equation p' = λp (euler 1 + z, midpoint/heun 1 + z + z²/2, rk4 the
//! Taylor polynomial of e^z to degree 4, implicit Euler 1/(1 - z)) and their closed-form limits:
//! real intervals [-2, 0] (euler, midpoint) and [-2.785293563405282, 0] (rk4), rk4's imaginary
//! interval |y| ≤ 2√2, none for euler/midpoint, the whole left half-plane for implicit Euler, and
//! hω ≤ 2 for verlet and symplectic Euler on x'' = -ω²x.
//! Behaviour: a solve 2% below `max_step` stays bounded for 10,000 steps, 2% above it diverges.

use kinema::ode::{
    amplification, imag_interval, max_step, real_interval, solve, solve_second_order, FnSecondOrder, FnSystem, Integrator,
    Method, SolveOptions, Termination,
};
use num_complex::Complex64;

fn named(m: Method) -> Integrator {
    Integrator::Named(m)
}

fn c(re: f64, im: f64) -> Complex64 {
    Complex64::new(re, im)
}

/// The negative real root of z + z²/2 + z³/6 + z⁴/24 = 0, i.e. R(z) = 1 (where |R| returns to 1
/// on the negative axis).
const RK4_REAL_LIMIT: f64 = -2.785293563405282;

#[test]
fn euler_and_midpoint_real_interval_is_minus_two_to_zero() {
    // |1 + z| ≤ 1 and |1 + z + z²/2| ≤ 1 on the real line: z ∈ [-2, 0].
    for m in [Method::Euler, Method::Midpoint, Method::Heun] {
        let (lo, hi) = real_interval(&named(m));
        eprintln!("{m}: real interval ({lo}, {hi})");
        assert!((lo + 2.0).abs() <= 1e-12 && hi.abs() <= 1e-12, "{m}: ({lo}, {hi})");
    }
}

#[test]
fn rk4_real_and_imaginary_limits() {
    let (lo, hi) = real_interval(&named(Method::Rk4));
    eprintln!("rk4: real interval ({lo:.16}, {hi}), theory ({RK4_REAL_LIMIT}, 0)");
    assert!((lo - RK4_REAL_LIMIT).abs() <= 1e-9 && hi.abs() <= 1e-12, "({lo}, {hi})");
    // The closed-form limit really is where |R| = 1: rk4's R is positive on the whole real line
    // (its minimum is ≈ 0.27), so the crossing is R(RK4_REAL_LIMIT) = +1 (to the rounding of
    // evaluating a quartic whose terms reach 3.9 in size).
    let r = amplification(&named(Method::Rk4), c(RK4_REAL_LIMIT, 0.0));
    assert!((r.re - 1.0).abs() < 1e-13 && r.im == 0.0, "{r}");

    // |R(iy)|² = 1 - y⁶/72 + y⁸/576, which is 1 again at y² = 8.
    let (lo, hi) = imag_interval(&named(Method::Rk4));
    let lim = 2.0 * 2f64.sqrt();
    eprintln!("rk4: imaginary interval ({lo:.16}, {hi:.16}), theory ±{lim:.16}");
    assert!((lo + lim).abs() <= 1e-9 && (hi - lim).abs() <= 1e-9, "({lo}, {hi})");
    assert!((max_step(&named(Method::Rk4), c(0.0, 1.0)) - lim).abs() <= 1e-9);
}

#[test]
fn euler_and_midpoint_have_no_imaginary_interval() {
    // |1 + iy|² = 1 + y² and |1 + iy - y²/2|² = 1 + y⁴/4: above 1 for every y ≠ 0.
    for m in [Method::Euler, Method::Midpoint, Method::Heun] {
        let (lo, hi) = imag_interval(&named(m));
        assert!(lo == 0.0 && hi == 0.0, "{m}: ({lo}, {hi})");
        assert_eq!(max_step(&named(m), c(0.0, 3.0)), 0.0, "{m}");
    }
}

#[test]
fn implicit_euler_is_stable_on_the_whole_left_half_plane() {
    // |1/(1 - z)| ≤ 1 iff |1 - z| ≥ 1, which holds for every Re z ≤ 0.
    let be = named(Method::ImplicitEuler);
    for lam in [
        c(-1.0, 0.0),
        c(0.0, 1.0),
        c(0.0, -1.0),
        c(-1.0, 5.0),
        c(-1e-3, 1e3),
        c(-1e6, -1.0),
        c(-3.0, -4.0),
    ] {
        let h = max_step(&be, lam);
        assert!(h.is_infinite() && h > 0.0, "implicit Euler max_step({lam}) = {h}");
    }
    assert_eq!(real_interval(&be), (f64::NEG_INFINITY, 0.0));
    // Growing modes (Re λ > 0): no positive step is "stable" starting from 0.
    assert_eq!(max_step(&be, c(1.0, 0.0)), 0.0);
}

#[test]
fn verlet_and_symplectic_euler_imaginary_interval_is_minus_two_to_two() {
    // On x'' = -ω²x one step is a 2×2 matrix with det 1 and trace 2 - (hω)²: bounded iff hω ≤ 2.
    for m in [Method::Verlet, Method::SymplecticEuler] {
        let (lo, hi) = imag_interval(&named(m));
        assert!((lo + 2.0).abs() <= 1e-12 && (hi - 2.0).abs() <= 1e-12, "{m}: ({lo}, {hi})");
        for w in [0.5, 1.0, 7.0] {
            let h = max_step(&named(m), c(0.0, w));
            assert!((h - 2.0 / w).abs() <= 1e-12 * (2.0 / w), "{m}: max_step(i{w}) = {h}");
        }
        // Damped or growing directions have no stable step for these methods.
        assert_eq!(max_step(&named(m), c(-1.0, 0.0)), 0.0, "{m}");
    }
}

#[test]
fn amplification_matches_the_hand_formulas() {
    let zs = [c(-0.5, 0.0), c(-1.0, 2.0), c(0.3, -0.7), c(-2.5, 0.1), c(0.0, 2.0)];
    for z in zs {
        let euler = 1.0 + z;
        let midpoint = 1.0 + z + z * z / 2.0;
        let rk4 = 1.0 + z + z * z / 2.0 + z.powi(3) / 6.0 + z.powi(4) / 24.0;
        let implicit = 1.0 / (1.0 - z);
        for (m, want) in [
            (Method::Euler, euler),
            (Method::Midpoint, midpoint),
            (Method::Heun, midpoint),
            (Method::Rk4, rk4),
            (Method::ImplicitEuler, implicit),
        ] {
            let got = amplification(&named(m), z);
            assert!(
                (got - want).norm() <= 1e-14 * (1.0 + want.norm()),
                "{m} R({z}) = {got}, expected {want}"
            );
        }
    }
}

/// Runs p' = λp as the real system [Re p, Im p] for `steps` fixed steps of size h from p0 = 1 + 0.5i.
/// Returns (max |p_n| / |p0| over the recorded states, termination).
fn run_test_equation(m: Method, lam: Complex64, h: f64, steps: usize) -> (f64, Option<Termination>) {
    let mut sys = FnSystem::new(2, move |_t, p: &[f64], dp: &mut [f64]| {
        dp[0] = lam.re * p[0] - lam.im * p[1];
        dp[1] = lam.im * p[0] + lam.re * p[1];
        Ok(())
    });
    let p0 = [1.0, 0.5];
    let opts = SolveOptions {
        t_span: (0.0, steps as f64 * h),
        h: Some(h),
        ..SolveOptions::default()
    };
    let sol = solve(&mut sys, &p0, &named(m), &opts).unwrap();
    let norm0 = f64::hypot(p0[0], p0[1]);
    let worst = (0..sol.t.len())
        .map(|i| f64::hypot(sol.state(i)[0], sol.state(i)[1]) / norm0)
        .fold(0.0, f64::max);
    if sol.termination.is_none() {
        assert_eq!(sol.t.len(), steps + 1, "{m}: expected {steps} steps");
    }
    (worst, sol.termination)
}

const STEPS: usize = 10_000;

#[test]
fn explicit_rk_solves_stay_bounded_just_below_max_step_and_diverge_just_above() {
    let left_half_plane = [c(-1.0, 0.0), c(-40.0, 0.0), c(-1.0, 2.0), c(-3.0, 1.0), c(-2.0, -5.0)];
    let mut cases: Vec<(Method, Complex64)> = Vec::new();
    for m in [Method::Euler, Method::Midpoint, Method::Heun, Method::Rk4] {
        cases.extend(left_half_plane.iter().map(|&l| (m, l)));
    }
    // rk4 alone has an imaginary-axis interval.
    cases.push((Method::Rk4, c(0.0, 1.0)));
    cases.push((Method::Rk4, c(0.0, -4.0)));

    for (m, lam) in cases {
        let h_max = max_step(&named(m), lam);
        assert!(h_max.is_finite() && h_max > 0.0, "{m} λ = {lam}: max_step = {h_max}");

        // 2% below: every step multiplies p by R(hλ) with |R| < 1, so |p_n| ≤ |p_0| for all n
        // (multiplication by a complex number is a normal map, no transient growth).
        let h = 0.98 * h_max;
        let r_below = amplification(&named(m), h * lam).norm();
        let (worst, term) = run_test_equation(m, lam, h, STEPS);
        eprintln!("{m:<8} λ = {lam:<8} max_step = {h_max:.6}: 0.98·h: |R| = {r_below:.6}, max |p|/|p0| = {worst:.3e}");
        assert!(term.is_none(), "{m} λ = {lam}, h = {h}: {term:?}");
        assert!(
            worst <= 1.0 + 1e-12,
            "{m} λ = {lam}, h = 0.98 max_step: |p| grew to {worst} |p0|"
        );

        // 2% above: |R| > 1 and the solution grows geometrically.
        let h = 1.02 * h_max;
        let r_above = amplification(&named(m), h * lam).norm();
        let (worst, term) = run_test_equation(m, lam, h, STEPS);
        eprintln!(
            "{:<8} {:<12} 1.02·h: |R| = {r_above:.6}, max |p|/|p0| = {worst:.3e}, termination {term:?}",
            "", ""
        );
        let diverged = worst > 1e3 || matches!(term, Some(Termination::NonFinite { .. }));
        assert!(
            diverged,
            "{m} λ = {lam}, h = 1.02 max_step: max |p| = {worst} |p0|, termination {term:?}"
        );
    }
}

/// x'' = -ω²x through verlet / symplectic Euler for `steps` steps from (x0, v0).
/// Returns (states [x, v] as recorded, termination).
fn run_oscillator(m: Method, w: f64, h: f64, x0: f64, v0: f64, steps: usize) -> (Vec<[f64; 2]>, Option<Termination>) {
    let mut sys = FnSecondOrder::new(1, move |_t, x: &[f64], _v: &[f64], a: &mut [f64]| {
        a[0] = -w * w * x[0];
        Ok(())
    });
    let opts = SolveOptions {
        t_span: (0.0, steps as f64 * h),
        h: Some(h),
        ..SolveOptions::default()
    };
    let sol = solve_second_order(&mut sys, &[x0], &[v0], &named(m), &opts).unwrap();
    let states = (0..sol.t.len()).map(|i| [sol.state(i)[0], sol.state(i)[1]]).collect();
    (states, sol.termination)
}

/// The quadratic form each symplectic method conserves exactly on x'' = -ω²x (checked with
/// sympy: Q(x₁, v₁) = Q(x₀, v₀) for one step):
///   symplectic Euler (kick, drift): Q = ω²x² + v² - hω² x v
///   velocity Verlet:                Q = ω²(1 - h²ω²/4) x² + v²
/// Both are positive definite iff hω < 2, so the state stays on an ellipse: bounded, though
/// |(x, v)| itself oscillates (the one-step matrix is not normal, so "|p| ≤ |p0|" is not the
/// right criterion here; |p_n| ≤ |p0| √(κ(Q)) is).
fn invariant(m: Method, w: f64, h: f64) -> [[f64; 2]; 2] {
    match m {
        Method::SymplecticEuler => [[w * w, -0.5 * h * w * w], [-0.5 * h * w * w, 1.0]],
        Method::Verlet => [[w * w * (1.0 - h * h * w * w / 4.0), 0.0], [0.0, 1.0]],
        _ => unreachable!(),
    }
}

fn quad(s: &[[f64; 2]; 2], p: &[f64; 2]) -> f64 {
    s[0][0] * p[0] * p[0] + 2.0 * s[0][1] * p[0] * p[1] + s[1][1] * p[1] * p[1]
}

fn eig_sym(s: &[[f64; 2]; 2]) -> (f64, f64) {
    let (a, b, d) = (s[0][0], s[0][1], s[1][1]);
    let mean = 0.5 * (a + d);
    let rad = (0.25 * (a - d).powi(2) + b * b).sqrt();
    (mean - rad, mean + rad)
}

#[test]
fn symplectic_solves_stay_bounded_just_below_hw_2_and_diverge_just_above() {
    for m in [Method::Verlet, Method::SymplecticEuler] {
        for w in [1.0, 3.0] {
            let lam = c(0.0, w);
            let h_max = max_step(&named(m), lam);
            assert!((h_max - 2.0 / w).abs() < 1e-12);
            for (x0, v0) in [(1.0, 0.0), (0.0, 1.0), (0.6, -0.8)] {
                let h = 0.98 * h_max;
                let (states, term) = run_oscillator(m, w, h, x0, v0, STEPS);
                assert!(term.is_none(), "{m} ω = {w}: {term:?}");
                assert_eq!(states.len(), STEPS + 1);
                let s = invariant(m, w, h);
                let (lmin, lmax) = eig_sym(&s);
                assert!(lmin > 0.0);
                let q0 = quad(&s, &states[0]);
                let p0 = f64::hypot(x0, v0);
                let bound = p0 * (lmax / lmin).sqrt();
                let worst = states.iter().map(|p| f64::hypot(p[0], p[1])).fold(0.0, f64::max);
                let drift = states.iter().map(|p| (quad(&s, p) - q0).abs() / q0).fold(0.0, f64::max);
                eprintln!(
                    "{m:<16} ω = {w}, hω = {:.4}, (x0, v0) = ({x0}, {v0}): max |p| = {worst:.4} (bound {bound:.4}), \
                     invariant drift {drift:.2e}",
                    h * w
                );
                assert!(
                    worst <= bound * (1.0 + 1e-9),
                    "{m} ω = {w}: |p| reached {worst}, bound {bound}"
                );
                assert!(
                    drift <= 1e-9,
                    "{m} ω = {w}: the conserved quadratic form drifted by {drift:e}"
                );

                let h = 1.02 * h_max;
                let (states, term) = run_oscillator(m, w, h, x0, v0, STEPS);
                let worst = states.iter().map(|p| f64::hypot(p[0], p[1])).fold(0.0, f64::max) / p0;
                eprintln!(
                    "{:<16} hω = {:.4}: max |p|/|p0| = {worst:.3e}, termination {term:?}",
                    "",
                    h * w
                );
                let diverged = worst > 1e3 || matches!(term, Some(Termination::NonFinite { .. }));
                assert!(
                    diverged,
                    "{m} ω = {w}, h = 1.02 max_step: max |p| = {worst} |p0|, termination {term:?}"
                );
            }
        }
    }
}

#[test]
fn symplectic_amplification_is_unimodular_inside_and_larger_outside() {
    // R is the larger root of μ² - (2 - (hω)²)μ + 1: modulus 1 for hω ≤ 2 and > 1 beyond.
    for m in [Method::Verlet, Method::SymplecticEuler] {
        for y in [0.1, 1.0, 1.5, 1.99] {
            let r = amplification(&named(m), c(0.0, y)).norm();
            assert!((r - 1.0).abs() < 1e-12, "{m} |R(i{y})| = {r}");
        }
        for y in [2.01_f64, 3.0] {
            let tau = 2.0 - y * y;
            let want = (tau.abs() + (tau * tau - 4.0).sqrt()) / 2.0;
            let r = amplification(&named(m), c(0.0, y)).norm();
            assert!((r - want).abs() < 1e-12, "{m} |R(i{y})| = {r}, expected {want}");
        }
    }
}
