"""Forces for `kinema.World`: descriptions that a world turns into engine forces.

Each class states its formula and units; the computation runs in the engine, except for
`PythonForce`, which calls your function once per force evaluation with whole arrays.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import _checks

STANDARD_GRAVITY = 9.81
"""The default gravity's magnitude, m/s² (one home: ``Gravity`` and the scenes use it)."""


def _vec3(name: str, value: Any) -> list[float]:
    arr = _checks.real_array(name, value).reshape(-1)
    if arr.size != 3:
        raise ValueError(f"{name} = {_checks.describe(value)} is invalid: it must be a 3-vector")
    return arr.tolist()


def _vec(name: str, value: Any, unit: str) -> list[float]:
    """A force's vector as 3 numbers: [x, y, z], or [x, y] meaning (x, y, 0), the scene
    file's rule (so ``Gravity([0, -9.81])`` in a 2D world is ``g = [0, -9.81]`` in its scene)."""
    arr = _checks.real_array(name, value).reshape(-1)
    if arr.size == 2:
        return [*arr.tolist(), 0.0]
    if arr.size != 3:
        raise ValueError(
            f"{name} = {_checks.describe(value)} is invalid: it has {arr.size} component{'' if arr.size == 1 else 's'}; "
            f"give [x, y, z] or, as in a scene file, [x, y] meaning (x, y, 0) ({unit})"
        )
    return arr.tolist()


class _Checked:
    """Checks its values when built (a bad one raises there, naming it) and keeps them,
    converted, for the world it is added to; the fields keep what was given."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "_args", self._checked())

    def _checked(self) -> tuple:  # pragma: no cover - every force overrides it
        raise NotImplementedError


@dataclass(frozen=True)
class Gravity(_Checked):
    """Uniform gravity: F_i = m_i g (N); g in m/s². The default is down at 9.81 m/s²: along −z
    in a 3D world (z is up), along −y in a 2D world (the xy-plane, y up), as a scene's
    `[[forces]] type = "gravity"` without `g`. A 2-vector ``g = [gx, gy]`` means (gx, gy, 0),
    as in a scene file."""

    g: Any = None

    def _checked(self) -> tuple:
        return (None if self.g is None else _vec("g", self.g, "m/s²"),)

    def vector(self, dim: int) -> list[float]:
        """g (m/s²) in a world of ``dim`` 2 or 3: the one given, else the default down."""
        (g,) = self._args
        if g is None:
            g = [0.0, -STANDARD_GRAVITY, 0.0] if dim == 2 else [0.0, 0.0, -STANDARD_GRAVITY]
        return list(g)

    def _attach(self, core: Any) -> None:
        core.add_gravity(self.vector(core.dim))


@dataclass(frozen=True)
class Drag(_Checked):
    """Drag: F_i = −b₁ v_i − b₂ |v_i| v_i (N); b₁ = `linear` in kg/s, b₂ = `quadratic` in kg/m."""

    linear: float = 0.0
    quadratic: float = 0.0

    def _checked(self) -> tuple:
        return _checks.real("linear", self.linear), _checks.real("quadratic", self.quadratic)

    def _attach(self, core: Any) -> None:
        core.add_drag(*self._args)


@dataclass(frozen=True)
class Spring(_Checked):
    """Springs between particles i[s] and j[s]: Hooke's law plus a dashpot along the spring,
    F_i = [k (L − L₀) + c (v_j − v_i)·n] n = −F_j, n the unit vector from i to j, L its length.

    `k` in N/m, `rest_length` L₀ in m (None: the current distance when added), `damping`
    c in N·s/m. Scalars broadcast over the index arrays, so one object holds many springs.
    Indices are integers (ints, NumPy integers or integer arrays; not floats, not bools) >= 0.
    """

    i: Any
    j: Any
    k: Any
    rest_length: Any = None
    damping: Any = 0.0

    def _checked(self) -> tuple:
        i = _checks.index_array("i", self.i)
        j = _checks.index_array("j", self.j)
        if i.shape != j.shape:
            raise ValueError(f"Spring: i has shape {i.shape} and j {j.shape}; they must be 1-D and equal")
        n = i.size

        def per_spring(name: str, value: Any) -> list[float]:
            arr = _checks.real_array(name, value)
            return _checks.broadcast(name, arr, (n,), f"a scalar or one value per spring, ({n},)").tolist()

        rest = None if self.rest_length is None else per_spring("rest_length", self.rest_length)
        return i.tolist(), j.tolist(), per_spring("k", self.k), rest, per_spring("damping", self.damping)

    def _attach(self, core: Any) -> list[float]:
        return core.add_springs(*self._args)  # the rest lengths, taken from the positions when not given


@dataclass(frozen=True)
class Attractor(_Checked):
    """Inverse-square pull toward a fixed point: F_i = −μ m_i r / (|r|² + ε²)^{3/2}, r = x_i − point.

    `strength` μ = G·M in m³/s², `softening` ε in m; `point` [x, y, z] or [x, y] (z = 0), m.
    """

    point: Any = (0.0, 0.0, 0.0)
    strength: float = 1.0
    softening: float = 0.0

    def _checked(self) -> tuple:
        return _vec("point", self.point, "m"), _checks.real("strength", self.strength), _checks.real("softening", self.softening)

    def _attach(self, core: Any) -> None:
        core.add_attractor(*self._args)


@dataclass(frozen=True)
class Wind(_Checked):
    """A uniform wind field: F_i = b (w − v_i), drag relative to air moving at `velocity` w
    (m/s; [x, y, z] or [x, y] meaning (x, y, 0)), `coefficient` b in kg/s."""

    velocity: Any = (1.0, 0.0, 0.0)
    coefficient: float = 1.0

    def _checked(self) -> tuple:
        return _vec("velocity", self.velocity, "m/s"), _checks.real("coefficient", self.coefficient)

    def _attach(self, core: Any) -> None:
        core.add_wind(*self._args)


@dataclass(frozen=True)
class PythonForce(_Checked):
    """Your own force: `fn(t, x, v) -> F` receives positions and velocities as (N, 3) arrays
    (m, m/s) and returns forces (N) of the same shape; called once per force evaluation."""

    fn: Callable[[float, np.ndarray, np.ndarray], Any]
    name: str = "python"

    def _checked(self) -> tuple:
        if not callable(self.fn):
            raise TypeError(f"fn = {_checks.describe(self.fn)} is invalid: PythonForce.fn must be a callable fn(t, x, v) -> F, not {type(self.fn).__name__}")
        return self.fn, _checks.text("name", self.name)

    def _attach(self, core: Any) -> None:
        core.add_python_force(*self._args)
