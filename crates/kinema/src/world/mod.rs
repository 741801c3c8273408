//! The world: particles, the forces on them, and `World::step`, the seed's four stages.

mod advisor;
mod collisions;
mod contact_force;
mod dynamics;
mod implicit;
mod order;

pub use advisor::Rates;
use collisions::StepFrame;
pub use collisions::{CollisionParams, CollisionStats, ContactModel};
pub use implicit::{CG_MAX_ITERATIONS, CG_TOLERANCE};

use crate::collide::{Collider, Contact, Partner, Periodic, GEOMETRY_LIMIT};
use crate::diagnostics::Diagnostics;
use crate::error::{CallbackError, Divergence, Error};
use crate::forces::{EnergyClass, Force, State};
use crate::ode::explicit_rk::ExplicitRk;
use crate::ode::stepper::{first_non_finite, Stats, StepFailure, Stepper, Termination};
use crate::ode::symplectic_euler::SymplecticEuler;
use crate::ode::system::{FirstOrderForm, OdeSystem, SecondOrderSystem};
use crate::ode::{self, Integrator, Method, MethodKind, SolveOptions};
use crate::particles::Particles;
use collisions::CollisionStage;
use contact_force::{ContactForce, CHUNK};
use dynamics::Dynamics;
use implicit::BaraffWitkin;
use rayon::prelude::*;
use std::cell::RefCell;
use std::rc::Rc;

/// The energy may grow by this many times its reference scale before a step counts as a
/// runaway (see [`World::step`]).
pub const RUNAWAY_FACTOR: f64 = 1e3;

/// The runaway-energy check runs at every this many steps (steps 10, 20, ...), not at every
/// step: the energy needs a pass over the particles and, with spring–dashpot contacts, over
/// the contacts, which would cost as much as a force evaluation per step. A runaway grows
/// over many steps, and a step that overflows is refused at once by the non-finite check.
pub const RUNAWAY_CHECK_EVERY: u64 = 10;

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

/// The stepper a world keeps between steps (so that a method's cache survives).
enum WorldStepper {
    /// Velocity Verlet on the particles' own arrays (see [`VerletBuffers`]).
    Verlet(Box<VerletBuffers>),
    SecondOrder(Box<dyn for<'a> Stepper<dyn SecondOrderSystem + 'a>>),
    FirstOrder(Box<dyn for<'a> Stepper<dyn OdeSystem + 'a>>),
    /// rk45 substeps adaptively inside each world step.
    Adaptive,
    /// implicit_euler: Baraff & Witkin's linearised step with conjugate gradients.
    Implicit(Box<BaraffWitkin>),
}

impl WorldStepper {
    fn new(method: &Integrator, n: usize) -> Self {
        match method {
            Integrator::Tableau(t) => WorldStepper::FirstOrder(Box::new(ExplicitRk::new(t.clone(), 2 * n))),
            Integrator::Named(m) => match m.kind() {
                MethodKind::SecondOrder if *m == Method::Verlet => WorldStepper::Verlet(Box::default()),
                MethodKind::SecondOrder => WorldStepper::SecondOrder(Box::new(SymplecticEuler::new(n))),
                MethodKind::ExplicitRk => WorldStepper::FirstOrder(Box::new(ExplicitRk::new(
                    m.tableau().expect("explicit methods have tableaux"),
                    2 * n,
                ))),
                MethodKind::Implicit => WorldStepper::Implicit(Box::default()),
                MethodKind::Adaptive => WorldStepper::Adaptive,
            },
        }
    }
}

/// Velocity Verlet's acceleration a_n at the current state, kept from the last step's end
/// (first same as last), and the next one's buffer; the world's `x_next`, `v_next` hold the
/// new state until the step is accepted. The scheme (and why the dashpot sees the Euler
/// predictor v + h a) is that of `ode/verlet.rs`, bit for bit:
///
/// ```text
///   x' = x + h v + h²/2 a,   v' = v + h a          (drift and predictor, one pass)
///   a' = F(t + h, x', v') / m                       (the force evaluation)
///   v' = v + h/2 (a + a')                           (the two half kicks, one pass)
/// ```
///
/// Nothing is joined, split or copied: the accepted step swaps buffers.
#[derive(Default)]
struct VerletBuffers {
    a: Vec<f64>,
    a_next: Vec<f64>,
    /// `a` holds the acceleration at the current state.
    fresh: bool,
}

/// Particles, forces, an integrator, a time step and the time.
pub struct World {
    particles: Particles,
    forces: Vec<Box<dyn Force>>,
    params: WorldParams,
    time: f64,
    steps: u64,
    stats: Stats,
    stepper: Option<WorldStepper>,
    y: Vec<f64>,
    y_next: Vec<f64>,
    /// The state a step produces, m and m/s (3 per particle); swapped in when accepted.
    x_next: Vec<f64>,
    v_next: Vec<f64>,
    force: Vec<f64>,
    /// The energy reference of the runaway check; `None` until the next step sets it.
    watch: Option<EnergyWatch>,
    /// Stages 2–4, when collisions are on.
    collisions: Option<CollisionStage>,
    /// Index in `forces` of the spring–dashpot contact force, with that model, and the
    /// force itself (shared: the world asks it when its list expires and sorts by it).
    contact_force: Option<usize>,
    contact: Option<Rc<RefCell<ContactForce>>>,
    /// The particles' order: `Some(user_of)` while they are sorted along space, with
    /// `user_of[i]` the user's index of particle i (see `order.rs`); `None` in the user's order.
    sorted: Option<Vec<u32>>,
    /// Sorts along space so far.
    sorts: u64,
    /// The contact force must be rebuilt before the next step (particles changed).
    contact_dirty: bool,
    /// Wall-clock time spent in each stage so far.
    times: StageTimes,
    /// Asked between the stages of a step and inside long ones whether to stop (Ctrl-C).
    interrupt: Interrupt,
}

/// Whether to stop a step: the caller's check (the Python bindings: Ctrl-C), asked at most
/// every [`Interrupt::EVERY`]; its error stops the step, which then leaves the world as it
/// was before it.
#[derive(Debug, Clone, Copy)]
pub struct Interrupt {
    check: Option<fn() -> Result<(), CallbackError>>,
    last: Option<std::time::Instant>,
}

impl Interrupt {
    /// How often the check runs at most.
    pub const EVERY: std::time::Duration = std::time::Duration::from_millis(10);

    /// No check.
    pub fn none() -> Self {
        Interrupt { check: None, last: None }
    }

    /// Runs the check if it has not run for [`Interrupt::EVERY`].
    pub fn poll(&mut self) -> Result<(), Error> {
        let Some(check) = self.check else { return Ok(()) };
        let now = std::time::Instant::now();
        if self.last.is_some_and(|t| now.duration_since(t) < Self::EVERY) {
            return Ok(());
        }
        self.last = Some(now);
        check().map_err(Error::Callback)
    }
}

/// Wall-clock time spent in the seed's four stages of [`World::step`], summed over all steps.
/// With spring–dashpot contacts the contacts are a force: all of their time is integration.
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
}

/// The reference of the runaway-energy check (see [`World::step`]).
#[derive(Debug, Clone, Copy)]
struct EnergyWatch {
    /// Kinetic plus potential energy at the reference state, J.
    energy: f64,
    /// Kinetic energy plus the magnitudes of the potential energies there, J.
    scale: f64,
}

impl World {
    /// The most adaptive sub-steps rk45 takes inside one step of dt: a step that needs more
    /// has a dt far beyond what its forces allow (or forces rk45 cannot follow, such as
    /// quadratic drag chattering about v = 0 over a step of 1e10 s, which took 24 s before
    /// stopping at the solver's 10⁷), and is refused as diverged in milliseconds instead.
    pub const RK45_SUBSTEPS: usize = 100_000;

    /// An empty world; checks the parameters.
    pub fn new(params: WorldParams) -> Result<Self, Error> {
        if !(params.dt.is_finite() && params.dt > 0.0) {
            return Err(Error::invalid("dt", params.dt, "the time step must be a finite number > 0 s"));
        }
        if params.dim != 2 && params.dim != 3 {
            return Err(Error::invalid("dim", params.dim, "a world is 2D (the xy-plane) or 3D"));
        }
        Ok(Self {
            particles: Particles::default(),
            forces: Vec::new(),
            params,
            time: 0.0,
            steps: 0,
            stats: Stats::default(),
            stepper: None,
            y: Vec::new(),
            y_next: Vec::new(),
            x_next: Vec::new(),
            v_next: Vec::new(),
            force: Vec::new(),
            watch: None,
            collisions: None,
            contact_force: None,
            contact: None,
            sorted: None,
            sorts: 0,
            contact_dirty: false,
            times: StageTimes::default(),
            interrupt: Interrupt::none(),
        })
    }

    /// Adds particles (see [`Particles::add`]); in 2D every z and z velocity must be 0.
    pub fn add_particles(
        &mut self,
        x: &[f64],
        v: &[f64],
        mass: &[f64],
        radius: &[f64],
        pinned: &[bool],
    ) -> Result<std::ops::Range<usize>, Error> {
        if self.params.dim == 2 {
            for (name, values) in [("position", x), ("velocity", v)] {
                if let Some(i) = values.chunks(3).position(|c| c.len() == 3 && c[2] != 0.0) {
                    return Err(Error::invalid(
                        format!("{name}[{i}][2]"),
                        values[3 * i + 2],
                        "a 2D world keeps z = 0",
                    ));
                }
            }
        }
        let range = self.particles.add(x, v, mass, radius, pinned)?;
        for f in &self.forces {
            f.validate(self.particles.len())?;
        }
        self.reset_caches(); // the state changed size
        if let Some(stage) = &mut self.collisions {
            if !stage.own.is_empty() {
                stage.own.resize(self.particles.len(), (None, None));
            }
            stage.refresh_materials()?;
        }
        self.rebuild_contact_force()?;
        Ok(range)
    }

    /// Restores what a checkpoint holds besides the particles' state: the time (s), the
    /// steps taken, and each particle's id with the id the next one gets (ids strictly
    /// increasing, as adding and removing leave them, all below `next_id`).
    pub fn restore_clock_and_ids(&mut self, time: f64, steps: u64, ids: &[u64], next_id: u64) -> Result<(), Error> {
        if !time.is_finite() {
            return Err(Error::invalid("time", time, "the time must be finite"));
        }
        if ids.len() != self.particles.len() {
            return Err(Error::invalid(
                "ids",
                format!("{} ids", ids.len()),
                format!("one per particle ({})", self.particles.len()),
            ));
        }
        if let Some(k) = (1..ids.len()).find(|&k| ids[k] <= ids[k - 1]) {
            return Err(Error::invalid(format!("ids[{k}]"), ids[k], "ids must increase strictly"));
        }
        if ids.last().is_some_and(|&l| l >= next_id) {
            return Err(Error::invalid("next_id", next_id, "it must be above every id"));
        }
        self.restore_user_order();
        self.time = time;
        self.steps = steps;
        self.particles.id.copy_from_slice(ids);
        self.particles.next_id = next_id;
        Ok(())
    }

    /// Restores the collision books of a checkpoint: the totals since collisions were turned
    /// on and the last step's (see [`World::collision_stats`]). Nothing when they are off.
    pub fn restore_collision_stats(&mut self, total: CollisionStats, last: CollisionStats) {
        if let Some(stage) = &mut self.collisions {
            stage.total = total;
            stage.last = last;
        }
    }

    /// Starts the collision stage's and the contact force's caches again, as after changing
    /// the particles (the contact lists and the particles' order along space, the impulse
    /// solver's warm start), and the method's: a checkpoint is taken at such a point, so that
    /// a world read from it, built afresh, and the world that wrote it go on from the same
    /// engine state. What the method carries from step to step is kept apart
    /// ([`World::integrator_carry`]) and given back to both.
    pub fn restart_caches(&mut self) -> Result<(), Error> {
        self.restore_user_order();
        self.reset_caches();
        self.rebuild_contact_force()
    }

    /// What the method carries from one step to the next, in the user's order: Verlet's
    /// acceleration at the current state (m/s², 3 per particle; only while it is up to date)
    /// or implicit Euler's last Δv (m/s, its first guess for the next solve). `None` for the
    /// other methods, which carry nothing, and before the first step.
    pub fn integrator_carry(&mut self) -> Option<Vec<f64>> {
        self.restore_user_order();
        let n = 3 * self.particles.len();
        match &self.stepper {
            Some(WorldStepper::Verlet(b)) if b.fresh && b.a.len() == n => Some(b.a.clone()),
            Some(WorldStepper::Implicit(bw)) if bw.warm_start().len() == n => Some(bw.warm_start().to_vec()),
            _ => None,
        }
    }

    /// The impulse model's warm start carried to the next step: each contact of the last
    /// step, (particle, partner, impulse totals in N·s), sorted; empty without collisions.
    pub fn collision_carry(&mut self) -> Vec<(usize, Partner, [f64; 3])> {
        self.restore_user_order();
        self.collisions.as_ref().map(|c| c.warm_start().to_vec()).unwrap_or_default()
    }

    /// Gives the impulse model back what [`World::collision_carry`] took (a checkpoint's);
    /// checks the particles and colliders it names.
    pub fn restore_collision_carry(&mut self, carry: Vec<(usize, Partner, [f64; 3])>) -> Result<(), Error> {
        let (n, colliders) = (self.particles.len(), self.colliders().len());
        if let Some(k) = carry.iter().position(|(i, other, t)| {
            *i >= n
                || !t.iter().all(|c| c.is_finite())
                || match other {
                    Partner::Particle(j) => *j >= n,
                    Partner::Collider(c) => *c >= colliders,
                }
        }) {
            return Err(Error::invalid(
                format!("collision_carry[{k}]"),
                format!("{:?}", carry[k]),
                format!("contacts between the {n} particles and {colliders} colliders, with finite impulses"),
            ));
        }
        match &mut self.collisions {
            Some(stage) => stage.set_warm_start(carry),
            None if carry.is_empty() => {}
            None => {
                return Err(Error::invalid(
                    "collision_carry",
                    carry.len(),
                    "no contacts: collisions are off",
                ))
            }
        }
        Ok(())
    }

    /// Gives the method back what [`World::integrator_carry`] took (a checkpoint's).
    pub fn restore_integrator_carry(&mut self, carry: Vec<f64>) -> Result<(), Error> {
        let n = 3 * self.particles.len();
        if carry.len() != n {
            return Err(Error::invalid(
                "integrator_carry",
                format!("{} values", carry.len()),
                format!("3 per particle ({n})"),
            ));
        }
        self.restore_user_order();
        let mut stepper = WorldStepper::new(&self.params.method, n);
        match &mut stepper {
            WorldStepper::Verlet(b) => {
                b.a = carry;
                b.fresh = true;
            }
            WorldStepper::Implicit(bw) => bw.set_warm_start(carry),
            _ => {
                return Err(Error::invalid(
                    "integrator_carry",
                    self.params.method.name(),
                    "only verlet and implicit_euler carry anything",
                ))
            }
        }
        self.stepper = Some(stepper);
        Ok(())
    }

    /// Each particle's own restitution and friction (`None`: the world's value); empty when
    /// no particle has its own.
    pub fn particle_materials(&self) -> Vec<(Option<f64>, Option<f64>)> {
        self.collisions.as_ref().map(|c| c.own.clone()).unwrap_or_default()
    }

    /// Removes the particles at the given indices (the user's order; repeats allowed); the
    /// others keep their order, their ids and their state. A removed particle takes with it
    /// what the forces hold for it (springs ending on it, [`Force::remove_particles`]) and its
    /// own collision materials; the integrator's and the collision stage's caches start
    /// again, as after [`World::add_particles`]. Between steps only: the time, the step
    /// count and the collision books go on.
    pub fn remove_particles(&mut self, indices: &[usize]) -> Result<(), Error> {
        let n = self.particles.len();
        if let Some(k) = indices.iter().position(|&i| i >= n) {
            return Err(Error::invalid(
                format!("index[{k}]"),
                indices[k],
                format!("indices of particles must be < {n}, the number of particles"),
            ));
        }
        if indices.is_empty() {
            return Ok(());
        }
        self.restore_user_order();
        let mut keep = vec![true; n];
        for &i in indices {
            keep[i] = false;
        }
        let new_of_old = self.particles.retain(&keep);
        for v in [&mut self.x_next, &mut self.v_next] {
            crate::particles::retain_rows(v, 3, &keep);
        }
        for f in &mut self.forces {
            f.reindex(&new_of_old);
        }
        if let Some(stage) = &mut self.collisions {
            crate::particles::retain_rows(&mut stage.own, 1, &keep);
            stage.refresh_materials()?;
        }
        self.reset_caches();
        self.rebuild_contact_force()
    }

    /// Adds a force, checked against the current particles (before the spring–dashpot contact
    /// force, which is always the last one).
    pub fn add_force(&mut self, force: Box<dyn Force>) -> Result<(), Error> {
        force.validate(self.particles.len())?;
        // The spring–dashpot contact force stays last: Verlet's fused pass adds it after the
        // sum of the others, the order in which the forces are summed everywhere else.
        match self.contact_force {
            Some(k) => {
                self.forces.insert(k, force);
                self.contact_force = Some(k + 1);
            }
            None => self.forces.push(force),
        }
        self.reset_caches();
        Ok(())
    }

    /// The particles (read only; change them through the world's methods).
    pub fn particles(&self) -> &Particles {
        &self.particles
    }

    /// Mutable particles: after changing positions or velocities the method caches are
    /// dropped, so the next step starts afresh.
    pub fn particles_mut(&mut self) -> &mut Particles {
        self.reset_caches();
        self.contact_dirty = self.contact_force.is_some();
        &mut self.particles
    }

    /// Drops what depends on the state: the method's caches and the energy reference.
    fn reset_caches(&mut self) {
        self.stepper = None;
        self.watch = None;
        if let Some(stage) = &mut self.collisions {
            stage.forget_list();
        }
    }

    /// The forces, in the order they were added.
    pub fn forces(&self) -> &[Box<dyn Force>] {
        &self.forces
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

    /// Work counters of all steps so far (force evaluations in `nfev`).
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// How many times the particles were sorted along space inside the engine (see
    /// [`World::advance`]); 0 where the world keeps the user's order.
    pub fn sorts(&self) -> u64 {
        self.sorts
    }

    /// Wall-clock time spent in each stage of the steps so far.
    pub fn stage_times(&self) -> StageTimes {
        let mut times = self.times;
        if let Some(stage) = &self.collisions {
            times.detect = stage.times.detect;
            times.respond = stage.times.respond;
            times.distribute = stage.times.distribute;
        }
        times
    }

    /// Energies and momenta now.
    pub fn diagnostics(&self) -> Diagnostics {
        let p = &self.particles;
        Diagnostics::measure(
            &State {
                t: self.time,
                x: &p.x,
                v: &p.v,
                mass: &p.mass,
            },
            &self.forces,
        )
    }

    /// The accelerations a = F/m now, m/s² (3 per particle).
    pub fn accelerations(&mut self) -> Result<Vec<f64>, Error> {
        let p = &self.particles;
        let mut dynamics = Dynamics::new(&mut self.forces, p, self.params.dim, &mut self.force);
        let mut a = vec![0.0; p.x.len()];
        dynamics.accel(self.time, &p.x, &p.v, &mut a)?;
        Ok(a)
    }

    /// The stable-step advisor's rates at the current state: the highest natural frequency of
    /// the linearised forces, its damping ratio and the largest damping rate (see [`Rates`]).
    pub fn rates(&mut self) -> Result<Rates, Error> {
        let p = &self.particles;
        let s = State {
            t: self.time,
            x: &p.x,
            v: &p.v,
            mass: &p.mass,
        };
        Ok(advisor::estimate(&mut self.forces, &s, &p.inv_mass, self.params.dim)?)
    }

    /// The largest stable time step (s) of `method` at the current state, by the advisor
    /// ([`Rates::max_step`]); infinite when no step is too large.
    pub fn stable_step(&mut self, method: &Integrator) -> Result<f64, Error> {
        Ok(self.rates()?.max_step(method))
    }

    /// Conjugate-gradient iterations of the last implicit_euler step, and whether they met
    /// [`CG_TOLERANCE`]; `None` for the other methods.
    pub fn linear_solve(&self) -> Option<(usize, bool)> {
        match &self.stepper {
            Some(WorldStepper::Implicit(bw)) => Some((bw.iterations, bw.converged)),
            _ => None,
        }
    }

    /// Advances the world by one time step `dt`, in the seed's order:
    ///
    /// 1. integrate — the state (t) → (t + dt) by the chosen method, under the forces;
    /// 2. detect — collisions between particles and with colliders;
    /// 3. respond — Newton's restitution law u_n⁺ = −e u_n⁻ gives each contact's impulse;
    /// 4. distribute — each impulse acts on both particles, equal and opposite.
    ///
    /// Stages 2–4 run when collisions are on ([`World::set_collisions`], or a collider was
    /// added) with the impulse model; see `collisions.rs` for how impacts inside the step are
    /// found (continuous detection) and resolved in time order.
    ///
    /// A step that would produce a non-finite state, or runaway energy, fails with
    /// [`Error::Diverged`] and leaves the world as it was before the step.
    ///
    /// Runaway energy is checked when no force can add energy ([`Force::can_add_energy`]): the
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
    /// Inside, with spring–dashpot contacts and velocity Verlet, the particles are kept in
    /// an order that follows space (re-sorted whenever the neighbour list is rebuilt, see
    /// `order.rs`); `advance` puts them back in the user's order before it returns, so every
    /// method of the world, and every force, callback and file, sees the user's order.
    pub fn advance(&mut self, n: u64) -> Result<(), Error> {
        let result = self.advance_in_engine_order(n);
        self.restore_user_order();
        result
    }

    /// [`World::advance`] for a caller that advances in slices: the particles stay in the
    /// engine's order (sorted along space) after it, for the next slice, until
    /// [`World::restore_order`] puts them back in the user's (every other method expects
    /// that order: call it before anything else).
    pub fn advance_in_engine_order(&mut self, n: u64) -> Result<(), Error> {
        for _ in 0..n {
            self.step_once()?;
        }
        Ok(())
    }

    /// Puts the particles back in the user's order after [`World::advance_in_engine_order`].
    pub fn restore_order(&mut self) {
        self.restore_user_order();
    }

    fn step_once(&mut self) -> Result<(), Error> {
        if self.contact_dirty {
            self.rebuild_contact_force()?;
        }
        if self.watch.is_none()
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
        self.integrate()?; // 1: the integrated state, in x_next, v_next
        self.times.integrate += start.elapsed();
        // 2–4: detect, respond, distribute, on x_next, v_next (timed inside)
        self.poll_interrupt()?;
        self.collide()?;
        // Accepted: the new state becomes the particles' own (a swap, not a copy).
        std::mem::swap(&mut self.particles.x, &mut self.x_next);
        std::mem::swap(&mut self.particles.v, &mut self.v_next);
        if let Some(WorldStepper::Verlet(b)) = &mut self.stepper {
            std::mem::swap(&mut b.a, &mut b.a_next);
        }
        self.time = self.params_time_after(self.steps + 1);
        self.steps += 1;
        Ok(())
    }

    /// Time after `k` steps: t = k·dt, computed by multiplication so it does not drift.
    fn params_time_after(&self, k: u64) -> f64 {
        k as f64 * self.params.dt
    }

    /// Stage 1: integrate positions and velocities over one step, into `x_next`, `v_next`.
    fn integrate(&mut self) -> Result<(), Error> {
        let n = 3 * self.particles.len();
        self.x_next.resize(n, 0.0);
        self.v_next.resize(n, 0.0);
        if n == 0 {
            return Ok(());
        }
        if self.stepper.is_none() {
            self.stepper = Some(WorldStepper::new(&self.params.method, n));
        }
        if matches!(self.stepper, Some(WorldStepper::Verlet(_))) {
            self.verlet()?;
        } else {
            self.integrate_joined()?;
        }
        if self.watch.is_some() && (self.steps + 1) % RUNAWAY_CHECK_EVERY == 0 {
            self.check_runaway()?;
        }
        Ok(())
    }

    /// Velocity Verlet on the particles' arrays (see [`VerletBuffers`]): drift and predictor
    /// in one parallel pass, the force evaluation (after sorting the particles along space
    /// when the contact force's neighbour list must be rebuilt), the two half kicks in one
    /// parallel pass that also finds a non-finite value.
    fn verlet(&mut self) -> Result<(), Error> {
        let n = 3 * self.particles.len();
        let (t, h) = (self.time, self.params.dt);
        let Some(WorldStepper::Verlet(mut b)) = self.stepper.take() else {
            unreachable!("called for verlet only")
        };
        let result = (|| {
            if self.forces.is_empty() {
                // No force at all (a gas of the impulse model): a = a' = 0, so the drift is
                // x + h v and both kicks add nothing. One pass instead of three, the same
                // numbers (to the sign of a zero).
                if !b.fresh || b.a.len() != n || b.a_next.len() != n {
                    // zeros once; no step writes them again
                    b.a.clear();
                    b.a.resize(n, 0.0);
                    b.a_next.clear();
                    b.a_next.resize(n, 0.0);
                    b.fresh = true;
                }
                // In a periodic cell x' is wrapped into it in the same pass (the collision
                // stage is told, and wraps only what it moves itself).
                let cell = self.collisions.as_ref().and_then(|c| c.domain.periodic_box());
                let p = &self.particles;
                let bad = self
                    .x_next
                    .par_chunks_mut(3 * CHUNK)
                    .zip(self.v_next.par_chunks_mut(3 * CHUNK))
                    .enumerate()
                    .map(|(c, (xn, vn))| {
                        let base = 3 * CHUNK * c;
                        let mut bad = None;
                        for k in 0..xn.len() {
                            let (x, v) = (p.x[base + k], p.v[base + k]);
                            xn[k] = x + h * v;
                            vn[k] = v;
                            if bad.is_none() && !xn[k].is_finite() {
                                bad = Some(base + k);
                            }
                        }
                        if let Some(cell) = cell {
                            cell.wrap_positions_serial(xn);
                        }
                        bad
                    })
                    .flatten()
                    .min();
                return Ok::<_, Error>(bad);
            }
            if !b.fresh || b.a.len() != n {
                b.a.resize(n, 0.0);
                let p = &self.particles;
                let mut dynamics = Dynamics::new(&mut self.forces, p, self.params.dim, &mut self.force);
                dynamics.accel(t, &p.x, &p.v, &mut b.a)?;
                self.stats.nfev += 1;
                b.fresh = true;
            }
            // With spring–dashpot contacts in a periodic cell, x' is wrapped into the cell in
            // the same pass, before the force evaluation, so that the kept acceleration is
            // that of the state kept (collide's wrap then changes nothing). The impulse
            // model's continuous detection needs the unwrapped drift, and wraps after its
            // impacts.
            let cell = self
                .collisions
                .as_ref()
                .and_then(|c| c.domain.periodic_box())
                .filter(|_| self.contact.is_some());
            let p = &self.particles;
            let a = &b.a;
            self.x_next
                .par_chunks_mut(3 * CHUNK)
                .zip(self.v_next.par_chunks_mut(3 * CHUNK))
                .enumerate()
                .for_each(|(c, (xn, vn))| {
                    let chunk = 3 * CHUNK * c..3 * CHUNK * c + xn.len();
                    let (x, v, a) = (&p.x[chunk.clone()], &p.v[chunk.clone()], &a[chunk]);
                    for ((((xn, vn), x), v), a) in xn.iter_mut().zip(vn.iter_mut()).zip(x).zip(v).zip(a) {
                        *xn = x + (h * v + 0.5 * h * h * a);
                        *vn = v + h * a;
                    }
                    if let Some(cell) = cell {
                        let (lo, hi, axes) = (cell.lo(), cell.hi(), cell.axes());
                        for q in xn.chunks_exact_mut(3) {
                            for (k, c) in q.iter_mut().enumerate() {
                                if axes[k] && !(*c >= lo[k] && *c < hi[k]) {
                                    *c = cell.wrap_coordinate(k, *c);
                                }
                            }
                        }
                    }
                });
            if self.sortable() && self.contact.as_ref().is_some_and(|c| c.borrow().list_expired(&self.x_next)) {
                self.sort_along_space(&mut b.a);
            }
            b.a_next.resize(n, 0.0);
            let p = &self.particles;
            if let Some(contact) = &self.contact {
                // The contact force and the closing kick in one pass, the other forces first.
                let s1 = State {
                    t: t + h,
                    x: &self.x_next,
                    v: &self.v_next,
                    mass: &p.mass,
                };
                let other = if self.forces.len() > 1 {
                    self.force.clear();
                    self.force.resize(n, 0.0);
                    for (k, f) in self.forces.iter_mut().enumerate() {
                        if Some(k) != self.contact_force {
                            f.accumulate(&s1, &mut self.force)?;
                        }
                    }
                    Some(&self.force[..])
                } else {
                    // nothing to sum: the buffer the first acceleration used is let go
                    self.force = Vec::new();
                    None
                };
                // The pass writes a' over a and the new velocities into a_next; two swaps put
                // a' in a_next (the next step's a once accepted) and the velocities in v_next
                // (v' there, the predictor, becomes spare).
                let bad = contact.borrow().verlet_force_and_kick(
                    &s1,
                    other,
                    &p.inv_mass,
                    self.params.dim == 2,
                    h,
                    &p.v,
                    &mut b.a,
                    &mut b.a_next,
                )?;
                std::mem::swap(&mut b.a, &mut b.a_next); // a_next = a'
                std::mem::swap(&mut b.a, &mut self.v_next); // v_next = v(t + h); a = spare
                self.stats.nfev += 1;
                b.fresh = true;
                return Ok::<_, Error>(bad);
            }
            let mut dynamics = Dynamics::new(&mut self.forces, p, self.params.dim, &mut self.force);
            dynamics.accel(t + h, &self.x_next, &self.v_next, &mut b.a_next)?;
            self.stats.nfev += 1;
            b.fresh = true; // a_next, the next step's a once accepted
            let (a, a_next) = (&b.a, &b.a_next);
            let bad = self
                .v_next
                .par_chunks_mut(3 * CHUNK)
                .zip(self.x_next.par_chunks(3 * CHUNK))
                .enumerate()
                .map(|(c, (vn, xn))| {
                    let base = 3 * CHUNK * c;
                    let mut bad = None;
                    for k in 0..vn.len() {
                        vn[k] = p.v[base + k] + 0.5 * h * (a[base + k] + a_next[base + k]);
                        if bad.is_none() && !(vn[k].is_finite() && xn[k].is_finite()) {
                            bad = Some(base + k);
                        }
                    }
                    bad
                })
                .flatten() // (Option's own order puts None first: drop the clean chunks)
                .min();
            Ok::<_, Error>(bad)
        })();
        self.stepper = Some(WorldStepper::Verlet(b));
        if let Some(contact) = &self.contact {
            contact.borrow().forget_verified();
        }
        match result? {
            Some(index) => Err(self.diverged(Divergence::NonFinite, Some(index / 3))),
            None => Ok(()),
        }
    }

    /// Stage 1 for the other methods, on the joined state [x, v] (their steppers work on one
    /// vector): joined into `y`, stepped into `y_next`, split into `x_next`, `v_next`.
    fn integrate_joined(&mut self) -> Result<(), Error> {
        let n = 3 * self.particles.len();
        let (t, h) = (self.time, self.params.dt);
        let p = &mut self.particles;
        self.y.resize(2 * n, 0.0);
        self.y_next.resize(2 * n, 0.0);
        FirstOrderForm::join(&p.x, &p.v, n, &mut self.y);
        let stepper = self.stepper.as_mut().expect("made by integrate");
        let mut dynamics = Dynamics::new(&mut self.forces, p, self.params.dim, &mut self.force);
        let outcome = match stepper {
            WorldStepper::Verlet(_) => unreachable!("verlet steps the particles' arrays"),
            WorldStepper::SecondOrder(s) => s.step(&mut dynamics, t, &self.y, h, &mut self.y_next, &mut self.stats),
            WorldStepper::FirstOrder(s) => {
                let mut first = FirstOrderForm::new(&mut dynamics);
                s.step(&mut first, t, &self.y, h, &mut self.y_next, &mut self.stats)
            }
            WorldStepper::Implicit(bw) => {
                let (x_next, v_next) = self.y_next.split_at_mut(n);
                bw.step(&mut dynamics, t, &p.x, &p.v, h, x_next, v_next, &mut self.stats)
                    .map_err(|e| StepFailure::Error(e.into()))
            }
            WorldStepper::Adaptive => {
                let opts = SolveOptions {
                    t_span: (t, t + h),
                    t_eval: Some(vec![t + h]),
                    max_steps: Self::RK45_SUBSTEPS,
                    ..SolveOptions::default()
                };
                let mut first = FirstOrderForm::new(&mut dynamics);
                let sol = ode::solve(&mut first, &self.y, &Integrator::Named(Method::Rk45), &opts)?;
                self.stats.nfev += sol.stats.nfev;
                match sol.termination {
                    None => {
                        self.y_next.copy_from_slice(sol.last());
                        Ok(())
                    }
                    Some(term) => Err(StepFailure::Stop(term)),
                }
            }
        };
        match outcome {
            Ok(()) => {}
            Err(StepFailure::Error(e)) => return Err(e),
            Err(StepFailure::Stop(Termination::NonFinite { index, .. })) => {
                return Err(self.diverged(Divergence::NonFinite, Some((index % n) / 3)))
            }
            Err(StepFailure::Stop(Termination::MaxSteps { .. })) => return Err(self.diverged(Divergence::TooManySubsteps, None)),
            Err(StepFailure::Stop(_)) => return Err(self.diverged(Divergence::StepTooSmall, None)),
        }
        if let Some(index) = first_non_finite(&self.y_next) {
            let particle = (index % n) / 3; // y_next = [x, v]
            return Err(self.diverged(Divergence::NonFinite, Some(particle)));
        }
        FirstOrderForm::split(&self.y_next, n, &mut self.x_next, &mut self.v_next);
        Ok(())
    }

    /// The runaway-energy check of [`World::step`] on the integrated state.
    fn check_runaway(&mut self) -> Result<(), Error> {
        let Some(watch) = self.watch else {
            return Ok(());
        };
        let (energy, scale) = self.energy_and_scale(&self.x_next, &self.v_next);
        if energy - watch.energy > RUNAWAY_FACTOR * watch.scale + 0.5 * scale {
            let fastest = self.fastest(&self.v_next);
            let reason = Divergence::RunawayEnergy {
                energy,
                reference: watch.energy,
                scale: watch.scale,
            };
            return Err(self.diverged(reason, fastest));
        }
        Ok(())
    }

    /// Stages 2–4 on the integrated state in `x_next`, `v_next` (a no-op without collisions):
    /// impacts inside the step and contacts at its end get Newton's restitution impulses,
    /// equal and opposite on the two particles (see [`CollisionParams`]).
    fn collide(&mut self) -> Result<(), Error> {
        let n = 3 * self.particles.len();
        let Some(stage) = self.collisions.as_mut() else {
            return Ok(());
        };
        if n == 0 {
            return Ok(());
        }
        if stage.params.model != ContactModel::Impulse {
            // The spring–dashpot model acted in stage 1, as a force; what is left here is
            // keeping positions in the periodic cell.
            stage.clear_step();
            if let Some(p) = stage.domain.periodic_box() {
                p.wrap_positions(&mut self.x_next);
            }
            return Ok(());
        }
        let p = &self.particles;
        let (x1, v1) = (&mut self.x_next[..], &mut self.v_next[..]);
        let accel = match &self.stepper {
            Some(WorldStepper::Verlet(b)) if b.a.len() == n => Some(&b.a[..]),
            _ => None,
        };
        // Without forces the paths are straight lines from step to step: the stage keeps
        // each particle's wake time and looks only at those due (collide/wake.rs). Verlet's
        // force-free pass wrapped x1 into the periodic cell already.
        let steady = self.forces.is_empty();
        let frame = StepFrame {
            t0: self.time,
            h: self.params.dt,
            accel,
            steady,
            wrapped: steady && accel.is_some(),
        };
        let changed = match stage.run(&frame, p, x1, v1) {
            Ok(changed) => changed,
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

    /// Turns collisions on (or changes their settings): stages 2–4 of every step with the
    /// impulse model, a contact force in stage 1 with the spring–dashpot model.
    pub fn set_collisions(&mut self, params: CollisionParams) -> Result<(), Error> {
        match &mut self.collisions {
            Some(stage) => stage.set_params(params)?,
            None => {
                let mut stage = CollisionStage::new(params, self.params.dim)?;
                stage.impulse.interrupt = self.interrupt;
                self.collisions = Some(stage);
            }
        }
        self.rebuild_contact_force()
    }

    /// Makes the spring–dashpot contact force match the collision settings, colliders and
    /// particles (added to the forces, replaced, or removed).
    fn rebuild_contact_force(&mut self) -> Result<(), Error> {
        self.contact_dirty = false;
        if let Some(stage) = &mut self.collisions {
            stage.forget_list(); // the impulse model's list: colliders, domain or particles changed
        }
        let wanted = match self.collisions.as_ref().map(|c| c.params.model) {
            Some(ContactModel::SpringDashpot { stiffness, damping }) => Some((stiffness, damping)),
            _ => None,
        };
        match (wanted, self.contact_force) {
            (None, None) => return Ok(()),
            (None, Some(k)) => {
                self.forces.remove(k);
                self.contact_force = None;
                self.contact = None;
            }
            (Some((stiffness, damping)), index) => {
                let stage = self.collisions.as_ref().expect("collisions are on");
                let (global, own) = stage.materials_parts();
                let p = &self.particles;
                let contact = Rc::new(RefCell::new(ContactForce::new(
                    stiffness,
                    damping,
                    global,
                    own,
                    p.radius.clone(),
                    p.inv_mass.clone(),
                    stage.colliders.clone(),
                    stage.domain,
                )));
                let force = Box::new(order::SharedContact(contact.clone()));
                self.contact = Some(contact);
                match index {
                    Some(k) => self.forces[k] = force,
                    None => {
                        self.forces.push(force);
                        self.contact_force = Some(self.forces.len() - 1);
                    }
                }
            }
        }
        self.reset_caches();
        Ok(())
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
        if self.collisions.is_none() {
            self.set_collisions(CollisionParams::default())?;
        }
        let stage = self.collisions.as_mut().expect("collisions are on");
        stage.own.resize(self.particles.len(), (None, None));
        for (k, (e, m)) in restitution.iter().zip(friction).enumerate() {
            stage.own[start + k] = (*e, *m);
        }
        stage.refresh_materials()?;
        self.rebuild_contact_force()
    }

    /// The collision settings, when collisions are on.
    pub fn collision_params(&self) -> Option<CollisionParams> {
        self.collisions.as_ref().map(|c| c.params)
    }

    /// Adds a static collider and returns its index; turns collisions on with the default
    /// settings if they are off.
    pub fn add_collider(&mut self, collider: impl Into<Collider>) -> Result<usize, Error> {
        let collider = collider.into();
        collider.check_dim(self.params.dim)?;
        if self.collisions.is_none() {
            self.set_collisions(CollisionParams::default())?;
        }
        let stage = self.collisions.as_mut().expect("collisions are on");
        stage.colliders.push(collider);
        let index = stage.colliders.len() - 1;
        self.rebuild_contact_force()?;
        Ok(index)
    }

    /// The colliders, in the order they were added.
    pub fn colliders(&self) -> &[Collider] {
        self.collisions.as_ref().map_or(&[], |c| &c.colliders)
    }

    /// Makes the axes with `axes[k]` true periodic, with the cell of the world's box collider
    /// (its walls along those axes then vanish: a particle leaving one side comes back on the
    /// other). All false makes space open again.
    pub fn set_periodic(&mut self, axes: [bool; 3]) -> Result<(), Error> {
        if self.collisions.is_none() {
            self.set_collisions(CollisionParams::default())?;
        }
        let stage = self.collisions.as_mut().expect("collisions are on");
        if !axes.iter().any(|a| *a) {
            stage.set_periodic(None)?;
            return self.rebuild_contact_force();
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
        self.rebuild_contact_force()?;
        self.reset_caches();
        Ok(())
    }

    /// The periodic axes (all false for open space).
    pub fn periodic(&self) -> [bool; 3] {
        self.collisions
            .as_ref()
            .and_then(|c| c.domain.periodic_box().map(|p| p.axes()))
            .unwrap_or([false; 3])
    }

    /// The contacts found at the end of the last step, as detected: `overlap` before it was
    /// removed and `u_n` before the end-of-step impulses (impacts found inside the step by
    /// continuous detection were already resolved). Empty with the spring–dashpot model,
    /// whose contacts live inside the force evaluations.
    pub fn contacts(&self) -> &[Contact] {
        self.collisions.as_ref().map_or(&[], |c| &c.impulse.detected)
    }

    /// What the collision stages did in the last step, and summed over all steps; `None`
    /// without collisions.
    pub fn collision_stats(&self) -> Option<(CollisionStats, CollisionStats)> {
        self.collisions.as_ref().map(|c| (c.last, c.total))
    }

    /// Mechanical energy (kinetic plus every potential, J) at (x, v), and its scale: kinetic
    /// plus the magnitudes of the potentials.
    fn energy_and_scale(&self, x: &[f64], v: &[f64]) -> (f64, f64) {
        let p = &self.particles;
        let kinetic: f64 = v
            .chunks_exact(3)
            .zip(&p.mass)
            .zip(&p.inv_mass)
            .filter(|(_, w)| **w > 0.0)
            .map(|((vi, m), _)| 0.5 * m * (vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]))
            .sum();
        let s = State {
            t: self.time,
            x,
            v,
            mass: &p.mass,
        };
        let (mut energy, mut scale) = (kinetic, kinetic);
        for f in &self.forces {
            if let Some(u) = f.potential_energy(&s) {
                energy += u;
                scale += u.abs();
            }
        }
        (energy, scale)
    }

    /// Whether a position or velocity is so large (> 10¹⁵⁰, m or m/s) that its square, or a
    /// sum of them, overflows: the collision geometry cannot be computed for such a state.
    fn beyond_geometry(x: &[f64], v: &[f64]) -> bool {
        x.iter().chain(v).any(|c| !(c.abs() <= GEOMETRY_LIMIT))
    }

    /// Sets the check that may stop a step (`None`: none): asked at most every
    /// [`Interrupt::EVERY`] between the stages of a step and inside the impacts of a long
    /// one; its error stops the step, and the world stays at the end of the step before.
    pub fn set_interrupt(&mut self, check: Option<fn() -> Result<(), CallbackError>>) {
        self.interrupt = Interrupt { check, last: None };
        if let Some(stage) = &mut self.collisions {
            stage.impulse.interrupt = self.interrupt;
        }
    }

    /// The interrupt check between stages; a stop forgets the method's cache (the step's
    /// half-made state is dropped).
    fn poll_interrupt(&mut self) -> Result<(), Error> {
        let result = self.interrupt.poll();
        if result.is_err() {
            self.stepper = None;
        }
        result
    }

    /// The movable particle with the largest speed in `v`.
    fn fastest(&self, v: &[f64]) -> Option<usize> {
        v.chunks_exact(3)
            .map(|vi| vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2])
            .enumerate()
            .filter(|(i, _)| self.particles.inv_mass[*i] > 0.0)
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    }

    /// The error of a refused step, with the advisor's step at the kept state.
    fn diverged(&mut self, reason: Divergence, particle: Option<usize>) -> Error {
        self.stepper = None;
        let particle = particle.map(|i| self.sorted.as_ref().map_or(i, |user_of| user_of[i] as usize));
        let method = self.params.method.clone();
        let advised_dt = self.stable_step(&method).ok().filter(|h| h.is_finite());
        Error::Diverged {
            step: self.steps + 1,
            time: self.time,
            particle,
            dt: self.params.dt,
            reason,
            advised_dt,
        }
    }
}
