"""Checkpoints: a world written to one file between steps and read back into a world that
goes on exactly as the one that wrote it.

What a checkpoint holds (an HDF5 file, written under a temporary name and renamed):

- the world as a scene (``World.to_scene``: particles with their state to every bit, masses,
  radii, pinned, species and own materials; forces, colliders, collision settings,
  periodicity, emitters and kill volumes), in the attribute ``scene`` (TOML);
- the time, the step count, each particle's id and the next id;
- what the Python world keeps per particle: time of death, own colour; the springs' end ids;
- each emitter's progress (particles emitted) and the state of its four random streams.

The method's and the collision stage's caches (Verlet's stored acceleration, implicit Euler's
warm start, the contact lists and the particles' order along space, the impulse solver's warm
start) are not state but they decide the last bits of what follows; rather than write them,
a checkpoint is a restart point: after writing it the world starts its caches again, exactly
as the world read from it does. So a run resumed from a checkpoint and the run that wrote it
go on bit for bit alike. (A run that writes checkpoints may differ in the last bits from one
that writes none.)

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


def save_checkpoint(world: Any, path: str | Path) -> Path:
    """Write ``world`` to ``path`` (see the module doc) and restart its caches; returns the path."""
    import h5py

    from . import __version__
    from .io._files import atomic_file

    path = Path(path)
    world._push()
    scene = world.to_scene()  # a PythonForce raises ValueError here, before anything is written
    core = world._core
    with atomic_file(path) as tmp, h5py.File(tmp, "w") as f:
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
            [{"emitted": s.emitted, "streams": {name: g.bit_generator.state for name, g in s.rng.items()}} for s in world._emitters]
        )
    core.restart_caches()
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
        world._warned = bool(f.attrs["warned"])
        world._advised_at = int(f.attrs["advised_at"])
        for source, saved in zip(world._emitters, json.loads(str(f.attrs["emitters"])), strict=True):
            source.emitted = int(saved["emitted"])
            for name, state in saved["streams"].items():
                source.rng[name].bit_generator.state = state
    world._advice_due = False  # the advisor had looked at this state already (its warning is in `warned`)
    world._new_views()
    return world
