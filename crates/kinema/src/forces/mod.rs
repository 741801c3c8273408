//! Forces on particles: the [`Force`] trait and the catalogue, one force per file.
//!
//! A force adds its contribution F (N) to a flat force array, x y z per particle. Forces that
//! are conservative report their potential energy (J); forces that can, give their Jacobian
//! prepared at a state ([`Linearized`]: products (∂F/∂x)·dx + (∂F/∂v)·dv and the diagonal)
//! for implicit integration; the others are differentiated numerically where that is needed.

use crate::error::{CallbackError, Error};
use crate::particles::check_per_particle;

pub mod attractor;
pub mod drag;
pub mod falloff;
pub mod field;
pub mod gravity;
pub mod spring;
mod spring_pass;
pub mod turbulence;
pub mod vortex;
pub mod wind;

#[cfg(test)]
pub(crate) mod testing;

pub use attractor::Attractor;
pub use drag::Drag;
pub use falloff::Falloff;
pub use field::Coupling;
pub use gravity::Gravity;
pub use spring::Springs;
pub use turbulence::Turbulence;
pub use vortex::Vortex;
pub use wind::Wind;

/// Particles per chunk where a pass over them runs on all threads; fewer particles than
/// one chunk stay on the calling thread (a small world would spend more on handing the work
/// over than on it). Each coordinate's value is the same either way.
pub(crate) const PARALLEL_CHUNK: usize = 4096;

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

/// How a force exchanges mechanical energy with the particles.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EnergyClass {
    /// F = −∇U: its work is −ΔU, counted by its potential energy (gravity, an attractor,
    /// springs without dashpots).
    Conservative,
    /// A conservative part, if any, and a part whose power is never positive (drag,
    /// dashpots, contacts): it cannot add energy.
    Dissipative,
    /// It may add mechanical energy (wind, a user's force).
    Source,
}

/// What a force is, for the world's bookkeeping (see [`Force::properties`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Properties {
    /// How it exchanges energy. The world watches for runaway energy only when no force is
    /// a [`EnergyClass::Source`].
    pub energy: EnergyClass,
    /// Whether F depends on the positions.
    pub depends_on_position: bool,
    /// Whether F depends on the velocities.
    pub depends_on_velocity: bool,
    /// Whether the force is internal: a sum of pairs acting equally and oppositely, so that
    /// it changes no total momentum.
    pub internal: bool,
    /// Whether the world may renumber the particles under this force (see
    /// [`Force::reindex`]). The world keeps its particles in an order that follows space (a
    /// Morton curve), re-sorted when its neighbour list is rebuilt, so that neighbours sit
    /// near each other in memory; the user never sees that order. False for a force that
    /// knows particles by index and cannot follow: the world then keeps the user's order.
    pub renumbers: bool,
    /// Whether each particle's force depends on that particle's own position, velocity and
    /// mass only (a field: gravity, drag, wind, an attractor), with no per-particle data: it
    /// can be evaluated on any subset of the particles alone, and adding or removing particles
    /// leaves the others' forces as they were. The world then keeps Verlet's acceleration
    /// across births and deaths (`world/contents.rs`). False for springs, contacts and
    /// forces the world knows nothing about.
    pub per_particle: bool,
}

impl Properties {
    /// A force the world knows nothing about (a user's): it may add energy, depends on the
    /// whole state, is not internal and cannot follow a renumbering.
    pub const UNKNOWN: Properties = Properties {
        energy: EnergyClass::Source,
        depends_on_position: true,
        depends_on_velocity: true,
        internal: false,
        renumbers: false,
        per_particle: false,
    };

    /// Whether F is the same for every position and velocity (a uniform field): then a
    /// method's cached force stays right when a collision moves the particles.
    pub fn is_uniform(&self) -> bool {
        !self.depends_on_position && !self.depends_on_velocity
    }
}

/// Closed-form upper bounds on the rates a force gives the particles (see [`Force::rates`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Rates {
    /// ω², 1/s²: bounds every |eigenvalue| of M⁻¹ ∂F/∂x (for a spring, the squared angular
    /// frequency of its oscillation).
    pub omega_squared: f64,
    /// γ, 1/s: bounds every |eigenvalue| of M⁻¹ ∂F/∂v (for a dashpot, the decay rate of the
    /// relative velocity along it).
    pub damping_rate: f64,
    /// The stiffest oscillation the force can have in states other than the current one — a
    /// contact that is not touching yet — for the stable-step advisor; `None` when the
    /// current state tells all (every force of the catalogue but the contact force).
    pub standby: Option<Standby>,
}

impl Rates {
    /// The bounds of two forces together: each is an ∞-norm (Gershgorin) bound, so they
    /// add; the stiffer standby oscillation stands for both.
    pub fn add(self, other: Rates) -> Rates {
        let standby = match (self.standby, other.standby) {
            (Some(a), Some(b)) => Some(if b.omega_squared > a.omega_squared { b } else { a }),
            (a, b) => a.or(b),
        };
        Rates {
            omega_squared: self.omega_squared + other.omega_squared,
            damping_rate: self.damping_rate + other.damping_rate,
            standby,
        }
    }
}

/// An oscillation a force can have in other states than the current one (see
/// [`Rates::standby`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Standby {
    /// ω², 1/s².
    pub omega_squared: f64,
    /// ζ, the damping ratio (1 = critical).
    pub zeta: f64,
}

/// Work on one chunk of particles' summed forces: `(c, f_c)` with the chunk's index and its
/// 3 values a particle ([`Force::accumulate_then`]).
pub type ChunkWork<'a> = dyn Fn(usize, &mut [f64]) + Sync + 'a;

/// `each(c, f_c)` on each chunk c of `chunk` particles of the summed forces `f`, on all
/// threads ([`Force::accumulate_then`]'s default, after the force's whole pass).
pub(crate) fn each_chunk(f: &mut [f64], chunk: usize, each: &ChunkWork) {
    use rayon::prelude::*;
    f.par_chunks_mut(3 * chunk.max(1)).enumerate().for_each(|(c, fc)| each(c, fc));
}

/// A force acting on the particles of a world.
///
/// What every force gives: its name, its contribution ([`Force::accumulate`]), a check
/// against the particles ([`Force::validate`]), its potential energy, what kind of force it
/// is ([`Force::properties`]), its Jacobian prepared at a state ([`Force::linearize`]), bounds
/// on the rates it gives ([`Force::rates`]), how it follows the particles when the world
/// renumbers or removes some ([`Force::reindex`]), and its contribution with the caller's
/// work on each chunk of particles once summed ([`Force::accumulate_then`]). Only `name` and
/// `accumulate` are required; the defaults describe a force the world knows nothing about.
pub trait Force: Send + Sync {
    /// Short name for diagnostics and messages (`"gravity"`, `"spring"`).
    fn name(&self) -> &str;

    /// Adds this force to `f` (N, 3 per particle).
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError>;

    /// [`Force::accumulate`], then `each(c, f_c)` on each chunk c of `chunk` particles of `f`
    /// (`f_c`: its 3 values a particle) once this force's additions to it are done, on all
    /// threads: work of the caller's that needs the summed force of each particle (Verlet's
    /// kick, when this is the last force) done while the chunk is in cache. The default adds
    /// everything, then passes the chunks; a force that sums by chunks of particles itself
    /// may call `each` from its own pass (the springs do, for chunks of their size).
    fn accumulate_then(&mut self, s: &State, f: &mut [f64], chunk: usize, each: &ChunkWork) -> Result<(), CallbackError> {
        self.accumulate(s, f)?;
        each_chunk(f, chunk, each);
        Ok(())
    }

    /// Checks the force against a world of `n` particles (indices in range, ...).
    fn validate(&self, _n: usize) -> Result<(), Error> {
        Ok(())
    }

    /// Potential energy, J, for a conservative force (F = −∇U); `None` otherwise.
    fn potential_energy(&self, _s: &State) -> Option<f64> {
        None
    }

    /// What kind of force this is: its energy class, what it depends on, whether it is
    /// internal and whether it follows a renumbering. Default [`Properties::UNKNOWN`].
    fn properties(&self) -> Properties {
        Properties::UNKNOWN
    }

    /// The Jacobian at state `s` prepared for many products (the implicit solve and the
    /// advisor take hundreds at one state): what depends only on `s` — a spring's axis and
    /// length — is computed once. With `definite`, the parts that can make the implicit
    /// system indefinite are dropped, so that conjugate gradients can solve it (Choi & Ko
    /// 2002: a spring in compression loses its transverse stiffness). `None` when the force
    /// does not know its Jacobian: the world then differentiates it numerically.
    fn linearize(&self, _s: &State, _definite: bool) -> Option<Box<dyn Linearized>> {
        None
    }

    /// Closed-form upper bounds, at state `s`, on the rates this force gives the particles
    /// (inverse masses `inv_mass`, 0 for pinned ones), each an ∞-norm (Gershgorin) bound so
    /// that the bounds of several forces add ([`Rates::add`]). `None` when the force has
    /// none (a user's force). A bound holds where its force documents it (springs: while
    /// longer than half their rest length, dashpot position terms aside).
    fn rates(&self, _s: &State, _inv_mass: &[f64]) -> Option<Rates> {
        None
    }

    /// Follows a renumbering or a removal of the particles: particle i is now particle
    /// `new_of_old[i]`, or was removed where that is [`crate::limits::GONE`]
    /// ([`crate::World::remove_particles`]). What the force holds per particle follows (a
    /// spring with a removed end is removed). A renumbering (no `GONE`) comes only when
    /// [`Properties::renumbers`] says yes. A force without per-particle data has nothing to
    /// do (the default).
    fn reindex(&mut self, _new_of_old: &[u32]) {}

    /// The acceleration, m/s², this force gives every movable particle at every time,
    /// position and velocity, if it is such a uniform field (gravity); `None` otherwise (the
    /// default). Event-driven dynamics flies particles on parabolas under it
    /// (`collide/event_driven/`).
    fn uniform_acceleration(&self) -> Option<[f64; 3]> {
        None
    }
}

/// A force's Jacobian prepared at one state `s` (see [`Force::linearize`]); its methods are
/// given the same `s` again, so that a preparation need not copy what it can read there.
pub trait Linearized: Send + Sync {
    /// Adds (∂F/∂x)·dx + (∂F/∂v)·dv to `out` (3 values per particle each).
    fn apply(&self, s: &State, dx: &[f64], dv: &[f64], out: &mut [f64]);

    /// Adds c_x·diag(∂F/∂x) + c_v·diag(∂F/∂v) to `out`, for the Jacobi preconditioner of the
    /// implicit solve. The default adds nothing: the diagonal only preconditions.
    fn add_diagonal(&self, _s: &State, _cx: f64, _cv: f64, _out: &mut [f64]) {}
}

/// The Jacobian of a force that has none: a uniform constant field.
pub(crate) struct ZeroJacobian;

impl Linearized for ZeroJacobian {
    fn apply(&self, _s: &State, _dx: &[f64], _dv: &[f64], _out: &mut [f64]) {}
}

/// Checks that the positions and velocities of `s` and every named buffer hold 3 values per
/// particle, so that a force can index them without panicking. The error names the force, the
/// buffer and its length.
pub(crate) fn check_buffers(force: &str, s: &State, buffers: &[(&str, usize)]) -> Result<(), Error> {
    for &(name, len) in [("x", s.x.len()), ("v", s.v.len())].iter().chain(buffers) {
        check_per_particle(&format!("{force}: {name}"), len, 3, s.len(), "particles")?;
    }
    Ok(())
}
