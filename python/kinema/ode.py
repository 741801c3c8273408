"""Numerical solution of ODEs: `solve` for y' = f(t, y), `solve_second_order` for
x'' = a(t, x, v).

Every method of the registry (`kinema.methods()`) is available by name, and any explicit
Runge-Kutta method by its Butcher tableau (`kinema.ButcherTableau`). The stepping runs in
the Rust engine; a Python right-hand side is called once per stage with a NumPy array.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from . import _checks, _core

if TYPE_CHECKING:
    from ._core import _SolveOptions


class ButcherTableau(_core.ButcherTableau):
    """An explicit Runge-Kutta method given by its Butcher tableau: `a` (s x s, strictly
    lower triangular), weights `b` and nodes `c` (length s) and its declared `order`.

    The arguments are checked as the API's numbers are (real numbers, not bools or strings; an
    integer order); the engine then checks the tableau itself (square A, rows of A summing to
    c, weights summing to 1). `ButcherTableau.of("rk4")` gives a registered method's.
    """

    __slots__ = ()

    def __new__(cls, a: Any, b: Any, c: Any, order: int, name: str = "custom") -> ButcherTableau:
        a = _checks.real_array("a", a, (None, None)).tolist()
        b = _checks.real_array("b", b, (None,)).tolist()
        c = _checks.real_array("c", c, (None,)).tolist()
        order = _checks.integer("order", order, 1, 2**32 - 1, what="the declared order must be an integer from 1 to 2**32 - 1")
        return super().__new__(cls, a, b, c, order, _checks.text("name", name))

    @classmethod
    def of(cls, method: str) -> ButcherTableau:
        """The tableau of a registered explicit method (`euler`, `midpoint`, `heun`,
        `rk4`, `rk45`)."""
        t = _core.ButcherTableau.of(_checks.text("method", method))
        return cls(t.A, t.b, t.c, t.order, t.name)


Method = "str | ButcherTableau"


class SolverWarning(RuntimeWarning):
    """A solve stopped before the end of its interval (`Solution.success` is False)."""


@dataclass(frozen=True)
class MethodInfo:
    """One entry of the method registry."""

    name: str
    order: int
    kind: str  # "explicit", "implicit", "adaptive" or "second_order"
    evals_per_step: int
    summary: str


def methods() -> list[MethodInfo]:
    """The registered methods, with their order, kind and cost per step."""
    return [MethodInfo(**m) for m in _core.methods()]


def method_names() -> list[str]:
    """Names accepted wherever a method is asked for."""
    return [m.name for m in methods()]


class DenseSolution:
    """The continuous solution of a solve with `dense_output=True`: `sol(t)`.

    A scalar `t` gives one state (y0's shape); an array of times gives one state per time,
    stacked along the first axis (as `Solution.y`; SciPy's `OdeSolution` puts time last).
    """

    def __init__(self, core: Any, shape: tuple[int, ...]):
        self._core = core
        self._shape = shape

    @property
    def span(self) -> tuple[float, float]:
        """The first and last time covered."""
        return self._core.span

    def __call__(self, t: Any) -> np.ndarray:
        ts = np.asarray(t, dtype=np.float64)
        out = self._core(ts.reshape(-1).tolist())
        return out.reshape((*ts.shape, *self._shape))

    def __repr__(self) -> str:
        return f"DenseSolution(span={self.span})"


@dataclass
class Solution:
    """Result of `solve` / `solve_second_order`.

    `t` has shape (T,); `y` has shape (T, n), or (T, batch, n) for a batch. For
    second-order problems `y` is [x, v] along the last axis and `x`, `v` are its halves.
    `sol` is the continuous solution when `dense_output=True` was given, else None.
    """

    t: np.ndarray
    y: np.ndarray
    nfev: int
    njev: int
    nlu: int
    nsteps: int
    nrejected: int
    method: str
    success: bool
    message: str
    sol: DenseSolution | None = field(default=None, repr=False)
    x: np.ndarray | None = field(default=None, repr=False)
    v: np.ndarray | None = field(default=None, repr=False)

    def __repr__(self) -> str:
        return (
            f"Solution(method={self.method!r}, success={self.success}, t=[{self.t[0]:g} .. {self.t[-1]:g}] "
            f"({self.t.size} points), y.shape={self.y.shape}, nsteps={self.nsteps}, nfev={self.nfev})"
        )


def _t_span(t_span: Sequence[float]) -> tuple[float, float]:
    try:
        t0, t1 = t_span
    except (TypeError, ValueError):
        raise ValueError(f"t_span = {_checks.describe(t_span)} is invalid: it must be a pair (t0, t_end) of numbers") from None
    return _checks.real("t_span[0]", t0), _checks.real("t_span[1]", t1)


def _state(name: str, value: Any) -> np.ndarray:
    arr = np.asarray(_checks.real_array(name, value), dtype=np.float64)
    if arr.ndim == 0:
        arr = arr.reshape(1)
    return np.ascontiguousarray(arr)


def _t_eval(t_eval: Any) -> list[float] | None:
    if t_eval is None:
        return None
    arr = np.asarray(_checks.real_array("t_eval", t_eval), dtype=np.float64)
    if arr.ndim != 1:
        raise ValueError(f"t_eval has shape {arr.shape}; it must be a 1-D array of times")
    return arr.tolist()


def _finish(raw: dict, shape: tuple[int, ...], caller: str) -> Solution:
    y = raw["y"].reshape((raw["t"].size, *shape))
    dense = DenseSolution(raw["sol"], shape) if raw["sol"] is not None else None
    sol = Solution(**{k: raw[k] for k in ("t", "nfev", "njev", "nlu", "nsteps", "nrejected", "method", "success", "message")}, y=y, sol=dense)
    if not sol.success:
        warnings.warn(f"kinema.{caller} stopped early: {sol.message}", SolverWarning, stacklevel=3)
    return sol


def solve(
    f: Callable[[float, np.ndarray], Any],
    y0: Any,
    t_span: Sequence[float],
    *,
    h: float | None = None,
    h_max: float | None = None,
    method: str | ButcherTableau = "rk4",
    jac: Callable[[float, np.ndarray], Any] | None = None,
    rtol: float = 1e-6,
    atol: float = 1e-9,
    t_eval: Any = None,
    vectorized: bool = False,
    dense_output: bool = False,
    max_steps: int = 10_000_000,
    h_min: float | None = None,
) -> Solution:
    """Solve the initial value problem y' = f(t, y), y(t0) = y0 over `t_span = (t0, t_end)`.

    Parameters
    ----------
    f : callable
        Right-hand side `f(t, y) -> array`; returns dy/dt with y's shape.
    y0 : array_like
        Initial state, shape (n,), or (batch, n) with `vectorized=True`; in the units of y.
    t_span : (t0, t_end)
        Interval, in the units of t; `t_end < t0` integrates backwards.
    h : float, optional
        Step size (> 0), in the units of t. Required by the fixed-step methods (the last step
        is shortened to end at t_end); for `rk45` the first step (chosen automatically when
        omitted).
    h_max : float, optional
        Largest step `rk45` may take, in the units of t (default: no limit); fixed-step
        methods ignore it.
    method : str or ButcherTableau
        A registered name (`kinema.method_names()`) or an explicit tableau. Default `rk4`.
    jac : callable, optional
        ∂f/∂y for `implicit_euler`, `jac(t, y) -> (n, n) array` ((batch, n, n) with a batch);
        finite differences otherwise (the default, None).
    rtol : float
        Relative tolerance (dimensionless), default 1e-6: rk45's error control, implicit
        Euler's Newton iterations. Each component's error is weighed against
        `atol + rtol |y|`.
    atol : float
        Absolute tolerance, in the units of y, default 1e-9: rk45's error control, implicit
        Euler's Newton iterations, with `rtol` as above.
    t_eval : array_like, optional
        Times at which to report the solution (interpolated between steps), in the units of t;
        default: every step.
    vectorized : bool
        With a 2-D `y0` of shape (batch, n): solve every row as its own initial condition,
        calling `f` once per stage with the whole (batch, n) array. Default False.
    dense_output : bool
        Keep every step's interpolant: `Solution.sol(t)` then gives the state at any time of
        the interval (rk45: Dormand-Prince's fourth-order extension; fixed-step methods: cubic
        Hermite, which costs one extra evaluation of f per step except for explicit
        Runge-Kutta methods). Default False.
    max_steps : int
        Most steps (default 10⁷): a fixed step `h`, or an `h_max`, that needs more over
        `t_span` is refused up front (`ValueError`); `rk45` stops there otherwise, with
        `success=False` and the reason.
    h_min : float, optional
        Smallest step `rk45` may take, in the units of t (default: what the time variable can
        resolve); below it the solve stops ("step too small").

    Returns
    -------
    Solution
        `t`, `y` (shape (len(t), n) or (len(t), batch, n)), counters and status. A solve that
        stops early (Newton failure, step too small, a non-finite state) returns what it had
        with `success=False` and a `message`, and warns with `SolverWarning`.
    """
    _callable("f", f)
    if jac is not None:
        _callable("jac", jac)
    y = _state("y0", y0)
    vectorized, options = _options(
        t_span=t_span,
        h=h,
        h_max=h_max,
        rtol=rtol,
        atol=atol,
        t_eval=t_eval,
        vectorized=vectorized,
        dense_output=dense_output,
        max_steps=max_steps,
        h_min=h_min,
    )
    raw = _core.solve(f, y, method, jac, vectorized, options)
    return _finish(raw, y.shape, "solve")


def solve_second_order(
    a: Callable[[float, np.ndarray, np.ndarray], Any],
    x0: Any,
    v0: Any,
    t_span: Sequence[float],
    *,
    h: float | None = None,
    h_max: float | None = None,
    method: str | ButcherTableau = "verlet",
    rtol: float = 1e-6,
    atol: float = 1e-9,
    t_eval: Any = None,
    vectorized: bool = False,
    dense_output: bool = False,
    max_steps: int = 10_000_000,
    h_min: float | None = None,
) -> Solution:
    """Solve x'' = a(t, x, v), x(t0) = x0, x'(t0) = v0 — Newton's law with a = F/m.

    Takes every method: `symplectic_euler` and `verlet` (default) work on x and v
    directly; the others integrate the first-order form y = [x, v]. The solution has `x` and
    `v` (each with x0's shape per time) besides `y` = [x, v] along the last axis.
    Parameters are those of `solve`.

    Parameters
    ----------
    a : callable
        Acceleration `a(t, x, v) -> array`; returns x'' with x's shape.
    x0 : array_like
        Initial position, shape (n,), or (batch, n) with `vectorized=True`; in the units of x.
    v0 : array_like
        Initial velocity, x0's shape; in the units of x per unit of t.
    t_span : (t0, t_end)
        Interval, in the units of t; `t_end < t0` integrates backwards.
    h : float, optional
        Step size (> 0), in the units of t; as in `solve`.
    h_max : float, optional
        Largest step `rk45` may take, in the units of t (default: no limit); as in `solve`.
    method : str or ButcherTableau
        A registered name (`kinema.method_names()`) or an explicit tableau. Default `verlet`.
    rtol : float
        Relative tolerance (dimensionless), default 1e-6; as in `solve`.
    atol : float
        Absolute tolerance, in the units of y = [x, v], default 1e-9; as in `solve`.
    t_eval : array_like, optional
        Times at which to report the solution, in the units of t; default: every step.
    vectorized : bool
        With 2-D `x0` and `v0` of shape (batch, n): solve every row as its own initial
        condition, calling `a` with whole (batch, n) arrays. Default False.
    dense_output : bool
        Keep every step's interpolant (`Solution.sol(t)`); as in `solve`. Default False.
    max_steps : int
        Most steps (default 10⁷); as in `solve`.
    h_min : float, optional
        Smallest step `rk45` may take, in the units of t; as in `solve`.

    Returns
    -------
    Solution
        As `solve`'s, with `x` and `v`.
    """
    _callable("a", a)
    x = _state("x0", x0)
    v = _state("v0", v0)
    vectorized, options = _options(
        t_span=t_span,
        h=h,
        h_max=h_max,
        rtol=rtol,
        atol=atol,
        t_eval=t_eval,
        vectorized=vectorized,
        dense_output=dense_output,
        max_steps=max_steps,
        h_min=h_min,
    )
    raw = _core.solve_second_order(a, x, v, method, vectorized, options)
    shape = (*x.shape[:-1], 2 * x.shape[-1])
    sol = _finish(raw, shape, "solve_second_order")
    n = x.shape[-1]
    sol.x = sol.y[..., :n]
    sol.v = sol.y[..., n:]
    return sol


def _options(
    *,
    t_span: Sequence[float],
    h: Any,
    h_max: Any,
    rtol: Any,
    atol: Any,
    t_eval: Any,
    vectorized: Any,
    dense_output: Any,
    max_steps: Any,
    h_min: Any,
) -> tuple[bool, _SolveOptions]:
    """The checked arguments of a solve: `vectorized`, and the options the engine reads as
    its `SolveOptions` (a dict keyed by the fields' names). Checked in the order of the
    public signature (method and jac aside), so that the first bad argument is the one
    reported."""
    span = _t_span(t_span)
    step, step_max = _float_or_none("h", h), _float_or_none("h_max", h_max)
    tolerances = _checks.real("rtol", rtol), _checks.real("atol", atol)
    times = _t_eval(t_eval)
    batch = _checks.boolean("vectorized", vectorized)
    dense = _checks.boolean("dense_output", dense_output)
    options: _SolveOptions = {
        "t_span": span,
        "h": step,
        "h_max": step_max,
        "rtol": tolerances[0],
        "atol": tolerances[1],
        "t_eval": times,
        "dense_output": dense,
        "max_steps": _count("max_steps", max_steps),
        "h_min": _float_or_none("h_min", h_min),
    }
    return batch, options


def _count(name: str, value: Any) -> int:
    return _checks.integer(name, value, 1, 2**63 - 1, what=f"{name} must be an integer >= 1")


def _float_or_none(name: str, value: Any) -> float | None:
    return _checks.real(name, value, optional=True)


def _callable(name: str, value: Any) -> None:
    if not callable(value):
        raise TypeError(f"{name} must be a callable, got {type(value).__name__}")
