"""Bad input gets a clear error naming the parameter, the value and what is allowed; no crash."""

import math

import numpy as np
import pytest

import kinema


def f(t, y):
    return -y


@pytest.mark.parametrize("h", [0.0, -0.1, math.nan, math.inf])
def test_non_positive_or_non_finite_h(h):
    with pytest.raises(ValueError, match=r"h = .* is invalid: the step size must be a finite number > 0"):
        kinema.solve(f, [1.0], (0, 1), h=h)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_nan_or_inf_in_y0_names_the_component(bad):
    with pytest.raises(ValueError, match=r"y0\[1\] = .* is invalid: initial values must be finite"):
        kinema.solve(f, [1.0, bad, 2.0], (0, 1), h=0.1)


def test_f_returning_the_wrong_shape():
    with pytest.raises(ValueError, match=r"f\(t, y\) returned an array of shape \(2,\) but \(3,\) was expected"):
        kinema.solve(lambda t, y: y[:2], [1.0, 2.0, 3.0], (0, 1), h=0.1)


def test_f_returning_something_that_is_not_an_array():
    with pytest.raises(TypeError, match=r"f\(t, y\) must return an array of floats of shape \(1,\); it returned str"):
        kinema.solve(lambda t, y: "fast", [1.0], (0, 1), h=0.1)


def test_f_may_return_a_list():
    sol = kinema.solve(lambda t, y: [-y[0]], [1.0], (0, 1), h=0.01)
    assert abs(sol.y[-1, 0] - math.exp(-1)) < 1e-9


class Boom(Exception):
    pass


@pytest.mark.parametrize("method", ["rk4", "rk45", "implicit_euler", "euler"])
def test_an_exception_raised_by_f_propagates_unchanged(method):
    err = Boom("from inside f")

    def bad(t, y):
        if t > 0.5:
            raise err
        return -y

    with pytest.raises(Boom) as info:
        kinema.solve(bad, [1.0], (0, 1), h=0.1, method=method)
    assert info.value is err


def test_an_exception_raised_by_a_propagates_unchanged():
    with pytest.raises(ZeroDivisionError):
        kinema.solve_second_order(lambda t, x, v: 1 / 0, [1.0], [0.0], (0, 1), h=0.1)


def test_unknown_method_lists_the_valid_ones():
    with pytest.raises(ValueError) as info:
        kinema.solve(f, [1.0], (0, 1), h=0.1, method="rk5")
    msg = str(info.value)
    assert "'rk5'" in msg
    for name in kinema.method_names():
        assert name in msg


def test_method_of_the_wrong_type():
    with pytest.raises(TypeError, match="method must be a method name"):
        kinema.solve(f, [1.0], (0, 1), h=0.1, method=4)


def test_tableau_whose_rows_do_not_sum_to_c():
    with pytest.raises(ValueError, match=r"row 1 of A sums to 0.4 but c\[1\] = 0.5"):
        kinema.ButcherTableau([[0, 0], [0.4, 0]], [0.5, 0.5], [0, 0.5], order=2)


def test_tableau_whose_weights_do_not_sum_to_one():
    with pytest.raises(ValueError, match="the weights b sum to 0.9"):
        kinema.ButcherTableau([[0]], [0.9], [0], order=1)


def test_implicit_tableau_is_refused():
    with pytest.raises(ValueError, match="on or above the diagonal"):
        kinema.ButcherTableau([[0.5]], [1.0], [0.5], order=2)


def test_fixed_step_method_without_h():
    with pytest.raises(ValueError, match="method 'rk4' takes a fixed step"):
        kinema.solve(f, [1.0], (0, 1))


def test_second_order_method_on_a_first_order_problem():
    with pytest.raises(ValueError, match="method 'verlet' cannot be used here"):
        kinema.solve(f, [1.0], (0, 1), h=0.1, method="verlet")


@pytest.mark.parametrize(
    "t_eval, what",
    [([0.5, 2.0], r"t_eval\[1\] = 2 is invalid: every t_eval point must lie within"), ([0.5, 0.2], r"t_eval\[1\] = 0.2 is invalid: t_eval must be sorted")],
)
def test_bad_t_eval(t_eval, what):
    with pytest.raises(ValueError, match=what):
        kinema.solve(f, [1.0], (0, 1), h=0.1, t_eval=t_eval)


def test_two_dimensional_y0_needs_vectorized():
    with pytest.raises(ValueError, match="pass vectorized=True"):
        kinema.solve(f, np.ones((2, 2)), (0, 1), h=0.1)


def test_f_not_callable():
    with pytest.raises(TypeError, match="f must be a callable"):
        kinema.solve(3.0, [1.0], (0, 1), h=0.1)


def test_bad_tolerances():
    with pytest.raises(ValueError, match=r"rtol = -1 is invalid"):
        kinema.solve(f, [1.0], (0, 1), method="rk45", rtol=-1)


def test_mismatched_x0_and_v0():
    with pytest.raises(ValueError, match="v0 has shape"):
        kinema.solve_second_order(lambda t, x, v: -x, [1.0, 2.0], [0.0], (0, 1), h=0.1)


def test_a_newton_failure_shrinks_the_step_then_reports():
    # y' = y² + 1 has the solution tan(t), which leaves every bound at t = π/2: implicit Euler
    # steps past it cannot be solved; the solve stops there with success=False and a message,
    # keeping only finite states.
    with pytest.warns(kinema.SolverWarning):
        sol = kinema.solve(lambda t, y: y * y + 1, [0.0], (0, 3), h=0.5, method="implicit_euler")
    assert not sol.success
    assert "Newton iterations did not converge" in sol.message
    assert np.all(np.isfinite(sol.y)) and sol.t[-1] < 3


def test_rk45_with_f_nan_at_the_start_stops_at_once():
    with pytest.warns(kinema.SolverWarning, match="non-finite value in component 0"):
        sol = kinema.solve(lambda t, y: np.array([np.nan]), [1.0], (1.0, 2.0), method="rk45")
    assert not sol.success and sol.t.tolist() == [1.0]


def test_rk45_with_f_nan_midway_stops_with_the_last_state_finite():
    with pytest.warns(kinema.SolverWarning, match="non-finite"):
        sol = kinema.solve(lambda t, y: -y if t < 0.5 else np.array([np.nan]), [1.0], (0.0, 1.0), method="rk45")
    assert not sol.success and sol.t[-1] < 0.5 and np.all(np.isfinite(sol.y))


def test_max_step_of_a_non_finite_lambda_is_nan():
    assert np.isnan(kinema.stability.max_step("rk4", np.nan))


def test_convergence_refuses_the_adaptive_method():
    with pytest.raises(ValueError, match=r"ButcherTableau.of\('rk45'\)"):
        kinema.convergence("rk45")


def test_a_step_so_small_it_would_never_finish_is_refused():
    with pytest.raises(ValueError, match=r"h = 1e-300 is invalid: over t_span \(0, 1\) it would take 1.000e300 steps"):
        kinema.solve(f, [1.0], (0, 1), h=1e-300)


def test_f_returning_none_or_complex_values():
    with pytest.raises(TypeError, match="it returned None"):
        kinema.solve(lambda t, y: None, [1.0], (0, 1), h=0.1)
    with pytest.raises(TypeError, match="it returned complex values"):
        kinema.solve(lambda t, y: np.array([1j]), [1.0], (0, 1), h=0.1)


def test_negative_declared_order():
    with pytest.raises(ValueError, match="order = -1 is invalid"):
        kinema.ButcherTableau([[0]], [1], [0], order=-1)


def test_amplification_of_something_that_is_not_a_number():
    with pytest.raises(ValueError, match="z = 'x' is invalid"):
        kinema.stability.amplification("rk4", "x")
