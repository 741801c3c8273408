//! Field forces: what turbulence and the vortex share — a field u(x, t) felt as an
//! acceleration or as air to be dragged along by, shaped by a falloff.
//!
//! A field gives u(x, t) and its Jacobian ∂u/∂x at a point ([`VectorField`]). A
//! [`Coupling`] says how the particles feel it, and a [`Falloff`] weight φ(x) in [0, 1]
//! (1 without one) scales the result:
//!
//! ```text
//!   acceleration:  F_i = φ(x_i) m_i u(x_i, t)              (u in m/s²; Blender's force fields)
//!   wind:          F_i = φ(x_i) b (u(x_i, t) − v_i)        (u in m/s, b in kg/s; Houdini's
//!                                                          "treat as wind" with air resistance b)
//! ```
//!
//! Differentiating, with F₀ the force before the falloff:
//!
//! ```text
//!   ∂F/∂x = φ c ∂u/∂x + F₀ ∇φᵀ      (c = m, or b for wind)
//!   ∂F/∂v = −φ b I                   (wind; 0 for an acceleration)
//! ```
//!
//! Each particle's force depends on its own state alone, so the particles are evaluated in
//! fixed chunks on all threads: the same numbers for any number of threads.

use rayon::prelude::*;

use super::falloff::Falloff;
use super::{check_buffers, EnergyClass, Linearized, Properties, Rates, State};
use crate::error::{CallbackError, Error};
use crate::vec3::get;

/// Particles per chunk of the parallel passes (fixed, so the split is the same for any
/// number of threads; each particle's value is computed alone whatever the split).
const CHUNK: usize = 1024;

/// A vector field u(x, t) with its Jacobian in x.
pub(crate) trait VectorField: Sync {
    /// u(x, t).
    fn value(&self, t: f64, x: [f64; 3]) -> [f64; 3];
    /// u(x, t) and ∂u/∂x (row k: the gradient of u_k).
    fn jacobian(&self, t: f64, x: [f64; 3]) -> ([f64; 3], [[f64; 3]; 3]);
}

/// How particles feel a field (see the module's doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Coupling {
    /// F = m u: the field is an acceleration, m/s², the same for every mass.
    Acceleration,
    /// F = b (u − v): the field is the velocity of air, m/s, and b the drag coefficient, kg/s
    /// (finite, ≥ 0): particles tend to move with it.
    Wind(f64),
}

impl Coupling {
    /// `None` is an acceleration, `Some(b)` a wind of coefficient b.
    pub fn from_coefficient(coefficient: Option<f64>) -> Coupling {
        coefficient.map_or(Coupling::Acceleration, Coupling::Wind)
    }

    /// Checks b.
    pub fn check(&self) -> Result<(), Error> {
        match *self {
            Coupling::Wind(b) if !(b.is_finite() && b >= 0.0) => Err(Error::invalid(
                "coefficient",
                b,
                "the drag coefficient toward the field must be finite and >= 0 kg/s (None: the field is an acceleration)",
            )),
            _ => Ok(()),
        }
    }
}

/// The properties of a field force: a source of energy, depending on the positions (and the
/// velocities for a wind), per particle, holding no indices.
pub(crate) fn properties(coupling: Coupling) -> Properties {
    Properties {
        energy: EnergyClass::Source,
        depends_on_position: true,
        depends_on_velocity: matches!(coupling, Coupling::Wind(_)),
        internal: false,
        renumbers: true,
        per_particle: true,
    }
}

/// The force on one particle (N) at position `x`, velocity `v`, mass `m`.
fn force_at<F: VectorField>(
    field: &F,
    coupling: Coupling,
    falloff: Option<&Falloff>,
    t: f64,
    x: [f64; 3],
    v: [f64; 3],
    m: f64,
) -> [f64; 3] {
    let phi = falloff.map_or(1.0, |f| f.weight(x));
    if phi == 0.0 {
        return [0.0; 3];
    }
    let u = field.value(t, x);
    match coupling {
        Coupling::Acceleration => [phi * m * u[0], phi * m * u[1], phi * m * u[2]],
        Coupling::Wind(b) => {
            let c = phi * b;
            [c * (u[0] - v[0]), c * (u[1] - v[1]), c * (u[2] - v[2])]
        }
    }
}

/// Adds a field force to `f` (N), the particles in fixed chunks on all threads.
pub(crate) fn accumulate<F: VectorField>(
    name: &str,
    field: &F,
    coupling: Coupling,
    falloff: Option<&Falloff>,
    s: &State,
    f: &mut [f64],
) -> Result<(), CallbackError> {
    check_buffers(name, s, &[("f", f.len())])?;
    f.par_chunks_mut(3 * CHUNK).enumerate().for_each(|(c, fc)| {
        for (l, fi) in fc.chunks_exact_mut(3).enumerate() {
            let p = c * CHUNK + l;
            let add = force_at(field, coupling, falloff, s.t, get(s.x, p), get(s.v, p), s.mass[p]);
            for k in 0..3 {
                fi[k] += add[k];
            }
        }
    });
    Ok(())
}

/// The Jacobian of a field force at a state, prepared per particle: ∂F/∂x (9 values,
/// row-major) and the scale −φ b of ∂F/∂v = −φ b I.
pub(crate) struct FieldJacobian {
    dfdx: Vec<f64>,
    dfdv: Vec<f64>,
}

/// One particle's ∂F/∂x and ∂F/∂v scale (see the module's doc).
fn jacobian_at<F: VectorField>(
    field: &F,
    coupling: Coupling,
    falloff: Option<&Falloff>,
    t: f64,
    x: [f64; 3],
    v: [f64; 3],
    m: f64,
) -> ([[f64; 3]; 3], f64) {
    let (phi, grad) = falloff.map_or((1.0, [0.0; 3]), |f| f.weight_and_gradient(x));
    if phi == 0.0 && grad == [0.0; 3] {
        return ([[0.0; 3]; 3], 0.0);
    }
    let (u, du) = field.jacobian(t, x);
    let (c, f0, dv) = match coupling {
        Coupling::Acceleration => (m, [m * u[0], m * u[1], m * u[2]], 0.0),
        Coupling::Wind(b) => (b, [b * (u[0] - v[0]), b * (u[1] - v[1]), b * (u[2] - v[2])], -phi * b),
    };
    let mut a = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            a[i][j] = phi * c * du[i][j] + f0[i] * grad[j];
        }
    }
    (a, dv)
}

/// Prepares the Jacobian of a field force at `s` (all threads, fixed chunks).
pub(crate) fn linearize<F: VectorField>(field: &F, coupling: Coupling, falloff: Option<&Falloff>, s: &State) -> FieldJacobian {
    let n = s.len();
    let mut dfdx = vec![0.0; 9 * n];
    let mut dfdv = vec![0.0; n];
    dfdx.par_chunks_mut(9 * CHUNK)
        .zip(dfdv.par_chunks_mut(CHUNK))
        .enumerate()
        .for_each(|(c, (ax, av))| {
            for (l, (a, d)) in ax.chunks_exact_mut(9).zip(av.iter_mut()).enumerate() {
                let p = c * CHUNK + l;
                let (m, dv) = jacobian_at(field, coupling, falloff, s.t, get(s.x, p), get(s.v, p), s.mass[p]);
                for i in 0..3 {
                    a[3 * i..3 * i + 3].copy_from_slice(&m[i]);
                }
                *d = dv;
            }
        });
    FieldJacobian { dfdx, dfdv }
}

impl FieldJacobian {
    /// ω² ≤ max_p w_p ‖∂F_p/∂x‖∞ (row sums), γ ≤ max_p w_p φ_p b: Gershgorin bounds of
    /// M⁻¹ ∂F/∂x and M⁻¹ ∂F/∂v (both block-diagonal, one 3×3 block per particle).
    pub(crate) fn rates(&self, inv_mass: &[f64]) -> Rates {
        let mut r = Rates::default();
        for (p, w) in inv_mass.iter().enumerate().filter(|(p, w)| **w > 0.0 && *p < self.dfdv.len()) {
            let a = &self.dfdx[9 * p..9 * p + 9];
            let row = (0..3)
                .map(|i| a[3 * i].abs() + a[3 * i + 1].abs() + a[3 * i + 2].abs())
                .fold(0.0, f64::max);
            r.omega_squared = r.omega_squared.max(w * row);
            r.damping_rate = r.damping_rate.max(-w * self.dfdv[p]);
        }
        r
    }
}

impl Linearized for FieldJacobian {
    /// Adds (∂F/∂x)·dx − φ b dv per particle.
    fn apply(&self, _s: &State, dx: &[f64], dv: &[f64], out: &mut [f64]) {
        for (p, oi) in out.chunks_exact_mut(3).enumerate() {
            let a = &self.dfdx[9 * p..9 * p + 9];
            for i in 0..3 {
                oi[i] += a[3 * i] * dx[3 * p]
                    + a[3 * i + 1] * dx[3 * p + 1]
                    + a[3 * i + 2] * dx[3 * p + 2]
                    + self.dfdv[p] * dv[3 * p + i];
            }
        }
    }

    /// Adds c_x (∂F/∂x)_kk + c_v (−φ b) per component.
    fn add_diagonal(&self, _s: &State, cx: f64, cv: f64, out: &mut [f64]) {
        for (p, oi) in out.chunks_exact_mut(3).enumerate() {
            for (i, o) in oi.iter_mut().enumerate() {
                *o += cx * self.dfdx[9 * p + 4 * i] + cv * self.dfdv[p];
            }
        }
    }
}

/// Boxes a prepared field Jacobian for [`super::Force::linearize`].
pub(crate) fn boxed(j: FieldJacobian) -> Option<Box<dyn Linearized>> {
    Some(Box::new(j))
}

/// [`super::Force::rates`] of a field force: its Jacobian at `s`, bounded.
pub(crate) fn rates<F: VectorField>(
    field: &F,
    coupling: Coupling,
    falloff: Option<&Falloff>,
    s: &State,
    inv_mass: &[f64],
) -> Option<Rates> {
    if s.x.len() != 3 * s.len() || s.v.len() != 3 * s.len() {
        return None;
    }
    Some(linearize(field, coupling, falloff, s).rates(inv_mass))
}
