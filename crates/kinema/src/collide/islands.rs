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
    fn solve(
        &mut self,
        island: &[usize],
        problem: &EndProblem<'_>,
        warm: &[[f64; 3]],
        v: &[f64],
        x: &[f64],
    ) -> Result<Solved, Error> {
        let all = problem.contacts;
        // The island's particles, numbered by rank, and their copies.
        self.particles.clear();
        self.particles.extend(
            island
                .iter()
                .flat_map(|&c| std::iter::once(all[c].i).chain(all[c].partner_particle())),
        );
        self.particles.sort_unstable();
        self.particles.dedup();
        let parts = &self.particles;
        let local = |q: usize| parts.binary_search(&q).expect("an island's contact names its particles");
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
        let mut materials = problem.materials;
        if let Some(m) = problem.materials.particles {
            self.materials.clear();
            self.materials.extend(parts.iter().map(|&q| m[q]));
            materials = materials.with_particles(&self.materials);
        }
        // Its contacts in the order of their pass (by colour when coloured), on the copies.
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
        if let Some((r, _)) = problem.spin {
            self.inv_inertia.clear();
            self.inv_inertia.extend(parts.iter().map(|&q| r.inv_inertia[q]));
            self.radius.clear();
            self.radius.extend(parts.iter().map(|&q| r.radius[q]));
        }
        if let Some(a) = problem.shock {
            gather(&mut self.accel, a);
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
        let moved: Vec<usize> = (0..parts.len()).filter(|&l| self.inv_mass[l] > 0.0).collect();
        let width = if held.rotation.is_some() { 6 } else { 3 };
        let kicks = if kicks.is_empty() {
            Vec::new()
        } else {
            moved
                .iter()
                .map(|&l| std::array::from_fn(|d| if d < width { kicks[width * l + d] } else { 0.0 }))
                .collect()
        };
        Ok(Solved {
            order,
            totals,
            rolls,
            solved,
            positions: moved.iter().map(|&l| vec3::get(&self.x, l)).collect(),
            moved: moved.iter().map(|&l| parts[l]).collect(),
            kicks,
            soft,
        })
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
mod tests {
    use super::super::colliders::{Collider, Plane, Surface};
    use super::*;
    use crate::collide::passes::PARALLEL_COLOUR;

    fn floor() -> Vec<Collider> {
        vec![Collider::Plane(
            Plane::new([0.0, 0.0, -0.5], [0.0, 0.0, 1.0], Surface::default()).unwrap(),
        )]
    }

    /// A cubic block of nx·ny·nz touching unit-mass balls (radius ½, spacing 1) on a floor at
    /// z = −½, all falling at 1 m/s (overlapping the floor by `sink` m): its contacts (each
    /// touching pair once, lower index first, then the floor) and its velocities.
    fn block(nx: usize, ny: usize, nz: usize, sink: f64) -> (Vec<Contact>, Vec<f64>, Vec<f64>) {
        let id = |x: usize, y: usize, z: usize| (z * ny + y) * nx + x;
        let n = nx * ny * nz;
        let mut contacts = Vec::new();
        let pair = |i, j, normal| Contact {
            i,
            other: Partner::Particle(j),
            normal,
            overlap: 0.0,
            u_n: 0.0,
            wall_velocity: [0.0; 3],
        };
        for z in 0..nz {
            for y in 0..ny {
                for x in 0..nx {
                    let i = id(x, y, z);
                    if x + 1 < nx {
                        contacts.push(pair(i, id(x + 1, y, z), [-1.0, 0.0, 0.0]));
                    }
                    if y + 1 < ny {
                        contacts.push(pair(i, id(x, y + 1, z), [0.0, -1.0, 0.0]));
                    }
                    if z + 1 < nz {
                        contacts.push(pair(i, id(x, y, z + 1), [0.0, 0.0, -1.0]));
                    }
                }
            }
        }
        for i in (0..nx * ny).map(|q| id(q % nx, q / nx, 0)) {
            contacts.push(Contact {
                i,
                other: Partner::Collider(0),
                normal: [0.0, 0.0, 1.0],
                overlap: sink,
                u_n: -1.0,
                wall_velocity: [0.0; 3],
            });
        }
        let v = (0..n).flat_map(|_| [0.0, 0.0, -1.0]).collect();
        let x = (0..n)
            .flat_map(|q| [(q % nx) as f64, (q / nx % ny) as f64, (q / (nx * ny)) as f64 - sink])
            .collect();
        (contacts, v, x)
    }

    const H: f64 = 1e-3;

    /// [`solve`] with no island left out as idle.
    fn solve_every_island(
        islands: &Islands,
        p: &EndProblem<'_>,
        solved: &mut [[f64; 3]],
        totals: &mut [[f64; 3]],
        v: &[f64],
        x: &mut [f64],
    ) -> IslandStats {
        solve(
            islands,
            &vec![false; p.contacts.len()],
            p,
            solved,
            totals,
            &mut Vec::new(),
            &mut Vec::new(),
            v,
            x,
        )
        .unwrap()
    }

    /// The soft-step targets of `block`'s contacts: a step of h in which every ball fell
    /// 1 m/s · h, ending `sink` into the floor (they started touching it).
    fn targets(contacts: &[Contact]) -> Vec<Target> {
        contacts
            .iter()
            .map(|c| {
                // relative to the floor each ball fell H in the step at 1 m/s, from touching it;
                // the pairs moved together
                let (fell, u1) = match c.partner_particle() {
                    None => ([0.0, 0.0, -H], [0.0, 0.0, -1.0]),
                    Some(_) => ([0.0; 3], [0.0; 3]),
                };
                Target::new(0.0, 0.0, fell, u1, c.normal, H, None)
            })
            .collect()
    }

    fn problem<'a>(
        contacts: &'a [Contact],
        targets: &'a [Target],
        inv_mass: &'a [f64],
        floor: &'a [Collider],
        passes: usize,
    ) -> EndProblem<'a> {
        EndProblem {
            contacts,
            targets,
            inv_mass,
            materials: MaterialTable::uniform(Material::new(0.0, 0.3).unwrap()).with_colliders(floor),
            spin: None,
            rolling: 0.0,
            shock: None,
            params: SoftParams {
                h: H,
                tolerance: 0.0,
                solve_passes: passes,
                relax_passes: passes,
            },
        }
    }

    #[test]
    fn contacts_join_through_movable_particles_only() {
        // 0–1–2 a chain; 3 pinned, touched by 4 and 5: they stay apart; 6 on a wall; 7–8 a
        // pair of two pinned particles, in no island. Islands by first contact.
        let c = |i, other| Contact {
            i,
            other,
            normal: [1.0, 0.0, 0.0],
            overlap: 0.0,
            u_n: 0.0,
            wall_velocity: [0.0; 3],
        };
        let p = Partner::Particle;
        let contacts = [
            c(4, p(3)),
            c(0, p(1)),
            c(3, p(5)),
            c(6, Partner::Collider(0)),
            c(1, p(2)),
            c(7, p(8)),
            c(2, Partner::Collider(0)),
        ];
        let mut inv_mass = vec![1.0; 9];
        for q in [3, 7, 8] {
            inv_mass[q] = 0.0;
        }
        let islands = Islands::find(&contacts, &inv_mass);
        let all: Vec<&[usize]> = (0..islands.len()).map(|k| islands.island(k)).collect();
        assert_eq!(all, [&[0][..], &[1, 4, 6], &[2], &[3]]);
    }

    #[test]
    fn islands_solve_what_one_solve_of_all_contacts_gives() {
        // Three small blocks (below the colouring size): solved island by island, each in list
        // order, they give the whole list's soft step bit for bit (fixed passes: tolerance 0 on
        // a problem that does not converge exactly). They start cold (no warm start), so each
        // gets COLD_PASSES times the passes.
        let (mut contacts, mut v, mut x) = (Vec::new(), Vec::new(), Vec::new());
        for b in 0..3 {
            let (c, bv, bx) = block(3, 3, 2 + b, 1e-3);
            let offset = v.len() / 3;
            contacts.extend(c.into_iter().map(|c| Contact {
                i: c.i + offset,
                other: match c.other {
                    Partner::Particle(j) => Partner::Particle(j + offset),
                    other => other,
                },
                ..c
            }));
            v.extend(bv);
            x.extend(bx);
        }
        // interleave the blocks' contacts in the list (sorted by particle, as the world's are)
        contacts.sort_by_key(|c| (c.i, c.other));
        let inv_mass = vec![1.0; v.len() / 3];
        let targets = targets(&contacts);
        let islands = Islands::find(&contacts, &inv_mass);
        assert_eq!(islands.len(), 3);
        let floor = floor();
        let p = problem(&contacts, &targets, &inv_mass, &floor, 7);
        let mut solved = vec![[0.0; 3]; contacts.len()];
        let mut totals = vec![[0.0; 3]; contacts.len()];
        let mut x_islands = x.clone();
        let stats = solve_every_island(&islands, &p, &mut solved, &mut totals, &v, &mut x_islands);
        assert_eq!((stats.soft.passes, stats.islands), (7 * COLD_PASSES, 3));

        let mut all_solved = vec![[0.0; 3]; contacts.len()];
        let mut all_totals = Vec::new();
        let (mut v_all, mut x_all) = (v.clone(), x.clone());
        let held = SoftContacts {
            contacts: &contacts,
            targets: &targets,
            inv_mass: &inv_mass,
            materials: &p.materials,
            rotation: None,
            rolling: 0.0,
            shock: None,
        };
        let in_order = [PassGroup::in_order(0..contacts.len())];
        let cold = SoftParams {
            solve_passes: 7 * COLD_PASSES,
            relax_passes: 7 * COLD_PASSES,
            ..p.params
        };
        soft_step::<3>(
            held,
            &cold,
            &mut v_all,
            &mut x_all,
            &mut all_solved,
            &mut all_totals,
            &mut Vec::new(),
            &mut Vec::new(),
            &in_order,
        )
        .unwrap();
        assert_eq!(totals, all_totals);
        assert_eq!(solved, all_solved);
        assert_eq!(x_islands, x_all);
        assert!(totals.iter().any(|t| t[2] != 0.0)); // the floor holds the blocks up
    }

    #[test]
    fn an_idle_island_is_left_out_and_the_solve_gives_the_same_bits() {
        // A block resting on a floor (an island that acts) beside pairs apart, each within
        // the speculative margin: one parting (idle: skipped), one closing within the step
        // beyond its target (acts), one approaching slowly enough that it ends the step short
        // of touching but would close the gap in the next (the relax acts: not idle), and one
        // parting with a warm start (not idle). `soft_step::idle` decides; the solve with the
        // idle islands left out gives what the solve of every island gives, bit for bit.
        let (mut contacts, mut v, mut x) = block(2, 2, 2, 1e-3);
        let mut targets = targets(&contacts);
        let mut warm = vec![[0.0; 3]; contacts.len()];
        // (gap at the step's start, relative displacement over the step, relative velocity)
        let pairs = [
            (0.02, 0.01, 1.0, [0.0; 3]),        // parting: idle
            (0.02, -0.03, -3.0, [0.0; 3]),      // closes beyond the gap in the step
            (0.02, -0.015, -15.0, [0.0; 3]),    // ends 0.005 apart, would close it in the next step
            (0.02, 0.01, 1.0, [0.1, 0.0, 0.0]), // parting, warm-started
        ];
        for (gap, d, u, w) in pairs {
            let i = v.len() / 3;
            v.extend([u, 0.0, 0.0, 0.0, 0.0, 0.0]);
            x.extend([10.0 + i as f64, 0.0, 5.0, 10.0 + i as f64 - 1.0 - gap - d, 0.0, 5.0]);
            contacts.push(Contact {
                i,
                other: Partner::Particle(i + 1),
                normal: [1.0, 0.0, 0.0],
                overlap: -(gap + d),
                u_n: u,
                wall_velocity: [0.0; 3],
            });
            targets.push(Target::new(gap, 0.0, [d, 0.0, 0.0], [u, 0.0, 0.0], [1.0, 0.0, 0.0], H, None));
            warm.push(w);
        }
        let inv_mass = vec![1.0; v.len() / 3];
        let idle: Vec<bool> = contacts
            .iter()
            .zip(&targets)
            .zip(&warm)
            .map(|((c, t), w)| super::super::soft_step::idle(c, t, *w, &inv_mass, None, &v, H))
            .collect();
        let n_block = idle.len() - 4;
        assert_eq!(&idle[n_block..], &[true, false, false, false]);
        // (the block's pairs move together and are idle alone; its floor contacts act, so
        // its island is solved, and with it those pairs)
        let on_floor = |k: usize| contacts[k].partner_particle().is_none();
        assert!((0..n_block).all(|k| idle[k] != on_floor(k)), "{idle:?}");
        let islands = Islands::find(&contacts, &inv_mass);
        assert_eq!(islands.len(), 5);
        let floor = floor();
        let p = problem(&contacts, &targets, &inv_mass, &floor, 50);
        let idle_islands = islands.all_of(&idle);
        assert_eq!(idle_islands.iter().filter(|&&i| i).count(), 1);
        let run = |idle: &[bool]| {
            let (mut solved, mut totals, mut x) = (warm.clone(), vec![[0.0; 3]; contacts.len()], x.clone());
            let stats = solve(
                &islands,
                idle,
                &p,
                &mut solved,
                &mut totals,
                &mut Vec::new(),
                &mut Vec::new(),
                &v,
                &mut x,
            )
            .unwrap();
            (solved, totals, x, stats.soft.active)
        };
        let (skipped, all) = (run(&idle_islands), run(&vec![false; islands.len()]));
        assert!(skipped == all, "leaving the idle island out changed the solve");
        let (_, totals, _, _) = all;
        assert_eq!(totals[n_block], [0.0; 3]); // the parting pair bears nothing
        assert!(totals[n_block + 1][0] > 0.0 && totals[n_block + 2][0] > 0.0); // both closing pairs are stopped
    }

    #[test]
    fn a_coloured_island_is_the_same_on_any_number_of_threads_and_holds_the_block_up() {
        // A block of 16·16·6 balls: 4,416 contacts, one island, coloured, with colours large
        // enough to be swept on threads. Its soft step on 1, 2 and 3 threads, bit for bit; and
        // the physics of a plastic block landing on a floor (e = 0): every ball stops, the
        // floor takes the block's momentum, 1,536 kg · 1 m/s, to the solver's tolerance, and
        // the solve lifts the block out of the floor by the step's fall (it ends touching).
        let (contacts, v, x) = block(16, 16, 6, H);
        let inv_mass = vec![1.0; v.len() / 3];
        let targets = targets(&contacts);
        let islands = Islands::find(&contacts, &inv_mass);
        assert_eq!((islands.len(), islands.island(0).len()), (1, 4416));
        let mut groups = Vec::new();
        colour(islands.island(0), &contacts, &inv_mass, |q| q, &mut groups);
        assert!(
            groups.iter().any(|g| g.together && g.range.len() >= PARALLEL_COLOUR),
            "{groups:?}"
        );
        let floor = floor();
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let mut p = problem(&contacts, &targets, &inv_mass, &floor, 2000);
                p.params.tolerance = 1e-12;
                let mut solved = vec![[0.0; 3]; contacts.len()];
                let mut totals = vec![[0.0; 3]; contacts.len()];
                let mut x = x.clone();
                let stats = solve_every_island(&islands, &p, &mut solved, &mut totals, &v, &mut x);
                (totals, x, stats)
            })
        };
        let (one, two, three) = (run(1), run(2), run(3));
        assert!(one == two, "1 and 2 threads differ");
        assert!(one == three, "1 and 3 threads differ");
        let (totals, x_after, stats) = one;
        assert!(stats.soft.converged, "{stats:?}");
        let floor: f64 = totals
            .iter()
            .zip(&contacts)
            .filter(|(_, c)| c.partner_particle().is_none())
            .map(|(t, _)| t[2])
            .sum();
        assert!((floor - 1536.0).abs() < 1e-6, "{floor}");
        let mut after = v.clone();
        for (c, t) in contacts.iter().zip(&totals) {
            vec3::add_scaled(&mut after, c.i, 1.0, *t);
            if let Some(j) = c.partner_particle() {
                vec3::add_scaled(&mut after, j, -1.0, *t);
            }
        }
        let fastest = after.iter().fold(0.0_f64, |m, u| m.max(u.abs()));
        assert!(fastest < 1e-6, "{fastest}");
        // every ball back at its lattice height (the bottom layer touching the floor at −½)
        for (q, z) in x_after.iter().skip(2).step_by(3).enumerate() {
            let layer = (q / 256) as f64;
            assert!((z - layer).abs() < 1e-9, "ball {q} at z = {z}");
        }
    }

    #[test]
    fn shock_propagation_stops_a_deep_column_in_few_sweeps_and_the_floor_takes_its_momentum() {
        // A plastic column of 40 unit balls landing at 1 m/s on a floor, cold, with 10 passes
        // (1 × COLD_PASSES): Gauss–Seidel moves the floor's stop up one ball per pass, and the
        // upper balls end the step sunk into the ones below. With shock propagation every
        // ball ends at its lattice height (the closed form of a column at rest: z = k) and at
        // rest, and the momentum the shock's pushes gave the column (40 kg · 1 m/s in all,
        // with the floor's totals) is what the floor took up.
        let (contacts, v, x) = block(1, 1, 40, H);
        let inv_mass = vec![1.0; 40];
        let targets = targets(&contacts);
        let islands = Islands::find(&contacts, &inv_mass);
        let floor = floor();
        let accel: Vec<f64> = (0..40).flat_map(|_| [0.0, 0.0, -9.81]).collect();
        let run = |shock: Option<&[f64]>| {
            let mut p = problem(&contacts, &targets, &inv_mass, &floor, 1);
            p.shock = shock;
            let (mut solved, mut totals, mut x) = (vec![[0.0; 3]; contacts.len()], vec![[0.0; 3]; contacts.len()], x.clone());
            let mut kicks = Vec::new();
            let every = vec![false; islands.len()];
            solve(
                &islands,
                &every,
                &p,
                &mut solved,
                &mut totals,
                &mut Vec::new(),
                &mut kicks,
                &v,
                &mut x,
            )
            .unwrap();
            let mut after = v.clone();
            for (c, t) in contacts.iter().zip(&totals) {
                vec3::add_scaled(&mut after, c.i, 1.0, *t);
                if let Some(j) = c.partner_particle() {
                    vec3::add_scaled(&mut after, j, -1.0, *t);
                }
            }
            for &(q, k) in &kicks {
                vec3::add_scaled(&mut after, q, 1.0, [k[0], k[1], k[2]]);
            }
            let sunk = x
                .iter()
                .skip(2)
                .step_by(3)
                .enumerate()
                .map(|(k, z)| k as f64 - z)
                .fold(0.0, f64::max);
            let pushed: f64 = kicks.iter().map(|(_, k)| k[2]).sum();
            let floor_took: f64 = totals
                .iter()
                .zip(&contacts)
                .filter(|(_, c)| c.partner_particle().is_none())
                .map(|(t, _)| t[2])
                .sum();
            (sunk, after, pushed, floor_took, kicks.iter().all(|(_, k)| k[2] >= 0.0))
        };
        let (sunk, _, _, _, _) = run(None);
        assert!(
            sunk > 0.1 * H,
            "without the shock the passes alone should leave it sunk: {sunk}"
        );
        let (sunk, after, pushed, floor_took, upward) = run(Some(&accel));
        assert!(sunk < 1e-9, "{sunk}");
        let fastest = after.iter().fold(0.0_f64, |m, u| m.max(u.abs()));
        assert!(fastest < 1e-9, "{fastest}");
        assert!(upward && pushed > 0.0, "the shock only pushes up: {pushed}");
        assert!((pushed + floor_took - 40.0).abs() < 1e-9, "{pushed} + {floor_took}");
    }
}
