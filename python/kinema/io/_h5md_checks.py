"""Checked reads of an H5MD file's elements (for `kinema.io.h5md_reader`): `Reader`
checks the type, shape and unit of each dataset and adds up the memory the reads need before
any data is read, then that the values read are finite; the datasets of a time-dependent
element, its step and time made one per frame; and `Live`, the particles of a file whose
number varies (H5MD's time-dependent `id` with a fill value). Errors are
`TrajectoryFileError`, one line naming the file, the dataset (by meaning and by path) and the
value.

The rules on values (`mass_problem`, `radius_problem`, `species_problem`,
`color_problem`, `boundary_problem`, `non_finite`, `increase_problem`) are shared
with the writers:
`check_frames` refuses, before anything is written, a trajectory that these rules would
refuse when it is read back (`save_h5md`, `export`); `links_out` finds what in a file
points out of it (external links, virtual datasets of other files, external storage)."""

from __future__ import annotations

import warnings
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from ._checks import dtype_problem, first_non_finite, gib, number, shown
from ._files import Frames, TrajectoryFileError
from ._h5md_layout import import_h5py
from .h5md_units import QUANTITY, assumed_unit, parse_unit
from .units import UnitWarning

#: The largest radius read or written, m: the engine's own limit (``GEOMETRY_LIMIT``:
#: collisions square distances), which the particles of a scene meet when it is built.
MAX_RADIUS = 1e150
#: The values of an H5MD box's ``boundary`` attribute kinema reads (its box is axis-aligned,
#: periodic or open along each axis).
BOUNDARIES = ("periodic", "none")
#: The largest magnitude a float32 holds (PLY, GSD and USD store particle data as float32).
FLOAT32_MAX = float(np.finfo(np.float32).max)


def non_finite(a: np.ndarray, axes: tuple[str, ...]) -> str | None:
    """`"has a non-finite value (nan) at frame 3, particle 7"` for the first NaN or ±inf in
    `a` (`axes` name its leading indices), `None` when all are finite."""
    at = first_non_finite(a)
    if at is None:
        return None
    place = ", ".join(f"{name} {i}" for name, i in zip(axes, at, strict=False))
    return f"has a non-finite value ({number(a[at])})" + (f" at {place}" if place else "")


def increase_problem(t: np.ndarray) -> str | None:
    """`"must increase: t[4] = 0.2 after t[3] = 0.3"` where the times `t` do not increase
    strictly, else `None`."""
    back = np.flatnonzero(np.diff(t) <= 0)
    if not back.size:
        return None
    k = int(back[0]) + 1
    return f"must increase: t[{k}] = {number(t[k])} after t[{k - 1}] = {number(t[k - 1])}"


def mass_problem(a: np.ndarray) -> str | None:
    """`"has mass[2] = -1 (masses must be finite and > 0 kg)"` for the first mass that is not
    finite and > 0, else `None`."""
    bad = ~(np.isfinite(a) & (a > 0))
    if not bad.any():
        return None
    i = int(np.argmax(bad))
    return f"has mass[{i}] = {number(a[i])} (masses must be finite and > 0 kg)"


def radius_problem(a: np.ndarray) -> str | None:
    """`"has radius[1] = -0.5 (radii must be finite and >= 0 m)"` for the first radius that
    is not finite, >= 0 m and at most `MAX_RADIUS`, else `None`."""
    bad = ~(np.isfinite(a) & (a >= 0))
    if bad.any():
        i = int(np.argmax(bad))
        return f"has radius[{i}] = {number(a[i])} (radii must be finite and >= 0 m)"
    big = a > MAX_RADIUS
    if big.any():
        i = int(np.argmax(big))
        return f"has radius[{i}] = {number(a[i])} (radii must be at most {MAX_RADIUS:g} m, kinema's limit: collisions square distances)"
    return None


def species_problem(names: Any, label: str = "species") -> str | None:
    """`"has species[3] = 'a\\x00b' (species names must be non-empty printable text: ...)"`
    for the first of `names` that is not a non-empty printable string (no NUL, no control
    characters), else `None`; `label` names the list in the message."""
    for k, name in enumerate(names):
        if not isinstance(name, str) or not name or not name.isprintable():
            return f"has {label}[{k}] = {shown(name)} (species names must be non-empty printable text: no NUL or control characters)"
    return None


def color_problem(a: np.ndarray) -> str | None:
    """`"has color[2] = [0.5, 1.5, 0] (colours are r, g, b in [0, 1], or NaN: none)"` for the
    first colour (a row of `a` (N, 3)) with a value neither NaN nor in [0, 1], else `None`."""
    bad = ~(np.isnan(a) | ((a >= 0) & (a <= 1)))
    if not bad.any():
        return None
    i = int(np.argmax(bad.any(axis=1)))
    return f"has color[{i}] = [{', '.join(number(v) for v in a[i])}] (colours are r, g, b in [0, 1], or NaN: none)"


#: Collision groups: an integer in 0..GROUPS - 1 (a bit of the engine's 32-bit masks, `World.groups`).
GROUPS = 32


def group_problem(a: np.ndarray) -> str | None:
    """`"has group[2] = 40 (collision groups are integers in 0..31)"` for the first of `a`
    (N,) outside 0..31, else `None`."""
    bad = (a < 0) | (a >= GROUPS)
    if not bad.any():
        return None
    i = int(np.argmax(bad))
    return f"has group[{i}] = {int(a[i])} (collision groups are integers in 0..{GROUPS - 1})"


def boundary_problem(values: list[str]) -> str | None:
    """`"has boundary 'spherical' ..."` for the first value of an H5MD box's `boundary`
    that is not one of `BOUNDARIES`, else `None`."""
    for k, b in enumerate(values):
        if b not in BOUNDARIES:
            return f"has boundary[{k}] = {b!r}; allowed: {' or '.join(map(repr, BOUNDARIES))} (kinema's box is axis-aligned, periodic or open on each axis)"
    return None


def triclinic_at(rows: np.ndarray) -> int | None:
    """The first row of `rows` (F, D, D), edge vectors, with an entry off the diagonal that is
    not 0 (NaN counts: it is not 0), else `None`."""
    d = rows.shape[1]
    off = np.flatnonzero(((rows != 0) & ~np.eye(d, dtype=bool)).reshape(rows.shape[0], -1).any(axis=1))
    return int(off[0]) if off.size else None


def edges_problem(rows: np.ndarray, periodic: Any, by_frame: bool) -> str | None:
    """What is wrong with the box edges `rows` (F, D) m: `"has edge[0] = nan at frame 3 (box
    edges must be finite, in m)"`, or an edge <= 0 on a periodic axis; `None` when they are
    right. `by_frame`: name the frame (a box that changes)."""
    frame = (lambda i: f" at frame {i}") if by_frame else (lambda i: "")
    bad = ~np.isfinite(rows)
    if bad.any():
        i, k = np.unravel_index(int(np.argmax(bad)), rows.shape)
        return f"has edge[{k}] = {number(rows[i, k])}{frame(i)} (box edges must be finite, in m)"
    bad = (rows <= 0) & np.array([bool(p) for p in periodic][: rows.shape[1]])
    if bad.any():
        i, k = np.unravel_index(int(np.argmax(bad)), rows.shape)
        return f"has edge[{k}] = {number(rows[i, k])}{frame(i)} (a periodic axis needs an edge > 0 m)"
    return None


def _per_frame_problem(a: np.ndarray, alive: np.ndarray, find: Any) -> tuple[int, ...] | None:
    """The index (frame, particle, ...) in `a` (F, N, ...) of the first entry `find` finds
    among the particles that exist (`alive` (F, N)), or `None`; `find(rows)` gives the
    index of a hit in `rows` or `None`. With particles that come and go it is applied
    frame by frame, so `a` is never copied whole."""
    if alive.all():
        return find(a)
    for i in range(a.shape[0]):
        live = np.flatnonzero(alive[i])
        hit = find(a[i, live])
        if hit is not None:
            return (i, int(live[hit[0]]), *hit[1:])
    return None


#: How far from 1 the norm of an orientation quaternion written may be.
UNIT_QUATERNION = 1e-6


def _first_not_unit(rows: np.ndarray) -> tuple[int, ...] | None:
    """The index of the first quaternion of `rows` (..., 4) whose norm is not 1 within
    `UNIT_QUATERNION`, or `None`."""
    bad = np.abs(np.linalg.norm(rows, axis=-1) - 1.0) > UNIT_QUATERNION
    return tuple(int(i) for i in np.unravel_index(int(np.argmax(bad)), bad.shape)) if bad.any() else None


def contact_record_problem(record: Any, fr: Any) -> str | None:
    """What is wrong with a trajectory's `contact_record` (a `ContactRecord`, or `None`)
    for the frames `fr`, or `None`: one entry per frame, and particles named by ids of
    the trajectory (`j` may be -1, a collider)."""
    if record is None:
        return None
    if record.n_frames != fr.n_frames:
        return f"has {record.n_frames} frames; the trajectory has {fr.n_frames}"
    for name in ("i", "j"):
        ids = record[name]
        known = np.isin(ids, fr.ids) | ((ids == -1) if name == "j" else False)
        if not known.all():
            k = int(np.argmax(~known))
            frame = int(np.searchsorted(record.offsets, k, side="right")) - 1
            return f"names particle {name} = {int(ids[k])} at frame {frame}, which is not an id of the trajectory"
    return None


def _first_beyond_float32_at(a: np.ndarray) -> tuple[int, ...] | None:
    if a.size == 0 or not (np.nanmax(a, initial=-np.inf) > FLOAT32_MAX or np.nanmin(a, initial=np.inf) < -FLOAT32_MAX):
        return None  # reductions only: no copy of a
    big = np.abs(np.nan_to_num(a, nan=0.0)) > FLOAT32_MAX
    return tuple(int(i) for i in np.unravel_index(int(np.argmax(big)), a.shape))


def _place(a: np.ndarray, at: tuple[int, ...], axes: tuple[str, ...]) -> str:
    place = ", ".join(f"{name} {i}" for name, i in zip(axes, at, strict=False))
    return f"({number(a[at])})" + (f" at {place}" if place else "")


def check_frames(path: Any, traj: Any, fr: Frames, float32: str | None = None, int32_ids: str | None = None) -> None:
    """Refuses, before anything is written to `path`, a trajectory whose values kinema's
    reader would refuse, by the reader's rules: finite times that increase; finite positions
    and velocities where a particle exists (velocities may be all NaN: unknown, not written
    to H5MD); masses finite and > 0 kg, radii finite, >= 0 m and at most `MAX_RADIUS` (of
    the particles that exist at some frame); collision groups in 0..31; species names of printable text; ids once per
    frame. `float32` (a format's name) also refuses values beyond float32, which that
    format stores (they would be inf); `int32_ids` ids beyond int32. Raises
    `TrajectoryFileError` (a `ValueError`), one line: `cannot write run.h5: trajectory
    'masses' has mass[2] = -1 (masses must be finite and > 0 kg)`. The (F, N, 3) arrays are
    checked frame by frame where particles come and go, never copied whole."""

    def refuse(word: str, problem: str | None) -> None:
        if problem is not None:
            raise TrajectoryFileError(f"cannot write {path}: trajectory {word!r} {problem}")

    refuse("t", non_finite(fr.t, ("frame",)))
    refuse("t", increase_problem(fr.t))
    axes = ("frame", "particle")
    at = _per_frame_problem(fr.positions, fr.alive, first_non_finite)
    refuse("positions", None if at is None else f"has a non-finite value {_place(fr.positions, at, axes)}")
    # velocities all NaN where the particles exist: unknown (a file without them), not an error
    known = _per_frame_problem(fr.velocities, fr.alive, lambda rows: None if np.isnan(rows).all() else (0,)) is not None
    if known:
        at = _per_frame_problem(fr.velocities, fr.alive, first_non_finite)
        refuse("velocities", None if at is None else f"has a non-finite value {_place(fr.velocities, at, axes)}")
    for word, a in (("angular_velocities", fr.angular_velocities), ("orientations", fr.orientations)):
        at = None if a is None else _per_frame_problem(a, fr.alive, first_non_finite)
        refuse(word, None if at is None else f"has a non-finite value {_place(a, at, axes)}")
    if fr.orientations is not None:
        at = _per_frame_problem(fr.orientations, fr.alive, _first_not_unit)
        refuse(
            "orientations",
            None
            if at is None
            else f"has |q| = {float(np.linalg.norm(fr.orientations[at[:2]])):.17g} {_place(fr.orientations, at, axes)}: a unit quaternion (w, x, y, z) has |q| = 1 (within {UNIT_QUATERNION})",
        )
    refuse("contact_record", contact_record_problem(getattr(traj, "contact_record", None), fr))
    exists = fr.alive.any(axis=0)
    if fr.inertia is not None:
        bad = exists & ~(np.isfinite(fr.inertia) & (fr.inertia >= 0))
        refuse(
            "inertia",
            None if not bad.any() else f"has inertia[{int(np.argmax(bad))}] = {fr.inertia[np.argmax(bad)]!r} (moments of inertia are finite and >= 0 kg m2)",
        )
    if fr.groups is not None:
        refuse("groups", group_problem(np.where(exists, fr.groups, 0)))
    if fr.masses is not None:
        refuse("masses", mass_problem(np.where(exists, fr.masses, 1.0)))
    if fr.radii is not None:
        refuse("radii", radius_problem(np.where(exists, fr.radii, 0.0)))
    species = getattr(traj, "species", None)
    if species is not None:
        refuse("species", species_problem(np.asarray(species, dtype=object).reshape(-1).tolist()))
    colors = getattr(traj, "colors", None)
    if colors is not None:
        c = np.asarray(colors, dtype=np.float64)
        if c.shape != (fr.n_particles, 3):
            refuse("colors", f"has shape {c.shape}; it must be ({fr.n_particles}, 3), r, g, b per particle")
        refuse("colors", color_problem(np.where(exists[:, None], c, np.nan)))
    if fr.changes_count and np.unique(fr.ids).size != fr.ids.size:
        for i in range(fr.n_frames):
            uniq, counts = np.unique(fr.ids[fr.alive[i]], return_counts=True)
            if (counts > 1).any():
                refuse("ids", f"has id {int(uniq[np.argmax(counts > 1)])} twice at frame {i} (an id names one particle)")
    if float32 is not None:
        beyond = f"beyond float32 (at most {FLOAT32_MAX:.8g} in magnitude), which format {float32!r} stores"
        for word, a in (("positions", fr.positions), ("velocities", fr.velocities), ("angular_velocities", fr.angular_velocities)):
            if a is None:
                continue
            at = _per_frame_problem(a, fr.alive, _first_beyond_float32_at)
            refuse(word, None if at is None else f"has a value {_place(a, at, axes)} {beyond}")
        for word, a in (("masses", fr.masses), ("radii", None if fr.radii is None else 2 * fr.radii)):
            a = None if a is None else np.where(exists, a, 0.0)
            at = None if a is None else _first_beyond_float32_at(a)
            refuse(word, None if at is None else f"has a value {_place(a, at, ('particle',))}{' as a diameter' * (word == 'radii')} {beyond}")
    if int32_ids is not None:
        info = np.iinfo(np.int32)
        bad = (fr.ids < info.min) | (fr.ids > info.max)
        if bad.any():
            k = int(np.argmax(bad))
            refuse("ids", f"has id[{k}] = {int(fr.ids[k])} beyond int32 (from {info.min} to {info.max}), which format {int32_ids!r} stores")


def fail(path: Path, what: str) -> TrajectoryFileError:
    """The error of a file at `path` of which `what` is wrong: one line naming it."""
    return TrajectoryFileError(f"{path}: {what}")


def utf8(raw: Any) -> Any:
    """An attribute's bytes (a fixed-length HDF5 string) as text; anything else as it is,
    for the caller to refuse by type."""
    if isinstance(raw, bytes):
        try:
            return raw.decode("utf-8")
        except UnicodeDecodeError:
            pass
    return raw


def where(word: str, ds: Any) -> str:
    """A dataset as a message names it: its meaning and its path in the file."""
    return f"dataset {word!r} ({ds.name})"


def as_text(value: Any) -> str:
    """A string attribute as text: H5MD's fixed-length strings read back as bytes."""
    if isinstance(value, np.ndarray) and value.size == 1:
        value = value.reshape(-1)[0]
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)


class Reader:
    """The reads of one file. Every dataset's type and shape is checked, and the bytes it
    needs added up (`plan`), before any data is read; `check_memory` then refuses a file
    that does not fit in the memory there is; `finite` checks values once read."""

    def __init__(self, path: Path, creator: str | None = None) -> None:
        self.path = path
        self.creator = creator  # the file's /h5md/creator name: what a dataset without a unit is in
        self.planned: list[tuple[str, Any, int]] = []

    def fail(self, what: str) -> TrajectoryFileError:
        return fail(self.path, what)

    def numbers(self, word: str, ds: Any, integer: bool = False) -> tuple[int, ...]:
        """The shape of `ds`, which must hold real numbers (integers when `integer`)."""
        must = "integers" if integer else "real numbers"
        if ds.shape is None:
            raise self.fail(f"{where(word, ds)} holds no data (an empty dataspace); it must hold {must}")
        problem = dtype_problem(ds.dtype, integer)
        if problem is not None:
            raise self.fail(f"{where(word, ds)} holds {problem}; it must hold {must}")
        return tuple(ds.shape)

    def clock(self, word: str, ds: Any, value_word: str, value: Any, integer: bool = False) -> None:
        """`ds` (the step or time of an element) holds one number per frame of `value`,
        or one number (H5MD's fixed interval)."""
        shape = self.numbers(word, ds, integer)
        n = value.shape[0]
        if shape not in ((), (n,)):
            one = word[:-1] if word.endswith("s") else word
            raise self.fail(f"{where(word, ds)} has shape {shape} but {where(value_word, value)} has {n} frames: one {one} per frame")

    def unit(self, word: str, ds: Any, dims: tuple[int, int, int]) -> Fraction:
        """The exact factor that converts the values of `ds` to SI, from its `unit`
        attribute, which must be a unit of the dimension `dims` (`parse_unit`). Without one:
        1 in kinema's files (SI, which they write a unit for anyway), else what
        `assumed_unit` takes for the file's creator (ASE's units for znh5md, SI for the
        others), said by a `UnitWarning`, one line naming the file, the dataset and the unit
        taken."""
        if "unit" not in ds.attrs:
            if self.creator == "kinema":
                return Fraction(1)
            factor, words = assumed_unit(self.creator, dims)
            warnings.warn(f"{self.path}: {where(word, ds)} has no unit; taken as {words}", UnitWarning, stacklevel=2)
            return factor
        raw = ds.attrs["unit"]
        text = utf8(raw.reshape(-1)[0] if isinstance(raw, np.ndarray) and raw.size == 1 else raw)
        if not isinstance(text, str):
            raise self.fail(f"{where(word, ds)} has a unit attribute that is not a string: {shown(raw)}")
        try:
            factor, dims_found = parse_unit(text)
            value = float(factor)
        except (ValueError, OverflowError) as e:
            raise self.fail(f"{where(word, ds)} has unit {text!r}, which kinema cannot read: {e}") from None
        if dims_found != dims:
            raise self.fail(f"{where(word, ds)} has unit {text!r}, which is not {QUANTITY[dims]}")
        if not 0 < value < np.inf:
            raise self.fail(f"{where(word, ds)} has unit {text!r}, whose factor to SI is out of the range of float64")
        return factor

    def plan(self, word: str, ds: Any, nbytes: int | None = None) -> None:
        self.planned.append((word, ds, int(ds.size) * ds.dtype.itemsize if nbytes is None else nbytes))

    def check_memory(self, limit: int | None) -> None:
        if limit is None or not self.planned:
            return
        for word, ds, nbytes in self.planned:
            if nbytes > limit:
                raise self.fail(
                    f"{where(word, ds)} of shape {tuple(ds.shape)} ({ds.dtype}) needs {gib(nbytes)} GiB of memory to load; {gib(limit)} GiB is available"
                )
        total = sum(nbytes for _, _, nbytes in self.planned)
        if total > limit:
            word, ds, nbytes = max(self.planned, key=lambda p: p[2])
            raise self.fail(
                f"loading it needs {gib(total)} GiB of memory ({where(word, ds)} of shape {tuple(ds.shape)} ({ds.dtype}): "
                f"{gib(nbytes)} GiB); {gib(limit)} GiB is available"
            )

    def finite(self, word: str, ds: Any, a: np.ndarray, axes: tuple[str, ...]) -> None:
        """Refuses a NaN or ±inf in `a` (read from `ds`), naming its place: `axes` name
        the leading indices (frame, particle)."""
        problem = non_finite(a, axes)
        if problem is not None:
            raise self.fail(f"{where(word, ds)} {problem}")


def links_out(f: Any) -> str | None:
    """What in the open HDF5 file `f` reads data from another file, as a message names it:
    an external link (`h5py.ExternalLink`), a virtual dataset with a source in another file
    (`h5py.VirtualLayout`), a dataset whose raw data is stored in external files; `None`
    when nothing does. Links are inspected without being followed (soft links stay inside
    the file and are skipped: their targets are reached by their own paths), so the other
    file is never opened."""
    h5py = import_h5py()
    seen: set[Any] = set()
    stack = [f["/"]]
    while stack:
        group = stack.pop()
        key = h5py.h5o.get_info(group.id).addr  # the group's place in the file
        if key in seen:
            continue  # a group reached again through another hard link
        seen.add(key)
        base = group.name.rstrip("/")
        for name in group:
            link = group.get(name, getlink=True)
            path = f"{base}/{name}"
            if isinstance(link, h5py.ExternalLink):
                return f"{path} is an external link to {link.path!r} in the file {link.filename!r}"
            if not isinstance(link, h5py.HardLink):
                continue  # a soft link: a path inside this file
            obj = group.get(name)
            if isinstance(obj, h5py.Group):
                stack.append(obj)
            elif isinstance(obj, h5py.Dataset):
                if obj.is_virtual:
                    other = next((m.file_name for m in obj.virtual_sources() if m.file_name != "."), None)
                    if other is not None:
                        return f"{path} is a virtual dataset that reads the file {other!r}"
                if obj.external:
                    return f"{path} is stored in the external file {obj.external[0][0]!r}"
    return None


def element_datasets(path: Path, parent: Any, name: str, required: bool = False) -> tuple[Any, Any, Any] | None:
    """The (value, step, time) datasets of a time-dependent element (time `None` when it
    has none), or `None` when it is absent."""
    h5py = import_h5py()
    if name not in parent:
        if required:
            raise fail(path, f"not a complete H5MD trajectory: {parent.name.rstrip('/')}/{name} is missing")
        return None
    g = parent[name]
    value, step, time = (g.get(k) for k in ("value", "step", "time")) if isinstance(g, h5py.Group) else (None, None, None)
    if not (isinstance(value, h5py.Dataset) and isinstance(step, h5py.Dataset) and (time is None or isinstance(time, h5py.Dataset))):
        raise fail(path, f"{g.name} is not a time-dependent H5MD element (a group with step and value datasets)")
    return value, step, time


def per_frame(ds: Any, a: np.ndarray, n: int, dtype: Any) -> np.ndarray:
    """A step or time read from `ds`: one per frame, or H5MD's fixed interval (a scalar
    `a` and the `offset` attribute) made one per frame."""
    if np.ndim(a) != 0:
        return np.asarray(a)
    offset = ds.attrs.get("offset", 0)
    if np.asarray(offset).size != 1 or dtype_problem(np.asarray(offset).dtype) is not None:
        raise TrajectoryFileError(f"attribute 'offset' ({ds.name}) = {shown(offset)} is not a number")
    return (np.asarray(offset).reshape(()) + a * np.arange(n)).astype(dtype, copy=False)


def varying_ids(path: Path, p: Any) -> Any:
    """The `value` dataset of the particle group's time-dependent `id` element when it has
    a fill value (set when it was created): the mark, in H5MD, of a number of particles that
    varies (an entry equal to it is a particle that does not exist at that frame); else
    `None`."""
    h5py = import_h5py()
    if not isinstance(p.get("id"), h5py.Group):
        return None
    ds = element_datasets(path, p, "id")[0]
    if ds.shape is None or ds.dtype.kind not in "iu":
        return None  # the per-particle checks name it
    return ds if ds.id.get_create_plist().fill_value_defined() == h5py.h5d.FILL_VALUE_USER_DEFINED else None


class Live:
    """The particles of a file whose number varies: the id of each of its (F, N) entries or
    the fill value (H5MD's "no particle here"). kinema's trajectories have one column per
    particle, the ids ascending, so the entries are gathered by id: `ids` (U,) the ids
    that exist at some frame, `alive` (F, U). A file whose particles keep their slot (as
    kinema writes them, with ascending ids) reads back column for column."""

    def __init__(self, r: Reader, ds: Any, frames: int, n: int) -> None:
        table = np.asarray(ds[()], dtype=np.int64)
        fill = ds.fillvalue
        self.present = table != fill
        self.frame, self.slot = np.nonzero(self.present)  # frame by frame
        self.ids, self.column = np.unique(table[self.present], return_inverse=True)
        self.column = self.column.reshape(-1)
        if self.ids.size == 0:
            raise r.fail(f"0 particles: every entry of {where('ids', ds)} is its fill value {number(fill)} (no particle exists at any frame)")
        key = self.frame * self.ids.size + self.column
        order = np.sort(key)
        twice = np.flatnonzero(np.diff(order) == 0)
        if twice.size:
            k, c = divmod(int(order[twice[0]]), self.ids.size)
            raise r.fail(f"{where('ids', ds)} holds id {int(self.ids[c])} twice at frame {k} (an id names one particle)")
        self.frames = frames
        self.alive = np.zeros((frames, self.ids.size), dtype=bool)
        self.alive[self.frame, self.column] = True
        # the entry where each particle first exists
        self.first_entry = np.unique(self.column, return_index=True)[1]

    def masked(self, a: np.ndarray) -> np.ndarray:
        """`a` (F, N, ...) with 0 where no particle exists: what is checked for finite values."""
        mask = self.present.reshape(self.present.shape + (1,) * (a.ndim - 2))
        return np.where(mask, a, 0)

    def columns(self, a: np.ndarray) -> np.ndarray:
        """`a` (F, N, D) by particle: (F, U, D), NaN where a particle does not exist."""
        out = np.full((self.frames, self.ids.size) + a.shape[2:], np.nan)
        out[self.frame, self.column] = a[self.frame, self.slot]
        return out

    def first(self, a: np.ndarray, element: bool) -> np.ndarray:
        """A per-particle value (U,) from `a`, (F, N) (a time-dependent element) or (N,):
        its value at the first entry of each particle."""
        e = self.first_entry
        return a[self.frame[e], self.slot[e]] if element else a[self.slot[e]]
