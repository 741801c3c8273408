"""The pydantic models of a scene file's [[colliders]]: a plane, a box, a sphere and a triangle
mesh, their surface keys and their motion (steady or keyframes). The mesh's shape and
placement, ``MeshShape``, is also an emitter's ``mesh``.
``kinema.scene.tables`` re-exports them; this module imports only ``kinema.scene.values`` of
the scene package."""

from __future__ import annotations

import math
import os
from typing import Annotated, Any, Literal

from pydantic import Discriminator, Field, Tag, field_validator, model_validator

from .values import Group, NonNeg, Unit, Vec, Vec3, _by_kind, _Model, _typed

# -- [[colliders]] ----------------------------------------------------------------------------
# A collider's `motion` (kinema.Motion, kinema.Keyframes): a steady table, or keyframes (a
# table with `times`), told apart by that key.


def _all_finite(values: Any, name: str, unit: str) -> None:
    flat = values if not values or not isinstance(values[0], list) else [c for row in values for c in row]
    if not all(math.isfinite(c) for c in flat):
        raise ValueError(f"{name} must be finite numbers ({unit})")


class SteadyMotion(_Model):
    """``motion = { velocity = [..], angular_velocity = [..], pivot = [..] }``: translation at
    ``velocity`` (m/s) and a turn at ``angular_velocity`` (rad/s, about its direction) about
    ``pivot`` (m, a point of the collider's placement), from ``start`` (s, on the world's
    clock; left out: from when the collider is added, the scene's time 0)."""

    velocity: Vec = [0.0, 0.0, 0.0]
    angular_velocity: Vec3 = [0.0, 0.0, 0.0]
    pivot: Vec = [0.0, 0.0, 0.0]
    start: float | None = None

    @field_validator("velocity", "angular_velocity", "pivot")
    @classmethod
    def _finite(cls, v: Any, info: Any) -> Any:
        _all_finite(v, info.field_name, {"velocity": "m/s", "angular_velocity": "rad/s"}.get(info.field_name, "m"))
        return v

    @field_validator("start")
    @classmethod
    def _finite_start(cls, v: Any) -> Any:
        if v is not None and not math.isfinite(v):
            raise ValueError(f"start = {v} is invalid: it must be a finite time, s")
        return v

    def turns(self) -> bool:
        return any(c != 0 for c in self.angular_velocity)


class KeyframesMotion(_Model):
    """``[colliders.motion]`` with ``times`` (s, strictly increasing), ``translations`` (m, one
    per time) and ``rotations`` (degrees about the fixed x, then y, then z axis, one per time;
    less than 180° apart about each axis from one key to the next) about ``pivot`` (m)."""

    times: Annotated[list[float], Field(min_length=1)]
    translations: list[Vec] | None = None
    rotations: list[Vec3] | None = None
    pivot: Vec = [0.0, 0.0, 0.0]

    @field_validator("times")
    @classmethod
    def _increasing(cls, v: list[float]) -> list[float]:
        for k, t in enumerate(v):
            if not math.isfinite(t) or (k > 0 and not t > v[k - 1]):
                raise ValueError(f"keyframe times must be finite and strictly increasing, s (times[{k}] = {t:g})")
        return v

    @field_validator("translations", "rotations", "pivot")
    @classmethod
    def _finite(cls, v: Any, info: Any) -> Any:
        if v is not None:
            _all_finite(v, info.field_name, "degrees" if info.field_name == "rotations" else "m")
        return v

    @model_validator(mode="after")
    def _one_per_time(self) -> KeyframesMotion:
        k = len(self.times)
        for name in ("translations", "rotations"):
            rows = getattr(self, name)
            if rows is not None and len(rows) != k:
                raise ValueError(f"{name} has {len(rows)} rows for {k} times; give one per keyframe time")
        for j in range(1, len(self.rotations or [])):
            step = [abs(a - b) for a, b in zip(self.rotations[j], self.rotations[j - 1], strict=True)]
            if max(step) >= 180:
                raise ValueError(
                    f"rotations[{j}] is {max(step):g}° about {'xyz'[step.index(max(step))]} from rotations[{j - 1}]; between two keys a collider "
                    "turns the shorter way (less than 180°): put keys in between"
                )
        return self

    def turns(self) -> bool:
        return any(c != 0 for row in self.rotations or [] for c in row)


def _motion_kind(v: Any) -> str:
    return "~keyframes" if (isinstance(v, dict) and "times" in v) or isinstance(v, KeyframesMotion) else "~steady"


MotionItem = Annotated[Annotated[SteadyMotion, Tag("~steady")] | Annotated[KeyframesMotion, Tag("~keyframes")], Discriminator(_motion_kind)]


class _Surface(_Model):
    restitution: Unit | None = None
    friction: NonNeg | None = None
    motion: MotionItem | None = None
    collides_with: list[Group] | None = None  # the collision groups it stops (None: all)


class PlaneCollider(_Surface):
    type: Literal["plane"] = "plane"
    point: Vec
    normal: Vec


class BoxCollider(_Surface):
    type: Literal["box"] = "box"
    lo: Vec
    hi: Vec

    @field_validator("motion")
    @classmethod
    def _translates(cls, v: Any) -> Any:
        if v is not None and v.turns():
            turn = "angular_velocity" if isinstance(v, SteadyMotion) else "rotations"
            raise ValueError(f"a box stays axis-aligned and can only translate ({turn} must be 0); a turning container is a mesh with inside = true")
        return v


class SphereCollider(_Surface):
    type: Literal["sphere"] = "sphere"
    center: Vec
    radius: NonNeg


class MeshShape(_Model):
    """A triangle mesh's shape and placement (``kinema.Mesh``, 3D only): from ``file`` (OBJ,
    STL, PLY, glTF, USD; a path relative to the scene file) or from ``vertices`` (m) and
    ``faces`` (vertex indices) written in the table, whose up axis is ``up_axis`` ("z",
    kinema's, or "y"; none: the file's own for glTF and USD, else "z"); then scaled by
    ``scale`` (one factor or 3), rotated by ``rotation`` (degrees about the fixed x, then y,
    then z axis) and moved by ``translation`` (m). An emitter's ``mesh``, and the mesh
    collider's keys."""

    file: Annotated[str, Field(min_length=1)] | None = None
    vertices: Annotated[list[Vec3], Field(min_length=1)] | None = None
    faces: Annotated[list[Annotated[list[Annotated[int, Field(ge=0, le=2**32 - 1)]], Field(min_length=3, max_length=3)]], Field(min_length=1)] | None = None
    up_axis: Literal["z", "y"] | None = None
    scale: _by_kind(float, Vec3) = 1.0
    rotation: Vec3 = [0.0, 0.0, 0.0]
    translation: Vec3 = [0.0, 0.0, 0.0]

    @field_validator("file")
    @classmethod
    def _format(cls, v: str | None) -> str | None:
        from ..io.mesh_files import formats_text, mesh_format

        if v is not None and mesh_format(v) is None:
            suffix = os.path.splitext(v)[1]
            raise ValueError(f"unknown mesh format {repr(suffix) if suffix else '(no suffix)'}; the formats read are {formats_text()}")
        return v

    @field_validator("scale")
    @classmethod
    def _factors(cls, v: Any) -> Any:
        if not all(math.isfinite(c) and c != 0 for c in (v if isinstance(v, list) else [v])):
            raise ValueError("each scale factor must be finite and non-zero (a negative one mirrors)")
        return v

    @field_validator("rotation", "translation", "vertices")
    @classmethod
    def _finite(cls, v: Any, info: Any) -> Any:
        rows = v if v is None or not v or not isinstance(v[0], list) else [c for row in v for c in row]
        if rows is not None and not all(math.isfinite(c) for c in rows):
            unit = "degrees" if info.field_name == "rotation" else "m"
            raise ValueError(f"{info.field_name} must be finite numbers ({unit})")
        return v

    @model_validator(mode="after")
    def _source(self) -> Any:
        arrays = self.vertices is not None or self.faces is not None
        if self.file is not None and arrays:
            raise ValueError("give either file or vertices and faces, not both")
        if self.file is None and not (self.vertices is not None and self.faces is not None):
            raise ValueError("a mesh needs file (a mesh file beside the scene) or both vertices and faces")
        return self


class MeshCollider(_Surface, MeshShape):
    """A triangle mesh collider (``kinema.Mesh``): ``MeshShape``'s keys, and ``inside``:
    particles live inside this closed mesh (a container)."""

    type: Literal["mesh"] = "mesh"
    inside: bool = False


ColliderItem = _typed(PlaneCollider, BoxCollider, SphereCollider, MeshCollider)
