"""Checkpoints: a world written between steps and read back goes on bit for bit as the world
that wrote it, for every integrator and both contact models, with springs, emitters,
lifetimes, own materials and particles sorted along space."""

import warnings

import numpy as np
import pytest

import kinema
from kinema.scene import Scene


def scene(method, model, count=60, emitter=False):
    """A small gas under gravity in a box, springs between neighbours in a chain, own
    materials for half the particles, and with ``emitter`` an emitter with lifetimes (its
    births restart the caches, so the matrix below runs without: there the caches count)."""
    collisions = {"model": model, "restitution": 0.7, "friction": 0.2}
    if model == "spring_dashpot":
        collisions.update(stiffness=2e3, friction=0.0)
    return {
        "world": {"dim": 3, "dt": 5e-4, "method": method, "duration": 1.0, "fps": 50.0},
        "particles": [
            {
                "type": "random",
                "lo": [0.05, 0.05, 0.05],
                "hi": [0.95, 0.95, 0.6],
                "count": count,
                "seed": 2,
                "min_distance": 0.05,
                "radius": 0.02,
                "mass": {"min": 0.01, "max": 0.02},
                "velocity": {"sigma": 0.3, "seed": 4},
                "restitution": [0.5, float("nan")] * (count // 2),
            }
        ],
        "forces": [{"type": "gravity"}, {"type": "spring", "i": list(range(0, 10)), "j": list(range(1, 11)), "k": 5.0, "damping": 0.01}],
        "colliders": [{"type": "box", "lo": [0, 0, 0], "hi": [1, 1, 1]}],
        "collisions": collisions,
        "emitters": []
        if not emitter
        else [
            {
                "rate": 200.0,
                "center": [0.5, 0.5, 0.8],
                "shape": "disc",
                "radius": 0.1,
                "speed": 0.5,
                "spread": 30,
                "particle_radius": 0.015,
                "lifetime": 0.05,
                "lifetime_spread": 0.02,
                "color": "#40a0ff",
                "seed": 9,
            }
        ],
    }


def run_alongside(world, tmp_path, before=60, after=80):
    """Steps, writes a checkpoint, reads it back; both step on. Returns the two worlds."""
    world.step(before)
    world.save_checkpoint(tmp_path / "w.ckpt")
    again = kinema.World.load_checkpoint(tmp_path / "w.ckpt")
    world.step(after)
    again.step(after)
    return world, again


def assert_same(a, b):
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.velocities, b.velocities)
    np.testing.assert_array_equal(a.masses, b.masses)
    np.testing.assert_array_equal(a.ids, b.ids)
    assert a.time == b.time and a._core.steps == b._core.steps


@pytest.mark.filterwarnings("ignore::kinema.StabilityWarning")
@pytest.mark.parametrize("model", ["impulse", "spring_dashpot"])
@pytest.mark.parametrize("method", kinema.method_names())
def test_a_resumed_world_goes_on_bit_for_bit(method, model, tmp_path):
    w = Scene.from_dict(scene(method, model)).build()
    a, b = run_alongside(w, tmp_path)
    assert_same(a, b)


@pytest.mark.filterwarnings("ignore::kinema.StabilityWarning")
@pytest.mark.parametrize("model", ["impulse", "spring_dashpot"])
def test_births_and_deaths_resume_bit_for_bit(model, tmp_path):
    w = Scene.from_dict(scene("verlet", model, emitter=True)).build()
    a, b = run_alongside(w, tmp_path)
    assert_same(a, b)
    # births and deaths happened on both sides of the checkpoint, alike
    assert a.ids.max() > 60 and not np.isin(np.arange(60, a.ids.max()), a.ids).all()


@pytest.mark.filterwarnings("ignore::kinema.StabilityWarning")
@pytest.mark.parametrize("model", ["impulse", "spring_dashpot"])
@pytest.mark.parametrize("method", kinema.method_names())
def test_writing_checkpoints_changes_no_bit_of_the_run(method, model, tmp_path):
    # What the method and the impulse solver carry from step to step is written and given
    # back (Verlet's a, implicit Euler's Δv, the warm start): the run that writes checkpoints
    # every 20 ms is the run that writes none. (Without the carry, verlet and implicit_euler
    # differ here by 1e-9 to 2e-5 m.)
    a = Scene.from_dict(scene(method, model)).build().run(0.2, fps=50)
    b = Scene.from_dict(scene(method, model)).build().run(0.2, fps=50, checkpoint=tmp_path / "c.ckpt", checkpoint_every=0.02)
    assert_same_trajectory(a, b)


@pytest.mark.filterwarnings("ignore::kinema.StabilityWarning")
def test_a_world_sorted_along_space_resumes_bit_for_bit(tmp_path):
    # Spring–dashpot contacts with Verlet from 4,096 particles: the engine sorts them along a
    # Morton curve whenever its list is rebuilt (without own materials); the checkpoint's
    # restart puts both worlds on the same list and order.
    d = scene("verlet", "spring_dashpot", count=4200)
    d["particles"][0].update(lo=[0.0, 0.0, 0.0], hi=[4.0, 4.0, 1.0], min_distance=0.045)
    del d["particles"][0]["restitution"]  # own materials keep the user's order (no sorting)
    d["colliders"][0]["hi"] = [4.0, 4.0, 2.0]
    w = Scene.from_dict(d).build()
    a, b = run_alongside(w, tmp_path, before=30, after=30)
    assert a._core.sorts > 0
    assert_same(a, b)


def test_the_checkpoint_keeps_what_the_world_knows(tmp_path):
    w = kinema.World(dt=1e-3, method="rk4")
    w.add_particles([[0, 0, 0], [0, 0, -1], [0, 0, -2]], pinned=[True, False, False], species=["anchor", "bob", "bob"], friction=[np.nan, 0.3, 0.4])
    w.add(kinema.Gravity())
    w.add(kinema.Spring([0, 1], [1, 2], k=50.0))
    w.add(kinema.Emitter(rate=10.0, mass=1.0, lifetime=0.5, color="#ff0000", seed=1))
    w.add(kinema.KillPlane([0, 0, -5], [0, 0, 1]))
    w.step(250)
    w.remove_particles([1])
    w.save_checkpoint(tmp_path / "w.ckpt")
    r = kinema.World.load_checkpoint(tmp_path / "w.ckpt")
    assert r.ids.tolist() == w.ids.tolist() and r._core.next_id == w._core.next_id
    assert r.species.tolist() == w.species.tolist()
    assert r._core.particle_materials() == w._core.particle_materials()
    np.testing.assert_array_equal(r._death, w._death)
    np.testing.assert_array_equal(r._colors, w._colors)
    np.testing.assert_array_equal(r._spring_ids, w._spring_ids)
    assert r._emitters[0].emitted == w._emitters[0].emitted and len(r._kills) == 1
    # the spring that survived (none: both ended on particle 1) and the emitter's stream go on alike
    w.step(300)
    r.step(300)
    assert_same(w, r)


def test_bad_checkpoints_are_refused_by_name(tmp_path):
    with pytest.raises(ValueError, match="no such checkpoint file"):
        kinema.World.load_checkpoint(tmp_path / "missing.ckpt")
    (tmp_path / "junk.ckpt").write_bytes(b"not hdf5")
    with pytest.raises(ValueError, match="cannot be read as HDF5"):
        kinema.World.load_checkpoint(tmp_path / "junk.ckpt")
    traj = kinema.World().run(0.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        traj.save(tmp_path / "t.h5")
    with pytest.raises(ValueError, match="not a kinema checkpoint"):
        kinema.World.load_checkpoint(tmp_path / "t.h5")
    w = kinema.World()
    w.add_particles([0, 0, 0])
    w.add(kinema.PythonForce(lambda t, x, v: -x))
    with pytest.raises(ValueError, match="PythonForce cannot be written"):
        w.save_checkpoint(tmp_path / "p.ckpt")
    assert not (tmp_path / "p.ckpt").exists()


ROOT = __import__("pathlib").Path(__file__).resolve().parent.parent
FIELDS = ("t", "positions", "velocities", "alive", "ids", "masses", "kinetic", "momentum", "contacts", "impulse_balance", "collision_energy_lost")


def assert_same_trajectory(a, b):
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.potential.keys() == b.potential.keys()
    for k in a.potential:
        np.testing.assert_array_equal(a.potential[k], b.potential[k])


class Stop(Exception):
    pass


@pytest.mark.parametrize("model", ["impulse", "spring_dashpot"])
def test_a_run_stopped_after_a_checkpoint_resumes_to_the_same_trajectory(model, tmp_path):
    # The run writes a checkpoint every 0.1 s; one copy runs through, another is stopped at
    # 0.25 s (after the checkpoint at 0.2 s) and resumed: the whole trajectories are the same
    # bits, the frames before the stop included, births, deaths and collision books too.
    def build():
        return Scene.from_dict(scene("verlet", model, emitter=True)).build()

    whole = build().run(0.5, fps=50, checkpoint=tmp_path / "a.ckpt", checkpoint_every=0.1)

    def stop(world):
        if world.time > 0.25:
            raise Stop

    with pytest.raises(Stop):
        build().run(0.5, fps=50, checkpoint=tmp_path / "b.ckpt", checkpoint_every=0.1, callback=stop)
    world, resumed = kinema.resume_run(tmp_path / "b.ckpt")
    assert_same_trajectory(whole, resumed)
    assert resumed.changes_count and world.time == pytest.approx(0.5)


def test_kinema_run_resumes_from_its_checkpoint(tmp_path):
    import signal
    import subprocess
    import sys
    import time
    from pathlib import Path

    kinema_bin = Path(sys.executable).parent / "kinema"
    scene_file = ROOT / "examples" / "scenes" / "fountain.toml"
    args = [str(kinema_bin), "run", str(scene_file), "--no-video", "--duration", "2.0", "--checkpoint-every", "0.5"]
    done = subprocess.run([*args, "-o", str(tmp_path / "a")], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert not (tmp_path / "a" / "checkpoint.ckpt").exists()  # removed once the run is whole
    # the same run, stopped by Ctrl-C once its first checkpoint is there, then resumed
    proc = subprocess.Popen([*args, "-o", str(tmp_path / "b")], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    ckpt = tmp_path / "b" / "checkpoint.ckpt"
    deadline = time.monotonic() + 120
    while not ckpt.exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    if proc.returncode == 0:
        pytest.skip("the run finished before it could be stopped")  # a machine far faster than this test expects
    assert proc.returncode == 130 and "interrupted" in err and ckpt.exists()
    assert not (tmp_path / "b" / "trajectory.h5").exists()
    again = subprocess.run(
        [str(kinema_bin), "run", str(scene_file), "--no-video", "--resume", "-o", str(tmp_path / "b")], capture_output=True, text=True, timeout=300
    )
    assert again.returncode == 0, again.stderr
    assert_same_trajectory(kinema.load_trajectory(tmp_path / "a" / "trajectory.h5"), kinema.load_trajectory(tmp_path / "b" / "trajectory.h5"))
    nothing = subprocess.run([str(kinema_bin), "run", str(scene_file), "--resume", "-o", str(tmp_path / "c")], capture_output=True, text=True, timeout=60)
    assert nothing.returncode == 2 and "no checkpoint to resume" in nothing.stderr


def test_a_sweep_member_interrupted_mid_run_resumes_from_its_checkpoint(tmp_path):
    from kinema.sweeps import members, run_member

    d = scene("verlet", "impulse", emitter=True)
    d["world"]["duration"] = 0.4
    (member,) = members(d)
    whole = run_member(member, str(tmp_path / "a"), None, None, checkpoint_every=0.1)
    # as if its worker had died after the checkpoint at 0.2 s: the checkpoint is left
    w = Scene.from_dict(d).build()
    where = tmp_path / "b" / "members" / member.name
    where.mkdir(parents=True)

    def stop(world):
        if world.time > 0.25:
            raise Stop

    with pytest.raises(Stop):
        w.run(0.4, fps=50, checkpoint=where / "checkpoint.ckpt", checkpoint_every=0.1, callback=stop)
    again = run_member(member, str(tmp_path / "b"), None, None, checkpoint_every=0.1)
    assert again["row"] == whole["row"] and not again["row"]["error"]
    assert not (where / "checkpoint.ckpt").exists()
    assert_same_trajectory(kinema.load_trajectory(tmp_path / "a" / "members" / member.name / "trajectory.h5"), kinema.load_trajectory(where / "trajectory.h5"))


def test_a_sleeping_pile_resumes_and_wakes_bit_for_bit(tmp_path):
    """Sleeping's state (each particle's calm time, the islands asleep with their contacts'
    warm start) is in the checkpoint: a pile written while asleep goes on bit for bit, a ball
    dropped on it wakes it alike in both, and writing the checkpoint changed nothing."""
    rng = np.random.default_rng(5)

    def pile():
        w = kinema.World(dt=1e-3)
        grid = np.stack(np.meshgrid(range(4), range(4), range(3), indexing="ij"), -1).reshape(-1, 3)
        w.add_particles(0.045 + 0.09 * grid, velocity=rng.uniform(-0.3, 0.3, (48, 3)), radius=0.035)
        w.add(kinema.Gravity())
        w.add(kinema.Box([0, 0, 0], [0.36, 0.36, 2.0]))
        w.set_collisions(restitution=0.3, friction=0.5)
        return w

    w = pile()
    rng = np.random.default_rng(5)
    untouched = pile()
    for _ in range(40):
        w.step(100)
        untouched.step(100)
        if w.collision_stats()["last"]["asleep"] == len(w):
            break
    assert w.collision_stats()["last"]["asleep"] == len(w)
    w.save_checkpoint(tmp_path / "w.ckpt")
    again = kinema.World.load_checkpoint(tmp_path / "w.ckpt")
    for world in (w, again, untouched):
        world.add_particles([0.18, 0.18, 0.6], radius=0.03)
        world.step(700)
    assert w.collision_stats()["total"]["woke"] >= 1
    for world in (again, untouched):
        assert_same(w, world)
        for part in ("last", "total"):
            mine, theirs = w.collision_stats()[part], world.collision_stats()[part]
            assert mine.keys() == theirs.keys()
            for key in mine:
                np.testing.assert_array_equal(mine[key], theirs[key], err_msg=f"{part} {key}")


def test_a_heap_asleep_on_pinned_particles_resumes_bit_for_bit(tmp_path):
    """A heap resting on pinned particles (no collider) sleeps; its contacts with the pinned
    particles, which sleep in no island, go with it into the checkpoint and back."""
    w = kinema.World(dt=1e-3)
    floor = [[0.1 * (k % 6), 0.1 * (k // 6), 0.0] for k in range(36)]
    balls = [[0.07 + 0.11 * (k % 4), 0.07 + 0.11 * (k // 4), 0.3] for k in range(16)]
    w.add_particles(floor + balls, radius=0.05, pinned=[True] * 36 + [False] * 16)
    w.add(kinema.Gravity())
    w.set_collisions(restitution=0.3, friction=0.5)
    for _ in range(50):
        w.step(100)
        if w.collision_stats()["last"]["asleep"] == 16:
            break
    assert w.collision_stats()["last"]["asleep"] == 16
    w.save_checkpoint(tmp_path / "w.ckpt")
    again = kinema.World.load_checkpoint(tmp_path / "w.ckpt")
    assert again.collision_stats()["last"]["asleep"] == 16
    for world in (w, again):
        world.add_particles([0.2, 0.2, 0.6], radius=0.04)
        world.step(600)
    assert w.collision_stats()["total"]["woke"] >= 1
    assert_same(w, again)
