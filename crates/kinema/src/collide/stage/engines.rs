//! What the world asks of the collide stage's contact engines (the impulse model,
//! `collide/impulse/`, and the contact force model, `collide/contact_force/`): the one
//! interface through which `world/` reaches them, so that the world never touches an engine's
//! fields. Each method says which engine answers; the other engines have nothing to do. (The
//! step itself is lent: `CollideStage::impulse_and_setting` gives `World::collide` the impulse
//! model with what it sees of the world, and `CollideStage::book_step` books what it did, so
//! that a step stays eight calls deep, `collide/mod.rs`.)

use std::ops::Range;

use super::{CollideStage, ContactModel};
use crate::collide::contact_force::ContactForceModel;
use crate::collide::impulse::end_of_step::overlap_at;
use crate::collide::impulse::KeptContacts;
use crate::collide::records::ContactRecord;
use crate::collide::touch::TouchEvent;
use crate::collide::{Contact, Partner};
use crate::interrupt::Interrupt;

impl CollideStage {
    /// The contact force model (spring–dashpot or Hertz), with those models.
    pub fn force_model(&self) -> Option<&ContactForceModel> {
        self.force_model.as_ref()
    }

    /// The impulse model's contacts, taken out to be kept across a change of the particles
    /// (their warm start: [`CollideStage::keep_contacts`]).
    pub fn take_contacts(&mut self) -> KeptContacts {
        self.impulse.take_contacts()
    }

    /// [`CollideStage::take_contacts`] after a removal: the survivors' contacts, renumbered
    /// (`new_of_old`).
    pub fn take_contacts_renumbered(&mut self, new_of_old: &[u32]) -> KeptContacts {
        self.impulse.take_contacts_renumbered(new_of_old)
    }

    /// Gives the contacts taken back, for `n` particles now (the impulse model's; the force
    /// models keep none).
    pub fn keep_contacts(&mut self, kept: KeptContacts, n: usize) {
        if self.params.model == ContactModel::Impulse {
            self.impulse.keep_contacts(kept, n);
        }
    }

    /// Whether the touches are recorded (`collide/touch.rs`).
    pub fn records_touches(&self) -> bool {
        self.impulse.touches.on
    }

    /// Records the touches (`on`) or stops, the contacts now carrying load (`loaded`) counted
    /// as touching.
    pub fn record_touches(&mut self, on: bool, loaded: impl Iterator<Item = (usize, Partner)>) {
        self.impulse.touches.record(on, loaded);
    }

    /// Follows a removal (`new_of_old`): the touches of the removed end at `time` (s), named
    /// by their ids before it (`ids`).
    pub fn renumber_touches(&mut self, new_of_old: &[u32], time: f64, ids: &[u64]) {
        self.impulse.touches.renumber(new_of_old, time, ids);
    }

    /// The begin and end of touch events recorded since the last call, in order, taken out.
    pub fn take_touch_events(&mut self) -> Vec<TouchEvent> {
        self.impulse.touches.take()
    }

    /// Wakes the islands asleep of particles `range` (a write to their state).
    pub fn wake_particles(&mut self, range: Range<usize>) {
        self.impulse.wake_particles(range);
    }

    /// The check that may stop a step inside the impulse model's impacts.
    pub fn set_interrupt(&mut self, interrupt: Interrupt) {
        self.impulse.interrupt = interrupt;
    }

    /// The contacts the impulse model detected in the last step.
    pub fn detected(&self) -> &[Contact] {
        &self.impulse.detected
    }

    /// The particles and contacts asleep now.
    pub fn asleep(&self) -> (usize, usize) {
        self.impulse.asleep()
    }

    /// The awake contacts' records, sorted by key (a checkpoint's warm start).
    pub fn contact_records(&self) -> &[ContactRecord] {
        self.impulse.records()
    }

    /// What sleeping carries to the next step: each of the `n` particles' calm time (s) and
    /// island (−1: awake).
    pub fn sleep_carry(&self, n: usize) -> (Vec<f64>, Vec<i64>) {
        self.impulse.sleep_carry(n)
    }

    /// Gives sleeping back what [`CollideStage::sleep_carry`] took, each contact's overlap
    /// measured at the particles' positions `x` (m) with their radii (m).
    pub fn restore_sleep(&mut self, calm: Vec<f64>, island: &[i64], radius: &[f64], x: &[f64]) {
        let (colliders, domain) = (&self.colliders, self.domain);
        let deepest = |i: usize, other: Partner| overlap_at(radius, colliders, &domain, x, i, other);
        self.impulse.restore_sleep(calm, island, deepest);
    }

    /// The impulse model's candidate list's skin, m (for the tests).
    #[cfg(test)]
    pub fn impulse_list_skin(&self) -> f64 {
        self.impulse.list.skin
    }

    /// Turns the impact search's check of each particle's sweep bound off (for the tests).
    #[cfg(test)]
    pub fn search_unbounded(&mut self) {
        self.impulse.unbounded = true;
    }

    /// Bounds the impulse model's candidate list to `entries` (for the tests).
    #[cfg(test)]
    pub fn set_impulse_list_limit(&mut self, entries: usize) {
        self.impulse.list.entry_limit = Some(entries);
    }
}
