//! rk45 (Dormand–Prince 5(4) with step-size control) delivers the accuracy it is asked for:
//! global errors against closed forms (harmonic oscillator y = (cos t, -sin t) on [0, 10], and
//! logistic y' = y(1 - y), y(0) = 0.1, y = 1/(1 + 9e^(-t))) stay within a small multiple of
//! the tolerance, tighter tolerances cost strictly more steps, dense output (t_eval between
//! steps) is as accurate as the steps, and integrating backwards (t_span = (1, 0)) works.
//!
//! Theory: each accepted step has ‖e‖ ≤ 1 where e is the embedded 4th-order error estimate
//! scaled by atol + rtol·|y|, i.e. the local error of the 4th-order solution is about tol·(1+|y|)
//! per step. The propagated solution is the 5th-order one (local extrapolation), whose own local
//! error is far smaller, and both test problems are non-expanding (the oscillator conserves
//! |y|, the logistic flow contracts towards y = 1), so local errors do not get amplified. The
//! global error is therefore expected to be of the order of tol·(1 + max|y|) or below; the
//! criterion is 10·tol·(1 + max|y|) — a factor 10 for error accumulation over many steps and the
//! controller's safety margin. It is not met by a method that ignores the tolerance: at
//! tol = 1e-10 the error must drop by 6 orders from tol = 1e-4.

use kinema::ode::{solve, FnSystem, Integrator, Method, OdeSystem, SolveOptions};

const TOLS: [f64; 4] = [1e-4, 1e-6, 1e-8, 1e-10];

fn rk45() -> Integrator {
    Integrator::Named(Method::Rk45)
}

fn opts(t_span: (f64, f64), tol: f64) -> SolveOptions {
    SolveOptions {
        t_span,
        rtol: tol,
        atol: tol,
        ..SolveOptions::default()
    }
}

fn oscillator() -> impl OdeSystem {
    FnSystem::new(2, |_t, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[1];
        dy[1] = -y[0];
        Ok(())
    })
}

fn osc_exact(t: f64) -> [f64; 2] {
    [t.cos(), -t.sin()]
}

fn logistic() -> impl OdeSystem {
    FnSystem::new(1, |_t, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[0] * (1.0 - y[0]);
        Ok(())
    })
}

fn logistic_exact(t: f64) -> [f64; 1] {
    [1.0 / (1.0 + 9.0 * (-t).exp())]
}

fn max_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// Solves over `t_span` for every tolerance; checks the error at every recorded step (not only
/// at the end) against the criterion and that nsteps falls strictly as tol loosens.
fn check_problem(
    label: &str,
    mut make: impl FnMut() -> Box<dyn OdeSystem>,
    exact: impl Fn(f64) -> Vec<f64>,
    t_span: (f64, f64),
    scale: f64,
) {
    let y0 = exact(t_span.0);
    let mut results = Vec::new();
    for tol in TOLS {
        let mut sys = make();
        let sol = solve(sys.as_mut(), &y0, &rk45(), &opts(t_span, tol)).unwrap();
        assert!(sol.success(), "{label} tol {tol}: {}", sol.message());
        assert_eq!(*sol.t.last().unwrap(), t_span.1);
        let end_err = max_diff(sol.last(), &exact(t_span.1));
        let worst = (0..sol.t.len())
            .map(|i| max_diff(sol.state(i), &exact(sol.t[i])))
            .fold(0.0, f64::max);
        eprintln!(
            "{label:<10} tol {tol:.0e}: nsteps {:>4}, nrejected {:>2}, nfev {:>5}; error at end {end_err:.3e} ({:.3} tol), worst over steps {worst:.3e} ({:.3} tol)",
            sol.stats.nsteps,
            sol.stats.nrejected,
            sol.stats.nfev,
            end_err / tol,
            worst / tol
        );
        let allowed = 10.0 * tol * scale;
        assert!(end_err <= allowed, "{label} tol {tol}: end error {end_err:e} > {allowed:e}");
        assert!(worst <= allowed, "{label} tol {tol}: worst error {worst:e} > {allowed:e}");
        assert_eq!(
            sol.stats.nsteps + 1,
            sol.t.len(),
            "one recorded state per accepted step (and t0)"
        );
        results.push((tol, sol.stats.nsteps, end_err));
    }
    // Looser tolerance -> strictly fewer steps.
    for w in results.windows(2) {
        let ((t_tight, n_tight, _), (t_loose, n_loose, _)) = (w[1], w[0]);
        assert!(
            n_loose < n_tight,
            "{label}: tol {t_loose} took {n_loose} steps, tol {t_tight} took {n_tight}"
        );
    }
    // The error follows the tolerance: six orders of tolerance buy at least four of accuracy
    // (a 5th-order method with a 4th-order controller gives error ∝ tol^(5/4) or so, or ∝ tol).
    let (first, last) = (results[0].2, results[results.len() - 1].2);
    assert!(
        last <= 1e-4 * first,
        "{label}: error {first:e} at tol 1e-4 but {last:e} at tol 1e-10"
    );
}

#[test]
fn global_error_follows_the_tolerance_on_the_oscillator() {
    // |y| = 1 throughout: scale 1 + max|y| = 2.
    check_problem(
        "oscillator",
        || Box::new(oscillator()),
        |t| osc_exact(t).to_vec(),
        (0.0, 10.0),
        2.0,
    );
}

#[test]
fn global_error_follows_the_tolerance_on_the_logistic_equation() {
    // 0.1 ≤ y < 1: scale 1 + max|y| ≤ 2.
    check_problem(
        "logistic",
        || Box::new(logistic()),
        |t| logistic_exact(t).to_vec(),
        (0.0, 10.0),
        2.0,
    );
}

#[test]
fn dense_output_between_steps_is_as_accurate_as_the_steps() {
    // t_eval points generally fall strictly inside steps; the 4th-order continuous extension
    // must be about as accurate as the steps themselves (same 10·tol·scale criterion).
    let t_eval: Vec<f64> = (0..=1000).map(|k| 0.01 * k as f64 + 0.00123).filter(|t| *t <= 10.0).collect();
    for tol in [1e-4, 1e-6, 1e-8] {
        let mut sys = oscillator();
        let o = SolveOptions {
            t_eval: Some(t_eval.clone()),
            ..opts((0.0, 10.0), tol)
        };
        let sol = solve(&mut sys, &[1.0, 0.0], &rk45(), &o).unwrap();
        assert!(sol.success());
        assert_eq!(sol.t, t_eval, "the output is exactly at t_eval");
        // Far more output points than steps: most are interpolated.
        assert!(
            sol.stats.nsteps < t_eval.len() / 2,
            "nsteps {} for {} points",
            sol.stats.nsteps,
            t_eval.len()
        );
        let worst = (0..sol.t.len())
            .map(|i| max_diff(sol.state(i), &osc_exact(sol.t[i])))
            .fold(0.0, f64::max);
        eprintln!(
            "dense output tol {tol:.0e}: {} steps, {} points, worst error {worst:.3e} ({:.3} tol)",
            sol.stats.nsteps,
            sol.t.len(),
            worst / tol
        );
        assert!(worst <= 10.0 * tol * 2.0, "tol {tol}: dense output error {worst:e}");

        // The dense output does not change the steps taken: same end state as without t_eval.
        let mut sys = oscillator();
        let plain = solve(&mut sys, &[1.0, 0.0], &rk45(), &opts((0.0, 10.0), tol)).unwrap();
        assert_eq!(plain.stats.nsteps, sol.stats.nsteps);
    }
}

#[test]
fn integrating_backwards_works() {
    // From the exact state at t = 1 back to t = 0 (and to t = -5).
    for (t_end, tol) in [(0.0, 1e-8), (-5.0, 1e-6)] {
        let mut sys = oscillator();
        let sol = solve(&mut sys, &osc_exact(1.0), &rk45(), &opts((1.0, t_end), tol)).unwrap();
        assert!(sol.success(), "{}", sol.message());
        assert!(sol.t.windows(2).all(|w| w[1] < w[0]), "times must decrease");
        assert_eq!(*sol.t.last().unwrap(), t_end);
        let err = max_diff(sol.last(), &osc_exact(t_end));
        eprintln!(
            "backwards 1 -> {t_end}, tol {tol:.0e}: {} steps, error {err:.3e}",
            sol.stats.nsteps
        );
        assert!(err <= 10.0 * tol * 2.0, "backwards to {t_end}: error {err:e}");
    }

    // With descending t_eval (interpolated points), and the logistic equation run backwards
    // (where the backward flow is expanding, away from y = 1: a harder check of direction).
    let t_eval = vec![1.0, 0.75, 0.5, 0.33, 0.0];
    let mut sys = logistic();
    let o = SolveOptions {
        t_eval: Some(t_eval.clone()),
        ..opts((1.0, 0.0), 1e-9)
    };
    let sol = solve(&mut sys, &logistic_exact(1.0), &rk45(), &o).unwrap();
    assert!(sol.success());
    assert_eq!(sol.t, t_eval);
    for i in 0..sol.t.len() {
        let err = (sol.state(i)[0] - logistic_exact(sol.t[i])[0]).abs();
        assert!(err <= 2e-8, "logistic backwards at t = {}: error {err:e}", sol.t[i]);
    }

    // A fixed-step method backwards as well: rk4 from t = 1 to 0 with h = 0.01 (error ~ h⁴).
    let mut sys = oscillator();
    let o = SolveOptions {
        t_span: (1.0, 0.0),
        h: Some(0.01),
        ..SolveOptions::default()
    };
    let sol = solve(&mut sys, &osc_exact(1.0), &Integrator::Named(Method::Rk4), &o).unwrap();
    assert_eq!(sol.t.len(), 101);
    assert!(sol.t.windows(2).all(|w| w[1] < w[0]));
    let err = max_diff(sol.last(), &osc_exact(0.0));
    assert!(err < 1e-9, "rk4 backwards: error {err:e}");
}

#[test]
fn a_given_first_step_is_used_and_the_result_still_meets_the_tolerance() {
    for h0 in [1e-6, 0.5, 5.0] {
        let mut sys = oscillator();
        let o = SolveOptions {
            h: Some(h0),
            ..opts((0.0, 10.0), 1e-8)
        };
        let sol = solve(&mut sys, &[1.0, 0.0], &rk45(), &o).unwrap();
        assert!(sol.success());
        let err = max_diff(sol.last(), &osc_exact(10.0));
        eprintln!(
            "first step {h0}: {} steps, {} rejected, error {err:.3e}",
            sol.stats.nsteps, sol.stats.nrejected
        );
        assert!(err <= 10.0 * 1e-8 * 2.0, "h0 = {h0}: error {err:e}");
        if h0 == 1e-6 {
            assert!(
                (sol.t[1] - 1e-6).abs() < 1e-20,
                "first step should be the given h: t[1] = {}",
                sol.t[1]
            );
        }
    }
}

#[test]
fn batch_members_each_meet_the_tolerance() {
    // Three oscillators with different amplitudes as one batched system (block_len = 2): the
    // error norm is the maximum over blocks, so the small-amplitude member (where atol dominates)
    // is not hidden by the large ones.
    struct Batch;
    impl OdeSystem for Batch {
        fn dim(&self) -> usize {
            6
        }
        fn block_len(&self) -> usize {
            2
        }
        fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), kinema::CallbackError> {
            for (yb, db) in y.chunks_exact(2).zip(dy.chunks_exact_mut(2)) {
                db[0] = yb[1];
                db[1] = -yb[0];
            }
            Ok(())
        }
    }
    let amps = [1e3, 1.0, 1e-3];
    let y0: Vec<f64> = amps.iter().flat_map(|a| [*a, 0.0]).collect();
    let tol = 1e-8;
    let sol = solve(&mut Batch, &y0, &rk45(), &opts((0.0, 10.0), tol)).unwrap();
    assert!(sol.success());
    for (k, a) in amps.iter().enumerate() {
        let ex = osc_exact(10.0);
        let got = &sol.last()[2 * k..2 * k + 2];
        let err = (got[0] - a * ex[0]).abs().max((got[1] - a * ex[1]).abs());
        eprintln!("batch member amplitude {a:e}: error {err:.3e}");
        assert!(err <= 10.0 * tol * (1.0 + a), "member {k} (amplitude {a}): error {err:e}");
    }
}

/// atol = 0 is accepted by validation ("must be a finite number >= 0"): a pure relative
/// tolerance. A component that is exactly zero then has scale atol + rtol·|y| = 0 and the error
/// control must still control the other components of its block.
///
/// Observed: 8 steps and a relative error of 3.9e6 (y₁(10) ≈ 176 instead of e^-10 ≈ 4.5e-5).
#[test]
fn pure_relative_tolerance_with_a_zero_component_still_controls_the_error() {
    // y = (0, e^(-t)) with y0' = 0: the first component stays exactly 0, its error estimate is 0.
    let mut sys = FnSystem::new(2, |_t, y: &[f64], dy: &mut [f64]| {
        dy[0] = 0.0;
        dy[1] = -y[1];
        Ok(())
    });
    let rtol = 1e-8;
    let o = SolveOptions {
        t_span: (0.0, 10.0),
        rtol,
        atol: 0.0,
        ..SolveOptions::default()
    };
    let res = solve(&mut sys, &[0.0, 1.0], &rk45(), &o);
    let sol = res.expect("atol = 0 is documented as valid");
    let exact = (-10.0f64).exp();
    let rel = (sol.last()[1] - exact).abs() / exact;
    eprintln!(
        "atol = 0: {} steps, termination {:?}, relative error {rel:.3e}",
        sol.stats.nsteps, sol.termination
    );
    assert!(sol.success(), "{}", sol.message());
    assert!(rel <= 10.0 * rtol * 10.0, "relative error {rel:e} with rtol {rtol}");
}
