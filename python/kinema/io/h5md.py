"""H5MD 1.1 trajectory files (HDF5 through h5py): writing a trajectory and reading it back,
and reading the H5MD files of other programs.

Layout written by :func:`save_h5md` (``(F)`` frames, ``N`` particles, ``D`` = 2 or 3, the
world's dimension; every time-dependent element shares one ``step`` and one ``time`` dataset
through HDF5 hard links, as the specification allows, and requires for the box)::

    /h5md                 +-- version = [1, 1]
        author            +-- name                      (fixed-length string)
        creator           +-- name = "kinema", version  (fixed-length strings)
        modules/units     +-- version = [1, 0], system = "SI"
    /particles/<group>
        box               +-- dimension = D, boundary = ["none" | "periodic"] * D (fixed-length)
            edges         step, time, value (F, D) [m]: the periodic cell, 0 along open axes
            pbc           step, time, value (F, D) bool: the boundary again, for znh5md
        position          step int64 (F,), time float64 (F,) [s], value (F, N, D) [m]
        velocity          step, time, value (F, N, D) [m s-1]
        species           step, time, value (F, N) int32: the type index of each particle
        mass [kg], radius [m], id      step, time, value (F, N), when known (id: always)
    /connectivity/springs (S, 2) int64: the ids at the ends of each spring, when the trajectory
                          has springs; attribute particles_group: a reference to the group
    /observables
        kinetic_energy, potential_energy, total_energy    step, time, value (F,) [J]
        potential_energy_by_force/<force name>             step, time, value (F,) [J]
        momentum (F, 3) [kg m s-1], angular_momentum (F, 3) [kg m2 s-1]
        contacts (F,), impulse_balance (F, 3) [kg m s-1], collision_energy_lost (F,) [J]
    /parameters/kinema    +-- dt [s], method   (when known)
        colliders/<k>     +-- type = "plane" | "box" | "sphere", its geometry [m]
                              (point, normal | lo, hi | center, radius), restitution,
                              friction when set; k = 0, 1, ... in the world's order

Units follow the H5MD units module: a ``unit`` attribute (a variable-length ASCII string) on
each ``value`` (and ``time``) dataset, in the "SI" system, written as space-separated factors
with integer powers. The per-particle elements (species, mass, radius, id) and the box are
time-dependent, constant over the frames, because znh5md (ASE's H5MD reader) reads only that
form; MDAnalysis's reader and pyh5md read them too.

Births and deaths (``Trajectory.alive`` not all True) are written as H5MD 1.1 provides for a
number of particles that varies: the arrays keep N columns, one per particle that exists at
some frame, and the ``id`` element's value dataset gets a fill value (-1, or one less than
the least id), which it holds where that particle does not exist; there ``position``,
``velocity``, ``mass`` and ``radius`` hold their datasets' fill value, NaN, and ``species``
-1. Without births and deaths no fill value is set and the layout is as above.

:func:`load_h5md` converts the units of what it reads to SI (``parse_unit``: "nm", "Ang",
"ps", "nm ps-1", "u", "kJ mol-1", ...), accepts files without velocities or observables and
reads a box that changes from frame to frame.
"""

from __future__ import annotations

import getpass
import os
import re
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from ._cell import particle_types
from ._checks import available_memory, dtype_problem, first_non_finite, gib, number, shown
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
    """What an H5MD file holds, as :func:`load_h5md` reads it: the arrays of a
    ``kinema.Trajectory`` under its attribute names, in SI units whatever the file's units,
    each ``None`` where the file does not hold it (``potential``, ``colliders``: empty).
    ``kinema.Trajectory.load`` makes a ``Trajectory`` of it, which fills what is missing
    (NaN velocities and energies, "unknown") and keeps the file's own facts as
    ``Trajectory.source``; this record keeps the difference between "not in the file" and a
    value, which a ``Trajectory`` cannot.

    ``t`` (F,) s; ``positions``, ``velocities`` (F, N, 3) m and m/s (z = 0 when ``dim`` is
    2); ``kinetic``, ``total`` (F,) J and ``potential`` {force name: (F,)} J; ``momentum``
    (F, 3) kg m/s and ``angular_momentum`` (F, 3) kg m²/s; ``contacts`` (F,),
    ``impulse_balance`` (F, 3) N s and ``collision_energy_lost`` (F,) J; ``masses`` (N,) kg,
    ``radii`` (N,) m, ``ids`` (N,), ``species`` (N,) names (kinema's files), ``dim``, ``dt``
    s, ``method``, ``periodic`` (3 bools) and ``box_edges`` (3,) m, the periodic cell at the
    first frame; ``colliders`` (descriptions, as ``Trajectory.colliders``), ``alive`` (F, N)
    bool, which particles exist at each frame (``None`` when all do: a file whose number of
    particles does not vary), ``springs`` (S, 2) the ids at the ends of each spring. Where
    particles come and go, ``positions`` and ``velocities`` are NaN where they do not exist,
    one column per id (ascending).

    What only a file has (``Trajectory.source`` after ``Trajectory.load``): ``step`` (F,) the
    integration step of each frame, ``box_edges_by_frame`` (F, 3) m, the cell at each frame
    (a box that changes), ``group``, the file's ``author`` and ``creator`` and its ``path``."""

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
    species: np.ndarray | None = None
    dim: int = 3
    dt: float | None = None
    method: str | None = None
    periodic: tuple[bool, bool, bool] | None = None
    box_edges: np.ndarray | None = None
    box_edges_by_frame: np.ndarray | None = None
    colliders: list[dict[str, Any]] = field(default_factory=list)
    alive: np.ndarray | None = None
    springs: np.ndarray | None = None
    group: str = "all"
    author: str | None = None
    creator: str | None = None
    path: Path | None = None


# -- Units ------------------------------------------------------------------------------------
# A unit string of the H5MD units module is space-separated factors: at most one number first
# ("60", "10+3" = 10^3) and unit symbols, each with an optional SI prefix and an integer power
# ("nm", "ps-1", "m2"). A dimension is the powers of (length, time, mass). A mole is a number,
# Avogadro's: "kJ mol-1" is an energy per particle and "g mol-1" a particle's mass (1 u), as
# molecular-dynamics programs mean them. "A" is the ångström (as MDAnalysis reads it), not
# the ampere, which no quantity kinema reads involves.
_LENGTH, _TIME, _MASS = (1, 0, 0), (0, 1, 0), (0, 0, 1)
_ANGSTROM = (Fraction(1, 10**10), _LENGTH)
_DALTON = (Fraction("1.66053906660e-27"), _MASS)  # kg, CODATA 2018
_ENERGY = (2, -2, 1)
_SYMBOLS: dict[str, tuple[Fraction, tuple[int, int, int]]] = {
    "m": (Fraction(1), _LENGTH),
    "Ang": _ANGSTROM,
    "\u00c5": _ANGSTROM,  # Å
    "\u212b": _ANGSTROM,  # the ångström sign
    "Angstrom": _ANGSTROM,
    "angstrom": _ANGSTROM,
    "A": _ANGSTROM,
    "s": (Fraction(1), _TIME),
    "g": (Fraction(1, 1000), _MASS),
    "u": _DALTON,
    "Da": _DALTON,
    "amu": _DALTON,
    "J": (Fraction(1), _ENERGY),
    "eV": (Fraction("1.602176634e-19"), _ENERGY),
    "cal": (Fraction("4.1868"), _ENERGY),
    "erg": (Fraction(1, 10**7), _ENERGY),
    "N": (Fraction(1), (1, -2, 1)),
    "Hz": (Fraction(1), (0, -1, 0)),
    "mol": (Fraction("6.02214076e23"), (0, 0, 0)),
}
_PREFIXES = {"E": 18, "P": 15, "T": 12, "G": 9, "M": 6, "k": 3, "h": 2, "da": 1, "d": -1, "c": -2, "m": -3, "u": -6, "\u00b5": -6, "\u03bc": -6}
_PREFIXES.update({"n": -9, "p": -12, "f": -15, "a": -18})
_QUANTITY = {
    _LENGTH: "a length (m)",
    _TIME: "a time (s)",
    _MASS: "a mass (kg)",
    (1, -1, 0): "a velocity (m s-1)",
    _ENERGY: "an energy (J)",
    (1, -1, 1): "a momentum (kg m s-1)",
    (2, -1, 1): "an angular momentum (kg m2 s-1)",
}


def _symbol(token: str) -> tuple[Fraction, tuple[int, int, int]] | None:
    if token in _SYMBOLS:
        return _SYMBOLS[token]
    for prefix in sorted(_PREFIXES, key=len, reverse=True):
        if token.startswith(prefix) and token[len(prefix) :] in _SYMBOLS:
            factor, dims = _SYMBOLS[token[len(prefix) :]]
            return factor * Fraction(10) ** _PREFIXES[prefix], dims
    return None


def parse_unit(text: str) -> tuple[Fraction, tuple[int, int, int]]:
    """The SI factor (exact) and the dimension (powers of length, time, mass) of an H5MD unit
    string: ``parse_unit("nm ps-1") == (Fraction(1000), (1, -1, 0))``. Raises ``ValueError``
    saying which factor it does not know."""
    tokens = text.split()
    if not tokens:
        raise ValueError("it is empty")
    if len(text) > 200:
        raise ValueError("it is over 200 characters long")
    factor, dims = Fraction(1), [0, 0, 0]
    for k, token in enumerate(tokens):
        number = re.fullmatch(r"([0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:([+-][0-9]{1,3})|[eE]([+-]?[0-9]{1,3}))?", token)
        if number:
            if k:
                raise ValueError(f"the number {token!r} is not the first factor")
            value = Fraction(number.group(1))
            if value == 0:
                raise ValueError("its number is 0")
            if number.group(2):
                value = value ** int(number.group(2))
            elif number.group(3):
                value = value * Fraction(10) ** int(number.group(3))
            factor *= value
            continue
        match = re.fullmatch(r"([^\W\d_]+)([+-]?[0-9]{1,2})?", token)
        known = _symbol(match.group(1)) if match else None
        if known is None and "/" in token:
            raise ValueError(f"{token!r}: H5MD writes a unit as space-separated factors with powers ('nm ps-1'), not with '/'")
        if known is None:
            raise ValueError(f"{token!r} is not a unit symbol kinema knows")
        power = int(match.group(2)) if match.group(2) else 1
        factor *= known[0] ** power
        dims = [a + power * b for a, b in zip(dims, known[1], strict=True)]
    return factor, (dims[0], dims[1], dims[2])


def _chunks(shape: tuple[int, ...]) -> tuple[int, ...] | None:
    """About 1 MiB of float64 per chunk, whole frames along the first axis; ``None``
    (contiguous) for an empty dataset, which HDF5 cannot chunk."""
    if 0 in shape:
        return None
    per_frame = int(np.prod(shape[1:], dtype=np.int64))
    return (max(1, min(shape[0], (1 << 17) // max(1, per_frame))),) + tuple(shape[1:])


def _storage(shape: tuple[int, ...], compression: str | None, time_series: bool) -> dict[str, Any]:
    chunks = _chunks(shape)
    kwargs: dict[str, Any] = {}
    if chunks is not None:
        kwargs["chunks"] = chunks
        if time_series:
            kwargs["maxshape"] = (None,) + shape[1:]
        if compression is not None:
            kwargs.update(compression=compression, shuffle=True)
    return kwargs


def _set_unit(ds: Any, unit: str | None) -> None:
    """The H5MD units module's ``unit`` attribute: a variable-length ASCII string."""
    if unit is not None:
        ds.attrs.create("unit", unit, dtype=_h5py().string_dtype("ascii"))


def _fixed_string(obj: Any, name: str, value: str | list[str]) -> None:
    """A string attribute of H5MD's fixed-length string type (``author``, ``creator``,
    ``boundary``): ASCII when it is, else UTF-8, as long as its longest value (at least 1)."""
    values = [value] if isinstance(value, str) else list(value)
    encoded = [v.encode("utf-8") for v in values]
    length = max([1, *(len(b) for b in encoded)])
    dtype = _h5py().string_dtype("ascii" if all(b.isascii() for b in encoded) else "utf-8", length)
    data = np.array(encoded, dtype=f"S{length}")
    obj.attrs.create(name, data[0] if isinstance(value, str) else data, dtype=dtype)


def _dataset(group: Any, name: str, data: np.ndarray, compression: str | None, unit: str | None = None, time_series: bool = False, fill: Any = None) -> Any:
    """A dataset of ``data``; ``fill``, when given, is its HDF5 fill value (H5MD's mark of an
    entry of a particle that does not exist)."""
    options = _storage(data.shape, compression, time_series)
    if fill is not None:
        options["fillvalue"] = fill
    ds = group.create_dataset(name, data=data, **options)
    _set_unit(ds, unit)
    return ds


def _element(parent: Any, name: str, value: np.ndarray, clock: Any, compression: str | None, unit: str | None, fill: Any = None) -> Any:
    """A time-dependent H5MD element: a group with ``step`` and ``time`` (hard links to the
    shared clock datasets) and ``value`` (of fill value ``fill`` when given)."""
    g = parent.create_group(name)
    g["step"] = clock["step"]
    g["time"] = clock["time"]
    _dataset(g, "value", value, compression, unit, time_series=True, fill=fill)
    return g


def _constant_element(
    parent: Any, name: str, row: np.ndarray, clock: Any, compression: str | None, unit: str | None, alive: np.ndarray | None = None, fill: Any = None
) -> Any:
    """A time-dependent H5MD element whose value is ``row`` at every frame, written chunk by
    chunk (the (F, ...) array is never made whole). With ``alive`` (F, N), the entries of the
    particles not alive hold ``fill``, the dataset's fill value."""
    g = parent.create_group(name)
    g["step"] = clock["step"]
    g["time"] = clock["time"]
    frames = clock["step"].shape[0]
    shape = (frames,) + row.shape
    options = _storage(shape, compression, time_series=True)
    if alive is not None:
        options["fillvalue"] = fill
    ds = g.create_dataset("value", shape=shape, dtype=row.dtype, **options)
    slab = options["chunks"][0] if "chunks" in options else max(1, frames)
    for i in range(0, frames, slab):
        rows = np.broadcast_to(row, (min(slab, frames - i),) + row.shape)
        ds[i : i + slab] = rows if alive is None else np.where(alive[i : i + slab], rows, np.asarray(fill, dtype=row.dtype))
    _set_unit(ds, unit)
    return g


def _unknown(a: Any) -> bool:
    """All NaN (and not empty): values a loaded trajectory did not have (velocities or
    energies of a file without them), which are not written."""
    a = np.asarray(a)
    return a.size > 0 and a.dtype.kind == "f" and bool(np.isnan(a).all())


def _write(f: Any, tr: Any, fr: Any, group: str, author: str, compression: str | None) -> None:
    from .. import __version__

    h5py = _h5py()
    string = h5py.string_dtype()
    h5md = f.create_group("h5md")
    h5md.attrs.create("version", np.array(H5MD_VERSION, dtype=np.int32))
    _fixed_string(h5md.create_group("author"), "name", author)
    creator = h5md.create_group("creator")
    _fixed_string(creator, "name", "kinema")
    _fixed_string(creator, "version", str(__version__))
    units = h5md.create_group("modules").create_group("units")
    units.attrs.create("version", np.array([1, 0], dtype=np.int32))
    units.attrs.create("system", "SI", dtype=h5py.string_dtype("ascii"))

    d = fr.dim
    particles = f.create_group("particles").create_group(group)
    box = particles.create_group("box")
    box.attrs.create("dimension", np.int32(d))
    periodic = getattr(tr, "periodic", None)
    flags = [False] * d if periodic is None else [bool(p) for p in np.asarray(periodic).reshape(-1)[:d]]
    _fixed_string(box, "boundary", ["periodic" if p else "none" for p in flags])
    edges = getattr(tr, "box_edges", None)
    if any(flags) and edges is None:
        raise ValueError("periodic boundaries need the box edges: the trajectory has no box_edges")
    edges = np.zeros(d) if edges is None else np.asarray(edges, dtype=np.float64).reshape(-1)[:d]
    if edges.size != d:
        raise ValueError(f"box_edges has {edges.size} values; it must have one per axis, {d}")

    # The clock shared by every time-dependent element: the integration step of each frame
    # (t / dt rounded, or the frame index when dt is unknown) and the time in s.
    clock = particles.create_group("position")
    step = np.arange(fr.n_frames, dtype=np.int64) if not fr.dt else np.rint(fr.t / fr.dt).astype(np.int64)
    _dataset(clock, "step", step, compression, time_series=True)
    _dataset(clock, "time", fr.t, compression, "s", time_series=True)
    # Births and deaths (H5MD's varying number of particles): the arrays keep one column per
    # particle; at a frame where it does not exist, its id is the id dataset's fill value and
    # its other entries the fill values of theirs (NaN; species -1).
    changes = fr.changes_count
    alive = fr.alive if changes else None
    nan = np.nan if changes else None

    def placed(a: np.ndarray) -> np.ndarray:  # NaN where a particle does not exist
        return a if not changes else np.where(fr.alive[..., None], a, np.nan)

    _dataset(clock, "value", placed(fr.positions[..., :d]), compression, "m", time_series=True, fill=nan)
    # The box, time-dependent as the readers want it (znh5md and MDAnalysis read edges/value
    # only), its step and time those of position as the specification requires. znh5md reads
    # a fixed-length boundary as all periodic (it compares bytes with "none"): pbc tells it.
    _constant_element(box, "edges", edges, clock, compression, "m")
    _constant_element(box, "pbc", np.array(flags, dtype=bool), clock, compression, None)
    if not _unknown(fr.velocities[fr.alive]):
        _element(particles, "velocity", placed(fr.velocities[..., :d]), clock, compression, "m s-1", fill=nan)
    names, species = particle_types(tr, fr.n_particles)
    no_id = min(-1, int(fr.ids.min()) - 1) if fr.ids.size else -1  # the id of no particle: -1 unless an id is negative
    per_particle = (
        ("species", species.astype(np.int32), None, -1),
        ("mass", fr.masses, "kg", np.nan),
        ("radius", fr.radii, "m", np.nan),
        ("id", fr.ids, None, no_id),
    )
    for name, a, unit, fill in per_particle:
        if a is not None:
            element = _constant_element(particles, name, np.asarray(a), clock, compression, unit, alive, fill)
            if name == "species" and getattr(tr, "species", None) is not None:
                _fixed_string(element, "names", names)  # species k is names[k] (kinema's; H5MD's species are integers)

    obs = f.create_group("observables")
    kinetic = getattr(tr, "kinetic", None)
    potential = dict(getattr(tr, "potential", None) or {})
    for name, (attr, unit) in _OBSERVABLES.items():
        a = getattr(tr, attr, None)
        if a is not None and not _unknown(a):
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
    if total is not None and not _unknown(total):
        _element(obs, "total_energy", np.asarray(total, dtype=np.float64), clock, compression, "J")

    springs = getattr(tr, "springs", None)
    if springs is not None:
        # H5MD's connectivity group: a time-independent list of pairs whose values are the
        # particles' ids (the particle group has an id element), particles_group naming it.
        pairs = np.asarray(springs, dtype=np.int64).reshape(-1, 2)
        unknown = np.setdiff1d(pairs, fr.ids)
        if unknown.size:
            raise ValueError(f"springs: id {int(unknown[0])} is not the id of a particle of the trajectory")
        ds = f.require_group("connectivity").create_dataset("springs", data=pairs)
        ds.attrs["particles_group"] = particles.ref

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


def _read_colliders(path: Path, params: Any, dim: int) -> list[dict[str, Any]]:
    """The descriptions under /parameters/kinema/colliders, in index order, each checked by
    the engine as ``World.add`` checks a collider (in a world of ``dim`` dimensions)."""
    h5py = _h5py()
    group = params.get("colliders")
    if not isinstance(group, h5py.Group):
        return []
    out = []
    names = []
    for name in sorted(group, key=lambda n: int(n) if n.isdigit() else -1):
        g = group[name]
        kind = g.attrs.get("type")
        kind = kind.decode() if isinstance(kind, bytes) else kind
        if not name.isdigit() or not isinstance(g, h5py.Group) or not isinstance(kind, str) or kind not in ("plane", "box", "sphere"):
            raise _fail(path, f"{g.name} is not a kinema collider (a group named by its index with type plane, box or sphere)")
        d: dict[str, Any] = {"type": str(kind)}
        for key, value in g.attrs.items():
            if key != "type":
                a = np.asarray(value)
                if a.size == 0 or dtype_problem(a.dtype) is not None:
                    raise _fail(path, f"attribute {key!r} ({g.name}) = {shown(value)} is not a number")
                a = a.astype(np.float64)
                d[key] = float(a) if a.ndim == 0 else a.tolist()
        out.append(d)
        names.append(g.name)
    if out:
        _check_colliders(path, names, out, dim)
    return out


def _check_colliders(path: Path, names: list[str], colliders: list[dict[str, Any]], dim: int) -> None:
    """Adds each collider to an empty engine world of ``dim`` dimensions, as ``World.add``
    does: the engine's checks (finite values, a non-zero normal, hi > lo, 2 or 3 values,
    restitution in [0, 1], ...). The engine's own ``World``, not ``kinema.World``: reading a
    file needs no world module (which imports ``kinema.trajectory``, which imports this)."""
    from .. import _core
    from ..colliders import Box, Plane, SphereObstacle
    from ..render import _KIND

    core = _core.World(dim, 1e-3, "verlet")
    make = {"plane": Plane, "box": Box, "sphere": SphereObstacle}
    for name, d in zip(names, colliders, strict=True):
        needed = _KIND[d["type"]]
        missing = [k for k in needed if k not in d]
        if missing:
            raise _fail(path, f"collider {name} (a {d['type']}) has no attribute {missing[0]!r}")
        args = {k: d[k] for k in (*needed, "restitution", "friction") if k in d}
        try:
            make[d["type"]](**args)._attach(core)
        except (ValueError, TypeError) as e:
            first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
            raise _fail(path, f"collider {name} (a {d['type']}): {first}") from None


def save_h5md(traj: Any, path: str | os.PathLike, group: str = "all", author: str | None = None, compression: str | None = "gzip") -> Path:
    """Write ``traj`` to the H5MD 1.1 file ``path`` (see the module doc for the layout) and
    return the path.

    ``traj`` is a ``kinema.Trajectory`` or any object with its attributes: ``t`` (F,) s,
    ``positions`` and ``velocities`` (F, N, 3) m and m/s, ``kinetic`` (F,) J, ``potential``
    {name: (F,)} J, ``momentum`` (F, 3) kg m/s, ``angular_momentum`` (F, 3) kg m²/s and,
    when present, ``total`` (F,) J, ``contacts`` (F,), ``impulse_balance`` (F, 3) N s,
    ``collision_energy_lost`` (F,) J, ``masses`` (N,) kg, ``radii`` (N,) m, ``ids`` (N,),
    ``dim`` (2: positions are stored as (F, N, 2)), ``dt`` s, ``method``, ``periodic`` (D
    bools) with ``box_edges`` (D,) m, ``species`` (N,) names (the ``species`` element: the
    index of each particle's name among the sorted names, which its ``names`` attribute
    holds; 0 for all without ``species``),
    ``colliders`` (``Trajectory.colliders``' descriptions or ``kinema`` collider objects),
    ``alive`` (F, N) bool, which particles exist at each frame (births and deaths: written
    with H5MD's fill values, see the module doc), ``springs`` (S, 2) the ids at the ends of
    each spring (``/connectivity/springs``). Velocities and observables that are all NaN (unknown: a trajectory loaded from a file
    without them) are not written.

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


def _species_names(r: Any, obj: Any, index: np.ndarray) -> np.ndarray | None:
    """The species names of the particles: ``names[index]`` when the species element (or
    dataset) ``obj`` has a ``names`` attribute (kinema writes one), else ``None`` (H5MD's
    species are integers, and a name cannot be made up for them)."""
    if "names" not in obj.attrs:
        return None
    names = [_utf8(b) for b in np.asarray(obj.attrs["names"]).reshape(-1)]
    bad = next((k for k in index.tolist() if not 0 <= k < len(names)), None)
    if not all(isinstance(s, str) and s for s in names) or bad is not None:
        raise r.fail(f"{_where('species', obj)} has species {bad} or names {names!r}: each particle's species must index its names")
    return np.array(names)[index.astype(np.int64)]


def _utf8(raw: Any) -> Any:
    """An attribute's bytes (a fixed-length HDF5 string) as text; anything else as it is,
    for the caller to refuse by type."""
    if isinstance(raw, bytes):
        try:
            return raw.decode("utf-8")
        except UnicodeDecodeError:
            pass
    return raw


def _where(word: str, ds: Any) -> str:
    """A dataset as a message names it: its meaning and its path in the file."""
    return f"dataset {word!r} ({ds.name})"


class _Reader:
    """The reads of one file. Every dataset's type and shape is checked, and the bytes it
    needs added up (``plan``), before any data is read; ``check_memory`` then refuses a file
    that does not fit in the memory there is; ``finite`` checks values once read."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.planned: list[tuple[str, Any, int]] = []

    def fail(self, what: str) -> TrajectoryFileError:
        return _fail(self.path, what)

    def numbers(self, word: str, ds: Any, integer: bool = False) -> tuple[int, ...]:
        """The shape of ``ds``, which must hold real numbers (integers when ``integer``)."""
        must = "integers" if integer else "real numbers"
        if ds.shape is None:
            raise self.fail(f"{_where(word, ds)} holds no data (an empty dataspace); it must hold {must}")
        problem = dtype_problem(ds.dtype, integer)
        if problem is not None:
            raise self.fail(f"{_where(word, ds)} holds {problem}; it must hold {must}")
        return tuple(ds.shape)

    def clock(self, word: str, ds: Any, value_word: str, value: Any, integer: bool = False) -> None:
        """``ds`` (the step or time of an element) holds one number per frame of ``value``,
        or one number (H5MD's fixed interval)."""
        shape = self.numbers(word, ds, integer)
        n = value.shape[0]
        if shape not in ((), (n,)):
            one = word[:-1] if word.endswith("s") else word
            raise self.fail(f"{_where(word, ds)} has shape {shape} but {_where(value_word, value)} has {n} frames: one {one} per frame")

    def unit(self, word: str, ds: Any, dims: tuple[int, int, int]) -> float:
        """The factor that converts the values of ``ds`` to SI, from its ``unit`` attribute,
        which must be a unit of the dimension ``dims`` (``parse_unit``); 1 when it has none
        (the values are taken as SI)."""
        if "unit" not in ds.attrs:
            return 1.0
        raw = ds.attrs["unit"]
        text = _utf8(raw.reshape(-1)[0] if isinstance(raw, np.ndarray) and raw.size == 1 else raw)
        if not isinstance(text, str):
            raise self.fail(f"{_where(word, ds)} has a unit attribute that is not a string: {shown(raw)}")
        try:
            factor, dims_found = parse_unit(text)
            value = float(factor)
        except (ValueError, OverflowError) as e:
            raise self.fail(f"{_where(word, ds)} has unit {text!r}, which kinema cannot read: {e}") from None
        if dims_found != dims:
            raise self.fail(f"{_where(word, ds)} has unit {text!r}, which is not {_QUANTITY[dims]}")
        if not 0 < value < np.inf:
            raise self.fail(f"{_where(word, ds)} has unit {text!r}, whose factor to SI is out of the range of float64")
        return value

    def plan(self, word: str, ds: Any, nbytes: int | None = None) -> None:
        self.planned.append((word, ds, int(ds.size) * ds.dtype.itemsize if nbytes is None else nbytes))

    def check_memory(self, limit: int | None) -> None:
        if limit is None or not self.planned:
            return
        for word, ds, nbytes in self.planned:
            if nbytes > limit:
                raise self.fail(
                    f"{_where(word, ds)} of shape {tuple(ds.shape)} ({ds.dtype}) needs {gib(nbytes)} GiB of memory to load; {gib(limit)} GiB is available"
                )
        total = sum(nbytes for _, _, nbytes in self.planned)
        if total > limit:
            word, ds, nbytes = max(self.planned, key=lambda p: p[2])
            raise self.fail(
                f"loading it needs {gib(total)} GiB of memory ({_where(word, ds)} of shape {tuple(ds.shape)} ({ds.dtype}): "
                f"{gib(nbytes)} GiB); {gib(limit)} GiB is available"
            )

    def finite(self, word: str, ds: Any, a: np.ndarray, axes: tuple[str, ...]) -> None:
        """Refuses a NaN or ±inf in ``a`` (read from ``ds``), naming its place: ``axes`` name
        the leading indices (frame, particle)."""
        at = first_non_finite(a)
        if at is not None:
            place = ", ".join(f"{name} {i}" for name, i in zip(axes, at, strict=False))
            raise self.fail(f"{_where(word, ds)} has a non-finite value ({number(a[at])})" + (f" at {place}" if place else ""))


def _element_datasets(path: Path, parent: Any, name: str, required: bool = False) -> tuple[Any, Any, Any] | None:
    """The (value, step, time) datasets of a time-dependent element (time ``None`` when it
    has none), or ``None`` when it is absent."""
    h5py = _h5py()
    if name not in parent:
        if required:
            raise _fail(path, f"not a complete H5MD trajectory: {parent.name.rstrip('/')}/{name} is missing")
        return None
    g = parent[name]
    value, step, time = (g.get(k) for k in ("value", "step", "time")) if isinstance(g, h5py.Group) else (None, None, None)
    if not (isinstance(value, h5py.Dataset) and isinstance(step, h5py.Dataset) and (time is None or isinstance(time, h5py.Dataset))):
        raise _fail(path, f"{g.name} is not a time-dependent H5MD element (a group with step and value datasets)")
    return value, step, time


def _per_frame(ds: Any, a: np.ndarray, n: int, dtype: Any) -> np.ndarray:
    """A step or time read from ``ds``: one per frame, or H5MD's fixed interval (a scalar
    ``a`` and the ``offset`` attribute) made one per frame."""
    if np.ndim(a) != 0:
        return np.asarray(a)
    offset = ds.attrs.get("offset", 0)
    if np.asarray(offset).size != 1 or dtype_problem(np.asarray(offset).dtype) is not None:
        raise TrajectoryFileError(f"attribute 'offset' ({ds.name}) = {shown(offset)} is not a number")
    return (np.asarray(offset).reshape(()) + a * np.arange(n)).astype(dtype, copy=False)


def _to_si(a: Any, factor: float) -> Any:
    """``a`` (just read from a file) in SI: times ``factor`` (in place when it is float64, else
    as float64); ``a`` itself when the factor is 1."""
    if factor == 1.0:
        return a
    if isinstance(a, np.ndarray) and a.dtype == np.float64 and a.flags.writeable:
        a *= factor
        return a
    return np.asarray(a, dtype=np.float64) * factor


def _text(value: Any) -> str:
    """A string attribute as text: H5MD's fixed-length strings read back as bytes."""
    if isinstance(value, np.ndarray) and value.size == 1:
        value = value.reshape(-1)[0]
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)


def _box_edges(r: _Reader, ds: Any, e: np.ndarray, by_frame: bool, periodic: tuple[bool, ...]) -> np.ndarray:
    """The edges of the box at each frame, (F, D) m, from the values ``e`` of ``ds`` in m:
    (D,) or (F, D) edges, or (D, D) or (F, D, D) edge vectors, which must lie along the axes
    (a cuboid: kinema has no triclinic cells). Each edge is finite, > 0 on a periodic axis."""
    rows = e[None] if not by_frame else e
    frame = (lambda i: f" at frame {i}") if by_frame else (lambda i: "")
    if rows.ndim == 3:
        r.finite("box edges", ds, rows, ("frame",) if by_frame else ())
        d = rows.shape[1]
        off = np.flatnonzero((rows * (1 - np.eye(d))).reshape(rows.shape[0], -1).any(axis=1))
        if off.size:
            raise r.fail(f"{_where('box edges', ds)} is a triclinic box{frame(int(off[0]))} (edge vectors not along the axes), which kinema does not support")
        rows = np.diagonal(rows, axis1=1, axis2=2)
    bad = ~np.isfinite(rows)
    if bad.any():
        i, k = np.unravel_index(int(np.argmax(bad)), rows.shape)
        raise r.fail(f"{_where('box edges', ds)} has edge[{k}] = {number(rows[i, k])}{frame(i)} (box edges must be finite, in m)")
    bad = (rows <= 0) & np.array(periodic[: rows.shape[1]])
    if bad.any():
        i, k = np.unravel_index(int(np.argmax(bad)), rows.shape)
        raise r.fail(f"{_where('box edges', ds)} has edge[{k}] = {number(rows[i, k])}{frame(i)} (a periodic axis needs an edge > 0 m)")
    return rows


def _varying_ids(path: Path, p: Any) -> Any:
    """The ``value`` dataset of the particle group's time-dependent ``id`` element when it has
    a fill value (set when it was created): the mark, in H5MD, of a number of particles that
    varies (an entry equal to it is a particle that does not exist at that frame); else
    ``None``."""
    h5py = _h5py()
    if not isinstance(p.get("id"), h5py.Group):
        return None
    ds = _element_datasets(path, p, "id")[0]
    if ds.shape is None or ds.dtype.kind not in "iu":
        return None  # the per-particle checks name it
    return ds if ds.id.get_create_plist().fill_value_defined() == h5py.h5d.FILL_VALUE_USER_DEFINED else None


class _Live:
    """The particles of a file whose number varies: the id of each of its (F, N) entries or
    the fill value (H5MD's "no particle here"). kinema's trajectories have one column per
    particle, the ids ascending, so the entries are gathered by id: ``ids`` (U,) the ids
    that exist at some frame, ``alive`` (F, U). A file whose particles keep their slot (as
    kinema writes them, with ascending ids) reads back column for column."""

    def __init__(self, r: _Reader, ds: Any, frames: int, n: int) -> None:
        table = np.asarray(ds[()], dtype=np.int64)
        fill = ds.fillvalue
        self.present = table != fill
        self.frame, self.slot = np.nonzero(self.present)  # frame by frame
        self.ids, self.column = np.unique(table[self.present], return_inverse=True)
        self.column = self.column.reshape(-1)
        if self.ids.size == 0:
            raise r.fail(f"0 particles: every entry of {_where('ids', ds)} is its fill value {number(fill)} (no particle exists at any frame)")
        key = self.frame * self.ids.size + self.column
        order = np.sort(key)
        twice = np.flatnonzero(np.diff(order) == 0)
        if twice.size:
            k, c = divmod(int(order[twice[0]]), self.ids.size)
            raise r.fail(f"{_where('ids', ds)} holds id {int(self.ids[c])} twice at frame {k} (an id names one particle)")
        self.frames = frames
        self.alive = np.zeros((frames, self.ids.size), dtype=bool)
        self.alive[self.frame, self.column] = True
        # the entry where each particle first exists
        self.first_entry = np.unique(self.column, return_index=True)[1]

    def masked(self, a: np.ndarray) -> np.ndarray:
        """``a`` (F, N, ...) with 0 where no particle exists: what is checked for finite values."""
        mask = self.present.reshape(self.present.shape + (1,) * (a.ndim - 2))
        return np.where(mask, a, 0)

    def columns(self, a: np.ndarray) -> np.ndarray:
        """``a`` (F, N, D) by particle: (F, U, D), NaN where a particle does not exist."""
        out = np.full((self.frames, self.ids.size) + a.shape[2:], np.nan)
        out[self.frame, self.column] = a[self.frame, self.slot]
        return out

    def first(self, a: np.ndarray, element: bool) -> np.ndarray:
        """A per-particle value (U,) from ``a``, (F, N) (a time-dependent element) or (N,):
        its value at the first entry of each particle."""
        e = self.first_entry
        return a[self.frame[e], self.slot[e]] if element else a[self.slot[e]]


def _read_springs(r: _Reader, f: Any, p: Any, ids: np.ndarray) -> np.ndarray | None:
    """The springs (S, 2) ids of ``/connectivity/springs`` (kinema's: H5MD's time-independent
    list of pairs, whose ``particles_group`` is the particle group read), ``None`` without
    them."""
    h5py = _h5py()
    ds = f.get("connectivity/springs")
    if not isinstance(ds, h5py.Dataset):
        return None
    ref = ds.attrs.get("particles_group")
    if isinstance(ref, h5py.Reference) and ref and f[ref].name != p.name:
        return None  # the springs of another particle group
    s = r.numbers("springs", ds, integer=True)
    if len(s) != 2 or s[1] != 2:
        raise r.fail(f"{_where('springs', ds)} has shape {s}; it must be (springs, 2), the ids of the two ends of each spring")
    pairs = np.asarray(ds[()], dtype=np.int64)
    unknown = np.setdiff1d(pairs, ids)
    if unknown.size:
        raise r.fail(f"{_where('springs', ds)} names id {int(unknown[0])}, which is no particle's ({p.name}/id)")
    return pairs


# /observables read back: (name, attribute of the trajectory, a vector per frame)
_READ_OBSERVABLES = [(name, attr, attr in ("momentum", "angular_momentum", "impulse_balance")) for name, (attr, _) in _OBSERVABLES.items()]


def _read(path: Path, f: Any, group: str | None, memory: int | None) -> LoadedTrajectory:
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
    r = _Reader(path)

    # -- What is there: types and shapes, before any data is read. ---------------------------
    x_ds, step_ds, t_ds = _element_datasets(path, p, "position", required=True)
    shape = r.numbers("positions", x_ds)
    if len(shape) != 3 or shape[2] not in (2, 3):
        raise r.fail(f"{_where('positions', x_ds)} has shape {shape}; it must be (frames, particles, 3) or (frames, particles, 2)")
    frames, n, d = shape
    if frames == 0:
        raise r.fail(f"0 frames: {_where('positions', x_ds)} has shape {shape}")
    if n == 0:
        raise r.fail(f"0 particles: {_where('positions', x_ds)} has shape {shape}")
    if t_ds is None:
        raise r.fail(f"{p.name}/position has no time dataset; kinema needs the time of each frame")
    r.clock("times", t_ds, "positions", x_ds)
    r.clock("steps", step_ds, "positions", x_ds, integer=True)
    box = p.get("box")
    if isinstance(box, h5py.Group) and "dimension" in box.attrs:
        dimension = box.attrs["dimension"]
        if np.asarray(dimension).size != 1 or dtype_problem(np.asarray(dimension).dtype, integer=True) or int(np.asarray(dimension).reshape(())) != d:
            raise r.fail(f"attribute 'dimension' ({box.name}) = {shown(dimension)} but {_where('positions', x_ds)} has {d} coordinates per particle")
    units: dict[str, float] = {"positions": r.unit("positions", x_ds, _LENGTH), "times": r.unit("times", t_ds, _TIME)}

    def vector_bytes(ds: Any, factor: float) -> int:
        # Read, converted to float64 when the unit is not SI (in place when it is float64),
        # and in 2D padded with z = 0 (a copy).
        converted = factor != 1.0 and ds.dtype != np.float64
        out = 8 if converted else ds.dtype.itemsize
        return ds.size * ds.dtype.itemsize + (ds.size * 8 if converted else 0) + (frames * n * 3 * out if d == 2 else 0)

    r.plan("positions", x_ds, vector_bytes(x_ds, units["positions"]))
    r.plan("times", t_ds)
    r.plan("steps", step_ds)

    vel = _element_datasets(path, p, "velocity")
    if vel is not None:
        v_ds = vel[0]
        if r.numbers("velocities", v_ds) != shape:
            raise r.fail(f"{_where('velocities', v_ds)} has shape {v_ds.shape} but {_where('positions', x_ds)} {shape}; they must match")
        r.clock("steps", vel[1], "velocities", v_ds, integer=True)
        if vel[2] is not None:
            r.clock("times", vel[2], "velocities", v_ds)
        units["velocities"] = r.unit("velocities", v_ds, (1, -1, 0))
        r.plan("velocities", v_ds, vector_bytes(v_ds, units["velocities"]))

    # A varying number of particles (births and deaths): H5MD marks the entries of a particle
    # that does not exist at a frame by the fill value of the time-dependent id element.
    id_table = _varying_ids(path, p)
    if id_table is not None:
        if r.numbers("ids", id_table, True) != (frames, n):
            raise r.fail(
                f"{_where('ids', id_table)} has shape {id_table.shape}; with a fill value (particles that come and go) it must be "
                f"({frames}, {n}), one id per frame and particle ({_where('positions', x_ds)} {shape})"
            )
        r.plan("ids", id_table, id_table.size * 8 * 4)  # the table, the entries present and their frames and columns

    per_particle = {}  # attribute: (dataset, word, whether it is a time-dependent element's value)
    # species: read where the file names them (kinema's `names`); H5MD's own species are
    # integers with no names, which a trajectory has no use for (znh5md writes them as floats)
    named = "species" in p and "names" in p["species"].attrs
    for name, attr, integer in (("mass", "masses", False), ("radius", "radii", False), ("id", "ids", True), ("species", "species", True)):
        if name not in p or (name == "species" and not named) or (name == "id" and id_table is not None):
            continue
        obj = p[name]
        if isinstance(obj, h5py.Dataset):
            if r.numbers(attr, obj, integer) != (n,):
                raise r.fail(
                    f"{_where(attr, obj)} has shape {obj.shape} but there are {n} particles ({_where('positions', x_ds)} {shape}): one value per particle"
                )
            r.plan(attr, obj)
            per_particle[attr] = (obj, False)
        else:
            obj = _element_datasets(path, p, name)[0]
            s = r.numbers(attr, obj, integer)
            if len(s) != 2 or s[0] == 0 or s[1] != n or (id_table is not None and s[0] != frames):
                raise r.fail(f"{_where(attr, obj)} has shape {s}; it must be (frames, {n}), one value per particle ({_where('positions', x_ds)} {shape})")
            r.plan(attr, obj, (frames if id_table is not None else 1) * n * obj.dtype.itemsize)
            per_particle[attr] = (obj, True)
        if not integer:
            units[attr] = r.unit(attr, obj, _MASS if attr == "masses" else _LENGTH)

    # The box: edges (D,) or a (D, D) matrix of edge vectors, fixed, or time-dependent with
    # one row per frame (a box that may change).
    periodic = None
    edges_ds = None
    edges_by_frame = False
    if isinstance(box, h5py.Group) and "boundary" in box.attrs:
        boundary = [b.decode("utf-8", "replace") if isinstance(b, bytes) else str(b) for b in np.asarray(box.attrs["boundary"]).reshape(-1)]
        flags = [b == "periodic" for b in boundary]
        if any(flags):
            periodic = tuple((flags + [False] * 3)[:3])
            edges = box.get("edges")
            if isinstance(edges, h5py.Group):
                edges_ds, edges_step, edges_time = _element_datasets(path, box, "edges")
                s = r.numbers("box edges", edges_ds)
                if s not in ((frames, d), (frames, d, d)):
                    raise r.fail(
                        f"{_where('box edges', edges_ds)} has shape {s}; it must be ({frames}, {d}), one edge per axis at each frame of "
                        f"{_where('positions', x_ds)} {shape} (or ({frames}, {d}, {d}), edge vectors)"
                    )
                r.clock("steps", edges_step, "box edges", edges_ds, integer=True)
                if edges_time is not None:
                    r.clock("times", edges_time, "box edges", edges_ds)
                edges_by_frame = True
            elif isinstance(edges, h5py.Dataset):
                edges_ds = edges
                s = r.numbers("box edges", edges_ds)
                if s not in ((d,), (d, d)):
                    raise r.fail(f"{_where('box edges', edges_ds)} has shape {s}; it must be ({d},), one edge per axis (or ({d}, {d}), edge vectors)")
            else:
                raise r.fail(f"{box.name} has periodic boundaries ({', '.join(boundary)}) but no edges dataset")
            units["box edges"] = r.unit("box edges", edges_ds, _LENGTH)
            r.plan("box edges", edges_ds, edges_ds.size * (edges_ds.dtype.itemsize + 8))

    observables: dict[str, Any] = {}  # attribute or ("potential", force name): value dataset
    obs = f.get("observables")
    if isinstance(obs, h5py.Group):

        def observable(parent: Any, name: str, vector: bool = False, required: bool = False, unit: str | None = "J") -> Any:
            e = _element_datasets(path, parent, name, required)
            if e is None:
                return None
            value, step, time = e
            s = r.numbers(name, value)
            good = len(s) == 2 and s[1] in (2, 3) if vector else len(s) == 1
            if not good or s[0] != frames:
                must = f"({frames}, 3)" if vector else f"({frames},)"
                raise r.fail(f"{_where(name, value)} has shape {s}; it must be {must}, one value per frame of {_where('positions', x_ds)} {shape}")
            r.clock("steps", step, name, value, integer=True)
            if time is not None:
                r.clock("times", time, name, value)
            if unit is not None:  # the kinema unit of the observable: the dimension its unit must have
                units[value.name] = r.unit(name, value, parse_unit(unit)[1])
            r.plan(name, value, value.size * max(8, value.dtype.itemsize))
            return value

        for name, attr, vector in _READ_OBSERVABLES:
            observables[attr] = observable(obs, name, vector, unit=_OBSERVABLES[name][1])
        observables["total"] = observable(obs, "total_energy")
        by_force = obs.get(_BY_FORCE)
        if isinstance(by_force, h5py.Group):
            names = [n.decode() if isinstance(n, bytes) else str(n) for n in np.asarray(by_force.attrs.get("names", list(by_force))).reshape(-1)]
            for name in names:
                observables[("potential", name)] = observable(by_force, name, required=True)
        elif "potential_energy" in obs:
            observables[("potential", "potential")] = observable(obs, "potential_energy")

    params = f.get("parameters/kinema")
    dt = method = None
    colliders: list[dict[str, Any]] = []
    if isinstance(params, h5py.Group):
        if "dt" in params.attrs:
            raw = params.attrs["dt"]
            a = np.asarray(raw)
            if a.size != 1 or dtype_problem(a.dtype) is not None or not (np.isfinite(a).all() and a.reshape(()) > 0):
                raise r.fail(f"attribute 'dt' ({params.name}) = {shown(raw)} is not a positive number (the time step in s)")
            dt = float(a.reshape(()))
        if "method" in params.attrs:
            raw = _utf8(params.attrs["method"])
            if not isinstance(raw, str):
                raise r.fail(f"attribute 'method' ({params.name}) = {shown(raw)} is not the name of an integration method")
            method = raw
        colliders = _read_colliders(path, params, d)

    r.check_memory(memory)

    # -- The data, and its values. ------------------------------------------------------------
    def three(a: np.ndarray) -> np.ndarray:
        return a if a.shape[-1] == 3 else np.concatenate([a, np.zeros(a.shape[:-1] + (3 - a.shape[-1],), dtype=a.dtype)], axis=-1)

    try:
        t = _to_si(_per_frame(t_ds, t_ds[()], frames, np.float64), units["times"])
        step = _per_frame(step_ds, step_ds[()], frames, np.int64)
    except TrajectoryFileError as e:
        raise r.fail(str(e)) from None
    r.finite("times", t_ds, t, ("frame",))
    back = np.flatnonzero(np.diff(t) <= 0)
    if back.size:
        k = int(back[0]) + 1
        raise r.fail(f"{_where('times', t_ds)} must increase: t[{k}] = {number(t[k])} after t[{k - 1}] = {number(t[k - 1])}")
    live = None if id_table is None else _Live(r, id_table, frames, n)
    x = _to_si(x_ds[()], units["positions"])
    r.finite("positions", x_ds, x if live is None else live.masked(x), ("frame", "particle"))
    velocities = None
    if vel is not None:
        v = _to_si(vel[0][()], units["velocities"])
        r.finite("velocities", vel[0], v if live is None else live.masked(v), ("frame", "particle"))
        velocities = three(v) if live is None else live.columns(three(v))
    positions = three(x) if live is None else live.columns(three(x))  # 2D: z = 0 where a particle exists
    out = LoadedTrajectory(t=t, positions=positions, velocities=velocities, step=step, dim=d, group=group, path=path)
    if live is not None:
        out.ids, out.alive = live.ids, live.alive
    for attr, (ds, element) in per_particle.items():
        if live is None:
            a = ds[0] if element else ds[()]
        else:  # each particle's value where it first exists
            a = live.first(ds[()], element)
        a = _to_si(a, units.get(attr, 1.0))
        r.finite(attr, ds, a, ("particle",))
        if attr == "masses" and np.any(a <= 0):
            i = int(np.argmax(a <= 0))
            raise r.fail(f"{_where(attr, ds)} has mass[{i}] = {number(a[i])} (masses must be finite and > 0 kg)")
        if attr == "radii" and np.any(a < 0):
            i = int(np.argmax(a < 0))
            raise r.fail(f"{_where(attr, ds)} has radius[{i}] = {number(a[i])} (radii must be finite and >= 0 m)")
        if attr == "species":  # names where the file gives them (kinema's ``names``), else none
            a = _species_names(r, p["species"], np.asarray(a))
        setattr(out, attr, a)
    if periodic is not None:
        edges = _box_edges(r, edges_ds, _to_si(np.asarray(edges_ds[()], dtype=np.float64), units["box edges"]), edges_by_frame, periodic)
        out.periodic = periodic
        out.box_edges_by_frame = np.ascontiguousarray(np.broadcast_to(np.pad(edges, [(0, 0), (0, 3 - d)]), (frames, 3)))
        out.box_edges = out.box_edges_by_frame[0].copy()
    # Observables are read as they are: a potential energy may be -inf (a particle exactly at
    # an unsoftened attractor point).
    for key, ds in observables.items():
        if ds is None:
            continue
        a = _to_si(ds[()], units.get(ds.name, 1.0))
        if isinstance(key, tuple):
            out.potential[key[1]] = a
        else:
            setattr(out, key, a)
    if out.total is None and out.kinetic is not None:
        out.total = out.kinetic + sum(out.potential.values(), np.zeros_like(out.kinetic))
    out.dt, out.method, out.colliders = dt, method, colliders
    out.springs = _read_springs(r, f, p, out.ids if out.ids is not None else np.arange(out.positions.shape[1]))
    author = f["h5md"].get("author")
    creator = f["h5md"].get("creator")
    out.author = None if author is None else _text(author.attrs.get("name", ""))
    if creator is not None:
        out.creator = f"{_text(creator.attrs.get('name', ''))} {_text(creator.attrs.get('version', ''))}".strip()
    return out


def load_h5md(path: str | os.PathLike, group: str | None = None) -> LoadedTrajectory:
    """Read the particle group ``group`` of the H5MD file ``path`` (``None``: the file's only
    group) with its observables; returns a :class:`LoadedTrajectory`, what the file holds
    (``kinema.Trajectory.load`` makes a ``kinema.Trajectory`` of it). Arrays of kinema's
    files come back exactly as written; 2D positions and velocities get z = 0.

    Files of other programs are read too. Each dataset's ``unit`` attribute (H5MD's units
    module) is converted to SI, the values multiplied by its exact factor (``parse_unit``:
    "Ang", "nm", "ps", "nm ps-1", "u", "kJ mol-1", ...; a dataset without one is taken as
    SI); a unit kinema does not know, or of the wrong kind, is an error. Velocities and
    observables may be absent (``None``; ``Trajectory.load`` makes them NaN, unknown). The box
    may be fixed (edges (D,)) or time-dependent (one row per frame, a box that may change:
    ``box_edges_by_frame``), edges or a (D, D) matrix of edge vectors along the axes. Step
    and time may be H5MD's fixed interval (a scalar with an ``offset``).

    A number of particles that varies (H5MD's time-dependent ``id`` with a fill value, as
    kinema writes births and deaths) is read by id, whatever slot a particle takes at each
    frame: one column per id that exists at some frame, ascending, ``alive`` (F, N) where it
    exists, NaN positions and velocities where not, and its mass, radius and species where
    it first exists. Only the entries that exist are checked (finite, an id once per frame).
    ``/connectivity/springs`` (ids, as kinema writes them) becomes ``springs``.

    What is read is checked first: the types and shapes of every dataset before any data
    is read (positions (F, N, 3) or (F, N, 2) with F, N > 0; velocities as positions; one
    time and one step per frame; masses, radii and ids (N,), or (frames, N) of which the
    first frame is read; observables and a time-dependent box one value or vector per frame;
    real numbers, integers for steps and ids; units), then the memory it needs against the
    memory available (``kinema.io._checks.available_memory``), then the values: finite
    positions, velocities and times, times that increase, masses > 0, radii >= 0, finite box
    edges, > 0 on periodic axes, at every frame, ``dt`` a positive number, ``method`` a name
    and each collider as ``World.add`` checks it. Observables are not checked for finite
    values (a potential energy may be -inf).

    Raises ``TrajectoryFileError`` (a ``ValueError``), one line naming the file, when it is
    missing, a directory, not HDF5 or corrupt, an HDF5 file without /h5md and /particles, of
    another major H5MD version, lacks ``group`` (the message lists the groups there), or when
    a check fails: the message names the dataset (its meaning and its path in the file) or
    attribute and the bad value, e.g. ``run.h5: dataset 'positions'
    (/particles/all/position/value) has a non-finite value (nan) at frame 3, particle 7``
    or ``md.h5: dataset 'velocities' (/particles/atoms/velocity/value) has unit 'furlong
    fortnight-1', which kinema cannot read: 'furlong' is not a unit symbol kinema knows``."""
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
            return _read(path, f, group, available_memory())
    except TrajectoryFileError:
        raise
    except MemoryError:
        raise _fail(path, "not enough memory to load it") from None
    except (OSError, KeyError, RuntimeError) as e:
        # h5py reports a damaged file as OSError/KeyError/RuntimeError with a multi-line text.
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise _fail(path, f"corrupt HDF5 file ({first})") from None
