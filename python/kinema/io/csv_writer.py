"""CSV, one text file of all frames: a row per particle and frame."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ._cell import Extras
from ._files import Frames, atomic_file

#: The columns of a spinning particle: its angular velocity (rad/s) and its orientation (w x y z).
SPIN_CSV = ("wx", "wy", "wz")
ORIENTATION_CSV = ("qw", "qx", "qy", "qz")


def _csv_header(fr: Frames, extras: Extras) -> str:
    return (
        "frame,time,id,x,y,z"
        + ",vx,vy,vz" * fr.has_velocities
        + ",mass" * (fr.masses is not None)
        + ",radius" * (fr.radii is not None)
        + ",species" * (extras.names is not None)
        + ",r,g,b" * (extras.colors is not None)
        + "".join(f",{c}" for c in SPIN_CSV) * (fr.angular_velocities is not None)
        + "".join(f",{c}" for c in ORIENTATION_CSV) * (fr.orientations is not None)
        + ",group" * (fr.groups is not None)
    )


def _csv(fr: Frames, i: int, extras: Extras) -> str:
    """The rows of frame `i`, one per particle alive at it: frame,time,id,x,y,z,vx,vy,vz,
    then mass, radius, species (its name), r,g,b (its colour in [0, 1]), wx,wy,wz (its
    angular velocity, rad/s), qw,qx,qy,qz (its orientation) and group (its collision
    group, an integer) where the trajectory has them (17 significant digits)."""
    t = repr(float(fr.t[i]))
    live = fr.live(i)
    cols = [
        fr.positions[i][live],
        *([fr.velocities[i][live]] if fr.has_velocities else []),
        *(a[live][:, None] for a in (fr.masses, fr.radii) if a is not None),
    ]
    table = np.hstack(cols).tolist()
    names = [f",{extras.names[k]}" for k in extras.typeid[live]] if extras.names is not None else [""] * live.size
    colors = [",".join(["", *map(repr, c)]) for c in extras.colors[live].tolist()] if extras.colors is not None else [""] * live.size
    spin = [a[i][live] for a in (fr.angular_velocities, fr.orientations) if a is not None]
    turning = [",".join(["", *map(repr, w)]) for w in np.hstack(spin).tolist()] if spin else [""] * live.size
    groups = [f",{int(g)}" for g in fr.groups[live]] if fr.groups is not None else [""] * live.size
    return "".join(
        f"{i},{t},{int(k)}," + ",".join(map(repr, r)) + name + rgb + w + g + "\n"
        for r, k, name, rgb, w, g in zip(table, fr.ids[live], names, colors, turning, groups, strict=True)
    )


def write_csv(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any]) -> list[Path]:
    """Write `fr` to one CSV file at `path`; returns `[path]`.

    The header `frame,time,id,x,y,z,vx,vy,vz,mass,radius,species,r,g,b,wx,wy,wz,qw,qx,qy,qz,group`
    (`_csv_header`: mass and radius where the trajectory has them, species and r,g,b where
    it has species and colours, the angular velocity and the orientation where it has
    spin, group, the collision group, where it has groups), then a row per particle and frame (`_csv`), every float with 17
    significant digits (exact for float64), in SI units. The file is written under a
    temporary name and renamed at the end. `on_frame(i)` is called after frame `i` is
    written."""
    extras = Extras(traj, fr)
    with atomic_file(path) as tmp, open(tmp, "w", encoding="ascii", newline="") as f:
        f.write(_csv_header(fr, extras) + "\n")
        for i in range(fr.n_frames):
            f.write(_csv(fr, i, extras))
            on_frame(i)
    return [path]
