//! Numerical solution of ordinary differential equations, and the stability of a time step.
//!
//! - [`system`]: what is integrated — [`OdeSystem`] (y' = f(t, y)) and
//!   [`SecondOrderSystem`] (x'' = a(t, x, v)).
//! - [`method`]: the registry of method names ([`Method`]) shared by every front end.
//! - [`tableau`]: explicit Runge–Kutta methods as checked Butcher tableaux; [`explicit_rk`]
//!   runs any of them. [`implicit_euler`], [`symplectic_euler`], [`verlet`]: the others.
//! - [`solve`](mod@solve): the fixed-step driver and the entry points; `adaptive`: the
//!   loop of rk45 (any embedded pair) with error control, `controller`: its step-size rule;
//!   [`solution`]: the options and the result both drivers share, and the output recorder;
//!   [`dense`]: output between steps.
//! - [`stability`]: R(z) on the test equation p' = λp, stable steps and intervals.

mod adaptive;
mod controller;
pub mod dense;
pub mod explicit_rk;
pub mod implicit_euler;
pub mod method;
pub mod solution;
pub mod solve;
pub mod stability;
pub mod stepper;
pub mod symplectic_euler;
pub mod system;
pub mod tableau;
pub mod verlet;

pub use dense::DenseOutput;
pub use method::{Integrator, Method, MethodKind};
pub use solution::{Solution, SolveOptions, MAX_STEPS};
pub use solve::{solve, solve_second_order, MAX_DENSE_JACOBIAN};
pub use stability::{
    amplification, imag_interval, max_step, oscillator_amplification, oscillator_max_step, real_interval, StabilityFunction,
};
pub use stepper::{Stats, Termination};
pub use system::{FirstOrderForm, FnSecondOrder, FnSystem, OdeSystem, SecondOrderSystem};
pub use tableau::ButcherTableau;
