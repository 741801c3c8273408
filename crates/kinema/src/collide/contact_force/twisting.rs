//! The twisting sub-model of the force models (LAMMPS GRANULAR's `twisting marshall`, read
//! from its `pair granular`; Marshall, J. Comp. Phys. 228 (2009) 1541): on the relative spin
//! about the normal, Ω = (ω_i − ω_j)·n, a spring on the twist angle θ accumulated while the
//! contact lasts,
//!
//! ```text
//!   M = −k_tw θ − γ_tw Ω,      |M| ≤ μ_tw |F_n|
//! ```
//!
//! with Marshall's k_tw = ½ k_t a², γ_tw = ½ γ_t a², μ_tw = ⅔ a μ from the sliding contact
//! (a the contact radius); beyond the cap θ is set to where M stays at it. The couple M n on
//! i and its opposite on j. It comes with rolling resistance (`rolling.rs`), as kinema's one
//! setting `rolling_friction` asks for both.

use super::springs::{Spins, Touch};
use crate::vec3;

/// The twisting sub-model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TwistingLaw {
    /// `marshall`: the spring–dashpot–slider above, of the sliding contact's constants.
    Marshall,
}

impl TwistingLaw {
    /// The names of its variants, as `name` gives them (`sub_models.rs`).
    pub const NAMES: [&'static str; 1] = ["marshall"];

    /// Its name (LAMMPS's).
    pub fn name(&self) -> &'static str {
        match self {
            TwistingLaw::Marshall => Self::NAMES[0],
        }
    }

    /// The twisting moment M on i about the normal (N·m; −M on j) of contact `t` turning at
    /// `spins`, and the twist angle after (rad), from `twist` before; with `step` (h, s) the
    /// angle grows by the step's turn first. `k_t` (N/m) and `gamma_t` (kg/s): the contact's
    /// tangential spring and dashpot.
    #[inline]
    pub(super) fn at(&self, t: &Touch, spins: &Spins, twist: f64, step: Option<f64>, k_t: f64, gamma_t: f64) -> (f64, f64) {
        let TwistingLaw::Marshall = self;
        let (n, a) = (t.normal, t.contact_radius);
        // Ω = Δω·n
        let spin_n = vec3::dot(spins.now, n);
        let mut twist = twist;
        if let Some(h) = step {
            twist += h * vec3::dot(spins.over_step, n);
        }
        let (k_tw, gamma_tw, cap) = (
            0.5 * k_t * a * a,
            0.5 * gamma_t * a * a,
            2.0 / 3.0 * a * t.friction * t.normal_force,
        );
        let mut m = -k_tw * twist - gamma_tw * spin_n;
        if m.abs() > cap {
            let sign = if spin_n > 0.0 {
                1.0
            } else if spin_n < 0.0 {
                -1.0
            } else {
                0.0
            };
            if k_tw > 0.0 {
                twist = (cap * sign - gamma_tw * spin_n) / k_tw;
            }
            m = -cap * sign;
        }
        (m, twist)
    }
}
