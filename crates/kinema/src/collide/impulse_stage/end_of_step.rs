//! The end of an impulse-model step (stages 2–4 after the impacts, [`ImpulseStage::run`]):
//! the contacts of the touched particles and of the piles they reach (detection), the
//! velocity solve of Newton's law with its warm start and the overlap removed (response),
//! each impulse onto both particles and the energy books (distribution).

use super::{ImpulseStage, StageSetting};
use crate::collide::islands::{self, EndProblem, IslandStats, Islands};
use crate::collide::neighbour_list::CHUNK;
use crate::collide::{pair_contact, Collider, Contact, Domain, HoldParams, Partner, ResolveParams, SeparateParams};
use crate::error::Error;
use crate::vec3;

/// The velocity solver of the end-of-step contacts: most sweeps, and the tolerance below which
/// a sweep counts as converged (m/s). Warm-started, a resting pile takes one or two sweeps a
/// step; the cap only matters while a heap settles (see `docs/collisions.md`).
const END_SWEEPS: usize = 200;

/// Pairs closer than r_i + r_j by less than this fraction of r_i + r_j (and particles this
/// fraction of their radius from a collider) are contacts at the end of a step: the position
/// correction leaves resting pairs touching to rounding, on either side of exact contact.
const CONTACT_GAP: f64 = 1e-9;

/// Sweeps of the position correction at the end of a step (overlap removed along the normals).
const SEPARATE_SWEEPS: usize = 20;

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

impl ImpulseStage {
    /// The contacts at the end of the step (pairs within [`CONTACT_GAP`] of touching, and
    /// with colliders) of the touched particles, and of every particle they reach through
    /// such contacts: a pile is one contact network, and the solver must see all of it (a
    /// ball the solver stops changes the approach of the one resting on it). Breadth first
    /// from the touched particles; a particle reached for the first time is touched, and its
    /// integrated state goes to the energy books. Each pair once, lower index first; sorted
    /// by (i, partner), then each touched particle's collider contacts.
    pub(super) fn end_contacts(&mut self, set: &StageSetting<'_>, x1: &[f64], v1: &[f64]) {
        self.contacts.clear();
        let (n, radius) = (set.radius.len(), set.radius);
        let mut work: Vec<usize> = (0..n).filter(|&i| self.touched[i]).collect();
        let mut done = vec![false; n];
        let mut next = 0;
        while next < work.len() {
            let i = work[next];
            next += 1;
            for &j in self.list.rows[i / CHUNK].of(i % CHUNK) {
                let j = j as usize;
                if done[j] {
                    continue; // the pair was seen from j's side
                }
                let (lo, hi) = (i.min(j), i.max(j));
                let gap = CONTACT_GAP * (radius[lo] + radius[hi]);
                if let Some(c) = pair_contact(lo, hi, x1, v1, radius, set.domain, gap) {
                    self.contacts.push(c);
                    if !self.touched[j] {
                        self.touched[j] = true;
                        self.books.push((j, vec3::get(x1, j), vec3::get(v1, j)));
                        work.push(j);
                    }
                }
            }
            done[i] = true;
        }
        self.contacts.sort_by_key(|c| (c.i, c.other));
        let list = &self.list;
        for i in (0..n).filter(|&i| self.touched[i]) {
            let (p, vi) = (vec3::get(x1, i), vec3::get(v1, i));
            let first = list.walls.partition_point(|w| w.0 < i);
            for &(_, k) in list.walls[first..].iter().take_while(|w| w.0 == i) {
                set.colliders[k].for_each_touch(p, radius[i], CONTACT_GAP * radius[i], |t| {
                    let c = Contact {
                        i,
                        other: Partner::Collider(k),
                        normal: t.normal,
                        overlap: t.overlap,
                        u_n: vec3::dot(vi, t.normal),
                    };
                    if !on_periodic_wall(&c, set.colliders, set.domain) {
                        self.contacts.push(c);
                    }
                });
            }
        }
    }

    /// The end-of-step contacts' solve, island by island on all threads (`collide/islands.rs`):
    /// the velocity solver's total impulse of each contact into `totals` (applied by the
    /// caller; `v1` is not changed), then the overlap removed from the positions `x1`. A
    /// contact approaching faster than the threshold is an impact with target u_n⁺ = −e u_n⁻
    /// (Newton's law); slower, a resting contact with target 0. Warm-started from the last
    /// step's totals of the same contacts.
    pub(super) fn solve(
        &mut self,
        set: &StageSetting<'_>,
        v1: &[f64],
        x1: &mut [f64],
        threshold: f64,
    ) -> Result<IslandStats, Error> {
        let (materials, inv_mass) = (set.materials, set.inv_mass);
        self.targets.clear();
        self.targets.extend(self.contacts.iter().map(|c| {
            if -c.u_n >= threshold && c.u_n < 0.0 {
                -materials.pair(c).restitution() * c.u_n
            } else {
                0.0
            }
        }));
        let warm = &self.warm;
        self.totals.clear();
        self.totals.extend(self.contacts.iter().map(|c| {
            warm.binary_search_by(|w| (w.0, w.1).cmp(&(c.i, c.other)))
                .map_or([0.0; 3], |k| warm[k].2)
        }));
        if self.contacts.is_empty() {
            self.warm.clear();
            self.resting.clear();
            let mut done = IslandStats::default();
            done.hold.converged = true;
            return Ok(done);
        }
        let problem = EndProblem {
            contacts: &self.contacts,
            targets: &self.targets,
            inv_mass,
            materials,
            hold: HoldParams {
                tolerance: ResolveParams::default().tolerance,
                max_iterations: END_SWEEPS,
            },
            separate: SeparateParams {
                iterations: SEPARATE_SWEEPS,
                ..SeparateParams::default()
            },
        };
        let islands = Islands::find(&self.contacts, inv_mass);
        let stats = islands::solve(&islands, &problem, &mut self.totals, v1, x1)?;
        self.warm.clear();
        self.warm
            .extend(self.contacts.iter().zip(&self.totals).map(|(c, p)| (c.i, c.other, *p)));
        self.warm.sort_by_key(|w| (w.0, w.1));
        self.resting.clear();
        self.resting.extend(self.warm.iter().map(|w| (w.0, w.1, w.2 != [0.0; 3])));
        Ok(stats)
    }

    /// The mechanical energy the end-of-step solve and the position correction took, J: over
    /// the particles in contact, the kinetic energy before them minus after, minus the work
    /// the step's forces (the constant accelerations of the paths) do along the positions
    /// the correction moved: Σ ½ m (|v_b|² − |v|²) + Σ m a·(x − x_b). For a resting contact
    /// held by the solver, whose sinking the correction undoes, it is 0: what the impulse
    /// took from the speed the force gave, the correction gave back as height. (An impact
    /// inside the step books its own ½ (1 − e²) μ u_n², exactly 0 for e = 1.)
    pub(super) fn energy_books(&self, set: &StageSetting<'_>, accel: &[f64], x1: &[f64], v1: &[f64]) -> f64 {
        let (mass, inv_mass) = (set.mass, set.inv_mass);
        let mut lost = 0.0;
        for &(q, xb, vb) in &self.books {
            if inv_mass[q] == 0.0 {
                continue;
            }
            let (x, v, a) = (vec3::get(x1, q), vec3::get(v1, q), vec3::get(accel, q));
            let dx = set.domain.displacement(x, xb);
            lost += 0.5 * mass[q] * (vec3::dot(vb, vb) - vec3::dot(v, v)) + mass[q] * vec3::dot(a, dx);
        }
        lost
    }
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
    for k in 0..3 {
        v[3 * i + k] += wi * impulse[k];
    }
    if let Some(j) = j {
        for k in 0..3 {
            v[3 * j + k] -= wj * impulse[k];
        }
        if wi > 0.0 && wj > 0.0 {
            for k in 0..3 {
                balance[k] += mass[i] * (wi * impulse[k]) - mass[j] * (wj * impulse[k]);
            }
        }
    }
}
