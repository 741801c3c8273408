//! The collide stage, stages 2–4 of a world step, and its kernels: detection (the grid and
//! the neighbour lists, continuous detection, the contacts of particle pairs and colliders)
//! and response (impulses, the end-of-step contact solve, or contact forces), on flat
//! particle arrays.
//!
//! What runs in a step of the impulse model, each function with its file (under `collide/`
//! unless under `world/`), in order; each stage writes buffers that the next one reads:
//!
//! ```text
//! World::step_once()                  world/mod.rs: one step
//! ├ World::place_moving_colliders()   world/collide.rs: moving colliders where the step ends
//! ├ World::integrate()                world/integrate.rs: stage 1, into x_next, v_next
//! └ World::collide()                  world/collide.rs: stages 2–4, with what they see of the
//!   │                                 world (CollideStage::impulse_and_setting(), stage.rs),
//!   │                                 then their books (CollideStage::book_step())
//!   └ ImpulseModel::step()            impulse/step.rs: wake_reached(): the islands asleep
//!                                     that an awake particle meets in the step wake; the
//!                                     others held; the step's parabolas,
//!                                     Paths::begin() (paths.rs); then the stage list
//!                                     ImpulseStage::ALL (impulse/mod.rs), each stage timed:
//!     list_stage()                    prepare() (impulse/list.rs): the neighbour list made
//!                                     to hold for the step's sweep, else rebuilt at x₀ by
//!                                     NeighbourList::update() (neighbour_list.rs) →
//!                                     Grid::prepare(), Grid::partners_from() (broad_phase.rs);
//!                                     the restitution threshold; next_meetings()
//!                                     (impulse/impacts.rs): a force-free world's meeting times
//!     impacts_stage()                 impacts() (impulse/impacts.rs), with ccd: every first
//!                                     impact, Surroundings::all_impacts() (events.rs), into the
//!                                     queue; then in time order: contact_at(),
//!                                     restitution_impulse() (response.rs), distribute()
//!                                     (impulse/end_of_step.rs), the two particles' next
//!                                     impacts, Surroundings::earliest()
//!     contacts_stage()                Paths::finish() (paths.rs): hit particles end on their
//!                                     last parabola; end_contacts() (impulse/end_of_step.rs):
//!                                     the contacts at the step's end, breadth first from the
//!                                     touched particles over the list: pair_contact()
//!                                     (narrow_phase.rs), then the colliders'
//!                                     Collider::for_each_touch(), Collider::contact()
//!                                     (colliders.rs)
//!     solve()                         impulse/end_of_step.rs: each contact's record
//!                                     read by Records::match_up() (records.rs), Target::new()
//!                                     (soft_step.rs), Islands::find_with() (islands.rs),
//!                                     soft_step::idle(), islands::solve() → soft_step(),
//!                                     island by island (at accuracy 'animation' with its
//!                                     shock stages: shock.rs levels(), order()); the
//!                                     step's records by Records::replace()
//!     apply_stage()                   distribute() (impulse/end_of_step.rs): each total onto
//!                                     both particles; energy_lost(): the energy the stages
//!                                     took
//!     settle_stage()                  settle() (impulse/end_of_step.rs): calm islands fall
//!                                     asleep; max_overlap(): the overlap left;
//!                                     Touches::end_step() (touch.rs): begin and end of touch,
//!                                     when recorded (the impacts were noted by Touches::hit())
//!     meetings_stage()                next_meetings() (impulse/impacts.rs): the next steps'
//!                                     meeting times
//! ```
//!
//! The order matters: the impacts change the paths the end-of-step contacts are found on,
//! and the end-of-step solve needs contacts that describe the positions the impacts left.
//! `impulse::ImpulseStage` names the stages, and each has its own timer in
//! `World.stage_times()` (the seed's detect, respond and distribute are sums of the same
//! laps). The deepest call of a step, to the impulse of one contact in the solve, is eight
//! calls below `World::step_once`: `collide` → `ImpulseModel::step` → `solve` →
//! `islands::solve` → `Local::solve` → `soft_step` → `passes` → `Row::visit` (the last two
//! inlined into the soft step, so that seven are frames at run time). Their cost follows what
//! the step touched: the touched particles are flags and a list (`marks.rs`), an island
//! whose contacts the soft step would leave alone is not solved (`soft_step::idle`), and in
//! a force-free world a parting contact that bore nothing is not kept into the next
//! step (`end_of_step.rs`).
//!
//! The force models (spring–dashpot, Hertz) act in stage 1 instead, as the last of the forces
//! (`contact_force/`):
//!
//! ```text
//! World::integrate()                   world/integrate.rs: contact_force() (world/forces.rs)
//!                                      → CollideStage::contact_force() (stage.rs): a call's view
//! ├ ContactForce::force_and_kick()     contact_force/verlet.rs: velocity Verlet's fused pass
//! └ ContactForce::accumulate()         contact_force/force.rs: the other methods → pair_pass()
//!   both: update_list() (contact_force/mod.rs) → NeighbourList::update() (a half list);
//!   pair_forces() (contact_force/pairs.rs): pair_contact(), normal_force_parts()
//!   (contact_force/law.rs) → spring_dashpot_force() (contact_force/spring_dashpot.rs),
//!   tangent_of() with friction; wall_contacts() (contact_force/contacts.rs) → Collider::contact()
//! ```
//!
//! With `CollisionParams::event_driven`, `World::advance` runs `World::advance_by_events`
//! (`world/event_driven.rs`, `event_driven/`) instead of these steps.
//!
//! The test oracles, O(N²) and plain references that the tests check these paths against
//! (`all_pairs`, `sphere_contacts`, `collider_contacts`, `SpringDashpotLaw`), are in
//! `oracles.rs`, compiled for the tests only; `tests/map.rs` checks that every function the two maps above
//! name is defined and called outside the tests.
//!
//! The contacts at a step's end are discrete: they see overlaps at the end of a step, and a
//! particle fast enough to cross another (or a wall) within one step is missed by them. The
//! continuous part is [`toi`] (with `paths.rs` and `events.rs`): the time of impact inside the
//! step, for sphere pairs and sphere obstacles in linear motion and for spheres against planes
//! under constant acceleration. The neighbour list finds the candidates for it: `prepare`
//! makes it hold for the distance each particle sweeps within the step (rebuilt with a skin
//! of four times the largest sweep, 2.5 where four would pass the list's memory bound, and
//! rebuilt tighter once the steps are four times slower than the skin was made for).
//!
//! Space is described by a [`Domain`]: 2D (circles in the xy-plane) or 3D, open or
//! periodic along any axis (the minimum image is used throughout).

/// The largest length (m) or speed (m/s) the contacts' geometry accepts (defined in
/// [`crate::limits`], which the particles' checks share; kept here under its old name).
pub use crate::limits::GEOMETRY_LIMIT;

pub mod books;
pub mod broad_phase;
pub mod colliders;
pub mod contact;
pub(crate) mod contact_force;
pub mod domain;
pub(crate) mod event_driven;
pub(crate) mod events;
pub mod groups;
pub(crate) mod impulse;
pub(crate) mod islands;
pub(crate) mod marks;
pub mod mesh;
pub(crate) mod morton;
pub mod motion;
pub mod narrow_phase;
pub(crate) mod neighbour_list;
#[cfg(test)]
pub(crate) mod oracles;
pub(crate) mod passes;
pub(crate) mod placement;
pub(crate) mod quiet;
pub(crate) mod records;
pub mod response;
mod roots;
pub(crate) mod shock;
pub(crate) mod sleep;
pub(crate) mod soft_step;
pub mod spin;
pub(crate) mod stage;
pub mod surface;
pub mod toi;
pub mod touch;
pub mod velocities;

mod grid_level;
mod paths;

pub use broad_phase::Grid;
pub use colliders::{BoxContainer, Collider, Plane, SphereObstacle, Surface, Touch};
pub use contact::{Contact, ContactReport, Partner};
pub use contact_force::spring_dashpot::{damping_ratio, dashpot_coefficient, spring_dashpot_force};
pub use contact_force::sub_models::{SubModel, SubModelKind, SUB_MODELS};
pub use domain::{Domain, Periodic};
pub use groups::{GroupMasks, GROUPS};
pub use mesh::{Side, TriangleMesh};
pub use motion::{Motion, Pose, SurfaceVelocity};
pub use narrow_phase::pair_contact;
pub use records::ContactRecord;
pub use response::{restitution_impulse, Impulse, Material, MaterialTable};
pub use toi::{toi_plane, toi_sphere_obstacle, toi_spheres};
pub use touch::TouchEvent;
