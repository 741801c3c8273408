//! Stages 2–4 of the world's step, the collide stage, as the world holds it: the step's call
//! ([`World::collide`], which runs the impulse model's stages, `collide/impulse/step.rs`) and the user's side of it:
//! turning collisions on, the contact model (the contact force model's force is the collide
//! stage's, lent to each evaluation: `forces.rs`), the particles' own materials, colliders, periodic axes, and what the
//! stage found (contacts, their books).

use super::integrate::WorldStepper;
use super::{CollisionParams, CollisionStats, ContactModel, World};
use crate::collide::stage::{CollideStage, ColliderBooks, StepFrame};
use crate::collide::{Collider, Contact, Motion, Periodic, TouchEvent};
use crate::error::{Divergence, Error};
use crate::forces::EnergyClass;

impl World {
    /// Stages 2–4 on the integrated state in `x_next`, `v_next` (a no-op without collisions):
    /// impacts inside the step and contacts at its end get Newton's restitution impulses,
    /// equal and opposite on the two particles (see [`CollisionParams`]); with
    /// `measure_overlap`, the step's statistics measure the overlap its contacts leave.
    pub(super) fn collide(&mut self, measure_overlap: bool) -> Result<(), Error> {
        let n = 3 * self.particles.len();
        let t_end = self.params_time_after(self.steps + 1);
        let h = self.step_length();
        let Some(stage) = self.collide_stage.as_mut() else {
            return Ok(());
        };
        if n == 0 {
            return Ok(());
        }
        if stage.params.model != ContactModel::Impulse {
            // the contact force model acted in stage 1, as a force; what is left here is
            // keeping positions in the periodic cell (Verlet's drift wrapped them already,
            // before its force evaluation: a second pass would change nothing).
            stage.book_contact_force(h);
            let wrapped = matches!(self.stepper, Some(WorldStepper::Verlet(_)));
            if let Some(p) = stage.domain.periodic_box().filter(|_| !wrapped) {
                p.wrap_positions(&mut self.x_next);
            }
            return Ok(());
        }
        // (the angular velocities lent to the stage for the step, beside the particles it reads)
        let mut omega = std::mem::take(&mut self.particles.omega);
        let p = &self.particles;
        let (x1, v1) = (&mut self.x_next[..], &mut self.v_next[..]);
        let accel = match &self.stepper {
            Some(WorldStepper::Verlet(b)) if b.a.len() == n => Some(&b.a[..]),
            _ => None,
        };
        // Without forces the paths are straight lines from step to step: the stage keeps
        // each particle's meeting time and looks only at those due (collide/quiet.rs). Verlet's
        // force-free pass wrapped x1 into the periodic cell already.
        // (a moving collider meets particles that stay put: no meeting times, no sleep)
        let moving = stage.moves_within(self.time, t_end);
        let steady = self.forces.is_empty() && !moving;
        // Islands may sleep under forces that cannot pull a sleeper nobody looks at: none
        // depends on the positions or adds energy (gravity, drag; `collide/sleep.rs`).
        let may_sleep = !steady
            && !moving
            && self.forces.iter().all(|f| {
                let p = f.properties();
                !p.depends_on_position && p.energy != EnergyClass::Source
            });
        let frame = StepFrame {
            t0: self.time,
            h,
            accel,
            steady,
            wrapped: steady && accel.is_some(),
            may_sleep,
            measure_overlap,
        };
        // (an event-driven world never steps: `World::advance` runs its events)
        let Some((impulse, set)) = stage.impulse_and_setting(p) else {
            return Ok(());
        };
        let ran = impulse.step(&set, &frame, &p.x, &p.v, x1, v1, &mut omega);
        self.particles.omega = omega;
        let changed = match ran {
            Ok((changed, stats, times)) => {
                stage.book_step(stats, times);
                changed
            }
            Err(Error::Diverged { reason, particle, .. }) => return Err(self.diverged(reason, particle)),
            Err(Error::InvalidParameter { .. }) if Self::beyond_geometry(&self.x_next, &self.v_next) => {
                // The collision stages' own quantities (a margin, a threshold) overflowed: the
                // state is too large for their geometry, which squares distances and speeds.
                let fastest = self.fastest(&self.v_next);
                return Err(self.diverged(Divergence::NonFinite, fastest));
            }
            Err(e) => return Err(e),
        };
        if changed {
            // A method's cache (Verlet's last acceleration) holds F at the integrated state;
            // it stays right only if no force depends on positions or velocities.
            let uniform = self.forces.iter().all(|f| f.properties().is_uniform());
            if !uniform {
                match &mut self.stepper {
                    Some(WorldStepper::Verlet(b)) => b.fresh = false, // a_next is stale; keep the buffers
                    _ => self.stepper = None,
                }
            }
        }
        Ok(())
    }

    /// The placement check that is due (`collide/placement.rs`), if any: before the next step,
    /// and before anything that evaluates the forces (the advisor, the accelerations), whose
    /// contact force list would hold the N²/2 pairs of coincident particles.
    pub fn check_pending_placement(&mut self) -> Result<(), Error> {
        match self.placement_from {
            Some(from) => self.check_placement(from),
            None => Ok(()),
        }
    }

    /// Refuses particles `from` on placed inside another particle or a collider when
    /// collisions are on, before the first step after they were placed (`collide/placement.rs`).
    pub(super) fn check_placement(&mut self, from: usize) -> Result<(), Error> {
        if let Some(stage) = &mut self.collide_stage {
            let overlaps = stage.check_placement(&self.particles, from, self.sorted.as_ref().map(|o| o.user_of()))?;
            if let Some(deepest) = overlaps.deepest {
                let count = overlaps.count;
                let many = if count >= crate::collide::placement::COUNT_LIMIT {
                    "at least "
                } else {
                    ""
                };
                self.placement_notice = Some(format!(
                    "{many}{count} overlap{} at the start that the collisions will push apart (more than {} % of the radii; \
                     the deepest: {deepest}): they set the particles moving; place them apart to start at rest",
                    if count == 1 { "" } else { "s" },
                    crate::collide::placement::NOTICE * 100.0
                ));
            }
        }
        self.placement_from = None;
        Ok(())
    }

    /// The overlaps the last placement check accepted but that will push particles apart (a
    /// sentence with their count and the deepest), once: taken by the caller.
    pub fn take_placement_notice(&mut self) -> Option<String> {
        self.placement_notice.take()
    }

    /// The sub-models of the contact force model's contacts (kind and name, as LAMMPS
    /// GRANULAR's `pair granular` names them: `collide/contact_force/sub_models.rs`), the
    /// parts they have now; `None` without a force model.
    pub fn contact_sub_models(&self) -> Option<Vec<(&'static str, &'static str)>> {
        let force = super::forces::contact_force(&self.collide_stage, &self.particles)?;
        Some(force.sub_models().into_iter().map(|(k, name)| (k.name(), name)).collect())
    }

    /// Turns collisions on (or changes their settings): stages 2–4 of every step with the
    /// impulse model, a contact force in stage 1 with the force models.
    pub fn set_collisions(&mut self, params: CollisionParams) -> Result<(), Error> {
        match &mut self.collide_stage {
            Some(stage) => {
                stage.set_params(params)?;
                if stage.params.model != ContactModel::Impulse || stage.params.event_driven {
                    // no step of the impulse model records touches now (the events not yet
                    // taken stay)
                    stage.record_touches(false, std::iter::empty());
                }
            }
            None => {
                let mut stage = CollideStage::new(params, self.params.dim)?;
                stage.set_interrupt(self.interrupt);
                self.collide_stage = Some(stage);
                self.check_placement_from(0);
            }
        }
        self.contacts_changed();
        Ok(())
    }

    /// After a change of the collision settings, colliders, materials or the domain: the
    /// contact lists start over (the impulse model's and the contact force model's), and so
    /// do the method's caches.
    pub(super) fn contacts_changed(&mut self) {
        if let Some(stage) = &mut self.collide_stage {
            stage.forget_list();
            if let Some(model) = stage.force_model() {
                model.forget_list();
            }
        }
        self.reset_caches();
    }

    /// Gives particles `start..start + len` their own restitution e ∈ [0, 1] and friction μ ≥ 0
    /// (`None` keeps the global value of [`CollisionParams`]); `restitution` and `friction`
    /// have one entry per particle. A pair combines its two values by Box2D's rule
    /// (e = max, μ = √(μ_i μ_j), [`crate::collide::Material::combine`]); a collider's own
    /// values override the particle's. Turns collisions on if they are off.
    pub fn set_particle_materials(
        &mut self,
        start: usize,
        restitution: &[Option<f64>],
        friction: &[Option<f64>],
    ) -> Result<(), Error> {
        let n = self.particles.len();
        if restitution.len() != friction.len() || start + restitution.len() > n {
            return Err(Error::invalid(
                "restitution",
                format!("{} values from particle {start}", restitution.len()),
                format!(
                    "one value per particle, with as many frictions ({}), within the {n} particles",
                    friction.len()
                ),
            ));
        }
        for (k, (e, m)) in restitution.iter().zip(friction).enumerate() {
            // Each value alone must make a valid material.
            crate::collide::Material::new(e.unwrap_or(0.0), m.unwrap_or(0.0)).map_err(|err| match err {
                Error::InvalidParameter {
                    parameter,
                    value,
                    allowed,
                } => Error::InvalidParameter {
                    parameter: format!("{parameter}[{}]", start + k),
                    value,
                    allowed,
                },
                other => other,
            })?;
        }
        if self.collide_stage.is_none() {
            self.set_collisions(CollisionParams::default())?;
        }
        let stage = self.collide_stage.as_mut().expect("collisions are on");
        stage.own.resize(self.particles.len(), (None, None));
        for (k, (e, m)) in restitution.iter().zip(friction).enumerate() {
            stage.own[start + k] = (*e, *m);
        }
        stage.refresh_materials()?;
        self.contacts_changed();
        Ok(())
    }

    /// Each particle's own restitution and friction (`None`: the world's value); empty when
    /// no particle has its own.
    pub fn particle_materials(&self) -> Vec<(Option<f64>, Option<f64>)> {
        self.collide_stage.as_ref().map(|c| c.own.clone()).unwrap_or_default()
    }

    /// The collision settings, when collisions are on.
    pub fn collision_params(&self) -> Option<CollisionParams> {
        self.collide_stage.as_ref().map(|c| c.params)
    }

    /// Adds a static collider and returns its index; turns collisions on with the default
    /// settings if they are off.
    pub fn add_collider(&mut self, collider: impl Into<Collider>) -> Result<usize, Error> {
        let collider = collider.into();
        collider.check_dim(self.params.dim)?;
        if self.collide_stage.is_none() {
            self.set_collisions(CollisionParams::default())?;
        }
        let stage = self.collide_stage.as_mut().expect("collisions are on");
        stage.colliders.push(collider);
        let index = stage.colliders.len() - 1;
        self.check_placement_from(0);
        self.contacts_changed();
        Ok(index)
    }

    /// Gives collider `k` a prescribed motion ([`Motion`]: steady velocity and angular
    /// velocity, or keyframes) from the placement it was added in, on the world's clock
    /// (the motion's t = 0 is the world's time 0); `None` puts it back there, still. It is
    /// placed at the current time at once and at the end of every step after; its surface's
    /// velocity enters every contact with it. A box can only be translated. In a 2D world
    /// the motion must keep the plane: velocities and translations in xy, turns about z.
    pub fn set_collider_motion(&mut self, k: usize, motion: Option<Motion>) -> Result<(), Error> {
        if self.params.dim == 2 {
            if let Some(m) = &motion {
                check_planar_motion(m)?;
            }
        }
        let t = self.time;
        let Some(stage) = self.collide_stage.as_mut() else {
            return Err(Error::invalid("collider", k, "the world has no colliders"));
        };
        stage.set_motion(k, motion, t)?;
        self.watch = None;
        self.check_placement_from(0);
        self.contacts_changed();
        Ok(())
    }

    /// What the particles gave each collider over all steps (momentum, angular momentum
    /// about the origin, the work the collider did on them, the momentum's normal and
    /// tangential parts), in the colliders' order, by every contact model (the force models'
    /// with velocity Verlet, the method whose step books them); with `last`, in the last
    /// step alone (the last call, event-driven).
    pub fn collider_books(&self, last: bool) -> Vec<ColliderBooks> {
        let Some(stage) = self.collide_stage.as_ref() else {
            return Vec::new();
        };
        let mut books = if last {
            stage.collider_last.clone()
        } else {
            stage.collider_books.clone()
        };
        books.resize(stage.colliders.len(), ColliderBooks::default());
        books
    }

    /// Places the moving colliders where their motions have them at the step's end `t1` (s)
    /// (the contact force reads them there); returns whether any collider moves within
    /// the step from the world's time.
    pub(super) fn place_moving_colliders(&mut self, t1: f64) -> Result<bool, Error> {
        let t0 = self.time;
        let Some(stage) = self.collide_stage.as_mut() else {
            return Ok(false);
        };
        stage.place_colliders(t0, t1)
    }

    /// The colliders, in the order they were added (a moving one where it is now).
    pub fn colliders(&self) -> &[Collider] {
        self.collide_stage.as_ref().map_or(&[], |c| &c.colliders)
    }

    /// Makes the axes with `axes[k]` true periodic, with the cell of the world's box collider
    /// (its walls along those axes then vanish: a particle leaving one side comes back on the
    /// other). All false makes space open again.
    pub fn set_periodic(&mut self, axes: [bool; 3]) -> Result<(), Error> {
        if self.collide_stage.is_none() {
            self.set_collisions(CollisionParams::default())?;
        }
        let stage = self.collide_stage.as_mut().expect("collisions are on");
        if !axes.iter().any(|a| *a) {
            stage.set_periodic(None)?;
            self.contacts_changed();
            return Ok(());
        }
        if self.params.dim == 2 && axes[2] {
            return Err(Error::invalid(
                "periodic",
                format!("{axes:?}"),
                "a 2D world has no periodic z axis",
            ));
        }
        let Some((lo, hi)) = stage.colliders.iter().find_map(|c| match c {
            Collider::Box(b) => Some((b.lo(), b.hi())),
            _ => None,
        }) else {
            return Err(Error::invalid(
                "periodic",
                format!("{axes:?}"),
                "periodic axes need a box collider (kinema.Box) whose sides give the periodic cell; add one first",
            ));
        };
        stage.set_periodic(Some(Periodic::new(lo, hi, axes)?))?;
        if let Some(p) = stage.domain.periodic_box() {
            p.wrap_positions(&mut self.particles.x);
        }
        self.contacts_changed();
        self.check_placement_from(0);
        Ok(())
    }

    /// The periodic axes (all false for open space).
    pub fn periodic(&self) -> [bool; 3] {
        self.collide_stage
            .as_ref()
            .and_then(|c| c.domain.periodic_box().map(|p| p.axes()))
            .unwrap_or([false; 3])
    }

    /// The contacts found at the end of the last step, as detected: `overlap` before it was
    /// removed and `u_n` before the end-of-step impulses (impacts found inside the step by
    /// continuous detection were already resolved). Empty with the force models,
    /// whose contacts live inside the force evaluations.
    pub fn contacts(&self) -> &[Contact] {
        self.collide_stage.as_ref().map_or(&[], |c| c.detected())
    }

    /// The contacts now, each with its point, its force split along and across the normal,
    /// and whether it slides ([`ContactReport`](crate::collide::ContactReport)): with the
    /// force models, every contact that pushes at the current state, its forces as the next
    /// evaluation finds them; with the impulse model, the last step's end-of-step contacts
    /// with the impulse each took and its mean force over the step (impacts inside the step
    /// are not among them: `contact_events` and `collision_stats` count those). Empty
    /// without collisions, and for an event-driven world (its impacts are instants).
    pub fn contact_reports(&mut self) -> Result<Vec<crate::collide::ContactReport>, Error> {
        self.check_pending_placement()?;
        let Some(stage) = self.collide_stage.as_ref() else {
            return Ok(Vec::new());
        };
        if stage.params.model == ContactModel::Impulse {
            return Ok(stage.impulse_reports(&self.particles.x, &self.particles.radius, self.last_step));
        }
        let p = &self.particles;
        let s = crate::forces::State {
            t: self.time,
            x: &p.x,
            v: &p.v,
            mass: &p.mass,
        };
        match super::forces::contact_force(&self.collide_stage, p) {
            Some(contact) => contact.contact_reports(&s),
            None => Ok(Vec::new()),
        }
    }

    /// Starts (`on`) or stops recording when pairs begin and end touching
    /// (`collide/touch.rs`): the impulse model's steps only. Started, the pairs whose last
    /// step's contact bore an impulse count as touching already; stopped, the events not
    /// yet taken stay.
    pub fn record_contact_events(&mut self, on: bool) -> Result<(), Error> {
        let refuse = |why: &str| {
            Error::invalid(
                "record_contact_events",
                if on { "True" } else { "False" },
                format!("begin and end of touch are recorded by the impulse model's steps only: {why}"),
            )
        };
        let Some(stage) = &mut self.collide_stage else {
            return Err(refuse("collisions are off (set_collisions first)"));
        };
        if on && stage.params.model != ContactModel::Impulse {
            return Err(refuse(
                "this world's contacts are a force (the spring–dashpot or Hertz model)",
            ));
        }
        if on && stage.params.event_driven {
            return Err(refuse("this world is event-driven"));
        }
        let loaded: Vec<_> = stage
            .all_warm()
            .into_iter()
            .filter(|w| w.impulse != [0.0; 3])
            .map(|w| (w.i, w.other))
            .collect();
        stage.record_touches(on, loaded.into_iter());
        Ok(())
    }

    /// The impulse model's candidate list's skin, m (`None`: collisions off; for the tests).
    #[cfg(test)]
    pub(crate) fn impulse_list_skin(&self) -> Option<f64> {
        self.collide_stage.as_ref().map(|s| s.impulse_list_skin())
    }

    /// Turns the impact search's check of each particle's sweep bound off (for the tests:
    /// every candidate's time of impact solved for, `collide::events::SweepBound`).
    #[cfg(test)]
    pub(crate) fn search_unbounded(&mut self) {
        if let Some(s) = self.collide_stage.as_mut() {
            s.search_unbounded();
        }
    }

    /// Bounds the impulse model's candidate list to `entries` (for the tests).
    #[cfg(test)]
    pub(crate) fn set_impulse_list_limit(&mut self, entries: usize) {
        if let Some(s) = self.collide_stage.as_mut() {
            s.set_impulse_list_limit(entries);
        }
    }

    /// The begin and end of touch events recorded since the last call, in order, taken out.
    pub fn take_contact_events(&mut self) -> Vec<TouchEvent> {
        self.collide_stage.as_mut().map_or_else(Vec::new, |s| s.take_touch_events())
    }

    /// What the collision stages did in the last step, and summed over all steps; `None`
    /// without collisions. The particles and contacts asleep are those asleep now: a write
    /// to the state, a removal or an addition since the last step may have woken them.
    pub fn collision_stats(&self) -> Option<(CollisionStats, CollisionStats)> {
        self.collide_stage.as_ref().map(|c| {
            let mut last = c.last;
            (last.asleep, last.asleep_contacts) = c.asleep();
            (last, c.total)
        })
    }
}

/// A 2D world's collider motion keeps the xy-plane: no velocity or translation along z, no
/// turn but about z.
fn check_planar_motion(m: &Motion) -> Result<(), Error> {
    let what = "a 2D world keeps z = 0: a collider moves in the xy-plane and turns about z";
    match m {
        Motion::Steady {
            velocity,
            angular_velocity,
            pivot,
            ..
        } => {
            for (name, v) in [
                ("velocity[2]", velocity[2]),
                ("angular_velocity[0]", angular_velocity[0]),
                ("angular_velocity[1]", angular_velocity[1]),
                ("pivot[2]", pivot[2]),
            ] {
                if v != 0.0 {
                    return Err(Error::invalid(name, v, what));
                }
            }
        }
        Motion::Keyframes {
            translations,
            rotations,
            pivot,
            ..
        } => {
            for (k, t) in translations.iter().enumerate() {
                if t[2] != 0.0 {
                    return Err(Error::invalid(format!("translations[{k}][2]"), t[2], what));
                }
            }
            for (k, q) in rotations.iter().enumerate() {
                if q[1] != 0.0 || q[2] != 0.0 {
                    return Err(Error::invalid(format!("rotations[{k}]"), format!("{q:?}"), what));
                }
            }
            if pivot[2] != 0.0 {
                return Err(Error::invalid("pivot[2]", pivot[2], what));
            }
        }
    }
    Ok(())
}
