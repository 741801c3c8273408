"""Static colliders for ``kinema.World``: planes, boxes and sphere obstacles.

A collider never moves and has infinite mass. Add one with ``world.add(...)``, which turns
collisions on (with ``World.set_collisions``' defaults if they were off). Its values are
checked by the engine when it is added; a bad one is a ``ValueError`` that names it.

``restitution`` e ∈ [0, 1] and ``friction`` μ ≥ 0 are the collider's own: where set, they
override the particle's value for every contact with it (a dead floor, e = 0, stops a bouncy
ball); ``None`` uses the particle's value (its own, else the world's).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from . import _checks
from .forces import _vec3


def _surface(c: Any) -> tuple[float | None, float | None]:
    return _checks.real("restitution", c.restitution, optional=True), _checks.real("friction", c.friction, optional=True)


class Collider:
    """Base of the colliders (a world tells them from forces by it). A collider checks its
    values' types when built (a bad one raises there, naming it); the engine checks their
    ranges when it is added."""

    __slots__ = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "_args", self._checked())

    def _checked(self) -> tuple:  # pragma: no cover - every collider overrides it
        raise NotImplementedError

    def _attach(self, core: Any) -> int:  # pragma: no cover - every collider overrides it
        raise NotImplementedError


@dataclass(frozen=True)
class Plane(Collider):
    """The plane through ``point`` (m) with ``normal`` (non-zero, normalised by the engine):
    particles stay on the side the normal points to. In a 2D world the normal lies in the
    xy-plane."""

    point: Any
    normal: Any
    restitution: float | None = None
    friction: float | None = None

    def _checked(self) -> tuple:
        return _vec3("point", self.point), _vec3("normal", self.normal), *_surface(self)

    def _attach(self, core: Any) -> int:
        return core.add_plane(*self._args)


@dataclass(frozen=True)
class Box(Collider):
    """The axis-aligned box [lo, hi] (m, hi > lo along each axis) that keeps particles inside.

    3 values per corner in a 3D world; 2 (x, y) in a 2D world, where it is a rectangle open
    along z. A bound may be infinite (−inf for ``lo``, +inf for ``hi``): that face has no
    wall. Its sides also give the cell of periodic axes (``World.periodic``)."""

    lo: Any
    hi: Any
    restitution: float | None = None
    friction: float | None = None

    def _checked(self) -> tuple:
        lo = _checks.real_array("lo", self.lo).reshape(-1).tolist()
        hi = _checks.real_array("hi", self.hi).reshape(-1).tolist()
        return lo, hi, *_surface(self)

    def _attach(self, core: Any) -> int:
        return core.add_box(*self._args)


@dataclass(frozen=True)
class SphereObstacle(Collider):
    """A fixed sphere (a circle in 2D) of ``center`` (m) and ``radius`` (m, ≥ 0) that keeps
    particles outside. In a 2D world its centre has z = 0."""

    center: Any
    radius: float
    restitution: float | None = None
    friction: float | None = None

    def _checked(self) -> tuple:
        return _vec3("center", self.center), _checks.real("radius", self.radius), *_surface(self)

    def _attach(self, core: Any) -> int:
        return core.add_sphere_obstacle(*self._args)
