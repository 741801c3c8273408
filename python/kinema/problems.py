"""Initial value problems with known exact solutions, for measuring orders of accuracy.

Each `Problem` has a first-order right-hand side `f(t, y)`, its exact solution
`exact(t)` and, for mechanical problems, the acceleration `a(t, x, v)` of the
second-order form (then y = [x, v]).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Problem:
    """An initial value problem y' = f(t, y), y(t0) = exact(t0), with its exact solution."""

    name: str
    f: Callable[[float, np.ndarray], np.ndarray]
    exact: Callable[[float], np.ndarray]
    t_span: tuple[float, float]
    a: Callable[[float, np.ndarray, np.ndarray], np.ndarray] | None = None
    """Acceleration of the second-order form x'' = a(t, x, v), when the problem has one."""

    @property
    def y0(self) -> np.ndarray:
        return self.exact(self.t_span[0])

    @property
    def second_order(self) -> bool:
        return self.a is not None


def harmonic_oscillator(omega: float = 1.0, x0: float = 1.0, v0: float = 0.0, t_end: float = 2.0) -> Problem:
    """x'' = −ω²x: x = x0 cos ωt + (v0/ω) sin ωt, v = x'. State y = [x, v]."""

    def exact(t: float) -> np.ndarray:
        c, s = np.cos(omega * t), np.sin(omega * t)
        return np.array([x0 * c + v0 / omega * s, -x0 * omega * s + v0 * c])

    def f(t: float, y: np.ndarray) -> np.ndarray:
        return np.array([y[1], -omega * omega * y[0]])

    def a(t: float, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        return -omega * omega * x

    return Problem("harmonic_oscillator", f, exact, (0.0, t_end), a)


def exponential(lam: float = -1.0, t_end: float = 1.0) -> Problem:
    """The test equation p' = λp with p(0) = 1: p = e^{λt}."""
    return Problem(
        "exponential",
        lambda t, y: lam * y,
        lambda t: np.array([np.exp(lam * t)]),
        (0.0, t_end),
    )


def logistic(r: float = 1.0, y0: float = 0.1, t_end: float = 2.0) -> Problem:
    """y' = r y (1 − y): y = 1 / (1 + (1/y0 − 1) e^{−rt}). Nonlinear."""
    return Problem(
        "logistic",
        lambda t, y: r * y * (1.0 - y),
        lambda t: np.array([1.0 / (1.0 + (1.0 / y0 - 1.0) * np.exp(-r * t))]),
        (0.0, t_end),
    )


def driven_oscillator(t_end: float = 1.0) -> Problem:
    """x'' = −x + t (a driven oscillator with time-dependent forcing): x = t + cos t − sin t,
    from x(0) = 1, v(0) = 0. Exercises the time argument of a(t, x, v)."""

    def exact(t: float) -> np.ndarray:
        return np.array([t + np.cos(t) - np.sin(t), 1.0 - np.sin(t) - np.cos(t)])

    return Problem(
        "driven_oscillator",
        lambda t, y: np.array([y[1], -y[0] + t]),
        exact,
        (0.0, t_end),
        lambda t, x, v: -x + t,
    )


BY_NAME: dict[str, Callable[[], Problem]] = {
    "harmonic_oscillator": harmonic_oscillator,
    "exponential": exponential,
    "logistic": logistic,
    "driven_oscillator": driven_oscillator,
}
"""Problems by name, with their default parameters."""


def get(name: str) -> Problem:
    """A problem by name (`kinema.problems.BY_NAME` lists them)."""
    try:
        return BY_NAME[name]()
    except KeyError:
        raise ValueError(f"problem = {name!r} is unknown; known problems are: {', '.join(BY_NAME)}") from None
