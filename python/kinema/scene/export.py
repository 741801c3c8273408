"""World -> scene: ``to_scene`` (``world.to_scene()``), and the ``World`` attributes this
package gives on import (``World.to_scene``, ``World.scene``, ``World.save_checkpoint``,
``World.load_checkpoint``), so that the world module stays free of the scene format."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..checkpoint import load_checkpoint, save_checkpoint
from ..colliders import Box, Plane
from ..emitter import KillBox, KillSphere
from ..forces import Attractor, Drag, Gravity, Spring, Wind
from ..world import World
from .build import _v3
from .schema import Scene
from .tables import EmitterTable

# -- world -> scene ---------------------------------------------------------------------------


def to_scene(world: World) -> Scene:
    """The scene of ``world`` as it is now: one explicit particle list, its forces, colliders
    and settings; duration, fps, render and output options come from ``world.scene`` when
    the world was loaded from one. Each particle's own restitution and friction come from the
    engine; a ``PythonForce`` cannot be written and raises ``ValueError``."""
    old: Scene | None = getattr(world, "scene", None)
    n = len(world)
    inverse = np.asarray(world._core.inverse_masses)
    blocks = []
    if n:
        block: dict[str, Any] = {
            "type": "list",
            "positions": world.positions.tolist(),
            "velocity": world.velocities.tolist(),
            "mass": world.masses.tolist(),
            "radius": list(world._core.radii),
            "pinned": (inverse == 0).tolist(),
        }
        if world.species is not None:
            block["species"] = world.species.tolist()
        own = world._core.particle_materials()  # each particle's own values, as the engine holds them
        if len(own) == n:
            for k, name in enumerate(("restitution", "friction")):
                arr = np.array([np.nan if m[k] is None else m[k] for m in own])
                if not np.all(np.isnan(arr)):
                    block[name] = arr.tolist()
        blocks.append(block)
    forces = []
    spring_offset = 0  # the springs' end ids, in the order the Spring forces were added
    for f in world.forces:
        if isinstance(f, Gravity):
            forces.append({"type": "gravity"} if f.g is None else {"type": "gravity", "g": _v3(np.asarray(f.g, float).tolist())})
        elif isinstance(f, Drag):
            forces.append({"type": "drag", "linear": float(f.linear), "quadratic": float(f.quadratic)})
        elif isinstance(f, Attractor):
            forces.append(
                {"type": "attractor", "point": _v3(np.asarray(f.point, float).tolist()), "strength": float(f.strength), "softening": float(f.softening)}
            )
        elif isinstance(f, Wind):
            forces.append({"type": "wind", "velocity": _v3(np.asarray(f.velocity, float).tolist()), "coefficient": float(f.coefficient)})
        elif isinstance(f, Spring):
            # The springs whose two ends live, at the ends' current indices (particles removed
            # since shifted them; a spring with a dead end died with it).
            count = len(f._args[0])
            ends = world._spring_ids[spring_offset : spring_offset + count]
            spring_offset += count
            ids = world.ids
            at = np.minimum(np.searchsorted(ids, ends), max(len(ids) - 1, 0))
            live = np.all(ids[at] == ends, axis=1) if len(ids) else np.zeros(count, dtype=bool)
            i, j = at[live, 0], at[live, 1]
            rest = f.rest_length
            if rest is None:  # unknown after the fact: the current lengths
                rest = np.linalg.norm(world.positions[j] - world.positions[i], axis=1)
            spring = {"type": "spring", "i": i.tolist(), "j": j.tolist()}
            for name, value in (("k", f.k), ("rest_length", rest), ("damping", f.damping)):
                arr = np.asarray(value, dtype=float)
                if arr.ndim and arr.size == count:
                    arr = arr[live]
                spring[name] = float(arr) if arr.ndim == 0 else arr.tolist()
            forces.append(spring)
        else:
            raise ValueError(f"{type(f).__name__} cannot be written to a scene file (only gravity, drag, spring, attractor and wind can)")
    colliders = []
    for c in world.colliders:
        s = {k: float(v) for k, v in (("restitution", c.restitution), ("friction", c.friction)) if v is not None}
        if isinstance(c, Plane):
            colliders.append({"type": "plane", "point": _v3(list(np.ravel(c.point))), "normal": _v3(list(np.ravel(c.normal))), **s})
        elif isinstance(c, Box):
            colliders.append({"type": "box", "lo": np.ravel(c.lo).astype(float).tolist(), "hi": np.ravel(c.hi).astype(float).tolist(), **s})
        else:
            colliders.append({"type": "sphere", "center": _v3(list(np.ravel(c.center))), "radius": float(c.radius), **s})
    emitters = []
    for source in world._emitters:
        table = EmitterTable.model_fields.keys()
        e = source.emitter
        emitters.append({name: getattr(e, name) for name in table if getattr(e, name) is not None})
        for name in ("center", "size", "normal", "direction"):
            if name in emitters[-1]:
                emitters[-1][name] = np.asarray(emitters[-1][name], float).tolist()
        if isinstance(e.color, (tuple, list, np.ndarray)):
            emitters[-1]["color"] = np.asarray(e.color, float).tolist()
    kills = []
    for k in world._kills:
        if isinstance(k, KillBox):
            kills.append({"type": "box", "lo": _v3(list(np.ravel(k.lo))), "hi": _v3(list(np.ravel(k.hi)))})
        elif isinstance(k, KillSphere):
            kills.append({"type": "sphere", "center": _v3(list(np.ravel(k.center))), "radius": float(k.radius)})
        else:
            kills.append({"type": "plane", "point": _v3(list(np.ravel(k.point))), "normal": _v3(list(np.ravel(k.normal)))})
    data: dict[str, Any] = {
        "world": {"dim": world.dim, "dt": world.dt, "method": world.method},
        "particles": blocks,
        "forces": forces,
        "colliders": colliders,
        "emitters": emitters,
        "kill_volumes": kills,
    }
    if old is not None:
        data["world"].update(duration=old.world.duration, fps=old.world.fps)
        data["render"] = old.render.model_dump(exclude_none=True)
        data["output"] = old.output.model_dump()
    if world.collisions is not None:
        c = {k: v for k, v in world.collisions.items() if v is not None}
        if world.collisions.get("sleep_time", 0.5) is None:
            c["sleep_time"] = float("inf")  # nothing sleeps (TOML has no None)
        if any(world.periodic):
            c["periodic"] = list(world.periodic)
        data["collisions"] = c
    return Scene.from_dict(data, "<world>")


World.to_scene = to_scene  # ``world.to_scene()``; the world module stays free of the scene format
World.save_checkpoint = save_checkpoint  # ``world.save_checkpoint(path)`` (kinema.checkpoint)
World.load_checkpoint = staticmethod(load_checkpoint)  # ``kinema.World.load_checkpoint(path)``
World.scene = None  # a world made in code has no scene; ``load_scene`` sets it on the instance
