//! Large pages for the large buffers the engine walks at random (issue 51).
//!
//! A search down the hierarchy of a mesh of 10⁶ triangles reads one node in each of some 18
//! levels, and the nodes, triangles and vertices it reads lie megabytes apart: the ~100 MB
//! of such a mesh span 25,000 pages of 4 KiB, far more than the core's translation buffer
//! holds (3,072 entries on the project's AMD Zen 4, 2,048 on an Intel Ice Lake), so nearly
//! every load of a search waited on a walk of the page tables before its miss in the cache.
//! In pages of 2 MiB the same buffers are 50 pages, whose translations all stay in the
//! buffer. Measured on `benchmarks/mesh_floor.py`'s pile on 10⁶ triangles (1 thread, the
//! closing note of stop 76): 12 % less time per step.
//!
//! Linux gives an anonymous mapping large pages (transparent huge pages) where the system
//! is set to `always`, or to `madvise` (the default of most distributions) and the mapping
//! asks for them with `madvise(MADV_HUGEPAGE)`: what [`advise_large`] does, before the
//! buffer is first written, so that its pages are faulted in large from the start. Only the
//! whole 2 MiB pages inside the buffer are asked for; a buffer smaller than one is left as it
//! is. Elsewhere, and where the system says `never`, it does nothing: the hint changes where
//! the memory lies, never what it holds.

/// The size of a large page on x86-64 and (with 4 KiB base pages) AArch64 Linux, bytes.
const LARGE: usize = 1 << 21;

/// Asks the system to back the whole 2 MiB pages within `buffer`'s capacity with large pages;
/// call it on a buffer reserved but not yet written. Whether it was asked (false for a
/// buffer without a whole 2 MiB page in it, off Linux, or where the system refused).
pub fn advise_large<T>(buffer: &Vec<T>) -> bool {
    let start = buffer.as_ptr() as usize;
    let end = start + buffer.capacity() * std::mem::size_of::<T>();
    let (first, last) = (start.next_multiple_of(LARGE), end / LARGE * LARGE);
    last > first && advise(first, last - first)
}

#[cfg(target_os = "linux")]
fn advise(at: usize, len: usize) -> bool {
    // SAFETY: [at, at + len) lies within one live allocation (the buffer's capacity), and
    // MADV_HUGEPAGE changes only how its pages are backed, never their contents.
    unsafe { libc::madvise(at as *mut libc::c_void, len, libc::MADV_HUGEPAGE) == 0 }
}

#[cfg(not(target_os = "linux"))]
fn advise(_at: usize, _len: usize) -> bool {
    false
}

#[cfg(test)]
mod tests {
    use super::advise_large;

    #[test]
    fn only_buffers_holding_a_whole_large_page_are_advised() {
        let small: Vec<f64> = Vec::with_capacity(1000);
        assert!(!advise_large(&small), "8 kB hold no 2 MiB page");
        let mut large: Vec<f64> = Vec::with_capacity(1 << 20); // 8 MiB
        let advised = advise_large(&large);
        if cfg!(target_os = "linux")
            && std::fs::read_to_string("/sys/kernel/mm/transparent_hugepage/enabled").is_ok_and(|s| !s.contains("[never]"))
        {
            assert!(advised, "8 MiB hold three whole 2 MiB pages, and this system has large pages");
        }
        // the buffer is the caller's as before: written and read as any other
        large.extend((0..1 << 20).map(|k| k as f64));
        assert_eq!(large[(1 << 20) - 1], ((1 << 20) - 1) as f64);
    }
}
