//! Spin in the impulse model: an impulse acts at the contact point, so its tangential part
//! turns both bodies, and friction acts on the velocity of the contact point, which their
//! turning changes.
//!
//! Contact c between particle i and its partner j has the unit normal n from j towards i.
//! The contact point lies on the line of centres, at the lever arms
//!
//! ```text
//!   a_i = −ρ_i n,   a_j = +ρ_j n      (from each centre to the contact point)
//!   ρ_i = d r_i / (r_i + r_j),   ρ_j = d r_j / (r_i + r_j)      (d = |x_i − x_j|: they split
//!                                                                  the distance of centres)
//!   ρ_i = r_i − δ                     (against a collider: at the surface, δ the overlap)
//! ```
//!
//! so that a_i − a_j = −(ρ_i + ρ_j) n = x_j − x_i exactly: the impulse J on i at a_i and −J on
//! j at a_j change the pair's angular momentum about any point by
//! (x_i + a_i) × J − (x_j + a_j) × J = 0 (the torque balance to rounding). The distance is
//! the one at which the impulse acts: at an impact's time, r_i + r_j − δ with the δ found
//! there; at the step's end, the overlap δ the soft step leaves (0 for a contact that
//! touches, `soft_step.rs` `Target::rest`), not the one the integrated positions had before
//! it (a ball resting on a floor sinks by g h² in stage 1, and the solve lifts it back:
//! its arm is r, and it rolls at exactly 5/7 g sin θ).
//!
//! An impulse J on i at a_i changes ω_i by I_i⁻¹ a_i × J = −k_i ρ_i n × J (k = 1/I), and −J on
//! j at a_j changes ω_j by I_j⁻¹ a_j × (−J) = −k_j ρ_j n × J: the same sense for both.
//! The velocity of the contact point relative to the partner's is
//!
//! ```text
//!   u_c = v_i + ω_i × a_i − v_j − ω_j × a_j = u − (ρ_i ω_i + ρ_j ω_j) × n
//! ```
//!
//! whose normal part is u_n (ω × n ⊥ n: a normal impulse turns nothing, and Newton's law is
//! unchanged). For a tangential impulse t ⊥ n, (a × t) × a = |a|² t, so the contact point's
//! tangential velocity changes by
//!
//! ```text
//!   Δu_c = (w_i + w_j + k_i ρ_i² + k_j ρ_j²) t = w_t t
//! ```
//!
//! an isotropic effective mass 1/w_t (kg). A solid sphere on a still floor (k ρ² = 5/(2m)):
//! w_t = 7/(2m), so friction that stops the sliding takes 2/7 of the slip velocity from the
//! centre, and a ball on a slope rolls at 5/7 g sin θ.

use super::contact::{action_reaction, Contact};
use crate::vec3;

/// What spin adds to one contact: the contact point's velocity from the turning, and the
/// inverse mass the turning adds along the tangent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSpin {
    /// (ρ_i ω_i + ρ_j ω_j) × n, m/s: subtracted from the centres' relative velocity to give
    /// the contact point's (⊥ n).
    pub turning: [f64; 3],
    /// k_i ρ_i² + k_j ρ_j², 1/kg: added to w_i + w_j along the tangent.
    pub w_rot: f64,
}

/// The particles' rotation as the collision stages use it: the inverse moments of inertia,
/// 1/(kg·m²) (0 for a pinned particle or a point), and the radii (m).
#[derive(Debug, Clone, Copy)]
pub struct Rotation<'a> {
    /// 1/I per particle, 1/(kg·m²).
    pub inv_inertia: &'a [f64],
    /// r per particle, m.
    pub radius: &'a [f64],
}

impl Rotation<'_> {
    /// The lever arms (ρ_i, ρ_j) of contact `c` at the overlap δ = `overlap` (m; module
    /// doc), m; ρ_j = 0 for a collider.
    pub fn arms(&self, c: &Contact, overlap: f64) -> (f64, f64) {
        let ri = self.radius[c.i];
        match c.partner_particle() {
            Some(j) => {
                let rj = self.radius[j];
                let sum = ri + rj;
                if sum > 0.0 {
                    let d = sum - overlap;
                    (d * (ri / sum), d * (rj / sum))
                } else {
                    (0.0, 0.0)
                }
            }
            None => ((ri - overlap).max(0.0), 0.0),
        }
    }

    /// The inverse moments of inertia of c's two sides (k_j = 0 for a collider).
    pub fn inverse_inertias(&self, c: &Contact) -> (f64, f64) {
        (
            self.inv_inertia[c.i],
            c.partner_particle().map_or(0.0, |j| self.inv_inertia[j]),
        )
    }

    /// What spin adds to contact `c` at its overlap, with the angular velocities `omega`
    /// (rad/s, 3 per particle).
    pub fn of(&self, c: &Contact, omega: &[f64]) -> ContactSpin {
        let (rho_i, rho_j) = self.arms(c, c.overlap);
        let (ki, kj) = self.inverse_inertias(c);
        let wi = vec3::get(omega, c.i);
        let w = match c.partner_particle() {
            Some(j) => vec3::add(vec3::scale(rho_i, wi), vec3::scale(rho_j, vec3::get(omega, j))),
            None => vec3::scale(rho_i, wi),
        };
        ContactSpin {
            turning: vec3::cross(w, c.normal),
            w_rot: ki * rho_i * rho_i + kj * rho_j * rho_j,
        }
    }

    /// The turn the impulse J (N·s, on i; −J on the partner) gives both sides of contact
    /// `c` at the overlap `overlap` (m): ω_i −= k_i ρ_i n × J and ω_j −= k_j ρ_j n × J, in
    /// `omega`.
    pub fn kick(&self, c: &Contact, overlap: f64, impulse: [f64; 3], omega: &mut [f64]) {
        let (rho_i, rho_j) = self.arms(c, overlap);
        let (ki, kj) = self.inverse_inertias(c);
        // (both turn the same way: j's arm points the other way, −ρ_j n, and it takes −J)
        let nj = vec3::cross(c.normal, impulse);
        action_reaction(omega, c.i, c.partner_particle(), (-ki * rho_i, kj * rho_j), nj);
    }
}

/// The rotational kinetic energy ½ Σ I |ω|² of the particles `which` (J), from the inverse
/// inertias (a particle with k = 0 cannot turn and counts 0).
pub(crate) fn rotational_energy(which: impl Iterator<Item = usize>, omega: &[f64], inv_inertia: &[f64]) -> f64 {
    which
        .filter(|&q| inv_inertia[q] > 0.0)
        .map(|q| {
            let w = vec3::get(omega, q);
            0.5 * vec3::dot(w, w) / inv_inertia[q]
        })
        .sum()
}
