"""The viewer page: the frames packed as little-endian float32, the metadata, and the HTML."""

from __future__ import annotations

import base64
import json
import math
import os
import re
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..io._files import atomic_file

_HERE = Path(__file__).parent
BUNDLE = _HERE / "static" / "viewer.js"
TEMPLATE = _HERE / "template.html"

# Bytes of frame data (positions and speeds) a page carries before frames, then particles,
# are left out. An inlined page grows by 4/3 (base64) and the browser holds the decoded copy.
HTML_MAX_BYTES = 100_000_000
SERVE_MAX_BYTES = 400_000_000
_MIN_FRAMES = 10  # frames kept, when there are that many, before particles are left out


class BundleMissingError(FileNotFoundError):
    """The viewer's script bundle has not been built."""

    def __init__(self) -> None:
        super().__init__(
            f"the viewer's script {BUNDLE} is missing: this installation of kinema is incomplete; reinstall it (from a source checkout: `make viewer` rebuilds the script with Node)"
        )


class ViewerWarning(UserWarning):
    """The page shows fewer frames or particles than the trajectory holds."""


@dataclass
class Packed:
    """What a page shows: metadata (JSON-ready) and float32 arrays (positions (F, N, 3),
    speed (F, N) or None, radii (N,))."""

    meta: dict[str, Any]
    positions: np.ndarray
    speed: np.ndarray | None
    radii: np.ndarray


def _strides(frames: int, particles: int, per_particle: int, max_bytes: int) -> tuple[int, int]:
    """Frame and particle strides that bring frames * particles * per_particle under max_bytes:
    frames first, down to _MIN_FRAMES, then particles."""
    total = frames * particles * per_particle
    if total <= max_bytes:
        return 1, 1
    keep = max(min(frames, _MIN_FRAMES), max_bytes // (particles * per_particle))
    frame_stride = math.ceil(frames / keep) if keep < frames else 1
    kept = len(range(0, frames, frame_stride))
    particle_stride = max(1, math.ceil(kept * particles * per_particle / max_bytes))
    return frame_stride, particle_stride


def pack(traj: Any, max_bytes: int) -> Packed:
    """The frames of ``traj`` as a page shows them, left out by strides if they are over
    ``max_bytes`` (a ``ViewerWarning`` says so, and the page shows a note)."""
    positions = np.asarray(traj.positions, dtype=np.float64)
    if positions.ndim != 3 or positions.shape[2] != 3 or positions.shape[0] == 0:
        raise ValueError(f"positions must be (frames, particles, 3) with at least one frame, got {positions.shape}")
    frames, particles, _ = positions.shape
    velocities = getattr(traj, "velocities", None)
    has_speed = velocities is not None and np.shape(velocities) == positions.shape
    per_particle = 4 * (3 + (1 if has_speed else 0))
    fs, ps = _strides(frames, particles, per_particle, max_bytes)
    note = ""
    if fs > 1 or ps > 1:
        kept_f, kept_n = len(range(0, frames, fs)), len(range(0, particles, ps))
        note = f"showing {kept_f} of {frames} frames and {kept_n} of {particles} particles"
        warnings.warn(f"the viewer is {note} (the frames are over {max_bytes / 1e6:.0f} MB)", ViewerWarning, stacklevel=3)
    positions = positions[::fs, ::ps]
    t = np.asarray(traj.t, dtype=np.float64)[::fs]
    speed = np.linalg.norm(np.asarray(velocities)[::fs, ::ps], axis=2).astype("<f4") if has_speed else None

    finite = positions[np.isfinite(positions).all(axis=2)]
    lo, hi = (finite.min(axis=0), finite.max(axis=0)) if finite.size else (np.zeros(3), np.ones(3))
    extent = float(np.max(hi - lo)) or 1.0
    default_radius = extent / 200.0  # as Trajectory.render draws particles without a radius
    radii = getattr(traj, "radii", None)
    radii = np.full(particles, default_radius) if radii is None else np.where(np.asarray(radii) > 0, radii, default_radius)
    radii = radii[::ps]
    pad = float(radii.max()) if radii.size else 0.0
    speed_max = float(np.nanmax(speed)) if speed is not None and speed.size and np.isfinite(speed).any() else 0.0
    meta = {
        "n": int(positions.shape[1]),
        "frames": int(positions.shape[0]),
        "dim": int(getattr(traj, "dim", 3) or 3),
        "t": [float(x) for x in t],
        "bounds": {"min": [float(x) - pad for x in lo], "max": [float(x) + pad for x in hi]},
        "speedMax": speed_max,
        "defaultRadius": default_radius,
        "note": note,
    }
    return Packed(meta, np.ascontiguousarray(positions, dtype="<f4"), speed, np.ascontiguousarray(radii, dtype="<f4"))


def bundle() -> str:
    """The built viewer script (shipped in the package); ``BundleMissingError`` when it is missing."""
    if not BUNDLE.is_file():
        raise BundleMissingError()
    script = BUNDLE.read_text(encoding="utf-8")
    # Inside <script> only "</script" ends the element; the bundle is escaped where it could.
    return re.sub(r"</(script)", r"<\\/\1", script, flags=re.IGNORECASE)


def page(meta: dict[str, Any], title: str = "kinema") -> str:
    """The HTML page around ``meta`` (the content of the kinema-data element) and the bundle."""
    data = json.dumps(meta, separators=(",", ":")).replace("</", "<\\/")
    parts = {"TITLE": title.replace("&", "&amp;").replace("<", "&lt;"), "DATA": data, "SCRIPT": bundle()}
    template = TEMPLATE.read_text(encoding="utf-8")
    return re.sub(r"\{\{(TITLE|DATA|SCRIPT)\}\}", lambda m: parts[m.group(1)], template)


def _b64(array: np.ndarray) -> str:
    return base64.b64encode(array.tobytes()).decode("ascii")


def html_page(traj: Any, *, title: str = "kinema", max_bytes: int = HTML_MAX_BYTES) -> str:
    """The self-contained page of ``traj`` as text (see :func:`write_html`)."""
    bundle()  # fail before any work when the script is not built
    packed = pack(traj, max_bytes)
    meta = dict(packed.meta, positions=_b64(packed.positions), radii=_b64(packed.radii))
    meta["speed"] = _b64(packed.speed) if packed.speed is not None else None
    return page(meta, title)


def write_html(traj: Any, path: str | os.PathLike, *, title: str = "kinema", max_bytes: int = HTML_MAX_BYTES) -> Path:
    """Write one self-contained HTML file that plays ``traj`` offline (the script and the
    frames inlined, the frames as base64 float32) and return its path. The file is written
    under a temporary name and renamed. Frames, then particles, are left out by strides when
    the frame data is over ``max_bytes`` (a ``ViewerWarning`` says so)."""
    text = html_page(traj, title=title, max_bytes=max_bytes)
    path = Path(path)
    with atomic_file(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return path
