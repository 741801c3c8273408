"""What a ``kinema.World`` is beyond its public API, as one object (issue 50, "one snapshot"):
``WorldState``, the field table of the world's engine and of the Python extras the world keeps
per particle and per run, a line each saying what it is and its unit (as REBOUND's
``Simulation`` is one table of fields).

The public API gives the rest: the particles' state (``positions``, ``velocities``,
``masses``, ``radii``, ``groups``, ``ids``, ``species``, the spins), the ``forces``, the
``colliders``, the collision settings, the clock (``time``, ``dt``, ``method``) and
``scene``.

Package-internal, and the one way across: ``World._state()`` gives a world's state, the
world's own objects and not copies (``_state(sync=True)`` hands what was written into the
views to the engine first); ``World._restore(state)`` gives the world a state back and reads
its views anew. The checkpoints (``kinema.checkpoint``: written, read back, a run resumed),
the scene export (``kinema.scene.export``) and the scene builder read and write a world only
through these two and the public API. This module imports nothing of kinema's."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(eq=False)
class WorldState:
    """A world's engine and the Python extras it keeps (module doc); N particles, S springs.
    (Compared by identity: its arrays and the engine have no one truth of equality.)"""

    # the engine's world (kinema._core.World): the particles' state to every bit, their ids,
    # the clock, the collision books and what is carried from step to step
    engine: Any
    # (N, 3) each particle's own colour, r g b in [0, 1] (NaN: none); a read-only broadcast while none has one
    colors: np.ndarray
    # (S, 2) int64: the ids at the two ends of each spring, the Spring forces in the order added
    # (a spring lives while both its ends do)
    spring_ids: np.ndarray
    # a Spring's index in the forces -> its springs' rest lengths as the engine took them, m
    # (from the positions when none was given)
    spring_rest: dict[int, np.ndarray]
    # the emitters at work (kinema.emitter's sources: each its Emitter, checked values, particles
    # emitted, births held back for their place, dropped, and its random streams), in the order added
    emitters: list[Any]
    # the kill volumes (KillBox, KillSphere, KillPlane), in the order added
    kills: list[Any]
    # the integration method as given: a name of kinema.method_names() or a ButcherTableau
    # (the engine's, ``World.method``, is its name)
    method: Any
    # whether the stable-step advisor's StabilityWarning has been given (once in a world's life)
    warned: bool
    # whether the ContactTimeWarning of kinema.first_step has been given (once)
    contact_warned: bool
    # whether the advisor looks again before the next step (particles or forces changed since it looked)
    advice_due: bool
    # the number of particles when the advisor last looked (it looks again when it has doubled)
    advised_at: int
    # how many of the colliders have been looked at for a MeshPlacementWarning (the first ones)
    placed: int
    # the scene file `kinema run` started the world's run from and its scene's hash
    # (scene_file, scene_sha256; empty for a world run from Python), written with its checkpoints
    run_source: dict[str, str]
    # (N,) times of death to give the world (a checkpoint's: World._restore hands them to the
    # engine); None: the engine's stay. Read them as ``death``.
    death_given: np.ndarray | None = None

    @property
    def death(self) -> np.ndarray:
        """(N,) each particle's time of death, s (inf: none): those given, else the engine's,
        which keeps them with the particles (``World::times_of_death``), read when asked (a
        read-only broadcast of inf while no particle has one)."""
        if self.death_given is not None:
            return self.death_given
        t = self.engine.times_of_death()
        return np.broadcast_to(np.float64(np.inf), (self.engine.len,)) if t is None else t

    @death.setter
    def death(self, value: np.ndarray) -> None:
        self.death_given = value
