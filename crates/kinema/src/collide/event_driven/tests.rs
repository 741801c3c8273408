//! The event-driven state's tests.

use super::*;
use crate::collide::{Material, Periodic};

/// A random gas of `n` spheres (radii 0.3–0.5) in a periodic cube of side `side`,
/// placed apart.
fn gas(n: usize, side: f64, seed: u64) -> (Particles, Domain) {
    let mut s = seed;
    let mut next = || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut x: Vec<f64> = Vec::new();
    let mut radius = Vec::new();
    let cell = Periodic::new([0.0; 3], [side; 3], [true; 3]).unwrap();
    let domain = Domain::periodic(3, cell).unwrap();
    while radius.len() < n {
        let (p, r) = ([next() * side, next() * side, next() * side], 0.3 + 0.2 * next());
        let apart = (0..radius.len()).all(|k| {
            let d = domain.displacement(p, vec3::get(&x, k));
            vec3::norm(d) > r + radius[k]
        });
        if apart {
            x.extend_from_slice(&p);
            radius.push(r);
        }
    }
    let v: Vec<f64> = (0..3 * n).map(|_| next() - 0.5).collect();
    let mut p = Particles::default();
    p.add(&x, &v, &vec![1.0; n], &radius, &vec![false; n]).unwrap();
    (p, domain)
}

/// The invariants the event search stands on, after thousands of events: the lists are
/// symmetric; every pair whose centres are within r_i + r_j + δ is listed (the module
/// doc's bound); every particle is within δ/2 of its centre; no two overlap.
#[test]
fn the_lists_hold_every_partner_and_no_spheres_overlap() {
    let (mut p, domain) = gas(300, 9.0, 5);
    let mut state = EventDriven::new(&p, &[], &domain, None, 0.0, [0.0; 3]);
    let table = MaterialTable::uniform(Material::new(1.0, 0.0).unwrap());
    let mut books = [];
    let mut interrupt = Interrupt::none();
    let mut impacts = 0;
    for frame in 1..=20 {
        let t = frame as f64;
        let stats = state
            .advance(&mut p, &table, 0.0, &domain, t, &mut books, &mut interrupt)
            .unwrap();
        impacts += stats.impacts;
        let n = p.len();
        // (each body stays at its own time: where it is at t)
        let at: Vec<[f64; 3]> = state.bodies.iter().map(|b| b.line(t)).collect();
        for i in 0..n {
            let c = state.shells.centre[i];
            let moved = vec3::norm(domain.displacement(at[i], c));
            assert!(
                moved <= 0.5 * state.shells.delta * (1.0 + 1e-12),
                "particle {i} left its shell"
            );
            for j in 0..n {
                if i == j {
                    continue;
                }
                let listed = state.shells.of(i).contains(&(j as u32));
                assert_eq!(
                    listed,
                    state.shells.of(j).contains(&(i as u32)),
                    "lists of {i} and {j} differ"
                );
                let reach = state.radius[i] + state.radius[j] + state.shells.delta;
                if vec3::norm(domain.displacement(c, state.shells.centre[j])) < reach {
                    assert!(listed, "{i} and {j} are within reach but not listed");
                }
                let gap = vec3::norm(domain.displacement(at[i], at[j])) - state.radius[i] - state.radius[j];
                assert!(gap > -1e-9, "{i} and {j} overlap by {}", -gap);
            }
        }
    }
    assert!(impacts > 1000, "{impacts} impacts");
}
