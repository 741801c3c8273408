//! A world that keeps the engine's order between calls (`kinema::world::UserOrder`, as the
//! Python binding holds it) shows only the user's order: what it gathers without moving the
//! particles, and the world it gives, are the user's particles, index for index, and
//! stepping in slices without putting them back gives the bits of one call that does.

use kinema::collide::{BoxContainer, Surface};
use kinema::ode::{Integrator, Method};
use kinema::world::{CollisionParams, ContactModel, UserOrder};
use kinema::{World, WorldParams};

mod common;
use common::Rng;

/// The granular gas of `tests/test_scale.py`: 17³ = 4,913 particles (more than the engine
/// sorts from) on a lattice in a periodic box, spring–dashpot contacts, velocity Verlet;
/// masses and radii cycle so that a particle in the wrong place shows.
fn gas() -> (World, Vec<f64>, Vec<f64>) {
    let (side, a) = (17, (1.0_f64 / 0.3).cbrt());
    let mut rng = Rng(1);
    let (mut x, mut v, mut m, mut r) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for p in 0..side * side * side {
        x.extend([p % side, (p / side) % side, p / (side * side)].map(|q| q as f64 * a));
        v.extend([(); 3].map(|_| 3.4 * (rng.next() - 0.5)));
        m.push(1.0 + (p % 3) as f64 * 0.25);
        r.push(0.5 - (p % 2) as f64 * 0.05);
    }
    let mut w = World::new(WorldParams {
        dt: 1e-3,
        method: Integrator::Named(Method::Verlet),
        dim: 3,
    })
    .unwrap();
    let n = m.len();
    w.add_particles(&x, &v, &m, &r, &vec![false; n]).unwrap();
    let cell = side as f64 * a;
    w.add_collider(BoxContainer::new([0.0; 3], [cell; 3], Surface::default()).unwrap())
        .unwrap();
    w.set_periodic([true; 3]).unwrap();
    w.set_collisions(CollisionParams {
        model: ContactModel::SpringDashpot {
            stiffness: 2000.0,
            damping: Some(50.0),
        },
        ..CollisionParams::default()
    })
    .unwrap();
    (w, m, r)
}

#[test]
fn a_world_kept_in_the_engines_order_shows_the_users() {
    let (world, m, r) = gas();
    let n = m.len();
    let mut kept = UserOrder::new(world);
    for _ in 0..10 {
        kept.advance_in_engine_order(10).unwrap();
    }
    assert!(
        kept.sorts() > 0 && kept.in_engine_order(),
        "the gas is sorted along space between calls"
    );

    // What it gathers, without moving the particles, is the user's order ...
    let (x, v) = (
        kept.in_user_order(|p| &p.x, 3).into_owned(),
        kept.in_user_order(|p| &p.v, 3).into_owned(),
    );
    let ids = kept.in_user_order(|p| &p.id, 1).into_owned();
    assert_eq!(ids, (0..n as u64).collect::<Vec<_>>());
    assert_eq!(*kept.in_user_order(|p| &p.mass, 1), m[..]);
    assert_eq!(*kept.in_user_order(|p| &p.radius, 1), r[..]);
    let (mut xr, mut vr) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
    kept.read_state_into(Some(&mut xr), Some(&mut vr));
    assert!(xr == x && vr == v && kept.state_is(Some(&x), Some(&v), Some(&m)));
    // one array alone reads and compares alone
    let mut x_only = vec![0.0; x.len()];
    kept.read_state_into(Some(&mut x_only), None);
    assert!(x_only == x && kept.state_is(Some(&x), None, None) && kept.state_is(None, None, Some(&m)));
    let mut v_off = v.clone();
    v_off[4] = f64::from_bits(v_off[4].to_bits() ^ 1); // one bit of one velocity
    assert!(!kept.state_is(None, Some(&v_off), None) && kept.state_is(Some(&x), None, Some(&m)));
    assert!(kept.in_engine_order(), "reading moved nothing");

    // ... and the same bits as one call of `World::advance`, which puts them back at its end.
    let (mut plain, _, _) = gas();
    plain.advance(100).unwrap();
    assert!(plain.sorts() > 0);
    let p = plain.particles();
    assert!(p.x == x && p.v == v, "slices kept in the engine's order step as one call");

    // The world it gives is in the user's order, index for index.
    let world = kept.get();
    assert!(world.particles().x == x && world.particles().id == ids);
    assert!(!kept.in_engine_order());

    // Sorted again, an index given to the world is the user's particle: removing particle 5
    // removes the particle of id 5, wherever the engine holds it.
    kept.advance_in_engine_order(200).unwrap();
    assert!(kept.in_engine_order());
    kept.get().remove_particles(&[5]).unwrap();
    let ids = kept.in_user_order(|p| &p.id, 1).into_owned();
    assert!(ids.len() == n - 1 && !ids.contains(&5) && ids.windows(2).all(|w| w[0] < w[1]));
}

/// Every number of `Diagnostics` as bits (equal bits, not equal to rounding).
fn diagnostics_bits(d: &kinema::diagnostics::Diagnostics) -> Vec<u64> {
    let mut out = vec![d.t.to_bits(), d.kinetic.to_bits(), d.rotational.to_bits()];
    out.extend(d.potential.iter().map(|(_, u)| u.to_bits()));
    for a in [&d.momentum[..], &d.angular_momentum, &d.spin, &d.kinetic_tensor] {
        out.extend(a.iter().map(|c| c.to_bits()));
    }
    out
}

#[test]
fn steps_that_measure_their_end_give_the_diagnostics_read_after_them_to_the_bit() {
    // `advance_in_engine_order_measured` (what `World.run` records at each frame) takes the
    // contacts' energy from the last step's own force pass; the diagnostics read after plain
    // steps sum it by a pass of their own. Both are Σ ½ k δ² over the same list in the same
    // order, so every number agrees to the bit, and the steps themselves are the same.
    let (plain, _, _) = gas();
    let (measured, _, _) = gas();
    let (mut plain, mut measured) = (UserOrder::new(plain), UserOrder::new(measured));
    let mut touching = 0;
    for k in [1, 7, 300, 3, 200, 150, 40] {
        plain.advance_in_engine_order(k).unwrap();
        let after = plain.diagnostics();
        let d = measured.advance_in_engine_order_measured(k).unwrap();
        assert_eq!(diagnostics_bits(&d), diagnostics_bits(&after), "after {k} more steps");
        assert_eq!(plain.in_user_order(|p| &p.x, 3), measured.in_user_order(|p| &p.x, 3));
        // read again: the kept sum was let go (a pass of its own gives the same bits)
        assert_eq!(diagnostics_bits(&measured.diagnostics()), diagnostics_bits(&d));
        touching += usize::from(d.potential.iter().any(|(_, u)| *u > 0.0));
    }
    assert!(touching >= 3, "the gas's spheres touch: a contact energy to compare");
}

#[test]
fn steps_that_measure_their_end_and_write_their_state_give_what_a_read_after_them_gives() {
    // `advance_in_engine_order_measured_into` (a frame of `World.run`) writes the positions
    // and velocities in the user's order by the diagnostics' own pass over the engine's
    // order (a scatter through the order's map); reading them after plain steps gathers
    // them (`read_state_into`). The same values, bit for bit, and the same diagnostics.
    let (plain, _, _) = gas();
    let (measured, _, _) = gas();
    let (mut plain, mut measured) = (UserOrder::new(plain), UserOrder::new(measured));
    let n = plain.len();
    let mut sorted = 0;
    for k in [1, 7, 300, 3, 200] {
        plain.advance_in_engine_order(k).unwrap();
        let after = plain.diagnostics();
        let (mut x, mut v) = (vec![f64::NAN; 3 * n], vec![f64::NAN; 3 * n]);
        plain.read_state_into(Some(&mut x), Some(&mut v));
        let (mut x1, mut v1) = (vec![f64::NAN; 3 * n], vec![f64::NAN; 3 * n]);
        let (d, written) = measured.advance_in_engine_order_measured_into(k, &mut x1, &mut v1).unwrap();
        assert!(written, "rooms of 3 N values are written");
        assert_eq!(diagnostics_bits(&d), diagnostics_bits(&after), "after {k} more steps");
        let bits = |a: &[f64]| a.iter().map(|c| c.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&x1), bits(&x), "the positions after {k} more steps");
        assert_eq!(bits(&v1), bits(&v), "the velocities after {k} more steps");
        sorted += usize::from(measured.in_engine_order());
    }
    assert!(
        sorted >= 2,
        "the engine's order differs from the user's: the scatter is tested"
    );
    // rooms of another size are not written (the diagnostics are given all the same)
    let (mut small, mut v) = (vec![f64::NAN; 3 * (n - 1)], vec![f64::NAN; 3 * (n - 1)]);
    let (_, written) = measured.advance_in_engine_order_measured_into(1, &mut small, &mut v).unwrap();
    assert!(!written && small.iter().all(|c| c.is_nan()));
}

#[test]
fn the_membership_count_moves_when_the_set_of_particles_changes_and_only_then() {
    let (world, _, _) = gas();
    let mut kept = UserOrder::new(world);
    let start = kept.membership();
    kept.advance_in_engine_order(20).unwrap();
    assert_eq!(kept.membership(), start, "steps (and sorts) keep the set");
    let w = kept.get();
    w.add_particles(&[0.5, 0.5, 0.5], &[0.0; 3], &[1.0], &[0.1], &[false])
        .unwrap();
    let added = w.membership();
    assert!(added > start, "added");
    w.remove_particles(&[3]).unwrap();
    assert!(w.membership() > added, "removed");
    let n = w.particles().len();
    let removed = w.membership();
    let ids: Vec<u64> = (0..n as u64).map(|i| 10 + i).collect();
    w.restore_clock_and_ids(0.0, 0, &ids, 10 + n as u64).unwrap();
    assert!(w.membership() > removed, "ids restored");
}

#[test]
fn worlds_stepped_side_by_side_on_one_pool_neither_wait_for_each_other_nor_change() {
    // The force models' passes hand each chunk to a chosen thread of the pool
    // (`rayon::broadcast`, contact_force/affinity.rs). Worlds stepped inside that pool's own
    // threads, several at once, must neither deadlock (a thread waiting in one world's pass
    // still runs its share of the other's) nor step otherwise than one by one.
    let alone: Vec<Vec<f64>> = (0..4)
        .map(|_| {
            let (mut w, _, _) = gas();
            w.advance(60).unwrap();
            w.particles().x.clone()
        })
        .collect();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    let together: Vec<Vec<f64>> = pool.install(|| {
        use rayon::prelude::*;
        (0..4)
            .into_par_iter()
            .map(|_| {
                let (mut w, _, _) = gas();
                w.advance(60).unwrap();
                w.particles().x.clone()
            })
            .collect()
    });
    assert_eq!(together, alone);
}
