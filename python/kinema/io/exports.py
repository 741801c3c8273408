"""Exports of a trajectory for other tools: VTK PolyData series (ParaView), PLY per frame
(Blender, Houdini), extended XYZ (OVITO, ASE) and CSV. All values in SI units (m, m/s, kg)."""

from __future__ import annotations

import base64
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

from ._files import Frames, atomic_file, atomic_folder, frames_of

FORMATS = ("vtk", "ply", "xyz", "csv")
_SUFFIXES = {".pvd": "vtk", ".vtp": "vtk", ".ply": "ply", ".xyz": "xyz", ".extxyz": "xyz", ".csv": "csv"}
_DIGITS = 5  # frame numbers in series file names: stem_00000.vtp


def export(traj: Any, path: str | os.PathLike, format: str | None = None, on_frame: Callable[[int], Any] | None = None) -> list[Path]:
    """Write ``traj`` (a ``kinema.Trajectory`` or any object with ``t``, ``positions``,
    ``velocities`` and optionally ``masses``, ``radii``, ``ids``) for another program; returns
    the paths written, the main file first.

    ``format`` (default: from the suffix of ``path``):

    - ``"vtk"`` (.pvd, .vtp): for ParaView, ``<stem>.pvd``, a collection whose timesteps are
      the frame times, and the folder ``<stem>/`` with one XML PolyData file per frame,
      ``<stem>_00000.vtp``: points (m) as vertex cells, point data ``velocity`` (m/s),
      ``speed`` (m/s), ``radius`` (m), ``mass`` (kg), ``id``; float64, base64.
    - ``"ply"`` (.ply): for Blender and Houdini, the folder ``<stem>/`` with one binary
      little-endian PLY per frame, ``<stem>_00000.ply``: vertex properties x y z vx vy vz
      (float32; m, m/s), radius (float32, m) and id (int32).
    - ``"xyz"`` (.xyz, .extxyz): for OVITO and ASE, one extended XYZ file, the frames one
      after the other: N, a comment line ``Properties=species:S:1:pos:R:3:velo:R:3:radius:R:1:mass:R:1:id:I:1
      Time=... pbc="F F F"`` (``Lattice`` when the trajectory has ``box_edges``), then one
      row per particle (species ``X``, ASE's dummy element).
    - ``"csv"`` (.csv): one file with the header ``frame,time,id,x,y,z,vx,vy,vz`` and a row
      per particle and frame.

    Text formats write every float with 17 significant digits (exact for float64); mass and
    radius are left out where the trajectory has none. Every file is written under a
    temporary name and renamed at the end; a series is built in a temporary folder that takes
    the place of ``<stem>/`` only when complete (an existing ``<stem>/`` is replaced only if
    it holds nothing but an earlier series). ``on_frame(i)`` is called after frame ``i`` is
    written (a progress bar). Raises ``ValueError`` for an unknown ``format`` and
    ``TrajectoryFileError`` (a ``ValueError``) naming the path that cannot be written."""
    path = Path(path)
    if format is None:
        format = _SUFFIXES.get(path.suffix.lower())
        if format is None:
            raise ValueError(
                f"format: cannot tell it from the suffix {path.suffix or '(none)'!r} of {path}; give format= one of {', '.join(map(repr, FORMATS))}"
            )
    if format not in FORMATS:
        raise ValueError(f"format = {format!r} is invalid: the allowed values are {', '.join(map(repr, FORMATS))}")
    fr = frames_of(traj)
    writer = {"vtk": _write_vtk, "ply": _write_ply, "xyz": _write_xyz, "csv": _write_csv}[format]
    return writer(traj, fr, path, on_frame or (lambda i: None))


def _series(path: Path, suffix: str) -> tuple[Path, str]:
    """The folder of a series and the regular expression of its file names."""
    stem = path.stem if path.suffix.lower() in _SUFFIXES else path.name
    return path.with_name(stem), rf"{stem}_\d{{{_DIGITS},}}\{suffix}"


# -- VTK ----------------------------------------------------------------------------------------


def _vtk_array(name: str, a: np.ndarray, components: int = 1, count: str = "NumberOfComponents") -> str:
    """An inline binary DataArray: base64 of the byte count (UInt64) and the little-endian
    data, as one stream (uncompressed data, header_type="UInt64")."""
    vtk_type = {"f8": "Float64", "i8": "Int64"}[a.dtype.str[1:]]
    data = np.ascontiguousarray(a, dtype=a.dtype.newbyteorder("<")).tobytes()
    payload = base64.b64encode(np.uint64(len(data)).tobytes() + data).decode("ascii")
    return f'<DataArray type="{vtk_type}" Name={quoteattr(name)} {count}="{components}" format="binary">{payload}</DataArray>'


def _vtp(fr: Frames, i: int) -> str:
    n = fr.n_particles
    x, v = fr.positions[i], fr.velocities[i]
    point_data = [_vtk_array("velocity", v, 3), _vtk_array("speed", np.linalg.norm(v, axis=1))]
    if fr.radii is not None:
        point_data.append(_vtk_array("radius", fr.radii))
    if fr.masses is not None:
        point_data.append(_vtk_array("mass", fr.masses))
    point_data.append(_vtk_array("id", fr.ids))
    # One vertex cell per particle, so that ParaView draws the points without a filter.
    cells = np.arange(n, dtype=np.int64)
    lines = [
        '<?xml version="1.0"?>',
        '<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">',
        "<PolyData>",
        f"<FieldData>{_vtk_array('TimeValue', np.array([fr.t[i]]), 1, 'NumberOfTuples')}</FieldData>",
        f'<Piece NumberOfPoints="{n}" NumberOfVerts="{n}" NumberOfLines="0" NumberOfStrips="0" NumberOfPolys="0">',
        '<PointData Scalars="speed" Vectors="velocity">',
        *point_data,
        "</PointData>",
        f"<Points>{_vtk_array('Points', x, 3)}</Points>",
        f"<Verts>{_vtk_array('connectivity', cells)}{_vtk_array('offsets', cells + 1)}</Verts>",
        "</Piece>",
        "</PolyData>",
        "</VTKFile>",
    ]
    return "\n".join(lines) + "\n"


def _write_vtk(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any]) -> list[Path]:
    folder, pattern = _series(path, ".vtp")
    stem = folder.name
    pvd = folder.with_name(stem + ".pvd")
    names = [f"{stem}_{i:0{_DIGITS}d}.vtp" for i in range(fr.n_frames)]
    datasets = "\n".join(f'<DataSet timestep="{float(fr.t[i])!r}" part="0" file={quoteattr(f"{stem}/{name}")}/>' for i, name in enumerate(names))
    collection = (
        f'<?xml version="1.0"?>\n<VTKFile type="Collection" version="1.0" byte_order="LittleEndian">\n<Collection>\n{datasets}\n</Collection>\n</VTKFile>\n'
    )
    # The frames first, then the collection that points at them.
    with atomic_file(pvd) as tmp_pvd:
        with atomic_folder(folder, pattern) as tmp:
            for i, name in enumerate(names):
                (tmp / name).write_text(_vtp(fr, i), encoding="ascii")
                on_frame(i)
        tmp_pvd.write_text(collection, encoding="utf-8")
    return [pvd, *(folder / name for name in names)]


# -- PLY ----------------------------------------------------------------------------------------


def _ply(fr: Frames, i: int) -> bytes:
    """Frame ``i`` as a binary little-endian PLY of vertices (float32 x y z vx vy vz radius,
    int32 id): the types Blender's and Houdini's importers read; extra properties are kept as
    point attributes."""
    columns = [("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("vx", "<f4"), ("vy", "<f4"), ("vz", "<f4")]
    if fr.radii is not None:
        columns.append(("radius", "<f4"))
    columns.append(("id", "<i4"))
    rows = np.empty(fr.n_particles, dtype=columns)
    for k, axis in enumerate("xyz"):
        rows[axis] = fr.positions[i, :, k]
        rows["v" + axis] = fr.velocities[i, :, k]
    if fr.radii is not None:
        rows["radius"] = fr.radii
    rows["id"] = fr.ids
    ply_type = {"<f4": "float", "<i4": "int"}
    header = [
        "ply",
        "format binary_little_endian 1.0",
        "comment kinema trajectory frame, SI units (m, m/s)",
        f"comment time {float(fr.t[i])!r}",
        f"element vertex {fr.n_particles}",
        *(f"property {ply_type[t]} {name}" for name, t in columns),
        "end_header",
    ]
    return ("\n".join(header) + "\n").encode("ascii") + rows.tobytes()


def _write_ply(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any]) -> list[Path]:
    folder, pattern = _series(path, ".ply")
    names = [f"{folder.name}_{i:0{_DIGITS}d}.ply" for i in range(fr.n_frames)]
    with atomic_folder(folder, pattern) as tmp:
        for i, name in enumerate(names):
            (tmp / name).write_bytes(_ply(fr, i))
            on_frame(i)
    return [folder / name for name in names]


# -- text ---------------------------------------------------------------------------------------


def _xyz(fr: Frames, i: int, header: str) -> str:
    """Frame ``i`` of an extended XYZ file: the count, the comment line, one row per particle
    (species X, then the columns of ``Properties``; 17 significant digits, exact float64)."""
    cols = [fr.positions[i], fr.velocities[i], *(a[:, None] for a in (fr.radii, fr.masses) if a is not None)]
    table = np.hstack(cols).tolist()
    rows = "".join("X " + " ".join(map(repr, r)) + f" {int(k)}\n" for r, k in zip(table, fr.ids, strict=True))
    return f"{fr.n_particles}\n{header} Time={float(fr.t[i])!r}\n{rows}"


def _write_xyz(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any]) -> list[Path]:
    props = "species:S:1:pos:R:3:velo:R:3" + ":radius:R:1" * (fr.radii is not None) + ":mass:R:1" * (fr.masses is not None) + ":id:I:1"
    periodic = getattr(traj, "periodic", None)
    pbc = np.zeros(3, dtype=bool) if periodic is None else np.resize(np.asarray(periodic, dtype=bool).reshape(-1), 3)
    header = f'Properties={props} pbc="{" ".join("T" if p else "F" for p in pbc)}"'
    edges = getattr(traj, "box_edges", None)
    if edges is not None:
        e = np.zeros(3)
        e[: np.size(edges)] = np.asarray(edges, dtype=np.float64).reshape(-1)[:3]
        header = 'Lattice="' + " ".join(repr(float(c)) for c in np.diag(e).reshape(-1)) + '" ' + header
    with atomic_file(path) as tmp, open(tmp, "w", encoding="ascii") as f:
        for i in range(fr.n_frames):
            f.write(_xyz(fr, i, header))
            on_frame(i)
    return [path]


def _csv(fr: Frames, i: int) -> str:
    """The rows of frame ``i``: frame,time,id,x,y,z,vx,vy,vz (17 significant digits)."""
    t = repr(float(fr.t[i]))
    table = np.hstack([fr.positions[i], fr.velocities[i]]).tolist()
    return "".join(f"{i},{t},{int(k)}," + ",".join(map(repr, r)) + "\n" for r, k in zip(table, fr.ids, strict=True))


def _write_csv(traj: Any, fr: Frames, path: Path, on_frame: Callable[[int], Any]) -> list[Path]:
    with atomic_file(path) as tmp, open(tmp, "w", encoding="ascii", newline="") as f:
        f.write("frame,time,id,x,y,z,vx,vy,vz\n")
        for i in range(fr.n_frames):
            f.write(_csv(fr, i))
            on_frame(i)
    return [path]
