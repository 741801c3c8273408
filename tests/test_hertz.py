"""Hertz's contact law (``set_collisions(model="hertz", youngs_modulus=E, poisson_ratio=nu)``):
F_n = 4/3 E* √R* δ^(3/2) − c_n u_n, integrated as a force (collide/contact_force/law.rs).

Closed forms: the elastic impact of two Hertzian spheres lasts t_c = 2 I δ_max / u, with
δ_max = (5 m* u² / (4 k_h))^(2/5), k_h = 4/3 E* √R*, I = ∫₀¹ dx / √(1 − x^(5/2)) (Hertz 1882;
Landau & Lifshitz, Theory of Elasticity §9): t_c ∝ u^(−1/5). The elastic energy is
∫ F dδ = 8/15 E* √R* δ^(5/2), so the total energy is kept through an elastic contact.
"""

import numpy as np
import pytest
from scipy.integrate import quad

import kinema

E, NU, R, M = 1e7, 0.3, 0.01, 1e-3
E_STAR = E / (2 * (1 - NU * NU))
R_STAR, M_STAR = R / 2, M / 2
K_H = 4 / 3 * E_STAR * np.sqrt(R_STAR)
TWICE_I = 2 * quad(lambda x: 1 / np.sqrt(1 - x**2.5), 0, 1)[0]  # 2.943275...


def closed_contact_time(u):
    return TWICE_I * (5 * M_STAR * u * u / (4 * K_H)) ** 0.4 / u


def head_on(u, e=1.0, steps_per_contact=400, energies=False):
    """Two equal spheres meeting at relative speed u; returns the measured contact time (the
    overlap's first and last zero, interpolated between steps), the restitution measured and,
    with ``energies``, the total energy at each step of the contact."""
    dt = closed_contact_time(u) / steps_per_contact
    w = kinema.World(dt=dt)
    w.set_collisions(model="hertz", youngs_modulus=E, poisson_ratio=NU, restitution=e)
    gap = 3 * u * dt
    w.add_particles([[-R - gap / 2, 0, 0], [R + gap / 2, 0, 0]], velocity=[[u / 2, 0, 0], [-u / 2, 0, 0]], mass=M, radius=R)
    times, overlaps, total = [], [], []
    for _ in range(2 * steps_per_contact):
        times.append(w.time)
        overlaps.append(2 * R - (w.positions[1, 0] - w.positions[0, 0]))
        if energies:
            d = w.diagnostics()
            total.append(d["kinetic"] + d["potential"].get("contact", 0.0))
        w.step(1)
    t, o = np.array(times), np.array(overlaps)
    inside = np.flatnonzero(o > 0)
    first, last = inside[0], inside[-1]
    t_in = t[first - 1] + (t[first] - t[first - 1]) * (-o[first - 1]) / (o[first] - o[first - 1])
    t_out = t[last] + (t[last + 1] - t[last]) * o[last] / (o[last] - o[last + 1])
    e_out = (w.velocities[1, 0] - w.velocities[0, 0]) / u
    return t_out - t_in, e_out, np.array(total)


def test_the_contact_time_falls_as_the_fifth_root_of_the_impact_speed_over_three_decades():
    speeds = [0.01, 0.1, 1.0, 10.0]
    measured = np.array([head_on(u)[0] for u in speeds])
    closed = np.array([closed_contact_time(u) for u in speeds])
    np.testing.assert_allclose(measured, closed, rtol=1e-5)
    # the slope of log t_c against log u, decade by decade
    slopes = np.diff(np.log(measured)) / np.diff(np.log(speeds))
    np.testing.assert_allclose(slopes, -0.2, atol=1e-7)


def test_an_elastic_hertzian_impact_keeps_its_energy_and_bounces_back_whole():
    _, e_out, total = head_on(1.0, energies=True)
    assert e_out == pytest.approx(1.0, abs=1e-7)
    # kinetic + 8/15 E* √R* δ^(5/2) through the contact: kept up to Verlet's error, which is
    # O(dt²) (a potential that were not the force's integral would leave an O(1) error)
    _, _, finer = head_on(1.0, steps_per_contact=800, energies=True)
    error, finer_error = np.ptp(total) / total[0], np.ptp(finer) / finer[0]
    assert error < 3e-5
    assert error / finer_error == pytest.approx(4.0, rel=0.05)


@pytest.mark.parametrize("e", [0.1, 0.3, 0.5, 0.9])
def test_the_damping_gives_nearly_the_set_restitution_at_every_speed(e):
    # LAMMPS's coeff_restitution damping for Hertz (Tsuji's form) is an approximation of the
    # set e, and the same at every speed (the law has no length or speed scale of its own
    # once δ is measured in δ_max): measured at 1000 steps per contact.
    got = [head_on(u, e, steps_per_contact=1000)[1] for u in (0.01, 1.0, 10.0)]
    assert np.ptp(got) < 1e-4
    assert got[1] == pytest.approx(e, abs=2e-3)


def test_a_hertz_pile_rests_on_its_floor_with_the_overlap_its_weight_gives():
    # A ball at rest on a floor: m g = 4/3 E* √r δ^(3/2) (against a wall R* = r).
    g, m, r = 9.81, 0.01, 0.02
    w = kinema.World(dt=2e-5)
    w.add(kinema.Gravity([0, 0, -g]))
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(model="hertz", youngs_modulus=E, poisson_ratio=NU, restitution=0.3)
    w.add_particles([0, 0, r], mass=m, radius=r)
    w.step(20000)
    delta = r - w.positions[0, 2]
    assert delta == pytest.approx((m * g / (4 / 3 * E_STAR * np.sqrt(r))) ** (2 / 3), rel=1e-6)


def test_hertz_takes_its_parameters_and_refuses_the_others():
    w = kinema.World()
    with pytest.raises(ValueError, match="youngs_modulus = None is invalid: model='hertz' needs"):
        w.set_collisions(model="hertz")
    with pytest.raises(ValueError, match="poisson_ratio = 0.5 is invalid"):
        w.set_collisions(model="hertz", youngs_modulus=1e9, poisson_ratio=0.5)
    with pytest.raises(ValueError, match="stiffness = 1000 is invalid: only model='spring_dashpot' uses it"):
        w.set_collisions(model="hertz", youngs_modulus=1e9, stiffness=1e3)
    with pytest.raises(ValueError, match="damping = 3 is invalid: model='hertz' takes its damping from the restitution"):
        w.set_collisions(model="hertz", youngs_modulus=1e9, damping=3.0)
    with pytest.raises(ValueError, match="youngs_modulus = 1000000000 is invalid: only model='hertz' uses it"):
        w.set_collisions(model="spring_dashpot", stiffness=1e3, youngs_modulus=1e9)
    w.set_collisions(model="hertz", youngs_modulus=1e9, restitution=0.5)
    assert w.collisions["model"] == "hertz" and w.collisions["poisson_ratio"] == 0.3
    w.set_collisions(**w.collisions)  # round-trips
    assert w.collisions["youngs_modulus"] == 1e9


def test_a_step_coarser_than_a_twentieth_of_the_contact_warns_with_the_restitution_it_gives():
    # Hooke: t_c = π / (ω₀ √(1 − ζ²)), ω₀² = k / m*, ζ = −ln e / √(π² + ln² e).
    import warnings

    from kinema.contact_time import restitution_at

    k, m, e = 1e4, 1e-3, 0.3
    zeta = -np.log(e) / np.sqrt(np.pi**2 + np.log(e) ** 2)
    t_c = np.pi / (np.sqrt(k / (m / 2)) * np.sqrt(1 - zeta**2))

    def pair(dt):
        w = kinema.World(dt=dt)
        w.set_collisions(model="spring_dashpot", stiffness=k, restitution=e)
        w.add_particles([[-0.0101, 0, 0], [0.0101, 0, 0]], velocity=[[0.5, 0, 0], [-0.5, 0, 0]], mass=m, radius=0.01)
        return w

    fine = pair(t_c / 100)
    assert fine.contact_time() == pytest.approx(t_c, rel=1e-12)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fine.step(1)  # 100 steps per contact: no warning
    coarse = pair(t_c / 8)
    with pytest.warns(kinema.ContactTimeWarning, match=r"spans 8 steps of the shortest contact") as got:
        coarse.step(100)
    # the restitution it names is the one this pair comes out with (to the spread the phase
    # of the first touch within a step gives at 8 steps per contact)
    said = float(str(got[0].message).split("this step gives e = ")[1].split(" ")[0])
    measured = coarse.velocities[1, 0] - coarse.velocities[0, 0]
    assert said == pytest.approx(measured, abs=2e-3)
    assert said == pytest.approx(restitution_at("spring_dashpot", "verlet", 8.0, e), abs=5e-5)  # (printed to 4 digits)
    assert abs(said - e) > 0.02  # and it is off


def test_the_hertz_contact_time_is_the_fastest_approachs():
    # kinema.first_step's bound between particles: the lightest pair (m* = M/2), the largest
    # radii (R* = r/2) at the sum of the two fastest speeds, 1 + 0.5 m/s: here the pair's own
    # head-on contact, t_c = 2 I δ_max / u
    w = kinema.World(dt=1e-6)
    w.set_collisions(model="hertz", youngs_modulus=E, poisson_ratio=NU)
    w.add_particles([[0, 0, 0], [0.05, 0, 0]], velocity=[[1.0, 0, 0], [-0.5, 0, 0]], mass=M, radius=R)
    assert w.contact_time() == pytest.approx(closed_contact_time(1.5), rel=1e-12)
    # a third, slower particle changes nothing; a faster one shortens it
    w.add_particles([0.1, 0, 0], velocity=[0, 0.2, 0], mass=M, radius=R)
    assert w.contact_time() == pytest.approx(closed_contact_time(1.5), rel=1e-12)
    w.velocities[2] = [0, 3.0, 0]
    assert w.contact_time() == pytest.approx(closed_contact_time(4.0), rel=1e-12)
    still = kinema.World()
    still.set_collisions(model="hertz", youngs_modulus=E)
    still.add_particles([[0, 0, 0], [0.05, 0, 0]], radius=R)
    assert still.contact_time() is None  # nothing moves, nothing falls: no contact to time
