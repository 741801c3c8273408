//! What the particles gave each collider, by every contact model: the momentum and work of
//! moving and still walls, split into the contacts' normal and tangential parts (the wall's
//! pressure and shear, LIGGGHTS's wall stress).

use crate::vec3;

/// What the particles gave one collider (the impulse model's impacts and end-of-step
/// contacts; the force models' contact forces integrated over the step): momentum, and the
/// work the collider did on them.
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
    /// Of `momentum`, the part along each contact's normal, −Σ (J·n) n, N·s: divided by the
    /// time, the force that presses on the collider.
    pub normal: [f64; 3],
    /// Of `momentum`, the part across each contact's normal (friction), −Σ (J − (J·n) n),
    /// N·s: divided by the time, the shear force on the collider.
    pub tangential: [f64; 3],
}

impl ColliderBooks {
    /// Books the impulse `j` (N·s) the collider gave a particle at the point `at` (m) of its
    /// surface moving at `u` (m/s), across the contact's unit normal `n`.
    pub(crate) fn book(&mut self, at: [f64; 3], u: [f64; 3], j: [f64; 3], n: [f64; 3]) {
        let torque = vec3::cross(at, j);
        let along = vec3::scale(vec3::dot(j, n), n);
        for k in 0..3 {
            self.momentum[k] -= j[k];
            self.angular_momentum[k] -= torque[k];
            self.normal[k] -= along[k];
            self.tangential[k] -= j[k] - along[k];
        }
        self.work += vec3::dot(j, u);
    }

    /// Adds `other`'s figures, each scaled by `s`.
    pub(crate) fn add_scaled(&mut self, s: f64, other: &ColliderBooks) {
        for k in 0..3 {
            self.momentum[k] += s * other.momentum[k];
            self.angular_momentum[k] += s * other.angular_momentum[k];
            self.normal[k] += s * other.normal[k];
            self.tangential[k] += s * other.tangential[k];
        }
        self.work += s * other.work;
    }
}
