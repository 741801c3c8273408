//! A crowd resolved by the whole impulse pipeline (grid → narrow phase → colliders →
//! sequential impulses with restitution and friction) keeps the books:
//! - Σ m Δv over the movable particles equals the impulse the colliders and the pinned
//!   particles gave (momentum changes only through them), and is zero in a periodic box
//!   without either;
//! - the particle–particle impulses sum to zero (action = reaction);
//! - the kinetic energy lost, measured from the velocities, equals the reported loss, and
//!   is ≥ 0 (e ≤ 1 and friction only dissipate);
//! - no contact approaches at the end, and the same input gives bit-identical output.
//!
//! Then `separate` reduces the overlaps without touching the velocities.

use kinema::collide::{
    collider_contacts, resolve, separate, sphere_contacts, BoxContainer, Collider, Contact, Domain, Grid, Material,
    MaterialTable, Periodic, ResolveParams, ResolveStats, SeparateParams, Surface,
};

/// Splitmix64, uniform in [0, 1).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

struct Crowd {
    x: Vec<f64>,
    v: Vec<f64>,
    mass: Vec<f64>,
    inv_mass: Vec<f64>,
    radius: Vec<f64>,
}

/// `side`³ (or `side`² in 2D) particles on a jittered lattice of spacing 0.2 m in [0, 0.2 side),
/// radii 0.05–0.12 m (so neighbours often overlap), masses 0.5–5 kg, speeds up to 2 m/s; every
/// `pin_every`-th particle pinned (at rest, inverse mass 0), none for 0.
fn crowd(dim: usize, side: usize, seed: u64, pin_every: usize) -> Crowd {
    let mut rng = Rng(seed);
    let n = side.pow(dim as u32);
    let mut c = Crowd {
        x: Vec::with_capacity(3 * n),
        v: Vec::with_capacity(3 * n),
        mass: Vec::with_capacity(n),
        inv_mass: Vec::with_capacity(n),
        radius: Vec::with_capacity(n),
    };
    for p in 0..n {
        let cell = [p % side, (p / side) % side, p / (side * side)];
        for (k, &at) in cell.iter().enumerate() {
            if k < dim {
                c.x.push(0.2 * (at as f64 + 0.5) + 0.06 * (rng.next() - 0.5));
                c.v.push(4.0 * (rng.next() - 0.5));
            } else {
                c.x.push(0.0);
                c.v.push(0.0);
            }
        }
        c.mass.push(0.5 + 4.5 * rng.next());
        c.radius.push(0.05 + 0.07 * rng.next());
        let pinned = pin_every > 0 && p % pin_every == 0;
        c.inv_mass.push(if pinned { 0.0 } else { 1.0 / c.mass[p] });
        if pinned {
            c.v[3 * p..3 * p + 3].fill(0.0);
        }
    }
    c
}

/// Σ m v over the movable particles.
fn momentum(v: &[f64], c: &Crowd) -> [f64; 3] {
    let mut p = [0.0; 3];
    for (i, m) in c.mass.iter().enumerate() {
        if c.inv_mass[i] > 0.0 {
            for k in 0..3 {
                p[k] += m * v[3 * i + k];
            }
        }
    }
    p
}

fn kinetic(v: &[f64], mass: &[f64]) -> f64 {
    mass.iter()
        .enumerate()
        .map(|(i, m)| 0.5 * m * (v[3 * i].powi(2) + v[3 * i + 1].powi(2) + v[3 * i + 2].powi(2)))
        .sum()
}

fn contacts_of(c: &Crowd, domain: &Domain, colliders: &[Collider]) -> Vec<Contact> {
    let mut pairs = Vec::new();
    Grid::new().find_pairs(&c.x, &c.radius, domain, 0.0, &mut pairs).unwrap();
    let mut contacts = Vec::new();
    sphere_contacts(&c.x, &c.v, &c.radius, &pairs, domain, 0.0, &mut contacts).unwrap();
    collider_contacts(colliders, &c.x, &c.v, &c.radius, 0.0, &mut contacts).unwrap();
    contacts
}

/// Resolves the crowd's contacts and checks the books; returns the velocities after.
fn resolve_and_check(c: &Crowd, contacts: &[Contact], colliders: &[Collider]) -> (Vec<f64>, ResolveStats) {
    let table = MaterialTable::uniform(Material::new(0.6, 0.3).unwrap()).with_colliders(colliders);
    let params = ResolveParams {
        max_iterations: 10_000,
        ..ResolveParams::default()
    };
    let mut v = c.v.clone();
    let stats = resolve(contacts, &mut v, &c.inv_mass, &table, &params).unwrap();
    assert!(stats.converged && stats.max_approach_speed <= params.tolerance, "{stats:?}");
    assert!(
        stats.impulses > contacts.len() / 2,
        "too few impulses to test much: {stats:?}"
    );

    let scale: f64 = c
        .mass
        .iter()
        .enumerate()
        .map(|(i, m)| m * c.v[3 * i..3 * i + 3].iter().map(|u| u.abs()).sum::<f64>())
        .sum();
    let (p0, p1) = (momentum(&c.v, c), momentum(&v, c));
    for k in 0..3 {
        let dp = p1[k] - p0[k];
        let external = stats.collider_impulse_sum[k] + stats.pinned_impulse_sum[k];
        assert!(
            (dp - external).abs() <= 1e-12 * scale,
            "Δp[{k}] = {dp} vs walls {:?}",
            stats.collider_impulse_sum
        );
        assert!(stats.particle_impulse_sum[k].abs() <= 1e-12 * scale, "{stats:?}");
    }
    let (e0, e1) = (kinetic(&c.v, &c.mass), kinetic(&v, &c.mass));
    assert!(stats.kinetic_energy_lost >= 0.0 && stats.kinetic_energy_lost < e0);
    assert!(
        ((e0 - e1) - stats.kinetic_energy_lost).abs() <= 1e-12 * e0,
        "measured {} vs reported {}",
        e0 - e1,
        stats.kinetic_energy_lost
    );
    (v, stats)
}

#[test]
fn a_2d_crowd_in_a_box_changes_momentum_only_through_the_walls() {
    let c = crowd(2, 20, 7, 7);
    let walls = [Collider::Box(
        BoxContainer::rect([0.0, 0.0], [4.0, 4.0], Surface::default()).unwrap(),
    )];
    let domain = Domain::open(2).unwrap();
    let contacts = contacts_of(&c, &domain, &walls);
    let wall_contacts = contacts.iter().filter(|k| k.partner_particle().is_none()).count();
    assert!(
        contacts.len() > 100 && wall_contacts > 10,
        "{} contacts, {wall_contacts} on walls",
        contacts.len()
    );
    let (v, stats) = resolve_and_check(&c, &contacts, &walls);
    assert!(stats.collider_impulse_sum.iter().any(|s| s.abs() > 0.0));
    assert!(stats.pinned_impulse_sum.iter().any(|s| s.abs() > 0.0));
    for (i, w) in c.inv_mass.iter().enumerate() {
        if *w == 0.0 {
            assert_eq!(&v[3 * i..3 * i + 3], &[0.0; 3], "pinned particle {i} moved");
        }
    }
    assert!(v.iter().skip(2).step_by(3).all(|z| *z == 0.0), "2D stays in the plane");

    // bit-identical on a second run
    let (again, _) = resolve_and_check(&c, &contacts, &walls);
    assert!(v.iter().zip(&again).all(|(a, b)| a.to_bits() == b.to_bits()));

    // positions: overlaps shrink, velocities are not an argument of `separate`
    let mut x = c.x.clone();
    let mut contacts = contacts;
    let params = SeparateParams {
        iterations: 500,
        ..SeparateParams::default()
    };
    let s = separate(&mut contacts, &mut x, &c.inv_mass, &params).unwrap();
    assert!(
        s.max_overlap_before > 0.01 && s.max_overlap_after < 1e-3 * s.max_overlap_before,
        "{s:?}"
    );
    assert!(x.iter().skip(2).step_by(3).all(|z| *z == 0.0));
}

#[test]
fn a_periodic_3d_crowd_conserves_momentum() {
    let c = crowd(3, 8, 11, 0);
    let p = Periodic::new([0.0; 3], [1.6; 3], [true; 3]).unwrap();
    let domain = Domain::periodic(3, p).unwrap();
    let contacts = contacts_of(&c, &domain, &[]);
    // some contacts must cross the periodic boundary for the test to mean anything
    let across = contacts
        .iter()
        .filter(|k| (c.x[3 * k.i] - c.x[3 * k.partner_particle().unwrap()]).abs() > 0.8)
        .count();
    assert!(
        contacts.len() > 200 && across > 5,
        "{} contacts, {across} across",
        contacts.len()
    );
    let (_, stats) = resolve_and_check(&c, &contacts, &[]);
    assert_eq!(stats.collider_impulse_sum, [0.0; 3]);
    assert_eq!(stats.pinned_impulse_sum, [0.0; 3]);
}
