"""Forces for `kinema.World`: descriptions that a world turns into engine forces.

Each class states its formula and units; the computation runs in the engine, except for
`PythonForce`, which calls your function once per force evaluation with whole arrays.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import _checks

STANDARD_GRAVITY = 9.81
"""The default gravity's magnitude, m/s² (one home: ``Gravity`` and the scenes use it)."""


def _vec3(name: str, value: Any) -> list[float]:
    arr = _checks.real_array(name, value).reshape(-1)
    if arr.size != 3:
        raise ValueError(f"{name} = {_checks.describe(value)} is invalid: it must be a 3-vector")
    return arr.tolist()


def _vec(name: str, value: Any, unit: str) -> list[float]:
    """A force's vector as 3 numbers: [x, y, z], or [x, y] meaning (x, y, 0), the scene
    file's rule (so ``Gravity([0, -9.81])`` in a 2D world is ``g = [0, -9.81]`` in its scene)."""
    arr = _checks.real_array(name, value).reshape(-1)
    if arr.size == 2:
        return [*arr.tolist(), 0.0]
    if arr.size != 3:
        raise ValueError(
            f"{name} = {_checks.describe(value)} is invalid: it has {arr.size} component{'' if arr.size == 1 else 's'}; "
            f"give [x, y, z] or, as in a scene file, [x, y] meaning (x, y, 0) ({unit})"
        )
    return arr.tolist()


class _Checked:
    """Checks its values when built (a bad one raises there, naming it) and keeps them,
    converted, for the world it is added to; the fields keep what was given."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "_args", self._checked())

    def _checked(self) -> tuple:  # pragma: no cover - every force overrides it
        raise NotImplementedError


@dataclass(frozen=True)
class Gravity(_Checked):
    """Uniform gravity: F_i = m_i g (N); g in m/s². The default is down at 9.81 m/s²: along −z
    in a 3D world (z is up), along −y in a 2D world (the xy-plane, y up), as a scene's
    `[[forces]] type = "gravity"` without `g`. A 2-vector ``g = [gx, gy]`` means (gx, gy, 0),
    as in a scene file."""

    g: Any = None

    def _checked(self) -> tuple:
        return (None if self.g is None else _vec("g", self.g, "m/s²"),)

    def vector(self, dim: int) -> list[float]:
        """g (m/s²) in a world of ``dim`` 2 or 3: the one given, else the default down."""
        (g,) = self._args
        if g is None:
            g = [0.0, -STANDARD_GRAVITY, 0.0] if dim == 2 else [0.0, 0.0, -STANDARD_GRAVITY]
        return list(g)

    def _attach(self, core: Any) -> None:
        core.add_gravity(self.vector(core.dim))


@dataclass(frozen=True)
class Drag(_Checked):
    """Drag: F_i = −b₁ v_i − b₂ |v_i| v_i (N); b₁ = `linear` in kg/s, b₂ = `quadratic` in kg/m."""

    linear: float = 0.0
    quadratic: float = 0.0

    def _checked(self) -> tuple:
        return _checks.real("linear", self.linear), _checks.real("quadratic", self.quadratic)

    def _attach(self, core: Any) -> None:
        core.add_drag(*self._args)


@dataclass(frozen=True)
class Spring(_Checked):
    """Springs between particles i[s] and j[s]: Hooke's law plus a dashpot along the spring,
    F_i = [k (L − L₀) + c (v_j − v_i)·n] n = −F_j, n the unit vector from i to j, L its length.

    `k` in N/m, `rest_length` L₀ in m (None: the current distance when added), `damping`
    c in N·s/m. Scalars broadcast over the index arrays, so one object holds many springs.
    Indices are integers (ints, NumPy integers or integer arrays; not floats, not bools) >= 0.
    """

    i: Any
    j: Any
    k: Any
    rest_length: Any = None
    damping: Any = 0.0

    def _checked(self) -> tuple:
        i = _checks.index_array("i", self.i)
        j = _checks.index_array("j", self.j)
        if i.shape != j.shape:
            raise ValueError(f"Spring: i has shape {i.shape} and j {j.shape}; they must be 1-D and equal")
        n = i.size

        def per_spring(name: str, value: Any) -> np.ndarray:
            arr = _checks.real_array(name, value)
            return np.ascontiguousarray(_checks.broadcast(name, arr, (n,), f"a scalar or one value per spring, ({n},)"), dtype=np.float64)

        # arrays, not lists: a million springs as Python lists would take 100 B each more
        rest = None if self.rest_length is None else per_spring("rest_length", self.rest_length)
        ends = (np.ascontiguousarray(a, dtype=np.int64).reshape(-1) for a in (i, j))
        return *ends, per_spring("k", self.k), rest, per_spring("damping", self.damping)

    def _attach(self, core: Any) -> list[float]:
        return core.add_springs(*self._args)  # the rest lengths, taken from the positions when not given


FALLOFF_SHAPES = ("sphere", "tube", "box")
FALLOFF_LAWS = ("constant", "linear", "smooth", "inverse_square")
VORTEX_PROFILES = ("rankine", "lamb_oseen", "constant")


def _choice(name: str, value: Any, allowed: tuple[str, ...]) -> str:
    value = _checks.text(name, value)
    if value not in allowed:
        raise ValueError(f"{name} = {value!r} is invalid: it must be one of {', '.join(repr(a) for a in allowed)}")
    return value


@dataclass(frozen=True)
class Falloff(_Checked):
    """Where a field force acts: a weight φ(x) in [0, 1] that multiplies it, F = φ(x) F₀ (as the
    falloff of Blender's force fields: Shape, Min/Max Distance).

    The distance d (m) is measured from a `shape`:

    - ``"sphere"``: from `center`;
    - ``"tube"``: from the line through `center` along `axis` (distance across it);
    - ``"box"``: from the axis-aligned box `center` ± `half_size` (0 inside it).

    `center` None is the force's own point (a `Vortex`'s or an `Attractor`'s; a `Wind` or a
    `Turbulence` has none, so give it); a tube's `axis` None is a `Vortex`'s axis, else z.
    The `law`, with r₀ = `min_distance` and r₁ = `max_distance` (None: no limit), gives φ = 1
    for d ≤ r₀, φ = 0 for d > r₁ and between, with t = (d − r₀)/(r₁ − r₀):
    ``"constant"`` φ = 1 (a cut at r₁); ``"linear"`` φ = 1 − t; ``"smooth"`` φ = 1 − (3t² −
    2t³) (continuous with its slope; these two need r₁); ``"inverse_square"`` φ = (r₀/d)²
    (needs r₀ > 0; jumps to 0 at r₁ if one is given).
    """

    shape: str = "sphere"
    law: str = "smooth"
    min_distance: float = 0.0
    max_distance: float | None = None
    center: Any = None
    axis: Any = None
    half_size: Any = None

    def _checked(self) -> tuple:
        shape = _choice("shape", self.shape, FALLOFF_SHAPES)
        law = _choice("law", self.law, FALLOFF_LAWS)
        r0 = _checks.real("min_distance", self.min_distance)
        r1 = _checks.real("max_distance", self.max_distance, optional=True)
        r1 = float("inf") if r1 is None else r1
        if not (math.isfinite(r0) and r0 >= 0):
            raise ValueError(f"min_distance = {_checks.describe(self.min_distance)} is invalid: it must be finite and >= 0 (m)")
        if law == "inverse_square" and r0 <= 0:
            raise ValueError(
                f"min_distance = {_checks.describe(self.min_distance)} is invalid: the inverse-square law needs min_distance > 0 m: φ = (min_distance/d)²"
            )
        if math.isnan(r1) or r1 <= r0 or (law in ("linear", "smooth") and math.isinf(r1)):
            need = (
                f"a {law} falloff needs a finite max_distance > min_distance" if law in ("linear", "smooth") else "it must be > min_distance (None: no limit)"
            )
            raise ValueError(f"max_distance = {_checks.describe(self.max_distance)} is invalid: {need} ({r0} m)")
        center = None if self.center is None else _vec("center", self.center, "m")
        axis = None if self.axis is None else _vec("axis", self.axis, "a direction")
        half = None if self.half_size is None else _vec("half_size", self.half_size, "m")
        if shape == "box" and half is None:
            raise ValueError("half_size = None is invalid: a box falloff needs its half sizes [hx, hy, hz] (m)")
        return shape, law, r0, r1, center, axis, half

    def _binding(self, owner: str, point: list[float] | None = None, axis: list[float] | None = None) -> tuple:
        """The engine's falloff for a force `owner` whose own point and axis are these."""
        shape, law, r0, r1, center, own_axis, half = self._args
        if center is None:
            if point is None:
                raise ValueError(f"falloff.center = None is invalid: a {owner} has no point of its own; give the falloff's center [x, y, z] (m)")
            center = point
        a = own_axis if own_axis is not None else (axis if axis is not None else [0.0, 0.0, 1.0])
        return shape, law, center, a, half if half is not None else [0.0, 0.0, 0.0], r0, r1


def _falloff(value: Any) -> Falloff | None:
    if value is None or isinstance(value, Falloff):
        return value
    raise TypeError(f"falloff = {_checks.describe(value)} is invalid: it must be a kinema.Falloff or None, not {type(value).__name__}")


@dataclass(frozen=True)
class Attractor(_Checked):
    """Inverse-square pull toward a fixed point: F_i = −μ m_i r / (|r|² + ε²)^{3/2}, r = x_i − point.

    `strength` μ = G·M in m³/s², `softening` ε in m; `point` [x, y, z] or [x, y] (z = 0), m.
    A `falloff` (``kinema.Falloff``; its centre defaults to `point`) multiplies the pull by
    φ(x); the shaped pull has no potential energy and counts as a force that may add energy.
    """

    point: Any = (0.0, 0.0, 0.0)
    strength: float = 1.0
    softening: float = 0.0
    falloff: Falloff | None = None

    def _checked(self) -> tuple:
        point = _vec("point", self.point, "m")
        falloff = _falloff(self.falloff)
        shaped = None if falloff is None else falloff._binding("Attractor", point)
        return point, _checks.real("strength", self.strength), _checks.real("softening", self.softening), shaped

    def _attach(self, core: Any) -> None:
        *args, falloff = self._args
        if falloff is None:
            core.add_attractor(*args)
        else:
            core.add_attractor(*args, falloff)


@dataclass(frozen=True)
class Wind(_Checked):
    """A uniform wind field: F_i = b (w − v_i), drag relative to air moving at `velocity` w
    (m/s; [x, y, z] or [x, y] meaning (x, y, 0)), `coefficient` b in kg/s. A `falloff`
    (``kinema.Falloff`` with its `center`) confines it: F_i = φ(x_i) b (w − v_i)."""

    velocity: Any = (1.0, 0.0, 0.0)
    coefficient: float = 1.0
    falloff: Falloff | None = None

    def _checked(self) -> tuple:
        falloff = _falloff(self.falloff)
        shaped = None if falloff is None else falloff._binding("Wind")
        return _vec("velocity", self.velocity, "m/s"), _checks.real("coefficient", self.coefficient), shaped

    def _attach(self, core: Any) -> None:
        *args, falloff = self._args
        if falloff is None:
            core.add_wind(*args)
        else:
            core.add_wind(*args, falloff)


@dataclass(frozen=True)
class Vortex(_Checked):
    """A vortex about the axis through `point` along `axis`: a purely tangential field
    u = U(r) θ̂, r the distance from the axis, θ̂ counter-clockwise seen from the axis' tip.

    `strength` S is the tangential speed at the core `radius` R (m); `profile`:
    ``"rankine"`` U = S r/R inside R, S R/r outside (a solid core, a free vortex around it);
    ``"lamb_oseen"`` U = S (R/r)(1 − e^{−r²/R²})/(1 − e^{−1}) (smooth); ``"constant"``
    U = S (Blender's vortex; R unused). Negative S turns the other way.

    With `coefficient` None the field is an acceleration (S in m/s²): F_i = m_i u. With a
    `coefficient` b (kg/s) it is air turning at U (S in m/s) that drags the particles along:
    F_i = b (u − v_i) (Houdini's "treat as wind"). A `falloff` (``kinema.Falloff``; its
    centre defaults to `point`, a tube's axis to `axis`) multiplies F by φ(x).
    `point` and `axis` are [x, y, z] or [x, y] (z = 0); in a 2D world the axis is z.
    """

    point: Any = (0.0, 0.0, 0.0)
    axis: Any = (0.0, 0.0, 1.0)
    strength: float = 1.0
    radius: float = 1.0
    profile: str = "rankine"
    coefficient: float | None = None
    falloff: Falloff | None = None

    def _checked(self) -> tuple:
        point = _vec("point", self.point, "m")
        axis = _vec("axis", self.axis, "a direction")
        falloff = _falloff(self.falloff)
        shaped = None if falloff is None else falloff._binding("Vortex", point, axis)
        return (
            point,
            axis,
            _checks.real("strength", self.strength),
            _checks.real("radius", self.radius),
            _choice("profile", self.profile, VORTEX_PROFILES),
            _checks.real("coefficient", self.coefficient, optional=True),
            shaped,
        )

    def _attach(self, core: Any) -> None:
        axis = self._args[1]
        if core.dim == 2 and (axis[0] != 0 or axis[1] != 0):
            raise ValueError(
                f"axis = {_checks.describe(self.axis)} is invalid: in a 2D world (the xy-plane) a vortex turns about z; give axis = [0, 0, 1] (or [0, 0, -1])"
            )
        core.add_vortex(*self._args)


MAX_SEED = 2**63 - 1


@dataclass(frozen=True)
class Turbulence(_Checked):
    """Curl-noise turbulence (Bridson, Hourihan & Nordenstam 2007): a divergence-free random
    field u = ∇ × ψ, ψ smooth Perlin noise, so particles swirl without bunching up.

    `strength` is the rms of each component of u; `scale` (m) the noise's feature size (the
    lattice spacing: u is correlated over about `scale`); `seed` (0 to 2**63 − 1) picks the
    field, the same seed giving the same bits. `time_scale` τ (s; None: a frozen field):
    the field changes over about τ (its gradients turn; the correlation in time is
    2 cos(t/τ) sin(t/2τ)/(t/τ)). `octaves` 1 to 8 add finer noise, each of half the scale and
    `roughness` (0 to 1) times the weight of the one before. In a 2D world u comes from one
    stream function ψ(x, y): u = (∂ψ/∂y, −∂ψ/∂x).

    With `coefficient` None it is an acceleration (`strength` in m/s²): F_i = m_i u, as
    Blender's turbulence field. With a `coefficient` b (kg/s) it is the velocity of air
    (`strength` in m/s) that drags the particles along: F_i = b (u − v_i), as Houdini's curl
    noise treated as wind. A `falloff` (``kinema.Falloff`` with its `center`) multiplies F
    by φ(x).
    """

    strength: float = 1.0
    scale: float = 1.0
    seed: int = 0
    time_scale: float | None = None
    octaves: int = 1
    roughness: float = 0.5
    coefficient: float | None = None
    falloff: Falloff | None = None

    def _checked(self) -> tuple:
        falloff = _falloff(self.falloff)
        return (
            _checks.real("strength", self.strength),
            _checks.real("scale", self.scale),
            _checks.integer("seed", self.seed, 0, MAX_SEED, what="the seed must be an integer from 0 to 2**63 - 1"),
            _checks.real("time_scale", self.time_scale, optional=True),
            _checks.integer("octaves", self.octaves, 1, 8),
            _checks.real("roughness", self.roughness),
            _checks.real("coefficient", self.coefficient, optional=True),
            None if falloff is None else falloff._binding("Turbulence"),
        )

    def _attach(self, core: Any) -> None:
        core.add_turbulence(*self._args)


@dataclass(frozen=True)
class PythonForce(_Checked):
    """Your own force: `fn(t, x, v) -> F` receives positions and velocities as (N, 3) arrays
    (m, m/s) and returns forces (N) of the same shape; called once per force evaluation."""

    fn: Callable[[float, np.ndarray, np.ndarray], Any]
    name: str = "python"

    def _checked(self) -> tuple:
        if not callable(self.fn):
            raise TypeError(f"fn = {_checks.describe(self.fn)} is invalid: PythonForce.fn must be a callable fn(t, x, v) -> F, not {type(self.fn).__name__}")
        return self.fn, _checks.text("name", self.name)

    def _attach(self, core: Any) -> None:
        core.add_python_force(*self._args)
