//! What the particles gave each collider: the impulse model's books of moving and still walls.

use crate::vec3;

/// What the particles gave one collider (the impulse model's impacts and end-of-step
/// contacts): momentum, and the work the collider did on them.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ColliderBooks {
    /// Momentum the collider received, −Σ J over the impulses J it gave particles, N·s (a
    /// collider has infinite mass: this is what it would have taken up, the force it felt
    /// integrated over time).
    pub momentum: [f64; 3],
    /// Angular momentum the collider received about the world's origin, −Σ x_c × J, N·m·s
    /// (x_c the contact point on its surface).
    pub angular_momentum: [f64; 3],
    /// Work the collider's surface did on the particles, Σ J·u(x_c), J (0 for a still one:
    /// a moving wall's energy input, which the collisions' `energy_lost` books as negative
    /// loss).
    pub work: f64,
}

impl ColliderBooks {
    /// Books the impulse `j` (N·s) the collider gave a particle at the point `at` (m) of its
    /// surface moving at `u` (m/s).
    pub(crate) fn book(&mut self, at: [f64; 3], u: [f64; 3], j: [f64; 3]) {
        let torque = vec3::cross(at, j);
        for k in 0..3 {
            self.momentum[k] -= j[k];
            self.angular_momentum[k] -= torque[k];
        }
        self.work += vec3::dot(j, u);
    }
}
