"""Checkpoints: a world written to one file between steps and read back into a world that
goes on exactly as the one that wrote it.

What a checkpoint holds (an HDF5 file, written under a temporary name and renamed):

- the world as a scene (``World.to_scene``: particles with their state to every bit, masses,
  radii, pinned, species and own materials; forces, colliders, collision settings,
  periodicity, emitters and kill volumes), in the attribute ``scene`` (TOML);
- the time, the step count, each particle's id and the next id;
- what the Python world keeps per particle: time of death, own colour; the springs' end ids;
- each emitter's progress (particles emitted, births held back) and the state of its four random streams;
- the collision books (totals since collisions were turned on: impacts, energy lost, ...).

What is carried from step to step is written too, to every bit: Verlet's acceleration at the
current state, implicit Euler's last Δv (its warm start), the impulse solver's warm start (the
impulse totals of the last step's contacts). The lists of candidate pairs and the particles'
order along space are not written: a checkpoint is a restart point for them. After writing it
the world builds them again, as the world read from it does, so a run resumed from a
checkpoint and the run that wrote it go on bit for bit alike. Where the lists decide no bit, a
run that writes checkpoints is also the same bits as one that writes none: tested for every
method with both contact models in a gas under gravity with springs, and for a spring–dashpot
world sorted along space. In a dense pile under the impulse model the rebuilt candidate list
changes the last bits (measured: the demo's pile first differs 54 steps after a checkpoint,
by 2e-6 m, then chaotically); the run and its resumption still agree to every bit.

A world with a ``PythonForce`` cannot be written (a Python function is not data); a scene's
duration, fps and render settings come along when the world was loaded from a scene.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

FORMAT = "kinema-checkpoint"
VERSION = 1


def save_checkpoint(world: Any, path: str | Path, _run: dict | None = None) -> Path:
    """Write ``world`` to ``path`` (see the module doc) and restart its caches; returns the path.
    (``_run``: the progress of ``World.run``, written by it; see ``resume_run``.)"""
    from . import __version__
    from .io._files import hdf5_file

    path = Path(path)
    world._push()
    scene = world.to_scene()  # a PythonForce raises ValueError here, before anything is written
    core = world._core
    carry = core.integrator_carry()
    warm = core.collision_carry()
    calm, island = core.sleep_carry()
    with hdf5_file(path) as f:
        f.attrs["format"] = FORMAT
        f.attrs["version"] = VERSION
        f.attrs["kinema"] = __version__
        f.attrs["scene"] = scene.to_toml_string()
        f.attrs["time"] = core.time
        f.attrs["steps"] = core.steps
        f.attrs["next_id"] = core.next_id
        f.attrs["warned"] = world._warned
        f.attrs["advised_at"] = world._advised_at
        f.create_dataset("ids", data=np.asarray(core.ids, dtype=np.uint64))
        f.create_dataset("death", data=world._death)
        f.create_dataset("colors", data=world._colors)
        f.create_dataset("spring_ids", data=world._spring_ids)
        f.attrs["emitters"] = json.dumps(
            [
                {
                    "emitted": s.emitted,
                    "streams": {name: g.bit_generator.state for name, g in s.rng.items()},
                    # the births held back because their place was taken (floats round-trip
                    # exactly through JSON's shortest repr)
                    "waiting": None if s.waiting is None else {k: v.tolist() for k, v in s.waiting.items()},
                }
                for s in world._emitters
            ]
        )
        if carry is not None:  # Verlet's a or implicit Euler's last Δv, to every bit
            f.create_dataset("integrator_carry", data=carry)
        g = f.create_group("collision_carry")  # the impulse solver's warm start
        g.create_dataset("particle", data=np.array([w[0] for w in warm], dtype=np.int64))
        g.create_dataset("collider", data=np.array([w[1] for w in warm], dtype=bool))
        g.create_dataset("partner", data=np.array([w[2] for w in warm], dtype=np.int64))
        g.create_dataset("impulse", data=np.array([w[3] for w in warm], dtype=float).reshape(-1, 3))
        # sleeping: each particle's calm time (s) and island (-1: awake); the islands'
        # contacts are in the warm start above
        g.create_dataset("sleep_calm", data=calm)
        g.create_dataset("sleep_island", data=island)
        stats = core.collision_stats()
        if stats is not None:  # the collision books go on where they were
            f.attrs["collision_stats"] = json.dumps(_plain(stats))
        if _run is not None:
            _write_run(f.create_group("run"), _run)
    core.restart_caches()
    core.restore_collision_carry(warm)
    core.restore_sleep_carry(calm.tolist(), island.tolist())
    if carry is not None:
        core.restore_integrator_carry(carry.tolist())
    return path


def load_checkpoint(path: str | Path) -> Any:
    """The world written by ``save_checkpoint`` at ``path``, ready to go on."""
    import h5py

    from .scene import Scene

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: no such checkpoint file")
    try:
        f = h5py.File(path, "r")
    except OSError as e:
        raise ValueError(f"{path}: not a checkpoint (cannot be read as HDF5: {e})") from None
    with f:
        if f.attrs.get("format") != FORMAT:
            raise ValueError(f"{path}: not a kinema checkpoint (no format attribute {FORMAT!r})")
        if int(f.attrs["version"]) > VERSION:
            raise ValueError(f"{path}: checkpoint version {int(f.attrs['version'])} is newer than this kinema reads ({VERSION})")
        scene = Scene.from_string(str(f.attrs["scene"]), f"{path} (scene)")
        world = scene.build(str(path))
        world._core.restore_clock_and_ids(float(f.attrs["time"]), int(f.attrs["steps"]), f["ids"][()].tolist(), int(f.attrs["next_id"]))
        world._death = np.asarray(f["death"][()], dtype=float)
        world._colors = np.asarray(f["colors"][()], dtype=float).reshape(-1, 3)
        world._spring_ids = np.asarray(f["spring_ids"][()], dtype=np.int64).reshape(-1, 2)
        if "collision_stats" in f.attrs:
            books = _unplain(json.loads(str(f.attrs["collision_stats"])))
            world._core.restore_collision_stats(books["total"], books["last"])
        carry = f["integrator_carry"][()].tolist() if "integrator_carry" in f else None
        g = f["collision_carry"]
        warm = list(zip(*(g[k][()].tolist() for k in ("particle", "collider", "partner", "impulse")), strict=True))
        # (a checkpoint from before sleeping has none: everything awake)
        sleep = [g[k][()].tolist() if k in g else [] for k in ("sleep_calm", "sleep_island")]
        world._warned = bool(f.attrs["warned"])
        world._advised_at = int(f.attrs["advised_at"])
        for source, saved in zip(world._emitters, json.loads(str(f.attrs["emitters"])), strict=True):
            source.emitted = int(saved["emitted"])
            waiting = saved.get("waiting")
            source.waiting = None if waiting is None else {k: np.asarray(v, dtype=float) for k, v in waiting.items()}
            for name, state in saved["streams"].items():
                source.rng[name].bit_generator.state = state
    world._advice_due = False  # the advisor had looked at this state already (its warning is in `warned`)
    world._new_views()
    # last: nothing after these may start the caches again
    world._core.restore_collision_carry(warm)
    world._core.restore_sleep_carry(*sleep)
    if carry is not None:
        world._core.restore_integrator_carry(carry)
    return world


# -- a run in progress ------------------------------------------------------------------------
# World.run(checkpoint=..., checkpoint_every=...) writes, with the world, how far the run has
# come (frames recorded and to go, steps per frame, how often to write) and the frames it has
# recorded, as plain arrays (no pickle: a checkpoint is data).


def _write_run(g: Any, run: dict) -> None:
    rec = run["recorder"]
    for key in ("frames_done", "frames_total", "per_frame", "every"):
        g.attrs[key] = int(run[key])
    g.attrs["fps"] = float(run["fps"])
    t, x, v, ke, pot, p, ang, contacts, balance, lost, ids = (list(c) for c in zip(*rec.frames, strict=True))
    counts = np.array([len(i) for i in ids], dtype=np.int64)
    for name, data in (
        ("t", np.array(t)),
        ("kinetic", np.array(ke)),
        ("momentum", np.array(p).reshape(-1, 3)),
        ("angular_momentum", np.array(ang).reshape(-1, 3)),
        ("contacts", np.array(contacts, dtype=np.int64)),
        ("impulse_total", np.array(balance).reshape(-1, 3)),
        ("energy_lost", np.array(lost)),
        ("counts", counts),
        ("x", np.concatenate(x).reshape(-1, 3)),
        ("v", np.concatenate(v).reshape(-1, 3)),
        ("ids", np.concatenate(ids).astype(np.int64)),
    ):
        g.create_dataset(name, data=data)
    g.attrs["potential"] = json.dumps(pot)
    g.attrs["about"] = json.dumps({k: _plain(v) for k, v in rec.about.items()})
    g.attrs["sets"] = json.dumps([[_plain(a) for a in entry] for entry in rec.sets])


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


def _unplain(value: Any) -> Any:
    if isinstance(value, dict) and "__array__" in value:
        return np.array(value["__array__"], dtype=value["dtype"])
    if isinstance(value, dict):
        return {k: _unplain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_unplain(v) for v in value]
    return value


def _read_run(g: Any) -> dict:
    from .trajectory import Trajectory

    rec = Trajectory._recorder()
    counts = g["counts"][()]
    cut = np.cumsum(counts)[:-1]
    x, v, ids = (np.split(g[name][()], cut) for name in ("x", "v", "ids"))
    pot = json.loads(str(g.attrs["potential"]))
    rows = zip(
        g["t"][()].tolist(),
        x,
        v,
        g["kinetic"][()].tolist(),
        pot,
        list(g["momentum"][()]),
        list(g["angular_momentum"][()]),
        g["contacts"][()].tolist(),
        list(g["impulse_total"][()]),
        g["energy_lost"][()].tolist(),
        ids,
        strict=True,
    )
    rec.frames = [tuple(r) for r in rows]
    rec.about = _unplain(json.loads(str(g.attrs["about"])))
    if isinstance(rec.about.get("periodic"), list):
        rec.about["periodic"] = tuple(rec.about["periodic"])
    rec.sets = [tuple(_unplain(a) for a in entry) for entry in json.loads(str(g.attrs["sets"]))]
    run = {key: int(g.attrs[key]) for key in ("frames_done", "frames_total", "per_frame", "every")}
    run.update(fps=float(g.attrs["fps"]), recorder=rec)
    return run


def resume_run(path: str | Path, callback: Any = None) -> tuple[Any, Any]:
    """Goes on with the ``World.run`` that wrote the checkpoint ``path`` (``checkpoint=``),
    writing checkpoints to the same file as it did, to its end; returns ``(world,
    trajectory)``: the trajectory of the whole run, the frames before the checkpoint
    included, the same bits as the run never stopped."""
    import h5py

    world = load_checkpoint(path)
    with h5py.File(path, "r") as f:
        if "run" not in f:
            raise ValueError(f"{path}: a checkpoint of a world, not of a run in progress (World.run(checkpoint=...) writes those)")
        run = _read_run(f["run"])
    return world, world._record(run, callback, Path(path))


def run_progress(path: str | Path) -> tuple[int, int]:
    """(frames recorded, frames in all) of the run in progress that wrote ``path``."""
    import h5py

    with h5py.File(path, "r") as f:
        g = f["run"]
        return int(g.attrs["frames_done"]), int(g.attrs["frames_total"])
