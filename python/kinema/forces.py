"""Forces for ``kinema.World``: descriptions that a world turns into engine forces.

Each class states its formula and units; the computation runs in the engine, except for
``PythonForce``, which calls your function once per force evaluation with whole arrays.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np


def _vec3(name: str, value: Any) -> list[float]:
    arr = np.asarray(value, dtype=np.float64).reshape(-1)
    if arr.size != 3:
        raise ValueError(f"{name} = {value!r} is invalid: it must be a 3-vector")
    return arr.tolist()


@dataclass(frozen=True)
class Gravity:
    """Uniform gravity: F_i = m_i g (N); g in m/s², default (0, 0, −9.81) (z is up)."""

    g: Any = (0.0, 0.0, -9.81)

    def _attach(self, core: Any) -> None:
        core.add_gravity(_vec3("g", self.g))


@dataclass(frozen=True)
class Drag:
    """Drag: F_i = −b₁ v_i − b₂ |v_i| v_i (N); b₁ = ``linear`` in kg/s, b₂ = ``quadratic`` in kg/m."""

    linear: float = 0.0
    quadratic: float = 0.0

    def _attach(self, core: Any) -> None:
        core.add_drag(float(self.linear), float(self.quadratic))


@dataclass(frozen=True)
class Spring:
    """Springs between particles i[s] and j[s]: Hooke's law plus a dashpot along the spring,
    F_i = [k (L − L₀) + c (v_j − v_i)·n] n = −F_j, n the unit vector from i to j, L its length.

    ``k`` in N/m, ``rest_length`` L₀ in m (None: the current distance when added), ``damping``
    c in N·s/m. Scalars broadcast over the index arrays, so one object holds many springs.
    """

    i: Any
    j: Any
    k: Any
    rest_length: Any = None
    damping: Any = 0.0

    def _attach(self, core: Any) -> None:
        i = np.atleast_1d(np.asarray(self.i)).astype(np.int64, copy=False)
        j = np.atleast_1d(np.asarray(self.j)).astype(np.int64, copy=False)
        if i.shape != j.shape or i.ndim != 1:
            raise ValueError(f"Spring: i has shape {i.shape} and j {j.shape}; they must be 1-D and equal")
        if (i < 0).any() or (j < 0).any():
            raise ValueError("Spring: particle indices must be >= 0")
        n = i.size

        def per_spring(name: str, value: Any) -> list[float]:
            arr = np.broadcast_to(np.asarray(value, dtype=np.float64), (n,))
            return arr.tolist()

        rest = None if self.rest_length is None else per_spring("rest_length", self.rest_length)
        core.add_springs(i.tolist(), j.tolist(), per_spring("k", self.k), rest, per_spring("damping", self.damping))


@dataclass(frozen=True)
class Attractor:
    """Inverse-square pull toward a fixed point: F_i = −μ m_i r / (|r|² + ε²)^{3/2}, r = x_i − point.

    ``strength`` μ = G·M in m³/s², ``softening`` ε in m.
    """

    point: Any = (0.0, 0.0, 0.0)
    strength: float = 1.0
    softening: float = 0.0

    def _attach(self, core: Any) -> None:
        core.add_attractor(_vec3("point", self.point), float(self.strength), float(self.softening))


@dataclass(frozen=True)
class Wind:
    """A uniform wind field: F_i = b (w − v_i), drag relative to air moving at ``velocity`` w
    (m/s), ``coefficient`` b in kg/s."""

    velocity: Any = (1.0, 0.0, 0.0)
    coefficient: float = 1.0

    def _attach(self, core: Any) -> None:
        core.add_wind(_vec3("velocity", self.velocity), float(self.coefficient))


@dataclass(frozen=True)
class PythonForce:
    """Your own force: ``fn(t, x, v) -> F`` receives positions and velocities as (N, 3) arrays
    (m, m/s) and returns forces (N) of the same shape; called once per force evaluation."""

    fn: Callable[[float, np.ndarray, np.ndarray], Any]
    name: str = "python"

    def _attach(self, core: Any) -> None:
        if not callable(self.fn):
            raise TypeError(f"PythonForce.fn must be a callable, got {type(self.fn).__name__}")
        core.add_python_force(self.fn, str(self.name))
