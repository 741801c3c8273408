"""Measured orders of accuracy against each method's theory (global p, local p + 1)."""

import numpy as np
import pytest

import kinema
from kinema import problems

# (method, global order, local order): the table; heun and symplectic Euler besides.
THEORY = [
    ("euler", 1, 2),
    ("midpoint", 2, 3),
    ("rk4", 4, 5),
    ("implicit_euler", 1, 2),
    ("verlet", 2, 3),
    ("heun", 2, 3),
    ("symplectic_euler", 1, 2),
]


@pytest.mark.parametrize("method, p_global, p_local", THEORY)
@pytest.mark.parametrize("problem", ["harmonic_oscillator", "driven_oscillator"])
def test_measured_orders_match_theory_on_mechanical_problems(method, p_global, p_local, problem):
    r = kinema.convergence(method, problem)
    assert r.expected_order == p_global
    assert abs(r.global_order - p_global) <= 0.15, (r.global_order, r.global_error)
    assert abs(r.local_order - p_local) <= 0.15, (r.local_order, r.local_error)


@pytest.mark.parametrize("method, p_global, p_local", [t for t in THEORY if t[0] not in ("verlet", "symplectic_euler")])
def test_measured_orders_match_theory_on_a_nonlinear_problem(method, p_global, p_local):
    # logistic y' = y(1 - y): exact y = 1 / (1 + 9 e^{-t})
    r = kinema.convergence(method, "logistic")
    assert abs(r.global_order - p_global) <= 0.15, r.global_order
    assert abs(r.local_order - p_local) <= 0.15, r.local_order


def test_errors_shrink_by_two_to_the_order_when_h_halves():
    r = kinema.convergence("rk4", problems.harmonic_oscillator())
    ratios = r.global_error[:-1] / r.global_error[1:]
    np.testing.assert_allclose(ratios, 2.0**4, rtol=0.1)


def test_verlet_on_a_first_order_problem_is_refused():
    with pytest.raises(ValueError, match="second-order systems"):
        kinema.convergence("verlet", "logistic")


def test_convergence_plot(tmp_path):
    import matplotlib.pyplot as plt

    ax = kinema.convergence("midpoint").plot()
    assert ax.get_xscale() == "log" and len(ax.get_lines()) == 2
    plt.close(ax.figure)
