"""The probability distribution of contact forces, P(f / ⟨f⟩)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import _checks
from .contacts import contact_table

PARTS = ("normal", "tangential", "total")


@dataclass(frozen=True)
class ForceDistribution:
    """What :func:`force_distribution` measured.

    `edges` (B + 1,) and `centers` (B,): the bins of x = f / ⟨f⟩ (dimensionless); `density`
    (B,): P(x), the counts / (K · bin width), so that Σ P Δx is the fraction of the K forces
    inside the bins (1 when the bins hold them all); `counts` (B,) int; `mean` N, ⟨f⟩;
    `forces` (K,) N, the magnitudes counted."""

    edges: np.ndarray
    centers: np.ndarray
    density: np.ndarray
    counts: np.ndarray
    mean: float
    forces: np.ndarray


def force_distribution(contacts: Any, *, bins: Any = 40, part: str = "normal", colliders: bool = False, min_force: float = 0.0) -> ForceDistribution:
    """The histogram of the contact forces' magnitudes f, normalised by their mean: P(f/⟨f⟩)
    (Radjai et al. 1996, Phys. Rev. Lett. 77, 274; Mueth, Jaeger & Nagel 1998, Phys. Rev. E
    57, 3164), whose tail above the mean is close to exp(−β f/⟨f⟩) in static packings.

    ``part``: "normal" (|force_n|), "tangential" (|force_t|) or "total" (|force_n + force_t|),
    N. The contacts between particles count (with colliders too when ``colliders``), those
    with f > ``min_force`` (N, ≥ 0) only. ``bins``: a number of equal bins from 0 to the
    largest f/⟨f⟩, or the edges (increasing, in units of ⟨f⟩)."""
    if part not in PARTS:
        raise ValueError(f"part = {_checks.describe(part)} is invalid: it must be one of {', '.join(map(repr, PARTS))}")
    colliders = _checks.boolean("colliders", colliders)
    min_force = _checks.real("min_force", min_force)
    if not (np.isfinite(min_force) and min_force >= 0):
        raise ValueError(f"min_force = {min_force!r} is invalid: it must be a finite force >= 0 (N)")
    need = {"normal": ("force_n",), "tangential": ("force_t",), "total": ("force_n", "force_t")}[part]
    c = contact_table(contacts, None, need, f"the distribution of {part} forces")
    vec = c["force_n"] if part == "normal" else c["force_t"] if part == "tangential" else c["force_n"] + c["force_t"]
    f = np.linalg.norm(vec, axis=1)
    f = f[((c["j"] >= 0) | colliders) & (f > min_force)]
    if len(f) == 0:
        raise ValueError(f"no contact carries a {part} force above min_force = {min_force!r} N: there is no distribution to measure")
    mean = float(f.mean())
    x = f / mean
    if isinstance(bins, (int, np.integer)) and not isinstance(bins, bool):
        count = _checks.integer("bins", bins, lo=1)
        edges = np.linspace(0.0, float(x.max()), count + 1)
    else:
        edges = _checks.real_array("bins", bins)
        if edges.ndim != 1 or len(edges) < 2 or not (np.isfinite(edges).all() and (np.diff(edges) > 0).all()):
            raise ValueError(f"bins = {_checks.describe(bins)} is invalid: give a number of bins (int >= 1) or >= 2 finite, increasing edges (in units of <f>)")
    counts, _ = np.histogram(x, edges)
    return ForceDistribution(
        edges=edges,
        centers=(edges[1:] + edges[:-1]) / 2,
        density=counts / (len(x) * np.diff(edges)),
        counts=counts,
        mean=mean,
        forces=f,
    )
