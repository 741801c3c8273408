//! Drivers: integrate a system over an interval with a method, record the solution.
//!
//! The system (what), the method (how one step advances) and the step control (when) are
//! separate: [`solve`] picks the stepper from the registry, the fixed-step loop here or the
//! adaptive loop in `adaptive` decides the steps, and a `Recorder` ([`solution`](super::solution))
//! stores the output.

use super::adaptive::Adaptive;
use super::controller::StepSizeController;
use super::dense::{self, DenseOutput};
use super::explicit_rk::ExplicitRk;
use super::implicit_euler::ImplicitEuler;
use super::method::{Integrator, Method, MethodKind};
use super::solution::Recorder;
use super::stepper::{first_non_finite, Stats, StepFailure, Stepper, Termination};
use super::symplectic_euler::SymplecticEuler;
use super::system::{FirstOrderForm, OdeSystem, SecondOrderSystem};
use super::verlet::Verlet;
use crate::error::Error;

// Also reachable as `ode::solve::{Solution, SolveOptions, MAX_STEPS}`, where they were defined
// before `solution` existed.
pub use super::solution::{Solution, SolveOptions, MAX_STEPS};

/// The most values a dense Jacobian of implicit Euler may hold (n unknowns × the block
/// length: 2²⁷, 1 GiB); larger systems are refused with advice.
pub const MAX_DENSE_JACOBIAN: usize = 1 << 27;

/// Solves y' = f(t, y), y(t0) = y0 with a first-order method (every method but the
/// second-order-only `symplectic_euler` and `verlet`).
pub fn solve(sys: &mut dyn OdeSystem, y0: &[f64], integrator: &Integrator, opts: &SolveOptions) -> Result<Solution, Error> {
    validate(sys.dim(), sys.block_len(), y0, opts)?;
    match integrator {
        Integrator::Tableau(tab) => {
            let h = fixed_step(integrator, opts)?;
            run_fixed(
                &mut ExplicitRk::new(tab.clone(), y0.len()),
                sys,
                y0,
                h,
                opts,
                integrator.name(),
            )
        }
        Integrator::Named(m) => match m.kind() {
            MethodKind::ExplicitRk => {
                let h = fixed_step(integrator, opts)?;
                let tab = m.tableau().expect("explicit methods have tableaux");
                run_fixed(&mut ExplicitRk::new(tab, y0.len()), sys, y0, h, opts, m.name())
            }
            MethodKind::Implicit => {
                let h = fixed_step(integrator, opts)?;
                let (n, block) = (y0.len(), sys.block_len());
                if n.saturating_mul(block) > MAX_DENSE_JACOBIAN {
                    return Err(Error::invalid(
                        "y0",
                        format!("{n} unknowns in blocks of {block}"),
                        format!(
                            "implicit_euler's Newton solve keeps a dense Jacobian of n × block values, {:.3e} here ({:.1} GiB), \
                             at most {MAX_DENSE_JACOBIAN} (1 GiB): solve independent systems as a batch (vectorized=True, \
                             one row each), or use a World, whose implicit Euler is matrix-free",
                            (n as f64) * (block as f64),
                            (n as f64) * (block as f64) * 8.0 / (1u64 << 30) as f64
                        ),
                    ));
                }
                let stepper = &mut ImplicitEuler::new(n, block, opts.rtol, opts.atol);
                run_fixed(stepper, sys, y0, h, opts, m.name())
            }
            MethodKind::Adaptive => {
                let tab = m.tableau().expect("adaptive methods have tableaux");
                Adaptive::new(tab, StepSizeController::default())?.run(sys, y0, opts, m.name())
            }
            MethodKind::SecondOrder => Err(Error::MethodNotApplicable {
                method: m.name().into(),
                reason: "it integrates second-order systems x'' = a(t, x, v) only; use solve_second_order, \
                         or a first-order method (euler, midpoint, heun, rk4, implicit_euler, rk45)"
                    .into(),
            }),
        },
    }
}

/// Solves x'' = a(t, x, v), x(t0) = x0, v(t0) = v0 with any method: `symplectic_euler` and
/// `verlet` directly, the others through the first-order form y = [x, v].
///
/// The solution's states are [x, v] per block (without batching: the n positions, then the
/// n velocities).
pub fn solve_second_order(
    sys: &mut dyn SecondOrderSystem,
    x0: &[f64],
    v0: &[f64],
    integrator: &Integrator,
    opts: &SolveOptions,
) -> Result<Solution, Error> {
    let n = sys.dim();
    let b = sys.block_len();
    for (name, values) in [("x0", x0), ("v0", v0)] {
        if values.len() != n {
            return Err(Error::invalid(
                name,
                format!("an array of {} values", values.len()),
                format!("the system has {n} coordinates, so x0 and v0 need {n} values each"),
            ));
        }
    }
    if b == 0 || n % b != 0 {
        return Err(Error::invalid("block_len", b, format!("must divide the dimension {n}")));
    }
    for (name, values) in [("x0", x0), ("v0", v0)] {
        if let Some(i) = first_non_finite(values) {
            return Err(Error::invalid(
                format!("{name}[{i}]"),
                values[i],
                "initial values must be finite (no NaN or inf)",
            ));
        }
    }
    let mut y0 = vec![0.0; 2 * n];
    FirstOrderForm::join(x0, v0, b, &mut y0);
    match integrator {
        Integrator::Named(m @ (Method::SymplecticEuler | Method::Verlet)) => {
            validate(2 * n, 2 * b, &y0, opts)?;
            let h = fixed_step(integrator, opts)?;
            if *m == Method::Verlet {
                run_fixed(&mut Verlet::new(n), sys, &y0, h, opts, m.name())
            } else {
                run_fixed(&mut SymplecticEuler::new(n), sys, &y0, h, opts, m.name())
            }
        }
        _ => solve(&mut FirstOrderForm::new(sys), &y0, integrator, opts),
    }
}

fn fixed_step(integrator: &Integrator, opts: &SolveOptions) -> Result<f64, Error> {
    let h = opts.h.ok_or_else(|| {
        Error::invalid(
            "h",
            "None",
            format!(
                "method '{}' takes a fixed step: give a step size h > 0, or use method 'rk45' for an adaptive step",
                integrator.name()
            ),
        )
    })?;
    let (t0, t1) = opts.t_span;
    let steps = (t1 - t0).abs() / h;
    if steps > opts.max_steps as f64 || t0 + h == t0 || t1 + h == t1 {
        return Err(Error::invalid(
            "h",
            format!("{h:e}"),
            format!(
                "over t_span ({t0}, {t1}) it would take {steps:.3e} steps (max_steps = {}) or be below the resolution of \
                 t; choose a larger h, or raise max_steps",
                opts.max_steps
            ),
        ));
    }
    Ok(h)
}

fn validate(dim: usize, block: usize, y0: &[f64], opts: &SolveOptions) -> Result<(), Error> {
    validate_state(dim, block, y0)?;
    validate_steps(opts)?;
    validate_output(opts)
}

/// The initial state's checks: `dim` finite values, in blocks of `block`.
fn validate_state(dim: usize, block: usize, y0: &[f64]) -> Result<(), Error> {
    if y0.is_empty() {
        return Err(Error::invalid("y0", "[]", "the initial state needs at least one value"));
    }
    if y0.len() != dim {
        return Err(Error::invalid(
            "y0",
            format!("an array of {} values", y0.len()),
            format!("the system has {dim} unknowns"),
        ));
    }
    if block == 0 || dim % block != 0 {
        return Err(Error::invalid("block_len", block, format!("must divide the dimension {dim}")));
    }
    if let Some(i) = first_non_finite(y0) {
        return Err(Error::invalid(
            format!("y0[{i}]"),
            y0[i],
            "initial values must be finite (no NaN or inf)",
        ));
    }
    Ok(())
}

/// The span's and the steps' checks: finite ends, h, h_max, h_min and max_steps that can
/// cover the span.
fn validate_steps(opts: &SolveOptions) -> Result<(), Error> {
    let (t0, t1) = opts.t_span;
    if !t0.is_finite() || !t1.is_finite() {
        return Err(Error::invalid("t_span", format!("({t0}, {t1})"), "both ends must be finite"));
    }
    if let Some(h) = opts.h {
        if !(h.is_finite() && h > 0.0) {
            return Err(Error::invalid(
                "h",
                h,
                "the step size must be a finite number > 0 (the direction comes from t_span)",
            ));
        }
    }
    if let Some(h_max) = opts.h_max {
        if h_max.is_nan() || h_max <= 0.0 {
            return Err(Error::invalid(
                "h_max",
                h_max,
                "the largest step must be a number > 0 (or None for no limit)",
            ));
        }
    }
    if opts.max_steps == 0 {
        return Err(Error::invalid("max_steps", 0, "at least one step"));
    }
    if let Some(h_min) = opts.h_min {
        if !(h_min.is_finite() && h_min > 0.0) {
            return Err(Error::invalid(
                "h_min",
                h_min,
                "the smallest step must be a finite number > 0 (or None)",
            ));
        }
        if opts.h_max.is_some_and(|h_max| h_max < h_min) {
            return Err(Error::invalid(
                "h_min",
                h_min,
                format!("the smallest step must be at most h_max = {}", opts.h_max.unwrap_or(0.0)),
            ));
        }
    }
    if let Some(h_max) = opts.h_max {
        let steps = (t1 - t0).abs() / h_max;
        if steps > opts.max_steps as f64 {
            return Err(Error::invalid(
                "h_max",
                format!("{h_max:e}"),
                format!(
                    "over t_span ({t0}, {t1}) rk45 would take at least {steps:.3e} steps of at most h_max (max_steps = {}); \
                     choose a larger h_max, or raise max_steps",
                    opts.max_steps
                ),
            ));
        }
    }
    Ok(())
}

/// The tolerances' and the output times' checks.
fn validate_output(opts: &SolveOptions) -> Result<(), Error> {
    let (t0, t1) = opts.t_span;
    if !(opts.rtol.is_finite() && opts.rtol > 0.0) {
        return Err(Error::invalid("rtol", opts.rtol, "must be a finite number > 0"));
    }
    if !(opts.atol.is_finite() && opts.atol >= 0.0) {
        return Err(Error::invalid("atol", opts.atol, "must be a finite number >= 0"));
    }
    if let Some(te) = &opts.t_eval {
        let dir = if t1 >= t0 { 1.0 } else { -1.0 };
        let (lo, hi) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
        for (i, &t) in te.iter().enumerate() {
            if !(t >= lo && t <= hi) {
                return Err(Error::invalid(
                    format!("t_eval[{i}]"),
                    t,
                    format!("every t_eval point must lie within t_span [{lo}, {hi}]"),
                ));
            }
            if i > 0 && dir * (t - te[i - 1]) < 0.0 {
                return Err(Error::invalid(
                    format!("t_eval[{i}]"),
                    t,
                    "t_eval must be sorted in the direction of integration (ascending when t_span increases)",
                ));
            }
        }
    }
    Ok(())
}

/// The fixed-step loop: steps t_k = t0 + k h, the last one shortened to end at t_end.
fn run_fixed<S: ?Sized>(
    stepper: &mut dyn Stepper<S>,
    sys: &mut S,
    y0: &[f64],
    h: f64,
    opts: &SolveOptions,
    name: &str,
) -> Result<Solution, Error> {
    let (t0, t_end) = opts.t_span;
    let dir = if t_end >= t0 { 1.0 } else { -1.0 };
    let span = (t_end - t0).abs();
    // ceil with a little slack so that h = span/N gives N steps despite rounding of span/h.
    let nsteps = if span == 0.0 {
        0
    } else {
        ((span / h) * (1.0 - 1e-12)).ceil().max(1.0) as usize
    };
    let n = y0.len();
    let mut rec = Recorder::new(opts, t0, y0);
    rec.reserve(opts.t_eval.as_ref().map_or(nsteps + 1, |te| te.len()))?;
    let mut stats = Stats::default();
    let mut termination = None;
    let (mut y, mut y_next) = (y0.to_vec(), vec![0.0; n]);
    let (mut f_a, mut f_b) = (vec![0.0; n], vec![0.0; n]);
    // f at the start of the current step, when it is already known from the previous one.
    let mut f_a_known = false;
    // With dense_output: the grid (t, y, f) of every step boundary, for Hermite pieces.
    let mut grid = dense_grid(opts.dense_output, nsteps, n)?;
    for k in 0..nsteps {
        let t_a = t0 + dir * k as f64 * h;
        let t_b = if k + 1 == nsteps {
            t_end
        } else {
            t0 + dir * (k + 1) as f64 * h
        };
        let hk = t_b - t_a;
        // what a message calls the step: h as given, but the last step, which is cut to t_end
        let asked = if k + 1 == nsteps { hk } else { dir * h };
        match stepper.step(sys, t_a, &y, hk, &mut y_next, &mut stats) {
            Ok(()) => {}
            Err(StepFailure::Stop(t)) => {
                termination = Some(t.with_step_asked(hk, asked));
                break;
            }
            Err(StepFailure::Error(e)) => return Err(e),
        }
        if let Some(index) = first_non_finite(&y_next) {
            termination = Some(Termination::NonFinite { t: t_a, h: asked, index });
            break;
        }
        stats.nsteps += 1;
        if let Some((gt, gy, gf)) = &mut grid {
            gt.push(t_a);
            gy.extend_from_slice(&y);
            match stepper.derivative_at_start() {
                Some(f) => gf.extend_from_slice(f),
                None => {
                    stepper.derivative(sys, t_a, &y, &mut f_a, &mut stats)?;
                    f_a_known = true; // f_a = f(t_a, y_a), as the t_eval interpolation needs
                    gf.extend_from_slice(&f_a);
                }
            }
        }
        if rec.needs_dense(t_b) {
            if !f_a_known {
                stepper.derivative(sys, t_a, &y, &mut f_a, &mut stats)?;
            }
            stepper.derivative(sys, t_b, &y_next, &mut f_b, &mut stats)?;
            rec.step(t_a, hk, t_b, &y_next, |theta, out| {
                dense::hermite(theta, hk, &y, &y_next, &f_a, &f_b, out)
            });
            std::mem::swap(&mut f_a, &mut f_b);
            f_a_known = true;
        } else {
            // No output time lies inside this step (needs_dense is false), so the
            // interpolant is never asked for.
            rec.step(t_a, hk, t_b, &y_next, |_, _| {});
            f_a_known = false;
        }
        std::mem::swap(&mut y, &mut y_next);
    }
    let mut sol = rec.finish(stats, termination, name);
    if let Some((mut gt, mut gy, mut gf)) = grid {
        // Close the grid with the last state reached: the end, or where the solve stopped
        // (after gt.len() completed steps).
        let t_stop = t0 + dir * gt.len() as f64 * h;
        let t_stop = if gt.len() == nsteps { t_end } else { t_stop };
        gt.push(t_stop);
        gy.extend_from_slice(&y);
        stepper.derivative(sys, t_stop, &y, &mut f_b, &mut sol.stats)?;
        gf.extend_from_slice(&f_b);
        sol.dense = Some(DenseOutput::hermite(n, gt, gy, gf));
    }
    Ok(sol)
}

/// The fixed-step loop's dense output grid (t, y, f at every step boundary), reserved for
/// `nsteps` steps of `n` values, when `dense` asks for it.
#[allow(clippy::type_complexity)]
fn dense_grid(dense: bool, nsteps: usize, n: usize) -> Result<Option<(Vec<f64>, Vec<f64>, Vec<f64>)>, Error> {
    let mut grid: Option<(Vec<f64>, Vec<f64>, Vec<f64>)> = dense.then(|| (Vec::new(), Vec::new(), Vec::new()));
    if let Some((gt, gy, gf)) = &mut grid {
        let values = (nsteps + 1).saturating_mul(n);
        if gt.try_reserve(nsteps + 1).is_err() || gy.try_reserve(values).is_err() || gf.try_reserve(values).is_err() {
            return Err(Error::out_of_memory(
                format!("the dense output's {} steps of {n} values", nsteps + 1),
                values.saturating_mul(16),
            ));
        }
    }
    Ok(grid)
}
