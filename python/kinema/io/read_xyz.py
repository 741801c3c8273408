"""Reading extended XYZ files (ASE's, OVITO's and kinema's own `.xyz`) and plain XYZ:
`read_xyz` gives a `LoadedTrajectory` in SI units. The numbers are parsed exactly (each
decimal to the nearest float64, as Python's `float` does), so a file kinema wrote reads back
bit for bit."""

from __future__ import annotations

import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from ._assemble import Box, RawFrame, assemble
from ._h5md_checks import fail
from .h5md_reader import LoadedTrajectory
from .units import ASE, Scales, UnitWarning, scales

# key=value pairs of the comment line (the extxyz convention of libAtoms and ASE): a value is
# "quoted" (with \" and \\ escapes), {braced} or a bare word; a key alone is a flag.
_PAIR = re.compile(r'\s*(?P<key>[^\s="{}]+)(?:\s*=\s*(?P<value>"(?:[^"\\]|\\.)*"|\{[^{}]*\}|[^\s"{}]+))?')
_TYPES = {"R": "real", "I": "integer", "S": "string", "L": "logical"}
_POSITIONS = ("pos", "positions")
_VELOCITIES = ("velo", "velocities", "vel")
_MASSES = ("mass", "masses")
_RADII = ("radius", "radii")
_IDS = ("id", "ids")
_NAMES = ("type", "species", "element")  # the first the file has names the particles


def comment_keys(line: str) -> dict[str, str] | None:
    """The key=value pairs of an extended XYZ comment line (a key alone is `"T"`), or `None`
    for a line that is not pairs (plain XYZ's free comment)."""
    out: dict[str, str] = {}
    pos, line = 0, line.rstrip("\r\n")
    while pos < len(line.rstrip()):
        m = _PAIR.match(line, pos)
        if m is None or m.end() == pos:
            return None
        value = m["value"]
        if value is None:
            value = "T"
        elif value[0] == '"':
            value = re.sub(r"\\(.)", r"\1", value[1:-1])
        elif value[0] == "{":
            value = value[1:-1]
        out[m["key"]] = value
        pos = m.end()
    return out


def _properties(path: Path, text: str, where: str) -> list[tuple[str, str, int]]:
    """`Properties=name:type:count:...` as (name, type letter, count) triples."""
    parts = text.split(":")
    if len(parts) % 3:
        raise fail(path, f"{where}: Properties={text!r} is not name:type:count triples")
    out = []
    for k in range(0, len(parts), 3):
        name, kind, count = parts[k : k + 3]
        if kind not in _TYPES or not count.isdigit() or int(count) < 1:
            raise fail(path, f"{where}: Properties={text!r}: {name}:{kind}:{count} is not a column (types R, I, S, L; a count >= 1)")
        out.append((name, kind, int(count)))
    return out


def _flags(path: Path, text: str, where: str) -> np.ndarray:
    words = text.split()
    known = {"T": True, "True": True, "true": True, "1": True, "F": False, "False": False, "false": False, "0": False}
    if len(words) != 3 or any(w not in known for w in words):
        raise fail(path, f"{where}: pbc={text!r} is invalid: give three flags T or F")
    return np.array([known[w] for w in words])


def _numbers(path: Path, text: str, count: int, key: str, where: str) -> np.ndarray:
    try:
        a = np.array(text.split(), dtype=str).astype(np.float64)
    except ValueError:
        a = np.zeros(0)
    if a.size != count or not np.isfinite(a).all():
        raise fail(path, f"{where}: {key}={text!r} is invalid: give {count} finite numbers")
    return a


def _box(path: Path, keys: dict[str, str], where: str) -> Box | None:
    """The cell of `Lattice` (its vectors along the axes: kinema's box is axis-aligned),
    placed at `Origin` (OVITO's and kinema's key; 0 without it), periodic along `pbc`
    (ASE's default with a Lattice: T T T)."""
    if "Lattice" not in keys:
        return None
    m = _numbers(path, keys["Lattice"], 9, "Lattice", where).reshape(3, 3)
    if np.any(m[~np.eye(3, dtype=bool)] != 0):
        raise fail(path, f"{where}: Lattice={keys['Lattice']!r} is a cell that is not along the axes (triclinic), which kinema cannot read")
    origin = _numbers(path, keys["Origin"], 3, "Origin", where) if "Origin" in keys else np.zeros(3)
    periodic = _flags(path, keys["pbc"], where) if "pbc" in keys else np.ones(3, dtype=bool)
    return Box(origin, origin + np.diag(m), periodic)


def _column(path: Path, table: np.ndarray, start: int, count: int, kind: str, name: str, where: str) -> np.ndarray:
    """Columns `start .. start + count` of the frame's words as their type's values."""
    words = table[:, start : start + count]
    try:
        if kind == "R":
            return words.astype(np.float64)
        if kind == "I":
            return words.astype(np.int64)
        if kind == "L":
            known = {"T": True, "True": True, "F": False, "False": False}
            return np.vectorize(lambda w: known[w], otypes=[bool])(words)
    except OverflowError:  # an integer beyond int64
        for r, row in enumerate(words):
            for w in row:
                if not -(2**63) <= int(w) <= 2**63 - 1:
                    raise fail(
                        path, f"{where}, row {r}: column {name!r} ({_TYPES[kind]}) has {str(w)[:40]}, beyond int64 ({-(2**63)} to {2**63 - 1})"
                    ) from None
        raise
    except (ValueError, KeyError):
        for r, row in enumerate(words):
            for w in row:
                try:
                    {"R": float, "I": int}.get(kind, lambda w: {"T": 1, "True": 1, "F": 0, "False": 0}[w])(w)
                except (ValueError, KeyError):
                    raise fail(path, f"{where}, row {r}: column {name!r} ({_TYPES[kind]}) has {str(w)!r}") from None
    return words


#: An `orientation` column (x y z w, OVITO's order, as kinema writes it) as kinema's w x y z.
WXYZ = [3, 0, 1, 2]


def _vectors(path: Path, columns: dict[str, np.ndarray], name: str, width: int, where: str) -> np.ndarray | None:
    """The column `name` of `width` real numbers per particle (`omega:R:3`,
    `orientation:R:4`), `None` where the frame has none; another shape is refused."""
    a = columns.get(name)
    if a is None:
        return None
    if a.ndim != 2 or a.shape[1] != width or a.dtype != np.float64:
        raise fail(path, f"{where}: column {name!r} must be {width} real numbers ({name}:R:{width})")
    return a


def _first(columns: dict[str, np.ndarray], names: tuple[str, ...]) -> np.ndarray | None:
    return next((columns[n] for n in names if n in columns), None)


def _ase_masses(path: Path, names: np.ndarray, warned: list[bool]) -> np.ndarray | None:
    """The masses (amu) ASE gives particles of these chemical symbols without a masses column
    (`Atoms.get_masses()`: its table of standard atomic weights), so that an ASE file's
    `momenta` give velocities as in ASE; said once with a `UnitWarning`. `None` where a
    name is not a chemical symbol, or ASE (the table's keeper) is not installed."""
    try:
        from ase.data import atomic_masses, atomic_numbers
    except ImportError:
        return None
    if not all(n in atomic_numbers and n != "X" for n in names):
        return None
    if not warned:
        warned.append(True)
        warnings.warn(
            f"{path}: no masses in the file; ASE's standard atomic masses of its chemical symbols (amu), as ASE's get_masses() gives", UnitWarning, stacklevel=4
        )
    return np.array([atomic_masses[atomic_numbers[n]] for n in names], dtype=np.float64)


def _frame_columns(path: Path, rows: list[str], first: int, keys: dict[str, str], where: str) -> dict[str, np.ndarray]:
    """A frame's `rows` (the first at line `first`) as the columns its `Properties` key names
    (`species:S:1:pos:R:3` when it names none), each parsed as its kind says; a row of
    another width is refused, naming its line."""
    n = len(rows)
    props = _properties(path, keys.get("Properties", "species:S:1:pos:R:3"), where)
    width = sum(c for _, _, c in props)
    words = " ".join(rows).split()
    if len(words) != n * width:
        for r, line in enumerate(rows):
            if len(line.split()) != width:
                raise fail(path, f"{where}, line {first + r}: {len(line.split())} values, but Properties names {width} columns")
    table = np.array(words, dtype=str).reshape(n, width)
    columns: dict[str, np.ndarray] = {}
    start = 0
    for name, kind, count in props:
        a = _column(path, table, start, count, kind, name, where)
        columns[name] = a if count > 1 else a[:, 0]
        start += count
    return columns


def read_xyz(path: Path, units: Any = None) -> LoadedTrajectory:
    """Read the extended XYZ (or plain XYZ) file `path`.

    Each frame: the number of particles, the comment line of key=value pairs, one row per
    particle with the columns `Properties` names (`species:S:1:pos:R:3` when it names
    none). Read: `pos` (positions), `velo` (velocities; else `momenta` / masses), `mass`
    or `masses` (else, in a file of ASE's units whose names are all chemical symbols, ASE's
    standard atomic masses, as `Atoms.get_masses()` gives, with a `UnitWarning`), `radius`,
    `id` (particles followed by id: a number of rows that varies
    is read as births and deaths), the names of `type` (OVITO's and kinema's particle type),
    else `species`, `color` (r g b in [0, 1], kinema's), `group` (an integer column:
    kinema's collision groups, 0..31), `omega` (angular velocities, in 1 /
    the time unit) and `orientation` (unit quaternions x y z w, OVITO's order, given back w
    first); the cell of `Lattice` (along the axes only) at `Origin` with `pbc`;
    `Time` (or `time`). Other columns and keys are skipped.

    Units: a file's `units=` key (kinema writes `units=SI`) says them; a file without one
    is in ASE's units, the convention of the format (Å, amu, Å per ASE time unit, ASE's
    `Time`), unless `units` (see `kinema.io.units.scales`) says otherwise. A `units`
    argument that contradicts the file's key is refused. Extended XYZ has no dimension: the
    trajectory is 3D (a 2D run's z is 0)."""
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as e:
        raise fail(path, f"not a text file ({e.reason} at byte {e.start}), so not XYZ") from None
    lines = text.splitlines()
    frames: list[RawFrame] = []
    file_units: str | None = None
    warned: list[bool] = []  # (ASE's masses said once a file)
    warned_momenta: list[bool] = []  # (momenta without masses said once a file)
    i = 0
    while i < len(lines):
        head = lines[i].strip()
        if not head:
            if any(line.strip() for line in lines[i:]):
                raise fail(path, f"line {i + 1} is empty where a frame's count of particles was due")
            break
        where = f"frame {len(frames)} (line {i + 1})"
        if not head.isdigit():
            raise fail(path, f"{where}: {head[:40]!r} is not a count of particles (an XYZ frame starts with one)")
        n = int(head)
        if i + 2 + n > len(lines):
            raise fail(path, f"{where}: the file ends before the {n} rows of the frame")
        keys = comment_keys(lines[i + 1]) or {}
        if "units" in keys:
            if file_units is not None and keys["units"] != file_units:
                raise fail(path, f"{where}: units={keys['units']} but an earlier frame says units={file_units}")
            file_units = keys["units"]
        columns = _frame_columns(path, lines[i + 2 : i + 2 + n], i + 3, keys, where)
        pos = _first(columns, _POSITIONS)
        if pos is None or pos.ndim != 2 or pos.shape[1] != 3 or pos.dtype != np.float64:
            raise fail(path, f"{where}: Properties has no pos:R:3 column (the positions)")
        box = _box(path, keys, where)  # (refused before anything is said about masses)
        masses = _first(columns, _MASSES)
        names = _first(columns, _NAMES)
        if masses is None and "units" not in keys and units is None and names is not None:
            masses = _ase_masses(path, names.astype(str), warned)
        velocities = _first(columns, _VELOCITIES)
        if velocities is None and "momenta" in columns and masses is not None:
            velocities = columns["momenta"] / masses[:, None]
        elif velocities is None and "momenta" in columns and not warned_momenta:
            # velocities are momenta / masses: without masses there are none to read (NaN, "unknown")
            warned_momenta.append(True)
            warnings.warn(
                f"{path}: {where} has momenta but no masses (no mass or masses column, and no chemical symbols in ASE's units to take ASE's masses from), "
                "so no velocities are read (they stay unknown); add a masses column to read them",
                UserWarning,
                stacklevel=4,
            )
        time = next((keys[k] for k in ("Time", "time") if k in keys), None)
        if time is not None:
            time = float(_numbers(path, time, 1, "Time", where)[0])
        frames.append(
            RawFrame(
                positions=pos,
                where=where,
                ids=_first(columns, _IDS),
                velocities=velocities,
                masses=masses,
                radii=_first(columns, _RADII),
                species=None if names is None else names.astype(str),
                colors=columns["color"] if "color" in columns and columns["color"].ndim == 2 and columns["color"].shape[1] == 3 else None,
                groups=columns["group"] if "group" in columns and columns["group"].ndim == 1 and columns["group"].dtype == np.int64 else None,
                angular_velocities=_vectors(path, columns, "omega", 3, where),
                orientations=None if (q := _vectors(path, columns, "orientation", 4, where)) is None else q[:, WXYZ],
                time=time,
                box=box,
            )
        )
        i += 2 + n
    if file_units is not None:
        given = scales(file_units, f"{path}: the file's key units")
        if units is not None and scales(units, "units") != given:
            raise fail(path, f"the file says units={file_units}, which units = {units!r} contradicts")
        unit_scales: Scales = given
    else:
        unit_scales = ASE if units is None else scales(units, "units")
    return assemble(path, frames, unit_scales)
