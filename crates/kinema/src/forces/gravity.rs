//! Uniform gravity: F_i = m_i g.
//!
//! The field is the same everywhere, so its potential is linear in the positions,
//! U = −Σ m_i g·x_i, and its Jacobian is zero. Pinned particles feel it too: they keep their
//! mass, and the world keeps them still through their inverse mass 0, not by skipping them
//! here (so that the reaction a support must provide can be read off the force array).

use super::{check_buffers, EnergyClass, Force, Linearized, Properties, Rates, State, ZeroJacobian};
use crate::error::{CallbackError, Error};
use rayon::prelude::*;

/// Standard gravity near the Earth's surface, m/s² (the rounded value 9.81 used throughout
/// the engine's examples; the CGPM standard is 9.80665).
pub const EARTH_GRAVITY: f64 = 9.81;

/// Uniform gravitational field: F_i = m_i g, N, for every particle i.
///
/// Potential energy U = −Σ m_i g·x_i, J (zero at the origin). In 3D z is up, so
/// [`Gravity::earth`] points along −z; a 2D scene lives in the xy-plane and wants
/// `Gravity::new([0.0, -EARTH_GRAVITY, 0.0])`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gravity {
    /// Acceleration of gravity g, m/s² (finite; default (0, 0, −9.81)).
    pub g: [f64; 3],
}

impl Gravity {
    /// Gravity `g`, m/s²; each component must be finite.
    pub fn new(g: [f64; 3]) -> Result<Self, Error> {
        let gravity = Gravity { g };
        gravity.check()?;
        Ok(gravity)
    }

    /// Earth's gravity for a z-up 3D scene: g = (0, 0, −9.81) m/s².
    pub fn earth() -> Self {
        Gravity {
            g: [0.0, 0.0, -EARTH_GRAVITY],
        }
    }

    fn check(&self) -> Result<(), Error> {
        match self.g.iter().position(|c| !c.is_finite()) {
            Some(k) => Err(Error::invalid(
                format!("g[{k}]"),
                self.g[k],
                "gravity components must be finite (m/s²)",
            )),
            None => Ok(()),
        }
    }
}

impl Default for Gravity {
    /// [`Gravity::earth`].
    fn default() -> Self {
        Gravity::earth()
    }
}

impl Force for Gravity {
    fn name(&self) -> &str {
        "gravity"
    }

    /// g, the same for every particle of any mass (F = m g).
    fn uniform_acceleration(&self) -> Option<[f64; 3]> {
        Some(self.g)
    }

    /// Adds m_i g to each particle's force, N.
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        check_buffers(self.name(), s, &[("f", f.len())])?;
        let g = self.g;
        let add = |f: &mut [f64], mass: &[f64]| {
            for (fi, m) in f.chunks_exact_mut(3).zip(mass) {
                for (fk, gk) in fi.iter_mut().zip(g) {
                    *fk += m * gk;
                }
            }
        };
        // on all threads for many particles (the same numbers: each is its own sum)
        let c = super::PARALLEL_CHUNK;
        if s.len() > c {
            f.par_chunks_mut(3 * c).zip(s.mass.par_chunks(c)).for_each(|(f, m)| add(f, m));
        } else {
            add(f, s.mass);
        }
        Ok(())
    }

    /// Re-checks g (the field is public and may have changed since construction).
    fn validate(&self, _n: usize) -> Result<(), Error> {
        self.check()
    }

    /// U = −Σ m_i g·x_i, J: −∂U/∂x_i = m_i g is the force.
    fn potential_energy(&self, s: &State) -> Option<f64> {
        let u =
            s.x.chunks_exact(3)
                .zip(s.mass)
                .map(|(xi, m)| -m * (self.g[0] * xi[0] + self.g[1] * xi[1] + self.g[2] * xi[2]));
        Some(u.sum())
    }

    /// Conservative (its work is −ΔU), uniform and constant; it holds no particle indices.
    fn properties(&self) -> Properties {
        Properties {
            energy: EnergyClass::Conservative,
            depends_on_position: false,
            depends_on_velocity: false,
            internal: false,
            renumbers: true,
            per_particle: true,
        }
    }

    /// The field is uniform and constant: ∂F/∂x = ∂F/∂v = 0, nothing to add.
    fn linearize(&self, _s: &State, _definite: bool) -> Option<Box<dyn Linearized>> {
        Some(Box::new(ZeroJacobian))
    }

    /// A uniform constant field adds no rates.
    fn rates(&self, _s: &State, _inv_mass: &[f64]) -> Option<Rates> {
        Some(Rates::default())
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::{assert_force_is_minus_gradient, assert_jacobian_matches_differences, forces, Rng};
    use super::*;

    /// Two particles, one of them meant to be pinned (its mass is kept either way).
    fn two() -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        (
            vec![0.0, 1.0, 2.0, -3.0, 0.5, 4.0],
            vec![1.0, 0.0, 0.0, 0.0, -2.0, 0.0],
            vec![2.0, 0.5],
        )
    }

    /// Theory: F_i = m_i g, for every particle including pinned ones (which keep their mass).
    #[test]
    fn force_is_mass_times_g() {
        let (x, v, m) = two();
        let s = State {
            t: 0.0,
            x: &x,
            v: &v,
            mass: &m,
        };
        let f = forces(&mut Gravity::earth(), &s);
        assert_eq!(f, vec![0.0, 0.0, -2.0 * 9.81, 0.0, 0.0, -0.5 * 9.81]);
        let f = forces(&mut Gravity::new([1.0, -2.0, 0.0]).unwrap(), &s);
        assert_eq!(f, vec![2.0, -4.0, 0.0, 0.5, -1.0, 0.0]);
    }

    /// Theory: U = −Σ m g·x. Closed form for the two particles (m g·x = 2·(−9.81)·2 +
    /// 0.5·(−9.81)·4 = −58.86), and F = −∇U by central differences.
    #[test]
    fn potential_is_minus_m_g_dot_x_and_its_gradient_is_the_force() {
        let (x, v, m) = two();
        let s = State {
            t: 0.0,
            x: &x,
            v: &v,
            mass: &m,
        };
        let u = Gravity::earth().potential_energy(&s).unwrap();
        assert!((u - 58.86).abs() < 1e-12, "{u}");
        assert_force_is_minus_gradient(&mut Gravity::new([0.3, -1.0, -9.81]).unwrap(), &s, 1e-6, 1e-6);
    }

    /// Theory: the Jacobian of a uniform field is zero; central differences of F must vanish.
    #[test]
    fn jacobian_is_zero() {
        let (x, v, m) = two();
        let s = State {
            t: 0.0,
            x: &x,
            v: &v,
            mass: &m,
        };
        assert_jacobian_matches_differences(&mut Gravity::earth(), &s, &mut Rng::new(1), 1e-6, 1e-6);
        let props = Gravity::earth().properties();
        assert!(!props.depends_on_velocity && !props.internal);
    }

    #[test]
    fn non_finite_g_is_named() {
        let e = Gravity::new([0.0, f64::NAN, 0.0]).unwrap_err().to_string();
        assert!(e.starts_with("g[1] = NaN is invalid"), "{e}");
        let g = Gravity {
            g: [f64::INFINITY, 0.0, 0.0],
        };
        let e = g.validate(3).unwrap_err().to_string();
        assert!(e.starts_with("g[0] = inf is invalid"), "{e}");
    }

    #[test]
    fn mismatched_buffers_are_errors_not_panics() {
        let (x, v, m) = two();
        let s = State {
            t: 0.0,
            x: &x,
            v: &v,
            mass: &m,
        };
        let mut f = vec![0.0; 5];
        let e = Gravity::earth().accumulate(&s, &mut f).unwrap_err().to_string();
        assert!(e.starts_with("gravity: f = 5 values is invalid"), "{e}");
    }
}
