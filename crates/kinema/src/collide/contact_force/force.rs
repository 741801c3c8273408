//! [`ContactForce`] as a [`Force`]: the forces and energy at a state, its properties and
//! the rates the step advisor reads (with the standby
//! oscillation of contacts not touching yet).

use super::ContactForce;
use crate::collide::damping_ratio;
use crate::error::{CallbackError, Error};
use crate::forces::{EnergyClass, Force, Properties, Rates, Standby, State};
use crate::limits::GEOMETRY_LIMIT;

impl Force for ContactForce<'_> {
    fn name(&self) -> &str {
        "contact"
    }

    /// The contact forces at `s`: particle pairs and colliders, on all threads.
    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        let mut scratch = std::mem::take(&mut *self.scratch());
        let result = self.update_list(s, &mut scratch);
        if result.is_ok() {
            self.pair_pass(s, &mut scratch, Some(f), true);
        }
        *self.scratch() = scratch;
        match result {
            Err(Error::InvalidParameter { .. }) if s.x.iter().chain(s.v).any(|c| !(c.abs() <= GEOMETRY_LIMIT)) => {
                // A state that is non-finite, or too large for the contacts' geometry (a
                // stage of rk45, an overflowing step): no contact force exists there. NaN
                // forces let the world stop the step as it stops any non-finite one
                // (SimulationDiverged), instead of an error about the list's internals.
                f.fill(f64::NAN);
                Ok(())
            }
            other => Ok(other?),
        }
    }

    // No `validate`: the world rebuilds this force whenever its particles change.

    /// U = Σ ½ k_n δ² over the overlapping contacts, J.
    fn potential_energy(&self, s: &State) -> Option<f64> {
        self.potential_at(s, &mut self.scratch()).ok()
    }

    /// Dissipative (the spring is conservative and the dashpot dissipative), a function of
    /// positions and velocities, internal when no collider pushes; it follows a renumbering
    /// (the world renumbers its list, [`ContactForceModel::renumber`](super::ContactForceModel::renumber):
    /// all else it reads where it lives).
    fn properties(&self) -> Properties {
        Properties {
            energy: EnergyClass::Dissipative,
            depends_on_position: true,
            depends_on_velocity: true,
            internal: self.colliders.is_empty(),
            renumbers: true,
            per_particle: false,
        }
    }

    /// Gershgorin over the contacts at `s`: a contact adds k_n w_p to particle p's row twice
    /// with a particle partner (diagonal and off-diagonal), once against a collider; the
    /// dashpot likewise with c_n. The standby oscillation is [`ContactForce::standby`].
    fn rates(&self, s: &State, inv_mass: &[f64]) -> Option<Rates> {
        let mut k_row = vec![0.0; inv_mass.len()];
        let mut c_row = vec![0.0; inv_mass.len()];
        self.for_each_contact(s, &mut self.scratch(), |c| {
            let w = self.inverse_mass_sum(c);
            if c.overlap.is_nan() || c.overlap <= 0.0 || w == 0.0 {
                return;
            }
            let times = if c.partner_particle().is_some() { 2.0 } else { 1.0 };
            let k = self.stiffness_of(c);
            let dashpot = self.dashpot_at(c, w, k);
            // dF/dδ: k_n (Hooke); 3/2 of the secant with Hertz's δ^(3/2)
            let tangent = self.normal.tangent_of_secant(k);
            for p in std::iter::once(c.i).chain(c.partner_particle()) {
                k_row[p] += times * tangent;
                c_row[p] += times * dashpot;
            }
        })
        .ok()?;
        let mut rates = Rates {
            standby: self.standby(inv_mass, s.v),
            ..Rates::default()
        };
        for (p, w) in inv_mass.iter().enumerate() {
            rates.omega_squared = rates.omega_squared.max(w * k_row[p]);
            rates.damping_rate = rates.damping_rate.max(w * c_row[p]);
        }
        Some(rates)
    }
}

impl ContactForce<'_> {
    /// A contact that is not touching yet counts as a spring: ω² = k_n (w_i + w_j) for the
    /// two lightest movable particles (or k_n w against a collider), with the ζ of the
    /// largest restitution's opposite, the least damped contact.
    ///
    /// With Hertz's law the stiffness is the one the contact reaches: the tangent stiffness
    /// 3/2 k_n at the deepest overlap of an elastic impact at the fastest approach the
    /// velocities `v` allow (2 |v|max between particles), δ_max = (5 m_eff u² / (4 k_h))^(2/5)
    /// with k_h = 4/3 E* √R* (energy: ½ m_eff u² = 2/5 k_h δ^(5/2)), R* the largest radius
    /// (the stiffest); none while nothing moves.
    fn standby(&self, inv_mass: &[f64], v: &[f64]) -> Option<Standby> {
        let mut lightest = [0.0_f64; 2];
        for w in inv_mass {
            if *w > lightest[0] {
                lightest = [*w, lightest[0]];
            } else if *w > lightest[1] {
                lightest[1] = *w;
            }
        }
        let w = (lightest[0] + lightest[1]).max(if self.colliders.is_empty() { 0.0 } else { lightest[0] });
        if w == 0.0 || (inv_mass.len() < 2 && self.colliders.is_empty()) {
            return None;
        }
        let fastest = || {
            v.chunks_exact(3)
                .map(|c| c[0] * c[0] + c[1] * c[1] + c[2] * c[2])
                .fold(0.0, f64::max)
                .sqrt()
        };
        let r = || self.radius.iter().copied().fold(0.0, f64::max);
        let stiffness = self.normal.impact_stiffness(|| 2.0 * fastest(), r, w)?;
        let omega_squared = stiffness * w;
        let zeta = self.damping.ratio_at(omega_squared, || {
            let e_max = self
                .own
                .into_iter()
                .flatten()
                .map(|m| m.restitution())
                .chain(self.colliders.iter().filter_map(|c| c.surface().restitution()))
                .fold(self.global.restitution(), f64::max);
            damping_ratio(e_max).unwrap_or(0.0)
        });
        Some(Standby { omega_squared, zeta })
    }
}
