//! Vortex: a field that turns about an axis, tangential only, with a radial speed profile.
//!
//! With the axis through `point` p along the unit `axis` a, a particle's offset from the
//! axis is r⊥ = (I − a aᵀ)(x − p), r = |r⊥|, and the tangential direction θ̂ = a × r⊥ / r
//! (counter-clockwise seen from the tip of a, the right-hand rule). The field is
//!
//! ```text
//!   u(x) = U(r) θ̂ = g(r) (a × r⊥),     g(r) = U(r) / r
//! ```
//!
//! with no radial and no axial part. The profile U(r), with S = `strength` (U at the core
//! radius R = `radius`) and the core's radius R:
//!
//! ```text
//!   rankine:     U = S r/R (r ≤ R),  S R/r (r > R)      a solid core turning at S/R rad/s,
//!                                                        a free (irrotational) vortex outside
//!   lamb_oseen:  U = S (R/r) (1 − e^{−r²/R²}) / (1 − e^{−1})
//!                                                        the viscous vortex (Lamb 1932 §334a):
//!                                                        smooth, U → S r/(R (1 − e⁻¹)) at the
//!                                                        axis, the free vortex far out
//!   constant:    U = S                                   Blender's vortex field (R unused);
//!                                                        no direction on the axis: u = 0 there
//! ```
//!
//! Its Jacobian, from ∂(a × r⊥)/∂x = [a]ₓ (the cross product with a; [a]ₓ a = 0) and
//! ∂r/∂x = r⊥ᵀ/r:
//!
//! ```text
//!   (∂u/∂x)·dx = g(r) (a × dx) + g'(r) (r⊥·dx / r) (a × r⊥)
//! ```
//!
//! The field is felt as an acceleration (S in m/s²) or as air turning at U(r) (S in m/s) with
//! a drag coefficient b, and shaped by a falloff ([`super::field`]). In the wind coupling a
//! particle held on a circle of radius r (by any radial force) settles at the tangential
//! speed U(r): the tangential force b (U − v_θ) vanishes there. In the acceleration
//! coupling with linear drag c, at v_θ = m U(r)/c.

use super::falloff::Falloff;
use super::field::{self, Coupling, VectorField};
use super::{Force, Linearized, Properties, Rates, State};
use crate::error::{CallbackError, Error};
use crate::vec3::{cross, dot, norm};

/// A vortex's radial profile U(r) (see the module's doc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Profile {
    /// A solid core inside R, a free vortex outside.
    Rankine,
    /// The smooth viscous vortex of Lamb and Oseen.
    LambOseen,
    /// The same speed at every distance (Blender's vortex).
    Constant,
}

impl Profile {
    /// The profile named `name` (`"rankine"`, `"lamb_oseen"`, `"constant"`).
    pub fn from_name(name: &str) -> Result<Profile, Error> {
        Ok(match name {
            "rankine" => Profile::Rankine,
            "lamb_oseen" => Profile::LambOseen,
            "constant" => Profile::Constant,
            _ => {
                return Err(Error::invalid(
                    "profile",
                    format!("{name:?}"),
                    "the vortex profile must be 'rankine', 'lamb_oseen' or 'constant'",
                ))
            }
        })
    }
}

/// 1 − e⁻¹: the Lamb–Oseen profile's normalisation, so that U(R) = S.
const LAMB_OSEEN_AT_R: f64 = 0.632_120_558_828_557_7;

/// A vortex about an axis: u = U(r) θ̂ felt as an acceleration or a wind, shaped by a falloff.
///
/// `point` p, m, and `axis` a (unit, normalised by [`Vortex::new`]); `strength` S, the
/// tangential speed at the core radius (m/s² as an acceleration, m/s as a wind; finite, either
/// sign: positive turns counter-clockwise about a); `radius` R, m (finite, > 0); the
/// `profile`; the `coupling`; an optional `falloff`. F_i = φ(x_i) m_i u or φ(x_i) b (u − v_i),
/// N. It may add energy; no potential energy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vortex {
    /// A point of the axis, m.
    pub point: [f64; 3],
    /// The axis' direction (unit).
    pub axis: [f64; 3],
    /// S: U(R), m/s² or m/s.
    pub strength: f64,
    /// The core radius R, m.
    pub radius: f64,
    /// U(r).
    pub profile: Profile,
    /// How particles feel it.
    pub coupling: Coupling,
    /// Where it acts (`None`: everywhere).
    pub falloff: Option<Falloff>,
}

impl Vortex {
    /// A vortex about the axis through `point` along `axis` (normalised here; see the type's
    /// doc for the rest).
    pub fn new(
        point: [f64; 3],
        axis: [f64; 3],
        strength: f64,
        radius: f64,
        profile: Profile,
        coupling: Coupling,
        falloff: Option<Falloff>,
    ) -> Result<Vortex, Error> {
        let a = norm(axis);
        if !(a.is_finite() && a > 0.0) {
            return Err(Error::invalid(
                "axis",
                format!("{axis:?}"),
                "the vortex axis must be a finite, non-zero direction",
            ));
        }
        let v = Vortex {
            point,
            axis: [axis[0] / a, axis[1] / a, axis[2] / a],
            strength,
            radius,
            profile,
            coupling,
            falloff,
        };
        v.check()?;
        Ok(v)
    }

    fn check(&self) -> Result<(), Error> {
        if let Some(k) = self.point.iter().position(|c| !c.is_finite()) {
            return Err(Error::invalid(
                format!("point[{k}]"),
                self.point[k],
                "the vortex's point must be finite (m)",
            ));
        }
        if (norm(self.axis) - 1.0).abs() > 1e-12 || self.axis.iter().any(|c| !c.is_finite()) {
            return Err(Error::invalid(
                "axis",
                format!("{:?}", self.axis),
                "the vortex axis must be a unit vector",
            ));
        }
        if !self.strength.is_finite() {
            return Err(Error::invalid(
                "strength",
                self.strength,
                "the vortex strength (tangential speed at the core radius) must be finite",
            ));
        }
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return Err(Error::invalid(
                "radius",
                self.radius,
                "the vortex core radius must be finite and > 0 m",
            ));
        }
        self.coupling.check()?;
        self.falloff.map_or(Ok(()), |f| f.check())
    }

    /// g(r) = U(r)/r (1/s, or 1/s² as an acceleration) and g'(r).
    fn g(&self, r: f64) -> (f64, f64) {
        let (s, big_r) = (self.strength, self.radius);
        match self.profile {
            Profile::Rankine if r <= big_r => (s / big_r, 0.0),
            Profile::Rankine => (s * big_r / (r * r), -2.0 * s * big_r / (r * r * r)),
            Profile::Constant if r == 0.0 => (0.0, 0.0),
            Profile::Constant => (s / r, -s / (r * r)),
            Profile::LambOseen => {
                // g = (S/(R c)) ψ(q), q = r²/R², ψ(q) = (1 − e^{−q})/q (expm1: exact to rounding,
                // → 1 at the axis), ψ'(q) = (q e^{−q} − (1 − e^{−q}))/q², whose numerator cancels
                // near q = 0: there the series ψ' = Σ_{k≥1} k (−q)^{k−1} (−1) / (k+1)!, to
                // rounding for q < 0.1 with 12 terms.
                let q = (r / big_r) * (r / big_r);
                let psi = if q == 0.0 { 1.0 } else { -(-q).exp_m1() / q };
                let dpsi = if q < 0.1 {
                    let (mut sum, mut power, mut factorial) = (0.0, 1.0, 1.0);
                    for k in 1..=12 {
                        factorial *= (k + 1) as f64;
                        sum -= k as f64 * power / factorial;
                        power *= -q;
                    }
                    sum
                } else {
                    (q * (-q).exp() + (-q).exp_m1()) / (q * q)
                };
                let c = s / (big_r * LAMB_OSEEN_AT_R);
                (c * psi, c * dpsi * 2.0 * r / (big_r * big_r))
            }
        }
    }

    /// r⊥ and r.
    fn offset(&self, x: [f64; 3]) -> ([f64; 3], f64) {
        let d = [x[0] - self.point[0], x[1] - self.point[1], x[2] - self.point[2]];
        let along = dot(d, self.axis);
        let rp = [
            d[0] - along * self.axis[0],
            d[1] - along * self.axis[1],
            d[2] - along * self.axis[2],
        ];
        (rp, norm(rp))
    }

    /// U(r), the profile's tangential speed at distance `r` from the axis (m/s or m/s²).
    pub fn speed_at(&self, r: f64) -> f64 {
        self.g(r).0 * r
    }
}

impl VectorField for Vortex {
    fn value(&self, _t: f64, x: [f64; 3]) -> [f64; 3] {
        let (rp, r) = self.offset(x);
        let (g, _) = self.g(r);
        let e = cross(self.axis, rp);
        [g * e[0], g * e[1], g * e[2]]
    }

    /// Row k of ∂u/∂x: g [a]ₓ + (g'/r) (a × r⊥) r⊥ᵀ (see the module's doc).
    fn jacobian(&self, t: f64, x: [f64; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
        let (rp, r) = self.offset(x);
        let (g, dg) = self.g(r);
        let a = self.axis;
        let e = cross(a, rp);
        let cross_a = [[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]];
        let radial = if r > 0.0 { dg / r } else { 0.0 };
        let mut j = [[0.0; 3]; 3];
        for i in 0..3 {
            for k in 0..3 {
                j[i][k] = g * cross_a[i][k] + radial * e[i] * rp[k];
            }
        }
        (self.value(t, x), j)
    }
}

impl Force for Vortex {
    fn name(&self) -> &str {
        "vortex"
    }

    /// Adds φ m_i u or φ b (u − v_i), N (all threads).
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        field::accumulate(self.name(), self, self.coupling, self.falloff.as_ref(), s, f)
    }

    /// Re-checks the parameters (the fields are public and may have changed).
    fn validate(&self, _n: usize) -> Result<(), Error> {
        self.check()
    }

    fn properties(&self) -> Properties {
        field::properties(self.coupling)
    }

    /// ∂F/∂x and ∂F/∂v per particle, prepared at `s` ([`super::field`]).
    fn linearize(&self, s: &State, _definite: bool) -> Option<Box<dyn Linearized>> {
        field::boxed(field::linearize(self, self.coupling, self.falloff.as_ref(), s))
    }

    /// Gershgorin bounds of the prepared Jacobian at `s`.
    fn rates(&self, s: &State, inv_mass: &[f64]) -> Option<Rates> {
        field::rates(self, self.coupling, self.falloff.as_ref(), s, inv_mass)
    }
}

#[cfg(test)]
mod tests {
    use super::super::falloff::{Law, Shape};
    use super::super::testing::{assert_jacobian_matches_differences, forces, Rng};
    use super::*;

    fn vortex(profile: Profile, coupling: Coupling) -> Vortex {
        Vortex::new([0.5, -0.25, 1.0], [1.0, 2.0, 2.0], 3.0, 0.75, profile, coupling, None).unwrap()
    }

    /// Theory: the profiles' closed forms, and u has no radial and no axial part: at random
    /// points u·r⊥ = 0 and u·a = 0 to rounding, |u| = |U(r)|, u·θ̂ = U(r).
    #[test]
    fn tangential_profile_in_closed_form() {
        let mut rng = Rng::new(17);
        for profile in [Profile::Rankine, Profile::LambOseen, Profile::Constant] {
            let v = vortex(profile, Coupling::Acceleration);
            for _ in 0..200 {
                let x = [rng.uniform(-3.0, 3.0), rng.uniform(-3.0, 3.0), rng.uniform(-3.0, 3.0)];
                let (rp, r) = v.offset(x);
                let u = v.value(0.0, x);
                let big_u = match profile {
                    Profile::Rankine if r <= 0.75 => 3.0 * r / 0.75,
                    Profile::Rankine => 3.0 * 0.75 / r,
                    Profile::LambOseen => 3.0 * (0.75 / r) * (1.0 - (-(r / 0.75).powi(2)).exp()) / (1.0 - (-1.0_f64).exp()),
                    Profile::Constant => 3.0,
                };
                let theta = cross(v.axis, rp).map(|c| c / r);
                assert!(
                    (dot(u, theta) - big_u).abs() <= 1e-13 * big_u.abs().max(1.0),
                    "{profile:?} r = {r}: {} vs {big_u}",
                    dot(u, theta)
                );
                assert!(dot(u, rp).abs() <= 1e-14 * r * big_u.abs().max(1.0), "radial part");
                assert!(dot(u, v.axis).abs() <= 1e-14 * big_u.abs().max(1.0), "axial part");
            }
            assert!((v.speed_at(0.75) - 3.0).abs() < 1e-14, "{profile:?}: U(R) = S");
        }
        // the Lamb–Oseen series near the axis meets the closed form
        let v = vortex(Profile::LambOseen, Coupling::Acceleration);
        for r in [1e-4, 0.2371, 0.2372, 0.5] {
            let exact = 3.0 * (0.75 / r) * (-(-(r / 0.75_f64).powi(2)).exp_m1()) / LAMB_OSEEN_AT_R;
            assert!((v.speed_at(r) - exact).abs() < 1e-12 * exact, "r = {r}");
        }
    }

    /// Theory: F = m u as an acceleration, b (u − v) as a wind, times the falloff's φ;
    /// a particle moving with the air feels nothing.
    #[test]
    fn couplings_and_falloff() {
        let v = Vortex::new(
            [0.0; 3],
            [0.0, 0.0, 1.0],
            2.0,
            1.0,
            Profile::Rankine,
            Coupling::Acceleration,
            None,
        )
        .unwrap();
        let x = [2.0, 0.0, 5.0, 0.5, 0.0, 0.0];
        let s = State {
            t: 0.0,
            x: &x,
            v: &[0.0; 6],
            mass: &[3.0, 1.0],
        };
        // U(2) = 2·1/2 = 1 along +y at (2, 0); U(½) = 1 along +y at (½, 0)
        assert_eq!(forces(&mut v.clone(), &s), vec![0.0, 3.0, 0.0, 0.0, 1.0, 0.0]);
        let mut wind = Vortex {
            coupling: Coupling::Wind(4.0),
            ..v
        };
        let moving = [0.0, 1.0, 0.0, 0.0, 0.0, 7.0];
        assert_eq!(
            forces(&mut wind, &State { v: &moving, ..s }),
            vec![0.0, 0.0, 0.0, 0.0, 4.0, -28.0]
        );
        let fo = Falloff::new(Shape::Sphere { center: [0.0; 3] }, Law::Linear, 1.0, 3.0).unwrap();
        let mut shaped = Vortex { falloff: Some(fo), ..v };
        // |x₀| = √29 > 3: φ = 0; |x₁| = ½ ≤ 1: φ = 1
        assert_eq!(forces(&mut shaped, &s), vec![0.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
        let x = [2.0, 0.0, 0.0];
        let one = State {
            x: &x,
            v: &[0.0; 3],
            mass: &[1.0],
            ..s
        };
        assert_eq!(forces(&mut shaped, &one), vec![0.0, 0.5, 0.0]); // φ(2) = ½
    }

    /// Theory: ∂F/∂x = φ c ∂u/∂x + F₀ ∇φᵀ and ∂F/∂v = −φ b I, by central differences, for
    /// every profile and coupling, with a falloff; the field's own Jacobian has zero trace
    /// (a vortex about a straight axis is divergence-free).
    #[test]
    fn jacobian_matches_finite_differences() {
        let mut rng = Rng::new(23);
        let n = 9;
        let x = rng.vec(3 * n, -1.5, 1.5);
        let vel = rng.vec(3 * n, -1.0, 1.0);
        let m = rng.vec(n, 0.5, 2.0);
        let s = State {
            t: 0.0,
            x: &x,
            v: &vel,
            mass: &m,
        };
        let fo = Falloff::new(
            Shape::Tube {
                center: [0.0; 3],
                axis: [0.2, 0.1, 1.0],
            },
            Law::Smooth,
            0.2,
            2.5,
        )
        .unwrap();
        for profile in [Profile::Rankine, Profile::LambOseen, Profile::Constant] {
            for coupling in [Coupling::Acceleration, Coupling::Wind(1.5)] {
                for falloff in [None, Some(fo)] {
                    let mut v = Vortex {
                        falloff,
                        ..vortex(profile, coupling)
                    };
                    assert_jacobian_matches_differences(&mut v, &s, &mut rng, 1e-6, 1e-6);
                }
            }
            let v = vortex(profile, Coupling::Acceleration);
            for p in 0..n {
                let (_, j) = v.jacobian(0.0, [x[3 * p], x[3 * p + 1], x[3 * p + 2]]);
                let scale = j.iter().flatten().fold(0.0_f64, |a, c| a.max(c.abs()));
                assert!((j[0][0] + j[1][1] + j[2][2]).abs() <= 1e-14 * scale, "{profile:?}: div u ≠ 0");
            }
        }
    }

    #[test]
    fn bad_parameters_are_named() {
        let make = |axis, radius, coupling| Vortex::new([0.0; 3], axis, 1.0, radius, Profile::Rankine, coupling, None);
        let e = make([0.0; 3], 1.0, Coupling::Acceleration).unwrap_err().to_string();
        assert!(e.starts_with("axis = [0.0, 0.0, 0.0] is invalid"), "{e}");
        let e = make([0.0, 0.0, 1.0], 0.0, Coupling::Acceleration).unwrap_err().to_string();
        assert!(e.starts_with("radius = 0 is invalid"), "{e}");
        let e = make([0.0, 0.0, 1.0], 1.0, Coupling::Wind(-1.0)).unwrap_err().to_string();
        assert!(e.starts_with("coefficient = -1 is invalid"), "{e}");
        let e = Profile::from_name("burgers").unwrap_err().to_string();
        assert!(e.starts_with("profile = \"burgers\" is invalid"), "{e}");
    }
}
