//! The impulse model's candidate list in a World: a list built for a fast step is rebuilt
//! tight once the particles are slow again (`impulse/impacts.rs`, `prepare`'s `loose`).

use crate::collide::{BoxContainer, Surface};
use crate::forces::Gravity;
use crate::ode::{Integrator, Method};
use crate::world::CollisionParams;
use crate::{World, WorldParams};

#[test]
fn a_pile_at_rest_keeps_no_skin_from_its_fall() {
    // 27 balls (r = 2 cm) dropped 1 m into a box at 60 Hz: falling at up to 4.4 m/s they sweep
    // 7 cm a step, so the list's skin is four of that, 30 cm (the whole box: every ball a
    // candidate of every other). At rest the skin a rebuild chooses is 0.6 r = 1.2 cm: the
    // list must come back to it (within its hysteresis of 4), not keep the fall's.
    let dt = 1.0 / 60.0;
    let mut w = World::new(WorldParams {
        dt,
        method: Integrator::Named(Method::Verlet),
        dim: 3,
    })
    .unwrap();
    let (mut x, r) = (Vec::new(), 0.02);
    for k in 0..27 {
        x.extend([
            0.05 + 0.06 * (k % 3) as f64,
            0.05 + 0.06 * (k / 3 % 3) as f64,
            1.0 + 0.06 * (k / 9) as f64,
        ]);
    }
    let v = vec![0.0; x.len()];
    w.add_particles(&x, &v, &[1.0; 27], &[r; 27], &[false; 27]).unwrap();
    w.add_force(Box::new(Gravity::new([0.0, 0.0, -9.81]).unwrap())).unwrap();
    w.add_collider(BoxContainer::new([0.0; 3], [0.2, 0.2, 2.0], Surface::default()).unwrap())
        .unwrap();
    w.set_collisions(CollisionParams {
        restitution: 0.3,
        friction: 0.5,
        sleep_time: None,
        ..CollisionParams::default()
    })
    .unwrap();
    let skin = |w: &World| w.impulse_list_skin().unwrap();
    let mut largest: f64 = 0.0;
    for _ in 0..(4.0 / dt) as usize {
        w.step().unwrap();
        largest = largest.max(skin(&w));
    }
    assert!(largest > 0.2, "the fall's skin: {largest} m");
    let speed = w.particles().v.iter().fold(0.0_f64, |m, c| m.max(c.abs()));
    assert!(speed < 0.05, "at rest: {speed} m/s");
    assert!(skin(&w) <= 4.0 * 0.6 * r * 1.0000001, "the skin at rest: {} m", skin(&w));
}

#[test]
fn a_lattice_too_fast_for_a_list_of_four_sweeps_is_stepped_on_one_of_two_and_a_half() {
    // 125 balls (r = 3 cm) on a 10 cm lattice thrown down at 10 m/s, at 60 Hz: each sweeps
    // 16.8 cm in the step (v h + g h²/2, and the parabola's bulge g h²/8), so a skin of four
    // sweeps lists nearly every pair. With the list's bound between what that skin and one of
    // 2.5 sweeps need, the step must be taken on the smaller list, not refused.
    let dt = 1.0 / 60.0;
    let (r, v0, g) = (0.03, 10.0, 9.81);
    let mut x = Vec::new();
    for k in 0..125 {
        x.extend([0.1 * (k % 5) as f64, 0.1 * (k / 5 % 5) as f64, 1.0 + 0.1 * (k / 25) as f64]);
    }
    let largest = v0 * dt + 0.5 * g * dt * dt + 0.125 * g * dt * dt;
    // the pairs a list of skin s holds (both sides: a full list), counted by brute force
    let entries = |s: f64| {
        let mut count = 0;
        for i in 0..125 {
            for j in 0..125 {
                let d: f64 = (0..3).map(|k| (x[3 * i + k] - x[3 * j + k]).powi(2)).sum::<f64>().sqrt();
                count += usize::from(i != j && d < 2.0 * r + s);
            }
        }
        count
    };
    let limit = entries(2.6 * largest);
    assert!(
        entries(3.9 * largest) > limit,
        "the test needs a list of four sweeps to pass the bound"
    );
    let mut w = World::new(WorldParams {
        dt,
        method: Integrator::Named(Method::Verlet),
        dim: 3,
    })
    .unwrap();
    let v: Vec<f64> = (0..125).flat_map(|_| [0.0, 0.0, -v0]).collect();
    w.add_particles(&x, &v, &[1.0; 125], &[r; 125], &[false; 125]).unwrap();
    w.add_force(Box::new(Gravity::new([0.0, 0.0, -g]).unwrap())).unwrap();
    w.set_collisions(CollisionParams::default()).unwrap();
    w.set_impulse_list_limit(limit);
    w.step().unwrap();
    let skin = w.impulse_list_skin().unwrap();
    assert!(
        skin < 3.0 * largest && skin >= 2.5 * largest,
        "skin {skin} m, sweep {largest} m"
    );
}
