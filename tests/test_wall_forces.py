"""Wall forces recorded per frame (issue 47): at each frame of a world with colliders,
`World.run` keeps what the particles had given each collider since the world began
(`World.collider_books()`: `Trajectory.collider_momentum`, `collider_normal`,
`collider_tangential`), and `Trajectory.collider_forces()` makes of them the mean pressure and
shear force on each collider between frames; H5MD files and checkpoints of a run keep them.

Each physics test compares with a closed form and says which: a resting column's floor bears
n m g over every frame interval and no shear (statics), with the Hertz model and with the
impulse model's column asleep; a ball sliding on a rough floor shears it by μ times the force
that presses on it (Coulomb), gives it 2/7 of its momentum by the time it rolls (the ball
keeps 5/7 of its speed: angular momentum about the contact point), and no shear after.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest
from test_contact_reports import G, M, column, resting_ball

import kinema

RECORD = ("collider_momentum", "collider_normal", "collider_tangential")


@pytest.mark.parametrize("model", ["hertz", "impulse"])
@pytest.mark.parametrize("n", [3, 7])
def test_a_resting_columns_floor_bears_its_weight_over_every_frame_and_no_shear(model, n):
    # Statics: the floor carries the whole column, n m g, which presses it down (−z); nothing
    # shears it. The impulse model's column is asleep (its steps book the loads of its last
    # awake step); the Hertz column (dt = 1e-5 s, e = 0.1) has settled after 1 s.
    w = column(model, n)
    if model == "impulse":
        assert w.collision_stats()["last"]["asleep"] == n
    tr = w.run(0.1, fps=100)
    forces = tr.collider_forces()
    frames = len(tr.t)
    assert forces.normal.shape == forces.tangential.shape == forces.total.shape == (frames - 1, 1, 3)
    np.testing.assert_array_equal(forces.start, tr.t[:-1])
    np.testing.assert_array_equal(forces.end, tr.t[1:])
    weight = np.tile([0.0, 0.0, -n * M * G], (frames - 1, 1))
    np.testing.assert_allclose(forces.normal[:, 0], weight, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(forces.total[:, 0], weight, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(forces.tangential, 0.0, atol=1e-12)
    # the record is the world's books, frame by frame: the last frame's are the books now
    books = w.collider_books()
    for name in RECORD:
        np.testing.assert_array_equal(getattr(tr, name)[-1], books[name.removeprefix("collider_")])


@pytest.mark.parametrize("model", ["impulse", "hertz"])
def test_a_sliding_ball_shears_the_floor_by_mu_times_its_weight_until_it_rolls(model):
    # Coulomb: while the ball slides, the friction on it is μ times the normal force, against
    # its motion; the floor feels the reaction, along +x, μ m g, and is pressed by m g. It
    # slides until v = ω R, at t* = 2 v₀ / (7 μ g) = 0.097 s, then rolls at 5/7 v₀ with no
    # friction: over the slide the floor took m v₀ − m (5/7) v₀ = 2/7 m v₀ along x.
    mu, v0 = 0.3, 1.0
    w = resting_ball(model, mu)
    w.velocities = [[v0, 0.0, 0.0]]
    tr = w.run(0.2, fps=100)
    forces = tr.collider_forces()
    t_star = 2 * v0 / (7 * mu * G)
    sliding, rolling = forces.end <= t_star + tr.t[0], forces.start >= t_star + tr.t[0] + 0.01
    assert sliding.sum() == 9 and rolling.sum() == 9
    press, shear = forces.normal[:, 0], forces.tangential[:, 0]
    np.testing.assert_allclose(press[:, 2], -M * G, rtol=1e-3)
    np.testing.assert_allclose(press[:, :2], 0.0, atol=1e-12)
    np.testing.assert_allclose(shear[sliding], mu * np.abs(press[sliding, 2:3]) * [1.0, 0.0, 0.0], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(shear[rolling], 0.0, atol=1e-3 * mu * M * G)
    # the interval it stops sliding in is sheared for the part of it before t*
    k = int(np.argmax(~sliding))
    part = (t_star + tr.t[0] - forces.start[k]) / (forces.end[k] - forces.start[k])
    assert shear[k, 0] == pytest.approx(part * mu * M * G, abs=0.02 * mu * M * G)
    took = tr.collider_tangential[-1, 0] - tr.collider_tangential[0, 0]
    np.testing.assert_allclose(took, [2 / 7 * M * v0, 0.0, 0.0], rtol=2e-3, atol=1e-12)


def bin_of_balls(model="impulse"):
    """Eighteen balls thrown sideways in a box on a floor: they strike the box's walls and rest
    on the floor, so that both colliders take momentum, pressure and shear."""
    w = kinema.World(dt=1e-3 if model == "impulse" else 2e-4, spin=True)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.add(kinema.Box([-0.2, -0.2, -0.5], [0.2, 0.2, 1.0]))
    x = [[-0.1 + 0.1 * a, -0.1 + 0.1 * b, 0.05 + 0.12 * c] for a in range(3) for b in range(3) for c in range(2)]
    w.add_particles(x, radius=0.04, mass=0.1, velocity=[[1.5 - 0.3 * k, 0.7 * (-1) ** k, 0.0] for k in range(18)])
    w.set_collisions(restitution=0.5, friction=0.4, **({"model": "spring_dashpot", "stiffness": 2e4} if model != "impulse" else {}))
    return w


def quiet_run(w, *args, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kinema.StabilityWarning)
        warnings.simplefilter("ignore", kinema.ContactTimeWarning)
        return w.run(*args, **options)


def test_h5md_keeps_the_wall_forces_bit_for_bit(tmp_path):
    tr = quiet_run(bin_of_balls(), 0.3, fps=50)
    assert tr.collider_normal.shape == (len(tr.t), 2, 3) and np.abs(tr.collider_tangential[-1]).min(axis=1).max() > 0
    tr.save(tmp_path / "run.h5")
    back = kinema.Trajectory.load(tmp_path / "run.h5")
    for name in RECORD:
        np.testing.assert_array_equal(getattr(back, name), getattr(tr, name), err_msg=name)
    tr.save(tmp_path / "md.h5", units="MD")  # u nm ps-1, within one rounding of the exact factor
    md = kinema.Trajectory.load(tmp_path / "md.h5")
    for name in RECORD:
        np.testing.assert_allclose(getattr(md, name), getattr(tr, name), rtol=4e-16, atol=0, err_msg=name)
    import h5py

    with h5py.File(tmp_path / "md.h5") as f:
        value = f["observables/collider_normal/value"]
        assert value.shape == (len(tr.t), 2, 3) and value.attrs["unit"] == "u nm ps-1"
        assert f["observables/collider_normal/step"] == f["particles/all/position/step"]  # the one clock, hard-linked


def test_a_trajectory_without_colliders_or_books_has_no_wall_forces(tmp_path):
    w = kinema.World()
    w.add_particles([0.0, 0.0, 0.0], velocity=[1.0, 0.0, 0.0])
    tr = w.run(0.05, fps=100)
    assert all(getattr(tr, name) is None for name in RECORD)
    with pytest.raises(ValueError, match="no collider_momentum"):
        tr.collider_forces()
    tr.save(tmp_path / "run.h5")
    assert kinema.Trajectory.load(tmp_path / "run.h5").collider_normal is None
    # a force model stepped by a method other than verlet books nothing: no record, not zeros
    w = kinema.World(dt=1e-4, method="rk4")
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.add_particles([0.0, 0.0, 0.011], radius=0.01, mass=0.01)
    w.add(kinema.Gravity())
    w.set_collisions(model="spring_dashpot", stiffness=1e4, friction=0.0)
    assert quiet_run(w, 0.05, fps=100).collider_normal is None


def test_a_collider_added_during_the_run_took_nothing_before():
    w = bin_of_balls()
    extra = []

    def add_a_wall(world):
        if not extra and world.time > 0.1:
            extra.append(world.add(kinema.Plane([0.0, 0.0, 0.5], [0.0, 0.0, -1.0])))

    tr = quiet_run(w, 0.2, fps=50, callback=add_a_wall)
    assert tr.collider_momentum.shape == (len(tr.t), 3, 3)
    before = tr.t <= 0.1 + 1e-9
    np.testing.assert_array_equal(tr.collider_momentum[before, 2], 0.0)
    np.testing.assert_array_equal(tr.collider_momentum[-1], w.collider_books()["momentum"])


# -- checkpoints ----------------------------------------------------------------------------------


class Stop(Exception):
    pass


def stopped_and_resumed(model, path):
    """A run of 0.4 s writing a checkpoint every 0.1 s, stopped at 0.25 s and resumed."""

    def stop(world):
        if world.time > 0.25:
            raise Stop

    with pytest.raises(Stop):
        quiet_run(bin_of_balls(model), 0.4, fps=50, checkpoint=path, checkpoint_every=0.1, callback=stop)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return kinema.resume_run(path)[1]


@pytest.mark.parametrize("model", ["impulse", "spring_dashpot"])
def test_a_resumed_run_records_the_wall_forces_of_the_run_that_went_on(model, tmp_path):
    # The frames up to the checkpoint (t = 0.2 s) come out of it as they were written; after
    # it, the world read back goes on from the books it carried and, with a force model, from
    # the last step's collider forces (the start of the next step's h/2 (F + F')): the same
    # bits as the run that went on.
    whole = quiet_run(bin_of_balls(model), 0.4, fps=50, checkpoint=tmp_path / "a.ckpt", checkpoint_every=0.1)
    resumed = stopped_and_resumed(model, tmp_path / "b.ckpt")
    for name in RECORD:
        np.testing.assert_array_equal(getattr(resumed, name), getattr(whole, name), err_msg=name)


def test_a_resumed_run_records_the_same_bits_of_wall_forces(tmp_path):
    # the engine takes the checkpoint's books back (restore_collider_books) and goes on from them
    whole = quiet_run(bin_of_balls(), 0.4, fps=50, checkpoint=tmp_path / "a.ckpt", checkpoint_every=0.1)
    resumed = stopped_and_resumed("impulse", tmp_path / "b.ckpt")
    for name in RECORD:
        np.testing.assert_array_equal(getattr(resumed, name), getattr(whole, name), err_msg=name)


@pytest.mark.parametrize("model", ["impulse", "spring_dashpot"])
def test_writing_checkpoints_changes_no_bit_of_the_wall_forces(model, tmp_path):
    plain = quiet_run(bin_of_balls(model), 0.4, fps=50)
    written = quiet_run(bin_of_balls(model), 0.4, fps=50, checkpoint=tmp_path / "a.ckpt", checkpoint_every=0.1)
    np.testing.assert_array_equal(written.positions, plain.positions)
    for name in RECORD:
        np.testing.assert_array_equal(getattr(written, name), getattr(plain, name), err_msg=name)


def test_a_world_read_from_a_checkpoint_goes_on_with_the_books_of_the_one_that_wrote_it(tmp_path):
    w = bin_of_balls()
    w.step(150)
    w.save_checkpoint(tmp_path / "w.ckpt")
    again = kinema.World.load_checkpoint(tmp_path / "w.ckpt")
    for last in (False, True):  # the same bits until it steps
        mine, read = w.collider_books(last=last), again.collider_books(last=last)
        for key in mine:
            np.testing.assert_array_equal(read[key], mine[key], err_msg=f"{key} (last={last})")
    w.step(100)
    again.step(100)
    mine, read = w.collider_books(), again.collider_books()
    for key in mine:
        np.testing.assert_allclose(read[key], mine[key], rtol=0, atol=1e-14 * np.abs(mine[key]).max(), err_msg=key)
    for key, a in w.collider_books(last=True).items():  # its own last step's, the engine's
        np.testing.assert_array_equal(again.collider_books(last=True)[key], a, err_msg=key)


def test_wall_forces_of_another_shape_are_refused_writing_and_reading(tmp_path):
    import h5py

    tr = quiet_run(bin_of_balls(), 0.1, fps=50)
    tr.collider_tangential = tr.collider_tangential[:, :1]  # one collider where the others have two
    with pytest.raises(kinema.io.TrajectoryFileError, match=r"'collider_tangential' has shape \(6, 1, 3\); it must be \(6, 2, 3\)"):
        tr.save(tmp_path / "run.h5")
    assert not (tmp_path / "run.h5").exists()
    with pytest.raises(ValueError, match=r"collider_normal has shape \(6, 2\); it must be \(frames, colliders, 3\)"):
        dataclasses.replace(tr, collider_normal=tr.collider_normal[..., 0])
    tr.collider_tangential = None
    tr.save(tmp_path / "run.h5")
    with h5py.File(tmp_path / "run.h5", "a") as f:
        value = f["observables/collider_normal/value"]
        data = value[()]
        del f["observables/collider_normal/value"]
        f["observables/collider_normal"].create_dataset("value", data=data[..., :2])
    with pytest.raises(
        kinema.io.TrajectoryFileError, match=r"'collider_normal' \(/observables/collider_normal/value\) has shape \(6, 2, 2\); it must be \(6, 2, 3\)"
    ):
        kinema.Trajectory.load(tmp_path / "run.h5")
