"""PLY, one binary file per frame, for Blender and Houdini: the particles as vertices, the
springs as edges."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ._cell import Extras, colors_uint8, live_springs
from ._files import SERIES_DIGITS, Frames, atomic_folder, series_names
from .csv_writer import ORIENTATION_CSV, SPIN_CSV

SUFFIXES = (".ply",)  # a path's suffixes that name a PLY export (``exports._SUFFIXES``)


def _ply(fr: Frames, i: int, extras: Extras) -> bytes:
    """Frame `i` as a binary little-endian PLY: one vertex per particle alive at it, float32
    x y z vx vy vz radius, uchar red green blue (the colour, where the trajectory has
    colours), int32 type (the index of its species in the `comment type <index> <name>`
    lines, where it has species), float32 wx wy wz (the angular velocity, rad/s) and qw qx qy
    qz (the orientation) where it has spin, int32 id, and int32 group (the collision
    group, where it has groups), the types Blender's and Houdini's importers
    read (Blender keeps the other properties as point attributes and red green blue as the
    colour attribute `Col`); then, where the trajectory has springs, one edge per spring
    whose two ends are alive, int32 vertex1 vertex2 (its ends' vertex indices), which
    Blender imports as the mesh's edges."""
    columns = [("x", "<f4"), ("y", "<f4"), ("z", "<f4")] + ([("vx", "<f4"), ("vy", "<f4"), ("vz", "<f4")] if fr.has_velocities else [])
    if fr.radii is not None:
        columns.append(("radius", "<f4"))
    if extras.colors is not None:
        columns += [("red", "u1"), ("green", "u1"), ("blue", "u1")]
    if extras.names is not None:
        columns.append(("type", "<i4"))
    spin = [(names, a) for names, a in ((SPIN_CSV, fr.angular_velocities), (ORIENTATION_CSV, fr.orientations)) if a is not None]
    columns += [(name, "<f4") for names, _ in spin for name in names]
    columns.append(("id", "<i4"))
    if fr.groups is not None:
        columns.append(("group", "<i4"))
    live = fr.live(i)
    rows = np.empty(live.size, dtype=columns)
    for k, axis in enumerate("xyz"):
        rows[axis] = fr.positions[i, live, k]
        if fr.has_velocities:
            rows["v" + axis] = fr.velocities[i, live, k]
    if fr.radii is not None:
        rows["radius"] = fr.radii[live]
    if extras.colors is not None:
        rgb = colors_uint8(extras.colors[live])
        for k, name in enumerate(("red", "green", "blue")):
            rows[name] = rgb[:, k]
    if extras.names is not None:
        rows["type"] = extras.typeid[live]
    for names, a in spin:
        for k, name in enumerate(names):
            rows[name] = a[i, live, k]
    rows["id"] = fr.ids[live]
    if fr.groups is not None:
        rows["group"] = fr.groups[live]
    edges = None if extras.springs is None else live_springs(extras.springs, fr, i).astype("<i4")
    ply_type = {"<f4": "float", "<i4": "int", "u1": "uchar"}
    header = [
        "ply",
        "format binary_little_endian 1.0",
        "comment kinema trajectory frame, SI units (m, m/s)",
        f"comment time {float(fr.t[i])!r}",
        *(f"comment type {k} {name}" for k, name in enumerate(extras.names or [])),
        f"element vertex {live.size}",
        *(f"property {ply_type[t]} {name}" for name, t in columns),
        *([f"element edge {len(edges)}", "property int vertex1", "property int vertex2"] if edges is not None else []),
        "end_header",
    ]
    return ("\n".join(header) + "\n").encode("ascii") + rows.tobytes() + (edges.tobytes() if edges is not None else b"")


def write_ply(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any]) -> list[Path]:
    """Write `fr` as a PLY series for Blender and Houdini; returns the paths of the frames'
    files.

    The folder `<stem>_ply/` with one binary little-endian PLY per frame,
    `<stem>_00000.ply`, `<stem>_00001.ply`, ... (`_ply`): vertex properties x y z vx vy
    vz (float32; m, m/s), radius (float32, m), red green blue (uchar, the colour), type
    (int32, the species, named in `comment type k name` lines), wx wy wz and qw qx qy qz
    (float32: the angular velocity, rad/s, and the orientation, with spin), id (int32) and
    group (int32, the collision group, with groups); with
    springs, `element edge` (vertex1 vertex2), one edge per spring whose ends are alive.
    The stem is the name of `path` less its suffix where that is .ply, the whole name
    otherwise. The series is built in a temporary folder that takes the place of
    `<stem>_ply/` only when complete (an existing one is replaced only if it holds nothing
    but an earlier series). `on_frame(i)` is called after frame `i` is written."""
    folder, stem, pattern = series_names(path, "ply", ".ply", SUFFIXES)
    extras = Extras(traj, fr)
    names = [f"{stem}_{i:0{SERIES_DIGITS}d}.ply" for i in range(fr.n_frames)]
    with atomic_folder(folder, pattern) as tmp:
        for i, name in enumerate(names):
            (tmp / name).write_bytes(_ply(fr, i, extras))
            on_frame(i)
    return [folder / name for name in names]
