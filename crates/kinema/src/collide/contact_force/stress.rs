//! Each particle's share of the contacts' virial (LAMMPS's `compute stress/atom`, without its
//! sign): ½ Σ_j (x_i − x_j) ⊗ F_ij over the particle pairs that touch, the force F_ij on i,
//! tangential part included, with the springs as they are.

use super::history::pair_memory;
use super::pairs::Turning;
use super::{ContactForce, Scratch};
use crate::collide::Contact;
use crate::error::Error;
use crate::forces::State;
use crate::vec3;

impl ContactForce<'_> {
    /// Adds ½ (x_i − x_j) ⊗ F_ij (N·m, row-major 3 × 3) of every touching pair at `s` to both
    /// particles' entries of `out` (9 per particle): the sum over all particles is Σ_pairs
    /// (x_i − x_j) ⊗ F_ij, the virial the pressure tensor counts (colliders left out, as
    /// there).
    pub(crate) fn particle_virial(&self, s: &State, out: &mut [f64]) -> Result<(), Error> {
        let mut scratch = self.scratch();
        let mut pairs = Vec::new();
        self.for_each_contact(s, &mut scratch, |c| {
            if c.partner_particle().is_some() {
                pairs.push(*c);
            }
        })?;
        let Scratch { histories, .. } = &*scratch;
        let turn = self.reading(histories);
        for c in &pairs {
            self.add_pair_virial(c, s, turn.as_ref(), out);
        }
        Ok(())
    }

    fn add_pair_virial(&self, c: &Contact, s: &State, turn: Option<&Turning<'_>>, out: &mut [f64]) {
        let Some(j) = c.partner_particle() else { return };
        let Some((force, dashpot)) = self.normal_force_parts(c) else {
            return;
        };
        let mut f = vec3::scale(force, c.normal);
        if let Some((t, model)) = turn.and_then(|t| t.model.map(|m| (t, m))) {
            let slip = pair_memory(t.pairs, c.i as u32, j as u32).unwrap_or_default();
            f = vec3::add(f, self.tangent_of(model, t, c, force, dashpot, s.v, slip).force);
        }
        // x_i − x_j = d n, d = r_i + r_j − δ (the minimum image along periodic axes)
        let d = self.radius[c.i] + self.radius[j] - c.overlap;
        for p in [c.i, j] {
            for r in 0..3 {
                for k in 0..3 {
                    out[9 * p + 3 * r + k] += 0.5 * d * c.normal[r] * f[k];
                }
            }
        }
    }
}
