//! Continuous detection for the impulse model: each particle's path through a step, the first
//! impact of two paths, and an event queue with one scheduled event per particle.
//!
//! **Paths** (`paths.rs`: [`Paths`], [`PathStore`], the first impact of two parabolas
//! [`pair_toi`], [`swept_reach`]): within a step of length h every particle moves on a
//! parabola, from its state at the start until an impact changes it.
//!
//! **Candidates.** A particle can only hit a partner of its Verlet neighbour list
//! ([`NeighbourList`]): pairs within r_i + r_j + s at the list's build. The list holds for the
//! whole step while the two largest *swept* displacements from the build positions sum to
//! less than the skin s: a particle's displacement at any τ of the step is at most the larger
//! of its displacements at the step's two ends plus the parabola's bulge over its chord,
//! ⅛ |a| h² (the distance from a fixed point is convex along the chord). An impact changes a
//! path; if the new path could leave the allowance, the list is rebuilt at the impact's time
//! and every particle's event recomputed from there ([`swept_reach`] gives the bound).
//!
//! **One event per particle** (Smallenburg's EDMD scheme, J. Chem. Phys. 2022): each particle
//! keeps only its earliest impact in the rest of the step, with any partner or wall, in a
//! binary heap keyed by (time, particle). After an impact of i and j, only i's and j's events
//! are recomputed. A third particle k whose event was with i is not touched: when its event
//! comes up, i's path version differs from the one k's prediction was made with, and k's
//! event is recomputed from that time. That is enough: k's other partners all met k later
//! than the stale event (it was k's earliest), and a new impact of k with i is i's own
//! earliest-event search's business. Each impact thus costs O(k log N) for k list partners,
//! whatever the speed.

use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;

use rayon::prelude::*;

use super::colliders::Collider;
use super::contact::Partner;
use super::domain::Domain;
use super::neighbour_list::{NeighbourList, CHUNK};
use super::paths::{pair_toi, Toi};
use super::records::Records;
use super::sleep::AWAKE;
use super::soft_step::SPECULATIVE;
use super::toi::{toi_plane, toi_sphere_obstacle, toi_spheres};
use crate::vec3;

pub(crate) use super::paths::{swept_reach, PathStore, Paths};

/// An impact: particle `i` meets `partner` (for a box, its wall `wall`) at `time`, s from the
/// step's start; `partner_version` is a partner particle's path version when it was predicted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Event {
    pub time: f64,
    pub i: usize,
    pub partner: Partner,
    pub wall: usize,
    pub partner_version: u32,
}

/// A heap entry: particle i's time, set by its schedule number `stamp`.
#[derive(Debug, Clone, Copy)]
struct Entry {
    time: f64,
    i: usize,
    stamp: u32,
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Entry {
    /// By time, then by particle: simultaneous impacts go in index order.
    fn cmp(&self, other: &Self) -> Ordering {
        self.time
            .total_cmp(&other.time)
            .then(self.i.cmp(&other.i))
            .then(self.stamp.cmp(&other.stamp))
    }
}

/// A binary heap of at most one current time per particle: setting a particle's time again
/// makes its older entry stale (its stamp no longer matches), and stale entries are dropped
/// as they come to the top. O(log N) per set and per pop.
#[derive(Debug, Default)]
pub(crate) struct Timetable {
    heap: BinaryHeap<Reverse<Entry>>,
    stamp: Vec<u32>,
}

impl Timetable {
    /// Empties the table for `n` particles.
    pub fn reset(&mut self, n: usize) {
        // Entries left from before are gone with the heap; the stamps keep counting.
        self.heap.clear();
        self.stamp.resize(n, 0);
    }

    /// Makes `time` particle i's only time (`None`: it has none).
    pub fn set(&mut self, i: usize, time: Option<f64>) {
        self.stamp[i] = self.stamp[i].wrapping_add(1);
        if let Some(time) = time {
            self.heap.push(Reverse(Entry {
                time,
                i,
                stamp: self.stamp[i],
            }));
        }
    }

    /// Sets the times of many particles at once, `(i, time)` (each i at most once), in O(n):
    /// the table is rebuilt from them (everything else is dropped).
    pub fn fill(&mut self, n: usize, times: impl Iterator<Item = (usize, f64)>) {
        self.reset(n);
        let mut entries = std::mem::take(&mut self.heap).into_vec();
        for (i, time) in times {
            self.stamp[i] = self.stamp[i].wrapping_add(1);
            entries.push(Reverse(Entry {
                time,
                i,
                stamp: self.stamp[i],
            }));
        }
        self.heap = BinaryHeap::from(entries);
    }

    /// Takes the particle with the earliest current time if that time is at most `until`.
    pub fn pop_until(&mut self, until: f64) -> Option<(usize, f64)> {
        while let Some(Reverse(top)) = self.heap.peek() {
            if top.stamp != self.stamp[top.i] {
                self.heap.pop(); // stale
                continue;
            }
            if top.time > until {
                return None;
            }
            let (i, time) = (top.i, top.time);
            self.heap.pop();
            self.stamp[i] = self.stamp[i].wrapping_add(1); // taken: no longer current
            return Some((i, time));
        }
        None
    }
}

/// The particles' next events: a [`Timetable`] of their times and each one's event.
#[derive(Debug, Default)]
pub(crate) struct EventQueue {
    times: Timetable,
    next: Vec<Option<Event>>,
}

impl EventQueue {
    /// Empties the queue for `n` particles.
    pub fn reset(&mut self, n: usize) {
        // A particle's `next` is read only through a current entry: old values may stay.
        self.times.reset(n);
        self.next.resize(n, None);
    }

    /// Makes `event` particle i's only event (`None`: it has none).
    pub fn schedule(&mut self, i: usize, event: Option<Event>) {
        self.next[i] = event;
        self.times.set(i, event.map(|e| e.time));
    }

    /// Takes the earliest current event (stale entries are dropped on the way).
    pub fn pop(&mut self) -> Option<Event> {
        let (i, _) = self.times.pop_until(f64::INFINITY)?;
        self.next[i].take()
    }
}

/// What detection sweeps against: the particles' radii, the colliders (with which box walls
/// are active), the domain and the neighbour list of candidates.
pub(crate) struct Surroundings<'a> {
    pub radius: &'a [f64],
    pub colliders: &'a [Collider],
    /// For each collider, whether each of its walls exists (a box's walls along periodic axes
    /// do not; a plane and an obstacle have one "wall").
    pub active: &'a [[bool; 6]],
    pub domain: &'a Domain,
    pub list: &'a NeighbourList,
    /// Meetings slower than this, m/s, are no impact but a contact for the end of the step:
    /// the larger of the solver's tolerance (rounding after an impulse) and the restitution
    /// threshold, below which contacts are plastic anyway. A resting contact is one of them:
    /// resting piles are the end-of-step solver's, which settles them all at once, where
    /// impacts at one instant would cascade through the pile one pair at a time.
    pub slow: f64,
    /// The end-of-step contacts of the last step, sorted by (particle, partner), lower index
    /// first for pairs, and whether each bore load (a nonzero total impulse). A pair of
    /// them that touches and approaches is a resting contact, not an impact, and goes to the
    /// end-of-step solver: at the step's start, any of them (the approach is what the last
    /// solve left, or a pile's contact pressed by a neighbour's correction); later in the
    /// step, the loaded ones (a body landing on a pile: its load is passed down at once,
    /// as shock propagation does, rather than by impacts cascading pair by pair).
    pub resting: &'a Records,
    /// Each particle's sleeping island or `sleep::AWAKE` (empty while none sleeps,
    /// `collide/sleep.rs`): a sleeper whose path no impact changed yet is a body at rest, and
    /// two of them meet nothing.
    pub asleep: &'a [u32],
    /// The particles' inverse masses, 1/kg (0: pinned): while some sleep, a pinned particle
    /// is a body at rest too, and meets no sleeper.
    pub inv_mass: &'a [f64],
    /// How far each particle can be from where the list was built, for the rest of the step:
    /// a pair farther apart there than their radii and both bounds meets nothing in it.
    pub bound: SweepBound<'a>,
}

/// A bound on how far each particle's path is from its position at the list's build
/// (`NeighbourList::built_at`) from now to the step's end, m (max over τ of |x(τ) − b|).
///
/// Why a pair beyond it meets nothing: a pair touches at τ when |x_i(τ) − x_j(τ)| ≤ r_i + r_j;
/// by the triangle inequality |x_i(τ) − x_j(τ)| ≥ |b_i − b_j| − |x_i(τ) − b_i| − |x_j(τ) − b_j|
/// ≥ |b_i − b_j| − B_i − B_j. So a pair with |b_i − b_j| > r_i + r_j + B_i + B_j neither
/// touches now nor meets before the step's end, and its time of impact need not be solved
/// for. A list candidate is within r_i + r_j + s of its partner at the build (s the skin,
/// four times the step's largest sweep); each particle's own bound is mostly far less (the
/// fastest particle sets the skin), so most candidates are passed over by this check, which
/// reads two build positions instead of two paths.
#[derive(Debug, Clone, Copy)]
pub(crate) enum SweepBound<'a> {
    /// Each particle's own bound.
    Each(&'a [f64]),
    /// One bound for every particle.
    All(f64),
}

impl SweepBound<'_> {
    #[inline]
    fn of(&self, q: usize) -> f64 {
        match self {
            SweepBound::Each(b) => b[q],
            SweepBound::All(b) => *b,
        }
    }
}

impl Surroundings<'_> {
    /// Whether particle q sleeps and no impact of this step has moved it, or (while some
    /// sleep) is pinned.
    #[inline]
    fn still(&self, paths: &Paths<'_>, q: usize) -> bool {
        match self.asleep.get(q) {
            Some(&k) => (k != AWAKE && paths.version(q) == 0) || self.inv_mass[q] == 0.0,
            None => false,
        }
    }

    fn is_resting(&self, i: usize, partner: Partner, now: f64) -> bool {
        self.resting.has(i, partner, now != 0.0)
    }
}

/// A sphere's motion from now, τ s on: x + v τ + ½ a τ² (m, m/s, m/s²).
#[derive(Debug, Clone, Copy)]
struct Parabola {
    x: [f64; 3],
    v: [f64; 3],
    a: [f64; 3],
}

/// What a particle meets: an impact, or something it touches (a partner particle, if any).
enum Found {
    Impact(Event),
    Touching(Option<usize>),
}

/// A particle's earliest event in [now, h], and whether it touches something at `now` or meets
/// something too slowly for an impact (then it has a contact at the step's end).
pub(crate) struct Earliest {
    pub event: Option<Event>,
    pub touching: bool,
}

impl Surroundings<'_> {
    /// Particle i's earliest impact after `now` within the step of length h, over its list
    /// partners, then its colliders (ties: the first found). A pair that touches at `now`
    /// and approaches faster than `slow` is an impact at `now`.
    pub fn earliest(&self, paths: &Paths<'_>, i: usize, now: f64, h: f64) -> Earliest {
        let mut best: Option<Event> = None;
        let mut touching = false;
        let partners = self.list.rows[i / CHUNK].of(i % CHUNK);
        self.visit(paths, i, partners, now, h, |found| match found {
            Found::Impact(e) => {
                if best.is_none_or(|b| e.time < b.time) {
                    best = Some(e);
                }
            }
            Found::Touching(_) => touching = true,
        });
        Earliest { event: best, touching }
    }

    /// Every pair's first impact after `now`, each pair once (from its lower index, on all
    /// threads), and each particle's with the colliders: the impacts found, and the particles
    /// touching something (each may be listed more than once). The caller keeps each
    /// particle's earliest.
    pub fn all_impacts(&self, paths: &Paths<'_>, now: f64, h: f64) -> (Vec<Event>, Vec<usize>) {
        let parts: Vec<(Vec<Event>, Vec<usize>)> = self
            .list
            .rows
            .par_iter()
            .enumerate()
            .map(|(c, rows)| {
                let (mut events, mut touching) = (Vec::new(), Vec::new());
                for l in 0..rows.len() {
                    let i = c * CHUNK + l;
                    let row = rows.of(l);
                    let upper = &row[row.partition_point(|&j| (j as usize) < i)..];
                    self.visit(paths, i, upper, now, h, |found| match found {
                        Found::Impact(e) => events.push(e),
                        Found::Touching(j) => {
                            touching.push(i);
                            touching.extend(j);
                        }
                    });
                }
                (events, touching)
            })
            .collect();
        let mut events = Vec::with_capacity(parts.iter().map(|p| p.0.len()).sum());
        let mut touching = Vec::new();
        for (e, t) in parts {
            events.extend(e);
            touching.extend(t);
        }
        (events, touching)
    }

    /// Calls `each` with what particle i meets after `now`: each of `partners` (an impact,
    /// or touching), then each of its colliders.
    fn visit(&self, paths: &Paths<'_>, i: usize, partners: &[u32], now: f64, h: f64, mut each: impl FnMut(Found)) {
        let (xi, vi) = paths.state_at(i, now);
        let ai = vec3::get(paths.accel, i);
        let rest = h - now;
        let still = self.still(paths, i);
        let asleep = still && self.inv_mass[i] > 0.0;
        // (the bound's check, with the list's rounding allowance on top: the bounds and the
        // distance are computed in floating point)
        let built = &self.list.built_at;
        let (bi, reach_i) = (vec3::get(built, i), self.bound.of(i));
        let slack = (self.list.skin - self.list.allowance).max(0.0);
        for &j in partners {
            let j = j as usize;
            if still && self.still(paths, j) {
                continue; // two bodies at rest
            }
            let apart = self.domain.displacement(bi, vec3::get(built, j));
            let reach = self.radius[i] + self.radius[j] + reach_i + self.bound.of(j) + slack;
            if vec3::dot(apart, apart) > reach * reach {
                continue; // too far apart to meet in the rest of the step (SweepBound)
            }
            let (xj, vj) = paths.state_at(j, now);
            let d0 = self.domain.displacement(xi, xj);
            let u = vec3::sub(vi, vj);
            let da = vec3::sub(ai, vec3::get(paths.accel, j));
            match pair_toi(d0, u, da, self.radius[i] + self.radius[j], rest, self.slow) {
                Toi::Never => {}
                Toi::Touching => each(Found::Touching(Some(j))),
                Toi::At(tau) if tau == 0.0 && self.is_resting(i, Partner::Particle(j), now) => each(Found::Touching(Some(j))),
                Toi::At(tau) => each(Found::Impact(Event {
                    time: now + tau,
                    i,
                    partner: Partner::Particle(j),
                    wall: 0,
                    partner_version: paths.version(j),
                })),
            }
        }
        if asleep {
            return; // a sleeper at rest on its colliders
        }
        let walls = &self.list.walls;
        let first = walls.partition_point(|w| w.0 < i);
        for &(_, k) in walls[first..].iter().take_while(|w| w.0 == i) {
            // A moving collider stands where it will be at the step's end; the particle's
            // path is seen from it, moved with the surface's motion over the rest of the
            // step (`SurfaceVelocity::moved_with`): x + u (h − now) and v − u for a translation,
            // exact; for a turn, from x turned by ω (h − now) to the particle's own end point
            // on the chord between, v + (x − x')/(h − now): both ends exact, so a particle
            // inside a turning container at the step's start that ends outside crosses a
            // wall on the way, however fast the turn.
            let (xi, vi) = if self.colliders[k].is_moving() {
                let field = self.colliders[k].surface().velocity();
                if field.angular == [0.0; 3] || rest <= 0.0 {
                    let u = self.colliders[k].velocity_at(xi);
                    (vec3::add(xi, vec3::scale(rest, u)), vec3::sub(vi, u))
                } else {
                    let seen = field.moved_with(xi, rest);
                    (seen, vec3::add(vi, vec3::scale(1.0 / rest, vec3::sub(xi, seen))))
                }
            } else {
                (xi, vi)
            };
            // touching a collider at the start, or within the speculative margin of it,
            // approaching or not: a contact of the step's end (a mesh answers with its time of
            // impact, from the same traversal of its hierarchy)
            let margin = (now == 0.0).then_some(2.0 * SPECULATIVE * self.radius[i]);
            let path = Parabola { x: xi, v: vi, a: ai };
            let mut touching = false;
            if let (Some(tolerance), false) = (margin, matches!(self.colliders[k], Collider::Mesh(_))) {
                touching = self.touches(k, xi, self.radius[i], tolerance);
            }
            if touching {
                each(Found::Touching(None));
            }
            let mut near = false;
            // (a contact resting on a moving collider is left to the step's end only if the
            // end still finds it: it approaches by less than r over the rest of the step; a
            // fast-turning container's wall that drives a particle faster is an impact)
            let moving = self.colliders[k].is_moving();
            let r = self.radius[i];
            self.collider_events(i, k, path, rest, margin, &mut near, |wall, tau| {
                let resting = tau == 0.0 && self.is_resting(i, Partner::Collider(k), now) && !(moving && -wall.1 * rest > r);
                if wall.1 > -self.slow || resting {
                    each(Found::Touching(None)); // meets it too slowly, or rests on it: a contact
                    return;
                }
                each(Found::Impact(Event {
                    time: now + tau,
                    i,
                    partner: Partner::Collider(k),
                    wall: wall.0,
                    partner_version: 0,
                }));
            });
            if near {
                each(Found::Touching(None));
            }
        }
    }

    /// The first time, s from now, at which particle i (state x, v, 3 values per particle,
    /// with its list partners) can have anything for continuous detection: it touches a
    /// partner or a collider now (0), or the straight paths of force-free motion meet within
    /// `horizon` s; `None`: nothing within the horizon. A meeting at any speed counts (a slow
    /// one is a contact, still detection's business).
    pub fn first_meeting(&self, x: &[f64], v: &[f64], i: usize, horizon: f64) -> Option<f64> {
        let (xi, vi) = (vec3::get(x, i), vec3::get(v, i));
        let mut first: Option<f64> = None;
        let mut meet = |tau: f64| {
            if first.is_none_or(|f| tau < f) {
                first = Some(tau);
            }
        };
        for &j in self.list.rows[i / CHUNK].of(i % CHUNK) {
            let j = j as usize;
            let d0 = self.domain.displacement(xi, vec3::get(x, j));
            let big_r = self.radius[i] + self.radius[j];
            if vec3::dot(d0, d0) <= big_r * big_r {
                return Some(0.0);
            }
            let u = vec3::sub(vi, vec3::get(v, j));
            if let Some(tau) = toi_spheres(d0, u, big_r, horizon) {
                meet(tau);
            }
        }
        let walls = &self.list.walls;
        let start = walls.partition_point(|w| w.0 < i);
        for &(_, k) in walls[start..].iter().take_while(|w| w.0 == i) {
            if self.touches(k, xi, self.radius[i], 0.0) {
                return Some(0.0);
            }
            let line = Parabola {
                x: xi,
                v: vi,
                a: [0.0; 3],
            };
            self.collider_events(i, k, line, horizon, None, &mut false, |_, tau| meet(tau));
        }
        first
    }

    /// Whether a sphere at x of radius r comes within `tolerance` (m) of an active wall of
    /// collider k.
    fn touches(&self, k: usize, x: [f64; 3], r: f64, tolerance: f64) -> bool {
        match &self.colliders[k] {
            Collider::Plane(p) => p.touch(x, r, tolerance).is_some(),
            Collider::Box(b) => b
                .walls()
                .iter()
                .enumerate()
                .any(|(w, wall)| self.active[k][w] && wall.touch(x, r, tolerance).is_some()),
            Collider::Sphere(s) => s.touch(x, r, tolerance).is_some(),
            Collider::Mesh(m) => {
                let mut any = false;
                m.for_each_touch(x, r, tolerance, |_| any = true);
                any
            }
        }
    }

    /// Calls `each((wall, u_n), τ)` with the first impact of a sphere at (x, v, a) with each
    /// active wall of collider k within `rest`, u_n its normal velocity then (< 0).
    ///
    /// A mesh also sets `near` when the sphere comes within `margin` (m) of it now (the
    /// other colliders leave that to [`Surroundings::touches`]).
    #[allow(clippy::too_many_arguments)]
    fn collider_events(
        &self,
        i: usize,
        k: usize,
        path: Parabola,
        rest: f64,
        margin: Option<f64>,
        near: &mut bool,
        mut each: impl FnMut((usize, f64), f64),
    ) {
        let Parabola { x, v, a } = path;
        let r = self.radius[i];
        match &self.colliders[k] {
            Collider::Plane(p) => {
                if let Some(t) = toi_plane(x, v, a, r, p, rest) {
                    each((0, vec3::dot(v, p.normal()) + vec3::dot(a, p.normal()) * t), t);
                }
            }
            Collider::Box(b) => {
                for (w, wall) in b.walls().iter().enumerate() {
                    if self.active[k][w] {
                        if let Some(t) = toi_plane(x, v, a, r, wall, rest) {
                            each((w, vec3::dot(v, wall.normal()) + vec3::dot(a, wall.normal()) * t), t);
                        }
                    }
                }
            }
            Collider::Sphere(s) => {
                // on the chord of the remaining step (an obstacle's TOI is for straight lines)
                let chord = [0, 1, 2].map(|c| v[c] + 0.5 * a[c] * rest);
                if let Some(t) = toi_sphere_obstacle(x, chord, r, s, rest) {
                    let d = [0, 1, 2].map(|c| x[c] + chord[c] * t - s.center()[c]);
                    let len = vec3::norm(d);
                    let u_n = if len > 0.0 { vec3::dot(chord, d) / len } else { 0.0 };
                    each((0, u_n), t);
                }
            }
            Collider::Mesh(m) => {
                // faces on the parabola, edges and vertices on its chord; the wall is the
                // triangle met
                let (touching, first) = m.toi_within(x, v, a, r, rest, margin);
                *near |= touching;
                if let Some((t, tri)) = first {
                    let at = vec3::parabola(x, v, a, t);
                    let n = m.touch_of_triangle(tri, at, r).normal;
                    each((tri, vec3::dot([0, 1, 2].map(|c| v[c] + a[c] * t), n)), t);
                }
            }
        }
    }
}

#[cfg(test)]
#[path = "tests/events.rs"]
mod tests;
