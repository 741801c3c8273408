//! The test oracles of the collide stage: plain, slow references that the step's own paths
//! are checked against, compiled for the unit tests only (`#[cfg(test)]` in `collide/mod.rs`;
//! nothing in a step calls them, see the map there).
//!
//! - [`all_pairs`], the O(N²) pair search: the grid's partner lists ([`Grid::prepare`],
//!   [`Grid::partners`], [`Grid::partners_from`]), from which the neighbour lists are built,
//!   must give exactly its pairs ([`grid_pairs`] gathers them as the lists do);
//! - [`sphere_contacts`] and [`collider_contacts`]: every contact of a list of pairs and of
//!   the colliders, in the order of a full search (the contacts the contact force's
//!   neighbour list finds at each evaluation must be these);
//! - [`SpringDashpotLaw`]: the linear spring–dashpot law on its own, whose restitution the tests
//!   measure, and [`restitution_of_damping`], the inverse of
//!   [`damping_ratio`](super::contact_force::spring_dashpot::damping_ratio).
//!
//! The tests that use them, and the test that the map of `collide/mod.rs` names only what a
//! step calls, are included at the end (`collide/tests/`).

use super::broad_phase::{check_inputs, touches, Grid};
use super::contact::Contact;
use super::contact_force::spring_dashpot::{damping_ratio, dashpot_coefficient, spring_dashpot_force};
use super::domain::Domain;
use super::{pair_contact, Collider};
use crate::error::Error;
use crate::particles::check_per_particle;
use crate::vec3;

/// A candidate pair (i, j) of particle indices, i < j.
pub(crate) type Pair = (usize, usize);

/// The O(N²) reference for the grid's searches ([`Grid::partners`]): every pair (i, j),
/// i < j, with |x_i − x_j| < r_i + r_j + `margin` (the minimum image along the domain's
/// periodic axes), sorted by i, then j, found by testing every pair with the grid's own pair
/// test. Same arguments and the same errors as [`Grid::prepare`].
pub(crate) fn all_pairs(x: &[f64], radius: &[f64], domain: &Domain, margin: f64, pairs: &mut Vec<Pair>) -> Result<(), Error> {
    check_inputs(x, radius, margin)?;
    pairs.clear();
    let n = radius.len();
    for i in 0..n {
        for j in i + 1..n {
            if touches(domain, vec3::get(x, i), vec3::get(x, j), radius[i], radius[j], margin) {
                pairs.push((i, j));
            }
        }
    }
    Ok(())
}

/// The pairs (i, j), i < j, sorted, that `grid` finds after [`Grid::prepare`] (which it runs
/// here), gathered as the neighbour lists gather them: each particle's partners from
/// [`Grid::partners`] (a full list: each pair must be found from both of its sides, exactly
/// once each, in ascending order) and from [`Grid::partners_from`] with `lowest` = i + 1 (a
/// half list: each pair once, from its lower index), which must agree.
pub(crate) fn grid_pairs(grid: &mut Grid, x: &[f64], radius: &[f64], domain: &Domain, margin: f64) -> Vec<Pair> {
    let mut half = Vec::new();
    if !grid.prepare(x, radius, domain, margin).unwrap() {
        return half;
    }
    let mut full = Vec::new();
    for i in 0..radius.len() {
        let mut out = Vec::new();
        grid.partners(i, x, radius, domain, margin, &mut out);
        assert!(
            out.windows(2).all(|w| w[0] < w[1]),
            "partners of {i} not strictly ascending: {out:?}"
        );
        full.extend(out.iter().map(|&j| (i, j as usize)));
        out.clear();
        grid.partners_from(i, i + 1, x, radius, domain, margin, &mut out);
        assert!(
            out.windows(2).all(|w| w[0] < w[1]),
            "half-list partners of {i} not strictly ascending: {out:?}"
        );
        half.extend(out.iter().map(|&j| (i, j as usize)));
    }
    let mut lower: Vec<Pair> = full.iter().filter(|&&(i, j)| i < j).copied().collect();
    let mut upper: Vec<Pair> = full.iter().filter(|&&(i, j)| i > j).map(|&(i, j)| (j, i)).collect();
    lower.sort_unstable();
    upper.sort_unstable();
    assert_eq!(lower, upper, "a pair found from one side only");
    assert_eq!(half, lower, "the half list differs from the full one");
    half
}

/// Appends to `contacts` (cleared first) the contact of each pair of `pairs` whose distance is
/// below r_i + r_j + `tolerance`, in the order of `pairs`, with `i` the pair's first index
/// ([`pair_contact`] of each).
///
/// `x`: positions, m, and `v`: velocities, m/s (3 per particle); `radius`: m (one per
/// particle); `tolerance`: m (finite, ≥ 0; 0 keeps only overlapping pairs). Errors name a
/// buffer of the wrong length, a pair with an index out of range or i = j, or a bad
/// tolerance.
pub(crate) fn sphere_contacts(
    x: &[f64],
    v: &[f64],
    radius: &[f64],
    pairs: &[Pair],
    domain: &Domain,
    tolerance: f64,
    contacts: &mut Vec<Contact>,
) -> Result<(), Error> {
    let n = radius.len();
    for (name, len) in [("x", x.len()), ("v", v.len())] {
        check_per_particle(name, len, 3, n, "radii")?;
    }
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(Error::invalid(
            "tolerance",
            tolerance,
            "the contact tolerance must be finite and >= 0 m",
        ));
    }
    if let Some(p) = pairs.iter().position(|&(i, j)| i >= n || j >= n || i == j) {
        return Err(Error::invalid(
            format!("pairs[{p}]"),
            format!("{:?}", pairs[p]),
            format!("pairs join two distinct particles of the {n} (indices < {n})"),
        ));
    }
    contacts.clear();
    contacts.extend(
        pairs
            .iter()
            .filter_map(|&(i, j)| pair_contact(i, j, x, v, radius, domain, tolerance)),
    );
    Ok(())
}

/// Appends to `contacts` (not cleared, so that it can follow the particle pairs' contacts)
/// every particle–collider contact within `tolerance`, particle by particle, then collider
/// by collider, then wall by wall: `Partner::Collider(k)` is the index in `colliders`, and
/// u_n = (v_i − u)·n, u the collider surface's velocity there ([`Collider::contact`]).
///
/// `x`, `v`: positions (m) and velocities (m/s), 3 per particle; `radius`: m, one per
/// particle; `tolerance`: m (finite, ≥ 0).
pub(crate) fn collider_contacts(
    colliders: &[Collider],
    x: &[f64],
    v: &[f64],
    radius: &[f64],
    tolerance: f64,
    contacts: &mut Vec<Contact>,
) -> Result<(), Error> {
    let n = radius.len();
    for (name, len) in [("x", x.len()), ("v", v.len())] {
        if len != 3 * n {
            return Err(Error::invalid(
                name,
                format!("{len} values"),
                format!("3 per particle ({} for the {n} radii)", 3 * n),
            ));
        }
    }
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        return Err(Error::invalid(
            "tolerance",
            tolerance,
            "the contact tolerance must be finite and >= 0 m",
        ));
    }
    for (i, &r) in radius.iter().enumerate() {
        let (p, vi) = (vec3::get(x, i), vec3::get(v, i));
        for (k, collider) in colliders.iter().enumerate() {
            collider.for_each_touch(p, r, tolerance, |t| contacts.push(collider.contact(k, t, i, p, vi, r)));
        }
    }
    Ok(())
}

/// The restitution of the contact oscillator with damping ratio ζ (≥ 0):
/// e = exp(−ζ π / √(1 − ζ²)) for ζ < 1, 0 from ζ = 1 on (no rebound). The inverse of
/// [`damping_ratio`] (see `collide/contact_force/spring_dashpot.rs` for the derivation).
pub(crate) fn restitution_of_damping(zeta: f64) -> f64 {
    if zeta >= 1.0 {
        0.0
    } else {
        (-zeta * std::f64::consts::PI / (1.0 - zeta * zeta).sqrt()).exp()
    }
}

/// A linear spring–dashpot contact law with stiffness k_n and the damping that gives a
/// restitution e for every pair (the derivation in `collide/contact_force/spring_dashpot.rs`):
/// the law alone, on a list of contacts, whose restitution the tests measure. Its force is
/// [`spring_dashpot_force`], the one the world's contact force calls for each contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SpringDashpotLaw {
    stiffness: f64,
    zeta: f64,
}

impl SpringDashpotLaw {
    /// A law of normal stiffness `stiffness` (k_n, N/m, finite, > 0) and restitution
    /// `restitution` (e ∈ [0, 1]).
    pub(crate) fn new(stiffness: f64, restitution: f64) -> Result<Self, Error> {
        if !(stiffness.is_finite() && stiffness > 0.0) {
            return Err(Error::invalid(
                "stiffness",
                stiffness,
                "the contact stiffness must be finite and > 0 N/m",
            ));
        }
        Ok(SpringDashpotLaw {
            stiffness,
            zeta: damping_ratio(restitution)?,
        })
    }

    /// ζ, the damping ratio (see [`damping_ratio`]).
    pub(crate) fn damping_ratio(&self) -> f64 {
        self.zeta
    }

    /// ω₀² = k_n / m_eff, 1/s², of a contact with reduced mass `m_eff` (kg). With inverse
    /// masses, ω₀² = k_n (w_i + w_j), see [`SpringDashpotLaw::contact_omega_squared`].
    pub(crate) fn omega_squared(&self, m_eff: f64) -> f64 {
        self.stiffness / m_eff
    }

    /// γ_n = 2 ζ √(k_n / m_eff), 1/s, for reduced mass `m_eff` (kg).
    pub(crate) fn damping_rate(&self, m_eff: f64) -> f64 {
        2.0 * self.zeta * self.omega_squared(m_eff).sqrt()
    }

    /// t_c = π / ω_d (s), how long a collision lasts for reduced mass `m_eff` (kg); infinite
    /// for e = 0. An integrator resolves e well with 50 or more steps per contact.
    pub(crate) fn contact_duration(&self, m_eff: f64) -> f64 {
        let omega_d = self.omega_squared(m_eff).sqrt() * (1.0 - self.zeta * self.zeta).sqrt();
        std::f64::consts::PI / omega_d
    }

    /// F_n = k_n δ − m_eff γ_n u_n, N, pushing the pair apart when > 0; for overlap `overlap`
    /// (δ, m), normal velocity `u_n` (m/s, < 0 approaching) and reduced mass `m_eff` (kg).
    /// The same arithmetic as the world's contact force: [`spring_dashpot_force`] with
    /// c_n = [`dashpot_coefficient`]`(k_n, ζ, 1/m_eff)`.
    pub(crate) fn normal_force(&self, overlap: f64, u_n: f64, m_eff: f64) -> f64 {
        spring_dashpot_force(
            self.stiffness,
            dashpot_coefficient(self.stiffness, self.zeta, 1.0 / m_eff),
            overlap,
            u_n,
        )
    }

    /// ω₀² = k_n (w_i + w_j), 1/s², of contact `c`, with `inv_mass` the inverse masses (1/kg;
    /// 0 pinned, and a collider's is 0): the rate to keep h ω₀ below an explicit method's
    /// stability limit. A particle pressed by several contacts at once oscillates faster (up
    /// to the sum of its contacts' rates), as in a spring network. Indices must be in range.
    pub(crate) fn contact_omega_squared(&self, c: &Contact, inv_mass: &[f64]) -> f64 {
        self.stiffness * (inv_mass[c.i] + c.partner_particle().map_or(0.0, |j| inv_mass[j]))
    }

    /// The largest ω₀² (1/s²) over `contacts`, 0 without contacts.
    pub(crate) fn max_omega_squared(&self, contacts: &[Contact], inv_mass: &[f64]) -> f64 {
        contacts
            .iter()
            .map(|c| self.contact_omega_squared(c, inv_mass))
            .fold(0.0, f64::max)
    }

    /// Adds each overlapping contact's force F_n n to particle i's entries of `f` (N, 3 per
    /// particle) and −F_n n to its partner particle's (a collider takes the reaction), so that
    /// particle pairs change no total momentum. Contacts with δ ≤ 0 add nothing; nor does a
    /// contact of two immovable bodies (w_i + w_j = 0). The contacts must describe the state
    /// the force is wanted at (recompute them at each force evaluation).
    ///
    /// m_eff γ_n = 2 ζ √(k_n m_eff) = 2 ζ √(k_n / (w_i + w_j)).
    pub(crate) fn accumulate(&self, contacts: &[Contact], inv_mass: &[f64], f: &mut [f64]) -> Result<(), Error> {
        let n = inv_mass.len();
        check_per_particle("f", f.len(), 3, n, "inverse masses")?;
        if let Some(p) = contacts
            .iter()
            .position(|c| c.i >= n || c.partner_particle().is_some_and(|j| j >= n || j == c.i))
        {
            return Err(Error::invalid(
                format!("contacts[{p}]"),
                format!("particle {} with {:?}", contacts[p].i, contacts[p].other),
                format!("contacts join distinct particles of the {n} (indices < {n})"),
            ));
        }
        for c in contacts {
            let w = inv_mass[c.i] + c.partner_particle().map_or(0.0, |j| inv_mass[j]);
            if c.overlap <= 0.0 || c.overlap.is_nan() || w == 0.0 {
                continue;
            }
            let force = self.stiffness * c.overlap - 2.0 * self.zeta * (self.stiffness / w).sqrt() * c.u_n;
            vec3::add_scaled(f, c.i, force, c.normal);
            if let Some(j) = c.partner_particle() {
                vec3::add_scaled(f, j, -force, c.normal);
            }
        }
        Ok(())
    }
}

/// A small deterministic generator for the tests (splitmix64), uniform in [lo, hi).
pub(crate) struct Rng(pub u64);

impl Rng {
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        lo + (hi - lo) * ((z >> 11) as f64 / (1u64 << 53) as f64)
    }
}

#[path = "tests/broad_phase_finds_every_pair.rs"]
mod broad_phase_finds_every_pair;
#[path = "tests/impulse_list.rs"]
mod impulse_list;
#[path = "tests/map.rs"]
mod map;
#[path = "tests/spring_dashpot_contacts_in_a_world.rs"]
mod spring_dashpot_contacts_in_a_world;
#[path = "tests/spring_dashpot_restitution_matches_request.rs"]
mod spring_dashpot_restitution_matches_request;
