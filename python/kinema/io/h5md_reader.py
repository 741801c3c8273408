"""Reading H5MD files (`kinema.io.load_h5md`): `read` turns an open file into a
`LoadedTrajectory`, what the file holds in SI units, checking what it reads (through
`kinema.io._h5md_checks`): shapes, types and the memory needed before any data, then the
values. Besides the frames: the box (fixed or changing), per-particle masses, radii, ids,
species and colours, the observables, kinema's parameters and colliders, and the springs.

The colliders are read and checked in `kinema.io._h5md_colliders` (`collider_problem`, which
the writer checks with too, is importable from here as before), the springs and the contacts
(pairs of particles by id) in `kinema.io._h5md_pairs`. What the file holds is found (types,
shapes, units and memory, before any data is read) by `kinema.io._h5md_found`; this module
reads the data."""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from ..contact_record import ContactRecord
from ._checks import number
from ._files import TrajectoryFileError
from ._h5md_checks import (
    Live,
    Reader,
    as_text,
    color_problem,
    edges_problem,
    group_problem,
    increase_problem,
    mass_problem,
    per_frame,
    radius_problem,
    species_problem,
    triclinic_at,
    utf8,
    where,
)
from ._h5md_colliders import collider_problem as collider_problem
from ._h5md_found import Found, find
from ._h5md_pairs import _read_contacts, _read_springs
from .h5md_units import to_si


@dataclass
class LoadedTrajectory:
    """What an H5MD file holds, as `load_h5md` reads it: the arrays of a
    `kinema.Trajectory` under its attribute names, in SI units whatever the file's units,
    each `None` where the file does not hold it (`potential`, `colliders`: empty).
    `kinema.Trajectory.load` makes a `Trajectory` of it, which fills what is missing
    (NaN velocities and energies, "unknown") and keeps the file's own facts as
    `Trajectory.source`; this record keeps the difference between "not in the file" and a
    value, which a `Trajectory` cannot.

    `t` (F,) s; `positions`, `velocities` (F, N, 3) m and m/s (z = 0 when `dim` is
    2); `kinetic`, `total` (F,) J and `potential` {force name: (F,)} J; `momentum`
    (F, 3) kg m/s and `angular_momentum` (F, 3) kg m²/s; `contacts` (F,),
    `impulse_balance` (F, 3) N s and `collision_energy_lost` (F,) J; `masses` (N,) kg,
    `radii` (N,) m, `ids` (N,), `species` (N,) names (kinema's files), `colors` (N, 3)
    r, g, b in [0, 1], NaN: none (kinema's files), `dim`, `dt` s, `method`, `fps` (the
    frames per second asked of `World.run`; kinema's files), `periodic` (3 bools) and `box_edges` (3,) m, the periodic cell at the
    first frame; `colliders` (descriptions, as `Trajectory.colliders`), `alive` (F, N)
    bool, which particles exist at each frame (`None` when all do: a file whose number of
    particles does not vary), `springs` (S, 2) the ids at the ends of each spring,
    `angular_velocities` (F, N, 3) rad/s, `orientations` (F, N, 4) and `inertia` (N,)
    kg m² (a world with spin), `groups` (N,) int64 each particle's collision group (kinema's
    files; `None` in a file without them), `contact_record` (the contacts of each frame, a
    `kinema.contact_record.ContactRecord`), `collider_momentum`, `collider_normal` and
    `collider_tangential` (F, K, 3) N s, what the particles had given each collider by each
    frame. Where
    particles come and go, `positions` and `velocities` are NaN where they do not exist,
    one column per id (ascending).

    What only a file has (`Trajectory.source` after `Trajectory.load`): `step` (F,) the
    integration step of each frame, `box_edges_by_frame` (F, 3) m, the cell at each frame
    (a box that changes), `group`, the file's `author` and `creator` and its `path`."""

    t: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray | None
    step: np.ndarray
    kinetic: np.ndarray | None = None
    potential: dict[str, np.ndarray] = field(default_factory=dict)
    total: np.ndarray | None = None
    momentum: np.ndarray | None = None
    angular_momentum: np.ndarray | None = None
    contacts: np.ndarray | None = None
    impulse_balance: np.ndarray | None = None
    collision_energy_lost: np.ndarray | None = None
    impacts: np.ndarray | None = None
    pressure: np.ndarray | None = None
    masses: np.ndarray | None = None
    radii: np.ndarray | None = None
    ids: np.ndarray | None = None
    species: np.ndarray | None = None
    colors: np.ndarray | None = None
    dim: int = 3
    dt: float | None = None
    method: str | None = None
    fps: float | None = None
    periodic: tuple[bool, bool, bool] | None = None
    box_edges: np.ndarray | None = None
    box_edges_by_frame: np.ndarray | None = None
    colliders: list[dict[str, Any]] = field(default_factory=list)
    alive: np.ndarray | None = None
    springs: np.ndarray | None = None
    angular_velocities: np.ndarray | None = None
    orientations: np.ndarray | None = None
    inertia: np.ndarray | None = None
    groups: np.ndarray | None = None
    contact_record: ContactRecord | None = None
    collider_momentum: np.ndarray | None = None
    collider_normal: np.ndarray | None = None
    collider_tangential: np.ndarray | None = None
    group: str = "all"
    author: str | None = None
    creator: str | None = None
    path: Path | None = None


def _species_names(r: Any, obj: Any, index: np.ndarray) -> np.ndarray | None:
    """The species names of the particles: `names[index]` when the species element (or
    dataset) `obj` has a `names` attribute (kinema writes one), else `None` (H5MD's
    species are integers, and a name cannot be made up for them)."""
    if "names" not in obj.attrs:
        return None
    names = [utf8(b) for b in np.asarray(obj.attrs["names"]).reshape(-1)]
    problem = species_problem(names, "names")
    if problem is not None:
        raise r.fail(f"{where('species', obj)} {problem}")
    bad = next((k for k in index.tolist() if not 0 <= k < len(names)), None)
    if not all(isinstance(s, str) and s for s in names) or bad is not None:
        raise r.fail(f"{where('species', obj)} has species {bad} or names {names!r}: each particle's species must index its names")
    return np.array(names)[index.astype(np.int64)]


def _box_edges(r: Reader, ds: Any, e: np.ndarray, by_frame: bool, periodic: tuple[bool, ...]) -> np.ndarray:
    """The edges of the box at each frame, (F, D) m, from the values `e` of `ds` in m:
    (D,) or (F, D) edges, or (D, D) or (F, D, D) edge vectors, which must lie along the axes
    (a cuboid: kinema has no triclinic cells). Each edge is finite, > 0 on a periodic axis."""
    rows = e[None] if not by_frame else e
    if rows.ndim == 3:
        r.finite("box edges", ds, rows, ("frame",) if by_frame else ())
        _refuse_triclinic(r, ds, rows, by_frame)
        rows = np.diagonal(rows, axis1=1, axis2=2)
    problem = edges_problem(rows, periodic, by_frame)
    if problem is not None:
        raise r.fail(f"{where('box edges', ds)} {problem}")
    return rows


def _refuse_triclinic(r: Reader, ds: Any, rows: np.ndarray, by_frame: bool) -> None:
    """Refuses edge vectors `rows` (F, D, D) with an entry off the diagonal that is not 0."""
    i = triclinic_at(rows)
    if i is not None:
        at = f" at frame {i}" if by_frame else ""
        raise r.fail(f"{where('box edges', ds)} is a triclinic box{at} (edge vectors not along the axes), which kinema does not support")


def read(path: Path, f: Any, group: str | None, memory: int | None) -> LoadedTrajectory:
    """The trajectory that the open H5MD file `f` (at `path`) holds in the particle group
    `group` (the only one when `None`), in SI units: first what is there (types, shapes and
    units of every dataset, and the memory they need, refused over `memory` bytes), found by
    `kinema.io._h5md_found.find`, then the data and its values (the `_read_*` stages)."""
    found = find(path, f, group, memory)  # (kinema.io._h5md_found)
    r = found.r

    # -- The data, and its values. ------------------------------------------------------------
    out, live = _read_frames(found)
    _read_per_particle(found, out, live)
    _read_box(found, out)
    _read_observables(found, out)
    out.dt, out.method, out.fps, out.colliders = found.dt, found.method, found.fps, found.colliders
    out.springs = _read_springs(r, f, found.p, out.ids if out.ids is not None else np.arange(out.positions.shape[1]))
    if found.contacts is not None:
        out.contact_record = _read_contacts(r, found.contacts, found.frames, out.ids if out.ids is not None else np.arange(out.positions.shape[1]))
    author = f["h5md"].get("author")
    creator = f["h5md"].get("creator")
    out.author = None if author is None else as_text(author.attrs.get("name", ""))
    if creator is not None:
        out.creator = f"{as_text(creator.attrs.get('name', ''))} {as_text(creator.attrs.get('version', ''))}".strip()
    return out


def _three(a: np.ndarray) -> np.ndarray:
    """Vectors of 2 or 3 components as 3 (z = 0)."""
    return a if a.shape[-1] == 3 else np.concatenate([a, np.zeros(a.shape[:-1] + (3 - a.shape[-1],), dtype=a.dtype)], axis=-1)


def _in_plane(found: Found, live: Live | None, word: str, ds: Any, a: np.ndarray) -> None:
    """Refuses, in a 2D world's file (3 coordinates), a z that is not 0 where a particle exists."""
    if found.dim == 2 and found.shape[2] == 3:
        z = a[..., 2] if live is None else live.masked(a)[..., 2]
        if z.any():
            i, k = np.unravel_index(int(np.argmax(z != 0)), z.shape)
            raise found.r.fail(f"{where(word, ds)} has z = {number(z[i, k])} at frame {i}, particle {k}, but {found.params.name} says dim = 2 (z = 0)")


def _read_frames(found: Found) -> tuple[LoadedTrajectory, Live | None]:
    """The frames read: times, steps, positions, velocities and spins (and, for particles
    that come and go, which are alive at each frame: `Live`)."""
    r, t_ds, step_ds, x_ds, vel, units = found.r, found.t_ds, found.step_ds, found.x_ds, found.vel, found.units
    frames, n, _ = found.shape
    try:
        t = to_si(per_frame(t_ds, t_ds[()], frames, np.float64), units["times"])
        step = per_frame(step_ds, step_ds[()], frames, np.int64)
    except TrajectoryFileError as e:
        raise r.fail(str(e)) from None
    r.finite("times", t_ds, t, ("frame",))
    problem = increase_problem(t)
    if problem is not None:
        raise r.fail(f"{where('times', t_ds)} {problem}")
    live = None if found.id_table is None else Live(r, found.id_table, frames, n)

    x = to_si(x_ds[()], units["positions"])
    r.finite("positions", x_ds, x if live is None else live.masked(x), ("frame", "particle"))
    _in_plane(found, live, "positions", x_ds, x)
    velocities = None
    if vel is not None:
        v = to_si(vel[0][()], units["velocities"])
        r.finite("velocities", vel[0], v if live is None else live.masked(v), ("frame", "particle"))
        _in_plane(found, live, "velocities", vel[0], v)
        velocities = _three(v) if live is None else live.columns(_three(v))
    positions = _three(x) if live is None else live.columns(_three(x))  # 2D: z = 0 where a particle exists
    out = LoadedTrajectory(t=t, positions=positions, velocities=velocities, step=step, dim=found.dim, group=found.group, path=found.path)
    if live is not None:
        out.ids, out.alive = live.ids, live.alive
    for attr, ds in found.spin.items():
        a = to_si(ds[()], units.get(attr, Fraction(1)))
        r.finite(attr, ds, a if live is None else live.masked(a), ("frame", "particle"))
        setattr(out, attr, np.asarray(a, dtype=np.float64) if live is None else live.columns(a))
    return out, live


def _read_per_particle(found: Found, out: LoadedTrajectory, live: Live | None) -> None:
    """Each particle's values read into `out`, checked (masses > 0, radii >= 0, ...)."""
    r, units = found.r, found.units
    for attr, (ds, element) in found.per_particle.items():
        if live is None:
            a = ds[0] if element else ds[()]
        else:  # each particle's value where it first exists
            a = live.first(ds[()], element)
        a = to_si(a, units.get(attr, Fraction(1)))
        if attr != "colors":  # a colour may be NaN: none
            r.finite(attr, ds, a, ("particle",))
        problem = mass_problem(a) if attr == "masses" else radius_problem(a) if attr == "radii" else color_problem(a) if attr == "colors" else None
        if attr == "groups":
            a = np.asarray(a)
            problem = group_problem(a)
            a = a.astype(np.int64)
        if attr == "inertia" and (a < 0).any():
            problem = f"has inertia[{int(np.argmax(a < 0))}] = {number(a[np.argmax(a < 0)])} (moments of inertia are >= 0 kg m2)"
        if problem is not None:
            raise r.fail(f"{where(attr, ds)} {problem}")
        if attr == "species":  # names where the file gives them (kinema's ``names``), else none
            a = _species_names(r, found.p[found.named], np.asarray(a))
        setattr(out, attr, a)


def _read_box(found: Found, out: LoadedTrajectory) -> None:
    """The periodic box read into `out` (its edges at each frame), or open boundaries' edge
    vectors checked to lie along the axes."""
    r, edges_ds, edges_by_frame, periodic = found.r, found.edges_ds, found.edges_by_frame, found.periodic
    frames, _, d = found.shape
    if periodic is None and edges_ds is not None:  # open boundaries with edge vectors
        rows = np.asarray(edges_ds[()])
        _refuse_triclinic(r, edges_ds, rows if edges_by_frame else rows[None], edges_by_frame)
    if periodic is not None:
        edges = _box_edges(r, edges_ds, to_si(np.asarray(edges_ds[()], dtype=np.float64), found.units["box edges"]), edges_by_frame, periodic)
        out.periodic = periodic
        out.box_edges_by_frame = np.ascontiguousarray(np.broadcast_to(np.pad(edges, [(0, 0), (0, 3 - d)]), (frames, 3)))
        out.box_edges = out.box_edges_by_frame[0].copy()


def _read_observables(found: Found, out: LoadedTrajectory) -> None:
    """The observables read into `out` as they are: a potential energy may be -inf (a particle
    exactly at an unsoftened attractor point); the total energy made where the file has none."""
    for key, ds in found.observables.items():
        if ds is None:
            continue
        a = to_si(ds[()], found.units.get(ds.name, 1.0))
        if isinstance(key, tuple):
            out.potential[key[1]] = a
        else:
            setattr(out, key, a)
    if out.total is None and out.kinetic is not None:
        out.total = out.kinetic + sum(out.potential.values(), np.zeros_like(out.kinetic))
