"""kinema.render: frames, colours, time stamps, MP4 and GIF files."""

from __future__ import annotations

from pathlib import Path

import imageio_ffmpeg
import numpy as np
import pytest
from PIL import Image

import kinema
from kinema import _core
from kinema.render import Camera2D, Camera3D, low_end, render_frames, write_video


def _scene(frames=3, n=5):
    """n particles on the x axis; particle k moves along y at speed k (the last is fastest)."""
    t = np.linspace(0.0, 1.0, frames)
    x = np.zeros((frames, n, 3))
    x[:, :, 0] = np.arange(n)
    x[:, :, 1] = t[:, None] * np.arange(n)[None, :]
    return x, t


def test_frames_have_the_requested_shape_and_dtype():
    x, t = _scene()
    for dim in (2, 3):
        frames = list(render_frames(x, 0.3, t, dim=dim, width=160, height=90))
        assert len(frames) == 3
        for f in frames:
            assert f.shape == (90, 160, 3) and f.dtype == np.uint8
            assert (f != 255).any()


def test_colour_by_speed_puts_the_fastest_particle_at_the_top_colour():
    x, t = _scene(frames=2, n=3)
    v = np.zeros_like(x)
    v[:, :, 1] = [0.0, 1.0, 5.0]
    cam = Camera2D(-1.0, -2.0, 3.0, 2.0)  # 4 m × 4 m onto 100 × 100: 25 px per m
    frame = next(render_frames(x[:, :, :2], 0.4, t, dim=2, velocities=v[:, :, :2], width=100, height=100, camera=cam, time_format=None))
    top = _core.colormap(np.array([1.0]), "viridis", 0.0, 1.0)[0]
    bottom = _core.colormap(np.array([low_end("viridis")]), "viridis", 0.0, 1.0)[0]  # the lifted low end

    def at(xw, yw):  # world → pixel: column 25·(x + 1), row 25·(2 − y)
        return frame[int(25 * (2 - yw)), int(25 * (xw + 1))]

    assert (at(2.0, 0.0) == top).all()  # particle 2, speed 5, the maximum
    assert (at(0.0, 0.0) == bottom).all()  # particle 0 at rest, the minimum


def test_colour_by_id_and_by_field_and_fixed_colours():
    x, t = _scene(frames=1, n=4)
    kw = dict(dim=2, width=80, height=40, time_format=None)
    by_id = next(render_frames(x, 0.3, t, color_by="id", **kw))
    by_field = next(render_frames(x, 0.3, t, color_by=np.array([0.0, 1.0, 2.0, 3.0]), **kw))
    red = np.tile(np.array([255, 0, 0], np.uint8), (4, 1))
    fixed = next(render_frames(x, 0.3, t, color_by=red, **kw))
    assert not np.array_equal(by_id, by_field)
    colours = {tuple(c) for c in fixed.reshape(-1, 3)}
    assert (255, 0, 0) in colours and (0, 255, 0) not in colours


def test_time_stamp_changes_pixels_between_frames():
    x = np.zeros((2, 1, 3))
    frames = list(render_frames(x, 0.1, [0.0, 1.5], dim=3, width=200, height=100, color_by="id"))
    diff = np.any(frames[0] != frames[1], axis=2)
    assert diff.any()
    rows, cols = np.nonzero(diff)
    # Only the stamp differs, in a corner on the left (the one with fewer of the sphere's pixels
    # under it: test_the_time_stamp_goes_to_a_corner_free_of_particles).
    assert rows.max() - rows.min() < 16 and (rows.max() < 30 or rows.min() > 70) and cols.max() < 150


def test_3d_camera_framing_and_depth_order():
    # Two spheres on the view axis: the nearer (green) hides the farther (red) at the centre.
    x = np.array([[[0.0, 0.0, 0.0], [0.0, -3.0, 0.0]]])
    cam = Camera3D(eye=(0.0, -10.0, 0.0), target=(0.0, 0.0, 0.0))
    colours = np.array([[255, 0, 0], [0, 255, 0]], np.uint8)
    f = next(render_frames(x, [1.0, 0.5], [0.0], camera=cam, color_by=colours, width=100, height=100, time_format=None))
    c = f[50, 50].astype(int)
    assert c[1] > c[0] + 100
    framed = Camera3D.framing((0, 0, 0), (1, 1, 1))
    assert np.linalg.norm(np.subtract(framed.eye, framed.target)) > 1.0


def test_mp4_and_gif_are_written_and_read_back(tmp_path):
    x, t = _scene(frames=6, n=20)
    frames = list(render_frames(x, 0.2, t, dim=2, width=96, height=64))
    mp4 = write_video(iter(frames), tmp_path / "a.mp4", fps=12)
    reader = imageio_ffmpeg.read_frames(str(mp4))
    meta = next(reader)
    assert tuple(meta["size"]) == (96, 64)
    assert sum(1 for _ in reader) == 6
    gif = write_video(frames, tmp_path / "a.gif", fps=12)
    with Image.open(gif) as im:
        assert im.size == (96, 64) and im.n_frames == 6
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.gif", "a.mp4"]


def test_odd_sizes_are_padded_for_h264(tmp_path):
    frames = [np.full((33, 47, 3), k * 40, np.uint8) for k in range(3)]
    reader = imageio_ffmpeg.read_frames(str(write_video(frames, tmp_path / "odd.mp4", fps=5)))
    assert tuple(next(reader)["size"]) == (48, 34)


def test_bad_path_is_a_clear_error_and_leaves_nothing_behind(tmp_path):
    frames = [np.zeros((16, 16, 3), np.uint8)]
    with pytest.raises(ValueError, match=r"path.*\.mp4, \.gif"):
        write_video(frames, tmp_path / "a.avi")
    with pytest.raises(FileNotFoundError, match="path"):
        write_video(frames, tmp_path / "missing" / "a.mp4")

    def failing():
        yield np.zeros((16, 16, 3), np.uint8)
        raise RuntimeError("simulation failed mid-way")

    for ext in (".mp4", ".gif"):
        with pytest.raises(RuntimeError, match="mid-way"):
            write_video(failing(), tmp_path / f"b{ext}")
    with pytest.raises(ValueError, match="frames"):
        write_video([np.zeros((16, 16, 3), np.uint8), np.zeros((8, 8, 3), np.uint8)], tmp_path / "c.mp4")
    with pytest.raises(ValueError, match="fps"):
        write_video(frames, tmp_path / "d.gif", fps=0)
    assert list(tmp_path.iterdir()) == []


def test_bad_render_input_names_the_parameter():
    x, t = _scene()
    with pytest.raises(ValueError, match="positions"):
        next(render_frames(x[:, :, :1], 0.1, t))
    with pytest.raises(ValueError, match="color_by"):
        next(render_frames(x, 0.1, t, color_by="mass"))
    with pytest.raises(ValueError, match="colormap"):
        next(render_frames(x, 0.1, t, colormap="jet"))
    with pytest.raises(ValueError, match="radius"):
        next(render_frames(x, -1.0, t))
    with pytest.raises(ValueError, match="fov_y_deg"):
        next(render_frames(x, 0.1, t, camera=Camera3D((0, -5, 0), (0, 0, 0), fov_deg=190)))
    with pytest.raises(ValueError, match="width"):
        next(render_frames(x, 0.1, t, width=0))
    with pytest.raises(ValueError, match="text"):
        next(render_frames(x, 0.1, t, time_format="time {:.2f}"))
    with pytest.raises(ValueError, match="positions\\[0\\]"):
        _core.render_frame(np.full((1, 3), np.nan), np.ones(1), view=(0, 0, 1, 1))


def test_a_trajectory_renders_itself(tmp_path):
    # Trajectory.render: one video frame per recorded frame, at the recording's frame rate.
    w = kinema.World(dt=1e-3)
    w.add_particles([[0, 0, 1.0], [0.5, 0, 1.0]], radius=0.1)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1], restitution=0.8))
    traj = w.run(0.5, fps=20)
    path = traj.render(tmp_path / "bounce.mp4", width=160, height=96)
    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    frames = list(reader)
    assert len(frames) == traj.t.size and meta["size"] == (160, 96)
    assert meta["fps"] == pytest.approx(20.0)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bounce.mp4"]


# -- colliders --------------------------------------------------------------------------------


def test_a_floor_changes_the_ground_and_not_the_sky():
    # Two particles above the floor z = 0, seen from the side and above: with the Plane the
    # lower part of the image becomes a neutral floor, the top rows (sky) stay background.
    x = np.array([[[-0.5, 0.0, 0.5], [0.5, 0.0, 0.8]]])
    cam = Camera3D(eye=(0.0, -4.0, 1.0), target=(0.0, 0.0, 0.5))
    kw = dict(camera=cam, color_by="id", width=160, height=120, time_format=None)
    bare = next(render_frames(x, 0.1, [0.0], **kw))
    floor = next(render_frames(x, 0.1, [0.0], colliders=[kinema.Plane([0, 0, 0], [0, 0, 1])], **kw))
    changed = np.any(bare != floor, axis=2)
    assert changed[-20:].all(), "the bottom rows are floor"
    assert not changed[:20].any(), "the sky is untouched"
    ground = floor[-20:].astype(int)
    assert (ground.max(axis=2) - ground.min(axis=2)).max() <= 8 and ground.max() < 250, "a light neutral grey"
    # The particles are still drawn over it.
    assert (floor[~changed] == bare[~changed]).all()


def test_a_box_outline_lights_its_edges_in_2d_and_a_description_draws_the_same():
    # [0, 4] × [0, 2] onto 200 × 100: 50 px per m. The box [1, 3] × [0.5, 1.5] has its left
    # side on pixel column 50 and its top on row 25; its interior is empty.
    x = np.array([[[0.2, 0.2]]])
    cam = Camera2D(0.0, 0.0, 4.0, 2.0)
    kw = dict(dim=2, camera=cam, width=200, height=100, time_format=None, color_by="id")
    bare = next(render_frames(x, 0.05, [0.0], **kw))
    boxed = next(render_frames(x, 0.05, [0.0], colliders=[kinema.Box([1, 0.5], [3, 1.5])], **kw))
    changed = np.any(bare != boxed, axis=2)
    assert changed[50, 49] and changed[50, 50] and changed[25, 100] and changed[75, 150]
    assert not changed[35:65, 60:140].any(), "the interior is untouched"
    assert not changed[:20].any() and not changed[:, :40].any(), "outside the box is untouched"
    described = next(render_frames(x, 0.05, [0.0], colliders=[{"type": "box", "lo": [1, 0.5], "hi": [3, 1.5]}], **kw))
    assert np.array_equal(boxed, described)


def test_a_sphere_obstacle_hides_what_is_behind_it():
    x = np.array([[[0.0, 2.0, 0.0], [1.5, 2.0, 0.0]]])  # behind the obstacle, and beside it
    cam = Camera3D(eye=(0.0, -8.0, 0.0), target=(0.0, 0.0, 0.0))
    red = np.array([[255, 0, 0], [255, 0, 0]], np.uint8)
    kw = dict(camera=cam, color_by=red, width=120, height=120, time_format=None)
    bare = next(render_frames(x, 0.3, [0.0], **kw))
    hidden = next(render_frames(x, 0.3, [0.0], colliders=[kinema.SphereObstacle([0, 0, 0], 1.0)], **kw))
    c = bare[60, 60].astype(int)
    assert c[0] > c[1] + 50, "the particle alone is red at the centre"
    c = hidden[60, 60].astype(int)
    assert abs(c[0] - c[1]) < 15, f"the obstacle hides it: {c}"
    assert (hidden[60, 90:110] == bare[60, 90:110]).all(), "the one beside it is not hidden"


def test_the_default_camera_frames_the_colliders_and_open_boxes_work():
    # A 2D box much larger than the particles: the default camera shows all four sides.
    x = np.array([[[0.5, 0.5]]])
    f = next(render_frames(x, 0.05, [0.0], dim=2, width=100, height=100, time_format=None, colliders=[kinema.Box([-2, -2], [3, 3])]))
    lit = np.any(f != 255, axis=2)
    assert lit[:, :10].any() and lit[:, -10:].any() and lit[:10].any() and lit[-10:].any()
    # An open 3D box (no lid) and a floor: drawn, no error.
    x3 = np.array([[[0.5, 0.5, 0.2]]])
    cols = [kinema.Box([0, 0, 0], [1, 1, np.inf]), kinema.Plane([0, 0, 0], [0, 0, 1])]
    f = next(render_frames(x3, 0.05, [0.0], width=100, height=80, time_format=None, colliders=cols))
    assert (f != 255).any(axis=2).mean() > 0.3


def test_bad_colliders_name_the_collider():
    x, t = _scene(frames=1)
    with pytest.raises(ValueError, match=r"colliders\[1\]\.radius = -1"):
        next(render_frames(x, 0.1, t, colliders=[kinema.Plane([0, 0, 0], [0, 0, 1]), kinema.SphereObstacle([0, 0, 0], -1.0)]))
    with pytest.raises(ValueError, match=r"colliders\[0\]\.normal.*non-zero"):
        next(render_frames(x, 0.1, t, colliders=[kinema.Plane([0, 0, 0], [0, 0, 0])]))
    with pytest.raises(ValueError, match=r"colliders\[0\] = .*Gravity.*Plane, Box or SphereObstacle"):
        next(render_frames(x, 0.1, t, colliders=[kinema.Gravity()]))
    with pytest.raises(ValueError, match=r"colliders\[0\].*needs center and radius"):
        next(render_frames(x, 0.1, t, colliders=[{"type": "sphere", "center": [0, 0, 0]}]))


def _bottom_brightness(path):
    reader = imageio_ffmpeg.read_frames(str(path))
    meta = next(reader)
    w, h = meta["size"]
    frames = [np.frombuffer(b, np.uint8).reshape(h, w, 3) for b in reader]
    return len(frames), float(np.mean([f[-h // 5 :].mean() for f in frames]))


def test_a_trajectory_renders_its_colliders_unless_told_not_to(tmp_path):
    from kinema.runner import _render_video

    w = kinema.World(dt=1e-3)
    w.add_particles([[0, 0, 1.0], [0.5, 0, 1.0]], radius=0.1)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1], restitution=0.8))
    traj = w.run(0.3, fps=20)
    assert traj.colliders == [{"type": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0], "restitution": 0.8}]
    with_floor = traj.render(tmp_path / "floor.mp4", width=160, height=96)
    without = traj.render(tmp_path / "bare.mp4", width=160, height=96, draw_colliders=False)
    n, floor_light = _bottom_brightness(with_floor)
    m, bare_light = _bottom_brightness(without)
    assert n == m == traj.t.size
    assert floor_light < bare_light - 10, "the floor darkens the bottom of every frame"
    # kinema run / kinema render go through runner._render_video: the same default and switch.
    cli_floor = _render_video(traj, tmp_path / "cli.mp4", {"width": 160, "height": 96}, None, "rendering")
    cli_bare = _render_video(traj, tmp_path / "cli_bare.mp4", {"width": 160, "height": 96, "draw_colliders": False}, None, "rendering")
    assert _bottom_brightness(cli_floor)[1] == pytest.approx(floor_light, abs=1.0)
    assert _bottom_brightness(cli_bare)[1] == pytest.approx(bare_light, abs=1.0)


# -- springs, births and deaths ---------------------------------------------------------------

LINE = tuple(_core.LINE_COLOR)


def _pair_scene():
    # [0, 10] × [0, 5] onto 200 × 100: 20 px per m. Discs of 10 px at x = 2 m and 8 m on the
    # row of pixel centres y = 49.5 (world y = 2.525); a third one at the top right.
    x = np.array([[[2.0, 2.525], [8.0, 2.525], [9.0, 4.5]]] * 3)
    colours = np.array([[255, 0, 0], [0, 200, 0], [0, 0, 255]], np.uint8)
    kw = dict(dim=2, camera=Camera2D(0.0, 0.0, 10.0, 5.0), width=200, height=100, color_by=colours, time_format=None)
    return x, kw


def test_a_spring_is_a_line_between_its_particles_and_none_when_an_end_is_dead():
    x, kw = _pair_scene()
    alive = np.array([[True, True, True], [True, False, True], [False, False, False]])
    frames = list(render_frames(x, 0.5, [0.0, 1.0, 2.0], springs=[[0, 1]], alive=alive, **kw))
    on_line = frames[0][49, 55:145]
    assert (on_line == LINE).all(), "the segment between the rims is the line colour"
    assert (frames[0][49, 45] == (255, 0, 0)).all() and (frames[0][49, 155] == (0, 200, 0)).all(), "the discs stay whole"
    for f in frames[1:]:
        assert not (f == LINE).all(axis=2).any(), "no line with a dead end"
    # Without springs there is no line either; a NaN position is a dead particle too.
    bare = next(render_frames(x, 0.5, [0.0, 1.0, 2.0], **kw))
    assert not (bare == LINE).all(axis=2).any()
    nan = x.copy()
    nan[0, 0] = np.nan
    f = next(render_frames(nan, 0.5, [0.0, 1.0, 2.0], springs=[[0, 1]], **kw))
    assert not (f == LINE).all(axis=2).any() and not (f == (255, 0, 0)).all(axis=2).any()
    with pytest.raises(ValueError, match=r"springs\[1\] = \[1, 3\]"):
        next(render_frames(x, 0.5, [0.0, 1.0, 2.0], springs=[[0, 1], [1, 3]], **kw))


def test_particles_not_alive_leave_no_pixels_and_an_all_dead_frame_is_background():
    x, kw = _pair_scene()
    alive = np.array([[True, True, True], [True, False, True], [False, False, False]])
    frames = list(render_frames(x, 0.5, [0.0, 1.0, 2.0], alive=alive, **kw))
    has = [{c: bool((f == c).all(axis=2).any()) for c in [(255, 0, 0), (0, 200, 0), (0, 0, 255)]} for f in frames]
    assert has[0] == {(255, 0, 0): True, (0, 200, 0): True, (0, 0, 255): True}
    assert has[1] == {(255, 0, 0): True, (0, 200, 0): False, (0, 0, 255): True}
    assert (frames[2] == 255).all(), "nothing alive: the background alone"
    # Coloured by speed with the default camera and a legend: the dead do not crash the
    # colour range or the camera, in 2D and 3D.
    x3 = np.concatenate([x, np.zeros((3, 3, 1))], axis=2)
    for dim in (2, 3):
        out = list(render_frames(x3, 0.5, [0.0, 1.0, 2.0], dim=dim, alive=alive, width=320, height=240))
        assert len(out) == 3 and all(f.shape == (240, 320, 3) for f in out)
    nothing = list(render_frames(np.full((2, 3, 3), np.nan), 0.5, [0.0, 1.0], width=320, height=240))
    assert len(nothing) == 2


def test_a_trajectory_maps_its_spring_ids_to_columns_and_renders_its_births(tmp_path):
    import dataclasses

    from kinema.render import _trajectory_options

    w = kinema.World(dt=1e-3, dim=2)
    w.add_particles([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]], radius=0.1)
    traj = w.run(0.05, fps=100)
    alive = np.ones(traj.alive.shape, bool)
    alive[:2, 2] = False  # the third is born at frame 2
    pos = traj.positions.copy()
    pos[~alive] = np.nan
    traj = dataclasses.replace(traj, positions=pos, ids=np.array([10, 11, 12]), alive=alive, springs=np.array([[12, 10], [11, 99]]))
    options = _trajectory_options(traj)
    assert options["springs"].tolist() == [[2, 0]], "id 99 is not in the trajectory: left out"
    assert options["alive"] is traj.alive
    path = traj.render(tmp_path / "born.gif", width=160, height=120, color_by="id")
    with Image.open(path) as im:
        assert im.n_frames >= 3


# -- the legend -------------------------------------------------------------------------------


def test_the_legend_is_a_colour_bar_in_the_top_right_corner():
    # Particles in the lower left; the legend goes into the top right corner, on the row of the
    # time stamp (none here).
    x = np.zeros((2, 3, 3))
    x[:, :, 0] = [0.0, 0.5, 1.0]
    x[1, :, 1] = [0.0, 1.0, 2.0]  # moving: speeds 0, 1, 2
    cam = Camera2D(0.0, 0.0, 4.0, 3.0)
    kw = dict(dim=2, camera=cam, width=320, height=240, time_format=None)
    top, bottom = (tuple(c) for c in _core.colormap(np.array([1.0, low_end("magma")]), "magma", 0.0, 1.0))
    corner = (slice(0, 60), slice(100, 320))

    def colours(frame):
        return {tuple(c) for c in frame[corner].reshape(-1, 3)}

    kw.update(vmin=-1.0, vmax=3.0)  # no particle takes an end colour of the colormap
    with_legend = next(render_frames(x, 0.1, [0.0, 1.0], colormap="magma", **kw))
    assert {top, bottom} <= colours(with_legend), "the bar's ends are the particles' end colours"
    bar = np.nonzero((with_legend == top).all(axis=2))
    assert bar[0].size and bar[0].max() < 60 and bar[1].min() >= 100, "in the top right corner"
    low = np.nonzero((with_legend == bottom).all(axis=2))
    assert low[1].max() < bar[1].min(), "the bottom colour on the left, the top colour on the right"
    assert np.any(with_legend[corner] < 100), "with dark text"
    without = next(render_frames(x, 0.1, [0.0, 1.0], colormap="magma", legend=False, **kw))
    assert colours(without) == {(255, 255, 255)}
    assert (with_legend[:, :100] == without[:, :100]).all() and (with_legend[60:] == without[60:]).all(), "only its corner"
    # Fixed colours and ids have no legend; a label names the quantity.
    by_id = next(render_frames(x, 0.1, [0.0, 1.0], color_by="id", **kw))
    assert colours(by_id) == {(255, 255, 255)}
    labelled = next(render_frames(x, 0.1, [0.0, 1.0], colormap="magma", color_by=np.arange(3.0), legend="temperature (K)", **kw))
    assert {top, bottom} <= colours(labelled) and not np.array_equal(labelled[corner], with_legend[corner])


# -- the default camera -----------------------------------------------------------------------


def _recorded_cameras(monkeypatch):
    """The camera keywords of every frame render_frames draws."""
    calls = []
    real = _core.render_frame

    def spy(*args, **kwargs):
        calls.append({k: kwargs[k] for k in ("eye", "target", "up", "fov_deg", "view") if k in kwargs})
        return real(*args, **kwargs)

    monkeypatch.setattr(_core, "render_frame", spy)
    return calls


def _pixels(cam, points, w, h):
    """Pinhole projection (camera.rs) of (P, 3) points: (P, 2) pixels."""
    eye, target, up = (np.asarray(cam[k], float) for k in ("eye", "target", "up"))
    fwd = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(fwd, up)
    right /= np.linalg.norm(right)
    upv = np.cross(right, fwd)
    f = 0.5 * h / np.tan(np.radians(cam["fov_deg"]) / 2)
    d = np.asarray(points, float) - eye
    z = d @ fwd
    return np.stack([0.5 * w + f * (d @ right) / z, 0.5 * h - f * (d @ upv) / z], axis=1)


def _box_corners(lo, hi):
    return np.array([[(hi if c >> k & 1 else lo)[k] for k in range(3)] for c in range(8)], float)


@pytest.mark.parametrize("legend", [True, False])
def test_the_default_camera_shows_the_demo_balls_and_floor_large(monkeypatch, legend):
    # `kinema demo`'s scene with its own [render] camera (none: the default), at 16:9: its
    # first 0.1 s, the balls still in their column, framed with the box's floor (its walls
    # bound them), not the box's empty top at 3 m (issue 28: a narrow column in wide bands).
    from kinema.runner import _camera

    world = kinema.load_scene(Path(kinema.__file__).parent / "scenes" / "demo.toml")
    traj = world.run(0.1, fps=30)
    box = traj.colliders[0]
    w, h = 480, 270
    calls = _recorded_cameras(monkeypatch)
    camera = _camera(world.scene.render.camera)
    kw = dict(colliders=traj.colliders, width=w, height=h, time_format=None, legend=legend, camera=camera)
    frame = next(render_frames(traj.positions, traj.radii, traj.t, **kw))
    r = traj.radii.max()
    top = traj.positions[..., 2].max() + r
    assert top < box["hi"][2]
    px = _pixels(calls[0], np.concatenate([_box_corners(box["lo"], [*box["hi"][:2], top]), traj.positions.reshape(-1, 3)]), w, h)
    assert (px >= 0).all() and (px[:, 0] <= w).all() and (px[:, 1] <= h).all(), "the floor and every particle in the frame"
    span = px.max(axis=0) - px.min(axis=0)
    assert span[0] >= 0.6 * w or span[1] >= 0.6 * h, f"the scene fills the frame: {span} of {w} × {h}"
    # Nothing but the walls above the balls touches the frame's edges: no ball is cropped.
    edges = np.concatenate([frame[-1], frame[:, 0], frame[:, -1]])
    assert (edges == 255).all()


@pytest.mark.parametrize("dim", [2, 3])
def test_the_default_camera_fits_a_tall_scene_into_a_wide_frame(monkeypatch, dim):
    # A column of particles 2 m tall in a 0.2 m box (its top open: drawn up to the particles).
    z = np.linspace(0.1, 2.0, 20)
    x = np.zeros((1, 20, 3))
    x[0, :, 0], x[0, :, 1 if dim == 2 else 2] = 0.1, z
    hi = [0.2, np.inf] if dim == 2 else [0.2, 0.2, np.inf]
    lo = [0.0, 0.0] if dim == 2 else [0.0, 0.0, 0.0]
    w, h = 400, 225
    calls = _recorded_cameras(monkeypatch)
    frame = next(render_frames(x, 0.05, [0.0], dim=dim, colliders=[kinema.Box(lo, hi)], width=w, height=h, time_format=None))
    lit = np.nonzero(np.any(frame != 255, axis=2))
    assert (lit[0].min() > 0 and lit[0].max() < h - 1) and (lit[1].min() > 0 and lit[1].max() < w - 1), "nothing cropped"
    assert lit[0].max() - lit[0].min() >= 0.6 * h, "the column spans most of the height"
    if dim == 3:
        px = _pixels(calls[0], np.concatenate([_box_corners([0, 0, 0], [0.2, 0.2, 2.05]), x[0]]), w, h)
        assert (px >= 0).all() and (px[:, 0] <= w).all() and (px[:, 1] <= h).all()
        assert px[:, 1].max() - px[:, 1].min() >= 0.6 * h
    else:
        xmin, ymin, xmax, ymax = calls[0]["view"]
        assert (ymax - ymin) <= (2.05 + 0.05) / 0.6, "the 2D view is not much taller than the column"


# -- the pictures: slow particles visible, the stamp clear of them, trails and attractors ------


def _luma(c):
    return 0.299 * c[0] + 0.587 * c[1] + 0.114 * c[2]


def test_slow_particles_are_not_near_black_and_the_legend_agrees():
    # Speeds 0 and 2: the one at rest gets the colormap at low_end, not its near-black bottom,
    # and the colour bar's left end is that colour too.
    x = np.zeros((2, 2, 3))
    x[:, 1, 0] = 2.0
    x[1, 1, 1] = 2.0
    cam = Camera2D(-1.0, -1.0, 3.0, 3.0)
    frame = list(render_frames(x[:, :, :2], 0.3, [0.0, 1.0], dim=2, camera=cam, width=240, height=240, time_format=None, trail=0))[0]
    rest = frame[int(240 * (3.0 - 0.0) / 4.0), int(240 * (0.0 + 1.0) / 4.0)]
    assert _luma(rest) >= 80 > _luma(_core.colormap(np.array([0.0]), "viridis", 0.0, 1.0)[0])
    assert (rest == _core.colormap(np.array([0.25]), "viridis", 0.0, 1.0)[0]).all() and low_end("viridis") == 0.25
    bar = np.nonzero((frame[:60] == rest).all(axis=2))
    assert bar[0].size, "the colour bar starts at the colour of the slowest particle"
    assert _luma(_core.colormap(np.array([low_end("magma")]), "magma", 0.0, 1.0)[0]) >= 80


def _stamp_pixels(frames):
    """Where two frames that differ only in their time stamp differ."""
    return np.nonzero(np.any(frames[0] != frames[1], axis=2))


def test_the_time_stamp_goes_to_a_corner_free_of_particles():
    # A still crowd of particles fills the top left corner: the stamp goes to the bottom left.
    g = np.stack(np.meshgrid(np.linspace(0.0, 1.0, 6), np.linspace(2.0, 3.0, 6)), axis=-1).reshape(-1, 2)
    x = np.repeat(g[None], 2, axis=0)
    cam = Camera2D(0.0, 0.0, 4.0, 3.0)
    kw = dict(dim=2, camera=cam, width=320, height=240, color_by="id", trail=0)
    rows, cols = _stamp_pixels(list(render_frames(x, 0.1, [0.0, 1.5], **kw)))
    assert rows.size and rows.min() > 180 and cols.max() < 120, "bottom left"
    # The crowd in the bottom left too: the top right (no colour bar with ids).
    y = np.concatenate([x, x - [0.0, 2.0]], axis=1)
    rows, cols = _stamp_pixels(list(render_frames(y, 0.1, [0.0, 1.5], **kw)))
    assert rows.size and rows.max() < 40 and cols.min() > 200, "top right"
    # Nothing in the top left: it stays there, as always.
    rows, cols = _stamp_pixels(list(render_frames(x + [2.5, -2.0], 0.1, [0.0, 1.5], **kw)))
    assert rows.max() < 30 and cols.max() < 150


def test_a_kepler_orbit_draws_its_trail_on_the_circle_and_its_attractor():
    # kepler_rk4: r = 1, v = 1 about an attractor at the origin (mu = 1): x(t) = (cos t, sin t).
    from kinema.runner import _attractors

    world = kinema.load_scene(Path(__file__).resolve().parent.parent / "examples" / "scenes" / "kepler_rk4.toml")
    traj = world.run(3.0, fps=20.0)
    assert _attractors(world) == [[0.0, 0.0, 0.0]]
    cam = Camera2D(-2.0, -2.0, 2.0, 2.0)  # 360 × 360: 90 px per m, the origin at (180, 180)
    frames = list(
        render_frames(
            traj.positions, traj.radii, traj.t, dim=2, camera=cam, width=360, height=360, attractors=_attractors(world), time_format=None, legend=False
        )
    )
    last = frames[-1]

    def px(p):
        return last[int(180 - 90 * p[1]), int(180 + 90 * p[0])]

    assert (px((0.0, 0.0)) == list(_core.MARKER_COLOR)).all(), "the attractor at the origin"
    t_end = traj.t[-1]
    # The default trail is a third of the run (1 s): the circle is drawn from t_end − 0.9 s on,
    # and not where the planet was 2 s before the end.
    for t in np.linspace(t_end - 0.9, t_end - 0.1, 9):
        assert (px((np.cos(t), np.sin(t))) != 255).any(), f"the trail at t = {t:.2f} s"
    assert (px((np.cos(t_end - 2.0), np.sin(t_end - 2.0))) == 255).all()
    assert (px((0.0, -1.0)) == 255).all() and (px((0.5, 0.5)) == 255).all(), "nothing off the path"
    # No trail without one, and many particles have none by default.
    bare = list(render_frames(traj.positions, traj.radii, traj.t, dim=2, camera=cam, width=360, height=360, time_format=None, legend=False, trail=0))[-1]
    t = t_end - 0.5
    assert (bare[int(180 - 90 * np.sin(t)), int(180 + 90 * np.cos(t))] == 255).all()


# -- moving colliders -------------------------------------------------------------------------


def _grey_centre(frame):
    """(x, y) pixel coordinates of the middle of the box around the neutral grey pixels (a
    sphere obstacle, its shading aside; pixel (i, j) spans x from i to i + 1), and their count."""
    g = frame.astype(int)
    grey = (np.abs(g[..., 0] - g[..., 1]) < 12) & (np.abs(g[..., 1] - g[..., 2]) < 12) & (g[..., 0] < 250)
    rows, cols = np.nonzero(grey)
    return np.array([cols.min() + cols.max() + 1, rows.min() + rows.max() + 1]) / 2, grey.sum()


MOVING_SPHERE = {"type": "sphere", "center": [0.0, 0.0, 0.5], "radius": 0.2, "motion": {"velocity": [1.0, 0.0, 0.0]}}


def test_a_moving_collider_is_drawn_where_it_is_at_each_frame_time():
    # Seen from straight above, 4.5 m over the sphere's plane: 1 m along x is f/4.5 pixels
    # (f = 120 / tan 20°, the focal length of 240 rows at 40°); a red particle stays put, out
    # of sight.
    t = np.array([0.0, 0.5, 1.0])
    x = np.tile([[0.5, 50.0, 0.1]], (3, 1, 1))
    cam = Camera3D(eye=(0.5, 0.0, 5.0), target=(0.5, 0.0, 0.5), up=(0.0, 1.0, 0.0), fov_deg=40.0)
    red = np.array([[220, 40, 40]], np.uint8)
    kw = dict(color_by=red, width=320, height=240, camera=cam, time_format=None)
    frames = list(render_frames(x, 0.1, t, colliders=[MOVING_SPHERE], **kw))
    (c0, n0), (c1, n1), (c2, n2) = (_grey_centre(f) for f in frames)
    px_per_m = 120.0 / np.tan(np.radians(20.0)) / 4.5
    assert n0 > 500 and abs(n1 - n0) < 0.02 * n0 and abs(n2 - n0) < 0.02 * n0  # the same sphere, seen from above
    np.testing.assert_allclose(c2 - c0, [px_per_m, 0.0], atol=1.0)  # 1 m further along x at t = 1 s
    np.testing.assert_allclose(c1 - c0, [px_per_m / 2, 0.0], atol=1.0)
    np.testing.assert_allclose(c0, [160 - 0.5 * px_per_m, 120.0], atol=1.0)  # at its centre at t = 0
    # Frame k is the still sphere placed where collider_poses puts it at t[k], byte for byte.
    for k in range(3):
        here = {"type": "sphere", "center": [t[k], 0.0, 0.5], "radius": 0.2}
        still = next(render_frames(x[k : k + 1], 0.1, t[k : k + 1], colliders=[here], **kw))
        assert np.array_equal(frames[k], still)


def test_still_scenes_draw_the_same_with_or_without_a_motion_key_and_a_world_run_moves_its_mesh():
    # A still collider (no motion) takes the one-scenery path; a motion of zero velocity the
    # per-frame path: the same pictures.
    x, t = _scene(frames=3, n=2)
    floor = {"type": "plane", "point": [0.0, 0.0, -0.5], "normal": [0.0, 0.0, 1.0]}
    ball = {"type": "sphere", "center": [1.0, 1.0, 0.0], "radius": 0.3}
    still = list(render_frames(x, 0.2, t, colliders=[floor, ball], width=160, height=96))
    resting = list(render_frames(x, 0.2, t, colliders=[floor, {**ball, "motion": {"velocity": [0.0, 0.0, 0.0]}}], width=160, height=96))
    assert all(np.array_equal(a, b) for a, b in zip(still, resting, strict=True))

    # A world's mesh lifted by keyframes: its trajectory's frames show it rising, and the same
    # frame drawn from the mesh placed by collider_poses is the same picture.
    from kinema.render.descriptions import collider_poses

    w = kinema.World(dt=1e-3)
    w.add_particles([[3.0, 3.0, 0.5]], radius=0.1)
    square = dict(vertices=[[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], faces=[[0, 1, 2], [0, 2, 3]])
    w.add(kinema.Mesh(**square, motion=kinema.Keyframes(times=[0.0, 0.2], translations=[[0, 0, 0], [0, 0, 1.0]])))
    traj = w.run(0.2, fps=10)
    assert traj.colliders[0]["motion"]["times"] == [0.0, 0.2]
    cam = Camera3D(eye=(0.0, -6.0, 1.0), target=(0.0, 0.0, 0.5))
    kw = dict(width=160, height=96, camera=cam, time_format=None)
    frames = list(render_frames(traj.positions, 0.1, traj.t, colliders=traj.colliders, **kw))
    assert not np.array_equal(frames[0], frames[-1])
    pose = collider_poses(traj.colliders[0], traj.t)[-1]
    placed = {**{k: v for k, v in traj.colliders[0].items() if k != "motion"}}
    placed["vertices"] = (np.asarray(placed["vertices"]) @ pose[:, :3].T + pose[:, 3]).tolist()
    last = next(render_frames(traj.positions[-1:], 0.1, traj.t[-1:], colliders=[placed], **kw))
    assert np.abs(frames[-1].astype(int) - last).max() <= 2  # the same but for rounding at edges


def test_a_colour_bar_end_within_rounding_of_zero_prints_0():
    # The pile video's bar started at "7.31e-17": the rounding of a speed that is 0, beside a
    # top speed of 2 m/s. Within 1e-12 of the larger end it prints as 0; a small value of its
    # own scale prints as it is.
    from kinema.render.legend import bar_labels

    assert bar_labels(7.31e-17, 2.0) == ("0", "2")
    assert bar_labels(-3e-16, 0.5) == ("0", "0.5")
    assert bar_labels(1e-3, 2.0) == ("0.001", "2")
    assert bar_labels(1e-17, 2e-17) == ("1e-17", "2e-17")
    assert bar_labels(0.0, 0.0) == ("0", "0")
    x = np.zeros((1, 2, 2))
    x[0, 1, 0] = 2.0
    cam = Camera2D(-1.0, -1.0, 3.0, 3.0)

    def frame(vmin):
        kw = dict(dim=2, camera=cam, width=240, height=240, time_format=None, trail=0, color_by=np.array([0.0, 2.0]), vmax=2.0)
        return next(render_frames(x, 0.3, [0.0], vmin=vmin, **kw))

    assert np.array_equal(frame(7.31e-17), frame(0.0))
    assert not np.array_equal(frame(1e-3), frame(0.0))
