"""The colliders of a USD stage (for `kinema.io.usd_writer`): each described collider as a
rendered `UsdGeom.Mesh` under `/World/colliders` (`_colliders`: a box, a plane as one square,
a sphere as a UV sphere, a triangle mesh turned to face out; a moving one with a transform
sampled at every frame), their colour and opacity, the meshes themselves as points and faces
(`box_mesh`, `plane_mesh`, `sphere_mesh`, `triangle_mesh`), and the sRGB to linear conversion
(`_srgb_to_linear`) every colour of the stage goes through."""

from __future__ import annotations

from typing import Any

import numpy as np

from ._cell import box_corners, trajectory_cell
from ._files import Frames


def _srgb_to_linear(c: np.ndarray) -> np.ndarray:
    """sRGB-encoded values in [0, 1] to linear ones (IEC 61966-2-1)."""
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def _colliders(stage: Any, traj: Any, fr: Frames, pxr: tuple) -> None:
    """The trajectory's colliders as meshes under /World/colliders (see write_usd)."""
    from ..collider_descriptions import collider_poses

    Gf, Sdf, Usd, UsdGeom, Vt = pxr
    described = [c for c in getattr(traj, "colliders", None) or [] if isinstance(c, dict)]
    if not described:
        return
    cell = trajectory_cell(traj, fr)
    centre, size = 0.5 * (cell.lo + cell.hi), float(np.max(cell.hi - cell.lo))
    UsdGeom.Scope.Define(stage, "/World/colliders")
    for k, c in enumerate(described):
        kind = c.get("type")
        normals = None
        if kind == "box":
            lo, hi = box_corners(c)
            lo, hi = np.where(np.isfinite(lo), lo, cell.lo), np.where(np.isfinite(hi), hi, cell.hi)  # open faces: the scene's extent
            points, faces = box_mesh(lo, hi)
        elif kind == "plane":
            normal = np.asarray(c["normal"], float).reshape(-1)
            point = np.asarray(c["point"], float).reshape(-1)
            points, faces = plane_mesh(point, normal, centre, size)
        elif kind == "sphere":
            centre_k, radius = np.asarray(c["center"], float).reshape(-1)[:3], float(c["radius"])
            points, faces = sphere_mesh(centre_k, radius)
            normals = (points - centre_k) / radius if radius > 0 else None  # smooth shading
        elif kind == "mesh":
            triangles = triangle_mesh(c)
            if triangles is None:
                continue
            points, faces = triangles
        else:
            continue
        mesh = UsdGeom.Mesh.Define(stage, f"/World/colliders/{kind}_{k}")
        mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points.astype(np.float32)))
        mesh.CreateFaceVertexCountsAttr(Vt.IntArray([len(f) for f in faces]))
        mesh.CreateFaceVertexIndicesAttr(Vt.IntArray([int(i) for f in faces for i in f]))
        mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)  # (a mesh is Catmull-Clark unless told)
        mesh.CreateDoubleSidedAttr(True)  # the particles are seen inside a box and from both sides of a plane
        mesh.CreateExtentAttr(UsdGeom.Mesh.ComputeExtent(mesh.GetPointsAttr().Get()))
        if normals is not None:
            mesh.CreateNormalsAttr(Vt.Vec3fArray.FromNumpy(normals.astype(np.float32)))
            mesh.SetNormalsInterpolation(UsdGeom.Tokens.vertex)
        grey = _srgb_to_linear(np.array(COLLIDER_COLOR) / 255.0)
        mesh.CreateDisplayColorPrimvar(UsdGeom.Tokens.constant).Set(Vt.Vec3fArray([Gf.Vec3f(*map(float, grey))]))
        mesh.CreateDisplayOpacityPrimvar(UsdGeom.Tokens.constant).Set(Vt.FloatArray([COLLIDER_OPACITY]))
        mesh.GetPrim().CreateAttribute("kinema:collider", Sdf.ValueTypeNames.Token).Set(kind)
        if c.get("motion") is not None:
            try:
                poses = collider_poses(c, fr.t)  # (F, 3, 4) [R | o]: x = R x0 + o
            except ValueError as e:
                raise ValueError(f"colliders[{k}].{e}") from None
            # Gf matrices act on row vectors (x' = x M): M is [R | o] transposed.
            transform = UsdGeom.Xformable(mesh).AddTransformOp()
            for i, pose in enumerate(poses):
                m = np.eye(4)
                m[:3, :] = pose
                transform.Set(Gf.Matrix4d(m.T.tolist()), Usd.TimeCode(float(i)))


#: The colliders' ``displayOpacity`` and their material's opacity: kinema's renderer draws
#: planes and meshes at 0.3.
COLLIDER_OPACITY = 0.3

#: The colliders' colour (sRGB 8-bit): kinema's videos' planes and meshes (``PLANE_COLOR``).
COLLIDER_COLOR = (150, 150, 142)


def triangle_mesh(c: dict) -> tuple[np.ndarray, np.ndarray] | None:
    """A `{"type": "mesh"}` description's vertices (V, 3) (m) and triangles (F, 3), a closed
    mesh's (every edge run once each way by two triangles) turned to face out (as the engine
    turns it: when its signed volume, the sum of a · (b × c) / 6, is negative); None when it
    is malformed (vertices not V × 3 finite numbers, faces not F × 3 indices below V)."""
    try:
        points = np.asarray(c.get("vertices"), dtype=np.float64).reshape(-1, 3)
        faces = np.asarray(c.get("faces"), dtype=np.int64).reshape(-1, 3)
    except (TypeError, ValueError):
        return None
    if not (len(points) and len(faces) and np.isfinite(points).all() and faces.min() >= 0 and faces.max() < len(points)):
        return None
    ends = np.stack([faces, np.roll(faces, -1, axis=1)], axis=2).reshape(-1, 2)  # each triangle's edges a → b
    forward, backward = ends[:, 0] * len(points) + ends[:, 1], ends[:, 1] * len(points) + ends[:, 0]
    closed = np.unique(forward).size == forward.size and np.array_equal(np.sort(forward), np.sort(backward))
    a, b, cc = (points[faces[:, k]] for k in range(3))
    if closed and np.einsum("ij,ij->", a, np.cross(b, cc)) < 0:
        faces = faces[:, [0, 2, 1]]
    return points, faces


def box_mesh(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, list[list[int]]]:
    """The box [lo, hi] (m) as 8 points (corner j at x = hi if j & 1, y = hi if j & 2, z = hi
    if j & 4, else lo) and 6 quads, counter-clockwise seen from outside (USD's right-handed
    orientation: their normals point out)."""
    points = np.array([[hi[0] if j & 1 else lo[0], hi[1] if j & 2 else lo[1], hi[2] if j & 4 else lo[2]] for j in range(8)], dtype=np.float64)
    return points, [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]]


def plane_mesh(point: np.ndarray, normal: np.ndarray, centre: np.ndarray, size: float) -> tuple[np.ndarray, list[list[int]]]:
    """The plane through `point` with `normal` as one square quad 2 `size` wide (m),
    centred on the plane's point nearest `centre`, counter-clockwise seen from the side the
    normal points to; its sides along the axes where the normal is one."""
    n = normal / np.linalg.norm(normal)
    foot = centre - np.dot(centre - point, n) * n
    axis = np.eye(3)[int(np.argmin(np.abs(n)))]  # the axis farthest from the normal
    u = axis - np.dot(axis, n) * n
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    corners = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
    return np.array([foot + size * (a * u + b * v) for a, b in corners]), [[0, 1, 2, 3]]


#: The sphere meshes' divisions: around (longitude) and from pole to pole (latitude).
SPHERE_SEGMENTS, SPHERE_RINGS = 32, 16


def sphere_mesh(centre: np.ndarray, radius: float) -> tuple[np.ndarray, list[list[int]]]:
    """The sphere as a UV sphere (m): its points on the sphere, a pole at each end of z and
    `SPHERE_RINGS` − 1 rings of `SPHERE_SEGMENTS` between; quads between the rings and
    triangles at the poles (448 quads and 64 triangles), counter-clockwise seen from outside."""
    m, rings = SPHERE_SEGMENTS, SPHERE_RINGS
    theta = np.pi * np.arange(1, rings) / rings  # from +z
    phi = 2.0 * np.pi * np.arange(m) / m
    ring = np.stack([np.outer(np.sin(theta), np.cos(phi)), np.outer(np.sin(theta), np.sin(phi)), np.repeat(np.cos(theta)[:, None], m, axis=1)], axis=2)
    unit = np.concatenate([[[0.0, 0.0, 1.0]], ring.reshape(-1, 3), [[0.0, 0.0, -1.0]]])
    south = len(unit) - 1

    def at(j: int, k: int) -> int:  # ring j (0 … rings − 2), segment k
        return 1 + j * m + k % m

    faces = [[0, at(0, k), at(0, k + 1)] for k in range(m)]
    faces += [[at(j, k), at(j + 1, k), at(j + 1, k + 1), at(j, k + 1)] for j in range(rings - 2) for k in range(m)]
    faces += [[south, at(rings - 2, k + 1), at(rings - 2, k)] for k in range(m)]
    return centre + radius * unit, faces
