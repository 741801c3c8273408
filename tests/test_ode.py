"""kinema.solve / solve_second_order: results against closed forms, output options, batches."""

import numpy as np
import pytest

import kinema


def decay(t, y):
    return -y


@pytest.mark.parametrize("method", ["euler", "midpoint", "heun", "rk4", "implicit_euler"])
def test_fixed_step_solution_has_the_documented_shape_and_counters(method):
    sol = kinema.solve(decay, [1.0, 2.0], (0.0, 1.0), h=0.1, method=method)
    assert sol.success and sol.method == method
    assert sol.t.shape == (11,) and sol.y.shape == (11, 2)
    np.testing.assert_allclose(sol.t, np.linspace(0.0, 1.0, 11), rtol=0, atol=1e-15)
    assert sol.t[-1] == 1.0  # the grid ends exactly at t_end
    assert sol.nsteps == 10
    # p' = -p: every method multiplies by R(-h) each step (exact for this linear problem)
    r = kinema.stability.amplification(method, -0.1)
    np.testing.assert_allclose(sol.y[-1], np.array([1.0, 2.0]) * r.real**10, rtol=1e-9)


def test_rk4_takes_four_evaluations_per_step_and_euler_one():
    assert kinema.solve(decay, [1.0], (0, 1), h=0.01, method="rk4").nfev == 400
    assert kinema.solve(decay, [1.0], (0, 1), h=0.01, method="euler").nfev == 100


def test_last_step_is_shortened_to_end_at_t_end():
    sol = kinema.solve(decay, [1.0], (0.0, 1.0), h=0.3, method="rk4")
    np.testing.assert_allclose(sol.t, [0.0, 0.3, 0.6, 0.9, 1.0], atol=1e-15)
    # three steps of 0.3 and one of 0.1: y = R(-0.3)^3 R(-0.1) exactly for p' = -p
    r = kinema.stability.amplification("rk4", np.array([-0.3, -0.1])).real
    assert abs(sol.y[-1, 0] - r[0] ** 3 * r[1]) < 1e-15


def test_backward_integration_recovers_the_initial_value():
    fwd = kinema.solve(decay, [1.0], (0.0, 2.0), h=0.01, method="rk4")
    back = kinema.solve(decay, fwd.y[-1], (2.0, 0.0), h=0.01, method="rk4")
    assert back.t[-1] == 0.0
    assert abs(back.y[-1, 0] - 1.0) < 1e-9


def test_projectile_is_exact_for_rk4_and_verlet():
    # x'' = -g: the path is quadratic in t, which both methods integrate exactly (RK4 is exact
    # for polynomials of degree <= 4; Verlet's position update is the Taylor polynomial).
    g = 9.81
    x0, v0 = np.array([0.0, 1.0]), np.array([3.0, 12.0])
    for method in ("rk4", "verlet"):
        sol = kinema.solve_second_order(lambda t, x, v: np.array([0.0, -g]), x0, v0, (0.0, 2.0), h=0.05, method=method)
        t = sol.t[:, None]
        exact = x0 + v0 * t + 0.5 * np.array([0.0, -g]) * t**2
        np.testing.assert_allclose(sol.x, exact, rtol=0, atol=1e-12)
        np.testing.assert_allclose(sol.v, v0 + np.array([0.0, -g]) * t, rtol=0, atol=1e-12)


def test_t_eval_interpolates_between_steps_to_the_method_accuracy():
    t_eval = np.linspace(0.0, 2.0, 37)  # not on the h = 0.1 grid
    sol = kinema.solve(lambda t, y: np.array([y[1], -y[0]]), [1.0, 0.0], (0.0, 2.0), h=0.1, method="rk4", t_eval=t_eval)
    np.testing.assert_array_equal(sol.t, t_eval)
    # RK4's global error at h = 0.1 is ~1e-6; the Hermite interpolant adds O(h^4) ~ 1e-5 * C
    np.testing.assert_allclose(sol.y[:, 0], np.cos(t_eval), atol=2e-6)


def test_rk45_meets_its_tolerance_and_takes_fewer_steps_when_looser():
    # Harmonic oscillator over [0, 10]: exact solution cos t, -sin t.
    steps = []
    for tol in (1e-10, 1e-8, 1e-6, 1e-4):
        sol = kinema.solve(lambda t, y: np.array([y[1], -y[0]]), [1.0, 0.0], (0.0, 10.0), method="rk45", rtol=tol, atol=tol)
        err = np.max(np.abs(sol.y[-1] - [np.cos(10.0), -np.sin(10.0)]))
        # Local error control gives a global error of the order of the tolerance times the
        # number of error-growth periods; 10 x tol bounds it here.
        assert err < 10 * tol, (tol, err)
        steps.append(sol.nsteps)
    assert steps == sorted(steps, reverse=True) and len(set(steps)) == 4, steps


def test_rk45_dense_output_is_accurate_between_steps():
    t_eval = np.linspace(0.0, 10.0, 1001)
    sol = kinema.solve(lambda t, y: np.array([y[1], -y[0]]), [1.0, 0.0], (0.0, 10.0), method="rk45", rtol=1e-9, atol=1e-12, t_eval=t_eval)
    assert sol.nsteps < 1000  # so most points are interpolated
    np.testing.assert_allclose(sol.y[:, 0], np.cos(t_eval), atol=1e-8)


def test_rk45_agrees_with_scipy_on_a_nonlinear_problem():
    from scipy.integrate import solve_ivp

    def lotka(t, y):
        return np.array([1.5 * y[0] - y[0] * y[1], -3.0 * y[1] + y[0] * y[1]])

    ours = kinema.solve(lotka, [10.0, 5.0], (0.0, 10.0), method="rk45", rtol=1e-10, atol=1e-10)
    ref = solve_ivp(lotka, (0.0, 10.0), [10.0, 5.0], method="DOP853", rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(ours.y[-1], ref.y[:, -1], rtol=1e-7)


def test_implicit_euler_uses_the_jacobian_when_given():
    lam = -1000.0

    def f(t, y):
        return lam * (y - np.cos(t)) - np.sin(t)

    def jac(t, y):
        return np.array([[lam]])

    with_jac = kinema.solve(f, [1.0], (0.0, 1.0), h=0.1, method="implicit_euler", jac=jac)
    without = kinema.solve(f, [1.0], (0.0, 1.0), h=0.1, method="implicit_euler")
    assert with_jac.njev > 0 and without.njev == 0
    np.testing.assert_allclose(with_jac.y, without.y, rtol=1e-9)
    # stiff: y stays on the slow manifold cos t (error O(h/|λ|)), where explicit Euler explodes
    assert np.max(np.abs(with_jac.y[:, 0] - np.cos(with_jac.t))) < 1e-3
    with pytest.warns(kinema.SolverWarning), np.errstate(over="ignore", invalid="ignore"):
        exploded = kinema.solve(f, [1.0], (0.0, 100.0), h=0.1, method="euler")
    assert not exploded.success and "non-finite" in exploded.message
    assert np.all(np.isfinite(exploded.y))


def test_batch_mode_calls_f_once_per_stage_and_matches_single_solves():
    omegas = np.array([1.0, 2.0, 3.0])
    calls = []

    def f(t, y):
        calls.append(y.shape)
        return np.stack([y[:, 1], -(omegas**2) * y[:, 0]], axis=1)

    y0 = np.array([[1.0, 0.0], [0.5, 0.1], [0.0, 1.0]])
    sol = kinema.solve(f, y0, (0.0, 1.0), h=0.01, method="rk4", vectorized=True)
    assert sol.y.shape == (101, 3, 2)
    assert len(calls) == 400 and set(calls) == {(3, 2)}
    for k, w in enumerate(omegas):
        single = kinema.solve(lambda t, y, w=w: np.array([y[1], -w * w * y[0]]), y0[k], (0.0, 1.0), h=0.01, method="rk4")
        np.testing.assert_allclose(sol.y[:, k, :], single.y, rtol=1e-13, atol=1e-15)


@pytest.mark.parametrize("method", ["rk45", "implicit_euler"])
def test_batch_mode_with_adaptive_and_implicit_methods(method):
    lams = np.array([-1.0, -10.0, -100.0])

    def f(t, y):
        return lams[:, None] * y

    sol = kinema.solve(f, np.ones((3, 1)), (0.0, 1.0), h=0.01, method=method, vectorized=True, rtol=1e-8, atol=1e-10)
    exact = np.exp(lams)
    if method == "rk45":
        np.testing.assert_allclose(sol.y[-1, :, 0], exact, rtol=1e-6, atol=1e-10)
    else:
        # backward Euler: (1 - hλ)^(-N)
        np.testing.assert_allclose(sol.y[-1, :, 0], (1 - 0.01 * lams) ** -100, rtol=1e-9)


def test_solve_second_order_batch_splits_x_and_v():
    x0 = np.array([[1.0, 0.0], [2.0, 0.0]])
    v0 = np.zeros((2, 2))
    sol = kinema.solve_second_order(lambda t, x, v: -x, x0, v0, (0.0, 1.0), h=0.001, method="verlet", vectorized=True)
    assert sol.x.shape == (1001, 2, 2) and sol.v.shape == (1001, 2, 2)
    np.testing.assert_allclose(sol.x[-1, :, 0], [np.cos(1.0), 2 * np.cos(1.0)], atol=1e-6)


def test_verlet_evaluates_the_acceleration_once_per_step():
    sol = kinema.solve_second_order(lambda t, x, v: -x, [1.0], [0.0], (0.0, 1.0), h=0.01, method="verlet")
    assert sol.nfev == 101  # one to start, then one per step (first same as last)


def test_verlet_stays_second_order_with_velocity_dependent_forces():
    # damped oscillator x'' = -x - 2ζ v (ζ = 0.1): x = e^{-ζt}(cos ωd t + ζ/ωd sin ωd t)
    zeta = 0.1
    wd = np.sqrt(1 - zeta**2)
    exact = np.exp(-zeta * 2.0) * (np.cos(wd * 2.0) + zeta / wd * np.sin(wd * 2.0))
    errs = []
    hs = [0.04, 0.02, 0.01, 0.005]
    for h in hs:
        sol = kinema.solve_second_order(lambda t, x, v: -x - 2 * zeta * v, [1.0], [0.0], (0.0, 2.0), h=h, method="verlet")
        errs.append(abs(sol.x[-1, 0] - exact))
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert abs(slope - 2.0) < 0.15, slope


def test_custom_tableau_runs_and_reports_its_name():
    ralston = kinema.ButcherTableau([[0, 0], [2 / 3, 0]], [1 / 4, 3 / 4], [0, 2 / 3], order=2, name="ralston")
    sol = kinema.solve(decay, [1.0], (0.0, 1.0), h=0.01, method=ralston)
    assert sol.method == "ralston"
    assert abs(sol.y[-1, 0] - np.exp(-1)) < 1e-5
    r = kinema.convergence(ralston, "logistic")
    assert abs(r.global_order - 2) < 0.15 and abs(r.local_order - 3) < 0.15


def test_the_registry_lists_every_method_once():
    names = kinema.method_names()
    assert names == ["euler", "midpoint", "heun", "rk4", "implicit_euler", "rk45", "symplectic_euler", "verlet"]
    orders = {m.name: m.order for m in kinema.methods()}
    assert orders["rk4"] == 4 and orders["verlet"] == 2 and orders["implicit_euler"] == 1


def test_implicit_euler_solves_a_strongly_nonlinear_stiff_step():
    # y' = -c y³ at h = 0.5 from y = 1: the step equation y - y_n + h c y³ = 0 has its root
    # near 0.058, where J = -3c y² is 300 times smaller than at y_n; simplified Newton with the
    # Jacobian of y_n crawls, so the solver must switch to full Newton and still converge.
    c, h = 1e4, 0.5
    sol = kinema.solve(lambda t, y: -c * y**3, [1.0], (0.0, 5.0), h=h, method="implicit_euler", jac=lambda t, y: np.array([[-3 * c * y[0] ** 2]]))
    assert sol.success, sol.message
    y = sol.y[:, 0]
    residual = y[1:] - y[:-1] + h * c * y[1:] ** 3
    assert np.max(np.abs(residual / y[1:])) < 1e-8
    # the exact solution 1/sqrt(1 + 2ct) decays monotonically; so does backward Euler's
    assert np.all(np.diff(y) < 0) and np.all(y > 0)


def test_rk45_h_max_resolves_a_short_pulse_the_error_control_would_step_over():
    # y' = 1 during [5, 5.01), else 0: y(10) = 0.01 exactly. Far from the pulse the error
    # estimate is 0 and the step grows, so without a limit the pulse falls between stages.
    def pulse(t, y):
        return np.array([1.0 if 5.0 <= t < 5.01 else 0.0])

    blind = kinema.solve(pulse, [0.0], (0.0, 10.0), method="rk45")
    limited = kinema.solve(pulse, [0.0], (0.0, 10.0), method="rk45", h_max=0.004)
    assert blind.y[-1, 0] == 0.0
    assert np.max(np.diff(limited.t)) <= 0.004 * (1 + 1e-12)
    # the error control then shrinks the steps at the pulse edges (measured error 8e-7)
    assert abs(limited.y[-1, 0] - 0.01) < 1e-5


def test_h_max_must_be_positive():
    with pytest.raises(ValueError, match="h_max = 0 is invalid"):
        kinema.solve(decay, [1.0], (0.0, 1.0), method="rk45", h_max=0.0)


@pytest.mark.parametrize("method", ["rk4", "heun", "implicit_euler", "rk45"])
def test_dense_output_reproduces_the_steps_and_interpolates_between_them(method):
    f = lambda t, y: np.array([y[1], -y[0]])  # noqa: E731  (x = cos t)
    kwargs = {"rtol": 1e-9, "atol": 1e-12} if method == "rk45" else {"h": 0.01}
    plain = kinema.solve(f, [1.0, 0.0], (0.0, 10.0), method=method, **kwargs)
    dense = kinema.solve(f, [1.0, 0.0], (0.0, 10.0), method=method, dense_output=True, **kwargs)
    assert plain.sol is None and dense.sol.span == (0.0, 10.0)
    np.testing.assert_array_equal(dense.y, plain.y)  # asking for it does not change the steps
    np.testing.assert_allclose(dense.sol(dense.t), dense.y, rtol=0, atol=1e-15)
    t = np.linspace(0.0, 10.0, 777)
    between = dense.sol(t)[:, 0]
    # between the steps the interpolant is as good as the steps themselves (Hermite: O(h^4);
    # Dormand-Prince's extension: order 4, within the tolerance)
    grid_err = np.max(np.abs(dense.y[:, 0] - np.cos(dense.t)))
    assert np.max(np.abs(between - np.cos(t))) < max(2 * grid_err, 1e-8)


def test_dense_output_costs_nothing_extra_for_explicit_runge_kutta():
    f = lambda t, y: -y  # noqa: E731
    plain = kinema.solve(f, [1.0], (0.0, 1.0), h=0.01, method="rk4")
    dense = kinema.solve(f, [1.0], (0.0, 1.0), h=0.01, method="rk4", dense_output=True)
    assert dense.nfev == plain.nfev + 1  # only f at the last point


def test_dense_output_shapes_and_range():
    sol = kinema.solve_second_order(lambda t, x, v: -x, np.ones((3, 2)), np.zeros((3, 2)), (0.0, 1.0), h=0.01, vectorized=True, dense_output=True)
    assert sol.sol(0.5).shape == (3, 4)
    assert sol.sol([0.1, 0.2]).shape == (2, 3, 4)
    np.testing.assert_allclose(sol.sol(0.505)[:, :2], np.cos(0.505), atol=1e-5)
    with pytest.raises(ValueError, match=r"t = 1.5 is invalid: the dense output covers \[0, 1\]"):
        sol.sol(1.5)


def test_dense_output_backwards_in_time():
    sol = kinema.solve(lambda t, y: -y, [1.0], (2.0, 0.0), h=0.01, method="rk4", dense_output=True)
    assert sol.sol.span == (2.0, 0.0)
    np.testing.assert_allclose(sol.sol([1.0, 0.0])[:, 0], np.exp([1.0, 2.0]), rtol=1e-9)


@pytest.mark.parametrize("method", ["euler", "rk4"])
def test_a_failed_step_is_named_by_the_h_the_user_gave(method):
    # The steps run between grid times t0 + k h, so the step from t = 10.9 is 11.0 − 10.9 =
    # 0.09999999999999964 in floating point (and 0.10000000000000142 from 29.5); the message
    # echoes h = 0.1 as given, not its rounded difference.
    with pytest.warns(kinema.SolverWarning), np.errstate(over="ignore", invalid="ignore"):
        sol = kinema.solve(lambda t, y: 100 * y, [1.0], (0.0, 100.0), h=0.1, method=method)
    assert not sol.success and " with h = 0.1 produced a non-finite value" in sol.message, sol.message
