//! The constructor and the Verlet pass with positional arguments, as `world/mod.rs` still
//! calls them: each only names its arguments and calls [`ContactForce::from_params`] or
//! [`ContactForce::force_and_kick`]. Issue 16 removes them (with their
//! `too_many_arguments`) once the world's callers build the parameter structs themselves.

use super::{ContactForce, ContactForceParams, VerletKick};
use crate::collide::{Collider, Domain, Material};
use crate::error::Error;
use crate::forces::State;

impl ContactForce {
    /// [`ContactForce::from_params`] with the fields of [`ContactForceParams`] in order.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        stiffness: f64,
        damping: Option<f64>,
        global: Material,
        own: Option<Vec<Material>>,
        radius: Vec<f64>,
        inv_mass: Vec<f64>,
        colliders: Vec<Collider>,
        domain: Domain,
    ) -> Self {
        Self::from_params(ContactForceParams {
            stiffness,
            damping,
            global,
            own,
            radius,
            inv_mass,
            colliders,
            domain,
        })
    }

    /// [`ContactForce::force_and_kick`] with the fields of [`VerletKick`] in order.
    #[allow(clippy::too_many_arguments)]
    pub fn verlet_force_and_kick(
        &self,
        s: &State,
        other: Option<&[f64]>,
        inv_mass: &[f64],
        flat: bool,
        h: f64,
        v: &[f64],
        a: &mut [f64],
        v_out: &mut [f64],
    ) -> Result<Option<usize>, Error> {
        self.force_and_kick(
            s,
            VerletKick {
                other,
                inv_mass,
                flat,
                h,
                v,
                a,
                v_out,
            },
        )
    }
}
