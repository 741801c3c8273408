"""Measured orders of accuracy: the slopes of error against step size on a log-log scale.

A method of order p has a local (one-step) error C h^{p+1} and a global error C' h^p at a
fixed end time. `convergence` measures both on a problem with an exact solution and fits
the slopes by least squares on log(error) against log(h).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import problems as _problems
from .ode import ButcherTableau, methods, solve, solve_second_order


@dataclass(frozen=True)
class ConvergenceResult:
    """Errors and fitted orders of one method on one problem."""

    method: str
    problem: str
    expected_order: int
    h_global: np.ndarray
    global_error: np.ndarray
    h_local: np.ndarray
    local_error: np.ndarray
    global_order: float
    local_order: float

    def plot(self, ax: Any = None, **style: Any) -> Any:
        """Log-log plot of both errors against h, with the fitted slopes in the legend."""
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(6, 5))
        (line,) = ax.loglog(self.h_global, self.global_error, "o-", label=f"{self.method} global, slope {self.global_order:.2f}", **style)
        ax.loglog(self.h_local, self.local_error, "s--", color=line.get_color(), alpha=0.7, label=f"{self.method} local, slope {self.local_order:.2f}")
        ax.set_xlabel("step size h")
        ax.set_ylabel("error (max norm)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize="small")
        return ax


def _slope(h: np.ndarray, err: np.ndarray) -> float:
    return float(np.polyfit(np.log(h), np.log(err), 1)[0])


def _expected_order(method: str | ButcherTableau) -> int:
    if isinstance(method, str):
        for m in methods():
            if m.name == method:
                return m.order
        raise ValueError(f"method = {method!r} is unknown")  # solve would say the same, with the list
    return int(method.order)


def convergence(
    method: str | ButcherTableau,
    problem: str | _problems.Problem = "harmonic_oscillator",
    *,
    steps: Sequence[int] = (16, 32, 64, 128, 256),
    local_steps: Sequence[int] = (8, 16, 32, 64),
) -> ConvergenceResult:
    """Measure the global and local orders of `method` on `problem`.

    Global: integrate over the problem's `t_span` with N equal steps for each N in
    `steps` and take the max-norm error at the end. Local: one step of h = T/N for each N in
    `local_steps` from the exact initial state, against the exact solution. Mechanical
    problems run through `solve_second_order` (so `verlet` and `symplectic_euler` apply),
    others through `solve`.
    """
    if isinstance(method, str) and method == "rk45":
        raise ValueError(
            "method = 'rk45' is adaptive, so its step is not the h of a convergence study; measure the "
            "Dormand-Prince method at fixed steps with method=kinema.ButcherTableau.of('rk45')"
        )
    prob = _problems.get(problem) if isinstance(problem, str) else problem
    t0, t1 = prob.t_span
    span = t1 - t0
    y0 = prob.y0

    def run(h: float, t_end: float) -> np.ndarray:
        if prob.second_order:
            n = y0.size // 2
            sol = solve_second_order(prob.a, y0[:n], y0[n:], (t0, t_end), h=h, method=method, rtol=1e-10, atol=1e-12)
        else:
            sol = solve(prob.f, y0, (t0, t_end), h=h, method=method, rtol=1e-10, atol=1e-12)
        if not sol.success:
            raise RuntimeError(f"{method} failed on {prob.name} with h = {h}: {sol.message}")
        return sol.y[-1]

    h_g = np.array([span / n for n in steps])
    e_g = np.array([np.max(np.abs(run(h, t1) - prob.exact(t1))) for h in h_g])
    h_l = np.array([span / n for n in local_steps])
    e_l = np.array([np.max(np.abs(run(h, t0 + h) - prob.exact(t0 + h))) for h in h_l])
    name = method if isinstance(method, str) else method.name
    return ConvergenceResult(
        method=name,
        problem=prob.name,
        expected_order=_expected_order(method),
        h_global=h_g,
        global_error=e_g,
        h_local=h_l,
        local_error=e_l,
        global_order=_slope(h_g, e_g),
        local_order=_slope(h_l, e_l),
    )
