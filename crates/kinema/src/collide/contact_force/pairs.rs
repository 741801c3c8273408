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

use super::affinity;
use super::exchange::Exchange;
use super::history::{pair_memory, wall_memory, PairSlip, Slip, WallSlip};
use super::overlapping::Overlapping;
use super::tangent::{Tangent, TangentialModel, Touch};
use super::{ContactForce, CHUNK};
use crate::collide::neighbour_list::{NeighbourList, Rows};
use crate::collide::velocities::Velocities;
use crate::collide::{pair_contact, Contact};
use crate::simd::prefetch;
use crate::vec3;

/// How many list entries ahead of its reads the pair pass asks for the partners' positions,
/// radii, inverse masses and velocities ([`prefetch`]): about a dozen particles' rows of a gas,
/// enough to cover a miss to memory at the pass's pace (8 and 32 measured no better).
const PREFETCH: usize = 16;

thread_local! {
    /// Each pool thread's room for [`Overlapping`], kept from one chunk to the next.
    static ROOM: std::cell::Cell<Overlapping> = std::cell::Cell::new(Overlapping::default());
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
    /// The dashpots' power Σ c_n u_n², W (≥ 0), and the tangential parts' (`tangent.rs`).
    pub power: f64,
    /// The energy JKR contacts lost as they let go, J (≥ 0; `cohesion.rs`).
    pub lost: f64,
    /// Σ (x_i − x_j) ⊗ F of the pairs (colliders left out), N·m, row-major 3 × 3.
    pub virial: [f64; 9],
}

impl ContactBooks {
    fn add(&mut self, other: &ContactBooks) {
        self.contacts += other.contacts;
        self.begun += other.begun;
        self.power += other.power;
        self.lost += other.lost;
        for k in 0..9 {
            self.virial[k] += other.virial[k];
        }
    }

    /// The books of a contact with force `force` (N, along n) and dashpot `dashpot` (kg/s),
    /// `arm` its separation |x_i − x_j| (m; `None` against a collider), in a step `h`; with a
    /// tangential part, its force on i (N) and the power it dissipates (W).
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn book(
        &mut self,
        c: &Contact,
        force: f64,
        dashpot: f64,
        arm: Option<f64>,
        h: f64,
        tangential_power: f64,
        tangential: Option<[f64; 3]>,
    ) {
        self.contacts += 1;
        self.begun += usize::from(c.overlap + c.u_n * h <= 0.0);
        self.power += dashpot * c.u_n * c.u_n + tangential_power;
        if let Some(d) = arm {
            // (x_i − x_j) ⊗ F = d n ⊗ (F_n n + F_t)
            let n = c.normal;
            match tangential {
                None => {
                    for r in 0..3 {
                        for k in 0..3 {
                            self.virial[3 * r + k] += d * force * n[r] * n[k];
                        }
                    }
                }
                Some(ft) => {
                    let f = vec3::add(vec3::scale(force, n), ft);
                    for r in 0..3 {
                        for k in 0..3 {
                            self.virial[3 * r + k] += d * n[r] * f[k];
                        }
                    }
                }
            }
        }
    }
}

/// One collider contact's force in a pass kept for the collider's books: on particle i, N
/// (tangential part included), with the contact's normal, its point on the collider's
/// surface (m) and the surface's velocity there (m/s).
#[derive(Clone, Copy, Debug)]
pub(crate) struct WallPush {
    pub collider: usize,
    pub force: [f64; 3],
    pub normal: [f64; 3],
    pub at: [f64; 3],
    pub u: [f64; 3],
}

/// What stage 1 of the pair pass found in one chunk.
#[derive(Clone, Default)]
pub(super) struct ChunkSums {
    /// The chunk's pair energy, J (−0.0 where not asked).
    pub energy: f64,
    /// The index of its first non-finite position coordinate, when asked and there is one.
    pub bad: Option<usize>,
    /// The chunk's contact books, when asked.
    pub books: ContactBooks,
    /// With the books, the chunk's collider contact forces, particle by particle.
    pub pushes: Vec<WallPush>,
    /// The pool thread that passed the chunk (rayon's index): the kick that follows runs
    /// the chunk there (`verlet.rs`, `kick_velocities`), and so does the next pass
    /// (`affinity.rs`).
    pub thread: Option<usize>,
    /// The chunk's listed pairs found in contact (overlapping, or held by JKR's adhesion).
    pub touching: usize,
}

/// The chunks' books summed in chunk order (the same on any number of threads).
pub(super) fn summed_books(sums: &[ChunkSums]) -> ContactBooks {
    let mut all = ContactBooks::default();
    for s in sums {
        all.add(&s.books);
    }
    all
}

/// The tangential part of a pass (`tangent.rs`): the model, the angular velocities it sees,
/// the contacts' memory it reads and, in Verlet's pass, the step that stretches the springs.
pub(super) struct Turning<'p> {
    /// The tangential law (`None`: the memory is kept for JKR's contacts alone, which hold
    /// past touching once made).
    pub model: Option<TangentialModel>,
    /// ω at the evaluation, rad/s (3 per particle; empty: nothing turns).
    pub omega: &'p [f64],
    /// The memory read (sorted, [`Histories`](super::history::Histories)).
    pub pairs: &'p [PairSlip],
    pub walls: &'p [WallSlip],
    /// h, s: stretch the springs by the step's slip and write the new memory (Verlet's pass).
    pub step: Option<f64>,
    /// With a step: the velocities and angular velocities at its start (ω empty: nothing
    /// turns), whose means with the evaluation's are the velocities over the step.
    pub start: Option<(&'p [f64], &'p [f64])>,
}

/// Where a pass with a tangential part writes: the torques (N·m, 3 per particle; `None`:
/// forces only), what chunks owe later chunks' torques, and per chunk the new memory (with a
/// step).
#[derive(Default)]
pub(super) struct TurningOut<'o> {
    /// The torques and what chunks owe later chunks' torques.
    pub torque: Option<(&'o mut [f64], &'o mut Exchange)>,
    /// The new memory, per chunk.
    pub memory: Option<(&'o mut Vec<Vec<PairSlip>>, &'o mut Vec<Vec<WallSlip>>)>,
}

/// One chunk's share of a pass's outputs.
struct ChunkOut<'o> {
    forces: Option<&'o mut [f64]>,
    sent: &'o mut Vec<(u32, [f64; 3])>,
    torque: Option<&'o mut [f64]>,
    torque_sent: Option<&'o mut Vec<(u32, [f64; 3])>>,
    pairs: Option<&'o mut Vec<PairSlip>>,
    walls: Option<&'o mut Vec<WallSlip>>,
}

/// Each chunk's share of a pass's outputs, side by side: its part of the force buffer and
/// of the torques, its outboxes, its new memory (`None` where the pass writes none).
fn chunk_outs<'o>(
    chunks: usize,
    forces: Option<&'o mut [f64]>,
    exchange: &'o mut Exchange,
    turn_out: Option<&'o mut TurningOut<'_>>,
) -> Vec<ChunkOut<'o>> {
    exchange.sent.resize_with(chunks, Vec::new);
    // each chunk's outputs, side by side
    let mut force_parts: Vec<Option<&mut [f64]>> = match forces {
        Some(f) => f.chunks_mut(3 * CHUNK).map(Some).collect(),
        None => (0..chunks).map(|_| None).collect(),
    };
    force_parts.resize_with(chunks, || None);
    let mut torque_parts: Vec<Option<&mut [f64]>> = Vec::new();
    let mut torque_sent: Vec<Option<&mut Vec<(u32, [f64; 3])>>> = Vec::new();
    let mut new_pairs: Vec<Option<&mut Vec<PairSlip>>> = Vec::new();
    let mut new_walls: Vec<Option<&mut Vec<WallSlip>>> = Vec::new();
    if let Some(o) = turn_out {
        if let Some((tq, ex)) = o.torque.as_mut() {
            torque_parts = tq.chunks_mut(3 * CHUNK).map(Some).collect();
            ex.sent.resize_with(chunks, Vec::new);
            torque_sent = ex.sent.iter_mut().map(Some).collect();
        }
        if let Some((pairs, walls)) = o.memory.as_mut() {
            pairs.resize_with(chunks, Vec::new);
            walls.resize_with(chunks, Vec::new);
            new_pairs = pairs.iter_mut().map(Some).collect();
            new_walls = walls.iter_mut().map(Some).collect();
        }
    }
    torque_parts.resize_with(chunks, || None);
    torque_sent.resize_with(chunks, || None);
    new_pairs.resize_with(chunks, || None);
    new_walls.resize_with(chunks, || None);
    let parts = force_parts
        .into_iter()
        .zip(exchange.sent.iter_mut())
        .zip(torque_parts.into_iter().zip(torque_sent))
        .zip(new_pairs.into_iter().zip(new_walls));
    let mut outs: Vec<ChunkOut<'_>> = Vec::with_capacity(chunks);
    for (((forces, sent), (torque, torque_sent)), (pairs, walls)) in parts {
        outs.push(ChunkOut {
            forces,
            sent,
            torque,
            torque_sent,
            pairs,
            walls,
        });
    }
    outs
}

impl ContactForce<'_> {
    /// Stage 1 of the pair pass (see the module doc) at positions `x` (m) and velocities `v`
    /// (m/s), with the list `list` (holding at `x`), and the exchange indexed for stage 2.
    ///
    /// `forces`: the force buffer, N (3 per particle), chunk c's part started by
    /// `init(c, part)` before its pairs are added; `None`: energies only. Returns each
    /// chunk's energy and first non-finite position in `sums`. With `turning` (a model with
    /// friction), each contact's tangential force is added to its normal one, and its
    /// torques, new memory and what chunks owe later chunks' torques go to `out`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn pair_forces<V: Velocities + ?Sized>(
        &self,
        x: &[f64],
        v: &V,
        list: &NeighbourList,
        forces: Option<&mut [f64]>,
        init: impl Fn(usize, &mut [f64]) + Sync,
        options: PassOptions,
        exchange: &mut Exchange,
        sums: &mut Vec<ChunkSums>,
        turning: Option<(&Turning<'_>, TurningOut<'_>)>,
    ) {
        debug_assert!(list.half, "the contact force keeps a half list");
        let chunks = list.rows.len();
        let (turn, mut turn_out) = match turning {
            Some((t, o)) => (Some(t), Some(o)),
            None => (None, None),
        };
        let outs = chunk_outs(chunks, forces, exchange, turn_out.as_mut());
        // each chunk on the thread that passed it the last time (`affinity.rs`)
        let threads = rayon::current_num_threads();
        let homes = affinity::homes(chunks, threads, |c| sums.get(c).and_then(|s| s.thread));
        // a chunk most of whose listed pairs overlapped at the last pass tests them in its
        // own loop this time (`chunk_pairs`)
        let dense: Vec<bool> = (0..chunks)
            .map(|c| sums.get(c).is_some_and(|s| 2 * s.touching > list.rows[c].partners().len()))
            .collect();
        let done = affinity::run(outs, &homes, |c, out| {
            self.chunk_pairs(c, &list.rows[c], out, (x, v), list, &init, (options, dense[c]), turn)
        });
        sums.clear();
        sums.extend(done.into_iter().map(|(s, t)| ChunkSums { thread: Some(t), ..s }));
        exchange.index(chunks);
        if let Some((_, ex)) = turn_out.and_then(|o| o.torque) {
            ex.index(chunks);
        }
    }

    /// Stage 1 of the pair pass for chunk `c` (its list rows `rows`, its share `out` of the
    /// outputs), at positions and velocities `xv`: see [`ContactForce::pair_forces`].
    ///
    /// Longer than 100 lines: it is the pass's kernel, one loop over the chunk's particles
    /// with, inside, the loop over each one's listed partners and then over its colliders.
    /// Each contact's force goes to the chunk's buffers through a dozen locals (the force and
    /// torque parts, the outboxes, the new memory, the books); split into functions, each
    /// would take most of them as arguments, for no gain in clarity, in the hottest loop of
    /// the force models.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn chunk_pairs<V: Velocities + ?Sized>(
        &self,
        c: usize,
        rows: &Rows,
        out: ChunkOut<'_>,
        (x, v): (&[f64], &V),
        list: &NeighbourList,
        init: &(impl Fn(usize, &mut [f64]) + Sync),
        (options, dense): (PassOptions, bool),
        turn: Option<&Turning<'_>>,
    ) -> ChunkSums {
        let ChunkOut {
            forces: mut fc,
            sent,
            torque: mut tc,
            torque_sent: mut ts,
            pairs: mut new_pairs,
            walls: mut new_walls,
        } = out;
        sent.clear();
        let first = c * CHUNK;
        let len = rows.len();
        if let Some(fc) = fc.as_deref_mut() {
            init(c, fc);
        }
        if let Some(tc) = tc.as_deref_mut() {
            tc.fill(0.0);
        }
        if let Some(ts) = ts.as_deref_mut() {
            ts.clear();
        }
        if let Some(p) = new_pairs.as_deref_mut() {
            p.clear();
        }
        if let Some(w) = new_walls.as_deref_mut() {
            w.clear();
        }
        // this chunk's part of the memory
        let (old_pairs, old_walls) = match turn {
            Some(t) => (
                part_of(t.pairs, first, first + len, |p| p.i),
                part_of(t.walls, first, first + len, |w| w.i),
            ),
            None => (&[][..], &[][..]),
        };
        // this chunk's wall candidates (sorted by particle)
        let w0 = list.walls.partition_point(|w| w.0 < first);
        let w1 = list.walls.partition_point(|w| w.0 < first + len);
        let mut walls = list.walls[w0..w1].iter().peekable();
        let mut energy = -0.0;
        let mut bad = None;
        let mut books = ContactBooks::default();
        let mut wall_lost = 0.0;
        let mut pushes = Vec::new();
        // A law that acts on overlapping pairs alone and keeps no memory visits the particles
        // with an overlapping pair or a collider candidate, found first in a loop of their
        // own (`overlapping.rs`), and their overlapping pairs; the others visit every
        // particle and test each listed pair here, and so does a `dense` chunk, most of whose
        // pairs overlapped at the last pass (a packing: there the first look finds nearly
        // every entry again, and cost a compressed lattice of 27,000 spheres 8 %). The same
        // pairs either way, in the same order.
        let plain = turn.is_none() && self.jkr().is_none() && !dense;
        let mut touching = 0;
        // (the room of the thread's last chunk, put back below: no allocations a chunk)
        let mut overlapping = ROOM.take();
        let (visits, start, partners) = if plain {
            self.overlapping(rows, first, x, &list.walls[w0..w1], options.check_positions, &mut overlapping);
            bad = overlapping.bad;
            (
                Visits::Some(&overlapping.visit),
                &overlapping.start[..],
                &overlapping.partners[..],
            )
        } else {
            (Visits::All(len), rows.start(), rows.partners())
        };
        // The partners' positions, radii, inverse masses and velocities PREFETCH entries
        // ahead of the row being read: beyond a core's caches (10⁶ particles) nearly every
        // partner's read misses, and the loop would wait for each in turn.
        let mut ahead = 0;
        for q in 0..visits.len() {
            let l = visits.at(q);
            let end = (start[q + 1] as usize + PREFETCH).min(partners.len());
            while ahead < end {
                let j = partners[ahead] as usize;
                prefetch(&x[3 * j]);
                prefetch(&x[3 * j + 2]); // (its line may end before z)
                prefetch(&self.radius[j]);
                prefetch(&self.inv_mass[j]);
                v.prefetch(j);
                ahead += 1;
            }
            let i = first + l;
            let (xi, ri) = ([x[3 * i], x[3 * i + 1], x[3 * i + 2]], self.radius[i]);
            if !plain && options.check_positions && bad.is_none() {
                bad = xi.iter().position(|c| !c.is_finite()).map(|k| 3 * i + k);
            }
            for &j in &partners[start[q] as usize..start[q + 1] as usize] {
                let j = j as usize;
                let found = if plain || self.overlaps(xi, ri, j, x) {
                    pair_contact(i, j, x, v, self.radius, &self.domain, 0.0)
                } else if self.jkr().is_some() {
                    self.held_pair(i, j, x, v, old_pairs, &mut books.lost)
                } else {
                    None
                };
                let Some(contact) = found else {
                    continue;
                };
                touching += 1;
                if options.energy {
                    if let Some(u) = self.spring_energy(&contact) {
                        energy += u;
                    }
                }
                let Some(fc) = fc.as_deref_mut() else { continue };
                let Some((force, dashpot)) = self.normal_force_parts(&contact) else {
                    continue;
                };
                let mut fv = contact.normal.map(|n| force * n);
                let mut tangent = None;
                if let Some(t) = turn {
                    let slip = pair_memory(old_pairs, i as u32, j as u32).unwrap_or_default();
                    let tg = t.model.map(|m| self.tangent_of(m, t, &contact, force, dashpot, v, slip));
                    if let Some(p) = new_pairs.as_deref_mut() {
                        p.push(PairSlip {
                            i: i as u32,
                            j: j as u32,
                            slip: tg.map_or(Slip::default(), |tg| tg.slip),
                        });
                    }
                    if let Some(tg) = tg {
                        fv = vec3::add(fv, tg.force);
                        tangent = Some(tg);
                    }
                }
                if let Some(h) = options.books {
                    let arm = self.radius[i] + self.radius[j] - contact.overlap;
                    let extra = tangent.map_or(0.0, |t| t.power);
                    books.book(&contact, force, dashpot, Some(arm), h, extra, tangent.map(|t| t.force));
                }
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
                if let (Some(tg), Some(tc)) = (tangent, tc.as_deref_mut()) {
                    let (ti, tj) = self.torques(&contact, &tg);
                    for k in 0..3 {
                        tc[3 * l + k] += ti[k];
                    }
                    if j < first + len {
                        for k in 0..3 {
                            tc[3 * (j - first) + k] += tj[k];
                        }
                    } else if let Some(ts) = ts.as_deref_mut() {
                        // (the receiver subtracts what it is sent)
                        ts.push((j as u32, tj.map(|c| -c)));
                    }
                }
            }
            let Some(fc) = fc.as_deref_mut().filter(|_| options.walls) else {
                continue;
            };
            while let Some(&(_, k)) = walls.next_if(|w| w.0 == i) {
                self.wall_contacts_held(i, k, x, v, old_walls, &mut wall_lost, |contact| {
                    if let Some((force, dashpot)) = self.normal_force_parts(contact) {
                        let mut fv = contact.normal.map(|n| force * n);
                        let mut tangent = None;
                        if let Some(t) = turn {
                            let slip = wall_memory(old_walls, i as u32, k as u32, contact.normal).unwrap_or_default();
                            let tg = t.model.map(|m| self.tangent_of(m, t, contact, force, dashpot, v, slip));
                            if let Some(w) = new_walls.as_deref_mut() {
                                w.push(WallSlip {
                                    i: i as u32,
                                    k: k as u32,
                                    normal: contact.normal,
                                    slip: tg.map_or(Slip::default(), |tg| tg.slip),
                                });
                            }
                            if let Some(tg) = tg {
                                fv = vec3::add(fv, tg.force);
                                tangent = Some(tg);
                            }
                        }
                        if let Some(h) = options.books {
                            let extra = tangent.map_or(0.0, |t| t.power);
                            books.book(contact, force, dashpot, None, h, extra, None);
                            pushes.push(WallPush {
                                collider: k,
                                force: fv,
                                normal: contact.normal,
                                at: vec3::sub(xi, vec3::scale(ri - contact.overlap, contact.normal)),
                                u: contact.wall_velocity,
                            });
                        }
                        for k in 0..3 {
                            fc[3 * l + k] += fv[k];
                        }
                        if let (Some(tg), Some(tc)) = (tangent, tc.as_deref_mut()) {
                            let (ti, _) = self.torques(contact, &tg);
                            for k in 0..3 {
                                tc[3 * l + k] += ti[k];
                            }
                        }
                    }
                });
            }
        }
        books.lost += wall_lost;
        ROOM.set(overlapping);
        ChunkSums {
            energy,
            bad,
            books,
            pushes,
            thread: None, // (set by the caller, which knows the pool's thread)
            touching,
        }
    }

    /// The tangential part of `contact` (normal force `force`, N, and dashpot `dashpot`,
    /// kg/s) at (x, v) with the memory `slip` (`tangent.rs`).
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn tangent_of<V: Velocities + ?Sized>(
        &self,
        model: TangentialModel,
        t: &Turning<'_>,
        c: &Contact,
        force: f64,
        dashpot: f64,
        v: &V,
        slip: super::history::Slip,
    ) -> Tangent {
        let (u, omega) = self.relative(c, v, t.omega);
        // the velocities over the step: the means of those at its start and the evaluation's
        let moved = t.start.map(|(v0, w0)| {
            let mean = |a: [f64; 3], b: [f64; 3]| [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])];
            let (u0, omega0) = self.relative(c, v0, w0);
            (mean(u, u0), [mean(omega[0], omega0[0]), mean(omega[1], omega0[1])])
        });
        let reduced = match c.partner_particle() {
            Some(_) => self.reduced_radius(c),
            None => self.radius[c.i],
        };
        let touch = Touch {
            normal: c.normal,
            contact_radius: self.contact_radius_of(c),
            reduced_radius: reduced,
            u,
            omega,
            moved,
            arms: self.arms(c),
            // (LAMMPS's Fncrit: with adhesion |F_n + 2 F_po|, the bound of friction measured
            // from the pull-off, so that a contact held by adhesion alone still rubs)
            normal_force: (force + 2.0 * self.pull_off_of(c)).abs(),
            dashpot,
            friction: self.friction_of(c),
        };
        model.at(&touch, slip, t.step)
    }

    /// The relative velocity u = v_i − v_j (v_i − w at a collider) of contact `c` at the
    /// velocities `v`, and the two sides' angular velocities from `omega` (0 at a collider,
    /// and everywhere when `omega` is empty: nothing turns).
    #[inline]
    fn relative<V: Velocities + ?Sized>(&self, c: &Contact, v: &V, omega: &[f64]) -> ([f64; 3], [[f64; 3]; 2]) {
        let vi = v.at(c.i);
        let turn = |q: usize| if omega.is_empty() { [0.0; 3] } else { vec3::get(omega, q) };
        match c.partner_particle() {
            Some(j) => (vec3::sub(vi, v.at(j)), [turn(c.i), turn(j)]),
            None => (vec3::sub(vi, c.wall_velocity), [turn(c.i), [0.0; 3]]),
        }
    }

    /// The lever arms (ρ_i, ρ_j) of contact `c`, m (`collide/spin.rs`: the distance of centres
    /// split by the radii; r_i − δ against a collider).
    #[inline]
    fn arms(&self, c: &Contact) -> (f64, f64) {
        crate::collide::spin::Rotation {
            inv_inertia: &[],
            radius: self.radius,
        }
        .arms(c, c.overlap)
    }

    /// The torques of a contact's tangential part on i and on its partner, N·m: −ρ n × F_t
    /// each, and the couple (+ on i, − on j).
    #[inline]
    fn torques(&self, c: &Contact, t: &Tangent) -> ([f64; 3], [f64; 3]) {
        let (rho_i, rho_j) = self.arms(c);
        let nf = vec3::cross(c.normal, t.force);
        (
            vec3::add(vec3::scale(-rho_i, nf), t.couple),
            vec3::sub(vec3::scale(-rho_j, nf), t.couple),
        )
    }
}

/// The particles of a chunk the pair pass visits, by their indices l in the chunk: all
/// `len` of them, or those listed (ascending; `overlapping.rs`).
enum Visits<'a> {
    All(usize),
    Some(&'a [u32]),
}

impl Visits<'_> {
    fn len(&self) -> usize {
        match self {
            Visits::All(len) => *len,
            Visits::Some(l) => l.len(),
        }
    }

    /// The q-th particle visited.
    #[inline(always)]
    fn at(&self, q: usize) -> usize {
        match self {
            Visits::All(_) => q,
            Visits::Some(l) => l[q] as usize,
        }
    }
}

/// The part of a sorted store whose particle lies in `first..end`.
fn part_of<T>(all: &[T], first: usize, end: usize, key: impl Fn(&T) -> u32) -> &[T] {
    let a = all.partition_point(|e| (key(e) as usize) < first);
    let b = all.partition_point(|e| (key(e) as usize) < end);
    &all[a..b]
}
