"""A Blender scene (.blend) of a trajectory, built by Blender itself: kinema writes the USD
stage beside it (`usd_writer.write_usd`) and Blender imports it and adds what its USD
importer leaves out (`blender_scene.py`, run in Blender's Python)."""

from __future__ import annotations

import importlib.util
import json
import os
import shutil
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ._files import Frames, TrajectoryFileError, copy_into, private_folder

#: The environment variable naming the Blender to run: its executable (`blender`), or a
#: Python that imports `bpy` (Blender as a Python module).
BLENDER_VARIABLE = "KINEMA_BLENDER"
#: How long Blender may take to import the stage and save the scene (s).
BLENDER_TIMEOUT = 600.0


def blender_command(script: Path, blender: str | os.PathLike | None = None) -> list[str]:
    """The command that runs `script` in Blender: `blender` (default `$KINEMA_BLENDER`),
    a Python with `bpy` (its name starts with "python") or a Blender executable; else this
    Python where it imports `bpy`; else `blender` on the PATH. Raises `RuntimeError`
    saying how to get one where there is none."""
    chosen = blender if blender is not None else os.environ.get(BLENDER_VARIABLE) or None
    if chosen is not None:
        found = shutil.which(str(chosen))
        if found is None:
            raise RuntimeError(f"Blender {str(chosen)!r} ({'blender=' if blender is not None else '$' + BLENDER_VARIABLE}) is not an executable file")
        if Path(found).name.lower().startswith("python"):
            return [found, str(script)]
        return [found, "--background", "--factory-startup", "--python", str(script), "--"]
    if importlib.util.find_spec("bpy") is not None:
        return [sys.executable, str(script)]
    found = shutil.which("blender")
    if found is not None:
        return [found, "--background", "--factory-startup", "--python", str(script), "--"]
    raise RuntimeError(
        "writing a .blend needs Blender (4.2 or later; tested with 5.0): put `blender` on the PATH, set "
        f"${BLENDER_VARIABLE} to the Blender executable or to a Python that imports bpy, or export "
        "format='usd' and import it in Blender (File → Import → Universal Scene Description)"
    )


def write_blend(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any], blender: str | os.PathLike | None = None) -> list[Path]:
    """Write `path` (.blend) and the stage it plays, `path` with the suffix .usdc; returns
    `[path, stage]`.

    Blender (`blender_command`) imports the stage and saves the scene: the timeline 0 … F − 1
    at the stage's rate (the fps asked of `World.run`, `usd_writer._frame_rate`), the
    particles in their `displayColor` in Cycles and Eevee (a material on the point cloud
    object, which the importer does not make), the colliders as rendered meshes (the stage's
    `colliders` material, translucent) moving where they move, the springs grey, a camera
    framing the particles, a sun and a grey world. The .blend reads the stage as it plays
    (a Mesh Sequence Cache, `//<stem>.usdc`): keep them in one folder."""
    from .usd_writer import _frame_rate, write_usd

    if path.suffix.lower() != ".blend":
        raise ValueError(f"path = {str(path)!r}: a Blender scene's name ends in .blend")
    script = Path(__file__).with_name("blender_scene.py")
    command = blender_command(script, blender)  # (no Blender: refused before anything is written)
    stage = path.with_suffix(".usdc")
    if stage.exists() and stage.is_dir():
        raise TrajectoryFileError(f"cannot write {stage} (the stage of {path.name}): it is a directory")
    write_usd(traj, fr, stage, on_frame)
    rate = _frame_rate(fr.t, getattr(traj, "fps", None))
    fps = max(1, round(rate))
    lo, hi = _extent(fr)
    # Blender saves in a private folder (its own failed write is not to touch `path`), and
    # Python copies the scene to `path` (a temporary name beside it, renamed when complete)
    with private_folder(path) as staging:
        built = staging / path.name
        job = {"usd": str(stage.resolve()), "blend": str(built), "fps": fps, "fps_base": fps / rate, "frames": fr.n_frames, "lo": lo, "hi": hi}
        run = subprocess.run([*command, json.dumps(job)], capture_output=True, text=True, timeout=BLENDER_TIMEOUT)
        if run.returncode != 0 or not built.is_file():
            tail = (run.stderr or run.stdout).strip().splitlines()[-8:]
            raise RuntimeError(f"Blender ({command[0]}) could not build {path}: exit status {run.returncode}\n" + "\n".join(tail))
        copy_into(built, path)
    return [path, stage]


def _extent(fr: Frames) -> tuple[list[float], list[float]]:
    """The particles' extent over the frames, their radii included (m)."""
    radii = fr.radii if fr.radii is not None else np.zeros(fr.n_particles)
    x = np.where(fr.alive[:, :, None], fr.positions, np.nan)
    reach = radii[None, :, None]
    if not np.isfinite(x).any():
        return [-1.0, -1.0, -1.0], [1.0, 1.0, 1.0]
    return np.nanmin(x - reach, axis=(0, 1)).tolist(), np.nanmax(x + reach, axis=(0, 1)).tolist()
