//! The tangential part of the force models, with memory: LAMMPS GRANULAR's `tangential
//! linear_history` and `mindlin`, `rolling sds` and `twisting marshall`, as its `pair
//! granular` computes them (read from its source; Luding, Granular Matter 10 (2008) 235 for
//! the spring's frame; Marshall, J. Comp. Phys. 228 (2009) 1541 for the twist).
//!
//! Contact c between particle i and its partner j (a particle, or a collider's surface
//! moving at w) has the normal n from j towards i, the overlap δ and the lever arms ρ_i, ρ_j
//! of `collide/spin.rs` (the contact point splits the distance of centres by the radii). The
//! contact point of i slides over the partner's at
//!
//! ```text
//!   v_t = u − (u·n) n − (ρ_i ω_i + ρ_j ω_j) × n,      u = v_i − v_j   (v_i − w at a collider)
//! ```
//!
//! **Tangential spring (sliding friction).** The spring's stretch ξ_t is the slip
//! accumulated while the contact lasts. At each step (Verlet's one force evaluation) it is
//! first turned into the current tangent plane, keeping its length (the pair has rolled
//! round: ξ ← |ξ| (ξ − (ξ·n) n)/|ξ − (ξ·n) n|), then stretched by the step's slip, ξ += h v̄_t
//! with v̄ the velocities over the step (x(t + h) − x(t))/h = v + h/2 a, Verlet's half-step
//! velocity as in LAMMPS (so that ξ is the contact point's displacement, to rounding: a block
//! held on a slope sits exactly ξ = m g sin θ / k_t below where it touched), and the force on
//! i, with v_t at the velocities the evaluation sees (the dashpots'), is
//!
//! ```text
//!   F_t = −k_t ξ_t − γ_t v_t,        |F_t| ≤ μ |F_n|          (Coulomb's cone)
//! ```
//!
//! k_t is the tangential stiffness: constant (`linear_history`, N/m), or Mindlin's 8 G* a
//! with the contact radius a = √(R* δ) and G* the effective shear modulus (`mindlin`); γ_t =
//! x_γt c_n, a fraction of the normal dashpot. Beyond the cone the force is cut to μ |F_n|
//! along itself and the spring set to the stretch that gives it, ξ_t = −(μ |F_n| F̂_t +
//! γ_t v_t)/k_t: the contact slides, and the stretch stays at the cone's edge, so a sliding
//! contact that stops sticks at once with the friction it had. Below the cone it sticks: a
//! block on a slope tan θ < μ holds with ξ_t = m g sin θ / k_t exactly.
//!
//! F_t acts at the contact point: −F_t on a particle partner, and torques −ρ_i n × F_t on i
//! and −ρ_j n × F_t on j (both turn the same way; the pair's angular momentum is kept, since
//! the arms meet at one point).
//!
//! **Rolling and twisting resistance** (with rolling friction μ_r > 0) are their own
//! sub-models, `rolling.rs` (`rolling sds`) and `twisting.rs` (`twisting marshall`), which
//! read the sliding contact's k_t and γ_t; [`TangentialModel`] composes the three.
//!
//! Only velocity Verlet steps these models (the springs stretch once per step, by the step's
//! slip at its one force evaluation, as LAMMPS's `fix nve/sphere` does). The other force
//! evaluations (the first step's, the advisor's, `accelerations`) read the springs as they
//! are, stretching nothing.

use super::history::Slip;
pub(super) use super::springs::Touch;
use super::springs::{into_plane, slider, Spins};
use super::{RollingLaw, TwistingLaw};
use crate::vec3;

/// LAMMPS's tangential sub-models with history.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TangentialLaw {
    /// `linear_history`: k_t constant, N/m.
    LinearHistory {
        /// k_t, N/m (> 0).
        stiffness: f64,
    },
    /// `mindlin`: k_t = 8 G* a, a = √(R* δ), with the effective shear modulus G* =
    /// E / (4 (2 − ν)(1 + ν)) between two bodies of the Hertz model's material, Pa.
    Mindlin {
        /// G*, Pa (> 0).
        shear_modulus: f64,
    },
}

impl TangentialLaw {
    /// The names of its variants, as `name` gives them (`sub_models.rs`).
    pub const NAMES: [&'static str; 2] = ["linear_history", "mindlin"];

    /// Its name (LAMMPS's).
    pub fn name(&self) -> &'static str {
        match self {
            TangentialLaw::LinearHistory { .. } => Self::NAMES[0],
            TangentialLaw::Mindlin { .. } => Self::NAMES[1],
        }
    }

    /// k_t at contact radius `a` (m), N/m.
    #[inline]
    fn stiffness(&self, a: f64) -> f64 {
        match *self {
            TangentialLaw::LinearHistory { stiffness } => stiffness,
            TangentialLaw::Mindlin { shear_modulus } => 8.0 * shear_modulus * a,
        }
    }
}

/// The tangential part of a force model, three of LAMMPS GRANULAR's sub-models composed:
/// `tangential` (this file) and, with rolling friction, `rolling` and `twisting`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TangentialModel {
    pub law: TangentialLaw,
    /// x_γt ≥ 0: the tangential dashpot γ_t = x_γt c_n, a fraction of the normal one.
    pub damping: f64,
    /// Rolling resistance (`rolling.rs`; `None`: none).
    pub rolling: Option<RollingLaw>,
    /// Twisting resistance (`twisting.rs`; `None`: none).
    pub twisting: Option<TwistingLaw>,
}

/// What the tangential part of one contact does now.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(super) struct Tangent {
    /// F_t on i, N (⊥ n; −F_t on a particle partner).
    pub force: [f64; 3],
    /// The couple on i from rolling and twisting resistance, N·m (its opposite on j).
    pub couple: [f64; 3],
    /// The springs after this evaluation.
    pub slip: Slip,
    /// The power the tangential part dissipates, W (≥ 0): γ_t |v_t|² while it sticks, |F_t·v_t|
    /// while it slides (the books' `energy_lost`).
    pub power: f64,
    /// Whether the contact slides: its force at the Coulomb bound μ |F_n| (to 1e-9 of it,
    /// so that a spring left at the bound by the last step's slide reads as sliding).
    pub slides: bool,
}

impl TangentialModel {
    /// The tangential force and couples of contact `t` with memory `slip`; with `step` (h, s)
    /// the springs are turned and stretched by the step's motion first (module doc).
    #[inline]
    pub(super) fn at(&self, t: &Touch, slip: Slip, step: Option<f64>) -> Tangent {
        let n = t.normal;
        let (rho_i, rho_j) = t.arms;
        // the contact point's sliding velocity at (u, ω)
        let sliding = |u: [f64; 3], [wi, wj]: [[f64; 3]; 2]| {
            let spin = vec3::add(vec3::scale(rho_i, wi), vec3::scale(rho_j, wj));
            vec3::sub(vec3::sub(u, vec3::scale(vec3::dot(u, n), n)), vec3::cross(spin, n))
        };
        let [wi, wj] = t.omega;
        let vt = sliding(t.u, t.omega);
        // what stretches the springs over the step
        let (vt_step, rel_step) = match t.moved {
            Some((u, w)) => (sliding(u, w), vec3::sub(w[0], w[1])),
            None => (vt, vec3::sub(wi, wj)),
        };
        let k_t = self.law.stiffness(t.contact_radius);
        let gamma_t = self.damping * t.dashpot;
        let mut shear = slip.shear;
        if let Some(h) = step {
            shear = into_plane(shear, n);
            for k in 0..3 {
                shear[k] += h * vt_step[k];
            }
        }
        let (force, shear, slides) = slider(shear, vt, k_t, gamma_t, t.friction * t.normal_force);
        let power = if slides {
            vec3::dot(force, vt).abs()
        } else {
            gamma_t * vec3::dot(vt, vt)
        };
        let cap = t.friction * t.normal_force;
        let mut out = Tangent {
            force,
            couple: [0.0; 3],
            slip: Slip { shear, ..slip },
            power,
            slides: slides || (cap > 0.0 && vec3::norm(force) >= cap * (1.0 - 1e-9)),
        };
        // rolling and twisting resistance: a couple on i (its opposite on j)
        let spins = Spins {
            now: vec3::sub(wi, wj),
            over_step: rel_step,
        };
        let mut couple = None;
        if let Some(rolling) = &self.rolling {
            let (c, roll) = rolling.at(t, &spins, slip.roll, step, k_t, gamma_t);
            out.slip.roll = roll;
            couple = Some(c);
        }
        if let Some(twisting) = &self.twisting {
            let (m, twist) = twisting.at(t, &spins, slip.twist, step, k_t, gamma_t);
            out.slip.twist = twist;
            let about_n = vec3::scale(m, n);
            couple = Some(couple.map_or(about_n, |c| vec3::add(c, about_n)));
        }
        if let Some(c) = couple {
            out.couple = c;
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn touch(u: [f64; 3]) -> Touch {
        Touch {
            normal: [0.0, 0.0, 1.0],
            contact_radius: (0.01_f64 * 1e-4).sqrt(),
            reduced_radius: 0.01,
            u,
            omega: [[0.0; 3]; 2],
            moved: None,
            arms: (0.01, 0.0),
            normal_force: 10.0,
            dashpot: 0.0,
            friction: 0.5,
        }
    }

    #[test]
    fn the_spring_sticks_inside_the_cone_and_slides_at_its_edge() {
        let model = TangentialModel {
            law: TangentialLaw::LinearHistory { stiffness: 1e4 },
            damping: 0.0,
            rolling: None,
            twisting: None,
        };
        // a step of slip 1e-4 m: F = −1 N, inside μ F_n = 5 N
        let t = model.at(&touch([1.0, 0.0, 0.0]), Slip::default(), Some(1e-4));
        assert_eq!(t.slip.shear, [1e-4, 0.0, 0.0]);
        assert_eq!(t.force, [-1.0, 0.0, 0.0]);
        // 1e-3 m more: −11 N, cut to the cone's −5 N with the stretch 5e-4 m
        let t = model.at(&touch([1.0, 0.0, 0.0]), t.slip, Some(1e-3));
        assert!((t.force[0] + 5.0).abs() < 1e-12, "{:?}", t.force);
        assert!((t.slip.shear[0] - 5e-4).abs() < 1e-16);
        // read without a step: the same force, the spring unchanged
        let again = model.at(&touch([0.0; 3]), t.slip, None);
        assert!((again.force[0] + 5.0).abs() < 1e-12);
        assert_eq!(again.slip, t.slip);
    }

    #[test]
    fn a_spring_turned_out_of_the_plane_keeps_its_length() {
        let xi = into_plane([3.0, 0.0, 4.0], [0.0, 0.0, 1.0]);
        assert_eq!(xi, [5.0, 0.0, 0.0]);
        assert_eq!(into_plane([0.0, 0.0, 4.0], [0.0, 0.0, 1.0]), [0.0; 3]);
    }
}
