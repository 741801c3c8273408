//! The contract between the solve drivers and the methods: one fixed step at a time.

use std::fmt;

use crate::error::Error;

/// Work counters of a solve.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Right-hand-side (or acceleration) evaluations, finite-difference Jacobians included.
    pub nfev: usize,
    /// Evaluations of a user-supplied Jacobian.
    pub njev: usize,
    /// LU factorizations.
    pub nlu: usize,
    /// Accepted steps.
    pub nsteps: usize,
    /// Rejected steps (error control) and Newton failures that halved a step.
    pub nrejected: usize,
}

/// Why a solve ended before reaching the end of its interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Termination {
    /// Newton iterations of an implicit step did not converge, even after halving the step
    /// `halvings` times.
    NewtonFailed {
        /// Time at the start of the failing step (the last recorded state).
        t: f64,
        /// The step that was asked for.
        h: f64,
        /// The smallest step tried.
        h_min: f64,
        /// Time at the start of the sub-step that could not be solved.
        t_fail: f64,
        /// How many times the step was halved.
        halvings: u32,
    },
    /// The adaptive step size fell below what the floating-point time can resolve.
    StepTooSmall {
        /// Time where it happened.
        t: f64,
        /// The step size.
        h: f64,
    },
    /// rk45 made `max_steps` steps before the end of its interval.
    MaxSteps {
        /// Time reached.
        t: f64,
        /// The steps made.
        steps: usize,
    },
    /// A step produced NaN or ±inf (the method is unstable at this step, or f returned them).
    NonFinite {
        /// Time at the start of the step.
        t: f64,
        /// The step size.
        h: f64,
        /// Index of the first non-finite component.
        index: usize,
    },
}

impl Termination {
    /// The termination with the step the caller asked for, `asked`, where it names the step
    /// `taken`. A fixed-step solve takes steps between grid times t₀ + k h, so a step is
    /// t_{k+1} − t_k: h to rounding (0.09999999999999964 for h = 0.1 near t = 10), which a
    /// message should not echo back as if the user had given it.
    pub fn with_step_asked(self, taken: f64, asked: f64) -> Self {
        match self {
            Termination::NewtonFailed {
                t,
                h,
                h_min,
                t_fail,
                halvings,
            } if h == taken => Termination::NewtonFailed {
                t,
                h: asked,
                h_min,
                t_fail,
                halvings,
            },
            Termination::NonFinite { t, h, index } if h == taken => Termination::NonFinite { t, h: asked, index },
            other => other,
        }
    }
}

impl fmt::Display for Termination {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Termination::NewtonFailed {
                t,
                h,
                h_min,
                t_fail,
                halvings,
            } => write!(
                f,
                "the implicit step from t = {} with h = {} failed: Newton iterations did not converge at t = {} even with \
                 the step halved {halvings} times (down to h = {}); the solution may blow up there or f may not be smooth; \
                 a smaller h helps when the solution changes too much in one step, the exact Jacobian (jac=...) when \
                 finite differences of f are inaccurate",
                num(t),
                num(h),
                num(t_fail),
                num(h_min)
            ),
            Termination::StepTooSmall { t, h } => write!(
                f,
                "required step size {} at t = {} is below what the time variable can resolve; the problem may be stiff \
                 (try method='implicit_euler') or singular at this time",
                num(h),
                num(t)
            ),
            Termination::MaxSteps { t, steps } => write!(
                f,
                "rk45 stopped at t = {} after max_steps = {steps} steps; raise max_steps, or loosen rtol/atol (or raise \
                 h_max) if the steps are smaller than the problem needs",
                num(t)
            ),
            Termination::NonFinite { t, h, index } => write!(
                f,
                "the step from t = {} with h = {} produced a non-finite value in component {index}; the solution \
                 diverged (h beyond the method's stability limit, see kinema.stability.max_step) or f returned NaN/inf",
                num(t),
                num(h)
            ),
        }
    }
}

/// A number for a message: plain where that reads well, scientific otherwise.
fn num(v: f64) -> String {
    if v == 0.0 || (1e-3..1e5).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// A step that did not complete: either a hard error (bad callback) or a stop.
#[derive(Debug)]
pub enum StepFailure {
    /// Propagate to the caller as an error.
    Error(Error),
    /// End the solve here, keep what was computed.
    Stop(Termination),
}

impl From<Error> for StepFailure {
    fn from(e: Error) -> Self {
        StepFailure::Error(e)
    }
}

impl From<crate::error::CallbackError> for StepFailure {
    fn from(e: crate::error::CallbackError) -> Self {
        StepFailure::Error(Error::from(e)) // (an engine error inside comes back as itself)
    }
}

/// A fixed-step method: its coefficients, work buffers and caches, apart from the system it
/// integrates (`S`: an [`OdeSystem`](super::OdeSystem) or a
/// [`SecondOrderSystem`](super::SecondOrderSystem)), which each call receives. So an owner of
/// a system (a world of particles) can keep a stepper across steps, and a method's cache
/// (Verlet's last acceleration) survives between them.
///
/// The state is flat: y for first-order systems, [x, v] per block for second-order ones.
pub trait Stepper<S: ?Sized> {
    /// Advances y(t) by h into `y_out`.
    fn step(&mut self, sys: &mut S, t: f64, y: &[f64], h: f64, y_out: &mut [f64], stats: &mut Stats) -> Result<(), StepFailure>;

    /// f(t_a, y_a) at the start of the last step taken, when the method computed it anyway
    /// (the first stage of an explicit Runge–Kutta method); saves an evaluation for dense
    /// output.
    fn derivative_at_start(&self) -> Option<&[f64]> {
        None
    }

    /// dy/dt at (t, y), for Hermite interpolation between steps.
    fn derivative(&mut self, sys: &mut S, t: f64, y: &[f64], dydt: &mut [f64], stats: &mut Stats) -> Result<(), Error>;
}

/// Index of the first non-finite value, if any.
pub fn first_non_finite(y: &[f64]) -> Option<usize> {
    y.iter().position(|v| !v.is_finite())
}
