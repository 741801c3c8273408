//! The particles' paths through a step for continuous detection (see `collide::events`), and
//! the first impact of two of them.
//!
//! Within a step of length h every particle moves on a parabola
//! x(τ) = x_ref + v_ref (τ − t_ref) + ½ a (τ − t_ref)², with t_ref = 0 and (x_ref, v_ref) its
//! state at the start until an impact changes it: the impact moves the particle's reference to
//! the impact time and its velocity there gets the impulse. `a` is the constant acceleration
//! of the step (Verlet's a(t), or the one that takes a method's x₀, v₀ to its x₁), exact for
//! uniform fields such as gravity, under which the relative motion of two particles is a
//! straight line. The references are read in place from the world's state (x₀, v₀): a
//! particle gets its own copy only when an impact opens its path ([`PathStore`]), so a step
//! copies nothing for the particles nothing happens to.
//!
//! Two paths' first meeting is [`pair_toi`] (exact for straight relative motion, Newton's
//! method on the chord otherwise); [`swept_reach`] bounds how far a path can go in the rest of
//! the step.

use super::domain::Domain;
use super::toi::toi_spheres;
use crate::vec3;

/// Where the step's paths are kept, allocated once: the reference states of the particles
/// whose path was opened in this step (an impact or a rebuild moved its reference), marked
/// by the step's number. A particle whose path is not open is on its path from the step's
/// start, read from the world's state where it lies: a step copies nothing for particles
/// nothing happens to.
#[derive(Debug, Clone, Default)]
pub(crate) struct PathStore {
    /// Time of each open path's reference state, s from the step's start.
    t_ref: Vec<f64>,
    /// Position (m) and velocity (m/s) at `t_ref`, 3 values per particle.
    x_ref: Vec<f64>,
    v_ref: Vec<f64>,
    /// Impacts each open path has had in the step (its version; 0 if not open).
    version: Vec<u32>,
    /// The step in which each particle's path was last opened.
    opened: Vec<u32>,
    step: u32,
    /// The particles whose path is open, in the order they were opened.
    open: Vec<usize>,
}

/// The particles' paths through one step (see the module doc): each starts at (x0, v0) at
/// τ = 0 with constant acceleration `accel`, until an impact opens it (its reference moves
/// to the impact, where its velocity gets the impulse).
pub(crate) struct Paths<'a> {
    /// The world's state at the step's start, m and m/s.
    pub x0: &'a [f64],
    pub v0: &'a [f64],
    /// Constant acceleration of the step, m/s², 3 per particle.
    pub accel: &'a [f64],
    store: &'a mut PathStore,
}

impl<'a> Paths<'a> {
    /// Starts the step: every particle at (x0, v0) at τ = 0 with acceleration `accel`.
    pub fn begin(store: &'a mut PathStore, x0: &'a [f64], v0: &'a [f64], accel: &'a [f64]) -> Self {
        let n = x0.len() / 3;
        store.step = store.step.wrapping_add(1);
        if store.step == 0 || store.opened.len() != n {
            // a new size, or the step numbers wrapped: no path is open
            store.opened.clear();
            store.opened.resize(n, 0);
            store.step = 1;
            store.t_ref.resize(n, 0.0);
            store.version.resize(n, 0);
            store.x_ref.resize(3 * n, 0.0);
            store.v_ref.resize(3 * n, 0.0);
        }
        store.open.clear();
        Paths { x0, v0, accel, store }
    }

    fn is_open(&self, q: usize) -> bool {
        self.store.opened[q] == self.store.step
    }

    /// Opens particle q's path (its reference: the step's start).
    fn open(&mut self, q: usize) {
        if self.is_open(q) {
            return;
        }
        let s = &mut *self.store;
        s.opened[q] = s.step;
        s.open.push(q);
        s.t_ref[q] = 0.0;
        s.version[q] = 0;
        s.x_ref[3 * q..3 * q + 3].copy_from_slice(&self.x0[3 * q..3 * q + 3]);
        s.v_ref[3 * q..3 * q + 3].copy_from_slice(&self.v0[3 * q..3 * q + 3]);
    }

    /// Position and velocity of particle q at time t on its current path.
    #[inline]
    pub fn state_at(&self, q: usize, t: f64) -> ([f64; 3], [f64; 3]) {
        let (x_ref, v_ref, dt) = if self.is_open(q) {
            (&self.store.x_ref[..], &self.store.v_ref[..], t - self.store.t_ref[q])
        } else {
            (self.x0, self.v0, t)
        };
        let (x, v, a) = (vec3::get(x_ref, q), vec3::get(v_ref, q), vec3::get(self.accel, q));
        (vec3::parabola(x, v, a, dt), [0, 1, 2].map(|k| v[k] + a[k] * dt))
    }

    /// Impacts particle q has had in the step (its path's version).
    #[inline]
    pub fn version(&self, q: usize) -> u32 {
        if self.is_open(q) {
            self.store.version[q]
        } else {
            0
        }
    }

    /// Moves particle q's reference along its path to time t (opening it).
    pub fn advance(&mut self, q: usize, t: f64) {
        self.open(q);
        if self.store.t_ref[q] == t {
            return;
        }
        let (x, v) = self.state_at(q, t);
        let s = &mut *self.store;
        s.x_ref[3 * q..3 * q + 3].copy_from_slice(&x);
        s.v_ref[3 * q..3 * q + 3].copy_from_slice(&v);
        s.t_ref[q] = t;
    }

    /// The reference position of an open path, m.
    pub fn x_ref(&self, q: usize) -> [f64; 3] {
        debug_assert!(self.is_open(q));
        vec3::get(&self.store.x_ref, q)
    }

    /// The reference velocities, m/s (meaningful for open paths only: impulses go there
    /// after [`Paths::advance`] moved both particles to the impact).
    pub fn v_ref(&self) -> &[f64] {
        &self.store.v_ref
    }

    /// Particle q's velocity at its path's reference: after its last impact if it had one,
    /// else at the step's start (m/s).
    pub fn reference_velocity(&self, q: usize) -> [f64; 3] {
        if self.is_open(q) {
            vec3::get(&self.store.v_ref, q)
        } else {
            vec3::get(self.v0, q)
        }
    }

    /// An impulse changed open path q (its velocity in [`Paths::v_ref_mut`]): a new version.
    pub fn changed(&mut self, q: usize) {
        debug_assert!(self.is_open(q));
        self.store.version[q] += 1;
    }

    /// See [`Paths::v_ref`].
    pub fn v_ref_mut(&mut self) -> &mut [f64] {
        &mut self.store.v_ref
    }

    /// Puts each particle that was hit at its last path's point at h, with velocity
    /// v(h) + (v1 − (v0 + a h)): what the integrator added beyond the parabola is kept.
    pub fn finish(&self, x1: &mut [f64], v1: &mut [f64], h: f64) {
        for &q in &self.store.open {
            if self.store.version[q] == 0 {
                continue;
            }
            let (x, v) = self.state_at(q, h);
            for k in 0..3 {
                let c = 3 * q + k;
                let beyond = v1[c] - (self.v0[c] + self.accel[c] * h);
                x1[c] = x[k];
                v1[c] = v[k] + beyond;
            }
        }
    }
}

/// The first impact of a pair in the rest of a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Toi {
    /// They meet after τ s, approaching faster than `slow` (τ = 0: they touch now).
    At(f64),
    /// They touch or overlap now, or meet within the step, approaching no faster than `slow`.
    Touching,
    /// No impact within the step.
    Never,
}

/// The first impact within `rest` s of two particles with separation d(τ) = d0 + u τ + ½ Δa τ²
/// (m; u and Δa their relative velocity and acceleration) and radius sum R; a meeting at an
/// approach speed −u_n ≤ `slow` (m/s) is [`Toi::Touching`].
///
/// With Δa = 0 (uniform fields) it is the exact root of |d0 + u τ| = R ([`toi_spheres`]),
/// after a rejection that needs no square root: the closest distance along the segment,
/// |d0|² − (d0·u)²/|u|² (or the end point's), above R² means no impact. Otherwise the chord
/// of the remaining step (u + ½ Δa rest) gives a first root, refined by Newton's method on
/// |d(τ)|² − R².
#[inline]
pub(crate) fn pair_toi(d0: [f64; 3], u: [f64; 3], da: [f64; 3], big_r: f64, rest: f64, slow: f64) -> Toi {
    let d2 = vec3::dot(d0, d0);
    let r2 = big_r * big_r;
    let b = vec3::dot(d0, u);
    if d2 <= r2 {
        // touching or overlapping now: an impact if approaching (u_n = b / |d0|) fast enough
        let dist = d2.sqrt();
        let approaching = dist > 0.0 && b < -slow * dist;
        return if approaching { Toi::At(0.0) } else { Toi::Touching };
    }
    // a meeting at τ > 0: an impact if u_n = (u + Δa τ)·d(τ)/|d(τ)| < −slow there
    let meet = |tau: f64| {
        let d = vec3::parabola(d0, u, da, tau);
        let w = [0, 1, 2].map(|k| u[k] + da[k] * tau);
        if vec3::dot(d, w) < -slow * vec3::norm(d) {
            Toi::At(tau)
        } else {
            Toi::Touching
        }
    };
    if da == [0.0; 3] {
        if b >= 0.0 {
            return Toi::Never;
        }
        let a = vec3::dot(u, u);
        // the closest squared distance over [0, rest]: at τ* = −b/a if inside, else at rest
        let closest = if -b < a * rest {
            d2 - b * (b / a)
        } else {
            let e = [0, 1, 2].map(|k| d0[k] + u[k] * rest);
            vec3::dot(e, e)
        };
        if closest > r2 * (1.0 + 1e-12) {
            return Toi::Never;
        }
        return match toi_spheres(d0, u, big_r, rest) {
            Some(tau) if tau > 0.0 => meet(tau),
            _ => Toi::Never,
        };
    }
    let chord = [0, 1, 2].map(|k| u[k] + 0.5 * da[k] * rest);
    let Some(mut tau) = toi_spheres(d0, chord, big_r, rest) else {
        return Toi::Never;
    };
    for _ in 0..8 {
        let d = vec3::parabola(d0, u, da, tau);
        let dd = [0, 1, 2].map(|k| u[k] + da[k] * tau);
        let g = vec3::dot(d, d) - r2;
        let dg = 2.0 * vec3::dot(d, dd);
        if dg == 0.0 {
            break;
        }
        let next = (tau - g / dg).clamp(0.0, rest);
        let done = (next - tau).abs() <= 1e-15 * rest;
        tau = next;
        if done {
            break;
        }
    }
    if tau > 0.0 {
        meet(tau)
    } else {
        Toi::Never
    }
}

/// A bound on how far particle q can be from `from` (m) at any time in [t, h] on its current
/// path: its distance at t (minimum image) plus |v(t)| (h − t) + ½ |a| (h − t)².
pub(crate) fn swept_reach(paths: &Paths<'_>, q: usize, t: f64, h: f64, from: [f64; 3], domain: &Domain) -> f64 {
    let (x, v) = paths.state_at(q, t);
    let rest = h - t;
    vec3::norm(domain.displacement(x, from)) + vec3::norm(v) * rest + 0.5 * vec3::norm(vec3::get(paths.accel, q)) * rest * rest
}

#[cfg(test)]
#[path = "tests/paths.rs"]
mod tests;
