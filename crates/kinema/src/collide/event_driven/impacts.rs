//! The event-driven state's impacts: a pair's, and a particle's with a wall, each by
//! Newton's restitution law of the stepped impacts ([`restitution_impulse`]).

use super::EventDriven;
use crate::collide::books::ColliderBooks;
use crate::collide::contact::{Contact, Partner};
use crate::collide::impulse::CollisionStats;
use crate::collide::response::{restitution_impulse, MaterialTable};
use crate::collide::spin::Rotation;
use crate::collide::Domain;
use crate::particles::Particles;
use crate::vec3;

impl EventDriven {
    /// The impact of i and j at time `now` (s): both moved there, the impulse of
    /// [`restitution_impulse`] given to i and its opposite to j; both paths change.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn impact_pair(
        &mut self,
        i: usize,
        j: usize,
        now: f64,
        p: &mut Particles,
        materials: &MaterialTable<'_>,
        threshold: f64,
        domain: &Domain,
        stats: &mut CollisionStats,
    ) {
        for k in [i, j] {
            self.bodies[k].move_to(now, self.g, None);
        }
        let (bi, bj) = (self.bodies[i], self.bodies[j]);
        let d = domain.displacement(bi.x, bj.x);
        let dist = vec3::norm(d);
        if dist == 0.0 {
            return; // coincident centres have no normal (placement refuses them)
        }
        let (wi, wj) = (self.order[i] as usize, self.order[j] as usize); // the world's indices
        let contact = Contact {
            i: wi,
            other: Partner::Particle(wj),
            normal: vec3::scale(1.0 / dist, d),
            overlap: self.radius[i] + self.radius[j] - dist,
            u_n: 0.0,
            wall_velocity: [0.0; 3],
        };
        let material = materials.pair(&contact);
        // the same rule as the stepped impacts, on the pair alone (i as 0, j as 1)
        let v = [bi.v[0], bi.v[1], bi.v[2], bj.v[0], bj.v[1], bj.v[2]];
        let w = [p.inv_mass[wi], p.inv_mass[wj]];
        let pair = Contact {
            i: 0,
            other: Partner::Particle(1),
            ..contact
        };
        // with spin, on the contact point's velocity, and both turn (`collide/spin.rs`; the
        // world's angular velocities: nothing turns between impacts)
        let rotation = p.has_spin().then_some(Rotation {
            inv_inertia: &p.inv_inertia,
            radius: &p.radius,
        });
        let spin = rotation.map(|r| r.of(&contact, &p.omega));
        let Some(imp) = restitution_impulse(&pair, &v, &w, material, threshold, spin) else {
            return;
        };
        if let Some(r) = rotation {
            r.kick(&contact, contact.overlap, imp.vector, &mut p.omega);
        }
        let (vi, vj) = (&mut self.bodies[i].v, vec3::add(bj.v, vec3::scale(-w[1], imp.vector)));
        *vi = vec3::add(*vi, vec3::scale(w[0], imp.vector));
        self.bodies[j].v = vj;
        for k in 0..3 {
            // Σ m Δv of the two: zero by action and reaction up to rounding
            let mut balance = 0.0;
            if w[0] > 0.0 {
                balance += p.mass[wi] * (self.bodies[i].v[k] - bi.v[k]);
            }
            if w[1] > 0.0 {
                balance += p.mass[wj] * (self.bodies[j].v[k] - bj.v[k]);
            }
            stats.impulse_balance[k] += balance;
        }
        crate::collide::impulse::add_outer(&mut stats.virial, d, imp.vector);
        self.bodies[i].path = self.bodies[i].path.wrapping_add(1);
        self.bodies[j].path = self.bodies[j].path.wrapping_add(1);
        stats.impacts += 1;
        stats.impulses += 1;
        stats.energy_lost += imp.energy_lost;
    }

    /// The impact of i with wall k at time `now` (s), by the same rule; the wall's collider
    /// books what it took. Whether an impulse was given (none when i does not approach).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn impact_wall(
        &mut self,
        i: usize,
        k: usize,
        now: f64,
        p: &mut Particles,
        materials: &MaterialTable<'_>,
        threshold: f64,
        stats: &mut CollisionStats,
        books: &mut [ColliderBooks],
    ) -> bool {
        let b = &mut self.bodies[i];
        b.move_to(now, self.g, None);
        let wall = self.walls[k];
        let wi = self.order[i] as usize; // the world's index
        let contact = Contact {
            i: wi,
            other: Partner::Collider(wall.collider),
            normal: wall.normal,
            overlap: self.radius[i] - vec3::dot(vec3::sub(b.x, wall.point), wall.normal),
            u_n: 0.0,
            wall_velocity: [0.0; 3],
        };
        let material = materials.pair(&contact);
        let alone = Contact { i: 0, ..contact };
        let rotation = p.has_spin().then_some(Rotation {
            inv_inertia: &p.inv_inertia,
            radius: &p.radius,
        });
        let spin = rotation.map(|r| r.of(&contact, &p.omega));
        let Some(imp) = restitution_impulse(&alone, &b.v, &[p.inv_mass[wi]], material, threshold, spin) else {
            return false;
        };
        if let Some(r) = rotation {
            r.kick(&contact, contact.overlap, imp.vector, &mut p.omega);
        }
        b.v = vec3::add(b.v, vec3::scale(p.inv_mass[wi], imp.vector));
        b.path = b.path.wrapping_add(1);
        stats.impacts += 1;
        stats.impulses += 1;
        stats.energy_lost += imp.energy_lost;
        if let Some(book) = books.get_mut(wall.collider) {
            // where it touched: the sphere's point on the wall
            let at = vec3::sub(b.x, vec3::scale(self.radius[i], wall.normal));
            book.book(at, [0.0; 3], imp.vector, wall.normal);
        }
        true
    }
}
