//! kinema._core: the PyO3 glue between the kinema engine and the Python package.
//!
//! Only conversions, classes and error mapping live here; the public, documented API is the
//! Python package `kinema`. The module function only registers one area after another.

mod callbacks;
mod collide;
mod errors;
mod ode;
#[cfg(target_os = "linux")]
mod pages;
mod render;
mod reports;
mod stability;
mod stepping;
mod threads;
mod world;

use pyo3::prelude::*;

/// Large blocks by pages of their own, given back when let go (`pages.rs`; Linux's `mremap`).
#[cfg(target_os = "linux")]
#[global_allocator]
static PAGES: pages::Pages = pages::Pages;

/// The instruction set the engine's hottest loops run on here: `"x86-64-v3"` or
/// `"baseline"` (`kinema::simd`; `KINEMA_SIMD=baseline` keeps the baseline).
#[pyfunction]
fn simd_level() -> &'static str {
    kinema::simd::level()
}

/// Gives the C allocator's free memory back to the system (glibc's `malloc_trim`; a no-op
/// elsewhere): what a scene's set-up let go of (NumPy's arrays of the positions it made, the
/// first-step check's looks) stays resident otherwise beside the steps' buffers. The number
/// of bytes it may have given back is not known: returns whether it gave any.
#[pyfunction]
fn give_back_memory(py: Python<'_>) -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: malloc_trim only walks glibc's own free lists
        py.detach(|| unsafe { libc::malloc_trim(0) } == 1)
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        let _ = py;
        false
    }
}

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    ode::register(m)?;
    stability::register(m)?;
    world::register(m)?;
    render::register(m)?;
    threads::register(m)?;
    m.add_function(wrap_pyfunction!(simd_level, m)?)?;
    m.add_function(wrap_pyfunction!(give_back_memory, m)?)?;
    Ok(())
}
