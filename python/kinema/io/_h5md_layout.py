"""What the writer and the reader of kinema's H5MD files share (`kinema.io.h5md`): the
version written, the names and units of the observables, the chemical symbols (species
written as atomic numbers), and h5py, imported when a file is written or read (an optional
dependency)."""

from __future__ import annotations

from typing import Any

H5MD_VERSION = (1, 1)

# name in /observables: (attribute of the trajectory, unit or None for a plain number)
OBSERVABLES = {
    "kinetic_energy": ("kinetic", "J"),
    "momentum": ("momentum", "kg m s-1"),
    "angular_momentum": ("angular_momentum", "kg m2 s-1"),
    "contacts": ("contacts", None),
    "impulse_balance": ("impulse_balance", "kg m s-1"),
    "collision_energy_lost": ("collision_energy_lost", "J"),
    "impacts": ("impacts", None),
}
# /observables/pressure: the pressure tensor per frame (F, 3, 3), by the world's dimension:
# Pa in 3D, a force per length in 2D
PRESSURE_UNIT = {3: "Pa", 2: "N m-1"}
# the group of /observables with one potential energy per force, J
BY_FORCE = "potential_energy_by_force"
# /observables with a row per collider, value (F, K, 3): what the particles had given each of
# the world's K colliders by each frame (World.collider_books: its momentum and the parts
# along and across the contacts' normals), N s, row k the collider /parameters/kinema/colliders/k
COLLIDER_OBSERVABLES = {
    "collider_momentum": ("collider_momentum", "kg m s-1"),
    "collider_normal": ("collider_normal", "kg m s-1"),
    "collider_tangential": ("collider_tangential", "kg m s-1"),
}

# The chemical symbols by atomic number (IUPAC, 1 to 118); 0 is "X", no element (as ASE has it).
# A species named by one is written as its atomic number, which ASE (znh5md) reads as that element.
ELEMENTS = tuple(
    """X H He Li Be B C N O F Ne Na Mg Al Si P S Cl Ar K Ca Sc Ti V Cr Mn Fe Co Ni Cu Zn Ga Ge As Se
    Br Kr Rb Sr Y Zr Nb Mo Tc Ru Rh Pd Ag Cd In Sn Sb Te I Xe Cs Ba La Ce Pr Nd Pm Sm Eu Gd Tb Dy Ho
    Er Tm Yb Lu Hf Ta W Re Os Ir Pt Au Hg Tl Pb Bi Po At Rn Fr Ra Ac Th Pa U Np Pu Am Cm Bk Cf Es Fm
    Md No Lr Rf Db Sg Bh Hs Mt Ds Rg Cn Nh Fl Mc Lv Ts Og""".split()
)


def import_h5py() -> Any:
    """The h5py module; an `ImportError` that says how to install it when it is missing."""
    try:
        import h5py
    except ImportError:
        raise ImportError("H5MD files need h5py: pip install h5py") from None
    return h5py
