"""A mesh as an emitter's source (for `kinema.emitter`, `shape="mesh"`, Blender's "Emit
From"): what a source samples, made once from its `kinema.Mesh` (`_mesh_source`: the faces of
non-zero area, their cumulative areas and normals, out of a closed mesh, the vertices'
normals, the bounding box), and the winding numbers of its surface about points
(`winding_numbers`), which keep the candidates inside it when it emits from its volume."""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from . import _checks
from .colliders import Mesh, _is_closed

EMIT_FROM = ("faces", "volume", "vertices")  # a mesh's: Blender's "Emit From" Faces, Volume, Verts
WINDING_BLOCK = 2_000_000  # candidate points × faces per block of the volume's inside test


def _mesh_source(shape: str, mesh: Any, emit_from: Any) -> dict[str, Any]:
    """What a mesh source samples (`shape="mesh"`): its vertices and kept faces (non-zero
    area), their cumulative areas and unit normals (out of a closed mesh), the vertices'
    normals, whether it is closed, its bounding box; {} for another shape (which refuses a
    `mesh`)."""
    if shape != "mesh":
        if mesh is not None:
            raise ValueError(f"mesh = {_checks.describe(mesh)} is given to shape = {shape!r}: a mesh is the source of shape = 'mesh' only")
        return {}
    if mesh is None:
        raise ValueError("shape = 'mesh' needs mesh = a kinema.Mesh or a mesh file's path (OBJ, STL, PLY, glTF, USD)")
    if isinstance(mesh, (str, os.PathLike)):
        mesh = Mesh(mesh)
    elif not isinstance(mesh, Mesh):
        raise TypeError(f"mesh = {_checks.describe(mesh)} is invalid: it must be a kinema.Mesh or a mesh file's path, not {_checks._type_words(mesh)}")
    if mesh.motion is not None:
        raise ValueError("mesh is invalid: it has a motion; an emitter's mesh stays where it is placed (give it without motion=)")
    how = _checks.text("emit_from", emit_from)
    if how not in EMIT_FROM:
        raise ValueError(f"emit_from = {how!r} is invalid: use one of {', '.join(map(repr, EMIT_FROM))} (Blender's Faces, Volume, Verts)")
    v, f = mesh.vertices, mesh.faces
    if f.min() < 0 or f.max() >= len(v):
        raise ValueError(f"mesh is invalid: its faces hold the vertex index {int(f.max() if f.max() >= len(v) else f.min())}; it has {len(v)} vertices")
    a, b, cc = (v[f[:, k]] for k in range(3))
    cross = np.cross(b - a, cc - a)
    twice = np.linalg.norm(cross, axis=1)
    kept = twice > 0
    if not kept.any():
        raise ValueError("mesh is invalid: it has no face of non-zero area to emit from")
    f, cross, twice = f[kept], cross[kept], twice[kept]
    closed = _is_closed(v, f)
    a, b, cc = (v[f[:, k]] for k in range(3))
    volume = float(np.einsum("ij,ij->i", a, np.cross(b, cc)).sum()) / 6.0  # signed: > 0 when the faces face out
    if closed and volume < 0:
        cross = -cross
    if how == "volume" and not (closed and volume != 0):
        raise ValueError(
            "emit_from = 'volume' needs a closed (watertight) mesh, every edge shared by exactly two faces running along it in "
            "opposite directions, to have an inside; this mesh is open (emit from its 'faces' or 'vertices', or close it)"
        )
    used = np.unique(f)
    vn = np.zeros_like(v)
    for k in range(3):
        np.add.at(vn, f[:, k], cross)  # each face's normal × twice its area
    vn = vn[used]
    length = np.linalg.norm(vn, axis=1, keepdims=True)
    vn = np.where(length > 0, vn / np.where(length > 0, length, 1.0), [0.0, 0.0, 1.0])  # (a vertex whose faces cancel: +z)
    return {
        "mesh": mesh,
        "emit_from": how,
        "mesh_vertices": v,
        "mesh_faces": f,
        "mesh_area": np.cumsum(twice / 2.0),
        "mesh_normals": cross / twice[:, None],
        "mesh_used": used,
        "mesh_vertex_normals": vn,
        "mesh_closed": closed,
        "mesh_volume": abs(volume),
        "mesh_box": (v[used].min(axis=0), v[used].max(axis=0)),
    }


def winding_numbers(points: np.ndarray, vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """The winding number (N,) of the closed surface `faces` about each of `points` (N, 3):
    the sum of the solid angles its triangles subtend there over 4π (Van Oosterom and
    Strackee's formula, as `kinema.Mesh`'s inside test): ±1 inside, 0 outside."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    out = np.empty(len(points))
    block = max(1, WINDING_BLOCK // max(1, len(faces)))
    tri = vertices[faces]  # (F, 3, 3)
    for lo in range(0, len(points), block):
        p = points[lo : lo + block, None, :]
        a, b, c = tri[None, :, 0] - p, tri[None, :, 1] - p, tri[None, :, 2] - p
        la, lb, lc = (np.linalg.norm(x, axis=2) for x in (a, b, c))
        num = np.einsum("ijk,ijk->ij", a, np.cross(b, c))
        den = la * lb * lc + np.einsum("ijk,ijk->ij", a, b) * lc + np.einsum("ijk,ijk->ij", a, c) * lb + np.einsum("ijk,ijk->ij", b, c) * la
        out[lo : lo + block] = np.sum(2.0 * np.arctan2(num, den), axis=1) / (4.0 * np.pi)
    return out
