//! The collide stage's contact engine, one closed choice ([`Engine`]: Newton's restitution
//! law stepped by impulses, the same law run by events, or a contact force), and what the
//! world asks of it: the one interface through which `world/` reaches the engine, so that the
//! world never touches an engine's fields. Each method says which engine answers; the others
//! have nothing to do and answer so (no contacts, no list, nobody asleep). (The step itself
//! is lent: `CollideStage::impulse_and_setting` gives `World::collide` the stepped engine
//! with what it sees of the world, and `CollideStage::book_step` books what it did, so that a
//! step stays eight calls deep, `collide/mod.rs`.)
//!
//! The engine follows the settings ([`Engine::kind_of`]): a change of the settings within
//! one kind keeps the engine and its buffers (the force model takes the new constants), a
//! change of kind makes the new engine afresh. The touch events not yet taken survive it:
//! the stepped engine records them while it runs, and the stage keeps them while another
//! engine does (`CollideStage::idle_touches`).

use std::ops::Range;

use super::{CollideStage, CollisionParams, ContactModel};
use crate::collide::contact_force::ContactForceModel;
use crate::collide::event_driven::EventDriven;
use crate::collide::groups::Filter;
use crate::collide::impulse::end_of_step::overlap_at;
use crate::collide::impulse::{ImpulseModel, KeptContacts};
use crate::collide::records::ContactRecord;
use crate::collide::touch::{TouchEvent, Touches};
use crate::collide::{Contact, Grid, Partner};
use crate::error::Error;
use crate::interrupt::Interrupt;

/// The contact engine of a collide stage. (Its variants differ in size, the stepped one's
/// buffers being held in place; a world holds one engine, so none is boxed.)
#[allow(clippy::large_enum_variant)]
pub(crate) enum Engine {
    /// Newton's restitution law by impulses after each integration step, stages 2–4
    /// (`collide/impulse/`): the seed's model, with its buffers kept from step to step.
    Stepped(ImpulseModel),
    /// The same law run by events from impact to impact instead of steps
    /// (`collide/event_driven/`, `CollisionParams::event_driven`): the state between calls
    /// (`None`: made afresh at the next).
    Events(Option<EventDriven>),
    /// A contact force while bodies overlap, integrated with the other forces in stage 1
    /// (`collide/contact_force/`: spring–dashpot, Hertz, DMT, JKR).
    Force(ContactForceModel),
}

/// Which [`Engine`] a stage's settings ask for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum EngineKind {
    Stepped,
    Events,
    Force,
}

impl Engine {
    /// The kind of engine the settings `params` ask for.
    pub fn kind_of(params: &CollisionParams) -> EngineKind {
        match (params.model, params.event_driven) {
            (ContactModel::Impulse, false) => EngineKind::Stepped,
            (ContactModel::Impulse, true) => EngineKind::Events,
            // (every other model is a force model: a new one needs no arm here)
            _ => EngineKind::Force,
        }
    }

    /// Its kind.
    pub fn kind(&self) -> EngineKind {
        match self {
            Engine::Stepped(_) => EngineKind::Stepped,
            Engine::Events(_) => EngineKind::Events,
            Engine::Force(_) => EngineKind::Force,
        }
    }

    /// The engine the settings `params` ask for, afresh (`interrupt`: the check that may stop
    /// a step of the stepped engine).
    pub fn of(params: &CollisionParams, interrupt: Interrupt) -> Self {
        match super::force_model_of(params) {
            Some(model) => Engine::Force(model),
            None if params.event_driven => Engine::Events(None),
            None => {
                let mut model = ImpulseModel::new();
                model.interrupt = interrupt;
                Engine::Stepped(model)
            }
        }
    }

    /// The engine for new settings `params`: this one kept when they ask for the same kind
    /// (the force model with their constants; its tangential springs forgotten when the
    /// tangential law changed), else afresh. Either way the event-driven state starts over.
    pub fn follow(self, params: &CollisionParams, interrupt: Interrupt) -> Self {
        match (self, Self::kind_of(params)) {
            (Engine::Force(mut kept), EngineKind::Force) => {
                // the list stays (it lists pairs by geometry alone); the constants are the new ones
                if let Some(new) = super::force_model_of(params) {
                    (kept.normal, kept.damping) = (new.normal, new.damping);
                    if kept.tangential != new.tangential {
                        kept.forget_history();
                    }
                    kept.tangential = new.tangential;
                }
                Engine::Force(kept)
            }
            (Engine::Stepped(kept), EngineKind::Stepped) => Engine::Stepped(kept),
            _ => Self::of(params, interrupt),
        }
    }
}

impl CollideStage {
    /// The stepped engine, `None` with another.
    fn stepped(&self) -> Option<&ImpulseModel> {
        match &self.engine {
            Engine::Stepped(m) => Some(m),
            _ => None,
        }
    }

    /// The stepped engine, mutable; `None` with another.
    fn stepped_mut(&mut self) -> Option<&mut ImpulseModel> {
        match &mut self.engine {
            Engine::Stepped(m) => Some(m),
            _ => None,
        }
    }

    /// The touches and their events: the stepped engine's while it runs, the stage's while
    /// another does (module doc).
    fn touches(&mut self) -> &mut Touches {
        match &mut self.engine {
            Engine::Stepped(m) => &mut m.touches,
            _ => &mut self.idle_touches,
        }
    }

    /// Follows the settings (checked, in `params`): the engine kept or made afresh
    /// ([`Engine::follow`]), the touches moved to where they are kept now.
    pub(super) fn follow_params(&mut self) {
        let (was, now) = (self.engine.kind(), Engine::kind_of(&self.params));
        if let (Engine::Stepped(m), true) = (&mut self.engine, now != EngineKind::Stepped) {
            self.idle_touches = std::mem::take(&mut m.touches);
        }
        let engine = std::mem::replace(&mut self.engine, Engine::Events(None));
        self.engine = engine.follow(&self.params, self.interrupt);
        if let (Engine::Stepped(m), true) = (&mut self.engine, was != EngineKind::Stepped) {
            m.touches = std::mem::take(&mut self.idle_touches);
        }
    }

    /// The contact force model (spring–dashpot, Hertz, DMT, JKR), `None` with the impulse
    /// engines.
    pub fn force_model(&self) -> Option<&ContactForceModel> {
        match &self.engine {
            Engine::Force(m) => Some(m),
            _ => None,
        }
    }

    /// The stepped engine's contacts, taken out to be kept across a change of the particles
    /// (their warm start: [`CollideStage::keep_contacts`]); none with the other engines.
    pub fn take_contacts(&mut self) -> KeptContacts {
        self.stepped_mut().map(ImpulseModel::take_contacts).unwrap_or_default()
    }

    /// [`CollideStage::take_contacts`] after a removal: the survivors' contacts, renumbered
    /// (`new_of_old`).
    pub fn take_contacts_renumbered(&mut self, new_of_old: &[u32]) -> KeptContacts {
        self.stepped_mut()
            .map(|m| m.take_contacts_renumbered(new_of_old))
            .unwrap_or_default()
    }

    /// Gives the contacts taken back, for `n` particles now (the stepped engine's; the others
    /// keep none).
    pub fn keep_contacts(&mut self, kept: KeptContacts, n: usize) {
        if let Some(m) = self.stepped_mut() {
            m.keep_contacts(kept, n);
        }
    }

    /// Whether the touches are recorded (`collide/touch.rs`; only the stepped engine records).
    pub fn records_touches(&self) -> bool {
        self.stepped().is_some_and(|m| m.touches.on)
    }

    /// Records the touches (`on`) or stops, the contacts now carrying load (`loaded`) counted
    /// as touching.
    pub fn record_touches(&mut self, on: bool, loaded: impl Iterator<Item = (usize, Partner)>) {
        self.touches().record(on, loaded);
    }

    /// Follows a removal (`new_of_old`): the touches of the removed end at `time` (s), named
    /// by their ids before it (`ids`).
    pub fn renumber_touches(&mut self, new_of_old: &[u32], time: f64, ids: &[u64]) {
        self.touches().renumber(new_of_old, time, ids);
    }

    /// The begin and end of touch events recorded since the last call, in order, taken out.
    pub fn take_touch_events(&mut self) -> Vec<TouchEvent> {
        self.touches().take()
    }

    /// Wakes the islands asleep of particles `range` (a write to their state; only the
    /// stepped engine's islands sleep).
    pub fn wake_particles(&mut self, range: Range<usize>) {
        if let Some(m) = self.stepped_mut() {
            m.wake_particles(range);
        }
    }

    /// The check that may stop a step inside the stepped engine's impacts (kept for an engine
    /// made later too).
    pub fn set_interrupt(&mut self, interrupt: Interrupt) {
        self.interrupt = interrupt;
        if let Some(m) = self.stepped_mut() {
            m.interrupt = interrupt;
        }
    }

    /// The contacts the stepped engine detected in the last step (none with the others).
    pub fn detected(&self) -> &[Contact] {
        self.stepped().map_or(&[], |m| &m.detected)
    }

    /// The particles and contacts asleep now.
    pub fn asleep(&self) -> (usize, usize) {
        self.stepped().map_or((0, 0), ImpulseModel::asleep)
    }

    /// The awake contacts' records, sorted by key (a checkpoint's warm start).
    pub fn contact_records(&self) -> &[ContactRecord] {
        self.stepped().map_or(&[], ImpulseModel::records)
    }

    /// Every contact's warm start, the sleeping islands' too (for a checkpoint).
    pub fn all_warm(&self) -> Vec<ContactRecord> {
        self.stepped().map(ImpulseModel::all_warm).unwrap_or_default()
    }

    /// Sets the warm start (a checkpoint's), and with it which contacts rested; the other
    /// engines keep none.
    pub fn set_warm_start(&mut self, warm: Vec<ContactRecord>) {
        if let Some(m) = self.stepped_mut() {
            m.set_warm_start(warm);
        }
    }

    /// What sleeping carries to the next step: each of the `n` particles' calm time (s) and
    /// island (−1: awake; everyone, with the engines that do not sleep).
    pub fn sleep_carry(&self, n: usize) -> (Vec<f64>, Vec<i64>) {
        match self.stepped() {
            Some(m) => m.sleep_carry(n),
            None => (vec![0.0; n], vec![-1; n]),
        }
    }

    /// Gives sleeping back what [`CollideStage::sleep_carry`] took, each contact's overlap
    /// measured at the particles' positions `x` (m) with their radii (m).
    pub fn restore_sleep(&mut self, calm: Vec<f64>, island: &[i64], radius: &[f64], x: &[f64]) {
        let (colliders, domain) = (&self.colliders, self.domain);
        let deepest = |i: usize, other: Partner| overlap_at(radius, colliders, &domain, x, i, other);
        if let Engine::Stepped(m) = &mut self.engine {
            m.restore_sleep(calm, island, deepest);
        }
    }

    /// The stepped engine's candidate list as built: the positions it was built at (m, 3 per
    /// particle) and its skin (m); `None` before a first build and with the other engines.
    pub fn list_carry(&self) -> Option<(Vec<f64>, f64)> {
        self.stepped()?.list_carry()
    }

    /// Builds the stepped engine's candidate list where [`CollideStage::list_carry`] says it
    /// was built (a checkpoint's), for particles of radii `radius` (m) in collision groups
    /// `group`; nothing to build with the other engines.
    pub fn restore_list(&mut self, built_at: &[f64], skin: f64, radius: &[f64], group: &[u8]) -> Result<(), Error> {
        let filter = Filter::of(group, &self.group_masks, self.params.self_collisions, &self.collider_masks);
        match &mut self.engine {
            Engine::Stepped(m) => m.restore_list(built_at, skin, radius, &self.colliders, &self.domain, filter),
            _ => Ok(()),
        }
    }

    /// The grid a placement check sorts the particles into: the stepped engine's (which
    /// rebuilds it at its next step), else one made for the check and dropped after it.
    pub(super) fn with_placement_grid<T>(&mut self, check: impl FnOnce(&mut Grid, &Self) -> T) -> T {
        let mut grid = match &mut self.engine {
            Engine::Stepped(m) => std::mem::take(&mut m.grid),
            _ => Grid::new(),
        };
        let out = check(&mut grid, self);
        if let Engine::Stepped(m) = &mut self.engine {
            m.grid = grid;
        }
        out
    }

    /// The event-driven state between calls, taken out (`None`: made afresh), and given back
    /// by [`CollideStage::keep_events`].
    pub(super) fn take_events(&mut self) -> Option<EventDriven> {
        match &mut self.engine {
            Engine::Events(e) => e.take(),
            _ => None,
        }
    }

    /// Keeps the event-driven state for the next call.
    pub(super) fn keep_events(&mut self, events: EventDriven) {
        if let Engine::Events(e) = &mut self.engine {
            *e = Some(events);
        }
    }

    /// The stepped engine's candidate list's skin, m (for the tests).
    #[cfg(test)]
    pub fn impulse_list_skin(&self) -> f64 {
        self.stepped().expect("the stepped engine").list.skin
    }

    /// Turns the impact search's check of each particle's sweep bound off (for the tests).
    #[cfg(test)]
    pub fn search_unbounded(&mut self) {
        self.stepped_mut().expect("the stepped engine").unbounded = true;
    }

    /// Bounds the stepped engine's candidate list to `entries` (for the tests).
    #[cfg(test)]
    pub fn set_impulse_list_limit(&mut self, entries: usize) {
        self.stepped_mut().expect("the stepped engine").list.entry_limit = Some(entries);
    }
}
