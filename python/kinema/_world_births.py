"""Births and deaths between the steps of a ``kinema.World``: ``WorldBirths``, a base class of
``World``, not used alone.

``World._advance`` steps in batches up to the next step boundary at which an emitter has a
birth due (``_steps_before_births``, on the engine's clock: ``_time_at``); before each batch
the births due are added where there is room (``_births``; ``_free_places`` and ``_inside``
say where a newborn would overlap a particle or sit inside a collider, and it waits), and the
kill volumes go to the engine (``_send_deaths``), whose deaths after the steps are dropped from
what the Python world holds (``_drop_removed``). ``_changes_count`` says whether any of it can
happen. The emitters' promise: ``emitter_stats``, and the ``EmitterWarning`` of
``_tell_dropped`` and ``_tell_behind``. (The emitters themselves: ``kinema.emitter``.)

Its methods use the world's engine (``_core``: ``kinema._world_views``), ``_add`` and
``_forget`` (``kinema._world_particles``), ``collisions`` (``kinema.world_collisions``) and
what ``World.__init__`` sets (``_emitters``, ``_kills``, ``_colliders``). Units: m, s, kg."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from . import _checks, _core
from .colliders import Collider
from .emitter import BEHIND, EmitterWarning


def _inside(c: Collider, p: np.ndarray, t: float = 0.0) -> bool:
    """Whether the point ``p`` (m) lies inside the collider ``c`` at time ``t`` (s): behind a
    plane, outside a box, inside a sphere obstacle, on the wrong side of a closed mesh (the
    rule of collide/placement.rs, without its tolerance). A moving collider is asked at the
    point of its placement as added that is at ``p`` at ``t``: x₀ = Rᵀ (p − o) of its pose
    [R | o] then (``_core.collider_poses``)."""
    from .colliders import Mesh, Plane, SphereObstacle

    if c.motion is not None:
        pose = _core.collider_poses([float(t)], **c.motion._binding())[0]
        p = np.asarray(p, float)[:3]
        p = pose[:, :3].T @ (p - pose[:, 3])

    if isinstance(c, Mesh):
        return c._contains(p)
    if isinstance(c, Plane):
        n = np.ravel(np.asarray(c.normal, float))
        return float(np.dot(p[: n.size] - np.ravel(np.asarray(c.point, float))[: n.size], n)) < 0.0
    if isinstance(c, SphereObstacle):
        centre = np.ravel(np.asarray(c.center, float))
        return float(np.linalg.norm(p[: centre.size] - centre)) < float(c.radius)
    lo, hi = np.ravel(np.asarray(c.lo, float)), np.ravel(np.asarray(c.hi, float))
    return bool(np.any(p[: lo.size] < lo) or np.any(p[: hi.size] > hi))


class WorldBirths:
    """Births and deaths between the steps of a ``kinema.World``: see ``World`` and
    docs/world.md."""

    def _changes_count(self) -> bool:
        return bool(self._emitters or self._kills or self._core.has_times_of_death)

    def _steps_before_births(self, most: int) -> int:
        """How many steps (1 to ``most``) the engine may take before the next step boundary at
        which some emitter has a particle due: each source's next birth time, as its own
        ``due`` counts it at the step boundaries (the engine's clock, ``_time_at``), or 1 while one holds
        back a particle whose place was taken."""
        if not self._emitters:
            return most
        now, t = self._core.steps, self._core.time
        h = self._core.clock[2]
        k = most
        for source in self._emitters:
            if source.waiting is not None:
                return 1
            c = source.c
            born = c["start"] + source.emitted / c["rate"]  # the next particle's birth time
            if not born < c["end"] or not np.isfinite(born):
                continue
            s = now + max(1, int((born - t) / h) - 1)
            while s - now < k and source.due(self._time_at(s)) <= source.emitted:
                s += 1
            k = min(k, s - now)
        return max(k, 1)

    def _time_at(self, k: int) -> float:
        """The engine's time after ``k`` steps, s, as its clock computes it (the same
        operations: ``crates/kinema/src/world/clock.rs``)."""
        k0, t0, h, landing = self._core.clock
        if landing is not None and k >= landing[0]:
            return landing[1] + float(k - landing[0]) * self._core.dt
        return t0 + float(k - k0) * h

    def _send_deaths(self, core: Any) -> None:
        """Hands the engine the kill volumes (``core``: lent by :meth:`_engine`); the times of
        death are the engine's own (``World::set_times_of_death``)."""
        core.set_kill_volumes([volume._spec() for volume in self._kills])

    def _drop_removed(self, before: np.ndarray) -> None:
        """Drops what the Python world holds for the particles the engine's deaths removed
        (``before``: the ids the world had, in its order)."""
        gone = np.asarray(self._core.take_removed_ids(), dtype=np.int64)
        if gone.size == 0:
            return
        self._forget(~np.isin(before, gone))

    def _births(self) -> None:
        t = self.time
        for source in self._emitters:
            b = source.births(t)
            if b is None:
                continue
            free = self._free_places(b["x"], b["r"], source.c["group"])
            source.hold_back(b, ~free, t)
            if free.any():
                b = {key: value[free] for key, value in b.items()}
                c, k = source.c, len(b["m"])
                e, mu = ([c[name]] * k if c[name] is not None else None for name in ("restitution", "friction"))
                group = np.full(k, c["group"], dtype=np.int64)
                self._add(b["x"], b["v"], b["m"], b["r"], np.zeros(k, bool), e, mu, [c["species"] or ""] * k, b["death"], c["color"], group=group)
        self._tell_dropped(t)

    def _tell_dropped(self, t: float) -> None:
        """One ``EmitterWarning`` for each emitter that has passed its ``end`` having dropped
        births for lack of room (once in its life: its counts are final then)."""
        for k, source in enumerate(self._emitters):
            if not source.told and source.dropped and source.finished(t):
                source.told = True
                warnings.warn(source.shortfall(k, t), EmitterWarning, stacklevel=5)

    def _tell_behind(self) -> None:
        """At the end of a run: one ``EmitterWarning`` for each emitter not yet past its ``end``
        whose births waiting for room are more than ``emitter.BEHIND`` of those due."""
        t = self.time
        for k, source in enumerate(self._emitters):
            st = source.stats(t)
            if not source.finished(t) and st["waiting"] > max(1.0, BEHIND * st["due"]):
                warnings.warn(source.shortfall(k, t), EmitterWarning, stacklevel=4)

    def emitter_stats(self) -> list[dict[str, Any]]:
        """Each emitter's promise and what it kept by now, in the order they were added: a dict
        of ``rate`` (asked, /s), ``start`` and ``until`` (s: its start, and now or its ``end``
        if sooner), ``due`` (particles due by ``until``: start + k/rate before ``end``),
        ``born`` (added to the world), ``waiting`` (drawn, waiting for room at the source),
        ``dropped`` (found no room before ``end``: never born) and ``achieved_rate``
        (born / (until − start), /s; NaN before the start). ``due`` = born + waiting + dropped
        once the births due have been drawn (at the step boundary after their time)."""
        return [source.stats(self.time) for source in self._emitters]

    def _free_places(self, x: np.ndarray, r: np.ndarray, group: int = 0) -> np.ndarray:
        """Which of the particles to be born at ``x`` (m) with radii ``r`` (m) in collision group
        ``group`` overlap neither a particle of the world nor one of them before it (in order),
        and have their centre outside every collider; the others wait (with collisions off, every
        place is free). Particles and colliders that ``group`` does not collide with take no place."""
        free = np.ones(len(r), bool)
        if self.collisions is None:
            return free
        # a centre inside a collider is no place either (the contacts cannot push it out: collide/placement.rs)
        t = self.time
        masks = self._core.collider_masks
        walls = [c for c, mask in zip(self._colliders, masks, strict=True) if mask >> group & 1]
        free &= ~np.array([any(_inside(c, p, t) for c in walls) for p in x], dtype=bool)
        row = self._core.group_masks[group] if self.collisions["self_collisions"] else 0
        if row == 0:
            return free  # the group collides with no particle
        here, radius = self.positions, np.asarray(self._core.radii)
        if row != (1 << _checks.GROUPS) - 1:
            near = (row >> np.asarray(self._core.groups, dtype=np.int64)) & 1 == 1
            here, radius = here[near], radius[near]
        own = row >> group & 1 == 1  # whether the newborns collide with each other
        for k in range(len(r)):
            before = free[:k] & own
            taken = np.concatenate([here, x[:k][before]])
            reach = np.concatenate([radius, r[:k][before]]) + r[k]
            if taken.size and (np.einsum("ij,ij->i", taken - x[k], taken - x[k]) < reach * reach).any():
                free[k] = False
        return free
