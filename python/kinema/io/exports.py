"""Exports of a trajectory for other tools: VTK PolyData series (ParaView), PLY per frame
(Blender, Houdini), extended XYZ (OVITO, ASE) and CSV. All values in SI units (m, m/s, kg)."""

from __future__ import annotations

import base64
import os
import re
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

from .. import _checks
from ._cell import ELEMENTS, box_corners, colors_uint8, live_springs, particle_colors, particle_types, spring_columns, trajectory_cell
from ._files import Frames, atomic_file, atomic_folder, atomic_outputs, frames_of, os_errors_as_write_errors
from ._h5md_checks import check_frames
from .gsd_writer import write_gsd
from .lammps_dump import write_lammps
from .usd_writer import SUFFIXES as USD_SUFFIXES
from .usd_writer import write_usd

FORMATS = ("vtk", "ply", "xyz", "csv", "gsd", "lammps", "usd")
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
}
SUFFIX = {
    "vtk": ".pvd",
    "ply": ".ply",
    "xyz": ".xyz",
    "csv": ".csv",
    "gsd": ".gsd",
    "lammps": ".lammpstrj",
    "usd": ".usd",
}  # the main file's suffix of each format
_TRAJECTORY_SUFFIXES = (".h5", ".hdf5", ".h5md")  # H5MD trajectories: never the name of an export
_DIGITS = 5  # frame numbers in series file names: stem_00000.vtp
_FLOAT32 = ("ply", "gsd", "usd")  # the formats that store particle data as float32


def export(traj: Any, path: str | os.PathLike, format: str | None = None, on_frame: Callable[[int], Any] | None = None) -> list[Path]:
    """Write ``traj`` (a ``kinema.Trajectory`` or any object with ``t``, ``positions``,
    ``velocities`` and optionally ``masses``, ``radii``, ``ids``, ``species``, ``periodic``,
    ``box_edges``, ``colliders``, ``springs``, ``colors``) for another program; returns the
    paths written, the main file first.

    ``format`` (default: from the suffix of ``path``); each format has its own names, so one
    trajectory exported as ``run.pvd``, ``run.ply``, ``run.xyz``, ``run.csv``, ``run.gsd`` and
    ``run.lammpstrj`` gives files that never collide:

    - ``"vtk"`` (.pvd, .vtp): for ParaView and OVITO, ``<stem>.pvd`` (open this one: a
      collection whose timesteps are the frame times) and the folder ``<stem>_vtk/`` with one
      XML PolyData file per frame, ``<stem>_00000.vtp``: points (m) as vertex cells, point
      data ``v`` (velocity, m/s), ``speed`` (m/s), ``radius`` (m), ``mass`` (kg), ``id``;
      float64 and int64, base64; ``type`` (the index of the species in the field
      ``type_names``) and ``Color`` (r g b in [0, 1]) where the trajectory has species and
      colours. OVITO maps ``v``, ``radius``, ``mass``, ``id`` and ``Color`` to Velocity,
      Radius, Mass, Particle Identifier and Color, ``type`` to Material Type. With
      ``springs``, each frame is a multi-block ``<stem>_00000.vtm`` (the one the .pvd names)
      of the particles .vtp and ``<stem>_springs_00000.vtp``, a line per spring whose ends
      are alive (``_springs_vtp``), which OVITO reads as Lines. When the trajectory has ``colliders``,
      ``<stem>_colliders.vtp`` beside the .pvd holds them: a box as its 12 edges (lines), a
      plane as a square (a polygon) that covers the scene, a sphere obstacle as a sphere of
      polygons (2D: a rectangle, a segment and a disk at z = 0), the cell data ``collider``
      the index in ``colliders``. OVITO reads the polygons of that file, not the lines.
    - ``"ply"`` (.ply): for Blender and Houdini, the folder ``<stem>_ply/`` with one binary
      little-endian PLY per frame, ``<stem>_00000.ply``, ``<stem>_00001.ply``, ...: vertex
      properties x y z vx vy vz (float32; m, m/s), radius (float32, m), red green blue
      (uchar, the colour), type (int32, the species, named in ``comment type k name``
      lines) and id (int32); with springs, ``element edge`` (vertex1 vertex2), one edge per
      spring whose ends are alive.
    - ``"xyz"`` (.xyz, .extxyz): for OVITO, ASE and MDAnalysis, one extended XYZ file, the
      frames one after the other: N, the comment line ``Lattice="ax 0 0 0 by 0 0 0 cz"
      Origin="ox oy oz" pbc="T T F" units=SI Properties=species:S:1:pos:R:3:velo:R:3:
      momenta:R:3:radius:R:1:mass:R:1:masses:R:1:color:R:3:id:I:1 Time=t``, then one row per
      particle; ``color`` (r g b in [0, 1], OVITO's Color) where the trajectory has colours.

      Units are SI, as ``units=SI`` says: positions, ``Lattice`` and ``Origin`` in m,
      ``velo`` in m/s, ``momenta`` (mass × velocity) in kg·m/s, ``mass`` and ``masses`` in
      kg, ``radius`` in m, ``Time`` in s. OVITO maps ``velo`` to Velocity, ``mass`` to Mass,
      ``radius`` to Radius, ``id`` to Particle Identifier and ``species`` to Particle Type,
      and places the cell at ``Origin``. ASE reads ``masses`` as ``atoms.get_masses()`` and
      ``momenta`` as ``atoms.get_momenta()``, so ``atoms.get_velocities()`` (momenta /
      masses) gives the velocities in m/s; ASE's own units are Å, amu and Å per ASE time
      unit, so these numbers are SI only, to be converted before ASE calculators see them.
      ASE keeps ``Origin`` in ``atoms.info["Origin"]`` (its cell starts at 0). ``momenta``,
      ``mass`` and ``masses`` are written only when the trajectory has masses, ``radius``
      when it has radii.

      The cell (``_cell.trajectory_cell``, shared with GSD and LAMMPS) is an orthogonal
      box, the same in every frame, that holds every particle of every frame: along a
      periodic axis the periodic cell (the world's ``Box``); along an axis where that box
      has two walls and every particle stays between them, the walls; otherwise the
      particles' extent over all frames widened on each side by the largest radius or 5 % of
      the largest extent, whichever is more; a 2D trajectory's z spans that margin. No edge
      is zero, so OVITO's cell analysis and ``atoms.get_volume()`` work. Particle types:
      a trajectory with ``species`` names (``World.add_particles(species=)``, a scene's
      ``species``) gets a first column ``type:S:1`` of the names, which OVITO takes as its
      Particle Type and MDAnalysis as the atom names (it reads a row as a name and x y z),
      then the positions, then a ``species`` column of the name where it is a chemical
      symbol and ``X`` (ASE's dummy element) where not, as ASE refuses other words; ASE
      keeps the names in ``atoms.arrays["type"]``. Without species names the first column
      is ``species``, every one ``X``.
    - ``"csv"`` (.csv): one file with the header
      ``frame,time,id,x,y,z,vx,vy,vz,mass,radius,species,r,g,b`` (species and r,g,b where the
      trajectory has species and colours) and a row per particle and frame.
    - ``"gsd"`` (.gsd): HOOMD-blue's format (OVITO, HOOMD, freud, MDAnalysis), written with
      the ``gsd`` package; float32 particle data, the box centred at 0 with its offset in
      ``log/kinema/origin`` and doubled along the axes that are not periodic, the springs as
      bonds, the colours as ``log/particles/Color`` (see ``gsd_writer.write_gsd``).
    - ``"lammps"`` (.lammpstrj, .dump): a LAMMPS ``dump custom`` text file (OVITO, ASE,
      MDAnalysis, VMD): ``id type element x y z vx vy vz radius mass`` with ids from 1,
      ``element`` where every species is a chemical symbol, the box with ``pp``/``ff``
      flags, no ``ITEM: UNITS`` or ``ITEM: TIME`` (MDAnalysis cannot read them), SI units;
      17 significant digits (see ``lammps_dump.write_lammps``).
    - ``"usd"`` (.usd, .usda, .usdc, .usdz): Pixar's USD for Blender and Houdini, written
      with the ``usd-core`` package: a ``UsdGeom.Points`` prim with positions and velocities
      as time samples at the recording's frame rate, widths 2r and ids, Z up, 1 m per unit,
      and the colliders as guide prims (see ``usd_writer.write_usd``); another suffix is a
      ``ValueError`` (USD picks its file format from the suffix).

    A particle without its own colour (a NaN row of ``colors``) is written in the renderer's
    ``NO_OWN_COLOR`` (RGB 70 130 200); a spring is written at a frame when both its ends are
    alive then.

    Births and deaths (a trajectory whose ``alive`` is not all True): every format writes at
    each frame the particles alive at it only, each with its id (VTK's ``id`` point data,
    PLY's ``id``, XYZ's ``id`` column, CSV's ``id``, GSD's ``log/particles/kinema/id``, LAMMPS's
    ``id`` column, USD's time-sampled ``ids``), so a frame may hold fewer particles than
    another, or none.

    Text formats write every float with 17 significant digits (exact for float64); mass and
    radius are left out where the trajectory has none. A suffix of ``path`` that names
    another format (``format="vtk"`` with ``run.ply``) or an H5MD trajectory (.h5) is a
    ``ValueError``; the folder of ``path`` must exist. Every file is written under a
    temporary name and renamed at the end; a series is built in a temporary folder that
    takes the place of ``<stem>_vtk/`` or ``<stem>_ply/`` only when complete (an existing
    one is replaced only if it holds nothing but an earlier series); a VTK export's folder,
    colliders file and .pvd are all written before any is put in place, the .pvd last, so a
    failed export leaves nothing new and an earlier export as it was. GSD and USD files are
    built by their libraries in the system's temporary folder (``tempfile.gettempdir()``)
    and copied by Python, whose failed write is a clean error. Files get the mode an
    ordinary ``open()`` gives (0666 less the umask; folders 0777 less the umask).
    ``on_frame(i)`` is called after frame ``i`` is written (a progress bar).

    What is written is checked first, by the rules kinema reads its own files with
    (``_h5md_checks.check_frames``): finite times that increase, finite positions and
    velocities of the particles that exist (velocities may be all NaN: unknown, written as
    NaN), masses finite and > 0 kg, radii finite, >= 0 m and at most 1e150 m, printable
    species names, periodic box edges finite and > 0 m, ids once per frame; for the float32
    formats (PLY, GSD, USD) no value beyond float32 (it would be written as inf), for PLY
    ids within int32. A value that breaks them is refused before anything is written.

    Raises ``ValueError`` for an unknown ``format``, ``TrajectoryFileError`` (a
    ``ValueError``) naming the path that cannot be written or the value that would not read
    back (``cannot write run.xyz: trajectory 'masses' has mass[2] = -1 (masses must be
    finite and > 0 kg)``), and ``FileWriteError`` (an ``OSError``) naming it when the system
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
    writer = {"vtk": _write_vtk, "ply": _write_ply, "xyz": _write_xyz, "csv": _write_csv, "gsd": write_gsd, "lammps": write_lammps, "usd": write_usd}[format]
    with os_errors_as_write_errors(path):
        return writer(traj, fr, path, on_frame or (lambda i: None))


def suffix_format(path: str | os.PathLike) -> str | None:
    """The format the suffix of ``path`` names: one of ``FORMATS``, ``"h5md"`` for a
    trajectory file (.h5, .hdf5, .h5md), ``None`` for another suffix or none. An export
    whose ``format`` differs from a suffix's format is refused."""
    suffix = Path(path).suffix.lower()
    return "h5md" if suffix in _TRAJECTORY_SUFFIXES else _SUFFIXES.get(suffix)


def default_path(source: str | os.PathLike, format: str) -> Path:
    """The export of the trajectory file ``source`` beside it: ``run.h5`` gives ``run.pvd``
    (and ``run_vtk/``), ``run.ply`` (the folder ``run_ply/``), ``run.xyz``, ``run.csv``."""
    return Path(source).with_suffix(SUFFIX[format])


def _series(path: Path, format: str, suffix: str) -> tuple[Path, str, str]:
    """The folder of a series (``<stem>_<format>``), the stem of its file names and the
    regular expression of those names."""
    stem = path.stem if path.suffix.lower() in _SUFFIXES else path.name
    return path.with_name(f"{stem}_{format}"), stem, rf"{re.escape(stem)}_\d{{{_DIGITS},}}{re.escape(suffix)}"


# -- VTK ----------------------------------------------------------------------------------------


def _vtk_array(name: str, a: np.ndarray, components: int = 1, count: str = "NumberOfComponents") -> str:
    """An inline binary DataArray: base64 of the byte count (UInt64) and the little-endian
    data, as one stream (uncompressed data, header_type="UInt64")."""
    vtk_type = {"f8": "Float64", "i8": "Int64"}[a.dtype.str[1:]]
    data = np.ascontiguousarray(a, dtype=a.dtype.newbyteorder("<")).tobytes()
    payload = base64.b64encode(np.uint64(len(data)).tobytes() + data).decode("ascii")
    return f'<DataArray type="{vtk_type}" Name={quoteattr(name)} {count}="{components}" format="binary">{payload}</DataArray>'


def _vtk_strings(name: str, values: Sequence[str]) -> str:
    """A field data array of strings, as VTK's XML writer writes one in ASCII: each string's
    UTF-8 bytes as numbers, each string ended by a 0."""
    codes = " ".join(" ".join(str(b) for b in v.encode("utf-8")) + " 0" for v in values)
    return f'<Array type="String" Name={quoteattr(name)} NumberOfTuples="{len(values)}" format="ascii">{codes}</Array>'


def _cells(cells: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """The connectivity and offsets arrays of a list of cells (each an array of point indices)."""
    if not cells:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    return np.concatenate(cells).astype(np.int64), np.cumsum([len(c) for c in cells], dtype=np.int64)


def _polydata(
    points: np.ndarray,
    point_data: Sequence[str] = (),
    cell_data: Sequence[str] = (),
    field_data: Sequence[str] = (),
    attributes: str = "",
    declared: Sequence[str] = ("Verts", "Lines", "Strips", "Polys"),
    **cells: tuple[np.ndarray, np.ndarray],
) -> str:
    """An XML PolyData file (one Piece): ``points`` (n, 3) float64, the DataArrays of
    ``point_data``, ``cell_data`` and ``field_data``, ``attributes`` of <PointData> (the
    active ``Scalars`` and ``Vectors``), and the cells ``verts``, ``lines``, ``polys`` as
    (connectivity, offsets) pairs; the <Piece> states the counts of the kinds ``declared``
    (VTK takes a count left out as 0).

    The <FieldData> comes after the Piece: VTK reads it anywhere in <PolyData>, but OVITO's
    format check walks from <VTKFile> to the first <Piece> and gives up at the end of a
    DataArray before it, so a frame with its FieldData first is not recognised (and an OVITO
    .pvd import silently loads no particles)."""
    counts = {name: len(cells[name.lower()][1]) if name.lower() in cells else 0 for name in declared}
    lines = [
        '<?xml version="1.0"?>',
        '<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">',
        "<PolyData>",
        f'<Piece NumberOfPoints="{len(points)}" ' + " ".join(f'NumberOf{k}="{v}"' for k, v in counts.items()) + ">",
        f"<PointData{attributes}>",
        *point_data,
        "</PointData>",
        *(["<CellData>", *cell_data, "</CellData>"] if cell_data else []),
        f"<Points>{_vtk_array('Points', np.asarray(points, dtype=np.float64).reshape(-1, 3), 3)}</Points>",
    ]
    for name in ("Verts", "Lines", "Polys"):
        if name.lower() in cells:
            connectivity, offsets = cells[name.lower()]
            lines.append(f"<{name}>{_vtk_array('connectivity', connectivity)}{_vtk_array('offsets', offsets)}</{name}>")
    lines.append("</Piece>")
    if field_data:
        lines.append(f"<FieldData>{''.join(field_data)}</FieldData>")
    lines += ["</PolyData>", "</VTKFile>"]
    return "\n".join(lines) + "\n"


class _Extras:
    """What a trajectory adds to its particles beyond ``Frames``, computed once before the
    files: the type names and each particle's type (``None`` without species), the colours
    (``particle_colors``; ``None`` without) and the springs as pairs of columns
    (``spring_columns``; ``None`` without)."""

    def __init__(self, traj: Any, fr: Frames) -> None:
        self.names, self.typeid = particle_types(traj, fr.n_particles) if getattr(traj, "species", None) is not None else (None, None)
        # every reader takes a name as one word (XYZ's columns, a PLY comment, a CSV field)
        for name in self.names or []:
            if not re.fullmatch(_checks.SPECIES_PATTERN, name):
                raise ValueError(f"species: {name!r} is invalid: a species name is one word of letters, digits and _ . + -")
        self.colors = particle_colors(traj, fr.n_particles)
        springs = spring_columns(traj, fr)
        self.springs = springs if springs.size else None


def _vtp(fr: Frames, i: int, extras: _Extras) -> str:
    """Frame ``i``: the particles alive at it as points and vertex cells, point data ``v``
    (velocity), ``speed``, ``radius``, ``mass``, ``id`` (the names OVITO maps to Velocity,
    Radius, Mass and Particle Identifier; ParaView takes ``v`` as the active vectors),
    ``type`` (the index of the particle's species in the field ``type_names``) and ``Color``
    (r g b in [0, 1], the name OVITO maps to its Color) where the trajectory has them, the
    field ``TimeValue``."""
    live = fr.live(i)
    n = live.size
    x, v = fr.positions[i][live], fr.velocities[i][live]
    point_data = [_vtk_array("v", v, 3), _vtk_array("speed", np.linalg.norm(v, axis=1))]
    if fr.radii is not None:
        point_data.append(_vtk_array("radius", fr.radii[live]))
    if fr.masses is not None:
        point_data.append(_vtk_array("mass", fr.masses[live]))
    point_data.append(_vtk_array("id", fr.ids[live]))
    field_data = [_vtk_array("TimeValue", np.array([fr.t[i]]), 1, "NumberOfTuples")]
    if extras.names is not None:
        point_data.append(_vtk_array("type", extras.typeid[live]))
        field_data.append(_vtk_strings("type_names", extras.names))
    if extras.colors is not None:
        point_data.append(_vtk_array("Color", extras.colors[live], 3))
    # One vertex cell per particle, so that ParaView draws the points without a filter (and
    # OVITO reads the file as particles: as many vertices as points, no other cells).
    cells = np.arange(n, dtype=np.int64)
    return _polydata(x, point_data, field_data=field_data, attributes=' Scalars="speed" Vectors="v"', verts=(cells, cells + 1))


def _springs_vtp(fr: Frames, i: int, springs: np.ndarray, rest: np.ndarray) -> str:
    """The springs of frame ``i`` whose two ends are alive: one line cell per spring between
    its own two points (the ends' positions, m), the cell data ``id1`` and ``id2`` the ends'
    ids. This is the layout of a contact network beside a particles file (Aspherix's), which
    OVITO reads as lines between particle ids; a particle file with line cells it does not
    open at all. The <Piece> states the numbers of points and lines only: OVITO takes a file
    that states as many vertices as points for particles.

    A frame in which no spring has both ends alive holds one line of zero length at ``rest``
    (the middle of the scene) with ``id1`` = ``id2`` = -1: OVITO 3.17 dies of a floating
    point exception on a file of no lines, and keeps the previous frame's lines where the
    frame has no springs file."""
    rows = live_springs(springs, fr, i)
    if not len(rows):
        none = np.array([-1], dtype=np.int64)
        points, id1, id2 = np.stack([rest, rest]), none, none
    else:
        ends = fr.live(i)[rows]  # (K, 2) columns
        points, id1, id2 = fr.positions[i][ends.reshape(-1)], fr.ids[ends[:, 0]], fr.ids[ends[:, 1]]
    k = np.arange(len(points), dtype=np.int64)
    return _polydata(points, cell_data=[_vtk_array("id1", id1), _vtk_array("id2", id2)], declared=("Lines",), lines=(k, k[1::2] + 1))


def _vtm(particles: str, springs: str) -> str:
    """A multi-block file of one frame: block 0 ``particles`` (the frame's .vtp), block 1
    ``springs`` (its springs' .vtp)."""
    return (
        '<?xml version="1.0"?>\n<VTKFile type="vtkMultiBlockDataSet" version="1.0" byte_order="LittleEndian" header_type="UInt64">\n'
        f'<vtkMultiBlockDataSet>\n<DataSet index="0" name="particles" file={quoteattr(particles)}/>\n'
        f'<DataSet index="1" name="springs" file={quoteattr(springs)}/>\n</vtkMultiBlockDataSet>\n</VTKFile>\n'
    )


_SPHERE_BANDS, _SPHERE_SEGMENTS = 16, 32  # a sphere obstacle's latitude bands and longitudes
_DISK_SEGMENTS = 64  # the sides of a 2D sphere obstacle's disk


def _unit(a: np.ndarray) -> np.ndarray:
    return a / np.linalg.norm(a)


def _scene_bounds(traj: Any, fr: Frames, colliders: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) of the trajectory's cell (``_cell.trajectory_cell``: all particles of all
    frames, or the box's walls) and of the colliders' finite parts: the room open box faces
    and planes are drawn in."""
    cell = trajectory_cell(traj, fr)
    lo, hi = cell.lo.astype(np.float64), cell.hi.astype(np.float64)
    for d in colliders:
        if d["type"] == "sphere":
            c, r = np.asarray(d["center"], dtype=np.float64), float(d["radius"])
            lo, hi = np.minimum(lo, c - r), np.maximum(hi, c + r)
        elif d["type"] == "box":
            for bound in (d["lo"], d["hi"]):
                b = np.full(3, np.nan)
                b[: len(bound)] = bound
                finite = np.isfinite(b)
                lo[finite], hi[finite] = np.minimum(lo[finite], b[finite]), np.maximum(hi[finite], b[finite])
    return lo, hi


def _uv_sphere() -> tuple[np.ndarray, list[np.ndarray]]:
    """The unit sphere as ``_SPHERE_BANDS`` bands of ``_SPHERE_SEGMENTS`` faces: its points
    (the poles first and last, the rings between) and its faces (triangles at the poles,
    quads between), anticlockwise seen from outside."""
    m, s = _SPHERE_BANDS, _SPHERE_SEGMENTS
    theta, phi = np.pi * np.arange(1, m) / m, 2 * np.pi * np.arange(s) / s
    ring = np.stack([np.sin(theta)[:, None] * np.cos(phi), np.sin(theta)[:, None] * np.sin(phi), np.cos(theta)[:, None] * np.ones(s)], axis=2)
    points = np.concatenate([[[0.0, 0.0, 1.0]], ring.reshape(-1, 3), [[0.0, 0.0, -1.0]]])
    north, south = 0, len(points) - 1

    def at(band: int, j: int) -> int:
        return 1 + band * s + j % s

    faces = [np.array([north, at(0, j), at(0, j + 1)]) for j in range(s)]
    faces += [np.array([at(b, j), at(b + 1, j), at(b + 1, j + 1), at(b, j + 1)]) for b in range(m - 2) for j in range(s)]
    faces += [np.array([south, at(m - 2, j + 1), at(m - 2, j)]) for j in range(s)]
    return points, faces


def _collider_geometry(traj: Any, fr: Frames) -> tuple[np.ndarray, list[tuple[int, np.ndarray]], list[tuple[int, np.ndarray]]] | None:
    """The trajectory's colliders as points (m) and line and polygon cells, each cell with
    the index of its collider; ``None`` without colliders.

    A box is its 12 edges (a 2D trajectory's box: the 4 edges of its rectangle at z = 0), an
    open face at the bound of ``_scene_bounds``; a plane is a square centred on the point
    of the plane nearest the middle of the scene, as wide as the scene's diagonal, so that it
    covers the scene (2D: a line segment at z = 0); a sphere obstacle is a UV sphere of
    ``_SPHERE_BANDS`` × ``_SPHERE_SEGMENTS`` faces, its points at exactly its radius (2D: a
    disk of ``_DISK_SEGMENTS`` sides at z = 0)."""
    if not getattr(traj, "colliders", None):
        return None
    from ..render import _describe_colliders

    colliders = _describe_colliders(traj.colliders)
    lo, hi = _scene_bounds(traj, fr, colliders)
    middle, half = (lo + hi) / 2, float(np.linalg.norm(hi - lo)) / 2
    points: list[np.ndarray] = []
    lines: list[tuple[int, np.ndarray]] = []
    polys: list[tuple[int, np.ndarray]] = []
    base = 0

    def add(p: np.ndarray) -> int:
        nonlocal base
        points.append(np.asarray(p, dtype=np.float64).reshape(-1, 3))
        first, base = base, base + len(points[-1])
        return first

    for k, d in enumerate(colliders):
        if d["type"] == "box":
            b_lo, b_hi = box_corners(d)
            b_lo, b_hi = np.where(np.isfinite(b_lo), b_lo, lo), np.where(np.isfinite(b_hi), b_hi, hi)
            if fr.dim == 2:
                first = add([[b_lo[0], b_lo[1], 0], [b_hi[0], b_lo[1], 0], [b_hi[0], b_hi[1], 0], [b_lo[0], b_hi[1], 0]])
                lines += [(k, first + np.array([j, (j + 1) % 4])) for j in range(4)]
            else:
                # Corner j has the upper bound along the axes of its set bits (x: 1, y: 2, z: 4).
                first = add([[(b_hi if j >> a & 1 else b_lo)[a] for a in range(3)] for j in range(8)])
                lines += [(k, first + np.array([j, j | 1 << a])) for j in range(8) for a in range(3) if not j >> a & 1]
        elif d["type"] == "plane":
            n = np.asarray(d["normal"], dtype=np.float64)
            if not np.linalg.norm(n) > 0:
                raise ValueError(f"colliders[{k}]: the plane's normal = {d['normal']!r} is invalid: it must not be zero")
            n = _unit(n)
            centre = middle - np.dot(middle - np.asarray(d["point"], dtype=np.float64), n) * n
            in_xy = np.cross(n, [0.0, 0.0, 1.0])
            if fr.dim == 2 and np.linalg.norm(in_xy) > 1e-12:
                u = _unit(in_xy)
                along = np.array([0.0, 0.0, 1.0]) - n[2] * n  # in the plane, up
                centre -= centre[2] / along[2] * along  # along the plane to z = 0
                lines.append((k, add([centre - half * u, centre + half * u]) + np.arange(2)))
            else:
                u = _unit(np.cross(n, np.eye(3)[np.argmin(np.abs(n))]))
                w = np.cross(n, u)  # u × w = n: the square's corners turn anticlockwise seen from the side n points to
                corners = [centre + half * (su * u + sw * w) for su, sw in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
                polys.append((k, add(corners) + np.arange(4)))
        else:
            c, r = np.asarray(d["center"], dtype=np.float64), float(d["radius"])
            if fr.dim == 2:
                phi = 2 * np.pi * np.arange(_DISK_SEGMENTS) / _DISK_SEGMENTS
                disk = np.stack([c[0] + r * np.cos(phi), c[1] + r * np.sin(phi), np.zeros_like(phi)], axis=1)
                polys.append((k, add(disk) + np.arange(_DISK_SEGMENTS)))
            else:
                unit, faces = _uv_sphere()
                first = add(c + r * unit)
                polys += [(k, first + f) for f in faces]
    return np.concatenate(points) if points else np.zeros((0, 3)), lines, polys


def _colliders_vtp(traj: Any, fr: Frames) -> str | None:
    """The colliders file: the geometry of ``_collider_geometry`` as line and polygon cells,
    with the cell data ``collider`` (the index in ``traj.colliders``); ``None`` without
    colliders."""
    geometry = _collider_geometry(traj, fr)
    if geometry is None:
        return None
    points, lines, polys = geometry
    index = np.array([k for k, _ in lines] + [k for k, _ in polys], dtype=np.int64)  # VTK numbers lines before polygons
    return _polydata(
        points,
        cell_data=[_vtk_array("collider", index)],
        lines=_cells([c for _, c in lines]),
        polys=_cells([c for _, c in polys]),
    )


def _write_vtk(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any]) -> list[Path]:
    folder, stem, _ = _series(path, "vtk", ".vtp")
    # the frames, and with springs their springs files and the multi-block files of both
    pattern = rf"{re.escape(stem)}(_springs)?_\d{{{_DIGITS},}}\.(vtp|vtm)"
    pvd = path.with_name(stem + ".pvd")
    colliders = path.with_name(stem + "_colliders.vtp")
    scenery = _colliders_vtp(traj, fr)  # before anything is written: a bad collider is a ValueError
    extras = _Extras(traj, fr)
    middle = np.zeros(3)  # where a frame without springs puts its line of zero length
    if extras.springs is not None:
        cell = trajectory_cell(traj, fr)
        middle = 0.5 * (cell.lo + cell.hi)
    names = [f"{stem}_{i:0{_DIGITS}d}.vtp" for i in range(fr.n_frames)]
    # With springs each frame is a multi-block file (.vtm) of its particles and its springs.
    entries = names if extras.springs is None else [f"{stem}_{i:0{_DIGITS}d}.vtm" for i in range(fr.n_frames)]
    datasets = "\n".join(f'<DataSet timestep="{float(fr.t[i])!r}" part="0" file={quoteattr(f"{folder.name}/{name}")}/>' for i, name in enumerate(entries))
    collection = (
        f'<?xml version="1.0"?>\n<VTKFile type="Collection" version="1.0" byte_order="LittleEndian">\n<Collection>\n{datasets}\n</Collection>\n</VTKFile>\n'
    )
    written: list[Path] = []
    # Everything is written under temporary names first: the frames, the colliders, the
    # collection that points at the frames; only then are they put in place, the .pvd last.
    # A write that fails leaves nothing new, and an earlier export (its .pvd, its series and
    # its colliders) as it was.
    with atomic_outputs(pvd) as out:
        tmp_pvd = out.file(pvd)
        tmp_colliders = out.file(colliders) if scenery is not None else None
        tmp = out.folder(folder, pattern)
        with out.naming(folder):
            for i, name in enumerate(names):
                (tmp / name).write_text(_vtp(fr, i, extras), encoding="ascii")
                if extras.springs is not None:
                    spring_name = f"{stem}_springs_{i:0{_DIGITS}d}.vtp"
                    (tmp / spring_name).write_text(_springs_vtp(fr, i, extras.springs, middle), encoding="ascii")
                    (tmp / entries[i]).write_text(_vtm(name, spring_name), encoding="utf-8")
                    written += [folder / entries[i], folder / name, folder / spring_name]
                else:
                    written.append(folder / name)
                on_frame(i)
        if tmp_colliders is not None:
            with out.naming(colliders):
                tmp_colliders.write_text(scenery, encoding="ascii")
        with out.naming(pvd):
            tmp_pvd.write_text(collection, encoding="utf-8")
    return [pvd, *([colliders] if scenery is not None else []), *written]


# -- PLY ----------------------------------------------------------------------------------------


def _ply(fr: Frames, i: int, extras: _Extras) -> bytes:
    """Frame ``i`` as a binary little-endian PLY: one vertex per particle alive at it, float32
    x y z vx vy vz radius, uchar red green blue (the colour, where the trajectory has
    colours), int32 type (the index of its species in the ``comment type <index> <name>``
    lines, where it has species) and int32 id, the types Blender's and Houdini's importers
    read (Blender keeps the other properties as point attributes and red green blue as the
    colour attribute ``Col``); then, where the trajectory has springs, one edge per spring
    whose two ends are alive, int32 vertex1 vertex2 (its ends' vertex indices), which
    Blender imports as the mesh's edges."""
    columns = [("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("vx", "<f4"), ("vy", "<f4"), ("vz", "<f4")]
    if fr.radii is not None:
        columns.append(("radius", "<f4"))
    if extras.colors is not None:
        columns += [("red", "u1"), ("green", "u1"), ("blue", "u1")]
    if extras.names is not None:
        columns.append(("type", "<i4"))
    columns.append(("id", "<i4"))
    live = fr.live(i)
    rows = np.empty(live.size, dtype=columns)
    for k, axis in enumerate("xyz"):
        rows[axis] = fr.positions[i, live, k]
        rows["v" + axis] = fr.velocities[i, live, k]
    if fr.radii is not None:
        rows["radius"] = fr.radii[live]
    if extras.colors is not None:
        rgb = colors_uint8(extras.colors[live])
        for k, name in enumerate(("red", "green", "blue")):
            rows[name] = rgb[:, k]
    if extras.names is not None:
        rows["type"] = extras.typeid[live]
    rows["id"] = fr.ids[live]
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


def _write_ply(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any]) -> list[Path]:
    folder, stem, pattern = _series(path, "ply", ".ply")
    extras = _Extras(traj, fr)
    names = [f"{stem}_{i:0{_DIGITS}d}.ply" for i in range(fr.n_frames)]
    with atomic_folder(folder, pattern) as tmp:
        for i, name in enumerate(names):
            (tmp / name).write_bytes(_ply(fr, i, extras))
            on_frame(i)
    return [folder / name for name in names]


# -- text ---------------------------------------------------------------------------------------


def _xyz(fr: Frames, i: int, header: str, first: list[str], after_pos: list[str], colors: np.ndarray | None) -> str:
    """Frame ``i`` of an extended XYZ file: the count, the comment line (``header`` and the
    frame's ``Time``), one row per particle alive at it: the columns of ``Properties``, its
    ``first`` word (its type or species name), pos, its ``after_pos`` word (its ``species``
    symbol; empty without), velo, momenta, radius, mass, masses, color, id (those the
    trajectory has; 17 significant digits, exact float64)."""
    live = fr.live(i)
    v = fr.velocities[i][live]
    masses = None if fr.masses is None else fr.masses[live][:, None]
    cols = [v]
    if masses is not None:
        cols.append(masses * v)
    if fr.radii is not None:
        cols.append(fr.radii[live][:, None])
    if masses is not None:
        cols += [masses, masses]
    if colors is not None:
        cols.append(colors[live])
    pos, rest = fr.positions[i][live].tolist(), np.hstack(cols).tolist()
    rows = "".join(
        f"{first[c]} " + " ".join(map(repr, x)) + after_pos[c] + " " + " ".join(map(repr, r)) + f" {int(k)}\n"
        for c, x, r, k in zip(live, pos, rest, fr.ids[live], strict=True)
    )
    return f"{live.size}\n{header} Time={float(fr.t[i])!r}\n{rows}"


def _write_xyz(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any]) -> list[Path]:
    # A trajectory's species names go to a `type` column, first: OVITO takes the first of
    # `type` and `species` as its Particle Type, and MDAnalysis's XYZ reader takes a row as a
    # name and x y z, so the positions come second. ASE reads `species` as chemical symbols
    # and refuses other words ("grain"), so that column, after the positions, holds the name
    # where it is an element's symbol and X (ASE's dummy element) where not; ASE keeps `type`
    # in atoms.arrays.
    extras = _Extras(traj, fr)
    typed = extras.names is not None
    if typed:
        first = [extras.names[t] for t in extras.typeid]
        after_pos = [f" {name if name in ELEMENTS else 'X'}" for name in first]
    else:
        first, after_pos = ["X"] * fr.n_particles, [""] * fr.n_particles
    has_m, has_r, has_c = fr.masses is not None, fr.radii is not None, extras.colors is not None
    props = (
        ("type:S:1:pos:R:3:species:S:1" if typed else "species:S:1:pos:R:3")
        + ":velo:R:3"
        + ":momenta:R:3" * has_m
        + ":radius:R:1" * has_r
        + ":mass:R:1:masses:R:1" * has_m
        + ":color:R:3" * has_c
        + ":id:I:1"
    )
    cell = trajectory_cell(traj, fr)
    origin, edges, pbc = cell.lo, cell.hi - cell.lo, cell.periodic
    lattice = " ".join(repr(float(c)) for c in np.diag(edges).reshape(-1))
    header = (
        f'Lattice="{lattice}" Origin="{" ".join(repr(float(c)) for c in origin)}" pbc="{" ".join("T" if p else "F" for p in pbc)}" units=SI Properties={props}'
    )
    with atomic_file(path) as tmp, open(tmp, "w", encoding="ascii") as f:
        for i in range(fr.n_frames):
            f.write(_xyz(fr, i, header, first, after_pos, extras.colors))
            on_frame(i)
    return [path]


def _csv_header(fr: Frames, extras: _Extras) -> str:
    return (
        "frame,time,id,x,y,z,vx,vy,vz"
        + ",mass" * (fr.masses is not None)
        + ",radius" * (fr.radii is not None)
        + ",species" * (extras.names is not None)
        + ",r,g,b" * (extras.colors is not None)
    )


def _csv(fr: Frames, i: int, extras: _Extras) -> str:
    """The rows of frame ``i``, one per particle alive at it: frame,time,id,x,y,z,vx,vy,vz,
    then mass, radius, species (its name) and r,g,b (its colour in [0, 1]) where the
    trajectory has them (17 significant digits)."""
    t = repr(float(fr.t[i]))
    live = fr.live(i)
    cols = [fr.positions[i][live], fr.velocities[i][live], *(a[live][:, None] for a in (fr.masses, fr.radii) if a is not None)]
    table = np.hstack(cols).tolist()
    names = [f",{extras.names[k]}" for k in extras.typeid[live]] if extras.names is not None else [""] * live.size
    colors = [",".join(["", *map(repr, c)]) for c in extras.colors[live].tolist()] if extras.colors is not None else [""] * live.size
    return "".join(
        f"{i},{t},{int(k)}," + ",".join(map(repr, r)) + name + rgb + "\n" for r, k, name, rgb in zip(table, fr.ids[live], names, colors, strict=True)
    )


def _write_csv(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any]) -> list[Path]:
    extras = _Extras(traj, fr)
    with atomic_file(path) as tmp, open(tmp, "w", encoding="ascii", newline="") as f:
        f.write(_csv_header(fr, extras) + "\n")
        for i in range(fr.n_frames):
            f.write(_csv(fr, i, extras))
            on_frame(i)
    return [path]
