"""The collisions' energy books are the same for every method and never create energy
(issue 46, "Energy books").

Closed form: a ball sliding a distance d under Coulomb friction μ with normal force N loses
μ N d to friction; with a constant force field the mechanical energy is ½ m |v|² + m g z (or
− F·x for a constant pull), and `collision_stats()["total"]["energy_lost"]` must be its drop.

Before, the books took the work of the forces from the step's fitted parabola through x₁,
which is the force for the second-order methods only: explicit Euler's x₁ = x₀ + v₀ h has no
acceleration at all (the books said −2.70 J for 2.92 J on the slope below), the symplectic
and implicit Euler steps have twice the force (+8.55 J)."""

import numpy as np
import pytest
from hypothesis import Phase, given, settings
from hypothesis import strategies as st

import kinema

G = 9.81
METHODS = kinema.method_names()


def _slope(method, angle_deg, mu, seconds=1.0, dt=1e-3):
    th = np.radians(angle_deg)
    n = np.array([-np.sin(th), 0.0, np.cos(th)])
    r = 0.1
    w = kinema.World(dim=3, dt=dt, method=method)
    w.add_particles(np.array([n * r]), radius=r, mass=2.0)
    w.add(kinema.Gravity())
    w.add(kinema.Plane(point=[0, 0, 0], normal=n))
    w.set_collisions(restitution=0.0, friction=mu)
    e0 = 2.0 * G * w.positions[0, 2]
    x0 = w.positions.copy()
    w.run(seconds)
    e1 = 0.5 * 2.0 * np.sum(w.velocities**2) + 2.0 * G * w.positions[0, 2]
    d = np.linalg.norm(w.positions - x0)
    return w.collision_stats()["total"]["energy_lost"], e0 - e1, d, th


@pytest.mark.parametrize("method", METHODS)
def test_a_ball_sliding_down_a_slope_books_mu_m_g_cos_theta_d_with_every_method(method):
    lost, drop, d, th = _slope(method, 30.0, 0.3)
    # closed form: friction takes μ m g cos θ d (the slide accelerates at g (sin θ − μ cos θ))
    assert lost == pytest.approx(0.3 * 2.0 * G * np.cos(th) * d, rel=5e-3)
    # and the books are the mechanical energy's drop, to rounding
    assert lost == pytest.approx(drop, rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("method", METHODS)
def test_a_ball_pulled_along_a_floor_books_the_pull_work_less_its_kinetic_energy(method):
    # a pull of 1.2 μ m g along x on a floor: friction takes μ m g d
    mu, m, r = 0.4, 1.5, 0.05
    pull = 1.2 * mu * m * G
    w = kinema.World(dim=3, dt=1e-3, method=method)
    w.add_particles(np.array([[0.0, 0.0, r]]), radius=r, mass=m)
    w.add(kinema.Gravity())
    w.add(kinema.Gravity(g=[pull / m, 0.0, 0.0]))
    w.add(kinema.Plane(point=[0, 0, 0], normal=[0, 0, 1]))
    w.set_collisions(restitution=0.0, friction=mu)
    w.run(1.0)
    d = w.positions[0, 0]
    lost = w.collision_stats()["total"]["energy_lost"]
    assert d > 0.1
    assert lost == pytest.approx(mu * m * G * d, rel=5e-3)
    assert lost == pytest.approx(pull * d - 0.5 * m * np.sum(w.velocities**2), rel=1e-9)


@settings(max_examples=40, deadline=None)
@given(
    method=st.sampled_from(METHODS),
    angle=st.floats(5.0, 60.0),
    mu=st.floats(0.0, 0.5),
    dt=st.sampled_from([5e-4, 1e-3, 4e-3]),
)
def test_the_slope_books_balance_for_every_method_angle_friction_and_step(method, angle, mu, dt):
    t = 0.4
    lost, drop, d, th = _slope(method, angle, mu, seconds=t, dt=dt)
    # sticking (μ ≥ tan θ) or sliding, the books are the mechanical energy's drop
    assert lost == pytest.approx(drop, rel=1e-9, abs=1e-9)
    if mu < np.tan(th) and d > 1e-3:
        # friction's μ m g cos θ d, and the resting contact's own step: it moves the ball by
        # symplectic Euler (x₁ = x₀ + h v₁), whose energy error on a constant acceleration a
        # is ½ m a² h² a step, ½ m a² h t in all (a = g (sin θ − μ cos θ) along the slope)
        a = G * (np.sin(th) - mu * np.cos(th))
        expected = mu * 2.0 * G * np.cos(th) * d + 0.5 * 2.0 * a**2 * dt * t
        # within 0.5 % of the energy the slide turned over, m g sin θ d
        assert abs(lost - expected) <= 5e-3 * 2.0 * G * np.sin(th) * d


# --- Energy never created by a collision (issue 46) -------------------------------------------
#
# Closed form: with restitution e ≤ 1, every impulse of Newton's law and every contact's
# solve takes kinetic energy or leaves it (e = 1, frictionless); none gives it. So each step's
# `energy_lost` is ≥ 0 up to what a converged solve leaves: it stops when no sweep changes a
# velocity by more than its tolerance (1e-9 m/s, `VELOCITY_TOLERANCE` in collide/response.rs),
# so a body at rest ends a step within that of 0 at both ends, and gravity's potential within
# 2 m g · 1e-9 m/s · h of its own (plus a relative 1e-12 of the energy for the sums' rounding).
#
# Today a body resting on a support falls on the forces' parabola inside the step (its
# supports act only in the end-of-step solve): a ball dropped on it meets it late, low and
# moving down, and the solve lifts the pair back at no cost (m g · ½ g τ²: 1.1e-6 J in one
# step for the first case below). These tests fail on that, and are strict xfails until it
# is fixed (issue 46; the hold of commit 8517506 passed all but the sweep, docs/collisions.md).

VELOCITY_TOLERANCE = 1e-9  # m/s, collide/response.rs


class EnergyCreated(AssertionError):
    """A converged step booked less than the solve's floor: the bug these tests expect. Any
    other failure (a scene with no impacts at all) is not it, and fails them."""


RESTING_BODY_FALLS = pytest.mark.xfail(
    strict=True,
    raises=EnergyCreated,
    reason="issue 46: a resting body falls inside the step; an impact on it creates energy (docs/collisions.md, Energy books)",
)


def _assert_none_created(below, hit, least_hits=1):
    assert hit >= least_hits, f"only {hit} steps had impacts: the scene tests nothing"
    if below:
        raise EnergyCreated(f"{len(below)} converged steps created energy: {below[:5]}")


def _stack(layers, per, gap, dt=1e-3, method="verlet", e=1.0, mu=0.0, r=0.05):
    """`layers` layers of per × per balls of radius r, the lowest on the floor, each `gap`
    above the one below and gap/2 from the walls of a box that fits them, under gravity."""
    w = kinema.World(dim=3, dt=dt, method=method)
    s = 2 * r + gap
    w.add_particles(np.array([[a * s + s / 2, b * s + s / 2, r + k * s] for k in range(layers) for a in range(per) for b in range(per)]), radius=r)
    w.add(kinema.Gravity())
    w.add(kinema.Box([0, 0, 0], [per * s, per * s, 10.0]))
    w.set_collisions(restitution=e, friction=mu)
    return w


def _created(w, seconds):
    """Steps `w` for `seconds`; returns the converged steps' `energy_lost` below the solve's
    floor (see above) as (step, J) pairs, and how many steps had impacts."""
    m = w.masses
    e0 = 0.5 * np.sum(m[:, None] * w.velocities**2) + G * np.sum(m * w.positions[:, 2])
    floor = -(1e-12 * e0 + 2 * m.sum() * G * VELOCITY_TOLERANCE * w.dt)
    below, hit = [], 0
    for k in range(round(seconds / w.dt)):
        w.step()
        last = w.collision_stats()["last"]
        hit += last["impacts"] > 0
        if last["unconverged"] == 0 and last["energy_lost"] < floor:
            below.append((k, last["energy_lost"]))
    return below, hit


@RESTING_BODY_FALLS
@pytest.mark.parametrize("gap", [0.01, 0.004, 0.02])
def test_a_ball_dropped_on_a_resting_ball_creates_no_energy(gap):
    # a ball `gap` above one resting on a floor Plane, e = 1: it falls on the lower one
    # (today, at 1 cm: one step of −1.12e-6 J, m g · ½ g τ² at τ = 0.15 ms into the step;
    # at 4 mm −1.5e-5 J, at 2 cm −3.6e-5 J)
    r = 0.05
    w = kinema.World(dim=3, dt=1e-3)
    w.add_particles([[0, 0, r], [0, 0, 3 * r + gap]], radius=r)
    w.add(kinema.Gravity())
    w.add(kinema.Plane(point=[0, 0, 0], normal=[0, 0, 1]))
    w.set_collisions(restitution=1.0)
    _assert_none_created(*_created(w, 0.3))


@RESTING_BODY_FALLS
def test_a_bouncing_column_and_a_stack_of_96_create_no_energy():
    # the cases at the default step: an e = 1 column of 5 with 2 mm gaps and a 3D e = 1
    # stack of 96 (4 × 4 × 6) bouncing for 2 s (today: four steps down to −2.6e-5 J in the
    # column, one of −4.5e-6 J in the stack)
    for w in (_stack(5, 1, 0.002), _stack(6, 4, 0.01)):
        _assert_none_created(*_created(w, 2.0), least_hits=51)


@RESTING_BODY_FALLS
@settings(max_examples=25, deadline=None, derandomize=True, database=None, phases=[Phase.explicit, Phase.generate])
@given(
    layers=st.integers(2, 8),
    per=st.sampled_from([1, 2]),
    gap=st.sampled_from([2e-3, 5e-3, 1e-2, 2e-2]),
    dt=st.sampled_from([5e-4, 1e-3]),
    method=st.sampled_from(["verlet", "midpoint", "heun", "rk4", "rk45"]),
    e=st.sampled_from([1.0, 0.9, 0.5]),
    mu=st.sampled_from([0.0, 0.3]),
)
def test_bouncing_stacks_never_create_energy(layers, per, gap, dt, method, e, mu):
    # the class: stacks of 2–32 balls bouncing on a floor for 1 s, any second-order method
    # (the first-order ones book their own contact error, m a² h² a step: see the slope above).
    # Measured over 100 such cases: 20 create up to 1.05e-4 J in a step today, none with the
    # hold of commit 8517506; but this sweep's own draws find one the hold misses too (7 balls,
    # 1 cm gaps, rk45, e = 0.9: −3.4e-6 J in one step). (Derandomized: a strict xfail must
    # fail the same way each run; not shrunk: it stops at its first failing stack.)
    _assert_none_created(*_created(_stack(layers, per, gap, dt, method, e, mu), 1.0))
