"""What kinema's readers of LAMMPS's text files share (`kinema.io.read_lammps`: `read_dump`
and `read_data`): the file's text (`_text`), its units as the file states them or as given
(`_unit_scales`), rows of words of a known width (`_words`) parsed exactly into numbers,
naming the line of a bad one (`_as`), LAMMPS's atom ids (`_atom_ids`: from 1) as kinema's,
and a box of edge vectors along the axes (`_axis_box`)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ._assemble import Box
from ._h5md_checks import fail
from .units import NAMES, Scales, scales


def _text(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError as e:
        raise fail(path, f"not a text file ({e.reason} at byte {e.start}), so not a LAMMPS file") from None


def _unit_scales(path: Path, stated: str | None, units: Any, how: str) -> Scales:
    """The units of a LAMMPS file: its own `stated` style (`how` it says it), which a
    `units` argument must not contradict, else `units`; neither is refused."""
    if stated is not None and stated.lower() == "lj":
        # LAMMPS's reduced units (σ, τ, m): the file cannot say them, the caller gives their SI values
        if units is None or isinstance(units, str):
            given = "" if units is None else f", not units = {units!r}"
            raise fail(
                path,
                f"the file says its units are 'lj' ({how}), LAMMPS's reduced units (σ, τ, m); give units = {{length = m, time = s, mass = kg}} (--units length=M,time=S,mass=KG), their SI values{given}",
            )
        return scales(units, "units")
    if stated is not None:
        try:
            own = scales(stated, f"{path}: {how}")
        except ValueError as e:
            raise fail(path, str(e).split(": ", 1)[1]) from None
        if units is not None and scales(units, "units") != own:
            raise fail(path, f"the file says its units are {stated!r} ({how}), which units = {units!r} contradicts")
        return own
    if units is None:
        raise fail(
            path,
            f"a LAMMPS file that does not say its units ({how} is missing); give units= (--units) one of {', '.join(repr(n) for n in NAMES if n != 'ase')}, "
            "or {length = m, time = s, mass = kg} for lj (kinema's own dumps are 'si')",
        )
    return scales(units, "units")


def _words(path: Path, lines: list[str], first: int, width: int, where: str) -> np.ndarray:
    """The rows `lines` (the first at line `first`, counting from 1) as an (n, `width`)
    array of words; a row of another width is refused, naming its line."""
    words = " ".join(lines).split()
    if len(words) != len(lines) * width:
        for r, line in enumerate(lines):
            if len(line.split()) != width:
                raise fail(path, f"{where}, line {first + r}: {len(line.split())} values, but {width} columns were announced")
    return np.array(words, dtype=str).reshape(len(lines), width)


def _as(path: Path, words: np.ndarray, dtype: Any, name: str, where: str, first: int) -> np.ndarray:
    try:
        return words.astype(dtype)
    except OverflowError:  # an integer beyond int64
        for r, w in enumerate(words.reshape(len(words), -1)):
            for v in w:
                if not _INT64[0] <= int(v) <= _INT64[1]:
                    raise fail(path, f"{where}, line {first + r}: column {name!r} has {str(v)[:40]}, beyond int64 ({_INT64[0]} to {_INT64[1]})") from None
        raise
    except ValueError:
        kind = int if dtype is np.int64 else float
        for r, w in enumerate(words.reshape(len(words), -1)):
            for v in w:
                try:
                    kind(v)
                except ValueError:
                    raise fail(path, f"{where}, line {first + r}: column {name!r} has {str(v)!r}, not {'an integer' if kind is int else 'a number'}") from None
        raise


_INT64 = (-(2**63), 2**63 - 1)


def _atom_ids(path: Path, ids: np.ndarray, first: int, where: str) -> np.ndarray:
    """LAMMPS's atom ids, which are >= 1 (LAMMPS refuses a data file with id 0 or below:
    "Invalid atom ID in Atoms section of data file"; OVITO writes id 0): one below is refused,
    naming its line. Returns kinema's ids, id − 1."""
    if ids.size and ids.min() < 1:
        bad = int(np.argmax(ids < 1))
        raise fail(
            path,
            f"{where}, line {first + bad}: atom id {int(ids[bad])} is invalid: LAMMPS's atom ids are integers >= 1 (LAMMPS refuses id {int(ids[bad])} too)",
        )
    return ids - 1


def _axis_box(path: Path, vectors: np.ndarray, origin: np.ndarray, periodic: np.ndarray, where: str) -> Box:
    """The box of edge vectors `vectors` (3, 3) (rows a, b, c) from `origin`: they must lie
    along x, y and z (kinema's box is axis-aligned)."""
    if np.any(vectors[~np.eye(3, dtype=bool)] != 0) or np.any(np.diag(vectors) <= 0):
        raise fail(path, f"{where}: a box of edge vectors {vectors.tolist()}; kinema reads boxes along the axes only (a along x, b along y, c along z)")
    return Box(origin.copy(), origin + np.diag(vectors), periodic)
