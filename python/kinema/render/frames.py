"""`render_frames`: a trajectory's frames as images, drawn by the engine one call per frame;
the colours (by speed, id, a field or fixed), the live particles, the springs, the scene laid
out once for every frame."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from .. import _core
from ..collider_descriptions import _describe_colliders, collider_poses
from .cameras import Camera2D, Camera3D, _auto_camera, _frame_corners
from .legend import _Legend

#: Names accepted by ``colormap=``.
COLORMAPS: tuple[str, ...] = tuple(_core.COLORMAP_NAMES)

#: The least luma (Rec. 601, 0–255) of the colour a colormap gives the lowest value
#: (``low_end``): viridis's and magma's bottom colours (luma 30 and 1) are near black, and a
#: resting pile, shaded, reads as a black block; from here up, a slow sphere's lit and shaded
#: sides differ enough to show its shape.
LOW_END_LUMA = 80.0

#: Scenes of at most this many particles get trails by default (``render_frames(trail=)``).
TRAIL_PARTICLES = 10


def low_end(colormap: str) -> float:
    """Where on `colormap` (0 … 1) `render_frames` puts the lowest value: the first of
    t = k/64 whose colour has a luma of at least `LOW_END_LUMA` (viridis 0.25, magma
    0.41, gray 0.31). The values from `vmin` to `vmax` use the map from there to 1, and
    the colour bar shows that part."""
    t = np.arange(65) / 64.0
    rgb = _core.colormap(t, colormap, 0.0, 1.0).astype(np.float64)
    luma = rgb @ np.array([0.299, 0.587, 0.114])
    return float(t[np.argmax(luma >= LOW_END_LUMA)]) if np.any(luma >= LOW_END_LUMA) else 0.0


# Over 100 lines (issue 50) by its documentation alone: 24 parameters, in the signature
# (27 lines) and each described in the docstring (54); the code (78 lines) checks the input and
# lays the scene out once, and `_drawn` draws each frame.
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
    trail: float | None = None,
    trail_width: float | None = None,
    attractors=None,
) -> Iterator[np.ndarray]:
    """Yield one (height, width, 3) uint8 RGB frame per time.

    positions: (F, N, 3) or, for `dim=2`, (F, N, 2) positions in m (2D uses x and y).
    radius: one radius for all particles or one per particle (N,), m.
    t: (F,) times, s, stamped on each frame with `time_format` (None: no stamp; the stamp
      may use only digits, '.', '-', '+', ':', '=', ' ', 't', 's', 'e'). The stamp goes into
      the corner (top left, bottom left, top right, bottom right, the first of the fewest)
      where the fewest particle pixels lie under it over the video (up to 24 frames evenly
      spaced, drawn without scenery to count them), clear of the colour bar; one corner for
      the whole video.
    color_by: "speed" (|v|, from `velocities` (F, N, dim) or else from finite differences of
      the positions in t), "id" (categorical colours by particle index), a field of floats of
      shape (N,) or (F, N) mapped through `colormap` between `vmin` and `vmax` (default:
      the field's minimum and maximum over all frames, so colours mean the same in every
      frame), or fixed uint8 colours of shape (N, 3) or (F, N, 3). Values use the colormap
      from `low_end(colormap)` up (viridis from 0.25: `vmin` is steel blue, not near
      black), so the slowest particles stay visible and their shading shows.
    camera: a Camera2D / Camera3D; default: one for the whole video, framing where the
      live particles (with their radii) spend the run and where they end (`cameras.
      _particle_region`: outliers and sparse transient tails such as the column a pile
      fell from left out), widened to the walls of a box that bounds them (2D: a box with
      finite walls whole) and the attractors; it fills the frame's width or height,
      whichever binds, to 3 % of its sides, centred (a 3D box seen from the front right and
      above; both fields of view are fitted), and kept clear of the legend.
    background: RGB8 colour.
    colliders: colliders to draw, `kinema.Plane` / `Box` / `SphereObstacle` objects or
      their descriptions (`Trajectory.colliders`: dicts {"type": "plane", "point",
      "normal"}, {"type": "box", "lo", "hi"}, {"type": "sphere", "center", "radius"}); None
      draws none. Infinite box bounds (an open top) are drawn up to the scene's extent. A
      collider with a `motion` is drawn where it is at each frame's time (`collider_poses`,
      the engine's motion), and the scene's extent holds it at every frame.
    alive: (F, N) bools (or (N,), the same in every frame): the particles that exist in each
      frame (`Trajectory.alive`: births and deaths). Those that do not, and any with a
      non-finite position, are not drawn, count for neither the camera nor the colour range,
      and their springs are not drawn. A frame with none alive shows the scenery alone.
    springs: (S, 2) particle indices (columns of `positions`) joined by springs, strings or
      bonds, each drawn as a grey line (`_core.LINE_COLOR`) `spring_width` pixels wide
      (default: 1 per 480 rows, at least 1) from one particle's rim to the other's, in frames
      where both are alive.
    legend: when the particles are coloured by a quantity (speed or a field of values; not
      ids or fixed colours), a colour bar from `vmin` to `vmax` with the quantity's name
      and units ("speed (m/s)"; a string gives them, e.g. "temperature (K)"; a field is
      "value" otherwise) in the top right corner, beside the time stamp, its text as tall
      (`label_scale`). False: none. It is left out of frames under 160 × 120 pixels or too
      narrow for it, which have no room for it.
    trail: seconds of each particle's recent path drawn behind it (its positions in the
      frames of the last `trail` seconds, as a line in its colour fading with age,
      `trail_width` pixels wide, default 1 per 300 rows, at least 1.5). Default: a third of
      the recording's span for at most `TRAIL_PARTICLES` (10) particles (a Kepler orbit of
      three periods shows one), none for more; 0: none.
    attractors: (A, 3) or (A, 2) points, m (the `point` of `kinema.Attractor` forces),
      each drawn as an amber disc with a dark rim (radius 1 per 80 rows, at least 4 pixels);
      the default camera frames them with the particles.
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
    marks = _attractor_points(attractors, dim)
    trail = _trail_seconds(trail, n, times)
    # The colliders become the engine's once; the engine lays the scene out (its extent:
    # all frames' live particles, the attractors and the colliders' finite parts, widened by
    # the largest radius), one extent for every frame, so that floors and open walls stay put.
    everything = np.concatenate([x.reshape(-1, 3), marks]) if len(marks) else x.reshape(-1, 3)
    described = _describe_colliders(colliders) if colliders is not None else []
    poses = _moving_poses(described, times)
    scenery = _core.Scenery(described, everything, r, poses=poses)
    lo, hi = (np.array(corner) for corner in scenery.extent)
    bg = tuple(int(c) for c in background)
    luminance = 0.299 * bg[0] + 0.587 * bg[1] + 0.114 * bg[2]
    label_color = (0, 0, 0) if luminance > 128 else (255, 255, 255)
    key = None
    if legend is not False and legend is not None and colors is None and width >= 160 and height >= 120:
        name = legend if isinstance(legend, str) else ("speed (m/s)" if isinstance(color_by, str) else "value")
        stamp = max((len(time_format.format(v)) for v in times), default=0) if time_format is not None else 0
        key = _Legend(name, colormap, vmin, vmax, int(width), int(height), int(label_scale), label_color, bg, stamp, low_end(colormap))
        if not key.fits:  # a frame too narrow for the name, the values and a bar
            key = None
    if camera is None:
        points = _frame_corners(x, r, described, lo, hi, marks, dim)
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
        trail_width=float(max(1.5, height / 300.0) if trail_width is None else trail_width),
        marker_radius=float(max(4.0, height / 80.0)),
        **camera._kwargs(),
    )
    if len(marks):
        common["markers"] = marks
    if values is not None and vmax > vmin:  # vmin at low_end(colormap) of the map, vmax at its top
        low = low_end(colormap)
        map_min = vmin - low / (1.0 - low) * (vmax - vmin)
    else:
        map_min = vmin
    windows = _trail_windows(times, trail)
    if time_format is not None:
        stamps = [time_format.format(v) for v in times]
        common["label_at"] = _label_corner(x, r, live, windows, stamps, int(label_scale), key.box if key is not None else None, common)
    if len(scenery) and poses is None:
        common["scenery"] = scenery
    colouring = {"colors": colors, "values": values, "colormap": colormap, "vmin": map_min, "vmax": vmax}
    yield from _drawn(x, r, live, times, time_format, colouring, pairs, windows, scenery, poses, key, common)


def _drawn(x, r, live, times, time_format, colouring: dict, pairs, windows, scenery, poses, key, common: dict) -> Iterator[np.ndarray]:
    """Each frame of `render_frames` drawn by the engine, its live particles only (their
    colours or values, the springs between two live ones, their trails), the moving
    colliders where they are at its time, and the colour bar."""
    colors, values = colouring["colors"], colouring["values"]
    for k in range(len(times)):
        label = time_format.format(times[k]) if time_format is not None else None
        here = live[k]
        every = bool(here.all())

        def pick(a, here=here, every=every):  # the live particles' rows
            return a if every else np.ascontiguousarray(a[here])

        if colors is not None:
            colour_kw = {"colors": pick(colors[k] if colors.ndim == 3 else colors)}
        else:
            colour_kw = {
                "values": pick(values[k] if values.ndim == 2 else values),
                "colormap": colouring["colormap"],
                "vmin": colouring["vmin"],
                "vmax": colouring["vmax"],
            }
        if pairs.size and not every:
            both = here[pairs[:, 0]] & here[pairs[:, 1]]
            column = np.cumsum(here) - 1  # a live particle's index among the live ones
            frame_pairs = np.ascontiguousarray(column[pairs[both]])
        else:
            frame_pairs = pairs
        if windows[k] < k:  # (N, L, 3): the trail's points, oldest first, NaN where not alive
            colour_kw["trails"] = pick(np.ascontiguousarray(x[windows[k] : k + 1].transpose(1, 0, 2)))
        if poses is not None:  # moving colliders: this frame's scenery, where they are at times[k]
            colour_kw["scenery"] = scenery.posed(poses[k])
        frame = _core.render_frame(pick(x[k]), pick(r), label=label, springs=frame_pairs, **colour_kw, **common)
        if key is not None:
            key.draw(frame)
        yield frame


def _moving_poses(described: list[dict], times: np.ndarray) -> np.ndarray | None:
    """(F, C, 3, 4): each collider's pose [R | o] at each frame's time (`collider_poses`:
    the identity for a still one), or None when none has a `motion` (a still scene is drawn
    from one scenery for every frame)."""
    if not any(d.get("motion") is not None for d in described):
        return None
    return np.ascontiguousarray(np.stack([collider_poses(d, times) for d in described], axis=1))


def _attractor_points(attractors, dim: int) -> np.ndarray:
    """(A, 3) finite points, m (z = 0 in 2D)."""
    if attractors is None:
        return np.zeros((0, 3))
    a = np.asarray(attractors, dtype=np.float64)
    if a.size == 0:
        return np.zeros((0, 3))
    a = a.reshape(1, -1) if a.ndim == 1 else a
    if a.ndim != 2 or a.shape[1] not in (2, 3) or not np.all(np.isfinite(a)):
        raise ValueError(f"attractors has shape {a.shape}: expected finite points (A, 3) or (A, 2), m")
    if a.shape[1] == 2:
        a = np.concatenate([a, np.zeros((len(a), 1))], axis=1)
    elif dim == 2:
        a = a.copy()
        a[:, 2] = 0.0
    return np.ascontiguousarray(a)


def _trail_seconds(trail, n: int, times: np.ndarray) -> float:
    """The trail's length, s: `trail`, or by default a third of the span for few particles."""
    if trail is None:
        span = float(times[-1] - times[0]) if times.size > 1 else 0.0
        return span / 3.0 if 0 < n <= TRAIL_PARTICLES and np.isfinite(span) else 0.0
    if isinstance(trail, bool) or not (np.isfinite(float(trail)) and float(trail) >= 0):
        raise ValueError(f"trail = {trail!r} is invalid: a number of seconds >= 0 (0: no trails)")
    return float(trail)


def _trail_windows(times: np.ndarray, trail: float) -> np.ndarray:
    """For each frame k, the first frame of its trail (k: none): the earliest j with
    times[j] >= times[k] − trail."""
    if trail <= 0:
        return np.arange(times.size)
    return np.minimum(np.searchsorted(times, times - trail * (1 + 1e-12), side="left"), np.arange(times.size))


#: The stamp's corners in the order of preference: top left, bottom left, top right, bottom right.
_CORNERS = ((0, 0), (0, 1), (1, 0), (1, 1))


def _label_corner(x, r, live, windows, stamps, scale: int, avoid, common: dict) -> tuple[int, int]:
    """(column, row) of the stamp's top left corner: the corner of the frame (`_CORNERS`,
    4 font pixels in) whose box holds the fewest particle, trail and marker pixels over up to
    24 frames evenly spaced, drawn without scenery (black on white); corners that meet the
    colour bar `avoid` (x0, y0, x1, y1) are not taken, unless all do."""
    width, height = common["width"], common["height"]
    margin = 4 * max(scale, 1)
    lw = max((len(s) for s in stamps), default=0) * 6 * scale
    lh = 7 * scale
    boxes = []
    for cx, cy in _CORNERS:
        x0 = margin if cx == 0 else max(0, width - margin - lw)
        y0 = margin if cy == 0 else max(0, height - margin - lh)
        boxes.append((x0, y0))
    n_frames = x.shape[0]
    sample = np.unique(np.linspace(0, n_frames - 1, min(n_frames, 24)).round().astype(int))
    kw = {k: v for k, v in common.items() if k not in ("scenery", "label_at", "background", "label_color")}
    counts = np.zeros(len(boxes))
    for k in sample:
        here = live[k]
        if not here.any():
            continue
        extra = {}
        if windows[k] < k:
            extra["trails"] = np.ascontiguousarray(x[windows[k] : k + 1].transpose(1, 0, 2)[here])
        n = int(here.sum())
        img = _core.render_frame(
            np.ascontiguousarray(x[k][here]), np.ascontiguousarray(r[here]), colors=np.zeros((n, 3), np.uint8), background=(255, 255, 255), **extra, **kw
        )
        used = np.any(img != 255, axis=2)
        for b, (x0, y0) in enumerate(boxes):
            counts[b] += used[max(0, y0 - margin // 2) : y0 + lh + margin // 2, max(0, x0 - margin // 2) : x0 + lw + margin // 2].sum()
    if avoid is not None:
        ax0, ay0, ax1, ay1 = avoid
        for b, (x0, y0) in enumerate(boxes):
            if x0 < ax1 and ax0 < x0 + lw and y0 < ay1 and ay0 < y0 + lh:
                counts[b] = np.inf
    best = int(np.argmin(counts)) if np.isfinite(counts).any() else 0
    return boxes[best]


def _trajectory_options(traj) -> dict:
    """`render_frames`' radius, alive and springs for a `Trajectory`: its radii (or, where
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
    """Each particle's own colour (`Trajectory.colors`: an `Emitter`'s `color`) as uint8
    RGB (N, 3) for `render_frames(color_by=...)`; `NO_OWN_COLOR` where it has none."""
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
