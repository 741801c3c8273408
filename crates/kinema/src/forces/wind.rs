//! Uniform wind: linear drag relative to moving air, F_i = b (w − v_i).
//!
//! A particle in air that moves at velocity w feels Stokes drag on its velocity relative to
//! the air, −b (v_i − w). At rest it is pushed with b w; it tends to the terminal state
//! v_i = w (plus whatever the other forces add: under gravity, v → w + m g / b). With w = 0 it
//! is the linear part of [`Drag`](super::Drag).

use super::{check_buffers, EnergyClass, Force, Linearized, Properties, Rates, State};
use crate::error::{CallbackError, Error};

/// Uniform wind field: F_i = b (w − v_i), N.
///
/// w = `velocity`, m/s (finite; default 0); b = `coefficient`, kg/s = N·s/m (finite, ≥ 0;
/// default 0). Not conservative (no potential energy); ∂F/∂v = −b I, ∂F/∂x = 0.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Wind {
    /// Wind velocity w, m/s.
    pub velocity: [f64; 3],
    /// Drag coefficient b, kg/s (≥ 0).
    pub coefficient: f64,
}

impl Wind {
    /// Wind at `velocity` (m/s, finite) with drag coefficient `coefficient` (kg/s, finite, ≥ 0).
    pub fn new(velocity: [f64; 3], coefficient: f64) -> Result<Self, Error> {
        let wind = Wind { velocity, coefficient };
        wind.check()?;
        Ok(wind)
    }

    fn check(&self) -> Result<(), Error> {
        if let Some(k) = self.velocity.iter().position(|c| !c.is_finite()) {
            return Err(Error::invalid(
                format!("velocity[{k}]"),
                self.velocity[k],
                "wind velocity components must be finite (m/s)",
            ));
        }
        if !(self.coefficient.is_finite() && self.coefficient >= 0.0) {
            return Err(Error::invalid(
                "coefficient",
                self.coefficient,
                "the wind drag coefficient must be finite and >= 0 kg/s",
            ));
        }
        Ok(())
    }
}

impl Force for Wind {
    fn name(&self) -> &str {
        "wind"
    }

    /// Adds b (w − v_i) to each particle's force, N.
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        check_buffers(self.name(), s, &[("f", f.len())])?;
        for (fi, vi) in f.chunks_exact_mut(3).zip(s.v.chunks_exact(3)) {
            for k in 0..3 {
                fi[k] += self.coefficient * (self.velocity[k] - vi[k]);
            }
        }
        Ok(())
    }

    /// Re-checks w and b (the fields are public and may have changed).
    fn validate(&self, _n: usize) -> Result<(), Error> {
        self.check()
    }

    /// A source of energy (moving air pushes particles along), a function of the velocities;
    /// it holds no particle indices.
    fn properties(&self) -> Properties {
        Properties {
            energy: EnergyClass::Source,
            depends_on_position: false,
            depends_on_velocity: true,
            internal: false,
            renumbers: true,
            per_particle: true,
        }
    }

    /// ∂F/∂v = −b I, ∂F/∂x = 0: see [`WindJacobian`].
    fn linearize(&self, _s: &State, _definite: bool) -> Option<Box<dyn Linearized>> {
        Some(Box::new(WindJacobian(self.coefficient)))
    }

    /// γ ≤ b · max_p w_p (∂F/∂v = −b I). No position dependence.
    fn rates(&self, _s: &State, inv_mass: &[f64]) -> Option<Rates> {
        Some(Rates {
            damping_rate: self.coefficient * inv_mass.iter().fold(0.0_f64, |a, w| a.max(*w)),
            ..Rates::default()
        })
    }
}

/// The wind's Jacobian ∂F/∂v = −b I (b, kg/s), ∂F/∂x = 0.
struct WindJacobian(f64);

impl Linearized for WindJacobian {
    /// Adds (∂F/∂v)·dv = −b dv.
    fn apply(&self, _s: &State, _dx: &[f64], dv: &[f64], out: &mut [f64]) {
        for (o, d) in out.iter_mut().zip(dv) {
            *o -= self.0 * d;
        }
    }

    /// Adds c_v·diag(∂F/∂v) = −c_v b per component.
    fn add_diagonal(&self, _s: &State, _cx: f64, cv: f64, out: &mut [f64]) {
        out.iter_mut().for_each(|o| *o -= cv * self.0);
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::{assert_jacobian_matches_differences, forces, Rng};
    use super::*;

    /// Theory: F = b (w − v). A particle moving with the wind feels nothing; one at rest is
    /// pushed with b w; one moving against it with b (w − v).
    #[test]
    fn closed_form_relative_to_the_air() {
        let w = [2.0, 0.0, -1.0];
        let x = [0.0; 9];
        let v = [2.0, 0.0, -1.0, 0.0, 0.0, 0.0, -3.0, 1.0, 0.0];
        let s = State {
            t: 0.0,
            x: &x,
            v: &v,
            mass: &[1.0, 1.0, 5.0],
        };
        let f = forces(&mut Wind::new(w, 0.5).unwrap(), &s);
        assert_eq!(f, vec![0.0, 0.0, 0.0, 1.0, 0.0, -0.5, 2.5, -0.5, -0.5]);
    }

    /// Theory: ∂F/∂v = −b I and ∂F/∂x = 0, by central differences.
    #[test]
    fn jacobian_matches_finite_differences() {
        let mut rng = Rng::new(3);
        let x = rng.vec(12, -1.0, 1.0);
        let v = rng.vec(12, -2.0, 2.0);
        let m = rng.vec(4, 0.5, 2.0);
        let s = State {
            t: 0.0,
            x: &x,
            v: &v,
            mass: &m,
        };
        let mut wind = Wind::new([1.0, -0.5, 0.2], 0.8).unwrap();
        assert_jacobian_matches_differences(&mut wind, &s, &mut rng, 1e-6, 1e-6);
        assert!(wind.properties().depends_on_velocity && wind.potential_energy(&s).is_none());
    }

    #[test]
    fn bad_parameters_are_named() {
        let e = Wind::new([0.0; 3], -0.1).unwrap_err().to_string();
        assert!(e.starts_with("coefficient = -0.1 is invalid"), "{e}");
        let e = Wind::new([0.0, 0.0, f64::NAN], 1.0).unwrap_err().to_string();
        assert!(e.starts_with("velocity[2] = NaN is invalid"), "{e}");
    }
}
