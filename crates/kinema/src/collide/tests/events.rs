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
