"""Recorded frames of a world run: times, positions, velocities and diagnostics as arrays."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass
class Trajectory:
    """Frames of a run. ``t`` (F,), ``positions`` and ``velocities`` (F, N, 3); energies in J:
    ``kinetic`` (F,), ``potential`` {force name: (F,)}, ``total`` (F,); ``momentum`` and
    ``angular_momentum`` (F, 3).

    Collisions (all zeros while they are off): ``contacts`` (F,), the number of contacts at
    the frame; ``impulse_balance`` (F, 3), N·s, the sum of the impulses between movable
    particles since the previous frame (0 at frame 0), zero by action and reaction up to
    rounding; ``collision_energy_lost`` (F,), J, the kinetic energy the collisions removed
    since they were turned on."""

    t: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    kinetic: np.ndarray
    potential: dict[str, np.ndarray]
    momentum: np.ndarray
    angular_momentum: np.ndarray
    contacts: np.ndarray
    impulse_balance: np.ndarray
    collision_energy_lost: np.ndarray
    total: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        self.total = self.kinetic + sum(self.potential.values(), np.zeros_like(self.kinetic))

    @staticmethod
    def _recorder() -> _Recorder:
        return _Recorder()

    def plot_energy(self, ax: Any = None) -> Any:
        """Kinetic, each potential and the total energy against time, and the energy lost in
        collisions when there is any; returns the Axes."""
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(figsize=(7, 4))
        ax.plot(self.t, self.kinetic, label="kinetic")
        for name, u in self.potential.items():
            ax.plot(self.t, u, label=f"potential ({name})")
        ax.plot(self.t, self.total, "k", lw=2, label="total")
        if np.any(self.collision_energy_lost != 0):
            ax.plot(self.t, self.collision_energy_lost, "k--", label="lost in collisions")
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
        stats = world.collision_stats()
        if stats is None:
            contacts, balance, lost = 0, np.zeros(3), 0.0
        else:
            contacts, balance, lost = stats["last"]["contacts"], stats["total"]["impulse_balance"], stats["total"]["energy_lost"]
        frame = (d["t"], world.positions.copy(), world.velocities.copy(), d["kinetic"], d["potential"], d["momentum"], d["angular_momentum"])
        self.frames.append((*frame, contacts, balance, lost))

    def finish(self) -> Trajectory:
        t, x, v, ke, pot, p, ang, contacts, balance, lost = zip(*self.frames, strict=True)
        names = list(dict.fromkeys(name for frame in pot for name in frame))  # a force added mid-run counts from then
        # The world sums the impulse balance over all its steps; a frame gets what its steps
        # added (the first frame none).
        balance = np.diff(np.array(balance), axis=0, prepend=np.array(balance)[:1])
        return Trajectory(
            t=np.array(t),
            positions=np.array(x),
            velocities=np.array(v),
            kinetic=np.array(ke),
            potential={name: np.array([f.get(name, 0.0) for f in pot]) for name in names},
            momentum=np.array(p),
            angular_momentum=np.array(ang),
            contacts=np.array(contacts, dtype=np.int64),
            impulse_balance=balance,
            collision_energy_lost=np.array(lost),
        )
