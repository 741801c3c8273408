"""Reading LAMMPS's text files: dumps (`dump custom` and `dump atom`; kinema's own
`.lammpstrj`) with `read_dump` and data files (`read_data`'s format, `write_data`'s and
ASE's) with `read_data`, each to a `LoadedTrajectory` in SI units. The numbers are parsed
exactly (each decimal to the nearest float64), so a dump kinema wrote reads back bit for bit.

Units are LAMMPS's unit styles (`kinema.io.units.LAMMPS_STYLES`), by LAMMPS's own constants:
a dump's `ITEM: UNITS` (`dump_modify units yes`), a data file's title `units = real`
(`write_data`), else the `units` argument; a file without either is refused (its masses
would be in no known unit), as is the style `lj` without its scales.

What the two readers share (the text, the units, rows of words parsed exactly, atom ids, a box
along the axes) is in `kinema.io._lammps_text`."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from .._checks import SPECIES_PATTERN
from ..contact_record import FIELDS, ContactRecord
from ._assemble import Box, RawFrame, assemble
from ._h5md_checks import fail
from ._lammps_text import _INT64, _as, _atom_ids, _axis_box, _text, _unit_scales, _words
from .h5md_reader import LoadedTrajectory
from .lammps_dump import LOCAL_COLUMNS, ORIENTATION_COLUMNS, SPIN_COLUMNS

# A dump's coordinates, in the order kinema takes them: wrapped, unwrapped, scaled, scaled unwrapped.
_COORDINATES = (("x", "y", "z"), ("xu", "yu", "zu"), ("xs", "ys", "zs"), ("xsu", "ysu", "zsu"))

#: The atom styles of a data file's Atoms section kinema reads: the columns of a row (before
#: 3 optional image flags), as LAMMPS's read_data documents them.
ATOM_STYLES = {
    "atomic": ("id", "type", "x", "y", "z"),
    "charge": ("id", "type", "q", "x", "y", "z"),
    "bond": ("id", "mol", "type", "x", "y", "z"),
    "angle": ("id", "mol", "type", "x", "y", "z"),
    "molecular": ("id", "mol", "type", "x", "y", "z"),
    "full": ("id", "mol", "type", "q", "x", "y", "z"),
    "sphere": ("id", "type", "diameter", "density", "x", "y", "z"),
}
# read_data's section keywords: a line that is one of them (its comment aside) starts a section.
_SECTIONS = frozenset(
    "Atoms Velocities Masses Ellipsoids Lines Triangles Bodies Bonds Angles Dihedrals Impropers "
    "Pair_Coeffs PairIJ_Coeffs Bond_Coeffs Angle_Coeffs Dihedral_Coeffs Improper_Coeffs BondBond_Coeffs BondAngle_Coeffs "
    "MiddleBondTorsion_Coeffs EndBondTorsion_Coeffs AngleTorsion_Coeffs AngleAngleTorsion_Coeffs BondBond13_Coeffs AngleAngle_Coeffs "
    "Atom_Type_Labels Bond_Type_Labels Angle_Type_Labels Dihedral_Type_Labels Improper_Type_Labels".replace("_", "\0").split()
)
_SECTIONS = frozenset(s.replace("\0", " ") for s in _SECTIONS)


def _periodic_flags(path: Path, flags: list[str], where: str) -> np.ndarray:
    if len(flags) != 3 or any(not re.fullmatch(r"[pfsm]{1,2}", f) for f in flags):
        raise fail(path, f"{where}: BOX BOUNDS flags {' '.join(flags)!r} are invalid: give three boundary flags (pp, ff, fs, ...)")
    return np.array([f.startswith("p") for f in flags])


def _two_d(frames: list[RawFrame]) -> bool:
    """A LAMMPS 2D run: z periodic (LAMMPS's rule for 2D) and every z (and z velocity) 0."""
    return all(
        fr.box is not None and fr.box.periodic[2] and not np.any(fr.positions[:, 2]) and (fr.velocities is None or not np.any(fr.velocities[:, 2]))
        for fr in frames
    )


def read_dump(path: Path, units: Any = None) -> LoadedTrajectory:
    """Read the LAMMPS text dump `path` (`dump custom`, `dump atom`; frames one after the
    other, as `dump_modify units yes time yes` writes them too).

    Read: `id` (particles followed by id: a number of atoms that changes is read as births
    and deaths), `type` as the species name (`element`, from `dump_modify element`, where
    there is one), the positions of `x y z`, else `xu yu zu`, else the scaled `xs ys zs`
    or `xsu ysu zsu` (times the box's edges), `vx vy vz`, `mass`, `radius` (or
    `diameter` / 2), `group` (kinema's collision groups, 0..31); `ITEM: TIME` (the frames' times), `ITEM: TIMESTEP` (`source.step`),
    the box of `ITEM: BOX BOUNDS`, periodic where its flag is `pp` (a tilted box is
    refused). A dump whose box is periodic in z and whose z are all 0 is a 2D run."""
    lines = _text(path).splitlines()
    frames: list[RawFrame] = []
    stated: str | None = None
    labels: dict[str, str] = {}
    time = step = n = box = None
    i = 0
    while i < len(lines):
        line = lines[i].strip()
        if not line:
            i += 1
            continue
        if not line.startswith("ITEM:"):
            raise fail(path, f"line {i + 1}: {line[:40]!r} where an ITEM: line was due")
        item = line[5:].strip()
        where = f"frame {len(frames)} (line {i + 1})"
        if item == "UNITS":
            stated = _value(path, lines, i, str, "ITEM: UNITS")
            i += 2
        elif item.startswith("ATOM TYPE LABELS"):
            count = item.split()[3:]
            if len(count) != 1 or not count[0].isdigit():
                raise fail(path, f"line {i + 1}: ITEM: ATOM TYPE LABELS needs the number of labels after it (ITEM: ATOM TYPE LABELS 2)")
            rows = lines[i + 1 : i + 1 + int(count[0])]
            for r, row in enumerate(_words(path, rows, i + 2, 2, "ITEM: ATOM TYPE LABELS")):
                if len(rows) < int(count[0]) or not re.fullmatch(SPECIES_PATTERN, row[1]):
                    raise fail(path, f"line {i + 2 + r}: the type label {row[1][:40]!r} is invalid: a species name is one word of letters, digits and _ . + -")
                labels[row[0]] = row[1]
            if len(rows) < int(count[0]):
                raise fail(path, f"line {i + 1}: the file ends before the {count[0]} type labels")
            i += 1 + len(rows)
        elif item == "TIME":
            time = _value(path, lines, i, float, "ITEM: TIME")
            i += 2
        elif item == "TIMESTEP":
            step = _value(path, lines, i, int, "ITEM: TIMESTEP")
            i += 2
        elif item == "NUMBER OF ATOMS":
            n = _value(path, lines, i, int, "ITEM: NUMBER OF ATOMS")
            if n < 0:
                raise fail(path, f"line {i + 2}: NUMBER OF ATOMS = {n} is invalid: it must be >= 0")
            i += 2
        elif item.startswith("BOX BOUNDS"):
            box = _dump_box(path, lines, i, item.split()[2:], where)
            i += 4
        elif item.startswith("ATOMS"):
            if n is None:
                raise fail(path, f"{where}: ITEM: ATOMS before ITEM: NUMBER OF ATOMS")
            frames.append(_dump_frame(path, item.split()[1:], lines[i + 1 : i + 1 + n], i + 2, where, time, step, box, labels))
            if len(lines) < i + 1 + n:
                raise fail(path, f"{where}: the file ends before the {n} atoms of the frame")
            time = step = n = None
            i += 1 + len(frames[-1].positions)
        elif item == "NUMBER OF ENTRIES":
            raise fail(
                path,
                f"line {i + 1}: a LAMMPS dump local file (ITEM: NUMBER OF ENTRIES), not a dump of atoms; read kinema's contacts with kinema.io.read_contacts_dump",
            )
        else:
            raise fail(path, f"line {i + 1}: ITEM: {item[:40]} is not an item of a LAMMPS dump kinema reads")
    scale = _unit_scales(path, stated, units, "ITEM: UNITS")
    return assemble(path, frames, scale, dim=2 if frames and _two_d(frames) else 3, creator="LAMMPS dump")


def read_contacts_dump(path: str | Path) -> tuple[np.ndarray, ContactRecord]:
    """Read a contacts file of kinema's LAMMPS export (`<stem>_contacts.dump` or
    `<stem>_collider_contacts.dump`, `lammps_dump.write_contacts_local`: LAMMPS's `dump
    local` layout) back: the `ITEM: TIMESTEP` of each frame (F,) and the contacts as a
    `kinema.contact_record.ContactRecord` in SI units, `i` and `j` kinema's ids (the
    file's `id1`, `id2` − 1; `j` −1 in the colliders' file), `collider` −1 in the
    particles' file. Columns other than kinema's (`LOCAL_COLUMNS`) are skipped. A file that
    is not such a dump is a `TrajectoryFileError` naming the line."""
    path = Path(path)
    lines = _text(path).splitlines()
    by_stem = {stem: name for name, stem in LOCAL_COLUMNS.items()}
    steps: list[int] = []
    frames: list[dict[str, np.ndarray]] = []
    i, step, n = 0, None, None
    while i < len(lines):
        line = lines[i].strip()
        if not line:
            i += 1
            continue
        if not line.startswith("ITEM:"):
            raise fail(path, f"line {i + 1}: {line[:40]!r} where an ITEM: line was due")
        item = line[5:].strip()
        if item == "TIMESTEP":
            step = _value(path, lines, i, int, "ITEM: TIMESTEP")
            i += 2
        elif item == "NUMBER OF ENTRIES":
            n = _value(path, lines, i, int, "ITEM: NUMBER OF ENTRIES")
            if n < 0:
                raise fail(path, f"line {i + 2}: NUMBER OF ENTRIES = {n} is invalid: it must be >= 0")
            i += 2
        elif item.startswith("BOX BOUNDS"):
            i += 4
        elif item.startswith("ENTRIES"):
            if n is None or step is None:
                raise fail(path, f"line {i + 1}: ITEM: ENTRIES before ITEM: TIMESTEP and ITEM: NUMBER OF ENTRIES")
            columns = item.split()[1:]
            if len(lines) < i + 1 + n:
                raise fail(path, f"line {i + 1}: the file ends before the {n} entries of the frame")
            table = _words(path, lines[i + 1 : i + 1 + n], i + 2, len(columns), f"timestep {step}")
            at = {c: k for k, c in enumerate(columns)}
            if "id1" not in at:
                raise fail(path, f"line {i + 1}: ITEM: ENTRIES has no id1 column (kinema's contacts: {' '.join(columns)})")
            frame: dict[str, np.ndarray] = {}
            for stem, name in by_stem.items():
                kind = FIELDS[name].kind
                dtype = np.float64 if kind == "real" else np.int64
                if stem in at:
                    frame[name] = _as(path, table[:, at[stem]], dtype, stem, f"timestep {step}", i + 2)
                elif all(stem + c in at for c in "xyz"):
                    frame[name] = np.stack([_as(path, table[:, at[stem + c]], dtype, stem + c, f"timestep {step}", i + 2) for c in "xyz"], axis=1)
            frame["i"] = frame["i"] - 1
            frame["j"] = frame["j"] - 1 if "j" in frame else np.full(n, -1, dtype=np.int64)
            frame.setdefault("collider", np.full(n, -1, dtype=np.int64))
            if "sliding" in frame:
                frame["sliding"] = frame["sliding"] != 0
            steps.append(int(step))
            frames.append(frame)
            step = n = None
            i += 1 + len(table)
        else:
            raise fail(path, f"line {i + 1}: ITEM: {item[:40]} is not an item of a LAMMPS dump local file")
    if not frames:
        raise fail(path, "holds no frame (no ITEM: ENTRIES)")
    return np.array(steps, dtype=np.int64), ContactRecord.from_frames(frames)


def _dump_box(path: Path, lines: list[str], i: int, words: list[str], where: str) -> Box:
    """`ITEM: BOX BOUNDS` at line `i`: orthogonal (`xlo xhi` rows), restricted triclinic
    (`xy xz yz`: rows `lo hi tilt`, tilts 0 only) or general triclinic (`abc origin`:
    rows `a_x a_y a_z origin_x`, LAMMPS 2024's and OVITO 3.10's), with the boundary flags."""
    if words[:2] == ["abc", "origin"]:
        rows = _as(path, _words(path, lines[i + 1 : i + 4], i + 2, 4, where), np.float64, "BOX BOUNDS", where, i + 2)
        return _axis_box(path, rows[:, :3], rows[:, 3], _periodic_flags(path, words[2:], where), where)
    tilted = words[:3] == ["xy", "xz", "yz"]
    flags = words[3:] if tilted else words
    rows = _as(path, _words(path, lines[i + 1 : i + 4], i + 2, 3 if tilted else 2, where), np.float64, "BOX BOUNDS", where, i + 2)
    if tilted and np.any(rows[:, 2] != 0):
        raise fail(path, f"{where}: a tilted box (xy xz yz = {rows[:, 2].tolist()}); kinema reads boxes along the axes only")
    return Box(rows[:, 0].copy(), rows[:, 1].copy(), _periodic_flags(path, flags, where))


def _value(path: Path, lines: list[str], i: int, kind: Any, item: str) -> Any:
    text = lines[i + 1].strip() if i + 1 < len(lines) else ""
    try:
        v = kind(text)
        if kind is float and not math.isfinite(v):
            raise ValueError
    except ValueError:
        raise fail(
            path, f"line {i + 2}: {item} holds {text[:40]!r}, not {'an integer' if kind is int else 'a finite number' if kind is float else 'a word'}"
        ) from None
    if kind is int and not _INT64[0] <= v <= _INT64[1]:
        raise fail(path, f"line {i + 2}: {item} holds {text[:40]}, beyond int64 ({_INT64[0]} to {_INT64[1]})")
    return v


def _dump_frame(
    path: Path, columns: list[str], rows: list[str], first: int, where: str, time: Any, step: Any, box: Box | None, labels: dict[str, str]
) -> RawFrame:
    if len(set(columns)) != len(columns):
        raise fail(path, f"{where}: ITEM: ATOMS names a column twice ({' '.join(columns)})")
    table = _words(path, rows, first, len(columns), where)
    at = {name: k for k, name in enumerate(columns)}

    def col(name: str, dtype: Any = np.float64) -> np.ndarray:
        return _as(path, table[:, at[name]], dtype, name, where, first)

    names = next((c for c in _COORDINATES if all(a in at for a in c)), None)
    if names is None:
        raise fail(path, f"{where}: ITEM: ATOMS has no positions (x y z, xu yu zu, xs ys zs or xsu ysu zsu): {' '.join(columns)}")
    x = np.stack([col(a) for a in names], axis=1)
    if names[0].startswith("xs"):
        if box is None:
            raise fail(path, f"{where}: scaled positions ({' '.join(names)}) but no ITEM: BOX BOUNDS")
        x = box.lo + x * (box.hi - box.lo)
    v = np.stack([col(a) for a in ("vx", "vy", "vz")], axis=1) if all(a in at for a in ("vx", "vy", "vz")) else None
    spin = {}
    for name, columns in (("angular_velocities", SPIN_COLUMNS), ("orientations", ORIENTATION_COLUMNS)):
        if all(a in at for a in columns.split()):
            spin[name] = np.stack([col(a) for a in columns.split()], axis=1)
    radii = col("radius") if "radius" in at else col("diameter") / 2 if "diameter" in at else None
    kind = "element" if "element" in at else "type" if "type" in at else None
    return RawFrame(
        positions=x,
        where=where,
        ids=_atom_ids(path, col("id", np.int64), first, where) if "id" in at else None,  # LAMMPS's ids from 1, kinema's from 0
        velocities=v,
        masses=col("mass") if "mass" in at else None,
        radii=radii,
        species=None if kind is None else _names(table[:, at[kind]], labels if kind == "type" else {}),
        groups=col("group", np.int64) if "group" in at else None,  # kinema's collision groups
        **spin,
        time=time,
        step=step,
        box=box,
    )


def _names(words: np.ndarray, labels: dict[str, str]) -> np.ndarray:
    """The species of a dump's `type` (or `element`) column: each type's label where
    `ITEM: ATOM TYPE LABELS` gave one, else the word itself."""
    return np.array([labels.get(w, w) for w in words.tolist()], dtype=object)


# -- data files --------------------------------------------------------------------------------


def _strip(line: str) -> str:
    return line.split("#", 1)[0].strip()


class _Section(NamedTuple):
    """A data file's section: the line number of its first row, its rows (comments cut off),
    the same rows as written (comments kept), the comment of its keyword line."""

    first: int
    rows: list[str]
    raw: list[str]
    comment: str


def _sections(path: Path, lines: list[str]) -> tuple[dict[str, str], dict[str, _Section]]:
    """The header (keyword -> its numbers, as text) and the sections of a data file."""
    header: dict[str, str] = {}
    sections: dict[str, _Section] = {}
    current: str | None = None
    for i, raw in enumerate(lines[1:], start=2):
        text = _strip(raw)
        if not text:
            continue
        if text in _SECTIONS:
            if text in sections:
                raise fail(path, f"line {i}: a second {text} section")
            current = text
            sections[current] = _Section(0, [], [], raw.split("#", 1)[1].strip() if "#" in raw else "")
            continue
        if current is None:
            m = re.fullmatch(r"([-+0-9.eE\s]+?)\s+([A-Za-z][A-Za-z ]*)", text)
            if m is None:
                raise fail(path, f"line {i}: {text[:40]!r} is neither a header line nor a section of a LAMMPS data file")
            header[m[2]] = m[1]
            continue
        if not sections[current].rows:
            sections[current] = sections[current]._replace(first=i)
        sections[current].rows.append(text)
        sections[current].raw.append(raw)
    return header, sections


def _count(path: Path, header: dict[str, str], key: str) -> int:
    text = header.get(key, "0")
    if not re.fullmatch(r"[0-9]+", text):
        raise fail(path, f"the header line '{text} {key}' is invalid: it must be a count >= 0")
    return int(text)


def _style(path: Path, comment: str, width: int, atom_style: str | None) -> str:
    """The atom style of the Atoms section: its `# style` comment (LAMMPS's write_data and ASE
    write one), else `atom_style`, else the one style with rows of `width` values (with or
    without 3 image flags)."""
    named = comment.split()[0] if comment else None
    if named is not None and atom_style is not None and named != atom_style:
        raise fail(path, f"the Atoms section says its style is {named!r}, which atom_style = {atom_style!r} contradicts")
    style = named or atom_style
    if style is not None:
        if style not in ATOM_STYLES:
            raise fail(path, f"atom style {style!r} is not one kinema reads; it reads {', '.join(ATOM_STYLES)}")
        return style
    fits = sorted({s for s, cols in ATOM_STYLES.items() if width in (len(cols), len(cols) + 3)}, key=list(ATOM_STYLES).index)
    if len(fits) == 1:
        return fits[0]
    if not fits:
        raise fail(path, f"the Atoms rows have {width} values, which fit none of the atom styles kinema reads ({', '.join(ATOM_STYLES)})")
    raise fail(path, f"the Atoms rows have {width} values, which fit the atom styles {', '.join(fits)}; name it: Atoms # <style> in the file, or atom_style=")


def _numbers(path: Path, header: dict[str, str], key: str, count: int) -> np.ndarray:
    try:
        a = np.array(header[key].split(), dtype=str).astype(np.float64)
    except ValueError:
        a = np.zeros(0)
    if a.size != count or not np.isfinite(a).all():
        raise fail(path, f"the header line '{header[key]} {key}' is invalid: give {count} finite numbers")
    return a


def _data_box(path: Path, header: dict[str, str]) -> Box:
    """The header's box: `xlo xhi`, `ylo yhi`, `zlo zhi` (and `xy xz yz`, 0 only), or
    LAMMPS 2024's general triclinic `avec`, `bvec`, `cvec` and `abc origin` (along the
    axes only), periodic on every axis (a data file does not say its boundaries: LAMMPS's
    default)."""
    periodic = np.ones(3, dtype=bool)
    if "avec" in header:
        for key in ("bvec", "cvec", "abc origin"):
            if key not in header:
                raise fail(path, f"the header has avec but no '{key}' line (the box)")
        vectors = np.stack([_numbers(path, header, k, 3) for k in ("avec", "bvec", "cvec")])
        return _axis_box(path, vectors, _numbers(path, header, "abc origin", 3), periodic, "the header")
    lo, hi = np.zeros(3), np.zeros(3)
    for k, axis in enumerate("xyz"):
        key = f"{axis}lo {axis}hi"
        if key not in header:
            raise fail(path, f"the header has no '{key}' line (the box)")
        lo[k], hi[k] = _numbers(path, header, key, 2)
    if "xy xz yz" in header and np.any((tilt := _numbers(path, header, "xy xz yz", 3)) != 0):
        raise fail(path, f"a tilted box (xy xz yz = {tilt.tolist()}); kinema reads boxes along the axes only")
    return Box(lo, hi, periodic)


def read_data(path: Path, units: Any = None, atom_style: str | None = None) -> LoadedTrajectory:
    """Read the LAMMPS data file `path` (`read_data`'s format) as a one-frame trajectory.

    Read: the header's atom count and box (`xlo xhi` ...; a tilted box, `xy xz yz` not 0,
    is refused), the `Masses` (per type), the `Atoms` in the styles of `ATOM_STYLES`
    (named by the section's `# style` comment, else by `atom_style`, else by the number of
    values of a row where only one style has that many; image flags are skipped; style
    `sphere` gives the radius, diameter / 2, and the mass, density × 4π/3 r³, or the density
    itself where the diameter is 0, as LAMMPS computes it), the `Velocities`; the species
    are the names of `Atom Type Labels`, else those of the `Masses` comments where each
    type has one word (ASE writes `1 55.845 # Fe`), else the type numbers. A data file does
    not say its boundaries: its box is taken as periodic on every axis (LAMMPS's default,
    `boundary p p p`). The step is the title's `timestep = N` (LAMMPS's write_data), the
    time 0."""
    lines = _text(path).splitlines()
    if not lines:
        raise fail(path, "is empty")
    title = lines[0]
    header, sections = _sections(path, lines)
    stated = re.search(r"\bunits\s*=\s*(\w+)", title)
    scale = _unit_scales(path, stated[1] if stated else None, units, "its title's 'units = <style>', which LAMMPS's write_data writes,")
    n = _count(path, header, "atoms")
    ntypes = _count(path, header, "atom types")
    if "Atoms" not in sections and n:
        raise fail(path, f"the header announces {n} atoms but there is no Atoms section")
    box = _data_box(path, header)
    first, rows, _, comment = sections.get("Atoms", _Section(0, [], [], ""))
    if len(rows) != n:
        raise fail(path, f"the Atoms section has {len(rows)} rows but the header announces {n} atoms")
    width = len(rows[0].split()) if rows else 0
    style = _style(path, comment, width, atom_style)
    cols = ATOM_STYLES[style]
    if width not in (len(cols), len(cols) + 3):
        raise fail(path, f"line {first}: {width} values, but atom style {style} has {len(cols)} (and 3 image flags)")
    where = f"Atoms section ({style})"
    table = _words(path, rows, first, width, where)
    at = {name: k for k, name in enumerate(cols)}

    def col(name: str, dtype: Any = np.float64) -> np.ndarray:
        return _as(path, table[:, at[name]], dtype, name, where, first)

    ids, types = col("id", np.int64), col("type", np.int64)
    if types.size and (types.min() < 1 or types.max() > ntypes):
        bad = int(np.argmax((types < 1) | (types > ntypes)))
        raise fail(path, f"line {first + bad}: atom type {int(types[bad])} is invalid: the header announces {ntypes} atom types (1 to {ntypes})")
    x = np.stack([col(a) for a in "xyz"], axis=1)
    radii = masses = None
    if style == "sphere":
        radii, density = 0.5 * col("diameter"), col("density")
        masses = np.where(radii > 0, 4.0 * math.pi / 3.0 * radii * radii * radii * density, density)
    elif "Masses" in sections:
        masses = _per_type(path, sections["Masses"], ntypes, "Masses")[types - 1]
    names = _type_names(sections, ntypes)
    v = None
    if "Velocities" in sections:
        vfirst, vrows = sections["Velocities"].first, sections["Velocities"].rows
        if len(vrows) != n:
            raise fail(path, f"the Velocities section has {len(vrows)} rows but the header announces {n} atoms")
        vwidth = len(vrows[0].split())
        vtable = _words(path, vrows, vfirst, vwidth, "Velocities section")
        if vwidth < 4:
            raise fail(path, f"line {vfirst}: a Velocities row has {vwidth} values; it needs id vx vy vz")
        vids = _as(path, vtable[:, 0], np.int64, "id", "Velocities section", vfirst)
        order = np.argsort(vids)
        if not np.array_equal(vids[order], np.sort(ids)):
            raise fail(path, "the Velocities section's ids are not those of the Atoms section")
        v = np.empty((n, 3))
        v[np.argsort(ids)] = _as(path, vtable[:, 1:4], np.float64, "vx vy vz", "Velocities section", vfirst)[order]
    step = re.search(r"\btimestep\s*=\s*([0-9]+)", title)
    frame = RawFrame(
        positions=x,
        where="Atoms section",
        ids=_atom_ids(path, ids, first, where),  # LAMMPS's ids from 1, kinema's from 0 (the dump export writes id + 1)
        velocities=v,
        masses=masses,
        radii=radii,
        species=names[types - 1].astype(object),
        time=None,
        step=int(step[1]) if step else 0,
        box=box,
    )
    # the writer, where the title names it: ASE's "(written by ASE)", "LAMMPS data file via write_data, version ...",
    # "LAMMPS data file via MDAnalysis", "# LAMMPS data file written by OVITO Pro 3.17.2"
    named = re.search(r"\bvia (.+?)(?:,|$)|written by (.+?)\)?$", title.strip())
    creator = None if named is None else "LAMMPS" if named[1] == "write_data" else (named[1] or named[2]).strip()
    return assemble(path, [frame], scale, creator=creator)


def _per_type(path: Path, section: _Section, ntypes: int, name: str) -> np.ndarray:
    """A section of one value per atom type (rows `type value`), as (ntypes,)."""
    table = _words(path, section.rows, section.first, 2, f"{name} section")
    types = _as(path, table[:, 0], np.int64, "type", f"{name} section", section.first)
    values = _as(path, table[:, 1], np.float64, name, f"{name} section", section.first)
    ok = (types >= 1) & (types <= ntypes)
    if not ok.all():
        raise fail(path, f"{name} section: type {int(types[np.argmin(ok)])} is invalid: the header announces {ntypes} atom types")
    out = np.full(ntypes, np.nan)
    out[types - 1] = values
    if np.isnan(out).any():
        raise fail(path, f"{name} section: atom type {int(np.argmax(np.isnan(out))) + 1} has no value")
    return out


def _type_names(sections: dict[str, _Section], ntypes: int) -> np.ndarray:
    """Each type's name: `Atom Type Labels`, else the `Masses` comments where every type
    has one word, else the type's number."""
    names = np.array([str(k + 1) for k in range(ntypes)], dtype=object)
    if "Atom Type Labels" in sections:
        for row in sections["Atom Type Labels"].rows:
            words = row.split()
            if len(words) == 2 and words[0].isdigit() and 1 <= int(words[0]) <= ntypes:
                names[int(words[0]) - 1] = words[1]
        return names
    if "Masses" in sections:
        found = {}
        for raw in sections["Masses"].raw:
            body, _, comment = raw.partition("#")
            words, label = body.split(), comment.strip()
            if words and words[0].isdigit() and re.fullmatch(SPECIES_PATTERN, label):
                found[int(words[0])] = label
        if sorted(found) == list(range(1, ntypes + 1)):
            for t, label in found.items():
                names[t - 1] = label
    return names
