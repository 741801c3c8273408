"""The value types of a scene file's tables: the strict base model of every table, the bounds
on numbers and counts, the annotated number and vector types, the per-particle value tables
(Uniform, Maxwell, Isotropic), and the unions told apart by a value's kind or by a table's
``type``.
The tables are in ``kinema.scene.tables``, ``kinema.scene.particle_tables`` and
``kinema.scene.collider_tables``, which import this module (never the other way round)."""

from __future__ import annotations

from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Discriminator, Field, Tag, model_validator

from .. import _checks

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


def vec3(v: list[float]) -> list[float]:
    """A scene's vector of 2 or 3 values as 3 floats (2 values: z = 0), as the engine objects
    take it (the builder's and the export's)."""
    return [*map(float, v), 0.0][:3] if len(v) == 2 else [float(c) for c in v]


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
