//! The passes of the end-of-step contact solve (`soft_step`'s velocities and positions):
//! over the contacts one after the other, or, where the contacts come in colours
//! (`collide/islands.rs`), colour by colour on all threads.
//!
//! A pass visits every contact once; a visit reads and writes the N-vectors of its two
//! particles (velocities, N = 3; velocities and angular velocities, N = 6, with spin) and its
//! own state (the totals of impulse). The
//! contacts of one colour share no movable particle, so their visits commute: done at once,
//! they give what they give in order, and the result cannot depend on the thread count.
//!
//! On threads the passes run as Box2D v3's solver stages do: each thread that joins takes
//! the next block of the current colour from a counter, visits it, counts it done, and
//! when the colour has no block left waits (spinning) until every block is done; then the
//! next colour. The threads are started once for all the passes, not once a colour (a
//! thread woken from sleep costs as much as a colour of a thousand visits). Nothing waits
//! on a thread that has not joined: a block is counted only when a running thread takes it,
//! so one thread alone does every block (a thread that joins late finds the colours done
//! and only reads where the others stopped).

use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

use super::contact::Contact;
use super::shock::Held;

/// Passes run on all threads when a colour has at least this many contacts (below, the
/// waits cost more than the visits; the result is the same either way). Since the pass in
/// order is inlined with its visit, the demo's heap (colours of 150–300 contacts) ran its
/// 4 s in 0.44 s on 2 threads with 256 and 0.39 s with 512 (1 thread: 0.39 s), the 2D
/// pour at the animation grade in 2.45 s with 512 and 2.68 s with 1024 (1 thread: 2.68 s).
pub(crate) const PARALLEL_COLOUR: usize = 512;

/// The least block of contacts a thread takes at once.
const BLOCK: usize = 32;

/// Contacts that a pass visits as one: the contacts `range` of the list, and whether they
/// share no movable particle (`together`: a colour, visited at once on all threads) or are
/// visited in order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct PassGroup {
    pub range: std::ops::Range<usize>,
    pub together: bool,
}

impl PassGroup {
    /// The contacts `range`, visited one after the other.
    pub fn in_order(range: std::ops::Range<usize>) -> Self {
        PassGroup { range, together: false }
    }
}

/// The two particles whose velocities one visit of a contact reads (j: none for a
/// collider, whose side is its surface's velocity `wall`), and which of them it may change
/// (an immovable side never changes).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Ends {
    pub i: usize,
    pub j: Option<usize>,
    wall: [f64; 3],
    write_i: bool,
    write_j: bool,
}

impl Ends {
    /// The contact's ends in a world with these inverse masses (1/kg); none if both are
    /// immovable (such a contact is skipped).
    pub fn of(c: &Contact, inv_mass: &[f64]) -> Option<Ends> {
        let j = c.partner_particle();
        let (wi, wj) = (inv_mass[c.i], j.map_or(0.0, |j| inv_mass[j]));
        (wi + wj > 0.0).then_some(Ends {
            i: c.i,
            j,
            wall: c.wall_velocity,
            write_i: wi > 0.0,
            write_j: wj > 0.0,
        })
    }

    /// Whether a visit may change i's, and j's, N-vector.
    pub fn writes_i(&self) -> bool {
        self.write_i
    }
    pub fn writes_j(&self) -> bool {
        self.write_j
    }

    /// The same ends with one side held still (`collide/shock.rs`).
    pub fn held(self, held: Held) -> Ends {
        Ends {
            write_i: self.write_i && held != Held::I,
            write_j: self.write_j && held != Held::J,
            ..self
        }
    }

    /// A collider's side as an N-vector: its surface's velocity, and no turning.
    fn wall<const N: usize>(&self) -> [f64; N] {
        let mut w = [0.0; N];
        w[..3].copy_from_slice(&self.wall);
        w
    }

    /// The N-vectors of i and j (a collider's surface velocity) in the flat array `a` of N
    /// values per particle.
    ///
    /// Each N-vector is read as one block and written back as one block ([`Ends::store`]):
    /// the next visit of a particle often follows at once (a pass in contact order), and its
    /// read must find the last write whole in the store buffer. Read and written value by
    /// value or in pieces that the compiler chose differently for the two (which changed with
    /// unrelated code around them), the reads waited on the writes: the demo's solve at 1 ms
    /// ran 29 % slower for the same work, bit for bit.
    #[inline(always)]
    pub fn load<const N: usize>(&self, a: &[f64]) -> ([f64; N], [f64; N]) {
        let get = |q: usize| -> [f64; N] {
            let block = &a[N * q..N * q + N];
            // SAFETY: `block` holds exactly N values (the slice above is checked)
            unsafe { std::ptr::read_unaligned(block.as_ptr().cast::<[f64; N]>()) }
        };
        (get(self.i), self.j.map_or_else(|| self.wall(), get))
    }

    /// Writes back the N-vectors of the movable sides, each as one block.
    #[inline(always)]
    pub fn store<const N: usize>(&self, a: &mut [f64], ai: [f64; N], aj: [f64; N]) {
        let mut put = |q: usize, v: [f64; N]| {
            let block = &mut a[N * q..N * q + N];
            // SAFETY: `block` holds exactly N values (the slice above is checked)
            unsafe { std::ptr::write_unaligned(block.as_mut_ptr().cast::<[f64; N]>(), v) }
        };
        if self.write_i {
            put(self.i, ai);
        }
        if let Some(j) = self.j.filter(|_| self.write_j) {
            put(j, aj);
        }
    }

    /// [`Ends::load`] through a pointer to the array.
    ///
    /// # Safety
    /// `a` points to an array that holds both particles, which no thread writes meanwhile.
    unsafe fn load_from<const N: usize>(&self, a: *const f64) -> ([f64; N], [f64; N]) {
        // one read of the N values (copied as a block, as the visit then reads them: read
        // value by value, the visit's wider loads waited on the narrow stores, and a
        // 2-thread pass ran 25 % slower)
        let get = |q: usize| -> [f64; N] { std::ptr::read_unaligned(a.add(N * q).cast::<[f64; N]>()) };
        (get(self.i), self.j.map_or_else(|| self.wall(), get))
    }

    /// [`Ends::store`] through a pointer to the array.
    ///
    /// # Safety
    /// `a` points to an array that holds both particles, whose movable sides no other thread
    /// reads or writes meanwhile.
    unsafe fn store_to<const N: usize>(&self, a: *mut f64, ai: [f64; N], aj: [f64; N]) {
        let put = |q: usize, v: [f64; N]| std::ptr::write_unaligned(a.add(N * q).cast::<[f64; N]>(), v);
        if self.write_i {
            put(self.i, ai);
        }
        if let Some(j) = self.j.filter(|_| self.write_j) {
            put(j, aj);
        }
    }
}

/// What [`passes`] did: the passes made, the largest change of the last one, and whether
/// it was at most the tolerance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PassesDone {
    pub passes: usize,
    pub last_change: f64,
    pub converged: bool,
}

/// Passes over the contacts, group after group (`groups` cover them in order), until a pass
/// changes nothing by more than `tolerance` or `most` passes are made: each contact k with
/// ends is visited by `visit(k, state[k], a_i, a_j)` on the N-vectors of its ends in `a`,
/// which returns the largest change it made (≥ 0).
///
/// Inlined where it is called, with the visit and the reads and writes of the N-vectors:
/// the loop is then one body in which a contact's two N-vectors stay in registers from
/// their read to their write. Called through a closure that the compiler kept apart, each
/// visit wrote them to the stack piece by piece and read them back whole, and waited on
/// those writes; whether it did changed with unrelated code elsewhere in the crate (the
/// demo's solve at 1 ms, the same work bit for bit: 2.8 s, 3.6 s after an unrelated
/// change, 2.5 s inlined).
#[inline(always)]
pub(crate) fn passes<const N: usize, T: Send>(
    groups: &[PassGroup],
    ends: &[Option<Ends>],
    a: &mut [f64],
    state: &mut [T],
    most: usize,
    tolerance: f64,
    visit: impl Fn(usize, &mut T, &mut [f64; N], &mut [f64; N]) -> f64 + Sync,
) -> PassesDone {
    let threads = rayon::current_num_threads();
    if most > 0 && threads > 1 && groups.iter().any(|g| g.together && g.range.len() >= PARALLEL_COLOUR) {
        let run = Run {
            most,
            tolerance,
            threads,
        };
        return on_threads(groups, ends, a, state, run, visit);
    }
    let mut done = PassesDone {
        passes: 0,
        last_change: 0.0,
        converged: false,
    };
    for pass in 1..=most {
        let mut change: f64 = 0.0;
        for k in groups.iter().flat_map(|g| g.range.clone()) {
            let Some(e) = ends[k] else { continue };
            let (mut ai, mut aj) = e.load::<N>(a);
            change = change.max(visit(k, &mut state[k], &mut ai, &mut aj));
            e.store(a, ai, aj);
        }
        done = PassesDone {
            passes: pass,
            last_change: change,
            converged: change <= tolerance,
        };
        if done.converged {
            break;
        }
    }
    done
}

/// A pointer that threads share; each writes through it only what no other reads or writes
/// in the same colour.
struct Shared<T>(*mut T);
impl<T> Clone for Shared<T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Shared<T> {}
unsafe impl<T: Send> Send for Shared<T> {}
unsafe impl<T: Send> Sync for Shared<T> {}

/// How [`on_threads`] runs: at most `most` passes, until one changes nothing by more than
/// `tolerance`, on `threads` threads.
#[derive(Debug, Clone, Copy)]
struct Run {
    most: usize,
    tolerance: f64,
    threads: usize,
}

/// [`passes`] on all threads (see the module's doc).
fn on_threads<const N: usize, T: Send>(
    groups: &[PassGroup],
    ends: &[Option<Ends>],
    a: &mut [f64],
    state: &mut [T],
    run: Run,
    visit: impl Fn(usize, &mut T, &mut [f64; N], &mut [f64; N]) -> f64 + Sync,
) -> PassesDone {
    let Run {
        most,
        tolerance,
        threads,
    } = run;
    // Each group's blocks: a few per thread for a colour, the whole group for one in order.
    let blocks: Vec<(usize, usize)> = groups
        .iter()
        .map(|g| {
            let len = g.range.len();
            let size = if g.together {
                (len / (4 * threads)).max(BLOCK)
            } else {
                len.max(1)
            };
            (size, len.div_ceil(size))
        })
        .collect();
    // Per phase (pass s, group g at s·G + g): blocks taken and done; per pass: the largest
    // change, as the bits of a non-negative f64 (ordered as the numbers are).
    let phases = most * groups.len();
    let taken: Vec<AtomicUsize> = (0..phases).map(|_| AtomicUsize::new(0)).collect();
    let finished: Vec<AtomicUsize> = (0..phases).map(|_| AtomicUsize::new(0)).collect();
    let change: Vec<AtomicU64> = (0..most).map(|_| AtomicU64::new(0)).collect();
    let (a_len, state_len) = (a.len(), state.len());
    let (a_at, state_at) = (Shared(a.as_mut_ptr()), Shared(state.as_mut_ptr()));
    let work = || {
        let (a_at, state_at) = (a_at, state_at);
        for s in 0..most {
            for (g, group) in groups.iter().enumerate() {
                let phase = s * groups.len() + g;
                let (size, count) = blocks[g];
                loop {
                    let b = taken[phase].fetch_add(1, Ordering::Relaxed);
                    if b >= count {
                        break;
                    }
                    let first = group.range.start + b * size;
                    let mut largest: f64 = 0.0;
                    for k in first..(first + size).min(group.range.end) {
                        let Some(e) = ends[k] else { continue };
                        // SAFETY: the block's contacts are its own (a block is taken once), and
                        // the movable particles of a colour's contacts are all distinct (a
                        // group in order is one block): nothing this visit writes is read or
                        // written by another thread in this phase; the phases are ordered by
                        // the release of `finished` and the acquire of the wait below.
                        debug_assert!(k < state_len && N * e.i.max(e.j.unwrap_or(0)) + N - 1 < a_len);
                        unsafe {
                            let (mut ai, mut aj) = e.load_from::<N>(a_at.0);
                            largest = largest.max(visit(k, &mut *state_at.0.add(k), &mut ai, &mut aj));
                            e.store_to(a_at.0, ai, aj);
                        }
                    }
                    change[s].fetch_max(largest.to_bits(), Ordering::Relaxed);
                    finished[phase].fetch_add(1, Ordering::Release);
                }
                let mut spins = 0u32;
                while finished[phase].load(Ordering::Acquire) < count {
                    spins += 1;
                    if spins < 4096 {
                        std::hint::spin_loop();
                    } else {
                        std::thread::yield_now();
                    }
                }
            }
            if f64::from_bits(change[s].load(Ordering::Relaxed)) <= tolerance {
                return;
            }
        }
    };
    let work = &work;
    rayon::scope(|scope| {
        for _ in 1..threads {
            scope.spawn(move |_| work());
        }
        work();
    });
    // Where every thread stopped: the first pass within the tolerance, or the last.
    let made = (0..most)
        .find(|&s| f64::from_bits(change[s].load(Ordering::Relaxed)) <= tolerance)
        .map_or(most, |s| s + 1);
    let last_change = f64::from_bits(change[made - 1].load(Ordering::Relaxed));
    PassesDone {
        passes: made,
        last_change,
        converged: last_change <= tolerance,
    }
}
