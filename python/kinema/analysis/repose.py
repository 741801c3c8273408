"""The angle of repose of a heap, from its particles' positions: the free surface traced by
the highest particle in each bin of horizontal distance, and a straight line fitted to its
flanks."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import _checks


@dataclass(frozen=True)
class Repose:
    """What :func:`angle_of_repose` measured.

    `angle` degrees: the heap's angle of repose (the mean of the two flanks' in
    ``"flanks"`` mode). `flanks` degrees: (left, right) in ``"flanks"`` mode, (angle,) in
    ``"radial"`` mode. `distance` (B,) m and `surface` (B,) m: the free surface traced, the
    height of the highest particle's top above the base against the horizontal distance
    from the axis (signed in ``"flanks"`` mode, NaN where a bin is empty); `fitted` (B,)
    bool: the points each line was fitted to. `height` m: the heap's height above its base.
    `residual` m: the root-mean-square distance of the fitted points from their lines."""

    angle: float
    flanks: tuple[float, ...]
    distance: np.ndarray
    surface: np.ndarray
    fitted: np.ndarray
    height: float
    residual: float


def angle_of_repose(
    positions: Any,
    radii: Any = 0.0,
    *,
    up: Any = (0.0, 0.0, 1.0),
    mode: str = "radial",
    along: Any = None,
    center: Any = None,
    bin_width: float | None = None,
    fit: tuple[float, float] = (0.2, 0.8),
) -> Repose:
    """The angle of repose of a heap of particles at ``positions`` (N, 3) m with ``radii``
    (one or (N,), m) resting on a base normal to ``up`` (the direction against gravity).

    Each particle's top is at height h = (x − c)·up + r, c a point of the heap's axis
    (``center``, m; default: in ``"radial"`` mode the particles' mean position, on the axis
    of a conical heap, and in ``"flanks"`` mode the highest particle's, the apex). The free surface is the
    highest top in each bin (``bin_width`` m, default the mean diameter) of horizontal
    distance ρ from the axis:

    - ``mode="radial"``: a conical heap (3D); ρ = |x − c − ((x − c)·up) up|.
    - ``mode="flanks"``: a two-dimensional heap (a 2D world, or a slot) along the horizontal
      direction ``along`` (default the first axis normal to up); ρ = (x − c)·along, signed,
      and the left (ρ < 0) and right flanks are fitted apart.

    A line h = h_0 − tan(θ) |ρ| is fitted (least squares) to the surface points whose height
    above the base lies between ``fit[0]`` and ``fit[1]`` of the heap's height H (the
    rounded top and the foot are left out), on each side of the highest bin (the bins nearer
    the axis than it, sparse on a cone, belong to the top); θ is the angle of repose. The base is the
    lowest particle's bottom, H the highest top above it. The highest particle sits at the
    nearest edge of its bin, which shifts the surface by at most one bin but not its slope."""
    x = _checks.real_array("positions", positions)
    _checks.check_shape("positions", x, (None, 3))
    r = _checks.broadcast("radii", _checks.real_array("radii", radii), (len(x),), f"one radius or one per particle, ({len(x)},)")
    if len(x) < 3 or not np.isfinite(x).all():
        raise ValueError(f"positions has {len(x)} rows{' with NaN or inf' if len(x) >= 3 else ''}: a heap needs at least 3 particles, all at finite places")
    u = _unit("up", up)
    if mode not in ("radial", "flanks"):
        raise ValueError(
            f"mode = {_checks.describe(mode)} is invalid: it must be 'radial' (a conical heap) or 'flanks' (a two-dimensional heap, left and right)"
        )
    lo_f, hi_f = (_checks.real("fit[0]", fit[0]), _checks.real("fit[1]", fit[1])) if len(fit) == 2 else (None, None)
    if lo_f is None or not 0.0 <= lo_f < hi_f <= 1.0:
        raise ValueError(f"fit = {_checks.describe(fit)} is invalid: give (low, high), 0 <= low < high <= 1, the part of the heap's height to fit")
    if center is not None:
        c = _checks.real_array("center", center, (3,))
    else:
        c = x.mean(axis=0) if mode == "radial" else x[int(np.argmax(x @ u + r))]
    rel = x - c
    h = rel @ u + r
    base = float((rel @ u - r).min())
    h -= base
    H = float(h.max())
    flat = rel - np.outer(rel @ u, u)
    if mode == "radial":
        rho = np.linalg.norm(flat, axis=1)
    else:
        a = _unit("along", along) if along is not None else _first_normal(u)
        a = a - (a @ u) * u
        if np.linalg.norm(a) < 1e-9:
            raise ValueError(f"along = {_checks.describe(along)} is invalid: it must be horizontal (not parallel to up = {_checks.describe(up)})")
        rho = flat @ (a / np.linalg.norm(a))
    width = 2.0 * float(r.mean()) if bin_width is None else _checks.real("bin_width", bin_width)
    if not (np.isfinite(width) and width > 0):
        raise ValueError(f"bin_width = {width!r} is invalid: it must be a length > 0 (m); with radii 0 give it")
    k = np.floor(rho / width).astype(np.int64)
    k0 = int(k.min())
    top = np.full(int(k.max()) - k0 + 1, -np.inf)
    np.maximum.at(top, k - k0, h)
    surface = np.where(np.isfinite(top), top, np.nan)
    distance = (np.arange(len(top)) + k0 + 0.5) * width
    band = (surface >= lo_f * H) & (surface <= hi_f * H)
    apex = distance[int(np.nanargmax(surface))]
    sides = [distance <= min(apex, 0.0), distance >= max(apex, 0.0)] if mode == "flanks" else [distance >= apex]
    angles, squares, fitted = [], [], np.zeros(len(top), dtype=bool)
    for side in sides:
        pick = band & side
        if pick.sum() < 2:
            raise ValueError(
                f"fewer than 2 surface bins lie between {lo_f} H and {hi_f} H on a flank ({int(pick.sum())}): the heap is too small for bin_width = {width:g} m, or not a heap; give a smaller bin_width or a wider fit"
            )
        slope, icpt = np.polyfit(np.abs(distance[pick]), surface[pick], 1)
        angles.append(float(np.degrees(np.arctan(-slope))))
        squares.append((surface[pick] - (icpt + slope * np.abs(distance[pick]))) ** 2)
        fitted |= pick
    return Repose(
        angle=float(np.mean(angles)),
        flanks=tuple(angles),
        distance=distance,
        surface=surface,
        fitted=fitted,
        height=H,
        residual=float(np.sqrt(np.concatenate(squares).mean())),
    )


def _unit(name: str, value: Any) -> np.ndarray:
    v = _checks.real_array(name, value, (3,))
    size = float(np.linalg.norm(v))
    if not (np.isfinite(size) and size > 0):
        raise ValueError(f"{name} = {_checks.describe(value)} is invalid: it must be a finite, non-zero direction (3,)")
    return v / size


def _first_normal(u: np.ndarray) -> np.ndarray:
    """The coordinate axis most nearly normal to ``u``."""
    e = np.eye(3)[int(np.argmin(np.abs(u)))]
    return e - (e @ u) * u
