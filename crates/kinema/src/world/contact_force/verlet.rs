//! Velocity Verlet's force evaluation and closing kick fused into one parallel pass over the
//! particles, for a world whose forces include the contact force.

use rayon::prelude::*;

use super::{ContactForce, CHUNK};
use crate::error::Error;
use crate::forces::State;

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
}

impl ContactForce {
    /// Velocity Verlet's force evaluation and closing kick fused into one parallel pass over
    /// the particles (see `VerletBuffers` in `world/mod.rs`): for each particle i,
    ///
    /// ```text
    ///   F_i  = other_i + Σ_j contact forces (pairs, then colliders: as `accumulate` sums them)
    ///   a'_i = F_i / m_i           (into `a`, which held a_i: only i reads its own a_i)
    ///   v_i  ← v_i + h/2 (a_i + a'_i)   (into `v_out`)
    /// ```
    ///
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
        } = kick;
        let mut scratch = self.scratch();
        self.update_list(s, &mut scratch)?;
        let list = &scratch.list;
        let (x, vp) = (s.x, s.v);
        let bad = a
            .par_chunks_mut(3 * CHUNK)
            .zip(v_out.par_chunks_mut(3 * CHUNK))
            .zip(list.rows.par_iter())
            .enumerate()
            .map(|(c, ((ac, vc), rows))| {
                let first = c * CHUNK;
                // this chunk's wall candidates (sorted by particle)
                let w0 = list.walls.partition_point(|w| w.0 < first);
                let w1 = list.walls.partition_point(|w| w.0 < first + rows.len());
                let mut walls = list.walls[w0..w1].iter().peekable();
                let mut bad = None;
                for (l, i) in (first..).take(rows.len()).enumerate() {
                    let mut f = match other {
                        Some(o) => [o[3 * i], o[3 * i + 1], o[3 * i + 2]],
                        None => [0.0; 3],
                    };
                    self.for_each_partner_contact(i, rows.of(l), x, vp, |contact, first| {
                        if let Some(force) = self.normal_force(contact) {
                            for k in 0..3 {
                                if first {
                                    f[k] += force * contact.normal[k];
                                } else {
                                    f[k] -= force * contact.normal[k];
                                }
                            }
                        }
                    });
                    while let Some(&(_, k)) = walls.next_if(|w| w.0 == i) {
                        self.wall_contacts(i, k, x, vp, |contact| {
                            if let Some(force) = self.normal_force(contact) {
                                for (fk, nk) in f.iter_mut().zip(contact.normal) {
                                    *fk += force * nk;
                                }
                            }
                        });
                    }
                    let w = inv_mass[i];
                    for k in 0..3 {
                        let a_new = if flat && k == 2 { 0.0 } else { f[k] * w };
                        let q = 3 * l + k;
                        vc[q] = v[3 * i + k] + 0.5 * h * (ac[q] + a_new);
                        ac[q] = a_new;
                        if bad.is_none() && !(vc[q].is_finite() && x[3 * i + k].is_finite()) {
                            bad = Some(3 * i + k);
                        }
                    }
                }
                bad
            })
            .flatten() // (Option's own order puts None first: drop the clean chunks)
            .min();
        Ok(bad)
    }
}
