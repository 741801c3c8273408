"""Linear stability of a time step on the test equation p' = λp.

A method applied to p' = λp multiplies p by R(z), z = hλ, every step; the step is stable when
|R(z)| ≤ 1. `amplification` evaluates R, `max_step` gives the largest stable h for a λ,
`real_interval` / `imag_interval` the stable stretches of the axes, `segments` the stable set
of a method whose region has no area (Verlet's [−2i, 2i]), and `plot_regions` draws the
regions {z : |R(z)| ≤ 1}, segments included. `max_step_oscillator` gives the stable step of every
method (symplectic ones included) on a damped spring.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

from . import _checks, _core
from .ode import ButcherTableau


class Interval(NamedTuple):
    """A stretch [lo, hi] of an axis of the z = hλ plane (lo = hi = 0: none)."""

    lo: float
    hi: float

    @property
    def empty(self) -> bool:
        """True when only z = 0 is stable on this axis."""
        return self.lo == 0.0 and self.hi == 0.0


def amplification(method: str | ButcherTableau, z: Any) -> np.ndarray:
    """R(z) for every z of a (complex) array; same shape as `z`.

    Explicit Runge-Kutta (any tableau): R(z) = 1 + z bᵀ(I − zA)⁻¹𝟙, a polynomial.
    Implicit Euler: 1/(1 − z). Symplectic Euler and Verlet, which integrate x'' = λ²x only:
    the eigenvalue of larger modulus of the one-step matrix (its modulus is the spectral
    radius), a function of w = z².
    """
    arr = _checks.complex_array("z", z)
    out = _core.amplification(method, np.ascontiguousarray(arr.reshape(arr.shape or (1,))))
    return out.reshape(arr.shape) if arr.shape else out.reshape(())[()]


def max_step(method: str | ButcherTableau, lam: Any) -> Any:
    """Largest h with |R(sλ)| ≤ 1 for all 0 < s ≤ h; elementwise over an array of λ.

    `inf` where no step is too large (e.g. implicit Euler for Re λ ≤ 0), `0` where no
    positive step is stable (e.g. forward Euler on the imaginary axis).
    """
    arr = _checks.complex_array("lam", lam)
    out = _core.max_step(method, np.ascontiguousarray(arr.reshape(arr.shape or (1,))))
    return out.reshape(arr.shape) if arr.shape else float(out[0])


def real_interval(method: str | ButcherTableau) -> Interval:
    """The stable interval of the real axis containing 0 (Euler: [−2, 0])."""
    return Interval(*_core.real_interval(method))


def imag_interval(method: str | ButcherTableau) -> Interval:
    """The stable interval [lo, hi] of the imaginary axis, z = iy (RK4: ±2√2; Euler: none)."""
    return Interval(*_core.imag_interval(method))


def _oscillator_args(omega: float, zeta: float) -> tuple[float, float]:
    omega, zeta = _checks.real("omega", omega), _checks.real("zeta", zeta)
    if not (np.isfinite(omega) and omega > 0):
        raise ValueError(f"omega = {omega} is invalid: the angular frequency must be a finite number > 0 (rad per time unit)")
    if not (np.isfinite(zeta) and zeta >= 0):
        raise ValueError(f"zeta = {zeta} is invalid: the damping ratio must be a finite number >= 0")
    return omega, zeta


def max_step_oscillator(method: str | ButcherTableau, omega: float, zeta: float = 0.0) -> float:
    """Largest stable h on the damped oscillator x'' = −ω²x − 2ζω v (a spring with a dashpot:
    ω² = k/m, 2ζω = c/m), for every method — the symplectic ones included, whose step limit
    with damping is not a function of a single λ.

    It is the largest h with spectral radius ρ(M(s)) ≤ 1 for all 0 < s ≤ h, M the one-step map
    (first-order methods: max |R(hλ±)| over the two eigenvalues λ± = ω(−ζ ± √(ζ² − 1))).
    Undamped it equals the imaginary interval over ω (verlet: 2/ω, rk4: 2√2/ω); damping lowers
    Verlet's (ζ = 0.1: 1.640/ω) and raises forward Euler's from 0 (2ζ/ω).
    """
    omega, zeta = _oscillator_args(omega, zeta)
    return _core.oscillator_max_step(method, omega, zeta)


def oscillator_amplification(method: str | ButcherTableau, h: float, omega: float, zeta: float = 0.0) -> float:
    """Spectral radius of one step of size h on x'' = −ω²x − 2ζω v (≤ 1: stable)."""
    omega, zeta = _oscillator_args(omega, zeta)
    return _core.oscillator_amplification(method, _checks.real("h", h), omega, zeta)


def _name(method: str | ButcherTableau) -> str:
    return method if isinstance(method, str) else method.name


# How far off an axis `segments` looks for stable points (relative to the stretch's length):
# small enough to stay inside any region of positive area that contains the stretch, large
# enough that |R| of a method with a thin stable set (1 + O(δ) off the axis) is > 1 by far
# more than rounding.
_OFF_AXIS = 1e-6


def segments(method: str | ButcherTableau) -> list[tuple[complex, complex]]:
    """The stable set of a method whose stability region has no interior, as (start, end)
    pairs of z: the stretches of the real and imaginary axes where |R(z)| ≤ 1 when no point
    just off them is stable. ``[]`` for a method whose region has an area (it is a filled
    region on a plot).

    Symplectic Euler and Verlet: ``[(-2j, 2j)]``, the segment [−2i, 2i] of the imaginary
    axis (hω ≤ 2 on an undamped oscillator); every z off the axis is unstable (|R| > 1), since
    R is the larger root of μ² − (2 + z²)μ + 1 = 0 and the roots' product is 1. Found from the
    method's own analysis: the axes' stable intervals (`real_interval`, `imag_interval`) and
    `amplification` at points beside them, not from a table of names.
    """
    stretches = []
    for interval, axis, across in ((real_interval(method), 1.0, 1j), (imag_interval(method), 1j, 1.0)):
        if interval.empty:
            continue
        lo, hi = max(interval.lo, -1e3), min(interval.hi, 1e3)  # (implicit Euler's are infinite)
        t = np.linspace(lo, hi, 65)
        delta = _OFF_AXIS * max(1.0, hi - lo)
        beside = np.concatenate([t * axis + delta * across, t * axis - delta * across])
        if np.any(np.abs(amplification(method, beside)) <= 1.0):
            return []  # a region with an area touches this stretch: it is drawn filled
        ends = [complex(x + 0.0, 0.0) if axis == 1.0 else complex(0.0, x + 0.0) for x in interval]  # (+ 0.0: no −0)
        stretches.append((ends[0], ends[1]))
    return stretches


def _segment_text(a: complex, b: complex) -> str:
    def num(x: float) -> str:
        return f"{x:.4g}".replace("-", "\u2212")

    if a.real == 0.0 and b.real == 0.0:
        return f"[{num(a.imag)}i, {num(b.imag)}i]"
    return f"[{num(a.real)}, {num(b.real)}]"


def _pale(color: Any, strength: float = 0.35) -> tuple[float, float, float, float]:
    """``color`` mixed with white, opaque: a region's fill and its legend patch's face."""
    from matplotlib.colors import to_rgb

    r, g, b = to_rgb(color)
    return (1 - strength * (1 - r), 1 - strength * (1 - g), 1 - strength * (1 - b), 1.0)


def plot_regions(
    methods: Sequence[str | ButcherTableau] = ("euler", "midpoint", "rk4", "implicit_euler"),
    ax: Any = None,
    *,
    extent: tuple[float, float, float, float] = (-5.0, 3.0, -4.0, 4.0),
    resolution: int = 600,
) -> Any:
    """Draw the stability regions {z : |R(z)| ≤ 1} of `methods` in the z = hλ plane.

    Each bounded region is filled with a pale opaque colour, the larger regions under the
    smaller ones (so each region shows its own colour, the one of its legend patch, where no
    smaller region covers it); an unbounded one (e.g. implicit Euler's, the outside of a disc)
    is hatched beneath them; all are outlined on top, with a legend; axes are equal. A stable
    set with no area (`segments`: symplectic Euler's and Verlet's segment [−2i, 2i] of the
    imaginary axis) is drawn as a thick line along the axis, labelled with the segment.
    `extent` = (re_min, re_max, im_min, im_max). Returns the matplotlib Axes.
    """
    import matplotlib.pyplot as plt
    from matplotlib.colors import to_rgba
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    if ax is None:
        _, ax = plt.subplots(figsize=(7, 6))
    re = np.linspace(extent[0], extent[1], resolution)
    im = np.linspace(extent[2], extent[3], resolution)
    z = re[None, :] + 1j * im[:, None]
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    handles = []
    fills = []  # (area, method index, magnitude, colour) of the bounded regions
    thin = 0
    for k, m in enumerate(methods):
        color = colors[k % len(colors)]
        mag = np.abs(amplification(m, z))
        stable = mag <= 1.0
        lines = segments(m)
        if lines:
            # No area: |R| ≤ 1 only on a stretch of an axis, which no grid point hits. A thick
            # line along it; the next thin set is drawn narrower on top, so both show.
            width = max(7.0 - 2.5 * thin, 2.0)
            thin += 1
            for a, b in lines:
                ax.plot([a.real, b.real], [a.imag, b.imag], color=color, lw=width, solid_capstyle="butt", zorder=4 + thin, gid=f"segment:{_name(m)}")
            text = " and ".join(_segment_text(a, b) for a, b in lines)
            handles.append(Line2D([], [], color=color, lw=width, label=f"{_name(m)}: only {text}"))
            continue
        # A region that reaches the frame on every side (implicit Euler: the outside of a
        # disc) is hatched beneath the filled regions, so it does not tint them.
        unbounded = stable[0, :].any() and stable[-1, :].any() and stable[:, 0].any() and stable[:, -1].any()
        if unbounded:
            faint = to_rgba(color, 0.4)
            cs = ax.contourf(re, im, mag, levels=[0.0, 1.0], colors="none", hatches=["/"], zorder=0.5)
            cs.set_edgecolor(faint)
            cs.set_linewidth(0.0)
            handles.append(Patch(facecolor="none", edgecolor=faint, hatch="/", label=_name(m)))
        else:
            fills.append((int(stable.sum()), k, mag, color))
            handles.append(Patch(facecolor=_pale(color), edgecolor=color, label=_name(m)))
        ax.contour(re, im, mag, levels=[1.0], colors=[color], linewidths=1.5, zorder=3)
    # Opaque fills, the largest first: a region nested in another shows its own colour.
    for rank, (_, _, mag, color) in enumerate(sorted(fills, key=lambda f: (-f[0], f[1]))):
        ax.contourf(re, im, mag, levels=[0.0, 1.0], colors=[_pale(color)], zorder=1 + rank / max(len(fills), 1))
    ax.axhline(0.0, color="0.3", lw=0.6, zorder=2.5)
    ax.axvline(0.0, color="0.3", lw=0.6, zorder=2.5)
    ax.set_aspect("equal")
    ax.set_xlim(extent[0], extent[1])
    ax.set_ylim(extent[2], extent[3])
    ax.set_xlabel("Re(hλ)")
    ax.set_ylabel("Im(hλ)")
    ax.set_title("Stability regions |R(hλ)| ≤ 1 on p′ = λp")
    ax.legend(handles=handles, loc="upper left")
    return ax
