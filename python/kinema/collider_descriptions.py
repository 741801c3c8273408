"""Colliders as plain descriptions (the dicts `Trajectory.colliders` holds), the form the
engine's `_core.Scenery` takes them in, and where a moving one is at given times
(`collider_poses`, from its description's `motion`).

Below everything that writes, reads or draws colliders: the world (`World.colliders`'
descriptions), the trajectory files (`kinema.io`), the checkpoints, the pictures
(`kinema.render`, which keeps these names as `kinema.render.descriptions`) and the viewer.
It imports only `kinema.colliders` and the engine, so none of those is tied into a circle
with another through it (tests/test_no_import_circles.py)."""

from __future__ import annotations

import numpy as np

from . import _core
from ._checks import describe
from .colliders import MOTIONS, Box, Mesh, Plane, SphereObstacle

_KIND = {"plane": ("point", "normal"), "box": ("lo", "hi"), "sphere": ("center", "radius"), "mesh": ("vertices", "faces")}


def _describe_colliders(colliders) -> list[dict]:
    """Plain descriptions of colliders (`kinema.Plane`, `Box`, `SphereObstacle`,
    `Mesh` or such descriptions already): {"type": "plane", "point": [3], "normal": [3]},
    {"type": "box", "lo": [2 or 3], "hi": [2 or 3]} (bounds may be ±inf), {"type": "sphere",
    "center": [3], "radius": r}, {"type": "mesh", "vertices": [[x, y, z], ...] (m, after the
    mesh's transform), "faces": [[i, j, k], ...] (ints), "inside": bool}, with "restitution"
    and "friction" where the collider sets them, and "motion" where it moves: {"velocity":
    [3] m/s, "angular_velocity": [3] rad/s, "pivot": [3] m} (steady) or {"times": [K] s,
    "translations": [K][3] m, "rotations": [K][4] unit quaternions (w, x, y, z), "pivot": [3]
    m} (keyframes) — the geometry is the placement as added, which the motion moves
    (`collider_poses`)."""

    def floats(name, value, sizes=(3,)):
        a = np.asarray(value, dtype=np.float64).reshape(-1)
        if a.size not in sizes:
            raise ValueError(f"{name} = {value!r} is invalid: it must have {' or '.join(map(str, sizes))} values")
        return a.tolist()

    out = []
    for k, c in enumerate(colliders):
        if isinstance(c, Plane):
            d = {"type": "plane", "point": c.point, "normal": c.normal}
        elif isinstance(c, Box):
            d = {"type": "box", "lo": c.lo, "hi": c.hi}
        elif isinstance(c, SphereObstacle):
            d = {"type": "sphere", "center": c.center, "radius": c.radius}
        elif isinstance(c, Mesh):
            d = {"type": "mesh", "vertices": c.vertices, "faces": c.faces, "inside": c.inside}
        elif isinstance(c, dict) and c.get("type") in _KIND:
            d = dict(c)
        else:
            raise ValueError(
                f"colliders[{k}] = {describe(c)} is invalid: use kinema.Plane, Box or SphereObstacle (or kinema.Mesh), or a description "
                "{'type': 'plane' | 'box' | 'sphere' | 'mesh', ...} (Trajectory.colliders)"
            )
        try:
            if d["type"] == "box":
                d["lo"], d["hi"] = floats(f"colliders[{k}].lo", d["lo"], (2, 3)), floats(f"colliders[{k}].hi", d["hi"], (2, 3))
            elif d["type"] == "sphere":
                d["center"], d["radius"] = floats(f"colliders[{k}].center", d["center"]), float(d["radius"])
            elif d["type"] == "mesh":
                d["vertices"], d["faces"] = _mesh_arrays(f"colliders[{k}]", d["vertices"], d["faces"])
                d["inside"] = _flag(f"colliders[{k}].inside", d.get("inside", False))
            else:
                d["point"], d["normal"] = floats(f"colliders[{k}].point", d["point"]), floats(f"colliders[{k}].normal", d["normal"])
        except KeyError as e:
            raise ValueError(f"colliders[{k}] = {describe(c)} is invalid: a {d['type']} needs {' and '.join(_KIND[d['type']])}, it has no {e}") from None
        for name in ("restitution", "friction"):
            value = getattr(c, name, None) if not isinstance(c, dict) else c.get(name)
            if value is not None:
                d[name] = float(value)
            else:
                d.pop(name, None)
        motion = c.get("motion") if isinstance(c, dict) else getattr(c, "motion", None)
        if motion is not None:
            d["motion"] = _motion(f"colliders[{k}].motion", motion)
        else:
            d.pop("motion", None)
        out.append(d)
    return out


#: A motion description's keys: steady, keyframes (``_describe_colliders``).
STEADY_KEYS = ("velocity", "angular_velocity", "pivot", "start")
KEYFRAME_KEYS = ("times", "translations", "rotations", "pivot")


def _motion(name: str, motion) -> dict:
    """A motion's description: from a `kinema.Motion` or `kinema.Keyframes` (its rotations
    as unit quaternions), or a description already, checked (its keys, shapes, and the
    engine's rules, by placing it once)."""
    if isinstance(motion, MOTIONS):
        binding = motion._binding()
        if binding.get("start") == 0.0:
            del binding["start"]  # from the world's time 0: the description has no start
        if "times" in binding:
            k = len(binding["times"])
            binding["translations"] = binding["translations"] or [[0.0, 0.0, 0.0]] * k
            binding["rotations"] = binding["rotations"] or [[1.0, 0.0, 0.0, 0.0]] * k
        return binding
    if not isinstance(motion, dict):
        raise ValueError(f"{name} = {describe(motion)} is invalid: a motion is a kinema.Motion, kinema.Keyframes or its description (a dict)")
    keys = KEYFRAME_KEYS if "times" in motion else STEADY_KEYS
    unknown = sorted(set(motion) - set(keys))
    if unknown:
        kind = "keyframes (they have times)" if keys is KEYFRAME_KEYS else "a steady motion (it has no times)"
        raise ValueError(f"{name} has the key {unknown[0]!r}, which {kind} do not take; the keys are {', '.join(keys)}")
    out = {}
    for key in keys:
        value = motion.get(key)
        if value is None:
            continue
        a = np.asarray(value, dtype=np.float64)
        shape = {"times": (None,), "translations": (None, 3), "rotations": (None, 4), "start": ()}.get(key, (3,))
        if a.ndim != len(shape) or any(want is not None and got != want for got, want in zip(a.shape, shape, strict=True)):
            want = "(" + ", ".join("K" if w is None else str(w) for w in shape) + ("," if len(shape) == 1 else "") + ")"
            raise ValueError(f"{name}.{key} has shape {a.shape}; it must be {want}")
        out[key] = float(a) if key == "start" else a.tolist()
    try:
        _core.collider_poses([0.0], **out)  # the engine's checks (finite, increasing times, one key each)
    except ValueError as e:
        raise ValueError(f"{name}: {e}") from None
    return out


def collider_poses(description: dict, times) -> np.ndarray:
    """Where the collider of `description` (one of `Trajectory.colliders`) is at each of
    `times` (s): (T, 3, 4) float64 matrices [R | o], a point x₀ of its geometry as described
    (the placement as added) being at R x₀ + o; the identity for a still collider (no
    "motion"). The engine's own motion (`_core.collider_poses`), the one implementation the
    pictures, the viewer and the exports share."""
    t = np.asarray(times, dtype=np.float64).reshape(-1)
    motion = description.get("motion") if isinstance(description, dict) else None
    if motion is None:
        return np.broadcast_to(np.eye(3, 4), (t.size, 3, 4)).copy()
    return _core.collider_poses(t.tolist(), **_motion("motion", motion))


def _mesh_arrays(name: str, vertices, faces) -> tuple[list, list]:
    """A mesh description's vertices as (V, 3) nested lists of floats (m) and faces as (F, 3)
    nested lists of ints; a `ValueError` naming `name` for another shape or for faces that
    are not integers."""
    v = np.asarray(vertices, dtype=np.float64)
    if v.ndim != 2 or v.shape[1] != 3:
        raise ValueError(f"{name}.vertices has shape {v.shape}; it must be (V, 3): x, y, z (m) of each vertex")
    f = np.asarray(faces)
    if f.size and f.dtype.kind not in "iu":
        raise ValueError(f"{name}.faces holds {f.dtype} values; they must be vertex indices (integers)")
    if f.ndim != 2 or f.shape[1] != 3:
        raise ValueError(f"{name}.faces has shape {f.shape}; it must be (F, 3): three vertex indices per triangle")
    return v.tolist(), f.astype(np.int64).tolist()


def _flag(name: str, value) -> bool:
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise ValueError(f"{name} = {value!r} is invalid: it must be true or false")
