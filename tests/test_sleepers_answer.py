"""Sleepers answer like the awake (issue 46): an island asleep is a shortcut for an island at
rest, never a different physics. Whatever reaches it (an impact inside a step, a write to a
sleeper's state) finds it as it would find it awake, and what the world reports of sleeping
is what sleeps now.

Theory used: a ball of speed u hitting the top of a resting column with restitution e
leaves at the speed Newton's law and the column's response give, whether the column was
asleep or awake; the rebound of a ball on a column resting on a floor is the same process
in both worlds, so the two outcomes agree to rounding. A ball spun at ω on a floor with
friction starts to roll (Coulomb's law), so a write of ω to a sleeping ball must set it
moving."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import kinema

G = 9.81


def _column(depth: int, e: float, sleep: bool, dt: float = 1e-3, mu: float = 0.0) -> kinema.World:
    """`depth` balls of radius 5 cm stacked on a floor at z = 0, at rest, under gravity;
    stepped 1.5 s (asleep after 0.5 s of calm when `sleep`)."""
    w = kinema.World(dt=dt, method="verlet")
    r = 0.05
    w.add_particles([[0.0, 0.0, r + 2 * r * k] for k in range(depth)], mass=1.0, radius=r)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(restitution=e, friction=mu, sleep_time=0.5 if sleep else None)
    w.step(int(round(1.5 / dt)))
    return w


def _drop_on(w: kinema.World, depth: int, speed: float) -> dict:
    """A ball 1 mm above the column's top falling at `speed`, stepped 20 steps: its largest
    upward speed after the impact, the impacts of the step that met the column, and the
    state at the end."""
    r = 0.05
    top = w.positions[depth - 1, 2]
    w.add_particles([[0.0, 0.0, top + 2 * r + 1e-3]], velocity=[[0.0, 0.0, -speed]], mass=1.0, radius=r)
    w.step(1)
    first = w.collision_stats()["last"]["impacts"]
    rebound = -np.inf
    for _ in range(19):
        w.step(1)
        rebound = max(rebound, w.velocities[-1, 2])
    return {"rebound": rebound, "first_step_impacts": first, "x": w.positions.copy(), "v": w.velocities.copy()}


@pytest.mark.parametrize("depth, e, speed", [(2, 0.3, 5.0), (2, 0.9, 3.0), (5, 0.5, 2.0)])
def test_an_impact_on_a_sleeping_column_is_the_impact_on_the_awake_column(depth, e, speed):
    # Before, the sleeping column was a body held at rest through the step: the ball's impact
    # ran through it as a chain of pair impacts against still bodies (25 of them in one step
    # for e = 0.3) and stopped it dead, where on the awake column it rebounds (0.31 m/s). Now
    # the island wakes before the step's impacts, and the two worlds go on bit for bit.
    asleep = _column(depth, e, sleep=True)
    assert asleep.collision_stats()["last"]["asleep"] == depth
    awake = _column(depth, e, sleep=False)
    assert awake.collision_stats()["last"]["asleep"] == 0
    np.testing.assert_array_equal(asleep.positions, awake.positions)  # the same column at rest
    a, b = _drop_on(asleep, depth, speed), _drop_on(awake, depth, speed)
    assert b["rebound"] > 0.1, "the awake column throws the ball back"
    assert a["first_step_impacts"] == b["first_step_impacts"] == 1
    if depth == 2:
        # a column of two holds the same totals step after step: the same bits
        assert a["rebound"] == b["rebound"]
        np.testing.assert_array_equal(a["x"], b["x"])
        np.testing.assert_array_equal(a["v"], b["v"])
    else:
        # a deeper one's warm start, kept asleep, differs from the one kept awake in the last
        # bits of its totals: the same outcome to rounding
        assert a["rebound"] == pytest.approx(b["rebound"], rel=1e-12)
        np.testing.assert_allclose(a["x"], b["x"], rtol=0, atol=1e-12)
        np.testing.assert_allclose(a["v"], b["v"], rtol=0, atol=1e-12 * speed)


def test_a_write_of_angular_velocity_wakes_a_sleeping_ball_and_it_rolls():
    # A ball asleep on a floor with friction, then spun at 100 rad/s about y: friction
    # turns the spin into rolling along x (Coulomb's law), as it does for the same ball awake.
    w = kinema.World(dt=1e-3, method="verlet", spin=True)
    w.add_particles([[0.0, 0.0, 0.05]], mass=1.0, radius=0.05)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(restitution=0.0, friction=0.5)
    w.step(1000)
    assert w.collision_stats()["last"]["asleep"] == 1
    w.angular_velocities[0] = [0.0, 100.0, 0.0]
    w.step(1)
    assert w.collision_stats()["last"]["asleep"] == 0
    w.step(199)
    # sliding until it rolls (at t = 2 ω r / (7 μ g) = 0.29 s): kinetic friction μ m g
    # speeds it up along +x and slows its spin, α = (μ m g r) / (2/5 m r²)
    mu, r, t = 0.5, 0.05, 0.2
    assert w.velocities[0, 0] == pytest.approx(mu * G * t, rel=1e-9)
    assert w.angular_velocities[0, 1] == pytest.approx(100.0 - 2.5 * mu * G / r * t, rel=1e-9)


def test_the_asleep_count_is_what_sleeps_now():
    # After every particle is removed nothing sleeps; before, collision_stats()["last"]
    # still reported the 16 of the last step.
    w = kinema.World(dt=1e-3, method="verlet")
    w.add_particles([[0.12 * i, 0.12 * j, 0.05] for i in range(4) for j in range(4)], mass=1.0, radius=0.05)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(restitution=0.0)
    w.step(1000)
    assert w.collision_stats()["last"]["asleep"] == 16
    w.remove_particles(range(16))
    assert w.collision_stats()["last"]["asleep"] == 0
    assert w.collision_stats()["last"]["asleep_contacts"] == 0


@pytest.mark.parametrize("stop", [0.3, 1.0])
def test_a_pile_sleeps_again_once_its_floors_keyframes_have_ended(stop):
    # Keyframes move the floor up 2 cm by `stop` s, then it rests at its last key: the
    # balls on it come to rest and sleep, as on a floor that never moved. Before, any
    # collider with a motion kept every island awake for ever.
    w = kinema.World(dt=1e-3, method="verlet")
    w.add_particles([[0.12 * i, 0.0, 0.05] for i in range(3)], mass=1.0, radius=0.05)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1], motion=kinema.Keyframes(times=[0.0, stop], translations=[[0, 0, 0], [0, 0, 0.02]])))
    w.set_collisions(restitution=0.0)
    w.step(int(round((stop + 1.5) / 1e-3)))
    assert w.collision_stats()["last"]["asleep"] == 3
    np.testing.assert_allclose(w.positions[:, 2], 0.07, atol=1e-3)


class MetLate(AssertionError):
    """A resting column met a step late, or the awake and sleeping worlds apart after it: the
    bug the test expects."""


@pytest.mark.xfail(
    strict=True,
    raises=MetLate,
    reason="issue 46: a resting body falls inside the step, so a ball that reaches it inside the step meets it at the step's end (docs/collisions.md)",
)
@pytest.mark.parametrize(
    "depth, speed, dt, sleep_time", [(4, 0.5, 2e-3, 0.1), (4, 0.5, 2e-3, 0.5), (2, 0.5, 2e-3, 0.1), (3, 0.25, 4e-3, 0.1), (1, 1.0, 1e-3, 0.1)]
)
def test_a_ball_that_reaches_a_resting_column_inside_the_step_meets_it_there_awake_and_asleep(depth, speed, dt, sleep_time):
    # A ball 1 mm above a resting column's top, falling at `speed`, reaches it inside the
    # step (1 mm at `speed` takes one step; gravity makes it a little less): Newton's law
    # says one impact in that step, whether the column sleeps or not. Today the awake
    # column's top ball falls on its free parabola inside the step like the ball, so they
    # meet only at the step's end: no impact in the step, in every case here. With
    # sleep_time = 0.1 s and 4 balls (the make-fuzz "sleeping" row's shrunk case, 7 wrong
    # answers of 4,000) the woken column is met in the step and the two worlds end ½ g dt²
    # (2e-5 m) apart. Holding a body at rest on its supports until its first impact (commit
    # 8517506, reverted for its cost) passed every case.
    def run(sleep: float | None) -> tuple[kinema.World, int]:
        w = kinema.World(dt=dt, method="verlet")
        w.add_particles([[0.0, 0.0, 0.05 + 0.1 * k] for k in range(depth)], mass=1.0, radius=0.05)
        w.add(kinema.Gravity())
        w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
        w.set_collisions(restitution=0.0, sleep_time=sleep)
        w.step(int(round(1.5 / dt)))
        assert w.collision_stats()["last"]["asleep"] == (depth if sleep else 0)
        top = w.positions[depth - 1, 2]
        w.add_particles([[0.0, 0.0, top + 0.1 + 1e-3]], velocity=[[0.0, 0.0, -speed]], mass=1.0, radius=0.05)
        w.step(1)
        met = w.collision_stats()["last"]["impacts"]
        w.step(4)
        return w, met

    (a, met_a), (b, met_b) = run(sleep_time), run(None)
    try:
        assert met_a == met_b == 1, f"impacts in the step: {met_a} asleep, {met_b} awake"
        np.testing.assert_allclose(a.positions, b.positions, rtol=0, atol=1e-12)
        np.testing.assert_allclose(a.velocities, b.velocities, rtol=0, atol=1e-9 * speed)
    except AssertionError as e:
        raise MetLate(str(e)) from e


@settings(max_examples=25, deadline=None)
@given(
    depth=st.integers(1, 4),
    e=st.floats(0.0, 1.0),
    mu=st.sampled_from([0.0, 0.3]),
    speed=st.floats(0.5, 8.0),
    dt=st.sampled_from([1e-3, 2e-3, 1 / 240]),
    offset=st.floats(-0.03, 0.03),
)
def test_an_impact_on_a_sleeping_column_of_any_depth_speed_and_step_is_the_awake_one(depth, e, mu, speed, dt, offset):
    # The class of the case above: columns of 1–4, any restitution, with and without
    # friction, other steps, the ball off the axis by up to 3 cm (so the impact turns it).
    # Compared through the step of the impact and the two after it. The awake column starts
    # from velocities of 1e-17 m/s, the sleeping one from exactly 0, and the engine decides
    # some things by an exact test (whether a contact's total is 0: a particle leaving it
    # moves by the step's parabola or by Euler, ½ g h² apart; whether a touching pair is an
    # impact or a contact), so the two agree to the engine's resolution: a step's fall
    # g h² in position, 1e-6 of the speed in velocity. Most cases agree to the bit. Before,
    # the sleeping column stopped the ball: a difference of the order of its speed.
    _sleeping_and_awake_agree(depth, e, mu, speed, dt, offset)


def _sleeping_and_awake_agree(depth: int, e: float, mu: float, speed: float, dt: float, offset: float) -> None:
    """The case of the test above: the ball met by the sleeping column and by the awake one,
    compared through the step of the impact and the two after it."""

    def run(sleep: bool) -> tuple[kinema.World, int]:
        w = _column(depth, e, sleep=sleep, dt=dt, mu=mu)
        assert w.collision_stats()["last"]["asleep"] == (depth if sleep else 0)
        top = w.positions[depth - 1, 2]
        w.add_particles([[offset, 0.0, top + 0.1 + 1e-3]], velocity=[[0.0, 0.0, -speed]], mass=1.0, radius=0.05)
        steps = 0  # until the ball meets the column (an impact, or a contact more)
        while steps < 100:
            w.step(1)
            steps += 1
            if w.collision_stats()["last"]["impacts"] or w.collision_stats()["last"]["resting"] > depth:
                break
        w.step(2)
        return w, steps

    (a, ka), (b, kb) = run(True), run(False)
    assert ka == kb < 100
    np.testing.assert_allclose(a.positions, b.positions, rtol=0, atol=G * dt**2)
    np.testing.assert_allclose(a.velocities, b.velocities, rtol=0, atol=1e-6 * speed)


@pytest.mark.xfail(
    strict=True,
    reason="found by the test above (2026-11-30, on the code of issue 50's close): a ball at 5 m/s onto a sleeping column "
    "of 3 at e = 0.248, dt = 2 ms ends 1.3e-4 m from the awake column's (over g dt^2 = 3.9e-5 m); left for the sleep work",
)
def test_a_ball_at_5_m_s_onto_a_sleeping_column_of_3_is_the_awake_one():
    _sleeping_and_awake_agree(3, 0.24755176342157387, 0.0, 5.0, 0.002, 0.0)
