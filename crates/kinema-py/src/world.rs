//! Bindings of the particle world: World, the force catalogue, Python forces, diagnostics,
//! collisions (conversions in `collide.rs`; stepping and SimulationDiverged in
//! `stepping.rs`; the Python force in `callbacks.rs`).

use kinema::collide::mesh::mesh_buffer;
use kinema::collide::{ContactRecord, Partner, Surface};
use kinema::forces::falloff::{Law, Shape};
use kinema::forces::vortex::Profile;
use kinema::forces::{Attractor, Coupling, Drag, Falloff, Gravity, Springs, Turbulence, Vortex, Wind};
use kinema::world::{KillVolume, UserOrder};
use kinema::{World, WorldParams};
use numpy::{
    PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadwriteArray2, PyUntypedArrayMethods,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::callbacks::PythonForce;
use crate::collide;
use crate::errors::to_py;
use crate::ode::integrator_from;
use crate::stepping::{ctrl_c, step_in_slices, world_err, SimulationDiverged};

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

    /// A checkpoint's time, steps and ids (see `World::restore_clock_and_ids`).
    fn restore_clock_and_ids(&mut self, time: f64, steps: u64, ids: Vec<u64>, next_id: u64) -> PyResult<()> {
        self.inner
            .get()
            .restore_clock_and_ids(time, steps, &ids, next_id)
            .map_err(to_py)
    }

    /// A checkpoint's clock anchor (see `World::restore_clock`).
    fn restore_clock(&mut self, k0: u64, t0: f64) -> PyResult<()> {
        self.inner.restore_clock(k0, t0).map_err(to_py)
    }

    /// The clock: (k0 steps, t0 s, h s, landing (k1, t1) or None) (see `World::clock`).
    #[getter]
    fn clock(&self) -> (u64, f64, f64, Option<(u64, f64)>) {
        let c = self.inner.clock();
        (c.k0, c.t0, c.h, c.landing)
    }

    /// Plans the next `n` steps to end at `t1` s exactly (see `World::land_at`).
    fn land_at(&mut self, t1: f64, n: u64) -> PyResult<()> {
        self.inner.land_at(t1, n).map_err(to_py)
    }

    /// A checkpoint's collision books (dicts as `collision_stats` gives them).
    fn restore_collision_stats(&mut self, total: Bound<'_, PyDict>, last: Bound<'_, PyDict>) -> PyResult<()> {
        let world = self.inner.get();
        let (total, last) = (collide::stats_from(&total)?, collide::stats_from(&last)?);
        world.restore_collision_stats(total, last);
        Ok(())
    }

    /// A checkpoint's collider books: `total` and `last`, dicts of arrays as `collider_books`
    /// gives them (one row per collider).
    fn restore_collider_books(&mut self, total: Bound<'_, PyDict>, last: Bound<'_, PyDict>) -> PyResult<()> {
        let (total, last) = (collide::books_from(&total)?, collide::books_from(&last)?);
        self.inner.get().restore_collider_books(total, last).map_err(to_py)
    }

    /// Starts the caches again (a checkpoint's restart point).
    fn restart_caches(&mut self) -> PyResult<()> {
        self.inner.get().restart_caches().map_err(to_py)
    }

    /// What the method carries from step to step (Verlet's a, implicit Euler's Δv), or None.
    fn integrator_carry<'py>(&mut self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.inner.get().integrator_carry().map(|c| PyArray1::from_vec(py, c))
    }

    fn restore_integrator_carry(&mut self, carry: Vec<f64>) -> PyResult<()> {
        self.inner.get().restore_integrator_carry(carry).map_err(to_py)
    }

    /// Verlet's angular accelerations under the contacts' torques (a checkpoint's carry).
    fn spin_carry<'py>(&mut self, py: Python<'py>) -> Option<Bound<'py, PyArray1<f64>>> {
        self.inner.get().spin_carry().map(|c| PyArray1::from_vec(py, c))
    }

    fn restore_spin_carry(&mut self, carry: Vec<f64>) -> PyResult<()> {
        self.inner.restore_spin_carry(carry).map_err(to_py)
    }

    /// The force models' contact memory: ([(i, j, springs[7])], [(i, collider, normal, springs[7])]).
    #[allow(clippy::type_complexity)]
    fn contact_history(&mut self) -> (Vec<kinema::world::PairMemory>, Vec<kinema::world::WallMemory>) {
        self.inner.get().contact_history()
    }

    fn restore_contact_history(
        &mut self,
        pairs: Vec<kinema::world::PairMemory>,
        walls: Vec<kinema::world::WallMemory>,
    ) -> PyResult<()> {
        self.inner.restore_contact_history(pairs, walls).map_err(to_py)
    }

    /// The impulse model's contact records: (particle, partner is a collider, partner index,
    /// the solve stage's impulse, whether it carried load).
    fn collision_carry(&mut self) -> Vec<(usize, bool, usize, [f64; 3], bool)> {
        self.inner
            .get()
            .collision_carry()
            .into_iter()
            .map(|r| match r.other {
                Partner::Particle(j) => (r.i, false, j, r.impulse, r.carried),
                Partner::Collider(c) => (r.i, true, c, r.impulse, r.carried),
            })
            .collect()
    }

    /// Gives the records back; `carried` None: taken from the impulse (a checkpoint written
    /// before the records kept it).
    #[allow(clippy::type_complexity)]
    fn restore_collision_carry(&mut self, carry: Vec<(usize, bool, usize, [f64; 3], Option<bool>)>) -> PyResult<()> {
        let world = self.inner.get();
        let carry = carry
            .into_iter()
            .map(|(i, collider, j, impulse, carried)| {
                let other = if collider {
                    Partner::Collider(j)
                } else {
                    Partner::Particle(j)
                };
                let record = ContactRecord::loaded(i, other, impulse);
                ContactRecord {
                    carried: carried.unwrap_or(record.carried),
                    ..record
                }
            })
            .collect();
        world.restore_collision_carry(carry).map_err(to_py)
    }

    /// The impulse model's candidate list's build: the positions it was built at (m, N×3)
    /// and its skin (m); None before a first build.
    fn list_carry<'py>(&mut self, py: Python<'py>) -> Option<(Bound<'py, PyArray1<f64>>, f64)> {
        self.inner
            .get()
            .list_carry()
            .map(|(built_at, skin)| (PyArray1::from_vec(py, built_at), skin))
    }

    fn restore_list_carry(&mut self, built_at: Vec<f64>, skin: f64) -> PyResult<()> {
        self.inner.get().restore_list_carry(built_at, skin).map_err(to_py)
    }

    /// Sleeping's carry: each particle's calm time (s) and sleeping island (-1: awake).
    fn sleep_carry<'py>(&mut self, py: Python<'py>) -> (Bound<'py, PyArray1<f64>>, Bound<'py, PyArray1<i64>>) {
        let world = self.inner.get();
        let (calm, island) = world.sleep_carry();
        (PyArray1::from_vec(py, calm), PyArray1::from_vec(py, island))
    }

    fn restore_sleep_carry(&mut self, calm: Vec<f64>, island: Vec<i64>) -> PyResult<()> {
        self.inner.get().restore_sleep_carry(calm, island).map_err(to_py)
    }

    /// Each particle's own (restitution, friction), None where not set; empty if none has.
    fn particle_materials(&mut self) -> Vec<(Option<f64>, Option<f64>)> {
        self.inner.get().particle_materials()
    }

    /// Each particle's collision group, in the user's order.
    #[getter]
    fn groups(&mut self) -> Vec<u32> {
        self.inner.get().particle_groups()
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

    #[getter]
    fn next_id(&self) -> u64 {
        self.inner.next_id()
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

    /// The overlaps the last placement check accepted but that the collisions will push
    /// apart, as a sentence (count and deepest), once; None if there were none.
    fn take_placement_notice(&mut self) -> Option<String> {
        self.inner.take_placement_notice()
    }

    /// What the particles gave each collider over all steps (with `last`, in the last step):
    /// {"momentum": (K, 3) N·s, "angular_momentum": (K, 3) N·m·s about the origin, "work":
    /// (K,) J done by the collider on the particles, "normal" and "tangential": (K, 3) N·s,
    /// the momentum's parts along and across the contacts' normals}.
    #[pyo3(signature = (last = false))]
    fn collider_books<'py>(&self, py: Python<'py>, last: bool) -> PyResult<Bound<'py, PyDict>> {
        collide::books_dict(py, &self.inner.collider_books(last))
    }

    /// The force models' collider forces of the last step's Verlet pass, as rates (the keys
    /// of `collider_books`, in N, N·m and W), which the next step's books start from; None
    /// when none are kept (for a checkpoint).
    fn wall_force_carry<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        self.inner.wall_force_carry().map(|b| collide::books_dict(py, &b)).transpose()
    }

    /// Sets what `wall_force_carry` gave (a checkpoint's).
    fn restore_wall_force_carry(&mut self, carry: Bound<'_, PyDict>) -> PyResult<()> {
        let carry = collide::books_from(&carry)?;
        self.inner.restore_wall_force_carry(Some(carry));
        Ok(())
    }

    /// The contacts now (the impulse model's: of the last step's end), as arrays, with their
    /// points, forces and whether they slide.
    fn contacts<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let world = self.inner.get();
        let impulses = world
            .collision_params()
            .is_some_and(|p| p.model == kinema::world::ContactModel::Impulse);
        let reports = world.contact_reports().map_err(to_py)?;
        collide::contacts_dict(py, &reports, impulses)
    }

    /// Starts or stops recording begin and end of touch.
    fn record_contact_events(&mut self, on: bool) -> PyResult<()> {
        self.inner.record_contact_events(on).map_err(to_py)
    }

    /// The begin and end of touch events since the last call, taken out, as arrays.
    fn contact_events<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        collide::touch_events_dict(py, &self.inner.take_contact_events())
    }

    /// {"last": ..., "total": ...} of the collision stages, or None without collisions.
    fn collision_stats<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some((last, total)) = self.inner.collision_stats() else {
            return Ok(None);
        };
        let out = PyDict::new(py);
        out.set_item("last", collide::stats_dict(py, &last)?)?;
        out.set_item("total", collide::stats_dict(py, &total)?)?;
        Ok(Some(out))
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

    /// Copies positions, velocities and masses from the caller's arrays into the world when
    /// they differ from its own (the method caches then restart); returns whether they did.
    /// Checks every value first: nothing is changed by a bad one.
    fn sync(
        &mut self,
        x: PyReadonlyArray2<'_, f64>,
        v: PyReadonlyArray2<'_, f64>,
        m: PyReadonlyArray1<'_, f64>,
    ) -> PyResult<bool> {
        let n = self.inner.len();
        let (x, v, m) = (x.as_array(), v.as_array(), m.as_array());
        if x.shape() != [n, 3] || v.shape() != [n, 3] || m.shape() != [n] {
            return Err(PyValueError::new_err(format!(
                "positions, velocities and masses must keep their shapes ({n}, 3), ({n}, 3) and ({n},); \
                 assign new values into them instead of resizing"
            )));
        }
        let unchanged = match (x.as_slice(), v.as_slice(), m.as_slice()) {
            (Some(xs), Some(vs), Some(ms)) => self.inner.state_is(xs, vs, ms),
            _ => {
                let flat = |a: numpy::ndarray::ArrayViewD<'_, f64>| a.iter().copied().collect::<Vec<f64>>();
                let (xs, vs, ms) = (
                    flat(x.view().into_dyn()),
                    flat(v.view().into_dyn()),
                    flat(m.view().into_dyn()),
                );
                self.inner.state_is(&xs, &vs, &ms)
            }
        };
        if unchanged {
            return Ok(false);
        }
        // (a write: the user's order; the values checked by the engine's one check,
        // `kinema::particles::check_state`, nothing written if one is bad)
        let flat = |a: numpy::ndarray::ArrayViewD<'_, f64>| a.iter().copied().collect::<Vec<f64>>();
        let (xs, vs, ms) = (
            flat(x.view().into_dyn()),
            flat(v.view().into_dyn()),
            flat(m.view().into_dyn()),
        );
        self.inner.get().write_state(&xs, &vs, &ms).map_err(to_py)?;
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

    /// Writes the positions and velocities into the caller's (N, 3) arrays.
    fn read_state(&self, mut x: PyReadwriteArray2<'_, f64>, mut v: PyReadwriteArray2<'_, f64>) -> PyResult<()> {
        let n = self.inner.len();
        let (mut x, mut v) = (x.as_array_mut(), v.as_array_mut());
        if x.shape() != [n, 3] || v.shape() != [n, 3] {
            return Err(PyValueError::new_err(format!("state arrays must have shape ({n}, 3)")));
        }
        match (x.as_slice_mut(), v.as_slice_mut()) {
            (Some(xs), Some(vs)) => self.inner.read_state_into(xs, vs),
            _ => {
                let (mut xs, mut vs) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
                self.inner.read_state_into(&mut xs, &mut vs);
                x.iter_mut().zip(&xs).for_each(|(d, s)| *d = *s);
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
        let d = self.inner.diagnostics();
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
        if self.inner.has_spin() {
            out.set_item("rotational", d.rotational)?;
            out.set_item("spin_angular_momentum", d.spin.to_vec())?;
        }
        Ok(out)
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
