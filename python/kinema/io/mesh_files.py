"""Reading triangle meshes from files for `kinema.Mesh`: OBJ, STL, PLY and glTF (.gltf, .glb)
through `trimesh`, USD (.usd, .usda, .usdc, .usdz) through Pixar's `usd-core` (`pxr`).

`read_mesh(path)` gives the file's vertices (V, 3) float64, in metres with +z up (kinema's
axes), and its triangles (F, 3) int64: polygons (quads, n-gons) are cut into fans
(v0, vk, vk+1), a file of several meshes gives all of them, concatenated, each placed by its
node's or prim's transform. Vertices at exactly the same coordinates are made one (the first
keeps its place in the file's order, so a file without such duplicates keeps its vertex order):
an STL file stores every triangle's corners apart, and a UV seam splits a vertex in two; for a
collider they are one point, and only a surface whose triangles share their vertices is known
to be closed. Faces left with a repeated vertex by that (they had no area) are dropped.

Up axes. kinema's gravity points along −z: +z is up. glTF and USD say which way is up, and
are read so: glTF's +y is up by its specification (2.0, §3.4: "+Y is up"), USD's the stage's
`upAxis` (Y or Z). OBJ, STL and PLY carry no axis: `up_axis` says it, "z" (the default) or
"y" (Blender's OBJ export, Maya, Unity, three.js). A +y-up file is turned so that its +y is
+z, a right-handed +90° turn about x: (x, y, z) → (x, −z, y). Blender's OBJ exporter writes
a Blender point (x, y, z) as (x, z, −y) (forward −Z, up +Y, its defaults), so reading that
file with up_axis="y" gives back (x, y, z), exactly (a permutation and a sign: no rounding).

A refused file is a `ValueError` of one line: `file = '<path>' is invalid: <why>` (no such
file, a directory, a format not read (the list of those read), a file the format's reader
cannot read, one with no triangle).
"""

from __future__ import annotations

import os
import stat
import warnings
from pathlib import Path
from typing import Any

import numpy as np

#: The up axes a file may be read with (`up_axis`): kinema's own, and the common other one.
UP_AXES = ("z", "y")
#: The formats that say their own up axis (glTF by its specification, USD by its stage's
#: upAxis); `up_axis` is for the others.
OWN_AXIS = ("glTF", "USD")

#: The formats read, with the suffixes that name them (the one home of this list).
MESH_FORMATS = {
    "OBJ": (".obj",),
    "STL": (".stl",),
    "PLY": (".ply",),
    "glTF": (".gltf", ".glb"),
    "USD": (".usd", ".usda", ".usdc", ".usdz"),
}


def mesh_format(path: str | os.PathLike) -> str | None:
    """The format `path` names by its suffix (a key of `MESH_FORMATS`), or None."""
    suffix = Path(path).suffix.lower()
    return next((name for name, suffixes in MESH_FORMATS.items() if suffix in suffixes), None)


def formats_text() -> str:
    """The formats read, in words, as a refusal names them."""
    return ", ".join(f"{name} ({', '.join(s)})" for name, s in MESH_FORMATS.items())


def y_up_to_z_up(vertices: np.ndarray) -> np.ndarray:
    """The points (V, 3) of a +y-up file in kinema's +z-up axes: (x, y, z) → (x, −z, y), the
    right-handed +90° turn about x that takes +y to +z (and +z to −y). Exact: no rounding."""
    v = np.asarray(vertices, dtype=np.float64)
    return np.stack([v[:, 0], -v[:, 2], v[:, 1]], axis=1) + 0.0  # (−0.0 + 0.0 = 0.0)


def check_up_axis(value: object, name: str = "up_axis") -> str | None:
    """`value` ("z", "y", upper case too, or None: the file's own or z) as "z", "y" or None; else a
    `ValueError` naming `name`."""
    if value is None:
        return None
    if isinstance(value, str) and value.strip().lower() in UP_AXES:
        return value.strip().lower()
    raise ValueError(f'{name} = {value!r} is invalid: use "z" (+z is up, kinema\'s own) or "y" (+y is up: Blender\'s OBJ export, glTF)')


def read_mesh(path: str | os.PathLike, name: str = "file", up_axis: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The vertices (V, 3) float64 and triangles (F, 3) int64 of the mesh file `path`, in
    kinema's axes: `read_mesh_axis`'s first two."""
    vertices, faces, _ = read_mesh_axis(path, name, up_axis)
    return vertices, faces


def read_mesh_axis(path: str | os.PathLike, name: str = "file", up_axis: str | None = None) -> tuple[np.ndarray, np.ndarray, str]:
    """The vertices (V, 3) float64 and triangles (F, 3) int64 of the mesh file `path` (see
    the module doc), in kinema's axes (+z up); `name` is the parameter a refusal names.

    `up_axis`: the file's up axis, "z" or "y", for a format that does not say it (OBJ, STL,
    PLY; None: "z"). glTF (+y up) and USD (its stage's upAxis) say theirs and are read by it;
    an `up_axis` given for them that disagrees is a `ValueError` (it would be a second turn).
    The third value is the up axis the file was read with, "z" or "y"."""
    path = Path(path)
    up_axis = check_up_axis(up_axis)

    def refuse(why: str) -> ValueError:
        return ValueError(f"{name} = {str(path)!r} is invalid: {why}")

    fmt = mesh_format(path)
    if fmt is None:
        said = f"'{path.suffix}'" if path.suffix else "(no suffix)"
        raise refuse(f"unknown mesh format {said}; the formats read are {formats_text()}")
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        where = "" if path.is_absolute() else f" (looked in {os.getcwd()})"
        raise refuse(f"no such file{where}") from None
    except OSError as e:
        raise refuse(f"cannot be read ({e.strerror or e})") from None
    if stat.S_ISDIR(mode):
        raise refuse(f"is a directory, not a mesh file ({formats_text()})")
    if not stat.S_ISREG(mode):
        from ._files import special_kind

        raise refuse(f"is not a regular file (a {special_kind(mode) or 'special file'}); a mesh is a file")
    if fmt == "USD":
        vertices, faces, own = _read_usd(path, refuse)
    else:
        vertices, faces = _read_trimesh(path, fmt, refuse)
        own = "y" if fmt == "glTF" else None
    if own is not None and up_axis is not None and up_axis != own:
        said = "by the glTF specification" if fmt == "glTF" else "by its stage's upAxis"
        raise ValueError(
            f"up_axis = {up_axis!r} is invalid for {path}: a {fmt} file says its own up axis (+{own} {said}) and is read "
            f"by it, turned to kinema's +z up; leave up_axis out (it is for OBJ, STL and PLY, which say none)"
        )
    axis = own or up_axis or "z"
    if axis == "y":
        vertices = y_up_to_z_up(np.asarray(vertices, dtype=np.float64).reshape(-1, 3))
    vertices, faces = _merged(vertices, faces)
    if len(faces) == 0:
        raise refuse("it holds no triangle (a mesh collider needs faces; a point cloud or a set of lines has none)")
    bad = ~np.isfinite(vertices)
    if bad.any():
        v, k = (int(i) for i in np.argwhere(bad)[0])
        raise refuse(f"its vertex {v} has the coordinate {vertices[v, k]!r}; a mesh's vertices must be finite")
    return vertices, faces, axis


def _merged(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One vertex for each set of vertices of exactly equal coordinates (in the order of their
    first appearance; −0.0 is 0.0), the faces re-indexed, faces with a repeated vertex dropped."""
    vertices = np.asarray(vertices, dtype=np.float64).reshape(-1, 3) + 0.0  # -0.0 + 0.0 = 0.0
    faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
    if len(vertices) == 0:
        return vertices, faces[:0]
    _, first, inverse = np.unique(vertices, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    order = np.argsort(first, kind="stable")  # the unique rows by first appearance
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    kept = vertices[first[order]]
    faces = rank[inverse[faces]]
    whole = (faces[:, 0] != faces[:, 1]) & (faces[:, 1] != faces[:, 2]) & (faces[:, 0] != faces[:, 2])
    return kept, faces[whole]


def fan(counts: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """The triangles (F, 3) of polygons given as their vertex counts and their vertex indices
    one after the other (USD's faceVertexCounts and faceVertexIndices, OBJ's faces): the fan
    (v0, vk, vk+1), k = 1 … n − 2, of each (a convex polygon's triangulation)."""
    counts = np.asarray(counts, dtype=np.int64).reshape(-1)
    indices = np.asarray(indices, dtype=np.int64).reshape(-1)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    per = np.maximum(counts - 2, 0)
    poly = np.repeat(np.arange(len(counts)), per)
    k = np.arange(int(per.sum())) - np.repeat(np.cumsum(per) - per, per) + 1  # 1 … n − 2 in each polygon
    s = starts[poly]
    return np.stack([indices[s], indices[s + k], indices[s + k + 1]], axis=1)


def _read_trimesh(path: Path, fmt: str, refuse: Any) -> tuple[np.ndarray, np.ndarray]:
    """OBJ, STL, PLY, glTF through trimesh, as the file has them (`process=False`: no vertex
    merged, reordered or dropped by trimesh; a scene of several meshes concatenated with its
    nodes' transforms by `force="mesh"`)."""
    try:
        import trimesh
    except ImportError:
        raise ImportError(f"reading {fmt} meshes needs the trimesh package: pip install trimesh") from None
    try:
        loaded = trimesh.load(str(path), file_type=path.suffix.lower().lstrip("."), force="mesh", process=False)
    except Exception as e:  # trimesh's parsers raise what their input makes them raise
        text = str(e).strip().splitlines()
        raise refuse(f"cannot be read as {fmt} (trimesh: {type(e).__name__}{': ' + text[0] if text else ''})") from None
    vertices = np.asarray(getattr(loaded, "vertices", np.zeros((0, 3))), dtype=np.float64).reshape(-1, 3)
    faces = np.asarray(getattr(loaded, "faces", np.zeros((0, 3))), dtype=np.int64).reshape(-1, 3)
    return vertices, faces


def _read_usd(path: Path, refuse: Any) -> tuple[np.ndarray, np.ndarray]:
    """Every `UsdGeom.Mesh` prim of the stage but guides (its purpose `guide`: kinema's own
    export drew its colliders so) and kinema's exported colliders (`kinema:collider`), at the earliest time code: `points` by the prim's
    local-to-world transform, × the stage's `metersPerUnit` (USD's fallback 0.01,
    centimetres, with a `UnitWarning` where the stage does not say it, as
    `kinema.io.read_usd` reads particles); `faceVertexCounts` and `faceVertexIndices`
    cut into fans; a `leftHanded` prim's triangles turned to run counter-clockwise. Also the
    stage's up axis, "y" or "z" (read_mesh turns a +y-up stage's points to +z up)."""
    try:
        from pxr import Tf, Usd, UsdGeom
    except ImportError:
        raise ImportError("reading USD meshes needs the usd-core package: pip install usd-core (or kinema[usd])") from None
    from .read_usd import _open, _usd_reason
    from .units import UnitWarning

    try:
        stage = _open(path)
    except Tf.ErrorException as e:
        raise refuse(f"not a USD stage that can be read ({_usd_reason(e)})") from None
    except ValueError as e:  # read_usd's refusal of a file that is no layer
        raise refuse(str(e).split(": ", 1)[-1]) from None
    if stage is None:
        raise refuse("not a USD stage that can be read")
    time = Usd.TimeCode.EarliestTime()
    parts_v, parts_f, offset = [], [], 0
    for prim in stage.Traverse():
        if not prim.IsA(UsdGeom.Mesh) or UsdGeom.Imageable(prim).ComputePurpose() == UsdGeom.Tokens.guide or prim.HasAttribute("kinema:collider"):
            continue
        mesh = UsdGeom.Mesh(prim)
        points = mesh.GetPointsAttr().Get(time)
        counts = mesh.GetFaceVertexCountsAttr().Get(time)
        indices = mesh.GetFaceVertexIndicesAttr().Get(time)
        if points is None or counts is None or indices is None or len(points) == 0:
            continue
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        c, i = np.asarray(counts, dtype=np.int64), np.asarray(indices, dtype=np.int64)
        where = f"{prim.GetPath()}"
        if (c < 3).any():
            k = int(np.argmax(c < 3))
            raise refuse(f"{where}: faceVertexCounts[{k}] = {int(c[k])}; a face has at least 3 vertices")
        if int(c.sum()) != len(i):
            raise refuse(f"{where}: faceVertexCounts add up to {int(c.sum())}, but faceVertexIndices has {len(i)} indices")
        if len(i) and (i.min() < 0 or i.max() >= len(p)):
            k = int(np.argmax((i < 0) | (i >= len(p))))
            raise refuse(f"{where}: faceVertexIndices[{k}] = {int(i[k])}; the prim has {len(p)} points (indices 0..{len(p) - 1})")
        tris = fan(c, i)
        if mesh.GetOrientationAttr().Get(time) == UsdGeom.Tokens.leftHanded:
            tris = tris[:, [0, 2, 1]]
        m = np.array(UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(time), dtype=np.float64)  # row vectors: p' = [p 1] M
        p = p @ m[:3, :3] + m[3, :3]
        parts_v.append(p)
        parts_f.append(tris + offset)
        offset += len(p)
    if not parts_v:
        raise refuse("the stage holds no UsdGeom.Mesh prim with points and faces (guides left out)")
    metres = UsdGeom.GetStageMetersPerUnit(stage)
    said = []
    if not UsdGeom.StageHasAuthoredMetersPerUnit(stage):
        said.append(f"the stage does not say its metersPerUnit: USD's fallback {metres!r} m (centimetres) is taken")
    up = "y" if UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.y else "z"  # (USD allows Y or Z; its fallback is Y)
    if said:
        warnings.warn(f"{path}: {'; '.join(said)}", UnitWarning, stacklevel=4)
    return np.concatenate(parts_v) * metres, np.concatenate(parts_f), up
