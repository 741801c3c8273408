//! rk45: Dormand–Prince 5(4) with error control by a PI step-size controller.
//!
//! Each step computes the fifth-order solution y_{n+1} = y_n + h Σ b_i k_i and the error
//! estimate e = h Σ (b_i − b̂_i) k_i against the embedded fourth-order solution. With the
//! scaled norm
//!
//! ```text
//!   ‖e‖ = max over blocks of sqrt( mean_i (e_i / (atol + rtol max(|y_n,i|, |y_{n+1},i|)))² )
//! ```
//!
//! a step is accepted when ‖e‖ ≤ 1 (the result is the fifth-order solution: local
//! extrapolation). The next step follows the PI controller of Hairer, Nørsett & Wanner
//! (Solving ODEs I, IV.2; their DOPRI5 code):
//!
//! ```text
//!   h_new = h · clamp(0.9 · ‖e_n‖^(−α) · ‖e_{n−1}‖^β, 0.2, 10),   α = 0.2 − 0.75 β, β = 0.04
//! ```
//!
//! The integral part α reacts to the current error, the proportional part β damps the
//! oscillation of the step size that a pure I controller (β = 0) shows on problems at the
//! edge of stability. After a rejection the step does not grow.

use super::dense::{self, DenseOutput};
use super::explicit_rk::ExplicitRk;
use super::solution::{Recorder, Solution, SolveOptions};
use super::stepper::{first_non_finite, Stats, Termination};
use super::system::OdeSystem;
use super::tableau::catalogue;
use crate::error::Error;

const SAFETY: f64 = 0.9;
const BETA: f64 = 0.04;
const ALPHA: f64 = 0.2 - 0.75 * BETA;
const MIN_FACTOR: f64 = 0.2;
const MAX_FACTOR: f64 = 10.0;

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
/// h = (0.01 / max(‖f0‖, ‖y''‖))^{1/(p+1)} with p = 4, bounded by 100 h₀.
fn initial_step(
    sys: &mut dyn OdeSystem,
    t0: f64,
    y0: &[f64],
    f0: &[f64],
    dir: f64,
    opts: &SolveOptions,
    stats: &mut Stats,
) -> Result<f64, Error> {
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
        (0.01 / d1.max(d2)).powf(1.0 / 5.0)
    };
    Ok((100.0 * h0).min(h1))
}

/// Integrates with Dormand–Prince 5(4) and step-size control.
pub(crate) fn run(sys: &mut dyn OdeSystem, y0: &[f64], opts: &SolveOptions) -> Result<Solution, Error> {
    let (t0, t_end) = opts.t_span;
    let dir = if t_end >= t0 { 1.0 } else { -1.0 };
    let n = y0.len();
    let block = sys.block_len();
    let tab = catalogue::dopri5();
    let e_weights: Vec<f64> = tab
        .b()
        .iter()
        .zip(tab.b_hat().expect("dopri5 is embedded"))
        .map(|(b, bh)| b - bh)
        .collect();
    let b_weights = tab.b().to_vec();
    let mut stats = Stats::default();
    let mut rec = Recorder::new(opts, t0, y0);
    let mut termination = None;
    let mut rk = ExplicitRk::new(tab, n);

    let (mut t, mut y) = (t0, y0.to_vec());
    let mut y_new = vec![0.0; n];
    let mut err = vec![0.0; n];
    rk.first_stage(sys, t0, y0, &mut stats)?;
    if let Some(index) = first_non_finite(&rk.k()[0]) {
        // f(t0, y0) itself is NaN/inf: no step can be taken.
        let termination = Some(Termination::NonFinite { t: t0, h: 0.0, index });
        return Ok(rec.finish(stats, termination, "rk45"));
    }
    let mut h = match opts.h {
        Some(h) => h,
        None if t_end == t0 => 0.0,
        None => {
            let f0 = rk.k()[0].clone();
            initial_step(sys, t0, y0, &f0, dir, opts, &mut stats)?
        }
    };
    let mut dense_out = opts.dense_output.then(|| DenseOutput::dopri5(n, t0));
    let mut err_prev = 1e-4_f64;
    let mut last_rejected = false;
    // Component that was non-finite in the last rejected attempt, if that was the reason.
    let mut non_finite_at: Option<usize> = None;

    while dir * (t_end - t) > 0.0 {
        // Smallest step: the user's h_min, and at least what the time variable can resolve at
        // t, ten units in the last place (at t = 0 the smallest subnormal, so a step that
        // keeps failing ends after a few hundred rejections at worst).
        let h_min = opts.h_min.unwrap_or(0.0).max(10.0 * (t.abs().next_up() - t.abs()));
        if stats.nsteps >= opts.max_steps {
            termination = Some(Termination::MaxSteps { t, steps: stats.nsteps });
            break;
        }
        if h.is_nan() || h < h_min {
            termination = Some(match non_finite_at {
                // The last attempts failed because f or the stages produced NaN/inf: say so.
                Some(index) => Termination::NonFinite { t, h, index },
                None => Termination::StepTooSmall { t, h },
            });
            break;
        }
        if let Some(h_max) = opts.h_max {
            h = h.min(h_max);
        }
        let remaining = (t_end - t).abs();
        let (h_step, last) = if h >= remaining { (remaining, true) } else { (h, false) };
        let t_b = if last { t_end } else { t + dir * h_step };
        let hs = t_b - t; // signed

        rk.stages(sys, t, &y, hs, true, &mut stats)?;
        rk.combine(&y, hs, &b_weights, &mut y_new);
        rk.increment(hs, &e_weights, &mut err);
        let norm = error_norm(&err, &y, &y_new, opts.rtol, opts.atol, block);

        let bad = first_non_finite(&y_new);
        if norm <= 1.0 && bad.is_none() {
            non_finite_at = None;
            stats.nsteps += 1;
            let k = rk.k();
            rec.step(t, hs, t_b, &y_new, |theta, out| dense::dopri5(theta, hs, &y, k, out));
            if let Some(d) = &mut dense_out {
                d.push_dopri5(t_b, &y, k);
            }
            t = t_b;
            std::mem::swap(&mut y, &mut y_new);
            let k = rk.k_mut();
            let s = k.len();
            k.swap(0, s - 1); // first same as last: k_7 = f(t_{n+1}, y_{n+1}) is the next k_1
            let mut factor = SAFETY * norm.max(1e-10).powf(-ALPHA) * err_prev.powf(BETA);
            factor = factor.clamp(MIN_FACTOR, MAX_FACTOR);
            if last_rejected {
                factor = factor.min(1.0);
            }
            err_prev = norm.max(1e-4);
            h = h_step * factor;
            last_rejected = false;
        } else {
            stats.nrejected += 1;
            non_finite_at = bad.or_else(|| (!norm.is_finite()).then(|| first_non_finite(&err).unwrap_or(0)));
            let factor = if norm.is_finite() {
                (SAFETY * norm.powf(-ALPHA)).max(MIN_FACTOR)
            } else {
                MIN_FACTOR
            };
            h = h_step * factor;
            last_rejected = true;
        }
    }
    let mut sol = rec.finish(stats, termination, "rk45");
    sol.dense = dense_out;
    Ok(sol)
}
