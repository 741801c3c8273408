"""Coarse-grained fields (kinema.analysis.slab_fields, grid_fields) against closed forms: a
hydrostatic column's stress ρ_b g (H − z), the uniform stress of a compressed lattice, a
moving block's velocity and zero kinetic stress, the kernels' integrals; and against an
independent computation: the virial kinema's World.particle_stress() gives for a resting
column, and numerical quadrature of the kernels."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

import kinema
from kinema import analysis
from kinema.analysis import Binning, Gaussian, Lucy

KERNELS = [Gaussian(0.02), Lucy(0.05), Binning()]
TOUCH = 1e-9  # m: a lattice's neighbours are 1 diameter apart up to rounding


# -- scenes ---------------------------------------------------------------------------------
def column(n=40, r=0.01, m=0.002, g=9.81):
    """n balls of radius r and mass m stacked on a floor (z = 0) under gravity g, touching,
    with the exact contact forces of rest: ball k+1 rests on ball k with the weight of the
    n − k − 1 balls from it up, ball 0 on the floor (collider 0) with all n. Positions, the
    contact table."""
    z = r + 2 * r * np.arange(n)
    x = np.stack([0 * z, 0 * z, z], axis=1)
    up = np.array([0.0, 0.0, 1.0])
    weight = (n - 1 - np.arange(n - 1)) * m * g
    table = {
        "i": np.r_[np.arange(1, n), 0],
        "j": np.r_[np.arange(n - 1), -1],
        "collider": np.r_[np.full(n - 1, -1), 0],
        "normal": np.tile(up, (n, 1)),
        "point": np.r_[x[:-1] + r * up, [[0.0, 0.0, 0.0]]],
        "force_n": np.outer(np.r_[weight, n * m * g], up),
        "force_t": np.zeros((n, 3)),
    }
    return x, table


def fcc(cells, d=1.0):
    """A periodic face-centred cubic packing of spheres of diameter d: positions, the cell (3,)."""
    a = d * math.sqrt(2)
    basis = np.array([[0, 0, 0], [0.5, 0.5, 0], [0.5, 0, 0.5], [0, 0.5, 0.5]])
    grid = np.array(list(np.ndindex(cells, cells, cells)), dtype=float)
    return ((grid[:, None, :] + basis[None] + 0.25) * a).reshape(-1, 3), np.full(3, cells * a)


def triangular(n, d=1.0):
    """A periodic triangular lattice of discs of diameter d (n × n, n even): positions, the cell."""
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    x = np.stack([(i + 0.5 * (j % 2) + 0.25) * d, (j + 0.5) * d * math.sqrt(3) / 2, 0 * i], axis=-1).reshape(-1, 3)
    return x.astype(float), np.array([n * d, n * d * math.sqrt(3) / 2, 0.0])


def pushed(x, cell, force):
    """The lattice's contacts, each pushing its pair apart with ``force`` N (a uniform compression)."""
    t = analysis.geometric_contacts(x, 0.5, gap=TOUCH, period=cell)
    return {**t, "force_n": force * t["normal"], "force_t": np.zeros_like(t["normal"])}


# -- the kernels ----------------------------------------------------------------------------
@pytest.mark.parametrize("kernel", [Gaussian(0.3), Lucy(0.7)], ids=["gaussian", "lucy"])
def test_the_kernels_integrate_to_one_and_their_integrals_are_the_quadratures(kernel):
    # Independent: adaptive quadrature (QUADPACK) of ψ over the line, the disc and the ball,
    # and of ψ and Ψ from −c to x for the closed forms Ψ and G the slabs use.
    c = kernel.cutoff

    def psi(r, dims):
        return float(kernel.value(np.array(abs(r)), dims))

    tight = {"epsabs": 1e-14, "epsrel": 1e-13, "limit": 200}
    assert quad(lambda x: psi(x, 1), -c, c, points=[0.0], **tight)[0] == pytest.approx(1.0, abs=1e-12)
    assert quad(lambda r: 2 * math.pi * r * psi(r, 2), 0, c)[0] == pytest.approx(1.0, abs=1e-12)
    assert quad(lambda r: 4 * math.pi * r * r * psi(r, 3), 0, c)[0] == pytest.approx(1.0, abs=1e-12)
    for x in (-1.3 * c, -0.5 * c, -0.1 * c, 0.0, 0.3 * c, 0.9 * c, c, 1.4 * c):
        cdf = quad(lambda t: psi(t, 1), -c, min(x, c), **tight)[0] if x > -c else 0.0
        assert float(kernel.cdf(np.array([x]))[0]) == pytest.approx(cdf, abs=1e-12)
        G = quad(lambda t: float(kernel.cdf(np.array([t]))[0]), -c, x, **tight)[0] if x > -c else 0.0
        assert float(kernel.cdf_integral(np.array([x]))[0]) == pytest.approx(G, abs=1e-10 * c)
    assert math.sqrt(quad(lambda x: x * x * psi(x, 1), -c, c)[0]) == pytest.approx(kernel.width, rel=0.02 if isinstance(kernel, Gaussian) else 1e-12)


# -- slabs ------------------------------------------------------------------------------------
@pytest.mark.parametrize("kernel", KERNELS, ids=["gaussian", "lucy", "binning"])
def test_a_hydrostatic_column_has_the_closed_form_stress_profile(kernel):
    # Closed form: each contact of a resting column carries the weight above it, so the
    # contact stress along the column is the staircase m g #(centres above z) / A; averaged
    # over one period 2r of the staircase it is exactly linear, ρ_b g (H − z) at the slab's
    # centre, with ρ_b = m / (2 r A) the column's bulk density (φ ρ_p: the solid fraction
    # of its tube times the grains' density). Smoothing commutes with that average, so every
    # kernel gives it in the slabs farther than its cutoff from the ends; the density there
    # is ρ_b. With no smoothing (binning) it holds down to the floor, whose contact carries
    # the whole weight along the branch from ball 0's centre to the floor.
    n, r, m, g = 40, 0.01, 0.002, 9.81
    x, table = column(n, r, m, g)
    A = (2 * r) ** 2  # a square tube around the column
    H = 2 * r * n
    edges = np.arange(-0.3 * r, H + 0.2, 2 * r) - 0.1  # slabs 2r wide, at no particular offset
    f = analysis.slab_fields(x, m, edges=edges, cross_section=A, kernel=kernel, contacts=table)
    rho_b = m / (2 * r * A)
    inner = (edges[:-1] > kernel.cutoff) & (edges[1:] < H - kernel.cutoff)
    assert inner.sum() >= 25
    closed = rho_b * g * (H - f.where)
    np.testing.assert_allclose(f.contact_stress[inner, 2, 2], closed[inner], rtol=1e-12)
    np.testing.assert_allclose(f.density[inner], rho_b, rtol=1e-12)
    others = f.contact_stress.copy()
    others[:, 2, 2] = 0
    assert np.abs(others).max() == 0.0
    if isinstance(kernel, Binning):
        full = (edges[:-1] >= 0) & (edges[1:] <= H)
        np.testing.assert_allclose(f.contact_stress[full, 2, 2], closed[full], rtol=1e-12)


@pytest.mark.parametrize("kernel", KERNELS, ids=["gaussian", "lucy", "binning"])
def test_slabs_keep_mass_momentum_and_the_virial(kernel):
    # ∫ ρ dV = Σ m, ∫ p dV = Σ m v and ∫ σᶜ dV = Σ_c b ⊗ f (the collider's branch to its
    # contact point included): the slabs' sums telescope, so to rounding. Random particles,
    # velocities and contacts, a periodic x–y cell (the branches by their nearest image).
    rng = np.random.default_rng(2)
    n, cell = 300, np.array([1.0, 1.0, 0.0])
    x = rng.uniform(0, 1, size=(n, 3))
    v = rng.normal(size=(n, 3))
    m = rng.uniform(0.5, 2.0, size=n)
    k = 500
    i = rng.integers(0, n, k)
    j = (i + rng.integers(1, n, k)) % n
    wall = rng.uniform(size=k) < 0.2
    table = {
        "i": i,
        "j": np.where(wall, -1, j),
        "collider": np.where(wall, 2, -1),
        "normal": np.tile([0.0, 0.0, 1.0], (k, 1)),
        "point": x[i] + rng.uniform(-0.05, 0.05, (k, 3)),
        "force_n": rng.normal(size=(k, 3)),
        "force_t": rng.normal(size=(k, 3)),
    }
    edges = np.linspace(-0.5, 1.5, 41)
    A = 0.37
    f = analysis.slab_fields(x, m, edges=edges, cross_section=A, kernel=kernel, velocities=v, contacts=table, period=cell)
    dz = np.diff(edges)
    assert (f.density * dz).sum() * A == pytest.approx(m.sum(), rel=1e-13)
    np.testing.assert_allclose((f.momentum * dz[:, None]).sum(axis=0) * A, (m[:, None] * v).sum(axis=0), rtol=1e-12)
    b = np.where(wall[:, None], x[i] - table["point"], analysis.contacts.minimum_image(x[i] - x[j], cell))
    virial = np.einsum("ca,cb->ab", b, table["force_n"] + table["force_t"])
    np.testing.assert_allclose((f.contact_stress * dz[:, None, None]).sum(axis=0) * A, virial, rtol=0, atol=1e-12 * np.abs(virial).max())
    # without the colliders' contacts, or the tangential forces
    pairs = analysis.slab_fields(x, m, edges=edges, cross_section=A, kernel=kernel, contacts=table, period=cell, colliders=False, tangential=False)
    normal_pairs = np.einsum("ca,cb->ab", b[~wall], table["force_n"][~wall])
    np.testing.assert_allclose((pairs.contact_stress * dz[:, None, None]).sum(axis=0) * A, normal_pairs, rtol=0, atol=1e-12 * np.abs(normal_pairs).max())


@pytest.mark.parametrize("kernel", KERNELS, ids=["gaussian", "lucy", "binning"])
def test_a_moving_block_has_its_velocity_and_no_kinetic_stress(kernel):
    # Closed form: every particle moves with v, so V = v wherever there is mass and v' = 0.
    x = np.array(list(np.ndindex(6, 6, 6)), dtype=float) * 0.1
    v = np.array([1.0, -2.0, 0.5])
    f = analysis.slab_fields(x, 0.3, edges=np.linspace(-0.3, 0.8, 23), cross_section=0.36, kernel=kernel, velocities=np.tile(v, (len(x), 1)))
    full = f.density > 0
    assert full.sum() >= 6
    np.testing.assert_allclose(f.velocity[full], np.tile(v, (full.sum(), 1)), rtol=1e-13)
    assert np.isnan(f.velocity[~full]).all()
    scale = f.density.max() * (v @ v)
    assert np.abs(f.kinetic_stress).max() < 1e-13 * scale


def test_the_kinetic_stress_of_grains_moving_both_ways_is_rho_u_squared():
    # Closed form: in each layer half the grains move at +u along x and half at −u, so the
    # slab's velocity is 0 and its kinetic stress is ρ u² in xx only (the mean of m v'⊗v'),
    # compressive positive like a gas's pressure.
    x = np.array(list(np.ndindex(4, 4, 10)), dtype=float) * 0.1
    u = 3.0
    v = np.zeros_like(x)
    v[:, 0] = np.where(np.arange(len(x)) // 10 % 2 == 0, u, -u)  # alternate columns
    f = analysis.slab_fields(x, 0.2, edges=np.linspace(-0.05, 0.95, 11), cross_section=0.16, velocities=v)
    np.testing.assert_allclose(f.velocity, 0.0, atol=1e-15)
    np.testing.assert_allclose(f.kinetic_stress[:, 0, 0], f.density * u * u, rtol=1e-14)
    assert np.abs(f.kinetic_stress[:, 1:, :]).max() == 0.0 and np.abs(f.kinetic_stress[:, 0, 1:]).max() == 0.0
    np.testing.assert_array_equal(f.stress, f.kinetic_stress)  # no contacts given: the kinetic part alone


# -- a grid -----------------------------------------------------------------------------------
def cell_grid(cell, per_side, dim):
    """Points of a regular grid over the periodic cell, ``per_side`` along each axis."""
    return tuple((np.arange(per_side) + 0.5) * cell[a] / per_side for a in range(dim))


def grid_sum(kernel, y, axes, cell, dim=3):
    """S(y) = Σ_k ψ(r_k − y) h^d over the points r_k of a grid spanning the periodic cell
    (nearest images), for each place y: the grid's own quadrature of ∫ ψ = 1, by brute force."""
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, dim)
    d = pts[None, :, :] - y[:, None, :dim]
    d -= cell[:dim] * np.round(d / cell[:dim])
    h = np.prod([ax[1] - ax[0] for ax in axes])
    return kernel.value(np.linalg.norm(d, axis=2), dim).sum(axis=1) * h


def test_a_compressed_fcc_packing_has_the_closed_form_uniform_stress_on_a_grid():
    # Closed form: a periodic face-centred cubic packing whose 6 N contacts each push with F
    # has the stress Σ_c b ⊗ f / V = 2√2 F / d² I (each sphere: ½ Σ_12 d F n⊗n = 2 d F I, in
    # a volume d³/√2) and the density √2 m / d³. The grid's mean over the cell is these
    # times the grid's own sum of the kernel, S = Σ_k ψ(r_k − y) h³ (1 to the grid's
    # discretisation error), at the particles (density) and the branches' quadrature nodes
    # (stress): bounded here by brute force, independently of the fields' binned search.
    d, F, m, nodes = 1.0, 2.0, 1.0, 3
    x, cell = fcc(3, d)
    table = pushed(x, cell, F)
    assert len(table["i"]) == 6 * len(x)
    kernel = Lucy(1.4 * d)
    axes = cell_grid(cell, 12, 3)
    f = analysis.grid_fields(x, m, at=axes, kernel=kernel, contacts=table, period=cell, nodes=nodes)
    sigma, rho = 2 * math.sqrt(2) * F / d**2, math.sqrt(2) * m / d**3
    s = (np.polynomial.legendre.leggauss(nodes)[0] + 1) / 2
    line = (x[table["i"]][:, None, :] - s[None, :, None] * d * table["normal"][:, None, :]).reshape(-1, 3)
    off = max(np.abs(grid_sum(kernel, x, axes, cell) - 1).max(), np.abs(grid_sum(kernel, line, axes, cell) - 1).max())
    assert off < 1e-3  # the grid's quadrature of the kernel, cutoff / spacing = 4.0: measured 2.0e-4
    np.testing.assert_allclose(f.contact_stress.mean(axis=(0, 1, 2)), sigma * np.eye(3), rtol=0, atol=(off + 1e-12) * sigma)
    assert f.density.mean() == pytest.approx(rho, rel=off + 1e-12)
    assert f.density.shape == (12, 12, 12) and f.where.shape == (12, 12, 12, 3)


def test_a_compressed_triangular_lattice_has_the_closed_form_uniform_stress_in_2d():
    # Closed form, 2D (N/m): each disc's 6 contacts push with F; Σ_6 n⊗n = 3 I, half of each
    # contact is the disc's, over its area √3 d²/2: σ = √3 F / d I, ρ = 2 m / (√3 d²). Lucy of
    # cutoff 4 d in the plane: the lattice's ripple through it < 1e-4 (measured 3.5e-5).
    d, F, m = 1.0, 2.0, 1.0
    x, cell = triangular(12, d)
    table = pushed(x, cell, F)
    rng = np.random.default_rng(4)
    pts = np.c_[rng.uniform(0, cell[0], 40), rng.uniform(0, cell[1], 40), np.zeros(40)]
    f = analysis.grid_fields(x, m, at=pts, kernel=Lucy(4.0 * d), dim=2, contacts=table, period=cell)
    sigma = math.sqrt(3) * F / d
    np.testing.assert_allclose(f.contact_stress[:, :2, :2], np.broadcast_to(sigma * np.eye(2), (40, 2, 2)), rtol=0, atol=1e-4 * sigma)
    np.testing.assert_allclose(f.density, 2 * m / (math.sqrt(3) * d * d), rtol=1e-4)
    assert np.abs(f.contact_stress[:, 2, :]).max() == 0.0


def test_a_moving_block_on_a_grid_has_its_velocity_and_no_kinetic_stress():
    x, cell = fcc(2)
    v = np.array([0.3, 0.0, -1.2])
    f = analysis.grid_fields(x, 2.0, at=cell_grid(cell, 5, 3), kernel=Gaussian(0.4), velocities=np.tile(v, (len(x), 1)), period=cell)
    np.testing.assert_allclose(f.velocity.reshape(-1, 3), np.tile(v, (125, 1)), rtol=1e-13)
    assert np.abs(f.kinetic_stress).max() < 1e-13 * f.density.max() * (v @ v)


# -- a World ---------------------------------------------------------------------------------
def resting_column(n=5, r=0.01, m=0.002, k=1e4, g=9.81):
    """n balls at rest on a floor under the spring–dashpot model: placed at their rest
    overlaps (each contact pressed by the weight above it, δ = W / k), then stepped 0.2 s."""
    w = kinema.World(dt=1e-5, method="verlet")
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.add(kinema.Gravity([0, 0, -g]))
    w.set_collisions(model="spring_dashpot", stiffness=k, restitution=0.2, friction=0.4)
    z = [r - n * m * g / k]
    for j in range(1, n):
        z.append(z[-1] + 2 * r - (n - j) * m * g / k)
    w.add_particles([[0, 0, zj] for zj in z], mass=m, radius=r)
    w.step(20_000)
    return w


def test_the_slabs_virial_of_a_resting_world_is_the_sum_of_its_particle_stresses():
    # Independent: kinema's World.particle_stress() (½ Σ_j (x_i − x_j) ⊗ F_ij per particle)
    # summed over the particles, against the slabs' ∫ σᶜ dV for the same column, whose contact
    # table is its touching pairs (from the positions) with the spring's force k δ along the
    # normal (at rest the dashpot and friction carry nothing). And the slab profile against
    # the closed form of a resting column, ρ_b g (H − z), in the slab around the middle ball.
    n, r, m, k, g = 5, 0.01, 0.002, 1e4, 9.81
    w = resting_column(n, r, m, k, g)
    snap = analysis.Snapshot.of_world(w)
    assert np.abs(snap.velocities).max() < 1e-9 and snap.dim == 3 and len(snap) == n
    table = analysis.geometric_contacts(snap.positions, snap.radii)
    assert len(table["i"]) == n - 1
    force = k * table["overlap"][:, None] * table["normal"]
    table = {**table, "force_n": force, "force_t": np.zeros_like(force)}
    A = (2 * r) ** 2
    edges = np.linspace(-0.05, 0.15, 201)
    f = analysis.slab_fields(snap.positions, snap.masses, edges=edges, cross_section=A, kernel=Lucy(0.01), contacts=table)
    integral = (f.contact_stress * np.diff(edges)[:, None, None]).sum(axis=0) * A
    kinema_virial = w.particle_stress(kinetic=False).sum(axis=0)
    np.testing.assert_allclose(integral, kinema_virial, rtol=0, atol=1e-9 * kinema_virial[2, 2])
    # each contact carries the weight above it (Newton at rest): (n − 1 − j) m g
    # (the table lists each pair once, i below j: the force on the lower ball points down)
    np.testing.assert_allclose(force[:, 2], -(n - 1 - np.arange(n - 1)) * m * g, rtol=1e-6)
    # the binned profile over 2r about the middle ball's centre: ρ_b g (H − z), ρ_b = m / (2 r A),
    # up to the overlaps, which shorten the column's period 2r by δ/2r ≤ 4 m g / (k 2r) = 4e-4
    zc = snap.positions[n // 2, 2]
    mid = analysis.slab_fields(snap.positions, snap.masses, edges=[zc - r, zc + r], cross_section=A, contacts=table)
    H = snap.positions[-1, 2] + r
    assert mid.contact_stress[0, 2, 2] == pytest.approx(m / (2 * r * A) * g * (H - zc), rel=1e-3)


def test_a_hertz_columns_own_contacts_give_the_statics_and_kinemas_virial():
    # World.contacts() of a settled Hertz column (7 balls on a floor, friction 0.3) read
    # straight into the slabs. Closed form (statics): the contact below ball k carries the
    # weight of the n − k balls from it up, so the binned slab of width 2r about ball k holds
    # half of each of its two contacts' branches: σ_zz A = (n − k − ½) m g, whatever the
    # overlaps. Independent: ∫ σᶜ dV over the pairs is Σ World.particle_stress(kinetic=False).
    n, r, m, g = 7, 0.01, 0.01, 9.81
    w = kinema.World(dt=1e-5)
    w.add_particles([[0.0, 0.0, r + 2 * k * r] for k in range(n)], radius=r, mass=m)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.set_collisions(restitution=0.1, friction=0.3, model="hertz", youngs_modulus=1e8, poisson_ratio=0.3)
    w.step(100_000)  # 1 s: at rest, each contact's force its weight to 1e-6 (tests/test_contact_reports.py)
    snap = analysis.Snapshot.of_world(w)
    assert len(snap.contacts["i"]) == n and np.abs(snap.velocities).max() < 1e-6
    A = (2 * r) ** 2
    x = snap.positions
    for k in range(1, n):
        slab = analysis.slab_fields(x, m, edges=[x[k, 2] - r, x[k, 2] + r], cross_section=A, contacts=snap.contacts)
        assert slab.contact_stress[0, 2, 2] * A == pytest.approx((n - k - 0.5) * m * g, rel=1e-6)
    # ball 0's slab also holds the floor's branch, from its centre to the contact point
    # (r − δ_floor long, all inside), carrying n m g: (n m g (r − δ) + (n − 1) m g r) / 2r
    floor = int(np.flatnonzero(snap.contacts["j"] < 0)[0])
    bottom = analysis.slab_fields(x, m, edges=[x[0, 2] - r, x[0, 2] + r], cross_section=A, contacts=snap.contacts)
    reach = x[0, 2] - snap.contacts["point"][floor, 2]
    assert bottom.contact_stress[0, 2, 2] * A * 2 * r == pytest.approx(n * m * g * reach + (n - 1) * m * g * r, rel=1e-6)
    edges = np.linspace(-0.05, 0.2, 251)
    f = analysis.slab_fields(x, m, edges=edges, cross_section=A, kernel=Lucy(0.01), contacts=snap.contacts, colliders=False)
    virial = (f.contact_stress * np.diff(edges)[:, None, None]).sum(axis=0) * A
    kinema_virial = w.particle_stress(kinetic=False).sum(axis=0)
    np.testing.assert_allclose(virial, kinema_virial, rtol=0, atol=1e-12 * kinema_virial[2, 2])


# -- refusals ---------------------------------------------------------------------------------
def test_the_fields_refuse_what_they_cannot_measure():
    x, table = column(4)
    with pytest.raises(ValueError, match=r"edges = .* is invalid: give >= 2 finite, increasing positions"):
        analysis.slab_fields(x, 1.0, edges=[0.0, 0.0], cross_section=1.0)
    with pytest.raises(ValueError, match=r"cross_section = 0.0 is invalid: it must be the slabs' area normal to the axis, > 0"):
        analysis.slab_fields(x, 1.0, edges=[0.0, 1.0], cross_section=0.0)
    with pytest.raises(ValueError, match=r"kernel = None is invalid: a grid's point values need a smoothing kernel"):
        analysis.grid_fields(x, 1.0, at=x, kernel=None)
    with pytest.raises(ValueError, match=r"along x the cell \(0.5 m\) is shorter than twice the cutoff"):
        analysis.grid_fields(x, 1.0, at=x, kernel=Lucy(0.3), period=(0.5, 0, 0))
    with pytest.raises(TypeError, match=r"kernel = 'lucy' is invalid: give kinema.analysis.Gaussian\(width\) or Lucy\(cutoff\)"):
        analysis.slab_fields(x, 1.0, edges=[0.0, 1.0], cross_section=1.0, kernel="lucy")
    with pytest.raises(ValueError, match=r"width = -1.0 is invalid: it must be a finite length > 0"):
        Gaussian(-1.0)
    no_point = {key: v for key, v in table.items() if key != "point"}
    with pytest.raises(ValueError, match=r"contacts has no 'point'.*against colliders \(colliders=False leaves them out\)"):
        analysis.slab_fields(x, 1.0, edges=[0.0, 1.0], cross_section=1.0, contacts=no_point)
    assert analysis.slab_fields(x, 1.0, edges=[0.0, 1.0], cross_section=1.0, contacts=no_point, colliders=False).contact_stress is not None
