"""Coordination numbers: how many force-carrying contacts each particle has, with the
rattlers (particles that carry no load) taken out as the jamming literature does."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import _checks
from .contacts import contact_table


@dataclass(frozen=True)
class Coordination:
    """What :func:`coordination` measured.

    `mean`: Z, the mean number of force-carrying contacts of the particles that are not
    rattlers, among themselves (and with colliders, when counted); NaN when every particle
    is a rattler. `per_particle` (N,) int: each particle's contacts counted the same way (0
    for a rattler). `rattler` (N,) bool. `contacts` (N,) int: each particle's force-carrying
    contacts before any rattler was removed, and `mean_all` their mean over all N (the
    plain Z = 2 C / N, with colliders as counted). `rounds`: the passes the removal took."""

    mean: float
    per_particle: np.ndarray
    rattler: np.ndarray
    contacts: np.ndarray
    mean_all: float
    rounds: int

    @property
    def rattler_fraction(self) -> float:
        """The fraction of the particles that are rattlers."""
        return float(self.rattler.mean()) if len(self.rattler) else float("nan")


def coordination(
    contacts: Any,
    n: int,
    *,
    dim: int = 3,
    colliders: bool = False,
    min_contacts: int | None = None,
    min_force: float = 0.0,
) -> Coordination:
    """The coordination number of ``n`` particles from their contact table (``contacts``,
    :mod:`kinema.analysis.contacts`), rattlers excluded.

    A contact carries force when its normal force exceeds ``min_force`` (N, ≥ 0):
    |``force_n``| > ``min_force``; a table without ``force_n`` (:func:`geometric_contacts`)
    counts every contact it lists. ``colliders``: count contacts with colliders (walls and
    floors) too; they hold a particle like a partner does, but are never removed.

    Rattlers are removed iteratively, as in O'Hern, Silbert, Liu & Nagel (2003, Phys. Rev.
    E 68, 011306) and van Hecke (2010, J. Phys.: Condens. Matter 22, 033101): a
    particle with fewer than ``min_contacts`` force-carrying contacts (default d + 1, the
    fewest that hold a frictionless sphere in d dimensions) is a rattler; its contacts are
    taken from its partners, which may then become rattlers, until none is left. Z is then
    the mean over the rest,

        Z = (2 C_pp + C_w) / N_nr,

    C_pp the contacts between non-rattlers, C_w their contacts with colliders (when
    counted), N_nr the non-rattlers: the "mechanical coordination number" of frictionless
    packings, isostatic at Z = 2d. For frictional packings, where a particle can be held by
    fewer than d + 1 contacts, give ``min_contacts``: Thornton's mechanical coordination
    number (Géotechnique 50, 43 (2000)), Z_m = (2 C − N_1) / (N − N_0 − N_1), drops the
    particles with 0 or 1 contact in one pass; ``min_contacts=2`` is its iterated form."""
    n = _checks.integer("n", n, lo=0)
    dim = _checks.integer("dim", dim, lo=2, hi=3)
    colliders = _checks.boolean("colliders", colliders)
    min_contacts = dim + 1 if min_contacts is None else _checks.integer("min_contacts", min_contacts, lo=0)
    min_force = _checks.real("min_force", min_force)
    if not (np.isfinite(min_force) and min_force >= 0):
        raise ValueError(f"min_force = {min_force!r} is invalid: it must be a finite force >= 0 (N)")
    has_force = isinstance(contacts, Mapping) and "force_n" in contacts
    c = contact_table(contacts, n, ("force_n",) if has_force else (), "the coordination number")
    carries = np.linalg.norm(c["force_n"], axis=1) > min_force if has_force else np.ones(len(c["i"]), dtype=bool)
    pair = carries & (c["j"] >= 0)
    wall = carries & (c["j"] < 0) if colliders else np.zeros_like(carries)
    pi, pj = c["i"][pair], c["j"][pair]
    walls = np.bincount(c["i"][wall], minlength=n)
    raw = np.bincount(pi, minlength=n) + np.bincount(pj, minlength=n) + walls
    rattler = np.zeros(n, dtype=bool)
    rounds = 0
    while True:
        live = ~rattler[pi] & ~rattler[pj]
        z = np.bincount(pi[live], minlength=n) + np.bincount(pj[live], minlength=n) + walls
        new = ~rattler & (z < min_contacts)
        if not new.any():
            break
        rattler |= new
        rounds += 1
    z = np.where(rattler, 0, z)
    mean = float(z[~rattler].mean()) if (~rattler).any() else float("nan")
    return Coordination(
        mean=mean,
        per_particle=z,
        rattler=rattler,
        contacts=raw,
        mean_all=float(raw.mean()) if n else float("nan"),
        rounds=rounds,
    )
