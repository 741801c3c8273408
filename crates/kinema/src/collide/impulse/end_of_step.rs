//! The end of an impulse-model step (stages 2–4 after the impacts, [`ImpulseModel::step`]):
//! the contacts of the touched particles and of the piles they reach (detection), the
//! velocity solve of Newton's law with its warm start and the overlap removed (response),
//! each impulse onto both particles and the energy lost (distribution).

use super::{ImpulseModel, StageSetting};
use crate::collide::colliders::{NearCache, Touch};
use crate::collide::contact::action_reaction;
use crate::collide::events::Paths;
use crate::collide::islands::{self, EndProblem, IslandStats, Islands};
use crate::collide::marks::Marks;
use crate::collide::neighbour_list::CHUNK;
use crate::collide::response::{bounces, VELOCITY_TOLERANCE};
use crate::collide::shock::Accuracy;
use crate::collide::soft_step::{self, SoftParams, Target, SLOP, SPECULATIVE};
use crate::collide::spin::rotational_energy;
use crate::collide::{pair_contact, Collider, Contact, Domain, Partner};
use crate::error::Error;
use crate::vec3;
use rayon::prelude::*;

/// Most passes of the soft step's solve stage, and of its relax and restitution stages, at
/// the `physics` accuracy. Warm-started, a heap at rest converges in one or two passes a
/// step; the caps matter while it settles, and for a frictionless heap, which converges
/// slowly. Measured on `benchmarks/piles.py` (docs/collisions.md): with caps of 100 and 30
/// the 2D pour of 2,000 discs, the 20-row pyramid, the 60-deep column and the frictional pour
/// of 10,000 balls all come to rest within 5 s at 1 ms; with 10 and 10 (Box2D's and
/// Chipmunk's habit of a few passes a step) the 2D pour still boiled after 5 s (KE 107 J)
/// and the frictional pour of 10,000 too (max |v| 2.4 m/s), though a frictionless demo heap
/// ran 2.8× faster.
const SOLVE_PASSES: usize = 100;
const RELAX_PASSES: usize = 30;

/// The caps at the `animation` accuracy, where shock propagation (`collide/shock.rs`) stops
/// each level on the one below whatever the solve's passes left: at 120 Hz the 2D pour
/// rested at 0.64 % of r in 2.4 s with 10 and 5, at 1.1 % in 8.5 s with 100 and 30 (the
/// 60-deep column: 0.47 % in 2.4 s, 0.24 % in 4.8 s). The relax keeps the physics grade's
/// 30: with 5, a column with rolling resistance never came to rest (1.2 % of r, 15 cm/s
/// after 5 s), the frictionless demo neither, and the 2D pour of seed 3 boiled (26 % of r,
/// 0.6 m/s); with 30 all three come to rest, and no pour boils (seeds 1–3 calm at 1.3–1.7 %
/// of r, max |v| 3–5 mm/s, but above the sleep rule's 1 %: awake after 5 s).
const ANIMATION_SOLVE_PASSES: usize = 10;
const ANIMATION_RELAX_PASSES: usize = RELAX_PASSES;

/// An island sleeps only while its deepest overlap is at most this many slops (1 % of r for
/// equal spheres): a pile rests at 0.23–0.26 % of r at 1 ms.
const SLEEP_OVERLAP: f64 = 5.0;

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

/// The most passes of the soft step's stages at `accuracy`, for a step of h s.
fn soft_params(accuracy: Accuracy, h: f64) -> SoftParams {
    SoftParams {
        h,
        tolerance: VELOCITY_TOLERANCE,
        solve_passes: match accuracy {
            Accuracy::Physics => SOLVE_PASSES,
            Accuracy::Animation => ANIMATION_SOLVE_PASSES,
        },
        relax_passes: match accuracy {
            Accuracy::Physics => RELAX_PASSES,
            Accuracy::Animation => ANIMATION_RELAX_PASSES,
        },
    }
}

/// Contact c's i's relative velocity (`per` = 1 s: f gives velocities) or displacement over
/// the step (`per` = h: f gives displacements) against its partner: a particle's, or a
/// collider surface's (its velocity at the contact, over the step h times it).
fn relative(c: &Contact, f: &dyn Fn(usize) -> [f64; 3], per: f64) -> [f64; 3] {
    match c.partner_particle() {
        Some(j) => vec3::sub(f(c.i), f(j)),
        None if c.wall_velocity == [0.0; 3] => f(c.i),
        None => vec3::sub(f(c.i), vec3::scale(per, c.wall_velocity)),
    }
}

/// The overlap contact c may keep, m: [`SLOP`] of r_i + r_j, or of the diameter against a
/// collider (`radius`: the particles' radii).
fn slop(radius: &[f64], c: &Contact) -> f64 {
    SLOP * (radius[c.i] + c.partner_particle().map_or(radius[c.i], |j| radius[j]))
}

impl ImpulseModel {
    /// The contacts at the end of the step (pairs within the [`SPECULATIVE`] margin of
    /// touching, and with colliders) of the touched particles, and of every particle they
    /// reach through such contacts: a pile is one contact network, and the solver must see all
    /// of it (a ball the solver stops changes the approach of the one resting on it). Breadth
    /// first from the touched particles; a particle reached for the first time is touched.
    /// Each touched particle's collider contacts, then each pair once, lower index first,
    /// sorted by (i, partner).
    ///
    /// A contact that reaches a particle asleep wakes its island, which joins the search and
    /// this step's solve (`collide/sleep.rs`); returns the islands woken.
    pub(super) fn end_contacts(&mut self, set: &StageSetting<'_>, x1: &[f64], v1: &[f64]) -> usize {
        self.contacts.clear();
        let (n, radius) = (set.radius.len(), set.radius);
        let mut work: Vec<usize> = self.touched.sorted().to_vec();
        // (each particle whose row was walked: the pair of two of them was seen already)
        let mut done = std::mem::take(&mut self.scratch);
        done.reset(n, false);
        let mut next = 0;
        let mut woke = 0;
        while next < work.len() {
            let i = work[next];
            next += 1;
            for k in 0..self.list.rows[i / CHUNK].of(i % CHUNK).len() {
                let j = self.list.rows[i / CHUNK].of(i % CHUNK)[k] as usize;
                if done.get(j) {
                    continue; // the pair was seen from j's side
                }
                let (lo, hi) = (i.min(j), i.max(j));
                let gap = SPECULATIVE * (radius[lo] + radius[hi]);
                if self.sleep.is_asleep(j) && set.inv_mass[i] == 0.0 {
                    continue; // a pinned particle wakes nothing: the contact is the sleeper's
                }
                if let Some(c) = pair_contact(lo, hi, x1, v1, radius, set.domain, gap) {
                    self.contacts.push(c);
                    if self.sleep.is_asleep(j) {
                        woke += self.wake_island(j, &mut work);
                    } else if self.touched.mark(j) {
                        work.push(j);
                    }
                }
            }
            done.mark(i);
        }
        self.scratch = done;
        if woke > 0 {
            self.records.sort();
        }
        // (each pair is found once: its key is unique, and an unstable sort gives the one order)
        self.contacts.sort_unstable_by_key(|c| (c.i, c.other));
        let pairs = self.contacts.len();
        let list = &self.list;
        let contacts = &mut self.contacts;
        // (a mesh asks the triangles it found near the particle last time, while they answer)
        let near = &mut self.near_meshes;
        let meshes = set.colliders.iter().any(|c| matches!(c, Collider::Mesh(_)));
        near.resize(if meshes { list.walls.len() } else { 0 }, NearCache::default());
        let mut spare = NearCache::default();
        for &i in self.touched.sorted() {
            let (p, vi) = (vec3::get(x1, i), vec3::get(v1, i));
            let first = list.walls.partition_point(|w| w.0 < i);
            for (w, &(_, k)) in list.walls[first..].iter().enumerate().take_while(|w| w.1 .0 == i) {
                let collider = &set.colliders[k];
                let cache = near.get_mut(first + w).unwrap_or(&mut spare);
                collider.for_each_touch_near(p, radius[i], 2.0 * SPECULATIVE * radius[i], cache, |t| {
                    let c = collider.contact(k, t, i, p, vi, radius[i]);
                    if !on_periodic_wall(&c, set.colliders, set.domain) {
                        contacts.push(c);
                    }
                });
            }
        }
        // The colliders' contacts first: a pass then hands what a wall holds up on through
        // the pile above it in one pass where it can (a column resting on a floor converges
        // in a few passes from zero, not hundreds).
        self.contacts.rotate_left(pairs);
        woke
    }

    /// Wakes the island particle q sleeps in (1 if it slept, else 0): its particles touched
    /// and added to `work`, its contacts' records back among the awake ones as they fell
    /// asleep (left unsorted: the caller sorts them).
    pub(super) fn wake_island(&mut self, q: usize, work: &mut Vec<usize>) -> usize {
        let Some(island) = self.sleep.wake(q) else { return 0 };
        for &m in &island.members {
            self.touched.mark(m);
            work.push(m);
        }
        // (whole: whether each bore load is the engine's own flag from the step it fell
        // asleep in, as the awake island would have it)
        self.records.append(island.records.iter().copied());
        1
    }

    /// Sleeping's update at the step's end (`collide/sleep.rs`): each awake particle's calm
    /// time grows by h if its speed and its displacement over the step divided by h are at
    /// most `speed` (m/s), else starts again; each island of this step's solve that rests on a
    /// collider or a pinned particle, and whose particles have all been calm for `time` s,
    /// falls asleep with its contacts' warm start, its velocities set to 0. Returns the
    /// islands put to sleep and the kinetic energy their velocities had, J.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn settle(
        &mut self,
        set: &StageSetting<'_>,
        x0: &[f64],
        x1: &[f64],
        (v1, omega): (&mut [f64], &mut [f64]),
        h: f64,
        speed: f64,
        time: f64,
    ) -> (usize, f64) {
        let (n, inv_mass, domain) = (set.radius.len(), set.inv_mass, set.domain);
        let reach = speed * h;
        for q in 0..n {
            if self.sleep.is_asleep(q) {
                continue;
            }
            let v = vec3::get(v1, q);
            let d = domain.displacement(vec3::get(x1, q), vec3::get(x0, q));
            let mut calm = vec3::dot(v, v) <= speed * speed && vec3::dot(d, d) <= reach * reach;
            if let Some(r) = set.rotation {
                // and its surface turns no faster than that speed (a ball spinning in place
                // is not at rest)
                let w = vec3::get(omega, q);
                calm &= r.radius[q] * r.radius[q] * vec3::dot(w, w) <= speed * speed;
            }
            // (a little under `time` counts: h added k times need not reach k h exactly)
            self.sleep.calm[q] = if calm { self.sleep.calm[q] + h } else { 0.0 };
        }
        let ready = time - 1e-9 * h;
        let mut slept = 0;
        let mut lost = 0.0;
        let mut island_of: Vec<usize> = Vec::new();
        for k in 0..self.islands.len() {
            let contacts = self.islands.island(k);
            let fixed = |q: usize| inv_mass[q] == 0.0;
            let supported = contacts.iter().any(|&c| match self.contacts[c].other {
                Partner::Collider(_) => true,
                Partner::Particle(j) => fixed(j) || fixed(self.contacts[c].i),
            });
            if !supported {
                continue;
            }
            let mut members: Vec<usize> = contacts
                .iter()
                .flat_map(|&c| std::iter::once(self.contacts[c].i).chain(self.contacts[c].partner_particle()))
                .filter(|&q| !fixed(q))
                .collect();
            if members.iter().any(|&q| self.sleep.calm[q] < ready) {
                continue;
            }
            // nor while an overlap deeper than SLEEP_OVERLAP slops is still being pushed out
            // (at a long step a pile comes to rest before its solve has taken out what its
            // fall pressed in, and asleep it would keep it); the deepest goes to sleep with it
            let mut overlap: f64 = 0.0;
            let mut pressed = false;
            for &c in contacts {
                let (i, other) = (self.contacts[c].i, self.contacts[c].other);
                let size = set.radius[i] + self.contacts[c].partner_particle().map_or(set.radius[i], |j| set.radius[j]);
                let depth = deepest(set, x1, i, other);
                pressed |= depth > SLEEP_OVERLAP * SLOP * size;
                overlap = overlap.max(depth);
            }
            if pressed {
                continue;
            }
            members.sort_unstable();
            members.dedup();
            if island_of.is_empty() {
                island_of.resize(n, usize::MAX);
            }
            for &q in &members {
                island_of[q] = k;
                lost += 0.5 * set.mass[q] * vec3::dot(vec3::get(v1, q), vec3::get(v1, q));
                v1[3 * q..3 * q + 3].fill(0.0);
                if let Some(r) = set.rotation {
                    // an island asleep does not turn either
                    lost += rotational_energy(std::iter::once(q), omega, r.inv_inertia);
                    omega[3 * q..3 * q + 3].fill(0.0);
                }
            }
            // its contacts' warm start goes with it (a pair's movable particles are in one
            // island; a pinned one is in none)
            let of = |i: usize, other: Partner| match (island_of[i], other) {
                (usize::MAX, Partner::Particle(j)) => island_of[j],
                (k, _) => k,
            };
            let mine = self.records.take_where(|r| of(r.i, r.other) == k);
            self.sleep.put_to_sleep(members, mine, overlap);
            slept += 1;
        }
        (slept, lost)
    }

    /// The end-of-step contacts' soft step, island by island on all threads
    /// (`collide/soft_step.rs`, `collide/islands.rs`): each contact's targets from the step
    /// (its gap and velocities at x₁, v₁, its tangential displacement since the step's start
    /// x₀, and its approach at the start, `paths`' reference velocities), the final total
    /// impulse of each contact into `totals` (applied by the caller; `v1` is not changed), the
    /// solve stage's into `solved` (the next warm start), and the positions `x1` moved by the
    /// solve stage. A contact that approached faster than the threshold at the step's start
    /// bounces by Newton's law, u_n⁺ = −e u_n⁻; slower, it comes to rest.
    pub(super) fn solve(
        &mut self,
        set: &StageSetting<'_>,
        paths: &Paths<'_>,
        h: f64,
        (v1, omega): (&[f64], &[f64]),
        x1: &mut [f64],
        threshold: f64,
        force_free: bool,
    ) -> Result<IslandStats, Error> {
        let (materials, inv_mass, domain) = (set.materials, set.inv_mass, set.domain);
        let x0 = paths.x0;
        let moved = |q: usize| domain.displacement(vec3::get(x1, q), vec3::get(x0, q));
        let euler_step = |q: usize| vec3::scale(h, vec3::get(v1, q));
        // Each contact's warm start: its record's total, read (`collide/records.rs`).
        self.records.match_up(&self.contacts, &mut self.matched);
        let records = self.records.rows();
        self.solved.clear();
        self.solved
            .extend(self.matched.iter().map(|m| m.map_or([0.0; 3], |k| records[k].impulse)));
        let mut resting = self.resting_particles(set, paths, h, &moved, &euler_step);
        // Each particle's displacement over the step as the solve sees it: a particle in
        // resting contact moves by symplectic Euler, as in Box2D (x = x₀ + h v: held at v = 0
        // it stays where it was, whatever the method); any other as it was integrated (the
        // method's own accuracy, an impact's exact path).
        let base = |q: usize| if resting.get(q) { euler_step(q) } else { moved(q) };
        self.prepared.clear();
        self.prepared.extend(self.contacts.iter().map(|c| {
            let n = c.normal;
            let start = -c.overlap - vec3::dot(relative(c, &moved, h), n);
            let u1 = relative(c, &|q| vec3::get(v1, q), 1.0);
            let u_pre = vec3::dot(relative(c, &|q| paths.reference_velocity(q), 1.0), n);
            let bounce = bounces(u_pre, threshold).then(|| -materials.pair(c).restitution() * u_pre);
            Target::new(start, slop(set.radius, c), relative(c, &base, h), u1, n, h, bounce)
        }));
        // What moving by symplectic Euler adds to the integrated position of each particle in
        // resting contact.
        let euler: Vec<(usize, [f64; 3])> = resting
            .sorted()
            .iter()
            .filter(|&&q| inv_mass[q] > 0.0)
            .map(|&q| (q, vec3::sub(euler_step(q), moved(q))))
            .collect();
        self.totals.clear();
        self.totals.resize(self.contacts.len(), [0.0; 3]);
        if self.contacts.is_empty() {
            self.islands = Islands::default();
            self.kicks.clear();
            self.acted.reset(inv_mass.len(), false);
            self.scratch = resting;
            self.records.clear();
            let mut done = IslandStats::default();
            done.soft.converged = true;
            return Ok(done);
        }
        let problem = EndProblem {
            contacts: &self.contacts,
            targets: &self.prepared,
            inv_mass,
            materials,
            spin: set.rotation.map(|r| (r, omega)),
            rolling: set.rolling_friction,
            shock: (set.accuracy == Accuracy::Animation).then_some(paths.accel),
            params: soft_params(set.accuracy, h),
        };
        self.islands = Islands::find_with(&self.contacts, inv_mass, &mut self.forest);
        // Each contact's check that the solve would leave it alone (most of a gas's contacts)
        let spin = set.rotation.map(|r| (r, omega));
        let idle: Vec<bool> = (&self.contacts, &self.prepared, &self.solved)
            .into_par_iter()
            .with_min_len(CHUNK)
            .map(|(c, t, w)| soft_step::idle(c, t, *w, inv_mass, spin, v1, h))
            .collect();
        let idle = self.islands.all_of(&idle);
        let stats = islands::solve(
            &self.islands,
            &idle,
            &problem,
            &mut self.solved,
            &mut self.totals,
            &mut self.rolls,
            &mut self.kicks,
            v1,
            x1,
        )?;
        for &(q, c) in &euler {
            vec3::add_scaled(x1, q, 1.0, c);
        }
        self.mark_acted(resting, inv_mass.len());
        self.keep_records(set.radius, &idle, force_free);
        Ok(stats)
    }

    /// The particles in resting contact at the step's end (in the stage's scratch flags,
    /// which [`ImpulseModel::mark_acted`] gives back): `moved` and `euler_step` give each
    /// particle's integrated displacement over the step and the one symplectic Euler makes.
    fn resting_particles(
        &mut self,
        set: &StageSetting<'_>,
        paths: &Paths<'_>,
        h: f64,
        moved: &dyn Fn(usize) -> [f64; 3],
        euler_step: &dyn Fn(usize) -> [f64; 3],
    ) -> Marks {
        let inv_mass = set.inv_mass;
        // The particles in resting contact: named by a contact that bore load in the last
        // step, or that the step would close beyond what its target allows (moving by
        // symplectic Euler, below). No impact hit them in this step.
        let mut resting = std::mem::take(&mut self.scratch);
        resting.reset(inv_mass.len(), false);
        // A particle touching a resting one (within the slop, by a contact that bore no load
        // in the last step) rests too: a column placed at rest on a floor then moves as one by
        // symplectic Euler from its first step, as it will in every step after, so that the
        // first step's totals are the next step's warm start (each ball moved by the method
        // in the first step and by Euler in the second asked the solve of the second for
        // another load, which it took up over several steps, booking up to 1e-6 of the
        // column's energy as lost). Such contacts are gathered here, then spread over in
        // passes until nothing changes: as many as the chain of them is long.
        let mut touching: Vec<(usize, usize)> = Vec::new();
        for (c, warm) in self.contacts.iter().zip(&self.solved) {
            let start = -c.overlap - vec3::dot(relative(c, moved, h), c.normal);
            let least = start.min(0.0);
            let closes = start + vec3::dot(relative(c, euler_step, h), c.normal) < least;
            if *warm != [0.0; 3] || closes {
                for q in std::iter::once(c.i).chain(c.partner_particle()) {
                    if paths.version(q) == 0 {
                        resting.mark(q);
                    }
                }
            } else if let Some(j) = c.partner_particle() {
                let slop = SLOP * (set.radius[c.i] + set.radius[j]);
                if start <= slop && paths.version(c.i) == 0 && paths.version(j) == 0 {
                    touching.push((c.i, j));
                }
            }
        }
        let mut spread = true;
        while spread {
            spread = false;
            for &(i, j) in &touching {
                if resting.get(i) != resting.get(j) {
                    resting.mark(i);
                    resting.mark(j);
                    spread = true;
                }
            }
        }
        resting
    }

    /// Marks what the stage acted on (for the energy lost) among the `n` particles, and
    /// gives the scratch flags `resting` back.
    fn mark_acted(&mut self, mut resting: Marks, n: usize) {
        // moved by symplectic Euler, or pushed
        self.acted.reset(n, false);
        for &q in resting.sorted() {
            self.acted.mark(q);
        }
        self.scratch = resting;
        for &(q, _) in &self.kicks {
            self.acted.mark(q);
        }
        for (c, (p, s)) in self.contacts.iter().zip(self.totals.iter().zip(&self.solved)) {
            if *p != [0.0; 3] || *s != [0.0; 3] {
                self.acted.mark(c.i);
                if let Some(j) = c.partner_particle() {
                    self.acted.mark(j);
                }
            }
        }
    }

    /// The step's records from its contacts, solved totals and totals (`radius`: the
    /// particles' radii; `idle`: each island's check that the solve left it alone).
    fn keep_records(&mut self, radius: &[f64], idle: &[bool], force_free: bool) {
        // The contacts the next step keeps (its warm start, and the particles it looks at
        // first). In a force-free world, a contact of an island the solve left alone, apart
        // beyond the slop and separating, is not kept: it bears nothing, its particles move
        // on straight lines that part, and the next step finds the pair again if continuous
        // detection sees either of them hit or a kept contact reaches them. In a gas that is
        // nearly every contact, and the next step's work then follows the contacts that act.
        // (Under forces a parting pair may turn back within the step, a pile's contact under
        // gravity: every contact is kept, as the pile's solve needs them.)
        let mut kept = vec![true; self.contacts.len()];
        if force_free {
            for k in (0..self.islands.len()).filter(|&k| idle[k]) {
                for &c in self.islands.island(k) {
                    let t = &self.prepared[c];
                    kept[c] = !(t.gap > slop(radius, &self.contacts[c]) && t.u_n >= 0.0);
                }
            }
        }
        self.records.replace(&self.contacts, &self.solved, &self.totals, &kept);
    }

    /// The largest overlap of the end-of-step contacts at the positions `x1` the step leaves
    /// (m, 0 if none): each pair's r_i + r_j − |x_i − x_j| and each collider contact's depth,
    /// measured again (the particles no contact names had no meeting in the step).
    pub(super) fn max_overlap(&self, set: &StageSetting<'_>, x1: &[f64]) -> f64 {
        self.contacts
            .iter()
            .map(|c| match c.other {
                // a mesh's from the triangles end_contacts kept near the particle (the same
                // overlap: `mesh::NearCache`)
                Partner::Collider(k) if matches!(set.colliders[k], Collider::Mesh(_)) => {
                    let walls = &self.list.walls;
                    let w = walls.partition_point(|&w| w < (c.i, k));
                    let mut cache = self.near_meshes.get(w).cloned().unwrap_or_default();
                    collider_overlap(
                        set.colliders,
                        set.domain,
                        vec3::get(x1, c.i),
                        set.radius[c.i],
                        c.i,
                        k,
                        Some(&mut cache),
                    )
                }
                _ => deepest(set, x1, c.i, c.other),
            })
            .fold(0.0, f64::max)
    }

    /// The mechanical energy the end-of-step stage took, J, over the particles it acted on
    /// (moved by symplectic Euler in resting contact, or pushed by a nonzero total): each one's kinetic energy at its reference state minus
    /// now, minus the work the step's forces (`accel`: their accelerations over the step) did
    /// since: Σ ½ m (|v_b|² − |v|²) + Σ m a·(x − x_b). The reference is the step's start for a
    /// particle no impact hit, so a body held at rest books exactly 0 with every method (it
    /// ends the step where and as it began); an impact inside the step books its own
    /// ½ (1 − e²) μ u_n², exactly 0 for e = 1.
    ///
    /// With spin, each one's rotational energy at its reference minus now is added,
    /// Σ ½ I (|ω_b|² − |ω|²) (stage 1 does not turn a particle: no work to subtract).
    pub(super) fn energy_lost(&self, set: &StageSetting<'_>, accel: &[f64], x1: &[f64], v1: &[f64], omega: &[f64]) -> f64 {
        let (mass, inv_mass) = (set.mass, set.inv_mass);
        let mut lost = 0.0;
        for (k, &(q, xb, vb)) in self.references.iter().enumerate() {
            if inv_mass[q] == 0.0 || !self.acted.get(q) {
                continue;
            }
            let (x, v, a) = (vec3::get(x1, q), vec3::get(v1, q), vec3::get(accel, q));
            let dx = set.domain.displacement(x, xb);
            lost += 0.5 * mass[q] * (vec3::dot(vb, vb) - vec3::dot(v, v)) + mass[q] * vec3::dot(a, dx);
            if let Some(r) = set.rotation.filter(|r| r.inv_inertia[q] > 0.0) {
                let (wb, w) = (self.references_spin[k], vec3::get(omega, q));
                lost += 0.5 * (vec3::dot(wb, wb) - vec3::dot(w, w)) / r.inv_inertia[q];
            }
        }
        lost
    }
}

/// The overlap of particle i with `other` at positions `x` (m; ≤ 0 apart): r_i + r_j −
/// |x_i − x_j| for a pair, the deepest touch of a collider (walls along periodic axes left
/// out), 0 if none.
pub(crate) fn deepest(set: &StageSetting<'_>, x: &[f64], i: usize, other: Partner) -> f64 {
    overlap_at(set.radius, set.colliders, set.domain, x, i, other)
}

/// [`deepest`] from the parts a world has between steps (a checkpoint's islands asleep).
pub(crate) fn overlap_at(radius: &[f64], colliders: &[Collider], domain: &Domain, x: &[f64], i: usize, other: Partner) -> f64 {
    match other {
        Partner::Particle(j) => {
            let d = domain.displacement(vec3::get(x, i), vec3::get(x, j));
            radius[i] + radius[j] - vec3::norm(d)
        }
        Partner::Collider(k) => collider_overlap(colliders, domain, vec3::get(x, i), radius[i], i, k, None),
    }
}

/// The deepest overlap of particle i (centre `p`, radius `r`, m) with collider k, m (0 if
/// none); with `near`, a mesh's from the triangles it keeps where they answer
/// (`mesh::NearCache`).
fn collider_overlap(
    colliders: &[Collider],
    domain: &Domain,
    p: [f64; 3],
    r: f64,
    i: usize,
    k: usize,
    near: Option<&mut NearCache>,
) -> f64 {
    let mut deepest: f64 = 0.0;
    let mut each = |t: Touch| {
        let c = Contact {
            i,
            other: Partner::Collider(k),
            normal: t.normal,
            overlap: t.overlap,
            u_n: 0.0,
            wall_velocity: [0.0; 3],
        };
        if !on_periodic_wall(&c, colliders, domain) {
            deepest = deepest.max(t.overlap);
        }
    };
    match near {
        Some(near) => colliders[k].for_each_touch_near(p, r, 0.0, near, &mut each),
        None => colliders[k].for_each_touch(p, r, 0.0, &mut each),
    }
    deepest
}

/// Stage 4 for one impulse: J on particle i (+w_i J to its velocity) and −J on its partner
/// particle (−w_j J), in `v`; adds to `balance` what the two movable sides received, m Δv
/// (Σ over both: zero by action and reaction, to rounding). An impulse from a collider or a
/// pinned particle comes from outside the movable particles and is not part of the balance.
pub(super) fn distribute(
    i: usize,
    j: Option<usize>,
    impulse: [f64; 3],
    v: &mut [f64],
    inv_mass: &[f64],
    mass: &[f64],
    balance: &mut [f64; 3],
) {
    let (wi, wj) = (inv_mass[i], j.map_or(0.0, |j| inv_mass[j]));
    action_reaction(v, i, j, (wi, wj), impulse);
    if let Some(j) = j {
        if wi > 0.0 && wj > 0.0 {
            for k in 0..3 {
                balance[k] += mass[i] * (wi * impulse[k]) - mass[j] * (wj * impulse[k]);
            }
        }
    }
}
