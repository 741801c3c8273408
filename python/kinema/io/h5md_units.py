"""The units of H5MD files (the H5MD units module): `parse_unit` reads a unit string into
its exact SI factor and its dimension, `to_si` converts values read from a file to SI
(m, s, kg, J, m/s, kg m/s) and `from_si` values to write to a file's units; `SYSTEMS`,
the unit systems `save_h5md` writes; `assumed_unit`, what a dataset without a unit is
taken in."""

from __future__ import annotations

import re
from fractions import Fraction
from typing import Any

import numpy as np

from .units import ASE

# A unit string of the H5MD units module is space-separated factors: at most one number first
# ("60", "10+3" = 10^3) and unit symbols, each with an optional SI prefix and an integer power
# ("nm", "ps-1", "m2"). A dimension is the powers of (length, time, mass). A mole is a number,
# Avogadro's: "kJ mol-1" is an energy per particle and "g mol-1" a particle's mass (1 u), as
# molecular-dynamics programs mean them. "A" is the ångström (as MDAnalysis reads it), not
# the ampere, which no quantity kinema reads involves.
LENGTH, TIME, MASS = (1, 0, 0), (0, 1, 0), (0, 0, 1)  # the dimensions of m, s and kg
_ANGSTROM = (Fraction(1, 10**10), LENGTH)
_DALTON = (Fraction("1.66053906660e-27"), MASS)  # kg, CODATA 2018
_ENERGY = (2, -2, 1)
_SYMBOLS: dict[str, tuple[Fraction, tuple[int, int, int]]] = {
    "m": (Fraction(1), LENGTH),
    "Ang": _ANGSTROM,
    "\u00c5": _ANGSTROM,  # Å
    "\u212b": _ANGSTROM,  # the ångström sign
    "Angstrom": _ANGSTROM,
    "angstrom": _ANGSTROM,
    "A": _ANGSTROM,
    "s": (Fraction(1), TIME),
    "g": (Fraction(1, 1000), MASS),
    "u": _DALTON,
    "Da": _DALTON,
    "amu": _DALTON,
    "J": (Fraction(1), _ENERGY),
    "eV": (Fraction("1.602176634e-19"), _ENERGY),
    "cal": (Fraction("4.1868"), _ENERGY),
    "erg": (Fraction(1, 10**7), _ENERGY),
    "N": (Fraction(1), (1, -2, 1)),
    "Pa": (Fraction(1), (-1, -2, 1)),
    "Hz": (Fraction(1), (0, -1, 0)),
    "mol": (Fraction("6.02214076e23"), (0, 0, 0)),
}
_PREFIXES = {"E": 18, "P": 15, "T": 12, "G": 9, "M": 6, "k": 3, "h": 2, "da": 1, "d": -1, "c": -2, "m": -3, "u": -6, "\u00b5": -6, "\u03bc": -6}
_PREFIXES.update({"n": -9, "p": -12, "f": -15, "a": -18})
# a dimension in words, with its SI unit, as a reader's message names it
QUANTITY = {
    LENGTH: "a length (m)",
    TIME: "a time (s)",
    MASS: "a mass (kg)",
    (1, -1, 0): "a velocity (m s-1)",
    _ENERGY: "an energy (J)",
    (1, -1, 1): "a momentum (kg m s-1)",
    (2, -1, 1): "an angular momentum (kg m2 s-1)",
    (-1, -2, 1): "a pressure (Pa)",
    (0, -2, 1): "a pressure of a 2D world, a force per length (N m-1)",
    (0, -1, 0): "an angular velocity (s-1, rad/s)",
    (1, -2, 1): "a force (N)",
    (2, 0, 1): "a moment of inertia (kg m2)",
}


def _symbol(token: str) -> tuple[Fraction, tuple[int, int, int]] | None:
    if token in _SYMBOLS:
        return _SYMBOLS[token]
    for prefix in sorted(_PREFIXES, key=len, reverse=True):
        if token.startswith(prefix) and token[len(prefix) :] in _SYMBOLS:
            factor, dims = _SYMBOLS[token[len(prefix) :]]
            return factor * Fraction(10) ** _PREFIXES[prefix], dims
    return None


def parse_unit(text: str) -> tuple[Fraction, tuple[int, int, int]]:
    """The SI factor (exact) and the dimension (powers of length, time, mass) of an H5MD unit
    string: `parse_unit("nm ps-1") == (Fraction(1000), (1, -1, 0))`. Raises `ValueError`
    saying which factor it does not know."""
    tokens = text.split()
    if not tokens:
        raise ValueError("it is empty")
    if len(text) > 200:
        raise ValueError("it is over 200 characters long")
    factor, dims = Fraction(1), [0, 0, 0]
    for k, token in enumerate(tokens):
        number = re.fullmatch(r"([0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:([+-][0-9]{1,3})|[eE]([+-]?[0-9]{1,3}))?", token)
        if number:
            if k:
                raise ValueError(f"the number {token!r} is not the first factor")
            value = Fraction(number.group(1))
            if value == 0:
                raise ValueError("its number is 0")
            if number.group(2):
                value = value ** int(number.group(2))
            elif number.group(3):
                value = value * Fraction(10) ** int(number.group(3))
            factor *= value
            continue
        match = re.fullmatch(r"([^\W\d_]+)([+-]?[0-9]{1,2})?", token)
        known = _symbol(match.group(1)) if match else None
        if known is None and "/" in token:
            raise ValueError(f"{token!r}: H5MD writes a unit as space-separated factors with powers ('nm ps-1'), not with '/'")
        if known is None:
            raise ValueError(f"{token!r} is not a unit symbol kinema knows")
        power = int(match.group(2)) if match.group(2) else 1
        factor *= known[0] ** power
        dims = [a + power * b for a, b in zip(dims, known[1], strict=True)]
    return factor, (dims[0], dims[1], dims[2])


def _exact_inverse(factor: Fraction) -> float | None:
    """The integer 1 / `factor` as a float when it is one and float64 holds it exactly (1e9
    for "nm", 1e10 for "Ang"), else `None`."""
    inverse = 1 / factor
    if inverse.denominator != 1 or Fraction(float(inverse)) != inverse:
        return None
    return float(inverse)


def to_si(a: Any, factor: Fraction | float) -> Any:
    """`a` (just read from a file) in SI: times `factor` (in place when it is float64, else
    as float64); `a` itself when the factor is 1. A factor whose inverse float64 holds
    exactly (1e-9 for "nm": 1e9) divides by that inverse instead, so that each value is the
    float64 nearest the exact product (1e-9 itself is not a float64)."""
    if factor == 1:
        return a
    inverse = _exact_inverse(Fraction(factor))
    out = a if isinstance(a, np.ndarray) and a.dtype == np.float64 and a.flags.writeable else np.array(a, dtype=np.float64)
    if inverse is not None:
        out /= inverse
    else:
        out *= float(factor)
    return out


def from_si(a: Any, unit: str) -> np.ndarray:
    """`a` in SI as float64 values in `unit` (`"nm"`: times 1e9), each the float64
    nearest the exact quotient where the factor or its inverse is a float64 (powers of ten up
    to 1e22, 1000 for "nm ps-1"), else within one rounding more; `a` itself (as an array)
    when the factor is 1. NaN stays NaN."""
    factor = parse_unit(unit)[0]
    if factor == 1:
        return np.asarray(a)
    a = np.asarray(a, dtype=np.float64)
    inverse = _exact_inverse(factor)
    if inverse is not None:
        return a * inverse
    return a / float(factor)


# The unit systems save_h5md writes, as the unit of each SI unit kinema's values are in.
# "MD": GROMACS's units (nm, ps, u, kJ mol-1), which MDAnalysis reads (its H5MD reader knows
# the lengths Å, nm, pm, fm and not m), as do VMD and the H5MD readers of the MD codes.
SI_UNITS = ("m", "s", "m s-1", "kg", "J", "kg m s-1", "kg m2 s-1", "Pa", "N m-1", "s-1", "N", "kg m2")
SYSTEMS: dict[str, dict[str, str]] = {
    "SI": {u: u for u in SI_UNITS},
    "MD": {
        "m": "nm",
        "s": "ps",
        "m s-1": "nm ps-1",
        "kg": "u",
        "J": "kJ mol-1",
        "kg m s-1": "u nm ps-1",
        "kg m2 s-1": "u nm2 ps-1",
        "Pa": "kJ mol-1 nm-3",
        "N m-1": "kJ mol-1 nm-2",
        "s-1": "ps-1",
        "N": "kJ mol-1 nm-1",
        "kg m2": "u nm2",
    },
}


def system_of(units: Any) -> dict[str, str]:
    """The units of the unit system named `units` ("SI" or "MD", any case); a `ValueError`
    naming the value and the names allowed."""
    if isinstance(units, str) and units.upper() in SYSTEMS:
        return SYSTEMS[units.upper()]
    raise ValueError(f"units = {units!r} is invalid: use 'SI' (m, s, kg, J) or 'MD' (nm, ps, u, kJ mol-1)")


# The SI unit of each dimension kinema reads, as messages name it.
_SI_OF = {parse_unit(u)[1]: u for u in SI_UNITS}
#: the creator (/h5md/creator name) whose datasets without a unit are in ASE's units: znh5md
#: writes ASE's numbers, and no unit on masses ("Angstrom" on positions and box, "fs" on
#: time where it writes units at all)
ZNH5MD = "znh5md"


def assumed_unit(creator: str | None, dims: tuple[int, int, int]) -> tuple[Fraction, str]:
    """What a dataset of dimension `dims` without a `unit` attribute is taken in, in a file
    `creator` (its /h5md/creator name) wrote, as (the SI factor, the words a warning says):
    ASE's units in znh5md's files (Å, u, fs for time, Å per ASE's time unit Å √(u/eV) for
    velocities), else SI. kinema's own files write a unit on every dataset that has one."""
    si = _SI_OF.get(dims, "SI")
    if creator != ZNH5MD:
        return Fraction(1), f"{si} (SI), which its creator {creator!r} may not mean"
    if dims == TIME:
        return Fraction(1, 10**15), "fs, znh5md's time unit"
    length, time, mass = dims
    factor = Fraction(ASE.length) ** length * Fraction(ASE.time) ** time * Fraction(ASE.mass) ** mass
    words = {LENGTH: "Å", MASS: f"u (ASE's, {ASE.mass} kg)", (1, -1, 0): f"Å per ASE's time unit ({ASE.velocity:.8g} m s-1)"}
    return factor, f"{words.get(dims, 'ASE units')}, as znh5md writes ASE's numbers"
