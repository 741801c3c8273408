//! The world's collision settings: turning collisions on, the contact model (and the
//! spring–dashpot contact force it puts among the forces), the particles' own materials,
//! colliders, periodic axes, and what the collision stages found (contacts, their books).

use super::collisions::CollisionStage;
use super::contact_force::{ContactForce, ContactForceParams};
use super::{order, CollisionParams, CollisionStats, ContactModel, World};
use crate::collide::{Collider, Contact, Periodic};
use crate::error::Error;
use std::cell::RefCell;
use std::rc::Rc;

impl World {
    /// Turns collisions on (or changes their settings): stages 2–4 of every step with the
    /// impulse model, a contact force in stage 1 with the spring–dashpot model.
    pub fn set_collisions(&mut self, params: CollisionParams) -> Result<(), Error> {
        match &mut self.collisions {
            Some(stage) => stage.set_params(params)?,
            None => {
                let mut stage = CollisionStage::new(params, self.params.dim)?;
                stage.impulse.interrupt = self.interrupt;
                self.collisions = Some(stage);
            }
        }
        self.rebuild_contact_force()
    }

    /// Makes the spring–dashpot contact force match the collision settings, colliders and
    /// particles (added to the forces, replaced, or removed).
    pub(super) fn rebuild_contact_force(&mut self) -> Result<(), Error> {
        self.contact_dirty = false;
        if let Some(stage) = &mut self.collisions {
            stage.forget_list(); // the impulse model's list: colliders, domain or particles changed
        }
        let wanted = match self.collisions.as_ref().map(|c| c.params.model) {
            Some(ContactModel::SpringDashpot { stiffness, damping }) => Some((stiffness, damping)),
            _ => None,
        };
        match (wanted, self.contact_force) {
            (None, None) => return Ok(()),
            (None, Some(k)) => {
                self.forces.remove(k);
                self.contact_force = None;
                self.contact = None;
            }
            (Some((stiffness, damping)), index) => {
                let stage = self.collisions.as_ref().expect("collisions are on");
                let (global, own) = stage.materials_parts();
                let p = &self.particles;
                let contact = Rc::new(RefCell::new(ContactForce::from_params(ContactForceParams {
                    stiffness,
                    damping,
                    global,
                    own,
                    radius: p.radius.clone(),
                    inv_mass: p.inv_mass.clone(),
                    colliders: stage.colliders.clone(),
                    domain: stage.domain,
                })));
                let force = Box::new(order::SharedContact(contact.clone()));
                self.contact = Some(contact);
                match index {
                    Some(k) => self.forces[k] = force,
                    None => {
                        self.forces.push(force);
                        self.contact_force = Some(self.forces.len() - 1);
                    }
                }
            }
        }
        self.reset_caches();
        Ok(())
    }

    /// Gives particles `start..start + len` their own restitution e ∈ [0, 1] and friction μ ≥ 0
    /// (`None` keeps the global value of [`CollisionParams`]); `restitution` and `friction`
    /// have one entry per particle. A pair combines its two values by Box2D's rule
    /// (e = max, μ = √(μ_i μ_j), [`crate::collide::Material::combine`]); a collider's own
    /// values override the particle's. Turns collisions on if they are off.
    pub fn set_particle_materials(
        &mut self,
        start: usize,
        restitution: &[Option<f64>],
        friction: &[Option<f64>],
    ) -> Result<(), Error> {
        let n = self.particles.len();
        if restitution.len() != friction.len() || start + restitution.len() > n {
            return Err(Error::invalid(
                "restitution",
                format!("{} values from particle {start}", restitution.len()),
                format!(
                    "one value per particle, with as many frictions ({}), within the {n} particles",
                    friction.len()
                ),
            ));
        }
        for (k, (e, m)) in restitution.iter().zip(friction).enumerate() {
            // Each value alone must make a valid material.
            crate::collide::Material::new(e.unwrap_or(0.0), m.unwrap_or(0.0)).map_err(|err| match err {
                Error::InvalidParameter {
                    parameter,
                    value,
                    allowed,
                } => Error::InvalidParameter {
                    parameter: format!("{parameter}[{}]", start + k),
                    value,
                    allowed,
                },
                other => other,
            })?;
        }
        if self.collisions.is_none() {
            self.set_collisions(CollisionParams::default())?;
        }
        let stage = self.collisions.as_mut().expect("collisions are on");
        stage.own.resize(self.particles.len(), (None, None));
        for (k, (e, m)) in restitution.iter().zip(friction).enumerate() {
            stage.own[start + k] = (*e, *m);
        }
        stage.refresh_materials()?;
        self.rebuild_contact_force()
    }

    /// Each particle's own restitution and friction (`None`: the world's value); empty when
    /// no particle has its own.
    pub fn particle_materials(&self) -> Vec<(Option<f64>, Option<f64>)> {
        self.collisions.as_ref().map(|c| c.own.clone()).unwrap_or_default()
    }

    /// The collision settings, when collisions are on.
    pub fn collision_params(&self) -> Option<CollisionParams> {
        self.collisions.as_ref().map(|c| c.params)
    }

    /// Adds a static collider and returns its index; turns collisions on with the default
    /// settings if they are off.
    pub fn add_collider(&mut self, collider: impl Into<Collider>) -> Result<usize, Error> {
        let collider = collider.into();
        collider.check_dim(self.params.dim)?;
        if self.collisions.is_none() {
            self.set_collisions(CollisionParams::default())?;
        }
        let stage = self.collisions.as_mut().expect("collisions are on");
        stage.colliders.push(collider);
        let index = stage.colliders.len() - 1;
        self.rebuild_contact_force()?;
        Ok(index)
    }

    /// The colliders, in the order they were added.
    pub fn colliders(&self) -> &[Collider] {
        self.collisions.as_ref().map_or(&[], |c| &c.colliders)
    }

    /// Makes the axes with `axes[k]` true periodic, with the cell of the world's box collider
    /// (its walls along those axes then vanish: a particle leaving one side comes back on the
    /// other). All false makes space open again.
    pub fn set_periodic(&mut self, axes: [bool; 3]) -> Result<(), Error> {
        if self.collisions.is_none() {
            self.set_collisions(CollisionParams::default())?;
        }
        let stage = self.collisions.as_mut().expect("collisions are on");
        if !axes.iter().any(|a| *a) {
            stage.set_periodic(None)?;
            return self.rebuild_contact_force();
        }
        if self.params.dim == 2 && axes[2] {
            return Err(Error::invalid(
                "periodic",
                format!("{axes:?}"),
                "a 2D world has no periodic z axis",
            ));
        }
        let Some((lo, hi)) = stage.colliders.iter().find_map(|c| match c {
            Collider::Box(b) => Some((b.lo(), b.hi())),
            _ => None,
        }) else {
            return Err(Error::invalid(
                "periodic",
                format!("{axes:?}"),
                "periodic axes need a box collider (kinema.Box) whose sides give the periodic cell; add one first",
            ));
        };
        stage.set_periodic(Some(Periodic::new(lo, hi, axes)?))?;
        if let Some(p) = stage.domain.periodic_box() {
            p.wrap_positions(&mut self.particles.x);
        }
        self.rebuild_contact_force()?;
        self.reset_caches();
        Ok(())
    }

    /// The periodic axes (all false for open space).
    pub fn periodic(&self) -> [bool; 3] {
        self.collisions
            .as_ref()
            .and_then(|c| c.domain.periodic_box().map(|p| p.axes()))
            .unwrap_or([false; 3])
    }

    /// The contacts found at the end of the last step, as detected: `overlap` before it was
    /// removed and `u_n` before the end-of-step impulses (impacts found inside the step by
    /// continuous detection were already resolved). Empty with the spring–dashpot model,
    /// whose contacts live inside the force evaluations.
    pub fn contacts(&self) -> &[Contact] {
        self.collisions.as_ref().map_or(&[], |c| &c.impulse.detected)
    }

    /// What the collision stages did in the last step, and summed over all steps; `None`
    /// without collisions.
    pub fn collision_stats(&self) -> Option<(CollisionStats, CollisionStats)> {
        self.collisions.as_ref().map(|c| (c.last, c.total))
    }
}
