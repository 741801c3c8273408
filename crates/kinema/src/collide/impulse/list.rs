//! The impulse model's candidate list over a step (`ImpulseStage::List`): made to hold for
//! the step's sweep at its start, rebuilt inside it when an impact's new path could reach
//! beyond it, with a skin sized by the step's sweeps; its build as a checkpoint keeps it;
//! the check that refuses a step whose sweeps cross the scene too many times.

use rayon::prelude::*;

use super::{ImpulseModel, StageSetting};
use crate::collide::events::{swept_reach, Paths};
use crate::collide::groups::Filter;
use crate::collide::neighbour_list::{collider_scale, ListBuild, CHUNK, SKIN_PER_RADIUS};
use crate::collide::{Collider, Domain};
use crate::error::{Divergence, Error};
use crate::vec3;

impl ImpulseModel {
    /// Makes the neighbour list hold for the whole step's sweep (rebuilt at x0 if not) and
    /// returns the restitution threshold (m/s), the largest swept displacement of any particle
    /// from the list's build positions (m) and the largest speed change the forces gave a
    /// particle in the step (m/s).
    ///
    /// One pass over the particles: each one's swept displacement max(|x0 − b|, |x1 − b|) +
    /// ⅛ |a| h² (b its build position) and the two largest of them; its velocity change
    /// |v1 − v0| for the automatic threshold (twice the largest: a body resting under gravity
    /// approaches at g h each step).
    ///
    /// With `quiet` (a force-free step with valid meeting times) the list's hold comes from the
    /// meetings' speed bound instead, with no pass (`collide/quiet.rs`), and the automatic
    /// threshold and speed change are 0 (no force changes a velocity). Sets `rebuilt` when it
    /// rebuilds.
    pub(super) fn prepare(
        &mut self,
        set: &StageSetting<'_>,
        paths: &Paths<'_>,
        x1: &[f64],
        v1: &[f64],
        h: f64,
        quiet: bool,
    ) -> Result<(f64, f64, f64), Error> {
        let reach = self.meetings.reach_after(h);
        let (x0, v0) = (paths.x0, paths.v0);
        // (the per-particle bounds are made by the sweep below; a quiet step has the one)
        self.bounded = false;
        if quiet && self.list.built_at.len() == x0.len() && 2.0 * reach < self.list.allowance {
            return Ok((set.restitution_threshold.unwrap_or(0.0), reach, 0.0));
        }
        let domain = *set.domain;
        // (each particle's swept displacement is also its bound for the impact search,
        // `events::SweepBound`, written into `bounds`)
        let sweep = |built: &[f64], accel: &[f64], bounds: &mut [f64]| {
            x0.par_chunks(3 * CHUNK)
                .zip(x1.par_chunks(3 * CHUNK))
                .zip(built.par_chunks(3 * CHUNK))
                .zip(bounds.par_chunks_mut(CHUNK))
                .enumerate()
                .map(|(c, (((x0, x1), b), bounds))| {
                    let mut top = Sweep::default();
                    for l in 0..x0.len() / 3 {
                        let q = c * CHUNK + l;
                        let bq = vec3::get(b, l);
                        let d0 = domain.displacement(vec3::get(x0, l), bq);
                        let d1 = domain.displacement(vec3::get(x1, l), bq);
                        let a = vec3::get(accel, q);
                        let bulge2 = vec3::dot(a, a);
                        let bulge = if bulge2 > 0.0 { 0.125 * bulge2.sqrt() * h * h } else { 0.0 };
                        let d = vec3::dot(d0, d0).max(vec3::dot(d1, d1)).sqrt() + bulge;
                        bounds[l] = d;
                        let step = domain.displacement(vec3::get(x1, l), vec3::get(x0, l));
                        let w = vec3::sub(vec3::get(v1, q), vec3::get(v0, q));
                        top = top.with(Sweep {
                            first: d,
                            second: 0.0,
                            kick2: vec3::dot(w, w),
                            nan: d.is_nan(),
                            step: vec3::norm(step) + bulge,
                        });
                    }
                    top
                })
                .reduce(Sweep::default, Sweep::with)
        };
        // (with `quiet` the bound said the list may not hold: rebuilt without the check, which
        // the actual displacements would pass only for a few more steps)
        let fresh = self.list.built_at.len() == x0.len() && !quiet;
        let mut bounds = std::mem::take(&mut self.bounds);
        bounds.resize(x0.len() / 3, 0.0);
        let mut top = if fresh {
            sweep(&self.list.built_at, paths.accel, &mut bounds)
        } else {
            Sweep {
                first: f64::INFINITY,
                ..Sweep::default()
            }
        };
        let holds = top.first + top.second < self.list.allowance;
        // A list built for a fast step (its skin four of that step's largest sweeps) is
        // rebuilt once the steps are much slower, though it still holds: a pile that came to
        // rest with the skin of its fall kept every particle's candidates within that skin
        // (at 60 Hz, the whole of the demo's box), and every impact swept them all again.
        let loose = self.list.skin > LOOSE * self.base_skin.max(4.0 * top.step);
        if top.nan || !holds || loose {
            // Rebuild at x0, with a skin of the base (0.6 mean radius) or four of this step's
            // largest sweeps, whichever is more: the list then lasts at least two such steps.
            let accel = paths.accel;
            let (largest_move, fastest) = (0..set.radius.len())
                .into_par_iter()
                .with_min_len(CHUNK)
                .map(|q| {
                    let a = vec3::norm(vec3::get(accel, q));
                    let d = vec3::norm(domain.displacement(vec3::get(x1, q), vec3::get(x0, q))) + 0.125 * a * h * h;
                    (d, q)
                })
                .reduce(|| (0.0, 0), |a, b| if b.0 > a.0 || (b.0 == a.0 && b.1 < a.1) { b } else { a });
            check_travel(set.colliders, set.radius, x0, largest_move, fastest, h)?;
            self.build_list(set, x0, largest_move)?;
            self.rebuilt = true;
            top = sweep(&self.list.built_at, paths.accel, &mut bounds);
            if top.nan || !top.first.is_finite() {
                // non-finite positions: the list's build named them already; a NaN velocity
                // change is caught by the world
                top.first = f64::INFINITY;
            }
        }
        self.bounds = bounds;
        self.bounded = true;
        let kick = top.kick2.sqrt();
        let threshold = set.restitution_threshold.unwrap_or(2.0 * kick);
        Ok((threshold, top.first, kick))
    }

    /// Rebuilds the list at the particles' positions at time t (their references moved there)
    /// for the rest of the step; returns the largest swept displacement from there, m.
    pub(super) fn rebuild_at(&mut self, set: &StageSetting<'_>, paths: &mut Paths<'_>, t: f64, h: f64) -> Result<f64, Error> {
        let n = set.radius.len();
        let mut x = vec![0.0; 3 * n];
        let (mut largest, mut fastest) = (0.0_f64, 0);
        // (each particle's sweep from x is its bound for the rest of the step)
        self.bounds.resize(n, 0.0);
        for q in 0..n {
            paths.advance(q, t);
            x[3 * q..3 * q + 3].copy_from_slice(&paths.x_ref(q));
            let reach = swept_reach(paths, q, t, h, vec3::get(&x, q), set.domain);
            self.bounds[q] = reach;
            if reach > largest {
                (largest, fastest) = (reach, q);
            }
        }
        self.bounded = true;
        check_travel(set.colliders, set.radius, &x, largest, fastest, h - t)?;
        self.build_list(set, &x, largest)?;
        Ok(largest)
    }

    /// Builds the candidate list at `x` for paths that sweep at most `largest` (m) from there
    /// in the step: with a skin of the base (0.6 mean radius) or four of `largest`, whichever
    /// is more, so that it lasts at least two such steps. Where that list would pass its
    /// memory bound (a whole lattice falling fast at 60 Hz: each ball's candidates within
    /// four of its 10 cm sweep), one with a skin of [`LEAST_SWEEPS`] of `largest`, which holds
    /// for this step and is built again at the next.
    fn build_list(&mut self, set: &StageSetting<'_>, x: &[f64], largest: f64) -> Result<(), Error> {
        let (radius, colliders, domain, filter) = (set.radius, set.colliders, set.domain, set.filter);
        self.base_skin = base_skin(radius);
        match self.build_with_skin(x, self.base_skin.max(4.0 * largest), radius, colliders, domain, filter) {
            Err(Error::OutOfMemory { .. }) if LEAST_SWEEPS * largest > self.base_skin => {
                self.build_with_skin(x, LEAST_SWEEPS * largest, radius, colliders, domain, filter)
            }
            done => done,
        }
    }

    /// Builds the candidate list at `x` (m, 3 per particle) with `skin` (m), of the pairs that
    /// collide (`filter`: the collision groups, `None` when all do).
    fn build_with_skin(
        &mut self,
        x: &[f64],
        skin: f64,
        radius: &[f64],
        colliders: &[Collider],
        domain: &Domain,
        filter: Option<Filter<'_>>,
    ) -> Result<(), Error> {
        let build = ListBuild {
            skin,
            reach: 0.0,
            collider_scale: colliders.iter().map(collider_scale).fold(0.0, f64::max),
        };
        self.list.built_at.clear();
        self.list.verified = None;
        self.list
            .update(&mut self.grid, x, radius, colliders, domain, filter, || build)
    }

    /// The candidate list's build as a checkpoint keeps it: the positions it was built at
    /// (m, 3 per particle) and its skin (m); `None` before a first build.
    ///
    /// The list is a cache, but when it is built decides two things of a step's bits: a
    /// rebuild inside a step moves every path's reference to that time, and the impacts are
    /// predicted again from there. A resumed run that built its list afresh went on to other
    /// bits than the run it continues (a heap of 18 balls, resumed every 25 steps: 3 of 19
    /// resumes differed within 300 steps); built where the written run had built it, the
    /// list holds as long and is rebuilt at the same steps.
    pub fn list_carry(&self) -> Option<(Vec<f64>, f64)> {
        (!self.list.built_at.is_empty()).then(|| (self.list.built_at.clone(), self.list.skin))
    }

    /// Builds the list at `built_at` (m, 3 per particle) with `skin` (m), as
    /// [`ImpulseModel::list_carry`] gave them: the list the written run had.
    pub fn restore_list(
        &mut self,
        built_at: &[f64],
        skin: f64,
        radius: &[f64],
        colliders: &[Collider],
        domain: &Domain,
        filter: Option<Filter<'_>>,
    ) -> Result<(), Error> {
        self.base_skin = base_skin(radius);
        self.build_with_skin(built_at, skin, radius, colliders, domain, filter)
    }
}

/// The least skin of a list of particles of these radii, m: [`SKIN_PER_RADIUS`] of the mean.
fn base_skin(radius: &[f64]) -> f64 {
    SKIN_PER_RADIUS * radius.iter().sum::<f64>() / radius.len().max(1) as f64
}

/// How many times the scene's extent a particle may travel in the rest of a step: more would
/// take more impacts than the step's cap (1000 a particle) to follow, each predicted against a
/// candidate list that holds every particle the sweep reaches.
pub(crate) const TRAVEL_LIMIT: f64 = 1000.0;

/// Stops a step (a divergence, [`Divergence::TooFast`]) in which particle `fastest` travels
/// `largest` (m) in the `rest` of the step (s), more than [`TRAVEL_LIMIT`] times the extent of the scene: the box around the
/// particles at `x` (m) and the box colliders (their finite sides). Such speeds (2.3e16 m/s in
/// a 10 m box: 5 s a step for 1,000 particles) bounce to the cap of continuous detection in
/// every step while resolving nothing. An extent of 0 (one particle, no box) has nothing to
/// bounce between.
pub(crate) fn check_travel(
    colliders: &[Collider],
    radius: &[f64],
    x: &[f64],
    largest: f64,
    fastest: usize,
    rest: f64,
) -> Result<(), Error> {
    if !(largest > 0.0) {
        return Ok(());
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    let mut grow = |p: [f64; 3]| {
        for k in 0..3 {
            if p[k].is_finite() {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    };
    x.chunks_exact(3).for_each(|p| grow([p[0], p[1], p[2]]));
    for c in colliders {
        if let Collider::Box(b) = c {
            grow(b.lo());
            grow(b.hi());
        }
    }
    let extent = (0..3)
        .map(|k| if hi[k] >= lo[k] { hi[k] - lo[k] } else { 0.0 })
        .fold(0.0, f64::max);
    let r_max = radius.iter().copied().fold(0.0, f64::max);
    let scale = extent + 2.0 * r_max;
    if scale > 0.0 && largest > TRAVEL_LIMIT * scale {
        // (the world fills in the step, the time and the advice: World::collide)
        return Err(Error::Diverged {
            step: 0,
            time: 0.0,
            particle: Some(fastest),
            dt: rest,
            reason: Divergence::TooFast {
                travel: largest,
                extent: scale,
                limit: TRAVEL_LIMIT,
            },
            advised_dt: None,
            verlet_only: false,
        });
    }
    Ok(())
}

/// Combines (largest, second largest, largest velocity change, NaN met) of two parts.
/// What `prepare` learns of the step's paths in one pass: the two largest displacements
/// from the list's build positions over the step (m), the largest velocity change squared
/// (m²/s²), whether a displacement is NaN, and the largest displacement over the step (m).
#[derive(Debug, Clone, Copy, Default)]
struct Sweep {
    first: f64,
    second: f64,
    kick2: f64,
    nan: bool,
    step: f64,
}

impl Sweep {
    /// Both passes' figures together.
    fn with(self, b: Sweep) -> Sweep {
        Sweep {
            first: self.first.max(b.first),
            second: self.first.min(b.first).max(self.second).max(b.second),
            kick2: self.kick2.max(b.kick2),
            nan: self.nan || b.nan,
            step: self.step.max(b.step),
        }
    }
}

/// The least skin of a candidate list, in sweeps of the step it is built for: the two
/// particles that sweep farthest may together sweep two (the list must hold for them), and
/// the rest is room for the rounding allowance and the list's own check.
const LEAST_SWEEPS: f64 = 2.5;

/// A list whose skin is more than this many times what a rebuild now would choose is rebuilt
/// (a factor that leaves room for the steps' speeds to vary without a rebuild each step).
const LOOSE: f64 = 4.0;
