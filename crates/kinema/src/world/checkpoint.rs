//! What a checkpoint takes from a world and gives back to it besides the particles' state:
//! the clock and ids, the collision books, and what the method and the impulse model carry
//! from one step to the next.

use super::{ColliderBooks, CollisionStats, World, WorldStepper};
use crate::collide::{ContactRecord, Partner};
use crate::error::Error;
use crate::vec3;

impl World {
    /// Restores what a checkpoint holds besides the particles' state: the time (s), the
    /// steps taken, and each particle's id with the id the next one gets (ids strictly
    /// increasing, as adding and removing leave them, all below `next_id`).
    pub fn restore_clock_and_ids(&mut self, time: f64, steps: u64, ids: &[u64], next_id: u64) -> Result<(), Error> {
        if !time.is_finite() {
            return Err(Error::invalid("time", time, "the time must be finite"));
        }
        if ids.len() != self.particles.len() {
            return Err(Error::invalid(
                "ids",
                format!("{} ids", ids.len()),
                format!("one per particle ({})", self.particles.len()),
            ));
        }
        if let Some(k) = (1..ids.len()).find(|&k| ids[k] <= ids[k - 1]) {
            return Err(Error::invalid(format!("ids[{k}]"), ids[k], "ids must increase strictly"));
        }
        if ids.last().is_some_and(|&l| l >= next_id) {
            return Err(Error::invalid("next_id", next_id, "it must be above every id"));
        }
        self.restore_user_order();
        self.time = time;
        self.steps = steps;
        // the clock of a world stepped by dt from 0 (`restore_clock` sets another)
        self.clock = if time == steps as f64 * self.params.dt {
            super::Clock::new(self.params.dt)
        } else {
            super::Clock {
                k0: steps,
                t0: time,
                h: self.params.dt,
                landing: None,
            }
        };
        self.particles.id.copy_from_slice(ids);
        self.membership += 1;
        self.particles.next_id = next_id;
        Ok(())
    }

    /// Restores a checkpoint's clock (`clock.rs`): the anchor, `k0` steps at `t0` s, from
    /// which the time after k steps is t0 + (k − k0)·dt, which must give the time restored
    /// ([`World::restore_clock_and_ids`]) to the bit.
    pub fn restore_clock(&mut self, k0: u64, t0: f64) -> Result<(), Error> {
        let clock = super::Clock {
            k0,
            t0,
            h: self.params.dt,
            landing: None,
        };
        if k0 > self.steps || !t0.is_finite() || clock.time_after(self.steps, self.params.dt) != self.time {
            return Err(Error::invalid(
                "clock",
                format!("({k0} steps, {t0} s)"),
                format!(
                    "the anchor of a clock at t = {} s after {} steps of dt = {} s: t0 + (steps − k0)·dt must be t",
                    self.time, self.steps, self.params.dt
                ),
            ));
        }
        self.clock = clock;
        Ok(())
    }

    /// Restores the collision books of a checkpoint: the totals since collisions were turned
    /// on and the last step's (see [`World::collision_stats`]). Nothing when they are off.
    pub fn restore_collision_stats(&mut self, total: CollisionStats, last: CollisionStats) {
        if let Some(stage) = &mut self.collide_stage {
            stage.total = total;
            stage.last = last;
        }
    }

    /// A checkpoint's collider books: what the particles gave each collider over all steps
    /// (`total`) and in the last step (`last`), one per collider (`collider_books`). A world
    /// read from a checkpoint goes on from the same sums, bit for bit.
    pub fn restore_collider_books(&mut self, total: Vec<ColliderBooks>, last: Vec<ColliderBooks>) -> Result<(), Error> {
        let Some(stage) = &mut self.collide_stage else {
            return Err(Error::invalid(
                "collider_books",
                "given",
                "a world with collisions (set_collisions first): only its colliders keep books",
            ));
        };
        let n = stage.colliders.len();
        if total.len() != n || last.len() != n {
            return Err(Error::invalid(
                "collider_books",
                format!("{} and {} rows", total.len(), last.len()),
                format!("one per collider ({n}) in both `total` and `last`"),
            ));
        }
        stage.collider_books = total;
        stage.collider_last = last;
        Ok(())
    }

    /// Starts the collision stage's and the contact force's caches again, as after changing
    /// the particles (the contact lists and the particles' order along space, the impulse
    /// solver's warm start), and the method's: a checkpoint is taken at such a point, so that
    /// a world read from it, built afresh, and the world that wrote it go on from the same
    /// engine state. What the method carries from step to step is kept apart
    /// ([`World::integrator_carry`]) and given back to both. The placement is not checked
    /// again (`collide/placement.rs`): it was when the run started, and the resumed run must
    /// go on as the one that wrote it.
    pub fn restart_caches(&mut self) -> Result<(), Error> {
        self.restore_user_order();
        // (the force models' last collider forces are a value of the state, not a cache:
        // kept, as a checkpoint keeps them, so that writing one changes no bit of the books)
        let walls = self.wall_force_carry();
        self.reset_caches();
        self.placement_from = None;
        self.contacts_changed();
        self.restore_wall_force_carry(walls);
        Ok(())
    }

    /// The force models' collider forces of the last step's Verlet pass, as rates (N, N·m
    /// and W in [`ColliderBooks`]' fields), which the next step's collider books start from;
    /// `None` when there are none (no force model, or none kept since a change).
    pub fn wall_force_carry(&self) -> Option<Vec<ColliderBooks>> {
        self.collide_stage.as_ref()?.force_model()?.wall_carry()
    }

    /// Sets what [`World::wall_force_carry`] gave (a checkpoint's).
    pub fn restore_wall_force_carry(&mut self, carry: Option<Vec<ColliderBooks>>) {
        if let Some(model) = self.collide_stage.as_ref().and_then(|c| c.force_model()) {
            model.set_wall_carry(carry);
        }
    }

    /// What the method carries from one step to the next, in the user's order: Verlet's
    /// acceleration at the current state (m/s², 3 per particle; only while it is up to date)
    /// or implicit Euler's last Δv (m/s, its first guess for the next solve). `None` for the
    /// other methods, which carry nothing, and before the first step.
    pub fn integrator_carry(&mut self) -> Option<Vec<f64>> {
        self.restore_user_order();
        let n = 3 * self.particles.len();
        match &self.stepper {
            Some(WorldStepper::Verlet(b)) if b.fresh && b.a.len() == n => Some(b.a.clone()),
            Some(WorldStepper::Implicit(bw)) if bw.warm_start().len() == n => Some(bw.warm_start().to_vec()),
            _ => None,
        }
    }

    /// The impulse model's records carried to the next step: each contact of the last step
    /// (its particle, partner, its solve stage's impulse in N·s and whether it carried
    /// load), sorted (a collider's several contacts with one particle in the order of its
    /// features); empty without collisions.
    pub fn collision_carry(&mut self) -> Vec<ContactRecord> {
        self.restore_user_order();
        self.collide_stage.as_ref().map(|c| c.all_warm()).unwrap_or_default()
    }

    /// The impulse model's candidate list as built (`ImpulseModel::list_carry`): the
    /// positions it was built at (m, 3 per particle) and its skin (m); `None` before a first
    /// build, without collisions, or when the list is stale (the particles changed since).
    pub fn list_carry(&mut self) -> Option<(Vec<f64>, f64)> {
        self.restore_user_order();
        let n = 3 * self.particles.len();
        // (a list built before particles were added or removed is stale: built afresh)
        self.collide_stage
            .as_ref()?
            .list_carry()
            .filter(|(built_at, _)| built_at.len() == n)
    }

    /// Builds the impulse model's candidate list where [`World::list_carry`] says it was
    /// built (a checkpoint's), so that it is rebuilt at the same steps as in the run that
    /// wrote it. Checks the length and that the values are finite.
    pub fn restore_list_carry(&mut self, built_at: Vec<f64>, skin: f64) -> Result<(), Error> {
        let n = self.particles.len();
        if built_at.len() != 3 * n {
            return Err(Error::invalid(
                "list_built_at",
                format!("{} values", built_at.len()),
                format!("3 per particle ({})", 3 * n),
            ));
        }
        if let Some((k, value)) = vec3::first_non_finite(&built_at) {
            return Err(Error::invalid(format!("list_built_at[{k}]"), value, "finite positions, m"));
        }
        if !(skin.is_finite() && skin > 0.0) {
            return Err(Error::invalid("list_skin", skin, "a finite skin > 0 m"));
        }
        self.restore_user_order();
        let Some(stage) = &mut self.collide_stage else {
            return Err(Error::invalid("list_built_at", n, "no candidate list: collisions are off"));
        };
        stage.restore_list(&built_at, skin, &self.particles.radius, &self.particles.group)
    }

    /// What sleeping carries to the next step (`collide/sleep.rs`): each particle's calm time
    /// (s) and the island it sleeps in (−1: awake); empty without collisions.
    pub fn sleep_carry(&mut self) -> (Vec<f64>, Vec<i64>) {
        self.restore_user_order();
        let n = self.particles.len();
        self.collide_stage.as_ref().map(|c| c.sleep_carry(n)).unwrap_or_default()
    }

    /// Gives sleeping back what [`World::sleep_carry`] took (a checkpoint's), after
    /// [`World::restore_collision_carry`]: the islands asleep again with their contacts'
    /// warm start. Checks the lengths, the times and that an island's contacts stay in it.
    pub fn restore_sleep_carry(&mut self, calm: Vec<f64>, island: Vec<i64>) -> Result<(), Error> {
        let n = self.particles.len();
        if calm.is_empty() && island.is_empty() {
            return Ok(()); // a checkpoint from before sleeping, or without collisions
        }
        for (name, len) in [("sleep_calm", calm.len()), ("sleep_island", island.len())] {
            if len != n {
                return Err(Error::invalid(
                    name,
                    format!("{len} values"),
                    format!("one per particle ({n})"),
                ));
            }
        }
        if let Some(k) = calm.iter().position(|c| !(c.is_finite() && *c >= 0.0)) {
            return Err(Error::invalid(
                format!("sleep_calm[{k}]"),
                calm[k],
                "calm times are finite and >= 0 s",
            ));
        }
        if let Some(k) = island.iter().position(|&k| k < -1) {
            return Err(Error::invalid(
                format!("sleep_island[{k}]"),
                island[k],
                "an island number >= 0, or -1: awake",
            ));
        }
        let Some(stage) = &mut self.collide_stage else {
            return Err(Error::invalid("sleep_island", n, "nothing sleeps: collisions are off"));
        };
        let pinned = |q: usize| self.particles.inv_mass[q] == 0.0;
        if let Some(w) = stage.contact_records().iter().find(|w| match w.other {
            Partner::Particle(j) => island[w.i] != island[j] && !pinned(w.i) && !pinned(j),
            Partner::Collider(_) => false,
        }) {
            return Err(Error::invalid(
                "sleep_island",
                format!("{:?}", w),
                "a contact's two movable particles sleep in one island, or are both awake",
            ));
        }
        stage.restore_sleep(calm, &island, &self.particles.radius, &self.particles.x);
        Ok(())
    }

    /// Gives the impulse model back what [`World::collision_carry`] took (a checkpoint's);
    /// checks the particles and colliders it names.
    pub fn restore_collision_carry(&mut self, carry: Vec<ContactRecord>) -> Result<(), Error> {
        let (n, colliders) = (self.particles.len(), self.colliders().len());
        if let Some(k) = carry.iter().position(|r| {
            r.i >= n
                || !r.impulse.iter().all(|c| c.is_finite())
                || match r.other {
                    Partner::Particle(j) => j >= n,
                    Partner::Collider(c) => c >= colliders,
                }
        }) {
            return Err(Error::invalid(
                format!("collision_carry[{k}]"),
                format!("{:?}", carry[k]),
                format!("contacts between the {n} particles and {colliders} colliders, with finite impulses"),
            ));
        }
        match &mut self.collide_stage {
            Some(stage) => stage.set_warm_start(carry),
            None if carry.is_empty() => {}
            None => {
                return Err(Error::invalid(
                    "collision_carry",
                    carry.len(),
                    "no contacts: collisions are off",
                ))
            }
        }
        Ok(())
    }

    /// Gives the method back what [`World::integrator_carry`] took (a checkpoint's).
    pub fn restore_integrator_carry(&mut self, carry: Vec<f64>) -> Result<(), Error> {
        let n = 3 * self.particles.len();
        if carry.len() != n {
            return Err(Error::invalid(
                "integrator_carry",
                format!("{} values", carry.len()),
                format!("3 per particle ({n})"),
            ));
        }
        self.restore_user_order();
        let mut stepper = WorldStepper::new(&self.params.method, n);
        match &mut stepper {
            WorldStepper::Verlet(b) => {
                b.a = carry;
                b.fresh = true;
            }
            WorldStepper::Implicit(bw) => bw.set_warm_start(carry),
            _ => {
                return Err(Error::invalid(
                    "integrator_carry",
                    self.params.method.name(),
                    "only verlet and implicit_euler carry anything",
                ))
            }
        }
        self.stepper = Some(stepper);
        Ok(())
    }
}

/// A touching pair's memory as a checkpoint holds it: (i, j, springs), the springs as
/// ξ_t (3, m), ξ_r (3, m), θ_tw (rad) (`collide/contact_force/history.rs`).
pub type PairMemory = (usize, usize, [f64; 7]);

/// A collider touch's memory as a checkpoint holds it: (particle, collider, the touch's
/// normal, springs).
pub type WallMemory = (usize, usize, [f64; 3], [f64; 7]);

impl World {
    /// Whether the contacts have a tangential part (a force model, and friction somewhere).
    fn has_tangential_contacts(&self) -> bool {
        super::forces::contact_force(&self.collide_stage, &self.particles).is_some_and(|c| c.has_tangential())
    }

    /// What spin carries from step to step under the contacts' torques, in the user's order:
    /// the angular accelerations α at the current state (rad/s², 3 per particle), while
    /// Verlet's carry is up to date; `None` otherwise.
    pub fn spin_carry(&mut self) -> Option<Vec<f64>> {
        self.restore_user_order();
        let n = 3 * self.particles.len();
        let fresh = matches!(&self.stepper, Some(WorldStepper::Verlet(b)) if b.fresh && b.a.len() == n);
        (fresh && self.particles.has_spin() && self.has_tangential_contacts()).then(|| self.particles.alpha.clone())
    }

    /// Gives back what [`World::spin_carry`] took (a checkpoint's), after
    /// [`World::restore_integrator_carry`].
    pub fn restore_spin_carry(&mut self, alpha: Vec<f64>) -> Result<(), Error> {
        let n = 3 * self.particles.len();
        if !self.particles.has_spin() {
            return Err(Error::invalid(
                "spin_carry",
                "given",
                "only a world with spin carries angular accelerations",
            ));
        }
        if alpha.len() != n {
            return Err(Error::invalid(
                "spin_carry",
                format!("{} values", alpha.len()),
                format!("3 per particle ({n})"),
            ));
        }
        if let Some((k, v)) = crate::vec3::first_non_finite(&alpha) {
            return Err(Error::invalid(
                format!("spin_carry[{k}]"),
                v,
                "angular accelerations must be finite",
            ));
        }
        self.restore_user_order();
        self.particles.alpha = alpha;
        Ok(())
    }

    /// The contacts' memory (the force models' tangential springs), in the user's order:
    /// touching pairs i < j, and particles touching colliders. Empty without it.
    pub fn contact_history(&mut self) -> (Vec<PairMemory>, Vec<WallMemory>) {
        self.restore_user_order();
        let Some(model) = self.force_model() else {
            return (Vec::new(), Vec::new());
        };
        let (pairs, walls) = model.history();
        (
            pairs
                .iter()
                .map(|p| (p.i as usize, p.j as usize, p.slip.to_array()))
                .collect(),
            walls
                .iter()
                .map(|w| (w.i as usize, w.k as usize, w.normal, w.slip.to_array()))
                .collect(),
        )
    }

    /// Gives back what [`World::contact_history`] took (a checkpoint's): checks that each
    /// index is in range and each number finite.
    pub fn restore_contact_history(&mut self, pairs: Vec<PairMemory>, walls: Vec<WallMemory>) -> Result<(), Error> {
        use crate::collide::contact_force::{PairSlip, Slip, WallSlip};
        let n = self.particles.len();
        let colliders = self.collide_stage.as_ref().map_or(0, |s| s.colliders.len());
        for (k, (i, j, s)) in pairs.iter().enumerate() {
            if *i >= n || *j >= n || i == j {
                return Err(Error::invalid(
                    format!("contact_history pair {k}"),
                    format!("({i}, {j})"),
                    format!("two different particles, each below {n}"),
                ));
            }
            if s.iter().any(|c| !c.is_finite()) {
                return Err(Error::invalid(
                    format!("contact_history pair {k}"),
                    format!("{s:?}"),
                    "finite springs",
                ));
            }
        }
        for (q, (i, k, normal, s)) in walls.iter().enumerate() {
            if *i >= n || *k >= colliders {
                return Err(Error::invalid(
                    format!("contact_history wall {q}"),
                    format!("({i}, {k})"),
                    format!("a particle below {n} and a collider below {colliders}"),
                ));
            }
            if s.iter().chain(normal).any(|c| !c.is_finite()) {
                return Err(Error::invalid(
                    format!("contact_history wall {q}"),
                    format!("{s:?}"),
                    "finite springs and normal",
                ));
            }
        }
        self.restore_user_order();
        let Some(model) = self.force_model() else {
            if pairs.is_empty() && walls.is_empty() {
                return Ok(());
            }
            return Err(Error::invalid(
                "contact_history",
                "given",
                "only the force models keep a contact history",
            ));
        };
        model.set_history(
            pairs
                .into_iter()
                .map(|(i, j, s)| PairSlip {
                    i: i as u32,
                    j: j as u32,
                    slip: Slip::from_array(s),
                })
                .collect(),
            walls
                .into_iter()
                .map(|(i, k, normal, s)| WallSlip {
                    i: i as u32,
                    k: k as u32,
                    normal,
                    slip: Slip::from_array(s),
                })
                .collect(),
        );
        Ok(())
    }
}
