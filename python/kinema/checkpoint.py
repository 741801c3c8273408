"""Checkpoints: a world written to one file between steps and read back into a world that
goes on exactly as the one that wrote it.

What a checkpoint holds (an HDF5 file, written under a temporary name and renamed):

- the world as a scene (`World.to_scene`: particles with their state to every bit, masses,
  radii, pinned, species and own materials; forces, colliders, collision settings,
  periodicity, emitters and kill volumes), in the attribute `scene` (TOML);
- the time, the step count, each particle's id and the next id;
- what the Python world keeps per particle: time of death, own colour; the springs' end ids;
- each emitter's progress (particles emitted, births held back) and the state of its four random streams;
- the collision books (totals since collisions were turned on: impacts, energy lost, ...) and
  what the particles gave each collider (`World.collider_books`, summed and in the last step).

What is carried from step to step is written too, to every bit: Verlet's acceleration at the
current state, implicit Euler's last Δv (its warm start), the impulse model's contact records
(each contact of the last step: its solve stage's impulse and whether it carried load) and
where its candidate list was built, with its skin. The
list itself is built again there, so it is rebuilt at the same steps as in the run that wrote
it: a rebuild inside a step moves every path's reference and predicts the impacts again, and
in a dense pile that decides the last bits (the demo's pile at dt = 1 ms, written at step 500,
differed by 0.27 m at step 1500 from a run that wrote none while the list was built afresh;
now it is the same bits). The spring–dashpot model's neighbour list and the particles' order
along space are not written: a checkpoint is a restart point for them. After writing it the
world builds them again, as the world read from it does, so a run resumed from a checkpoint
and the run that wrote it go on bit for bit alike; a run that writes checkpoints is also the
same bits as one that writes none where those decide no bit (tested for every method with
both contact models in a gas under gravity with springs, and for a spring–dashpot world
sorted along space).

A world with a `PythonForce` cannot be written (a Python function is not data); a scene's
duration, fps and render settings come along when the world was loaded from a scene.

Reading one back checks every field first (present, of its type, shape, finite, in range,
consistent with the others; the scene by the scene's validation): a damaged, truncated or
foreign file is one `CheckpointError`, one line naming the file, the field and the value
(see "reading, every field checked" below). `run_plan` reads what a run in progress has
left to do without building its world, for a work estimate (`kinema run --resume`).

Who owns what: the world's methods `World.save_checkpoint` and `World.load_checkpoint` are
defined in `World` and import this module when called; it never imports `kinema.world` (it
builds its world by `scene.build()`), so the dependency goes one way. It reads and writes a
world only through the world's public API and its state, `World._state()` and
`World._restore(state)` (`kinema._state.WorldState`: the engine, each particle's time of
death and colour, the springs' end ids, the emitters, the advisor's books); a run resumed
goes on with the world's own run loop, `World._record`.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from . import _checks
from ._checks import _dtype_words, _type_words, describe
from .contact_record import FIELDS, ContactRecord, offsets_problem
from .emitter import births_until
from .frames import MAX_WORK
from .frames import plan as frames_plan
from .io._files import TrajectoryFileError
from .io._hdf5_heaps import global_heap_problem

FORMAT = "kinema-checkpoint"
VERSION = 2  # 2: the clock's anchor and the run's t0 and duration (frames at exact times)


def save_checkpoint(world: Any, path: str | Path, _run: dict | None = None) -> Path:
    """Write `world` to `path` (see the module doc) and restart its caches; returns the path.
    (`_run`: the progress of `World.run`, written by it; see `resume_run`.)"""
    from . import __version__
    from .io._files import hdf5_file

    path = Path(path)
    state = world._state(sync=True)  # (what was written into the views handed to the engine first)
    scene = world.to_scene()  # a PythonForce raises ValueError here, before anything is written
    core = state.engine
    carry = core.integrator_carry()
    spin_carry = core.spin_carry()
    wall_carry = core.wall_force_carry()
    memory = core.contact_history()
    warm = core.collision_carry()
    calm, island = core.sleep_carry()
    built = core.list_carry()
    with hdf5_file(path) as f:
        f.attrs["format"] = FORMAT
        f.attrs["version"] = VERSION
        f.attrs["kinema"] = __version__
        f.attrs["scene"] = scene.to_toml_string()
        f.attrs["time"] = core.time
        f.attrs["steps"] = core.steps
        # the clock's anchor: the time after k steps is clock_time + (k − clock_steps)·dt
        # (frames at exact times move it: kinema.frames)
        k0, t0, _, landing = core.clock
        if landing is not None:
            raise ValueError("a checkpoint between the steps of a frame cannot be written: write it at a frame (World.run's checkpoint=)")
        f.attrs["clock_steps"] = k0
        f.attrs["clock_time"] = t0
        f.attrs["next_id"] = core.next_id
        f.attrs["warned"] = state.warned
        f.attrs["advised_at"] = state.advised_at
        f.create_dataset("ids", data=np.asarray(core.ids, dtype=np.uint64))
        f.create_dataset("death", data=state.death)
        f.create_dataset("colors", data=state.colors)
        f.create_dataset("spring_ids", data=state.spring_ids)
        f.attrs["emitters"] = json.dumps(
            [
                {
                    "emitted": s.emitted,
                    "dropped": s.dropped,  # (born = emitted - dropped - waiting)
                    "told": s.told,
                    "streams": {name: g.bit_generator.state for name, g in s.rng.items()},
                    # the births held back because their place was taken (floats round-trip
                    # exactly through JSON's shortest repr)
                    "waiting": None if s.waiting is None else {k: v.tolist() for k, v in s.waiting.items()},
                }
                for s in state.emitters
            ]
        )
        if carry is not None:  # Verlet's a or implicit Euler's last Δv, to every bit
            f.create_dataset("integrator_carry", data=carry)
        if spin_carry is not None:  # Verlet's α under the contacts' torques
            f.create_dataset("spin_carry", data=spin_carry)
        if world.spin:  # how far each particle has turned
            f.create_dataset("orientations", data=world.orientations)
        if memory[0] or memory[1]:  # the force models' tangential springs
            pairs, walls = memory
            h = f.create_group("contact_history")
            h.create_dataset("pair_i", data=np.array([p[0] for p in pairs], dtype=np.int64))
            h.create_dataset("pair_j", data=np.array([p[1] for p in pairs], dtype=np.int64))
            h.create_dataset("pair_springs", data=np.array([p[2] for p in pairs], dtype=float).reshape(-1, 7))
            h.create_dataset("wall_particle", data=np.array([w[0] for w in walls], dtype=np.int64))
            h.create_dataset("wall_collider", data=np.array([w[1] for w in walls], dtype=np.int64))
            h.create_dataset("wall_normal", data=np.array([w[2] for w in walls], dtype=float).reshape(-1, 3))
            h.create_dataset("wall_springs", data=np.array([w[3] for w in walls], dtype=float).reshape(-1, 7))
        g = f.create_group("collision_carry")  # the impulse solver's warm start
        g.create_dataset("particle", data=np.array([w[0] for w in warm], dtype=np.int64))
        g.create_dataset("collider", data=np.array([w[1] for w in warm], dtype=bool))
        g.create_dataset("partner", data=np.array([w[2] for w in warm], dtype=np.int64))
        g.create_dataset("impulse", data=np.array([w[3] for w in warm], dtype=float).reshape(-1, 3))
        # whether each carried load at the step's end (an impact on it is then a resting contact)
        g.create_dataset("carried", data=np.array([w[4] for w in warm], dtype=bool))
        # sleeping: each particle's calm time (s) and island (-1: awake); the islands'
        # contacts are in the warm start above
        g.create_dataset("sleep_calm", data=calm)
        g.create_dataset("sleep_island", data=island)
        if built is not None:  # where the candidate list was built, and its skin (m): the
            # resumed run rebuilds it at the same steps, as the run that wrote it does
            g.create_dataset("list_built_at", data=built[0].reshape(-1, 3))
            g.create_dataset("list_skin", data=built[1])
        stats = core.collision_stats()
        if stats is not None:  # the collision books go on where they were
            f.attrs["collision_stats"] = json.dumps(_plain(stats))
            # and what the particles gave each collider, summed and in the last step
            for part, last in (("total", False), ("last", True)):
                for key, a in core.collider_books(last=last).items():  # (World.collider_books, nothing written since the sync)
                    f.create_dataset(f"collider_books/{part}/{key}", data=np.asarray(a, dtype=np.float64))
            if wall_carry is not None:  # a force model's collider forces of the last step (rates)
                for key, a in wall_carry.items():
                    f.create_dataset(f"collider_books/carry/{key}", data=np.asarray(a, dtype=np.float64))
        if _run is not None:
            _write_run(f.create_group("run"), _run)
    core.restart_caches()
    core.restore_collision_carry(warm)
    core.restore_sleep_carry(calm.tolist(), island.tolist())
    if built is not None:
        core.restore_list_carry(built[0].tolist(), built[1])
    if carry is not None:
        core.restore_integrator_carry(carry.tolist())
    if spin_carry is not None:
        core.restore_spin_carry(spin_carry.tolist())
    if wall_carry is not None:
        core.restore_wall_force_carry(wall_carry)
    return path


# -- writing a run in progress --------------------------------------------------------------
# World.run(checkpoint=..., checkpoint_every=...) writes, with the world, how far the run has
# come (frames recorded and to go, steps per frame, how often to write) and the frames it has
# recorded, as plain arrays (no pickle: a checkpoint is data).


def _write_run(g: Any, run: dict) -> None:
    from .trajectory import _stacked_walls

    rec = run["recorder"]
    for key in ("frames_done", "frames_total", "per_frame", "every"):
        g.attrs[key] = int(run[key])
    for key in ("fps", "t0", "duration"):
        g.attrs[key] = float(run[key])
    for key in ("scene_file", "scene_sha256"):  # the scene file the run was started from (kinema run: --resume checks it)
        if run.get(key) is not None:
            g.attrs[key] = str(run[key])
    t, x, v, ke, pot, p, ang, contacts, balance, lost, ids, impacts, virial, kinetic = (list(c) for c in zip(*rec.frames, strict=True))
    counts = np.array([len(i) for i in ids], dtype=np.int64)
    for name, data in (
        ("t", np.array(t)),
        ("kinetic", np.array(ke)),
        ("momentum", np.array(p).reshape(-1, 3)),
        ("angular_momentum", np.array(ang).reshape(-1, 3)),
        ("contacts", np.array(contacts, dtype=np.int64)),
        ("impulse_total", np.array(balance).reshape(-1, 3)),
        ("energy_lost", np.array(lost)),
        ("impacts_total", np.array(impacts, dtype=np.int64)),
        ("virial_total", np.array(virial).reshape(-1, 9)),
        ("kinetic_tensor", np.array(kinetic).reshape(-1, 9)),
        ("counts", counts),
        ("x", np.concatenate(x).reshape(-1, 3)),
        ("v", np.concatenate(v).reshape(-1, 3)),
        ("ids", np.concatenate(ids).astype(np.int64)),
    ):
        g.create_dataset(name, data=data)
    g.attrs["potential"] = json.dumps(pot)
    g.attrs["about"] = json.dumps({k: _plain(v) for k, v in rec.about.items()})
    g.attrs["sets"] = json.dumps([[_plain(a) for a in entry] for entry in rec.sets])
    # a world with spin: each frame's angular velocities (w), orientations (q) and moments of
    # inertia (inertia, a column), rows as x
    for name, key in (("w", "angular_velocities"), ("q", "orientations"), ("inertia", "inertia")):
        rows = [f.get(key) for f in rec.turning]
        if rows and all(r is not None for r in rows):
            g.create_dataset(name, data=np.concatenate(rows))
    if rec.walls is not None:  # what the particles had given each collider at each frame, (frames, K, 3) N·s
        stacked = _stacked_walls(rec.walls)
        for name, a in stacked.items():
            g.create_dataset(name, data=a if a is not None else np.zeros((len(rec.walls), 0, 3)))
    if rec.contacts:  # each frame's contacts, one table (kinema.contact_record); its presence says the run records them
        record = ContactRecord.from_frames(rec.touching)
        c = g.create_group("contact_record")
        c.create_dataset("offsets", data=record.offsets)
        for name, a in record.values.items():
            c.create_dataset(name, data=a)


def _plain(value: Any) -> Any:
    """JSON-able: arrays as nested lists (floats by repr: every bit), tuples as lists."""
    if isinstance(value, np.ndarray):
        return {"__array__": value.tolist(), "dtype": str(value.dtype)}
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return value.item()
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    return value


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


_INT64_MAX = 2**63 - 1
_TIME_STEPS = 2**53  # beyond this many steps, t = steps·dt no longer grows with every step
_PARTICLE_BYTES = 1024  # a particle's memory in the engine (kinema.runner.ENGINE_BYTES)
_STREAMS = ("position", "velocity", "size", "life")  # an emitter's random streams (kinema.emitter)
_WAITING = {"x": 3, "v": 3, "spawn": 3, "m": 0, "r": 0, "death": 0, "born": 0, "life": 0}  # births held back: vectors, numbers
_STATS_NEEDED = ("contacts", "impacts", "impulses", "solver_sweeps", "islands", "unconverged")
_STATS_LATER = ("resting", "speculative", "bounced", "asleep", "asleep_contacts", "slept", "woke")  # (0 where absent: older checkpoints)
_ABOUT = ("masses", "radii", "ids", "species", "colors", "groups", "springs", "dim", "dt", "method", "periodic", "box_edges", "colliders")
_ABOUT_LATER = ("groups",)  # (absent from checkpoints written before the groups were recorded: the first set's)


def _first_line(e: BaseException) -> str:
    text = str(e).strip()
    return text.splitlines()[0] if text else type(e).__name__


def _scene_error(e: Exception) -> CheckpointError:
    """A checkpoint's scene refused (one line per problem): the first, and how many more."""
    lines = str(e).splitlines() or ["attribute 'scene' is not a valid scene"]
    return CheckpointError(lines[0] + (f" (and {len(lines) - 1} more problems)" if len(lines) > 1 else ""))


def _shape_words(shape: tuple[int | None, ...]) -> str:
    return "(" + ", ".join("n" if s is None else str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"


def _at(field: str, index: tuple[int, ...]) -> str:
    return f"{field}[{', '.join(str(int(i)) for i in index)}]"


class _Reader:
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
                    raise self.invalid(_at(field, index), v, f"it must be {must} ({_type_words(v)} is not)")
                if integer and not -_INT64_MAX <= v <= _INT64_MAX:
                    raise self.invalid(_at(field, index), v, "it must be an integer of 64 bits")
                if not integer and isinstance(v, int) and abs(v) > 2**1000:
                    raise self.invalid(_at(field, index), v, "it must be a number within the range of float64")
                return
            where = _at(field, index) if index else field
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
        """An array as `_plain` writes it, {"__array__": [...], "dtype": "..."}: `kind`
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
            raise self.invalid(_at(field, (bad,)), data[bad], f"it must be a name ({_type_words(data[bad])} is not)")
        return np.array(data, dtype=str)

    def each(self, field: str, a: np.ndarray, ok: np.ndarray, allowed: str) -> None:
        """Refuses the first element of `a` where `ok` is False, naming its index."""
        ok = np.asarray(ok)
        if ok.size and not ok.all():
            index = np.unravel_index(int(np.argmin(ok)), ok.shape)
            raise self.invalid(_at(field, index), a[index], allowed)

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
            raise self.fail(field, f"is not JSON ({_first_line(e)})") from None

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
            if a.dtype.kind == "u" and a.size and int(a.max()) > _INT64_MAX:
                self.each(field, a, a <= _INT64_MAX, "it must be an integer of 64 bits (below 2**63)")
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
            raise self.fail(field, f"is refused by the engine: {_first_line(e)}") from None


@contextmanager
def _reading(path: Path) -> Iterator[_Reader]:
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
        raise CheckpointError(f"{path}: cannot be read ({_first_line(e)})") from None
    if heaps is not None:
        raise CheckpointError(f"{path}: not a checkpoint that can be read: {heaps}")
    try:
        f = h5py.File(path, "r")
    except Exception as e:  # (an OSError for a file that is not HDF5, or truncated)
        raise CheckpointError(f"{path}: not a checkpoint (cannot be read as HDF5: {_first_line(e)})") from None
    r = _Reader(path, f)
    try:
        with f:
            found = f.attrs.get("format")
            if not (isinstance(found, str) and found == FORMAT):
                raise CheckpointError(f"{path}: not a kinema checkpoint (no attribute 'format' = {FORMAT!r})")
            version = r.int_attr("version", 1, _INT64_MAX, f"a checkpoint version from 1 to {VERSION}")
            if version > VERSION:
                raise CheckpointError(f"{path}: attribute 'version' = {version}: checkpoint version {version} is newer than this kinema reads ({VERSION})")
            r.version = version
            yield r
    except CheckpointError:
        raise
    except MemoryError:
        raise CheckpointError(f"{path}: {r.field} needs more memory than there is to load") from None
    except Exception as e:  # h5py, json or numpy on a damaged file: named by what was being read
        raise CheckpointError(f"{path}: {r.field} cannot be read ({type(e).__name__}: {_first_line(e)}); the checkpoint is damaged") from None


def _scene_and_clock(r: _Reader, read_ids: bool = True) -> dict:
    """The scene (validated as a scene file is), the ids (or their number) and the clock."""
    from .scene import Scene, SceneError

    field, text = r.text("scene")
    try:
        scene = Scene.from_string(text, f"{r.path}: {field}")
    except SceneError as e:
        raise _scene_error(e) from None
    # a list of particles as World.to_scene writes it: counted without building it
    field_ids, ids = r.dataset("ids", "int", (None,), "one id per particle (integers)", read=read_ids)
    n = ids.shape[0] if read_ids else ids[0]
    made = scene.particle_count()
    if made != n:
        raise r.fail(field_ids, f"holds {n} ids but attribute 'scene' makes {made:,} particles; there must be one id per particle")
    r.memory(f"the world of {n:,} particles", n * _PARTICLE_BYTES)
    dt = scene.world.dt
    steps = r.int_attr("steps", 0, _TIME_STEPS, "the steps taken: an integer from 0 to 2**53")
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
    next_id = r.int_attr("next_id", 0, _INT64_MAX, "the id the next particle gets: an integer from 0 to 2**63 - 1")
    if read_ids:
        r.each(field_ids, ids, ids >= 0, "ids are integers >= 0")
        if n > 1:
            k = int(np.argmin(np.diff(ids) > 0)) + 1
            if ids[k] <= ids[k - 1]:
                raise r.invalid(_at(field_ids, (k,)), ids[k], f"ids must increase strictly (ids[{k - 1}] = {ids[k - 1]})")
        if n and next_id <= ids[-1]:
            raise r.invalid("attribute 'next_id'", next_id, f"it must be above every id (the largest is {ids[-1]})")
    return {"scene": scene, "ids": ids, "n": n, "steps": steps, "time": time, "next_id": next_id, "clock": (k0, t0)}


def _load_world(r: _Reader) -> Any:
    """The world of the checkpoint `r` reads, every field checked (see `_reading`)."""
    from .scene import SceneError

    c = _scene_and_clock(r)
    n, ids, next_id, time = c["n"], c["ids"], c["next_id"], c["time"]
    try:
        world = c["scene"].build(f"{r.path}: attribute 'scene'")
    except SceneError as e:
        raise _scene_error(e) from None
    except ValueError as e:
        raise r.fail("attribute 'scene'", f"cannot be built: {_first_line(e)}") from None
    state = world._state()  # the built world's, its fields set from the file below and given back to it
    core = state.engine
    r.engine("dataset 'ids'", core.restore_clock_and_ids, time, c["steps"], ids.tolist(), next_id)
    r.engine("attribute 'clock_steps'", core.restore_clock, *c["clock"])
    # what the Python world keeps per particle
    _, state.death = r.reals("death", (n,), lambda a: ~np.isnan(a), "one time of death per particle, s (inf: none), not NaN")
    _, state.colors = r.reals("colors", (n, 3), lambda a: np.isnan(a) | ((a >= 0) & (a <= 1)), "one colour per particle, r g b in [0, 1] (NaN: none)")
    _, state.spring_ids = r.ints("spring_ids", (None, 2), 0, next_id - 1, f"the ids at the ends of each spring: integers from 0 to next_id - 1 = {next_id - 1}")
    state.warned = r.bool_attr("warned")
    state.advised_at = r.int_attr("advised_at", 0, _INT64_MAX, "the particles when the advisor last looked: an integer >= 0")
    # the collision books: there exactly when collisions are on
    wall_carry = None
    if world.collision_stats() is not None:
        books = _collision_books(r)
        r.engine("attribute 'collision_stats'", core.restore_collision_stats, books["total"], books["last"])
        if "collider_books" in r.f:  # (a checkpoint from before: the world books from zero)
            carried = _carried_books(r, len(world.colliders))
            r.engine("group 'collider_books'", core.restore_collider_books, carried["total"], carried["last"])
            wall_carry = carried.get("carry")
    elif "collision_stats" in r.f.attrs:
        raise r.fail("attribute 'collision_stats'", "is there but attribute 'scene' has collisions off; only a world with collisions has collision books")
    elif "collider_books" in r.f:
        raise r.fail("group 'collider_books'", "is there but attribute 'scene' has collisions off; only a world with collisions has collider books")
    # what is carried from step to step
    carry = None
    if "integrator_carry" in r.f:
        if world.method not in ("verlet", "implicit_euler"):
            raise r.fail("dataset 'integrator_carry'", f"is there but the method is {world.method}; only verlet and implicit_euler carry anything")
        _, carry = r.reals("integrator_carry", (3 * n,), np.isfinite, "3 finite numbers per particle (Verlet's a, m/s², or implicit Euler's last Δv, m/s)")
    spin_carry = None
    if "spin_carry" in r.f:
        if carry is None or world.method != "verlet" or not world.spin:
            raise r.fail("dataset 'spin_carry'", "is there without Verlet's carry in a world with spin; only such a world carries angular accelerations")
        _, spin_carry = r.reals("spin_carry", (3 * n,), np.isfinite, "3 finite numbers per particle (Verlet's α, rad/s²)")
    orientations = None
    if "orientations" in r.f:  # (a checkpoint from before: unturned)
        if not world.spin:
            raise r.fail("dataset 'orientations'", "is there in a world without spin; only particles that turn have orientations")
        _, orientations = r.reals(
            "orientations", (n, 4), lambda a: np.isfinite(a) & (np.linalg.norm(a, axis=-1, keepdims=True) > 0), "a finite quaternion (w, x, y, z) per particle"
        )
    memory: tuple[list, list] = ([], [])
    if "contact_history" in r.f:
        r.group("contact_history")
        springs = "7 finite numbers per contact (the tangential spring's stretch, m, 3; the rolling spring's, m, 3; the twist, rad)"
        _, pi = r.ints("contact_history/pair_i", (None,), 0, n - 1, f"a particle index from 0 to {n - 1}")
        kp = pi.shape[0]
        _, pj = r.ints("contact_history/pair_j", (kp,), 0, n - 1, f"a particle index from 0 to {n - 1}")
        _, ps = r.reals("contact_history/pair_springs", (kp, 7), np.isfinite, springs)
        _, wi = r.ints("contact_history/wall_particle", (None,), 0, n - 1, f"a particle index from 0 to {n - 1}")
        kw = wi.shape[0]
        colliders = len(world.colliders)
        _, wk = r.ints("contact_history/wall_collider", (kw,), 0, max(colliders - 1, 0), f"a collider index below {colliders}")
        _, wn = r.reals("contact_history/wall_normal", (kw, 3), np.isfinite, "3 finite numbers per touch (its normal)")
        _, ws = r.reals("contact_history/wall_springs", (kw, 7), np.isfinite, springs)
        memory = (
            list(zip(pi.tolist(), pj.tolist(), ps.tolist(), strict=True)),
            list(zip(wi.tolist(), wk.tolist(), wn.tolist(), ws.tolist(), strict=True)),
        )
    g = r.group("collision_carry")
    _, particle = r.ints("collision_carry/particle", (None,), 0, n - 1, f"the particle of each contact: an index from 0 to {n - 1}")
    k = particle.shape[0]
    _, collider = r.dataset("collision_carry/collider", "bool", (k,), "one bool per contact (its partner is a collider)")
    field, partner = r.ints("collision_carry/partner", (k,), 0, _INT64_MAX, "the partner of each contact: an index >= 0")
    colliders = len(world.colliders)
    r.each(
        field,
        partner,
        np.where(collider, partner < colliders, partner < n),
        f"the partner of each contact: one of the {n} particles, or of the {colliders} colliders",
    )
    _, impulse = r.reals("collision_carry/impulse", (k, 3), np.isfinite, "each contact's impulse totals, 3 finite numbers, N·s")
    carried: list = [None] * k  # (a checkpoint from before: taken from the impulse)
    if "carried" in g:
        carried = r.dataset("collision_carry/carried", "bool", (k,), "one bool per contact (whether it carried load)")[1].tolist()
    warm = list(zip(particle.tolist(), collider.tolist(), partner.tolist(), impulse.tolist(), carried, strict=True))
    sleep: list[list] = [[], []]
    present = [name in g for name in ("sleep_calm", "sleep_island")]
    if any(present):  # (a checkpoint from before sleeping has neither: everything awake)
        if not all(present):
            missing = "sleep_island" if present[0] else "sleep_calm"
            raise r.fail(f"dataset 'collision_carry/{missing}'", "is missing (sleep_calm and sleep_island go together)")
        m = r.dataset("collision_carry/sleep_calm", "real", (None,), "", read=False)[1][0]
        if m not in (0, n):
            raise r.fail("dataset 'collision_carry/sleep_calm'", f"has {m} values; it must have one per particle ({n}), or none")
        _, calm = r.reals("collision_carry/sleep_calm", (m,), lambda a: np.isfinite(a) & (a >= 0), "each particle's calm time: finite, >= 0 s")
        _, island = r.ints("collision_carry/sleep_island", (m,), -1, _INT64_MAX, "each particle's island: an integer >= 0, or -1 (awake)")
        sleep = [calm.tolist(), island.tolist()]
    built = None
    present = [name in g for name in ("list_built_at", "list_skin")]
    if any(present):  # (a checkpoint from before: the list is built afresh)
        if not all(present):
            missing = "list_skin" if present[0] else "list_built_at"
            raise r.fail(f"dataset 'collision_carry/{missing}'", "is missing (list_built_at and list_skin go together)")
        _, at = r.reals("collision_carry/list_built_at", (n, 3), np.isfinite, "where the candidate list was built: 3 finite numbers per particle, m")
        _, skin = r.reals("collision_carry/list_skin", (), lambda a: np.isfinite(a) & (a > 0), "the candidate list's skin: a finite number > 0, m")
        built = (at.reshape(-1).tolist(), float(skin))
    _restore_emitters(r, state.emitters, world.dim, time)
    if orientations is not None:
        r.engine("dataset 'orientations'", core.set_orientations, np.ascontiguousarray(orientations))
    state.advice_due = False  # the advisor had looked at this state already (its warning is in `warned`)
    world._restore(state)  # (and the views read anew)
    # last: nothing after these may start the caches again
    r.engine("group 'collision_carry'", core.restore_collision_carry, warm)
    r.engine("dataset 'collision_carry/sleep_island'", core.restore_sleep_carry, *sleep)
    if built is not None:
        r.engine("dataset 'collision_carry/list_built_at'", core.restore_list_carry, *built)
    if carry is not None:
        r.engine("dataset 'integrator_carry'", core.restore_integrator_carry, carry.tolist())
    if spin_carry is not None:
        r.engine("dataset 'spin_carry'", core.restore_spin_carry, spin_carry.tolist())
    if wall_carry is not None:
        r.engine("group 'collider_books/carry'", core.restore_wall_force_carry, wall_carry)
    if memory[0] or memory[1]:
        r.engine("group 'contact_history'", core.restore_contact_history, *memory)
    return world


# What the particles gave each collider (`World.collider_books`): each key's unit and width.
_COLLIDER_BOOKS = {"momentum": ("N·s", 3), "angular_momentum": ("N·m·s", 3), "work": ("J", 0), "normal": ("N·s", 3), "tangential": ("N·s", 3)}


def _carried_books(r: _Reader, colliders: int) -> dict:
    """The collider books the world that wrote the checkpoint had (group `collider_books`:
    `total` and `last`, each a dataset per key of `World.collider_books`, one row per
    collider; and with a force model `carry`, the last step's collider forces as rates), for
    the world read from it to go on with."""
    g = r.group("collider_books")
    out: dict = {}
    for part in ("total", "last", "carry"):
        if part == "carry" and "carry" not in g:
            continue
        out[part] = {}
        for key, (unit, width) in _COLLIDER_BOOKS.items():
            shape = (colliders, width) if width else (colliders,)
            when = {"total": "over all steps", "last": "in the last step", "carry": "per second at the last step's end"}[part]
            rate = {"N·s": "N", "N·m·s": "N·m", "J": "W"}[unit] if part == "carry" else unit
            what = f"{when}: one {'vector' if width else 'number'} per collider ({colliders}), finite, {rate}"
            out[part][key] = r.reals(f"collider_books/{part}/{key}", shape, np.isfinite, f"what the particles gave each collider {what}")[1]
    return out


def _collision_books(r: _Reader) -> dict:
    """The collision books (attribute `collision_stats`): "total" and "last", each the
    counts and sums `World.collision_stats` gives."""
    field, books = r.json("collision_stats")
    if not (isinstance(books, dict) and set(books) == {"total", "last"}):
        raise r.invalid(field, books, "it must be {'total': {...}, 'last': {...}}")
    out = {}
    for part, stats in books.items():
        at = f"{field} {part}"
        if not isinstance(stats, dict):
            raise r.invalid(at, stats, "it must be a dict of the collision figures")
        unknown = set(stats) - {*_STATS_NEEDED, *_STATS_LATER, "impulse_balance", "virial", "energy_lost", "max_overlap", "converged"}
        if unknown:
            raise r.fail(f"{at}.{sorted(unknown)[0]}", "is not a collision figure kinema writes")
        clean: dict[str, Any] = {}
        for key in (*_STATS_NEEDED, "impulse_balance", "energy_lost", "max_overlap"):
            if key not in stats:
                raise r.fail(f"{at}.{key}", "is missing")
        for key in (*_STATS_NEEDED, *_STATS_LATER):
            if key in stats:
                clean[key] = r.integer(f"{at}.{key}", stats[key], 0, _INT64_MAX, "a count: an integer >= 0")
        balance = r.array(f"{at}.impulse_balance", stats["impulse_balance"], (3,), "real")
        r.each(f"{at}.impulse_balance", balance, np.isfinite(balance), "3 finite numbers, N·s")
        clean["impulse_balance"] = balance
        if "virial" in stats:  # (older checkpoints lack it: zeros)
            virial = r.array(f"{at}.virial", stats["virial"], (3, 3), "real")
            r.each(f"{at}.virial", virial, np.isfinite(virial), "3 × 3 finite numbers, N·m·s")
            clean["virial"] = virial
        for key in ("energy_lost", "max_overlap"):
            clean[key] = r.real(f"{at}.{key}", stats[key], math.isfinite, "a finite number")
        if "converged" in stats and not isinstance(stats["converged"], bool):
            raise r.invalid(f"{at}.converged", stats["converged"], "it must be true or false")
        out[part] = clean
    return out


def _restore_emitters(r: _Reader, sources: list[Any], dim: int, time: float) -> None:
    """Each emitter's progress and random streams (attribute `emitters`), checked, given to
    the world's emitters at work `sources` (in a `dim`-D world)."""
    field, saved = r.json("emitters")
    if not isinstance(saved, list) or len(saved) != len(sources):
        raise r.invalid(field, saved, f"it must be a list of the {len(sources)} emitters' states (attribute 'scene' has {len(sources)})")
    for k, (source, state) in enumerate(zip(sources, saved, strict=True)):
        at = f"{field} [{k}]"
        if not isinstance(state, dict) or not {"emitted", "streams"} <= set(state) <= {"emitted", "streams", "waiting", "dropped", "told"}:
            raise r.invalid(at, state, "it must be {'emitted': n, 'streams': {...}, 'waiting': ..., 'dropped': n, 'told': bool}")
        due = min(source.due(time), _INT64_MAX)
        emitted = r.integer(
            f"{at}.emitted", state["emitted"], 0, due, f"the particles emitted by t = {time:g} s: an integer from 0 to {due} (those due by then)"
        )
        streams = state["streams"]
        if not (isinstance(streams, dict) and set(streams) == set(_STREAMS)):
            raise r.invalid(f"{at}.streams", streams, f"it must be the states of the streams {', '.join(_STREAMS)}")
        for name in _STREAMS:
            _check_stream(r, f"{at}.streams.{name}", streams[name])
        waiting = state.get("waiting")
        if waiting is not None:
            waiting = _check_waiting(r, f"{at}.waiting", waiting, dim)
        held = 0 if waiting is None else len(waiting["m"])
        dropped = r.integer(
            f"{at}.dropped",
            state.get("dropped", 0),
            0,
            emitted - held,
            f"the births dropped: an integer from 0 to {emitted - held} (emitted, less those waiting)",
        )
        told = state.get("told", False)
        if not isinstance(told, bool):
            raise r.invalid(f"{at}.told", told, "it must be true or false")
        source.emitted, source.waiting, source.dropped, source.told = emitted, waiting, dropped, told
        for name in _STREAMS:
            try:
                source.rng[name].bit_generator.state = streams[name]
            except (ValueError, TypeError, OverflowError) as e:
                raise r.fail(f"{at}.streams.{name}", f"is refused by NumPy: {_first_line(e)}") from None


def _check_stream(r: _Reader, field: str, state: Any) -> None:
    """A PCG64 state as `Generator.bit_generator.state` gives it."""
    keys = {"bit_generator", "state", "has_uint32", "uinteger"}
    if not (isinstance(state, dict) and set(state) == keys):
        raise r.invalid(field, state, "it must be a PCG64 state {'bit_generator': 'PCG64', 'state': {'state', 'inc'}, 'has_uint32', 'uinteger'}")
    if state["bit_generator"] != "PCG64":
        raise r.invalid(f"{field}.bit_generator", state["bit_generator"], "it must be 'PCG64'")
    inner = state["state"]
    if not (isinstance(inner, dict) and set(inner) == {"state", "inc"}):
        raise r.invalid(f"{field}.state", inner, "it must be {'state': s, 'inc': i}")
    r.integer(f"{field}.state.state", inner["state"], 0, 2**128 - 1, "an integer from 0 to 2**128 - 1")
    inc = r.integer(f"{field}.state.inc", inner["inc"], 0, 2**128 - 1, "an odd integer from 1 to 2**128 - 1")
    if inc % 2 == 0:
        raise r.invalid(f"{field}.state.inc", inc, "it must be an odd integer (PCG64's increment)")
    r.integer(f"{field}.has_uint32", state["has_uint32"], 0, 1, "0 or 1")
    r.integer(f"{field}.uinteger", state["uinteger"], 0, 2**32 - 1, "an integer from 0 to 2**32 - 1")


def _check_waiting(r: _Reader, field: str, waiting: Any, dim: int) -> dict[str, np.ndarray]:
    """The births an emitter held back: for each, position, velocity, spawn point (3 each),
    mass, radius, times of death and birth, lifetime."""
    if not (isinstance(waiting, dict) and set(waiting) == set(_WAITING)):
        raise r.invalid(field, waiting, f"it must be null or {{{', '.join(_WAITING)}}}, a list for each")
    m = waiting["m"]
    count = len(m) if isinstance(m, list) else None
    out = {}
    for key, width in _WAITING.items():
        at = f"{field}.{key}"
        a = r.numbers(at, waiting[key], (count, 3) if width else (count,))
        if key in ("life", "death"):
            r.each(at, a, ~np.isnan(a), "numbers of seconds, not NaN (inf: no lifetime)")
        elif key == "m":
            r.each(at, a, np.isfinite(a) & (a > 0), "masses, finite and > 0 kg")
        elif key == "r":
            r.each(at, a, np.isfinite(a) & (a >= 0), "radii, finite and >= 0 m")
        else:
            r.each(at, a, np.isfinite(a), "finite numbers")
        if width and dim == 2:
            r.each(at, a, a[:, 2] == 0, "z = 0 in a 2D world")
        out[key] = a
    return out


# -- a run in progress ------------------------------------------------------------------------


def _run_progress(r: _Reader, dt: float, steps: int) -> dict:
    """How far the run in progress has come (the attributes of the group `run`), checked:
    frames recorded and in all, steps per frame (what `fps` makes of `dt`), how often a
    checkpoint is written; and that it ends within the steps a clock counts."""
    if "run" not in r.f:
        raise CheckpointError(f"{r.path}: a checkpoint of a world, not of a run in progress (no group 'run'; World.run(checkpoint=...) writes those)")
    total = r.int_attr("frames_total", 0, _INT64_MAX, "the frames the run records after its first: an integer >= 0", "run")
    done = r.int_attr("frames_done", 0, total, f"the frames recorded after the first: an integer from 0 to run/frames_total = {total}", "run")
    per_frame = r.int_attr("per_frame", 1, _INT64_MAX, "the steps between frames: an integer >= 1", "run")
    every = r.int_attr("every", 1, _INT64_MAX, "the frames between checkpoints: an integer >= 1", "run")
    fps = r.real_attr("fps", lambda v: math.isfinite(v) and v > 0, "frames per second: a finite number > 0", "run")
    steps_per_frame = 1.0 / fps / dt
    if not steps_per_frame < 2.0**63:
        raise r.invalid("attribute 'run/fps'", fps, f"one frame would take {steps_per_frame:.3g} steps of dt = {dt:g} s (at most 2**63)")
    if r.version < 2:
        raise CheckpointError(
            f"{r.path}: a run in progress written by checkpoint version 1, before frames came at exact times: "
            "load_checkpoint reads its world; run it again from there with World.run"
        )
    t0 = r.real_attr("t0", lambda v: math.isfinite(v) and v >= 0, "the time the run started: a finite number of seconds >= 0", "run")
    duration = r.real_attr("duration", lambda v: math.isfinite(v) and v >= 0, "the run's duration: a finite number of seconds >= 0", "run")
    plan = frames_plan(duration, dt, fps)
    if per_frame != plan.per_frame:
        raise r.invalid(
            "attribute 'run/per_frame'",
            per_frame,
            f"the run records a frame every ⌈1/(fps·dt)⌉ = {plan.per_frame} steps (run/fps = {fps:g}, dt = {dt:g} s)",
        )
    if total != plan.frames:
        raise r.invalid(
            "attribute 'run/frames_total'",
            total,
            f"a run of run/duration = {describe(duration)} s at run/fps = {fps:g} records {plan.frames} frames after its first",
        )
    end = steps + (total - done) * per_frame + plan.tail
    if end > _TIME_STEPS:
        raise r.invalid(
            "attribute 'run/frames_total'",
            total,
            f"the run would end after {end:.3g} steps ({total - done} frames to go × {per_frame} steps from step {steps}), more than 2**53, "
            "where t = steps·dt no longer grows with every step",
        )
    source = {}  # the scene file kinema run started the run from, and its scene's hash (absent from a run started in Python)
    for key in ("scene_file", "scene_sha256"):
        value = r.f["run"].attrs.get(key)
        source[key] = value.decode(errors="replace") if isinstance(value, bytes) else (None if value is None else str(value))
    return {"frames_done": done, "frames_total": total, "per_frame": per_frame, "every": every, "fps": fps, "t0": t0, "duration": duration, **source}


def _read_run(r: _Reader, world: Any, time: float, steps: int) -> dict:
    """The run in progress: its progress and the frames it has recorded, every one checked
    (`World.run` records them: `kinema.trajectory._Recorder`)."""
    from .collider_descriptions import _describe_colliders
    from .trajectory import Trajectory

    run = _run_progress(r, world.dt, steps)
    frames = run["frames_done"] + 1
    field_t, t = r.reals("run/t", (frames,), np.isfinite, f"the time of each frame recorded (run/frames_done + 1 = {frames}), finite, s")
    if frames > 1:
        k = int(np.argmin(np.diff(t) > 0)) + 1
        if t[k] <= t[k - 1]:
            raise r.invalid(_at(field_t, (k,)), t[k], f"the times of the frames must increase (t[{k - 1}] = {describe(t[k - 1])})")
    if t[-1] > time:
        raise r.invalid(_at(field_t, (frames - 1,)), t[-1], f"the last frame cannot be after attribute 'time' = {describe(time)} s")
    finite = np.isfinite
    _, kinetic = r.reals("run/kinetic", (frames,), lambda a: finite(a) & (a >= 0), "each frame's kinetic energy: finite, >= 0 J")
    _, momentum = r.reals("run/momentum", (frames, 3), finite, "each frame's momentum: 3 finite numbers")
    _, angular = r.reals("run/angular_momentum", (frames, 3), finite, "each frame's angular momentum: 3 finite numbers")
    _, contacts = r.ints("run/contacts", (frames,), 0, _INT64_MAX, "each frame's number of contacts: an integer >= 0")
    _, balance = r.reals("run/impulse_total", (frames, 3), finite, "each frame's impulse total: 3 finite numbers")
    _, lost = r.reals("run/energy_lost", (frames,), finite, "each frame's energy taken by the collisions: finite, J")
    # (checkpoints written before these were recorded lack all three: zeros)
    if any(f"run/{name}" in r.f for name in ("impacts_total", "virial_total", "kinetic_tensor")):
        _, impacts = r.ints("run/impacts_total", (frames,), 0, _INT64_MAX, "the impacts up to each frame: integers >= 0")
        _, virial = r.reals("run/virial_total", (frames, 9), finite, "the virial summed up to each frame: 9 finite numbers, N m s")
        _, kinetic_tensor = r.reals("run/kinetic_tensor", (frames, 9), finite, "each frame's sum of m v v: 9 finite numbers, J")
    else:
        impacts, virial, kinetic_tensor = np.zeros(frames, dtype=np.int64), np.zeros((frames, 9)), np.zeros((frames, 9))
    _, counts = r.ints("run/counts", (frames,), 0, _INT64_MAX, "the particles at each frame: integers >= 0")
    rows = sum(counts.tolist())
    field_x, x = r.reals("run/x", (rows, 3), finite, f"the positions of the particles at each frame ({rows} in all, run/counts), finite")
    field_v, v = r.reals("run/v", (rows, 3), finite, f"the velocities of the particles at each frame ({rows} in all, run/counts), finite")
    if world.dim == 2:
        r.each(field_x, x, x[:, 2] == 0, "z = 0 in a 2D world")
        r.each(field_v, v, v[:, 2] == 0, "z = 0 in a 2D world")
    field_ids, ids = r.ints("run/ids", (rows,), 0, _INT64_MAX, f"the ids of the particles at each frame ({rows} in all, run/counts): integers >= 0")
    cut = np.cumsum(counts)[:-1]
    ids_by_frame = np.split(ids, cut)
    for k, a in enumerate(ids_by_frame):
        if a.size > 1 and not (np.diff(a) > 0).all():
            raise r.fail(field_ids, f"at frame {k}: the ids must increase strictly ({describe(a)})")
    field_pot, pot = r.json("potential", "run")
    if not isinstance(pot, list) or len(pot) != frames:
        raise r.invalid(field_pot, pot, f"it must be a list of {frames} dicts, each frame's potential energy by force")
    for k, energies in enumerate(pot):
        if not isinstance(energies, dict):
            raise r.invalid(f"{field_pot} [{k}]", energies, "it must be a dict {force name: energy in J}")
        for name, value in energies.items():
            r.real(f"{field_pot} [{k}].{name}", value, lambda u: not math.isnan(u), "an energy in J, not NaN")
    sets = _recorded_sets(r, frames, ids_by_frame)
    about = _recorded_about(r, world, sets[0], _describe_colliders)
    turning: list[dict[str, np.ndarray]] = [{} for _ in range(frames)]
    for name, key, width in (("w", "angular_velocities", 3), ("q", "orientations", 4), ("inertia", "inertia", 1)):
        if f"run/{name}" in r.f:
            _, a = r.reals(
                f"run/{name}", (rows, width), finite, f"the {key.replace('_', ' ')} of the particles at each frame ({rows} in all, run/counts), finite"
            )
            for k, part in enumerate(np.split(a, cut)):
                turning[k][key] = part
    record_contacts = "contact_record" in r.group("run")  # (the run records contacts: World.run(record_contacts=True))
    rec = Trajectory._recorder(contacts=record_contacts)
    rec.turning = turning
    rec.walls = _recorded_walls(r, frames, len(world.colliders))
    if record_contacts:
        rec.touching = _recorded_contacts(r, frames)
    rec.frames = list(
        zip(
            t.tolist(),
            np.split(x, cut),
            np.split(v, cut),
            kinetic.tolist(),
            pot,
            list(momentum),
            list(angular),
            contacts.tolist(),
            list(balance),
            lost.tolist(),
            ids_by_frame,
            impacts.tolist(),
            list(virial),
            list(kinetic_tensor),
            strict=True,
        )
    )
    rec.about, rec.sets = about, sets
    run.update(recorder=rec)
    return run


def _recorded_walls(r: _Reader, frames: int, colliders: int) -> list[dict[str, np.ndarray]] | None:
    """What the particles had given each collider at each recorded frame (datasets
    `run/collider_momentum`, `run/collider_normal`, `run/collider_tangential`, (frames, K, 3)
    N·s, K at most the world's colliders): the recorder's `walls`; `None` where the run
    records none (its steps book nothing, or a checkpoint from before)."""
    from .trajectory import COLLIDER_RECORD

    if not any(f"run/{name}" in r.f for name in COLLIDER_RECORD):
        return None
    arrays, k = {}, None
    for name, key in COLLIDER_RECORD.items():
        shape = (frames, k, 3)
        what = f"what the particles had given each collider by each frame (run/frames_done + 1 = {frames}), 3 finite numbers per collider, N·s"
        field, a = r.reals(f"run/{name}", shape, np.isfinite, what)
        if a.shape[1] > colliders:
            raise r.fail(field, f"has rows for {a.shape[1]} colliders; the world has {colliders}")
        arrays[key], k = a, a.shape[1]
    return [{key: a[i] for key, a in arrays.items()} for i in range(frames)]


def _recorded_contacts(r: _Reader, frames: int) -> list[dict[str, np.ndarray]]:
    """Each recorded frame's contacts (group `run/contact_record`: `offsets` (frames + 1,) and a
    column of each `kinema.contact_record.FIELDS` name), checked as a `ContactRecord`."""
    _, offsets = r.ints("run/contact_record/offsets", (frames + 1,), 0, _INT64_MAX, "each frame's first row of the contact table, from 0, never decreasing")
    problem = offsets_problem(offsets)
    if problem is not None:
        raise r.fail("dataset 'run/contact_record/offsets'", problem)
    total = int(offsets[-1])
    values = {}
    for name in r.group("run/contact_record"):
        if name == "offsets":
            continue
        known = FIELDS.get(name)
        if known is None:
            raise r.fail(f"dataset 'run/contact_record/{name}'", f"is not a column of a contact record ({', '.join(FIELDS)})")
        # a vector per contact, or one number (a column the engine gives as a number)
        shape = (total,) if getattr(r.f[f"run/contact_record/{name}"], "ndim", 1) == 1 else (total, None)
        if known.kind == "int":
            _, a = r.ints(f"run/contact_record/{name}", shape, -1, _INT64_MAX, f"the contacts' {name}: integers >= -1")
        elif known.kind == "bool":
            _, a = r.dataset(f"run/contact_record/{name}", "bool", shape, f"the contacts' {name}: a flag per contact")
        else:
            _, a = r.reals(f"run/contact_record/{name}", shape, lambda a: ~np.isinf(a), f"the contacts' {name}: numbers (NaN where not given)")
        values[name] = a
    try:
        record = ContactRecord(offsets, values)
    except ValueError as e:
        raise r.fail("group 'run/contact_record'", str(e)) from None
    return [record.frame(k) for k in range(frames)]


def _recorded_sets(r: _Reader, frames: int, ids_by_frame: list[np.ndarray]) -> list[tuple]:
    """The particle sets recorded (attribute `run/sets`): (ids, masses, radii, species,
    colors, groups) each time the particles changed, in the order the frames show them. A set
    of five (a checkpoint written before the collision groups were recorded) has every
    particle in group 0."""
    field, raw = r.json("sets", "run")
    if not isinstance(raw, list) or not raw:
        raise r.invalid(field, raw, "it must be a list of the particle sets recorded (at least one)")
    sets = []
    for k, entry in enumerate(raw):
        at = f"{field} [{k}]"
        if not isinstance(entry, list) or len(entry) not in (5, 6):
            raise r.invalid(at, entry, "it must be [ids, masses, radii, species, colors, groups] (or, written before the groups were, the first five)")
        ids = r.array(f"{at}[0] (ids)", entry[0], (None,), "int")
        n = ids.shape[0]
        r.each(f"{at}[0] (ids)", ids, ids >= 0, "ids are integers >= 0")
        if n > 1 and not (np.diff(ids) > 0).all():
            raise r.fail(f"{at}[0] (ids)", f"= {describe(ids)} is invalid: ids must increase strictly")
        masses = r.array(f"{at}[1] (masses)", entry[1], (n,), "real")
        r.each(f"{at}[1] (masses)", masses, np.isfinite(masses) & (masses > 0), "masses are finite and > 0 kg")
        radii = r.array(f"{at}[2] (radii)", entry[2], (n,), "real")
        r.each(f"{at}[2] (radii)", radii, np.isfinite(radii) & (radii >= 0), "radii are finite and >= 0 m")
        species = None if entry[3] is None else r.array(f"{at}[3] (species)", entry[3], (n,), "text")
        colors = None
        if entry[4] is not None:
            colors = r.array(f"{at}[4] (colors)", entry[4], (n, 3), "real")
            r.each(f"{at}[4] (colors)", colors, np.isnan(colors) | ((colors >= 0) & (colors <= 1)), "r g b in [0, 1] (NaN: none)")
        groups = np.zeros(n, dtype=np.int64)
        if len(entry) == 6:
            groups = r.array(f"{at}[5] (groups)", entry[5], (n,), "int").astype(np.int64)
            r.each(f"{at}[5] (groups)", groups, (groups >= 0) & (groups <= 31), "collision groups are integers in 0..31")
        sets.append((ids, masses, radii, species, colors, groups))
    # the recorder adds a set whenever a frame's ids differ from the last set's
    j = 0
    for k, ids in enumerate(ids_by_frame):
        if not np.array_equal(ids, sets[j][0]):
            j += 1
            if j == len(sets) or not np.array_equal(ids, sets[j][0]):
                raise r.fail(
                    "dataset 'run/ids'",
                    f"at frame {k}: the particles {describe(ids)} are not those of the set recorded next ({field} [{min(j, len(sets) - 1)}])",
                )
    if j != len(sets) - 1:
        raise r.fail(field, f"has {len(sets)} sets but the frames (dataset 'run/ids') show {j + 1}")
    return sets


def _recorded_about(r: _Reader, world: Any, first: tuple, describe_colliders: Any) -> dict:
    """What the recording knows of the world (attribute `run/about`, `World._trajectory_info`)."""
    field, about = r.json("about", "run")
    if not isinstance(about, dict):
        raise r.invalid(field, about, "it must be a dict of what the trajectory knows of the world")
    for key in about:
        if key not in _ABOUT:
            raise r.fail(f"{field}.{key}", f"is not one of {', '.join(_ABOUT)}")
    for key in _ABOUT:
        if key not in about and key not in _ABOUT_LATER:
            raise r.fail(f"{field}.{key}", "is missing")
    out: dict[str, Any] = {}
    # the particles as the first set has them
    particles = (("ids", "int", 0), ("masses", "real", 0), ("radii", "real", 0), ("species", "text", 0), ("colors", "real", 3), ("groups", "int", 0))
    for k, (key, kind, width) in enumerate(particles):
        if key not in about:  # (an older checkpoint's: the first set's zeros)
            out[key] = first[k]
            continue
        value = about[key]
        n = first[0].shape[0]
        a = None if value is None else r.array(f"{field}.{key}", value, (n, 3) if width else (n,), kind)
        same = (a is None) == (first[k] is None) and (a is None or np.array_equal(a, first[k], equal_nan=kind == "real"))
        if not same:
            raise r.fail(f"{field}.{key}", f"= {describe(a)} is invalid: it must be the first set's (attribute 'run/sets' [0]: {describe(first[k])})")
        out[key] = a
    springs = about["springs"]
    out["springs"] = None if springs is None else r.array(f"{field}.springs", springs, (None, 2), "int")
    if out["springs"] is not None:
        r.each(f"{field}.springs", out["springs"], out["springs"] >= 0, "ids are integers >= 0")
    for key, value in (("dim", world.dim), ("dt", world.dt), ("method", world.method)):
        if type(about[key]) is not type(value) or about[key] != value:
            raise r.invalid(f"{field}.{key}", about[key], f"it must be the world's ({describe(value)}, attribute 'scene')")
        out[key] = about[key]
    periodic = about["periodic"]
    if periodic is not None and not (isinstance(periodic, list) and len(periodic) == 3 and all(isinstance(p, bool) for p in periodic)):
        raise r.invalid(f"{field}.periodic", periodic, "it must be null or 3 bools")
    out["periodic"] = None if periodic is None else tuple(periodic)
    edges = about["box_edges"]
    out["box_edges"] = None if edges is None else r.array(f"{field}.box_edges", edges, (3,), "real")
    if out["box_edges"] is not None:
        r.each(f"{field}.box_edges", out["box_edges"], np.isfinite(out["box_edges"]) & (out["box_edges"] >= 0), "3 finite numbers >= 0, m")
    colliders = about["colliders"]
    if not isinstance(colliders, list):
        raise r.invalid(f"{field}.colliders", colliders, "it must be a list of collider descriptions")
    from .io.h5md_reader import collider_problem

    try:
        problem = collider_problem([f"[{k}]" for k in range(len(colliders))], describe_colliders(colliders), world.dim)
    except (ValueError, TypeError, KeyError) as e:
        problem = _first_line(e)
    if problem is not None:
        raise r.fail(f"{field}.colliders", f"is invalid: {problem}")
    out["colliders"] = colliders
    return out


def load_checkpoint(path: str | Path) -> Any:
    """The world written by `save_checkpoint` at `path`, ready to go on. Every field is
    checked first; a missing, damaged or foreign file is a `CheckpointError` (a
    `ValueError`), one line naming the file, the field and the value."""
    with _reading(Path(path)) as r:
        return _load_world(r)


def load_run(path: str | Path) -> tuple[Any, dict]:
    """The world of the checkpoint `path` and the run in progress that wrote it (the
    frames recorded, how far it has come), every field checked (`CheckpointError`):
    `resume_run` goes on with it."""
    with _reading(Path(path)) as r:
        world = _load_world(r)
        return world, _read_run(r, world, world.time, world._state().engine.steps)


def resume_run(path: str | Path, callback: Any = None, *, max_work: float | None = MAX_WORK) -> tuple[Any, Any]:
    """Goes on with the `World.run` that wrote the checkpoint `path` (`checkpoint=`),
    writing checkpoints to the same file as it did, to its end; returns `(world,
    trajectory)`: the trajectory of the whole run, the frames before the checkpoint
    included, the same bits as the run never stopped. The checkpoint is checked first, as
    `load_checkpoint` checks it, and the run's progress and frames with it
    (`CheckpointError`). `max_work`: as `World.run`'s, the most particle-steps the rest
    of the run may take (particles now and those the emitters will add × the steps left),
    refused before any step with a
    `ValueError` (`None`: no limit)."""
    limit = _checks.real("max_work", max_work, optional=True)
    if limit is not None and not limit > 0:
        raise ValueError(f"max_work = {describe(max_work)} is invalid: it must be a number of particle-steps > 0, or None for no limit")
    world, run = load_run(path)
    plan = frames_plan(run["duration"], world.dt, run["fps"])
    steps = (run["frames_total"] - run["frames_done"]) * run["per_frame"] + plan.tail
    born = births_until(world._state().emitters, run["t0"] + run["duration"])
    work = float(len(world) + born) * steps
    if limit is not None and work > limit:
        whom = f"{len(world):,} particles" + (f" and up to {born:,} from the emitters" if born else "")
        raise ValueError(
            f"{path}: the rest of the run would take {work:.1e} particle-steps ({whom} × {steps:,} steps of dt = {world.dt:g} s, "
            f"{run['frames_total'] - run['frames_done']:,} frames to go), over max_work = {limit:.1e}; give max_work=None (or a larger number) to run it anyway"
        )
    return world, world._record(run, callback, Path(path))


def run_plan(path: str | Path) -> dict:
    """What the run in progress that wrote the checkpoint `path` has left to do, read and
    checked without building its world (for a work estimate before resuming it: `kinema
    run --resume`): `scene` (a `Scene`), `particles` now, `born` (at most, by the
    emitters until the end), `steps` taken, `time` (s), `frames_done`,
    `frames_total`, `per_frame`, `every`, `fps`, `t0`, `duration`; `scene_file` and
    `scene_sha256`, the scene file `kinema run` started the run from and the hash of its
    scene (`kinema.runner.scene_digest`), or None."""
    with _reading(Path(path)) as r:
        c = _scene_and_clock(r, read_ids=False)
        run = _run_progress(r, c["scene"].world.dt, c["steps"])
    scene, time = c["scene"], c["time"]
    end = run["t0"] + run["duration"]
    try:
        born: float = max(0, scene.emitted_count(end) - scene.emitted_count(time))
    except OverflowError:  # more births than a float counts (rate × time): work no limit allows
        born = math.inf
    return {"scene": scene, "particles": c["n"], "born": born, "steps": c["steps"], "time": time, **run}


def run_progress(path: str | Path) -> tuple[int, int]:
    """(frames recorded, frames in all) of the run in progress that wrote `path`."""
    plan = run_plan(path)
    return plan["frames_done"], plan["frames_total"]
