//! Bindings of the linear stability analysis (vectorized amplification, stable steps).

use kinema::ode::stability::StabilityFunction;
use num_complex::Complex64;
use numpy::{PyArrayDyn, PyReadonlyArrayDyn, ToPyArray};
use pyo3::prelude::*;

use crate::ode::integrator_from;

/// R(z) elementwise over a complex array of any shape.
#[pyfunction]
fn amplification<'py>(
    py: Python<'py>,
    method: Bound<'py, PyAny>,
    z: PyReadonlyArrayDyn<'py, Complex64>,
) -> PyResult<Bound<'py, PyArrayDyn<Complex64>>> {
    let f = StabilityFunction::of(&integrator_from(&method)?);
    let out = z.as_array().mapv(|z| f.eval(z));
    Ok(out.to_pyarray(py))
}

/// Largest stable step for each λ of a complex array (inf: no limit, 0: none stable).
#[pyfunction]
fn max_step<'py>(
    py: Python<'py>,
    method: Bound<'py, PyAny>,
    lam: PyReadonlyArrayDyn<'py, Complex64>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let f = StabilityFunction::of(&integrator_from(&method)?);
    let out = lam.as_array().mapv(|l| f.max_step(l));
    Ok(out.to_pyarray(py))
}

/// (lo, hi) of the stable real interval around 0, in z = hλ.
#[pyfunction]
fn real_interval(method: Bound<'_, PyAny>) -> PyResult<(f64, f64)> {
    Ok(kinema::ode::real_interval(&integrator_from(&method)?))
}

/// (lo, hi) of the stable imaginary interval around 0, z = i·y.
#[pyfunction]
fn imag_interval(method: Bound<'_, PyAny>) -> PyResult<(f64, f64)> {
    Ok(kinema::ode::imag_interval(&integrator_from(&method)?))
}

/// Largest stable h on the damped oscillator x'' = −ω²x − 2ζω v.
#[pyfunction]
fn oscillator_max_step(method: Bound<'_, PyAny>, omega: f64, zeta: f64) -> PyResult<f64> {
    Ok(kinema::ode::oscillator_max_step(&integrator_from(&method)?, omega, zeta))
}

/// Spectral radius of one step of size h on the damped oscillator.
#[pyfunction]
fn oscillator_amplification(method: Bound<'_, PyAny>, h: f64, omega: f64, zeta: f64) -> PyResult<f64> {
    Ok(kinema::ode::oscillator_amplification(
        &integrator_from(&method)?,
        h,
        omega,
        zeta,
    ))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(amplification, m)?)?;
    m.add_function(wrap_pyfunction!(max_step, m)?)?;
    m.add_function(wrap_pyfunction!(real_interval, m)?)?;
    m.add_function(wrap_pyfunction!(imag_interval, m)?)?;
    m.add_function(wrap_pyfunction!(oscillator_max_step, m)?)?;
    m.add_function(wrap_pyfunction!(oscillator_amplification, m)?)?;
    Ok(())
}
