//! The contact solvers that follow the impulse law of [`response`](super::response): `hold`
//! (projected Gauss–Seidel with accumulated, warm-startable totals and velocity targets: the
//! contact forces of touching contacts over a step) and `separate` (the position correction
//! that removes overlap), each also grouped (`hold_grouped`, `separate_grouped`: contacts
//! visited colour by colour on all threads, see `sweeps`). Their public paths are
//! `collide::response::…` and `collide::…`, re-exported from there.

use super::contact::{Contact, Partner};
use super::response::{check_contacts, check_len, MaterialTable};
use super::sweeps::{sweeps, Ends, SweepGroup};
use crate::error::Error;
use crate::vec3;

/// Settings of [`hold`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoldParams {
    /// A sweep whose largest velocity change is at most this has converged, m/s (≥ 0;
    /// default 0: until a sweep changes nothing, which a resting stack reaches exactly).
    pub tolerance: f64,
    /// Most sweeps over the contacts (≥ 1; default 50). A world starts each step's solve
    /// from the last step's impulses, so the sweeps add up over the steps of a resting heap;
    /// a solve cut short leaves a slight approach that the next step's continues from.
    /// Measured on a settled heap of 400 balls (1,200 contacts): 50 sweeps a step keep it at
    /// rest (the booked loss grows by 5·10⁻⁵ J a step), where started from zero it took
    /// 300–2,000 sweeps to converge to 10⁻⁵ m/s.
    pub max_iterations: usize,
}

impl Default for HoldParams {
    fn default() -> Self {
        HoldParams {
            tolerance: 0.0,
            max_iterations: 50,
        }
    }
}

/// What [`hold`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct HoldStats {
    /// Sweeps over the contacts.
    pub iterations: usize,
    /// Whether the last sweep changed no velocity by more than the tolerance.
    pub converged: bool,
    /// The largest velocity change of the last sweep, m/s.
    pub last_change: f64,
    /// Contacts that carry a nonzero impulse at the end.
    pub active: usize,
    /// Σ of the impulses the colliders gave the particles, N·s.
    pub collider_impulse_sum: [f64; 3],
    /// Σ of the impulses pinned particles gave movable ones, N·s.
    pub pinned_impulse_sum: [f64; 3],
}

/// The contact forces of touching contacts over one step, as impulses: projected Gauss–Seidel
/// with accumulated impulses (Catto's sequential impulses with clamping of the total) on
/// the velocities `v` (m/s, 3 per particle, updated in place).
///
/// Each contact c gets a total impulse P_c = λ_c n + t_c on i (−P_c on a partner particle)
/// with
///
/// ```text
///   λ_c ≥ 0,   u_n ≥ b_c,   λ_c (u_n − b_c) = 0          (normal: push only, complementary)
///   |t_c| ≤ μ λ_c, t_c opposing the sliding, u_t = 0 while |t_c| < μ λ_c   (Coulomb)
/// ```
///
/// where `targets[c]` = b_c (m/s) is the least normal velocity the contact allows at the end:
/// 0 for a resting contact, −e u_n⁻ > 0 for an impact by Newton's law (Box2D's restitution
/// as a velocity target), < 0 to let a pair keep approaching. Each visit of a contact moves its totals to what would satisfy it alone, clamped to
/// λ ≥ 0 and to the cone: unlike [`resolve`](super::response::resolve), whose impulses only ever push, a total can shrink
/// again when other contacts took over its load, so at convergence no contact pushes
/// while the pair separates faster than b_c (the impulses do no spurious work).
///
/// `impulses`: on entry, each contact's starting total if it holds one per contact (an
/// earlier step's totals, for warm starting: a resting contact carries the same load from
/// step to step, and starting from it takes few sweeps where starting from zero takes
/// hundreds in a deep heap), otherwise zeros are used; each starting total is first
/// projected onto the current normal, λ ≥ 0 and the cone, and applied. On return, each
/// contact's total impulse vector on i. Indices must be valid (they are checked, as in
/// [`resolve`](super::response::resolve)); a contact of two immovable bodies is skipped.
pub fn hold(
    contacts: &[Contact],
    targets: &[f64],
    v: &mut [f64],
    inv_mass: &[f64],
    materials: &MaterialTable,
    params: &HoldParams,
    impulses: &mut Vec<[f64; 3]>,
) -> Result<HoldStats, Error> {
    let all = [SweepGroup::in_order(0..contacts.len())];
    let held = HoldContacts {
        contacts,
        targets,
        inv_mass,
        materials,
    };
    hold_grouped(held, v, params, impulses, &all)
}

/// What [`hold_grouped`] holds, as [`hold`] takes it: the contacts, each one's target b_c
/// (`targets`, m/s, one per contact), the particles' inverse masses (1/kg, 0 for pinned) and
/// the materials.
#[derive(Clone, Copy)]
pub(crate) struct HoldContacts<'a> {
    pub contacts: &'a [Contact],
    pub targets: &'a [f64],
    pub inv_mass: &'a [f64],
    pub materials: &'a MaterialTable<'a>,
}

/// [`hold`] with each sweep visiting the contacts group by group (`groups` cover the contacts
/// in order): a group of contacts that share no movable particle (`together`) is visited
/// all at once, on all threads, the others one contact after the other. The result does not
/// depend on the thread count: the contacts of a `together` group read and write disjoint
/// velocities, so visiting them at once is the same as visiting them in order.
pub(crate) fn hold_grouped(
    held: HoldContacts<'_>,
    v: &mut [f64],
    params: &HoldParams,
    impulses: &mut Vec<[f64; 3]>,
    groups: &[SweepGroup],
) -> Result<HoldStats, Error> {
    let HoldContacts {
        contacts,
        targets,
        inv_mass,
        materials,
    } = held;
    check_contacts(contacts, inv_mass.len())?;
    check_len("v", v.len(), inv_mass.len())?;
    materials.check(inv_mass.len(), contacts)?;
    if targets.len() != contacts.len() {
        return Err(Error::invalid(
            "targets",
            format!("{} values", targets.len()),
            format!("one per contact ({})", contacts.len()),
        ));
    }
    if let Some(p) = targets.iter().position(|b| !b.is_finite()) {
        return Err(Error::invalid(
            format!("targets[{p}]"),
            targets[p],
            "a contact's least normal velocity must be finite m/s",
        ));
    }
    if !(params.tolerance.is_finite() && params.tolerance >= 0.0) {
        return Err(Error::invalid("tolerance", params.tolerance, "must be finite and >= 0 m/s"));
    }
    if params.max_iterations == 0 {
        return Err(Error::invalid("max_iterations", 0, "at least one sweep"));
    }
    if impulses.len() != contacts.len() {
        impulses.clear();
        impulses.resize(contacts.len(), [0.0; 3]);
    }
    let ends: Vec<Option<Ends>> = contacts.iter().map(|c| Ends::of(c, inv_mass)).collect();
    let rows: Vec<Row> = contacts
        .iter()
        .zip(targets)
        .map(|(c, &b)| {
            let (wi, wj) = (inv_mass[c.i], c.partner_particle().map_or(0.0, |j| inv_mass[j]));
            Row {
                wi,
                wj,
                inv_w: 1.0 / (wi + wj),
                mu: materials.pair(c).friction(),
                n: c.normal,
                b,
            }
        })
        .collect();
    // The totals (λ, t): normal λ ≥ 0 along n and the tangential part t ⊥ n, |t| ≤ μ λ. Warm
    // start: each starting total, projected onto them, is applied before the sweeps.
    let mut totals = vec![(0.0, [0.0; 3]); contacts.len()];
    for (k, (r, e)) in rows.iter().zip(&ends).enumerate() {
        let start = impulses[k];
        let Some(e) = e else { continue };
        if start == [0.0; 3] || vec3::first_non_finite(&start).is_some() {
            continue;
        }
        let lambda = vec3::dot(start, r.n).max(0.0);
        let mut t = vec3::sub(start, vec3::scale(vec3::dot(start, r.n), r.n));
        let (len, cap) = (vec3::norm(t), r.mu * lambda);
        if len > cap {
            t = vec3::scale(if len > 0.0 { cap / len } else { 0.0 }, t);
        }
        totals[k] = (lambda, t);
        let (mut vi, mut vj) = e.load(v);
        r.apply(e.j.is_some(), &mut vi, &mut vj, vec3::add(vec3::scale(lambda, r.n), t));
        e.store(v, vi, vj);
    }
    let mut stats = HoldStats::default();
    let visit = |k: usize, total: &mut (f64, [f64; 3]), vi: &mut [f64; 3], vj: &mut [f64; 3]| {
        rows[k].visit(ends[k].is_some_and(|e| e.j.is_some()), vi, vj, total)
    };
    let done = sweeps(groups, &ends, v, &mut totals, params.max_iterations, params.tolerance, visit);
    stats.iterations = done.sweeps;
    stats.last_change = done.last_change;
    stats.converged = done.converged;
    for (k, (r, (lambda, t))) in rows.iter().zip(&totals).enumerate() {
        impulses[k] = match ends[k] {
            Some(_) => vec3::add(vec3::scale(*lambda, r.n), *t),
            None => [0.0; 3],
        };
    }
    for (c, p) in contacts.iter().zip(impulses.iter()) {
        if *p == [0.0; 3] {
            continue;
        }
        stats.active += 1;
        let add = |sum: &mut [f64; 3], sign: f64| sum.iter_mut().zip(p).for_each(|(s, j)| *s += sign * j);
        match c.other {
            Partner::Particle(j) => {
                if inv_mass[j] == 0.0 && inv_mass[c.i] > 0.0 {
                    add(&mut stats.pinned_impulse_sum, 1.0);
                } else if inv_mass[c.i] == 0.0 && inv_mass[j] > 0.0 {
                    add(&mut stats.pinned_impulse_sum, -1.0);
                }
            }
            Partner::Collider(_) => {
                if inv_mass[c.i] > 0.0 {
                    add(&mut stats.collider_impulse_sum, 1.0);
                }
            }
        }
    }
    Ok(stats)
}

/// A contact of [`hold`]: its inverse masses w (1/kg), 1/(w_i + w_j), friction μ, normal n
/// and target b (m/s).
struct Row {
    wi: f64,
    wj: f64,
    inv_w: f64,
    mu: f64,
    n: [f64; 3],
    b: f64,
}

impl Row {
    /// The impulse p on i and −p on j: v_i += w_i p, v_j −= w_j p (`has_j`: j is a particle).
    fn apply(&self, has_j: bool, vi: &mut [f64; 3], vj: &mut [f64; 3], p: [f64; 3]) {
        for k in 0..3 {
            vi[k] += self.wi * p[k];
        }
        if has_j {
            for k in 0..3 {
                vj[k] += -self.wj * p[k];
            }
        }
    }

    /// One visit with the totals (λ, t) on the velocities of i and j: returns the largest
    /// change it made, as a velocity (impulse · (w_i + w_j), m/s).
    fn visit(&self, has_j: bool, vi: &mut [f64; 3], vj: &mut [f64; 3], (normal, tangent): &mut (f64, [f64; 3])) -> f64 {
        let mut change: f64 = 0.0;
        // Normal: the total that brings u_n to b, clamped at 0.
        let u_n = vec3::dot(vec3::sub(*vi, *vj), self.n);
        let total = (*normal - (u_n - self.b) * self.inv_w).max(0.0);
        let dn = total - *normal;
        *normal = total;
        if dn != 0.0 {
            change = change.max(dn.abs() / self.inv_w);
            self.apply(has_j, vi, vj, vec3::scale(dn, self.n));
        }
        // Friction: the total that stops the sliding, clamped to the cone μ λ.
        if self.mu > 0.0 {
            let u = vec3::sub(*vi, *vj);
            let u_t = vec3::sub(u, vec3::scale(vec3::dot(u, self.n), self.n));
            let old = *tangent;
            let mut t = vec3::sub(old, vec3::scale(self.inv_w, u_t));
            let (len, cap) = (vec3::norm(t), self.mu * total);
            if len > cap {
                t = vec3::scale(if len > 0.0 { cap / len } else { 0.0 }, t);
            }
            let dt = vec3::sub(t, old);
            if dt != [0.0; 3] {
                change = change.max(vec3::norm(dt) / self.inv_w);
                *tangent = t;
                self.apply(has_j, vi, vj, dt);
            }
        }
        change
    }
}

/// Settings of [`separate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeparateParams {
    /// Sweeps over the contacts (default 4): a particle pushed out of one contact may be
    /// pushed into another, and the next sweep sees it.
    pub iterations: usize,
    /// Fraction of each overlap removed per push, in (0, 1] (default 1: all of it).
    pub fraction: f64,
    /// Overlap left in place, m (≥ 0; default 0). A small slop keeps resting contacts
    /// touching, so that they stay contacts from step to step.
    pub slop: f64,
}

impl Default for SeparateParams {
    fn default() -> Self {
        SeparateParams {
            iterations: 4,
            fraction: 1.0,
            slop: 0.0,
        }
    }
}

/// What [`separate`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SeparateStats {
    /// The largest overlap before, m (0 if none).
    pub max_overlap_before: f64,
    /// The largest overlap left, m (0 if none), as linearised along the fixed normals.
    pub max_overlap_after: f64,
}

/// Removes overlap by moving positions along the contact normals, in proportion to the
/// inverse masses (a pinned particle does not move; against a collider the particle takes
/// it all); velocities are not touched.
///
/// Each contact's overlap is kept up to date to first order as particles move: with the
/// normal held fixed, δ = δ₀ − ((x_i − x_j) − (x_i − x_j)₀)·n (x_j = 0 for a collider),
/// exact for two spheres moved along their line of centres and for planes. A push of Δ
/// moves i by Δ w_i / (w_i + w_j) along n and j by −Δ w_j / (w_i + w_j), which changes the
/// momentum Σ m x not at all (w_i m_i = w_j m_j = 1 for movable particles). On return each
/// contact's `overlap` is what is left of it, in that linearisation.
///
/// `x`: positions, m (3 per particle), updated in place; `inv_mass`: 1/kg (0 for pinned).
pub fn separate(
    contacts: &mut [Contact],
    x: &mut [f64],
    inv_mass: &[f64],
    params: &SeparateParams,
) -> Result<SeparateStats, Error> {
    let all = [SweepGroup::in_order(0..contacts.len())];
    separate_grouped(contacts, x, inv_mass, params, &all)
}

/// [`separate`] with each sweep visiting the contacts group by group, as
/// [`hold_grouped`] does (the same result for any thread count).
pub(crate) fn separate_grouped(
    contacts: &mut [Contact],
    x: &mut [f64],
    inv_mass: &[f64],
    params: &SeparateParams,
    groups: &[SweepGroup],
) -> Result<SeparateStats, Error> {
    check_contacts(contacts, inv_mass.len())?;
    check_len("x", x.len(), inv_mass.len())?;
    if !(params.fraction > 0.0 && params.fraction <= 1.0) {
        return Err(Error::invalid(
            "fraction",
            params.fraction,
            "the fraction of overlap removed must be in (0, 1]",
        ));
    }
    if !(params.slop.is_finite() && params.slop >= 0.0) {
        return Err(Error::invalid(
            "slop",
            params.slop,
            "the overlap slop must be finite and >= 0 m",
        ));
    }

    let weights = |c: &Contact| (inv_mass[c.i], c.partner_particle().map_or(0.0, |j| inv_mass[j]));
    let along = |x: &[f64], c: &Contact| {
        let xj = c.partner_particle().map_or([0.0; 3], |j| vec3::get(x, j));
        vec3::dot(vec3::sub(vec3::get(x, c.i), xj), c.normal)
    };
    let mut stats = SeparateStats::default();
    // Each overlap becomes the constant δ₀ + (x_i − x_j)₀·n for the sweeps; the current
    // overlap is then that constant minus the current (x_i − x_j)·n.
    for c in contacts.iter_mut() {
        let (wi, wj) = weights(c);
        if wi + wj > 0.0 {
            stats.max_overlap_before = stats.max_overlap_before.max(c.overlap);
        }
        c.overlap += along(x, c);
    }
    let ends: Vec<Option<Ends>> = contacts.iter().map(|c| Ends::of(c, inv_mass)).collect();
    let mut none = vec![(); contacts.len()];
    let fixed: &[Contact] = contacts;
    // A push of Δ = fraction · (depth − slop) / (w_i + w_j): i by w_i Δ along n, j by −w_j Δ.
    let push = |k: usize, _: &mut (), xi: &mut [f64; 3], xj: &mut [f64; 3]| {
        let c = &fixed[k];
        let (wi, wj) = weights(c);
        let depth = c.overlap - vec3::dot(vec3::sub(*xi, *xj), c.normal);
        if depth <= params.slop || depth.is_nan() {
            return 0.0;
        }
        let push = params.fraction * (depth - params.slop) / (wi + wj);
        for k in 0..3 {
            xi[k] += push * wi * c.normal[k];
        }
        if c.partner_particle().is_some() {
            for k in 0..3 {
                xj[k] += -push * wj * c.normal[k];
            }
        }
        push
    };
    if params.iterations > 0 {
        // every sweep (no tolerance: a change is never below −1)
        sweeps(groups, &ends, x, &mut none, params.iterations, -1.0, push);
    }
    for c in contacts.iter_mut() {
        c.overlap -= along(x, c);
        let (wi, wj) = weights(c);
        if wi + wj > 0.0 {
            stats.max_overlap_after = stats.max_overlap_after.max(c.overlap);
        }
    }
    Ok(stats)
}
