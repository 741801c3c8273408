//! The damping sub-model of the force models (LAMMPS GRANULAR's `damping`): the normal
//! dashpot c_n (kg/s) of a contact, F_n = F_el − c_n u_n.
//!
//! - `coeff_restitution` (the default): c_n from the pair's restitution e, so that a head-on
//!   impact comes out with that e. For Hooke's law the damped linear oscillator's exact rule,
//!   c_n = 2 ζ √(k m_eff) with ζ = −ln e / √(π² + ln² e) (`spring_dashpot.rs`); for Hertz's
//!   law √5/2 of that at the current secant stiffness k (Tsuji et al. 1992's form, LAMMPS's
//!   `damping coeff_restitution` for Hertzian contacts: `NormalLaw::restitution_dashpot`), an
//!   approximation of the set e that comes out the same at every impact speed (the table in
//!   docs/collisions.md).
//! - `mass_velocity`: c_n = m_eff γ_n with a given rate γ_n (1/s), whatever e.

use super::NormalLaw;
use crate::collide::dashpot_coefficient;

/// The damping sub-model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum DampingLaw {
    /// `coeff_restitution`: c_n from each pair's restitution e (module doc).
    CoeffRestitution,
    /// `mass_velocity`: c_n = m_eff γ_n.
    MassVelocity {
        /// γ_n, 1/s (≥ 0).
        rate: f64,
    },
}

impl DampingLaw {
    /// The names of its variants, as `name` gives them (the table of sub-models,
    /// `sub_models.rs`).
    pub const NAMES: [&'static str; 2] = ["coeff_restitution", "mass_velocity"];

    /// A given rate γ_n (1/s) as `mass_velocity`; none as `coeff_restitution`.
    pub fn of(rate: Option<f64>) -> Self {
        match rate {
            Some(rate) => DampingLaw::MassVelocity { rate },
            None => DampingLaw::CoeffRestitution,
        }
    }

    /// Its name (LAMMPS's).
    pub fn name(&self) -> &'static str {
        match self {
            DampingLaw::CoeffRestitution => Self::NAMES[0],
            DampingLaw::MassVelocity { .. } => Self::NAMES[1],
        }
    }

    /// c_n (kg/s) of a contact of the normal law `normal` with w = w_i + w_j > 0 (1/kg),
    /// secant stiffness `k` (N/m) and damping ratio `zeta` of its restitution (asked for only
    /// by `coeff_restitution`).
    #[inline(always)]
    pub fn coefficient(&self, normal: &NormalLaw, w: f64, k: f64, zeta: impl FnOnce() -> f64) -> f64 {
        match self {
            DampingLaw::MassVelocity { rate } => rate / w,
            DampingLaw::CoeffRestitution => normal.restitution_dashpot(dashpot_coefficient(k, zeta(), w)),
        }
    }

    /// The damping ratio ζ of a contact oscillating at ω² = k w (1/s²), the restitution's
    /// (`zeta_of_restitution`, asked for only by `coeff_restitution`) or the given rate's
    /// γ_n / (2 ω): what the step advisor weighs the stiffest contact with.
    pub fn ratio_at(&self, omega_squared: f64, zeta_of_restitution: impl FnOnce() -> f64) -> f64 {
        match self {
            DampingLaw::MassVelocity { rate } => rate / (2.0 * omega_squared.sqrt()),
            DampingLaw::CoeffRestitution => zeta_of_restitution(),
        }
    }
}
