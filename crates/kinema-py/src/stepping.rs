//! Running a world's steps from Python: the steps with the GIL released, in slices with
//! Ctrl-C checked between, and the engine's divergence as `kinema.SimulationDiverged`.

use kinema::error::CallbackError;
use kinema::world::UserOrder;
use kinema::Divergence;
use kinema::Error;
use pyo3::prelude::*;

use crate::errors::to_py;

pyo3::create_exception!(
    kinema,
    SimulationDiverged,
    pyo3::exceptions::PyRuntimeError,
    "A world step produced a non-finite state or runaway energy, rk45 could not finish it, or a particle moved \
     too fast for the event-driven engine to follow; the world keeps the state from before it. Attributes: \
     step, time, particle, dt, advised_dt, reason ('non-finite', 'runaway energy', 'step too small', \
     'too many sub-steps' or 'too fast')."
);

/// Engine errors of a world: divergence gets its own exception, with its facts as attributes.
pub fn world_err(e: Error) -> PyErr {
    match e {
        Error::Diverged {
            step,
            time,
            particle,
            dt,
            reason,
            advised_dt,
            ..
        } => {
            let err = SimulationDiverged::new_err(e.to_string());
            Python::attach(|py| {
                let value = err.value(py);
                let reason = match reason {
                    Divergence::NonFinite => "non-finite",
                    Divergence::StepTooSmall => "step too small",
                    Divergence::TooManySubsteps => "too many sub-steps",
                    Divergence::RunawayEnergy { .. } => "runaway energy",
                    Divergence::TooFast { .. } => "too fast",
                };
                let set = || -> PyResult<()> {
                    value.setattr("step", step)?;
                    value.setattr("time", time)?;
                    value.setattr("particle", particle)?;
                    value.setattr("dt", dt)?;
                    value.setattr("advised_dt", advised_dt)?;
                    value.setattr("reason", reason)?;
                    Ok(())
                };
                set().err().unwrap_or(err.clone_ref(py))
            })
        }
        other => to_py(other),
    }
}

/// The world's interrupt check inside a step (`World::set_interrupt`): Python's pending
/// signals, whose handler raises (Ctrl-C: `KeyboardInterrupt`); it runs them only on the main
/// thread, and takes the GIL back for it (the steps run without it).
pub fn ctrl_c() -> Result<(), CallbackError> {
    Python::attach(|py| py.check_signals()).map_err(|e| Box::new(e) as CallbackError)
}

/// How long a slice of `World.step` runs before Ctrl-C is checked.
const SLICE: std::time::Duration = std::time::Duration::from_millis(20);

/// The body of `World.step`: slices of steps in the engine's order, Ctrl-C checked between.
pub fn step_in_slices(py: Python<'_>, inner: &mut UserOrder, n: u64) -> PyResult<()> {
    let mut left = n;
    let mut slice = 1u64;
    while left > 0 {
        let k = slice.min(left);
        let world = &mut *inner;
        let start = std::time::Instant::now();
        // A slice of several short steps runs as one task on a worker of rayon's pool, where
        // the world allows it (`World::runs_in_pool`): the parallel passes of its steps then
        // start from inside the pool, instead of the calling thread handing each step's work
        // over and sleeping until it is done. The in-step Ctrl-C check finds nothing off the
        // main thread, and needs to find nothing: a slice grows past one step only after its
        // steps took under SLICE / 4 together, and Ctrl-C is checked after each slice. A slice
        // of one step (a long one) stays on the calling thread, where the check inside the
        // step sees Ctrl-C.
        let in_pool = k > 1 && world.runs_in_pool();
        py.detach(move || {
            if in_pool {
                rayon::scope(move |_| world.advance_in_engine_order(k))
            } else {
                world.advance_in_engine_order(k)
            }
        })
        .map_err(world_err)?;
        left -= k;
        py.check_signals()?;
        // the next slice: as many steps as fit in SLICE at this pace
        let took = start.elapsed().as_secs_f64();
        slice = if took < SLICE.as_secs_f64() / 4.0 {
            (2 * slice).min(1 << 24)
        } else if took > SLICE.as_secs_f64() {
            (slice / 2).max(1)
        } else {
            slice
        };
    }
    Ok(())
}
