"""Which run a checkpoint belongs to (for `kinema.runner`): the scene file a run was started
from and its scene's hash, given to the world (`_run_source`) and written with its
checkpoints, and the check that ``kinema run --resume`` goes on with the same scene and
duration (`_same_run`, by content: `scene_digest`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any


def scene_digest(scene: Any) -> str:
    """The hash (SHA-256, hex) of a scene's content: the scene as kinema writes it
    (``Scene.to_toml_string``), whatever the file's layout, comments or name."""
    import hashlib

    try:
        text = scene.to_toml_string()
    except (TypeError, ValueError):  # (a value TOML cannot write: the scene's data as Python says it)
        text = repr(scene.to_dict())
    return hashlib.sha256(text.encode()).hexdigest()


def _same_run(plan: dict, ckpt: Path, path: Path, scene: Any, duration: float | None) -> None:
    """Refuse (``ValueError``) to resume from ``ckpt`` a run of another scene than ``scene``
    (read from ``path``; by content: ``scene_digest``) or of another duration than the
    ``--duration`` given. A checkpoint of a run started in Python says no scene file: only
    its duration is checked."""
    if plan.get("scene_sha256") is not None and plan["scene_sha256"] != scene_digest(scene):
        raise ValueError(
            f"--resume: {ckpt} was written by a run of the scene {plan.get('scene_file') or '(unnamed)'} as it was then, "
            f"and {path} differs from it; run {path} without --resume to start it afresh"
        )
    if duration is not None and duration != plan["duration"]:
        raise ValueError(
            f"--resume: --duration {duration:g} s differs from the {plan['duration']:g} s of the run that wrote {ckpt}; "
            f"give --duration {plan['duration']:g} or none to resume it, or run without --resume to start afresh"
        )


def _run_source(world: Any, source: dict[str, str]) -> None:
    """Gives the world the scene file its run was started from and its scene's hash
    (``scene_file``, ``scene_sha256``: its state's ``run_source``), written with its
    checkpoints: ``--resume`` refuses a checkpoint of another scene."""
    state = world._state()
    state.run_source = source
    world._restore(state)
