"""The run loop of a ``kinema.World`` and what it records: ``WorldRun``, a base class of
``World``, not used alone.

``World.run`` checks its arguments and plans the frames (``kinema.frames``), then hands the
run to ``_record``, the loop a run resumed from a checkpoint goes on with too
(``kinema.checkpoint``): each frame is ``_land``-ed at its time exactly and added to the
recorder of ``kinema.trajectory``, which reads the world through the methods made for it
(``_trajectory_info``, ``_diagnostics_as_pulled``, ``_collision_stats_as_pulled``).
``_look_at_meshes`` is the look at the still meshes added since the last one that ``step`` and
``run`` take before they step (``MeshPlacementWarning``; ``_region``: where an emitter gives
birth).

Its methods use the world's engine and views (``_core``, ``_engine``, ``_pull``, ``_m``:
``kinema._world_views``), its steps and advisor (``World._advance``, ``World._advise``), the
emitters' warnings (``_tell_behind``: ``kinema._world_births``) and the collision API
(``periodic``, ``colliders``: ``kinema.world_collisions``). Units: m, s, kg."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Any

import numpy as np

from . import first_step
from ._world_particles import _unset
from .colliders import Box, Mesh, MeshPlacementWarning, placement_problems
from .frames import plan as frames_plan
from .trajectory import Trajectory


def _region(c: dict) -> tuple[np.ndarray, np.ndarray]:
    """The box (lo, hi) of an emitter's source (its checked values ``c``): where it gives birth."""
    if c["shape"] == "mesh":
        return c["mesh_box"]
    half = np.asarray(c["size"], float) / 2.0 if c["shape"] == "box" else np.full(3, c["radius"] if c["shape"] in ("disc", "sphere") else 0.0)
    return c["center"] - half, c["center"] + half


class WorldRun:
    """The run loop of a ``kinema.World`` and its recording: see ``World`` and docs/world.md."""

    def _record(self, run: dict, callback: Any, checkpoint: Path | None) -> Trajectory:
        """The frames of ``run`` from ``frames_done`` on, writing ``checkpoint`` every
        ``every`` frames (the loop of ``run``, and of a run resumed from a checkpoint)."""
        rec = run["recorder"]
        plan = frames_plan(run["duration"], self.dt, run["fps"])
        while run["frames_done"] < run["frames_total"]:
            try:
                if self._advice_due and self._changes_count():
                    with self._engine() as core:
                        self._advise(core)
                # frame k + 1 at t0 + (k + 1)/fps exactly (kinema.frames)
                measured = self._land(plan.time(run["t0"], run["frames_done"] + 1), plan.per_frame, measure=True, into=rec.room(len(self)))
            finally:
                self._pull()
            rec.add(self, measured)
            run["frames_done"] += 1
            if callback is not None:
                callback(self)
                self._push()
            if checkpoint is not None and run["frames_done"] % run["every"] == 0 and run["frames_done"] < run["frames_total"]:
                self.save_checkpoint(checkpoint, _run=run)
        if plan.tail:
            # a duration of no whole number of frames: on to its end, unrecorded
            try:
                self._land(run["t0"] + run["duration"], plan.tail)
            finally:
                self._pull()
        traj = rec.finish()
        traj.fps = float(run["fps"])  # (saved with it: a video's default rate)
        traj.step = None if plan.divides else plan.step
        self._tell_behind()
        return traj

    def _land(self, t1: float, n: int, measure: bool = False, into: tuple[np.ndarray, np.ndarray] | None = None) -> dict | None:
        """``n`` steps ending at time ``t1`` (s) exactly, each (t1 − t)/n long (the engine's
        clock: ``World::land_at``); with ``measure``, the diagnostics at their end where
        ``_advance`` gives them (else ``None``), and the state written ``into`` the recorder's
        room on the way (``_advance``)."""
        with self._engine() as core:
            core.land_at(t1, n)
        return self._advance(n, measure, into)

    def _look_at_meshes(self) -> None:
        """One ``MeshPlacementWarning`` for each still mesh collider added since the last look
        that is far from every particle and emitter, lies on its side under gravity, or is too
        coarse for the smallest particle (``kinema.colliders.placement_problems``)."""
        if self._placed >= len(self._colliders):
            return
        fresh = range(self._placed, len(self._colliders))
        self._placed = len(self._colliders)
        meshes = [(k, self._colliders[k]) for k in fresh if isinstance(self._colliders[k], Mesh) and self._colliders[k].motion is None]
        if not meshes:
            return
        g = first_step.gravity(self._forces, self.dim)
        regions = [_region(source.c) for source in self._emitters]
        radii = [float(self.radii.min())] if len(self) else []
        radii += [source.c["particle_radius"] - source.c["radius_spread"] for source in self._emitters]
        radius = min((r for r in radii if r > 0), default=None)
        for k, mesh in meshes:
            said = placement_problems(mesh, self.positions, regions, g, radius)
            if said:
                name = f"'{mesh.file.name}'" if mesh.file is not None else "of arrays"
                warnings.warn(f"colliders[{k}], the mesh {name}: {'; '.join(said)}", MeshPlacementWarning, stacklevel=3)

    def _trajectory_info(self) -> dict[str, Any]:
        """What a Trajectory records about the world besides its frames."""
        from .collider_descriptions import _describe_colliders

        periodic = self.periodic
        edges = None
        if any(periodic):
            box = next(c for c in self.colliders if isinstance(c, Box))
            lo, hi = np.zeros(3), np.zeros(3)
            lo[: len(np.ravel(box.lo))], hi[: len(np.ravel(box.hi))] = np.ravel(box.lo), np.ravel(box.hi)
            edges = np.where(periodic, hi - lo, 0.0)
        return {
            "masses": self.masses.copy(),
            "radii": np.array(self._core.radii),
            "ids": self.ids.copy(),
            "species": self.species,
            "colors": self._colors.copy() if not _unset(self._colors) and np.isfinite(self._colors).any() else None,
            "groups": np.array(self.groups),
            "springs": self._spring_ids.copy() if self._spring_ids.size else None,
            "dim": self.dim,
            "dt": self.dt,
            "method": self.method,
            "periodic": periodic if any(periodic) else None,
            "box_edges": edges,
            "colliders": _describe_colliders(self.colliders),
        }

    def _diagnostics_as_pulled(self) -> dict:
        """:meth:`diagnostics` right after the views were read from the engine, with nothing
        written since (the recorder's frames): without comparing the views with the engine."""
        with self._engine() as core:
            return core.diagnostics()

    def _collision_stats_as_pulled(self) -> dict | None:
        """``collision_stats()`` for the recorder, as :meth:`_diagnostics_as_pulled`: the books of
        the steps taken, with nothing written into the views since they were read."""
        return self._core.collision_stats()
