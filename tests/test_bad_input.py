"""Bad input gets a clear error naming the parameter, the value and what is allowed; no crash."""

import math
import re
import signal
import subprocess
import sys
import textwrap
import time
from fractions import Fraction
from pathlib import Path

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
    # a wrong type is a TypeError, as at every other boundary of the API (kinema._checks)
    with pytest.raises(TypeError, match=r"z = 'x' is invalid: it must be a number \(int, float or complex\), not a string"):
        kinema.stability.amplification("rk4", "x")
    with pytest.raises(TypeError, match=r"z\[1\] = True is invalid: it must be a number"):
        kinema.stability.amplification("rk4", [0.5, True])
    with pytest.raises(ValueError, match="too large for a float"):
        kinema.stability.max_step("rk4", [10**400])
    # complex numbers are what z is made of: accepted, as Python's and NumPy's
    assert kinema.stability.amplification("euler", [1j, np.complex64(-1)]).tolist() == [1 + 1j, 0j]


@pytest.mark.parametrize(
    "args, exc, text",
    [
        (([[0]], [1], [0], True), TypeError, "order = True is invalid: it must be an integer"),
        (([[0]], [1], [0], 2**64), ValueError, "order = 1.84467e\\+19 is invalid: the declared order must be an integer from 1 to 2\\*\\*32 - 1"),
        (([[0]], [10**400], [0], 1), ValueError, "b = .* too large for a float"),
        (([[0]], ["1"], [0], 1), TypeError, r"b\[0\] = '1' is invalid"),
        (([0], [1], [0], 1), ValueError, r"a has shape \(1,\); it must be \(N, N\)"),
    ],
)
def test_butcher_tableau_arguments_are_checked_strictly(args, exc, text):
    with pytest.raises(exc, match=text):
        kinema.ButcherTableau(*args)


# -- the strict checks at the World / forces / colliders boundary (kinema._checks) ------------
# A wrong type is a TypeError, a wrong value a ValueError; each message names the parameter,
# shows the value compactly and says what is allowed. Nothing is silently coerced.


def _raises(exc, text):
    """pytest.raises whose message must contain ``text`` literally."""
    return pytest.raises(exc, match=re.escape(text))


@pytest.mark.parametrize("bad, shown", [("no", "'no'"), ("False", "'False'"), ("0", "'0'"), (0, "0"), (1, "1"), (1.0, "1.0")])
def test_pinned_must_be_a_real_bool(bad, shown):
    w = kinema.World()
    with _raises(TypeError, f"pinned = {shown} is invalid: it must be True or False (a bool)"):
        w.add_particles([[0, 0, 0]], pinned=bad)
    assert len(w) == 0  # nothing added


def test_pinned_ints_and_none_entries_are_refused():
    w = kinema.World()
    with _raises(TypeError, "pinned[1] = 1 is invalid: it must be True or False (a bool), not an int"):
        w.add_particles([[0, 0, 0], [1, 0, 0]], pinned=[False, 1])
    with _raises(TypeError, "pinned = array([0, 1]) is invalid"):
        w.add_particles([[0, 0, 0], [1, 0, 0]], pinned=np.array([0, 1]))
    with _raises(TypeError, "pinned[0] = None is invalid: it must be True or False (a bool), not None"):
        w.add_particles([[0, 0, 0], [1, 0, 0]], pinned=[None, True])
    assert len(w) == 0


@pytest.mark.parametrize("bad, shown", [("no", "'no'"), ("False", "'False'"), ("0", "'0'"), (1, "1"), (0, "0"), (None, "None"), (1.0, "1.0")])
def test_ccd_must_be_a_real_bool(bad, shown):
    w = kinema.World()
    w.set_collisions(ccd=False)
    with _raises(TypeError, f"ccd = {shown} is invalid: it must be True or False (a bool)"):
        w.set_collisions(ccd=bad)
    assert w.collisions["ccd"] is False  # the refused call changed nothing


def test_periodic_flags_must_be_bools():
    w = kinema.World()
    w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
    with _raises(TypeError, "periodic[0] = 1 is invalid: it must be True or False (a bool), not an int"):
        w.periodic = [1, 0, 0]
    with _raises(TypeError, "periodic = 'yes' is invalid"):
        w.periodic = "yes"
    assert w.periodic == (False, False, False)


@pytest.mark.parametrize(
    "i, shown, what",
    [
        (0.9, "i = 0.9", "not a float"),
        (2.0, "i = 2.0", "not a float"),
        (True, "i = True", "not a bool"),
        ("0", "i = '0'", "not a string"),
        (None, "i = None", "not None"),
        ([0, 1.5], "i[1] = 1.5", "not a float"),
        ([2, True], "i[1] = True", "not a bool"),
        (np.array([0.0, 1.0]), "i = array([0., 1.])", "not floats"),
        (np.array([True, False]), "i = array([ True, False])", "not bools"),
        (np.timedelta64(0), "i = np.timedelta64(0)", "not a timedelta64"),  # NumPy counts it as an integer
    ],
)
def test_spring_indices_must_be_integers(i, shown, what):
    with pytest.raises(TypeError) as info:
        kinema.Spring(i, np.ones(np.shape(i), dtype=int) * 3, k=1.0)
    msg = str(info.value)
    assert msg.startswith(f"{shown} is invalid: particle indices must be integers"), msg
    assert what in msg


@pytest.mark.parametrize(
    "i, shown, what",
    [
        (-1, "i = -1", "particle indices must be >= 0"),
        ([0, -2], "i[1] = -2", "particle indices must be >= 0"),
        (2**70, "i = 1.18059e+21", "particle indices must be < 9.22337e+18"),
        (np.array([2**64 - 1], dtype=np.uint64), "i[0] = 1.84467e+19", "particle indices must be < 9.22337e+18"),
    ],
)
def test_spring_indices_negative_or_huge(i, shown, what):
    with _raises(ValueError, f"{shown} is invalid: {what}"):
        kinema.Spring(i, np.ones(np.shape(i), dtype=int), k=1.0)


def test_spring_j_is_checked_too_and_the_world_is_unchanged():
    w = kinema.World()
    w.add_particles([[0, 0, 0], [1, 0, 0]])
    with _raises(TypeError, "j = 0.5 is invalid: particle indices must be integers"):
        w.add(kinema.Spring(0, 0.5, k=1.0))
    assert w.forces == []


@pytest.mark.parametrize(
    "position, shown, what",
    [
        ([[1j, 0, 0]], "position[0][0] = 1j", "not a complex number"),
        ([[0, 0, 2 + 0j]], "position[0][2] = (2+0j)", "not a complex number"),
        (np.array([[1, 0, 0]], dtype=complex), "position = array([[1.+0.j, 0.+0.j, 0.+0.j]])", "not complex numbers (complex128)"),
        (np.array([[1, 2, 3]], dtype="datetime64[s]"), "position = array([['1970-01-01T00:00:01'", "not dates (datetime64[s])"),
        (np.array([[1, 2, 3]], dtype="timedelta64[s]"), "position = array([[1, 2, 3]], dtype='timedelta64[s]')", "not time spans (timedelta64[s])"),
        (np.array([["1", "2", "3"]]), "position = array([['1', '2', '3']], dtype='<U1')", "not strings"),
        (np.array([[0, "a", 0]], dtype=object), "position[0][1] = 'a'", "not a string"),
        (np.array([[None, 0, 0]], dtype=object), "position[0][0] = None", "not None"),
        ([["1", "2", "3"]], "position[0][0] = '1'", "not a string"),
        (b"abc", "position = b'abc'", "not bytes"),
        (np.ones((1, 3), dtype=bool), "position = array([[ True, True, True]])", "not bools"),
        ([[0, True, 0]], "position[0][1] = True", "not a bool"),
        (None, "position = None", "not None"),
    ],
)
def test_positions_must_be_real_numbers(position, shown, what):
    w = kinema.World()
    with pytest.raises(TypeError) as info:
        w.add_particles(position)
    msg = str(info.value)
    assert msg.startswith(shown), msg
    assert "is invalid: it must" in msg and "real number" in msg and what in msg
    assert len(w) == 0


@pytest.mark.parametrize("radius", [1e308, 1.0000001e150, float("inf"), -1.0])
def test_a_radius_beyond_the_collision_geometry_is_refused_up_front(radius):
    # The contacts square distances: (r_i + r_j + margin)^2 must not overflow, so radii stop at
    # 1e150 m (a radius of 1e308 used to fail at the first step with a message about the
    # neighbour list's 'margin', a name the user never gave).
    w = kinema.World()
    with pytest.raises(ValueError, match=r"^radius\[1\] = .* is invalid: radii must be finite, >= 0 m and <= 1e150 m"):
        w.add_particles([[0, 0, 0], [0, 0, 0]], radius=[1.0, radius])
    assert len(w) == 0
    w.add_particles([[0, 0, 0], [0, 0, 0]], radius=1e150)  # the limit itself is allowed


def _world2():
    w = kinema.World()
    w.add_particles([[0, 0, 0], [1, 0, 0]])
    return w


@pytest.mark.parametrize(
    "call, shown",
    [
        (lambda w: w.add_particles([[0, 0, 0]], velocity=[1j, 0, 0]), "velocity[0] = 1j"),
        (lambda w: w.add_particles([[0, 0, 0]], mass="1"), "mass = '1'"),
        (lambda w: w.add_particles([[0, 0, 0]], mass=True), "mass = True"),
        (lambda w: w.add_particles([[0, 0, 0], [1, 1, 1]], mass=[1.5, True]), "mass[1] = True"),
        (lambda w: w.add_particles([[0, 0, 0]], radius=np.array([0.1 + 0j])), "radius = array([0.1+0.j])"),
        (lambda w: w.add_particles([[0, 0, 0]], restitution=["a"]), "restitution[0] = 'a'"),
        (lambda w: w.add_particles([[0, 0, 0]], friction=1j), "friction = 1j"),
        (lambda w: w.set_collisions(restitution="0.5"), "restitution = '0.5'"),
        (lambda w: w.set_collisions(friction=True), "friction = True"),
        (lambda w: w.set_collisions(model="spring_dashpot", stiffness="1e3"), "stiffness = '1e3'"),
        (lambda w: w.set_collisions(restitution_threshold=1j), "restitution_threshold = 1j"),
        (lambda w: w.set_collisions(sleep_time="0.5"), "sleep_time = '0.5'"),
        (lambda w: w.set_collisions(sleep_speed=[0.1]), "sleep_speed = [0.1]"),
        (lambda w: w.set_collisions(model=3), "model = 3"),
        (lambda w: w.add(kinema.Gravity((0, 0, 1j))), "g[2] = 1j"),
        (lambda w: w.add(kinema.Gravity(np.array(["0", "0", "-9.8"]))), "g = array(['0', '0', '-9.8'], dtype='<U4')"),
        (lambda w: w.add(kinema.Drag("1")), "linear = '1'"),
        (lambda w: w.add(kinema.Drag(0.1, quadratic=[1.0])), "quadratic = [1.0]"),
        (lambda w: w.add(kinema.Attractor(strength=True)), "strength = True"),
        (lambda w: w.add(kinema.Attractor(point=(0, 0, None))), "point[2] = None"),
        (lambda w: w.add(kinema.Wind(coefficient=1j)), "coefficient = 1j"),
        (lambda w: w.add(kinema.Spring(0, 1, k="1")), "k = '1'"),
        (lambda w: w.add(kinema.Spring(0, 1, k=1.0, damping=[1j])), "damping[0] = 1j"),
        (lambda w: w.add(kinema.Spring(0, 1, k=1.0, rest_length=np.datetime64("2020-01-01"))), "rest_length = np.datetime64('2020-01-01')"),
        (lambda w: w.add(kinema.PythonForce(lambda t, x, v: 0 * x, name=3)), "name = 3"),
        (lambda w: w.add(kinema.Plane([0, 0, 0], [0, 0, 1], restitution="0.5")), "restitution = '0.5'"),
        (lambda w: w.add(kinema.Plane([0, 0, 0], [0, 0, 1j])), "normal[2] = 1j"),
        (lambda w: w.add(kinema.Box([0, 0, 1j], [1, 1, 1])), "lo[2] = 1j"),
        (lambda w: w.add(kinema.Box([0, 0, 0], [1, 1, True])), "hi[2] = True"),
        (lambda w: w.add(kinema.SphereObstacle([0, 0, 0], "1")), "radius = '1'"),
        (lambda w: w.add(kinema.SphereObstacle([0, 0, 0], 1.0, friction=True)), "friction = True"),
        (lambda w: kinema.World(dt="0.1"), "dt = '0.1'"),
        (lambda w: kinema.World(dt=True), "dt = True"),
        (lambda w: kinema.World(dt=np.timedelta64(1, "ms")), "dt = np.timedelta64(1,'ms')"),
        (lambda w: w.add_particles([[np.timedelta64(1, "s"), 0, 0]]), "position[0][0] = np.timedelta64(1,'s')"),
        (lambda w: w.run("1"), "duration = '1'"),
        (lambda w: w.run(1.0, fps=1j), "fps = 1j"),
        (lambda w: setattr(w, "masses", "1"), "masses = '1'"),
        (lambda w: setattr(w, "positions", np.zeros((2, 3)) + 1j), "positions = array([[0.+1.j"),
        (lambda w: setattr(w, "velocities", np.zeros((2, 3), dtype=bool)), "velocities = array([[False"),
    ],
)
def test_numeric_parameters_refuse_what_is_not_a_real_number(call, shown):
    w = _world2()
    before = (w.positions.copy(), w.velocities.copy(), w.masses.copy(), w.collisions)
    with pytest.raises(TypeError) as info:
        call(w)
    msg = str(info.value)
    assert msg.startswith(f"{shown}"), msg
    assert "is invalid: " in msg and ("real number" in msg or "string" in msg)
    assert len(w) == 2 and w.forces == [] and w.colliders == []
    np.testing.assert_array_equal(w.positions, before[0])
    np.testing.assert_array_equal(w.velocities, before[1])
    np.testing.assert_array_equal(w.masses, before[2])
    assert w.collisions == before[3]


@pytest.mark.parametrize("dim, shown", [(-1, "-1"), (0, "0"), (1, "1"), (5, "5"), (2**70, "1.18059e+21"), (np.int64(-3), "-3")])
def test_world_dim_out_of_range(dim, shown):
    with _raises(ValueError, f"dim = {shown} is invalid: a world is 2D (the xy-plane) or 3D: dim must be 2 or 3"):
        kinema.World(dim=dim)


@pytest.mark.parametrize(
    "dim, shown, what", [(2.5, "2.5", "a float"), (3.0, "3.0", "a float"), (True, "True", "a bool"), ("3", "'3'", "a string"), (None, "None", "None")]
)
def test_world_dim_must_be_an_integer(dim, shown, what):
    with _raises(TypeError, f"dim = {shown} is invalid: it must be an integer (int), not {what}"):
        kinema.World(dim=dim)


@pytest.mark.parametrize("n, shown, what", [(1.5, "1.5", "a float"), (2.0, "2.0", "a float"), (True, "True", "a bool"), ("2", "'2'", "a string")])
def test_step_count_must_be_an_integer(n, shown, what):
    w = _world2()
    with _raises(TypeError, f"n = {shown} is invalid: it must be an integer (int), not {what}"):
        w.step(n)
    assert w.time == 0.0


def test_step_count_out_of_range():
    w = _world2()
    with _raises(ValueError, "n = -1 is invalid: the number of steps must be >= 0"):
        w.step(-1)
    with _raises(ValueError, "n = 1.18059e+21 is invalid: the number of steps must be < 2**64"):
        w.step(2**70)
    assert w.time == 0.0


def test_numbers_in_messages_are_compact():
    with pytest.raises(ValueError) as info:
        kinema.Drag(10**400)
    assert str(info.value) == "linear = an integer of 401 digits is invalid: it is too large for a float (at most 1.79769e+308)"
    with pytest.raises(ValueError) as info:
        kinema.Spring(10**5000, 1, k=1.0)
    assert str(info.value) == "i = an integer of 5001 digits is invalid: particle indices must be < 9.22337e+18"
    with pytest.raises(ValueError) as info:
        kinema.World().add_particles([[10**400, 0, 0]])
    assert info.value.args[0].startswith("position = ") and len(str(info.value)) < 200
    with pytest.raises(TypeError) as info:
        kinema.World().add_particles(np.zeros((10_000, 3), dtype=complex))
    assert len(str(info.value)) < 250 and "..." in str(info.value)


def test_ragged_and_misshapen_inputs_name_the_parameter():
    w = kinema.World()
    with _raises(ValueError, "position = [[0, 0, 0], [1, 1]] is invalid: its rows have different lengths"):
        w.add_particles([[0, 0, 0], [1, 1]])
    with _raises(ValueError, "mass has shape (3,); it must be a scalar or one value per particle, (2,)"):
        w.add_particles([[0, 0, 0], [1, 1, 1]], mass=[1, 2, 3])
    with _raises(ValueError, "pinned has shape (3,); it must be a scalar or one value per particle, (2,)"):
        w.add_particles([[0, 0, 0], [1, 1, 1]], pinned=[True, False, True])
    with _raises(ValueError, "velocity has shape (1, 2); it must be a (3,) vector or one per particle, (2, 3)"):
        w.add_particles([[0, 0, 0], [1, 1, 1]], velocity=[1, 2])
    with _raises(ValueError, "k has shape (2,); it must be a scalar or one value per spring, (1,)"):
        kinema.Spring(0, 1, k=[1.0, 2.0])
    with _raises(ValueError, "i has shape (1, 1); it must be one index or a 1-D list of indices"):
        kinema.Spring([[0]], [[1]], k=1.0)
    assert len(w) == 0


def test_callables_are_checked():
    with _raises(TypeError, "fn = 3 is invalid: PythonForce.fn must be a callable"):
        kinema.PythonForce(3)
    with _raises(TypeError, "callback = 'print' is invalid: it must be a function callback(world) or None"):
        _world2().run(0.01, callback="print")


def test_valid_inputs_of_every_accepted_kind_still_work():
    w = kinema.World(dim=np.int64(3), dt=np.float32(0.001))
    assert w.dim == 3
    # int positions, float32 velocities, numpy bool arrays for pinned, 0-d arrays for scalars
    idx = w.add_particles(
        [[0, 0, 0], [1, 0, 0], [2, 0, 0]], velocity=np.ones((3, 3), dtype=np.float32), mass=np.array(2.0), pinned=np.array([True, False, False])
    )
    np.testing.assert_array_equal(idx, [0, 1, 2])
    np.testing.assert_array_equal(w.positions, [[0, 0, 0], [1, 0, 0], [2, 0, 0]])
    np.testing.assert_array_equal(w.velocities, [[0, 0, 0], [1, 1, 1], [1, 1, 1]])  # the pinned one keeps 0
    np.testing.assert_array_equal(w._core.inverse_masses, [0.0, 0.5, 0.5])
    # float32 positions, a numpy bool scalar, a Python bool list, uint8 masses, Fractions, None entries
    w.add_particles(np.array([[3, 0, 0]], dtype=np.float32), pinned=np.True_, radius=np.float32(0.1))
    w.add_particles([[4, 0, 0], [5, 0, 0]], pinned=[False, True], mass=np.array([1, 2], dtype=np.uint8), restitution=[0.5, None])
    w.add_particles(np.array([[Fraction(13, 2), 0, 0]], dtype=object), friction=np.array([None], dtype=object))
    assert len(w) == 7 and w.positions[6, 0] == 6.5
    np.testing.assert_array_equal(w._core.inverse_masses, [0.0, 0.5, 0.5, 0.0, 1.0, 0.0, 1.0])
    # numpy integer indices of every width, Python int lists, an empty list
    w.add(kinema.Spring(np.int64(1), np.int64(2), k=np.float32(10.0)))
    w.add(kinema.Spring(np.array([1, 2], dtype=np.int32), np.array([4, 6], dtype=np.uint16), k=[1, 2], damping=np.array([0, 1])))
    w.add(kinema.Spring([4, 0], [6, 1], k=1))
    w.add(kinema.Spring([], [], k=1.0))
    w.add(kinema.Gravity(np.array([0, 0, -10])))
    w.add(kinema.Drag(np.float32(0.1), 0))
    w.add(kinema.Wind(velocity=[1, 0, 0], coefficient=np.array(0.5)))
    w.add(kinema.Attractor(point=np.zeros(3, dtype=np.float32), strength=1, softening=0.1))
    w.set_collisions(ccd=np.False_, restitution=np.float64(0.5), friction=0, restitution_threshold=np.float32(0.01))
    assert w.collisions["ccd"] is False and w.collisions["restitution"] == 0.5
    w.set_collisions(**w.collisions)  # the documented round trip
    w.add(kinema.Plane(np.array([0, 0, -1]), (0, 0, 1), restitution=np.float32(0.5), friction=0))
    w.add(kinema.SphereObstacle([10, 10, 10], np.int64(1)))
    w.add(kinema.Box(np.array([-20, -20, -20], dtype=np.int16), [20.0, 20.0, 20.0]))
    w.periodic = np.array([True, False, False])
    assert w.periodic == (True, False, False)
    w.periodic = (False, np.False_, False)
    w.step(np.int64(2))
    w.step(np.array(1))
    w.positions = w.positions.astype(np.float32)
    w.masses = np.array([1, 2, 3, 4, 5, 6, 7])
    traj = w.run(np.float32(0.01), fps=np.int64(100), callback=lambda world: None)
    assert len(traj.t) >= 1 and w.time > 0
    flat = kinema.World(dim=2)
    flat.add(kinema.Box([0, 0], [1, 1]))
    flat.periodic = [True, np.True_]
    assert flat.periodic == (True, True, False)


def test_a_force_that_steps_or_changes_its_own_world_gets_a_clear_error():
    # A PythonForce that calls w.step (or changes the world) while the world is stepping: a
    # RuntimeError that says so, not pyo3's "Already borrowed"; the world keeps its state.
    for act in ("step", "add"):
        w = kinema.World()
        w.add_particles([[0, 0, 0]])

        def force(t, x, v, w=w, act=act):
            if act == "step":
                w.step()
            else:
                w.add_particles([[1, 0, 0]])
            return np.zeros_like(x)

        w.add(kinema.PythonForce(force))
        with pytest.raises(RuntimeError, match="the world was used while it is stepping") as err:
            w.step()
        assert "borrowed" not in str(err.value)
        assert len(w) == 1 and w.time == 0.0


def test_implicit_euler_reports_a_non_finite_force_instead_of_taking_it_as_zero():
    # A NaN force: SimulationDiverged, as the explicit methods raise; the state before kept.
    w = kinema.World(method="implicit_euler")
    w.add_particles([[0, 0, 0]])
    w.add(kinema.PythonForce(lambda t, x, v: np.full_like(x, np.nan)))
    with pytest.raises(kinema.SimulationDiverged, match="non-finite"):
        w.step(3)
    assert w.time == 0.0 and np.all(w.velocities == 0)
    # A force so large that |F|² overflows: still the step's closed form, v = g t (it was 0).
    w = kinema.World(method="implicit_euler")
    w.add_particles([[0, 0, 0]])
    w.add(kinema.Gravity((0, 0, -1e160)))
    w.step(3)
    assert w.velocities[0, 2] == pytest.approx(-1e160 * 3e-3, rel=1e-12)


def _interrupted(code: str, after: float) -> list[str]:
    """Runs ``code`` (from the repository's root) until it prints "stepping", sends it
    SIGINT ``after`` s later, and returns the words of what it printed then, which must
    start with "interrupted" (exit status 0: it caught the KeyboardInterrupt)."""
    root = Path(__file__).resolve().parents[1]
    proc = subprocess.Popen([sys.executable, "-c", code], cwd=root, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert proc.stdout.readline().strip() == "stepping"
    time.sleep(after)
    proc.send_signal(signal.SIGINT)
    try:
        out, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        proc.kill()
        pytest.fail("the step did not stop on SIGINT")
    words = out.split()
    assert proc.returncode == 0 and words[:1] == ["interrupted"], (out, err)
    return words


def test_ctrl_c_stops_a_long_step_call_at_a_whole_step():
    # w.step(10**12) used to ignore SIGINT. Now the steps run in slices of a few ms with Ctrl-C
    # checked between: KeyboardInterrupt, and the world at the end of its last whole step
    # (v = g t exactly as the steps made it: t = steps · dt).
    code = textwrap.dedent(
        """
        import kinema, sys
        w = kinema.World()
        w.add_particles([[0, 0, 0]])
        w.add(kinema.Gravity())
        print("stepping", flush=True)
        try:
            w.step(10**12)
        except KeyboardInterrupt:
            steps = w._core.steps
            print("interrupted", steps, w.time == steps * 1e-3, w.velocities[0, 2] == -9.81 * w.time or abs(w.velocities[0, 2] / (-9.81 * w.time) - 1) < 1e-9, flush=True)
        """
    )
    words = _interrupted(code, after=0.5)
    assert int(words[1]) > 0 and words[2:] == ["True", "True"], words


def test_solve_refuses_step_limits_that_cannot_end_and_stops_at_max_steps():
    f = lambda t, y: -y  # noqa: E731
    # an h_max with which rk45 could never reach the end: refused up front, naming it
    with pytest.raises(ValueError, match=r"h_max = 1e-300 is invalid: .*1\.000e300 steps.*max_steps"):
        kinema.solve(f, [1.0], (0, 1), method="rk45", h_max=1e-300)
    with pytest.raises(ValueError, match=r"h = 1e-9 is invalid: .*1\.000e9 steps"):
        kinema.solve(f, [1.0], (0, 1), method="rk4", h=1e-9)
    # rk45 stops at max_steps with the solution so far and the reason
    with pytest.warns(kinema.SolverWarning):
        s = kinema.solve(f, [1.0], (0, 10), method="rk45", rtol=1e-12, atol=1e-14, max_steps=5)
    assert not s.success and "max_steps = 5" in s.message and len(s.t) == 6
    np.testing.assert_allclose(s.y[:, 0], np.exp(-s.t), rtol=1e-10)  # what it has is right
    # h_min: a step below it stops the solve ("step too small")
    with pytest.warns(kinema.SolverWarning):
        s = kinema.solve(f, [1.0], (0, 1), method="rk45", rtol=1e-12, h_min=0.5)
    assert not s.success and "step size" in s.message
    for name, value, kind in (("max_steps", 0, ValueError), ("max_steps", 2.5, TypeError), ("h_min", -1.0, ValueError)):
        with pytest.raises(kind, match=name):
            kinema.solve(f, [1.0], (0, 1), method="rk45", **{name: value})


def test_implicit_euler_refuses_a_dense_jacobian_larger_than_memory_with_advice():
    # 10⁶ unknowns in one system: a 10¹² entry Jacobian (7,451 GiB) used to abort the
    # interpreter on the failed allocation; now a ValueError that names y0 and what to do.
    with pytest.raises(ValueError, match=r"y0 = 1000000 unknowns .*dense Jacobian.*7450\.6 GiB.*vectorized=True.*World"):
        kinema.solve(lambda t, y: -y, np.ones(1_000_000), (0.0, 1.0), h=0.1, method="implicit_euler")
    # as a batch of independent rows the same size is fine (one 1×1 block each)
    s = kinema.solve(lambda t, y: -y, np.ones((100_000, 1)), (0.0, 0.1), h=0.1, method="implicit_euler", vectorized=True)
    np.testing.assert_allclose(s.y[-1], 1 / 1.1, rtol=1e-6)


def test_a_world_larger_than_memory_is_a_memory_error_not_an_abort():
    # Under a 3 GiB address-space cap, 6·10⁶ particles (≈ 6 GiB of world) used to abort the
    # interpreter on the failed allocation (exit 134). Now: MemoryError naming the request,
    # the world unchanged, Python alive.
    code = textwrap.dedent(
        """
        import resource, numpy as np, kinema
        resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))
        w = kinema.World()
        w.add_particles([[0, 0, 0]])
        try:
            w.add_particles(np.arange(18_000_000, dtype=float).reshape(-1, 3))
        except MemoryError as e:
            print("MemoryError", e)
        w.step(2)
        print("alive", len(w))
        try:  # a solve whose states cannot be kept: 10⁷ steps of 10⁵ values (7,451 GiB)
            kinema.solve(lambda t, y: -y, np.ones(100_000), (0, 1000), h=1e-4)
        except MemoryError as e:
            print("MemoryError", e)
        """
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr[-2000:]
    assert "MemoryError adding 6000000 particles needs about" in res.stdout and "alive 1" in res.stdout, res.stdout
    assert "MemoryError the solution's 10000001 states of 100000 values needs about 7450.656 GiB" in res.stdout, res.stdout


def test_springs_larger_than_memory_are_a_memory_error_not_an_abort():
    # Under an address-space cap, 2·10⁷ springs between two particles were taken (as Python
    # lists, 100 B a spring more) and the first step aborted the interpreter on the advice's
    # Jacobian blocks ("memory allocation of 1760000000 bytes failed", exit 134). Now the
    # room for them (kinema::forces::Springs::BYTES_PER_SPRING each) is asked for first:
    # MemoryError naming the count, the world unchanged, Python alive.
    code = textwrap.dedent(
        """
        import resource, numpy as np, kinema
        resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))
        w = kinema.World()
        w.add_particles([[0, 0, 0], [1, 0, 0]])
        n = 20_000_000
        try:
            w.add(kinema.Spring(np.zeros(n, dtype=np.int64), np.ones(n, dtype=np.int64), k=1.0, rest_length=1.0))
        except MemoryError as e:
            print("MemoryError", e)
        w.add(kinema.Spring([0], [1], k=2.0, rest_length=0.5))
        w.step(2)
        print("alive", len(w.forces), w.positions[1][0] < 1.0)
        """
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr[-2000:]
    assert "MemoryError 20000000 springs needs about 4.768 GiB" in res.stdout and "alive 1 True" in res.stdout, res.stdout


def test_ctrl_c_stops_inside_one_long_step_and_leaves_the_step_before():
    # One step of 400 discs at 10⁴ m/s (benchmarks/impacts.py's scene) makes ~56,000 impacts
    # and takes a second or more: Ctrl-C is checked inside its impacts too. KeyboardInterrupt
    # long before the step could end, and the world exactly as before it (time 0, the same
    # positions and velocities).
    code = textwrap.dedent(
        """
        import sys, time
        import numpy as np
        sys.path.insert(0, "benchmarks")
        import impacts
        w = impacts.build(1e4)
        w.step(0)
        x0, v0 = w.positions.copy(), w.velocities.copy()
        print("stepping", flush=True)
        start = time.perf_counter()
        try:
            w.step(50)
            print("finished", flush=True)
        except KeyboardInterrupt:
            print("interrupted", round(time.perf_counter() - start, 3), w.time, w._core.steps,
                  bool(np.array_equal(w.positions, x0) and np.array_equal(w.velocities, v0)), flush=True)
        """
    )
    words = _interrupted(code, after=0.3)
    assert float(words[1]) < 5.0 and words[2:] == ["0.0", "0", "True"], words  # 50 steps take ~90 s
