//! What the collision tests (and `benches/pile_solve.rs`) share: a world of the impulse
//! model, and a small seeded generator. (Each test file uses some of them.)
#![allow(dead_code)]

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

/// Splitmix64, uniform in [0, 1): the same draws on every machine, without a dependency.
pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}
