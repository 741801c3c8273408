"""World -> scene: ``to_scene``, the body of ``World.to_scene`` (``world.to_scene()``, which
imports it when called). It reads the world through its public API and its state
(``World._state()``, ``kinema._state.WorldState``: the engine, the springs' ends and rest
lengths, the emitters and kill volumes), and imports neither ``kinema.world`` nor the scene's
builder: ``world -> export -> schema`` goes one way (tests/test_no_import_circles.py)."""

from __future__ import annotations

import os
import re
from typing import Any

import numpy as np

from .. import _checks
from ..colliders import Box, Keyframes, Mesh, Motion, Plane
from ..emitter import KillBox, KillSphere
from ..forces import Attractor, Drag, Falloff, Gravity, Spring, Turbulence, Vortex, Wind
from .schema import Scene, SceneError
from .tables import EmitterTable
from .values import vec3

# -- world -> scene ---------------------------------------------------------------------------


def _mesh_table(c: Mesh) -> dict[str, Any]:
    """A mesh's keys in a scene: its file (absolute) and placement where it was read from one
    (the scene stays small), else its vertices as placed (after the transform) and its faces."""
    if c.file is not None:
        return {
            "file": os.path.abspath(c.file),
            "up_axis": c.up_axis,
            "scale": list(c.scale),
            "rotation": list(c.rotation),
            "translation": list(c.translation),
        }
    return {"vertices": c.vertices.tolist(), "faces": c.faces.tolist()}


_SOURCE = "<world>"  # what the messages of to_scene name


def _radius_limit() -> float:
    from ..io._h5md_checks import MAX_RADIUS  # the engine's limit on radii, as the readers apply it

    return MAX_RADIUS


def _check_particles(block: dict[str, Any], dim: int) -> None:
    """Refuses a particle value ``Scene.build`` would refuse when the scene is read back (the
    engine's rules of ``World.add_particles``): finite positions and velocities (z = 0 in 2D),
    masses finite and > 0 kg, radii finite, >= 0 m and at most 1e150 m, species names of one
    word, restitution in [0, 1] and friction finite and >= 0 where set (NaN: the world's).
    Values written into the world's arrays (``world.masses[3] = -1``) reach the engine only
    at its next step; here they are caught before a scene holds them. One line, a
    ``SceneError``: ``<world>: particles[0].mass[3]: -1.0 is invalid: masses must be finite
    and > 0 kg (particle 3)``."""

    def refuse(key: str, i: int, value: Any, rule: str, k: int | None = None) -> None:
        at = f"particles[0].{key}[{i}]" + ("" if k is None else f"[{k}]")
        raise SceneError(f"{_SOURCE}: {at}: {_checks.describe(value)} is invalid: {rule} (particle {i})")

    for key in ("positions", "velocity"):
        a = np.asarray(block[key], dtype=np.float64).reshape(-1, 3)
        bad = ~np.isfinite(a)
        if bad.any():
            i, k = (int(j) for j in np.unravel_index(int(np.argmax(bad)), a.shape))
            refuse(key, i, float(a[i, k]), "coordinates must be finite", k)
        if dim == 2 and (a[:, 2] != 0).any():
            i = int(np.argmax(a[:, 2] != 0))
            refuse(key, i, float(a[i, 2]), "a 2D world keeps z = 0", 2)
    m = np.asarray(block["mass"], dtype=np.float64)
    bad = ~(np.isfinite(m) & (m > 0))
    if bad.any():
        i = int(np.argmax(bad))
        refuse("mass", i, float(m[i]), "masses must be finite and > 0 kg (pin a particle to make it immovable)")
    r = np.asarray(block["radius"], dtype=np.float64)
    bad = ~(np.isfinite(r) & (r >= 0) & (r <= _radius_limit()))
    if bad.any():
        i = int(np.argmax(bad))
        refuse("radius", i, float(r[i]), f"radii must be finite, >= 0 m and <= {_radius_limit():g} m")
    for i, name in enumerate(block.get("species") or []):
        if not isinstance(name, str) or not re.fullmatch(_checks.SPECIES_PATTERN, name):
            refuse("species", i, name, "a species name is one word of letters, digits and _ . + -")
    for key, ok, rule in (
        ("restitution", lambda a: (a >= 0) & (a <= 1), "the coefficient of restitution must be in [0, 1] (NaN: the world's)"),
        ("friction", lambda a: np.isfinite(a) & (a >= 0), "the friction coefficient must be finite and >= 0 (NaN: the world's)"),
    ):
        if key in block:
            a = np.asarray(block[key], dtype=np.float64)
            bad = ~(np.isnan(a) | ok(a))
            if bad.any():
                i = int(np.argmax(bad))
                refuse(key, i, float(a[i]), rule)


def to_scene(world: Any) -> Scene:
    """The scene of ``world`` (a ``kinema.World``) as it is now: one explicit particle list, its forces, colliders
    and settings; duration, fps, render, output and analysis options come from ``world.scene`` when
    the world was loaded from one. Each particle's own restitution and friction come from the
    engine; a ``PythonForce`` cannot be written and raises ``ValueError``.

    What it makes is checked to be a scene kinema reads back and builds: the particles' values
    by the engine's rules (``_check_particles``: a mass written into ``world.masses`` as -1 is
    refused), then the whole scene by its schema. A value that fails is a ``SceneError`` (a
    ``ValueError``) of one line naming the key, the particle index and the value:
    ``<world>: particles[0].mass[3]: -1.0 is invalid: masses must be finite and > 0 kg ...``."""
    old: Scene | None = world.scene
    state = world._state()  # (as it is: what was written into the views is checked here, not handed to the engine)
    data: dict[str, Any] = {
        "world": {"dim": world.dim, "dt": world.dt, "method": world.method, **({"spin": True} if world.spin else {})},
        "particles": _particle_blocks(world, state),
        "forces": _force_tables(world, state),
        "colliders": _collider_tables(world),
        "emitters": _emitter_tables(state),
        "kill_volumes": _kill_tables(state),
    }
    if old is not None:
        data["world"].update(duration=old.world.duration, fps=old.world.fps)
        data["render"] = old.render.model_dump(exclude_none=True)
        data["output"] = old.output.model_dump()
        if old.analysis is not None:
            data["analysis"] = old.analysis.model_dump(exclude_none=True)
    if world.collisions is not None:
        data["collisions"] = _collision_table(world)
    try:
        return Scene.from_dict(data, _SOURCE)
    except SceneError as e:  # one line per problem: the first, and how many more
        lines = str(e).splitlines() or [f"{_SOURCE}: not a valid scene"]
        more = f" (and {len(lines) - 1} more problems)" if len(lines) > 1 else ""
        raise SceneError(lines[0] + more) from None


def _particle_blocks(world: Any, state: Any) -> list[dict[str, Any]]:
    """The world's particles as one explicit list block (none without particles): positions,
    velocities, masses, radii, pins, and where the world has them species, groups, spins and
    each particle's own restitution and friction; checked (`_check_particles`)."""
    n = len(world)
    inverse = np.asarray(state.engine.inverse_masses)
    blocks = []
    if n:
        block: dict[str, Any] = {
            "type": "list",
            "positions": world.positions.tolist(),
            "velocity": world.velocities.tolist(),
            "mass": world.masses.tolist(),
            "radius": list(state.engine.radii),
            "pinned": (inverse == 0).tolist(),
        }
        if world.species is not None:
            block["species"] = world.species.tolist()
        if world.groups.any():
            block["group"] = world.groups.tolist()
        if world.spin:
            block["angular_velocity"] = world.angular_velocities.tolist()
            block["inertia"] = world.inertia.tolist()
        own = state.engine.particle_materials()  # each particle's own values, as the engine holds them
        if len(own) == n:
            for k, name in enumerate(("restitution", "friction")):
                arr = np.array([np.nan if m[k] is None else m[k] for m in own])
                if not np.all(np.isnan(arr)):
                    block[name] = arr.tolist()
        _check_particles(block, world.dim)
        blocks.append(block)
    return blocks


def _force_tables(world: Any, state: Any) -> list[dict[str, Any]]:
    """The world's forces as [[forces]] tables, in the order they were added; a force a scene
    cannot hold (a `PythonForce`) raises `ValueError`."""
    forces = []
    spring_offset = 0  # the springs' end ids, in the order the Spring forces were added
    for index, f in enumerate(world.forces):
        if isinstance(f, Gravity):
            forces.append({"type": "gravity"} if f.g is None else {"type": "gravity", "g": vec3(np.asarray(f.g, float).tolist())})
        elif isinstance(f, Drag):
            forces.append({"type": "drag", "linear": float(f.linear), "quadratic": float(f.quadratic)})
        elif isinstance(f, Attractor):
            forces.append(
                {"type": "attractor", "point": vec3(np.asarray(f.point, float).tolist()), "strength": float(f.strength), "softening": float(f.softening)}
                | _falloff_entry(f.falloff)
            )
        elif isinstance(f, Wind):
            forces.append(
                {"type": "wind", "velocity": vec3(np.asarray(f.velocity, float).tolist()), "coefficient": float(f.coefficient)} | _falloff_entry(f.falloff)
            )
        elif isinstance(f, Turbulence):
            strength, scale, seed, time_scale, octaves, roughness, coefficient, _ = f._args
            entry = {"type": "turbulence", "strength": strength, "scale": scale, "seed": seed, "octaves": octaves, "roughness": roughness}
            entry |= {k: v for k, v in (("time_scale", time_scale), ("coefficient", coefficient)) if v is not None}
            forces.append(entry | _falloff_entry(f.falloff))
        elif isinstance(f, Vortex):
            point, axis, strength, radius, profile, coefficient, _ = f._args
            entry = {"type": "vortex", "point": point, "axis": axis, "strength": strength, "radius": radius, "profile": profile}
            entry |= {} if coefficient is None else {"coefficient": coefficient}
            forces.append(entry | _falloff_entry(f.falloff))
        elif isinstance(f, Spring):
            forces.append(_spring_table(world, state, f, index, spring_offset))
            spring_offset += len(f._args[0])
        else:
            raise ValueError(f"{type(f).__name__} cannot be written to a scene file (only gravity, drag, spring, attractor, wind, turbulence and vortex can)")
    return forces


def _spring_table(world: Any, state: Any, f: Spring, index: int, spring_offset: int) -> dict[str, Any]:
    """A `Spring` force (the `index`-th force; its ends' ids from `spring_offset` in the
    state's `spring_ids`) as a table: the springs whose two ends live, at the ends' current
    indices (particles removed since shifted them; a spring with a dead end died with it)."""
    count = len(f._args[0])
    ends = state.spring_ids[spring_offset : spring_offset + count]
    ids = world.ids
    at = np.minimum(np.searchsorted(ids, ends), max(len(ids) - 1, 0))
    live = np.all(ids[at] == ends, axis=1) if len(ids) else np.zeros(count, dtype=bool)
    i, j = at[live, 0], at[live, 1]
    rest = f.rest_length
    if rest is None:  # the lengths the engine took when the spring was added
        rest = state.spring_rest[index]
    spring = {"type": "spring", "i": i.tolist(), "j": j.tolist()}
    for name, value in (("k", f.k), ("rest_length", rest), ("damping", f.damping)):
        arr = np.asarray(value, dtype=float)
        if arr.ndim and arr.size == count:
            arr = arr[live]
        spring[name] = float(arr) if arr.ndim == 0 else arr.tolist()
    return spring


def _collider_tables(world: Any) -> list[dict[str, Any]]:
    """The world's colliders as [[colliders]] tables, with their materials, motions and groups."""
    colliders = []
    for c in world.colliders:
        s = {k: float(v) for k, v in (("restitution", c.restitution), ("friction", c.friction)) if v is not None}
        if c.motion is not None:
            s["motion"] = _motion_table(c.motion)
        if c.collides_with is not None:
            s["collides_with"] = list(c.collides_with)
        if isinstance(c, Plane):
            colliders.append({"type": "plane", "point": vec3(list(np.ravel(c.point))), "normal": vec3(list(np.ravel(c.normal))), **s})
        elif isinstance(c, Box):
            colliders.append({"type": "box", "lo": np.ravel(c.lo).astype(float).tolist(), "hi": np.ravel(c.hi).astype(float).tolist(), **s})
        elif isinstance(c, Mesh):
            # its file and transform where it was read from one (the scene stays small), else
            # its vertices as the world has them (after the transform) and its faces
            colliders.append({"type": "mesh", **_mesh_table(c), "inside": c.inside, **s})
        else:
            colliders.append({"type": "sphere", "center": vec3(list(np.ravel(c.center))), "radius": float(c.radius), **s})
    return colliders


def _emitter_tables(state: Any) -> list[dict[str, Any]]:
    """The world's emitters (its state's) as [[emitters]] tables: each emitter's keys as given."""
    emitters = []
    for source in state.emitters:
        table = EmitterTable.model_fields.keys()
        e = source.emitter
        emitters.append({name: getattr(e, name) for name in table if getattr(e, name) is not None})
        for name in ("center", "size", "normal", "direction"):
            if name in emitters[-1]:
                emitters[-1][name] = np.asarray(emitters[-1][name], float).tolist()
        if isinstance(e.color, (tuple, list, np.ndarray)):
            emitters[-1]["color"] = np.asarray(e.color, float).tolist()
        if e.mesh is not None:
            emitters[-1]["mesh"] = _mesh_table(source.c["mesh"])
    return emitters


def _kill_tables(state: Any) -> list[dict[str, Any]]:
    """The world's kill volumes (its state's) as [[kill_volumes]] tables."""
    kills = []
    for k in state.kills:
        if isinstance(k, KillBox):
            kills.append({"type": "box", "lo": vec3(list(np.ravel(k.lo))), "hi": vec3(list(np.ravel(k.hi)))})
        elif isinstance(k, KillSphere):
            kills.append({"type": "sphere", "center": vec3(list(np.ravel(k.center))), "radius": float(k.radius)})
        else:
            kills.append({"type": "plane", "point": vec3(list(np.ravel(k.point))), "normal": vec3(list(np.ravel(k.normal)))})
    return kills


def _collision_table(world: Any) -> dict[str, Any]:
    """The world's collision settings as the [collisions] table: sleep_time = inf where
    nothing sleeps, the periodic axes, the pairs of groups that do not collide."""
    c = {k: v for k, v in world.collisions.items() if v is not None}
    if world.collisions.get("sleep_time", 0.5) is None:
        c["sleep_time"] = float("inf")  # nothing sleeps (TOML has no None)
    if any(world.periodic):
        c["periodic"] = list(world.periodic)
    m = world.collision_matrix
    off = [[a, b] for a in range(len(m)) for b in range(a, len(m)) if not m[a, b]]
    if off:
        c["ignore_groups"] = off
    return c


def _falloff_entry(f: Falloff | None) -> dict[str, Any]:
    """``{"falloff": {...}}`` for a force's falloff as it was given (a centre or axis left
    out stays the force's own), or nothing without one."""
    if f is None:
        return {}
    shape, law, r0, r1, center, axis, half = f._args
    table: dict[str, Any] = {"shape": shape, "law": law, "min_distance": r0}
    if r1 != float("inf"):
        table["max_distance"] = r1
    table |= {k: v for k, v in (("center", center), ("axis", axis), ("half_size", half)) if v is not None}
    return {"falloff": table}


def _motion_table(m: Motion | Keyframes) -> dict[str, Any]:
    """A collider's motion as its scene table: steady (velocity, angular_velocity, pivot, and
    its start when not 0) or
    keyframes (times, translations, rotations in degrees as given, pivot; those not given left
    out)."""
    if isinstance(m, Motion):
        table = {"velocity": list(m.velocity), "angular_velocity": list(m.angular_velocity), "pivot": list(m.pivot)}
        if m.start:  # (0 and None: from the scene's time 0)
            table["start"] = m.start
        return table
    out: dict[str, Any] = {"times": list(m.times)}
    for name in ("translations", "rotations"):
        rows = getattr(m, name)
        if rows is not None:
            out[name] = [list(r) for r in rows]
    out["pivot"] = list(m.pivot)
    return out
