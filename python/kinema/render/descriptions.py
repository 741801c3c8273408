"""Colliders as plain descriptions, where a moving one is at given times (`collider_poses`):
the names of `kinema.collider_descriptions`, kept here, where the pictures first had them
(docs/collisions.md names `kinema.render.descriptions.collider_poses`). The module itself moved
below the trajectory files and the checkpoints, which use it as the pictures do."""

from __future__ import annotations

from ..collider_descriptions import _KIND as _KIND
from ..collider_descriptions import KEYFRAME_KEYS as KEYFRAME_KEYS
from ..collider_descriptions import STEADY_KEYS as STEADY_KEYS
from ..collider_descriptions import _describe_colliders as _describe_colliders
from ..collider_descriptions import collider_poses as collider_poses
