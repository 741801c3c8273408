//! What a birth or a death keeps of velocity Verlet's cache: the acceleration a_n at the
//! current state, for the particles that stay, as Rapier's change flags keep what did not
//! change. Without it the next step evaluates every force once more before its drift.
//!
//! A change of particles leaves the others' forces as they were when
//!
//! - every force but the contact force acts on each particle alone
//!   ([`Properties::per_particle`](crate::forces::Properties::per_particle): gravity, drag,
//!   wind, an attractor; not springs, whose ends may go, nor a Python force), and
//! - no contact joins what stays to what changes: no survivor touches a particle that dies,
//!   no newborn touches anything (the contact force's neighbour list, kept across the change,
//!   says so exactly).
//!
//! Then the survivors' a_n are theirs before the change, and a newborn's is the sum of the
//! per-particle forces on it alone, divided by its mass: the same operations, in the same
//! order, as the force evaluation of a fresh start ([`super::dynamics::Dynamics::accel`]),
//! since a contact force that touches nothing adds nothing. Otherwise the cache is dropped,
//! as before, and the next step starts afresh.

use super::dynamics::newton;
use super::forces::contact_force;
use super::integrate::{VerletBuffers, WorldStepper};
use super::World;
use crate::error::Error;
use crate::forces::State;

impl World {
    /// Whether Verlet's acceleration is kept for `n` particles and every force (the contact
    /// force aside) is a per-particle one.
    fn acceleration_carries(&self, n: usize) -> bool {
        let Some(WorldStepper::Verlet(b)) = &self.stepper else {
            return false;
        };
        let fields = self.forces.iter().all(|f| f.properties().per_particle);
        b.fresh && b.a.len() == 3 * n && fields
    }

    /// Takes Verlet's acceleration for `n` particles if it carries over a change.
    fn take_acceleration(&mut self, n: usize) -> Option<Vec<f64>> {
        if !self.acceleration_carries(n) {
            return None;
        }
        match &mut self.stepper {
            Some(WorldStepper::Verlet(b)) => Some(std::mem::take(&mut b.a)),
            _ => None,
        }
    }

    /// The survivors' acceleration before a removal (`keep[i]`: particle i stays; the user's
    /// order), if the removal leaves it right (see the module doc).
    pub(super) fn acceleration_after_removal(&mut self, keep: &[bool]) -> Option<Vec<f64>> {
        if !self.acceleration_carries(keep.len()) {
            return None;
        }
        if let Some(contact) = contact_force(&self.collide_stage, &self.particles) {
            if contact.touches_across(&self.particles.x, keep) != Some(false) {
                return None;
            }
        }
        let a = self.take_acceleration(keep.len())?;
        let kept = a
            .chunks_exact(3)
            .zip(keep)
            .filter(|(_, &k)| k)
            .flat_map(|(a, _)| a.iter().copied());
        Some(kept.collect())
    }

    /// The acceleration of the `n` particles there are before a birth, to be extended to the
    /// newborns after it ([`World::acceleration_after_birth`]); the cache is left without it.
    pub(super) fn acceleration_before_birth(&mut self, n: usize) -> Option<Vec<f64>> {
        self.take_acceleration(n)
    }

    /// Verlet's cache again after particles `start..` were born, from the acceleration before
    /// (`before`, 3 per old particle): the newborns' own from the per-particle forces, when
    /// no newborn touches anything; the cache stays dropped otherwise. `admitted`: whether
    /// the contact force kept its neighbour list across the birth.
    pub(super) fn acceleration_after_birth(
        &mut self,
        before: Option<Vec<f64>>,
        start: usize,
        admitted: bool,
    ) -> Result<(), Error> {
        let Some(mut a) = before else {
            return Ok(());
        };
        let p = &self.particles;
        if let Some(contact) = contact_force(&self.collide_stage, p) {
            if !admitted || contact.newborns_touch(&p.x, &p.v, start) {
                return Ok(());
            }
        }
        // F on the newborns alone (every force here is a per-particle one), then Newton's
        // a = F/m as the force evaluation has it
        let s = State {
            t: self.time,
            x: &p.x[3 * start..],
            v: &p.v[3 * start..],
            mass: &p.mass[start..],
        };
        let mut f = vec![0.0; s.x.len()];
        for force in self.forces.iter_mut() {
            force.accumulate(&s, &mut f)?;
        }
        let old = a.len();
        a.resize(old + f.len(), 0.0);
        newton(&f, &p.inv_mass[start..], self.params.dim, &mut a[old..]);
        self.keep_acceleration(Some(a));
        Ok(())
    }

    /// Makes `a` (3 per particle, at the current state) Verlet's kept acceleration.
    pub(super) fn keep_acceleration(&mut self, a: Option<Vec<f64>>) {
        if let Some(a) = a.filter(|a| a.len() == 3 * self.particles.len()) {
            self.stepper = Some(WorldStepper::Verlet(Box::new(VerletBuffers {
                a,
                a_next: Vec::new(),
                omega_next: Vec::new(),
                alpha_next: Vec::new(),
                fresh: true,
            })));
        }
    }
}
