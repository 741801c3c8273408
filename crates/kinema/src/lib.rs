//! kinema: a particle-system simulation engine — numerical ODE integrators with their
//! stability analysis, and (in later modules) particles, forces and collisions.
//!
//! The engine is pure Rust; Python reaches it through the `kinema-py` crate only.
//! Units are SI (m, kg, s) and every number is `f64`.
#![warn(missing_docs)]

pub mod error;
pub mod ode;

pub use error::{CallbackError, Error};
