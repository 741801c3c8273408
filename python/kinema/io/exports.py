"""Exports of a trajectory for other tools: `export` checks what is written, tells the format
from the suffix and hands the frames to the format's writer (`vtk_writer`, `ply_writer`,
`xyz_writer`, `csv_writer`, `gsd_writer`, `lammps_dump`, `usd_writer`). All values
in SI units (m, m/s, kg)."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ._files import frames_of, os_errors_as_write_errors
from ._h5md_checks import check_frames
from .blend_writer import write_blend
from .csv_writer import write_csv
from .gsd_writer import write_gsd
from .lammps_dump import write_lammps
from .ply_writer import write_ply
from .usd_writer import SUFFIXES as USD_SUFFIXES
from .usd_writer import write_usd
from .vtk_writer import write_vtk
from .xyz_writer import write_xyz

FORMATS = ("vtk", "ply", "xyz", "csv", "gsd", "lammps", "usd", "blend")
_SUFFIXES = {
    ".pvd": "vtk",
    ".vtp": "vtk",
    ".ply": "ply",
    ".xyz": "xyz",
    ".extxyz": "xyz",
    ".csv": "csv",
    ".gsd": "gsd",
    ".lammpstrj": "lammps",
    ".dump": "lammps",
    ".usd": "usd",
    ".usda": "usd",
    ".usdc": "usd",
    ".usdz": "usd",
    ".blend": "blend",
}
SUFFIX = {
    "vtk": ".pvd",
    "ply": ".ply",
    "xyz": ".xyz",
    "csv": ".csv",
    "gsd": ".gsd",
    "lammps": ".lammpstrj",
    "usd": ".usd",
    "blend": ".blend",
}  # the main file's suffix of each format
_TRAJECTORY_SUFFIXES = (".h5", ".hdf5", ".h5md")  # H5MD trajectories: never the name of an export
_FLOAT32 = ("ply", "gsd", "usd", "blend")  # the formats that store particle data as float32


# Over 100 lines (issue 50) by its docstring (94 lines): the public export's reference, every
# format's files and names; the code is 32 lines, each format's work in its own writer.
def export(
    traj: Any, path: str | os.PathLike, format: str | None = None, on_frame: Callable[[int], Any] | None = None, *, plain_dump: bool = False
) -> list[Path]:
    """Write `traj` (a `kinema.Trajectory` or any object with `t`, `positions`,
    `velocities` and optionally `masses`, `radii`, `ids`, `species`, `periodic`,
    `box_edges`, `colliders`, `springs`, `colors`) for another program; returns the
    paths written, the main file first.

    `format` (default: from the suffix of `path`); each format has its own names, so one
    trajectory exported as `run.pvd`, `run.ply`, `run.xyz`, `run.csv`, `run.gsd` and
    `run.lammpstrj` gives files that never collide:

    - `"vtk"` (.pvd, .vtp): for ParaView and OVITO, `<stem>.pvd` (open this one: a
      collection whose timesteps are the frame times) and the folder `<stem>_vtk/` with one
      XML PolyData file per frame, `<stem>_00000.vtp` (a multi-block `.vtm` of the
      particles and their springs where the trajectory has springs), and the colliders in
      `<stem>_colliders.vtp` (see `vtk_writer.write_vtk`).
    - `"ply"` (.ply): for Blender and Houdini, the folder `<stem>_ply/` with one binary
      little-endian PLY per frame, `<stem>_00000.ply`, `<stem>_00001.ply`, ...: float32
      particle data, colours, species types and int32 ids, the springs as edges (see
      `ply_writer.write_ply`).
    - `"xyz"` (.xyz, .extxyz): for OVITO, ASE and MDAnalysis, one extended XYZ file, the
      frames one after the other, `units=SI`, the cell of `_cell.trajectory_cell` (shared
      with GSD and LAMMPS), the species names as a `type` column and ASE's `species`
      symbols (see `xyz_writer.write_xyz`).
    - `"csv"` (.csv): one file with the header
      `frame,time,id,x,y,z,vx,vy,vz,mass,radius,species,r,g,b` and a row per particle and
      frame (see `csv_writer.write_csv`).
    - `"gsd"` (.gsd): HOOMD-blue's format (OVITO, HOOMD, freud, MDAnalysis), written with
      the `gsd` package; float32 particle data, the box centred at 0 with its offset in
      `log/kinema/origin` and doubled along the axes that are not periodic, the springs as
      bonds, the colours as `log/particles/Color` (see `gsd_writer.write_gsd`).
    - `"lammps"` (.lammpstrj, .dump): a LAMMPS `dump custom` text file (OVITO, ASE,
      MDAnalysis, VMD): `id type element x y z vx vy vz radius mass` with ids from 1,
      `element` where every species is a chemical symbol, the box with `pp`/`ff`
      flags, `ITEM: UNITS si` and each frame's `ITEM: TIME` (LAMMPS's `dump_modify units
      yes time yes`), SI units; 17 significant digits (see `lammps_dump.write_lammps`).
      MDAnalysis reads no dump with those items, LAMMPS's own included: `plain_dump=True`
      (`kinema export --plain-dump`) writes LAMMPS's default layout without them, which it
      reads.
    - `"usd"` (.usd, .usda, .usdc, .usdz): Pixar's USD for Blender and Houdini, written
      with the `usd-core` package: a `UsdGeom.Points` prim with positions and velocities
      as time samples at the frame rate asked, widths 2r and ids, Z up, 1 m per unit,
      and the colliders as translucent meshes, with bound materials (see `usd_writer.write_usd`); another suffix is a
      `ValueError` (USD picks its file format from the suffix).
    - `"blend"` (.blend): a Blender scene built by Blender itself (`blender` on the PATH,
      `$KINEMA_BLENDER`, or `bpy` in this Python), and beside it `<stem>.usdc`, the stage
      it plays: the frame rate asked, the particles in their colours in Cycles and Eevee,
      the colliders rendered, a camera and a light (see `blend_writer.write_blend`).

    Spin and contacts: a trajectory with `angular_velocities` (and `orientations`) writes
    them in every format (LAMMPS `omegax.. quatw..`, XYZ `omega`, `orientation`,
    GSD HOOMD's orientation and angmom, VTK point data, USD a PointInstancer of balls, CSV
    and PLY columns); one with a `contact_record` (`World.run(record_contacts=True)`) adds its
    contacts to `"lammps"` (`<stem>_contacts.dump` and `<stem>_collider_contacts.dump`,
    LAMMPS `dump local`) and `"vtk"` (a `contacts` block of lines per frame): docs/files.md,
    "Spins and contacts".

    A particle without its own colour (a NaN row of `colors`) is written in the renderer's
    `NO_OWN_COLOR` (RGB 70 130 200); a spring is written at a frame when both its ends are
    alive then.

    Births and deaths (a trajectory whose `alive` is not all True): every format writes at
    each frame the particles alive at it only, each with its id (VTK's `id` point data,
    PLY's `id`, XYZ's `id` column, CSV's `id`, GSD's `log/particles/kinema/id`, LAMMPS's
    `id` column, USD's time-sampled `ids`), so a frame may hold fewer particles than
    another, or none.

    Text formats write every float with 17 significant digits (exact for float64); mass and
    radius are left out where the trajectory has none. A suffix of `path` that names
    another format (`format="vtk"` with `run.ply`) or an H5MD trajectory (.h5) is a
    `ValueError`; the folder of `path` must exist. Every file is written under a
    temporary name and renamed at the end; a series is built in a temporary folder that
    takes the place of `<stem>_vtk/` or `<stem>_ply/` only when complete (an existing
    one is replaced only if it holds nothing but an earlier series); a VTK export's folder,
    colliders file and .pvd are all put in place together, the .pvd last (see
    `vtk_writer.write_vtk`), so a failed export leaves nothing new and an earlier export
    as it was. GSD and USD files are built by their libraries in the system's temporary
    folder (`tempfile.gettempdir()`) and copied by Python, whose failed write is a clean
    error. Files get the mode an ordinary `open()` gives (0666 less the umask; folders
    0777 less the umask).
    `on_frame(i)` is called after frame `i` is written (a progress bar).

    What is written is checked first, by the rules kinema reads its own files with
    (`_h5md_checks.check_frames`): finite times that increase, finite positions and
    velocities of the particles that exist (velocities may be all NaN: unknown, a trajectory
    read from a file without them; then no velocity columns or properties are written, and
    the file reads back without velocities), masses finite and > 0 kg, radii finite, >= 0 m and at most 1e150 m, printable
    species names, periodic box edges finite and > 0 m, ids once per frame; for the float32
    formats (PLY, GSD, USD) no value beyond float32 (it would be written as inf), for PLY
    ids within int32. A value that breaks them is refused before anything is written.

    Raises `ValueError` for an unknown `format`, `TrajectoryFileError` (a
    `ValueError`) naming the path that cannot be written or the value that would not read
    back (`cannot write run.xyz: trajectory 'masses' has mass[2] = -1 (masses must be
    finite and > 0 kg)`), and `FileWriteError` (an `OSError`) naming it when the system
    fails the write or refuses the name (a name too long)."""
    path = Path(path)
    if format is None:
        format = _SUFFIXES.get(path.suffix.lower())
        if format is None:
            raise ValueError(
                f"format: cannot tell it from the suffix {path.suffix or '(none)'!r} of {path}; give format= one of {', '.join(map(repr, FORMATS))}"
            )
    if format not in FORMATS:
        raise ValueError(f"format = {format!r} is invalid: the allowed values are {', '.join(map(repr, FORMATS))}")
    other = suffix_format(path)
    if other not in (None, format):
        what = "an H5MD trajectory" if other == "h5md" else f"format {other!r}"
        raise ValueError(f"path = {str(path)!r}: the suffix {path.suffix!r} is for {what}, not format = {format!r}; give a name ending in {SUFFIX[format]}")
    if format == "usd" and path.suffix.lower() not in USD_SUFFIXES:
        raise ValueError(f"path = {str(path)!r}: the suffix {path.suffix or '(none)'!r} is not a USD file's; allowed: {', '.join(USD_SUFFIXES)}")
    fr = frames_of(traj)
    check_frames(path, traj, fr, float32=format if format in _FLOAT32 else None, int32_ids="ply" if format == "ply" else None)
    writer = {
        "vtk": write_vtk,
        "ply": write_ply,
        "xyz": write_xyz,
        "csv": write_csv,
        "gsd": write_gsd,
        "lammps": write_lammps,
        "usd": write_usd,
        "blend": write_blend,
    }[format]
    if plain_dump and format != "lammps":
        raise ValueError(f"plain_dump = True is invalid for format = {format!r}: it is the LAMMPS dump's (format 'lammps')")
    options = {"plain": plain_dump} if format == "lammps" else {}
    with os_errors_as_write_errors(path):
        return writer(traj, fr, path, on_frame or (lambda i: None), **options)


def suffix_format(path: str | os.PathLike) -> str | None:
    """The format the suffix of `path` names: one of `FORMATS`, `"h5md"` for a
    trajectory file (.h5, .hdf5, .h5md), `None` for another suffix or none. An export
    whose `format` differs from a suffix's format is refused."""
    suffix = Path(path).suffix.lower()
    return "h5md" if suffix in _TRAJECTORY_SUFFIXES else _SUFFIXES.get(suffix)


def default_path(source: str | os.PathLike, format: str) -> Path:
    """The export of the trajectory file `source` beside it: `run.h5` gives `run.pvd`
    (and `run_vtk/`), `run.ply` (the folder `run_ply/`), `run.xyz`, `run.csv`."""
    return Path(source).with_suffix(SUFFIX[format])
