//! Particles placed inside each other or inside a collider are refused before the first step
//! (`collide/placement.rs`), with both contact models, naming how many and the deepest; a
//! placement short of that (overlapping, but each centre outside the other body) steps.
//!
//! The rule: with impulses a pair is refused when d < max(r_i, r_j), the centre of one inside
//! the other; with soft spring–dashpot contacts, which overlap deeply by design, when the
//! centres coincide (no direction to push along). With both, a particle whose centre lies
//! inside a sphere obstacle, behind a plane or outside a box.

use kinema::collide::{Plane, SphereObstacle, Surface};
use kinema::ode::{Integrator, Method};
use kinema::world::{CollisionParams, ContactModel};
use kinema::{Error, World, WorldParams};

fn world(model: ContactModel) -> World {
    let mut w = World::new(WorldParams {
        dt: 1e-3,
        method: Integrator::Named(Method::Verlet),
        dim: 3,
    })
    .unwrap();
    w.set_collisions(CollisionParams {
        model,
        ..CollisionParams::default()
    })
    .unwrap();
    w
}

const MODELS: [ContactModel; 2] = [
    ContactModel::Impulse,
    ContactModel::SpringDashpot {
        stiffness: 1e4,
        damping: None,
    },
];

fn add(w: &mut World, x: &[f64], r: f64) {
    let n = x.len() / 3;
    w.add_particles(x, &vec![0.0; 3 * n], &vec![1.0; n], &vec![r; n], &vec![false; n])
        .unwrap();
}

fn placement(e: Error) -> String {
    assert!(matches!(e, Error::Placement { .. }), "{e}");
    e.to_string()
}

#[test]
fn coincident_particles_are_refused_with_the_count_and_the_deepest_pair() {
    // 4 at one point: 6 pairs, all at distance 0; one more 0.05 m from them, inside each
    // (r = 0.1): 4 more pairs, shallower, refused with impulses only.
    for (model, count) in [(MODELS[0], 10), (MODELS[1], 6)] {
        let mut w = world(model);
        add(&mut w, &[0.0; 12], 0.1);
        add(&mut w, &[0.05, 0.0, 0.0], 0.1);
        let before = w.particles().x.clone();
        let e = placement(w.step().unwrap_err());
        let head = format!("positions: particles 0 and 1 are 0 m apart (radii 0.1 and 0.1 m), the deepest of {count} placements");
        assert!(e.starts_with(&head), "{e}");
        assert_eq!(w.particles().x, before, "nothing moved");
        assert_eq!(w.steps(), 0);
    }
}

#[test]
fn thirty_thousand_coincident_particles_are_refused_at_once_without_their_pairs() {
    // 4.5e8 pairs: the count stops at its limit, nothing of the pairs is kept.
    let mut w = world(ContactModel::Impulse);
    add(&mut w, &vec![0.0; 3 * 30_000], 0.1);
    let e = placement(w.step().unwrap_err());
    assert!(e.contains("the deepest of at least 100000 placements"), "{e}");
}

#[test]
fn a_shallow_overlap_steps_and_a_deep_one_does_not_with_impulses() {
    // r = 0.1: 0.1001 apart (overlap 0.0999 m, each centre just outside the other) steps;
    // 0.0999 apart is refused with impulses and pushed apart by the spring–dashpot.
    for model in MODELS {
        let mut w = world(model);
        add(&mut w, &[0.0, 0.0, 0.0, 0.1001, 0.0, 0.0], 0.1);
        w.step().unwrap();
    }
    let mut w = world(MODELS[0]);
    add(&mut w, &[0.0, 0.0, 0.0, 0.0999, 0.0, 0.0], 0.1);
    let e = placement(w.step().unwrap_err());
    assert!(e.contains("the one placement"), "{e}");
    let mut w = world(MODELS[1]);
    add(&mut w, &[0.0, 0.0, 0.0, 0.0999, 0.0, 0.0], 0.1);
    w.step().unwrap();
    assert!(w.particles().x[3] > 0.0999);
}

#[test]
fn a_centre_inside_a_collider_is_refused_and_one_outside_steps() {
    let surface = Surface::new(None, None).unwrap();
    for model in MODELS {
        let mut w = world(model);
        w.add_collider(SphereObstacle::new([0.0; 3], 100.0, surface).unwrap())
            .unwrap();
        add(&mut w, &[0.0, 0.0, 1.0], 0.1);
        let e = placement(w.step().unwrap_err());
        assert!(
            e.contains("particle 0's centre lies inside colliders[0] (1 m from its centre, radius 100 m)"),
            "{e}"
        );

        let mut w = world(model);
        w.add_collider(Plane::new([0.0; 3], [0.0, 0.0, 1.0], surface).unwrap())
            .unwrap();
        add(&mut w, &[0.0, 0.0, 0.05, 1.0, 0.0, -0.25], 0.1); // the first overlaps the floor by half
        let e = placement(w.step().unwrap_err());
        assert!(
            e.contains("particle 1's centre lies inside colliders[0] (0.25 m behind it)"),
            "{e}"
        );

        let mut w = world(model);
        w.add_collider(Plane::new([0.0; 3], [0.0, 0.0, 1.0], surface).unwrap())
            .unwrap();
        add(&mut w, &[0.0, 0.0, 0.05], 0.1);
        w.step().unwrap();
    }
}

#[test]
fn the_check_runs_for_newcomers_and_for_writes_before_the_first_step_only() {
    let mut w = world(ContactModel::Impulse);
    add(&mut w, &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0], 0.1);
    w.particles_mut().x[3] = 0.0; // particle 1 onto particle 0 before the first step
    placement(w.step().unwrap_err());
    w.particles_mut().x[3] = 1.0;
    w.step().unwrap();
    // a newcomer onto particle 1: refused, named by its index
    add(&mut w, &[1.0, 0.0, 0.0], 0.1);
    let e = placement(w.step().unwrap_err());
    assert!(e.contains("particles 1 and 2 are 0 m apart"), "{e}");
    w.remove_particles(&[2]).unwrap();
    w.step().unwrap();
    // after the first step a write is the user's own dynamics: not checked
    w.particles_mut().x[3] = 0.05;
    w.step().unwrap();
}

#[test]
fn a_centre_exactly_on_a_wall_is_allowed_despite_rounding() {
    // 0.1 + 0.2 + 0.3 = 0.6000000000000001 against a box wall at 0.6.
    let surface = Surface::new(None, None).unwrap();
    let mut w = world(ContactModel::Impulse);
    w.add_collider(kinema::collide::BoxContainer::new([0.0; 3], [1.0, 0.6, 1.0], surface).unwrap())
        .unwrap();
    add(&mut w, &[0.5, 0.1 + 0.2 + 0.3, 0.5], 0.05);
    w.step().unwrap();
}

#[test]
fn shallow_overlaps_at_the_start_are_noticed_with_their_count() {
    // Two pairs overlapping by 10 % and 30 % of r_i + r_j, and a ball 0.02 m into the floor
    // (20 % of its radius): accepted by both models, and noticed once, with the count (3)
    // and the deepest (the 30 % pair); touching ones (δ = 0) are not noticed.
    for model in [
        ContactModel::Impulse,
        ContactModel::SpringDashpot {
            stiffness: 1e4,
            damping: None,
        },
    ] {
        let mut w = World::new(WorldParams::default()).unwrap();
        w.set_collisions(CollisionParams {
            model,
            ..CollisionParams::default()
        })
        .unwrap();
        let x = [
            0.0, 0.0, 1.0, 0.18, 0.0, 1.0, 5.0, 0.0, 1.0, 5.14, 0.0, 1.0, 9.0, 0.0, 0.08, 12.0, 0.0, 1.0, 12.2, 0.0, 1.0,
        ];
        w.add_particles(&x, &[0.0; 21], &[1.0; 7], &[0.1; 7], &[false; 7]).unwrap();
        w.add_collider(Plane::new([0.0; 3], [0.0, 0.0, 1.0], Surface::default()).unwrap())
            .unwrap();
        w.step().unwrap();
        let notice = w.take_placement_notice().expect("noticed");
        assert!(notice.starts_with("3 overlaps at the start"), "{notice}");
        assert!(notice.contains("particles 2 and 3 overlap by 0.06 m"), "{notice}");
        assert_eq!(w.take_placement_notice(), None);
        w.step().unwrap();
        assert_eq!(w.take_placement_notice(), None, "only at the placement's check");
    }
}
