//! Velocity Verlet's force evaluation and closing kick fused into one parallel pass over the
//! particles, for a world whose forces include the contact force.

use rayon::prelude::*;

use super::affinity;
use super::exchange::Exchange;
use super::pairs::{summed_books, ChunkSums, ContactBooks, PassOptions};
use super::{ContactForce, Scratch, CHUNK};
use crate::collide::books::ColliderBooks;
use crate::collide::velocities::Predictor;
use crate::error::Error;
use crate::forces::State;
use crate::ode::verlet;
use crate::vec3::{first_non_finite, non_finite_bits};

/// The rest of what [`ContactForce::force_and_kick`] needs besides the drifted state: the
/// step's other forces, masses and size, the velocities at its start, and the buffers it
/// writes.
pub(crate) struct VerletKick<'a> {
    /// The other forces' sum at the drifted state, N (3 per particle; `None`: none).
    pub other: Option<&'a [f64]>,
    /// Inverse masses, 1/kg (0: pinned).
    pub inv_mass: &'a [f64],
    /// 2D: a_z = 0.
    pub flat: bool,
    /// The step, s.
    pub h: f64,
    /// The velocities at the step's start, m/s.
    pub v: &'a [f64],
    /// Whether the contacts see Verlet's predictor v + h a made from `v` and `a` when they
    /// need it (`collide/velocities.rs`: no array of it), or the one in the drifted state's
    /// velocities (stored, where another force reads it too).
    pub predict: bool,
    /// In: a_i, the accelerations at the step's start; out: a'_i, m/s².
    pub a: &'a mut [f64],
    /// Out: the new velocities, m/s (sized here: its values are not read, and where the
    /// neighbour list is rebuilt its room is let go for the build's and made again after).
    pub v_out: &'a mut Vec<f64>,
    /// Also sum the pair energy at the drifted positions, for the runaway check that asks
    /// for it right after ([`ContactForce::forget_energy`] drops it).
    pub energy: bool,
    /// The turning of the particles under the contacts' torques (spin with a tangential
    /// part, `tangent.rs`; `None`: nothing turns in stage 1).
    pub spin: Option<SpinKick<'a>>,
}

/// The fewest values (3 a particle) of a `VerletKick::v_out` whose room is let go while the
/// neighbour list is rebuilt (`ContactForce::force_and_kick`): 16 MiB, ~700,000 particles;
/// 1 in the crate's own tests, so that every test of the kick lends it (Python's, on the
/// release build, run the smaller worlds that keep it).
const LEND_FROM: usize = if cfg!(test) { 1 } else { 1 << 21 };

/// The particles whose inverse masses the 3D kick repeats for its coordinates at a time.
const KICK_BLOCK: usize = 64;

/// Velocity Verlet for the angular velocities, beside the velocities' (LAMMPS's `fix
/// nve/sphere`, in the same drift–predict–kick form as `VerletBuffers` in `world/integrate.rs`):
///
/// ```text
///   ω' = ω + h α                       (the predictor the contacts see)
///   α' = τ(t + h, x', v', ω') / I      (the torques of the force evaluation)
///   ω  ← ω + h/2 (α + α')
/// ```
pub(crate) struct SpinKick<'a> {
    /// ω at the step's start, rad/s (3 per particle).
    pub omega: &'a [f64],
    /// α at the step's start, rad/s².
    pub alpha: &'a [f64],
    /// 1/I, 1/(kg·m²) (0: cannot turn).
    pub inv_inertia: &'a [f64],
    /// Out: α', rad/s².
    pub alpha_out: &'a mut [f64],
    /// Out: ω at the step's end, rad/s (the predictor meanwhile).
    pub omega_out: &'a mut [f64],
}

/// The step's contact books, summed from the chunks' (in chunk order), for the world to take,
/// with what each of the `colliders` took over the step h (s). Verlet's kick
/// v ← v + h/2 (a + a') gives a particle h/2 (F + F') from a collider, F the force of the last
/// pass (at the step's start, `walls`) and F' this one's, so that is what the collider books
/// (exactly what the particles took, to rounding); after a change that dropped the last
/// pass's forces (a new list), h F'.
fn scratch_books(
    books: &mut Option<(ContactBooks, Vec<ColliderBooks>)>,
    walls: &mut Option<Vec<ColliderBooks>>,
    sums: &[ChunkSums],
    colliders: usize,
    h: f64,
) {
    // the forces of this pass as rates: N, N·m and W where the books hold N·s, N·m·s and J
    let mut now = vec![ColliderBooks::default(); colliders];
    for p in sums.iter().flat_map(|s| &s.pushes) {
        if let Some(b) = now.get_mut(p.collider) {
            b.book(p.at, p.u, p.force, p.normal);
        }
    }
    let mut step = vec![ColliderBooks::default(); colliders];
    for (k, s) in step.iter_mut().enumerate() {
        match walls.as_ref().and_then(|w| w.get(k)) {
            Some(before) => {
                s.add_scaled(0.5 * h, before);
                s.add_scaled(0.5 * h, &now[k]);
            }
            None => s.add_scaled(h, &now[k]),
        }
    }
    *walls = Some(now);
    *books = Some((summed_books(sums), step));
}

impl ContactForce<'_> {
    /// Velocity Verlet's force evaluation and closing kick fused into one parallel pass over
    /// the particles (see `VerletBuffers` in `world/mod.rs`): for each particle i,
    ///
    /// ```text
    ///   F_i  = other_i + Σ_j contact forces (pairs and colliders, summed in `v_out` in the
    ///          order of `pairs.rs`, as `accumulate` sums them)
    ///   a'_i = F_i / m_i           (into `a`, which held a_i: only i reads its own a_i)
    ///   v_i  ← v_i + h/2 (a_i + a'_i)   (into `v_out`, over F_i: only i reads its own F_i)
    /// ```
    ///
    /// The pair stage writes each chunk's F into its part of `v_out`; the second stage, chunk
    /// by chunk, receives what earlier chunks sent and kicks.
    /// at the drifted state `s` (x', and the predictor v' that the dashpot sees: `s.v`, or made
    /// from [`VerletKick`]'s `v` and `a` with `predict`), with
    /// [`VerletKick`]'s `v` the velocities at the step's start, `other` the other forces' sum
    /// (N; `None`: none), `inv_mass` (0 pinned) and `flat` (2D: a_z = 0). Saves the separate passes that clear the
    /// force buffer, turn it into accelerations and kick. Returns the first non-finite
    /// coordinate of x' or of the new velocities, if any.
    pub fn force_and_kick(&self, s: &State, kick: VerletKick<'_>) -> Result<Option<usize>, Error> {
        let VerletKick {
            other,
            inv_mass,
            flat,
            h,
            v,
            a,
            v_out,
            predict,
            energy,
            spin,
        } = kick;
        let mut scratch = self.scratch();
        // Where the list is rebuilt in a large world, `v_out`'s room (24 B a particle) goes
        // back before the build and the build's grid (~14 B a particle, let go after it) takes
        // its place: a gas of 10⁶ spheres peaked at its builds by the grid's size over its
        // steps. The room's pages are then touched afresh (~6,000 page faults at 10⁶, a few
        // % of the steps between builds), which a smaller world is spared.
        let lend = v_out.len() >= LEND_FROM;
        self.update_list_lending(s, &mut scratch, || {
            if lend {
                *v_out = Vec::new();
            }
        })?;
        if v_out.is_empty() {
            // (fresh zero pages, first touched by the pass's own threads, each its chunks)
            *v_out = vec![0.0; s.x.len()];
        } else {
            v_out.resize(s.x.len(), 0.0);
        }
        let v_out = &mut v_out[..];
        let Scratch {
            list,
            sums,
            exchange,
            pair_energy,
            books,
            wall_forces,
            histories,
            torque_exchange,
            torque,
            ..
        } = &mut *scratch;
        // the predictor ω' = ω + h α, which the contacts see
        let mut spin = spin;
        if let Some(k) = spin.as_mut() {
            angular_predictor(k, h);
            torque.resize(s.x.len(), 0.0);
        }
        let predictor: &[f64] = match spin.as_ref() {
            Some(k) => k.omega_out,
            None => self.omega,
        };
        let (x, vp) = (s.x, s.v);
        // F_i summed in v_out (each chunk's part is written by that chunk alone), started
        // at the other forces' sum
        let start = |c: usize, fc: &mut [f64]| match other {
            Some(o) => fc.copy_from_slice(&o[3 * c * CHUNK..3 * c * CHUNK + fc.len()]),
            None => fc.fill(0.0),
        };
        let options = PassOptions {
            energy,
            walls: true,
            check_positions: true,
            books: Some(h),
        };
        let turned = spin.is_some();
        let omega_start: &[f64] = match spin.as_ref() {
            Some(k) => k.omega,
            None => self.omega,
        };
        let turn = super::turning(
            self.tangential,
            self.jkr().is_some(),
            predictor,
            histories,
            torque_exchange,
            Some((h, v, omega_start)),
            turned.then_some(&mut torque[..]),
        );
        let (turning, out) = match turn {
            Some((t, o)) => (Some(t), Some(o)),
            None => (None, None),
        };
        let turn = turning.as_ref().zip(out);
        if predict {
            let vp = Predictor { v, a: &*a, h };
            self.pair_forces(x, &vp, list, Some(&mut *v_out), start, options, exchange, sums, turn);
        } else {
            self.pair_forces(x, vp, list, Some(&mut *v_out), start, options, exchange, sums, turn);
        }
        scratch_books(books, wall_forces, sums, self.colliders.len(), h);
        *pair_energy = energy.then(|| {
            (
                (x.as_ptr() as usize, x.len()),
                sums.iter().fold(-0.0, |sum, c| sum + c.energy),
            )
        });
        let bad_x = sums.iter().find_map(|c| c.bad);
        let bad = kick_velocities(a, v_out, exchange, (inv_mass, flat), v, h, sums);
        // the angular kick, beside: α' = τ/I, ω ← ω + h/2 (α + α')
        let bad_w = spin.and_then(|k| angular_kick(k, torque, torque_exchange, flat, h));
        // the first non-finite coordinate of x', of the new velocities or angular velocities
        let bad = bad.into_iter().chain(bad_x).chain(bad_w).min();
        Ok(bad)
    }
}

/// The predictor ω' = ω + h α of `k`'s angular velocities (into `omega_out`), which the
/// contacts see.
#[inline]
fn angular_predictor(k: &mut SpinKick<'_>, h: f64) {
    let (omega, alpha) = (k.omega, k.alpha);
    k.omega_out.par_chunks_mut(3 * CHUNK).enumerate().for_each(|(c, wc)| {
        let base = 3 * CHUNK * c;
        for (q, w) in wc.iter_mut().enumerate() {
            *w = omega[base + q] + h * alpha[base + q];
        }
    });
}

/// The kick, chunk by chunk after each receives what earlier chunks sent (`exchange`):
/// a'_i = F_i / m_i into `a` (which held a_i), v_i + h/2 (a_i + a'_i) into `v_out` (which held
/// F_i), with the particles' inverse masses and `flat` (2D: a_z = 0); `v`: the velocities at
/// the step's start. The first non-finite new velocity's index, if any.
///
/// Each chunk is kicked on the thread that summed its forces in stage 1 (`sums`' `thread`):
/// its force sums are still in that core's cache, and on another core each of their lines
/// crosses between the cores' caches first. Left to rayon's own split, half the chunks went
/// to the other thread: the kick took a quarter of the 2-thread gas's time (N = 103,823)
/// and 9 % of the 1-thread one's; on the stage-1 threads, 13 %, and the step 18 % less (this
/// machine on a day its two cores shared little; where they share a cache, no change). The
/// chunks' arithmetic is their own, so the bits are the same on any thread.
#[inline]
fn kick_velocities(
    a: &mut [f64],
    v_out: &mut [f64],
    exchange: &Exchange,
    (inv_mass, flat): (&[f64], bool),
    v: &[f64],
    h: f64,
    sums: &[ChunkSums],
) -> Option<usize> {
    let kick = |c: usize, ac: &mut [f64], vc: &mut [f64]| {
        exchange.receive(c, vc);
        let first = c * CHUNK;
        let n = ac.len() / 3;
        let (v0, w) = (&v[3 * first..3 * (first + n)], &inv_mass[first..first + n]);
        // (a non-finite new velocity found by `non_finite_bits` or-ed in the loop: no branch
        // a coordinate, and the one found afterwards where there is one)
        let mut nan = 0;
        if flat {
            for (((a, vn), v0), &w) in ac
                .chunks_exact_mut(3)
                .zip(vc.chunks_exact_mut(3))
                .zip(v0.chunks_exact(3))
                .zip(w)
            {
                for k in 0..3 {
                    let a_new = if k == 2 { 0.0 } else { vn[k] * w };
                    vn[k] = verlet::kick(v0[k], a[k], a_new, h);
                    a[k] = a_new;
                    nan |= non_finite_bits(vn[k]);
                }
            }
        } else {
            // In 3D one loop over the coordinates, each with its particle's 1/m from a
            // block of them repeated three times: the compiler makes vector operations of it
            // (over the particles, with three coordinates each, it did not).
            let mut w3 = [0.0; 3 * KICK_BLOCK];
            for (((a, vn), v0), w) in ac
                .chunks_mut(3 * KICK_BLOCK)
                .zip(vc.chunks_mut(3 * KICK_BLOCK))
                .zip(v0.chunks(3 * KICK_BLOCK))
                .zip(w.chunks(KICK_BLOCK))
            {
                for (w3, &w) in w3.chunks_exact_mut(3).zip(w) {
                    w3.fill(w);
                }
                for (((a, vn), v0), w) in a.iter_mut().zip(vn.iter_mut()).zip(v0).zip(&w3) {
                    let a_new = *vn * w;
                    *vn = verlet::kick(*v0, *a, a_new, h);
                    *a = a_new;
                    nan |= non_finite_bits(*vn);
                }
            }
        }
        (nan != 0).then(|| first_non_finite(vc).map(|(q, _)| 3 * first + q)).flatten()
    };
    // (the stage-1 threads as homes, with the same stealing as stage 1: `affinity.rs`)
    let chunks: Vec<(&mut [f64], &mut [f64])> = a.chunks_mut(3 * CHUNK).zip(v_out.chunks_mut(3 * CHUNK)).collect();
    let homes = affinity::homes(chunks.len(), rayon::current_num_threads(), |c| {
        sums.get(c).and_then(|s| s.thread)
    });
    let firsts = affinity::run(chunks, &homes, |c, (ac, vc)| kick(c, ac, vc));
    firsts.into_iter().filter_map(|(bad, _)| bad).min()
}

/// The angular kick beside the kick: α' = τ/I, ω ← ω + h/2 (α + α'), chunk by chunk after
/// each receives what earlier chunks sent of the torques (`exchange`). The first non-finite
/// new angular velocity's index, if any.
#[inline]
fn angular_kick(k: SpinKick<'_>, torque: &mut [f64], exchange: &Exchange, flat: bool, h: f64) -> Option<usize> {
    let SpinKick {
        omega,
        alpha,
        inv_inertia,
        alpha_out,
        omega_out,
    } = k;
    omega_out
        .par_chunks_mut(3 * CHUNK)
        .zip(alpha_out.par_chunks_mut(3 * CHUNK))
        .zip(torque.par_chunks_mut(3 * CHUNK))
        .enumerate()
        .map(|(c, ((wc, alc), tc))| {
            exchange.receive(c, tc);
            let first = c * CHUNK;
            let mut bad = None;
            for (l, i) in (first..).take(wc.len() / 3).enumerate() {
                let k_i = inv_inertia[i];
                for k in 0..3 {
                    let q = 3 * l + k;
                    // (a disc turns about z alone)
                    let alpha_new = if flat && k < 2 { 0.0 } else { tc[q] * k_i };
                    wc[q] = verlet::kick(omega[3 * i + k], alpha[3 * i + k], alpha_new, h);
                    alc[q] = alpha_new;
                    if bad.is_none() && !wc[q].is_finite() {
                        bad = Some(3 * i + k);
                    }
                }
            }
            bad
        })
        .flatten()
        .min()
}
