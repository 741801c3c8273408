//! The world: particles, the forces on them, and `World::step`, the seed's four stages.
//!
//! This file holds the world itself and its step; the other parts of `World` live beside it,
//! each in its own `impl World` block:
//!
//! - `integrate.rs`: stage 1, the kept stepper and the integration of one step;
//! - `collide.rs`: stages 2–4, `World::collide`, which runs the collide stage
//!   (`collide::stage::CollideStage`, detection and response in `collide/`), and the
//!   collision settings, colliders, materials and periodic axes;
//! - `groups.rs`: the collision groups (each particle's, the matrix, the colliders' masks);
//! - `forces.rs`: the forces of one evaluation, the world's own and the
//!   contact force the collide stage lends (`collide/contact_force/`);
//! - `divergence.rs`: the non-finite and runaway-energy checks that refuse a step;
//! - `contents.rs`: adding and removing particles and forces;
//! - `carry.rs`: what a birth or death keeps of velocity Verlet's acceleration;
//! - `deaths.rs`: the deaths (times of death, kill volumes) applied after each step;
//! - `checkpoint.rs`: what a checkpoint takes and gives back besides the particles' state;
//! - `measures.rs`: diagnostics, accelerations, the advisor's rates, counters and timings;
//! - `order.rs`: the particles' order in memory (sorted along space inside the steps), and
//!   `UserOrder`, through which a caller that keeps that order between calls reaches the world.

mod advisor;
mod carry;
mod checkpoint;
pub use checkpoint::{PairMemory, WallMemory};
mod clock;
mod collide;
mod contents;
mod deaths;
mod divergence;
mod dynamics;
mod event_driven;
mod forces;
mod groups;
mod implicit;
mod integrate;
mod measures;
mod order;

pub use crate::collide::shock::Accuracy;
pub use crate::collide::stage::{
    Cohesion, ColliderBooks, CollisionParams, CollisionStats, ContactModel, ModelArgs, TangentialArgs, TangentialKind,
};
pub use crate::interrupt::Interrupt;
pub use advisor::Rates;
pub use clock::Clock;
pub use deaths::KillVolume;
pub use divergence::{RUNAWAY_CHECK_EVERY, RUNAWAY_FACTOR};
pub use implicit::{CG_MAX_ITERATIONS, CG_TOLERANCE};
pub use measures::LinearSolve;
pub use order::UserOrder;

use crate::collide::contact_force::CHUNK;
use crate::collide::stage::CollideStage;
use crate::diagnostics::Diagnostics;
use crate::error::{CallbackError, Error};
use crate::forces::{EnergyClass, Force};
use crate::ode::stepper::Stats;
use crate::ode::{Integrator, Method};
use crate::particles::Particles;
use deaths::Deaths;
use divergence::EnergyWatch;
use integrate::WorldStepper;

/// Parameters of a world. Units SI.
#[derive(Debug, Clone, PartialEq)]
pub struct WorldParams {
    /// Time step, s (> 0). Default 1e-3.
    pub dt: f64,
    /// The integrator, any method of the registry or an explicit tableau. Default `verlet`.
    pub method: Integrator,
    /// 2 or 3. A 2D world lives in the xy-plane: z and its velocity stay exactly 0. Default 3.
    pub dim: usize,
}

impl Default for WorldParams {
    fn default() -> Self {
        Self {
            dt: 1e-3,
            method: Integrator::Named(Method::Verlet),
            dim: 3,
        }
    }
}

/// Particles, forces, an integrator, a time step and the time.
pub struct World {
    particles: Particles,
    forces: Vec<Box<dyn Force>>,
    params: WorldParams,
    time: f64,
    steps: u64,
    /// The time after each step and the next step's length (`clock.rs`).
    clock: Clock,
    /// The length of the last step taken, s (dt before the first).
    last_step: f64,
    stats: Stats,
    stepper: Option<WorldStepper>,
    y: Vec<f64>,
    y_next: Vec<f64>,
    /// The state a step produces, m and m/s (3 per particle); swapped in when accepted.
    x_next: Vec<f64>,
    /// With spin, the angular velocities at the start of the step being taken, rad/s (3 per
    /// particle): with those at its end they turn the orientations.
    omega_before: Vec<f64>,
    v_next: Vec<f64>,
    /// Scratch for the forces' sum, N (3 per particle); Verlet without contacts writes the
    /// new velocities over it in its kick and swaps its room with `v_next`, so between steps
    /// it holds nothing to read.
    force: Vec<f64>,
    /// The energy reference of the runaway check; `None` until the next step sets it.
    watch: Option<EnergyWatch>,
    /// The step (its count once taken) whose contact force pass also sums the contacts'
    /// energy, for [`World::advance_measured`]'s diagnostics; `None`: only the runaway
    /// check's steps do.
    energy_at: Option<u64>,
    /// Stages 2–4, when collisions are on.
    collide_stage: Option<CollideStage>,
    /// The particles' order: `Some` while they are sorted along space (see `order.rs`; only
    /// ever between calls inside a [`UserOrder`]); `None` in the user's order.
    sorted: Option<order::Order>,
    /// Sorts along space so far.
    sorts: u64,
    /// How many times the set of particles changed (added, removed, their ids restored): a
    /// reader of the ids reads them again only when this moved ([`World::membership`]).
    membership: u64,
    /// The particles' placement is checked before the next step from this index on
    /// (`collide/placement.rs`): 0 after anything that places them all (collisions turned
    /// on, a collider, periodic axes, positions written before the first step), the first
    /// newcomer's index after particles are added; `None`: nothing to check.
    placement_from: Option<usize>,
    /// What the last placement check accepted but will push apart (`World::take_placement_notice`).
    placement_notice: Option<String>,
    /// Wall-clock time spent in each stage so far.
    times: StageTimes,
    /// Asked between the stages of a step and inside long ones whether to stop (Ctrl-C).
    interrupt: Interrupt,
    /// The deaths applied after each step (`deaths.rs`).
    deaths: Deaths,
    /// The ids of the particles those deaths removed, until taken.
    removed_ids: Vec<u64>,
    /// A force declares nothing about itself ([`Properties::UNKNOWN`](crate::forces::Properties::UNKNOWN):
    /// a user's, such as a Python callable, which may need its own thread's state): stage 1
    /// then runs on the calling thread (`integrate.rs`).
    unknown_force: bool,
    /// Whether the next step measures the overlap its contacts leave (`CollisionStats::
    /// max_overlap`, a figure of the latest step's statistics): every step but those of a call
    /// to advance that another step of the same call follows, whose figure nobody can read
    /// (a sphere's on a fine mesh is a walk down its tree, a tenth of such a pile's step).
    overlap_due: bool,
}

/// Wall-clock time spent in the seed's four stages of [`World::step`], summed over all steps.
/// with contact forces the contacts are a force: all of their time is integration.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageTimes {
    /// Stage 1: integration (force evaluations included).
    pub integrate: std::time::Duration,
    /// Stage 2: collision detection (candidates, times of impact, contacts).
    pub detect: std::time::Duration,
    /// Stage 3: the response by Newton's restitution law (impulses; overlap removed).
    pub respond: std::time::Duration,
    /// Stage 4: each impulse distributed onto both particles.
    pub distribute: std::time::Duration,
    /// Stages 2–4 of the impulse model by its own stages, in the order a step runs them
    /// (`collide/impulse/mod.rs`, `ImpulseStage`): each one's name and time.
    pub impulse: [(&'static str, std::time::Duration); 7],
}

impl World {
    /// An empty world; checks the parameters.
    pub fn new(params: WorldParams) -> Result<Self, Error> {
        if !(params.dt.is_finite() && params.dt > 0.0) {
            return Err(Error::invalid("dt", params.dt, "the time step must be a finite number > 0 s"));
        }
        if params.dim != 2 && params.dim != 3 {
            return Err(Error::invalid("dim", params.dim, "a world is 2D (the xy-plane) or 3D"));
        }
        let dt = params.dt;
        Ok(Self {
            particles: Particles::default(),
            forces: Vec::new(),
            params,
            time: 0.0,
            steps: 0,
            clock: Clock::new(dt),
            last_step: dt,
            stats: Stats::default(),
            stepper: None,
            y: Vec::new(),
            y_next: Vec::new(),
            x_next: Vec::new(),
            omega_before: Vec::new(),
            v_next: Vec::new(),
            force: Vec::new(),
            watch: None,
            energy_at: None,
            collide_stage: None,
            sorted: None,
            sorts: 0,
            membership: 0,
            placement_from: None,
            placement_notice: None,
            times: StageTimes::default(),
            interrupt: Interrupt::none(),
            deaths: Deaths::default(),
            removed_ids: Vec::new(),
            unknown_force: false,
            overlap_due: true,
        })
    }

    /// The forces, in the order they were added (the contact force, with a
    /// force model, is the collide stage's, not among them).
    pub fn forces(&self) -> &[Box<dyn Force>] {
        &self.forces
    }

    /// Whether the contact force acts (collisions on with a force model).
    pub(super) fn has_contact_force(&self) -> bool {
        self.force_model().is_some()
    }

    /// The contact force model's constants and buffers, with a force model (spring–dashpot,
    /// Hertz, DMT, JKR: the collide stage's `Engine::Force`).
    pub(super) fn force_model(&self) -> Option<&crate::collide::contact_force::ContactForceModel> {
        self.collide_stage.as_ref()?.force_model()
    }

    /// A count that moves whenever the set of particles changes (particles added or removed,
    /// ids restored from a checkpoint) and only then: equal counts, the same ids in the same
    /// order (what `World.run`'s recorder compares instead of the ids themselves).
    pub fn membership(&self) -> u64 {
        self.membership
    }

    /// The parameters.
    pub fn params(&self) -> &WorldParams {
        &self.params
    }

    /// Current time, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Advances the world by one time step `dt`, in the seed's order:
    ///
    /// 1. integrate — the state (t) → (t + dt) by the chosen method, under the forces;
    /// 2. detect — collisions between particles and with colliders;
    /// 3. respond — Newton's restitution law u_n⁺ = −e u_n⁻ gives each contact's impulse;
    /// 4. distribute — each impulse acts on both particles, equal and opposite.
    ///
    /// Stages 2–4 run when collisions are on ([`World::set_collisions`], or a collider was
    /// added) with the impulse model; see `collide.rs` for how impacts inside the step are
    /// found (continuous detection) and resolved in time order.
    ///
    /// A step that would produce a non-finite state, or runaway energy, fails with
    /// [`Error::Diverged`] and leaves the world as it was before the step.
    ///
    /// Runaway energy is checked when no force can add energy (no force's
    /// [`Properties::energy`](crate::forces::Properties::energy) is [`EnergyClass::Source`]): the
    /// mechanical energy E = kinetic + potential can then only fall, and what an integrator
    /// adds is an error. The reference E₀ and its scale S₀ (kinetic energy plus the
    /// magnitudes of the potential energies) are taken at the first step after the last change
    /// of particles, forces or state at which S₀ > 0. A step is refused when
    ///
    /// ```text
    ///   E − E₀ > RUNAWAY_FACTOR · S₀ + S / 2        (S: the scale after the step)
    /// ```
    ///
    /// An unstable mode's energy is all new (E − E₀ ≈ S) and crosses this once it has grown
    /// about 2·RUNAWAY_FACTOR-fold, long before overflow. The S/2 term keeps out first-order
    /// errors that are large only against a tiny S₀: forward Euler in free fall from rest adds
    /// ½ m g² h² per step, a fraction 1/(2n) of S after n steps.
    pub fn step(&mut self) -> Result<(), Error> {
        self.advance(1)
    }

    /// Advances the world by `n` steps of [`World::step`]; stops at the first refused one,
    /// keeping the state before it.
    ///
    /// Inside, with contact forces and velocity Verlet, the particles are kept in
    /// an order that follows space (re-sorted whenever the neighbour list is rebuilt, see
    /// `order.rs`); `advance` puts them back in the user's order before it returns, so every
    /// method of the world, and every force, callback and file, sees the user's order. (A
    /// caller that steps in slices and keeps the engine's order between them holds the world
    /// in a [`UserOrder`].)
    pub fn advance(&mut self, n: u64) -> Result<(), Error> {
        let result = self.advance_in_engine_order(n);
        self.restore_user_order();
        result
    }

    /// [`World::diagnostics`] at the end of [`World::advance`]`(n)`: the contacts' energy is
    /// summed by the last step's own force pass (Verlet with a force model: the sum the
    /// runaway check reads, the same bits as a pass of its own over the same list) instead of
    /// by another pass over every pair, a third of a step at 10⁶ particles. What
    /// `World.run` records at each frame; the error of a refused step, as `advance`'s.
    pub fn advance_measured(&mut self, n: u64) -> Result<Diagnostics, Error> {
        let result = self.advance_in_engine_order_measured(n, None);
        self.restore_user_order();
        result.map(|(d, _)| d)
    }

    /// [`World::advance_measured`] without putting the particles back (for [`UserOrder`]);
    /// with `state`, rooms for the positions and velocities (3 per particle), those at the
    /// end written there in the user's order by the diagnostics' own pass, where they hold
    /// 3 N values each then (the bool: whether they were written; a death in the steps
    /// changes N).
    pub(super) fn advance_in_engine_order_measured(
        &mut self,
        n: u64,
        state: Option<(&mut [f64], &mut [f64])>,
    ) -> Result<(Diagnostics, bool), Error> {
        self.energy_at = Some(self.steps + n);
        let stepped = self.advance_in_engine_order(n);
        let size = 3 * self.particles.len();
        let d = stepped.map(|()| match state {
            Some((x, v)) if x.len() == size && v.len() == size => (self.diagnostics_and_state(x, v), true),
            _ => (self.diagnostics(), false),
        });
        // kept no longer: a buffer written later is summed again
        self.energy_at = None;
        if let Some(model) = self.force_model() {
            model.forget_energy();
        }
        d
    }

    /// [`World::advance`] without putting the particles back: they stay in the engine's order
    /// (sorted along space) after it, for the next slice. Only [`UserOrder`] calls it, which
    /// gives the world out only in the user's order again (see `order.rs`).
    ///
    /// After each step the deaths set by [`World::set_deaths`] are applied (which puts
    /// the particles back in the user's order when someone dies).
    fn advance_in_engine_order(&mut self, n: u64) -> Result<(), Error> {
        if n > 0 && self.collide_stage.as_ref().is_some_and(|s| s.params.event_driven) {
            if !self.deaths.any() {
                return self.advance_by_events(n);
            }
            for _ in 0..n {
                self.advance_by_events(1)?;
                self.apply_deaths()?;
            }
            return Ok(());
        }
        for k in 0..n {
            self.overlap_due = k + 1 == n;
            self.step_once()?;
            self.apply_deaths()?;
        }
        Ok(())
    }

    fn step_once(&mut self) -> Result<(), Error> {
        self.check_pending_placement()?;
        // A moving collider stands where it will be at the step's end (`collide/events.rs`);
        // it can add energy, so the runaway watch is off while one moves.
        let moving = self.place_moving_colliders(self.params_time_after(self.steps + 1))?;
        if self.watch.is_none()
            && !moving
            && !self.particles.is_empty()
            && self.forces.iter().all(|f| f.properties().energy != EnergyClass::Source)
        {
            let (energy, scale) = self.energy_and_scale(&self.particles.x, &self.particles.v);
            if scale > 0.0 {
                self.watch = Some(EnergyWatch { energy, scale });
            }
        }
        let start = std::time::Instant::now();
        self.poll_interrupt()?;
        // the angular velocities at the step's start, which turn the orientations with those
        // at its end
        self.omega_before.clone_from(&self.particles.omega);
        self.integrate()?; // 1: the integrated state, in x_next, v_next
        self.times.integrate += start.elapsed();
        // 2–4: detect, respond, distribute, on x_next, v_next (timed inside)
        self.poll_interrupt()?;
        let overlap_due = std::mem::replace(&mut self.overlap_due, true);
        self.collide(overlap_due)?;
        // Accepted: the new state becomes the particles' own (a swap, not a copy).
        std::mem::swap(&mut self.particles.x, &mut self.x_next);
        std::mem::swap(&mut self.particles.v, &mut self.v_next);
        if let Some(WorldStepper::Verlet(b)) = &mut self.stepper {
            std::mem::swap(&mut b.a, &mut b.a_next);
            if !b.omega_next.is_empty() {
                // turned by the contacts' torques in stage 1
                std::mem::swap(&mut self.particles.omega, &mut b.omega_next);
                std::mem::swap(&mut self.particles.alpha, &mut b.alpha_next);
            }
        }
        if let Some(model) = self.force_model() {
            model.accept_history();
        }
        let h = self.step_length();
        let p = &mut self.particles;
        crate::particles::turn_orientations(&mut p.orientation, &self.omega_before, &p.omega, h);
        self.time = self.params_time_after(self.steps + 1);
        self.steps += 1;
        self.last_step = h;
        self.clock.reached(self.steps, self.params.dt);
        Ok(())
    }

    /// Time after `k` steps: t = t₀ + (k − k₀)·h from the clock's anchor (`clock.rs`),
    /// computed by multiplication so it does not drift.
    fn params_time_after(&self, k: u64) -> f64 {
        self.clock.time_after(k, self.params.dt)
    }

    /// The length of the next step, s: dt, or a planned frame's share (`clock.rs`).
    pub(super) fn step_length(&self) -> f64 {
        self.clock.step_after(self.steps, self.params.dt)
    }

    /// Plans the next `n` steps to end at time `t1` (s) exactly, each (t₁ − t)/n ≤ dt long;
    /// then steps of dt again (`clock.rs`: how `World.run` lands on its frames).
    pub fn land_at(&mut self, t1: f64, n: u64) -> Result<(), Error> {
        self.clock.land(self.steps, self.time, t1, n, self.params.dt)
    }

    /// The clock (`clock.rs`), for a checkpoint.
    pub fn clock(&self) -> Clock {
        self.clock
    }

    /// Sets the check that may stop a step (`None`: none): asked at most every
    /// [`Interrupt::EVERY`] between the stages of a step and inside the impacts of a long
    /// one; its error stops the step, and the world stays at the end of the step before.
    pub fn set_interrupt(&mut self, check: Option<fn() -> Result<(), CallbackError>>) {
        self.interrupt = Interrupt::new(check);
        if let Some(stage) = &mut self.collide_stage {
            stage.set_interrupt(self.interrupt);
        }
    }

    /// The interrupt check between stages; a stop forgets the method's cache (the step's
    /// half-made state is dropped).
    pub(super) fn poll_interrupt(&mut self) -> Result<(), Error> {
        let result = self.interrupt.poll();
        if result.is_err() {
            self.stepper = None;
        }
        result
    }
}

// A World is Send + Sync (its forces, steppers and prepared Jacobians are bound so), so that
// the Python binding's World may be dropped on any thread (issue 49: pyo3 leaked an
// `unsendable` one dropped on another thread, with a message each time).
const _: fn() = || {
    fn send_sync<T: Send + Sync>() {}
    send_sync::<World>();
};
