"""Emitters and kill volumes: particles born over time at a rate, living for a while, dying.

An `Emitter` is what Blender's particle system, Houdini's POP Source and Niagara call a
source: a shape (a point, a box, a disc or a sphere's surface) that emits `rate` particles
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

A particle dies at the first step boundary at or after t_k + its lifetime, or at the first
step boundary where it is inside a kill volume. Deaths are removals
(`World.remove_particles`): springs ending on a dead particle die with it, and its id is
never given again.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import _checks

SHAPES = ("point", "box", "disc", "sphere")
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
    of the sphere (a circle in 2D) of `radius` about `center`.

    Velocity: `speed` (m/s) ± `speed_spread` (uniform) along `direction`, deviated
    uniformly over the cone of half-angle `spread` (degrees; 180: every direction).
    `direction` None: the disc's `normal`, the sphere's outward normal at the point of
    birth, else +z (+y in 2D).

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
    _checked: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        c: dict[str, Any] = {}
        c["rate"] = _positive("rate", self.rate, "particles per second must be a finite number > 0")
        shape = _checks.text("shape", self.shape)
        if shape not in SHAPES:
            raise ValueError(f"shape = {shape!r} is invalid: use one of {', '.join(map(repr, SHAPES))}")
        c["shape"] = shape
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

    def _attach(self, world: Any) -> None:
        world._emitters.append(_Source(self, world.dim))


class _Source:
    """An emitter at work: how many it has emitted, and its random streams."""

    def __init__(self, emitter: Emitter, dim: int) -> None:
        self.emitter, self.c, self.dim = emitter, emitter._checked, dim
        streams = np.random.SeedSequence(self.c["seed"]).spawn(4)
        self.rng = {name: np.random.Generator(np.random.PCG64(s)) for name, s in zip(("position", "velocity", "size", "life"), streams, strict=True)}
        self.emitted = 0
        # Particles drawn but held back because their place was taken (``hold_back``): each
        # keeps what it was drawn with and is born where it was to be born once that is free.
        self.waiting: dict[str, np.ndarray] | None = None

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
        (born now at their spawn points); None if none."""
        waiting, self.waiting = self.waiting, None
        new = self._drawn(t)
        if waiting is not None:
            waiting = {**waiting, "x": waiting["spawn"].copy(), "born": np.full(len(waiting["m"]), t)}
            waiting["death"] = waiting["born"] + waiting["life"]
            new = waiting if new is None else {key: np.concatenate([waiting[key], new[key]]) for key in new}
        return new

    def hold_back(self, births: dict[str, Any], held: np.ndarray) -> None:
        """Keeps the particles `held` (a mask over `births`) for the next step: their place
        is taken (an emitter never creates a particle inside another)."""
        if held.any():
            self.waiting = {key: value[held] for key, value in births.items()}

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

    def _attach(self, world: Any) -> None:
        world._kills.append(self)


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

    def _attach(self, world: Any) -> None:
        world._kills.append(self)


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

    def _attach(self, world: Any) -> None:
        world._kills.append(self)


KILL_VOLUMES = (KillBox, KillSphere, KillPlane)
