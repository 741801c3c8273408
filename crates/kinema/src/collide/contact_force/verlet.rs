//! Velocity Verlet's force evaluation and closing kick fused into one parallel pass over the
//! particles, for a world whose forces include the contact force.

use rayon::prelude::*;

use super::pairs::{summed_books, ChunkSums, ContactBooks, PassOptions};
use super::{ContactForce, Scratch, CHUNK};
use crate::error::Error;
use crate::forces::State;
use crate::ode::verlet;

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
    /// In: a_i, the accelerations at the step's start; out: a'_i, m/s².
    pub a: &'a mut [f64],
    /// Out: the new velocities, m/s.
    pub v_out: &'a mut [f64],
    /// Also sum the pair energy at the drifted positions, for the runaway check that asks
    /// for it right after ([`ContactForce::forget_energy`] drops it).
    pub energy: bool,
}

/// The step's contact books, summed from the chunks' (in chunk order), for the world to take.
fn scratch_books(books: &mut Option<ContactBooks>, sums: &[ChunkSums]) {
    *books = Some(summed_books(sums));
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
    /// at the drifted state `s` (x', and the predictor v' that the dashpot sees), with
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
            energy,
        } = kick;
        let mut scratch = self.scratch();
        self.update_list(s, &mut scratch)?;
        let Scratch {
            list,
            sums,
            exchange,
            pair_energy,
            books,
            ..
        } = &mut *scratch;
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
        self.pair_forces(x, vp, list, Some(&mut *v_out), start, options, exchange, sums);
        scratch_books(books, sums);
        *pair_energy = energy.then(|| {
            (
                (x.as_ptr() as usize, x.len()),
                sums.iter().fold(-0.0, |sum, c| sum + c.energy),
            )
        });
        let bad_x = sums.iter().find_map(|c| c.bad);
        let exchange = &*exchange;
        let bad = a
            .par_chunks_mut(3 * CHUNK)
            .zip(v_out.par_chunks_mut(3 * CHUNK))
            .enumerate()
            .map(|(c, (ac, vc))| {
                exchange.receive(c, vc);
                let first = c * CHUNK;
                let mut bad = None;
                for (l, i) in (first..).take(ac.len() / 3).enumerate() {
                    let w = inv_mass[i];
                    for k in 0..3 {
                        let q = 3 * l + k;
                        let a_new = if flat && k == 2 { 0.0 } else { vc[q] * w };
                        vc[q] = verlet::kick(v[3 * i + k], ac[q], a_new, h);
                        ac[q] = a_new;
                        if bad.is_none() && !vc[q].is_finite() {
                            bad = Some(3 * i + k);
                        }
                    }
                }
                bad
            })
            .flatten() // (Option's own order puts None first: drop the clean chunks)
            .min();
        // the first non-finite coordinate of x' or of the new velocities
        let bad = bad.into_iter().chain(bad_x).min();
        Ok(bad)
    }
}
