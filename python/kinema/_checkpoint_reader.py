"""Reading a checkpoint, every field checked (package-internal: ``kinema.checkpoint`` is the
public face, and re-exports ``CheckpointError``, ``FORMAT`` and ``VERSION``): the file's
format and version (which the writer, ``kinema.checkpoint.save_checkpoint``, writes),
``CheckpointError``, ``Reader`` (the checked reads of one open checkpoint), ``reading`` (a
checkpoint opened, its format and version checked, any failure while it is read a
``CheckpointError``) and ``scene_and_clock`` (its scene, validated as a scene file is, its ids
and its clock). What is read with them: the world in ``kinema._checkpoint_world``, a run in
progress in ``kinema._checkpoint_run``."""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from ._checks import _dtype_words, _type_words, describe
from .io._files import TrajectoryFileError
from .io._hdf5_heaps import global_heap_problem

FORMAT = "kinema-checkpoint"
VERSION = 2  # 2: the clock's anchor and the run's t0 and duration (frames at exact times)
# (what a checkpoint says it is: kinema.checkpoint.save_checkpoint writes them, `reading` checks them)


# -- reading, every field checked ---------------------------------------------------------------
# A checkpoint is read as a scene file or an H5MD trajectory is: every attribute and dataset
# that load_checkpoint and resume_run use is checked for presence, type (a bool is not a
# number), shape (one value per particle, one row per frame recorded), finiteness and range,
# and against the others (the time after the steps taken, ids below the next id, the frames'
# particles and the sets recorded), before the world is built or the run goes on; its scene
# goes through the scene's own validation. A failure is one CheckpointError, one line naming
# the file, the field, the value found and what is allowed. What h5py, json or numpy raise on
# a damaged file (KeyError, OSError, OverflowError, TypeError, ...) becomes one too.


class CheckpointError(TrajectoryFileError):
    """A checkpoint that cannot be read back: missing, not HDF5, truncated, not a kinema
    checkpoint, or with a field missing or damaged. The message is one line naming the file
    and the field (`attribute 'time'`, `dataset 'run/x'`, `attribute 'emitters'
    [0].emitted`), the value found and what is allowed. A `ValueError` (by way of
    `kinema.io.TrajectoryFileError`): the command line prints it as one line, exit 2."""

    __module__ = "kinema.checkpoint"


INT64_MAX = 2**63 - 1
TIME_STEPS = 2**53  # beyond this many steps, t = steps·dt no longer grows with every step
_PARTICLE_BYTES = 1024  # a particle's memory in the engine (kinema.runner.ENGINE_BYTES)


def first_line(e: BaseException) -> str:
    text = str(e).strip()
    return text.splitlines()[0] if text else type(e).__name__


def scene_error(e: Exception) -> CheckpointError:
    """A checkpoint's scene refused (one line per problem): the first, and how many more."""
    lines = str(e).splitlines() or ["attribute 'scene' is not a valid scene"]
    return CheckpointError(lines[0] + (f" (and {len(lines) - 1} more problems)" if len(lines) > 1 else ""))


def _shape_words(shape: tuple[int | None, ...]) -> str:
    return "(" + ", ".join("n" if s is None else str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"


def field_at(field: str, index: tuple[int, ...]) -> str:
    return f"{field}[{', '.join(str(int(i)) for i in index)}]"


class Reader:
    """The checked reads of one open checkpoint. `field` is what is being read, named in
    the message when h5py or numpy fails on it."""

    def __init__(self, path: Path, f: Any) -> None:
        self.path, self.f = path, f
        self.field = "the file"
        self.version = VERSION
        self._available: int | None = -1

    # -- messages
    def fail(self, field: str, what: str) -> CheckpointError:
        return CheckpointError(f"{self.path}: {field} {what}")

    def invalid(self, field: str, value: Any, allowed: str) -> CheckpointError:
        return self.fail(field, f"= {describe(value)} is invalid: {allowed}")

    def memory(self, what: str, nbytes: int) -> None:
        from .io._checks import available_memory, gib

        if self._available == -1:
            self._available = available_memory()
        if self._available is not None and nbytes > self._available:
            raise self.fail(what, f"needs {gib(nbytes)} GiB of memory to load; {gib(self._available)} GiB is available")

    # -- values (of attributes and of JSON)
    def integer(self, field: str, value: Any, lo: int, hi: int, allowed: str) -> int:
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
            raise self.invalid(field, value, f"{allowed} ({_type_words(value)} is not an integer)")
        if not lo <= int(value) <= hi:
            raise self.invalid(field, value, allowed)
        return int(value)

    def real(self, field: str, value: Any, ok: Any, allowed: str) -> float:
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise self.invalid(field, value, f"{allowed} ({_type_words(value)} is not a number)")
        try:
            v = float(value)
        except OverflowError:
            raise self.invalid(field, value, allowed) from None
        if not ok(v):
            raise self.invalid(field, value, allowed)
        return v

    def numbers(self, field: str, value: Any, shape: tuple[int | None, ...], integer: bool = False) -> np.ndarray:
        """A JSON list nested as `shape` (None: any length) of numbers (integers when
        `integer`; a bool is neither) as an array (int64 or float64)."""
        must = "an integer" if integer else "a number"

        def walk(v: Any, depth: int, index: tuple[int, ...]) -> None:
            if depth == len(shape):
                if isinstance(v, bool) or not isinstance(v, (int, float)) or (integer and not isinstance(v, int)):
                    raise self.invalid(field_at(field, index), v, f"it must be {must} ({_type_words(v)} is not)")
                if integer and not -INT64_MAX <= v <= INT64_MAX:
                    raise self.invalid(field_at(field, index), v, "it must be an integer of 64 bits")
                if not integer and isinstance(v, int) and abs(v) > 2**1000:
                    raise self.invalid(field_at(field, index), v, "it must be a number within the range of float64")
                return
            where = field_at(field, index) if index else field
            if not isinstance(v, list):
                raise self.invalid(where, v, f"it must be a list ({_type_words(v)} is not)")
            if shape[depth] is not None and len(v) != shape[depth]:
                raise self.fail(where, f"has {len(v)} values; it must have {shape[depth]}")
            for i, x in enumerate(v):
                walk(x, depth + 1, (*index, i))

        walk(value, 0, ())
        a = np.array(value, dtype=np.int64 if integer else np.float64)
        return a.reshape([-1 if s is None else s for s in shape]) if a.size == 0 else a

    def array(self, field: str, value: Any, shape: tuple[int | None, ...], kind: str) -> np.ndarray:
        """An array as `kinema.checkpoint._plain` writes it, {"__array__": [...], "dtype": "..."}: `kind`
        "int", "real" or "text" (names)."""
        if not (isinstance(value, dict) and set(value) == {"__array__", "dtype"}):
            raise self.invalid(field, value, "it must be an array written as {'__array__': [...], 'dtype': '...'}")
        kinds = {"int": "iu", "real": "f", "text": "U"}[kind]
        try:
            dtype = np.dtype(value["dtype"]) if isinstance(value["dtype"], str) else None
        except (TypeError, ValueError):
            dtype = None
        if dtype is None or dtype.kind not in kinds:
            words = {"int": "integers", "real": "floats", "text": "strings"}[kind]
            raise self.invalid(f"{field}.dtype", value["dtype"], f"it must be the name of a NumPy dtype of {words}")
        data = value["__array__"]
        if kind != "text":
            return self.numbers(field, data, shape, integer=kind == "int")
        if not isinstance(data, list) or len(shape) != 1 or (shape[0] is not None and len(data) != shape[0]):
            raise self.invalid(field, data, f"it must be a list of {shape[0]} names")
        bad = next((k for k, s in enumerate(data) if not isinstance(s, str)), None)
        if bad is not None:
            raise self.invalid(field_at(field, (bad,)), data[bad], f"it must be a name ({_type_words(data[bad])} is not)")
        return np.array(data, dtype=str)

    def each(self, field: str, a: np.ndarray, ok: np.ndarray, allowed: str) -> None:
        """Refuses the first element of `a` where `ok` is False, naming its index."""
        ok = np.asarray(ok)
        if ok.size and not ok.all():
            index = np.unravel_index(int(np.argmin(ok)), ok.shape)
            raise self.invalid(field_at(field, index), a[index], allowed)

    # -- the file
    def attr(self, name: str, group: str | None = None) -> tuple[str, Any]:
        """The value of an attribute of the file (or of `group`): one value, not an array."""
        key = name if group is None else f"{group}/{name}"
        field = self.field = f"attribute {key!r}"
        holder = self.f if group is None else self.group(group)
        self.field = field
        if name not in holder.attrs:
            raise self.fail(field, "is missing")
        raw = holder.attrs[name]
        if isinstance(raw, np.ndarray):
            if raw.ndim != 0:
                raise self.fail(field, f"holds an array of shape {raw.shape}; it must be one value")
            raw = raw[()]
        return field, raw

    def int_attr(self, name: str, lo: int, hi: int, allowed: str, group: str | None = None) -> int:
        field, raw = self.attr(name, group)
        return self.integer(field, raw, lo, hi, allowed)

    def real_attr(self, name: str, ok: Any, allowed: str, group: str | None = None) -> float:
        field, raw = self.attr(name, group)
        return self.real(field, raw, ok, allowed)

    def bool_attr(self, name: str) -> bool:
        field, raw = self.attr(name)
        if not isinstance(raw, (bool, np.bool_)):
            raise self.invalid(field, raw, f"it must be True or False ({_type_words(raw)} is not a bool)")
        return bool(raw)

    def text(self, name: str, group: str | None = None) -> tuple[str, str]:
        field, raw = self.attr(name, group)
        if isinstance(raw, (bytes, np.bytes_)):
            try:
                raw = bytes(raw).decode("utf-8")
            except UnicodeDecodeError:
                raise self.fail(field, "is not UTF-8 text") from None
        if not isinstance(raw, str):
            raise self.invalid(field, raw, f"it must be text ({_type_words(raw)} is not)")
        return field, str(raw)

    def json(self, name: str, group: str | None = None) -> tuple[str, Any]:
        field, text = self.text(name, group)
        try:
            return field, json.loads(text)
        except (ValueError, RecursionError) as e:  # (JSONDecodeError is a ValueError; an int of 5000 digits too)
            raise self.fail(field, f"is not JSON ({first_line(e)})") from None

    def group(self, name: str) -> Any:
        import h5py

        field = self.field = f"group {name!r}"
        if name not in self.f:
            raise self.fail(field, "is missing")
        g = self.f[name]
        if not isinstance(g, h5py.Group):
            raise self.fail(field, "is a dataset; it must be a group")
        return g

    def dataset(self, name: str, kind: str, shape: tuple[int | None, ...], allowed: str, read: bool = True) -> tuple[str, Any]:
        """A dataset holding `kind` ("real": numbers, "int": integers, "bool") of `shape`
        (None: any length), checked before it is read, and read (its shape when not `read`)."""
        import h5py

        from .io._checks import dtype_problem

        field = self.field = f"dataset {name!r}"
        if name not in self.f:
            raise self.fail(field, "is missing")
        ds = self.f[name]
        if not isinstance(ds, h5py.Dataset):
            raise self.fail(field, f"is a group; it must be a dataset of {allowed}")
        if ds.shape is None:
            raise self.fail(field, f"holds no data (an empty dataspace); it must hold {allowed}")
        if kind == "bool":
            problem = None if ds.dtype.kind == "b" else _dtype_words(ds.dtype)
        else:
            problem = dtype_problem(ds.dtype, integer=kind == "int")
        if problem is not None:
            raise self.fail(field, f"holds {problem}; it must hold {allowed}")
        if len(ds.shape) != len(shape) or any(want is not None and got != want for got, want in zip(ds.shape, shape, strict=False)):
            raise self.fail(field, f"has shape {tuple(ds.shape)}; it must have shape {_shape_words(shape)}: {allowed}")
        if not read:
            return field, tuple(ds.shape)
        self.memory(field, int(ds.size) * ds.dtype.itemsize)
        a = ds[()]
        if kind == "real":
            a = np.asarray(a, dtype=np.float64)
        elif kind == "int":
            if a.dtype.kind == "u" and a.size and int(a.max()) > INT64_MAX:
                self.each(field, a, a <= INT64_MAX, "it must be an integer of 64 bits (below 2**63)")
            a = np.asarray(a, dtype=np.int64)
        return field, a

    def ints(self, name: str, shape: tuple[int | None, ...], lo: int, hi: int, allowed: str) -> tuple[str, np.ndarray]:
        field, a = self.dataset(name, "int", shape, allowed)
        self.each(field, a, (a >= lo) & (a <= hi), allowed)
        return field, a

    def reals(self, name: str, shape: tuple[int | None, ...], ok: Any, allowed: str) -> tuple[str, np.ndarray]:
        field, a = self.dataset(name, "real", shape, allowed)
        self.each(field, a, ok(a), allowed)
        return field, a

    def engine(self, field: str, call: Any, *args: Any) -> Any:
        """`call(*args)`, an engine's restore: what it refuses, named by `field`."""
        self.field = field
        try:
            return call(*args)
        except (ValueError, TypeError, OverflowError) as e:
            raise self.fail(field, f"is refused by the engine: {first_line(e)}") from None


@contextmanager
def reading(path: Path) -> Iterator[Reader]:
    """The checkpoint at `path` open, its format and version checked; any failure while
    it is read is a `CheckpointError`."""
    import h5py

    if not path.exists():
        raise CheckpointError(f"{path}: no such checkpoint file")
    if not path.is_file():
        raise CheckpointError(f"{path}: not a checkpoint file (a directory or a special file)")
    try:
        heaps = global_heap_problem(path)
    except OSError as e:
        raise CheckpointError(f"{path}: cannot be read ({first_line(e)})") from None
    if heaps is not None:
        raise CheckpointError(f"{path}: not a checkpoint that can be read: {heaps}")
    try:
        f = h5py.File(path, "r")
    except Exception as e:  # (an OSError for a file that is not HDF5, or truncated)
        raise CheckpointError(f"{path}: not a checkpoint (cannot be read as HDF5: {first_line(e)})") from None
    r = Reader(path, f)
    try:
        with f:
            found = f.attrs.get("format")
            if not (isinstance(found, str) and found == FORMAT):
                raise CheckpointError(f"{path}: not a kinema checkpoint (no attribute 'format' = {FORMAT!r})")
            version = r.int_attr("version", 1, INT64_MAX, f"a checkpoint version from 1 to {VERSION}")
            if version > VERSION:
                raise CheckpointError(f"{path}: attribute 'version' = {version}: checkpoint version {version} is newer than this kinema reads ({VERSION})")
            r.version = version
            yield r
    except CheckpointError:
        raise
    except MemoryError:
        raise CheckpointError(f"{path}: {r.field} needs more memory than there is to load") from None
    except Exception as e:  # h5py, json or numpy on a damaged file: named by what was being read
        raise CheckpointError(f"{path}: {r.field} cannot be read ({type(e).__name__}: {first_line(e)}); the checkpoint is damaged") from None


def scene_and_clock(r: Reader, read_ids: bool = True) -> dict:
    """The scene (validated as a scene file is), the ids (or their number) and the clock."""
    from .scene import Scene, SceneError

    field, text = r.text("scene")
    try:
        scene = Scene.from_string(text, f"{r.path}: {field}")
    except SceneError as e:
        raise scene_error(e) from None
    # a list of particles as World.to_scene writes it: counted without building it
    field_ids, ids = r.dataset("ids", "int", (None,), "one id per particle (integers)", read=read_ids)
    n = ids.shape[0] if read_ids else ids[0]
    made = scene.particle_count()
    if made != n:
        raise r.fail(field_ids, f"holds {n} ids but attribute 'scene' makes {made:,} particles; there must be one id per particle")
    r.memory(f"the world of {n:,} particles", n * _PARTICLE_BYTES)
    dt = scene.world.dt
    steps = r.int_attr("steps", 0, TIME_STEPS, "the steps taken: an integer from 0 to 2**53")
    time = r.real_attr("time", lambda t: math.isfinite(t) and t >= 0, "the time: a finite number of seconds >= 0")
    # the clock's anchor (checkpoints before frames at exact times: 0 steps at 0 s)
    k0, t0 = 0, 0.0  # (version 1: a clock from 0)
    if r.version >= 2:
        k0 = r.int_attr("clock_steps", 0, steps, f"the steps at the clock's anchor: an integer from 0 to attribute 'steps' = {steps}")
        t0 = r.real_attr("clock_time", math.isfinite, "the time at the clock's anchor: a finite number of seconds")
    if time != t0 + float(steps - k0) * dt:
        raise r.fail(
            "attribute 'time'",
            f"= {describe(time)} is invalid: it must be the time after attribute 'steps' = {steps} steps of dt = {dt:g} s from "
            f"{k0} steps at {describe(t0)} s (attributes 'clock_steps', 'clock_time'): {describe(t0 + float(steps - k0) * dt)} s",
        )
    next_id = r.int_attr("next_id", 0, INT64_MAX, "the id the next particle gets: an integer from 0 to 2**63 - 1")
    if read_ids:
        r.each(field_ids, ids, ids >= 0, "ids are integers >= 0")
        if n > 1:
            k = int(np.argmin(np.diff(ids) > 0)) + 1
            if ids[k] <= ids[k - 1]:
                raise r.invalid(field_at(field_ids, (k,)), ids[k], f"ids must increase strictly (ids[{k - 1}] = {ids[k - 1]})")
        if n and next_id <= ids[-1]:
            raise r.invalid("attribute 'next_id'", next_id, f"it must be above every id (the largest is {ids[-1]})")
    return {"scene": scene, "ids": ids, "n": n, "steps": steps, "time": time, "next_id": next_id, "clock": (k0, t0)}
