//! Stage 1 of a world step: the stepper the world keeps between steps, and the integration of
//! positions and velocities over one step (velocity Verlet on the particles' own arrays, the
//! other methods on the joined state [x, v]).

use super::dynamics::{newton_in_place, newton_serial, Dynamics};
use super::forces::{contact_force, every_force};
use super::implicit::{BaraffWitkin, StepSpan};
use super::{World, RUNAWAY_CHECK_EVERY};
use crate::collide::contact_force::{SpinKick, VerletKick};
use crate::error::{Divergence, Error};
use crate::forces::State;
use crate::ode::explicit_rk::ExplicitRk;
use crate::ode::stepper::{first_non_finite, StepFailure, Stepper, Termination};
use crate::ode::symplectic_euler::SymplecticEuler;
use crate::ode::system::{FirstOrderForm, OdeSystem, SecondOrderSystem};
use crate::ode::{self, verlet, Integrator, Method, MethodKind, SolveOptions};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, PoisonError};

/// The stepper a world keeps between steps (so that a method's cache survives).
pub(super) enum WorldStepper {
    /// Velocity Verlet on the particles' own arrays (see [`VerletBuffers`]).
    Verlet(Box<VerletBuffers>),
    SecondOrder(Box<dyn for<'a> Stepper<dyn SecondOrderSystem + 'a> + Send + Sync>),
    FirstOrder(Box<dyn for<'a> Stepper<dyn OdeSystem + 'a> + Send + Sync>),
    /// rk45 substeps adaptively inside each world step.
    Adaptive,
    /// implicit_euler: Baraff & Witkin's linearised step with conjugate gradients.
    Implicit(Box<BaraffWitkin>),
}

impl WorldStepper {
    pub(super) fn new(method: &Integrator, n: usize) -> Self {
        match method {
            Integrator::Tableau(t) => WorldStepper::FirstOrder(Box::new(ExplicitRk::new(t.clone(), 2 * n))),
            Integrator::Named(m) => match m.kind() {
                MethodKind::SecondOrder if *m == Method::Verlet => WorldStepper::Verlet(Box::default()),
                MethodKind::SecondOrder => WorldStepper::SecondOrder(Box::new(SymplecticEuler::new(n))),
                MethodKind::ExplicitRk => WorldStepper::FirstOrder(Box::new(ExplicitRk::new(
                    m.tableau().expect("explicit methods have tableaux"),
                    2 * n,
                ))),
                MethodKind::Implicit => WorldStepper::Implicit(Box::default()),
                MethodKind::Adaptive => WorldStepper::Adaptive,
            },
        }
    }
}

/// Velocity Verlet's acceleration a_n at the current state, kept from the last step's end
/// (first same as last), and the next one's buffer; the world's `x_next`, `v_next` hold the
/// new state until the step is accepted. The scheme (and why the dashpot sees the Euler
/// predictor v + h a) is that of `ode/verlet.rs`, bit for bit:
///
/// ```text
///   x' = x + h v + h²/2 a,   v' = v + h a          (drift and predictor, one pass)
///   a' = F(t + h, x', v') / m                       (the force evaluation)
///   v' = v + h/2 (a + a')                           (the two half kicks, one pass)
/// ```
///
/// Nothing is joined, split or copied: the accepted step swaps buffers. Where the contact
/// force is the only force that reads velocities, the predictor is not stored: the contacts
/// make it from v and a where two touch (`collide/velocities.rs`, the same bits), and the
/// step holds five arrays of 3 per particle (x, v, a, x', the force sum that becomes the new
/// velocities), not six; `a_next` is then empty between steps.
#[derive(Default)]
pub(super) struct VerletBuffers {
    pub(super) a: Vec<f64>,
    pub(super) a_next: Vec<f64>,
    /// With spin under the contacts' torques (`SpinKick`): ω and α at the step's end, until
    /// the step is accepted; empty otherwise.
    pub(super) omega_next: Vec<f64>,
    pub(super) alpha_next: Vec<f64>,
    /// `a` holds the acceleration at the current state.
    pub(super) fresh: bool,
}

/// Particles per task of Verlet's per-particle passes (the drift, the kick of forces other
/// than the contacts'): each particle's own arithmetic, so the same bits for any chunks, and
/// small enough that a cloth of 10⁴ nodes splits evenly over two threads (2048 gave five
/// tasks, three on one thread).
const PASS_CHUNK: usize = 1024;

/// The particles below which stage 1 runs on a worker of rayon's pool ([`World::integrate`]),
/// 2²² (4,194,304). Above, each of its passes is long beside a thread switch (microseconds),
/// and it stays on the calling thread. The bound was once 2¹⁶: glibc's allocator keeps an
/// arena per thread, and a gas of 10⁶ spheres whose stage 1 ran on whichever worker took it
/// peaked at 757 MB against 441 MB on the calling thread, the 10⁵ gas at +19 %. The Python
/// module's allocator now maps the large blocks wherever they are made (its `pages.rs`): the
/// 10⁵ gas (`benchmarks/granular_gas.py`) steps 5–15 % faster in the pool at +2 % of its peak,
/// the 10⁶ gas peaks at the same 240 B a particle.
pub const IN_POOL_BELOW: usize = 1 << 22;

impl World {
    /// The most adaptive sub-steps rk45 takes inside one step of dt: a step that needs more
    /// has a dt far beyond what its forces allow, and is refused as diverged in milliseconds
    /// instead ([`crate::limits::RK45_SUBSTEPS`], which the errors name too).
    pub const RK45_SUBSTEPS: usize = crate::limits::RK45_SUBSTEPS;

    /// Stage 1: integrate positions and velocities over one step, into `x_next`, `v_next`.
    ///
    /// Below [`IN_POOL_BELOW`] particles it runs as one task on a worker of rayon's pool
    /// (unless a force declares nothing about itself, a user's such as a Python callable,
    /// which may need the calling thread's state: `unknown_force`): each parallel pass of the
    /// step then starts from inside the pool. Started from outside it, every pass (four or
    /// more a step) hands its work to the pool and puts the calling thread to sleep until it
    /// is done, two thread switches each: about a fifth of a 10,000-node cloth's step. The
    /// stage polls no interrupt (Ctrl-C is checked between the stages, on the calling thread).
    pub(super) fn integrate(&mut self) -> Result<(), Error> {
        if self.runs_in_pool() {
            rayon::scope(|_| self.integrate_here())
        } else {
            self.integrate_here()
        }
    }

    /// Whether the world's work may run as one task on a worker of rayon's pool: below
    /// [`IN_POOL_BELOW`] particles, and no force that declares nothing about itself (see
    /// [`World::integrate`]). A caller stepping such a world many steps at once can run them
    /// all there (the Python binding's slices of more than one step), so that no pass of
    /// theirs starts from outside the pool.
    pub fn runs_in_pool(&self) -> bool {
        !self.unknown_force && self.particles.len() < IN_POOL_BELOW
    }

    /// [`World::integrate`] on the current thread.
    fn integrate_here(&mut self) -> Result<(), Error> {
        let n = 3 * self.particles.len();
        self.x_next.resize(n, 0.0);
        self.v_next.resize(n, 0.0);
        if n == 0 {
            return Ok(());
        }
        if self.stepper.is_none() {
            self.stepper = Some(WorldStepper::new(&self.params.method, n));
        }
        if matches!(self.stepper, Some(WorldStepper::Verlet(_))) {
            self.verlet()?;
        } else {
            if let Some(c) = contact_force(&self.collide_stage, &self.particles).filter(|c| c.has_memory()) {
                let (what, instead) = if c.has_tangential() {
                    ("contacts with friction", "friction=0")
                } else {
                    ("JKR cohesion", "cohesion='dmt'")
                };
                return Err(Error::invalid(
                    "method",
                    format!("'{}'", self.params.method.name()),
                    format!(
                        "{what} under a force model ('spring_dashpot', 'hertz') step with method='verlet' only: \
                         the contacts' memory (tangential springs, JKR's touches) is renewed once per step, at its \
                         one force evaluation (LAMMPS's fix nve/sphere); use method='verlet', or {instead}"
                    ),
                ));
            }
            self.integrate_joined()?;
        }
        if self.watch.is_some() && (self.steps + 1) % RUNAWAY_CHECK_EVERY == 0 {
            let checked = self.check_runaway();
            if let Some(model) = self.force_model() {
                model.forget_energy();
            }
            checked?;
        }
        Ok(())
    }

    /// Velocity Verlet on the particles' arrays (see [`VerletBuffers`]): drift and predictor
    /// in one parallel pass, the force evaluation (after sorting the particles along space
    /// when the contact force's neighbour list must be rebuilt), the two half kicks in one
    /// parallel pass that also finds a non-finite value. Three variants: no force at all
    /// ([`World::verlet_force_free`]), the contact force fused with the closing kick
    /// ([`World::verlet_fused_kick`]), and the other forces alone ([`World::verlet_kick`]).
    fn verlet(&mut self) -> Result<(), Error> {
        let Some(WorldStepper::Verlet(mut b)) = self.stepper.take() else {
            unreachable!("called for verlet only")
        };
        let result = self.verlet_step(&mut b);
        self.stepper = Some(WorldStepper::Verlet(b));
        if let Some(model) = self.force_model() {
            model.forget_verified();
        }
        match result? {
            Some(index) => Err(self.diverged(Divergence::NonFinite, Some(index / 3))),
            None => Ok(()),
        }
    }

    /// One step of velocity Verlet into `x_next`, `v_next` (the stepper's buffers `b` taken
    /// out of the world meanwhile): the first non-finite value's index, if any.
    #[inline]
    fn verlet_step(&mut self, b: &mut VerletBuffers) -> Result<Option<usize>, Error> {
        let n = 3 * self.particles.len();
        let (t, h) = (self.time, self.step_length());
        let contacts = self.has_contact_force();
        if self.forces.is_empty() && !contacts {
            return Ok(self.verlet_force_free(b, h, n));
        }
        if !b.fresh || b.a.len() != n {
            self.verlet_first_accel(b, t, n)?;
        }
        // the contacts make the predictor where they need it when no other force reads it
        let predict = contacts && !self.forces.iter().any(|f| f.properties().depends_on_velocity);
        self.verlet_drift(b, h, contacts, !predict);
        if self.sortable()
            && self
                .collide_stage
                .as_ref()
                .and_then(|s| s.force_model().map(|m| m.list_expired(&self.x_next, &s.domain)))
                .unwrap_or(false)
        {
            // (the room the arrays move through: one the step writes before it reads)
            let spare = if predict { &mut self.v_next } else { &mut b.a_next };
            let mut spare = std::mem::take(spare);
            self.sort_along_space(&mut b.a, &mut spare);
            *(if predict { &mut self.v_next } else { &mut b.a_next }) = spare;
        }
        if contacts {
            self.verlet_fused_kick(b, t, h, n, predict)
        } else {
            b.a_next.resize(n, 0.0);
            self.verlet_kick(b, t, h)
        }
    }

    /// No force at all (a gas of the impulse model): a = a' = 0, so the drift is x + h v and
    /// both kicks add nothing. One pass instead of three, the same numbers (to the sign of a
    /// zero). The first non-finite position's index, if any.
    #[inline]
    fn verlet_force_free(&mut self, b: &mut VerletBuffers, h: f64, n: usize) -> Option<usize> {
        if !b.fresh || b.a.len() != n || b.a_next.len() != n {
            // zeros once; no step writes them again, so made as zero pages that the
            // collisions' reads of a leave unwritten (48 MB of a 10⁶-sphere impulse gas,
            // not resident)
            b.a = vec![0.0; n];
            b.a_next = vec![0.0; n];
            b.fresh = true;
        }
        // In a periodic cell x' is wrapped into it in the same pass (the collision
        // stage is told, and wraps only what it moves itself).
        let cell = self.collide_stage.as_ref().and_then(|c| c.domain.periodic_box());
        let p = &self.particles;
        self.x_next
            .par_chunks_mut(3 * PASS_CHUNK)
            .zip(self.v_next.par_chunks_mut(3 * PASS_CHUNK))
            .enumerate()
            .map(|(c, (xn, vn))| {
                let base = 3 * PASS_CHUNK * c;
                let mut bad = None;
                for k in 0..xn.len() {
                    let (x, v) = (p.x[base + k], p.v[base + k]);
                    xn[k] = x + h * v;
                    vn[k] = v;
                    if bad.is_none() && !xn[k].is_finite() {
                        bad = Some(base + k);
                    }
                }
                if let Some(cell) = cell {
                    cell.wrap_positions_serial(xn);
                }
                bad
            })
            .flatten()
            .min()
    }

    /// The acceleration at the current state when none is kept (the first step, or after a
    /// change that dropped it), and α = τ/I where the contacts' torques turn the particles.
    #[inline]
    fn verlet_first_accel(&mut self, b: &mut VerletBuffers, t: f64, n: usize) -> Result<(), Error> {
        b.a.resize(n, 0.0);
        let p = &self.particles;
        let mut contact = contact_force(&self.collide_stage, p);
        let mut forces = every_force(&mut self.forces, contact.as_mut());
        // the forces are summed in `a` itself and divided by the masses there: no buffer of
        // summed forces beside it (24 B a particle, which a gas of contacts alone then let
        // go of: the top of its first step's memory)
        let mut dynamics = Dynamics::new(&mut forces, p, self.params.dim, &mut b.a);
        dynamics.total_force(t, &p.x, &p.v)?;
        newton_in_place(&mut b.a, &p.inv_mass, self.params.dim);
        self.stats.nfev += 1;
        // and α = τ/I, where the contacts' torques turn the particles
        if let Some(c) = contact.as_ref().filter(|c| c.has_tangential() && p.has_spin()) {
            let s = State {
                t,
                x: &p.x,
                v: &p.v,
                mass: &p.mass,
            };
            let mut alpha = vec![0.0; n];
            c.torques_at(&s, &mut alpha)?;
            for (q, a) in alpha.iter_mut().enumerate() {
                *a = if self.params.dim == 2 && q % 3 < 2 {
                    0.0
                } else {
                    *a * p.inv_inertia[q / 3]
                };
            }
            self.particles.alpha = alpha;
        }
        b.fresh = true;
        Ok(())
    }

    /// Drift and predictor in one parallel pass: x' = x + h v + h²/2 a, and with `predictor`
    /// v' = v + h a (else `v_next` is left as it is: the contacts make v' themselves). Without
    /// contacts the same pass zeroes the forces' sum, which [`World::verlet_kick`] then adds
    /// the forces to: one parallel pass a step fewer (a 10,000-node cloth's step is a few
    /// such passes besides its springs').
    #[inline]
    fn verlet_drift(&mut self, b: &VerletBuffers, h: f64, contacts: bool, predictor: bool) {
        // with contact forces in a periodic cell, x' is wrapped into the cell in
        // the same pass, before the force evaluation, so that the kept acceleration is
        // that of the state kept (collide's wrap then changes nothing). The impulse
        // model's continuous detection needs the unwrapped drift, and wraps after its
        // impacts.
        let cell = self
            .collide_stage
            .as_ref()
            .and_then(|c| c.domain.periodic_box())
            .filter(|_| contacts);
        let wrap = |xn: &mut [f64]| {
            if let Some(cell) = cell {
                cell.wrap_positions_serial(xn);
            }
        };
        // (without contacts the predictor is always made: no contact force makes v')
        debug_assert!(predictor || contacts);
        if !contacts {
            self.force.resize(self.x_next.len(), 0.0); // (zeroed below)
        }
        let p = &self.particles;
        let a = &b.a;
        let xs = self.x_next.par_chunks_mut(3 * PASS_CHUNK).enumerate();
        if !predictor {
            xs.for_each(|(c, xn)| {
                let chunk = 3 * PASS_CHUNK * c..3 * PASS_CHUNK * c + xn.len();
                let (x, v, a) = (&p.x[chunk.clone()], &p.v[chunk.clone()], &a[chunk]);
                for (((xn, x), v), a) in xn.iter_mut().zip(x).zip(v).zip(a) {
                    (*xn, _) = verlet::drift(*x, *v, *a, h);
                }
                wrap(xn);
            });
            return;
        }
        let drift = |c: usize, xn: &mut [f64], vn: &mut [f64]| {
            let chunk = 3 * PASS_CHUNK * c..3 * PASS_CHUNK * c + xn.len();
            let (x, v, a) = (&p.x[chunk.clone()], &p.v[chunk.clone()], &a[chunk]);
            for ((((xn, vn), x), v), a) in xn.iter_mut().zip(vn.iter_mut()).zip(x).zip(v).zip(a) {
                (*xn, *vn) = verlet::drift(*x, *v, *a, h);
            }
            wrap(xn);
        };
        let vs = self.v_next.par_chunks_mut(3 * PASS_CHUNK);
        if contacts {
            xs.zip(vs).for_each(|((c, xn), vn)| drift(c, xn, vn));
        } else {
            // (the sum's room was sized before the pass: as long as x')
            let forces = self.force.par_chunks_mut(3 * PASS_CHUNK);
            xs.zip(vs).zip(forces).for_each(|(((c, xn), vn), f)| {
                drift(c, xn, vn);
                f.fill(0.0);
            });
        }
    }

    /// The contact force and the closing kick in one pass, the other forces first (and with
    /// spin under the contacts' torques, the angular kick beside): the first non-finite
    /// value's index, if any.
    #[inline]
    fn verlet_fused_kick(
        &mut self,
        b: &mut VerletBuffers,
        t: f64,
        h: f64,
        n: usize,
        predict: bool,
    ) -> Result<Option<usize>, Error> {
        let p = &self.particles;
        let contact = contact_force(&self.collide_stage, p).expect("a force model lends its contact force");
        let turns = contact.has_tangential() && p.has_spin();
        if turns {
            b.omega_next.resize(n, 0.0);
            b.alpha_next.resize(n, 0.0);
        }
        // The pass writes a' over a and the new velocities into `v_out`. With `predict` the
        // contacts make v' from v and a (no other force reads velocities: the state's are
        // those at the start, for its lengths), and `v_out` is `v_next`, which the drift left
        // unwritten; `a_next` holds nothing until the swap below. Else v' is in `v_next` and
        // `v_out` is `a_next`.
        // (`v_out` is sized by the contacts: they let its room go while their list is rebuilt)
        if predict {
            b.a_next = Vec::new();
        }
        let (seen, v_out) = if predict {
            (&p.v, &mut self.v_next)
        } else {
            (&self.v_next, &mut b.a_next)
        };
        let s1 = State {
            t: t + h,
            x: &self.x_next,
            v: seen,
            mass: &p.mass,
        };
        let other = if !self.forces.is_empty() {
            self.force.clear();
            self.force.resize(n, 0.0);
            for f in self.forces.iter_mut() {
                f.accumulate(&s1, &mut self.force)?;
            }
            Some(&self.force[..])
        } else {
            // nothing to sum: the buffer the first acceleration used is let go
            self.force = Vec::new();
            None
        };
        let bad = contact.force_and_kick(
            &s1,
            VerletKick {
                other,
                inv_mass: &p.inv_mass,
                flat: self.params.dim == 2,
                h,
                v: &p.v,
                a: &mut b.a,
                v_out,
                predict,
                energy: (self.watch.is_some() && (self.steps + 1) % RUNAWAY_CHECK_EVERY == 0)
                    || self.energy_at == Some(self.steps + 1),
                spin: turns.then(|| SpinKick {
                    omega: &p.omega,
                    alpha: &p.alpha,
                    inv_inertia: &p.inv_inertia,
                    alpha_out: &mut b.alpha_next,
                    omega_out: &mut b.omega_next,
                }),
            },
        )?;
        if !turns {
            b.omega_next.clear();
        }
        // a' to a_next (the next step's a once accepted); without `predict` the velocities,
        // in a_next, to v_next (v' there becomes spare)
        std::mem::swap(&mut b.a, &mut b.a_next);
        if !predict {
            std::mem::swap(&mut b.a, &mut self.v_next);
        }
        self.stats.nfev += 1;
        b.fresh = true;
        Ok(bad)
    }

    /// The other forces at the drifted state, then the two half kicks in the last force's own
    /// pass, chunk by chunk as its sums are done (`Force::accumulate_then`), which also finds a
    /// non-finite value: the first one's index, if any.
    ///
    /// In each chunk a' = F/m goes to `a_next` and v' = v + h/2 (a + a') is written over the
    /// chunk's force sum, which nothing reads after; the sums' room then becomes `v_next` (and
    /// `v_next`'s, the predictor the forces read, the next step's sums, which the drift
    /// zeroes). The springs, added last, call the kick from their sum pass while the chunk is
    /// in cache: one parallel pass a step fewer. The same operations as a pass of its own:
    /// the same bits.
    #[inline]
    fn verlet_kick(&mut self, b: &mut VerletBuffers, t: f64, h: f64) -> Result<Option<usize>, Error> {
        let p = &self.particles;
        let dim = self.params.dim;
        let mut forces = every_force(&mut self.forces, None);
        let Some((last, others)) = forces.split_last_mut() else {
            unreachable!("a world without forces or contacts steps force-free")
        };
        let mut dynamics = Dynamics::new(others, p, dim, &mut self.force);
        dynamics.add_forces(t + h, &self.x_next, &self.v_next)?; // (zeroed by the drift)
        self.stats.nfev += 1;
        b.fresh = true; // a_next, the next step's a once accepted

        let (a, x_next) = (&b.a, &self.x_next);
        let a_next: Vec<Mutex<&mut [f64]>> = b.a_next.chunks_mut(3 * PASS_CHUNK).map(Mutex::new).collect();
        let first_bad = AtomicUsize::new(usize::MAX);
        let kick = |c: usize, f: &mut [f64]| {
            let chunk = 3 * PASS_CHUNK * c..3 * PASS_CHUNK * c + f.len();
            let (v, a, xn) = (&p.v[chunk.clone()], &a[chunk.clone()], &x_next[chunk.clone()]);
            let inv_mass = &p.inv_mass[PASS_CHUNK * c..PASS_CHUNK * c + f.len() / 3];
            let mut a_next = a_next[c].lock().unwrap_or_else(PoisonError::into_inner);
            newton_serial(f, inv_mass, dim, &mut a_next);
            for (((vn, v), a), a_next) in f.iter_mut().zip(v).zip(a).zip(a_next.iter()) {
                *vn = verlet::kick(*v, *a, *a_next, h);
            }
            // (the check in a pass of its own, which the compiler vectorises; the search for
            // the first bad value only where there is one)
            let finite = |s: &[f64]| s.iter().fold(true, |all, c| all & c.is_finite());
            if !(finite(f) && finite(xn)) {
                if let Some(k) = (0..f.len()).find(|&k| !(f[k].is_finite() && xn[k].is_finite())) {
                    first_bad.fetch_min(chunk.start + k, Ordering::Relaxed);
                }
            }
        };
        let s = State {
            t: t + h,
            x: &self.x_next,
            v: &self.v_next,
            mass: &p.mass,
        };
        last.accumulate_then(&s, &mut self.force, PASS_CHUNK, &kick)?;
        std::mem::swap(&mut self.force, &mut self.v_next);
        let bad = first_bad.into_inner();
        Ok((bad != usize::MAX).then_some(bad))
    }

    /// Stage 1 for the other methods, on the joined state [x, v] (their steppers work on one
    /// vector): joined into `y`, stepped into `y_next`, split into `x_next`, `v_next`.
    fn integrate_joined(&mut self) -> Result<(), Error> {
        let n = 3 * self.particles.len();
        let (t, h) = (self.time, self.step_length());
        let p = &self.particles;
        self.y.resize(2 * n, 0.0);
        self.y_next.resize(2 * n, 0.0);
        FirstOrderForm::join(&p.x, &p.v, n, &mut self.y);
        let stepper = self.stepper.as_mut().expect("made by integrate");
        let mut contact = contact_force(&self.collide_stage, p);
        let mut forces = every_force(&mut self.forces, contact.as_mut());
        let mut dynamics = Dynamics::new(&mut forces, p, self.params.dim, &mut self.force);
        let outcome = match stepper {
            WorldStepper::Verlet(_) => unreachable!("verlet steps the particles' arrays"),
            WorldStepper::SecondOrder(s) => s.step(&mut dynamics, t, &self.y, h, &mut self.y_next, &mut self.stats),
            WorldStepper::FirstOrder(s) => {
                let mut first = FirstOrderForm::new(&mut dynamics);
                s.step(&mut first, t, &self.y, h, &mut self.y_next, &mut self.stats)
            }
            WorldStepper::Implicit(bw) => {
                let (x_next, v_next) = self.y_next.split_at_mut(n);
                let span = StepSpan {
                    t,
                    h,
                    x: &p.x,
                    v: &p.v,
                    x_out: x_next,
                    v_out: v_next,
                };
                bw.step(&mut dynamics, span, &mut self.stats)
                    .map_err(|e| StepFailure::Error(e.into()))
            }
            WorldStepper::Adaptive => {
                let opts = SolveOptions {
                    t_span: (t, t + h),
                    t_eval: Some(vec![t + h]),
                    max_steps: Self::RK45_SUBSTEPS,
                    ..SolveOptions::default()
                };
                let mut first = FirstOrderForm::new(&mut dynamics);
                let sol = ode::solve(&mut first, &self.y, &Integrator::Named(Method::Rk45), &opts)?;
                self.stats.nfev += sol.stats.nfev;
                match sol.termination {
                    None => {
                        self.y_next.copy_from_slice(sol.last());
                        Ok(())
                    }
                    Some(term) => Err(StepFailure::Stop(term)),
                }
            }
        };
        match outcome {
            Ok(()) => {}
            Err(StepFailure::Error(e)) => return Err(e),
            Err(StepFailure::Stop(Termination::NonFinite { index, .. })) => {
                return Err(self.diverged(Divergence::NonFinite, Some((index % n) / 3)))
            }
            Err(StepFailure::Stop(Termination::MaxSteps { .. })) => return Err(self.diverged(Divergence::TooManySubsteps, None)),
            Err(StepFailure::Stop(_)) => return Err(self.diverged(Divergence::StepTooSmall, None)),
        }
        if let Some(index) = first_non_finite(&self.y_next) {
            let particle = (index % n) / 3; // y_next = [x, v]
            return Err(self.diverged(Divergence::NonFinite, Some(particle)));
        }
        FirstOrderForm::split(&self.y_next, n, &mut self.x_next, &mut self.v_next);
        Ok(())
    }
}
