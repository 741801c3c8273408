//! The contact force models (spring–dashpot and Hertz): contacts found at every force
//! evaluation push overlapping bodies apart with F_n = k_n δ − m_eff γ_n u_n (Hertz: a
//! stiffness that grows with the overlap), a force of stage 1.
//!
//! The collide stage owns the model ([`ContactForceModel`]: the law's constants and the buffers
//! kept between evaluations, the neighbour list above all) beside the impulse model; each call
//! sees the particles' radii and inverse masses, the materials, the colliders and the domain
//! where they live, through a [`ContactForce`] made for it
//! ([`CollideStage::contact_force`](crate::collide::stage::CollideStage::contact_force)).
//! Nothing is copied, so nothing is kept fresh: a birth, a death, a new collider or material is
//! seen by the next call as it is.
//!
//! The contacts come from a Verlet neighbour list ([`NeighbourList`]): the grid's candidate
//! pairs within r_i + r_j + skin (and the particles within the skin of a collider), kept until
//! the particles have moved far enough that something left out could touch. Every evaluation
//! tests what is listed exactly, so the contacts, and the forces, are those of a search at
//! every evaluation, bit for bit.
//!
//! The list is a half one (each pair listed once, in the row of its lower index) kept in
//! chunks of [`CHUNK`] particles, so that the build and the force pass run on all threads
//! with rayon. Each pair's force is computed once and given to both sides; what a chunk owes
//! particles of later chunks is exchanged in a second stage in a fixed order (`pairs.rs`), so
//! every particle's force is summed in the same order on any number of threads.
//!
//! The parts: this file holds the model, the view of a call and the neighbour list's upkeep;
//! `contacts.rs` finds the contacts (listed pairs that overlap, collider touches),
//! `pairs.rs` the pair pass, `exchange.rs` its exchange between chunks, `spring_dashpot.rs`
//! the linear law's damping for a restitution (its closed form), `law.rs` the force law,
//! the summed forces and energy and the damping ratios, `verlet.rs` the fused Verlet
//! force-and-kick pass, `force.rs` the [`Force`](crate::forces::Force) impl and the rates.

use std::sync::{Mutex, MutexGuard};

use crate::collide::books::ColliderBooks;
use crate::collide::groups::Filter;
pub(crate) use crate::collide::neighbour_list::CHUNK;
use crate::collide::neighbour_list::{collider_scale, ListBuild, NeighbourList, SKIN_PER_RADIUS};
use crate::collide::{Collider, Domain, Grid, Material};
use crate::error::Error;
use crate::forces::State;
pub use cohesion::Cohesion;
use cohesion::Jkr;
pub(crate) use damping::DampingLaw;
use exchange::Exchange;
use history::Histories;
pub(crate) use history::{PairSlip, Slip, WallSlip};
pub(crate) use law::particle_ratios;
use law::DampingRatios;
pub(crate) use normal::NormalLaw;
use pairs::{ChunkSums, Turning, TurningOut};
pub use rolling::RollingLaw;
pub use tangent::{TangentialLaw, TangentialModel};
pub use twisting::TwistingLaw;
pub(crate) use verlet::{SpinKick, VerletKick};

mod affinity;
mod cohesion;
mod contacts;
mod damping;
mod exchange;
mod force;
mod history;
mod law;
mod listing;
mod normal;
mod overlapping;
mod pairs;
mod rolling;
pub mod spring_dashpot;
mod springs;
mod stress;
pub mod sub_models;
mod tangent;
mod twisting;
mod verlet;

/// The contact force model (spring–dashpot, Hertz, DMT, JKR) between calls: its laws, the
/// sub-models LAMMPS GRANULAR composes a contact of (the table: `sub_models.rs`), and the
/// buffers one evaluation leaves the next (the neighbour list, the grid, the exchange between
/// chunks).
pub(crate) struct ContactForceModel {
    /// The normal law (`normal.rs`: Hooke's, Hertz's, with DMT's or JKR's adhesion).
    pub normal: NormalLaw,
    /// The normal dashpot (`damping.rs`: from each pair's restitution e, or a given rate).
    pub damping: DampingLaw,
    /// The tangential part with memory, when contacts have friction: the tangential law
    /// (`tangent.rs`) with rolling and twisting resistance (`rolling.rs`, `twisting.rs`).
    pub tangential: Option<TangentialModel>,
    /// A fixed skin, m (tests); `None`: [`SKIN_PER_RADIUS`] times the mean radius, at each
    /// build of the list.
    skin: Option<f64>,
    /// Buffers kept between evaluations (a mutex, not a `RefCell`: the passes share `&self`
    /// across threads).
    scratch: Mutex<Scratch>,
}

impl ContactForceModel {
    /// The model with stiffness k_n (N/m) and damping rate γ_n (1/s; `None`: from e).
    pub fn new(stiffness: f64, damping: Option<f64>) -> Self {
        Self::of(NormalLaw::Hooke { stiffness }, DampingLaw::of(damping))
    }

    /// The model of normal law `normal` and damping law `damping`, without a tangential part.
    pub fn of(normal: NormalLaw, damping: DampingLaw) -> Self {
        ContactForceModel {
            normal,
            damping,
            tangential: None,
            skin: None,
            scratch: Mutex::new(Scratch::default()),
        }
    }

    /// The buffers (a panic in another evaluation leaves them usable: each build starts over).
    fn scratch(&self) -> MutexGuard<'_, Scratch> {
        self.scratch.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Forgets the neighbour list (colliders, the domain or the particles' radii changed):
    /// the next evaluation builds one.
    pub fn forget_list(&self) {
        let mut scratch = self.scratch();
        scratch.list.built_at.clear();
        scratch.list.verified = None;
        scratch.wall_forces = None;
    }

    /// Follows a renumbering of the particles (`new_of_old`, `old_of_new`): the list stays
    /// the same list in the new numbering.
    pub fn renumber(&self, new_of_old: &[u32], old_of_new: &[u32]) {
        let mut scratch = self.scratch();
        scratch.list.renumber(new_of_old, old_of_new);
        scratch.histories.renumber(new_of_old);
    }

    /// Follows a sort made because the list has expired ([`ContactForceModel::list_expired`]:
    /// the next evaluation builds it anew from the positions alone): the contacts' memory
    /// follows the particles, the list is only dropped (its rows' room kept for the build).
    /// Renumbering it was work thrown away at once: a new copy of its rows and of its build
    /// positions at every sort.
    pub fn renumber_expired(&self, new_of_old: &[u32]) {
        let mut scratch = self.scratch();
        scratch.list.expire();
        scratch.histories.renumber(new_of_old);
    }

    /// Follows a removal of particles (`new_of_old` as [`NeighbourList::retain_survivors`]
    /// takes it): the survivors' pairs stay listed, so the next evaluation need not search
    /// the grid again.
    pub fn retain_survivors(&self, new_of_old: &[u32]) {
        let mut scratch = self.scratch();
        scratch.list.retain_survivors(new_of_old);
        scratch.histories.renumber(new_of_old);
    }

    /// The collider forces of the last fused Verlet pass, as rates (what the next step's
    /// collider books start from: `verlet.rs`), for a checkpoint; `None` when none is kept.
    pub fn wall_carry(&self) -> Option<Vec<ColliderBooks>> {
        self.scratch().wall_forces.clone()
    }

    /// Sets what [`ContactForceModel::wall_carry`] gave (a checkpoint's, or the same world's
    /// across a restart of its caches).
    pub fn set_wall_carry(&self, carry: Option<Vec<ColliderBooks>>) {
        self.scratch().wall_forces = carry;
    }

    /// Forgets the contacts' memory (the tangential model changed).
    pub fn forget_history(&self) {
        self.scratch().histories.clear();
    }

    /// The memory the last Verlet pass made becomes the contacts' own (its step was
    /// accepted; `history.rs`).
    pub fn accept_history(&self) {
        self.scratch().histories.accept();
    }

    /// The contacts' memory: touching pairs (i, j, springs) and collider touches (i, k,
    /// normal, springs), in the engine's numbering.
    pub fn history(&self) -> (Vec<PairSlip>, Vec<WallSlip>) {
        let scratch = self.scratch();
        (scratch.histories.pairs.clone(), scratch.histories.walls.clone())
    }

    /// Sets the contacts' memory (a checkpoint's), sorted here; pairs with i ≥ j are
    /// turned round.
    pub fn set_history(&self, pairs: Vec<PairSlip>, walls: Vec<WallSlip>) {
        let mut scratch = self.scratch();
        let h = &mut scratch.histories;
        h.clear();
        h.pairs = pairs;
        h.walls = walls;
        let n = h
            .pairs
            .iter()
            .map(|p| p.i.max(p.j) as usize + 1)
            .chain(h.walls.iter().map(|w| w.i as usize + 1))
            .max()
            .unwrap_or(0);
        let identity: Vec<u32> = (0..n as u32).collect();
        h.renumber(&identity);
    }

    /// Whether the neighbour list must be rebuilt before an evaluation at positions `x` (m,
    /// 3 per particle) in `domain`: there is none, or the particles have moved too far since
    /// its build.
    ///
    /// The world asks this right before the force evaluation at the same `x`; a list that
    /// holds is remembered for that buffer, so the evaluation does not check a second time.
    pub fn list_expired(&self, x: &[f64], domain: &Domain) -> bool {
        let list = &mut self.scratch().list;
        let holds = list.holds(x, domain);
        list.verified = holds.then_some((x.as_ptr() as usize, x.len()));
        !holds
    }

    /// Forgets what [`ContactForceModel::list_expired`] found (the world calls this at the end of
    /// each step, so that a buffer reused later is checked again).
    pub fn forget_verified(&self) {
        self.scratch().list.verified = None;
    }

    /// The contact books of the last fused Verlet pass and what each collider took over its
    /// step, once (`None`: no such pass since).
    pub(crate) fn take_books(&self) -> Option<(pairs::ContactBooks, Vec<ColliderBooks>)> {
        self.scratch().books.take()
    }

    /// Forgets the pair energy the last fused pass kept (the world calls this after the
    /// runaway check, so that a buffer reused later is summed again).
    pub fn forget_energy(&self) {
        self.scratch().pair_energy = None;
    }

    /// How many times the neighbour list was built so far.
    #[cfg(test)]
    fn list_builds(&self) -> usize {
        self.scratch().list.builds
    }
}
/// The contact forces (spring–dashpot or Hertz) between particles and with colliders (the DEM
/// way), as one call sees them.
/// Penalty contacts between particles and with colliders (the DEM way), as one call sees them.
///
/// While particle i overlaps its partner by δ > 0, the pair feels F_n n on i and −F_n n on a
/// partner particle (a collider takes the reaction), N, with
///
/// ```text
///   F_n = k_n δ − c_n u_n,      c_n = 2 ζ √(k_n m_eff)   (ζ from e, closed form)
///                               c_n = m_eff γ_n           (γ_n given)
/// ```
///
/// m_eff = 1/(w_i + w_j) the reduced mass and u_n the normal relative velocity. The damping
/// ratio ζ = −ln e / √(π² + ln² e) makes the contact's damped half-oscillation bounce back with
/// exactly the requested e ([`spring_dashpot`]); e is the pair's material (global, per
/// particle, per collider, combined as in the impulse model). The spring part is
/// conservative, with U = Σ ½ k_n δ² over overlapping contacts; the dashpot only removes
/// energy. No friction: tangential forces belong to the impulse model.
///
/// With Hertz's law (`ContactModel::Hertz`, LAMMPS's `hertz/material` with `damping
/// coeff_restitution`) the stiffness grows with the contact's area: k_n = 4/3 E* a, a =
/// √(R* δ), R* = r_i r_j / (r_i + r_j) (r_i against a collider), so that F_n = 4/3 E* √R*
/// δ^(3/2) − c_n u_n with the same c_n = 2 ζ √(k_n m_eff) at the current k_n, and
/// U = Σ 2/5 k_n δ² (`law.rs`); with DMT adhesion, less the pull-off 4π γ R* while they
/// overlap.
///
/// Everything here is borrowed for the call: the model's constants and buffers, the
/// particles' radii and inverse masses, the materials, the colliders and the domain.
pub(crate) struct ContactForce<'a> {
    model: &'a ContactForceModel,
    /// The normal law (`normal.rs`).
    normal: NormalLaw,
    damping: DampingLaw,
    /// How far past touching a contact can hold (JKR's largest pull-off distance of a pair),
    /// m; 0 with the other laws.
    reach_past_touching: f64,
    global: Material,
    own: Option<&'a [Material]>,
    /// ζ of the pair materials.
    ratios: DampingRatios<'a>,
    radius: &'a [f64],
    inv_mass: &'a [f64],
    colliders: &'a [Collider],
    /// (a copy: the hot loops read it without a pointer to follow)
    domain: Domain,
    /// The tangential part (`tangent.rs`), when some contact has friction.
    tangential: Option<TangentialModel>,
    /// The angular velocities, rad/s (3 per particle; empty without spin).
    omega: &'a [f64],
    /// The collision groups' filter, applied where the neighbour list is built (`None`:
    /// every pair collides).
    filter: Option<Filter<'a>>,
}

/// What a [`ContactForce`] reads besides its model: the pair materials (with each
/// particle's (e, ζ) where particles have their own), the particles' radii and inverse
/// masses, the colliders and the domain.
pub(crate) struct Bodies<'a> {
    /// The material of every pair without its own.
    pub global: Material,
    /// Each particle's own material and its (e, ζ), if particles have their own.
    pub own: Option<(&'a [Material], &'a [(f64, f64)])>,
    /// Whether some particle's own material has friction (worked out with the materials,
    /// not at each call).
    pub own_friction: bool,
    /// Radii, m.
    pub radius: &'a [f64],
    /// Inverse masses, 1/kg (0: pinned).
    pub inv_mass: &'a [f64],
    pub colliders: &'a [Collider],
    /// 2D/3D, periodic axes.
    pub domain: &'a Domain,
    /// Angular velocities, rad/s (3 per particle; empty without spin).
    pub omega: &'a [f64],
    /// The collision groups' filter (`collide/groups.rs`; `None`: every pair collides).
    pub filter: Option<Filter<'a>>,
}

/// A pass's tangential part over the memory in `histories`, with the angular velocities
/// `omega` (rad/s), the step `step` (h in s, with the velocities and angular velocities at its
/// start; `None`: the springs are read, not stretched) and the torques into `torque` (N·m;
/// `None`: forces only). Without a tangential `model`, the memory alone when `remember`
/// (JKR's contacts, which hold past touching once made: `cohesion.rs`), else `None`.
fn turning<'s>(
    model: Option<TangentialModel>,
    remember: bool,
    omega: &'s [f64],
    histories: &'s mut Histories,
    torque_exchange: &'s mut Exchange,
    step: Option<(f64, &'s [f64], &'s [f64])>,
    torque: Option<&'s mut [f64]>,
) -> Option<(Turning<'s>, TurningOut<'s>)> {
    if model.is_none() && !remember {
        return None;
    }
    histories.pending |= step.is_some();
    let Histories {
        pairs,
        walls,
        pending_pairs,
        pending_walls,
        ..
    } = histories;
    Some((
        Turning {
            model,
            omega,
            pairs,
            walls,
            step: step.map(|s| s.0),
            start: step.map(|s| (s.1, s.2)),
        },
        TurningOut {
            torque: torque.map(|t| (t, torque_exchange)),
            memory: step.map(|_| (pending_pairs, pending_walls)),
        },
    ))
}

struct Scratch {
    grid: Grid,
    /// A half list (each pair once, in the row of its lower index).
    list: NeighbourList,
    /// What each chunk's pairs summed (its share of the contact energy, J), kept to allocate
    /// nothing per evaluation.
    sums: Vec<ChunkSums>,
    /// The forces chunks owe particles of later chunks (`pairs.rs`).
    exchange: Exchange,
    /// The pair energy Σ ½ k_n δ² (J) the fused Verlet pass summed on its way, with the
    /// positions' buffer (address, length) it was summed at: the runaway check asks for the
    /// energy at those positions right after, and takes it from here instead of a second
    /// pass (the same sum, in the same order). Taken once; the world forgets it after the
    /// check ([`ContactForce::forget_energy`]).
    pair_energy: Option<((usize, usize), f64)>,
    /// The contact books of the last fused Verlet pass, with what each collider took over
    /// its step, until the world takes them ([`ContactForceModel::take_books`]).
    books: Option<(pairs::ContactBooks, Vec<ColliderBooks>)>,
    /// The collider forces of the last fused Verlet pass, as rates (N, N·m, W in the books'
    /// fields): the start of the next step's ([`ColliderBooks`]; `None` after a change).
    wall_forces: Option<Vec<ColliderBooks>>,
    /// The contacts' memory (`history.rs`).
    histories: Histories,
    /// The torques chunks owe particles of later chunks (as `exchange` the forces).
    torque_exchange: Exchange,
    /// The torques of Verlet's pass, N·m (3 per particle).
    torque: Vec<f64>,
}

impl Default for Scratch {
    fn default() -> Self {
        Scratch {
            grid: Grid::default(),
            list: NeighbourList {
                half: true,
                ..NeighbourList::default()
            },
            sums: Vec::new(),
            exchange: Exchange::default(),
            pair_energy: None,
            books: None,
            wall_forces: None,
            histories: Histories::default(),
            torque_exchange: Exchange::default(),
            torque: Vec::new(),
        }
    }
}

impl<'a> ContactForce<'a> {
    /// The force of `model` on `bodies`, for one call.
    pub fn new(model: &'a ContactForceModel, bodies: Bodies<'a>) -> Self {
        ContactForce {
            model,
            normal: model.normal,
            damping: model.damping,
            // (R* is largest for a particle against a collider: R* = r_i)
            // (the largest radius only with JKR's law: no O(N) pass at each evaluation else)
            reach_past_touching: model
                .normal
                .reach_past_touching(|| bodies.radius.iter().fold(0.0_f64, |m, r| m.max(*r))),
            ratios: DampingRatios::new(bodies.global, bodies.own.map(|o| o.1), bodies.colliders),
            global: bodies.global,
            own: bodies.own.map(|o| o.0),
            radius: bodies.radius,
            inv_mass: bodies.inv_mass,
            colliders: bodies.colliders,
            domain: *bodies.domain,
            tangential: model
                .tangential
                .filter(|_| has_friction(bodies.global, bodies.own_friction, bodies.colliders)),
            omega: bodies.omega,
            filter: bodies.filter,
        }
    }

    /// Whether the contacts have a tangential part (`tangent.rs`): the model has one and some
    /// contact has friction.
    pub fn has_tangential(&self) -> bool {
        self.tangential.is_some()
    }

    /// Whether the contacts keep a memory from step to step, which only Verlet's one force
    /// evaluation per step stretches and renews: friction's springs (`tangent.rs`), JKR's
    /// touches (`cohesion.rs`).
    pub fn has_memory(&self) -> bool {
        self.tangential.is_some() || self.jkr().is_some()
    }

    /// JKR's contact with its reach past touching (the largest pull-off distance of a pair,
    /// m), the one law whose contacts hold apart.
    #[inline(always)]
    pub(super) fn jkr(&self) -> Option<(Jkr, f64)> {
        self.normal.jkr().map(|jkr| (jkr, self.reach_past_touching))
    }

    /// μ of contact `c` (`MaterialTable::pair`'s rule: √(μ_i μ_j) between particles, the
    /// collider's own where it sets one).
    #[inline]
    pub(super) fn friction_of(&self, c: &crate::collide::Contact) -> f64 {
        let own = |i: usize| self.own.map_or(self.global, |m| m[i]);
        match c.other {
            crate::collide::Partner::Particle(j) => Material::combine(own(c.i), own(j)).friction(),
            crate::collide::Partner::Collider(k) => self.colliders[k].surface().friction().unwrap_or(own(c.i).friction()),
        }
    }

    /// Adds the newborns, particles `start..` at positions `x` (m), to the neighbour list
    /// ([`NeighbourList::admit`]: their pairs are added, the others stay); false when the
    /// list could not be kept (the next evaluation builds one).
    pub fn admit_newborns(&self, x: &[f64], start: usize) -> bool {
        self.scratch()
            .list
            .admit(x, self.radius, self.colliders, &self.domain, self.filter, start)
    }

    /// The neighbour list's skin at a build now, m: the model's fixed one, or
    /// [`SKIN_PER_RADIUS`] times the mean radius.
    fn skin(&self) -> f64 {
        self.model.skin.unwrap_or_else(|| {
            let mean_radius = if self.radius.is_empty() {
                0.0
            } else {
                self.radius.iter().sum::<f64>() / self.radius.len() as f64
            };
            SKIN_PER_RADIUS * mean_radius
        })
    }

    /// The width of the cells the neighbour list searches, 2 r_max + skin, m.
    pub fn reach(&self) -> f64 {
        2.0 * self.radius.iter().fold(0.0, |m: f64, r| m.max(*r)) + self.skin() + self.reach_past_touching()
    }

    /// How far past touching a contact can hold, m: JKR's largest pull-off distance, else 0.
    fn reach_past_touching(&self) -> f64 {
        self.reach_past_touching
    }

    /// The domain (2D/3D, periodic axes).
    pub fn domain(&self) -> &Domain {
        &self.domain
    }

    /// The model's buffers.
    fn scratch(&self) -> MutexGuard<'a, Scratch> {
        self.model.scratch()
    }

    /// Checks the state's lengths and makes the neighbour list hold at its positions.
    fn update_list(&self, s: &State, scratch: &mut Scratch) -> Result<(), Error> {
        self.update_list_lending(s, scratch, || ())
    }

    /// [`ContactForce::update_list`], calling `before_build` where the list is about to be
    /// built (not where it holds): a caller with a buffer it writes before it reads next lets
    /// it go there, and the build's grid takes its place instead of adding to it.
    fn update_list_lending(&self, s: &State, scratch: &mut Scratch, before_build: impl FnOnce()) -> Result<(), Error> {
        let n = self.radius.len();
        for (name, len) in [("x", s.x.len()), ("v", s.v.len())] {
            if len != 3 * n {
                return Err(Error::invalid(
                    name,
                    format!("{len} values"),
                    format!("3 per particle ({} for the {n} radii)", 3 * n),
                ));
            }
        }
        let Scratch { grid, list, .. } = scratch;
        // (worked out at a build only: O(N) and O(colliders))
        // (JKR's contacts hold past touching: the list reaches that much further, and holds
        // while the particles have moved less than its skin beyond it)
        let reach = self.reach_past_touching();
        let build = || {
            before_build();
            ListBuild {
                skin: self.skin() + reach,
                reach,
                collider_scale: self.colliders.iter().map(collider_scale).fold(0.0, f64::max),
            }
        };
        let builds = list.builds;
        list.update(grid, s.x, self.radius, self.colliders, &self.domain, self.filter, build)?;
        if list.builds != builds {
            // the grid serves the builds alone, every few dozen steps: its buffers go back
            // meanwhile
            grid.release();
        }
        Ok(())
    }
}

/// Whether some contact can have friction: the global μ, a particle's own (`own`) or a
/// collider's.
fn has_friction(global: Material, own: bool, colliders: &[Collider]) -> bool {
    global.friction() > 0.0 || own || colliders.iter().any(|c| c.surface().friction().is_some_and(|f| f > 0.0))
}

#[cfg(test)]
#[path = "../tests/contact_force.rs"]
mod tests;
