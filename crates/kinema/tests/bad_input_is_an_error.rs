//! Bad input is an `Error` value that names what is wrong, never a panic or a silent wrong
//! answer: bad step sizes, non-finite initial values (named y0[i]), t_eval outside t_span or
//! unsorted, unknown method names (the message lists the valid ones), inconsistent Butcher
//! tableaux (the consistency conditions Σ_j a_ij = c_i, Σ b_i = 1), second-order-only methods
//! on first-order systems, a fixed-step method without h, and a failing user callback (its own
//! error comes back untouched as `Error::Callback`). A right-hand side that turns NaN mid-way
//! ends the solve with `Termination::NonFinite` and keeps the finite states computed before.

use std::fmt;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use kinema::ode::{
    solve, solve_second_order, ButcherTableau, FnSecondOrder, FnSystem, Integrator, Method, OdeSystem, SolveOptions, Termination,
};
use kinema::{CallbackError, Error};

fn decay() -> impl OdeSystem {
    FnSystem::new(3, |_t, y: &[f64], dy: &mut [f64]| {
        for (d, v) in dy.iter_mut().zip(y) {
            *d = -v;
        }
        Ok(())
    })
}

fn named(m: Method) -> Integrator {
    Integrator::Named(m)
}

fn opts_h(h: f64) -> SolveOptions {
    SolveOptions {
        h: Some(h),
        ..SolveOptions::default()
    }
}

/// A valid user tableau (Ralston's second-order method).
fn ralston() -> Integrator {
    ButcherTableau::new(
        "ralston",
        vec![vec![0.0, 0.0], vec![2.0 / 3.0, 0.0]],
        vec![0.25, 0.75],
        vec![0.0, 2.0 / 3.0],
        2,
    )
    .unwrap()
    .into()
}

/// Every first-order integrator (named ones that `solve` accepts, plus a user tableau).
fn first_order_integrators() -> Vec<Integrator> {
    let mut v: Vec<Integrator> = [
        Method::Euler,
        Method::Midpoint,
        Method::Heun,
        Method::Rk4,
        Method::ImplicitEuler,
        Method::Rk45,
    ]
    .into_iter()
    .map(named)
    .collect();
    v.push(ralston());
    v
}

/// Asserts an `InvalidParameter` naming `param`, and that the message names it too.
fn expect_invalid(res: Result<kinema::ode::Solution, Error>, param: &str, context: &str) -> String {
    match res {
        Err(e @ Error::InvalidParameter { .. }) => {
            let msg = e.to_string();
            let Error::InvalidParameter { parameter, .. } = &e else {
                unreachable!()
            };
            assert_eq!(parameter, param, "{context}: {msg}");
            assert!(msg.contains(param), "{context}: message does not name {param}: {msg}");
            msg
        }
        Err(e) => panic!("{context}: expected InvalidParameter({param}), got {e:?}"),
        Ok(sol) => panic!(
            "{context}: expected InvalidParameter({param}), the solve ran ({})",
            sol.message()
        ),
    }
}

#[test]
fn nonpositive_or_nonfinite_h_is_rejected() {
    for integ in first_order_integrators() {
        for h in [0.0, -0.1, -0.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let msg = expect_invalid(
                solve(&mut decay(), &[1.0, 2.0, 3.0], &integ, &opts_h(h)),
                "h",
                &format!("{} h = {h}", integ.name()),
            );
            assert!(msg.contains("> 0"), "{msg}");
        }
    }
    // The second-order-only methods check h the same way.
    for m in [Method::Verlet, Method::SymplecticEuler] {
        for h in [0.0, -1.0, f64::NAN] {
            let mut sys = FnSecondOrder::new(1, |_t, x: &[f64], _v: &[f64], a: &mut [f64]| {
                a[0] = -x[0];
                Ok(())
            });
            expect_invalid(
                solve_second_order(&mut sys, &[1.0], &[0.0], &named(m), &opts_h(h)),
                "h",
                &format!("{m} h = {h}"),
            );
        }
    }
}

#[test]
fn fixed_step_methods_need_h() {
    let no_h = SolveOptions::default();
    assert!(no_h.h.is_none());
    let mut fixed: Vec<Integrator> = [
        Method::Euler,
        Method::Midpoint,
        Method::Heun,
        Method::Rk4,
        Method::ImplicitEuler,
    ]
    .into_iter()
    .map(named)
    .collect();
    fixed.push(ralston());
    for integ in fixed {
        let msg = expect_invalid(solve(&mut decay(), &[1.0, 2.0, 3.0], &integ, &no_h), "h", integ.name());
        // The message says which method needs it and offers the adaptive alternative.
        assert!(msg.contains(integ.name()) && msg.contains("rk45"), "{msg}");
    }
    for m in [Method::Verlet, Method::SymplecticEuler] {
        let mut sys = FnSecondOrder::new(1, |_t, x: &[f64], _v: &[f64], a: &mut [f64]| {
            a[0] = -x[0];
            Ok(())
        });
        expect_invalid(solve_second_order(&mut sys, &[1.0], &[0.0], &named(m), &no_h), "h", m.name());
    }
    // rk45 does not need one.
    let sol = solve(&mut decay(), &[1.0, 2.0, 3.0], &named(Method::Rk45), &no_h).unwrap();
    assert!(sol.success());
}

#[test]
fn nonfinite_initial_values_are_named_by_index() {
    for integ in first_order_integrators() {
        for (y0, idx) in [
            ([1.0, f64::NAN, 2.0], 1),
            ([f64::INFINITY, 0.0, 0.0], 0),
            ([0.0, 0.0, f64::NEG_INFINITY], 2),
        ] {
            let param = format!("y0[{idx}]");
            let msg = expect_invalid(solve(&mut decay(), &y0, &integ, &opts_h(0.1)), &param, integ.name());
            assert!(msg.contains("finite"), "{msg}");
        }
    }
}

/// For a second-order solve the caller wrote x0 and v0, not y0. `Error::InvalidParameter`
/// documents `parameter` as "Name of the parameter as the user wrote it", so a NaN in v0[0]
/// should be reported as v0[0] (or x0[i]).
#[test]
fn nonfinite_second_order_initial_values_are_named_as_the_caller_wrote_them() {
    for m in [Method::Verlet, Method::Rk4] {
        let mut sys = FnSecondOrder::new(2, |_t, x: &[f64], _v: &[f64], a: &mut [f64]| {
            a[0] = -x[0];
            a[1] = -x[1];
            Ok(())
        });
        let res = solve_second_order(&mut sys, &[1.0, 2.0], &[f64::NAN, 0.0], &named(m), &opts_h(0.1));
        let msg = res.unwrap_err().to_string();
        assert!(msg.contains("v0[0]"), "{m}: {msg}");
    }
}

#[test]
fn wrong_lengths_and_other_options_are_rejected() {
    let integ = named(Method::Rk4);
    expect_invalid(solve(&mut decay(), &[1.0, 2.0], &integ, &opts_h(0.1)), "y0", "y0 too short");
    expect_invalid(solve(&mut decay(), &[], &integ, &opts_h(0.1)), "y0", "empty y0");
    let o = SolveOptions {
        t_span: (0.0, f64::INFINITY),
        ..opts_h(0.1)
    };
    expect_invalid(solve(&mut decay(), &[1.0, 2.0, 3.0], &integ, &o), "t_span", "infinite t_end");
    let o = SolveOptions {
        t_span: (f64::NAN, 1.0),
        ..opts_h(0.1)
    };
    expect_invalid(solve(&mut decay(), &[1.0, 2.0, 3.0], &integ, &o), "t_span", "NaN t0");
    for rtol in [0.0, -1e-6, f64::NAN] {
        let o = SolveOptions {
            rtol,
            ..SolveOptions::default()
        };
        expect_invalid(
            solve(&mut decay(), &[1.0, 2.0, 3.0], &named(Method::Rk45), &o),
            "rtol",
            "bad rtol",
        );
    }
    for atol in [-1e-9, f64::NAN, f64::INFINITY] {
        let o = SolveOptions {
            atol,
            ..SolveOptions::default()
        };
        expect_invalid(
            solve(&mut decay(), &[1.0, 2.0, 3.0], &named(Method::Rk45), &o),
            "atol",
            "bad atol",
        );
    }
    let mut sys = FnSecondOrder::new(2, |_t, _x: &[f64], _v: &[f64], a: &mut [f64]| {
        a.fill(0.0);
        Ok(())
    });
    expect_invalid(
        solve_second_order(&mut sys, &[1.0, 2.0], &[0.0], &integ, &opts_h(0.1)),
        "v0",
        "v0 too short",
    );
}

#[test]
fn t_eval_outside_t_span_or_unsorted_is_rejected() {
    for integ in [named(Method::Rk4), named(Method::Rk45)] {
        let run = |t_span: (f64, f64), te: Vec<f64>| {
            let o = SolveOptions {
                t_span,
                t_eval: Some(te),
                ..opts_h(0.1)
            };
            solve(&mut decay(), &[1.0, 2.0, 3.0], &integ, &o)
        };
        let msg = expect_invalid(run((0.0, 1.0), vec![0.5, 1.5]), "t_eval[1]", "beyond t_end");
        assert!(msg.contains("t_span"), "{msg}");
        expect_invalid(run((0.0, 1.0), vec![-0.1, 0.5]), "t_eval[0]", "before t0");
        expect_invalid(run((0.0, 1.0), vec![0.2, f64::NAN]), "t_eval[1]", "NaN point");
        let msg = expect_invalid(run((0.0, 1.0), vec![0.1, 0.5, 0.3]), "t_eval[2]", "unsorted");
        assert!(msg.contains("sorted"), "{msg}");
        // Backwards: t_eval must descend.
        let msg = expect_invalid(run((1.0, 0.0), vec![0.2, 0.8]), "t_eval[1]", "ascending on a backward solve");
        assert!(msg.contains("sorted"), "{msg}");
        expect_invalid(run((1.0, 0.0), vec![0.8, 1.2]), "t_eval[1]", "backwards, beyond t0");
        // And the valid versions go through.
        let sol = run((1.0, 0.0), vec![0.8, 0.2, 0.0]).unwrap();
        assert_eq!(sol.t, vec![0.8, 0.2, 0.0]);
        let sol = run((0.0, 1.0), vec![0.0, 0.3, 0.3, 1.0]).unwrap();
        assert_eq!(sol.t, vec![0.0, 0.3, 0.3, 1.0]);
    }
}

#[test]
fn unknown_method_names_list_the_valid_ones() {
    let valid = [
        "euler",
        "midpoint",
        "heun",
        "rk4",
        "implicit_euler",
        "rk45",
        "symplectic_euler",
        "verlet",
    ];
    for bad in ["rk5", "RK4", "", "runge-kutta", "euler "] {
        let e = Method::from_name(bad).unwrap_err();
        assert!(matches!(&e, Error::UnknownMethod { name, .. } if name == bad), "{e:?}");
        let msg = e.to_string();
        assert!(msg.contains(&format!("'{bad}'")), "{msg}");
        for v in valid {
            assert!(msg.contains(v), "'{bad}': message does not list {v}: {msg}");
        }
        assert!(bad.parse::<Method>().is_err());
    }
    for v in valid {
        assert_eq!(v.parse::<Method>().unwrap().name(), v);
    }
}

#[test]
fn inconsistent_tableaux_are_rejected() {
    let bad = |a: Vec<Vec<f64>>, b: Vec<f64>, c: Vec<f64>| match ButcherTableau::new("bad", a, b, c, 2) {
        Err(Error::InvalidTableau(msg)) => msg,
        other => panic!("expected InvalidTableau, got {other:?}"),
    };
    // Row 1 of A sums to 0.4 but c[1] = 0.5: the stage would be evaluated at the wrong time.
    let msg = bad(vec![vec![0.0, 0.0], vec![0.4, 0.0]], vec![0.5, 0.5], vec![0.0, 0.5]);
    assert!(msg.contains("row 1") && msg.contains("c[1]"), "{msg}");
    // A row sum off by 1e-9 is far above the rounding of decimal coefficients: rejected too.
    let msg = bad(vec![vec![0.0, 0.0], vec![0.5 + 1e-9, 0.0]], vec![0.0, 1.0], vec![0.0, 0.5]);
    assert!(msg.contains("row 1"), "{msg}");
    // c[0] ≠ 0 with an empty first row.
    let msg = bad(vec![vec![0.0, 0.0], vec![0.5, 0.0]], vec![0.0, 1.0], vec![0.1, 0.5]);
    assert!(msg.contains("row 0"), "{msg}");
    // Weights that do not sum to 1.
    let msg = bad(vec![vec![0.0, 0.0], vec![0.5, 0.0]], vec![0.3, 0.6], vec![0.0, 0.5]);
    assert!(msg.contains("sum to"), "{msg}");
    // Diagonal entry: implicit.
    let msg = bad(vec![vec![0.5, 0.0], vec![0.5, 0.0]], vec![0.5, 0.5], vec![0.5, 0.5]);
    assert!(msg.contains("diagonal"), "{msg}");
    // Shapes.
    bad(vec![vec![0.0, 0.0]], vec![0.5, 0.5], vec![0.0, 0.5]);
    bad(vec![vec![0.0], vec![0.5]], vec![0.5, 0.5], vec![0.0, 0.5]);
    bad(vec![], vec![], vec![]);
    // Non-finite coefficients.
    bad(vec![vec![0.0, 0.0], vec![f64::NAN, 0.0]], vec![0.5, 0.5], vec![0.0, 0.5]);
    // Decimal coefficients (rounded thirds) are accepted.
    ButcherTableau::new(
        "decimal",
        vec![vec![0.0, 0.0], vec![0.6666666666666666, 0.0]],
        vec![0.25, 0.75],
        vec![0.0, 0.6666666666666666],
        2,
    )
    .unwrap();
}

#[test]
fn second_order_only_methods_on_a_first_order_system_are_not_applicable() {
    for m in [Method::Verlet, Method::SymplecticEuler] {
        let e = solve(&mut decay(), &[1.0, 2.0, 3.0], &named(m), &opts_h(0.1)).unwrap_err();
        match &e {
            Error::MethodNotApplicable { method, reason } => {
                assert_eq!(method, m.name());
                assert!(reason.contains("solve_second_order"), "{reason}");
            }
            other => panic!("{m}: expected MethodNotApplicable, got {other:?}"),
        }
    }
}

// ---------- a failing callback comes back as the caller's own error ----------

#[derive(Debug, PartialEq)]
struct MyError {
    code: i32,
    at: f64,
}

impl fmt::Display for MyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "my error {} at t = {}", self.code, self.at)
    }
}

impl std::error::Error for MyError {}

fn expect_my_error(res: Result<kinema::ode::Solution, Error>, code: i32, context: &str) {
    match res {
        Err(Error::Callback(inner)) => {
            let mine = inner
                .downcast_ref::<MyError>()
                .unwrap_or_else(|| panic!("{context}: not my error type: {inner:?}"));
            assert_eq!(mine.code, code, "{context}");
            assert!(mine.at >= 0.3, "{context}: {mine}");
        }
        Err(e) => panic!("{context}: expected Error::Callback, got {e:?}"),
        Ok(sol) => panic!("{context}: expected Error::Callback, solve returned ({})", sol.message()),
    }
}

/// f fails from t = 0.3 on.
fn failing_rhs(t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), CallbackError> {
    if t >= 0.3 {
        return Err(Box::new(MyError { code: 42, at: t }));
    }
    dy[0] = -y[0];
    Ok(())
}

#[test]
fn a_failing_rhs_returns_its_own_error() {
    for integ in first_order_integrators() {
        let mut sys = FnSystem::new(1, failing_rhs);
        expect_my_error(solve(&mut sys, &[1.0], &integ, &opts_h(0.1)), 42, integ.name());
        // Also when the failure happens while producing dense output for t_eval.
        let mut sys = FnSystem::new(1, failing_rhs);
        let o = SolveOptions {
            t_eval: Some(vec![0.05, 0.55]),
            ..opts_h(0.1)
        };
        expect_my_error(
            solve(&mut sys, &[1.0], &integ, &o),
            42,
            &format!("{} with t_eval", integ.name()),
        );
    }
    // The error's Display/source chain keeps the original message.
    let mut sys = FnSystem::new(1, failing_rhs);
    let e = solve(&mut sys, &[1.0], &named(Method::Euler), &opts_h(0.1)).unwrap_err();
    assert!(e.to_string().contains("my error 42"), "{e}");
    assert!(std::error::Error::source(&e).unwrap().to_string().contains("my error 42"));
}

#[test]
fn a_failing_acceleration_returns_its_own_error() {
    for m in Method::ALL {
        let mut sys = FnSecondOrder::new(1, |t, x: &[f64], _v: &[f64], a: &mut [f64]| {
            if t >= 0.3 {
                return Err(Box::new(MyError { code: 7, at: t }) as CallbackError);
            }
            a[0] = -x[0];
            Ok(())
        });
        expect_my_error(
            solve_second_order(&mut sys, &[1.0], &[0.0], &named(m), &opts_h(0.1)),
            7,
            m.name(),
        );
    }
}

#[test]
fn a_failing_jacobian_returns_its_own_error() {
    struct Sys;
    impl OdeSystem for Sys {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), CallbackError> {
            dy[0] = -y[0];
            Ok(())
        }
        fn has_jacobian(&self) -> bool {
            true
        }
        fn jacobian(&mut self, t: f64, _y: &[f64], jac: &mut [f64]) -> Result<(), CallbackError> {
            if t >= 0.3 {
                return Err(Box::new(MyError { code: 99, at: t }));
            }
            jac[0] = -1.0;
            Ok(())
        }
    }
    expect_my_error(
        solve(&mut Sys, &[1.0], &named(Method::ImplicitEuler), &opts_h(0.1)),
        99,
        "implicit_euler jacobian",
    );
}

// ---------- a right-hand side that turns NaN mid-way ----------

/// Evaluations allowed before the test's f gives up with an error (so that a solver that never
/// terminates makes the test fail instead of hanging).
const EVAL_CAP: usize = 200_000;

#[derive(Debug)]
struct TooManyEvaluations;
impl fmt::Display for TooManyEvaluations {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "more than {EVAL_CAP} evaluations: the solver does not terminate")
    }
}
impl std::error::Error for TooManyEvaluations {}

const T_NAN: f64 = 0.5;
const H: f64 = 0.1;

/// y' = -y for t ≤ 0.5, NaN beyond; returns the solution (or the error) and the number of f calls.
fn solve_with_nan_rhs(integ: &Integrator) -> (Result<kinema::ode::Solution, Error>, usize) {
    let calls = Arc::new(AtomicUsize::new(0));
    let c = calls.clone();
    let mut sys = FnSystem::new(2, move |t, y: &[f64], dy: &mut [f64]| {
        if c.fetch_add(1, Ordering::Relaxed) >= EVAL_CAP {
            return Err(Box::new(TooManyEvaluations) as CallbackError);
        }
        for (d, v) in dy.iter_mut().zip(y) {
            *d = if t > T_NAN { f64::NAN } else { -v };
        }
        Ok(())
    });
    let o = SolveOptions {
        t_span: (0.0, 1.0),
        h: Some(H),
        ..SolveOptions::default()
    };
    let res = solve(&mut sys, &[1.0, 2.0], integ, &o);
    (res, calls.load(Ordering::Relaxed))
}

fn check_stops_nonfinite(integ: &Integrator) {
    let name = integ.name().to_string();
    let (res, calls) = solve_with_nan_rhs(integ);
    let sol = match res {
        Ok(sol) => sol,
        Err(e) => panic!("{name}: expected a solution ending with NonFinite, got an error after {calls} evaluations: {e}"),
    };
    eprintln!(
        "{name:<16} NaN f beyond t = {T_NAN}: termination {:?} after {calls} evaluations; last t = {}",
        sol.termination,
        sol.t.last().unwrap()
    );
    assert!(
        matches!(sol.termination, Some(Termination::NonFinite { .. })),
        "{name}: {:?}: {}",
        sol.termination,
        sol.message()
    );
    assert!(!sol.success());
    assert!(sol.y.iter().all(|v| v.is_finite()), "{name}: a recorded state is not finite");
    let t_last = *sol.t.last().unwrap();
    // Forward Euler evaluates f at the start of a step only, so it gets one step past t = 0.5.
    assert!(t_last <= T_NAN + H + 1e-12, "{name}: last recorded t = {t_last}");
    assert!(t_last >= T_NAN - H - 1e-12, "{name}: stopped too early at t = {t_last}");
    // The recorded states are the correct ones (e^-t) up to the method's accuracy.
    let exact = (-t_last).exp();
    assert!(
        (sol.last()[0] - exact).abs() < 2e-2 && (sol.last()[1] - 2.0 * exact).abs() < 4e-2,
        "{name}: {:?}",
        sol.last()
    );
    if let Some(Termination::NonFinite { t, .. }) = sol.termination {
        assert!(t <= T_NAN + H + 1e-12, "{name}: NonFinite at t = {t}");
    }
}

#[test]
fn nan_rhs_midway_stops_explicit_fixed_step_methods_with_nonfinite() {
    for integ in [
        named(Method::Euler),
        named(Method::Midpoint),
        named(Method::Heun),
        named(Method::Rk4),
        ralston(),
    ] {
        check_stops_nonfinite(&integ);
    }
}

#[test]
fn nan_acceleration_midway_stops_verlet_and_symplectic_euler_with_nonfinite() {
    for m in [Method::Verlet, Method::SymplecticEuler] {
        let mut sys = FnSecondOrder::new(1, |t, x: &[f64], _v: &[f64], a: &mut [f64]| {
            a[0] = if t > T_NAN { f64::NAN } else { -x[0] };
            Ok(())
        });
        let o = SolveOptions {
            t_span: (0.0, 1.0),
            h: Some(H),
            ..SolveOptions::default()
        };
        let sol = solve_second_order(&mut sys, &[1.0], &[0.0], &named(m), &o).unwrap();
        eprintln!(
            "{m:<16} NaN a beyond t = {T_NAN}: termination {:?}; last t = {}",
            sol.termination,
            sol.t.last().unwrap()
        );
        assert!(
            matches!(sol.termination, Some(Termination::NonFinite { .. })),
            "{m}: {:?}",
            sol.termination
        );
        assert!(sol.y.iter().all(|v| v.is_finite()), "{m}");
        assert!(*sol.t.last().unwrap() <= T_NAN + H + 1e-12);
    }
}

/// Observed: rk45 never terminates. The test's f gives up after 200,000 evaluations.
#[test]
fn nan_rhs_midway_stops_rk45_with_nonfinite() {
    check_stops_nonfinite(&named(Method::Rk45));
}

/// Observed: Termination::NewtonFailed (after 10 halvings), whose message advises giving a
/// Jacobian or a smaller h — wrong advice when f itself returned NaN.
#[test]
fn nan_rhs_midway_stops_implicit_euler_with_nonfinite() {
    check_stops_nonfinite(&named(Method::ImplicitEuler));
}
