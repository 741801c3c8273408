"""H5MD 1.1 trajectory files (HDF5 through h5py): writing a trajectory and reading it back,
and reading the H5MD files of other programs.

Layout written by `save_h5md` (`(F)` frames, `N` particles; every time-dependent
element shares one `step` and one `time` dataset through HDF5 hard links, as the
specification allows, and requires for the box; units shown for `units="SI"`, the default):

    /h5md                 +-- version = [1, 1]
        author            +-- name                      (fixed-length string)
        creator           +-- name = "kinema", version  (fixed-length strings)
        modules/units     +-- version = [1, 0], system = "SI"
    /particles/<group>
        box               +-- dimension = 3, boundary = ["none" | "periodic"] * 3 (fixed-length)
            edges         step, time, value (F, 3) [m]: the periodic cell, 0 along open axes
            pbc           step, time, value (F, 3) bool: the boundary again, for znh5md
        position          step int64 (F,), time float64 (F,) [s], value (F, N, 3) [m]
        velocity          step, time, value (F, N, 3) [m s-1]
        species           step, time, value (F, N) int32: the atomic number of each particle's
                          species name where it is a chemical symbol ("He": 2), else 0
        species_index     step, time, value (F, N) int32: each particle's index among the
                          sorted species names, attribute names (when the trajectory has species)
        mass [kg], radius [m], id      step, time, value (F, N), when known (id: always)
        color             step, time, value (F, N, 3) float64: r, g, b in [0, 1], NaN: none
                          (when the trajectory has colours)
        collision_group   step, time, value (F, N) int32: each particle's collision group, 0..31
                          (World.groups; when the trajectory has groups; kinema's name)
        angular_velocity  step, time, value (F, N, 3) [s-1]: each particle's ω, rad/s (a world with
                          spin; H5MD has no element for it: kinema's name)
        moment_of_inertia step, time, value (F, N) [kg m2]: about the centre (with spin; kinema's name)
        orientation       step, time, value (F, N, 4): each particle's orientation, a unit
                          quaternion w, x, y, z turning its body frame into the world's (with spin,
                          where the engine integrates it; kinema's name)
    /contacts             the contacts of each frame (World.run(record_contacts=True)), an extension
                          group of kinema's; attribute particles_group: a reference to the group
        step, time        the clock of position (hard links)
        offsets           (F + 1,) int64: frame k's contacts are rows offsets[k] to offsets[k + 1]
        i, j, collider    (K,) int64: the particle's id, the other particle's id (-1: a collider),
                          the collider's index in /parameters/kinema/colliders (-1: a particle)
        point [m], normal (K, 3); overlap [m], u_n [m s-1] (K,); force_n, force_t (K, 3) [N];
        sliding (K,) bool; impulse_n, impulse_t (K, 3) [kg m s-1]: those the world gave
                          (kinema.contact_record.FIELDS says what each is)
    /connectivity/springs (S, 2) int64: the ids at the ends of each spring, when the trajectory
                          has springs; attribute particles_group: a reference to the group
    /observables
        kinetic_energy, potential_energy, total_energy    step, time, value (F,) [J]
        potential_energy_by_force/<force name>             step, time, value (F,) [J]
        momentum (F, 3) [kg m s-1], angular_momentum (F, 3) [kg m2 s-1]
        contacts (F,), impulse_balance (F, 3) [kg m s-1], collision_energy_lost (F,) [J]
        collider_momentum, collider_normal, collider_tangential    step, time, value (F, K, 3)
                          [kg m s-1]: what the particles had given each of the world's K
                          colliders by each frame (World.collider_books; row k: colliders/k
                          below), kinema's names
    /parameters/kinema    +-- dim = 2 | 3, dt [s], method, fps [s-1]   (each but dim when known;
                              fps: the frames per second asked of World.run, a video's rate)
        colliders/<k>     +-- type = "plane" | "box" | "sphere" | "mesh", its geometry [m]
                              (point, normal | lo, hi | center, radius | inside), restitution,
                              friction when set; k = 0, 1, ... in the world's order
            vertices, faces   a mesh's vertices (V, 3) float64 [m] and triangles (F, 3) int64
                              (datasets: an attribute holds at most 64 KiB)
            motion        +-- a moving collider's motion (its geometry above is the placement
                              as added): steady, attributes velocity [m s-1],
                              angular_velocity [s-1, rad], pivot [m], and start [s] when
                              it does not start at 0; or keyframes, attribute
                              pivot [m] and datasets times (K,) [s], translations (K, 3) [m],
                              rotations (K, 4) unit quaternions w, x, y, z

A 2D world is written 3D, z = 0 and its box open along z, so that 3D readers (MDAnalysis,
znh5md) read it; `/parameters/kinema` `dim = 2` makes it 2D again for kinema, which
also reads the (F, N, 2) files of 2D worlds it wrote before.

Units follow the H5MD units module: a `unit` attribute (a variable-length ASCII string:
MDAnalysis reads no other) on each `value` (and `time`) dataset, written as
space-separated factors with integer powers; `units="MD"` writes nm, ps, nm ps-1, u and
kJ mol-1 instead of m, s, m s-1, kg and J (`/parameters/kinema` stays SI). The per-particle
elements (species, mass, radius, id, color, collision_group) and the box are time-dependent, constant over the
frames, because znh5md (ASE's H5MD reader) reads only that form; MDAnalysis's reader and
pyh5md read them too.

Births and deaths (`Trajectory.alive` not all True) are written as H5MD 1.1 provides for a
number of particles that varies: the arrays keep N columns, one per particle that exists at
some frame, and the `id` element's value dataset gets a fill value (-1, or one less than
the least id), which it holds where that particle does not exist; there `position`,
`velocity`, `mass`, `radius` and `color` hold their datasets' fill value, NaN, and
`species`, `species_index` and `collision_group` -1. Without births and deaths no fill value is set and the
layout is as above.

`load_h5md` converts the units of what it reads to SI (`parse_unit`: "nm", "Ang",
"ps", "nm ps-1", "u", "kJ mol-1", ...), accepts files without velocities or observables and
reads a box that changes from frame to frame.

This module writes (`save_h5md`) and opens a file to read (`load_h5md`); the reading
itself is `kinema.io.h5md_reader` (with the checks of `kinema.io._h5md_checks`), the
units `kinema.io.h5md_units`, what both sides share `kinema.io._h5md_layout`, the checks
before writing (what would not read back) `kinema.io._h5md_write_checks`.
"""

from __future__ import annotations

import getpass
import os
from pathlib import Path
from typing import Any

import numpy as np

from ..contact_record import FIELDS
from ._cell import particle_types
from ._checks import available_memory
from ._files import TrajectoryFileError, frames_of, hdf5_file, os_errors_as_write_errors
from ._h5md_checks import fail, links_out
from ._h5md_colliders import MESH_DATASETS, MOTION_DATASETS
from ._h5md_layout import BY_FORCE, COLLIDER_OBSERVABLES, ELEMENTS, H5MD_VERSION, OBSERVABLES, PRESSURE_UNIT, import_h5py
from ._h5md_write_checks import _check_writable, _colliders_of
from ._hdf5_heaps import global_heap_problem
from .h5md_reader import LoadedTrajectory, read
from .h5md_units import from_si, parse_unit, system_of

__all__ = ["H5MD_VERSION", "LoadedTrajectory", "load_h5md", "parse_unit", "save_h5md"]


def _chunks(shape: tuple[int, ...]) -> tuple[int, ...] | None:
    """About 1 MiB of float64 per chunk, whole frames along the first axis; `None`
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
    """The H5MD units module's `unit` attribute: a variable-length ASCII string."""
    if unit is not None:
        ds.attrs.create("unit", unit, dtype=import_h5py().string_dtype("ascii"))


def _fixed_string(obj: Any, name: str, value: str | list[str]) -> None:
    """A string attribute of H5MD's fixed-length string type (`author`, `creator`,
    `boundary`): ASCII when it is, else UTF-8, as long as its longest value (at least 1)."""
    values = [value] if isinstance(value, str) else list(value)
    encoded = [v.encode("utf-8") for v in values]
    length = max([1, *(len(b) for b in encoded)])
    dtype = import_h5py().string_dtype("ascii" if all(b.isascii() for b in encoded) else "utf-8", length)
    data = np.array(encoded, dtype=f"S{length}")
    obj.attrs.create(name, data[0] if isinstance(value, str) else data, dtype=dtype)


def _dataset(group: Any, name: str, data: np.ndarray, unit: str | None, compression: str | None, time_series: bool = False, fill: Any = None) -> Any:
    """A dataset of `data`; `fill`, when given, is its HDF5 fill value (H5MD's mark of an
    entry of a particle that does not exist)."""
    options = _storage(data.shape, compression, time_series)
    if fill is not None:
        options["fillvalue"] = fill
    ds = group.create_dataset(name, data=data, **options)
    _set_unit(ds, unit)
    return ds


def _element(parent: Any, name: str, value: np.ndarray, unit: str | None, clock: Any, compression: str | None, fill: Any = None) -> Any:
    """A time-dependent H5MD element: a group with `step` and `time` (hard links to the
    shared clock datasets) and `value` (of fill value `fill` when given)."""
    g = parent.create_group(name)
    g["step"] = clock["step"]
    g["time"] = clock["time"]
    _dataset(g, "value", value, unit, compression, time_series=True, fill=fill)
    return g


def _constant_element(
    parent: Any, name: str, row: np.ndarray, unit: str | None, clock: Any, compression: str | None, alive: np.ndarray | None = None, fill: Any = None
) -> Any:
    """A time-dependent H5MD element whose value is `row` at every frame, written chunk by
    chunk (the (F, ...) array is never made whole). With `alive` (F, N), the entries of the
    particles not alive hold `fill`, the dataset's fill value (all of a particle's row (N,
    3) of colours)."""
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
        here = None if alive is None else alive[i : i + slab].reshape(alive[i : i + slab].shape + (1,) * (row.ndim - 1))
        ds[i : i + slab] = rows if here is None else np.where(here, rows, np.asarray(fill, dtype=row.dtype))
    _set_unit(ds, unit)
    return g


def _unknown(a: Any) -> bool:
    """All NaN (and not empty): values a loaded trajectory did not have (velocities or
    energies of a file without them), which are not written."""
    a = np.asarray(a)
    return a.size > 0 and a.dtype.kind == "f" and bool(np.isnan(a).all())


def _write(f: Any, tr: Any, fr: Any, group: str, author: str, compression: str | None, system: dict[str, str]) -> None:
    """The trajectory `tr` (its checked frames `fr`) written into the open file `f` in the
    unit `system`, part by part: the /h5md header, the particle group (box, clock, positions,
    velocities, spins, per-particle elements), the observables, the contacts, the springs and
    kinema's parameters (the layout of the module doc)."""

    def unit(a: Any, si: str | None) -> tuple[np.ndarray, str | None]:
        """`a` (in the SI unit `si`, or a plain number when `None`) as written: in the
        file's unit system, with that system's unit."""
        if si is None:
            return np.asarray(a), None
        return from_si(a, system[si]), system[si]

    _write_header(f, author)
    particles, clock = _write_particles(f, tr, fr, group, compression, unit)
    _write_observables(f.create_group("observables"), tr, fr, clock, compression, unit)

    record = getattr(tr, "contact_record", None)
    if record is not None:
        _write_contacts(f.create_group("contacts"), record, particles, clock, unit, compression)

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

    _write_parameters(f, tr, fr, compression)


def _write_header(f: Any, author: str) -> None:
    """/h5md: the version, the author, the creator (kinema and its version), the units module."""
    from .. import __version__

    h5py = import_h5py()
    h5md = f.create_group("h5md")
    h5md.attrs.create("version", np.array(H5MD_VERSION, dtype=np.int32))
    _fixed_string(h5md.create_group("author"), "name", author)
    creator = h5md.create_group("creator")
    _fixed_string(creator, "name", "kinema")
    _fixed_string(creator, "version", str(__version__))
    units = h5md.create_group("modules").create_group("units")
    units.attrs.create("version", np.array([1, 0], dtype=np.int32))
    units.attrs.create("system", "SI", dtype=h5py.string_dtype("ascii"))


def _write_particles(f: Any, tr: Any, fr: Any, group: str, compression: str | None, unit: Any) -> tuple[Any, Any]:
    """/particles/<group>: the box, the clock every time-dependent element shares (with the
    positions), the velocities, the spins and the per-particle elements; returns the group
    and the clock (its position element)."""
    # Every file is 3D: a 2D world's positions and velocities get z = 0 and its box an open z
    # axis, so that 3D readers (MDAnalysis, znh5md) read it; /parameters/kinema says dim = 2.
    d = fr.dim
    particles = f.create_group("particles").create_group(group)
    box = particles.create_group("box")
    box.attrs.create("dimension", np.int32(3))
    periodic = getattr(tr, "periodic", None)
    flags = [False] * d if periodic is None else [bool(p) for p in np.asarray(periodic).reshape(-1)[:d]]
    flags += [False] * (3 - d)
    _fixed_string(box, "boundary", ["periodic" if p else "none" for p in flags])
    edges = getattr(tr, "box_edges", None)
    if any(flags) and edges is None:
        raise ValueError("periodic boundaries need the box edges: the trajectory has no box_edges")
    edges = np.zeros(d) if edges is None else np.asarray(edges, dtype=np.float64).reshape(-1)[:d]
    if edges.size != d:
        raise ValueError(f"box_edges has {edges.size} values; it must have one per axis, {d}")
    edges = np.pad(edges, (0, 3 - d))

    # The clock shared by every time-dependent element: the integration step of each frame
    # (t / dt rounded, or the frame index when dt is unknown) and the time.
    clock = particles.create_group("position")
    step = np.arange(fr.n_frames, dtype=np.int64) if not fr.dt else np.rint(fr.t / fr.dt).astype(np.int64)
    _dataset(clock, "step", step, None, compression, time_series=True)
    _dataset(clock, "time", *unit(fr.t, "s"), compression, time_series=True)
    # Births and deaths (H5MD's varying number of particles): the arrays keep one column per
    # particle; at a frame where it does not exist, its id is the id dataset's fill value and
    # its other entries the fill values of theirs (NaN; species and collision_group -1).
    changes = fr.changes_count
    nan = np.nan if changes else None

    def placed(a: np.ndarray) -> np.ndarray:  # z = 0 in 2D; NaN where a particle does not exist
        if d == 2:
            a = np.concatenate([a[..., :2], np.zeros(a.shape[:-1] + (1,))], axis=-1)
        return a if not changes else np.where(fr.alive[..., None], a, np.nan)

    _dataset(clock, "value", *unit(placed(fr.positions), "m"), compression, time_series=True, fill=nan)
    # The box, time-dependent as the readers want it (znh5md and MDAnalysis read edges/value
    # only), its step and time those of position as the specification requires. znh5md reads
    # a fixed-length boundary as all periodic (it compares bytes with "none"): pbc tells it.
    _constant_element(box, "edges", *unit(edges, "m"), clock, compression)
    _constant_element(box, "pbc", np.array(flags, dtype=bool), None, clock, compression)
    if not _unknown(fr.velocities[fr.alive]):
        _element(particles, "velocity", *unit(placed(fr.velocities), "m s-1"), clock, compression, fill=nan)
    # Spin: H5MD has no element for it; kinema's names beside position and velocity, the
    # same form (a 2D world turns about z: ω's x and y are 0, kept as they are)
    for name, a, si in (("angular_velocity", fr.angular_velocities, "s-1"), ("orientation", fr.orientations, None)):
        if a is not None and not _unknown(a[fr.alive]):
            _element(particles, name, *unit(a if not changes else np.where(fr.alive[..., None], a, np.nan), si), clock, compression, fill=nan)
    _write_per_particle(particles, tr, fr, clock, compression, unit)
    return particles, clock


def _write_per_particle(particles: Any, tr: Any, fr: Any, clock: Any, compression: str | None, unit: Any) -> None:
    """Each particle's species, mass, radius, moment of inertia, id, colour and collision
    group (those the trajectory has), as time-dependent elements of one value per frame."""
    alive = fr.alive if fr.changes_count else None
    # Species: H5MD's integers, for ASE (znh5md) the atomic number of a name that is a chemical
    # symbol, else 0 (ASE's "X"); kinema's names in species_index, each particle's index among
    # the sorted names (two names that are no element would share 0).
    names, index = particle_types(tr, fr.n_particles)
    named = getattr(tr, "species", None) is not None
    numbers = np.array([ELEMENTS.index(n) if named and n in ELEMENTS else 0 for n in names], dtype=np.int32)
    no_id = min(-1, int(fr.ids.min()) - 1) if fr.ids.size else -1  # the id of no particle: -1 unless an id is negative
    colors = getattr(tr, "colors", None)
    per_particle = (
        ("species", numbers[index], None, -1),
        ("species_index", index.astype(np.int32) if named else None, None, -1),
        ("mass", fr.masses, "kg", np.nan),
        ("radius", fr.radii, "m", np.nan),
        ("moment_of_inertia", fr.inertia, "kg m2", np.nan),
        ("id", fr.ids, None, no_id),
        ("color", None if colors is None else np.asarray(colors, dtype=np.float64), None, np.nan),
        ("collision_group", None if fr.groups is None else fr.groups.astype(np.int32), None, -1),
    )
    for name, a, si, fill in per_particle:
        if a is not None:
            element = _constant_element(particles, name, *unit(a, si), clock, compression, alive, fill)
            if name == "species_index":
                _fixed_string(element, "names", names)  # species_index k is names[k]


def _write_observables(obs: Any, tr: Any, fr: Any, clock: Any, compression: str | None, unit: Any) -> None:
    """/observables: the energies, momenta and impulse balance, the pressure tensor, the
    collider books, the potential energy of each force and the total energy."""
    d = fr.dim
    string = import_h5py().string_dtype()
    kinetic = getattr(tr, "kinetic", None)
    potential = dict(getattr(tr, "potential", None) or {})
    for name, (attr, si) in OBSERVABLES.items():
        a = getattr(tr, attr, None)
        if a is not None and not _unknown(a):
            _element(obs, name, *unit(a, si), clock, compression)
    pressure = getattr(tr, "pressure", None)
    if pressure is not None and not _unknown(pressure):  # (F, 3, 3), NaN at frame 0
        _element(obs, "pressure", *unit(np.asarray(pressure, dtype=np.float64), PRESSURE_UNIT[d]), clock, compression)
    for name, (attr, si) in COLLIDER_OBSERVABLES.items():  # (F, K, 3), a row per collider
        a = getattr(tr, attr, None)
        if a is not None:
            _element(obs, name, *unit(np.asarray(a, dtype=np.float64), si), clock, compression)
    if potential:
        by_force = obs.create_group(BY_FORCE, track_order=True)
        by_force.attrs.create("names", list(potential), dtype=string)
        for name, u in potential.items():
            if "/" in name or name in ("", ".", ".."):
                raise ValueError(f"force name {name!r} cannot name an HDF5 group")
            _element(by_force, name, *unit(np.asarray(u, dtype=np.float64), "J"), clock, compression)
        _element(obs, "potential_energy", *unit(sum(np.asarray(u, dtype=np.float64) for u in potential.values()), "J"), clock, compression)
    total = getattr(tr, "total", None)
    if total is None and kinetic is not None:
        total = np.asarray(kinetic) + sum((np.asarray(u) for u in potential.values()), np.zeros(fr.n_frames))
    if total is not None and not _unknown(total):
        _element(obs, "total_energy", *unit(np.asarray(total, dtype=np.float64), "J"), clock, compression)


def _write_parameters(f: Any, tr: Any, fr: Any, compression: str | None) -> None:
    """kinema's own parameters, in SI whatever the units of the rest: the world's dimension (a
    2D world's file is 3D with z = 0), dt, the method, the frames per second and the colliders."""
    colliders = _colliders_of(tr)
    params = f.create_group("parameters").create_group("kinema")
    params.attrs["dim"] = np.int32(fr.dim)
    if fr.dt is not None:
        params.attrs["dt"] = fr.dt
        params.attrs["dt_unit"] = "s"
    if fr.method is not None:
        params.attrs["method"] = fr.method
    fps = getattr(tr, "fps", None)
    if fps is not None:  # the frames per second asked of World.run: a video's default rate
        params.attrs["fps"] = float(fps)
        params.attrs["fps_unit"] = "s-1"
    if colliders:
        # One group per collider, named by its index; the values are attributes (H5MD
        # leaves /parameters to the program), lengths in m, ±inf for an open box face.
        group_of = params.create_group("colliders", track_order=True)
        # A mesh's vertices and faces are datasets (a 20,000-triangle mesh is 480 kB of
        # faces; an attribute holds 64 KiB) and its inside flag a bool.
        for k, c in enumerate(colliders):
            g = group_of.create_group(str(k), track_order=True)
            g.attrs["type"] = c["type"]
            for name, value in c.items():
                if name == "type":
                    continue
                if name in MESH_DATASETS:
                    g.create_dataset(name, data=np.asarray(value, dtype=MESH_DATASETS[name]).reshape(-1, 3), compression=compression)
                elif name == "motion":
                    _write_motion(g.create_group("motion", track_order=True), value)
                elif name == "inside":
                    g.attrs.create(name, np.bool_(value))
                else:
                    g.attrs.create(name, np.asarray(value, dtype=np.float64))


def _write_contacts(g: Any, record: Any, particles: Any, clock: Any, unit: Any, compression: str | None) -> None:
    """The contacts of each frame (a `kinema.contact_record.ContactRecord`) in the group
    `/contacts`, an extension of H5MD (see the module doc): the clock's `step` and `time`
    (hard links), `offsets` (F + 1,) and one dataset per column, in the file's units;
    `particles_group` refers to the particle group whose ids `i` and `j` are."""
    g.attrs["particles_group"] = particles.ref
    g["step"] = clock["step"]
    g["time"] = clock["time"]
    _dataset(g, "offsets", record.offsets, None, compression)
    for name, a in record.values.items():
        known = FIELDS.get(name)
        _dataset(g, name, *unit(a, None if known is None else known.unit), compression)


def _write_motion(g: Any, motion: dict[str, Any]) -> None:
    """A collider's motion description into its group `g`: the 3-vectors (velocity,
    angular_velocity, pivot) as attributes, the keyframes' arrays (times, translations,
    rotations: as many rows as keys) as datasets, in SI."""
    for key, value in motion.items():
        if key in MOTION_DATASETS:
            g.create_dataset(key, data=np.asarray(value, dtype=np.float64))
        else:
            g.attrs.create(key, np.asarray(value, dtype=np.float64))


def save_h5md(traj: Any, path: str | os.PathLike, group: str = "all", author: str | None = None, compression: str | None = "gzip", units: str = "SI") -> Path:
    """Write `traj` to the H5MD 1.1 file `path` (see the module doc for the layout) and
    return the path.

    `traj` is a `kinema.Trajectory` or any object with its attributes: `t` (F,) s,
    `positions` and `velocities` (F, N, 3) m and m/s, `kinetic` (F,) J, `potential`
    {name: (F,)} J, `momentum` (F, 3) kg m/s, `angular_momentum` (F, 3) kg m²/s and,
    when present, `total` (F,) J, `contacts` (F,), `impulse_balance` (F, 3) N s,
    `collision_energy_lost` (F,) J, `masses` (N,) kg, `radii` (N,) m, `ids` (N,),
    `dim` (2: stored 3D with z = 0, `dim` in /parameters/kinema), `dt` s, `method`,
    `periodic` (D bools) with `box_edges` (D,) m, `species` (N,) names (the
    `species` element: the atomic number of a name that is a chemical symbol, else 0, and
    `species_index`: the index of each particle's name among the sorted names, which its
    `names` attribute holds; all 0 and no `species_index` without `species`),
    `colors` (N, 3) r, g, b in [0, 1], NaN: none (the `color` element), `groups` (N,)
    ints in 0..31, each particle's collision group (the `collision_group` element),
    `colliders` (`Trajectory.colliders`' descriptions or `kinema` collider objects),
    `alive` (F, N) bool, which particles exist at each frame (births and deaths: written
    with H5MD's fill values, see the module doc), `springs` (S, 2) the ids at the ends of
    each spring (`/connectivity/springs`), `angular_velocities` (F, N, 3) rad/s and
    `orientations` (F, N, 4) and `inertia` (N,) kg m² of a world with spin (the
    `angular_velocity`, `orientation` and `moment_of_inertia` elements), `contact_record` (a `kinema.contact_record.ContactRecord`:
    the group `/contacts`), `collider_momentum`, `collider_normal` and `collider_tangential`
    (F, K, 3) N s, what the particles had given each collider (observables of those names). Velocities and observables that are all NaN (unknown: a trajectory loaded from a file
    without them) are not written.

    `group` names the particle group (/particles/<group>); `author` the /h5md/author name
    (default: the login name); `compression` "gzip", "lzf" or None for the chunked
    datasets; `units` the unit system of the values: "SI" (m, s, kg, J), read back
    exactly, or "MD" (nm, ps, u, kJ mol-1: GROMACS's, which MDAnalysis reads), each value the
    float64 nearest its exact conversion where the factor or its inverse is a float64 (nm,
    ps, nm ps-1), else within one rounding more (u, kJ mol-1), read back within one ulp.
    `/parameters/kinema` (dt, the colliders) stays in SI. The file is written under a
    temporary name in the same folder and renamed at the end, so a failed write leaves
    `path` as it was.

    What is written is checked first, by the rules `load_h5md` reads it with, so that every
    file kinema writes reads back: finite times that increase, finite positions and
    velocities (velocities all NaN, unknown, are left out), masses finite and > 0 kg, radii
    finite, >= 0 m and at most 1e150 m, printable species names, colours in [0, 1] or NaN,
    box edges finite and > 0 m on periodic axes, ids once per frame, `dt` > 0, observables
    one value per frame, the colliders as the engine checks them; with `units="MD"` values
    that float64 holds in those units (1e300 m is 1e309 nm) and times that stay apart. A value that breaks them is refused before
    anything is written (a `TrajectoryFileError`, one line: `cannot write run.h5:
    trajectory 'masses' has mass[2] = -1 (masses must be finite and > 0 kg)`).

    Raises `TrajectoryFileError` when `path` cannot be written or the values would not
    read back, `FileWriteError` (an `OSError`) when the system fails the write or refuses
    the name (a name too long), and `ValueError` for a malformed trajectory."""
    import_h5py()  # the ImportError that says how to get it, before any work
    if not group or "/" in group or group in (".", ".."):
        raise ValueError(f"group = {group!r} is invalid: it must be a non-empty name without '/'")
    system = system_of(units)
    fr = frames_of(traj)
    if author is None:
        try:
            author = getpass.getuser()
        except Exception:
            author = "unknown"
    path = Path(path)
    _check_writable(path, traj, fr, system)
    with os_errors_as_write_errors(path), hdf5_file(path, libver=("earliest", "latest"), track_order=True) as f:
        _write(f, traj, fr, group, author, compression, system)
    return path


def load_h5md(path: str | os.PathLike, group: str | None = None, follow_links: bool = False) -> LoadedTrajectory:
    """Read the particle group `group` of the H5MD file `path` (`None`: the file's only
    group) with its observables; returns a `LoadedTrajectory`, what the file holds
    (`kinema.Trajectory.load` makes a `kinema.Trajectory` of it). Arrays of kinema's
    files come back exactly as written (within one ulp from `units="MD"`); a 2D world's
    file (`dim = 2` in /parameters/kinema, or (F, N, 2) positions) gives `dim` 2, z = 0.

    Files of other programs are read too. Each dataset's `unit` attribute (H5MD's units
    module) is converted to SI by its exact factor (`parse_unit`: "Ang", "nm", "ps",
    "nm ps-1", "u", "kJ mol-1", ...; `h5md_units.to_si`); a unit kinema does not know, or of
    the wrong kind, is an error. A dataset without one is SI in kinema's files; in others it
    is taken as `h5md_units.assumed_unit` says (ASE's units in znh5md's files: its masses in
    u, else SI), with a `kinema.io.UnitWarning` naming the file, the dataset and the unit
    taken. Velocities and
    observables may be absent (`None`; `Trajectory.load` makes them NaN, unknown). The box
    may be fixed (edges (D,)) or time-dependent (one row per frame, a box that may change:
    `box_edges_by_frame`), edges or a (D, D) matrix of edge vectors along the axes. Step
    and time may be H5MD's fixed interval (a scalar with an `offset`).

    A number of particles that varies (H5MD's time-dependent `id` with a fill value, as
    kinema writes births and deaths) is read by id, whatever slot a particle takes at each
    frame: one column per id that exists at some frame, ascending, `alive` (F, N) where it
    exists, NaN positions and velocities where not, and its mass, radius and species where
    it first exists. Only the entries that exist are checked (finite, an id once per frame).
    `/connectivity/springs` (ids, as kinema writes them) becomes `springs`.

    What is read is checked first: the types and shapes of every dataset before any data
    is read (positions (F, N, 3) or (F, N, 2) with F, N > 0; velocities as positions; one
    time and one step per frame; masses, radii and ids (N,), or (frames, N) of which the
    first frame is read; observables and a time-dependent box one value or vector per frame;
    real numbers, integers for steps and ids; units), then the memory it needs against the
    memory available (`kinema.io._checks.available_memory`), then the values: finite
    positions, velocities and times, times that increase, masses > 0, radii >= 0 and at most
    1e150 m (the engine's limit), species names of printable text (no NUL or control
    characters), colours in [0, 1] or NaN, z = 0 in a file of a 2D world, a box `boundary` of "periodic" or "none" on each axis and edges along the
    axes (a matrix of edge vectors must be diagonal, with open boundaries too), finite box
    edges, > 0 on periodic axes, at every frame, `dt` a positive number, `method` a name
    and each collider as `World.add` checks it. Observables are not checked for finite
    values (a potential energy may be -inf).

    The file is read alone: a file with an external link (`h5py.ExternalLink`), a virtual
    dataset with a source in another file (`h5py.VirtualLayout`) or a dataset stored in
    external files is refused before anything is read, since reading it would read other
    files, perhaps outside its folder (soft links stay inside the file and are followed).
    `follow_links=True` reads such a file, following its links (HDF5 looks for a relative
    name from the folder of the file, then from the working directory). The `path` itself
    may be a symbolic link: the caller named it.

    Raises `TrajectoryFileError` (a `ValueError`), one line naming the file, when it is
    missing, a directory, not HDF5 or corrupt, its name cannot be used (too long), it has
    links to other files (without `follow_links`), an HDF5 file without /h5md and /particles, of
    another major H5MD version, lacks `group` (the message lists the groups there), or when
    a check fails: the message names the dataset (its meaning and its path in the file) or
    attribute and the bad value, e.g. `run.h5: dataset 'positions'
    (/particles/all/position/value) has a non-finite value (nan) at frame 3, particle 7`
    or `md.h5: dataset 'velocities' (/particles/atoms/velocity/value) has unit 'furlong
    fortnight-1', which kinema cannot read: 'furlong' is not a unit symbol kinema knows`."""
    h5py = import_h5py()
    path = Path(path)
    try:
        if not path.exists():
            raise fail(path, "no such file")
        if path.is_dir():
            raise fail(path, "is a directory, not an H5MD file")
        is_hdf5 = h5py.is_hdf5(path)
    except OSError as e:  # a name too long, a loop of links, a folder not searchable
        raise fail(path, f"cannot be read ({e.strerror or e})") from None
    if not is_hdf5:
        raise fail(path, "not an HDF5 file (corrupt, or another format)")
    heaps = global_heap_problem(path)
    if heaps is not None:
        raise fail(path, f"corrupt HDF5 file: {heaps}")
    try:
        with h5py.File(path, "r") as f:
            if not follow_links:
                out = links_out(f)
                if out is not None:
                    raise fail(path, f"{out}; kinema reads a file alone (load it with follow_links=True to read the other file)")
            return read(path, f, group, available_memory())
    except TrajectoryFileError:
        raise
    except MemoryError:
        raise fail(path, "not enough memory to load it") from None
    except (OSError, KeyError, RuntimeError) as e:
        # h5py reports a damaged file as OSError/KeyError/RuntimeError with a multi-line text.
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise fail(path, f"corrupt HDF5 file ({first})") from None
