//! The pair pass of [`ContactForce`] over its half neighbour list: each listed pair is tested
//! once, from its lower index, and its force goes to both sides, in a fixed order whatever the
//! number of threads.
//!
//! The pass runs in two stages, chunk by chunk ([`CHUNK`] particles, a fixed partition):
//!
//! 1. **Pairs.** Chunk c, on one thread, starts its particles' forces (the caller's `init`),
//!    then for each particle i in order and each listed j > i that overlaps it, computes the
//!    contact (i first, so the pair's numbers are those of a search) and its force F n:
//!    +F n onto i, −F n onto j if j is in the same chunk, else into the chunk's outbox
//!    `sent[c]` as (j, F n). Then i's collider contacts, when asked. Nothing but chunk c's
//!    own memory is written.
//! 2. **Exchange.** Each outbox is sorted (stably) by its receivers' chunks and indexed by
//!    receiving chunk; chunk d then subtracts what the earlier chunks sent it, chunk by chunk
//!    in ascending order, each outbox in the order it was filled ([`Exchange::receive`]).
//!
//! So particle i's force is summed in this order: the forces of its same-chunk partners
//! j < i (as they were met), its own pairs (ascending j), its colliders, and what the earlier
//! chunks sent it (ascending chunk). The order depends on the list and the chunk partition
//! alone: the forces are the same to the bit on any number of threads. A pair's two forces
//! are F n and −F n exactly (both from one product, one added, one subtracted), so momentum
//! is kept to rounding, as with the full list this replaced, which computed each pair twice.

use rayon::prelude::*;

use super::{ContactForce, CHUNK};
use crate::collide::neighbour_list::{NeighbourList, Rows};
use crate::collide::pair_contact;

/// The forces chunks send to particles of later chunks (stage 2 of the pair pass), kept
/// between evaluations so that a pass allocates nothing once warm.
#[derive(Default)]
pub(super) struct Exchange {
    /// Per chunk: (j, F n) for each contact force, N, it owes particle j of a later chunk;
    /// after stage 1, sorted by j's chunk (stably: the order found within a chunk kept).
    sent: Vec<Vec<(u32, [f64; 3])>>,
    /// Per receiving chunk d: (chunk c, start, end) of what `sent[c]` owes d, ascending c.
    inbox: Vec<Vec<(u32, u32, u32)>>,
}

impl Exchange {
    /// Subtracts from chunk `d`'s forces `fc` (N, 3 per particle of the chunk) what the
    /// earlier chunks sent it, in ascending order of sending chunk.
    #[inline]
    pub(super) fn receive(&self, d: usize, fc: &mut [f64]) {
        let first = d * CHUNK;
        for &(c, start, end) in &self.inbox[d] {
            for (j, fv) in &self.sent[c as usize][start as usize..end as usize] {
                let l = *j as usize - first;
                for k in 0..3 {
                    fc[3 * l + k] -= fv[k];
                }
            }
        }
    }

    /// How many forces the last pass sent between chunks.
    #[cfg(test)]
    pub(super) fn sent_count(&self) -> usize {
        self.sent.iter().map(Vec::len).sum()
    }

    /// Sorts each outbox by receiving chunk and indexes the runs by receiver.
    fn index(&mut self, chunks: usize) {
        self.sent.par_iter_mut().for_each(|s| s.sort_by_key(|e| e.0 as usize / CHUNK));
        self.inbox.resize_with(chunks, Vec::new);
        self.inbox.iter_mut().for_each(Vec::clear);
        for (c, sent) in self.sent.iter().enumerate() {
            let mut start = 0;
            while start < sent.len() {
                let d = sent[start].0 as usize / CHUNK;
                let end = start + sent[start..].partition_point(|e| e.0 as usize / CHUNK == d);
                self.inbox[d].push((c as u32, start as u32, end as u32));
                start = end;
            }
        }
    }
}

/// What stage 1 of the pair pass is asked to do besides the pair forces.
#[derive(Clone, Copy)]
pub(super) struct PassOptions {
    /// Sum each chunk's pair energy Σ ½ k_n δ² (J).
    pub energy: bool,
    /// Add each particle's collider contact forces after its pairs'.
    pub walls: bool,
    /// Find each chunk's first non-finite position coordinate (x_i is at hand here: the
    /// Verlet kick need not read the positions again for its check).
    pub check_positions: bool,
    /// Keep the contacts' books ([`ContactBooks`]) for a step of this length, s.
    pub books: Option<f64>,
}

/// What the contacts of one force evaluation did, for the collision books (a step's: the
/// step's force evaluation of velocity Verlet).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ContactBooks {
    /// Contacts pushing (overlapping pairs and particle–collider contacts).
    pub contacts: usize,
    /// Of them, those that began within the step: δ − h δ' ≤ 0, the overlap one step earlier
    /// on the current approach (δ' = −u_n), is no overlap. An impact's count.
    pub begun: usize,
    /// The dashpots' power Σ c_n u_n², W (≥ 0).
    pub power: f64,
    /// Σ (x_i − x_j) ⊗ F of the pairs (colliders left out), N·m, row-major 3 × 3.
    pub virial: [f64; 9],
}

impl ContactBooks {
    fn add(&mut self, other: &ContactBooks) {
        self.contacts += other.contacts;
        self.begun += other.begun;
        self.power += other.power;
        for k in 0..9 {
            self.virial[k] += other.virial[k];
        }
    }

    /// The books of a contact with force `force` (N, along n) and dashpot `dashpot` (kg/s),
    /// `arm` its separation |x_i − x_j| (m; `None` against a collider), in a step `h`.
    #[inline]
    fn book(&mut self, c: &crate::collide::Contact, force: f64, dashpot: f64, arm: Option<f64>, h: f64) {
        self.contacts += 1;
        self.begun += usize::from(c.overlap + c.u_n * h <= 0.0);
        self.power += dashpot * c.u_n * c.u_n;
        if let Some(d) = arm {
            let n = c.normal;
            for r in 0..3 {
                for k in 0..3 {
                    self.virial[3 * r + k] += d * force * n[r] * n[k];
                }
            }
        }
    }
}

/// What stage 1 of the pair pass found in one chunk.
#[derive(Clone, Copy, Default)]
pub(super) struct ChunkSums {
    /// The chunk's pair energy, J (−0.0 where not asked).
    pub energy: f64,
    /// The index of its first non-finite position coordinate, when asked and there is one.
    pub bad: Option<usize>,
    /// The chunk's contact books, when asked.
    pub books: ContactBooks,
}

/// The chunks' books summed in chunk order (the same on any number of threads).
pub(super) fn summed_books(sums: &[ChunkSums]) -> ContactBooks {
    let mut all = ContactBooks::default();
    for s in sums {
        all.add(&s.books);
    }
    all
}

impl ContactForce<'_> {
    /// Stage 1 of the pair pass (see the module doc) at positions `x` (m) and velocities `v`
    /// (m/s), with the list `list` (holding at `x`), and the exchange indexed for stage 2.
    ///
    /// `forces`: the force buffer, N (3 per particle), chunk c's part started by
    /// `init(c, part)` before its pairs are added; `None`: energies only. Returns each
    /// chunk's energy and first non-finite position in `sums`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn pair_forces(
        &self,
        x: &[f64],
        v: &[f64],
        list: &NeighbourList,
        forces: Option<&mut [f64]>,
        init: impl Fn(usize, &mut [f64]) + Sync,
        options: PassOptions,
        exchange: &mut Exchange,
        sums: &mut Vec<ChunkSums>,
    ) {
        debug_assert!(list.half, "the contact force keeps a half list");
        let chunks = list.rows.len();
        exchange.sent.resize_with(chunks, Vec::new);
        let chunk = |c: usize, rows: &Rows, sent: &mut Vec<(u32, [f64; 3])>, mut fc: Option<&mut [f64]>| {
            sent.clear();
            let first = c * CHUNK;
            let len = rows.len();
            if let Some(fc) = fc.as_deref_mut() {
                init(c, fc);
            }
            // this chunk's wall candidates (sorted by particle)
            let w0 = list.walls.partition_point(|w| w.0 < first);
            let w1 = list.walls.partition_point(|w| w.0 < first + len);
            let mut walls = list.walls[w0..w1].iter().peekable();
            let mut energy = -0.0;
            let mut bad = None;
            let mut books = ContactBooks::default();
            for l in 0..len {
                let i = first + l;
                let (xi, ri) = ([x[3 * i], x[3 * i + 1], x[3 * i + 2]], self.radius[i]);
                if options.check_positions && bad.is_none() {
                    bad = xi.iter().position(|c| !c.is_finite()).map(|k| 3 * i + k);
                }
                for &j in rows.of(l) {
                    let j = j as usize;
                    if !self.overlaps(xi, ri, j, x) {
                        continue;
                    }
                    let Some(contact) = pair_contact(i, j, x, v, self.radius, &self.domain, 0.0) else {
                        continue;
                    };
                    if options.energy {
                        if let Some(u) = self.spring_energy(&contact) {
                            energy += u;
                        }
                    }
                    let Some(fc) = fc.as_deref_mut() else { continue };
                    let Some((force, dashpot)) = self.normal_force_parts(&contact) else {
                        continue;
                    };
                    if let Some(h) = options.books {
                        let arm = self.radius[i] + self.radius[j] - contact.overlap;
                        books.book(&contact, force, dashpot, Some(arm), h);
                    }
                    let fv = contact.normal.map(|n| force * n);
                    for k in 0..3 {
                        fc[3 * l + k] += fv[k];
                    }
                    if j < first + len {
                        for k in 0..3 {
                            fc[3 * (j - first) + k] -= fv[k];
                        }
                    } else {
                        sent.push((j as u32, fv));
                    }
                }
                let Some(fc) = fc.as_deref_mut().filter(|_| options.walls) else {
                    continue;
                };
                while let Some(&(_, k)) = walls.next_if(|w| w.0 == i) {
                    self.wall_contacts(i, k, x, v, |contact| {
                        if let Some((force, dashpot)) = self.normal_force_parts(contact) {
                            if let Some(h) = options.books {
                                books.book(contact, force, dashpot, None, h);
                            }
                            for k in 0..3 {
                                fc[3 * l + k] += force * contact.normal[k];
                            }
                        }
                    });
                }
            }
            ChunkSums { energy, bad, books }
        };
        match forces {
            Some(f) => f
                .par_chunks_mut(3 * CHUNK)
                .zip(list.rows.par_iter().zip(exchange.sent.par_iter_mut()))
                .enumerate()
                .map(|(c, (fc, (rows, sent)))| chunk(c, rows, sent, Some(fc)))
                .collect_into_vec(sums),
            None => list
                .rows
                .par_iter()
                .zip(exchange.sent.par_iter_mut())
                .enumerate()
                .map(|(c, (rows, sent))| chunk(c, rows, sent, None))
                .collect_into_vec(sums),
        }
        exchange.index(chunks);
    }
}
