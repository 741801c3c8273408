"""Coarse-grained continuum fields from particles and their contacts (MercuryCG's; Goldhirsch
2010, Granular Matter 12, 239; Weinhart, Thornton, Luding & Bokhove 2012, Granular Matter 14,
289): density, velocity, kinetic and contact stress, averaged over slabs along one axis or
evaluated at points of a grid.

With a kernel ψ (``kinema.analysis.kernels``) of integral 1, at a place r:

    ρ(r)    = Σ_i m_i ψ(r − x_i)                                   density
    p(r)    = Σ_i m_i v_i ψ(r − x_i),   V = p / ρ                  momentum, velocity
    σᵏ(r)   = Σ_i m_i v'_i ⊗ v'_i ψ(r − x_i),   v'_i = v_i − V(r)  kinetic stress
    σᶜ(r)   = Σ_c b_c ⊗ f_c ∫_0^1 ψ(r − x_i + s b_c) ds           contact stress

c runs over the contacts, each pair once: f_c the force on i (``force_n`` + ``force_t``),
b_c the branch from the partner to i, x_i − x_j (the nearest periodic image), or from the
contact point to i against a collider, x_i − point; the integral runs along the branch, from
x_i (s = 0) to the partner's centre or the contact point (s = 1), so a contact's stress is
spread over the line it is carried along.

Signs: compressive stress is positive, as ``World.particle_stress()`` (whose Σ_i over the
particles is the pair part of ∫ σᶜ dV) and MercuryCG (its ``contactStress`` is f ⊗ b, the
transpose of b ⊗ f here, the same for the normal forces' symmetric part; kinema follows
``particle_stress`` and LAMMPS's virial, branch ⊗ force). The Cauchy stress of continuum
mechanics (tension positive; LAMMPS's ``compute stress/atom`` over a volume) is −σ.

Integrals over space: ∫ ρ dV = Σ m (mass), ∫ p dV = Σ m v, ∫ σᶜ dV = Σ_c b_c ⊗ f_c (the
virial) wherever the kernel's support lies inside the region; the slab averages here keep
them to rounding (a slab's average of ψ is a difference of the kernel's integral Ψ, and the
slabs' sum telescopes), the grid's point values to the accuracy of a sum over its points."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from .. import _checks
from ._neighbours import near
from .contacts import contact_table, minimum_image, periodic_lengths
from .kernels import Binning, Gaussian, Kernel, Lucy

_CHUNK = 1 << 20  # entries per block of (particles × slabs) arrays


@dataclass(frozen=True)
class Fields:
    """Coarse-grained fields (:func:`slab_fields`, :func:`grid_fields`).

    `where`: slabs: their centres (B,) m along `axis`, between `edges` (B + 1,) m; a grid:
    its points (..., 3) m. `density` (...,): kg/m³ (3D), kg/m² (a 2D world). `momentum`
    (..., 3) kg/(m² s) and `velocity` (..., 3) m/s (NaN where the density is 0); `None`
    without velocities. `kinetic_stress` and `contact_stress` (..., 3, 3): Pa in 3D (N/m in
    2D), compressive positive, branch ⊗ force (see the module); `None` without velocities,
    or without contacts. `kernel`: the kernel used."""

    where: np.ndarray
    edges: np.ndarray | None
    axis: int | None
    kernel: Kernel
    density: np.ndarray
    momentum: np.ndarray | None
    velocity: np.ndarray | None
    kinetic_stress: np.ndarray | None
    contact_stress: np.ndarray | None

    @property
    def stress(self) -> np.ndarray | None:
        """σ = σᵏ + σᶜ (the parts known; `None` when neither is), compressive positive."""
        parts = [s for s in (self.kinetic_stress, self.contact_stress) if s is not None]
        return sum(parts[1:], parts[0]) if parts else None


# Over 100 lines (issue 50) by its documentation: 11 parameters in the signature (14 lines)
# and the docstring (29: the fields, their units and the kernels); the code is 58 lines.
def slab_fields(
    positions: Any,
    masses: Any,
    *,
    edges: Any,
    cross_section: float,
    axis: int = 2,
    kernel: Kernel | None = None,
    velocities: Any = None,
    contacts: Any = None,
    colliders: bool = True,
    tangential: bool = True,
    period: Any = None,
) -> Fields:
    """The fields averaged over slabs [edges[k], edges[k+1]] normal to ``axis`` (0, 1, 2:
    x, y, z), over a cross-section of area ``cross_section`` (m² in 3D; in a 2D world, the
    slabs' length, m): profiles along one direction, as LAMMPS's ``fix ave/chunk`` over
    ``compute chunk/atom bin/1d`` or MercuryCG averaged over the other directions.

    ``kernel``: the smoothing along ``axis`` (``Gaussian``, ``Lucy``) or None (plain
    binning: a particle counts in the slab of its centre, a contact along the part of its
    branch inside the slab). Each slab holds the average of the kernel's 1D field, over the
    slab's width Δ_k, divided by the cross-section A:

        ρ_k = Σ_i m_i W_ik / A,   W_ik = (Ψ(e_{k+1} − z_i) − Ψ(e_k − z_i)) / Δ_k,

    Ψ the kernel's integral; likewise the momentum, V_k = p_k / ρ_k, the kinetic stress
    Σ_i m_i (v_i − V_k) ⊗ (v_i − V_k) W_ik / A (the slab's mean momentum flux less ρ_k V_k ⊗
    V_k), and the contact stress Σ_c b_c ⊗ f_c L_ck / A with the slab's average of the
    branch integral in closed form: z = z_i − s b_z along the branch, and with G = ∫ Ψ,

        ∫_0^1 Ψ(a + s β) ds = (G(a + β) − G(a)) / β      (Ψ(a + β/2) when |β| ≲ 1e-5 (c + |a|),
                                                             where the difference would cancel),
        L_ck = (I(e_{k+1}) − I(e_k)) / Δ_k,   I(e) = ∫_0^1 Ψ(e − z_i + s b_z) ds.

    So Σ_k ρ_k Δ_k A = Σ m, Σ_k σᶜ_k Δ_k A = Σ_c b_c ⊗ f_c to rounding when the slabs hold
    every particle's and branch's support. The other coordinates are not looked at: A is the
    cross-section the particles occupy (for a bed in a box, the box's floor).

    ``positions`` (N, 3) m, ``masses`` (one or (N,), kg), ``velocities`` (N, 3) m/s or None,
    ``contacts`` the contact table (``force_n``, and ``force_t`` unless not ``tangential``)
    or None; ``colliders``: include the contacts with colliders; ``period`` (3,) m: the
    periodic cell (0 along open axes), for the branches' nearest images."""
    x, m, v = _particles(positions, masses, velocities)
    axis = _checks.integer("axis", axis, lo=0, hi=2)
    e = _checks.real_array("edges", edges)
    if e.ndim != 1 or len(e) < 2 or not (np.isfinite(e).all() and (np.diff(e) > 0).all()):
        raise ValueError(f"edges = {_checks.describe(edges)} is invalid: give >= 2 finite, increasing positions (m) along the axis")
    area = _checks.real("cross_section", cross_section)
    if not (np.isfinite(area) and area > 0):
        raise ValueError(f"cross_section = {area!r} is invalid: it must be the slabs' area normal to the axis, > 0 (m², or m in a 2D world)")
    kern = Binning() if kernel is None else _kernel(kernel)
    width = np.diff(e)
    z = x[:, axis]
    rho = np.zeros(len(width))
    mom = np.zeros((len(width), 3))
    blocks = []
    for lo in range(0, len(x), max(1, _CHUNK // len(e))):
        sl = slice(lo, lo + max(1, _CHUNK // len(e)))
        W = np.diff(kern.cdf(e[None, :] - z[sl, None]), axis=1) / width
        blocks.append((sl, W))
        rho += m[sl] @ W
        if v is not None:
            mom += W.T @ (m[sl, None] * v[sl])
    momentum = velocity = kinetic = None
    if v is not None:
        with np.errstate(invalid="ignore", divide="ignore"):
            velocity = np.where(rho[:, None] > 0, mom / rho[:, None], np.nan)
        kinetic = np.zeros((len(width), 3, 3))
        V = np.nan_to_num(velocity)
        for sl, W in blocks:
            d = v[sl, None, :] - V[None, :, :]
            kinetic += np.einsum("nk,nka,nkb->kab", m[sl, None] * W, d, d)
        momentum, kinetic = mom / area, kinetic / area
    contact = None
    if contacts is not None:
        b, f, xi = _branches_and_forces(contacts, x, colliders, tangential, period, "slab_fields' contact stress")
        contact = np.zeros((len(width), 3, 3))
        c = float(kern.cutoff)
        for lo in range(0, len(b), max(1, _CHUNK // len(e))):
            sl = slice(lo, lo + max(1, _CHUNK // len(e)))
            a = e[None, :] - xi[sl, axis, None]
            beta = np.broadcast_to(b[sl, axis, None], a.shape)
            small = np.abs(beta) <= 1e-5 * (c + np.abs(a))
            with np.errstate(invalid="ignore", divide="ignore"):
                along = (kern.cdf_integral(a + beta) - kern.cdf_integral(a)) / beta
            integral = np.where(small, kern.cdf(a + beta / 2), along)
            L = np.diff(integral, axis=1) / width
            contact += np.einsum("ck,ca,cb->kab", L, b[sl], f[sl])
        contact /= area
    return Fields(
        where=(e[1:] + e[:-1]) / 2,
        edges=e,
        axis=axis,
        kernel=kern,
        density=rho / area,
        momentum=momentum,
        velocity=velocity,
        kinetic_stress=kinetic,
        contact_stress=contact,
    )


def grid_fields(
    positions: Any,
    masses: Any,
    *,
    at: Any,
    kernel: Gaussian | Lucy,
    dim: int = 3,
    velocities: Any = None,
    contacts: Any = None,
    colliders: bool = True,
    tangential: bool = True,
    period: Any = None,
    nodes: int = 8,
) -> Fields:
    """The fields at points: ``at`` (M, 3) m, or a grid given by its axes, a tuple of ``dim``
    1D arrays (x, y[, z]; m), whose fields then have the grid's shape. The kernel is
    normalised in ``dim`` dimensions (a 2D world: the plane z = 0; kg/m², N/m), and only
    particles within its cutoff of a point count (a binned search: the work grows as the
    points plus the particles plus the pairs within reach, not their product).

    The kinetic stress uses each point's own velocity, v'_i = v_i − V(r) (Weinhart et al.
    2012); the contact stress's branch integral is a Gauss–Legendre sum of ``nodes`` points
    along the branch (exact for polynomials in s of degree 2 nodes − 1; for a branch of
    length ℓ against a Gaussian of width w the error falls as (ℓ/w)^(2 nodes) / (2 nodes)!;
    the Gaussian's step at its cut and Lucy's third derivative there limit it to about
    (ℓ/nodes)/c of the step). Periodic axes (``period``, (3,) m) wrap both the particles'
    and the branches' distances to the points.

    ``positions``, ``masses``, ``velocities``, ``contacts``, ``colliders`` and ``tangential``
    as :func:`slab_fields`."""
    x, m, v = _particles(positions, masses, velocities)
    dim = _checks.integer("dim", dim, lo=2, hi=3)
    if isinstance(kernel, Binning) or kernel is None:
        raise ValueError(f"kernel = {_checks.describe(kernel)} is invalid: a grid's point values need a smoothing kernel, Gaussian(width) or Lucy(cutoff)")
    kern = _kernel(kernel)
    nodes = _checks.integer("nodes", nodes, lo=1, hi=64)
    cell = periodic_lengths(period)
    short = (cell > 0) & (cell < 2 * kern.cutoff)
    if short.any():
        a = int(np.argmax(short))
        raise ValueError(
            f"period = {_checks.describe(period)} is invalid with a kernel of cutoff {kern.cutoff:g} m: along {'xyz'[a]} the cell ({cell[a]:g} m) is shorter than twice the cutoff, "
            "where a point would see two images of one particle; give a narrower kernel or a larger cell"
        )
    points, shape = _points(at, dim)
    k, i, psi = _weights(points, x, kern, dim, cell)
    M = len(points)
    rho = np.bincount(k, m[i] * psi, minlength=M)
    momentum = velocity = kinetic = None
    if v is not None:
        momentum = np.stack([np.bincount(k, m[i] * v[i, a] * psi, minlength=M) for a in range(3)], axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            velocity = np.where(rho[:, None] > 0, momentum / rho[:, None], np.nan)
        d = v[i] - np.nan_to_num(velocity)[k]
        kinetic = np.stack([np.bincount(k, m[i] * d[:, a] * d[:, b] * psi, minlength=M) for a in range(3) for b in range(3)], axis=1).reshape(M, 3, 3)
    contact = None
    if contacts is not None:
        b, f, xi = _branches_and_forces(contacts, x, colliders, tangential, period, "grid_fields' contact stress")
        s, w = np.polynomial.legendre.leggauss(nodes)
        s, w = (s + 1) / 2, w / 2  # on [0, 1]
        y = (xi[:, None, :] - s[None, :, None] * b[:, None, :]).reshape(-1, 3)
        kq, cq, psi_q = _weights(points, y, kern, dim, cell)
        weight = psi_q * np.tile(w, len(b))[cq]
        owner = cq // nodes
        bf = np.einsum("ca,cb->cab", b, f).reshape(-1, 9)
        contact = np.stack([np.bincount(kq, bf[owner, e] * weight, minlength=M) for e in range(9)], axis=1).reshape(M, 3, 3)

    def shaped(a: np.ndarray | None, tail: tuple[int, ...]) -> np.ndarray | None:
        return None if a is None else a.reshape(*shape, *tail)

    return Fields(
        where=points.reshape(*shape, 3),
        edges=None,
        axis=None,
        kernel=kern,
        density=rho.reshape(shape),
        momentum=shaped(momentum, (3,)),
        velocity=shaped(velocity, (3,)),
        kinetic_stress=shaped(kinetic, (3, 3)),
        contact_stress=shaped(contact, (3, 3)),
    )


def _weights(points: np.ndarray, y: np.ndarray, kern: Gaussian | Lucy, dim: int, cell: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(k, i, ψ): the pairs of point k and place y_i closer than the cutoff, with the kernel's
    value at their distance (the nearest image along periodic axes)."""
    k, i = near(points, y, kern.cutoff, cell)
    r = np.linalg.norm(minimum_image(points[k] - y[i], cell), axis=1)
    keep = r < kern.cutoff
    k, i, r = k[keep], i[keep], r[keep]
    return k, i, kern.value(r, dim)


def _points(at: Any, dim: int) -> tuple[np.ndarray, tuple[int, ...]]:
    """The points (M, 3) and the fields' shape: (M,) for a list of points, the grid's shape
    for a tuple of axes."""
    if isinstance(at, tuple):
        if len(at) != dim:
            raise ValueError(f"at has {len(at)} axes: a grid in a {dim}D world takes {dim} (x, y{', z' if dim == 3 else ''}), each a 1D array of positions (m)")
        axes = [_checks.real_array(f"at[{a}]", ax).reshape(-1) for a, ax in enumerate(at)]
        mesh = np.meshgrid(*axes, indexing="ij")
        pts = np.zeros((mesh[0].size, 3))
        for a in range(dim):
            pts[:, a] = mesh[a].reshape(-1)
        shape = tuple(len(ax) for ax in axes)
    else:
        pts = _checks.real_array("at", at)
        if pts.ndim == 1:
            pts = pts[None, :]
        _checks.check_shape("at", pts, (None, 3))
        shape = (len(pts),)
    if not np.isfinite(pts).all():
        raise ValueError("at holds NaN or inf: the points must be finite places (m)")
    return pts, shape


def _particles(positions: Any, masses: Any, velocities: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    x = _checks.real_array("positions", positions)
    _checks.check_shape("positions", x, (None, 3))
    m = np.array(_checks.broadcast("masses", _checks.real_array("masses", masses), (len(x),), f"one mass or one per particle, ({len(x)},)"))
    if not np.isfinite(x).all():
        raise ValueError("positions hold NaN or inf: give the particles alive (Snapshot.of_frame keeps only those)")
    if not (np.isfinite(m).all() and (m >= 0).all()):
        raise ValueError(f"masses = {_checks.describe(masses)} is invalid: masses must be finite and >= 0 (kg)")
    v = None
    if velocities is not None:
        v = _checks.real_array("velocities", velocities)
        _checks.check_shape("velocities", v, (len(x), 3))
        if not np.isfinite(v).all():
            raise ValueError("velocities hold NaN or inf: give finite velocities (m/s)")
    return x, m, v


def _kernel(kernel: Any) -> Kernel:
    if not isinstance(kernel, (Gaussian, Lucy, Binning)):
        raise TypeError(
            f"kernel = {_checks.describe(kernel)} is invalid: give kinema.analysis.Gaussian(width) or Lucy(cutoff) (or None for slabs: plain binning)"
        )
    return kernel


def _branches_and_forces(contacts: Any, x: np.ndarray, colliders: bool, tangential: bool, period: Any, what: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(b, f, x_i) of the contacts counted: the branch b (K, 3) m towards i, the force on i
    f (K, 3) N, and i's position (K, 3) m."""
    colliders = _checks.boolean("colliders", colliders)
    tangential = _checks.boolean("tangential", tangential)
    need = ("force_n", "force_t") if tangential else ("force_n",)
    c = contact_table(contacts, len(x), need, what + " (tangential=False leaves force_t out)")
    keep = (c["j"] >= 0) | colliders
    if not keep.all() or (c["j"] >= 0).all():
        c["point"] = np.zeros((len(keep), 3))  # no collider's contact is counted: no point is read
    else:
        c["point"] = contact_table(contacts, len(x), ("point",), what + " against colliders (colliders=False leaves them out)")["point"]
    i, j = c["i"][keep], c["j"][keep]
    cell = periodic_lengths(period)
    xi = x[i]
    pair = j >= 0
    b = np.empty_like(xi)
    b[pair] = minimum_image(xi[pair] - x[j[pair]], cell)
    b[~pair] = minimum_image(xi[~pair] - c["point"][keep][~pair], cell)
    f = c["force_n"][keep] + (c["force_t"][keep] if tangential else 0.0)
    return b, f, xi
