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
    /// Memory that cannot be allocated for what the user asked (the Python bindings raise
    /// `MemoryError`).
    #[error("{what} needs about {:.3} GiB of memory, which cannot be allocated", *bytes as f64 / (1u64 << 30) as f64)]
    OutOfMemory {
        /// What needed it, in the user's words.
        what: String,
        /// The bytes asked for.
        bytes: usize,
    },
    /// Particles placed where contacts cannot resolve them: a centre inside another particle
    /// (coincident ones among them) or inside a collider (`collide/placement.rs`).
    #[error(
        "positions: {deepest}, {count} where contacts cannot push the bodies apart (coincident centres give \
         no direction; a centre inside the other particle, with impulses, or inside a collider is pushed across \
         the body): place the particles further apart, each centre on the free side of every collider"
    )]
    Placement {
        /// The deepest one, in words (the particles, their distance and radii, or the collider).
        deepest: String,
        /// How many there are, in words: "the one placement", "the deepest of 12 placements"
        /// ("at least N" where the count stopped).
        count: String,
    },
    /// A method name that is not in the registry.
    #[error("unknown method '{name}';{hint} valid methods are: {valid}")]
    UnknownMethod {
        /// The name that was asked for.
        name: String,
        /// " did you mean 'rk4'?" where [`Method::suggestion`](crate::ode::Method::suggestion)
        /// finds the method meant, else empty.
        hint: String,
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
    /// A world step produced a non-finite state or runaway energy (the time step is beyond
    /// the stability limit of the method for these forces, or a force returned NaN/inf). The
    /// world keeps the state from before the step.
    #[error(
        "the simulation diverged at step {step} (t = {} s, dt = {} s){}: {reason}; {}",
        significant(*time),
        significant(*dt),
        particle.map(|p| format!(", first at particle {p}")).unwrap_or_default(),
        advice(*dt, *advised_dt, *verlet_only)
    )]
    Diverged {
        /// The step that failed (1 = the first step).
        step: u64,
        /// Time at the start of the failed step, s.
        time: f64,
        /// First offending particle: the first with a non-finite position or velocity, or the
        /// fastest one when the energy ran away.
        particle: Option<usize>,
        /// The time step, s.
        dt: f64,
        /// What went wrong.
        reason: Divergence,
        /// The stable-step advisor's largest stable step for the world's method at the state
        /// before the step, s, when it could be estimated.
        advised_dt: Option<f64>,
        /// Whether the world steps with velocity Verlet only (contacts with friction under a
        /// force model): the advice then names no other method.
        verlet_only: bool,
    },
    /// The user's callback failed; the inner error is its own.
    #[error("callback failed: {0}")]
    Callback(#[source] CallbackError),
}

/// Why a world step was refused.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Divergence {
    /// A position or velocity became NaN or ±inf.
    NonFinite,
    /// rk45 could not finish the step: its adaptive step fell below what the time resolves.
    StepTooSmall,
    /// rk45 took its cap of sub-steps ([`crate::limits::RK45_SUBSTEPS`], `World::RK45_SUBSTEPS`) inside one step.
    TooManySubsteps,
    /// A particle would travel more than `limit` times the scene's extent within the step:
    /// more impacts than continuous detection follows (`collide/impulse/impacts.rs`).
    TooFast {
        /// The distance it would travel in the rest of the step, m.
        travel: f64,
        /// The scene's extent (the particles' and the boxes' span, plus 2 r_max), m.
        extent: f64,
        /// The most extents a step may cross.
        limit: f64,
    },
    /// The mechanical energy grew far beyond anything the forces can supply.
    RunawayEnergy {
        /// Kinetic plus potential energy after the step, J.
        energy: f64,
        /// Energy at the reference state (the first step after the last change of particles,
        /// forces or state), J.
        reference: f64,
        /// The energy scale the growth is measured against, J.
        scale: f64,
    },
}

impl fmt::Display for Divergence {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Divergence::NonFinite => write!(f, "the state became non-finite"),
            Divergence::StepTooSmall => write!(f, "rk45's adaptive step became too small to finish it"),
            Divergence::TooManySubsteps => write!(
                f,
                "rk45 took {} adaptive sub-steps inside this one step and stopped",
                crate::limits::RK45_SUBSTEPS
            ),
            Divergence::TooFast { travel, extent, limit } => write!(
                f,
                "a particle would travel {travel:.3e} m within the step, over {limit} times the scene's extent \
                 ({extent:.3e} m): more impacts than continuous detection follows"
            ),
            Divergence::RunawayEnergy {
                energy,
                reference,
                scale,
            } => write!(
                f,
                "the energy ran away to {energy:.6e} J from {reference:.6e} J (scale {scale:.3e} J), \
                 which none of the forces can supply"
            ),
        }
    }
}

/// The advice of a divergence message: the advisor's step when known, and another method
/// only where the world accepts one (`verlet_only`: it does not).
fn advice(dt: f64, advised: Option<f64>, verlet_only: bool) -> String {
    let step = match advised {
        Some(h) if h.is_finite() && h < dt => {
            format!("the stable-step advisor gives dt <= {} s for this method; ", significant(h))
        }
        _ => String::new(),
    };
    if verlet_only {
        format!("{step}reduce dt (contacts with friction under a force model step with velocity Verlet only)")
    } else if step.is_empty() {
        "reduce dt, or use a more stable method (implicit_euler for stiff springs)".to_string()
    } else {
        format!("{step}reduce dt, or use implicit_euler for stiff springs")
    }
}

/// A number as a user writes it: six significant digits, trailing zeros dropped, in fixed
/// notation from 1e-4 up to 1e6 and in exponent notation beyond (Python's `:g`, and its
/// exponent's sign and two digits): 0.059, 0.001, 1e-05, 2.5e+07.
pub(crate) fn significant(x: f64) -> String {
    if !x.is_finite() || x == 0.0 {
        return format!("{x}");
    }
    // the exponent after rounding to six digits (9.999995 rounds up to 10)
    let sci = format!("{x:.5e}");
    let (mantissa, exp) = sci.split_once('e').expect("a formatted exponent");
    let exp: i32 = exp.parse().expect("an integer exponent");
    let trim = |t: &str| -> String {
        if t.contains('.') {
            t.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            t.to_string()
        }
    };
    if (-4..6).contains(&exp) {
        let decimals = (5 - exp).max(0) as usize;
        trim(&format!("{x:.decimals$}"))
    } else {
        let sign = if exp < 0 { '-' } else { '+' };
        format!("{}e{sign}{:02}", trim(mantissa), exp.abs())
    }
}

impl Error {
    /// Shorthand for [`Error::InvalidParameter`].
    pub fn invalid(parameter: impl Into<String>, value: impl fmt::Display, allowed: impl Into<String>) -> Self {
        Error::InvalidParameter {
            parameter: parameter.into(),
            value: compact(value.to_string()),
            allowed: allowed.into(),
        }
    }
}

impl Error {
    /// Memory for `what` (bytes) that cannot be allocated.
    pub fn out_of_memory(what: impl Into<String>, bytes: usize) -> Self {
        Error::OutOfMemory {
            what: what.into(),
            bytes,
        }
    }
}

/// A value for a message, short: a number that Rust prints with dozens of digits (1e112 as
/// 1 and 112 zeros, 1e-300 as 300 zeros and a 1) in scientific notation instead; integers
/// that fit 64 bits and everything that is not a number unchanged.
fn compact(text: String) -> String {
    let integer = !text.contains(['.', 'e', 'E']) && text.trim_start_matches('-').len() <= 20;
    match text.parse::<f64>() {
        Ok(v) if text.len() > 16 && !integer => format!("{v:e}"),
        _ => text,
    }
}

/// A callback's error; an engine error that passed through a callback's signature (the
/// contact force is a `Force`, whose errors are `CallbackError`s) comes back as
/// itself, so that the same bad input is the same error under either contact model.
impl From<CallbackError> for Error {
    fn from(e: CallbackError) -> Self {
        match e.downcast::<Error>() {
            Ok(engine) => *engine,
            Err(e) => Error::Callback(e),
        }
    }
}

#[cfg(test)]
mod compact_tests {
    use super::*;

    #[test]
    fn numbers_in_messages_are_short() {
        let text = |v: f64| Error::invalid("x", v, "finite").to_string();
        assert_eq!(text(1e112), "x = 1e112 is invalid: finite");
        assert_eq!(text(-1e-300), "x = -1e-300 is invalid: finite");
        assert_eq!(text(f64::MAX), "x = 1.7976931348623157e308 is invalid: finite");
        assert_eq!(text(0.25), "x = 0.25 is invalid: finite");
        assert_eq!(text(f64::NAN), "x = NaN is invalid: finite");
        assert_eq!(
            Error::invalid("n", u64::MAX, "small").to_string(),
            "n = 18446744073709551615 is invalid: small"
        );
        assert_eq!(
            Error::invalid("name", "a long name that is not a number", "short").to_string(),
            "name = a long name that is not a number is invalid: short"
        );
    }

    #[test]
    fn times_in_messages_read_as_a_user_writes_them() {
        // Python's `:g`: six significant digits, fixed from 1e-4 up to 1e6
        assert_eq!(significant(0.059000000000000004), "0.059");
        assert_eq!(significant(1e-3), "0.001");
        assert_eq!(significant(7.6712345e-5), "7.67123e-05");
        assert_eq!(significant(2.5e7), "2.5e+07");
        assert_eq!(significant(9.9999996), "10");
        assert_eq!(significant(123456.7), "123457");
        assert_eq!(significant(-0.5), "-0.5");
        assert_eq!(significant(0.0), "0");
        let diverged = |verlet_only| Error::Diverged {
            step: 60,
            time: 0.059000000000000004,
            particle: Some(3),
            dt: 1e-3,
            reason: Divergence::NonFinite,
            advised_dt: Some(7.67e-5),
            verlet_only,
        };
        let text = diverged(true).to_string();
        assert!(text.contains("(t = 0.059 s, dt = 0.001 s)"), "{text}");
        assert!(
            text.contains("dt <= 7.67e-05 s") && !text.contains("implicit_euler"),
            "{text}"
        );
        assert!(diverged(false).to_string().contains("implicit_euler"));
    }
}
