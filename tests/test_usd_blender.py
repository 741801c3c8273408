"""kinema's USD imported into Blender itself (bpy 5.0, Blender as a Python module), as a user
would: File → Import → USD, then play. Every frame of the timeline holds that frame's live
particles (count, positions, ids, colours), the springs are curves between their ends, the
colliders are rendered meshes, and the timeline spans the frames.

bpy 5.0.1 needs numpy < 2, which kinema's venv does not have, so Blender runs in a venv of its
own (.venv-blender, made by `make test` from requirements/blender-test.txt) as a separate
process, once for all the stages of this module; the tests skip where it is not installed."""

import json
import subprocess
from pathlib import Path

import numpy as np
import pytest

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
    frames = range(scene.frame_start, scene.frame_end + 1) if job["frames"] else [scene.frame_start]
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
    # Blender takes the stage's frame range (time codes 0 … F − 1) as its timeline's
    assert (meta["frame_start"], meta["frame_end"]) == (0, len(traj.t) - 1)
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
    # mass and displayColor; the string primvar species is left out (Blender takes no strings)
    [cloud] = blender["fountain"].objects("POINTCLOUD")
    attributes = blender["fountain"].meta["objects"][cloud]["attributes"]
    assert attributes == {
        "position": ["FLOAT_VECTOR", "POINT"],
        "radius": ["FLOAT", "POINT"],
        "velocity": ["FLOAT_VECTOR", "POINT"],
        "id": ["INT", "POINT"],
        "mass": ["FLOAT", "POINT"],
        "displayColor": ["FLOAT_COLOR", "POINT"],
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
