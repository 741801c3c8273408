//! The world's event-driven advance (`CollisionParams::event_driven`): from t to t + n·dt by
//! events instead of n steps (`collide/event_driven/`, run by the collide stage).

use super::World;
use crate::error::Error;

impl World {
    /// Advances by `n` steps' time with event-driven dynamics: every impact at its exact time,
    /// by the stepped model's rule; then t is the clock's after steps + n (`clock.rs`). The forces must be uniform fields
    /// (gravity): the particles fly on straight lines or parabolas between impacts. Refused
    /// (naming why) otherwise. An interrupt leaves the world at the start.
    pub(super) fn advance_by_events(&mut self, n: u64) -> Result<(), Error> {
        self.check_pending_placement()?;
        let t1 = self.params_time_after(self.steps + n);
        // the forces must be uniform fields; their accelerations add
        let mut field = [0.0; 3];
        let mut other = None;
        for f in &self.forces {
            match f.uniform_acceleration() {
                Some(a) => field = [field[0] + a[0], field[1] + a[1], field[2] + a[2]],
                None => other = other.or(Some(f.name())),
            }
        }
        let Some(stage) = self.collide_stage.as_mut() else {
            return Ok(());
        };
        if let Some(why) = stage.events_refused(other, field, &self.particles) {
            return Err(Error::invalid(
                "event_driven",
                "True",
                format!("event-driven dynamics cannot run this world: {why} (event_driven=False steps it)"),
            ));
        }
        match stage.advance_events(&mut self.particles, self.time, t1, field, &mut self.interrupt) {
            // too fast to follow, as a step would say it (with the step, the time and the advice)
            Err(Error::Diverged { reason, particle, .. }) => return Err(self.diverged(reason, particle)),
            other => other?,
        }
        // a method's cache (Verlet's last acceleration) is for the state before
        self.stepper = None;
        self.time = t1;
        self.steps += n;
        self.clock.reached(self.steps, self.params.dt);
        Ok(())
    }
}
