"""What docs/collisions.md says of the force models (``spring_dashpot``, ``hertz``) and spin,
each sentence's behaviour measured: their contacts have friction (a tangential spring with
memory) and turn particles in a world with spin (§Friction, §Spin, §Known limits); a grain
rides a moving collider by that friction (§Moving colliders, examples/scenes/drum.toml); and
``collision_stats()`` reports them (§Known limits, §``w.collision_stats()``).

Closed forms: a ball thrown along a floor without spin slides, keeping its angular momentum
about the contact point, until it rolls at v = v₀ / (1 + I/(m ρ²)) (ρ = r − δ the lever arm at
the static overlap δ; 5/7 v₀ as δ → 0), with Hertz's δ from m g = 4/3 E* √r δ^(3/2); a grain at
rest on a belt moving at V is pushed by the sliding friction μ m g, v = μ g t, until it rides
at V from t = V/(μ g) on.
"""

import math

import numpy as np
import pytest

import kinema

G, R, M = 9.81, 0.01, 0.01
E, NU = 1e7, 0.3
E_STAR = E / (2 * (1 - NU * NU))
K_N = 1e4


def hertz_overlap(m=M, r=R):
    """δ at rest on a floor: m g = 4/3 E* √r δ^(3/2) (R* = r against a wall)."""
    return (m * G / (4 / 3 * E_STAR * np.sqrt(r))) ** (2 / 3)


def on_floor(model, mu, spin, floor_motion=None, dt=1e-5):
    w = kinema.World(dt=dt, method="verlet", spin=spin)
    w.add(kinema.Gravity([0, 0, -G]))
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1], motion=floor_motion))
    if model == "hertz":
        w.set_collisions(model="hertz", youngs_modulus=E, poisson_ratio=NU, restitution=0.3, friction=mu, tangential="mindlin")
        delta = hertz_overlap()
    else:
        w.set_collisions(model="spring_dashpot", stiffness=K_N, restitution=0.3, friction=mu)
        delta = M * G / K_N
    w.add_particles([0, 0, R - delta], mass=M, radius=R)
    return w, delta


def test_a_hertz_mindlin_ball_thrown_along_a_floor_ends_rolling_at_five_sevenths():
    # §Spin, §Friction, §Known limits: the force models have friction and turn particles
    v0, mu = 1.0, 0.3
    w, delta = on_floor("hertz", mu, spin=True)
    w.velocities[0] = [v0, 0, 0]
    w.step(40_000)  # 0.4 s; sliding ends at 2 v₀ / (7 μ g) = 0.097 s
    rho = R - delta
    closed = v0 / (1 + 0.4 * R * R / (rho * rho))
    v, om = w.velocities[0, 0], w.angular_velocities[0, 1]
    assert v == pytest.approx(closed, rel=1e-9)
    assert closed == pytest.approx(5 / 7 * v0, rel=1e-2)  # (ρ = r − 2.6e-5 m)
    assert om * rho == pytest.approx(v, rel=1e-9)  # rolling: no slip at the contact


@pytest.mark.parametrize("model", ["spring_dashpot", "hertz"])
def test_a_force_model_grain_rides_a_moving_belt_at_its_speed(model):
    # §Moving colliders: a floor moving along itself at V = 0.2 m/s drags a grain at rest by
    # friction, v = μ g t, until it rides at V (t = V/(μ g) = 0.068 s; then the stuck
    # tangential spring's damped swing about V dies out: 5.6e-6 m/s off at 0.1 s, 1.2e-13 at
    # 0.2 s with the linear spring, 1.5e-10 with Mindlin's, none at 0.3 s)
    V, mu = 0.2, 0.3
    w, _ = on_floor(model, mu, spin=False, floor_motion=kinema.Motion(velocity=[V, 0, 0]))
    w.step(3000)  # 0.03 s: sliding
    assert w.velocities[0, 0] == pytest.approx(mu * G * w.time, rel=2e-3)
    w.step(27_000)  # 0.3 s
    assert w.velocities[0, 0] == pytest.approx(V, abs=1e-12)
    assert abs(w.velocities[0, 1]) < 1e-12


def test_collision_stats_reports_the_force_models():
    # §Known limits, §w.collision_stats(): a ball dropped 0.1 m onto the floor with e = 0.8
    # meets it at t₁ = √(2h/g) = 0.143 s and at t₁ (1 + 2e) = 0.371 s, the next at
    # t₁ (1 + 2e + 2e²) = 0.554 s: by 0.4 s two contacts begun (`impacts`), none touching in
    # flight; the dashpots' books are the mechanical energy lost (to the rectangle rule's
    # 1.5e-4 at this step), which is m g h (1 − e⁴) to 0.84 %: e is each contact's closed-form
    # restitution without gravity, which pushes on through its t_c = π/√(k/m) = 3.1 ms
    e, h = 0.8, 0.1
    w = kinema.World(dt=2e-5, method="verlet")
    w.add(kinema.Gravity([0, 0, -G]))
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(model="spring_dashpot", stiffness=K_N, restitution=e)
    w.add_particles([0, 0, R + h], mass=M, radius=R)
    w.step(int(0.4 / w.dt))
    stats = w.collision_stats()
    assert stats is not None and stats["total"]["impacts"] == 2
    assert stats["last"]["contacts"] == 0
    d = w.diagnostics()
    mechanical = M * G * (R + h) - d["kinetic"] - d["potential"]["gravity"]
    assert stats["total"]["energy_lost"] == pytest.approx(mechanical, rel=2e-4)
    assert stats["total"]["energy_lost"] == pytest.approx(M * G * h * (1 - e**4), rel=1e-2)


def test_a_force_model_drum_lifts_a_grain():
    # §Moving colliders, examples/scenes/drum.toml: the drum (a closed mesh, R = 0.25 m,
    # inside = true) turning at ω = 1.2 rad/s about y carries a grain at its bottom up its
    # side by friction (μ = 0.8) with the spring–dashpot model: stuck to the wall (and not
    # turning: no spin), the grain moves as the wall's surface at the contact, ω (d + r) (d its
    # centre's distance from the axis), and is lifted past 30° in 0.5 s (at ω t = 34°); it
    # slides back only beyond tan θ = μ, 38.7°
    from pathlib import Path

    drum = Path(__file__).resolve().parent.parent / "examples" / "scenes" / "drum.obj"
    m, r, omega = 0.0032, 0.006, 1.2
    w = kinema.World(dt=5e-5, method="verlet")
    w.add(kinema.Gravity([0, 0, -G]))
    w.add(kinema.Mesh(drum, inside=True, friction=0.8, motion=kinema.Motion(angular_velocity=[0, omega, 0])))
    w.set_collisions(model="spring_dashpot", stiffness=1e4, restitution=0.3, friction=0.8)
    w.add_particles([0, 0, -0.25 + r + 0.001], mass=m, radius=r)
    w.step(10_000)
    x, v = w.positions[0], w.velocities[0]
    assert np.degrees(np.arctan2(-x[0], -x[2])) > 30.0
    assert np.linalg.norm(v) == pytest.approx(omega * (np.hypot(x[0], x[2]) + r), rel=1e-3)


@pytest.mark.parametrize("model", [dict(model="spring_dashpot", stiffness=1e4), dict(model="hertz", youngs_modulus=1e7)])
def test_the_force_models_wrap_positions_into_a_periodic_cell(model):
    # collisions.md §Periodic boxes: positions are wrapped into [lo, hi) after every step with
    # every contact model: a ball crossing x = 1 at 1 m/s from 0.9 is at 0.9 + 0.3 − 1 = 0.2
    # after 0.3 s
    w = kinema.World(dt=1e-3)
    w.add(kinema.Box([0, 0, 0], [1, 1, math.inf]))
    w.periodic = (True, True, False)
    w.set_collisions(**model)
    w.add_particles([[0.9, 0.5, 0.5]], velocity=[[1.0, 0, 0]], mass=1.0, radius=0.01)
    w.step(300)
    np.testing.assert_allclose(w.positions[0], [0.2, 0.5, 0.5], atol=1e-12)
