"""Moving colliders from Python (kinema.Motion, kinema.Keyframes, issue 28): bad motions are
refused by name; a plane moving into a ball at rest throws it at (1 + e) V and books −m (1 + e)
V; a grain carried by a turning drum moves with the wall; the drum scene, at a reduced size,
holds every grain, carries the bed with its wall and balances momentum with the colliders'
books and gravity; the paddle scene throws balls; a motion goes through scene files, H5MD and
checkpoints, and a description gives the engine's poses."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import kinema
from kinema import _core
from kinema.colliders import rotation_matrix
from kinema.render.descriptions import collider_poses
from kinema.scene import Scene, SceneError

SCENES = Path(__file__).resolve().parent.parent / "examples" / "scenes"
DRUM_RADIUS = 0.25  # m (examples/scenes/make_drum.py)
DRUM_DEPTH = 0.08  # m
G = np.array([0.0, 0.0, -9.81])  # m/s², kinema.Gravity()'s default


# -- refusals ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "make, kind, words",
    [
        (lambda: kinema.Motion(velocity=[1, 2]), ValueError, "velocity = [1, 2] is invalid: it must be 3 finite numbers (x, y, z), m/s"),
        (
            lambda: kinema.Motion(angular_velocity=[0, math.inf, 0]),
            ValueError,
            "angular_velocity = [0, inf, 0] is invalid: it must be 3 finite numbers (x, y, z), rad/s",
        ),
        (lambda: kinema.Motion(pivot="origin"), TypeError, "pivot = 'origin' is invalid"),
        (lambda: kinema.Keyframes([]), ValueError, "times = [] is invalid: keyframes need at least one time, s"),
        (lambda: kinema.Keyframes([0, 1, 1]), ValueError, "times[2] = 1.0 is invalid: keyframe times must be finite and strictly increasing, s"),
        (lambda: kinema.Keyframes([[0, 1]]), ValueError, "times = [[0, 1]] is invalid: it must be a list of keyframe times, s"),
        (
            lambda: kinema.Keyframes([0, 1], translations=[[0, 0, 0]]),
            ValueError,
            "translations has shape (1, 3); it must be (2, 3): one (x, y, z) per keyframe time, m",
        ),
        (lambda: kinema.Keyframes([0, 1], rotations=[[0, 0, 0], [0, math.nan, 0]]), ValueError, "rotations[1][1] = nan is invalid: it must be finite, degrees"),
        (lambda: kinema.Keyframes([0, 1], rotations=[[0, 0, 0], [0, 0, 270]]), ValueError, "rotations[1] = [0.0, 0.0, 270.0] is invalid: it is 270° about z"),
        (lambda: kinema.Keyframes([0, 1], pivot=[0, 0]), ValueError, "pivot = [0, 0] is invalid: it must be 3 finite numbers (x, y, z), m"),
        (
            lambda: kinema.Plane([0, 0, 0], [0, 0, 1], motion=(1, 0, 0)),
            TypeError,
            "motion = (1, 0, 0) is invalid: it must be a kinema.Motion, kinema.Keyframes or None",
        ),
        (
            lambda: kinema.Box([0, 0, 0], [1, 1, 1], motion=kinema.Motion(angular_velocity=[0, 0, 1])),
            ValueError,
            "a Box stays axis-aligned and can only translate",
        ),
        (
            lambda: kinema.Box([0, 0, 0], [1, 1, 1], motion=kinema.Keyframes([0, 1], rotations=[[0, 0, 0], [0, 0, 10]])),
            ValueError,
            "a Box stays axis-aligned and can only translate",
        ),
    ],
)
def test_bad_motions_are_refused_by_name(make, kind, words):
    with pytest.raises(kind) as e:
        make()
    assert words in str(e.value)


def test_the_world_refuses_a_motion_before_adding_the_collider():
    w = kinema.World(dim=2)
    with pytest.raises(ValueError, match=r"velocity\[2\] = 1 is invalid: a 2D world keeps z = 0"):
        w.add(kinema.Plane([0, 0, 0], [0, 1, 0], motion=kinema.Motion(velocity=[0, 0, 1])))
    assert w.colliders == []  # nothing was added
    plane = w.add(kinema.Plane([0, 0, 0], [0, 1, 0], motion=kinema.Motion(velocity=[1, 0, 0], angular_velocity=[0, 0, 0.5])))
    with pytest.raises(ValueError, match=r"collider = 3 is invalid: an index of w.colliders, 0..0"):
        w.set_motion(3, None)
    with pytest.raises(ValueError, match="it is not one of this world's colliders"):
        w.set_motion(kinema.Plane([0, 0, 0], [0, 1, 0]), None)
    with pytest.raises(TypeError, match="motion = 'still' is invalid"):
        w.set_motion(plane, "still")
    w.set_motion(plane, None)  # the object added still names it after set_motion replaced it
    w.set_motion(plane, kinema.Keyframes([0, 1], translations=[[0, 0, 0], [1, 0, 0]]))
    assert isinstance(w.colliders[0].motion, kinema.Keyframes) and plane.motion.velocity == (1.0, 0.0, 0.0)


def test_keyframe_rotations_are_the_meshes_euler_angles():
    angles = [[10, -20, 35], [100, 40, -170], [0, 90, 0], [180, 0, 0]]
    for a in angles:
        pose = collider_poses({"type": "plane", "motion": kinema.Keyframes([0.0], rotations=[a])._binding()}, [5.0])[0]
        assert np.allclose(pose[:, :3], rotation_matrix(a), atol=1e-14)
    q = kinema.Keyframes([0, 1, 2], rotations=[[0, 0, 0], [0, 0, 90], [0, 0, 179]]).quaternions
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0) and np.allclose(q[1], [math.sqrt(0.5), 0, 0, math.sqrt(0.5)])


# -- closed forms -----------------------------------------------------------------------------


def test_a_moving_plane_throws_a_ball_at_rest_at_one_plus_e_times_its_speed():
    """A floor moving up at V into a ball at rest (no gravity): in the floor's frame the ball
    comes at −V and leaves at e V, so it leaves at (1 + e) V; the floor books −m (1 + e) V of
    momentum, did work J·V = m (1 + e) V² on it, and the collisions dissipated ½ m (1 − e²) V²
    = energy_lost + work."""
    m, e, v_wall = 2.0, 0.5, 1.0
    w = kinema.World(dt=1e-4)
    w.add_particles([0.0, 0.0, 0.1], radius=0.05, mass=m)
    w.set_collisions(restitution=e)
    w.add(kinema.Plane([0, 0, -0.2], [0, 0, 1], motion=kinema.Motion(velocity=[0, 0, v_wall])))
    w.step(3000)
    assert w.velocities[0] == pytest.approx([0.0, 0.0, (1 + e) * v_wall], abs=1e-12)
    books = w.collider_books()
    assert books["momentum"][0] == pytest.approx([0.0, 0.0, -m * (1 + e) * v_wall], abs=1e-12)
    assert books["work"][0] == pytest.approx(m * (1 + e) * v_wall**2, rel=1e-12)
    lost = w.collision_stats()["total"]["energy_lost"]
    assert lost + books["work"][0] == pytest.approx(0.5 * m * (1 - e * e) * v_wall**2, rel=1e-12)


def test_a_grain_in_a_turning_drum_moves_with_its_wall():
    """One grain at the bottom of the drum turning at ω is carried by friction (μ = 0.8, so up
    to atan 0.8 = 38.7° from the bottom) at the wall's velocity ω × x_c at the contact point
    x_c = x − r n: to 1.5e-5 m/s of the 0.3 m/s (the grain rides over the 128 flat facets)."""
    omega = np.array([0.0, 1.2, 0.0])
    w = kinema.World(dt=0.002)
    w.add_particles([0.0, 0.0, -0.243], radius=0.007, mass=0.0032)
    w.set_collisions(restitution=0.25)
    w.add(kinema.Gravity())
    w.add(kinema.Mesh(SCENES / "drum.obj", inside=True, friction=0.8, motion=kinema.Motion(angular_velocity=omega)))
    worst = 0.0
    for _ in range(10):  # 0.5 s: carried to 34° from the bottom
        w.step(25)
        c = w.contacts()
        assert list(c["collider"]) == [0]
        xc = w.positions[0] - 0.007 * c["normal"][0]
        worst = max(worst, float(np.linalg.norm(w.velocities[0] - np.cross(omega, xc))))
    x = w.positions[0]
    assert math.degrees(math.atan2(-x[0], -x[2])) == pytest.approx(math.degrees(0.5 * 1.2), abs=0.5)
    assert worst < 1.5e-5


# -- the example scenes, reduced --------------------------------------------------------------


def _lattice(block, counts):
    block.counts = counts
    block.origin = [-(n - 1) / 2 * block.spacing for n in counts]


def test_the_drum_holds_every_grain_carries_the_bed_and_balances_momentum():
    """examples/scenes/drum.toml with 360 grains, 1.5 s. Every grain stays inside: its centre at
    most R − r from the axis and D/2 − r from the mid-plane, up to 1e-4 m (measured 1.3e-5 m,
    at a cap: the overlaps the contacts leave). While the bed is carried up (0.4 to 0.8 s), most
    wall contacts move with the wall to 1 cm/s, a thirtieth of its 0.3 m/s (the surface velocity
    enters every contact; measured 0.78 to 0.94 of them, 0.22 to 0.32 to 1e-4 m/s and at most
    0.02 to 1e-6 m/s: the solver stops at its 100 sweeps in this pile, where a lone grain sticks
    to 1.5e-5 m/s, above). Momentum: Σ m Δv = −Σ the colliders' booked momentum + M g t, to rounding."""
    scene = Scene.from_toml(SCENES / "drum.toml")
    _lattice(scene.particles[0], [9, 4, 10])
    w = scene.build()
    omega = np.array(w.colliders[0].motion.angular_velocity)
    r = np.asarray(w._core.radii)
    m, v0 = w.masses.copy(), w.velocities.copy()
    outside, carried = 0.0, []
    for k in range(15):
        w.step(50)
        x = w.positions
        radial = np.hypot(x[:, 0], x[:, 2]) - (DRUM_RADIUS - r)
        axial = np.abs(x[:, 1]) - (DRUM_DEPTH / 2 - r)
        outside = max(outside, float(radial.max()), float(axial.max()))
        if 3 <= k <= 7:
            c = w.contacts()
            wall = (c["collider"] == 0) & (c["overlap"] > 0)
            i, n = c["i"][wall], c["normal"][wall]
            slip = np.linalg.norm(w.velocities[i] - np.cross(omega, x[i] - r[i, None] * n), axis=1)
            carried.append(float(np.mean(slip < 1e-2)))
    assert len(w) == 360 and w.time == pytest.approx(1.5)
    assert outside < 1e-4
    assert min(carried) > 0.7, carried
    given = (m[:, None] * (w.velocities - v0)).sum(axis=0)
    books = w.collider_books()
    assert given == pytest.approx(-books["momentum"].sum(axis=0) + m.sum() * G * w.time, abs=1e-12)
    dissipated = w.collision_stats()["total"]["energy_lost"] + books["work"].sum()
    assert books["work"][0] > 0 and dissipated > 0


def test_the_paddle_throws_the_balls():
    """examples/scenes/paddle.toml with 60 balls on the paddle's far end, 0.9 s: they settle on
    it (slower than 0.3 m/s: they start up to 2 mm apart) until it turns at 0.4 s, then leave it
    faster than 2 m/s and rise above 0.3 m, where gravity alone would give them at most
    √(2 g h₀) = 1.0 m/s, h₀ the highest start above the floor. The two colliders' books and
    gravity balance their momentum."""
    scene = Scene.from_toml(SCENES / "paddle.toml")
    block = scene.particles[0]
    block.counts = [6, 5, 2]
    block.origin = [-0.175 + 9 * block.spacing, -2 * block.spacing, block.origin[2]]  # the paddle's far end
    w = scene.build()
    m, v0 = w.masses.copy(), w.velocities.copy()
    fall = math.sqrt(2 * 9.81 * float(w.positions[:, 2].max()))
    traj = w.run(0.9, fps=50)
    speed = np.linalg.norm(traj.velocities, axis=2)
    assert speed[traj.t < 0.4].max() < 0.3
    assert fall < 1.1 and speed.max() > 2.0 and traj.positions[:, :, 2].max() > 0.3
    books = w.collider_books()
    given = (m[:, None] * (w.velocities - v0)).sum(axis=0)
    assert given == pytest.approx(-books["momentum"].sum(axis=0) + m.sum() * G * w.time, abs=1e-12)
    assert books["work"][1] > 0  # the paddle gave the energy


# -- files ------------------------------------------------------------------------------------


def _moving_world() -> kinema.World:
    w = kinema.World(dt=1e-3)
    w.add_particles([[0.0, 0.0, 0.3], [0.1, 0.0, 0.5]], radius=0.02, mass=0.01)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1], friction=0.3, motion=kinema.Motion(velocity=[0.1, 0, 0], angular_velocity=[0, 0, 0.2], pivot=[0, 0, 0])))
    w.add(kinema.Box([-1, -1, -1], [1, 1, 2], motion=kinema.Keyframes([0.0, 0.5], translations=[[0, 0, 0], [0.05, 0, 0]])))
    w.add(
        kinema.SphereObstacle(
            [0.3, 0.0, 0.2],
            0.1,
            motion=kinema.Keyframes([0.0, 0.2, 0.4], [[0, 0, 0], [0, 0, 0.1], [0, 0, 0.1]], [[0, 0, 0], [0, 30, 0], [0, 60, 45]], pivot=[0.3, 0, 0]),
        )
    )
    w.set_collisions(restitution=0.5, friction=0.3)
    return w


def test_a_motion_goes_through_a_scene_file_and_a_checkpoint(tmp_path):
    w = _moving_world()
    w.step(100)
    scene = w.to_scene()
    assert scene.colliders[2].motion.rotations == [[0.0, 0.0, 0.0], [0.0, 30.0, 0.0], [0.0, 60.0, 45.0]]  # degrees, as given
    again = Scene.from_string(scene.to_toml_string()).build()
    assert [c.motion for c in again.colliders] == [c.motion for c in w.colliders]
    w.save_checkpoint(tmp_path / "w.ckpt")
    back = kinema.World.load_checkpoint(tmp_path / "w.ckpt")
    w.step(300)
    back.step(300)
    assert np.array_equal(w.positions, back.positions) and np.array_equal(w.velocities, back.velocities)


def test_a_motion_goes_through_h5md_and_gives_the_engines_poses(tmp_path):
    w = _moving_world()
    traj = w.run(0.2, fps=50)
    path = traj.save(tmp_path / "moving.h5")
    back = kinema.load_trajectory(path)
    assert back.colliders == traj.colliders
    steady, box, sphere = back.colliders
    assert set(steady["motion"]) == {"velocity", "angular_velocity", "pivot"} and "motion" in box
    times = np.linspace(-0.1, 0.6, 8)
    expected = _core.collider_poses(times.tolist(), **w.colliders[2].motion._binding())
    assert np.array_equal(collider_poses(sphere, times), expected)
    still = collider_poses({"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 1]}, times)
    assert np.array_equal(still, np.broadcast_to(np.eye(3, 4), (8, 3, 4)))
    # the pose at 0.4 s: the last key, held
    pose = collider_poses(sphere, [0.4, 1.0])
    assert np.allclose(pose[0, :, :3], rotation_matrix([0, 60, 45])) and np.array_equal(pose[0], pose[1])
    assert np.allclose(pose[0, :, 3], np.array([0.3, 0, 0]) + [0, 0, 0.1] - rotation_matrix([0, 60, 45]) @ [0.3, 0, 0])


def test_scene_motion_errors_name_the_field():
    head = '[world]\ndim = DIM\n[[colliders]]\ntype = "TYPE"\n'
    plane3 = head.replace("DIM", "3").replace("TYPE", "plane") + "point = [0, 0, 0]\nnormal = [0, 0, 1]\n"
    cases = [
        (plane3 + "motion = { velocty = [0, 0, 1] }\n", "s.toml: colliders[0].motion.velocty: unknown key; did you mean 'velocity'?"),
        (plane3 + "motion = { velocity = [0, 0, nan] }\n", "colliders[0].motion.velocity: [0, 0, nan] is invalid: velocity must be finite numbers (m/s)"),
        (
            plane3 + "[colliders.motion]\ntimes = [0, 0]\n",
            "colliders[0].motion.times: [0, 0] is invalid: keyframe times must be finite and strictly increasing, s",
        ),
        (plane3 + "[colliders.motion]\ntimes = [0, 1]\ntranslations = [[0, 0, 0]]\n", "translations has 1 rows for 2 times; give one per keyframe time"),
        (plane3 + "[colliders.motion]\ntimes = [0, 1]\nrotations = [[0, 0, 0], [0, 0, 200]]\n", "rotations[1] is 200° about z from rotations[0]"),
        (plane3 + "[colliders.motion]\ntimes = [0, 1]\nvelocity = [1, 0, 0]\n", "colliders[0].motion.velocity: unknown key"),
        (
            head.replace("DIM", "3").replace("TYPE", "box") + "lo = [0, 0, 0]\nhi = [1, 1, 1]\nmotion = { angular_velocity = [0, 0, 1] }\n",
            "colliders[0].motion: {'angular_velocity': [0, 0, 1]} is invalid: a box stays axis-aligned and can only translate (angular_velocity must be 0)",
        ),
        (
            head.replace("DIM", "2").replace("TYPE", "plane") + "point = [0, 0]\nnormal = [0, 1]\nmotion = { angular_velocity = [1, 0, 0] }\n",
            "colliders[0].motion.angular_velocity = [1.0, 0.0, 0.0] is invalid: in a 2D world (world.dim = 2) a collider moves in the xy-plane and turns about z",
        ),
    ]
    for text, words in cases:
        with pytest.raises(SceneError) as e:
            Scene.from_string(text, "s.toml")
        assert words in str(e.value), (text, str(e.value))


def test_the_docs_example_prints_what_the_docs_say(capsys):
    """docs/collisions.md, "Moving colliders": the rising floor's example and its output."""
    text = (Path(__file__).resolve().parent.parent / "docs" / "collisions.md").read_text()
    after = text[text.index("A ball rising into a floor moving") :]
    code = after.split("```python\n", 1)[1].split("```", 1)[0]
    printed = after.split("```text {.output}\n", 1)[1].split("```", 1)[0]  # (also checked by test_docs.py)
    exec(compile(code, "docs/collisions.md", "exec"), {})
    assert capsys.readouterr().out == printed


# -- a Motion starts when it is given (issue 46) ---------------------------------------------
def _ball_on_a_floor():
    w = kinema.World(dim=3, dt=1e-3)
    w.add_particles(np.array([[0.0, 0.0, 0.1]]), radius=0.1)
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1], restitution=0.0))
    w.add(kinema.Gravity())
    return w


def test_a_motion_set_late_starts_where_the_collider_is():
    # Before, a Motion set at t = 4 s ran on the world's clock from 0: the floor jumped 4 m up
    # at once and threw the ball. Now it starts then, from where the floor is: over the next
    # 0.5 s the ball rides it up 0.5 m (closed form: the floor's V t, the ball on it).
    w = _ball_on_a_floor()
    w.step(4000)
    t0 = w.time
    w.set_motion(0, kinema.Motion(velocity=(0, 0, 1.0)))
    assert w.colliders[0].motion.start == t0
    w.step(500)
    assert w.positions[0, 2] == pytest.approx(0.1 + (w.time - t0), abs=2e-3)
    assert w.velocities[0, 2] == pytest.approx(1.0, abs=1e-9)


def test_a_motion_with_a_start_rests_until_then():
    w = _ball_on_a_floor()
    w.set_motion(0, kinema.Motion(velocity=(0, 0, 1.0), start=0.25))
    w.step(200)
    assert w.positions[0, 2] == pytest.approx(0.1, abs=1e-6)  # at rest on the floor at 0.2 s
    w.step(300)
    assert w.positions[0, 2] == pytest.approx(0.1 + (w.time - 0.25), abs=2e-3)
    # a turning motion from its start: at 0.25 s + τ the plane has turned by ω τ
    poses = _core.collider_poses([0.0, 0.25, 0.75], **kinema.Motion(angular_velocity=(0, 0, 2.0), start=0.25)._binding())
    assert np.array_equal(poses[0], np.eye(3, 4)) and np.array_equal(poses[1], np.eye(3, 4))
    assert np.allclose(poses[2, :, :3], rotation_matrix([0, 0, np.degrees(2.0 * 0.5)]))


def test_a_late_motion_goes_through_a_scene_a_checkpoint_and_h5md(tmp_path):
    w = _ball_on_a_floor()
    w.step(1500)
    w.set_motion(0, kinema.Motion(velocity=(0, 0, 0.5)))
    w.step(100)
    start = w.colliders[0].motion.start
    again = Scene.from_string(w.to_scene().to_toml_string()).build()
    assert again.colliders[0].motion == w.colliders[0].motion
    w.save_checkpoint(tmp_path / "w.ckpt")
    back = kinema.World.load_checkpoint(tmp_path / "w.ckpt")
    assert back.colliders[0].motion.start == start
    traj = w.run(0.1, fps=100)
    back.run(0.1, fps=100)
    assert np.array_equal(w.positions, back.positions) and np.array_equal(w.velocities, back.velocities)
    path = traj.save(tmp_path / "late.h5")
    assert kinema.load_trajectory(path).colliders[0]["motion"]["start"] == start


@pytest.mark.parametrize("start", [math.nan, math.inf, "soon"])
def test_a_bad_start_is_refused_by_name(start):
    with pytest.raises((ValueError, TypeError), match="start"):
        kinema.Motion(velocity=(0, 0, 1), start=start)


@settings(max_examples=60, deadline=None)
@given(
    start=st.floats(-2.0, 5.0),
    velocity=st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3)),
    omega=st.tuples(st.floats(-4, 4), st.floats(-4, 4), st.floats(-4, 4)),
    pivot=st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)),
    times=st.lists(st.floats(-3.0, 8.0), min_size=1, max_size=6),
)
def test_a_steady_motion_is_its_closed_form_from_its_start(start, velocity, omega, pivot, times):
    # x(t) = R(ω (t − t_s)) (x₀ − c) + c + V (t − t_s) from t_s on, the placement before it
    from scipy.spatial.transform import Rotation

    motion = kinema.Motion(velocity=velocity, angular_velocity=omega, pivot=pivot, start=start)
    poses = _core.collider_poses(times, **motion._binding())
    c = np.array(pivot)
    for t, pose in zip(times, poses, strict=True):
        tau = max(t - start, 0.0)
        turn = Rotation.from_rotvec(tau * np.array(omega)).as_matrix()
        assert np.allclose(pose[:, :3], turn, atol=1e-12)
        assert np.allclose(pose[:, 3], c - turn @ c + tau * np.array(velocity), atol=1e-12)
