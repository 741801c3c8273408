//! Time of impact: continuous detection of the first contact inside a step of length h.
//!
//! Each case reduces to the first root in [0, h] of a quadratic g(τ) = A τ² + B τ + C
//! (a squared distance, or a signed distance, minus its contact value) at which g decreases:
//! the two then touch while approaching. A root where g only touches zero (g' = 0: grazing,
//! tangent motion) is no impact. Two that already touch (g(0) ≤ 0) and approach give τ = 0.
//!
//! The roots come from the cancellation-free form of the quadratic formula: with
//! q = −½ (B + sign(B) √(B² − 4AC)), the roots are q / A and C / q. The textbook
//! (−B ± √(B² − 4AC)) / 2A subtracts two nearly equal numbers for the root of small magnitude
//! whenever 4|AC| ≪ B², which is the common case here (a fast particle still far away
//! relative to its radius): the root that matters would lose most of its digits.
//!
//! A step length h that is negative or NaN finds nothing.

use super::colliders::{Plane, SphereObstacle};
#[cfg(test)]
use super::roots::distinct_roots;
use super::roots::toi_half_space;
use crate::vec3;

/// First time τ ∈ [0, h] (s) at which two spheres in linear relative motion touch while
/// approaching; `None` if they do not within the step.
///
/// `dx` = x_i − x_j (m; the minimum image in a periodic domain) and `dv` = v_i − v_j (m/s)
/// at the start of the step, `radius_sum` = r_i + r_j (m, ≥ 0), `h` the step (s).
///
/// ```text
///   d(τ) = dx + τ dv,   |d(τ)|² = R²   ⇔   a τ² + 2 b τ + c = 0,
///   a = dv·dv,   b = dx·dv,   c = |dx|² − R² = (|dx| − R)(|dx| + R)
/// ```
///
/// d|d|²/dτ = 2 (b + a τ): they approach at τ = 0 iff b < 0. If c ≤ 0 they already touch:
/// τ = 0 when approaching, else `None`. Otherwise an impact needs b < 0 and a positive
/// quarter discriminant b² − a c (= 0 is a graze, closest distance exactly R); then both
/// roots are positive (product c / a > 0, sum −2b / a > 0), and the first is the smaller,
/// c / q with q = −b + √(b² − a c) (the form above with B = 2b; no cancellation as −b > 0).
/// The discriminant itself is evaluated as |dv|² R² − |dx × dv|², which is the same number
/// without the cancellation of b² − a c when the path passes close to the contact distance.
pub fn toi_spheres(dx: [f64; 3], dv: [f64; 3], radius_sum: f64, h: f64) -> Option<f64> {
    if h < 0.0 || h.is_nan() {
        return None;
    }
    let a = vec3::dot(dv, dv);
    let b = vec3::dot(dx, dv);
    // (|dx| − R)(|dx| + R) rather than |dx|² − R²: near contact the gap |dx| − R is then
    // exact (Sterbenz) instead of the difference of two rounded squares.
    let dist = vec3::norm(dx);
    let c = (dist - radius_sum) * (dist + radius_sum);
    if c <= 0.0 {
        return (b < 0.0).then_some(0.0);
    }
    if b >= 0.0 {
        return None;
    }
    // b² − a c = |dv|² R² − |dx × dv|² (Lagrange's identity (dx·dv)² = |dx|²|dv|² − |dx × dv|²):
    // |dv|² times R² minus the squared miss distance of the straight path. In this form a
    // near-graze is not the difference of two large numbers b² and a c.
    let cross = vec3::norm(vec3::cross(dx, dv));
    let speed_r = a.sqrt() * radius_sum;
    let quarter_disc = (speed_r - cross) * (speed_r + cross);
    if quarter_disc <= 0.0 || quarter_disc.is_nan() {
        return None;
    }
    let tau = c / (-b + quarter_disc.sqrt());
    (tau <= h).then_some(tau)
}

/// First time τ ∈ [0, h] (s) at which a sphere of radius `radius` (m) starting at `x0` (m)
/// with velocity `v0` (m/s) and constant acceleration `a` (m/s²) touches the plane while
/// approaching it; `None` if it does not within the step.
///
/// The centre moves as x(τ) = x0 + v0 τ + ½ a τ², so its signed distance from the plane,
/// s(τ) = (x(τ) − p)·n, is a quadratic, and contact is s = r:
///
/// ```text
///   g(τ) = s(τ) − r = ½ (a·n) τ² + (v0·n) τ + (s0 − r),   s0 = (x0 − p)·n
/// ```
///
/// If g(0) ≤ 0 (touching or overlapping) and the distance is decreasing — v0·n < 0, or
/// v0·n = 0 with a·n < 0 — the answer is 0. Otherwise the impact is the root where g falls
/// through zero: for A = ½ a·n > 0 (the parabola opens upwards) the smaller root, for A < 0
/// the larger one, for A = 0 the single root −C/B when B < 0. A particle overlapping at the
/// start and moving away has no impact unless it leaves the contact and comes back within h.
pub fn toi_plane(x0: [f64; 3], v0: [f64; 3], a: [f64; 3], radius: f64, plane: &Plane, h: f64) -> Option<f64> {
    toi_half_space(x0, v0, a, radius, plane.point(), plane.normal(), h)
}

/// First time τ ∈ [0, h] (s) at which a sphere of radius `radius` (m) at `x0` (m) moving with
/// constant velocity `v0` (m/s) touches the static `obstacle` while approaching: two spheres
/// with dx = x0 − c, dv = v0 and R = r + R_obstacle (see [`toi_spheres`]).
pub fn toi_sphere_obstacle(x0: [f64; 3], v0: [f64; 3], radius: f64, obstacle: &SphereObstacle, h: f64) -> Option<f64> {
    toi_spheres(vec3::sub(x0, obstacle.center()), v0, radius + obstacle.radius(), h)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stable_form_keeps_the_small_root() {
        // τ² − 1e8 τ + 1 = 0 has roots ≈ 1e-8 and 1e8; the textbook formula gives the small
        // one as (1e8 − √(1e16 − 4)) / 2, which cancels to 0 or worse in f64.
        let (lo, hi) = distinct_roots(1.0, -1e8, 1.0).unwrap();
        assert!((lo - 1e-8).abs() < 1e-22, "{lo}");
        assert!((hi - 1e8).abs() < 1e-6, "{hi}");
        let naive = (1e8 - (1e16f64 - 4.0).sqrt()) / 2.0;
        assert!(
            (naive - 1e-8).abs() > 1e-10,
            "the naive formula happened to be accurate: {naive}"
        );
        assert!(distinct_roots(1.0, 2.0, 1.0).is_none());
        assert!(distinct_roots(0.0, 2.0, 1.0).is_none());
    }
}
