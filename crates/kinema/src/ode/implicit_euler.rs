//! Backward (implicit) Euler: y_{n+1} = y_n + h f(t_{n+1}, y_{n+1}), solved by Newton.
//!
//! The step is the root of G(y) = y − y_n − h f(t_{n+1}, y). Newton's iteration
//!
//! ```text
//!   (I − h J) Δ = −G(y_k),   y_{k+1} = y_k + Δ,   J = ∂f/∂y
//! ```
//!
//! starts from y_n and keeps J (and the LU factors of I − hJ) fixed over the iterations
//! (simplified Newton) while they contract fast. J comes from the system when it provides
//! one, else from forward differences of f. When the contraction is slow
//! (θ > [`SLOW_CONTRACTION`]), J is re-evaluated at the current iterate (full Newton); when
//! even that does not contract, or after [`MAX_NEWTON_ITERATIONS`], the step is split into two
//! halves (recursively, up to [`MAX_HALVINGS`] times) and the solve stops with a clear reason
//! only after that.
//! Stability: R(z) = 1/(1 − z), |R| ≤ 1 on the whole left half-plane (A-stable) and R → 0 as
//! z → −∞ (L-stable), so stiff components are damped at any step.

use faer::linalg::solvers::{PartialPivLu, Solve};
use faer::Mat;

use super::stepper::{first_non_finite, Stats, StepFailure, Stepper, Termination};
use super::system::OdeSystem;
use crate::error::Error;

/// Newton iterations allowed per attempt.
pub const MAX_NEWTON_ITERATIONS: usize = 20;
/// A contraction rate ‖Δ_k‖/‖Δ_{k−1}‖ above this re-evaluates the Jacobian at the iterate.
pub const SLOW_CONTRACTION: f64 = 0.1;
/// How many times a step whose Newton iteration fails may be halved before the solve stops.
pub const MAX_HALVINGS: u32 = 10;
/// Newton converges when the weighted max-norm of the update, with weights
/// 1/(atol + rtol |y|), is at most this.
pub const NEWTON_TOL: f64 = 1e-3;

/// Backward Euler for systems of a given dimension and block length.
pub struct ImplicitEuler {
    rtol: f64,
    atol: f64,
    block: usize,
    /// J's diagonal blocks, each block × block row-major.
    jac: Vec<f64>,
    lu: Vec<PartialPivLu<f64>>,
    f: Vec<f64>,
    f_pert: Vec<f64>,
    y_pert: Vec<f64>,
    delta: Mat<f64>,
}

/// One attempted step: from (t, y) by h, for the blocks marked in `active` (the others ride
/// along: f is evaluated for the whole state at once, and their values are discarded).
#[derive(Debug, Clone, Copy)]
struct Attempt<'a> {
    t: f64,
    y: &'a [f64],
    h: f64,
    active: &'a [bool],
}

/// Where a block's Newton iteration stands.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Block {
    Iterating,
    Converged,
    /// Not converged (diverging, singular, or out of iterations).
    Failed,
    /// f was NaN or ±inf at this component.
    NonFinite(usize),
}

impl ImplicitEuler {
    /// Backward Euler for systems of `n` unknowns in independent blocks of `block` (n for
    /// one system); `rtol`, `atol` set the Newton tolerance.
    pub fn new(n: usize, block: usize, rtol: f64, atol: f64) -> Self {
        Self {
            rtol,
            atol,
            block,
            jac: vec![0.0; n * block],
            lu: Vec::new(),
            f: vec![0.0; n],
            f_pert: vec![0.0; n],
            y_pert: vec![0.0; n],
            delta: Mat::zeros(block, n / block.max(1)),
        }
    }

    /// J at (t, y) into `self.jac`; `self.f` must hold f(t, y) (used by finite differences).
    fn jacobian(&mut self, sys: &mut dyn OdeSystem, t: f64, y: &[f64], stats: &mut Stats) -> Result<(), Error> {
        let b = self.block;
        if sys.has_jacobian() {
            sys.jacobian(t, y, &mut self.jac)?;
            stats.njev += 1;
            return Ok(());
        }
        // Forward differences, column j of every block at once (blocks do not couple):
        // J_ij ≈ (f_i(y + δ e_j) − f_i(y)) / δ with δ = √ε max(|y_j|, 1).
        let nblocks = y.len() / b;
        for j in 0..b {
            self.y_pert.copy_from_slice(y);
            for m in 0..nblocks {
                let yj = y[m * b + j];
                let delta = f64::EPSILON.sqrt() * yj.abs().max(1.0);
                // exactly representable δ: (y + δ) − y
                self.y_pert[m * b + j] = yj + delta;
            }
            sys.rhs(t, &self.y_pert, &mut self.f_pert)?;
            stats.nfev += 1;
            for m in 0..nblocks {
                let delta = self.y_pert[m * b + j] - y[m * b + j];
                for i in 0..b {
                    let r = m * b + i;
                    self.jac[m * b * b + i * b + j] = (self.f_pert[r] - self.f[r]) / delta;
                }
            }
        }
        Ok(())
    }

    /// LU factors of I − hJ, one per block.
    fn factor(&mut self, h: f64, stats: &mut Stats) {
        let b = self.block;
        self.lu = self
            .jac
            .chunks_exact(b * b)
            .map(|jb| {
                let m = Mat::<f64>::from_fn(b, b, |i, j| if i == j { 1.0 } else { 0.0 } - h * jb[i * b + j]);
                m.partial_piv_lu()
            })
            .collect();
        stats.nlu += self.lu.len();
    }

    /// One attempt at y_out = y + h f(t + h, y_out), block by block.
    ///
    /// Blocks are independent systems (a batch), so each converges or fails on its own;
    /// only the blocks marked in `active` are judged (the others ride along, since f is
    /// evaluated for the whole state at once, and their values are discarded by the caller).
    fn newton(
        &mut self,
        sys: &mut dyn OdeSystem,
        attempt: Attempt<'_>,
        y_out: &mut [f64],
        stats: &mut Stats,
    ) -> Result<Vec<Block>, Error> {
        let Attempt { t, y, h, active } = attempt;
        let b = self.block;
        let t1 = t + h;
        y_out.copy_from_slice(y);
        let mut status: Vec<Block> = active
            .iter()
            .map(|&a| if a { Block::Iterating } else { Block::Converged })
            .collect();
        let mut prev_norm = vec![f64::INFINITY; active.len()];
        // Whether a block's last measured contraction rate was ≥ 1 (it then gets one more
        // chance with a Jacobian evaluated at its current iterate).
        let mut diverged = vec![false; active.len()];
        for iter in 0..MAX_NEWTON_ITERATIONS {
            sys.rhs(t1, y_out, &mut self.f)?;
            stats.nfev += 1;
            for (m, st) in status.iter_mut().enumerate() {
                if *st == Block::Iterating {
                    if let Some(i) = first_non_finite(&self.f[m * b..(m + 1) * b]) {
                        *st = Block::NonFinite(m * b + i);
                    }
                }
            }
            if iter == 0 {
                self.jacobian(sys, t1, y_out, stats)?;
                self.factor(h, stats);
            }
            let mut slow = false;
            for (m, lu) in self.lu.iter().enumerate() {
                if status[m] != Block::Iterating {
                    continue;
                }
                // Δ = −(I − hJ)⁻¹ G(y_k), G = y_k − y_n − h f(t_{n+1}, y_k)
                for i in 0..b {
                    let r = m * b + i;
                    self.delta[(i, m)] = -(y_out[r] - y[r] - h * self.f[r]);
                }
                lu.solve_in_place(self.delta.as_mut().subcols_mut(m, 1));
                let mut norm = 0.0_f64;
                for i in 0..b {
                    let r = m * b + i;
                    let d = self.delta[(i, m)];
                    y_out[r] += d;
                    let w = d.abs() / (self.atol + self.rtol * y_out[r].abs());
                    // NaN-propagating max: a NaN update (singular I − hJ, overflow) must fail.
                    norm = if w.is_nan() || w > norm { w } else { norm };
                }
                // Contraction rate θ = ‖Δ_k‖ / ‖Δ_{k−1}‖ (only meaningful from the second
                // iteration on).
                let theta = (prev_norm[m].is_finite()).then(|| norm / prev_norm[m]);
                if !norm.is_finite() {
                    status[m] = Block::Failed;
                } else if norm <= NEWTON_TOL {
                    status[m] = Block::Converged;
                } else if let Some(theta) = theta {
                    if theta >= 1.0 && diverged[m] {
                        // Not contracting even after the Jacobian was re-evaluated at the
                        // iterate: the step is too large for this nonlinearity.
                        status[m] = Block::Failed;
                    } else {
                        diverged[m] = theta >= 1.0;
                        slow |= theta > SLOW_CONTRACTION;
                    }
                }
                prev_norm[m] = norm;
            }
            if !status.contains(&Block::Iterating) {
                return Ok(status);
            }
            // Simplified Newton converges linearly at the rate θ, which is slow when J has
            // changed much since the start of the step (strongly nonlinear f): re-evaluate J
            // at the current iterate, i.e. switch to full Newton (quadratic near the root).
            if slow {
                // θ compares updates made with the same Jacobian only.
                prev_norm.fill(f64::INFINITY);
                sys.rhs(t1, y_out, &mut self.f)?;
                stats.nfev += 1;
                let yk = y_out.to_vec();
                self.jacobian(sys, t1, &yk, stats)?;
                self.factor(h, stats);
            }
        }
        for st in status.iter_mut() {
            if *st == Block::Iterating {
                *st = Block::Failed;
            }
        }
        Ok(status)
    }

    /// A step of the blocks in `attempt.active`; a block whose Newton iteration fails is
    /// redone as two half steps (the others keep their full-step result, so a batch member's
    /// answer does not depend on the other members). `depth`: halvings so far.
    fn step_with_halving(
        &mut self,
        sys: &mut dyn OdeSystem,
        attempt: Attempt<'_>,
        y_out: &mut [f64],
        stats: &mut Stats,
        depth: u32,
    ) -> Result<(), StepFailure> {
        let Attempt { t, y, h, .. } = attempt;
        let b = self.block;
        let status = self.newton(sys, attempt, y_out, stats)?;
        let failing: Vec<bool> = status.iter().map(|s| *s != Block::Converged).collect();
        let Some(first) = failing.iter().position(|&f| f) else {
            return Ok(());
        };
        if depth == MAX_HALVINGS {
            return Err(StepFailure::Stop(match status[first] {
                Block::NonFinite(index) => Termination::NonFinite { t, h, index },
                _ => Termination::NewtonFailed {
                    t,
                    h,
                    h_min: h,
                    t_fail: t,
                    halvings: depth,
                },
            }));
        }
        stats.nrejected += 1;
        let mut mid = y.to_vec();
        let first_half = Attempt {
            t,
            y,
            h: 0.5 * h,
            active: &failing,
        };
        self.step_with_halving(sys, first_half, &mut mid, stats, depth + 1)?;
        let mut end = mid.clone();
        let second_half = Attempt {
            t: t + 0.5 * h,
            y: &mid,
            h: 0.5 * h,
            active: &failing,
        };
        self.step_with_halving(sys, second_half, &mut end, stats, depth + 1)?;
        for (m, &f) in failing.iter().enumerate() {
            if f {
                y_out[m * b..(m + 1) * b].copy_from_slice(&end[m * b..(m + 1) * b]);
            }
        }
        Ok(())
    }
}

impl<'a> Stepper<dyn OdeSystem + 'a> for ImplicitEuler {
    fn step(
        &mut self,
        sys: &mut (dyn OdeSystem + 'a),
        t: f64,
        y: &[f64],
        h: f64,
        y_out: &mut [f64],
        stats: &mut Stats,
    ) -> Result<(), StepFailure> {
        let active = vec![true; y.len() / self.block];
        match self.step_with_halving(
            sys,
            Attempt {
                t,
                y,
                h,
                active: &active,
            },
            y_out,
            stats,
            0,
        ) {
            // Report the step the driver asked for; the sub-step that failed is in t_fail/h_min.
            Err(StepFailure::Stop(Termination::NewtonFailed {
                h_min, t_fail, halvings, ..
            })) => Err(StepFailure::Stop(Termination::NewtonFailed {
                t,
                h,
                h_min,
                t_fail,
                halvings,
            })),
            Err(StepFailure::Stop(Termination::NonFinite { index, .. })) => {
                Err(StepFailure::Stop(Termination::NonFinite { t, h, index }))
            }
            other => other,
        }
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
