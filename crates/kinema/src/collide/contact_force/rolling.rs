//! The rolling sub-model of the force models (LAMMPS GRANULAR's `rolling sds`, read from its
//! `pair granular`), with rolling friction μ_r > 0: a spring on the rolling displacement,
//! v_r = R* (ω_i − ω_j) × n (R* = r_i r_j/(r_i + r_j); r_i at a collider), stretched and
//! turned as the tangential spring is (`tangent.rs`):
//!
//! ```text
//!   f_r = −k_r ξ_r − γ_r v_r,      |f_r| ≤ μ_r |F_n|
//! ```
//!
//! with k_r and γ_r given, or the contact's tangential k_t and γ_t; the couple R* n × f_r on
//! i and its opposite on j.

use super::springs::{into_plane, slider, Spins, Touch};
use crate::vec3;

/// The rolling sub-model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RollingLaw {
    /// `sds`: the spring–dashpot–slider above.
    Sds {
        /// μ_r > 0: the rolling spring's force is at most μ_r |F_n|.
        friction: f64,
        /// k_r, N/m (`None`: the contact's k_t).
        stiffness: Option<f64>,
        /// γ_r, kg/s (`None`: the contact's γ_t).
        damping: Option<f64>,
    },
}

impl RollingLaw {
    /// The names of its variants, as `name` gives them (`sub_models.rs`).
    pub const NAMES: [&'static str; 1] = ["sds"];

    /// Its name (LAMMPS's).
    pub fn name(&self) -> &'static str {
        match self {
            RollingLaw::Sds { .. } => Self::NAMES[0],
        }
    }

    /// The couple on i (N·m; its opposite on j) of contact `t` turning at `spins`, and the
    /// rolling spring after (m), from `roll` before; with `step` (h, s) the spring is turned
    /// and stretched by the step's motion first. `k_t` (N/m) and `gamma_t` (kg/s): the
    /// contact's tangential spring and dashpot.
    #[inline]
    pub(super) fn at(
        &self,
        t: &Touch,
        spins: &Spins,
        roll: [f64; 3],
        step: Option<f64>,
        k_t: f64,
        gamma_t: f64,
    ) -> ([f64; 3], [f64; 3]) {
        let RollingLaw::Sds {
            friction,
            stiffness,
            damping,
        } = *self;
        let n = t.normal;
        // v_r = R* Δω × n
        let vr = vec3::scale(t.reduced_radius, vec3::cross(spins.now, n));
        let mut roll = roll;
        if let Some(h) = step {
            let vr_step = vec3::scale(t.reduced_radius, vec3::cross(spins.over_step, n));
            roll = into_plane(roll, n);
            for k in 0..3 {
                roll[k] += h * vr_step[k];
            }
        }
        let (k_r, gamma_r) = (stiffness.unwrap_or(k_t), damping.unwrap_or(gamma_t));
        let (fr, roll, _) = slider(roll, vr, k_r, gamma_r, friction * t.normal_force);
        (vec3::scale(t.reduced_radius, vec3::cross(n, fr)), roll)
    }
}
