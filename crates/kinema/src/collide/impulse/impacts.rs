//! Continuous detection of the impulse model and its impacts in time order (stages 2–4 inside
//! the step, [`ImpulseModel::step`]): the neighbour list made to hold for the step's sweep,
//! each particle's first impact into the queue, the impacts popped in time order, each
//! resolved by Newton's law and distributed at its time, and the force-free world's meeting
//! times (`quiet.rs`) for the next steps.

use std::time::{Duration, Instant};

use rayon::prelude::*;

use super::end_of_step::distribute;
use super::{CollisionStats, ImpulseModel, StageSetting};
use crate::collide::events::{swept_reach, Event, Paths, Surroundings, SweepBound};
use crate::collide::groups::Filter;
use crate::collide::neighbour_list::{active_walls, collider_scale, ListBuild, CHUNK, SKIN_PER_RADIUS};
use crate::collide::response::VELOCITY_TOLERANCE;
use crate::collide::{restitution_impulse, Collider, Contact, Domain, Partner};
use crate::error::{Divergence, Error};
use crate::vec3;

/// The least approach speed of an impact, m/s: slower meetings are contacts for the end of
/// the step (the solver's tolerance, or the restitution threshold below which they would be
/// plastic anyway).
pub(super) fn least_impact_speed(threshold: f64) -> f64 {
    VELOCITY_TOLERANCE.max(threshold)
}

/// What an impact search sweeps against: the stage's setting, which walls of each collider
/// exist ([`active_walls`]), the step h (s) and the restitution threshold (m/s).
pub(super) struct Search<'s, 'a> {
    pub set: &'s StageSetting<'a>,
    pub active: &'s [[bool; 6]],
    /// The world's time at the step's start, s.
    pub t0: f64,
    pub h: f64,
    pub threshold: f64,
}

/// What continuous detection sweeps against (`collide::events::Surroundings`), from a [`Search`]
/// and the stage's own fields (a macro, not a method: the event loop holds it while it
/// changes other fields).
macro_rules! surroundings {
    ($stage:ident, $search:expr, $reach:expr) => {
        Surroundings {
            radius: $search.set.radius,
            colliders: $search.set.colliders,
            active: $search.active,
            domain: $search.set.domain,
            list: &$stage.list,
            slow: least_impact_speed($search.threshold),
            resting: &$stage.records,
            asleep: $stage.sleep.marks(),
            inv_mass: $search.set.inv_mass,
            bound: sweep_bound(&$stage.bounds, $stage.bounded, $stage.unbounded(), $reach),
        }
    };
}

/// The impact search's bound on each particle's sweep (`events::SweepBound`): its own
/// (`bounds`) when `bounded`, else the step's largest, `reach` (m); none with `unbounded`
/// (the tests' search without the check).
fn sweep_bound(bounds: &[f64], bounded: bool, unbounded: bool, reach: f64) -> SweepBound<'_> {
    if unbounded {
        SweepBound::All(f64::INFINITY)
    } else if bounded {
        SweepBound::Each(bounds)
    } else {
        SweepBound::All(reach)
    }
}

impl ImpulseModel {
    /// Whether the tests turned the sweep bound's check off (never outside them).
    fn unbounded(&self) -> bool {
        #[cfg(test)]
        return self.unbounded;
        #[cfg(not(test))]
        false
    }

    /// Makes the neighbour list hold for the whole step's sweep (rebuilt at x0 if not) and
    /// returns the restitution threshold (m/s), the largest swept displacement of any particle
    /// from the list's build positions (m) and the largest speed change the forces gave a
    /// particle in the step (m/s).
    ///
    /// One pass over the particles: each one's swept displacement max(|x0 − b|, |x1 − b|) +
    /// ⅛ |a| h² (b its build position) and the two largest of them; its velocity change
    /// |v1 − v0| for the automatic threshold (twice the largest: a body resting under gravity
    /// approaches at g h each step).
    ///
    /// With `quiet` (a force-free step with valid meeting times) the list's hold comes from the
    /// meetings' speed bound instead, with no pass (`collide/quiet.rs`), and the automatic
    /// threshold and speed change are 0 (no force changes a velocity). Sets `rebuilt` when it
    /// rebuilds.
    pub(super) fn prepare(
        &mut self,
        set: &StageSetting<'_>,
        paths: &Paths<'_>,
        x1: &[f64],
        v1: &[f64],
        h: f64,
        quiet: bool,
    ) -> Result<(f64, f64, f64), Error> {
        let reach = self.meetings.reach_after(h);
        let (x0, v0) = (paths.x0, paths.v0);
        // (the per-particle bounds are made by the sweep below; a quiet step has the one)
        self.bounded = false;
        if quiet && self.list.built_at.len() == x0.len() && 2.0 * reach < self.list.allowance {
            return Ok((set.restitution_threshold.unwrap_or(0.0), reach, 0.0));
        }
        let domain = *set.domain;
        // (each particle's swept displacement is also its bound for the impact search,
        // `events::SweepBound`, written into `bounds`)
        let sweep = |built: &[f64], accel: &[f64], bounds: &mut [f64]| {
            x0.par_chunks(3 * CHUNK)
                .zip(x1.par_chunks(3 * CHUNK))
                .zip(built.par_chunks(3 * CHUNK))
                .zip(bounds.par_chunks_mut(CHUNK))
                .enumerate()
                .map(|(c, (((x0, x1), b), bounds))| {
                    let mut top = Sweep::default();
                    for l in 0..x0.len() / 3 {
                        let q = c * CHUNK + l;
                        let bq = vec3::get(b, l);
                        let d0 = domain.displacement(vec3::get(x0, l), bq);
                        let d1 = domain.displacement(vec3::get(x1, l), bq);
                        let a = vec3::get(accel, q);
                        let bulge2 = vec3::dot(a, a);
                        let bulge = if bulge2 > 0.0 { 0.125 * bulge2.sqrt() * h * h } else { 0.0 };
                        let d = vec3::dot(d0, d0).max(vec3::dot(d1, d1)).sqrt() + bulge;
                        bounds[l] = d;
                        let step = domain.displacement(vec3::get(x1, l), vec3::get(x0, l));
                        let w = vec3::sub(vec3::get(v1, q), vec3::get(v0, q));
                        top = top.with(Sweep {
                            first: d,
                            second: 0.0,
                            kick2: vec3::dot(w, w),
                            nan: d.is_nan(),
                            step: vec3::norm(step) + bulge,
                        });
                    }
                    top
                })
                .reduce(Sweep::default, Sweep::with)
        };
        // (with `quiet` the bound said the list may not hold: rebuilt without the check, which
        // the actual displacements would pass only for a few more steps)
        let fresh = self.list.built_at.len() == x0.len() && !quiet;
        let mut bounds = std::mem::take(&mut self.bounds);
        bounds.resize(x0.len() / 3, 0.0);
        let mut top = if fresh {
            sweep(&self.list.built_at, paths.accel, &mut bounds)
        } else {
            Sweep {
                first: f64::INFINITY,
                ..Sweep::default()
            }
        };
        let holds = top.first + top.second < self.list.allowance;
        // A list built for a fast step (its skin four of that step's largest sweeps) is
        // rebuilt once the steps are much slower, though it still holds: a pile that came to
        // rest with the skin of its fall kept every particle's candidates within that skin
        // (at 60 Hz, the whole of the demo's box), and every impact swept them all again.
        let loose = self.list.skin > LOOSE * self.base_skin.max(4.0 * top.step);
        if top.nan || !holds || loose {
            // Rebuild at x0, with a skin of the base (0.6 mean radius) or four of this step's
            // largest sweeps, whichever is more: the list then lasts at least two such steps.
            let accel = paths.accel;
            let (largest_move, fastest) = (0..set.radius.len())
                .into_par_iter()
                .with_min_len(CHUNK)
                .map(|q| {
                    let a = vec3::norm(vec3::get(accel, q));
                    let d = vec3::norm(domain.displacement(vec3::get(x1, q), vec3::get(x0, q))) + 0.125 * a * h * h;
                    (d, q)
                })
                .reduce(|| (0.0, 0), |a, b| if b.0 > a.0 || (b.0 == a.0 && b.1 < a.1) { b } else { a });
            check_travel(set.colliders, set.radius, x0, largest_move, fastest, h)?;
            self.build_list(set, x0, largest_move)?;
            self.rebuilt = true;
            top = sweep(&self.list.built_at, paths.accel, &mut bounds);
            if top.nan || !top.first.is_finite() {
                // non-finite positions: the list's build named them already; a NaN velocity
                // change is caught by the world
                top.first = f64::INFINITY;
            }
        }
        self.bounds = bounds;
        self.bounded = true;
        let kick = top.kick2.sqrt();
        let threshold = set.restitution_threshold.unwrap_or(2.0 * kick);
        Ok((threshold, top.first, kick))
    }

    /// Continuous detection and the impacts in time order (see [`ImpulseModel::step`]):
    /// returns the time spent detecting, responding and distributing, and whether any impulse
    /// was applied. `reach`: the largest swept displacement from the list's build positions.
    pub(super) fn impacts(
        &mut self,
        s: &Search<'_, '_>,
        paths: &mut Paths<'_>,
        mut reach: f64,
        only_due: bool,
        stats: &mut CollisionStats,
        omega: &mut [f64],
    ) -> Result<(Duration, Duration, Duration, bool), Error> {
        let (h, threshold) = (s.h, s.threshold);
        let (inv_mass, mass) = (s.set.inv_mass, s.set.mass);
        let n = s.set.radius.len();
        let clock = Instant::now();
        if only_due {
            self.schedule_due(s, paths, reach);
        } else {
            self.schedule_all(s, paths, 0.0, reach);
        }
        let (mut t_detect, mut t_respond, mut t_distribute) = (clock.elapsed(), Duration::ZERO, Duration::ZERO);
        // A cap keeps an inelastic collapse (a particle wedged between two others, hit back
        // and forth ever faster) from looping: what is left goes to the end-of-step solver.
        let cap = 1000 * n + 100_000;
        let mut processed = 0;
        let mut any = false;
        loop {
            let clock = Instant::now();
            let Some(event) = self.queue.pop() else { break };
            let t = event.time;
            let around = surroundings!(self, s, reach);
            let partner = match event.partner {
                Partner::Particle(j) => Some(j),
                Partner::Collider(_) => None,
            };
            if partner.is_some_and(|j| paths.version(j) != event.partner_version) {
                // the partner's path changed since: predicted on a path that no longer exists
                let next = around.earliest(paths, event.i, t, h);
                if next.touching {
                    self.touched.mark(event.i);
                }
                self.queue.schedule(event.i, next.event);
                t_detect += clock.elapsed();
                continue;
            }
            processed += 1;
            if processed % 256 == 0 {
                self.interrupt.poll()?; // a stop leaves the meeting times invalid (see `stages`)
            }
            if processed > cap {
                stats.unconverged += 1;
                self.touched.mark_all();
                t_detect += clock.elapsed();
                break;
            }
            paths.advance(event.i, t);
            if let Some(j) = partner {
                paths.advance(j, t);
            }
            let contact = contact_at(s.set, paths, &event, h);
            t_detect += clock.elapsed();

            // Stage 3: the impulse of Newton's law at the impact.
            let clock = Instant::now();
            let impulse = contact.and_then(|c| {
                let material = s.set.materials.pair(&c);
                let spin = s.set.rotation.map(|r| r.of(&c, omega));
                restitution_impulse(&c, paths.v_ref(), inv_mass, material, threshold, spin).map(|imp| (imp, c))
            });
            t_respond += clock.elapsed();

            // Stage 4: onto both particles.
            let clock = Instant::now();
            if let Some((imp, c)) = impulse {
                if let Some(r) = s.set.rotation {
                    r.kick(&c, c.overlap, imp.vector, omega);
                }
                any = true;
                stats.impacts += 1;
                stats.impulses += 1;
                if let Some(c) = contact {
                    self.touches
                        .hit(s.t0 + t, event.i, event.partner, vec3::dot(imp.vector, c.normal));
                }
                stats.energy_lost += imp.energy_lost;
                distribute(
                    event.i,
                    partner,
                    imp.vector,
                    paths.v_ref_mut(),
                    inv_mass,
                    mass,
                    &mut stats.impulse_balance,
                );
                if let Some(j) = partner {
                    let d = s.set.domain.displacement(paths.x_ref(event.i), paths.x_ref(j));
                    super::add_outer(&mut stats.virial, d, imp.vector);
                }
                if let (Partner::Collider(k), Some(c)) = (event.partner, contact) {
                    let at = vec3::sub(paths.x_ref(event.i), vec3::scale(s.set.radius[event.i], c.normal));
                    self.collider_books[k].book(at, c.wall_velocity, imp.vector, c.normal);
                }
                for q in std::iter::once(event.i).chain(partner) {
                    paths.changed(q);
                    self.touched.mark(q);
                    self.fastest_hit = self.fastest_hit.max(vec3::norm(vec3::get(paths.v_ref(), q)));
                }
            }
            t_distribute += clock.elapsed();

            // Stage 2 again: the two particles' next impacts, on the list if it still holds.
            let clock = Instant::now();
            let built = &self.list.built_at;
            let swept =
                [Some(event.i), partner].map(|q| q.map(|q| (q, swept_reach(paths, q, t, h, vec3::get(built, q), s.set.domain))));
            let farthest = swept.iter().flatten().map(|&(_, r)| r).fold(0.0, f64::max);
            if farthest + reach >= self.list.allowance {
                // a new path could reach beyond the list: rebuild it at t, predict everything again
                reach = self.rebuild_at(s.set, paths, t, h)?;
                self.rebuilt = true;
                self.schedule_all(s, paths, t, reach);
            } else {
                reach = reach.max(farthest);
                if self.bounded {
                    // (the new paths' bounds from t on; the larger keeps it a bound of both)
                    for &(q, r) in swept.iter().flatten() {
                        self.bounds[q] = self.bounds[q].max(r);
                    }
                }
                let around = surroundings!(self, s, reach);
                for q in std::iter::once(event.i).chain(partner) {
                    if impulse.is_some() || q == event.i {
                        let next = around.earliest(paths, q, t, h);
                        if next.touching {
                            self.touched.mark(q);
                        }
                        self.queue.schedule(q, next.event);
                    }
                }
            }
            t_detect += clock.elapsed();
        }
        Ok((t_detect, t_respond, t_distribute, any))
    }

    /// Every particle's first impact after `now` into the queue (the queue emptied first),
    /// on all threads; with `flag`, the particles touching something at `now` are marked.
    fn schedule_all(&mut self, s: &Search<'_, '_>, paths: &Paths<'_>, now: f64, reach: f64) {
        let n = s.set.radius.len();
        let around = surroundings!(self, s, reach);
        let (mut events, touching) = around.all_impacts(paths, now, s.h);
        for q in touching {
            self.touched.mark(q);
        }
        // Each particle's earliest: every pair's impact counts for both of its particles.
        let mirrored: Vec<Event> = events
            .iter()
            .filter_map(|e| match e.partner {
                Partner::Particle(j) => Some(Event {
                    i: j,
                    partner: Partner::Particle(e.i),
                    partner_version: paths.version(e.i),
                    ..*e
                }),
                Partner::Collider(_) => None,
            })
            .collect();
        events.extend(mirrored);
        events.sort_by(|a, b| a.i.cmp(&b.i).then(a.time.total_cmp(&b.time)).then(a.partner.cmp(&b.partner)));
        self.queue.reset(n);
        let mut last = usize::MAX;
        for e in events {
            if e.i != last {
                self.queue.schedule(e.i, Some(e));
                last = e.i;
            }
        }
    }

    /// The first impacts of the particles due in this step only (the others are quiet:
    /// their lines meet nothing in it, `collide/quiet.rs`), into the emptied queue.
    fn schedule_due(&mut self, s: &Search<'_, '_>, paths: &Paths<'_>, reach: f64) {
        self.queue.reset(s.set.radius.len());
        let around = surroundings!(self, s, reach);
        for &q in &self.due {
            let next = around.earliest(paths, q, 0.0, s.h);
            if next.touching {
                self.touched.mark(q);
            }
            self.queue.schedule(q, next.event);
        }
    }

    /// The meeting times at time `end` (world clock, s) of a force-free world in state x1, v1
    /// (`collide/quiet.rs`). `incremental` (at the end of a step that looked only at the due
    /// particles): the times of the rest still hold, and only the particles this step looked
    /// at or changed get new ones (the bound grows by the step); otherwise all are computed
    /// again, with the bound measured. Leaves `meetings.valid` set if the list holds.
    pub(super) fn next_meetings(&mut self, set: &StageSetting<'_>, x1: &[f64], v1: &[f64], end: f64, h: f64, incremental: bool) {
        let n = set.radius.len();
        let domain = *set.domain;
        if incremental {
            // The touched particles (all of them have reference states) moved at most at the
            // fastest speed of the step, plus what the end-of-step solve moved them by.
            let (mut moved, mut fastest_after) = (0.0_f64, 0.0_f64);
            for &(q, x, _) in &self.references {
                moved = moved.max(vec3::norm(domain.displacement(vec3::get(x1, q), x)));
                fastest_after = fastest_after.max(vec3::norm(vec3::get(v1, q)));
            }
            let fastest = self.meetings.vmax.max(self.fastest_hit);
            self.meetings.reach += h * fastest + moved;
            self.meetings.vmax = fastest.max(fastest_after);
        } else {
            let built = &self.list.built_at;
            let (reach, vmax) = (0..n)
                .into_par_iter()
                .with_min_len(CHUNK)
                .map(|q| {
                    let d = domain.displacement(vec3::get(x1, q), vec3::get(built, q));
                    (vec3::norm(d), vec3::norm(vec3::get(v1, q)))
                })
                .reduce(|| (0.0, 0.0), |a, b| (a.0.max(b.0), a.1.max(b.1)));
            self.meetings.reach = reach;
            self.meetings.vmax = vmax;
        }
        if !(2.0 * self.meetings.reach < self.list.allowance) {
            return; // the list expires now: the next step rebuilds it and looks at everyone
        }
        // Meetings up to the list's expiry, and a step beyond it.
        let horizon = self.meetings.horizon(self.list.allowance) + h;
        let active = active_walls(set.colliders, set.domain);
        let search = Search {
            set,
            active: &active,
            t0: end,
            h,
            threshold: 0.0,
        };
        let around = surroundings!(self, search, f64::INFINITY);
        let at = |q: usize| around.first_meeting(x1, v1, q, horizon).map(|tau| end + tau);
        if incremental {
            let mut involved: Vec<usize> = self.references.iter().map(|b| b.0).chain(self.due.iter().copied()).collect();
            involved.sort_unstable();
            involved.dedup();
            // (each one's meeting is its own search: on all threads, set in order)
            let times: Vec<(usize, Option<f64>)> = involved.into_par_iter().with_min_len(CHUNK / 8).map(|q| (q, at(q))).collect();
            for (q, time) in times {
                self.meetings.table.set(q, time);
            }
        } else {
            let times: Vec<(usize, f64)> = (0..n)
                .into_par_iter()
                .with_min_len(CHUNK)
                .filter_map(|q| at(q).map(|t| (q, t)))
                .collect();
            self.meetings.table.fill(n, times.into_iter());
        }
        self.meetings.valid = true;
    }

    /// Rebuilds the list at the particles' positions at time t (their references moved there)
    /// for the rest of the step; returns the largest swept displacement from there, m.
    fn rebuild_at(&mut self, set: &StageSetting<'_>, paths: &mut Paths<'_>, t: f64, h: f64) -> Result<f64, Error> {
        let n = set.radius.len();
        let mut x = vec![0.0; 3 * n];
        let (mut largest, mut fastest) = (0.0_f64, 0);
        // (each particle's sweep from x is its bound for the rest of the step)
        self.bounds.resize(n, 0.0);
        for q in 0..n {
            paths.advance(q, t);
            x[3 * q..3 * q + 3].copy_from_slice(&paths.x_ref(q));
            let reach = swept_reach(paths, q, t, h, vec3::get(&x, q), set.domain);
            self.bounds[q] = reach;
            if reach > largest {
                (largest, fastest) = (reach, q);
            }
        }
        self.bounded = true;
        check_travel(set.colliders, set.radius, &x, largest, fastest, h - t)?;
        self.build_list(set, &x, largest)?;
        Ok(largest)
    }

    /// Builds the candidate list at `x` for paths that sweep at most `largest` (m) from there
    /// in the step: with a skin of the base (0.6 mean radius) or four of `largest`, whichever
    /// is more, so that it lasts at least two such steps. Where that list would pass its
    /// memory bound (a whole lattice falling fast at 60 Hz: each ball's candidates within
    /// four of its 10 cm sweep), one with a skin of [`LEAST_SWEEPS`] of `largest`, which holds
    /// for this step and is built again at the next.
    fn build_list(&mut self, set: &StageSetting<'_>, x: &[f64], largest: f64) -> Result<(), Error> {
        let (radius, colliders, domain, filter) = (set.radius, set.colliders, set.domain, set.filter);
        self.base_skin = base_skin(radius);
        match self.build_with_skin(x, self.base_skin.max(4.0 * largest), radius, colliders, domain, filter) {
            Err(Error::OutOfMemory { .. }) if LEAST_SWEEPS * largest > self.base_skin => {
                self.build_with_skin(x, LEAST_SWEEPS * largest, radius, colliders, domain, filter)
            }
            done => done,
        }
    }

    /// Builds the candidate list at `x` (m, 3 per particle) with `skin` (m), of the pairs that
    /// collide (`filter`: the collision groups, `None` when all do).
    fn build_with_skin(
        &mut self,
        x: &[f64],
        skin: f64,
        radius: &[f64],
        colliders: &[Collider],
        domain: &Domain,
        filter: Option<Filter<'_>>,
    ) -> Result<(), Error> {
        let build = ListBuild {
            skin,
            reach: 0.0,
            collider_scale: colliders.iter().map(collider_scale).fold(0.0, f64::max),
        };
        self.list.built_at.clear();
        self.list.verified = None;
        self.list
            .update(&mut self.grid, x, radius, colliders, domain, filter, || build)
    }

    /// The candidate list's build as a checkpoint keeps it: the positions it was built at
    /// (m, 3 per particle) and its skin (m); `None` before a first build.
    ///
    /// The list is a cache, but when it is built decides two things of a step's bits: a
    /// rebuild inside a step moves every path's reference to that time, and the impacts are
    /// predicted again from there. A resumed run that built its list afresh went on to other
    /// bits than the run it continues (a heap of 18 balls, resumed every 25 steps: 3 of 19
    /// resumes differed within 300 steps); built where the written run had built it, the
    /// list holds as long and is rebuilt at the same steps.
    pub fn list_carry(&self) -> Option<(Vec<f64>, f64)> {
        (!self.list.built_at.is_empty()).then(|| (self.list.built_at.clone(), self.list.skin))
    }

    /// Builds the list at `built_at` (m, 3 per particle) with `skin` (m), as
    /// [`ImpulseModel::list_carry`] gave them: the list the written run had.
    pub fn restore_list(
        &mut self,
        built_at: &[f64],
        skin: f64,
        radius: &[f64],
        colliders: &[Collider],
        domain: &Domain,
        filter: Option<Filter<'_>>,
    ) -> Result<(), Error> {
        self.base_skin = base_skin(radius);
        self.build_with_skin(built_at, skin, radius, colliders, domain, filter)
    }
}

/// The least skin of a list of particles of these radii, m: [`SKIN_PER_RADIUS`] of the mean.
fn base_skin(radius: &[f64]) -> f64 {
    SKIN_PER_RADIUS * radius.iter().sum::<f64>() / radius.len().max(1) as f64
}

/// How many times the scene's extent a particle may travel in the rest of a step: more would
/// take more impacts than the step's cap (1000 a particle) to follow, each predicted against a
/// candidate list that holds every particle the sweep reaches.
pub(crate) const TRAVEL_LIMIT: f64 = 1000.0;

/// Stops a step (a divergence, [`Divergence::TooFast`]) in which particle `fastest` travels
/// `largest` (m) in the `rest` of the step (s), more than [`TRAVEL_LIMIT`] times the extent of the scene: the box around the
/// particles at `x` (m) and the box colliders (their finite sides). Such speeds (2.3e16 m/s in
/// a 10 m box: 5 s a step for 1,000 particles) bounce to the cap of continuous detection in
/// every step while resolving nothing. An extent of 0 (one particle, no box) has nothing to
/// bounce between.
pub(crate) fn check_travel(
    colliders: &[Collider],
    radius: &[f64],
    x: &[f64],
    largest: f64,
    fastest: usize,
    rest: f64,
) -> Result<(), Error> {
    if !(largest > 0.0) {
        return Ok(());
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    let mut grow = |p: [f64; 3]| {
        for k in 0..3 {
            if p[k].is_finite() {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    };
    x.chunks_exact(3).for_each(|p| grow([p[0], p[1], p[2]]));
    for c in colliders {
        if let Collider::Box(b) = c {
            grow(b.lo());
            grow(b.hi());
        }
    }
    let extent = (0..3)
        .map(|k| if hi[k] >= lo[k] { hi[k] - lo[k] } else { 0.0 })
        .fold(0.0, f64::max);
    let r_max = radius.iter().copied().fold(0.0, f64::max);
    let scale = extent + 2.0 * r_max;
    if scale > 0.0 && largest > TRAVEL_LIMIT * scale {
        // (the world fills in the step, the time and the advice: World::collide)
        return Err(Error::Diverged {
            step: 0,
            time: 0.0,
            particle: Some(fastest),
            dt: rest,
            reason: Divergence::TooFast {
                travel: largest,
                extent: scale,
                limit: TRAVEL_LIMIT,
            },
            advised_dt: None,
            verlet_only: false,
        });
    }
    Ok(())
}

/// The contact of an event at its time (the particles already moved there).
fn contact_at(set: &StageSetting<'_>, paths: &Paths<'_>, e: &Event, h: f64) -> Option<Contact> {
    let at = paths.x_ref(e.i);
    // A moving collider stands where it will be at the step's end: the particle is seen
    // moved with the surface's motion over the rest of the step (`events.rs`). A turning
    // one's surface velocity is then that carriage's chord, (x' − x)/(h − t), the one the
    // detection's path saw: the impulse leaves the particle leaving on that path, where
    // the surface's velocity at the impact would leave it meeting the wall again at once.
    let back = h - e.time;
    let (xi, field) = match e.partner {
        Partner::Collider(k) if set.colliders[k].is_moving() => {
            let field = set.colliders[k].surface().velocity();
            (field.moved_with(at, back), Some(field))
        }
        _ => (at, None),
    };
    let unit = |d: [f64; 3]| {
        let len = vec3::norm(d);
        (len > 0.0).then(|| vec3::scale(1.0 / len, d))
    };
    let normal = match e.partner {
        Partner::Particle(j) => unit(set.domain.displacement(xi, paths.x_ref(j)))?,
        Partner::Collider(k) => match &set.colliders[k] {
            Collider::Plane(p) => p.normal(),
            Collider::Box(b) => b.walls()[e.wall].normal(),
            Collider::Sphere(s) => unit(vec3::sub(xi, s.center()))?,
            Collider::Mesh(m) => m.touch_of_triangle(e.wall, xi, set.radius[e.i]).normal,
        },
    };
    let wall_velocity = match field {
        Some(f) if f.angular != [0.0; 3] && back > 0.0 => vec3::scale(1.0 / back, vec3::sub(xi, at)),
        Some(f) => f.at(vec3::sub(xi, vec3::scale(set.radius[e.i], normal))),
        None => [0.0; 3],
    };
    Some(Contact {
        i: e.i,
        other: e.partner,
        normal,
        overlap: 0.0,
        u_n: 0.0,
        wall_velocity,
    })
}

/// Combines (largest, second largest, largest velocity change, NaN met) of two parts.
/// What `prepare` learns of the step's paths in one pass: the two largest displacements
/// from the list's build positions over the step (m), the largest velocity change squared
/// (m²/s²), whether a displacement is NaN, and the largest displacement over the step (m).
#[derive(Debug, Clone, Copy, Default)]
struct Sweep {
    first: f64,
    second: f64,
    kick2: f64,
    nan: bool,
    step: f64,
}

impl Sweep {
    /// Both passes' figures together.
    fn with(self, b: Sweep) -> Sweep {
        Sweep {
            first: self.first.max(b.first),
            second: self.first.min(b.first).max(self.second).max(b.second),
            kick2: self.kick2.max(b.kick2),
            nan: self.nan || b.nan,
            step: self.step.max(b.step),
        }
    }
}

/// The least skin of a candidate list, in sweeps of the step it is built for: the two
/// particles that sweep farthest may together sweep two (the list must hold for them), and
/// the rest is room for the rounding allowance and the list's own check.
const LEAST_SWEEPS: f64 = 2.5;

/// A list whose skin is more than this many times what a rebuild now would choose is rebuilt
/// (a factor that leaves room for the steps' speeds to vary without a rebuild each step).
const LOOSE: f64 = 4.0;
