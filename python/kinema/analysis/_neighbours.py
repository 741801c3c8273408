"""Which particles lie near which points: a binned search shared by the contact finder and
the coarse-graining (private)."""

from __future__ import annotations

import numpy as np


def near(points: np.ndarray, x: np.ndarray, reach: float, cell: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Candidate pairs (k, i), point k of ``points`` (M, 3) and particle i of ``x`` (N, 3),
    that may lie within ``reach`` (m): x binned in cells of side ≥ ``reach``, each point
    paired with the particles of its cell and of the 26 around it. ``cell`` (3,) m: the
    periodic length along each axis (0: open), where cells wrap. Each pair once; the caller
    measures the distances (a candidate may be up to 2√3 reach away), by the nearest image."""
    m, n = len(points), len(x)
    if m == 0 or n == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    both = np.concatenate([points, x])
    lo = np.where(cell > 0, 0.0, both.min(axis=0))
    span = np.where(cell > 0, cell, both.max(axis=0) - lo)
    counts = np.clip(np.floor(span / max(reach, 1e-300)), 1, 2**20).astype(np.int64)  # keys < 2^60
    side = np.where(span > 0, span / counts, 1.0)

    def cells(y: np.ndarray) -> np.ndarray:
        c = np.floor((y - lo) / side).astype(np.int64)
        return np.where(cell > 0, np.mod(c, counts), np.clip(c, 0, counts - 1))

    def keys(c: np.ndarray) -> np.ndarray:
        return (c[:, 0] * counts[1] + c[:, 1]) * counts[2] + c[:, 2]

    key = keys(cells(x))
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    cp = cells(points)
    # the neighbour offsets along each axis; where a periodic axis has fewer than 3 cells,
    # −1 and +1 (or all three) name one cell, taken once so that no pair is met twice
    steps = [np.unique(np.mod([-1, 0, 1], counts[a])) if cell[a] > 0 and counts[a] < 3 else np.array([-1, 0, 1]) for a in range(3)]
    found_k, found_i = [], []
    for off in np.array(np.meshgrid(*steps, indexing="ij")).reshape(3, -1).T:
        nb = cp + off
        inside = np.ones(m, dtype=bool)
        for a in range(3):
            if cell[a] > 0:
                nb[:, a] = np.mod(nb[:, a], counts[a])
            else:
                inside &= (nb[:, a] >= 0) & (nb[:, a] < counts[a])
        nkey = keys(nb)
        start = np.searchsorted(sorted_key, nkey, side="left")
        many = np.where(inside, np.searchsorted(sorted_key, nkey, side="right") - start, 0)
        step = np.arange(many.sum()) - np.repeat(np.cumsum(many) - many, many)
        found_k.append(np.repeat(np.arange(m), many))
        found_i.append(order[np.repeat(start, many) + step])
    k, i = np.concatenate(found_k), np.concatenate(found_i)
    return k, i
