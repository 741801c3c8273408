"""Cameras: `Camera2D` (orthographic, xy) and `Camera3D` (pinhole), and the default camera
that frames where the particles spend the run and where they end (with the walls of the box
they are in) into the frame, clear of the legend."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import _core


@dataclass(frozen=True)
class Camera2D:
    """Orthographic view of the xy-plane: the rectangle [xmin, xmax] × [ymin, ymax] (m) fits the
    image, centred, aspect kept (x to the right, y up)."""

    xmin: float
    ymin: float
    xmax: float
    ymax: float

    @classmethod
    def framing(cls, lo, hi, margin: float = 0.0) -> Camera2D:
        """The box [lo, hi] (xy, m) widened by `margin` (m) on every side."""
        return cls(lo[0] - margin, lo[1] - margin, hi[0] + margin, hi[1] + margin)

    def _kwargs(self) -> dict:
        return {"view": (float(self.xmin), float(self.ymin), float(self.xmax), float(self.ymax))}


@dataclass(frozen=True)
class Camera3D:
    """Pinhole camera at `eye` (m) looking at `target` (m), `up` the image's up direction
    (z is up by default), `fov_deg` the vertical field of view in degrees."""

    eye: tuple[float, float, float]
    target: tuple[float, float, float]
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    fov_deg: float = 40.0

    @classmethod
    def framing(cls, lo, hi, direction=(1.0, -1.6, 0.9), fov_deg: float = 40.0, width: int = 1280, height: int = 720, margin: float | None = None) -> Camera3D:
        """A camera looking at the box [lo, hi] (m) from `direction` (box → eye), as near
        as it can be with all 8 corners in view: they fill the image's width or height (both
        fields of view are fitted) up to `margin` (a fraction of each side; default
        `FRAME_MARGIN`, 3 %), centred."""
        m = _core.FRAME_MARGIN if margin is None else float(margin)
        if not 0.0 <= m < 0.5:
            raise ValueError(f"margin = {margin!r} is invalid: a fraction of the image in [0, 0.5)")
        window = (m * width, m * height, (1.0 - m) * width, (1.0 - m) * height)
        eye, target, up, _ = _core.frame_points(_corners(lo, hi), _vec3(direction), float(fov_deg), int(width), int(height), window)
        return cls(tuple(eye), tuple(target), tuple(up), float(fov_deg))

    def _kwargs(self) -> dict:
        return {"eye": _vec3(self.eye), "target": _vec3(self.target), "up": _vec3(self.up), "fov_deg": float(self.fov_deg)}


def _vec3(v) -> list[float]:
    return [float(c) for c in v]


def _corners(lo, hi) -> np.ndarray:
    """The 8 corners of the box [lo, hi], (8, 3)."""
    lo, hi = np.asarray(_vec3(lo)), np.asarray(_vec3(hi))
    return np.array([[(hi if c >> k & 1 else lo)[k] for k in range(3)] for c in range(8)])


#: The camera direction of the default 3D view (box → eye): front right, above.
_VIEW_FROM = (1.0, -1.6, 0.9)


#: The share of the particles the default camera may leave out on each side of each axis,
#: in the last frame and over the run: a few flung far away take no room from the rest (the
#: k-th of N from the side, k = floor(0.005 N): none of fewer than 200 in the last frame).
OUTLIER_SHARE = 0.005
#: Where the particles pass through only briefly, a tail of the run's positions along an
#: axis whose density (time spent per metre, ``DENSITY_BINS`` bins) is under this fraction of
#: the typical density (the median that the run's positions see), is left out of the
#: default camera's box, up to ``TRANSIENT_SHARE`` of the run on each side: the column balls
#: fall from before they pile up, not the path of a ball that sweeps across (its density is
#: even) nor an orbit. The last frame is always in view (up to ``OUTLIER_SHARE``).
SPARSE_DENSITY = 0.25
TRANSIENT_SHARE = 0.4
DENSITY_BINS = 48
#: A collider box whose wall lies within this fraction of the particles' region's largest
#: span beyond it widens the region to that wall (the box the particles are in, whole on
#: that side); a farther wall (the top of a tall box, an open top) does not.
WALL_REACH = 0.5
#: A mesh whose box holds the particles' region in x and y (a bowl they rest in) is framed
#: whole when its largest span is at most this many times the region's: the bowl reads as a
#: bowl, not as a curved floor under a pile; a larger one (a terrain) is a wall as above.
MESH_REACH = 4.0
#: The most frames and particles per frame sampled for the default camera (evenly spaced).
_SAMPLE_FRAMES, _SAMPLE_PARTICLES = 240, 20000


def _frame_corners(x, r, colliders, lo, hi, marks=None, dim: int = 3) -> np.ndarray:
    """(P, 3): the points the default camera frames: the 8 corners of the particles' region
    (`_particle_region`: where they spend the run and where they end), widened to the walls
    of the colliders that bound it (`colliders`: descriptions, `_describe_colliders`; a
    box's finite walls, a sphere's cube, a mesh's box; planes and infinite bounds none), the
    vertices of a mesh around them (`MESH_REACH`: the bowl they rest in, whole), and the
    `marks`
    (attractors). In 2D a box of finite walls that holds the particles is framed whole (the
    table). No particle alive in any frame: the colliders' finite parts, else [lo, hi] (the
    scene's extent)."""
    marks = np.zeros((0, 3)) if marks is None or not len(marks) else np.asarray(marks, np.float64).reshape(-1, 3)
    region = _particle_region(x, r)
    boxes = [box for box in map(_collider_box, colliders) if box is not None]
    meshes = [np.asarray(d["vertices"], np.float64).reshape(-1, 3) for d in colliders if d["type"] == "mesh"]
    if region is None:
        finite = [np.clip(_corners(a, b), lo, hi) for a, b in boxes]
        return np.concatenate(finite + [marks]) if finite else np.concatenate([_corners(lo, hi), marks])
    low, high = region
    if not np.max(high - low) > 0.0:  # one point particle: the scene's extent
        low, high = np.asarray(lo, np.float64), np.asarray(hi, np.float64)
    reach = WALL_REACH * float(np.max(high - low))
    grown_lo, grown_hi = low.copy(), high.copy()
    for a, b in boxes:
        if dim == 2 and np.all(np.isfinite([*a[:2], *b[:2]])) and np.all(a[:2] <= low[:2] + reach) and np.all(b[:2] >= high[:2] - reach):
            grown_lo[:2], grown_hi[:2] = np.minimum(grown_lo[:2], a[:2]), np.maximum(grown_hi[:2], b[:2])
            continue
        if np.any(a > high + reach) or np.any(b < low - reach):
            continue  # not around or beside the particles
        near_lo = (a < low) & (low - a <= reach)
        near_hi = (b > high) & (b - high <= reach)
        grown_lo = np.where(near_lo, np.minimum(grown_lo, a), grown_lo)
        grown_hi = np.where(near_hi, np.maximum(grown_hi, b), grown_hi)
    around = []  # the vertices (up to _SAMPLE_PARTICLES, evenly spaced) of the meshes around them
    for v in meshes:
        a, b = v.min(axis=0), v.max(axis=0)
        if np.all(a[:2] <= low[:2]) and np.all(b[:2] >= high[:2]) and np.max(b - a) <= MESH_REACH * float(np.max(high - low)):
            around.append(v[np.unique(np.round(np.linspace(0, len(v) - 1, min(len(v), _SAMPLE_PARTICLES))).astype(int))])
    return np.concatenate([_corners(grown_lo, grown_hi), *around, marks])


def _collider_box(d):
    """(lo, hi) (3,) of a collider description: a box's bounds (z 0 in 2D; may be infinite),
    a sphere's cube, the box of a mesh's vertices; None for a plane."""
    if d["type"] == "box":
        lo, hi = (np.append(np.asarray(d[k], np.float64), 0.0)[:3] for k in ("lo", "hi"))
        return lo, hi
    if d["type"] == "sphere":
        c, radius = np.asarray(d["center"], np.float64), float(d["radius"])
        return c - radius, c + radius
    if d["type"] == "mesh":
        vertices = np.asarray(d["vertices"], np.float64).reshape(-1, 3)
        return vertices.min(axis=0), vertices.max(axis=0)
    return None


def _particle_region(x, r):
    """(lo, hi), the box of the particles (radii included) that the default camera frames, or
    None when none is alive: where they spend the run (all frames, up to `_SAMPLE_FRAMES`
    evenly spaced, each weighing the same; `OUTLIER_SHARE` and the sparse tails left out,
    `_dense_span`) and where they end (the last frame, `OUTLIER_SHARE` left out)."""
    live = np.all(np.isfinite(x), axis=2)
    rows = np.flatnonzero(live.any(axis=1))
    if rows.size == 0:
        return None
    last = rows[-1]
    if rows.size > _SAMPLE_FRAMES:
        rows = rows[np.round(np.linspace(0, rows.size - 1, _SAMPLE_FRAMES)).astype(int)]
    centres, radii, weights = [], [], []
    for k in rows:
        idx = np.flatnonzero(live[k])
        if idx.size > _SAMPLE_PARTICLES:
            idx = idx[np.round(np.linspace(0, idx.size - 1, _SAMPLE_PARTICLES)).astype(int)]
        centres.append(x[k, idx])
        radii.append(r[idx])
        weights.append(np.full(idx.size, 1.0 / idx.size))
    c, rs, w = np.concatenate(centres), np.concatenate(radii), np.concatenate(weights)
    run = np.array([_dense_span(c[:, d], rs, w) for d in range(3)])
    end_lo, end_hi = _robust_box(x[last], r, live[last])
    return np.minimum(run[:, 0], end_lo), np.maximum(run[:, 1], end_hi)


def _dense_span(v, r, w):
    """(lo, hi) along one axis of the weighted positions `v` (radii `r`): less
    `OUTLIER_SHARE` of the weight at each side, then less the sparse tails (bins under
    `SPARSE_DENSITY` of the typical density, at most `TRANSIENT_SHARE` of the weight)."""
    total = w.sum()
    lo = _weighted_end(v - r, w, OUTLIER_SHARE * total, low=True)
    hi = _weighted_end(v + r, w, OUTLIER_SHARE * total, low=False)
    if not hi > lo:
        return lo, hi
    edges = np.linspace(lo, hi, DENSITY_BINS + 1)
    inside = (v >= lo) & (v <= hi)
    if not inside.any():
        return lo, hi
    mass = np.bincount(np.clip(np.searchsorted(edges, v[inside], side="right") - 1, 0, DENSITY_BINS - 1), w[inside], DENSITY_BINS)
    where = np.clip(np.searchsorted(edges, v[inside], side="right") - 1, 0, DENSITY_BINS - 1)
    seen = mass[where]  # the density each position sees
    order = np.argsort(seen, kind="stable")
    typical = seen[order][min(int(np.searchsorted(np.cumsum(w[inside][order]), 0.5 * w[inside].sum())), seen.size - 1)]
    sparse = mass < SPARSE_DENSITY * typical
    first, cut = 0, 0.0
    while first < DENSITY_BINS - 1 and sparse[first] and cut + mass[first] <= TRANSIENT_SHARE * total:
        cut += mass[first]
        first += 1
    end, cut = DENSITY_BINS - 1, 0.0
    while end > first and sparse[end] and cut + mass[end] <= TRANSIENT_SHARE * total:
        cut += mass[end]
        end -= 1
    rmax = float(r.max())
    return (lo if first == 0 else edges[first] - rmax), (hi if end == DENSITY_BINS - 1 else edges[end + 1] + rmax)


def _weighted_end(values, weights, beyond, low):
    """The least value (`low`; else the greatest) with at most the weight `beyond` of the
    others below it (above it)."""
    order = np.argsort(values if low else -values, kind="stable")
    before = np.cumsum(weights[order]) - weights[order]
    return float(values[order[np.flatnonzero(before <= beyond)[-1]]])


def _robust_box(x, r, live):
    """(lo, hi) (3,) of the live particles of one frame, radii included, less
    `OUTLIER_SHARE` of them on each side of each axis."""
    idx = np.flatnonzero(live)
    if idx.size > _SAMPLE_PARTICLES:
        idx = idx[np.round(np.linspace(0, idx.size - 1, _SAMPLE_PARTICLES)).astype(int)]
    k = int(OUTLIER_SHARE * idx.size)
    low = np.partition(x[idx] - r[idx, None], k, axis=0)[k]
    high = -np.partition(-(x[idx] + r[idx, None]), k, axis=0)[k]
    return low, high


def _auto_camera(lo, hi, dim, width, height, avoid=None, fov_deg: float = 40.0, points=None):
    """The camera that fits the scene into the frame to `FRAME_MARGIN` of its sides (2D: the
    xy rectangle of the box [lo, hi], orthographic; 3D: `points`, by default the 8 corners
    of [lo, hi], seen from `_VIEW_FROM`, both fields of view fitted). When the scene would
    overlap `avoid` (x0, y0, x1, y1 pixels: the legend), it is fitted either between it and
    its mirror image on the left or below it, whichever leaves it larger."""
    m = _core.FRAME_MARGIN
    w, h = float(width), float(height)

    def fit(window):
        if dim == 2:
            if points is None:
                return _fit_2d(lo, hi, w, h, window)
            return _fit_2d(points.min(axis=0), points.max(axis=0), w, h, window)
        pts = _corners(lo, hi) if points is None else points
        eye, target, up, box = _core.frame_points(pts, _VIEW_FROM, fov_deg, int(width), int(height), window)
        return Camera3D(tuple(eye), tuple(target), tuple(up), fov_deg), box

    full = (m * w, m * h, (1.0 - m) * w, (1.0 - m) * h)
    camera, box = fit(full)
    if avoid is None or not (box[0] < avoid[2] and avoid[0] < box[2] and box[1] < avoid[3] and avoid[1] < box[3]):
        return camera
    best, area = camera, 0.0
    # Beside it: a window narrowed on both sides, so that the view stays centred (a scene off
    # the axis of a perspective camera leans); under it: the rows below the legend.
    side = w - avoid[0] + m * w
    for window in ((side, full[1], w - side, full[3]), (full[0], avoid[3] + m * h, full[2], full[3])):
        if window[2] - window[0] < 0.3 * w or window[3] - window[1] < 0.3 * h:
            continue
        c, b = fit(window)
        if (b[2] - b[0]) * (b[3] - b[1]) > area:
            best, area = c, (b[2] - b[0]) * (b[3] - b[1])
    return best


def _fit_2d(lo, hi, w, h, window):
    """The Camera2D showing the rectangle [lo, hi] (xy) as large as fits the pixel window,
    centred in it, and the rectangle's pixel box."""
    x0, y0, x1, y1 = window
    span = np.asarray(hi[:2], float) - np.asarray(lo[:2], float)
    s = min((x1 - x0) / span[0], (y1 - y0) / span[1])  # pixels per metre
    left, top = x0 + 0.5 * ((x1 - x0) - s * span[0]), y0 + 0.5 * ((y1 - y0) - s * span[1])
    xmin, ymax = float(lo[0]) - left / s, float(hi[1]) + top / s
    camera = Camera2D(xmin, ymax - h / s, xmin + w / s, ymax)
    return camera, (left, top, left + s * span[0], top + s * span[1])
