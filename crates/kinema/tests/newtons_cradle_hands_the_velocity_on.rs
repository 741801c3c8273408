//! Newton's cradle: five equal balls in a row, touching, e = 1. Sequential impulses with the
//! current relative velocity pass the whole velocity along the row, as the real cradle does:
//! one ball in, one ball out; two in, two out. (Momentum and energy conservation alone allow
//! other outcomes; a simultaneous solve spreads the velocity over the row instead.)

use kinema::collide::{resolve, sphere_contacts, Contact, Domain, Grid, Material, MaterialTable, ResolveParams, ResolveStats};

const N: usize = 5;

/// Contacts of the row of touching balls (radius 0.5, centres 1 apart along x): exactly
/// touching pairs need a contact tolerance, and the broad phase the same margin.
fn row_contacts() -> (Vec<f64>, Vec<Contact>) {
    let x: Vec<f64> = (0..N).flat_map(|i| [i as f64, 0.0, 0.0]).collect();
    let radius = [0.5; N];
    let domain = Domain::open(3).unwrap();
    let mut pairs = Vec::new();
    Grid::new().find_pairs(&x, &radius, &domain, 1e-9, &mut pairs).unwrap();
    assert_eq!(pairs, vec![(0, 1), (1, 2), (2, 3), (3, 4)]);
    let mut contacts = Vec::new();
    sphere_contacts(&x, &[0.0; 3 * N], &radius, &pairs, &domain, 1e-9, &mut contacts).unwrap();
    (x, contacts)
}

fn swing(vx: [f64; N], contacts: &[Contact]) -> ([f64; N], ResolveStats) {
    let mut v: Vec<f64> = vx.iter().flat_map(|u| [*u, 0.0, 0.0]).collect();
    let table = MaterialTable::uniform(Material::new(1.0, 0.0).unwrap());
    let stats = resolve(contacts, &mut v, &[1.0; N], &table, &ResolveParams::default()).unwrap();
    let mut out = [0.0; N];
    for i in 0..N {
        out[i] = v[3 * i];
        assert_eq!((v[3 * i + 1], v[3 * i + 2]), (0.0, 0.0));
    }
    (out, stats)
}

fn assert_row(got: [f64; N], want: [f64; N]) {
    for i in 0..N {
        assert!((got[i] - want[i]).abs() < 1e-15, "ball {i}: {got:?} vs {want:?}");
    }
}

#[test]
fn one_ball_in_one_ball_out() {
    let (_, contacts) = row_contacts();
    let (v, stats) = swing([1.0, 0.0, 0.0, 0.0, 0.0], &contacts);
    assert_row(v, [0.0, 0.0, 0.0, 0.0, 1.0]);
    // one sweep hands it along the row (4 impulses), the second finds nothing to do
    assert_eq!((stats.iterations, stats.impulses, stats.converged), (2, 4, true));
    // Σ of the impulses on particles: zero by action = reaction (scale: m v = 1 N·s)
    assert!(stats.particle_impulse_sum.iter().all(|s| s.abs() < 1e-12), "{stats:?}");
    assert!(stats.kinetic_energy_lost.abs() < 1e-15, "e = 1 loses nothing: {stats:?}");
}

#[test]
fn two_balls_in_two_balls_out() {
    let (_, contacts) = row_contacts();
    let (v, stats) = swing([1.0, 1.0, 0.0, 0.0, 0.0], &contacts);
    assert_row(v, [0.0, 0.0, 0.0, 1.0, 1.0]);
    assert!(stats.converged);
    assert!(stats.particle_impulse_sum.iter().all(|s| s.abs() < 1e-12), "{stats:?}");
}

#[test]
fn the_contact_order_changes_the_sweeps_not_the_outcome() {
    // Listed from the far end, each sweep passes the velocity one ball further.
    let (_, mut contacts) = row_contacts();
    contacts.reverse();
    let (v, stats) = swing([1.0, 0.0, 0.0, 0.0, 0.0], &contacts);
    assert_row(v, [0.0, 0.0, 0.0, 0.0, 1.0]);
    assert_eq!((stats.iterations, stats.impulses, stats.converged), (5, 4, true));
    // and from the other side: the last ball swings in
    let (_, contacts) = row_contacts();
    let (v, _) = swing([0.0, 0.0, 0.0, 0.0, -1.0], &contacts);
    assert_row(v, [-1.0, 0.0, 0.0, 0.0, 0.0]);
}

#[test]
fn an_iteration_cap_reports_what_is_left() {
    // One sweep over the reversed list moves the velocity one ball on; the cap stops there
    // and reports the still-approaching pair.
    let (_, mut contacts) = row_contacts();
    contacts.reverse();
    let mut v: Vec<f64> = [1.0, 0.0, 0.0, 0.0, 0.0].iter().flat_map(|u| [*u, 0.0, 0.0]).collect();
    let table = MaterialTable::uniform(Material::new(1.0, 0.0).unwrap());
    let params = ResolveParams {
        max_iterations: 1,
        ..ResolveParams::default()
    };
    let stats = resolve(&contacts, &mut v, &[1.0; N], &table, &params).unwrap();
    assert_eq!((stats.iterations, stats.impulses, stats.converged), (1, 1, false));
    assert_eq!(stats.max_approach_speed, 1.0);
    assert_eq!((v[0], v[3]), (0.0, 1.0));
}
