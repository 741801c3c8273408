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

/// A continuous solution: the state at any time of the solved interval, from the
/// interpolants of every step (`SolveOptions::dense_output`).
#[derive(Debug, Clone, PartialEq)]
pub struct DenseOutput {
    dim: usize,
    /// Step boundaries t_0, t_1, ..., t_m (monotone in the direction of integration).
    t: Vec<f64>,
    pieces: Pieces,
}

#[derive(Debug, Clone, PartialEq)]
enum Pieces {
    /// Cubic Hermite from y and f = dy/dt at every step boundary (m + 1 of each).
    Hermite { y: Vec<f64>, f: Vec<f64> },
    /// Dormand–Prince: the state at the start of each step and its 7 stages (m of each).
    Dopri5 { y: Vec<f64>, k: Vec<f64> },
}

impl DenseOutput {
    /// Hermite pieces from the states `y` and derivatives `f` at the boundaries `t`
    /// (`t.len() × dim` values each).
    pub fn hermite(dim: usize, t: Vec<f64>, y: Vec<f64>, f: Vec<f64>) -> Self {
        debug_assert_eq!(y.len(), t.len() * dim);
        debug_assert_eq!(f.len(), t.len() * dim);
        Self {
            dim,
            t,
            pieces: Pieces::Hermite { y, f },
        }
    }

    /// An empty Dormand–Prince output starting at t0, filled step by step.
    pub(crate) fn dopri5(dim: usize, t0: f64) -> Self {
        Self {
            dim,
            t: vec![t0],
            pieces: Pieces::Dopri5 {
                y: Vec::new(),
                k: Vec::new(),
            },
        }
    }

    /// Appends one Dormand–Prince step ending at `t_end`, from `y_start` and its stages.
    pub(crate) fn push_dopri5(&mut self, t_end: f64, y_start: &[f64], stages: &[Vec<f64>]) {
        if let Pieces::Dopri5 { y, k } = &mut self.pieces {
            y.extend_from_slice(y_start);
            for s in stages {
                k.extend_from_slice(s);
            }
            self.t.push(t_end);
        }
    }

    /// Appends the end (t, y, f = dy/dt) of one more step to Hermite pieces (the adaptive
    /// driver with a pair that has no continuous extension of its own).
    pub(crate) fn push_hermite(&mut self, t_end: f64, y_end: &[f64], f_end: &[f64]) {
        if let Pieces::Hermite { y, f } = &mut self.pieces {
            y.extend_from_slice(y_end);
            f.extend_from_slice(f_end);
            self.t.push(t_end);
        }
    }

    /// Number of values per state.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The interval covered, (first, last) time.
    pub fn span(&self) -> (f64, f64) {
        (self.t[0], self.t[self.t.len() - 1])
    }

    /// Writes the state at time `t` into `out` (length `dim`). `t` must lie in [`Self::span`].
    pub fn eval(&self, t: f64, out: &mut [f64]) -> Result<(), crate::Error> {
        let (a, b) = self.span();
        let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
        if !(t >= lo && t <= hi) {
            return Err(crate::Error::invalid("t", t, format!("the dense output covers [{lo}, {hi}]")));
        }
        let n = self.dim;
        let m = self.t.len() - 1;
        if m == 0 {
            match &self.pieces {
                Pieces::Hermite { y, .. } => out.copy_from_slice(&y[..n]),
                Pieces::Dopri5 { .. } => return Err(crate::Error::invalid("t", t, "the solution has no step to interpolate")),
            }
            return Ok(());
        }
        // The step i with t in [t_i, t_{i+1}]: boundaries before t, in the direction of time.
        let dir = if b >= a { 1.0 } else { -1.0 };
        let i = self.t[1..m].partition_point(|&ti| dir * ti < dir * t);
        let (ta, tb) = (self.t[i], self.t[i + 1]);
        let h = tb - ta;
        let theta = (t - ta) / h;
        match &self.pieces {
            Pieces::Hermite { y, f } => hermite(
                theta,
                h,
                &y[i * n..(i + 1) * n],
                &y[(i + 1) * n..(i + 2) * n],
                &f[i * n..(i + 1) * n],
                &f[(i + 1) * n..(i + 2) * n],
                out,
            ),
            Pieces::Dopri5 { y, k } => {
                let stages: Vec<Vec<f64>> = k[i * 7 * n..(i + 1) * 7 * n].chunks_exact(n).map(|c| c.to_vec()).collect();
                dopri5(theta, h, &y[i * n..(i + 1) * n], &stages, out)
            }
        }
        Ok(())
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
    fn dense_output_finds_the_step_of_any_time_in_either_direction() {
        // y = t³ sampled at t = 0, 1, 3 (y' = 3t²): Hermite pieces reproduce it exactly.
        let t = vec![0.0, 1.0, 3.0];
        let y: Vec<f64> = t.iter().map(|t: &f64| t.powi(3)).collect();
        let f: Vec<f64> = t.iter().map(|t: &f64| 3.0 * t * t).collect();
        let d = DenseOutput::hermite(1, t.clone(), y.clone(), f.clone());
        let back = DenseOutput::hermite(
            1,
            t.iter().rev().copied().collect(),
            y.iter().rev().copied().collect(),
            f.iter().rev().copied().collect(),
        );
        let mut out = [0.0];
        for &s in &[0.0, 0.5, 1.0, 2.2, 3.0] {
            d.eval(s, &mut out).unwrap();
            assert!((out[0] - s * s * s).abs() < 1e-12, "{s}");
            back.eval(s, &mut out).unwrap();
            assert!((out[0] - s * s * s).abs() < 1e-12, "{s}");
        }
        assert!(d.eval(3.5, &mut out).is_err());
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
