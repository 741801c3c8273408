//! The engine's limits and sentinels that modules on both sides of a dependency share: the
//! errors name them, the particles and the contacts check against them, the world steps by
//! them. A leaf: it uses no other module of the crate, so that each of those can use it
//! without a circle (`tests/test_no_import_circles.py`).

/// The largest length (m) or speed (m/s) the contacts' geometry accepts: it squares
/// distances and speeds, and (r_i + r_j + margin)² must stay far from overflow (1e308).
/// A particle's radius is refused above it; a state beyond it is a diverged step.
pub const GEOMETRY_LIMIT: f64 = 1e150;

/// In a `new_of_old` map of [`Particles::retain`](crate::particles::Particles::retain): the
/// particle was removed.
pub const GONE: u32 = u32::MAX;

/// The most adaptive sub-steps rk45 takes inside one step of dt: a step that needs more
/// has a dt far beyond what its forces allow (or forces rk45 cannot follow, such as
/// quadratic drag chattering about v = 0 over a step of 1e10 s, which took 24 s before
/// stopping at the solver's 10⁷), and is refused as diverged in milliseconds instead.
pub const RK45_SUBSTEPS: usize = 100_000;
