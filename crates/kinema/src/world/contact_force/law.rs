//! The spring–dashpot law of [`ContactForce`]: the pair pass that sums the particles' forces
//! and energies chunk by chunk, the normal force and spring energy of a contact, and the
//! damping ratios of the pair materials.

use rayon::prelude::*;

use super::{ContactForce, Scratch, CHUNK};
use crate::collide::neighbour_list::Rows;
use crate::collide::{damping_ratio, dashpot_coefficient, spring_dashpot_force, Collider, Contact, Material, Partner};
use crate::error::Error;
use crate::forces::State;

impl ContactForce {
    /// The pair forces at `s` added to `f` (N, 3 per particle), and the pairs' energy
    /// Σ ½ k_n δ² (J). Chunk by chunk in parallel: particle i sums the forces of its listed
    /// partners in ascending order of j, each pair's contact computed with the lower index
    /// first, so i and j get F_n n and −F_n n to the bit; a pair's energy is counted by its
    /// lower index, and the chunks' sums are added in chunk order. Without `f`, the energy only.
    pub(super) fn pair_pass(&self, s: &State, scratch: &mut Scratch, f: Option<&mut [f64]>) -> f64 {
        let Scratch { list, chunk_energy, .. } = scratch;
        let (x, v) = (s.x, s.v);
        let chunk = |c: usize, rows: &Rows, mut fc: Option<&mut [f64]>| {
            let mut energy = -0.0;
            for (l, i) in (c * CHUNK..).take(rows.len()).enumerate() {
                self.for_each_partner_contact(i, rows.of(l), x, v, |contact, first| {
                    if first {
                        if let Some(u) = self.spring_energy(contact) {
                            energy += u;
                        }
                    }
                    let (Some(fc), Some(force)) = (fc.as_deref_mut(), self.normal_force(contact)) else {
                        return;
                    };
                    for k in 0..3 {
                        if first {
                            fc[3 * l + k] += force * contact.normal[k];
                        } else {
                            fc[3 * l + k] -= force * contact.normal[k];
                        }
                    }
                });
            }
            energy
        };
        match f {
            Some(f) => f
                .par_chunks_mut(3 * CHUNK)
                .zip(list.rows.par_iter())
                .enumerate()
                .map(|(c, (fc, rows))| chunk(c, rows, Some(fc)))
                .collect_into_vec(chunk_energy),
            None => list
                .rows
                .par_iter()
                .enumerate()
                .map(|(c, rows)| chunk(c, rows, None))
                .collect_into_vec(chunk_energy),
        }
        chunk_energy.iter().fold(-0.0, |sum, u| sum + u)
    }

    /// The force of contact `c` along its normal, N (> 0 pushes apart), or `None` when it
    /// exerts none (not overlapping, or both sides immovable).
    #[inline(always)]
    pub(super) fn normal_force(&self, c: &Contact) -> Option<f64> {
        let w = self.inverse_mass_sum(c);
        if c.overlap.is_nan() || c.overlap <= 0.0 || w == 0.0 {
            return None;
        }
        Some(spring_dashpot_force(self.stiffness, self.dashpot(c, w), c.overlap, c.u_n))
    }

    /// ½ k_n δ² of contact `c` if it counts in the potential energy (overlapping, with a
    /// movable particle), J.
    #[inline]
    fn spring_energy(&self, c: &Contact) -> Option<f64> {
        (c.overlap > 0.0 && self.inverse_mass_sum(c) > 0.0).then_some(0.5 * self.stiffness * c.overlap * c.overlap)
    }

    /// U = Σ ½ k_n δ² at the positions of `s` (J), summed as the force evaluation sums it.
    pub(super) fn potential_at(&self, s: &State, scratch: &mut Scratch) -> Result<f64, Error> {
        self.update_list(s, scratch)?;
        let mut energy = self.pair_pass(s, scratch, None);
        self.for_each_wall_contact(s, &scratch.list, |c| {
            if let Some(u) = self.spring_energy(c) {
                energy += u;
            }
        });
        Ok(energy)
    }

    /// w_i + w_j of a contact.
    pub(super) fn inverse_mass_sum(&self, c: &Contact) -> f64 {
        self.inv_mass[c.i] + c.partner_particle().map_or(0.0, |j| self.inv_mass[j])
    }

    /// c_n (kg/s) of a contact with w = w_i + w_j > 0.
    pub(super) fn dashpot(&self, c: &Contact, w: f64) -> f64 {
        match self.damping {
            Some(gamma) => gamma / w,
            None => dashpot_coefficient(self.stiffness, self.ratios.of(c), w),
        }
    }
}

/// The damping ratio ζ = `damping_ratio`(e) of every contact's material, worked out once per
/// particle and collider rather than per contact (a logarithm and a square root each).
///
/// A pair of particles has e = max(e_i, e_j) ([`Material::combine`]), so its ζ is the ζ of
/// the particle with the larger e (either one when they are equal: the same e gives the same
/// ζ), bit for bit what `damping_ratio(max(e_i, e_j))` gives. Against a collider, the
/// collider's own e where it sets one, else the particle's.
pub(super) struct DampingRatios {
    /// ζ of the global e.
    global: f64,
    /// (e, ζ) of each particle, when particles have their own materials.
    pub(super) particles: Option<Vec<(f64, f64)>>,
    /// ζ of each collider's own e, where it sets one.
    colliders: Vec<Option<f64>>,
}

impl DampingRatios {
    pub(super) fn new(global: Material, own: Option<&[Material]>, colliders: &[Collider]) -> Self {
        let zeta = |e: f64| damping_ratio(e).unwrap_or(0.0);
        DampingRatios {
            global: zeta(global.restitution()),
            particles: own.map(|m| m.iter().map(|m| (m.restitution(), zeta(m.restitution()))).collect()),
            colliders: colliders.iter().map(|c| c.surface().restitution().map(zeta)).collect(),
        }
    }

    /// Particle i's (e, ζ), or `None` when every particle has the global material.
    fn particle(&self, i: usize) -> Option<(f64, f64)> {
        self.particles.as_ref().map(|p| p[i])
    }

    /// ζ of contact `c`.
    fn of(&self, c: &Contact) -> f64 {
        match c.other {
            Partner::Collider(k) => self.colliders[k].unwrap_or_else(|| self.particle(c.i).map_or(self.global, |p| p.1)),
            Partner::Particle(j) => match (self.particle(c.i), self.particle(j)) {
                (Some((e_i, z_i)), Some((e_j, z_j))) => {
                    if e_j > e_i {
                        z_j
                    } else {
                        z_i
                    }
                }
                _ => self.global,
            },
        }
    }
}
