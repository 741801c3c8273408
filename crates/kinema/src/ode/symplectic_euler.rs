//! Symplectic (semi-implicit) Euler for x'' = a(t, x, v): kick, then drift.
//!
//! ```text
//!   v_{n+1} = v_n + h a(t_n, x_n, v_n)
//!   x_{n+1} = x_n + h v_{n+1}
//! ```
//!
//! First order, one acceleration per step. For forces that depend on x only it is
//! symplectic: it conserves a modified energy, so the energy error of an oscillator stays in
//! a band instead of drifting (forward Euler's grows, backward Euler's decays).

use super::stepper::{Stats, StepFailure, Stepper};
use super::system::{FirstOrderForm, SecondOrderSystem};
use crate::error::Error;

/// Symplectic Euler for second-order systems of n coordinates; state [x, v] per block.
pub struct SymplecticEuler {
    x: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
}

impl SymplecticEuler {
    /// The method for systems of `n` coordinates.
    pub fn new(n: usize) -> Self {
        Self {
            x: vec![0.0; n],
            v: vec![0.0; n],
            a: vec![0.0; n],
        }
    }
}

impl<'a> Stepper<dyn SecondOrderSystem + 'a> for SymplecticEuler {
    fn step(
        &mut self,
        sys: &mut (dyn SecondOrderSystem + 'a),
        t: f64,
        y: &[f64],
        h: f64,
        y_out: &mut [f64],
        stats: &mut Stats,
    ) -> Result<(), StepFailure> {
        let b = sys.block_len();
        FirstOrderForm::split(y, b, &mut self.x, &mut self.v);
        sys.accel(t, &self.x, &self.v, &mut self.a)?;
        stats.nfev += 1;
        for ((x, v), a) in self.x.iter_mut().zip(self.v.iter_mut()).zip(&self.a) {
            *v += h * a; // kick
            *x += h * *v; // drift with the new velocity
        }
        FirstOrderForm::join(&self.x, &self.v, b, y_out);
        Ok(())
    }

    fn derivative(
        &mut self,
        sys: &mut (dyn SecondOrderSystem + 'a),
        t: f64,
        y: &[f64],
        dydt: &mut [f64],
        stats: &mut Stats,
    ) -> Result<(), Error> {
        second_order_derivative(sys, t, y, dydt, stats, (&mut self.x, &mut self.v, &mut self.a))
    }
}

/// dy/dt = [v, a(t, x, v)] of a second-order system in first-order form.
pub(crate) fn second_order_derivative(
    sys: &mut dyn SecondOrderSystem,
    t: f64,
    y: &[f64],
    dydt: &mut [f64],
    stats: &mut Stats,
    (x, v, a): (&mut [f64], &mut [f64], &mut [f64]),
) -> Result<(), Error> {
    let b = sys.block_len();
    FirstOrderForm::split(y, b, x, v);
    sys.accel(t, x, v, a)?;
    stats.nfev += 1;
    FirstOrderForm::join(v, a, b, dydt);
    Ok(())
}
