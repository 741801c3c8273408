"""H5MD 1.1 trajectory files (HDF5 through h5py): writing a trajectory and reading it back.

Layout written by :func:`save_h5md` (``(F)`` frames, ``N`` particles, ``D`` = 2 or 3, the
world's dimension; every time-dependent element shares one ``step`` and one ``time`` dataset
through HDF5 hard links, as the specification allows)::

    /h5md                 +-- version = [1, 1]
        author            +-- name
        creator           +-- name = "kinema", version
        modules/units     +-- version = [1, 0], system = "SI"
    /particles/<group>
        box               +-- dimension = D, boundary = ["none"] * D or "periodic" (+ edges)
        position          step int64 (F,), time float64 (F,) [s], value (F, N, D) [m]
        velocity          step, time, value (F, N, D) [m s-1]
        mass (N,) [kg], radius (N,) [m], id (N,)      time-independent, when known
    /observables
        kinetic_energy, potential_energy, total_energy    step, time, value (F,) [J]
        potential_energy_by_force/<force name>             step, time, value (F,) [J]
        momentum (F, 3) [kg m s-1], angular_momentum (F, 3) [kg m2 s-1]
        contacts (F,), impulse_balance (F, 3) [kg m s-1], collision_energy_lost (F,) [J]
    /parameters/kinema    +-- dt [s], method   (when known)
        colliders/<k>     +-- type = "plane" | "box" | "sphere", its geometry [m]
                              (point, normal | lo, hi | center, radius), restitution,
                              friction when set; k = 0, 1, ... in the world's order

Units follow the H5MD units module: a ``unit`` attribute on each ``value`` (and ``time``)
dataset, in the "SI" system, written as space-separated factors with integer powers.
"""

from __future__ import annotations

import getpass
import os
from dataclasses import MISSING, dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from ._files import TrajectoryFileError, atomic_file, frames_of

H5MD_VERSION = (1, 1)

# name in /observables: (attribute of the trajectory, unit or None for a plain number)
_OBSERVABLES = {
    "kinetic_energy": ("kinetic", "J"),
    "momentum": ("momentum", "kg m s-1"),
    "angular_momentum": ("angular_momentum", "kg m2 s-1"),
    "contacts": ("contacts", None),
    "impulse_balance": ("impulse_balance", "kg m s-1"),
    "collision_energy_lost": ("collision_energy_lost", "J"),
}
_BY_FORCE = "potential_energy_by_force"


def _h5py() -> Any:
    try:
        import h5py
    except ImportError:
        raise ImportError("H5MD files need h5py: pip install h5py") from None
    return h5py


@dataclass
class LoadedTrajectory:
    """A trajectory read from an H5MD file, with the attributes of ``kinema.Trajectory``:
    ``t`` (F,) s; ``positions``, ``velocities`` (F, N, 3) m and m/s (z = 0 when ``dim`` is
    2); ``kinetic``, ``total`` (F,) J and ``potential`` {force name: (F,)} J; ``momentum``
    (F, 3) kg m/s and ``angular_momentum`` (F, 3) kg m²/s; ``contacts`` (F,),
    ``impulse_balance`` (F, 3) N s and ``collision_energy_lost`` (F,) J. Besides: ``step``
    (F,) the integration step of each frame, ``masses`` (N,) kg, ``radii`` (N,) m, ``ids``
    (N,), ``dim``, ``dt`` s, ``method``, ``colliders`` (descriptions, as
    ``Trajectory.colliders``), ``group`` and the file's ``author`` and ``creator``. An
    element the file does not hold is ``None`` (``potential``, ``colliders``: empty)."""

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
    masses: np.ndarray | None = None
    radii: np.ndarray | None = None
    ids: np.ndarray | None = None
    dim: int = 3
    dt: float | None = None
    method: str | None = None
    periodic: tuple[bool, bool, bool] | None = None
    box_edges: np.ndarray | None = None
    colliders: list[dict[str, Any]] = field(default_factory=list)
    group: str = "all"
    author: str | None = None
    creator: str | None = None

    def to_trajectory(self) -> Any:
        """A ``kinema.Trajectory`` of these arrays: every field its constructor takes is
        passed (absent collision fields as zeros), so it follows the class as it grows."""
        from ..trajectory import Trajectory

        f = self.t.shape[0]
        zeros = {"contacts": np.zeros(f, dtype=np.int64), "impulse_balance": np.zeros((f, 3)), "collision_energy_lost": np.zeros(f)}
        args = {}
        for fl in fields(Trajectory):
            if not fl.init:
                continue
            value = getattr(self, fl.name, None)
            if value is None:
                value = zeros.get(fl.name)
            if value is None and (fl.default is not MISSING or fl.default_factory is not MISSING):
                continue  # optional in Trajectory: its default
            if value is None:
                raise ValueError(f"the file holds no {fl.name!r}, which kinema.Trajectory needs")
            args[fl.name] = value
        return Trajectory(**args)


def _chunks(shape: tuple[int, ...]) -> tuple[int, ...] | None:
    """About 1 MiB of float64 per chunk, whole frames along the first axis; ``None``
    (contiguous) for an empty dataset, which HDF5 cannot chunk."""
    if 0 in shape:
        return None
    per_frame = int(np.prod(shape[1:], dtype=np.int64))
    return (max(1, min(shape[0], (1 << 17) // max(1, per_frame))),) + tuple(shape[1:])


def _dataset(group: Any, name: str, data: np.ndarray, compression: str | None, unit: str | None = None, time_series: bool = False) -> Any:
    chunks = _chunks(data.shape)
    kwargs: dict[str, Any] = {}
    if chunks is not None:
        kwargs["chunks"] = chunks
        if time_series:
            kwargs["maxshape"] = (None,) + data.shape[1:]
        if compression is not None:
            kwargs.update(compression=compression, shuffle=True)
    ds = group.create_dataset(name, data=data, **kwargs)
    if unit is not None:
        ds.attrs["unit"] = unit
    return ds


def _element(parent: Any, name: str, value: np.ndarray, clock: Any, compression: str | None, unit: str | None) -> Any:
    """A time-dependent H5MD element: a group with ``step`` and ``time`` (hard links to the
    shared clock datasets) and ``value``."""
    g = parent.create_group(name)
    g["step"] = clock["step"]
    g["time"] = clock["time"]
    _dataset(g, "value", value, compression, unit, time_series=True)
    return g


def _write(f: Any, tr: Any, fr: Any, group: str, author: str, compression: str | None) -> None:
    from .. import __version__

    h5py = _h5py()
    string = h5py.string_dtype()
    h5md = f.create_group("h5md")
    h5md.attrs.create("version", np.array(H5MD_VERSION, dtype=np.int32))
    h5md.create_group("author").attrs["name"] = author
    creator = h5md.create_group("creator")
    creator.attrs["name"] = "kinema"
    creator.attrs["version"] = str(__version__)
    units = h5md.create_group("modules").create_group("units")
    units.attrs.create("version", np.array([1, 0], dtype=np.int32))
    units.attrs["system"] = "SI"

    d = fr.dim
    particles = f.create_group("particles").create_group(group)
    box = particles.create_group("box")
    box.attrs.create("dimension", np.int32(d))
    periodic = getattr(tr, "periodic", None)
    flags = [False] * d if periodic is None else [bool(p) for p in np.asarray(periodic).reshape(-1)[:d]]
    box.attrs.create("boundary", ["periodic" if p else "none" for p in flags], dtype=string)
    edges = getattr(tr, "box_edges", None)
    if any(flags) and edges is None:
        raise ValueError("periodic boundaries need the box edges: the trajectory has no box_edges")
    if edges is not None:
        _dataset(box, "edges", np.asarray(edges, dtype=np.float64).reshape(-1)[:d], None, "m")

    # The clock shared by every time-dependent element: the integration step of each frame
    # (t / dt rounded, or the frame index when dt is unknown) and the time in s.
    clock = particles.create_group("position")
    step = np.arange(fr.n_frames, dtype=np.int64) if not fr.dt else np.rint(fr.t / fr.dt).astype(np.int64)
    _dataset(clock, "step", step, compression, time_series=True)
    _dataset(clock, "time", fr.t, compression, "s", time_series=True)
    _dataset(clock, "value", fr.positions[..., :d], compression, "m", time_series=True)
    _element(particles, "velocity", fr.velocities[..., :d], clock, compression, "m s-1")
    for name, a, unit in (("mass", fr.masses, "kg"), ("radius", fr.radii, "m"), ("id", fr.ids, None)):
        if a is not None:
            _dataset(particles, name, a, compression, unit)

    obs = f.create_group("observables")
    kinetic = getattr(tr, "kinetic", None)
    potential = dict(getattr(tr, "potential", None) or {})
    for name, (attr, unit) in _OBSERVABLES.items():
        a = getattr(tr, attr, None)
        if a is not None:
            _element(obs, name, np.asarray(a), clock, compression, unit)
    if potential:
        by_force = obs.create_group(_BY_FORCE, track_order=True)
        by_force.attrs.create("names", list(potential), dtype=string)
        for name, u in potential.items():
            if "/" in name or name in ("", ".", ".."):
                raise ValueError(f"force name {name!r} cannot name an HDF5 group")
            _element(by_force, name, np.asarray(u, dtype=np.float64), clock, compression, "J")
        _element(obs, "potential_energy", sum(np.asarray(u, dtype=np.float64) for u in potential.values()), clock, compression, "J")
    total = getattr(tr, "total", None)
    if total is None and kinetic is not None:
        total = np.asarray(kinetic) + sum((np.asarray(u) for u in potential.values()), np.zeros(fr.n_frames))
    if total is not None:
        _element(obs, "total_energy", np.asarray(total, dtype=np.float64), clock, compression, "J")

    colliders = _colliders_of(tr)
    if fr.dt is not None or fr.method is not None or colliders:
        params = f.create_group("parameters").create_group("kinema")
        if fr.dt is not None:
            params.attrs["dt"] = fr.dt
            params.attrs["dt_unit"] = "s"
        if fr.method is not None:
            params.attrs["method"] = fr.method
        if colliders:
            # One group per collider, named by its index; the values are attributes (H5MD
            # leaves /parameters to the program), lengths in m, ±inf for an open box face.
            group_of = params.create_group("colliders", track_order=True)
            for k, c in enumerate(colliders):
                g = group_of.create_group(str(k), track_order=True)
                g.attrs["type"] = c["type"]
                for name, value in c.items():
                    if name != "type":
                        g.attrs.create(name, np.asarray(value, dtype=np.float64))


def _colliders_of(tr: Any) -> list[dict[str, Any]]:
    """The trajectory's collider descriptions (``Trajectory.colliders``), checked; [] when it
    has none."""
    colliders = getattr(tr, "colliders", None) or []
    if not colliders:
        return []
    from ..render import _describe_colliders

    return _describe_colliders(colliders)


def _read_colliders(path: Path, params: Any) -> list[dict[str, Any]]:
    """The descriptions under /parameters/kinema/colliders, in index order."""
    h5py = _h5py()
    group = params.get("colliders")
    if not isinstance(group, h5py.Group):
        return []
    out = []
    for name in sorted(group, key=lambda n: int(n) if n.isdigit() else -1):
        g = group[name]
        kind = g.attrs.get("type")
        kind = kind.decode() if isinstance(kind, bytes) else kind
        if not name.isdigit() or not isinstance(g, h5py.Group) or kind not in ("plane", "box", "sphere"):
            raise _fail(path, f"{g.name} is not a kinema collider (a group named by its index with type plane, box or sphere)")
        d: dict[str, Any] = {"type": str(kind)}
        for key, value in g.attrs.items():
            if key != "type":
                a = np.asarray(value, dtype=np.float64)
                d[key] = float(a) if a.ndim == 0 else a.tolist()
        out.append(d)
    return out


def save_h5md(traj: Any, path: str | os.PathLike, group: str = "all", author: str | None = None, compression: str | None = "gzip") -> Path:
    """Write ``traj`` to the H5MD 1.1 file ``path`` (see the module doc for the layout) and
    return the path.

    ``traj`` is a ``kinema.Trajectory`` or any object with its attributes: ``t`` (F,) s,
    ``positions`` and ``velocities`` (F, N, 3) m and m/s, ``kinetic`` (F,) J, ``potential``
    {name: (F,)} J, ``momentum`` (F, 3) kg m/s, ``angular_momentum`` (F, 3) kg m²/s and,
    when present, ``total`` (F,) J, ``contacts`` (F,), ``impulse_balance`` (F, 3) N s,
    ``collision_energy_lost`` (F,) J, ``masses`` (N,) kg, ``radii`` (N,) m, ``ids`` (N,),
    ``dim`` (2: positions are stored as (F, N, 2)), ``dt`` s, ``method``, ``periodic`` (D
    bools) with ``box_edges`` (D,) m, ``colliders`` (``Trajectory.colliders``' descriptions
    or ``kinema`` collider objects).

    ``group`` names the particle group (/particles/<group>); ``author`` the /h5md/author name
    (default: the login name); ``compression`` "gzip", "lzf" or None for the chunked
    datasets. The file is written under a temporary name in the same folder and renamed at
    the end, so a failed write leaves ``path`` as it was. Raises ``TrajectoryFileError`` when
    ``path`` cannot be written and ``ValueError`` for a malformed trajectory."""
    h5py = _h5py()
    if not group or "/" in group or group in (".", ".."):
        raise ValueError(f"group = {group!r} is invalid: it must be a non-empty name without '/'")
    fr = frames_of(traj)
    if author is None:
        try:
            author = getpass.getuser()
        except Exception:
            author = "unknown"
    path = Path(path)
    with atomic_file(path) as tmp:
        with h5py.File(tmp, "w", libver=("earliest", "latest"), track_order=True) as f:
            _write(f, traj, fr, group, author, compression)
    return path


def _fail(path: Path, what: str) -> TrajectoryFileError:
    return TrajectoryFileError(f"{path}: {what}")


def _read_element(path: Path, parent: Any, name: str, required: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(step, time, value) of a time-dependent element, or ``None`` when it is absent."""
    h5py = _h5py()
    if name not in parent:
        if required:
            raise _fail(path, f"not a complete H5MD trajectory: {parent.name}/{name} is missing")
        return None
    g = parent[name]
    if not isinstance(g, h5py.Group) or "value" not in g or "step" not in g:
        raise _fail(path, f"{g.name} is not a time-dependent H5MD element (a group with step and value)")
    value = g["value"][()]
    step = g["step"][()]
    time = g["time"][()] if "time" in g else None
    n = value.shape[0] if value.ndim else 0
    # H5MD 1.1 allows scalar step/time with an offset attribute: equal intervals.
    if np.ndim(step) == 0:
        step = g["step"].attrs.get("offset", 0) + step * np.arange(n)
    if time is not None and np.ndim(time) == 0:
        time = g["time"].attrs.get("offset", 0.0) + time * np.arange(n)
    if np.shape(step) != (n,) or (time is not None and np.shape(time) != (n,)):
        raise _fail(path, f"{g.name}: step and time must have one entry per frame of value ({n})")
    return np.asarray(step), (None if time is None else np.asarray(time)), value


def _read(path: Path, f: Any, group: str | None) -> LoadedTrajectory:
    h5py = _h5py()
    missing = [name for name in ("h5md", "particles") if not isinstance(f.get(name), h5py.Group)]
    if missing:
        raise _fail(path, f"a foreign HDF5 file, not H5MD: it has no /{' or /'.join(missing)} group")
    version = np.asarray(f["h5md"].attrs.get("version", [])).reshape(-1)
    if version.size != 2 or version[0] != 1:
        raise _fail(path, f"unsupported H5MD version {version.tolist()}; kinema reads version 1.x")
    groups = [k for k, g in f["particles"].items() if isinstance(g, h5py.Group)]
    if group is None:
        if len(groups) != 1:
            raise _fail(path, f"holds {len(groups)} particle groups; choose one with group=: {', '.join(groups) or '(none)'}")
        group = groups[0]
    if group not in groups:
        raise _fail(path, f"has no particle group {group!r}; available: {', '.join(groups) or '(none)'}")
    p = f["particles"][group]
    step, t, x = _read_element(path, p, "position", required=True)
    if x.ndim != 3 or x.shape[2] not in (2, 3):
        raise _fail(path, f"{p.name}/position/value has shape {x.shape}; it must be (F, N, 2) or (F, N, 3)")
    if t is None:
        raise _fail(path, f"{p.name}/position has no time dataset; kinema needs the time of each frame")
    d = x.shape[2]

    def three(a: np.ndarray) -> np.ndarray:
        return a if a.shape[-1] == 3 else np.concatenate([a, np.zeros(a.shape[:-1] + (3 - a.shape[-1],), dtype=a.dtype)], axis=-1)

    vel = _read_element(path, p, "velocity")
    if vel is not None and vel[2].shape != x.shape:
        raise _fail(path, f"{p.name}/velocity/value has shape {vel[2].shape} but position/value {x.shape}")
    out = LoadedTrajectory(t=t, positions=three(x), velocities=None if vel is None else three(vel[2]), step=step, dim=d, group=group)
    for name, attr in (("mass", "masses"), ("radius", "radii"), ("id", "ids")):
        if name in p:
            a = p[name][()] if isinstance(p[name], h5py.Dataset) else _read_element(path, p, name)[2][0]
            setattr(out, attr, a)
    box = p.get("box")
    if isinstance(box, h5py.Group) and "boundary" in box.attrs:
        boundary = [b.decode() if isinstance(b, bytes) else str(b) for b in np.asarray(box.attrs["boundary"]).reshape(-1)]
        flags = [b == "periodic" for b in boundary]
        if any(flags):
            out.periodic = tuple((flags + [False] * 3)[:3])
            if isinstance(box.get("edges"), h5py.Dataset):
                edges = np.asarray(box["edges"][()], dtype=np.float64).reshape(-1)
                out.box_edges = np.concatenate([edges, np.zeros(3 - edges.size)])[:3]
    obs = f.get("observables")
    if isinstance(obs, h5py.Group):
        for name, (attr, _) in _OBSERVABLES.items():
            e = _read_element(path, obs, name)
            if e is not None:
                setattr(out, attr, e[2])
        e = _read_element(path, obs, "total_energy")
        out.total = None if e is None else e[2]
        by_force = obs.get(_BY_FORCE)
        if isinstance(by_force, h5py.Group):
            names = [str(n) for n in by_force.attrs.get("names", list(by_force))]
            out.potential = {n: _read_element(path, by_force, n, required=True)[2] for n in names}
        elif "potential_energy" in obs:
            out.potential = {"potential": _read_element(path, obs, "potential_energy")[2]}
    if out.total is None and out.kinetic is not None:
        out.total = out.kinetic + sum(out.potential.values(), np.zeros_like(out.kinetic))
    params = f.get("parameters/kinema")
    if isinstance(params, h5py.Group):
        out.dt = float(params.attrs["dt"]) if "dt" in params.attrs else None
        out.method = str(params.attrs["method"]) if "method" in params.attrs else None
        out.colliders = _read_colliders(path, params)
    author = f["h5md"].get("author")
    creator = f["h5md"].get("creator")
    out.author = None if author is None else str(author.attrs.get("name", ""))
    if creator is not None:
        out.creator = f"{creator.attrs.get('name', '')} {creator.attrs.get('version', '')}".strip()
    return out


def load_h5md(path: str | os.PathLike, group: str | None = None) -> LoadedTrajectory:
    """Read the particle group ``group`` of the H5MD file ``path`` (``None``: the file's only
    group) with its observables; returns a :class:`LoadedTrajectory` (``.to_trajectory()``
    makes a ``kinema.Trajectory``). Arrays come back exactly as written; 2D positions and
    velocities get z = 0.

    Raises ``TrajectoryFileError`` (a ``ValueError``), one line naming the file, when it is
    missing, a directory, not HDF5 or corrupt, an HDF5 file without /h5md and /particles, of
    another major H5MD version, or lacks ``group`` (the message lists the groups there)."""
    h5py = _h5py()
    path = Path(path)
    if not path.exists():
        raise _fail(path, "no such file")
    if path.is_dir():
        raise _fail(path, "is a directory, not an H5MD file")
    try:
        is_hdf5 = h5py.is_hdf5(path)
    except OSError as e:
        raise _fail(path, f"cannot be read ({e.strerror or e})") from None
    if not is_hdf5:
        raise _fail(path, "not an HDF5 file (corrupt, or another format)")
    try:
        with h5py.File(path, "r") as f:
            return _read(path, f, group)
    except TrajectoryFileError:
        raise
    except (OSError, KeyError, RuntimeError) as e:
        # h5py reports a damaged file as OSError/KeyError/RuntimeError with a multi-line text.
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise _fail(path, f"corrupt HDF5 file ({first})") from None
