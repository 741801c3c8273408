//! The contact records of the impulse model: one per contact of the last step's end, kept
//! from step to step and keyed by its pair, holding what the next step needs of it (Box2D
//! v3's `b2Contact` with its manifold's accumulated impulses, `contact.c`; Rapier's
//! `ContactPair` in its narrow phase's contact graph).
//!
//! A record is made at the end of a step for each end-of-step contact the step keeps (a
//! touching pair, a speculative one within the margin, a particle against a collider), and
//! it holds the solve stage's total impulse of that contact (N·s, the world frame: the
//! next step's **warm start**) and whether its final total carried load (continuous
//! detection then treats an approach of the pair as a resting contact, not an impact:
//! `events::Scene::resting`). The records survive the neighbour list's rebuilds (they
//! are keyed by particles, not by the list) and go to sleep and wake with their island
//! (`collide/sleep.rs`); a checkpoint saves them (`World::collision_carry`); removing and
//! adding particles renumbers them (`ImpulseModel::take_contacts_renumbered`).
//!
//! **The key.** A contact's key is (i, partner, feature) with the lower particle index
//! first for a pair; a particle against a collider is (i, collider, feature), the feature
//! being which part of the collider it touches (`Touch::feature`: a box's wall, a mesh's
//! triangle; 0 for a plane, an obstacle and a pair). A ball in a box's corner touches its
//! floor and a wall at once, two contacts of one pair, and each reads its own record,
//! however the set of walls it touches changes from step to step and through a
//! checkpoint, which saves the feature. (Matching them by pair alone, as a search by pair
//! does, gave both contacts of a corner the same record: the floor's total projected on the
//! wall's normal, and the floor then started cold; matching them by their order among the
//! pair's contacts gave a ball that came to touch a side wall the floor's record on the
//! wall, and none on the floor.) Several contacts of one key, which a mesh may give, read
//! its records in order.
//!
//! **The read.** The step's contacts come in runs sorted by key (the colliders' contacts,
//! then the pairs'; `ImpulseModel::end_contacts`), and the records are sorted by key: each
//! contact finds its record by a merge of the two, one pass over both ([`Records::match_up`]),
//! not a search per contact.

use super::contact::{Contact, Partner};

/// A pair: (particle, partner), the lower particle index first for two particles.
pub(crate) type Pair = (usize, Partner);

/// A contact's key: its pair and the feature of a collider partner (0 for a particle).
pub(crate) type Key = (usize, Partner, u32);

/// The pair of particle i with `other`.
#[inline]
pub(crate) fn pair_of(i: usize, other: Partner) -> Pair {
    match other {
        Partner::Particle(j) if j < i => (j, Partner::Particle(i)),
        o => (i, o),
    }
}

/// One contact's record (see the module's doc); a checkpoint keeps them whole
/// (`World::collision_carry`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactRecord {
    /// The particle (the lower index of a pair).
    pub i: usize,
    /// Its partner: the other particle, or a collider.
    pub other: Partner,
    /// The collider's feature it touches (0 for a particle partner).
    pub feature: u32,
    /// The solve stage's total impulse on i in the last step, N·s (world frame): the warm
    /// start of the next.
    pub impulse: [f64; 3],
    /// Whether its final total in that step was not zero (it carried load).
    pub carried: bool,
}

impl ContactRecord {
    /// Its key.
    #[inline]
    pub fn key(&self) -> Key {
        (self.i, self.other, self.feature)
    }

    /// Its pair.
    #[inline]
    pub fn pair(&self) -> Pair {
        (self.i, self.other)
    }

    /// The record of a contact that holds `impulse` (N·s) from its solve stage, taken to
    /// have carried load if that is not zero (a sleeping island's record as it wakes; a
    /// checkpoint's written before the records kept whether they carried).
    pub fn loaded(i: usize, other: Partner, feature: u32, impulse: [f64; 3]) -> ContactRecord {
        ContactRecord {
            i,
            other,
            feature,
            impulse,
            carried: impulse != [0.0; 3],
        }
    }
}

/// The records of the awake contacts, sorted by key (several of one key in the order of
/// their collider's features).
#[derive(Debug, Clone, Default)]
pub(crate) struct Records {
    rows: Vec<ContactRecord>,
}

impl Records {
    /// The records, sorted by key.
    pub fn rows(&self) -> &[ContactRecord] {
        &self.rows
    }

    pub fn len(&self) -> usize {
        self.rows.len()
    }

    pub fn clear(&mut self) {
        self.rows.clear();
    }

    /// Records in any order, sorted (stable: several of one key keep their order).
    pub fn from_unsorted(mut rows: Vec<ContactRecord>) -> Records {
        rows.sort_by_key(ContactRecord::key);
        Records { rows }
    }

    /// Adds records (an island woken: its records) at the end; [`Records::sort`] then puts
    /// them in place.
    pub fn append(&mut self, more: impl IntoIterator<Item = ContactRecord>) {
        self.rows.extend(more);
    }

    /// Sorts the records by key after [`Records::append`] (stable: several of one key keep
    /// their order; sorted runs are merged in one pass).
    pub fn sort(&mut self) {
        self.rows.sort_by_key(ContactRecord::key);
    }

    /// Takes out the records for which `mine` holds (an island falling asleep), in order.
    pub fn take_where(&mut self, mine: impl Fn(&ContactRecord) -> bool) -> Vec<ContactRecord> {
        let (taken, rest): (Vec<_>, Vec<_>) = self.rows.iter().partition(|r| mine(r));
        self.rows = rest;
        taken
    }

    /// Takes every record out.
    pub fn take(&mut self) -> Vec<ContactRecord> {
        std::mem::take(&mut self.rows)
    }

    /// Whether the pair of i and `other` has a record (without `loaded`), or one that
    /// carried load (with). Against a collider with several records (a box's walls in a
    /// corner), the record of its first feature answers, whichever wall an impact strikes.
    /// (Measured on the 5 × 5 column of `benchmarks/piles.py`, deep3d at 1 ms: with
    /// the first, 14.1 s and 2,060 steps at the sweep cap; with the last, what a search by
    /// key used to find, 19.6 s and 2,521; with any of them, 21.3 s and 2,730: an impact on a
    /// side wall taken as resting because the floor carries. Columns of 750 of three other
    /// seeds, 4 s: the first 6.6, 9.3 and 7.0 s, all asleep; the last 5.5, 12.3 and 11.4 s,
    /// two of them awake; the search by key 8.2, 9.2 and 10.9 s. A key with the feature
    /// would answer exactly.)
    pub fn has(&self, i: usize, other: Partner, loaded: bool) -> bool {
        let pair = pair_of(i, other);
        let first = self.rows.partition_point(|r| r.pair() < pair);
        self.rows
            .get(first)
            .filter(|r| r.pair() == pair)
            .is_some_and(|r| !loaded || r.carried)
    }

    /// Each of `contacts`' record, by index into [`Records::rows`] (`None`: a new contact),
    /// into `out`. `contacts` come in runs sorted by key (each contact's `i` the lower index
    /// of a pair): one pass over the contacts and the records of each run, the k-th contact of
    /// a key (if a key has several) matched with the k-th record of it.
    pub fn match_up(&self, contacts: &[Contact], out: &mut Vec<Option<usize>>) {
        out.clear();
        let rows = &self.rows;
        // (the record's cursor; the last contact's key and how many of it came before)
        let mut at = 0;
        let mut last: Option<(Key, usize)> = None;
        for c in contacts {
            let key = (c.i, c.other, c.feature);
            let ordinal = match last {
                Some((k, n)) if k == key => n + 1,
                Some((k, _)) if k > key => {
                    at = rows.partition_point(|r| r.key() < key); // a new run
                    0
                }
                _ => 0,
            };
            last = Some((key, ordinal));
            if ordinal == 0 {
                while at < rows.len() && rows[at].key() < key {
                    at += 1;
                }
            }
            let k = at + ordinal;
            out.push((k < rows.len() && rows[k].key() == key).then_some(k));
        }
    }

    /// The records of the step's end: each contact for which `kept` holds, with its solve
    /// stage's total `solved` and its final total `total` (N·s), replacing the last step's.
    pub fn replace(&mut self, contacts: &[Contact], solved: &[[f64; 3]], totals: &[[f64; 3]], kept: &[bool]) {
        self.rows.clear();
        for (((c, s), t), _) in contacts.iter().zip(solved).zip(totals).zip(kept).filter(|(_, &k)| k) {
            self.rows.push(ContactRecord {
                i: c.i,
                other: c.other,
                feature: c.feature,
                impulse: *s,
                carried: *t != [0.0; 3],
            });
        }
        // (runs sorted by key: the stable sort merges them and keeps a key's features in order)
        self.rows.sort_by_key(ContactRecord::key);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn contact(i: usize, other: Partner, feature: u32) -> Contact {
        Contact {
            i,
            other,
            feature,
            normal: [0.0, 0.0, 1.0],
            overlap: 0.0,
            u_n: 0.0,
            wall_velocity: [0.0; 3],
        }
    }

    fn record(i: usize, other: Partner, feature: u32, z: f64) -> ContactRecord {
        ContactRecord::loaded(i, other, feature, [0.0, 0.0, z])
    }

    fn read(records: &Records, contacts: &[Contact]) -> Vec<Option<f64>> {
        let mut out = Vec::new();
        records.match_up(contacts, &mut out);
        out.iter().map(|k| k.map(|k| records.rows()[k].impulse[2])).collect()
    }

    #[test]
    fn each_contact_reads_its_own_record_and_each_wall_of_a_corner_its_own() {
        use Partner::{Collider as C, Particle as P};
        // the records of the last step, sorted: ball 0 in a corner of box 0 (its walls −x and
        // −z: features 0 and 4), pairs 0–1 and 1–2, ball 2 on the floor
        let records = Records::from_unsorted(vec![
            record(2, C(0), 4, 5.0),
            record(0, C(0), 4, 2.0),
            record(0, C(0), 0, 1.0),
            record(1, P(2), 0, 4.0),
            record(0, P(1), 0, 3.0),
        ]);
        // this step's contacts as end_contacts makes them: the colliders' run, then the pairs';
        // ball 0 in its corner still, 2 has left the floor, a new pair 0–2
        let contacts = [
            contact(0, C(0), 0),
            contact(0, C(0), 4),
            contact(0, P(1), 0),
            contact(0, P(2), 0),
            contact(1, P(2), 0),
        ];
        assert_eq!(read(&records, &contacts), [Some(1.0), Some(2.0), Some(3.0), None, Some(4.0)]);
        // ball 0 comes to touch the wall −y (feature 2) and leaves the wall −x: the floor keeps
        // its record, the new wall has none (read by their order among the ball's contacts,
        // the wall −y took the record of the wall −x)
        assert_eq!(read(&records, &[contact(0, C(0), 2), contact(0, C(0), 4)]), [None, Some(2.0)]);
        // ball 2 on the floor comes to touch the wall −x: the floor's record is still its own
        // (read by their order, the wall took the floor's record and the floor started cold)
        assert_eq!(read(&records, &[contact(2, C(0), 0), contact(2, C(0), 4)]), [None, Some(5.0)]);
        // a pair's lookup sees it from both sides; against a collider, its first feature answers
        assert!(records.has(2, P(1), true) && records.has(1, P(2), true) && !records.has(2, P(0), false));
        assert!(records.has(0, C(0), true) && records.has(2, C(0), true) && !records.has(1, C(0), false));
    }

    #[test]
    fn the_records_of_a_step_are_its_kept_contacts_sorted_by_key() {
        use Partner::{Collider as C, Particle as P};
        let contacts = [contact(3, C(1), 2), contact(0, P(3), 0), contact(1, P(2), 0)];
        let solved = [[0.0, 0.0, 1.0], [0.0; 3], [0.0, 0.0, 2.0]];
        let totals = [[0.0, 0.0, 1.5], [0.0; 3], [0.0; 3]];
        let mut records = Records::default();
        records.replace(&contacts, &solved, &totals, &[true, true, false]);
        let keys: Vec<Key> = records.rows().iter().map(ContactRecord::key).collect();
        assert_eq!(keys, [(0, P(3), 0), (3, C(1), 2)]);
        assert!(records.rows()[1].carried && !records.rows()[0].carried);
        assert!(records.has(3, C(1), true) && !records.has(3, P(0), true) && records.has(3, P(0), false));
    }
}
