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
//! The permutation never leaves the world: [`World::advance`] puts the particles back in
//! the user's order before it returns (ids, positions, velocities, forces' indices), and an
//! error names the user's particle. The sort runs only where every force can follow a
//! renumbering ([`Force::can_renumber`]: a Python force cannot, and then the world keeps the
//! user's order), with velocity Verlet, without per-particle materials and from
//! [`SORT_MIN_PARTICLES`] particles (below, everything fits in cache anyway). Sorting changes
//! only the order in which each particle's contact forces are summed, so the state may differ
//! from an unsorted run in the last bits; it depends on the positions alone, so it is the
//! same for any number of threads.

use rayon::prelude::*;

use super::forces::contact_force;
use super::{World, WorldStepper};
use crate::collide::morton::morton_order;

/// The fewest particles the world sorts along space.
pub(crate) const SORT_MIN_PARTICLES: usize = 2 * super::CHUNK;

/// `a` (3 values per particle) in the new order.
fn gather3(a: &mut Vec<f64>, old_of_new: &[u32]) {
    if a.len() != 3 * old_of_new.len() {
        return; // not in use (an empty buffer)
    }
    let mut out = vec![0.0; a.len()];
    out.par_chunks_exact_mut(3).zip(old_of_new.par_iter()).for_each(|(o, &i)| {
        let i = 3 * i as usize;
        o.copy_from_slice(&a[i..i + 3]);
    });
    *a = out;
}

/// `a` (one value per particle) in the new order.
fn gather<T: Copy + Send + Sync>(a: &mut Vec<T>, old_of_new: &[u32]) {
    if a.len() != old_of_new.len() {
        return; // not in use (an empty buffer)
    }
    *a = old_of_new.par_iter().map(|&i| a[i as usize]).collect();
}

impl World {
    /// Whether the particles may be sorted along space now (see the module doc; the caller
    /// is the Verlet step).
    pub(super) fn sortable(&self) -> bool {
        self.has_contact_force()
            && self.particles.len() >= SORT_MIN_PARTICLES
            && self.collide_stage.as_ref().is_some_and(|c| c.materials_parts().1.is_none())
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
            Some(user_of) => old_of_new.iter().map(|&o| user_of[o as usize]).collect(),
            None => old_of_new.clone(),
        };
        self.permute(&old_of_new, a, true);
        self.sorted = Some(user_of);
        self.sorts += 1;
    }

    /// Puts the particles back in the user's order, if they are sorted.
    pub(super) fn restore_user_order(&mut self) {
        let Some(user_of) = self.sorted.take() else {
            return;
        };
        // The particle now at i goes back to place user_of[i].
        let mut old_of_new = vec![0u32; user_of.len()];
        for (i, &u) in user_of.iter().enumerate() {
            old_of_new[u as usize] = i as u32;
        }
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
            gather3(v, old_of_new);
        }
        if step_buffers {
            gather3(&mut self.x_next, old_of_new);
            gather3(&mut self.v_next, old_of_new);
        }
        gather(&mut p.mass, old_of_new);
        gather(&mut p.inv_mass, old_of_new);
        gather(&mut p.radius, old_of_new);
        gather(&mut p.id, old_of_new);
        gather(&mut self.deaths.time, old_of_new);
        if let Some(stage) = &mut self.collide_stage {
            gather(&mut stage.own, old_of_new);
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
