use super::*;

#[test]
fn the_queue_keeps_one_event_per_particle_in_time_order() {
    let ev = |time, i| Event {
        time,
        i,
        partner: Partner::Collider(0),
        wall: 0,
        partner_version: 0,
    };
    let mut q = EventQueue::default();
    q.reset(3);
    q.schedule(0, Some(ev(0.5, 0)));
    q.schedule(1, Some(ev(0.2, 1)));
    q.schedule(2, Some(ev(0.2, 2)));
    q.schedule(0, Some(ev(0.1, 0))); // replaces 0.5
    q.schedule(2, None); // 2 has none any more
    assert_eq!(q.pop().map(|e| (e.time, e.i)), Some((0.1, 0)));
    assert_eq!(q.pop().map(|e| (e.time, e.i)), Some((0.2, 1)));
    assert_eq!(q.pop(), None, "the stale entries are dropped");
    // simultaneous events go in index order
    q.schedule(2, Some(ev(0.3, 2)));
    q.schedule(1, Some(ev(0.3, 1)));
    assert_eq!(q.pop().map(|e| e.i), Some(1));
}

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
