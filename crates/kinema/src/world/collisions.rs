//! Stages 2–4 of a world step with the impulse model: detect collisions (continuously inside
//! the step, then as contacts at its end), respond by Newton's restitution law, distribute each
//! impulse onto both particles.

use std::time::{Duration, Instant};

use rayon::prelude::*;

use crate::collide::events::{swept_reach, Event, EventQueue, PathStore, Paths, Scene};
use crate::collide::islands::{self, EndProblem, IslandStats, Islands};
use crate::collide::neighbour_list::{collider_scale, NeighbourList, CHUNK, SKIN_PER_RADIUS};
use crate::collide::wake::Wake;
use crate::collide::{
    pair_contact, restitution_impulse, Collider, Contact, Domain, Grid, HoldParams, Material, MaterialTable, Partner, Periodic,
    Plane, ResolveParams, SeparateParams,
};
use crate::error::Error;
use crate::vec3;

/// The contact model: how a collision changes the motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactModel {
    /// Newton's restitution law by impulses after integration (stages 2–4), the seed's model.
    Impulse,
    /// A spring–dashpot force while bodies overlap (the DEM way), integrated with the other
    /// forces in stage 1: F_n = k_n δ − m_eff γ_n u_n with γ_n from the requested e by the
    /// damped oscillator's closed form ([`crate::collide::PenaltyLaw`]), or given.
    SpringDashpot {
        /// Normal stiffness k_n, N/m (> 0).
        stiffness: f64,
        /// Damping rate γ_n, 1/s (≥ 0), instead of the one the restitution implies.
        damping: Option<f64>,
    },
}

impl ContactModel {
    /// The models' names, as the binding and the scene files spell them, in the order an
    /// error lists them.
    pub const NAMES: [&'static str; 2] = ["impulse", "spring_dashpot"];

    /// The model named `name`, with the spring–dashpot's stiffness k_n (N/m) and damping
    /// rate γ_n (1/s). Each parameter belongs to one model: giving it to the other is an
    /// error, and `"spring_dashpot"` needs its stiffness. (The values themselves are checked
    /// by [`CollisionParams::check`].)
    pub fn from_name(name: &str, stiffness: Option<f64>, damping: Option<f64>) -> Result<ContactModel, Error> {
        match name {
            "impulse" => {
                for (param, value) in [("stiffness", stiffness), ("damping", damping)] {
                    if let Some(v) = value {
                        return Err(Error::invalid(
                            param,
                            v,
                            "only model='spring_dashpot' uses it; the impulse model has no contact spring",
                        ));
                    }
                }
                Ok(ContactModel::Impulse)
            }
            "spring_dashpot" => match stiffness {
                Some(stiffness) => Ok(ContactModel::SpringDashpot { stiffness, damping }),
                None => Err(Error::invalid(
                    "stiffness",
                    "None",
                    "model='spring_dashpot' needs the contact stiffness k_n, finite and > 0 N/m",
                )),
            },
            other => Err(Error::invalid(
                "model",
                format!("'{other}'"),
                format!(
                    "the contact model must be one of {}",
                    Self::NAMES.map(|n| format!("'{n}'")).join(", ")
                ),
            )),
        }
    }

    /// The model's name ([`ContactModel::NAMES`]), with its stiffness and damping (`None`
    /// for the impulse model): what [`ContactModel::from_name`] takes back.
    pub fn named(&self) -> (&'static str, Option<f64>, Option<f64>) {
        match *self {
            ContactModel::Impulse => (Self::NAMES[0], None, None),
            ContactModel::SpringDashpot { stiffness, damping } => (Self::NAMES[1], Some(stiffness), damping),
        }
    }
}

/// How collisions between particles, and with colliders, are handled. Units SI.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CollisionParams {
    /// The contact model. Default [`ContactModel::Impulse`].
    pub model: ContactModel,
    /// Coefficient of restitution e ∈ [0, 1] of every particle without its own (1: elastic,
    /// 0: plastic). Default 1.
    pub restitution: f64,
    /// Coulomb friction coefficient μ ≥ 0 of every particle without its own. Default 0.
    pub friction: f64,
    /// Continuous detection: impacts are found at their time inside the step and resolved
    /// in time order, so nothing passes through a particle or a wall however fast. Default
    /// true.
    pub ccd: bool,
    /// Approach speeds below this use e = 0, m/s, so that resting contacts do not bounce in
    /// place. `None` (default): twice the largest speed change the forces gave a particle in
    /// the step (a body resting under gravity approaches at g·dt each step).
    pub restitution_threshold: Option<f64>,
}

impl Default for CollisionParams {
    fn default() -> Self {
        CollisionParams {
            model: ContactModel::Impulse,
            restitution: 1.0,
            friction: 0.0,
            ccd: true,
            restitution_threshold: None,
        }
    }
}

impl CollisionParams {
    /// Checks the values; the error names the parameter.
    pub fn check(&self) -> Result<Material, Error> {
        if let ContactModel::SpringDashpot { stiffness, damping } = self.model {
            if !(stiffness.is_finite() && stiffness > 0.0) {
                return Err(Error::invalid(
                    "stiffness",
                    stiffness,
                    "the contact stiffness must be finite and > 0 N/m",
                ));
            }
            if let Some(g) = damping {
                if !(g.is_finite() && g >= 0.0) {
                    return Err(Error::invalid(
                        "damping",
                        g,
                        "the contact damping rate must be finite and >= 0 1/s",
                    ));
                }
            }
        }
        if let Some(t) = self.restitution_threshold {
            if !(t.is_finite() && t >= 0.0) {
                return Err(Error::invalid(
                    "restitution_threshold",
                    t,
                    "the restitution threshold must be finite and >= 0 m/s (or None for automatic)",
                ));
            }
        }
        Material::new(self.restitution, self.friction)
    }
}

/// What the collision stages did, over one step or summed over many.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CollisionStats {
    /// Contacts at the end of the step (touching or overlapping pairs and particle–collider
    /// contacts).
    pub contacts: usize,
    /// Impacts found by continuous detection inside the step, each resolved at its time.
    pub impacts: usize,
    /// Impulses applied (impacts and end-of-step contacts).
    pub impulses: usize,
    /// Σ m Δv of all particles over the collision stages minus the impulses that colliders
    /// and pinned particles gave them, N·s: the sum of all impulses between movable
    /// particles, zero by action and reaction up to rounding.
    pub impulse_balance: [f64; 3],
    /// Kinetic energy removed by the collisions, J (≥ 0; 0 for e = 1 without friction).
    pub energy_lost: f64,
    /// The largest overlap left after the step, m.
    pub max_overlap: f64,
    /// Sweeps of the end-of-step velocity solver (the latest step's; the most any island took).
    pub solver_sweeps: usize,
    /// Independent groups of the end-of-step contacts, each solved on its own on one of the
    /// threads (the latest step's; `collide/islands.rs`).
    pub islands: usize,
    /// Steps whose end-of-step solver stopped at its sweep cap before converging, or whose
    /// impacts stopped at the cap of continuous detection (0 or 1 for one step; summed).
    pub unconverged: usize,
}

impl CollisionStats {
    /// Adds another step's figures (contacts: the latest).
    pub fn accumulate(&mut self, step: &CollisionStats) {
        self.contacts = step.contacts;
        self.impacts += step.impacts;
        self.impulses += step.impulses;
        for k in 0..3 {
            self.impulse_balance[k] += step.impulse_balance[k];
        }
        self.energy_lost += step.energy_lost;
        self.max_overlap = step.max_overlap;
        self.solver_sweeps = step.solver_sweeps;
        self.islands = step.islands;
        self.unconverged += step.unconverged;
    }
}

/// Wall-clock time of the collision stages 2–4 of the impulse model, summed over steps.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CollisionTimes {
    /// Stage 2: the candidate list, each particle's first impact, the events' validity and
    /// rescheduling, the end-of-step contacts.
    pub detect: std::time::Duration,
    /// Stage 3: the impulses of Newton's law (impacts, and the end-of-step solver) and the
    /// removal of overlap.
    pub respond: std::time::Duration,
    /// Stage 4: each impulse onto both particles, the impulse balance and the energy books.
    pub distribute: std::time::Duration,
}

/// The velocity solver of the end-of-step contacts: most sweeps, and the tolerance below which
/// a sweep counts as converged (m/s). Warm-started, a resting pile takes one or two sweeps a
/// step; the cap only matters while a heap settles (see `docs/collisions.md`).
const END_SWEEPS: usize = 200;

/// Pairs closer than r_i + r_j by less than this fraction of r_i + r_j (and particles this
/// fraction of their radius from a collider) are contacts at the end of a step: the position
/// correction leaves resting pairs touching to rounding, on either side of exact contact.
const CONTACT_GAP: f64 = 1e-9;

/// Sweeps of the position correction at the end of a step (overlap removed along the normals).
const SEPARATE_SWEEPS: usize = 20;

/// The least approach speed of an impact, m/s: slower meetings are contacts for the end of
/// the step (the solver's tolerance, or the restitution threshold below which they would be
/// plastic anyway).
fn least_impact_speed(threshold: f64) -> f64 {
    ResolveParams::default().tolerance.max(threshold)
}

/// What continuous detection sweeps against (`collide::events::Scene`), from the stage's own
/// fields (a macro, not a method: the event loop holds it while it changes other fields).
macro_rules! scene {
    ($stage:ident, $radius:expr, $active:expr, $threshold:expr) => {
        Scene {
            radius: $radius,
            colliders: &$stage.colliders,
            active: $active,
            domain: &$stage.domain,
            list: &$stage.list,
            slow: least_impact_speed($threshold),
            resting: &$stage.resting,
        }
    };
}

/// What the world tells the collision stages about the step they follow.
pub(crate) struct StepFrame<'a> {
    /// The world's clock at the step's start, s.
    pub t0: f64,
    /// The step, s.
    pub h: f64,
    /// The method's constant acceleration of the step (velocity Verlet's a(t)), m/s², 3 per
    /// particle; `None`: the parabola through x₁ is taken.
    pub accel: Option<&'a [f64]>,
    /// No force acts: every path is a straight line from one step to the next, and the
    /// impact search starts only from the particles whose wake time falls in the step
    /// (`collide/wake.rs`).
    pub steady: bool,
    /// x₁ is already in the periodic cell (the stages wrap only what they move).
    pub wrapped: bool,
}

/// The collision stages of a world, with their settings, colliders and buffers.
pub(crate) struct CollisionStage {
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
    grid: Grid,
    /// Candidate pairs of continuous detection and of the end-of-step contacts.
    list: NeighbourList,
    /// The particles' paths through the step and the queue of their next impacts.
    paths: PathStore,
    /// The step's constant accelerations when the method gives none (the parabola
    /// through x₁), m/s².
    fitted: Vec<f64>,
    queue: EventQueue,
    /// In a force-free world, each particle's wake time (see `collide/wake.rs`), the
    /// particles woken in this step, whether this step rebuilt the list, and the fastest
    /// speed an impact of this step left.
    wake: Wake,
    woken: Vec<usize>,
    rebuilt: bool,
    fastest_hit: f64,
    /// Particles that touched something at the step's start or were hit in it: the only
    /// ones that can be in contact at its end (continuous detection saw every other path).
    touched: Vec<bool>,
    /// The integrated state (x₁, v₁) of each touched particle, for the energy books.
    books: Vec<(usize, [f64; 3], [f64; 3])>,
    contacts: Vec<Contact>,
    /// The end-of-step contacts as detected (overlap and u_n before the response).
    pub detected: Vec<Contact>,
    /// The end-of-step solver's velocity targets, totals, and the last step's totals by
    /// contact (for warm starting).
    targets: Vec<f64>,
    totals: Vec<[f64; 3]>,
    warm: Vec<(usize, Partner, [f64; 3])>,
    /// The contacts of `warm` and whether each carried load (see `Scene::resting`).
    resting: Vec<(usize, Partner, bool)>,
    pub total: CollisionStats,
    pub last: CollisionStats,
    pub times: CollisionTimes,
    /// The world's check that may stop a step, asked inside a long run of impacts.
    pub interrupt: super::Interrupt,
}

/// Whether contact `c` is with a wall of a box collider along a periodic axis of `domain`:
/// such walls do not exist (a particle leaving one side comes back on the other). Box walls
/// have axis-aligned normals.
pub(crate) fn on_periodic_wall(c: &Contact, colliders: &[Collider], domain: &Domain) -> bool {
    let in_box = matches!(c.other, Partner::Collider(k) if matches!(colliders[k], Collider::Box(_)));
    in_box
        && domain
            .periodic_box()
            .is_some_and(|p| (0..3).any(|k| p.axes()[k] && c.normal[k] != 0.0))
}

impl CollisionStage {
    pub fn new(params: CollisionParams, dim: usize) -> Result<Self, Error> {
        let material = params.check()?;
        Ok(CollisionStage {
            params,
            material,
            own: Vec::new(),
            particle_materials: None,
            colliders: Vec::new(),
            domain: Domain::open(dim)?,
            grid: Grid::new(),
            list: NeighbourList::default(),
            paths: PathStore::default(),
            fitted: Vec::new(),
            queue: EventQueue::default(),
            wake: Wake::default(),
            woken: Vec::new(),
            rebuilt: false,
            fastest_hit: 0.0,
            touched: Vec::new(),
            books: Vec::new(),
            contacts: Vec::new(),
            detected: Vec::new(),
            targets: Vec::new(),
            totals: Vec::new(),
            warm: Vec::new(),
            resting: Vec::new(),
            total: CollisionStats::default(),
            last: CollisionStats::default(),
            times: CollisionTimes::default(),
            interrupt: super::Interrupt::none(),
        })
    }

    /// Changes the settings, keeping colliders and buffers.
    pub fn set_params(&mut self, params: CollisionParams) -> Result<(), Error> {
        self.material = params.check()?;
        self.params = params;
        self.refresh_materials()
    }

    /// Forgets the last step's contacts and figures (a step of the spring–dashpot model).
    pub fn clear_step(&mut self) {
        self.detected.clear();
        self.last = CollisionStats::default();
    }

    /// The global material and the per-particle ones (if any particle has its own).
    pub fn materials_parts(&self) -> (Material, Option<Vec<Material>>) {
        (self.material, self.particle_materials.clone())
    }

    /// The end-of-step solver's warm start: each contact of the last step (particle, partner)
    /// with the impulse totals it carried, N·s, sorted by (particle, partner).
    pub fn warm_start(&self) -> &[(usize, Partner, [f64; 3])] {
        &self.warm
    }

    /// Sets the warm start (a checkpoint's), and with it which contacts rested.
    pub fn set_warm_start(&mut self, mut warm: Vec<(usize, Partner, [f64; 3])>) {
        warm.sort_by_key(|w| (w.0, w.1));
        self.resting = warm.iter().map(|w| (w.0, w.1, w.2 != [0.0; 3])).collect();
        self.warm = warm;
    }

    /// Rebuilds the per-particle materials from `own` and the global value.
    pub fn refresh_materials(&mut self) -> Result<(), Error> {
        if self.own.iter().all(|(e, m)| e.is_none() && m.is_none()) {
            self.particle_materials = None;
            return Ok(());
        }
        let global = self.material;
        self.particle_materials = Some(
            self.own
                .iter()
                .map(|(e, m)| Material::new(e.unwrap_or(global.restitution()), m.unwrap_or(global.friction())))
                .collect::<Result<_, _>>()?,
        );
        Ok(())
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

    fn materials(&self) -> MaterialTable<'_> {
        let table = MaterialTable::uniform(self.material).with_colliders(&self.colliders);
        match &self.particle_materials {
            Some(m) => table.with_particles(m),
            None => table,
        }
    }

    /// The walls of collider `k` that are active: a box's walls along periodic axes are not.
    fn wall_active(&self, plane: &Plane) -> bool {
        match self.domain.periodic_box() {
            Some(p) => {
                let n = plane.normal();
                !(0..3).any(|k| p.axes()[k] && n[k] != 0.0)
            }
            None => true,
        }
    }

    /// Forgets the candidate list and the warm start (particles, colliders or the domain
    /// changed).
    pub fn forget_list(&mut self) {
        self.list.built_at.clear();
        self.wake.valid = false;
        self.warm.clear();
        self.resting.clear();
    }

    /// Leaves out of the list's collider candidates a box whose walls all lie along
    /// periodic axes (a fully periodic cell has no walls to meet).
    fn drop_inactive_walls(&mut self) {
        let active = self.active_walls();
        self.list.walls.retain(|&(_, k)| active[k].iter().any(|a| *a));
    }

    /// Which walls of each collider exist: a box's walls along periodic axes do not.
    fn active_walls(&self) -> Vec<[bool; 6]> {
        self.colliders
            .iter()
            .map(|c| {
                let mut active = [false; 6];
                match c {
                    Collider::Box(b) => {
                        for (w, wall) in b.walls().iter().enumerate() {
                            active[w] = self.wall_active(wall);
                        }
                    }
                    _ => active[0] = true,
                }
                active
            })
            .collect()
    }

    /// Stages 2–4 of the impulse model on the step from (x0, v0) to the integrated (x1, v1),
    /// over `h` s; `accel` is the step's constant acceleration where the method knows it
    /// (velocity Verlet's a(t)), else it is the one that takes x0, v0 to x1. (x1, v1) are
    /// updated in place; returns whether anything changed.
    ///
    /// The order, and why (as Box2D's solver stages are listed):
    ///
    /// ```text
    ///   detect      the list holds for the step's sweep (else rebuilt); each particle's first
    ///               impact in [0, h] into the queue; who touches something at τ = 0
    ///   ┌ detect    the earliest event; a stale one is recomputed and put back
    ///   │ respond   its impulse by Newton's law at the impact time
    ///   │ distribute +w_i J on i, −w_j J on j; their paths change from there
    ///   └ detect    the two particles' next impacts           (until the queue is empty)
    ///   detect      end-of-step contacts among the touched particles
    ///   respond     the velocity solver's totals (restitution targets for impacts, holds for
    ///               resting contacts, warm-started); overlap removed by moving positions
    ///   distribute  the totals onto both particles; impulse balance; energy books
    /// ```
    ///
    /// Continuous detection interleaves the stages in time: an impact's impulse changes the
    /// two paths, and the next impacts of those two can only be found after it is applied.
    /// The end-of-step solve comes after all impacts, on the state they leave.
    #[allow(clippy::too_many_arguments)]
    pub fn run(
        &mut self,
        frame: &StepFrame<'_>,
        x0: &[f64],
        v0: &[f64],
        x1: &mut [f64],
        v1: &mut [f64],
        radius: &[f64],
        inv_mass: &[f64],
        mass: &[f64],
    ) -> Result<bool, Error> {
        let clock = Instant::now();
        let h = frame.h;
        // The step's paths: Verlet's own acceleration, or the parabola through x1.
        let mut store = std::mem::take(&mut self.paths);
        let mut fitted = std::mem::take(&mut self.fitted);
        let accel = match frame.accel {
            Some(a) => a,
            None => {
                fitted.clear();
                fitted.extend((0..x0.len()).map(|c| 2.0 * (x1[c] - x0[c] - v0[c] * h) / (h * h)));
                &fitted
            }
        };
        let mut paths = Paths::begin(&mut store, x0, v0, accel);
        let result = self.stages(&mut paths, clock, frame, x1, v1, radius, inv_mass, mass);
        self.paths = store;
        self.fitted = fitted;
        result
    }

    /// The body of [`CollisionStage::run`] on the step's paths (`clock`: the detect stage's
    /// start).
    #[allow(clippy::too_many_arguments)]
    fn stages(
        &mut self,
        paths: &mut Paths<'_>,
        clock: Instant,
        frame: &StepFrame<'_>,
        x1: &mut [f64],
        v1: &mut [f64],
        radius: &[f64],
        inv_mass: &[f64],
        mass: &[f64],
    ) -> Result<bool, Error> {
        let (t0, h) = (frame.t0, frame.h);
        let n = radius.len();
        let mut stats = CollisionStats::default();
        // The wake times hold only if this step ends well (an error leaves them invalid).
        let steady = frame.steady && self.params.ccd;
        let quiet = std::mem::replace(&mut self.wake.valid, false) && steady;
        self.rebuilt = false;
        self.fastest_hit = 0.0;
        let (threshold, reach) = self.prepare(paths, x1, v1, radius, h, quiet)?;
        let mut only_woken = quiet && !self.rebuilt;
        if steady && !only_woken {
            // New wake times for everyone, from the step's start (one pass over all pairs,
            // instead of a search of this step's impacts from every particle).
            self.wake_up(paths.x0, paths.v0, radius, t0, h, false);
            only_woken = std::mem::replace(&mut self.wake.valid, false);
        }
        // From here `rebuilt`: the list was rebuilt inside the step.
        self.rebuilt = false;
        self.woken.clear();
        if only_woken {
            self.woken = self.wake.due(t0 + h, h);
        }
        self.touched.clear();
        self.touched.resize(n, !self.params.ccd);
        self.books.clear();
        let mut changed = false;
        let mut t_detect = clock.elapsed();
        let (mut t_respond, mut t_distribute) = (Duration::ZERO, Duration::ZERO);

        if self.params.ccd {
            let (d, r, s, any) = self.impacts(paths, radius, inv_mass, mass, h, threshold, reach, only_woken, &mut stats)?;
            t_detect += d;
            t_respond += r;
            t_distribute += s;
            changed |= any;
        }
        let clock = Instant::now();
        if self.params.ccd {
            paths.finish(x1, v1, h);
        }
        // The state of the touched particles before the end-of-step solve, for its books.
        for q in (0..n).filter(|&q| self.touched[q]) {
            self.books.push((q, vec3::get(x1, q), vec3::get(v1, q)));
        }
        // Stage 2 at the end of the step: the contacts of the touched particles.
        self.end_contacts(x1, v1, radius);
        stats.contacts = self.contacts.len();
        self.detected.clone_from(&self.contacts);
        // A pair that only touches (no overlap) and approaches faster than an impact's least
        // speed meets exactly at the step's end: its impact belongs to the next step's t = 0,
        // where the law resolves it pair by pair, like every other impact (with ccd).
        if self.params.ccd {
            let slow = least_impact_speed(threshold);
            self.contacts.retain(|c| !(c.overlap <= 0.0 && c.u_n < -slow));
        }
        t_detect += clock.elapsed();

        // Stage 3: the solver's totals, and the overlap removed.
        let clock = Instant::now();
        let solved = self.solve(v1, x1, inv_mass, threshold)?;
        stats.solver_sweeps = solved.hold.iterations;
        stats.unconverged = stats.unconverged.max(usize::from(!solved.hold.converged));
        stats.islands = solved.islands;
        stats.max_overlap = solved.separate.max_overlap_after;
        changed |= solved.separate.max_overlap_before > 0.0;
        t_respond += clock.elapsed();

        // Stage 4: the totals onto both particles; the books.
        let clock = Instant::now();
        for (c, p) in self.contacts.iter().zip(&self.totals) {
            if *p == [0.0; 3] {
                continue;
            }
            changed = true;
            stats.impulses += 1;
            distribute(c.i, c.partner_particle(), *p, v1, inv_mass, mass, &mut stats.impulse_balance);
        }
        stats.energy_lost += self.energy_books(paths.accel, x1, v1, mass, inv_mass);
        if let Some(p) = self.domain.periodic_box() {
            if frame.wrapped {
                // only the touched particles moved since (the impacts, the correction)
                for &(q, _, _) in &self.books {
                    p.wrap_positions_serial(&mut x1[3 * q..3 * q + 3]);
                }
            } else {
                p.wrap_positions(x1);
            }
        }
        t_distribute += clock.elapsed();

        // The next steps' wake times: of the particles this step looked at, or of all.
        if steady {
            let clock = Instant::now();
            self.wake_up(x1, v1, radius, t0 + h, h, only_woken && !self.rebuilt);
            t_detect += clock.elapsed();
        }

        self.times.detect += t_detect;
        self.times.respond += t_respond;
        self.times.distribute += t_distribute;
        self.last = stats;
        self.total.accumulate(&stats);
        Ok(changed)
    }

    /// Makes the neighbour list hold for the whole step's sweep (rebuilt at x0 if not) and
    /// returns the restitution threshold and the largest swept displacement of any particle
    /// from the list's build positions, m.
    ///
    /// One pass over the particles: each one's swept displacement max(|x0 − b|, |x1 − b|) +
    /// ⅛ |a| h² (b its build position) and the two largest of them; its velocity change
    /// |v1 − v0| for the automatic threshold (twice the largest: a body resting under gravity
    /// approaches at g h each step).
    ///
    /// With `quiet` (a force-free step with valid wake times) the list's hold comes from the
    /// wake's speed bound instead, with no pass (`collide/wake.rs`), and the automatic
    /// threshold is 0 (no force changes a velocity). Sets `rebuilt` when it rebuilds.
    #[allow(clippy::too_many_arguments)]
    fn prepare(
        &mut self,
        paths: &Paths<'_>,
        x1: &[f64],
        v1: &[f64],
        radius: &[f64],
        h: f64,
        quiet: bool,
    ) -> Result<(f64, f64), Error> {
        let reach = self.wake.reach_after(h);
        let (x0, v0) = (paths.x0, paths.v0);
        if quiet && self.list.built_at.len() == x0.len() && 2.0 * reach < self.list.allowance {
            return Ok((self.params.restitution_threshold.unwrap_or(0.0), reach));
        }
        let domain = self.domain;
        let automatic = self.params.restitution_threshold.is_none();
        let sweep = |built: &[f64], accel: &[f64]| {
            x0.par_chunks(3 * CHUNK)
                .zip(x1.par_chunks(3 * CHUNK))
                .zip(built.par_chunks(3 * CHUNK))
                .enumerate()
                .map(|(c, ((x0, x1), b))| {
                    let mut top = (0.0_f64, 0.0_f64, 0.0_f64, false);
                    for l in 0..x0.len() / 3 {
                        let q = c * CHUNK + l;
                        let bq = vec3::get(b, l);
                        let d0 = domain.displacement(vec3::get(x0, l), bq);
                        let d1 = domain.displacement(vec3::get(x1, l), bq);
                        let a = vec3::get(accel, q);
                        let bulge2 = vec3::dot(a, a);
                        let mut d = vec3::dot(d0, d0).max(vec3::dot(d1, d1)).sqrt();
                        if bulge2 > 0.0 {
                            d += 0.125 * bulge2.sqrt() * h * h;
                        }
                        let dv = if automatic {
                            let w = vec3::sub(vec3::get(v1, q), vec3::get(v0, q));
                            vec3::dot(w, w)
                        } else {
                            0.0
                        };
                        top = top_two(top, (d, 0.0, dv, d.is_nan()));
                    }
                    top
                })
                .reduce(|| (0.0, 0.0, 0.0, false), top_two)
        };
        // (with `quiet` the bound said the list may not hold: rebuilt without the check, which
        // the actual displacements would pass only for a few more steps)
        let fresh = self.list.built_at.len() == x0.len() && !quiet;
        let mut top = if fresh {
            sweep(&self.list.built_at, paths.accel)
        } else {
            (f64::INFINITY, 0.0, 0.0, false)
        };
        let holds = top.0 + top.1 < self.list.allowance;
        if top.3 || !holds {
            // Rebuild at x0, with a skin of the base (0.6 mean radius) or four of this step's
            // largest sweeps, whichever is more: the list then lasts at least two such steps.
            let accel = paths.accel;
            let largest_move = (0..radius.len())
                .into_par_iter()
                .with_min_len(CHUNK)
                .map(|q| {
                    let a = vec3::norm(vec3::get(accel, q));
                    vec3::norm(domain.displacement(vec3::get(x1, q), vec3::get(x0, q))) + 0.125 * a * h * h
                })
                .reduce(|| 0.0, f64::max);
            let mean_radius = radius.iter().sum::<f64>() / radius.len().max(1) as f64;
            let skin = (SKIN_PER_RADIUS * mean_radius).max(4.0 * largest_move);
            let scale = self.colliders.iter().map(collider_scale).fold(0.0, f64::max);
            self.list.built_at.clear();
            self.list
                .update(&mut self.grid, x0, radius, &self.colliders, &self.domain, skin, scale)?;
            self.list.verified = None;
            self.drop_inactive_walls();
            self.rebuilt = true;
            top = sweep(&self.list.built_at, paths.accel);
            if top.3 || !top.0.is_finite() {
                // non-finite positions: the list's build named them already; a NaN velocity
                // change is caught by the world
                top.0 = f64::INFINITY;
            }
        }
        let threshold = self.params.restitution_threshold.unwrap_or(2.0 * top.2.sqrt());
        Ok((threshold, top.0))
    }

    /// Continuous detection and the impacts in time order (see [`CollisionStage::run`]):
    /// returns the time spent detecting, responding and distributing, and whether any impulse
    /// was applied. `reach`: the largest swept displacement from the list's build positions.
    #[allow(clippy::too_many_arguments)]
    fn impacts(
        &mut self,
        paths: &mut Paths<'_>,
        radius: &[f64],
        inv_mass: &[f64],
        mass: &[f64],
        h: f64,
        threshold: f64,
        mut reach: f64,
        only_woken: bool,
        stats: &mut CollisionStats,
    ) -> Result<(Duration, Duration, Duration, bool), Error> {
        let n = radius.len();
        let clock = Instant::now();
        let active = self.active_walls();
        if only_woken {
            self.schedule_woken(paths, radius, &active, h, threshold);
        } else {
            self.schedule_all(paths, radius, &active, 0.0, h, threshold);
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
            let scene = scene!(self, radius, &active, threshold);
            let partner = match event.partner {
                Partner::Particle(j) => Some(j),
                Partner::Collider(_) => None,
            };
            if partner.is_some_and(|j| paths.version(j) != event.partner_version) {
                // the partner's path changed since: predicted on a path that no longer exists
                let next = scene.earliest(paths, event.i, t, h);
                self.touched[event.i] |= next.touching;
                self.queue.schedule(event.i, next.event);
                t_detect += clock.elapsed();
                continue;
            }
            processed += 1;
            if processed % 256 == 0 {
                self.interrupt.poll()?; // a stop leaves the wake times invalid (see `stages`)
            }
            if processed > cap {
                stats.unconverged += 1;
                self.touched.iter_mut().for_each(|f| *f = true);
                t_detect += clock.elapsed();
                break;
            }
            paths.advance(event.i, t);
            if let Some(j) = partner {
                paths.advance(j, t);
            }
            let contact = self.contact_at(paths, &event);
            t_detect += clock.elapsed();

            // Stage 3: the impulse of Newton's law at the impact.
            let clock = Instant::now();
            let impulse = contact.and_then(|c| {
                let material = self.materials().pair(&c);
                restitution_impulse(&c, paths.v_ref(), inv_mass, material, threshold)
            });
            t_respond += clock.elapsed();

            // Stage 4: onto both particles.
            let clock = Instant::now();
            if let Some(imp) = impulse {
                any = true;
                stats.impacts += 1;
                stats.impulses += 1;
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
                for q in std::iter::once(event.i).chain(partner) {
                    paths.changed(q);
                    self.touched[q] = true;
                    self.fastest_hit = self.fastest_hit.max(vec3::norm(vec3::get(paths.v_ref(), q)));
                }
            }
            t_distribute += clock.elapsed();

            // Stage 2 again: the two particles' next impacts, on the list if it still holds.
            let clock = Instant::now();
            let built = &self.list.built_at;
            let farthest = std::iter::once(event.i)
                .chain(partner)
                .map(|q| swept_reach(paths, q, t, h, vec3::get(built, q), &self.domain))
                .fold(0.0, f64::max);
            if farthest + reach >= self.list.allowance {
                // a new path could reach beyond the list: rebuild it at t, predict everything again
                reach = self.rebuild_at(paths, t, radius, h)?;
                self.rebuilt = true;
                self.schedule_all(paths, radius, &active, t, h, threshold);
            } else {
                reach = reach.max(farthest);
                let scene = scene!(self, radius, &active, threshold);
                for q in std::iter::once(event.i).chain(partner) {
                    if impulse.is_some() || q == event.i {
                        let next = scene.earliest(paths, q, t, h);
                        self.touched[q] |= next.touching;
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
    fn schedule_all(&mut self, paths: &Paths<'_>, radius: &[f64], active: &[[bool; 6]], now: f64, h: f64, threshold: f64) {
        let n = radius.len();
        let scene = scene!(self, radius, active, threshold);
        let (mut events, touching) = scene.all_impacts(paths, now, h);
        for q in touching {
            self.touched[q] = true;
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

    /// The first impacts of the particles woken for this step only (the others are quiet:
    /// their lines meet nothing in it, `collide/wake.rs`), into the emptied queue.
    fn schedule_woken(&mut self, paths: &Paths<'_>, radius: &[f64], active: &[[bool; 6]], h: f64, threshold: f64) {
        self.queue.reset(radius.len());
        let scene = scene!(self, radius, active, threshold);
        for &q in &self.woken {
            let next = scene.earliest(paths, q, 0.0, h);
            self.touched[q] |= next.touching;
            self.queue.schedule(q, next.event);
        }
    }

    /// The wake times at time `end` (world clock, s) of a force-free world in state x1, v1
    /// (`collide/wake.rs`). `incremental` (at the end of a step that looked only at the woken
    /// particles): the times of the rest still hold, and only the particles this step looked
    /// at or changed get new ones (the bound grows by the step); otherwise all are computed
    /// again, with the bound measured. Leaves `wake.valid` set if the list holds.
    fn wake_up(&mut self, x1: &[f64], v1: &[f64], radius: &[f64], end: f64, h: f64, incremental: bool) {
        let n = radius.len();
        let domain = self.domain;
        if incremental {
            // The touched particles (all of them have books) moved at most at the fastest
            // speed of the step, plus what the end-of-step solve moved them by.
            let (mut moved, mut fastest_after) = (0.0_f64, 0.0_f64);
            for &(q, x, _) in &self.books {
                moved = moved.max(vec3::norm(domain.displacement(vec3::get(x1, q), x)));
                fastest_after = fastest_after.max(vec3::norm(vec3::get(v1, q)));
            }
            let fastest = self.wake.vmax.max(self.fastest_hit);
            self.wake.reach += h * fastest + moved;
            self.wake.vmax = fastest.max(fastest_after);
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
            self.wake.reach = reach;
            self.wake.vmax = vmax;
        }
        if !(2.0 * self.wake.reach < self.list.allowance) {
            return; // the list expires now: the next step rebuilds it and looks at everyone
        }
        // Meetings up to the list's expiry, and a step beyond it.
        let horizon = self.wake.horizon(self.list.allowance) + h;
        let active = self.active_walls();
        let scene = scene!(self, radius, &active, 0.0);
        let at = |q: usize| scene.first_meeting(x1, v1, q, horizon).map(|tau| end + tau);
        if incremental {
            let mut involved: Vec<usize> = self.books.iter().map(|b| b.0).chain(self.woken.iter().copied()).collect();
            involved.sort_unstable();
            involved.dedup();
            let times: Vec<(usize, Option<f64>)> = involved.into_iter().map(|q| (q, at(q))).collect();
            for (q, time) in times {
                self.wake.table.set(q, time);
            }
        } else {
            let times: Vec<(usize, f64)> = (0..n)
                .into_par_iter()
                .with_min_len(CHUNK)
                .filter_map(|q| at(q).map(|t| (q, t)))
                .collect();
            self.wake.table.fill(n, times.into_iter());
        }
        self.wake.valid = true;
    }

    /// Rebuilds the list at the particles' positions at time t (their references moved there)
    /// for the rest of the step; returns the largest swept displacement from there, m.
    fn rebuild_at(&mut self, paths: &mut Paths<'_>, t: f64, radius: &[f64], h: f64) -> Result<f64, Error> {
        let n = radius.len();
        let mut x = vec![0.0; 3 * n];
        let mut largest: f64 = 0.0;
        for q in 0..n {
            paths.advance(q, t);
            x[3 * q..3 * q + 3].copy_from_slice(&paths.x_ref(q));
            largest = largest.max(swept_reach(paths, q, t, h, vec3::get(&x, q), &self.domain));
        }
        let mean_radius = radius.iter().sum::<f64>() / n.max(1) as f64;
        let skin = (SKIN_PER_RADIUS * mean_radius).max(4.0 * largest);
        let scale = self.colliders.iter().map(collider_scale).fold(0.0, f64::max);
        self.list.built_at.clear();
        self.list
            .update(&mut self.grid, &x, radius, &self.colliders, &self.domain, skin, scale)?;
        self.list.verified = None;
        self.drop_inactive_walls();
        Ok(largest)
    }

    /// The contact of an event at its time (the particles already moved there).
    fn contact_at(&self, paths: &Paths<'_>, e: &Event) -> Option<Contact> {
        let xi = paths.x_ref(e.i);
        let unit = |d: [f64; 3]| {
            let len = vec3::norm(d);
            (len > 0.0).then(|| vec3::scale(1.0 / len, d))
        };
        let normal = match e.partner {
            Partner::Particle(j) => unit(self.domain.displacement(xi, paths.x_ref(j)))?,
            Partner::Collider(k) => match &self.colliders[k] {
                Collider::Plane(p) => p.normal(),
                Collider::Box(b) => b.walls()[e.wall].normal(),
                Collider::Sphere(s) => unit(vec3::sub(xi, s.center()))?,
            },
        };
        Some(Contact {
            i: e.i,
            other: e.partner,
            normal,
            overlap: 0.0,
            u_n: 0.0,
        })
    }

    /// The contacts at the end of the step (pairs within [`CONTACT_GAP`] of touching, and
    /// with colliders) of the touched particles, and of every particle they reach through
    /// such contacts: a pile is one contact network, and the solver must see all of it (a
    /// ball the solver stops changes the approach of the one resting on it). Breadth first
    /// from the touched particles; a particle reached for the first time is touched, and its
    /// integrated state goes to the energy books. Each pair once, lower index first; sorted
    /// by (i, partner), then each touched particle's collider contacts.
    fn end_contacts(&mut self, x1: &[f64], v1: &[f64], radius: &[f64]) {
        self.contacts.clear();
        let n = radius.len();
        let mut work: Vec<usize> = (0..n).filter(|&i| self.touched[i]).collect();
        let mut done = vec![false; n];
        let mut next = 0;
        while next < work.len() {
            let i = work[next];
            next += 1;
            for &j in self.list.rows[i / CHUNK].of(i % CHUNK) {
                let j = j as usize;
                if done[j] {
                    continue; // the pair was seen from j's side
                }
                let (lo, hi) = (i.min(j), i.max(j));
                let gap = CONTACT_GAP * (radius[lo] + radius[hi]);
                if let Some(c) = pair_contact(lo, hi, x1, v1, radius, &self.domain, gap) {
                    self.contacts.push(c);
                    if !self.touched[j] {
                        self.touched[j] = true;
                        self.books.push((j, vec3::get(x1, j), vec3::get(v1, j)));
                        work.push(j);
                    }
                }
            }
            done[i] = true;
        }
        self.contacts.sort_by_key(|c| (c.i, c.other));
        let list = &self.list;
        for i in (0..n).filter(|&i| self.touched[i]) {
            let (p, vi) = (vec3::get(x1, i), vec3::get(v1, i));
            let first = list.walls.partition_point(|w| w.0 < i);
            for &(_, k) in list.walls[first..].iter().take_while(|w| w.0 == i) {
                self.colliders[k].for_each_touch(p, radius[i], CONTACT_GAP * radius[i], |t| {
                    let c = Contact {
                        i,
                        other: Partner::Collider(k),
                        normal: t.normal,
                        overlap: t.overlap,
                        u_n: vec3::dot(vi, t.normal),
                    };
                    if !on_periodic_wall(&c, &self.colliders, &self.domain) {
                        self.contacts.push(c);
                    }
                });
            }
        }
    }

    /// The end-of-step contacts' solve, island by island on all threads (`collide/islands.rs`):
    /// the velocity solver's total impulse of each contact into `totals` (applied by the
    /// caller; `v1` is not changed), then the overlap removed from the positions `x1`. A
    /// contact approaching faster than the threshold is an impact with target u_n⁺ = −e u_n⁻
    /// (Newton's law); slower, a resting contact with target 0. Warm-started from the last
    /// step's totals of the same contacts.
    fn solve(&mut self, v1: &[f64], x1: &mut [f64], inv_mass: &[f64], threshold: f64) -> Result<IslandStats, Error> {
        let table = MaterialTable::uniform(self.material).with_colliders(&self.colliders);
        let materials = match &self.particle_materials {
            Some(m) => table.with_particles(m),
            None => table,
        };
        self.targets.clear();
        self.targets.extend(self.contacts.iter().map(|c| {
            if -c.u_n >= threshold && c.u_n < 0.0 {
                -materials.pair(c).restitution() * c.u_n
            } else {
                0.0
            }
        }));
        let warm = &self.warm;
        self.totals.clear();
        self.totals.extend(self.contacts.iter().map(|c| {
            warm.binary_search_by(|w| (w.0, w.1).cmp(&(c.i, c.other)))
                .map_or([0.0; 3], |k| warm[k].2)
        }));
        if self.contacts.is_empty() {
            self.warm.clear();
            self.resting.clear();
            let mut done = IslandStats::default();
            done.hold.converged = true;
            return Ok(done);
        }
        let problem = EndProblem {
            contacts: &self.contacts,
            targets: &self.targets,
            inv_mass,
            materials,
            hold: HoldParams {
                tolerance: ResolveParams::default().tolerance,
                max_iterations: END_SWEEPS,
            },
            separate: SeparateParams {
                iterations: SEPARATE_SWEEPS,
                ..SeparateParams::default()
            },
        };
        let islands = Islands::find(&self.contacts, inv_mass);
        let stats = islands::solve(&islands, &problem, &mut self.totals, v1, x1)?;
        self.warm.clear();
        self.warm
            .extend(self.contacts.iter().zip(&self.totals).map(|(c, p)| (c.i, c.other, *p)));
        self.warm.sort_by_key(|w| (w.0, w.1));
        self.resting.clear();
        self.resting.extend(self.warm.iter().map(|w| (w.0, w.1, w.2 != [0.0; 3])));
        Ok(stats)
    }

    /// The mechanical energy the end-of-step solve and the position correction took, J: over
    /// the particles in contact, the kinetic energy before them minus after, minus the work
    /// the step's forces (the constant accelerations of the paths) do along the positions
    /// the correction moved: Σ ½ m (|v_b|² − |v|²) + Σ m a·(x − x_b). For a resting contact
    /// held by the solver, whose sinking the correction undoes, it is 0: what the impulse
    /// took from the speed the force gave, the correction gave back as height. (An impact
    /// inside the step books its own ½ (1 − e²) μ u_n², exactly 0 for e = 1.)
    fn energy_books(&self, accel: &[f64], x1: &[f64], v1: &[f64], mass: &[f64], inv_mass: &[f64]) -> f64 {
        let mut lost = 0.0;
        for &(q, xb, vb) in &self.books {
            if inv_mass[q] == 0.0 {
                continue;
            }
            let (x, v, a) = (vec3::get(x1, q), vec3::get(v1, q), vec3::get(accel, q));
            let dx = self.domain.displacement(x, xb);
            lost += 0.5 * mass[q] * (vec3::dot(vb, vb) - vec3::dot(v, v)) + mass[q] * vec3::dot(a, dx);
        }
        lost
    }
}

/// Stage 4 for one impulse: J on particle i (+w_i J to its velocity) and −J on its partner
/// particle (−w_j J), in `v`; adds to `balance` what the two movable sides received, m Δv
/// (Σ over both: zero by action and reaction, to rounding). An impulse from a collider or a
/// pinned particle comes from outside the movable particles and is not part of the balance.
fn distribute(
    i: usize,
    j: Option<usize>,
    impulse: [f64; 3],
    v: &mut [f64],
    inv_mass: &[f64],
    mass: &[f64],
    balance: &mut [f64; 3],
) {
    let (wi, wj) = (inv_mass[i], j.map_or(0.0, |j| inv_mass[j]));
    for k in 0..3 {
        v[3 * i + k] += wi * impulse[k];
    }
    if let Some(j) = j {
        for k in 0..3 {
            v[3 * j + k] -= wj * impulse[k];
        }
        if wi > 0.0 && wj > 0.0 {
            for k in 0..3 {
                balance[k] += mass[i] * (wi * impulse[k]) - mass[j] * (wj * impulse[k]);
            }
        }
    }
}

/// Combines (largest, second largest, largest velocity change, NaN met) of two parts.
fn top_two(a: (f64, f64, f64, bool), b: (f64, f64, f64, bool)) -> (f64, f64, f64, bool) {
    (a.0.max(b.0), a.0.min(b.0).max(a.1).max(b.1), a.2.max(b.2), a.3 || b.3)
}
