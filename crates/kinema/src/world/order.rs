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
//! The permutation never shows outside the world, but it need not be undone per call:
//! [`World::advance`] puts the particles back in the user's order before it returns (ids,
//! positions, velocities, forces' indices), while [`World::advance_in_engine_order`] leaves
//! them sorted, as LAMMPS keeps its sorted atoms with a tag → index map (`atom->map`). A
//! caller that keeps the engine's order (the Python binding, between calls of `step` and
//! the frames of `run`) reads what it shows every frame through the two maps of [`Order`]
//! ([`World::read_state_into`], [`World::in_user_order`], [`World::state_is`]: gathers, not
//! permutations of the world), and puts the particles back ([`World::restore_order`]) only
//! before a method that takes or gives particle indices or changes the world. An error
//! names the user's particle. The sort runs only where every force can follow a
//! renumbering (`Properties::renumbers`: a Python force cannot, and then the world keeps the
//! user's order), with velocity Verlet and from [`SORT_MIN_PARTICLES`] particles (below,
//! everything fits in cache anyway); the particles' own materials, where set, move with them
//! (`CollideStage::permute_particles`). Sorting changes
//! only the order in which each particle's contact forces are summed, so the state may differ
//! from an unsorted run in the last bits; it depends on the positions alone, so it is the
//! same for any number of threads.

use std::borrow::Cow;

use rayon::prelude::*;

use super::forces::contact_force;
use super::{World, WorldStepper, CHUNK};
use crate::collide::morton::morton_order;

/// The particles' order while the engine keeps its own: the two maps between it and the
/// user's, each the other's inverse.
pub(super) struct Order {
    /// `user_of[i]`: the user's index of the particle the engine holds at index i.
    user_of: Vec<u32>,
    /// `engine_of[u]`: where the engine holds the user's particle u.
    engine_of: Vec<u32>,
}

impl Order {
    /// `user_of[i]`: the user's index of the particle the engine holds at index i.
    pub(super) fn user_of(&self) -> &[u32] {
        &self.user_of
    }
}

/// The fewest particles the world sorts along space.
pub(crate) const SORT_MIN_PARTICLES: usize = 2 * super::CHUNK;

/// `out[i]` = `a[from[i]]`, `width` values per particle (`from`: each new place's old index,
/// as `engine_of` is for the user's order and `old_of_new` for a sort).
fn gather_into<T: Copy + Send + Sync>(out: &mut [T], a: &[T], from: &[u32], width: usize) {
    out.par_chunks_exact_mut(width)
        .zip(from.par_iter())
        .with_min_len(CHUNK)
        .for_each(|(o, &i)| {
            let i = width * i as usize;
            o.copy_from_slice(&a[i..i + width]);
        });
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
    /// acceleration `a`.
    pub(super) fn sort_along_space(&mut self, a: &mut Vec<f64>) {
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
        let old_of_new = morton_order(&self.x_next, origin, width);
        if old_of_new.iter().enumerate().all(|(i, &o)| i == o as usize) {
            return; // already in order
        }
        let user_of: Vec<u32> = match &self.sorted {
            Some(order) => old_of_new.par_iter().map(|&o| order.user_of[o as usize]).collect(),
            None => old_of_new.clone(),
        };
        let mut engine_of = vec![0u32; user_of.len()];
        for (i, &u) in user_of.iter().enumerate() {
            engine_of[u as usize] = i as u32;
        }
        self.permute(&old_of_new, a, true);
        self.sorted = Some(Order { user_of, engine_of });
        self.sorts += 1;
    }

    /// Where the particles stand while the engine keeps its own order: `Some(user_of)` while
    /// they are sorted along space, `user_of[i]` being the user's index of the particle the
    /// engine holds at index i; `None` when the two orders are one. A caller that keeps the
    /// engine's order between calls ([`World::advance_in_engine_order`]) reads per-particle
    /// values through it instead of putting the particles back.
    pub fn user_of(&self) -> Option<&[u32]> {
        self.sorted.as_ref().map(Order::user_of)
    }

    /// `a` (`width` values per particle, in the engine's order) in the user's order: a copy
    /// gathered through the engine's index of each user's particle, or `a` itself when the
    /// orders are one.
    pub fn in_user_order<'a, T: Copy + Default + Send + Sync>(&self, a: &'a [T], width: usize) -> Cow<'a, [T]> {
        let Some(order) = &self.sorted else {
            return Cow::Borrowed(a);
        };
        let mut out = vec![T::default(); a.len()];
        gather_into(&mut out, a, &order.engine_of, width);
        Cow::Owned(out)
    }

    /// Writes the positions (m) and velocities (m/s), 3 per particle, into `x` and `v` in the
    /// user's order (which the engine need not keep: a gather, not a permutation of the world).
    pub fn read_state_into(&self, x: &mut [f64], v: &mut [f64]) {
        let p = &self.particles;
        match &self.sorted {
            Some(order) => {
                gather_into(x, &p.x, &order.engine_of, 3);
                gather_into(v, &p.v, &order.engine_of, 3);
            }
            None => {
                x.copy_from_slice(&p.x);
                v.copy_from_slice(&p.v);
            }
        }
    }

    /// Whether `x`, `v` (3 per particle) and `m` (one per particle), in the user's order, are
    /// bit for bit the world's positions, velocities and masses (the caller's copies, unwritten).
    pub fn state_is(&self, x: &[f64], v: &[f64], m: &[f64]) -> bool {
        let p = &self.particles;
        let same = |a: &f64, b: &f64| a.to_bits() == b.to_bits();
        match &self.sorted {
            Some(order) => order.engine_of.par_iter().enumerate().with_min_len(CHUNK).all(|(u, &i)| {
                let (u, i) = (u, i as usize);
                (0..3).all(|k| same(&x[3 * u + k], &p.x[3 * i + k]) && same(&v[3 * u + k], &p.v[3 * i + k]))
                    && same(&m[u], &p.mass[i])
            }),
            None => {
                let (x, v) = ((x, &p.x), (v, &p.v));
                [x, v].into_iter().all(|(a, b)| {
                    a.par_chunks(CHUNK)
                        .zip(b.par_chunks(CHUNK))
                        .all(|(a, b)| a.iter().zip(b).all(|(a, b)| same(a, b)))
                }) && m.iter().zip(&p.mass).all(|(a, b)| same(a, b))
            }
        }
    }

    /// Puts the particles back in the user's order, if they are sorted.
    pub(super) fn restore_user_order(&mut self) {
        let Some(order) = self.sorted.take() else {
            return;
        };
        // The user's particle u goes back to place u from where the engine holds it.
        let old_of_new = order.engine_of;
        let mut a = match &mut self.stepper {
            Some(WorldStepper::Verlet(b)) => std::mem::take(&mut b.a),
            _ => Vec::new(),
        };
        // (between steps `x_next`, `v_next` hold nothing the next step reads: its drift
        // writes them first)
        self.permute(&old_of_new, &mut a, false);
        if let Some(WorldStepper::Verlet(b)) = &mut self.stepper {
            b.a = a;
        }
    }

    /// Moves every per-particle value of the world to the new order (`old_of_new[i]`: the
    /// index now of the particle that goes to place i), and tells the forces; with
    /// `step_buffers`, the step's `x_next`, `v_next` too (inside a step, where they hold the
    /// drifted state).
    fn permute(&mut self, old_of_new: &[u32], a: &mut Vec<f64>, step_buffers: bool) {
        let p = &mut self.particles;
        for v in [&mut p.x, &mut p.v, a] {
            gather(v, old_of_new, 3);
        }
        if step_buffers {
            gather(&mut self.x_next, old_of_new, 3);
            gather(&mut self.v_next, old_of_new, 3);
        }
        gather(&mut p.mass, old_of_new, 1);
        gather(&mut p.inv_mass, old_of_new, 1);
        gather(&mut p.radius, old_of_new, 1);
        gather(&mut p.id, old_of_new, 1);
        gather(&mut p.group, old_of_new, 1);
        gather(&mut p.omega, old_of_new, 3);
        gather(&mut p.orientation, old_of_new, 4);
        gather(&mut p.alpha, old_of_new, 3);
        gather(&mut p.inertia, old_of_new, 1);
        gather(&mut p.inv_inertia, old_of_new, 1);
        gather(&mut self.deaths.time, old_of_new, 1);
        if let Some(stage) = &mut self.collide_stage {
            stage.permute_particles(old_of_new); // (their own materials, where set)
        }
        let mut new_of_old = vec![0u32; old_of_new.len()];
        for (new, &old) in old_of_new.iter().enumerate() {
            new_of_old[old as usize] = new as u32;
        }
        for f in &mut self.forces {
            f.reindex(&new_of_old);
        }
        if let Some(model) = self.spring_dashpot() {
            model.renumber(&new_of_old, old_of_new);
        }
    }
}
