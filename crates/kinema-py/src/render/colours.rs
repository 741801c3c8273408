//! Colours of values for Python: a named colormap over a value range, categorical colours of
//! ids (`kinema::render::colormap`); the renderer's colourings use `value_range` too.

use kinema::render::colormap::{categorical, Colormap};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1};
use pyo3::prelude::*;

use super::data;
use crate::errors::to_py;

/// (vmin, vmax): the given ones, or the finite minimum and maximum of the values.
pub(super) fn value_range(v: &[f64], vmin: Option<f64>, vmax: Option<f64>) -> (f64, f64) {
    let finite = v.iter().copied().filter(|x| x.is_finite());
    let lo = vmin.unwrap_or_else(|| finite.clone().fold(f64::INFINITY, f64::min));
    let hi = vmax.unwrap_or_else(|| finite.fold(f64::NEG_INFINITY, f64::max));
    if lo.is_finite() && hi.is_finite() {
        (lo, hi)
    } else {
        (0.0, 1.0)
    }
}

/// Colours of values through a named colormap: an (N, 3) uint8 array.
#[pyfunction]
#[pyo3(signature = (values, colormap="viridis", vmin=None, vmax=None))]
pub(super) fn colormap<'py>(
    py: Python<'py>,
    values: PyReadonlyArray1<'py, f64>,
    colormap: &str,
    vmin: Option<f64>,
    vmax: Option<f64>,
) -> PyResult<Bound<'py, PyArray2<u8>>> {
    let cmap = Colormap::from_name(colormap).map_err(to_py)?;
    let v = data(&values);
    let (lo, hi) = value_range(&v, vmin, vmax);
    let mut out = vec![0u8; 3 * v.len()];
    cmap.map(&v, lo, hi, &mut out).map_err(to_py)?;
    PyArray1::from_vec(py, out).reshape([v.len(), 3])
}

/// Categorical colours (tab10, repeating) of integer ids: an (N, 3) uint8 array.
#[pyfunction]
pub(super) fn categorical_colors<'py>(py: Python<'py>, ids: PyReadonlyArray1<'py, u64>) -> PyResult<Bound<'py, PyArray2<u8>>> {
    let ids = data(&ids);
    let out: Vec<u8> = ids.iter().flat_map(|&i| categorical(i)).collect();
    PyArray1::from_vec(py, out).reshape([ids.len(), 3])
}
