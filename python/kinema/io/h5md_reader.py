"""Reading H5MD files (`kinema.io.load_h5md`): `read` turns an open file into a
`LoadedTrajectory`, what the file holds in SI units, checking what it reads (through
`kinema.io._h5md_checks`): shapes, types and the memory needed before any data, then the
values. Besides the frames: the box (fixed or changing), per-particle masses, radii, ids,
species and colours, the observables, kinema's parameters and colliders, and the springs.

The colliders are read and checked in `kinema.io._h5md_colliders` (`collider_problem`, which
the writer checks with too, is importable from here as before), the springs and the contacts
(pairs of particles by id) in `kinema.io._h5md_pairs`."""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from ..contact_record import ContactRecord
from ._checks import dtype_problem, number, shown
from ._files import TrajectoryFileError
from ._h5md_checks import (
    Live,
    Reader,
    as_text,
    boundary_problem,
    color_problem,
    edges_problem,
    element_datasets,
    fail,
    group_problem,
    increase_problem,
    mass_problem,
    per_frame,
    radius_problem,
    species_problem,
    triclinic_at,
    utf8,
    varying_ids,
    where,
)
from ._h5md_colliders import _read_colliders
from ._h5md_colliders import collider_problem as collider_problem
from ._h5md_layout import BY_FORCE, COLLIDER_OBSERVABLES, OBSERVABLES, PRESSURE_UNIT, import_h5py
from ._h5md_pairs import _contact_datasets, _read_contacts, _read_springs
from .h5md_units import LENGTH, MASS, TIME, parse_unit, to_si


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


TIME_INVERSE = (0, -1, 0)  # an angular velocity's dimension (rad/s)
MOMENT_OF_INERTIA = (2, 0, 1)  # kg m2


# /observables read back: (name, attribute of the trajectory, a vector per frame)
_READ_OBSERVABLES = [(name, attr, attr in ("momentum", "angular_momentum", "impulse_balance")) for name, (attr, _) in OBSERVABLES.items()]


def read(path: Path, f: Any, group: str | None, memory: int | None) -> LoadedTrajectory:
    h5py = import_h5py()
    missing = [name for name in ("h5md", "particles") if not isinstance(f.get(name), h5py.Group)]
    if missing:
        raise fail(path, f"a foreign HDF5 file, not H5MD: it has no /{' or /'.join(missing)} group")
    version = np.asarray(f["h5md"].attrs.get("version", [])).reshape(-1)
    if version.size != 2 or version[0] != 1:
        raise fail(path, f"unsupported H5MD version {version.tolist()}; kinema reads version 1.x")
    groups = [k for k, g in f["particles"].items() if isinstance(g, h5py.Group)]
    if group is None:
        if len(groups) != 1:
            raise fail(path, f"holds {len(groups)} particle groups; choose one with group=: {', '.join(groups) or '(none)'}")
        group = groups[0]
    if group not in groups:
        raise fail(path, f"has no particle group {group!r}; available: {', '.join(groups) or '(none)'}")
    p = f["particles"][group]
    creator = f["h5md"].get("creator")
    r = Reader(path, None if creator is None else as_text(creator.attrs.get("name", "")))

    # -- What is there: types and shapes, before any data is read. ---------------------------
    x_ds, step_ds, t_ds = element_datasets(path, p, "position", required=True)
    shape = r.numbers("positions", x_ds)
    if len(shape) != 3 or shape[2] not in (2, 3):
        raise r.fail(f"{where('positions', x_ds)} has shape {shape}; it must be (frames, particles, 3) or (frames, particles, 2)")
    frames, n, d = shape
    if frames == 0:
        raise r.fail(f"0 frames: {where('positions', x_ds)} has shape {shape}")
    if n == 0:
        raise r.fail(f"0 particles: {where('positions', x_ds)} has shape {shape}")
    if t_ds is None:
        raise r.fail(f"{p.name}/position has no time dataset; kinema needs the time of each frame")
    r.clock("times", t_ds, "positions", x_ds)
    r.clock("steps", step_ds, "positions", x_ds, integer=True)
    box = p.get("box")
    if isinstance(box, h5py.Group) and "dimension" in box.attrs:
        dimension = box.attrs["dimension"]
        if np.asarray(dimension).size != 1 or dtype_problem(np.asarray(dimension).dtype, integer=True) or int(np.asarray(dimension).reshape(())) != d:
            raise r.fail(f"attribute 'dimension' ({box.name}) = {shown(dimension)} but {where('positions', x_ds)} has {d} coordinates per particle")
    units: dict[str, float] = {"positions": r.unit("positions", x_ds, LENGTH), "times": r.unit("times", t_ds, TIME)}

    def vector_bytes(ds: Any, factor: float) -> int:
        # Read, converted to float64 when the unit is not SI (in place when it is float64),
        # and in 2D padded with z = 0 (a copy).
        converted = factor != 1.0 and ds.dtype != np.float64
        out = 8 if converted else ds.dtype.itemsize
        return ds.size * ds.dtype.itemsize + (ds.size * 8 if converted else 0) + (frames * n * 3 * out if d == 2 else 0)

    r.plan("positions", x_ds, vector_bytes(x_ds, units["positions"]))
    r.plan("times", t_ds)
    r.plan("steps", step_ds)

    vel = element_datasets(path, p, "velocity")
    if vel is not None:
        v_ds = vel[0]
        if r.numbers("velocities", v_ds) != shape:
            raise r.fail(f"{where('velocities', v_ds)} has shape {v_ds.shape} but {where('positions', x_ds)} {shape}; they must match")
        r.clock("steps", vel[1], "velocities", v_ds, integer=True)
        if vel[2] is not None:
            r.clock("times", vel[2], "velocities", v_ds)
        units["velocities"] = r.unit("velocities", v_ds, (1, -1, 0))
        r.plan("velocities", v_ds, vector_bytes(v_ds, units["velocities"]))

    # Spin (kinema's elements: H5MD has none): the angular velocities and the orientations,
    # one row per particle and frame as the positions
    spin = {}
    for name, attr, width, dims in (("angular_velocity", "angular_velocities", 3, TIME_INVERSE), ("orientation", "orientations", 4, None)):
        e = element_datasets(path, p, name)
        if e is None:
            continue
        ds = e[0]
        if r.numbers(attr, ds) != (frames, n, width):
            raise r.fail(
                f"{where(attr, ds)} has shape {ds.shape}; it must be ({frames}, {n}, {width}), as {where('positions', x_ds)} {shape} with {width} values"
            )
        r.clock("steps", e[1], attr, ds, integer=True)
        if e[2] is not None:
            r.clock("times", e[2], attr, ds)
        if dims is not None:
            units[attr] = r.unit(attr, ds, dims)
        r.plan(attr, ds, ds.size * 8 * 2)
        spin[attr] = ds
    contacts = _contact_datasets(r, f, p)

    # A varying number of particles (births and deaths): H5MD marks the entries of a particle
    # that does not exist at a frame by the fill value of the time-dependent id element.
    id_table = varying_ids(path, p)
    if id_table is not None:
        if r.numbers("ids", id_table, True) != (frames, n):
            raise r.fail(
                f"{where('ids', id_table)} has shape {id_table.shape}; with a fill value (particles that come and go) it must be "
                f"({frames}, {n}), one id per frame and particle ({where('positions', x_ds)} {shape})"
            )
        r.plan("ids", id_table, id_table.size * 8 * 4)  # the table, the entries present and their frames and columns

    per_particle = {}  # attribute: (dataset, word, whether it is a time-dependent element's value)
    # species: read where the file names them: kinema's species_index, each particle's index
    # among its `names` (its species element holds atomic numbers, for ASE), or, in kinema's
    # files before it, the species element with `names`; H5MD's own species are integers with
    # no names, which a trajectory has no use for (znh5md writes them as floats)
    named = next((k for k in ("species_index", "species") if k in p and "names" in p[k].attrs), None)
    each = (
        ("mass", "masses", False),
        ("radius", "radii", False),
        ("moment_of_inertia", "inertia", False),
        ("id", "ids", True),
        (named, "species", True),
        ("color", "colors", False),
        ("collision_group", "groups", True),  # kinema's element
    )
    for name, attr, integer in each:
        if name is None or name not in p or (name == "id" and id_table is not None):
            continue
        tail = (3,) if attr == "colors" else ()  # r, g, b per particle
        obj = p[name]
        if isinstance(obj, h5py.Dataset):
            if r.numbers(attr, obj, integer) != (n, *tail):
                raise r.fail(
                    f"{where(attr, obj)} has shape {obj.shape} but there are {n} particles ({where('positions', x_ds)} {shape}): "
                    f"it must be {(n, *tail)}, one value per particle"
                )
            r.plan(attr, obj)
            per_particle[attr] = (obj, False)
        else:
            obj = element_datasets(path, p, name)[0]
            s = r.numbers(attr, obj, integer)
            if len(s) != 2 + len(tail) or s[0] == 0 or s[1] != n or s[2:] != tail or (id_table is not None and s[0] != frames):
                must = ", ".join(["frames", str(n), *map(str, tail)])
                raise r.fail(f"{where(attr, obj)} has shape {s}; it must be ({must}), one value per particle ({where('positions', x_ds)} {shape})")
            r.plan(attr, obj, (frames if id_table is not None else 1) * n * (3 if tail else 1) * obj.dtype.itemsize)
            per_particle[attr] = (obj, True)
        if attr in ("masses", "radii", "inertia"):
            units[attr] = r.unit(attr, obj, {"masses": MASS, "radii": LENGTH, "inertia": MOMENT_OF_INERTIA}[attr])

    # The box: edges (D,) or a (D, D) matrix of edge vectors, fixed, or time-dependent with
    # one row per frame (a box that may change). Its boundary is "periodic" or "none" on each
    # axis, and its edges, periodic or not, lie along the axes (kinema's box is axis-aligned).
    periodic = None
    edges_ds = None
    edges_by_frame = False
    flags: list[bool] = []
    if isinstance(box, h5py.Group) and "boundary" in box.attrs:
        boundary = [b.decode("utf-8", "replace") if isinstance(b, bytes) else str(b) for b in np.asarray(box.attrs["boundary"]).reshape(-1)]
        problem = boundary_problem(boundary)
        if problem is not None:
            raise r.fail(f"attribute 'boundary' ({box.name}) {problem}")
        flags = [b == "periodic" for b in boundary]
    edges = box.get("edges") if isinstance(box, h5py.Group) else None
    if any(flags):
        periodic = tuple((flags + [False] * 3)[:3])
        if isinstance(edges, h5py.Group):
            edges_ds, edges_step, edges_time = element_datasets(path, box, "edges")
            s = r.numbers("box edges", edges_ds)
            if s not in ((frames, d), (frames, d, d)):
                raise r.fail(
                    f"{where('box edges', edges_ds)} has shape {s}; it must be ({frames}, {d}), one edge per axis at each frame of "
                    f"{where('positions', x_ds)} {shape} (or ({frames}, {d}, {d}), edge vectors)"
                )
            r.clock("steps", edges_step, "box edges", edges_ds, integer=True)
            if edges_time is not None:
                r.clock("times", edges_time, "box edges", edges_ds)
            edges_by_frame = True
        elif isinstance(edges, h5py.Dataset):
            edges_ds = edges
            s = r.numbers("box edges", edges_ds)
            if s not in ((d,), (d, d)):
                raise r.fail(f"{where('box edges', edges_ds)} has shape {s}; it must be ({d},), one edge per axis (or ({d}, {d}), edge vectors)")
        else:
            raise r.fail(f"{box.name} has periodic boundaries ({', '.join(boundary)}) but no edges dataset")
        units["box edges"] = r.unit("box edges", edges_ds, LENGTH)
        r.plan("box edges", edges_ds, edges_ds.size * (edges_ds.dtype.itemsize + 8))
    else:
        # Open boundaries: the edges are not used, but edge vectors (a matrix per frame, or
        # one) must still lie along the axes: kinema would drop a tilt it cannot hold.
        by_frame = isinstance(edges, h5py.Group)  # time-dependent: (F, D, D) edge vectors; fixed: (D, D)
        value = edges.get("value") if by_frame else edges
        if isinstance(value, h5py.Dataset) and value.shape is not None and dtype_problem(value.dtype) is None:
            if len(value.shape) == 2 + by_frame and value.shape[-2:] == (d, d):
                edges_ds, edges_by_frame = value, by_frame
                r.plan("box edges", edges_ds)

    observables: dict[str, Any] = {}  # attribute or ("potential", force name): value dataset
    obs = f.get("observables")
    if isinstance(obs, h5py.Group):

        def observable(parent: Any, name: str, vector: bool = False, required: bool = False, unit: str | None = "J") -> Any:
            e = element_datasets(path, parent, name, required)
            if e is None:
                return None
            value, step, time = e
            s = r.numbers(name, value)
            good = len(s) == 2 and s[1] in (2, 3) if vector else len(s) == 1
            if not good or s[0] != frames:
                must = f"({frames}, 3)" if vector else f"({frames},)"
                raise r.fail(f"{where(name, value)} has shape {s}; it must be {must}, one value per frame of {where('positions', x_ds)} {shape}")
            r.clock("steps", step, name, value, integer=True)
            if time is not None:
                r.clock("times", time, name, value)
            if unit is not None:  # the kinema unit of the observable: the dimension its unit must have
                units[value.name] = r.unit(name, value, parse_unit(unit)[1])
            r.plan(name, value, value.size * max(8, value.dtype.itemsize))
            return value

        for name, attr, vector in _READ_OBSERVABLES:
            observables[attr] = observable(obs, name, vector, unit=OBSERVABLES[name][1])
        observables["total"] = observable(obs, "total_energy")
        by_force = obs.get(BY_FORCE)
        if isinstance(by_force, h5py.Group):
            names = [n.decode() if isinstance(n, bytes) else str(n) for n in np.asarray(by_force.attrs.get("names", list(by_force))).reshape(-1)]
            for name in names:
                observables[("potential", name)] = observable(by_force, name, required=True)
        elif "potential_energy" in obs:
            observables[("potential", "potential")] = observable(obs, "potential_energy")

    params = f.get("parameters/kinema")
    dt = method = fps = None
    dim = d  # kinema's dimension: a 2D world's file holds z = 0 and says dim = 2 (below)
    colliders: list[dict[str, Any]] = []
    if isinstance(params, h5py.Group):
        if "dim" in params.attrs:
            raw = params.attrs["dim"]
            a = np.asarray(raw)
            if a.size != 1 or dtype_problem(a.dtype, integer=True) is not None or int(a.reshape(())) not in (2, d):
                raise r.fail(
                    f"attribute 'dim' ({params.name}) = {shown(raw)} is not the dimension of the world (2, or {d}: {where('positions', x_ds)} has {d} coordinates)"
                )
            dim = int(a.reshape(()))
        if "dt" in params.attrs:
            raw = params.attrs["dt"]
            a = np.asarray(raw)
            if a.size != 1 or dtype_problem(a.dtype) is not None or not (np.isfinite(a).all() and a.reshape(()) > 0):
                raise r.fail(f"attribute 'dt' ({params.name}) = {shown(raw)} is not a positive number (the time step in s)")
            dt = float(a.reshape(()))
        if "method" in params.attrs:
            raw = utf8(params.attrs["method"])
            if not isinstance(raw, str):
                raise r.fail(f"attribute 'method' ({params.name}) = {shown(raw)} is not the name of an integration method")
            method = raw
        if "fps" in params.attrs:
            raw = params.attrs["fps"]
            a = np.asarray(raw)
            if a.size != 1 or dtype_problem(a.dtype) is not None or not (np.isfinite(a).all() and a.reshape(()) > 0):
                raise r.fail(f"attribute 'fps' ({params.name}) = {shown(raw)} is not a positive number (the frames per second recorded)")
            fps = float(a.reshape(()))
        colliders = _read_colliders(path, params, dim)
    if isinstance(obs, h5py.Group) and "pressure" in obs:  # (F, 3, 3), in Pa (N m-1 in 2D)
        value, p_step, p_time = element_datasets(path, obs, "pressure", True)
        s = r.numbers("pressure", value)
        if tuple(s) != (frames, 3, 3):
            raise r.fail(f"{where('pressure', value)} has shape {s}; it must be ({frames}, 3, 3), a tensor per frame of {where('positions', x_ds)} {shape}")
        r.clock("steps", p_step, "pressure", value, integer=True)
        if p_time is not None:
            r.clock("times", p_time, "pressure", value)
        units[value.name] = r.unit("pressure", value, parse_unit(PRESSURE_UNIT[dim])[1])
        r.plan("pressure", value, value.size * max(8, value.dtype.itemsize))
        observables["pressure"] = value
    colliders_k = None  # (F, K, 3) each, K the same in all: a row per collider
    for name, (attr, si) in COLLIDER_OBSERVABLES.items():
        if not (isinstance(obs, h5py.Group) and name in obs):
            continue
        value, c_step, c_time = element_datasets(path, obs, name, True)
        s = r.numbers(name, value)
        if len(s) != 3 or s[0] != frames or s[2] != 3 or colliders_k not in (None, s[1]):
            k = "K" if colliders_k is None else colliders_k
            raise r.fail(
                f"{where(name, value)} has shape {s}; it must be ({frames}, {k}, 3), a vector per frame of {where('positions', x_ds)} {shape} and collider"
            )
        colliders_k = s[1]
        r.clock("steps", c_step, name, value, integer=True)
        if c_time is not None:
            r.clock("times", c_time, name, value)
        units[value.name] = r.unit(name, value, parse_unit(si)[1])
        r.plan(name, value, value.size * max(8, value.dtype.itemsize))
        observables[attr] = value

    r.check_memory(memory)

    # -- The data, and its values. ------------------------------------------------------------
    def three(a: np.ndarray) -> np.ndarray:
        return a if a.shape[-1] == 3 else np.concatenate([a, np.zeros(a.shape[:-1] + (3 - a.shape[-1],), dtype=a.dtype)], axis=-1)

    try:
        t = to_si(per_frame(t_ds, t_ds[()], frames, np.float64), units["times"])
        step = per_frame(step_ds, step_ds[()], frames, np.int64)
    except TrajectoryFileError as e:
        raise r.fail(str(e)) from None
    r.finite("times", t_ds, t, ("frame",))
    problem = increase_problem(t)
    if problem is not None:
        raise r.fail(f"{where('times', t_ds)} {problem}")
    live = None if id_table is None else Live(r, id_table, frames, n)

    def plane(word: str, ds: Any, a: np.ndarray) -> None:  # a 2D world's file: z = 0 where a particle exists
        if dim == 2 and d == 3:
            z = a[..., 2] if live is None else live.masked(a)[..., 2]
            if z.any():
                i, k = np.unravel_index(int(np.argmax(z != 0)), z.shape)
                raise r.fail(f"{where(word, ds)} has z = {number(z[i, k])} at frame {i}, particle {k}, but {params.name} says dim = 2 (z = 0)")

    x = to_si(x_ds[()], units["positions"])
    r.finite("positions", x_ds, x if live is None else live.masked(x), ("frame", "particle"))
    plane("positions", x_ds, x)
    velocities = None
    if vel is not None:
        v = to_si(vel[0][()], units["velocities"])
        r.finite("velocities", vel[0], v if live is None else live.masked(v), ("frame", "particle"))
        plane("velocities", vel[0], v)
        velocities = three(v) if live is None else live.columns(three(v))
    positions = three(x) if live is None else live.columns(three(x))  # 2D: z = 0 where a particle exists
    out = LoadedTrajectory(t=t, positions=positions, velocities=velocities, step=step, dim=dim, group=group, path=path)
    if live is not None:
        out.ids, out.alive = live.ids, live.alive
    for attr, ds in spin.items():
        a = to_si(ds[()], units.get(attr, Fraction(1)))
        r.finite(attr, ds, a if live is None else live.masked(a), ("frame", "particle"))
        setattr(out, attr, np.asarray(a, dtype=np.float64) if live is None else live.columns(a))
    for attr, (ds, element) in per_particle.items():
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
            a = _species_names(r, p[named], np.asarray(a))
        setattr(out, attr, a)
    if periodic is None and edges_ds is not None:  # open boundaries with edge vectors
        rows = np.asarray(edges_ds[()])
        _refuse_triclinic(r, edges_ds, rows if edges_by_frame else rows[None], edges_by_frame)
    if periodic is not None:
        edges = _box_edges(r, edges_ds, to_si(np.asarray(edges_ds[()], dtype=np.float64), units["box edges"]), edges_by_frame, periodic)
        out.periodic = periodic
        out.box_edges_by_frame = np.ascontiguousarray(np.broadcast_to(np.pad(edges, [(0, 0), (0, 3 - d)]), (frames, 3)))
        out.box_edges = out.box_edges_by_frame[0].copy()
    # Observables are read as they are: a potential energy may be -inf (a particle exactly at
    # an unsoftened attractor point).
    for key, ds in observables.items():
        if ds is None:
            continue
        a = to_si(ds[()], units.get(ds.name, 1.0))
        if isinstance(key, tuple):
            out.potential[key[1]] = a
        else:
            setattr(out, key, a)
    if out.total is None and out.kinetic is not None:
        out.total = out.kinetic + sum(out.potential.values(), np.zeros_like(out.kinetic))
    out.dt, out.method, out.fps, out.colliders = dt, method, fps, colliders
    out.springs = _read_springs(r, f, p, out.ids if out.ids is not None else np.arange(out.positions.shape[1]))
    if contacts is not None:
        out.contact_record = _read_contacts(r, contacts, frames, out.ids if out.ids is not None else np.arange(out.positions.shape[1]))
    author = f["h5md"].get("author")
    creator = f["h5md"].get("creator")
    out.author = None if author is None else as_text(author.attrs.get("name", ""))
    if creator is not None:
        out.creator = f"{as_text(creator.attrs.get('name', ''))} {as_text(creator.attrs.get('version', ''))}".strip()
    return out
