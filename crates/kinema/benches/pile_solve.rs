//! The end-of-step contact solve on a settling pile, as a criterion bench: the kernel where
//! a pile's time goes (`collide/soft_step.rs` through `collide/islands.rs`: the solve stage
//! is 3.85 s of the 4.38 s of CPU the demo's first 3 s take at dt = 1 ms, by `stage_times`).
//!
//! Why a kernel bench beside `benchmarks/`: the Python benchmarks time whole scenes, whose
//! histories move with every change to the physics. Here the physics is fixed (the same
//! pile, the same steps, the same bits), so a change in time is a change in the code's
//! speed alone. A change elsewhere in the engine once made this solve 30 % slower at
//! identical bits, through the compiler's choices of what to inline (issue 46's notes):
//! this bench shows such a swing at once.
//!
//! The scene: `make demo`'s heap at dt = 1 ms (400 balls, r = 2.5–4 cm, 1 kg, on a
//! jittered 5 × 5 × 16 lattice in a 0.5 m box, e = 0.7, no sleeping), landed for 1.5 s in
//! the setup; each sample times the next 50 steps, 1 thread.
//!
//! Run: `cargo bench -p kinema --bench pile_solve` (`make bench` runs it).

use std::time::Duration;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use kinema::collide::{BoxContainer, Surface};
use kinema::forces::Gravity;
use kinema::ode::Method;
use kinema::world::CollisionParams;
use kinema::World;

#[path = "../tests/common/mod.rs"]
mod common;
use common::{impulse_world, Rng};

/// The demo's heap at dt = 1 ms, stepped `landing` steps.
fn heap(landing: u64) -> World {
    let collisions = CollisionParams {
        restitution: 0.7,
        sleep_time: None,
        ..CollisionParams::default()
    };
    let mut w = impulse_world(3, Method::Verlet, 1e-3, collisions);
    let mut rng = Rng(2026);
    let (mut x, mut v, mut radius) = (Vec::new(), Vec::new(), Vec::new());
    for layer in 0..16 {
        for row in 0..5 {
            for col in 0..5 {
                for (k, at) in [col, row, layer].into_iter().enumerate() {
                    let origin = [0.07, 0.07, 0.5][k];
                    x.push(origin + 0.09 * at as f64 + 0.01 * (rng.next() - 0.5));
                    v.push(0.5 * (rng.next() - 0.5));
                }
                radius.push(0.025 + 0.015 * rng.next());
            }
        }
    }
    let n = radius.len();
    w.add_particles(&x, &v, &vec![1.0; n], &radius, &vec![false; n]).unwrap();
    w.add_force(Box::new(Gravity::new([0.0, 0.0, -9.81]).unwrap())).unwrap();
    w.add_collider(BoxContainer::new([0.0; 3], [0.5, 0.5, 3.0], Surface::default()).unwrap())
        .unwrap();
    w.advance(landing).unwrap();
    w
}

fn pile_solve(c: &mut Criterion) {
    // one thread: rayon's global pool, before anything uses it (a World is not Send)
    let _ = rayon::ThreadPoolBuilder::new().num_threads(1).build_global();
    let mut group = c.benchmark_group("pile");
    group.sample_size(10).measurement_time(Duration::from_secs(30));
    group.bench_function("demo heap at 1 ms, 50 steps after 1.5 s", |b| {
        b.iter_batched_ref(|| heap(1500), |w| w.advance(50).unwrap(), BatchSize::PerIteration)
    });
    group.finish();
}

criterion_group!(benches, pile_solve);
criterion_main!(benches);
