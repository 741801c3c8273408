//! The impulse model's collision stages 2–4 over one step ([`ImpulseModel::step`], its stage list in `step.rs`): what they
//! keep from step to step (the candidate list, the paths and the queue of impacts, the meeting
//! times, the end-of-step contacts and their warm start), what the world tells them
//! ([`StageSetting`], [`StepFrame`]) and what they report ([`CollisionStats`],
//! [`CollisionTimes`]). Continuous detection and the impacts are in `impacts.rs`, the
//! end-of-step contacts, their solve and the books in `end_of_step.rs`; the world keeps the
//! settings, colliders, domain and the books summed over steps (`collide/stage.rs`).

pub(crate) mod end_of_step;
pub(crate) mod impacts;
pub(crate) mod list;
mod step;

use super::books::ColliderBooks;
use super::events::{EventQueue, PathStore};
use super::islands::{Forest, Islands};
use super::marks::Marks;
use super::neighbour_list::NeighbourList;
use super::quiet::Meetings;
use super::records::{ContactRecord, Records};
use super::shock::Accuracy;
use super::sleep::Sleep;
use super::soft_step::{Target, SPECULATIVE};
use super::spin::Rotation;
use super::touch::Touches;
use super::{Collider, Contact, Domain, Grid, MaterialTable, Partner};
use crate::interrupt::Interrupt;

/// What the collision stages did, over one step or summed over many.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CollisionStats {
    /// Contacts at the end of the step (touching or overlapping pairs and particle–collider
    /// contacts).
    pub contacts: usize,
    /// Of the contacts: those that bear an impulse at the step's end (held, pushed or
    /// bounced by the end-of-step soft step), ...
    pub resting: usize,
    /// ... and those apart at the step's end that bore nothing (speculative: within the
    /// margin, `collide/soft_step.rs`, SPECULATIVE).
    pub speculative: usize,
    /// End-of-step contacts that bounced by Newton's law in the soft step's restitution stage.
    pub bounced: usize,
    /// Impacts found by continuous detection inside the step, each resolved at its time.
    pub impacts: usize,
    /// Impulses applied (impacts and end-of-step contacts).
    pub impulses: usize,
    /// Σ m Δv of all particles over the collision stages minus the impulses that colliders
    /// and pinned particles gave them, N·s: the sum of all impulses between movable
    /// particles, zero by action and reaction up to rounding.
    pub impulse_balance: [f64; 3],
    /// Kinetic energy removed by the collisions, J (≥ 0; 0 for e = 1 without friction).
    /// With the spring–dashpot and Hertz models (velocity Verlet): the dashpots' power
    /// c_n u_n² at each step's force evaluation times the step.
    pub energy_lost: f64,
    /// The virial of the pair interactions, Σ (x_i − x_j) ⊗ J (N·m·s, row-major 3 × 3): each
    /// impulse J between two particles at their separation (the minimum image), and with the
    /// force models h Σ (x_i − x_j) ⊗ F at each step's force evaluation; summed over steps.
    /// Divided by a time and a volume it is the interactions' part of the pressure tensor
    /// (colliders excluded: `Trajectory.pressure`).
    pub virial: [f64; 9],
    /// The largest overlap left after the step, m: measured at the last step of each call
    /// that advances the world (the figure anyone reads; 0 for the steps before it).
    pub max_overlap: f64,
    /// Passes of the end-of-step velocity solver (the latest step's; the most any island took;
    /// `solver_sweeps` is its public name, which the binding and Python read).
    pub solver_sweeps: usize,
    /// Independent groups of the end-of-step contacts, each solved on its own on one of the
    /// threads (the latest step's; `collide/islands.rs`).
    pub islands: usize,
    /// Particles asleep at the step's end (`collide/sleep.rs`; the latest step's).
    pub asleep: usize,
    /// The contacts of the islands asleep (not among `contacts`: nothing solves them).
    pub asleep_contacts: usize,
    /// Islands that fell asleep (summed over steps).
    pub slept: usize,
    /// Islands woken, by a touch or an impact (summed over steps).
    pub woke: usize,
    /// Steps whose end-of-step solver stopped at its sweep cap before converging, or whose
    /// impacts stopped at the cap of continuous detection (0 or 1 for one step; summed).
    pub unconverged: usize,
}

impl CollisionStats {
    /// Adds another step's figures (contacts: the latest).
    pub fn accumulate(&mut self, step: &CollisionStats) {
        self.contacts = step.contacts;
        self.resting = step.resting;
        self.speculative = step.speculative;
        self.bounced += step.bounced;
        self.impacts += step.impacts;
        self.impulses += step.impulses;
        for k in 0..3 {
            self.impulse_balance[k] += step.impulse_balance[k];
        }
        self.energy_lost += step.energy_lost;
        for k in 0..9 {
            self.virial[k] += step.virial[k];
        }
        self.max_overlap = step.max_overlap;
        self.solver_sweeps = step.solver_sweeps;
        self.islands = step.islands;
        self.asleep = step.asleep;
        self.asleep_contacts = step.asleep_contacts;
        self.slept += step.slept;
        self.woke += step.woke;
        self.unconverged += step.unconverged;
    }
}

/// Adds the outer product a ⊗ b to the row-major 3 × 3 `m` (a virial's Σ r ⊗ J).
pub(crate) fn add_outer(m: &mut [f64; 9], a: [f64; 3], b: [f64; 3]) {
    for r in 0..3 {
        for c in 0..3 {
            m[3 * r + c] += a[r] * b[c];
        }
    }
}

/// Wall-clock time of the collision stages 2–4 of the impulse model, summed over steps.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CollisionTimes {
    /// Stage 2: the candidate list, each particle's first impact, the events' validity and
    /// rescheduling, the end-of-step contacts.
    pub detect: std::time::Duration,
    /// Stage 3: the impulses of Newton's law (impacts, and the end-of-step solver) and the
    /// removal of overlap.
    pub respond: std::time::Duration,
    /// Stage 4: each impulse onto both particles, the impulse balance and the energy lost.
    pub distribute: std::time::Duration,
    /// The same time by [`ImpulseStage`], in its order.
    pub stages: [std::time::Duration; 7],
}

/// The impulse model's stages in the order a step runs them (as Box2D's `b2SolverStage`
/// lists its solver's), each with its own timer ([`CollisionTimes::stages`]). Continuous
/// detection interleaves detect, respond and distribute inside `Impacts`; the rest run once
/// a step, in this order, because each reads what the one before it wrote.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImpulseStage {
    /// The neighbour list holds for the step's sweep, or is rebuilt (with the meeting times of
    /// a force-free world); who is looked at.
    List,
    /// Continuous detection: each impact at its time, by Newton's law, onto both particles.
    Impacts,
    /// The end-of-step contacts of the touched particles and of the piles they reach.
    Contacts,
    /// The soft step: targets, islands, the passes (idle islands skipped).
    Solve,
    /// The totals onto both particles; the energy lost.
    Apply,
    /// Sleeping, the largest overlap, positions wrapped into the periodic cell.
    Settle,
    /// The next steps' meeting times (a force-free world).
    Meetings,
}

impl ImpulseStage {
    /// Every stage, in order.
    pub const ALL: [ImpulseStage; 7] = [
        ImpulseStage::List,
        ImpulseStage::Impacts,
        ImpulseStage::Contacts,
        ImpulseStage::Solve,
        ImpulseStage::Apply,
        ImpulseStage::Settle,
        ImpulseStage::Meetings,
    ];

    /// Its name in `World.stage_times()`.
    pub fn name(self) -> &'static str {
        match self {
            ImpulseStage::List => "list",
            ImpulseStage::Impacts => "impacts",
            ImpulseStage::Contacts => "contacts",
            ImpulseStage::Solve => "solve",
            ImpulseStage::Apply => "apply",
            ImpulseStage::Settle => "settle",
            // ("wake": the stage's public name in `stage_times`, kept from before the rename)
            ImpulseStage::Meetings => "wake",
        }
    }
}

/// What the world tells the collision stages about the step they follow.
pub(crate) struct StepFrame<'a> {
    /// The world's clock at the step's start, s.
    pub t0: f64,
    /// The step, s.
    pub h: f64,
    /// The method's constant acceleration of the step (velocity Verlet's a(t)), m/s², 3 per
    /// particle; `None`: the parabola through x₁ is taken.
    pub accel: Option<&'a [f64]>,
    /// No force acts: every path is a straight line from one step to the next, and the
    /// impact search starts only from the particles whose meeting time falls in the step
    /// (`collide/quiet.rs`).
    pub steady: bool,
    /// x₁ is already in the periodic cell (the stages wrap only what they move).
    pub wrapped: bool,
    /// Whether islands may sleep in this step: no force depends on the positions or adds
    /// energy (`collide/sleep.rs`).
    pub may_sleep: bool,
    /// Whether the step's statistics measure the overlap the contacts leave
    /// ([`CollisionStats::max_overlap`]; else 0): the world asks it of the last step of each
    /// call, the one whose statistics can be read.
    pub measure_overlap: bool,
}

/// What the stages see of the world in a step, besides its state: the colliders, the domain,
/// the materials (global, per particle, per collider), the settings they follow, and the
/// particles' radii (m), inverse masses (1/kg) and masses (kg).
pub(crate) struct StageSetting<'a> {
    pub colliders: &'a [Collider],
    pub domain: &'a Domain,
    pub materials: MaterialTable<'a>,
    /// Continuous detection ([`crate::world::CollisionParams::ccd`]).
    pub ccd: bool,
    /// The restitution threshold, m/s, or `None` for the automatic one
    /// ([`crate::world::CollisionParams::restitution_threshold`]).
    pub restitution_threshold: Option<f64>,
    /// The time to sleep, s (`None`: nothing sleeps), and the sleep speed, m/s (`None`:
    /// automatic) ([`crate::world::CollisionParams::sleep_time`]).
    pub sleep_time: Option<f64>,
    pub sleep_speed: Option<f64>,
    pub radius: &'a [f64],
    /// The particles' ids (for the touch events, `collide/touch.rs`).
    pub id: &'a [u64],
    pub inv_mass: &'a [f64],
    pub mass: &'a [f64],
    /// With spin: the particles' inverse moments of inertia and radii (`collide/spin.rs`).
    pub rotation: Option<Rotation<'a>>,
    /// Rolling resistance μ_r ([`crate::world::CollisionParams::rolling_friction`]; with spin).
    pub rolling_friction: f64,
    /// The end-of-step solve's accuracy setting ([`crate::world::CollisionParams::accuracy`]).
    pub accuracy: Accuracy,
    /// The collision groups' filter (`collide/groups.rs`), applied where the neighbour list
    /// is built; `None` when every pair collides.
    pub filter: Option<crate::collide::groups::Filter<'a>>,
}

/// What the stages keep of their contacts while particles are added
/// ([`ImpulseModel::take_contacts`]).
#[derive(Default)]
pub(crate) struct KeptContacts {
    warm: Vec<ContactRecord>,
    sleep: Sleep,
}

/// The impulse model's stages and their buffers.
pub(crate) struct ImpulseModel {
    pub(crate) grid: Grid,
    /// Candidate pairs of continuous detection and of the end-of-step contacts.
    pub(crate) list: NeighbourList,
    /// The least skin of the list's last build, m (`SKIN_PER_RADIUS` of the mean radius).
    pub(super) base_skin: f64,
    /// The particles' paths through the step and the queue of their next impacts.
    pub(super) paths: PathStore,
    /// The step's constant accelerations when the method gives none (the parabola
    /// through x₁), m/s².
    pub(super) fitted: Vec<f64>,
    /// The step's accelerations by the forces when the method gives none, (v₁ − v₀)/h, for
    /// the energy lost, m/s².
    pub(super) forced: Vec<f64>,
    pub(super) queue: EventQueue,
    /// Each particle's bound on its distance from its list build position for the rest of
    /// the step, m, when `bounded` (`events::SweepBound`; else the step's one bound `reach`).
    pub(super) bounds: Vec<f64>,
    pub(super) bounded: bool,
    /// The tests' switch that turns the bounds' check off (every candidate solved for).
    #[cfg(test)]
    pub(crate) unbounded: bool,
    /// In a force-free world, each particle's meeting time (see `collide/quiet.rs`), the
    /// particles due in this step, whether this step rebuilt the list, and the fastest
    /// speed an impact of this step left.
    pub(super) meetings: Meetings,
    pub(super) due: Vec<usize>,
    pub(super) rebuilt: bool,
    pub(super) fastest_hit: f64,
    /// Particles that touched something at the step's start or were hit in it: the only
    /// ones that can be in contact at its end (continuous detection saw every other path).
    pub(super) touched: Marks,
    /// Scratch flags, one per particle, all false between uses (`end_of_step.rs`).
    pub(super) scratch: Marks,
    /// Each touched particle's reference state for the energy lost: at the step's start, or
    /// after its impacts (x, v).
    pub(super) references: Vec<(usize, [f64; 3], [f64; 3])>,
    /// With spin, the angular velocity of each entry of `references` at its reference, rad/s.
    pub(super) references_spin: Vec<[f64; 3]>,
    pub(super) contacts: Vec<Contact>,
    /// Where a world has a mesh: for each entry of the list's colliders (`list.walls`, by
    /// place), the triangles last found near that particle (`mesh::NearCache`). What an
    /// entry keeps answers for a place and a mesh, not for a particle: one that comes to
    /// serve another particle or collider (the list rebuilt) is gathered again where it does
    /// not answer, never misread. Empty in a world without a mesh.
    pub(super) near_meshes: Vec<crate::collide::colliders::NearCache>,
    /// The end-of-step contacts as detected (overlap and u_n before the response).
    pub detected: Vec<Contact>,
    /// The soft step's final totals of the end-of-step contacts, N·s.
    pub(super) totals: Vec<[f64; 3]>,
    /// The solve stage's totals (the next step's warm start), N·s.
    pub(super) solved: Vec<[f64; 3]>,
    /// With rolling resistance, each end-of-step contact's final angular impulse on i,
    /// N·m·s (empty without).
    pub(super) rolls: Vec<[f64; 3]>,
    /// With shock propagation, the end-of-step solve's velocity changes that no total holds
    /// (particle, velocity then angular velocity), m/s and rad/s.
    pub(super) kicks: Vec<(usize, [f64; 6])>,
    /// The particles the end-of-step stage acted on in this step (for the energy lost).
    pub(super) acted: Marks,
    /// Each end-of-step contact's targets (`collide/soft_step.rs`).
    pub(super) prepared: Vec<Target>,
    /// The awake contacts' records: the last step's totals (the warm start) and whether each
    /// bore load (`collide/records.rs`).
    pub(super) records: Records,
    /// Each end-of-step contact's record, by index into `records` (`None`: a new contact).
    pub(super) matched: Vec<Option<usize>>,
    /// The islands of the last end-of-step solve (`collide/islands.rs`).
    pub(super) islands: Islands,
    /// The union–find arrays the islands are found with.
    pub(super) forest: Forest,
    /// What the particles gave each collider in the last step.
    pub(crate) collider_books: Vec<ColliderBooks>,
    /// Each particle's calm time and the islands asleep (`collide/sleep.rs`).
    pub(super) sleep: Sleep,
    /// The pairs touching and the begin and end events, when recorded (`collide/touch.rs`).
    pub(crate) touches: Touches,
    /// The world's check that may stop a step, asked inside a long run of impacts.
    pub interrupt: Interrupt,
}

impl ImpulseModel {
    /// The end-of-step contacts of the last step as detected, each with the total impulse
    /// the step's soft step gave it (N·s, on i; zeros where it gave none, and for every
    /// contact after a step that solved none), less those of the islands that went to sleep
    /// at its end ([`ImpulseModel::sleeping_contacts`] has them).
    pub fn detected_with_totals(&self) -> impl Iterator<Item = (&Contact, [f64; 3])> + '_ {
        let aligned = self.totals.len() == self.detected.len();
        let asleep = self.sleep.any();
        self.detected
            .iter()
            .enumerate()
            .filter(move |(_, c)| !(asleep && self.sleep.is_asleep(c.i)))
            .map(move |(k, c)| (c, if aligned { self.totals[k] } else { [0.0; 3] }))
    }

    /// The contacts of the islands asleep, each with the impulse its last awake step's solve
    /// gave it (N·s on i; the load it bears in each step asleep), measured at the positions
    /// `x` (m, 3 per particle) as [`sleeping_contact`] measures them.
    pub(crate) fn sleeping_contacts(
        &self,
        x: &[f64],
        radius: &[f64],
        colliders: &[Collider],
        domain: &Domain,
    ) -> Vec<(Contact, [f64; 3])> {
        self.sleep
            .records()
            .filter_map(|r| sleeping_contact(r, x, radius, colliders, domain).map(|c| (c, r.impulse)))
            .collect()
    }

    /// Books what the islands asleep at the positions `x` give the colliders in a step: each
    /// collider contact's load, as in its last awake step (a still collider: no work). Only
    /// the collider records are measured: a pile asleep costs its few wall contacts a step.
    pub(super) fn book_sleepers(&mut self, x: &[f64], radius: &[f64], colliders: &[Collider], domain: &Domain) {
        let walls = self.sleep.records().filter(|r| matches!(r.other, Partner::Collider(_)));
        let given: Vec<(Contact, [f64; 3])> = walls
            .filter_map(|r| sleeping_contact(r, x, radius, colliders, domain).map(|c| (c, r.impulse)))
            .collect();
        for (c, p) in given {
            let Partner::Collider(k) = c.other else { continue };
            let at = crate::vec3::sub(
                crate::vec3::get(x, c.i),
                crate::vec3::scale(radius[c.i] - c.overlap, c.normal),
            );
            if let Some(b) = self.collider_books.get_mut(k) {
                b.book(at, [0.0; 3], p, c.normal);
            }
        }
    }

    /// Empty buffers; no check may stop a step.
    pub fn new() -> Self {
        ImpulseModel {
            grid: Grid::new(),
            list: NeighbourList::default(),
            base_skin: 0.0,
            paths: PathStore::default(),
            fitted: Vec::new(),
            forced: Vec::new(),
            queue: EventQueue::default(),
            bounds: Vec::new(),
            bounded: false,
            #[cfg(test)]
            unbounded: false,
            meetings: Meetings::default(),
            due: Vec::new(),
            rebuilt: false,
            fastest_hit: 0.0,
            touched: Marks::default(),
            scratch: Marks::default(),
            references: Vec::new(),
            references_spin: Vec::new(),
            contacts: Vec::new(),
            near_meshes: Vec::new(),
            detected: Vec::new(),
            totals: Vec::new(),
            solved: Vec::new(),
            rolls: Vec::new(),
            kicks: Vec::new(),
            acted: Marks::default(),
            prepared: Vec::new(),
            records: Records::default(),
            matched: Vec::new(),
            islands: Islands::default(),
            forest: Forest::default(),
            collider_books: Vec::new(),
            sleep: Sleep::default(),
            touches: Touches::default(),
            interrupt: Interrupt::none(),
        }
    }

    /// Wakes the islands asleep of the particles `range` (their state was written), each with
    /// its contacts' warm start; returns how many woke.
    pub fn wake_particles(&mut self, range: std::ops::Range<usize>) -> usize {
        let mut work = Vec::new();
        let mut woke = 0;
        for q in range {
            if self.sleep.is_asleep(q) {
                woke += self.wake_island(q, &mut work);
            }
        }
        if woke > 0 {
            self.records.sort();
        }
        woke
    }

    /// The particles and the contacts in the islands asleep now.
    pub fn asleep(&self) -> (usize, usize) {
        (self.sleep.asleep(), self.sleep.contacts())
    }

    /// The awake contacts' records (`collide/records.rs`), sorted by key.
    pub(crate) fn records(&self) -> &[ContactRecord] {
        self.records.rows()
    }

    /// Sets the contacts' records (a checkpoint's).
    pub fn set_warm_start(&mut self, warm: Vec<ContactRecord>) {
        self.records = Records::from_unsorted(warm);
    }

    /// Forgets the candidate list and the warm start, and wakes every island (particles,
    /// colliders or the domain changed).
    pub fn forget_list(&mut self) {
        self.list.built_at.clear();
        self.meetings.valid = false;
        self.records.clear();
        self.sleep.wake_all();
    }

    /// The contacts' warm start and the islands asleep, taken out (particles are being added:
    /// [`ImpulseModel::keep_contacts`] gives them back).
    pub fn take_contacts(&mut self) -> KeptContacts {
        KeptContacts {
            warm: self.records.take(),
            sleep: std::mem::take(&mut self.sleep),
        }
    }

    /// Particles are being removed (`new_of_old[i]`: particle i's index after,
    /// [`GONE`](crate::limits::GONE) for a removed one): the contacts between survivors,
    /// renumbered, with their warm starts, for [`ImpulseModel::keep_contacts`]. Every island
    /// wakes (a sleeping island's contacts join the others): what is removed may have held
    /// any of them up.
    pub fn take_contacts_renumbered(&mut self, new_of_old: &[u32]) -> KeptContacts {
        use crate::limits::GONE;
        let warm = self
            .all_warm()
            .into_iter()
            .filter_map(|r| {
                let i = *new_of_old.get(r.i).filter(|&&i| i != GONE)?;
                let other = match r.other {
                    Partner::Particle(j) => Partner::Particle(*new_of_old.get(j).filter(|&&j| j != GONE)? as usize),
                    other => other,
                };
                Some(ContactRecord {
                    i: i as usize,
                    other,
                    ..r
                })
            })
            .collect();
        self.records.clear();
        self.sleep.wake_all();
        KeptContacts {
            warm,
            sleep: Sleep::default(),
        }
    }

    /// Particles were added (now `n`): the list is rebuilt, and the contacts of the others
    /// and their islands asleep, taken before, stay (their numbers did not change).
    pub fn keep_contacts(&mut self, kept: KeptContacts, n: usize) {
        self.list.built_at.clear();
        self.meetings.valid = false;
        self.set_warm_start(kept.warm);
        self.sleep = kept.sleep;
        self.sleep.resize(n);
    }

    /// Every contact's warm start, as a checkpoint keeps it: the awake records' and the
    /// sleeping islands', sorted by key.
    pub fn all_warm(&self) -> Vec<ContactRecord> {
        let mut all = self.records.rows().to_vec();
        all.extend(self.sleep.records().copied());
        all.sort_by_key(ContactRecord::key);
        all
    }

    /// What a checkpoint keeps of sleeping: each particle's calm time (s) and island (−1:
    /// awake).
    pub fn sleep_carry(&self, n: usize) -> (Vec<f64>, Vec<i64>) {
        self.sleep.carry(n)
    }

    /// Gives back what [`ImpulseModel::sleep_carry`] took, after the warm start (which holds
    /// the sleeping islands' contacts, taken out of it here): the islands asleep again, each
    /// with its largest overlap measured at `x`.
    pub fn restore_sleep(&mut self, calm: Vec<f64>, island: &[i64], deepest: impl Fn(usize, Partner) -> f64) {
        self.sleep.wake_all();
        self.sleep.calm = calm;
        // Each island's members and contacts, gathered in one pass each (a contact with a
        // pinned particle, which sleeps in no island, is its partner's).
        let mut islands: std::collections::BTreeMap<i64, (Vec<usize>, Vec<ContactRecord>)> = Default::default();
        for (q, &k) in island.iter().enumerate().filter(|(_, &k)| k >= 0) {
            islands.entry(k).or_default().0.push(q);
        }
        let of = |i: usize, other: Partner| match (island[i], other) {
            (-1, Partner::Particle(j)) => island[j],
            (k, _) => k,
        };
        let mut awake = Vec::with_capacity(self.records.len());
        for w in self.records.take() {
            match islands.get_mut(&of(w.i, w.other)) {
                Some(entry) => entry.1.push(w),
                None => awake.push(w),
            }
        }
        self.records = Records::from_unsorted(awake);
        for (members, mine) in islands.into_values() {
            let overlap = mine.iter().map(|w| deepest(w.i, w.other)).fold(0.0, f64::max);
            self.sleep.put_to_sleep(members, mine, overlap);
        }
    }
}

/// The contact of a sleeping island's record `r` at the positions `x` (m): a pair along its
/// line of centres; a collider by its touch within the end-of-step contacts' margin whose
/// normal is most along the record's impulse (`None` when it touches no longer).
fn sleeping_contact(r: &ContactRecord, x: &[f64], radius: &[f64], colliders: &[Collider], domain: &Domain) -> Option<Contact> {
    let xi = crate::vec3::get(x, r.i);
    let (normal, overlap) = match r.other {
        Partner::Particle(j) => {
            let d = domain.displacement(xi, crate::vec3::get(x, j));
            let dist = crate::vec3::norm(d);
            if dist <= 0.0 {
                return None;
            }
            (crate::vec3::scale(1.0 / dist, d), radius[r.i] + radius[j] - dist)
        }
        Partner::Collider(k) => {
            let mut best: Option<(f64, [f64; 3], f64)> = None;
            colliders[k].for_each_touch(xi, radius[r.i], 2.0 * SPECULATIVE * radius[r.i], |t| {
                let along = crate::vec3::dot(t.normal, r.impulse);
                if best.is_none_or(|(a, _, _)| along > a) {
                    best = Some((along, t.normal, t.overlap));
                }
            });
            let (_, normal, overlap) = best?;
            (normal, overlap)
        }
    };
    Some(Contact {
        i: r.i,
        other: r.other,
        normal,
        overlap,
        u_n: 0.0,
        wall_velocity: [0.0; 3],
    })
}
