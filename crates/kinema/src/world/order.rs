//! The particles' order in memory: sorted along a Morton curve while the world steps, the
//! user's order whenever anyone else looks.
//!
//! A force pass reads each particle's neighbours; if neighbours in space are far apart in
//! memory, each read is a cache miss, and as a granular gas mixes, the order the particles
//! were created in stops saying anything about where they are. So, as LAMMPS
//! (`atom_modify sort`) and HOOMD-blue (`SFCPackTuner`) do, the world re-sorts the particles
//! along a space-filling curve: whenever the spring–dashpot contact force's neighbour list must
//! be rebuilt, before the rebuild, by the Morton code of each particle's cell (cells as wide as
//! the list's reach, 2 r_max + skin), ties kept in the current order. Interleaving the bits
//! of the three cell coordinates makes the code of cells near in space mostly near in value,
//! so the particles of a cell and of its neighbours end up in a few nearby runs of memory.
//!
//! The permutation never shows outside the world, and it need not be undone per call. A
//! [`World`] itself is always in the user's order between calls: [`World::advance`] puts the
//! particles back before it returns (ids, positions, velocities, forces' indices). A caller
//! that steps in slices and would rather keep the engine's order between them (the Python
//! binding, between calls of `step` and the frames of `run`), as LAMMPS keeps its sorted
//! atoms with a tag → index map (`atom->map`), holds the world inside a [`UserOrder`]: the
//! one way to step without putting the particles back ([`UserOrder::advance_in_engine_order`])
//! and the one way to reach a world so stepped. It gives the world itself only in the
//! user's order ([`UserOrder::get`] puts the particles back first, as HOOMD-blue's snapshots
//! give its particles in tag order whatever its local order), and besides, without
//! restoring, only what cannot show the engine's order: per-particle values gathered into the
//! user's order through the two maps of [`Order`] ([`UserOrder::in_user_order`],
//! [`UserOrder::read_state_into`], [`UserOrder::state_is`]: gathers, not permutations of the
//! world), values that do not depend on it (the time, the collision books, the diagnostics'
//! sums over the engine's order), and the few writes that map through the order or put the
//! particles back themselves. So a method of the binding cannot forget to put them back: it
//! has no other way in. An error names the user's particle. The sort runs only where every
//! force can follow a renumbering (`Properties::renumbers`: a Python force cannot, and then the
//! world keeps the user's order, so that a callback sees it), with velocity Verlet and from
//! [`SORT_MIN_PARTICLES`] particles (below, everything fits in cache anyway); the particles'
//! own materials, where set, move with them (`CollideStage::permute_particles`). Sorting
//! changes only the order in which each particle's contact forces are summed, so the state
//! may differ from an unsorted run in the last bits; it depends on the positions alone, so it
//! is the same for any number of threads. Where the particles are put back matters to the
//! bits the same way (the steps after sum in the user's order until the next sort), which is
//! why [`UserOrder`] restores exactly where a caller asks for the world.

use std::borrow::Cow;
use std::sync::OnceLock;

use rayon::prelude::*;

use super::forces::contact_force;
use super::{Clock, ColliderBooks, CollisionParams, CollisionStats, KillVolume, LinearSolve, PairMemory, StageTimes};
use super::{WallMemory, World, WorldParams, WorldStepper, CHUNK};
use crate::collide::morton::morton_order_in;
use crate::collide::{GroupMasks, TouchEvent};
use crate::diagnostics::Diagnostics;
use crate::error::Error;
use crate::ode::stepper::Stats;
use crate::particles::Particles;
use crate::simd::prefetch;

/// The particles' order while the engine keeps its own: the two maps between it and the
/// user's, each the other's inverse.
pub(super) struct Order {
    /// `user_of[i]`: the user's index of the particle the engine holds at index i.
    user_of: Vec<u32>,
    /// `engine_of[u]`: where the engine holds the user's particle u; made at its first use
    /// after the sort (a world that nobody reads between its sorts, as a gas run for its
    /// figures, never makes it: 4 B a particle).
    engine_of: OnceLock<Vec<u32>>,
}

impl Order {
    fn new(user_of: Vec<u32>) -> Self {
        Order {
            user_of,
            engine_of: OnceLock::new(),
        }
    }

    /// `user_of[i]`: the user's index of the particle the engine holds at index i.
    pub(super) fn user_of(&self) -> &[u32] {
        &self.user_of
    }

    /// `engine_of[u]`: where the engine holds the user's particle u (`user_of`'s inverse).
    fn engine_of(&self) -> &[u32] {
        self.engine_of.get_or_init(|| inverse(&self.user_of))
    }

    /// `engine_of`, the order given up for it.
    fn into_engine_of(self) -> Vec<u32> {
        self.engine_of.into_inner().unwrap_or_else(|| inverse(&self.user_of))
    }
}

/// The inverse of a permutation: `out[p[i]] = i`.
fn inverse(p: &[u32]) -> Vec<u32> {
    let mut out = vec![0u32; p.len()];
    for (i, &u) in p.iter().enumerate() {
        out[u as usize] = i as u32;
    }
    out
}

/// The fewest particles the world sorts along space.
pub(crate) const SORT_MIN_PARTICLES: usize = 2 * super::CHUNK;

/// `out[i]` = `a[from[i]]`, `width` values per particle (`from`: each new place's old index,
/// as `engine_of` is for the user's order and `old_of_new` for a sort).
///
/// The reads are scattered (a sort's or the user's order against the engine's), so each asks
/// for the one [`GATHER_AHEAD`] places on to be brought into cache ([`prefetch`]): at 10⁶
/// particles nearly every read misses, and they then overlap instead of following one another.
fn gather_into<T: Copy + Send + Sync>(out: &mut [T], a: &[T], from: &[u32], width: usize) {
    out.par_chunks_mut(width * CHUNK)
        .zip(from.par_chunks(CHUNK))
        .for_each(|(oc, fc)| {
            for (k, (o, &i)) in oc.chunks_exact_mut(width).zip(fc).enumerate() {
                if let Some(&ahead) = fc.get(k + GATHER_AHEAD) {
                    prefetch(&a[width * ahead as usize]);
                }
                let i = width * i as usize;
                o.copy_from_slice(&a[i..i + width]);
            }
        });
}

/// How many places ahead [`gather_into`] asks for its reads.
const GATHER_AHEAD: usize = 16;

/// `a` (`width` values per particle) in the new order, gathered into `spare`'s room, which is
/// left holding `a`'s old room: every array of one type moves through the same two
/// allocations, instead of a new one for each (24 MB at 10⁶ particles).
fn gather_through<T: Copy + Default + Send + Sync>(a: &mut Vec<T>, spare: &mut Vec<T>, old_of_new: &[u32], width: usize) {
    if a.len() != width * old_of_new.len() {
        return; // not in use (an empty buffer)
    }
    spare.resize(a.len(), T::default()); // (every value is written below)
    gather_into(spare, a, old_of_new, width);
    std::mem::swap(a, spare);
}

/// `a` (one value per particle) in the new order, gathered into the front of `spare`'s room and
/// copied back: `a` keeps its room (a room of 3 per particle for 1 would waste 2), and the
/// sort makes no array for it (at 10⁶ particles a sort's transient arrays were the step's
/// peak).
fn gather_back<T: bytemuck::Pod + Send + Sync>(a: &mut [T], spare: &mut Vec<f64>, old_of_new: &[u32]) {
    if a.len() != old_of_new.len() {
        return; // not in use (an empty buffer)
    }
    let room = room_in::<T>(spare, a.len());
    gather_into(room, a, old_of_new, 1);
    a.copy_from_slice(room);
}

/// The front of `spare`'s room as `n` values of `T` (the room grown to hold them where it is
/// smaller): bytes the sort writes before it reads, as reals, the ids' 8-byte integers, the
/// maps' 4-byte indices or the groups' bytes.
fn room_in<T: bytemuck::Pod>(spare: &mut Vec<f64>, n: usize) -> &mut [T] {
    const {
        assert!(
            size_of::<f64>() % size_of::<T>() == 0 && align_of::<T>() <= align_of::<f64>(),
            "values that tile a real"
        )
    };
    let reals = (n * size_of::<T>()).div_ceil(size_of::<f64>());
    if spare.len() < reals {
        spare.resize(reals, 0.0);
    }
    &mut bytemuck::cast_slice_mut(&mut spare[..reals])[..n]
}

/// `a` (`width` values per particle) in the new order.
fn gather<T: Copy + Default + Send + Sync>(a: &mut Vec<T>, old_of_new: &[u32], width: usize) {
    if a.len() != width * old_of_new.len() {
        return; // not in use (an empty buffer)
    }
    let mut out = vec![T::default(); a.len()];
    gather_into(&mut out, a, old_of_new, width);
    *a = out;
}

impl World {
    /// Whether the particles may be sorted along space now (see the module doc; the caller
    /// is the Verlet step).
    pub(super) fn sortable(&self) -> bool {
        self.has_contact_force()
            && self.particles.len() >= SORT_MIN_PARTICLES
            && self.forces.iter().all(|f| f.properties().renumbers)
    }

    /// Sorts the particles along the Morton curve of the positions in `x_next` (the step's
    /// drifted state, where the neighbour list is about to be rebuilt), with Verlet's
    /// acceleration `a`; `spare` (a buffer of Verlet's that the step writes before it reads:
    /// `v_next` where the contacts make the predictor, else `a_next`) is the room the arrays
    /// move through.
    pub(super) fn sort_along_space(&mut self, a: &mut Vec<f64>, spare: &mut Vec<f64>) {
        let (width, origin) = {
            let Some(contact) = contact_force(&self.collide_stage, &self.particles) else {
                return;
            };
            let mut origin = [0.0; 3];
            for (k, o) in origin.iter_mut().enumerate() {
                *o = match contact.domain().periodic_box() {
                    Some(p) if p.axes()[k] => p.lo()[k],
                    _ => self.x_next.iter().skip(k).step_by(3).fold(f64::INFINITY, |m, c| m.min(*c)),
                };
            }
            (contact.reach(), origin)
        };
        if !(width > 0.0 && width.is_finite()) {
            return;
        }
        // (the keys, and the new map below, in `spare`'s room: the sort's only new array is
        // the order, 4 B a particle; at 10⁶ particles its transient arrays were the peak)
        let n = self.particles.len();
        let old_of_new = morton_order_in(&self.x_next, origin, width, room_in(spare, n));
        if old_of_new.iter().enumerate().all(|(i, &o)| i == o as usize) {
            return; // already in order
        }
        // the new order's map, over the old one (its inverse, if made, let go)
        let user_of: Vec<u32> = match self.sorted.take() {
            Some(Order { mut user_of, .. }) => {
                let room = room_in(spare, n);
                gather_into(room, &user_of, &old_of_new, 1);
                user_of.copy_from_slice(room);
                user_of
            }
            None => old_of_new.clone(),
        };
        self.permute(&old_of_new, a, spare, true);
        self.sorted = Some(Order::new(user_of));
        self.sorts += 1;
    }

    /// Where the particles stand while the engine keeps its own order: `Some(user_of)` while
    /// they are sorted along space, `user_of[i]` being the user's index of the particle the
    /// engine holds at index i; `None` when the two orders are one (always, outside a step,
    /// but in a [`UserOrder`]).
    pub(super) fn user_of(&self) -> Option<&[u32]> {
        self.sorted.as_ref().map(Order::user_of)
    }

    /// `a` (`width` values per particle, in the engine's order) in the user's order: a copy
    /// gathered through the engine's index of each user's particle, or `a` itself when the
    /// orders are one.
    fn in_user_order<'a, T: Copy + Default + Send + Sync>(&self, a: &'a [T], width: usize) -> Cow<'a, [T]> {
        let Some(order) = &self.sorted else {
            return Cow::Borrowed(a);
        };
        let mut out = vec![T::default(); a.len()];
        gather_into(&mut out, a, order.engine_of(), width);
        Cow::Owned(out)
    }

    /// Writes the positions (m) and velocities (m/s), 3 per particle, into `x` and `v` (those
    /// given) in the user's order (which the engine need not keep: a gather, not a permutation
    /// of the world).
    fn read_state_into(&self, x: Option<&mut [f64]>, v: Option<&mut [f64]>) {
        let p = &self.particles;
        for (out, own) in [(x, &p.x), (v, &p.v)] {
            let Some(out) = out else { continue };
            match &self.sorted {
                Some(order) => gather_into(out, own, order.engine_of(), 3),
                None => out.copy_from_slice(own),
            }
        }
    }

    /// Whether `x`, `v` (3 per particle) and `m` (one per particle), those given, in the
    /// user's order, are bit for bit the world's positions, velocities and masses (the
    /// caller's copies, unwritten).
    fn state_is(&self, x: Option<&[f64]>, v: Option<&[f64]>, m: Option<&[f64]>) -> bool {
        let p = &self.particles;
        let same = |a: &f64, b: &f64| a.to_bits() == b.to_bits();
        [(x, &p.x, 3), (v, &p.v, 3), (m, &p.mass, 1)]
            .into_iter()
            .all(|(given, own, width)| {
                let Some(given) = given else { return true };
                match &self.sorted {
                    Some(order) => order.engine_of().par_iter().enumerate().with_min_len(CHUNK).all(|(u, &i)| {
                        let i = i as usize;
                        (0..width).all(|k| same(&given[width * u + k], &own[width * i + k]))
                    }),
                    None => given
                        .par_chunks(CHUNK)
                        .zip(own.par_chunks(CHUNK))
                        .all(|(a, b)| a.iter().zip(b).all(|(a, b)| same(a, b))),
                }
            })
    }

    /// Puts the particles back in the user's order, if they are sorted.
    pub(super) fn restore_user_order(&mut self) {
        let Some(order) = self.sorted.take() else {
            return;
        };
        // The user's particle u goes back to place u from where the engine holds it.
        let old_of_new = order.into_engine_of();
        let mut a = match &mut self.stepper {
            Some(WorldStepper::Verlet(b)) => std::mem::take(&mut b.a),
            _ => Vec::new(),
        };
        // (between steps `x_next`, `v_next` hold nothing the next step reads: its drift
        // writes them first; `x_next` is the room the arrays move through)
        let mut spare = std::mem::take(&mut self.x_next);
        self.permute(&old_of_new, &mut a, &mut spare, false);
        self.x_next = spare;
        if let Some(WorldStepper::Verlet(b)) = &mut self.stepper {
            b.a = a;
        }
    }

    /// Moves every per-particle value of the world to the new order (`old_of_new[i]`: the
    /// index now of the particle that goes to place i), and tells the forces; with
    /// `step_buffers`, the step's `x_next`, `v_next` too (inside a step, where they hold the
    /// drifted state). The arrays of three reals a particle move through `spare`'s room (left
    /// holding the room of the last one moved: its values are not to be read), those of one
    /// through its front and back: each array keeps a room of its size.
    fn permute(&mut self, old_of_new: &[u32], a: &mut Vec<f64>, spare: &mut Vec<f64>, step_buffers: bool) {
        let p = &mut self.particles;
        let mut vectors = vec![&mut p.x, &mut p.v, a, &mut p.omega, &mut p.alpha];
        if step_buffers {
            vectors.extend([&mut self.x_next, &mut self.v_next]);
        }
        for values in vectors {
            gather_through(values, spare, old_of_new, 3);
        }
        for values in [
            &mut p.mass,
            &mut p.inv_mass,
            &mut p.radius,
            &mut p.inertia,
            &mut p.inv_inertia,
            &mut self.deaths.time,
        ] {
            gather_back(values, spare, old_of_new);
        }
        gather(&mut p.orientation, old_of_new, 4);
        gather_back(&mut p.id, spare, old_of_new);
        gather_back(&mut p.group, spare, old_of_new);
        if let Some(stage) = &mut self.collide_stage {
            stage.permute_particles(old_of_new); // (their own materials, where set)
        }
        // (the inverse in `spare`'s room, which the moves are done with)
        let new_of_old = room_in(spare, old_of_new.len());
        for (i, &o) in old_of_new.iter().enumerate() {
            new_of_old[o as usize] = i as u32;
        }
        let new_of_old = &*new_of_old;
        for f in &mut self.forces {
            f.reindex(new_of_old);
        }
        if let Some(model) = self.force_model() {
            if step_buffers {
                // (a sort along space: made because the list has expired, `sort_along_space`)
                model.renumber_expired(new_of_old);
            } else {
                model.renumber(new_of_old, old_of_new);
            }
        }
    }
}

/// A world that may keep the engine's order between calls (see the module doc), and gives
/// itself only in the user's order: the type through which a caller that steps in slices
/// (the Python binding) reaches its world, so that none of its methods can see the engine's
/// order by forgetting to put the particles back.
///
/// - [`UserOrder::get`]: the world, in the user's order (the particles put back first if a
///   step sorted them): for every method that takes or gives particle indices or
///   per-particle values, or changes the world.
/// - [`UserOrder::advance_in_engine_order`]: steps, leaving the particles as the steps leave
///   them (the only way to step without putting them back: [`World::advance`] puts them back).
/// - The rest reads or writes without putting the particles back, and so keeps the order the
///   next step sums in: per-particle values gathered into the user's order, values that do not
///   depend on the order, and writes that map through it or put the particles back
///   themselves once their arguments pass their checks (each says which).
///
/// Where the particles are put back changes the last bits of the steps after (they sum in the
/// user's order until the next sort), so nothing here puts them back but [`UserOrder::get`]
/// and the writes that say they do.
///
/// A world outside a `UserOrder` cannot step in the engine's order:
///
/// ```compile_fail
/// let mut world = kinema::World::new(kinema::WorldParams::default()).unwrap();
/// world.advance_in_engine_order(1).unwrap(); // private: only a `UserOrder` steps so
/// ```
pub struct UserOrder {
    world: World,
}

impl UserOrder {
    /// Takes the world (in the user's order, as every [`World`] is between calls).
    pub fn new(world: World) -> Self {
        Self { world }
    }

    /// The world with its particles in the user's order: puts them back first if a step
    /// sorted them (a no-op when they are).
    pub fn get(&mut self) -> &mut World {
        self.world.restore_user_order();
        &mut self.world
    }

    /// Advances `n` steps ([`World::advance`]) and leaves the particles in the engine's order,
    /// for the next slice; deaths after a step put them back themselves.
    pub fn advance_in_engine_order(&mut self, n: u64) -> Result<(), Error> {
        self.world.advance_in_engine_order(n)
    }

    /// [`World::runs_in_pool`].
    pub fn runs_in_pool(&self) -> bool {
        self.world.runs_in_pool()
    }

    /// [`World::advance_measured`], leaving the particles in the engine's order: the
    /// diagnostics at the end of the `n` steps, summed over the engine's order (as
    /// [`UserOrder::diagnostics`]).
    pub fn advance_in_engine_order_measured(&mut self, n: u64) -> Result<Diagnostics, Error> {
        self.world.advance_in_engine_order_measured(n, None).map(|(d, _)| d)
    }

    /// [`UserOrder::advance_in_engine_order_measured`] that also writes the positions (m) and
    /// velocities (m/s) at the end into `x` and `v` (3 per particle) in the user's order, as
    /// [`UserOrder::read_state_into`] would, by the diagnostics' own pass over the state (a
    /// frame of `World.run`: one pass instead of two); the bool says whether they were
    /// written: only where they hold 3 N values each after the steps (a death changes N).
    pub fn advance_in_engine_order_measured_into(
        &mut self,
        n: u64,
        x: &mut [f64],
        v: &mut [f64],
    ) -> Result<(Diagnostics, bool), Error> {
        self.world.advance_in_engine_order_measured(n, Some((x, v)))
    }

    /// Whether the particles are in the engine's order now (sorted along space).
    pub fn in_engine_order(&self) -> bool {
        self.world.user_of().is_some()
    }

    // -- per-particle values, gathered into the user's order --------------------------------

    /// A per-particle array of the particles (`width` values per particle, or none at all,
    /// as the orientations without spin), chosen by `field`, in the user's order: a copy
    /// gathered through the engine's index of each user's particle, or the array itself when
    /// the orders are one.
    pub fn in_user_order<'a, T: Copy + Default + Send + Sync>(
        &'a self,
        field: impl FnOnce(&'a Particles) -> &'a [T],
        width: usize,
    ) -> Cow<'a, [T]> {
        let a = field(&self.world.particles);
        let n = self.world.particles.len();
        assert!(
            a.is_empty() || a.len() == width * n,
            "a per-particle array, {width} values each"
        );
        self.world.in_user_order(a, width)
    }

    /// Writes the positions (m) and velocities (m/s), 3 per particle, into `x` and `v` (those
    /// given) in the user's order.
    pub fn read_state_into(&self, x: Option<&mut [f64]>, v: Option<&mut [f64]>) {
        self.world.read_state_into(x, v);
    }

    /// Whether `x`, `v` (3 per particle) and `m` (one per particle), those given, in the
    /// user's order, are bit for bit the world's positions, velocities and masses.
    pub fn state_is(&self, x: Option<&[f64]>, v: Option<&[f64]>, m: Option<&[f64]>) -> bool {
        self.world.state_is(x, v, m)
    }

    // -- values that do not depend on the order ---------------------------------------------

    /// The number of particles.
    pub fn len(&self) -> usize {
        self.world.particles.len()
    }

    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.world.particles.is_empty()
    }

    /// The id the next particle added gets.
    pub fn next_id(&self) -> u64 {
        self.world.particles.next_id
    }

    /// [`World::params`].
    pub fn params(&self) -> &WorldParams {
        self.world.params()
    }

    /// [`World::time`].
    pub fn time(&self) -> f64 {
        self.world.time()
    }

    /// [`World::steps`].
    pub fn steps(&self) -> u64 {
        self.world.steps()
    }

    /// [`World::clock`].
    pub fn clock(&self) -> Clock {
        self.world.clock()
    }

    /// [`World::stats`].
    pub fn stats(&self) -> Stats {
        self.world.stats()
    }

    /// [`World::sorts`].
    pub fn sorts(&self) -> u64 {
        self.world.sorts()
    }

    /// [`World::membership`].
    pub fn membership(&self) -> u64 {
        self.world.membership()
    }

    /// [`World::stage_times`].
    pub fn stage_times(&self) -> StageTimes {
        self.world.stage_times()
    }

    /// [`World::linear_solve`].
    pub fn linear_solve(&self) -> Option<LinearSolve> {
        self.world.linear_solve()
    }

    /// [`World::has_spin`].
    pub fn has_spin(&self) -> bool {
        self.world.has_spin()
    }

    /// [`World::collision_params`].
    pub fn collision_params(&self) -> Option<CollisionParams> {
        self.world.collision_params()
    }

    /// [`World::contact_sub_models`] (no order: the laws are the same for every particle).
    pub fn contact_sub_models(&self) -> Option<Vec<(&'static str, &'static str)>> {
        self.world.contact_sub_models()
    }

    /// [`World::group_masks`].
    pub fn group_masks(&self) -> GroupMasks {
        self.world.group_masks()
    }

    /// [`World::collider_masks`].
    pub fn collider_masks(&self) -> Vec<u32> {
        self.world.collider_masks()
    }

    /// [`World::periodic`].
    pub fn periodic(&self) -> [bool; 3] {
        self.world.periodic()
    }

    /// [`World::collider_books`] (one row per collider).
    pub fn collider_books(&self, last: bool) -> Vec<ColliderBooks> {
        self.world.collider_books(last)
    }

    /// [`World::wall_force_carry`] (one row per collider).
    pub fn wall_force_carry(&self) -> Option<Vec<ColliderBooks>> {
        self.world.wall_force_carry()
    }

    /// [`World::collision_stats`].
    pub fn collision_stats(&self) -> Option<(CollisionStats, CollisionStats)> {
        self.world.collision_stats()
    }

    /// [`World::diagnostics`], summed over the engine's order where it keeps one (totals the
    /// same to rounding; the particles stay where they are).
    pub fn diagnostics(&self) -> Diagnostics {
        self.world.diagnostics()
    }

    // -- writes that leave the particles where they are --------------------------------------

    /// [`World::land_at`].
    pub fn land_at(&mut self, t1: f64, n: u64) -> Result<(), Error> {
        self.world.land_at(t1, n)
    }

    /// [`World::restore_clock`].
    pub fn restore_clock(&mut self, k0: u64, t0: f64) -> Result<(), Error> {
        self.world.restore_clock(k0, t0)
    }

    /// [`World::restore_wall_force_carry`] (one row per collider).
    pub fn restore_wall_force_carry(&mut self, carry: Option<Vec<ColliderBooks>>) {
        self.world.restore_wall_force_carry(carry);
    }

    /// [`World::set_deaths`]: the times of death are given in the user's order and mapped
    /// into the engine's.
    pub fn set_deaths(&mut self, time_of_death: Option<Vec<f64>>, kills: Vec<KillVolume>) -> Result<(), Error> {
        self.world.set_deaths(time_of_death, kills)
    }

    /// [`World::times_of_death`] (a gather into the user's order).
    pub fn times_of_death(&self) -> Vec<f64> {
        self.world.times_of_death()
    }

    /// [`World::set_times_of_death`] (mapped into the engine's order, which stays).
    pub fn set_times_of_death(&mut self, start: usize, times: &[f64]) -> Result<(), Error> {
        self.world.set_times_of_death(start, times)
    }

    /// [`World::has_times_of_death`] (no order).
    pub fn has_times_of_death(&self) -> bool {
        self.world.has_times_of_death()
    }

    /// [`World::set_kill_volumes`] (no order).
    pub fn set_kill_volumes(&mut self, kills: Vec<KillVolume>) -> Result<(), Error> {
        self.world.set_kill_volumes(kills)
    }

    /// [`World::take_removed_ids`] (ids, not indices).
    pub fn take_removed_ids(&mut self) -> Vec<u64> {
        self.world.take_removed_ids()
    }

    /// [`World::take_placement_notice`] (a sentence naming the user's particles).
    pub fn take_placement_notice(&mut self) -> Option<String> {
        self.world.take_placement_notice()
    }

    /// [`World::record_contact_events`] (a switch).
    pub fn record_contact_events(&mut self, on: bool) -> Result<(), Error> {
        self.world.record_contact_events(on)
    }

    /// [`World::take_contact_events`]: recorded by the impulse model's steps, which never
    /// sort the particles (only the spring–dashpot contact force does).
    pub fn take_contact_events(&mut self) -> Vec<TouchEvent> {
        self.world.take_contact_events()
    }

    /// [`World::set_particle_spin`], which puts the particles back itself once the range
    /// passes its check.
    pub fn set_particle_spin(
        &mut self,
        range: std::ops::Range<usize>,
        omega: Option<&[f64]>,
        inertia: Option<&[f64]>,
    ) -> Result<(), Error> {
        self.world.set_particle_spin(range, omega, inertia)
    }

    /// [`World::set_orientations`], which puts the particles back itself once the
    /// quaternions pass their checks.
    pub fn set_orientations(&mut self, range: std::ops::Range<usize>, q: &[f64]) -> Result<(), Error> {
        self.world.set_orientations(range, q)
    }

    /// [`World::restore_spin_carry`], which puts the particles back itself once the carry
    /// passes its checks.
    pub fn restore_spin_carry(&mut self, alpha: Vec<f64>) -> Result<(), Error> {
        self.world.restore_spin_carry(alpha)
    }

    /// [`World::restore_contact_history`], which puts the particles back itself once the
    /// memory passes its checks.
    pub fn restore_contact_history(&mut self, pairs: Vec<PairMemory>, walls: Vec<WallMemory>) -> Result<(), Error> {
        self.world.restore_contact_history(pairs, walls)
    }
}
