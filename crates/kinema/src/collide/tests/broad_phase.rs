use super::super::domain::Periodic;
use super::super::oracles::{all_pairs, grid_pairs, Pair};
use super::*;

/// The pairs of the grid's partner lists (full and half, [`grid_pairs`]) and of the O(N²)
/// search.
fn both(x: &[f64], radius: &[f64], domain: &Domain, margin: f64) -> (Vec<Pair>, Vec<Pair>) {
    let mut slow = Vec::new();
    let fast = grid_pairs(&mut Grid::new(), x, radius, domain, margin);
    all_pairs(x, radius, domain, margin, &mut slow).unwrap();
    (fast, slow)
}

#[test]
fn a_small_line_by_hand() {
    // centres 0, 1, 2.5, 2.875 on x, radii 0.5, 0.5, 0.125, 0.25 (all exact in binary):
    // 0–1 touch at exactly 1.0 (not < 1.0), 1–2 are 1.5 apart (reach 0.625), 2–3 are
    // 0.375 apart (reach 0.375, not <). A margin of 1.25 adds 1–2 (1.5 < 1.875) and 1–3
    // (1.875 < 2.0), not 0–2 (2.5 ≥ 1.875) nor 0–3 (2.875 ≥ 2.0).
    let x = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 2.5, 0.0, 0.0, 2.875, 0.0, 0.0];
    let r = [0.5, 0.5, 0.125, 0.25];
    let d = Domain::open(3).unwrap();
    assert_eq!(both(&x, &r, &d, 0.0), (vec![], vec![]));
    let (fast, slow) = both(&x, &r, &d, 0.01);
    assert_eq!(fast, vec![(0, 1), (2, 3)]);
    assert_eq!(fast, slow);
    let (fast, _) = both(&x, &r, &d, 1.25);
    assert_eq!(fast, vec![(0, 1), (1, 2), (1, 3), (2, 3)]);
}

#[test]
fn pairs_across_a_periodic_boundary_once_even_in_a_two_cell_box() {
    // period 2.0 along x with cells ≥ 1.0 wide: 2 cells, whose −1 and +1 neighbours are
    // the same cell. 0.05 and 1.95 are 0.1 apart through the boundary.
    let p = Periodic::new([0.0; 3], [2.0, 1.0, 1.0], [true, false, false]).unwrap();
    let d = Domain::periodic(2, p).unwrap();
    let x = [0.05, 0.5, 0.0, 1.95, 0.5, 0.0, 1.0, 0.5, 0.0];
    let r = [0.45, 0.45, 0.45];
    let (fast, slow) = both(&x, &r, &d, 0.0);
    assert_eq!(fast, vec![(0, 1)]);
    assert_eq!(fast, slow);
    let mut g = Grid::new();
    let pairs = grid_pairs(&mut g, &x, &r, &d, 0.12);
    assert_eq!(g.cells(), [1, 1, 1]);
    assert_eq!(pairs, vec![(0, 1), (0, 2), (1, 2)]);
}

#[test]
fn a_chain_just_inside_contact_distance_is_found_link_by_link() {
    // Equal radii, neighbours a hair closer than 2r along a line (axis-aligned and
    // diagonal): every link is a pair, and links cross cell boundaries all along. Cells
    // even slightly narrower than 2r would put some neighbours two cells apart.
    let (n, r) = (2000, 0.05);
    for dir in [[1.0, 0.0, 0.0], [0.6, 0.0, 0.8], [0.48, 0.6, 0.64]] {
        for gap in [1e-3, 1e-9, 1e-15] {
            let step = 2.0 * r * (1.0 - gap);
            let x: Vec<f64> = (0..n).flat_map(|k| dir.map(|c| 1.7 + c * step * k as f64)).collect();
            let (fast, slow) = both(&x, &vec![r; n], &Domain::open(3).unwrap(), 0.0);
            assert!(
                fast == slow,
                "direction {dir:?}, gap {gap}: {} pairs, {} expected",
                fast.len(),
                slow.len()
            );
            // at a relative gap of 1e-15 the rounding of the positions decides each link
            if gap > 1e-12 {
                assert_eq!(fast.len(), n - 1, "direction {dir:?}, gap {gap}");
            }
        }
    }
}

#[test]
fn boulders_among_grains_get_levels_of_their_own() {
    // 30 × 30 × 3 grains of radius 0.01 (spacing 0.019: each touches its lattice
    // neighbours), two boulders of radius 0.3 and one of 1.0 resting on and sinking into
    // the bed, in an open and in a periodic domain: three levels, the finest with cells
    // of the grains' size, and exactly the pairs of the O(N²) search, from both sides.
    let (r, a) = (0.01, 0.019);
    let mut x = Vec::new();
    for k in 0..3 {
        for j in 0..30 {
            for i in 0..30 {
                x.extend([i as f64 * a, j as f64 * a, k as f64 * a]);
            }
        }
    }
    let mut radius = vec![r; 2700];
    for (c, big) in [([0.1, 0.1, 0.33], 0.3), ([0.5, 0.3, 0.3], 0.3), ([0.3, 0.3, 1.02], 1.0)] {
        x.extend(c);
        radius.push(big);
    }
    let periodic = Domain::periodic(3, Periodic::new([0.0; 3], [0.57, 0.57, 3.0], [true, true, false]).unwrap());
    for domain in [Domain::open(3).unwrap(), periodic.unwrap()] {
        for margin in [0.0, 0.004] {
            let (fast, slow) = both(&x, &radius, &domain, margin);
            assert!(
                slow.len() > 5000 && slow.iter().any(|&(_, j)| j == 2702),
                "{} pairs",
                slow.len()
            );
            assert_eq!(fast, slow);
            let mut g = Grid::new();
            g.prepare(&x, &radius, &domain, margin).unwrap();
            assert_eq!(g.level_count(), 3);
            assert!(g.cell_width()[0] < 2.0 * (2.0 * r + margin), "{:?}", g.cell_width());
            assert!(g.cell_count() <= 2 * radius.len() + 16 * 3);
        }
    }
}

#[test]
fn sparse_particles_coarsen_the_grid_instead_of_allocating_it() {
    // 3 tiny particles 1e6 m apart would need 1e18 cells of 2e-3 m.
    let x = [0.0, 0.0, 0.0, 1e6, 1e6, 1e6, 1e6, 1e6, 1e6 + 1e-3];
    let r = [1e-3; 3];
    let mut g = Grid::new();
    let pairs = grid_pairs(&mut g, &x, &r, &Domain::open(3).unwrap(), 0.0);
    assert_eq!(pairs, vec![(1, 2)]);
    assert!(g.cells().iter().product::<usize>() <= 2 * 3 + 16, "{:?}", g.cells());
}

#[test]
fn points_beside_balls_make_a_level_of_their_own() {
    // radius 0 with margin 0 (the level's reach is 0: its cells still need a width)
    let x = [0.0, 1.0, 0.0, 0.5, 1.0, 0.0, 0.0, 0.0, 0.0, 0.3, 0.0, 0.0, 0.0, 0.96, 0.0];
    let r = [0.0, 0.0, 0.05, 0.05, 0.05];
    let d = Domain::open(2).unwrap();
    let (fast, slow) = both(&x, &r, &d, 0.0);
    assert_eq!(fast, vec![(0, 4)]);
    assert_eq!(fast, slow);
}

#[test]
fn zero_radii_pair_only_through_the_margin() {
    let x = [0.0; 6];
    let d = Domain::open(2).unwrap();
    assert_eq!(both(&x, &[0.0, 0.0], &d, 0.0).0, vec![]);
    assert_eq!(both(&x, &[0.0, 0.0], &d, 1e-9).0, vec![(0, 1)]);
}

#[test]
fn buffers_are_kept_between_calls() {
    let x: Vec<f64> = (0..300).map(|k| (k as f64 * 0.37).sin() * 3.0).collect();
    let r = vec![0.2; 100];
    let d = Domain::open(3).unwrap();
    let mut g = Grid::new();
    let first = grid_pairs(&mut g, &x, &r, &d, 0.0);
    let caps = |g: &Grid| {
        let l = &g.levels[0];
        (g.cell_of.capacity(), l.start.capacity(), l.order.capacity())
    };
    let before = caps(&g);
    assert_eq!(grid_pairs(&mut g, &x, &r, &d, 0.0), first);
    assert_eq!(before, caps(&g));
}

#[test]
fn bad_input_is_named() {
    let d = Domain::open(3).unwrap();
    let mut pairs = Vec::new();
    let mut g = Grid::new();
    let e = g.prepare(&[0.0; 5], &[1.0; 2], &d, 0.0).unwrap_err().to_string();
    assert!(e.starts_with("x = 5 values is invalid"), "{e}");
    let e = g
        .prepare(&[0.0, 0.0, 0.0, 0.0, f64::INFINITY, 0.0], &[1.0; 2], &d, 0.0)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("x[1][1] = inf is invalid"), "{e}");
    let e = all_pairs(&[0.0; 6], &[1.0, -1.0], &d, 0.0, &mut pairs)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("radius[1] = -1 is invalid"), "{e}");
    let e = all_pairs(&[0.0; 6], &[1.0; 2], &d, f64::NAN, &mut pairs)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("margin = NaN is invalid"), "{e}");
}
