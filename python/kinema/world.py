"""The particle world: particles with mass, position and velocity, moved by forces through
any integration method of the registry.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from . import _core
from .ode import ButcherTableau
from .trajectory import Trajectory

SimulationDiverged = _core.SimulationDiverged


class World:
    """Particles, forces, an integrator, a time step and the time.

    ``World(dim=3, dt=1e-3, method="verlet")``: ``dim`` 2 keeps every particle in the
    xy-plane (z = 0 exactly); ``dt`` in s; ``method`` any name of ``kinema.method_names()`` or
    a ``ButcherTableau``.
    """

    def __init__(self, dim: int = 3, dt: float = 1e-3, method: str | ButcherTableau = "verlet"):
        self._core = _core.World(int(dim), float(dt), method)
        self._forces: list[Any] = []

    # -- building ---------------------------------------------------------------------------
    def add_particles(self, position: Any, velocity: Any = None, mass: Any = 1.0, radius: Any = 0.0, pinned: Any = None) -> np.ndarray:
        """Add particles; returns their indices.

        ``position`` (N, 3) in m (a single (3,) point adds one particle); ``velocity`` (N, 3)
        in m/s (default 0); ``mass`` in kg and ``radius`` in m, scalars or (N,); ``pinned``
        bool, scalar or (N,): a pinned particle never moves (inverse mass 0).
        """
        x = np.atleast_2d(np.asarray(position, dtype=np.float64))
        if x.ndim != 2 or x.shape[1] != 3:
            raise ValueError(f"position has shape {np.shape(position)}; it must be (N, 3) or a single (3,) point")
        n = x.shape[0]
        v = np.zeros_like(x) if velocity is None else np.atleast_2d(np.asarray(velocity, dtype=np.float64))
        try:
            v = np.broadcast_to(v, (n, 3))
            m = np.broadcast_to(np.asarray(mass, dtype=np.float64), (n,))
            r = np.broadcast_to(np.asarray(radius, dtype=np.float64), (n,))
            p = np.broadcast_to(np.asarray(False if pinned is None else pinned, dtype=bool), (n,))
        except ValueError as e:
            raise ValueError(f"velocity, mass, radius and pinned must broadcast to {n} particles: {e}") from None
        start, end = self._core.add_particles(np.ascontiguousarray(x), np.ascontiguousarray(v), m.tolist(), r.tolist(), p.tolist())
        return np.arange(start, end)

    def add(self, force: Any) -> Any:
        """Add a force (``kinema.Gravity``, ``Drag``, ``Spring``, ``Attractor``, ``Wind``,
        ``PythonForce``); returns it."""
        attach = getattr(force, "_attach", None)
        if attach is None:
            raise TypeError(f"{type(force).__name__} is not a kinema force; use kinema.Gravity, Drag, Spring, Attractor, Wind or PythonForce")
        attach(self._core)
        self._forces.append(force)
        return force

    # -- running ----------------------------------------------------------------------------
    def step(self, n: int = 1) -> None:
        """Advance ``n`` steps of ``dt``. Raises ``kinema.SimulationDiverged`` at a step that
        would leave a non-finite state; the world then keeps the state from before it."""
        if int(n) < 0:
            raise ValueError(f"n = {n} is invalid: the number of steps must be >= 0")
        self._core.step(int(n))

    def run(self, duration: float, fps: float = 60.0, callback: Callable[[World], Any] | None = None) -> Trajectory:
        """Simulate ``duration`` seconds from now, recording a frame every 1/fps s (rounded to
        a whole number of steps), the current state included; ``callback(world)`` runs after
        each recorded frame. Returns the ``Trajectory``."""
        duration, fps = float(duration), float(fps)
        if not (np.isfinite(duration) and duration >= 0):
            raise ValueError(f"duration = {duration} is invalid: it must be a finite number of seconds >= 0")
        if not (np.isfinite(fps) and fps > 0):
            raise ValueError(f"fps = {fps} is invalid: frames per second must be > 0")
        per_frame = max(1, round(1.0 / (fps * self.dt)))
        frames = int(np.floor(duration / (per_frame * self.dt) + 1e-9))
        rec = Trajectory._recorder()
        rec.add(self)
        for _ in range(frames):
            self._core.step(per_frame)
            rec.add(self)
            if callback is not None:
                callback(self)
        return rec.finish()

    # -- state ------------------------------------------------------------------------------
    @property
    def positions(self) -> np.ndarray:
        """Positions (N, 3), m (a copy; assign to change them)."""
        return self._core.positions

    @positions.setter
    def positions(self, value: Any) -> None:
        self._core.set_state(np.ascontiguousarray(np.asarray(value, dtype=np.float64)), self._core.velocities)

    @property
    def velocities(self) -> np.ndarray:
        """Velocities (N, 3), m/s (a copy; assign to change them)."""
        return self._core.velocities

    @velocities.setter
    def velocities(self, value: Any) -> None:
        self._core.set_state(self._core.positions, np.ascontiguousarray(np.asarray(value, dtype=np.float64)))

    @property
    def masses(self) -> np.ndarray:
        """Masses (N,), kg (pinned particles keep theirs)."""
        return self._core.masses

    @property
    def momenta(self) -> np.ndarray:
        """Momenta L = m v (N, 3), kg·m/s (0 for pinned particles)."""
        return self._core.masses[:, None] * self._core.velocities

    @property
    def accelerations(self) -> np.ndarray:
        """Accelerations a = F/m (N, 3), m/s², under the forces now (0 for pinned particles)."""
        return self._core.accelerations()

    @property
    def time(self) -> float:
        return self._core.time

    @property
    def dt(self) -> float:
        return self._core.dt

    @property
    def method(self) -> str:
        return self._core.method

    @property
    def dim(self) -> int:
        return self._core.dim

    @property
    def forces(self) -> list[Any]:
        return list(self._forces)

    def __len__(self) -> int:
        return self._core.len

    def diagnostics(self) -> dict:
        """Kinetic energy, potential energy per conservative force, linear and angular momentum now."""
        return self._core.diagnostics()

    def __repr__(self) -> str:
        return f"World(dim={self.dim}, dt={self.dt}, method={self.method!r}, particles={len(self)}, t={self.time:g})"
