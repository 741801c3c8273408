//! kinema._core: the PyO3 glue between the kinema engine and the Python package.
//!
//! Only conversions, classes and error mapping live here; the public, documented API is the
//! Python package `kinema`. The module function only registers one area after another.

mod callbacks;
mod collide;
mod errors;
mod ode;
mod render;
mod reports;
mod stability;
mod stepping;
mod threads;
mod world;

use pyo3::prelude::*;

/// The instruction set the engine's hottest loops run on here: `"x86-64-v3"` or
/// `"baseline"` (`kinema::simd`; `KINEMA_SIMD=baseline` keeps the baseline).
#[pyfunction]
fn simd_level() -> &'static str {
    kinema::simd::level()
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
    Ok(())
}
