//! One step of the impulse model, stages 2–4 of the seed's step, as a list of stages
//! ([`ImpulseStage::ALL`], as Box2D v3's `b2SolverStage` and Rapier's `step_inner` list
//! theirs): [`ImpulseModel::step`] runs them in order, each with its own timer, and each
//! stage below is the glue between the kernels it calls (`impacts.rs`, `end_of_step.rs`).
//!
//! ```text
//!   (before)  the islands asleep that an awake particle meets within the step wake
//!             (`wake_reached`); the other sleepers are held at rest
//!   list      the neighbour list holds for the step's sweep (else rebuilt at x₀); the
//!             restitution threshold; who is looked at (the touched particles)
//!   impacts   with ccd: each particle's first impact into the queue, then in time order
//!             Newton's law at the impact (response.rs), +w_i J on i and −w_j J on j, the
//!             two particles' next impacts
//!   contacts  the paths finished; the contacts at the step's end of the touched particles
//!             and of the piles they reach (waking the islands asleep they touch)
//!   solve     the soft step's totals, island by island (warm-started from the records);
//!             the positions follow its solve stage (`end_of_step.rs`, `solve`)
//!   apply     each total onto both particles (and the shock stages' kicks); energy lost
//!   settle    calm islands fall asleep; the largest overlap; positions into the cell;
//!             begin and end of touch
//!   meetings  a force-free world's next meeting times (timed as "wake")
//! ```
//!
//! The order matters: the impacts change the paths the end-of-step contacts are found on,
//! and the solve needs contacts that describe the positions the impacts left. What one
//! stage hands the next that is not the model's own buffers is in [`StepState`].

use std::time::{Duration, Instant};

use super::end_of_step::distribute;
use super::impacts::{least_impact_speed, Search};
use super::{add_outer, CollisionStats, CollisionTimes, ImpulseModel, ImpulseStage, StageSetting, StepFrame};
use crate::collide::books::ColliderBooks;
use crate::collide::contact::action_reaction;
use crate::collide::events::Paths;
use crate::collide::islands::IslandStats;
use crate::collide::neighbour_list::{active_walls, CHUNK};
use crate::collide::paths::{pair_toi, Toi};
use crate::collide::records::ContactRecord;
use crate::collide::Partner;
use crate::error::Error;
use crate::vec3;

/// What the stages of one step hand each other.
#[derive(Default)]
struct StepState {
    stats: CollisionStats,
    /// Whether any velocity or position changed.
    changed: bool,
    /// The restitution threshold (m/s), the largest displacement swept from the list's build
    /// positions (m) and the largest velocity change of stage 1 (m/s), from the list stage.
    threshold: f64,
    reach: f64,
    kick: f64,
    /// A force-free step with continuous detection (the meeting times hold), and whether only
    /// the particles due in it are searched.
    steady: bool,
    only_due: bool,
    /// The impacts stage's time spent responding and distributing (the rest is detecting).
    impacts_respond: Duration,
    impacts_distribute: Duration,
}

/// The step's times: each stage's lap, and the seed's three stages from the same laps (the
/// impacts interleave all three).
fn collision_times(laps: [Duration; 7], step: &StepState) -> CollisionTimes {
    let lap = |s: ImpulseStage| laps[s as usize];
    let (respond, distribute) = (step.impacts_respond, step.impacts_distribute);
    CollisionTimes {
        detect: lap(ImpulseStage::List)
            + lap(ImpulseStage::Impacts).saturating_sub(respond + distribute)
            + lap(ImpulseStage::Contacts)
            + lap(ImpulseStage::Meetings),
        respond: respond + lap(ImpulseStage::Solve),
        distribute: distribute + lap(ImpulseStage::Apply) + lap(ImpulseStage::Settle),
        stages: laps,
    }
}

impl ImpulseModel {
    /// Stages 2–4 of the impulse model on the step from (x0, v0) to the integrated (x1, v1),
    /// over `frame.h` s, among the colliders, materials and particles of `set`;
    /// `frame.accel` is the step's constant acceleration where the method knows it
    /// (velocity Verlet's a(t)), else it is the one that takes x0, v0 to x1. (x1, v1) are
    /// updated in place; returns whether anything changed, what the stages did and their
    /// time (for the world's books: an error books nothing).
    ///
    /// With spin (`set.rotation`), `omega` holds the angular velocities (rad/s, 3 per
    /// particle; empty without): every impulse acts at its contact point and turns both
    /// particles (`collide/spin.rs`), and friction acts on the contact point's velocity.
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &mut self,
        set: &StageSetting<'_>,
        frame: &StepFrame<'_>,
        x0: &[f64],
        v0: &[f64],
        x1: &mut [f64],
        v1: &mut [f64],
        omega: &mut [f64],
    ) -> Result<(bool, CollisionStats, CollisionTimes), Error> {
        let mut laps = [Duration::ZERO; 7];
        let mut at = Instant::now();
        self.collider_books.clear();
        self.collider_books.resize(set.colliders.len(), ColliderBooks::default());
        let (woke, sleeping) = self.sleepers(set, frame, (x0, v0), (x1, v1))?;
        // The step's paths: Verlet's own acceleration, or the parabola through x1 (the path
        // store is lent out of the model for the step, and given back whatever happens).
        let mut store = std::mem::take(&mut self.paths);
        let mut fitted = std::mem::take(&mut self.fitted);
        let h = frame.h;
        let accel = match frame.accel {
            Some(a) if sleeping => {
                fitted.clear();
                fitted.extend_from_slice(a);
                for q in (0..x0.len() / 3).filter(|&q| self.sleep.is_asleep(q)) {
                    fitted[3 * q..3 * q + 3].fill(0.0);
                }
                &fitted
            }
            Some(a) => a,
            None => fit_parabolas(&mut fitted, (x0, v0, x1), h),
        };
        let mut paths = Paths::begin(&mut store, x0, v0, accel);
        // The forces' own accelerations, for the energy lost: the fitted parabola is the
        // force for the second-order methods only (Euler's x₁ has none, symplectic Euler's twice).
        let mut forced = std::mem::take(&mut self.forced);
        let forces = match frame.accel {
            Some(a) => a,
            None => velocity_slopes(&mut forced, (v0, v1), h),
        };
        let mut step = StepState::default();
        step.stats.woke = woke;
        let mut ran = Ok(());
        for stage in ImpulseStage::ALL {
            let (paths, x1, v1, omega) = (&mut paths, &mut *x1, &mut *v1, &mut *omega);
            ran = match stage {
                ImpulseStage::List => self.list_stage(set, frame, paths, x1, v1, &mut step),
                ImpulseStage::Impacts => self.impacts_stage(set, frame, paths, omega, &mut step),
                ImpulseStage::Contacts => self.contacts_stage(set, frame, paths, (x1, v1, omega), &mut step),
                ImpulseStage::Solve => self
                    .solve(set, paths, frame.h, (v1, omega), x1, step.threshold, frame.steady)
                    .map(|solved| self.count_solve(&solved, &mut step)),
                ImpulseStage::Apply => self.apply_stage(set, forces, (x1, v1, omega), &mut step),
                ImpulseStage::Settle => self.settle_stage(set, frame, paths, (x1, v1, omega), &mut step),
                ImpulseStage::Meetings => self.meetings_stage(set, frame, x1, v1, &step),
            };
            if ran.is_err() {
                break;
            }
            let now = Instant::now();
            laps[stage as usize] += now - at;
            at = now;
        }
        self.paths = store;
        self.fitted = fitted;
        self.forced = forced;
        ran?;
        let times = collision_times(laps, &step);
        Ok((step.changed, step.stats, times))
    }

    /// Sleeping before the stages: the sleep flags sized (or every island woken where
    /// nothing may sleep), the islands an awake particle meets woken, the others held at rest
    /// with their loads on the colliders. Returns the islands woken and whether any still
    /// sleeps.
    fn sleepers(
        &mut self,
        set: &StageSetting<'_>,
        frame: &StepFrame<'_>,
        (x0, v0): (&[f64], &[f64]),
        (x1, v1): (&mut [f64], &mut [f64]),
    ) -> Result<(usize, bool), Error> {
        // (no pass over the particles where nothing can sleep: a force-free world's step looks
        // only at the particles due, `collide/quiet.rs`)
        if frame.may_sleep && set.sleep_time.is_some() {
            self.sleep.resize(x0.len() / 3);
        } else if !self.sleep.calm.is_empty() {
            self.sleep.wake_all();
        }
        // An island asleep that an awake particle meets within the step wakes first, so that
        // the step runs for it as for the awake, from what stage 1 made of it (a body held at
        // rest would take the impact as an immovable stack of impacts). Any other particle
        // asleep stays where it is, at rest: what the integrator made of it is dropped
        // (x₀ = x₁, v₀ = v₁ = 0, and its path has no acceleration).
        let woke = if self.sleep.any() {
            self.wake_reached(set, frame, (x0, v0), (x1, v1))?
        } else {
            0
        };
        let sleeping = self.sleep.any();
        if sleeping {
            // what the islands still asleep give the colliders over the step: their loads
            self.book_sleepers(x0, set.radius, set.colliders, set.domain);
            for q in (0..x0.len() / 3).filter(|&q| self.sleep.is_asleep(q)) {
                x1[3 * q..3 * q + 3].copy_from_slice(&x0[3 * q..3 * q + 3]);
                v1[3 * q..3 * q + 3].fill(0.0);
            }
        }
        Ok((woke, sleeping))
    }

    /// Wakes each island asleep that an awake movable particle meets within the step on
    /// the paths stage 1 gave both, or with the sleeper held at rest (a meeting at any speed,
    /// touching at the start included: `pair_toi` on the candidates of a list made to hold
    /// for those paths); returns the islands woken. Box2D v3 wakes an island when a contact with it begins; here the
    /// impacts inside the step come before any contact, so the wake comes before them: the
    /// step then runs for the woken as if they had never slept.
    fn wake_reached(
        &mut self,
        set: &StageSetting<'_>,
        frame: &StepFrame<'_>,
        (x0, v0): (&[f64], &[f64]),
        (x1, v1): (&[f64], &[f64]),
    ) -> Result<usize, Error> {
        let (h, n) = (frame.h, x0.len() / 3);
        if self.sleep.asleep() >= n {
            return Ok(0); // no one awake to meet them
        }
        let mut fitted = std::mem::take(&mut self.fitted);
        let accel: &[f64] = match frame.accel {
            Some(a) => a,
            None => fit_parabolas(&mut fitted, (x0, v0, x1), h),
        };
        let mut store = std::mem::take(&mut self.paths);
        let paths = Paths::begin(&mut store, x0, v0, accel);
        // (the list for the paths of all, sleepers' included; its bounds are each one's sweep)
        let prepared = self.prepare(set, &paths, x1, v1, h, false);
        let mut reached = Vec::new();
        if prepared.is_ok() {
            let list = &self.list;
            let slack = (list.skin - list.allowance).max(0.0);
            for i in (0..n).filter(|&i| !self.sleep.is_asleep(i) && set.inv_mass[i] > 0.0) {
                for &j in list.rows[i / CHUNK].of(i % CHUNK) {
                    let j = j as usize;
                    if !self.sleep.is_asleep(j) {
                        continue;
                    }
                    let sum = set.radius[i] + set.radius[j];
                    let apart = set
                        .domain
                        .displacement(vec3::get(&list.built_at, i), vec3::get(&list.built_at, j));
                    let reach = sum + self.bounds[i] + self.bounds[j] + slack;
                    if vec3::dot(apart, apart) > reach * reach {
                        continue; // too far apart to meet in the step
                    }
                    // on j's path awake, or held at rest (as the impacts would see it asleep:
                    // a meeting either way must find j awake)
                    let d0 = set.domain.displacement(vec3::get(x0, i), vec3::get(x0, j));
                    let u = vec3::sub(vec3::get(v0, i), vec3::get(v0, j));
                    let (ai, aj) = (vec3::get(accel, i), vec3::get(accel, j));
                    let meets = |da: [f64; 3]| !matches!(pair_toi(d0, u, da, sum, h, 0.0), Toi::Never);
                    if meets(vec3::sub(ai, aj)) || meets(ai) {
                        reached.push(j);
                    }
                }
            }
        }
        self.paths = store;
        self.fitted = fitted;
        prepared?;
        let mut work = Vec::new();
        let mut woke = 0;
        for j in reached {
            woke += self.wake_island(j, &mut work);
        }
        if woke > 0 {
            self.records.sort();
        }
        Ok(woke)
    }

    /// The list stage: the neighbour list made to hold for the step's sweep, else rebuilt at
    /// x₀ (`impacts.rs`, `prepare`), with a force-free world's meeting times; the restitution
    /// threshold; the particles looked at: those due (force-free), everyone awake (without
    /// ccd), and those named by the last step's contacts (a resting pile is solved at every
    /// step's end, whether or not its pairs touch to the last bit).
    fn list_stage(
        &mut self,
        set: &StageSetting<'_>,
        frame: &StepFrame<'_>,
        paths: &mut Paths<'_>,
        x1: &[f64],
        v1: &[f64],
        step: &mut StepState,
    ) -> Result<(), Error> {
        let (t0, h, n) = (frame.t0, frame.h, set.radius.len());
        // The meeting times hold only if this step ends well (an error leaves them invalid).
        step.steady = frame.steady && set.ccd;
        let quiet = std::mem::replace(&mut self.meetings.valid, false) && step.steady;
        self.rebuilt = false;
        self.fastest_hit = 0.0;
        self.touches.begin_step();
        (step.threshold, step.reach, step.kick) = self.prepare(set, paths, x1, v1, h, quiet)?;
        let mut only_due = quiet && !self.rebuilt;
        if step.steady && !only_due {
            // New meeting times for everyone, from the step's start (one pass over all pairs,
            // instead of a search of this step's impacts from every particle).
            self.next_meetings(set, paths.x0, paths.v0, t0, h, false);
            only_due = std::mem::replace(&mut self.meetings.valid, false);
        }
        // From here `rebuilt`: the list was rebuilt inside the step.
        self.rebuilt = false;
        self.due.clear();
        if only_due {
            self.due = self.meetings.due(t0 + h, h);
        }
        step.only_due = only_due;
        let everyone = !set.ccd && !self.sleep.any();
        self.touched.reset(n, everyone);
        if !set.ccd && !everyone {
            for q in (0..n).filter(|&q| !self.sleep.is_asleep(q)) {
                self.touched.mark(q);
            }
        }
        for &ContactRecord { i, other, .. } in self.records.rows() {
            for q in std::iter::once(i).chain(match other {
                Partner::Particle(j) => Some(j),
                Partner::Collider(_) => None,
            }) {
                if q < n {
                    self.touched.mark(q);
                }
            }
        }
        self.references.clear();
        Ok(())
    }

    /// The impacts stage, with continuous detection (`impacts.rs`, `impacts`).
    fn impacts_stage(
        &mut self,
        set: &StageSetting<'_>,
        frame: &StepFrame<'_>,
        paths: &mut Paths<'_>,
        omega: &mut [f64],
        step: &mut StepState,
    ) -> Result<(), Error> {
        if !set.ccd {
            return Ok(());
        }
        let active = active_walls(set.colliders, set.domain);
        let search = Search {
            set,
            active: &active,
            t0: frame.t0,
            h: frame.h,
            threshold: step.threshold,
        };
        let (_, respond, distribute, any) = self.impacts(&search, paths, step.reach, step.only_due, &mut step.stats, omega)?;
        (step.impacts_respond, step.impacts_distribute) = (respond, distribute);
        step.changed |= any;
        Ok(())
    }

    /// The contacts stage: hit particles end on their last parabola; a sleeper hit inside the
    /// step, or touched by an awake particle at its start, wakes with its island
    /// (`collide/sleep.rs`); the contacts at the step's end of the touched particles and of
    /// the piles they reach (`end_of_step.rs`, `end_contacts`); the reference states for the
    /// energy lost.
    fn contacts_stage(
        &mut self,
        set: &StageSetting<'_>,
        frame: &StepFrame<'_>,
        paths: &mut Paths<'_>,
        (x1, v1, omega): (&mut [f64], &mut [f64], &mut [f64]),
        step: &mut StepState,
    ) -> Result<(), Error> {
        if set.ccd {
            paths.finish(x1, v1, frame.h);
        }
        if self.sleep.any() {
            let mut work = Vec::new();
            let touched: Vec<usize> = self.touched.sorted().to_vec();
            for q in touched {
                if self.sleep.is_asleep(q) {
                    step.stats.woke += self.wake_island(q, &mut work);
                }
            }
            if !work.is_empty() {
                self.records.sort();
            }
        }
        step.stats.woke += self.end_contacts(set, x1, v1);
        step.stats.contacts = self.contacts.len();
        self.detected.clone_from(&self.contacts);
        // The reference state of each touched particle (for the energy lost): its state at the
        // step's start if no impact changed its path (a body at rest then books 0 whatever the
        // method), else the integrated state after its impacts (which booked their own loss).
        for &q in self.touched.sorted() {
            self.references.push(if paths.version(q) == 0 {
                (q, vec3::get(paths.x0, q), vec3::get(paths.v0, q))
            } else {
                (q, vec3::get(x1, q), vec3::get(v1, q))
            });
        }
        // (with spin, each one's angular velocity now: the step's start's, or after its
        // impacts, as above; stage 1 does not turn a particle)
        self.references_spin.clear();
        if set.rotation.is_some() {
            self.references_spin
                .extend(self.references.iter().map(|&(q, _, _)| vec3::get(omega, q)));
        }
        // A pair that only touches (no overlap) and approaches faster than an impact's least
        // speed meets exactly at the step's end: its impact belongs to the next step's t = 0,
        // where the law resolves it pair by pair, like every other impact (with ccd).
        if set.ccd {
            let slow = least_impact_speed(step.threshold);
            self.contacts.retain(|c| !(c.overlap <= 0.0 && c.u_n < -slow));
        }
        Ok(())
    }

    /// What the solve stage did (`end_of_step.rs`, `solve`: the soft step's totals, the
    /// positions moved by its solve stage), counted.
    fn count_solve(&self, solved: &IslandStats, step: &mut StepState) {
        let stats = &mut step.stats;
        stats.solver_sweeps = solved.soft.passes;
        stats.unconverged = stats.unconverged.max(usize::from(!solved.soft.converged));
        stats.islands = solved.islands;
        stats.bounced = solved.soft.bounced;
        stats.resting = self.totals.iter().filter(|p| **p != [0.0; 3]).count();
        stats.speculative = self
            .contacts
            .iter()
            .zip(&self.totals)
            .filter(|(c, p)| **p == [0.0; 3] && c.overlap < 0.0)
            .count();
        step.changed |= self.solved.iter().any(|p| *p != [0.0; 3]);
    }

    /// The apply stage: each total onto both particles (+w_i P on i, −w_j P on j, with spin at
    /// their contact points), the rolling resistance's angular impulses, the shock stages'
    /// kicks; the colliders' books and the energy lost.
    fn apply_stage(
        &mut self,
        set: &StageSetting<'_>,
        forces: &[f64],
        (x1, v1, omega): (&mut [f64], &mut [f64], &mut [f64]),
        step: &mut StepState,
    ) -> Result<(), Error> {
        let stats = &mut step.stats;
        for (k, (c, p)) in self.contacts.iter().zip(&self.totals).enumerate() {
            if *p == [0.0; 3] {
                continue;
            }
            step.changed = true;
            stats.impulses += 1;
            distribute(
                c.i,
                c.partner_particle(),
                *p,
                v1,
                set.inv_mass,
                set.mass,
                &mut stats.impulse_balance,
            );
            if let Some(j) = c.partner_particle() {
                let d = set.domain.displacement(vec3::get(x1, c.i), vec3::get(x1, j));
                add_outer(&mut stats.virial, d, *p);
            }
            if let Some(r) = set.rotation {
                r.kick(c, self.prepared[k].rest, *p, omega);
            }
            if let (Some(r), Some(m)) = (set.rotation, self.rolls.get(k)) {
                // the rolling resistance's angular impulse: +M on i, −M on j
                let k_j = c.partner_particle().map_or(0.0, |j| r.inv_inertia[j]);
                action_reaction(omega, c.i, c.partner_particle(), (r.inv_inertia[c.i], k_j), *m);
            }
            if let Partner::Collider(k) = c.other {
                let at = vec3::sub(vec3::get(x1, c.i), vec3::scale(set.radius[c.i] - c.overlap, c.normal));
                self.collider_books[k].book(at, c.wall_velocity, *p, c.normal);
            }
        }
        // (with shock propagation, what its stages gave with a side held still)
        for &(q, kick) in &self.kicks {
            step.changed = true;
            vec3::add_scaled(v1, q, 1.0, [kick[0], kick[1], kick[2]]);
            if set.rotation.is_some() {
                vec3::add_scaled(omega, q, 1.0, [kick[3], kick[4], kick[5]]);
            }
        }
        stats.energy_lost += self.energy_lost(set, forces, x1, v1, omega);
        Ok(())
    }

    /// The settle stage: islands calm long enough fall asleep (their velocities to 0, that
    /// energy booked); the overlap left; positions into the periodic cell; the pairs that
    /// began or ended touching in this step (when recorded, `collide/touch.rs`).
    fn settle_stage(
        &mut self,
        set: &StageSetting<'_>,
        frame: &StepFrame<'_>,
        paths: &mut Paths<'_>,
        (x1, v1, omega): (&mut [f64], &mut [f64], &mut [f64]),
        step: &mut StepState,
    ) -> Result<(), Error> {
        let stats = &mut step.stats;
        if let (Some(time), true) = (set.sleep_time, frame.may_sleep) {
            let speed = set.sleep_speed.unwrap_or(step.kick);
            let (slept, lost) = self.settle(set, paths.x0, x1, (v1, omega), frame.h, speed, time);
            stats.slept += slept;
            stats.energy_lost += lost;
        }
        stats.asleep = self.sleep.asleep();
        stats.asleep_contacts = self.sleep.contacts();
        if frame.measure_overlap {
            stats.max_overlap = self.max_overlap(set, x1).max(self.sleep.max_overlap());
        }
        if let Some(p) = set.domain.periodic_box() {
            if frame.wrapped {
                // only the touched particles moved since (the impacts, the correction)
                for &(q, _, _) in &self.references {
                    p.wrap_positions_serial(&mut x1[3 * q..3 * q + 3]);
                }
            } else {
                p.wrap_positions(x1);
            }
        }
        let sleep = &self.sleep;
        self.touches.end_step(
            frame.t0 + frame.h,
            &self.contacts,
            &self.totals,
            |q| sleep.is_asleep(q),
            set.id,
        );
        Ok(())
    }

    /// The meetings stage: the next steps' meeting times in a force-free world, of the particles
    /// this step looked at, or of all (`impacts.rs`, `next_meetings`).
    fn meetings_stage(
        &mut self,
        set: &StageSetting<'_>,
        frame: &StepFrame<'_>,
        x1: &[f64],
        v1: &[f64],
        step: &StepState,
    ) -> Result<(), Error> {
        if step.steady {
            let incremental = step.only_due && !self.rebuilt;
            self.next_meetings(set, x1, v1, frame.t0 + frame.h, frame.h, incremental);
        }
        Ok(())
    }
}

/// Each particle's acceleration by the forces over the step when the method gives none:
/// a = (v₁ − v₀) / h (m/s², 3 per particle), written into `out`. Every method's velocity
/// update is v₀ + h a for a force constant over the step (Euler's a(t₀), symplectic and
/// implicit Euler's a(t₁), the Runge–Kutta stages' mean), whatever its position update.
fn velocity_slopes<'a>(out: &'a mut Vec<f64>, (v0, v1): (&[f64], &[f64]), h: f64) -> &'a [f64] {
    out.clear();
    out.extend(v0.iter().zip(v1).map(|(a, b)| (b - a) / h));
    out
}

/// Each particle's constant acceleration over the step when the method gives none: the
/// parabola through x₀ with v₀ that ends at x₁ after h s, a = 2 (x₁ − x₀ − v₀ h) / h²
/// (m/s², 3 per particle), written into `fitted`.
fn fit_parabolas<'a>(fitted: &'a mut Vec<f64>, (x0, v0, x1): (&[f64], &[f64], &[f64]), h: f64) -> &'a [f64] {
    fitted.clear();
    fitted.extend((0..x0.len()).map(|c| 2.0 * (x1[c] - x0[c] - v0[c] * h) / (h * h)));
    fitted
}
