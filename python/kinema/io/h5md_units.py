"""The units of H5MD files (the H5MD units module): ``parse_unit`` reads a unit string into
its exact SI factor and its dimension, ``to_si`` converts values read from a file to SI
(m, s, kg, J, m/s, kg m/s)."""

from __future__ import annotations

import re
from fractions import Fraction
from typing import Any

import numpy as np

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
    string: ``parse_unit("nm ps-1") == (Fraction(1000), (1, -1, 0))``. Raises ``ValueError``
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


def to_si(a: Any, factor: float) -> Any:
    """``a`` (just read from a file) in SI: times ``factor`` (in place when it is float64, else
    as float64); ``a`` itself when the factor is 1."""
    if factor == 1.0:
        return a
    if isinstance(a, np.ndarray) and a.dtype == np.float64 and a.flags.writeable:
        a *= factor
        return a
    return np.asarray(a, dtype=np.float64) * factor
