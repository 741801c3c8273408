//! Drag in still air: F_i = −b₁ v_i − b₂ |v_i| v_i.
//!
//! The linear (Stokes) term dominates at low Reynolds number, b₁ = 6π η r for a sphere of
//! radius r in a fluid of viscosity η; the quadratic (Newton) term at high Reynolds number,
//! b₂ = ½ ρ C_d A for a body of frontal area A and drag coefficient C_d in a fluid of
//! density ρ. Both oppose the velocity, so the force only removes energy: its power is
//! F·v = −b₁ |v|² − b₂ |v|³ ≤ 0. The coefficients are the same for every particle.

use super::{check_buffers, EnergyClass, Force, Linearized, Properties, Rates, State};
use crate::error::{CallbackError, Error};

/// Linear plus quadratic drag: F_i = −b₁ v_i − b₂ |v_i| v_i, N.
///
/// b₁ = `linear`, N·s/m = kg/s; b₂ = `quadratic`, N·s²/m² = kg/m; both finite and ≥ 0
/// (default 0). Depends on velocity only; not conservative (no potential energy).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Drag {
    /// Linear coefficient b₁, kg/s (≥ 0, finite).
    pub linear: f64,
    /// Quadratic coefficient b₂, kg/m (≥ 0, finite).
    pub quadratic: f64,
}

impl Drag {
    /// Drag with linear coefficient `linear` (kg/s) and quadratic coefficient `quadratic`
    /// (kg/m); each must be finite and ≥ 0.
    pub fn new(linear: f64, quadratic: f64) -> Result<Self, Error> {
        let drag = Drag { linear, quadratic };
        drag.check()?;
        Ok(drag)
    }

    fn check(&self) -> Result<(), Error> {
        if !(self.linear.is_finite() && self.linear >= 0.0) {
            return Err(Error::invalid(
                "linear",
                self.linear,
                "the linear drag coefficient must be finite and >= 0 kg/s",
            ));
        }
        if !(self.quadratic.is_finite() && self.quadratic >= 0.0) {
            return Err(Error::invalid(
                "quadratic",
                self.quadratic,
                "the quadratic drag coefficient must be finite and >= 0 kg/m",
            ));
        }
        Ok(())
    }
}

impl Force for Drag {
    fn name(&self) -> &str {
        "drag"
    }

    /// Adds −(b₁ + b₂ |v_i|) v_i to each particle's force, N.
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        check_buffers(self.name(), s, &[("f", f.len())])?;
        for (fi, vi) in f.chunks_exact_mut(3).zip(s.v.chunks_exact(3)) {
            let speed = (vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]).sqrt();
            let b = self.linear + self.quadratic * speed;
            for k in 0..3 {
                fi[k] -= b * vi[k];
            }
        }
        Ok(())
    }

    /// Re-checks the coefficients (the fields are public and may have changed).
    fn validate(&self, _n: usize) -> Result<(), Error> {
        self.check()
    }

    /// Dissipative (its power −b₁|v|² − b₂|v|³ is never positive), a function of the
    /// velocities only; it holds no particle indices.
    fn properties(&self) -> Properties {
        Properties {
            energy: EnergyClass::Dissipative,
            depends_on_position: false,
            depends_on_velocity: true,
            internal: false,
            renumbers: true,
            per_particle: true,
        }
    }

    /// Nothing to prepare: the products read the velocities of `s` (see [`DragJacobian`]).
    fn linearize(&self, _s: &State, _definite: bool) -> Option<Box<dyn Linearized>> {
        Some(Box::new(DragJacobian {
            linear: self.linear,
            quadratic: self.quadratic,
        }))
    }

    /// γ ≤ max_p w_p (b₁ + 2 b₂ |v_p|): the eigenvalues of ∂F/∂v are −(b₁ + b₂ s) across v
    /// and −(b₁ + 2 b₂ s) along it. No position dependence.
    fn rates(&self, s: &State, inv_mass: &[f64]) -> Option<Rates> {
        let mut damping_rate: f64 = 0.0;
        for (vi, w) in s.v.chunks_exact(3).zip(inv_mass) {
            let speed = (vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]).sqrt();
            damping_rate = damping_rate.max(w * (self.linear + 2.0 * self.quadratic * speed));
        }
        Some(Rates {
            damping_rate,
            ..Rates::default()
        })
    }
}

/// Drag's Jacobian: ∂F/∂x = 0 and ∂F/∂v per particle (below), read from the velocities.
struct DragJacobian {
    linear: f64,
    quadratic: f64,
}

impl Linearized for DragJacobian {
    /// Adds c_v·diag(∂F/∂v) = −c_v (b₁ + b₂ (s + v_k²/s)) per component (see
    /// [`Linearized::apply`] below for ∂F/∂v).
    fn add_diagonal(&self, s: &State, _cx: f64, cv: f64, out: &mut [f64]) {
        for (oi, vi) in out.chunks_exact_mut(3).zip(s.v.chunks_exact(3)) {
            let speed = (vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]).sqrt();
            for k in 0..3 {
                let along = if speed > 0.0 { vi[k] * vi[k] / speed } else { 0.0 };
                oi[k] -= cv * (self.linear + self.quadratic * (speed + along));
            }
        }
    }

    /// Adds (∂F/∂v)·dv; ∂F/∂x = 0.
    ///
    /// With s = |v|, ∂(s v)/∂v = s I + v (∂s/∂v)ᵀ = s I + v vᵀ/s, so per particle
    ///
    /// ```text
    ///   ∂F/∂v = −b₁ I − b₂ (s I + v vᵀ / s)
    ///   (∂F/∂v)·dv = −(b₁ + b₂ s) dv − b₂ (v·dv / s) v
    /// ```
    ///
    /// At v = 0 the quadratic term is O(|v|²) and its derivative is 0: the product is −b₁ dv
    /// (the v vᵀ/s term is bounded by s and is dropped, not divided by zero).
    fn apply(&self, s: &State, _dx: &[f64], dv: &[f64], out: &mut [f64]) {
        for ((oi, vi), di) in out.chunks_exact_mut(3).zip(s.v.chunks_exact(3)).zip(dv.chunks_exact(3)) {
            let speed = (vi[0] * vi[0] + vi[1] * vi[1] + vi[2] * vi[2]).sqrt();
            let along = if speed > 0.0 {
                (vi[0] * di[0] + vi[1] * di[1] + vi[2] * di[2]) / speed
            } else {
                0.0
            };
            let b = self.linear + self.quadratic * speed;
            for k in 0..3 {
                oi[k] -= b * di[k] + self.quadratic * along * vi[k];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::{assert_jacobian_matches_differences, forces, product, Rng};
    use super::*;

    /// Theory: for v = (3, 4, 0) m/s, |v| = 5, F = −(b₁ + 5 b₂) v; with b₁ = 0.5, b₂ = 0.1:
    /// F = −1.0 · v = (−3, −4, 0). A particle at rest feels nothing.
    #[test]
    fn closed_form_on_known_velocities() {
        let x = [0.0; 6];
        let v = [3.0, 4.0, 0.0, 0.0, 0.0, 0.0];
        let m = [1.0, 2.0];
        let s = State {
            t: 0.0,
            x: &x,
            v: &v,
            mass: &m,
        };
        let f = forces(&mut Drag::new(0.5, 0.1).unwrap(), &s);
        let expect = [-3.0, -4.0, 0.0, 0.0, 0.0, 0.0];
        for (a, b) in f.iter().zip(expect) {
            assert!((a - b).abs() < 1e-14, "{f:?}");
        }
        // Power is −b₁|v|² − b₂|v|³ = −12.5 − 12.5 = −25 W.
        let power: f64 = f.iter().zip(&v).map(|(f, v)| f * v).sum();
        assert!((power + 25.0).abs() < 1e-12, "{power}");
    }

    /// Theory: ∂F/∂v = −b₁ I − b₂ (|v| I + v vᵀ/|v|), checked by central differences on random
    /// velocities; ∂F/∂x = 0.
    #[test]
    fn jacobian_matches_finite_differences() {
        let mut rng = Rng::new(7);
        let n = 6;
        let x = rng.vec(3 * n, -1.0, 1.0);
        let v = rng.vec(3 * n, -2.0, 2.0);
        let m = rng.vec(n, 0.5, 2.0);
        let s = State {
            t: 0.0,
            x: &x,
            v: &v,
            mass: &m,
        };
        assert_jacobian_matches_differences(&mut Drag::new(0.3, 0.7).unwrap(), &s, &mut rng, 1e-6, 1e-6);
        // The quadratic term alone, so that a wrong v vᵀ/|v| term cannot hide behind b₁.
        assert_jacobian_matches_differences(&mut Drag::new(0.0, 1.0).unwrap(), &s, &mut rng, 1e-6, 1e-6);
    }

    /// Theory: at v = 0, ∂F/∂v = −b₁ I exactly (no 0/0).
    #[test]
    fn jacobian_at_rest_is_finite() {
        let x = [0.0; 3];
        let v = [0.0; 3];
        let s = State {
            t: 0.0,
            x: &x,
            v: &v,
            mass: &[1.0],
        };
        let dv = [1.0, -2.0, 0.5];
        let mut out = [0.0; 3];
        assert!(product(&Drag::new(0.25, 3.0).unwrap(), &s, &[0.0; 3], &dv, &mut out, false));
        assert_eq!(out, [-0.25, 0.5, -0.125]);
    }

    #[test]
    fn bad_coefficients_are_named() {
        let e = Drag::new(-1.0, 0.0).unwrap_err().to_string();
        assert!(e.starts_with("linear = -1 is invalid"), "{e}");
        let e = Drag::new(0.0, f64::NAN).unwrap_err().to_string();
        assert!(e.starts_with("quadratic = NaN is invalid"), "{e}");
        let e = Drag {
            linear: f64::INFINITY,
            quadratic: 0.0,
        }
        .validate(1)
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("linear = inf is invalid"), "{e}");
        assert!(Drag::new(0.0, 0.0).unwrap().properties().depends_on_velocity);
        assert!(Drag::default()
            .potential_energy(&State {
                t: 0.0,
                x: &[],
                v: &[],
                mass: &[]
            })
            .is_none());
    }
}
