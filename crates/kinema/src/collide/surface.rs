//! A collider's surface: its restitution, friction and velocity, and where a sphere touches it.

use super::motion::SurfaceVelocity;
use crate::error::Error;

/// A collider's own restitution and friction; `None` uses the particle's value (the world's
/// global value where particles have none). See [`crate::collide::response::MaterialTable`].
/// And the velocity of its surface: zero for a still collider, the rigid field of its motion
/// for a moving one.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Surface {
    restitution: Option<f64>,
    friction: Option<f64>,
    velocity: SurfaceVelocity,
}

impl Surface {
    /// A surface with restitution e ∈ [0, 1] and Coulomb friction coefficient μ ≥ 0 (finite),
    /// each `None` to use the particle's value.
    pub fn new(restitution: Option<f64>, friction: Option<f64>) -> Result<Self, Error> {
        if let Some(e) = restitution {
            if !(0.0..=1.0).contains(&e) {
                return Err(Error::invalid(
                    "restitution",
                    e,
                    "the coefficient of restitution must be in [0, 1]",
                ));
            }
        }
        if let Some(mu) = friction {
            if !(mu.is_finite() && mu >= 0.0) {
                return Err(Error::invalid(
                    "friction",
                    mu,
                    "the friction coefficient must be finite and >= 0",
                ));
            }
        }
        Ok(Surface {
            restitution,
            friction,
            velocity: SurfaceVelocity::default(),
        })
    }

    /// The same surface moving with `velocity`.
    pub fn with_velocity(self, velocity: SurfaceVelocity) -> Surface {
        Surface { velocity, ..self }
    }

    /// The velocity field of the surface (zero for a still collider).
    pub fn velocity(&self) -> SurfaceVelocity {
        self.velocity
    }

    /// Restitution e, if the surface sets its own.
    pub fn restitution(&self) -> Option<f64> {
        self.restitution
    }

    /// Friction coefficient μ, if the surface sets its own.
    pub fn friction(&self) -> Option<f64> {
        self.friction
    }
}

/// Where a particle touches a collider: the normal into the free side and the overlap.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Touch {
    /// Unit normal into the free side.
    pub normal: [f64; 3],
    /// Penetration depth, m (> 0 when overlapping; < 0 for a gap within the tolerance).
    pub overlap: f64,
}
