//! Interrupting a long computation: the caller's check (the Python binding's Ctrl-C), asked
//! between the stages of a step and inside long ones. Shared by the world and the collision
//! stages, so that neither needs the other for it.

use crate::error::{CallbackError, Error};

/// Whether to stop a step: the caller's check (the Python bindings: Ctrl-C), asked at most
/// every [`Interrupt::EVERY`]; its error stops the step, which then leaves the world as it
/// was before it.
#[derive(Debug, Clone, Copy)]
pub struct Interrupt {
    check: Option<fn() -> Result<(), CallbackError>>,
    last: Option<std::time::Instant>,
}

impl Interrupt {
    /// How often the check runs at most.
    pub const EVERY: std::time::Duration = std::time::Duration::from_millis(10);

    /// No check.
    pub fn none() -> Self {
        Interrupt { check: None, last: None }
    }

    /// The caller's `check` (`None`: none), not asked yet.
    pub fn new(check: Option<fn() -> Result<(), CallbackError>>) -> Self {
        Interrupt { check, last: None }
    }

    /// Runs the check if it has not run for [`Interrupt::EVERY`].
    pub fn poll(&mut self) -> Result<(), Error> {
        let Some(check) = self.check else { return Ok(()) };
        let now = std::time::Instant::now();
        if self.last.is_some_and(|t| now.duration_since(t) < Self::EVERY) {
            return Ok(());
        }
        self.last = Some(now);
        check().map_err(Error::Callback)
    }
}
