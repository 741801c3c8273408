//! The collide stage, stages 2–4 of a world step (`World::collide`, `world/collide.rs`, calls
//! it): the collision settings
//! ([`ContactModel`], [`CollisionParams`]; `stage/settings.rs`) and [`CollideStage`], which holds them with the
//! colliders, the domain, the materials and the books summed over steps, and its contact
//! engine, one closed choice (`stage/engines.rs`, [`Engine`]): the impulse model's detection
//! and response of `collide/` (`collide/impulse/`) on each step — detect collisions
//! (continuously inside the step, then as contacts at its end), respond by Newton's
//! restitution law, distribute each impulse onto both particles —, the same law by events,
//! or a contact force.

pub use crate::collide::books::ColliderBooks;
pub use crate::collide::contact_force::Cohesion;
use crate::collide::contact_force::{particle_ratios, Bodies, ContactForce};
use crate::collide::event_driven::{unsupported_collider, EventDriven};
use crate::collide::groups::{Filter, GroupMasks};
use crate::collide::impulse::end_of_step::overlap_at;
use crate::collide::impulse::list::check_travel;
use crate::collide::impulse::{ImpulseModel, StageSetting};
use crate::collide::spin::Rotation;
use crate::collide::touch::Touches;
use crate::collide::{placement, Collider, Contact, Domain, Material, MaterialTable, Motion, Periodic};
use crate::error::Error;
use crate::interrupt::Interrupt;
use crate::particles::Particles;
use crate::vec3;

pub(crate) use crate::collide::impulse::end_of_step::on_periodic_wall;
pub use crate::collide::impulse::CollisionStats;
pub(crate) use crate::collide::impulse::{CollisionTimes, StepFrame};
pub(crate) use engines::Engine;
use settings::force_model_of;
pub use settings::{CollisionParams, ContactModel, ModelArgs, TangentialArgs, TangentialKind};

mod engines;
mod settings;

/// The largest turn a moving collider may make in one step, rad (about 5.7°). Continuous
/// detection sees a particle's path from the collider placed at the step's end, moved there
/// on the chord of the turn. Measured on closed cubes turning about any axis with 8–27 balls
/// (e 0–1, μ 0–0.5, half-widths 0.4–0.8 m, 150 steps): none lost in 700 cases up to 0.12 rad a
/// step; 3 of 150 lost between 0.15 and 0.2 rad (balls wedged in a corner at thousands of g,
/// frictionless and inelastic), and more from 0.25 rad.
pub const MAX_TURN: f64 = 0.1;

/// The collision stages of a world, with their settings, colliders and books, and the contact
/// engine that runs them ([`Engine`]).
pub(crate) struct CollideStage {
    pub params: CollisionParams,
    material: Material,
    /// Per-particle restitution and friction where set (`None`: the global value); empty
    /// until some particle gets its own (32 B per particle otherwise spent on nothing).
    pub own: Vec<(Option<f64>, Option<f64>)>,
    /// The materials of all particles, built from `own` and the global value when some
    /// particle has its own.
    particle_materials: Option<Vec<Material>>,
    pub colliders: Vec<Collider>,
    pub domain: Domain,
    /// The contact engine, with its buffers: the impulse model stepped, run by events, or a
    /// contact force model ([`CollideStage::contact_force`] lends that out with what it reads).
    engine: Engine,
    /// The touches and their events while an engine that does not record them runs (the
    /// stepped engine holds them while it runs: `stage/engines.rs`).
    idle_touches: Touches,
    /// The check that may stop a step, given to each stepped engine made.
    interrupt: Interrupt,
    /// Whether some particle's own material has friction (the force models' tangential part).
    own_friction: bool,
    /// Each particle's (e, ζ) from `particle_materials`, for the force models' damping.
    particle_ratios: Option<Vec<(f64, f64)>>,
    pub total: CollisionStats,
    pub last: CollisionStats,
    pub times: CollisionTimes,
    /// Each collider's prescribed motion with the placement it was added in (`None`: it
    /// stays where it was added).
    pub motions: Vec<Option<(Motion, Collider)>>,
    /// What the particles gave each collider over all steps.
    pub collider_books: Vec<ColliderBooks>,
    /// What they gave each collider in the last step (the last call, event-driven).
    pub collider_last: Vec<ColliderBooks>,
    /// Which collision groups collide with which (`collide/groups.rs`; all by default).
    pub group_masks: GroupMasks,
    /// Each collider's mask of the groups it collides with (one per collider, all by default).
    pub collider_masks: Vec<u32>,
}

impl CollideStage {
    pub fn new(params: CollisionParams, dim: usize) -> Result<Self, Error> {
        let material = params.check()?;
        let params = params.normalised();
        Ok(CollideStage {
            params,
            material,
            own: Vec::new(),
            particle_materials: None,
            own_friction: false,
            colliders: Vec::new(),
            domain: Domain::open(dim)?,
            engine: Engine::of(&params, Interrupt::none()),
            idle_touches: Touches::default(),
            interrupt: Interrupt::none(),
            particle_ratios: None,
            total: CollisionStats::default(),
            last: CollisionStats::default(),
            times: CollisionTimes::default(),
            motions: Vec::new(),
            collider_books: Vec::new(),
            collider_last: Vec::new(),
            group_masks: GroupMasks::default(),
            collider_masks: Vec::new(),
        })
    }

    /// The collision groups' filter for particles in `groups` (`Particles::group`), or `None`
    /// when every pair collides.
    pub fn filter<'a>(&'a self, groups: &'a [u8]) -> Option<Filter<'a>> {
        Filter::of(groups, &self.group_masks, self.params.self_collisions, &self.collider_masks)
    }

    /// Gives collider k a prescribed motion from the placement it was added in (`None`:
    /// back there, still), and places it at time `t` (s).
    pub fn set_motion(&mut self, k: usize, motion: Option<Motion>, t: f64) -> Result<(), Error> {
        let n = self.colliders.len();
        if k >= n {
            return Err(Error::invalid(
                "collider",
                k,
                format!("an index below the number of colliders ({n})"),
            ));
        }
        if let (Some(m), Collider::Box(_)) = (&motion, &self.colliders[k]) {
            if m.rotates() {
                return Err(Error::invalid(
                    "angular_velocity",
                    "a turn",
                    "a box collider stays axis-aligned and can only be translated; a turning container is a closed mesh (inside = true)",
                ));
            }
        }
        self.motions.resize(n, None);
        let rest = match self.motions[k].take() {
            Some((_, rest)) => rest,
            None => self.colliders[k].clone(),
        };
        match motion {
            None => self.colliders[k] = rest,
            Some(m) => {
                let (pose, velocity) = m.at(t);
                let placed = rest.posed(&pose, velocity);
                match placed {
                    Ok(c) => {
                        self.colliders[k] = c;
                        self.motions[k] = Some((m, rest));
                    }
                    Err(e) => {
                        self.motions[k] = None;
                        self.colliders[k] = rest;
                        return Err(e);
                    }
                }
            }
        }
        Ok(())
    }

    /// Places the colliders with a prescribed motion where it has them at the step's end `t1`
    /// (s); returns whether any of them moves within the step from `t0` (a keyframed one
    /// outside its keys rests: [`Motion::moves_within`]).
    pub fn place_colliders(&mut self, t0: f64, t1: f64) -> Result<bool, Error> {
        let mut any = false;
        for (k, m) in self.motions.iter().enumerate() {
            if let Some((motion, rest)) = m {
                let (pose, velocity) = motion.over(t0, t1);
                let turn = vec3::norm(velocity.angular) * (t1 - t0);
                // (a step of dt = MAX_TURN / ω is one, whatever the clock's rounding of t1 − t0)
                if turn > MAX_TURN * (1.0 + 1e-9) {
                    return Err(Error::invalid(
                        format!("collider {k}'s turn in one step"),
                        format!("{turn:.3} rad (from t = {t0} s to t = {t1} s)"),
                        format!(
                            "at most {MAX_TURN} rad a step: continuous detection sweeps a turning collider on the chord of \
                             each step's turn, which lets particles through beyond that; a dt of at most {:.3e} s keeps it within",
                            MAX_TURN / vec3::norm(velocity.angular)
                        ),
                    ));
                }
                self.colliders[k] = rest.posed(&pose, velocity)?;
                any |= motion.moves_within(t0, t1);
            }
        }
        Ok(any)
    }

    /// Whether some collider moves within the step from `t0` to `t1` (s).
    pub fn moves_within(&self, t0: f64, t1: f64) -> bool {
        self.motions.iter().flatten().any(|(m, _)| m.moves_within(t0, t1))
    }

    /// Whether some collider has a prescribed motion.
    pub fn has_motion(&self) -> bool {
        self.motions.iter().any(Option::is_some)
    }

    /// Changes the settings, keeping colliders and buffers.
    pub fn set_params(&mut self, params: CollisionParams) -> Result<(), Error> {
        self.material = params.check()?;
        self.params = params.normalised();
        self.follow_params();
        self.refresh_materials()
    }

    /// Forgets the last step's contacts and figures (a step of a force model).
    pub fn clear_step(&mut self) {
        if let Engine::Stepped(m) = &mut self.engine {
            m.detected.clear();
        }
        self.last = CollisionStats::default();
        self.collider_last.clear();
    }

    /// A step of the force models (`h`, s): the books its force evaluation kept (velocity
    /// Verlet's fused pass; none with the other methods) as the step's collision figures:
    /// the contacts pushing, those begun in the step as its impacts, the dashpots' power
    /// times h as the energy lost (with what JKR's contacts lost as they let go), h times the
    /// pairs' virial.
    pub fn book_contact_force(&mut self, h: f64) {
        self.clear_step();
        let Some((books, walls)) = self.force_model().and_then(|m| m.take_books()) else {
            return;
        };
        self.book_colliders(walls);
        let step = CollisionStats {
            contacts: books.contacts,
            impacts: books.begun,
            energy_lost: h * books.power + books.lost,
            virial: books.virial.map(|w| h * w),
            ..CollisionStats::default()
        };
        self.last = step;
        self.total.accumulate(&step);
    }

    /// The impulse model's end-of-step contacts of the last step, then those of the islands
    /// asleep (their last awake step's loads), each with its impulse and its mean force over
    /// the step h (s): the impulse's normal part (J·n) n and the rest,
    /// each over h; sliding when the tangential part is at the Coulomb bound μ (J·n) (to
    /// 1e-9 of it). `x` (m, 3 per particle) and `radius` place the points.
    pub fn impulse_reports(&self, x: &[f64], radius: &[f64], h: f64) -> Vec<crate::collide::ContactReport> {
        let Engine::Stepped(impulse) = &self.engine else {
            return Vec::new();
        };
        let table = MaterialTable::uniform(self.material).with_colliders(&self.colliders);
        let materials = match &self.particle_materials {
            Some(m) => table.with_particles(m),
            None => table,
        };
        let asleep = impulse.sleeping_contacts(x, radius, &self.colliders, &self.domain);
        impulse
            .detected_with_totals()
            .map(|(c, p)| (*c, p))
            .chain(asleep)
            .map(|(c, p)| {
                let c = &c;
                let lambda = vec3::dot(p, c.normal);
                let along = vec3::scale(lambda, c.normal);
                let across = vec3::sub(p, along);
                let cap = materials.pair(c).friction() * lambda;
                let rj = c.partner_particle().map(|j| radius[j]);
                // the point where the contact is now (the overlap as detected was pushed out)
                let now = Contact {
                    overlap: overlap_at(radius, &self.colliders, &self.domain, x, c.i, c.other),
                    ..*c
                };
                crate::collide::ContactReport {
                    contact: *c,
                    point: crate::collide::ContactReport::point_of(&now, vec3::get(x, c.i), radius[c.i], rj),
                    force_n: vec3::scale(1.0 / h, along),
                    force_t: vec3::scale(1.0 / h, across),
                    impulse: [along, across],
                    sliding: cap > 0.0 && vec3::norm(across) >= cap * (1.0 - 1e-9),
                }
            })
            .collect()
    }

    /// Moves what the stage holds per particle (their own materials: `own`, and the
    /// materials and damping ratios made of them) to a new order of the particles
    /// (`old_of_new[i]`: the index now of the particle that goes to place i), as
    /// [`crate::World`] moves the particles' arrays when it sorts them along space.
    pub fn permute_particles(&mut self, old_of_new: &[u32]) {
        fn gather<T: Copy>(v: &mut Vec<T>, old_of_new: &[u32]) {
            if v.len() == old_of_new.len() {
                *v = old_of_new.iter().map(|&o| v[o as usize]).collect();
            }
        }
        gather(&mut self.own, old_of_new);
        if let Some(m) = &mut self.particle_materials {
            gather(m, old_of_new);
        }
        if let Some(r) = &mut self.particle_ratios {
            gather(r, old_of_new);
        }
    }

    /// Rebuilds the per-particle materials from `own` and the global value.
    pub fn refresh_materials(&mut self) -> Result<(), Error> {
        if self.own.iter().all(|(e, m)| e.is_none() && m.is_none()) {
            self.particle_materials = None;
            self.particle_ratios = None;
            self.own_friction = false;
            return Ok(());
        }
        let global = self.material;
        self.particle_materials = Some(
            self.own
                .iter()
                .map(|(e, m)| Material::new(e.unwrap_or(global.restitution()), m.unwrap_or(global.friction())))
                .collect::<Result<_, _>>()?,
        );
        self.particle_ratios = self.particle_materials.as_deref().map(particle_ratios);
        self.own_friction = self
            .particle_materials
            .as_deref()
            .is_some_and(|o| o.iter().any(|m| m.friction() > 0.0));
        Ok(())
    }

    /// The contact force on particles of radii `radius` (m) and inverse masses
    /// `inv_mass` (1/kg), with this stage's materials, colliders and domain, for one call;
    /// `None` with the impulse model.
    pub fn contact_force<'a>(
        &'a self,
        radius: &'a [f64],
        inv_mass: &'a [f64],
        omega: &'a [f64],
        group: &'a [u8],
    ) -> Option<ContactForce<'a>> {
        let model = self.force_model()?;
        let own = self.particle_materials.as_deref().zip(self.particle_ratios.as_deref());
        Some(ContactForce::new(
            model,
            Bodies {
                global: self.material,
                own,
                own_friction: self.own_friction,
                radius,
                inv_mass,
                colliders: &self.colliders,
                domain: &self.domain,
                omega,
                filter: self.filter(group),
            },
        ))
    }

    /// Makes the axes `axes` periodic with the cell [lo, hi) (m); the walls of a box
    /// collider along those axes are removed (particles leaving one side come back on the
    /// other). `None` makes space open again.
    pub fn set_periodic(&mut self, periodic: Option<Periodic>) -> Result<(), Error> {
        let dim = self.domain.dim();
        self.domain = match periodic {
            Some(p) => Domain::periodic(dim, p)?,
            None => Domain::open(dim)?,
        };
        Ok(())
    }

    /// Forgets the impulse engines' candidate list and warm start, and the event-driven
    /// state (particles, colliders or the domain changed; the contact force model's list is
    /// its own, `ContactForceModel::forget_list`).
    pub fn forget_list(&mut self) {
        match &mut self.engine {
            Engine::Stepped(m) => m.forget_list(),
            Engine::Events(e) => *e = None,
            Engine::Force(_) => {}
        }
    }

    /// Refuses particles `from` on placed where this contact model cannot resolve them
    /// ([`placement::check`], on the stepped engine's grid or one of its own).
    pub fn check_placement(&mut self, p: &Particles, from: usize, user_of: Option<&[u32]>) -> Result<placement::Overlaps, Error> {
        let rule = match self.params.model {
            ContactModel::Impulse => placement::Rule::CentreInside,
            ContactModel::SpringDashpot { .. } | ContactModel::Hertz { .. } => placement::Rule::Coincident,
        };
        self.with_placement_grid(|grid, stage| {
            let place = placement::Placed {
                x: &p.x,
                radius: &p.radius,
                from,
                user_of,
                filter: Filter::of(
                    &p.group,
                    &stage.group_masks,
                    stage.params.self_collisions,
                    &stage.collider_masks,
                ),
            };
            placement::check(grid, &place, &stage.domain, &stage.colliders, rule)
        })
    }

    /// The stepped engine, lent for a step (`World::collide` runs its
    /// [`ImpulseModel::step`]), and what its stages see of the world: these settings,
    /// colliders, domain and materials, and the particles `p`; `None` with another engine.
    pub fn impulse_and_setting<'a>(&'a mut self, p: &'a Particles) -> Option<(&'a mut ImpulseModel, StageSetting<'a>)> {
        let Engine::Stepped(impulse) = &mut self.engine else {
            return None;
        };
        let table = MaterialTable::uniform(self.material).with_colliders(&self.colliders);
        let set = StageSetting {
            colliders: &self.colliders,
            domain: &self.domain,
            materials: match &self.particle_materials {
                Some(m) => table.with_particles(m),
                None => table,
            },
            ccd: self.params.ccd,
            restitution_threshold: self.params.restitution_threshold,
            sleep_time: self.params.sleep_time,
            sleep_speed: self.params.sleep_speed,
            radius: &p.radius,
            id: &p.id,
            inv_mass: &p.inv_mass,
            mass: &p.mass,
            rotation: p.has_spin().then_some(Rotation {
                inv_inertia: &p.inv_inertia,
                radius: &p.radius,
            }),
            rolling_friction: self.params.rolling_friction,
            accuracy: self.params.accuracy,
            filter: Filter::of(&p.group, &self.group_masks, self.params.self_collisions, &self.collider_masks),
        };
        Some((impulse, set))
    }

    /// What the particles gave each collider in a step (`step`, one per collider, or fewer:
    /// the rest gave nothing): the last step's, and added to the sums over steps.
    fn book_colliders(&mut self, mut step: Vec<ColliderBooks>) {
        let n = self.colliders.len();
        step.resize(n, ColliderBooks::default());
        self.collider_books.resize(n, ColliderBooks::default());
        for (all, given) in self.collider_books.iter_mut().zip(&step) {
            all.add_scaled(1.0, given);
        }
        self.collider_last = step;
    }

    /// Books what a step of the impulse model did (`stats`) and its time: the sums over
    /// steps, and what the particles gave each collider.
    pub fn book_step(&mut self, stats: CollisionStats, times: CollisionTimes) {
        let step = match &self.engine {
            Engine::Stepped(m) => m.collider_books.clone(),
            _ => Vec::new(),
        };
        self.book_colliders(step);
        self.times.detect += times.detect;
        self.times.respond += times.respond;
        self.times.distribute += times.distribute;
        for (all, step) in self.times.stages.iter_mut().zip(times.stages) {
            *all += step;
        }
        self.last = stats;
        self.total.accumulate(&stats);
    }

    /// Why the event-driven path cannot run on this stage (a sentence), or `None`: it needs
    /// the impulse model, no forces but uniform fields (`other`: the name of a force that is
    /// not one; `field`: their summed acceleration, m/s²), no moving collider, and still
    /// planes and boxes as colliders. Under a field, no particle may be pinned (it would not
    /// fall with the others) and, with walls, every restitution must be 1: a dissipative
    /// bounce on a floor comes to rest through infinitely many ever smaller bounces, which
    /// events cannot run and a resting contact needs the stepped model for.
    pub fn events_refused(&self, other: Option<&str>, field: [f64; 3], p: &Particles) -> Option<String> {
        if self.params.model != ContactModel::Impulse {
            return Some("it is a way of running the impulse model, not a force model".into());
        }
        if let Some(name) = other {
            return Some(format!(
                "particles must fly free between impacts (forces: none or uniform fields such as gravity), and this world has the force '{name}'"
            ));
        }
        if field != [0.0; 3] {
            if let Some(i) = p.inv_mass.iter().position(|&w| w == 0.0) {
                return Some(format!(
                    "particle {i} is pinned, and under a field it would not fall with the others"
                ));
            }
            let walls = self
                .colliders
                .iter()
                .any(|c| matches!(c, Collider::Plane(_) | Collider::Box(_)));
            let global = self.material.restitution() < 1.0;
            let own = self
                .particle_materials
                .as_ref()
                .is_some_and(|m| m.iter().any(|m| m.restitution() < 1.0));
            let surface = self
                .colliders
                .iter()
                .any(|c| c.surface().restitution().is_some_and(|e| e < 1.0));
            if walls && (global || own || surface) {
                return Some(
                    "under a field with walls every restitution must be 1: a dissipative bounce on a floor comes to rest \
                     through ever smaller bounces, a resting contact that only the stepped model holds"
                        .into(),
                );
            }
        }
        if self.has_motion() {
            return Some("a collider moves".into());
        }
        if let Some((k, what)) = unsupported_collider(&self.colliders) {
            return Some(format!("collider {k} is {what}; only planes and boxes are walls to it"));
        }
        None
    }

    /// Runs the particles `p` by events from time `t0` to `t1` (s) under the uniform field
    /// `field` (m/s²) ([`EventDriven::advance`]),
    /// keeping the state for the next call; books the impacts like [`CollideStage::book_step`]. The
    /// caller checked [`CollideStage::events_refused`].
    pub fn advance_events(
        &mut self,
        p: &mut Particles,
        t0: f64,
        t1: f64,
        field: [f64; 3],
        interrupt: &mut Interrupt,
    ) -> Result<(), Error> {
        self.domain.check_radii(&p.radius)?;
        // As a step refuses it (`impulse/list.rs`, `check_travel`): a particle that would
        // cross the scene more than TRAVEL_LIMIT times until t1 takes more events than any run
        // can follow (1e10 m/s in a 1 m box: 1e7 wall events a millisecond).
        // (by the largest component, which does not overflow where |v|² would: 1e200 m/s)
        let largest = |a: [f64; 3]| a.iter().fold(0.0_f64, |m, c| m.max(c.abs()));
        let (fastest, speed) =
            (0..p.len())
                .map(|i| (i, largest(vec3::get(&p.v, i))))
                .fold((0, 0.0), |a, b| if b.1 > a.1 || b.1.is_nan() { b } else { a });
        let span = t1 - t0;
        let travel = speed * span + 0.5 * largest(field) * span * span;
        if travel.is_nan() || travel.is_infinite() {
            return Err(Error::Diverged {
                step: 0,
                time: 0.0,
                particle: Some(fastest),
                dt: span,
                reason: crate::error::Divergence::NonFinite,
                advised_dt: None,
                verlet_only: false,
            });
        }
        check_travel(&self.colliders, &p.radius, &p.x, travel, fastest, span)?;
        let start = std::time::Instant::now();
        let mut events = match self.take_events() {
            Some(e) if e.is_at(p.len(), t0, field) => e,
            _ => {
                let filter = Filter::of(&p.group, &self.group_masks, self.params.self_collisions, &self.collider_masks);
                EventDriven::new(p, &self.colliders, &self.domain, filter, t0, field)
            }
        };
        let table = MaterialTable::uniform(self.material).with_colliders(&self.colliders);
        let materials = match &self.particle_materials {
            Some(m) => table.with_particles(m),
            None => table,
        };
        let threshold = self.params.restitution_threshold.unwrap_or(0.0);
        let mut given = vec![ColliderBooks::default(); self.colliders.len()];
        let stats = events.advance(p, &materials, threshold, &self.domain, t1, &mut given, interrupt)?;
        self.book_colliders(given);
        self.keep_events(events);
        self.times.detect += start.elapsed();
        self.last = stats;
        self.total.accumulate(&stats);
        Ok(())
    }
}
