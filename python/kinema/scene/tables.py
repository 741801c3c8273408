"""The pydantic models of a scene file's tables [world], [[forces]], [[emitters]],
[[kill_volumes]], [collisions], [render], [output] and [analysis].
The value types are in ``kinema.scene.values``, the [[particles]] blocks in
``kinema.scene.particle_tables`` and the [[colliders]] in ``kinema.scene.collider_tables``; this
module re-exports their names, so every table and value type is found here.
The whole file, ``Scene``, is in ``kinema.scene.schema``, which imports this module (never the
other way round)."""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import Field, field_validator, model_validator

from .. import _core
from ..ode import method_names
from .collider_tables import BoxCollider as BoxCollider
from .collider_tables import ColliderItem as ColliderItem
from .collider_tables import KeyframesMotion as KeyframesMotion
from .collider_tables import MeshCollider as MeshCollider
from .collider_tables import MeshShape as MeshShape
from .collider_tables import MotionItem as MotionItem
from .collider_tables import PlaneCollider as PlaneCollider
from .collider_tables import SphereCollider as SphereCollider
from .collider_tables import SteadyMotion as SteadyMotion
from .collider_tables import _all_finite as _all_finite
from .collider_tables import _motion_kind as _motion_kind
from .collider_tables import _Surface as _Surface
from .particle_tables import AtomStyle as AtomStyle
from .particle_tables import Block as Block
from .particle_tables import FileBlock as FileBlock
from .particle_tables import FileFormat as FileFormat
from .particle_tables import FileUnits as FileUnits
from .particle_tables import LatticeBlock as LatticeBlock
from .particle_tables import ListBlock as ListBlock
from .particle_tables import RandomBlock as RandomBlock
from .particle_tables import ScalesTable as ScalesTable
from .particle_tables import _Block as _Block
from .values import MAX_NESTING as MAX_NESTING
from .values import MAX_PARTICLES as MAX_PARTICLES
from .values import MAX_RATE as MAX_RATE
from .values import MAX_SEED as MAX_SEED
from .values import MIN_DT as MIN_DT
from .values import MIN_FPS as MIN_FPS
from .values import Count as Count
from .values import Flags as Flags
from .values import Group as Group
from .values import Index as Index
from .values import Isotropic as Isotropic
from .values import Material as Material
from .values import Maxwell as Maxwell
from .values import NonNeg as NonNeg
from .values import PerParticle as PerParticle
from .values import Positive as Positive
from .values import Seed as Seed
from .values import SpeciesName as SpeciesName
from .values import Uniform as Uniform
from .values import Unit as Unit
from .values import Vec as Vec
from .values import Vec3 as Vec3
from .values import Velocity as Velocity
from .values import _by_kind as _by_kind
from .values import _exact as _exact
from .values import _kind as _kind
from .values import _Model as _Model
from .values import _typed as _typed
from .values import _union as _union
from .values import _velocity_kind as _velocity_kind

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

# The contact models a scene may name: the engine's list (ContactModel::NAMES), so that a new
# model is named in one place.
ContactModelName = Literal[tuple(_core.CONTACT_MODELS)]  # type: ignore[valid-type]


class CollisionsTable(_Model):
    model: ContactModelName = _COLLISION_DEFAULTS["model"]
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
