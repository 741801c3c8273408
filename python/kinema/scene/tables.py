"""A scene file's value types and the pydantic models of its tables: [world], [[particles]],
[[forces]], [[colliders]], [[emitters]], [[kill_volumes]], [collisions], [render], [output],
[analysis].
The whole file, ``Scene``, is in ``kinema.scene.schema``, which imports this module (never the
other way round)."""

from __future__ import annotations

import math
import os
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Discriminator, Field, PrivateAttr, Tag, field_validator, model_validator

from .. import _checks, _core
from ..ode import method_names

# -- value types ------------------------------------------------------------------------------
# A callable discriminator picks one member of a union, so a wrong value gets one error (that
# member's) rather than one per member. Tags start with "~" so they can be cut out of key paths.


class _Model(BaseModel):
    # strict: no str -> number, bool -> number or float -> int (TOML's 1 is an int, and
    # pydantic's strict mode still takes an int where a float is wanted)
    model_config = ConfigDict(extra="forbid", validate_assignment=True, strict=True)


# Bounds that keep the engine's arithmetic finite and its integers in range (the CLI's work
# estimate, kinema.runner, refuses much smaller runs unless told --force).
MIN_DT = 1e-300  # s; with MIN_FPS, 1/(fps dt) (the steps of one frame) stays finite
MIN_FPS = 1e-6  # frames per second
MAX_PARTICLES = 2**32 - 1  # particles in one block, and the largest particle index + 1
MAX_SEED = 2**64 - 1
MAX_NESTING = 32  # arrays and tables inside each other (a scene's deepest key path is 5 long)
MAX_RATE = 1e15  # particles a second from one emitter: a million a step at dt = 1 ns, and counts of births stay exact floats for 9 s


Vec = Annotated[list[float], Field(min_length=2, max_length=3)]
Vec3 = Annotated[list[float], Field(min_length=3, max_length=3)]
NonNeg = Annotated[float, Field(ge=0)]
Positive = Annotated[float, Field(gt=0)]
SpeciesName = Annotated[str, Field(pattern=f"^{_checks.SPECIES_PATTERN}$")]  # one word, as World.add_particles takes it
Unit = Annotated[float, Field(ge=0, le=1)]
Index = Annotated[int, Field(ge=0, lt=MAX_PARTICLES)]
Count = Annotated[int, Field(ge=1, le=MAX_PARTICLES)]
Seed = Annotated[int, Field(ge=0, le=MAX_SEED)]
Group = Annotated[int, Field(ge=0, le=_checks.GROUPS - 1, strict=True)]  # a collision group (World.add_particles' group)


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
    spin: bool = False

    _dim = field_validator("dim", mode="before")(_exact(2, 3))

    @field_validator("method")
    @classmethod
    def _known(cls, v: str) -> str:
        if v not in method_names():
            meant = _core.method_suggestion(v)
            hint = f" did you mean {meant!r}?" if meant else ""
            raise ValueError(f"unknown method;{hint} valid methods are: {', '.join(method_names())}")
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
    group: Group | list[Group] = 0
    seed: Seed = 0
    angular_velocity: list[float] | list[list[float]] | None = None
    inertia: PerParticle | None = None

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

    # (a NaN or infinite corner, or a box wider than a float holds, was numpy's "OverflowError: Range exceeds valid bounds")
    @field_validator("lo", "hi")
    @classmethod
    def _finite(cls, v: list[float]) -> list[float]:
        if not all(math.isfinite(c) for c in v):
            raise ValueError("each coordinate of a corner of the box must be a finite number of metres")
        return v

    @model_validator(mode="after")
    def _box(self) -> RandomBlock:
        if len(self.lo) != len(self.hi) or any(a > b for a, b in zip(self.lo, self.hi, strict=False)):
            raise ValueError(f"lo = {self.lo} and hi = {self.hi}: give corners of the same length with lo <= hi")
        if not all(math.isfinite(b - a) for a, b in zip(self.lo, self.hi, strict=False)):
            raise ValueError(f"lo = {self.lo} and hi = {self.hi}: the box is wider than a float holds; hi - lo must be finite")
        return self


class ScalesTable(_Model):
    """A file's units given as their SI values: one unit of length in m, of time in s, of mass in kg."""

    length: Positive
    time: Positive
    mass: Positive


# the formats a file block reads (kinema.io.readers.READ_FORMATS) and a LAMMPS data file's atom styles (read_lammps.ATOM_STYLES)
FileFormat = Literal["h5md", "xyz", "gsd", "lammps", "lammps-data", "csv", "vtk", "ply", "usd"]
AtomStyle = Literal["atomic", "charge", "bond", "angle", "molecular", "full", "sphere"]


FileUnits = Annotated[
    Annotated[str, Tag("~scalar")] | Annotated[ScalesTable, Tag("~dict")],
    Discriminator(_kind, custom_error_type="kind", custom_error_message="give a unit style's name or a table {length = m, time = s, mass = kg}"),
]


class FileBlock(_Block):
    """The particles of one frame of a trajectory file (``World.add_particles_from``): their
    positions (+ ``translate``), and their velocities, masses, radii, species and collision
    groups where the file has them (else the block's own keys)."""

    type: Literal["file"] = "file"
    path: Annotated[str, Field(min_length=1)]
    frame: int = -1
    units: FileUnits | None = None
    format: FileFormat | None = None
    atom_style: AtomStyle | None = None
    translate: Vec | None = None
    _read: dict[str, Any] | None = PrivateAttr(default=None)  # the particles read, for counting and building

    @field_validator("units")
    @classmethod
    def _known_units(cls, v: Any) -> Any:
        from ..io.units import scales

        if isinstance(v, str):
            try:
                scales(v, "units")
            except ValueError as e:
                raise ValueError(str(e).split(" is invalid: ", 1)[-1]) from None
        return v

    def particles(self) -> dict[str, Any]:
        """The particles the block takes from its file (``kinema.io.readers.particles_from``),
        read once (a relative ``path``: from the working folder; ``Scene.from_toml`` makes it
        relative to the scene file's folder). Raises ``ValueError``, one line naming ``path``
        and why the file cannot be read."""
        if self._read is None:
            from ..io.readers import particles_from

            units = self.units.model_dump() if isinstance(self.units, ScalesTable) else self.units
            try:
                self._read = particles_from(self.path, self.frame, units, format=self.format, atom_style=self.atom_style)
            except (ValueError, TypeError) as e:
                raise ValueError(f"path = {self.path!r}: {str(e).strip().splitlines()[0]}") from None
        return self._read


Block = _typed(ListBlock, LatticeBlock, RandomBlock, FileBlock)

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


class FalloffTable(_Model):
    """``falloff = { shape = "sphere", law = "smooth", max_distance = 2.0 }`` on a field force
    (``kinema.Falloff``): left out, ``center`` is the force's own point, a tube's ``axis`` a
    vortex's axis; ``max_distance`` left out is no limit."""

    shape: Literal["sphere", "tube", "box"] = "sphere"
    law: Literal["constant", "linear", "smooth", "inverse_square"] = "smooth"
    min_distance: NonNeg = 0.0
    max_distance: Positive | None = None
    center: Vec | None = None
    axis: Vec | None = None
    half_size: Vec | None = None


class AttractorForce(_Model):
    type: Literal["attractor"] = "attractor"
    point: Vec = [0.0, 0.0, 0.0]
    strength: NonNeg = 1.0
    softening: NonNeg = 0.0
    falloff: FalloffTable | None = None


class WindForce(_Model):
    type: Literal["wind"] = "wind"
    velocity: Vec = [1.0, 0.0, 0.0]
    coefficient: NonNeg = 1.0
    falloff: FalloffTable | None = None


class TurbulenceForce(_Model):
    type: Literal["turbulence"] = "turbulence"
    strength: NonNeg = 1.0
    scale: Positive = 1.0
    seed: Annotated[int, Field(ge=0, le=2**63 - 1)] = 0
    time_scale: Positive | None = None  # left out: a frozen field
    octaves: Annotated[int, Field(ge=1, le=8)] = 1
    roughness: Unit = 0.5
    coefficient: NonNeg | None = None  # left out: an acceleration field
    falloff: FalloffTable | None = None


class VortexForce(_Model):
    type: Literal["vortex"] = "vortex"
    point: Vec = [0.0, 0.0, 0.0]
    axis: Vec = [0.0, 0.0, 1.0]
    strength: float = 1.0
    radius: Positive = 1.0
    profile: Literal["rankine", "lamb_oseen", "constant"] = "rankine"
    coefficient: NonNeg | None = None  # left out: an acceleration field
    falloff: FalloffTable | None = None


ForceItem = _typed(GravityForce, DragForce, SpringForce, AttractorForce, WindForce, TurbulenceForce, VortexForce)

# -- [[colliders]] ----------------------------------------------------------------------------
# A collider's `motion` (kinema.Motion, kinema.Keyframes): a steady table, or keyframes (a
# table with `times`), told apart by that key.


def _all_finite(values: Any, name: str, unit: str) -> None:
    flat = values if not values or not isinstance(values[0], list) else [c for row in values for c in row]
    if not all(math.isfinite(c) for c in flat):
        raise ValueError(f"{name} must be finite numbers ({unit})")


class SteadyMotion(_Model):
    """``motion = { velocity = [..], angular_velocity = [..], pivot = [..] }``: translation at
    ``velocity`` (m/s) and a turn at ``angular_velocity`` (rad/s, about its direction) about
    ``pivot`` (m, a point of the collider's placement), from ``start`` (s, on the world's
    clock; left out: from when the collider is added, the scene's time 0)."""

    velocity: Vec = [0.0, 0.0, 0.0]
    angular_velocity: Vec3 = [0.0, 0.0, 0.0]
    pivot: Vec = [0.0, 0.0, 0.0]
    start: float | None = None

    @field_validator("velocity", "angular_velocity", "pivot")
    @classmethod
    def _finite(cls, v: Any, info: Any) -> Any:
        _all_finite(v, info.field_name, {"velocity": "m/s", "angular_velocity": "rad/s"}.get(info.field_name, "m"))
        return v

    @field_validator("start")
    @classmethod
    def _finite_start(cls, v: Any) -> Any:
        if v is not None and not math.isfinite(v):
            raise ValueError(f"start = {v} is invalid: it must be a finite time, s")
        return v

    def turns(self) -> bool:
        return any(c != 0 for c in self.angular_velocity)


class KeyframesMotion(_Model):
    """``[colliders.motion]`` with ``times`` (s, strictly increasing), ``translations`` (m, one
    per time) and ``rotations`` (degrees about the fixed x, then y, then z axis, one per time;
    less than 180° apart about each axis from one key to the next) about ``pivot`` (m)."""

    times: Annotated[list[float], Field(min_length=1)]
    translations: list[Vec] | None = None
    rotations: list[Vec3] | None = None
    pivot: Vec = [0.0, 0.0, 0.0]

    @field_validator("times")
    @classmethod
    def _increasing(cls, v: list[float]) -> list[float]:
        for k, t in enumerate(v):
            if not math.isfinite(t) or (k > 0 and not t > v[k - 1]):
                raise ValueError(f"keyframe times must be finite and strictly increasing, s (times[{k}] = {t:g})")
        return v

    @field_validator("translations", "rotations", "pivot")
    @classmethod
    def _finite(cls, v: Any, info: Any) -> Any:
        if v is not None:
            _all_finite(v, info.field_name, "degrees" if info.field_name == "rotations" else "m")
        return v

    @model_validator(mode="after")
    def _one_per_time(self) -> KeyframesMotion:
        k = len(self.times)
        for name in ("translations", "rotations"):
            rows = getattr(self, name)
            if rows is not None and len(rows) != k:
                raise ValueError(f"{name} has {len(rows)} rows for {k} times; give one per keyframe time")
        for j in range(1, len(self.rotations or [])):
            step = [abs(a - b) for a, b in zip(self.rotations[j], self.rotations[j - 1], strict=True)]
            if max(step) >= 180:
                raise ValueError(
                    f"rotations[{j}] is {max(step):g}° about {'xyz'[step.index(max(step))]} from rotations[{j - 1}]; between two keys a collider "
                    "turns the shorter way (less than 180°): put keys in between"
                )
        return self

    def turns(self) -> bool:
        return any(c != 0 for row in self.rotations or [] for c in row)


def _motion_kind(v: Any) -> str:
    return "~keyframes" if (isinstance(v, dict) and "times" in v) or isinstance(v, KeyframesMotion) else "~steady"


MotionItem = Annotated[Annotated[SteadyMotion, Tag("~steady")] | Annotated[KeyframesMotion, Tag("~keyframes")], Discriminator(_motion_kind)]


class _Surface(_Model):
    restitution: Unit | None = None
    friction: NonNeg | None = None
    motion: MotionItem | None = None
    collides_with: list[Group] | None = None  # the collision groups it stops (None: all)


class PlaneCollider(_Surface):
    type: Literal["plane"] = "plane"
    point: Vec
    normal: Vec


class BoxCollider(_Surface):
    type: Literal["box"] = "box"
    lo: Vec
    hi: Vec

    @field_validator("motion")
    @classmethod
    def _translates(cls, v: Any) -> Any:
        if v is not None and v.turns():
            turn = "angular_velocity" if isinstance(v, SteadyMotion) else "rotations"
            raise ValueError(f"a box stays axis-aligned and can only translate ({turn} must be 0); a turning container is a mesh with inside = true")
        return v


class SphereCollider(_Surface):
    type: Literal["sphere"] = "sphere"
    center: Vec
    radius: NonNeg


class MeshShape(_Model):
    """A triangle mesh's shape and placement (``kinema.Mesh``, 3D only): from ``file`` (OBJ,
    STL, PLY, glTF, USD; a path relative to the scene file) or from ``vertices`` (m) and
    ``faces`` (vertex indices) written in the table, whose up axis is ``up_axis`` ("z",
    kinema's, or "y"; none: the file's own for glTF and USD, else "z"); then scaled by
    ``scale`` (one factor or 3), rotated by ``rotation`` (degrees about the fixed x, then y,
    then z axis) and moved by ``translation`` (m). An emitter's ``mesh``, and the mesh
    collider's keys."""

    file: Annotated[str, Field(min_length=1)] | None = None
    vertices: Annotated[list[Vec3], Field(min_length=1)] | None = None
    faces: Annotated[list[Annotated[list[Annotated[int, Field(ge=0, le=2**32 - 1)]], Field(min_length=3, max_length=3)]], Field(min_length=1)] | None = None
    up_axis: Literal["z", "y"] | None = None
    scale: _by_kind(float, Vec3) = 1.0
    rotation: Vec3 = [0.0, 0.0, 0.0]
    translation: Vec3 = [0.0, 0.0, 0.0]

    @field_validator("file")
    @classmethod
    def _format(cls, v: str | None) -> str | None:
        from ..io.mesh_files import formats_text, mesh_format

        if v is not None and mesh_format(v) is None:
            suffix = os.path.splitext(v)[1]
            raise ValueError(f"unknown mesh format {repr(suffix) if suffix else '(no suffix)'}; the formats read are {formats_text()}")
        return v

    @field_validator("scale")
    @classmethod
    def _factors(cls, v: Any) -> Any:
        if not all(math.isfinite(c) and c != 0 for c in (v if isinstance(v, list) else [v])):
            raise ValueError("each scale factor must be finite and non-zero (a negative one mirrors)")
        return v

    @field_validator("rotation", "translation", "vertices")
    @classmethod
    def _finite(cls, v: Any, info: Any) -> Any:
        rows = v if v is None or not v or not isinstance(v[0], list) else [c for row in v for c in row]
        if rows is not None and not all(math.isfinite(c) for c in rows):
            unit = "degrees" if info.field_name == "rotation" else "m"
            raise ValueError(f"{info.field_name} must be finite numbers ({unit})")
        return v

    @model_validator(mode="after")
    def _source(self) -> Any:
        arrays = self.vertices is not None or self.faces is not None
        if self.file is not None and arrays:
            raise ValueError("give either file or vertices and faces, not both")
        if self.file is None and not (self.vertices is not None and self.faces is not None):
            raise ValueError("a mesh needs file (a mesh file beside the scene) or both vertices and faces")
        return self


class MeshCollider(_Surface, MeshShape):
    """A triangle mesh collider (``kinema.Mesh``): ``MeshShape``'s keys, and ``inside``:
    particles live inside this closed mesh (a container)."""

    type: Literal["mesh"] = "mesh"
    inside: bool = False


ColliderItem = _typed(PlaneCollider, BoxCollider, SphereCollider, MeshCollider)

# -- [[emitters]], [[kill_volumes]] ------------------------------------------------------------
# The emitter checks its own values (kinema.Emitter); the tables check the types and names.


class EmitterTable(_Model):
    rate: float  # particles a second

    @field_validator("rate")
    @classmethod
    def _rate(cls, v: float) -> float:  # (1e308 was an OverflowError counting the births)
        if not (0 < v <= MAX_RATE):
            raise ValueError(f"the rate must be a number of particles a second > 0 and <= {MAX_RATE:g}")
        return v

    shape: Literal["point", "box", "disc", "sphere", "mesh"] = "point"
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
    group: Group = 0
    seed: Annotated[int, Field(ge=0, le=2**63 - 1)] = 0
    mesh: MeshShape | None = None
    emit_from: Literal["faces", "volume", "vertices"] = "faces"


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


# -- [collisions], [render], [output] ---------------------------------------------------------


# The engine's defaults and contact-model rule (kinema::world::CollisionParams, ContactModel):
# the table states the types and ranges a TOML file may hold, the engine the rest.
_COLLISION_DEFAULTS = _core.collision_defaults()


class CollisionsTable(_Model):
    model: Literal["impulse", "spring_dashpot", "hertz"] = _COLLISION_DEFAULTS["model"]
    restitution: Unit = _COLLISION_DEFAULTS["restitution"]
    friction: NonNeg = _COLLISION_DEFAULTS["friction"]
    ccd: bool = _COLLISION_DEFAULTS["ccd"]
    restitution_threshold: NonNeg | None = _COLLISION_DEFAULTS["restitution_threshold"]
    sleep_time: Positive | None = _COLLISION_DEFAULTS["sleep_time"]
    sleep_speed: Positive | None = _COLLISION_DEFAULTS["sleep_speed"]
    stiffness: Positive | None = _COLLISION_DEFAULTS["stiffness"]
    damping: NonNeg | None = _COLLISION_DEFAULTS["damping"]
    youngs_modulus: Positive | None = _COLLISION_DEFAULTS["youngs_modulus"]
    poisson_ratio: NonNeg | None = _COLLISION_DEFAULTS["poisson_ratio"]
    cohesion: Literal["dmt", "jkr"] | None = _COLLISION_DEFAULTS["cohesion"]
    surface_energy: NonNeg | None = _COLLISION_DEFAULTS["surface_energy"]
    event_driven: bool = _COLLISION_DEFAULTS["event_driven"]
    rolling_friction: NonNeg = _COLLISION_DEFAULTS["rolling_friction"]
    tangential: Literal["linear_history", "mindlin"] | None = _COLLISION_DEFAULTS["tangential"]
    tangential_stiffness: Positive | None = _COLLISION_DEFAULTS["tangential_stiffness"]
    tangential_damping: NonNeg | None = _COLLISION_DEFAULTS["tangential_damping"]
    rolling_stiffness: Positive | None = _COLLISION_DEFAULTS["rolling_stiffness"]
    rolling_damping: NonNeg | None = _COLLISION_DEFAULTS["rolling_damping"]
    accuracy: Literal["physics", "animation"] = _COLLISION_DEFAULTS["accuracy"]
    self_collisions: bool = _COLLISION_DEFAULTS["self_collisions"]
    # the pairs of collision groups that pass through each other (World.set_group_collisions(a, b, False))
    ignore_groups: list[Annotated[list[Group], Field(min_length=2, max_length=2)]] | None = None
    periodic: Annotated[list[bool], Field(min_length=2, max_length=3)] | None = None

    @model_validator(mode="after")
    def _model_takes_its_parameters(self) -> CollisionsTable:
        # "spring_dashpot needs stiffness", "only spring_dashpot takes damping": the engine's rule.
        _core.check_contact_model(self.model, self.stiffness, self.damping, self.youngs_modulus, self.poisson_ratio, self.cohesion, self.surface_energy)
        return self


def _engine_takes_camera(**camera: Any) -> None:
    """Raises the engine's ``ValueError`` for a camera it cannot draw with (it draws a 16×16
    frame of no particles with it): a camera is checked when the scene is read, not after the
    run whose video it was to film."""
    import numpy as np

    _core.render_frame(np.zeros((0, 3)), np.zeros(0), width=16, height=16, **camera)


class Camera2DTable(_Model):
    """An orthographic view of the xy-plane: the rectangle [xmin, xmax] × [ymin, ymax] (m)
    fits the image, centred, aspect kept (render.cameras.Camera2D)."""

    type: Literal["2d"] = "2d"
    xmin: float
    ymin: float
    xmax: float
    ymax: float

    @model_validator(mode="after")
    def _rectangle(self) -> Camera2DTable:
        corners = (self.xmin, self.ymin, self.xmax, self.ymax)
        if not (all(math.isfinite(v) for v in corners) and self.xmin < self.xmax and self.ymin < self.ymax):
            raise ValueError(
                f"xmin = {self.xmin:g}, xmax = {self.xmax:g}, ymin = {self.ymin:g}, ymax = {self.ymax:g}: the view must be a finite rectangle with xmin < xmax and ymin < ymax (m)"
            )
        _engine_takes_camera(view=corners)  # (a width beyond float64, -1e308 to 1e308)
        return self


class Camera3DTable(_Model):
    """A pinhole camera at ``eye`` looking at ``target`` (m), ``up`` the image's up direction,
    ``fov_deg`` the vertical field of view (render.cameras.Camera3D)."""

    type: Literal["3d"] = "3d"
    eye: Vec3
    target: Vec3
    up: Vec3 = [0.0, 0.0, 1.0]
    fov_deg: Annotated[float, Field(gt=0, lt=180)] = 40.0

    @model_validator(mode="after")
    def _pose(self) -> Camera3DTable:
        for name in ("eye", "target", "up"):
            if not all(math.isfinite(v) for v in getattr(self, name)):
                raise ValueError(f"{name} = {getattr(self, name)}: the camera's {name} must be finite")
        _engine_takes_camera(eye=self.eye, target=self.target, up=self.up, fov_deg=self.fov_deg)  # eye != target, up not along the view
        return self


class RenderTable(_Model):
    width: Annotated[int, Field(ge=16, le=8192)] = 640
    height: Annotated[int, Field(ge=16, le=8192)] = 480
    color_by: Literal["speed", "id", "color"] = "speed"
    colormap: str = "viridis"
    background: Annotated[list[Annotated[int, Field(ge=0, le=255)]], Field(min_length=3, max_length=3)] = [255, 255, 255]
    fps: Annotated[float, Field(ge=0.01, le=1000)] | None = None  # playback; what GIF and MP4 can hold (kinema.runner.VIDEO_FPS)
    camera: _typed(Camera2DTable, Camera3DTable) | None = None
    trail: Annotated[float, Field(ge=0, allow_inf_nan=False)] | None = None  # s of each particle's path drawn; None: render_frames' default

    @field_validator("colormap")
    @classmethod
    def _known(cls, v: str) -> str:
        from ..render import COLORMAPS

        if v not in COLORMAPS:
            raise ValueError(f"unknown colormap; valid colormaps are: {', '.join(COLORMAPS)}")
        return v


class OutputTable(_Model):
    trajectory: bool = True
    video: Literal["mp4", "gif", False] = "mp4"
    plot: bool = True
    # contact_events.csv: every begin and end of touch (World.contact_events), impulse model
    contact_events: bool = False
    # each frame's contacts (World.run(record_contacts=True)) in trajectory.h5's /contacts
    contacts: bool = False

    _video = field_validator("video", mode="before")(_exact("mp4", "gif", False))


# -- [analysis] -------------------------------------------------------------------------------
# The measures kinema run makes of its trajectory after the run and writes as analysis.json
# (kinema.analysis.report, the same document as kinema analyze --json).
_MEASURES = ("coordination", "fabric", "forces", "repose", "profile")  # kinema.analysis.report.MEASURES


class AnalysisTable(_Model):
    measures: Annotated[list[Literal["coordination", "fabric", "forces", "repose", "profile"]], Field(min_length=1)] = list(_MEASURES)
    frames: Literal["last", "all"] = "last"  # all: the last frame's measures and their time series
    axis: Literal["x", "y", "z"] | None = None  # the height; None: y in a 2D world, z in 3D
    bins: Annotated[int, Field(ge=1, le=100_000)] = 20  # the profile's slabs, the force histogram's bins
    cross_section: Annotated[float, Field(gt=0, allow_inf_nan=False)] | None = None  # m² (m in 2D); None: the cell's, a box's or the pile's

    @field_validator("measures")
    @classmethod
    def _once(cls, v: list[str]) -> list[str]:
        twice = sorted({m for m in v if v.count(m) > 1})
        if twice:
            raise ValueError(f"{twice[0]!r} is named twice; name each measure once")
        return v

    @property
    def needs_contacts(self) -> list[str]:
        """The measures asked that need each frame's contacts recorded."""
        return [m for m in self.measures if m in ("coordination", "fabric", "forces")]
