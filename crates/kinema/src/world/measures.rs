//! What a world measures of itself without stepping: energies and momenta, accelerations,
//! the stable-step advisor's rates, work counters and the time spent in each stage.

use super::dynamics::Dynamics;
use super::forces::{contact_force, every_force, every_force_ref};
use super::{advisor, Rates, StageTimes, World, WorldStepper};
use crate::collide::impulse::ImpulseStage;
use crate::diagnostics::{Diagnostics, StateCopy};
use crate::error::Error;
use crate::forces::State;
use crate::ode::stepper::Stats;
use crate::ode::system::SecondOrderSystem;
use crate::ode::Integrator;

impl World {
    /// Work counters of all steps so far (force evaluations in `nfev`).
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// How many times the particles were sorted along space inside the engine (see
    /// [`World::advance`]); 0 where the world keeps the user's order.
    pub fn sorts(&self) -> u64 {
        self.sorts
    }

    /// Wall-clock time spent in each stage of the steps so far.
    pub fn stage_times(&self) -> StageTimes {
        let mut times = self.times;
        if let Some(stage) = &self.collide_stage {
            times.detect = stage.times.detect;
            times.respond = stage.times.respond;
            times.distribute = stage.times.distribute;
            for (k, stage_time) in stage.times.stages.iter().enumerate() {
                times.impulse[k] = (ImpulseStage::ALL[k].name(), *stage_time);
            }
        }
        times
    }

    /// Energies and momenta now.
    pub fn diagnostics(&self) -> Diagnostics {
        self.diagnostics_copying(None)
    }

    /// [`World::diagnostics`], the same bits, with the positions (m) and velocities (m/s)
    /// written into `x` and `v` (3 per particle) in the user's order on the way: one pass over
    /// the state for a frame of `World.run` (`UserOrder::advance_in_engine_order_measured`).
    /// Panics unless `x` and `v` hold 3 N values each.
    pub(super) fn diagnostics_and_state(&self, x: &mut [f64], v: &mut [f64]) -> Diagnostics {
        let copy = match self.user_of() {
            Some(user_of) => StateCopy::placed(x, v, user_of),
            None => StateCopy::new(x, v),
        };
        self.diagnostics_copying(Some(copy))
    }

    fn diagnostics_copying(&self, copy: Option<StateCopy<'_>>) -> Diagnostics {
        let p = &self.particles;
        let contact = contact_force(&self.collide_stage, p);
        let d = Diagnostics::measure_copying(
            &State {
                t: self.time,
                x: &p.x,
                v: &p.v,
                mass: &p.mass,
            },
            &every_force_ref(&self.forces, contact.as_ref()),
            copy,
        );
        if p.has_spin() {
            d.with_spin(&p.omega, &p.inertia)
        } else {
            d
        }
    }

    /// The accelerations a = F/m now, m/s² (3 per particle).
    pub fn accelerations(&mut self) -> Result<Vec<f64>, Error> {
        self.check_pending_placement()?;
        let p = &self.particles;
        let mut contact = contact_force(&self.collide_stage, p);
        let mut forces = every_force(&mut self.forces, contact.as_mut());
        let mut dynamics = Dynamics::new(&mut forces, p, self.params.dim, &mut self.force);
        let mut a = vec![0.0; p.x.len()];
        dynamics.accel(self.time, &p.x, &p.v, &mut a)?;
        Ok(a)
    }

    /// The stable-step advisor's rates at the current state: the highest natural frequency of
    /// the linearised forces, its damping ratio and the largest damping rate (see [`Rates`]).
    pub fn rates(&mut self) -> Result<Rates, Error> {
        self.check_pending_placement()?;
        let p = &self.particles;
        let s = State {
            t: self.time,
            x: &p.x,
            v: &p.v,
            mass: &p.mass,
        };
        let mut contact = contact_force(&self.collide_stage, p);
        let mut forces = every_force(&mut self.forces, contact.as_mut());
        Ok(advisor::estimate(&mut forces, &s, &p.inv_mass, self.params.dim)?)
    }

    /// The largest stable time step (s) of `method` at the current state, by the advisor
    /// ([`Rates::max_step`]); infinite when no step is too large.
    pub fn stable_step(&mut self, method: &Integrator) -> Result<f64, Error> {
        Ok(self.rates()?.max_step(method))
    }

    /// The conjugate-gradient solve of the last implicit_euler step; `None` for the other
    /// methods.
    pub fn linear_solve(&self) -> Option<LinearSolve> {
        match &self.stepper {
            Some(WorldStepper::Implicit(bw)) => Some(LinearSolve {
                iterations: bw.iterations,
                converged: bw.converged,
            }),
            _ => None,
        }
    }
}

/// How the last implicit step's linear system was solved (see [`World::linear_solve`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LinearSolve {
    /// Conjugate-gradient iterations.
    pub iterations: usize,
    /// Whether they met [`CG_TOLERANCE`](super::CG_TOLERANCE) within
    /// [`CG_MAX_ITERATIONS`](super::CG_MAX_ITERATIONS).
    pub converged: bool,
}

impl World {
    /// Each particle's share of the contacts' virial and of the kinetic tensor now, N·m
    /// (Pa·m³; 9 per particle, row-major 3 × 3): ½ Σ_j (x_i − x_j) ⊗ F_ij over its touching
    /// partners (the force models' contact forces, tangential part included; colliders left
    /// out), plus m_i v_i ⊗ v_i with `kinetic`. Summed over the particles and divided by the
    /// volume it is the pressure tensor; LAMMPS's `compute stress/atom` is its negative.
    /// The impulse model has no forces to share: an error that says so.
    pub fn particle_stress(&mut self, kinetic: bool) -> Result<Vec<f64>, Error> {
        self.check_pending_placement()?;
        let p = &self.particles;
        let mut out = vec![0.0; 9 * p.len()];
        match self.collide_stage.as_ref().map(|c| c.params.model) {
            Some(crate::collide::stage::ContactModel::Impulse) => {
                return Err(Error::invalid(
                    "model",
                    "'impulse'",
                    "a per-particle stress needs contact forces: the force models ('spring_dashpot', 'hertz'); the impulse model's collisions are impulses (their virial is collision_stats()['virial'])",
                ))
            }
            Some(_) => {
                let s = State {
                    t: self.time,
                    x: &p.x,
                    v: &p.v,
                    mass: &p.mass,
                };
                if let Some(contact) = contact_force(&self.collide_stage, p) {
                    contact.particle_virial(&s, &mut out)?;
                }
            }
            None => {}
        }
        if kinetic {
            for i in 0..p.len() {
                let v = crate::vec3::get(&p.v, i);
                for r in 0..3 {
                    for k in 0..3 {
                        out[9 * i + 3 * r + k] += p.mass[i] * v[r] * v[k];
                    }
                }
            }
        }
        Ok(out)
    }
}
