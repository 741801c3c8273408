//! Test helpers of the force catalogue: a deterministic generator and finite-difference checks.
//!
//! The checks compare a force with the calculus it claims:
//! - F = −∇U, by central differences of the potential, one coordinate at a time:
//!   ∂U/∂x_k ≈ (U(x + h e_k) − U(x − h e_k)) / 2h, error O(h²) + O(ε_mach |U| / h);
//! - the Jacobian product, by central differences of F along a random direction:
//!   (∂F/∂x)·dx ≈ (F(x + h dx) − F(x − h dx)) / 2h, and the same in v.
//!
//! With h = 1e-6 on unit-sized states both error terms are near 1e-10 relative, four orders
//! below the 1e-6 tolerance the tests use, while any missing or wrong Jacobian term of a
//! non-negligible size exceeds it.

use super::{Force, State};

/// Splitmix64: a tiny deterministic generator, so that the tests need no dependency and give
/// the same numbers on every platform.
pub(crate) struct Rng(u64);

impl Rng {
    /// A generator started from `seed`.
    pub(crate) fn new(seed: u64) -> Self {
        Rng(seed)
    }

    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [lo, hi).
    pub(crate) fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        let u = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * u
    }

    /// `n` values uniform in [lo, hi).
    pub(crate) fn vec(&mut self, n: usize, lo: f64, hi: f64) -> Vec<f64> {
        (0..n).map(|_| self.uniform(lo, hi)).collect()
    }

    /// Uniform integer in 0..n.
    pub(crate) fn index(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

/// Adds `force`'s Jacobian product (∂F/∂x)·dx + (∂F/∂v)·dv at `s` to `out`, through its
/// linearisation (the definite one with `definite`); false, adding nothing, when it has none.
pub(crate) fn product(force: &dyn Force, s: &State, dx: &[f64], dv: &[f64], out: &mut [f64], definite: bool) -> bool {
    match force.linearize(s, definite) {
        Some(op) => {
            op.apply(s, dx, dv, out);
            true
        }
        None => false,
    }
}

/// The force of `force` alone on the particles of `s`, N (3 per particle).
pub(crate) fn forces(force: &mut dyn Force, s: &State) -> Vec<f64> {
    let mut f = vec![0.0; s.x.len()];
    force.accumulate(s, &mut f).expect("accumulate failed");
    f
}

/// Largest absolute component.
pub(crate) fn max_abs(a: &[f64]) -> f64 {
    a.iter().fold(0.0, |m, x| m.max(x.abs()))
}

/// Asserts |a − b|∞ ≤ rtol · max(|a|∞, |b|∞), with a message naming `what`.
pub(crate) fn assert_close(a: &[f64], b: &[f64], rtol: f64, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: lengths differ");
    let err = a.iter().zip(b).fold(0.0, |m: f64, (x, y)| m.max((x - y).abs()));
    let scale = max_abs(a).max(max_abs(b));
    assert!(
        err <= rtol * scale,
        "{what}: max difference {err:e} > {rtol:e} × {scale:e}\n  a = {a:?}\n  b = {b:?}"
    );
}

/// Asserts F = −∇U for `force` at `s` (central differences with step `h`, m; relative
/// tolerance `rtol` against |F|∞, which must not be zero, so the test cannot pass vacuously).
pub(crate) fn assert_force_is_minus_gradient(force: &mut dyn Force, s: &State, h: f64, rtol: f64) {
    let f = forces(force, s);
    assert!(
        max_abs(&f) > 0.0,
        "{}: zero force makes the gradient check vacuous",
        force.name()
    );
    let mut x = s.x.to_vec();
    let mut minus_grad = vec![0.0; x.len()];
    for k in 0..x.len() {
        let x0 = x[k];
        x[k] = x0 + h;
        let up = force.potential_energy(&State { x: &x, ..*s }).expect("no potential energy");
        x[k] = x0 - h;
        let um = force.potential_energy(&State { x: &x, ..*s }).expect("no potential energy");
        x[k] = x0;
        minus_grad[k] = -(up - um) / (2.0 * h);
    }
    assert_close(&f, &minus_grad, rtol, &format!("{}: F vs −∇U", force.name()));
}

/// Asserts that `force` has a Jacobian product (its linearisation) and matches central differences of
/// `accumulate` along random directions dx (positions) and dv (velocities) drawn from `rng`,
/// separately and together; `h` is the difference step (m, m/s), `rtol` relative.
pub(crate) fn assert_jacobian_matches_differences(force: &mut dyn Force, s: &State, rng: &mut Rng, h: f64, rtol: f64) {
    let len = s.x.len();
    let zero = vec![0.0; len];
    let dx = rng.vec(len, -1.0, 1.0);
    let dv = rng.vec(len, -1.0, 1.0);
    for (label, dx, dv) in [("x", &dx, &zero), ("v", &zero, &dv), ("x and v", &dx, &dv)] {
        let mut jp = vec![0.0; len];
        assert!(product(force, s, dx, dv, &mut jp, false), "{}: no Jacobian", force.name());
        let shifted = |sign: f64| -> (Vec<f64>, Vec<f64>) {
            (
                s.x.iter().zip(dx).map(|(x, d)| x + sign * h * d).collect(),
                s.v.iter().zip(dv).map(|(v, d)| v + sign * h * d).collect(),
            )
        };
        let (xp, vp) = shifted(1.0);
        let (xm, vm) = shifted(-1.0);
        let fp = forces(force, &State { x: &xp, v: &vp, ..*s });
        let fm = forces(force, &State { x: &xm, v: &vm, ..*s });
        let fd: Vec<f64> = fp.iter().zip(&fm).map(|(p, m)| (p - m) / (2.0 * h)).collect();
        assert_close(&jp, &fd, rtol, &format!("{}: J·d{label} vs finite differences", force.name()));
    }
}
