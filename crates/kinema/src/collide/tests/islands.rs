//! The islands' tests: the islands found, and each solved as one solve of all contacts
//! would, on any number of threads.

use super::super::colliders::{Collider, Plane, Surface};
use super::*;
use crate::collide::passes::PARALLEL_COLOUR;

fn floor() -> Vec<Collider> {
    vec![Collider::Plane(
        Plane::new([0.0, 0.0, -0.5], [0.0, 0.0, 1.0], Surface::default()).unwrap(),
    )]
}

/// A cubic block of nx·ny·nz touching unit-mass balls (radius ½, spacing 1) on a floor at
/// z = −½, all falling at 1 m/s (overlapping the floor by `sink` m): its contacts (each
/// touching pair once, lower index first, then the floor) and its velocities.
fn block(nx: usize, ny: usize, nz: usize, sink: f64) -> (Vec<Contact>, Vec<f64>, Vec<f64>) {
    let id = |x: usize, y: usize, z: usize| (z * ny + y) * nx + x;
    let n = nx * ny * nz;
    let mut contacts = Vec::new();
    let pair = |i, j, normal| Contact {
        i,
        other: Partner::Particle(j),
        normal,
        overlap: 0.0,
        u_n: 0.0,
        wall_velocity: [0.0; 3],
    };
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                let i = id(x, y, z);
                if x + 1 < nx {
                    contacts.push(pair(i, id(x + 1, y, z), [-1.0, 0.0, 0.0]));
                }
                if y + 1 < ny {
                    contacts.push(pair(i, id(x, y + 1, z), [0.0, -1.0, 0.0]));
                }
                if z + 1 < nz {
                    contacts.push(pair(i, id(x, y, z + 1), [0.0, 0.0, -1.0]));
                }
            }
        }
    }
    for i in (0..nx * ny).map(|q| id(q % nx, q / nx, 0)) {
        contacts.push(Contact {
            i,
            other: Partner::Collider(0),
            normal: [0.0, 0.0, 1.0],
            overlap: sink,
            u_n: -1.0,
            wall_velocity: [0.0; 3],
        });
    }
    let v = (0..n).flat_map(|_| [0.0, 0.0, -1.0]).collect();
    let x = (0..n)
        .flat_map(|q| [(q % nx) as f64, (q / nx % ny) as f64, (q / (nx * ny)) as f64 - sink])
        .collect();
    (contacts, v, x)
}

const H: f64 = 1e-3;

/// [`solve`] with no island left out as idle.
fn solve_every_island(
    islands: &Islands,
    p: &EndProblem<'_>,
    solved: &mut [[f64; 3]],
    totals: &mut [[f64; 3]],
    v: &[f64],
    x: &mut [f64],
) -> IslandStats {
    solve(
        islands,
        &vec![false; p.contacts.len()],
        p,
        solved,
        totals,
        &mut Vec::new(),
        &mut Vec::new(),
        v,
        x,
    )
    .unwrap()
}

/// The soft-step targets of `block`'s contacts: a step of h in which every ball fell
/// 1 m/s · h, ending `sink` into the floor (they started touching it).
fn targets(contacts: &[Contact]) -> Vec<Target> {
    contacts
        .iter()
        .map(|c| {
            // relative to the floor each ball fell H in the step at 1 m/s, from touching it;
            // the pairs moved together
            let (fell, u1) = match c.partner_particle() {
                None => ([0.0, 0.0, -H], [0.0, 0.0, -1.0]),
                Some(_) => ([0.0; 3], [0.0; 3]),
            };
            Target::new(0.0, 0.0, fell, u1, c.normal, H, None)
        })
        .collect()
}

fn problem<'a>(
    contacts: &'a [Contact],
    targets: &'a [Target],
    inv_mass: &'a [f64],
    floor: &'a [Collider],
    passes: usize,
) -> EndProblem<'a> {
    EndProblem {
        contacts,
        targets,
        inv_mass,
        materials: MaterialTable::uniform(Material::new(0.0, 0.3).unwrap()).with_colliders(floor),
        spin: None,
        rolling: 0.0,
        shock: None,
        params: SoftParams {
            h: H,
            tolerance: 0.0,
            solve_passes: passes,
            relax_passes: passes,
        },
    }
}

#[test]
fn contacts_join_through_movable_particles_only() {
    // 0–1–2 a chain; 3 pinned, touched by 4 and 5: they stay apart; 6 on a wall; 7–8 a
    // pair of two pinned particles, in no island. Islands by first contact.
    let c = |i, other| Contact {
        i,
        other,
        normal: [1.0, 0.0, 0.0],
        overlap: 0.0,
        u_n: 0.0,
        wall_velocity: [0.0; 3],
    };
    let p = Partner::Particle;
    let contacts = [
        c(4, p(3)),
        c(0, p(1)),
        c(3, p(5)),
        c(6, Partner::Collider(0)),
        c(1, p(2)),
        c(7, p(8)),
        c(2, Partner::Collider(0)),
    ];
    let mut inv_mass = vec![1.0; 9];
    for q in [3, 7, 8] {
        inv_mass[q] = 0.0;
    }
    let islands = Islands::find(&contacts, &inv_mass);
    let all: Vec<&[usize]> = (0..islands.len()).map(|k| islands.island(k)).collect();
    assert_eq!(all, [&[0][..], &[1, 4, 6], &[2], &[3]]);
}

#[test]
fn islands_solve_what_one_solve_of_all_contacts_gives() {
    // Three small blocks (below the colouring size): solved island by island, each in list
    // order, they give the whole list's soft step bit for bit (fixed passes: tolerance 0 on
    // a problem that does not converge exactly). They start cold (no warm start), so each
    // gets COLD_PASSES times the passes.
    let (mut contacts, mut v, mut x) = (Vec::new(), Vec::new(), Vec::new());
    for b in 0..3 {
        let (c, bv, bx) = block(3, 3, 2 + b, 1e-3);
        let offset = v.len() / 3;
        contacts.extend(c.into_iter().map(|c| Contact {
            i: c.i + offset,
            other: match c.other {
                Partner::Particle(j) => Partner::Particle(j + offset),
                other => other,
            },
            ..c
        }));
        v.extend(bv);
        x.extend(bx);
    }
    // interleave the blocks' contacts in the list (sorted by particle, as the world's are)
    contacts.sort_by_key(|c| (c.i, c.other));
    let inv_mass = vec![1.0; v.len() / 3];
    let targets = targets(&contacts);
    let islands = Islands::find(&contacts, &inv_mass);
    assert_eq!(islands.len(), 3);
    let floor = floor();
    let p = problem(&contacts, &targets, &inv_mass, &floor, 7);
    let mut solved = vec![[0.0; 3]; contacts.len()];
    let mut totals = vec![[0.0; 3]; contacts.len()];
    let mut x_islands = x.clone();
    let stats = solve_every_island(&islands, &p, &mut solved, &mut totals, &v, &mut x_islands);
    assert_eq!((stats.soft.passes, stats.islands), (7 * COLD_PASSES, 3));

    let mut all_solved = vec![[0.0; 3]; contacts.len()];
    let mut all_totals = Vec::new();
    let (mut v_all, mut x_all) = (v.clone(), x.clone());
    let held = SoftContacts {
        contacts: &contacts,
        targets: &targets,
        inv_mass: &inv_mass,
        materials: &p.materials,
        rotation: None,
        rolling: 0.0,
        shock: None,
    };
    let in_order = [PassGroup::in_order(0..contacts.len())];
    let cold = SoftParams {
        solve_passes: 7 * COLD_PASSES,
        relax_passes: 7 * COLD_PASSES,
        ..p.params
    };
    soft_step::<3>(
        held,
        &cold,
        &mut v_all,
        &mut x_all,
        &mut all_solved,
        &mut all_totals,
        &mut Vec::new(),
        &mut Vec::new(),
        &in_order,
    )
    .unwrap();
    assert_eq!(totals, all_totals);
    assert_eq!(solved, all_solved);
    assert_eq!(x_islands, x_all);
    assert!(totals.iter().any(|t| t[2] != 0.0)); // the floor holds the blocks up
}

#[test]
fn an_idle_island_is_left_out_and_the_solve_gives_the_same_bits() {
    // A block resting on a floor (an island that acts) beside pairs apart, each within
    // the speculative margin: one parting (idle: skipped), one closing within the step
    // beyond its target (acts), one approaching slowly enough that it ends the step short
    // of touching but would close the gap in the next (the relax acts: not idle), and one
    // parting with a warm start (not idle). `soft_step::idle` decides; the solve with the
    // idle islands left out gives what the solve of every island gives, bit for bit.
    let (mut contacts, mut v, mut x) = block(2, 2, 2, 1e-3);
    let mut targets = targets(&contacts);
    let mut warm = vec![[0.0; 3]; contacts.len()];
    // (gap at the step's start, relative displacement over the step, relative velocity)
    let pairs = [
        (0.02, 0.01, 1.0, [0.0; 3]),        // parting: idle
        (0.02, -0.03, -3.0, [0.0; 3]),      // closes beyond the gap in the step
        (0.02, -0.015, -15.0, [0.0; 3]),    // ends 0.005 apart, would close it in the next step
        (0.02, 0.01, 1.0, [0.1, 0.0, 0.0]), // parting, warm-started
    ];
    for (gap, d, u, w) in pairs {
        let i = v.len() / 3;
        v.extend([u, 0.0, 0.0, 0.0, 0.0, 0.0]);
        x.extend([10.0 + i as f64, 0.0, 5.0, 10.0 + i as f64 - 1.0 - gap - d, 0.0, 5.0]);
        contacts.push(Contact {
            i,
            other: Partner::Particle(i + 1),
            normal: [1.0, 0.0, 0.0],
            overlap: -(gap + d),
            u_n: u,
            wall_velocity: [0.0; 3],
        });
        targets.push(Target::new(gap, 0.0, [d, 0.0, 0.0], [u, 0.0, 0.0], [1.0, 0.0, 0.0], H, None));
        warm.push(w);
    }
    let inv_mass = vec![1.0; v.len() / 3];
    let idle: Vec<bool> = contacts
        .iter()
        .zip(&targets)
        .zip(&warm)
        .map(|((c, t), w)| super::super::soft_step::idle(c, t, *w, &inv_mass, None, &v, H))
        .collect();
    let n_block = idle.len() - 4;
    assert_eq!(&idle[n_block..], &[true, false, false, false]);
    // (the block's pairs move together and are idle alone; its floor contacts act, so
    // its island is solved, and with it those pairs)
    let on_floor = |k: usize| contacts[k].partner_particle().is_none();
    assert!((0..n_block).all(|k| idle[k] != on_floor(k)), "{idle:?}");
    let islands = Islands::find(&contacts, &inv_mass);
    assert_eq!(islands.len(), 5);
    let floor = floor();
    let p = problem(&contacts, &targets, &inv_mass, &floor, 50);
    let idle_islands = islands.all_of(&idle);
    assert_eq!(idle_islands.iter().filter(|&&i| i).count(), 1);
    let run = |idle: &[bool]| {
        let (mut solved, mut totals, mut x) = (warm.clone(), vec![[0.0; 3]; contacts.len()], x.clone());
        let stats = solve(
            &islands,
            idle,
            &p,
            &mut solved,
            &mut totals,
            &mut Vec::new(),
            &mut Vec::new(),
            &v,
            &mut x,
        )
        .unwrap();
        (solved, totals, x, stats.soft.active)
    };
    let (skipped, all) = (run(&idle_islands), run(&vec![false; islands.len()]));
    assert!(skipped == all, "leaving the idle island out changed the solve");
    let (_, totals, _, _) = all;
    assert_eq!(totals[n_block], [0.0; 3]); // the parting pair bears nothing
    assert!(totals[n_block + 1][0] > 0.0 && totals[n_block + 2][0] > 0.0); // both closing pairs are stopped
}

#[test]
fn a_coloured_island_is_the_same_on_any_number_of_threads_and_holds_the_block_up() {
    // A block of 16·16·6 balls: 4,416 contacts, one island, coloured, with colours large
    // enough to be swept on threads. Its soft step on 1, 2 and 3 threads, bit for bit; and
    // the physics of a plastic block landing on a floor (e = 0): every ball stops, the
    // floor takes the block's momentum, 1,536 kg · 1 m/s, to the solver's tolerance, and
    // the solve lifts the block out of the floor by the step's fall (it ends touching).
    let (contacts, v, x) = block(16, 16, 6, H);
    let inv_mass = vec![1.0; v.len() / 3];
    let targets = targets(&contacts);
    let islands = Islands::find(&contacts, &inv_mass);
    assert_eq!((islands.len(), islands.island(0).len()), (1, 4416));
    let mut groups = Vec::new();
    colour(islands.island(0), &contacts, &inv_mass, |q| q, &mut groups);
    assert!(
        groups.iter().any(|g| g.together && g.range.len() >= PARALLEL_COLOUR),
        "{groups:?}"
    );
    let floor = floor();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let mut p = problem(&contacts, &targets, &inv_mass, &floor, 2000);
            p.params.tolerance = 1e-12;
            let mut solved = vec![[0.0; 3]; contacts.len()];
            let mut totals = vec![[0.0; 3]; contacts.len()];
            let mut x = x.clone();
            let stats = solve_every_island(&islands, &p, &mut solved, &mut totals, &v, &mut x);
            (totals, x, stats)
        })
    };
    let (one, two, three) = (run(1), run(2), run(3));
    assert!(one == two, "1 and 2 threads differ");
    assert!(one == three, "1 and 3 threads differ");
    let (totals, x_after, stats) = one;
    assert!(stats.soft.converged, "{stats:?}");
    let floor: f64 = totals
        .iter()
        .zip(&contacts)
        .filter(|(_, c)| c.partner_particle().is_none())
        .map(|(t, _)| t[2])
        .sum();
    assert!((floor - 1536.0).abs() < 1e-6, "{floor}");
    let mut after = v.clone();
    for (c, t) in contacts.iter().zip(&totals) {
        vec3::add_scaled(&mut after, c.i, 1.0, *t);
        if let Some(j) = c.partner_particle() {
            vec3::add_scaled(&mut after, j, -1.0, *t);
        }
    }
    let fastest = after.iter().fold(0.0_f64, |m, u| m.max(u.abs()));
    assert!(fastest < 1e-6, "{fastest}");
    // every ball back at its lattice height (the bottom layer touching the floor at −½)
    for (q, z) in x_after.iter().skip(2).step_by(3).enumerate() {
        let layer = (q / 256) as f64;
        assert!((z - layer).abs() < 1e-9, "ball {q} at z = {z}");
    }
}

#[test]
fn shock_propagation_stops_a_deep_column_in_few_sweeps_and_the_floor_takes_its_momentum() {
    // A plastic column of 40 unit balls landing at 1 m/s on a floor, cold, with 10 passes
    // (1 × COLD_PASSES): Gauss–Seidel moves the floor's stop up one ball per pass, and the
    // upper balls end the step sunk into the ones below. With shock propagation every
    // ball ends at its lattice height (the closed form of a column at rest: z = k) and at
    // rest, and the momentum the shock's pushes gave the column (40 kg · 1 m/s in all,
    // with the floor's totals) is what the floor took up.
    let (contacts, v, x) = block(1, 1, 40, H);
    let inv_mass = vec![1.0; 40];
    let targets = targets(&contacts);
    let islands = Islands::find(&contacts, &inv_mass);
    let floor = floor();
    let accel: Vec<f64> = (0..40).flat_map(|_| [0.0, 0.0, -9.81]).collect();
    let run = |shock: Option<&[f64]>| {
        let mut p = problem(&contacts, &targets, &inv_mass, &floor, 1);
        p.shock = shock;
        let (mut solved, mut totals, mut x) = (vec![[0.0; 3]; contacts.len()], vec![[0.0; 3]; contacts.len()], x.clone());
        let mut kicks = Vec::new();
        let every = vec![false; islands.len()];
        solve(
            &islands,
            &every,
            &p,
            &mut solved,
            &mut totals,
            &mut Vec::new(),
            &mut kicks,
            &v,
            &mut x,
        )
        .unwrap();
        let mut after = v.clone();
        for (c, t) in contacts.iter().zip(&totals) {
            vec3::add_scaled(&mut after, c.i, 1.0, *t);
            if let Some(j) = c.partner_particle() {
                vec3::add_scaled(&mut after, j, -1.0, *t);
            }
        }
        for &(q, k) in &kicks {
            vec3::add_scaled(&mut after, q, 1.0, [k[0], k[1], k[2]]);
        }
        let sunk = x
            .iter()
            .skip(2)
            .step_by(3)
            .enumerate()
            .map(|(k, z)| k as f64 - z)
            .fold(0.0, f64::max);
        let pushed: f64 = kicks.iter().map(|(_, k)| k[2]).sum();
        let floor_took: f64 = totals
            .iter()
            .zip(&contacts)
            .filter(|(_, c)| c.partner_particle().is_none())
            .map(|(t, _)| t[2])
            .sum();
        (sunk, after, pushed, floor_took, kicks.iter().all(|(_, k)| k[2] >= 0.0))
    };
    let (sunk, _, _, _, _) = run(None);
    assert!(
        sunk > 0.1 * H,
        "without the shock the passes alone should leave it sunk: {sunk}"
    );
    let (sunk, after, pushed, floor_took, upward) = run(Some(&accel));
    assert!(sunk < 1e-9, "{sunk}");
    let fastest = after.iter().fold(0.0_f64, |m, u| m.max(u.abs()));
    assert!(fastest < 1e-9, "{fastest}");
    assert!(upward && pushed > 0.0, "the shock only pushes up: {pushed}");
    assert!((pushed + floor_took - 40.0).abs() < 1e-9, "{pushed} + {floor_took}");
}
