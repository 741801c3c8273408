//! Turbulence: curl noise, a divergence-free random field (Bridson, Hourihan & Nordenstam 2007).
//!
//! "Curl-noise for procedural fluid flow" (SIGGRAPH 2007): a velocity field that is the curl
//! of a smooth random vector potential ψ is divergence-free, ∇·(∇ × ψ) = 0, so particles that
//! follow it swirl without bunching up or thinning out, as in an incompressible fluid.
//!
//! The potential. Each component of ψ is Perlin's gradient noise (Perlin 2002, "Improving
//! noise") on the lattice of spacing `scale` L: at p = x/L, with the cell's corners c and
//! their random gradients g_c,
//!
//! ```text
//!   n(p) = Σ_c W_c(p) g_c·(p − c),     W_c = Π_k w(f_k) or (1 − w(f_k)),  f = p − ⌊p⌋,
//!   w(f) = 6f⁵ − 15f⁴ + 10f³     (C²: its first and second derivatives vanish at 0 and 1)
//! ```
//!
//! so n is twice continuously differentiable and its gradient and Hessian are sums over the
//! corners in closed form (`noise` below): with L = g·(p − c), ∂ᵢn = Σ (∂ᵢW L + W gᵢ) and
//! ∂ᵢ∂ⱼn = Σ (∂ᵢ∂ⱼW L + ∂ᵢW gⱼ + ∂ⱼW gᵢ). The gradients are drawn from a hash of the corner, the
//! component and the `seed`: each component uniform in [−1, 1], the same numbers on every
//! platform. The three components of ψ use independent hashes.
//!
//! The field, from the potential's analytic gradients (no finite differences, so the
//! divergence is zero to rounding: ∂ⱼuⱼ is a sum of Hessian entries that cancel in pairs):
//!
//! ```text
//!   3D:  u = ∇ × (ψ₀, ψ₁, ψ₂) = (∂₁ψ₂ − ∂₂ψ₁, ∂₂ψ₀ − ∂₀ψ₂, ∂₀ψ₁ − ∂₁ψ₀)
//!   2D:  u = (∂ψ/∂y, −∂ψ/∂x, 0)    from one stream function ψ(x, y)
//! ```
//!
//! Octaves (Houdini's "turbulence"): octave o is noise of spacing L/2ᵒ, weighted by
//! `roughness`ᵒ; each octave's curl is taken in its own lattice units, so each adds
//! roughnessᵒ of the first octave's amplitude. The sum is divided by its measured rms per
//! component, so that `strength` is the rms of each component of u (m/s² or m/s), averaged
//! over space: RMS_3D and RMS_2D below, measured over 10⁶ points (test
//! `statistics_are_isotropic_and_scaled`).
//!
//! Time (`time_scale` τ, s; ∞: a frozen field). Each corner's gradient turns in the plane of
//! two random vectors, g_c(t) = a_c cos θ_c + b_c sin θ_c, θ_c = ±ω_c t/τ with the rate ω_c
//! uniform in [½, 3/2] and the sign drawn by the hash, as Perlin & Neyret's flow noise (2001)
//! turns its gradients: the field changes over about τ without drifting in space and without
//! pulsing (the gradients' second moments are the same at every t), and stays
//! divergence-free at every instant. Its correlation in time, ⟨u(x, 0)·u(x, t)⟩/⟨|u|²⟩ =
//! E[cos θ_c] = 2 cos(t/τ) sin(t/2τ)/(t/τ), decays as τ/t.
//!
//! Felt as an acceleration or a wind, and shaped by a falloff, as every field
//! ([`super::field`]). A falloff weight φ(x) multiplies the force, so the shaped field φ u has
//! divergence ∇φ·u where φ varies (the band between the falloff's distances), zero elsewhere.

use super::falloff::Falloff;
use super::field::{self, Coupling, VectorField};
use super::{Force, Linearized, Properties, Rates, State};
use crate::error::{CallbackError, Error};

/// The rms of each component of one octave's curl in 3D, with gradients uniform in [−1, 1]³
/// (measured; see the module's doc).
const RMS_3D: f64 = 0.7042;
/// The same in 2D.
const RMS_2D: f64 = 0.5100;
/// The most octaves.
pub const MAX_OCTAVES: u32 = 8;

/// Curl-noise turbulence (see the module's doc).
///
/// `strength` (rms of each component of u: m/s² as an acceleration, m/s as a wind; finite,
/// ≥ 0); `scale` L, the noise's feature size, m (finite, > 0); `seed`; `time_scale` τ, s (> 0;
/// ∞ freezes the field); `octaves` (1 to [`MAX_OCTAVES`]) and `roughness` (each octave's
/// weight relative to the one before, in [0, 1]); `dim`, 2 (the xy-plane, a stream
/// function) or 3; the `coupling`; an optional `falloff`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Turbulence {
    /// rms of each component of u, m/s² or m/s.
    pub strength: f64,
    /// The feature size L, m.
    pub scale: f64,
    /// Which random field.
    pub seed: u64,
    /// τ, s (∞: frozen).
    pub time_scale: f64,
    /// Octaves of noise.
    pub octaves: u32,
    /// Each octave's weight relative to the one before.
    pub roughness: f64,
    /// 2 or 3.
    pub dim: usize,
    /// How particles feel it.
    pub coupling: Coupling,
    /// Where it acts (`None`: everywhere).
    pub falloff: Option<Falloff>,
}

/// Splitmix64's finaliser: a bijective mixing of 64 bits.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A hash of a lattice corner under `key`.
fn corner_hash(key: u64, cell: [i64; 3]) -> u64 {
    let mut h = key;
    for c in cell {
        h = mix(h.wrapping_add(c as u64).wrapping_add(0x9E37_79B9_7F4A_7C15));
    }
    h
}

/// Three numbers uniform in [−1, 1) from 21 bits each of `h`.
fn unit_cube(h: u64) -> [f64; 3] {
    let c = |k: u32| ((h >> (21 * k)) & 0x1F_FFFF) as f64 * (2.0 / (1u64 << 21) as f64) - 1.0;
    [c(0), c(1), c(2)]
}

/// Uniform in [0, 1) from the top 53 bits of `h`.
fn unit(h: u64) -> f64 {
    (h >> 11) as f64 / (1u64 << 53) as f64
}

/// Perlin's quintic fade w(f) and its first two derivatives.
fn fade(f: f64) -> (f64, f64, f64) {
    let w = f * f * f * (f * (6.0 * f - 15.0) + 10.0);
    let dw = 30.0 * f * f * (f - 1.0) * (f - 1.0);
    let ddw = 60.0 * f * (f - 1.0) * (2.0 * f - 1.0);
    (w, dw, ddw)
}

/// The gradient and the Hessian (lattice units) of one noise field.
type Derivatives = ([f64; 3], [[f64; 3]; 3]);

/// The gradients and (with `hessian`) the Hessians of `keys.len()` (1 or 3) gradient-noise
/// fields at `p` in its first `dim` coordinates (see the module's doc), in lattice units,
/// at the turning time `phase` = t/τ (`None`: frozen). The fields share their corners'
/// weights and, when turning, each corner's angle θ_c = ±ω_c t/τ (drawn under `angle_key`,
/// ω_c uniform in [½, 3/2]); their gradients are independent.
#[allow(clippy::needless_range_loop)] // i, j index several arrays at once: the formulas read as written
fn noise(keys: &[u64], angle_key: u64, p: [f64; 3], dim: usize, phase: Option<f64>, hessian: bool) -> [Derivatives; 3] {
    let mut base = [0i64; 3];
    let mut f = [0.0; 3];
    // per axis and corner bit: the weight, its slope, its curvature
    let mut wgt = [[1.0; 2]; 3];
    let mut slope = [[0.0; 2]; 3];
    let mut curv = [[0.0; 2]; 3];
    for k in 0..dim {
        let fl = p[k].floor();
        base[k] = fl as i64;
        f[k] = p[k] - fl;
        let (w, dw, ddw) = fade(f[k]);
        wgt[k] = [1.0 - w, w];
        slope[k] = [-dw, dw];
        curv[k] = [-ddw, ddw];
    }
    let mut out = [([0.0; 3], [[0.0; 3]; 3]); 3];
    for corner in 0..(1usize << dim) {
        let bit = |k: usize| (corner >> k) & 1;
        let mut cell = base;
        let mut delta = [0.0; 3];
        for k in 0..dim {
            cell[k] += bit(k) as i64;
            delta[k] = f[k] - bit(k) as f64;
        }
        // this corner's weight W = Π A_k, its gradient ∂ᵢW and Hessian ∂ᵢ∂ⱼW, from each
        // axis' weight A_k, slope B_k and curvature C_k (A_k = 1 beyond `dim`)
        let a = |k: usize| wgt[k][bit(k)];
        let b = |k: usize| slope[k][bit(k)];
        let all = a(0) * a(1) * a(2);
        let mut dw = [0.0; 3];
        let mut ddw = [[0.0; 3]; 3];
        for i in 0..dim {
            dw[i] = b(i) * (0..3).filter(|&k| k != i).map(a).product::<f64>();
            if hessian {
                ddw[i][i] = curv[i][bit(i)] * (0..3).filter(|&k| k != i).map(a).product::<f64>();
                for j in i + 1..dim {
                    ddw[i][j] = b(i) * b(j) * (0..3).filter(|&k| k != i && k != j).map(a).product::<f64>();
                }
            }
        }
        let turn = phase.map(|ph| {
            let h = corner_hash(angle_key, cell);
            let (s, c) = ((0.5 + unit(h)) * ph).sin_cos();
            (c, if h & 1 == 0 { s } else { -s })
        });
        for (key, (grad, hess)) in keys.iter().zip(out.iter_mut()) {
            let h = corner_hash(*key, cell);
            let mut g = unit_cube(h);
            if let Some((c, s)) = turn {
                let g2 = unit_cube(mix(h ^ 0x5851_F42D_4C95_7F2D));
                g = [g[0] * c + g2[0] * s, g[1] * c + g2[1] * s, g[2] * c + g2[2] * s];
            }
            // n = Σ W L, L = g·(p − c): ∂ᵢn = Σ ∂ᵢW L + W gᵢ, ∂ᵢ∂ⱼn = Σ ∂ᵢ∂ⱼW L + ∂ᵢW gⱼ + ∂ⱼW gᵢ
            let l: f64 = (0..dim).map(|k| g[k] * delta[k]).sum();
            for i in 0..dim {
                grad[i] += dw[i] * l + all * g[i];
                if hessian {
                    for j in i..dim {
                        hess[i][j] += ddw[i][j] * l + dw[i] * g[j] + dw[j] * g[i];
                    }
                }
            }
        }
    }
    for (_, hess) in out.iter_mut() {
        for i in 0..dim {
            for j in 0..i {
                hess[i][j] = hess[j][i];
            }
        }
    }
    out
}

impl Turbulence {
    /// Curl-noise turbulence (see the type's doc); checks every parameter.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        strength: f64,
        scale: f64,
        seed: u64,
        time_scale: f64,
        octaves: u32,
        roughness: f64,
        dim: usize,
        coupling: Coupling,
        falloff: Option<Falloff>,
    ) -> Result<Turbulence, Error> {
        let t = Turbulence {
            strength,
            scale,
            seed,
            time_scale,
            octaves,
            roughness,
            dim,
            coupling,
            falloff,
        };
        t.check()?;
        Ok(t)
    }

    fn check(&self) -> Result<(), Error> {
        if !(self.strength.is_finite() && self.strength >= 0.0) {
            return Err(Error::invalid(
                "strength",
                self.strength,
                "the turbulence strength (rms of each component) must be finite and >= 0",
            ));
        }
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return Err(Error::invalid(
                "scale",
                self.scale,
                "the turbulence scale (feature size) must be finite and > 0 m",
            ));
        }
        if self.time_scale.is_nan() || self.time_scale <= 0.0 {
            return Err(Error::invalid(
                "time_scale",
                self.time_scale,
                "the turbulence time scale must be > 0 s (inf: a frozen field)",
            ));
        }
        if !(1..=MAX_OCTAVES).contains(&self.octaves) {
            return Err(Error::invalid(
                "octaves",
                self.octaves,
                format!("octaves must be an integer from 1 to {MAX_OCTAVES}"),
            ));
        }
        if !(0.0..=1.0).contains(&self.roughness) {
            return Err(Error::invalid("roughness", self.roughness, "the roughness must be in [0, 1]"));
        }
        if !matches!(self.dim, 2 | 3) {
            return Err(Error::invalid("dim", self.dim, "the turbulence's dimension must be 2 or 3"));
        }
        self.coupling.check()?;
        self.falloff.map_or(Ok(()), |f| f.check())
    }

    /// The hash key of potential component `component` in octave `octave`.
    fn key(&self, component: u64, octave: u32) -> u64 {
        mix(mix(self.seed ^ 0xD1B5_4A32_D192_ED03).wrapping_add(component * 64 + octave as u64))
    }

    /// strength / (rms of the unit sum): the factor from the octaves' summed curl to u.
    fn amplitude(&self) -> f64 {
        let r2 = self.roughness * self.roughness;
        let sum: f64 = (0..self.octaves).map(|o| r2.powi(o as i32)).sum();
        let rms = if self.dim == 2 { RMS_2D } else { RMS_3D };
        self.strength / (rms * sum.sqrt())
    }

    /// u(x, t) and, with `jacobian`, ∂u/∂x.
    fn eval(&self, t: f64, x: [f64; 3], jacobian: bool) -> ([f64; 3], [[f64; 3]; 3]) {
        let phase = self.time_scale.is_finite().then(|| t / self.time_scale);
        let amp = self.amplitude();
        let (mut u, mut du) = ([0.0; 3], [[0.0; 3]; 3]);
        let mut weight = 1.0;
        for o in 0..self.octaves {
            let freq = (1u64 << o) as f64 / self.scale; // lattice units per metre
            let p = [x[0] * freq, x[1] * freq, if self.dim == 3 { x[2] * freq } else { 0.0 }];
            let w = amp * weight;
            let wj = w * freq; // ∂/∂x = freq ∂/∂p
            let angle_key = self.key(3, o);
            if self.dim == 2 {
                let [(g, h), _, _] = noise(&[self.key(0, o)], angle_key, p, 2, phase, jacobian);
                u[0] += w * g[1];
                u[1] -= w * g[0];
                for j in 0..2 {
                    du[0][j] += wj * h[1][j];
                    du[1][j] -= wj * h[0][j];
                }
            } else {
                let keys = [self.key(0, o), self.key(1, o), self.key(2, o)];
                let [(g0, h0), (g1, h1), (g2, h2)] = noise(&keys, angle_key, p, 3, phase, jacobian);
                u[0] += w * (g2[1] - g1[2]);
                u[1] += w * (g0[2] - g2[0]);
                u[2] += w * (g1[0] - g0[1]);
                for j in 0..3 {
                    du[0][j] += wj * (h2[1][j] - h1[2][j]);
                    du[1][j] += wj * (h0[2][j] - h2[0][j]);
                    du[2][j] += wj * (h1[0][j] - h0[1][j]);
                }
            }
            weight *= self.roughness;
        }
        (u, du)
    }
}

impl VectorField for Turbulence {
    fn value(&self, t: f64, x: [f64; 3]) -> [f64; 3] {
        self.eval(t, x, false).0
    }

    fn jacobian(&self, t: f64, x: [f64; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
        self.eval(t, x, true)
    }
}

impl Force for Turbulence {
    fn name(&self) -> &str {
        "turbulence"
    }

    /// Adds φ m_i u or φ b (u − v_i), N (all threads).
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        field::accumulate(self.name(), self, self.coupling, self.falloff.as_ref(), s, f)
    }

    /// Re-checks the parameters (the fields are public and may have changed).
    fn validate(&self, _n: usize) -> Result<(), Error> {
        self.check()
    }

    fn properties(&self) -> Properties {
        field::properties(self.coupling)
    }

    /// ∂F/∂x (from the noise's analytic Hessians) and ∂F/∂v per particle, prepared at `s`.
    fn linearize(&self, s: &State, _definite: bool) -> Option<Box<dyn Linearized>> {
        field::boxed(field::linearize(self, self.coupling, self.falloff.as_ref(), s))
    }

    /// Gershgorin bounds of the prepared Jacobian at `s`.
    fn rates(&self, s: &State, inv_mass: &[f64]) -> Option<Rates> {
        field::rates(self, self.coupling, self.falloff.as_ref(), s, inv_mass)
    }
}

#[cfg(test)]
#[path = "tests/turbulence.rs"]
mod tests;
