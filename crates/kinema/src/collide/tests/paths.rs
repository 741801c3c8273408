use super::*;

#[test]
fn pair_toi_is_exact_in_a_uniform_field_and_rejects_misses() {
    // head-on at 2 m/s from a gap of 0.1 m: τ = 0.05 s
    let Toi::At(at) = pair_toi([-0.3, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0; 3], 0.2, 1.0, 1e-9) else {
        panic!("no impact")
    };
    assert!((at - 0.05).abs() < 1e-16, "{at}");
    // passing 0.25 m to the side of R = 0.2: never, and receding: never
    assert_eq!(
        pair_toi([-1.0, 0.25, 0.0], [2.0, 0.0, 0.0], [0.0; 3], 0.2, 1.0, 1e-9),
        Toi::Never
    );
    assert_eq!(
        pair_toi([1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0; 3], 0.2, 1.0, 1e-9),
        Toi::Never
    );
    // out of reach within the step
    assert_eq!(
        pair_toi([-1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0; 3], 0.2, 0.3, 1e-9),
        Toi::Never
    );
    // touching: an impact now when approaching, else only touching
    assert_eq!(
        pair_toi([-0.2, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0; 3], 0.2, 1.0, 1e-9),
        Toi::At(0.0)
    );
    assert_eq!(
        pair_toi([-0.2, 0.0, 0.0], [1e-12, 0.0, 0.0], [0.0; 3], 0.2, 1.0, 1e-9),
        Toi::Touching
    );
    assert_eq!(
        pair_toi([-0.2, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0; 3], 0.2, 1.0, 1e-9),
        Toi::Touching
    );
    // under a relative acceleration from rest: ½ Δa τ² = gap, τ = √(2·0.1/2) s
    let Toi::At(tau) = pair_toi([-0.3, 0.0, 0.0], [0.0; 3], [2.0, 0.0, 0.0], 0.2, 1.0, 1e-9) else {
        panic!("no impact")
    };
    assert!((tau - 0.1f64.sqrt()).abs() < 1e-14, "{tau}");
}
