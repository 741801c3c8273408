//! The contact force law of [`ContactForce`]: the particles' summed forces and energies
//! (the pair pass of `pairs.rs`), the normal force and spring energy of a contact, and the
//! damping ratios of the pair materials.

use rayon::prelude::*;

use super::pairs::PassOptions;
use super::{ContactForce, Scratch, CHUNK};
use crate::collide::{damping_ratio, Collider, Contact, Material, Partner};
use crate::error::Error;
use crate::forces::State;

impl ContactForce<'_> {
    /// The pair forces at `s` added to `f` (N, 3 per particle), with the colliders' when
    /// `walls`, and the pairs' energy Σ ½ k_n δ² (J), each pair counted once and the chunks'
    /// sums added in chunk order (see `pairs.rs` for the order of the forces' sums). Without
    /// `f`, the energy only.
    pub(super) fn pair_pass(&self, s: &State, scratch: &mut Scratch, f: Option<&mut [f64]>, walls: bool) -> f64 {
        let Scratch {
            list,
            sums,
            exchange,
            histories,
            torque_exchange,
            ..
        } = scratch;
        let options = PassOptions {
            energy: true,
            walls,
            check_positions: false,
            books: None,
        };
        // the springs read as they are (`tangent.rs`); JKR's held contacts from the memory
        let turn = super::turning(
            self.tangential,
            self.jkr().is_some(),
            self.omega,
            histories,
            torque_exchange,
            None,
            None,
        );
        let turn = turn.as_ref().map(|(t, _)| (t, super::pairs::TurningOut::default()));
        match f {
            Some(f) => {
                self.pair_forces(s.x, s.v, list, Some(&mut *f), |_, _| {}, options, exchange, sums, turn);
                let exchange = &*exchange;
                f.par_chunks_mut(3 * CHUNK)
                    .enumerate()
                    .for_each(|(d, fc)| exchange.receive(d, fc));
            }
            None => self.pair_forces(s.x, s.v, list, None, |_, _| {}, options, exchange, sums, turn),
        }
        sums.iter().fold(-0.0, |sum, c| sum + c.energy)
    }

    /// The contact torques at `s` (N·m, 3 per particle) into `torque`, with the springs as
    /// they are (`tangent.rs`; zeros without a tangential part): Verlet's first angular
    /// acceleration.
    pub(crate) fn torques_at(&self, s: &State, torque: &mut [f64]) -> Result<(), Error> {
        torque.fill(0.0);
        if self.tangential.is_none() {
            return Ok(());
        }
        let mut scratch = self.scratch();
        self.update_list(s, &mut scratch)?;
        let options = PassOptions {
            energy: false,
            walls: true,
            check_positions: false,
            books: None,
        };
        let mut forces = vec![0.0; s.x.len()];
        {
            let Scratch {
                list,
                sums,
                exchange,
                histories,
                torque_exchange,
                ..
            } = &mut *scratch;
            if let Some((t, o)) = super::turning(
                self.tangential,
                false,
                self.omega,
                histories,
                torque_exchange,
                None,
                Some(&mut *torque),
            ) {
                self.pair_forces(
                    s.x,
                    s.v,
                    list,
                    Some(&mut forces),
                    |_, _| {},
                    options,
                    exchange,
                    sums,
                    Some((&t, o)),
                );
            }
        }
        let exchange = &scratch.torque_exchange;
        torque
            .par_chunks_mut(3 * CHUNK)
            .enumerate()
            .for_each(|(d, tc)| exchange.receive(d, tc));
        Ok(())
    }

    /// The force of contact `c` along its normal, N (> 0 pushes apart), or `None` when it
    /// exerts none (not overlapping, or both sides immovable), with its dashpot c_n, kg/s:
    /// the normal law's ([`NormalLaw::force_parts`](super::NormalLaw::force_parts)).
    #[inline(always)]
    pub(super) fn normal_force_parts(&self, c: &Contact) -> Option<(f64, f64)> {
        let w = self.inverse_mass_sum(c);
        if c.overlap.is_nan() || w == 0.0 {
            return None;
        }
        self.normal
            .force_parts(c.overlap, c.u_n, || self.reduced_radius(c), |k| self.dashpot_at(c, w, k))
    }

    /// The pull-off force of contact `c`, N: DMT's 4π γ R*, JKR's 3π γ R* (0 without
    /// adhesion).
    #[inline(always)]
    pub(super) fn pull_off_of(&self, c: &Contact) -> f64 {
        self.normal.pull_off(|| self.reduced_radius(c))
    }

    /// The radius of the contact disc of `c`, m: √(R* δ) (Hertz), JKR's a with its adhesion.
    #[inline]
    pub(super) fn contact_radius_of(&self, c: &Contact) -> f64 {
        self.normal.contact_radius(c.overlap, || self.reduced_radius(c))
    }

    /// The secant stiffness F_el/δ of contact `c` at its overlap δ > 0, N/m
    /// ([`NormalLaw::secant_stiffness`](super::NormalLaw::secant_stiffness)).
    #[inline(always)]
    pub(super) fn stiffness_of(&self, c: &Contact) -> f64 {
        self.normal.secant_stiffness(c.overlap, || self.reduced_radius(c))
    }

    /// R* = r_i r_j / (r_i + r_j) of a pair (r_i against a collider), m.
    #[inline]
    pub(super) fn reduced_radius(&self, c: &Contact) -> f64 {
        let ri = self.radius[c.i];
        match c.partner_particle() {
            Some(j) => ri * self.radius[j] / (ri + self.radius[j]),
            None => ri,
        }
    }

    /// The elastic energy of contact `c` if it counts in the potential energy (overlapping,
    /// or JKR's held contact, with a movable particle), J
    /// ([`NormalLaw::energy`](super::NormalLaw::energy)).
    #[inline]
    pub(super) fn spring_energy(&self, c: &Contact) -> Option<f64> {
        if self.inverse_mass_sum(c) == 0.0 {
            return None;
        }
        self.normal.energy(c.overlap, || self.reduced_radius(c))
    }

    /// U = Σ ½ k_n δ² at the positions of `s` (J), summed as the force evaluation sums it.
    pub(super) fn potential_at(&self, s: &State, scratch: &mut Scratch) -> Result<f64, Error> {
        let here = (s.x.as_ptr() as usize, s.x.len());
        let mut energy = match scratch.pair_energy.take() {
            // summed by the fused pass at these positions, which the list held (`verlet.rs`)
            Some((at, u)) if at == here => u,
            _ => {
                self.update_list(s, scratch)?;
                self.pair_pass(s, scratch, None, false)
            }
        };
        self.for_each_wall_contact(s, &scratch.list, &scratch.histories.walls, |c| {
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

    /// c_n (kg/s) of a contact with w = w_i + w_j > 0 and secant stiffness `k` (N/m): the
    /// damping law's ([`DampingLaw::coefficient`](super::DampingLaw::coefficient), with the
    /// damping ratio of the pair's restitution).
    #[inline(always)]
    pub(super) fn dashpot_at(&self, c: &Contact, w: f64, k: f64) -> f64 {
        self.damping.coefficient(&self.normal, w, k, || self.ratios.of(c))
    }
}

/// The damping ratio ζ = `damping_ratio`(e) of every contact's material, worked out once per
/// particle and collider rather than per contact (a logarithm and a square root each).
///
/// A pair of particles has e = max(e_i, e_j) ([`Material::combine`]), so its ζ is the ζ of
/// the particle with the larger e (either one when they are equal: the same e gives the same
/// ζ), bit for bit what `damping_ratio(max(e_i, e_j))` gives. Against a collider, the
/// collider's own e where it sets one, else the particle's.
pub(super) struct DampingRatios<'a> {
    /// ζ of the global e.
    global: f64,
    /// (e, ζ) of each particle, when particles have their own materials (the collide
    /// stage works them out with the materials, [`particle_ratios`]).
    particles: Option<&'a [(f64, f64)]>,
    /// ζ of each collider's own e, where it sets one.
    colliders: Vec<Option<f64>>,
}

/// ζ of restitution e (0 where e gives none).
fn zeta(e: f64) -> f64 {
    damping_ratio(e).unwrap_or(0.0)
}

/// Each particle's (e, ζ) from its material, for [`Bodies::own`](super::Bodies).
pub(crate) fn particle_ratios(own: &[Material]) -> Vec<(f64, f64)> {
    own.iter().map(|m| (m.restitution(), zeta(m.restitution()))).collect()
}

impl<'a> DampingRatios<'a> {
    pub(super) fn new(global: Material, particles: Option<&'a [(f64, f64)]>, colliders: &[Collider]) -> Self {
        DampingRatios {
            global: zeta(global.restitution()),
            particles,
            colliders: colliders.iter().map(|c| c.surface().restitution().map(zeta)).collect(),
        }
    }

    /// Particle i's (e, ζ), or `None` when every particle has the global material.
    fn particle(&self, i: usize) -> Option<(f64, f64)> {
        self.particles.map(|p| p[i])
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
