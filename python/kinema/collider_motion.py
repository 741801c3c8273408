"""The prescribed motion of a collider: ``Motion`` (steady translation and turn) and
``Keyframes`` (keys of translations and rotations), with the checks of their values. It also
holds the rotations by Euler angles they take: ``rotation_matrix`` and ``quaternion``.
``kinema.colliders`` re-exports every name; this module does not import it."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from . import _checks

# -- prescribed motion --------------------------------------------------------------------------
# The engine moves a collider (collide/motion.rs): at time t a point x₀ of the placement it was
# added in is at x(t) = R(t) (x₀ − c) + c + T(t), c the pivot; its surface moves at
# u(x) = Ṫ + ω × (x − c − T). These two classes say which R and T; `_core.collider_poses` is the
# one implementation of them (the pictures call it, never a copy in Python).


@dataclass(frozen=True)
class Motion:
    """A steady motion of a collider: it translates at `velocity` V (m/s) and turns at
    `angular_velocity` ω (rad/s, the axis's direction by the right-hand rule, its length
    the rate) about `pivot` c (m, a point of the collider's placement as added):

        x(t) = R(t − t_s) (x₀ − c) + c + V (t − t_s),     R(τ) = the rotation by |ω| τ about ω

    from its `start` t_s (s, on the world's clock) on; before it the collider rests where it
    was added. `start=None` (the default) is the time the motion is given: the world's time
    when the collider is added (`World.add`) or the motion set (`World.set_motion`), so a
    motion set at t = 4 s starts there, where the collider is, rather than jumping to where
    it would be had it moved since 0; the world keeps it with that time filled in
    (`w.colliders[k].motion.start`). A drum turning about its own axis:
    `Motion(angular_velocity=(0, 2.0, 0), pivot=(0, 0, 0.3))` with the pivot on the axis.
    Each vector is 3 finite numbers, `start` a finite time (a `ValueError` naming it
    otherwise; a wrong type is a `TypeError`). A `Box` can only translate (ω = 0); in a 2D
    world V lies in the xy-plane and ω along z."""

    velocity: Any = (0.0, 0.0, 0.0)
    angular_velocity: Any = (0.0, 0.0, 0.0)
    pivot: Any = (0.0, 0.0, 0.0)
    start: Any = None

    def __post_init__(self) -> None:
        for name, unit in (("velocity", "m/s"), ("angular_velocity", "rad/s"), ("pivot", "m")):
            object.__setattr__(self, name, _finite3(name, getattr(self, name), unit))
        if self.start is not None:
            start = _checks.real("start", self.start)
            if not math.isfinite(start):
                raise ValueError(f"start = {_checks.describe(self.start)} is invalid: it must be a finite time, s")
            object.__setattr__(self, "start", start)

    def _given_at(self, t: float) -> Motion:
        """This motion with its start filled in: `t` (s, the world's time it is given) when
        it has none."""
        return self if self.start is not None else dataclasses.replace(self, start=float(t))

    @property
    def turns(self) -> bool:
        """Whether it rotates the collider (ω ≠ 0)."""
        return any(c != 0.0 for c in self.angular_velocity)

    def _binding(self) -> dict[str, Any]:
        """The keyword arguments of `_core.World.set_collider_motion` and `_core.collider_poses`."""
        return {
            "velocity": list(self.velocity),
            "angular_velocity": list(self.angular_velocity),
            "pivot": list(self.pivot),
            "start": 0.0 if self.start is None else self.start,
        }


@dataclass(frozen=True)
class Keyframes:
    """A collider's motion by keys: at `times[k]` (s, strictly increasing, at least one) the
    collider is turned by `rotations[k]` about `pivot` c (m) and displaced by
    `translations[k]` (m):

        x(t) = R(t) (x₀ − c) + c + T(t)

    `rotations`: (K, 3) Euler angles in degrees, about the fixed x, then y, then z axis
    (extrinsic XYZ, as `kinema.Mesh`'s `rotation`); `None`: no turn. `translations`:
    (K, 3), m; `None`: no displacement. Between two keys T moves linearly and R turns at a
    constant rate (spherical linear interpolation of the keys' quaternions), so the
    collider's velocity jumps at each key; before the first key and after the last it rests
    there. On the world's clock (t = 0 is the world's time 0).

    Between two keys the collider turns the shorter way, by less than 180°: a key whose angle
    differs from the one before by 180° or more about an axis is refused (put keys in
    between). `quaternions` gives the rotations as unit quaternions (w, x, y, z), the form the
    engine and the descriptions take. Refused with a `ValueError` naming the parameter: no
    time, times not finite or not increasing, a number of translations or rotations other than
    one per time, a value that is not finite; a wrong type is a `TypeError`. A `Box` can
    only translate (rotations must be 0); in a 2D world translations lie in the xy-plane and
    turns are about z."""

    times: Any
    translations: Any = None
    rotations: Any = None
    pivot: Any = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        t = _checks.real_array("times", self.times).reshape(-1) if np.ndim(self.times) <= 1 else None
        if t is None:
            raise ValueError(f"times = {_checks.describe(self.times)} is invalid: it must be a list of keyframe times, s")
        if t.size == 0:
            raise ValueError("times = [] is invalid: keyframes need at least one time, s")
        for k, value in enumerate(t.tolist()):
            if not math.isfinite(value) or (k > 0 and not value > t[k - 1]):
                raise ValueError(f"times[{k}] = {_checks.describe(value)} is invalid: keyframe times must be finite and strictly increasing, s")
        object.__setattr__(self, "times", tuple(t.tolist()))
        for name, unit in (("translations", "m"), ("rotations", "degrees")):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, _rows(name, value, len(self.times), unit))
        object.__setattr__(self, "pivot", _finite3("pivot", self.pivot, "m"))
        if self.rotations is not None:
            for k in range(1, len(self.rotations)):
                step = np.abs(np.subtract(self.rotations[k], self.rotations[k - 1]))
                if step.max() >= 180.0:
                    axis = "xyz"[int(step.argmax())]
                    raise ValueError(
                        f"rotations[{k}] = {_checks.describe(list(self.rotations[k]))} is invalid: it is {step.max():g}° about {axis} from "
                        f"rotations[{k - 1}]; between two keys the collider turns the shorter way (less than 180°): put keys in between"
                    )

    @property
    def turns(self) -> bool:
        """Whether it rotates the collider (a rotation not 0)."""
        return self.rotations is not None and any(c != 0.0 for row in self.rotations for c in row)

    @property
    def quaternions(self) -> np.ndarray | None:
        """(K, 4) unit quaternions (w, x, y, z) of `rotations` (None without them)."""
        if self.rotations is None:
            return None
        return np.array([quaternion(r) for r in self.rotations])

    def _given_at(self, t: float) -> Keyframes:
        """Keys are on the world's clock: the same keyframes whenever they are given."""
        return self

    def _binding(self) -> dict[str, Any]:
        """The keyword arguments of `_core.World.set_collider_motion` and `_core.collider_poses`."""
        q = self.quaternions
        return {
            "times": list(self.times),
            "translations": None if self.translations is None else [list(r) for r in self.translations],
            "rotations": None if q is None else q.tolist(),
            "pivot": list(self.pivot),
        }


MOTIONS = (Motion, Keyframes)


def _finite3(name: str, value: Any, unit: str) -> tuple[float, float, float]:
    """`value` as 3 finite floats (a `ValueError` naming `name` and the `unit` otherwise)."""
    v = _checks.real_array(name, value).reshape(-1)
    if v.size != 3 or not np.all(np.isfinite(v)):
        raise ValueError(f"{name} = {_checks.describe(value)} is invalid: it must be 3 finite numbers (x, y, z), {unit}")
    return tuple(v.tolist())


def _rows(name: str, value: Any, n: int, unit: str) -> tuple[tuple[float, float, float], ...]:
    """`value` as `n` rows of 3 finite numbers (a `ValueError` naming `name` otherwise)."""
    a = _checks.real_array(name, value)
    if a.shape != (n, 3):
        raise ValueError(f"{name} has shape {a.shape}; it must be ({n}, 3): one (x, y, z) per keyframe time, {unit}")
    bad = np.argwhere(~np.isfinite(a))
    if bad.size:
        k, c = bad[0]
        raise ValueError(f"{name}[{k}][{c}] = {_checks.describe(a[k, c])} is invalid: it must be finite, {unit}")
    return tuple(tuple(row) for row in a.tolist())


def _motion_of(value: Any) -> Motion | Keyframes | None:
    """A collider's `motion`: a `Motion`, `Keyframes` or None (a `TypeError` naming it)."""
    if value is None or isinstance(value, MOTIONS):
        return value
    raise TypeError(f"motion = {_checks.describe(value)} is invalid: it must be a kinema.Motion, kinema.Keyframes or None, not {_checks._type_words(value)}")


def quaternion(rotation: Any) -> tuple[float, float, float, float]:
    """The unit quaternion (w, x, y, z), w ≥ 0, of Euler angles (α, β, γ) in degrees about the
    fixed x, y, z axes (extrinsic XYZ, the matrix of `rotation_matrix`). From the matrix
    R by Shepperd's method: of 4w² = 1 + tr R, 4x² = 1 + 2R₀₀ − tr R, ... the largest is taken
    (its square root loses no digits), the others from the off-diagonal sums and differences."""
    r = rotation_matrix(rotation)
    tr = r[0, 0] + r[1, 1] + r[2, 2]
    squares = [1.0 + tr, 1.0 + 2 * r[0, 0] - tr, 1.0 + 2 * r[1, 1] - tr, 1.0 + 2 * r[2, 2] - tr]  # 4w², 4x², 4y², 4z²
    k = int(np.argmax(squares))
    s = 2.0 * math.sqrt(squares[k])  # 4 times the largest component
    d = (r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1])  # 4w·(x, y, z)
    sums = {(0, 1): r[0, 1] + r[1, 0], (0, 2): r[0, 2] + r[2, 0], (1, 2): r[1, 2] + r[2, 1]}  # 4xy, 4xz, 4yz
    if k == 0:
        q = [s / 4, d[0] / s, d[1] / s, d[2] / s]
    else:
        a = k - 1
        q = [d[a] / s, 0.0, 0.0, 0.0]
        q[k] = s / 4
        for b in range(3):
            if b != a:
                q[b + 1] = sums[(min(a, b), max(a, b))] / s
    if q[0] < 0:
        q = [-c for c in q]
    return tuple(float(c) for c in q)


def rotation_matrix(rotation: Any) -> np.ndarray:
    """R = R_z(γ) R_y(β) R_x(α) (3, 3) of Euler angles (α, β, γ) in degrees: a rotation about
    the fixed x axis, then y, then z (extrinsic XYZ)."""
    ax, ay, az = np.radians(np.asarray(rotation, dtype=np.float64))
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx
