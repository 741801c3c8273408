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
