"""The contact table the analysis reads: K contacts as a dict of arrays, checked once, and
the same table built from the particles' geometry alone where no contacts were recorded.

The table is ``World.contacts()``'s (the force models and the impulse model alike):

========== ======= ===== ============================================================
key        shape   unit  meaning
========== ======= ===== ============================================================
i          (K,)          the particle (an index into the positions)
j          (K,)          the partner particle, −1 against a collider
collider   (K,)          the collider's index (``World.colliders``), −1 between particles
normal     (K, 3)        unit normal, from the partner towards i
overlap    (K,)    m     r_i + r_j − |x_i − x_j| (against a collider: the penetration)
point      (K, 3)  m     the contact point
force_n    (K, 3)  N     the normal force on i (the impulse model: the step's mean)
force_t    (K, 3)  N     the tangential (friction) force on i
sliding    (K,)          whether the contact slides (Coulomb's limit reached)
u_n        (K,)    m/s   (v_i − v_j)·n when the contact was found (< 0: approaching)
impulse_n  (K, 3)  N·s   the impulse model only: the normal impulse on i
impulse_t  (K, 3)  N·s   the impulse model only: the tangential impulse on i
========== ======= ===== ============================================================

Each pair of particles is listed once (i, j) with the forces on i; the forces on j are
their negatives (action and reaction). The analysis functions read only the keys they
need, through :func:`contact_table`."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from .. import _checks
from ._neighbours import near

# key: (the shape after K, the kind of values, what it is), in the order of the table above
FIELDS: dict[str, tuple[tuple[int, ...], str, str]] = {
    "i": ((), "index", "the particle"),
    "j": ((), "index", "the partner particle, -1 against a collider"),
    "collider": ((), "index", "the collider's index, -1 between particles"),
    "normal": ((3,), "real", "the unit normal from the partner towards i"),
    "overlap": ((), "real", "the overlap, m"),
    "point": ((3,), "real", "the contact point, m"),
    "force_n": ((3,), "real", "the normal force on i, N"),
    "force_t": ((3,), "real", "the tangential force on i, N"),
    "sliding": ((), "bool", "whether the contact slides"),
    "impulse_n": ((3,), "real", "the normal impulse on i, N·s"),
    "impulse_t": ((3,), "real", "the tangential impulse on i, N·s"),
}


def contact_table(contacts: Any, n: int | None = None, need: tuple[str, ...] = (), what: str = "this measure") -> dict[str, np.ndarray]:
    """The keys ``need`` of the contact table ``contacts`` (a mapping of arrays, as
    ``World.contacts()`` returns), checked: each present, of one length K, of the shape
    and kind of :data:`FIELDS`, the indices valid (0 ≤ i < ``n``, −1 ≤ j < ``n``, j ≠ i,
    and a contact is either between particles, j ≥ 0 and collider = −1, or against a
    collider, j = −1 and collider ≥ 0) and the reals finite. ``i``, ``j`` and ``collider``
    are always checked (and returned). A ``ValueError`` or ``TypeError`` names the key, the
    value and what is allowed; ``what`` names the measure that needs a missing key."""
    if not isinstance(contacts, Mapping):
        raise TypeError(
            f"contacts = {_checks.describe(contacts)} is invalid: it must be a dict of arrays (K contacts) as World.contacts() returns, not {type(contacts).__name__}"
        )
    keys = ["i", "j", "collider", *[k for k in need if k not in ("i", "j", "collider")]]
    missing = [k for k in keys if k not in contacts]
    if missing:
        have = ", ".join(repr(k) for k in contacts) or "none"
        wanted = "; ".join(f"{k!r}: {FIELDS[k][2]}, shape {'(K, 3)' if FIELDS[k][0] else '(K,)'}" for k in missing)
        raise ValueError(f"contacts has no {', '.join(repr(k) for k in missing)} (it has {have}): {what} needs {wanted}")
    out: dict[str, np.ndarray] = {}
    length: int | None = None
    for key in keys:
        shape, kind, _ = FIELDS[key]
        name = f"contacts[{key!r}]"
        value = contacts[key]
        if kind == "real":
            arr = _checks.real_array(name, value)
        elif kind == "bool":
            arr = np.asarray(value)
            if arr.dtype != np.bool_:
                raise TypeError(f"{name} = {_checks.describe(value)} is invalid: it must be a bool array")
        else:
            arr = np.asarray(value)
            if arr.dtype.kind not in "iu":
                raise TypeError(f"{name} = {_checks.describe(value)} is invalid: indices must be integers, not {arr.dtype}")
            arr = arr.astype(np.int64, copy=False)
        if length is None:
            length = arr.shape[0] if arr.ndim else -1
        _checks.check_shape(name, arr, (length, *shape))
        if kind == "real" and not np.isfinite(arr).all():
            k = np.argwhere(~np.isfinite(arr))[0]
            raise ValueError(f"{name}{''.join(f'[{x}]' for x in k)} = {arr[tuple(k)]} is invalid: it must be finite")
        out[key] = arr
    _check_indices(out, n)
    return out


def _check_indices(c: dict[str, np.ndarray], n: int | None) -> None:
    """The index rules of :func:`contact_table`, each failure naming the first bad contact."""
    i, j, col = c["i"], c["j"], c["collider"]
    rules = [
        (i < 0, "i", i, "a particle index must be >= 0"),
        (j < -1, "j", j, "the partner must be a particle index or -1 (a collider)"),
        (j == i, "j", j, "a particle cannot touch itself (j == i)"),
        (col < -1, "collider", col, "a collider index must be >= 0, or -1 between particles"),
        ((j >= 0) == (col >= 0), "collider", col, "a contact is between particles (j >= 0, collider = -1) or against a collider (j = -1, collider >= 0)"),
    ]
    if n is not None:
        rules[1:1] = [
            (i >= n, "i", i, f"there are {n} particles (indices 0..{n - 1})"),
            (j >= n, "j", j, f"there are {n} particles (indices 0..{n - 1}, or -1)"),
        ]
    for bad, key, arr, allowed in rules:
        if bad.any():
            k = int(np.argmax(bad))
            raise ValueError(f"contacts[{key!r}][{k}] = {int(arr[k])} is invalid: {allowed}")


def pair_mask(c: dict[str, np.ndarray]) -> np.ndarray:
    """(K,) bool: the contacts between two particles (the rest are against colliders)."""
    return c["j"] >= 0


def geometric_contacts(positions: Any, radii: Any, *, gap: float = 0.0, period: Any = None) -> dict[str, np.ndarray]:
    """The pairs of particles that touch, from their positions (N, 3) m and radii (N,) m
    alone: |x_i − x_j| ≤ r_i + r_j + ``gap`` (m, ≥ 0: how far apart two particles may be and
    still count, for a packing whose contacts are not exactly closed). For a trajectory
    that recorded no contacts; it knows no forces, so a measure that needs them refuses
    this table, and those that count force-carrying contacts count every pair here.

    ``period`` (3,) m: the cell's length along each periodic axis, 0 along the others (the
    minimum image is used along periodic axes; ``Snapshot.period``). Each pair is listed once,
    i < j (by the image nearest to i): ``i``, ``j``, ``collider`` (−1), ``normal`` (from j
    towards i), ``overlap`` (m, negative within the gap) and ``point`` (m, the middle of the
    overlap, x_j + (r_j − δ/2) n, by the image of j nearest to i).

    Cells of side 2 max(r) + gap find the candidates (a particle's neighbours lie in its own
    cell and the 26 around it), so the work grows as N, not N²."""
    x = _checks.real_array("positions", positions)
    _checks.check_shape("positions", x, (None, 3))
    r = _checks.broadcast("radii", _checks.real_array("radii", radii), (len(x),), f"one radius or one per particle, ({len(x)},)")
    gap = _checks.real("gap", gap)
    if not (np.isfinite(gap) and gap >= 0):
        raise ValueError(f"gap = {gap!r} is invalid: it must be a finite distance >= 0 (m)")
    if not np.isfinite(x).all():
        raise ValueError("positions hold NaN or inf: give the positions of the particles alive (Snapshot.of_frame keeps only those)")
    if (r < 0).any() or not np.isfinite(r).all():
        raise ValueError(f"radii = {_checks.describe(r)} is invalid: radii must be finite and >= 0 (m)")
    cell = periodic_lengths(period)
    reach = 2 * float(r.max(initial=0.0)) + gap
    pi, pj = _candidate_pairs(x, cell, reach)
    d = minimum_image(x[pi] - x[pj], cell)
    dist = np.linalg.norm(d, axis=1)
    touch = dist <= r[pi] + r[pj] + gap
    pi, pj, d, dist = pi[touch], pj[touch], d[touch], dist[touch]
    if (dist == 0).any():
        k = int(np.argmax(dist == 0))
        raise ValueError(f"positions[{pi[k]}] and positions[{pj[k]}] are the same point: two particles at one place have no normal")
    n = d / dist[:, None]
    overlap = r[pi] + r[pj] - dist
    point = x[pi] - d + (r[pj] - overlap / 2)[:, None] * n
    order = np.lexsort((pj, pi))
    return {
        "i": pi[order],
        "j": pj[order],
        "collider": np.full(len(pi), -1, dtype=np.int64),
        "normal": n[order],
        "overlap": overlap[order],
        "point": point[order],
    }


def periodic_lengths(period: Any) -> np.ndarray:
    """``period`` as (3,) m, 0 along non-periodic axes (None: none periodic)."""
    if period is None:
        return np.zeros(3)
    cell = _checks.real_array("period", period).reshape(-1)
    if cell.shape != (3,) or not (np.isfinite(cell).all() and (cell >= 0).all()):
        raise ValueError(
            f"period = {_checks.describe(period)} is invalid: give the cell's length along x, y, z (m, >= 0; 0 along an axis that is not periodic)"
        )
    return cell


def minimum_image(d: np.ndarray, cell: np.ndarray) -> np.ndarray:
    """The displacements ``d`` (..., 3) m by their nearest periodic image along the axes
    where ``cell`` > 0: d − L round(d / L)."""
    if not cell.any():
        return d
    L = np.where(cell > 0, cell, 1.0)
    return np.where(cell > 0, d - L * np.round(d / L), d)


def _candidate_pairs(x: np.ndarray, cell: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """Pairs (i < j) that may lie within ``reach`` (m), each once."""
    if len(x) < 2 or reach <= 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    i, j = near(x, x, reach, cell)
    keep = i < j
    return i[keep], j[keep]
