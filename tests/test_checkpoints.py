"""Checkpoints: a world written between steps and read back goes on bit for bit as the world
that wrote it, for every integrator and both contact models, with springs, emitters,
lifetimes, own materials and particles sorted along space."""

import re
import sys
import warnings
from pathlib import Path

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
    if model == "impulse":  # (the force models' walls: test_wall_forces.py, an engine limit)
        for name in WALLS:
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


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
    np.testing.assert_array_equal(r._state().death, w._state().death)  # (the engine's: issue 50)
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
WALLS = ("collider_momentum", "collider_normal", "collider_tangential")


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
    # the wall forces: the frames the checkpoint holds as written, the rest to rounding (the
    # engine takes no collider books back: the world read adds those it carried to its own)
    written = whole.t <= 0.2 + 1e-9
    for name in WALLS:
        a, b = getattr(whole, name), getattr(resumed, name)
        np.testing.assert_array_equal(b[written], a[written], err_msg=name)
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-14 * np.abs(a).max(), err_msg=name)


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


# -- damaged checkpoints ------------------------------------------------------------------------
# Every field load_checkpoint and resume_run read is checked (presence, type, shape, finite,
# range, consistency with the others); a damaged checkpoint is one CheckpointError, one line
# naming the file and the field, never a KeyError, OverflowError, ZeroDivisionError, ...
# (an outside fuzz run found those), and never a run that writes a trajectory kinema's own
# reader refuses (per_frame = 0).

import json  # noqa: E402
import shutil  # noqa: E402
import time  # noqa: E402

import h5py  # noqa: E402

from kinema.checkpoint import CheckpointError  # noqa: E402


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    """A checkpoint of a run in progress holding every field: births held back by an
    emitter, contacts with particles and with colliders (the warm start), Verlet's carry,
    sleeping's carry, the collision books, 11 frames recorded with births among them."""
    path = tmp_path_factory.mktemp("pristine") / "checkpoint.ckpt"
    w = Scene.from_dict(scene("verlet", "impulse", emitter=True)).build()

    def stop(world):
        if world.time > 0.2:
            raise Stop

    with pytest.raises(Stop):
        w.run(0.3, fps=50, checkpoint=path, checkpoint_every=0.2, callback=stop)
    with h5py.File(path) as f:
        collider = f["collision_carry/collider"][()]
        assert collider.any() and not collider.all()
        assert json.loads(f.attrs["emitters"])[0]["waiting"] is not None
        assert "integrator_carry" in f and "collision_stats" in f.attrs and len(json.loads(f["run"].attrs["sets"])) > 1
    return path


def _holder(f, name):
    group, _, key = name.rpartition("/")
    return (f[group] if group else f), key


def set_attr(name, value):
    def damage(f):
        holder, key = _holder(f, name)
        holder.attrs[key] = value

    return damage


def del_attr(name):
    def damage(f):
        holder, key = _holder(f, name)
        del holder.attrs[key]

    return damage


def del_node(name):
    def damage(f):
        del f[name]

    return damage


def edit_ds(name, change):
    """Replace the dataset ``name`` by ``change(its data)``."""

    def damage(f):
        data = f[name][()]
        del f[name]
        f.create_dataset(name, data=change(data))

    return damage


def at(index, value):
    """``data`` with ``data[index] = value`` (a float copy when the value is NaN or inf)."""

    def change(data):
        data = data.astype(float) if isinstance(value, float) and data.dtype.kind != "f" else data.copy()
        data[index] = value
        return data

    return change


def edit_json(name, change):
    """Change the JSON attribute ``name`` in place: ``change(its value)``."""

    def damage(f):
        holder, key = _holder(f, name)
        value = json.loads(holder.attrs[key])
        change(value)
        holder.attrs[key] = json.dumps(value)

    return damage


def edit_scene(old, new):
    def damage(f):
        text = f.attrs["scene"]
        assert old in text
        f.attrs["scene"] = text.replace(old, new, 1)

    return damage


ROOT_ATTRS = ("format", "version", "scene", "time", "steps", "clock_steps", "clock_time", "next_id", "warned", "advised_at", "emitters", "collision_stats")
RUN_ATTRS = ("frames_done", "frames_total", "per_frame", "every", "fps", "t0", "duration", "potential", "about", "sets")
DATASETS = (
    "ids",
    "death",
    "colors",
    "spring_ids",
    "collision_carry/particle",
    "collision_carry/collider",
    "collision_carry/partner",
    "collision_carry/impulse",
    "collision_carry/sleep_calm",
    "collision_carry/sleep_island",
    "run/t",
    "run/kinetic",
    "run/momentum",
    "run/angular_momentum",
    "run/contacts",
    "run/impulse_total",
    "run/energy_lost",
    "run/impacts_total",
    "run/virial_total",
    "run/kinetic_tensor",
    "run/counts",
    "run/x",
    "run/v",
    "run/ids",
    *(f"run/collider_{key}" for key in ("momentum", "normal", "tangential")),
    *(f"collider_books/{part}/{key}" for part in ("total", "last") for key in ("momentum", "angular_momentum", "work", "normal", "tangential")),
)
# not read / absent before a first step (verlet) and for methods that carry nothing / absent
# in a checkpoint written before the records' `carried` and the list's build were saved
OPTIONAL = (
    "kinema",
    "integrator_carry",
    *(f"collision_carry/{d}" for d in ("carried", "list_built_at", "list_skin")),
)
NUMERIC_ATTRS = ("version", "time", "steps", "clock_steps", "clock_time", "next_id", "advised_at", *(f"run/{a}" for a in RUN_ATTRS[:7]))
JSON_ATTRS = ("emitters", "collision_stats", "run/potential", "run/about", "run/sets")
NUMERIC_DATASETS = tuple(d for d in (*DATASETS, "integrator_carry") if d != "collision_carry/collider")


def test_the_damage_cases_cover_every_field_of_a_checkpoint(pristine):
    found = set()
    with h5py.File(pristine) as f:
        found |= set(f.attrs) | {f"run/{a}" for a in f["run"].attrs}
        f.visititems(lambda name, obj: found.add(name) if isinstance(obj, h5py.Dataset) else None)
    covered = {*ROOT_ATTRS, *(f"run/{a}" for a in RUN_ATTRS), *DATASETS, *OPTIONAL}
    assert found == covered


CASES = [
    # every field deleted
    *((f"delete {a}", del_attr(a), "format" if a == "format" else f"'{a}'") for a in ROOT_ATTRS),
    *((f"delete run/{a}", del_attr(f"run/{a}"), f"'run/{a}'") for a in RUN_ATTRS),
    *((f"delete {d}", del_node(d), f"'{d}'") for d in DATASETS),
    ("delete run", del_node("run"), "'run'"),
    ("delete collision_carry", del_node("collision_carry"), "'collision_carry'"),
    # the wrong type: text for numbers, numbers for text, bools for numbers and numbers for bools
    *((f"{a} text", set_attr(a, "x"), f"'{a}'") for a in NUMERIC_ATTRS),
    *((f"{a} bool", set_attr(a, True), f"'{a}'") for a in NUMERIC_ATTRS),
    *((f"{a} float", set_attr(a, 2.5), f"'{a}'") for a in NUMERIC_ATTRS if a not in ("time", "clock_time", "run/fps", "run/t0", "run/duration")),
    *((f"{a} a number", set_attr(a, 1.5), f"'{a}'") for a in ("scene", *JSON_ATTRS)),
    *((f"{a} array", set_attr(a, np.array([1, 2])), f"'{a}'") for a in ("steps", "time", "run/per_frame")),
    ("warned a number", set_attr("warned", 1), "'warned'"),
    ("format other", set_attr("format", "kinema-trajectory"), "format"),
    *((f"{d} text", edit_ds(d, lambda a: np.full(a.shape, b"x")), f"'{d}'") for d in NUMERIC_DATASETS),
    *((f"{d} bool", edit_ds(d, lambda a: np.ones(a.shape, bool)), f"'{d}'") for d in NUMERIC_DATASETS),
    ("collider integers", edit_ds("collision_carry/collider", lambda a: a.astype(np.int64)), "'collision_carry/collider'"),
    *((f"{d} float", edit_ds(d, lambda a: a + 0.5), f"'{d}'") for d in ("ids", "spring_ids", "run/counts", "run/ids", "collision_carry/partner")),
    ("ids a group", lambda f: (f.__delitem__("ids"), f.create_group("ids")), "'ids'"),
    ("collision_carry a dataset", lambda f: (f.__delitem__("collision_carry"), f.create_dataset("collision_carry", data=[1])), "'collision_carry'"),
    ("run a dataset", lambda f: (f.__delitem__("run"), f.create_dataset("run", data=[1])), "'run'"),
    ("ids empty dataspace", lambda f: (f.__delitem__("ids"), f.create_dataset("ids", dtype="u8")), "'ids'"),
    # NaN and inf where a number must be finite (or not NaN)
    *((f"{a} nan", set_attr(a, float("nan")), f"'{a}'") for a in ("time", "run/fps")),
    *((f"{a} inf", set_attr(a, float("inf")), f"'{a}'") for a in ("time", "run/fps")),
    *(
        (f"{d} nan", edit_ds(d, at(-1, float("nan"))), f"'{d}'")
        for d in (
            "death",
            "integrator_carry",
            "collision_carry/impulse",
            "collision_carry/sleep_calm",
            "run/t",
            "run/kinetic",
            "run/momentum",
            "run/angular_momentum",
            "run/impulse_total",
            "run/energy_lost",
            "run/x",
            "run/v",
            "run/collider_normal",
            "collider_books/total/momentum",
            "collider_books/last/work",
        )
    ),
    *(
        (f"{d} inf", edit_ds(d, at(-1, float("inf"))), f"'{d}'")
        for d in ("integrator_carry", "collision_carry/impulse", "collision_carry/sleep_calm", "run/t", "run/kinetic", "run/x", "run/v")
    ),
    ("colors 2", edit_ds("colors", at((0, 1), 2.0)), "'colors'"),
    ("colors inf", edit_ds("colors", at((0, 1), float("inf"))), "'colors'"),
    # negative, and huge (2**64 - 1 as uint64, 1e300)
    *((f"{a} negative", set_attr(a, -1), f"'{a}'") for a in ("version", "steps", "next_id", "advised_at", *(f"run/{a}" for a in RUN_ATTRS[:4]))),
    *((f"{a} negative", set_attr(a, -1.0), f"'{a}'") for a in ("time", "run/fps")),
    *((f"{a} huge", set_attr(a, np.uint64(2**64 - 1)), f"'{a}'") for a in ("version", "steps", "next_id", "advised_at", *(f"run/{a}" for a in RUN_ATTRS[:4]))),
    ("time huge", set_attr("time", 1e300), "'time'"),
    *(
        (f"{d} negative", edit_ds(d, at(0, -1)), f"'{d}'")
        for d in ("spring_ids", "collision_carry/particle", "collision_carry/partner", "run/counts", "run/contacts", "run/ids")
    ),
    ("ids negative", edit_ds("ids", lambda a: np.concatenate([[-1], a[1:].astype(np.int64)])), "'ids'"),
    ("sleep_island -2", edit_ds("collision_carry/sleep_island", at(0, -2)), "'collision_carry/sleep_island'"),
    ("sleep_calm negative", edit_ds("collision_carry/sleep_calm", at(0, -1.0)), "'collision_carry/sleep_calm'"),
    ("kinetic negative", edit_ds("run/kinetic", at(0, -1.0)), "'run/kinetic'"),
    ("colors negative", edit_ds("colors", at((0, 0), -0.5)), "'colors'"),
    ("ids huge", edit_ds("ids", at(-1, np.uint64(2**64 - 1))), "'ids'"),
    ("particle huge", edit_ds("collision_carry/particle", at(0, 2**62)), "'collision_carry/particle'"),
    ("partner huge", edit_ds("collision_carry/partner", at(0, 2**62)), "'collision_carry/partner'"),
    ("partner collider out of range", edit_ds("collision_carry/partner", lambda a: a + 1000), "'collision_carry/partner'"),
    ("carried integers", edit_ds("collision_carry/carried", lambda a: a.astype(np.int64)), "'collision_carry/carried'"),
    ("carried one less", edit_ds("collision_carry/carried", lambda a: a[:-1]), "'collision_carry/carried'"),
    ("list_built_at nan", edit_ds("collision_carry/list_built_at", at((0, 1), float("nan"))), "'collision_carry/list_built_at'"),
    ("list_built_at one less", edit_ds("collision_carry/list_built_at", lambda a: a[:-1]), "'collision_carry/list_built_at'"),
    ("list_built_at flat", edit_ds("collision_carry/list_built_at", lambda a: a.reshape(-1)), "'collision_carry/list_built_at'"),
    ("list_skin negative", edit_ds("collision_carry/list_skin", lambda a: -a), "'collision_carry/list_skin'"),
    ("list_skin inf", edit_ds("collision_carry/list_skin", lambda a: np.inf), "'collision_carry/list_skin'"),
    ("list_skin text", edit_ds("collision_carry/list_skin", lambda a: b"x"), "'collision_carry/list_skin'"),
    ("delete list_skin", del_node("collision_carry/list_skin"), "'collision_carry/list_skin'"),
    ("delete list_built_at", del_node("collision_carry/list_built_at"), "'collision_carry/list_built_at'"),
    ("spring end above next_id", edit_ds("spring_ids", at(0, 10**6)), "'spring_ids'"),
    # the wrong shape
    ("ids one more", edit_ds("ids", lambda a: np.append(a, a[-1] + 1)), "'ids'"),
    ("death one more", edit_ds("death", lambda a: np.append(a, np.inf)), "'death'"),
    ("colors 2 columns", edit_ds("colors", lambda a: a[:, :2]), "'colors'"),
    ("colors flat", edit_ds("colors", lambda a: a.reshape(-1)), "'colors'"),
    ("spring_ids 3 columns", edit_ds("spring_ids", lambda a: np.tile(a, (1, 2))[:, :3]), "'spring_ids'"),
    ("integrator_carry short", edit_ds("integrator_carry", lambda a: a[:-3]), "'integrator_carry'"),
    ("particle one more", edit_ds("collision_carry/particle", lambda a: np.append(a, 0)), "'collision_carry/collider'"),
    ("impulse 2 columns", edit_ds("collision_carry/impulse", lambda a: a[:, :2]), "'collision_carry/impulse'"),
    ("sleep_calm one more", edit_ds("collision_carry/sleep_calm", lambda a: np.append(a, 0.0)), "'collision_carry/sleep_calm'"),
    ("sleep_island one less", edit_ds("collision_carry/sleep_island", lambda a: a[:-1]), "'collision_carry/sleep_island'"),
    ("run/t one more", edit_ds("run/t", lambda a: np.append(a, a[-1] + 1)), "'run/t'"),
    ("run/kinetic one less", edit_ds("run/kinetic", lambda a: a[:-1]), "'run/kinetic'"),
    ("run/momentum 2 columns", edit_ds("run/momentum", lambda a: a[:, :2]), "'run/momentum'"),
    ("run/contacts 2-D", edit_ds("run/contacts", lambda a: a[:, None]), "'run/contacts'"),
    ("run/counts one more", edit_ds("run/counts", lambda a: np.append(a, 0)), "'run/counts'"),
    ("run/x one more", edit_ds("run/x", lambda a: np.vstack([a, a[:1]])), "'run/x'"),
    ("run/v one less", edit_ds("run/v", lambda a: a[:-1]), "'run/v'"),
    ("run/ids one more", edit_ds("run/ids", lambda a: np.append(a, 10**6)), "'run/ids'"),
    ("run/collider_normal 2 columns", edit_ds("run/collider_normal", lambda a: a[..., :2]), "'run/collider_normal'"),
    ("run/collider_momentum one less", edit_ds("run/collider_momentum", lambda a: a[:-1]), "'run/collider_momentum'"),
    ("run/collider_tangential another K", edit_ds("run/collider_tangential", lambda a: np.concatenate([a, a], axis=1)), "'run/collider_tangential'"),
    (
        "run/collider_* more colliders",
        lambda f: [edit_ds(f"run/collider_{k}", lambda a: np.concatenate([a, a], axis=1))(f) for k in ("momentum", "normal", "tangential")],
        "'run/collider_momentum'",
    ),
    ("collider_books/total/normal one more", edit_ds("collider_books/total/normal", lambda a: np.vstack([a, a[:1]])), "'collider_books/total/normal'"),
    ("collider_books/last/work 2-D", edit_ds("collider_books/last/work", lambda a: a[:, None]), "'collider_books/last/work'"),
    ("collider_books a dataset", lambda f: (f.__delitem__("collider_books"), f.create_dataset("collider_books", data=[1])), "'collider_books'"),
    # values that do not fit the others
    ("per_frame 0", set_attr("run/per_frame", 0), "'run/per_frame'"),
    ("per_frame another", set_attr("run/per_frame", 41), "'run/per_frame'"),
    ("every 0", set_attr("run/every", 0), "'run/every'"),
    ("fps tiny", set_attr("run/fps", 5e-324), "'run/fps'"),
    ("frames_done above frames_total", lambda f: f["run"].attrs.__setitem__("frames_done", f["run"].attrs["frames_total"] + 1), "'run/frames_done'"),
    ("frames_done one less", lambda f: f["run"].attrs.__setitem__("frames_done", f["run"].attrs["frames_done"] - 1), "'run/t'"),
    ("frames_total past 2**53 steps", set_attr("run/frames_total", 2**60), "'run/frames_total'"),
    ("steps one more", lambda f: f.attrs.__setitem__("steps", f.attrs["steps"] + 1), "'steps'"),
    ("time a bit later", lambda f: f.attrs.__setitem__("time", f.attrs["time"] + 1e-9), "'time'"),
    ("next_id at the last id", lambda f: f.attrs.__setitem__("next_id", f["ids"][-1]), "'next_id'"),
    ("ids out of order", edit_ds("ids", lambda a: a[[1, 0, *range(2, len(a))]]), "'ids'"),
    ("run/t not increasing", edit_ds("run/t", lambda a: np.concatenate([a[:1], a[:1], a[2:]])), "'run/t'"),
    ("run/t after the time", edit_ds("run/t", lambda a: a + 1.0), "'run/t'"),
    ("run/ids out of order", edit_ds("run/ids", lambda a: a[[1, 0, *range(2, len(a))]]), "'run/ids'"),
    ("run/counts moved", edit_ds("run/counts", lambda a: np.concatenate([[a[0] - 1, a[1] + 1], a[2:]])), "'run/ids'"),
    # the scene, through the scene's validation
    ("scene not TOML", set_attr("scene", "[[[ nonsense"), "'scene'"),
    ("scene dt negative", edit_scene("dt = 0.0005", "dt = -1.0"), "'scene'"),
    ("scene unknown key", edit_scene("[world]", "[world]\nwarp = 9"), "'scene'"),
    ("scene another dt", edit_scene("dt = 0.0005", "dt = 0.001"), "'run/per_frame'"),
    ("clock_time a bit later", lambda f: f.attrs.__setitem__("clock_time", f.attrs["clock_time"] + 1e-9), "'time'"),
    ("run/duration another", lambda f: f["run"].attrs.__setitem__("duration", f["run"].attrs["duration"] * 2), "'run/frames_total'"),
    (
        "scene a billion particles",
        set_attr("scene", Scene.from_dict({"particles": [{"type": "random", "count": 10**9, "lo": [0, 0, 0], "hi": [1, 1, 1]}]}).to_toml_string()),
        "'scene'",
    ),
    ("scene not UTF-8", set_attr("scene", np.bytes_(b"\xff\xfe")), "'scene'"),
    # the emitters' states
    ("emitters not JSON", set_attr("emitters", "[{"), "'emitters'"),
    ("emitters a dict", set_attr("emitters", "{}"), "'emitters'"),
    ("emitters none", set_attr("emitters", "[]"), "'emitters'"),
    ("emitted missing", edit_json("emitters", lambda e: e[0].pop("emitted")), "'emitters'"),
    ("emitted bool", edit_json("emitters", lambda e: e[0].update(emitted=True)), "emitted"),
    ("emitted negative", edit_json("emitters", lambda e: e[0].update(emitted=-1)), "emitted"),
    ("emitted 2**70", edit_json("emitters", lambda e: e[0].update(emitted=2**70)), "emitted"),
    ("emitted float", edit_json("emitters", lambda e: e[0].update(emitted=1.5)), "emitted"),
    ("emitted more than due", edit_json("emitters", lambda e: e[0].update(emitted=e[0]["emitted"] + 1000)), "emitted"),
    ("stream missing", edit_json("emitters", lambda e: e[0]["streams"].pop("life")), "streams"),
    ("stream other generator", edit_json("emitters", lambda e: e[0]["streams"]["size"].update(bit_generator="MT19937")), "streams.size.bit_generator"),
    ("stream state 2**200", edit_json("emitters", lambda e: e[0]["streams"]["position"]["state"].update(state=2**200)), "streams.position.state.state"),
    ("stream inc even", edit_json("emitters", lambda e: e[0]["streams"]["velocity"]["state"].update(inc=2)), "streams.velocity.state.inc"),
    ("stream inc text", edit_json("emitters", lambda e: e[0]["streams"]["velocity"]["state"].update(inc="1")), "streams.velocity.state.inc"),
    ("stream has_uint32 2", edit_json("emitters", lambda e: e[0]["streams"]["life"].update(has_uint32=2)), "streams.life.has_uint32"),
    ("stream uinteger negative", edit_json("emitters", lambda e: e[0]["streams"]["life"].update(uinteger=-1)), "streams.life.uinteger"),
    ("waiting key missing", edit_json("emitters", lambda e: e[0]["waiting"].pop("spawn")), "waiting"),
    ("waiting x nan", edit_json("emitters", lambda e: e[0]["waiting"]["x"][0].__setitem__(0, float("nan"))), "waiting.x"),
    ("waiting m negative", edit_json("emitters", lambda e: e[0]["waiting"]["m"].__setitem__(0, -1.0)), "waiting.m"),
    ("waiting m one more", edit_json("emitters", lambda e: e[0]["waiting"]["m"].append(0.01)), "waiting.x"),
    ("waiting v flat", edit_json("emitters", lambda e: e[0]["waiting"].update(v=[0.0] * len(e[0]["waiting"]["v"]))), "waiting.v"),
    ("waiting life bool", edit_json("emitters", lambda e: e[0]["waiting"]["life"].__setitem__(0, True)), "waiting.life"),
    ("waiting a list", edit_json("emitters", lambda e: e[0].update(waiting=[])), "waiting"),
    # the collision books
    ("collision_stats not JSON", set_attr("collision_stats", "{"), "'collision_stats'"),
    ("collision_stats no total", edit_json("collision_stats", lambda s: s.pop("total")), "'collision_stats'"),
    ("collision_stats contacts missing", edit_json("collision_stats", lambda s: s["total"].pop("contacts")), "total.contacts"),
    ("collision_stats contacts negative", edit_json("collision_stats", lambda s: s["total"].update(contacts=-1)), "total.contacts"),
    ("collision_stats impacts bool", edit_json("collision_stats", lambda s: s["last"].update(impacts=True)), "last.impacts"),
    ("collision_stats impacts 2**70", edit_json("collision_stats", lambda s: s["last"].update(impacts=2**70)), "last.impacts"),
    ("collision_stats energy nan", edit_json("collision_stats", lambda s: s["total"].update(energy_lost=float("nan"))), "total.energy_lost"),
    ("collision_stats balance dtype", edit_json("collision_stats", lambda s: s["total"]["impulse_balance"].update(dtype="object")), "total.impulse_balance"),
    (
        "collision_stats balance dtype nonsense",
        edit_json("collision_stats", lambda s: s["total"]["impulse_balance"].update(dtype="foo")),
        "total.impulse_balance",
    ),
    ("collision_stats balance 2", edit_json("collision_stats", lambda s: s["total"]["impulse_balance"]["__array__"].pop()), "total.impulse_balance"),
    ("collision_stats unknown", edit_json("collision_stats", lambda s: s["last"].update(warp=1)), "last.warp"),
    ("collision_stats without collisions", edit_scene("[collisions]", "[unused]"), "'scene'"),
    # the frames' potential energies, what the recording knows of the world, the sets of particles
    ("potential one less", edit_json("run/potential", lambda p: p.pop()), "'run/potential'"),
    ("potential not a dict", edit_json("run/potential", lambda p: p.__setitem__(0, 1.0)), "'run/potential'"),
    ("potential text", edit_json("run/potential", lambda p: p[0].update(gravity="x")), "'run/potential'"),
    ("potential nan", edit_json("run/potential", lambda p: p[0].update(gravity=float("nan"))), "'run/potential'"),
    ("about not a dict", set_attr("run/about", "[]"), "'run/about'"),
    ("about dim", edit_json("run/about", lambda a: a.update(dim=2)), "about'.dim"),
    ("about dim bool", edit_json("run/about", lambda a: a.update(dim=True)), "about'.dim"),
    ("about dt", edit_json("run/about", lambda a: a.update(dt=1.0)), "about'.dt"),
    ("about method", edit_json("run/about", lambda a: a.update(method="rk4")), "about'.method"),
    ("about masses", edit_json("run/about", lambda a: a["masses"]["__array__"].__setitem__(0, 1.0)), "about'.masses"),
    ("about ids dtype", edit_json("run/about", lambda a: a["ids"].update(dtype="float64")), "about'.ids"),
    ("about unknown", edit_json("run/about", lambda a: a.update(warp=1)), "about'.warp"),
    ("about colliders missing", edit_json("run/about", lambda a: a.pop("colliders")), "about'.colliders"),
    ("about colliders torus", edit_json("run/about", lambda a: a.update(colliders=[{"type": "torus"}])), "about'.colliders"),
    ("about colliders nan", edit_json("run/about", lambda a: a["colliders"][0].update(lo=[float("nan")] * 3)), "about'.colliders"),
    ("about periodic", edit_json("run/about", lambda a: a.update(periodic=[1, 2, 3])), "about'.periodic"),
    ("about box_edges", edit_json("run/about", lambda a: a.update(box_edges={"__array__": [-1.0, 0.0, 0.0], "dtype": "float64"})), "about'.box_edges"),
    ("about springs", edit_json("run/about", lambda a: a.update(springs={"__array__": [[0, -1]], "dtype": "int64"})), "about'.springs"),
    ("sets empty", set_attr("run/sets", "[]"), "'run/sets'"),
    ("sets entry short", edit_json("run/sets", lambda s: (s[0].pop(), s[0].pop())), "'run/sets'"),
    ("sets entry long", edit_json("run/sets", lambda s: s[0].append(None)), "'run/sets'"),
    ("sets groups 32", edit_json("run/sets", lambda s: s[1][5]["__array__"].__setitem__(0, 32)), "'run/sets'"),
    ("sets groups negative", edit_json("run/sets", lambda s: s[-1][5]["__array__"].__setitem__(-1, -1)), "'run/sets'"),
    ("sets groups float", edit_json("run/sets", lambda s: s[0][5].update(dtype="float64")), "'run/sets'"),
    ("sets groups short", edit_json("run/sets", lambda s: s[1][5]["__array__"].pop()), "'run/sets'"),
    ("sets groups null", edit_json("run/sets", lambda s: s[0].__setitem__(5, None)), "'run/sets'"),
    ("about groups", edit_json("run/about", lambda a: a["groups"]["__array__"].__setitem__(0, 9)), "about'.groups"),
    ("about groups null", edit_json("run/about", lambda a: a.update(groups=None)), "about'.groups"),
    ("sets ids dtype", edit_json("run/sets", lambda s: s[0][0].update(dtype="foo")), "'run/sets'"),
    ("sets ids bools", edit_json("run/sets", lambda s: s[0][0]["__array__"].__setitem__(0, True)), "'run/sets'"),
    ("sets masses negative", edit_json("run/sets", lambda s: s[1][1]["__array__"].__setitem__(0, -1.0)), "'run/sets'"),
    ("sets radii nan", edit_json("run/sets", lambda s: s[1][2]["__array__"].__setitem__(0, float("nan"))), "'run/sets'"),
    ("sets radii short", edit_json("run/sets", lambda s: s[1][2]["__array__"].pop()), "'run/sets'"),
    ("sets colors 2", edit_json("run/sets", lambda s: s[-1][4]["__array__"][-1].__setitem__(0, 2.0)), "'run/sets'"),
    (
        "sets species numbers",
        edit_json("run/sets", lambda s: s[0].__setitem__(3, {"__array__": [1] * len(s[0][0]["__array__"]), "dtype": "<U1"})),
        "'run/sets'",
    ),
    ("sets one dropped", edit_json("run/sets", lambda s: s.pop(1)), "'run/ids'"),
    ("sets one more", edit_json("run/sets", lambda s: s.append(s[-1])), "'run/sets'"),
]


@pytest.mark.parametrize("damage, field", [pytest.param(d, field, id=name) for name, d, field in CASES])
def test_a_damaged_checkpoint_is_one_clean_error_naming_the_field(pristine, tmp_path, damage, field):
    path = tmp_path / "checkpoint.ckpt"
    shutil.copy(pristine, path)
    with h5py.File(path, "r+") as f:
        damage(f)
    calls = [kinema.resume_run] if field.startswith(("'run", "about", "'run/")) else [kinema.resume_run, kinema.World.load_checkpoint]
    for call in calls:
        with pytest.raises(CheckpointError) as caught:  # and nothing else (KeyError, OverflowError, ...)
            call(path)
        message = str(caught.value)
        assert "\n" not in message and message.startswith(f"{path}: ") and field in message, message
    assert issubclass(CheckpointError, kinema.io.TrajectoryFileError) and issubclass(CheckpointError, ValueError)


def test_a_checkpoint_whose_global_heap_would_hang_hdf5_is_refused(pristine, tmp_path):
    # (the trajectory reader's case, tests/test_io.py: one byte that would make the HDF5
    # library loop forever on the checkpoint's strings)
    from test_io import empty_free_space_in_the_global_heap, refusal_within_a_minute

    path = tmp_path / "checkpoint.ckpt"
    shutil.copy(pristine, path)
    at = empty_free_space_in_the_global_heap(path)
    for call in ("kinema.resume_run", "kinema.World.load_checkpoint"):
        said = refusal_within_a_minute(f"import kinema\n{call}({str(path)!r})")
        assert re.fullmatch(
            rf"CheckpointError: {re.escape(str(path))}: not a checkpoint that can be read: .* free-space object at byte {at} has size 0 .*", said
        ), said


def test_the_undamaged_checkpoint_resumes(pristine, tmp_path):
    # (the control of the cases above: the same copy, undamaged, goes on to the run's end)
    path = tmp_path / "checkpoint.ckpt"
    shutil.copy(pristine, path)
    with h5py.File(path, "r+") as f:  # opened for writing and closed, as the cases are
        f.attrs["kinema"] = f.attrs["kinema"]
    world, traj = kinema.resume_run(path)
    assert len(traj.t) == 16 and world.time == pytest.approx(0.3)
    traj.save(tmp_path / "t.h5")
    assert len(kinema.load_trajectory(tmp_path / "t.h5").t) == 16


def test_a_checkpoint_written_before_the_groups_resumes_with_group_0(pristine, tmp_path):
    # (sets of five fields and an about without groups: what kinema wrote before it recorded them)
    path = tmp_path / "checkpoint.ckpt"
    shutil.copy(pristine, path)
    with h5py.File(path, "r+") as f:
        sets = json.loads(f["run"].attrs["sets"])
        assert all(len(entry) == 6 for entry in sets)
        f["run"].attrs["sets"] = json.dumps([entry[:5] for entry in sets])
        about = json.loads(f["run"].attrs["about"])
        del about["groups"]
        f["run"].attrs["about"] = json.dumps(about)
    _, old = kinema.resume_run(path)
    _, new = kinema.resume_run(pristine)
    assert old.groups.dtype == np.int64 and old.groups.shape == old.ids.shape and not old.groups.any()
    np.testing.assert_array_equal(old.groups, new.groups)
    np.testing.assert_array_equal(old.positions, new.positions)


@pytest.mark.parametrize(
    "content",
    [
        pytest.param(lambda data: data[: len(data) // 2], id="truncated"),
        pytest.param(lambda data: data[:2048], id="truncated-to-2k"),
        pytest.param(lambda data: np.random.default_rng(1).bytes(len(data)), id="random-bytes"),
        pytest.param(lambda data: data[:8] + np.random.default_rng(2).bytes(len(data) - 8), id="hdf5-signature-then-random"),
        pytest.param(lambda data: b"", id="empty"),
    ],
)
def test_a_truncated_or_random_file_is_one_clean_error(pristine, tmp_path, content):
    path = tmp_path / "checkpoint.ckpt"
    path.write_bytes(content(pristine.read_bytes()))
    for call in (kinema.resume_run, kinema.World.load_checkpoint):
        with pytest.raises(CheckpointError) as caught:
            call(path)
        assert "\n" not in str(caught.value) and str(caught.value).startswith(f"{path}: ")


def test_a_damaged_waiting_birth_is_caught_where_it_is(pristine, tmp_path):
    # in a 2D world a birth held back must lie in the plane; here the world is 3D, so z is free,
    # but a held-back birth with an infinite velocity is refused by name
    path = tmp_path / "checkpoint.ckpt"
    shutil.copy(pristine, path)
    with h5py.File(path, "r+") as f:
        edit_json("emitters", lambda e: e[0]["waiting"]["v"][0].__setitem__(2, float("inf")))(f)
    with pytest.raises(CheckpointError, match=r"\[0\]\.waiting\.v\[0, 2\] = inf is invalid"):
        kinema.World.load_checkpoint(path)


def test_a_checkpoint_write_removes_what_a_killed_writer_of_it_left(tmp_path):
    # A writer killed mid-write (kill -9) leaves .checkpoint.ckpt.<host>-<pid>.<hex>.part;
    # the next write of the checkpoint removes it once that process is gone.
    import subprocess
    import sys

    from kinema.io._files import host_name

    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    left = tmp_path / f".checkpoint.ckpt.{host_name()}-{dead.pid}.8d906b868137.part"
    left.write_bytes(b"half a checkpoint")
    w = Scene.from_dict(scene("verlet", "impulse", count=20)).build()
    w.run(0.06, fps=50, checkpoint=tmp_path / "checkpoint.ckpt", checkpoint_every=0.02)
    assert not left.exists()
    assert not list(tmp_path.glob(".checkpoint.ckpt.*"))


# -- kinema run --resume of a damaged checkpoint, or of one whose remaining work is absurd ----


def _resumable(pristine, tmp_path):
    """A scene file and an output folder holding the checkpoint of a run of it."""
    scene_file = tmp_path / "gas.toml"
    Scene.from_dict(scene("verlet", "impulse", emitter=True)).to_toml(scene_file)
    out = tmp_path / "out"
    out.mkdir()
    shutil.copy(pristine, out / "checkpoint.ckpt")
    return scene_file, out


@pytest.mark.parametrize(
    "damage, field",
    [
        pytest.param(set_attr("run/per_frame", 0), "'run/per_frame'", id="per_frame-0"),
        pytest.param(set_attr("run/every", 0), "'run/every'", id="every-0"),
        pytest.param(edit_ds("run/x", at((3, 1), float("nan"))), "'run/x'", id="x-nan"),
        pytest.param(edit_json("emitters", lambda e: e[0].update(emitted=2**70)), "emitted", id="emitted-2**70"),
        pytest.param(del_attr("run/about"), "'run/about'", id="about-missing"),
        pytest.param(set_attr("steps", np.uint64(2**64 - 1)), "'steps'", id="steps-huge"),
    ],
)
def test_kinema_run_resume_of_a_damaged_checkpoint_is_exit_2_with_one_line(pristine, tmp_path, damage, field):
    from typer.testing import CliRunner

    from kinema.cli import app

    scene_file, out = _resumable(pristine, tmp_path)
    with h5py.File(out / "checkpoint.ckpt", "r+") as f:
        damage(f)
    res = CliRunner().invoke(app, ["run", str(scene_file), "--no-video", "--resume", "-o", str(out)])
    lines = res.output.strip().splitlines()
    assert res.exit_code == 2, res.output
    assert len(lines) == 1 and lines[0].startswith("error: ") and "checkpoint.ckpt" in lines[0] and field in lines[0], res.output
    assert not (out / "trajectory.h5").exists() and (out / "checkpoint.ckpt").exists()


def test_kinema_run_resume_refuses_absurd_remaining_work_before_running(pristine, tmp_path):
    # A checkpoint edited to a run of 1e10 more frames (4e11 steps, within a clock's 2**53) is
    # refused as a fresh run over the limits is, before any step; it ran for ages before.
    from typer.testing import CliRunner

    from kinema.cli import app

    scene_file, out = _resumable(pristine, tmp_path)
    with h5py.File(out / "checkpoint.ckpt", "r+") as f:
        f["run"].attrs["frames_total"] = 10**10
        f["run"].attrs["duration"] = 10**10 / f["run"].attrs["fps"]
    start = time.monotonic()
    res = CliRunner().invoke(app, ["run", str(scene_file), "--no-video", "--resume", "-o", str(out)])
    assert res.exit_code == 2, res.output
    assert time.monotonic() - start < 20
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and "checkpoint.ckpt: the resumed run would take" in lines[0] and "over the limits of" in lines[0] and "--force" in lines[0], (
        res.output
    )
    assert "frames to go" in lines[0] and "run/per_frame" in lines[0]
    assert not (out / "trajectory.h5").exists() and (out / "checkpoint.ckpt").exists()
    # as a fresh run of the scene over the limits is
    fresh = CliRunner().invoke(app, ["run", str(scene_file), "--no-video", "--duration", "1e9", "-o", str(tmp_path / "fresh")])
    assert fresh.exit_code == 2 and "over the limits of" in fresh.output and "--force" in fresh.output


def test_kinema_run_resume_of_a_sound_checkpoint_goes_on(pristine, tmp_path):
    from typer.testing import CliRunner

    from kinema.cli import app

    scene_file, out = _resumable(pristine, tmp_path)
    res = CliRunner().invoke(app, ["run", str(scene_file), "--no-video", "--resume", "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert "resuming" in res.output and "frame 11 of 16" in res.output
    assert len(kinema.load_trajectory(out / "trajectory.h5").t) == 16 and not (out / "checkpoint.ckpt").exists()


def test_resume_run_refuses_absurd_remaining_work_as_world_run_does(pristine, tmp_path):
    path = tmp_path / "checkpoint.ckpt"
    shutil.copy(pristine, path)
    with h5py.File(path, "r+") as f:
        f["run"].attrs["frames_total"] = 10**10  # 4e11 steps more: valid, but years of work
        f["run"].attrs["duration"] = 10**10 / f["run"].attrs["fps"]
    start = time.monotonic()
    with pytest.raises(ValueError, match=r"the rest of the run would take .* over max_work = 1\.0e\+11; give max_work=None"):
        kinema.resume_run(path)
    with pytest.raises(ValueError, match="over max_work = 1.0e.03"):
        kinema.resume_run(pristine, max_work=1e3)  # (the pristine one: 68 particles × 200 steps left)
    assert time.monotonic() - start < 20
    with pytest.raises(ValueError, match="max_work = -1 is invalid"):
        kinema.resume_run(pristine, max_work=-1)


def test_a_spring_made_without_a_rest_length_keeps_the_one_it_was_made_with(tmp_path):
    # Found by the fuzz suite: to_scene wrote the spring's length of the day as its rest
    # length, so a resumed run ended 2e-7 m from the run that wrote the checkpoint.
    w = kinema.World(dt=0.005)
    w.add_particles([[0.1, 0.2, 0.3], [0.45, 0.21, 0.33]], velocity=[[0.1, 0, 0], [0, 0.2, 0]])
    w.add(kinema.Spring(0, 1, 5.0))
    made = float(np.linalg.norm(w.positions[1] - w.positions[0]))
    w.step(4)
    w.save_checkpoint(tmp_path / "c.ckpt")
    back = kinema.World.load_checkpoint(tmp_path / "c.ckpt")
    assert float(np.ravel(back.forces[0].rest_length)[0]) == made
    assert float(np.ravel(w.to_scene().forces[0].rest_length)[0]) == made
    w.step(50)
    back.step(50)
    assert np.array_equal(w.positions, back.positions)


def test_a_pile_at_the_animation_accuracy_resumes_bit_for_bit(tmp_path):
    # The shock (collide/shock.rs) keeps nothing from step to step but what the physics grade
    # keeps (the warm start): a settling pile resumed from a checkpoint goes on bit for bit,
    # and the setting comes back with it.
    sys.path.insert(0, str(Path(__file__).parent))
    from test_collisions import _column

    w, _ = _column(2, 8, 20, 1 / 120, 11, seconds=0.4, accuracy="animation")
    a, b = run_alongside(w, tmp_path, before=30, after=60)
    assert b.collisions["accuracy"] == "animation"
    assert a.collision_stats()["total"]["impulses"] > 1000  # a pile in contact, not a gas
    assert_same(a, b)


def test_a_heap_sliding_into_a_corner_resumes_bit_for_bit_from_any_step(tmp_path):
    """18 balls fall into a box and slide into its corner under a tilted gravity (e = 0.3,
    mu = 0.3, 1 ms): impacts, resting contacts, walls touched and left. The impulse model's
    candidate list is rebuilt inside some of these steps, which moves every path's reference
    and predicts the impacts again, so where it was built decides the last bits: the
    checkpoint keeps where it was built and its skin, and the contact records whole (whether
    each carried load, which the solve's impulse alone does not tell). A run resumed from a
    checkpoint written every 25 steps goes on bit for bit, and so does the run that wrote it.
    (With the list built afresh on reading, 3 of these 19 resumes differed within 300 steps,
    and the demo's pile at 1 ms, written at step 500, by 0.27 m at step 1500.) A checkpoint
    written before the list was saved still resumes, its heap at rest in the same corner."""

    def heap():
        w = kinema.World(dt=1e-3, method="verlet")
        grid = np.stack(np.meshgrid(range(3), range(3), range(2), indexing="ij"), -1).reshape(-1, 3)
        w.add_particles(0.06 + 0.1 * grid + np.random.default_rng(7).uniform(-0.01, 0.01, (18, 3)), radius=0.04)
        w.add(kinema.Box([0, 0, 0], [0.5, 0.5, 1.0]))
        w.add(kinema.Gravity(g=[-2.0, -1.0, -9.81]))
        w.set_collisions(restitution=0.3, friction=0.3)
        return w

    steps = 500
    whole = heap()
    whole.step(steps)
    differ = 0
    # (after 99 steps a ball on the floor has a record that carried load with no impulse of
    # the solve stage: it bounced, so the checkpoint must say it carried)
    for at in sorted({99, *range(25, steps, 25)}):
        w = heap()
        w.step(at)
        w.save_checkpoint(tmp_path / "w.ckpt")
        again = kinema.World.load_checkpoint(tmp_path / "w.ckpt")
        assert again._core.collision_carry() == w._core.collision_carry()  # every record whole
        again.step(steps - at)
        assert_same(whole, again)
        w.step(steps - at)  # (and writing it changed no bit of the writer's run)
        assert_same(whole, w)
        with h5py.File(tmp_path / "w.ckpt", "r+") as f:
            del f["collision_carry/list_built_at"], f["collision_carry/list_skin"]
        older = kinema.World.load_checkpoint(tmp_path / "w.ckpt")
        older.step(steps - at)
        differ += not np.array_equal(older.positions, whole.positions)
        np.testing.assert_allclose(older.positions, whole.positions, rtol=0, atol=0.02)
    assert differ > 0  # (the list's build was needed: without it some resumed run differs)
