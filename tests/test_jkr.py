"""JKR cohesion of the Hertz model (issue 47): LAMMPS GRANULAR's ``jkr``,
``World.set_collisions(model="hertz", cohesion="jkr", surface_energy=γ)``.

Closed forms (Johnson, Kendall and Roberts 1971; Johnson, Contact Mechanics §5.5), R* the
reduced radius (R against a wall), E* = E / (2 (1 − ν²)), γ the surface energy (w = 2γ):

- the contact radius a and the overlap δ(a) = a²/R* − 2 √(π γ a / E*), the force
  F(a) = 4 E* a³ / (3 R*) − 4 √(π γ E* a³);
- the pull-off force F_po = 3π γ R* (3/2 π w R*), the least F, at δ_f = −(3π² γ² R* /
  (16 E*²))^(1/3), where a contact pulled apart lets go (LAMMPS's `pulloff_distance`);
- hysteresis: bodies touch at δ = 0, but once touching hold on past it, to δ_f. A ball
  hangs under a ceiling iff m g < F_po, at the overlap where F(a) = −m g on the stable branch
  (a > a_f), which for m g near F_po is negative: only a contact that remembers its touch
  holds there;
- the energy lost at a separation U_f = ∫₀^δ_f F dδ (the adhesive neck's work), so that
  with no dashpot (e = 1) a body approaching at u sticks iff m* u²/2 < U_f, and otherwise
  leaves at √(u² − 2 U_f / m*) (Thornton and Ning 1998's sticking velocity). U_f is computed
  here by quadrature of F(a) δ'(a), independently of the engine's closed form.
"""

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq
from test_cohesion import NU, E, G, M, R, hanging_scene  # (the ball of DMT's tests)

import kinema

E_STAR = E / (2 * (1 - NU**2))


def gamma_for(pull_off, r=R):
    """γ (J/m²) whose JKR pull-off 3π γ R* is `pull_off` (N) for reduced radius `r`."""
    return pull_off / (3 * math.pi * r)


def overlap(a, gamma, r=R):
    return a * a / r - 2 * math.sqrt(math.pi * gamma * a / E_STAR)


def force(a, gamma, r=R):
    return 4 * E_STAR * a**3 / (3 * r) - 4 * math.sqrt(math.pi * gamma * E_STAR * a**3)


def a_pull_off(gamma, r=R):
    """a_f, where F is least: a_f³ = 9π γ R*² / (4 E*)."""
    return (9 * math.pi * gamma * r * r / (4 * E_STAR)) ** (1 / 3)


def a_touch(gamma, r=R):
    """a₀ at δ = 0: a₀³ = 4π γ R*² / E*."""
    return (4 * math.pi * gamma * r * r / E_STAR) ** (1 / 3)


def overlap_under(load, gamma, r=R):
    """δ on the stable branch (a > a_f) where the contact's force is `load` (N, > 0 pushes)."""
    a_f = a_pull_off(gamma, r)
    a = brentq(lambda a: force(a, gamma, r) - load, a_f, 100 * a_f + 1e-3, xtol=1e-16, rtol=1e-15)
    return overlap(a, gamma, r)


def separation_energy(gamma, r=R):
    """U_f = ∫ F dδ from δ = 0 to δ_f, by quadrature over a (δ'(a) = 2a/R* − √(πγ/(E* a)))."""
    slope = lambda a: 2 * a / r - math.sqrt(math.pi * gamma / (E_STAR * a))  # noqa: E731
    value, _ = quad(lambda a: force(a, gamma, r) * slope(a), a_touch(gamma, r), a_pull_off(gamma, r), epsabs=0, epsrel=1e-13)
    return value


def jkr_world(gamma, dt=1e-6, restitution=0.1, gravity=(0, 0, -G), **collisions):
    w = kinema.World(dt=dt)
    if gravity is not None:
        w.add(kinema.Gravity(list(gravity)))
    w.set_collisions(model="hertz", youngs_modulus=E, poisson_ratio=NU, restitution=restitution, cohesion="jkr", surface_energy=gamma, **collisions)
    return w


def ceiling(pull_off_over_weight, **kw):
    """A ball touching a ceiling (plane through the origin facing down) with F_po = k m g."""
    w = jkr_world(gamma_for(pull_off_over_weight * M * G), **kw)
    w.add(kinema.Plane([0, 0, 0], [0, 0, -1]))
    w.add_particles([[0, 0, -(R - 1e-7)]], radius=R, mass=M)
    return w


def test_the_pull_off_distance_and_the_force_there_are_jkrs():
    # the closed forms the tests below lean on, checked against each other
    gamma = 0.01
    d_f = (3 * math.pi**2 * gamma**2 * R / (16 * E_STAR**2)) ** (1 / 3)
    assert overlap(a_pull_off(gamma), gamma) == pytest.approx(-d_f, rel=1e-12)
    assert force(a_pull_off(gamma), gamma) == pytest.approx(-3 * math.pi * gamma * R, rel=1e-12)
    assert force(a_touch(gamma), gamma) == pytest.approx(-8 / 9 * 3 * math.pi * gamma * R, rel=1e-12)


@pytest.mark.parametrize("ratio", [0.9, 1.02, 1.2, 3.0])
def test_a_ball_hangs_under_a_ceiling_only_while_the_pull_off_exceeds_its_weight(ratio):
    w = ceiling(ratio)
    w.step(100_000)  # 0.1 s
    c = w.contacts()
    if ratio > 1:
        gamma = gamma_for(ratio * M * G)
        assert len(c["i"]) == 1
        assert c["overlap"][0] == pytest.approx(overlap_under(-M * G, gamma), rel=1e-8)
        np.testing.assert_allclose(c["force_n"][0], [0, 0, M * G], rtol=1e-8)  # the ceiling holds its weight
        if ratio < 1.1:
            # near the pull-off the contact hangs apart (δ < 0): held past touching
            assert c["overlap"][0] < 0
    else:
        assert len(c["i"]) == 0 and w.velocities[0, 2] < -0.5, "it falls"


def test_a_ball_rests_on_a_floor_where_the_jkr_force_holds_its_weight():
    gamma = gamma_for(2.0 * M * G)
    w = jkr_world(gamma)
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.add_particles([[0, 0, R - 1e-7]], radius=R, mass=M)
    w.step(100_000)
    c = w.contacts()
    assert c["overlap"][0] == pytest.approx(overlap_under(M * G, gamma), rel=1e-8)
    np.testing.assert_allclose(c["force_n"][0], [0, 0, M * G], rtol=1e-8)


def bounce(u, gamma, dt=2e-8):
    """A ball without gravity or dashpot (e = 1) thrown at a floor at u (m/s): its speed
    after the contact (0 while it sticks), the energy the books say the contacts lost."""
    w = jkr_world(gamma, dt=dt, restitution=1.0, gravity=None)
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.add_particles([[0, 0, R + 2e-7]], radius=R, mass=M)
    w.velocities = [[0, 0, -u]]
    w.step(300_000)  # 6 ms: the slowest contact here lasts 4.3 ms
    stuck = len(w.contacts()["i"]) == 1
    return (0.0 if stuck else float(w.velocities[0, 2])), w.collision_stats()["total"]["energy_lost"]


@pytest.mark.parametrize("over", [0.8, 1.5, 3.0])
def test_a_ball_sticks_below_the_jkr_sticking_speed_and_leaves_with_the_energy_left_above(over):
    gamma = 0.05
    lost = separation_energy(gamma)
    u_stick = math.sqrt(2 * lost / M)
    u = over * u_stick
    out, booked = bounce(u, gamma)
    if over < 1:
        assert out == 0.0 and booked == 0.0
    else:
        # (to the step's sampling of the force's jump at the touch, −8/9 F_po: 1e-5 here)
        assert out == pytest.approx(math.sqrt(u * u - u_stick * u_stick), rel=1e-4)
        # the books count the neck's energy, lost as the contact let go
        assert booked == pytest.approx(lost, rel=1e-9)


def test_two_balls_stick_or_part_by_the_sticking_speed_of_their_pair():
    # R* = R/2, m* = M/2: the pair's U_f and sticking speed of the relative approach
    gamma, r_star = 0.05, R / 2
    u_stick = math.sqrt(2 * separation_energy(gamma, r_star) / (M / 2))
    for over, parts in [(0.8, False), (2.0, True)]:
        w = jkr_world(gamma, dt=2e-8, restitution=1.0, gravity=None)
        w.add_particles([[-R - 1e-7, 0, 0], [R + 1e-7, 0, 0]], radius=R, mass=M)
        u = over * u_stick
        w.velocities = [[u / 2, 0, 0], [-u / 2, 0, 0]]
        w.step(300_000)
        touching = len(w.contacts()["i"]) == 1
        assert touching != parts
        if parts:
            relative = w.velocities[1, 0] - w.velocities[0, 0]
            assert relative == pytest.approx(math.sqrt(u * u - u_stick * u_stick), rel=1e-4)
        np.testing.assert_allclose(w.velocities.sum(axis=0), [0, 0, 0], atol=1e-12)  # action and reaction


def test_a_hanging_ball_apart_from_its_ceiling_still_hangs_after_a_checkpoint(tmp_path):
    w = ceiling(1.02)
    w.step(50_000)
    assert w.contacts()["overlap"][0] < 0, "held past touching"
    path = w.save_checkpoint(tmp_path / "hang.h5")
    back = kinema.World.load_checkpoint(path)
    for world in (w, back):
        world.step(50_000)
    assert len(back.contacts()["i"]) == 1 and back.positions[0, 2] == w.positions[0, 2]


def test_jkr_steps_with_verlet_only_and_its_parameters_are_checked_by_name():
    w = kinema.World(dt=1e-6, method="rk4")
    w.set_collisions(model="hertz", youngs_modulus=E, cohesion="jkr", surface_energy=0.01)
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.add_particles([[0, 0, R - 1e-7]], radius=R, mass=M)
    with pytest.raises(ValueError, match=r"JKR cohesion .* method='verlet' only.*cohesion='dmt'"):
        w.step()
    with pytest.raises(ValueError, match=r"surface_energy = None is invalid: cohesion='jkr' needs .*3π γ R\*"):
        w.set_collisions(model="hertz", youngs_modulus=E, cohesion="jkr")
    with pytest.raises(ValueError, match=r"cohesion = 'wet' is invalid: .*'dmt'.*'jkr'"):
        w.set_collisions(model="hertz", youngs_modulus=E, cohesion="wet", surface_energy=0.1)
    with pytest.raises(ValueError, match=r"surface_energy = -0.1 is invalid: the surface energy γ of JKR"):
        w.set_collisions(model="hertz", youngs_modulus=E, cohesion="jkr", surface_energy=-0.1)
    w.set_collisions(model="hertz", youngs_modulus=E, cohesion="jkr", surface_energy=0.1)
    assert (w.collisions["cohesion"], w.collisions["surface_energy"]) == ("jkr", 0.1)


def test_a_scene_file_hangs_a_ball_with_jkr_adhesion(tmp_path):
    gamma = gamma_for(1.05 * M * G)
    w = kinema.Scene.from_toml(hanging_scene(tmp_path / "hang.toml", "jkr", gamma, 0.05)).build()
    w.step(50_000)
    assert w.contacts()["overlap"][0] == pytest.approx(overlap_under(-M * G, gamma), rel=1e-6)
    assert w.to_scene().collisions.cohesion == "jkr"


@pytest.mark.parametrize("cohesion", ["dmt", "jkr"])
def test_adhesion_given_to_a_world_that_has_a_hertz_model_acts_as_if_given_at_first(cohesion):
    """Two touching balls that adhesion pulls together. Giving the cohesion by a second
    `set_collisions` (the world already has Hertz's model without it) steps the same bits as
    giving it at once: the engine keeps its neighbour list across a change of settings and
    takes the new normal law whole (it once kept the old law's adhesion, none here, so the
    balls stayed apart)."""

    def pulled(settings_before: list[dict]) -> np.ndarray:
        w = kinema.World(dt=1e-5)
        w.add_particles([[0, 0, 0], [2 * R - 1e-5, 0, 0]], mass=M, radius=R)
        for s in settings_before:
            w.set_collisions(**s)
        w.step(2000)
        return w.positions

    hertz = {"model": "hertz", "youngs_modulus": E, "poisson_ratio": NU}
    adhesive = {**hertz, "cohesion": cohesion, "surface_energy": 1.0}
    at_once, later = pulled([adhesive]), pulled([hertz, adhesive])
    assert np.array_equal(at_once, later)
    assert at_once[1, 0] - at_once[0, 0] < 2 * R - 1e-5  # (the pull did draw them closer)
