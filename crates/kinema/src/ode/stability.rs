//! Linear stability on the test equation p' = λp (λ ∈ ℂ): the stability function R(z),
//! z = hλ, of every method, and the largest stable step along a ray of λ.
//!
//! A method applied to p' = λp multiplies the state by R(hλ) each step, so the numerical
//! solution stays bounded iff |R(hλ)| ≤ 1. The exact flow multiplies by e^{hλ}, which is
//! bounded iff Re λ ≤ 0.

use num_complex::Complex64;

use super::method::{Integrator, Method, MethodKind};

/// The stability function of a method.
#[derive(Debug, Clone, PartialEq)]
pub enum StabilityFunction {
    /// R(z) = P(z) / Q(z) with real coefficients in ascending powers of z.
    ///
    /// Explicit Runge–Kutta: R(z) = 1 + z bᵀ(I − zA)⁻¹𝟙, a polynomial (Q = 1) of degree ≤ s
    /// (see [`super::ButcherTableau::stability_polynomial`]). Implicit Euler:
    /// p_{n+1} = p_n + hλ p_{n+1}, so R(z) = 1 / (1 − z).
    Rational {
        /// Numerator coefficients P_0, P_1, ...
        num: Vec<f64>,
        /// Denominator coefficients Q_0, Q_1, ...
        den: Vec<f64>,
    },
    /// Symplectic Euler and velocity Verlet, which integrate second-order systems only.
    ///
    /// Their test problem is the oscillator x'' = λ²x, whose first-order form has the
    /// eigenvalues ±λ (λ = iω for the harmonic oscillator x'' = −ω²x). With w = z² = h²λ², one
    /// step maps (x, h v) by a 2×2 matrix M(w):
    ///
    /// ```text
    ///   symplectic Euler  (v += hλ²x; x += h v):        M = [[1 + w, 1], [w, 1]]
    ///   velocity Verlet   (half kick, drift, half kick): M = [[1 + w/2, 1], [w(1 + w/4), 1 + w/2]]
    /// ```
    ///
    /// Both have det M = 1 and trace M = 2 + w, so the eigenvalues are the roots of
    /// μ² − (2 + w)μ + 1 = 0 and R(z) is the root of larger modulus (the spectral radius
    /// governs growth). |R| ≤ 1 iff w ∈ [−4, 0]: the step is stable iff λ is imaginary and
    /// h|λ| ≤ 2, the familiar hω ≤ 2.
    Symplectic,
}

impl StabilityFunction {
    /// The stability function of a registered method or a user tableau.
    pub fn of(integrator: &Integrator) -> Self {
        match integrator {
            Integrator::Tableau(t) => StabilityFunction::Rational {
                num: t.stability_polynomial(),
                den: vec![1.0],
            },
            Integrator::Named(m) => match m.kind() {
                MethodKind::ExplicitRk | MethodKind::Adaptive => StabilityFunction::Rational {
                    num: m.tableau().expect("explicit methods have tableaux").stability_polynomial(),
                    den: vec![1.0],
                },
                MethodKind::Implicit => {
                    debug_assert_eq!(*m, Method::ImplicitEuler);
                    StabilityFunction::Rational {
                        num: vec![1.0],
                        den: vec![1.0, -1.0],
                    }
                }
                MethodKind::SecondOrder => StabilityFunction::Symplectic,
            },
        }
    }

    /// R(z).
    pub fn eval(&self, z: Complex64) -> Complex64 {
        match self {
            StabilityFunction::Rational { num, den } => horner(num, z) / horner(den, z),
            StabilityFunction::Symplectic => {
                // Roots of μ² − (2 + w)μ + 1: μ = (τ ± √(τ² − 4)) / 2 with τ = 2 + w.
                let tau = 2.0 + z * z;
                let d = (tau * tau - 4.0).sqrt();
                let (m1, m2) = ((tau + d) / 2.0, (tau - d) / 2.0);
                if m1.norm() >= m2.norm() {
                    m1
                } else {
                    m2
                }
            }
        }
    }

    /// The largest h ≥ 0 such that |R(sλ)| ≤ 1 for every 0 < s ≤ h, in the unit of 1/λ.
    ///
    /// `f64::INFINITY` when the whole ray is stable, 0 when no positive step is, NaN for a
    /// non-finite λ.
    pub fn max_step(&self, lam: Complex64) -> f64 {
        if !(lam.re.is_finite() && lam.im.is_finite()) {
            return f64::NAN;
        }
        let r = lam.norm();
        if r == 0.0 {
            return f64::INFINITY; // p' = 0: every step is exact
        }
        let dir = lam / r;
        let unit = match self {
            StabilityFunction::Rational { num, den } => first_unstable_root(&ray_polynomial(num, den, dir)),
            StabilityFunction::Symplectic => {
                // w = s² dir² lies in [−4, 0] for all small s only when dir² is real and ≤ 0,
                // i.e. dir = ±i; then s ≤ 2.
                let d2 = dir * dir;
                if d2.im.abs() <= 1e-14 && d2.re < 0.0 {
                    2.0 / (-d2.re).sqrt()
                } else {
                    0.0
                }
            }
        };
        unit / r
    }
}

fn horner(coef: &[f64], z: Complex64) -> Complex64 {
    coef.iter().rev().fold(Complex64::new(0.0, 0.0), |acc, &c| acc * z + c)
}

/// Coefficients (ascending in s) of |P(s·d)|² − |Q(s·d)|², a real polynomial in s ≥ 0 whose
/// sign tells whether |R(s·d)| > 1.
fn ray_polynomial(num: &[f64], den: &[f64], dir: Complex64) -> Vec<f64> {
    fn abs2(coef: &[f64], dir: Complex64) -> Vec<f64> {
        // P(s d) = Σ α_k s^k with α_k = P_k d^k; |Σ α_k s^k|² = Σ_m s^m Σ_{j+k=m} Re(α_j ᾱ_k).
        let mut pow = Complex64::new(1.0, 0.0);
        let alpha: Vec<Complex64> = coef
            .iter()
            .map(|&c| {
                let a = pow * c;
                pow *= dir;
                a
            })
            .collect();
        let mut out = vec![0.0; 2 * alpha.len() - 1];
        for (j, aj) in alpha.iter().enumerate() {
            for (k, ak) in alpha.iter().enumerate() {
                out[j + k] += (aj * ak.conj()).re;
            }
        }
        out
    }
    let p = abs2(num, dir);
    let q = abs2(den, dir);
    let mut c = vec![0.0; p.len().max(q.len())];
    for (i, v) in p.iter().enumerate() {
        c[i] += v;
    }
    for (i, v) in q.iter().enumerate() {
        c[i] -= v;
    }
    c
}

/// The smallest s > 0 where the polynomial c (with c(0) = 0, c < 0 just right of 0 for a
/// stable start) turns positive. Coefficients below 1e-12 of the largest are rounding noise
/// (e.g. the exact cancellations that make RK4's |R(iy)|² = 1 − y⁶/72 + y⁸/576).
fn first_unstable_root(c: &[f64]) -> f64 {
    let scale = c.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if scale == 0.0 {
        return f64::INFINITY; // |R| = 1 on the whole ray
    }
    let significant = |v: f64| v.abs() > 1e-12 * scale;
    let lo = match c.iter().position(|&v| significant(v)) {
        Some(i) => i,
        None => return f64::INFINITY,
    };
    let hi = c.iter().rposition(|&v| significant(v)).unwrap();
    // q(s) = c(s) / s^lo: same sign as c for s > 0, and q(0) = c_lo ≠ 0, so no cancellation.
    let q: Vec<f64> = c[lo..=hi].iter().map(|&v| if significant(v) { v } else { 0.0 }).collect();
    if q[0] > 0.0 {
        return 0.0;
    }
    let eval = |s: f64| q.iter().rev().fold(0.0, |acc, &v| acc * s + v);
    if q.len() == 1 {
        return f64::INFINITY;
    }
    // Cauchy's bound: every real root lies below 1 + max |q_k / q_top|.
    let top = q[q.len() - 1];
    let bound = 1.0 + q[..q.len() - 1].iter().fold(0.0_f64, |m, v| m.max((v / top).abs()));
    const SAMPLES: usize = 20_000;
    let mut prev = 0.0;
    for k in 1..=SAMPLES {
        let s = bound * k as f64 / SAMPLES as f64;
        if eval(s) > 0.0 {
            // bisect on [prev, s]: q(prev) ≤ 0 < q(s)
            let (mut a, mut b) = (prev, s);
            for _ in 0..200 {
                let m = 0.5 * (a + b);
                if m <= a || m >= b {
                    break;
                }
                if eval(m) > 0.0 {
                    b = m;
                } else {
                    a = m;
                }
            }
            return a;
        }
        prev = s;
    }
    f64::INFINITY
}

/// R(z) for a method or tableau.
pub fn amplification(integrator: &Integrator, z: Complex64) -> Complex64 {
    StabilityFunction::of(integrator).eval(z)
}

/// Largest stable step on p' = λp: the largest h with |R(sλ)| ≤ 1 for all 0 < s ≤ h
/// (`INFINITY`: no limit; 0: no positive step is stable). h in the time unit of 1/λ.
pub fn max_step(integrator: &Integrator, lam: Complex64) -> f64 {
    StabilityFunction::of(integrator).max_step(lam)
}

/// The stable interval of the real axis around 0: (−max_step(−1), max_step(1)) in z = hλ.
pub fn real_interval(integrator: &Integrator) -> (f64, f64) {
    let f = StabilityFunction::of(integrator);
    (-f.max_step(Complex64::new(-1.0, 0.0)), f.max_step(Complex64::new(1.0, 0.0)))
}

/// The stable interval of the imaginary axis around 0, as (lo, hi) with z = i·y, y ∈ [lo, hi].
/// (0, 0) when the method has no imaginary interval.
pub fn imag_interval(integrator: &Integrator) -> (f64, f64) {
    let f = StabilityFunction::of(integrator);
    (-f.max_step(Complex64::new(0.0, -1.0)), f.max_step(Complex64::new(0.0, 1.0)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn named(m: Method) -> Integrator {
        Integrator::Named(m)
    }

    #[test]
    fn implicit_euler_is_one_over_one_minus_z() {
        let z = Complex64::new(-0.3, 0.7);
        let r = amplification(&named(Method::ImplicitEuler), z);
        assert!((r - 1.0 / (1.0 - z)).norm() < 1e-15);
    }

    #[test]
    fn symplectic_amplification_is_unimodular_inside_the_imaginary_interval() {
        for m in [Method::Verlet, Method::SymplecticEuler] {
            let r = amplification(&named(m), Complex64::new(0.0, 1.9));
            assert!((r.norm() - 1.0).abs() < 1e-12);
            let r = amplification(&named(m), Complex64::new(0.0, 2.1));
            assert!(r.norm() > 1.0);
        }
    }
}
