"""Which way is up in a mesh file (issue 48): a +y-up OBJ as Blender writes it, read with
up_axis="y", is the +z-up original exactly; glTF and USD say their own axis and are read by
it; the scene key goes there and back; and a mesh collider far from every particle, or lying
on its side under gravity, is said (MeshPlacementWarning), an upright bowl is not."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import kinema
from kinema.scene import Scene

SCENES = Path(__file__).resolve().parent.parent / "examples" / "scenes"


def blender_obj(path: Path, vertices: np.ndarray, faces: np.ndarray) -> Path:
    """`vertices` (Blender's +z-up coordinates) written as Blender's OBJ exporter writes them
    by default (forward −Z, up +Y): a point (x, y, z) as the line `v x z −y`, at its 6 decimals."""
    lines = [f"v {x:.6f} {z:.6f} {-y:.6f}" for x, y, z in vertices]
    lines += ["f " + " ".join(str(i + 1) for i in f) for f in faces]
    path.write_text("\n".join(lines) + "\n")
    return path


def bowl_arrays(segments: int = 24, rings: int = 6, radius: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """An open hemispherical bowl, bottom at the origin, rim at z = radius, opening up; the
    coordinates rounded to 6 decimals (what an OBJ file holds, so a file round-trips exactly)."""
    pts = [[0.0, 0.0, 0.0]]
    for i in range(1, rings + 1):
        th = i * (np.pi / 2) / rings
        for j in range(segments):
            ph = 2 * np.pi * j / segments
            pts.append([radius * np.sin(th) * np.cos(ph), radius * np.sin(th) * np.sin(ph), radius - radius * np.cos(th)])
    faces = [[0, 1 + j, 1 + (j + 1) % segments] for j in range(segments)]
    for i in range(rings - 1):
        a, b = 1 + i * segments, 1 + (i + 1) * segments
        for j in range(segments):
            k = (j + 1) % segments
            faces += [[a + j, b + j, b + k], [a + j, b + k, a + k]]
    return np.round(np.array(pts), 6) + 0.0, np.array(faces)


def test_a_y_up_obj_read_with_up_axis_y_is_the_z_up_original_exactly(tmp_path):
    v, f = bowl_arrays()
    path = blender_obj(tmp_path / "bowl.obj", v, f)
    m = kinema.Mesh(path, up_axis="y")
    assert m.up_axis == "y"
    assert np.array_equal(m.vertices, v)  # exactly: a permutation and a sign
    assert np.array_equal(m.faces, f)
    # read as +z up it lies on its side: the rim (y' = ...) is where z was
    side = kinema.Mesh(path)
    assert side.up_axis == "z" and np.array_equal(side.vertices, np.stack([v[:, 0], v[:, 2], -v[:, 1]], axis=1) + 0.0)
    # arrays take the axis too, and then the transform: x' = R (s ⊙ U x) + t
    arrays = kinema.Mesh(vertices=side.vertices, faces=f, up_axis="Y", translation=[0, 0, 1])
    assert np.array_equal(arrays.vertices, v + [0.0, 0.0, 1.0])
    with pytest.raises(ValueError, match=r"up_axis = 'x' is invalid: use \"z\".*or \"y\""):
        kinema.Mesh(path, up_axis="x")


def test_gltf_and_usd_say_their_own_up_axis(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    v, f = bowl_arrays()
    gl = trimesh.Trimesh(vertices=np.stack([v[:, 0], v[:, 2], -v[:, 1]], axis=1), faces=f, process=False)
    gl.export(tmp_path / "bowl.glb")  # glTF's own axes: +y up
    m = kinema.Mesh(tmp_path / "bowl.glb")
    assert m.up_axis == "y" and np.allclose(m.vertices, v, rtol=0, atol=1e-7)  # (glTF stores float32)
    assert np.array_equal(kinema.Mesh(tmp_path / "bowl.glb", up_axis="y").vertices, m.vertices)
    with pytest.raises(ValueError, match=r"up_axis = 'z' is invalid for .*bowl\.glb: a glTF file says its own up axis \(\+y by the glTF specification\)"):
        kinema.Mesh(tmp_path / "bowl.glb", up_axis="z")
    pytest.importorskip("pxr")
    from pxr import Gf, Usd, UsdGeom

    for up, points in (("y", np.stack([v[:, 0], v[:, 2], -v[:, 1]], axis=1)), ("z", v)):
        stage = Usd.Stage.CreateNew(str(tmp_path / f"bowl_{up}.usda"))
        UsdGeom.SetStageMetersPerUnit(stage, 1.0)
        UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y if up == "y" else UsdGeom.Tokens.z)
        mesh = UsdGeom.Mesh.Define(stage, "/bowl")
        mesh.CreatePointsAttr([Gf.Vec3f(*p) for p in points.tolist()])
        mesh.CreateFaceVertexCountsAttr([3] * len(f))
        mesh.CreateFaceVertexIndicesAttr(f.reshape(-1).tolist())
        stage.GetRootLayer().Save()
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # a stated up axis and unit: nothing to say
            u = kinema.Mesh(tmp_path / f"bowl_{up}.usda")
        assert u.up_axis == up and np.allclose(u.vertices, v, rtol=0, atol=1e-7), up


def test_the_scene_key_up_axis_goes_there_and_back(tmp_path):
    v, f = bowl_arrays()
    blender_obj(tmp_path / "bowl.obj", v, f)
    text = '[world]\ndim = 3\n[[colliders]]\ntype = "mesh"\nfile = "bowl.obj"\nup_axis = "y"\n'
    (tmp_path / "s.toml").write_text(text)
    w = kinema.load_scene(tmp_path / "s.toml")
    assert w.colliders[0].up_axis == "y" and np.array_equal(w.colliders[0].vertices, v)
    scene = w.to_scene()
    assert scene.colliders[0].up_axis == "y"
    back = kinema.load_scene(scene.to_toml(tmp_path / "back.toml"))
    assert np.array_equal(back.colliders[0].vertices, v)
    with pytest.raises(kinema.SceneError, match=r"colliders\[0\]\.up_axis"):
        Scene.from_string(text.replace('"y"', '"x"'))
