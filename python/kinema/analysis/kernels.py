"""Coarse-graining kernels (MercuryCG's): a Gaussian cut at three widths and Lucy's
polynomial, each normalised in 1, 2 or 3 dimensions, with the 1D integrals that make slab
averages exact.

A kernel ψ(r) ≥ 0 vanishes beyond its ``cutoff`` c and integrates to 1 over the space it is
used in: ∫ ψ d^D r = 1 with D = 1 for slabs (ψ of the distance along one axis, the others
averaged over), D = 2 or 3 on a grid of a 2D or 3D world. For slabs it also gives

    Ψ(x) = ∫_{−∞}^{x} ψ(ξ) dξ          (0 below −c, 1 above c),
    G(x) = ∫_{−∞}^{x} Ψ(ξ) dξ          (0 below −c, x above c),

from which a slab's average of ψ, and of ψ along a contact's branch, follow in closed form
(``kinema.analysis.fields``). ψ is even, so Ψ(x) − ½ is odd and, on |x| ≤ c,

    G(x) = c/2 + x/2 + K(|x|) − K(c),   K(t) = ∫_0^t (Ψ(ξ) − ½) dξ,

which is 0 at −c and c at c (∫_{−c}^{c} Ψ = c, as Ψ(ξ) + Ψ(−ξ) = 1)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import _checks

_ERF = np.frompyfunc(math.erf, 1, 1)  # NumPy has no erf (SciPy is not a dependency)


def _erf(x: np.ndarray) -> np.ndarray:
    return np.asarray(_ERF(x), dtype=float) if np.size(x) else np.zeros(np.shape(x))


def _positive(name: str, value: float) -> float:
    v = _checks.real(name, value)
    if not (math.isfinite(v) and v > 0):
        raise ValueError(f"{name} = {v!r} is invalid: it must be a finite length > 0 (m)")
    return v


def _check_dims(dims: int) -> None:
    if dims not in (1, 2, 3):
        raise ValueError(f"dims = {dims!r} is invalid: a kernel is normalised in 1, 2 or 3 dimensions")


@dataclass(frozen=True)
class Gaussian:
    """ψ(r) = exp(−r² / 2w²) / Z_D for r < c = 3w, 0 beyond: the Gaussian of standard
    deviation ``width`` w (m), cut at three widths and normalised over the ball it is cut to
    (MercuryCG's "Gaussian"; Weinhart et al. 2012, Granular Matter 14, 289):

        Z_1 = √(2π) w erf(3/√2),
        Z_2 = 2π w² (1 − e^(−9/2)),
        Z_3 = (2π)^(3/2) w³ (erf(3/√2) − 3 √(2/π) e^(−9/2)),

    from ∫_0^c e^(−r²/2w²) r^(D−1) dr with c = 3w (for D = 3 by parts: ∫_0^a u² e^(−u²/2) du
    = √(π/2) erf(a/√2) − a e^(−a²/2)). Its step at the cut is e^(−9/2) ≈ 1.1 % of the peak."""

    width: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "width", _positive("width", self.width))

    @property
    def cutoff(self) -> float:
        """c = 3 w, m."""
        return 3.0 * self.width

    def value(self, r: np.ndarray, dims: int) -> np.ndarray:
        """ψ at the distances ``r`` (m, ≥ 0), normalised in ``dims`` dimensions: 1/m^dims."""
        _check_dims(dims)
        w = self.width
        e3 = math.erf(3 / math.sqrt(2))
        z = {
            1: math.sqrt(2 * math.pi) * w * e3,
            2: 2 * math.pi * w**2 * (1 - math.exp(-4.5)),
            3: (2 * math.pi) ** 1.5 * w**3 * (e3 - 3 * math.sqrt(2 / math.pi) * math.exp(-4.5)),
        }[dims]
        r = np.asarray(r, dtype=float)
        return np.where(r < self.cutoff, np.exp(-(r * r) / (2 * w * w)) / z, 0.0)

    def _half(self, t: np.ndarray) -> np.ndarray:
        """Ψ(t) − ½ for 0 ≤ t ≤ c: erf(t / √2 w) / (2 erf(3/√2))."""
        return _erf(t / (math.sqrt(2) * self.width)) / (2 * math.erf(3 / math.sqrt(2)))

    def _k(self, t: np.ndarray) -> np.ndarray:
        """K(t) = ∫_0^t (Ψ − ½) for 0 ≤ t ≤ c: with s = √2 w, ∫ erf(ξ/s) dξ = ξ erf(ξ/s) +
        (s/√π) e^(−ξ²/s²), so K = (t erf(t/s) + (s/√π)(e^(−t²/s²) − 1)) / (2 erf(3/√2))."""
        s = math.sqrt(2) * self.width
        return (t * _erf(t / s) + s / math.sqrt(math.pi) * (np.exp(-((t / s) ** 2)) - 1)) / (2 * math.erf(3 / math.sqrt(2)))

    def cdf(self, x: np.ndarray) -> np.ndarray:
        """Ψ(x), the 1D kernel's integral from −∞ to ``x`` (m): dimensionless, in [0, 1]."""
        return _cdf(self, x)

    def cdf_integral(self, x: np.ndarray) -> np.ndarray:
        """G(x) = ∫_{−∞}^x Ψ, m."""
        return _cdf_integral(self, x)


@dataclass(frozen=True)
class Lucy:
    """ψ(r) = A_D (1 + 3q)(1 − q)³, q = r/c < 1, 0 beyond: Lucy's polynomial (Lucy 1977,
    Astron. J. 82, 1013; MercuryCG's "Lucy") of support radius ``cutoff`` c (m), smooth to
    its second derivative at the cut (its 1D standard deviation: :attr:`width`). The
    normalisations, from ∫_0^1 (1 + 3q)(1 − q)³ q^(D−1) dq = 2/5, 1/10,
    4/105 for D = 1, 2, 3 (u = 1 − q turns each into a sum of powers of u):

        A_1 = 5 / (4c),  A_2 = 5 / (π c²),  A_3 = 105 / (16 π c³)."""

    cutoff: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "cutoff", _positive("cutoff", self.cutoff))

    @property
    def width(self) -> float:
        """The 1D kernel's standard deviation, m: √(∫ x² ψ dx) = c √(2 A_1 c ∫_0^1 q² p(q) dq)
        = c √(2/21) (p the polynomial; ∫_0^1 q² p = 4/105)."""
        return self.cutoff * math.sqrt(2 / 21)

    def value(self, r: np.ndarray, dims: int) -> np.ndarray:
        """ψ at the distances ``r`` (m, ≥ 0), normalised in ``dims`` dimensions: 1/m^dims."""
        _check_dims(dims)
        c = self.cutoff
        a = {1: 5 / (4 * c), 2: 5 / (math.pi * c**2), 3: 105 / (16 * math.pi * c**3)}[dims]
        q = np.minimum(np.asarray(r, dtype=float) / c, 1.0)
        return a * (1 + 3 * q) * (1 - q) ** 3

    def _half(self, t: np.ndarray) -> np.ndarray:
        """Ψ(t) − ½ = A_1 c P(t/c) for 0 ≤ t ≤ c, P(q) = ∫_0^q (1 − 6u² + 8u³ − 3u⁴) du
        = q − 2q³ + 2q⁴ − 3q⁵/5 (P(1) = 2/5, so Ψ(c) = 1)."""
        q = t / self.cutoff
        return 1.25 * (q - 2 * q**3 + 2 * q**4 - 0.6 * q**5)

    def _k(self, t: np.ndarray) -> np.ndarray:
        """K(t) = A_1 c² Q(t/c), Q(q) = ∫_0^q P = q²/2 − q⁴/2 + 2q⁵/5 − q⁶/10."""
        q = t / self.cutoff
        return 1.25 * self.cutoff * (q**2 / 2 - q**4 / 2 + 0.4 * q**5 - q**6 / 10)

    def cdf(self, x: np.ndarray) -> np.ndarray:
        """Ψ(x), the 1D kernel's integral from −∞ to ``x`` (m): dimensionless, in [0, 1]."""
        return _cdf(self, x)

    def cdf_integral(self, x: np.ndarray) -> np.ndarray:
        """G(x) = ∫_{−∞}^x Ψ, m."""
        return _cdf_integral(self, x)


@dataclass(frozen=True)
class Binning:
    """No smoothing: a slab counts what lies inside it (LAMMPS's ``compute chunk/atom`` bins),
    a particle by its centre and a contact by the part of its branch inside the slab.
    Ψ(x) = 0 for x < 0, ½ at 0, 1 above; G(x) = max(x, 0). Slabs only (it has no point
    values)."""

    cutoff: float = 0.0

    def cdf(self, x: np.ndarray) -> np.ndarray:
        return np.heaviside(np.asarray(x, dtype=float), 0.5)

    def cdf_integral(self, x: np.ndarray) -> np.ndarray:
        return np.maximum(np.asarray(x, dtype=float), 0.0)


Kernel = Gaussian | Lucy | Binning


def _cdf(kernel: Gaussian | Lucy, x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    c = kernel.cutoff
    out = np.where(x >= c, 1.0, 0.0)
    mid = np.abs(x) < c
    out[mid] = 0.5 + np.sign(x[mid]) * kernel._half(np.abs(x[mid]))
    return out


def _cdf_integral(kernel: Gaussian | Lucy, x: np.ndarray) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    c = kernel.cutoff
    out = np.where(x >= c, x, 0.0)
    mid = np.abs(x) < c
    kc = float(kernel._k(np.array(c)))
    out[mid] = c / 2 + x[mid] / 2 + kernel._k(np.abs(x[mid])) - kc
    return out
