"""The units of files that do not carry H5MD's: LAMMPS's unit styles, ASE's units, kinema's
own SI, or scales given by the caller; and `UnitWarning`, said when a reader takes a file's
numbers in units the file does not state.

`scales(units, where)` turns a `units=` argument into `Scales`: the SI value of one of
the file's units of length, time, mass and velocity, by which the numbers read are
multiplied."""

from __future__ import annotations

import math
from collections.abc import Mapping
from fractions import Fraction
from typing import Any, NamedTuple


class UnitWarning(UserWarning):
    """A reader took a file's numbers in units the file does not state (a HOOMD GSD file, whose
    format has no units: its numbers taken as SI, its masses as kg). The message names the file
    and the assumption; give `units=` to say what they are."""

    __module__ = "kinema.io"


class Scales(NamedTuple):
    """One of a file's units in SI: `length` m, `time` s, `mass` kg, `velocity` m/s
    (`length / time`, rounded once), and `name`, how messages and docs name the system."""

    length: float
    time: float
    mass: float
    velocity: float
    name: str


def _exact(name: str, length: Fraction, time: Fraction, mass: Fraction) -> Scales:
    return Scales(float(length), float(time), float(mass), float(length / time), name)


# LAMMPS's unit styles by LAMMPS's own constants (src/update.cpp, Update::set_units): the style's
# length is 1e-10 m / force->angstrom, its time 1e-15 s / force->femtosecond, and a gram per mole
# is 1e-3 kg / 6.02214129e23, the Avogadro number of force->mv2d = 1 / 0.602214129 (g/mol per
# Å³ to g/cm³). The velocity is the style's length per its time, as LAMMPS integrates
# (x += dt v, dt in the style's time): for "electron" that is Bohr per fs, the unit its mvv2e =
# 1.06657236 (amu Bohr² fs⁻² in Hartree) is computed for; LAMMPS's units page and ASE's
# unitconvert say Bohr per atomic time unit (1.03275 fs), which LAMMPS's code does not use.
_GRAM_PER_MOLE = Fraction(1, 1000) / Fraction("6.02214129e23")
_ANGSTROM = Fraction(1, 10**10)
_FS = Fraction(1, 10**15)
LAMMPS_STYLES: dict[str, Scales] = {
    "real": _exact("LAMMPS real (Å, fs, g/mol)", _ANGSTROM, _FS, _GRAM_PER_MOLE),
    "metal": _exact("LAMMPS metal (Å, ps, g/mol)", _ANGSTROM, _FS * 1000, _GRAM_PER_MOLE),
    "si": _exact("SI (m, s, kg)", Fraction(1), Fraction(1), Fraction(1)),
    "cgs": _exact("LAMMPS cgs (cm, s, g)", Fraction(1, 100), Fraction(1), Fraction(1, 1000)),
    "electron": _exact("LAMMPS electron (Bohr, fs, amu)", _ANGSTROM / Fraction("1.88972612"), _FS, _GRAM_PER_MOLE),
    "micro": _exact("LAMMPS micro (µm, µs, pg)", Fraction(1, 10**6), Fraction(1, 10**6), Fraction(1, 10**15)),
    "nano": _exact("LAMMPS nano (nm, ns, ag)", Fraction(1, 10**9), Fraction(1, 10**9), Fraction(1, 10**21)),
}

# ASE's units (ase.units, CODATA 2014, ASE's default): Å, the unified atomic mass unit, and
# ASE's time unit Å √(amu/eV), so that a velocity in Å per that unit is √(eV/amu) m/s.
_ASE_AMU = 1.66053904e-27  # kg, ase.units._amu
_ASE_EV = 1.6021766208e-19  # J, ase.units._e
ASE = Scales(1e-10, 1e-10 * math.sqrt(_ASE_AMU / _ASE_EV), _ASE_AMU, math.sqrt(_ASE_EV / _ASE_AMU), "ASE's (Å, amu, Å/(Å √(amu/eV)))")
SI = LAMMPS_STYLES["si"]

#: the names ``units=`` takes (any case): the LAMMPS styles kinema converts, and "ase"
NAMES = (*LAMMPS_STYLES, "ase")
_KEYS = ("length", "time", "mass")


def scales(units: Any, where: str) -> Scales:
    """The `Scales` of a `units=` argument: a name of `NAMES` (`"real"`, `"metal"`,
    `"SI"`, `"ase"`, ...; `"lj"` is refused: its scales are the caller's to give) or a
    mapping {"length": m, "time": s, "mass": kg} of the file's units in SI (each finite and > 0;
    the velocity is length / time). Raises `ValueError` naming `where` (the argument or the
    key) and the value."""
    if isinstance(units, str):
        key = units.lower()
        if key == "ase":
            return ASE
        if key in LAMMPS_STYLES:
            return LAMMPS_STYLES[key]
        if key == "lj":
            raise ValueError(
                f"{where} = 'lj' is invalid: LAMMPS's lj units are reduced (σ, ε, m), so kinema cannot know them; "
                "give units = {length = m, time = s, mass = kg}, the SI value of σ, τ and m"
            )
        raise ValueError(f"{where} = {units!r} is invalid: give one of {', '.join(repr(n) for n in NAMES)} or {{length = m, time = s, mass = kg}}")
    if isinstance(units, Mapping):
        if sorted(units) != sorted(_KEYS):
            raise ValueError(f"{where} = {dict(units)!r} is invalid: a table of scales has exactly the keys length (m), time (s) and mass (kg)")
        values = {}
        for k in _KEYS:
            v = units[k]
            if isinstance(v, bool) or not isinstance(v, int | float) or not (math.isfinite(v) and v > 0):
                raise ValueError(f"{where}.{k} = {v!r} is invalid: it must be a finite number > 0, the file's unit of {k} in SI")
            values[k] = float(v)
        velocity = values["length"] / values["time"]
        if not (math.isfinite(velocity) and velocity > 0):
            raise ValueError(f"{where} = {dict(units)!r} is invalid: length / time = {velocity!r} is not a finite velocity > 0")
        name = f"scales (length {values['length']!r} m, time {values['time']!r} s, mass {values['mass']!r} kg)"
        return Scales(values["length"], values["time"], values["mass"], velocity, name)
    raise ValueError(f"{where} = {units!r} is invalid: give one of {', '.join(repr(n) for n in NAMES)} or {{length = m, time = s, mass = kg}}")
