//! Step-size control of the adaptive driver: the next step from the error norm of the last.
//!
//! Derivation (Hairer, Nørsett & Wanner, Solving ODEs I, II.4 "automatic step size control";
//! SciPy's `_ivp/rk.py`). An embedded pair of orders p and p̂ estimates the local error by
//! e = y − ŷ; with q = min(p, p̂) the order of that estimate (`ButcherTableau::error_order`),
//! its scaled norm behaves like
//!
//! ```text
//!   ‖e‖ ≈ C h^(q+1)          (C depends on the solution, not on h)
//! ```
//!
//! The step h_opt that would give ‖e‖ = 1, the largest acceptable, solves C h_opt^(q+1) = 1;
//! dividing by the measured ‖e‖ = C h^(q+1) eliminates the unknown C:
//!
//! ```text
//!   h_opt = h · ‖e‖^(−1/(q+1))
//! ```
//!
//! A safety factor (0.9) makes the next step likely to be accepted although C drifts, and the
//! factor h_new/h is clamped to [0.2, 10] so that one odd estimate cannot change the step
//! much. That is the I ("integral") controller, exponent α = 1/(q+1) (SciPy's `RK45`/`RK23`).
//!
//! The PI controller (Gustafsson; Hairer & Wanner, Solving ODEs II, IV.2, and their DOPRI5
//! code) also weighs the previous accepted norm, which damps the oscillation of h that the
//! I controller shows on problems at the edge of stability:
//!
//! ```text
//!   h_new = h · clamp(0.9 · ‖e_n‖^(−α) · ‖e_{n−1}‖^β, 0.2, 10),   α = 1/(q+1) − 0.75 β
//! ```
//!
//! with β = 0.04 (DOPRI5's value; β = 0 is the I controller). For Dormand–Prince q = 4, so
//! α = 0.2 − 0.75 · 0.04 = 0.17. After a rejection the step only shrinks: h · max(0.9 ·
//! ‖e_n‖^(−α), 0.2) (0.2 when ‖e_n‖ is not finite), and the step accepted next does not grow.

/// The previous accepted error norm is floored at this (and starts at it) in the PI factor
/// ‖e_{n−1}‖^β, so that a step with a tiny error does not inflate the next factor.
pub(crate) const ERR_PREV_FLOOR: f64 = 1e-4;

/// The current error norm is floored at this in ‖e_n‖^(−α) (an exact step, e = 0, would
/// otherwise give an infinite factor; the clamp takes over long before).
const ERR_FLOOR: f64 = 1e-10;

/// The parameters of the PI step-size controller (see the module's derivation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct StepSizeController {
    /// Factor on the optimal step (< 1: aim below the tolerance).
    pub safety: f64,
    /// Smallest factor h_new/h, after any step.
    pub min_factor: f64,
    /// Largest factor h_new/h.
    pub max_factor: f64,
    /// Weight β of the previous error (0: the I controller).
    pub beta: f64,
}

impl Default for StepSizeController {
    /// DOPRI5's: safety 0.9, factors in [0.2, 10], β = 0.04.
    fn default() -> Self {
        Self {
            safety: 0.9,
            min_factor: 0.2,
            max_factor: 10.0,
            beta: 0.04,
        }
    }
}

impl StepSizeController {
    /// The exponent α = 1/(q+1) − 0.75 β of the current error, for an error estimate of
    /// order q ([`ButcherTableau::error_order`](super::tableau::ButcherTableau::error_order)).
    pub(crate) fn alpha(&self, error_order: u32) -> f64 {
        1.0 / (f64::from(error_order) + 1.0) - 0.75 * self.beta
    }

    /// h_new/h after an accepted step with error norm `norm` (≤ 1), `prev` the previous
    /// accepted norm (floored at [`ERR_PREV_FLOOR`]), `alpha` from [`Self::alpha`]; capped at 1
    /// when the attempt before was rejected.
    pub(crate) fn after_accept(&self, alpha: f64, norm: f64, prev: f64, after_rejection: bool) -> f64 {
        let factor = self.safety * norm.max(ERR_FLOOR).powf(-alpha) * prev.powf(self.beta);
        let factor = factor.clamp(self.min_factor, self.max_factor);
        if after_rejection {
            factor.min(1.0)
        } else {
            factor
        }
    }

    /// h_new/h after a rejected step with error norm `norm` (> 1, or not finite).
    pub(crate) fn after_reject(&self, alpha: f64, norm: f64) -> f64 {
        if norm.is_finite() {
            (self.safety * norm.powf(-alpha)).max(self.min_factor)
        } else {
            self.min_factor
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ode::tableau::catalogue;

    #[test]
    fn dormand_prince_gets_the_exponent_of_its_constant_bit_for_bit() {
        // Before the controller read the order from the tableau, the driver had
        // `const ALPHA: f64 = 0.2 - 0.75 * 0.04;`: the same f64, so the same steps.
        let q = catalogue::dopri5().error_order().unwrap();
        let alpha = StepSizeController::default().alpha(q);
        assert_eq!(alpha.to_bits(), (0.2_f64 - 0.75 * 0.04).to_bits());
        // Bogacki–Shampine's estimate is of order 2: α = 1/3 − 0.03.
        let q = catalogue::bs3().error_order().unwrap();
        assert_eq!(StepSizeController::default().alpha(q), 1.0 / 3.0 - 0.75 * 0.04);
    }

    #[test]
    fn factors_are_clamped_and_do_not_grow_after_a_rejection() {
        let c = StepSizeController::default();
        let alpha = c.alpha(4);
        assert_eq!(c.after_accept(alpha, 0.0, ERR_PREV_FLOOR, false), 10.0);
        assert_eq!(c.after_accept(alpha, 0.0, ERR_PREV_FLOOR, true), 1.0);
        assert_eq!(c.after_reject(alpha, 1e12), 0.2);
        assert_eq!(c.after_reject(alpha, f64::NAN), 0.2);
        let f = c.after_reject(alpha, 2.0);
        assert!(f > 0.2 && f < 0.9, "{f}");
    }
}
