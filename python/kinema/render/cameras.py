"""Cameras: ``Camera2D`` (orthographic, xy) and ``Camera3D`` (pinhole), and the default camera
that fits the whole scene into the frame, clear of the legend."""

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
        """The box [lo, hi] (xy, m) widened by ``margin`` (m) on every side."""
        return cls(lo[0] - margin, lo[1] - margin, hi[0] + margin, hi[1] + margin)

    def _kwargs(self) -> dict:
        return {"view": (float(self.xmin), float(self.ymin), float(self.xmax), float(self.ymax))}


@dataclass(frozen=True)
class Camera3D:
    """Pinhole camera at ``eye`` (m) looking at ``target`` (m), ``up`` the image's up direction
    (z is up by default), ``fov_deg`` the vertical field of view in degrees."""

    eye: tuple[float, float, float]
    target: tuple[float, float, float]
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    fov_deg: float = 40.0

    @classmethod
    def framing(cls, lo, hi, direction=(1.0, -1.6, 0.9), fov_deg: float = 40.0, width: int = 1280, height: int = 720, margin: float | None = None) -> Camera3D:
        """A camera looking at the box [lo, hi] (m) from ``direction`` (box → eye), as near
        as it can be with all 8 corners in view: they fill the image's width or height (both
        fields of view are fitted) up to ``margin`` (a fraction of each side; default
        ``FRAME_MARGIN``, 3 %), centred."""
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


def _frame_corners(x, r, collider_boxes, lo, hi) -> np.ndarray:
    """(P, 3): the corners of each frame's box of its live particles (radii included) and of
    each collider's box (``_core.Scenery.boxes``: a box's infinite bounds at the extent [lo,
    hi], a sphere's cube). Each frame's box, not one over all frames, so that a scene whose
    parts sit apart in space and time (a cloth above a sphere, then draped on it) is framed
    by what it shows: the box around all of it has empty corners that would take room in
    the frame."""
    live = np.all(np.isfinite(x), axis=2)
    rows = live.any(axis=1)
    boxes = []
    if rows.any():
        xr = x[rows]
        low = np.where(live[rows][:, :, None], xr - r[None, :, None], np.inf).min(axis=1)
        high = np.where(live[rows][:, :, None], xr + r[None, :, None], -np.inf).max(axis=1)
        boxes += list(zip(low, high, strict=True))
    boxes += collider_boxes
    if not boxes:
        return _corners(lo, hi)
    return np.concatenate([_corners(a, b) for a, b in boxes])


def _auto_camera(lo, hi, dim, width, height, avoid=None, fov_deg: float = 40.0, points=None):
    """The camera that fits the scene into the frame to ``FRAME_MARGIN`` of its sides (2D: the
    xy rectangle of the box [lo, hi], orthographic; 3D: ``points``, by default the 8 corners
    of [lo, hi], seen from ``_VIEW_FROM``, both fields of view fitted). When the scene would
    overlap ``avoid`` (x0, y0, x1, y1 pixels: the legend), it is fitted either between it and
    its mirror image on the left or below it, whichever leaves it larger."""
    m = _core.FRAME_MARGIN
    w, h = float(width), float(height)

    def fit(window):
        if dim == 2:
            return _fit_2d(lo, hi, w, h, window)
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
