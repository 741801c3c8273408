//! Uniform wind: linear drag relative to moving air, F_i = b (w − v_i).
//!
//! A particle in air that moves at velocity w feels Stokes drag on its velocity relative to
//! the air, −b (v_i − w). At rest it is pushed with b w; it tends to the terminal state
//! v_i = w (plus whatever the other forces add: under gravity, v → w + m g / b). With w = 0 it
//! is the linear part of [`Drag`](super::Drag).
//!
//! An optional [`Falloff`] confines it in space: F_i = φ(x_i) b (w − v_i), the weight φ(x) in
//! [0, 1] of a sphere, tube or box (Blender's wind with a falloff shape); without one, φ = 1.

use super::falloff::Falloff;
use super::{check_buffers, EnergyClass, Force, Linearized, Properties, Rates, State};
use crate::error::{CallbackError, Error};
use crate::vec3::get;

/// Uniform wind field: F_i = b (w − v_i), N, times a falloff's weight φ(x_i) when it has one.
///
/// w = `velocity`, m/s (finite; default 0); b = `coefficient`, kg/s = N·s/m (finite, ≥ 0;
/// default 0). Not conservative (no potential energy); ∂F/∂v = −b I, ∂F/∂x = 0 (with a
/// falloff: ∂F/∂v = −φ b I, ∂F/∂x = b (w − v) ∇φᵀ).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Wind {
    /// Wind velocity w, m/s.
    pub velocity: [f64; 3],
    /// Drag coefficient b, kg/s (≥ 0).
    pub coefficient: f64,
    /// Where the wind blows: full strength where the weight is 1 (`None`: everywhere).
    pub falloff: Option<Falloff>,
}

impl Wind {
    /// Wind at `velocity` (m/s, finite) with drag coefficient `coefficient` (kg/s, finite, ≥ 0).
    pub fn new(velocity: [f64; 3], coefficient: f64) -> Result<Self, Error> {
        let wind = Wind {
            velocity,
            coefficient,
            falloff: None,
        };
        wind.check()?;
        Ok(wind)
    }

    /// The same wind confined by `falloff` (`None`: everywhere).
    pub fn with_falloff(self, falloff: Option<Falloff>) -> Self {
        Wind { falloff, ..self }
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
        self.falloff.map_or(Ok(()), |f| f.check())
    }
}

impl Force for Wind {
    fn name(&self) -> &str {
        "wind"
    }

    /// Adds b (w − v_i) to each particle's force, N (times the falloff's φ(x_i)).
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        check_buffers(self.name(), s, &[("f", f.len())])?;
        for ((fi, vi), xi) in f.chunks_exact_mut(3).zip(s.v.chunks_exact(3)).zip(s.x.chunks_exact(3)) {
            let b = match &self.falloff {
                None => self.coefficient,
                Some(fo) => fo.weight([xi[0], xi[1], xi[2]]) * self.coefficient,
            };
            for k in 0..3 {
                fi[k] += b * (self.velocity[k] - vi[k]);
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
            depends_on_position: self.falloff.is_some(),
            depends_on_velocity: true,
            internal: false,
            renumbers: true,
            per_particle: true,
        }
    }

    /// ∂F/∂v = −b I, ∂F/∂x = 0: see [`WindJacobian`]; with a falloff, [`ShapedWindJacobian`].
    fn linearize(&self, _s: &State, _definite: bool) -> Option<Box<dyn Linearized>> {
        match self.falloff {
            None => Some(Box::new(WindJacobian(self.coefficient))),
            Some(_) => Some(Box::new(ShapedWindJacobian(*self))),
        }
    }

    /// γ ≤ b · max_p w_p (∂F/∂v = −φ b I, φ ≤ 1). No position dependence without a falloff;
    /// with one, ω² ≤ max_p w_p b |w − v_p|∞ |∇φ_p|₁, the ∞-norm of the rank-one
    /// M⁻¹ b (w − v) ∇φᵀ.
    fn rates(&self, s: &State, inv_mass: &[f64]) -> Option<Rates> {
        let mut omega_squared: f64 = 0.0;
        if let Some(fo) = &self.falloff {
            for (p, w) in inv_mass.iter().enumerate() {
                if *w > 0.0 && 3 * p + 2 < s.x.len().min(s.v.len()) {
                    let (_, g) = fo.weight_and_gradient(get(s.x, p));
                    let v = get(s.v, p);
                    let rel = (0..3).fold(0.0_f64, |a, k| a.max((self.velocity[k] - v[k]).abs()));
                    omega_squared = omega_squared.max(w * self.coefficient * rel * (g[0].abs() + g[1].abs() + g[2].abs()));
                }
            }
        }
        Some(Rates {
            omega_squared,
            damping_rate: self.coefficient * inv_mass.iter().fold(0.0_f64, |a, w| a.max(*w)),
            ..Rates::default()
        })
    }
}

/// The Jacobian of a wind with a falloff, read from the positions and velocities of `s`:
/// F = φ(x) b (w − v) gives ∂F/∂x = b (w − v) ∇φᵀ and ∂F/∂v = −φ b I.
struct ShapedWindJacobian(Wind);

impl Linearized for ShapedWindJacobian {
    /// Adds b (w − v)(∇φ·dx) − φ b dv per particle.
    fn apply(&self, s: &State, dx: &[f64], dv: &[f64], out: &mut [f64]) {
        let (wind, fo) = (&self.0, self.0.falloff.as_ref().expect("a shaped wind has a falloff"));
        for (p, oi) in out.chunks_exact_mut(3).enumerate() {
            let (w, g) = fo.weight_and_gradient(get(s.x, p));
            let v = get(s.v, p);
            let along = g[0] * dx[3 * p] + g[1] * dx[3 * p + 1] + g[2] * dx[3 * p + 2];
            for k in 0..3 {
                oi[k] += wind.coefficient * ((wind.velocity[k] - v[k]) * along - w * dv[3 * p + k]);
            }
        }
    }

    /// Adds c_x b (w_k − v_k) ∂_k φ − c_v φ b per component.
    fn add_diagonal(&self, s: &State, cx: f64, cv: f64, out: &mut [f64]) {
        let (wind, fo) = (&self.0, self.0.falloff.as_ref().expect("a shaped wind has a falloff"));
        for (p, oi) in out.chunks_exact_mut(3).enumerate() {
            let (w, g) = fo.weight_and_gradient(get(s.x, p));
            let v = get(s.v, p);
            for k in 0..3 {
                oi[k] += wind.coefficient * (cx * (wind.velocity[k] - v[k]) * g[k] - cv * w);
            }
        }
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

    /// Theory: with a falloff F = φ(x) b (w − v): a sphere of linear falloff from r₀ = 1 to
    /// r₁ = 3 gives ½ of the force at distance 2, all of it at ½, none at 3.5; its Jacobian
    /// (∂F/∂x = b (w − v) ∇φᵀ, ∂F/∂v = −φ b I) matches central differences; without a falloff
    /// the wind still does not depend on the positions.
    #[test]
    fn falloff_scales_the_force() {
        use super::super::falloff::{Law, Shape};
        let fo = Falloff::new(Shape::Sphere { center: [1.0, 0.0, 0.0] }, Law::Linear, 1.0, 3.0).unwrap();
        let mut wind = Wind::new([2.0, 0.0, -1.0], 0.5).unwrap().with_falloff(Some(fo));
        let x = [3.0, 0.0, 0.0, 1.5, 0.0, 0.0, 1.0, 0.0, 3.5];
        let s = State {
            t: 0.0,
            x: &x,
            v: &[0.0; 9],
            mass: &[1.0; 3],
        };
        assert_eq!(forces(&mut wind, &s), vec![0.5, 0.0, -0.25, 1.0, 0.0, -0.5, 0.0, 0.0, 0.0]);
        assert!(wind.properties().depends_on_position && !Wind::new([1.0; 3], 1.0).unwrap().properties().depends_on_position);
        let mut rng = Rng::new(8);
        let x = rng.vec(18, -1.0, 3.0);
        let v = rng.vec(18, -2.0, 2.0);
        let s = State {
            t: 0.0,
            x: &x,
            v: &v,
            mass: &[1.0; 6],
        };
        assert_jacobian_matches_differences(&mut wind, &s, &mut rng, 1e-6, 1e-6);
    }

    #[test]
    fn bad_parameters_are_named() {
        let e = Wind::new([0.0; 3], -0.1).unwrap_err().to_string();
        assert!(e.starts_with("coefficient = -0.1 is invalid"), "{e}");
        let e = Wind::new([0.0, 0.0, f64::NAN], 1.0).unwrap_err().to_string();
        assert!(e.starts_with("velocity[2] = NaN is invalid"), "{e}");
    }
}
