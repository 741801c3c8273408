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
