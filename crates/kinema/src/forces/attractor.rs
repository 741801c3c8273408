//! Point attractor: softened inverse-square pull toward a fixed point, F_i = −μ m_i r / s³.
//!
//! With r = x_i − p and s = √(|r|² + ε²), the potential per particle is U = −μ m / s. Its
//! gradient is ∂U/∂x = μ m r / s³ (since ∂s/∂x = r/s), so F = −∇U = −μ m r / s³. For ε = 0
//! this is Newton's gravity of a fixed mass M with μ = G M (|F| = μ m / |r|²). The softening
//! ε > 0 (Plummer's) caps the force near the point: |F| peaks at 2μm/(3√3 ε²), for |r| = ε/√2,
//! and falls to zero at the point, so close passes need no tiny steps.
//!
//! An optional [`Falloff`] shapes the pull in space: F_i = φ(x_i) F_a(x_i), the weight φ in
//! [0, 1] of a sphere, tube or box (Blender's force fields' falloff). A shaped attractor is
//! no longer the gradient of a potential in general (φ F_a has a curl where ∇φ is not along
//! r), so it has no potential energy and counts as a force that may add energy.

use super::falloff::Falloff;
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
    /// Where it pulls: F = φ(x) F_a (`None`: everywhere, φ = 1, conservative).
    pub falloff: Option<Falloff>,
}

impl Attractor {
    /// An attractor at `point` (m) of strength `strength` = G M (m³/s², ≥ 0) softened over
    /// `softening` (m, ≥ 0); all finite.
    pub fn new(point: [f64; 3], strength: f64, softening: f64) -> Result<Self, Error> {
        let a = Attractor {
            point,
            strength,
            softening,
            falloff: None,
        };
        a.check()?;
        Ok(a)
    }

    /// The same attractor shaped by `falloff` (`None`: everywhere).
    pub fn with_falloff(self, falloff: Option<Falloff>) -> Self {
        Attractor { falloff, ..self }
    }

    /// The falloff's weight φ and gradient ∇φ (1/m) at `xi` (1 and 0 without one).
    fn weight(&self, xi: &[f64]) -> (f64, [f64; 3]) {
        match &self.falloff {
            None => (1.0, [0.0; 3]),
            Some(f) => f.weight_and_gradient([xi[0], xi[1], xi[2]]),
        }
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
        self.falloff.map_or(Ok(()), |f| f.check())
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

    /// Adds −μ m_i r / s³ to each particle's force, N (times the falloff's φ(x_i)).
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        check_buffers(self.name(), s, &[("f", f.len())])?;
        for ((fi, xi), m) in f.chunks_exact_mut(3).zip(s.x.chunks_exact(3)).zip(s.mass) {
            let (r, s2) = self.offset(xi);
            if s2 == 0.0 {
                continue; // at an unsoftened point: no direction, see the type's doc
            }
            let phi = if self.falloff.is_some() { self.weight(xi).0 } else { 1.0 };
            let c = phi * self.strength * m / (s2 * s2.sqrt());
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

    /// U = −Σ μ m_i / s_i, J (−∞ for a particle exactly at an unsoftened point); none
    /// with a falloff (see the module's doc).
    fn potential_energy(&self, s: &State) -> Option<f64> {
        if self.falloff.is_some() {
            return None;
        }
        let u =
            s.x.chunks_exact(3)
                .zip(s.mass)
                .map(|(xi, m)| -self.strength * m / self.offset(xi).1.sqrt());
        Some(u.sum())
    }

    /// Conservative (its work is −ΔU; with a falloff, a source), a function of the
    /// positions; it holds no particle indices.
    fn properties(&self) -> Properties {
        Properties {
            energy: if self.falloff.is_some() {
                EnergyClass::Source
            } else {
                EnergyClass::Conservative
            },
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
    /// across it. No velocity dependence. With a falloff, ∂F/∂x = φ ∂F_a/∂x + F_a ∇φᵀ
    /// adds |F_a/m|∞ |∇φ|₁ (the rank-one term's ∞-norm) to φ times that.
    fn rates(&self, s: &State, inv_mass: &[f64]) -> Option<Rates> {
        let mut omega_squared: f64 = 0.0;
        for (xi, w) in s.x.chunks_exact(3).zip(inv_mass) {
            if *w > 0.0 {
                let (r, s2) = self.offset(xi);
                let (phi, g) = self.weight(xi);
                let per_mass = self.strength / (s2 * s2.sqrt()); // |F_a/m| / |r|
                let tilt = if s2 > 0.0 {
                    per_mass * r.iter().fold(0.0_f64, |a, c| a.max(c.abs())) * (g[0].abs() + g[1].abs() + g[2].abs())
                } else {
                    0.0
                };
                omega_squared = omega_squared.max(phi * 2.0 * per_mass + tilt);
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
    /// With a falloff, F = φ F_a: (∂F/∂x)·dx = φ (∂F_a/∂x)·dx + F_a (∇φ·dx).
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
            let (phi, g) = a.weight(xi);
            let shift = g[0] * di[0] + g[1] * di[1] + g[2] * di[2]; // ∇φ·dx
            for k in 0..3 {
                oi[k] -= c * (phi * (di[k] - along * r[k]) + shift * r[k]);
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

    /// Theory: with a falloff F = φ(x) F_a: a tube of inverse-square falloff about the z axis
    /// (r₀ = 1) gives ¼ of Newton's pull at 2 m from the axis, all of it within 1 m; the
    /// shaped force has no potential and may add energy; its Jacobian (φ ∂F_a/∂x + F_a ∇φᵀ)
    /// matches central differences.
    #[test]
    fn falloff_scales_the_force() {
        use super::super::falloff::{Law, Shape};
        let fo = Falloff::new(
            Shape::Tube {
                center: [0.0; 3],
                axis: [0.0, 0.0, 1.0],
            },
            Law::InverseSquare,
            1.0,
            f64::INFINITY,
        )
        .unwrap();
        let mut a = Attractor::new([0.0; 3], 16.0, 0.0).unwrap().with_falloff(Some(fo));
        let x = [2.0, 0.0, 0.0, 0.0, 0.5, 0.0];
        let s = State {
            t: 0.0,
            x: &x,
            v: &[0.0; 6],
            mass: &[1.0, 1.0],
        };
        // Newton: μ/d² = 4 N at 2 m, times (1/2)² = 1 N; 64 N at ½ m, times 1
        assert_eq!(forces(&mut a, &s), vec![-1.0, 0.0, 0.0, 0.0, -64.0, 0.0]);
        assert!(a.potential_energy(&s).is_none() && a.properties().energy == EnergyClass::Source);
        let mut rng = Rng::new(12);
        let x = rng.vec(21, -2.0, 2.0);
        let m = rng.vec(7, 0.5, 2.0);
        let s = State {
            t: 0.0,
            x: &x,
            v: &[0.0; 21],
            mass: &m,
        };
        let fo = Falloff::new(Shape::Sphere { center: [0.5, 0.0, 0.0] }, Law::Smooth, 0.5, 2.5).unwrap();
        let mut a = Attractor::new([0.1, 0.2, -0.1], 5.0, 0.3).unwrap().with_falloff(Some(fo));
        assert_jacobian_matches_differences(&mut a, &s, &mut rng, 1e-6, 1e-6);
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
