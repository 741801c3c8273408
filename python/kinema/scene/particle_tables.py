"""The pydantic models of a scene file's [[particles]] blocks: a list of positions, a lattice,
a random box, and the particles of a trajectory file's frame (with its units and format).
``kinema.scene.tables`` re-exports them; this module imports only ``kinema.scene.values`` of
the scene package."""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import Discriminator, Field, PrivateAttr, Tag, field_validator, model_validator

from .values import (
    MAX_PARTICLES,
    Count,
    Flags,
    Group,
    Material,
    NonNeg,
    PerParticle,
    Positive,
    Seed,
    SpeciesName,
    Vec,
    Velocity,
    _by_kind,
    _kind,
    _Model,
    _typed,
)

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
