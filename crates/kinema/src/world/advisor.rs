//! The stable-step advisor: the stiffest rates of a world's linearised dynamics, and the
//! largest stable time step of each method for them.

use super::dynamics::ForceJacobian;
use crate::error::CallbackError;
use crate::forces::{Force, Rates as ForceRates, State};
use crate::ode::stability::{oscillator_max_step, StabilityFunction};
use crate::ode::{Integrator, Method, MethodKind};
use crate::vec3::dot_slices as dot;
use num_complex::Complex64;

/// Power iterations at most, per estimate.
const MAX_ITERATIONS: usize = 500;
/// Power iteration stops when the estimate changes by less than this, relatively.
const RELATIVE_CHANGE: f64 = 1e-7;

/// The rates that limit the time step of an explicit method, at one state.
///
/// Linearised about the state, the particles move by M δx'' = K δx + C δv with K = ∂F/∂x and
/// C = ∂F/∂v. A mode u of the symmetrised stiffness M^(−½)(−K)M^(−½) with eigenvalue ω² is an
/// oscillator δx'' = −ω² δx − 2ζω δx', whose damping 2ζω = uᵀ M^(−½)(−C)M^(−½) u is exact
/// when C is diagonal in the modes (proportional damping, as for springs with dashpots in
/// proportion to their stiffness) and the modal estimate otherwise. Methods lose stability
/// first on the stiffest mode; a mode of pure damping (drag) at rate γ is the second limit.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Rates {
    /// ω, rad/s: the highest natural angular frequency, √|λ_max| of M^(−½)(−K)M^(−½) by
    /// power iteration on Jacobian–vector products (a negative λ, an unstable direction such
    /// as an attractor's tidal stretching, counts by its magnitude).
    pub omega: f64,
    /// ζ: the damping ratio of that mode (≥ 0).
    pub zeta: f64,
    /// γ, 1/s: the largest damping rate, the top eigenvalue of M^(−½)(−C)M^(−½).
    pub damping_rate: f64,
    /// Closed-form upper bounds on ω² (1/s²) and γ (1/s), the sum of every force's
    /// [`Force::rates`]; `None` when some force has none.
    pub bound: Option<ForceRates>,
    /// Power iterations used (both estimates together).
    pub iterations: usize,
    /// The stiffest mode a force can reach from other states (a contact not touching yet),
    /// as (ω, rad/s; ζ): [`crate::forces::Rates::standby`]. It limits the step like the others.
    pub standby: Option<(f64, f64)>,
}

impl Rates {
    /// The largest stable step for `method` on these rates, s: the smaller of the stiffest
    /// mode's limit (the damped-oscillator analysis of [`oscillator_max_step`], which covers
    /// symplectic Euler and Verlet as well as the Runge–Kutta methods) and the pure-damping
    /// limit on λ = −γ. Infinite when nothing limits it: implicit Euler is A-stable, and rk45
    /// chooses its own sub-steps inside a world step.
    pub fn max_step(&self, method: &Integrator) -> f64 {
        if matches!(method, Integrator::Named(m) if m.kind() == MethodKind::Adaptive) {
            return f64::INFINITY;
        }
        let oscillation = if self.omega > 0.0 {
            oscillator_max_step(method, self.omega, self.zeta)
        } else {
            f64::INFINITY
        };
        let damping = if self.damping_rate > 0.0 {
            match method {
                // v' = −γ v: symplectic Euler multiplies v by 1 − hγ; Verlet, with its velocity
                // predictor, by 1 − hγ + (hγ)²/2. Both are stable for hγ ≤ 2.
                Integrator::Named(Method::SymplecticEuler | Method::Verlet) => 2.0 / self.damping_rate,
                other => StabilityFunction::of(other).max_step(Complex64::new(-self.damping_rate, 0.0)),
            }
        } else {
            f64::INFINITY
        };
        let standby = match self.standby {
            Some((omega, zeta)) if omega > 0.0 => oscillator_max_step(method, omega, zeta),
            _ => f64::INFINITY,
        };
        oscillation.min(damping).min(standby)
    }
}

/// Estimates the [`Rates`] of the forces at state `s` for particles of inverse masses
/// `inv_mass` (0 = pinned), in `dim` dimensions.
pub(crate) fn estimate(forces: &mut [&mut dyn Force], s: &State, inv_mass: &[f64], dim: usize) -> Result<Rates, CallbackError> {
    let mut rates = declared_rates(forces, s, inv_mass);
    let bound = rates.bound;
    let n = s.x.len();
    // Symmetric scaling M^(−½) on free components, 0 on the filtered ones (pinned, z in 2D):
    // √w_i on each free component of particle i, kept per particle and filtered when read
    // (the same numbers as a vector of 3N filters times √w). The vectors of 3N values are two,
    // the iterate (scaled where it stands when applied: the next iterate is the product's) and
    // the product, besides the Jacobian's and a vector of zeros that is never written (its
    // pages are the system's zero page): at 10⁶ particles each is 24 MB, and the advice runs
    // before the first step, beside everything the step keeps; with five, its peak was the
    // whole run's (issue 51).
    if known_zero(bound, false) && known_zero(bound, true) {
        // the forces declare both rates 0 (a gas of contacts none of which touches yet: its
        // contacts' stiffness is the standby's): no power iteration, and none of its buffers
        // (32 B a particle, made and let go beside the first step's)
        return Ok(rates);
    }
    let root: Vec<f64> = inv_mass.iter().map(|w| w.sqrt()).collect();
    let scale = |k: usize| {
        if inv_mass[k / 3] > 0.0 && !(dim == 2 && k % 3 == 2) {
            root[k / 3]
        } else {
            0.0
        }
    };
    let mut jac = ForceJacobian::default();
    jac.prepare(forces, s, false)?;
    let zero = vec![0.0; n];

    // J_· M^(−½) u for the stiffness (position) or the damping (velocity) part, into y; u is
    // M^(−½) u after it.
    let mut apply = |forces: &mut [&mut dyn Force], u: &mut [f64], velocity: bool, y: &mut [f64]| {
        for (k, c) in u.iter_mut().enumerate() {
            *c *= scale(k);
        }
        if velocity {
            jac.apply(forces, s, &zero, u, y)
        } else {
            jac.apply(forces, s, u, &zero, y)
        }
    };

    let skip = known_zero;
    let mut y = vec![0.0; n];
    for velocity in [false, true] {
        if skip(bound, velocity) {
            continue;
        }
        // Power iteration on M^(−½)(−J_·)M^(−½) from a fixed pseudo-random start (reproducible
        // advice): for a symmetric operator ‖A u_k‖ rises monotonically to |λ|max.
        let mut u: Vec<f64> = (0..n).map(|k| if scale(k) != 0.0 { start(k) } else { 0.0 }).collect();
        let norm = dot(&u, &u).sqrt();
        if norm == 0.0 {
            break; // nothing is free to move
        }
        u.iter_mut().for_each(|a| *a /= norm);
        let mut lambda = 0.0;
        for it in 0..MAX_ITERATIONS {
            apply(forces, &mut u, velocity, &mut y)?;
            for (k, c) in y.iter_mut().enumerate() {
                *c *= -scale(k);
            }
            rates.iterations += 1;
            let next = dot(&y, &y).sqrt();
            if next == 0.0 || !next.is_finite() {
                lambda = if next.is_finite() { 0.0 } else { f64::INFINITY };
                break;
            }
            let done = it > 5 && (next - lambda).abs() <= RELATIVE_CHANGE * next;
            lambda = next;
            for k in 0..n {
                u[k] = y[k] / next;
            }
            if done {
                break;
            }
        }
        if velocity {
            rates.damping_rate = lambda;
        } else {
            rates.omega = lambda.sqrt();
            if rates.omega > 0.0 {
                // The mode's own damping, uᵀ M^(−½)(−C)M^(−½) u = (M^(−½) u)ᵀ(−C)(M^(−½) u) = 2ζω.
                apply(forces, &mut u, true, &mut y)?;
                let modal = (-dot(&u, &y)).max(0.0);
                rates.zeta = modal / (2.0 * rates.omega);
            }
        }
    }
    Ok(rates)
}

/// The rates the forces declare at `s`: the bounds add, and hold when every force has one;
/// the stiffest standby oscillation counts whatever the others say.
fn declared_rates(forces: &[&mut dyn Force], s: &State, inv_mass: &[f64]) -> Rates {
    let mut all = ForceRates::default();
    let mut every = true;
    for f in forces.iter() {
        match f.rates(s, inv_mass) {
            Some(r) => all = all.add(r),
            None => every = false,
        }
    }
    let bound = every.then_some(all);
    let standby = all.standby.map(|s| (s.omega_squared.sqrt(), s.zeta));
    Rates {
        bound,
        standby,
        ..Rates::default()
    }
}

/// Whether the declared bound `b` says the damping rate (`damping`) or the stiffness is 0:
/// no power iteration is needed for it.
fn known_zero(b: Option<ForceRates>, damping: bool) -> bool {
    b.is_some_and(|b| {
        if damping {
            b.damping_rate == 0.0
        } else {
            b.omega_squared == 0.0
        }
    })
}

/// A deterministic pseudo-random number in [−1, 1) for component k (a SplitMix64 hash).
fn start(k: usize) -> f64 {
    let mut z = (k as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}
