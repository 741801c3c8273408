"""The viewer page: the frames packed as little-endian float32, the metadata, and the HTML."""

from __future__ import annotations

import base64
import json
import math
import os
import re
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..collider_descriptions import collider_poses
from ..io._files import atomic_file
from ..render import NO_OWN_COLOR

_HERE = Path(__file__).parent
BUNDLE = _HERE / "static" / "viewer.js"
TEMPLATE = _HERE / "template.html"

# Bytes of frame data (positions and speeds) a page carries before frames, then particles,
# are left out. An inlined page grows by 4/3 (base64) and the browser holds the decoded copy.
HTML_MAX_BYTES = 100_000_000
SERVE_MAX_BYTES = 400_000_000
_MIN_FRAMES = 10  # frames kept, when there are that many, before particles are left out


class BundleMissingError(FileNotFoundError):
    """The viewer's script bundle has not been built."""

    def __init__(self) -> None:
        super().__init__(
            f"the viewer's script {BUNDLE} is missing: this installation of kinema is incomplete; reinstall it (from a source checkout: `make viewer` rebuilds the script with Node)"
        )


class ViewerWarning(UserWarning):
    """The page shows fewer frames or particles than the trajectory holds."""


@dataclass
class Packed:
    """What a page shows: metadata (JSON-ready) and the arrays: positions (F, N, 3) float32
    (0 where a particle is not alive), speed (F, N) float32 or None, radii (N,) float32,
    springs (2 S,) int32 column pairs or None, alive (F, ceil(N / 8)) uint8, each frame's
    bits little-endian (bit i of byte j: particle 8 j + i), or None when all are alive, and
    colors (N, 4) uint8, each particle's own colour as RGBA (A 0: none), or None."""

    meta: dict[str, Any]
    positions: np.ndarray
    speed: np.ndarray | None
    radii: np.ndarray
    springs: np.ndarray | None = None
    alive: np.ndarray | None = None
    colors: np.ndarray | None = None


def _strides(frames: int, particles: int, per_particle: int, max_bytes: int) -> tuple[int, int]:
    """Frame and particle strides that bring frames * particles * per_particle under max_bytes:
    frames first, down to _MIN_FRAMES, then particles."""
    total = frames * particles * per_particle
    if total <= max_bytes:
        return 1, 1
    keep = max(min(frames, _MIN_FRAMES), max_bytes // (particles * per_particle))
    frame_stride = math.ceil(frames / keep) if keep < frames else 1
    kept = len(range(0, frames, frame_stride))
    particle_stride = max(1, math.ceil(kept * particles * per_particle / max_bytes))
    return frame_stride, particle_stride


def _finite_or_none(values: Any, size: int = 3, pad: float | None = None) -> list[float | None] | None:
    """Up to ``size`` numbers with ±inf as None (JSON has no infinity), padded with ``pad``;
    None when there are too many values or one is NaN."""
    try:
        a = np.asarray(values, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        return None
    if a.size == 0 or a.size > size or np.isnan(a).any():
        return None
    out: list[float | None] = [float(x) if math.isfinite(x) else None for x in a]
    return out + [pad] * (size - a.size)


def _mesh(c: dict[str, Any]) -> dict[str, Any] | None:
    """A mesh description as the page draws it: its vertices as base64 little-endian float32
    (x, y, z each), its triangles as base64 little-endian uint32 (three vertex indices
    each), their counts, its bounding box (lo, hi: what the camera frames) and ``inside``;
    None when it cannot be drawn (vertices not V x 3 finite numbers, faces not F x 3
    indices below V, or none)."""
    try:
        vertices = np.asarray(c.get("vertices"), dtype=np.float64).reshape(-1, 3)
        faces = np.asarray(c.get("faces"), dtype=np.int64).reshape(-1, 3)
    except (TypeError, ValueError):
        return None
    if not (len(vertices) and len(faces) and np.isfinite(vertices).all() and faces.min() >= 0 and faces.max() < len(vertices)):
        return None
    return {
        "type": "mesh",
        "vertices": _b64(np.ascontiguousarray(vertices, dtype="<f4")),
        "faces": _b64(np.ascontiguousarray(faces, dtype="<u4")),
        "vertexCount": len(vertices),
        "faceCount": len(faces),
        "lo": [float(x) for x in vertices.min(axis=0)],
        "hi": [float(x) for x in vertices.max(axis=0)],
        "inside": bool(c.get("inside", False)),
    }


def _poses(c: dict[str, Any], t: np.ndarray) -> np.ndarray | None:
    """A moving collider's pose at each of the page's frame times ``t``: (F, 4, 4) matrices
    [[R, o], [0, 0, 0, 1]] (x = R x₀ + o for a point x₀ of it as described), from the engine's
    motion (``collider_poses``); None for a still one (no "motion"). A malformed motion is a
    ValueError."""
    if c.get("motion") is None:
        return None
    pose = collider_poses(c, t)
    out = np.zeros((len(t), 4, 4))
    out[:, :3, :] = pose
    out[:, 3, 3] = 1.0
    return out


def _path_box(c: dict[str, Any], poses: np.ndarray) -> dict[str, Any] | None:
    """The box (as a page "box": lo, hi, None where open) around where a moving collider's
    finite parts go over ``poses``: a box's finite bounds moved (a box only translates), the
    corners of a sphere's or a mesh's box turned and moved; None for a plane."""
    if c["type"] == "box":
        o = poses[:, :3, 3]
        lo = [None if b is None else float(b + o[:, k].min()) for k, b in enumerate(c["lo"])]
        hi = [None if b is None else float(b + o[:, k].max()) for k, b in enumerate(c["hi"])]
        return {"type": "box", "lo": lo, "hi": hi}
    if c["type"] == "sphere":
        r = c["radius"]
        lo, hi = np.asarray(c["center"]) - r, np.asarray(c["center"]) + r
    elif c["type"] == "mesh":
        lo, hi = np.asarray(c["lo"]), np.asarray(c["hi"])
    else:
        return None
    corners = np.array([[hi[k] if j >> k & 1 else lo[k] for k in range(3)] for j in range(8)])
    moved = np.einsum("fij,cj->fci", poses[:, :3, :3], corners) + poses[:, None, :3, 3]
    return {"type": "box", "lo": moved.min(axis=(0, 1)).tolist(), "hi": moved.max(axis=(0, 1)).tolist()}


def _colliders(colliders: Any, t: np.ndarray) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """The trajectory's collider descriptions as the page draws them: 3 values per vector
    (a 2-value box is open along z), ±inf bounds as None, a mesh's arrays in base64
    (``_mesh``); what cannot be drawn (a malformed description or motion, a plane with no
    finite normal) is left out. A collider with a "motion" carries ``poses``: its pose at
    each of the page's frame times ``t`` (``_poses``), base64 little-endian float32, 16 a
    frame in column-major order (three.js's ``Matrix4.fromArray``). Also returns the boxes
    the moving colliders sweep (``_path_box``), for the extent."""
    out: list[dict[str, Any]] = []
    paths: list[dict[str, Any]] = []
    for c in colliders or []:
        drawn = _drawn(c) if isinstance(c, dict) else None
        if drawn is None:
            continue
        try:
            poses = _poses(c, t)
        except (TypeError, ValueError):
            continue
        if poses is not None:
            drawn["poses"] = _b64(np.ascontiguousarray(poses.transpose(0, 2, 1), dtype="<f4"))
            path = _path_box(drawn, poses)
            if path is not None:
                paths.append(path)
        out.append(drawn)
    return out, paths


def _drawn(c: dict[str, Any]) -> dict[str, Any] | None:
    """The description ``c`` as the page draws it (``_colliders``); None when it cannot be
    drawn."""
    kind = c.get("type")
    if kind == "plane":
        point, normal = _finite_or_none(c.get("point"), pad=0.0), _finite_or_none(c.get("normal"), pad=0.0)
        if point and normal and None not in point and None not in normal and any(normal):
            return {"type": "plane", "point": point, "normal": normal}
    elif kind == "box":
        lo, hi = _finite_or_none(c.get("lo")), _finite_or_none(c.get("hi"))
        if lo and hi and all(a is None or b is None or a < b for a, b in zip(lo, hi, strict=True)):
            return {"type": "box", "lo": lo, "hi": hi}
    elif kind == "sphere":
        center = _finite_or_none(c.get("center"), pad=0.0)
        try:
            radius = float(c.get("radius"))
        except (TypeError, ValueError):
            return None
        if center and None not in center and math.isfinite(radius) and radius >= 0:
            return {"type": "sphere", "center": center, "radius": radius}
    elif kind == "mesh":
        return _mesh(c)
    return None


def _extent(lo: np.ndarray, hi: np.ndarray, colliders: list[dict[str, Any]]) -> tuple[np.ndarray, np.ndarray]:
    """The particles' box (lo, hi: NaN where none) joined with the colliders' finite parts: a
    box's finite bounds, each along its own axis, a sphere's and a mesh's box; a plane adds
    nothing.
    An axis nothing reached gets [0, 1] (or the other axes' size around 0 when any has one)."""
    lo, hi = lo.astype(np.float64).copy(), hi.astype(np.float64).copy()

    def grow(k: int, v: float | None) -> None:
        if v is not None and math.isfinite(v):
            lo[k] = v if math.isnan(lo[k]) else min(lo[k], v)
            hi[k] = v if math.isnan(hi[k]) else max(hi[k], v)

    for c in colliders:
        for k in range(3):
            if c["type"] in ("box", "mesh"):
                grow(k, c["lo"][k])
                grow(k, c["hi"][k])
            elif c["type"] == "sphere":
                grow(k, c["center"][k] - c["radius"])
                grow(k, c["center"][k] + c["radius"])
    known = ~np.isnan(lo)
    span = float(np.max(hi[known] - lo[known])) if known.any() else 0.0
    span = span or 1.0
    return np.where(known, lo, -0.5 * span), np.where(known, hi, 0.5 * span)


def _springs(traj: Any, particles: int, particle_stride: int) -> np.ndarray | None:
    """The springs' ends as the columns of the page's particles (``ids`` mapped to columns,
    then to the kept columns when particles are left out), flattened to int32; springs with
    an end that is unknown or left out are dropped. None when the trajectory has none."""
    springs = getattr(traj, "springs", None)
    if springs is None:
        return None
    springs = np.asarray(springs, dtype=np.int64).reshape(-1, 2)
    if springs.size == 0:
        return None
    ids = getattr(traj, "ids", None)
    ids = np.arange(particles) if ids is None or np.size(ids) != particles else np.asarray(ids, dtype=np.int64).reshape(-1)
    order = np.argsort(ids, kind="stable")
    where = np.clip(np.searchsorted(ids, springs, sorter=order), 0, max(ids.size - 1, 0))
    columns = order[where] if ids.size else np.zeros_like(springs)
    known = (ids[columns] == springs).all(axis=1) if ids.size else np.zeros(len(springs), dtype=bool)
    kept = known & (columns % particle_stride == 0).all(axis=1)
    return np.ascontiguousarray((columns[kept] // particle_stride).reshape(-1), dtype="<i4")


def _colors(traj: Any, particles: int, particle_stride: int) -> np.ndarray | None:
    """The particles' own colours (``Trajectory.colors``, r g b in [0, 1], NaN: none) as RGBA
    bytes, A 255 where a particle has one and 0 where not; None when none has one."""
    colors = getattr(traj, "colors", None)
    if colors is None or np.shape(colors) != (particles, 3):
        return None
    colors = np.asarray(colors, dtype=np.float64)[::particle_stride]
    own = np.isfinite(colors).all(axis=1)
    if not own.any():
        return None
    rgba = np.zeros((len(colors), 4), dtype=np.uint8)
    rgba[own, :3] = np.round(np.clip(colors[own], 0.0, 1.0) * 255.0).astype(np.uint8)
    rgba[own, 3] = 255
    return rgba


def _id_range(ids: np.ndarray) -> list[int]:
    """The lowest and highest id of the particles shown (the legend's ends, shown exactly);
    their columns' numbers when the ids are not numbers."""
    try:
        return [int(ids.min()), int(ids.max())] if ids.size else [0, 0]
    except (TypeError, ValueError):
        return [0, max(int(ids.size) - 1, 0)]


#: The page's colourings (its menu): ``color`` is each particle's own colour.
COLOR_BY = ("speed", "id", "color", "none")


def camera_meta(camera: Any, dim: int) -> dict[str, Any] | None:
    """The camera the page opens with, as the page reads it: ``None`` (the page fits its own
    view to the scene), a ``kinema.Camera3D`` (3D: ``{"type": "3d", "eye", "target", "up",
    "fovDeg"}``, a pinhole at eye looking at target, fovDeg the vertical field of view, as the
    renderer draws it) or a ``kinema.Camera2D`` (2D: ``{"type": "2d", "view": [xmin, ymin,
    xmax, ymax]}``, the rectangle fitted to the canvas, centred, aspect kept): a scene's
    ``[render] camera``. A camera of the other dimension than the trajectory's is refused."""
    from ..render import Camera2D, Camera3D

    if camera is None:
        return None
    if isinstance(camera, Camera3D):
        if dim == 2:
            raise ValueError(f"camera = {camera!r} is invalid: a 2D trajectory is viewed by a kinema.Camera2D (its xy rectangle)")
        out = {"type": "3d", **{k: [float(x) for x in v] for k, v in camera._kwargs().items() if k != "fov_deg"}, "fovDeg": float(camera.fov_deg)}
    elif isinstance(camera, Camera2D):
        if dim != 2:
            raise ValueError(f"camera = {camera!r} is invalid: a 3D trajectory is viewed by a kinema.Camera3D (eye, target, up, fov_deg)")
        out = {"type": "2d", "view": [float(x) for x in camera._kwargs()["view"]]}
    else:
        raise TypeError(f"camera = {camera!r} is invalid: give a kinema.Camera3D (3D), a kinema.Camera2D (2D) or None (the page fits its own view)")
    values = [x for k, v in out.items() if k != "type" for x in (v if isinstance(v, list) else [v])]
    if not all(math.isfinite(x) for x in values):
        raise ValueError(f"camera = {camera!r} is invalid: its values must be finite")
    return out


def pack(traj: Any, max_bytes: int, color_by: str | None = None, camera: Any = None) -> Packed:
    """The frames of ``traj`` as a page shows them, left out by strides if they are over
    ``max_bytes`` (a ``ViewerWarning`` says so, and the page shows a note). ``color_by`` (one
    of ``COLOR_BY``, as a scene's ``[render] color_by``) is the colouring the page opens
    with; None: speed (id when the speeds are unknown). ``camera`` (a scene's ``[render]
    camera``: ``kinema.Camera3D`` or ``kinema.Camera2D``) is the view it opens with; None:
    its own, fitted to the scene (see ``camera_meta``)."""
    if color_by is not None and color_by not in COLOR_BY:
        raise ValueError(f"color_by = {color_by!r} is invalid: use one of {', '.join(COLOR_BY)}")
    positions = np.asarray(traj.positions, dtype=np.float64)
    if positions.ndim != 3 or positions.shape[2] != 3 or positions.shape[0] == 0:
        raise ValueError(f"positions must be (frames, particles, 3) with at least one frame, got {positions.shape}")
    frames, particles, _ = positions.shape
    dim = int(getattr(traj, "dim", 3) or 3)
    opening_view = camera_meta(camera, dim)
    velocities = getattr(traj, "velocities", None)
    has_speed = velocities is not None and np.shape(velocities) == positions.shape
    per_particle = 4 * (3 + (1 if has_speed else 0))
    fs, ps = _strides(frames, particles, per_particle, max_bytes)
    note = ""
    if fs > 1 or ps > 1:
        kept_f, kept_n = len(range(0, frames, fs)), len(range(0, particles, ps))
        note = f"showing {kept_f} of {frames} frames and {kept_n} of {particles} particles"
        warnings.warn(f"the viewer is {note} (the frames are over {max_bytes / 1e6:.0f} MB)", ViewerWarning, stacklevel=3)
    positions = positions[::fs, ::ps]
    # A particle is drawn where the trajectory says it is alive and its position is finite
    # (NaN where it is not alive, and JSON and the page have no use for NaN: 0 with the mask).
    alive = getattr(traj, "alive", None)
    alive = np.ones((frames, particles), dtype=bool) if alive is None or np.shape(alive) != (frames, particles) else np.asarray(alive, dtype=bool)
    alive = alive[::fs, ::ps] & np.isfinite(positions).all(axis=2)
    t = np.asarray(traj.t, dtype=np.float64)[::fs]
    speed, speed_min, speed_max = None, 0.0, 0.0
    if has_speed:
        speed = np.linalg.norm(np.asarray(velocities, dtype=np.float64)[::fs, ::ps], axis=2).astype("<f4")
        known = alive & np.isfinite(speed)
        if known.any():
            speed_min, speed_max = float(speed[known].min()), float(speed[known].max())
            speed[~known] = 0.0
        else:
            speed = None  # velocities unknown (NaN): no colouring by speed
    out_positions = np.ascontiguousarray(positions, dtype="<f4")
    out_positions[~alive] = 0.0

    radii = getattr(traj, "radii", None)
    radii = None if radii is None or np.size(radii) != particles else np.asarray(radii, dtype=np.float64).reshape(-1)[::ps]
    lo, hi, plo, phi = _live_box(positions, alive, radii)
    extent = float(np.max(hi - lo)) or 1.0
    default_radius = extent / 200.0  # as Trajectory.render draws particles without a radius
    if radii is None or not np.all(radii > 0):
        # Particles without a radius (or with 0) are drawn at the default radius.
        plo, phi = np.minimum(plo, lo - default_radius), np.maximum(phi, hi + default_radius)
        radii = np.full(positions.shape[1], default_radius) if radii is None else np.where(radii > 0, radii, default_radius)
    if not alive.any():
        plo, phi = np.full(3, np.nan), np.full(3, np.nan)
    colliders, paths = _colliders(getattr(traj, "colliders", None), t)
    elo, ehi = _extent(plo, phi, colliders + paths)
    ids = getattr(traj, "ids", None)
    ids = np.arange(particles) if ids is None or np.size(ids) != particles else np.asarray(ids).reshape(-1)
    ids = ids[::ps]
    springs = _springs(traj, particles, ps)
    bits = None if alive.all() else np.packbits(alive, axis=1, bitorder="little")
    pad = float(radii.max()) if radii.size else 0.0
    meta = {
        "n": int(positions.shape[1]),
        "frames": int(positions.shape[0]),
        "dim": dim,
        "t": [float(x) for x in t],
        "bounds": {"min": [float(x) - pad for x in lo], "max": [float(x) + pad for x in hi]},
        # What the camera frames and the colliders are drawn within (open boxes up to it,
        # floor patches around it): the live particles with their radii, over every frame,
        # and the colliders' finite parts (a moving one's wherever it goes).
        "extent": {"min": [float(x) for x in elo], "max": [float(x) for x in ehi]},
        "colliders": colliders,
        "speedMin": speed_min,
        "speedMax": speed_max,
        "idRange": _id_range(ids),
        "springCount": 0 if springs is None else int(springs.size // 2),
        "aliveBytes": 0 if bits is None else int(bits.shape[1]),
        "defaultRadius": default_radius,
        "note": note,
        "colorBy": color_by,
        # What "color" draws a particle without its own colour in (the renderer's colour).
        "noOwnColor": list(NO_OWN_COLOR),
        # The view the page opens with (a scene's [render] camera); None: fitted to the scene.
        "camera": opening_view,
    }
    return Packed(meta, out_positions, speed, np.ascontiguousarray(radii, dtype="<f4"), springs, bits, _colors(traj, particles, ps))


def _live_box(positions: np.ndarray, alive: np.ndarray, radii: np.ndarray | None) -> tuple[np.ndarray, ...]:
    """The live particles' box over every frame, bare (lo, hi) and with each particle's own
    radius (plo, phi), a block of frames at a time (no copy of all the frames); (0, 1) bare
    where nothing is alive anywhere."""
    lo, hi, plo, phi = (np.full(3, v) for v in (np.inf, -np.inf, np.inf, -np.inf))
    block = max(1, 2**20 // max(positions.shape[1], 1))
    for k in range(0, positions.shape[0], block):
        mask = alive[k : k + block]
        if not mask.any():
            continue
        live = positions[k : k + block][mask]
        lo, hi = np.minimum(lo, live.min(axis=0)), np.maximum(hi, live.max(axis=0))
        if radii is not None:
            r = np.broadcast_to(np.where(radii > 0, radii, 0.0), mask.shape)[mask][:, None]
            plo, phi = np.minimum(plo, (live - r).min(axis=0)), np.maximum(phi, (live + r).max(axis=0))
    if not np.isfinite(lo).all():
        lo, hi = np.zeros(3), np.ones(3)  # nothing alive anywhere
    return lo, hi, plo, phi


def bundle() -> str:
    """The built viewer script (shipped in the package); ``BundleMissingError`` when it is missing."""
    if not BUNDLE.is_file():
        raise BundleMissingError()
    script = BUNDLE.read_text(encoding="utf-8")
    # Inside <script> only "</script" ends the element; the bundle is escaped where it could.
    return re.sub(r"</(script)", r"<\\/\1", script, flags=re.IGNORECASE)


def page(meta: dict[str, Any], title: str = "kinema") -> str:
    """The HTML page around ``meta`` (the content of the kinema-data element) and the bundle."""
    data = json.dumps(meta, separators=(",", ":")).replace("</", "<\\/")
    parts = {"TITLE": title.replace("&", "&amp;").replace("<", "&lt;"), "DATA": data, "SCRIPT": bundle()}
    template = TEMPLATE.read_text(encoding="utf-8")
    return re.sub(r"\{\{(TITLE|DATA|SCRIPT)\}\}", lambda m: parts[m.group(1)], template)


def _b64(array: np.ndarray) -> str:
    return base64.b64encode(array.tobytes()).decode("ascii")


def html_page(traj: Any, *, title: str = "kinema", max_bytes: int = HTML_MAX_BYTES, color_by: str | None = None, camera: Any = None) -> str:
    """The self-contained page of ``traj`` as text (see :func:`write_html`)."""
    bundle()  # fail before any work when the script is not built
    packed = pack(traj, max_bytes, color_by, camera)
    meta = dict(packed.meta, positions=_b64(packed.positions), radii=_b64(packed.radii))
    for name in ("speed", "springs", "alive", "colors"):
        array = getattr(packed, name)
        meta[name] = _b64(array) if array is not None else None
    return page(meta, title)


def write_html(
    traj: Any, path: str | os.PathLike, *, title: str = "kinema", max_bytes: int = HTML_MAX_BYTES, color_by: str | None = None, camera: Any = None
) -> Path:
    """Write one self-contained HTML file that plays ``traj`` offline (the script and the
    frames inlined, the frames as base64 float32) and return its path. The file is written
    under a temporary name and renamed. Frames, then particles, are left out by strides when
    the frame data is over ``max_bytes`` (a ``ViewerWarning`` says so). ``color_by``: the
    colouring the page opens with, ``speed``, ``id``, ``color`` (each particle's own, as
    ``[render] color_by = "color"``) or ``none``; None: speed. ``camera``: the view the page
    opens with, a scene's ``[render] camera`` (``kinema.Camera3D``: eye, target, up, vertical
    field of view; ``kinema.Camera2D``: the xy rectangle, fitted centred); None: the page's
    own view, fitted to the scene."""
    text = html_page(traj, title=title, max_bytes=max_bytes, color_by=color_by, camera=camera)
    path = Path(path)
    with atomic_file(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path
