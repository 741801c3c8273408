//! Bindings of the particle world: World, the force catalogue, Python forces, diagnostics,
//! collisions (conversions in `collide.rs`; stepping and SimulationDiverged in
//! `stepping.rs`; the Python force in `callbacks.rs`).

use kinema::diagnostics::Diagnostics;
use kinema::forces::falloff::{Law, Shape};
use kinema::forces::{Falloff, Springs};
use kinema::world::{KillVolume, UserOrder};
use kinema::{World, WorldParams};
use numpy::{
    PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadwriteArray2, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::collide;
use crate::errors::to_py;
use crate::ode::integrator_from;
use crate::stepping::{ctrl_c, step_in_slices, world_err, SimulationDiverged};

mod carries;
mod contents;

/// `add_particles`' arguments, read by name from the dict Python passes (`World._add`: the
/// values already checked and converted there, contiguous float64 and bool arrays).
#[derive(FromPyObject)]
struct NewParticles<'py> {
    /// Positions, m, (N, 3).
    #[pyo3(item)]
    x: PyReadonlyArray2<'py, f64>,
    /// Velocities, m/s, (N, 3).
    #[pyo3(item)]
    v: PyReadonlyArray2<'py, f64>,
    /// Masses, kg, (N,).
    #[pyo3(item)]
    mass: PyReadonlyArray1<'py, f64>,
    /// Radii, m, (N,).
    #[pyo3(item)]
    radius: PyReadonlyArray1<'py, f64>,
    /// Pinned or not, (N,).
    #[pyo3(item)]
    pinned: PyReadonlyArray1<'py, bool>,
    /// Each particle's own e (NaN: the global one), or None.
    #[pyo3(item)]
    restitution: Option<Vec<f64>>,
    /// Each particle's own μ (NaN: the global one), or None.
    #[pyo3(item)]
    friction: Option<Vec<f64>>,
    /// Each particle's collision group (0..32), or None (group 0).
    #[pyo3(item)]
    group: Option<Vec<u32>>,
}

/// The particle world (see kinema.World).
///
/// The engine keeps its own order between calls: with spring–dashpot contacts it sorts the
/// particles along space (`kinema::world::order`) and `step` leaves them so, where the
/// world used to put them back in the user's order after every call (5 × 3N + 5N values
/// permuted and the neighbour list renumbered, to be sorted again at the next rebuild).
/// The world is held in a [`UserOrder`], the binding's only way to it, which gives it only in
/// the user's order: `self.inner.get()` puts the particles back first (a no-op when they
/// are), for every method given or giving particle indices, changing the world, the advisor
/// and the checkpoint's carries; the engine sorts them again at its next rebuild. What Python
/// reads every frame (positions, velocities, masses, radii, ids) is gathered into the user's
/// order through the order's maps without moving the particles (`in_user_order`,
/// `read_state_into`); `sync` compares through them and moves nothing when nothing was
/// written; the diagnostics are sums over the engine's order.
#[pyclass(name = "World", module = "kinema._core")]
pub struct PyWorld {
    inner: UserOrder,
}

fn rows<'py>(py: Python<'py>, flat: &[f64]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    PyArray1::from_slice(py, flat).reshape([flat.len() / 3, 3])
}

fn flat3<'a>(name: &str, a: &'a PyReadonlyArray2<'_, f64>) -> PyResult<std::borrow::Cow<'a, [f64]>> {
    let shape = a.shape();
    if shape[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "{name} has shape ({}, {}); it must be (N, 3)",
            shape[0], shape[1]
        )));
    }
    // A C-contiguous array is read where it lies (no copy of 24 B per particle).
    Ok(match a.as_slice() {
        Ok(flat) => std::borrow::Cow::Borrowed(flat),
        Err(_) => std::borrow::Cow::Owned(a.as_array().iter().copied().collect()),
    })
}

#[pymethods]
impl PyWorld {
    #[new]
    fn new(dim: usize, dt: f64, method: Bound<'_, PyAny>) -> PyResult<Self> {
        let method = integrator_from(&method)?;
        let mut world = World::new(WorldParams { dt, method, dim }).map_err(world_err)?;
        world.set_interrupt(Some(ctrl_c));
        Ok(Self {
            inner: UserOrder::new(world),
        })
    }

    /// Appends particles; returns (first, end) indices. `restitution` and `friction` (one per
    /// particle, NaN: the world's global value) are checked before anything is added.
    fn add_particles(&mut self, particles: NewParticles<'_>) -> PyResult<(usize, usize)> {
        let world = self.inner.get();
        let NewParticles {
            x,
            v,
            mass,
            radius,
            pinned,
            restitution,
            friction,
            group,
        } = particles;
        let (x, v) = (flat3("position", &x)?, flat3("velocity", &v)?);
        let (mass, radius, pinned) = (mass.as_slice()?, radius.as_slice()?, pinned.as_slice()?);
        let own = collide::materials(mass.len(), restitution, friction).map_err(to_py)?;
        let r = world
            .add_particles_in_groups(&x, &v, mass, radius, pinned, group.as_deref())
            .map_err(world_err)?;
        if let Some((e, mu)) = own {
            world.set_particle_materials(r.start, &e, &mu).map_err(to_py)?;
        }
        Ok((r.start, r.end))
    }

    /// Refuses now what the first step would: particles placed where contacts cannot resolve
    /// them (`World::check_pending_placement`).
    fn check_placement(&mut self) -> PyResult<()> {
        self.inner.get().check_pending_placement().map_err(to_py)
    }

    /// The overlaps the last placement check accepted but that the collisions will push
    /// apart, as a sentence (count and deepest), once; None if there were none.
    fn take_placement_notice(&mut self) -> Option<String> {
        self.inner.take_placement_notice()
    }

    /// Advances n steps; stops at the first failing one (the state before it is kept).
    ///
    /// The steps run in slices of a few milliseconds with the GIL released (other Python
    /// threads run meanwhile; a Python force takes it back for its call), and Ctrl-C is
    /// checked between slices: `KeyboardInterrupt` within [`SLICE`]'s order of time, the
    /// world at the end of its last whole step.
    fn step(&mut self, py: Python<'_>, n: u64) -> PyResult<()> {
        step_in_slices(py, &mut self.inner, n) // (in the engine's order: see `PyWorld`'s doc)
    }

    #[getter]
    fn time(&self) -> f64 {
        self.inner.time()
    }

    /// Wall-clock seconds spent in each of the seed's four stages so far.
    fn stage_times<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let t = self.inner.stage_times();
        let out = PyDict::new(py);
        out.set_item("integrate", t.integrate.as_secs_f64())?;
        out.set_item("detect", t.detect.as_secs_f64())?;
        out.set_item("respond", t.respond.as_secs_f64())?;
        out.set_item("distribute", t.distribute.as_secs_f64())?;
        for (name, time) in t.impulse.iter().filter(|(name, _)| !name.is_empty()) {
            out.set_item(*name, time.as_secs_f64())?;
        }
        Ok(out)
    }

    /// How many times the engine sorted the particles along space (internal; for tests).
    #[getter]
    fn sorts(&self) -> u64 {
        self.inner.sorts()
    }

    /// A count that moves whenever the set of particles changes, and only then (internal:
    /// the recorder reads the ids again when it moved).
    #[getter]
    fn membership(&self) -> u64 {
        self.inner.membership()
    }

    /// Whether the engine holds the particles in its own order now (internal; for tests).
    #[getter]
    fn in_engine_order(&self) -> bool {
        self.inner.in_engine_order()
    }

    #[getter]
    fn steps(&self) -> u64 {
        self.inner.steps()
    }

    #[getter]
    fn nfev(&self) -> usize {
        self.inner.stats().nfev
    }

    #[getter]
    fn dt(&self) -> f64 {
        self.inner.params().dt
    }

    #[getter]
    fn dim(&self) -> usize {
        self.inner.params().dim
    }

    #[getter]
    fn method(&self) -> String {
        self.inner.params().method.name().to_string()
    }

    #[getter]
    fn len(&self) -> usize {
        self.inner.len()
    }

    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        rows(py, &self.inner.in_user_order(|p| &p.x, 3))
    }

    #[getter]
    fn velocities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        rows(py, &self.inner.in_user_order(|p| &p.v, 3))
    }

    #[getter]
    fn masses<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.inner.in_user_order(|p| &p.mass, 1))
    }

    #[getter]
    fn ids<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u64>> {
        PyArray1::from_slice(py, &self.inner.in_user_order(|p| &p.id, 1))
    }

    #[getter]
    fn radii<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.inner.in_user_order(|p| &p.radius, 1))
    }

    #[getter]
    fn inverse_masses<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.inner.in_user_order(|p| &p.inv_mass, 1))
    }

    /// Copies positions, velocities and masses from the caller's arrays (those given; `None`
    /// where Python holds no view) into the world when they differ from its own (the method
    /// caches then restart); returns whether they did. Checks every value first: nothing is
    /// changed by a bad one.
    #[pyo3(signature = (x=None, v=None, m=None))]
    fn sync(
        &mut self,
        x: Option<PyReadonlyArray2<'_, f64>>,
        v: Option<PyReadonlyArray2<'_, f64>>,
        m: Option<PyReadonlyArray1<'_, f64>>,
    ) -> PyResult<bool> {
        let n = self.inner.len();
        let shape_ok = |shape: &[usize], want: &[usize]| shape == want;
        let (x, v, m) = (
            x.as_ref().map(|a| a.as_array()),
            v.as_ref().map(|a| a.as_array()),
            m.as_ref().map(|a| a.as_array()),
        );
        if !(x.as_ref().is_none_or(|a| shape_ok(a.shape(), &[n, 3]))
            && v.as_ref().is_none_or(|a| shape_ok(a.shape(), &[n, 3]))
            && m.as_ref().is_none_or(|a| shape_ok(a.shape(), &[n])))
        {
            return Err(PyValueError::new_err(format!(
                "positions, velocities and masses must keep their shapes ({n}, 3), ({n}, 3) and ({n},); \
                 assign new values into them instead of resizing"
            )));
        }
        let (xs, vs, ms) = (
            x.as_ref().map(|a| values(a.view().into_dyn())),
            v.as_ref().map(|a| values(a.view().into_dyn())),
            m.as_ref().map(|a| values(a.view().into_dyn())),
        );
        if self.inner.state_is(xs.as_deref(), vs.as_deref(), ms.as_deref()) {
            return Ok(false);
        }
        // (a write: the user's order, what no view holds read from the world; the values
        // checked by the engine's one check, `kinema::particles::check_state`, nothing written
        // if one is bad)
        let (xw, vw, mw) = (
            xs.map_or_else(|| self.inner.in_user_order(|p| &p.x, 3).into_owned(), |a| a.into_owned()),
            vs.map_or_else(|| self.inner.in_user_order(|p| &p.v, 3).into_owned(), |a| a.into_owned()),
            ms.map_or_else(|| self.inner.in_user_order(|p| &p.mass, 1).into_owned(), |a| a.into_owned()),
        );
        self.inner.get().write_state(&xw, &vw, &mw).map_err(to_py)?;
        Ok(true)
    }

    /// Turns spin on or off (`World::set_spin`).
    fn set_spin(&mut self, on: bool) {
        self.inner.get().set_spin(on);
    }

    #[getter]
    fn spin(&self) -> bool {
        self.inner.has_spin()
    }

    /// Sets the angular velocities ((K, 3), rad/s) and moments of inertia ((K,), kg m²) of
    /// the particles first..end, where given.
    fn set_particle_spin(
        &mut self,
        first: usize,
        end: usize,
        omega: Option<PyReadonlyArray2<'_, f64>>,
        inertia: Option<PyReadonlyArray1<'_, f64>>,
    ) -> PyResult<()> {
        let omega = omega.as_ref().map(|w| flat3("angular_velocity", w)).transpose()?;
        let inertia = inertia.as_ref().map(|i| i.as_slice()).transpose()?;
        self.inner
            .set_particle_spin(first..end, omega.as_deref(), inertia)
            .map_err(to_py)
    }

    /// Checks angular velocities ((K, 3), rad/s) and moments of inertia ((K,), kg m²) for K
    /// particles about to be added (the checks of `set_particle_spin`).
    fn check_particle_spin(
        &self,
        omega: Option<PyReadonlyArray2<'_, f64>>,
        inertia: Option<PyReadonlyArray1<'_, f64>>,
    ) -> PyResult<()> {
        let omega = omega.as_ref().map(|w| flat3("angular_velocity", w)).transpose()?;
        let inertia = inertia.as_ref().map(|i| i.as_slice()).transpose()?;
        let n = omega.as_ref().map_or_else(|| inertia.map_or(0, |i| i.len()), |w| w.len() / 3);
        kinema::Particles::check_spin(n, omega.as_deref(), inertia, self.inner.params().dim).map_err(to_py)
    }

    /// The moments of inertia, kg m² (N,), in the user's order (empty without spin).
    #[getter]
    fn inertia<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, &self.inner.in_user_order(|p| &p.inertia, 1))
    }

    /// The orientations, unit quaternions (w, x, y, z), (N, 4), in the user's order (N = 0
    /// rows without spin).
    #[getter]
    fn orientations<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let q = self.inner.in_user_order(|p| &p.orientation, 4);
        let n = q.len() / 4;
        PyArray1::from_vec(py, q.to_vec()).reshape([n, 4])
    }

    /// Sets the orientations of all particles ((N, 4) unit quaternions (w, x, y, z), the
    /// user's order; each normalised). Needs spin.
    fn set_orientations(&mut self, q: PyReadonlyArray2<'_, f64>) -> PyResult<()> {
        let n = self.inner.len();
        let q = q.as_array();
        if q.shape() != [n, 4] {
            return Err(PyValueError::new_err(format!(
                "orientations of shape {:?} is invalid: it must be ({n}, 4), a quaternion (w, x, y, z) per particle",
                q.shape()
            )));
        }
        let given: Vec<f64> = q.iter().copied().collect();
        self.inner.set_orientations(0..n, &given).map_err(to_py)
    }

    /// Writes the angular velocities (rad/s) into the caller's (N, 3) array, in the user's
    /// order (needs spin).
    fn read_spin(&self, mut w: PyReadwriteArray2<'_, f64>) -> PyResult<()> {
        let n = self.inner.len();
        let mut w = w.as_array_mut();
        let omega = self.inner.in_user_order(|p| &p.omega, 3);
        if w.shape() != [n, 3] || omega.len() != 3 * n {
            return Err(PyValueError::new_err(format!(
                "angular velocities: a world with spin reads them into an ({n}, 3) array"
            )));
        }
        w.iter_mut().zip(omega.iter()).for_each(|(d, s)| *d = *s);
        Ok(())
    }

    /// Copies the angular velocities (rad/s, (N, 3), the user's order) into the world when
    /// they differ from its own; returns whether they did. Every value is checked first.
    fn sync_spin(&mut self, w: PyReadonlyArray2<'_, f64>) -> PyResult<bool> {
        let n = self.inner.len();
        let w = w.as_array();
        if w.shape() != [n, 3] {
            return Err(PyValueError::new_err(format!(
                "angular_velocities must keep its shape ({n}, 3); assign new values into it instead of resizing"
            )));
        }
        let given: Vec<f64> = w.iter().copied().collect();
        if *self.inner.in_user_order(|p| &p.omega, 3) == given[..] {
            return Ok(false);
        }
        // (named as the user wrote them: into the view)
        if let Some(k) = given.iter().position(|c| !c.is_finite()) {
            return Err(PyValueError::new_err(format!(
                "angular_velocities[{}][{}] = {} is invalid: it must be finite, rad/s",
                k / 3,
                k % 3,
                given[k]
            )));
        }
        self.inner.set_particle_spin(0..n, Some(&given), None).map_err(to_py)?;
        Ok(true)
    }

    /// Writes the positions and velocities into the caller's (N, 3) arrays (those given).
    #[pyo3(signature = (x=None, v=None))]
    fn read_state(&self, x: Option<PyReadwriteArray2<'_, f64>>, v: Option<PyReadwriteArray2<'_, f64>>) -> PyResult<()> {
        let n = self.inner.len();
        let mut arrays = [x, v];
        for a in arrays.iter_mut().flatten() {
            if a.as_array().shape() != [n, 3] {
                return Err(PyValueError::new_err(format!("state arrays must have shape ({n}, 3)")));
            }
        }
        let [x, v] = &mut arrays;
        let (mut x, mut v) = (x.as_mut().map(|a| a.as_array_mut()), v.as_mut().map(|a| a.as_array_mut()));
        let contiguous = x.as_ref().is_none_or(|a| a.is_standard_layout()) && v.as_ref().is_none_or(|a| a.is_standard_layout());
        if contiguous {
            self.inner.read_state_into(
                x.as_mut().and_then(|a| a.as_slice_mut()),
                v.as_mut().and_then(|a| a.as_slice_mut()),
            );
        } else {
            let (mut xs, mut vs) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
            self.inner.read_state_into(Some(&mut xs), Some(&mut vs));
            if let Some(x) = &mut x {
                x.iter_mut().zip(&xs).for_each(|(d, s)| *d = *s);
            }
            if let Some(v) = &mut v {
                v.iter_mut().zip(&vs).for_each(|(d, s)| *d = *s);
            }
        }
        Ok(())
    }

    /// The advisor's largest stable step (s) for `method` (a name or tableau) at the current
    /// state; inf when no step is too large.
    fn stable_step(&mut self, method: Bound<'_, PyAny>) -> PyResult<f64> {
        let world = self.inner.get();
        let method = integrator_from(&method)?;
        world.stable_step(&method).map_err(world_err)
    }

    /// The advisor's rates at the current state, as a dict.
    fn rates<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let world = self.inner.get();
        let r = world.rates().map_err(world_err)?;
        let out = PyDict::new(py);
        out.set_item("omega", r.omega)?;
        out.set_item("zeta", r.zeta)?;
        out.set_item("damping_rate", r.damping_rate)?;
        out.set_item("omega_bound", r.bound.map(|b| b.omega_squared.sqrt()))?;
        out.set_item("damping_rate_bound", r.bound.map(|b| b.damping_rate))?;
        out.set_item("iterations", r.iterations)?;
        out.set_item("standby_omega", r.standby.map(|s| s.0))?;
        out.set_item("standby_zeta", r.standby.map(|s| s.1))?;
        Ok(out)
    }

    /// CG iterations of the last implicit_euler step and whether they converged, or None.
    fn linear_solve(&self) -> Option<(usize, bool)> {
        self.inner.linear_solve().map(|s| (s.iterations, s.converged))
    }

    /// Sets positions and velocities (both (N, 3)); method caches restart.
    fn set_state(&mut self, x: PyReadonlyArray2<'_, f64>, v: PyReadonlyArray2<'_, f64>) -> PyResult<()> {
        let world = self.inner.get();
        let (x, v) = (flat3("positions", &x)?, flat3("velocities", &v)?);
        let n = world.particles().len();
        if x.len() != 3 * n || v.len() != 3 * n {
            return Err(PyValueError::new_err(format!(
                "positions and velocities must have shape ({n}, 3)"
            )));
        }
        if let Some(i) = x.iter().chain(v.iter()).position(|c| !c.is_finite()) {
            return Err(PyValueError::new_err(format!("state value {i} is not finite")));
        }
        let p = world.particles_mut();
        p.x.copy_from_slice(&x);
        for (k, (dst, src)) in p.v.iter_mut().zip(v.iter()).enumerate() {
            *dst = if p.inv_mass[k / 3] == 0.0 { 0.0 } else { *src }; // pinned particles stay at rest
        }
        Ok(())
    }

    fn accelerations<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let world = self.inner.get();
        let a = world.accelerations().map_err(world_err)?;
        rows(py, &a)
    }

    /// Each particle's share of the contacts' virial (and of the kinetic tensor), N·m: (N, 3, 3).
    fn particle_stress<'py>(&mut self, py: Python<'py>, kinetic: bool) -> PyResult<Bound<'py, PyArray3<f64>>> {
        let world = self.inner.get();
        let s = world.particle_stress(kinetic).map_err(world_err)?;
        let n = s.len() / 9;
        Ok(PyArray1::from_vec(py, s).reshape([n, 3, 3])?)
    }

    /// Energies and momenta now, as a dict (sums over the engine's order: see `PyWorld`).
    fn diagnostics<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        diagnostics_dict(py, &self.inner.diagnostics(), self.inner.has_spin())
    }

    /// `step(n)` and then `diagnostics()`, the contacts' energy summed by the last step's own
    /// force pass rather than by a pass of its own (`World::advance_measured`): what
    /// `World.run` records at each frame.
    ///
    /// With `x` and `v` ((N, 3) C-contiguous float64 arrays), the positions and velocities at
    /// the end are written there too, in the user's order, by the diagnostics' own pass over
    /// the state (what `read_state` would write: `World.run` records its frames so); the
    /// dict's `"state"` says whether they were (not where a death in the steps changed N).
    #[pyo3(signature = (n, x=None, v=None))]
    fn step_measured<'py>(
        &mut self,
        py: Python<'py>,
        n: u64,
        x: Option<PyReadwriteArray2<'_, f64>>,
        v: Option<PyReadwriteArray2<'_, f64>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let (mut x, mut v) = match (x, v) {
            (None, None) => (None, None),
            (Some(x), Some(v)) => {
                for (name, a) in [("x", &x), ("v", &v)] {
                    if a.as_array().shape()[1] != 3 || !a.as_array().is_standard_layout() {
                        return Err(PyValueError::new_err(format!(
                            "{name} must be a C-contiguous (N, 3) float64 array"
                        )));
                    }
                }
                (Some(x), Some(v))
            }
            _ => {
                return Err(PyValueError::new_err(
                    "x and v go together: rooms for the positions and velocities",
                ))
            }
        };
        if n == 0 {
            let d = self.diagnostics(py)?;
            if x.is_some() {
                d.set_item("state", false)?;
            }
            return Ok(d);
        }
        step_in_slices(py, &mut self.inner, n - 1)?;
        let world = &mut self.inner;
        let rooms = x.as_mut().zip(v.as_mut()).map(|(x, v)| (x.as_slice_mut(), v.as_slice_mut()));
        let (d, written) = match rooms {
            Some((Ok(x), Ok(v))) => py.detach(move || world.advance_in_engine_order_measured_into(1, x, v)),
            _ => py.detach(move || world.advance_in_engine_order_measured(1).map(|d| (d, false))),
        }
        .map_err(world_err)?;
        py.check_signals()?;
        let out = diagnostics_dict(py, &d, self.inner.has_spin())?;
        if x.is_some() {
            out.set_item("state", written)?;
        }
        Ok(out)
    }
}

/// A world's [`Diagnostics`] as the dict `World.diagnostics()` gives (`spin`: the rotational
/// energy and the spins' angular momentum too).
fn diagnostics_dict<'py>(py: Python<'py>, d: &Diagnostics, spin: bool) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    out.set_item("t", d.t)?;
    out.set_item("kinetic", d.kinetic)?;
    let pot = PyDict::new(py);
    for (name, u) in &d.potential {
        let prev: f64 = pot.get_item(name)?.map(|v| v.extract()).transpose()?.unwrap_or(0.0);
        pot.set_item(name, prev + u)?;
    }
    out.set_item("potential", pot)?;
    out.set_item("momentum", d.momentum.to_vec())?;
    out.set_item("angular_momentum", d.angular_momentum.to_vec())?;
    out.set_item("kinetic_tensor", d.kinetic_tensor.to_vec())?;
    if spin {
        out.set_item("rotational", d.rotational)?;
        out.set_item("spin_angular_momentum", d.spin.to_vec())?;
    }
    Ok(out)
}

/// The values of an array in row-major order: borrowed where it is contiguous, else copied.
fn values<'a>(a: numpy::ndarray::ArrayViewD<'a, f64>) -> std::borrow::Cow<'a, [f64]> {
    match a.to_slice() {
        Some(s) => std::borrow::Cow::Borrowed(s),
        None => std::borrow::Cow::Owned(a.iter().copied().collect()),
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyWorld>()?;
    collide::register(m)?;
    m.add("SimulationDiverged", m.py().get_type::<SimulationDiverged>())?;
    Ok(())
}

/// A falloff as `kinema.Falloff` hands it over: shape, law, centre (m), axis (a tube's),
/// half size (a box's, m), min and max distance (m; max may be inf).
type FalloffArgs = (String, String, [f64; 3], [f64; 3], [f64; 3], f64, f64);

/// The engine's falloff from its arguments (see [`FalloffArgs`]).
fn falloff_from(args: Option<FalloffArgs>) -> PyResult<Option<Falloff>> {
    let Some((shape, law, center, axis, half_size, min_distance, max_distance)) = args else {
        return Ok(None);
    };
    let shape = match shape.as_str() {
        "sphere" => Shape::Sphere { center },
        "tube" => Shape::Tube { center, axis },
        "box" => Shape::Box { center, half_size },
        _ => {
            return Err(PyValueError::new_err(format!(
                "falloff.shape = {shape:?} is invalid: the falloff shape must be 'sphere', 'tube' or 'box'"
            )))
        }
    };
    let law = Law::from_name(&law).map_err(to_py)?;
    Falloff::new(shape, law, min_distance, max_distance).map(Some).map_err(to_py)
}

/// `items` (`len` of them) collected into a vector whose memory was asked for first: memory
/// the machine cannot give for `count` springs is a `MemoryError`, not an abort.
fn fallible<T>(items: impl Iterator<Item = T>, len: usize, count: usize) -> PyResult<Vec<T>> {
    let mut out = Vec::new();
    if out.try_reserve_exact(len.max(count)).is_err() {
        return Err(to_py(kinema::Error::out_of_memory(
            format!("{count} springs"),
            count.saturating_mul(Springs::BYTES_PER_SPRING),
        )));
    }
    out.extend(items);
    Ok(out)
}

/// The kill volumes as Python gives them: ("box", lo, hi), ("sphere", center, radius) or
/// ("plane", point, normal).
fn kill_volumes(kills: Vec<(String, [f64; 3], Bound<'_, PyAny>)>) -> PyResult<Vec<KillVolume>> {
    kills
        .into_iter()
        .map(|(kind, a, b)| {
            Ok(match kind.as_str() {
                "box" => KillVolume::Box { lo: a, hi: b.extract()? },
                "sphere" => KillVolume::Sphere {
                    center: a,
                    radius: b.extract()?,
                },
                "plane" => KillVolume::Plane {
                    point: a,
                    normal: b.extract()?,
                },
                other => {
                    return Err(PyValueError::new_err(format!(
                        "kill volume {other:?} is unknown: \"box\", \"sphere\" or \"plane\""
                    )))
                }
            })
        })
        .collect::<PyResult<Vec<_>>>()
}
