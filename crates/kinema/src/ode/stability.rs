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

/// The damped oscillator x'' = −ω²x − 2ζω v, the test problem of a spring with a dashpot
/// (ω² = k/m, 2ζω = c/m), for which a second-order method's step is not a function of one
/// λ alone.
///
/// One step of a method is a linear map M(h) of its state; the step is stable when the
/// spectral radius ρ(M) ≤ 1:
///
/// ```text
///   first-order methods (through y = [x, v]): ρ = max |R(hλ±)|, λ± = ω(−ζ ± √(ζ² − 1))
///   symplectic Euler on (x, v):  v₁ = v + h a(x, v),  x₁ = x + h v₁
///       M = [[1 − h²ω², h(1 − hγ)], [−hω², 1 − hγ]]                       (γ = 2ζω)
///   velocity Verlet on (x, v, a), a carried from step to step (first same as last), with
///   the velocity predictor v + h a for a(t_{n+1}):
///       x₁ = x + h v + h²a/2,   a₁ = −ω²x₁ − γ(v + h a),   v₁ = v + h(a + a₁)/2
/// ```
///
/// Returns ρ(M(h)) for `h` in the time unit of 1/ω.
pub fn oscillator_amplification(integrator: &Integrator, h: f64, omega: f64, zeta: f64) -> f64 {
    // ρ depends on hω and ζ only (time scaled by 1/ω). Computing at ω = 1 keeps the 3×3
    // Verlet map well scaled: with ω itself its columns differ by ω², and for ω ≳ 400 rad/s
    // the rounding of the eigenvalues alone exceeded the 1e-9 that decides stability.
    let (h, omega) = (h * omega, 1.0);
    let gamma = 2.0 * zeta * omega;
    let w2 = omega * omega;
    let m: Vec<Vec<f64>> = match integrator {
        Integrator::Named(Method::SymplecticEuler) => {
            vec![vec![1.0 - h * h * w2, h * (1.0 - h * gamma)], vec![-h * w2, 1.0 - h * gamma]]
        }
        Integrator::Named(Method::Verlet) => {
            let x1 = [1.0, h, 0.5 * h * h];
            // a₁ = −ω² x₁ − γ (v + h a)
            let a1 = [-w2 * x1[0], -w2 * x1[1] - gamma, -w2 * x1[2] - gamma * h];
            let v1 = [0.5 * h * a1[0], 1.0 + 0.5 * h * a1[1], 0.5 * h + 0.5 * h * a1[2]];
            vec![x1.to_vec(), v1.to_vec(), a1.to_vec()]
        }
        other => {
            let f = StabilityFunction::of(other);
            return oscillator_eigenvalues(omega, zeta)
                .iter()
                .map(|&l| f.eval(h * l).norm())
                .fold(0.0, f64::max);
        }
    };
    let n = m.len();
    let mat = faer::Mat::<f64>::from_fn(n, n, |i, j| m[i][j]);
    match mat.eigenvalues() {
        Ok(ev) => ev.iter().map(|c| c.norm()).fold(0.0, f64::max),
        Err(_) => f64::NAN,
    }
}

/// The eigenvalues ω(−ζ ± √(ζ² − 1)) of the damped oscillator's first-order form.
fn oscillator_eigenvalues(omega: f64, zeta: f64) -> [Complex64; 2] {
    let root = Complex64::new(zeta * zeta - 1.0, 0.0).sqrt();
    [omega * (-zeta + root), omega * (-zeta - root)]
}

/// The largest h with ρ(M(s)) ≤ 1 for every 0 < s ≤ h on the damped oscillator (see
/// [`oscillator_amplification`]); `INFINITY` when no step is too large, NaN for ω ≤ 0,
/// ζ < 0 or non-finite input.
pub fn oscillator_max_step(integrator: &Integrator, omega: f64, zeta: f64) -> f64 {
    if !(omega.is_finite() && zeta.is_finite() && omega > 0.0 && zeta >= 0.0) {
        return f64::NAN;
    }
    match integrator {
        Integrator::Named(Method::SymplecticEuler | Method::Verlet) => {}
        other => {
            // The exact polynomial machinery of max_step, on both eigenvalues.
            let f = StabilityFunction::of(other);
            return oscillator_eigenvalues(omega, zeta)
                .iter()
                .map(|&l| f.max_step(l))
                .fold(f64::INFINITY, f64::min);
        }
    }
    // Scan s·ω over (0, 4 + 4ζ] (beyond every limit of these explicit methods: ρ grows like
    // (hω)² there), then bisect the first crossing of ρ = 1. Inside the stable range of an
    // undamped oscillator ρ = 1 exactly, so "unstable" means ρ > 1 + 1e-9.
    let unstable = |s: f64| oscillator_amplification(integrator, s, omega, zeta) > 1.0 + 1e-9;
    let top = (4.0 + 4.0 * zeta) / omega;
    const SAMPLES: usize = 4000;
    let mut prev = 0.0;
    for k in 1..=SAMPLES {
        let s = top * k as f64 / SAMPLES as f64;
        if unstable(s) {
            let (mut a, mut b) = (prev, s);
            for _ in 0..100 {
                let mid = 0.5 * (a + b);
                if mid <= a || mid >= b {
                    break;
                }
                if unstable(mid) {
                    b = mid;
                } else {
                    a = mid;
                }
            }
            return a;
        }
        prev = s;
    }
    f64::INFINITY
}

#[cfg(test)]
mod tests {
    use super::*;

    fn named(m: Method) -> Integrator {
        Integrator::Named(m)
    }

    #[test]
    fn undamped_oscillator_limits_are_the_imaginary_intervals() {
        for (m, limit) in [
            (Method::Verlet, 2.0),
            (Method::SymplecticEuler, 2.0),
            (Method::Rk4, 2.0 * 2f64.sqrt()),
        ] {
            let h = oscillator_max_step(&named(m), 10.0, 0.0);
            assert!((h - limit / 10.0).abs() < 1e-9, "{m}: {h}");
        }
        assert_eq!(oscillator_max_step(&named(Method::Euler), 10.0, 0.0), 0.0);
        // Regression: stiff springs (ω up to 1e6 rad/s) have the same hω limit.
        for omega in [400.0, 2e3, 1e4, 1e6] {
            for m in [Method::Verlet, Method::SymplecticEuler] {
                let h = oscillator_max_step(&named(m), omega, 0.0);
                assert!((h * omega / 2.0 - 1.0).abs() < 1e-9, "{m} at ω = {omega}: hω = {}", h * omega);
            }
        }
        assert!(oscillator_max_step(&named(Method::ImplicitEuler), 10.0, 0.3).is_infinite());
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
