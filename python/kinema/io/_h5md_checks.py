"""Checked reads of an H5MD file's elements (for ``kinema.io.h5md_reader``): ``Reader``
checks the type, shape and unit of each dataset and adds up the memory the reads need before
any data is read, then that the values read are finite; the datasets of a time-dependent
element, its step and time made one per frame; and ``Live``, the particles of a file whose
number varies (H5MD's time-dependent ``id`` with a fill value). Errors are
``TrajectoryFileError``, one line naming the file, the dataset (by meaning and by path) and the
value."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ._checks import dtype_problem, first_non_finite, gib, number, shown
from ._files import TrajectoryFileError
from ._h5md_layout import import_h5py
from .h5md_units import QUANTITY, parse_unit


def fail(path: Path, what: str) -> TrajectoryFileError:
    """The error of a file at ``path`` of which ``what`` is wrong: one line naming it."""
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
    needs added up (``plan``), before any data is read; ``check_memory`` then refuses a file
    that does not fit in the memory there is; ``finite`` checks values once read."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.planned: list[tuple[str, Any, int]] = []

    def fail(self, what: str) -> TrajectoryFileError:
        return fail(self.path, what)

    def numbers(self, word: str, ds: Any, integer: bool = False) -> tuple[int, ...]:
        """The shape of ``ds``, which must hold real numbers (integers when ``integer``)."""
        must = "integers" if integer else "real numbers"
        if ds.shape is None:
            raise self.fail(f"{where(word, ds)} holds no data (an empty dataspace); it must hold {must}")
        problem = dtype_problem(ds.dtype, integer)
        if problem is not None:
            raise self.fail(f"{where(word, ds)} holds {problem}; it must hold {must}")
        return tuple(ds.shape)

    def clock(self, word: str, ds: Any, value_word: str, value: Any, integer: bool = False) -> None:
        """``ds`` (the step or time of an element) holds one number per frame of ``value``,
        or one number (H5MD's fixed interval)."""
        shape = self.numbers(word, ds, integer)
        n = value.shape[0]
        if shape not in ((), (n,)):
            one = word[:-1] if word.endswith("s") else word
            raise self.fail(f"{where(word, ds)} has shape {shape} but {where(value_word, value)} has {n} frames: one {one} per frame")

    def unit(self, word: str, ds: Any, dims: tuple[int, int, int]) -> float:
        """The factor that converts the values of ``ds`` to SI, from its ``unit`` attribute,
        which must be a unit of the dimension ``dims`` (``parse_unit``); 1 when it has none
        (the values are taken as SI)."""
        if "unit" not in ds.attrs:
            return 1.0
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
        return value

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
        """Refuses a NaN or ±inf in ``a`` (read from ``ds``), naming its place: ``axes`` name
        the leading indices (frame, particle)."""
        at = first_non_finite(a)
        if at is not None:
            place = ", ".join(f"{name} {i}" for name, i in zip(axes, at, strict=False))
            raise self.fail(f"{where(word, ds)} has a non-finite value ({number(a[at])})" + (f" at {place}" if place else ""))


def element_datasets(path: Path, parent: Any, name: str, required: bool = False) -> tuple[Any, Any, Any] | None:
    """The (value, step, time) datasets of a time-dependent element (time ``None`` when it
    has none), or ``None`` when it is absent."""
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
    """A step or time read from ``ds``: one per frame, or H5MD's fixed interval (a scalar
    ``a`` and the ``offset`` attribute) made one per frame."""
    if np.ndim(a) != 0:
        return np.asarray(a)
    offset = ds.attrs.get("offset", 0)
    if np.asarray(offset).size != 1 or dtype_problem(np.asarray(offset).dtype) is not None:
        raise TrajectoryFileError(f"attribute 'offset' ({ds.name}) = {shown(offset)} is not a number")
    return (np.asarray(offset).reshape(()) + a * np.arange(n)).astype(dtype, copy=False)


def varying_ids(path: Path, p: Any) -> Any:
    """The ``value`` dataset of the particle group's time-dependent ``id`` element when it has
    a fill value (set when it was created): the mark, in H5MD, of a number of particles that
    varies (an entry equal to it is a particle that does not exist at that frame); else
    ``None``."""
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
    particle, the ids ascending, so the entries are gathered by id: ``ids`` (U,) the ids
    that exist at some frame, ``alive`` (F, U). A file whose particles keep their slot (as
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
