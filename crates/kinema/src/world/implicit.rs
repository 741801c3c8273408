//! Implicit Euler for particle systems: Baraff & Witkin's linearised step, solved by
//! preconditioned conjugate gradients without forming a matrix.

use super::dynamics::{free_components, Dynamics, ForceJacobian};
use crate::error::CallbackError;
use crate::forces::State;
use crate::ode::stepper::Stats;
use crate::vec3::dot_slices as dot;

/// Relative residual ‖b − A Δv‖ ≤ tol ‖b‖ at which conjugate gradients stop.
pub const CG_TOLERANCE: f64 = 1e-6;
/// CG iterations per step at most: this many, or the number of state components (3N) if
/// larger. In exact arithmetic CG needs at most the number of free components, so the cap
/// only matters when rounding slows it.
pub const CG_MAX_ITERATIONS: usize = 2000;

/// One backward-Euler step of M x'' = F(t, x, v), linearised as in Baraff & Witkin (1998),
/// "Large steps in cloth simulation", eq. (15)–(16).
///
/// Backward Euler asks for Δv with
///
/// ```text
///   Δx = h (v₀ + Δv),      M Δv = h F(x₀ + Δx, v₀ + Δv).
/// ```
///
/// One Newton step from (x₀, v₀), F(x₀ + Δx, v₀ + Δv) ≈ F₀ + ∂F/∂x Δx + ∂F/∂v Δv, gives the
/// linear system
///
/// ```text
///   (M − h ∂F/∂v − h² ∂F/∂x) Δv = h (F₀ + h ∂F/∂x v₀)
/// ```
///
/// then v₁ = v₀ + Δv and x₁ = x₀ + h v₁. It is exact for linear forces (the harmonic oscillator
/// gets backward Euler's R = 1/(1 − z) exactly) and first order in general. The matrix A is
/// never formed: A p = M p − h J(h p, p) with J the force Jacobian–vector product ([`ForceJacobian`],
/// analytic where the force provides it, forward differences otherwise). A is symmetric
/// positive definite when ∂F/∂x and ∂F/∂v are symmetric negative semi-definite, which the
/// definite products ensure for springs and drag (a compressed spring's transverse stiffness
/// is dropped, Choi & Ko 2002). Conjugate gradients then converge; they start from the last
/// step's Δv and are preconditioned by diag(A) (Jacobi). Pinned particles, and z in 2D, are
/// filtered out of the solve (Baraff & Witkin's S): their Δv is 0. Forces are evaluated at
/// t₀ (the linearisation point).
///
/// A direction with pᵀA p ≤ 0 (possible only with forces that are not definite, such as an
/// attractor's tidal term or a user's force) stops the iteration at the last iterate.
#[derive(Default)]
pub(crate) struct BaraffWitkin {
    jac: ForceJacobian,
    /// Free components (1) and filtered ones (0).
    free: Vec<f64>,
    /// Mass per component, kg.
    mass: Vec<f64>,
    /// The last step's solution, the next step's first guess.
    dv: Vec<f64>,
    b: Vec<f64>,
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    q: Vec<f64>,
    diag: Vec<f64>,
    hp: Vec<f64>,
    zero: Vec<f64>,
    /// CG iterations of the last step.
    pub iterations: usize,
    /// Whether the last step's CG met its tolerance.
    pub converged: bool,
}

/// One step of [`BaraffWitkin::step`]: from the state (x, v) (m, m/s, 3 per particle) at
/// time t (s) over h (s), into (x_out, v_out).
pub struct StepSpan<'a> {
    pub t: f64,
    pub h: f64,
    pub x: &'a [f64],
    pub v: &'a [f64],
    pub x_out: &'a mut [f64],
    pub v_out: &'a mut [f64],
}

impl BaraffWitkin {
    /// The last step's Δv (m/s, 3 per particle): the next solve's first guess.
    pub(crate) fn warm_start(&self) -> &[f64] {
        &self.dv
    }

    /// Sets the next solve's first guess (a checkpoint's).
    pub(crate) fn set_warm_start(&mut self, dv: Vec<f64>) {
        self.dv = dv;
    }

    /// Advances (x, v) at time t by h into (x_out, v_out) (see [`StepSpan`]).
    pub fn step(&mut self, dynamics: &mut Dynamics<'_, '_>, span: StepSpan<'_>, stats: &mut Stats) -> Result<(), CallbackError> {
        let StepSpan {
            t,
            h,
            x,
            v,
            x_out,
            v_out,
        } = span;
        let n = x.len();
        self.reset_buffers(dynamics, n);

        // F₀, and the products at (x₀, v₀).
        dynamics.total_force(t, x, v)?;
        stats.nfev += 1;
        let s = State {
            t,
            x,
            v,
            mass: dynamics.mass,
        };
        let evaluations_before = self.jac.evaluations;
        self.jac.prepare(dynamics.forces, &s, true)?;
        self.right_hand_side(dynamics, &s, h)?;
        self.precondition(&s, h);
        self.conjugate_gradients(dynamics, &s, h)?;
        stats.nfev += self.jac.evaluations - evaluations_before;

        // v₁ = v₀ + Δv, x₁ = x₀ + h v₁.
        for k in 0..n {
            v_out[k] = v[k] + self.dv[k];
            x_out[k] = x[k] + h * v_out[k];
        }
        Ok(())
    }

    /// The filter, the masses per component and the solve's buffers for n components (the
    /// last Δv kept if it fits).
    fn reset_buffers(&mut self, dynamics: &Dynamics<'_, '_>, n: usize) {
        free_components(dynamics.inv_mass, dynamics.dim, &mut self.free);
        self.mass.clear();
        self.mass.extend(dynamics.mass.iter().flat_map(|m| [*m; 3]));
        for buf in [
            &mut self.b,
            &mut self.r,
            &mut self.z,
            &mut self.p,
            &mut self.q,
            &mut self.diag,
            &mut self.hp,
            &mut self.zero,
        ] {
            buf.clear();
            buf.resize(n, 0.0);
        }
        if self.dv.len() != n {
            self.dv.clear();
            self.dv.resize(n, 0.0);
        }
    }

    /// b = h (F₀ + h ∂F/∂x v₀), filtered (F₀ in `dynamics.force`, the Jacobian prepared at s).
    fn right_hand_side(&mut self, dynamics: &mut Dynamics<'_, '_>, s: &State, h: f64) -> Result<(), CallbackError> {
        let (v, n) = (s.v, s.x.len());
        for (hp, vk) in self.hp.iter_mut().zip(v) {
            *hp = h * vk;
        }
        self.jac.apply(dynamics.forces, s, &self.hp, &self.zero, &mut self.q)?;
        for k in 0..n {
            self.b[k] = self.free[k] * h * (dynamics.force[k] + self.q[k]);
        }

        Ok(())
    }

    /// The Jacobi preconditioner diag(A) = m − h² diag(∂F/∂x) − h diag(∂F/∂v), where known
    /// (m where not, or where that is not positive).
    fn precondition(&mut self, s: &State, h: f64) {
        self.diag.copy_from_slice(&self.mass);
        self.jac.add_diagonal(s, -h * h, -h, &mut self.diag);
        for (d, m) in self.diag.iter_mut().zip(&self.mass) {
            if !(d.is_finite() && *d > 0.0) {
                *d = *m;
            }
        }
    }

    /// Conjugate gradients on A Δv = b from the last step's Δv, until the residual is
    /// [`CG_TOLERANCE`] of b (or a direction is not positive definite, or the cap): Δv in
    /// `dv`, with `iterations` and `converged`.
    fn conjugate_gradients(&mut self, dynamics: &mut Dynamics<'_, '_>, s: &State, h: f64) -> Result<(), CallbackError> {
        let n = s.x.len();
        // Conjugate gradients on A Δv = b from the last step's Δv.
        for (dv, f) in self.dv.iter_mut().zip(&self.free) {
            *dv *= f;
        }
        let dv = std::mem::take(&mut self.dv);
        self.product(dynamics, s, h, &dv)?;
        self.dv = dv;
        for k in 0..n {
            self.r[k] = self.b[k] - self.q[k];
        }
        let b_norm = dot(&self.b, &self.b).sqrt();
        let limit = CG_TOLERANCE * b_norm;
        self.iterations = 0;
        self.converged = dot(&self.r, &self.r).sqrt() <= limit;
        if b_norm == 0.0 {
            self.dv.fill(0.0);
            self.converged = true;
        }
        if !b_norm.is_finite() {
            // F₀ (or h ∂F/∂x v₀) is NaN or ±inf, or so large that |b|² overflows: no solve can
            // take it. Δv = b/m, the step without the Jacobian (exact for a constant force):
            // non-finite where F₀ is, and the world stops the step as it does for the explicit
            // methods (SimulationDiverged naming the particle) instead of taking Δv = 0.
            for k in 0..n {
                self.dv[k] = self.b[k] / self.mass[k];
            }
            self.converged = true;
        }
        if !self.converged {
            for k in 0..n {
                self.z[k] = self.r[k] / self.diag[k];
            }
            self.p.copy_from_slice(&self.z);
            let mut rz = dot(&self.r, &self.z);
            let cap = CG_MAX_ITERATIONS.max(n);
            while self.iterations < cap {
                self.iterations += 1;
                let p = std::mem::take(&mut self.p);
                let result = self.product(dynamics, s, h, &p);
                self.p = p;
                result?;
                let curvature = dot(&self.p, &self.q);
                if curvature.is_nan() {
                    // a product overflowed or a force's derivative is NaN: not a solution to
                    // keep (the world reports the non-finite velocity)
                    self.dv.fill(f64::NAN);
                    break;
                }
                if curvature <= 0.0 {
                    break; // not positive definite along p: keep the last iterate
                }
                let alpha = rz / curvature;
                for k in 0..n {
                    self.dv[k] += alpha * self.p[k];
                    self.r[k] -= alpha * self.q[k];
                }
                if dot(&self.r, &self.r).sqrt() <= limit {
                    self.converged = true;
                    break;
                }
                for k in 0..n {
                    self.z[k] = self.r[k] / self.diag[k];
                }
                let rz_next = dot(&self.r, &self.z);
                let beta = rz_next / rz;
                rz = rz_next;
                for k in 0..n {
                    self.p[k] = self.z[k] + beta * self.p[k];
                }
            }
        }
        Ok(())
    }

    /// q = A p = M p − h J(h p, p), filtered.
    fn product(&mut self, dynamics: &mut Dynamics<'_, '_>, s: &State, h: f64, p: &[f64]) -> Result<(), CallbackError> {
        for (hp, pk) in self.hp.iter_mut().zip(p) {
            *hp = h * pk;
        }
        self.jac.apply(dynamics.forces, s, &self.hp, p, &mut self.q)?;
        for (k, pk) in p.iter().enumerate() {
            self.q[k] = self.free[k] * (self.mass[k] * pk - h * self.q[k]);
        }
        Ok(())
    }
}
