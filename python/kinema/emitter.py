"""Emitters and kill volumes: particles born over time at a rate, living for a while, dying.

An `Emitter` is what Blender's particle system, Houdini's POP Source and Niagara call a
source: a shape (a point, a box, a disc, a sphere's surface, or a triangle mesh's faces,
vertices or volume) that emits `rate` particles
per second from `start` to `end`, each with an initial velocity (a direction, a speed, a
cone of spread), a mass, a radius, a colour and a lifetime. A kill volume removes every
particle that enters it (Houdini's POP Kill by bounding region).

Births are exact in time and do not depend on the step: particle k of an emitter is born at
t_k = start + k / rate (while t_k < end). It joins the world at the first step boundary
t ≥ t_k, carried along its initial velocity for the time it has already lived,
x = x_born + v₀ (t − t_k), so that a stream stays a stream at any dt (Houdini's sub-frame
emission). Its random draws come from the emitter's own streams (`numpy.random.PCG64`
seeded by `seed`), one stream per quantity, consumed particle by particle: the k-th
particle is the same whatever the step, the frame rate or the number of threads.

A particle whose place is taken (by another particle, or a collider about its centre) waits
for it, and is born there once it is free, at that step boundary; one still waiting at the
first step boundary at or after `end` is dropped, never born (so no particle is born at or
after `end`), and counted (`World.emitter_stats`, an `EmitterWarning`).

A mesh source (`shape="mesh"`, Blender's "Emit From": Faces, Verts, Volume): `"faces"`, a
triangle drawn with probability ∝ its area, then a point uniform on it by the square-root
rule, x = (1 − √u) a + √u (1 − w) b + √u w c (Turk, "Generating random points in triangles",
Graphics Gems, 1990), the initial direction its normal; `"vertices"`, a vertex of a face drawn
uniformly, the direction its normal (the sum of its faces' normals weighted by their areas);
`"volume"`, uniform inside a closed mesh by rejection: points uniform in its bounding box,
kept where the winding number of the surface about them is 1 (each candidate takes 3 draws of
the position stream, and exactly the candidates up to the last one kept are consumed, so the
k-th particle does not depend on how many are born at once). A face's normal follows its
winding (counter-clockwise seen from the side it points to); a closed mesh's normals point
out of it.

A particle dies at the first step boundary at or after t_k + its lifetime, or at the first
step boundary where it is inside a kill volume. Deaths are removals
(`World.remove_particles`): springs ending on a dead particle die with it, and its id is
never given again.

A mesh source's sampling (`_mesh_source`) and the winding numbers of its volume
(`winding_numbers`) are in `kinema._emitter_mesh`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import _checks
from ._emitter_mesh import _mesh_source, winding_numbers

SHAPES = ("point", "box", "disc", "sphere", "mesh")
BEHIND = 0.01  # an emitter whose births wait for room, more than this fraction of those due, is said at a run's end


class EmitterWarning(UserWarning):
    """An emitter did not keep its rate: births found no room at the source (a particle or a
    collider in their place) and waited, and those still waiting at `end` were dropped. Once
    per emitter as its `end` passes, and at the end of `World.run` for one still behind by more
    than 1 % of the births due; the message gives the counts and the rate achieved."""


BIRTHS_AT_ONCE = 10**8  # particles one emitter may add in one step (about 100 GB of world)
REACH_LIMIT = 1e150  # m and m/s: an emitter's extent from the origin and its fastest speed (the contacts' GEOMETRY_LIMIT)


def _vec3(name: str, value: Any) -> np.ndarray:
    return _checks.real_array(name, value, (3,)).astype(float)


def _unit(v: np.ndarray) -> np.ndarray:
    """`v` (non-zero, finite) divided by its length, scaled first by its largest component so
    that the length cannot overflow ([1e300, 0, -1] has |v|² = inf)."""
    v = v / np.abs(v).max()
    return v / np.linalg.norm(v)


def _colour(value: Any) -> np.ndarray | None:
    """'#rrggbb' or an (r, g, b) triple in [0, 1] → floats in [0, 1]; None stays None."""
    if value is None:
        return None
    if isinstance(value, str):
        text = value.strip()
        if not (len(text) == 7 and text[0] == "#" and all(c in "0123456789abcdefABCDEF" for c in text[1:])):
            raise ValueError(f"color = {value!r} is invalid: use '#rrggbb' (hex) or three numbers in [0, 1]")
        return np.array([int(text[k : k + 2], 16) / 255.0 for k in (1, 3, 5)])
    rgb = _checks.real_array("color", value, (3,)).astype(float)
    if not np.all((rgb >= 0) & (rgb <= 1)):
        raise ValueError(f"color = {rgb.tolist()} is invalid: each of r, g, b must be in [0, 1]")
    return rgb


def _basis(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors perpendicular to the unit `normal` (3,) or normals (n, 3) and to
    each other (crossed with x, or with y where the normal is near x)."""
    near_x = np.abs(normal[..., :1]) >= 0.9
    helper = np.where(near_x, [0.0, 1.0, 0.0], [1.0, 0.0, 0.0])
    e1 = np.cross(normal, helper)
    e1 /= np.linalg.norm(e1, axis=-1, keepdims=True)
    return e1, np.cross(normal, e1)


def _positive(name: str, value: Any, what: str, *, zero: bool = False, optional: bool = False) -> float | None:
    x = _checks.real(name, value, optional=optional)
    if x is None:
        return None
    if not (np.isfinite(x) and (x >= 0 if zero else x > 0)):
        raise ValueError(f"{name} = {x} is invalid: {what}")
    return x


@dataclass(frozen=True)
class Emitter:
    """Emits `rate` particles per second from a shape between `start` and `end` (s).

    Shapes (lengths in m): `"point"` at `center`; `"box"`, uniform inside the box of
    edge lengths `size` (3,) centred at `center`; `"disc"`, uniform on the disc of
    `radius` through `center` perpendicular to `normal` (in 2D: the segment of
    half-length `radius` perpendicular to `normal`); `"sphere"`, uniform on the surface
    of the sphere (a circle in 2D) of `radius` about `center`; `"mesh"` (3D only), from
    `mesh`, a `kinema.Mesh` (placed by its own `up_axis`, `scale`, `rotation`,
    `translation`; not moving) or a mesh file's path (read as `Mesh(path)`), as
    `emit_from` says: `"faces"` (area-weighted, uniform on each triangle), `"vertices"` or
    `"volume"` (uniform inside; a closed mesh only). `center` plays no part there.

    Velocity: `speed` (m/s) ± `speed_spread` (uniform) along `direction`, deviated
    uniformly over the cone of half-angle `spread` (degrees; 180: every direction).
    `direction` None: the disc's `normal`, the sphere's outward normal at the point of
    birth, a mesh face's normal (a vertex's, for `"vertices"`), else +z (+y in 2D).

    Each particle: `particle_radius` (m) ± `radius_spread` (uniform); `mass` (kg), or
    if None `density` (kg/m³) times the sphere's volume 4/3 π r³; `lifetime` (s,
    `inf`: until killed) ± `lifetime_spread` (uniform, s); `color` ('#rrggbb' or r, g,
    b in [0, 1]; drawn by the renderer and the viewer with `color_by="color"`);
    `species` (a name, as in `World.add_particles`); `restitution` and `friction` (the
    particle's own collision values, None: the world's); `group` (the particles' collision
    group, 0..31, as in `World.add_particles`: a jet whose group does not collide with itself
    stays a jet).

    `seed`: the emitter's random streams (position, velocity, size, lifetime); the same
    seed gives the same particles, bit for bit. Add it with `World.add`.
    """

    rate: float
    shape: str = "point"
    center: Any = (0.0, 0.0, 0.0)
    size: Any = (0.0, 0.0, 0.0)
    radius: float = 0.0
    normal: Any = (0.0, 0.0, 1.0)
    start: float = 0.0
    end: float = float("inf")
    direction: Any = None
    speed: float = 0.0
    speed_spread: float = 0.0
    spread: float = 0.0
    particle_radius: float = 0.0
    radius_spread: float = 0.0
    mass: float | None = None
    density: float = 1000.0
    lifetime: float = float("inf")
    lifetime_spread: float = 0.0
    color: Any = None
    species: str | None = None
    restitution: float | None = None
    friction: float | None = None
    group: int = 0
    seed: int = 0
    mesh: Any = None
    emit_from: str = "faces"
    _checked: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        c: dict[str, Any] = {}
        c["rate"] = _positive("rate", self.rate, "particles per second must be a finite number > 0")
        shape = _checks.text("shape", self.shape)
        if shape not in SHAPES:
            raise ValueError(f"shape = {shape!r} is invalid: use one of {', '.join(map(repr, SHAPES))}")
        c["shape"] = shape
        c.update(_mesh_source(shape, self.mesh, self.emit_from))
        c["center"] = _vec3("center", self.center)
        c["size"] = _vec3("size", self.size)
        if shape == "box" and not np.all(c["size"] >= 0):
            raise ValueError(f"size = {c['size'].tolist()} is invalid: a box's edge lengths must be >= 0 m")
        c["radius"] = _positive("radius", self.radius, "the shape's radius must be a finite number >= 0 m", zero=True)
        normal = _vec3("normal", self.normal)
        if not (np.all(np.isfinite(normal)) and np.abs(normal).max() > 0):
            raise ValueError(f"normal = {normal.tolist()} is invalid: it must be a finite, non-zero vector")
        c["normal"] = _unit(normal)
        start = _checks.real("start", self.start)
        end = _checks.real("end", self.end)
        if not np.isfinite(start) or not end > start:
            raise ValueError(f"start = {start}, end = {end} are invalid: start must be finite and end > start (s)")
        c["start"], c["end"] = start, end
        if self.direction is None:
            c["direction"] = None
        else:
            d = _vec3("direction", self.direction)
            if not (np.all(np.isfinite(d)) and np.abs(d).max() > 0):
                raise ValueError(f"direction = {d.tolist()} is invalid: it must be a finite, non-zero vector (or None)")
            c["direction"] = _unit(d)
        c["speed"] = _positive("speed", self.speed, "it must be a finite number >= 0 m/s", zero=True)
        c["speed_spread"] = _positive("speed_spread", self.speed_spread, "it must be a finite number >= 0 m/s", zero=True)
        spread = _checks.real("spread", self.spread)
        if not 0 <= spread <= 180:
            raise ValueError(f"spread = {spread} is invalid: the cone's half-angle must be from 0 to 180 degrees")
        c["spread"] = np.radians(spread)
        # Births at x_born + v0 (t - t_k) must be finite: the shape and the speeds within the
        # contacts' geometry limit (kinema.collide's GEOMETRY_LIMIT, 1e150 m and m/s).
        with np.errstate(over="ignore", invalid="ignore"):
            reach = float(np.abs(c["center"]).max() + np.abs(c["size"]).max() + c["radius"])
            if shape == "mesh":
                reach = max(reach, float(np.abs(c["mesh_vertices"]).max()))
        if not reach <= REACH_LIMIT:
            raise ValueError(
                f"center = {c['center'].tolist()}, size = {c['size'].tolist()}, radius = {c['radius']:g} are invalid: the emitter "
                f"reaches {reach:g} m from the origin; at most {REACH_LIMIT:g} m"
            )
        if not c["speed"] + c["speed_spread"] <= REACH_LIMIT:
            raise ValueError(f"speed = {c['speed']:g}, speed_spread = {c['speed_spread']:g} are invalid: their sum must be at most {REACH_LIMIT:g} m/s")
        c["particle_radius"] = _positive("particle_radius", self.particle_radius, "it must be a finite number >= 0 m", zero=True)
        c["radius_spread"] = _positive("radius_spread", self.radius_spread, "it must be a finite number >= 0 m", zero=True)
        if c["radius_spread"] > c["particle_radius"]:
            raise ValueError(f"radius_spread = {c['radius_spread']} is invalid: it must be <= particle_radius = {c['particle_radius']} m (radii >= 0)")
        c["mass"] = _positive("mass", self.mass, "masses must be finite and > 0 kg", optional=True)
        c["density"] = _positive("density", self.density, "it must be a finite number > 0 kg/m³")
        if c["mass"] is None and c["particle_radius"] - c["radius_spread"] <= 0:
            raise ValueError(
                "mass = None is invalid for particles of radius 0: give the mass (kg), or a particle_radius above radius_spread "
                "so that the mass comes from the density"
            )
        if c["mass"] is None:  # the masses density · 4/3 π r³ must be finite and > 0 for every r drawn
            r_lo, r_hi = c["particle_radius"] - c["radius_spread"], c["particle_radius"] + c["radius_spread"]
            with np.errstate(over="ignore", under="ignore"):
                m_lo, m_hi = (np.float64(c["density"]) * 4.0 / 3.0 * np.pi * np.float64(r) ** 3 for r in (r_lo, r_hi))
            if not (np.isfinite(m_hi) and m_lo > 0):
                raise ValueError(
                    f"density = {c['density']:g} is invalid: with radii from {r_lo:g} to {r_hi:g} m it gives masses from {m_lo:g} to {m_hi:g} kg; "
                    "masses must be finite and > 0 kg (give mass, or a density and radii whose product is)"
                )
        lifetime = _checks.real("lifetime", self.lifetime)
        if not lifetime > 0:
            raise ValueError(f"lifetime = {lifetime} is invalid: it must be > 0 s (inf: until killed)")
        c["lifetime"] = lifetime
        c["lifetime_spread"] = _positive("lifetime_spread", self.lifetime_spread, "it must be a finite number >= 0 s", zero=True)
        if c["lifetime_spread"] >= lifetime:
            raise ValueError(f"lifetime_spread = {c['lifetime_spread']} is invalid: it must be < lifetime = {lifetime} s")
        c["color"] = _colour(self.color)
        c["species"] = None if self.species is None else _checks.species("species", self.species)
        for name in ("restitution", "friction"):
            c[name] = _checks.real(name, getattr(self, name), optional=True)
        c["group"] = _checks.integer("group", self.group, 0, _checks.GROUPS - 1, what=f"a collision group is an integer in 0..{_checks.GROUPS - 1}")
        c["seed"] = _checks.integer("seed", self.seed, 0, 2**63 - 1, what="the seed must be an integer from 0 to 2**63 - 1")
        object.__setattr__(self, "_checked", c)

    def _attach(self, world: Any) -> _Source:
        """The emitter at work in ``world`` (of its ``dim``), which the world keeps (``World.add``)."""
        if world.dim == 2 and self._checked["shape"] == "mesh":
            raise ValueError("shape = 'mesh' is invalid in a 2D world: a triangle mesh is 3D only (emit from a disc, a box or a point)")
        return _Source(self, world.dim)


class _Source:
    """An emitter at work: how many it has emitted, and its random streams."""

    def __init__(self, emitter: Emitter, dim: int) -> None:
        self.emitter, self.c, self.dim = emitter, emitter._checked, dim
        streams = np.random.SeedSequence(self.c["seed"]).spawn(4)
        self.rng = {name: np.random.Generator(np.random.PCG64(s)) for name, s in zip(("position", "velocity", "size", "life"), streams, strict=True)}
        self.emitted = 0  # drawn from the streams: born, waiting or dropped
        self.dropped = 0  # drawn, but found no room before `end` (never born)
        self.told = False  # whether its EmitterWarning at `end` has been given
        # Particles drawn but held back because their place was taken (``hold_back``): each
        # keeps what it was drawn with and is born where it was to be born once that is free,
        # if that is before `end`.
        self.waiting: dict[str, np.ndarray] | None = None

    @property
    def born(self) -> int:
        """The particles this emitter has added to the world."""
        return self.emitted - self.dropped - (0 if self.waiting is None else len(self.waiting["m"]))

    def due(self, t: float) -> int:
        """How many particles have birth times <= t (and < end): k with start + k/rate <= t."""
        c = self.c
        if t < c["start"]:
            return 0
        with np.errstate(over="ignore"):
            count = np.floor((t - c["start"]) * c["rate"]) + 1.0
            if np.isfinite(c["end"]):
                count = min(count, np.ceil((c["end"] - c["start"]) * c["rate"]))
        return int(min(count, 2.0**62))  # (an overflow to inf: more than can be born, see _drawn)

    def births(self, t: float) -> dict[str, Any] | None:
        """The particles born up to time t not yet emitted, carried to t, after those held back
        (born now at their spawn points); None if none. At t >= end those held back are
        dropped instead: born now, they would be born after `end`."""
        waiting, self.waiting = self.waiting, None
        if waiting is not None and not t < self.c["end"]:
            self.dropped += len(waiting["m"])
            waiting = None
        new = self._drawn(t)
        if waiting is not None:
            waiting = {**waiting, "x": waiting["spawn"].copy(), "born": np.full(len(waiting["m"]), t)}
            waiting["death"] = waiting["born"] + waiting["life"]
            new = waiting if new is None else {key: np.concatenate([waiting[key], new[key]]) for key in new}
        return new

    def hold_back(self, births: dict[str, Any], held: np.ndarray, t: float) -> None:
        """Keeps the particles `held` (a mask over `births`) for the next step: their place
        is taken (an emitter never creates a particle inside another). At a step boundary t
        at or after `end` they are dropped: the next chance would be after `end`."""
        if not held.any():
            return
        if t < self.c["end"]:
            self.waiting = {key: value[held] for key, value in births.items()}
        else:
            self.dropped += int(held.sum())

    def finished(self, t: float) -> bool:
        """Whether every particle this emitter will ever emit has been drawn and is born or
        dropped (t at or after `end`, nothing waiting)."""
        return not t < self.c["end"] and self.waiting is None and self.emitted >= self.due(t)

    def stats(self, t: float) -> dict[str, Any]:
        """Its promise and what it kept by time t (s): see `World.emitter_stats`."""
        c = self.c
        until = min(t, c["end"])
        due = self.due(t)
        span = until - c["start"]
        born = self.born
        return {
            "rate": c["rate"],
            "start": c["start"],
            "until": until,
            "due": due,
            "born": born,
            "waiting": 0 if self.waiting is None else len(self.waiting["m"]),
            "dropped": self.dropped,
            "achieved_rate": born / span if span > 0 else float("nan"),
        }

    def shortfall(self, k: int, t: float) -> str:
        """The words of its `EmitterWarning` (emitter k, at time t)."""
        st = self.stats(t)
        head = (
            f"emitter {k}: {st['born']:,} of {st['due']:,} particles born by t = {st['until']:g} s "
            f"({st['achieved_rate']:.4g}/s of the {st['rate']:g}/s asked): no room at the source"
        )
        if st["dropped"]:
            head += f"; {st['dropped']:,} found none before end = {self.c['end']:g} s and were dropped"
        if st["waiting"]:
            head += f"; {st['waiting']:,} wait for it"
        return head + " (births wait while a particle or a collider takes their place: a larger source, a lower rate or a faster speed makes room)"

    def _drawn(self, t: float) -> dict[str, Any] | None:
        """The particles due by t not drawn yet, carried to t; None if none. More than
        `BIRTHS_AT_ONCE` at once is a `MemoryError` (rate = 1e300 asked numpy for 1e297)."""
        due = self.due(t)
        if due - self.emitted > BIRTHS_AT_ONCE:
            raise MemoryError(
                f"the emitter (rate = {self.c['rate']:g} per second) has {due - self.emitted:.3g} particles due by t = {t:g} s, "
                f"more than {BIRTHS_AT_ONCE:.0e} at once: lower the rate or the time step"
            )
        k = np.arange(self.emitted, due)
        if k.size == 0:
            return None
        self.emitted += k.size
        c, n = self.c, k.size
        born = c["start"] + k / c["rate"]
        x, normals = self._positions(n)
        v = self._velocities(n, normals)
        size = self.rng["size"].uniform(-1.0, 1.0, n)
        r = c["particle_radius"] + c["radius_spread"] * size
        m = np.full(n, c["mass"]) if c["mass"] is not None else c["density"] * 4.0 / 3.0 * np.pi * r**3
        life = c["lifetime"] + c["lifetime_spread"] * self.rng["life"].uniform(-1.0, 1.0, n)
        spawn = x.copy()
        x = x + v * (t - born)[:, None]
        if self.dim == 2:
            x[:, 2] = v[:, 2] = spawn[:, 2] = 0.0
        return {"x": x, "v": v, "m": m, "r": r, "death": born + life, "born": born, "life": life, "spawn": spawn}

    def _positions(self, n: int) -> tuple[np.ndarray, np.ndarray | None]:
        """Points of birth (n, 3) and, for a sphere, the outward normals there."""
        c, rng = self.c, self.rng["position"]
        centre, shape = c["center"], c["shape"]
        if shape == "point":
            return np.tile(centre, (n, 1)), None
        if shape == "mesh":
            return self._mesh_positions(n)
        if shape == "box":
            return centre + (rng.random((n, 3)) - 0.5) * c["size"], None
        if shape == "disc":
            if self.dim == 2:
                along = np.array([-c["normal"][1], c["normal"][0], 0.0])
                along /= np.linalg.norm(along) or 1.0
                return centre + c["radius"] * rng.uniform(-1.0, 1.0, (n, 1)) * along, None
            e1, e2 = _basis(c["normal"])
            u = rng.random((n, 2))
            rho, phi = c["radius"] * np.sqrt(u[:, :1]), 2 * np.pi * u[:, 1:]
            return centre + rho * (np.cos(phi) * e1 + np.sin(phi) * e2), None
        # sphere surface: z = cos θ uniform in [-1, 1] (Archimedes), φ uniform; in 2D a circle
        u = rng.random((n, 2))
        phi = 2 * np.pi * u[:, 1]
        if self.dim == 2:
            normals = np.stack([np.cos(phi), np.sin(phi), np.zeros(n)], axis=1)
        else:
            z = 2 * u[:, 0] - 1
            s = np.sqrt(np.maximum(0.0, 1 - z * z))
            normals = np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1)
        return centre + c["radius"] * normals, normals

    def _mesh_positions(self, n: int) -> tuple[np.ndarray, np.ndarray | None]:
        """Points of birth (n, 3) on a mesh source and, from faces or vertices, the normals there."""
        c, rng = self.c, self.rng["position"]
        v, f = c["mesh_vertices"], c["mesh_faces"]
        if c["emit_from"] == "faces":
            u = rng.random((n, 3))  # the face (∝ area), then √u and w of the square-root rule
            cum = c["mesh_area"]
            k = np.minimum(np.searchsorted(cum, u[:, 0] * cum[-1], side="right"), len(cum) - 1)
            s, w = np.sqrt(u[:, 1:2]), u[:, 2:3]
            a, b, cc = (v[f[k, j]] for j in range(3))
            return (1.0 - s) * a + s * (1.0 - w) * b + s * w * cc, c["mesh_normals"][k]
        if c["emit_from"] == "vertices":
            used = c["mesh_used"]
            k = np.minimum((rng.random(n) * len(used)).astype(np.int64), len(used) - 1)
            return v[used[k]].copy(), c["mesh_vertex_normals"][k]
        # volume: candidates uniform in the box, kept inside; the stream is left just after the
        # last candidate used, so that the draws do not depend on n
        lo, hi = c["mesh_box"]
        inside = c["mesh_volume"] / max(float(np.prod(hi - lo)), 1e-300)
        kept: list[np.ndarray] = []
        have = 0
        while have < n:
            start = rng.bit_generator.state
            m = int(min(1e6, np.ceil((n - have) / max(inside, 1e-3) * 1.25) + 16))
            cand = lo + rng.random((m, 3)) * (hi - lo)
            ok = np.abs(winding_numbers(cand, v, f)) > 0.5
            picked = np.flatnonzero(ok)[: n - have]
            if have + len(picked) >= n:  # rewind to just after the last candidate used
                rng.bit_generator.state = start
                rng.random((int(picked[-1]) + 1, 3))
            kept.append(cand[picked])
            have += len(picked)
        return np.concatenate(kept) if kept else np.empty((0, 3)), None

    def _velocities(self, n: int, normals: np.ndarray | None) -> np.ndarray:
        """Initial velocities: speed ± spread along the direction, deviated over the cone."""
        c, rng = self.c, self.rng["velocity"]
        up = np.array([0.0, 1.0, 0.0]) if self.dim == 2 else np.array([0.0, 0.0, 1.0])
        if c["direction"] is not None:
            axes = np.tile(c["direction"], (n, 1))
        elif normals is not None:
            axes = normals
        elif c["shape"] == "disc":
            axes = np.tile(c["normal"], (n, 1))
        else:
            axes = np.tile(up, (n, 1))
        u = rng.random((n, 3))
        speed = c["speed"] + c["speed_spread"] * (2 * u[:, 0] - 1)
        alpha = c["spread"]
        if self.dim == 2:
            # in the plane: an angle uniform in [-α, α] about the axis's direction in xy
            base = np.arctan2(axes[:, 1], axes[:, 0])
            theta = base + alpha * (2 * u[:, 1] - 1)
            d = np.stack([np.cos(theta), np.sin(theta), np.zeros(n)], axis=1)
        else:
            # uniform over the cap of half-angle α: cos θ uniform in [cos α, 1]
            cos_t = 1 - u[:, 1] * (1 - np.cos(alpha))
            sin_t = np.sqrt(np.maximum(0.0, 1 - cos_t * cos_t))
            phi = 2 * np.pi * u[:, 2:]
            e1, e2 = _basis(axes)
            d = cos_t[:, None] * axes + sin_t[:, None] * (np.cos(phi) * e1 + np.sin(phi) * e2)
        return speed[:, None] * d


def births_until(sources: list[Any], t: float) -> int:
    """How many particles the emitters at work ``sources`` (a world's) will add from now to
    time ``t`` (s), those held back for their place included: a work estimate counts each
    from the start, as the command line counts a scene's."""
    return sum(max(0, s.due(t) - s.emitted) + (0 if s.waiting is None else len(s.waiting["m"])) for s in sources)


@dataclass(frozen=True)
class KillBox:
    """Removes every particle whose centre is inside the axis-aligned box [lo, hi] (m)."""

    lo: Any
    hi: Any

    def __post_init__(self) -> None:
        lo, hi = _vec3("lo", self.lo), _vec3("hi", self.hi)
        if not np.all(hi >= lo):
            raise ValueError(f"lo = {lo.tolist()}, hi = {hi.tolist()} are invalid: hi must be >= lo along every axis")

    def _spec(self) -> tuple:
        """What the engine's deaths test (`KillVolume::Box`: lo <= x <= hi along every axis)."""
        return ("box", [float(c) for c in self.lo], [float(c) for c in self.hi])

    def _attach(self, world: Any) -> Any:
        """What the world keeps of it (``World.add``): itself."""
        return self


@dataclass(frozen=True)
class KillSphere:
    """Removes every particle whose centre is inside the sphere of `radius` (m) about `center`."""

    center: Any
    radius: float

    def __post_init__(self) -> None:
        _vec3("center", self.center)
        _positive("radius", self.radius, "it must be a finite number > 0 m")

    def _spec(self) -> tuple:
        """What the engine's deaths test (`KillVolume::Sphere`: |x - center|^2 <= radius^2)."""
        return ("sphere", [float(c) for c in self.center], float(self.radius))

    def _attach(self, world: Any) -> Any:
        """What the world keeps of it (``World.add``): itself."""
        return self


@dataclass(frozen=True)
class KillPlane:
    """Removes every particle whose centre is behind the plane through `point` with
    `normal`: (x − point)·normal < 0 (a floor that swallows what falls through it)."""

    point: Any
    normal: Any

    def __post_init__(self) -> None:
        _vec3("point", self.point)
        if not np.linalg.norm(_vec3("normal", self.normal)) > 0:
            raise ValueError(f"normal = {list(self.normal)} is invalid: it must be a non-zero vector")

    def _spec(self) -> tuple:
        """What the engine's deaths test (`KillVolume::Plane`: (x - point)·normal < 0)."""
        return ("plane", [float(c) for c in self.point], [float(c) for c in self.normal])

    def _attach(self, world: Any) -> Any:
        """What the world keeps of it (``World.add``): itself."""
        return self


KILL_VOLUMES = (KillBox, KillSphere, KillPlane)
