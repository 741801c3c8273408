//! Continuous collision detection against hand-solved times of impact, including a 1000 m/s
//! particle of radius 0.01 m that a discrete check at h = 1/60 s would step through, and the
//! cases that must give `None`: grazing (tangent) paths, receding pairs, impacts after the
//! step. A property test then checks any answer against the motion itself: at τ the distance
//! is the contact distance while approaching, and no earlier time in the step touches.

use kinema::collide::{toi_plane, toi_sphere_obstacle, toi_spheres, Plane, SphereObstacle, Surface};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;

const H: f64 = 1.0 / 60.0;

fn assert_rel(got: Option<f64>, want: f64, rtol: f64) {
    let got = got.unwrap_or_else(|| panic!("no impact, expected τ = {want}"));
    assert!((got - want).abs() <= rtol * want.abs(), "τ = {got}, expected {want}");
}

fn plane(point: [f64; 3], normal: [f64; 3]) -> Plane {
    Plane::new(point, normal, Surface::default()).unwrap()
}

#[test]
fn a_fast_small_sphere_hits_within_the_step() {
    // 1000 m/s, r = 0.01 m each, 10 m apart: contact when the centres are 0.02 m apart,
    // after 9.98 m: τ = 9.98 ms < h = 16.7 ms (a discrete check at the step's end would find
    // them 6.67 m past each other).
    assert_rel(toi_spheres([-10.0, 0.0, 0.0], [1000.0, 0.0, 0.0], 0.02, H), 9.98e-3, 1e-14);
    // both moving, 500 m/s each: the same relative motion
    let (xi, xj, vi, vj) = ([0.0, 1.0, 2.0], [10.0, 1.0, 2.0], [500.0, 0.0, 0.0], [-500.0, 0.0, 0.0]);
    let d = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    assert_rel(toi_spheres(d(xi, xj), d(vi, vj), 0.02, H), 9.98e-3, 1e-14);
    // off-centre by b = 0.01 m: contact when the x-separation is √(R² − b²)
    let tau = (10.0 - (0.02f64 * 0.02 - 0.01 * 0.01).sqrt()) / 1000.0;
    assert_rel(toi_spheres([-10.0, 0.01, 0.0], [1000.0, 0.0, 0.0], 0.02, H), tau, 1e-14);
    // 20 m apart it needs 19.98 ms, beyond the step
    assert_eq!(toi_spheres([-20.0, 0.0, 0.0], [1000.0, 0.0, 0.0], 0.02, H), None);
    assert_rel(
        toi_spheres([-20.0, 0.0, 0.0], [1000.0, 0.0, 0.0], 0.02, 0.02),
        19.98e-3,
        1e-14,
    );
}

#[test]
fn grazing_receding_and_resting_pairs_do_not_collide() {
    // tangent: dx = (−4, 3, 0) moving along x passes at distance 3 = R exactly
    assert_eq!(toi_spheres([-4.0, 3.0, 0.0], [1.0, 0.0, 0.0], 3.0, 10.0), None);
    // a hair closer is an impact (at about τ = 4 − √(2·3·3e-9)), a hair farther is not
    assert!(toi_spheres([-4.0, 3.0, 0.0], [1.0, 0.0, 0.0], 3.0 * (1.0 + 1e-9), 10.0).is_some_and(|t| (t - 4.0).abs() < 1e-3));
    assert_eq!(toi_spheres([-4.0, 3.0, 0.0], [1.0, 0.0, 0.0], 3.0 * (1.0 - 1e-9), 10.0), None);
    // receding, and no relative motion
    assert_eq!(toi_spheres([10.0, 0.0, 0.0], [1000.0, 0.0, 0.0], 0.02, H), None);
    assert_eq!(toi_spheres([-10.0, 0.0, 0.0], [0.0; 3], 0.02, H), None);
    // moving sideways past each other (dx ⟂ dv, not touching)
    assert_eq!(toi_spheres([0.0, 1.0, 0.0], [5.0, 0.0, 0.0], 0.5, 1.0), None);
}

#[test]
fn touching_pairs_collide_now_only_while_approaching() {
    assert_eq!(toi_spheres([0.015, 0.0, 0.0], [-1.0, 0.0, 0.0], 0.02, H), Some(0.0));
    assert_eq!(toi_spheres([0.02, 0.0, 0.0], [-1.0, 0.0, 0.0], 0.02, H), Some(0.0));
    assert_eq!(toi_spheres([0.015, 0.0, 0.0], [1.0, 0.0, 0.0], 0.02, H), None);
    assert_eq!(toi_spheres([0.015, 0.0, 0.0], [0.0, 1.0, 0.0], 0.02, H), None);
}

#[test]
fn a_nearly_touching_pair_keeps_its_digits() {
    // gap 1e-10 m at unit radius, closing at 1 m/s: τ = gap, to rounding, although
    // |dx|² − R² and the discriminant both involve numbers ≈ 1.
    let d = 1.0 + 1e-10;
    let gap = d - 1.0;
    assert_rel(toi_spheres([d, 0.0, 0.0], [-1.0, 0.0, 0.0], 1.0, 1.0), gap, 1e-14);
    // a diagonal approach, gap 1e-9 m: τ = gap / speed along the line of centres
    let n: [f64; 3] = [0.6, 0.0, 0.8];
    let dist: f64 = 2.0 + 1e-9;
    let dx = [dist * n[0], dist * n[1], dist * n[2]];
    let gap = (dx[0] * dx[0] + dx[2] * dx[2]).sqrt() - 2.0;
    assert_rel(toi_spheres(dx, [-3.0 * n[0], 0.0, -3.0 * n[2]], 2.0, 1.0), gap / 3.0, 1e-6);
}

#[test]
fn a_sphere_hits_a_static_obstacle() {
    // r = 0.01 at 1000 m/s towards an obstacle of R = 0.5 at 10 m: τ = (10 − 0.51) / 1000
    let ob = SphereObstacle::new([10.0, 0.0, 0.0], 0.5, Surface::default()).unwrap();
    assert_rel(
        toi_sphere_obstacle([0.0; 3], [1000.0, 0.0, 0.0], 0.01, &ob, H),
        9.49e-3,
        1e-14,
    );
    // off-centre by 0.3 m: contact at x-separation √(0.51² − 0.3²)
    let tau = (10.0 - (0.51f64 * 0.51 - 0.09).sqrt()) / 1000.0;
    assert_rel(
        toi_sphere_obstacle([0.0, 0.3, 0.0], [1000.0, 0.0, 0.0], 0.01, &ob, H),
        tau,
        1e-14,
    );
    // 0.52 m off-centre passes by
    assert_eq!(toi_sphere_obstacle([0.0, 0.52, 0.0], [1000.0, 0.0, 0.0], 0.01, &ob, H), None);
    // already touching and approaching
    assert_eq!(toi_sphere_obstacle([9.5, 0.0, 0.0], [1.0, 0.0, 0.0], 0.01, &ob, H), Some(0.0));
}

#[test]
fn a_sphere_under_constant_acceleration_meets_a_plane() {
    let g = [0.0, 0.0, -9.81];
    let floor = plane([0.0; 3], [0.0, 0.0, 1.0]);
    // dropped from 1 m, r = 0.01: 0.99 = ½ g τ²
    assert_rel(
        toi_plane([0.0, 0.0, 1.0], [0.0; 3], g, 0.01, &floor, 1.0),
        (2.0 * 0.99 / 9.81f64).sqrt(),
        1e-14,
    );
    // thrown up at 3 m/s from 0.5 m, r = 0.1: 0.4 + 3τ − 4.905τ² = 0, the later root (the first
    // one is in the past)
    let tau = (3.0 + (9.0 + 4.0 * 4.905 * 0.4f64).sqrt()) / 9.81;
    assert_rel(toi_plane([0.0, 0.0, 0.5], [0.0, 0.0, 3.0], g, 0.1, &floor, 1.0), tau, 1e-14);
    // a fast particle tunnelling through a thin wall within one step: plane x = 5, facing −x
    let wall = plane([5.0, 0.0, 0.0], [-1.0, 0.0, 0.0]);
    assert_rel(toi_plane([0.0; 3], [1000.0, 0.0, 0.0], g, 0.01, &wall, H), 4.99e-3, 1e-14);
    assert_rel(
        toi_plane([-10.0, 0.0, 0.0], [1000.0, 0.0, 0.0], [0.0; 3], 0.01, &wall, H),
        14.99e-3,
        1e-14,
    );
    // braking before the floor: 0.99 − 2τ + 1.5τ² never reaches 0
    assert_eq!(
        toi_plane([0.0, 0.0, 1.0], [0.0, 0.0, -2.0], [0.0, 0.0, 3.0], 0.01, &floor, 10.0),
        None
    );
    // tangent: g(τ) = (τ − 1)², reaching the surface with zero normal speed
    assert_eq!(
        toi_plane([0.0, 0.0, 1.5], [0.0, 0.0, -2.0], [0.0, 0.0, 2.0], 0.5, &floor, 10.0),
        None
    );
    // linear motion with no acceleration along n
    assert_rel(
        toi_plane([0.0, 0.0, 2.0], [3.0, 0.0, -0.5], [1.0, 0.0, 0.0], 0.5, &floor, 10.0),
        3.0,
        1e-15,
    );
}

#[test]
fn touching_a_plane_counts_now_only_while_approaching() {
    let g = [0.0, 0.0, -9.81];
    let floor = plane([0.0; 3], [0.0, 0.0, 1.0]);
    assert_eq!(
        toi_plane([0.0, 0.0, 0.5], [0.0, 0.0, -1.0], [0.0; 3], 0.5, &floor, H),
        Some(0.0)
    );
    // resting on the floor under gravity: pressed into it from now on
    assert_eq!(toi_plane([0.0, 0.0, 0.5], [1.0, 0.0, 0.0], g, 0.5, &floor, H), Some(0.0));
    // separating and never coming back
    assert_eq!(toi_plane([0.0, 0.0, 0.4], [0.0, 0.0, 1.0], [0.0; 3], 0.5, &floor, H), None);
    // touching, leaving at 1 m/s under g = 10: back at τ = 2 v / g = 0.2 s
    let g10 = [0.0, 0.0, -10.0];
    assert_rel(toi_plane([0.0, 0.0, 0.5], [0.0, 0.0, 1.0], g10, 0.5, &floor, 1.0), 0.2, 1e-14);
    assert_eq!(toi_plane([0.0, 0.0, 0.5], [0.0, 0.0, 1.0], g10, 0.5, &floor, 0.1), None);
    // receding from the plane at rest
    assert_eq!(
        toi_plane([0.0, 0.0, 3.0], [0.0, 0.0, 1.0], [0.0; 3], 0.5, &floor, 100.0),
        None
    );
    // a negative step finds nothing
    assert_eq!(
        toi_plane([0.0, 0.0, 0.5], [0.0, 0.0, -1.0], [0.0; 3], 0.5, &floor, -1.0),
        None
    );
}

fn distance(p: [f64; 3]) -> f64 {
    (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt()
}

proptest! {
    // a fixed seed: every run tests the same 1024 motions
    #![proptest_config(ProptestConfig {
        cases: 1024,
        rng_seed: RngSeed::Fixed(0x0074_6f69),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// Any answer agrees with the motion d(τ) = dx + τ dv sampled over the step.
    #[test]
    fn sphere_impacts_agree_with_the_sampled_motion(
        dx in prop::array::uniform3(-2.0f64..2.0),
        dv in prop::array::uniform3(-3.0f64..3.0),
        r in 0.05f64..1.0,
    ) {
        let h = 1.0;
        let at = |t: f64| distance([dx[0] + t * dv[0], dx[1] + t * dv[1], dx[2] + t * dv[2]]);
        let approaching = |t: f64| (0..3).map(|k| (dx[k] + t * dv[k]) * dv[k]).sum::<f64>() < 0.0;
        let samples = 2000;
        match toi_spheres(dx, dv, r, h) {
            Some(tau) => {
                prop_assert!((0.0..=h).contains(&tau));
                if tau > 0.0 {
                    prop_assert!((at(tau) - r).abs() < 1e-12 * (1.0 + distance(dx)), "|d(τ)| = {} vs R = {r}", at(tau));
                    // no sample before τ touches
                    for s in 0..samples {
                        let t = tau * s as f64 / samples as f64;
                        prop_assert!(at(t) >= r * (1.0 - 1e-12), "touching at {t} before τ = {tau}");
                    }
                } else {
                    prop_assert!(at(0.0) <= r);
                }
                prop_assert!(approaching(tau));
            }
            None => {
                // never touching while approaching within the step (sampled)
                for s in 0..=samples {
                    let t = h * s as f64 / samples as f64;
                    prop_assert!(!(at(t) < r * (1.0 - 1e-9) && approaching(t)), "missed an impact near τ = {t}");
                }
            }
        }
    }
}
