//! `World`'s checkpoint methods: the clock and ids, the collision books, and what the engine
//! carries from step to step (the integrator's, the impulse model's contacts and list, sleep,
//! spin, the contacts' memory, the colliders' forces), each read and restored
//! (`kinema::world::checkpoint`), for `kinema.checkpoint`.

use kinema::collide::{ContactRecord, Partner};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::to_py;
use crate::reports;

use super::*;

#[pymethods]
impl PyWorld {
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
        let (total, last) = (reports::stats_from(&total)?, reports::stats_from(&last)?);
        world.restore_collision_stats(total, last);
        Ok(())
    }

    /// A checkpoint's collider books: `total` and `last`, dicts of arrays as `collider_books`
    /// gives them (one row per collider).
    fn restore_collider_books(&mut self, total: Bound<'_, PyDict>, last: Bound<'_, PyDict>) -> PyResult<()> {
        let (total, last) = (reports::books_from(&total)?, reports::books_from(&last)?);
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

    #[getter]
    fn next_id(&self) -> u64 {
        self.inner.next_id()
    }

    /// The force models' collider forces of the last step's Verlet pass, as rates (the keys
    /// of `collider_books`, in N, N·m and W), which the next step's books start from; None
    /// when none are kept (for a checkpoint).
    fn wall_force_carry<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        self.inner.wall_force_carry().map(|b| reports::books_dict(py, &b)).transpose()
    }

    /// Sets what `wall_force_carry` gave (a checkpoint's).
    fn restore_wall_force_carry(&mut self, carry: Bound<'_, PyDict>) -> PyResult<()> {
        let carry = reports::books_from(&carry)?;
        self.inner.restore_wall_force_carry(Some(carry));
        Ok(())
    }
}
