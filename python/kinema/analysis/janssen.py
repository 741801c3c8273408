"""Janssen's silo: the pressure in a column of grains held partly by wall friction, in
closed form, and the wall pressure measured from the contacts with the walls."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import _checks
from .contacts import contact_table


def janssen_pressure(z: Any, rho: float, g: float, D: float, mu_w: float, K: float) -> np.ndarray:
    """The mean vertical stress σ_v (Pa) at depth ``z`` (m, ≥ 0, below the free surface) in
    a silo of diameter ``D`` (m; a non-circular section: 4 area / perimeter) filled with grains
    of bulk density ``rho`` (kg/m³: the grains' density times the packing fraction) under
    gravity ``g`` (m/s²), with wall friction ``mu_w`` and Janssen's ratio ``K`` of horizontal
    to vertical stress (Janssen 1895, Z. Ver. Dtsch. Ing. 39, 1045; Sperl 2006, Granular
    Matter 8, 59):

        σ_v(z) = ρ g D / (4 μ_w K) · (1 − exp(−4 μ_w K z / D)).

    A slice of height dz and section A = π D²/4 carries its weight ρ g A dz less the wall
    friction μ_w K σ_v π D dz, so dσ_v/dz = ρ g − (4 μ_w K / D) σ_v with σ_v(0) = 0: hydrostatic
    (ρ g z) near the top, saturating at ρ g D / (4 μ_w K) below a few D / (4 μ_w K). The
    pressure on the wall is K σ_v (:func:`janssen_wall_pressure`)."""
    z = _checks.real_array("z", z)
    if not (np.isfinite(z).all() and (z >= 0).all()):
        raise ValueError(f"z = {_checks.describe(z)} is invalid: depths must be finite and >= 0 (m, below the free surface)")
    rho, g, D, mu_w, K = (_positive(name, value) for name, value in (("rho", rho), ("g", g), ("D", D), ("mu_w", mu_w), ("K", K)))
    scale = 4 * mu_w * K / D
    return rho * g / scale * -np.expm1(-scale * z)


def janssen_wall_pressure(z: Any, rho: float, g: float, D: float, mu_w: float, K: float) -> np.ndarray:
    """The normal pressure on the silo's wall at depth ``z``, Pa: K σ_v(z)
    (:func:`janssen_pressure`), saturating at ρ g D / (4 μ_w)."""
    return _positive("K", K) * janssen_pressure(z, rho, g, D, mu_w, K)


def _positive(name: str, value: float) -> float:
    v = _checks.real(name, value)
    if not (np.isfinite(v) and v > 0):
        raise ValueError(f"{name} = {v!r} is invalid: it must be finite and > 0")
    return v


@dataclass(frozen=True)
class WallPressure:
    """What :func:`wall_pressure` measured, per band of height.

    `edges` (B + 1,) m and `centers` (B,) m: the bands, along the axis. `pressure` (B,) Pa:
    the normal force the walls took in each band, per wall area (the perimeter times the
    band's height). `shear` (B,) Pa: the force along the axis they took there (friction
    holding the grains up is positive, against gravity if the axis points up), per area.
    `count` (B,): the contacts in each band."""

    edges: np.ndarray
    centers: np.ndarray
    pressure: np.ndarray
    shear: np.ndarray
    count: np.ndarray


def wall_pressure(contacts: Any, colliders: Any, *, edges: Any, perimeter: float, axis: Any = (0.0, 0.0, 1.0)) -> WallPressure:
    """The pressure on walls against height, from a contact table's contacts with the
    colliders ``colliders`` (an index or a list of them, ``World.colliders``' order): each
    contact's normal force on its particle, f_n (N), is pushed back on the wall, and its
    size |f_n| is added to the band [edges[k], edges[k+1]) (m along ``axis``, the silo's
    axis, pointing up) holding the contact point, and divided by the wall's area there: the
    ``perimeter`` (m; π D for a cylinder, the four sides for a square box; in a 2D world the
    number of walls, 2, making the pressure a force per length, N/m) times the band's height. The shear
    is the tangential force on the particles along ``axis``: what the wall's friction holds up.

    Averaged over time it is the Janssen wall pressure K σ_v(depth) of a silo at rest
    (:func:`janssen_wall_pressure`), the depth measured down from the fill's free surface."""
    c = contact_table(contacts, None, ("point", "force_n", "force_t"), "the wall pressure")
    ids = np.atleast_1d(np.asarray(colliders))
    if ids.dtype.kind not in "iu" or ids.ndim != 1 or (ids < 0).any():
        raise ValueError(f"colliders = {_checks.describe(colliders)} is invalid: give a collider's index or a list of them (ints >= 0, World.colliders' order)")
    e = _checks.real_array("edges", edges)
    if e.ndim != 1 or len(e) < 2 or not (np.isfinite(e).all() and (np.diff(e) > 0).all()):
        raise ValueError(f"edges = {_checks.describe(edges)} is invalid: give >= 2 finite, increasing heights (m) along the axis")
    perimeter = _positive("perimeter", perimeter)
    u = _checks.real_array("axis", axis, (3,))
    if not (np.isfinite(u).all() and np.linalg.norm(u) > 0):
        raise ValueError(f"axis = {_checks.describe(axis)} is invalid: it must be a finite, non-zero direction (3,)")
    u = u / np.linalg.norm(u)
    on = np.isin(c["collider"], ids)
    h = c["point"][on] @ u
    band = np.searchsorted(e, h, side="right") - 1
    inside = (band >= 0) & (band < len(e) - 1)
    band = band[inside]
    fn = np.linalg.norm(c["force_n"][on][inside], axis=1)
    ft = c["force_t"][on][inside] @ u
    area = perimeter * np.diff(e)
    B = len(e) - 1
    return WallPressure(
        edges=e,
        centers=(e[1:] + e[:-1]) / 2,
        pressure=np.bincount(band, fn, minlength=B) / area,
        shear=np.bincount(band, ft, minlength=B) / area,
        count=np.bincount(band, minlength=B),
    )
