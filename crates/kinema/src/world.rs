//! The world: particles, the forces on them, and `World::step`, the seed's four stages.

use crate::diagnostics::Diagnostics;
use crate::error::{CallbackError, Error};
use crate::forces::{Force, State};
use crate::ode::explicit_rk::ExplicitRk;
use crate::ode::implicit_euler::ImplicitEuler;
use crate::ode::stepper::{first_non_finite, Stats, StepFailure, Stepper};
use crate::ode::symplectic_euler::SymplecticEuler;
use crate::ode::system::{FirstOrderForm, OdeSystem, SecondOrderSystem};
use crate::ode::verlet::Verlet;
use crate::ode::{self, Integrator, Method, MethodKind, SolveOptions};
use crate::particles::Particles;

/// Parameters of a world. Units SI.
#[derive(Debug, Clone, PartialEq)]
pub struct WorldParams {
    /// Time step, s (> 0). Default 1e-3.
    pub dt: f64,
    /// The integrator, any method of the registry or an explicit tableau. Default `verlet`.
    pub method: Integrator,
    /// 2 or 3. A 2D world lives in the xy-plane: z and its velocity stay exactly 0. Default 3.
    pub dim: usize,
}

impl Default for WorldParams {
    fn default() -> Self {
        Self {
            dt: 1e-3,
            method: Integrator::Named(Method::Verlet),
            dim: 3,
        }
    }
}

/// The dynamics of the particles as a second-order system: x'' = F(t, x, v) / m.
///
/// Pinned particles (inverse mass 0) get no acceleration; in 2D the z acceleration is 0.
struct Dynamics<'a> {
    forces: &'a mut [Box<dyn Force>],
    mass: &'a [f64],
    inv_mass: &'a [f64],
    dim: usize,
    /// Scratch for the summed forces, N (owned by the World, so a step allocates nothing).
    force: &'a mut Vec<f64>,
}

impl SecondOrderSystem for Dynamics<'_> {
    fn dim(&self) -> usize {
        3 * self.mass.len()
    }

    fn accel(&mut self, t: f64, x: &[f64], v: &[f64], acc: &mut [f64]) -> Result<(), CallbackError> {
        self.force.clear();
        self.force.resize(x.len(), 0.0);
        let s = State {
            t,
            x,
            v,
            mass: self.mass,
        };
        for f in self.forces.iter_mut() {
            f.accumulate(&s, self.force)?;
        }
        // Newton's second law, a = F/m, with 1/m = 0 for pinned particles.
        for (i, inv_m) in self.inv_mass.iter().enumerate() {
            for k in 0..3 {
                acc[3 * i + k] = self.force[3 * i + k] * inv_m;
            }
            if self.dim == 2 {
                acc[3 * i + 2] = 0.0;
            }
        }
        Ok(())
    }
}

/// The stepper a world keeps between steps (so that a method's cache survives).
enum WorldStepper {
    SecondOrder(Box<dyn for<'a> Stepper<dyn SecondOrderSystem + 'a>>),
    FirstOrder(Box<dyn for<'a> Stepper<dyn OdeSystem + 'a>>),
    /// rk45 substeps adaptively inside each world step.
    Adaptive,
}

impl WorldStepper {
    fn new(method: &Integrator, n: usize) -> Self {
        match method {
            Integrator::Tableau(t) => WorldStepper::FirstOrder(Box::new(ExplicitRk::new(t.clone(), 2 * n))),
            Integrator::Named(m) => match m.kind() {
                MethodKind::SecondOrder if *m == Method::Verlet => WorldStepper::SecondOrder(Box::new(Verlet::new(n))),
                MethodKind::SecondOrder => WorldStepper::SecondOrder(Box::new(SymplecticEuler::new(n))),
                MethodKind::ExplicitRk => WorldStepper::FirstOrder(Box::new(ExplicitRk::new(
                    m.tableau().expect("explicit methods have tableaux"),
                    2 * n,
                ))),
                MethodKind::Implicit => WorldStepper::FirstOrder(Box::new(ImplicitEuler::new(2 * n, 2 * n, 1e-9, 1e-12))),
                MethodKind::Adaptive => WorldStepper::Adaptive,
            },
        }
    }
}

/// Particles, forces, an integrator, a time step and the time.
pub struct World {
    particles: Particles,
    forces: Vec<Box<dyn Force>>,
    params: WorldParams,
    time: f64,
    steps: u64,
    stats: Stats,
    stepper: Option<WorldStepper>,
    y: Vec<f64>,
    y_next: Vec<f64>,
    force: Vec<f64>,
}

impl World {
    /// An empty world; checks the parameters.
    pub fn new(params: WorldParams) -> Result<Self, Error> {
        if !(params.dt.is_finite() && params.dt > 0.0) {
            return Err(Error::invalid("dt", params.dt, "the time step must be a finite number > 0 s"));
        }
        if params.dim != 2 && params.dim != 3 {
            return Err(Error::invalid("dim", params.dim, "a world is 2D (the xy-plane) or 3D"));
        }
        Ok(Self {
            particles: Particles::default(),
            forces: Vec::new(),
            params,
            time: 0.0,
            steps: 0,
            stats: Stats::default(),
            stepper: None,
            y: Vec::new(),
            y_next: Vec::new(),
            force: Vec::new(),
        })
    }

    /// Adds particles (see [`Particles::add`]); in 2D every z and z velocity must be 0.
    pub fn add_particles(
        &mut self,
        x: &[f64],
        v: &[f64],
        mass: &[f64],
        radius: &[f64],
        pinned: &[bool],
    ) -> Result<std::ops::Range<usize>, Error> {
        if self.params.dim == 2 {
            for (name, values) in [("position", x), ("velocity", v)] {
                if let Some(i) = values.chunks(3).position(|c| c.len() == 3 && c[2] != 0.0) {
                    return Err(Error::invalid(
                        format!("{name}[{i}][2]"),
                        values[3 * i + 2],
                        "a 2D world keeps z = 0",
                    ));
                }
            }
        }
        let range = self.particles.add(x, v, mass, radius, pinned)?;
        for f in &self.forces {
            f.validate(self.particles.len())?;
        }
        self.stepper = None; // the state changed size: caches are void
        Ok(range)
    }

    /// Adds a force, checked against the current particles.
    pub fn add_force(&mut self, force: Box<dyn Force>) -> Result<(), Error> {
        force.validate(self.particles.len())?;
        self.forces.push(force);
        self.stepper = None;
        Ok(())
    }

    /// The particles (read only; change them through the world's methods).
    pub fn particles(&self) -> &Particles {
        &self.particles
    }

    /// Mutable particles: after changing positions or velocities the method caches are
    /// dropped, so the next step starts afresh.
    pub fn particles_mut(&mut self) -> &mut Particles {
        self.stepper = None;
        &mut self.particles
    }

    /// The forces, in the order they were added.
    pub fn forces(&self) -> &[Box<dyn Force>] {
        &self.forces
    }

    /// The parameters.
    pub fn params(&self) -> &WorldParams {
        &self.params
    }

    /// Current time, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Work counters of all steps so far (force evaluations in `nfev`).
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Energies and momenta now.
    pub fn diagnostics(&self) -> Diagnostics {
        let p = &self.particles;
        Diagnostics::measure(
            &State {
                t: self.time,
                x: &p.x,
                v: &p.v,
                mass: &p.mass,
            },
            &self.forces,
        )
    }

    /// The accelerations a = F/m now, m/s² (3 per particle).
    pub fn accelerations(&mut self) -> Result<Vec<f64>, Error> {
        let p = &self.particles;
        let mut dynamics = Dynamics {
            forces: &mut self.forces,
            mass: &p.mass,
            inv_mass: &p.inv_mass,
            dim: self.params.dim,
            force: &mut self.force,
        };
        let mut a = vec![0.0; p.x.len()];
        dynamics.accel(self.time, &p.x, &p.v, &mut a)?;
        Ok(a)
    }

    /// Advances the world by one time step `dt`, in the seed's order:
    ///
    /// 1. integrate — the state (t) → (t + dt) by the chosen method, under the forces;
    /// 2. detect — collisions between particles and with colliders;
    /// 3. respond — Newton's restitution law u_n⁺ = −e u_n⁻ gives each contact's impulse;
    /// 4. distribute — each impulse acts on both particles, equal and opposite.
    ///
    /// Stages 2–4 come with the collision module; today a step is stage 1.
    ///
    /// A step that would produce a non-finite state fails with [`Error::Diverged`] and leaves
    /// the world as it was before the step.
    pub fn step(&mut self) -> Result<(), Error> {
        self.integrate()?;
        self.time = self.params_time_after(self.steps + 1);
        self.steps += 1;
        Ok(())
    }

    /// Time after `k` steps: t = k·dt, computed by multiplication so it does not drift.
    fn params_time_after(&self, k: u64) -> f64 {
        k as f64 * self.params.dt
    }

    /// Stage 1: integrate positions and velocities over one step.
    fn integrate(&mut self) -> Result<(), Error> {
        let n = 3 * self.particles.len();
        if n == 0 {
            return Ok(());
        }
        let (t, h) = (self.time, self.params.dt);
        let p = &mut self.particles;
        self.y.resize(2 * n, 0.0);
        self.y_next.resize(2 * n, 0.0);
        FirstOrderForm::join(&p.x, &p.v, n, &mut self.y);
        let stepper = self.stepper.get_or_insert_with(|| WorldStepper::new(&self.params.method, n));
        let mut dynamics = Dynamics {
            forces: &mut self.forces,
            mass: &p.mass,
            inv_mass: &p.inv_mass,
            dim: self.params.dim,
            force: &mut self.force,
        };
        let outcome = match stepper {
            WorldStepper::SecondOrder(s) => s.step(&mut dynamics, t, &self.y, h, &mut self.y_next, &mut self.stats),
            WorldStepper::FirstOrder(s) => {
                let mut first = FirstOrderForm::new(&mut dynamics);
                s.step(&mut first, t, &self.y, h, &mut self.y_next, &mut self.stats)
            }
            WorldStepper::Adaptive => {
                let opts = SolveOptions {
                    t_span: (t, t + h),
                    t_eval: Some(vec![t + h]),
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
            Err(StepFailure::Stop(_)) => return Err(self.diverged(None)),
        }
        if let Some(index) = first_non_finite(&self.y_next) {
            return Err(self.diverged(Some(index)));
        }
        FirstOrderForm::split(&self.y_next, n, &mut self.particles.x, &mut self.particles.v);
        Ok(())
    }

    fn diverged(&mut self, index: Option<usize>) -> Error {
        self.stepper = None;
        let n = 3 * self.particles.len();
        // y_next = [x, v]: component c belongs to particle (c mod n) / 3.
        let particle = index.map(|c| (c % n) / 3);
        Error::Diverged {
            step: self.steps + 1,
            time: self.time,
            particle,
            dt: self.params.dt,
        }
    }
}
