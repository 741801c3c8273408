//! Response: Newton's restitution by impulses, Coulomb friction, and the materials that set
//! them (the pair rule, [`MaterialTable`]). The impulse of one contact is
//! [`restitution_impulse`]; the world applies it at each impact inside a step
//! (`impulse/impacts.rs`), and the end-of-step contacts are solved by `soft_step`.
//!
//! For a contact with normal n (from the partner towards i), inverse masses w_i, w_j (0 for a
//! pinned particle and for a collider) and relative normal velocity u_n = (v_i − v_j)·n < 0,
//! Newton's law u_n⁺ = −e u_n⁻ fixes the normal impulse j n (on i; −j n on j):
//!
//! ```text
//!   u_n⁺ = u_n + (w_i + w_j) j = −e u_n    ⇒    j = −(1 + e) u_n / (w_i + w_j)
//!   v_i += w_i j n,    v_j −= w_j j n
//! ```
//!
//! Its kinetic energy change is j u_n + ½ (w_i + w_j) j² = −½ (1 − e²) μ u_n², with
//! μ = 1 / (w_i + w_j) the reduced mass: nothing is lost for e = 1, all the normal motion of
//! the pair's centre-of-mass frame for e = 0.
//!
//! Against a moving collider, v_j is its surface's velocity at the contact
//! (`Contact::wall_velocity`): the law acts on the relative velocity, and the surface does
//! work on the particle, which the energy lost (the particles' kinetic energy lost) counts.
//!
//! Without spin, particles have no rotational inertia, so a tangential impulse j_t changes the
//! tangential relative velocity u_t by (w_i + w_j) j_t, the same effective mass as along the
//! normal. With spin (`collide/spin.rs`) u_t is the contact point's sliding velocity
//! u_t − (ρ_i ω_i + ρ_j ω_j) × n and the tangential inverse mass is w_t = w_i + w_j + k_i ρ_i² +
//! k_j ρ_j² (k = 1/I); without, w_t = w_i + w_j. Coulomb friction gives the impulse that stops
//! the sliding, |u_t| / w_t (a tangential restitution of 0: the contact point leaves with the
//! partner's velocity), unless it exceeds the cone μ j; then it slides with j_t = μ j. Either
//! way it opposes u_t and changes the kinetic energy (with spin: translational and
//! rotational) by −j_t |u_t| + ½ w_t j_t² ≤ −½ j_t |u_t| ≤ 0.

use super::colliders::Collider;
use super::contact::{Contact, Partner};
use super::spin::ContactSpin;
use crate::error::Error;
use crate::vec3;

/// The restitution and friction of a contact, or of one body before combining.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    restitution: f64,
    friction: f64,
}

impl Material {
    /// Coefficient of restitution e ∈ [0, 1] (1: elastic, 0: no rebound) and Coulomb friction
    /// coefficient μ (finite, ≥ 0; 0: frictionless).
    pub fn new(restitution: f64, friction: f64) -> Result<Self, Error> {
        if !(0.0..=1.0).contains(&restitution) {
            return Err(Error::invalid(
                "restitution",
                restitution,
                "the coefficient of restitution must be in [0, 1]",
            ));
        }
        if !(friction.is_finite() && friction >= 0.0) {
            return Err(Error::invalid(
                "friction",
                friction,
                "the friction coefficient must be finite and >= 0",
            ));
        }
        Ok(Material { restitution, friction })
    }

    /// Restitution e.
    pub fn restitution(&self) -> f64 {
        self.restitution
    }

    /// Friction coefficient μ.
    pub fn friction(&self) -> f64 {
        self.friction
    }

    /// The value of a pair of particles, Box2D's rule: e = max(e_a, e_b) (a bouncy body
    /// bounces off anything), μ = √(μ_a μ_b) (either frictionless body makes the contact
    /// frictionless). Both are symmetric, and give back a body's value when paired with
    /// itself.
    pub fn combine(a: Material, b: Material) -> Material {
        Material {
            restitution: a.restitution.max(b.restitution),
            friction: (a.friction * b.friction).sqrt(),
        }
    }
}

/// Where each contact's [`Material`] comes from.
///
/// - Particle–particle: [`Material::combine`] of the two particles' values; a particle's value
///   is `particles[i]`, or `global` without per-particle values.
/// - Particle–collider: the collider's [`Surface`](super::colliders::Surface) value where it
///   sets one, else the particle's value. A collider's value is not combined: it is a
///   boundary condition, and a "dead" floor (e = 0) must stop bouncy balls.
#[derive(Debug, Clone, Copy)]
pub struct MaterialTable<'a> {
    /// The value of every particle without a value of its own.
    pub global: Material,
    /// Per-particle values (one per particle), if any.
    pub particles: Option<&'a [Material]>,
    /// The colliders that `Partner::Collider(k)` indexes.
    pub colliders: &'a [Collider],
}

impl<'a> MaterialTable<'a> {
    /// One value for all particles, no colliders.
    pub fn uniform(global: Material) -> Self {
        MaterialTable {
            global,
            particles: None,
            colliders: &[],
        }
    }

    /// The same table with these colliders.
    pub fn with_colliders(self, colliders: &'a [Collider]) -> Self {
        MaterialTable { colliders, ..self }
    }

    /// The same table with per-particle values.
    pub fn with_particles(self, particles: &'a [Material]) -> Self {
        MaterialTable {
            particles: Some(particles),
            ..self
        }
    }

    /// Particle i's own value (i in range when per-particle values are set).
    pub fn particle(&self, i: usize) -> Material {
        self.particles.map_or(self.global, |m| m[i])
    }

    /// The material of contact `c` (see the type's doc for the rule). Its indices must be in
    /// the table's range.
    pub fn pair(&self, c: &Contact) -> Material {
        let own = self.particle(c.i);
        match c.other {
            Partner::Particle(j) => Material::combine(own, self.particle(j)),
            Partner::Collider(k) => {
                let s = self.colliders[k].surface();
                Material {
                    restitution: s.restitution().unwrap_or(own.restitution),
                    friction: s.friction().unwrap_or(own.friction),
                }
            }
        }
    }
}

/// The impulse applied at one contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Impulse {
    /// Normal impulse j, N·s (> 0).
    pub normal: f64,
    /// Magnitude of the friction impulse j_t, N·s (≤ μ j).
    pub tangent: f64,
    /// The impulse vector on particle i, J = j n − j_t t (t the sliding direction), N·s; the
    /// partner particle receives −J.
    pub vector: [f64; 3],
    /// The restitution used (0 below the restitution threshold).
    pub restitution: f64,
    /// Kinetic energy removed, J (≥ 0 unless a pinned particle moves and does work).
    pub energy_lost: f64,
}

/// The restitution and friction impulse of contact `c` at the velocities `v` (m/s, 3 per
/// particle) if the pair approaches (current u_n < 0), without applying it; `None` otherwise,
/// and when neither side can move. `inv_mass`: 1/kg, 0 for pinned. Approach speeds |u_n|
/// below `restitution_threshold` (m/s) use e = 0. The contact's own `u_n` is not read: the
/// current one is computed from `v`. `spin`: what the bodies' turning adds to the contact
/// (`collide/spin.rs`), `None` without spin. Indices must be in range.
pub fn restitution_impulse(
    c: &Contact,
    v: &[f64],
    inv_mass: &[f64],
    material: Material,
    restitution_threshold: f64,
    spin: Option<ContactSpin>,
) -> Option<Impulse> {
    let partner = c.partner_particle();
    let (wi, wj) = (inv_mass[c.i], partner.map_or(0.0, |j| inv_mass[j]));
    let w = wi + wj;
    if w == 0.0 {
        return None;
    }
    let n = c.normal;
    let vi = vec3::get(v, c.i);
    let vj = partner.map_or(c.wall_velocity, |j| vec3::get(v, j));
    let u = vec3::sub(vi, vj);
    let u_n = vec3::dot(u, n);
    if u_n >= 0.0 || u_n.is_nan() {
        return None;
    }
    let e = if bounces(u_n, restitution_threshold) {
        material.restitution
    } else {
        0.0
    };
    let j_n = -(1.0 + e) * u_n / w;

    // Friction: the impulse that stops the sliding, capped by the Coulomb cone μ j.
    let u_t = vec3::sub(u, vec3::scale(u_n, n));
    let (u_t, w_t) = match spin {
        Some(s) => (vec3::sub(u_t, s.turning), w + s.w_rot),
        None => (u_t, w),
    };
    let slide = vec3::norm(u_t);
    let (j_t, t) = if material.friction > 0.0 && slide > 0.0 {
        ((slide / w_t).min(material.friction * j_n), vec3::scale(1.0 / slide, u_t))
    } else {
        (0.0, [0.0; 3])
    };
    let impulse = vec3::sub(vec3::scale(j_n, n), vec3::scale(j_t, t));

    // Energy (module doc): ½ (1 − e²) μ u_n² along n, j_t (|u_t| − ½ w j_t) across. These
    // assume both bodies' kinetic energies change by v·J + ½ w J²; a pinned particle's does
    // not change, so if one moves (kinematically) the v·J it would have taken is put back.
    let mut lost = 0.5 * (1.0 - e * e) * u_n * u_n / w + j_t * (slide - 0.5 * w_t * j_t);
    if wi == 0.0 {
        lost += vec3::dot(vi, impulse);
    }
    if wj == 0.0 && vj != [0.0; 3] {
        // a pinned particle or a collider moving: the particles' own loss
        lost -= vec3::dot(vj, impulse);
    }
    Some(Impulse {
        normal: j_n,
        tangent: j_t,
        vector: impulse,
        restitution: e,
        energy_lost: lost,
    })
}

/// Newton's law's threshold, the one rule for every impact and every end-of-step contact:
/// a pair meeting at normal velocity u_n (m/s, < 0 approaching) bounces, u_n⁺ = −e u_n⁻, when
/// it approaches at least as fast as `threshold` (m/s); a slower meeting is plastic (e = 0),
/// which is what keeps a resting body from hopping on rounding.
pub(crate) fn bounces(u_n: f64, threshold: f64) -> bool {
    u_n < 0.0 && -u_n >= threshold
}

/// The speed below which a pair counts as not approaching, m/s: slower approaches are left
/// to the end-of-step contact solve (`impulse/impacts.rs`, `least_impact_speed`), and
/// that solve's convergence tolerance (`impulse/end_of_step.rs`, `soft_step`).
pub(crate) const VELOCITY_TOLERANCE: f64 = 1e-9;

#[cfg(test)]
#[path = "tests/response.rs"]
mod tests;
