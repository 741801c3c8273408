//! The particles' equations of motion, x'' = F(t, x, v) / m, and Jacobian–vector products of F.

use crate::error::CallbackError;
use crate::forces::{Force, Linearized, State, PARALLEL_CHUNK};
use crate::ode::system::SecondOrderSystem;
use rayon::prelude::*;

/// The dynamics of the particles as a second-order system: x'' = F(t, x, v) / m.
///
/// Pinned particles (inverse mass 0) get no acceleration; in 2D the z acceleration is 0.
pub(crate) struct Dynamics<'a, 'f> {
    /// Every force of the evaluation ([`super::forces::every_force`]).
    pub forces: &'a mut [&'f mut dyn Force],
    pub mass: &'a [f64],
    pub inv_mass: &'a [f64],
    pub dim: usize,
    /// Scratch for the summed forces, N (owned by the World, so a step allocates nothing).
    pub force: &'a mut Vec<f64>,
}

impl<'a, 'f> Dynamics<'a, 'f> {
    /// The dynamics of `particles` under `forces` in `dim` dimensions, with `force` as the
    /// buffer of the summed forces.
    pub fn new(
        forces: &'a mut [&'f mut dyn Force],
        particles: &'a crate::particles::Particles,
        dim: usize,
        force: &'a mut Vec<f64>,
    ) -> Self {
        Dynamics {
            forces,
            mass: &particles.mass,
            inv_mass: &particles.inv_mass,
            dim,
            force,
        }
    }

    /// Sums every force at (t, x, v) into `self.force`, N.
    pub fn total_force(&mut self, t: f64, x: &[f64], v: &[f64]) -> Result<(), CallbackError> {
        if self.force.len() == x.len() && x.len() > 3 * PARALLEL_CHUNK {
            self.force.par_chunks_mut(3 * PARALLEL_CHUNK).for_each(|c| c.fill(0.0));
        } else {
            self.force.clear();
            self.force.resize(x.len(), 0.0);
        }
        self.add_forces(t, x, v)
    }

    /// Adds every force at (t, x, v) to `self.force` (N, as long as `x`), which the caller
    /// zeroed: [`Dynamics::total_force`] without its pass of zeros (Verlet's drift writes
    /// them in its own pass).
    pub fn add_forces(&mut self, t: f64, x: &[f64], v: &[f64]) -> Result<(), CallbackError> {
        debug_assert_eq!(self.force.len(), x.len());
        let s = State {
            t,
            x,
            v,
            mass: self.mass,
        };
        for f in self.forces.iter_mut() {
            f.accumulate(&s, self.force)?;
        }
        Ok(())
    }
}

impl SecondOrderSystem for Dynamics<'_, '_> {
    fn dim(&self) -> usize {
        3 * self.mass.len()
    }

    fn accel(&mut self, t: f64, x: &[f64], v: &[f64], acc: &mut [f64]) -> Result<(), CallbackError> {
        self.total_force(t, x, v)?;
        newton(self.force, self.inv_mass, self.dim, acc);
        Ok(())
    }
}

/// Newton's second law, a = F/m (m/s², 3 per particle) from the forces `force` (N), with
/// 1/m = `inv_mass` (0 for pinned particles) and a_z = 0 in 2D; on all threads for more than
/// [`PARALLEL_CHUNK`] particles.
pub(crate) fn newton(force: &[f64], inv_mass: &[f64], dim: usize, acc: &mut [f64]) {
    if inv_mass.len() > PARALLEL_CHUNK {
        let c = PARALLEL_CHUNK;
        acc.par_chunks_mut(3 * c)
            .zip(force.par_chunks(3 * c))
            .zip(inv_mass.par_chunks(c))
            .for_each(|((acc, force), inv_mass)| newton_serial(force, inv_mass, dim, acc));
    } else {
        newton_serial(force, inv_mass, dim, acc);
    }
}

/// [`newton`] written over the forces' own room: a = F/m in place of F (the same products),
/// so that a first acceleration needs no buffer of summed forces beside it.
pub(crate) fn newton_in_place(force_then_acc: &mut [f64], inv_mass: &[f64], dim: usize) {
    let serial = |fa: &mut [f64], inv_mass: &[f64]| {
        for (fa, inv_m) in fa.chunks_exact_mut(3).zip(inv_mass) {
            fa.iter_mut().for_each(|c| *c *= inv_m);
            if dim == 2 {
                fa[2] = 0.0;
            }
        }
    };
    if inv_mass.len() > PARALLEL_CHUNK {
        let c = PARALLEL_CHUNK;
        force_then_acc
            .par_chunks_mut(3 * c)
            .zip(inv_mass.par_chunks(c))
            .for_each(|(fa, inv_mass)| serial(fa, inv_mass));
    } else {
        serial(force_then_acc, inv_mass);
    }
}

/// [`newton`] on the calling thread.
pub(crate) fn newton_serial(force: &[f64], inv_mass: &[f64], dim: usize, acc: &mut [f64]) {
    for (i, inv_m) in inv_mass.iter().enumerate() {
        for k in 0..3 {
            acc[3 * i + k] = force[3 * i + k] * inv_m;
        }
        if dim == 2 {
            acc[3 * i + 2] = 0.0;
        }
    }
}

/// 1 for each state component that moves (a coordinate of a particle that is not pinned,
/// and not z in 2D), 0 for the others: the filter of Baraff & Witkin's constrained solve.
pub(crate) fn free_components(inv_mass: &[f64], dim: usize, out: &mut Vec<f64>) {
    out.clear();
    out.reserve_exact(3 * inv_mass.len());
    for w in inv_mass {
        let free = if *w > 0.0 { 1.0 } else { 0.0 };
        out.extend([free, free, if dim == 2 { 0.0 } else { free }]);
    }
}

/// Jacobian–vector products of the total force at one state (t, x, v):
/// J·(dx, dv) = (∂F/∂x) dx + (∂F/∂v) dv.
///
/// Forces that know their Jacobian add it exactly ([`Force::linearize`], the definite
/// variant for the implicit solve); the others are differentiated by a forward
/// difference, (F(x + ε dx, v + ε dv) − F(x, v)) / ε, with ε = √ε_mach (1 + ‖(x, v)‖∞) /
/// ‖(dx, dv)‖∞ — the step that balances truncation O(ε) against rounding O(ε_mach / ε).
#[derive(Default)]
pub(crate) struct ForceJacobian {
    /// Whether force k provides its own product (decided when prepared).
    analytic: Vec<bool>,
    /// Force k's Jacobian prepared at the state, when it prepares one ([`Force::linearize`]).
    prepared: Vec<Option<Box<dyn Linearized>>>,
    /// The numerically differentiated forces summed at the state, N.
    base: Vec<f64>,
    /// Whether some force is differentiated numerically.
    numeric: bool,
    /// ‖(x, v)‖∞ at the state.
    scale: f64,
    xp: Vec<f64>,
    vp: Vec<f64>,
    fp: Vec<f64>,
    /// Evaluations of the numerically differentiated forces so far.
    pub evaluations: usize,
}

impl ForceJacobian {
    /// Prepares products at state `s`: finds which forces give their own, and evaluates the
    /// others once at `s` (the base of the differences).
    pub fn prepare(&mut self, forces: &mut [&mut dyn Force], s: &State, definite: bool) -> Result<(), CallbackError> {
        let n = s.x.len();
        self.analytic.clear();
        self.prepared.clear();
        for f in forces.iter() {
            let op = f.linearize(s, definite);
            self.analytic.push(op.is_some());
            self.prepared.push(op);
        }
        self.numeric = self.analytic.iter().any(|a| !a);
        // (the difference buffers are made when a product needs them: at 10⁶ particles each is
        // 24 MB)
        for b in [&mut self.xp, &mut self.vp, &mut self.fp] {
            *b = Vec::new();
        }
        if !self.numeric {
            // Every force gives its own products: no base either.
            self.base = Vec::new();
            self.scale = s.x.iter().chain(s.v).fold(0.0_f64, |a, b| a.max(b.abs()));
            return Ok(());
        }
        self.base.clear();
        self.base.resize(n, 0.0);
        for (f, has) in forces.iter_mut().zip(&self.analytic) {
            if !has {
                f.accumulate(s, &mut self.base)?;
            }
        }
        self.evaluations += 1;
        self.scale = s.x.iter().chain(s.v).fold(0.0_f64, |a, b| a.max(b.abs()));
        Ok(())
    }

    /// Writes J·(dx, dv) into `out` (N per unit of dx, dv), at the prepared state `s`.
    pub fn apply(
        &mut self,
        forces: &mut [&mut dyn Force],
        s: &State,
        dx: &[f64],
        dv: &[f64],
        out: &mut [f64],
    ) -> Result<(), CallbackError> {
        out.fill(0.0);
        for op in self.prepared.iter().flatten() {
            op.apply(s, dx, dv, out);
        }
        if !self.numeric {
            return Ok(());
        }
        let size = dx.iter().chain(dv).fold(0.0_f64, |a, b| a.max(b.abs()));
        if size == 0.0 {
            return Ok(());
        }
        let eps = f64::EPSILON.sqrt() * (1.0 + self.scale) / size;
        // The perturbed state: a direction that is zero (the stable-step advisor probes the
        // positions and the velocities apart) leaves its half as it is (x + ε·0 = x, to the
        // sign of a zero), with no copy.
        let x = probed(&mut self.xp, s.x, dx, eps);
        let v = probed(&mut self.vp, s.v, dv, eps);
        let perturbed = State {
            t: s.t,
            x,
            v,
            mass: s.mass,
        };
        // Where no force gives its own product, `out` (zeros) sums the perturbed forces
        // itself, then becomes their difference quotient: no buffer of its own.
        let fp = if self.prepared.iter().all(Option::is_none) {
            self.fp = Vec::new();
            &mut *out
        } else {
            self.fp.clear();
            self.fp.resize(out.len(), 0.0);
            &mut self.fp[..]
        };
        for (f, has) in forces.iter_mut().zip(&self.analytic) {
            if !has {
                f.accumulate(&perturbed, fp)?;
            }
        }
        self.evaluations += 1;
        if self.fp.is_empty() {
            for (o, f0) in out.iter_mut().zip(&self.base) {
                *o = (*o - f0) / eps;
            }
        } else {
            for ((o, fp), f0) in out.iter_mut().zip(&self.fp).zip(&self.base) {
                *o += (fp - f0) / eps;
            }
        }
        Ok(())
    }

    /// Adds c_x·diag(∂F/∂x) + c_v·diag(∂F/∂v) of the prepared forces that provide it (the
    /// others are left out: the diagonal only preconditions).
    pub fn add_diagonal(&self, s: &State, cx: f64, cv: f64, out: &mut [f64]) {
        for op in self.prepared.iter().flatten() {
            op.add_diagonal(s, cx, cv, out);
        }
    }
}

/// `at + eps d` in `room`, or `at` itself where the direction `d` is zero (its room let go).
fn probed<'a>(room: &'a mut Vec<f64>, at: &'a [f64], d: &[f64], eps: f64) -> &'a [f64] {
    if d.iter().all(|c| *c == 0.0) {
        *room = Vec::new();
        return at;
    }
    room.clear();
    room.extend(at.iter().zip(d).map(|(a, d)| a + eps * d));
    room
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forces::{Drag, Springs};

    /// A force without a Jacobian: F_i = −k x_i³ per component (∂F/∂x = −3k x² on the diagonal).
    struct Cubic(f64);
    impl Force for Cubic {
        fn name(&self) -> &str {
            "cubic"
        }
        fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
            for (fi, xi) in f.iter_mut().zip(s.x) {
                *fi -= self.0 * xi * xi * xi;
            }
            Ok(())
        }
    }

    /// Theory: the analytic parts add exactly and the cubic force's product is −3k x² dx, which
    /// a forward difference reproduces to about √ε_mach relative.
    #[test]
    fn numeric_and_analytic_products_add() {
        let x = [0.1, 0.2, 0.3, 1.0, 1.2, 0.9];
        let v = [0.5, -0.5, 0.0, 0.1, 0.0, 0.2];
        let mass = [1.0, 2.0];
        let s = State {
            t: 0.0,
            x: &x,
            v: &v,
            mass: &mass,
        };
        let springs = Springs::uniform(vec![0], vec![1], 30.0, 0.5, 0.7).unwrap();
        let mut forces: Vec<Box<dyn Force>> = vec![
            Box::new(springs.clone()),
            Box::new(Cubic(4.0)),
            Box::new(Drag::new(0.3, 0.0).unwrap()),
        ];
        let mut jac = ForceJacobian::default();
        let mut forces: Vec<&mut dyn Force> = forces.iter_mut().map(|f| &mut **f as &mut dyn Force).collect();
        jac.prepare(&mut forces, &s, false).unwrap();
        let dx = [0.3, -0.1, 0.2, 0.0, 0.4, -0.2];
        let dv = [0.1, 0.2, -0.3, 0.05, 0.0, 0.1];
        let mut out = [0.0; 6];
        jac.apply(&mut forces, &s, &dx, &dv, &mut out).unwrap();
        let mut expected = [0.0; 6];
        springs.linearize(&s, false).unwrap().apply(&s, &dx, &dv, &mut expected);
        for k in 0..6 {
            expected[k] += -3.0 * 4.0 * x[k] * x[k] * dx[k] - 0.3 * dv[k];
        }
        for k in 0..6 {
            assert!(
                (out[k] - expected[k]).abs() < 1e-6 * (1.0 + expected[k].abs()),
                "{k}: {out:?} vs {expected:?}"
            );
        }
        assert_eq!(jac.evaluations, 2, "one base evaluation, one per product");
    }

    #[test]
    fn free_components_filter_pinned_particles_and_2d_z() {
        let mut out = Vec::new();
        free_components(&[1.0, 0.0, 0.5], 2, &mut out);
        assert_eq!(out, vec![1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0]);
        free_components(&[1.0, 0.0], 3, &mut out);
        assert_eq!(out, vec![1.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
    }
}
