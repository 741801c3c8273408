//! The event calendar: each particle's next event, by time, in buckets (Smallenburg's EDMD
//! event list, after the calendar queues of Paul, J. Comput. Phys. 221, 615 (2007)).
//!
//! Time is cut into buckets of width w. The bucket of the present, and every event at or
//! before it, sits in a binary heap ordered by (time, particle); the next `len` − 1 buckets
//! are unsorted lists in a ring (absolute bucket b at slot b mod len); later events wait in
//! an overflow list, which is swept into the ring once every `len` buckets. Taking the next
//! event costs a heap pop over the few events of one bucket, and scheduling one costs a push
//! onto a list: O(1) per event instead of O(log N), when w is chosen so that a bucket holds a
//! few events ([`Calendar::width_for`]).
//!
//! Each particle has one event at a time. Rescheduling a particle does not look for its old
//! entry: the entry holds the particle's schedule version, and an entry whose version is no
//! longer the particle's is dropped when it comes up (lazy deletion).

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use crate::collide::domain::floor;

/// One scheduled event: when, whose, which of its schedules, and what (the caller's).
#[derive(Debug, Clone, Copy)]
pub(super) struct Entry<T> {
    /// Absolute time, s.
    pub time: f64,
    pub particle: u32,
    pub version: u32,
    pub what: T,
}

impl<T> PartialEq for Entry<T> {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl<T> Eq for Entry<T> {}
impl<T> PartialOrd for Entry<T> {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl<T> Ord for Entry<T> {
    /// Reversed, so that `BinaryHeap` (a max-heap) gives the earliest first; ties by particle
    /// index, so that the order of simultaneous events is fixed.
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .time
            .total_cmp(&self.time)
            .then(other.particle.cmp(&self.particle))
            .then(other.version.cmp(&self.version))
    }
}

/// The bucketed calendar (module doc).
pub(super) struct Calendar<T> {
    /// Bucket width w, s, and its inverse.
    width: f64,
    inv_width: f64,
    /// Time of bucket 0's start, s.
    origin: f64,
    /// The bucket of the present (absolute index): it and every earlier one are in `heap`.
    current: i64,
    /// The bucket at which the overflow was last swept into the ring.
    swept: i64,
    heap: BinaryHeap<Entry<T>>,
    /// The ring's buckets, a power of two of them: absolute bucket b is at slot b & `mask`
    /// (b mod len, without a division).
    ring: Vec<Vec<Entry<T>>>,
    mask: i64,
    /// Entries in the ring.
    in_ring: usize,
    overflow: Vec<Entry<T>>,
}

impl<T: Copy> Calendar<T> {
    /// An empty calendar from time `origin` (s), buckets `width` s wide (> 0), `len` of them
    /// in the ring (rounded up to a power of two).
    pub fn new(origin: f64, width: f64, len: usize) -> Self {
        let len = len.max(1).next_power_of_two();
        Calendar {
            width,
            inv_width: 1.0 / width,
            origin,
            current: 0,
            swept: 0,
            heap: BinaryHeap::new(),
            ring: vec![Vec::new(); len],
            mask: len as i64 - 1,
            in_ring: 0,
            overflow: Vec::new(),
        }
    }

    /// A bucket width for `events` pending events at mean distance `mean_wait` s ahead of
    /// now: the calendar then holds about `PER_BUCKET` events a bucket (the rate of events is
    /// about events / mean_wait). Positive and finite for any input.
    pub fn width_for(events: usize, mean_wait: f64) -> f64 {
        const PER_BUCKET: f64 = 4.0;
        let w = PER_BUCKET * mean_wait / events.max(1) as f64;
        if w.is_finite() && w > 0.0 {
            w
        } else {
            1.0
        }
    }

    /// The absolute bucket of time `t`, s.
    #[inline(always)]
    fn bucket(&self, t: f64) -> i64 {
        let b = floor((t - self.origin) * self.inv_width);
        // (saturating: a time far beyond the ring is overflow whatever its bucket)
        if b >= i64::MAX as f64 {
            i64::MAX
        } else if b <= i64::MIN as f64 {
            i64::MIN
        } else {
            b as i64
        }
    }

    /// Schedules an entry (its time finite).
    #[inline(always)]
    pub fn push(&mut self, e: Entry<T>) {
        let b = self.bucket(e.time);
        let len = self.ring.len() as i64;
        if b <= self.current {
            self.heap.push(e);
        } else if b - self.current < len {
            self.ring[(b & self.mask) as usize].push(e);
            self.in_ring += 1;
        } else {
            self.overflow.push(e);
        }
    }

    /// The earliest entry that `live` accepts (the particle's current version), removed from
    /// the calendar, if it is at or before `until` (s); stale entries met on the way are
    /// dropped. `None`: no live entry until then (a later one stays).
    #[inline(always)]
    pub fn pop_until(&mut self, until: f64, live: impl Fn(&Entry<T>) -> bool) -> Option<Entry<T>> {
        loop {
            while let Some(top) = self.heap.peek() {
                if !live(top) {
                    self.heap.pop();
                    continue;
                }
                if top.time > until {
                    return None;
                }
                return self.heap.pop();
            }
            // The present bucket is done: on to the next that holds anything.
            if self.in_ring == 0 && self.overflow.is_empty() {
                return None;
            }
            let next_start = self.origin + (self.current + 1) as f64 * self.width;
            if next_start > until {
                return None;
            }
            self.advance();
        }
    }

    /// Moves the present to the next bucket (jumping over an empty ring to the overflow's
    /// earliest bucket), sweeping the overflow into the ring when due.
    fn advance(&mut self) {
        let len = self.ring.len() as i64;
        if self.in_ring == 0 {
            // Nothing in the ring: the next event is in the overflow; go straight to it.
            let first = self
                .overflow
                .iter()
                .map(|e| self.bucket(e.time))
                .min()
                .unwrap_or(self.current + 1);
            self.current = first.max(self.current + 1);
            self.sweep();
        } else {
            self.current += 1;
            if self.current - self.swept >= len {
                self.sweep();
            }
        }
        let slot = (self.current & self.mask) as usize;
        self.in_ring -= self.ring[slot].len();
        let heap = &mut self.heap;
        heap.extend(self.ring[slot].drain(..));
    }

    /// Puts every overflow entry within the ring's reach into it (or the heap).
    fn sweep(&mut self) {
        self.swept = self.current;
        let waiting = std::mem::take(&mut self.overflow);
        for e in waiting {
            self.push(e);
        }
    }

    /// Entries held, stale ones included.
    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.heap.len() + self.in_ring + self.overflow.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Random times through many buckets and the overflow, some rescheduled: the calendar
    /// gives back exactly the live entries, in time order — what a sorted list gives.
    #[test]
    fn gives_the_live_entries_in_time_order() {
        let mut next = super::super::tests::uniform(12345);
        let n = 500;
        let mut cal: Calendar<()> = Calendar::new(0.0, 0.01, 16);
        let mut version = vec![0u32; n];
        let mut due = vec![0.0; n];
        for i in 0..n {
            due[i] = 10.0 * next();
            cal.push(Entry {
                time: due[i],
                particle: i as u32,
                version: 0,
                what: (),
            });
        }
        // reschedule a third of them (the old entries go stale)
        for i in (0..n).step_by(3) {
            version[i] += 1;
            due[i] = 10.0 * next();
            cal.push(Entry {
                time: due[i],
                particle: i as u32,
                version: version[i],
                what: (),
            });
        }
        assert_eq!(cal.len(), n + (n + 2) / 3);
        let mut expected: Vec<(f64, u32)> = (0..n).map(|i| (due[i], i as u32)).collect();
        expected.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut got = Vec::new();
        while let Some(e) = cal.pop_until(f64::INFINITY, |e| e.version == version[e.particle as usize]) {
            got.push((e.time, e.particle));
        }
        assert_eq!(got, expected);
    }

    /// An entry after `until` stays for the next call; one pushed behind the present goes
    /// first.
    #[test]
    fn stops_at_until_and_keeps_the_rest() {
        let mut cal: Calendar<()> = Calendar::new(0.0, 1.0, 4);
        for (k, t) in [0.5, 2.5, 30.0].into_iter().enumerate() {
            cal.push(Entry {
                time: t,
                particle: k as u32,
                version: 0,
                what: (),
            });
        }
        let live = |_: &Entry<()>| true;
        assert_eq!(cal.pop_until(1.0, live).map(|e| e.particle), Some(0));
        assert!(cal.pop_until(1.0, live).is_none());
        assert_eq!(cal.pop_until(3.0, live).map(|e| e.particle), Some(1));
        cal.push(Entry {
            time: 2.9,
            particle: 7,
            version: 0,
            what: (),
        });
        assert_eq!(cal.pop_until(100.0, live).map(|e| e.particle), Some(7));
        assert_eq!(cal.pop_until(100.0, live).map(|e| e.particle), Some(2));
        assert!(cal.pop_until(f64::INFINITY, live).is_none());
    }
}
