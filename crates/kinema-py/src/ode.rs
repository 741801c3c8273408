//! Bindings of the ODE solvers, the method registry and Butcher tableaux.

use kinema::ode::{self, ButcherTableau, Integrator, Method, MethodKind, Solution, SolveOptions};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::callbacks::{shape_str, PyAccel, PyOde};
use crate::errors::to_py;

/// An explicit Runge–Kutta method given by its Butcher tableau (A, b, c), checked when built.
/// Subclassed by `kinema.ButcherTableau`, which checks the arguments' types first.
#[pyclass(name = "ButcherTableau", module = "kinema._core", frozen, subclass)]
pub struct PyButcherTableau {
    pub inner: ButcherTableau,
}

#[pymethods]
impl PyButcherTableau {
    #[new]
    #[pyo3(signature = (a, b, c, order, name = "custom".to_string()))]
    fn new(a: Vec<Vec<f64>>, b: Vec<f64>, c: Vec<f64>, order: i64, name: String) -> PyResult<Self> {
        let order = u32::try_from(order).map_err(|_| {
            PyValueError::new_err(format!(
                "order = {order} is invalid: the declared order must be an integer >= 1"
            ))
        })?;
        ButcherTableau::new(name, a, b, c, order)
            .map(|inner| Self { inner })
            .map_err(to_py)
    }

    /// The tableau of a registered explicit method (`euler`, `midpoint`, `heun`, `rk4`, `rk45`).
    #[staticmethod]
    fn of(method: &str) -> PyResult<Self> {
        let m = Method::from_name(method).map_err(to_py)?;
        m.tableau().map(|inner| Self { inner }).ok_or_else(|| {
            PyValueError::new_err(format!(
                "method '{method}' is not an explicit Runge-Kutta method and has no Butcher tableau"
            ))
        })
    }

    #[getter]
    fn name(&self) -> &str {
        self.inner.name()
    }
    #[getter]
    fn order(&self) -> u32 {
        self.inner.order()
    }
    #[getter]
    fn stages(&self) -> usize {
        self.inner.stages()
    }
    #[getter(A)]
    fn a<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let s = self.inner.stages();
        let rows: Vec<Vec<f64>> = (0..s).map(|i| self.inner.a_row(i).to_vec()).collect();
        Ok(PyArray2::from_vec2(py, &rows)?)
    }
    #[getter]
    fn b<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.b())
    }
    #[getter]
    fn c<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.c())
    }
    /// Coefficients γ_0..γ_s of the stability polynomial R(z) = Σ γ_k z^k.
    fn stability_polynomial<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.inner.stability_polynomial())
    }
    fn __repr__(&self) -> String {
        format!(
            "ButcherTableau(name='{}', stages={}, order={})",
            self.inner.name(),
            self.inner.stages(),
            self.inner.order()
        )
    }
}

/// The continuous solution of a solve with `dense_output=True`.
#[pyclass(name = "DenseOutput", module = "kinema._core", frozen)]
pub struct PyDenseOutput {
    inner: kinema::ode::DenseOutput,
}

#[pymethods]
impl PyDenseOutput {
    /// The states at the times `t` (a 1-D array), one row per time.
    fn __call__<'py>(&self, py: Python<'py>, t: Vec<f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let n = self.inner.dim();
        let mut out = vec![0.0; t.len() * n];
        for (ti, row) in t.iter().zip(out.chunks_exact_mut(n.max(1))) {
            self.inner.eval(*ti, row).map_err(to_py)?;
        }
        PyArray1::from_vec(py, out).reshape([t.len(), n])
    }
    /// (first, last) time covered.
    #[getter]
    fn span(&self) -> (f64, f64) {
        self.inner.span()
    }
}

/// A method argument from Python: a registered name or a `ButcherTableau`.
pub fn integrator_from(obj: &Bound<'_, PyAny>) -> PyResult<Integrator> {
    if let Ok(name) = obj.extract::<String>() {
        return Method::from_name(&name).map(Integrator::Named).map_err(to_py);
    }
    if let Ok(t) = obj.cast::<PyButcherTableau>() {
        return Ok(Integrator::Tableau(t.get().inner.clone()));
    }
    Err(PyTypeError::new_err(format!(
        "method must be a method name (str) or a kinema.ButcherTableau, got {}",
        obj.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "?".into())
    )))
}

fn kind_name(k: MethodKind) -> &'static str {
    match k {
        MethodKind::ExplicitRk => "explicit",
        MethodKind::Implicit => "implicit",
        MethodKind::Adaptive => "adaptive",
        MethodKind::SecondOrder => "second_order",
    }
}

/// The registered name an unknown method name probably means (`"RK4"` → `"rk4"`,
/// `"backward_euler"` → `"implicit_euler"`), or None: `Method::suggestion`.
#[pyfunction]
fn method_suggestion(name: &str) -> Option<&'static str> {
    Method::suggestion(name).map(Method::name)
}

/// The registry: one dict per method (name, order, kind, evals_per_step, summary).
#[pyfunction]
fn methods<'py>(py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
    Method::ALL
        .iter()
        .map(|m| {
            let d = PyDict::new(py);
            d.set_item("name", m.name())?;
            d.set_item("order", m.order())?;
            d.set_item("kind", kind_name(m.kind()))?;
            d.set_item("evals_per_step", m.evals_per_step())?;
            d.set_item("summary", m.summary())?;
            Ok(d)
        })
        .collect()
}

/// The options of a solve as `kinema.ode` passes them: a dict with one key per field of
/// [`SolveOptions`] (every key present; the values already checked there, so that a bad one
/// is reported with the API's message before it gets here).
#[derive(FromPyObject)]
#[pyo3(from_item_all)]
struct Options {
    t_span: (f64, f64),
    h: Option<f64>,
    h_max: Option<f64>,
    rtol: f64,
    atol: f64,
    t_eval: Option<Vec<f64>>,
    dense_output: bool,
    max_steps: usize,
    h_min: Option<f64>,
}

impl From<Options> for SolveOptions {
    fn from(o: Options) -> Self {
        SolveOptions {
            t_span: o.t_span,
            h: o.h,
            h_max: o.h_max,
            dense_output: o.dense_output,
            rtol: o.rtol,
            atol: o.atol,
            t_eval: o.t_eval,
            max_steps: o.max_steps,
            h_min: o.h_min,
        }
    }
}

fn solution_dict<'py>(py: Python<'py>, sol: Solution) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let rows = sol.t.len();
    d.set_item("success", sol.success())?;
    d.set_item("message", sol.message())?;
    d.set_item("method", &sol.method)?;
    d.set_item("nfev", sol.stats.nfev)?;
    d.set_item("njev", sol.stats.njev)?;
    d.set_item("nlu", sol.stats.nlu)?;
    d.set_item("nsteps", sol.stats.nsteps)?;
    d.set_item("nrejected", sol.stats.nrejected)?;
    d.set_item("sol", sol.dense.map(|inner| PyDenseOutput { inner }))?;
    d.set_item("t", PyArray1::from_vec(py, sol.t))?;
    d.set_item("y", PyArray1::from_vec(py, sol.y).reshape([rows, sol.dim])?)?;
    Ok(d)
}

/// Flat copy of an initial state, and its shape (checked: 1-D, or 2-D when batched).
fn initial_state(name: &str, arr: &PyReadonlyArrayDyn<'_, f64>, vectorized: bool) -> PyResult<(Vec<f64>, Vec<usize>)> {
    let shape = arr.shape().to_vec();
    match (shape.len(), vectorized) {
        (1, _) => {}
        (2, true) => {}
        (2, false) => {
            return Err(PyValueError::new_err(format!(
                "{name} has shape {}: a 2-D initial state is a batch of initial conditions (batch, n); pass vectorized=True \
                 and a function that takes and returns (batch, n) arrays",
                shape_str(&shape)
            )))
        }
        _ => {
            return Err(PyValueError::new_err(format!(
                "{name} has shape {}; it must be 1-D (n,) or, with vectorized=True, 2-D (batch, n)",
                shape_str(&shape)
            )))
        }
    }
    Ok((arr.as_array().iter().copied().collect(), shape))
}

/// Solves y' = f(t, y); returns a dict (see kinema.ode.Solution). `options`: see [`Options`].
#[pyfunction]
fn solve<'py>(
    py: Python<'py>,
    f: Bound<'py, PyAny>,
    y0: PyReadonlyArrayDyn<'py, f64>,
    method: Bound<'py, PyAny>,
    jac: Option<Bound<'py, PyAny>>,
    vectorized: bool,
    options: Options,
) -> PyResult<Bound<'py, PyDict>> {
    let integrator = integrator_from(&method)?;
    let (y, shape) = initial_state("y0", &y0, vectorized)?;
    let mut sys = PyOde { py, f, jac, shape };
    let sol = ode::solve(&mut sys, &y, &integrator, &options.into()).map_err(to_py)?;
    solution_dict(py, sol)
}

/// Solves x'' = a(t, x, v); the dict's y rows are [x, v] per block. `options`: see [`Options`].
#[pyfunction]
fn solve_second_order<'py>(
    py: Python<'py>,
    a: Bound<'py, PyAny>,
    x0: PyReadonlyArrayDyn<'py, f64>,
    v0: PyReadonlyArrayDyn<'py, f64>,
    method: Bound<'py, PyAny>,
    vectorized: bool,
    options: Options,
) -> PyResult<Bound<'py, PyDict>> {
    let integrator = integrator_from(&method)?;
    let (x, shape) = initial_state("x0", &x0, vectorized)?;
    let (v, vshape) = initial_state("v0", &v0, vectorized)?;
    if vshape != shape {
        return Err(PyValueError::new_err(format!(
            "v0 has shape {vshape:?} but x0 has shape {shape:?}; they must match"
        )));
    }
    let mut sys = PyAccel { py, a, shape };
    let sol = ode::solve_second_order(&mut sys, &x, &v, &integrator, &options.into()).map_err(to_py)?;
    solution_dict(py, sol)
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyButcherTableau>()?;
    m.add_class::<PyDenseOutput>()?;
    m.add_function(wrap_pyfunction!(methods, m)?)?;
    m.add_function(wrap_pyfunction!(method_suggestion, m)?)?;
    m.add_function(wrap_pyfunction!(solve, m)?)?;
    m.add_function(wrap_pyfunction!(solve_second_order, m)?)?;
    Ok(())
}
