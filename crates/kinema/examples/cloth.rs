//! The hanging cloth of `benchmarks/springs.py` in Rust alone, for profiling the spring force
//! and the Verlet step without Python: 100 × 100 nodes 1 cm apart (10 g each), the two top
//! corners pinned, under gravity, ~59,000 damped springs, dt = 1e-4 s.
//!
//!     cargo run --release -p kinema --example cloth [steps] [n]

use kinema::forces::{Gravity, Springs};
use kinema::{World, WorldParams};

/// Node spacing, m; node mass, kg; dashpot, N·s/m.
const SPACING: f64 = 0.01;
const MASS: f64 = 0.01;
const DAMPING: f64 = 0.05;

fn main() {
    let mut args = std::env::args().skip(1).map(|a| a.parse::<usize>().expect("a number"));
    let steps = args.next().unwrap_or(3000);
    let n = args.next().unwrap_or(100);
    let mut x = Vec::with_capacity(3 * n * n);
    for r in 0..n {
        for c in 0..n {
            x.extend([c as f64 * SPACING, 0.0, -(r as f64) * SPACING]);
        }
    }
    let id = |r: usize, c: usize| r * n + c;
    let (mut i, mut j, mut k) = (Vec::new(), Vec::new(), Vec::new());
    let mut join = |a: usize, b: usize, stiffness: f64| {
        i.push(a);
        j.push(b);
        k.push(stiffness);
    };
    // the order of benchmarks/springs.py: right, down, down-right, down-left, two right, two down
    for (dr, dc0, dc1, stiffness) in [
        (0, 0, 1, 500.0),
        (1, 0, 0, 500.0),
        (1, 0, 1, 500.0),
        (1, 1, 0, 500.0),
        (0, 0, 2, 100.0),
        (2, 0, 0, 100.0),
    ] {
        let span = dc0.max(dc1);
        for r in 0..n - dr {
            for c in 0..n - span {
                join(id(r, c + dc0), id(r + dr, c + dc1), stiffness);
            }
        }
    }
    let rest: Vec<f64> = i
        .iter()
        .zip(&j)
        .map(|(&a, &b)| ((0..3).map(|q| (x[3 * b + q] - x[3 * a + q]).powi(2)).sum::<f64>()).sqrt())
        .collect();
    let count = i.len();
    let springs = Springs::new(i, j, k, rest, vec![DAMPING; count]).expect("springs");
    let mut pinned = vec![false; n * n];
    pinned[id(0, 0)] = true;
    pinned[id(0, n - 1)] = true;
    let params = WorldParams {
        dt: 1e-4,
        ..WorldParams::default()
    };
    let mut w = World::new(params).expect("world");
    w.add_particles(&x, &vec![0.0; 3 * n * n], &vec![MASS; n * n], &vec![0.0; n * n], &pinned)
        .expect("particles");
    w.add_force(Box::new(Gravity::new([0.0, 0.0, -9.81]).expect("gravity")))
        .expect("gravity");
    w.add_force(Box::new(springs)).expect("springs");
    w.advance(1).expect("setup step");
    let (start, cpu_start) = (std::time::Instant::now(), cpu_seconds());
    w.advance(steps as u64).expect("steps");
    let seconds = start.elapsed().as_secs_f64();
    let cpu = cpu_seconds() - cpu_start;
    // a fingerprint of the final state, to see that a change left the numbers as they were
    let p = w.particles();
    let hash = p.x.iter().chain(&p.v).fold(0xcbf2_9ce4_8422_2325_u64, |h, c| {
        (h ^ c.to_bits()).wrapping_mul(0x0100_0000_01b3)
    });
    println!(
        "{n}x{n} cloth, {count} springs: {steps} steps in {seconds:.3} s, {:.1} steps/s, {:.1} µs of CPU per step, state hash {hash:016x}",
        steps as f64 / seconds,
        1e6 * cpu / steps as f64
    );
}

/// CPU time of all the process's threads so far, s (Linux: the run time in each thread's
/// `schedstat`, ns; 0 elsewhere). Unlike the wall clock it does not count the time other
/// programs hold the cores.
fn cpu_seconds() -> f64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return 0.0;
    };
    let ns: u64 = tasks
        .flatten()
        .filter_map(|t| std::fs::read_to_string(t.path().join("schedstat")).ok())
        .filter_map(|s| s.split_whitespace().next()?.parse::<u64>().ok())
        .sum();
    ns as f64 * 1e-9
}
