//! Collision groups (`collide/groups.rs`): two balls in groups that do not collide cross each
//! other as if alone, each still bouncing on the floor, in every contact path: the impulse
//! model (continuous detection and the end-of-step contacts), the Hertz force model and
//! event-driven dynamics. Exact: each ball's state is, to the bit, that of a world where it is
//! alone. The same scene with the groups colliding is not (the test can fail), and a
//! collider's mask lets one group fall through a floor that stops the other.

use kinema::collide::{Plane, Surface};
use kinema::forces::Gravity;
use kinema::ode::{Integrator, Method};
use kinema::world::{CollisionParams, ContactModel};
use kinema::{World, WorldParams};

const R: f64 = 0.1;

/// A ball of each group: group 0 from x = −1 moving +x, group 1 from x = +1 moving −x, both
/// at z = 0.35 over the floor z = 0, crossing at x = 0 after a bounce.
fn balls() -> [([f64; 3], [f64; 3], u32); 2] {
    [
        ([-1.0, 0.0, 0.35], [2.0, 0.0, 0.0], 0),
        ([1.0, 0.0, 0.35], [-2.0, 0.0, 0.0], 1),
    ]
}

fn world(collisions: CollisionParams, dt: f64) -> World {
    let mut w = World::new(WorldParams {
        dt,
        method: Integrator::Named(Method::Verlet),
        dim: 3,
    })
    .unwrap();
    w.set_collisions(collisions).unwrap();
    w.add_collider(Plane::new([0.0; 3], [0.0, 0.0, 1.0], Surface::default()).unwrap())
        .unwrap();
    w.add_force(Box::new(Gravity::earth())).unwrap();
    w
}

/// The balls `which` (indices of [`balls`]) after `steps`, with (0, 1) colliding or not.
fn run(collisions: CollisionParams, dt: f64, steps: u64, which: &[usize], collide: bool) -> (Vec<f64>, Vec<f64>, World) {
    let mut w = world(collisions, dt);
    w.set_group_collisions(0, 1, collide).unwrap();
    for &k in which {
        let (x, v, g) = balls()[k];
        w.add_particles_in_groups(&x, &v, &[1.0], &[R], &[false], Some(&[g])).unwrap();
    }
    w.advance(steps).unwrap();
    (w.particles().x.clone(), w.particles().v.clone(), w)
}

/// Each ball of the pair ends where it ends alone; with the groups colliding it does not.
fn crosses_as_if_alone(collisions: CollisionParams, dt: f64, steps: u64) {
    let (x, v, w) = run(collisions, dt, steps, &[0, 1], false);
    for k in 0..2 {
        let (xa, va, _) = run(collisions, dt, steps, &[k], false);
        assert_eq!(&x[3 * k..3 * k + 3], &xa[..], "ball {k}'s position");
        assert_eq!(&v[3 * k..3 * k + 3], &va[..], "ball {k}'s velocity");
    }
    // they did cross, and bounced on the floor (moving up or down, not resting at z = 0.35)
    assert!(x[0] > 0.5 && x[3] < -0.5, "{x:?}");
    let (_, total) = w.collision_stats().unwrap();
    assert!(total.impacts + total.contacts > 0, "the floor was met: {total:?}");
    let (xc, _, _) = run(collisions, dt, steps, &[0, 1], true);
    assert!(
        xc[0] < 0.0 && xc[3] > 0.0,
        "colliding, the balls bounce back off each other: {xc:?}"
    );
}

#[test]
fn groups_that_do_not_collide_cross_as_if_alone_impulse() {
    crosses_as_if_alone(CollisionParams::default(), 1e-3, 1000);
}

#[test]
fn groups_that_do_not_collide_cross_as_if_alone_hertz() {
    let hertz = CollisionParams {
        model: ContactModel::Hertz {
            youngs_modulus: 1e7,
            poisson_ratio: 0.3,
            cohesion: None,
        },
        ..CollisionParams::default()
    };
    crosses_as_if_alone(hertz, 1e-4, 10_000);
}

#[test]
fn groups_that_do_not_collide_cross_as_if_alone_event_driven() {
    let events = CollisionParams {
        event_driven: true,
        ..CollisionParams::default()
    };
    crosses_as_if_alone(events, 1e-2, 100);
}

#[test]
fn without_self_collisions_no_pair_ever_collides_but_the_floor_holds() {
    for model in [
        ContactModel::Impulse,
        ContactModel::SpringDashpot {
            stiffness: 1e5,
            damping: None,
        },
    ] {
        let params = CollisionParams {
            model,
            self_collisions: false,
            restitution: 0.5,
            ..CollisionParams::default()
        };
        let mut w = world(params, 1e-4);
        // a column of 20 overlapping balls (a jet): nothing pushes them apart
        let n = 20;
        let x: Vec<f64> = (0..n).flat_map(|k| [0.0, 0.0, 0.2 + 0.05 * k as f64]).collect();
        w.add_particles(&x, &vec![0.0; 3 * n], &vec![1.0; n], &vec![R; n], &vec![false; n])
            .unwrap();
        w.advance(8000).unwrap();
        let p = w.particles();
        for k in 0..n {
            assert_eq!(p.x[3 * k], 0.0, "{model:?}: no sideways push");
            assert!(
                p.x[3 * k + 2] > 0.5 * R,
                "{model:?}: ball {k} held by the floor: {}",
                p.x[3 * k + 2]
            );
        }
        assert!(w.contacts().iter().all(|c| c.partner_particle().is_none()), "{model:?}");
    }
}

#[test]
fn a_collider_mask_lets_one_group_through() {
    for event_driven in [false, true] {
        let params = CollisionParams {
            event_driven,
            ..CollisionParams::default()
        };
        let mut w = world(params, 1e-2);
        w.set_collider_mask(0, 0b01).unwrap(); // the floor stops group 0 only
        for (x, g) in [([-1.0, 0.0, 0.5], 0), ([1.0, 0.0, 0.5], 1)] {
            w.add_particles_in_groups(&x, &[0.0; 3], &[1.0], &[R], &[false], Some(&[g]))
                .unwrap();
        }
        w.advance(100).unwrap();
        let z = |k: usize| w.particles().x[3 * k + 2];
        assert!(z(0) > 0.0, "group 0 stays above the floor: {}", z(0));
        assert!(z(1) < -1.0, "group 1 falls through it: {}", z(1));
        assert_eq!(w.collider_masks(), vec![0b01]);
    }
}

#[test]
fn groups_out_of_range_and_of_the_wrong_length_are_refused() {
    let mut w = world(CollisionParams::default(), 1e-3);
    let e = w
        .add_particles_in_groups(&[0.0, 0.0, 1.0], &[0.0; 3], &[1.0], &[R], &[false], Some(&[32]))
        .unwrap_err()
        .to_string();
    assert!(e.contains("group[0]") && e.contains("0..31"), "{e}");
    assert_eq!(w.particles().len(), 0, "nothing added");
    w.add_particles(&[0.0, 0.0, 1.0], &[0.0; 3], &[1.0], &[R], &[false]).unwrap();
    let e = w.set_particle_groups(0, &[1, 2]).unwrap_err().to_string();
    assert!(e.contains("group"), "{e}");
    let e = w.set_group_collisions(40, 0, false).unwrap_err().to_string();
    assert!(e.contains("40") && e.contains("0..31"), "{e}");
    w.set_group_collisions(2, 5, false).unwrap();
    let m = w.group_masks();
    assert!(!m.collide(2, 5) && !m.collide(5, 2) && m.collide(2, 2));
}
