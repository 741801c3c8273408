"""kinema's USD imported into Blender itself (bpy 5.0, Blender as a Python module), as a user
would: File → Import → USD, then play. Every frame of the timeline holds that frame's live
particles (count, positions, ids, colours), the springs are curves between their ends, the
colliders are rendered meshes, and the timeline spans the frames. And the .blend that
`export(format="blend")` builds through Blender, opened and rendered (Cycles and Eevee): the
rate asked, the balls in their colours, the floor, a moving collider where it moves.

bpy 5.0.1 needs numpy < 2, which kinema's venv does not have, so Blender runs in a venv of its
own (.venv-blender, made by `make test` from requirements/blender-test.txt) as a separate
process, once for all the stages of this module; the tests skip where it is not installed."""

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

import kinema

pytest.importorskip("pxr")
from test_usd import _run, cloth, expected_colours, fountain, spring_ends  # noqa: E402

BLENDER_PYTHON = Path(__file__).resolve().parent.parent / ".venv-blender" / "bin" / "python"

# Runs in Blender's Python: for each job {usd, out, import (the operator's options), fps (the
# scene's rate set after the import, as docs/files.md tells a user to), frames (read them)}
# imports the stage into an empty scene and writes what Blender holds at every frame of the
# timeline: each mesh, point cloud and curves object's evaluated attributes, to out (.npz).
BLENDER_SIDE = r"""
import json, sys
import bpy, numpy as np

WIDTH = {"FLOAT_VECTOR": 3, "FLOAT_COLOR": 4, "FLOAT": 1, "INT": 1}
FIELD = {"FLOAT_VECTOR": "vector", "FLOAT_COLOR": "color", "FLOAT": "value", "INT": "value"}
for job in json.load(open(sys.argv[1])):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    result = bpy.ops.wm.usd_import(filepath=job["usd"], **job["import"])
    scene = bpy.context.scene
    meta = {"result": sorted(result), "frame_start": scene.frame_start, "frame_end": scene.frame_end,
            "fps": scene.render.fps, "fps_base": scene.render.fps_base, "objects": {}}
    if job.get("fps"):
        scene.render.fps, scene.render.fps_base = job["fps"]
    arrays = {}
    frames = range(0, scene.frame_end + 1) if job["frames"] else [scene.frame_start]  # from frame 0, before the timeline where it starts later
    for k in frames:
        scene.frame_set(k)
        graph = bpy.context.evaluated_depsgraph_get()
        for ob in scene.objects:
            info = meta["objects"].setdefault(ob.name, {"type": ob.type, "attributes": {}})
            if ob.type not in ("POINTCLOUD", "CURVES", "MESH"):
                continue
            data = ob.evaluated_get(graph).data
            arrays[f"{ob.name}|count|{k}"] = np.array(len(data.vertices if ob.type == "MESH" else data.points))
            for a in data.attributes:
                info["attributes"].setdefault(a.name, [a.data_type, a.domain])
                if a.name.startswith(".") or a.data_type not in WIDTH:
                    continue
                n = len(a.data)
                buf = np.empty(n * WIDTH[a.data_type], dtype=np.int32 if a.data_type == "INT" else np.float32)
                if n:
                    a.data.foreach_get(FIELD[a.data_type], buf)
                arrays[f"{ob.name}|{a.name}|{k}"] = buf.reshape(n, WIDTH[a.data_type]) if WIDTH[a.data_type] > 1 else buf
            if ob.type == "CURVES":
                arrays[f"{ob.name}|sizes|{k}"] = np.array([c.points_length for c in data.curves], dtype=np.int32)
            if ob.type == "MESH":
                arrays[f"{ob.name}|faces|{k}"] = np.array([len(p.vertices) for p in data.polygons], dtype=np.int32)
    np.savez(job["out"], meta=json.dumps(meta), **arrays)
"""


#: The attributes that are vectors in Blender, and their lengths.
VECTORS = {"position": 3, "velocity": 3, "displayColor": 4}


class Imported:
    """What Blender holds after importing one stage: ``meta`` (frame range, rate, objects
    and their attributes' types) and ``get(object, attribute, frame)``."""

    def __init__(self, traj, out):
        self.traj = traj
        with np.load(out) as d:
            self.meta = json.loads(str(d["meta"]))
            self.arrays = {k: d[k] for k in d.files if k != "meta"}

    def get(self, name, attribute, frame):
        """The attribute's values at ``frame``; an object with no points has no attributes
        in Blender: then an empty array."""
        key = f"{name}|{attribute}|{frame}"
        if key not in self.arrays and self.arrays[f"{name}|count|{frame}"] == 0:
            return np.zeros((0, VECTORS[attribute]) if attribute in VECTORS else 0)
        return self.arrays[key]

    def objects(self, kind):
        return sorted(name for name, info in self.meta["objects"].items() if info["type"] == kind)


def recording_rate(traj):
    return 1.0 / float(np.median(np.diff(traj.t)))


@pytest.fixture(scope="module")
def blender(tmp_path_factory):
    """The stages of this module, each imported into Blender once: name → Imported."""
    if not BLENDER_PYTHON.exists():
        pytest.skip(f"Blender (bpy) is not installed: no {BLENDER_PYTHON} (make test installs it from requirements/blender-test.txt)")
    folder = tmp_path_factory.mktemp("usd_blender")
    trajectories = {"fountain": fountain(), "cloth": cloth(), "cloth with deaths": cloth(deaths=True), "colliders": _run()}
    guide = {"import_guide": True}
    rate = recording_rate(trajectories["fountain"])
    jobs = {
        # the fountain at its own rate, set by hand after the import (fps / fps_base)
        "fountain": ("fountain", guide, [round(rate), round(rate) / rate], True),
        "fountain, default options": ("fountain", {}, None, False),
        "cloth": ("cloth", guide, None, True),
        "cloth with deaths": ("cloth with deaths", {}, None, True),
        "colliders": ("colliders", guide, None, True),
    }
    spec = []
    for name, (traj_name, options, fps, frames) in jobs.items():
        usd = folder / f"{traj_name.replace(' ', '_')}.usdc"
        if not usd.exists():
            trajectories[traj_name].export(usd)
        spec.append({"usd": str(usd), "out": str(folder / f"{name.replace(' ', '_').replace(',', '')}.npz"), "import": options, "fps": fps, "frames": frames})
    (folder / "jobs.json").write_text(json.dumps(spec))
    (folder / "blender_side.py").write_text(BLENDER_SIDE)
    run = subprocess.run([str(BLENDER_PYTHON), str(folder / "blender_side.py"), str(folder / "jobs.json")], capture_output=True, text=True, timeout=300)
    if run.returncode != 0 and "No module named 'bpy'" in run.stderr:
        pytest.skip(f"Blender (bpy) cannot be imported by {BLENDER_PYTHON}")
    assert run.returncode == 0, run.stderr[-3000:]
    return {name: Imported(trajectories[jobs[name][0]], job["out"]) for name, job in zip(jobs, spec, strict=True)}


PLAYED = ["fountain", "cloth", "cloth with deaths", "colliders"]


@pytest.mark.parametrize("name", PLAYED)
def test_blender_plays_each_frame_at_its_own_frame_number(blender, name):
    imported = blender[name]
    traj, meta = imported.traj, imported.meta
    assert meta["result"] == ["FINISHED"]
    # Blender takes the stage's frame range as its timeline's: time codes 0 … F − 1, from the
    # first frame with particles (the fountain's 1: its frame 0 has none, and Blender aborts
    # exporting a point cloud of no points), frame k at time code k
    first = int(np.flatnonzero(traj.alive.any(axis=1))[0])
    assert (meta["frame_start"], meta["frame_end"]) == (first, len(traj.t) - 1)
    assert (first > 0) == (name == "fountain")
    # but not its rate: the scene keeps Blender's 24 fps, which docs/files.md says to set
    # by hand (the fountain's job sets it to the recording's rate; frame k stays frame k)
    assert (meta["fps"], meta["fps_base"]) == (24, 1.0)
    [cloud] = imported.objects("POINTCLOUD")
    worst, scale = 0.0, 0.0
    for k in range(len(traj.t)):
        live = traj.alive[k]
        want = traj.positions[k][live]
        got = imported.get(cloud, "position", k)
        assert got.shape == want.shape, f"frame {k}: {len(got)} points in Blender, {len(want)} alive"
        if len(want):
            worst, scale = max(worst, float(np.max(np.abs(got - want)))), max(scale, float(np.max(np.abs(want))))
        np.testing.assert_array_equal(imported.get(cloud, "id", k), traj.ids[live])  # each point's id
        np.testing.assert_array_equal(imported.get(cloud, "radius", k), traj.radii[live].astype(np.float32))
        colour = imported.get(cloud, "displayColor", k)
        np.testing.assert_allclose(colour[:, :3], expected_colours(traj, k), rtol=0, atol=1e-6)
        assert np.all(colour[:, 3] == 1.0)
    assert worst <= 1e-6 * scale, f"positions off by up to {worst} m"  # float32, as USD stores them


def test_blender_reads_these_point_cloud_attributes(blender):
    # what comes through to Blender: the ids as `id` (not USD's int64 `ids`), the primvars
    # mass, displayColor and collisionGroup; the string primvar species is left out (Blender
    # takes no strings)
    [cloud] = blender["fountain"].objects("POINTCLOUD")
    attributes = blender["fountain"].meta["objects"][cloud]["attributes"]
    assert attributes == {
        "position": ["FLOAT_VECTOR", "POINT"],
        "radius": ["FLOAT", "POINT"],
        "velocity": ["FLOAT_VECTOR", "POINT"],
        "id": ["INT", "POINT"],
        "mass": ["FLOAT", "POINT"],
        "displayColor": ["FLOAT_COLOR", "POINT"],
        "collisionGroup": ["INT", "POINT"],
    }


@pytest.mark.parametrize("name", ["cloth", "cloth with deaths"])
def test_blender_draws_the_springs_as_curves_between_their_ends(blender, name):
    imported = blender[name]
    traj = imported.traj
    [springs] = imported.objects("CURVES")
    for k in range(len(traj.t)):
        want = spring_ends(traj, k)
        got = imported.get(springs, "position", k)
        assert got.shape == want.shape, f"frame {k}: {len(got)} spring ends in Blender, {len(want)} expected"
        np.testing.assert_array_equal(got, want.astype(np.float32))
        sizes = imported.get(springs, "sizes", k)
        assert len(sizes) == len(want) // 2 and np.all(sizes == 2)
        np.testing.assert_allclose(imported.get(springs, "radius", k), 0.012 / 4, rtol=1e-6)  # half the USD width


def test_blender_imports_the_colliders_as_rendered_meshes(blender):
    # the default purpose: imported without the Guide option, and rendered
    assert blender["fountain, default options"].objects("MESH") == ["box_1", "plane_0"]
    assert blender["fountain"].objects("MESH") == ["box_1", "plane_0"]
    imported = blender["colliders"]
    assert imported.objects("MESH") == ["box_0", "plane_1", "sphere_2"]
    box = imported.get("box_0", "position", 0)
    np.testing.assert_array_equal(box, [[x, y, z] for z in (0, 2) for y in (0, 1) for x in (0, 1)])
    assert imported.get("box_0", "faces", 0).tolist() == [4] * 6
    plane = imported.get("plane_1", "position", 0)
    np.testing.assert_allclose((plane - [0, 0, 0.1]) @ (np.array([0, 1, 1]) / np.sqrt(2)), 0, atol=1e-6)
    sphere = imported.get("sphere_2", "position", 0)
    np.testing.assert_allclose(np.linalg.norm(sphere - [0.5, 0.5, 0.2], axis=1), 0.1, rtol=1e-6)
    assert sorted(imported.get("sphere_2", "faces", 0).tolist()) == [3] * 64 + [4] * 448


# Runs in Blender's Python: imports one stage and writes the world matrix of every instance
# Blender draws at each frame of the timeline (a PointInstancer's prototypes placed, turned and
# scaled), to out (.npz).
BLENDER_INSTANCES = r"""
import sys
import bpy, numpy as np

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.usd_import(filepath=sys.argv[1])
scene = bpy.context.scene
mats = []
for k in range(scene.frame_start, scene.frame_end + 1):
    scene.frame_set(k)
    graph = bpy.context.evaluated_depsgraph_get()
    mats.append([np.array(inst.matrix_world) for inst in graph.object_instances if inst.is_instance])
np.savez(sys.argv[2], mats=np.array(mats))
"""


def test_blender_turns_a_rolling_ball_as_kinema_does(tmp_path):
    # A ball rolling on a floor at 0.8 m/s with ω = v / r = 16 rad/s about y (n × v̂): the
    # USD's PointInstancer gives Blender each frame's orientation, and the ball Blender draws
    # (its instance's world matrix) is turned by exactly kinema's quaternion, scaled by r and
    # placed at the centre: a textured ball rolls in Blender (to float32 and half precision).
    if not BLENDER_PYTHON.exists():
        pytest.skip(f"Blender (bpy) is not installed: no {BLENDER_PYTHON} (make test installs it from requirements/blender-test.txt)")
    import kinema

    r = 0.05
    w = kinema.World(dt=1e-3, spin=True)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.set_collisions(restitution=0.3, friction=0.5)
    w.add_particles([[0, 0, r]], radius=r, mass=0.3, velocity=[[0.8, 0, 0]], angular_velocity=[[0, 16, 0]])
    traj = w.run(0.5, fps=10)
    usd = tmp_path / "roll.usdc"
    traj.export(usd)
    (tmp_path / "side.py").write_text(BLENDER_INSTANCES)
    run = subprocess.run([str(BLENDER_PYTHON), str(tmp_path / "side.py"), str(usd), str(tmp_path / "out.npz")], capture_output=True, text=True, timeout=300)
    if run.returncode != 0 and "No module named 'bpy'" in run.stderr:
        pytest.skip(f"Blender (bpy) cannot be imported by {BLENDER_PYTHON}")
    assert run.returncode == 0, run.stderr[-3000:]
    mats = np.load(tmp_path / "out.npz")["mats"]
    assert mats.shape == (len(traj.t), 1, 4, 4)
    for k, q in enumerate(traj.orientations[:, 0]):
        a, b, c, d = q
        turn = np.array(
            [
                [1 - 2 * (c * c + d * d), 2 * (b * c - a * d), 2 * (b * d + a * c)],
                [2 * (b * c + a * d), 1 - 2 * (b * b + d * d), 2 * (c * d - a * b)],
                [2 * (b * d - a * c), 2 * (c * d + a * b), 1 - 2 * (b * b + c * c)],
            ]
        )
        np.testing.assert_allclose(mats[k, 0, :3, :3], r * turn, atol=r * 2e-3)  # quath: 11-bit mantissa
        np.testing.assert_allclose(mats[k, 0, :3, 3], traj.positions[k, 0], atol=1e-6)
    assert np.ptp(mats[:, 0, 0, 0]) > r, "the ball turns"


# Runs in Blender's Python: opens the .blend that `kinema export --format blend` built and
# writes, as JSON to argv[2], the scene's rate and range, each object's material slots, and
# for each render asked (engine, frame) the colour (8-bit sRGB, as the PNG holds it) at the
# pixels where named world points land (the balls' centres, a floor point, the moving
# collider's centres), with the collider's place at that frame.
BLENDER_RENDER = r"""
import json, sys
import bpy, numpy as np
from bpy_extras.object_utils import world_to_camera_view
from mathutils import Vector

job = json.load(open(sys.argv[1]))
bpy.ops.wm.open_mainfile(filepath=job["blend"])
scene = bpy.context.scene
out = {"fps": scene.render.fps, "fps_base": scene.render.fps_base, "frame_start": scene.frame_start, "frame_end": scene.frame_end,
       "camera": scene.camera is not None, "caches": [c.filepath for c in bpy.data.cache_files],
       "objects": {ob.name: {"type": ob.type, "hide_render": ob.hide_render, "slots": [[s.link, s.material.name if s.material else None] for s in ob.material_slots]} for ob in scene.objects},
       "renders": []}
scene.render.resolution_x, scene.render.resolution_y = job["size"]
scene.render.resolution_percentage = 100
scene.cycles.samples, scene.cycles.device = 16, "CPU"
scene.eevee.taa_render_samples = 4
for n, (engine, frame) in enumerate(job["renders"]):
    scene.render.engine = engine
    scene.frame_set(frame)
    scene.render.filepath = job["png"] % n
    entry = {"engine": engine, "frame": frame, "png": scene.render.filepath}
    try:
        bpy.ops.render.render(write_still=True)
    except RuntimeError as e:
        entry["error"] = str(e)
        out["renders"].append(entry)
        continue
    image = bpy.data.images.load(scene.render.filepath)
    w, h = image.size
    pixels = np.array(image.pixels[:]).reshape(h, w, image.channels)
    graph = bpy.context.evaluated_depsgraph_get()
    mover = scene.objects[job["mover"]].evaluated_get(graph)
    entry["mover"] = list(mover.matrix_world.translation)
    entry["background"] = (pixels[h - 2, w // 2, :3] * 255).tolist()
    entry["points"] = {}
    for name, point in job["points"].items():
        p = world_to_camera_view(scene, scene.camera, Vector(point))
        i, j = int(p.x * w), int(p.y * h)  # rows from the bottom, as image.pixels
        entry["points"][name] = (pixels[j, i, :3] * 255).tolist() if 0 <= i < w and 0 <= j < h else None
    out["renders"].append(entry)
json.dump(out, open(sys.argv[2], "w"))
"""


def three_balls():
    """Red, green and blue balls at rest on a floor (a plane), a cube (a mesh collider)
    moving past behind them at 0.5 m/s, recorded at fps = 30 with dt = 1 ms (frame k at
    k/30 s, 34 steps of 0.98 ms a frame)."""
    w = kinema.World(dt=1e-3)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    corners = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], float) * 0.2 - [0.1, 0.1, 0.0] + [-0.2, 0.35, 0.0]
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    faces = [t for a, b, c, d in quads for t in ([a, b, c], [a, c, d])]
    w.add(kinema.Mesh(vertices=corners, faces=faces, motion=kinema.Motion(velocity=(0.5, 0, 0))))
    w.add_particles([[-0.25, 0, 0.08], [0, 0, 0.08], [0.25, 0, 0.08]], radius=0.08, mass=1.0)
    traj = w.run(0.5, fps=30)
    traj.colors = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]])
    return traj


@pytest.fixture(scope="module")
def blend(tmp_path_factory):
    """The three balls exported with `format="blend"` (Blender: .venv-blender's Python, by
    $KINEMA_BLENDER), opened in Blender and rendered: (traj, what Blender says)."""
    if not BLENDER_PYTHON.exists():
        pytest.skip(f"Blender (bpy) is not installed: no {BLENDER_PYTHON} (make test installs it from requirements/blender-test.txt)")
    folder = tmp_path_factory.mktemp("blend")
    traj = three_balls()
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("KINEMA_BLENDER", str(BLENDER_PYTHON))
        written = traj.export(folder / "balls.blend")
    assert written == [folder / "balls.blend", folder / "balls.usdc"]
    late = len(traj.t) - 1
    cube = lambda k: [-0.2 + 0.5 * traj.t[k], 0.35, 0.1]  # noqa: E731
    job = {
        "blend": str(folder / "balls.blend"),
        "png": str(folder / "render_%d.png"),
        "size": [160, 120],
        "renders": [["CYCLES", 0], ["CYCLES", late], ["BLENDER_EEVEE", 0]],
        "mover": "mesh_1",
        "points": {
            "red": traj.positions[0, 0].tolist(),
            "green": traj.positions[0, 1].tolist(),
            "blue": traj.positions[0, 2].tolist(),
            "floor": [0.0, -0.22, 0.0],
            "cube then": cube(0),
            "cube now": cube(late),
        },
    }
    (folder / "job.json").write_text(json.dumps(job))
    (folder / "render.py").write_text(BLENDER_RENDER)
    run = subprocess.run(
        [str(BLENDER_PYTHON), str(folder / "render.py"), str(folder / "job.json"), str(folder / "out.json")], capture_output=True, text=True, timeout=600
    )
    if run.returncode != 0 and "No module named 'bpy'" in run.stderr:
        pytest.skip(f"Blender (bpy) cannot be imported by {BLENDER_PYTHON}")
    assert run.returncode == 0, run.stderr[-3000:]
    return traj, json.loads((folder / "out.json").read_text())


def dominant(rgb, channel):
    """Whether `channel` of the 8-bit colour `rgb` exceeds both others by 100 and more."""
    others = [v for k, v in enumerate(rgb) if k != channel]
    return rgb[channel] >= max(others) + 100


def test_the_blend_plays_at_the_asked_rate_over_the_frames(blend):
    traj, out = blend
    # World.run(fps=30) at dt = 1 ms records frame k at k/30 s; the scene plays the 30 frames
    # a second asked, frame k the stage's time code k
    assert traj.t.tolist() == [k / 30 for k in range(len(traj.t))]
    assert (out["fps"], out["fps_base"]) == (30, 1.0)
    assert (out["frame_start"], out["frame_end"]) == (0, len(traj.t) - 1)
    assert out["caches"] == ["//balls.usdc"]  # beside the .blend, wherever the two are moved
    assert out["camera"]


def test_the_blend_gives_the_point_cloud_its_colours_material_on_the_object(blend):
    _, out = blend
    objects = out["objects"]
    # on the object, not the data: the cache modifier's data of each frame has no material
    assert objects["particles"]["slots"] == [["OBJECT", "kinema particles"]]
    # the colliders are rendered meshes with the stage's material (imported without Guide)
    assert objects["plane_0"]["slots"] == objects["mesh_1"]["slots"] == [["DATA", "colliders"]]
    assert not objects["plane_0"]["hide_render"] and not objects["mesh_1"]["hide_render"]


@pytest.mark.parametrize("render", [0, 1, 2], ids=["cycles frame 0", "cycles last frame", "eevee frame 0"])
def test_a_render_shows_the_balls_in_their_colours_and_the_floor(blend, render):
    _, out = blend
    shot = out["renders"][render]
    assert "error" not in shot, shot.get("error")
    points = shot["points"]
    for channel, name in enumerate(["red", "green", "blue"]):
        assert dominant(points[name], channel), f"{shot['engine']}: the {name} ball renders {points[name]}"
    # the floor renders (the white background where nothing is; a guide would leave it)
    assert shot["background"] == [255, 255, 255]
    floor = points["floor"]
    assert max(floor) <= 245 and max(floor) - min(floor) <= 6, f"the floor renders {floor}"


def test_the_moving_collider_moves_in_the_render(blend):
    traj, out = blend
    first, last = out["renders"][0], out["renders"][1]
    # the cube's transform follows its motion (0.5 m/s along x) ...
    np.testing.assert_allclose(first["mover"], [0, 0, 0], atol=1e-6)
    np.testing.assert_allclose(last["mover"], [0.5 * traj.t[-1], 0, 0], atol=1e-6)
    # ... and the render shows it there: darker than the floor where it is, not where it was
    floor = np.mean(first["points"]["floor"])
    assert np.mean(first["points"]["cube then"]) < floor - 20 and np.mean(last["points"]["cube now"]) < floor - 20
    assert abs(np.mean(last["points"]["cube then"]) - floor) < 8 and abs(np.mean(first["points"]["cube now"]) - floor) < 8


def test_kinema_export_format_blend_from_a_saved_run(tmp_path, monkeypatch):
    # The way: `kinema run` saves run.h5 (its fps kept), `kinema export -f blend`
    # writes run.blend and run.usdc beside it, the stage at the 30 frames a second asked
    if not BLENDER_PYTHON.exists():
        pytest.skip(f"Blender (bpy) is not installed: no {BLENDER_PYTHON}")
    from pxr import Usd
    from typer.testing import CliRunner

    from kinema.cli import app

    three_balls().save(tmp_path / "run.h5")
    monkeypatch.setenv("KINEMA_BLENDER", str(BLENDER_PYTHON))
    result = CliRunner().invoke(app, ["export", str(tmp_path / "run.h5"), "-f", "blend"])
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.blend", "run.h5", "run.usdc"]
    assert Usd.Stage.Open(str(tmp_path / "run.usdc")).GetFramesPerSecond() == 30.0
    assert (tmp_path / "run.blend").read_bytes()[:7] == b"BLENDER"


# Runs in Blender's Python: imports a stage as a user would (File → Import → USD) and exports
# the scene to USD again, the animation over the timeline, then the current frame.
BLENDER_REEXPORT = r"""
import sys
import bpy

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.usd_import(filepath=sys.argv[1])
scene = bpy.context.scene
print("timeline", scene.frame_start, scene.frame_end, flush=True)
assert bpy.ops.wm.usd_export(filepath=sys.argv[2], export_animation=True) == {"FINISHED"}
scene.frame_set(scene.frame_start)
assert bpy.ops.wm.usd_export(filepath=sys.argv[3]) == {"FINISHED"}
"""


def test_blender_exports_an_emitters_stage_again(tmp_path):
    # Blender 5.0 aborts (std::bad_alloc, the whole process) exporting a point cloud of no
    # points, which an emitter's frame 0 imports as: kinema's stage starts its frame range at
    # the first frame with particles, so that exporting the imported animation or its first
    # frame works (frame k still at time code k); kinema's reader reads the stage back whole.
    if not BLENDER_PYTHON.exists():
        pytest.skip(f"Blender (bpy) is not installed: no {BLENDER_PYTHON} (make test installs it from requirements/blender-test.txt)")
    from pxr import Usd, UsdGeom

    traj = fountain()
    assert not traj.alive[0].any()
    usd = tmp_path / "fountain.usdc"
    traj.export(usd)
    (tmp_path / "side.py").write_text(BLENDER_REEXPORT)
    animation, frame = tmp_path / "animation.usdc", tmp_path / "frame.usdc"
    run = subprocess.run([str(BLENDER_PYTHON), str(tmp_path / "side.py"), str(usd), str(animation), str(frame)], capture_output=True, text=True, timeout=300)
    if run.returncode != 0 and "No module named 'bpy'" in run.stderr:
        pytest.skip(f"Blender (bpy) cannot be imported by {BLENDER_PYTHON}")
    assert run.returncode == 0, f"Blender exited with {run.returncode}: {run.stderr[-3000:]}"
    assert f"timeline 1 {len(traj.t) - 1}" in run.stdout
    stage = Usd.Stage.Open(str(animation))
    [cloud] = [p for p in stage.Traverse() if p.IsA(UsdGeom.Points)]
    codes = UsdGeom.Points(cloud).GetPointsAttr().GetTimeSamples()
    assert (codes[0], codes[-1]) == (1.0, len(traj.t) - 1)
    back = kinema.load_trajectory(usd)
    np.testing.assert_array_equal(back.alive, traj.alive)
    np.testing.assert_array_equal(back.ids, traj.ids)
