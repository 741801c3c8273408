//! The contact records of the impulse model: one per contact of the last step's end, kept
//! from step to step and keyed by its pair, holding what the next step needs of it (Box2D
//! v3's `b2Contact` with its manifold's accumulated impulses, `contact.c`; Rapier's
//! `ContactPair` in its narrow phase's contact graph).
//!
//! A record is made at the end of a step for each end-of-step contact the step keeps (a
//! touching pair, a speculative one within the margin, a particle against a collider), and
//! it holds the solve stage's total impulse of that contact (N·s, the world frame: the
//! next step's **warm start**) and whether its final total bore load (continuous
//! detection then treats an approach of the pair as a resting contact, not an impact:
//! `events::Surroundings::resting`). The records survive the neighbour list's rebuilds (they
//! are keyed by particles, not by the list) and go to sleep and wake with their island
//! (`collide/sleep.rs`); a checkpoint saves them (`World::collision_carry`); removing and
//! adding particles renumbers them (`ImpulseModel::take_contacts_renumbered`).
//!
//! **The key.** A pair's key is (i, partner) with the lower particle index first; a
//! particle against a collider is (i, collider). Those are one contact each, except
//! against a collider that touches a ball in several places at once (a box's floor and
//! wall in a corner, a mesh's two faces in a crease): such contacts share their key and
//! come in the order of the collider's features (`Collider::for_each_touch`: a box's walls
//! in order, a mesh's triangles in order), and the k-th contact of a key reads the k-th
//! record of it. (Matching them by key alone, as a search by key does, gave both contacts
//! of a corner the same record: the floor's total projected on the wall's normal, and the
//! floor then started cold.) A key with the feature touched (Box2D's feature ids) would
//! match a corner's contacts exactly also while its set of walls changes; measured, it
//! did not pay: on the demo's heap (16 seeds at 60 Hz) 15 % more steps at the solve's
//! pass cap, 3 seeds awake after 4 s against 1 (5 seeds at 1 ms: 9 % more); a contact
//! that a wall's changed record left cold costs less than one that an exact record
//! pushes with the impulse of its last touch.
//!
//! **The read.** The step's contacts come in runs sorted by key (the colliders' contacts,
//! then the pairs'; `ImpulseModel::end_contacts`), and the records are sorted by key: each
//! contact finds its record by a merge of the two, one pass over both ([`Records::match_up`]),
//! not a search per contact.

use super::contact::{Contact, Partner};

/// A contact's key: (particle, partner), the lower particle index first for a pair.
pub(crate) type Key = (usize, Partner);

/// The key of the contact of particle i with `other`.
#[inline]
pub(crate) fn key_of(i: usize, other: Partner) -> Key {
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
    /// The solve stage's total impulse on i in the last step, N·s (world frame): the warm
    /// start of the next.
    pub impulse: [f64; 3],
    /// Whether its final total in that step was not zero (it bore load; `carried` is the name
    /// the binding and the checkpoints use).
    pub carried: bool,
}

impl ContactRecord {
    /// Its key.
    #[inline]
    pub fn key(&self) -> Key {
        (self.i, self.other)
    }

    /// The record of a contact that holds `impulse` (N·s) from its solve stage, taken to
    /// have borne load if that is not zero (a sleeping island's record as it wakes; a
    /// checkpoint's written before the records kept whether they bore load).
    pub fn loaded(i: usize, other: Partner, impulse: [f64; 3]) -> ContactRecord {
        ContactRecord {
            i,
            other,
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
    /// bore load (with). Against a collider with several records (a box's walls in a
    /// corner), the record of its first feature answers: which wall an impact strikes is not
    /// in the key. (Measured on the 5 × 5 column of `benchmarks/piles.py`, deep3d at 1 ms: with
    /// the first, 14.1 s and 2,060 steps at the pass cap; with the last, what a search by
    /// key used to find, 19.6 s and 2,521; with any of them, 21.3 s and 2,730: an impact on a
    /// side wall taken as resting because the floor bears the load. Columns of 750 of three other
    /// seeds, 4 s: the first 6.6, 9.3 and 7.0 s, all asleep; the last 5.5, 12.3 and 11.4 s,
    /// two of them awake; the search by key 8.2, 9.2 and 10.9 s. A key with the feature
    /// would answer exactly.)
    pub fn has(&self, i: usize, other: Partner, loaded: bool) -> bool {
        let key = key_of(i, other);
        let first = self.rows.partition_point(|r| r.key() < key);
        self.rows
            .get(first)
            .filter(|r| r.key() == key)
            .is_some_and(|r| !loaded || r.carried)
    }

    /// Each of `contacts`' record, by index into [`Records::rows`] (`None`: a new contact),
    /// into `out`. `contacts` come in runs sorted by key (each contact's `i` the lower index
    /// of a pair): one pass over the contacts and the records of each run, the k-th contact of
    /// a key matched with the k-th record of it.
    pub fn match_up(&self, contacts: &[Contact], out: &mut Vec<Option<usize>>) {
        out.clear();
        let rows = &self.rows;
        // (the record's cursor; the last contact's key and how many of it came before)
        let mut at = 0;
        let mut last: Option<(Key, usize)> = None;
        for c in contacts {
            let key = (c.i, c.other);
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

    fn contact(i: usize, other: Partner) -> Contact {
        Contact {
            i,
            other,
            normal: [0.0, 0.0, 1.0],
            overlap: 0.0,
            u_n: 0.0,
            wall_velocity: [0.0; 3],
        }
    }

    fn record(i: usize, other: Partner, z: f64) -> ContactRecord {
        ContactRecord::loaded(i, other, [0.0, 0.0, z])
    }

    #[test]
    fn each_contact_reads_its_own_record_and_a_corner_its_two() {
        use Partner::{Collider as C, Particle as P};
        // the records of the last step, sorted: ball 0 in a corner of box 0 (two walls),
        // pairs 0–1 and 1–2, ball 2 on the floor
        let records = Records::from_unsorted(vec![
            record(2, C(0), 5.0),
            record(0, C(0), 1.0),
            record(0, C(0), 2.0),
            record(1, P(2), 4.0),
            record(0, P(1), 3.0),
        ]);
        // this step's contacts as end_contacts makes them: the colliders' run, then the pairs';
        // ball 0 in its corner still, 2 has left the floor, a new pair 0–2
        let contacts = [
            contact(0, C(0)),
            contact(0, C(0)),
            contact(0, P(1)),
            contact(0, P(2)),
            contact(1, P(2)),
        ];
        let mut out = Vec::new();
        records.match_up(&contacts, &mut out);
        let read: Vec<Option<f64>> = out.iter().map(|k| k.map(|k| records.rows()[k].impulse[2])).collect();
        assert_eq!(read, [Some(1.0), Some(2.0), Some(3.0), None, Some(4.0)]);
        // a corner's third contact has no record; a key's lookup sees each pair from both sides
        records.match_up(&[contact(0, C(0)), contact(0, C(0)), contact(0, C(0))], &mut out);
        assert_eq!(out, [Some(1), Some(2), None]);
        assert!(records.has(2, P(1), true) && records.has(1, P(2), true) && !records.has(2, P(0), false));
    }

    #[test]
    fn the_records_of_a_step_are_its_kept_contacts_sorted_by_key() {
        use Partner::{Collider as C, Particle as P};
        let contacts = [contact(3, C(1)), contact(0, P(3)), contact(1, P(2))];
        let solved = [[0.0, 0.0, 1.0], [0.0; 3], [0.0, 0.0, 2.0]];
        let totals = [[0.0, 0.0, 1.5], [0.0; 3], [0.0; 3]];
        let mut records = Records::default();
        records.replace(&contacts, &solved, &totals, &[true, true, false]);
        let keys: Vec<Key> = records.rows().iter().map(ContactRecord::key).collect();
        assert_eq!(keys, [(0, P(3)), (3, C(1))]);
        assert!(records.rows()[1].carried && !records.rows()[0].carried);
        assert!(records.has(3, C(1), true) && !records.has(3, P(0), true) && records.has(3, P(0), false));
    }
}
