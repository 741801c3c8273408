//! Dense output: values between steps, for `t_eval` points that fall inside a step.

/// Cubic Hermite interpolation on [t_a, t_a + h] from the values and derivatives at both ends.
///
/// With θ = (t − t_a)/h:
/// y(θ) = (1 − θ) y_a + θ y_b + θ(θ − 1)[(1 − 2θ)(y_b − y_a) + (θ − 1) h f_a + θ h f_b],
/// which matches y and y' at both ends; its error is O(h⁴) — below the local error of every
/// method of order ≤ 3, and of order h⁴ for RK4.
pub fn hermite(theta: f64, h: f64, ya: &[f64], yb: &[f64], fa: &[f64], fb: &[f64], out: &mut [f64]) {
    for i in 0..out.len() {
        let d = yb[i] - ya[i];
        out[i] = (1.0 - theta) * ya[i]
            + theta * yb[i]
            + theta * (theta - 1.0) * ((1.0 - 2.0 * theta) * d + (theta - 1.0) * h * fa[i] + theta * h * fb[i]);
    }
}

/// Dormand–Prince's continuous extension of order 4 (Hairer, Nørsett & Wanner, II.6; the
/// coefficients are those of Shampine's dense output, as used by SciPy's `RK45`):
/// y(t_a + θh) = y_a + h Σ_i k_i Σ_{j=1..4} P_ij θ^j. At θ = 1 the rows sum to b.
pub const DOPRI5_DENSE: [[f64; 4]; 7] = [
    [
        1.0,
        -8048581381.0 / 2820520608.0,
        8663915743.0 / 2820520608.0,
        -12715105075.0 / 11282082432.0,
    ],
    [0.0, 0.0, 0.0, 0.0],
    [
        0.0,
        131558114200.0 / 32700410799.0,
        -68118460800.0 / 10900136933.0,
        87487479700.0 / 32700410799.0,
    ],
    [
        0.0,
        -1754552775.0 / 470086768.0,
        14199869525.0 / 1410260304.0,
        -10690763975.0 / 1880347072.0,
    ],
    [
        0.0,
        127303824393.0 / 49829197408.0,
        -318862633887.0 / 49829197408.0,
        701980252875.0 / 199316789632.0,
    ],
    [
        0.0,
        -282668133.0 / 205662961.0,
        2019193451.0 / 616988883.0,
        -1453857185.0 / 822651844.0,
    ],
    [
        0.0,
        40617522.0 / 29380423.0,
        -110615467.0 / 29380423.0,
        69997945.0 / 29380423.0,
    ],
];

/// Evaluates the Dormand–Prince dense output at θ ∈ [0, 1].
pub fn dopri5(theta: f64, h: f64, ya: &[f64], k: &[Vec<f64>], out: &mut [f64]) {
    out.copy_from_slice(ya);
    for (row, ki) in DOPRI5_DENSE.iter().zip(k) {
        let w = theta * (row[0] + theta * (row[1] + theta * (row[2] + theta * row[3])));
        if w != 0.0 {
            for (o, kv) in out.iter_mut().zip(ki) {
                *o += h * w * kv;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ode::tableau::catalogue::dopri5 as tableau;

    #[test]
    fn dopri5_dense_output_ends_at_the_step() {
        let b = tableau().b().to_vec();
        for (row, bi) in DOPRI5_DENSE.iter().zip(b) {
            let s: f64 = row.iter().sum();
            assert!((s - bi).abs() < 1e-15, "{s} vs {bi}");
        }
    }

    #[test]
    fn hermite_is_exact_for_cubics() {
        // y = t³ on [1, 3]
        let (ta, h) = (1.0, 2.0);
        let mut out = [0.0];
        hermite(0.3, h, &[1.0], &[27.0], &[3.0], &[27.0], &mut out);
        let t: f64 = ta + 0.3 * h;
        assert!((out[0] - t.powi(3)).abs() < 1e-12);
    }
}
