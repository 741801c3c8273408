//! Placements the collide stage cannot resolve, refused before the first step that meets them.
//!
//! Both contact models push overlapping particles apart along the line of centres: the
//! impulse model projects the overlap away at the end of the step, the force models
//! (spring–dashpot, Hertz) push with k_n·δ. That is sound while the overlap δ = r_i + r_j − d
//! is a fraction of the radii. It is not when the centre of one particle lies inside the other (d < max(r_i, r_j)):
//! the normal (x_i − x_j)/d is then the accident of where the centres fell (undefined for
//! coincident particles, d = 0), the push-out of a pile of them chains into a displacement of
//! metres in one step, and every particle of a cluster of N coincident ones touches every
//! other: N²/2 contacts (30,000 at one point asked for 2.7 GB before the allocation failed).
//! The same holds for a particle whose centre lies inside a sphere obstacle, behind a plane or
//! outside a box (or on the wrong side of a closed mesh): the push-out to the nearest surface is a jump across the obstacle (a
//! particle 1 m from the centre of a 100 m sphere went to z = 20.8 m in one step).
//!
//! So the world checks its particles' placement before the first step after anything that
//! places them: collisions turned on, a collider or periodic axes added, positions written
//! before the first step (all particles), particles added (the newcomers, against all). Later
//! writes are the user's own dynamics, and a checkpoint restores a run that was checked when
//! it started, so neither is checked. Such placements are refused with one error naming how
//! many there are and the deepest one. The check is bounded: it stops counting at
//! [`COUNT_LIMIT`], and reads each particle's neighbours once (the broad phase's grid).
//!
//! The rule depends on the contact model ([`Rule`]). Spring–dashpot contacts are soft: bodies
//! overlap deeply in a crowded box by design, and the spring pushes along the line of centres
//! whatever the depth, so only coincident particles (no line) are refused among particles.
//! Colliders are rigid for both models: a centre inside one is refused for both.
//!
//! A tolerance of [`TOLERANCE`] of the lengths involved keeps a centre placed exactly on a
//! wall (0.1 + 0.2 + 0.3 = 0.6000000000000001 against a wall at 0.6) or exactly at the
//! distance max(r_i, r_j) on the allowed side.

use crate::collide::broad_phase::Grid;
use crate::collide::{Collider, Domain, Side};
use crate::error::Error;
use crate::vec3;

/// Placements counted at most: beyond, the error says "at least" this many.
pub const COUNT_LIMIT: usize = 100_000;

/// Relative tolerance of the tests (of the distances and coordinates compared).
pub const TOLERANCE: f64 = 1e-9;

/// Which particle pairs a contact model cannot resolve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Rule {
    /// The impulse model: a centre inside the other particle, d < max(r_i, r_j).
    CentreInside,
    /// The force models: coincident centres, d ≤ TOLERANCE · (r_i + r_j).
    Coincident,
}

/// The particles to check: positions `x` (m, 3 per particle), radii `radius` (m); those from
/// index `from` on are checked against all; `user_of`: the user's index of each particle
/// when the world holds them in another order.
pub struct Placed<'a> {
    pub x: &'a [f64],
    pub radius: &'a [f64],
    pub from: usize,
    pub user_of: Option<&'a [u32]>,
    /// The collision groups' filter (`groups.rs`): pairs that do not collide may overlap, and
    /// a particle may lie behind a collider it does not collide with.
    pub filter: Option<crate::collide::groups::Filter<'a>>,
}

/// Overlaps a contact model resolves but that start the run with a push: particles
/// overlapping each other, or a collider's surface, by more than [`NOTICE`] of the lengths
/// involved. The collisions push them apart in the first steps (the impulse model removes
/// the overlap, the force models push with k_n δ), which sets them moving: worth a
/// warning, not a refusal.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Overlaps {
    /// How many pairs and particle–collider overlaps (at most [`COUNT_LIMIT`]).
    pub count: usize,
    /// The deepest, in words.
    pub deepest: Option<String>,
}

/// An overlap is noticed beyond this fraction of r_i + r_j (a pair) or of r (a collider).
pub const NOTICE: f64 = 0.01;

/// The deepest placement found, in words, and how deep (0 at the limit of what is allowed,
/// 1 when centres coincide or a centre is a body's depth inside).
struct Deepest {
    what: String,
    depth: f64,
}

/// What a check found so far: the placements refused (how many, the deepest) and the
/// overlaps noticed.
#[derive(Default)]
struct Found {
    count: usize,
    deepest: Option<Deepest>,
    shallow: Overlaps,
    shallowest_depth: f64,
}

impl Found {
    /// Notes a refused placement of `depth`, described by `what`: whether the count is full.
    fn note(&mut self, depth: f64, what: &dyn Fn() -> String) -> bool {
        self.count += 1;
        if self.deepest.as_ref().is_none_or(|d| depth > d.depth) {
            self.deepest = Some(Deepest { what: what(), depth });
        }
        self.count >= COUNT_LIMIT
    }

    /// Notices an accepted overlap of `depth`, described by `what`.
    fn notice(&mut self, depth: f64, what: &dyn Fn() -> String) {
        if self.shallow.count < COUNT_LIMIT {
            self.shallow.count += 1;
        }
        if depth > self.shallowest_depth {
            self.shallowest_depth = depth;
            self.shallow.deepest = Some(what());
        }
    }

    /// The check's answer: the error naming the deepest refused placement, else the overlaps.
    fn result(self) -> Result<Overlaps, Error> {
        match self.deepest {
            None => Ok(self.shallow),
            Some(d) => Err(Error::Placement {
                deepest: d.what,
                count: match self.count {
                    1 => "the one placement".to_string(),
                    c if c >= COUNT_LIMIT => format!("the deepest of at least {COUNT_LIMIT} placements"),
                    c => format!("the deepest of {c} placements"),
                },
            }),
        }
    }
}

impl Placed<'_> {
    /// The user's index of particle i.
    fn user(&self, i: usize) -> usize {
        self.user_of.map_or(i, |u| u[i] as usize)
    }
}

/// Checks the particles of `place` against each other (in `domain`, periodic images
/// included) by `rule` and against `colliders` (a centre inside a sphere obstacle, behind a
/// plane or outside a box).
/// Errors: [`Error::Placement`] naming the deepest and how many; what the broad phase's grid
/// refuses (non-finite values). Otherwise the overlaps it accepts but that will push
/// particles apart ([`Overlaps`]).
pub fn check(
    grid: &mut Grid,
    place: &Placed<'_>,
    domain: &Domain,
    colliders: &[Collider],
    rule: Rule,
) -> Result<Overlaps, Error> {
    // First what the neighbour list refuses at its build, whose words say more about such a
    // crowd than its deepest pair: radii too large for the periodic cell or the box.
    domain.check_radii(place.radius)?;
    for c in colliders {
        if let Collider::Box(b) = c {
            b.check_fill(domain.dim(), place.x, place.radius)?;
        }
    }
    let mut found = Found::default();
    let full = check_pairs(grid, place, domain, rule, &mut found)?;
    if !full {
        check_colliders(place, domain, colliders, &mut found);
    }
    found.result()
}

/// Particles against particles: a refused pair is also a touching one (d < r_i + r_j),
/// so the grid's partners are the candidates; a pair is looked at from its later index
/// among those checked (i ≥ from, and j < from or j < i). Whether the count of refused
/// placements is full.
fn check_pairs(grid: &mut Grid, place: &Placed<'_>, domain: &Domain, rule: Rule, found: &mut Found) -> Result<bool, Error> {
    let Placed {
        x, radius, from, filter, ..
    } = *place;
    let n = radius.len();
    if from < n && grid.prepare(x, radius, domain, 0.0)? {
        let mut out = Vec::new();
        for i in from..n {
            out.clear();
            grid.partners(i, x, radius, domain, 0.0, &mut out);
            for &j in &out {
                let j = j as usize;
                if (j >= from && j > i) || filter.is_some_and(|f| !f.pair(i, j)) {
                    continue;
                }
                let d = vec3::norm(domain.displacement(vec3::get(x, i), vec3::get(x, j)));
                let bound = match rule {
                    Rule::CentreInside => radius[i].max(radius[j]) * (1.0 - TOLERANCE),
                    Rule::Coincident => TOLERANCE * (radius[i] + radius[j]),
                };
                let refused = match rule {
                    Rule::CentreInside => d < bound,
                    Rule::Coincident => d <= bound,
                };
                let sum = radius[i] + radius[j];
                if !refused && d < sum * (1.0 - NOTICE) {
                    let (a, b) = if place.user(i) < place.user(j) { (i, j) } else { (j, i) };
                    found.notice((sum - d) / sum, &|| {
                        format!(
                            "particles {} and {} overlap by {} m (radii {} and {} m)",
                            place.user(a),
                            place.user(b),
                            short(sum - d),
                            radius[a],
                            radius[b]
                        )
                    });
                }
                if refused {
                    let (a, b) = if place.user(i) < place.user(j) { (i, j) } else { (j, i) };
                    let words = || {
                        format!(
                            "particles {} and {} are {} m apart (radii {} and {} m)",
                            place.user(a),
                            place.user(b),
                            short(d),
                            radius[a],
                            radius[b]
                        )
                    };
                    if found.note(1.0 - d / bound.max(f64::MIN_POSITIVE), &words) {
                        return Ok(true);
                    }
                }
            }
        }
    }
    Ok(false)
}

/// Particles against colliders: the centre on the wrong side of a surface (refused), or
/// the sphere into the surface (noticed).
fn check_colliders(place: &Placed<'_>, domain: &Domain, colliders: &[Collider], found: &mut Found) {
    let Placed {
        x, radius, from, filter, ..
    } = *place;
    let n = radius.len();
    for i in from..n {
        let p = vec3::get(x, i);
        let slack = TOLERANCE * (radius[i] + vec3::norm(p));
        for (k, c) in colliders.iter().enumerate() {
            if filter.is_some_and(|f| !f.wall(i, k)) {
                continue;
            }
            let inside = match c {
                Collider::Sphere(s) => {
                    let d = vec3::norm(vec3::sub(p, s.center()));
                    (d < s.radius() - slack).then(|| {
                        (
                            1.0 - d / s.radius(),
                            format!("{} m from its centre, radius {} m", short(d), s.radius()),
                        )
                    })
                }
                Collider::Plane(w) => {
                    let s = w.signed_distance(p);
                    (s < -slack).then(|| (1.0, format!("{} m behind it", short(-s))))
                }
                Collider::Box(b) => b
                    .walls()
                    .iter()
                    .map(|w| w.signed_distance(p))
                    .fold(None, |worst: Option<f64>, s| {
                        if s < -slack && worst.is_none_or(|v| s < v) {
                            Some(s)
                        } else {
                            worst
                        }
                    })
                    .map(|s| (1.0, format!("{} m outside it", short(-s)))),
                Collider::Mesh(m) => match m.side() {
                    Side::Both => None,
                    Side::Outside => m.contains(p).then(|| (1.0, "inside the closed mesh".to_string())),
                    Side::Inside => {
                        (!m.contains(p)).then(|| (1.0, "outside the closed mesh that contains the particles".to_string()))
                    }
                },
            };
            if inside.is_none() {
                // the centre on the right side, the sphere into the surface
                // (a box's walls along periodic axes do not exist)
                let periodic = domain.periodic_box().map(|b| b.axes());
                let exists = |n: [f64; 3]| match (c, periodic) {
                    (Collider::Box(_), Some(axes)) => !(0..3).any(|k| axes[k] && n[k] != 0.0),
                    _ => true,
                };
                let mut depth: f64 = 0.0;
                c.for_each_touch(p, radius[i], 0.0, |t| {
                    if exists(t.normal) {
                        depth = depth.max(t.overlap);
                    }
                });
                if depth > NOTICE * radius[i] {
                    let u = place.user(i);
                    found.notice(depth / radius[i], &|| {
                        format!(
                            "particle {u} overlaps colliders[{k}] by {} m (radius {} m)",
                            short(depth),
                            radius[i]
                        )
                    });
                }
            }
            if let Some((depth, words)) = inside {
                let u = place.user(i);
                if found.note(depth, &|| {
                    format!("particle {u}'s centre lies inside colliders[{k}] ({words})")
                }) {
                    return;
                }
            }
        }
    }
}

/// A distance for a message: 6 decimals.
fn short(d: f64) -> String {
    let rounded = (d * 1e6).round() / 1e6;
    if rounded == 0.0 {
        "0".to_string()
    } else {
        format!("{rounded}")
    }
}
