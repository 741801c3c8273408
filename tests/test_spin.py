"""Spin in the impulse model (``World(spin=True)``): impulses act at the contact point, friction
acts on the contact point's velocity v + ω × a, and both bodies turn (collide/spin.rs).

Each physics test compares with a closed form and says which: rolling without slipping on a
slope (a = g sin θ / (1 + I/(m r²))), sliding into rolling on a floor (Coulomb friction until
v = ω r: t* = 2 v₀ / (7 μ g), v* = 5/7 v₀), the oblique impact of a spinning sphere on a wall
(Walton's rule as Brilliantov & Pöschel write it, with the tangential restitution of the
impulse model's sticking, β₀ = 0), and the conservation of angular momentum (orbital and
spin) and of the energy books in an elastic rough gas.
"""

import numpy as np
import pytest

import kinema

G = 9.81


def slope_world(theta_deg, mu, method="verlet", dim=3, inertia=None, dt=1e-3):
    """A ball (a disc in 2D) resting on a slope through the origin, under gravity; returns the
    world and the unit vector down the slope."""
    th = np.radians(theta_deg)
    w = kinema.World(dim=dim, dt=dt, method=method, spin=True)
    if dim == 3:
        normal, g = np.array([-np.sin(th), 0.0, np.cos(th)]), [0.0, 0.0, -G]
        down = -np.array([np.cos(th), 0.0, np.sin(th)])
    else:
        normal, g = np.array([-np.sin(th), np.cos(th), 0.0]), [0.0, -G, 0.0]
        down = -np.array([np.cos(th), np.sin(th), 0.0])
    w.add(kinema.Plane([0.0, 0.0, 0.0], normal))
    w.add(kinema.Gravity(g))
    w.set_collisions(restitution=0.0, friction=mu)
    r = 0.1
    w.add_particles(r * normal, mass=2.0, radius=r, inertia=inertia)
    return w, down, normal, r


def accelerations_along(w, down, steps):
    speeds = []
    for _ in range(steps):
        w.step(1)
        speeds.append(w.velocities[0] @ down)
    return np.diff(speeds) / w.dt


@pytest.mark.parametrize("method", ["verlet", "symplectic_euler", "rk4"])
@pytest.mark.parametrize("theta, mu", [(30.0, 0.5), (30.0, 0.2), (10.0, 0.06), (60.0, 0.6)])
def test_a_ball_on_a_slope_rolls_at_five_sevenths_g_sin_theta(method, theta, mu):
    # Rolling without slipping (μ > 2/7 tan θ): m a = m g sin θ − F, I α = F r, a = α r
    # ⇒ a = g sin θ / (1 + I/(m r²)) = 5/7 g sin θ for a solid sphere.
    assert mu > 2 / 7 * np.tan(np.radians(theta))
    w, down, normal, r = slope_world(theta, mu, method)
    a = accelerations_along(w, down, 300)
    closed = 5 / 7 * G * np.sin(np.radians(theta))
    assert np.abs(a / closed - 1).max() < 1e-9
    # and the contact point is still: v = ω × (r n), to rounding
    v, om = w.velocities[0], w.angular_velocities[0]
    assert np.linalg.norm(v + np.cross(om, -r * normal)) < 1e-12 * np.linalg.norm(v)
    # it neither sinks into the slope nor leaves it
    assert abs(w.positions[0] @ normal - r) < 1e-12


def test_a_disc_rolls_at_two_thirds_and_a_hollow_sphere_at_three_fifths():
    # The same law with I = 1/2 m r² (a disc, the 2D default): a = 2/3 g sin θ; with
    # I = 2/3 m r² (a thin shell, given as inertia): a = 3/5 g sin θ.
    theta = 25.0
    w, down, _, _ = slope_world(theta, 0.5, dim=2)
    a = accelerations_along(w, down, 200)
    assert np.abs(a / (2 / 3 * G * np.sin(np.radians(theta))) - 1).max() < 1e-9
    assert w.angular_velocities[0][:2].tolist() == [0.0, 0.0]
    w, down, _, _ = slope_world(theta, 0.5, inertia=2 / 3 * 2.0 * 0.1**2)
    a = accelerations_along(w, down, 200)
    assert np.abs(a / (3 / 5 * G * np.sin(np.radians(theta))) - 1).max() < 1e-9


def test_with_too_little_friction_the_ball_slides_and_spins_up_at_coulombs_rate():
    # μ < 2/7 tan θ: the contact slides, F = μ m g cos θ: a = g (sin θ − μ cos θ) and
    # α = F r / I = 5 μ g cos θ / (2 r).
    theta, mu = 30.0, 0.1
    w, down, _, r = slope_world(theta, mu)
    th = np.radians(theta)
    a = accelerations_along(w, down, 100)
    assert np.abs(a / (G * (np.sin(th) - mu * np.cos(th))) - 1).max() < 1e-9
    alpha = np.linalg.norm(w.angular_velocities[0]) / w.time
    assert alpha == pytest.approx(5 * mu * G * np.cos(th) / (2 * r), rel=1e-9)


@pytest.mark.parametrize("v0, mu, r", [(2.0, 0.3, 0.05), (0.7, 0.8, 0.2)])
def test_a_sliding_ball_rolls_at_five_sevenths_v0_after_two_v0_over_seven_mu_g(v0, mu, r):
    # A ball thrown along a floor without spin: friction μ m g slows it (v = v₀ − μ g t) and
    # spins it up (ω r = 5/2 μ g t) until v = ω r: t* = 2 v₀ / (7 μ g), v* = 5/7 v₀ (its angular
    # momentum about the contact point, m v r + I ω, is kept).
    h = 1e-5
    w = kinema.World(dt=h, spin=True)
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.add(kinema.Gravity([0.0, 0.0, -G]))
    w.set_collisions(restitution=0.0, friction=mu)
    w.add_particles([0.0, 0.0, r], velocity=[v0, 0.0, 0.0], mass=0.3, radius=r)
    t_star = 2 * v0 / (7 * mu * G)
    w.step(int(t_star / h) - 3)
    slips = []
    for _ in range(6):
        slips.append((w.time, w.velocities[0][0] - w.angular_velocities[0][1] * r))
        w.step(1)
    # the slip velocity falls at 7/2 μ g while sliding: from the last step that slid, the time
    # it reaches 0
    t, slip = [(t, s) for t, s in slips if s > 1e-12][-1]
    assert t + slip / (3.5 * mu * G) == pytest.approx(t_star, rel=1e-6)
    w.step(2000)
    assert w.velocities[0][0] == pytest.approx(5 / 7 * v0, rel=1e-6)
    assert w.angular_velocities[0][1] * r == pytest.approx(5 / 7 * v0, rel=1e-6)


def walton(v, om, r, m, e, mu):
    """A sphere (I = 2/5 m r²) hitting the still wall z = 0 with velocity v and spin om: Newton's
    law along n, and along the tangent the contact point's velocity g_t = v_t + ω × (−r n)
    leaves as −β g_t with β = min(β₀, −1 + μ (1 + e)(1 + 1/q) |v_n| / |g_t|), q = I/(m r²)
    (Walton; Brilliantov & Pöschel, Kinetic Theory of Granular Gases, ch. 3), β₀ = 0 in the
    impulse model (sticking stops the slip). Returns (v', ω')."""
    n = np.array([0.0, 0.0, 1.0])
    q = 2 / 5
    vn = v @ n
    g_t = v - vn * n + np.cross(om, -r * n)
    slip = np.linalg.norm(g_t)
    beta = min(0.0, -1 + mu * (1 + e) * (1 + 1 / q) * abs(vn) / slip)
    # the tangential impulse J_t (on the sphere) that changes g_t by −(1 + β) g_t:
    # Δg_t = (1/m + r²/I) J_t
    j_t = -(1 + beta) * g_t / (1 / m + r * r / (q * m * r * r))
    j = -(1 + e) * m * vn * n + j_t
    return v + j / m, om + np.cross(-r * n, j) / (q * m * r * r)


@pytest.mark.parametrize(
    "v, om",
    [
        ([1.0, 0.0, -2.0], [0.0, 0.0, 0.0]),  # sticks: slip stopped
        ([3.0, 0.0, -0.5], [0.0, 0.0, 0.0]),  # slides through the impact
        ([0.5, -0.3, -1.0], [8.0, -20.0, 3.0]),  # spinning, sticks
        ([0.2, 0.1, -0.4], [30.0, 40.0, -5.0]),  # spinning fast, slides
        ([0.0, 0.0, -1.0], [0.0, 25.0, 0.0]),  # a topspin drop: thrown forward
    ],
)
@pytest.mark.parametrize("event_driven", [False, True])
def test_the_oblique_impact_of_a_spinning_sphere_on_a_wall_is_waltons(v, om, event_driven):
    v, om = np.array(v), np.array(om)
    r, m, e, mu = 0.05, 0.2, 0.8, 0.3
    w = kinema.World(dt=1e-3, spin=True)
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.set_collisions(restitution=e, friction=mu, restitution_threshold=0.0, event_driven=event_driven)
    # one step before the impact, which happens inside the next step
    w.add_particles([0.0, 0.0, r - v[2] * 0.5e-3], velocity=v, mass=m, radius=r, angular_velocity=om)
    w.step(3)
    assert w.collision_stats()["total"]["impacts"] == 1
    v_after, om_after = walton(v, om, r, m, e, mu)
    np.testing.assert_allclose(w.velocities[0], v_after, rtol=0, atol=1e-12)
    np.testing.assert_allclose(w.angular_velocities[0], om_after, rtol=0, atol=1e-10)


def rough_gas(dim, n=150, seed=3):
    """A cloud of spheres (discs) of mixed sizes and masses, spinning and thrown inward, in free
    space: elastic (e = 1), rough (μ = 0.5)."""
    rng = np.random.default_rng(seed)
    r = 0.05
    w = kinema.World(dim=dim, dt=1e-3, spin=True)
    w.set_collisions(restitution=1.0, friction=0.5)
    side = 1.2 if dim == 3 else 2.0
    x = rng.uniform(-side / 2, side / 2, (20 * n, 3))
    if dim == 2:
        x[:, 2] = 0.0
    placed = []
    for p in x:  # apart by more than the largest pair of radii (1.3 r each)
        if all(np.linalg.norm(p - q) > 2.7 * r for q in placed):
            placed.append(p)
        if len(placed) == n:
            break
    x = np.array(placed)
    v = -2.0 * x + rng.normal(0.0, 0.5, x.shape)
    om = rng.normal(0.0, 20.0, x.shape)
    if dim == 2:
        v[:, 2] = 0.0
        om[:, :2] = 0.0
    w.add_particles(x, velocity=v, mass=rng.uniform(0.5, 2.0, len(x)), radius=r * rng.uniform(0.7, 1.3, len(x)), angular_velocity=om)
    return w


@pytest.mark.parametrize("event_driven", [False, True])
@pytest.mark.parametrize("dim", [2, 3])
def test_an_elastic_rough_gas_keeps_its_angular_momentum_and_books_its_energy(dim, event_driven):
    # Each impulse J acts on i at its contact point and −J on j at the same point: the pair's
    # angular momentum about any point, Σ m x × v + Σ I ω, is unchanged (collide/spin.rs),
    # stepped or event-driven (the same rule at each impact's exact time).
    # Friction (β₀ = 0) takes energy, translational and rotational; the books count it all.
    w = rough_gas(dim)
    w.set_collisions(restitution=1.0, friction=0.5, event_driven=event_driven)
    d0 = w.diagnostics()
    scale = np.abs(w.masses[:, None] * np.cross(w.positions, w.velocities)).sum() + np.abs(w.inertia[:, None] * w.angular_velocities).sum()
    w.step(600)
    d = w.diagnostics()
    stats = w.collision_stats()["total"]
    assert stats["impacts"] > 300
    assert np.abs(np.subtract(d["angular_momentum"], d0["angular_momentum"])).max() < 1e-12 * scale
    assert np.abs(np.subtract(d["momentum"], d0["momentum"])).max() < 1e-12 * np.abs(w.masses[:, None] * w.velocities).sum()
    energy = lambda d: d["kinetic"] + d["rotational"]  # noqa: E731
    assert stats["energy_lost"] > 0.1 * energy(d0)
    assert energy(d0) - energy(d) == pytest.approx(stats["energy_lost"], rel=1e-12)
    # the spin part is Σ I ω, read back from the arrays
    np.testing.assert_allclose(d["spin_angular_momentum"], (w.inertia[:, None] * w.angular_velocities).sum(axis=0), rtol=1e-12)


def test_without_friction_spin_changes_nothing_and_nothing_turns():
    # A normal impulse has no torque (the arm is along n): a smooth gas with spin moves as the
    # same gas without it, bit for bit, and every particle keeps its angular velocity (to the
    # rounding of n × j n, which is 0 only in exact arithmetic).
    worlds = []
    for spin in (False, True):
        w = kinema.World(dt=1e-3, spin=spin)
        w.set_collisions(restitution=0.9, friction=0.0)
        base = rough_gas(3, n=80)
        w.add_particles(base.positions, velocity=base.velocities, mass=base.masses, radius=base._core.radii)
        if spin:
            w.angular_velocities = base.angular_velocities
        w.step(400)
        worlds.append(w)
    plain, spun = worlds
    assert spun.collision_stats()["total"]["impacts"] > 50
    assert np.array_equal(plain.positions, spun.positions) and np.array_equal(plain.velocities, spun.velocities)
    np.testing.assert_allclose(spun.angular_velocities, base.angular_velocities, rtol=0, atol=1e-12)
    assert not np.array_equal(spun.velocities, base.velocities)


def test_the_spin_interface_says_what_is_wrong():
    plain = kinema.World()
    with pytest.raises(ValueError, match="angular_velocity is given, but this world has no spin"):
        plain.add_particles([0.0, 0.0, 0.0], angular_velocity=[0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="angular_velocities: this world has no spin"):
        _ = plain.angular_velocities
    assert len(plain) == 0 and not plain.spin
    flat = kinema.World(dim=2, spin=True)
    with pytest.raises(ValueError, match=r"angular_velocity\[0\].*turns about z only"):
        flat.add_particles([0.0, 0.0, 0.0], radius=0.1, angular_velocity=[1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"inertia\[1\] = -1 is invalid"):
        flat.add_particles([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], radius=0.1, inertia=[1.0, -1.0])
    assert len(flat) == 0  # a bad value adds nothing
    w = kinema.World(spin=True)
    w.add_particles([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]], mass=[1.0, 2.0, 3.0], radius=0.5, pinned=[False, True, False])
    np.testing.assert_allclose(w.inertia, [0.1, 0.2, 0.3])  # 2/5 m r²
    w.angular_velocities[:] = [[1.0, 2.0, 3.0]] * 3
    with pytest.raises(ValueError, match=r"angular_velocities\[2\]\[0\] = NaN is invalid"):
        w.angular_velocities[2, 0] = np.nan
        w.step(1)
    w.angular_velocities[:] = [[1.0, 2.0, 3.0]] * 3
    w.step(1)
    # a pinned particle does not turn; the others keep their spin in free flight
    assert w.angular_velocities.tolist() == [[1.0, 2.0, 3.0], [0.0, 0.0, 0.0], [1.0, 2.0, 3.0]]
    w.remove_particles([0])
    assert w.angular_velocities.tolist() == [[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]]
    np.testing.assert_allclose(w.inertia, [0.2, 0.3])


def test_a_scene_turns_spin_on_and_keeps_the_spin_it_was_given(tmp_path):
    scene = tmp_path / "spin.toml"
    scene.write_text(
        """
[world]
dt = 1e-3
spin = true

[[particles]]
type = "list"
positions = [[0, 0, 0.1], [1, 0, 0.1]]
radius = 0.1
angular_velocity = [0, 0, 4]
inertia = [0.004, 0.006]
"""
    )
    w = kinema.load_scene(scene)
    assert w.spin
    np.testing.assert_array_equal(w.angular_velocities, [[0.0, 0.0, 4.0]] * 2)
    np.testing.assert_array_equal(w.inertia, [0.004, 0.006])
    again = w.to_scene().build()
    np.testing.assert_array_equal(again.angular_velocities, w.angular_velocities)
    np.testing.assert_array_equal(again.inertia, w.inertia)


def test_a_checkpoint_of_a_spinning_world_resumes_bit_for_bit(tmp_path):
    w = kinema.World(spin=True)
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.add(kinema.Gravity([0.0, 0.0, -G]))
    w.set_collisions(restitution=0.0, friction=0.3)
    w.add_particles([0.0, 0.0, 0.05], velocity=[2.0, 0.0, 0.0], mass=0.3, radius=0.05, inertia=0.0004)
    w.step(100)  # sliding, spinning up
    w.save_checkpoint(tmp_path / "spin.h5")
    again = kinema.World.load_checkpoint(tmp_path / "spin.h5")
    assert again.spin and again.angular_velocities[0, 1] > 0
    w.step(200)
    again.step(200)
    assert np.array_equal(w.positions, again.positions) and np.array_equal(w.velocities, again.velocities)
    assert np.array_equal(w.angular_velocities, again.angular_velocities)
    assert np.array_equal(again.inertia, [0.0004])


def test_rolling_resistance_slows_a_rolling_ball_at_five_sevenths_mu_r_g_and_stops_it():
    # A rolling torque μ_r r N against the turning: m a = −F, I α = F r − μ_r r m g, a = α r
    # ⇒ a = −μ_r g / (1 + I/(m r²)) = −5/7 μ_r g until it stops, and then it stays.
    r, mu_r, v0 = 0.05, 0.02, 1.0
    w = kinema.World(dt=1e-4, spin=True)
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.add(kinema.Gravity([0.0, 0.0, -G]))
    w.set_collisions(restitution=0.0, friction=0.5, rolling_friction=mu_r)
    w.add_particles([0.0, 0.0, r], velocity=[v0, 0.0, 0.0], mass=0.3, radius=r, angular_velocity=[0.0, v0 / r, 0.0])
    speeds = []
    for _ in range(200):
        w.step(1)
        speeds.append(w.velocities[0, 0])
    np.testing.assert_allclose(np.diff(speeds) / w.dt, -5 / 7 * mu_r * G, rtol=1e-9)
    stop = v0 / (5 / 7 * mu_r * G)  # 7.14 s
    w.step(int((stop + 1.0) / w.dt) - 200)
    assert abs(w.velocities[0, 0]) < 1e-9 and np.abs(w.angular_velocities[0]).max() < 1e-9 / r
    # it went as far as the closed form says: v0² / (2 · 5/7 μ_r g)
    assert w.positions[0, 0] == pytest.approx(v0 * v0 / (2 * 5 / 7 * mu_r * G), rel=1e-3)


@pytest.mark.parametrize("ratio, moves", [(0.8, False), (1.2, True)])
def test_rolling_resistance_holds_a_ball_on_a_slope_below_tan_theta_equal_mu_r(ratio, moves):
    # Torques about the contact point: gravity's m g r sin θ against at most μ_r r m g cos θ.
    mu_r = 0.1
    theta = np.degrees(np.arctan(ratio * mu_r))
    w, down, _, r = slope_world(theta, 0.5)
    w.set_collisions(restitution=0.0, friction=0.5, rolling_friction=mu_r)
    a = accelerations_along(w, down, 300)
    th = np.radians(theta)
    expected = 5 / 7 * G * (np.sin(th) - mu_r * np.cos(th)) if moves else 0.0
    np.testing.assert_allclose(a[5:], expected, atol=1e-9)


def test_rolling_resistance_needs_spin():
    w = kinema.World()
    with pytest.raises(ValueError, match="rolling_friction = 0.1 is invalid: rolling resistance acts on turning particles"):
        w.set_collisions(rolling_friction=0.1)
    with pytest.raises(ValueError, match="rolling_friction = -1 is invalid"):
        kinema.World(spin=True).set_collisions(rolling_friction=-1.0)


def test_rolling_resistance_also_stops_a_ball_spinning_on_its_axis():
    # a twist about the contact normal against μ_r r m g: ω̇ = μ_r g r m / I = 5/2 μ_r g / r
    r, mu_r = 0.05, 0.02
    w = kinema.World(dt=1e-4, spin=True)
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.add(kinema.Gravity([0.0, 0.0, -G]))
    w.set_collisions(restitution=0.0, friction=0.5, rolling_friction=mu_r)
    w.add_particles([0.0, 0.0, r], mass=0.3, radius=r, angular_velocity=[0.0, 0.0, 20.0])
    spins = []
    for _ in range(300):
        w.step(1)
        spins.append(w.angular_velocities[0, 2])
    np.testing.assert_allclose(np.diff(spins) / w.dt, -2.5 * mu_r * G / r, rtol=1e-9)
    w.step(25_000)  # 20 rad/s at 9.81 rad/s² stops after 2.04 s
    assert abs(w.angular_velocities[0, 2]) < 1e-9 and np.abs(w.velocities[0]).max() < 1e-9
