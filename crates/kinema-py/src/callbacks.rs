//! Python callables as engine systems: f(t, y) and a(t, x, v) with NumPy arrays in and out,
//! and a world's force F(t, x, v) (`PythonForce`).
//!
//! This is the hot path of a solve with a Python right-hand side, so each call does only what
//! it must: one array for each argument (a fresh one, so the callable may keep it), the call,
//! and one copy of the result. A result that is already a float64 array of the right shape is
//! read directly; anything else goes through `numpy.asarray` once.

use kinema::error::CallbackError;
use kinema::forces::{Force, State};
use kinema::ode::{OdeSystem, SecondOrderSystem};
use numpy::{PyArray1, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;

fn boxed(e: PyErr) -> CallbackError {
    Box::new(e)
}

/// A flat engine slice as the array the user's callable expects (1-D, or (batch, n)).
fn to_array<'py>(py: Python<'py>, data: &[f64], shape: &[usize]) -> PyResult<Bound<'py, PyAny>> {
    let arr = PyArray1::from_slice(py, data);
    if shape.len() == 1 {
        Ok(arr.into_any())
    } else {
        Ok(arr.reshape(shape)?.into_any())
    }
}

pub fn shape_str(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => format!("({})", shape.iter().map(|s| s.to_string()).collect::<Vec<_>>().join(", ")),
    }
}

/// Copies a callable's result into `out`, checking its shape.
pub fn copy_result(py: Python<'_>, what: &str, value: &Bound<'_, PyAny>, shape: &[usize], out: &mut [f64]) -> PyResult<()> {
    let arr = match value.cast::<PyArrayDyn<f64>>() {
        Ok(a) => a.clone(),
        Err(_) => slow_convert(py, what, value, shape)?,
    };
    if arr.shape() != shape {
        return Err(PyValueError::new_err(format!(
            "{what} returned an array of shape {} but {} was expected",
            shape_str(arr.shape()),
            shape_str(shape)
        )));
    }
    let ro = arr.readonly();
    match ro.as_slice() {
        Ok(s) => out.copy_from_slice(s),
        Err(_) => {
            for (o, v) in out.iter_mut().zip(ro.as_array().iter()) {
                *o = *v;
            }
        }
    }
    Ok(())
}

/// Anything but a float64 array: lists, tuples, integer arrays — once through numpy.asarray.
/// None, booleans and complex values are refused rather than silently turned into NaN, 0/1 or
/// their real part.
fn slow_convert<'py>(
    py: Python<'py>,
    what: &str,
    value: &Bound<'py, PyAny>,
    shape: &[usize],
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let type_name = || value.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "?".into());
    let expected = || format!("{what} must return an array of floats of shape {}", shape_str(shape));
    if value.is_none() {
        return Err(PyTypeError::new_err(format!(
            "{}; it returned None (a missing return statement?)",
            expected()
        )));
    }
    let np = py.import("numpy")?;
    let raw = np
        .call_method1("asarray", (value,))
        .map_err(|_| PyTypeError::new_err(format!("{}; it returned {}", expected(), type_name())))?;
    let kind: String = raw.getattr("dtype")?.getattr("kind")?.extract()?;
    match kind.as_str() {
        "f" | "i" | "u" => {}
        "b" => {
            return Err(PyTypeError::new_err(format!(
                "{}; it returned booleans (True/False are not numbers here: return floats, e.g. 1.0 * mask)",
                expected()
            )))
        }
        "c" => {
            return Err(PyTypeError::new_err(format!(
                "{}; it returned complex values (write a complex system as its real and imaginary parts)",
                expected()
            )))
        }
        _ => return Err(PyTypeError::new_err(format!("{}; it returned {}", expected(), type_name()))),
    }
    Ok(np.call_method1("asarray", (raw, "float64"))?.cast_into::<PyArrayDyn<f64>>()?)
}

/// f(t, y) (and optionally jac(t, y)) as an [`OdeSystem`].
pub struct PyOde<'py> {
    pub py: Python<'py>,
    pub f: Bound<'py, PyAny>,
    pub jac: Option<Bound<'py, PyAny>>,
    /// Shape of y as the user sees it: (n,) or (batch, n).
    pub shape: Vec<usize>,
}

impl PyOde<'_> {
    fn block(&self) -> usize {
        *self.shape.last().unwrap_or(&0)
    }
}

impl OdeSystem for PyOde<'_> {
    fn dim(&self) -> usize {
        self.shape.iter().product()
    }
    fn block_len(&self) -> usize {
        self.block()
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), CallbackError> {
        let arr = to_array(self.py, y, &self.shape).map_err(boxed)?;
        let out = self.f.call1((t, arr)).map_err(boxed)?;
        copy_result(self.py, "f(t, y)", &out, &self.shape, dydt).map_err(boxed)
    }
    fn has_jacobian(&self) -> bool {
        self.jac.is_some()
    }
    fn jacobian(&mut self, t: f64, y: &[f64], jac: &mut [f64]) -> Result<(), CallbackError> {
        let Some(j) = &self.jac else {
            return Err("no Jacobian".into());
        };
        let arr = to_array(self.py, y, &self.shape).map_err(boxed)?;
        let out = j.call1((t, arr)).map_err(boxed)?;
        let mut shape = self.shape.clone();
        shape.push(self.block());
        copy_result(self.py, "jac(t, y)", &out, &shape, jac).map_err(boxed)
    }
}

/// a(t, x, v) as a [`SecondOrderSystem`].
pub struct PyAccel<'py> {
    pub py: Python<'py>,
    pub a: Bound<'py, PyAny>,
    /// Shape of x (and v) as the user sees it: (n,) or (batch, n).
    pub shape: Vec<usize>,
}

impl SecondOrderSystem for PyAccel<'_> {
    fn dim(&self) -> usize {
        self.shape.iter().product()
    }
    fn block_len(&self) -> usize {
        *self.shape.last().unwrap_or(&0)
    }
    fn accel(&mut self, t: f64, x: &[f64], v: &[f64], acc: &mut [f64]) -> Result<(), CallbackError> {
        let xa = to_array(self.py, x, &self.shape).map_err(boxed)?;
        let va = to_array(self.py, v, &self.shape).map_err(boxed)?;
        let out = self.a.call1((t, xa, va)).map_err(boxed)?;
        copy_result(self.py, "a(t, x, v)", &out, &self.shape, acc).map_err(boxed)
    }
}

/// A force computed by a Python callable `fn(t, x, v) -> F` on whole (N, 3) arrays.
pub struct PythonForce {
    pub f: Py<PyAny>,
    pub name: String,
}

impl Force for PythonForce {
    fn name(&self) -> &str {
        &self.name
    }
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        let n = s.len();
        Python::attach(|py| -> PyResult<()> {
            let x = PyArray1::from_slice(py, s.x).reshape([n, 3])?;
            let v = PyArray1::from_slice(py, s.v).reshape([n, 3])?;
            let out = self.f.bind(py).call1((s.t, x, v))?;
            let mut buf = vec![0.0; 3 * n];
            copy_result(py, &format!("force '{}' fn(t, x, v)", self.name), &out, &[n, 3], &mut buf)?;
            for (fi, bi) in f.iter_mut().zip(&buf) {
                *fi += bi;
            }
            Ok(())
        })
        .map_err(|e| Box::new(e) as CallbackError)
    }
    // No `properties`: the default, a force the world knows nothing about, is what a
    // Python callable is (it may add energy and depend on anything).
}
