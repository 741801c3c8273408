//! The spring–dashpot contact model as a force of stage 1: contacts found at every force
//! evaluation push overlapping bodies apart with F_n = k_n δ − m_eff γ_n u_n.

use std::cell::RefCell;

use super::collisions::on_periodic_wall;
use crate::collide::{
    collider_contacts, damping_ratio, sphere_contacts, Collider, Contact, Domain, Grid, Material, MaterialTable, Pair,
};
use crate::error::{CallbackError, Error};
use crate::forces::{Force, SpringRates, State};

/// Penalty contacts between particles and with colliders (the DEM way).
///
/// While particle i overlaps its partner by δ > 0, the pair feels F_n n on i and −F_n n on a
/// partner particle (a collider takes the reaction), N, with
///
/// ```text
///   F_n = k_n δ − c_n u_n,      c_n = 2 ζ √(k_n m_eff)   (ζ from e, closed form)
///                               c_n = m_eff γ_n           (γ_n given)
/// ```
///
/// m_eff = 1/(w_i + w_j) the reduced mass and u_n the normal relative velocity. The damping
/// ratio ζ = −ln e / √(π² + ln² e) makes the contact's damped half-oscillation bounce back with
/// exactly the requested e ([`crate::collide::penalty`]); e is the pair's material (global,
/// per particle, per collider, combined as in the impulse model). The spring part is
/// conservative, with U = Σ ½ k_n δ² over overlapping contacts; the dashpot only removes
/// energy. No friction: tangential forces belong to the impulse model.
pub(crate) struct ContactForce {
    stiffness: f64,
    damping: Option<f64>,
    global: Material,
    own: Option<Vec<Material>>,
    radius: Vec<f64>,
    inv_mass: Vec<f64>,
    colliders: Vec<Collider>,
    domain: Domain,
    scratch: RefCell<Scratch>,
}

#[derive(Default)]
struct Scratch {
    grid: Grid,
    pairs: Vec<Pair>,
    contacts: Vec<Contact>,
    walls: Vec<Contact>,
}

impl ContactForce {
    /// The force for particles of radii `radius` (m) and inverse masses `inv_mass` (1/kg),
    /// with stiffness k_n (N/m) and optional damping rate γ_n (1/s), the pair materials from
    /// `global` and `own`, the colliders and the domain (2D/3D, periodic axes).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        stiffness: f64,
        damping: Option<f64>,
        global: Material,
        own: Option<Vec<Material>>,
        radius: Vec<f64>,
        inv_mass: Vec<f64>,
        colliders: Vec<Collider>,
        domain: Domain,
    ) -> Self {
        ContactForce {
            stiffness,
            damping,
            global,
            own,
            radius,
            inv_mass,
            colliders,
            domain,
            scratch: RefCell::new(Scratch::default()),
        }
    }

    /// The contacts at state `s` into the scratch (particle pairs, then colliders; box walls
    /// along periodic axes left out).
    fn detect(&self, s: &State, scratch: &mut Scratch) -> Result<(), Error> {
        let Scratch {
            grid,
            pairs,
            contacts,
            walls,
        } = scratch;
        grid.find_pairs(s.x, &self.radius, &self.domain, 0.0, pairs)?;
        sphere_contacts(s.x, s.v, &self.radius, pairs, &self.domain, 0.0, contacts)?;
        walls.clear();
        collider_contacts(&self.colliders, s.x, s.v, &self.radius, 0.0, walls)?;
        contacts.extend(walls.iter().filter(|c| !on_periodic_wall(c, &self.colliders, &self.domain)));
        Ok(())
    }

    fn materials(&self) -> MaterialTable<'_> {
        let table = MaterialTable::uniform(self.global).with_colliders(&self.colliders);
        match &self.own {
            Some(m) => table.with_particles(m),
            None => table,
        }
    }

    /// w_i + w_j of a contact.
    fn inverse_mass_sum(&self, c: &Contact) -> f64 {
        self.inv_mass[c.i] + c.partner_particle().map_or(0.0, |j| self.inv_mass[j])
    }

    /// c_n (kg/s) of a contact with w = w_i + w_j > 0.
    fn dashpot(&self, c: &Contact, w: f64) -> f64 {
        match self.damping {
            Some(gamma) => gamma / w,
            None => {
                let e = self.materials().pair(c).restitution();
                let zeta = damping_ratio(e).unwrap_or(0.0);
                2.0 * zeta * (self.stiffness / w).sqrt()
            }
        }
    }
}

impl Force for ContactForce {
    fn name(&self) -> &str {
        "contact"
    }

    fn accumulate(&mut self, s: &State, f: &mut [f64]) -> Result<(), CallbackError> {
        let mut scratch = self.scratch.borrow_mut();
        self.detect(s, &mut scratch)?;
        for c in &scratch.contacts {
            let w = self.inverse_mass_sum(c);
            if c.overlap.is_nan() || c.overlap <= 0.0 || w == 0.0 {
                continue;
            }
            let force = self.stiffness * c.overlap - self.dashpot(c, w) * c.u_n;
            for k in 0..3 {
                f[3 * c.i + k] += force * c.normal[k];
                if let Some(j) = c.partner_particle() {
                    f[3 * j + k] -= force * c.normal[k];
                }
            }
        }
        Ok(())
    }

    // No `validate`: the world rebuilds this force whenever its particles change.

    /// U = Σ ½ k_n δ² over the overlapping contacts, J.
    fn potential_energy(&self, s: &State) -> Option<f64> {
        let mut scratch = self.scratch.borrow_mut();
        self.detect(s, &mut scratch).ok()?;
        Some(
            scratch
                .contacts
                .iter()
                .filter(|c| c.overlap > 0.0 && self.inverse_mass_sum(c) > 0.0)
                .map(|c| 0.5 * self.stiffness * c.overlap * c.overlap)
                .sum(),
        )
    }

    fn depends_on_velocity(&self) -> bool {
        true
    }

    fn is_internal(&self) -> bool {
        self.colliders.is_empty()
    }

    /// The spring is conservative and the dashpot dissipative.
    fn can_add_energy(&self) -> bool {
        false
    }

    /// Gershgorin over the contacts at `s`: a contact adds k_n w_p to particle p's row twice
    /// with a particle partner (diagonal and off-diagonal), once against a collider; the
    /// dashpot likewise with c_n.
    fn rate_bound(&self, s: &State, inv_mass: &[f64]) -> Option<SpringRates> {
        let mut scratch = self.scratch.borrow_mut();
        self.detect(s, &mut scratch).ok()?;
        let mut k_row = vec![0.0; inv_mass.len()];
        let mut c_row = vec![0.0; inv_mass.len()];
        for c in scratch.contacts.iter().filter(|c| c.overlap > 0.0) {
            let w = self.inverse_mass_sum(c);
            if w == 0.0 {
                continue;
            }
            let times = if c.partner_particle().is_some() { 2.0 } else { 1.0 };
            let dashpot = self.dashpot(c, w);
            for p in std::iter::once(c.i).chain(c.partner_particle()) {
                k_row[p] += times * self.stiffness;
                c_row[p] += times * dashpot;
            }
        }
        let mut rates = SpringRates::default();
        for (p, w) in inv_mass.iter().enumerate() {
            rates.omega_squared = rates.omega_squared.max(w * k_row[p]);
            rates.damping_rate = rates.damping_rate.max(w * c_row[p]);
        }
        Some(rates)
    }

    /// A contact that is not touching yet counts as a spring: ω² = k_n (w_i + w_j) for the
    /// two lightest movable particles (or k_n w against a collider), with the ζ of the
    /// largest restitution's opposite, the least damped contact.
    fn standby_rates(&self, inv_mass: &[f64]) -> Option<(f64, f64)> {
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
        let omega_squared = self.stiffness * w;
        let zeta = match self.damping {
            Some(gamma) => gamma / (2.0 * omega_squared.sqrt()),
            None => {
                let e_max = self
                    .own
                    .iter()
                    .flatten()
                    .map(|m| m.restitution())
                    .chain(self.colliders.iter().filter_map(|c| c.surface().restitution()))
                    .fold(self.global.restitution(), f64::max);
                damping_ratio(e_max).unwrap_or(0.0)
            }
        };
        Some((omega_squared, zeta))
    }
}
