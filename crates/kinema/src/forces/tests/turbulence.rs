//! The turbulence force's tests.

use super::super::falloff::{Law, Shape};
use super::super::testing::{assert_jacobian_matches_differences, forces, Rng};
use super::*;

fn turbulence(dim: usize, seed: u64) -> Turbulence {
    Turbulence::new(2.0, 0.5, seed, f64::INFINITY, 1, 0.5, dim, Coupling::Acceleration, None).unwrap()
}

fn point(rng: &mut Rng, half: f64) -> [f64; 3] {
    [rng.uniform(-half, half), rng.uniform(-half, half), rng.uniform(-half, half)]
}

/// Theory: ∇·(∇ × ψ) = 0. The analytic Jacobian's trace cancels to rounding (≤ 1e-13 of
/// its largest entry) at 2000 random points, in 3D and 2D, with octaves and a turning
/// field; central differences of the analytic field (h = 10⁻⁵ L) give a divergence within
/// their O(h²) error (≤ 1e-6 of the gradient's size).
#[test]
fn divergence_is_zero_to_rounding() {
    let mut rng = Rng::new(7);
    for dim in [3, 2] {
        let t = Turbulence::new(1.5, 0.8, 42, 0.3, 3, 0.6, dim, Coupling::Acceleration, None).unwrap();
        let (mut worst_trace, mut worst_fd) = (0.0_f64, 0.0_f64);
        for _ in 0..2000 {
            let x = point(&mut rng, 5.0);
            let time = rng.uniform(0.0, 2.0);
            let (_, j) = t.jacobian(time, x);
            let size = j.iter().flatten().fold(0.0_f64, |a, c| a.max(c.abs()));
            worst_trace = worst_trace.max((j[0][0] + j[1][1] + j[2][2]).abs() / size);
            let h = 1e-5 * t.scale;
            let mut div = 0.0;
            for k in 0..dim {
                let (mut xp, mut xm) = (x, x);
                xp[k] += h;
                xm[k] -= h;
                div += (t.value(time, xp)[k] - t.value(time, xm)[k]) / (2.0 * h);
            }
            worst_fd = worst_fd.max(div.abs() / size);
        }
        eprintln!("{dim}D: |tr J| / max |J_ij| ≤ {worst_trace:.1e}; |div u (central differences)| / max |J_ij| ≤ {worst_fd:.1e}");
        assert!(worst_trace < 1e-13, "{dim}D: trace {worst_trace:e}");
        assert!(worst_fd < 1e-6, "{dim}D: finite-difference divergence {worst_fd:e}");
    }
}

/// Theory: ∂F/∂x = φ c ∂u/∂x + F₀ ∇φᵀ, ∂F/∂v = −φ b I (the noise's analytic Hessians), by
/// central differences, in 3D and 2D, both couplings, with and without a falloff.
#[test]
fn jacobian_matches_finite_differences() {
    let mut rng = Rng::new(29);
    let n = 8;
    let x = rng.vec(3 * n, -1.0, 1.0);
    let v = rng.vec(3 * n, -1.0, 1.0);
    let m = rng.vec(n, 0.5, 2.0);
    let s = State {
        t: 0.4,
        x: &x,
        v: &v,
        mass: &m,
    };
    let fo = Falloff::new(Shape::Sphere { center: [0.1, 0.0, 0.0] }, Law::Smooth, 0.3, 1.6).unwrap();
    for dim in [2, 3] {
        for coupling in [Coupling::Acceleration, Coupling::Wind(2.0)] {
            for falloff in [None, Some(fo)] {
                let mut t = Turbulence::new(1.0, 0.7, 5, 1.0, 2, 0.5, dim, coupling, falloff).unwrap();
                assert_jacobian_matches_differences(&mut t, &s, &mut rng, 1e-6, 1e-6);
            }
        }
    }
}

/// Theory: `strength` is the rms of each component (the noise is statistically the same
/// along every axis: the lattice and the gradients' distribution are symmetric under their
/// permutations), the mean is 0 (g and −g are equally likely), and the turning gradients
/// keep the same second moments at every time. Over 2·10⁵ points spread over 10⁵ cells
/// each rms is within 2% of `strength` and each mean within 1.5% of it.
#[test]
fn statistics_are_isotropic_and_scaled() {
    let mut rng = Rng::new(3);
    for (dim, octaves, time) in [(3, 1, 0.0), (3, 3, 0.37), (2, 1, 0.0), (2, 4, 5.1)] {
        let t = Turbulence::new(2.0, 0.25, 11, 1.0, octaves, 0.5, dim, Coupling::Acceleration, None).unwrap();
        let n = 200_000;
        let (mut sum, mut sq) = ([0.0; 3], [0.0; 3]);
        for _ in 0..n {
            let u = t.value(time, point(&mut rng, 50.0 * t.scale));
            for k in 0..3 {
                sum[k] += u[k];
                sq[k] += u[k] * u[k];
            }
        }
        for k in 0..dim {
            let (mean, rms) = (sum[k] / n as f64, (sq[k] / n as f64).sqrt());
            eprintln!("{dim}D, {octaves} octave(s), t = {time}: u_{k} mean {mean:+.4}, rms {rms:.4} (strength 2)");
            assert!((rms / 2.0 - 1.0).abs() < 0.02, "{dim}D axis {k}: rms {rms}");
            assert!(mean.abs() < 0.03, "{dim}D axis {k}: mean {mean}");
        }
        if dim == 2 {
            assert_eq!(sq[2], 0.0, "2D: no z component");
        }
    }
}

/// Theory: the field of scale L at x is the field of scale 1 at x/L (its curl is taken in
/// lattice units), bit for bit when 1/L is a power of two; so its correlation length is
/// proportional to L. The autocorrelation of u_x along x, measured for L = 1 and L = 3 at
/// lags L/4 and 2L, is the same within a few % and falls to about 0 beyond a cell or two.
#[test]
fn correlation_length_scales_with_scale() {
    let unit = Turbulence::new(1.0, 1.0, 9, f64::INFINITY, 1, 0.5, 3, Coupling::Acceleration, None).unwrap();
    let four = Turbulence { scale: 4.0, ..unit };
    let mut rng = Rng::new(13);
    for _ in 0..100 {
        let x = point(&mut rng, 20.0);
        assert_eq!(four.value(0.0, x), unit.value(0.0, x.map(|c| c / 4.0)));
    }
    let correlation = |t: &Turbulence, lag: f64, rng: &mut Rng| {
        let (mut c, mut v) = (0.0, 0.0);
        for _ in 0..100_000 {
            let x = point(rng, 100.0 * t.scale);
            let a = t.value(0.0, x)[0];
            let b = t.value(0.0, [x[0] + lag, x[1], x[2]])[0];
            c += a * b;
            v += a * a;
        }
        c / v
    };
    let three = Turbulence { scale: 3.0, ..unit };
    for frac in [0.25, 2.0] {
        let (c1, c3) = (correlation(&unit, frac, &mut rng), correlation(&three, 3.0 * frac, &mut rng));
        eprintln!("correlation of u_x at lag {frac} L: {c1:.3} (L = 1), {c3:.3} (L = 3)");
        assert!((c1 - c3).abs() < 0.03, "lag {frac} L: {c1} vs {c3}");
        if frac >= 2.0 {
            assert!(c1.abs() < 0.05, "decorrelated beyond 2 L: {c1}");
        } else {
            assert!(c1 > 0.3, "correlated within a cell: {c1}");
        }
    }
}

/// The same seed gives the same bits (two instances, two calls, any thread count); other
/// seeds other fields; a frozen field does not change in time, a turning one does,
/// continuously.
#[test]
fn deterministic_by_seed_and_thread_count() {
    let mut rng = Rng::new(21);
    let n = 5000; // several chunks
    let x = rng.vec(3 * n, -10.0, 10.0);
    let v = vec![0.0; 3 * n];
    let m = vec![1.0; n];
    let s = State {
        t: 1.3,
        x: &x,
        v: &v,
        mass: &m,
    };
    let mut t = Turbulence {
        time_scale: 0.5,
        ..turbulence(3, 1)
    };
    let pool = |threads| rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    let one = pool(1).install(|| forces(&mut t.clone(), &s));
    let four = pool(4).install(|| forces(&mut t.clone(), &s));
    assert!(
        one.iter().zip(&four).all(|(a, b)| a.to_bits() == b.to_bits()),
        "thread count changed the bits"
    );
    assert_eq!(forces(&mut t, &s), forces(&mut t.clone(), &s));
    let other = forces(&mut Turbulence { seed: 2, ..t }, &s);
    assert!(
        one.iter().zip(&other).filter(|(a, b)| a != b).count() > n,
        "seeds 1 and 2 gave the same field"
    );

    let frozen = turbulence(3, 1);
    let p = [0.3, -1.2, 2.2];
    assert_eq!(frozen.value(0.0, p), frozen.value(100.0, p));
    let (a, b) = (t.value(1.0, p), t.value(1.0 + 1e-9, p));
    assert!(a != b && (0..3).all(|k| (a[k] - b[k]).abs() < 1e-7), "{a:?} {b:?}");
}

/// Theory: the turning field's correlation in time at a point, ⟨u(0)·u(t)⟩/⟨|u|²⟩ =
/// E[cos θ_c] = 2 cos(t/τ) sin(t/2τ)/(t/τ) (the rates uniform in [½, 3/2]); measured
/// over 50 000 points within 0.02 at t = ½τ, 2τ, 5τ and 40τ; its rms stays `strength`.
#[test]
fn correlation_in_time_follows_the_turning_rates() {
    let t = Turbulence::new(1.0, 1.0, 8, 0.5, 1, 0.5, 3, Coupling::Acceleration, None).unwrap();
    let mut rng = Rng::new(37);
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    for lag in [0.5, 2.0, 5.0, 40.0] {
        let (mut c, mut v0, mut v1) = (0.0, 0.0, 0.0);
        for _ in 0..50_000 {
            let q = point(&mut rng, 100.0);
            let (u0, u1) = (t.value(1.0, q), t.value(1.0 + lag * t.time_scale, q));
            c += dot(u0, u1);
            v0 += dot(u0, u0);
            v1 += dot(u1, u1);
        }
        let theory = 2.0 * lag.cos() * (lag / 2.0).sin() / lag;
        eprintln!(
            "correlation at t = {lag} τ: {:.3} (theory {theory:.3}); rms ratio {:.3}",
            c / v0,
            (v1 / v0).sqrt()
        );
        assert!((c / v0 - theory).abs() < 0.02, "lag {lag} τ: {} vs {theory}", c / v0);
        assert!(((v1 / v0).sqrt() - 1.0).abs() < 0.02);
    }
}

/// In 2D the field lies in the xy-plane and does not depend on z: u_z = 0 and the
/// Jacobian's z row and column are 0.
#[test]
fn two_dimensional_field_is_planar() {
    let t = turbulence(2, 4);
    let mut rng = Rng::new(31);
    for _ in 0..100 {
        let x = point(&mut rng, 3.0);
        let (u, j) = t.jacobian(0.0, x);
        assert_eq!(u, t.value(0.0, [x[0], x[1], 7.5]));
        assert_eq!(u[2], 0.0);
        assert!((0..3).all(|k| j[2][k] == 0.0 && j[k][2] == 0.0));
    }
}

#[test]
fn bad_parameters_are_named() {
    let base = turbulence(3, 0);
    let e = |t: Turbulence| t.check().unwrap_err().to_string();
    assert!(e(Turbulence { scale: 0.0, ..base }).starts_with("scale = 0 is invalid"));
    assert!(e(Turbulence { strength: -1.0, ..base }).starts_with("strength = -1 is invalid"));
    assert!(e(Turbulence { time_scale: 0.0, ..base }).starts_with("time_scale = 0 is invalid"));
    assert!(e(Turbulence { octaves: 9, ..base }).starts_with("octaves = 9 is invalid: octaves must be an integer from 1 to 8"));
    assert!(e(Turbulence { roughness: 1.5, ..base }).starts_with("roughness = 1.5 is invalid"));
    assert!(e(Turbulence { dim: 1, ..base }).starts_with("dim = 1 is invalid"));
}
