//! The spring–dashpot contact model as a force of stage 1: contacts found at every force
//! evaluation push overlapping bodies apart with F_n = k_n δ − m_eff γ_n u_n.
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
//! The parts: this file holds the force's data, its constructor and the neighbour list's
//! upkeep; `contacts.rs` finds the contacts (listed pairs that overlap, collider touches),
//! `pairs.rs` the pair pass and its exchange between chunks, `law.rs` the force law, the
//! summed forces and energy and the damping ratios, `verlet.rs` the fused Verlet
//! force-and-kick pass, `force.rs` the [`Force`](crate::forces::Force) impl and the rates.

use std::sync::{Mutex, MutexGuard};

pub(crate) use crate::collide::neighbour_list::CHUNK;
use crate::collide::neighbour_list::{collider_scale, ListBuild, NeighbourList, SKIN_PER_RADIUS};
use crate::collide::{Collider, Domain, Grid, Material};
use crate::error::Error;
use crate::forces::State;
use law::DampingRatios;
use pairs::{ChunkSums, Exchange};
pub(crate) use verlet::VerletKick;

mod contacts;
mod force;
mod law;
mod pairs;
mod verlet;

/// Penalty contacts between particles and with colliders (the DEM way).
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
/// exactly the requested e ([`crate::collide::penalty`]); e is the pair's material (global,
/// per particle, per collider, combined as in the impulse model). The spring part is
/// conservative, with U = Σ ½ k_n δ² over overlapping contacts; the dashpot only removes
/// energy. No friction: tangential forces belong to the impulse model.
pub(crate) struct ContactForce {
    stiffness: f64,
    damping: Option<f64>,
    global: Material,
    own: Option<Vec<Material>>,
    /// ζ of the pair materials, worked out once.
    ratios: DampingRatios,
    radius: Vec<f64>,
    inv_mass: Vec<f64>,
    colliders: Vec<Collider>,
    domain: Domain,
    /// The neighbour list's skin, m.
    skin: f64,
    /// The largest |coordinate| of the colliders' points, centres and radii, m (for the
    /// neighbour list's rounding margin).
    collider_scale: f64,
    /// Buffers kept between evaluations (a mutex, not a `RefCell`: the passes share `&self`
    /// across threads).
    scratch: Mutex<Scratch>,
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
        }
    }
}

/// What a [`ContactForce`] is made of: the law's constants, the pair materials, the
/// particles' radii and inverse masses, the colliders and the domain.
pub(crate) struct ContactForceParams {
    /// k_n, N/m.
    pub stiffness: f64,
    /// γ_n, 1/s (`None`: the damping follows from the restitution e).
    pub damping: Option<f64>,
    /// The material of every pair without its own.
    pub global: Material,
    /// Each particle's own material, if particles have their own.
    pub own: Option<Vec<Material>>,
    /// Radii, m.
    pub radius: Vec<f64>,
    /// Inverse masses, 1/kg (0: pinned).
    pub inv_mass: Vec<f64>,
    pub colliders: Vec<Collider>,
    /// 2D/3D, periodic axes.
    pub domain: Domain,
}

impl ContactForce {
    /// The colliders where they are now (a moving collider's placement at a step), the same
    /// colliders as built.
    pub(crate) fn place_colliders(&mut self, colliders: &[Collider]) {
        self.colliders.clone_from_slice(colliders);
        self.collider_scale = self
            .collider_scale
            .max(colliders.iter().map(collider_scale).fold(0.0, f64::max));
    }

    /// The force for particles of radii `radius` (m) and inverse masses `inv_mass` (1/kg),
    /// with stiffness k_n (N/m) and optional damping rate γ_n (1/s), the pair materials from
    /// `global` and `own`, the colliders and the domain (2D/3D, periodic axes).
    pub fn from_params(params: ContactForceParams) -> Self {
        let ContactForceParams {
            stiffness,
            damping,
            global,
            own,
            radius,
            inv_mass,
            colliders,
            domain,
        } = params;
        let mean_radius = if radius.is_empty() {
            0.0
        } else {
            radius.iter().sum::<f64>() / radius.len() as f64
        };
        ContactForce {
            stiffness,
            damping,
            ratios: DampingRatios::new(global, own.as_deref(), &colliders),
            global,
            own,
            skin: SKIN_PER_RADIUS * mean_radius,
            collider_scale: colliders.iter().map(collider_scale).fold(0.0, f64::max),
            radius,
            inv_mass,
            colliders,
            domain,
            scratch: Mutex::new(Scratch::default()),
        }
    }

    /// The same force with a neighbour-list skin of `skin` m (≥ 0, finite; 0 searches the
    /// grid at every evaluation).
    #[cfg(test)]
    fn with_skin(mut self, skin: f64) -> Self {
        self.skin = skin;
        self
    }

    /// Whether the neighbour list must be rebuilt before an evaluation at positions `x` (m,
    /// 3 per particle): there is none, or the particles have moved too far since its build.
    ///
    /// The world asks this right before the force evaluation at the same `x`; a yes is
    /// remembered for that buffer, so the evaluation does not check a second time.
    pub fn list_expired(&self, x: &[f64]) -> bool {
        let list = &mut self.scratch().list;
        let holds = list.holds(x, &self.domain);
        list.verified = holds.then_some((x.as_ptr() as usize, x.len()));
        !holds
    }

    /// Forgets what [`ContactForce::list_expired`] found (the world calls this at the end of
    /// each step, so that a buffer reused later is checked again).
    pub fn forget_verified(&self) {
        self.scratch().list.verified = None;
    }

    /// Takes this force's neighbour list (for the force that replaces it after a removal,
    /// [`ContactForce::keep_list`]); this force is left without one.
    pub fn take_list(&mut self) -> NeighbourList {
        std::mem::take(&mut self.scratch().list)
    }

    /// Gives this force the list of the force it replaces, after particles were removed
    /// (`new_of_old` as [`NeighbourList::retain_survivors`] takes it): the survivors' pairs
    /// stay listed, so the next evaluation need not search the grid again.
    pub fn keep_list(&mut self, mut list: NeighbourList, new_of_old: &[u32]) {
        list.retain_survivors(new_of_old);
        if list.half {
            self.scratch().list = list;
        }
    }

    /// Gives this force the list of the force it replaces, after particles `start..` were
    /// born ([`NeighbourList::admit`]: the newborns' pairs are added, the others stay);
    /// false when the list could not be kept (the next evaluation builds one).
    pub fn keep_list_with_newborns(&mut self, mut list: NeighbourList, x: &[f64], start: usize) -> bool {
        if !list.half || !list.admit(x, &self.radius, &self.colliders, &self.domain, start) {
            return false;
        }
        self.scratch().list = list;
        true
    }

    /// Forgets the pair energy the last fused pass kept (the world calls this after the
    /// runaway check, so that a buffer reused later is summed again).
    pub fn forget_energy(&self) {
        self.scratch().pair_energy = None;
    }

    /// The width of the cells the neighbour list searches, 2 r_max + skin, m.
    pub fn reach(&self) -> f64 {
        2.0 * self.radius.iter().fold(0.0, |m: f64, r| m.max(*r)) + self.skin
    }

    /// The domain (2D/3D, periodic axes).
    pub fn domain(&self) -> &Domain {
        &self.domain
    }

    /// The buffers (a panic in another evaluation leaves them usable: each build starts over).
    fn scratch(&self) -> MutexGuard<'_, Scratch> {
        self.scratch.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// How many times the neighbour list was built so far.
    #[cfg(test)]
    fn list_builds(&self) -> usize {
        self.scratch().list.builds
    }

    /// Checks the state's lengths and makes the neighbour list hold at its positions.
    fn update_list(&self, s: &State, scratch: &mut Scratch) -> Result<(), Error> {
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
        let build = ListBuild {
            skin: self.skin,
            collider_scale: self.collider_scale,
        };
        list.update(grid, s.x, &self.radius, &self.colliders, &self.domain, build)
    }
}

#[cfg(test)]
#[path = "../tests/contact_force.rs"]
mod tests;
