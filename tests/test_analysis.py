"""Contact-level measures of a granular packing (kinema.analysis): the contact table's checks,
contacts found from geometry, the coordination number with rattlers removed, the fabric
tensor, the contact-force distribution, a heap's angle of repose and Janssen's silo. Each
is compared with a closed form (a lattice's coordination and fabric, the exponential
distribution, a cone's angle, Janssen's ODE) or an independent computation (an O(N²) pair
search, normals sampled from a known density)."""

import math

import numpy as np
import pytest

import kinema
from kinema import analysis


# -- scenes ---------------------------------------------------------------------------------
def brute_pairs(x, r, gap=0.0, period=None):
    """The touching pairs (i < j) by testing every pair, the nearest image along periodic axes."""
    d = x[:, None, :] - x[None, :, :]
    if period is not None:
        L = np.asarray(period, dtype=float)
        d = np.where(L > 0, d - np.where(L > 0, L, 1) * np.round(d / np.where(L > 0, L, 1)), d)
    close = np.linalg.norm(d, axis=2) <= r[:, None] + r[None, :] + gap
    i, j = np.nonzero(np.triu(close, 1))
    return set(zip(i.tolist(), j.tolist(), strict=True))


def triangular_lattice(n, d=1.0):
    """An n × n triangular (hexagonal) lattice of discs of diameter d in its periodic cell
    (n even): every disc touches 6. Positions (n², 3), the cell (3,)."""
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    x = np.stack([(i + 0.5 * (j % 2)) * d, j * d * math.sqrt(3) / 2, 0 * i], axis=-1).reshape(-1, 3).astype(float)
    return x, np.array([n * d, n * d * math.sqrt(3) / 2, 0.0])


def fcc_lattice(n, d=1.0):
    """n³ cubic cells of a face-centred cubic lattice of spheres of diameter d, periodic:
    every sphere touches 12. Positions (4 n³, 3), the cell (3,)."""
    a = d * math.sqrt(2)
    basis = np.array([[0, 0, 0], [0.5, 0.5, 0], [0.5, 0, 0.5], [0, 0.5, 0.5]])
    cells = np.array(list(np.ndindex(n, n, n)), dtype=float)
    return ((cells[:, None, :] + basis[None]) * a).reshape(-1, 3), np.full(3, n * a)


TOUCH = 1e-9  # m: the gap within which a lattice's neighbours touch (their distances are 1 ± rounding)


def with_forces(table, f=1.0):
    """The table with a normal force of size f on i along each normal."""
    return {**table, "force_n": f * table["normal"], "force_t": np.zeros_like(table["normal"])}


# -- the contact table ----------------------------------------------------------------------
def test_the_contacts_found_from_geometry_are_the_pairs_an_every_pair_search_finds():
    # An independent O(N²) search over a random packing, open and periodic, with a gap.
    rng = np.random.default_rng(1)
    x = rng.uniform(0, 5, size=(400, 3))
    r = rng.uniform(0.1, 0.3, size=400)
    for period, gap in [(None, 0.0), ((5.0, 5.0, 0.0), 0.05), ((5.0, 5.0, 5.0), 0.0)]:
        t = analysis.geometric_contacts(x, r, gap=gap, period=period)
        got = set(zip(t["i"].tolist(), t["j"].tolist(), strict=True))
        assert got == brute_pairs(x, r, gap, period) and len(got) > 100
        # the normal points from j to i, the overlap is r_i + r_j − distance, the point lies between
        cell = np.zeros(3) if period is None else np.asarray(period, dtype=float)
        d = analysis.contacts.minimum_image(x[t["i"]] - x[t["j"]], cell)
        dist = np.linalg.norm(d, axis=1)
        np.testing.assert_allclose(t["normal"], d / dist[:, None], rtol=0, atol=1e-15)
        np.testing.assert_allclose(t["overlap"], r[t["i"]] + r[t["j"]] - dist, rtol=0, atol=1e-15)
        np.testing.assert_allclose(t["point"], x[t["i"]] - (r[t["i"]] - t["overlap"] / 2)[:, None] * t["normal"], rtol=0, atol=1e-14)


def test_a_lattice_has_its_closed_form_number_of_contacts():
    # simple cubic, n³ spheres touching: 3 n² (n − 1) pairs open, 3 n³ periodic
    n = 5
    x = np.array(list(np.ndindex(n, n, n)), dtype=float)
    assert len(analysis.geometric_contacts(x, 0.5)["i"]) == 3 * n * n * (n - 1)
    assert len(analysis.geometric_contacts(x, 0.5, period=(n, n, n))["i"]) == 3 * n**3
    # a periodic axis only 2 cells long: each pair still once (the wrapped neighbour is the same cell)
    x2 = np.array(list(np.ndindex(2, 1, 1)), dtype=float)
    assert len(analysis.geometric_contacts(x2, 0.5, period=(2, 0, 0))["i"]) == 1


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            {"force_n": None},
            r"contacts has no 'force_n' \(it has 'i', 'j', 'collider', 'normal'\): the fabric tensor \(min_force=None counts contacts without forces\) needs 'force_n': the normal force on i, N, shape \(K, 3\)",
        ),
        ({"j": [1, 0]}, r"contacts\['j'\]\[0\] = 1 is invalid: a particle cannot touch itself \(j == i\)"),
        ({"j": [5, 0]}, r"contacts\['j'\]\[0\] = 5 is invalid: there are 3 particles \(indices 0..2, or -1\)"),
        ({"collider": [0, -1]}, r"contacts\['collider'\]\[0\] = 0 is invalid: a contact is between particles \(j >= 0, collider = -1\) or against a collider"),
        ({"force_n": np.zeros((2, 2))}, r"contacts\['force_n'\] has shape \(2, 2\); it must be \(2, 3\)"),
        ({"i": [0.0, 1.0]}, r"contacts\['i'\] = .* is invalid: indices must be integers, not float64"),
        ({"force_n": [[np.nan, 0, 0], [0, 0, 1]]}, r"contacts\['force_n'\]\[0\]\[0\] = nan is invalid: it must be finite"),
    ],
)
def test_a_bad_contact_table_is_refused_by_key_value_and_rule(change, message):
    table = {"i": [1, 2], "j": [2, 0], "collider": [-1, -1], "normal": [[1, 0, 0], [0, 1, 0]], "force_n": [[1, 0, 0], [0, 1, 0]]}
    table = {k: v for k, v in {**table, **change}.items() if v is not None}
    with pytest.raises((ValueError, TypeError), match=message):
        analysis.coordination(table, 3)
        analysis.fabric(table)


# -- coordination -----------------------------------------------------------------------------
def test_the_coordination_of_lattices_is_their_closed_form_and_none_rattles():
    # Closed forms: the triangular lattice 6, the face-centred cubic 12 (periodic: every one).
    x, cell = triangular_lattice(8)
    z = analysis.coordination(with_forces(analysis.geometric_contacts(x, 0.5, gap=TOUCH, period=cell)), len(x), dim=2)
    assert z.mean == z.mean_all == 6.0 and not z.rattler.any() and (z.per_particle == 6).all() and z.rounds == 0
    x, cell = fcc_lattice(3)
    z = analysis.coordination(with_forces(analysis.geometric_contacts(x, 0.5, gap=TOUCH, period=cell)), len(x))
    assert z.mean == 12.0 and not z.rattler.any()


def test_rattlers_are_removed_until_none_is_left():
    # A triangular lattice (Z = 6) with two extra discs on top: A rests on two lattice discs
    # and B on A only. In 2D a disc needs d + 1 = 3 contacts: B (1) goes in the first pass,
    # which leaves A with 2, gone in the second. Removing them once would keep A (3 contacts).
    x, cell = triangular_lattice(8)
    n = len(x)
    table = with_forces(analysis.geometric_contacts(x, 0.5, gap=TOUCH, period=cell))
    a, b = n, n + 1
    extra = {"i": [a, a, b], "j": [0, 1, a], "collider": [-1, -1, -1], "normal": [[0, 1, 0]] * 3, "force_n": [[0, 1, 0]] * 3}
    both = {k: np.concatenate([np.asarray(table[k]), np.asarray(extra[k])]) for k in extra}
    z = analysis.coordination(both, n + 2, dim=2)
    assert z.rattler.tolist() == [False] * n + [True, True] and z.rounds == 2
    assert z.mean == 6.0 and z.contacts[a] == 3 and z.contacts[b] == 1
    assert z.mean_all == pytest.approx((6 * n + 2 * 3) / (n + 2), abs=1e-15)  # (2 C) / N before removal
    once = analysis.coordination(both, n + 2, dim=2, min_contacts=2)  # A keeps 2 once B has gone
    assert once.rattler.tolist() == [False] * n + [False, True]


def test_only_force_carrying_contacts_count_and_colliders_when_asked():
    # Three discs in a row on a floor: 0–1 carries 2 N, 1–2 carries nothing (a touching
    # neighbour), each rests on the floor (collider 0).
    table = {
        "i": np.array([0, 1, 0, 1, 2]),
        "j": np.array([1, 2, -1, -1, -1]),
        "collider": np.array([-1, -1, 0, 0, 0]),
        "normal": np.array([[-1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, 1, 0], [0, 1, 0]], dtype=float),
    }
    table["force_n"] = table["normal"] * np.array([2.0, 0.0, 1.0, 1.0, 1.0])[:, None]
    z = analysis.coordination(table, 3, dim=2, min_contacts=0)
    assert z.per_particle.tolist() == [1, 1, 0]
    z = analysis.coordination(table, 3, dim=2, min_contacts=0, colliders=True)
    assert z.per_particle.tolist() == [2, 2, 1] and z.mean == 5 / 3
    z = analysis.coordination(table, 3, dim=2, min_contacts=0, min_force=1.5)
    assert z.per_particle.tolist() == [1, 1, 0]
    assert analysis.coordination({k: table[k] for k in ("i", "j", "collider")}, 3, dim=2, min_contacts=0).per_particle.tolist() == [1, 2, 1]


# -- fabric ---------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("normals", "dim"),
    [
        ([[math.cos(a), math.sin(a), 0] for a in np.arange(3) * math.pi / 3], 2),  # the triangular lattice's 3 directions
        ([[math.cos(a), math.sin(a), 0] for a in np.arange(7) * 2 * math.pi / 7], 2),
        (np.eye(3), 3),  # simple cubic
        ([[1, 1, 0], [1, -1, 0], [1, 0, 1], [1, 0, -1], [0, 1, 1], [0, 1, -1]], 3),  # face-centred cubic
    ],
)
def test_the_fabric_of_an_isotropic_set_of_normals_is_the_identity_over_d(normals, dim):
    # Closed form: for directions whose second moment is isotropic (regular polygons, the
    # cubic lattices' neighbours), F = I/d exactly, trace 1, no anisotropy.
    n = np.asarray(normals, dtype=float)
    n /= np.linalg.norm(n, axis=1)[:, None]
    k = len(n)
    table = {"i": np.arange(k), "j": np.arange(k) + k, "collider": np.full(k, -1), "normal": n}
    f = analysis.fabric(table, dim=dim, min_force=None)
    np.testing.assert_allclose(f.tensor, np.eye(dim) / dim, rtol=0, atol=1e-15)
    assert np.trace(f.tensor) == pytest.approx(1.0, abs=1e-15) and f.anisotropy < 1e-14 and f.count == k


def test_the_fabric_of_a_square_lattice_and_of_chains_is_exact():
    # A periodic square lattice: as many x as y contacts, F = diag(1/2, 1/2). Stretched along y
    # until only the x chains touch: F = diag(1, 0), the largest 2D anisotropy, a = 2.
    n = 6
    x = np.array([[i, j, 0] for i in range(n) for j in range(n)], dtype=float)
    f = analysis.fabric(with_forces(analysis.geometric_contacts(x, 0.5, period=(n, n, 0))), dim=2)
    np.testing.assert_array_equal(f.tensor, np.diag([0.5, 0.5]))
    assert f.count == 2 * n * n
    assert f.anisotropy == 0.0
    x[:, 1] *= 1.5
    f = analysis.fabric(with_forces(analysis.geometric_contacts(x, 0.5, period=(n, 1.5 * n, 0))), dim=2)
    np.testing.assert_array_equal(f.tensor, np.diag([1.0, 0.0]))
    assert f.anisotropy == 2.0 and f.eigenvalues.tolist() == [1.0, 0.0]


@pytest.mark.parametrize("dim", [2, 3])
def test_the_anisotropy_of_normals_drawn_from_a_known_density_is_recovered(dim):
    # Independent: normals drawn (rejection sampling, 400 000 of them) from the density
    # E(n) ∝ 1 + a_ab n_a n_b with a = diag(−q, −q, 2q) in 3D (a_zz − a_xx = 3q), a =
    # diag(q, −q) in 2D; the fabric must give a back. The statistical error of F's entries
    # is ≈ 0.5/√K ≈ 8e-4, of a ≈ d(d+2)/2 times that: 3e-3 in 2D, 6e-3 in 3D; 4 of them allowed.
    rng = np.random.default_rng(3)
    q = 0.3
    a = np.diag([q, -q]) if dim == 2 else np.diag([-q, -q, 2 * q])
    k = 400_000
    n = rng.normal(size=(3 * k, dim))
    n /= np.linalg.norm(n, axis=1)[:, None]
    density = 1 + np.einsum("ka,ab,kb->k", n, a, n)
    n = n[rng.uniform(0, 1 + 2 * q, size=len(n)) < density][:k]
    assert len(n) == k
    normal = np.zeros((k, 3))
    normal[:, :dim] = n
    table = {"i": np.zeros(k, dtype=int), "j": np.ones(k, dtype=int), "collider": np.full(k, -1), "normal": normal}
    f = analysis.fabric(table, dim=dim, min_force=None)
    tol = 4 * 0.5 / math.sqrt(k) * dim * (dim + 2) / 2
    np.testing.assert_allclose(f.anisotropy_tensor, a, rtol=0, atol=tol)
    assert f.anisotropy == pytest.approx(q if dim == 2 else 3 * q, abs=2 * tol)


# -- the force distribution -----------------------------------------------------------------
def test_exponential_forces_give_the_exponential_distribution():
    # Closed form: forces drawn from P(f) = e^(−f/f0)/f0 give P(x) = e^(−x) for x = f/<f> (up
    # to <f> = f0 (1 ± 1/√K)): each bin holds K (e^(−a m/f0) − e^(−b m/f0)) of them, m the
    # measured mean. A chi-square over the 30 bins below x = 6 must pass at 5 standard deviations
    # (χ² < dof + 5 √(2 dof)); a wrong normalisation (by the median, say) fails it by far.
    rng = np.random.default_rng(5)
    f0, k = 3.0, 200_000
    f = rng.exponential(f0, size=k)
    normal = rng.normal(size=(k, 3))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    table = {"i": np.zeros(k, dtype=int), "j": np.ones(k, dtype=int), "collider": np.full(k, -1), "normal": normal, "force_n": f[:, None] * normal}
    edges = np.linspace(0, 6, 31)
    p = analysis.force_distribution(table, bins=edges)
    assert p.mean == pytest.approx(f0, rel=5 / math.sqrt(k))
    expected = k * (np.exp(-edges[:-1] * p.mean / f0) - np.exp(-edges[1:] * p.mean / f0))
    chi2 = float(((p.counts - expected) ** 2 / expected).sum())
    assert chi2 < 30 + 5 * math.sqrt(60), chi2
    np.testing.assert_allclose(p.density * np.diff(edges), p.counts / k, rtol=1e-15)
    # and the density against e^(−x) at the bins' centres: the bin average of e^(−x) is
    # e^(−x_c) sinh(h)/h for half-width h (1 + h²/6), and the counting noise in the first bins
    # is ≈ 1 %
    np.testing.assert_allclose(p.density[:10], np.exp(-p.centers[:10]) * np.sinh(0.1) / 0.1, rtol=0.03)
    # all in: the density integrates to 1
    whole = analysis.force_distribution(table, bins=50)
    assert float((whole.density * np.diff(whole.edges)).sum()) == pytest.approx(1.0, abs=1e-12) and whole.edges[-1] == pytest.approx(f.max() / f.mean())


def test_the_force_distribution_refuses_what_it_cannot_measure():
    table = {"i": [0], "j": [1], "collider": [-1], "normal": [[0, 0, 1]], "force_n": [[0, 0, 0]]}
    with pytest.raises(ValueError, match=r"no contact carries a normal force above min_force = 0.0 N"):
        analysis.force_distribution(table)
    with pytest.raises(ValueError, match=r"part = 'shear' is invalid: it must be one of 'normal', 'tangential', 'total'"):
        analysis.force_distribution(table, part="shear")
    with pytest.raises(ValueError, match=r"contacts has no 'force_t'.*the distribution of tangential forces needs 'force_t'"):
        analysis.force_distribution(table, part="tangential")


# -- the angle of repose ---------------------------------------------------------------------
def cone(angle, height, r, rng, n=20_000):
    """Spheres of radius r filling a cone of the given angle (degrees) and height: their
    centres uniform in its section under the surface, and one in three on it (its top
    touching the cone's surface)."""
    t = math.tan(math.radians(angle))
    R = height / t
    rho = R * np.sqrt(rng.uniform(0, 1, n))
    phi = rng.uniform(0, 2 * math.pi, n)
    surface = height - t * rho - r
    depth = np.where(rng.uniform(0, 1, n) < 1 / 3, 0.0, rng.uniform(0, 1, n) * np.maximum(surface - r, 0))
    z = np.maximum(surface - depth, r)
    return np.stack([rho * np.cos(phi), rho * np.sin(phi), z], axis=1)


@pytest.mark.parametrize("angle", [22.0, 35.0])
def test_the_angle_of_a_synthetic_cone_is_its_angle(angle):
    # Closed form: the tops of the highest spheres lie on the cone h = H − tan θ ρ. In each
    # bin the highest sits within a few hundredths of a bin of its inner edge (≈ 70 surface
    # spheres a bin), so the traced surface is the cone shifted, slope unchanged: θ within 0.3°.
    rng = np.random.default_rng(11)
    x = cone(angle, 1.0, 0.01, rng)
    got = analysis.angle_of_repose(x, 0.01, center=(0, 0, 0))
    assert got.angle == pytest.approx(angle, abs=0.3) and got.height == pytest.approx(1.0, abs=0.02)
    assert got.fitted.sum() >= 10 and got.residual < 0.01
    # the default axis (the mean position) is the cone's, to the sampling's noise
    assert analysis.angle_of_repose(x, 0.01).angle == pytest.approx(angle, abs=0.5)


def test_the_two_flanks_of_a_two_dimensional_heap_are_measured_apart():
    # A 2D heap (discs in x, z) with a 25° left flank and a 40° right one: each flank's own angle.
    rng = np.random.default_rng(12)
    r, H = 0.005, 0.5
    left, right = math.tan(math.radians(25)), math.tan(math.radians(40))
    xs = rng.uniform(-H / left, H / right, 20_000)
    top = H - np.where(xs < 0, -xs * left, xs * right) - r
    z = np.maximum(np.where(rng.uniform(size=len(xs)) < 0.5, top, rng.uniform(r, np.maximum(top, r))), r)
    x = np.stack([xs, 0 * xs, z], axis=1)
    got = analysis.angle_of_repose(x, r, mode="flanks")
    assert got.flanks == pytest.approx((25.0, 40.0), abs=0.3) and got.angle == pytest.approx(32.5, abs=0.3)


def test_the_angle_of_repose_refuses_what_is_not_a_heap():
    with pytest.raises(ValueError, match=r"mode = 'cone' is invalid"):
        analysis.angle_of_repose(np.zeros((5, 3)) + np.arange(5)[:, None], 0.1, mode="cone")
    with pytest.raises(ValueError, match=r"fit = \(0.8, 0.2\) is invalid"):
        analysis.angle_of_repose(np.arange(15.0).reshape(5, 3), 0.1, fit=(0.8, 0.2))
    with pytest.raises(ValueError, match=r"fewer than 2 surface bins"):
        analysis.angle_of_repose(np.array([[0, 0, 0.1], [1, 0, 0.1], [2, 0, 0.1]]), 0.1)


# -- Janssen --------------------------------------------------------------------------------
def test_janssen_pressure_solves_its_force_balance_and_saturates():
    # Closed form: dσ/dz = ρ g − (4 μ_w K / D) σ, σ(0) = 0; hydrostatic near the top, ρ g D/(4 μ_w K) deep down.
    rho, g, D, mu, K = 1500.0, 9.81, 0.1, 0.4, 0.5
    z = np.linspace(0, 1, 2001)
    s = analysis.janssen_pressure(z, rho, g, D, mu, K)
    h = z[1] - z[0]
    slope = (s[2:] - s[:-2]) / (2 * h)  # central difference: error h² σ'''/6 ≈ 1e-4 of ρ g here
    np.testing.assert_allclose(slope, rho * g - 4 * mu * K / D * s[1:-1], rtol=0, atol=2e-4 * rho * g)
    assert s[0] == 0.0 and s[1] == pytest.approx(rho * g * z[1], rel=4 * mu * K / D * z[1])
    assert s[-1] == pytest.approx(rho * g * D / (4 * mu * K), rel=math.exp(-8))
    np.testing.assert_allclose(analysis.janssen_wall_pressure(z, rho, g, D, mu, K), K * s, rtol=1e-15)
    with pytest.raises(ValueError, match=r"mu_w = 0.0 is invalid: it must be finite and > 0"):
        analysis.janssen_pressure(z, rho, g, D, 0.0, K)
    with pytest.raises(ValueError, match=r"z = .* is invalid: depths must be finite and >= 0"):
        analysis.janssen_pressure([-1.0], rho, g, D, mu, K)


def test_the_wall_pressure_of_contacts_carrying_janssen_forces_is_janssen():
    # Synthetic: contacts on a cylinder's wall (collider 1) at 40 heights, one ring of 24 per
    # band at its centre, each pushing K σ_v(depth) times its share of the wall (π D h / 24)
    # and held up by friction at the limit μ_w; a floor's contacts (collider 0) are not the
    # wall's. The measured pressure per band is the closed form at the band's centre, exactly.
    rho, g, D, mu, K, fill = 1500.0, 9.81, 0.1, 0.4, 0.5, 0.8
    edges = np.linspace(0, fill, 41)
    h = edges[1] - edges[0]
    zc = (edges[1:] + edges[:-1]) / 2
    p = analysis.janssen_wall_pressure(fill - zc, rho, g, D, mu, K)
    ring = np.arange(24) * 2 * math.pi / 24
    z, phi = np.meshgrid(zc, ring, indexing="ij")
    inward = -np.stack([np.cos(phi), np.sin(phi), 0 * phi], axis=-1).reshape(-1, 3)
    point = np.stack([D / 2 * np.cos(phi), D / 2 * np.sin(phi), z], axis=-1).reshape(-1, 3)
    size = np.repeat(p, 24) * math.pi * D * h / 24
    k = len(size)
    table = {
        "i": np.arange(k),
        "j": np.full(k + 1, -1),
        "collider": np.r_[np.ones(k, dtype=int), 0],
        "normal": np.r_[inward, [[0, 0, 1]]],
        "point": np.r_[point, [[0, 0, 0]]],
        "force_n": np.r_[size[:, None] * inward, [[0, 0, 99.0]]],
        "force_t": np.r_[np.outer(mu * size, [0, 0, 1]), [[0, 0, 0]]],
    }
    table["i"] = np.r_[table["i"], 0]
    w = analysis.wall_pressure(table, 1, edges=edges, perimeter=math.pi * D)
    np.testing.assert_allclose(w.pressure, p, rtol=1e-12)
    np.testing.assert_allclose(w.shear, mu * p, rtol=1e-12)
    assert (w.count == 24).all()
    assert w.pressure[0] == pytest.approx(rho * g * D / (4 * mu), rel=0.01)  # saturated at the bottom


# -- snapshots ------------------------------------------------------------------------------
def test_a_snapshot_of_a_frame_keeps_the_particles_alive_and_finds_their_contacts():
    # Three discs resting side by side on a floor in a periodic-along-x box; one removed
    # mid-run. The last frame's snapshot holds the two left (by id), the world's snapshot
    # the same state, and their geometric contacts the one touching pair, with the period.
    w = kinema.World(dim=2, dt=2e-5, method="verlet")
    w.add(kinema.Box([0.0, 0.0], [0.06, 1.0]))
    w.periodic = (True, False, False)
    w.add(kinema.Gravity([0, -9.81, 0]))
    w.set_collisions(model="spring_dashpot", stiffness=1e4, restitution=0.3)
    w.add_particles([[0.01, 0.01, 0], [0.03, 0.01, 0], [0.05, 0.01, 0]], radius=0.01, mass=0.001)
    w.run(0.02, fps=100)
    w.remove_particles([1])
    tr = w.run(0.02, fps=100)
    snap = analysis.Snapshot.of_frame(tr, -1)
    now = analysis.Snapshot.of_world(w)
    assert snap.ids.tolist() == now.ids.tolist() == [0, 2] and snap.dim == now.dim == 2
    np.testing.assert_array_equal(snap.positions, now.positions)
    np.testing.assert_array_equal(snap.period, [0.06, 0.0, 0.0])
    pairs = snap.with_geometric_contacts(gap=1e-4).contacts
    # discs 0 and 2 touch across the periodic boundary (x = 0.01 and 0.05, 0.04 apart: 0.02 by the image)
    assert pairs["i"].tolist() == [0] and pairs["j"].tolist() == [1]
    np.testing.assert_allclose(pairs["normal"][0], [1.0, 0.0, 0.0], atol=1e-6)


def test_the_pairs_found_from_geometry_are_the_pairs_the_engine_reports():
    # Independent: the engine's own contact detection (World.contacts() of a Hertz pile of
    # 80 discs settled in a box, periodic along x) against the binned search from the
    # positions alone: the same pairs, the same normals and overlaps.
    rng = np.random.default_rng(8)
    w = kinema.World(dim=2, dt=2e-5)
    w.add(kinema.Box([0.0, 0.0], [0.1, 1.0]))
    w.periodic = (True, False, False)
    w.add(kinema.Gravity([0, -9.81, 0]))
    w.set_collisions(model="hertz", youngs_modulus=1e7, poisson_ratio=0.3, restitution=0.3, friction=0.5)
    grid = np.array(list(np.ndindex(8, 10)), dtype=float)
    x = np.c_[(grid[:, 0] + 0.5) * 0.0125, 0.01 + grid[:, 1] * 0.0125, np.zeros(len(grid))]
    w.add_particles(x, radius=rng.uniform(0.004, 0.006, len(x)), mass=0.001, velocity=np.c_[rng.normal(0, 0.2, (len(x), 2)), np.zeros(len(x))])
    w.step(10_000)
    snap = analysis.Snapshot.of_world(w)
    engine = snap.contacts
    pair = engine["j"] >= 0
    assert pair.sum() > 60
    found = analysis.geometric_contacts(snap.positions, snap.radii, period=snap.period)
    key = {(min(a, b), max(a, b)): k for k, (a, b) in enumerate(zip(engine["i"][pair].tolist(), engine["j"][pair].tolist(), strict=True))}
    assert set(key) == set(zip(found["i"].tolist(), found["j"].tolist(), strict=True))
    order = [key[(a, b)] for a, b in zip(found["i"].tolist(), found["j"].tolist(), strict=True)]
    sign = np.where(engine["i"][pair][order] == found["i"], 1.0, -1.0)
    np.testing.assert_allclose(found["normal"], sign[:, None] * engine["normal"][pair][order], rtol=0, atol=1e-9)
    np.testing.assert_allclose(found["overlap"], engine["overlap"][pair][order], rtol=0, atol=1e-12)
