//! What each contact of [`ContactForce`] does at a state, for output (LAMMPS's
//! `compute pair/local`, Yade's `O.forces`): the contacts of a full search (`contacts.rs`),
//! each with its normal force F_n n and its tangential force F_t as the next evaluation would
//! find them (the springs read, not stretched: `tangent.rs`), whether it slides, and its point.

use super::history::{pair_memory, wall_memory, Histories};
use super::pairs::Turning;
use super::ContactForce;
use crate::collide::{Contact, ContactReport};
use crate::error::Error;
use crate::forces::State;
use crate::vec3;

impl ContactForce<'_> {
    /// The contacts' memory as an output reads it (`None` without friction or JKR's
    /// contacts): `histories` as it is, not stretched by a step (`tangent.rs`).
    pub(super) fn reading<'s>(&'s self, histories: &'s Histories) -> Option<Turning<'s>> {
        (self.tangential.is_some() || self.jkr().is_some()).then_some(Turning {
            model: self.tangential,
            omega: self.omega,
            pairs: &histories.pairs,
            walls: &histories.walls,
            step: None,
            start: None,
        })
    }

    /// Every contact at `s` that acts (an overlap, or JKR's held contact, and a movable
    /// side), in the order of a
    /// full search: pairs by (i, j), i < j, then particle by particle, collider by collider.
    pub(crate) fn contact_reports(&self, s: &State) -> Result<Vec<ContactReport>, Error> {
        let mut scratch = self.scratch();
        let mut found: Vec<Contact> = Vec::new();
        self.for_each_contact(s, &mut scratch, |c| found.push(*c))?;
        let turn = self.reading(&scratch.histories);
        let mut out = Vec::with_capacity(found.len());
        for c in &found {
            let Some((force, dashpot)) = self.normal_force_parts(c) else {
                continue;
            };
            let (mut force_t, mut sliding) = ([0.0; 3], false);
            if let Some((t, model)) = turn.as_ref().and_then(|t| t.model.map(|m| (t, m))) {
                let slip = match c.other {
                    crate::collide::Partner::Particle(j) => pair_memory(t.pairs, c.i as u32, j as u32),
                    crate::collide::Partner::Collider(k) => wall_memory(t.walls, c.i as u32, k as u32, c.normal),
                };
                let tg = self.tangent_of(model, t, c, force, dashpot, s.v, slip.unwrap_or_default());
                (force_t, sliding) = (tg.force, tg.slides);
            }
            let xi = vec3::get(s.x, c.i);
            let rj = c.partner_particle().map(|j| self.radius[j]);
            out.push(ContactReport {
                contact: *c,
                point: ContactReport::point_of(c, xi, self.radius[c.i], rj),
                force_n: vec3::scale(force, c.normal),
                force_t,
                impulse: [[0.0; 3]; 2],
                sliding,
            });
        }
        Ok(out)
    }
}
