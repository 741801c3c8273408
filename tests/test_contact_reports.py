"""What a granular researcher reads off the contacts (issue 47): ``World.contacts()`` with each
contact's point, normal and tangential force and whether it slides, for every contact model,
and ``collider_books()`` with the momentum each collider took, split into the pressure and
the shear on it, per step and summed.

Each physics test compares with a closed form and says which: a resting column's contacts
each carry the weight above them, and its floor takes N m g t (statics); a ball dropped on
a floor leaves the floor exactly the momentum it took, m Δv = −p_floor + m g t (Newton's third
law, with Verlet's kick h/2 (F + F')); a sliding ball's friction is μ times its normal force
(Coulomb) until it rolls at 5/7 of its speed, where it sticks; a contact point lies on the
line of centres, at ρ_i = d r_i/(r_i + r_j) from i.
"""

import numpy as np
import pytest

import kinema

G = 9.81
R = 0.01
M = 0.01
MODELS = {
    "hertz": dict(model="hertz", youngs_modulus=1e8, poisson_ratio=0.3),
    "spring_dashpot": dict(model="spring_dashpot", stiffness=1e5),
    "impulse": dict(),
}


def column(model, n, friction=0.3, settle=1.0):
    """n balls stacked on a floor, settled under gravity for `settle` s."""
    w = kinema.World(dim=3, dt=1e-5 if model != "impulse" else 1e-3)
    w.add_particles([[0.0, 0.0, R + 2 * k * R] for k in range(n)], radius=R, mass=M)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.set_collisions(restitution=0.1, friction=friction, **MODELS[model])
    w.step(int(round(settle / w.dt)))
    return w


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("n", [3, 7])
def test_a_resting_columns_contacts_each_carry_the_weight_above_and_the_floor_takes_it_all(model, n):
    # Statics: the contact below ball k carries the weight of the n − k balls from k up, so
    # its normal force is (n − k) m g, along +z on the upper side; the floor's is n m g.
    # The impulse model's column is asleep by then: its contacts report the loads of its last
    # awake step, and the floor books them in every step asleep.
    w = column(model, n)
    if model == "impulse":
        assert w.collision_stats()["last"]["asleep"] == n
    c = w.contacts()
    assert len(c["i"]) == n
    z = w.positions[:, 2]
    for k in range(len(c["i"])):
        i, j = c["i"][k], c["j"][k]
        upper = max(i, j, key=lambda q: z[q]) if j >= 0 else i
        above = int(np.sum(z >= z[upper] - 1e-9))  # the balls it carries: from `upper` up
        up = c["force_n"][k] if (j < 0 or z[i] > z[j]) else -c["force_n"][k]  # on the upper side
        np.testing.assert_allclose(up, [0.0, 0.0, above * M * G], rtol=1e-6, atol=1e-12)
        np.testing.assert_allclose(c["force_t"][k], 0.0, atol=1e-12)
        assert not c["sliding"][k]
    before = w.collider_books()["momentum"][0].copy()
    steps = 50
    w.step(steps)
    books = w.collider_books()
    took = books["momentum"][0] - before
    np.testing.assert_allclose(took, [0.0, 0.0, -n * M * G * steps * w.dt], rtol=1e-6)
    np.testing.assert_allclose(books["tangential"][0], 0.0, atol=1e-15)
    last = w.collider_books(last=True)
    np.testing.assert_allclose(last["momentum"][0] / w.dt, [0.0, 0.0, -n * M * G], rtol=1e-6)
    np.testing.assert_allclose(last["normal"][0], last["momentum"][0], rtol=1e-12)


@pytest.mark.parametrize("model", ["hertz", "spring_dashpot"])
@pytest.mark.parametrize("e", [0.3, 1.0])
def test_a_dropped_ball_leaves_the_floor_exactly_the_momentum_it_took(model, e):
    # Newton's third law: over the fall and the bounce, m Δv = −p_floor + m g t, to rounding
    # (velocity Verlet gives the ball h/2 (F + F') of the floor's force in each step, and the
    # floor books the same). Before the books of the force models existed, p_floor was 0.
    w = kinema.World(dim=3, dt=1e-5)
    w.add_particles([0.0, 0.0, R + 0.02], radius=R, mass=M, velocity=[0.3, 0.0, -1.0])
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.set_collisions(restitution=e, friction=0.0, **MODELS[model])
    v0, t0 = w.velocities[0].copy(), w.time
    w.step(5000)  # 50 ms: falls 2 cm at about 1 m/s, bounces within it
    assert w.velocities[0, 2] > 0.0, "the ball must have bounced"
    taken = M * (w.velocities[0] - v0)
    gravity = M * np.array([0.0, 0.0, -G]) * (w.time - t0)
    floor = w.collider_books()["momentum"][0]
    np.testing.assert_allclose(taken, -floor + gravity, rtol=0, atol=1e-12 * M * 1.0)
    assert floor[2] < -M * 1.0 * (1 + 0.9 * e), "the floor took the bounce's momentum"


def resting_ball(model, mu):
    """A spinning ball resting on a rough floor (friction μ; Hertz with Mindlin's tangential
    spring, placed at Hertz's static overlap δ = (3 m g / (4 E* √R))^(2/3), E* = E / (2 (1 −
    ν²))), its normal force settled for 10 ms."""
    dt = 1e-5 if model == "hertz" else 1e-3
    w = kinema.World(dim=3, dt=dt, spin=True)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    kw = dict(MODELS[model], tangential="mindlin") if model == "hertz" else {}
    w.set_collisions(restitution=0.3, friction=mu, **kw)
    delta = 0.0
    if model == "hertz":
        e_star = 1e8 / (2 * (1 - 0.3**2))
        delta = (3 * M * G / (4 * e_star * np.sqrt(R))) ** (2 / 3)
    w.add_particles([0.0, 0.0, R - delta], radius=R, mass=M)
    w.step(int(round(0.01 / dt)))
    return w


@pytest.mark.parametrize("model", ["hertz", "impulse"])
def test_a_sliding_ball_reports_coulomb_friction_until_it_rolls(model):
    # A ball thrown along a rough floor without spin slides, its friction μ times its normal
    # force against its motion (Coulomb), until it rolls at v₀ / (1 + I/(m ρ²)) ≈ 5/7 v₀
    # (angular momentum about the contact point is kept), where the contact sticks.
    mu, v0 = 0.3, 1.0
    w = resting_ball(model, mu)
    dt = w.dt
    w.velocities = [[v0, 0.0, 0.0]]
    w.step(int(round(0.05 / dt)))
    c = w.contacts()
    assert c["sliding"].tolist() == [True]
    fn, ft = np.linalg.norm(c["force_n"][0]), np.linalg.norm(c["force_t"][0])
    assert fn == pytest.approx(M * G, rel=1e-3)
    assert ft == pytest.approx(mu * fn, rel=1e-6)
    assert c["force_t"][0, 0] < 0.0, "friction opposes the slide"
    last = w.collider_books(last=True)
    shear, press = np.linalg.norm(last["tangential"][0]), np.linalg.norm(last["normal"][0])
    assert shear == pytest.approx(mu * press, rel=1e-3)
    # t* = 2 v₀ / (7 μ g) ≈ 0.097 s to roll; at 0.3 s it rolls and sticks
    w.step(int(round(0.3 / dt)))
    assert w.velocities[0, 0] == pytest.approx(5 / 7 * v0, rel=2e-3)
    c = w.contacts()
    assert c["sliding"].tolist() == [False]
    assert np.linalg.norm(c["force_t"][0]) < 1e-3 * mu * M * G


@pytest.mark.parametrize("model", MODELS)
def test_a_contact_point_lies_on_the_line_of_centres_split_by_the_radii(model):
    # Two balls of radii r and 2r pressed together: the point is at ρ_i = d r_i/(r_i + r_j)
    # from i towards j, and at ρ_j from j (d the distance of the centres).
    w = kinema.World(dim=3, dt=1e-5 if model != "impulse" else 1e-3)
    w.add_particles([[0.0, 0.0, 0.0], [0.029, 0.004, 0.0]], radius=[R, 2 * R], mass=M)
    w.set_collisions(restitution=0.5, friction=0.0, **MODELS[model])
    w.step()
    c = w.contacts()
    assert len(c["i"]) == 1
    xi, xj = w.positions[c["i"][0]], w.positions[c["j"][0]]
    d = np.linalg.norm(xj - xi)
    np.testing.assert_array_equal(w.radii, [R, 2 * R])
    ri, rj = w.radii[c["i"][0]], w.radii[c["j"][0]]
    np.testing.assert_allclose(c["point"][0], xi + (xj - xi) * ri / (ri + rj), atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(c["point"][0] - xj), d * rj / (ri + rj), rtol=1e-9)
