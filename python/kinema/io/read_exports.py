"""Reading kinema's own exports back: the CSV (`read_csv`), the VTK series of a `.pvd`
collection (`read_vtk`) and the PLY series folder (`read_ply`), each to a
`LoadedTrajectory` in SI units, the units kinema writes them in. The CSV's and VTK's float64
values read back bit for bit, PLY's float32 as float32."""

from __future__ import annotations

import base64
import os
import re
import stat
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ._assemble import RawFrame, assemble
from ._h5md_checks import fail
from .csv_writer import ORIENTATION_CSV, SPIN_CSV
from .h5md_reader import LoadedTrajectory
from .units import SI, UnitWarning

_CSV_COLUMNS = ("frame", "time", "id", "x", "y", "z")
_CSV_VELOCITIES = ("vx", "vy", "vz")  # (left out by an export whose velocities are unknown)


def read_csv(path: Path) -> LoadedTrajectory:
    """Read a CSV kinema exported: the header `frame,time,id,x,y,z,vx,vy,vz` (without
    `vx,vy,vz` where the velocities are unknown: read as none), then any of
    `mass`, `radius`, `species`, `r,g,b` (the colour), `wx,wy,wz` (the angular velocity),
    `qw,qx,qy,qz` (the orientation) and `group` (the collision group), a row per particle and frame,
    SI units. Frames are the distinct `frame` numbers, in order; a frame in which no particle
    was alive has no row, so it is not read."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except UnicodeDecodeError as e:
        raise fail(path, f"not a text file ({e.reason} at byte {e.start}), so not a CSV") from None
    header = lines[0].strip().split(",") if lines else []
    has_v = tuple(header[len(_CSV_COLUMNS) : len(_CSV_COLUMNS) + 3]) == _CSV_VELOCITIES
    extra = header[len(_CSV_COLUMNS) + 3 * has_v :]
    known = {"mass", "radius", "species", "r", "g", "b", *SPIN_CSV, *ORIENTATION_CSV, "group"}
    if tuple(header[: len(_CSV_COLUMNS)]) != _CSV_COLUMNS or not set(extra) <= known or len(set(extra)) != len(extra):
        raise fail(
            path,
            f"a CSV whose header is not kinema's ({','.join(_CSV_COLUMNS)}[,vx,vy,vz][,mass][,radius][,species][,r,g,b][,wx,wy,wz][,qw,qx,qy,qz][,group]); kinema reads back its own CSV only",
        )
    rows = [line for line in lines[1:] if line.strip()]
    width = len(header)
    words = ",".join(rows).split(",")
    if len(words) != len(rows) * width:
        for r, line in enumerate(rows):
            if len(line.split(",")) != width:
                raise fail(path, f"line {r + 2}: {len(line.split(','))} values, but the header names {width} columns")
    table = np.array(words, dtype=str).reshape(len(rows), width)
    at = {name: k for k, name in enumerate(header)}
    numbers = [k for k, name in enumerate(header) if name not in ("frame", "id", "species", "group")]
    try:
        frame_no, ids = table[:, 0].astype(np.int64), table[:, 2].astype(np.int64)
        groups = table[:, header.index("group")].astype(np.int64) if "group" in header else None
        values = np.zeros((len(rows), width))
        values[:, numbers] = table[:, numbers].astype(np.float64)
    except ValueError as e:
        raise fail(path, f"a value is not a number ({e})") from None
    if np.any(np.diff(frame_no) < 0):
        k = int(np.argmax(np.diff(frame_no) < 0)) + 1
        raise fail(path, f"line {k + 2}: frame {int(frame_no[k])} after frame {int(frame_no[k - 1])}; the rows of a frame follow each other, in order")
    rgb = [at[c] for c in "rgb"] if all(c in at for c in "rgb") else None
    frames = []
    for number in np.unique(frame_no):
        rows_at = frame_no == number
        v = values[rows_at]
        times = np.unique(v[:, at["time"]])
        if times.size != 1:
            raise fail(path, f"frame {int(number)} has {times.size} different times")
        frames.append(
            RawFrame(
                positions=v[:, 3:6],
                where=f"frame {int(number)}",
                ids=ids[rows_at],
                velocities=v[:, 6:9] if has_v else None,
                masses=v[:, at["mass"]] if "mass" in at else None,
                radii=v[:, at["radius"]] if "radius" in at else None,
                species=table[rows_at, at["species"]].astype(object) if "species" in at else None,
                colors=v[:, rgb] if rgb else None,
                groups=None if groups is None else groups[rows_at],
                angular_velocities=v[:, [at[c] for c in SPIN_CSV]] if all(c in at for c in SPIN_CSV) else None,
                orientations=v[:, [at[c] for c in ORIENTATION_CSV]] if all(c in at for c in ORIENTATION_CSV) else None,
                time=float(times[0]),
                step=int(number),
            )
        )
    return assemble(path, frames, SI, creator="kinema")


# -- VTK ----------------------------------------------------------------------------------------

_VTK_TYPES = {"Float32": "<f4", "Float64": "<f8", "Int32": "<i4", "Int64": "<i8", "UInt32": "<u4", "UInt64": "<u8"}


def _data_array(path: Path, a: ET.Element, header: str, where: str) -> np.ndarray:
    """A DataArray's values: inline binary (base64 of a byte count and the data, uncompressed)
    or ascii."""
    kind = _VTK_TYPES.get(a.get("type", ""))
    if kind is None:
        raise fail(path, f"{where}: DataArray {a.get('Name')!r} of type {a.get('type')!r}, which kinema does not read")
    text = (a.text or "").strip()
    if a.get("format") == "ascii":
        return np.array(text.split(), dtype=str).astype(kind)
    if a.get("format") != "binary":
        raise fail(path, f"{where}: DataArray {a.get('Name')!r} is {a.get('format')!r} data; kinema reads inline binary or ascii (its own exports)")
    raw = base64.b64decode(text)
    size = np.dtype(header).itemsize
    count = int(np.frombuffer(raw[:size], dtype=header)[0])
    if len(raw) - size != count or count % np.dtype(kind).itemsize:
        raise fail(path, f"{where}: DataArray {a.get('Name')!r} announces {count} bytes but holds {len(raw) - size}")
    return np.frombuffer(raw[size:], dtype=kind).copy()


def _xml(path: Path, file: Path, where: str) -> ET.Element:
    try:
        return ET.parse(file).getroot()
    except (ET.ParseError, OSError) as e:
        raise fail(path, f"{where}: {file} cannot be read as XML ({e})") from None


def _inside(path: Path, folder: Path, name: str | None, where: str) -> Path:
    """The file `name` a collection names, in `folder` or below it (never outside it), and a
    regular file (`_frame_file`)."""
    if not name or Path(name).is_absolute() or ".." in Path(name).parts:
        raise fail(path, f"{where}: the file {name!r} is not a name inside the collection's folder")
    return _frame_file(path, folder / name, where)


def _frame_file(path: Path, file: Path, where: str) -> Path:
    """`file`, a frame's file of the series `path`, checked before it is opened as the main
    file is (`readers.read_trajectory`): it exists and is a regular file (followed through
    links; a FIFO would block the reader, a device feed it without end), and its text fits
    in the memory available."""
    from ._checks import TEXT_FACTOR, available_memory, gib
    from ._files import special_kind

    try:
        st = os.stat(file)
    except FileNotFoundError:
        raise fail(path, f"{where}: its file {file.name} does not exist") from None
    except OSError as e:
        raise fail(path, f"{where}: its file {file.name} cannot be read ({e.strerror or e})") from None
    if not stat.S_ISREG(st.st_mode):
        kind = "a directory" if stat.S_ISDIR(st.st_mode) else f"a {special_kind(st.st_mode) or 'special file'}"
        raise fail(path, f"{where}: its file {file.name} is {kind}, not a regular file")
    free = available_memory()
    if free is not None and st.st_size * TEXT_FACTOR > free:
        raise fail(path, f"{where}: its file {file.name} of {gib(st.st_size)} GiB needs about {gib(st.st_size * TEXT_FACTOR)} GiB of memory to read")
    return file


def _vtp(path: Path, file: Path, where: str) -> dict[str, np.ndarray]:
    """A frame's particles: its PolyData file, or block 0 (the particles) of its multi-block
    file (kinema's frames with springs, whose block 1 is the springs)."""
    root = _xml(path, file, where)
    if root.get("type") == "vtkMultiBlockDataSet":
        block = next((d for d in root.iter("DataSet") if d.get("index") == "0"), None)
        if block is None:
            raise fail(path, f"{where}: {file} has no block 0 (the particles)")
        file = _inside(path, file.parent, block.get("file"), where)
        root = _xml(path, file, where)
    if root.get("type") != "PolyData" or root.get("compressor"):
        raise fail(path, f"{where}: {file} is not uncompressed XML PolyData (kinema's own VTK frames)")
    header = _VTK_TYPES.get(root.get("header_type", "UInt32"), "<u4")
    if root.get("byte_order", "LittleEndian") != "LittleEndian":
        raise fail(path, f"{where}: {file} is big-endian; kinema reads its own little-endian files")
    piece = root.find("PolyData/Piece")
    if piece is None:
        raise fail(path, f"{where}: {file} has no Piece")
    out = {}
    points = piece.find("Points/DataArray")
    out["Points"] = np.zeros((0, 3)) if points is None else _data_array(path, points, header, where).reshape(-1, 3)
    for a in piece.findall("PointData/DataArray"):
        out[a.get("Name", "")] = _data_array(path, a, header, where)
    names = root.find("PolyData/FieldData/Array[@Name='type_names']")
    if names is not None and names.get("format") == "ascii":  # strings: their UTF-8 bytes, each ended by a 0
        codes = bytes(int(c) for c in (names.text or "").split())
        out["type_names"] = np.array(codes.decode("utf-8").split("\0")[:-1], dtype=object)
    return out


def read_vtk(path: Path) -> LoadedTrajectory:
    """Read a VTK series through its `.pvd` collection: each DataSet's `timestep` (the
    frame's time) and PolyData file (XML, inline binary or ascii, uncompressed; or the
    multi-block file of a frame with springs, its block 0), its points and the point data
    `v` (velocities), `radius`, `mass`, `id`, `type` (names: the field data
    `type_names`), `Color`, `group` (the collision groups), `angular_velocity` and `orientation` (w x y z), in SI units, the
    units kinema writes them in. A series without kinema's `speed` point data (another
    program's) is read in the same units, with a `UnitWarning`."""
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        raise fail(path, f"not a VTK collection (.pvd) that can be read as XML ({e})") from None
    if root.tag != "VTKFile" or root.get("type") != "Collection":
        raise fail(path, 'not a VTK collection (.pvd): its root is not <VTKFile type="Collection">')
    frames = []
    own = True
    for k, d in enumerate(root.findall("Collection/DataSet")):
        where = f"frame {k}"
        data = _vtp(path, _inside(path, path.parent, d.get("file"), where), where)
        x = data["Points"]
        n = len(x)
        own = own and "speed" in data
        try:
            time = float(d.get("timestep", ""))
        except ValueError:
            raise fail(path, f"{where}: DataSet timestep {d.get('timestep')!r} is not a number") from None
        frames.append(
            RawFrame(
                positions=x.astype(np.float64),
                where=where,
                ids=data["id"].astype(np.int64) if "id" in data else None,
                velocities=data["v"].reshape(n, 3).astype(np.float64) if "v" in data else None,
                masses=data["mass"].astype(np.float64) if "mass" in data else None,
                radii=data["radius"].astype(np.float64) if "radius" in data else None,
                species=data["type_names"][data["type"].astype(np.int64)] if "type" in data and "type_names" in data else None,
                colors=data["Color"].reshape(n, 3).astype(np.float64) if "Color" in data else None,
                groups=data["group"].astype(np.int64) if "group" in data and data["group"].dtype.kind in "iu" else None,
                angular_velocities=data["angular_velocity"].reshape(n, 3).astype(np.float64) if "angular_velocity" in data else None,
                orientations=data["orientation"].reshape(n, 4).astype(np.float64) if "orientation" in data else None,
                time=time,
                step=k,
            )
        )
    if frames and not own:
        warnings.warn(f"{path}: a VTK series kinema did not write (no 'speed' point data); its numbers are taken as SI (m, m/s, kg)", UnitWarning, stacklevel=4)
    return assemble(path, frames, SI, creator="kinema" if own else None)


# -- PLY ----------------------------------------------------------------------------------------

_PLY_TYPES = {"float": "f4", "float32": "f4", "double": "f8", "float64": "f8", "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4"}
_PLY_TYPES.update({"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2"})


def _ply_frame(path: Path, file: Path, where: str) -> RawFrame:
    data = file.read_bytes()
    end = data.find(b"end_header\n")
    if not data.startswith(b"ply\n") or end < 0:
        raise fail(path, f"{where}: {file.name} is not a PLY file")
    header = data[:end].decode("ascii", errors="replace").splitlines()
    if "comment kinema trajectory frame, SI units (m, m/s)" not in header:
        raise fail(path, f"{where}: {file.name} is not a PLY frame kinema wrote (kinema reads back its own PLY series only)")
    fmt = next((line.split()[1] for line in header if line.startswith("format ")), "")
    order = {"binary_little_endian": "<", "binary_big_endian": ">"}.get(fmt)
    time = next((line.split()[2] for line in header if line.startswith("comment time ")), None)
    type_names = {int(w[2]): w[3] for w in (line.split() for line in header) if w[:2] == ["comment", "type"] and len(w) == 4 and w[2].isdigit()}
    count, props, element = 0, [], None
    for line in header:
        words = line.split()
        if words[:1] == ["element"]:
            element = words[1]
            if element == "vertex":
                count = int(words[2])
        elif words[:1] == ["property"] and element == "vertex":
            if words[1] not in _PLY_TYPES:
                raise fail(path, f"{where}: {file.name}: vertex property {line!r} is not one kinema reads")
            props.append((words[2], _PLY_TYPES[words[1]]))
    body = data[end + len(b"end_header\n") :]
    if order is None:
        raise fail(path, f"{where}: {file.name} is PLY of format {fmt!r}; kinema writes and reads binary PLY")
    rows = np.frombuffer(body, dtype=[(name, order + t) for name, t in props], count=count)
    names = set(rows.dtype.names or ())
    vel = ("vx", "vy", "vz")
    species = None
    if "type" in names and type_names:
        known = np.isin(rows["type"], list(type_names))
        if not known.all():
            raise fail(path, f"{where}: {file.name}: vertex type {int(rows['type'][np.argmin(known)])} has no 'comment type' line naming it")
        species = np.array([type_names[int(t)] for t in rows["type"]], dtype=object)
    rgb = ("red", "green", "blue")
    return RawFrame(
        positions=np.stack([rows[a] for a in "xyz"], axis=1).astype(np.float64),
        where=where,
        ids=rows["id"].astype(np.int64) if "id" in names else None,
        velocities=np.stack([rows[a] for a in vel], axis=1).astype(np.float64) if names.issuperset(vel) else None,
        radii=rows["radius"].astype(np.float64) if "radius" in names else None,
        species=species,
        colors=np.stack([rows[c] for c in rgb], axis=1) / 255.0 if names.issuperset(rgb) else None,
        groups=rows["group"].astype(np.int64) if "group" in names and rows["group"].dtype.kind in "iu" else None,
        angular_velocities=np.stack([rows[c] for c in SPIN_CSV], axis=1).astype(np.float64) if names.issuperset(SPIN_CSV) else None,
        orientations=np.stack([rows[c] for c in ORIENTATION_CSV], axis=1).astype(np.float64) if names.issuperset(ORIENTATION_CSV) else None,
        time=None if time is None else float(time),
    )


def read_ply(folder: Path) -> LoadedTrajectory:
    """Read the PLY series kinema exported into `folder` (`<stem>_ply/`, its files
    `<stem>_00000.ply`, ... in the order of their numbers): each frame's vertices x y z, vx vy
    vz, radius and id (float32 and int32, as written), the species (`type` and the `comment
    type <index> <name>` lines), the colour (`red green blue`, /255), the collision group
    (`group`) and its `comment time`,
    SI units. PLY holds no masses."""
    files = sorted((p for p in folder.iterdir() if p.suffix.lower() == ".ply"), key=lambda p: (len(p.stem), p.stem))
    numbered = [p for p in files if re.search(r"_\d+$", p.stem)]
    frames = [_ply_frame(folder, _frame_file(folder, p, f"frame {k}"), f"frame {k} ({p.name})") for k, p in enumerate(numbered or files)]
    for k, fr in enumerate(frames):
        fr.step = k
    return assemble(folder, frames, SI, creator="kinema")
