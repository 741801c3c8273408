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


# -- where a mesh collider lies ---------------------------------------------------------------


def placement_warnings(world, seconds=0.01):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        world.run(seconds, fps=100)
    return [str(c.message) for c in caught if issubclass(c.category, kinema.MeshPlacementWarning)]


def poured_into(mesh, **emitter):
    w = kinema.World(dt=1e-3)
    w.add(kinema.Gravity())
    w.add(mesh)
    w.add(kinema.Emitter(rate=100, shape="disc", center=[0, 0, 0.8], radius=0.05, normal=[0, 0, -1], particle_radius=0.01, mass=0.01, **emitter))
    return w


def test_a_bowl_on_its_side_is_said_and_an_upright_one_is_not(tmp_path):
    v, f = bowl_arrays()
    path = blender_obj(tmp_path / "bowl.obj", v, f)
    # the case: a Blender OBJ read as +z-up, its opening facing −y
    said = placement_warnings(poured_into(kinema.Mesh(path)))
    assert len(said) == 1
    assert said[0].startswith("colliders[0], the mesh 'bowl.obj': it lies on its side: the axis of its opening")
    assert "leans 90° from the vertical" in said[0] and "give up_axis='y'" in said[0]
    # read upright: nothing to say (the example bowl too, 19,800 triangles)
    assert placement_warnings(poured_into(kinema.Mesh(path, up_axis="y"))) == []
    assert placement_warnings(poured_into(kinema.Mesh(SCENES / "bowl.obj"))) == []
    # tipped 45°: within 60° of the vertical; 75°: on its side
    assert placement_warnings(poured_into(kinema.Mesh(path, up_axis="y", rotation=[45, 0, 0]))) == []
    assert len(placement_warnings(poured_into(kinema.Mesh(path, up_axis="y", rotation=[75, 0, 0])))) == 1
    # no gravity: no side to lie on; a flat sheet stood up is a wall, not a bowl
    w = kinema.World(dt=1e-3)
    w.add(kinema.Mesh(path))
    w.add_particles([0.0, 0.0, 0.3], radius=0.01)
    assert placement_warnings(w) == []
    wall = kinema.Mesh(vertices=[[0, 0, 0], [1, 0, 0], [1, 0, 1], [0, 0, 1]], faces=[[0, 1, 2], [0, 2, 3]])
    assert placement_warnings(poured_into(wall)) == []


def test_a_mesh_far_from_everything_is_said_once():
    v, f = bowl_arrays()
    far = kinema.Mesh(vertices=v, faces=f, translation=[5, 0, 0])  # 1 m wide, 0.5 m deep (diagonal 1.5 m), 4.5 m away
    w = poured_into(far)
    said = placement_warnings(w)
    assert len(said) == 1 and said[0].startswith("colliders[0], the mesh of arrays: every particle and emitter lies outside its bounding box")
    assert "by more than its size (1.5 m), the nearest 4.46 m away" in said[0]  # the spout: (4.45, 0, 0.3) m from the box
    assert placement_warnings(w) == []  # once: the next run says nothing
    # a particle near it, or an emitter's source: nothing to say
    w = poured_into(kinema.Mesh(vertices=v, faces=f, translation=[5, 0, 0]))
    w.add_particles([5.0, 0.0, 1.0], radius=0.01)
    assert placement_warnings(w) == []
    w = kinema.World(dt=1e-3)
    w.add(kinema.Mesh(vertices=v, faces=f, translation=[5, 0, 0]))
    w.add(kinema.Emitter(rate=10, shape="box", center=[5, 0, 2], size=[1, 1, 1], mass=1.0))
    assert placement_warnings(w) == []
    # nothing to collide yet: nothing to say
    w = kinema.World(dt=1e-3)
    w.add(kinema.Mesh(vertices=v, faces=f, translation=[5, 0, 0]))
    assert placement_warnings(w) == []


def test_a_mesh_too_coarse_for_the_particles_is_said_and_a_ball_falls_through_it():
    # A floor of two triangles, a 5 cm ball 7 cm from their seam: float64 numbers at 1e15 m
    # are 0.125 m apart, more than the ball: it falls through (z = −4.7 m after 1 s), and
    # the warning says so; at 1e8 m (1.5e-8 m apart) it rests at z = r and nothing is said.
    def floor(half_width):
        w = kinema.World(dt=1e-3)
        w.add(kinema.Gravity())
        v = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float) * [half_width, half_width, 1]
        w.add(kinema.Mesh(vertices=v, faces=[[0, 1, 2], [0, 2, 3]]))
        w.set_collisions(restitution=0.3)
        w.add_particles([[0.3, 0.2, 0.2]], radius=0.05)
        return w

    coarse = floor(1e15)
    said = placement_warnings(coarse, seconds=1.0)
    assert len(said) == 1 and "it is too coarse for the particles: its coordinates reach 1e+15 m, where numbers are 0.125 m apart" in said[0]
    assert coarse.positions[0, 2] < -1.0  # through the seam
    fine = floor(1e8)
    assert placement_warnings(fine, seconds=1.0) == []
    assert fine.positions[0, 2] == pytest.approx(0.05, abs=1e-6)
