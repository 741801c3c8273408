"""Collisions in kinema.World from Python, against Newton's restitution law, conservation laws
and the guarantees of continuous detection."""

from pathlib import Path

import numpy as np
import pytest

import kinema

G = 9.81


def head_on(m1, m2, u1, u2, e_own=(None, None), **settings):
    """Two balls of radius 0.1 m on the x-axis, 1 m apart, closing at u1 − u2 > 0 (no forces);
    returns the world after 0.5 s, well after their single impact."""
    w = kinema.World(dt=1e-3)
    w.add_particles(
        [[0, 0, 0], [1, 0, 0]],
        velocity=[[u1, 0, 0], [u2, 0, 0]],
        mass=[m1, m2],
        radius=0.1,
        restitution=list(e_own),
    )
    w.set_collisions(**settings)
    w.step(500)
    return w


def restitution_closed_form(m1, m2, u1, u2, e):
    # Momentum m1 u1 + m2 u2 is kept and the relative velocity reverses times e:
    # v1 = (P − m2 e u)/M, v2 = (P + m1 e u)/M, u = u1 − u2, M = m1 + m2.
    p, u, m = m1 * u1 + m2 * u2, u1 - u2, m1 + m2
    return (p - m2 * e * u) / m, (p + m1 * e * u) / m


@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_head_on_impact_follows_newtons_restitution_law(e):
    # Newton's law u_n⁺ = −e u_n⁻ with momentum conservation fixes both velocities after the
    # impact; the kinetic energy removed is (1 − e²)·½ μ u², μ = m1 m2/(m1 + m2).
    m1, m2, u1, u2 = 1.0, 3.0, 2.0, -1.0
    w = head_on(m1, m2, u1, u2, restitution=e)
    v1, v2 = restitution_closed_form(m1, m2, u1, u2, e)
    np.testing.assert_allclose(w.velocities[:, 0], [v1, v2], rtol=1e-12, atol=0)
    assert np.all(w.velocities[:, 1:] == 0.0)
    stats = w.collision_stats()
    mu, u = m1 * m2 / (m1 + m2), u1 - u2
    assert stats["total"]["energy_lost"] == pytest.approx((1 - e**2) * 0.5 * mu * u**2, rel=1e-12, abs=1e-14)
    assert stats["total"]["impacts"] == 1 and stats["total"]["impulses"] == 1
    assert np.abs(stats["total"]["impulse_balance"]).max() <= 1e-15 * (m1 * abs(u1) + m2 * abs(u2))
    assert stats["last"]["impacts"] == 0  # the impact was in an earlier step


def test_a_dropped_ball_loses_e_squared_of_its_height_at_each_bounce():
    # The rebound speed is e times the impact speed, so the bounce height (z + v_z²/2g above
    # the contact, constant in flight) falls by e² per bounce. Verlet is exact under uniform
    # gravity and continuous detection finds the impact on the exact parabola, so the ratio is
    # e² to rounding.
    e, r = 0.8, 0.1
    w = kinema.World(dt=1e-3, method="verlet")
    w.add_particles([0.0, 0.0, 1.0], radius=r)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1], restitution=e))
    heights, before = [], w.velocities[0, 2]
    while len(heights) < 5:
        w.step()
        vz = w.velocities[0, 2]
        if before < 0 < vz:  # right after a bounce
            heights.append(w.positions[0, 2] - r + vz**2 / (2 * G))
        before = vz
        assert w.time < 5.0, "the ball stopped bouncing"
    heights = np.array(heights)
    np.testing.assert_allclose(heights[1:] / heights[:-1], e**2, rtol=1e-6)
    assert heights[0] == pytest.approx(e**2 * (1.0 - r), rel=1e-6)  # dropped from 0.9 m above contact


def test_trajectory_accounts_for_the_energy_lost_in_bounces():
    # kinetic + potential + lost is the initial energy: each bounce removes (1 − e²) of the
    # kinetic energy m g h it arrives with (two bounces within 1.5 s from 0.9 m).
    e, r, m, h0 = 0.8, 0.1, 2.0, 0.9
    w = kinema.World(dt=1e-3)
    w.add_particles([0.0, 0.0, h0 + r], radius=r, mass=m)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1], restitution=e))
    tr = w.run(1.5, fps=100)
    np.testing.assert_allclose(tr.total + tr.collision_energy_lost, tr.total[0], rtol=1e-9)
    lost = (1 - e**2) * m * G * (h0 + e**2 * h0)
    assert tr.collision_energy_lost[-1] == pytest.approx(lost, rel=1e-9)
    assert np.all(np.diff(tr.collision_energy_lost) >= 0) and tr.collision_energy_lost[0] == 0.0
    assert tr.contacts.shape == tr.t.shape and tr.impulse_balance.shape == (tr.t.size, 3)
    np.testing.assert_array_equal(tr.impulse_balance, 0.0)  # a collider's impulses are external
    ax = tr.plot_energy()
    assert [line.get_label() for line in ax.get_lines()][-1] == "lost in collisions"
    import matplotlib.pyplot as plt

    plt.close(ax.figure)


def test_without_collisions_the_trajectory_records_zeros():
    w = kinema.World(dt=1e-3)
    w.add_particles([[0, 0, 0], [0.1, 0, 0]], velocity=[[1, 0, 0], [-1, 0, 0]], radius=0.1)
    tr = w.run(0.1, fps=100)
    assert w.collisions is None and w.collision_stats() is None
    assert tr.contacts.dtype.kind == "i" and not tr.contacts.any()
    assert tr.impulse_balance.shape == (11, 3) and not tr.impulse_balance.any() and not tr.collision_energy_lost.any()
    np.testing.assert_allclose(tr.positions[-1, :, 0], [0.1, 0.0], atol=1e-12)  # they pass through each other


def test_a_pair_takes_the_larger_restitution_and_a_collider_its_own():
    # Box2D's rule: a pair bounces with e = max(e_i, e_j), whichever particle is which; a NaN
    # entry takes the world's value. A collider's own e overrides the particle's: a dead
    # floor (e = 0) stops a perfectly bouncy ball.
    m1, m2, u1, u2 = 1.0, 2.0, 1.5, -0.5
    for own in [(0.2, 0.9), (0.9, 0.2)]:
        w = head_on(m1, m2, u1, u2, e_own=own, restitution=0.0)
        np.testing.assert_allclose(w.velocities[:, 0], restitution_closed_form(m1, m2, u1, u2, 0.9), rtol=1e-12)
    for own in [(0.2, None), (np.nan, 0.2)]:
        w = head_on(m1, m2, u1, u2, e_own=own, restitution=0.5)
        np.testing.assert_allclose(w.velocities[:, 0], restitution_closed_form(m1, m2, u1, u2, 0.5), rtol=1e-12)

    w = kinema.World(dt=1e-3)
    w.add_particles([0.0, 0.0, 0.5], velocity=[0.3, 0.0, -2.0], radius=0.1, restitution=1.0)
    assert w.collisions is not None  # a particle's own restitution turns collisions on
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1], restitution=0.0))
    w.step(1000)
    np.testing.assert_allclose(w.velocities[0], [0.3, 0.0, 0.0], rtol=0, atol=1e-14)  # normal motion stopped, no friction
    assert w.positions[0, 2] == pytest.approx(0.1, abs=1e-12)
    bouncy = kinema.World(dt=1e-3)
    bouncy.add_particles([0.0, 0.0, 0.5], velocity=[0.3, 0.0, -2.0], radius=0.1, restitution=1.0)
    bouncy.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    bouncy.step(1000)
    assert bouncy.velocities[0, 2] == pytest.approx(2.0, rel=1e-12)  # the same floor without its own e


def test_a_periodic_box_conserves_momentum_and_energy():
    # Elastic impulses between particles are equal and opposite and keep the kinetic energy;
    # with every wall replaced by periodic boundaries nothing external acts, so the total
    # momentum and kinetic energy are conserved to rounding, every frame's impulse balance is
    # zero, and positions stay in the cell [lo, hi).
    rng = np.random.default_rng(7)
    sites = (np.stack(np.meshgrid(*[np.arange(6)] * 3, indexing="ij"), axis=-1).reshape(-1, 3) + 0.5) / 6
    n = 200
    w = kinema.World(dt=1e-3)
    w.add_particles(sites[rng.permutation(len(sites))[:n]], velocity=rng.normal(size=(n, 3)), mass=rng.uniform(0.5, 2.0, n), radius=0.03)
    w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
    w.periodic = (True, True, True)
    assert w.periodic == (True, True, True)
    scale = np.sum(w.masses * np.linalg.norm(w.velocities, axis=1))
    p0 = w.momenta.sum(axis=0)
    tr = w.run(2.0, fps=50)  # 100 frames of 20 steps
    assert w._core.steps == 2000
    ke0 = tr.kinetic[0]
    np.testing.assert_allclose(tr.momentum, np.broadcast_to(p0, tr.momentum.shape), rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(tr.kinetic, ke0, rtol=1e-9)
    assert tr.positions.min() >= 0.0 and tr.positions.max() < 1.0
    assert np.abs(tr.impulse_balance).max() <= 1e-12 * scale
    stats = w.collision_stats()["total"]
    assert stats["impacts"] > 100 and stats["energy_lost"] == 0.0  # the check is not empty


def test_a_periodic_axis_wraps_positions_into_the_live_view():
    w = kinema.World(dt=1e-3)
    w.add_particles([[1.25, 0.5, 0.5]], velocity=[[1.0, 0, 0]], radius=0.05)
    x = w.positions
    w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
    w.periodic = (True, False, False)
    assert x is w.positions and x[0, 0] == pytest.approx(0.25, abs=1e-15)
    x[0, 0] = 0.99  # a write is handed to the world before it moves
    w.step(20)  # 2 cm along x: across the periodic face, not bounced back
    assert w.positions[0, 0] == pytest.approx(0.01, abs=1e-12) and w.velocities[0, 0] == 1.0
    w.periodic = (False, False, False)
    assert w.periodic == (False, False, False)


def test_a_two_dimensional_box_can_be_periodic():
    w = kinema.World(dim=2, dt=1e-3)
    w.add_particles([[1.25, 0.5, 0.0]], radius=0.05)
    w.add(kinema.Box([0, 0], [1, 1]))
    w.periodic = (True, True)
    assert w.periodic == (True, True, False) and w.positions[0, 0] == pytest.approx(0.25)


def test_a_rectangle_reflects_specularly_in_two_dimensions():
    # Elastic reflection off an axis-aligned wall flips one velocity component and keeps the
    # other: |v_x| and |v_y| never change, and the particle stays inside [r, 1 − r], z = 0.
    r = 0.05
    w = kinema.World(dim=2, dt=1e-3)
    w.add_particles([[0.5, 0.5, 0.0]], velocity=[[3.0, 2.0, 0.0]], radius=r)
    w.add(kinema.Box([0, 0], [1, 1]))
    tr = w.run(2.0, fps=100)
    np.testing.assert_allclose(np.abs(tr.velocities[:, 0, :2]), np.broadcast_to([3.0, 2.0], (tr.t.size, 2)), rtol=1e-12)
    assert np.all(tr.positions[:, 0, 2] == 0.0)
    assert tr.positions[:, 0, :2].min() >= r - 1e-12 and tr.positions[:, 0, :2].max() <= 1 - r + 1e-12
    assert w.collision_stats()["total"]["impacts"] >= 10  # 6 m along x, 4 m along y in a 0.9 m free cell


@pytest.mark.parametrize("collider", [kinema.Plane([1.0, 0, 0], [-1.0, 0, 0]), kinema.SphereObstacle([1.5, 0, 0], 0.5)])
def test_no_tunnelling_at_1000_m_per_s(collider):
    # At 1000 m/s and dt = 1/60 s a particle moves 16.7 m per step, past a wall 1 m away.
    # Continuous detection finds the impact at t* = (1 − r)/1000 inside the step and reflects
    # the particle there: after the step x = (1 − r) − 1000 (dt − t*), v = −1000 m/s.
    r, dt = 0.05, 1 / 60
    w = kinema.World(dt=dt)
    w.add_particles([0.0, 0.0, 0.0], velocity=[1000.0, 0, 0], radius=r)
    w.add(collider)
    w.step()
    t_hit = (1 - r) / 1000.0
    np.testing.assert_allclose(w.velocities[0], [-1000.0, 0, 0], rtol=1e-12)
    assert w.positions[0, 0] == pytest.approx((1 - r) - 1000.0 * (dt - t_hit), rel=1e-12)
    assert w.collision_stats()["last"]["impacts"] == 1


def test_without_ccd_a_fast_particle_tunnels_through_an_obstacle():
    # The contrast to the test above: seen only at the ends of the step, the particle was
    # before the obstacle and is 16 m beyond it, never overlapping.
    w = kinema.World(dt=1 / 60)
    w.add_particles([0.0, 0.0, 0.0], velocity=[1000.0, 0, 0], radius=0.05)
    w.add(kinema.SphereObstacle([1.5, 0, 0], 0.5))
    w.set_collisions(ccd=False)
    w.step()
    assert w.velocities[0, 0] == 1000.0 and w.positions[0, 0] > 16.0


def test_contacts_report_pairs_and_colliders():
    # Two particles overlapping at rest by δ = 0.05 m: one contact, normal from j to i (−x for
    # i = 0). The contact reports the overlap as detected, δ. The soft step removes β = 0.2 of
    # its excess over the slop s = 0.001 (r_i + r_j) in a step, along the normal in proportion
    # to the inverse masses (i moves 2/3 of it, j 1/3 for m = 1, 2 kg): the centre of mass
    # stays put, and the relax stage leaves both at rest (docs/collisions.md).
    w = kinema.World(dt=1e-3)
    empty = w.contacts()
    assert set(empty) == {"i", "j", "collider", "normal", "overlap", "u_n", "point", "force_n", "force_t", "sliding"}
    assert all(empty[k].shape == (0, 3) for k in ("normal", "point", "force_n", "force_t"))
    assert all(empty[k].shape == (0,) for k in ("i", "j", "collider", "overlap", "u_n", "sliding"))
    w.add_particles([[0, 0, 0], [0.15, 0, 0]], mass=[1.0, 2.0], radius=0.1)
    w.set_collisions()
    w.step()
    c = w.contacts()
    assert c["i"].tolist() == [0] and c["j"].tolist() == [1] and c["collider"].tolist() == [-1]
    assert c["normal"].shape == (1, 3) and c["i"].dtype == np.int64
    np.testing.assert_array_equal(c["normal"], [[-1.0, 0.0, 0.0]])
    assert c["overlap"][0] == pytest.approx(0.05, abs=1e-15) and c["u_n"][0] == 0.0
    push = 0.2 * (0.05 - 0.001 * 0.2)
    np.testing.assert_allclose(w.positions[:, 0], [-push * 2 / 3, 0.15 + push / 3], atol=1e-15)
    np.testing.assert_allclose(w.velocities, 0.0, atol=1e-12)
    assert w.collision_stats()["last"]["contacts"] == 1
    # The excess shrinks by 1 − β a step: after 60 steps 0.8⁶⁰ of it is left, within 1e-6 m.
    w.step(59)
    gap = w.positions[1, 0] - w.positions[0, 0] - 0.2
    assert -0.001 * 0.2 - 1e-6 < gap <= 0.0
    assert w.positions[0, 0] * 1.0 + w.positions[1, 0] * 2.0 == pytest.approx(0.3, abs=1e-14)

    # Against a collider: j = −1 and the collider's index in world.colliders; the normal is
    # the plane's, normalised. Without continuous detection the contact is found at the end
    # of the step, still approaching (u_n = −1 m/s), and then gets its impulse (e = 1).
    w = kinema.World(dt=1e-3)
    w.add_particles([[0, 0, 0.1]], velocity=[[0, 0, -1.0]], radius=0.1)
    far, floor = kinema.SphereObstacle([10, 0, 0], 1.0), kinema.Plane([0, 0, 0], [0, 0, 2.0])
    w.add(far)
    w.add(floor)
    w.set_collisions(ccd=False)
    assert w.colliders == [far, floor]
    w.step()
    c = w.contacts()
    assert c["i"].tolist() == [0] and c["j"].tolist() == [-1] and c["collider"].tolist() == [1]
    np.testing.assert_array_equal(c["normal"], [[0.0, 0.0, 1.0]])
    assert c["u_n"][0] == -1.0 and w.velocities[0, 2] == 1.0
    assert c["overlap"][0] == pytest.approx(1e-3, abs=1e-15)
    assert w.positions[0, 2] == pytest.approx(0.1, abs=1e-15)  # the 1 mm overlap was removed


def test_settings_read_back_and_round_trip():
    w = kinema.World()
    assert w.collisions is None and w.periodic == (False, False, False) and w.colliders == []
    w.set_collisions(restitution=0.3, friction=0.2, ccd=False, restitution_threshold=0.01)
    expected = {
        "model": "impulse",
        "restitution": 0.3,
        "friction": 0.2,
        "ccd": False,
        "restitution_threshold": 0.01,
        "sleep_time": 0.5,
        "sleep_speed": None,
        "stiffness": None,
        "damping": None,
        "event_driven": False,
        "youngs_modulus": None,
        "poisson_ratio": None,
        "cohesion": None,
        "surface_energy": None,
        "rolling_friction": 0.0,
        "tangential": None,
        "tangential_stiffness": None,
        "tangential_damping": None,
        "rolling_stiffness": None,
        "rolling_damping": None,
        "accuracy": "physics",
        "self_collisions": True,
    }
    assert w.collisions == expected
    w.set_collisions(**w.collisions)
    assert w.collisions == expected
    w.set_collisions(model="spring_dashpot", stiffness=1e5, damping=3.0)
    assert w.collisions["model"] == "spring_dashpot" and w.collisions["stiffness"] == 1e5 and w.collisions["damping"] == 3.0
    assert w.collisions["restitution"] == 1.0  # every setting is replaced


def test_bad_collision_input_is_named():
    w = kinema.World()
    w.add_particles([[0, 0, 0]], radius=0.1)
    with pytest.raises(ValueError, match=r"restitution = 1.5 is invalid: .*\[0, 1\]"):
        w.set_collisions(restitution=1.5)
    with pytest.raises(ValueError, match=r"sleep_time = 0 is invalid: .*> 0 s \(inf or None: nothing sleeps\)"):
        w.set_collisions(sleep_time=0.0)
    with pytest.raises(ValueError, match=r"sleep_speed = -1 is invalid: .*> 0 m/s"):
        w.set_collisions(sleep_speed=-1.0)
    with pytest.raises(ValueError, match=r"restitution = 1.5 is invalid: .*\[0, 1\]"):
        w.add(kinema.Plane([0, 0, 0], [0, 0, 1], restitution=1.5))
    with pytest.raises(ValueError, match=r"restitution\[1\] = 1.5 is invalid: .*\[0, 1\]"):
        w.add_particles([[1, 0, 0], [2, 0, 0]], restitution=[0.5, 1.5])
    with pytest.raises(ValueError, match=r"friction\[0\] = -1 is invalid"):
        w.add_particles([[1, 0, 0]], friction=-1.0)
    assert len(w) == 1  # nothing added
    with pytest.raises(ValueError, match=r"normal = \[0.0, 0.0, 0.0\] is invalid: a plane's normal must be non-zero"):
        w.add(kinema.Plane([0, 0, 0], [0, 0, 0]))
    with pytest.raises(ValueError, match=r"hi\[1\] = 0 is invalid: the box needs hi > lo"):
        w.add(kinema.Box([0, 0, 0], [1, 0, 1]))
    with pytest.raises(ValueError, match=r"hi\[0\] = 1 is invalid"):
        w.add(kinema.Box([2, 0, 0], [1, 1, 1]))
    with pytest.raises(ValueError, match=r"radius = -1 is invalid"):
        w.add(kinema.SphereObstacle([0, 0, 0], -1.0))
    with pytest.raises(ValueError, match=r"lo = .* is invalid: a 3D world's box has 3 values"):
        w.add(kinema.Box([0, 0], [1, 1]))
    assert w.colliders == []
    with pytest.raises(ValueError, match="periodic = .* is invalid: periodic axes need a box collider"):
        w.periodic = (True, False, False)
    with pytest.raises(ValueError, match="periodic = .* is invalid"):
        w.periodic = (True, False)
    with pytest.raises(ValueError, match=r"model = 'foo' is invalid: .*'impulse', 'spring_dashpot'"):
        w.set_collisions(model="foo")
    with pytest.raises(ValueError, match=r"stiffness = None is invalid: model='spring_dashpot' needs the contact stiffness"):
        w.set_collisions(model="spring_dashpot")
    with pytest.raises(ValueError, match=r"stiffness = -1 is invalid"):
        w.set_collisions(model="spring_dashpot", stiffness=-1.0)
    with pytest.raises(ValueError, match=r"damping = -2 is invalid"):
        w.set_collisions(model="spring_dashpot", stiffness=1.0, damping=-2.0)
    with pytest.raises(ValueError, match=r"stiffness = 1000 is invalid: only model='spring_dashpot' uses it"):
        w.set_collisions(stiffness=1e3)
    with pytest.raises(TypeError, match="is not a kinema force, collider or emitter"):
        w.add(object())
    assert w.collisions["restitution"] == 1.0  # the refused settings changed nothing

    flat = kinema.World(dim=2)
    with pytest.raises(ValueError, match=r"normal\[2\] = 1 is invalid: a 2D world keeps z = 0"):
        flat.add(kinema.Plane([0, 0, 0], [0, 1, 1]))
    with pytest.raises(ValueError, match=r"center\[2\] = 0.5 is invalid: a 2D world keeps z = 0"):
        flat.add(kinema.SphereObstacle([0, 0, 0.5], 1.0))
    with pytest.raises(ValueError, match=r"lo = .* is invalid: a 2D world's box has 2 values"):
        flat.add(kinema.Box([0, 0, 0], [1, 1, 1]))
    with pytest.raises(ValueError, match="periodic = .* is invalid: a 2D world has no periodic z axis"):
        flat.add(kinema.Box([0, 0], [1, 1]))
        flat.periodic = (False, False, True)


def test_spring_dashpot_contacts_bounce_with_the_requested_restitution():
    # A linear spring–dashpot contact is a damped oscillator in the overlap: with γ_n chosen
    # for e = 0.5 the balls separate at half their approach speed after half a damped period,
    # π/(ω √(1 − ζ²)) with ω² = k/μ (μ = 0.5 kg: about 7 ms, 700 steps), overlapping by less
    # than the undamped amplitude u/ω. The impulse model would give the same e with no overlap
    # at all, hence the checks on the contact's duration and depth.
    k, e, mu, u = 1e5, 0.5, 0.5, 2.0
    w = kinema.World(dt=1e-5)
    w.add_particles([[0, 0, 0], [0.21, 0, 0]], velocity=[[u / 2, 0, 0], [-u / 2, 0, 0]], radius=0.1)
    w.set_collisions(model="spring_dashpot", stiffness=k, restitution=e)
    tr = w.run(0.03, fps=1e5)  # every step
    overlap = 0.2 - (tr.positions[:, 1, 0] - tr.positions[:, 0, 0])
    u_after = w.velocities[1, 0] - w.velocities[0, 0]
    assert u_after / u == pytest.approx(e, rel=0.02)
    omega = np.sqrt(k / mu)
    zeta = -np.log(e) / np.hypot(np.pi, np.log(e))
    assert np.count_nonzero(overlap > 0) * w.dt == pytest.approx(np.pi / (omega * np.sqrt(1 - zeta**2)), rel=0.05)
    assert 0 < overlap.max() < u / omega
    # The contact is a force of stage 1: its elastic energy is a potential, and the impulse
    # stages (contacts, statistics) have nothing to report.
    assert "contact" in tr.potential and tr.potential["contact"].max() > 0 and tr.potential["contact"][-1] == 0.0
    assert w.contacts()["i"].size == 0 and w.collision_stats()["total"]["impulses"] == 0


def test_the_stability_warning_counts_contact_springs():
    # A spring–dashpot contact between two 1 kg balls is a spring k_n on their relative
    # motion: ω² = k_n (1/m + 1/m) = 2·10⁵ s⁻², so Verlet needs dt ≤ 2/ω = 4.47 ms even before
    # they touch, and a world with no other force warns at dt = 10 ms.
    w = kinema.World(dt=0.01)
    w.add_particles([[0, 0, 0], [1, 0, 0]], radius=0.1)
    w.set_collisions(model="spring_dashpot", stiffness=1e5)
    assert w.stable_step("verlet") == pytest.approx(2 / np.sqrt(2e5), rel=1e-6)
    with pytest.warns(kinema.StabilityWarning, match="limit 0.004472 s"):
        w.step()


def test_the_spring_dashpot_model_keeps_positions_in_the_periodic_cell():
    # A particle crossing a periodic face comes back on the other side under either model;
    # the spring–dashpot model keeps no end-of-step contacts (its contacts live in the force).
    w = kinema.World(dt=1e-3)
    w.add_particles([[0.95, 0.5, 0.5], [0.2, 0.5, 0.5]], velocity=[[1.0, 0, 0], [0, 0, 0]], radius=0.01)
    w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
    w.set_collisions(model="spring_dashpot", stiffness=1e4, restitution=0.5)
    w.periodic = (True, True, True)
    w.step(100)  # 10 cm along x: across the face at x = 1
    assert w.positions[0, 0] == pytest.approx(0.05, abs=1e-12)
    assert np.all((w.positions >= 0) & (w.positions < 1))
    assert w.contacts()["i"].size == 0 and w.collision_stats()["last"]["contacts"] == 0


def test_the_demo_pile_books_only_what_the_collisions_take():
    # The scene of `make demo`: 400 balls fall into a box under gravity (e = 0.7). Energy is
    # conserved but for what the collisions take (velocity Verlet is exact on the free
    # parabolas), so the books must balance: total energy + collision_energy_lost stays at
    # the start's, and the count can never exceed the energy the system had (gravity's work
    # is its potential energy). Once the heap has settled the count stops growing.
    # (Regression: it once ended at 5,449 J in a system that never had more than 4,780 J.)
    w = kinema.load_scene(Path(__file__).parent.parent / "examples" / "scenes" / "demo.toml")
    energy = lambda d: d["kinetic"] + sum(d["potential"].values())  # noqa: E731
    e0 = energy(w.diagnostics())
    lost = []
    for _ in range(5):
        w.step(round(0.5 / w.dt))
        total = w.collision_stats()["total"]
        lost.append(total["energy_lost"])
        assert energy(w.diagnostics()) + total["energy_lost"] == pytest.approx(e0, rel=1e-10)
        assert total["energy_lost"] <= e0
    assert lost[0] > 0.5 * e0  # the check is not empty: most of the fall's energy is gone
    # settled by 2 s (a frictionless heap still creeps): under 0.1 % more in the last 0.5 s
    assert lost[-1] - lost[-2] < 1e-3 * lost[-1], lost


def _gas_in_a_slab(zero_force: bool):
    # 1,728 spheres (two radii) at number density 0.3 with random velocities of a few m/s in
    # a box periodic along x and y, with walls along z; e = 0.8.
    rng = np.random.default_rng(7)
    ncell, a = 12, (1 / 0.3) ** (1 / 3)
    i, j, k = np.meshgrid(*[np.arange(ncell)] * 3, indexing="ij")
    x = (np.stack([i, j, k], axis=-1).reshape(-1, 3) + 0.5) * a
    v = rng.normal(0.0, 2.0, x.shape)
    radius = 0.5 - 0.1 * (np.arange(len(x)) % 2)
    w = kinema.World(dt=1e-3, method="verlet")
    w.add_particles(x, velocity=v, mass=1.0, radius=radius)
    w.add(kinema.Box([0, 0, 0], [ncell * a] * 3))
    w.periodic = (True, True, False)
    w.set_collisions(model="impulse", restitution=0.8)
    if zero_force:
        w.add(kinema.Gravity((0.0, 0.0, 0.0)))
    return w, radius


def test_the_wake_schedule_of_a_force_free_world_misses_no_impact():
    # Without forces, a step searches impacts only from the particles whose wake time falls
    # in it (collide/wake.rs). A zero force makes the world search from every particle, as
    # with any force, on the same numbers (x + h v; a = 0). Had the wake times missed an
    # impact, a pair would pass through each other: the two runs would part, and spheres
    # would overlap.
    runs = []
    for zero_force in (False, True):
        w, radius = _gas_in_a_slab(zero_force)
        w.step(600)
        runs.append((w.positions.copy(), w.velocities.copy(), w.collision_stats()["total"]))
    (x_wake, v_wake, s_wake), (x_all, v_all, s_all) = runs
    assert s_wake["impacts"] > 1500, s_wake["impacts"]
    assert s_wake["impacts"] == s_all["impacts"]
    assert np.allclose(x_wake, x_all, rtol=0, atol=1e-9)
    assert np.allclose(v_wake, v_all, rtol=0, atol=1e-9)
    # no two spheres overlap (minimum image along the periodic axes)
    box = 12 * (1 / 0.3) ** (1 / 3)
    d = x_wake[:, None, :] - x_wake[None, :, :]
    d[..., :2] -= box * np.round(d[..., :2] / box)
    gap = np.sqrt((d**2).sum(-1)) - (radius[:, None] + radius[None, :])
    np.fill_diagonal(gap, np.inf)
    assert gap.min() > -1e-9, gap.min()


def test_contacts_that_share_no_movable_particle_are_separate_islands():
    # Four balls resting on a floor: 0 and 1 touching each other, 2 alone, 3 touching a pinned
    # ball 4 that also touches nothing else. Islands join contacts through movable particles
    # only (the floor and the pinned ball join nothing): {0–1, 0–floor, 1–floor}, {2–floor},
    # {3–floor, 3–4} = 3; the pinned ball on the floor, a contact of two immovable bodies,
    # is in none.
    w = kinema.World(dt=1e-3, method="verlet")
    x = [[0, 0, 0.1], [0.2, 0, 0.1], [1, 0, 0.1], [2, 0, 0.1], [2.2, 0, 0.1]]
    w.add_particles(x, radius=0.1, pinned=[False, False, False, False, True])
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(restitution=0.5)
    w.step(5)
    last = w.collision_stats()["last"]
    assert (last["contacts"], last["islands"]) == (7, 3), last


def test_collision_defaults_and_contact_models_are_the_engines():
    """One home for each fact (issue 16): World.set_collisions' defaults, the scene table's
    defaults and its model names are the engine's CollisionParams::default and
    ContactModel::NAMES, and a scene file breaks the contact-model rule with the engine's
    message."""
    import inspect
    import typing

    from kinema import _core
    from kinema.scene.tables import CollisionsTable

    engine = _core.collision_defaults()
    assert engine == {
        "model": "impulse",
        "restitution": 1.0,
        "friction": 0.0,
        "ccd": True,
        "restitution_threshold": None,
        "sleep_time": 0.5,
        "sleep_speed": None,
        "stiffness": None,
        "damping": None,
        "event_driven": False,
        "youngs_modulus": None,
        "poisson_ratio": None,
        "cohesion": None,
        "surface_energy": None,
        "rolling_friction": 0.0,
        "tangential": None,
        "tangential_stiffness": None,
        "tangential_damping": None,
        "rolling_stiffness": None,
        "rolling_damping": None,
        "accuracy": "physics",
        "self_collisions": True,
    }
    signature = inspect.signature(kinema.World.set_collisions)
    assert {k: p.default for k, p in signature.parameters.items() if k != "self"} == engine
    table = CollisionsTable()
    assert {k: getattr(table, k) for k in engine} == engine
    assert typing.get_args(CollisionsTable.model_fields["model"].annotation) == tuple(_core.CONTACT_MODELS)
    w = kinema.World()
    w.set_collisions()
    assert w.collisions == engine
    with pytest.raises(ValueError, match=r"stiffness = None is invalid: model='spring_dashpot' needs the contact stiffness"):
        CollisionsTable(model="spring_dashpot")
    with pytest.raises(ValueError, match=r"damping = 2 is invalid: only model='spring_dashpot' uses it"):
        CollisionsTable(model="impulse", damping=2.0)


def test_gravity_pulls_down_in_either_dimension():
    # kinema.Gravity() with no g is 9.81 m/s² down: −z in 3D, −y in a 2D world (whose z is
    # zeroed). One verlet step from rest under a constant force is exact: v = g h.
    for dim, down in ((3, 2), (2, 1)):
        w = kinema.World(dim=dim, dt=1e-3)
        w.add_particles([0.0, 0.0, 0.0])
        w.add(kinema.Gravity())
        w.step()
        expected = np.zeros(3)
        expected[down] = -9.81e-3
        np.testing.assert_allclose(w.velocities[0], expected, rtol=1e-15, atol=0)


def test_collision_stats_count_resting_and_speculative_contacts_and_the_overlap_is_real():
    # A ball resting on a floor with a second one 1 mm above it (within the speculative margin,
    # 5 % of r_i + r_j = 1 cm) and falling slower than anything that would close the gap in a
    # step: two contacts, the floor's resting (it carries the weight), the pair's speculative
    # (apart, carrying nothing); the solver converged. max_overlap is measured by brute force.
    w = kinema.World(dt=1e-3)
    w.add_particles([[0, 0, 0.1], [0, 0, 0.301]], radius=0.1)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(restitution=0.5)
    w.step()
    last = w.collision_stats()["last"]
    assert (last["contacts"], last["resting"], last["speculative"], last["unconverged"]) == (2, 1, 1, 0), last
    x = w.positions
    real = max(0.1 - x[0, 2], 0.2 - np.linalg.norm(x[1] - x[0]), 0.0)
    assert last["max_overlap"] == pytest.approx(real, abs=1e-15)


@pytest.mark.parametrize("floor", ["plane", "mesh"])
def test_the_overlap_a_call_reports_is_its_last_steps_measured_at_the_positions_it_leaves(floor):
    # The overlap left is measured at the last step of each call only (the figure anyone
    # reads; on a fine mesh a walk down its tree per contact): 40 steps in one call must
    # report what 39 and then 1 report, the brute-force overlap of the state they leave, and
    # the same bits as the same 40 steps run one at a time.
    def pile():
        w = kinema.World(dt=1e-3)
        x = np.array([[0.05 + 0.0205 * (k % 3), 0.05 + 0.0205 * (k // 3 % 3), 0.0105 + 0.0205 * (k // 9)] for k in range(27)])
        w.add_particles(x, mass=0.01, radius=0.01)
        w.add(kinema.Gravity())
        if floor == "plane":
            w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
        else:
            t = np.linspace(0.0, 0.2, 41)
            gx, gy = np.meshgrid(t, t, indexing="xy")
            vertices = np.column_stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)])
            q = (np.arange(40)[:, None] * 41 + np.arange(40)[None, :]).ravel()
            faces = np.concatenate([np.stack([q, q + 1, q + 42], -1), np.stack([q, q + 42, q + 41], -1)])
            w.add(kinema.Mesh(vertices=vertices, faces=faces))
        w.set_collisions(restitution=0.2, friction=0.5, sleep_time=None)
        return w

    one_call, two_calls, single = pile(), pile(), pile()
    one_call.step(40)
    two_calls.step(39)
    two_calls.step(1)
    for _ in range(40):
        single.step(1)
    got = [w.collision_stats()["last"]["max_overlap"] for w in (one_call, two_calls, single)]
    assert got[0] == got[1] == got[2] > 0.0, got
    x = one_call.positions
    d = np.linalg.norm(x[:, None] - x[None, :], axis=-1) + np.eye(len(x))
    real = max(float(np.max(0.02 - d)), float(np.max(0.01 - x[:, 2])))
    assert got[0] == pytest.approx(real, abs=1e-15)


def test_removing_a_particle_keeps_the_warm_start_of_the_contacts_that_stay():
    # A pile of 48 spheres resting in a box beside one far away that never touches them.
    # Removing the far one must leave the pile's contacts and their warm starts as they
    # were (renumbered: Rapier's change flags keep what did not change), so the pile goes on
    # bit for bit as the same pile that never had the far sphere. Dropping the warm start
    # (as before) moved it by ~2e-12 m within 50 steps.
    def pile(extra):
        w = kinema.World(dt=1e-3)
        rng = np.random.default_rng(2)
        x = np.array([[0.1 + 0.021 * (k % 4), 0.1 + 0.021 * ((k // 4) % 4), 0.011 + 0.021 * (k // 16)] for k in range(48)])
        x += rng.uniform(-1e-4, 1e-4, x.shape)
        if extra:
            x = np.vstack([x, [[0.9, 0.9, 0.5]]])
        w.add_particles(x, mass=0.01, radius=0.01)
        w.add(kinema.Gravity())
        w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
        w.set_collisions(restitution=0.2, friction=0.5)
        return w

    a, c = pile(True), pile(False)
    a.step(300)
    c.step(300)
    np.testing.assert_array_equal(a.positions[:48], c.positions)
    assert c.collision_stats()["last"]["contacts"] > 48, "the pile rests on its contacts"
    a.remove_particles([48])
    a.step(50)
    c.step(50)
    np.testing.assert_array_equal(a.positions, c.positions)
    np.testing.assert_array_equal(a.velocities, c.velocities)


def test_a_ball_pressed_into_a_box_corner_warm_starts_each_wall_from_its_own_record():
    # A ball at rest in a corner of a box, pressed into its floor and two walls by a tilted
    # gravity: three contacts with one key (the ball, the box). Each carries m g_k h a step
    # along its wall's normal, the same every step, so a warm start from each contact's own
    # record is already the answer and the solve stops after one sweep. Read by key alone,
    # the three shared one record (the floor's push projected on a wall's normal is 0):
    # two sweeps every step. The ball stays where it was (closed form: at rest).
    w = kinema.World(dt=1e-3, method="verlet")
    r = 0.05
    w.add_particles([[r, r, r]], mass=1.0, radius=r)
    w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
    w.add(kinema.Gravity(g=[-2.0, -1.0, -9.81]))
    w.set_collisions(restitution=0.5, friction=0.3)
    w.step(50)
    sweeps = []
    for _ in range(20):
        w.step(1)
        last = w.collision_stats()["last"]
        assert (last["contacts"], last["resting"]) == (3, 3), last
        sweeps.append(last["solver_sweeps"])
    assert sweeps == [1] * 20
    np.testing.assert_allclose(w.positions[0], [r, r, r], rtol=0, atol=1e-12)
    np.testing.assert_allclose(w.velocities[0], 0.0, rtol=0, atol=1e-12)


def test_stage_times_name_the_impulse_models_stages_in_the_order_a_step_runs_them():
    # A pile falling onto a floor: every stage of the impulse model runs (impacts, contacts,
    # the soft step, the books). The lecture notes' four stages come first; the impulse model's own
    # stages follow in its order, and they cover the collision time the four report
    # (measured by the same clock's laps: at least detect + respond + distribute).
    w = kinema.World(dt=1e-3, method="verlet")
    rng = np.random.default_rng(3)
    x = np.array([[0.1 * i + 0.05, 0.1 * j + 0.05, 0.06 + 0.1 * k] for i in range(3) for j in range(3) for k in range(3)])
    w.add_particles(x + rng.uniform(-0.005, 0.005, x.shape), mass=1.0, radius=0.04)
    w.add(kinema.Gravity())
    w.add(kinema.Box([0, 0, 0], [0.3, 0.3, 1.0]))
    w.set_collisions(restitution=0.5, friction=0.3)
    w.step(300)
    t = w.stage_times()
    stages = ["list", "impacts", "contacts", "solve", "apply", "settle", "wake"]
    assert list(t) == ["integrate", "detect", "respond", "distribute", *stages]
    assert all(t[k] >= 0.0 for k in t)
    assert t["impacts"] > 0.0 and t["contacts"] > 0.0 and t["solve"] > 0.0
    assert sum(t[k] for k in stages) >= t["detect"] + t["respond"] + t["distribute"] - 1e-6


def _column(dim, per_row, layers, dt, seed, seconds=5.0, accuracy="physics"):
    """A column of discs (dim 2) or balls (dim 3), radii uniform in [2.5, 4] cm, `per_row`
    across (per side in 3D) and `layers` high on a jittered lattice in a box, e = 0.7,
    μ = 0.5, stepped for `seconds` at `dt` at the `accuracy`; returns the world and the
    radii."""
    rng = np.random.default_rng(seed)
    r_max, gap = 0.04, 0.01
    a, across = 2 * r_max + gap, dim - 1
    grids = np.meshgrid(*[np.arange(per_row)] * across, np.arange(layers), indexing="ij")
    idx = np.stack([g.ravel() for g in grids], axis=-1)
    n = len(idx)
    x = np.zeros((n, 3))
    x[:, :across] = (idx[:, :across] + 0.5) * a + rng.uniform(-1, 1, (n, across)) * 0.4 * (a - 2 * r_max)
    x[:, across] = r_max + gap + idx[:, -1] * a + rng.uniform(-1, 1, n) * 0.4 * gap
    r = rng.uniform(0.025, r_max, n)
    w = kinema.World(dim=dim, dt=dt, method="verlet")
    w.add_particles(x, radius=r)
    g = [0.0, 0.0, 0.0]
    g[across] = -G
    w.add(kinema.Gravity(g=tuple(g)))
    w.add(kinema.Box([0.0] * dim, [per_row * a] * across + [layers * a + 1.0]))
    w.set_collisions(restitution=0.7, friction=0.5, accuracy=accuracy)
    w.step(round(seconds / dt))
    return w, r


def _overlaps(w, r):
    """Each pair's overlap as a fraction of the two radii's mean (brute force)."""
    x = w.positions
    d = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=-1)
    np.fill_diagonal(d, np.inf)
    s = r[:, None] + r[None, :]
    return (s - d) / (s / 2)


@pytest.mark.parametrize(
    "dim, per_row, layers, dt, seed, rests",
    [(2, 10, 40, 1 / 60, 19, True), (2, 16, 25, 1 / 60, 5, True), (3, 5, 16, 1 / 60, 7, True), (2, 10, 40, 1 / 30, 3, False)],
)
def test_a_column_sleeps_only_once_its_overlaps_are_within_a_percent_of_r(dim, per_row, layers, dt, seed, rests):
    # At a long step a column comes to rest (calm for 0.5 s at the automatic sleep speed g·dt)
    # before its solve has pushed out what the fall pressed in; an island may sleep only with
    # its overlaps within 5 slops, 1 % of the two radii's mean (a pile rests at 0.23 % of r
    # at 1 ms). The 40-row column at 60 Hz fell asleep at 6.6 % of r before, at 30 Hz at 21 %;
    # at 60 Hz it now rests within 1 %, at 30 Hz (whose solve cannot push it out) it stays
    # awake. Asleep particles are those of velocity exactly 0 (sleeping sets it).
    w, r = _column(dim, per_row, layers, dt, seed)
    overlap = _overlaps(w, r)
    asleep = np.all(w.velocities == 0.0, axis=1)
    both = asleep[:, None] & asleep[None, :]
    assert (asleep.sum() == len(r)) == rests, asleep.sum()
    if asleep.any():
        assert overlap[both].max() <= 0.01 + 1e-9
    if rests:
        assert w.collision_stats()["last"]["asleep"] == len(r)


@pytest.mark.parametrize(
    "dim, per_row, layers, seed",
    [(2, 10, 80, 4), (2, 20, 40, 8), (3, 4, 40, 17)],
)
def test_the_animation_accuracy_brings_deep_columns_to_rest_at_120_hz(dim, per_row, layers, seed):
    # Shock propagation (collide/shock.rs) stops each level on its supports in one pass, so a
    # pile 40 to 80 layers deep rests at 120 Hz with 10 sweeps a step: every particle asleep
    # (velocity exactly 0) within 1 % of r of overlap (the sleep rule's bound; a column at
    # 1 ms rests at 0.23 %), and the energy the collisions booked as lost is what the pile
    # lost (kinetic + potential: the books are measured from the states, the shock's pushes
    # included). Without the shock, 10 sweeps leave a 60-deep column at 13 % of r at 60 Hz.
    w0, r = _column(dim, per_row, layers, 1 / 120, seed, seconds=0.0, accuracy="animation")
    e0 = w0.diagnostics()
    w, _ = _column(dim, per_row, layers, 1 / 120, seed, seconds=4.0, accuracy="animation")
    e1 = w.diagnostics()
    assert w.collision_stats()["last"]["asleep"] == len(r)
    assert np.all(w.velocities == 0.0)
    assert _overlaps(w, r).max() <= 0.01
    energy = lambda e: e["kinetic"] + sum(e["potential"].values())  # noqa: E731
    lost = w.collision_stats()["total"]["energy_lost"]
    assert energy(e0) - energy(e1) == pytest.approx(lost, rel=1e-9)


def test_the_animation_accuracy_is_the_same_on_any_number_of_threads(on_threads):
    # The shock runs island by island on one thread each, in an order of the island's own
    # (levels, then list order): 1, 2 and 3 threads give the same bits.
    out = on_threads(
        "import sys, hashlib; sys.path.insert(0, 'tests'); import test_collisions as t; "
        "w, _ = t._column(3, 6, 20, 1 / 120, 3, seconds=0.5, accuracy='animation'); "
        "print(hashlib.sha256(w.positions.tobytes() + w.velocities.tobytes()).hexdigest())"
    )
    assert out[1] == out[2] == out[3], out


def test_the_accuracy_setting_is_named_and_refused_where_nothing_uses_it():
    w = kinema.World(dim=2, dt=1 / 120)
    w.set_collisions(accuracy="animation")
    assert w.collisions["accuracy"] == "animation"
    w.set_collisions(**w.collisions)
    assert w.collisions["accuracy"] == "animation"
    with pytest.raises(ValueError, match="accuracy = 'fast' is invalid: the accuracy must be 'physics' or 'animation'"):
        w.set_collisions(accuracy="fast")
    with pytest.raises(ValueError, match="accuracy = 'animation' is invalid: only the stepped impulse model"):
        w.set_collisions(accuracy="animation", model="spring_dashpot", stiffness=1e4)
    with pytest.raises(ValueError, match="accuracy = 'animation' is invalid"):
        w.set_collisions(accuracy="animation", event_driven=True)
