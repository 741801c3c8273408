//! kinema: a particle-system simulation engine — numerical ODE integrators with their
//! stability analysis, particles, the forces on them and their collisions.
//!
//! The engine is pure Rust; Python reaches it through the `kinema-py` crate only.
//! Units are SI (m, kg, s) and every number is `f64`.
#![warn(missing_docs)]

pub mod collide;
pub mod diagnostics;
pub mod error;
pub mod forces;
pub mod interrupt;
pub mod limits;
pub mod ode;
pub mod particles;
pub mod render;
pub mod simd;
pub(crate) mod vec3;
pub mod world;

pub use error::{CallbackError, Divergence, Error};
pub use particles::Particles;
pub use world::{Interrupt, World, WorldParams};
