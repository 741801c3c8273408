//! Response: Newton's restitution by impulses, Coulomb friction, the materials that set them
//! (the pair rule, [`MaterialTable`]) and a sequential-impulse resolver. The contact solvers
//! [`hold`] and [`separate`] (the position correction that removes overlap) live in
//! `contact_solver.rs` and are re-exported here.
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
//! Particles have no rotational inertia, so a tangential impulse j_t changes the tangential
//! relative velocity u_t by (w_i + w_j) j_t, the same effective mass as along the normal.
//! Coulomb friction gives the impulse that stops the sliding, |u_t| / (w_i + w_j), unless it
//! exceeds the cone μ j; then it slides with j_t = μ j. Either way it opposes u_t and changes
//! the kinetic energy by −j_t |u_t| + ½ (w_i + w_j) j_t² ≤ −½ j_t |u_t| ≤ 0.

use super::colliders::Collider;
use super::contact::{Contact, Partner};
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
    /// the table's range ([`resolve`] checks them before use).
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

    /// Errors unless the table covers `n` particles and every collider the contacts name.
    pub(super) fn check(&self, n: usize, contacts: &[Contact]) -> Result<(), Error> {
        if let Some(m) = self.particles {
            if m.len() != n {
                return Err(Error::invalid(
                    "materials.particles",
                    format!("{} values", m.len()),
                    format!("one per particle ({n})"),
                ));
            }
        }
        for (p, c) in contacts.iter().enumerate() {
            if let Partner::Collider(k) = c.other {
                if k >= self.colliders.len() {
                    return Err(Error::invalid(
                        format!("contacts[{p}].other"),
                        format!("Collider({k})"),
                        format!("the material table has {} colliders", self.colliders.len()),
                    ));
                }
            }
        }
        Ok(())
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

/// Applies the restitution and friction impulse of contact `c` to the velocities `v` (m/s, 3
/// per particle) if the pair approaches (current u_n < 0), and returns it; `None` otherwise,
/// and when neither side can move. `inv_mass`: 1/kg, 0 for pinned. Approach speeds
/// |u_n| below `restitution_threshold` (m/s) use e = 0. The contact's own `u_n` is not read:
/// the current one is computed from `v`. Indices must be in range.
pub fn apply_impulse(
    c: &Contact,
    v: &mut [f64],
    inv_mass: &[f64],
    material: Material,
    restitution_threshold: f64,
) -> Option<Impulse> {
    impulse_if_faster(c, v, inv_mass, material, restitution_threshold, 0.0)
}

/// The restitution and friction impulse of contact `c` at the velocities `v` (m/s, 3 per
/// particle) if the pair approaches, without applying it: what [`apply_impulse`] applies.
/// Indices must be in range.
pub fn restitution_impulse(
    c: &Contact,
    v: &[f64],
    inv_mass: &[f64],
    material: Material,
    restitution_threshold: f64,
) -> Option<Impulse> {
    impulse_of(c, v, inv_mass, material, restitution_threshold, 0.0)
}

/// [`apply_impulse`] when the current approach speed −u_n exceeds `tolerance`.
fn impulse_if_faster(
    c: &Contact,
    v: &mut [f64],
    inv_mass: &[f64],
    material: Material,
    restitution_threshold: f64,
    tolerance: f64,
) -> Option<Impulse> {
    let impulse = impulse_of(c, v, inv_mass, material, restitution_threshold, tolerance)?;
    vec3::add_scaled(v, c.i, inv_mass[c.i], impulse.vector);
    if let Some(j) = c.partner_particle() {
        vec3::add_scaled(v, j, -inv_mass[j], impulse.vector);
    }
    Some(impulse)
}

/// [`restitution_impulse`] when the current approach speed −u_n exceeds `tolerance`.
fn impulse_of(
    c: &Contact,
    v: &[f64],
    inv_mass: &[f64],
    material: Material,
    restitution_threshold: f64,
    tolerance: f64,
) -> Option<Impulse> {
    let partner = c.partner_particle();
    let (wi, wj) = (inv_mass[c.i], partner.map_or(0.0, |j| inv_mass[j]));
    let w = wi + wj;
    if w == 0.0 {
        return None;
    }
    let n = c.normal;
    let vi = vec3::get(v, c.i);
    let vj = partner.map_or([0.0; 3], |j| vec3::get(v, j));
    let u = vec3::sub(vi, vj);
    let u_n = vec3::dot(u, n);
    if u_n >= -tolerance || u_n.is_nan() {
        return None;
    }
    let e = if -u_n < restitution_threshold {
        0.0
    } else {
        material.restitution
    };
    let j_n = -(1.0 + e) * u_n / w;

    // Friction: the impulse that stops the sliding, capped by the Coulomb cone μ j.
    let u_t = vec3::sub(u, vec3::scale(u_n, n));
    let slide = vec3::norm(u_t);
    let (j_t, t) = if material.friction > 0.0 && slide > 0.0 {
        ((slide / w).min(material.friction * j_n), vec3::scale(1.0 / slide, u_t))
    } else {
        (0.0, [0.0; 3])
    };
    let impulse = vec3::sub(vec3::scale(j_n, n), vec3::scale(j_t, t));

    // Energy (module doc): ½ (1 − e²) μ u_n² along n, j_t (|u_t| − ½ w j_t) across. These
    // assume both bodies' kinetic energies change by v·J + ½ w J²; a pinned particle's does
    // not change, so if one moves (kinematically) the v·J it would have taken is put back.
    let mut lost = 0.5 * (1.0 - e * e) * u_n * u_n / w + j_t * (slide - 0.5 * w * j_t);
    if wi == 0.0 {
        lost += vec3::dot(vi, impulse);
    }
    if partner.is_some() && wj == 0.0 {
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

/// Settings of [`resolve`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResolveParams {
    /// Approach speeds below this use e = 0, m/s (≥ 0; default 0). Resting contacts under
    /// gravity approach at about g·dt each step; a threshold a few times that stops them
    /// bouncing in place.
    pub restitution_threshold: f64,
    /// Contacts approaching slower than this count as resolved, m/s (≥ 0; default 1e-9).
    pub tolerance: f64,
    /// Most sweeps over the contacts (≥ 1; default 100).
    pub max_iterations: usize,
}

impl Default for ResolveParams {
    fn default() -> Self {
        ResolveParams {
            restitution_threshold: 0.0,
            tolerance: 1e-9,
            max_iterations: 100,
        }
    }
}

/// What [`resolve`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ResolveStats {
    /// Sweeps over the contact list; when converged, the last found nothing to do.
    pub iterations: usize,
    /// Impulses applied.
    pub impulses: usize,
    /// Whether no contact approaches faster than the tolerance at the end.
    pub converged: bool,
    /// The fastest approach −u_n left at the end, m/s (0 if none approaches).
    pub max_approach_speed: f64,
    /// Σ of the particle–particle impulses as applied to each of the two particles (+J to i
    /// and −J to j), N·s: zero to rounding since action equals reaction.
    pub particle_impulse_sum: [f64; 3],
    /// Σ of the impulses the colliders gave the particles, N·s.
    pub collider_impulse_sum: [f64; 3],
    /// Σ of the impulses pinned particles gave movable ones, N·s. Like the colliders', these
    /// come from outside the movable particles: Σ m Δv over the movable particles equals
    /// `collider_impulse_sum + pinned_impulse_sum`.
    pub pinned_impulse_sum: [f64; 3],
    /// Kinetic energy removed by all impulses, J.
    pub kinetic_energy_lost: f64,
}

/// Sequential impulses (Gauss–Seidel over the contacts): sweeps `contacts` in their order, applying
/// [`apply_impulse`] with the current velocities at each contact that approaches faster than
/// the tolerance, until a sweep applies none or `max_iterations` sweeps are done.
///
/// `v`: velocities, m/s (3 per particle), updated in place; `inv_mass`: 1/kg (0 for pinned);
/// `materials`: each contact's restitution and friction. The order of the contacts is the
/// order of the impulses, so the same list gives the same result bit for bit.
///
/// Using the current u_n pair by pair propagates momentum along chains: five equal balls in
/// a row, touching, e = 1, the first moving — each impulse hands the whole velocity on, and
/// the last ball leaves with the first's velocity while the others rest, as Newton's cradle
/// does. (Solving all contacts at once would share the momentum out instead.) A contact
/// between two immovable bodies is skipped.
pub fn resolve(
    contacts: &[Contact],
    v: &mut [f64],
    inv_mass: &[f64],
    materials: &MaterialTable,
    params: &ResolveParams,
) -> Result<ResolveStats, Error> {
    check_contacts(contacts, inv_mass.len())?;
    check_len("v", v.len(), inv_mass.len())?;
    materials.check(inv_mass.len(), contacts)?;
    if !(params.restitution_threshold.is_finite() && params.restitution_threshold >= 0.0) {
        return Err(Error::invalid(
            "restitution_threshold",
            params.restitution_threshold,
            "must be finite and >= 0 m/s",
        ));
    }
    if !(params.tolerance.is_finite() && params.tolerance >= 0.0) {
        return Err(Error::invalid("tolerance", params.tolerance, "must be finite and >= 0 m/s"));
    }
    if params.max_iterations == 0 {
        return Err(Error::invalid("max_iterations", 0, "at least one sweep"));
    }

    let mut stats = ResolveStats::default();
    for sweep in 1..=params.max_iterations {
        stats.iterations = sweep;
        let before = stats.impulses;
        for c in contacts {
            let material = materials.pair(c);
            let Some(imp) = impulse_if_faster(c, v, inv_mass, material, params.restitution_threshold, params.tolerance) else {
                continue;
            };
            stats.impulses += 1;
            stats.kinetic_energy_lost += imp.energy_lost;
            let add = |sum: &mut [f64; 3], sign: f64| sum.iter_mut().zip(imp.vector).for_each(|(s, j)| *s += sign * j);
            match c.other {
                Partner::Particle(p) => {
                    add(&mut stats.particle_impulse_sum, 1.0); // on i
                    add(&mut stats.particle_impulse_sum, -1.0); // on p
                                                                // A pinned side gives the other its impulse from outside the movable
                                                                // particles (both pinned never get here: nothing can move).
                    if inv_mass[p] == 0.0 {
                        add(&mut stats.pinned_impulse_sum, 1.0);
                    } else if inv_mass[c.i] == 0.0 {
                        add(&mut stats.pinned_impulse_sum, -1.0);
                    }
                }
                Partner::Collider(_) => add(&mut stats.collider_impulse_sum, 1.0),
            }
        }
        if stats.impulses == before {
            break;
        }
    }
    stats.max_approach_speed = contacts
        .iter()
        .filter(|c| inv_mass[c.i] + c.partner_particle().map_or(0.0, |j| inv_mass[j]) > 0.0)
        .map(|c| {
            let vj = c.partner_particle().map_or([0.0; 3], |j| vec3::get(v, j));
            -vec3::dot(vec3::sub(vec3::get(v, c.i), vj), c.normal)
        })
        .fold(0.0, f64::max);
    stats.converged = stats.max_approach_speed <= params.tolerance;
    Ok(stats)
}

pub(super) fn check_len(name: &str, len: usize, n: usize) -> Result<(), Error> {
    if len == 3 * n {
        return Ok(());
    }
    Err(Error::invalid(
        name,
        format!("{len} values"),
        format!("3 per particle ({} for the {n} inverse masses)", 3 * n),
    ))
}

pub(super) fn check_contacts(contacts: &[Contact], n: usize) -> Result<(), Error> {
    for (p, c) in contacts.iter().enumerate() {
        let j = c.partner_particle();
        if c.i >= n || j.is_some_and(|j| j >= n || j == c.i) {
            return Err(Error::invalid(
                format!("contacts[{p}]"),
                format!("particle {} with {:?}", c.i, c.other),
                format!("contacts join distinct particles of the {n} (indices < {n})"),
            ));
        }
        if let Some((k, value)) = vec3::first_non_finite(&c.normal) {
            return Err(Error::invalid(
                format!("contacts[{p}].normal[{k}]"),
                value,
                "normals must be finite",
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
#[path = "tests/response.rs"]
mod tests;
