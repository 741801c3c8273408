"""Which reader reads a trajectory file: `read_trajectory` tells the format by the file's
magic bytes (HDF5, GSD), else by its suffix, else by its first lines, and reads it with that
format's reader into a `LoadedTrajectory` in SI units (`Trajectory.load` makes a
`Trajectory` of it). A file of no format kinema reads is refused with the list of those it
reads."""

from __future__ import annotations

import os
import re
import stat
from pathlib import Path
from typing import Any

import numpy as np

from ._checks import TEXT_FACTOR, available_memory, gib
from ._files import TrajectoryFileError, special_kind
from ._h5md_checks import fail
from .h5md_reader import LoadedTrajectory

#: The formats ``read_trajectory`` reads, with the suffixes that name them.
READ_FORMATS = {
    "h5md": (".h5", ".hdf5", ".h5md"),
    "xyz": (".xyz", ".extxyz"),
    "gsd": (".gsd",),
    "lammps": (".lammpstrj", ".dump"),
    "lammps-data": (".data", ".lmp"),
    "csv": (".csv",),
    "vtk": (".pvd",),
    "ply": (".ply",),
    "usd": (".usd", ".usda", ".usdc", ".usdz"),
}
_HDF5 = b"\x89HDF\r\n\x1a\n"
_GSD = bytes.fromhex("df65df65df65df65")
# USD's binary (crate) and text layers (_usd.MAGIC_CRATE, MAGIC_TEXT); a .usdz, a zip
# ("PK"), is known by its suffix only: a zip is many things
_USD = (b"PXR-USDC", b"#usda")


def formats_read() -> str:
    """The formats kinema reads, in words, as a refusal names them."""
    return (
        "H5MD (.h5, .hdf5, .h5md), extended XYZ (.xyz, .extxyz), GSD (.gsd), LAMMPS dumps (.lammpstrj, .dump) and data files (.data, .lmp), "
        "kinema's own CSV (.csv), VTK series (.pvd) and PLY series (<stem>_ply/), and USD (.usd, .usda, .usdc, .usdz)"
    )


def _ply_series(path: Path) -> Path | None:
    """The folder of a PLY series `path` names: the folder itself (`run_ply/`), or the
    `<stem>_ply/` of the export `run.ply` named when it was written."""
    if path.is_dir():
        return path if any(p.suffix.lower() == ".ply" for p in path.iterdir()) else None
    if path.suffix.lower() == ".ply" and not path.exists():
        folder = path.with_name(f"{path.stem}_ply")
        return folder if folder.is_dir() else None
    return None


def _sniff_text(head: bytes) -> tuple[str | None, bool]:
    """The text format the first bytes of a file look like (or `None`), and whether the sign
    is sure (a LAMMPS dump's `ITEM:`, kinema's CSV header, a VTK collection) rather than a
    guess (a count alone on the first line: XYZ; `N atoms` in a header: a LAMMPS data file)."""
    text = head.decode("utf-8", errors="replace")
    lines = [line.strip() for line in text.splitlines()]
    first = next((line for line in lines if line), "")
    if first.startswith("ITEM:"):
        return "lammps", True
    if first.startswith("frame,time,id,"):
        return "csv", True
    if (first.startswith("<?xml") or first.startswith("<VTKFile")) and 'type="Collection"' in text:
        return "vtk", True
    if re.fullmatch(r"[0-9]+", lines[0] if lines else ""):
        return "xyz", False
    if any(re.fullmatch(r"[0-9]+\s+atoms", line.split("#")[0].strip()) for line in lines[1:40]):
        return "lammps-data", False
    return None, False


def detect_format(path: Path) -> str:
    """The format of the file `path`: HDF5's, GSD's or USD's magic bytes first, then a sure sign in
    the first lines (`ITEM:` a LAMMPS dump, kinema's CSV header, a VTK collection), then the
    suffix (`READ_FORMATS`), then a guess from the first lines (a count alone an XYZ file,
    `N atoms` in the header a LAMMPS data file).
    Raises `TrajectoryFileError` naming the formats kinema reads when none fits."""
    if _ply_series(path) is not None:
        return "ply"
    with open(path, "rb") as f:
        head = f.read(4096)
    if head.startswith(_HDF5):
        return "h5md"
    if head.startswith(_GSD):
        return "gsd"
    if head.startswith(_USD):
        return "usd"
    sniffed, sure = _sniff_text(head)
    if sure:  # (a dump named .lmp, say)
        return sniffed
    suffix = path.suffix.lower()
    by_suffix = next((name for name, suffixes in READ_FORMATS.items() if suffix in suffixes), None)
    if by_suffix not in (None, "h5md", "gsd"):  # (a binary format's suffix without its magic: the content decides)
        return by_suffix
    if sniffed is not None and by_suffix is None:  # (a guess does not overrule an .h5 or .gsd name)
        return sniffed
    if by_suffix == "h5md":
        raise fail(path, f"not an HDF5 file (corrupt, or another format); kinema reads {formats_read()}")
    if by_suffix == "gsd":
        raise fail(path, f"not a GSD file (it lacks GSD's first bytes); kinema reads {formats_read()}")
    said = f"the suffix {path.suffix!r}" if path.suffix else "no suffix"
    raise fail(path, f"not a format kinema reads (by {said} and by its content); kinema reads {formats_read()}")


def read_trajectory(
    path: str | os.PathLike,
    format: str | None = None,
    units: Any = None,
    group: str | None = None,
    follow_links: bool = False,
    atom_style: str | None = None,
) -> LoadedTrajectory:
    """Read the trajectory file `path` in its `format` (default: `detect_format`); returns
    a `LoadedTrajectory` in SI units.

    `units`: the units of a file that does not say them (a LAMMPS file without `ITEM:
    UNITS`, a HOOMD GSD file, an XYZ file not in ASE's units): a name (`"real"`,
    `"metal"`, `"si"`, `"cgs"`, `"electron"`, `"micro"`, `"nano"`, `"ase"`) or
    {"length": m, "time": s, "mass": kg}; refused for H5MD and kinema's own CSV, VTK and PLY,
    which are in known units, and USD, whose stage says them. `group` and `follow_links`
    are H5MD's (`load_h5md`), `atom_style` a LAMMPS data file's
    (`read_lammps.read_data`).

    Raises `TrajectoryFileError` (a `ValueError`), one line naming the file: missing, a
    directory or a device, of no format kinema reads (the message names those it reads), or
    what its format's reader refuses."""
    path = Path(path)
    if format is not None and format not in READ_FORMATS:
        raise ValueError(f"format = {format!r} is invalid: the formats read are {', '.join(map(repr, READ_FORMATS))}")
    try:
        series = _ply_series(path)
        if series is None:
            if not path.exists():
                raise fail(path, "no such file")
            mode = os.stat(path).st_mode
            if stat.S_ISDIR(mode):
                raise fail(path, f"is a directory, not a trajectory file; kinema reads {formats_read()}")
            kind = special_kind(mode)
            if kind is not None:
                raise fail(path, f"is a {kind}, not a trajectory file")
            size = os.stat(path).st_size
        fmt = format or detect_format(path)
    except OSError as e:  # a name too long, a loop of links, a folder not searchable
        raise fail(path, f"cannot be read ({e.strerror or e})") from None
    if fmt != "h5md" and (group is not None or follow_links):
        raise ValueError(f"group and follow_links are H5MD's options; {path} is read as {fmt}")
    if fmt != "lammps-data" and atom_style is not None:
        raise ValueError(f"atom_style is a LAMMPS data file's option; {path} is read as {fmt}")
    if fmt in ("h5md", "csv", "vtk", "ply", "usd") and units is not None:
        raise ValueError(
            f"units = {units!r}: {path} is read as {fmt}, whose units are known (SI, or the file's own); give units only for XYZ, GSD and LAMMPS files"
        )
    if fmt in ("xyz", "lammps", "lammps-data", "csv", "vtk") and series is None:
        free = available_memory()
        if free is not None and size * TEXT_FACTOR > free:
            raise fail(
                path, f"a text file of {gib(size)} GiB needs about {gib(size * TEXT_FACTOR)} GiB of memory to read, more than the {gib(free)} GiB available"
            )
    try:
        if fmt == "h5md":
            from .h5md import load_h5md

            return load_h5md(path, group=group, follow_links=follow_links)
        if fmt == "xyz":
            from .read_xyz import read_xyz

            return read_xyz(path, units)
        if fmt == "gsd":
            from .read_gsd import read_gsd

            return read_gsd(path, units)
        if fmt == "lammps":
            from .read_lammps import read_dump

            return read_dump(path, units)
        if fmt == "lammps-data":
            from .read_lammps import read_data

            return read_data(path, units, atom_style)
        if fmt == "usd":
            from .read_usd import read_usd

            return read_usd(path)
        from .read_exports import read_csv, read_ply, read_vtk

        return {"csv": read_csv, "vtk": read_vtk, "ply": read_ply}[fmt](series if fmt == "ply" else path)
    except MemoryError:
        raise fail(path, "not enough memory to read it") from None
    except OSError as e:
        if e.errno is None:
            raise
        raise fail(path, f"cannot be read ({e.strerror or e})") from None
    except TrajectoryFileError:
        raise
    except _DAMAGE.get(fmt, ()) as e:
        # what a parser (numpy, base64, plyfile's layout, USD's text, gsd) raises on a damaged
        # file that kinema's own checks did not reach first: one line naming the file
        # (make fuzz's reader generators found each: tests/fuzz_readers.py)
        what = str(e).splitlines()[0] if str(e) else ""
        where = series if fmt == "ply" and series is not None else path  # (a PLY series: its folder)
        raise fail(where, f"cannot be read: the {fmt} file is damaged ({type(e).__name__}: {what})") from None


# The exceptions that mean a damaged file, by format, where a parser raises them past kinema's
# own checks (ValueError covers UnicodeDecodeError and binascii.Error). Not for the formats
# whose readers raise ValueError for a bad `units=` (XYZ, LAMMPS, GSD's ValueErrors): their
# own checks name what they refuse.
_DAMAGE: dict[str, tuple[type[Exception], ...]] = {
    "csv": (ValueError, IndexError, OverflowError, KeyError),
    "vtk": (ValueError, IndexError, OverflowError, KeyError),
    "ply": (ValueError, IndexError, OverflowError, KeyError),
    "usd": (ValueError, IndexError, OverflowError, KeyError, RuntimeError),  # (pxr's Tf errors are RuntimeErrors)
    "gsd": (IndexError, OverflowError, KeyError),
    "h5md": (UnicodeError, IndexError, OverflowError),
}

_PARTICLES_CACHE: dict[tuple, dict[str, Any]] = {}  # the last file read by particles_from


def particles_from(
    path: str | os.PathLike,
    frame: int = -1,
    units: Any = None,
    format: str | None = None,
    atom_style: str | None = None,
) -> dict[str, Any]:
    """The particles of frame `frame` (an index, negative from the end: -1 the last) of the
    trajectory file `path` (any format `read_trajectory` reads, with its `units`,
    `format` and `atom_style`), in SI units, as a world takes them: `positions` (n, 3) m,
    `velocities` (n, 3) m/s or `None` where the file has none, `masses` kg, `radii` m,
    `species` and `groups` (collision groups) (n,) or `None` each where the file has none,
    `ids` (n,): the particles alive at that frame, in the order of their ids.

    The last file read is kept (by its path, size and time of change and the arguments), so a
    scene that counts its particles before it builds them reads the file once. Raises
    `ValueError` for a `frame` that is not an integer within the file's frames or a frame
    that holds no particle, and `TrajectoryFileError` as `read_trajectory`."""
    if isinstance(frame, bool) or not isinstance(frame, int | np.integer):
        raise TypeError(f"frame = {frame!r} is invalid: give an integer, the index of a frame (-1: the last)")
    path = Path(path)
    try:
        st = os.stat(path)
        stamp: tuple = (st.st_size, st.st_mtime_ns, st.st_ino)
    except OSError:
        stamp = ()
    key = (str(path.resolve()) if stamp else str(path), stamp, int(frame), repr(units), format, atom_style)
    if stamp and key in _PARTICLES_CACHE:
        return _PARTICLES_CACHE[key]
    read = read_trajectory(path, format=format, units=units, atom_style=atom_style)
    count = read.t.size
    if not -count <= frame < count:
        raise ValueError(f"frame = {frame} is invalid: {path} has {count} frame{'s' * (count != 1)} (0 to {count - 1}, or -{count} to -1 from the end)")
    k = int(frame) % count
    n = read.positions.shape[1]
    live = np.ones(n, dtype=bool) if read.alive is None else read.alive[k]
    if not live.any():
        raise ValueError(f"frame = {frame} is invalid: frame {k} of {path} holds no particle")
    v = None if read.velocities is None else read.velocities[k][live]
    out = {
        "positions": read.positions[k][live],
        "velocities": None if v is None or np.isnan(v).all() else v,
        "masses": None if read.masses is None else read.masses[live],
        "radii": None if read.radii is None else read.radii[live],
        "species": None if read.species is None else np.asarray(read.species)[live],
        "groups": None if getattr(read, "groups", None) is None else np.asarray(read.groups, dtype=np.int64)[live],
        "ids": (np.arange(n) if read.ids is None else np.asarray(read.ids))[live],
    }
    if stamp:
        _PARTICLES_CACHE.clear()
        _PARTICLES_CACHE[key] = out
    return out
