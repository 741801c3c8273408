//! What a world holds between steps: adding and removing particles and forces, and the caches
//! that changing them drops.

use super::forces::contact_force;
use super::World;
use crate::error::Error;
use crate::forces::Force;
use crate::particles::{check_state, Particles};

impl World {
    /// Adds particles (see [`Particles::add`]); in 2D every z and z velocity must be 0.
    pub fn add_particles(
        &mut self,
        x: &[f64],
        v: &[f64],
        mass: &[f64],
        radius: &[f64],
        pinned: &[bool],
    ) -> Result<std::ops::Range<usize>, Error> {
        self.add_particles_in_groups(x, v, mass, radius, pinned, None)
    }

    /// [`World::add_particles`] with each newborn's collision group (`group`, one per particle,
    /// 0..32, `collide/groups.rs`; `None`: group 0), checked before anything is added. The
    /// newborns are placed and listed in their groups from the start.
    pub fn add_particles_in_groups(
        &mut self,
        x: &[f64],
        v: &[f64],
        mass: &[f64],
        radius: &[f64],
        pinned: &[bool],
        group: Option<&[u32]>,
    ) -> Result<std::ops::Range<usize>, Error> {
        if let Some(g) = group {
            check_groups(g, mass.len())?;
        }
        if self.params.dim == 2 {
            // (z = 0 here; `Particles::add` checks the rest of the values by the same rule)
            check_state(["position", "velocity", "mass"], x, v, mass, Some(2))?;
        }
        let range = self.particles.add(x, v, mass, radius, pinned)?;
        self.membership += 1;
        if let Some(g) = group.filter(|g| g.iter().any(|&g| g != 0)) {
            let p = &mut self.particles;
            p.group.resize(p.len(), 0);
            for (k, &g) in g.iter().enumerate() {
                p.group[range.start + k] = g as u8;
            }
        }
        if !self.deaths.time.is_empty() {
            self.deaths.time.resize(self.particles.len(), f64::INFINITY); // (live until set)
        }
        for f in &self.forces {
            f.validate(self.particles.len())?;
        }
        // The state changed size; the others' contacts (their warm start, the islands asleep)
        // stay: their numbers did not change, and a newborn wakes what it touches. So do the
        // contact force's neighbour list (the newborns' pairs added) and, where the
        // newborns touch nothing, Verlet's acceleration (`carry.rs`).
        let kept = self.collide_stage.as_mut().map(|stage| stage.take_contacts());
        let a = self.acceleration_before_birth(range.start);
        self.reset_caches();
        self.check_placement_from(range.start);
        if let Some(stage) = &mut self.collide_stage {
            if !stage.own.is_empty() {
                stage.own.resize(self.particles.len(), (None, None));
            }
            stage.refresh_materials()?;
        }
        if let (Some(stage), Some(kept)) = (&mut self.collide_stage, kept) {
            stage.keep_contacts(kept, self.particles.len());
        }
        let admitted =
            contact_force(&self.collide_stage, &self.particles).is_some_and(|c| c.admit_newborns(&self.particles.x, range.start));
        self.acceleration_after_birth(a, range.start, admitted)?;
        Ok(range)
    }

    /// Removes the particles at the given indices (the user's order; repeats allowed); the
    /// others keep their order, their ids and their state. A removed particle takes with it
    /// what the forces hold for it (springs ending on it, [`Force::reindex`]) and its
    /// own collision materials; velocity Verlet keeps the survivors' acceleration where the
    /// removal leaves it right (`carry.rs`), the other methods' caches start again; the impulse model's contacts between survivors keep their
    /// warm start (every island wakes), and the contact force's neighbour list their
    /// pairs. Between steps only: the time, the step
    /// count and the collision books go on.
    pub fn remove_particles(&mut self, indices: &[usize]) -> Result<(), Error> {
        let n = self.particles.len();
        if let Some(k) = indices.iter().position(|&i| i >= n) {
            return Err(Error::invalid(
                format!("index[{k}]"),
                indices[k],
                format!("indices of particles must be < {n}, the number of particles"),
            ));
        }
        if indices.is_empty() {
            return Ok(());
        }
        self.restore_user_order();
        let mut keep = vec![true; n];
        for &i in indices {
            keep[i] = false;
        }
        // Verlet's acceleration for the survivors, where the removal leaves it right (`carry.rs`)
        let a = self.acceleration_after_removal(&keep);
        let recording = self.collide_stage.as_ref().is_some_and(|s| s.records_touches());
        let ids_before = if recording { self.particles.id.clone() } else { Vec::new() };
        let new_of_old = self.particles.retain(&keep);
        self.membership += 1;
        if let Some(stage) = &mut self.collide_stage {
            // the touches of the removed end now (`collide/touch.rs`)
            stage.renumber_touches(&new_of_old, self.time, &ids_before);
        }
        // The survivors' contacts keep their warm start (renumbered), as Rapier's change
        // flags keep the contacts of what did not change.
        let kept = self
            .collide_stage
            .as_mut()
            .map(|stage| stage.take_contacts_renumbered(&new_of_old));
        for v in [&mut self.x_next, &mut self.v_next] {
            crate::particles::retain_rows(v, 3, &keep);
        }
        crate::particles::retain_rows(&mut self.deaths.time, 1, &keep);
        for f in &mut self.forces {
            f.reindex(&new_of_old);
        }
        if let Some(stage) = &mut self.collide_stage {
            crate::particles::retain_rows(&mut stage.own, 1, &keep);
            stage.refresh_materials()?;
        }
        self.reset_caches();
        if self.placement_from.is_some() {
            self.placement_from = Some(0); // (the pending newcomers were renumbered)
        }
        if let (Some(stage), Some(kept)) = (&mut self.collide_stage, kept) {
            stage.keep_contacts(kept, self.particles.len());
        }
        // and the contact force's neighbour list keeps the survivors' pairs
        if let Some(model) = self.force_model() {
            model.retain_survivors(&new_of_old);
        }
        self.keep_acceleration(a);
        Ok(())
    }

    /// Writes the whole state back (the user's order): positions `x` (m) and velocities `v`
    /// (m/s), 3 per particle, and masses (kg), checked first by [`check_state`] (nothing is
    /// written if a value is bad). Pinned particles stay at rest and immovable (their
    /// velocity is written as 0, their mass kept as given with no inverse). The method caches
    /// start again, as after [`World::particles_mut`].
    pub fn write_state(&mut self, x: &[f64], v: &[f64], mass: &[f64]) -> Result<(), Error> {
        let n = self.particles.len();
        for (name, len, per) in [
            ("positions", x.len(), 3),
            ("velocities", v.len(), 3),
            ("masses", mass.len(), 1),
        ] {
            if len != per * n {
                return Err(Error::invalid(
                    name,
                    format!("{len} values"),
                    format!("{per} per particle ({n} particles)"),
                ));
            }
        }
        check_state(["positions", "velocities", "masses"], x, v, mass, Some(self.params.dim))?;
        let p = self.particles_mut();
        p.x.copy_from_slice(x);
        for (k, (dst, src)) in p.v.iter_mut().zip(v).enumerate() {
            *dst = if p.inv_mass[k / 3] == 0.0 { 0.0 } else { *src }; // pinned particles stay at rest
        }
        for (i, mi) in mass.iter().enumerate() {
            p.mass[i] = *mi;
            if p.inv_mass[i] != 0.0 {
                p.inv_mass[i] = 1.0 / mi;
            }
        }
        Ok(())
    }

    /// Adds a force, checked against the current particles.
    pub fn add_force(&mut self, force: Box<dyn Force>) -> Result<(), Error> {
        force.validate(self.particles.len())?;
        self.unknown_force |= force.properties() == crate::forces::Properties::UNKNOWN;
        self.forces.push(force);
        self.reset_caches();
        Ok(())
    }

    /// The particles (read only; change them through the world's methods).
    pub fn particles(&self) -> &Particles {
        &self.particles
    }

    /// Mutable particles: after changing positions or velocities the method caches are
    /// dropped, so the next step starts afresh.
    pub fn particles_mut(&mut self) -> &mut Particles {
        self.reset_caches();
        if self.steps == 0 {
            // (placed by hand before the first step; later writes are the user's dynamics)
            self.check_placement_from(0);
        }
        // (radii may change: the contact force list starts over)
        if let Some(model) = self.force_model() {
            model.forget_list();
        }
        &mut self.particles
    }

    /// Asks for the placement check of particles `from` on before the next step.
    pub(super) fn check_placement_from(&mut self, from: usize) {
        self.placement_from = Some(self.placement_from.map_or(from, |f| f.min(from)));
    }

    /// Drops what depends on the state: the method's caches and the energy reference.
    pub(super) fn reset_caches(&mut self) {
        self.stepper = None;
        self.watch = None;
        if let Some(stage) = &mut self.collide_stage {
            stage.forget_list();
        }
    }

    /// Turns spin on or off. With spin every particle, those there now and those added later,
    /// has an angular velocity (rad/s; 0 to start) and a moment of inertia, by default a
    /// solid sphere's 2/5 m r² in 3D and a disc's 1/2 m r² in 2D (`set_particle_spin` sets
    /// others); the impulse model's impulses act at the contact point and turn the particles
    /// (`collide/spin.rs`), and the diagnostics count the rotation. Without spin (the
    /// default) particles are points with mass: nothing of the above exists or is computed,
    /// and every result is what it was before spin existed, bit for bit.
    pub fn set_spin(&mut self, on: bool) {
        let factor = match (on, self.params.dim) {
            (false, _) => 0.0,
            (true, 2) => 0.5,
            (true, _) => 0.4,
        };
        self.particles.enable_spin(factor);
    }

    /// Whether the particles have spin ([`World::set_spin`]).
    pub fn has_spin(&self) -> bool {
        self.particles.has_spin()
    }

    /// Sets the angular velocities (rad/s, 3 per particle) and moments of inertia (kg·m², one
    /// per particle) of the particles `range` (the user's order), where given
    /// ([`Particles::set_spin`]); needs spin.
    pub fn set_particle_spin(
        &mut self,
        range: std::ops::Range<usize>,
        omega: Option<&[f64]>,
        inertia: Option<&[f64]>,
    ) -> Result<(), Error> {
        if range.end > self.particles.len() {
            return Err(Error::invalid(
                "range",
                format!("{range:?}"),
                format!("particles 0..{}", self.particles.len()),
            ));
        }
        self.restore_user_order();
        self.particles.set_spin(range.clone(), omega, inertia, self.params.dim)?;
        if let (Some(_), Some(stage)) = (omega, &mut self.collide_stage) {
            // a write to the state: a sleeper's island wakes (asleep it would ignore it)
            stage.wake_particles(range);
        }
        Ok(())
    }

    /// Sets the orientations of particles `range` (unit quaternions (w, x, y, z), 4 per
    /// particle; each is normalised, and must be finite and not zero). Needs spin.
    pub fn set_orientations(&mut self, range: std::ops::Range<usize>, q: &[f64]) -> Result<(), Error> {
        if !self.particles.has_spin() {
            return Err(Error::invalid(
                "orientations",
                "given",
                "a world with spin (spin=True) turns its particles; without spin they have no orientation",
            ));
        }
        if range.end > self.particles.len() || q.len() != 4 * range.len() {
            return Err(Error::invalid(
                "orientations",
                format!("{} values for particles {range:?}", q.len()),
                format!("4 per particle (w, x, y, z), of particles 0..{}", self.particles.len()),
            ));
        }
        for (k, c) in q.chunks_exact(4).enumerate() {
            let len = c.iter().map(|a| a * a).sum::<f64>().sqrt();
            if !(len.is_finite() && len > 0.0) {
                return Err(Error::invalid(
                    format!("orientations[{k}]"),
                    format!("{c:?}"),
                    "a finite quaternion (w, x, y, z) other than 0 (it is normalised)",
                ));
            }
        }
        self.restore_user_order();
        for (k, c) in q.chunks_exact(4).enumerate() {
            let len = c.iter().map(|a| a * a).sum::<f64>().sqrt();
            let p = range.start + k;
            for (q, a) in self.particles.orientation[4 * p..4 * p + 4].iter_mut().zip(c) {
                *q = a / len;
            }
        }
        Ok(())
    }
}

/// Refuses a group list of another length than `n` or with a group outside 0..32; the error
/// names the first.
pub(super) fn check_groups(group: &[u32], n: usize) -> Result<(), Error> {
    if group.len() != n {
        return Err(Error::invalid(
            "group",
            format!("{} values", group.len()),
            format!("one collision group per particle ({n})"),
        ));
    }
    for (k, &g) in group.iter().enumerate() {
        crate::collide::groups::check_group(&format!("group[{k}]"), g as u64)?;
    }
    Ok(())
}
