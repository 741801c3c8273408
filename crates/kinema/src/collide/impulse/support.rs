//! Bodies held at rest on their supports through the step's impacts: which particles the
//! step's paths hold at x₀ with no velocity until their first impact (`paths.rs`,
//! [`Paths::holding`](crate::collide::paths::Paths::holding)).
//!
//! Why. Continuous detection moves every particle on the parabola of the forces, and the
//! contacts act only in the end-of-step solve. A ball resting on a floor then falls ½ g τ²
//! inside the step by τ and moves down at g τ. A ball dropped onto it meets it late, low and
//! too fast; the end-of-step solve lifts the pair back at no cost, and the books show the
//! energy created: m g · ½ g τ² for a ball on a floor with e = 1 (1.1e-6 J for 0.5 kg at
//! τ = 0.15 ms). And a ball dropped so that it meets a resting column just at the step's
//! end misses it in the step, where the same column held asleep is met before.
//!
//! Which. A particle is held if a contact carried it in the last step (its record's total is
//! not zero: something supports it) and it starts the step at rest on that support: moving
//! slower than [`AT_REST`] of what the forces would add in one step, |v₀| ≤ 0.01 |a| h (a
//! converged solve leaves a body at rest within 1e-9 m/s), with a force to hold it against
//! (|a| > 0: in a force-free world nothing is held, and the paths are exactly the straight
//! ones). A body creeping on its supports is not held: a 60 Hz heap creeps at 1–10 % of g h,
//! and holding those too (|v₀| ≤ g h) changed their impacts by up to 2 g h and made the
//! demo's heap take 40 % longer to come to rest (8 seeds: a median of 3.66 s against
//! 2.63 s before; at 1 %, 2.54 s). Box2D v3 gets the same from the other side: it applies the last
//! step's impulses to the velocities before anything moves (`b2WarmStartContactsTask`).
//!
//! Held means at rest: x(τ) = x₀, v(τ) = 0, for every held particle alike, so that a pile's
//! particles keep their relative paths (all still, as before all fell alike). At its first
//! impact, at τ, a particle lets go ([`ImpulseModel::let_go`]): the impact saw it where it
//! rests and at rest, and from there it moves on the forces' parabola. The ½ m |v₀|² the hold
//! took (rounding at rest; at most ½ m (a h)²) is booked as lost: the hold never gives energy.
//!
//! The hold was a force, and its impulse J = m (0 − (v₀ + a τ)) (what kept the particle from
//! moving) came from the contacts that carried it. It is carried down at once, as shock
//! propagation carries a load ([`ImpulseModel::carry_holds`]): each particle passes the load
//! it was given on to the contacts that push it along the load, each its share of their last
//! totals' push; a particle that passes on all it was given is unchanged, and a collider at
//! the bottom books its share (`ColliderBooks`). So momentum balances as before: Σ m Δv =
//! the forces' impulse + what the colliders gave. (A load that finds no contact to pass it
//! on to — a particle carried only sideways — stays with that particle: its velocity takes
//! it, and the end-of-step solve carries it on.)
//!
//! A particle held and never hit ends the step where the integrator put it (`Paths::finish`
//! writes only the paths an impact opened): the end-of-step solve finds the contacts that
//! still carry it, as before.

use std::collections::{BinaryHeap, HashMap, HashSet};

use super::{ImpulseModel, StageSetting};
use crate::collide::paths::Paths;
use crate::collide::records::ContactRecord;
use crate::collide::Partner;
use crate::vec3;

/// How still a supported particle must be to be held, as a fraction of the speed the forces
/// add in one step, |a| h (see the module doc).
pub(crate) const AT_REST: f64 = 0.01;

impl ImpulseModel {
    /// Fills `self.held` with whether each particle is held at rest on its path until its
    /// first impact (see the module doc), from the awake records, the step's start velocities
    /// `v0` (m/s) and the forces' accelerations `accel` (m/s²) over a step of `h` s; leaves it
    /// empty where none is.
    pub(super) fn fill_held(&mut self, inv_mass: &[f64], v0: &[f64], accel: &[f64], h: f64) {
        let held = &mut self.held;
        held.clear();
        self.hold_loads.clear();
        self.hold_kicks.clear();
        let n = inv_mass.len();
        for &ContactRecord { i, other, impulse, .. } in self.records.rows() {
            if impulse == [0.0; 3] {
                continue; // carried nothing
            }
            for q in std::iter::once(i).chain(partner_particle(other)) {
                if q >= n || inv_mass[q] == 0.0 {
                    continue; // (a pinned particle is not moved by anything)
                }
                let (a, v) = (vec3::get(accel, q), vec3::get(v0, q));
                let a2 = vec3::dot(a, a);
                if a2 == 0.0 || vec3::dot(v, v) > AT_REST * AT_REST * a2 * h * h {
                    continue; // nothing to hold it against, or moving on its support
                }
                if held.is_empty() {
                    held.resize(n, false);
                }
                held[q] = true;
            }
        }
    }

    /// Held particle q lets go at its first impact, `t` s into the step (see the module doc):
    /// its hold's impulse J = −m (v₀ + a t) (N·s) is kept for [`Self::carry_holds`]; returns
    /// the kinetic energy the hold took, ½ m |v₀|² (J).
    pub(super) fn let_go(&mut self, set: &StageSetting<'_>, paths: &Paths<'_>, q: usize, t: f64) -> f64 {
        let (m, v0, a) = (set.mass[q], vec3::get(paths.v0, q), vec3::get(paths.accel, q));
        self.hold_loads
            .push((q, vec3::scale(-m, [0, 1, 2].map(|k| v0[k] + a[k] * t))));
        0.5 * m * vec3::dot(v0, v0)
    }

    /// Carries the holds' impulses down to the colliders through the contacts that carried
    /// the held particles in the last step (see the module doc), the highest along the loads
    /// first (positions `x0`, m); what finds no contact to pass it on goes into that
    /// particle's velocity `v1` (m/s) and stays listed in `hold_kicks` for the books.
    pub(super) fn carry_holds(&mut self, set: &StageSetting<'_>, x0: &[f64], v1: &mut [f64]) {
        if self.hold_loads.is_empty() {
            return;
        }
        // each particle's records that carried something, by particle
        let rows = self.records.rows();
        let mut of: Vec<(u32, u32)> = Vec::new();
        for (k, r) in rows.iter().enumerate() {
            if r.impulse != [0.0; 3] {
                of.push((r.i as u32, k as u32));
                if let Some(j) = partner_particle(r.other) {
                    of.push((j as u32, k as u32));
                }
            }
        }
        of.sort_unstable();
        let up = vec3::scale(-1.0, self.hold_loads.iter().fold([0.0; 3], |s, l| vec3::add(s, l.1)));
        let up = if up == [0.0; 3] {
            up
        } else {
            vec3::scale(-1.0 / vec3::norm(up), up)
        };
        let height = |q: usize| Height(vec3::dot(vec3::get(x0, q), up), q);
        let mut pending: HashMap<usize, [f64; 3]> = HashMap::new();
        let mut queue = BinaryHeap::new();
        for &(q, load) in &self.hold_loads {
            let p = pending.entry(q).or_insert([0.0; 3]);
            *p = vec3::add(*p, load);
            queue.push(height(q));
        }
        let mut done: HashSet<usize> = HashSet::new();
        let kicks = &mut self.hold_kicks;
        while let Some(Height(_, p)) = queue.pop() {
            let Some(load) = pending.remove(&p) else { continue };
            done.insert(p);
            let first = of.partition_point(|e| (e.0 as usize) < p);
            let mine = &of[first..first + of[first..].partition_point(|e| e.0 as usize == p)];
            // the contacts that push p along its load, each by its push along it
            let push = |k: u32| {
                let r = &rows[k as usize];
                let on_p = if r.i == p { r.impulse } else { vec3::scale(-1.0, r.impulse) };
                (vec3::dot(on_p, load).max(0.0), on_p)
            };
            let total: f64 = mine.iter().map(|e| push(e.1).0).sum();
            if !(total > 0.0) {
                kicks.push((p, vec3::scale(-1.0, load)));
                continue;
            }
            for &(_, k) in mine {
                let (w, on_p) = push(k);
                if w == 0.0 {
                    continue;
                }
                let share = vec3::scale(w / total, load);
                let r = &rows[k as usize];
                match r.other {
                    Partner::Collider(c) => {
                        // (at its contact: a radius from x₀ against the collider's push)
                        let along = vec3::scale(1.0 / vec3::norm(on_p), on_p);
                        let at = vec3::sub(vec3::get(x0, p), vec3::scale(set.radius[p], along));
                        self.collider_books[c].book(at, set.colliders[c].velocity_at(at), share);
                    }
                    Partner::Particle(j) => {
                        let o = if r.i == p { j } else { r.i };
                        if set.inv_mass[o] == 0.0 {
                            continue; // a pinned particle takes it
                        }
                        if done.contains(&o) {
                            kicks.push((o, vec3::scale(-1.0, share))); // (a loop: it stays)
                            continue;
                        }
                        let q = pending.entry(o).or_insert([0.0; 3]);
                        *q = vec3::add(*q, share);
                        queue.push(height(o));
                    }
                }
            }
        }
        for &(q, kick) in kicks.iter() {
            vec3::add_scaled(v1, q, set.inv_mass[q], kick);
        }
    }
}

impl ImpulseModel {
    /// Marks as acted on, for the books, the particles a hold's load stayed with (their
    /// velocity took it at the step's end).
    pub(super) fn mark_holds(&mut self) {
        for &(q, _) in &self.hold_kicks {
            self.acted.mark(q);
        }
    }
}

/// A particle's height along the loads (m) and its index: the highest first, ties by index.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Height(f64, usize);

impl Eq for Height {}

impl PartialOrd for Height {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Height {
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&other.0).then(other.1.cmp(&self.1))
    }
}

fn partner_particle(other: Partner) -> Option<usize> {
    match other {
        Partner::Particle(j) => Some(j),
        Partner::Collider(_) => None,
    }
}
