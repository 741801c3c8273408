"""The checks `save_h5md` (`kinema.io.h5md`) makes before it writes anything: a trajectory
that `load_h5md` would refuse to read back is refused (`_check_writable`: the frames, the box,
the time step, the observables' shapes, the colliders as the engine checks them), and values
the file's unit system would make infinite or equal (`_check_units`); one line naming the file,
the attribute and the value, a `TrajectoryFileError`. The colliders of a trajectory, checked
(`_colliders_of`), which the writer writes too."""

from __future__ import annotations

import math
import numbers
from pathlib import Path
from typing import Any

import numpy as np

from ..contact_record import FIELDS
from ._checks import number
from ._files import TrajectoryFileError
from ._h5md_checks import check_frames, edges_problem, increase_problem
from ._h5md_layout import COLLIDER_OBSERVABLES, OBSERVABLES, PRESSURE_UNIT
from .h5md_units import from_si


def _check_writable(path: Path, tr: Any, fr: Any, system: dict[str, str]) -> None:
    """Refuses, before anything is written, a trajectory that `load_h5md` would refuse to read
    back: the values `check_frames` checks, and the box edges (finite, > 0 m on periodic
    axes), the time step, the observables' shapes and the colliders (as the reader checks them: the engine's rules), and values
    that the unit `system` would make infinite or times it would make equal. One line naming the file,
    the attribute and the value (a `TrajectoryFileError`)."""
    check_frames(path, tr, fr)
    _check_units(path, tr, fr, system)
    periodic, edges = getattr(tr, "periodic", None), getattr(tr, "box_edges", None)
    flags = [] if periodic is None else [bool(p) for p in np.asarray(periodic).reshape(-1)[: fr.dim]]
    rows = None if edges is None else np.asarray(edges, dtype=np.float64).reshape(1, -1)[:, : len(flags)]
    if any(flags) and rows is not None and rows.shape[1] == len(flags):  # (else a ValueError of _write)
        problem = edges_problem(np.where(flags, rows, 0.0), flags, False)
        if problem is not None:
            raise TrajectoryFileError(f"cannot write {path}: trajectory 'box_edges' {problem}")
    if fr.dt is not None and not (np.isfinite(fr.dt) and fr.dt > 0):
        raise TrajectoryFileError(f"cannot write {path}: trajectory 'dt' = {fr.dt!r} is not a positive number (the time step in s)")
    fps = getattr(tr, "fps", None)
    if fps is not None and (isinstance(fps, bool) or not isinstance(fps, numbers.Real) or not (math.isfinite(fps) and fps > 0)):
        raise TrajectoryFileError(f"cannot write {path}: trajectory 'fps' = {fps!r} is not a positive number (the frames per second recorded)")
    for attr in [a for a, _ in OBSERVABLES.values()] + ["total"]:
        a = getattr(tr, attr, None)
        if a is None:
            continue
        s = np.shape(a)
        vector = attr in ("momentum", "angular_momentum", "impulse_balance")
        want = (fr.n_frames, 3) if vector else (fr.n_frames,)
        if s != want and not (vector and s == (fr.n_frames, 2)):
            raise TrajectoryFileError(f"cannot write {path}: trajectory {attr!r} has shape {s}; it must be {want}, one value per frame")
    pressure = getattr(tr, "pressure", None)
    if pressure is not None and np.shape(pressure) != (fr.n_frames, 3, 3):
        raise TrajectoryFileError(
            f"cannot write {path}: trajectory 'pressure' has shape {np.shape(pressure)}; it must be ({fr.n_frames}, 3, 3), a tensor per frame"
        )
    colliders = None  # (K: the same in each)
    for attr, _ in COLLIDER_OBSERVABLES.values():
        a = getattr(tr, attr, None)
        if a is None:
            continue
        s = np.shape(a)
        if len(s) != 3 or s[0] != fr.n_frames or s[2] != 3 or colliders not in (None, s[1]):
            k = "K" if colliders is None else colliders
            raise TrajectoryFileError(
                f"cannot write {path}: trajectory {attr!r} has shape {s}; it must be ({fr.n_frames}, {k}, 3), a vector per frame and collider"
            )
        colliders = s[1]
    for name, u in (dict(getattr(tr, "potential", None) or {})).items():
        if np.shape(u) != (fr.n_frames,):
            raise TrajectoryFileError(
                f"cannot write {path}: trajectory 'potential' {name!r} has shape {np.shape(u)}; it must be ({fr.n_frames},), one value per frame"
            )
    colliders = _colliders_of(tr)
    if colliders:
        from ._h5md_colliders import collider_problem

        problem = collider_problem([f"colliders[{k}]" for k in range(len(colliders))], colliders, fr.dim)
        if problem is not None:
            raise TrajectoryFileError(f"cannot write {path}: trajectory {problem}")


def _check_units(path: Path, tr: Any, fr: Any, system: dict[str, str]) -> None:
    """Refuses values that the unit `system` makes infinite (1e300 m is 1e309 nm, beyond
    float64) or times it makes equal (two times a float64 apart may round to one in ps)."""
    if system["m"] == "m":
        return
    t = from_si(fr.t, system["s"])
    problem = increase_problem(t)
    if problem is not None:
        raise TrajectoryFileError(f"cannot write {path}: trajectory 't' in {system['s']} (units 'MD') {problem}")
    arrays = [("t", fr.t, "s"), ("positions", fr.positions, "m"), ("velocities", fr.velocities, "m s-1"), ("masses", fr.masses, "kg"), ("radii", fr.radii, "m")]
    arrays += [("angular_velocities", fr.angular_velocities, "s-1"), ("inertia", fr.inertia, "kg m2")]
    record = getattr(tr, "contact_record", None)
    if record is not None:
        arrays += [(f"contact_record {name!r}", a, FIELDS[name].unit) for name, a in record.values.items() if name in FIELDS and FIELDS[name].unit is not None]
    arrays += [("box_edges", getattr(tr, "box_edges", None), "m"), ("total", getattr(tr, "total", None), "J")]
    arrays += [(attr, getattr(tr, attr, None), si) for attr, si in OBSERVABLES.values() if si is not None]
    arrays += [(f"potential {name!r}", u, "J") for name, u in (getattr(tr, "potential", None) or {}).items()]
    arrays += [("pressure", getattr(tr, "pressure", None), PRESSURE_UNIT[fr.dim])]
    arrays += [(attr, getattr(tr, attr, None), si) for attr, si in COLLIDER_OBSERVABLES.values()]
    for word, a, si in arrays:
        if a is None or np.size(a) == 0:
            continue
        big = np.nanmax(np.abs(np.asarray(a, dtype=np.float64)), initial=0.0)
        with np.errstate(over="ignore"):
            beyond = np.isfinite(big) and not np.isfinite(from_si(big, system[si]))
        if beyond:
            raise TrajectoryFileError(
                f"cannot write {path}: trajectory {word!r} has a value ({number(big)} {si} in magnitude) beyond float64 in {system[si]} (units 'MD'); write it in SI"
            )


def _colliders_of(tr: Any) -> list[dict[str, Any]]:
    """The trajectory's collider descriptions (`Trajectory.colliders`), checked; [] when it
    has none."""
    colliders = getattr(tr, "colliders", None) or []
    if not colliders:
        return []
    from ..collider_descriptions import _describe_colliders

    return _describe_colliders(colliders)
