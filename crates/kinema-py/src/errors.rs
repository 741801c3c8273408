//! Engine errors to Python exceptions.
//!
//! A callback's own exception comes back unchanged (same type, same traceback); bad input
//! becomes `ValueError` (or `TypeError` for wrong types) whose message names the parameter,
//! the value and what is allowed.

use kinema::Error;
use pyo3::exceptions::{PyMemoryError, PyRuntimeError, PyValueError};
use pyo3::PyErr;

/// Converts an engine error into the Python exception to raise.
pub fn to_py(e: Error) -> PyErr {
    match e {
        Error::Callback(inner) => match inner.downcast::<PyErr>() {
            Ok(py_err) => *py_err,
            Err(other) => PyRuntimeError::new_err(other.to_string()),
        },
        e @ Error::OutOfMemory { .. } => PyMemoryError::new_err(e.to_string()),
        other => PyValueError::new_err(other.to_string()),
    }
}
