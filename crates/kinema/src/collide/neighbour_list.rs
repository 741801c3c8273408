//! A Verlet neighbour list with a skin: the candidate pairs of the contact searches, rebuilt
//! only when the particles have moved far enough that something left out could touch. The
//! contact force tests its pairs at every evaluation; the impulse model's continuous
//! detection sweeps each step's paths against them (the skin then also covers the step's
//! sweep, see `collide::events`).

use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

use super::groups::Filter;
use super::{Collider, Domain, Grid, Plane};
use crate::error::Error;

/// The neighbour list's default skin, as a fraction of the particles' mean radius.
///
/// The skin trades the pairs tested at every evaluation against how often the list is
/// rebuilt: a thicker shell lists more pairs that do not touch, a thinner one is outlived
/// sooner (the list lasts while the two particles that moved most have together moved less
/// than s). Measured on the granular gas of benchmarks/granular_gas.py (N = 103,823, density
/// 0.3, T = 1, 500 steps, particle-steps/s with 1 and 2 threads): 0.2 r: 8.6e6 and 1.5e7;
/// 0.6 r: 1.0e7 and 1.8e7; 1.0 r: 7.0e6 and 1.3e7. 0.6 r is LAMMPS's skin for that gas
/// (0.3 d). In the denser granular settle of benchmarks/collisions_lammps.py the optimum
/// was flat between 0.1 r and 0.5 r. A fraction of the radius keeps the choice independent
/// of the units and of the size of the particles.
pub const SKIN_PER_RADIUS: f64 = 0.6;

/// Particles per chunk of the neighbour list and of the parallel passes over it. Fixed (not
/// derived from the number of threads), so that sums over chunks are always the same sums.
pub const CHUNK: usize = 2048;

/// The largest |coordinate| of a collider's points (a plane's, each box wall's) or of an
/// obstacle's centre plus its radius, or of a mesh's vertices, m.
pub(crate) fn collider_scale(c: &Collider) -> f64 {
    let largest = |p: [f64; 3]| p.iter().fold(0.0, |m: f64, c| m.max(c.abs()));
    match c {
        Collider::Plane(p) => largest(p.point()),
        Collider::Box(b) => b.walls().iter().map(|w| largest(w.point())).fold(0.0, f64::max),
        Collider::Sphere(s) => largest(s.center()) + s.radius(),
        Collider::Mesh(m) => m.scale(),
    }
}

/// The settings of a [`NeighbourList`] build: the skin s, m, and the colliders' largest
/// |coordinate| (m, [`collider_scale`] of each), which enters the rounding allowance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ListBuild {
    pub skin: f64,
    /// How far past touching a contact can act, m (JKR's pull-off distance; 0 for the
    /// others): the list lists pairs within r_i + r_j + s, and holds while the particles
    /// have moved less than s − reach (see [`NeighbourList`]).
    pub reach: f64,
    pub collider_scale: f64,
}

/// A Verlet neighbour list: the particle pairs (i, j) with |x_i − x_j| < r_i + r_j + s at the
/// build (the grid's [`Grid::partners`] with margin s, the skin), and the particles within
/// s of touching each collider, reused until the particles have moved far enough that
/// something left out could touch.
///
/// Why that is exact. Let a_i be particle i's displacement since the build (its minimum image
/// along periodic axes: positions matter only modulo the period there, so any image of the
/// move will do, and a particle wrapped to the other side has not moved far). A pair left out
/// had |d_b| ≥ r_i + r_j + s at the build for every image d_b of x_i − x_j. Each image of
/// the pair's separation now is an image of d_b + a_i − a_j, so by the triangle inequality
///
/// ```text
///   |d| ≥ |d_b| − |a_i| − |a_j| ≥ r_i + r_j + s − (|a_i| + |a_j|)
/// ```
///
/// and while |a_i| + |a_j| < s for every pair, no pair left out can touch (|d| < r_i + r_j).
/// That holds while the two largest displacements sum to less than s; the usual criterion,
/// "rebuild once some particle has moved more than s/2", implies it (both are then < s/2)
/// and rebuilds sooner. A collider is fixed, and the distance from a plane, or from an
/// obstacle's centre, changes by at most |a_i| ≤ the largest displacement: a particle left out
/// at r_i + s or more from it cannot touch it either. What is in the list is tested exactly
/// at every evaluation, with the full search's floating-point tests, so the contacts are the
/// same as a search at every evaluation, in the same order.
///
/// In floating point each of those inequalities holds to a few roundings of numbers no
/// larger than `scale` = the largest |coordinate| of the particles and colliders + the
/// periods + 2 r_max + s (the coordinate differences, minimum images, squares and square
/// roots: ≲ 10 ε·scale ≈ 2·10⁻¹⁵ scale in all); the list is rebuilt once the two largest
/// moves reach s − 10⁻¹² scale, which leaves a margin of hundreds of roundings. (When
/// 10⁻¹² scale ≥ s, coordinates 10¹² times the skin, it is rebuilt at every evaluation,
/// still exact.)
#[derive(Default)]
pub(crate) struct NeighbourList {
    /// Each chunk of [`CHUNK`] particles' partners, ascending: a full list lists a pair
    /// from both sides, a half list ([`NeighbourList::half`]) once, in the row of its lower
    /// index.
    pub(crate) rows: Vec<Rows>,
    /// Whether this is a half list: particle i's row holds its partners j > i only. The
    /// contact force's list is one (each pair's force computed once, for both
    /// sides); the impulse model sweeps each particle against all its partners, and keeps
    /// a full one.
    pub(crate) half: bool,
    /// The candidate (particle, collider) pairs, sorted.
    pub(crate) walls: Vec<(usize, usize)>,
    /// Positions at the build, m (empty: no list).
    pub(crate) built_at: Vec<f64>,
    /// The list holds while the two largest displacements since the build sum to less, m.
    pub(crate) allowance: f64,
    /// The build's skin s, m, and the parts of its rounding allowance's scale (see the type's
    /// doc): the largest |coordinate| of particles and colliders, the periods' sum and the
    /// largest radius, m. A birth's admission ([`NeighbourList::admit`]) tests with them.
    pub(crate) skin: f64,
    /// The build's reach past touching, m ([`ListBuild::reach`]).
    pub(crate) reach: f64,
    pub(crate) extent: [f64; 3],
    /// Builds so far.
    pub(crate) builds: usize,
    /// The buffer (address, length) at which [`ContactForceModel::list_expired`](crate::collide::contact_force::ContactForceModel::list_expired) just found that
    /// the list holds: the next update at that buffer, the world's force evaluation of the
    /// same step with nothing written in between, need not check again. Any update clears it.
    pub(crate) verified: Option<(usize, usize)>,
    /// The most entries a build may hold (`None`: [`Self::ENTRIES_PER_PARTICLE`] a particle,
    /// at least [`Self::MIN_ENTRIES`]; tests set less).
    pub(crate) entry_limit: Option<usize>,
    /// Which colliders moved at the build (every particle is a moving one's candidate): a
    /// collider that starts moving needs a new list even if no particle moved.
    pub(crate) moving: Vec<bool>,
}

/// The partners of one chunk's particles, compressed: particle l of the chunk has
/// `partners[start[l]..start[l + 1]]`, and `owner[k]` is the particle l whose row holds entry
/// k (the contact force's first look reads it, `contact_force/overlapping.rs`: it loops over
/// a chunk's entries, not its particles).
///
/// Made in this module alone (the builds and `upkeep.rs`'s renumberings), each ending with
/// [`Rows::seal`], which makes `owner` from the starts; read elsewhere through
/// [`Rows::start`], [`Rows::partners`], [`Rows::owner`] and [`Rows::of`].
#[derive(Default)]
pub(crate) struct Rows {
    start: Vec<u32>,
    partners: Vec<u32>,
    owner: Vec<u16>,
}

// (`owner` holds a chunk's particle index in 16 bits)
const _: () = assert!(CHUNK <= 1 << 16);

impl Rows {
    /// Particles in the chunk.
    pub(crate) fn len(&self) -> usize {
        self.start.len().saturating_sub(1)
    }

    /// The partners of the chunk's particle `l`.
    #[inline]
    pub(crate) fn of(&self, l: usize) -> &[u32] {
        &self.partners[self.start[l] as usize..self.start[l + 1] as usize]
    }

    /// Where each particle's row starts in [`Rows::partners`], and where the last ends.
    pub(crate) fn start(&self) -> &[u32] {
        &self.start
    }

    /// Every row's partners, one row after the other.
    pub(crate) fn partners(&self) -> &[u32] {
        &self.partners
    }

    /// For each entry of [`Rows::partners`], the chunk's particle whose row holds it.
    pub(crate) fn owner(&self) -> &[u16] {
        &self.owner
    }

    /// Rows with no particle yet: the first row starts at 0.
    fn begin(&mut self) {
        self.start.clear();
        self.partners.clear();
        self.owner.clear();
        self.start.push(0);
    }

    /// Ends the row of the next particle at the partners pushed so far.
    fn end_row(&mut self) {
        self.start.push(self.partners.len() as u32);
    }

    /// Makes `owner` from the rows' starts, once they are all made: a mark at each row's
    /// first entry (rows ending at the last entry or past it mark a spare place at the end),
    /// summed, a loop without a branch a particle (most particles of a gas have zero or one
    /// partner, and a loop over each particle's row would end at a branch the processor
    /// cannot foresee).
    fn seal(&mut self) {
        let (entries, particles) = (self.partners.len(), self.len());
        let owner = &mut self.owner;
        owner.clear();
        owner.resize(entries + 1, 0);
        for &s in self.start.iter().take(particles).skip(1) {
            owner[s as usize] += 1;
        }
        let mut l = 0;
        for o in owner.iter_mut() {
            l += *o;
            *o = l;
        }
        owner.truncate(entries);
    }

    /// Rows made from each particle's partners in `rows` (tests).
    #[cfg(test)]
    pub(crate) fn from_rows(rows: &[Vec<u32>]) -> Rows {
        let mut out = Rows::default();
        out.begin();
        for row in rows {
            out.partners.extend_from_slice(row);
            out.end_row();
        }
        out.seal();
        out
    }
}

impl NeighbourList {
    /// The most entries (a particle's partner, 4 bytes, and its row's owner, 2: [`Rows`]) a
    /// list holds per particle: 768 B, where a packing of spheres gives each fewer than 50
    /// within the skin; with at least [`Self::MIN_ENTRIES`] in all. The memory is so bounded
    /// by the particle count, as the command line's work estimate counts it.
    pub(crate) const ENTRIES_PER_PARTICLE: usize = 128;

    /// The fewest entries a list may hold before it stops (192 MiB with their owners): room
    /// for a few thousand candidates a particle in scenes of 10⁴ particles, which a lattice
    /// falling at 60 Hz needs while it falls (the 10,000-ball pour of `benchmarks/piles.py`:
    /// more than 419 a particle, refused at 16 MiB).
    pub(crate) const MIN_ENTRIES: usize = 1 << 25;

    /// Makes the list hold for positions `x` (rebuilt with `grid` if needed, with the skin
    /// and the colliders' largest |coordinate| that `build` works out then). With a `filter`
    /// (collision groups, `groups.rs`) a pair or particle–collider pair that does not collide
    /// is never listed: the list is the unfiltered one less those pairs, so the argument of
    /// the type's doc holds for the pairs that collide. The filter must stay as it was while
    /// the list is kept (the world forgets the list when groups or masks change).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn update(
        &mut self,
        grid: &mut Grid,
        x: &[f64],
        radius: &[f64],
        colliders: &[Collider],
        domain: &Domain,
        filter: Option<Filter<'_>>,
        build: impl FnOnce() -> ListBuild,
    ) -> Result<(), Error> {
        let moving_now = colliders
            .iter()
            .enumerate()
            .any(|(k, c)| c.is_moving() && !self.moving.get(k).copied().unwrap_or(false));
        if !moving_now && (self.verified.take() == Some((x.as_ptr() as usize, x.len())) || self.holds(x, domain)) {
            return Ok(());
        }
        self.verified = None;
        let ListBuild {
            skin,
            reach,
            collider_scale,
        } = build();
        self.moving = colliders.iter().map(Collider::is_moving).collect();
        self.built_at.clear(); // no list until the build succeeds (non-finite positions fail)
        let n = radius.len();
        if n > u32::MAX as usize {
            return Err(Error::invalid(
                "particles",
                n,
                format!("at most {} with spring-dashpot contacts", u32::MAX),
            ));
        }
        domain.check_radii(radius)?;
        for c in colliders {
            if let Collider::Box(b) = c {
                b.check_fill(domain.dim(), x, radius)?;
            }
        }
        // (no pair collides: no pair search, only the colliders' candidates)
        let searched = filter.is_none_or(|f| !f.no_pairs()) && grid.prepare(x, radius, domain, skin)?;
        self.build_rows(grid, (x, radius), domain, filter, skin, searched)?;
        self.collider_candidates((x, radius), colliders, domain, filter, skin);
        self.built_at.extend_from_slice(x);
        let largest = |a: &[f64]| a.par_iter().map(|c| c.abs()).reduce(|| 0.0, f64::max);
        let periods = domain
            .periodic_box()
            .map_or(0.0, |p| (0..3).filter(|&k| p.axes()[k]).map(|k| p.period(k)).sum());
        self.skin = skin;
        self.reach = reach;
        self.extent = [largest(x).max(collider_scale), periods, largest(radius)];
        self.allowance = self.allowance_now();
        self.builds += 1;
        Ok(())
    }

    /// The rows of a build with `skin` (m), chunk by chunk on all threads (`searched`: the
    /// grid is prepared for a pair search; false: no pair collides). Errors: more entries
    /// than the list's limit.
    fn build_rows(
        &mut self,
        grid: &Grid,
        (x, radius): (&[f64], &[f64]),
        domain: &Domain,
        filter: Option<Filter<'_>>,
        skin: f64,
        searched: bool,
    ) -> Result<(), Error> {
        // The rows, chunk by chunk on all threads; each particle's row depends on the
        // positions only, so the list is the same for any number of threads. The entries are
        // counted as they come (into a shared count every 64 particles, so the threads rarely
        // meet on it), so that a list beyond its limit stops before it exhausts the
        // machine's memory (an abort Python could not catch).
        let n = radius.len();
        self.rows.resize_with(n.div_ceil(CHUNK), Rows::default);
        let half = self.half;
        let entries = AtomicUsize::new(0);
        let limit = self
            .entry_limit
            .unwrap_or((Self::ENTRIES_PER_PARTICLE * n).max(Self::MIN_ENTRIES));
        self.rows.par_iter_mut().enumerate().for_each(|(c, rows)| {
            rows.begin();
            let mut counted = 0;
            let mut over = false;
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                if searched && !over && filter.is_none_or(|f| f.mask(i) != 0) {
                    let lowest = if half { i + 1 } else { 0 };
                    let partners = &mut rows.partners;
                    let before = partners.len();
                    grid.partners_from(i, lowest, x, radius, domain, skin, partners);
                    if let Some(f) = filter {
                        retain_colliding(partners, before, |j| f.pair(i, j));
                    }
                    if i % 64 == 63 {
                        let added = partners.len() - counted;
                        counted = partners.len();
                        over = entries.fetch_add(added, Ordering::Relaxed) + added > limit;
                    }
                }
                rows.end_row();
            }
            rows.seal();
            entries.fetch_add(rows.partners.len() - counted, Ordering::Relaxed);
        });
        if entries.into_inner() > limit {
            self.rows.clear();
            // (the skin is the impulse model's four largest sweeps of a step when those
            // exceed its base, 2.5 where four would not fit: a fast particle at a long step
            // widens every particle's reach)
            let what = format!(
                "the contact list of {n} particles (over {} neighbours per particle within \
                 r_i + r_j + {skin:.3} m, the list's skin: radii far too large for the space the \
                 particles fill, or, with impulses, a step in which the fastest particle sweeps \
                 far, as the skin is at least 2.5 times the largest sweep of a step: a shorter \
                 dt shortens it)",
                limit / n.max(1)
            );
            return Err(Error::out_of_memory(what, limit * std::mem::size_of::<u32>()));
        }
        Ok(())
    }

    /// The collider candidates of a build with `skin` (m): each particle within the skin of
    /// a collider (of every moving one), in particle order.
    fn collider_candidates(
        &mut self,
        (x, radius): (&[f64], &[f64]),
        colliders: &[Collider],
        domain: &Domain,
        filter: Option<Filter<'_>>,
        skin: f64,
    ) {
        self.walls.clear();
        if !colliders.is_empty() {
            // a box whose walls all lie along periodic axes has none: no particle's candidate
            let walled: Vec<bool> = active_walls(colliders, domain).iter().map(|a| a.iter().any(|&w| w)).collect();
            for (i, &r) in radius.iter().enumerate() {
                let p = [x[3 * i], x[3 * i + 1], x[3 * i + 2]];
                for (k, c) in colliders
                    .iter()
                    .enumerate()
                    .filter(|&(k, _)| walled[k] && filter.is_none_or(|f| f.wall(i, k)))
                {
                    // a moving collider can reach a particle that stays put: every particle
                    // is its candidate
                    let mut near = c.is_moving();
                    if !near {
                        c.for_each_touch(p, r, skin, |_| near = true);
                    }
                    if near {
                        self.walls.push((i, k));
                    }
                }
            }
        }
    }

    /// Whether there is a list and the two largest displacements since its build sum to less
    /// than the allowance (false for non-finite positions, which then go to the grid and its
    /// error). Chunk by chunk in parallel; the two largest of all are the two largest of
    /// the chunks' two largest, whatever the order they are combined in.
    pub(crate) fn holds(&self, x: &[f64], domain: &Domain) -> bool {
        if self.built_at.len() != x.len() || x.is_empty() {
            return false;
        }
        // (first, second, nan): the two largest squared displacements, first ≥ second, and
        // whether a NaN was met (which `max` would pass over).
        let top = |a: (f64, f64, bool), b: (f64, f64, bool)| {
            let first = a.0.max(b.0);
            let second = a.0.min(b.0).max(a.1).max(b.1);
            (first, second, a.2 || b.2)
        };
        let (first, second, nan) = x
            .par_chunks(3 * CHUNK)
            .zip(self.built_at.par_chunks(3 * CHUNK))
            .map(|(xc, bc)| {
                // First the largest alone, in a loop without a branch a particle: while
                // twice it is under the allowance (most of a list's life), so is the sum of
                // the two largest, and the chunk gives (largest, largest) for them, which
                // decides as the two would. A NaN makes `largest` false below and is counted.
                let (mut largest, mut nans) = (0.0_f64, 0u64);
                for (p, q) in xc.chunks_exact(3).zip(bc.chunks_exact(3)) {
                    let a = domain.displacement([p[0], p[1], p[2]], [q[0], q[1], q[2]]);
                    let a2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
                    nans += u64::from(a2.is_nan());
                    largest = if a2 > largest { a2 } else { largest };
                }
                if nans == 0 && 2.0 * largest.sqrt() < self.allowance {
                    return (largest, largest, false);
                }
                let (mut first, mut second, mut nan) = (0.0_f64, 0.0_f64, false);
                for (p, q) in xc.chunks_exact(3).zip(bc.chunks_exact(3)) {
                    let a = domain.displacement([p[0], p[1], p[2]], [q[0], q[1], q[2]]);
                    let a2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
                    nan |= a2.is_nan();
                    if a2 > second {
                        second = a2.min(first);
                        first = first.max(a2);
                    }
                }
                (first, second, nan)
            })
            .reduce(|| (0.0, 0.0, false), top);
        !nan && first.sqrt() + second.sqrt() < self.allowance
    }
}

/// Keeps, of `partners[from..]`, those for which `collides` holds, in their order.
fn retain_colliding(partners: &mut Vec<u32>, from: usize, collides: impl Fn(usize) -> bool) {
    let mut kept = from;
    for k in from..partners.len() {
        let j = partners[k];
        if collides(j as usize) {
            partners[kept] = j;
            kept += 1;
        }
    }
    partners.truncate(kept);
}

impl NeighbourList {
    /// s − reach − 10⁻¹² scale, scale = the largest |coordinate| + the periods + 2 r_max + s
    /// (the type's doc; contacts that act up to `reach` past touching are all listed while
    /// the two largest moves sum to less than s − reach).
    fn allowance_now(&self) -> f64 {
        let [coordinates, periods, r_max] = self.extent;
        self.skin - self.reach - 1e-12 * (coordinates + periods + 2.0 * r_max + self.skin)
    }
}

/// Which walls of each collider exist: a box's walls along periodic axes do not.
pub(crate) fn active_walls(colliders: &[Collider], domain: &Domain) -> Vec<[bool; 6]> {
    colliders
        .iter()
        .map(|c| {
            let mut active = [false; 6];
            match c {
                Collider::Box(b) => {
                    for (w, wall) in b.walls().iter().enumerate() {
                        active[w] = wall_active(domain, wall);
                    }
                }
                _ => active[0] = true,
            }
            active
        })
        .collect()
}

/// Whether a wall is active: a box's walls along periodic axes are not.
fn wall_active(domain: &Domain, plane: &Plane) -> bool {
    match domain.periodic_box() {
        Some(p) => {
            let n = plane.normal();
            !(0..3).any(|k| p.axes()[k] && n[k] != 0.0)
        }
        None => true,
    }
}

mod upkeep;

#[cfg(test)]
#[path = "tests/neighbour_list.rs"]
mod tests;
