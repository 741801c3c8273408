//! Every fixed-step method converges at the order theory gives it: global error O(h^p) and
//! local (one-step) error O(h^(p+1)), with p = 1 (euler, implicit_euler, symplectic_euler),
//! 2 (midpoint, heun, verlet) and 4 (rk4), and a user-built Butcher tableau at the order it
//! declares. Compared with closed forms: the harmonic oscillator x'' = -x (x = cos t) and the
//! logistic equation y' = y(1 - y), y(0) = 0.1 (y = 1 / (1 + 9 e^(-t))).
//!
//! The order is the least-squares slope of log(error) against log(h) over step sizes that halve;
//! it must lie within ±0.15 of the theory. Step ranges keep every error well above rounding
//! (> 1e-12) and inside the asymptotic regime (the ratio of successive errors is printed).

use kinema::ode::{solve, solve_second_order, ButcherTableau, FnSecondOrder, FnSystem, Integrator, Method, SolveOptions};

const ORDER_TOL: f64 = 0.15;

/// Least-squares slope of log(err) against log(h).
fn fitted_order(hs: &[f64], errs: &[f64]) -> f64 {
    assert_eq!(hs.len(), errs.len());
    let xs: Vec<f64> = hs.iter().map(|h| h.ln()).collect();
    let ys: Vec<f64> = errs.iter().map(|e| e.ln()).collect();
    let n = xs.len() as f64;
    let mx = xs.iter().sum::<f64>() / n;
    let my = ys.iter().sum::<f64>() / n;
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    sxy / sxx
}

/// Measures the order from `err(h)` over `hs`, prints it, and checks it against `expected`.
fn check_order(label: &str, expected: f64, hs: &[f64], err: impl Fn(f64) -> f64) -> f64 {
    let errs: Vec<f64> = hs.iter().map(|&h| err(h)).collect();
    for (h, e) in hs.iter().zip(&errs) {
        assert!(
            e.is_finite() && *e > 1e-13,
            "{label}: error {e:e} at h = {h} is at rounding level or not finite; the fit would be meaningless"
        );
    }
    let ratios: Vec<String> = errs.windows(2).map(|w| format!("{:.3}", w[0] / w[1])).collect();
    let p = fitted_order(hs, &errs);
    eprintln!(
        "{label:<46} measured order {p:.4} (theory {expected}); errors {:?}; ratios per halving [{}]",
        errs.iter().map(|e| format!("{e:.3e}")).collect::<Vec<_>>(),
        ratios.join(", ")
    );
    assert!(
        (p - expected).abs() <= ORDER_TOL,
        "{label}: measured order {p:.4}, theory {expected} (errors {errs:?})"
    );
    p
}

fn halvings(h0: f64, count: usize) -> Vec<f64> {
    (0..count).map(|k| h0 / f64::powi(2.0, k as i32)).collect()
}

fn fixed(t_span: (f64, f64), h: f64) -> SolveOptions {
    SolveOptions {
        t_span,
        h: Some(h),
        ..SolveOptions::default()
    }
}

// ---------- harmonic oscillator x'' = -x, x(0) = 1, v(0) = 0: x = cos t, v = -sin t ----------

const OSC_T: f64 = 2.0;
/// Start of the one-step (local error) experiments; away from t = 0 so that neither x nor v
/// of the start state vanishes (which could hide a leading error term).
const LOCAL_T0: f64 = 0.3;

fn osc_exact(t: f64) -> [f64; 2] {
    [t.cos(), -t.sin()]
}

fn osc_solve(integ: &Integrator, t_span: (f64, f64), x0: f64, v0: f64, h: f64) -> Vec<f64> {
    let mut sys = FnSecondOrder::new(1, |_t, x: &[f64], _v: &[f64], a: &mut [f64]| {
        a[0] = -x[0];
        Ok(())
    });
    let sol = solve_second_order(&mut sys, &[x0], &[v0], integ, &fixed(t_span, h)).unwrap();
    assert!(sol.success(), "{}: {}", integ.name(), sol.message());
    assert_eq!(*sol.t.last().unwrap(), t_span.1);
    sol.last().to_vec()
}

/// max(|x - cos T|, |v + sin T|) after integrating [0, T] with step h = T / N.
fn osc_global_error(integ: &Integrator, h: f64) -> f64 {
    let y = osc_solve(integ, (0.0, OSC_T), 1.0, 0.0, h);
    let ex = osc_exact(OSC_T);
    (y[0] - ex[0]).abs().max((y[1] - ex[1]).abs())
}

/// One step of size h from the exact state at LOCAL_T0, against the exact state at LOCAL_T0 + h.
fn osc_local_error(integ: &Integrator, h: f64) -> f64 {
    let s = osc_exact(LOCAL_T0);
    let y = osc_solve(integ, (LOCAL_T0, LOCAL_T0 + h), s[0], s[1], h);
    let ex = osc_exact(LOCAL_T0 + h);
    (y[0] - ex[0]).abs().max((y[1] - ex[1]).abs())
}

// ---------- logistic y' = y (1 - y), y(0) = 0.1: y = 1 / (1 + 9 e^(-t)) ----------

const LOG_T: f64 = 2.0;

fn logistic_exact(t: f64) -> f64 {
    1.0 / (1.0 + 9.0 * (-t).exp())
}

fn logistic_solve(integ: &Integrator, t_span: (f64, f64), y0: f64, h: f64) -> f64 {
    let mut sys = FnSystem::new(1, |_t, y: &[f64], dy: &mut [f64]| {
        dy[0] = y[0] * (1.0 - y[0]);
        Ok(())
    });
    // Implicit Euler's Newton tolerance is tied to rtol/atol: keep it far below the errors measured.
    let opts = SolveOptions {
        rtol: 1e-12,
        atol: 1e-14,
        ..fixed(t_span, h)
    };
    let sol = solve(&mut sys, &[y0], integ, &opts).unwrap();
    assert!(sol.success(), "{}: {}", integ.name(), sol.message());
    sol.last()[0]
}

fn logistic_global_error(integ: &Integrator, h: f64) -> f64 {
    (logistic_solve(integ, (0.0, LOG_T), 0.1, h) - logistic_exact(LOG_T)).abs()
}

fn logistic_local_error(integ: &Integrator, h: f64) -> f64 {
    let y = logistic_solve(integ, (LOCAL_T0, LOCAL_T0 + h), logistic_exact(LOCAL_T0), h);
    (y - logistic_exact(LOCAL_T0 + h)).abs()
}

/// Global step sizes T/N for N = 16, 32, ..., 256 (T = 2) and local step sizes 0.2 ... 0.025.
fn global_hs() -> Vec<f64> {
    halvings(OSC_T / 16.0, 5)
}
fn local_hs() -> Vec<f64> {
    halvings(0.2, 4)
}

/// (method, global order, local order)
const THEORY: [(Method, f64, f64); 7] = [
    (Method::Euler, 1.0, 2.0),
    (Method::Midpoint, 2.0, 3.0),
    (Method::Heun, 2.0, 3.0),
    (Method::Rk4, 4.0, 5.0),
    (Method::ImplicitEuler, 1.0, 2.0),
    (Method::SymplecticEuler, 1.0, 2.0),
    (Method::Verlet, 2.0, 3.0),
];

#[test]
fn global_orders_on_the_harmonic_oscillator() {
    for (m, p, _) in THEORY {
        let integ = Integrator::from(m);
        // rk4 reaches rounding level sooner: N = 8..128 keeps its errors above 1e-10.
        let hs = if m == Method::Rk4 {
            halvings(OSC_T / 8.0, 5)
        } else {
            global_hs()
        };
        check_order(&format!("oscillator global {m}"), p, &hs, |h| osc_global_error(&integ, h));
    }
}

#[test]
fn local_orders_on_the_harmonic_oscillator() {
    for (m, _, q) in THEORY {
        let integ = Integrator::from(m);
        check_order(&format!("oscillator local {m}"), q, &local_hs(), |h| {
            osc_local_error(&integ, h)
        });
    }
}

#[test]
fn global_orders_on_the_logistic_equation() {
    for (m, p, _) in THEORY
        .iter()
        .copied()
        .filter(|(m, _, _)| *m != Method::Verlet && *m != Method::SymplecticEuler)
    {
        let integ = Integrator::from(m);
        let hs = if m == Method::Rk4 {
            halvings(LOG_T / 4.0, 5)
        } else {
            global_hs()
        };
        check_order(&format!("logistic global {m}"), p, &hs, |h| logistic_global_error(&integ, h));
    }
}

#[test]
fn local_orders_on_the_logistic_equation() {
    for (m, _, q) in THEORY
        .iter()
        .copied()
        .filter(|(m, _, _)| *m != Method::Verlet && *m != Method::SymplecticEuler)
    {
        let integ = Integrator::from(m);
        check_order(&format!("logistic local {m}"), q, &local_hs(), |h| {
            logistic_local_error(&integ, h)
        });
    }
}

/// The order a method declares is the order it has: the registry's `order()` is the global order
/// measured above (one less than the local order).
#[test]
fn declared_orders_match_the_theory_table() {
    for (m, p, q) in THEORY {
        assert_eq!(m.order() as f64, p, "{m}");
        assert_eq!(q, p + 1.0);
    }
}

/// Ralston's second-order method: a21 = 2/3, b = (1/4, 3/4), c = (0, 2/3).
fn ralston() -> ButcherTableau {
    ButcherTableau::new(
        "ralston",
        vec![vec![0.0, 0.0], vec![2.0 / 3.0, 0.0]],
        vec![0.25, 0.75],
        vec![0.0, 2.0 / 3.0],
        2,
    )
    .unwrap()
}

/// Kutta's 3/8 rule, order 4: c = (0, 1/3, 2/3, 1), b = (1/8, 3/8, 3/8, 1/8).
fn kutta_three_eighths() -> ButcherTableau {
    ButcherTableau::new(
        "kutta 3/8",
        vec![
            vec![0.0, 0.0, 0.0, 0.0],
            vec![1.0 / 3.0, 0.0, 0.0, 0.0],
            vec![-1.0 / 3.0, 1.0, 0.0, 0.0],
            vec![1.0, -1.0, 1.0, 0.0],
        ],
        vec![1.0 / 8.0, 3.0 / 8.0, 3.0 / 8.0, 1.0 / 8.0],
        vec![0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0],
        4,
    )
    .unwrap()
}

#[test]
fn user_tableaux_measure_the_order_they_declare() {
    for tab in [ralston(), kutta_three_eighths()] {
        let p = tab.order() as f64;
        let integ = Integrator::from(tab);
        let name = integ.name().to_string();
        let hs = if p >= 4.0 { halvings(OSC_T / 8.0, 5) } else { global_hs() };
        check_order(&format!("oscillator global {name}"), p, &hs, |h| osc_global_error(&integ, h));
        check_order(&format!("oscillator local {name}"), p + 1.0, &local_hs(), |h| {
            osc_local_error(&integ, h)
        });
        let hs = if p >= 4.0 { halvings(LOG_T / 4.0, 5) } else { global_hs() };
        check_order(&format!("logistic global {name}"), p, &hs, |h| {
            logistic_global_error(&integ, h)
        });
        check_order(&format!("logistic local {name}"), p + 1.0, &local_hs(), |h| {
            logistic_local_error(&integ, h)
        });
    }
}

/// A tableau that declares a wrong order is measured at its true one: the check above can fail.
/// (Heun's coefficients declared as order 3 still measure 2.)
#[test]
fn a_mislabelled_tableau_is_caught_by_the_measurement() {
    let tab = ButcherTableau::new(
        "heun-as-3",
        vec![vec![0.0, 0.0], vec![1.0, 0.0]],
        vec![0.5, 0.5],
        vec![0.0, 1.0],
        3,
    )
    .unwrap();
    let integ = Integrator::from(tab);
    let errs: Vec<f64> = global_hs().iter().map(|&h| osc_global_error(&integ, h)).collect();
    let p = fitted_order(&global_hs(), &errs);
    eprintln!("heun declared as order 3 measures {p:.4}");
    assert!((p - 3.0).abs() > ORDER_TOL && (p - 2.0).abs() <= ORDER_TOL);
}

// ---------- velocity Verlet with a velocity-dependent force ----------
//
// verlet.rs claims second order also for forces that depend on v (its Euler-predicted velocity
// at t + h is O(h²) off, which costs only an O(h³) local error). Damped oscillator
// x'' = -x - 2ζ x', ζ = 0.1, x(0) = 1, v(0) = 0:
// x = e^(-ζt) (cos ωt + ζ/ω sin ωt), v = -e^(-ζt) sin(ωt) / ω, ω = sqrt(1 - ζ²).

const ZETA: f64 = 0.1;

fn damped_exact(t: f64) -> [f64; 2] {
    let w = (1.0 - ZETA * ZETA).sqrt();
    let e = (-ZETA * t).exp();
    [e * ((w * t).cos() + ZETA / w * (w * t).sin()), -e * (w * t).sin() / w]
}

fn damped_error(integ: &Integrator, t0: f64, t1: f64, h: f64) -> f64 {
    let mut sys = FnSecondOrder::new(1, |_t, x: &[f64], v: &[f64], a: &mut [f64]| {
        a[0] = -x[0] - 2.0 * ZETA * v[0];
        Ok(())
    });
    let s = damped_exact(t0);
    let sol = solve_second_order(&mut sys, &[s[0]], &[s[1]], integ, &fixed((t0, t1), h)).unwrap();
    assert!(sol.success());
    let y = sol.last();
    let ex = damped_exact(t1);
    (y[0] - ex[0]).abs().max((y[1] - ex[1]).abs())
}

#[test]
fn verlet_and_symplectic_euler_keep_their_order_with_velocity_dependent_forces() {
    for (m, p) in [(Method::Verlet, 2.0), (Method::SymplecticEuler, 1.0)] {
        let integ = Integrator::from(m);
        check_order(&format!("damped oscillator global {m}"), p, &global_hs(), |h| {
            damped_error(&integ, 0.0, OSC_T, h)
        });
        check_order(&format!("damped oscillator local {m}"), p + 1.0, &local_hs(), |h| {
            damped_error(&integ, LOCAL_T0, LOCAL_T0 + h, h)
        });
    }
}
