//! The pair pass's chunks kept on the threads that passed them the last time: the force
//! models' decomposition of space over threads (as LAMMPS's ranks keep their atoms), so that
//! a chunk's positions, velocities and force sums stay in one core's cache from step to step
//! instead of crossing to the other core whenever rayon's split hands the chunk over.
//!
//! Each thread of the pool takes its own chunks first, in ascending order, then the chunks of
//! the others not yet started, from the ends of their lists (work stealing by chunk, which
//! keeps a descheduled or slower thread from holding the pass); a chunk then belongs to the
//! thread that passed it. A chunk's work is its own and its result is kept in its place, so
//! the bits are the same whichever thread passes it. Verlet's kick after the pass takes the
//! same homes (`verlet.rs`): each chunk's force sums are still in that core's cache.

use std::sync::{Mutex, PoisonError};

/// Each pool thread's own chunks, ascending: those it passed the last time (`last(c)`: the
/// thread of chunk c then, if known and in the pool), the others in contiguous runs of equal
/// count (the first pass, or chunks new since).
pub(super) fn homes(chunks: usize, threads: usize, last: impl Fn(usize) -> Option<usize>) -> Vec<Vec<usize>> {
    let threads = threads.max(1);
    let mut homes = vec![Vec::new(); threads];
    for c in 0..chunks {
        let t = last(c).filter(|&t| t < threads).unwrap_or(c * threads / chunks.max(1));
        homes[t].push(c);
    }
    homes
}

/// `work(c, item)` for each chunk c's item on the pool's threads (`rayon::broadcast`), each
/// thread its own chunks of `homes` first, then the others' unstarted ones from the ends of
/// their lists. Returns each chunk's result, in chunk order, with the thread that passed it.
pub(super) fn run<T: Send, R: Send>(items: Vec<T>, homes: &[Vec<usize>], work: impl Fn(usize, T) -> R + Sync) -> Vec<(R, usize)> {
    let chunks = items.len();
    // a chunk's item is taken once, by the first thread to lock it
    let slots: Vec<Mutex<Option<T>>> = items.into_iter().map(|item| Mutex::new(Some(item))).collect();
    let take = |c: usize| slots[c].lock().unwrap_or_else(PoisonError::into_inner).take();
    let done = rayon::broadcast(|ctx| {
        let me = ctx.index();
        let mine = homes.get(me).into_iter().flatten().copied();
        let others = (1..homes.len()).flat_map(|k| homes[(me + k) % homes.len()].iter().rev().copied());
        mine.chain(others)
            .filter_map(|c| take(c).map(|item| (c, work(c, item))))
            .collect::<Vec<_>>()
    });
    let mut out: Vec<Option<(R, usize)>> = (0..chunks).map(|_| None).collect();
    for (t, results) in done.into_iter().enumerate() {
        for (c, r) in results {
            out[c] = Some((r, t));
        }
    }
    out.into_iter()
        .map(|r| r.expect("every chunk is in some thread's list, and each is taken once"))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_chunk_is_passed_once_in_its_place_whatever_the_homes() {
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                for (chunks, last) in [(0, None), (1, None), (7, None), (7, Some(vec![1, 1, 0, 2, 0, 1, 9]))] {
                    let homes = homes(chunks, threads, |c| last.as_ref().map(|l: &Vec<usize>| l[c]));
                    let mut listed: Vec<usize> = homes.concat();
                    listed.sort_unstable();
                    assert_eq!(listed, (0..chunks).collect::<Vec<_>>(), "each chunk in one home");
                    let items: Vec<usize> = (0..chunks).map(|c| 10 * c).collect();
                    let out = run(items, &homes, |c, item| (c, item + 1));
                    assert_eq!(out.len(), chunks);
                    for (c, ((seen, value), t)) in out.into_iter().enumerate() {
                        assert_eq!((seen, value), (c, 10 * c + 1), "the result of chunk {c}, in its place");
                        assert!(t < threads);
                    }
                }
            });
        }
    }

    #[test]
    fn a_chunk_goes_home_to_the_thread_that_passed_it_last() {
        // thread 1 passed chunks 0 and 3 last time; chunk 4 is new: runs of equal count
        let homes = homes(5, 2, |c| [Some(1), Some(0), Some(0), Some(1), None][c]);
        assert_eq!(homes, vec![vec![1, 2], vec![0, 3, 4]]);
        assert_eq!(super::homes(4, 2, |_| None), vec![vec![0, 1], vec![2, 3]]);
    }
}
