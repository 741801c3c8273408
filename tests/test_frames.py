"""Frames at the rate asked (issue 48): ``World.run(duration, fps)`` records frame k at
t₀ + k/fps exactly and ends at t₀ + duration (``kinema.frames``; the engine's clock,
``world/clock.rs``), each frame ⌈1/(fps·dt)⌉ equal steps of at most dt.

Closed forms: a ball thrown under uniform gravity, stepped by velocity Verlet, is at
x₀ + v₀ t + g t²/2 at every step whatever the steps' lengths (Verlet integrates a constant
acceleration exactly), so its frames must be there at the frames' exact times; an emitter of
rate r has ⌊r (t − start)⌋ + 1 births due by t.
"""

import numpy as np
import pytest

import kinema
from kinema.frames import plan

CASES = [  # (dt, fps, duration, t0)
    (1e-3, 30.0, 2.0, 0.0),
    (1e-3, 60.0, 2.0, 0.0),
    (2e-3, 30.0, 1.0, 0.25),
    (1e-3, 25.0, 1.0, 0.0),
    (7e-4, 24.0, 0.5, 0.1),
    (1e-3, 30000 / 1001, 0.4, 0.0),
    (5e-4, 50.0, 0.3, 0.0),  # dt divides the frame
    (1e-3, 30.0, 0.105, 0.0),  # no whole number of frames
]


def thrown(dt, t0=0.0):
    w = kinema.World(dt=dt)
    w.add(kinema.Gravity([0, 0, -9.81]))
    w.add_particles([[0.0, 0.0, 0.0]], velocity=[[1.0, 0.5, 3.0]])
    if t0:
        w.step(round(t0 / dt))
    return w


@pytest.mark.parametrize("dt, fps, duration, t0", CASES)
def test_frame_k_is_at_t0_plus_k_over_fps_and_the_run_ends_at_its_duration(dt, fps, duration, t0):
    w = thrown(dt, t0)
    start = w.time
    traj = w.run(duration, fps=fps)
    p = plan(duration, dt, fps)
    frames = int(np.floor(duration * fps + 1e-9))
    assert len(traj.t) == frames + 1
    expected = [start + k / fps for k in range(frames + 1)]
    if p.tail == 0:
        expected[-1] = start + duration
    assert traj.t.tolist() == expected  # to the bit
    assert w.time == start + duration
    assert traj.fps == fps
    # no step longer than dt; the steps are dt where dt divides the frame
    assert p.step <= dt and (traj.step is None) == p.divides
    assert w._core.steps == round(t0 / dt) + p.steps


@pytest.mark.parametrize("dt, fps, duration, t0", CASES)
def test_verlet_stays_exact_on_the_frames_of_a_thrown_ball(dt, fps, duration, t0):
    w = thrown(dt, t0)
    traj = w.run(duration, fps=fps)
    t = traj.t[:, None]
    exact = np.array([1.0, 0.5, 3.0]) * t + np.array([0, 0, -9.81]) * t * t / 2
    np.testing.assert_allclose(traj.positions[:, 0], exact, rtol=1e-12, atol=1e-13)


def test_a_resumed_run_with_frames_of_no_whole_steps_goes_on_bit_for_bit(tmp_path):
    # fps = 30 at dt = 1 ms: 34 steps of 0.980 ms a frame; checkpoints at frames
    def build():
        w = kinema.World(dt=1e-3)
        w.add(kinema.Gravity([0, 0, -9.81]))
        w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
        w.set_collisions(restitution=0.8)
        w.add_particles([[0.0, 0.0, 0.3], [0.05, 0.0, 0.5]], radius=0.02)
        return w

    whole = build().run(0.5, fps=30)

    class Stop(Exception):
        pass

    def stop(world):
        if world.time > 0.3:
            raise Stop

    with pytest.raises(Stop):
        build().run(0.5, fps=30, checkpoint=tmp_path / "c.ckpt", checkpoint_every=0.1, callback=stop)
    world, traj = kinema.resume_run(tmp_path / "c.ckpt")
    assert traj.t.tolist() == whole.t.tolist()
    np.testing.assert_array_equal(traj.positions, whole.positions)
    assert world.time == 0.5


def test_an_emitter_keeps_its_births_on_time_between_frames_of_no_whole_steps():
    # rate 100/s from t = 0: births at k/100 s, each added before the first step that starts
    # at or after its time, so a frame at t holds the births before t: ⌈100 t⌉ of them (one
    # due at t itself comes at the next step's start)
    w = kinema.World(dt=1e-3)
    w.add(kinema.Emitter(rate=100.0, speed=1.0, particle_radius=0.001, seed=1))
    counts = []
    w.run(0.5, fps=30, callback=lambda world: counts.append((world.time, len(world))))
    assert len(counts) == 15
    for t, n in counts:
        assert n == int(np.ceil(100 * t - 1e-9)), (t, n)


def test_the_plan_refuses_nothing_it_cannot_land_and_names_what_it_changed():
    p = plan(2.0, 1e-3, 30.0)
    assert (p.frames, p.per_frame, p.tail) == (60, 34, 0)
    assert "34 steps a frame" in p.note() and "0.000980392 s" in p.note()
    assert plan(2.0, 1e-3, 50.0).note() is None  # 20 steps of dt: nothing changed
    w = kinema.World(dt=1e-3)
    w.add_particles([[0.0, 0.0, 0.0]])
    with pytest.raises(ValueError, match=r"steps = 33 is invalid: .*longer than dt = 0.001 s: give at least 34 steps"):
        w._core.land_at(1 / 30, 33)
    with pytest.raises(ValueError, match=r"time = 0 is invalid: a landing time must be finite and after the world's time"):
        w._core.land_at(0.0, 5)


def _gas(model: str, n_side: int = 13, seed: int = 3) -> kinema.World:
    """Spheres (more than the engine sorts along space) on a lattice of a periodic box, fast
    enough to touch within a few frames: a contact energy at most frames."""
    spacing = 1.05
    g = np.arange(n_side) * spacing
    x = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    v = np.random.default_rng(seed).uniform(-3.0, 3.0, x.shape)
    w = kinema.World(dt=2.0**-10, method="verlet")  # 32 steps a frame at 32 fps, exactly
    w.add_particles(x, velocity=v, radius=0.5)
    w.add(kinema.Box([0, 0, 0], [n_side * spacing] * 3))
    w.periodic = (True, True, True)
    if model == "hertz_friction_walls":  # walls along z, friction and spin
        w.periodic = (True, True, False)
        w.set_collisions(model="hertz", youngs_modulus=2e5, restitution=0.7, friction=0.4)
    else:
        w.set_collisions(model="spring_dashpot", stiffness=2000.0, damping=30.0)
    return w


@pytest.mark.parametrize("model", ["spring_dashpot", "hertz_friction_walls"])
@pytest.mark.filterwarnings("ignore")
def test_a_runs_frames_hold_the_diagnostics_and_ids_read_after_each_frames_steps(model):
    """`World.run` takes each frame's contact energy from its last step's own force pass
    and reads the ids again only when the set of particles changed: its frames must hold, to
    the bit, what `diagnostics()` and `ids` read after the same steps by `step` give,
    particles added and removed by the callback included."""

    def callback(w):
        if round(w.time * 32) == 3:
            w.add_particles([[0.3, 0.3, 2.0]], velocity=[[0.0, 0.0, 1.0]], radius=0.2)
        if round(w.time * 32) == 6:
            w.remove_particles([5, 17])

    run_world, step_world = _gas(model), _gas(model)
    traj = run_world.run(9 / 32, fps=32.0, callback=callback)
    assert traj.step is None, "each frame whole steps of dt"
    per = 32
    expected = [step_world.diagnostics()]
    ids = [step_world.ids.copy()]
    for _ in range(9):
        step_world.step(per)
        expected.append(step_world.diagnostics())
        ids.append(step_world.ids.copy())
        callback(step_world)
    assert traj.alive is not None and len(set(map(len, ids))) == 3, "the set changed twice"
    for k, d in enumerate(expected):
        assert traj.kinetic[k] == d["kinetic"] and np.array_equal(traj.momentum[k], d["momentum"])
        for name, u in d["potential"].items():
            assert traj.potential[name][k] == u, (k, name)
        alive_ids = traj.ids[traj.alive[k]]
        assert np.array_equal(alive_ids, ids[k]), k
    assert max(traj.potential["contact"]) > 0, "the spheres touched"
