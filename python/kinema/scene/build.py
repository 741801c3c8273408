"""Scene -> engine objects: the World a ``Scene`` describes (``build``, which ``Scene.build``
calls), ``load_scene``. This module imports ``schema``, ``tables`` and ``kinema.world``; none
of them imports it (the package does, so every ``Scene`` builds).

``Scene.build`` is written in ``Scene``'s body and calls the ``build`` this module puts in
``schema.BUILDERS`` when it is imported: a scene makes a World and a world makes a scene
(``World.to_scene``, ``World.load_checkpoint``), so an import of this module by the schema
would close the circle schema -> build -> world -> scene.export -> schema (the schema's module
doc). So the schema knows nothing of ``World``, and the world and the checkpoint's reader build
a world by ``scene.build()`` without importing this module (tests/test_no_import_circles.py)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ..colliders import Box, Keyframes, Mesh, Motion, Plane, SphereObstacle
from ..emitter import Emitter, KillBox, KillPlane, KillSphere
from ..forces import Attractor, Drag, Falloff, Gravity, Spring, Turbulence, Vortex, Wind
from ..world import World
from .schema import BUILDERS, Scene, SceneError
from .tables import (
    AttractorForce,
    BoxCollider,
    DragForce,
    EmitterTable,
    FalloffTable,
    FileBlock,
    GravityForce,
    Isotropic,
    KillBoxTable,
    KillSphereTable,
    LatticeBlock,
    ListBlock,
    Maxwell,
    MeshCollider,
    PlaneCollider,
    SpringForce,
    SteadyMotion,
    TurbulenceForce,
    Uniform,
    VortexForce,
    WindForce,
)
from .values import vec3


def build(scene: Scene, source: str = "<scene>") -> World:
    """The World ``scene`` describes (``Scene.build``, which says what it refuses)."""
    dim = scene.world.dim
    w = World(dim=dim, dt=scene.world.dt, method=scene.world.method, spin=scene.world.spin)
    starts: list[tuple[int, int]] = []
    for b, block in enumerate(scene.particles):
        where = f"{source}: particles[{b}]"
        try:
            x, v, m, r, p, e, mu = _particles(block, dim)
            spin = _spin(block, len(m))
            idx = w.add_particles(x, v, m, r, p, e, mu, species=_species(block), group=_groups(block), **spin)
        except ValueError as err:
            raise SceneError(f"{where}: {err}") from None
        starts.append((int(idx[0]), int(idx[-1]) + 1))
    if scene.collisions is not None:
        c = scene.collisions.model_dump(exclude={"periodic", "ignore_groups"})
        try:
            w.set_collisions(**c)
            for a, b in scene.collisions.ignore_groups or []:
                w.set_group_collisions(a, b, False)
        except ValueError as err:
            raise SceneError(f"{source}: collisions: {err}") from None
    for k, col in enumerate(scene.colliders):
        try:
            w.add(_collider(col, dim))
        except ValueError as err:
            raise SceneError(f"{source}: colliders[{k}]: {err}") from None
    for k, f in enumerate(scene.forces):
        try:
            w.add(_force(f, dim, w, starts, scene.particles))
        except ValueError as err:
            raise SceneError(f"{source}: forces[{k}]: {err}") from None
    for key, items, make in (("emitters", scene.emitters, _emitter), ("kill_volumes", scene.kill_volumes, _kill)):
        for k, item in enumerate(items):
            try:
                w.add(make(item))
            except (ValueError, TypeError) as err:
                raise SceneError(f"{source}: {key}[{k}]: {err}") from None
    if scene.collisions is not None and scene.collisions.periodic is not None:
        try:
            w.periodic = scene.collisions.periodic
        except (ValueError, StopIteration) as err:
            raise SceneError(f"{source}: collisions.periodic: {err or 'periodic axes need a box collider'}") from None
    # Particles placed where the contacts cannot resolve them (collide/placement.rs) are the
    # scene's error, said when it is built, as every other of its values is: not at the first step.
    try:
        w._state().engine.check_placement()
    except ValueError as err:
        raise SceneError(f"{source}: particles: {err}") from None
    w.scene = scene
    return w


# ``scene.build()`` calls this module's ``build`` (the module doc: a hook, not an import)
BUILDERS["world"] = build


def load_scene(path: str | Path) -> World:
    """Read, validate and build the scene file ``path``; the world keeps it as ``world.scene``."""
    return Scene.from_toml(path).build(source=str(path))


def _emitter(e: EmitterTable) -> Emitter:
    values = e.model_dump(exclude={"mesh"})
    for name in ("center", "size", "normal", "direction"):
        if values[name] is not None:
            values[name] = vec3(values[name])
    return Emitter(**values, mesh=None if e.mesh is None else _mesh(e.mesh))


def _mesh(c: Any, **more: Any) -> Mesh:
    """The ``kinema.Mesh`` of a mesh table (``MeshShape``: an emitter's mesh, a collider's)."""
    shape = {"up_axis": c.up_axis, "scale": c.scale, "rotation": c.rotation, "translation": c.translation, **more}
    if c.file is not None:
        return Mesh(c.file, **shape)
    return Mesh(vertices=c.vertices, faces=c.faces, **shape)


def _kill(k: Any) -> Any:
    if isinstance(k, KillBoxTable):
        return KillBox(vec3(k.lo), vec3(k.hi))
    if isinstance(k, KillSphereTable):
        return KillSphere(vec3(k.center), k.radius)
    return KillPlane(vec3(k.point), vec3(k.normal))


# -- scene -> engine objects ------------------------------------------------------------------


def _rng(seed: int, stream: int) -> np.random.Generator:
    # one stream per purpose, so changing one rule does not change the others' draws
    return np.random.default_rng([int(seed), stream])


def _positions(block: Any, dim: int) -> np.ndarray:
    if isinstance(block, FileBlock):
        x = block.particles()["positions"]
        return x + np.asarray(vec3(block.translate)) if block.translate is not None else x.copy()
    if isinstance(block, ListBlock):
        return np.array([vec3(p) for p in block.positions])
    if isinstance(block, LatticeBlock):
        counts = [*block.counts, 1][:3]
        spacing = np.broadcast_to(np.asarray(vec3(block.spacing) if isinstance(block.spacing, list) else block.spacing, dtype=float), (3,))
        grid = np.stack(np.meshgrid(*[np.arange(c) for c in counts], indexing="ij"), axis=-1).reshape(-1, 3)
        x = np.asarray(vec3(block.origin)) + grid * spacing
        if block.jitter > 0:
            x = x + _rng(block.seed, 0).uniform(-block.jitter, block.jitter, x.shape)
        if dim == 2:
            x[:, 2] = 0.0
        return x
    lo, hi = np.asarray(vec3(block.lo)), np.asarray(vec3(block.hi))
    rng = _rng(block.seed, 0)
    if not block.min_distance:
        return rng.uniform(lo, hi, (block.count, 3))
    return _spaced(rng, lo, hi, block.count, block.min_distance)


def _spaced(rng: np.random.Generator, lo: np.ndarray, hi: np.ndarray, count: int, d: float) -> np.ndarray:
    """Random sequential addition: uniform points, each kept only if no kept point lies within d;
    in batches of max(count, 256) points, at most 200, and it gives up after a batch that kept
    none (the box is full: random addition jams at about 38 % of the volume for spheres of
    diameter d; a block of 2,000 that fit 688 tried all 200 batches, 10 s, before saying so)."""
    kept = np.empty((count, 3))
    n = 0
    for _ in range(200):
        before = n
        for c in rng.uniform(lo, hi, (max(count, 256), 3)):
            if n == 0 or np.min(np.sum((kept[:n] - c) ** 2, axis=1)) >= d * d:
                kept[n] = c
                n += 1
                if n == count:
                    return kept
        if n == before:
            break
    raise ValueError(f"min_distance = {d}: could place only {n} of {count} particles in the box; enlarge the box or lower count or min_distance")


def _per_particle(name: str, value: Any, n: int, rng: np.random.Generator) -> np.ndarray:
    if isinstance(value, Uniform):
        return rng.uniform(value.min, value.max, n)
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 1 and arr.size != n:
        raise ValueError(f"{name} has {arr.size} values for {n} particles")
    return np.broadcast_to(arr, (n,)).copy()


def _species(block: Any) -> Any:
    """The block's species: a file block's from its file where it has them."""
    if isinstance(block, FileBlock) and block.particles()["species"] is not None:
        return block.particles()["species"]
    return block.species


def _groups(block: Any) -> Any:
    """A block's collision groups: a file block's from its file where the file has them (as
    `World.add_particles_from` takes them), else the block's `group`."""
    if isinstance(block, FileBlock) and block.particles()["groups"] is not None:
        return block.particles()["groups"]
    return block.group


def _particles(block: Any, dim: int) -> tuple:
    x = _positions(block, dim)
    n = len(x)
    m = _per_particle("mass", block.mass, n, _rng(block.seed, 1))
    r = _per_particle("radius", block.radius, n, _rng(block.seed, 2))
    # A file block: the file's masses, radii and velocities where it has them, the block's keys
    # where it has none.
    read = block.particles() if isinstance(block, FileBlock) else {}
    m = read["masses"] if read.get("masses") is not None else m
    r = read["radii"] if read.get("radii") is not None else r
    vel = block.velocity
    if read.get("velocities") is not None:
        v = read["velocities"]
    elif vel is None:
        v = np.zeros((n, 3))
    elif isinstance(vel, Maxwell):
        rng = _rng(block.seed if vel.seed is None else vel.seed, 3)
        sigma = vel.sigma if vel.sigma is not None else np.sqrt(vel.kT / m)
        v = rng.standard_normal((n, 3)) * np.reshape(sigma, (-1, 1))
        if dim == 2:
            v[:, 2] = 0.0
        if vel.zero_momentum and n > 1:
            v -= (m[:, None] * v).sum(axis=0) / m.sum()
    elif isinstance(vel, Isotropic):
        # A normal vector divided by its length is uniform on the sphere (the circle with z = 0).
        rng = _rng(block.seed if vel.seed is None else vel.seed, 3)
        u = rng.standard_normal((n, 3))
        if dim == 2:
            u[:, 2] = 0.0
        v = vel.speed * u / np.linalg.norm(u, axis=1, keepdims=True)
        if vel.zero_momentum and n > 1:
            v -= (m[:, None] * v).sum(axis=0) / m.sum()
    elif vel and isinstance(vel[0], list):
        if len(vel) != n:
            raise ValueError(f"velocity has {len(vel)} vectors for {n} particles")
        v = np.array([vec3(u) for u in vel])
    else:
        if len(vel) not in (2, 3):
            raise ValueError(f"velocity = {vel} is invalid: it must be a vector of 2 or 3 values")
        v = np.broadcast_to(vec3(vel), (n, 3)).copy()
    pinned = np.asarray(block.pinned, dtype=bool)
    if pinned.ndim == 1 and pinned.size != n:
        raise ValueError(f"pinned has {pinned.size} values for {n} particles")
    e = None if block.restitution is None else _per_particle("restitution", block.restitution, n, _rng(block.seed, 4))
    mu = None if block.friction is None else _per_particle("friction", block.friction, n, _rng(block.seed, 5))
    return x, v, m, r, np.broadcast_to(pinned, (n,)), e, mu


def _spin(block: Any, n: int) -> dict[str, Any]:
    """A block's ``angular_velocity`` (one vector [wx, wy, wz], or one per particle, rad/s; a 2D
    world turns about z: [0, 0, wz]) and ``inertia`` (kg m², per particle), where given, as
    ``add_particles`` takes them (which refuses them in a world without spin)."""
    out: dict[str, Any] = {}
    w = block.angular_velocity
    if w is not None:
        if w and isinstance(w[0], list):
            if len(w) != n:
                raise ValueError(f"angular_velocity has {len(w)} vectors for {n} particles")
            if any(len(u) != 3 for u in w):
                raise ValueError("angular_velocity: each vector must have 3 values [wx, wy, wz], rad/s")
            out["angular_velocity"] = np.array(w, dtype=float)
        else:
            if len(w) != 3:
                raise ValueError(f"angular_velocity = {w} is invalid: it must be a vector of 3 values, rad/s")
            out["angular_velocity"] = np.broadcast_to(np.array(w, dtype=float), (n, 3)).copy()
    if block.inertia is not None:
        out["inertia"] = _per_particle("inertia", block.inertia, n, _rng(block.seed, 6))
    return out


def _motion(m: Any) -> Motion | Keyframes | None:
    """A [[colliders]] table's motion as ``kinema.Motion`` or ``kinema.Keyframes`` (2 values of
    a vector: z = 0)."""
    if m is None:
        return None
    if isinstance(m, SteadyMotion):
        return Motion(vec3(m.velocity), list(m.angular_velocity), vec3(m.pivot), m.start)
    translations = None if m.translations is None else [vec3(t) for t in m.translations]
    return Keyframes(list(m.times), translations, None if m.rotations is None else [list(r) for r in m.rotations], vec3(m.pivot))


def _collider(c: Any, dim: int) -> Any:
    s = {"restitution": c.restitution, "friction": c.friction, "motion": _motion(c.motion), "collides_with": c.collides_with}
    if isinstance(c, PlaneCollider):
        return Plane(vec3(c.point), vec3(c.normal), **s)
    if isinstance(c, BoxCollider):
        return Box(list(c.lo), list(c.hi), **s)
    if isinstance(c, MeshCollider):
        return _mesh(c, inside=c.inside, **s)
    return SphereObstacle(vec3(c.center), c.radius, **s)


def _falloff(t: FalloffTable | None) -> Falloff | None:
    """A force's ``falloff`` table as a ``kinema.Falloff`` (vectors of 2 meaning (x, y, 0))."""
    if t is None:
        return None
    vec = {k: vec3(v) for k in ("center", "axis", "half_size") if (v := getattr(t, k)) is not None}
    return Falloff(t.shape, t.law, t.min_distance, t.max_distance, **vec)


def _force(f: Any, dim: int, w: World, starts: list[tuple[int, int]], blocks: list) -> Any:
    if isinstance(f, GravityForce):
        return Gravity(vec3(f.g) if f.g is not None else None)
    if isinstance(f, DragForce):
        return Drag(f.linear, f.quadratic)
    if isinstance(f, AttractorForce):
        return Attractor(vec3(f.point), f.strength, f.softening, falloff=_falloff(f.falloff))
    if isinstance(f, WindForce):
        return Wind(vec3(f.velocity), f.coefficient, falloff=_falloff(f.falloff))
    if isinstance(f, TurbulenceForce):
        return Turbulence(f.strength, f.scale, f.seed, f.time_scale, f.octaves, f.roughness, f.coefficient, _falloff(f.falloff))
    if isinstance(f, VortexForce):
        return Vortex(vec3(f.point), vec3(f.axis), f.strength, f.radius, f.profile, f.coefficient, _falloff(f.falloff))
    if f.rule is None:
        i, j = np.asarray(f.i, dtype=np.int64), np.asarray(f.j, dtype=np.int64)
    else:
        i, j = _spring_rule(f, starts, blocks)
    n = len(w)
    bad = np.flatnonzero((i >= n) | (j >= n))
    if bad.size:
        s = int(bad[0])
        raise ValueError(f"spring {s} joins particles {int(i[s])} and {int(j[s])}, but the scene has {n} particles (indices 0..{n - 1})")
    for name, value in (("k", f.k), ("rest_length", f.rest_length), ("damping", f.damping)):
        if isinstance(value, list) and len(value) != i.size:
            raise ValueError(f"{name} has {len(value)} values for {i.size} springs")
    rest = f.rest_length
    if rest is None:  # the distance at load time, written out so that the scene round-trips
        rest = np.linalg.norm(w.positions[j] - w.positions[i], axis=1)
    return Spring(i, j, f.k, rest, f.damping)


def _spring_rule(f: SpringForce, starts: list[tuple[int, int]], blocks: list) -> tuple[np.ndarray, np.ndarray]:
    start, end = starts[f.block]
    if f.rule == "chain":
        idx = np.arange(start, end)
        return idx[:-1], idx[1:]
    block = blocks[f.block]
    if not isinstance(block, LatticeBlock):
        raise ValueError(f"rule = 'grid' needs a lattice block, but particles[{f.block}] is of type {block.type!r}")
    counts = [*block.counts, 1][:3]
    ids = np.arange(start, end).reshape(counts)
    pairs = []
    for axis in range(3):
        a = np.moveaxis(ids, axis, 0)
        pairs.append((a[:-1].ravel(), a[1:].ravel()))
    if f.diagonals:  # shear springs across each cell of the first two lattice axes
        pairs.append((ids[:-1, :-1].ravel(), ids[1:, 1:].ravel()))
        pairs.append((ids[1:, :-1].ravel(), ids[:-1, 1:].ravel()))
    return np.concatenate([p[0] for p in pairs]), np.concatenate([p[1] for p in pairs])
