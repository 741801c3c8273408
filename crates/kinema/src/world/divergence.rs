//! The checks that refuse a step: a non-finite state, runaway energy (see [`World::step`]),
//! a state beyond the collision geometry; and the error a refused step returns.

use rayon::prelude::*;

use super::forces::{contact_force, every_force_ref};
use super::World;
use crate::error::{Divergence, Error};
use crate::forces::State;
use crate::limits::GEOMETRY_LIMIT;

/// The energy may grow by this many times its reference scale before a step counts as a
/// runaway (see [`World::step`]).
pub const RUNAWAY_FACTOR: f64 = 1e3;

/// The runaway-energy check runs at every this many steps (steps 10, 20, ...), not at every
/// step: the energy needs a pass over the particles and, with contact forces, over
/// the contacts, which would cost as much as a force evaluation per step. A runaway grows
/// over many steps, and a step that overflows is refused at once by the non-finite check.
pub const RUNAWAY_CHECK_EVERY: u64 = 10;

/// Particles per chunk of the check's kinetic energy sum (fixed: the sum's bits do not
/// depend on the number of threads).
const KINETIC_CHUNK: usize = 4096;

/// The reference of the runaway-energy check (see [`World::step`]).
#[derive(Debug, Clone, Copy)]
pub(super) struct EnergyWatch {
    /// Kinetic plus potential energy at the reference state, J.
    pub(super) energy: f64,
    /// Kinetic energy plus the magnitudes of the potential energies there, J.
    pub(super) scale: f64,
}

impl World {
    /// The runaway-energy check of [`World::step`] on the integrated state.
    pub(super) fn check_runaway(&mut self) -> Result<(), Error> {
        let Some(watch) = self.watch else {
            return Ok(());
        };
        let (energy, scale) = self.energy_and_scale(&self.x_next, &self.v_next);
        if energy - watch.energy > RUNAWAY_FACTOR * watch.scale + 0.5 * scale {
            let fastest = self.fastest(&self.v_next);
            let reason = Divergence::RunawayEnergy {
                energy,
                reference: watch.energy,
                scale: watch.scale,
            };
            return Err(self.diverged(reason, fastest));
        }
        Ok(())
    }

    /// Mechanical energy (kinetic plus every potential, J) at (x, v), and its scale: kinetic
    /// plus the magnitudes of the potentials.
    pub(super) fn energy_and_scale(&self, x: &[f64], v: &[f64]) -> (f64, f64) {
        let p = &self.particles;
        // Σ ½ m |v|² over the movable particles: each chunk of a fixed size summed on its own
        // thread, the chunks' sums added in order (the same bits for any number of threads)
        let kinetic: f64 = v
            .par_chunks(3 * KINETIC_CHUNK)
            .zip(p.mass.par_chunks(KINETIC_CHUNK))
            .zip(p.inv_mass.par_chunks(KINETIC_CHUNK))
            .map(|((v, mass), inv_mass)| {
                v.chunks_exact(3)
                    .zip(mass)
                    .zip(inv_mass)
                    .filter(|(_, w)| **w > 0.0)
                    .map(|((vi, m), _)| 0.5 * m * (vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]))
                    .sum::<f64>()
            })
            .collect::<Vec<f64>>()
            .into_iter()
            .sum();
        let s = State {
            t: self.time,
            x,
            v,
            mass: &p.mass,
        };
        let (mut energy, mut scale) = (kinetic, kinetic);
        let contact = contact_force(&self.collide_stage, p);
        for f in every_force_ref(&self.forces, contact.as_ref()) {
            if let Some(u) = f.potential_energy(&s) {
                energy += u;
                scale += u.abs();
            }
        }
        (energy, scale)
    }

    /// Whether a position or velocity is so large (> 10¹⁵⁰, m or m/s) that its square, or a
    /// sum of them, overflows: the collision geometry cannot be computed for such a state.
    pub(super) fn beyond_geometry(x: &[f64], v: &[f64]) -> bool {
        x.iter().chain(v).any(|c| !(c.abs() <= GEOMETRY_LIMIT))
    }

    /// The movable particle with the largest speed in `v`.
    pub(super) fn fastest(&self, v: &[f64]) -> Option<usize> {
        v.chunks_exact(3)
            .map(|vi| vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2])
            .enumerate()
            .filter(|(i, _)| self.particles.inv_mass[*i] > 0.0)
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    }

    /// The error of a refused step, with the advisor's step at the kept state.
    pub(super) fn diverged(&mut self, reason: Divergence, particle: Option<usize>) -> Error {
        self.stepper = None;
        let particle = particle.map(|i| self.user_of().map_or(i, |user_of| user_of[i] as usize));
        let method = self.params.method.clone();
        let advised_dt = self.stable_step(&method).ok().filter(|h| h.is_finite());
        let verlet_only = super::forces::contact_force(&self.collide_stage, &self.particles).is_some_and(|c| c.has_memory());
        Error::Diverged {
            step: self.steps + 1,
            time: self.time,
            particle,
            dt: self.step_length(),
            reason,
            advised_dt,
            verlet_only,
        }
    }
}
