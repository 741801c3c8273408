//! `World`'s contents between steps: the forces of the catalogue and Python's, the
//! colliders and their motion, collision settings, groups and masks, the particles'
//! materials, removals and deaths, and what the collisions report (books, contacts, events,
//! statistics).

use kinema::collide::mesh::mesh_buffer;
use kinema::collide::Surface;
use kinema::forces::vortex::Profile;
use kinema::forces::{Attractor, Coupling, Drag, Gravity, Springs, Turbulence, Vortex, Wind};
use numpy::{PyArray1, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::callbacks::PythonForce;
use crate::collide;
use crate::errors::to_py;
use crate::reports;

use super::*;

#[pymethods]
impl PyWorld {
    /// Each particle's own (restitution, friction), None where not set; empty if none has.
    fn particle_materials(&mut self) -> Vec<(Option<f64>, Option<f64>)> {
        self.inner.get().particle_materials()
    }

    /// Each particle's collision group, in the user's order (gathered: the engine may keep
    /// its own order, which a read leaves as it is).
    #[getter]
    fn groups<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<u8>> {
        let groups = self.inner.in_user_order(|p| &p.group, 1);
        if groups.is_empty() {
            PyArray1::zeros(py, self.inner.len(), false) // all in group 0 (none stored)
        } else {
            PyArray1::from_slice(py, &groups)
        }
    }

    /// Puts particles start.. into the collision groups `group` (checked: 0..32).
    fn set_groups(&mut self, start: usize, group: Vec<u32>) -> PyResult<()> {
        self.inner.get().set_particle_groups(start, &group).map_err(to_py)
    }

    /// The collision groups' matrix as one 32-bit mask per group (bit h of row g: g and h
    /// collide).
    #[getter]
    fn group_masks(&self) -> Vec<u32> {
        self.inner.group_masks().rows().to_vec()
    }

    /// Sets the matrix from 32 masks (checked symmetric).
    fn set_group_masks(&mut self, masks: [u32; 32]) -> PyResult<()> {
        let world = self.inner.get();
        let masks = kinema::collide::GroupMasks::from_rows(masks).map_err(to_py)?;
        world.set_group_masks(masks).map_err(to_py)
    }

    /// Sets whether groups a and b collide (both ways).
    fn set_group_collisions(&mut self, a: usize, b: usize, collide: bool) -> PyResult<()> {
        self.inner.get().set_group_collisions(a, b, collide).map_err(to_py)
    }

    /// Sets the mask of the groups collider k collides with.
    fn set_collider_mask(&mut self, k: usize, mask: u32) -> PyResult<()> {
        self.inner.get().set_collider_mask(k, mask).map_err(to_py)
    }

    /// Each collider's mask of the groups it collides with.
    #[getter]
    fn collider_masks(&self) -> Vec<u32> {
        self.inner.collider_masks()
    }

    /// Removes the particles at these indices (checked; repeats allowed).
    fn remove_particles(&mut self, indices: Vec<usize>) -> PyResult<()> {
        self.inner.get().remove_particles(&indices).map_err(to_py)
    }

    /// Sets the deaths the engine carries out after each step: each particle's time of
    /// death (s, inf: never; None: nobody dies of age) and the kill volumes, each
    /// ("box", lo, hi), ("sphere", center, radius) or ("plane", point, normal).
    #[pyo3(signature = (time_of_death, kills))]
    fn set_deaths(
        &mut self,
        time_of_death: Option<PyReadonlyArray1<'_, f64>>,
        kills: Vec<(String, [f64; 3], Bound<'_, PyAny>)>,
    ) -> PyResult<()> {
        let time_of_death = time_of_death.map(|t| t.as_array().to_vec());
        let kills = kill_volumes(kills)?;
        self.inner.set_deaths(time_of_death, kills).map_err(to_py)
    }

    /// Sets the kill volumes (as `set_deaths` takes them); the times of death stay.
    fn set_kill_volumes(&mut self, kills: Vec<(String, [f64; 3], Bound<'_, PyAny>)>) -> PyResult<()> {
        let kills = kill_volumes(kills)?;
        self.inner.set_kill_volumes(kills).map_err(to_py)
    }

    /// Sets the times of death (s; inf: never) of particles `start..start + len(times)` (the
    /// user's order); the engine keeps them with the particles from then on.
    fn set_times_of_death(&mut self, start: usize, times: PyReadonlyArray1<'_, f64>) -> PyResult<()> {
        let times = times.as_array().to_vec();
        self.inner.set_times_of_death(start, &times).map_err(to_py)
    }

    /// Each particle's time of death (s; inf: never) in the user's order, or None while no
    /// particle has one.
    fn times_of_death<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        let t = self.inner.times_of_death();
        (!t.is_empty()).then(|| PyArray1::from_vec(py, t))
    }

    /// Whether some particle has a finite time of death.
    #[getter]
    fn has_times_of_death(&self) -> bool {
        self.inner.has_times_of_death()
    }

    /// The ids of the particles the engine's deaths removed since the last call.
    fn take_removed_ids(&mut self) -> Vec<u64> {
        self.inner.take_removed_ids()
    }

    fn add_gravity(&mut self, g: [f64; 3]) -> PyResult<()> {
        self.inner
            .get()
            .add_force(Box::new(Gravity::new(g).map_err(to_py)?))
            .map_err(to_py)
    }

    fn add_drag(&mut self, linear: f64, quadratic: f64) -> PyResult<()> {
        let world = self.inner.get();
        world
            .add_force(Box::new(Drag::new(linear, quadratic).map_err(to_py)?))
            .map_err(to_py)
    }

    /// Adds springs; returns their rest lengths, m (those given, or the current distances).
    #[pyo3(signature = (i, j, k, rest_length, damping))]
    fn add_springs<'py>(
        &mut self,
        py: Python<'py>,
        i: PyReadonlyArray1<'py, i64>,
        j: PyReadonlyArray1<'py, i64>,
        k: PyReadonlyArray1<'py, f64>,
        rest_length: Option<PyReadonlyArray1<'py, f64>>,
        damping: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let world = self.inner.get();
        let count = i.len();
        // Room first (the springs' arrays, the force pass's buffers), so that a count the
        // machine cannot hold is a MemoryError here, not an abort in a later step.
        Springs::room(count).map_err(to_py)?;
        let indices = |name: &str, a: &PyReadonlyArray1<'py, i64>| -> PyResult<Vec<usize>> {
            let a = a.as_slice()?;
            if let Some(s) = a.iter().position(|v| *v < 0) {
                return Err(PyValueError::new_err(format!(
                    "{name}[{s}] = {} is invalid: particle indices are >= 0",
                    a[s]
                )));
            }
            fallible(a.iter().map(|v| *v as usize), a.len(), count)
        };
        let values = |a: &PyReadonlyArray1<'py, f64>| -> PyResult<Vec<f64>> {
            let a = a.as_slice()?;
            fallible(a.iter().copied(), a.len(), count)
        };
        let (i, j) = (indices("i", &i)?, indices("j", &j)?);
        let rest = match rest_length {
            Some(r) => values(&r)?,
            None => {
                // rest lengths from the current positions (a spring at rest as built)
                let x = &world.particles().x;
                let n = world.particles().len();
                let mut rest = fallible(std::iter::empty(), 0, count)?;
                for (s, (&a, &b)) in i.iter().zip(&j).enumerate() {
                    if a >= n || b >= n {
                        return Err(PyValueError::new_err(format!(
                            "spring {s} joins particles {a} and {b}, but the world has {n} particles"
                        )));
                    }
                    rest.push((0..3).map(|c| (x[3 * b + c] - x[3 * a + c]).powi(2)).sum::<f64>().sqrt());
                }
                rest
            }
        };
        let taken = PyArray1::from_slice(py, &rest); // (the lengths taken from the positions, which a scene or checkpoint must keep)
        let springs = Springs::new(i, j, values(&k)?, rest, values(&damping)?).map_err(to_py)?;
        world.add_force(Box::new(springs)).map_err(to_py)?;
        Ok(taken)
    }

    #[pyo3(signature = (point, strength, softening, falloff=None))]
    fn add_attractor(&mut self, point: [f64; 3], strength: f64, softening: f64, falloff: Option<FalloffArgs>) -> PyResult<()> {
        let world = self.inner.get();
        let attractor = Attractor::new(point, strength, softening).map_err(to_py)?;
        let falloff = falloff_from(falloff)?;
        world.add_force(Box::new(attractor.with_falloff(falloff))).map_err(to_py)
    }

    #[pyo3(signature = (velocity, coefficient, falloff=None))]
    fn add_wind(&mut self, velocity: [f64; 3], coefficient: f64, falloff: Option<FalloffArgs>) -> PyResult<()> {
        let world = self.inner.get();
        let wind = Wind::new(velocity, coefficient).map_err(to_py)?;
        let falloff = falloff_from(falloff)?;
        world.add_force(Box::new(wind.with_falloff(falloff))).map_err(to_py)
    }

    /// Adds a vortex (`kinema.Vortex`); `coefficient` None: an acceleration field.
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (point, axis, strength, radius, profile, coefficient, falloff))]
    fn add_vortex(
        &mut self,
        point: [f64; 3],
        axis: [f64; 3],
        strength: f64,
        radius: f64,
        profile: &str,
        coefficient: Option<f64>,
        falloff: Option<FalloffArgs>,
    ) -> PyResult<()> {
        let world = self.inner.get();
        let profile = Profile::from_name(profile).map_err(to_py)?;
        let falloff = falloff_from(falloff)?;
        let vortex = Vortex::new(
            point,
            axis,
            strength,
            radius,
            profile,
            Coupling::from_coefficient(coefficient),
            falloff,
        )
        .map_err(to_py)?;
        world.add_force(Box::new(vortex)).map_err(to_py)
    }

    /// Adds curl-noise turbulence (`kinema.Turbulence`) in the world's dimension;
    /// `time_scale` None freezes it, `coefficient` None makes it an acceleration field.
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (strength, scale, seed, time_scale, octaves, roughness, coefficient, falloff))]
    fn add_turbulence(
        &mut self,
        strength: f64,
        scale: f64,
        seed: u64,
        time_scale: Option<f64>,
        octaves: u32,
        roughness: f64,
        coefficient: Option<f64>,
        falloff: Option<FalloffArgs>,
    ) -> PyResult<()> {
        let world = self.inner.get();
        let falloff = falloff_from(falloff)?;
        let turbulence = Turbulence::new(
            strength,
            scale,
            seed,
            time_scale.unwrap_or(f64::INFINITY),
            octaves,
            roughness,
            world.params().dim,
            Coupling::from_coefficient(coefficient),
            falloff,
        )
        .map_err(to_py)?;
        world.add_force(Box::new(turbulence)).map_err(to_py)
    }

    fn add_python_force(&mut self, f: Py<PyAny>, name: String) -> PyResult<()> {
        self.inner.get().add_force(Box::new(PythonForce { f, name })).map_err(to_py)
    }

    /// Turns collisions on, or changes their settings (every one of them), from the dict of
    /// `World.set_collisions`' keyword arguments.
    fn set_collisions(&mut self, settings: collide::CollisionArgs) -> PyResult<()> {
        let world = self.inner.get();
        let params = settings.params().map_err(to_py)?;
        world.set_collisions(params).map_err(to_py)
    }

    /// The collision settings as set_collisions' keyword arguments, or None when off.
    #[getter]
    fn collisions<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        self.inner
            .collision_params()
            .map(|p| collide::params_dict(py, &p))
            .transpose()
    }

    /// The contact force model's sub-models now, (kind, name) pairs, or None without one.
    fn contact_sub_models(&self) -> Option<Vec<(&'static str, &'static str)>> {
        self.inner.contact_sub_models()
    }

    /// Adds a plane; returns the collider's index.
    fn add_plane(
        &mut self,
        point: [f64; 3],
        normal: [f64; 3],
        restitution: Option<f64>,
        friction: Option<f64>,
    ) -> PyResult<usize> {
        let world = self.inner.get();
        let surface = Surface::new(restitution, friction).map_err(to_py)?;
        let plane = collide::plane(world.params().dim, point, normal, surface).map_err(to_py)?;
        world.add_collider(plane).map_err(to_py)
    }

    /// Adds a box container (2 values per corner in 2D, 3 in 3D); returns its index.
    fn add_box(&mut self, lo: Vec<f64>, hi: Vec<f64>, restitution: Option<f64>, friction: Option<f64>) -> PyResult<usize> {
        let world = self.inner.get();
        let surface = Surface::new(restitution, friction).map_err(to_py)?;
        let b = collide::box_container(world.params().dim, &lo, &hi, surface).map_err(to_py)?;
        world.add_collider(b).map_err(to_py)
    }

    /// Adds a sphere obstacle; returns its index.
    fn add_sphere_obstacle(
        &mut self,
        center: [f64; 3],
        radius: f64,
        restitution: Option<f64>,
        friction: Option<f64>,
    ) -> PyResult<usize> {
        let world = self.inner.get();
        let surface = Surface::new(restitution, friction).map_err(to_py)?;
        let s = collide::sphere_obstacle(world.params().dim, center, radius, surface).map_err(to_py)?;
        world.add_collider(s).map_err(to_py)
    }

    /// Adds a triangle mesh (vertices V × 3, m; faces F × 3 vertex indices); returns its index.
    #[pyo3(signature = (vertices, faces, inside, restitution, friction))]
    fn add_mesh(
        &mut self,
        vertices: PyReadonlyArray2<'_, f64>,
        faces: PyReadonlyArray2<'_, i64>,
        inside: bool,
        restitution: Option<f64>,
        friction: Option<f64>,
    ) -> PyResult<usize> {
        let world = self.inner.get();
        let surface = Surface::new(restitution, friction).map_err(to_py)?;
        let (v, f) = (vertices.as_array(), faces.as_array());
        if v.ncols() != 3 || f.ncols() != 3 {
            return Err(PyValueError::new_err(format!(
                "vertices and faces must have 3 columns (x, y, z; three vertex indices), not {} and {}",
                v.ncols(),
                f.ncols()
            )));
        }
        // Buffers sized by the user, allocated fallibly: a mesh too large is a MemoryError.
        let mut verts = mesh_buffer(v.nrows(), f.nrows()).map_err(to_py)?;
        verts.extend(v.rows().into_iter().map(|r| [r[0], r[1], r[2]]));
        let tris = f.rows().into_iter().map(|r| [r[0], r[1], r[2]]);
        let mesh = collide::mesh(verts, tris, inside, surface).map_err(to_py)?;
        world.add_collider(mesh).map_err(to_py)
    }

    /// Makes the axes periodic with the cell of the box collider (wraps the positions).
    fn set_periodic(&mut self, axes: [bool; 3]) -> PyResult<()> {
        self.inner.get().set_periodic(axes).map_err(to_py)
    }

    #[getter]
    fn periodic(&self) -> (bool, bool, bool) {
        let [x, y, z] = self.inner.periodic();
        (x, y, z)
    }

    /// Gives collider k a prescribed motion: steady (`velocity`, m/s; `angular_velocity`,
    /// rad/s; about `pivot`, m), or keyframes (`times`, s; `translations`, m, K × 3;
    /// `rotations`, unit quaternions w, x, y, z, K × 4; about `pivot`); all None: still.
    #[pyo3(signature = (k, velocity=None, angular_velocity=None, pivot=None, times=None, translations=None, rotations=None, start=None))]
    #[allow(clippy::too_many_arguments)]
    fn set_collider_motion(
        &mut self,
        k: usize,
        velocity: Option<[f64; 3]>,
        angular_velocity: Option<[f64; 3]>,
        pivot: Option<[f64; 3]>,
        times: Option<Vec<f64>>,
        translations: Option<Vec<[f64; 3]>>,
        rotations: Option<Vec<[f64; 4]>>,
        start: Option<f64>,
    ) -> PyResult<()> {
        let world = self.inner.get();
        let motion = collide::motion(velocity, angular_velocity, pivot, times, translations, rotations, start).map_err(to_py)?;
        world.set_collider_motion(k, motion).map_err(to_py)
    }

    /// What the particles gave each collider over all steps (with `last`, in the last step):
    /// {"momentum": (K, 3) N·s, "angular_momentum": (K, 3) N·m·s about the origin, "work":
    /// (K,) J done by the collider on the particles, "normal" and "tangential": (K, 3) N·s,
    /// the momentum's parts along and across the contacts' normals}.
    #[pyo3(signature = (last = false))]
    fn collider_books<'py>(&self, py: Python<'py>, last: bool) -> PyResult<Bound<'py, PyDict>> {
        reports::books_dict(py, &self.inner.collider_books(last))
    }

    /// The contacts now (the impulse model's: of the last step's end), as arrays, with their
    /// points, forces and whether they slide.
    fn contacts<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let world = self.inner.get();
        let impulses = world
            .collision_params()
            .is_some_and(|p| p.model == kinema::world::ContactModel::Impulse);
        let reports = world.contact_reports().map_err(to_py)?;
        reports::contacts_dict(py, &reports, impulses)
    }

    /// Starts or stops recording begin and end of touch.
    fn record_contact_events(&mut self, on: bool) -> PyResult<()> {
        self.inner.record_contact_events(on).map_err(to_py)
    }

    /// The begin and end of touch events since the last call, taken out, as arrays.
    fn contact_events<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        reports::touch_events_dict(py, &self.inner.take_contact_events())
    }

    /// {"last": ..., "total": ...} of the collision stages, or None without collisions.
    fn collision_stats<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some((last, total)) = self.inner.collision_stats() else {
            return Ok(None);
        };
        let out = PyDict::new(py);
        out.set_item("last", reports::stats_dict(py, &last)?)?;
        out.set_item("total", reports::stats_dict(py, &total)?)?;
        Ok(Some(out))
    }
}
