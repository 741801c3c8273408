"""Frames at the rate asked: which steps ``World.run`` takes between its frames.

A run records frame k at t₀ + k/fps exactly, as Blender and Houdini step a frame: by a whole
number of equal substeps. Each frame is ``per_frame`` = ⌈1/(fps·dt)⌉ steps of
h = (1/fps)/per_frame ≤ dt (no step longer than the dt asked, so what is stable at dt stays
stable), the last landing on the frame's time to the bit (the engine's clock,
``crates/kinema/src/world/clock.rs``). A duration that is no whole number of frames ends with
a shorter stretch, unrecorded, so that the world ends at t₀ + duration. Where dt divides the
frame (1/(fps·dt) a whole number), h = dt: the steps are the world's own.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

# The most particle-steps World.run takes unless told otherwise: hours of work (5 hours at 6e6
# particle-steps a second in a gas, days in a pile of contacts); the command line's limit too.
# Here, with the run's plan, so that the checkpoints (resume_run) and the command line share it
# without importing kinema.world (which re-exports it as kinema.world.MAX_WORK).
MAX_WORK = 1e11

# (1/(fps·dt) within this of a whole number counts as that number: 1/(50·0.001) is
# 20.000000000000004 in floating point)
_WHOLE = 1e-9


@dataclass(frozen=True)
class FramePlan:
    """The steps of a run of ``duration`` s at ``fps`` with a world's ``dt`` (see the module
    doc): ``frames`` recorded after the first, ``per_frame`` steps each, then ``tail`` steps
    to the end (0 when the duration is whole frames)."""

    duration: float
    fps: float
    dt: float
    frames: int
    per_frame: int
    tail: int

    @property
    def steps(self) -> int:
        """Steps in all."""
        return self.frames * self.per_frame + self.tail

    @property
    def step(self) -> float:
        """h, s: the length of a frame's steps (dt when dt divides the frame)."""
        return self.dt if self.divides else 1.0 / self.fps / self.per_frame

    @property
    def divides(self) -> bool:
        """Whether dt divides the frame, so that the steps are dt."""
        return abs(1.0 / (self.fps * self.dt) - self.per_frame) <= _WHOLE * self.per_frame

    def time(self, t0: float, k: int) -> float:
        """The time of frame k (0 … frames) of a run from t₀, s: t₀ + k/fps, the last one
        t₀ + duration when the duration is whole frames."""
        if k == self.frames and self.tail == 0:
            return t0 + self.duration
        return t0 + k / self.fps

    def note(self) -> str | None:
        """What the plan changed of dt, in words (``None`` when nothing)."""
        if self.divides:
            return None
        return (
            f"dt = {self.dt:g} s does not divide a frame of 1/{self.fps:g} s: the run steps by {self.step:.6g} s, "
            f"{self.per_frame} steps a frame, so that frame k is at t0 + k/fps exactly"
        )


def plan(duration: float, dt: float, fps: float) -> FramePlan:
    """The frames and steps of a run (``duration`` ≥ 0 s, ``dt`` > 0 s, ``fps`` > 0, finite,
    one frame fewer than 2**63 steps: checked by the callers)."""
    per = 1.0 / fps / dt  # (fps * dt may underflow to 0: 5e-324 * 1e-3)
    per_frame = max(1, math.ceil(per - _WHOLE * per))
    frames = int(math.floor(duration * fps + _WHOLE))
    rest = duration - frames / fps
    tail = math.ceil(rest / dt - _WHOLE * rest / dt) if rest > _WHOLE / fps else 0
    return FramePlan(duration=duration, fps=fps, dt=dt, frames=frames, per_frame=per_frame, tail=max(0, tail))
