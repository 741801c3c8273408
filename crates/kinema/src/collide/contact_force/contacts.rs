//! Finding the contacts of [`ContactForce`]: the listed particle pairs that overlap, each
//! tested exactly as [`pair_contact`] tests it, and the particles' contacts with the colliders
//! (box walls along periodic axes left out).

use super::history::{pair_memory, touches_of, wall_memory, PairSlip, WallSlip};
use super::{ContactForce, Scratch, CHUNK};
use crate::collide::neighbour_list::NeighbourList;
use crate::collide::stage::on_periodic_wall;
use crate::collide::velocities::Velocities;
use crate::collide::{pair_contact, Contact};
use crate::error::Error;
use crate::forces::State;

impl ContactForce<'_> {
    /// Calls `each` with every contact at state `s`, in the order of a full search: particle
    /// pairs by (i, j), i < j (those of the (half) neighbour list that touch, each tested exactly as
    /// [`pair_contact`] tests it), then particle by particle, collider by collider, wall by
    /// wall (box walls along periodic axes left out), as the tests' `collider_contacts`
    /// (`collide/oracles.rs`) lists them.
    ///
    /// With JKR's contacts, those held past touching are among them (the contacts' memory
    /// says which touched at the last step: `cohesion.rs`).
    pub(super) fn for_each_contact(&self, s: &State, scratch: &mut Scratch, mut each: impl FnMut(&Contact)) -> Result<(), Error> {
        self.update_list(s, scratch)?;
        let Scratch { list, histories, .. } = &*scratch;
        let (x, v) = (s.x, s.v);
        let mut lost = 0.0;
        for (c, rows) in list.rows.iter().enumerate() {
            for (l, i) in (c * CHUNK..).take(rows.len()).enumerate() {
                for &j in rows.of(l) {
                    if j as usize > i {
                        let j = j as usize;
                        let found = match self.pair(i, j, x, v) {
                            None if self.jkr().is_some() => self.held_pair(i, j, x, v, &histories.pairs, &mut lost),
                            found => found,
                        };
                        if let Some(contact) = found {
                            each(&contact);
                        }
                    }
                }
            }
        }
        self.for_each_wall_contact(s, list, &histories.walls, each);
        Ok(())
    }

    /// With JKR's contacts, the contact of particles i < j at (x, v) that touched at the last
    /// step (`memory`, sorted) and are apart now but within its pull-off distance; `None` for
    /// the others, and for a pair that went past it, whose contact lets go: the energy it
    /// loses is added to `lost` (J, `cohesion.rs`).
    #[cold]
    pub(super) fn held_pair<V: Velocities + ?Sized>(
        &self,
        i: usize,
        j: usize,
        x: &[f64],
        v: &V,
        memory: &[PairSlip],
        lost: &mut f64,
    ) -> Option<Contact> {
        let (jkr, reach) = self.jkr()?;
        pair_memory(memory, i as u32, j as u32)?;
        let r = self.radius[i] * self.radius[j] / (self.radius[i] + self.radius[j]);
        let held = pair_contact(i, j, x, v, self.radius, &self.domain, reach).filter(|c| c.overlap > -jkr.pull_off_distance(r));
        if held.is_none() {
            *lost += jkr.separation_energy(r);
        }
        held
    }

    /// The contact of particles i < j at (x, v), if they overlap: `pair_contact`, after its own
    /// test |d|² < (r_i + r_j + 0)² with the same floating-point operations, inline (most
    /// listed pairs do not touch, and are dropped here without a call).
    #[inline]
    fn pair(&self, i: usize, j: usize, x: &[f64], v: &[f64]) -> Option<Contact> {
        let d = self
            .domain
            .displacement([x[3 * i], x[3 * i + 1], x[3 * i + 2]], [x[3 * j], x[3 * j + 1], x[3 * j + 2]]);
        let reach = self.radius[i] + self.radius[j] + 0.0;
        if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] >= reach * reach {
            return None;
        }
        pair_contact(i, j, x, v, self.radius, &self.domain, 0.0)
    }

    /// Whether particles i and j overlap at `x`, tested from i's side with x_i already loaded:
    /// the same operations as [`ContactForce::pair`]'s test of the pair (lower index first),
    /// bit for bit, since x_i − x_j = −(x_j − x_i) exactly, the minimum image is odd and the
    /// squares and r_i + r_j do not care about the order.
    #[inline(always)]
    pub(super) fn overlaps(&self, xi: [f64; 3], ri: f64, j: usize, x: &[f64]) -> bool {
        let d = self.domain.displacement(xi, [x[3 * j], x[3 * j + 1], x[3 * j + 2]]);
        let reach = ri + self.radius[j] + 0.0;
        d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < reach * reach
    }

    /// Calls `each` with every contact of a particle with a collider at `s`, particle by
    /// particle, collider by collider (the list must hold at `s`), JKR's held ones among them
    /// by the touches in `memory` ([`ContactForce::wall_contacts_held`]).
    pub(super) fn for_each_wall_contact(
        &self,
        s: &State,
        list: &NeighbourList,
        memory: &[WallSlip],
        mut each: impl FnMut(&Contact),
    ) {
        let mut lost = 0.0;
        for &(i, k) in &list.walls {
            self.wall_contacts_held(i, k, s.x, s.v, memory, &mut lost, &mut each);
        }
    }

    /// Calls `each` with the contacts of particle i with collider k at (x, v): those that
    /// overlap and, with JKR's contacts, those apart now but within the pull-off distance
    /// that touched at the last step (`memory`, the store's part with i's touches, by
    /// their normals); the energy of each remembered touch that let go is added to `lost`
    /// (J, `cohesion.rs`).
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub(super) fn wall_contacts_held<V: Velocities + ?Sized>(
        &self,
        i: usize,
        k: usize,
        x: &[f64],
        v: &V,
        memory: &[WallSlip],
        lost: &mut f64,
        mut each: impl FnMut(&Contact),
    ) {
        let Some((jkr, reach)) = self.jkr() else {
            return self.wall_contacts(i, k, x, v, each);
        };
        let remembered = touches_of(memory, i as u32, k as u32);
        let (p, vi) = ([x[3 * i], x[3 * i + 1], x[3 * i + 2]], v.at(i));
        let (collider, r) = (&self.colliders[k], self.radius[i]);
        let mut held = 0;
        collider.for_each_touch(p, r, reach, |t| {
            let c = collider.contact(k, t, i, p, vi, r);
            if on_periodic_wall(&c, self.colliders, &self.domain) {
                return;
            }
            if c.overlap > 0.0 {
                held += usize::from(wall_memory(remembered, i as u32, k as u32, c.normal).is_some());
                each(&c);
            } else if c.overlap > -jkr.pull_off_distance(r) && wall_memory(remembered, i as u32, k as u32, c.normal).is_some() {
                held += 1;
                each(&c);
            }
        });
        // (the remembered touches not found again let go)
        *lost += remembered.len().saturating_sub(held) as f64 * jkr.separation_energy(r);
    }

    /// Calls `each` with the contacts of particle i with collider k at (x, v) (a box's walls
    /// along periodic axes left out).
    #[inline]
    pub(super) fn wall_contacts<V: Velocities + ?Sized>(
        &self,
        i: usize,
        k: usize,
        x: &[f64],
        v: &V,
        mut each: impl FnMut(&Contact),
    ) {
        let (p, vi) = ([x[3 * i], x[3 * i + 1], x[3 * i + 2]], v.at(i));
        let collider = &self.colliders[k];
        collider.for_each_touch(p, self.radius[i], 0.0, |t| {
            let c = collider.contact(k, t, i, p, vi, self.radius[i]);
            if !on_periodic_wall(&c, self.colliders, &self.domain) {
                each(&c);
            }
        });
    }

    /// Whether, at positions `x` (m), some particle that stays (`keep[i]`) touches one that
    /// goes, or `None` when the list does not hold at `x` (nothing can be said from it).
    pub(crate) fn touches_across(&self, x: &[f64], keep: &[bool]) -> Option<bool> {
        let scratch = self.scratch();
        let list = &scratch.list;
        if keep.len() != self.radius.len() || !list.holds(x, &self.domain) {
            return None;
        }
        Some(self.listed_touch(list, x, |i, j| keep[i] != keep[j]))
    }

    /// Whether a newborn (a particle from `start` on) touches another particle or a collider
    /// at (x, v), by the list, which must hold there ([`ContactForce::keep_list_with_newborns`]
    /// admitted them); true when it does not hold (nothing can be said from it).
    pub(crate) fn newborns_touch(&self, x: &[f64], v: &[f64], start: usize) -> bool {
        let scratch = self.scratch();
        let list = &scratch.list;
        if x.len() != 3 * self.radius.len() || !list.holds(x, &self.domain) {
            return true;
        }
        if self.listed_touch(list, x, |i, j| i.max(j) >= start) {
            return true;
        }
        let mut touch = false;
        for &(i, k) in list.walls.iter().filter(|w| w.0 >= start) {
            self.wall_contacts(i, k, x, v, |_| touch = true);
        }
        touch
    }

    /// Whether some listed pair (i, j) that `which` picks overlaps at `x`.
    fn listed_touch(&self, list: &NeighbourList, x: &[f64], which: impl Fn(usize, usize) -> bool) -> bool {
        list.rows.iter().enumerate().any(|(c, rows)| {
            (0..rows.len()).any(|l| {
                let i = c * CHUNK + l;
                let xi = [x[3 * i], x[3 * i + 1], x[3 * i + 2]];
                rows.of(l)
                    .iter()
                    .any(|&j| which(i, j as usize) && self.overlaps(xi, self.radius[i], j as usize, x))
            })
        })
    }
}
