"""Issue 49, mesh, USD and PLY readers: a file that would make a reader lie (a scene read
mirrored, every position 0), block (a FIFO it names) or read without end (a device) is refused
with one line naming the file, the field, the value and what is allowed."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys

import numpy as np
import pytest
from typer.testing import CliRunner

import kinema
from kinema.cli import app
from kinema.io import TrajectoryFileError

runner = CliRunner()

TRIANGLE_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"


def one_line(e: pytest.ExceptionInfo) -> str:
    text = str(e.value)
    assert "\n" not in text, text
    return text


def points_stage(path, header: str) -> str:
    """A text USD stage of one Points prim moving over two time codes, with `header` metadata."""
    path.write_text(
        f'#usda 1.0\n(\n    {header}\n    upAxis = "Z"\n)\ndef Points "p" {{\n    point3f[] points.timeSamples = {{ 0: [(1, 2, 3)], 1: [(1, 2, 4)] }}\n}}\n'
    )
    return str(path)


def mesh_stage(path, header: str, sublayer: str | None = None) -> str:
    """A text USD stage of one triangle Mesh prim, with `header` metadata (and a sublayer)."""
    sub = f"subLayers = [@{sublayer}@]" if sublayer else ""
    path.write_text(
        f'#usda 1.0\n(\n    {header}\n    {sub}\n    upAxis = "Z"\n)\n'
        'def Mesh "m" {\n    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n'
        "    int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 2]\n}\n"
    )
    return str(path)


# -- USD units ---------------------------------------------------------------------------------


@pytest.mark.parametrize("value", ["nan", "0", "1e-320", "-1"])
def test_usd_time_codes_per_second_must_be_finite_and_not_tiny(tmp_path, value):
    pytest.importorskip("pxr")
    path = points_stage(tmp_path / f"t{value}.usda", f"timeCodesPerSecond = {value}\n    metersPerUnit = 1")
    with pytest.raises(TrajectoryFileError) as e:
        kinema.load_trajectory(path)
    text = one_line(e)
    assert path in text and "timeCodesPerSecond = " in text and "finite and at least 1e-06" in text


@pytest.mark.parametrize("value", ["nan", "0", "-1"])
def test_usd_meters_per_unit_must_be_finite_and_positive(tmp_path, value):
    pytest.importorskip("pxr")
    path = points_stage(tmp_path / f"m{value}.usda", f"timeCodesPerSecond = 24\n    metersPerUnit = {value}")
    with pytest.raises(TrajectoryFileError) as e:
        kinema.load_trajectory(path)
    text = one_line(e)
    assert path in text and "metersPerUnit = " in text and "finite and > 0" in text
    mesh = mesh_stage(tmp_path / f"mesh{value}.usda", f"metersPerUnit = {value}")
    with pytest.raises(ValueError, match=r"metersPerUnit = .* is invalid: it must be finite and > 0") as e:
        kinema.Mesh(mesh)
    assert mesh in one_line(e)


def test_commands_refuse_a_usd_stage_of_no_clock(tmp_path):
    pytest.importorskip("pxr")
    path = points_stage(tmp_path / "zero.usda", "timeCodesPerSecond = 0\n    metersPerUnit = 1")
    res = runner.invoke(app, ["view", path, "--html", str(tmp_path / "v.html")])
    assert res.exit_code == 2, res.output
    assert "timeCodesPerSecond = 0.0 is invalid" in res.output
    assert not (tmp_path / "v.html").exists()


def test_a_good_usd_stage_still_reads(tmp_path):
    pytest.importorskip("pxr")
    traj = kinema.load_trajectory(points_stage(tmp_path / "ok.usda", "timeCodesPerSecond = 2\n    metersPerUnit = 0.5"))
    np.testing.assert_array_equal(traj.positions[:, 0], [[0.5, 1.0, 1.5], [0.5, 1.0, 2.0]])


# -- face indices ------------------------------------------------------------------------------


def ply_mesh(path, index: int) -> str:
    path.write_text(
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
        "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
        f"0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 {index}\n"
    )
    return str(path)


@pytest.mark.parametrize("index", [-1, 4])
def test_a_ply_face_index_out_of_range_is_refused(tmp_path, index):
    pytest.importorskip("trimesh")
    path = ply_mesh(tmp_path / "bad.ply", index)
    with pytest.raises(ValueError) as e:
        kinema.Mesh(path)
    text = one_line(e)
    assert path in text and f"its face 0 has the vertex index {index}; a face's vertex indices are 0 … 3" in text
    assert len(kinema.Mesh(ply_mesh(tmp_path / "good.ply", 3)).faces) == 1


def gltf(path, indices: list[int], buffer_uri: str | None = None, declared: int | None = None) -> str:
    """A glTF of one triangle (3 vertices) whose indices are `indices`; its buffer embedded as a
    data URI, or the file `buffer_uri` (written beside it unless it exists) with `declared`
    as its byteLength."""
    import base64

    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float32).tobytes()
    idx = np.array(indices, dtype=np.uint32).tobytes()
    blob = positions + idx
    if buffer_uri is None:
        buffer = {"uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode(), "byteLength": len(blob)}
    else:
        target = path.parent / buffer_uri
        if not os.path.lexists(target):
            target.write_bytes(blob)
        buffer = {"uri": buffer_uri, "byteLength": len(blob) if declared is None else declared}
    tree = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [buffer],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": len(idx)}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5125, "count": len(indices), "type": "SCALAR"},
        ],
    }
    path.write_text(json.dumps(tree))
    return str(path)


def test_a_gltf_face_index_out_of_range_is_one_line(tmp_path):
    pytest.importorskip("trimesh")
    path = gltf(tmp_path / "bad.gltf", [0, 1, 7])
    with pytest.raises(ValueError) as e:
        kinema.Mesh(path)
    text = one_line(e)
    assert path in text and "vertex index 7" in text
    assert len(kinema.Mesh(gltf(tmp_path / "good.gltf", [0, 1, 2])).faces) == 1


# -- files a mesh or a stage names -------------------------------------------------------------


def finishes(code: str, timeout: float = 30.0) -> subprocess.CompletedProcess:
    """Runs `code` in a fresh Python (a reader blocked on a FIFO must not hang the tests)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=timeout, env=env)


def test_a_gltf_buffer_that_is_a_fifo_is_refused_unopened(tmp_path):
    pytest.importorskip("trimesh")
    os.mkfifo(tmp_path / "buffer.bin")
    path = gltf(tmp_path / "fifo.gltf", [0, 1, 2], buffer_uri="buffer.bin", declared=48)
    run = finishes(f"import kinema\ntry:\n    kinema.Mesh({path!r})\nexcept ValueError as e:\n    print(e)")
    assert run.returncode == 0, run.stderr
    assert run.stdout.count("\n") == 1 and path in run.stdout
    assert "the glTF buffer 'buffer.bin' (buffers[0].uri) is a FIFO, not a regular file" in run.stdout


def test_a_gltf_buffer_that_is_a_device_is_refused_unread(tmp_path):
    pytest.importorskip("trimesh")
    os.mknod(tmp_path / "zero", stat.S_IFCHR | 0o600, os.makedev(1, 5))  # a private /dev/zero
    path = gltf(tmp_path / "zero.gltf", [0, 1, 2], buffer_uri="zero", declared=48)
    # (in a child of bounded memory: a reader that follows the device reads until memory runs out)
    code = f"import resource\nresource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))\nimport kinema\ntry:\n    kinema.Mesh({path!r})\nexcept ValueError as e:\n    print(e)"
    run = finishes(code)
    assert run.returncode == 0, run.stderr
    assert run.stdout.count("\n") == 1 and path in run.stdout
    assert "the glTF buffer 'zero' (buffers[0].uri) is a character device, not a regular file" in run.stdout


def test_a_gltf_buffer_shorter_than_declared_is_refused(tmp_path):
    pytest.importorskip("trimesh")
    path = gltf(tmp_path / "short.gltf", [0, 1, 2], buffer_uri="short.bin", declared=10**12)
    with pytest.raises(ValueError, match=r"buffers\[0\]\.byteLength = 1000000000000 is invalid: the glTF buffer 'short.bin' .* holds 48 bytes"):
        kinema.Mesh(path)
    assert len(kinema.Mesh(gltf(tmp_path / "fine.gltf", [0, 1, 2], buffer_uri="fine.bin")).faces) == 1


def test_an_obj_mtllib_is_not_followed(tmp_path):
    pytest.importorskip("trimesh")
    os.mkfifo(tmp_path / "materials.mtl")
    path = tmp_path / "fifo.obj"
    path.write_text("mtllib materials.mtl\n" + TRIANGLE_OBJ)
    run = finishes(f"import kinema\nprint(len(kinema.Mesh({str(path)!r}).faces))")
    assert run.returncode == 0 and run.stdout == "1\n", run.stderr


def test_an_obj_with_a_latin1_comment_is_read(tmp_path):
    pytest.importorskip("trimesh")
    path = tmp_path / "cafe.obj"
    path.write_bytes(b"# caf\xe9 au lait\n" + TRIANGLE_OBJ.encode())
    mesh = kinema.Mesh(path)
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2]])


def test_a_usd_sublayer_that_is_a_fifo_is_refused_unopened(tmp_path):
    pytest.importorskip("pxr")
    os.mkfifo(tmp_path / "sub.usda")
    mesh = mesh_stage(tmp_path / "mesh.usda", "metersPerUnit = 1", sublayer="./sub.usda")
    points = tmp_path / "points.usda"
    points.write_text(
        open(points_stage(tmp_path / "p0.usda", "metersPerUnit = 1")).read().replace('upAxis = "Z"', 'upAxis = "Z"\n    subLayers = [@./sub.usda@]')
    )
    code = (
        "import kinema\n"
        f"for call in (lambda: kinema.Mesh({mesh!r}), lambda: kinema.load_trajectory({str(points)!r})):\n"
        "    try:\n        call()\n    except ValueError as e:\n        print(type(e).__name__, e)\n"
    )
    run = finishes(code)
    assert run.returncode == 0, run.stderr
    lines = run.stdout.splitlines()
    assert len(lines) == 2, run.stdout
    assert lines[0].startswith("ValueError") and mesh in lines[0]
    assert lines[1].startswith("TrajectoryFileError") and str(points) in lines[1]
    for line in lines:
        assert "the layer './sub.usda' named by the stage (a sublayer, reference or payload) is a FIFO, not a regular file" in line


def test_a_missing_usd_sublayer_is_refused(tmp_path):
    pytest.importorskip("pxr")
    mesh = mesh_stage(tmp_path / "mesh.usda", "metersPerUnit = 1", sublayer="./gone.usda")
    with pytest.raises(ValueError, match=r"the layer './gone.usda' named by the stage .* does not exist"):
        kinema.Mesh(mesh)


def test_a_regular_usd_sublayer_is_read(tmp_path):
    pytest.importorskip("pxr")
    mesh_stage(tmp_path / "sub.usda", "metersPerUnit = 1")
    top = tmp_path / "top.usda"
    top.write_text('#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = "Z"\n    subLayers = [@./sub.usda@]\n)\n')
    assert len(kinema.Mesh(top).faces) == 1


# -- mesh geometry -----------------------------------------------------------------------------

FLOOR = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype=float)
FLOOR_FACES = [[0, 1, 2], [0, 2, 3]]


@pytest.mark.parametrize("half_width", [1e78, 1e300])
def test_mesh_coordinates_beyond_the_limit_are_refused(half_width):
    with pytest.raises(ValueError) as e:
        kinema.Mesh(vertices=FLOOR * half_width, faces=FLOOR_FACES)
    text = one_line(e)
    assert text.startswith("vertices[0][0] = ") and "at most 1e+75 m in magnitude" in text
    kinema.Mesh(vertices=FLOOR * 1e75, faces=FLOOR_FACES)


def test_a_scaled_mesh_beyond_the_limit_is_refused():
    cube = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], dtype=float)
    with pytest.raises(ValueError, match=r"vertices\[1\]\[2\] = 1e\+155 m after scale, rotation and translation is invalid"):
        kinema.Mesh(vertices=cube, faces=[[0, 1, 3]], scale=1e155)
    with pytest.raises(ValueError, match=r"after scale, rotation and translation is invalid"):
        kinema.Mesh(vertices=FLOOR, faces=FLOOR_FACES, translation=(0, 0, 1e80))


def test_an_infinite_vertex_is_named_at_its_own_coordinate():
    v = FLOOR.copy()
    v[2, 1] = np.inf
    with pytest.raises(ValueError) as e:
        kinema.Mesh(vertices=v, faces=FLOOR_FACES, rotation=(30, 40, 50))
    assert one_line(e).startswith("vertices[2][1] = inf is invalid: a mesh's vertices must be finite")


def test_a_mesh_file_beyond_the_limit_names_the_file(tmp_path):
    pytest.importorskip("trimesh")
    path = tmp_path / "huge.obj"
    path.write_text("v 0 0 0\nv 1e300 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(ValueError) as e:
        kinema.Mesh(path)
    text = one_line(e)
    assert text.startswith("vertices[1][0] = 1e+300 m (file ") and str(path) in text


@pytest.mark.parametrize("node", ["fifo", "device", "dir", "missing"])
@pytest.mark.parametrize("series", ["ply", "pvd"])
def test_a_frame_file_of_a_series_is_checked_before_it_is_opened(tmp_path, series, node):
    # A PLY series (a folder of frames) and a VTK series (a .pvd naming .vtp files) name files
    # beyond the one given: a frame that is a FIFO blocked load_trajectory for good, a device
    # fed it without end. Each frame file is checked as the main file is: one line naming the
    # series, the frame and what the file is.
    w = kinema.World(dt=0.01)
    w.add_particles([[0, 0, 0], [1, 0, 0]], radius=0.1)
    w.run(0.03, fps=100).export(tmp_path / f"t.{series}")
    target = sorted((tmp_path / f"t_{'ply' if series == 'ply' else 'vtk'}").iterdir())[1]
    target.unlink()
    if node == "fifo":
        os.mkfifo(target)
    elif node == "device":
        os.mknod(target, stat.S_IFCHR | 0o600, os.makedev(1, 5))  # a private /dev/zero
    elif node == "dir":
        target.mkdir()
    main = tmp_path / ("t_ply" if series == "ply" else "t.pvd")
    if (series, node) == ("ply", "missing"):  # a folder's frames are the files there: each says its time
        back = kinema.load_trajectory(main)
        np.testing.assert_allclose(back.t, [0.0, 0.02, 0.03], rtol=1e-6)
        return
    run = finishes(f"import kinema\ntry:\n    kinema.load_trajectory({str(main)!r})\nexcept kinema.io.TrajectoryFileError as e:\n    print(e)")
    assert run.returncode == 0, run.stderr
    said = {"fifo": "is a FIFO, not a regular file", "device": "is a character device, not a regular file", "dir": "is a directory, not a regular file"}
    expected = f"{main}: frame 1: its file {target.name} " + said.get(node, "does not exist")
    assert run.stdout == expected + "\n"
