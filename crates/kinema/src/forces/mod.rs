//! Forces on particles: the [`Force`] trait and the catalogue, one force per file.
//!
//! A force adds its contribution F (N) to a flat force array, x y z per particle. Forces that
//! are conservative report their potential energy (J); forces that can, give their Jacobian
//! as products (∂F/∂x)·dx + (∂F/∂v)·dv for implicit integration; the others are
//! differentiated numerically where that is needed.

use crate::error::{CallbackError, Error};

pub mod attractor;
pub mod drag;
pub mod gravity;
pub mod spring;
pub mod wind;

#[cfg(test)]
pub(crate) mod testing;

pub use attractor::Attractor;
pub use drag::Drag;
pub use gravity::Gravity;
pub use spring::{SpringRates, Springs};
pub use wind::Wind;

/// What a force sees of the particles at one instant.
#[derive(Debug, Clone, Copy)]
pub struct State<'a> {
    /// Time, s.
    pub t: f64,
    /// Positions, m (3 per particle).
    pub x: &'a [f64],
    /// Velocities, m/s (3 per particle).
    pub v: &'a [f64],
    /// Masses, kg (pinned particles keep theirs).
    pub mass: &'a [f64],
}

impl State<'_> {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.mass.len()
    }
    /// Whether there are no particles.
    pub fn is_empty(&self) -> bool {
        self.mass.is_empty()
    }
}

/// A force acting on the particles of a world.
pub trait Force {
    /// Short name for diagnostics and messages (`"gravity"`, `"spring"`).
    fn name(&self) -> &str;

    /// Adds this force to `f` (N, 3 per particle).
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError>;

    /// Checks the force against a world of `n` particles (indices in range, ...).
    fn validate(&self, _n: usize) -> Result<(), Error> {
        Ok(())
    }

    /// Potential energy, J, for a conservative force (F = −∇U); `None` otherwise.
    fn potential_energy(&self, _s: &State) -> Option<f64> {
        None
    }

    /// Whether F depends on the velocities.
    fn depends_on_velocity(&self) -> bool {
        false
    }

    /// Whether this force is internal: a sum of pairs acting equally and oppositely, so that
    /// it changes no total momentum.
    fn is_internal(&self) -> bool {
        false
    }

    /// Adds (∂F/∂x)·dx + (∂F/∂v)·dv to `out` when the force knows its Jacobian; returns
    /// `false` (and adds nothing) when it does not.
    fn jacobian_product(&self, _s: &State, _dx: &[f64], _dv: &[f64], _out: &mut [f64]) -> bool {
        false
    }

    /// Like [`Force::jacobian_product`], but with the parts that can make the implicit
    /// system indefinite dropped, so that conjugate gradients can solve it (Choi & Ko 2002:
    /// a spring in compression loses its transverse stiffness). Defaults to the exact product.
    fn definite_jacobian_product(&self, s: &State, dx: &[f64], dv: &[f64], out: &mut [f64]) -> bool {
        self.jacobian_product(s, dx, dv, out)
    }

    /// Adds c_x·diag(∂F/∂x) + c_v·diag(∂F/∂v) of the definite Jacobian (see
    /// [`Force::definite_jacobian_product`]) to `out`, for the Jacobi preconditioner of the
    /// implicit solve; returns `false` (adding nothing) when the force does not provide it.
    fn jacobian_diagonal(&self, _s: &State, _cx: f64, _cv: f64, _out: &mut [f64]) -> bool {
        false
    }

    /// Whether the force can add mechanical energy to the particles (wind, a user's force).
    /// Conservative forces (their work is counted in their potential energy) and dissipative
    /// ones (drag, dashpots) cannot; the world watches for runaway energy only when no force
    /// can add it.
    fn can_add_energy(&self) -> bool {
        true
    }

    /// Closed-form upper bounds, at state `s`, on the rates this force gives the particles
    /// (inverse masses `inv_mass`, 0 for pinned ones): ω² ≥ every |eigenvalue| of M⁻¹ ∂F/∂x
    /// and γ ≥ every |eigenvalue| of M⁻¹ ∂F/∂v, each an ∞-norm (Gershgorin) bound so that the
    /// bounds of several forces add. `None` when the force has none (a user's force). A bound
    /// holds where its force documents it (springs: while longer than half their rest
    /// length, dashpot position terms aside).
    fn rate_bound(&self, _s: &State, _inv_mass: &[f64]) -> Option<SpringRates> {
        None
    }

    /// The stiffest oscillation this force can have in states other than the current one —
    /// a contact that is not touching yet — as (ω², 1/s²; ζ), for the stable-step advisor;
    /// `None` when the current state tells all (every force of the catalogue).
    fn standby_rates(&self, _inv_mass: &[f64]) -> Option<(f64, f64)> {
        None
    }

    /// The Jacobian at state `s` prepared for many products (the implicit solve and the
    /// advisor take hundreds at one state): what depends only on `s` — a spring's axis and
    /// length — is computed once. Its products equal [`Force::jacobian_product`] (or the
    /// definite variant with `definite`). `None` when the force has nothing to prepare.
    fn linearize(&self, _s: &State, _definite: bool) -> Option<Box<dyn Linearized>> {
        None
    }

    /// Whether the world may renumber the particles under this force (see
    /// [`Force::renumber`]). The world keeps its particles in an order that follows space (a
    /// Morton curve), re-sorted when its neighbour list is rebuilt, so that neighbours sit
    /// near each other in memory; the user never sees that order. Default false, for a force
    /// that knows particles by index and cannot follow: the world then keeps the user's order.
    fn can_renumber(&self) -> bool {
        false
    }

    /// Follows a renumbering of the particles: particle i is now particle `new_of_old[i]`.
    /// Called only when [`Force::can_renumber`] says yes; a force without per-particle data
    /// has nothing to do (the default).
    fn renumber(&mut self, _new_of_old: &[u32]) {}

    /// Follows the removal of particles ([`crate::World::remove_particles`]): particle i is
    /// now particle `new_of_old[i]`, or was removed where that is
    /// [`crate::particles::GONE`]. What the force holds per particle goes with a removed
    /// one (a spring with a removed end is removed). A force without per-particle data has
    /// nothing to do (the default).
    fn remove_particles(&mut self, _new_of_old: &[u32]) {}
}

/// A force's Jacobian prepared at one state (see [`Force::linearize`]).
pub trait Linearized {
    /// Adds (∂F/∂x)·dx + (∂F/∂v)·dv to `out` (3 values per particle each).
    fn apply(&self, dx: &[f64], dv: &[f64], out: &mut [f64]);
}

/// Checks that the positions and velocities of `s` and every named buffer hold 3 values per
/// particle, so that a force can index them without panicking. The error names the force, the
/// buffer and its length.
pub(crate) fn check_buffers(force: &str, s: &State, buffers: &[(&str, usize)]) -> Result<(), Error> {
    let n = s.len();
    for &(name, len) in [("x", s.x.len()), ("v", s.v.len())].iter().chain(buffers) {
        if len != 3 * n {
            return Err(Error::invalid(
                format!("{force}: {name}"),
                format!("{len} values"),
                format!("3 per particle for {n} particles ({} values)", 3 * n),
            ));
        }
    }
    Ok(())
}
