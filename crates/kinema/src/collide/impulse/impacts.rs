//! Continuous detection of the impulse model and its impacts in time order (stages 2–4 inside
//! the step, [`ImpulseModel::step`]; the neighbour list made to hold for the step's sweep is
//! `list.rs`'s): each particle's first impact into the queue, the impacts popped in time
//! order, each resolved by Newton's law and distributed at its time, and the force-free
//! world's meeting times (`quiet.rs`) for the next steps.

use std::time::{Duration, Instant};

use rayon::prelude::*;

use super::end_of_step::distribute;
use super::{CollisionStats, ImpulseModel, StageSetting};
use crate::collide::events::{swept_reach, Event, Paths, Surroundings, SweepBound};
use crate::collide::neighbour_list::{active_walls, CHUNK};
use crate::collide::response::VELOCITY_TOLERANCE;
use crate::collide::{restitution_impulse, Collider, Contact, Impulse, Partner};
use crate::error::Error;
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
        let inv_mass = s.set.inv_mass;
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
                self.apply_impact(s, paths, (&event, partner), (imp, c), contact, stats, omega);
                any = true;
            }
            t_distribute += clock.elapsed();

            // Stage 2 again: the two particles' next impacts, on the list if it still holds.
            let clock = Instant::now();
            reach = self.next_impacts(s, paths, (&event, partner), reach, impulse.is_some())?;
            t_detect += clock.elapsed();
        }
        Ok((t_detect, t_respond, t_distribute, any))
    }

    /// Stage 4 of an impact: its impulse `imp` (at contact `c`) onto both particles (and their
    /// spins), the step's figures, the touch, the collider's books; the two particles' paths
    /// changed from the impact's time on.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn apply_impact(
        &mut self,
        s: &Search<'_, '_>,
        paths: &mut Paths<'_>,
        (event, partner): (&Event, Option<usize>),
        (imp, c): (Impulse, Contact),
        contact: Option<Contact>,
        stats: &mut CollisionStats,
        omega: &mut [f64],
    ) {
        let t = event.time;
        let (inv_mass, mass) = (s.set.inv_mass, s.set.mass);
        if let Some(r) = s.set.rotation {
            r.kick(&c, c.overlap, imp.vector, omega);
        }
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

    /// Stage 2 again after an impact: the next impacts of its particle and (if it was `hit`)
    /// its partner, on the list if it still holds for their new paths, else on a list
    /// rebuilt at the impact's time (everyone's again). Returns the largest swept
    /// displacement from the list's build positions, `reach` before.
    #[inline]
    fn next_impacts(
        &mut self,
        s: &Search<'_, '_>,
        paths: &mut Paths<'_>,
        (event, partner): (&Event, Option<usize>),
        reach: f64,
        hit: bool,
    ) -> Result<f64, Error> {
        let (t, h) = (event.time, s.h);
        let built = &self.list.built_at;
        let swept =
            [Some(event.i), partner].map(|q| q.map(|q| (q, swept_reach(paths, q, t, h, vec3::get(built, q), s.set.domain))));
        let farthest = swept.iter().flatten().map(|&(_, r)| r).fold(0.0, f64::max);
        if farthest + reach >= self.list.allowance {
            // a new path could reach beyond the list: rebuild it at t, predict everything again
            let reach = self.rebuild_at(s.set, paths, t, h)?;
            self.rebuilt = true;
            self.schedule_all(s, paths, t, reach);
            Ok(reach)
        } else {
            let reach = reach.max(farthest);
            if self.bounded {
                // (the new paths' bounds from t on; the larger keeps it a bound of both)
                for &(q, r) in swept.iter().flatten() {
                    self.bounds[q] = self.bounds[q].max(r);
                }
            }
            let around = surroundings!(self, s, reach);
            for q in std::iter::once(event.i).chain(partner) {
                if hit || q == event.i {
                    let next = around.earliest(paths, q, t, h);
                    if next.touching {
                        self.touched.mark(q);
                    }
                    self.queue.schedule(q, next.event);
                }
            }
            Ok(reach)
        }
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
