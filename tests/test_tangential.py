"""Tangential contacts with memory in the force models (``spring_dashpot``, ``hertz`` with
``friction``): LAMMPS's ``linear_history`` and ``mindlin`` springs capped by Coulomb's μ |F_n|,
``rolling sds`` and ``twisting marshall``, the torques they give stepped by Verlet
(collide/contact_force/tangent.rs, history.rs).

Each physics test compares with a closed form and says which: a block held on a slope by the
spring's static stretch (k_t ξ = m g sin θ; Mindlin's k_t = 8 G* a with Hertz's static overlap),
a block sliding at g (sin θ − μ cos θ), a ball rolling down a slope at g sin θ / (1 + I/(m ρ²))
and one thrown along a floor rolling at last at v₀ / (1 + I/(m ρ²)) (ρ = r − δ the lever arm at
the static overlap δ), rolling resistance slowing a ball at μ_r g (r/ρ) / (1 + I/(m ρ²)), and the
conservation of momentum and angular momentum (orbital and spin) in an elastic rough gas whose
pairs cross the chunks of the pair pass. Then: piles come to rest, checkpoints resume bit for
bit, the thread count changes no bit, and the refusals name their parameter.
"""

import hashlib
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import kinema

G = 9.81
R = 0.005
M = 1e-3
K_N = 1e4


def slope(theta_deg, spin=False, dim=3):
    """The slope's unit normal, the direction down it, and gravity."""
    th = np.radians(theta_deg)
    if dim == 3:
        return np.array([-np.sin(th), 0.0, np.cos(th)]), -np.array([np.cos(th), 0.0, np.sin(th)]), [0.0, 0.0, -G]
    return np.array([-np.sin(th), np.cos(th), 0.0]), -np.array([np.cos(th), np.sin(th), 0.0]), [0.0, -G, 0.0]


def on_slope(theta_deg, mu, spin=False, dim=3, dt=1e-5, model="spring_dashpot", overlap=None, **collisions):
    """A particle resting at its static overlap on a slope through the origin, under gravity."""
    normal, down, g = slope(theta_deg, dim=dim)
    w = kinema.World(dim=dim, dt=dt, method="verlet", spin=spin)
    w.add(kinema.Plane([0.0, 0.0, 0.0], normal))
    w.add(kinema.Gravity(g))
    if model == "spring_dashpot":
        w.set_collisions(model=model, stiffness=K_N, restitution=0.3, friction=mu, **collisions)
    else:
        w.set_collisions(model=model, restitution=0.3, friction=mu, **collisions)
    delta = overlap if overlap is not None else M * G * np.cos(np.radians(theta_deg)) / K_N
    w.add_particles((R - delta) * normal, mass=M, radius=R)
    return w, normal, down, delta


def test_a_block_inside_the_cone_holds_with_the_springs_static_stretch():
    # tan θ < μ: the contact sticks, and at rest the spring holds the block: k_t ξ = m g sin θ,
    # ξ its displacement down the slope since it touched (the spring starts unstretched; at
    # 10° its first swing, to 2 ξ, stays inside the cone, so it never slips).
    th = 10.0
    for k_t in (None, 500.0):
        w, normal, down, _ = on_slope(th, 0.5, tangential_stiffness=k_t)
        x0 = w.positions[0].copy()
        w.step(30_000)  # 0.3 s: the springs' ringing long gone
        kt = 2 / 7 * K_N if k_t is None else k_t
        closed = M * G * np.sin(np.radians(th)) / kt
        moved = (w.positions[0] - x0) @ down
        assert abs(moved / closed - 1) < 1e-9, (moved, closed)
        assert np.abs(w.velocities[0]).max() < 1e-12
        # the spring the contact remembers: ξ down the slope
        (_, _, n, springs) = w._core.contact_history()[1][0]
        np.testing.assert_allclose(springs[:3], closed * down, rtol=1e-9, atol=1e-9 * closed)


def test_a_block_that_slipped_into_place_holds_with_the_same_stretch():
    # At 20° the first swing (2 m g sin θ) leaves the cone: the block slips, the spring is
    # cut to the cone's edge, and the block comes to rest further down; the spring at rest
    # still holds exactly k_t ξ = m g sin θ.
    th = 20.0
    w, normal, down, _ = on_slope(th, 0.5)
    x0 = w.positions[0].copy()
    w.step(30_000)
    closed = M * G * np.sin(np.radians(th)) / (2 / 7 * K_N)
    assert (w.positions[0] - x0) @ down > 1.01 * closed  # it slipped
    (_, _, n, springs) = w._core.contact_history()[1][0]
    np.testing.assert_allclose(springs[:3], closed * down, rtol=1e-9, atol=1e-9 * closed)
    assert np.abs(w.velocities[0]).max() < 1e-12


def test_mindlin_holds_a_block_with_its_stiffness_from_the_contact_radius():
    # Hertz (E, ν) with Mindlin's k_t = 8 G* a: the normal overlap δ from m g cos θ =
    # 4/3 E* √r δ^(3/2) (E* = E/(2(1 − ν²)) against the plane's own E*), a = √(r δ), and the
    # static stretch ξ = m g sin θ / (8 G* a), G* = E / (4 (2 − ν)(1 + ν)).
    e, nu, th = 1e7, 0.3, 15.0
    e_star = e / (2 * (1 - nu * nu))
    fn = M * G * np.cos(np.radians(th))
    delta = (fn / (4 / 3 * e_star * np.sqrt(R))) ** (2 / 3)
    w, normal, down, _ = on_slope(th, 0.5, model="hertz", youngs_modulus=e, poisson_ratio=nu, overlap=delta)
    x0 = w.positions[0].copy()
    w.step(30_000)
    g_star = e / (4 * (2 - nu) * (1 + nu))
    closed = M * G * np.sin(np.radians(th)) / (8 * g_star * np.sqrt(R * delta))
    moved = (w.positions[0] - x0) @ down
    # (the stiffness follows the overlap, which settles to δ; the stretch to 1e-6 of it)
    assert abs(moved / closed - 1) < 1e-6, (moved, closed)


@pytest.mark.parametrize("dim", [3, 2])
def test_a_block_beyond_the_cone_slides_at_g_sin_minus_mu_cos(dim):
    # tan θ > μ: the spring sits at the cone's edge, F_t = μ F_n = μ m g cos θ once the normal
    # ringing is gone: a = g (sin θ − μ cos θ), constant.
    th, mu = 35.0, 0.5
    w, normal, down, _ = on_slope(th, mu, dim=dim)
    w.step(20_000)
    v0, t0 = w.velocities[0] @ down, w.time
    w.step(10_000)
    a = (w.velocities[0] @ down - v0) / (w.time - t0)
    closed = G * (np.sin(np.radians(th)) - mu * np.cos(np.radians(th)))
    assert abs(a / closed - 1) < 1e-9, (a, closed)


@pytest.mark.parametrize("dim", [3, 2])
def test_a_ball_rolls_down_a_slope_at_g_sin_over_one_plus_i_over_m_rho_squared(dim):
    # μ > 2/7 tan θ: the contact point sticks (its spring at a constant stretch, F = m g sin θ −
    # m a), and the ball rolls about the contact point at the lever arm ρ = r − δ:
    # a = g sin θ / (1 + I/(m ρ²)), I = 2/5 m r² (3D) or 1/2 m r² (a disc).
    th = 20.0
    w, normal, down, delta = on_slope(th, 0.5, spin=True, dim=dim)
    w.step(20_000)
    v0, t0 = w.velocities[0] @ down, w.time
    w.step(10_000)
    a = (w.velocities[0] @ down - v0) / (w.time - t0)
    rho = R - delta
    inertia = (0.4 if dim == 3 else 0.5) * M * R * R
    closed = G * np.sin(np.radians(th)) / (1 + inertia / (M * rho * rho))
    assert abs(a / closed - 1) < 1e-7, (a, closed)
    # and the contact point rolls: v = ω × (ρ n)
    v, om = w.velocities[0], w.angular_velocities[0]
    assert np.linalg.norm(v + np.cross(om, -rho * normal)) < 1e-7 * np.linalg.norm(v)


def thrown(rolling=0.0, v0=1.0, mu=0.3, t=0.4, **collisions):
    """A ball on a floor thrown along x without spin; its speed and spin at the end."""
    w, normal, _, delta = on_slope(0.0, mu, spin=True, rolling_friction=rolling, **collisions)
    w.velocities[0] = [v0, 0.0, 0.0]
    w.step(int(round(t / w.dt)))
    return w, delta


def test_a_ball_thrown_along_a_floor_slides_into_rolling_at_five_sevenths():
    # Angular momentum about the contact point is kept while it slides (friction acts there):
    # m v₀ ρ = m v ρ + I ω with v = ω ρ ⇒ v* = v₀ / (1 + I/(m ρ²)) ≈ 5/7 v₀.
    w, delta = thrown()
    rho = R - delta
    closed = 1.0 / (1 + 0.4 * R * R / (rho * rho))
    v, om = w.velocities[0], w.angular_velocities[0]
    assert abs(v[0] / closed - 1) < 1e-9, (v[0], closed)
    assert abs(om[1] * rho / v[0] - 1) < 1e-9


def test_rolling_resistance_slows_a_rolling_ball_at_its_closed_form():
    # Rolling sds at its cap: a couple μ_r r m g against the turning (R* = r at the floor),
    # friction F at the contact keeps it rolling: m a = −F, I α = F ρ − μ_r m g r, a = α ρ
    # ⇒ a = −μ_r g (r/ρ) / (1 + I/(m ρ²)).
    mu_r = 0.01
    w, delta = thrown(rolling=mu_r, t=0.3, v0=2.0)  # (rolling from 0.19 s)
    v1, t1 = w.velocities[0, 0], w.time
    w.step(10_000)
    a = (w.velocities[0, 0] - v1) / (w.time - t1)
    rho = R - delta
    closed = -mu_r * G * (R / rho) / (1 + 0.4 * R * R / (rho * rho))
    assert abs(a / closed - 1) < 1e-7, (a, closed)


def rough_gas(n, dim, seed=3):
    """An elastic rough gas (e = 1: no dashpots; μ = 0.5): n particles of mixed radii drawn
    towards each other in open space, spinning."""
    rng = np.random.default_rng(seed)
    w = kinema.World(dim=dim, dt=2e-5, method="verlet", spin=True)
    side = int(np.ceil(n ** (1 / dim)))
    idx = np.array(np.unravel_index(np.arange(n), (side,) * dim)).T.astype(float)
    x = np.zeros((n, 3))
    x[:, :dim] = idx * 2.7 * R + rng.uniform(-0.1, 0.1, (n, dim)) * R
    v = np.zeros((n, 3))
    v[:, :dim] = -(x[:, :dim] - x[:, :dim].mean(0)) * 5.0 + rng.normal(0, 0.3, (n, dim))
    om = np.zeros((n, 3))
    if dim == 3:
        om[:] = rng.normal(0, 50, (n, 3))
    else:
        om[:, 2] = rng.normal(0, 50, n)
    radii = R * rng.uniform(0.8, 1.2, n)
    w.set_collisions(model="spring_dashpot", stiffness=K_N, restitution=1.0, friction=0.5)
    w.add_particles(x, velocity=v, mass=M * (radii / R) ** 3, radius=radii, angular_velocity=om)
    return w


@pytest.mark.parametrize("n, dim", [(300, 3), (300, 2), (3000, 3)])
def test_an_elastic_rough_gas_keeps_momentum_and_angular_momentum(n, dim):
    # Each contact's tangential force acts on both at the one contact point (the arms split
    # the distance of centres) and its couples are equal and opposite: Σ m v and
    # Σ (x × m v + I ω) are kept to rounding, through sliding and sticking, across the chunks
    # of the pair pass (3,000 particles: two chunks, torques sent between them).
    w = rough_gas(n, dim)
    d0 = w.diagnostics()
    scale = np.sum(np.abs(np.cross(w.positions, w.masses[:, None] * w.velocities))) + np.sum(np.abs(w.inertia[:, None] * w.angular_velocities))
    w.step(1500)
    d1 = w.diagnostics()
    assert w.collision_stats()["total"]["impacts"] > n // 10  # (the gas collides)
    spin = np.abs(w.angular_velocities).max()
    assert spin > 0
    np.testing.assert_allclose(d1["momentum"], d0["momentum"], rtol=0, atol=1e-13 * np.sum(w.masses * np.linalg.norm(w.velocities, axis=1)) + 1e-18)
    np.testing.assert_allclose(d1["angular_momentum"], d0["angular_momentum"], rtol=0, atol=1e-12 * scale)
    # the gas did collide with friction: rotation and translation exchanged energy
    e0 = d0["kinetic"] + d0["rotational"]
    assert abs(d1["rotational"] - d0["rotational"]) > 1e-3 * e0


def pile(n, dim, seed=0, mu=0.5, rolling=0.1):
    """Particles dropped from a loose lattice onto a floor, with friction and rolling
    resistance, spinning."""
    rng = np.random.default_rng(seed)
    w = kinema.World(dim=dim, dt=3e-5, method="verlet", spin=True)
    up = 1 if dim == 2 else 2
    g = [0.0, 0.0, 0.0]
    g[up] = -G
    normal = [0.0, 0.0, 0.0]
    normal[up] = 1.0
    w.add(kinema.Gravity(g))
    w.add(kinema.Plane([0, 0, 0], normal))
    w.set_collisions(model="spring_dashpot", stiffness=K_N, restitution=0.5, friction=mu, rolling_friction=rolling)
    width = int(np.ceil(np.sqrt(n))) if dim == 2 else 5
    k = np.arange(n)
    x = np.zeros((n, 3))
    x[:, 0] = (k % width) * 2.5 * R + rng.uniform(-0.1, 0.1, n) * R
    if dim == 2:
        x[:, 1] = (1.2 + (k // width) * 2.5) * R
    else:
        x[:, 1] = ((k // width) % width) * 2.5 * R
        x[:, 2] = (1.2 + (k // width**2) * 2.5) * R
    radii = R * rng.uniform(0.9, 1.1, n)
    w.add_particles(x, mass=M * (radii / R) ** 3, radius=radii)
    return w


@pytest.mark.parametrize("n, dim, seed", [(240, 2, 0), (600, 2, 1), (300, 3, 2)])
def test_a_pile_with_friction_and_rolling_resistance_comes_to_rest(n, dim, seed):
    # A heap held by static friction (the springs' memory) and rolling resistance stops: no
    # creep, no boiling. (Without memory a force-model heap keeps creeping.)
    w = pile(n, dim, seed)
    w.step(int(2.5 / w.dt))
    assert np.abs(w.velocities).max() < 1e-5, np.abs(w.velocities).max()
    assert np.abs(w.angular_velocities).max() * R < 1e-5
    # and it stands: higher than one layer (a frictionless heap spreads flat)
    up = 1 if dim == 2 else 2
    assert w.positions[:, up].max() > 4 * R


def test_a_checkpoint_resumes_the_springs_and_the_spin_bit_for_bit(tmp_path):
    # The contacts' memory and Verlet's α go into the checkpoint; the world read back goes on
    # as the one that wrote it, to every bit.
    a = pile(240, 2, seed=4)
    a.step(4000)
    assert len(a._core.contact_history()[0]) > 50  # it holds springs
    a.save_checkpoint(tmp_path / "p.ckpt")
    b = kinema.World.load_checkpoint(tmp_path / "p.ckpt")
    for w in (a, b):
        w.step(3000)
    assert np.array_equal(a.positions, b.positions)
    assert np.array_equal(a.velocities, b.velocities)
    assert np.array_equal(a.angular_velocities, b.angular_velocities)


THREADS = textwrap.dedent(
    """
    import hashlib, sys
    import numpy as np
    sys.path.insert(0, {tests!r})
    from test_tangential import pile
    w = pile(2600, 3, seed=5)
    w.step(1500)
    print(hashlib.sha256(w.positions.tobytes() + w.velocities.tobytes() + w.angular_velocities.tobytes()).hexdigest())
    """
)


def test_the_thread_count_changes_no_bit():
    # The tangential pass keeps the forces' order (chunks, then what earlier chunks sent), and
    # the torques the same way: 1 and 2 threads give the same bits (2,600 particles: two chunks).
    code = THREADS.format(tests=os.path.dirname(__file__))
    out = {}
    for t in (1, 2):
        env = {**os.environ, "RAYON_NUM_THREADS": str(t)}
        res = subprocess.run([sys.executable, "-W", "ignore", "-c", code], env=env, capture_output=True, text=True, timeout=600)
        assert res.returncode == 0, res.stderr
        out[t] = res.stdout.strip()
    assert out[1] == out[2], out
    assert len(out[1]) == 64 and out[1] != hashlib.sha256(b"").hexdigest()


def test_the_refusals_name_their_parameter():
    w = kinema.World(dt=1e-4, method="rk4")
    w.add_particles([[0, 0, 0], [0.0095, 0, 0]], radius=R, mass=M)
    w.set_collisions(model="spring_dashpot", stiffness=K_N, friction=0.3)
    with pytest.raises(ValueError, match=r"method = 'rk4' is invalid: contacts with friction under a force model"):
        w.step()
    w.set_collisions(model="spring_dashpot", stiffness=K_N, friction=0.0)
    w.step()  # (no friction: any method)
    v = kinema.World(dt=1e-4)
    with pytest.raises(ValueError, match=r"tangential = 'mindlin' is invalid: .*model='hertz'"):
        v.set_collisions(model="spring_dashpot", stiffness=K_N, tangential="mindlin")
    with pytest.raises(ValueError, match=r"tangential_stiffness = 100 is invalid: only the force models"):
        v.set_collisions(tangential_stiffness=100.0)
    with pytest.raises(ValueError, match=r"tangential_stiffness = None is invalid: model='hertz' with tangential='linear_history' needs"):
        v.set_collisions(model="hertz", youngs_modulus=1e7, tangential="linear_history")
    with pytest.raises(ValueError, match=r"tangential_damping = -1 is invalid"):
        v.set_collisions(model="spring_dashpot", stiffness=K_N, tangential_damping=-1.0)
    with pytest.raises(ValueError, match=r"tangential = 'coulomb' is invalid"):
        v.set_collisions(model="spring_dashpot", stiffness=K_N, tangential="coulomb")
    # the settings read back and round-trip
    v.set_collisions(model="hertz", youngs_modulus=1e7, friction=0.4, tangential="mindlin", tangential_damping=0.2)
    assert v.collisions["tangential"] == "mindlin" and v.collisions["tangential_damping"] == 0.2
    v.set_collisions(**v.collisions)
