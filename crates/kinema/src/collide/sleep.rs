//! Sleeping: islands of the impulse model at rest take no work until something reaches them.
//!
//! A settled pile is solved again at every step's end although nothing in it moves. As Box2D,
//! Bullet and Chipmunk do, each particle keeps how long it has been *calm* (its speed, and
//! its displacement over the step divided by the step, both at most the sleep speed), and an
//! island of the end-of-step contacts (`collide/islands.rs`) whose particles have all been
//! calm for the sleep time falls asleep: its velocities become exactly 0 (their kinetic
//! energy, at most ½ m v_sleep² each, is booked as lost), and from then on its particles are
//! not moved by the integrator's result, start no impact search, and take no part in the
//! end-of-step solve. Its contacts' warm start is put aside with it, so that it wakes warm.
//!
//! **Which islands may sleep.** Only one that rests on something that does not move: a
//! collider, or a pinned particle. A cluster floating free (a granular gas's clump, a body in
//! free fall, a slow ball gliding through space) never sleeps: stopping it would change its
//! momentum, and nothing holds it. And only while no force depends on the positions or adds
//! energy (the world decides, `World::collide`): a spring or a user's force could pull a
//! sleeper, and nothing would notice.
//!
//! **The sleep speed.** By default Chipmunk's rule: the largest speed change the forces gave
//! any particle in the step (g·h under gravity, 9.8 mm/s at h = 1 ms), the resolution below
//! which a body under those forces cannot be told from one at rest within a step. A resting
//! pile held by the soft step moves far slower (10⁻⁵ m/s); a settling one, or a ball at the
//! top of a bounce, is faster or calm for less than the sleep time (0.5 s by default, Box2D's
//! `b2_timeToSleep`).
//!
//! **What wakes an island**, and how (Box2D's rule: touching links islands):
//! - an impact of an awake particle on one of its particles (continuous detection sees the
//!   sleepers as bodies at rest; the one hit is awake from the hit on, the rest of its island
//!   from the step's end);
//! - an end-of-step contact (within the speculative margin) between one of its particles and
//!   an awake one: the whole island joins that step's solve;
//! - anything the user changes: positions, velocities, masses, forces, colliders, settings
//!   (`World::reset_caches` wakes every island). Adding particles wakes nothing by itself: a
//!   newborn that lands on a pile wakes it by its contact.
//!
//! An island wakes with the velocities it slept with (0) and its warm start, so a pile woken
//! by a touch is solved from where it was.

use super::records::ContactRecord;

/// A particle that sleeps in no island.
pub(crate) const AWAKE: u32 = u32::MAX;

/// An island asleep.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct SleepingIsland {
    /// Its particles, ascending.
    pub members: Vec<usize>,
    /// Its contacts' records (`collide/records.rs`), sorted by key.
    pub records: Vec<ContactRecord>,
    /// The largest overlap of its contacts, m (its particles do not move while it sleeps).
    pub max_overlap: f64,
}

/// Each particle's calm time and island, and the islands asleep.
#[derive(Debug, Clone, Default)]
pub(crate) struct Sleep {
    /// How long each particle has been calm, s (0 for one asleep: it starts again on waking).
    pub calm: Vec<f64>,
    /// The island each particle sleeps in, or [`AWAKE`]; empty while none sleeps.
    pub island: Vec<u32>,
    /// The islands, by number (`None`: a free number).
    islands: Vec<Option<SleepingIsland>>,
    /// Particles asleep, and the contacts of their islands.
    asleep: usize,
    contacts: usize,
}

impl Sleep {
    /// Whether any particle sleeps.
    pub fn any(&self) -> bool {
        self.asleep > 0
    }

    /// The number of particles asleep.
    pub fn asleep(&self) -> usize {
        self.asleep
    }

    /// The number of contacts in the islands asleep.
    pub fn contacts(&self) -> usize {
        self.contacts
    }

    /// Whether particle q sleeps.
    #[inline]
    pub fn is_asleep(&self, q: usize) -> bool {
        self.island.get(q).is_some_and(|&k| k != AWAKE)
    }

    /// The particles' marks for detection: each one's island or [`AWAKE`] (empty while none
    /// sleeps).
    pub fn marks(&self) -> &[u32] {
        if self.any() {
            &self.island
        } else {
            &[]
        }
    }

    /// Makes room for `n` particles (new ones awake, not calm).
    pub fn resize(&mut self, n: usize) {
        self.calm.resize(n, 0.0);
        if !self.island.is_empty() {
            self.island.resize(n, AWAKE);
        }
    }

    /// Wakes everything and forgets every calm time (what the user changed may reach any
    /// particle); the islands' warm starts are dropped with them.
    pub fn wake_all(&mut self) {
        self.calm.clear();
        self.island.clear();
        self.islands.clear();
        self.asleep = 0;
        self.contacts = 0;
    }

    /// The largest overlap among the sleeping islands, m (0 if none).
    pub fn max_overlap(&self) -> f64 {
        self.islands.iter().flatten().map(|s| s.max_overlap).fold(0.0, f64::max)
    }

    /// Puts an island to sleep: its particles `members` (ascending), its contacts' records
    /// (sorted) and their largest overlap (m). Their calm times start again.
    pub fn put_to_sleep(&mut self, members: Vec<usize>, records: Vec<ContactRecord>, max_overlap: f64) {
        let n = self.calm.len();
        if self.island.len() != n {
            self.island.clear();
            self.island.resize(n, AWAKE);
        }
        let k = match self.islands.iter().position(Option::is_none) {
            Some(k) => k,
            None => {
                self.islands.push(None);
                self.islands.len() - 1
            }
        };
        for &q in &members {
            self.island[q] = k as u32;
            self.calm[q] = 0.0;
        }
        self.asleep += members.len();
        self.contacts += records.len();
        self.islands[k] = Some(SleepingIsland {
            members,
            records,
            max_overlap,
        });
    }

    /// Wakes the island particle q sleeps in (nothing if q is awake): returns it (its members
    /// and warm start), its particles marked awake.
    pub fn wake(&mut self, q: usize) -> Option<SleepingIsland> {
        let k = *self.island.get(q)?;
        if k == AWAKE {
            return None;
        }
        let island = self.islands[k as usize].take().expect("a particle's island exists");
        for &m in &island.members {
            self.island[m] = AWAKE;
        }
        self.asleep -= island.members.len();
        self.contacts -= island.records.len();
        if self.asleep == 0 {
            self.island.clear();
            self.islands.clear();
        }
        Some(island)
    }

    /// What a checkpoint keeps of `n` particles: each one's calm time (s) and island number
    /// (−1: awake). With the warm start (which holds the sleeping islands' contacts too) that
    /// is all.
    pub fn carry(&self, n: usize) -> (Vec<f64>, Vec<i64>) {
        let mut calm = self.calm.clone();
        calm.resize(n, 0.0);
        let island = (0..n)
            .map(|q| match self.island.get(q) {
                Some(&k) if k != AWAKE => k as i64,
                _ => -1,
            })
            .collect();
        (calm, island)
    }

    /// The sleeping islands' contact records (for a checkpoint: the awake records with these
    /// are every contact's).
    pub fn records(&self) -> impl Iterator<Item = &ContactRecord> {
        self.islands.iter().flatten().flat_map(|s| s.records.iter())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn islands_sleep_and_wake_whole() {
        let mut s = Sleep::default();
        s.resize(6);
        assert!(!s.any() && s.marks().is_empty());
        use crate::collide::Partner;
        let warm = vec![
            ContactRecord::loaded(1, Partner::Particle(2), [0.0, 1.0, 0.0]),
            ContactRecord::loaded(2, Partner::Collider(0), [0.0, 2.0, 0.0]),
        ];
        s.put_to_sleep(vec![1, 2], warm.clone(), 1e-5);
        s.put_to_sleep(
            vec![4],
            vec![ContactRecord::loaded(4, Partner::Collider(0), [0.0, 3.0, 0.0])],
            2e-5,
        );
        assert_eq!((s.asleep(), s.contacts()), (3, 3));
        assert!(s.is_asleep(1) && s.is_asleep(2) && s.is_asleep(4) && !s.is_asleep(0));
        assert_eq!(s.max_overlap(), 2e-5);
        assert_eq!(s.carry(6).1, vec![-1, 0, 0, -1, 1, -1]);
        // waking one member wakes its island, and gives its warm start back
        let woken = s.wake(2).expect("2 sleeps");
        assert_eq!(woken.members, vec![1, 2]);
        assert_eq!(woken.records, warm);
        assert!(!s.is_asleep(1) && s.is_asleep(4));
        assert!(s.wake(1).is_none(), "already awake");
        assert_eq!(s.max_overlap(), 2e-5);
        // the freed number is taken again
        s.put_to_sleep(vec![0], Vec::new(), 0.0);
        assert_eq!(s.carry(6).1[0], 0);
        s.resize(8);
        assert!(!s.is_asleep(7));
        s.wake_all();
        assert!(!s.any() && (0..8).all(|q| !s.is_asleep(q)));
    }
}
