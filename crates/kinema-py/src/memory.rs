//! The process's allocator, told once at import to give large blocks back when they are freed.
//!
//! glibc serves a block of at least `M_MMAP_THRESHOLD` bytes (128 KiB at start) by a mapping
//! of its own, returned to the system when freed; but each such free *raises* the threshold
//! to the freed block's size (up to 32 MiB), so after the first freed array of a large world
//! every array below that size comes from the arenas (one per thread: rayon's workers each
//! have theirs), whose freed room stays resident and splits. A gas of 10⁶ spheres grew from
//! 315 to 383 MB resident over 300 steps that way, 96 MB of it freed room in the arenas
//! (`benchmarks/speed_targets.py`'s memory row: 388 B a particle at its peak, 347 with the
//! threshold held). Holding the threshold at 2 MiB keeps every large array in a mapping of
//! its own, so what a world frees is given back; a step of the force models makes none (200
//! steps of a 10⁵ gas: no mapping made, `strace`), and a fresh mapping's first touch costs a
//! page fault per 4 KiB, so smaller blocks stay in the arenas: at 1 MiB a 640 × 480 frame of
//! the renderer (1.2 MB) was mapped anew each frame, 3 % slower; at 4 MiB the gas at 10⁶
//! peaked 14 B a particle higher (its 4 MB index arrays stayed in the arenas).
//!
//! Nothing is changed where the user chose the threshold (`MALLOC_MMAP_THRESHOLD_` in the
//! environment) or on other C libraries.

/// The size from which a block gets a mapping of its own, bytes.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
const MMAP_THRESHOLD: i32 = 2 << 20;

/// Holds glibc's mmap threshold at [`MMAP_THRESHOLD`] unless the user set it.
pub(crate) fn give_back_large_blocks() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    if std::env::var_os("MALLOC_MMAP_THRESHOLD_").is_none() {
        // SAFETY: mallopt only sets a parameter of the allocator; it is safe to call at any
        // time from any thread (glibc takes its own lock).
        unsafe {
            libc::mallopt(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD);
        }
    }
}
