"""Recorded frames of a world run: times, positions, velocities and diagnostics as arrays."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass
class Trajectory:
    """Frames of a run. ``t`` (F,), ``positions`` and ``velocities`` (F, N, 3); energies in J:
    ``kinetic`` (F,), ``potential`` {force name: (F,)}, ``total`` (F,); ``momentum`` and
    ``angular_momentum`` (F, 3)."""

    t: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    kinetic: np.ndarray
    potential: dict[str, np.ndarray]
    momentum: np.ndarray
    angular_momentum: np.ndarray
    total: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.total = self.kinetic + sum(self.potential.values(), np.zeros_like(self.kinetic))

    @staticmethod
    def _recorder() -> _Recorder:
        return _Recorder()

    def plot_energy(self, ax: Any = None) -> Any:
        """Kinetic, each potential and the total energy against time; returns the Axes."""
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(7, 4))
        ax.plot(self.t, self.kinetic, label="kinetic")
        for name, u in self.potential.items():
            ax.plot(self.t, u, label=f"potential ({name})")
        ax.plot(self.t, self.total, "k", lw=2, label="total")
        ax.set_xlabel("t (s)")
        ax.set_ylabel("energy (J)")
        ax.legend(fontsize="small")
        ax.grid(True, alpha=0.3)
        return ax


class _Recorder:
    def __init__(self) -> None:
        self.frames: list[tuple] = []

    def add(self, world: Any) -> None:
        d = world.diagnostics()
        self.frames.append((d["t"], world.positions.copy(), world.velocities.copy(), d["kinetic"], d["potential"], d["momentum"], d["angular_momentum"]))

    def finish(self) -> Trajectory:
        t, x, v, ke, pot, p, ang = zip(*self.frames, strict=True)
        names = list(pot[0])
        return Trajectory(
            t=np.array(t),
            positions=np.array(x),
            velocities=np.array(v),
            kinetic=np.array(ke),
            potential={name: np.array([f[name] for f in pot]) for name in names},
            momentum=np.array(p),
            angular_momentum=np.array(ang),
        )
