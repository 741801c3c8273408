//! The engine's large buffers straight from the kernel's pages, given back when let go.
//!
//! glibc's `malloc` serves a block of 128 KiB or more by `mmap` only until such a block is
//! freed: it then raises that threshold to the freed block's size (up to 32 MiB) and keeps
//! up to twice as much free memory at the top of its heap, resident, for the next request.
//! A world of 10⁶ particles frees blocks of 4–24 MB now and then (the sort along space
//! every few dozen steps, the stable-step advisor before the first step), and NumPy's
//! arrays of a scene's set-up do too: each freed block stayed resident beside the step's
//! own buffers and the next ones went elsewhere, so the process held 40–60 MB it did not use
//! (`benchmarks/granular_gas.py` at N = 10⁶: 282 B per particle at its peak, ~215 B of them
//! in use).
//!
//! [`Pages`], the module's global allocator, serves a block of [`LARGE`] bytes or more by
//! `mmap` and gives it back by `munmap` when freed (grown or shrunk by `mremap`, without a
//! copy); smaller blocks go to the system's allocator as before. It applies to this
//! module's Rust allocations only: NumPy's arrays and Python's objects keep glibc's own
//! policy. A large block freed and made again costs its pages' first touch (~0.3 ms a MB on
//! the machines measured), which a world pays only where it lets one go: its step buffers
//! are kept from step to step.

use std::alloc::{GlobalAlloc, Layout, System};

/// The smallest block served by pages of its own, bytes (2 MiB: 512 pages). At 1 MiB the
/// gas of 10⁵ spheres (`benchmarks/granular_gas.py`) paid 2–5 % for its list builds' grids,
/// made afresh each time; at 2 MiB its only large blocks are its arrays of 3 reals a particle
/// (2.5 MB), which it keeps, and a world of 10⁶ has all of its large ones here.
pub const LARGE: usize = 2 << 20;

/// The page size every platform this module supports has at least, bytes: `mmap` returns
/// page-aligned blocks, so any alignment up to it is met.
const PAGE: usize = 4096;

/// The global allocator of the module (see the module doc).
pub struct Pages;

impl Pages {
    /// Whether a block of `layout` is served by pages of its own.
    #[inline]
    fn own_pages(layout: &Layout) -> bool {
        layout.size() >= LARGE && layout.align() <= PAGE
    }
}

unsafe impl GlobalAlloc for Pages {
    #[inline]
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if Self::own_pages(&layout) {
            map(layout.size())
        } else {
            System.alloc(layout)
        }
    }

    #[inline]
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if Self::own_pages(&layout) {
            map(layout.size()) // (fresh pages are zero)
        } else {
            System.alloc_zeroed(layout)
        }
    }

    #[inline]
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        if Self::own_pages(&layout) {
            libc::munmap(ptr.cast(), layout.size());
        } else {
            System.dealloc(ptr, layout)
        }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let new = Layout::from_size_align_unchecked(new_size, layout.align());
        match (Self::own_pages(&layout), Self::own_pages(&new)) {
            (false, false) => System.realloc(ptr, layout, new_size),
            (true, true) => {
                let moved = libc::mremap(ptr.cast(), layout.size(), new_size, libc::MREMAP_MAYMOVE);
                if moved == libc::MAP_FAILED {
                    std::ptr::null_mut()
                } else {
                    moved.cast()
                }
            }
            // across the line: a new block, the common part copied, the old one let go
            _ => {
                let out = self.alloc(new);
                if !out.is_null() {
                    std::ptr::copy_nonoverlapping(ptr, out, layout.size().min(new_size));
                    self.dealloc(ptr, layout);
                }
                out
            }
        }
    }
}

/// `size` bytes of fresh pages, or null where the kernel refuses them (the caller's
/// allocation error, as from `malloc`).
#[inline]
unsafe fn map(size: usize) -> *mut u8 {
    let p = libc::mmap(
        std::ptr::null_mut(),
        size,
        libc::PROT_READ | libc::PROT_WRITE,
        libc::MAP_PRIVATE | libc::MAP_ANONYMOUS,
        -1,
        0,
    );
    if p == libc::MAP_FAILED {
        std::ptr::null_mut()
    } else {
        p.cast()
    }
}
