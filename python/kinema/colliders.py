"""Colliders for `kinema.World`: planes, boxes, sphere obstacles and triangle meshes, still
or moving by a prescribed motion (`Motion`: steady; `Keyframes`).

A collider has infinite mass: nothing the particles do moves it. It stays where it was placed,
or follows its `motion` (the `motion=` keyword of every collider, or
`World.set_motion`): its placement and its surface's velocity at each contact are the
motion's (docs/collisions.md, "Moving colliders"). Add one with `world.add(...)`, which
turns collisions on (with `World.set_collisions`' defaults if they were off). Its values are
checked by the engine when it is added; a bad one is a `ValueError` that names it.

`restitution` e ∈ [0, 1] and `friction` μ ≥ 0 are the collider's own: where set, they
override the particle's value for every contact with it (a dead floor, e = 0, stops a bouncy
ball); `None` uses the particle's value (its own, else the world's).

`collides_with`: the collision groups (integers in 0..31, `World.groups`) whose particles the
collider stops; the others pass through it (Box2D's mask bits). `None` (the default): every group.
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from . import _checks
from .collider_motion import MOTIONS as MOTIONS
from .collider_motion import Keyframes as Keyframes
from .collider_motion import Motion as Motion
from .collider_motion import _finite3 as _finite3
from .collider_motion import _motion_of as _motion_of
from .collider_motion import _rows as _rows
from .collider_motion import quaternion as quaternion
from .collider_motion import rotation_matrix as rotation_matrix
from .forces import _vec3


def _surface(c: Any) -> tuple[float | None, float | None]:
    return _checks.real("restitution", c.restitution, optional=True), _checks.real("friction", c.friction, optional=True)


class Collider:
    """Base of the colliders (a world tells them from forces by it). A collider checks its
    values' types when built (a bad one raises there, naming it); the engine checks their
    ranges when it is added. `motion`: a `Motion`, `Keyframes` or None (still)."""

    __slots__ = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "motion", _motion_of(self.motion))
        object.__setattr__(self, "_args", self._checked())
        object.__setattr__(self, "collides_with", _collides_with(self.collides_with))

    @property
    def _group_mask(self) -> int:
        """The groups it collides with as a 32-bit mask (every bit: all)."""
        return _checks.group_mask("collides_with", self.collides_with)

    def _moved(self, motion: Any) -> Collider:
        """This collider with another `motion` (`World.set_motion` keeps it so)."""
        return dataclasses.replace(self, motion=motion)

    def _checked(self) -> tuple:  # pragma: no cover - every collider overrides it
        raise NotImplementedError

    def _attach(self, core: Any) -> int:  # pragma: no cover - every collider overrides it
        raise NotImplementedError


@dataclass(frozen=True)
class Plane(Collider):
    """The plane through `point` (m) with `normal` (non-zero, normalised by the engine):
    particles stay on the side the normal points to. In a 2D world the normal lies in the
    xy-plane. `motion`: a `Motion` or `Keyframes` that moves it (None: still)."""

    point: Any
    normal: Any
    restitution: float | None = None
    friction: float | None = None
    motion: Motion | Keyframes | None = None
    collides_with: Any = None

    def _checked(self) -> tuple:
        return _vec3("point", self.point), _vec3("normal", self.normal), *_surface(self)

    def _attach(self, core: Any) -> int:
        return core.add_plane(*self._args)


@dataclass(frozen=True)
class Box(Collider):
    """The axis-aligned box [lo, hi] (m, hi > lo along each axis) that keeps particles inside.

    3 values per corner in a 3D world; 2 (x, y) in a 2D world, where it is a rectangle open
    along z. A bound may be infinite (−inf for `lo`, +inf for `hi`): that face has no
    wall. Its sides also give the cell of periodic axes (`World.periodic`).

    `motion`: a `Motion` or `Keyframes` that translates it (None: still). A box stays
    axis-aligned: a motion that turns it is refused (`motion = ... is invalid`); a turning
    container is a closed `Mesh` with `inside=True`."""

    lo: Any
    hi: Any
    restitution: float | None = None
    friction: float | None = None
    motion: Motion | Keyframes | None = None
    collides_with: Any = None

    def _checked(self) -> tuple:
        if self.motion is not None and self.motion.turns:
            raise ValueError(
                f"motion = {self.motion!r} is invalid: a Box stays axis-aligned and can only translate; "
                "a turning container is a closed kinema.Mesh with inside=True"
            )
        lo = _checks.real_array("lo", self.lo).reshape(-1).tolist()
        hi = _checks.real_array("hi", self.hi).reshape(-1).tolist()
        return lo, hi, *_surface(self)

    def _attach(self, core: Any) -> int:
        return core.add_box(*self._args)


@dataclass(frozen=True)
class SphereObstacle(Collider):
    """A fixed sphere (a circle in 2D) of `center` (m) and `radius` (m, ≥ 0) that keeps
    particles outside. In a 2D world its centre has z = 0. `motion`: a `Motion` or
    `Keyframes` that moves it (None: still; a turn about its centre moves only its surface,
    which then drags particles by friction)."""

    center: Any
    radius: float
    restitution: float | None = None
    friction: float | None = None
    motion: Motion | Keyframes | None = None
    collides_with: Any = None

    def _checked(self) -> tuple:
        return _vec3("center", self.center), _checks.real("radius", self.radius), *_surface(self)

    def _attach(self, core: Any) -> int:
        return core.add_sphere_obstacle(*self._args)


class Mesh(Collider):
    """A triangle mesh (3D worlds only), from a file or from arrays, still or moving:

        kinema.Mesh("bowl.obj", scale=1.0, rotation=(0, 0, 0), translation=(0, 0, 0), inside=False)
        kinema.Mesh(vertices=V, faces=F)
        kinema.Mesh("drum.obj", inside=True, motion=kinema.Motion(angular_velocity=(0, 1.5, 0)))

    `file`: a mesh file, OBJ (.obj), STL (.stl), PLY (.ply), glTF (.gltf, .glb) or USD
    (.usd, .usda, .usdc, .usdz; needs `pip install usd-core`), read by
    `kinema.io.mesh_files.read_mesh`: polygons cut into triangles, a file of several meshes
    taken whole, vertices of equal coordinates made one. Its coordinates are metres. Or
    `vertices` (V, 3), m, and `faces` (F, 3), the indices of each triangle's three vertices
    (integers, from 0).

    `up_axis`: which way is up in the file (the arrays): "z" (kinema's own: gravity points
    along −z) or "y" (Blender's OBJ export, Maya, Unity, three.js); a +y-up mesh is turned so
    that its +y is +z, (x, y, z) → (x, −z, y) (+90° about x). OBJ, STL, PLY and arrays say
    no axis: None means "z". glTF (+y up by its specification) and USD (its stage's
    `upAxis`) say theirs and are always read by it; an `up_axis` that disagrees is refused.
    `Mesh.up_axis` is the one read with. A +y-up file read as +z-up lies on its side: a
    `MeshPlacementWarning` says so at the first step under gravity (`kinema.colliders`).

    The vertices are then scaled, rotated and translated, in that order, about the origin of
    the file's (the arrays') coordinates, +z up: x' = R (s ⊙ x) + t, with

    - `scale` s: one factor or three (x, y, z), each finite and non-zero (a negative one
      mirrors);
    - `rotation` (α, β, γ): Euler angles in degrees about the fixed x, then y, then z axis
      (extrinsic XYZ, Blender's default 'XYZ' rotation mode): R = R_z(γ) R_y(β) R_x(α);
    - `translation` t (m).

    `vertices` (V, 3) float64 (after the transform) and `faces` (F, 3) int64 are
    read-only arrays; `file` is the `Path` given (None for arrays).

    A *closed* mesh (every edge shared by exactly two faces running along it in opposite
    directions) bounds a solid: particles stay outside it (an obstacle), or inside it with
    `inside=True` (a container). An *open* mesh is two-sided: a particle stays on the side
    it is on, and `inside=True` is refused. The engine drops faces of zero area and turns a
    closed mesh's faces outwards (docs/collisions.md, "Triangle meshes").

    `motion`: a `Motion` or `Keyframes` that moves the mesh from this placement (the
    vertices after the transform; None: still).

    Refused when built, a `ValueError` naming the parameter: a file and arrays both given,
    or neither; a missing file, an unknown suffix (the formats read are listed), a file that
    cannot be read; arrays of the wrong shape; a non-finite vertex (named at its own
    coordinate); a zero or non-finite scale, rotation or translation (a wrong type is a
    `TypeError`); a coordinate beyond `MESH_LIMIT` (1e75 m) after the transform. The engine
    checks the rest when the mesh is added (an index out of range, a face with a repeated
    vertex, no face of non-zero area, a 2D world).
    """

    __slots__ = (
        "_file",
        "_vertices",
        "_faces",
        "_up_axis",
        "_scale",
        "_rotation",
        "_translation",
        "_inside",
        "_restitution",
        "_friction",
        "_motion",
        "_args",
        "_closed",
        "_collides_with",
    )

    def __init__(
        self,
        file: str | os.PathLike | None = None,
        *,
        vertices: Any = None,
        faces: Any = None,
        up_axis: str | None = None,
        scale: Any = 1.0,
        rotation: Any = (0.0, 0.0, 0.0),
        translation: Any = (0.0, 0.0, 0.0),
        inside: bool = False,
        restitution: float | None = None,
        friction: float | None = None,
        motion: Motion | Keyframes | None = None,
        collides_with: Any = None,
    ) -> None:
        motion = _motion_of(motion)
        collides_with = _collides_with(collides_with)
        arrays = vertices is not None or faces is not None
        if file is not None and arrays:
            given = " and ".join(n for n, v in (("vertices", vertices), ("faces", faces)) if v is not None)
            raise ValueError(f"file = {_checks.describe(_text(file))} and {given} are given: give either a file or vertices and faces, not both")
        if file is None and not arrays:
            raise ValueError("Mesh needs a file (Mesh('bowl.obj')) or vertices and faces (Mesh(vertices=V, faces=F)); neither is given")
        from .io.mesh_files import check_up_axis, read_mesh_axis, y_up_to_z_up

        up = check_up_axis(up_axis)
        s = _factors(scale)
        rot = _vec3("rotation", rotation)
        t = _vec3("translation", translation)
        for name, value in (("rotation", rot), ("translation", t)):
            if not all(math.isfinite(c) for c in value):
                raise ValueError(f"{name} = {_checks.describe(value)} is invalid: it must be 3 finite numbers ({'degrees' if name == 'rotation' else 'm'})")
        if file is not None:
            if not isinstance(file, (str, os.PathLike)):
                raise TypeError(f"file = {_checks.describe(file)} is invalid: it must be a path (a str or a pathlib.Path), not {_checks._type_words(file)}")
            path = Path(file)
            v, f, up = read_mesh_axis(path, "file", up)
        else:
            path = None
            if vertices is None or faces is None:
                missing = "faces" if faces is None else "vertices"
                raise ValueError(f"{missing} is missing: a mesh from arrays needs both vertices (V, 3), m, and faces (F, 3), vertex indices")
            v = _checks.real_array("vertices", vertices)
            if v.ndim != 2 or v.shape[1] != 3 or v.shape[0] == 0:
                raise ValueError(f"vertices has shape {v.shape}; it must be (V, 3): x, y, z (m) of each vertex")
            f = _indices(faces)
            bad = np.argwhere(~np.isfinite(v))
            if len(bad):
                i, k = (int(x) for x in bad[0])
                raise ValueError(f"vertices[{i}][{k}] = {_checks.describe(v[i, k])} is invalid: a mesh's vertices must be finite, m")
            up = up or "z"
            if up == "y":
                v = y_up_to_z_up(v)
        with np.errstate(over="ignore", invalid="ignore"):
            v = transformed(v, s, rot, t)
        far = np.argwhere(~(np.abs(v) <= MESH_LIMIT))
        if len(far):
            i, k = (int(x) for x in far[0])
            placed = (
                ""
                if (tuple(s) == (1.0, 1.0, 1.0) and tuple(t) == (0.0, 0.0, 0.0) and tuple(rot) == (0.0, 0.0, 0.0))
                else " after scale, rotation and translation"
            )
            source = f" (file {str(path)!r})" if path is not None else ""
            raise ValueError(
                f"vertices[{i}][{k}] = {_checks.describe(float(v[i, k]))} m{placed}{source} is invalid: a mesh's coordinates must be finite "
                f"and at most {MESH_LIMIT:g} m in magnitude (the contacts' triangle geometry takes fourth powers of lengths)"
            )
        v.flags.writeable = False
        f = np.ascontiguousarray(f, dtype=np.int64)
        f.flags.writeable = False
        inside = _checks.boolean("inside", inside)
        surface = _surface_values(restitution, friction)
        for name, value in (
            ("_file", path),
            ("_vertices", v),
            ("_faces", f),
            ("_up_axis", up),
            ("_scale", tuple(s)),
            ("_rotation", tuple(rot)),
            ("_translation", tuple(t)),
            ("_inside", inside),
            ("_restitution", restitution),
            ("_friction", friction),
            ("_motion", motion),
            ("_args", (v, f, inside, *surface)),
            ("_closed", None),
            ("_collides_with", collides_with),
        ):
            object.__setattr__(self, name, value)

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"a Mesh cannot be changed (its {name!r} is read-only); make a new one")

    @property
    def file(self) -> Path | None:
        """The mesh file given, or None for a mesh of arrays."""
        return self._file

    @property
    def vertices(self) -> np.ndarray:
        """(V, 3) float64, m: the vertices after scale, rotation and translation (read-only)."""
        return self._vertices

    @property
    def faces(self) -> np.ndarray:
        """(F, 3) int64: each triangle's three vertex indices (read-only)."""
        return self._faces

    @property
    def up_axis(self) -> str:
        """The up axis the file (the arrays) was read with, "z" or "y" (turned to +z)."""
        return self._up_axis

    @property
    def scale(self) -> tuple[float, float, float]:
        """The scale factors along x, y, z applied to the file's (the arrays') vertices."""
        return self._scale

    @property
    def rotation(self) -> tuple[float, float, float]:
        """Euler angles in degrees about the fixed x, y, z axes, in that order."""
        return self._rotation

    @property
    def translation(self) -> tuple[float, float, float]:
        """The translation (m), applied last."""
        return self._translation

    @property
    def inside(self) -> bool:
        """Whether particles live inside this (closed) mesh: a container."""
        return self._inside

    @property
    def restitution(self) -> float | None:
        return self._restitution

    @property
    def friction(self) -> float | None:
        return self._friction

    @property
    def motion(self) -> Motion | Keyframes | None:
        """The mesh's prescribed motion, or None (still)."""
        return self._motion

    @property
    def collides_with(self) -> tuple[int, ...] | None:
        """The collision groups it stops (None: every group)."""
        return self._collides_with

    def _moved(self, motion: Any) -> Mesh:
        """This mesh with another `motion` (`World.set_motion` keeps it so)."""
        out = Mesh.__new__(Mesh)
        for name in Mesh.__slots__:
            object.__setattr__(out, name, getattr(self, name))
        object.__setattr__(out, "_motion", _motion_of(motion))
        return out

    def __repr__(self) -> str:
        source = repr(str(self._file)) if self._file is not None else "vertices=..., faces=..."
        moving = f", motion={self._motion!r}" if self._motion is not None else ""
        return f"Mesh({source}, {len(self._vertices)} vertices, {len(self._faces)} triangles, inside={self._inside}{moving})"

    def _attach(self, core: Any) -> int:
        return core.add_mesh(*self._args)

    def _contains(self, p: Any) -> bool:
        """Whether the point `p` (m) lies where no particle may be: inside a closed obstacle,
        outside a closed container; never for an open mesh (two-sided). By the winding number
        of the surface about p (the sum of the solid angles of its triangles over 4π, Van
        Oosterom and Strackee's formula): 1 inside, 0 outside."""
        if self._closed is None:
            object.__setattr__(self, "_closed", _is_closed(self._vertices, self._faces))
        if not self._closed:
            return False
        a, b, c = (self._vertices[self._faces[:, k]] - np.asarray(p, float)[:3] for k in range(3))
        la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
        # tan(Ω/2) = a·(b × c) / (|a||b||c| + (a·b)|c| + (a·c)|b| + (b·c)|a|)
        num = np.einsum("ij,ij->i", a, np.cross(b, c))
        den = la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", a, c) * lb + np.einsum("ij,ij->i", b, c) * la
        winding = abs(float(np.sum(2.0 * np.arctan2(num, den))) / (4.0 * math.pi))
        return winding < 0.5 if self._inside else winding > 0.5


class MeshPlacementWarning(UserWarning):
    """A mesh collider placed where it will likely do nothing, or lying on its side (see
    `placement_problems`): said once per mesh, at the first `World.step` or `World.run` after
    it is added."""


#: The largest magnitude (m) of a mesh's coordinate after its transform: the engine's triangle
#: geometry squares cross products of edges (fourth powers of lengths), which overflow float64
#: (1.8e308) near 1e77 m; a floor of half-width 1e78 m let a ball through. (A particle's radius
#: may reach the contacts' GEOMETRY_LIMIT, 1e150 m: its geometry squares lengths only.)
MESH_LIMIT = 1e75

#: An open mesh is "curved" (a bowl, a cup, a chute: it has an opening) when the length of its
#: vector area |Σ A_f n_f| is between these fractions of its area Σ A_f; a flat sheet's is all
#: of it, a tube's or a closed surface's none.
CURVED = (0.05, 0.95)
#: The most the opening's axis may lean from the vertical (degrees) before a mesh is said to
#: lie on its side.
SIDEWAYS_DEG = 60.0


def placement_problems(mesh: Mesh, points: np.ndarray, regions: list[tuple[np.ndarray, np.ndarray]], g: np.ndarray, radius: float | None = None) -> list[str]:
    """What is wrong with where a still mesh collider is, in words (none: []):

    - **far**: there is something to collide (particles at `points` (N, 3) or emitters whose
      source regions are the boxes `regions` [(lo, hi), ...]) and every one of them lies
      outside the mesh's bounding box by more than its size (the box's diagonal L);
    - **on its side**: under gravity `g` (m/s²), an open, curved mesh (its vector area
      |Σ A_f n_f| from 5 % to 95 % of its area Σ A_f: a bowl, a cup, a chute) whose opening's
      axis, the direction of Σ A_f n_f (the rim's normal, the same whichever way its faces
      are wound up to sign), leans more than 60° from the vertical: a bowl lying on its side,
      as a +y-up file read as +z-up lies. Flat sheets, tubes and closed meshes have no
      opening and are never said to lie on their side;
    - **too coarse**: its coordinates reach X m, where float64 numbers are u apart (≤ X·2⁻⁵²),
      more than `COARSE` of the smallest particle `radius` (m; None: no particles): a
      contact's distance near its faces is then off by up to a few u, and a ball can sink
      into it or fall through a seam between two faces (measured: a floor of two triangles
      of half-width 1e14 m lets a 5 cm ball sink 1.7 mm, 1e15 m lets it through, 7 cm from
      the seam; 1e13 m holds it to the last digit)."""
    v, f = mesh.vertices, mesh.faces
    lo, hi = v.min(axis=0), v.max(axis=0)
    size = float(np.linalg.norm(hi - lo))
    said = []
    far = [float(np.linalg.norm(np.maximum(np.maximum(lo - points, points - hi), 0.0), axis=1).min())] if len(points) else []
    far += [float(np.linalg.norm(np.maximum(np.maximum(lo - r_hi, r_lo - hi), 0.0))) for r_lo, r_hi in regions]
    if far and min(far) > size:
        said.append(
            f"every particle and emitter lies outside its bounding box {lo.tolist()} to {hi.tolist()} m by more than its size "
            f"({size:.3g} m), the nearest {min(far):.3g} m away: is it placed (translation, scale, up_axis) where they are?"
        )
    gn = float(np.linalg.norm(g))
    if gn > 0 and not _is_closed(v, f):
        a, b, c = (v[f[:, k]] for k in range(3))
        cross = np.cross(b - a, c - a)
        area = float(np.linalg.norm(cross, axis=1).sum())
        axis = cross.sum(axis=0)
        fraction = float(np.linalg.norm(axis)) / area if area > 0 else 0.0
        if CURVED[0] <= fraction <= CURVED[1]:
            lean = math.degrees(math.acos(min(1.0, abs(float(axis @ g)) / (float(np.linalg.norm(axis)) * gn))))
            if lean > SIDEWAYS_DEG:
                up = "" if mesh.up_axis == "y" else " (a +y-up file, as Blender exports OBJ, read as +z-up lies so: give up_axis='y')"
                said.append(
                    f"it lies on its side: the axis of its opening (the direction of its faces' area-weighted normals, "
                    f"{(axis / np.linalg.norm(axis)).round(3).tolist()}) leans {lean:.0f}° from the vertical (gravity {np.round(g, 3).tolist()} m/s²){up}"
                )
    reach = float(np.abs(v).max()) if v.size else 0.0
    spacing = float(np.spacing(reach))
    if radius is not None and radius > 0 and spacing > COARSE * radius:
        said.append(
            f"it is too coarse for the particles: its coordinates reach {reach:.3g} m, where numbers are {spacing:.3g} m apart, "
            f"more than {COARSE:g} of the smallest radius ({radius:.3g} m), so contacts near its faces are off by that much and a "
            "ball can fall through a seam: make it smaller or place it nearer the origin"
        )
    return said


# a mesh's float spacing at its largest coordinate may be at most this fraction of the smallest
# particle radius (`placement_problems`)
COARSE = 0.05


def transformed(vertices: np.ndarray, scale: Any, rotation: Any, translation: Any) -> np.ndarray:
    """x' = R (s ⊙ x) + t for each row x of `vertices` (V, 3), m: `scale` s (3,), then
    `rotation` (α, β, γ) in degrees about the fixed x, y and z axes in that order, R = R_z(γ)
    R_y(β) R_x(α) (extrinsic XYZ, Blender's 'XYZ' mode), then `translation` t (3,), m."""
    scaled = np.asarray(vertices, dtype=np.float64) * np.asarray(scale, dtype=np.float64)
    return scaled @ rotation_matrix(rotation).T + np.asarray(translation, dtype=np.float64)


def _collides_with(value: Any) -> tuple[int, ...] | None:
    """`collides_with` checked: None (every group) or the sorted groups, each once."""
    if value is None:
        return None
    return tuple(sorted({int(g) for g in _checks.groups("collides_with", value).reshape(-1).tolist()}))


def _text(file: Any) -> Any:
    return os.fspath(file) if isinstance(file, os.PathLike) else file


def _surface_values(restitution: Any, friction: Any) -> tuple[float | None, float | None]:
    return _checks.real("restitution", restitution, optional=True), _checks.real("friction", friction, optional=True)


def _factors(scale: Any) -> list[float]:
    """`scale` as 3 factors (one number: the same along each axis), each finite and non-zero."""
    s = _checks.real_array("scale", scale).reshape(-1)
    if s.size == 1:
        s = np.repeat(s, 3)
    if s.size != 3:
        raise ValueError(f"scale = {_checks.describe(scale)} is invalid: it must be one number or 3 (x, y, z)")
    if not (np.all(np.isfinite(s)) and np.all(s != 0)):
        raise ValueError(f"scale = {_checks.describe(scale)} is invalid: each factor must be finite and non-zero (a negative one mirrors)")
    return s.tolist()


def _indices(faces: Any) -> np.ndarray:
    """`faces` as an (F, 3) int64 array: integers only (a float, even 2.0, or a bool is a
    `TypeError` naming it); ranges are the engine's to check."""
    arr = _checks._as_array("faces", faces)
    if isinstance(faces, np.ndarray) and arr.dtype.kind in "iu":
        if arr.dtype.kind == "u" and arr.size and int(arr.max()) > _checks.INT64_MAX:
            raise ValueError(f"faces holds {int(arr.max())}; vertex indices must be below 2**63")
        out = arr.astype(np.int64)
    elif isinstance(faces, np.ndarray) and arr.dtype.kind != "O":
        raise TypeError(f"faces = {_checks.describe(faces)} is invalid: vertex indices must be integers, not {_checks._dtype_words(arr.dtype)}")
    else:
        obj = _checks._objects(faces)
        bad = _checks._first_bad("faces", obj, _checks._is_integer)
        if bad is not None:
            raise TypeError(f"{bad[0]} = {_checks.describe(bad[1])} is invalid: vertex indices must be integers (int), not {_checks._type_words(bad[1])}")
        values = [int(x) for x in obj.reshape(-1).tolist()]
        if values and (max(values) > _checks.INT64_MAX or min(values) < -_checks.INT64_MAX):
            raise ValueError(f"faces holds {max(values, key=abs)}; vertex indices must fit in 64 bits")
        out = np.array(values, dtype=np.int64).reshape(obj.shape)
    if out.ndim != 2 or out.shape[1] != 3 or out.shape[0] == 0:
        raise ValueError(
            f"faces has shape {out.shape}; it must be (F, 3): three vertex indices per triangle, F >= 1 (cut polygons into triangles, or load a file, which does)"
        )
    return out


def _is_closed(vertices: np.ndarray, faces: np.ndarray) -> bool:
    """The engine's rule (collide/mesh.rs): over the faces of non-zero area, every edge is
    shared by exactly two faces that run along it in opposite directions."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    f = faces[np.linalg.norm(np.cross(b - a, c - a), axis=1) > 0.0]
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    if len(np.unique(directed, axis=0)) != len(directed):
        return False  # an edge run twice the same way
    undirected, counts = np.unique(np.sort(directed, axis=1), axis=0, return_counts=True)
    return bool(len(undirected) and np.all(counts == 2))
