//! Implicit (backward) Euler is stable on stiff problems at steps far beyond the explicit
//! stability limit, and its Newton solve, with a user Jacobian, with finite differences, and
//! batched (block-diagonal), computes the same backward-Euler step.
//!
//! Theory: backward Euler has R(z) = 1/(1 - z), |R| ≤ 1 on the whole left half-plane and R → 0
//! as z → -∞ (L-stable). On y' = -1000 (y - cos t) - sin t (exact y = cos t + C e^(-1000t)) at
//! h = 0.1, z = -100: forward Euler multiplies the fast mode by |1 + z| = 99 per step, backward
//! Euler by 1/101. The backward-Euler recursion is linear here, so its discrete solution is known
//! in closed form, y_{n+1} = (y_n + h (1000 cos t_{n+1} - sin t_{n+1})) / (1 + 1000 h), and the
//! solver must reproduce it to rounding, whichever way the Jacobian is obtained.

use kinema::ode::{solve, FnSystem, Integrator, Method, OdeSystem, Solution, SolveOptions, Termination};
use kinema::CallbackError;

const K: f64 = 1000.0;
const H: f64 = 0.1;
const T_END: f64 = 2.0;

/// y' = -K (y - cos t) - sin t, with or without an analytic Jacobian (∂f/∂y = -K).
struct Stiff {
    with_jacobian: bool,
}

impl OdeSystem for Stiff {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), CallbackError> {
        dy[0] = -K * (y[0] - t.cos()) - t.sin();
        Ok(())
    }
    fn has_jacobian(&self) -> bool {
        self.with_jacobian
    }
    fn jacobian(&mut self, _t: f64, _y: &[f64], jac: &mut [f64]) -> Result<(), CallbackError> {
        jac[0] = -K;
        Ok(())
    }
}

fn fixed(h: f64) -> SolveOptions {
    SolveOptions {
        t_span: (0.0, T_END),
        h: Some(h),
        ..SolveOptions::default()
    }
}

fn implicit() -> Integrator {
    Integrator::Named(Method::ImplicitEuler)
}

/// The backward-Euler recursion for the stiff scalar problem, in closed form per step.
fn backward_euler_by_hand(y0: f64, h: f64, n: usize) -> Vec<f64> {
    let mut y = vec![y0];
    for k in 1..=n {
        let t1 = k as f64 * h;
        let prev = y[k - 1];
        y.push((prev + h * (K * t1.cos() - t1.sin())) / (1.0 + K * h));
    }
    y
}

#[test]
fn implicit_euler_stays_bounded_and_close_to_cos_t_at_h_0_1() {
    // y0 = 2: the fast transient e^(-1000t) is present (C = 1).
    for with_jacobian in [false, true] {
        let sol = solve(&mut Stiff { with_jacobian }, &[2.0], &implicit(), &fixed(H)).unwrap();
        assert!(sol.success(), "{}", sol.message());
        assert_eq!(sol.t.len(), 21);
        let mut worst_late = 0.0_f64;
        for (i, &t) in sol.t.iter().enumerate() {
            let y = sol.state(i)[0];
            assert!(y.abs() <= 2.0, "unbounded at t = {t}: {y}");
            if t >= 0.3 - 1e-12 {
                worst_late = worst_late.max((y - t.cos()).abs());
            }
        }
        // After the transient (damped by 1/101 per step: 1e-6 after 3 steps), backward Euler's
        // error on the slow solution is e ≈ τ / (K h) with local truncation τ ≈ h² |y''| / 2 ≤
        // 0.005: e ≲ 5e-5.
        eprintln!(
            "implicit_euler (jacobian: {with_jacobian}) h = {H}: max |y - cos t| for t ≥ 0.3 = {worst_late:.3e}; stats {:?}",
            sol.stats
        );
        assert!(worst_late <= 1e-4, "max |y - cos t| = {worst_late:e}");

        // And it is exactly the backward-Euler recursion.
        let by_hand = backward_euler_by_hand(2.0, H, 20);
        for (i, want) in by_hand.iter().enumerate() {
            let got = sol.state(i)[0];
            assert!(
                (got - want).abs() <= 1e-12,
                "step {i}: {got} vs backward Euler by hand {want}"
            );
        }
    }
}

#[test]
fn explicit_methods_blow_up_at_the_same_step() {
    // z = hλ = -100 is far outside euler's [-2, 0] and rk4's [-2.79, 0].
    for m in [Method::Euler, Method::Rk4] {
        let sol = solve(&mut Stiff { with_jacobian: false }, &[2.0], &Integrator::Named(m), &fixed(H)).unwrap();
        let worst = sol.y.iter().map(|v| v.abs()).fold(0.0, f64::max);
        eprintln!("{m} at h = {H}: max |y| = {worst:.3e}, termination {:?}", sol.termination);
        let blew_up = worst > 1e6 || matches!(sol.termination, Some(Termination::NonFinite { .. }));
        assert!(blew_up, "{m}: max |y| = {worst}, termination {:?}", sol.termination);
    }
    // While below its limit (h = 1.9e-3 < 2/1000) forward Euler is fine — the blow-up above is
    // the stability limit, not a broken problem.
    let sol = solve(
        &mut Stiff { with_jacobian: false },
        &[2.0],
        &Integrator::Named(Method::Euler),
        &fixed(1.9e-3),
    )
    .unwrap();
    assert!(sol.success());
    assert!((sol.last()[0] - T_END.cos()).abs() < 1e-3);
}

#[test]
fn user_jacobian_and_finite_differences_give_the_same_steps() {
    let with = solve(&mut Stiff { with_jacobian: true }, &[2.0], &implicit(), &fixed(H)).unwrap();
    let without = solve(&mut Stiff { with_jacobian: false }, &[2.0], &implicit(), &fixed(H)).unwrap();
    assert_eq!(with.t, without.t);
    let diff = with.y.iter().zip(&without.y).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    eprintln!(
        "user vs finite-difference Jacobian: max difference {diff:.3e}; stats with {:?}, without {:?}",
        with.stats, without.stats
    );
    assert!(diff <= 1e-10, "difference {diff:e}");
    // njev counts user Jacobian calls only; finite differences cost f evaluations instead.
    assert!(
        with.stats.njev > 0 && with.stats.njev <= with.stats.nsteps,
        "{:?}",
        with.stats
    );
    assert_eq!(without.stats.njev, 0, "{:?}", without.stats);
    assert!(
        without.stats.nfev > with.stats.nfev,
        "finite differences should cost f evaluations"
    );
    assert!(with.stats.nlu > 0 && without.stats.nlu > 0);
}

#[test]
fn implicit_euler_damps_arbitrarily_stiff_modes() {
    // L-stability: y' = λy with λ = -1e8 and h = 1 gives y1 = y0 / (1 + 1e8).
    for with_jac in [false, true] {
        struct Decay(bool);
        impl OdeSystem for Decay {
            fn dim(&self) -> usize {
                1
            }
            fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), CallbackError> {
                dy[0] = -1e8 * y[0];
                Ok(())
            }
            fn has_jacobian(&self) -> bool {
                self.0
            }
            fn jacobian(&mut self, _t: f64, _y: &[f64], jac: &mut [f64]) -> Result<(), CallbackError> {
                jac[0] = -1e8;
                Ok(())
            }
        }
        let o = SolveOptions {
            t_span: (0.0, 5.0),
            h: Some(1.0),
            ..SolveOptions::default()
        };
        let sol = solve(&mut Decay(with_jac), &[1.0], &implicit(), &o).unwrap();
        assert!(sol.success());
        for i in 0..sol.t.len() {
            let want = (1.0 + 1e8f64).powi(-(i as i32));
            let got = sol.state(i)[0];
            assert!(
                (got - want).abs() <= 1e-9 * want.max(1e-300) + 1e-30,
                "step {i}: {got} vs {want}"
            );
        }
    }
}

// ---------- batches: block_len < dim ----------
//
// One 2-D stiff linear system, non-symmetric so that a transposed Jacobian block would be wrong:
//   u' = -u,   w' = 1000 (u - w) - u,     J = [[-1, 0], [999, -1000]]
// exact: u = a e^(-t), w = a e^(-t) + (b - a) e^(-1000t) for u(0) = a, w(0) = b.
// Backward Euler per step solves (I - hJ) y_{n+1} = y_n: u_{n+1} = u_n / (1 + h),
// w_{n+1} = (w_n + 999 h u_{n+1}) / (1 + 1000 h).

struct Batch {
    blocks: usize,
    with_jacobian: bool,
}

impl OdeSystem for Batch {
    fn dim(&self) -> usize {
        2 * self.blocks
    }
    fn block_len(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), CallbackError> {
        for (yb, db) in y.chunks_exact(2).zip(dy.chunks_exact_mut(2)) {
            db[0] = -yb[0];
            db[1] = 1000.0 * (yb[0] - yb[1]) - yb[0];
        }
        Ok(())
    }
    fn has_jacobian(&self) -> bool {
        self.with_jacobian
    }
    fn jacobian(&mut self, _t: f64, _y: &[f64], jac: &mut [f64]) -> Result<(), CallbackError> {
        // Diagonal blocks one after the other, each 2×2 row-major.
        assert_eq!(jac.len(), 2 * self.dim(), "jacobian buffer must hold dim × block_len values");
        for jb in jac.chunks_exact_mut(4) {
            jb.copy_from_slice(&[-1.0, 0.0, 999.0, -1000.0]);
        }
        Ok(())
    }
}

const ICS: [[f64; 2]; 3] = [[1.0, 2.0], [2.0, -1.0], [0.5, 0.5]];

fn solve_batch(blocks: &[[f64; 2]], with_jacobian: bool, method: Method) -> Solution {
    let y0: Vec<f64> = blocks.iter().flatten().copied().collect();
    let o = SolveOptions {
        t_span: (0.0, 1.0),
        h: Some(H),
        ..SolveOptions::default()
    };
    let sol = solve(
        &mut Batch {
            blocks: blocks.len(),
            with_jacobian,
        },
        &y0,
        &Integrator::Named(method),
        &o,
    )
    .unwrap();
    assert!(sol.success(), "{}", sol.message());
    sol
}

#[test]
fn a_batch_gives_each_block_the_answer_it_gets_alone() {
    for with_jacobian in [false, true] {
        let batch = solve_batch(&ICS, with_jacobian, Method::ImplicitEuler);
        for (k, ic) in ICS.iter().enumerate() {
            let alone = solve_batch(&[*ic], with_jacobian, Method::ImplicitEuler);
            assert_eq!(alone.t, batch.t);
            let mut by_hand = *ic;
            for i in 0..batch.t.len() {
                let b = &batch.state(i)[2 * k..2 * k + 2];
                let a = alone.state(i);
                let diff = (a[0] - b[0]).abs().max((a[1] - b[1]).abs());
                assert!(
                    diff <= 1e-12,
                    "jacobian {with_jacobian}, block {k}, step {i}: batch {b:?} vs alone {a:?}"
                );
                let err = (b[0] - by_hand[0]).abs().max((b[1] - by_hand[1]).abs());
                assert!(
                    err <= 1e-12,
                    "jacobian {with_jacobian}, block {k}, step {i}: {b:?} vs backward Euler by hand {by_hand:?}"
                );
                let u = by_hand[0] / (1.0 + H);
                by_hand = [u, (by_hand[1] + 999.0 * H * u) / (1.0 + 1000.0 * H)];
            }
            // The stiff component has relaxed onto the slow one, as in the exact solution
            // (w - u = (b - a) e^(-1000t) → 0).
            let last = &batch.last()[2 * k..2 * k + 2];
            assert!(
                (last[1] - last[0]).abs() < 1e-6 * (1.0 + (ic[1] - ic[0]).abs()),
                "block {k}: {last:?}"
            );
        }
        eprintln!(
            "batch of {} blocks (jacobian: {with_jacobian}): stats {:?}",
            ICS.len(),
            batch.stats
        );
        if with_jacobian {
            assert!(batch.stats.njev > 0);
            // Exact Newton on a linear problem: one iteration lands on the solution, a second
            // confirms it — at most 2 f evaluations per step (a mislaid Jacobian block would
            // need more, or fail).
            assert!(batch.stats.nfev <= 2 * batch.stats.nsteps, "{:?}", batch.stats);
        } else {
            assert_eq!(batch.stats.njev, 0);
        }
    }
}

#[test]
fn a_batch_matches_single_solves_for_explicit_methods_too() {
    // Explicit steps at a stable h (|hλ| = 1e-3·1000 = 1 < 2) touch each component alone:
    // block results are bitwise those of the single solves.
    let y0: Vec<f64> = ICS.iter().flatten().copied().collect();
    let o = SolveOptions {
        t_span: (0.0, 0.1),
        h: Some(1e-3),
        ..SolveOptions::default()
    };
    for m in [Method::Euler, Method::Rk4] {
        let batch = solve(
            &mut Batch {
                blocks: 3,
                with_jacobian: false,
            },
            &y0,
            &Integrator::Named(m),
            &o,
        )
        .unwrap();
        for (k, ic) in ICS.iter().enumerate() {
            let alone = solve(
                &mut Batch {
                    blocks: 1,
                    with_jacobian: false,
                },
                ic,
                &Integrator::Named(m),
                &o,
            )
            .unwrap();
            for i in 0..batch.t.len() {
                assert_eq!(&batch.state(i)[2 * k..2 * k + 2], alone.state(i), "{m} block {k} step {i}");
            }
        }
    }
}

// A nonlinear stiff batch: Van der Pol x' = v, v' = μ(1 - x²)v - x with μ = 100, three initial
// conditions, with the analytic Jacobian [[0, 1], [-2μxv - 1, μ(1 - x²)]] and without (finite
// differences). The blocks' Newton iterations share one convergence test (the max over blocks),
// so a block may take an extra iteration inside a batch; with rtol = 1e-10, atol = 1e-12 the
// Newton remainder is ≤ 1e-3·(atol + rtol|y|) ≈ 1e-12 per step, hence agreement to 1e-9.

const MU: f64 = 100.0;

struct Vdp {
    blocks: usize,
    with_jacobian: bool,
}

impl OdeSystem for Vdp {
    fn dim(&self) -> usize {
        2 * self.blocks
    }
    fn block_len(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), CallbackError> {
        for (yb, db) in y.chunks_exact(2).zip(dy.chunks_exact_mut(2)) {
            db[0] = yb[1];
            db[1] = MU * (1.0 - yb[0] * yb[0]) * yb[1] - yb[0];
        }
        Ok(())
    }
    fn has_jacobian(&self) -> bool {
        self.with_jacobian
    }
    fn jacobian(&mut self, _t: f64, y: &[f64], jac: &mut [f64]) -> Result<(), CallbackError> {
        for (yb, jb) in y.chunks_exact(2).zip(jac.chunks_exact_mut(4)) {
            let (x, v) = (yb[0], yb[1]);
            jb.copy_from_slice(&[0.0, 1.0, -2.0 * MU * x * v - 1.0, MU * (1.0 - x * x)]);
        }
        Ok(())
    }
}

fn vdp_solve(ics: &[[f64; 2]], with_jacobian: bool) -> Solution {
    let y0: Vec<f64> = ics.iter().flatten().copied().collect();
    let o = SolveOptions {
        t_span: (0.0, 5.0),
        h: Some(0.05),
        rtol: 1e-10,
        atol: 1e-12,
        ..SolveOptions::default()
    };
    let sol = solve(
        &mut Vdp {
            blocks: ics.len(),
            with_jacobian,
        },
        &y0,
        &implicit(),
        &o,
    )
    .unwrap();
    assert!(sol.success(), "{}", sol.message());
    sol
}

/// Max over steps of the difference between block k of `batch` and the single solve `alone`.
fn block_difference(batch: &Solution, k: usize, alone: &Solution) -> f64 {
    assert_eq!(batch.t, alone.t);
    (0..alone.t.len())
        .map(|i| {
            let (a, b) = (alone.state(i), &batch.state(i)[2 * k..2 * k + 2]);
            (a[0] - b[0]).abs().max((a[1] - b[1]).abs())
        })
        .fold(0.0, f64::max)
}

fn check_vdp_batch(ics: &[[f64; 2]]) {
    let reference = vdp_solve(ics, true);
    let fd = vdp_solve(ics, false);
    let diff = reference.y.iter().zip(&fd.y).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    eprintln!(
        "Van der Pol batch {ics:?}: user vs finite-difference Jacobian max difference {diff:.3e}; stats {:?}",
        reference.stats
    );
    assert!(diff <= 1e-9, "{diff:e}");
    assert!(reference.stats.njev > 0 && fd.stats.njev == 0);
    // Stiff but bounded: Van der Pol's limit cycle has |x| ≤ 2.03, and these starts lie inside it.
    assert!(
        reference.y.chunks_exact(2).all(|p| p[0].abs() <= 2.1),
        "left the limit cycle's range"
    );
    for (k, ic) in ics.iter().enumerate() {
        for (with_jacobian, batch) in [(true, &reference), (false, &fd)] {
            let alone = vdp_solve(&[*ic], with_jacobian);
            let diff = block_difference(batch, k, &alone);
            eprintln!(
                "  block {k} {ic:?} (jacobian: {with_jacobian}): batch vs alone max difference {diff:.3e} (alone: {} Newton failures)",
                alone.stats.nrejected
            );
            assert!(
                diff <= 1e-9,
                "block {k} {ic:?} (jacobian: {with_jacobian}): batch vs alone differ by {diff:e}"
            );
        }
    }
}

#[test]
fn a_nonlinear_stiff_batch_agrees_with_single_solves_and_with_the_jacobian() {
    // Initial conditions whose single solves never halve a step.
    let ics = [[2.0, 0.0], [-1.5, 0.1], [0.5, -0.1]];
    for ic in ics {
        assert_eq!(
            vdp_solve(&[ic], true).stats.nrejected,
            0,
            "precondition: {ic:?} solves without step halving"
        );
    }
    check_vdp_batch(&ics);
}

/// Observed: alone, (0.5, -3) needs 27 step halvings and (2, 0) none; in the batch every block
/// takes the halved sub-steps, and block (2, 0) then differs from its single solve by 4.2e-4
/// (the size of backward Euler's O(h) error at h = 0.05).
#[test]
fn one_blocks_newton_failure_does_not_change_the_other_blocks() {
    check_vdp_batch(&[[2.0, 0.0], [-1.5, 0.5], [0.5, -3.0]]);
}

#[test]
fn stiff_and_mild_components_side_by_side_each_get_their_backward_euler_step() {
    // Two uncoupled components, one stiff (λ = -1000) and one mild (λ = -1), in one block: the
    // finite-difference Jacobian must find the diagonal [-1000, -1] and nothing off it.
    let mut sys = FnSystem::new(2, |t, y: &[f64], dy: &mut [f64]| {
        dy[0] = -K * (y[0] - t.cos()) - t.sin();
        dy[1] = -(y[1] - t.cos()) - t.sin();
        Ok(())
    });
    let sol = solve(&mut sys, &[2.0, 2.0], &implicit(), &fixed(H)).unwrap();
    let stiff = backward_euler_by_hand(2.0, H, 20);
    assert_eq!(stiff.len(), sol.t.len());
    for (i, expected) in stiff.iter().enumerate() {
        assert!((sol.state(i)[0] - expected).abs() < 1e-12);
    }
    // The mild member is O(h) accurate: y = cos t + e^(-t).
    let t = T_END;
    assert!((sol.last()[1] - (t.cos() + (-t).exp())).abs() < 0.02);
}
