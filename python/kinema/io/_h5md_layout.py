"""What the writer and the reader of kinema's H5MD files share (``kinema.io.h5md``): the
version written, the names and units of the observables, and h5py, imported when a file is
written or read (an optional dependency)."""

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
}
# the group of /observables with one potential energy per force, J
BY_FORCE = "potential_energy_by_force"


def import_h5py() -> Any:
    """The h5py module; an ``ImportError`` that says how to install it when it is missing."""
    try:
        import h5py
    except ImportError:
        raise ImportError("H5MD files need h5py: pip install h5py") from None
    return h5py
