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

use std::cell::RefCell;
use std::rc::Rc;

use rayon::prelude::*;

use super::contact_force::ContactForce;
use super::{World, WorldStepper};
use crate::error::{CallbackError, Error};
use crate::forces::{Force, Properties, Rates, State};

/// The fewest particles the world sorts along space.
pub(crate) const SORT_MIN_PARTICLES: usize = 2 * super::CHUNK;

/// Bits of each cell coordinate in a Morton code (3 × 21 = 63).
const MORTON_BITS: u32 = 21;

/// The world's spring–dashpot contact force, shared between the forces (where it acts like
/// any other) and the world (which asks it when its neighbour list expires).
pub(crate) struct SharedContact(pub Rc<RefCell<ContactForce>>);

impl Force for SharedContact {
    fn name(&self) -> &str {
        "contact"
    }
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        self.0.borrow_mut().accumulate(s, f)
    }
    fn validate(&self, n: usize) -> Result<(), Error> {
        self.0.borrow().validate(n)
    }
    fn potential_energy(&self, s: &State) -> Option<f64> {
        self.0.borrow().potential_energy(s)
    }
    fn properties(&self) -> Properties {
        self.0.borrow().properties()
    }
    fn rates(&self, s: &State, inv_mass: &[f64]) -> Option<Rates> {
        self.0.borrow().rates(s, inv_mass)
    }
    fn reindex(&mut self, new_of_old: &[u32]) {
        self.0.borrow_mut().reindex(new_of_old)
    }
}

/// `v`'s low 21 bits spread to every third bit (bit k to bit 3k).
fn spread(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | x << 32) & 0x1f_0000_0000_ffff;
    x = (x | x << 16) & 0x1f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

/// The Morton code of cell (i, j, k): their bits interleaved, x lowest.
pub(crate) fn morton(c: [u64; 3]) -> u64 {
    spread(c[0]) | spread(c[1]) << 1 | spread(c[2]) << 2
}

/// The order that sorts positions `x` (m, 3 per particle) by the Morton code of their cells
/// of width `width` (m) from `origin`, ties in index order: `old_of_new[i]` is the index now
/// of the particle that goes to place i.
///
/// Each key is one u64, the code above the index (8 B per particle while sorting, not 16):
/// the index takes ⌈log₂ N⌉ bits and each cell coordinate B = ⌊(64 − those) / 3⌋ ≥ 10 of the
/// rest; where the particles span more than 2^B cells the cells are widened to fit.
pub(crate) fn morton_order(x: &[f64], origin: [f64; 3], width: f64) -> Vec<u32> {
    let n = x.len() / 3;
    let index_bits = usize::BITS - n.saturating_sub(1).leading_zeros();
    let bits = ((64 - index_bits) / 3).min(MORTON_BITS);
    let top = ((1u64 << bits) - 1) as f64;
    let span = x
        .par_chunks_exact(3)
        .map(|p| (0..3).map(|k| p[k] - origin[k]).fold(0.0, f64::max))
        .reduce(|| 0.0, f64::max);
    let width = width.max(span / top);
    let mut keys: Vec<u64> = x
        .par_chunks_exact(3)
        .enumerate()
        .map(|(i, p)| {
            // `as u64` truncates (the floor for t ≥ 0, without `f64::floor`'s library call)
            // and saturates: below the origin is cell 0, NaN is 0, beyond the top the top.
            let cell = [0, 1, 2].map(|k| ((p[k] - origin[k]) / width).min(top) as u64);
            morton(cell) << index_bits | i as u64
        })
        .collect();
    keys.par_sort_unstable(); // the keys are distinct: one result for any thread count
    let mask = (1u64 << index_bits) - 1;
    keys.into_iter().map(|k| (k & mask) as u32).collect()
}

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
        self.contact.is_some()
            && self.particles.len() >= SORT_MIN_PARTICLES
            && self.collide_stage.as_ref().is_some_and(|c| c.materials_parts().1.is_none())
            && self.forces.iter().all(|f| f.properties().renumbers)
    }

    /// Sorts the particles along the Morton curve of the positions in `x_next` (the step's
    /// drifted state, where the neighbour list is about to be rebuilt), with Verlet's
    /// acceleration `a`.
    pub(super) fn sort_along_space(&mut self, a: &mut Vec<f64>) {
        let Some(contact) = &self.contact else {
            return;
        };
        let (width, origin) = {
            let contact = contact.borrow();
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
        self.permute(&old_of_new, a);
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
        self.permute(&old_of_new, &mut a);
        if let Some(WorldStepper::Verlet(b)) = &mut self.stepper {
            b.a = a;
        }
    }

    /// Moves every per-particle value of the world to the new order (`old_of_new[i]`: the
    /// index now of the particle that goes to place i), and tells the forces.
    fn permute(&mut self, old_of_new: &[u32], a: &mut Vec<f64>) {
        let p = &mut self.particles;
        for v in [&mut p.x, &mut p.v, &mut self.x_next, &mut self.v_next, a] {
            gather3(v, old_of_new);
        }
        gather(&mut p.mass, old_of_new);
        gather(&mut p.inv_mass, old_of_new);
        gather(&mut p.radius, old_of_new);
        gather(&mut p.id, old_of_new);
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
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_codes_interleave_the_bits() {
        assert_eq!(morton([1, 0, 0]), 0b001);
        assert_eq!(morton([0, 1, 0]), 0b010);
        assert_eq!(morton([0, 0, 1]), 0b100);
        assert_eq!(morton([3, 5, 6]), 0b110_101_011);
        let top = (1 << MORTON_BITS) - 1;
        assert_eq!(morton([top, top, top]), (1 << 63) - 1);
    }

    #[test]
    fn the_order_visits_cells_along_the_curve_and_keeps_ties() {
        // Cells (1,1,0), (0,0,0), (1,0,0), (0,0,0) again: codes 3, 0, 1, 0.
        let x = [1.5, 1.5, 0.5, 0.2, 0.2, 0.2, 1.2, 0.9, 0.1, 0.7, 0.7, 0.7];
        assert_eq!(morton_order(&x, [0.0; 3], 1.0), vec![1, 3, 2, 0]);
        // below the origin: cell 0
        assert_eq!(morton_order(&[-5.0, 0.0, 0.0, 0.5, 0.5, 0.5], [0.0; 3], 1.0), vec![0, 1]);
    }
}
