//! Adaptive steps: an embedded explicit Runge–Kutta pair with error control by a step-size
//! controller. rk45 is Dormand–Prince 5(4) with DOPRI5's PI controller; the loop reads what it
//! needs from the tableau (the weights b and b̂, the order of the error estimate, whether the
//! last stage is the next first), so any embedded pair runs in it.
//!
//! Each step computes the solution y_{n+1} = y_n + h Σ b_i k_i (order p) and the error
//! estimate e = h Σ (b_i − b̂_i) k_i against the embedded solution (order p̂). With the scaled
//! norm
//!
//! ```text
//!   ‖e‖ = max over blocks of sqrt( mean_i (e_i / (atol + rtol max(|y_n,i|, |y_{n+1},i|)))² )
//! ```
//!
//! a step is accepted when ‖e‖ ≤ 1 (the result is the order-p solution: local
//! extrapolation). The next step follows the PI controller of Hairer, Nørsett & Wanner
//! (Solving ODEs I, IV.2; their DOPRI5 code), derived in `controller`:
//!
//! ```text
//!   h_new = h · clamp(0.9 · ‖e_n‖^(−α) · ‖e_{n−1}‖^β, 0.2, 10),   α = 1/(q+1) − 0.75 β, β = 0.04
//! ```
//!
//! with q = min(p, p̂) the order of the error estimate (4 for Dormand–Prince: α = 0.17). The
//! integral part α reacts to the current error, the proportional part β damps the
//! oscillation of the step size that a pure I controller (β = 0) shows on problems at the
//! edge of stability. After a rejection the step does not grow.

use super::controller::{StepSizeController, ERR_PREV_FLOOR};
use super::dense::{self, DenseOutput};
use super::explicit_rk::ExplicitRk;
use super::solution::{Recorder, Solution, SolveOptions};
use super::stepper::{first_non_finite, Stats, Termination};
use super::system::OdeSystem;
use super::tableau::{catalogue, ButcherTableau};
use crate::error::Error;

/// Scaled error norm: RMS over each block, maximum over blocks (so that one member of a batch
/// cannot hide its error among the others).
fn error_norm(err: &[f64], y: &[f64], y_new: &[f64], rtol: f64, atol: f64, block: usize) -> f64 {
    let mut worst = 0.0_f64;
    for ((e, a), b) in err
        .chunks_exact(block)
        .zip(y.chunks_exact(block))
        .zip(y_new.chunks_exact(block))
    {
        let mut sum = 0.0;
        for i in 0..block {
            let sc = atol + rtol * a[i].abs().max(b[i].abs());
            // With atol = 0 a component that is exactly 0 has scale 0: its error counts as 0
            // when it is exactly 0 too, and as infinite otherwise (never as 0/0 = NaN).
            let r = if e[i] == 0.0 { 0.0 } else { e[i] / sc };
            sum += r * r;
        }
        let norm = (sum / block as f64).sqrt();
        // NaN-propagating max: a NaN error (f returned NaN) must reject the step.
        if norm.is_nan() || norm > worst {
            worst = norm;
        }
    }
    worst
}

fn rms_scaled(v: &[f64], y: &[f64], rtol: f64, atol: f64, block: usize) -> f64 {
    error_norm(v, y, y, rtol, atol, block)
}

/// First step size (Hairer, Nørsett & Wanner, II.4, "automatic step size selection"):
/// h₀ = 0.01 ‖y0‖/‖f0‖, one Euler step to estimate the second derivative, then
/// h = (0.01 / max(‖f0‖, ‖y''‖))^{1/(q+1)} with q the order of the error estimate (4 for
/// Dormand–Prince; as SciPy's `select_initial_step`), bounded by 100 h₀. Starts at
/// t0 = `opts.t_span.0` in the direction of t_span.
fn initial_step(
    sys: &mut dyn OdeSystem,
    y0: &[f64],
    f0: &[f64],
    error_order: u32,
    opts: &SolveOptions,
    stats: &mut Stats,
) -> Result<f64, Error> {
    let (t0, t_end) = opts.t_span;
    let dir = if t_end >= t0 { 1.0 } else { -1.0 };
    let b = sys.block_len();
    let d0 = rms_scaled(y0, y0, opts.rtol, opts.atol, b);
    let d1 = rms_scaled(f0, y0, opts.rtol, opts.atol, b);
    let h0 = if d0 < 1e-5 || d1 < 1e-5 { 1e-6 } else { 0.01 * d0 / d1 };
    let y1: Vec<f64> = y0.iter().zip(f0).map(|(y, f)| y + dir * h0 * f).collect();
    let mut f1 = vec![0.0; y0.len()];
    sys.rhs(t0 + dir * h0, &y1, &mut f1)?;
    stats.nfev += 1;
    let diff: Vec<f64> = f1.iter().zip(f0).map(|(a, b)| a - b).collect();
    let d2 = rms_scaled(&diff, y0, opts.rtol, opts.atol, b) / h0;
    let h1 = if d1.max(d2) <= 1e-15 {
        (h0 * 1e-3).max(1e-6)
    } else {
        (0.01 / d1.max(d2)).powf(1.0 / (f64::from(error_order) + 1.0))
    };
    Ok((100.0 * h0).min(h1))
}

/// How the state between two step boundaries is evaluated (`t_eval`, `dense_output`).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Interpolant {
    /// Dormand–Prince's continuous extension of order 4, from the step's stages.
    Dopri5,
    /// Cubic Hermite from y and f at both ends (O(h⁴) error): pairs without an extension
    /// of their own.
    Hermite,
}

/// An adaptive method: an embedded pair, what the loop reads from its tableau, and the
/// controller of its step.
pub(crate) struct Adaptive {
    tab: ButcherTableau,
    controller: StepSizeController,
    /// Weights b − b̂ of the error estimate.
    e_weights: Vec<f64>,
    /// Order q of the error estimate (its local error is O(h^(q+1))).
    error_order: u32,
    /// First same as last: the last stage is f(t_{n+1}, y_{n+1}), the next step's first.
    fsal: bool,
    interpolant: Interpolant,
}

impl Adaptive {
    /// The pair `tab` (which must have embedded weights) under `controller`.
    pub(crate) fn new(tab: ButcherTableau, controller: StepSizeController) -> Result<Self, Error> {
        let (Some(b_hat), Some(error_order)) = (tab.b_hat(), tab.error_order()) else {
            return Err(Error::InvalidTableau(format!(
                "tableau '{}' has no embedded weights: adaptive steps need an error estimate",
                tab.name()
            )));
        };
        let e_weights = tab.b().iter().zip(b_hat).map(|(b, bh)| b - bh).collect();
        // Dormand–Prince's dense coefficients belong to its stages: any other pair (other
        // coefficients) is interpolated by Hermite pieces.
        let dp = catalogue::dopri5();
        let same_as_dopri5 = tab.stages() == dp.stages()
            && tab.b() == dp.b()
            && tab.c() == dp.c()
            && (0..dp.stages()).all(|i| tab.a_row(i) == dp.a_row(i));
        Ok(Self {
            fsal: tab.is_fsal(),
            interpolant: if same_as_dopri5 {
                Interpolant::Dopri5
            } else {
                Interpolant::Hermite
            },
            tab,
            controller,
            e_weights,
            error_order,
        })
    }

    /// Integrates y' = f(t, y) from y0 over `opts.t_span` with step-size control; the
    /// solution is labelled `name`.
    pub(crate) fn run(&self, sys: &mut dyn OdeSystem, y0: &[f64], opts: &SolveOptions, name: &str) -> Result<Solution, Error> {
        let (t0, t_end) = opts.t_span;
        let dir = if t_end >= t0 { 1.0 } else { -1.0 };
        let n = y0.len();
        let block = sys.block_len();
        let b_weights = self.tab.b().to_vec();
        let alpha = self.controller.alpha(self.error_order);
        let mut stats = Stats::default();
        let mut rec = Recorder::new(opts, t0, y0);
        let mut termination = None;
        let mut rk = ExplicitRk::new(self.tab.clone(), n);

        let (mut t, mut y) = (t0, y0.to_vec());
        let mut y_new = vec![0.0; n];
        let mut err = vec![0.0; n];
        // f(t_{n+1}, y_{n+1}) for a pair that is not FSAL (evaluated after an accepted step).
        let mut f_new = vec![0.0; n];
        let mut h = match self.first_step(sys, y0, opts, &mut rk, &mut stats)? {
            Ok(h) => h,
            Err(termination) => return Ok(rec.finish(stats, Some(termination), name)),
        };
        let mut dense_out = opts.dense_output.then(|| match self.interpolant {
            Interpolant::Dopri5 => DenseOutput::dopri5(n, t0),
            Interpolant::Hermite => DenseOutput::hermite(n, vec![t0], y0.to_vec(), rk.k()[0].clone()),
        });
        let mut err_prev = ERR_PREV_FLOOR;
        let mut last_rejected = false;
        // Component that was non-finite in the last rejected attempt, if that was the reason.
        let mut non_finite_at: Option<usize> = None;

        while dir * (t_end - t) > 0.0 {
            if let Some(stop) = limits(t, h, &stats, opts, non_finite_at) {
                termination = Some(stop);
                break;
            }
            if let Some(h_max) = opts.h_max {
                h = h.min(h_max);
            }
            let remaining = (t_end - t).abs();
            let (h_step, last) = if h >= remaining { (remaining, true) } else { (h, false) };
            let t_b = if last { t_end } else { t + dir * h_step };
            let hs = t_b - t; // signed

            // k_1 = f(t, y) is known: from the start, the previous step, or the attempt
            // rejected before (which did not touch it).
            rk.stages(sys, t, &y, hs, true, &mut stats)?;
            rk.combine(&y, hs, &b_weights, &mut y_new);
            rk.increment(hs, &self.e_weights, &mut err);
            let norm = error_norm(&err, &y, &y_new, opts.rtol, opts.atol, block);

            let bad = first_non_finite(&y_new);
            if norm <= 1.0 && bad.is_none() {
                non_finite_at = None;
                stats.nsteps += 1;
                let s = self.tab.stages();
                // f at the new state, for Hermite pieces and as the next step's k_1: an FSAL
                // pair has it as its last stage; another one evaluates it (after the last step
                // only when an interpolant needs it).
                let f_new_known = !self.fsal && (!last || dense_out.is_some() || rec.needs_dense(t_b));
                if f_new_known {
                    sys.rhs(t_b, &y_new, &mut f_new)?;
                    stats.nfev += 1;
                }
                let k = rk.k();
                let f_b = if self.fsal { &k[s - 1] } else { &f_new };
                self.record(&mut rec, dense_out.as_mut(), (t, hs, t_b), (&y, &y_new), (k, f_b));
                t = t_b;
                std::mem::swap(&mut y, &mut y_new);
                if self.fsal {
                    // first same as last: k_s = f(t_{n+1}, y_{n+1}) is the next k_1
                    rk.k_mut().swap(0, s - 1);
                } else if f_new_known {
                    std::mem::swap(&mut rk.k_mut()[0], &mut f_new);
                }
                h = h_step * self.controller.after_accept(alpha, norm, err_prev, last_rejected);
                err_prev = norm.max(ERR_PREV_FLOOR);
                last_rejected = false;
            } else {
                stats.nrejected += 1;
                non_finite_at = bad.or_else(|| (!norm.is_finite()).then(|| first_non_finite(&err).unwrap_or(0)));
                h = h_step * self.controller.after_reject(alpha, norm);
                last_rejected = true;
            }
        }
        let mut sol = rec.finish(stats, termination, name);
        sol.dense = dense_out;
        Ok(sol)
    }

    /// The first stage f(t0, y0) into `rk`, and the first step: `opts.h`, else the initial
    /// step's estimate (0 over an empty span). A non-finite f(t0, y0) ends the run before
    /// any step (`Err` inside).
    fn first_step(
        &self,
        sys: &mut dyn OdeSystem,
        y0: &[f64],
        opts: &SolveOptions,
        rk: &mut ExplicitRk,
        stats: &mut Stats,
    ) -> Result<Result<f64, Termination>, Error> {
        let (t0, t_end) = opts.t_span;
        rk.first_stage(sys, t0, y0, stats)?;
        if let Some(index) = first_non_finite(&rk.k()[0]) {
            // f(t0, y0) itself is NaN/inf: no step can be taken.
            return Ok(Err(Termination::NonFinite { t: t0, h: 0.0, index }));
        }
        Ok(Ok(match opts.h {
            Some(h) => h,
            None if t_end == t0 => 0.0,
            None => {
                let f0 = rk.k()[0].clone();
                initial_step(sys, y0, &f0, self.error_order, opts, stats)?
            }
        }))
    }

    /// An accepted step from (t, y) by hs to (t_b, y_new) (stages `k`, f at the new state
    /// `f_b`) into the recorder and the dense output, through the pair's interpolant.
    fn record(
        &self,
        rec: &mut Recorder,
        dense_out: Option<&mut DenseOutput>,
        (t, hs, t_b): (f64, f64, f64),
        (y, y_new): (&[f64], &[f64]),
        (k, f_b): (&[Vec<f64>], &[f64]),
    ) {
        match self.interpolant {
            Interpolant::Dopri5 => rec.step(t, hs, t_b, y_new, |theta, out| dense::dopri5(theta, hs, y, k, out)),
            Interpolant::Hermite => rec.step(t, hs, t_b, y_new, |theta, out| {
                dense::hermite(theta, hs, y, y_new, &k[0], f_b, out)
            }),
        }
        if let Some(d) = dense_out {
            match self.interpolant {
                Interpolant::Dopri5 => d.push_dopri5(t_b, y, k),
                Interpolant::Hermite => d.push_hermite(t_b, y_new, f_b),
            }
        }
    }
}

/// Why the loop stops before a step from t with h, if it does: the step count reached, or a
/// step below the smallest (the user's h_min, and at least what the time variable can
/// resolve at t, ten units in the last place: at t = 0 the smallest subnormal, so a step
/// that keeps failing ends after a few hundred rejections at worst), named non-finite when
/// the last attempts failed on NaN/inf (`non_finite_at`).
fn limits(t: f64, h: f64, stats: &Stats, opts: &SolveOptions, non_finite_at: Option<usize>) -> Option<Termination> {
    let h_min = opts.h_min.unwrap_or(0.0).max(10.0 * (t.abs().next_up() - t.abs()));
    if stats.nsteps >= opts.max_steps {
        return Some(Termination::MaxSteps { t, steps: stats.nsteps });
    }
    if h.is_nan() || h < h_min {
        return Some(match non_finite_at {
            // The last attempts failed because f or the stages produced NaN/inf: say so.
            Some(index) => Termination::NonFinite { t, h, index },
            None => Termination::StepTooSmall { t, h },
        });
    }
    None
}

#[cfg(test)]
mod tests {
    //! The loop with pairs other than Dormand–Prince (which the rk45 tests cover), on
    //! y' = −y, y(0) = 1, y(t) = e^(−t) over [0, 2]: Bogacki–Shampine 3(2) (FSAL, error
    //! estimate of order 2) and Heun–Euler 2(1) (not FSAL, order 1).
    use super::*;
    use crate::ode::system::FnSystem;

    fn decay() -> impl OdeSystem {
        FnSystem::new(1, |_t, y: &[f64], dy: &mut [f64]| {
            dy[0] = -y[0];
            Ok(())
        })
    }

    fn opts(tol: f64) -> SolveOptions {
        SolveOptions {
            t_span: (0.0, 2.0),
            rtol: tol,
            atol: tol,
            ..SolveOptions::default()
        }
    }

    fn adaptive(tab: ButcherTableau, tol: f64) -> Solution {
        let method = Adaptive::new(tab, StepSizeController::default()).unwrap();
        method.run(&mut decay(), &[1.0], &opts(tol), "pair").unwrap()
    }

    /// Heun's method with Euler as the embedded method: b = (1/2, 1/2), b̂ = (1, 0). Its last
    /// stage is f(t + h, y + h k_1), not f at the new state: not FSAL.
    fn heun_euler() -> ButcherTableau {
        catalogue::heun().with_embedded(vec![1.0, 0.0], 1).unwrap()
    }

    /// Slopes log2(e(h) / e(h/2)) of successive errors.
    fn slopes(errors: &[f64]) -> Vec<f64> {
        errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
    }

    #[test]
    fn bogacki_shampine_has_order_3_and_its_error_estimate_order_2() {
        let tab = catalogue::bs3();
        assert!(tab.is_fsal());
        // Global order 3: fixed steps h = 2/N of the order-3 solution, error at t = 2.
        let mut rk = ExplicitRk::new(tab.clone(), 1);
        let errors: Vec<f64> = [16, 32, 64, 128]
            .iter()
            .map(|&steps| {
                let h = 2.0 / steps as f64;
                let (mut y, mut y_next) = ([1.0], [0.0]);
                for k in 0..steps {
                    rk.stages(&mut decay(), k as f64 * h, &y, h, false, &mut Stats::default())
                        .unwrap();
                    rk.combine(&y, h, tab.b(), &mut y_next);
                    y = y_next;
                }
                (y[0] - (-2.0_f64).exp()).abs()
            })
            .collect();
        for p in slopes(&errors) {
            assert!((p - 3.0).abs() < 0.1, "global order {p} from {errors:?}");
        }
        // The estimate e = h Σ (b_i − b̂_i) k_i of one step is the local error of the
        // second-order solution: O(h³), so the controller's exponent is 1/3.
        let e_weights: Vec<f64> = tab.b().iter().zip(tab.b_hat().unwrap()).map(|(b, bh)| b - bh).collect();
        let estimates: Vec<f64> = [0.1, 0.05, 0.025, 0.0125]
            .iter()
            .map(|&h| {
                let mut e = [0.0];
                rk.stages(&mut decay(), 0.0, &[1.0], h, false, &mut Stats::default()).unwrap();
                rk.increment(h, &e_weights, &mut e);
                e[0].abs()
            })
            .collect();
        for p in slopes(&estimates) {
            assert!((p - 3.0).abs() < 0.1, "estimate order {p} from {estimates:?}");
        }
    }

    #[test]
    fn bogacki_shampine_meets_the_tolerance_and_reuses_its_last_stage() {
        // Criterion as in tests/rk45_meets_tolerance.rs: global error within 10 tol (1 + max|y|)
        // on a contracting problem.
        let mut steps = Vec::new();
        for tol in [1e-3, 1e-5, 1e-7, 1e-9] {
            let sol = adaptive(catalogue::bs3(), tol);
            assert!(sol.success(), "{}", sol.message());
            let err = (sol.last()[0] - (-2.0_f64).exp()).abs();
            assert!(err <= 20.0 * tol, "tol {tol}: error {err}");
            // FSAL, read from the tableau: 3 new evaluations per attempt (of 4 stages), plus
            // f(t0, y0) and the one of the initial step selection.
            let s = sol.stats;
            assert_eq!(s.nfev, 2 + 3 * (s.nsteps + s.nrejected), "{s:?}");
            steps.push(s.nsteps as f64);
        }
        // Steps h ∝ tol^(1/(q+1)) = tol^(1/3): 100 times tighter, 100^(1/3) ≈ 4.6 times the steps.
        for w in steps.windows(2) {
            let ratio = w[1] / w[0];
            assert!((3.0..7.0).contains(&ratio), "steps {steps:?}");
        }
    }

    #[test]
    fn a_pair_that_is_not_fsal_evaluates_f_at_each_new_state() {
        let tab = heun_euler();
        assert!(!tab.is_fsal());
        let tol = 1e-6;
        let sol = adaptive(tab, tol);
        assert!(sol.success(), "{}", sol.message());
        assert!((sol.last()[0] - (-2.0_f64).exp()).abs() <= 20.0 * tol);
        // Per attempt one new stage (k_1 is known); after each accepted step but the last,
        // f at the new state (the next k_1); f(t0, y0) and the initial step's evaluation.
        let s = sol.stats;
        assert_eq!(s.nfev, 2 + (s.nsteps + s.nrejected) + (s.nsteps - 1), "{s:?}");
    }

    #[test]
    fn pairs_without_their_own_extension_interpolate_with_hermite_pieces() {
        let tol = 1e-7;
        for tab in [catalogue::bs3(), heun_euler()] {
            let name = tab.name().to_string();
            let t_eval: Vec<f64> = (0..=20).map(|i| 0.1 * i as f64).collect();
            let o = SolveOptions {
                t_eval: Some(t_eval.clone()),
                dense_output: true,
                ..opts(tol)
            };
            let method = Adaptive::new(tab, StepSizeController::default()).unwrap();
            assert_eq!(method.interpolant, Interpolant::Hermite);
            let sol = method.run(&mut decay(), &[1.0], &o, &name).unwrap();
            assert_eq!(sol.t, t_eval, "{name}");
            let dense = sol.dense.as_ref().unwrap();
            let mut out = [0.0];
            for (i, &t) in t_eval.iter().enumerate() {
                let exact = (-t).exp();
                assert!((sol.state(i)[0] - exact).abs() <= 20.0 * tol, "{name} at t = {t}");
                dense.eval(t + 0.03_f64.min(2.0 - t), &mut out).unwrap();
                assert!(
                    (out[0] - (-(t + 0.03_f64.min(2.0 - t))).exp()).abs() <= 20.0 * tol,
                    "{name} dense near {t}"
                );
            }
        }
        let dopri5 = Adaptive::new(catalogue::dopri5(), StepSizeController::default()).unwrap();
        assert_eq!(dopri5.interpolant, Interpolant::Dopri5);
    }

    #[test]
    fn a_tableau_without_embedded_weights_is_refused() {
        let e = Adaptive::new(catalogue::rk4(), StepSizeController::default()).err().unwrap();
        assert!(e.to_string().contains("tableau 'rk4' has no embedded weights"), "{e}");
    }
}
