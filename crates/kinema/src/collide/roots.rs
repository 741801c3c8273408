//! The first root of a quadratic in a step (`toi.rs` derives the cases): the roots in the
//! cancellation-free form, and a sphere's first contact with a half-space under constant
//! acceleration, shared by the plane colliders and the faces of meshes.

use crate::vec3;

/// The two real roots of A τ² + B τ + C = 0, smaller first, for A ≠ 0 and a positive
/// discriminant; `None` otherwise (no roots, or a double root: a tangency).
pub(crate) fn distinct_roots(a: f64, b: f64, c: f64) -> Option<(f64, f64)> {
    let disc = b * b - 4.0 * a * c;
    if a == 0.0 || disc <= 0.0 || disc.is_nan() {
        return None;
    }
    // sign(B) with sign(0) = +1: then |q| ≥ ½ √disc > 0, so C / q is defined.
    let q = -0.5 * (b + disc.sqrt().copysign(if b < 0.0 { -1.0 } else { 1.0 }));
    let (r1, r2) = (q / a, c / q);
    Some(if r1 <= r2 { (r1, r2) } else { (r2, r1) })
}

/// [`super::toi::toi_plane`] for the plane through `point` with unit normal `n` (a plane
/// collider's, a mesh's face).
pub(crate) fn toi_half_space(
    x0: [f64; 3],
    v0: [f64; 3],
    a: [f64; 3],
    radius: f64,
    point: [f64; 3],
    n: [f64; 3],
    h: f64,
) -> Option<f64> {
    if h < 0.0 || h.is_nan() {
        return None;
    }
    let qa = 0.5 * vec3::dot(a, n);
    let qb = vec3::dot(v0, n);
    let qc = vec3::dot(vec3::sub(x0, point), n) - radius;
    if qc <= 0.0 && (qb < 0.0 || (qb == 0.0 && qa < 0.0)) {
        return Some(0.0);
    }
    let tau = if qa == 0.0 {
        // linear: g(τ) = C + B τ falls through 0 at −C / B when B < 0 (then C > 0 here)
        if qb < 0.0 {
            -qc / qb
        } else {
            return None;
        }
    } else {
        let (lo, hi) = distinct_roots(qa, qb, qc)?;
        if qa > 0.0 {
            lo
        } else {
            hi
        }
    };
    (0.0..=h).contains(&tau).then_some(tau)
}
