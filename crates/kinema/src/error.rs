//! Errors of the engine: values, never panics.

use std::fmt;

/// An error raised inside a user-supplied callback (a right-hand side, a Jacobian, a force).
///
/// The engine passes it through untouched so that the caller gets back exactly what its own
/// callback raised (the Python bindings turn it back into the original Python exception).
pub type CallbackError = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Every error the engine reports.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A parameter is out of its allowed range; the message names it, its value and the rule.
    #[error("{parameter} = {value} is invalid: {allowed}")]
    InvalidParameter {
        /// Name of the parameter as the user wrote it (`h`, `y0[2]`, `t_eval`).
        parameter: String,
        /// The offending value, formatted.
        value: String,
        /// What is allowed instead.
        allowed: String,
    },
    /// A method name that is not in the registry.
    #[error("unknown method '{name}'; valid methods are: {valid}")]
    UnknownMethod {
        /// The name that was asked for.
        name: String,
        /// The registered names, comma separated.
        valid: String,
    },
    /// A method that cannot integrate this kind of problem (e.g. `verlet` on a first-order ODE).
    #[error("method '{method}' cannot be used here: {reason}")]
    MethodNotApplicable {
        /// The method's name.
        method: String,
        /// Why, and what to use instead.
        reason: String,
    },
    /// A Butcher tableau whose coefficients are inconsistent.
    #[error("invalid Butcher tableau: {0}")]
    InvalidTableau(String),
    /// A world step produced a non-finite state (the time step is beyond the stability limit
    /// of the method for these forces, or a force returned NaN/inf). The world keeps the state
    /// from before the step.
    #[error(
        "the simulation diverged at step {step} (t = {time} s, dt = {dt} s){}: the state became non-finite; \
         reduce dt, or use a more stable method (implicit_euler for stiff springs)",
        particle.map(|p| format!(", first at particle {p}")).unwrap_or_default()
    )]
    Diverged {
        /// The step that failed (1 = the first step).
        step: u64,
        /// Time at the start of the failed step, s.
        time: f64,
        /// First particle whose position or velocity became non-finite, when known.
        particle: Option<usize>,
        /// The time step, s.
        dt: f64,
    },
    /// The user's callback failed; the inner error is its own.
    #[error("callback failed: {0}")]
    Callback(#[source] CallbackError),
}

impl Error {
    /// Shorthand for [`Error::InvalidParameter`].
    pub fn invalid(parameter: impl Into<String>, value: impl fmt::Display, allowed: impl Into<String>) -> Self {
        Error::InvalidParameter {
            parameter: parameter.into(),
            value: value.to_string(),
            allowed: allowed.into(),
        }
    }
}

impl From<CallbackError> for Error {
    fn from(e: CallbackError) -> Self {
        Error::Callback(e)
    }
}
