//! The neighbour list's tests.

use super::*;

#[test]
fn a_list_beyond_its_entry_limit_is_an_out_of_memory_error_and_no_list() {
    // 300 particles of radius 1 within a unit cube: every one is every other's partner,
    // 300 × 299 = 89,700 entries; a limit of 10,000 stops the build (counted every 64
    // particles, so it stops early rather than filling all rows)
    let n = 300;
    let x: Vec<f64> = (0..n)
        .flat_map(|k| [(k as f64 * 0.618) % 1.0, (k as f64 * 0.755) % 1.0, (k as f64 * 0.57) % 1.0])
        .collect();
    let radius = vec![1.0; n];
    let domain = Domain::open(3).unwrap();
    let mut grid = Grid::new();
    let mut list = NeighbourList {
        entry_limit: Some(10_000),
        ..NeighbourList::default()
    };
    let err = list
        .update(&mut grid, &x, &radius, &[], &domain, None, || ListBuild {
            skin: 0.1,
            reach: 0.0,
            collider_scale: 0.0,
        })
        .unwrap_err();
    assert!(matches!(err, Error::OutOfMemory { .. }), "{err}");
    assert!(
        err.to_string()
            .starts_with("the contact list of 300 particles (over 33 neighbours per particle"),
        "{err}"
    );
    assert!(
        err.to_string().contains("within r_i + r_j + 0.100 m, the list's skin"),
        "{err}"
    );
    assert!(list.rows.is_empty() && list.built_at.is_empty(), "no list is left behind");
    list.entry_limit = None;
    list.update(&mut grid, &x, &radius, &[], &domain, None, || ListBuild {
        skin: 0.1,
        reach: 0.0,
        collider_scale: 0.0,
    })
    .unwrap();
    let entries: usize = list.rows.iter().map(|r| r.partners().len()).sum();
    assert_eq!(entries, n * (n - 1));
}
