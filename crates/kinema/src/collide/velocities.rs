//! The velocities a contact sees, particle by particle: stored in an array, or Verlet's
//! predictor made when asked.
//!
//! Velocity Verlet's force evaluation sees the predictor v' = v + h a (the dashpots and the
//! friction need a velocity at the drifted positions; `world/integrate.rs`). Stored, it is an
//! array of 3 values per particle that lives only through the force pass: 24 MB at 10⁶
//! particles, beside the state, the drifted positions and the accelerations. The contacts read
//! a velocity only for the pairs that touch, so [`Predictor`] makes it there from the step's
//! start, with the same operations as the drift (`ode::verlet::drift`): the same bits.

use crate::vec3;

/// The velocities of the particles, m/s, as the contacts read them.
pub trait Velocities: Sync {
    /// Particle i's velocity, m/s.
    fn at(&self, i: usize) -> [f64; 3];

    /// Asks for what [`Velocities::at`] will read of particle i to be brought into cache
    /// (`simd::prefetch`; nothing by default).
    #[inline(always)]
    fn prefetch(&self, i: usize) {
        let _ = i;
    }
}

impl Velocities for [f64] {
    #[inline(always)]
    fn at(&self, i: usize) -> [f64; 3] {
        vec3::get(self, i)
    }

    #[inline(always)]
    fn prefetch(&self, i: usize) {
        crate::simd::prefetch(&self[3 * i]);
    }
}

impl<const N: usize> Velocities for [f64; N] {
    #[inline(always)]
    fn at(&self, i: usize) -> [f64; 3] {
        vec3::get(self, i)
    }

    #[inline(always)]
    fn prefetch(&self, i: usize) {
        self[..].prefetch(i);
    }
}

impl Velocities for Vec<f64> {
    #[inline(always)]
    fn at(&self, i: usize) -> [f64; 3] {
        vec3::get(self, i)
    }

    #[inline(always)]
    fn prefetch(&self, i: usize) {
        self[..].prefetch(i);
    }
}

/// Verlet's predictor v' = v + h a of the velocities `v` (m/s) and accelerations `a` (m/s²) at
/// a step's start, over the step `h` (s), made particle by particle when asked.
#[derive(Clone, Copy)]
pub struct Predictor<'a> {
    /// Velocities at the step's start, m/s (3 per particle).
    pub v: &'a [f64],
    /// Accelerations at the step's start, m/s² (3 per particle).
    pub a: &'a [f64],
    /// The step, s.
    pub h: f64,
}

impl Velocities for Predictor<'_> {
    #[inline(always)]
    fn prefetch(&self, i: usize) {
        crate::simd::prefetch(&self.v[3 * i]);
        crate::simd::prefetch(&self.a[3 * i]);
    }

    #[inline(always)]
    fn at(&self, i: usize) -> [f64; 3] {
        let (v, a) = (vec3::get(self.v, i), vec3::get(self.a, i));
        // (`ode::verlet::drift`'s v + h a, coordinate by coordinate: the same bits)
        [v[0] + self.h * a[0], v[1] + self.h * a[1], v[2] + self.h * a[2]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_predictor_is_the_drifts_to_the_bit() {
        let v = [0.1, -2.5, 1e-300, 3.0, 0.7, -0.0];
        let a = [9.81, 1.0 / 3.0, -7.0, 1e17, -0.2, 0.0];
        let h = 1e-3 / 3.0;
        let p = Predictor { v: &v, a: &a, h };
        for i in 0..2 {
            let seen = p.at(i);
            for k in 0..3 {
                let (_, drifted) = crate::ode::verlet::drift(0.0, v[3 * i + k], a[3 * i + k], h);
                assert_eq!(seen[k].to_bits(), drifted.to_bits());
            }
        }
        assert_eq!(v[..].at(1), [3.0, 0.7, -0.0]);
    }
}
