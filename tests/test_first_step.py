"""The time-step check before a force model's first step (``kinema.first_step``): the
contact time of the fastest impact the scene can produce and the Rayleigh time, against their
closed forms and against measured contacts.

Closed forms: an elastic Hertzian impact at approach speed u lasts
t_c = 2 I δ_max / u = 2 I (15/16)^(2/5) (m*² / (R* E*² u))^(1/5), I = ∫₀¹ dx / √(1 − x^(5/2))
(Landau & Lifshitz §9; Johnson, Contact Mechanics §11.4, who rounds the constant to 2.87); a
ball falling a height h meets the floor at u = √(2 g h); the Rayleigh time of a sphere is
T_R = π r √(ρ/G) / (0.1631 ν + 0.8766), G = E / (2 (1 + ν)) (as LIGGGHTS's
``fix check/timestep/gran`` computes it).
"""

import math
import warnings

import numpy as np
import pytest
from scipy.integrate import quad

import kinema
from kinema import first_step
from kinema.contact_time import hertz_contact_time

E, NU, R, RHO, G = 1e7, 0.3, 0.01, 2500.0, 9.81
M = RHO * 4 / 3 * np.pi * R**3
E_STAR = E / (2 * (1 - NU * NU))
TWICE_I = 2 * quad(lambda x: 1 / np.sqrt(1 - x**2.5), 0, 1)[0]


def johnson(m_star, r_star, u):
    return TWICE_I * (15 / 16) ** 0.4 * (m_star**2 / (r_star * E_STAR**2 * u)) ** 0.2


def column(dt, n=10, gap=0.005):
    """A Hertz column of n glass-like balls (r = 1 cm, ρ = 2500 kg/m³, E = 10 MPa), each
    `gap` above the one below and the lowest `gap` above the floor, at rest under gravity."""
    w = kinema.World(dt=dt)
    w.add(kinema.Gravity([0, 0, -G]))
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(model="hertz", youngs_modulus=E, poisson_ratio=NU, restitution=0.5)
    w.add_particles([[0, 0, R + gap + k * (2 * R + gap)] for k in range(n)], mass=M, radius=R)
    return w


def contact_duration(w, i, touching, steps):
    """The time particle i spends in its first contact (touching(w) true), interpolated at
    both ends on the gap touching(w) returns as a number (< 0: touching)."""
    t, gap = [], []
    for _ in range(steps):
        t.append(w.time)
        gap.append(touching(w))
        w.step(1)
    t, gap = np.array(t), np.array(gap)
    inside = np.flatnonzero(gap < 0)
    first = inside[0]
    last = first + np.flatnonzero(gap[first:] >= 0)[0] - 1
    t_in = t[first - 1] + (t[first] - t[first - 1]) * gap[first - 1] / (gap[first - 1] - gap[first])
    t_out = t[last] + (t[last + 1] - t[last]) * gap[last] / (gap[last] - gap[last + 1])
    return t_out - t_in


def test_the_hertz_contact_time_is_johnsons_closed_form_and_a_measured_two_ball_collision():
    # the constant: 2 I (15/16)^(2/5) = 2.868, Johnson's 2.87
    assert TWICE_I * (15 / 16) ** 0.4 == pytest.approx(2.87, abs=0.005)
    m_star, r_star, u = M / 2, R / 2, 1.3
    t_c = hertz_contact_time(m_star, r_star, E_STAR, u)
    assert t_c == pytest.approx(johnson(m_star, r_star, u), rel=1e-13)
    # measured: two balls meeting head on at 1.3 m/s, 1000 steps per contact
    w = kinema.World(dt=t_c / 1000)
    w.set_collisions(model="hertz", youngs_modulus=E, poisson_ratio=NU, restitution=1.0)
    w.add_particles([[-R - 0.0005, 0, 0], [R + 0.0005, 0, 0]], velocity=[[u / 2, 0, 0], [-u / 2, 0, 0]], mass=M, radius=R)
    assert w.contact_time() == pytest.approx(t_c, rel=1e-13)
    measured = contact_duration(w, 0, lambda w: w.positions[1, 0] - w.positions[0, 0] - 2 * R, 3000)
    assert measured == pytest.approx(t_c, rel=1e-5)


def test_a_fall_onto_the_floor_times_the_contact_at_the_speed_of_the_fall():
    # a ball at rest h above the floor meets it at u = √(2 g h): m* = m, R* = r against a wall.
    # Measured, the contact is longer by gravity's share of the force (m g is 0.3 % of the
    # contact's peak force 5/4 m u² / δ_max here; measured 0.13 % longer)
    h = 0.2
    t_c = johnson(M, R, np.sqrt(2 * G * h))
    w = kinema.World(dt=t_c / 1000)
    w.add(kinema.Gravity([0, 0, -G]))
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(model="hertz", youngs_modulus=E, poisson_ratio=NU, restitution=1.0)
    w.add_particles([0, 0, R + h], mass=M, radius=R)
    assert w.contact_time() == pytest.approx(t_c, rel=1e-12)
    w.step(int(np.sqrt(2 * h / G) / w.dt) - 50)
    measured = contact_duration(w, 0, lambda w: w.positions[0, 2] - R, 1200)
    assert measured == pytest.approx(t_c, rel=2e-3)
    assert measured > t_c


def test_the_hertz_column_dropped_from_rest_at_1_ms_warns_once_and_still_diverges():
    w = column(1e-3)
    found = first_step.check(w, w._core)
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        with pytest.raises(kinema.SimulationDiverged):
            w.run(1.0, fps=50)
    said = [str(g.message) for g in got if issubclass(g.category, kinema.ContactTimeWarning)]
    assert len(said) == 1, said
    assert not [g for g in got if issubclass(g.category, kinema.StabilityWarning)]
    # the fastest impact: the top ball falls 10 gaps + 9 diameters onto the floor's level, the
    # pair bound adds the two fastest such speeds (m* = m/2, R* = r/2)
    u_top = np.sqrt(2 * G * (10 * 0.005 + 9 * 2 * R))
    u_next = np.sqrt(2 * G * (9 * 0.005 + 8 * 2 * R))
    assert found.contact.t_c == pytest.approx(johnson(M / 2, R / 2, u_top + u_next), rel=1e-12)
    assert "dt = 0.001 s spans 1.54 steps of the shortest contact" in said[0]
    assert "beyond the stable step of method 'verlet' on that contact" in said[0]
    assert f"Use dt <= {first_step._round_down(found.dt_safe)} s" in said[0]


def test_the_hertz_column_at_the_safe_step_runs_without_a_warning():
    safe = first_step.check(probe := column(1e-3), probe._core).dt_safe
    w = column(float(first_step._round_down(safe)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        w.run(0.3, fps=20)
    assert np.all(np.isfinite(w.positions))
    # and 2.5 times coarser, between it and the divergence, warns
    with pytest.warns(kinema.ContactTimeWarning, match="restitution drifts"):
        column(2.5 * safe).step(1)


def test_the_rayleigh_time_limits_slow_scenes():
    # one ball resting on the floor: no impact to time, so the Rayleigh time alone limits dt
    shear = E / (2 * (1 + NU))
    t_r = np.pi * R * np.sqrt(RHO / shear) / (0.1631 * NU + 0.8766)
    assert first_step.rayleigh_time(R, M, E, NU) == pytest.approx(t_r, rel=1e-13)

    def resting(dt):
        w = kinema.World(dt=dt)
        w.add(kinema.Gravity([0, 0, -G]))
        w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
        w.set_collisions(model="hertz", youngs_modulus=E, poisson_ratio=NU, restitution=0.5)
        w.add_particles([0, 0, R], mass=M, radius=R)
        return w

    assert resting(1e-5).contact_time() is None
    with pytest.warns(kinema.ContactTimeWarning, match=r"Rayleigh time T_R = 0.000865 s, over the 0.2 T_R") as got:
        resting(0.25 * t_r).step(1)
    assert f"Use dt <= {first_step._round_down(0.2 * t_r)} s" in str(got[0].message)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        resting(0.19 * t_r).step(1)


def test_an_emitters_particles_count_before_they_exist():
    # nothing in the world yet: particles shot down at 8 m/s from 0.5 m meet the floor at
    # √(8² + 2 g (0.5 − r)); the smallest (r = R/2) and the largest (3R/2) are both tried, and
    # two of them meet at most at the sum of their speeds (the lightest pair, two small ones;
    # the largest R*, two large ones)
    w = kinema.World(dt=2e-4)
    w.add(kinema.Gravity([0, 0, -G]))
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(model="hertz", youngs_modulus=E, poisson_ratio=NU, restitution=0.5)
    w.add(kinema.Emitter(rate=10, center=[0, 0, 0.5], direction=[0, 0, -1], speed=8.0, particle_radius=R, radius_spread=R / 2, density=RHO))
    radii = np.array([R / 2, 3 * R / 2])
    mass = RHO * 4 / 3 * np.pi * radii**3
    u = np.sqrt(8.0**2 + 2 * G * (0.5 - radii))
    walls = johnson(mass, radii, u)
    pair = johnson(mass[0] / 2, radii[1] / 2, 2 * u.max())
    assert w.contact_time() == pytest.approx(min(walls.min(), pair), rel=1e-12)
    with pytest.warns(kinema.ContactTimeWarning, match="two particles meeting .* the two fastest: emitter 0's particle of r = 0.005 m\\)"):
        w.step(1)


def test_a_moving_collider_adds_its_speed():
    # no gravity; a floor rising at 3 m/s under a ball at rest: u = 3 m/s (m* = m, R* = r)
    w = kinema.World(dt=1e-6)
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1], motion=kinema.Motion(velocity=[0, 0, 3.0])))
    w.set_collisions(model="hertz", youngs_modulus=E, poisson_ratio=NU)
    w.add_particles([0, 0, 0.05], mass=M, radius=R)
    assert w.contact_time() == pytest.approx(johnson(M, R, 3.0), rel=1e-9)


def test_a_sphere_obstacle_bounds_the_fall_by_its_bottom():
    # a ball h = 0.1 m above a sphere obstacle's top (R = 0.2 m): conservatively, the fall
    # ends resting on the obstacle's lowest point, 2R + h below (module doc, stage 1)
    w = kinema.World(dt=1e-6)
    w.add(kinema.Gravity([0, 0, -G]))
    w.add(kinema.SphereObstacle([0, 0, 0], 0.2))
    w.set_collisions(model="hertz", youngs_modulus=E, poisson_ratio=NU)
    w.add_particles([0, 0, 0.2 + R + 0.1], mass=M, radius=R)
    assert w.contact_time() == pytest.approx(johnson(M, R, np.sqrt(2 * G * (0.4 + 0.1))), rel=1e-12)


def test_the_spring_dashpot_contact_time_does_not_wait_for_speed():
    # Hooke: t_c = π / (ω₀ √(1 − ζ²)), ω₀² = k / m*, whatever the speeds; a lone particle
    # over a floor: m* = m
    k, e = 1e3, 0.5
    zeta = -np.log(e) / np.sqrt(np.pi**2 + np.log(e) ** 2)
    w = kinema.World(dt=1e-3)
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(model="spring_dashpot", stiffness=k, restitution=e)
    w.add_particles([0, 0, 0.5], mass=M, radius=R)
    t_c = np.pi / (np.sqrt(k / M) * np.sqrt(1 - zeta**2))
    assert w.contact_time() == pytest.approx(t_c, rel=1e-12)
    with pytest.warns(kinema.ContactTimeWarning, match="lightest particle against a collider"):
        w.step(1)


def test_the_divergence_message_advises_only_what_the_world_accepts_and_prints_times_as_written():
    # the column with friction steps with Verlet only (a ValueError for implicit_euler)
    w = column(1e-3)
    w.set_collisions(model="hertz", youngs_modulus=E, poisson_ratio=NU, restitution=0.5, friction=0.5)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(kinema.SimulationDiverged) as got:
            w.run(1.0, fps=50)
    text = str(got.value)
    assert f"(t = {got.value.time:g} s, dt = 0.001 s)" in text
    assert "implicit_euler" not in text


def test_the_damping_ratio_has_one_home_the_engines():
    # ζ(e) = −ln e / √(π² + ln² e) (Schwager & Pöschel's spring–dashpot): the engine's
    # kinema::collide::damping_ratio, which contact_time asks (it kept its own copy); the
    # closed form at e = 0.5, critical at e = 0, none at e = 1; e outside [0, 1] refused.
    from kinema import _core, contact_time

    ln = math.log(2.0)
    assert _core.damping_ratio(0.5) == pytest.approx(ln / math.sqrt(math.pi**2 + ln**2), rel=1e-15)
    assert (_core.damping_ratio(0.0), _core.damping_ratio(1.0)) == (1.0, 0.0)
    for e in (0.0, 0.1, 0.5, 0.9, 1.0):
        assert contact_time._zeta(e) == _core.damping_ratio(e)
    with pytest.raises(ValueError, match=r"restitution = 1\.5 is invalid: the coefficient of restitution must be in \[0, 1\]"):
        _core.damping_ratio(1.5)
