"""The measures of a recorded trajectory as one document: what ``kinema analyze`` prints and
writes with ``--json``, and what a scene's ``[analysis]`` table makes ``kinema run`` write
as ``analysis.json`` (docs/analysis.md, "From a scene file and the command line").

:func:`analyze` reads a trajectory (``Trajectory``, recorded or loaded; its contacts from
``contact_record``, through :meth:`Snapshot.of_frame`) and calls this package's functions
at one frame, or at every frame for a time series; the maths is theirs, nothing here
recomputes it. The document is plain data (dicts, lists, numbers, strings, None) that
:func:`write_json` writes as standard JSON: a number JSON cannot hold (NaN, ±inf) is null.
A measure that cannot be made at a frame (no contacts to average, no heap to fit) is a
``{"undefined": "<why>"}`` entry, not an error, so that a long run still gets its file."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from .coordination import coordination
from .fabric import fabric
from .fields import slab_fields
from .force_distribution import force_distribution
from .repose import angle_of_repose
from .snapshot import Snapshot

#: The measures, in the order they are reported.
MEASURES = ("coordination", "fabric", "forces", "repose", "profile")
#: Those that need each frame's contacts; ``profile`` reads them for its contact stress where
#: recorded (without them it has no contact stress), ``repose`` reads the positions only.
CONTACT_MEASURES = ("coordination", "fabric", "forces")
AXES = ("x", "y", "z")
#: The coordination number reported: Thornton's mechanical one, iterated (a frictional pile
#: holds particles with fewer than d + 1 contacts), the contacts with colliders counted.
COORDINATION = {"colliders": True, "min_contacts": 2}
FORMAT = 1  # the document's layout; a change of its keys' meaning gets a new number


def parse_measures(text: str | list[str] | tuple[str, ...], option: str = "--measure") -> list[str]:
    """The measure names of a comma-separated ``text`` (or a list), checked: known, each
    once, at least one. A ``ValueError`` names ``option``, the value and the measures."""
    names = [m.strip() for m in text.split(",")] if isinstance(text, str) else [str(m) for m in text]
    names = [m for m in names if m]
    if not names:
        raise ValueError(f"{option} {text!r}: give at least one measure, comma separated: {', '.join(MEASURES)}")
    for m in names:
        if m not in MEASURES:
            raise ValueError(f"{option} {text!r}: unknown measure {m!r}; the measures are {', '.join(MEASURES)}")
    if len(set(names)) != len(names):
        raise ValueError(f"{option} {text!r}: a measure is named twice")
    return names


def frame_index(trajectory: Any, frame: str | int, option: str = "--frame") -> int | str:
    """The frame asked: an index (a negative one counts from the end: -1 the last), or
    "all" (also "last" for -1). A ``ValueError`` names ``option`` and the frames there are."""
    n = len(trajectory.t)
    text = str(frame).strip()
    if text in ("all", "last"):
        return "all" if text == "all" else n - 1
    try:
        k = int(text)
    except ValueError:
        raise ValueError(f"{option} {frame!r}: give a frame number (0 to {n - 1}, or -1 for the last), last or all") from None
    if not -n <= k < n:
        raise ValueError(f"{option} {k}: the trajectory has {n} frame{'s' if n != 1 else ''}; give 0 to {n - 1}, or -1 to {-n} counting from the end, or all")
    return k % n


def axis_index(axis: str | None, dim: int, option: str = "--axis") -> int:
    """The axis of height: "x", "y" or "z" (None: y in a 2D world, z in 3D)."""
    if axis is None:
        return dim - 1
    if axis not in AXES[:dim]:
        extra = f" (a {dim}D trajectory's axes are {' and '.join(AXES[:dim])})" if axis in AXES else ""
        raise ValueError(f"{option} {axis!r}: use {', '.join(AXES[:dim])}{extra}")
    return AXES.index(axis)


def needs_contacts(trajectory: Any, measures: list[str], option: str = "--measure", what: str = "the trajectory") -> None:
    """Refuse (``ValueError`` naming ``option``) contact measures of a trajectory that
    recorded no contacts; ``what`` names the trajectory (its file)."""
    wanted = [m for m in measures if m in CONTACT_MEASURES]
    if wanted and getattr(trajectory, "contact_record", None) is None:
        raise ValueError(
            f"{option} {wanted[0]}: {what} records no contacts, and {', '.join(CONTACT_MEASURES)} need them: "
            "write it with kinema run --record-contacts (or [output] contacts = true, or an [analysis] table); repose and profile work without"
        )


def analyze(
    trajectory: Any,
    *,
    measures: Any = MEASURES,
    frame: str | int = -1,
    axis: str | None = None,
    bins: int = 20,
    cross_section: float | None = None,
    source: str | None = None,
) -> dict[str, Any]:
    """The ``measures`` of ``trajectory`` at ``frame`` (an index, -1 the last, or "all":
    the last frame's measures and, over every frame, the time series of :func:`series`),
    as one plain document.

    ``axis`` ("x", "y", "z"; default the last of the world's) is the height: the angle of
    repose's up and the profile's slabs. ``bins``: the profile's slabs, from the lowest
    particle's bottom to the highest top, and the force distribution's bins. ``cross_section``
    (m², a length in 2D): the slabs' area and the base pressure's; default the periodic
    cell's across the axis, else a box collider's, else the particles' extent at the frame.
    ``source``: the file's name, written into the document."""
    measures = parse_measures(measures if isinstance(measures, str) else list(measures), "measures")
    k = frame_index(trajectory, frame, "frame")
    every = k == "all"
    k = len(trajectory.t) - 1 if every else int(k)
    ax = axis_index(axis, int(trajectory.dim or 3), "axis")
    if isinstance(bins, bool) or not isinstance(bins, (int, np.integer)) or bins < 1:
        raise ValueError(f"bins = {bins!r}: give a whole number of slabs and histogram bins >= 1")
    needs_contacts(trajectory, measures, "measures")
    snap = Snapshot.of_frame(trajectory, k)
    area, area_from = _cross_section(trajectory, snap, ax, cross_section)
    doc: dict[str, Any] = {
        "kinema_analysis": FORMAT,
        "source": source,
        "frame": k,
        "time": snap.time,
        "particles": len(snap),
        "dim": snap.dim,
        "axis": AXES[ax],
        "bins": int(bins),
        "cross_section": area,
        "cross_section_from": area_from,
        "measures": {m: _measure(m, snap, ax, int(bins), area, area_from) for m in measures},
    }
    if every:
        doc["series"] = series(trajectory, measures, ax, area)
    return _plain(doc)


def _measure(name: str, snap: Snapshot, ax: int, bins: int, area: float, area_from: str) -> dict[str, Any]:
    try:
        return MEASURE_FUNCTIONS[name](snap, ax, bins, area)
    except ValueError as e:  # (no contact to average, no heap to fit: said, not raised)
        return {"undefined": str(e).strip().splitlines()[0]}


def _coordination(snap: Snapshot, ax: int, bins: int, area: float) -> dict[str, Any]:
    z = coordination(snap.contacts, len(snap), dim=snap.dim, **COORDINATION)
    return {
        "mean": z.mean,
        "mean_all": z.mean_all,
        "rattler_fraction": z.rattler_fraction,
        "rattlers": int(z.rattler.sum()),
        "rounds": z.rounds,
        **COORDINATION,
    }


def _fabric(snap: Snapshot, ax: int, bins: int, area: float) -> dict[str, Any]:
    f = fabric(snap.contacts, dim=snap.dim)
    return {"tensor": f.tensor, "eigenvalues": f.eigenvalues, "anisotropy": f.anisotropy, "contacts": f.count, "colliders": False}


def _forces(snap: Snapshot, ax: int, bins: int, area: float) -> dict[str, Any]:
    p = force_distribution(snap.contacts, bins=bins)
    return {
        "part": "normal",
        "mean": p.mean,
        "max": float(p.forces.max()),
        "contacts": len(p.forces),
        "edges": p.edges,
        "centers": p.centers,
        "density": p.density,
        "counts": p.counts,
        "colliders": False,
    }


def _repose(snap: Snapshot, ax: int, bins: int, area: float) -> dict[str, Any]:
    mode = "radial" if snap.dim == 3 else "flanks"
    r = angle_of_repose(snap.positions, snap.radii, up=np.eye(3)[ax], mode=mode)
    return {"angle": r.angle, "flanks": list(r.flanks), "height": r.height, "residual": r.residual, "fitted_bins": int(r.fitted.sum()), "mode": mode}


def _profile(snap: Snapshot, ax: int, bins: int, area: float) -> dict[str, Any]:
    if len(snap) == 0:
        raise ValueError("no particle is alive at the frame: there is no profile to measure")
    height = snap.positions[:, ax]
    edges = np.linspace(float((height - snap.radii).min()), float((height + snap.radii).max()), bins + 1)
    slabs = {"edges": edges, "cross_section": area, "axis": ax, "period": snap.period}
    f = slab_fields(snap.positions, snap.masses, velocities=snap.velocities, contacts=snap.contacts, **slabs)
    volumes = math.pi * snap.radii**2 if snap.dim == 2 else 4.0 / 3.0 * math.pi * snap.radii**3
    solid = slab_fields(snap.positions, volumes, **slabs).density  # the volume (area in 2D) the grains fill per unit
    return {
        "kernel": "binning",
        "edges": edges,
        "center": f.where,
        "density": f.density,
        "solid_fraction": solid,
        "velocity": f.velocity,
        "kinetic_stress": f.kinetic_stress,
        "contact_stress": f.contact_stress,
    }


MEASURE_FUNCTIONS = {"coordination": _coordination, "fabric": _fabric, "forces": _forces, "repose": _repose, "profile": _profile}


def series(trajectory: Any, measures: list[str], ax: int, area: float) -> dict[str, Any]:
    """Over every frame: `time` s, `particles` alive, `contacts` recorded (where recorded),
    and per measure asked the coordination number Z (`coordination`, as at one frame) and
    2C/N (`coordination_all`), the fabric's `anisotropy`, the `mean_force` (N) and the
    `angle` of repose; None where undefined at a frame. `base_pressure` (Pa; N/m in 2D): the
    normal force on the floor over each interval up to the frame (``collider_forces()``),
    over ``area``, None at frame 0; the floor is the lowest plane collider facing up along
    the axis (a box's faces are booked together and cannot be told apart)."""
    out: dict[str, Any] = {"time": np.asarray(trajectory.t, dtype=float)}
    frames = [Snapshot.of_frame(trajectory, k) for k in range(len(trajectory.t))]
    out["particles"] = [len(s) for s in frames]
    if getattr(trajectory, "contact_record", None) is not None:
        out["contacts"] = trajectory.contact_record.counts
    if "coordination" in measures:
        z = [_or_none(lambda s: _coordination(s, ax, 1, area), s) for s in frames]
        out["coordination"] = [None if c is None else c["mean"] for c in z]
        out["coordination_all"] = [None if c is None else c["mean_all"] for c in z]
    wanted = {
        "fabric": ("anisotropy", lambda s: fabric(s.contacts, dim=s.dim).anisotropy),
        "forces": ("mean_force", lambda s: force_distribution(s.contacts, bins=1).mean),
        "repose": ("angle", lambda s: _repose(s, ax, 1, area)["angle"]),
    }
    for m in measures:
        if m in wanted:
            key, fn = wanted[m]
            out[key] = [_or_none(fn, s) for s in frames]
    out["base_pressure"] = base_pressure(trajectory, ax, area)
    return out


def base_pressure(trajectory: Any, ax: int, area: float) -> list[float | None] | dict[str, str]:
    """The floor's pressure at each frame (see :func:`series`), or ``{"undefined": why}``."""
    up = np.eye(3)[ax]
    floors = []
    for k, c in enumerate(getattr(trajectory, "colliders", None) or []):
        if c.get("type") == "plane":
            n = np.asarray(c["normal"], dtype=float)
            if n @ up > (1 - 1e-9) * np.linalg.norm(n):
                floors.append((float(np.asarray(c["point"], dtype=float) @ up), k))
    if not floors:
        return {"undefined": f"no plane collider faces up along {AXES[ax]} (a floor): the base pressure is the normal force on one"}
    if getattr(trajectory, "collider_normal", None) is None:
        return {"undefined": "the trajectory has no collider force record (a force model records it with the verlet method)"}
    k = min(floors)[1]
    if len(trajectory.t) < 2:
        return [None]
    force = trajectory.collider_forces().normal[:, k]  # (F - 1, 3) N, on the floor: downwards
    return [None, *(-(force @ up) / area).tolist()]


def _or_none(fn: Any, snap: Snapshot) -> Any:
    try:
        return fn(snap)
    except ValueError:
        return None


def _cross_section(trajectory: Any, snap: Snapshot, ax: int, given: float | None) -> tuple[float, str]:
    """The slabs' cross-section across axis ``ax`` (m², m in 2D) and where it came from."""
    if given is not None:
        if isinstance(given, bool) or not (isinstance(given, (int, float)) and math.isfinite(given) and given > 0):
            raise ValueError(f"cross_section = {given!r}: give the area across the axis, > 0 (m², a length in m in 2D)")
        return float(given), "given"
    across = [a for a in range(snap.dim) if a != ax]
    period = snap.period
    if all(period[a] > 0 for a in across):
        return float(np.prod([period[a] for a in across])), "the periodic cell"
    for c in getattr(trajectory, "colliders", None) or []:
        if c.get("type") == "box":
            lo, hi = np.asarray(c["lo"], dtype=float), np.asarray(c["hi"], dtype=float)
            sides = [hi[a] - lo[a] for a in across if a < len(lo)]
            if len(sides) == len(across) and all(math.isfinite(s) and s > 0 for s in sides):
                return float(np.prod(sides)), "the box collider"
    if len(snap) == 0:
        return 1.0, "none (no particle alive: 1)"
    sides = [float((snap.positions[:, a] + snap.radii).max() - (snap.positions[:, a] - snap.radii).min()) for a in across]
    return float(np.prod(sides)), "the particles' extent"


def _plain(v: Any) -> Any:
    """``v`` as JSON's values: arrays as (nested) lists, numpy numbers as Python's, and a
    number JSON cannot hold (NaN, ±inf) as None."""
    if isinstance(v, dict):
        return {str(k): _plain(x) for k, x in v.items()}
    if isinstance(v, np.ndarray):
        return _plain(v.tolist())
    if isinstance(v, (list, tuple)):
        return [_plain(x) for x in v]
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return float(v) if math.isfinite(v) else None
    return v


def to_json(doc: dict[str, Any]) -> str:
    """Standard JSON text of a document (RFC 8259: no NaN or Infinity, which are null)."""
    return json.dumps(_plain(doc), indent=1, allow_nan=False) + "\n"


def write_json(doc: dict[str, Any], path: str | Path) -> Path:
    """Write the document to ``path`` atomically (a temporary file in its folder, renamed)."""
    from ..io._files import atomic_file

    path = Path(path)
    with atomic_file(path) as tmp:
        tmp.write_text(to_json(doc), encoding="utf-8")
    return path


def summary(doc: dict[str, Any]) -> list[tuple[str, str]]:
    """(measure, its values in words) for each measure of the document, one line each."""
    rows = []
    for name, m in doc["measures"].items():
        if "undefined" in m:
            rows.append((name, f"undefined: {m['undefined']}"))
        elif name == "coordination":
            rows.append((name, f"Z = {_num(m['mean'], '.4f')} (walls counted, rattlers out: {m['rattlers']}), 2C/N = {_num(m['mean_all'], '.4f')}"))
        elif name == "fabric":
            eig = " ".join(_num(e, ".4f") for e in m["eigenvalues"])
            rows.append((name, f"eigenvalues {eig}, anisotropy {_num(m['anisotropy'], '.4f')} ({m['contacts']} contacts)"))
        elif name == "forces":
            rows.append(
                (name, f"<f_n> = {_num(m['mean'], '.4g')} N, max/mean {_num(m['max'] / m['mean'] if m['mean'] else None, '.3f')} ({m['contacts']} contacts)")
            )
        elif name == "repose":
            rows.append((name, f"angle {_num(m['angle'], '.2f')} degrees ({m['mode']}), height {_num(m['height'], '.4g')} m"))
        elif name == "profile":
            stress = m["contact_stress"]
            ax = AXES.index(doc["axis"])
            bottom = "none (no contacts recorded)" if stress is None else f"{_num(stress[0][ax][ax], '.4g')} Pa"
            rows.append((name, f"{len(m['center'])} slabs along {doc['axis']}; contact stress at the bottom {bottom}"))
    if "series" in doc:
        p = doc["series"]["base_pressure"]
        last = p["undefined"] if isinstance(p, dict) else f"{_num(p[-1], '.4g')} Pa at the end"
        rows.append(("series", f"{len(doc['series']['time'])} frames; base pressure: {last}"))
    return rows


def _num(v: float | None, spec: str) -> str:
    return "n/a" if v is None else format(v, spec)
