//! What a solve is asked and what it returns, shared by the fixed-step driver (`solve`) and
//! the adaptive one (`adaptive`): [`SolveOptions`], [`Solution`], and the `Recorder` that
//! stores the output (every step, or the `t_eval` points) as a driver advances.
//!
//! Both drivers depend on this module and neither on the other's internals, so `adaptive`
//! does not import `solve` (which calls it).

use super::dense::DenseOutput;
use super::stepper::{Stats, Termination};
use crate::error::Error;

/// Options of a solve. Times in the problem's unit (s by default).
#[derive(Debug, Clone, PartialEq)]
pub struct SolveOptions {
    /// (t0, t_end); t_end < t0 integrates backwards.
    pub t_span: (f64, f64),
    /// Step size > 0. Required by fixed-step methods (the last step is shortened to end at
    /// t_end); for `rk45` the first step (chosen automatically when `None`).
    pub h: Option<f64>,
    /// Largest step rk45 may take (`None`: no limit), e.g. to resolve a short forcing pulse
    /// the error estimate would step over. Fixed-step methods ignore it.
    pub h_max: Option<f64>,
    /// Relative tolerance (rk45 error control; implicit Euler's Newton tolerance). Default 1e-6.
    pub rtol: f64,
    /// Absolute tolerance, same roles. Default 1e-9.
    pub atol: f64,
    /// Keep the interpolant of every step, so that the solution can be evaluated at any time
    /// afterwards ([`Solution::dense`]). Costs memory, and for fixed-step methods one
    /// evaluation of f per step where the method does not already compute f at the grid
    /// points (every explicit Runge–Kutta method does). Default false.
    pub dense_output: bool,
    /// Times at which to report the solution, inside t_span and ordered in the direction of
    /// integration. `None`: every step. Points between steps are interpolated (Hermite cubic;
    /// rk45: its own fourth-order dense output).
    pub t_eval: Option<Vec<f64>>,
    /// Most steps of a solve (default [`MAX_STEPS`]): a fixed step that needs more is refused
    /// up front, as is an `h_max` with which rk45 would; rk45 stops there otherwise (the
    /// solution so far, with its reason).
    pub max_steps: usize,
    /// Smallest step rk45 may take (`None`: ten units in the last place of t); below it the
    /// solve stops ("step too small").
    pub h_min: Option<f64>,
}

/// The default [`SolveOptions::max_steps`].
pub const MAX_STEPS: usize = 10_000_000;

impl Default for SolveOptions {
    fn default() -> Self {
        Self {
            t_span: (0.0, 1.0),
            h: None,
            h_max: None,
            dense_output: false,
            rtol: 1e-6,
            atol: 1e-9,
            t_eval: None,
            max_steps: MAX_STEPS,
            h_min: None,
        }
    }
}

/// The result of a solve.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// Times of the recorded states.
    pub t: Vec<f64>,
    /// States, `t.len() × dim` row-major.
    pub y: Vec<f64>,
    /// Number of unknowns per state.
    pub dim: usize,
    /// Work counters.
    pub stats: Stats,
    /// Why the solve ended early; `None` when it reached t_end.
    pub termination: Option<Termination>,
    /// Name of the method used.
    pub method: String,
    /// The continuous solution, when `dense_output` was asked for.
    pub dense: Option<DenseOutput>,
}

impl Solution {
    /// Whether t_end was reached.
    pub fn success(&self) -> bool {
        self.termination.is_none()
    }
    /// A one-line account of how the solve ended.
    pub fn message(&self) -> String {
        match &self.termination {
            None => "the solver reached the end of the interval".to_string(),
            Some(t) => t.to_string(),
        }
    }
    /// The i-th recorded state.
    pub fn state(&self, i: usize) -> &[f64] {
        &self.y[i * self.dim..(i + 1) * self.dim]
    }
    /// The last recorded state.
    pub fn last(&self) -> &[f64] {
        self.state(self.t.len() - 1)
    }
}

/// Stores the output: every step, or the `t_eval` points (interpolated inside steps).
pub(crate) struct Recorder<'a> {
    t_eval: Option<&'a [f64]>,
    next: usize,
    dir: f64,
    dim: usize,
    pub(crate) t: Vec<f64>,
    pub(crate) y: Vec<f64>,
    buf: Vec<f64>,
}

impl<'a> Recorder<'a> {
    pub(crate) fn new(opts: &'a SolveOptions, t0: f64, y0: &[f64]) -> Self {
        let (a, b) = opts.t_span;
        let mut rec = Self {
            t_eval: opts.t_eval.as_deref(),
            next: 0,
            dir: if b >= a { 1.0 } else { -1.0 },
            dim: y0.len(),
            t: Vec::new(),
            y: Vec::new(),
            buf: vec![0.0; y0.len()],
        };
        match rec.t_eval {
            None => rec.push(t0, y0),
            Some(te) => {
                while rec.next < te.len() && te[rec.next] == t0 {
                    rec.push(t0, y0);
                    rec.next += 1;
                }
            }
        }
        rec
    }

    /// Room for `rows` states in all (a fixed step knows them up front): a size the machine
    /// cannot hold is [`Error::OutOfMemory`] before the solve starts, not an abort in it.
    pub(crate) fn reserve(&mut self, rows: usize) -> Result<(), Error> {
        let more = rows.saturating_sub(self.t.len());
        let values = more.saturating_mul(self.dim);
        if self.t.try_reserve(more).is_err() || self.y.try_reserve(values).is_err() {
            return Err(Error::out_of_memory(
                format!("the solution's {rows} states of {} values", self.dim),
                rows.saturating_mul(self.dim + 1).saturating_mul(8),
            ));
        }
        Ok(())
    }

    fn push(&mut self, t: f64, y: &[f64]) {
        self.t.push(t);
        self.y.extend_from_slice(y);
    }

    /// Whether some output time falls strictly inside the step ending at `t_b` (so the
    /// step's dense output is needed).
    pub(crate) fn needs_dense(&self, t_b: f64) -> bool {
        match self.t_eval {
            Some(te) => self.next < te.len() && self.dir * (te[self.next] - t_b) < 0.0,
            None => false,
        }
    }

    /// Records the step [t_a, t_b = t_a + h]; `dense(θ, out)` evaluates the state at
    /// t_a + θh for output times inside the step.
    pub(crate) fn step(&mut self, t_a: f64, h: f64, t_b: f64, y_b: &[f64], mut dense: impl FnMut(f64, &mut [f64])) {
        let Some(te) = self.t_eval else {
            self.push(t_b, y_b);
            return;
        };
        while self.next < te.len() && self.dir * (te[self.next] - t_b) <= 0.0 {
            let t = te[self.next];
            if t == t_b {
                self.push(t, y_b);
            } else {
                let mut buf = std::mem::take(&mut self.buf);
                dense((t - t_a) / h, &mut buf);
                self.push(t, &buf);
                self.buf = buf;
            }
            self.next += 1;
        }
    }

    pub(crate) fn finish(self, stats: Stats, termination: Option<Termination>, method: &str) -> Solution {
        Solution {
            t: self.t,
            y: self.y,
            dim: self.dim,
            stats,
            termination,
            method: method.to_string(),
            dense: None,
        }
    }
}
