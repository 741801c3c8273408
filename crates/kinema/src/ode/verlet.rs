//! Velocity Verlet for x'' = a(t, x, v): half kick, drift, half kick.
//!
//! ```text
//!   x_{n+1} = x_n + h v_n + h²/2 a_n
//!   a_{n+1} = a(t_{n+1}, x_{n+1}, v_n + h a_n)
//!   v_{n+1} = v_n + h/2 (a_n + a_{n+1})
//! ```
//!
//! Second order, time-reversible and symplectic for forces that depend on x only, with one
//! acceleration per step: a_{n+1} is the next step's a_n (first same as last).
//!
//! Velocity-dependent forces (drag, dashpots) need a velocity at t_{n+1} before v_{n+1} is
//! known. The half-kick velocity v_n + h/2 a_n (the usual choice in MD codes) is O(h) off
//! and would cost an order; the Euler predictor v_n + h a_n is O(h²) off, so a_{n+1} is
//! O(h²) off, which enters v_{n+1} times h/2: an O(h³) local error, and the method stays
//! second order. For position-only forces the predictor is never read and this is exactly
//! the textbook method.

use super::stepper::{Stats, StepFailure, Stepper};

/// Velocity Verlet's drift of one coordinate over a step h (s): the position
/// x + (h v + h²/2 a) and the Euler predictor v + h a that the forces at t + h see (m,
/// m/s; a in m/s²). The one place the formulas are written: the solver below, the world's
/// step and its fused contact pass all call it (and [`kick`]), so they agree to the bit.
#[inline(always)]
pub(crate) fn drift(x: f64, v: f64, a: f64, h: f64) -> (f64, f64) {
    (x + (h * v + 0.5 * h * h * a), v + h * a)
}

/// Velocity Verlet's closing kick of one coordinate: v + h/2 (a + a'), m/s, from the
/// velocity v at the step's start and the accelerations a at its start and a' at its end.
#[inline(always)]
pub(crate) fn kick(v: f64, a: f64, a_next: f64, h: f64) -> f64 {
    v + 0.5 * h * (a + a_next)
}
use super::symplectic_euler::second_order_derivative;
use super::system::{FirstOrderForm, SecondOrderSystem};
use crate::error::Error;

/// Velocity Verlet for second-order systems of n coordinates; state [x, v] per block.
pub struct Verlet {
    x: Vec<f64>,
    v: Vec<f64>,
    a: Vec<f64>,
    a_next: Vec<f64>,
    v_pred: Vec<f64>,
    /// (t, y) at which `a` was last evaluated, for first-same-as-last reuse.
    cached: Option<(f64, Vec<f64>)>,
}

impl Verlet {
    /// The method for systems of `n` coordinates.
    pub fn new(n: usize) -> Self {
        Self {
            x: vec![0.0; n],
            v: vec![0.0; n],
            a: vec![0.0; n],
            a_next: vec![0.0; n],
            v_pred: vec![0.0; n],
            cached: None,
        }
    }
}

impl<'a> Stepper<dyn SecondOrderSystem + 'a> for Verlet {
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
        // Same state and (to rounding of the time grid) the same time: a_n is already known.
        let reuse = matches!(&self.cached, Some((tc, yc)) if (tc - t).abs() <= 8.0 * f64::EPSILON * t.abs().max(h.abs()) && yc.as_slice() == y);
        if !reuse {
            sys.accel(t, &self.x, &self.v, &mut self.a)?;
            stats.nfev += 1;
        }
        for i in 0..self.x.len() {
            (self.x[i], self.v_pred[i]) = drift(self.x[i], self.v[i], self.a[i], h);
        }
        let t1 = t + h;
        sys.accel(t1, &self.x, &self.v_pred, &mut self.a_next)?;
        stats.nfev += 1;
        for i in 0..self.v.len() {
            self.v[i] = kick(self.v[i], self.a[i], self.a_next[i], h);
        }
        FirstOrderForm::join(&self.x, &self.v, b, y_out);
        std::mem::swap(&mut self.a, &mut self.a_next);
        match &mut self.cached {
            Some((tc, yc)) => {
                *tc = t1;
                yc.copy_from_slice(y_out);
            }
            None => self.cached = Some((t1, y_out.to_vec())),
        }
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
        let mut scratch = vec![0.0; self.a.len()];
        let (mut x, mut v) = (vec![0.0; self.a.len()], vec![0.0; self.a.len()]);
        second_order_derivative(sys, t, y, dydt, stats, (&mut x, &mut v, &mut scratch))
    }
}
