//! The engine's threads in a forked child process.
//!
//! The engine runs its parallel loops on rayon's global pool, whose worker threads start at
//! its first use. `fork` copies only the thread that called it, so a child forked after the
//! parent stepped (Python's `multiprocessing` on Linux, by default) has a global pool with no
//! workers: its first parallel loop would wait forever for them.
//!
//! `after_fork_in_child` runs in the child's forking thread (`os.register_at_fork`, set up by
//! the package's `__init__`) and makes that thread worker 0 of a new pool
//! (`ThreadPoolBuilder::use_current_thread`). A parallel loop started on a worker runs in the
//! worker's own pool, so every call the child makes on that thread, which is the thread its
//! Worlds belong to, runs on the new pool. The results do not depend on the pool: the
//! engine's bits are the same on any number of threads.
//!
//! Left as it is: a thread the child starts later and its Worlds still reach the dead global
//! pool (a World made in such a thread would hang its first step); the docs say to use the
//! "spawn" start method for that.

use pyo3::prelude::*;
use std::sync::Mutex;

/// The pools made in forked children of this process's line, kept for the process's life:
/// a pool with `use_current_thread` must outlive the thread's use of it.
static CHILD_POOLS: Mutex<Vec<rayon::ThreadPool>> = Mutex::new(Vec::new());

/// Called in a child process right after `fork`, on the thread that forked.
#[pyfunction]
fn _after_fork_in_child() -> PyResult<()> {
    // After a fork, a lock the parent's other threads held stays held: start from a fresh one.
    let mut pools = match CHILD_POOLS.try_lock() {
        Ok(p) => p,
        Err(_) => return Ok(()),
    };
    // In a grandchild this thread is already worker 0 of its parent's child pool, whose other
    // workers did not survive either; `build` refuses a second pool, and the loops of that
    // pool run on this worker alone (every job it queues is still its own to take).
    if let Ok(pool) = rayon::ThreadPoolBuilder::new().use_current_thread().build() {
        pools.push(pool);
    }
    Ok(())
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_after_fork_in_child, m)?)
}
