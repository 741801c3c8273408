"""Begin and end of touch (``World.record_contact_events``, ``World.contact_events``), against
the closed-form times and impulses of a bouncing ball and of a head-on impact, and the rules of
``collide/touch.rs``: a pile at rest begins nothing when recording starts, a sleeping island
ends nothing, a removed particle ends its touches, ids (not indices) name the particles."""

import math

import numpy as np
import pytest

import kinema

G = 9.81


def bouncing_ball(e, height, dt, seconds, radius=0.1, mass=1.0):
    """A ball of `radius` whose lowest point is `height` above a floor, dropped from rest under
    gravity with restitution e, recorded for `seconds`."""
    w = kinema.World(dim=3, dt=dt)
    w.add_particles([[0.0, 0.0, height + radius]], radius=radius, mass=mass)
    w.add(kinema.Gravity(g=(0.0, 0.0, -G)))
    w.add(kinema.Plane(point=(0.0, 0.0, 0.0), normal=(0.0, 0.0, 1.0)))
    w.set_collisions(restitution=e)
    w.record_contact_events()
    w.step(round(seconds / dt))
    return w


@pytest.mark.parametrize("e, height, dt", [(0.8, 1.0, 1e-3), (0.5, 2.5, 4e-3), (0.9, 0.3, 1 / 60)])
def test_a_bouncing_ball_begins_each_touch_at_its_impact_time_with_its_impulse(e, height, dt):
    # Free fall from rest: the first impact at t₁ = √(2H/g) with speed v₁ = g t₁; Newton's law
    # sends it up at e v₁, so the k-th impact (k = 1, 2, …) comes at speed e^(k−1) v₁, a flight
    # of 2 e^(k−1) v₁/g after the one before, and exchanges the impulse m (1 + e) e^(k−1) v₁. Each bounce begins a
    # touch at its impact (continuous detection finds its time inside the step) and ends it at
    # the end of that step (the ball is off the floor again).
    m = 1.0
    w = bouncing_ball(e, height, dt, seconds=3.0, mass=m)
    ev = w.contact_events()
    v1 = math.sqrt(2 * G * height)
    begins = ev["time"][ev["begin"]]
    # the bounces: each begin with an end after it (a last begin alone is the ball at rest,
    # its impact slower than the restitution threshold)
    bounces = int((~ev["begin"]).sum())
    assert bounces >= 3 and len(begins) - bounces in (0, 1)
    k = np.arange(bounces)
    speeds = v1 * e**k
    times = v1 / G + np.concatenate([[0.0], np.cumsum(2 * e * speeds[:-1] / G)])
    np.testing.assert_allclose(begins[:bounces], times, rtol=0, atol=1e-9)
    np.testing.assert_allclose(ev["impulse"][ev["begin"]][:bounces], m * (1 + e) * speeds, rtol=1e-9)
    # begin, end, begin, end …: each end at the end of its begin's step, same impulse
    assert np.all(ev["begin"][0::2]) and not np.any(ev["begin"][1::2])
    ends = ev["time"][~ev["begin"]]
    np.testing.assert_allclose(ends, np.ceil(begins[: len(ends)] / dt - 1e-6) * dt, atol=1e-9)
    assert np.all(ev["i"] == w.ids[0]) and np.all(ev["j"] == -1) and np.all(ev["collider"] == 0)


def test_a_ball_that_comes_to_rest_begins_its_last_touch_and_never_ends_it():
    # Below the restitution threshold the ball stays on the floor: its last event is a begin,
    # and nothing follows while it rests (asleep or awake).
    e = 0.6
    w = bouncing_ball(e, 0.5, 1e-3, seconds=3.0)
    ev = w.contact_events()
    assert ev["begin"][-1] and int(ev["begin"].sum()) == int((~ev["begin"]).sum()) + 1
    # it rests before the time the closed-form bounces sum to, t₁ (1 + 2e/(1 − e))
    t1 = math.sqrt(2 * 0.5 / G)
    assert ev["time"][-1] < t1 * (1 + 2 * e / (1 - e))
    w.step(2000)
    assert len(w.contact_events()["time"]) == 0


def test_a_head_on_impact_begins_and_ends_one_touch_of_the_two_ids():
    # Two balls of radius 0.1 m, 1 m apart, closing at u = 3 m/s: the gap of 0.8 m closes at
    # t = 0.8/3 s; Newton's law exchanges the impulse μ (1 + e) u, μ = m1 m2/(m1 + m2).
    (m1, m2, u, e) = (1.0, 3.0, 3.0, 0.5)
    w = kinema.World(dt=1e-3)
    w.add_particles([[0, 0, 0], [1, 0, 0]], velocity=[[u, 0, 0], [0, 0, 0]], mass=[m1, m2], radius=0.1)
    w.set_collisions(restitution=e)
    w.record_contact_events()
    w.step(500)
    ev = w.contact_events()
    assert list(ev["begin"]) == [True, False]
    np.testing.assert_allclose(ev["time"][0], 0.8 / u, atol=1e-12)
    np.testing.assert_allclose(ev["impulse"], m1 * m2 / (m1 + m2) * (1 + e) * u, rtol=1e-12)
    assert set(ev["i"]) | set(ev["j"]) == {0, 1} and np.all(ev["collider"] == -1)


def column(rows=12, seconds=2.0):
    """A 2D column of `rows` discs of radius 5 cm, one above the other on a floor, touching."""
    w = kinema.World(dim=2, dt=2e-3)
    r = 0.05
    w.add_particles([[0.0, r + 2 * r * k, 0.0] for k in range(rows)], radius=r)
    w.add(kinema.Gravity(g=(0.0, -G, 0.0)))
    w.add(kinema.Plane(point=(0.0, 0.0, 0.0), normal=(0.0, 1.0, 0.0)))
    w.set_collisions(restitution=0.5, friction=0.5)
    w.step(round(seconds / 2e-3))
    return w


def test_a_resting_column_begins_nothing_when_recording_starts_and_ends_nothing_asleep():
    # Its contacts carried load in the last step, so they touch already; asleep (after 0.5 s
    # calm) its contacts are solved no more, and still touch.
    w = column()
    assert w.collision_stats()["last"]["asleep"] == 12
    w.record_contact_events()
    w.step(500)
    assert len(w.contact_events()["time"]) == 0
    # stopped and started again: the same
    w.record_contact_events(False)
    w.record_contact_events(True)
    w.step(50)
    assert len(w.contact_events()["time"]) == 0


def test_removing_a_touching_particle_ends_its_touches_at_that_time_by_id():
    # The column's third disc touches the second and the fourth: removing it ends both touches
    # at the world's time; the events name ids (the fourth disc is the third index after).
    w = column()
    w.record_contact_events()
    ids = w.ids.copy()
    w.remove_particles([2])
    ev = w.contact_events()
    assert list(ev["begin"]) == [False, False]
    np.testing.assert_allclose(ev["time"], w.time)
    pairs = {tuple(sorted((int(i), int(j)))) for i, j in zip(ev["i"], ev["j"], strict=True)}
    assert pairs == {(ids[1], ids[2]), (ids[2], ids[3])}
    # the column above falls onto the second disc: the third id's new touch begins
    w.step(500)
    ev = w.contact_events()
    began = {tuple(sorted((int(i), int(j)))) for i, j, b in zip(ev["i"], ev["j"], ev["begin"], strict=True) if b}
    assert (ids[1], ids[3]) in began


def test_recording_contact_events_is_refused_where_there_are_none():
    w = kinema.World(dt=1e-3)
    w.add_particles([[0.0, 0.0, 0.0]], radius=0.1)
    with pytest.raises(ValueError, match=r"record_contact_events = True is invalid: .* collisions are off"):
        w.record_contact_events()
    w.set_collisions(model="spring_dashpot", stiffness=1e5)
    with pytest.raises(ValueError, match=r"record_contact_events = True is invalid: .*a force"):
        w.record_contact_events()
    assert len(w.contact_events()["time"]) == 0


@pytest.mark.parametrize("dim", [2, 3])
def test_in_a_shaken_heap_every_pair_alternates_begin_and_end_and_what_overlaps_is_open(dim):
    # 200 balls poured into a box with restitution 0.7 and friction 0.3: per pair the events
    # alternate, starting with a begin, at non-decreasing times; at the end every contact that
    # overlaps (a touching pair by definition) has an open begin.
    rng = np.random.default_rng(4)
    n, r, pitch = 200, 0.02, 0.05
    shape = (8, 25) if dim == 2 else (5, 5, 8)
    cells = np.stack(np.meshgrid(*[np.arange(k) for k in shape], indexing="ij"), -1).reshape(-1, dim)
    x = np.zeros((n, 3))
    x[:, :dim] = 0.05 + pitch * cells + rng.uniform(-0.004, 0.004, (n, dim))
    v = np.zeros((n, 3))
    v[:, :dim] = rng.normal(0.0, 0.5, (n, dim))
    w = kinema.World(dim=dim, dt=1e-3)
    w.add_particles(x, radius=r, velocity=v)
    g = [0.0, 0.0, 0.0]
    g[dim - 1] = -G
    w.add(kinema.Gravity(g=tuple(g)))
    w.add(kinema.Box((0.0,) * dim, (0.45,) * (dim - 1) + (2.0,)))
    w.set_collisions(restitution=0.7, friction=0.3)
    w.record_contact_events()
    w.step(800)
    ev = w.contact_events()
    assert ev["begin"].sum() > n
    assert np.all(np.diff(ev["time"]) >= -1e-3)  # (begins by time within a step; ends at its end)
    state: dict[tuple, bool] = {}
    for b, i, j, k in zip(ev["begin"], ev["i"], ev["j"], ev["collider"], strict=True):
        key = (min(i, j), max(i, j), -1) if j >= 0 else (i, -1, k)
        assert state.get(key, False) != b, f"pair {key} {'began' if b else 'ended'} twice in a row"
        state[key] = bool(b)
    c = w.contacts()
    ids = w.ids
    for i, j, k, overlap in zip(c["i"], c["j"], c["collider"], c["overlap"], strict=True):
        if overlap >= 0:
            key = (min(ids[i], ids[j]), max(ids[i], ids[j]), -1) if j >= 0 else (ids[i], -1, k)
            assert state.get(key), f"the overlapping pair {key} has no open begin"


def test_a_change_to_a_force_model_stops_recording_and_keeps_what_was_recorded():
    # the spring–dashpot model's steps do not run the impulse model's stages: no touch they
    # could record would be right, so recording stops; the events taken before stay
    w = bouncing_ball(0.8, 1.0, 1e-3, seconds=0.5)
    w.set_collisions(model="spring_dashpot", stiffness=1e4, restitution=0.8)
    w.step(500)
    ev = w.contact_events()
    assert list(ev["begin"]) == [True, False] and ev["time"][0] < 0.5
    w.set_collisions(model="impulse", restitution=0.8)
    w.step(1000)
    assert len(w.contact_events()["time"]) == 0
