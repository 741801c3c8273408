//! Begin and end of touch: the pairs that touch at each step's end, kept from step to step,
//! and the events when a pair starts or stops touching (Box2D v3's begin and end touch
//! events, `contact.c`; Rapier's `CollisionEvent::Started`/`Stopped`), for the impulse model.
//!
//! A pair (two particles, or a particle and a collider) **touches at a step's end** when the
//! end-of-step solve gave it an impulse (it holds, pushes or bounced something) or its gap
//! there is at most 0 (`Contact::overlap` ≥ 0). A pair of an island asleep keeps touching
//! while it sleeps. It **touched in the step** when it touches at the end or an impact of
//! continuous detection struck it inside the step. Then:
//!
//! ```text
//!   begin   touched in this step, not touching at the last step's end; at the time of its
//!           first impact in the step, else at the step's end
//!   end     touching at the last step's end and not at this one's, or began by an impact in
//!           this step and apart at its end (a bounce within one step): at the step's end;
//!           or one of its particles removed (then at the world's time of the removal)
//! ```
//!
//! A ball dropped on a floor with restitution e therefore begins and ends one touch per
//! bounce, each begin at the time of its impact (t₁ = √(2H/g), then every 2 e^k v₁/g later),
//! until its bounces fall under the restitution threshold and it stays (a begin, no end).
//! Each event holds the normal impulse the pair exchanged in the step (N·s, ≥ 0: the
//! impacts' and the end-of-step total's normal parts), so a begin tells how hard the touch
//! was. Particles are named by their ids (kept for life), colliders by their index.
//!
//! Recording is off until asked for (a gas of 10⁵ particles begins and ends thousands of
//! touches a step); the events wait, in order, until they are taken.

use super::contact::{Contact, Partner};
use super::records::key_of as ordered;
use crate::vec3;

/// One begin or end of touch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TouchEvent {
    /// The world's time of the event, s.
    pub time: f64,
    /// A begin (`true`) or an end of touch.
    pub begin: bool,
    /// The particle's id.
    pub i: u64,
    /// The other particle's id, or `None` against a collider.
    pub j: Option<u64>,
    /// The collider's index, or `None` between particles.
    pub collider: Option<usize>,
    /// The normal impulse the pair exchanged in the step of the event, N·s (≥ 0).
    pub impulse: f64,
}

impl TouchEvent {
    /// The event of the pair (i, `other`) (engine indices), its particles named by `id`.
    fn of(time: f64, begin: bool, (i, other): (usize, Partner), impulse: f64, id: &[u64]) -> TouchEvent {
        let (j, collider) = match other {
            Partner::Particle(j) => (Some(id[j]), None),
            Partner::Collider(k) => (None, Some(k)),
        };
        TouchEvent {
            time,
            begin,
            i: id[i],
            j,
            collider,
            impulse,
        }
    }
}

/// The pairs touching at the last step's end, this step's impacts, and the events waiting.
#[derive(Debug, Clone, Default)]
pub(crate) struct Touches {
    /// Whether events are recorded (the rest is kept only while they are).
    pub on: bool,
    /// The pairs touching at the last step's end, sorted, by engine index (lower first).
    touching: Vec<(usize, Partner)>,
    /// This step's impacts: (time, i, partner, normal impulse N·s), in the order struck.
    hits: Vec<(f64, usize, Partner, f64)>,
    /// The events not yet taken.
    events: Vec<TouchEvent>,
}

impl Touches {
    /// Starts (or stops) recording. Started, the pairs touching now are those whose last
    /// totals were not zero (`loaded`: the contacts' warm start, sorted), so that a pile
    /// resting when recording starts begins nothing.
    pub fn record(&mut self, on: bool, loaded: impl Iterator<Item = (usize, Partner)>) {
        self.on = on;
        self.hits.clear();
        self.touching.clear();
        if on {
            self.touching.extend(loaded);
            self.touching.sort_unstable();
            self.touching.dedup();
        }
    }

    /// A new step begins: no impact yet.
    pub fn begin_step(&mut self) {
        self.hits.clear();
    }

    /// An impact of this step at `time` (s, the world's) between i and `other`, with the
    /// normal impulse `impulse` (N·s).
    pub fn hit(&mut self, time: f64, i: usize, other: Partner, impulse: f64) {
        if self.on {
            let (a, b) = ordered(i, other);
            self.hits.push((time, a, b, impulse.abs()));
        }
    }

    /// The step ended at `end` (s): its end-of-step contacts with their final totals (N·s on
    /// i), whether a particle is asleep now, and the particles' ids. Records the step's
    /// events and keeps the pairs touching now.
    pub fn end_step(&mut self, end: f64, contacts: &[Contact], totals: &[[f64; 3]], asleep: impl Fn(usize) -> bool, id: &[u64]) {
        if !self.on {
            return;
        }
        // (pair, touching at the end, impulse of the step, first impact's time)
        let mut step: Vec<((usize, Partner), bool, f64, Option<f64>)> = contacts
            .iter()
            .zip(totals)
            .map(|(c, p)| {
                let touching = *p != [0.0; 3] || c.overlap >= 0.0;
                (ordered(c.i, c.other), touching, vec3::dot(*p, c.normal).abs(), None)
            })
            .collect();
        step.extend(self.hits.iter().map(|&(t, a, b, imp)| ((a, b), false, imp, Some(t))));
        step.sort_by(|x, y| x.0.cmp(&y.0));
        // one entry per pair: touching if any says so, impulses summed, the earliest impact
        let mut merged: Vec<((usize, Partner), bool, f64, Option<f64>)> = Vec::with_capacity(step.len());
        for s in step {
            match merged.last_mut() {
                Some(m) if m.0 == s.0 => {
                    m.1 |= s.1;
                    m.2 += s.2;
                    m.3 = match (m.3, s.3) {
                        (Some(a), Some(b)) => Some(a.min(b)),
                        (a, b) => a.or(b),
                    };
                }
                _ => merged.push(s),
            }
        }
        let event = |time: f64, begin: bool, pair: (usize, Partner), impulse: f64| TouchEvent::of(time, begin, pair, impulse, id);
        let was = |pair: &(usize, Partner)| self.touching.binary_search(pair).is_ok();
        let mut now: Vec<(usize, Partner)> = Vec::with_capacity(self.touching.len());
        let (mut begins, mut ends): (Vec<TouchEvent>, Vec<TouchEvent>) = (Vec::new(), Vec::new());
        for &(pair, touching, impulse, struck) in &merged {
            let before = was(&pair);
            if !before && (touching || struck.is_some()) {
                begins.push(event(struck.unwrap_or(end), true, pair, impulse));
            }
            if touching {
                now.push(pair);
            } else if before || struck.is_some() {
                ends.push(event(end, false, pair, impulse));
            }
        }
        // pairs touching before that this step did not see: asleep (still touching), or apart
        for &pair in &self.touching {
            if merged.binary_search_by(|m| m.0.cmp(&pair)).is_ok() {
                continue;
            }
            let sleeps = asleep(pair.0) || matches!(pair.1, Partner::Particle(j) if asleep(j));
            if sleeps {
                now.push(pair);
            } else {
                ends.push(event(end, false, pair, 0.0));
            }
        }
        // the begins in time order (a stable sort: pairs in order at one time), then the ends,
        // at the step's end
        begins.sort_by(|a, b| a.time.total_cmp(&b.time));
        self.events.extend(begins);
        self.events.extend(ends);
        now.sort_unstable();
        self.touching = now;
        self.hits.clear();
    }

    /// Particles are being removed at `time` (s; `new_of_old[i]`: particle i's index after,
    /// [`GONE`](crate::limits::GONE) for a removed one; `id`: the ids before): each touching
    /// pair of a removed particle ends, the others are renumbered.
    pub fn renumber(&mut self, new_of_old: &[u32], time: f64, id: &[u64]) {
        use crate::limits::GONE;
        if !self.on {
            return;
        }
        let gone = |q: usize| new_of_old.get(q).is_none_or(|&n| n == GONE);
        let mut kept = Vec::with_capacity(self.touching.len());
        for &(i, other) in &self.touching {
            if gone(i) || matches!(other, Partner::Particle(j) if gone(j)) {
                self.events.push(TouchEvent::of(time, false, (i, other), 0.0, id));
                continue;
            }
            let other = match other {
                Partner::Particle(j) => Partner::Particle(new_of_old[j] as usize),
                c => c,
            };
            kept.push(ordered(new_of_old[i] as usize, other));
        }
        kept.sort_unstable();
        self.touching = kept;
    }

    /// The events recorded since the last take, in order, taken out.
    pub fn take(&mut self) -> Vec<TouchEvent> {
        std::mem::take(&mut self.events)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn contact(i: usize, other: Partner, overlap: f64) -> Contact {
        Contact {
            i,
            other,
            normal: [0.0, 0.0, 1.0],
            overlap,
            u_n: 0.0,
            wall_velocity: [0.0; 3],
        }
    }

    const IDS: [u64; 3] = [10, 11, 12];

    #[test]
    fn an_impact_and_a_load_of_one_pair_begin_one_touch_at_the_impact_with_both_impulses() {
        let mut t = Touches::default();
        t.record(true, std::iter::empty());
        t.begin_step();
        // an impact found from 2's side at 0.25 s, then the pair resting under a load at the
        // step's end (0.5 s), seen from 1's side
        t.hit(0.25, 2, Partner::Particle(1), -3.0);
        t.end_step(
            0.5,
            &[contact(1, Partner::Particle(2), -1e-6)],
            &[[0.0, 0.0, 0.5]],
            |_| false,
            &IDS,
        );
        let ev = t.take();
        assert_eq!(ev.len(), 1);
        assert_eq!(
            (ev[0].begin, ev[0].time, ev[0].i, ev[0].j, ev[0].collider),
            (true, 0.25, 11, Some(12), None)
        );
        assert_eq!(ev[0].impulse, 3.5);
        // the next step: still loaded, nothing; then apart, an end at that step's end
        t.begin_step();
        t.end_step(1.0, &[contact(1, Partner::Particle(2), 0.0)], &[[0.0; 3]], |_| false, &IDS);
        assert!(t.take().is_empty());
        t.begin_step();
        t.end_step(1.5, &[], &[], |_| false, &IDS);
        let ev = t.take();
        assert_eq!((ev.len(), ev[0].begin, ev[0].time), (1, false, 1.5));
    }

    #[test]
    fn a_bounce_within_a_step_begins_and_ends_and_a_sleeper_keeps_touching() {
        let mut t = Touches::default();
        // a pair loaded when recording starts touches already
        t.record(true, [(0, Partner::Collider(0))].into_iter());
        t.begin_step();
        t.hit(0.1, 1, Partner::Collider(0), 2.0);
        // 1 bounced and is apart at the end (a speculative contact); 0 is asleep (no contact)
        t.end_step(0.2, &[contact(1, Partner::Collider(0), -1e-3)], &[[0.0; 3]], |q| q == 0, &IDS);
        let ev = t.take();
        let seen: Vec<_> = ev.iter().map(|e| (e.begin, e.time, e.i, e.collider)).collect();
        assert_eq!(seen, vec![(true, 0.1, 11, Some(0)), (false, 0.2, 11, Some(0))]);
        // awake and apart: the sleeper's touch ends
        t.begin_step();
        t.end_step(0.3, &[], &[], |_| false, &IDS);
        let ev = t.take();
        assert_eq!((ev.len(), ev[0].begin, ev[0].i), (1, false, 10));
    }

    #[test]
    fn nothing_is_kept_or_recorded_while_off() {
        let mut t = Touches::default();
        t.hit(0.1, 1, Partner::Collider(0), 2.0);
        t.end_step(
            0.2,
            &[contact(1, Partner::Collider(0), 0.0)],
            &[[0.0, 0.0, 1.0]],
            |_| false,
            &IDS,
        );
        assert!(t.take().is_empty() && t.touching.is_empty());
    }
}
