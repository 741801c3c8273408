//! Butcher tableaux: explicit Runge–Kutta methods as data, checked when they are built.
//!
//! A tableau (A, b, c) with s stages advances y' = f(t, y) by
//!
//! ```text
//!   k_i     = f(t_n + c_i h, y_n + h Σ_{j<i} a_ij k_j)      i = 1..s
//!   y_{n+1} = y_n + h Σ_i b_i k_i
//! ```
//!
//! and one stepper (`explicit_rk`) runs them all.

use crate::error::Error;

/// Tolerance for the consistency checks of a tableau (rows of A sum to c, b sums to 1).
///
/// Coefficients typed as decimals (0.3333333333333333) pass; a wrong coefficient does not.
pub const TABLEAU_TOL: f64 = 1e-12;

/// An explicit Runge–Kutta method: strictly lower-triangular A, weights b, nodes c, its
/// declared order, and optionally embedded weights (with their order) for an error estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct ButcherTableau {
    name: String,
    /// A, s × s row-major; strictly lower triangular.
    a: Vec<f64>,
    b: Vec<f64>,
    c: Vec<f64>,
    /// Embedded lower-order weights b̂ (error estimate y − ŷ = h Σ (b_i − b̂_i) k_i) and their
    /// declared order p̂.
    embedded: Option<(Vec<f64>, u32)>,
    order: u32,
}

impl ButcherTableau {
    /// Builds and checks a tableau. `a` holds s rows of s entries (s × s, strictly lower
    /// triangular), `b` and `c` s entries each; `order` is the declared order of accuracy
    /// (tests measure it).
    ///
    /// Errors name what is wrong: a non-square A, an entry on or above the diagonal (the
    /// method would be implicit), a row of A that does not sum to its c, weights b that do not
    /// sum to 1, a non-finite coefficient.
    pub fn new(name: impl Into<String>, a: Vec<Vec<f64>>, b: Vec<f64>, c: Vec<f64>, order: u32) -> Result<Self, Error> {
        let s = b.len();
        if s == 0 {
            return Err(Error::InvalidTableau("b is empty: a method needs at least one stage".into()));
        }
        if c.len() != s || a.len() != s {
            return Err(Error::InvalidTableau(format!(
                "A has {} rows, b has {} entries and c has {}; all three must have the number of stages",
                a.len(),
                s,
                c.len()
            )));
        }
        let mut flat = vec![0.0; s * s];
        for (i, row) in a.iter().enumerate() {
            if row.len() != s {
                return Err(Error::InvalidTableau(format!(
                    "row {i} of A has {} entries, expected {s} (A must be square)",
                    row.len()
                )));
            }
            for (j, &v) in row.iter().enumerate() {
                if !v.is_finite() {
                    return Err(Error::InvalidTableau(format!("A[{i}][{j}] = {v} is not finite")));
                }
                if j >= i && v != 0.0 {
                    return Err(Error::InvalidTableau(format!(
                        "A[{i}][{j}] = {v} is on or above the diagonal; only explicit methods (strictly lower-triangular A) are supported"
                    )));
                }
                flat[i * s + j] = v;
            }
        }
        for (i, &v) in b.iter().chain(c.iter()).enumerate() {
            if !v.is_finite() {
                let (what, k) = if i < s { ("b", i) } else { ("c", i - s) };
                return Err(Error::InvalidTableau(format!("{what}[{k}] = {v} is not finite")));
            }
        }
        // Consistency: c_i = Σ_j a_ij (each stage is evaluated at the time its increment
        // assumes), and Σ b_i = 1 (order ≥ 1).
        for i in 0..s {
            let row_sum: f64 = flat[i * s..(i + 1) * s].iter().sum();
            if (row_sum - c[i]).abs() > TABLEAU_TOL * (1.0 + c[i].abs()) {
                return Err(Error::InvalidTableau(format!(
                    "row {i} of A sums to {row_sum} but c[{i}] = {}; each row of A must sum to its c",
                    c[i]
                )));
            }
        }
        let b_sum: f64 = b.iter().sum();
        if (b_sum - 1.0).abs() > TABLEAU_TOL {
            return Err(Error::InvalidTableau(format!(
                "the weights b sum to {b_sum}, they must sum to 1"
            )));
        }
        if order == 0 {
            return Err(Error::InvalidTableau("order = 0; a consistent method has order ≥ 1".into()));
        }
        Ok(Self {
            name: name.into(),
            a: flat,
            b,
            c,
            embedded: None,
            order,
        })
    }

    /// Adds embedded weights b̂ (same number of stages, summing to 1) of declared order
    /// `order` (≥ 1; p̂ = p − 1 for the usual pairs: Dormand–Prince 5(4) has p̂ = 4) for error
    /// estimation. The adaptive driver takes the exponent of its step-size update from it.
    pub fn with_embedded(mut self, b_hat: Vec<f64>, order: u32) -> Result<Self, Error> {
        if b_hat.len() != self.stages() {
            return Err(Error::InvalidTableau(format!(
                "embedded weights have {} entries, expected {}",
                b_hat.len(),
                self.stages()
            )));
        }
        let sum: f64 = b_hat.iter().sum();
        if (sum - 1.0).abs() > TABLEAU_TOL {
            return Err(Error::InvalidTableau(format!(
                "the embedded weights sum to {sum}, they must sum to 1"
            )));
        }
        if order == 0 {
            return Err(Error::InvalidTableau(
                "embedded order = 0; a consistent method has order ≥ 1".into(),
            ));
        }
        self.embedded = Some((b_hat, order));
        Ok(self)
    }

    /// The method's name.
    pub fn name(&self) -> &str {
        &self.name
    }
    /// Number of stages s (right-hand-side evaluations per step, before FSAL reuse).
    pub fn stages(&self) -> usize {
        self.b.len()
    }
    /// a_ij.
    #[inline]
    pub fn a(&self, i: usize, j: usize) -> f64 {
        self.a[i * self.stages() + j]
    }
    /// Row i of A (s entries).
    #[inline]
    pub fn a_row(&self, i: usize) -> &[f64] {
        let s = self.stages();
        &self.a[i * s..(i + 1) * s]
    }
    /// Weights b.
    pub fn b(&self) -> &[f64] {
        &self.b
    }
    /// Nodes c.
    pub fn c(&self) -> &[f64] {
        &self.c
    }
    /// Embedded weights b̂, if any.
    pub fn b_hat(&self) -> Option<&[f64]> {
        self.embedded.as_ref().map(|(b_hat, _)| b_hat.as_slice())
    }
    /// Declared order p̂ of the embedded weights, if any.
    pub fn embedded_order(&self) -> Option<u32> {
        self.embedded.as_ref().map(|&(_, order)| order)
    }
    /// Order q of the error estimate e = y − ŷ, if the tableau is embedded: q = min(p, p̂).
    ///
    /// y has local error O(hᵖ⁺¹) and ŷ O(hᵖ̂⁺¹), so their difference is O(h^(q+1)), dominated
    /// by the less accurate of the two (for Dormand–Prince, q = p̂ = 4).
    pub fn error_order(&self) -> Option<u32> {
        self.embedded_order().map(|p_hat| p_hat.min(self.order))
    }
    /// Declared order p: the global error is O(hᵖ), the local (one-step) error O(hᵖ⁺¹).
    pub fn order(&self) -> u32 {
        self.order
    }
    /// First same as last: the last stage is evaluated at (t + h, y_{n+1}), so it is the
    /// next step's first stage and can be reused.
    pub fn is_fsal(&self) -> bool {
        let s = self.stages();
        s > 1 && self.c[0] == 0.0 && self.c[s - 1] == 1.0 && self.a_row(s - 1) == self.b.as_slice()
    }

    /// Coefficients γ_0..γ_s of the stability polynomial R(z) = Σ_k γ_k z^k.
    ///
    /// R(z) = 1 + z bᵀ(I − zA)⁻¹𝟙; with A strictly lower triangular (nilpotent, Aˢ = 0) the
    /// Neumann series terminates: (I − zA)⁻¹ = Σ_{k<s} zᵏAᵏ, so γ_0 = 1 and
    /// γ_k = bᵀ A^{k−1} 𝟙 for k = 1..s.
    pub fn stability_polynomial(&self) -> Vec<f64> {
        let s = self.stages();
        let mut gamma = vec![1.0];
        let mut w = vec![1.0; s]; // A^{k-1} 𝟙
        for _ in 0..s {
            gamma.push(self.b.iter().zip(&w).map(|(b, w)| b * w).sum());
            let next: Vec<f64> = (0..s)
                .map(|i| self.a_row(i).iter().zip(&w).map(|(a, w)| a * w).sum())
                .collect();
            w = next;
        }
        gamma
    }
}

/// The tableaux kinema ships, by name.
pub mod catalogue {
    use super::ButcherTableau;

    fn build(name: &str, a: Vec<Vec<f64>>, b: Vec<f64>, c: Vec<f64>, order: u32) -> ButcherTableau {
        ButcherTableau::new(name, a, b, c, order).expect("built-in tableau is consistent")
    }

    /// Forward Euler: y_{n+1} = y_n + h f(t_n, y_n). Order 1.
    pub fn euler() -> ButcherTableau {
        build("euler", vec![vec![0.0]], vec![1.0], vec![0.0], 1)
    }

    /// Explicit midpoint: y_{n+1} = y_n + h f(t_n + h/2, y_n + h/2 f(t_n, y_n)). Order 2.
    pub fn midpoint() -> ButcherTableau {
        build(
            "midpoint",
            vec![vec![0.0, 0.0], vec![0.5, 0.0]],
            vec![0.0, 1.0],
            vec![0.0, 0.5],
            2,
        )
    }

    /// Heun (explicit trapezoid): predictor Euler, corrector the trapezoid rule. Order 2.
    pub fn heun() -> ButcherTableau {
        build(
            "heun",
            vec![vec![0.0, 0.0], vec![1.0, 0.0]],
            vec![0.5, 0.5],
            vec![0.0, 1.0],
            2,
        )
    }

    /// The classical fourth-order Runge–Kutta method (weights 1/6, 1/3, 1/3, 1/6).
    pub fn rk4() -> ButcherTableau {
        build(
            "rk4",
            vec![
                vec![0.0, 0.0, 0.0, 0.0],
                vec![0.5, 0.0, 0.0, 0.0],
                vec![0.0, 0.5, 0.0, 0.0],
                vec![0.0, 0.0, 1.0, 0.0],
            ],
            vec![1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0],
            vec![0.0, 0.5, 0.5, 1.0],
            4,
        )
    }

    /// Dormand–Prince 5(4) (Dormand & Prince 1980; Hairer, Nørsett & Wanner, Solving ODEs I,
    /// II.5): 7 stages, FSAL, fifth-order solution with an embedded fourth-order estimate.
    pub fn dopri5() -> ButcherTableau {
        let a = vec![
            vec![0.0; 7],
            vec![1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            vec![3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            vec![44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0, 0.0],
            vec![
                19372.0 / 6561.0,
                -25360.0 / 2187.0,
                64448.0 / 6561.0,
                -212.0 / 729.0,
                0.0,
                0.0,
                0.0,
            ],
            vec![
                9017.0 / 3168.0,
                -355.0 / 33.0,
                46732.0 / 5247.0,
                49.0 / 176.0,
                -5103.0 / 18656.0,
                0.0,
                0.0,
            ],
            vec![
                35.0 / 384.0,
                0.0,
                500.0 / 1113.0,
                125.0 / 192.0,
                -2187.0 / 6784.0,
                11.0 / 84.0,
                0.0,
            ],
        ];
        let b = vec![
            35.0 / 384.0,
            0.0,
            500.0 / 1113.0,
            125.0 / 192.0,
            -2187.0 / 6784.0,
            11.0 / 84.0,
            0.0,
        ];
        let c = vec![0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];
        let b_hat = vec![
            5179.0 / 57600.0,
            0.0,
            7571.0 / 16695.0,
            393.0 / 640.0,
            -92097.0 / 339200.0,
            187.0 / 2100.0,
            1.0 / 40.0,
        ];
        build("dopri5", a, b, c, 5)
            .with_embedded(b_hat, 4)
            .expect("Dormand–Prince embedded weights are consistent")
    }

    /// Bogacki–Shampine 3(2) (Bogacki & Shampine 1989; SciPy's `RK23`): 4 stages, FSAL,
    /// third-order solution with an embedded second-order estimate. Not in the method
    /// registry: the adaptive driver's tests run it.
    pub fn bs3() -> ButcherTableau {
        let a = vec![
            vec![0.0; 4],
            vec![1.0 / 2.0, 0.0, 0.0, 0.0],
            vec![0.0, 3.0 / 4.0, 0.0, 0.0],
            vec![2.0 / 9.0, 1.0 / 3.0, 4.0 / 9.0, 0.0],
        ];
        let b = vec![2.0 / 9.0, 1.0 / 3.0, 4.0 / 9.0, 0.0];
        let c = vec![0.0, 1.0 / 2.0, 3.0 / 4.0, 1.0];
        let b_hat = vec![7.0 / 24.0, 1.0 / 4.0, 1.0 / 3.0, 1.0 / 8.0];
        build("bs3", a, b, c, 3)
            .with_embedded(b_hat, 2)
            .expect("Bogacki–Shampine embedded weights are consistent")
    }
}

#[cfg(test)]
mod tests {
    use super::catalogue::*;
    use super::*;

    #[test]
    fn rk4_stability_polynomial_is_the_taylor_polynomial_of_exp() {
        let g = rk4().stability_polynomial();
        let expect = [1.0, 1.0, 0.5, 1.0 / 6.0, 1.0 / 24.0];
        for (a, b) in g.iter().zip(expect) {
            assert!((a - b).abs() < 1e-15, "{g:?}");
        }
    }

    #[test]
    fn dopri5_is_fsal_and_rk4_is_not() {
        assert!(dopri5().is_fsal());
        assert!(!rk4().is_fsal());
    }

    #[test]
    fn embedded_pairs_know_the_order_of_their_error_estimate() {
        assert_eq!((dopri5().embedded_order(), dopri5().error_order()), (Some(4), Some(4)));
        assert_eq!((bs3().embedded_order(), bs3().error_order()), (Some(2), Some(2)));
        assert!(bs3().is_fsal());
        assert_eq!(rk4().error_order(), None);
        let e = heun().with_embedded(vec![1.0, 0.0], 0).unwrap_err();
        assert!(e.to_string().contains("embedded order = 0"), "{e}");
    }

    #[test]
    fn rows_that_do_not_sum_to_c_are_rejected() {
        let e = ButcherTableau::new("bad", vec![vec![0.0, 0.0], vec![0.4, 0.0]], vec![0.5, 0.5], vec![0.0, 0.5], 2).unwrap_err();
        assert!(e.to_string().contains("row 1 of A sums to 0.4 but c[1] = 0.5"), "{e}");
    }

    #[test]
    fn weights_that_do_not_sum_to_one_are_rejected() {
        let e = ButcherTableau::new("bad", vec![vec![0.0]], vec![0.9], vec![0.0], 1).unwrap_err();
        assert!(e.to_string().contains("sum to 0.9"), "{e}");
    }

    #[test]
    fn implicit_tableaux_are_rejected() {
        let e = ButcherTableau::new("be", vec![vec![1.0]], vec![1.0], vec![1.0], 1).unwrap_err();
        assert!(e.to_string().contains("on or above the diagonal"), "{e}");
    }
}
