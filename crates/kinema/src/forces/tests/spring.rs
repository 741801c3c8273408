//! Unit tests of the spring network ([`super::Springs`]): forces, energies and Jacobians against
//! finite differences, the rates, and the errors of bad input.

use super::super::testing::{
    assert_close, assert_force_is_minus_gradient, assert_jacobian_matches_differences, forces, max_abs, product, Rng,
};
use super::*;

fn state<'a>(x: &'a [f64], v: &'a [f64], m: &'a [f64]) -> State<'a> {
    State { t: 0.0, x, v, mass: m }
}

/// A random network of `n` particles in the unit cube and `count` springs with random
/// stiffness, rest length (some 0) and damping; random velocities.
fn network(rng: &mut Rng, n: usize, count: usize, damped: bool) -> (Springs, Vec<f64>, Vec<f64>, Vec<f64>) {
    let x = rng.vec(3 * n, -1.0, 1.0);
    let v = rng.vec(3 * n, -1.0, 1.0);
    let m = rng.vec(n, 0.5, 2.0);
    let mut i = Vec::new();
    let mut j = Vec::new();
    while i.len() < count {
        let (a, b) = (rng.index(n), rng.index(n));
        if a != b {
            i.push(a);
            j.push(b);
        }
    }
    let k = rng.vec(count, 10.0, 100.0);
    // Rest lengths around the typical distance (≈ 0.9), so that springs are both stretched
    // and compressed; every fifth spring has rest length 0.
    let rest = (0..count)
        .map(|s| if s % 5 == 0 { 0.0 } else { rng.uniform(0.2, 1.6) })
        .collect();
    let c = if damped { rng.vec(count, 0.5, 3.0) } else { vec![0.0; count] };
    (Springs::new(i, j, k, rest, c).unwrap(), x, v, m)
}

/// Theory: Hooke's law plus a dashpot. Ends 5 m apart along n = (0.6, 0.8, 0), rest 2 m,
/// k = 10 N/m: a pull of k (L − L₀) = 30 N on i toward j, and the opposite on j. With
/// c = 2 N·s/m and v_j − v_i = (1, 0, 0), u·n = 0.6 m/s adds c u·n = 1.2 N of tension.
/// Compressed to 1 m, the spring pushes the ends apart with 10 N.
#[test]
fn stretched_and_compressed_spring_closed_form() {
    let x = [1.0, 1.0, 1.0, 4.0, 5.0, 1.0];
    let v = [0.0; 6];
    let m = [1.0, 1.0];
    let mut sp = Springs::uniform(vec![0], vec![1], 10.0, 2.0, 0.0).unwrap();
    let f = forces(&mut sp, &state(&x, &v, &m));
    assert_close(&f, &[18.0, 24.0, 0.0, -18.0, -24.0, 0.0], 1e-15, "stretched");
    assert!((sp.potential_energy(&state(&x, &v, &m)).unwrap() - 45.0).abs() < 1e-12);

    let vm = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0];
    let mut damped = Springs::uniform(vec![0], vec![1], 10.0, 2.0, 2.0).unwrap();
    let f = forces(&mut damped, &state(&x, &vm, &m));
    assert_close(
        &f,
        &[31.2 * 0.6, 31.2 * 0.8, 0.0, -31.2 * 0.6, -31.2 * 0.8, 0.0],
        1e-15,
        "damped",
    );

    let xc = [0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
    let f = forces(&mut sp, &state(&xc, &v, &m));
    assert_close(&f, &[0.0, 0.0, -10.0, 0.0, 0.0, 10.0], 1e-15, "compressed");
}

/// Theory: action = −reaction, so Σ_p F_p = 0 up to rounding (relative 1e-12 of Σ|F_p|),
/// on a random damped network in motion; the force must not be trivially zero.
#[test]
fn total_force_of_a_random_network_is_zero() {
    let mut rng = Rng::new(42);
    let (mut sp, x, v, m) = network(&mut rng, 12, 40, true);
    let f = forces(&mut sp, &state(&x, &v, &m));
    assert!(max_abs(&f) > 1.0);
    for c in 0..3 {
        let total: f64 = f.iter().skip(c).step_by(3).sum();
        let scale: f64 = f.iter().skip(c).step_by(3).map(|x| x.abs()).sum();
        assert!(
            total.abs() <= 1e-12 * scale,
            "component {c}: Σ F = {total:e}, Σ |F| = {scale:e}"
        );
    }
    assert!(sp.properties().internal && sp.properties().depends_on_velocity);
}

/// Theory: F = −∇U with U = Σ ½ k (L − L₀)², by central differences; for undamped springs
/// in motion, and for damped springs at rest (where the dashpot adds nothing).
#[test]
fn force_is_minus_gradient_of_elastic_energy() {
    let mut rng = Rng::new(5);
    let (mut sp, x, v, m) = network(&mut rng, 8, 20, false);
    assert!(!sp.properties().depends_on_velocity);
    assert_force_is_minus_gradient(&mut sp, &state(&x, &v, &m), 1e-6, 1e-6);
    let (mut sp, x, _, m) = network(&mut rng, 8, 20, true);
    assert_force_is_minus_gradient(&mut sp, &state(&x, &[0.0; 24], &m), 1e-6, 1e-6);
}

/// Theory: the derived blocks k [n nᵀ + (1 − L₀/L) P], c [(u·n) P + n (P u)ᵀ] / L and
/// c n nᵀ are the derivatives of the force: central differences of F along random dx, dv,
/// on a damped network in motion with stretched, compressed and zero-rest-length springs.
///
/// The products of the derivation above written out spring by spring, without the
/// prepared blocks: the reference the linearisation is checked against.
fn reference_product(sp: &Springs, s: &State, dx: &[f64], dv: &[f64], out: &mut [f64], definite: bool) {
    for i in 0..sp.len() {
        let (k, rest, c) = (sp.k[i], sp.rest_length[i], sp.damping[i]);
        let e = sp.relative(dx, i); // dx_j − dx_i
        let g = match sp.axis(s.x, i) {
            None if rest == 0.0 => [k * e[0], k * e[1], k * e[2]],
            None => continue,
            Some((n, len)) => {
                let u = sp.relative(s.v, i);
                let w = sp.relative(dv, i); // dv_j − dv_i
                let (ne, un, nw) = (dot(n, e), dot(u, n), dot(n, w));
                let pe = [e[0] - ne * n[0], e[1] - ne * n[1], e[2] - ne * n[2]]; // P e
                let (transverse, axial) = if definite {
                    (k * (1.0 - rest / len).max(0.0), k * ne + c * nw)
                } else {
                    // coefficient of P e; coefficient of n, with (P u)·e = u·(P e)
                    (k * (1.0 - rest / len) + c * un / len, k * ne + c * dot(u, pe) / len + c * nw)
                };
                [
                    axial * n[0] + transverse * pe[0],
                    axial * n[1] + transverse * pe[1],
                    axial * n[2] + transverse * pe[2],
                ]
            }
        };
        let (a, b) = (3 * sp.i[i], 3 * sp.j[i]);
        for q in 0..3 {
            out[a + q] += g[q];
            out[b + q] -= g[q];
        }
    }
}

/// The prepared Jacobian is the linear map of the derivation, products written out
/// spring by spring: exact and definite, for a damped network in motion with compressed
/// and stretched springs, and with coincident ends of rest length 0. Its diagonal is the
/// diagonal of those products (unit directions e_k: (J e_k)_k).
#[test]
fn linearized_products_equal_the_direct_ones() {
    let mut rng = Rng::new(21);
    let (sp, mut x, v, m) = network(&mut rng, 12, 40, true);
    let (a, b) = (3 * sp.i[0], 3 * sp.j[0]);
    let end: Vec<f64> = x[a..a + 3].to_vec();
    x[b..b + 3].copy_from_slice(&end); // spring 0's ends coincide
    let s = state(&x, &v, &m);
    for definite in [false, true] {
        let op = sp.linearize(&s, definite).unwrap();
        for _ in 0..5 {
            let (dx, dv) = (rng.vec(36, -1.0, 1.0), rng.vec(36, -1.0, 1.0));
            let (mut direct, mut prepared) = (vec![0.0; 36], vec![0.0; 36]);
            reference_product(&sp, &s, &dx, &dv, &mut direct, definite);
            op.apply(&s, &dx, &dv, &mut prepared);
            for (p, d) in prepared.iter().zip(&direct) {
                assert!((p - d).abs() <= 1e-12 * (1.0 + d.abs()), "definite {definite}: {p} vs {d}");
            }
        }
        let (cx, cv) = (-0.3, -0.7);
        let mut diagonal = vec![0.0; 36];
        op.add_diagonal(&s, cx, cv, &mut diagonal);
        for k in 0..36 {
            let mut unit = vec![0.0; 36];
            unit[k] = 1.0;
            let (mut jx, mut jv) = (vec![0.0; 36], vec![0.0; 36]);
            reference_product(&sp, &s, &unit, &[0.0; 36], &mut jx, definite);
            reference_product(&sp, &s, &[0.0; 36], &unit, &mut jv, definite);
            let expected = cx * jx[k] + cv * jv[k];
            assert!(
                (diagonal[k] - expected).abs() <= 1e-12 * (1.0 + expected.abs()),
                "definite {definite}: diagonal[{k}] = {} vs {expected}",
                diagonal[k]
            );
        }
    }
}

/// The check is sensitive to the dashpot's position term: that term (the difference of the
/// damped and undamped x-Jacobians, less nothing else) is far above the tolerance here,
/// so a product that left it out would fail.
#[test]
fn jacobian_matches_finite_differences_for_damped_springs_in_motion() {
    let mut rng = Rng::new(9);
    let (mut sp, x, v, m) = network(&mut rng, 10, 30, true);
    let s = state(&x, &v, &m);
    assert_jacobian_matches_differences(&mut sp, &s, &mut rng, 1e-6, 1e-6);

    let undamped = Springs::new(
        sp.i.clone(),
        sp.j.clone(),
        sp.k.clone(),
        sp.rest_length.clone(),
        vec![0.0; sp.len()],
    )
    .unwrap();
    let dx = rng.vec(30, -1.0, 1.0);
    let (mut jd, mut ju) = (vec![0.0; 30], vec![0.0; 30]);
    assert!(product(&sp, &s, &dx, &[0.0; 30], &mut jd, false));
    assert!(product(&undamped, &s, &dx, &[0.0; 30], &mut ju, false));
    let term: Vec<f64> = jd.iter().zip(&ju).map(|(a, b)| a - b).collect();
    assert!(
        max_abs(&term) > 1e-2 * max_abs(&jd),
        "dashpot position term {} vs {}",
        max_abs(&term),
        max_abs(&jd)
    );
}

/// Coincident ends: no NaN anywhere. The spring of rest length 0 has force k d = 0 and
/// Jacobian k I; the one of rest length 1 adds nothing (documented convention).
#[test]
fn coincident_ends_give_no_nan() {
    let x = [0.5, 0.5, 0.5, 0.5, 0.5, 0.5];
    let v = [0.0, 0.0, 0.0, 1.0, 2.0, 3.0];
    let m = [1.0, 1.0];
    let s = state(&x, &v, &m);
    for (rest, expect) in [(0.0, [-4.0, 4.0, 2.0, 4.0, -4.0, -2.0]), (1.0, [0.0; 6])] {
        let mut sp = Springs::uniform(vec![0], vec![1], 2.0, rest, 1.0).unwrap();
        assert_eq!(forces(&mut sp, &s), vec![0.0; 6]);
        assert_eq!(sp.potential_energy(&s).unwrap(), 0.5 * 2.0 * rest * rest);
        let mut out = [0.0; 6];
        assert!(product(
            &sp,
            &s,
            &[1.0, -1.0, 0.0, -1.0, 1.0, 1.0],
            &[1.0; 6],
            &mut out,
            false
        ));
        assert_eq!(out, expect);
    }
}

/// Theory: an isolated spring's stretch obeys r'' = −ω² r − γ r' with ω² = k (w_i + w_j),
/// γ = c (w_i + w_j). Measured from the accelerations w F of a small stretch and of a
/// separating velocity, for free ends and for a pinned end (w = 0).
#[test]
fn per_spring_rates_match_the_relative_motion() {
    let (k, c, rest) = (50.0, 0.4, 1.0);
    let sp = Springs::uniform(vec![0], vec![1], k, rest, c).unwrap();
    for inv_mass in [[0.5, 0.25], [0.5, 0.0]] {
        let rates = sp.stiffness_bounds(&inv_mass).unwrap()[0];
        let n = [0.0, 0.6, 0.8];
        let (delta, speed) = (1e-3, 0.7);
        let x = [
            0.0,
            0.0,
            0.0,
            (rest + delta) * n[0],
            (rest + delta) * n[1],
            (rest + delta) * n[2],
        ];
        let v = [0.0, 0.0, 0.0, speed * n[0], speed * n[1], speed * n[2]];
        let f = forces(&mut sp.clone(), &state(&x, &v, &[2.0, 4.0]));
        let rel_acc: f64 = (0..3).map(|q| (inv_mass[1] * f[3 + q] - inv_mass[0] * f[q]) * n[q]).sum();
        let expect = -rates.omega_squared * delta - rates.damping_rate * speed;
        assert!((rel_acc - expect).abs() < 1e-12 * expect.abs(), "{rel_acc} vs {expect}");
        assert_eq!(rates.omega_squared, k * (inv_mass[0] + inv_mass[1]));
    }
}

/// Theory: the largest eigenvalue of M⁻¹K of a chain at rest (found by power iteration on
/// the symmetric M^{-1/2} K M^{-1/2}, K = −∂F/∂x from the linearisation) lies below the
/// Gershgorin bound of `max_rates`, and above every per-spring ω², which is why the
/// network bound exists.
#[test]
fn network_bound_covers_the_fastest_chain_mode() {
    let n = 12;
    let x: Vec<f64> = (0..n).flat_map(|p| [p as f64 * 0.5, 0.0, 0.0]).collect();
    let mut rng = Rng::new(17);
    let inv_mass: Vec<f64> = (0..n)
        .map(|p| if p == 0 { 0.0 } else { 1.0 / rng.uniform(0.8, 1.2) })
        .collect();
    let sp = Springs::with_rest_from_positions((0..n - 1).collect(), (1..n).collect(), 30.0, 0.0, &x).unwrap();
    let mass = vec![1.0; n];
    let s = state(&x, &x, &mass);
    let root_w: Vec<f64> = inv_mass.iter().flat_map(|w| [w.sqrt(); 3]).collect();
    let mut y = rng.vec(3 * n, -1.0, 1.0);
    let mut lambda = 0.0;
    for _ in 0..2000 {
        let z: Vec<f64> = y.iter().zip(&root_w).map(|(y, r)| y * r).collect();
        let mut jz = vec![0.0; 3 * n];
        assert!(product(&sp, &s, &z, &vec![0.0; 3 * n], &mut jz, false));
        let ay: Vec<f64> = jz.iter().zip(&root_w).map(|(j, r)| -j * r).collect();
        let norm = ay.iter().map(|a| a * a).sum::<f64>().sqrt();
        lambda = ay.iter().zip(&y).map(|(a, y)| a * y).sum::<f64>() / y.iter().map(|y| y * y).sum::<f64>();
        y = ay.iter().map(|a| a / norm).collect();
    }
    let bound = sp.max_rates(&inv_mass).unwrap().omega_squared;
    let per_spring = sp
        .stiffness_bounds(&inv_mass)
        .unwrap()
        .iter()
        .fold(0.0, |m: f64, r| m.max(r.omega_squared));
    assert!(lambda <= bound, "λ_max = {lambda} > bound {bound}");
    assert!(lambda > per_spring, "λ_max = {lambda} <= per-spring {per_spring}");
    assert!(lambda > 0.6 * bound, "bound {bound} is loose: λ_max = {lambda}");
}

#[test]
fn rest_lengths_from_positions() {
    let x = [0.0, 0.0, 0.0, 3.0, 4.0, 0.0, 3.0, 4.0, 12.0];
    let sp = Springs::with_rest_from_positions(vec![0, 1], vec![1, 2], 5.0, 0.1, &x).unwrap();
    assert_eq!(sp.rest_length(), &[5.0, 12.0]);
    let f = forces(&mut sp.clone(), &state(&x, &[0.0; 9], &[1.0; 3]));
    assert_eq!(f, vec![0.0; 9]);
    let e = Springs::with_rest_from_positions(vec![0], vec![3], 5.0, 0.0, &x)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("j[0] = 3 is invalid: spring 0's ends must be indices of the 3 particles"),
        "{e}"
    );
}

#[test]
fn validation_errors_name_the_spring_and_the_value() {
    let ok = |k: f64, rest: f64, c: f64| Springs::new(vec![0, 1], vec![1, 2], vec![1.0, k], vec![1.0, rest], vec![0.0, c]);
    let e = ok(-2.0, 1.0, 0.0).unwrap_err().to_string();
    assert!(e.starts_with("k[1] = -2 is invalid"), "{e}");
    let e = ok(1.0, f64::NAN, 0.0).unwrap_err().to_string();
    assert!(e.starts_with("rest_length[1] = NaN is invalid"), "{e}");
    let e = ok(1.0, 1.0, -0.5).unwrap_err().to_string();
    assert!(e.starts_with("damping[1] = -0.5 is invalid"), "{e}");
    let e = ok(f64::INFINITY, 1.0, 0.0).unwrap_err().to_string();
    assert!(e.starts_with("k[1] = inf is invalid"), "{e}");
    let e = Springs::uniform(vec![0, 4], vec![1, 4], 1.0, 1.0, 0.0)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("j[1] = 4 is invalid: spring 1 joins particle 4 to itself"),
        "{e}"
    );
    let e = Springs::new(vec![0, 1], vec![1], vec![1.0; 2], vec![1.0; 2], vec![0.0; 2])
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("j = 1 values is invalid"), "{e}");

    let sp = Springs::uniform(vec![0, 1, 2], vec![1, 7, 0], 1.0, 1.0, 0.0).unwrap();
    assert!(sp.validate(8).is_ok());
    let e = sp.validate(5).unwrap_err().to_string();
    assert!(e.starts_with("j[1] = 7 is invalid: spring 1's ends"), "{e}");
    // accumulate reports the same instead of panicking on an out-of-range index
    let x = [0.0; 15];
    let e = sp
        .clone()
        .accumulate(&state(&x, &x, &[1.0; 5]), &mut [0.0; 15])
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("j[1] = 7 is invalid"), "{e}");
}
