//! Narrow phase: the sphere–sphere (circle–circle in 2D) contact of a candidate pair.
//!
//! For a pair (i, j) with d = x_i − x_j (minimum image along periodic axes) and L = |d|:
//!
//! ```text
//!   n = d / L                 unit, from j towards i
//!   δ = r_i + r_j − L         overlap, m (> 0 when penetrating)
//!   u_n = (v_i − v_j)·n       m/s (< 0 while approaching)
//! ```
//!
//! Coincident centres (L = 0) have no line of centres: the normal is then +x, a fixed choice
//! so that the result does not depend on anything but the input (any unit vector would
//! separate them; +x lies in the plane of a 2D domain).

use super::contact::{Contact, Partner};
use super::domain::Domain;
use super::velocities::Velocities;
use crate::vec3;

/// The contact of particles i and j if their distance is below r_i + r_j + `tolerance`
/// (m, ≥ 0; > 0 also reports near misses, with overlap −gap < 0), else `None`.
///
/// `x`: positions (m), 3 per particle; `v`: velocities (m/s, an array of 3 per particle or
/// Verlet's predictor made when asked, `velocities.rs`); `radius`: m. Indices must
/// be in range (the callers' lists hold them so). Every particle pair's contact in kinema is
/// this function's: the end-of-step contacts of the impulse model, and the contact force
/// force's at each evaluation.
pub fn pair_contact<V: Velocities + ?Sized>(
    i: usize,
    j: usize,
    x: &[f64],
    v: &V,
    radius: &[f64],
    domain: &Domain,
    tolerance: f64,
) -> Option<Contact> {
    let d = domain.displacement(vec3::get(x, i), vec3::get(x, j));
    let sum = radius[i] + radius[j];
    let reach = sum + tolerance;
    let dist2 = vec3::dot(d, d);
    if dist2 >= reach * reach {
        return None;
    }
    let dist = dist2.sqrt();
    let normal = if dist > 0.0 {
        vec3::scale(1.0 / dist, d)
    } else {
        [1.0, 0.0, 0.0]
    };
    let u = vec3::sub(v.at(i), v.at(j));
    Some(Contact {
        i,
        other: Partner::Particle(j),
        normal,
        overlap: sum - dist,
        u_n: vec3::dot(u, normal),
        wall_velocity: [0.0; 3],
    })
}

#[cfg(test)]
mod tests {
    use super::super::domain::Periodic;
    use super::super::oracles::sphere_contacts;
    use super::*;

    #[test]
    fn normal_overlap_and_approach_speed() {
        // j at the origin, i at (0.6, 0.8, 0): L = 1, n = (0.6, 0.8, 0); radii 0.7 + 0.4 = 1.1.
        let x = [0.6, 0.8, 0.0, 0.0, 0.0, 0.0];
        let v = [-1.0, 0.0, 0.0, 0.0, 2.0, 0.0];
        let d = Domain::open(3).unwrap();
        let c = pair_contact(0, 1, &x, &v, &[0.7, 0.4], &d, 0.0).unwrap();
        assert_eq!(c.other, Partner::Particle(1));
        assert!((c.normal[0] - 0.6).abs() < 1e-15 && (c.normal[1] - 0.8).abs() < 1e-15);
        assert!((c.overlap - 0.1).abs() < 1e-15);
        // u = (−1, −2, 0): u·n = −0.6 − 1.6 = −2.2
        assert!((c.u_n + 2.2).abs() < 1e-15);
        assert!(pair_contact(0, 1, &x, &v, &[0.5, 0.4], &d, 0.0).is_none());
        let near = pair_contact(0, 1, &x, &v, &[0.5, 0.4], &d, 0.2).unwrap();
        assert!((near.overlap + 0.1).abs() < 1e-15);
    }

    #[test]
    fn coincident_centres_separate_along_plus_x() {
        let d = Domain::open(2).unwrap();
        let c = pair_contact(0, 1, &[1.0, 2.0, 0.0, 1.0, 2.0, 0.0], &[0.0; 6], &[0.5, 0.5], &d, 0.0).unwrap();
        assert_eq!(c.normal, [1.0, 0.0, 0.0]);
        assert_eq!(c.overlap, 1.0);
    }

    #[test]
    fn the_minimum_image_points_across_the_boundary() {
        // period 10: i at 9.9, j at 0.1 are 0.2 apart through the boundary, and i lies on j's
        // −x side, so the normal from j towards i is −x.
        let p = Periodic::new([0.0; 3], [10.0; 3], [true; 3]).unwrap();
        let d = Domain::periodic(3, p).unwrap();
        let x = [9.9, 5.0, 5.0, 0.1, 5.0, 5.0];
        let mut out = Vec::new();
        sphere_contacts(&x, &[0.0; 6], &[0.15, 0.15], &[(0, 1)], &d, 0.0, &mut out).unwrap();
        assert_eq!(out.len(), 1);
        assert!((out[0].normal[0] + 1.0).abs() < 1e-12, "{:?}", out[0]);
        assert!((out[0].overlap - 0.1).abs() < 1e-12);
    }

    #[test]
    fn bad_pairs_are_named() {
        let d = Domain::open(3).unwrap();
        let mut out = Vec::new();
        let e = sphere_contacts(&[0.0; 6], &[0.0; 6], &[1.0; 2], &[(0, 1), (1, 2)], &d, 0.0, &mut out)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("pairs[1] = (1, 2) is invalid"), "{e}");
        let e = sphere_contacts(&[0.0; 6], &[0.0; 3], &[1.0; 2], &[], &d, 0.0, &mut out)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("v = 3 values is invalid"), "{e}");
        let e = sphere_contacts(&[0.0; 6], &[0.0; 6], &[1.0; 2], &[], &d, -1.0, &mut out)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("tolerance = -1 is invalid"), "{e}");
    }
}
