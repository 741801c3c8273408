"""Force fields (issue 48): turbulence (curl noise), vortex and falloff shapes, seen from Python.

The engine's own tests check the calculus (crates/kinema/src/forces/{turbulence,vortex,
falloff,field}.rs: zero divergence to rounding, Jacobians, the noise's statistics); these
check what a user sees: the falloff's formula in the accelerations, a vortex's tangential
speed profile reached by particles in steady circular motion, turbulence's scale and seed,
2D worlds, scene files and checkpoints, and bad input named.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import kinema
from kinema.checkpoint import load_checkpoint, save_checkpoint


def world(positions, dim=3, **kw):
    w = kinema.World(dim=dim, dt=1e-3, **kw)
    w.add_particles(np.asarray(positions, dtype=float))
    return w


# -- falloff: the formula, exactly --------------------------------------------------------------


def smooth(t):
    return 1.0 - t * t * (3.0 - 2.0 * t)


@pytest.mark.parametrize(
    ("law", "r0", "r1", "expected"),
    [
        ("constant", 0.0, 2.0, lambda d: 1.0 if d <= 2.0 else 0.0),
        ("linear", 0.5, 2.5, lambda d: float(np.clip((2.5 - d) / 2.0, 0.0, 1.0))),
        ("smooth", 0.5, 2.5, lambda d: 1.0 if d <= 0.5 else (0.0 if d > 2.5 else smooth((d - 0.5) / 2.0))),
        ("inverse_square", 0.5, None, lambda d: 1.0 if d <= 0.5 else (0.5 / d) ** 2),
        ("inverse_square", 0.5, 2.0, lambda d: 1.0 if d <= 0.5 else ((0.5 / d) ** 2 if d <= 2.0 else 0.0)),
    ],
)
def test_wind_falloff_is_the_formula(law, r0, r1, expected):
    """A sphere falloff about (1, 0, 0) on a wind: each particle at rest feels φ(d) b w with
    φ the law's formula at its distance d, to rounding, and nothing beyond max_distance."""
    d = np.array([0.0, 0.25, 0.5, 0.75, 1.0, 1.5, 1.99, 2.0, 2.25, 2.5, 2.6, 4.0])
    w = world(np.c_[1.0 + d, np.zeros_like(d), np.zeros_like(d)])
    falloff = kinema.Falloff("sphere", law, r0, r1, center=[1.0, 0.0, 0.0])
    w.add(kinema.Wind([2.0, 0.0, 0.0], 0.5, falloff=falloff))
    want = np.array([expected(x) for x in d])
    np.testing.assert_allclose(w.accelerations[:, 0], 1.0 * want, rtol=1e-14, atol=0)
    assert np.all(w.accelerations[:, 1:] == 0)


def test_tube_and_box_distances():
    """A tube measures across its axis (not along it); a box from its surface, 0 inside."""
    tube = kinema.Falloff("tube", "linear", 0.0, 4.0, center=[0, 0, 0], axis=[0, 0, 1])
    w = world([[1.0, 0.0, 5.0], [0.0, 3.0, -2.0], [3.0, 4.0, 0.0]])
    w.add(kinema.Wind([1.0, 0.0, 0.0], 1.0, falloff=tube))
    np.testing.assert_allclose(w.accelerations[:, 0], [0.75, 0.25, 0.0], rtol=1e-15)
    box = kinema.Falloff("box", "linear", 0.0, 2.0, center=[0, 0, 0], half_size=[1, 1, 1])
    w = world([[0.5, -0.9, 0.2], [2.0, 0.0, 0.0], [2.0, 2.0, 0.0], [4.0, 0.0, 0.0]])
    w.add(kinema.Wind([1.0, 0.0, 0.0], 1.0, falloff=box))
    np.testing.assert_allclose(w.accelerations[:, 0], [1.0, 0.5, 1.0 - math.sqrt(2) / 2, 0.0], rtol=1e-15)


def test_attractor_falloff_centred_on_its_point():
    """An attractor's falloff without a centre is about the attractor's point: Newton's
    μ/d² times (r₀/d)² beyond r₀ = 1."""
    w = world([[3.0, 0.0, 0.0], [1.5, 0.5, 0.0]])
    w.add(kinema.Attractor([1.0, 0.0, 0.0], strength=8.0, falloff=kinema.Falloff(law="inverse_square", min_distance=1.0)))
    a = w.accelerations
    np.testing.assert_allclose(a[0], [-8.0 / 4.0 * (1.0 / 4.0), 0.0, 0.0], rtol=1e-14)
    r = np.array([0.5, 0.5, 0.0])
    np.testing.assert_allclose(a[1], -8.0 * r / np.linalg.norm(r) ** 3, rtol=1e-14)  # within r₀: all of it
    assert "attractor" not in w.diagnostics()["potential"]  # shaped: no potential energy


def test_defaults_unchanged_without_falloff():
    """Wind and Attractor without a falloff are the forces they were: the same numbers."""
    x = np.random.default_rng(1).uniform(-2, 2, (20, 3))
    a, b = world(x), world(x)
    a.add(kinema.Wind([1.0, -2.0, 0.5], 0.7))
    a.add(kinema.Attractor([0.1, 0.2, 0.3], 2.0, 0.1))
    b.add(kinema.Wind([1.0, -2.0, 0.5], 0.7, falloff=None))
    b.add(kinema.Attractor([0.1, 0.2, 0.3], 2.0, 0.1, falloff=None))
    assert np.array_equal(a.accelerations, b.accelerations)
    assert "attractor" in a.diagnostics()["potential"]


# -- vortex: the tangential speed profile --------------------------------------------------------


def test_vortex_field_is_tangential_with_its_profile():
    """At rest in a vortex wind of coefficient b, a particle of mass m feels b U(r) θ̂ / m:
    no radial or axial part, U the profile's closed form."""
    rng = np.random.default_rng(4)
    x = rng.uniform(-3, 3, (200, 3))
    S, R, b = 1.5, 0.8, 2.0
    profiles = {
        "rankine": lambda r: np.where(r <= R, S * r / R, S * R / r),
        "lamb_oseen": lambda r: S * (R / r) * (1 - np.exp(-((r / R) ** 2))) / (1 - math.exp(-1)),
        "constant": lambda r: S + 0 * r,
    }
    for name, U in profiles.items():
        w = world(x)
        w.add(kinema.Vortex([0, 0, 0], [0, 0, 1], S, R, name, coefficient=b))
        a = w.accelerations
        r = np.hypot(x[:, 0], x[:, 1])
        theta = np.c_[-x[:, 1], x[:, 0], np.zeros(len(x))] / r[:, None]
        np.testing.assert_allclose(np.sum(a * theta, axis=1), b * U(r), rtol=1e-13, err_msg=name)
        assert np.max(np.abs(a[:, 2])) == 0.0
        assert np.max(np.abs(np.sum(a[:, :2] * x[:, :2], axis=1))) < 1e-13


def orbit(vortex, mu, r_start, duration, drag=None, v_start=0.0):
    """A particle released at r_start with the tangential speed v_start in a vortex, pulled
    in by an attractor of μ: its final radius, tangential and radial speeds (2D world, the
    vortex about z)."""
    w = kinema.World(dim=2, dt=2e-3, method="rk4")
    w.add_particles([[r_start, 0.0, 0.0]], velocity=[0.0, v_start, 0.0])
    w.add(vortex)
    w.add(kinema.Attractor([0, 0, 0], mu))
    if drag is not None:
        w.add(kinema.Drag(linear=drag))
    w.step(int(duration / w.dt))
    x, v = w.positions[0], w.velocities[0]
    r = math.hypot(x[0], x[1])
    return r, (x[0] * v[1] - x[1] * v[0]) / r, (x[0] * v[0] + x[1] * v[1]) / r


def test_vortex_wind_settles_on_its_profile():
    """Theory: in a vortex wind (coefficient b) and an attractor's pull μ/r², a particle
    settles on the circle where the air's speed U(r) keeps it in orbit: tangentially the wind
    force b (U − v_θ) vanishes, so v_θ = U(r), and radially v_θ²/r = μ/r². For the Rankine
    profile outside the core, U = S R/r gives r* = (S R)²/μ, v* = S R/r* (a stable circle:
    U² r falls with r). Here r* = 0.5 m; measured after 40 s (b/m = 2/s): both to 1e-9."""
    R, mu = 0.2, 0.25
    S = math.sqrt(0.125) / R
    r, v, vr = orbit(kinema.Vortex(strength=S, radius=R, coefficient=2.0), mu, 0.6, 40.0)
    r_star = (S * R) ** 2 / mu
    assert r == pytest.approx(r_star, rel=1e-9) and v == pytest.approx(S * R / r_star, rel=1e-9)
    assert abs(vr) < 1e-9


def test_vortex_acceleration_with_drag_settles_on_its_profile():
    """Theory: a vortex acceleration a_θ(r) against linear drag c (m = 1) gives the terminal
    tangential speed v_θ = a_θ(r)/c; with the attractor, v_θ²/r = μ/r², so r* solves
    (a_θ(r)/c)² r = μ where that falls with r (inside a solid core the circle is unstable:
    the centrifugal pull grows with r). Rankine outside the core: r* = (S R/c)²/μ; Lamb–Oseen:
    r* by bisection on the profile's outer branch. Both radius and speed to 1e-8 after 40 s."""
    S, R, c = math.sqrt(0.125) / 0.1, 0.2, 2.0
    r, v, _ = orbit(kinema.Vortex(strength=S, radius=R), 0.25, 0.6, 40.0, drag=c)
    r_star = (S * R / c) ** 2 / 0.25
    assert r_star > R
    assert r == pytest.approx(r_star, rel=1e-8) and v == pytest.approx(S * R / r_star / c, rel=1e-8)

    def U(r):
        return S * (R / r) * (1 - math.exp(-((r / R) ** 2))) / (1 - math.exp(-1))

    mu = 0.75
    lo, hi = 0.3, 5.0  # (U/c)² r − μ falls through 0 once here, beyond the peak of U² r
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if (U(mid) / c) ** 2 * mid > mu else (lo, mid)
    # started near the circle (from rest it would fall past the profile's peak and be flung out)
    r, v, _ = orbit(kinema.Vortex(strength=S, radius=R, profile="lamb_oseen"), mu, 1.1 * lo, 40.0, drag=c, v_start=U(lo) / c)
    assert r == pytest.approx(lo, rel=1e-8) and v == pytest.approx(U(lo) / c, rel=1e-8)


# -- turbulence ------------------------------------------------------------------------------------


def sample(turbulence, dim=3, n=20_000, half=40.0, seed=0):
    rng = np.random.default_rng(seed)
    x = rng.uniform(-half, half, (n, 3))
    if dim == 2:
        x[:, 2] = 0.0
    w = world(x, dim=dim)
    w.add(turbulence)
    return x, w.accelerations


def test_turbulence_strength_is_the_rms_per_axis():
    """Theory: `strength` is the rms of each component; the mean is 0. Over 20 000 points
    spread over many cells: within 4% (the sampling error is about 1%)."""
    for dim in (3, 2):
        _, a = sample(kinema.Turbulence(strength=3.0, scale=0.5, seed=1), dim=dim)
        rms = np.sqrt(np.mean(a[:, :dim] ** 2, axis=0))
        np.testing.assert_allclose(rms, 3.0, rtol=0.04)
        assert np.all(np.abs(a[:, :dim].mean(axis=0)) < 0.1)
        if dim == 2:
            assert np.all(a[:, 2] == 0)


def test_turbulence_scale_seed_and_coupling():
    """The field of scale L at x is the field of scale 1 at x/L (bit for bit for L = 4); the
    same seed gives the same bits, another seed another field; as a wind it is b (u − v)/m."""
    x, a4 = sample(kinema.Turbulence(scale=4.0, seed=7), n=500)
    w = world(x / 4.0)
    w.add(kinema.Turbulence(scale=1.0, seed=7))
    assert np.array_equal(a4, w.accelerations)
    _, again = sample(kinema.Turbulence(scale=4.0, seed=7), n=500)
    _, other = sample(kinema.Turbulence(scale=4.0, seed=8), n=500)
    assert np.array_equal(a4, again) and not np.allclose(a4, other)
    w = world(x / 4.0)
    w.add_particles([[0.0, 0.0, 0.0]], mass=2.0, velocity=[1.0, 0.0, 0.0])
    w.add(kinema.Turbulence(scale=1.0, seed=7, coefficient=3.0))
    a = w.accelerations
    np.testing.assert_allclose(a[:-1], 3.0 * np.asarray(again), rtol=1e-14)  # u at rest, b = 3, m = 1


def test_turbulence_divergence_from_python():
    """Central differences of the accelerations (an acceleration field: a = u) at 200 random
    points: |∇·u| ≤ 1e-6 of |∇u| (the difference's O(h²) error; the engine's test checks the
    analytic Jacobian's trace to 1e-13)."""
    rng = np.random.default_rng(3)
    x = rng.uniform(-5, 5, (200, 3))
    t = kinema.Turbulence(strength=1.0, scale=0.7, seed=2, octaves=2)
    h = 1e-5
    div = np.zeros(len(x))
    grad = np.zeros(len(x))
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        up, down = world(x + e), world(x - e)
        up.add(t)
        down.add(t)
        d = (up.accelerations - down.accelerations) / (2 * h)
        div += d[:, k]
        grad = np.maximum(grad, np.max(np.abs(d), axis=1))
    assert np.max(np.abs(div) / grad) < 1e-6


def test_turbulence_moves_particles_without_bunching():
    """Particles carried by a strong turbulent wind (b/m = 50/s, so they follow u) spread over
    a periodic-free region keep their density: the mean distance to the nearest neighbour
    changes by less than 10% over 2 s in which they travel several feature sizes."""
    rng = np.random.default_rng(5)
    x = rng.uniform(-2, 2, (400, 3))
    x[:, 2] = 0
    w = kinema.World(dim=2, dt=2e-3, method="rk4")
    w.add_particles(x)
    w.add(kinema.Turbulence(strength=1.0, scale=1.0, seed=4, coefficient=50.0))

    def spacing(p):
        d = np.linalg.norm(p[:, None, :2] - p[None, :, :2], axis=2)
        np.fill_diagonal(d, np.inf)
        inner = np.all(np.abs(p[:, :2] - p[:, :2].mean(axis=0)) < 1.0, axis=1)
        return d.min(axis=1)[inner].mean()

    before = spacing(w.positions.copy())
    start = w.positions.copy()
    w.step(1000)
    travelled = np.linalg.norm(w.positions - start, axis=1).mean()
    assert travelled > 1.0
    assert abs(spacing(w.positions.copy()) / before - 1) < 0.1


# -- scene files, checkpoints, bad input -----------------------------------------------------------


def fields_world(dim=3):
    rng = np.random.default_rng(9)
    w = world(rng.uniform(-1, 1, (30, 3)) * ([1, 1, 1] if dim == 3 else [1, 1, 0]), dim=dim)
    w.add(
        kinema.Turbulence(
            strength=2,
            scale=0.5,
            seed=3,
            time_scale=0.7,
            octaves=2,
            coefficient=0.3,
            falloff=kinema.Falloff("box", "linear", 0.1, 2.0, center=[0, 0, 0.5], half_size=[1, 1, 1]),
        )
    )
    w.add(kinema.Vortex([0.1, 0, 0], strength=-1, radius=0.5, profile="lamb_oseen", falloff=kinema.Falloff("tube", "smooth", 0.5, 2.0)))
    w.add(kinema.Wind([1, 0, 0], 0.5, falloff=kinema.Falloff(center=[0, 0, 0], max_distance=1)))
    w.add(kinema.Attractor(falloff=kinema.Falloff(law="inverse_square", min_distance=0.5)))
    return w


@pytest.mark.parametrize("dim", [2, 3])
def test_scene_round_trip(dim):
    """World.to_scene writes the fields and their falloffs (a centre left out stays the
    force's own); the scene read back builds the same forces: the same accelerations, bit for
    bit, at a later time too."""
    w = fields_world(dim)
    text = w.to_scene().to_toml_string()
    assert 'type = "turbulence"' in text and 'type = "vortex"' in text and "[forces.falloff]" in text
    back = kinema.Scene.from_string(text).build()
    assert [type(f) for f in back.forces] == [type(f) for f in w.forces]
    assert [f.falloff for f in back.forces] == [f.falloff for f in w.forces]
    assert np.array_equal(back.accelerations, w.accelerations)
    w.step(50)
    back.step(50)
    assert np.array_equal(w.positions, back.positions)


def test_checkpoint_round_trip(tmp_path):
    """A checkpoint holds the fields (through the scene): the run resumed from it is the same
    bits as the run that wrote it."""
    w = fields_world()
    w.step(20)
    path = save_checkpoint(w, tmp_path / "fields.h5")
    back = load_checkpoint(path)
    w.step(30)
    back.step(30)
    assert np.array_equal(w.positions, back.positions)


def test_scene_file_table():
    """A scene's [[forces]] entries of type turbulence and vortex, with falloff sub-tables."""
    text = """
[world]
dim = 3
dt = 0.001
[[particles]]
type = "list"
positions = [[0.5, 0.0, 0.0], [3.0, 0.0, 0.0]]
[[forces]]
type = "vortex"
strength = 2.0
radius = 1.0
falloff = { shape = "tube", law = "linear", min_distance = 1.0, max_distance = 2.0 }
[[forces]]
type = "turbulence"
strength = 0.0
scale = 2.0
seed = 5
"""
    w = kinema.Scene.from_string(text).build()
    assert isinstance(w.forces[0], kinema.Vortex) and w.forces[0].falloff == kinema.Falloff("tube", "linear", 1.0, 2.0)
    np.testing.assert_allclose(w.accelerations, [[0.0, 1.0, 0.0], [0.0, 0.0, 0.0]], atol=1e-15)
    with pytest.raises(kinema.SceneError, match="falloff"):
        kinema.Scene.from_string(text.replace('law = "linear"', 'law = "cubic"'))


@pytest.mark.parametrize(
    ("make", "error", "match"),
    [
        (lambda: kinema.Turbulence(scale=0.0), ValueError, r"scale = 0 is invalid: the turbulence scale \(feature size\) must be finite and > 0 m"),
        (lambda: kinema.Turbulence(strength=-1.0), ValueError, r"strength = -1 is invalid"),
        (lambda: kinema.Turbulence(octaves=0), ValueError, r"octaves = 0 is invalid: it must be an integer from 1 to 8"),
        (lambda: kinema.Turbulence(seed=-1), ValueError, r"seed = -1 is invalid: the seed must be an integer from 0 to 2\*\*63 - 1"),
        (lambda: kinema.Turbulence(roughness=2.0), ValueError, r"roughness = 2 is invalid: the roughness must be in \[0, 1\]"),
        (lambda: kinema.Turbulence(time_scale=0.0), ValueError, r"time_scale = 0 is invalid"),
        (lambda: kinema.Turbulence(scale="big"), TypeError, r"scale = 'big' is invalid"),
        (lambda: kinema.Vortex(radius=0.0), ValueError, r"radius = 0 is invalid: the vortex core radius must be finite and > 0 m"),
        (lambda: kinema.Vortex(axis=[0, 0, 0]), ValueError, r"axis = \[0.0, 0.0, 0.0\] is invalid"),
        (lambda: kinema.Vortex(profile="burgers"), ValueError, r"profile = 'burgers' is invalid: it must be one of 'rankine', 'lamb_oseen', 'constant'"),
        (lambda: kinema.Vortex(coefficient=-1.0), ValueError, r"coefficient = -1 is invalid"),
        (lambda: kinema.Falloff(shape="cone"), ValueError, r"shape = 'cone' is invalid: it must be one of 'sphere', 'tube', 'box'"),
        (lambda: kinema.Falloff(law="linear"), ValueError, r"max_distance = None is invalid: a linear falloff needs a finite max_distance"),
        (lambda: kinema.Falloff(law="inverse_square"), ValueError, r"min_distance = 0.0 is invalid: the inverse-square law needs min_distance > 0"),
        (lambda: kinema.Falloff("box", max_distance=1.0), ValueError, r"half_size = None is invalid: a box falloff needs"),
        (lambda: kinema.Falloff(max_distance=1.0, min_distance=2.0), ValueError, r"max_distance = 1.0 is invalid: .*> min_distance"),
        (lambda: kinema.Wind(falloff=kinema.Falloff(max_distance=1.0)), ValueError, r"falloff.center = None is invalid: a Wind has no point of its own"),
        (lambda: kinema.Wind(falloff="sphere"), TypeError, r"falloff = 'sphere' is invalid: it must be a kinema.Falloff or None"),
        (lambda: kinema.Vortex(falloff=kinema.Falloff("tube", max_distance=1.0, axis=[0, 0, 0])), ValueError, r"falloff.axis = \[0.0, 0.0, 0.0\] is invalid"),
    ],
)
def test_bad_input_is_named(make, error, match):
    with pytest.raises(error, match=match):
        world([[0.0, 0.0, 0.0]]).add(make())


def test_a_2d_vortex_turns_about_z():
    w = world([[1.0, 0.0, 0.0]], dim=2)
    with pytest.raises(ValueError, match=r"axis = \[1, 0\] is invalid: in a 2D world \(the xy-plane\) a vortex turns about z"):
        w.add(kinema.Vortex(axis=[1, 0]))
    w.add(kinema.Vortex(axis=[0, 0, -2], strength=1.0, radius=1.0))
    np.testing.assert_allclose(w.accelerations, [[0.0, -1.0, 0.0]], atol=1e-15)
