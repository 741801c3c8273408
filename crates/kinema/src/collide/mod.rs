//! The collide stage, stages 2–4 of a world step, and its kernels: detection (broad phase →
//! narrow phase, colliders) and response (impulses, the end-of-step contact solve, or
//! penalty forces), on flat particle arrays.
//!
//! `World::collide` (`world/collide.rs`) calls `stage::CollideStage::run` (`stage.rs`: the
//! settings, colliders, domain, materials and books), which runs the impulse model over the
//! step (`impulse/`: `impulse::ImpulseModel` and its buffers). Its stages, in order, each
//! writing a buffer that the next one reads:
//!
//! ```text
//!   positions ──broad_phase::Grid::find_pairs──▶ pairs (i < j), sorted
//!   pairs ──narrow_phase::sphere_contacts──▶ contacts (normal, overlap, u_n)
//!     + colliders::collider_contacts (planes, boxes, sphere obstacles) appended
//!   impacts inside the step ──response::restitution_impulse──▶ velocities: Newton's
//!                                   restitution u_n⁺ = −e u_n⁻ and Coulomb friction
//!   contacts at the step's end ──soft_step (by islands)──▶ velocities and positions:
//!                                   resting contacts held, overlap removed
//!   islands at rest ──sleep──▶ asleep: frozen, skipped by the impact search and the solve,
//!                                   until an impact or an awake particle's contact wakes them
//! ```
//!
//! The order matters: the end-of-step solve needs contacts that describe the current
//! positions.
//!
//! The penalty model replaces the response stages: [`penalty::PenaltyLaw::accumulate`] turns
//! the contacts into spring–dashpot forces that the integrator applies within the step.
//!
//! The broad and narrow phases are discrete: they see overlaps at the end of a step, and a
//! particle fast enough to cross another (or a wall) within one step is missed by them. The
//! continuous part is [`toi`]: the time of impact inside the step, for sphere pairs and
//! sphere obstacles in linear motion and for spheres against planes under constant
//! acceleration. The broad phase finds the candidates for it when given a `margin` of the
//! distance two particles can close within the step (h times the largest relative speed,
//! 2 h |v|_max).
//!
//! Space is described by a [`Domain`]: 2D (circles in the xy-plane) or 3D, open or
//! periodic along any axis (the minimum image is used throughout).

/// The largest length (m) or speed (m/s) the contacts' geometry accepts: it squares
/// distances and speeds, and (r_i + r_j + margin)² must stay far from overflow (1e308).
/// A particle's radius is refused above it; a state beyond it is a diverged step.
pub const GEOMETRY_LIMIT: f64 = 1e150;

pub mod books;
pub mod broad_phase;
pub mod colliders;
pub mod contact;
pub(crate) mod contact_force;
pub mod domain;
pub(crate) mod event_driven;
pub(crate) mod events;
pub(crate) mod impulse;
pub(crate) mod islands;
pub mod mesh;
pub(crate) mod morton;
pub mod motion;
pub mod narrow_phase;
pub(crate) mod neighbour_list;
pub mod penalty;
pub(crate) mod placement;
pub mod response;
mod roots;
pub(crate) mod sleep;
pub(crate) mod soft_step;
pub mod spin;
pub(crate) mod stage;
pub mod surface;
pub(crate) mod sweeps;
pub mod toi;
pub(crate) mod wake;

mod grid_level;
mod paths;

pub use broad_phase::{all_pairs, Grid, Pair};
pub use colliders::{collider_contacts, BoxContainer, Collider, Plane, SphereObstacle, Surface, Touch};
pub use contact::{Contact, Partner};
pub use domain::{Domain, Periodic};
pub use mesh::{Side, TriangleMesh};
pub use motion::{Motion, Pose, SurfaceVelocity};
pub use narrow_phase::{pair_contact, sphere_contacts};
pub use penalty::{damping_ratio, dashpot_coefficient, restitution_of_damping, spring_dashpot_force, PenaltyLaw};
pub use response::{restitution_impulse, Impulse, Material, MaterialTable};
pub use toi::{toi_plane, toi_sphere_obstacle, toi_spheres};
