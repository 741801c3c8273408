//! Independent groups of end-of-step contacts (islands), solved on all threads.
//!
//! Two contacts are in one island when they share a movable particle. A collider or a
//! pinned particle joins nothing: its velocity and position never change, so what one
//! contact does to it cannot reach another (Box2D's static bodies). The soft step
//! ([`soft_step`](super::soft_step)) of one island never reads what another writes, so each
//! island is a problem of its own: its
//! particles are gathered into small arrays, solved, and the results scattered back. The
//! islands are solved on rayon's threads, a batch of them per task.
//!
//! One island of many contacts (a heap is one) is parallel inside by colouring, as Box2D v3's
//! solver colours its constraint graph: in the island's contact order each contact takes the
//! first colour that neither of its movable particles has yet (64 colours; a contact that
//! finds none goes to a last group visited in order, Box2D's overflow). The contacts of one
//! colour share no movable particle, so a pass visits the colours in turn and all the
//! contacts of one colour at once. Such an island is swept in colour order rather than in
//! contact order: Gauss–Seidel all the same, converging alike.
//!
//! Determinism: the islands, their order (by first contact) and the colours are functions of
//! the contact list alone, each island is solved the same way on any thread (a coloured pass
//! gives what the same pass gives in order), and the islands' figures are combined in island
//! order. The result is bit for bit the same for any thread count.

use rayon::prelude::*;

use super::contact::{Contact, Partner};
use super::passes::PassGroup;
use super::response::{Material, MaterialTable};
use super::soft_step::{soft_step, SoftContacts, SoftParams, SoftStats, Target};
use super::spin::Rotation;
use crate::error::Error;
use crate::vec3;

/// Islands of at least this many contacts are coloured (smaller ones are swept in contact
/// order: a colour of theirs would be too small to share among threads).
const COLOUR_FROM: usize = 512;

/// Islands are handed to the threads in batches of at least this many contacts.
const BATCH: usize = 256;

/// The passes of an island that starts cold (no contact of it loaded in the last step), as a
/// multiple of the usual cap.
const COLD_PASSES: usize = 10;

/// The end-of-step contacts split into islands.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Islands {
    /// The contacts' indices, island after island, each island's in list order (a contact
    /// of two immovable bodies is in none).
    members: Vec<usize>,
    /// Island k is `members[starts[k]..starts[k + 1]]`.
    starts: Vec<usize>,
}

/// The union–find arrays of [`Islands::find_with`], one entry per particle: each particle's
/// parent (itself between calls) and its tree's island (`u32::MAX` between calls).
#[derive(Debug, Default, Clone)]
pub(crate) struct Forest {
    parent: Vec<u32>,
    label: Vec<u32>,
}

impl Forest {
    /// Sized for `n` particles (resized only when the count changed).
    fn reset(&mut self, n: usize) {
        if self.parent.len() != n {
            self.parent.clear();
            self.parent.extend(0..n as u32);
            self.label.clear();
            self.label.resize(n, u32::MAX);
        }
    }
}

impl Islands {
    /// The islands of `contacts` in a world with these inverse masses (0: pinned), numbered
    /// in the order of their first contact; a contact of two immovable bodies is in none.
    #[cfg(test)]
    pub fn find(contacts: &[Contact], inv_mass: &[f64]) -> Islands {
        Islands::find_with(contacts, inv_mass, &mut Forest::default())
    }

    /// [`Islands::find`] with the union–find's arrays of a [`Forest`] kept from step to step
    /// (each touched entry is put back after use: the work follows the contacts, not N).
    pub fn find_with(contacts: &[Contact], inv_mass: &[f64], forest: &mut Forest) -> Islands {
        // A union–find over the contacts' movable particles, by their index (the lower index
        // is the root: each tree's root is its least particle, the same forest for the same
        // list whatever the order of the unions).
        let movable = |q: usize| inv_mass[q] > 0.0;
        forest.reset(inv_mass.len());
        let Forest { parent, label } = forest;
        fn root(parent: &mut [u32], mut a: u32) -> u32 {
            while parent[a as usize] != a {
                parent[a as usize] = parent[parent[a as usize] as usize]; // path halving
                a = parent[a as usize];
            }
            a
        }
        for c in contacts {
            if let (true, Some(j)) = (movable(c.i), c.partner_particle().filter(|&j| movable(j))) {
                let (ra, rb) = (root(parent, c.i as u32), root(parent, j as u32));
                parent[ra.max(rb) as usize] = ra.min(rb);
            }
        }
        // Each contact's island: that of its movable side (a contact of two immovable bodies,
        // which the solvers skip, is in none).
        let mut count = 0;
        let labels: Vec<Option<usize>> = contacts
            .iter()
            .map(|c| {
                let side = Some(c.i)
                    .filter(|&q| movable(q))
                    .or_else(|| c.partner_particle().filter(|&q| movable(q)))?;
                let r = root(parent, side as u32) as usize;
                if label[r] == u32::MAX {
                    label[r] = count as u32;
                    count += 1;
                }
                Some(label[r] as usize)
            })
            .collect();
        // (the arrays back as they were: each particle its own root, no label)
        for c in contacts {
            for q in std::iter::once(c.i).chain(c.partner_particle()) {
                parent[q] = q as u32;
                label[q] = u32::MAX;
            }
        }
        // Counting sort by island, stable: each island's contacts stay in list order.
        let mut starts = vec![0; count + 1];
        for &l in labels.iter().flatten() {
            starts[l + 1] += 1;
        }
        for k in 0..count {
            starts[k + 1] += starts[k];
        }
        let mut fill = starts.clone();
        let mut members = vec![0; starts[count]];
        for (c, l) in labels.iter().enumerate() {
            if let Some(l) = *l {
                members[fill[l]] = c;
                fill[l] += 1;
            }
        }
        Islands { members, starts }
    }

    /// Which islands have only contacts marked in `idle` (one flag per contact; an island
    /// none of whose contacts acts, [`soft_step::idle`](super::soft_step::idle)).
    pub fn all_of(&self, idle: &[bool]) -> Vec<bool> {
        (0..self.len()).map(|k| self.island(k).iter().all(|&c| idle[c])).collect()
    }

    /// The number of islands.
    #[allow(clippy::len_without_is_empty)]
    pub fn len(&self) -> usize {
        self.starts.len().saturating_sub(1)
    }

    /// The contacts of island `k`, in list order.
    pub fn island(&self, k: usize) -> &[usize] {
        &self.members[self.starts[k]..self.starts[k + 1]]
    }
}

/// The end-of-step problem the islands split: the contacts, each one's targets
/// (`collide/soft_step.rs`), the particles' inverse masses (1/kg), the materials and, with
/// spin, the particles' rotation and angular velocities (rad/s, 3 per particle).
pub(crate) struct EndProblem<'a> {
    pub contacts: &'a [Contact],
    pub targets: &'a [Target],
    pub inv_mass: &'a [f64],
    pub materials: MaterialTable<'a>,
    pub spin: Option<(Rotation<'a>, &'a [f64])>,
    /// Rolling resistance μ_r (with spin).
    pub rolling: f64,
    /// With shock propagation (`collide/shock.rs`): each particle's acceleration, m/s² (3
    /// per particle).
    pub shock: Option<&'a [f64]>,
    pub params: SoftParams,
}

/// What the islands' solves did, combined: the most passes of each stage, converged if all
/// did, the active and bounced contacts added.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct IslandStats {
    pub soft: SoftStats,
    /// The islands.
    pub islands: usize,
}

/// The islands' soft steps (`collide/soft_step.rs`), each island on its own copy of its
/// particles. `solved` holds each contact's starting total (the warm start) on entry and its
/// solve stage's total on return; `totals` receives each contact's final total impulse on i
/// (N·s; the caller applies them to the velocities, `v` is not changed); the positions `x`
/// are moved in place by what the solve stage did. With rolling resistance, `rolls` receives
/// each contact's angular impulse on i (N·m·s; left empty without). With shock propagation,
/// `kicks` receives the velocity change of each particle the shock stages moved (m/s, then
/// with spin rad/s), which no total holds (also applied by the caller).
///
/// An island marked in `idle` (one flag per island: all its contacts idle,
/// [`Islands::all_of`] of [`soft_step::idle`](super::soft_step::idle): no warm start, targets
/// met by the velocities as they are) is not gathered nor solved: its soft step would give
/// exactly nothing. In a gas nearly every island is such a pair
/// (speculative contacts that do not close), and the step's cost then follows the contacts
/// that act.
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve(
    islands: &Islands,
    idle: &[bool],
    problem: &EndProblem<'_>,
    solved: &mut [[f64; 3]],
    totals: &mut [[f64; 3]],
    rolls: &mut Vec<[f64; 3]>,
    kicks: &mut Vec<(usize, [f64; 6])>,
    v: &[f64],
    x: &mut [f64],
) -> Result<IslandStats, Error> {
    // Batches of consecutive islands, each solved in turn by one task.
    let mut batches = Vec::new();
    let mut first = 0;
    for k in 0..islands.len() {
        if islands.starts[k + 1] - islands.starts[first] >= BATCH || k + 1 == islands.len() {
            batches.push(first..k + 1);
            first = k + 1;
        }
    }
    let seen: &[f64] = x;
    let warm: &[[f64; 3]] = solved;
    let results: Vec<Result<Vec<Solved>, Error>> = batches
        .into_par_iter()
        .map(|batch| {
            let mut local = Local::default();
            batch
                .filter(|&k| !idle[k])
                .map(|k| local.solve(islands.island(k), problem, warm, v, seen))
                .collect()
        })
        .collect();
    let any_idle = idle.iter().any(|&i| i);
    // Scattered back, and the figures combined, in island order (a contact in no island, of
    // two immovable bodies, bears nothing).
    solved.fill([0.0; 3]);
    totals.fill([0.0; 3]);
    rolls.clear();
    kicks.clear();
    if problem.spin.is_some() && problem.rolling > 0.0 {
        rolls.resize(totals.len(), [0.0; 3]);
    }
    // (an idle island's soft step is one pass of each of the solve and relax stages that
    // changes nothing)
    let mut stats = IslandStats {
        islands: islands.len(),
        soft: SoftStats {
            converged: true,
            passes: usize::from(any_idle),
            relax_passes: usize::from(any_idle),
            ..SoftStats::default()
        },
    };
    for island in results.into_iter().collect::<Result<Vec<_>, _>>()?.into_iter().flatten() {
        for ((&c, p), s) in island.order.iter().zip(&island.totals).zip(&island.solved) {
            totals[c] = *p;
            solved[c] = *s;
        }
        for (&c, m) in island.order.iter().zip(&island.rolls) {
            rolls[c] = *m;
        }
        for (&q, p) in island.moved.iter().zip(&island.positions) {
            x[3 * q..3 * q + 3].copy_from_slice(p);
        }
        kicks.extend(island.moved.iter().copied().zip(island.kicks));
        let (s, all) = (island.soft, &mut stats.soft);
        all.passes = all.passes.max(s.passes);
        all.converged &= s.converged;
        all.relax_passes = all.relax_passes.max(s.relax_passes);
        all.restitution_passes = all.restitution_passes.max(s.restitution_passes);
        all.active += s.active;
        all.bounced += s.bounced;
    }
    Ok(stats)
}

/// One impulse (N·s, or N·m·s) per contact.
type Impulses = Vec<[f64; 3]>;

/// One island's results: its contacts in the order solved, their final and solve-stage
/// totals; its movable particles and their new positions; the solver's figures.
struct Solved {
    order: Vec<usize>,
    totals: Vec<[f64; 3]>,
    rolls: Vec<[f64; 3]>,
    solved: Vec<[f64; 3]>,
    moved: Vec<usize>,
    positions: Vec<[f64; 3]>,
    /// With shock propagation, the moved particles' kicks (velocity, then angular velocity).
    kicks: Vec<[f64; 6]>,
    soft: SoftStats,
}

/// The gathered copy of one island (buffers reused from island to island of a batch).
#[derive(Default)]
struct Local {
    particles: Vec<usize>,
    contacts: Vec<Contact>,
    targets: Vec<Target>,
    v: Vec<f64>,
    x: Vec<f64>,
    inv_mass: Vec<f64>,
    materials: Vec<Material>,
    groups: Vec<PassGroup>,
    /// With spin: the particles' inverse inertias and radii.
    inv_inertia: Vec<f64>,
    radius: Vec<f64>,
    /// With shock propagation: the particles' accelerations.
    accel: Vec<f64>,
}

impl Local {
    /// The soft step of one island (contacts `island` of the problem's), on copies of its
    /// particles numbered by rank: `warm` each contact's warm start, `v` and `x` the
    /// velocities and positions of all particles.
    fn solve(
        &mut self,
        island: &[usize],
        problem: &EndProblem<'_>,
        warm: &[[f64; 3]],
        v: &[f64],
        x: &[f64],
    ) -> Result<Solved, Error> {
        self.copy_particles(island, problem, v, x);
        let order = self.copy_contacts(island, problem);
        let mut materials = problem.materials;
        if let Some(m) = problem.materials.particles {
            self.materials.clear();
            self.materials.extend(self.particles.iter().map(|&q| m[q]));
            materials = materials.with_particles(&self.materials);
        }
        let mut solved: Vec<[f64; 3]> = order.iter().map(|&c| warm[c]).collect();
        let mut totals = Vec::new();
        // An island none of whose contacts held a load in the last step (a stack placed at
        // rest, a pile made at once) starts from nothing: it gets COLD_PASSES times the passes,
        // so that it takes up its load in its first step instead of sinking over the next ones
        // (what sinks is booked as lost: an elastic column of 10 lost 1.5e-6 of its energy, one
        // of 30 1.7e-5). A warm island starts from the last step's totals and needs few.
        let mut params = problem.params;
        if solved.iter().all(|s| *s == [0.0; 3]) {
            params.solve_passes *= COLD_PASSES;
            params.relax_passes *= COLD_PASSES;
        }
        let held = SoftContacts {
            contacts: &self.contacts,
            targets: &self.targets,
            inv_mass: &self.inv_mass,
            materials: &materials,
            rotation: problem.spin.is_some().then_some(Rotation {
                inv_inertia: &self.inv_inertia,
                radius: &self.radius,
            }),
            rolling: problem.rolling,
            shock: problem.shock.map(|_| self.accel.as_slice()),
        };
        let (v, x, groups) = (&mut self.v, &mut self.x, &self.groups);
        let (mut rolls, mut kicks) = (Vec::new(), Vec::new());
        let out = (&mut solved, &mut totals, &mut rolls, &mut kicks);
        let soft = match held.rotation {
            Some(_) => soft_step::<6>(held, &params, v, x, out.0, out.1, out.2, out.3, groups)?,
            None => soft_step::<3>(held, &params, v, x, out.0, out.1, out.2, out.3, groups)?,
        };
        let width = if held.rotation.is_some() { 6 } else { 3 };
        Ok(self.solved(order, (solved, totals, rolls), &kicks, width, soft))
    }

    /// The island's particles, numbered by rank, and their copies: velocities (with spin,
    /// each particle's velocity and angular velocity, 6 values), positions, inverse masses,
    /// with spin the inverse inertias and radii, with shock propagation the accelerations.
    fn copy_particles(&mut self, island: &[usize], problem: &EndProblem<'_>, v: &[f64], x: &[f64]) {
        let all = problem.contacts;
        self.particles.clear();
        self.particles.extend(
            island
                .iter()
                .flat_map(|&c| std::iter::once(all[c].i).chain(all[c].partner_particle())),
        );
        self.particles.sort_unstable();
        self.particles.dedup();
        let parts = &self.particles;
        let gather = |out: &mut Vec<f64>, from: &[f64]| {
            out.clear();
            out.extend(parts.iter().flat_map(|&q| vec3::get(from, q)));
        };
        match problem.spin {
            // with spin, each particle's velocity and angular velocity, 6 values
            Some((_, omega)) => {
                self.v.clear();
                self.v.extend(
                    parts
                        .iter()
                        .flat_map(|&q| vec3::get(v, q).into_iter().chain(vec3::get(omega, q))),
                );
            }
            None => gather(&mut self.v, v),
        }
        gather(&mut self.x, x);
        self.inv_mass.clear();
        self.inv_mass.extend(parts.iter().map(|&q| problem.inv_mass[q]));
        if let Some((r, _)) = problem.spin {
            self.inv_inertia.clear();
            self.inv_inertia.extend(parts.iter().map(|&q| r.inv_inertia[q]));
            self.radius.clear();
            self.radius.extend(parts.iter().map(|&q| r.radius[q]));
        }
        if let Some(a) = problem.shock {
            gather(&mut self.accel, a);
        }
    }

    /// The island's contacts in the order of their pass (by colour when coloured), on the
    /// copies, with their targets; returns that order (indices into the problem's contacts).
    fn copy_contacts(&mut self, island: &[usize], problem: &EndProblem<'_>) -> Vec<usize> {
        let all = problem.contacts;
        let parts = &self.particles;
        let local = |q: usize| parts.binary_search(&q).expect("an island's contact names its particles");
        let order = colour(island, all, &self.inv_mass, local, &mut self.groups);
        self.contacts.clear();
        self.contacts.extend(order.iter().map(|&c| {
            let c = all[c];
            Contact {
                i: local(c.i),
                other: match c.other {
                    Partner::Particle(j) => Partner::Particle(local(j)),
                    other => other,
                },
                ..c
            }
        }));
        self.targets.clear();
        self.targets.extend(order.iter().map(|&c| problem.targets[c]));
        order
    }

    /// What the island's soft step gives back for the movable particles, in the problem's
    /// numbering: the contacts' totals in `order`, the positions, the shock stages' kicks
    /// (`width` values a particle).
    fn solved(
        &self,
        order: Vec<usize>,
        (solved, totals, rolls): (Impulses, Impulses, Impulses),
        kicks: &[f64],
        width: usize,
        soft: SoftStats,
    ) -> Solved {
        let parts = &self.particles;
        let moved: Vec<usize> = (0..parts.len()).filter(|&l| self.inv_mass[l] > 0.0).collect();
        let kicks = if kicks.is_empty() {
            Vec::new()
        } else {
            moved
                .iter()
                .map(|&l| std::array::from_fn(|d| if d < width { kicks[width * l + d] } else { 0.0 }))
                .collect()
        };
        Solved {
            order,
            totals,
            rolls,
            solved,
            positions: moved.iter().map(|&l| vec3::get(&self.x, l)).collect(),
            moved: moved.iter().map(|&l| parts[l]).collect(),
            kicks,
            soft,
        }
    }
}

/// The island's contacts in the order of their pass, with its pass groups in `groups`: in
/// list order as one group below [`COLOUR_FROM`] contacts; else colour after colour (greedy,
/// in list order, over the movable particles: `inv_mass` of the island's particles, which
/// `local` numbers), then the contacts that found no colour, in order.
fn colour(
    island: &[usize],
    all: &[Contact],
    inv_mass: &[f64],
    local: impl Fn(usize) -> usize,
    groups: &mut Vec<PassGroup>,
) -> Vec<usize> {
    groups.clear();
    if island.len() < COLOUR_FROM {
        groups.push(PassGroup::in_order(0..island.len()));
        return island.to_vec();
    }
    const OVERFLOW: usize = 64;
    // The colours each movable particle has taken, as a bit set.
    let mut taken = vec![0u64; inv_mass.len()];
    let colours: Vec<usize> = island
        .iter()
        .map(|&k| {
            let c = &all[k];
            let sides = [Some(local(c.i)), c.partner_particle().map(&local)];
            let movable = sides.into_iter().flatten().filter(|&l| inv_mass[l] > 0.0);
            let free = (!movable.clone().fold(0, |m, l| m | taken[l])).trailing_zeros() as usize;
            if free < OVERFLOW {
                movable.for_each(|l| taken[l] |= 1 << free);
            }
            free.min(OVERFLOW)
        })
        .collect();
    // Counting sort by colour, stable.
    let mut starts = [0usize; OVERFLOW + 2];
    for &c in &colours {
        starts[c + 1] += 1;
    }
    for c in 0..=OVERFLOW {
        starts[c + 1] += starts[c];
    }
    let mut fill = starts;
    let mut order = vec![0; island.len()];
    for (&k, &c) in island.iter().zip(&colours) {
        order[fill[c]] = k;
        fill[c] += 1;
    }
    for c in (0..=OVERFLOW).filter(|&c| starts[c + 1] > starts[c]) {
        groups.push(PassGroup {
            range: starts[c]..starts[c + 1],
            together: c < OVERFLOW,
        });
    }
    order
}

#[cfg(test)]
#[path = "tests/islands.rs"]
mod tests;
