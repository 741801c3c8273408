//! The forces of one evaluation: the world's own, in the order they were added, then, with the
//! force models (spring–dashpot, Hertz), the contact force the collide stage lends for the call
//! ([`CollideStage::contact_force`]: its model with the particles' radii and inverse masses,
//! the materials, colliders and domain where they live). The contact force comes last:
//! Verlet's fused pass adds it after the sum of the others, the order of every evaluation.

use crate::collide::contact_force::ContactForce;
use crate::collide::stage::CollideStage;
use crate::forces::Force;
use crate::particles::Particles;

/// The contact force on `particles` for one call (`None` without it).
pub(super) fn contact_force<'a>(stage: &'a Option<CollideStage>, particles: &'a Particles) -> Option<ContactForce<'a>> {
    stage
        .as_ref()?
        .contact_force(&particles.radius, &particles.inv_mass, &particles.omega, &particles.group)
}

/// `forces` and then `contact`, in the order they are summed.
pub(super) fn every_force<'a>(
    forces: &'a mut [Box<dyn Force>],
    contact: Option<&'a mut ContactForce<'_>>,
) -> Vec<&'a mut dyn Force> {
    let mut all: Vec<&'a mut dyn Force> = Vec::with_capacity(forces.len() + 1);
    all.extend(forces.iter_mut().map(|f| &mut **f as &mut dyn Force));
    if let Some(c) = contact {
        all.push(c);
    }
    all
}

/// [`every_force`] to read.
pub(super) fn every_force_ref<'a>(forces: &'a [Box<dyn Force>], contact: Option<&'a ContactForce<'_>>) -> Vec<&'a dyn Force> {
    let mut all: Vec<&'a dyn Force> = forces.iter().map(|f| &**f as &dyn Force).collect();
    if let Some(c) = contact {
        all.push(c);
    }
    all
}
