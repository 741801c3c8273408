//! What the collision tests share: a world of the impulse model.

use kinema::ode::{Integrator, Method};
use kinema::world::CollisionParams;
use kinema::{World, WorldParams};

/// A `dim`-dimensional world stepping by `method` at `dt` (s), with the impulse model's
/// collisions set to `collisions`.
pub fn impulse_world(dim: usize, method: Method, dt: f64, collisions: CollisionParams) -> World {
    let mut w = World::new(WorldParams {
        dt,
        method: Integrator::Named(method),
        dim,
    })
    .unwrap();
    w.set_collisions(collisions).unwrap();
    w
}
