"""The fabric tensor: the mean orientation of the contacts, and how far from isotropic it is."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import _checks
from .contacts import contact_table


@dataclass(frozen=True)
class Fabric:
    """What :func:`fabric` measured, in the world's d dimensions.

    `tensor` (d, d): F = (1/N_c) Σ_c n_c ⊗ n_c, trace 1, I/d for isotropic contacts.
    `deviator` (d, d): F − I/d. `anisotropy_tensor` (d, d): a = d(d + 2)/2 (F − I/d), the
    coefficients of the contact normals' density to second order (see :func:`fabric`).
    `anisotropy`: its size, √(a:a / 2) in 2D (Rothenburg and Bathurst's a) and √(3/2 a:a) in
    3D (a_zz − a_xx for an axisymmetric a). `count`: N_c, the contacts averaged over."""

    tensor: np.ndarray
    deviator: np.ndarray
    anisotropy_tensor: np.ndarray
    anisotropy: float
    count: int

    @property
    def eigenvalues(self) -> np.ndarray:
        """F's eigenvalues, largest first (each in [0, 1], summing to 1)."""
        return np.linalg.eigvalsh(self.tensor)[::-1]


def fabric(contacts: Any, *, dim: int = 3, colliders: bool = False, min_force: float | None = 0.0) -> Fabric:
    """The fabric tensor of a contact table (:mod:`kinema.analysis.contacts`),

        F_ab = (1/N_c) Σ_c n_a n_b,

    over the contacts between particles (and with colliders when ``colliders``), n the unit
    normal, its first ``dim`` components (in a 2D world, x and y). Each pair is one contact
    (n and −n give the same n ⊗ n). Contacts count when |``force_n``| > ``min_force`` (N);
    ``min_force=None`` counts every contact listed (the table needs no ``force_n`` then).

    The anisotropy (Rothenburg & Bathurst 1989, Géotechnique 39, 601, in 2D; Ouadfel &
    Rothenburg 2001, Mech. Mater. 33, 201, in 3D): the density of contact normals over the
    unit sphere, to second order, is E(n) = (1 + a_ab n_a n_b) / |S^(d−1)| with a traceless.
    Its second moment is F = I/d + 2 a / (d(d + 2)), because ⟨n_a n_b n_c n_d⟩ over the
    sphere is (δ_ab δ_cd + δ_ac δ_bd + δ_ad δ_bc) / (d(d + 2)); so a = d(d + 2)/2 (F − I/d):
    4 F' in 2D, where E = (1 + a cos 2(θ − θ_a)) / 2π, and 15/2 F' in 3D."""
    dim = _checks.integer("dim", dim, lo=2, hi=3)
    colliders = _checks.boolean("colliders", colliders)
    need: tuple[str, ...] = ("normal",)
    if min_force is not None:
        min_force = _checks.real("min_force", min_force)
        if not (np.isfinite(min_force) and min_force >= 0):
            raise ValueError(f"min_force = {min_force!r} is invalid: it must be a finite force >= 0 (N), or None to count every contact")
        need += ("force_n",)
    c = contact_table(contacts, None, need, "the fabric tensor (min_force=None counts contacts without forces)")
    keep = (c["j"] >= 0) | colliders
    if min_force is not None:
        keep &= np.linalg.norm(c["force_n"], axis=1) > min_force
    n = c["normal"][keep, :dim]
    if len(n) == 0:
        raise ValueError("the contact table has no contact to average over (after min_force and colliders): the fabric of no contacts is undefined")
    length = np.linalg.norm(n, axis=1)
    if dim == 2 and np.abs(c["normal"][keep, 2]).max() > 1e-9:
        raise ValueError("contacts['normal'] has a z component: dim=2 reads x and y only (a 2D world's normals lie in the plane); give dim=3")
    if np.abs(length - 1).max() > 1e-6:
        k = int(np.argmax(np.abs(length - 1)))
        raise ValueError(f"contacts['normal'] has a normal of length {length[k]:.6g} (contact {int(np.flatnonzero(keep)[k])}): normals must be unit vectors")
    F = n.T @ n / len(n)
    dev = F - np.eye(dim) / dim
    a = dim * (dim + 2) / 2 * dev
    size = np.sqrt(np.sum(a * a) / 2) if dim == 2 else np.sqrt(1.5 * np.sum(a * a))
    return Fabric(tensor=F, deviator=dev, anisotropy_tensor=a, anisotropy=float(size), count=len(n))
