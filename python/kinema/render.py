"""Off-screen rendering of particle trajectories into frames, MP4 (H.264) and GIF.

2D scenes are drawn as antialiased discs seen from +z, 3D scenes as shaded spheres in
perspective, far to near. Particles are coloured by speed, by id, or by any per-particle field,
and each frame carries a time stamp. The world's colliders can be drawn with them
(``colliders=``): in 3D a plane is a floor patch with a faint grid, a box its edges and a
lightly filled floor, a sphere obstacle a grey shaded sphere; in 2D a plane is a thick line
with its solid side shaded, a box a rectangle outline, a sphere obstacle a grey disc. Pixels
are drawn by the engine (``kinema._core``, in parallel, with the GIL released); this module
chooses cameras and colours and writes files. Springs (``springs=``, pairs of particles) are
lines between the particles, and particles not alive in a frame (``alive=``, or NaN
positions: births and deaths) are left out, with their springs. Particles coloured by a
quantity get a colour bar with its name, units and range in the top right corner
(``legend=``). The default camera fits the whole scene, particles of every frame and the
colliders' finite parts, into the frame's width and height, clear of the legend.

    frames = render_frames(traj_x, radius=0.01, t=traj_t, dim=3, color_by="speed", colliders=world.colliders)
    write_video(frames, "out.mp4", fps=30, times=traj_t)  # exactly 30 fps, in real time

MP4s are BT.709, tagged so, with ``moov`` first; ``video_rate`` gives the exact frame rate a
file is written at (GIF delays are whole 1/100 s).
"""

from __future__ import annotations

import math
import numbers
import os
import tempfile
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import numpy as np

from . import _core

__all__ = ["Camera2D", "Camera3D", "COLORMAPS", "render_frames", "write_video", "video_rate", "VIDEO_EXTENSIONS"]

#: Names accepted by ``colormap=``.
COLORMAPS: tuple[str, ...] = tuple(_core.COLORMAP_NAMES)
#: File extensions ``write_video`` knows.
VIDEO_EXTENSIONS = (".mp4", ".gif")


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


def render_frames(
    positions,
    radius,
    t,
    *,
    dim: int = 3,
    color_by="speed",
    velocities=None,
    colormap: str = "viridis",
    vmin: float | None = None,
    vmax: float | None = None,
    width: int = 1280,
    height: int = 720,
    camera: Camera2D | Camera3D | None = None,
    background=(255, 255, 255),
    time_format: str | None = "t = {:.3f} s",
    label_scale: int = 2,
    min_radius_px: float = 1.0,
    colliders=None,
    alive=None,
    springs=None,
    spring_width: float | None = None,
    legend: bool | str = True,
) -> Iterator[np.ndarray]:
    """Yield one (height, width, 3) uint8 RGB frame per time.

    positions: (F, N, 3) or, for ``dim=2``, (F, N, 2) positions in m (2D uses x and y).
    radius: one radius for all particles or one per particle (N,), m.
    t: (F,) times, s, stamped on each frame with ``time_format`` (None: no stamp; the stamp
      may use only digits, '.', '-', '+', ':', '=', ' ', 't', 's', 'e').
    color_by: "speed" (|v|, from ``velocities`` (F, N, dim) or else from finite differences of
      the positions in t), "id" (categorical colours by particle index), a field of floats of
      shape (N,) or (F, N) mapped through ``colormap`` between ``vmin`` and ``vmax`` (default:
      the field's minimum and maximum over all frames, so colours mean the same in every
      frame), or fixed uint8 colours of shape (N, 3) or (F, N, 3).
    camera: a Camera2D / Camera3D; default: the bounding box of the live particles of all
      frames (with the largest radius) and of the colliders' finite parts fills the frame's
      width or height, whichever binds, to 3 % of its sides, centred (a 3D box seen from the
      front right and above; both fields of view are fitted), and kept clear of the legend.
    background: RGB8 colour.
    colliders: colliders to draw, ``kinema.Plane`` / ``Box`` / ``SphereObstacle`` objects or
      their descriptions (``Trajectory.colliders``: dicts {"type": "plane", "point",
      "normal"}, {"type": "box", "lo", "hi"}, {"type": "sphere", "center", "radius"}); None
      draws none. Infinite box bounds (an open top) are drawn up to the scene's extent.
    alive: (F, N) bools (or (N,), the same in every frame): the particles that exist in each
      frame (``Trajectory.alive``: births and deaths). Those that do not, and any with a
      non-finite position, are not drawn, count for neither the camera nor the colour range,
      and their springs are not drawn. A frame with none alive shows the scenery alone.
    springs: (S, 2) particle indices (columns of ``positions``) joined by springs, strings or
      bonds, each drawn as a grey line (``_core.LINE_COLOR``) ``spring_width`` pixels wide
      (default: 1 per 480 rows, at least 1) from one particle's rim to the other's, in frames
      where both are alive.
    legend: when the particles are coloured by a quantity (speed or a field of values; not
      ids or fixed colours), a colour bar from ``vmin`` to ``vmax`` with the quantity's name
      and units ("speed (m/s)"; a string gives them, e.g. "temperature (K)"; a field is
      "value" otherwise) in the top right corner, beside the time stamp, its text as tall
      (``label_scale``). False: none. It is left out of frames under 160 × 120 pixels or too
      narrow for it, which have no room for it.
    """
    if dim not in (2, 3):
        raise ValueError(f"dim = {dim!r} is invalid: use 2 (discs in the xy-plane) or 3 (spheres)")
    x = np.asarray(positions, dtype=np.float64)
    if x.ndim != 3 or x.shape[2] not in (dim, 3):
        raise ValueError(f"positions has shape {x.shape}: expected (F, N, 3){' or (F, N, 2)' if dim == 2 else ''}")
    n_frames, n = x.shape[:2]
    times = np.asarray(t, dtype=np.float64).reshape(-1)
    if times.shape != (n_frames,):
        raise ValueError(f"t has {times.size} times: expected one per frame ({n_frames})")
    if x.shape[2] == 2:
        x = np.concatenate([x, np.zeros((n_frames, n, 1))], axis=2)
    elif dim == 2:
        x = x.copy()
        x[:, :, 2] = 0.0
    r = np.broadcast_to(np.asarray(radius, dtype=np.float64), (n,))
    r = np.ascontiguousarray(r)
    if not np.all(np.isfinite(r)) or np.any(r < 0):
        raise ValueError("radius is invalid: radii must be finite and >= 0")
    live = _live(alive, x)
    if not live.all():
        x = np.where(live[:, :, None], x, np.nan)  # the dead are nowhere: no camera, no colour range
    pairs = _springs(springs, n)
    if spring_width is None:
        spring_width = max(1.0, height / 480.0)

    colors, values, vmin, vmax = _colouring(color_by, x, times, velocities, dim, vmin, vmax)
    # The colliders become the engine's once; the engine lays the scene out (its extent:
    # all frames' live particles and the colliders' finite parts, widened by the largest
    # radius), one extent for every frame, so that floors and open walls stay put.
    scenery = _core.Scenery(_describe_colliders(colliders) if colliders is not None else [], x.reshape(-1, 3), r)
    lo, hi = (np.array(corner) for corner in scenery.extent)
    bg = tuple(int(c) for c in background)
    luminance = 0.299 * bg[0] + 0.587 * bg[1] + 0.114 * bg[2]
    label_color = (0, 0, 0) if luminance > 128 else (255, 255, 255)
    key = None
    if legend is not False and legend is not None and colors is None and width >= 160 and height >= 120:
        name = legend if isinstance(legend, str) else ("speed (m/s)" if isinstance(color_by, str) else "value")
        stamp = max((len(time_format.format(v)) for v in times), default=0) if time_format is not None else 0
        key = _Legend(name, colormap, vmin, vmax, int(width), int(height), int(label_scale), label_color, bg, stamp)
        if not key.fits:  # a frame too narrow for the name, the values and a bar
            key = None
    if camera is None:
        points = _frame_corners(x, r, scenery.boxes, lo, hi) if dim == 3 else None
        camera = _auto_camera(lo, hi, dim, width, height, avoid=key.box if key is not None else None, points=points)
    elif dim == 2 and not isinstance(camera, Camera2D) or dim == 3 and not isinstance(camera, Camera3D):
        raise ValueError(f"camera = {camera!r} is invalid: dim={dim} needs a Camera{dim}D")
    common = dict(
        width=int(width),
        height=int(height),
        background=bg,
        min_radius_px=float(min_radius_px),
        label_scale=int(label_scale),
        label_color=label_color,
        spring_width=float(spring_width),
        **camera._kwargs(),
    )
    if len(scenery):
        common["scenery"] = scenery
    for k in range(n_frames):
        label = time_format.format(times[k]) if time_format is not None else None
        here = live[k]
        every = bool(here.all())

        def pick(a, here=here, every=every):  # the live particles' rows
            return a if every else np.ascontiguousarray(a[here])

        if colors is not None:
            colour_kw = {"colors": pick(colors[k] if colors.ndim == 3 else colors)}
        else:
            colour_kw = {"values": pick(values[k] if values.ndim == 2 else values), "colormap": colormap, "vmin": vmin, "vmax": vmax}
        if pairs.size and not every:
            both = here[pairs[:, 0]] & here[pairs[:, 1]]
            column = np.cumsum(here) - 1  # a live particle's index among the live ones
            frame_pairs = np.ascontiguousarray(column[pairs[both]])
        else:
            frame_pairs = pairs
        frame = _core.render_frame(pick(x[k]), pick(r), label=label, springs=frame_pairs, **colour_kw, **common)
        if key is not None:
            key.draw(frame)
        yield frame


def _trajectory_options(traj) -> dict:
    """``render_frames``' radius, alive and springs for a ``Trajectory``: its radii (or, where
    it has none, 1/200 of the size of what its live particles span), its alive mask, and its
    springs (particle ids) as pairs of columns, those whose ids it does not hold left out."""
    x = np.asarray(traj.positions, dtype=np.float64)
    radius = traj.radii
    if radius is None or not np.any(np.asarray(radius) > 0):
        finite = x[np.all(np.isfinite(x), axis=2)]
        extent = float(np.ptp(finite, axis=0).max()) if finite.size else 0.0
        radius = np.full(x.shape[1], (extent or 1.0) / 200.0)
    options = {"radius": radius, "alive": getattr(traj, "alive", None)}
    springs = getattr(traj, "springs", None)
    if springs is not None and np.size(springs):
        ids = np.arange(x.shape[1]) if traj.ids is None else np.asarray(traj.ids).reshape(-1)
        order = np.argsort(ids, kind="stable")
        pairs = np.asarray(springs, dtype=np.int64).reshape(-1, 2)
        at = np.clip(np.searchsorted(ids[order], pairs), 0, ids.size - 1) if ids.size else np.zeros_like(pairs)
        known = (ids[order][at] == pairs).all(axis=1) if ids.size else np.zeros(len(pairs), bool)
        options["springs"] = order[at[known]]
    return options


#: The colour of a particle without its own (``color_by="color"``), RGB8.
NO_OWN_COLOR = (70, 130, 200)


def own_colours(traj) -> np.ndarray:
    """Each particle's own colour (``Trajectory.colors``: an ``Emitter``'s ``color``) as uint8
    RGB (N, 3) for ``render_frames(color_by=...)``; ``NO_OWN_COLOR`` where it has none."""
    n = np.shape(traj.positions)[1]
    colors = getattr(traj, "colors", None)
    out = np.tile(np.array(NO_OWN_COLOR, dtype=np.uint8), (n, 1))
    if colors is not None:
        c = np.asarray(colors, dtype=np.float64)
        given = np.all(np.isfinite(c), axis=1)
        out[given] = np.round(np.clip(c[given], 0, 1) * 255).astype(np.uint8)
    return out


def _live(alive, x) -> np.ndarray:
    """(F, N) bools: alive (all when None) and with a finite position."""
    n_frames, n = x.shape[:2]
    finite = np.all(np.isfinite(x), axis=2)
    if alive is None:
        return finite
    a = np.asarray(alive)
    if a.dtype != np.bool_ or a.shape not in ((n,), (n_frames, n)):
        raise ValueError(f"alive has shape {a.shape} and type {a.dtype}: expected bools of shape ({n_frames}, {n}) or ({n},)")
    return np.broadcast_to(a, (n_frames, n)) & finite


def _springs(springs, n: int) -> np.ndarray:
    """(S, 2) int64 particle indices, checked."""
    if springs is None:
        return np.zeros((0, 2), np.int64)
    s = np.asarray(springs)
    if s.size == 0:
        return np.zeros((0, 2), np.int64)
    if s.ndim != 2 or s.shape[1] != 2 or not np.issubdtype(s.dtype, np.integer):
        raise ValueError(f"springs has shape {s.shape} and type {s.dtype}: expected integer particle indices of shape (S, 2)")
    bad = np.nonzero((s < 0).any(axis=1) | (s >= n).any(axis=1))[0]
    if bad.size:
        raise ValueError(f"springs[{bad[0]}] = {s[bad[0]].tolist()} is invalid: particle indices in [0, {n})")
    return np.ascontiguousarray(s, dtype=np.int64)


class _Legend:
    """A colour bar, drawn into frames: in the top right corner, on the time stamp's row (or
    under it where the row is too short for both), the quantity's name, ``vmin``, a horizontal
    bar of the colormap (its bottom colour on the left, its top colour on the right) and
    ``vmax``, on a panel of the background colour (3/4 opaque). Pillow draws it once, its text
    in DejaVu Sans (matplotlib's) as tall as the time stamp; each frame gets it by blending,
    ``box`` (x0, y0, x1, y1) pixels being where it goes."""

    def __init__(self, name, colormap, vmin, vmax, width, height, scale, ink, background, stamp_chars=0):
        from PIL import Image, ImageDraw

        scale = max(scale, 1)
        size = max(9, 7 * scale)  # the time stamp's glyphs are 7 font pixels of `scale` tall
        font = _legend_font(size)
        margin, pad, gap = 4 * scale, max(2, size // 5), max(3, size // 3)
        low, high = f"{vmin:.3g}", f"{vmax:.3g}"
        probe = ImageDraw.Draw(Image.new("L", (1, 1)))
        name_w, low_w, high_w = (round(probe.textlength(text, font=font)) for text in (name, low, high))
        bar_w, bar_h = int(min(max(0.2 * width, 40), 240)), max(6, round(0.75 * size))
        pw = pad + name_w + 2 * gap + low_w + gap + bar_w + gap + high_w + pad
        ph = size + size // 3 + 2 * pad
        x0 = width - margin - pw
        # On the stamp's row, centred on it, unless the two would meet; then under it.
        y0 = max(0, round(margin + 3.5 * scale - 0.5 * ph))
        if stamp_chars and x0 < margin + 6 * scale * stamp_chars + 2 * margin:
            y0 = margin + 7 * scale + margin
        self.box = (x0, y0, x0 + pw, y0 + ph)
        # out = frame·(1 − A) + C over the panel: A the opacity, C the colour times it.
        opacity = np.full((ph, pw, 1), 0.75, np.float32)
        colour = opacity * np.asarray(background, np.float32)
        mask = Image.new("L", (pw, ph), 0)
        draw = ImageDraw.Draw(mask)
        cy = ph // 2
        draw.text((pad, cy), name, fill=255, font=font, anchor="lm")
        bx0 = pad + name_w + 2 * gap + low_w + gap
        draw.text((bx0 - gap, cy), low, fill=255, font=font, anchor="rm")
        draw.text((bx0 + bar_w + gap, cy), high, fill=255, font=font, anchor="lm")
        m = np.asarray(mask, np.float32)[:, :, None] / 255.0
        colour = colour * (1.0 - m) + m * np.asarray(ink, np.float32)
        opacity = opacity * (1.0 - m) + m
        # The bar, opaque: left column the colormap's bottom colour, right column its top colour.
        by0 = cy - bar_h // 2
        ramp = _core.colormap(np.linspace(0.0, 1.0, bar_w), colormap, 0.0, 1.0).astype(np.float32)
        colour[by0 : by0 + bar_h, bx0 : bx0 + bar_w] = ramp[None, :, :]
        opacity[by0 : by0 + bar_h, bx0 : bx0 + bar_w] = 1.0
        edge = np.asarray([128, 128, 128], np.float32)
        for rows, cols in (
            (slice(by0 - 1, by0), slice(bx0 - 1, bx0 + bar_w + 1)),
            (slice(by0 + bar_h, by0 + bar_h + 1), slice(bx0 - 1, bx0 + bar_w + 1)),
            (slice(by0, by0 + bar_h), slice(bx0 - 1, bx0)),
            (slice(by0, by0 + bar_h), slice(bx0 + bar_w, bx0 + bar_w + 1)),
        ):
            colour[rows, cols], opacity[rows, cols] = edge, 1.0
        self._opacity, self._colour = opacity, colour
        self.fits = x0 >= 0 and y0 + ph <= height

    def draw(self, frame: np.ndarray) -> None:
        x0, y0, x1, y1 = self.box
        region = frame[y0:y1, x0:x1]
        region[:] = np.clip(region * (1.0 - self._opacity) + self._colour + 0.5, 0, 255).astype(np.uint8)


def _legend_font(size: int):
    from PIL import ImageFont

    try:
        import matplotlib

        return ImageFont.truetype(str(Path(matplotlib.get_data_path()) / "fonts" / "ttf" / "DejaVuSans.ttf"), size)
    except (ImportError, OSError):
        try:
            return ImageFont.load_default(size=size)
        except TypeError:  # Pillow < 10.1: the fixed bitmap font
            return ImageFont.load_default()


def _colouring(color_by, x, times, velocities, dim, vmin, vmax):
    """(colors, values, vmin, vmax): fixed uint8 colours, or values for the colormap."""
    n_frames, n = x.shape[:2]
    if isinstance(color_by, str):
        if color_by == "id":
            return _core.categorical_colors(np.arange(n, dtype=np.uint64)), None, vmin, vmax
        if color_by != "speed":
            raise ValueError(f"color_by = {color_by!r} is invalid: use 'speed', 'id' or an array of values or colours")
        if velocities is not None:
            v = np.asarray(velocities, dtype=np.float64)
            if v.shape[:2] != (n_frames, n) or v.ndim != 3:
                raise ValueError(f"velocities has shape {v.shape}: expected ({n_frames}, {n}, {dim})")
            speed = np.linalg.norm(v[:, :, :dim], axis=2)
        elif n_frames >= 2:
            speed = np.linalg.norm(np.gradient(x[:, :, :dim], times, axis=0), axis=2)
        else:
            speed = np.zeros((n_frames, n))
        values = speed
    else:
        field = np.asarray(color_by)
        if field.dtype == np.uint8 and field.shape[-1:] == (3,) and field.shape in ((n, 3), (n_frames, n, 3)):
            return np.ascontiguousarray(field), None, vmin, vmax
        values = np.asarray(field, dtype=np.float64)
        if values.shape not in ((n,), (n_frames, n)):
            raise ValueError(
                f"color_by has shape {field.shape}: expected values (N,) or (F, N), or uint8 colours (N, 3) or (F, N, 3), with F={n_frames}, N={n}"
            )
    finite = values[np.isfinite(values)]
    lo = float(finite.min()) if vmin is None and finite.size else (0.0 if vmin is None else float(vmin))
    hi = float(finite.max()) if vmax is None and finite.size else (1.0 if vmax is None else float(vmax))
    return None, np.ascontiguousarray(values), lo, hi


_KIND = {"plane": ("point", "normal"), "box": ("lo", "hi"), "sphere": ("center", "radius")}


def _describe_colliders(colliders) -> list[dict]:
    """Plain descriptions of colliders (``kinema.Plane``, ``Box``, ``SphereObstacle`` or such
    descriptions already): {"type": "plane", "point": [3], "normal": [3]}, {"type": "box",
    "lo": [2 or 3], "hi": [2 or 3]} (bounds may be ±inf), {"type": "sphere", "center": [3],
    "radius": r}, with "restitution" and "friction" where the collider sets them."""
    from .colliders import Box, Plane, SphereObstacle

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
        elif isinstance(c, dict) and c.get("type") in _KIND:
            d = dict(c)
        else:
            raise ValueError(
                f"colliders[{k}] = {c!r} is invalid: use kinema.Plane, Box or SphereObstacle, or a description "
                "{'type': 'plane' | 'box' | 'sphere', ...} (Trajectory.colliders)"
            )
        try:
            if d["type"] == "box":
                d["lo"], d["hi"] = floats(f"colliders[{k}].lo", d["lo"], (2, 3)), floats(f"colliders[{k}].hi", d["hi"], (2, 3))
            elif d["type"] == "sphere":
                d["center"], d["radius"] = floats(f"colliders[{k}].center", d["center"]), float(d["radius"])
            else:
                d["point"], d["normal"] = floats(f"colliders[{k}].point", d["point"]), floats(f"colliders[{k}].normal", d["normal"])
        except KeyError as e:
            raise ValueError(f"colliders[{k}] = {c!r} is invalid: a {d['type']} needs {' and '.join(_KIND[d['type']])}, it has no {e}") from None
        for name in ("restitution", "friction"):
            value = getattr(c, name, None) if not isinstance(c, dict) else c.get(name)
            if value is not None:
                d[name] = float(value)
            else:
                d.pop(name, None)
        out.append(d)
    return out


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


def write_video(
    frames: Iterable[np.ndarray],
    path,
    fps: float = 30.0,
    *,
    times=None,
    preset: str = "ultrafast",
    crf: int = 20,
) -> Path:
    """Write RGB uint8 frames of one size to ``path`` and return it as a Path.

    The frame rate written is ``video_rate(fps, path)``, exactly:

    - ``.mp4``: ``fps`` as a fraction with a denominator of at most 1001 (30 → 30/1,
      29.97 → 2997/100, 30000/1001 stays; ``fps`` may be a ``fractions.Fraction``), so a
      30 fps video says 30 fps, not 30.00003.
    - ``.gif``: a GIF counts each frame's delay in whole 1/100 s, and browsers play a delay of
      0 or 1/100 s as 1/10 s: the delay is the whole number of 1/100 s from 2 to 65535 whose
      rate is closest to ``fps`` (ratio nearest 1), so 60 fps is written at 50 (2/100 s),
      30 fps at 33.3 (3/100 s), 25 at 25, 12 at 12.5 (8/100 s).

    ``times`` (seconds, increasing, one per frame; optional): the frames were recorded at these
    times and are to play in real time. The video is written at the rate above and each of its
    frames shows the recorded frame nearest in time to it (from ``times[0]``, every 1/rate s up
    to the last time): frames are repeated or dropped where the recording interval differs from
    1/rate, and none are when it equals it (``World.run(fps=30)`` with dt = 1 ms records every
    33 ms, 30.30 a second: at 30 fps one frame in about a hundred is dropped). Without
    ``times``, each frame is one video frame at that rate (its playback speed is up to you).

    ``.mp4``: H.264 (libx264, yuv420p, 4:2:0) by the ffmpeg that imageio-ffmpeg ships. The RGB
    is converted with the BT.709 matrix into limited ("tv") range by ffmpeg's scaler and the
    stream and the MP4 say so (``colr`` box and H.264 VUI: primaries, transfer and matrix
    BT.709, limited range), so players convert it back with the same matrix; the ``moov`` box
    comes before the media data (``-movflags +faststart``), so a browser plays the file while
    it downloads. Odd sizes are padded by one edge row/column. x264 ``preset`` (ultrafast …
    veryslow; the default ultrafast keeps 10,000 particles at 1280×720 above 60 frames per
    second on two cores, ``benchmarks/render.py``; slower presets give smaller files) and
    constant-quality ``crf`` (0 lossless … 51 worst).
    ``.gif``: Pillow, looping, at most 256 colours a frame.

    The file is written under a temporary name in the same directory and renamed when
    complete: on any error nothing is left behind and an existing file is untouched.
    """
    path = Path(path)
    ext = path.suffix.lower()
    if ext not in VIDEO_EXTENSIONS:
        raise ValueError(f"path = {str(path)!r} is invalid: the extension must be one of {', '.join(VIDEO_EXTENSIONS)}")
    rate = video_rate(fps, ext)
    counts = None if times is None else _repeats(times, rate)
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise FileNotFoundError(f"path = {str(path)!r} is invalid: the directory {str(parent)!r} does not exist")
    fd, tmp_name = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=f".part{ext}", dir=parent)
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        stream = _checked(frames)
        if counts is not None:
            stream = _resampled(stream, counts)
        count = (_write_mp4 if ext == ".mp4" else _write_gif)(stream, tmp, rate, preset, crf)
        if count == 0:
            raise ValueError("frames is empty: a video needs at least one frame")
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return path


#: GIF frame delays, in 1/100 s: browsers play 0 and 1 as 10, and the field has 16 bits.
GIF_DELAYS_CS = (2, 65535)


def video_rate(fps, path=".mp4") -> Fraction:
    """The exact frame rate ``write_video`` writes for ``fps`` into ``path`` (a file name or
    just its extension, ".mp4" or ".gif"), in frames per second: for MP4 ``fps`` as a fraction
    with a denominator up to 1001 (``video_rate(30) == 30``; below 1/1001, 1/n for n whole
    seconds a frame); for GIF 100/d, d the delay in 1/100 s from 2 to 65535 whose rate is
    nearest ``fps`` (``video_rate(60, ".gif") == 50``)."""
    if isinstance(fps, bool) or not isinstance(fps, numbers.Real) or not (math.isfinite(fps) and fps > 0):
        raise ValueError(f"fps = {fps!r} is invalid: frames per second must be a finite number > 0")
    ext = str(path).lower()
    ext = ext if ext in VIDEO_EXTENSIONS else Path(ext).suffix
    if ext not in VIDEO_EXTENSIONS:
        raise ValueError(f"path = {str(path)!r} is invalid: the extension must be one of {', '.join(VIDEO_EXTENSIONS)}")
    exact = Fraction(fps) if isinstance(fps, numbers.Rational) else Fraction(float(fps))
    if ext == ".gif":
        lo, hi = GIF_DELAYS_CS
        ideal = 100 / exact
        candidates = {min(max(d, lo), hi) for d in (math.floor(ideal), math.ceil(ideal))}
        delay = min(candidates, key=lambda d: (abs(math.log(d / ideal)), d))
        return Fraction(100, delay)
    if exact < Fraction(1, 1001):  # slower than a frame in 1001 s: a whole number of seconds a frame
        return Fraction(1, round(1 / exact))
    return exact.limit_denominator(1001)


def _repeats(times, rate: Fraction) -> np.ndarray:
    """How many video frames at ``rate`` each frame recorded at ``times`` fills, for playback
    in real time: video frame k (at times[0] + k/rate, k = 0 … round(span·rate)) shows the
    recorded frame nearest in time (the earlier one on a tie); 0 drops the frame."""
    t = np.asarray(times, dtype=np.float64)
    if t.ndim != 1 or t.size == 0 or not np.all(np.isfinite(t)):
        raise ValueError(f"times has shape {t.shape}: expected one finite time (s) per frame")
    if np.any(np.diff(t) <= 0):
        k = int(np.argmax(np.diff(t) <= 0)) + 1
        raise ValueError(f"times[{k}] = {t[k]!r} is invalid: times must increase (times[{k - 1}] = {t[k - 1]!r})")
    r = float(rate)
    n_out = int(round((t[-1] - t[0]) * r)) + 1
    # Video frames up to the midpoint between recorded frames i and i + 1 show frame i or one
    # before it; a relative 1e-9 settles ties that rounding would otherwise decide.
    mid = 0.5 * (t[:-1] + t[1:]) - t[0]
    upto = np.minimum(np.floor(mid * r * (1 + 1e-9)).astype(np.int64) + 1, n_out)
    return np.diff(np.concatenate([[0], upto, [n_out]]))


def _resampled(frames: Iterator[np.ndarray], counts: np.ndarray) -> Iterator[np.ndarray]:
    """Each frame repeated counts[k] times (0: left out)."""
    k = -1
    for k, f in enumerate(frames):
        if k >= counts.size:
            raise ValueError(f"frames has more frames than times ({counts.size}): give one time per frame")
        for _ in range(int(counts[k])):
            yield f
    if k + 1 != counts.size:
        raise ValueError(f"frames has {k + 1} frames and times {counts.size}: give one time per frame")


def _checked(frames: Iterable[np.ndarray]) -> Iterator[np.ndarray]:
    """The frames as C-contiguous (H, W, 3) uint8, all of the first one's size."""
    shape = None
    for k, f in enumerate(frames):
        f = np.asarray(f)
        if f.dtype != np.uint8 or f.ndim != 3 or f.shape[2] != 3:
            raise ValueError(f"frames[{k}] has dtype {f.dtype} and shape {f.shape}: expected uint8 (H, W, 3)")
        if shape is None:
            shape = f.shape
        elif f.shape != shape:
            raise ValueError(f"frames[{k}] has shape {f.shape}: all frames must have the first one's shape {shape}")
        yield np.ascontiguousarray(f)


#: What the MP4 says about its colours, and the conversion that makes it true: ffmpeg's
#: scaler converts the RGB frames with the BT.709 matrix into limited range (the tags alone
#: would not change the matrix), then x264 and the MP4 muxer record the same description.
_MP4_COLOUR = [
    "-vf",
    "scale=out_color_matrix=bt709:out_range=tv:flags=bicubic+accurate_rnd,format=yuv420p,"
    "setparams=colorspace=bt709:color_primaries=bt709:color_trc=bt709:range=tv",
    "-colorspace",
    "bt709",
    "-color_primaries",
    "bt709",
    "-color_trc",
    "bt709",
    "-color_range",
    "tv",
]


def _write_mp4(frames: Iterator[np.ndarray], tmp: Path, rate: Fraction, preset: str, crf: int) -> int:
    import imageio_ffmpeg

    writer = None
    count = 0
    try:
        for f in frames:
            h, w = f.shape[:2]
            if h % 2 or w % 2:
                # yuv420p stores colour at half resolution: both sides must be even.
                f = np.pad(f, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge")
            if writer is None:
                writer = imageio_ffmpeg.write_frames(
                    str(tmp),
                    (f.shape[1], f.shape[0]),
                    pix_fmt_in="rgb24",
                    fps=rate,
                    codec="libx264",
                    quality=None,
                    macro_block_size=1,
                    output_params=["-preset", str(preset), "-crf", str(int(crf)), *_MP4_COLOUR, "-movflags", "+faststart"],
                    ffmpeg_log_level="error",
                )
                writer.send(None)
            writer.send(f)
            count += 1
    finally:
        if writer is not None:
            writer.close()
    return count


def _write_gif(frames: Iterator[np.ndarray], tmp: Path, rate: Fraction, preset: str, crf: int) -> int:
    from PIL import Image

    count = 0

    def images():
        nonlocal count
        for f in frames:
            count += 1
            yield Image.fromarray(f)

    it = images()
    first = next(it, None)
    if first is None:
        return 0
    # rate is 100/d (video_rate): d/100 s a frame, given to Pillow in ms.
    delay_ms = round(1000 / rate)
    first.save(tmp, format="GIF", save_all=True, append_images=it, duration=delay_ms, loop=0)
    return count
