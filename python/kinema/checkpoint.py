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
(`kinema._checkpoint_reader`: "reading, every field checked"). `run_plan` reads what a run in progress has
left to do without building its world, for a work estimate (`kinema run --resume`).

Who owns what: the world's methods `World.save_checkpoint` and `World.load_checkpoint` are
defined in `World` and import this module when called; it never imports `kinema.world` (it
builds its world by `scene.build()`), so the dependency goes one way. It reads and writes a
world only through the world's public API and its state, `World._state()` and
`World._restore(state)` (`kinema._state.WorldState`: the engine, each particle's time of
death and colour, the springs' end ids, the emitters, the advisor's books); a run resumed
goes on with the world's own run loop, `World._record`.

This module writes checkpoints and is the public face of reading them; the reading itself is
in three package-internal modules: `kinema._checkpoint_reader` (`CheckpointError`, the file's
`FORMAT` and `VERSION`, re-exported here, and the checked reads of an open checkpoint),
`kinema._checkpoint_world` (the world) and `kinema._checkpoint_run` (a run in progress).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from . import _checks
from ._checkpoint_reader import FORMAT as FORMAT
from ._checkpoint_reader import VERSION as VERSION
from ._checkpoint_reader import CheckpointError as CheckpointError
from ._checkpoint_reader import reading, scene_and_clock
from ._checkpoint_run import read_progress, read_run
from ._checkpoint_world import load_world
from ._checks import describe
from .contact_record import ContactRecord
from .emitter import births_until
from .frames import MAX_WORK
from .frames import plan as frames_plan


def save_checkpoint(world: Any, path: str | Path, _run: dict | None = None) -> Path:
    """Write `world` to `path` (see the module doc) and restart its caches; returns the path.
    (`_run`: the progress of `World.run`, written by it; see `resume_run`.)"""
    from .io._files import hdf5_file

    path = Path(path)
    state = world._state(sync=True)  # (what was written into the views handed to the engine first)
    scene = world.to_scene()  # a PythonForce raises ValueError here, before anything is written
    core = state.engine
    carries = _Carries(core)
    with hdf5_file(path) as f:
        _write_world(f, scene, state, world)
        _write_carries(f, carries, world)
        _write_books(f, core, carries.wall)
        if _run is not None:
            _write_run(f.create_group("run"), _run)
    carries.give_back(core)
    return path


class _Carries:
    """What the engine carries from step to step, taken before the file is written and given
    back after it (the caches restart: module doc)."""

    def __init__(self, core: Any) -> None:
        self.integrator = core.integrator_carry()
        self.spin = core.spin_carry()
        self.wall = core.wall_force_carry()
        self.memory = core.contact_history()
        self.warm = core.collision_carry()
        self.calm, self.island = core.sleep_carry()
        self.built = core.list_carry()

    def give_back(self, core: Any) -> None:
        core.restart_caches()
        core.restore_collision_carry(self.warm)
        core.restore_sleep_carry(self.calm.tolist(), self.island.tolist())
        if self.built is not None:
            core.restore_list_carry(self.built[0].tolist(), self.built[1])
        if self.integrator is not None:
            core.restore_integrator_carry(self.integrator.tolist())
        if self.spin is not None:
            core.restore_spin_carry(self.spin.tolist())
        if self.wall is not None:
            core.restore_wall_force_carry(self.wall)


def _write_world(f: Any, scene: Any, state: Any, world: Any) -> None:
    """The format, the scene, the clock, the ids and what the Python world keeps per particle
    and per emitter."""
    from . import __version__

    core = state.engine
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
    if world.spin:  # how far each particle has turned
        f.create_dataset("orientations", data=world.orientations)


def _write_carries(f: Any, c: _Carries, world: Any) -> None:
    """What the engine carries from step to step, to every bit (module doc)."""
    if c.integrator is not None:  # Verlet's a or implicit Euler's last Δv, to every bit
        f.create_dataset("integrator_carry", data=c.integrator)
    if c.spin is not None:  # Verlet's α under the contacts' torques
        f.create_dataset("spin_carry", data=c.spin)
    if c.memory[0] or c.memory[1]:  # the force models' tangential springs
        pairs, walls = c.memory
        h = f.create_group("contact_history")
        h.create_dataset("pair_i", data=np.array([p[0] for p in pairs], dtype=np.int64))
        h.create_dataset("pair_j", data=np.array([p[1] for p in pairs], dtype=np.int64))
        h.create_dataset("pair_springs", data=np.array([p[2] for p in pairs], dtype=float).reshape(-1, 7))
        h.create_dataset("wall_particle", data=np.array([w[0] for w in walls], dtype=np.int64))
        h.create_dataset("wall_collider", data=np.array([w[1] for w in walls], dtype=np.int64))
        h.create_dataset("wall_normal", data=np.array([w[2] for w in walls], dtype=float).reshape(-1, 3))
        h.create_dataset("wall_springs", data=np.array([w[3] for w in walls], dtype=float).reshape(-1, 7))
    warm = c.warm
    g = f.create_group("collision_carry")  # the impulse solver's warm start
    g.create_dataset("particle", data=np.array([w[0] for w in warm], dtype=np.int64))
    g.create_dataset("collider", data=np.array([w[1] for w in warm], dtype=bool))
    g.create_dataset("partner", data=np.array([w[2] for w in warm], dtype=np.int64))
    g.create_dataset("impulse", data=np.array([w[3] for w in warm], dtype=float).reshape(-1, 3))
    # whether each carried load at the step's end (an impact on it is then a resting contact)
    g.create_dataset("carried", data=np.array([w[4] for w in warm], dtype=bool))
    # sleeping: each particle's calm time (s) and island (-1: awake); the islands'
    # contacts are in the warm start above
    g.create_dataset("sleep_calm", data=c.calm)
    g.create_dataset("sleep_island", data=c.island)
    if c.built is not None:  # where the candidate list was built, and its skin (m): the
        # resumed run rebuilds it at the same steps, as the run that wrote it does
        g.create_dataset("list_built_at", data=c.built[0].reshape(-1, 3))
        g.create_dataset("list_skin", data=c.built[1])


def _write_books(f: Any, core: Any, wall_carry: Any) -> None:
    """The collision books, and what the particles gave each collider (summed, in the last
    step, and a force model's collider forces of the last step)."""
    stats = core.collision_stats()
    if stats is None:
        return
    f.attrs["collision_stats"] = json.dumps(_plain(stats))  # the collision books go on where they were
    for part, last in (("total", False), ("last", True)):
        for key, a in core.collider_books(last=last).items():  # (World.collider_books, nothing written since the sync)
            f.create_dataset(f"collider_books/{part}/{key}", data=np.asarray(a, dtype=np.float64))
    if wall_carry is not None:  # a force model's collider forces of the last step (rates)
        for key, a in wall_carry.items():
            f.create_dataset(f"collider_books/carry/{key}", data=np.asarray(a, dtype=np.float64))


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


def load_checkpoint(path: str | Path) -> Any:
    """The world written by `save_checkpoint` at `path`, ready to go on. Every field is
    checked first; a missing, damaged or foreign file is a `CheckpointError` (a
    `ValueError`), one line naming the file, the field and the value."""
    with reading(Path(path)) as r:
        return load_world(r)


def load_run(path: str | Path) -> tuple[Any, dict]:
    """The world of the checkpoint `path` and the run in progress that wrote it (the
    frames recorded, how far it has come), every field checked (`CheckpointError`):
    `resume_run` goes on with it."""
    with reading(Path(path)) as r:
        world = load_world(r)
        return world, read_run(r, world, world.time, world._state().engine.steps)


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
    with reading(Path(path)) as r:
        c = scene_and_clock(r, read_ids=False)
        run = read_progress(r, c["scene"].world.dt, c["steps"])
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
