//! Point attractor: softened inverse-square pull toward a fixed point, F_i = −μ m_i r / s³.
//!
//! With r = x_i − p and s = √(|r|² + ε²), the potential per particle is U = −μ m / s. Its
//! gradient is ∂U/∂x = μ m r / s³ (since ∂s/∂x = r/s), so F = −∇U = −μ m r / s³. For ε = 0
//! this is Newton's gravity of a fixed mass M with μ = G M (|F| = μ m / |r|²). The softening
//! ε > 0 (Plummer's) caps the force near the point: |F| peaks at 2μm/(3√3 ε²), for |r| = ε/√2,
//! and falls to zero at the point, so close passes need no tiny steps.

use super::{check_buffers, EnergyClass, Force, Linearized, Properties, Rates, State};
use crate::error::{CallbackError, Error};

/// Softened inverse-square attraction toward a fixed point: F_i = −μ m_i r / (|r|² + ε²)^{3/2},
/// N, with r = x_i − `point`.
///
/// `point` p, m (finite); `strength` μ = G M, m³/s² (finite, ≥ 0); `softening` ε, m (finite,
/// ≥ 0; 0 is the exact inverse-square law). Potential U = −Σ μ m_i / √(|r|² + ε²), J.
///
/// Without softening the force is singular at the point itself: a particle exactly there gets
/// no force (no direction to pull in) and contributes U = −∞, its Jacobian nothing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Attractor {
    /// The attracting point p, m.
    pub point: [f64; 3],
    /// μ = G M, m³/s² (≥ 0).
    pub strength: f64,
    /// Softening length ε, m (≥ 0).
    pub softening: f64,
}

impl Attractor {
    /// An attractor at `point` (m) of strength `strength` = G M (m³/s², ≥ 0) softened over
    /// `softening` (m, ≥ 0); all finite.
    pub fn new(point: [f64; 3], strength: f64, softening: f64) -> Result<Self, Error> {
        let a = Attractor {
            point,
            strength,
            softening,
        };
        a.check()?;
        Ok(a)
    }

    fn check(&self) -> Result<(), Error> {
        if let Some(k) = self.point.iter().position(|c| !c.is_finite()) {
            return Err(Error::invalid(
                format!("point[{k}]"),
                self.point[k],
                "the attractor's coordinates must be finite (m)",
            ));
        }
        if !(self.strength.is_finite() && self.strength >= 0.0) {
            return Err(Error::invalid(
                "strength",
                self.strength,
                "the attractor's strength G·M must be finite and >= 0 m³/s²",
            ));
        }
        if !(self.softening.is_finite() && self.softening >= 0.0) {
            return Err(Error::invalid(
                "softening",
                self.softening,
                "the softening length must be finite and >= 0 m",
            ));
        }
        Ok(())
    }

    /// r = x − p and s² = |r|² + ε² for one particle.
    fn offset(&self, xi: &[f64]) -> ([f64; 3], f64) {
        let r = [xi[0] - self.point[0], xi[1] - self.point[1], xi[2] - self.point[2]];
        (r, r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + self.softening * self.softening)
    }
}

impl Force for Attractor {
    fn name(&self) -> &str {
        "attractor"
    }

    /// Adds −μ m_i r / s³ to each particle's force, N.
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        check_buffers(self.name(), s, &[("f", f.len())])?;
        for ((fi, xi), m) in f.chunks_exact_mut(3).zip(s.x.chunks_exact(3)).zip(s.mass) {
            let (r, s2) = self.offset(xi);
            if s2 == 0.0 {
                continue; // at an unsoftened point: no direction, see the type's doc
            }
            let c = self.strength * m / (s2 * s2.sqrt());
            for k in 0..3 {
                fi[k] -= c * r[k];
            }
        }
        Ok(())
    }

    /// Re-checks the parameters (the fields are public and may have changed).
    fn validate(&self, _n: usize) -> Result<(), Error> {
        self.check()
    }

    /// U = −Σ μ m_i / s_i, J (−∞ for a particle exactly at an unsoftened point).
    fn potential_energy(&self, s: &State) -> Option<f64> {
        let u =
            s.x.chunks_exact(3)
                .zip(s.mass)
                .map(|(xi, m)| -self.strength * m / self.offset(xi).1.sqrt());
        Some(u.sum())
    }

    /// Conservative (its work is −ΔU), a function of the positions; it holds no particle
    /// indices.
    fn properties(&self) -> Properties {
        Properties {
            energy: EnergyClass::Conservative,
            depends_on_position: true,
            depends_on_velocity: false,
            internal: false,
            renumbers: true,
            per_particle: true,
        }
    }

    /// Nothing to prepare: the products read the positions of `s` (see
    /// [`AttractorJacobian`]).
    fn linearize(&self, _s: &State, _definite: bool) -> Option<Box<dyn Linearized>> {
        Some(Box::new(AttractorJacobian(*self)))
    }

    /// ω² ≤ max over movable particles of 2μ / s³: the eigenvalues of M⁻¹∂F/∂x (see
    /// [`Linearized::apply`] below) are μ (3|r|²/s² − 1)/s³ ≤ 2μ/s³ along r and −μ/s³
    /// across it. No velocity dependence.
    fn rates(&self, s: &State, inv_mass: &[f64]) -> Option<Rates> {
        let mut omega_squared: f64 = 0.0;
        for (xi, w) in s.x.chunks_exact(3).zip(inv_mass) {
            if *w > 0.0 {
                let s2 = self.offset(xi).1;
                omega_squared = omega_squared.max(2.0 * self.strength / (s2 * s2.sqrt()));
            }
        }
        Some(Rates {
            omega_squared,
            ..Rates::default()
        })
    }
}

/// The attractor's Jacobian: ∂F/∂x per particle (below), read from the positions; ∂F/∂v = 0.
/// It gives no diagonal (the default): the implicit solve's preconditioner leaves it out.
struct AttractorJacobian(Attractor);

impl Linearized for AttractorJacobian {
    /// Adds (∂F/∂x)·dx; ∂F/∂v = 0.
    ///
    /// Differentiating F = −μ m r s⁻³ with ∂r/∂x = I and ∂s⁻³/∂x = −3 s⁻⁵ r:
    ///
    /// ```text
    ///   ∂F/∂x = −μ m [ I / s³ − 3 r rᵀ / s⁵ ]
    ///   (∂F/∂x)·dx = −μ m [ dx − 3 (r·dx / s²) r ] / s³
    /// ```
    ///
    /// Radially (dx ∥ r, ε = 0) this is +2μm/|r|³: the tidal stretching; across, −μm/|r|³.
    fn apply(&self, s: &State, dx: &[f64], _dv: &[f64], out: &mut [f64]) {
        let a = &self.0;
        for (((oi, xi), di), m) in out
            .chunks_exact_mut(3)
            .zip(s.x.chunks_exact(3))
            .zip(dx.chunks_exact(3))
            .zip(s.mass)
        {
            let (r, s2) = a.offset(xi);
            if s2 == 0.0 {
                continue;
            }
            let c = a.strength * m / (s2 * s2.sqrt());
            let along = 3.0 * (r[0] * di[0] + r[1] * di[1] + r[2] * di[2]) / s2;
            for k in 0..3 {
                oi[k] -= c * (di[k] - along * r[k]);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::testing::{assert_force_is_minus_gradient, assert_jacobian_matches_differences, forces, product, Rng};
    use super::*;

    /// Theory: Newton's law. A 2 kg particle 3 m above an unsoftened attractor of μ = 18 m³/s²
    /// is pulled down with μ m / d² = 4 N; U = −μ m / d = −12 J. With ε = 4 m the distance in
    /// the law becomes s = √(9 + 16) = 5 m: |F| = μ m d / s³ = 108/125 N, U = −36/5 J.
    #[test]
    fn closed_form_at_a_known_distance() {
        let p = [1.0, -1.0, 0.5];
        let x = [1.0, -1.0, 3.5];
        let s = State {
            t: 0.0,
            x: &x,
            v: &[0.0; 3],
            mass: &[2.0],
        };
        let mut a = Attractor::new(p, 18.0, 0.0).unwrap();
        let f = forces(&mut a, &s);
        assert_eq!(f, vec![0.0, 0.0, -4.0]);
        assert!((a.potential_energy(&s).unwrap() + 12.0).abs() < 1e-12);
        let mut a = Attractor::new(p, 18.0, 4.0).unwrap();
        let f = forces(&mut a, &s);
        assert!(f[0] == 0.0 && f[1] == 0.0 && (f[2] + 108.0 / 125.0).abs() < 1e-14, "{f:?}");
        assert!((a.potential_energy(&s).unwrap() + 36.0 / 5.0).abs() < 1e-12);
    }

    /// Theory: F = −∇U and ∂F/∂x = −μ m [I/s³ − 3 r rᵀ/s⁵], by central differences, with and
    /// without softening, on particles scattered around the point.
    #[test]
    fn gradient_and_jacobian_match_finite_differences() {
        let mut rng = Rng::new(11);
        let n = 7;
        let x = rng.vec(3 * n, -2.0, 2.0);
        let v = rng.vec(3 * n, -1.0, 1.0);
        let m = rng.vec(n, 0.5, 3.0);
        let s = State {
            t: 0.0,
            x: &x,
            v: &v,
            mass: &m,
        };
        for eps in [0.0, 0.3] {
            let mut a = Attractor::new([0.1, 0.2, -0.1], 5.0, eps).unwrap();
            assert_force_is_minus_gradient(&mut a, &s, 1e-6, 1e-6);
            assert_jacobian_matches_differences(&mut a, &s, &mut rng, 1e-6, 1e-6);
        }
    }

    /// At the point itself: softened, the force is exactly 0 and U finite (−μ m/ε);
    /// unsoftened, the force is 0 by convention (no NaN) and U = −∞.
    #[test]
    fn at_the_point_nothing_is_nan() {
        let x = [0.0; 3];
        let s = State {
            t: 0.0,
            x: &x,
            v: &[0.0; 3],
            mass: &[1.0],
        };
        for (eps, u) in [(0.5, -2.0), (0.0, f64::NEG_INFINITY)] {
            let mut a = Attractor::new([0.0; 3], 1.0, eps).unwrap();
            assert_eq!(forces(&mut a, &s), vec![0.0; 3]);
            assert_eq!(a.potential_energy(&s).unwrap(), u);
            let mut out = [0.0; 3];
            assert!(product(&a, &s, &[1.0, 2.0, 3.0], &[0.0; 3], &mut out, false));
            assert!(out.iter().all(|o| o.is_finite()), "{out:?}");
        }
    }

    #[test]
    fn bad_parameters_are_named() {
        let e = Attractor::new([0.0; 3], -1.0, 0.0).unwrap_err().to_string();
        assert!(e.starts_with("strength = -1 is invalid"), "{e}");
        let e = Attractor::new([0.0; 3], 1.0, f64::NAN).unwrap_err().to_string();
        assert!(e.starts_with("softening = NaN is invalid"), "{e}");
        let e = Attractor::new([0.0, f64::INFINITY, 0.0], 1.0, 0.0).unwrap_err().to_string();
        assert!(e.starts_with("point[1] = inf is invalid"), "{e}");
    }
}
