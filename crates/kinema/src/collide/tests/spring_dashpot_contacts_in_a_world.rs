//! The spring–dashpot contact model in a World: the requested restitution comes out, the
//! stable-step advisor counts a contact's stiffness before it touches, and the contact
//! force's neighbour list steps a crowded periodic box exactly as a search at every step.

use super::{all_pairs, collider_contacts, sphere_contacts, Rng};
use crate::collide::{BoxContainer, Domain, Periodic, Plane, Surface};
use crate::forces::Gravity;
use crate::ode::{Integrator, Method};
use crate::world::{CollisionParams, ContactModel};
use crate::{World, WorldParams};

const K: f64 = 1e5; // N/m

fn world(method: Method, dt: f64, e: f64) -> World {
    let mut w = World::new(WorldParams {
        dt,
        method: Integrator::Named(method),
        dim: 3,
    })
    .unwrap();
    w.set_collisions(CollisionParams {
        model: ContactModel::SpringDashpot {
            stiffness: K,
            damping: None,
        },
        restitution: e,
        ..CollisionParams::default()
    })
    .unwrap();
    w
}

/// Two balls (1 kg and 3 kg, r = 0.1 m) meet head-on at 1.5 m/s relative speed; returns the
/// measured e = −(relative velocity after)/(before), once they have separated.
fn measured_restitution(method: Method, dt: f64, e: f64) -> f64 {
    let mut w = world(method, dt, e);
    w.add_particles(
        &[0.0, 0.0, 0.0, 0.25, 0.0, 0.0],
        &[1.0, 0.0, 0.0, -0.5, 0.0, 0.0],
        &[1.0, 3.0],
        &[0.1, 0.1],
        &[false, false],
    )
    .unwrap();
    let steps = (0.5 / dt) as usize;
    for _ in 0..steps {
        w.step().unwrap();
    }
    let v = &w.particles().v;
    -(v[0] - v[3]) / 1.5
}

#[test]
fn the_measured_restitution_is_the_requested_one() {
    // Theory: the overlap obeys the damped oscillator δ'' + γ δ' + ω₀² δ = 0 (ω₀² = k/m_eff),
    // and with ζ = −ln e / √(π² + ln² e) it returns to δ = 0 after half a damped period with
    // e times its entry speed. A step of t_c/100 resolves the contact.
    let m_eff: f64 = 0.75;
    for e in [0.3, 0.5, 0.9] {
        let zeta = -f64::ln(e) / (std::f64::consts::PI.powi(2) + f64::ln(e).powi(2)).sqrt();
        let t_c = std::f64::consts::PI / ((K / m_eff).sqrt() * (1.0 - zeta * zeta).sqrt());
        for method in [Method::Verlet, Method::Rk4] {
            let got = measured_restitution(method, t_c / 100.0, e);
            eprintln!("{method} e = {e}: measured {got:.5}");
            assert!((got / e - 1.0).abs() < 0.02, "{method}, e = {e}: measured {got}");
        }
    }
}

#[test]
fn the_advisor_counts_a_contact_before_it_touches() {
    // Theory: a contact of two free balls is a spring of ω² = k (1/m₁ + 1/m₂); before they touch
    // the advisor must already limit Verlet to 2/ω (less with the dashpot's damping).
    let e = 0.5;
    let mut w = world(Method::Verlet, 1e-3, e);
    w.add_particles(
        &[0.0, 0.0, 0.0, 5.0, 0.0, 0.0],
        &[1.0, 0.0, 0.0, -0.5, 0.0, 0.0],
        &[1.0, 3.0],
        &[0.1, 0.1],
        &[false, false],
    )
    .unwrap();
    let omega = (K * (1.0 + 1.0 / 3.0)).sqrt();
    let h = w.stable_step(&Integrator::Named(Method::Verlet)).unwrap();
    assert!(h <= 2.0 / omega && h > 0.5 / omega, "advised {h} vs 2/ω = {}", 2.0 / omega);
    let rates = w.rates().unwrap();
    let (standby_omega, zeta) = rates.standby.unwrap();
    assert!((standby_omega / omega - 1.0).abs() < 1e-12);
    assert!((zeta - 0.2155).abs() < 1e-3, "ζ = {zeta}");
}

/// The highest total energy (J) over 3 s of a 1 kg ball of radius 0.1 m dropped from 0.5 m
/// onto a floor of contact stiffness k (e = 0.5) under gravity, stepped by `method` at
/// `factor` times the advised step; `None` if the world refused a step as divergent.
fn bouncing_energy(method: Method, factor: f64) -> (f64, Option<f64>) {
    let build = |dt: f64| {
        let mut w = world(method, dt, 0.5);
        w.add_particles(&[0.0, 0.0, 0.5], &[0.0; 3], &[1.0], &[0.1], &[false])
            .unwrap();
        w.add_force(Box::new(Gravity::new([0.0, 0.0, -9.81]).unwrap())).unwrap();
        w.add_collider(Plane::new([0.0; 3], [0.0, 0.0, 1.0], Surface::default()).unwrap())
            .unwrap();
        w
    };
    let advised = build(1e-3).stable_step(&Integrator::Named(method)).unwrap();
    let dt = if advised.is_finite() { factor * advised } else { 1e-3 };
    let mut w = build(dt);
    let e0 = w.diagnostics().total_energy();
    let mut highest = e0;
    for _ in 0..(3.0 / dt) as usize {
        if w.step().is_err() {
            return (e0, None);
        }
        highest = highest.max(w.diagnostics().total_energy());
    }
    (e0, Some(highest))
}

#[test]
fn the_advised_step_separates_stable_from_unstable() {
    // At 0.9 times the advised step every method keeps the bouncing ball's energy bounded:
    // RK4, Heun and Verlet never rise above the start (measured: exactly E₀), while the
    // first-order methods (forward, symplectic and implicit Euler) gain at contact entry —
    // a contact that starts inside a step is felt late — and measured 1.30, 1.22 and 1.07
    // times E₀ at most over 3 s. At 2 times the advised step the contact oscillation
    // amplifies at every bounce: 9.6 to 29 times E₀ within 3 s (or refused as divergent).
    for method in [
        Method::Euler,
        Method::Heun,
        Method::Rk4,
        Method::SymplecticEuler,
        Method::Verlet,
        Method::ImplicitEuler,
    ] {
        let (e0, stable) = bouncing_energy(method, 0.9);
        let highest = stable.unwrap_or_else(|| panic!("{method}: diverged at 0.9 times the advised step"));
        eprintln!("{method}: at 0.9x highest energy {highest:.4} of {e0:.4} J");
        assert!(highest <= 1.5 * e0, "{method}: energy rose to {highest} from {e0}");
        if method != Method::ImplicitEuler {
            let (_, unstable) = bouncing_energy(method, 2.0);
            eprintln!("{method}: at 2x {unstable:?}");
            assert!(
                unstable.is_none_or(|h| h > 5.0 * e0),
                "{method}: stable at twice the advised step"
            );
        }
    }
}

/// A box 0.8 × 0.8 × 0.6 m, periodic along x and y, with a floor and a ceiling: 250 spheres
/// (r in [2, 4] cm, 0.5 to 2 kg) placed apart at random with speeds up to 1 m/s, under
/// gravity, spring–dashpot contacts of k_n = 2·10⁴ N/m and restitution `e`; particle 0 is
/// shot sideways at 60 m/s (3 cm a step at dt = 0.5 ms: through the gas and the periodic
/// sides, a neighbour-list rebuild at each step).
fn crowded_box(method: Method, e: f64) -> World {
    let mut rng = Rng(42);
    let (n, side, height): (usize, f64, f64) = (250, 0.8, 0.6);
    let (mut x, mut v, mut radius, mut mass): (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) = (vec![], vec![], vec![], vec![]);
    while radius.len() < n {
        let r = rng.uniform(0.02, 0.04);
        let p: [f64; 3] = [rng.uniform(0.0, side), rng.uniform(0.0, side), rng.uniform(r, height - r)];
        let apart = (0..radius.len()).all(|j| {
            let d: Vec<f64> = (0..3)
                .map(|k| {
                    let d = p[k] - x[3 * j + k];
                    if k < 2 {
                        d - side * (d / side).round()
                    } else {
                        d
                    }
                })
                .collect();
            d.iter().map(|c| c * c).sum::<f64>() >= (r + radius[j]).powi(2)
        });
        if apart {
            x.extend(p);
            v.extend([rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)]);
            radius.push(r);
            mass.push(rng.uniform(0.5, 2.0));
        }
    }
    v[..3].copy_from_slice(&[60.0, 17.0, 0.0]);
    let mut w = world(method, 5e-4, e);
    w.set_collisions(CollisionParams {
        model: ContactModel::SpringDashpot {
            stiffness: 2e4,
            damping: None,
        },
        restitution: e,
        ..CollisionParams::default()
    })
    .unwrap();
    w.add_particles(&x, &v, &mass, &radius, &vec![false; n]).unwrap();
    w.add_force(Box::new(Gravity::new([0.0, 0.0, -9.81]).unwrap())).unwrap();
    w.add_collider(BoxContainer::new([0.0; 3], [side, side, height], Surface::default()).unwrap())
        .unwrap();
    w.set_periodic([true, true, false]).unwrap();
    w
}

/// U = Σ ½ k_n δ² over the contacts an exhaustive search finds (`all_pairs` and the collide
/// kernels), summed in the contact force's order: pairs by (i, j), then walls particle by
/// particle (the box's walls along the periodic x and y left out).
fn exhaustive_contact_energy(w: &World, k: f64) -> f64 {
    let p = w.particles();
    let domain = Domain::periodic(3, Periodic::new([0.0; 3], [0.8, 0.8, 0.6], [true, true, false]).unwrap()).unwrap();
    let (mut pairs, mut contacts, mut walls) = (Vec::new(), Vec::new(), Vec::new());
    all_pairs(&p.x, &p.radius, &domain, 0.0, &mut pairs).unwrap();
    sphere_contacts(&p.x, &p.v, &p.radius, &pairs, &domain, 0.0, &mut contacts).unwrap();
    collider_contacts(w.colliders(), &p.x, &p.v, &p.radius, 0.0, &mut walls).unwrap();
    contacts.extend(walls.iter().filter(|c| c.normal[0] == 0.0 && c.normal[1] == 0.0));
    contacts
        .iter()
        .filter(|c| c.overlap > 0.0)
        .map(|c| 0.5 * k * c.overlap * c.overlap)
        .sum()
}

#[test]
fn the_neighbour_list_steps_a_world_as_a_search_at_every_step_does() {
    // Two copies of the crowded periodic box; before each step the second one is handed its
    // particles (`particles_mut`), which rebuilds its contact force and so its neighbour
    // list: its contacts come from a full grid search at every step. The trajectories must
    // be the same bit for bit, with the dashpot (RK4, whose steps keep nothing from the
    // last one) and without (Verlet at e = 1, where recomputing the step's first force
    // changes nothing). Along the way the world's contact energy (the runaway check's and
    // `diagnostics`', taken from the last force evaluation where the positions are the same)
    // is that of an exhaustive search.
    for (method, e) in [(Method::Rk4, 0.5), (Method::Verlet, 1.0)] {
        let (mut listed, mut searched) = (crowded_box(method, e), crowded_box(method, e));
        let (mut touching, mut crossings) = (0, 0);
        for step in 0..400 {
            let before = listed.particles().x.clone();
            listed.step().unwrap();
            let after = &listed.particles().x;
            crossings += (0..before.len()).filter(|&k| (after[k] - before[k]).abs() > 0.4).count();
            searched.particles_mut();
            searched.step().unwrap();
            let (a, b) = (listed.particles(), searched.particles());
            let same = |p: &[f64], q: &[f64]| p.iter().zip(q).all(|(s, t)| s.to_bits() == t.to_bits());
            assert!(same(&a.x, &b.x) && same(&a.v, &b.v), "{method}: step {step} differs");
            let diagnostics = listed.diagnostics();
            let (_, u) = diagnostics.potential.iter().find(|(name, _)| name == "contact").unwrap();
            assert_eq!(
                u.to_bits(),
                exhaustive_contact_energy(&listed, 2e4).to_bits(),
                "{method}: step {step}"
            );
            touching += usize::from(*u > 0.0);
        }
        // particles crossed the periodic sides, and touched throughout
        eprintln!(
            "{method}: {crossings} crossings, contacts in {touching} of 400 steps, v0 = {:?}",
            &listed.particles().v[..3]
        );
        assert!(crossings > 10, "{method}: {crossings} crossings");
        assert!(touching > 300, "{method}: contacts in {touching} of 400 steps");
    }
}
