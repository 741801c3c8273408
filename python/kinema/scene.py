"""Scene files: a whole simulation (particles, forces, colliders, settings, outputs) in TOML.

``Scene.from_toml(path)`` reads and validates a file (pydantic models in strict mode: unknown
keys are errors, and no value is converted to another type but an integer to a float, so
``dt = "1e-3"``, ``mass = true`` or ``count = 2.0`` are refused; values nested more than
``MAX_NESTING`` deep are refused before validation); ``scene.build()`` makes the ``World``;
``load_scene(path)`` does both and keeps the scene on the world (``world.scene``) so that ``kinema run`` knows duration, fps and outputs.
``world.to_scene()`` describes a world as it is now, as one explicit particle list, and
``scene.to_toml(path)`` writes it (tomli-w); reading that file back gives an identical world.

The format, key by key with units, is in docs/scenes.md.
"""

from __future__ import annotations

import difflib
import math
import re
import tomllib
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Discriminator, Field, Tag, ValidationError, field_validator, model_validator

from . import _checks
from .checkpoint import load_checkpoint, save_checkpoint
from .colliders import Box, Plane, SphereObstacle
from .emitter import Emitter, KillBox, KillPlane, KillSphere
from .forces import Attractor, Drag, Gravity, Spring, Wind
from .ode import method_names
from .world import World

__all__ = ["Isotropic", "Maxwell", "Scene", "SceneError", "Uniform", "load_scene", "to_scene"]


class SceneError(ValueError):
    """A scene that cannot be read or built. The message has one line per problem:
    ``<file>: <key path>: <value> is invalid: <what is allowed>``."""

    __module__ = "kinema"


# -- value types ------------------------------------------------------------------------------
# A callable discriminator picks one member of a union, so a wrong value gets one error (that
# member's) rather than one per member. Tags start with "~" so they can be cut out of key paths.


class _Model(BaseModel):
    # strict: no str -> number, bool -> number or float -> int (TOML's 1 is an int, and
    # pydantic's strict mode still takes an int where a float is wanted)
    model_config = ConfigDict(extra="forbid", validate_assignment=True, strict=True)


# Bounds that keep the engine's arithmetic finite and its integers in range (the CLI's work
# estimate, kinema.cli, refuses much smaller runs unless told --force).
MIN_DT = 1e-300  # s; with MIN_FPS, 1/(fps dt) (the steps of one frame) stays finite
MIN_FPS = 1e-6  # frames per second
MAX_PARTICLES = 2**32 - 1  # particles in one block, and the largest particle index + 1
MAX_SEED = 2**64 - 1
MAX_NESTING = 32  # arrays and tables inside each other (a scene's deepest key path is 5 long)


Vec = Annotated[list[float], Field(min_length=2, max_length=3)]
NonNeg = Annotated[float, Field(ge=0)]
Positive = Annotated[float, Field(gt=0)]
SpeciesName = Annotated[str, Field(pattern=f"^{_checks.SPECIES_PATTERN}$")]  # one word, as World.add_particles takes it
Unit = Annotated[float, Field(ge=0, le=1)]
Index = Annotated[int, Field(ge=0, lt=MAX_PARTICLES)]
Count = Annotated[int, Field(ge=1, le=MAX_PARTICLES)]
Seed = Annotated[int, Field(ge=0, le=MAX_SEED)]


def _exact(*allowed: Any) -> Any:
    """A before-validator for a Literal field: pydantic's strict mode still matches 2.0 to 2
    and 0 to False; this takes only values of the listed ones' own types."""

    def check(v: Any) -> Any:
        if not any(type(v) is type(a) and v == a for a in allowed):
            raise ValueError(f"input should be {' or '.join(repr(a) for a in allowed)}")
        return v

    return check


class Uniform(_Model):
    """A value drawn per particle, uniformly in [min, max], with the block's seed."""

    min: float
    max: float

    @model_validator(mode="after")
    def _ordered(self) -> Uniform:
        if not self.min <= self.max:
            raise ValueError(f"min = {self.min} > max = {self.max}; min must be <= max")
        return self


class Maxwell(_Model):
    """Velocities from the Maxwell–Boltzmann distribution: each component normal with standard
    deviation ``sigma`` (m/s), or sqrt(kT/m) for a thermal energy ``kT`` (J)."""

    sigma: NonNeg | None = None
    kT: NonNeg | None = None
    seed: Seed | None = None
    zero_momentum: bool = False

    @model_validator(mode="after")
    def _one(self) -> Maxwell:
        if (self.sigma is None) == (self.kT is None):
            raise ValueError("give exactly one of sigma (m/s) or kT (J)")
        return self


class Isotropic(_Model):
    """Every particle at the same ``speed`` (m/s) in a direction drawn uniformly on the sphere
    (the circle in 2D): a gas far from equilibrium, which collisions take to Maxwell–Boltzmann."""

    speed: NonNeg
    seed: Seed | None = None
    zero_momentum: bool = False


def _kind(v: Any) -> str:
    if isinstance(v, (dict, BaseModel)):  # a table as read, or as a model when written back
        return "~dict"
    if isinstance(v, list):
        return "~list"
    return "~scalar"


def _by_kind(scalar: Any, listed: Any, table: Any = None) -> Any:
    """scalar | list | table, chosen by the value's kind (a table may be left out)."""
    members = Annotated[scalar, Tag("~scalar")] | Annotated[listed, Tag("~list")]
    if table is not None:
        members = members | Annotated[table, Tag("~dict")]
    return Annotated[members, Discriminator(_kind, custom_error_type="kind", custom_error_message="give a number or a list of numbers")]


PerParticle = _by_kind(float, list[float], Uniform)


def _velocity_kind(v: Any) -> str:
    if isinstance(v, list) and v and isinstance(v[0], list):
        return "~vectors"
    if isinstance(v, dict) and "speed" in v or isinstance(v, Isotropic):
        return "~speed"
    return _kind(v)


Velocity = Annotated[
    Annotated[float, Tag("~scalar")]
    | Annotated[list[float], Tag("~list")]
    | Annotated[list[list[float]], Tag("~vectors")]
    | Annotated[Maxwell, Tag("~dict")]
    | Annotated[Isotropic, Tag("~speed")],
    Discriminator(_velocity_kind),
]  # a scalar is refused below, with a message that says what to give
Flags = _by_kind(bool, list[bool], bool)
Material = _by_kind(float, list[float], float)


def _typed(*models: type[_Model]) -> Any:
    """A union of models told apart by their ``type`` key."""
    names = [m.model_fields["type"].default for m in models]

    def tag(v: Any) -> str | None:
        t = v.get("type") if isinstance(v, dict) else getattr(v, "type", None)
        return f"~{t}" if t in names else None

    allowed = ", ".join(repr(n) for n in names)
    members = tuple(Annotated[m, Tag(f"~{n}")] for m, n in zip(models, names, strict=True))
    return Annotated[
        members[0] if len(members) == 1 else _union(members),
        Discriminator(tag, custom_error_type="type", custom_error_message=f"type must be one of {allowed}"),
    ]


def _union(members: tuple) -> Any:
    u = members[0]
    for m in members[1:]:
        u = u | m
    return u


# -- [world] ----------------------------------------------------------------------------------


class WorldTable(_Model):
    dim: Literal[2, 3] = 3
    dt: float = 1e-3
    method: str = "verlet"
    duration: float = 1.0
    fps: float = 60.0

    _dim = field_validator("dim", mode="before")(_exact(2, 3))

    @field_validator("method")
    @classmethod
    def _known(cls, v: str) -> str:
        if v not in method_names():
            raise ValueError(f"unknown method; valid methods are: {', '.join(method_names())}")
        return v

    @field_validator("dt")
    @classmethod
    def _dt(cls, v: float) -> float:
        if not (math.isfinite(v) and v >= MIN_DT):
            raise ValueError(f"the time step must be a finite number of seconds >= {MIN_DT:g}")
        return v

    @field_validator("duration")
    @classmethod
    def _duration(cls, v: float) -> float:
        if not (math.isfinite(v) and v >= 0):
            raise ValueError("the duration must be a finite number of seconds >= 0")
        return v

    @field_validator("fps")
    @classmethod
    def _fps(cls, v: float) -> float:
        if not (math.isfinite(v) and v >= MIN_FPS):
            raise ValueError(f"frames per second must be a finite number >= {MIN_FPS:g}")
        return v


# -- [[particles]] ----------------------------------------------------------------------------


class _Block(_Model):
    mass: PerParticle = 1.0
    radius: PerParticle = 0.0
    velocity: Velocity | None = None
    pinned: Flags = False
    restitution: Material | None = None
    friction: Material | None = None
    species: SpeciesName | list[SpeciesName] | None = None
    seed: Seed = 0

    @field_validator("velocity")
    @classmethod
    def _not_scalar(cls, v: Any) -> Any:
        if isinstance(v, float):
            raise ValueError("give a vector [vx, vy, vz], one vector per particle, or a table {sigma = ...}, {kT = ...} or {speed = ...}")
        return v


class ListBlock(_Block):
    type: Literal["list"] = "list"
    positions: Annotated[list[Vec], Field(min_length=1)]


class LatticeBlock(_Block):
    type: Literal["lattice"] = "lattice"
    origin: Vec = [0.0, 0.0, 0.0]
    counts: Annotated[list[Count], Field(min_length=2, max_length=3)]
    spacing: _by_kind(Positive, Annotated[list[Positive], Field(min_length=2, max_length=3)]) = 1.0
    jitter: NonNeg = 0.0

    @field_validator("counts")
    @classmethod
    def _size(cls, v: list[int]) -> list[int]:
        if math.prod(v) > MAX_PARTICLES:
            raise ValueError(f"the lattice would have {math.prod(v):,} particles, more than {MAX_PARTICLES:,}")
        return v


class RandomBlock(_Block):
    type: Literal["random"] = "random"
    lo: Vec
    hi: Vec
    count: Count
    min_distance: NonNeg | None = None

    @model_validator(mode="after")
    def _box(self) -> RandomBlock:
        if len(self.lo) != len(self.hi) or any(a > b for a, b in zip(self.lo, self.hi, strict=False)):
            raise ValueError(f"lo = {self.lo} and hi = {self.hi}: give corners of the same length with lo <= hi")
        return self


Block = _typed(ListBlock, LatticeBlock, RandomBlock)

# -- [[forces]] -------------------------------------------------------------------------------


class GravityForce(_Model):
    type: Literal["gravity"] = "gravity"
    g: Vec | None = None  # default (0, 0, -9.81) in 3D, (0, -9.81) in 2D


class DragForce(_Model):
    type: Literal["drag"] = "drag"
    linear: NonNeg = 0.0
    quadratic: NonNeg = 0.0


class SpringForce(_Model):
    type: Literal["spring"] = "spring"
    i: list[Index] | None = None
    j: list[Index] | None = None
    rule: Literal["chain", "grid"] | None = None
    block: Index | None = None
    diagonals: bool = False
    k: _by_kind(Positive, list[Positive])
    rest_length: _by_kind(NonNeg, list[NonNeg]) | None = None
    damping: _by_kind(NonNeg, list[NonNeg]) = 0.0

    @model_validator(mode="after")
    def _which(self) -> SpringForce:
        explicit = self.i is not None or self.j is not None
        if explicit == (self.rule is not None):
            raise ValueError("give either i and j (particle indices) or rule = 'chain' | 'grid' with block")
        if explicit and (self.i is None or self.j is None or len(self.i) != len(self.j)):
            raise ValueError("i and j must both be given, with the same length")
        if self.rule is not None and self.block is None:
            raise ValueError(f"rule = {self.rule!r} needs block, the index of the [[particles]] block it joins")
        return self


class AttractorForce(_Model):
    type: Literal["attractor"] = "attractor"
    point: Vec = [0.0, 0.0, 0.0]
    strength: NonNeg = 1.0
    softening: NonNeg = 0.0


class WindForce(_Model):
    type: Literal["wind"] = "wind"
    velocity: Vec = [1.0, 0.0, 0.0]
    coefficient: NonNeg = 1.0


ForceItem = _typed(GravityForce, DragForce, SpringForce, AttractorForce, WindForce)

# -- [[colliders]] ----------------------------------------------------------------------------


class _Surface(_Model):
    restitution: Unit | None = None
    friction: NonNeg | None = None


class PlaneCollider(_Surface):
    type: Literal["plane"] = "plane"
    point: Vec
    normal: Vec


class BoxCollider(_Surface):
    type: Literal["box"] = "box"
    lo: Vec
    hi: Vec


class SphereCollider(_Surface):
    type: Literal["sphere"] = "sphere"
    center: Vec
    radius: NonNeg


ColliderItem = _typed(PlaneCollider, BoxCollider, SphereCollider)

# -- [[emitters]], [[kill_volumes]] ------------------------------------------------------------
# The emitter checks its own values (kinema.Emitter); the tables check the types and names.


class EmitterTable(_Model):
    rate: Positive
    shape: Literal["point", "box", "disc", "sphere"] = "point"
    center: Vec = [0.0, 0.0, 0.0]
    size: Vec = [0.0, 0.0, 0.0]
    radius: NonNeg = 0.0
    normal: Vec = [0.0, 0.0, 1.0]
    start: float = 0.0
    end: float = float("inf")
    direction: Vec | None = None
    speed: NonNeg = 0.0
    speed_spread: NonNeg = 0.0
    spread: Annotated[float, Field(ge=0, le=180)] = 0.0
    particle_radius: NonNeg = 0.0
    radius_spread: NonNeg = 0.0
    mass: Positive | None = None
    density: Positive = 1000.0
    lifetime: Positive = float("inf")
    lifetime_spread: NonNeg = 0.0
    color: str | Annotated[list[Unit], Field(min_length=3, max_length=3)] | None = None
    species: SpeciesName | None = None
    restitution: Unit | None = None
    friction: NonNeg | None = None
    seed: Annotated[int, Field(ge=0, le=2**63 - 1)] = 0


class KillBoxTable(_Model):
    type: Literal["box"] = "box"
    lo: Vec
    hi: Vec


class KillSphereTable(_Model):
    type: Literal["sphere"] = "sphere"
    center: Vec
    radius: Positive


class KillPlaneTable(_Model):
    type: Literal["plane"] = "plane"
    point: Vec
    normal: Vec


KillItem = _typed(KillBoxTable, KillSphereTable, KillPlaneTable)


def _emitter(e: EmitterTable) -> Emitter:
    values = e.model_dump()
    for name in ("center", "size", "normal", "direction"):
        if values[name] is not None:
            values[name] = _v3(values[name])
    return Emitter(**values)


def _kill(k: Any) -> Any:
    if isinstance(k, KillBoxTable):
        return KillBox(_v3(k.lo), _v3(k.hi))
    if isinstance(k, KillSphereTable):
        return KillSphere(_v3(k.center), k.radius)
    return KillPlane(_v3(k.point), _v3(k.normal))


# -- [collisions], [render], [output] ---------------------------------------------------------


class CollisionsTable(_Model):
    model: Literal["impulse", "spring_dashpot"] = "impulse"
    restitution: Unit = 1.0
    friction: NonNeg = 0.0
    ccd: bool = True
    restitution_threshold: NonNeg | None = None
    stiffness: Positive | None = None
    damping: NonNeg | None = None
    periodic: Annotated[list[bool], Field(min_length=2, max_length=3)] | None = None

    @model_validator(mode="after")
    def _stiff(self) -> CollisionsTable:
        if self.model == "spring_dashpot" and self.stiffness is None:
            raise ValueError("model = 'spring_dashpot' needs stiffness (N/m)")
        return self


class Camera2DTable(_Model):
    type: Literal["2d"] = "2d"
    xmin: float
    ymin: float
    xmax: float
    ymax: float


class Camera3DTable(_Model):
    type: Literal["3d"] = "3d"
    eye: Vec
    target: Vec
    up: Vec = [0.0, 0.0, 1.0]
    fov_deg: Annotated[float, Field(gt=0, lt=180)] = 40.0


class RenderTable(_Model):
    width: Annotated[int, Field(ge=16, le=8192)] = 640
    height: Annotated[int, Field(ge=16, le=8192)] = 480
    color_by: Literal["speed", "id", "color"] = "speed"
    colormap: str = "viridis"
    background: Annotated[list[Annotated[int, Field(ge=0, le=255)]], Field(min_length=3, max_length=3)] = [255, 255, 255]
    fps: Annotated[float, Field(ge=0.01, le=1000)] | None = None  # playback; what GIF and MP4 can hold (kinema.cli.VIDEO_FPS)
    camera: _typed(Camera2DTable, Camera3DTable) | None = None

    @field_validator("colormap")
    @classmethod
    def _known(cls, v: str) -> str:
        from .render import COLORMAPS

        if v not in COLORMAPS:
            raise ValueError(f"unknown colormap; valid colormaps are: {', '.join(COLORMAPS)}")
        return v


class OutputTable(_Model):
    trajectory: bool = True
    video: Literal["mp4", "gif", False] = "mp4"
    plot: bool = True

    _video = field_validator("video", mode="before")(_exact("mp4", "gif", False))


# -- the scene --------------------------------------------------------------------------------


class Scene(_Model):
    """A whole simulation; see docs/scenes.md for every key."""

    world: WorldTable = Field(default_factory=WorldTable)
    particles: list[Block] = Field(default_factory=list)
    forces: list[ForceItem] = Field(default_factory=list)
    colliders: list[ColliderItem] = Field(default_factory=list)
    emitters: list[EmitterTable] = Field(default_factory=list)
    kill_volumes: list[KillItem] = Field(default_factory=list)
    collisions: CollisionsTable | None = None
    render: RenderTable = Field(default_factory=RenderTable)
    output: OutputTable = Field(default_factory=OutputTable)

    @model_validator(mode="after")
    def _references(self) -> Scene:
        for f in self.forces:
            if isinstance(f, SpringForce) and f.block is not None and f.block >= len(self.particles):
                raise ValueError(f"a spring names block = {f.block}, but the scene has {len(self.particles)} [[particles]] blocks")
        return self

    # reading -----------------------------------------------------------------------------
    @classmethod
    def from_toml(cls, path: str | Path) -> Scene:
        """Read and validate a scene file; raises ``SceneError`` (one line per problem)."""
        path = Path(path)
        if not path.exists():
            raise SceneError(f"{path}: no such file")
        if path.is_dir():
            raise SceneError(f"{path}: is a directory, not a scene file (.toml)")
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as e:
            raise SceneError(f"{path}: cannot be read ({getattr(e, 'strerror', None) or e})") from None
        return cls.from_string(text, source=str(path))

    @classmethod
    def from_string(cls, text: str, source: str = "<scene>") -> Scene:
        """Validate a scene given as TOML text; ``source`` names it in messages."""
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as e:
            raise SceneError(f"{source}: TOML syntax error: {e}") from None  # the message has "(at line L, column C)"
        except ValueError as e:  # an integer of more than 4300 digits
            raise SceneError(f"{source}: cannot be read as TOML: {e}") from None
        except RecursionError:  # arrays or inline tables nested hundreds deep
            raise SceneError(_too_deep_in_text(text, source)) from None
        return cls.from_dict(data, source)

    @classmethod
    def from_dict(cls, data: dict, source: str = "<scene>") -> Scene:
        deep = _too_deep(data, source)
        if deep is not None:
            raise SceneError(deep)
        try:
            return cls.model_validate(data)
        except ValidationError as e:
            raise SceneError("\n".join(_describe(err, source) for err in e.errors())) from None

    # size --------------------------------------------------------------------------------
    def particle_count(self) -> int:
        """How many particles ``build`` makes, counted without making them."""
        return sum(block_size(b) for b in self.particles)

    def emitted_count(self, seconds: float) -> int:
        """How many particles the emitters give in the first ``seconds`` of a run (births at
        start + k / rate, k = 0, 1, ..., before ``end``), counted without making them."""
        total = 0
        for e in self.emitters:
            until = min(e.end, seconds)
            if until >= e.start:
                count = math.floor((until - e.start) * e.rate) + 1
                if math.isfinite(e.end):
                    count = min(count, math.ceil((e.end - e.start) * e.rate))
                total += count
        return total

    # writing -----------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """Plain data, ``None`` values left out (TOML has no null)."""
        return self.model_dump(mode="python", exclude_none=True)

    def to_toml_string(self) -> str:
        import tomli_w

        return tomli_w.dumps(self.to_dict())

    def to_toml(self, path: str | Path) -> Path:
        """Write the scene as TOML under a temporary name, then rename; returns the path."""
        from .io._files import atomic_file

        path = Path(path)
        text = self.to_toml_string()
        with atomic_file(path) as tmp:
            tmp.write_text(text, encoding="utf-8")
        return path

    # building ----------------------------------------------------------------------------
    def build(self, source: str = "<scene>") -> World:
        """The World this scene describes (``world.scene`` is this scene). An engine refusal
        (a 2D scene with z ≠ 0, a spring index out of range, ...) is a ``SceneError`` naming
        the entry."""
        dim = self.world.dim
        w = World(dim=dim, dt=self.world.dt, method=self.world.method)
        starts: list[tuple[int, int]] = []
        for b, block in enumerate(self.particles):
            where = f"{source}: particles[{b}]"
            try:
                x, v, m, r, p, e, mu = _particles(block, dim)
                idx = w.add_particles(x, v, m, r, p, e, mu, species=block.species)
            except ValueError as err:
                raise SceneError(f"{where}: {err}") from None
            starts.append((int(idx[0]), int(idx[-1]) + 1))
        if self.collisions is not None:
            c = self.collisions.model_dump(exclude={"periodic"})
            try:
                w.set_collisions(**c)
            except ValueError as err:
                raise SceneError(f"{source}: collisions: {err}") from None
        for k, col in enumerate(self.colliders):
            try:
                w.add(_collider(col, dim))
            except ValueError as err:
                raise SceneError(f"{source}: colliders[{k}]: {err}") from None
        for k, f in enumerate(self.forces):
            try:
                w.add(_force(f, dim, w, starts, self.particles))
            except ValueError as err:
                raise SceneError(f"{source}: forces[{k}]: {err}") from None
        for key, items, make in (("emitters", self.emitters, _emitter), ("kill_volumes", self.kill_volumes, _kill)):
            for k, item in enumerate(items):
                try:
                    w.add(make(item))
                except (ValueError, TypeError) as err:
                    raise SceneError(f"{source}: {key}[{k}]: {err}") from None
        if self.collisions is not None and self.collisions.periodic is not None:
            try:
                w.periodic = self.collisions.periodic
            except (ValueError, StopIteration) as err:
                raise SceneError(f"{source}: collisions.periodic: {err or 'periodic axes need a box collider'}") from None
        w.scene = self
        return w


def block_size(block: Any) -> int:
    """The particles of one [[particles]] block, counted without making them."""
    if isinstance(block, ListBlock):
        return len(block.positions)
    if isinstance(block, LatticeBlock):
        return math.prod(block.counts)
    return block.count


def load_scene(path: str | Path) -> World:
    """Read, validate and build the scene file ``path``; the world keeps it as ``world.scene``."""
    return Scene.from_toml(path).build(source=str(path))


# -- errors -----------------------------------------------------------------------------------


def _describe(err: dict, source: str) -> str:
    """One line for one pydantic error: file, key path, value, what is allowed."""
    loc = [p for p in err["loc"] if not (isinstance(p, str) and p.startswith("~"))]
    path = _path(loc)
    kind = err["type"]
    msg = err["msg"].removeprefix("Value error, ")
    if kind == "extra_forbidden":
        allowed = _allowed_keys(err["loc"])
        hint = ""
        if allowed:
            close = difflib.get_close_matches(str(loc[-1]), allowed, n=1)
            hint = (f"; did you mean {close[0]!r}?" if close else "") + f" allowed keys here: {', '.join(allowed)}"
        return f"{source}: {path}: unknown key{hint}"
    if kind == "missing":
        return f"{source}: {path}: missing: a value is required"
    value = err.get("input")
    shown = repr(value) if not isinstance(value, dict | list) or len(repr(value)) < 60 else repr(value)[:57] + "..."
    msg = msg[0].lower() + msg[1:] if msg[:1].isupper() and not msg[1:2].isupper() else msg
    return f"{source}: {path}: {shown} is invalid: {msg}"


def _path(loc: list) -> str:
    return "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in loc).lstrip(".") or "(top level)"


def _preview(value: Any, width: int = 40) -> str:
    """The start of a value's repr, made without recursing (repr itself fails on deep values)."""
    out = ""
    while len(out) < width:
        if isinstance(value, list):
            out += "["
            if not value:
                out += "]"
                break
            value = value[0]
        elif isinstance(value, dict):
            out += "{"
            if not value:
                out += "}"
                break
            key, value = next(iter(value.items()))
            out += f"{key!r}: "
        else:
            out += repr(value)
            break
    return out[:width] + "..."


def _too_deep(data: Any, source: str) -> str | None:
    """A line naming the first value nested more than MAX_NESTING deep, or None."""
    stack: list[tuple[Any, list]] = [(data, [])]
    while stack:
        value, loc = stack.pop()
        if len(loc) > MAX_NESTING:
            where = _path(loc[:6]) + "..."  # the key, and the start of the path inside it
            return f"{source}: {where}: {_preview(value)} is invalid: arrays and tables nested more than {MAX_NESTING} levels deep are refused"
        if isinstance(value, dict):
            stack.extend((v, [*loc, k]) for k, v in value.items())
        elif isinstance(value, list):
            stack.extend((v, [*loc, k]) for k, v in enumerate(value) if isinstance(v, list | dict))
    return None


_TOKEN = re.compile(r'"""|\'\'\'|["\'#\n\[\]{}=]')
_STRING_END = {  # from just after the opening quotes to just after the closing ones
    '"': re.compile(r'(?:[^"\\\n]|\\.)*"?'),
    "'": re.compile(r"[^'\n]*'?"),
    '"""': re.compile(r'(?:[^"\\]|\\.|"(?!""))*(?:"""|$)', re.S),
    "'''": re.compile(r"(?:[^']|'(?!''))*(?:'''|$)", re.S),
}


def _too_deep_in_text(text: str, source: str) -> str:
    """The line for a TOML text too deep for the parser: the line and key where arrays or inline
    tables first nest more than MAX_NESTING deep (strings and comments skipped)."""
    depth, line, pos, key, start, table = 0, 1, 0, "", 0, ""
    seen: dict[str, int] = {}  # [[name]] headers so far, for the index of the next one
    while (m := _TOKEN.search(text, pos)) is not None:
        t, pos = m.group(), m.end()
        if t == "[" and depth == 0 and not text[start : m.start()].strip():  # a [table] or [[array]] header
            header = re.match(r"(\[\[?)\s*([^\]\n]*?)\s*\]", text[m.start() :])
            if header is not None:
                table = header.group(2)
                if header.group(1) == "[[":
                    seen[table] = seen.get(table, -1) + 1
                    table += f"[{seen[table]}]"
                pos = m.start() + header.end()
                continue
        if t in _STRING_END:
            stop = _STRING_END[t].match(text, pos).end()
            line += text.count("\n", pos, stop)
            pos = stop
        elif t == "#":
            end = text.find("\n", pos)
            pos = len(text) if end < 0 else end
        elif t == "\n":
            line += 1
            start = pos
        elif t == "=" and depth == 0:
            key = ".".join(filter(None, (table, text[start : m.start()].strip())))
        elif t in "[{":
            depth += 1
            if depth > MAX_NESTING:
                head = text[m.start() - MAX_NESTING + 1 : m.start() + 1].lstrip()
                return (
                    f"{source}: line {line}: {key or '(top level)'}: {head}... is invalid: arrays and tables nested more than {MAX_NESTING} levels deep"
                    " are refused"
                )
        elif t in "]}":
            depth = max(0, depth - 1)
    return f"{source}: arrays or tables are nested too deep to read (more than {MAX_NESTING} levels deep are refused)"


_TAGGED = {
    f"~{m.model_fields['type'].default}": m
    for m in (
        ListBlock,
        LatticeBlock,
        RandomBlock,
        GravityForce,
        DragForce,
        SpringForce,
        AttractorForce,
        WindForce,
        PlaneCollider,
        BoxCollider,
        SphereCollider,
        Camera2DTable,
        Camera3DTable,
    )
}


def _allowed_keys(loc: tuple) -> list[str]:
    """The keys of the table that holds the unknown key at ``loc``."""
    cls: Any = Scene
    for part in loc[:-1]:
        if isinstance(part, int) or part in ("~dict", "~list", "~scalar", "~vectors"):
            continue
        if part in _TAGGED:
            cls = _TAGGED[part]
            continue
        field = cls.model_fields.get(part) if isinstance(cls, type) and issubclass(cls, BaseModel) else None
        if field is None:
            return []
        cls = _model_in(field.annotation)
    return sorted(cls.model_fields) if isinstance(cls, type) and issubclass(cls, BaseModel) else []


def _model_in(annotation: Any) -> Any:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in getattr(annotation, "__args__", ()) or ():
        found = _model_in(arg)
        if found is not None:
            return found
    return None


# -- scene -> engine objects ------------------------------------------------------------------


def _v3(v: list[float]) -> list[float]:
    return [*map(float, v), 0.0][:3] if len(v) == 2 else [float(c) for c in v]


def _rng(seed: int, stream: int) -> np.random.Generator:
    # one stream per purpose, so changing one rule does not change the others' draws
    return np.random.default_rng([int(seed), stream])


def _positions(block: Any, dim: int) -> np.ndarray:
    if isinstance(block, ListBlock):
        return np.array([_v3(p) for p in block.positions])
    if isinstance(block, LatticeBlock):
        counts = [*block.counts, 1][:3]
        spacing = np.broadcast_to(np.asarray(_v3(block.spacing) if isinstance(block.spacing, list) else block.spacing, dtype=float), (3,))
        grid = np.stack(np.meshgrid(*[np.arange(c) for c in counts], indexing="ij"), axis=-1).reshape(-1, 3)
        x = np.asarray(_v3(block.origin)) + grid * spacing
        if block.jitter > 0:
            x = x + _rng(block.seed, 0).uniform(-block.jitter, block.jitter, x.shape)
        if dim == 2:
            x[:, 2] = 0.0
        return x
    lo, hi = np.asarray(_v3(block.lo)), np.asarray(_v3(block.hi))
    rng = _rng(block.seed, 0)
    if not block.min_distance:
        return rng.uniform(lo, hi, (block.count, 3))
    return _spaced(rng, lo, hi, block.count, block.min_distance)


def _spaced(rng: np.random.Generator, lo: np.ndarray, hi: np.ndarray, count: int, d: float) -> np.ndarray:
    """Random sequential addition: uniform points, each kept only if no kept point lies within d."""
    kept = np.empty((count, 3))
    n = 0
    for _ in range(200):
        for c in rng.uniform(lo, hi, (max(count, 256), 3)):
            if n == 0 or np.min(np.sum((kept[:n] - c) ** 2, axis=1)) >= d * d:
                kept[n] = c
                n += 1
                if n == count:
                    return kept
    raise ValueError(f"min_distance = {d}: could place only {n} of {count} particles in the box; enlarge the box or lower count or min_distance")


def _per_particle(name: str, value: Any, n: int, rng: np.random.Generator) -> np.ndarray:
    if isinstance(value, Uniform):
        return rng.uniform(value.min, value.max, n)
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 1 and arr.size != n:
        raise ValueError(f"{name} has {arr.size} values for {n} particles")
    return np.broadcast_to(arr, (n,)).copy()


def _particles(block: Any, dim: int) -> tuple:
    x = _positions(block, dim)
    n = len(x)
    m = _per_particle("mass", block.mass, n, _rng(block.seed, 1))
    r = _per_particle("radius", block.radius, n, _rng(block.seed, 2))
    vel = block.velocity
    if vel is None:
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
        v = np.array([_v3(u) for u in vel])
    else:
        if len(vel) not in (2, 3):
            raise ValueError(f"velocity = {vel} is invalid: it must be a vector of 2 or 3 values")
        v = np.broadcast_to(_v3(vel), (n, 3)).copy()
    pinned = np.asarray(block.pinned, dtype=bool)
    if pinned.ndim == 1 and pinned.size != n:
        raise ValueError(f"pinned has {pinned.size} values for {n} particles")
    e = None if block.restitution is None else _per_particle("restitution", block.restitution, n, _rng(block.seed, 4))
    mu = None if block.friction is None else _per_particle("friction", block.friction, n, _rng(block.seed, 5))
    return x, v, m, r, np.broadcast_to(pinned, (n,)), e, mu


def _collider(c: Any, dim: int) -> Any:
    s = {"restitution": c.restitution, "friction": c.friction}
    if isinstance(c, PlaneCollider):
        return Plane(_v3(c.point), _v3(c.normal), **s)
    if isinstance(c, BoxCollider):
        return Box(list(c.lo), list(c.hi), **s)
    return SphereObstacle(_v3(c.center), c.radius, **s)


def _force(f: Any, dim: int, w: World, starts: list[tuple[int, int]], blocks: list) -> Any:
    if isinstance(f, GravityForce):
        return Gravity(_v3(f.g) if f.g is not None else ([0.0, -9.81, 0.0] if dim == 2 else [0.0, 0.0, -9.81]))
    if isinstance(f, DragForce):
        return Drag(f.linear, f.quadratic)
    if isinstance(f, AttractorForce):
        return Attractor(_v3(f.point), f.strength, f.softening)
    if isinstance(f, WindForce):
        return Wind(_v3(f.velocity), f.coefficient)
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
            forces.append({"type": "gravity", "g": _v3(np.asarray(f.g, float).tolist())})
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
        if any(world.periodic):
            c["periodic"] = list(world.periodic)
        data["collisions"] = c
    return Scene.from_dict(data, "<world>")


World.to_scene = to_scene  # ``world.to_scene()``; the world module stays free of the scene format
World.save_checkpoint = save_checkpoint  # ``world.save_checkpoint(path)`` (kinema.checkpoint)
World.load_checkpoint = staticmethod(load_checkpoint)  # ``kinema.World.load_checkpoint(path)``
World.scene = None  # a world made in code has no scene; ``load_scene`` sets it on the instance
