//! The event-driven state's tests.

use super::*;
use crate::collide::{Material, Periodic};

/// Uniform numbers in [0, 1) from `seed` (Knuth's MMIX linear congruential generator, the
/// top 53 bits): the same stream on every machine, for the module's tests.
pub(super) fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed;
    move || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A random gas of `n` spheres (radii 0.3–0.5) in a periodic cube of side `side`,
/// placed apart.
fn gas(n: usize, side: f64, seed: u64) -> (Particles, Domain) {
    let mut next = uniform(seed);
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

/// The loop on x86-64-v3's instructions gives the baseline's bits (`simd.rs`): two states of
/// the same gas, with walls (a box closed along z) and a field, run through each version
/// frame by frame, agree to the bit in every position, velocity and impact count.
#[test]
fn the_loop_on_either_instruction_set_gives_the_same_bits() {
    #[cfg(target_arch = "x86_64")]
    {
        if !crate::simd::v3() {
            eprintln!("skipped: this CPU (or KINEMA_SIMD) keeps the baseline only");
            return;
        }
        for (g, periodic_z) in [([0.0; 3], true), ([0.0, 0.0, -0.5], false)] {
            let (p0, _) = gas(400, 10.0, 11);
            let cell = Periodic::new([0.0; 3], [10.0; 3], [true, true, periodic_z]).unwrap();
            let domain = Domain::periodic(3, cell).unwrap();
            let walls: Vec<Collider> = if periodic_z {
                vec![]
            } else {
                vec![Collider::Box(
                    crate::collide::BoxContainer::new([0.0; 3], [10.0; 3], crate::collide::Surface::default()).unwrap(),
                )]
            };
            let table = MaterialTable::uniform(Material::new(0.9, 0.2).unwrap()).with_colliders(&walls);
            let (mut pa, mut pb) = (p0.clone(), p0.clone());
            let mut a = EventDriven::new(&pa, &walls, &domain, None, 0.0, g);
            let mut b = EventDriven::new(&pb, &walls, &domain, None, 0.0, g);
            let (mut books_a, mut books_b) = (
                vec![ColliderBooks::default(); walls.len()],
                vec![ColliderBooks::default(); walls.len()],
            );
            let mut interrupt = Interrupt::none();
            let mut impacts = 0;
            for frame in 1..=10 {
                let t = 0.5 * frame as f64;
                let sa = a
                    .advance_baseline((&mut pa, &table, 0.0, &domain, t, &mut books_a, &mut interrupt))
                    .unwrap();
                // SAFETY: the CPU has x86-64-v3 (checked above)
                let sb = unsafe { b.advance_v3((&mut pb, &table, 0.0, &domain, t, &mut books_b, &mut interrupt)) }.unwrap();
                assert_eq!(sa.impacts, sb.impacts, "frame {frame}");
                impacts += sa.impacts;
                let bits = |v: &[f64]| v.iter().map(|c| c.to_bits()).collect::<Vec<_>>();
                assert_eq!(bits(&pa.x), bits(&pb.x), "positions, frame {frame}");
                assert_eq!(bits(&pa.v), bits(&pb.v), "velocities, frame {frame}");
            }
            assert!(impacts > 500, "{impacts} impacts");
        }
    }
}
