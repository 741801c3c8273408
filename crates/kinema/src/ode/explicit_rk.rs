//! One stepper for every explicit Runge–Kutta method: the tableau is the method.

use super::stepper::{Stats, StepFailure, Stepper};
use super::system::OdeSystem;
use super::tableau::ButcherTableau;
use crate::error::Error;

/// Runs a [`ButcherTableau`] on an [`OdeSystem`] of a given dimension.
pub struct ExplicitRk {
    tab: ButcherTableau,
    /// Stage derivatives k_1..k_s (each of length n).
    k: Vec<Vec<f64>>,
    ytmp: Vec<f64>,
}

impl ExplicitRk {
    /// The method `tab` for systems of `n` unknowns.
    pub fn new(tab: ButcherTableau, n: usize) -> Self {
        let s = tab.stages();
        Self {
            tab,
            k: vec![vec![0.0; n]; s],
            ytmp: vec![0.0; n],
        }
    }

    /// The tableau being run.
    pub fn tableau(&self) -> &ButcherTableau {
        &self.tab
    }

    /// Stage derivatives of the last call to [`Self::stages`].
    pub fn k(&self) -> &[Vec<f64>] {
        &self.k
    }

    /// Mutable stage storage (to hand over an FSAL stage).
    pub fn k_mut(&mut self) -> &mut [Vec<f64>] {
        &mut self.k
    }

    /// k_1 = f(t, y) alone (to start a first-same-as-last sequence of steps).
    pub fn first_stage(&mut self, sys: &mut dyn OdeSystem, t: f64, y: &[f64], stats: &mut Stats) -> Result<(), Error> {
        stats.nfev += 1;
        Ok(sys.rhs(t, y, &mut self.k[0])?)
    }

    /// Computes the stages k_i = f(t + c_i h, y + h Σ_{j<i} a_ij k_j).
    /// With `first_known`, k_1 already holds f(t, y) (first same as last) and is not recomputed.
    pub fn stages(
        &mut self,
        sys: &mut dyn OdeSystem,
        t: f64,
        y: &[f64],
        h: f64,
        first_known: bool,
        stats: &mut Stats,
    ) -> Result<(), Error> {
        for i in 0..self.tab.stages() {
            if i == 0 && first_known {
                continue;
            }
            let row = self.tab.a_row(i);
            let (done, rest) = self.k.split_at_mut(i);
            let ki = &mut rest[0];
            if row[..i].iter().all(|&a| a == 0.0) {
                sys.rhs(t + self.tab.c()[i] * h, y, ki)?;
            } else {
                self.ytmp.copy_from_slice(y);
                for (j, kj) in done.iter().enumerate() {
                    let a = row[j];
                    if a != 0.0 {
                        let ha = h * a;
                        for (yt, kv) in self.ytmp.iter_mut().zip(kj) {
                            *yt += ha * kv;
                        }
                    }
                }
                sys.rhs(t + self.tab.c()[i] * h, &self.ytmp, ki)?;
            }
            stats.nfev += 1;
        }
        Ok(())
    }

    /// y_out = y + h Σ w_i k_i for weights w (b for the solution, b − b̂ for the error).
    pub fn combine(&self, y: &[f64], h: f64, w: &[f64], y_out: &mut [f64]) {
        y_out.copy_from_slice(y);
        for (wi, ki) in w.iter().zip(&self.k) {
            if *wi != 0.0 {
                let hw = h * wi;
                for (yo, kv) in y_out.iter_mut().zip(ki) {
                    *yo += hw * kv;
                }
            }
        }
    }

    /// out = h Σ w_i k_i (the error estimate, for weights b − b̂).
    pub fn increment(&self, h: f64, w: &[f64], out: &mut [f64]) {
        out.fill(0.0);
        for (wi, ki) in w.iter().zip(&self.k) {
            if *wi != 0.0 {
                let hw = h * wi;
                for (o, kv) in out.iter_mut().zip(ki) {
                    *o += hw * kv;
                }
            }
        }
    }
}

impl<'a> Stepper<dyn OdeSystem + 'a> for ExplicitRk {
    fn step(
        &mut self,
        sys: &mut (dyn OdeSystem + 'a),
        t: f64,
        y: &[f64],
        h: f64,
        y_out: &mut [f64],
        stats: &mut Stats,
    ) -> Result<(), StepFailure> {
        self.stages(sys, t, y, h, false, stats)?;
        self.combine(y, h, self.tab.b(), y_out);
        Ok(())
    }

    fn derivative_at_start(&self) -> Option<&[f64]> {
        // A is strictly lower triangular and c_1 = Σ_j a_1j = 0, so k_1 = f(t_a, y_a).
        Some(&self.k[0])
    }

    fn derivative(
        &mut self,
        sys: &mut (dyn OdeSystem + 'a),
        t: f64,
        y: &[f64],
        dydt: &mut [f64],
        stats: &mut Stats,
    ) -> Result<(), Error> {
        stats.nfev += 1;
        Ok(sys.rhs(t, y, dydt)?)
    }
}
