"""What an H5MD file holds, found before any of its data is read (for
`kinema.io.h5md_reader`, which then reads the data): `find` runs the stages in turn, each
checking the types, shapes and units of its datasets and planning the memory they need
(`Reader.plan`): the particle group, the positions and their clock, the velocities and the
spin, the contacts, the ids of particles that come and go and each particle's values, the box,
the observables, kinema's parameters and colliders, the pressure and the collider books; then
the memory, all together, against what is available. What it found is a `Found`."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ._checks import dtype_problem, shown
from ._h5md_checks import Reader, as_text, boundary_problem, element_datasets, fail, utf8, varying_ids, where
from ._h5md_colliders import _read_colliders
from ._h5md_layout import BY_FORCE, COLLIDER_OBSERVABLES, OBSERVABLES, PRESSURE_UNIT, import_h5py
from ._h5md_pairs import _contact_datasets
from .h5md_units import LENGTH, MASS, TIME, parse_unit

TIME_INVERSE = (0, -1, 0)  # an angular velocity's dimension (rad/s)
MOMENT_OF_INERTIA = (2, 0, 1)  # kg m2


# /observables read back: (name, attribute of the trajectory, a vector per frame)
_READ_OBSERVABLES = [(name, attr, attr in ("momentum", "angular_momentum", "impulse_balance")) for name, (attr, _) in OBSERVABLES.items()]


def find(path: Path, f: Any, group: str | None, memory: int | None) -> Found:
    """What the open H5MD file `f` (at `path`) holds in the particle group `group` (the only
    one when `None`), every dataset's type, shape and unit checked, and the memory reading
    them needs refused over `memory` bytes (`Reader.check_memory`); no data read."""
    found = _particle_group(path, f, group)
    _find_positions(found)
    _find_velocities(found)
    found.contacts = _contact_datasets(found.r, f, found.p)
    _find_per_particle(found)
    _find_box(found)
    _find_observables(found)
    _find_parameters(found)
    _find_books(found)
    found.r.check_memory(memory)
    return found


@dataclass
class Found:
    """What `read` finds in a file before it reads any data, filled in by its `_find_*`
    stages in turn: the particle group `p` and its `Reader`, the positions' datasets and their
    `shape` (frames, particles, coordinates), each dataset's unit factor to SI (`units`), and
    the other datasets the file has, their types and shapes checked and their memory planned."""

    path: Path
    f: Any
    p: Any
    r: Reader
    group: str
    x_ds: Any = None
    step_ds: Any = None
    t_ds: Any = None
    shape: tuple[int, ...] = ()
    box: Any = None  # /particles/<group>/box, when the file has it
    units: dict[str, Any] = field(default_factory=dict)
    vel: Any = None  # the velocity element's (value, step, time) datasets
    spin: dict[str, Any] = field(default_factory=dict)  # attribute: value dataset
    contacts: dict[str, Any] | None = None
    id_table: Any = None  # the time-dependent id element's values: particles that come and go
    per_particle: dict[str, tuple[Any, bool]] = field(default_factory=dict)  # attribute: (dataset, a time-dependent element's value)
    named: str | None = None  # the element of the species with names
    periodic: tuple[bool, ...] | None = None
    edges_ds: Any = None
    edges_by_frame: bool = False
    obs: Any = None  # /observables, when the file has it
    observables: dict[Any, Any] = field(default_factory=dict)  # attribute or ("potential", force name): value dataset
    params: Any = None  # /parameters/kinema, when the file has it
    dt: float | None = None
    method: str | None = None
    fps: float | None = None
    dim: int = 3
    colliders: list[dict[str, Any]] = field(default_factory=list)

    @property
    def frames(self) -> int:
        return self.shape[0]

    def vector_bytes(self, ds: Any, factor: float) -> int:
        """The memory reading the vectors `ds` takes: read, converted to float64 when the unit
        is not SI (in place when it is float64), and in 2D padded with z = 0 (a copy)."""
        frames, n, d = self.shape
        converted = factor != 1.0 and ds.dtype != np.float64
        out = 8 if converted else ds.dtype.itemsize
        return ds.size * ds.dtype.itemsize + (ds.size * 8 if converted else 0) + (frames * n * 3 * out if d == 2 else 0)


def _particle_group(path: Path, f: Any, group: str | None) -> Found:
    """The H5MD file's particle group to read (`group`, or the only one), with its `Reader`."""
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
    return Found(path, f, p, r, group)


def _find_positions(found: Found) -> None:
    """The positions (frames, particles, 3 or 2), their times and steps, and the box's
    dimension, which must be theirs."""
    h5py = import_h5py()
    path, p, r = found.path, found.p, found.r
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
    units: dict[str, Any] = {"positions": r.unit("positions", x_ds, LENGTH), "times": r.unit("times", t_ds, TIME)}
    found.x_ds, found.step_ds, found.t_ds, found.shape, found.box, found.units = x_ds, step_ds, t_ds, tuple(shape), box, units
    found.dim = d  # kinema's dimension, unless /parameters/kinema says 2 (`_find_parameters`)

    r.plan("positions", x_ds, found.vector_bytes(x_ds, units["positions"]))
    r.plan("times", t_ds)
    r.plan("steps", step_ds)


def _find_velocities(found: Found) -> None:
    """The velocities, and the spin: the angular velocities and the orientations."""
    path, p, r, x_ds, shape, units = found.path, found.p, found.r, found.x_ds, found.shape, found.units
    frames, n, _ = shape
    vel = element_datasets(path, p, "velocity")
    if vel is not None:
        v_ds = vel[0]
        if r.numbers("velocities", v_ds) != shape:
            raise r.fail(f"{where('velocities', v_ds)} has shape {v_ds.shape} but {where('positions', x_ds)} {shape}; they must match")
        r.clock("steps", vel[1], "velocities", v_ds, integer=True)
        if vel[2] is not None:
            r.clock("times", vel[2], "velocities", v_ds)
        units["velocities"] = r.unit("velocities", v_ds, (1, -1, 0))
        r.plan("velocities", v_ds, found.vector_bytes(v_ds, units["velocities"]))
    found.vel = vel

    # Spin (kinema's elements: H5MD has none): the angular velocities and the orientations,
    # one row per particle and frame as the positions
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
        found.spin[attr] = ds


def _find_per_particle(found: Found) -> None:
    """The ids of particles that come and go, and each particle's values: mass, radius,
    moment of inertia, id, species, colour and collision group."""
    h5py = import_h5py()
    path, p, r, x_ds, shape, units = found.path, found.p, found.r, found.x_ds, found.shape, found.units
    frames, n, _ = shape
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
    found.id_table = id_table

    per_particle = found.per_particle  # attribute: (dataset, word, whether it is a time-dependent element's value)
    # species: read where the file names them: kinema's species_index, each particle's index
    # among its `names` (its species element holds atomic numbers, for ASE), or, in kinema's
    # files before it, the species element with `names`; H5MD's own species are integers with
    # no names, which a trajectory has no use for (znh5md writes them as floats)
    named = next((k for k in ("species_index", "species") if k in p and "names" in p[k].attrs), None)
    found.named = named
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


def _find_box(found: Found) -> None:
    """The box: edges (D,) or a (D, D) matrix of edge vectors, fixed, or time-dependent with
    one row per frame (a box that may change). Its boundary is "periodic" or "none" on each
    axis, and its edges, periodic or not, lie along the axes (kinema's box is axis-aligned)."""
    h5py = import_h5py()
    path, r, x_ds, shape, units, box = found.path, found.r, found.x_ds, found.shape, found.units, found.box
    frames, _, d = shape
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
    found.periodic, found.edges_ds, found.edges_by_frame = periodic, edges_ds, edges_by_frame


def _observable(found: Found, parent: Any, name: str, vector: bool = False, required: bool = False, unit: str | None = "J") -> Any:
    """The value dataset of the observable `name` of `parent`, one value (or vector) per frame."""
    path, r, x_ds, shape, units = found.path, found.r, found.x_ds, found.shape, found.units
    frames = found.frames
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


def _find_observables(found: Found) -> None:
    """The observables: energies, momenta, the impulse balance, and the potential energy of
    each force."""
    h5py = import_h5py()
    observables = found.observables
    obs = found.obs = found.f.get("observables")
    if isinstance(obs, h5py.Group):
        for name, attr, vector in _READ_OBSERVABLES:
            observables[attr] = _observable(found, obs, name, vector, unit=OBSERVABLES[name][1])
        observables["total"] = _observable(found, obs, "total_energy")
        by_force = obs.get(BY_FORCE)
        if isinstance(by_force, h5py.Group):
            names = [n.decode() if isinstance(n, bytes) else str(n) for n in np.asarray(by_force.attrs.get("names", list(by_force))).reshape(-1)]
            for name in names:
                observables[("potential", name)] = _observable(found, by_force, name, required=True)
        elif "potential_energy" in obs:
            observables[("potential", "potential")] = _observable(found, obs, "potential_energy")


def _find_parameters(found: Found) -> None:
    """kinema's parameters: the world's dimension (a 2D world's file holds z = 0 and says
    dim = 2), the time step, the method, the frames per second and the colliders."""
    h5py = import_h5py()
    path, r, x_ds, d = found.path, found.r, found.x_ds, found.shape[2]
    params = found.params = found.f.get("parameters/kinema")
    if isinstance(params, h5py.Group):
        if "dim" in params.attrs:
            raw = params.attrs["dim"]
            a = np.asarray(raw)
            if a.size != 1 or dtype_problem(a.dtype, integer=True) is not None or int(a.reshape(())) not in (2, d):
                raise r.fail(
                    f"attribute 'dim' ({params.name}) = {shown(raw)} is not the dimension of the world (2, or {d}: {where('positions', x_ds)} has {d} coordinates)"
                )
            found.dim = int(a.reshape(()))
        if "dt" in params.attrs:
            raw = params.attrs["dt"]
            a = np.asarray(raw)
            if a.size != 1 or dtype_problem(a.dtype) is not None or not (np.isfinite(a).all() and a.reshape(()) > 0):
                raise r.fail(f"attribute 'dt' ({params.name}) = {shown(raw)} is not a positive number (the time step in s)")
            found.dt = float(a.reshape(()))
        if "method" in params.attrs:
            raw = utf8(params.attrs["method"])
            if not isinstance(raw, str):
                raise r.fail(f"attribute 'method' ({params.name}) = {shown(raw)} is not the name of an integration method")
            found.method = raw
        if "fps" in params.attrs:
            raw = params.attrs["fps"]
            a = np.asarray(raw)
            if a.size != 1 or dtype_problem(a.dtype) is not None or not (np.isfinite(a).all() and a.reshape(()) > 0):
                raise r.fail(f"attribute 'fps' ({params.name}) = {shown(raw)} is not a positive number (the frames per second recorded)")
            found.fps = float(a.reshape(()))
        found.colliders = _read_colliders(path, params, found.dim)


def _find_books(found: Found) -> None:
    """The pressure tensor of each frame and the collider books: what the particles gave each
    collider."""
    h5py = import_h5py()
    path, r, x_ds, shape, units, obs = found.path, found.r, found.x_ds, found.shape, found.units, found.obs
    frames = found.frames
    if isinstance(obs, h5py.Group) and "pressure" in obs:  # (F, 3, 3), in Pa (N m-1 in 2D)
        value, p_step, p_time = element_datasets(path, obs, "pressure", True)
        s = r.numbers("pressure", value)
        if tuple(s) != (frames, 3, 3):
            raise r.fail(f"{where('pressure', value)} has shape {s}; it must be ({frames}, 3, 3), a tensor per frame of {where('positions', x_ds)} {shape}")
        r.clock("steps", p_step, "pressure", value, integer=True)
        if p_time is not None:
            r.clock("times", p_time, "pressure", value)
        units[value.name] = r.unit("pressure", value, parse_unit(PRESSURE_UNIT[found.dim])[1])
        r.plan("pressure", value, value.size * max(8, value.dtype.itemsize))
        found.observables["pressure"] = value
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
        found.observables[attr] = value
