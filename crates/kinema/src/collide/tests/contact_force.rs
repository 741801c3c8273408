//! The neighbour list against a search at every evaluation: the forces and energies of
//! [`ContactForce`] are compared bit for bit with a reference that finds the contacts with
//! the O(N²) [`all_pairs`] and the collide kernels at every call and applies the law as
//! written before the list (the material table and ζ per contact), while the particles
//! move: through the sides of a periodic cell, at speeds that force rebuilds.

use super::*;
use crate::collide::oracles::{all_pairs, collider_contacts, sphere_contacts};
use crate::collide::stage::on_periodic_wall;
use crate::collide::{damping_ratio, BoxContainer, MaterialTable, Periodic, Plane, SphereObstacle, Surface};
use crate::error::CallbackError;
use crate::forces::testing::Rng;
use crate::forces::Force;

/// What a [`ContactForce`] reads, owned: the law's constants, the pair materials, the
/// particles' radii and inverse masses, the colliders and the domain (the world keeps them
/// in its particles and collide stage).
struct ContactForceParams {
    stiffness: f64,
    damping: Option<f64>,
    global: Material,
    own: Option<Vec<Material>>,
    radius: Vec<f64>,
    inv_mass: Vec<f64>,
    colliders: Vec<Collider>,
    domain: Domain,
}

/// A spring–dashpot model with what it reads, for the tests: each call goes through a
/// [`ContactForce`] made for it, as the world's do.
struct Owned {
    stiffness: f64,
    damping: Option<f64>,
    global: Material,
    own: Option<Vec<Material>>,
    ratios: Option<Vec<(f64, f64)>>,
    radius: Vec<f64>,
    inv_mass: Vec<f64>,
    colliders: Vec<Collider>,
    domain: Domain,
    model: ContactForceModel,
}

impl Owned {
    fn from_params(p: ContactForceParams) -> Self {
        Owned {
            stiffness: p.stiffness,
            damping: p.damping,
            global: p.global,
            ratios: p.own.as_deref().map(particle_ratios),
            own: p.own,
            radius: p.radius,
            inv_mass: p.inv_mass,
            colliders: p.colliders,
            domain: p.domain,
            model: ContactForceModel::new(p.stiffness, p.damping),
        }
    }

    /// The same force with a neighbour-list skin of `skin` m (0 searches the grid at every
    /// evaluation).
    fn with_skin(mut self, skin: f64) -> Self {
        self.model.skin = Some(skin);
        self
    }

    fn view(&self) -> ContactForce<'_> {
        ContactForce::new(
            &self.model,
            Bodies {
                global: self.global,
                own: self.own.as_deref().zip(self.ratios.as_deref()),
                own_friction: self.own.as_deref().is_some_and(|o| o.iter().any(|m| m.friction() > 0.0)),
                radius: &self.radius,
                inv_mass: &self.inv_mass,
                colliders: &self.colliders,
                domain: &self.domain,
                omega: &[],
                filter: None,
            },
        )
    }

    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        self.view().accumulate(s, f)
    }

    fn potential_energy(&self, s: &State) -> Option<f64> {
        self.view().potential_energy(s)
    }

    fn rates(&self, s: &State, inv_mass: &[f64]) -> Option<crate::forces::Rates> {
        self.view().rates(s, inv_mass)
    }

    fn force_and_kick(&self, s: &State, kick: VerletKick<'_>) -> Result<Option<usize>, Error> {
        self.view().force_and_kick(s, kick)
    }

    fn touches_across(&self, x: &[f64], keep: &[bool]) -> Option<bool> {
        self.view().touches_across(x, keep)
    }

    fn newborns_touch(&self, x: &[f64], v: &[f64], start: usize) -> bool {
        self.view().newborns_touch(x, v, start)
    }

    fn list_builds(&self) -> usize {
        self.model.list_builds()
    }

    fn scratch(&self) -> MutexGuard<'_, Scratch> {
        self.model.scratch()
    }

    fn forget_energy(&self) {
        self.model.forget_energy()
    }

    /// Takes the model's neighbour list (for the force that replaces it).
    fn take_list(&mut self) -> NeighbourList {
        std::mem::take(&mut self.model.scratch().list)
    }

    /// Gives this force the list of the force it replaces after a removal, as the world's
    /// model keeps its own ([`ContactForceModel::retain_survivors`]).
    fn keep_list(&mut self, list: NeighbourList, new_of_old: &[u32]) {
        self.model.scratch().list = list;
        self.model.retain_survivors(new_of_old);
    }

    /// Gives this force the list of the force it replaces after a birth of particles
    /// `start..`, as the world's model admits the newborns into its own.
    fn keep_list_with_newborns(&mut self, list: NeighbourList, x: &[f64], start: usize) -> bool {
        self.model.scratch().list = list;
        self.view().admit_newborns(x, start)
    }
}

/// The state (x, v) of particles of masses `mass` at t = 0.
fn state<'a>(x: &'a [f64], v: &'a [f64], mass: &'a [f64]) -> State<'a> {
    State { t: 0.0, x, v, mass }
}

/// Forces (N) and U (J) from the contacts of an exhaustive search at `s`, by the law as
/// it was written before the neighbour list.
fn reference(force: &Owned, s: &State) -> (Vec<f64>, f64) {
    let (mut pairs, mut contacts, mut walls) = (Vec::new(), Vec::new(), Vec::new());
    all_pairs(s.x, &force.radius, &force.domain, 0.0, &mut pairs).unwrap();
    sphere_contacts(s.x, s.v, &force.radius, &pairs, &force.domain, 0.0, &mut contacts).unwrap();
    collider_contacts(&force.colliders, s.x, s.v, &force.radius, 0.0, &mut walls).unwrap();
    contacts.extend(walls.iter().filter(|c| !on_periodic_wall(c, &force.colliders, &force.domain)));
    let table = MaterialTable::uniform(force.global).with_colliders(&force.colliders);
    let table = match &force.own {
        Some(m) => table.with_particles(m),
        None => table,
    };
    let mut f = vec![0.0; s.x.len()];
    for c in &contacts {
        let w = force.view().inverse_mass_sum(c);
        if c.overlap.is_nan() || c.overlap <= 0.0 || w == 0.0 {
            continue;
        }
        let dashpot = match force.damping {
            Some(gamma) => gamma / w,
            None => 2.0 * damping_ratio(table.pair(c).restitution()).unwrap_or(0.0) * (force.stiffness / w).sqrt(),
        };
        let fn_ = force.stiffness * c.overlap - dashpot * c.u_n;
        for k in 0..3 {
            f[3 * c.i + k] += fn_ * c.normal[k];
            if let Some(j) = c.partner_particle() {
                f[3 * j + k] -= fn_ * c.normal[k];
            }
        }
    }
    let u = contacts
        .iter()
        .filter(|c| c.overlap > 0.0 && force.view().inverse_mass_sum(c) > 0.0)
        .map(|c| 0.5 * force.stiffness * c.overlap * c.overlap)
        .sum();
    (f, u)
}

fn bits(a: &[f64]) -> Vec<u64> {
    a.iter().map(|c| c.to_bits()).collect()
}

struct Scene {
    force: Owned,
    x: Vec<f64>,
    v: Vec<f64>,
    mass: Vec<f64>,
    /// A constant acceleration on every particle, m/s².
    g: [f64; 3],
}

/// Steps `scene` with symplectic Euler (kick with the contact forces and g, then drift,
/// then wrap into the periodic cell as the world does) for `steps` steps of `dt`; at every
/// step the force with the list, the same force rebuilding its list at every call (skin 0)
/// and the exhaustive reference must give the same forces and energies, bit for bit.
/// `kicks` gives particles new velocities before some steps (fast movers). Returns the
/// list's builds and how many times a particle was wrapped through a periodic side.
fn run(mut scene: Scene, steps: usize, dt: f64, kicks: &[(usize, usize, [f64; 3])]) -> (usize, usize) {
    let n = scene.mass.len();
    let mut every_call = Owned::from_params(ContactForceParams {
        stiffness: scene.force.stiffness,
        damping: scene.force.damping,
        global: scene.force.global,
        own: scene.force.own.clone(),
        radius: scene.force.radius.clone(),
        inv_mass: scene.force.inv_mass.clone(),
        colliders: scene.force.colliders.clone(),
        domain: scene.force.domain,
    })
    .with_skin(0.0);
    let (mut touching, mut wrapped) = (0, 0);
    for step in 0..steps {
        for &(when, i, v) in kicks {
            if when == step {
                scene.v[3 * i..3 * i + 3].copy_from_slice(&v);
            }
        }
        let s = State {
            t: 0.0,
            x: &scene.x,
            v: &scene.v,
            mass: &scene.mass,
        };
        let (f_ref, u_ref) = reference(&scene.force, &s);
        let mut f = vec![0.0; 3 * n];
        scene.force.accumulate(&s, &mut f).unwrap();
        let mut f0 = vec![0.0; 3 * n];
        every_call.accumulate(&s, &mut f0).unwrap();
        assert_eq!(bits(&f), bits(&f_ref), "step {step}: forces with the list");
        assert_eq!(bits(&f0), bits(&f_ref), "step {step}: forces with a search at every call");
        let u = scene.force.potential_energy(&s).unwrap();
        assert_eq!(u.to_bits(), u_ref.to_bits(), "step {step}: remembered U {u} vs {u_ref}");
        touching += usize::from(u_ref > 0.0);
        for i in 0..n {
            for k in 0..3 {
                let a = f[3 * i + k] * scene.force.inv_mass[i] + scene.g[k];
                scene.v[3 * i + k] += dt * a;
                scene.x[3 * i + k] += dt * scene.v[3 * i + k];
            }
        }
        if let Some(p) = scene.force.domain.periodic_box() {
            let before = scene.x.clone();
            p.wrap_positions(&mut scene.x);
            wrapped += before.iter().zip(&scene.x).filter(|(a, b)| a != b).count();
        }
    }
    assert!(touching > steps / 2, "contacts in only {touching} of {steps} steps");
    assert_eq!(every_call.list_builds(), steps, "skin 0 searches at every call");
    (scene.force.list_builds(), wrapped)
}

/// Positions, velocities, radii, masses and inverse masses.
type Gas = (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>);

/// What [`gas`] draws: `n` particles of radii in [r/2, r] at random in [lo, hi) (3D, or z = 0
/// in 2D), with `apart`: not overlapping (drawn again where one would overlap an earlier one;
/// the minimum image in `domain`), with speeds up to `speed` (m/s).
struct GasSpec<'a> {
    n: usize,
    r: f64,
    lo: [f64; 3],
    hi: [f64; 3],
    domain: &'a Domain,
    apart: bool,
    speed: f64,
}

/// The particles of `spec` ([`GasSpec`]), with masses in [0.5, 2] kg, the first one pinned.
fn gas(rng: &mut Rng, spec: GasSpec<'_>) -> Gas {
    let GasSpec {
        n,
        r,
        lo,
        hi,
        domain,
        apart,
        speed,
    } = spec;
    let dim = domain.dim();
    let radius = rng.vec(n, 0.5 * r, r);
    let (mut x, mut v): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
    for i in 0..n {
        let p = loop {
            let p = [0, 1, 2].map(|k| if k < dim { rng.uniform(lo[k], hi[k]) } else { 0.0 });
            let clear = !apart
                || (0..i).all(|j| {
                    let d = domain.displacement(p, [x[3 * j], x[3 * j + 1], x[3 * j + 2]]);
                    d[0] * d[0] + d[1] * d[1] + d[2] * d[2] >= (radius[i] + radius[j]).powi(2)
                });
            if clear {
                break p;
            }
        };
        x.extend(p);
        v.extend([0, 1, 2].map(|k| if k < dim { rng.uniform(-speed, speed) } else { 0.0 }));
    }
    let mass = rng.vec(n, 0.5, 2.0);
    let mut inv_mass: Vec<f64> = mass.iter().map(|m| 1.0 / m).collect();
    inv_mass[0] = 0.0;
    (x, v, radius, mass, inv_mass)
}

#[test]
fn a_periodic_gas_crossing_its_cell_gets_the_forces_of_a_search_at_every_call() {
    // A gas in a periodic unit cube (all three axes), r ≤ 4 cm: at up to 1 m/s and
    // dt = 0.25 ms a particle moves up to 0.25 mm a step against a skin of 0.2 mean radii
    // (6 mm), so the list lasts several steps; particles leave through the sides and are
    // wrapped back (their displacements taken as minimum images). Particles 1 and 2
    // are shot across the cell at 40 and 60 m/s for 20 steps (1–1.5 cm a step: a
    // rebuild at every one of those steps).
    let mut rng = Rng::new(7);
    let (lo, hi) = ([0.0; 3], [1.0; 3]);
    let cell = Periodic::new(lo, hi, [true; 3]).unwrap();
    let domain = Domain::periodic(3, cell).unwrap();
    let (x, v, radius, mass, inv_mass) = gas(
        &mut rng,
        GasSpec {
            n: 400,
            r: 0.04,
            lo,
            hi,
            domain: &domain,
            apart: true,
            speed: 1.0,
        },
    );
    let walls = vec![Collider::Box(BoxContainer::new(lo, hi, Surface::default()).unwrap())];
    let material = Material::new(0.5, 0.0).unwrap();
    let force = Owned::from_params(ContactForceParams {
        stiffness: 1e4,
        damping: None,
        global: material,
        own: None,
        radius,
        inv_mass,
        colliders: walls,
        domain,
    });
    let scene = Scene {
        force,
        x,
        v,
        mass,
        g: [0.0; 3],
    };
    let kicks = [
        (100, 1, [40.0, 10.0, -5.0]),
        (100, 2, [-60.0, 0.0, 30.0]),
        (120, 1, [0.0; 3]),
        (120, 2, [0.0; 3]),
    ];
    let (builds, wrapped) = run(scene, 300, 2.5e-4, &kicks);
    eprintln!("periodic gas: {builds} builds in 300 steps, {wrapped} crossings");
    assert!(
        builds >= 20,
        "the fast particles force a rebuild at every step: {builds} builds"
    );
    assert!(builds < 120, "the list is reused: {builds} builds in 300 steps");
    assert!(wrapped > 10, "{wrapped} crossings of the cell's sides");
}

#[test]
fn a_pile_on_colliders_with_own_materials_gets_the_forces_of_a_search_at_every_call() {
    // Open space, a box open at the top, a tilted plane and a sphere obstacle, gravity:
    // particles fall onto the floor and the obstacle and push each other apart. Particles have
    // their own restitutions (0, 1 and equal values included), colliders their own or
    // none, so ζ comes from every branch of the pair rule. One particle is dropped in at
    // 30 m/s (a rebuild at each step until it stops).
    let mut rng = Rng::new(11);
    let (lo, hi) = ([0.0; 3], [0.6, 0.6, f64::INFINITY]);
    let (x, v, radius, mass, inv_mass) = gas(
        &mut rng,
        GasSpec {
            n: 300,
            r: 0.05,
            lo: [0.0; 3],
            hi: [0.6, 0.6, 0.8],
            domain: &Domain::open(3).unwrap(),
            apart: true,
            speed: 0.3,
        },
    );
    let own: Vec<Material> = (0..300)
        .map(|i| {
            let e = match i % 5 {
                0 => 0.0,
                1 => 1.0,
                2 => 0.5,
                _ => rng.uniform(0.0, 1.0),
            };
            Material::new(e, 0.0).unwrap()
        })
        .collect();
    let colliders = vec![
        Collider::Box(BoxContainer::new(lo, hi, Surface::new(None, None).unwrap()).unwrap()),
        Collider::Plane(Plane::new([0.0, 0.0, 0.1], [1.0, 0.0, 3.0], Surface::new(Some(0.3), None).unwrap()).unwrap()),
        Collider::Sphere(SphereObstacle::new([0.3, 0.3, 0.3], 0.1, Surface::new(Some(0.9), None).unwrap()).unwrap()),
    ];
    let material = Material::new(0.4, 0.0).unwrap();
    let force = Owned::from_params(ContactForceParams {
        stiffness: 5e3,
        damping: None,
        global: material,
        own: Some(own),
        radius,
        inv_mass,
        colliders,
        domain: Domain::open(3).unwrap(),
    });
    let scene = Scene {
        force,
        x,
        v,
        mass,
        g: [0.0, 0.0, -9.81],
    };
    let (builds, _) = run(scene, 600, 2e-4, &[(50, 5, [0.0, 0.0, -30.0])]);
    eprintln!("pile: {builds} builds in 600 steps");
    assert!(builds < 200, "the list is reused: {builds} builds in 600 steps");
}

#[test]
fn a_2d_strip_periodic_along_x_with_a_given_damping() {
    // Circles in the xy-plane, periodic along x only, the rectangle's walls along y
    // kept (those along x vanish), γ_n given instead of e. Particle 9 runs at 80 m/s
    // (2 cm a step) for 140 steps, through the gas and the cell's sides.
    let mut rng = Rng::new(3);
    let (lo, hi) = ([-1.0, 0.0, 0.0], [1.0, 0.5, 0.0]);
    let cell = Periodic::new(
        [-1.0, 0.0, f64::NEG_INFINITY],
        [1.0, 0.5, f64::INFINITY],
        [true, false, false],
    )
    .unwrap();
    let domain = Domain::periodic(2, cell).unwrap();
    let (x, v, radius, mass, inv_mass) = gas(
        &mut rng,
        GasSpec {
            n: 200,
            r: 0.03,
            lo,
            hi,
            domain: &domain,
            apart: true,
            speed: 0.5,
        },
    );
    let rect = BoxContainer::rect([-1.0, 0.0], [1.0, 0.5], Surface::default()).unwrap();
    let material = Material::new(0.7, 0.0).unwrap();
    let force = Owned::from_params(ContactForceParams {
        stiffness: 1e4,
        damping: Some(30.0),
        global: material,
        own: None,
        radius,
        inv_mass,
        colliders: vec![Collider::Box(rect)],
        domain,
    });
    let scene = Scene {
        force,
        x,
        v,
        mass,
        g: [0.0, -2.0, 0.0],
    };
    let (builds, wrapped) = run(scene, 400, 2.5e-4, &[(10, 9, [80.0, 5.0, 0.0]), (150, 9, [1.0, 0.0, 0.0])]);
    eprintln!("2D strip: {builds} builds in 400 steps, {wrapped} crossings");
    assert!(wrapped > 3, "{wrapped} crossings of the cell's sides");
    assert!((140..260).contains(&builds), "{builds} builds in 400 steps");
}

#[test]
fn a_head_on_pair_just_outside_the_list_is_caught_before_it_touches() {
    // The worst case of the criterion: two particles (r = 0.1 m, skin s = 0.02 m) start
    // s (1 + 10⁻³) beyond contact, so out of the list, and close head-on at 1 mm each a
    // step. They touch at the 11th step; the two largest moves reach s at the 10th, when
    // the list is rebuilt with them in it. A criterion 30 % looser would miss the touch.
    let x = vec![0.0, 0.0, 0.0, 0.2 + 0.02 * 1.001, 0.0, 0.0, 5.0, 5.0, 5.0];
    let v = vec![1.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let force = Owned::from_params(ContactForceParams {
        stiffness: 10.0,
        damping: None,
        global: Material::new(0.5, 0.0).unwrap(),
        own: None,
        radius: vec![0.1; 3],
        inv_mass: vec![1.0; 3],
        colliders: vec![],
        domain: Domain::open(3).unwrap(),
    })
    .with_skin(0.02);
    let scene = Scene {
        force,
        x,
        v,
        mass: vec![1.0; 3],
        g: [0.0; 3],
    };
    let (builds, _) = run(scene, 40, 1e-3, &[]);
    assert_eq!(builds, 4, "built at steps 0, 10, 20, 30");
}

#[test]
fn the_energy_is_that_of_the_positions_asked_about() {
    // U at x after a force evaluation there is the reference's; at other positions (a
    // particle of an overlapping pair a micrometre away) it is found again, not the last
    // evaluation's.
    let mut rng = Rng::new(5);
    let (x, v, radius, mass, inv_mass) = gas(
        &mut rng,
        GasSpec {
            n: 200,
            r: 0.06,
            lo: [0.0; 3],
            hi: [0.5; 3],
            domain: &Domain::open(3).unwrap(),
            apart: false,
            speed: 1.0,
        },
    );
    let mut force = Owned::from_params(ContactForceParams {
        stiffness: 1e3,
        damping: None,
        global: Material::new(0.5, 0.0).unwrap(),
        own: None,
        radius,
        inv_mass,
        colliders: vec![],
        domain: Domain::open(3).unwrap(),
    });
    let s = state(&x, &v, &mass);
    let mut f = vec![0.0; x.len()];
    force.accumulate(&s, &mut f).unwrap();
    let u = force.potential_energy(&s).unwrap();
    assert!(u > 0.0);
    assert_eq!(u.to_bits(), reference(&force, &s).1.to_bits());
    // a particle of an overlapping pair a micrometre away: found again
    let mut pairs = Vec::new();
    all_pairs(&x, &force.radius, &force.domain, 0.0, &mut pairs).unwrap();
    let (i, _) = pairs[0];
    let mut x2 = x.clone();
    x2[3 * i] += 1e-6;
    let s2 = State { x: &x2, ..s };
    let u2 = force.potential_energy(&s2).unwrap();
    assert_eq!(u2.to_bits(), reference(&force, &s2).1.to_bits());
    assert_ne!(u2.to_bits(), u.to_bits(), "a moved overlap changes U");
    // At NaN positions no force exists: NaN forces (the world then stops the step with
    // SimulationDiverged), and no U
    let mut bad = x.clone();
    bad[4] = f64::NAN;
    let s3 = State { x: &bad, ..s };
    assert!(force.accumulate(&s3, &mut f).is_ok());
    assert!(f.iter().all(|c| c.is_nan()));
    assert_eq!(force.potential_energy(&s3), None);
    // and the rates at s are those of its contacts
    assert!(force.rates(&s, &force.inv_mass.clone()).unwrap().omega_squared > 0.0);
}

#[test]
fn the_allowance_leaves_a_rounding_margin_below_the_skin() {
    // Coordinates 10¹² times the skin leave no room: the list is rebuilt at every call.
    let radius = vec![1e-3; 2];
    let domain = Domain::open(3).unwrap();
    let (mut list, mut grid) = (NeighbourList::default(), Grid::new());
    let x = [0.0, 0.0, 0.0, 1.5e-3, 0.0, 0.0];
    let build = ListBuild {
        skin: 2e-4,
        reach: 0.0,
        collider_scale: 0.0,
    };
    list.update(&mut grid, &x, &radius, &[], &domain, None, || build).unwrap();
    assert!(list.allowance < 2e-4 && list.allowance > 2e-4 * (1.0 - 1e-10));
    assert_eq!(
        (list.rows[0].of(0), list.rows[0].of(1)),
        (&[1][..], &[0][..]),
        "listed from both sides"
    );
    list.update(&mut grid, &x, &radius, &[], &domain, None, || build).unwrap();
    assert_eq!(list.builds, 1, "nothing moved");
    let far = [1e9, 0.0, 0.0, 1e9 + 1.5e-3, 0.0, 0.0];
    list.update(&mut grid, &far, &radius, &[], &domain, None, || build).unwrap();
    assert!(list.allowance < 0.0);
    list.update(&mut grid, &far, &radius, &[], &domain, None, || build).unwrap();
    assert_eq!(list.builds, 3);
    // two particles that together moved the allowance (exactly: half each, along
    // coordinates that were 0): rebuilt; a hair less: kept
    list.update(&mut grid, &x, &radius, &[], &domain, None, || build).unwrap();
    let half = 0.5 * list.allowance;
    assert!(!list.holds(&[-half, 0.0, 0.0, 1.5e-3, half, 0.0], &domain));
    let less = 0.99 * half;
    assert!(list.holds(&[-less, 0.0, 0.0, 1.5e-3, half, 0.0], &domain));
    assert!(!list.holds(&[f64::NAN, 0.0, 0.0, 1.5e-3, 0.0, 0.0], &domain));
}

/// A periodic gas of `n` overlapping particles (drawn anywhere, in creation order: most
/// pairs join particles of different chunks), with the contact force over it.
fn chunked_gas(n: usize) -> (Owned, Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut rng = Rng::new(11);
    let (lo, hi) = ([0.0; 3], [1.0; 3]);
    let domain = Domain::periodic(3, Periodic::new(lo, hi, [true; 3]).unwrap()).unwrap();
    let (x, v, radius, mass, inv_mass) = gas(
        &mut rng,
        GasSpec {
            n,
            r: 0.02,
            lo,
            hi,
            domain: &domain,
            apart: false,
            speed: 1.0,
        },
    );
    let force = Owned::from_params(ContactForceParams {
        stiffness: 1e4,
        damping: None,
        global: Material::new(0.5, 0.0).unwrap(),
        own: None,
        radius,
        inv_mass,
        colliders: Vec::new(),
        domain,
    });
    (force, x, v, mass)
}

#[test]
fn a_gas_of_several_chunks_sums_each_pair_once_the_same_on_any_number_of_threads() {
    // 3 chunks and a part: the half list tests each pair once, from its lower index, and
    // sends the force owed to a particle of a later chunk through the exchange. Against the
    // exhaustive reference (which sums each particle's pairs in another order) the forces
    // agree to a few roundings of the largest; on 1 and 2 threads they are the same bits;
    // Σ F = 0 (each pair gives +F n and −F n exactly) to rounding.
    let n = 3 * CHUNK + 100;
    let (mut force, x, v, mass) = chunked_gas(n);
    let s = state(&x, &v, &mass);
    let on = |threads: usize, force: &mut Owned| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let mut f = vec![0.0; 3 * n];
            force.accumulate(&s, &mut f).unwrap();
            let sent = force.scratch().exchange.sent_count();
            (f, force.potential_energy(&s).unwrap(), sent)
        })
    };
    let (f1, u1, sent) = on(1, &mut force);
    let (f2, u2, _) = on(2, &mut force);
    assert_eq!(bits(&f1), bits(&f2), "forces on 1 and 2 threads");
    assert_eq!(u1.to_bits(), u2.to_bits(), "U on 1 and 2 threads");
    let (f_ref, u_ref) = reference(&force, &s);
    let scale = f_ref.iter().fold(0.0_f64, |m, c| m.max(c.abs()));
    let worst = f1.iter().zip(&f_ref).fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(scale > 0.0 && worst <= 1e-13 * scale, "|F − F_ref| ≤ {worst:e} of {scale:e}");
    assert!((u1 - u_ref).abs() <= 1e-12 * u_ref, "U {u1} vs {u_ref}");
    assert!(sent > 100, "pairs across chunks: {sent} forces exchanged");
    for k in 0..3 {
        let total: f64 = f1.iter().skip(k).step_by(3).sum();
        assert!(total.abs() <= 1e-11 * scale, "Σ F_{k} = {total:e}");
    }
}

/// Each entry of each chunk's rows is owned by the particle whose row holds it
/// (`Rows::owner`, which the first look of the pair pass reads instead of the rows' starts):
/// what a build, a renumbering or an admission of newborns leaves must say so.
fn assert_owners(list: &NeighbourList) {
    for (c, rows) in list.rows.iter().enumerate() {
        assert_eq!(
            rows.owner().len(),
            rows.partners().len(),
            "chunk {c}: an owner for each entry"
        );
        for l in 0..rows.len() {
            let (a, b) = (rows.start()[l] as usize, rows.start()[l + 1] as usize);
            assert!(
                rows.owner()[a..b].iter().all(|&o| o as usize == l),
                "chunk {c}: row {l}'s entries"
            );
        }
    }
}

#[test]
fn a_renumbered_half_list_has_the_rows_of_a_build_in_the_new_order() {
    // A pair (a, b), a < b, sits in a's row; after a renumbering its lower index may be b's
    // new one. The renumbered list must be the list a build at the same positions, in the
    // new order, makes (same rows, each ascending), so that a run that renumbers sums its
    // forces as one that builds.
    let n = 2 * CHUNK + 50;
    let (force, x, _, _) = chunked_gas(n);
    let build = ListBuild {
        skin: 0.02,
        reach: 0.0,
        collider_scale: 0.0,
    };
    let new_list = || NeighbourList {
        half: true,
        ..NeighbourList::default()
    };
    let (mut list, mut grid) = (new_list(), Grid::new());
    list.update(&mut grid, &x, &force.radius, &[], &force.domain, None, || build)
        .unwrap();
    let entries = |l: &NeighbourList| l.rows.iter().map(|r| r.partners().len()).sum::<usize>();
    assert!(entries(&list) > n / 2, "{} pairs", entries(&list));
    // a shuffle: new index of old particle i
    let mut rng = Rng::new(3);
    let mut old_of_new: Vec<u32> = (0..n as u32).collect();
    for i in (1..n).rev() {
        let j = (rng.uniform(0.0, 1.0) * (i + 1) as f64) as usize;
        old_of_new.swap(i, j.min(i));
    }
    let mut new_of_old = vec![0u32; n];
    for (new, &old) in old_of_new.iter().enumerate() {
        new_of_old[old as usize] = new as u32;
    }
    list.renumber(&new_of_old, &old_of_new);
    let moved: Vec<f64> = old_of_new
        .iter()
        .flat_map(|&o| x[3 * o as usize..3 * o as usize + 3].to_vec())
        .collect();
    let radius: Vec<f64> = old_of_new.iter().map(|&o| force.radius[o as usize]).collect();
    let mut fresh = new_list();
    fresh
        .update(&mut grid, &moved, &radius, &[], &force.domain, None, || build)
        .unwrap();
    assert_eq!(list.rows.len(), fresh.rows.len());
    for (c, (a, b)) in list.rows.iter().zip(&fresh.rows).enumerate() {
        assert_eq!(a.start(), b.start(), "chunk {c}: row lengths");
        assert_eq!(a.partners(), b.partners(), "chunk {c}: partners");
        assert_eq!(a.owner(), b.owner(), "chunk {c}: each entry's particle");
    }
    assert_owners(&list);
    for (l, i) in (0..n).map(|i| (i % CHUNK, i)) {
        assert!(
            list.rows[i / CHUNK].of(l).iter().all(|&j| j as usize > i),
            "row {i} holds j > {i} only"
        );
    }
    assert!(
        list.holds(&moved, &force.domain),
        "the build's positions moved with their particles"
    );
}

#[test]
fn after_a_removal_the_kept_list_gives_the_forces_of_a_fresh_one_without_a_search() {
    // A removal takes pairs out of the list and adds none: the force that replaces the old
    // one keeps the survivors' pairs (renumbered), does not search the grid at its first
    // evaluation, and gives the forces of a force built afresh on the survivors, bit for bit
    // (the pairs that do not touch add nothing, and those that do are summed in the same
    // order).
    let n = 2 * CHUNK + 300;
    let (mut force, x, v, mass) = chunked_gas(n);
    let s = state(&x, &v, &mass);
    let mut f = vec![0.0; 3 * n];
    force.accumulate(&s, &mut f).unwrap();
    let builds = force.list_builds();
    // every third particle goes
    let keep: Vec<bool> = (0..n).map(|i| i % 3 != 1).collect();
    let mut new_of_old = vec![crate::particles::GONE; n];
    let mut next = 0u32;
    for (i, _) in keep.iter().enumerate().filter(|(_, k)| **k) {
        new_of_old[i] = next;
        next += 1;
    }
    let pick = |a: &[f64], width: usize| -> Vec<f64> {
        a.chunks(width)
            .zip(&keep)
            .filter(|(_, k)| **k)
            .flat_map(|(c, _)| c.to_vec())
            .collect()
    };
    let (x2, v2, m2) = (pick(&x, 3), pick(&v, 3), pick(&mass, 1));
    let survivors = |force: &Owned| ContactForceParams {
        stiffness: force.stiffness,
        damping: force.damping,
        global: force.global,
        own: None,
        radius: pick(&force.radius, 1),
        inv_mass: pick(&force.inv_mass, 1),
        colliders: Vec::new(),
        domain: force.domain,
    };
    let mut kept = Owned::from_params(survivors(&force));
    kept.keep_list(force.take_list(), &new_of_old);
    assert_eq!(kept.scratch().list.built_at.len(), x2.len(), "a list, before any evaluation");
    let mut fresh = Owned::from_params(survivors(&force));
    let s2 = State {
        t: 0.0,
        x: &x2,
        v: &v2,
        mass: &m2,
    };
    let (mut fk, mut ff) = (vec![0.0; x2.len()], vec![0.0; x2.len()]);
    kept.accumulate(&s2, &mut fk).unwrap();
    fresh.accumulate(&s2, &mut ff).unwrap();
    assert_eq!(kept.list_builds(), builds, "no search: the kept list holds");
    assert_owners(&kept.scratch().list);
    assert_eq!(fresh.list_builds(), 1);
    assert!(ff.iter().any(|c| *c != 0.0), "the survivors touch");
    assert_eq!(bits(&fk), bits(&ff), "the forces of a fresh list");
}

#[test]
fn the_fused_pass_keeps_the_pair_energy_the_runaway_check_asks_for_once() {
    // The fused Verlet pass, asked for the energy, sums Σ ½ k_n δ² on its way; the next
    // potential_energy at the same positions takes that sum (the same bits as a pass of its
    // own), once; after forget_energy, or at other positions, it sums again.
    let n = 2 * CHUNK + 300;
    let (force, x, v, mass) = chunked_gas(n);
    let s = state(&x, &v, &mass);
    let own = force.potential_energy(&s).unwrap();
    assert!(own > 0.0);
    let (mut a, mut v_out) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
    let kick = |a: &'_ mut [f64], v_out: &'_ mut Vec<f64>, energy: bool| {
        force
            .force_and_kick(
                &s,
                VerletKick {
                    other: None,
                    inv_mass: &force.inv_mass,
                    flat: false,
                    h: 1e-4,
                    v: &v,
                    a,
                    v_out,
                    predict: false,
                    energy,
                    spin: None,
                },
            )
            .unwrap();
    };
    kick(&mut a, &mut v_out, true);
    assert_eq!(force.scratch().pair_energy.map(|e| e.1.to_bits()), Some(own.to_bits()));
    assert_eq!(force.potential_energy(&s).unwrap().to_bits(), own.to_bits());
    assert!(force.scratch().pair_energy.is_none(), "taken once");
    kick(&mut a, &mut v_out, false);
    assert!(force.scratch().pair_energy.is_none(), "not asked: not kept");
    kick(&mut a, &mut v_out, true);
    force.forget_energy();
    assert!(force.scratch().pair_energy.is_none());
    // kept for one buffer: other positions (a copy, one sphere moved) are summed afresh
    kick(&mut a, &mut v_out, true);
    let mut moved = x.clone();
    moved[0] += 1e-3;
    let s2 = State { x: &moved, ..s };
    assert_ne!(force.potential_energy(&s2).unwrap().to_bits(), own.to_bits());
}

#[test]
fn the_fused_pass_with_the_predictor_made_where_two_touch_is_the_stored_ones_to_the_bit() {
    // Verlet's predictor v' = v + h a, stored (as the world stores it when another force reads
    // velocities) or made by the contacts where two touch (`predict`): the dashpots see the
    // same numbers, so the new accelerations and velocities are the same bits.
    let n = 2 * CHUNK + 300;
    let (force, x, v, mass) = chunked_gas(n);
    let h = 1e-4;
    let mut rng = Rng::new(5);
    let a0: Vec<f64> = (0..3 * n).map(|_| rng.uniform(-50.0, 50.0)).collect();
    let predictor: Vec<f64> = v
        .iter()
        .zip(&a0)
        .map(|(v, a)| crate::ode::verlet::drift(0.0, *v, *a, h).1)
        .collect();
    let run = |seen: &[f64], predict: bool| {
        let (mut a, mut v_out) = (a0.clone(), vec![f64::NAN; 3 * n]);
        let bad = force
            .force_and_kick(
                &state(&x, seen, &mass),
                VerletKick {
                    other: None,
                    inv_mass: &force.inv_mass,
                    flat: false,
                    h,
                    v: &v,
                    a: &mut a,
                    v_out: &mut v_out,
                    predict,
                    energy: false,
                    spin: None,
                },
            )
            .unwrap();
        assert_eq!(bad, None);
        (a, v_out)
    };
    let (stored, made) = (run(&predictor, false), run(&v, true));
    let bits = |a: &[f64]| a.iter().map(|c| c.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&made.0), bits(&stored.0));
    assert_eq!(bits(&made.1), bits(&stored.1));
    // (the dashpots matter: with the start velocities seen instead, the forces differ)
    assert_ne!(bits(&run(&v, false).0), bits(&stored.0));
}

#[test]
fn after_a_birth_the_admitted_list_gives_the_forces_of_a_fresh_one_without_a_search() {
    // A birth adds the newborns' pairs to the list the force had (each newborn tested
    // against every particle's build position): the force over all particles then needs no
    // search at its first evaluation and gives the forces of a force built afresh, bit for
    // bit, while the old particles have moved since the build (less than the skin allows).
    let n = 2 * CHUNK + 300;
    let born = 150; // the last ones, some overlapping old particles and one another
    let (all, x, v, mass) = chunked_gas(n);
    let params = |count: usize| ContactForceParams {
        stiffness: all.stiffness,
        damping: all.damping,
        global: all.global,
        own: None,
        radius: all.radius[..count].to_vec(),
        inv_mass: all.inv_mass[..count].to_vec(),
        colliders: Vec::new(),
        domain: all.domain,
    };
    let old = n - born;
    let mut before = Owned::from_params(params(old));
    let s_old = State {
        t: 0.0,
        x: &x[..3 * old],
        v: &v[..3 * old],
        mass: &mass[..old],
    };
    before.accumulate(&s_old, &mut vec![0.0; 3 * old]).unwrap();
    let builds = before.list_builds();
    // the old particles move a little (a tenth of the skin, along x) before the birth
    let skin = before.view().skin();
    let mut x1 = x.clone();
    for (i, c) in x1[..3 * old].iter_mut().step_by(3).enumerate() {
        *c += 0.1 * skin * ((i % 7) as f64 / 7.0);
    }
    let mut kept = Owned::from_params(params(n));
    assert!(kept.keep_list_with_newborns(before.take_list(), &x1, old), "admitted");
    assert!(kept.newborns_touch(&x1, &v, old), "this gas's newborns overlap");
    let s = State {
        t: 0.0,
        x: &x1,
        v: &v,
        mass: &mass,
    };
    let mut fresh = Owned::from_params(params(n));
    let (mut fk, mut ff) = (vec![0.0; 3 * n], vec![0.0; 3 * n]);
    kept.accumulate(&s, &mut fk).unwrap();
    fresh.accumulate(&s, &mut ff).unwrap();
    assert_eq!(kept.list_builds(), builds, "no search: the admitted list holds");
    assert_owners(&kept.scratch().list);
    assert!(ff[3 * old..].iter().any(|c| *c != 0.0), "the newborns touch");
    assert_eq!(bits(&fk), bits(&ff), "the forces of a fresh list");

    // Too many newborns at once for one-by-one tests: no list is kept.
    let mut many = Owned::from_params(params(n));
    let mut list = Owned::from_params(params(old));
    list.accumulate(&s_old, &mut vec![0.0; 3 * old]).unwrap();
    let mut taken = list.take_list();
    taken.skin = skin;
    assert!(n * born <= NeighbourList::ADMIT_MAX_TESTS);
    let limit_n = NeighbourList::ADMIT_MAX_TESTS / n + 1;
    assert!(!many.keep_list_with_newborns(taken, &x1, n - limit_n), "a new build instead");
}

#[test]
fn the_list_tells_which_changes_touch() {
    // Two touching pairs and a loner: a removal of the loner touches no survivor, one of a
    // pair's partners does; a newborn far from all touches nothing, one on a particle does.
    let domain = Domain::open(3).unwrap();
    let params = |radius: Vec<f64>| ContactForceParams {
        stiffness: 1e3,
        damping: None,
        global: Material::new(0.5, 0.0).unwrap(),
        own: None,
        inv_mass: vec![1.0; radius.len()],
        radius,
        colliders: Vec::new(),
        domain,
    };
    let x = [0.0, 0.0, 0.0, 0.15, 0.0, 0.0, 1.0, 0.0, 0.0, 1.15, 0.0, 0.0, 3.0, 0.0, 0.0];
    let v = [0.0; 15];
    let mass = [1.0; 5];
    let mut force = Owned::from_params(params(vec![0.1; 5]));
    let s = state(&x, &v, &mass);
    force.accumulate(&s, &mut [0.0; 15]).unwrap();
    assert_eq!(force.touches_across(&x, &[true, true, true, true, false]), Some(false));
    assert_eq!(force.touches_across(&x, &[true, false, true, true, true]), Some(true));
    let far = [50.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    assert_eq!(
        force.touches_across(&far, &[true; 3]),
        None,
        "a list over other particles says nothing"
    );
    for (at, touches) in [(5.0, false), (3.1, true)] {
        let mut x6 = x.to_vec();
        x6.extend([at, 0.0, 0.0]);
        let mut born = Owned::from_params(params(vec![0.1; 6]));
        let mut old = Owned::from_params(params(vec![0.1; 5]));
        old.accumulate(&s, &mut [0.0; 15]).unwrap();
        assert!(born.keep_list_with_newborns(old.take_list(), &x6, 5));
        assert_eq!(born.newborns_touch(&x6, &[0.0; 18], 5), touches, "newborn at x = {at}");
    }
}
