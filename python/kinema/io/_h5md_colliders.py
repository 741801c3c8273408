"""The colliders of an H5MD file (kinema's /parameters/kinema/colliders, for
`kinema.io.h5md_reader` and the writer's checks in `kinema.io.h5md`): the groups read back into
the plain descriptions of `Trajectory.colliders` (`_read_colliders`, a moving collider's
`_read_motion`), each checked by the engine as `World.add` checks a collider
(`collider_problem`), and the names of what a collider's group holds (`MESH_DATASETS`,
`MOTION_DATASETS`, `MOTION_ATTRIBUTES`, `COLLIDER_TYPES`), which the writer writes."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ._checks import dtype_problem, shown
from ._h5md_checks import fail
from ._h5md_layout import import_h5py

#: A mesh collider's arrays, datasets of its group (``save_h5md``), and their dtypes.
MESH_DATASETS = {"vertices": "float64", "faces": "int64"}
#: A moving collider's keyframe arrays, datasets of its ``motion`` group, and their shapes (K: keys).
MOTION_DATASETS = {"times": ("K",), "translations": ("K", 3), "rotations": ("K", 4)}
#: A motion group's attributes: 3-vectors (steady: velocity, angular_velocity; both kinds: pivot),
#: and a steady motion's start (s), one number.
MOTION_ATTRIBUTES = ("velocity", "angular_velocity", "pivot", "start")
#: The collider types a file holds.
COLLIDER_TYPES = ("plane", "box", "sphere", "mesh")


def _read_colliders(path: Path, params: Any, dim: int) -> list[dict[str, Any]]:
    """The descriptions under /parameters/kinema/colliders, in index order, each checked by
    the engine as `World.add` checks a collider (in a world of `dim` dimensions): the
    attributes are numbers (a mesh's `inside` a bool), a mesh's `vertices` (V, 3) real
    numbers and `faces` (F, 3) integers are datasets of its group."""
    h5py = import_h5py()
    group = params.get("colliders")
    if not isinstance(group, h5py.Group):
        return []
    out = []
    names = []
    for name in sorted(group, key=lambda n: int(n) if n.isdigit() else -1):
        g = group[name]
        kind = g.attrs.get("type") if isinstance(g, h5py.Group) else None
        kind = kind.decode() if isinstance(kind, bytes) else kind
        if not name.isdigit() or not isinstance(g, h5py.Group) or not isinstance(kind, str) or kind not in COLLIDER_TYPES:
            raise fail(
                path, f"{g.name} is not a kinema collider (a group named by its index with type {', '.join(COLLIDER_TYPES[:-1])} or {COLLIDER_TYPES[-1]})"
            )
        d: dict[str, Any] = {"type": str(kind)}
        for key, value in g.attrs.items():
            if key == "type":
                continue
            a = np.asarray(value)
            if key == "inside" and kind == "mesh":
                if a.size != 1 or a.dtype.kind != "b":
                    raise fail(path, f"attribute 'inside' ({g.name}) = {shown(value)} is not a bool")
                d[key] = bool(a.reshape(()))
                continue
            if a.size == 0 or dtype_problem(a.dtype) is not None:
                raise fail(path, f"attribute {key!r} ({g.name}) = {shown(value)} is not a number")
            a = a.astype(np.float64)
            d[key] = float(a) if a.ndim == 0 else a.tolist()
        for key in g:
            ds = g[key]
            if key == "motion" and isinstance(ds, h5py.Group):
                d["motion"] = _read_motion(path, ds)
                continue
            if kind != "mesh" or key not in MESH_DATASETS or not isinstance(ds, h5py.Dataset):
                raise fail(
                    path, f"{ds.name} is not part of a kinema collider (a mesh's group holds the datasets vertices and faces, any collider's a group motion)"
                )
            integer = MESH_DATASETS[key] == "int64"
            if ds.shape is None or len(ds.shape) != 2 or ds.shape[1] != 3 or dtype_problem(ds.dtype, integer) is not None:
                must = "integers" if integer else "real numbers"
                raise fail(path, f"{ds.name} has shape {ds.shape} of {ds.dtype}; it must be (N, 3) {must}")
            d[key] = np.asarray(ds[()], dtype=MESH_DATASETS[key]).tolist()
        out.append(d)
        names.append(g.name)
    if out:
        _check_colliders(path, names, out, dim)
    return out


def _read_motion(path: Path, g: Any) -> dict[str, Any]:
    """A collider's `motion` group: 3-vector attributes (velocity, angular_velocity, pivot)
    and keyframe datasets (times (K,), translations (K, 3), rotations (K, 4)), numbers of the
    shapes said; the engine checks the rest (`collider_problem`)."""
    h5py = import_h5py()
    out: dict[str, Any] = {}
    for key, value in g.attrs.items():
        a = np.asarray(value)
        if key not in MOTION_ATTRIBUTES or a.shape != (() if key == "start" else (3,)) or dtype_problem(a.dtype) is not None:
            raise fail(
                path,
                f"attribute {key!r} ({g.name}) = {shown(value)} is not part of a motion "
                f"(attributes {', '.join(MOTION_ATTRIBUTES[:3])}: 3 numbers each; start: one number, s)",
            )
        out[key] = float(a) if key == "start" else a.astype(np.float64).tolist()
    for key in g:
        ds = g[key]
        shape = MOTION_DATASETS.get(key)
        ok = shape is not None and isinstance(ds, h5py.Dataset) and ds.shape is not None and len(ds.shape) == len(shape)
        if not (ok and all(w == "K" or w == n for n, w in zip(ds.shape, shape, strict=True)) and dtype_problem(ds.dtype) is None):
            want = ", ".join(f"{k} {MOTION_DATASETS[k]}" for k in MOTION_DATASETS)
            raise fail(path, f"{ds.name} is not part of a motion (its datasets are real numbers: {want}, K keys)")
        out[key] = np.asarray(ds[()], dtype=np.float64).tolist()
    return out


def _check_colliders(path: Path, names: list[str], colliders: list[dict[str, Any]], dim: int) -> None:
    """Refuses the first collider `collider_problem` finds wrong, named by its group."""
    problem = collider_problem(names, colliders, dim)
    if problem is not None:
        raise fail(path, f"collider {problem}")


def collider_problem(names: list[str], colliders: list[dict[str, Any]], dim: int) -> str | None:
    """Adds each collider to an empty engine world of `dim` dimensions, as `World.add`
    does: the engine's checks (finite values, a non-zero normal, hi > lo, 2 or 3 values,
    restitution in [0, 1], ..., and a motion's: finite, times increasing, one key each, a box
    that only translates, a 2D motion in the xy-plane); returns `"<name> (a plane): <the engine's message>"` for
    the first it refuses, else `None`. The engine's own `World`, not `kinema.World`:
    reading a file needs no world module (which imports `kinema.trajectory`, which imports
    this). `save_h5md` checks what it writes with it."""
    from .. import _core
    from ..collider_descriptions import _KIND
    from ..colliders import Box, Mesh, Plane, SphereObstacle

    core = _core.World(dim, 1e-3, "verlet")
    make = {"plane": Plane, "box": Box, "sphere": SphereObstacle, "mesh": Mesh}
    for name, d in zip(names, colliders, strict=True):
        needed = _KIND[d["type"]]
        missing = [k for k in needed if k not in d]
        if missing:
            return f"{name} (a {d['type']}) has no {'dataset' if d['type'] == 'mesh' else 'attribute'} {missing[0]!r}"
        flags = ("inside",) if d["type"] == "mesh" else ()
        args = {k: d[k] for k in (*needed, *flags, "restitution", "friction") if k in d}
        try:
            k = make[d["type"]](**args)._attach(core)
            if d.get("motion") is not None:
                core.set_collider_motion(k, **d["motion"])
        except (ValueError, TypeError) as e:
            first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
            return f"{name} (a {d['type']}): {first}"
    return None
