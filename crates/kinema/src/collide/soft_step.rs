//! The end-of-step contact solve of the impulse model: Box2D v3's soft step (`solver.c`,
//! `contact_solver.c`), written for a step whose forces were already integrated.
//!
//! Stage 1 has moved every particle from (x₀, v₀) to (x₁, v₁) by the world's method. A
//! contact's impulse P, taken as acting at the step's start, changes the end velocity by
//! Δv = w P and the end position by h Δv (the velocity it leaves acts over the whole
//! step). Written for one contact, with g₁ its gap at x₁ (< 0: overlap), u₁ its normal
//! velocity at v₁ and u its normal velocity after the solve,
//!
//! ```text
//!   g = g₁ + h (u − u₁)                                (the gap the solve leaves)
//! ```
//!
//! so every position condition is a velocity target, and one projected Gauss–Seidel over
//! velocities keeps positions too. The stages, in order (Box2D's `b2SolverStage`):
//!
//! ```text
//!   warm start   last step's totals of the same contacts, applied
//!   solve        g ≥ 0 for a pair apart at the step's start (speculative: they may close
//!                the gap, not pass it); g ≥ g₀ for one that overlapped by −g₀ within the
//!                slop, and a part β of the excess removed per step beyond it;
//!                tangential velocity u_t → u₁t − d_t/h (no sliding over the step: d_t is
//!                the tangential displacement the step made), |t| ≤ μ λ (Coulomb)
//!   shock        at the `animation` accuracy only (`collide/shock.rs`): the solve's normal
//!                targets again, level by level bottom up, each particle pushed off its
//!                supports, which are held still
//!   integrate    x += h Δv of the solve (positions follow the solve, not the later stages)
//!   relax        u ≥ 0 where the solve left them touching, u ≥ −g/h across a gap g; u_t → 0:
//!                the velocity the solve needed to move positions is not kept (Box2D's relax)
//!                (and at the `animation` accuracy its shock stage, as after the solve)
//!   restitution  u⁺ = −e u⁻ for each contact that bears load and approached faster than
//!                the threshold at the step's start (Newton's law, Box2D's restitution stage)
//! ```
//!
//! All stages work on the same accumulated totals (λ ≥ 0 along n, |t| ≤ μ λ), so an impulse
//! that the relax finds too large shrinks again. A body resting under any method ends each
//! step where it started, at rest: its gap is closed exactly and its velocity relaxed to 0.
//!
//! With spin (`collide/spin.rs`) the passes update each particle's velocity and angular
//! velocity (6 values), the tangential targets are the contact point's velocity, and the
//! tangential effective mass is 1/w_t. The sticking target is the same: stage 1 does not
//! turn a particle, so the contact point's slip over the step with the solve's impulse taken
//! at its start is d_t + h (u_c − u₁t), zero for u_c = u₁t − d_t/h (a ball rolling on a floor
//! has u₁t = d_t/h and keeps rolling; the relax then holds its contact point still).
//!
//! Rolling resistance (`rolling_friction` μ_r > 0) adds a
//! third total to each contact: an angular impulse M, +M on i and −M on j, that brings the
//! relative turning ω_i − ω_j to 0 in the solve and relax stages, within the cone
//! |M| ≤ μ_r R* λ (R* = r_i r_j / (r_i + r_j), r_i against a collider): across n it is
//! rolling resistance, the torque μ_r R* F_n of LAMMPS's `rolling sds` at its slider's limit;
//! along n twisting resistance, LAMMPS's `twisting sds` with the same coefficient. Without
//! the twist, a pile's grains kept spinning in place about their contact normals, nothing
//! resisting them, and the pile never slept. Its effective mass is 1/(k_i + k_j) (k = 1/I).

use super::contact::Contact;
use super::passes::{passes, Ends, PassGroup};
use super::response::MaterialTable;
use super::shock::{levels, order, Held, ShockOrder, SUPPORT_COSINE};
use super::spin::Rotation;
use crate::error::Error;
use crate::vec3;
use row::Row;

mod row;

/// What the stage prepared for one contact (m, m/s, 3-vectors ⊥ n).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Target {
    /// The gap g₁ at the integrated positions x₁, m (< 0: overlap).
    pub gap: f64,
    /// The normal velocity u₁ at v₁, m/s.
    pub u_n: f64,
    /// The least normal velocity of the solve stage, m/s.
    pub solve_n: f64,
    /// The tangential velocity of sticking over the step, m/s.
    pub stick_t: [f64; 3],
    /// Newton's target −e u⁻ > 0 when the contact approached faster than the threshold at
    /// the step's start (`None`: no bounce).
    pub bounce: Option<f64>,
    /// The overlap the solve leaves, m (≥ 0; 0 for a contact that ends touching or apart):
    /// where its impulse acts, for the lever arms of spin (`collide/spin.rs`).
    pub rest: f64,
}

/// Overlap removed per step by the solve stage (Baumgarte's β: 0.2, as Box2D v2 and Chipmunk
/// use; an overlap only remains where a solve stopped short, and this takes it out gently).
pub(crate) const OVERLAP_RECOVERY: f64 = 0.2;

impl Target {
    /// The targets of a contact whose gap was g₀ at the step's start (m), whose relative
    /// displacement over the step is d without the solve (m), and whose relative velocity at
    /// the step's end is u₁ (m/s), along `normal`, at step h (s); `bounce`: Newton's target if
    /// any.
    ///
    /// Without the solve the step ends at the gap g₁ = g₀ + d·n. The solve lets it end at a gap
    /// of at least 0 if they were apart at the start; at g₀ if they overlapped by at most the
    /// `slop` (m: Box2D's linear slop, an overlap left in place so that a rounding of the
    /// solve does not push a pile apart and back every step); and at g₀ + β (−slop − g₀)
    /// if deeper (β = [`OVERLAP_RECOVERY`] of the excess removed per step). What the step
    /// itself would close is never allowed, so a body resting under a force ends every step
    /// where it began. With g = g₁ + h (u − u₁·n), the target is
    /// u ≥ u₁·n + (g_target − g₁)/h. Sticking (no sliding over the step) is a tangential
    /// velocity of u₁t − d_t/h.
    pub fn new(start: f64, slop: f64, d: [f64; 3], u1: [f64; 3], normal: [f64; 3], h: f64, bounce: Option<f64>) -> Target {
        let (d_n, u_n) = (vec3::dot(d, normal), vec3::dot(u1, normal));
        let gap = start + d_n;
        let least = if start >= 0.0 {
            0.0
        } else if start >= -slop {
            start
        } else {
            start + OVERLAP_RECOVERY * (-slop - start)
        };
        let tangential = |a: [f64; 3], a_n: f64| vec3::sub(a, vec3::scale(a_n, normal));
        Target {
            gap,
            u_n,
            solve_n: u_n + (least - gap) / h,
            stick_t: vec3::sub(tangential(u1, u_n), vec3::scale(1.0 / h, tangential(d, d_n))),
            bounce,
            rest: (-least).max(0.0),
        }
    }
}

/// The speculative margin: pairs closer than r_i + r_j by less than this fraction of
/// r_i + r_j (and particles this fraction of their diameter from a collider) are contacts at
/// the end of a step, touching or not (Box2D's speculative distance). A resting contact then
/// stays a contact from step to step, whatever rounding leaves of its gap, and the solve
/// lets such a pair close its gap but not pass it.
pub(crate) const SPECULATIVE: f64 = 0.05;

/// The overlap a contact may keep, as a fraction of r_i + r_j (of the diameter against a
/// collider): 0.2 % of r for equal spheres. Box2D's linear slop, relative to the size.
pub(crate) const SLOP: f64 = 1e-3;

/// Settings of [`soft_step`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SoftParams {
    /// The step, s.
    pub h: f64,
    /// A pass whose largest velocity change is at most this has converged, m/s.
    pub tolerance: f64,
    /// Most passes of the solve stage.
    pub solve_passes: usize,
    /// Most passes of the relax and of the restitution stages.
    pub relax_passes: usize,
}

/// What [`soft_step`] did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct SoftStats {
    /// Passes of the solve stage, and whether its last changed nothing beyond the tolerance.
    pub passes: usize,
    pub converged: bool,
    /// Passes of the relax stage, and of the restitution stage.
    pub relax_passes: usize,
    pub restitution_passes: usize,
    /// Contacts that bear a nonzero impulse at the end.
    pub active: usize,
    /// Contacts that bounced by Newton's law.
    pub bounced: usize,
}

/// What [`soft_step`] holds: the contacts (indices into the arrays it is given), their
/// targets, the particles' inverse masses (1/kg, 0 for pinned), the materials and, with
/// spin, the particles' inverse inertias and radii.
#[derive(Clone, Copy)]
pub(crate) struct SoftContacts<'a> {
    pub contacts: &'a [Contact],
    pub targets: &'a [Target],
    pub inv_mass: &'a [f64],
    pub materials: &'a MaterialTable<'a>,
    pub rotation: Option<Rotation<'a>>,
    /// Rolling resistance μ_r (≥ 0; with spin).
    pub rolling: f64,
    /// With shock propagation (`collide/shock.rs`): each particle's acceleration from the
    /// forces (m/s², 3 per particle), which tells its supports.
    pub shock: Option<&'a [f64]>,
}

/// The soft step's stages (see the module's doc) on velocities `v` (N per particle: the
/// velocity, then with spin, N = 6, the angular velocity) and positions `x` (3 per particle),
/// updated in place, with each pass visiting the contacts group by group (as
/// `collide/passes.rs` describes: the same result on any number of threads).
///
/// `solved`: each contact's starting total on entry (the last step's solve, for the warm
/// start; zeros if none), its solve stage's total on return (the next step's warm start).
/// `totals`: each contact's final total impulse on i, N·s (−total on a partner particle);
/// `rolls`: with rolling resistance, its final angular impulse on i, N·m·s (−on a partner).
/// `kicks`: with shock propagation, the velocity change of the shock stages (N per
/// particle), which no total holds; left empty without.
#[allow(clippy::too_many_arguments)]
pub(crate) fn soft_step<const N: usize>(
    held: SoftContacts<'_>,
    params: &SoftParams,
    v: &mut [f64],
    x: &mut [f64],
    solved: &mut [[f64; 3]],
    totals: &mut Vec<[f64; 3]>,
    rolls: &mut Vec<[f64; 3]>,
    kicks: &mut Vec<f64>,
    groups: &[PassGroup],
) -> Result<SoftStats, Error> {
    let SoftContacts {
        contacts,
        targets,
        inv_mass,
        materials,
        rotation,
        rolling,
        shock,
    } = held;
    debug_assert!(N == 3 || (N == 6 && rotation.is_some()));
    let h = params.h;
    let ends: Vec<Option<Ends>> = contacts.iter().map(|c| Ends::of(c, inv_mass)).collect();
    let rows: Vec<Row> = contacts
        .iter()
        .zip(targets)
        .map(|(c, target)| Row::new(c, target, inv_mass, rotation, rolling, materials.pair(c).friction()))
        .collect();
    let before = v.to_vec();

    // Warm start: each starting total projected onto λ ≥ 0 and the cone, then applied.
    let mut acc = warm_start::<N>(&rows, &ends, solved, v);
    let mut stats = SoftStats::default();

    // Solve: the position targets, as velocities.
    let done = passes::<N, _>(
        groups,
        &ends,
        v,
        &mut acc,
        params.solve_passes,
        params.tolerance,
        |k, a, vi, vj| rows[k].visit(vi, vj, a, targets[k].solve_n, Some(targets[k].stick_t)),
    );
    stats.passes = done.passes;
    stats.converged = done.converged;
    store_solved(&rows, &acc, solved);
    // Shock: the solve's targets again, level by level bottom up, the level below held still.
    kicks.clear();
    let shocks = shock.map(|accel| {
        kicks.resize(v.len(), 0.0);
        Shocks::new(contacts, targets, &rows, &ends, &acc, accel, v.len() / N)
    });
    if let Some(s) = &shocks {
        s.run::<N>(v, kicks, params, |k| targets[k].solve_n);
    }

    // Integrate: the positions follow the solve's velocity change over the whole step.
    follow_velocities::<N>(x, v, &before, inv_mass, h);

    // Relax: velocity targets on the gaps the solve left.
    let relax_n = relax_targets::<N>(&rows, &ends, targets, v, h);
    let relaxed = passes::<N, _>(
        groups,
        &ends,
        v,
        &mut acc,
        params.relax_passes,
        params.tolerance,
        |k, a, vi, vj| rows[k].visit(vi, vj, a, relax_n[k], Some([0.0; 3])),
    );
    stats.relax_passes = relaxed.passes;
    if let Some(s) = &shocks {
        s.run::<N>(v, kicks, params, |k| relax_n[k]);
    }

    // Restitution: Newton's law on the contacts that bear load and came in fast.
    let bouncing = bouncing(targets, &acc);
    stats.bounced = bouncing.iter().flatten().count();
    if stats.bounced > 0 {
        let bounced = passes::<N, _>(
            groups,
            &ends,
            v,
            &mut acc,
            params.relax_passes,
            params.tolerance,
            |k, a, vi, vj| match bouncing[k] {
                Some(b) => rows[k].visit(vi, vj, a, b, None),
                None => 0.0,
            },
        );
        stats.restitution_passes = bounced.passes;
    }

    final_totals::<N>(&rows, &acc, &ends, rolling, totals, rolls);
    stats.active = totals.iter().filter(|p| **p != [0.0; 3]).count();
    Ok(stats)
}

/// Each contact's accumulated (λ, tangential, rolling) impulses after the warm start: its
/// starting total `solved` projected onto λ ≥ 0 and the cone, then applied to `v`.
#[inline]
fn warm_start<const N: usize>(rows: &[Row], ends: &[Option<Ends>], solved: &[[f64; 3]], v: &mut [f64]) -> Vec<Accumulated> {
    let mut acc: Vec<Accumulated> = vec![(0.0, [0.0; 3], [0.0; 3]); rows.len()];
    for (k, (r, e)) in rows.iter().zip(ends).enumerate() {
        let start = solved[k];
        let Some(e) = e else { continue };
        if start == [0.0; 3] || vec3::first_non_finite(&start).is_some() {
            continue;
        }
        let lambda = vec3::dot(start, r.n).max(0.0);
        let t = r.clamp(vec3::sub(start, vec3::scale(vec3::dot(start, r.n), r.n)), lambda);
        acc[k] = (lambda, t, [0.0; 3]);
        let (mut vi, mut vj) = e.load::<N>(v);
        r.apply(&mut vi, &mut vj, vec3::add(vec3::scale(lambda, r.n), t));
        e.store(v, vi, vj);
    }
    acc
}

/// Each contact's solve stage total (its normal and tangential impulses) into `solved`: the
/// next step's warm start.
#[inline]
fn store_solved(rows: &[Row], acc: &[Accumulated], solved: &mut [[f64; 3]]) {
    for (k, r) in rows.iter().enumerate() {
        solved[k] = vec3::add(vec3::scale(acc[k].0, r.n), acc[k].1);
    }
}

/// The positions `x` moved by h times the velocity change from `before` to `v` (movable
/// particles only).
#[inline]
fn follow_velocities<const N: usize>(x: &mut [f64], v: &[f64], before: &[f64], inv_mass: &[f64], h: f64) {
    for (q, xq) in x.iter_mut().enumerate() {
        let (p, d) = (q / 3, q % 3);
        if inv_mass[p] > 0.0 {
            *xq += h * (v[N * p + d] - before[N * p + d]);
        }
    }
}

/// The relax stage's normal velocity target of each contact: closing, at most, the gap the
/// solve left (0 where none is left).
#[inline]
fn relax_targets<const N: usize>(rows: &[Row], ends: &[Option<Ends>], targets: &[Target], v: &[f64], h: f64) -> Vec<f64> {
    rows.iter()
        .zip(ends)
        .zip(targets)
        .map(|((r, e), t)| {
            let Some(e) = e else { return 0.0 };
            let (vi, vj) = e.load::<N>(v);
            let gap = t.gap + h * (vec3::dot(r.relative(&vi, &vj), r.n) - t.u_n);
            if gap > 0.0 {
                -gap / h
            } else {
                0.0
            }
        })
        .collect()
}

/// Each contact's restitution target, for those that bear load (λ > 0) and came in fast.
#[inline]
fn bouncing(targets: &[Target], acc: &[Accumulated]) -> Vec<Option<f64>> {
    targets.iter().zip(acc).map(|(t, a)| t.bounce.filter(|_| a.0 > 0.0)).collect()
}

/// Each contact's final total impulse on i into `totals` and, with rolling resistance
/// (N = 6), its angular impulse into `rolls`.
#[inline]
fn final_totals<const N: usize>(
    rows: &[Row],
    acc: &[Accumulated],
    ends: &[Option<Ends>],
    rolling: f64,
    totals: &mut Vec<[f64; 3]>,
    rolls: &mut Vec<[f64; 3]>,
) {
    totals.clear();
    totals.extend(rows.iter().zip(acc).zip(ends).map(|((r, (lambda, t, _)), e)| match e {
        Some(_) => vec3::add(vec3::scale(*lambda, r.n), *t),
        None => [0.0; 3],
    }));
    rolls.clear();
    if N == 6 && rolling > 0.0 {
        rolls.extend(
            acc.iter()
                .zip(ends)
                .map(|((_, _, m), e)| if e.is_some() { *m } else { [0.0; 3] }),
        );
    }
}

/// A contact's impulses accumulated over the passes: the normal λ (N·s), the tangential and
/// the rolling (angular) ones.
type Accumulated = (f64, [f64; 3], [f64; 3]);

/// Most passes of a shock stage over one level's contacts.
const SHOCK_PASSES: usize = 10;

/// The shock stages of one island (`collide/shock.rs`): its contacts bottom up by level,
/// each with its row and ends with the lower side held still.
struct Shocks {
    order: ShockOrder,
    rows: Vec<Row>,
    ends: Vec<Ends>,
}

impl Shocks {
    /// The levels of the island's `n` particles from the contacts that touch (bear load
    /// after the solve, or overlap at the step's end) and the particles' accelerations
    /// `accel` (m/s², 3 per particle), and the visits they give.
    fn new(
        contacts: &[Contact],
        targets: &[Target],
        rows: &[Row],
        ends: &[Option<Ends>],
        acc: &[(f64, [f64; 3], [f64; 3])],
        accel: &[f64],
        n: usize,
    ) -> Shocks {
        // whether a push along `dir` holds q up: against its acceleration
        let holds = |q: usize, dir: [f64; 3]| {
            let a = vec3::get(accel, q);
            vec3::dot(dir, a) < -SUPPORT_COSINE * vec3::norm(a)
        };
        // each touching contact's support: (particle held up, its support if a movable
        // particle, the side held still)
        let support: Vec<Option<(usize, Option<usize>, Held)>> = contacts
            .iter()
            .zip(ends)
            .enumerate()
            .map(|(k, (c, e))| {
                let e = (*e)?;
                if !(acc[k].0 > 0.0 || targets[k].gap <= 0.0) {
                    return None; // not touching
                }
                let (nrm, j) = (rows[k].n, e.j.filter(|_| e.writes_j()));
                if e.writes_i() && holds(c.i, nrm) {
                    return Some((c.i, j, if j.is_some() { Held::J } else { Held::Neither }));
                }
                let i = e.writes_i().then_some(c.i);
                j.filter(|&j| holds(j, vec3::scale(-1.0, nrm)))
                    .map(|j| (j, i, if i.is_some() { Held::I } else { Held::Neither }))
            })
            .collect();
        let grounded: Vec<usize> = support.iter().flatten().filter(|s| s.1.is_none()).map(|s| s.0).collect();
        let edges: Vec<(usize, usize)> = support.iter().flatten().filter_map(|s| s.1.map(|p| (p, s.0))).collect();
        let level = levels(n, &grounded, &edges);
        let order = order(support.iter().map(|s| s.map(|(q, _, held)| (level[q], held))));
        Shocks {
            rows: order.visits.iter().map(|&(k, held)| rows[k].held(held)).collect(),
            ends: order
                .visits
                .iter()
                .map(|&(k, held)| ends[k].expect("a visit has ends").held(held))
                .collect(),
            order,
        }
    }

    /// One shock stage on the velocities `v` (N per particle): level by level, its support
    /// contacts swept until no visit changes more than the tolerance (at most
    /// [`SHOCK_PASSES`]; a level's visits are each particle's own few supports) toward the
    /// normal velocity `target(k)` of contact k. Each contact's push starts from 0 and stays
    /// ≥ 0: the stage only stops what sinks into its supports, and leaves friction to the
    /// passes. The velocity changes are added to `kicks`.
    fn run<const N: usize>(&self, v: &mut [f64], kicks: &mut [f64], params: &SoftParams, target: impl Fn(usize) -> f64) {
        let before = v.to_vec();
        let visits = &self.order.visits;
        let mut state = vec![(0.0, [0.0; 3], [0.0; 3]); visits.len()];
        for level in self.order.starts.windows(2) {
            for _ in 0..SHOCK_PASSES {
                let mut change: f64 = 0.0;
                for m in level[0]..level[1] {
                    let e = &self.ends[m];
                    let (mut vi, mut vj) = e.load::<N>(v);
                    change = change.max(self.rows[m].visit(&mut vi, &mut vj, &mut state[m], target(visits[m].0), None));
                    e.store(v, vi, vj);
                }
                if change <= params.tolerance {
                    break;
                }
            }
        }
        for (kick, (now, was)) in kicks.iter_mut().zip(v.iter().zip(&before)) {
            *kick += now - was;
        }
    }
}

/// Whether [`soft_step`] leaves contact `c` alone: it has no warm start (`warm` = 0, N·s),
/// and at the velocities `v` the step ends with (m/s, 3 per particle; with spin also the
/// angular velocities `omega`, rad/s) its relative normal velocity u already meets both its
/// solve target and its relax target (u ≥ −g/h across the gap g it ends with, else u ≥ 0).
/// Then every visit of every stage finds λ = 0 and leaves it there, and with λ = 0 the cone
/// holds friction and rolling resistance at 0: the contact gives nothing, moves nothing, and
/// bounces not (the restitution stage takes only contacts that bear load). An island whose
/// contacts are all idle would be solved to exactly nothing (`collide/islands.rs` leaves it
/// out). u is computed as the visits compute it, from the same row, bit for bit; a value
/// that is not finite is never idle (the solve decides what it does).
pub(crate) fn idle(
    c: &Contact,
    target: &Target,
    warm: [f64; 3],
    inv_mass: &[f64],
    spin: Option<(Rotation<'_>, &[f64])>,
    v: &[f64],
    h: f64,
) -> bool {
    if warm != [0.0; 3] {
        return false;
    }
    let Some(e) = Ends::of(c, inv_mass) else {
        return true; // two immovable sides: the solve skips it
    };
    let (vi, vj) = e.load::<3>(v);
    let u_n = match spin {
        None => {
            let row = Row::new(c, target, inv_mass, None, 0.0, 0.0);
            let finite = vi.iter().chain(&vj).all(|a| a.is_finite());
            if !finite {
                return false;
            }
            vec3::dot(row.relative::<3>(&vi, &vj), row.n)
        }
        Some((r, omega)) => {
            let row = Row::new(c, target, inv_mass, Some(r), 0.0, 0.0);
            let wj = e.j.map_or([0.0; 3], |j| vec3::get(omega, j));
            let six = |a: [f64; 3], w: [f64; 3]| -> [f64; 6] { [a[0], a[1], a[2], w[0], w[1], w[2]] };
            let (ai, aj) = (six(vi, vec3::get(omega, c.i)), six(vj, wj));
            if !ai.iter().chain(&aj).all(|a| a.is_finite()) {
                return false;
            }
            vec3::dot(row.relative::<6>(&ai, &aj), row.n)
        }
    };
    let finite = [target.gap, target.u_n, target.solve_n]
        .iter()
        .chain(&target.stick_t)
        .all(|a| a.is_finite());
    let gap = target.gap + h * (u_n - target.u_n);
    let relax_n = if gap > 0.0 { -gap / h } else { 0.0 };
    finite && u_n >= target.solve_n && u_n >= relax_n
}
