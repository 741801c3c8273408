"""The checked frames of a trajectory-like object: ``Frames``, its per-particle arrays in SI
units, and ``frames_of``, which reads them from the object's attributes and checks their
shapes. ``kinema.io._files`` re-exports these names."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Frames:
    """The per-particle data of a trajectory-like object, checked and in SI units: `t`
    (F,) s; `positions` (F, N, 3) m and `velocities` (F, N, 3) m/s (z = 0 in 2D worlds);
    `masses` (N,) kg and `radii` (N,) m, `None` when the object has none; `ids` (N,)
    (0..N-1 by default); `dim` 2 or 3; `dt` s and `method`, `None` when unknown;
    `alive` (F, N) bool, which particles exist at each frame (all True without births and
    deaths; positions and velocities are NaN where not); with spin `angular_velocities`
    (F, N, 3) rad/s, `orientations` (F, N, 4) unit quaternions (w, x, y, z) and
    `inertia` (N,) kg·m², `None` where the trajectory has none; `groups` (N,) int64, each
    particle's collision group (0..31, `check_frames` refuses others), `None` where the
    trajectory has none; `step` s, the length of the run's steps where it is not `dt`
    (`Trajectory.step`: a frame of 1/fps that dt does not divide), else `None`."""

    t: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    masses: np.ndarray | None
    radii: np.ndarray | None
    ids: np.ndarray
    dim: int
    dt: float | None
    method: str | None
    alive: np.ndarray
    angular_velocities: np.ndarray | None = None
    orientations: np.ndarray | None = None
    inertia: np.ndarray | None = None
    groups: np.ndarray | None = None
    step: float | None = None

    @property
    def n_frames(self) -> int:
        return self.t.shape[0]

    @property
    def n_particles(self) -> int:
        return self.positions.shape[1]

    @property
    def changes_count(self) -> bool:
        """Whether particles are born or die: some are not alive at some frame."""
        return not bool(self.alive.all())

    @property
    def has_velocities(self) -> bool:
        """Whether the velocities are known: some particle that exists has one that is not
        NaN. A trajectory read from a file without velocities has them all NaN ("unknown",
        `Trajectory.load`); the exports then write no velocity columns, so that the file
        reads back without velocities rather than with NaN ones."""
        live = self.velocities[self.alive]
        return live.size == 0 or not bool(np.isnan(live).all())

    def live(self, i: int) -> np.ndarray:
        """The columns (particles) alive at frame `i`, in column order (that of `ids`)."""
        return np.flatnonzero(self.alive[i])


def _per_frame_vectors(traj: Any, name: str, n_frames: int) -> np.ndarray:
    a = np.asarray(getattr(traj, name), dtype=np.float64)
    if a.ndim != 3 or a.shape[0] != n_frames or a.shape[2] not in (2, 3):
        raise ValueError(f"{name} has shape {a.shape}; it must be (F, N, 3) with F = {n_frames} frames")
    if a.shape[2] == 2:
        a = np.concatenate([a, np.zeros(a.shape[:2] + (1,))], axis=2)
    return a


def _per_frame_rows(traj: Any, name: str, shape: tuple[int, int, int]) -> np.ndarray | None:
    """The optional (F, N, w) array `name` of `traj` (angular velocities, orientations),
    shape-checked; `None` where it has none."""
    value = getattr(traj, name, None)
    if value is None:
        return None
    a = np.asarray(value, dtype=np.float64)
    if a.shape != shape:
        raise ValueError(f"{name} has shape {a.shape}; it must be {shape}, (F, N, {shape[2]})")
    return a


def _per_particle(traj: Any, names: tuple[str, ...], n: int, dtype: Any) -> np.ndarray | None:
    for name in names:
        value = getattr(traj, name, None)
        if value is not None:
            a = np.asarray(value, dtype=dtype)
            if a.shape != (n,):
                raise ValueError(f"{name} has shape {a.shape}; it must be ({n},), one value per particle")
            return a
    return None


def _groups(traj: Any, n: int) -> np.ndarray | None:
    """The optional collision groups (N,) of `traj` as int64, shape- and type-checked (their
    range is `check_frames`'s); `None` where it has none."""
    value = getattr(traj, "groups", None)
    if value is None:
        return None
    a = np.asarray(value)
    if a.shape != (n,):
        raise ValueError(f"groups has shape {a.shape}; it must be ({n},), one collision group per particle")
    if a.dtype.kind not in "iu" and a.size:
        raise ValueError(f"groups has dtype {a.dtype}; collision groups are integers in 0..31")
    return a.astype(np.int64)


def frames_of(traj: Any) -> Frames:
    """Reads `t`, `positions`, `velocities` and the optional `masses` (or `mass`),
    `radii` (or `radius`), `ids`, `alive`, `dim`, `dt`, `method`,
    `angular_velocities`, `orientations`, `inertia` and `groups` of a
    trajectory-like object and checks their shapes; raises `ValueError` naming the
    attribute that is wrong."""
    t = np.asarray(traj.t, dtype=np.float64)
    if t.ndim != 1:
        raise ValueError(f"t has shape {t.shape}; it must be (F,), one time per frame")
    x = _per_frame_vectors(traj, "positions", t.shape[0])
    v = _per_frame_vectors(traj, "velocities", t.shape[0])
    if v.shape != x.shape:
        raise ValueError(f"velocities have shape {v.shape} but positions {x.shape}; they must match")
    n = x.shape[1]
    alive = getattr(traj, "alive", None)
    alive = np.ones((t.shape[0], n), dtype=bool) if alive is None else np.asarray(alive, dtype=bool)
    if alive.shape != (t.shape[0], n):
        raise ValueError(f"alive has shape {alive.shape}; it must be (F, N) = {(t.shape[0], n)}, one flag per frame and particle")
    dim = int(getattr(traj, "dim", None) or 3)
    if dim not in (2, 3):
        raise ValueError(f"dim = {dim} is invalid: it must be 2 or 3")
    # NaN (a particle not alive, or velocities unknown) is no z != 0
    if dim == 2 and (np.any(np.abs(x[..., 2]) > 0) or np.any(np.abs(v[..., 2]) > 0)):
        raise ValueError("dim = 2 but some positions or velocities have z != 0; a 2D trajectory lies in the xy-plane")
    ids = _per_particle(traj, ("ids", "id"), n, np.int64)
    dt = getattr(traj, "dt", None)
    method = getattr(traj, "method", None)
    return Frames(
        t=t,
        positions=x,
        velocities=v,
        masses=_per_particle(traj, ("masses", "mass"), n, np.float64),
        radii=_per_particle(traj, ("radii", "radius"), n, np.float64),
        ids=np.arange(n, dtype=np.int64) if ids is None else ids,
        dim=dim,
        dt=None if dt is None else float(dt),
        # (a Trajectory's `step` is the steps' length; other objects' may be step numbers)
        step=float(traj.step) if isinstance(getattr(traj, "step", None), float) else None,
        method=None if method is None else str(method),
        alive=alive,
        angular_velocities=_per_frame_rows(traj, "angular_velocities", (t.shape[0], n, 3)),
        orientations=_per_frame_rows(traj, "orientations", (t.shape[0], n, 4)),
        inertia=_per_particle(traj, ("inertia",), n, np.float64),
        groups=_groups(traj, n),
    )
