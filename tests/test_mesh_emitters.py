"""Emitters on a triangle mesh (issue 48, Blender's "Emit From" Faces, Verts, Volume): faces
drawn in proportion to their areas and points on them to rounding, directions the face
normals; vertices with their area-weighted normals; uniform inside a closed mesh; the same
births for the same seed bit for bit, whatever the step; and the scene table there and back.
The statistical tests draw thousands of births at fixed seeds: a χ² whose p-value falls below
1e-4 fails (a rule that ignored the areas, or a volume sampler biased to the box's corners,
gives p < 1e-30)."""

from __future__ import annotations

import tempfile

import numpy as np
import pytest
from scipy.stats import chisquare

import kinema
from kinema.scene import Scene

# Four triangles in four different planes, areas 0.125, 0.5, 2 and 4.5 m² (1 : 4 : 16 : 36),
# so each birth's triangle is known by the plane it lies in.
TRIANGLES = np.array(
    [
        [[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [0.0, 0.5, 0.0]],  # z = 0, normal +z
        [[2.0, 0.0, 0.0], [2.0, 1.0, 0.0], [2.0, 0.0, 1.0]],  # x = 2, normal +x
        [[0.0, -3.0, 0.0], [0.0, -3.0, 2.0], [2.0, -3.0, 0.0]],  # y = −3, normal +y: (b − a) × (c − a) = (0, 4, 0)
        [[0.0, 0.0, 5.0], [3.0, 3.0, 5.0], [3.0, 0.0, 8.0]],  # a tilted plane
    ]
)
AREAS = 0.5 * np.linalg.norm(np.cross(TRIANGLES[:, 1] - TRIANGLES[:, 0], TRIANGLES[:, 2] - TRIANGLES[:, 0]), axis=1)
NORMALS = np.cross(TRIANGLES[:, 1] - TRIANGLES[:, 0], TRIANGLES[:, 2] - TRIANGLES[:, 0]) / (2 * AREAS[:, None])


def scattered() -> kinema.Mesh:
    return kinema.Mesh(vertices=TRIANGLES.reshape(-1, 3), faces=np.arange(12).reshape(4, 3))


def octahedron(r: float = 1.0) -> kinema.Mesh:
    v = r * np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
    f = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]  # counter-clockwise from outside
    return kinema.Mesh(vertices=v, faces=f)


def cube() -> kinema.Mesh:
    """[−1, 1]³, 12 triangles facing out."""
    p = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=float) * 2 - 1
    quads = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [2, 3, 7, 6], [0, 4, 7, 3], [1, 2, 6, 5]]
    return kinema.Mesh(vertices=p, faces=[t for a, b, c, d in quads for t in ([a, b, c], [a, c, d])])


def births(mesh, n, emit_from="faces", speed=0.0, seed=7, dt=1e-3, **more):
    """The first n births of a mesh emitter (rate n per second for 1 s), at rest where they were
    born (speed 0) or with their initial velocities: (positions, velocities) by id."""
    w = kinema.World(dt=dt)  # no collider, no collisions: every place is free
    w.add(kinema.Emitter(rate=float(n), shape="mesh", mesh=mesh, emit_from=emit_from, end=1.0, speed=speed, mass=1.0, seed=seed, **more))
    w.step(int(np.ceil(1.0 / dt)) + 2)  # (births due by a step boundary join at the start of the step after it)
    assert len(w) == n and (np.diff(w.ids) > 0).all()
    return w.positions.copy(), w.velocities.copy()


def which_face(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each point's triangle (the plane nearest it) and its distance to that plane (m)."""
    d = np.abs(np.einsum("fk,nfk->nf", NORMALS, x[:, None, :] - TRIANGLES[None, :, 0]))
    k = d.argmin(axis=1)
    return k, d[np.arange(len(x)), k]


def test_faces_are_drawn_in_proportion_to_their_areas_and_births_lie_on_them():
    x, _ = births(scattered(), 20000)
    k, dist = which_face(x)
    assert dist.max() < 1e-12  # on the plane of its face, to rounding
    # and inside the triangle: barycentric coordinates >= 0
    a, b, c = (TRIANGLES[k, j] for j in range(3))
    n = np.cross(b - a, c - a)
    for p, q in ((a, b), (b, c), (c, a)):
        assert (np.einsum("ij,ij->i", np.cross(q - p, x - p), n) >= -1e-12).all()
    counts = np.bincount(k, minlength=4)
    expected = len(x) * AREAS / AREAS.sum()
    assert chisquare(counts, expected).pvalue > 1e-4, (counts, expected)
    # uniform on each triangle (the square-root rule): the largest one's four sub-triangles
    # (its midpoints cut it into four of equal area) get equal shares
    big = x[k == 3]
    a, b, c = TRIANGLES[3]
    lam = np.linalg.lstsq(np.stack([b - a, c - a], axis=1), (big - a).T, rcond=None)[0].T  # x = a + s (b − a) + t (c − a)
    s, t = lam[:, 0], lam[:, 1]
    part = np.where(s > 0.5, 0, np.where(t > 0.5, 1, np.where(s + t < 0.5, 2, 3)))
    assert chisquare(np.bincount(part, minlength=4)).pvalue > 1e-4


def test_without_spread_the_births_leave_along_their_faces_normals():
    x, _ = births(scattered(), 2000)
    _, v = births(scattered(), 2000, speed=2.0)  # the same births (the position stream is its own)
    k, _ = which_face(x)
    np.testing.assert_allclose(v, 2.0 * NORMALS[k], rtol=0, atol=1e-14)
    # a spread of 30°: within the cone about the face's normal, and filling it
    _, v = births(scattered(), 2000, speed=2.0, spread=30.0)
    cos = np.einsum("ij,ij->i", v / 2.0, NORMALS[k])
    assert cos.min() >= np.cos(np.radians(30)) - 1e-12 and cos.min() < np.cos(np.radians(28))
    # a closed mesh's normals point out, however its faces are wound
    flipped = kinema.Mesh(vertices=octahedron().vertices, faces=octahedron().faces[:, ::-1])
    x, _ = births(flipped, 500)
    _, v = births(flipped, 500, speed=1.0)
    assert (np.einsum("ij,ij->i", x, v) > 0).all()


def test_vertices_are_drawn_evenly_with_their_area_weighted_normals():
    x, _ = births(octahedron(), 6000, "vertices")
    _, v = births(octahedron(), 6000, "vertices", speed=1.0)
    corners = octahedron().vertices
    k = np.argmin(np.linalg.norm(x[:, None] - corners[None], axis=2), axis=1)
    assert np.array_equal(x, corners[k])  # exactly at a vertex
    np.testing.assert_allclose(v, corners[k], rtol=0, atol=1e-15)  # each vertex's four faces: its own direction
    assert chisquare(np.bincount(k, minlength=6)).pvalue > 1e-4


def test_volume_births_are_uniform_inside_a_closed_mesh():
    x, _ = births(cube(), 8000, "volume")
    assert (np.abs(x) <= 1.0).all()
    octant = (x[:, 0] > 0) * 4 + (x[:, 1] > 0) * 2 + (x[:, 2] > 0)
    assert chisquare(np.bincount(octant, minlength=8)).pvalue > 1e-4
    inner = (np.abs(x) < 0.5).all(axis=1)  # the inner cube: 1/8 of the volume
    assert chisquare([inner.sum(), (~inner).sum()], [len(x) / 8, len(x) * 7 / 8]).pvalue > 1e-4
    # an octahedron |x| + |y| + |z| <= 1 in a box of 8 times its volume: all inside, uniform
    x, _ = births(octahedron(), 8000, "volume", seed=3)
    assert (np.abs(x).sum(axis=1) <= 1.0 + 1e-12).all()
    octant = (x[:, 0] > 0) * 4 + (x[:, 1] > 0) * 2 + (x[:, 2] > 0)
    assert chisquare(np.bincount(octant, minlength=8)).pvalue > 1e-4
    # the inner octahedron of half the size holds 1/8 of the volume
    inner = np.abs(x).sum(axis=1) < 0.5
    assert chisquare([inner.sum(), (~inner).sum()], [len(x) / 8, len(x) * 7 / 8]).pvalue > 1e-4
    # an open mesh has no inside
    with pytest.raises(ValueError, match=r"emit_from = 'volume' needs a closed \(watertight\) mesh"):
        kinema.Emitter(rate=1, shape="mesh", mesh=scattered(), emit_from="volume", mass=1.0)


@pytest.mark.parametrize("emit_from", ["faces", "vertices", "volume"])
def test_the_same_seed_gives_the_same_births_bit_for_bit_at_any_step(emit_from):
    a = births(octahedron(), 300, emit_from, speed=1.0, spread=20.0, seed=11)
    b = births(octahedron(), 300, emit_from, speed=1.0, spread=20.0, seed=11)
    assert all(np.array_equal(p, q) for p, q in zip(a, b, strict=True))
    c = births(octahedron(), 300, emit_from, speed=1.0, spread=20.0, seed=12)
    assert not np.array_equal(a[0], c[0]) and not np.array_equal(a[1], c[1])
    # born one at a time (dt = 1 ms) or ten at a time (dt = 30 ms, 300/s): the same particles
    one, _ = births(octahedron(), 300, emit_from, seed=11)
    ten, _ = births(octahedron(), 300, emit_from, seed=11, dt=0.03)
    assert np.array_equal(one, ten)


def test_bad_mesh_emitters_are_refused_by_name(tmp_path):
    with pytest.raises(ValueError, match=r"shape = 'mesh' needs mesh = a kinema.Mesh or a mesh file's path"):
        kinema.Emitter(rate=1, shape="mesh", mass=1.0)
    with pytest.raises(ValueError, match=r"emit_from = 'edges' is invalid: use one of 'faces', 'volume', 'vertices'"):
        kinema.Emitter(rate=1, shape="mesh", mesh=cube(), emit_from="edges", mass=1.0)
    with pytest.raises(ValueError, match=r"a mesh is the source of shape = 'mesh' only"):
        kinema.Emitter(rate=1, shape="disc", mesh=cube(), mass=1.0)
    with pytest.raises(TypeError, match=r"mesh = .* is invalid: it must be a kinema.Mesh or a mesh file's path"):
        kinema.Emitter(rate=1, shape="mesh", mesh=3, mass=1.0)
    moving = kinema.Mesh(vertices=cube().vertices, faces=cube().faces, motion=kinema.Motion(velocity=(1, 0, 0)))
    with pytest.raises(ValueError, match=r"an emitter's mesh stays where it is placed"):
        kinema.Emitter(rate=1, shape="mesh", mesh=moving, mass=1.0)
    with pytest.raises(ValueError, match=r"2D world: a triangle mesh is 3D only"):
        kinema.World(dim=2).add(kinema.Emitter(rate=1, shape="mesh", mesh=cube(), mass=1.0))
    with pytest.raises(ValueError, match=r"file = '.*none\.obj' is invalid: no such file"):
        kinema.Emitter(rate=1, shape="mesh", mesh=tmp_path / "none.obj", mass=1.0)


SCENE = """
[world]
dim = 3
dt = 0.001

[[emitters]]
shape = "mesh"
emit_from = "faces"
rate = 500
end = 0.2
speed = 0.5
particle_radius = 0.002
mass = 0.001
seed = 4

[emitters.mesh]
file = "spout.obj"
up_axis = "y"
scale = 0.5
translation = [0, 0, 1]
"""


def test_a_scene_emits_from_a_mesh_file_beside_it_and_goes_there_and_back(tmp_path):
    o = octahedron()
    (tmp_path / "spout.obj").write_text(
        "\n".join([f"v {x:g} {z:g} {-y:g}" for x, y, z in o.vertices] + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in o.faces]) + "\n"
    )  # written +y up, as Blender does
    (tmp_path / "s.toml").write_text(SCENE)
    w = kinema.load_scene(tmp_path / "s.toml")
    src = w._emitters[0].c["mesh"]
    assert src.up_axis == "y" and np.array_equal(src.vertices, 0.5 * o.vertices + [0.0, 0.0, 1.0])
    scene = w.to_scene()  # (before the run: its scene would hold the particles born too)
    a = w.run(0.3, fps=50)
    assert a.alive[-1].sum() == 100
    assert scene.emitters[0].shape == "mesh" and scene.emitters[0].emit_from == "faces" and scene.emitters[0].mesh.up_axis == "y"
    back = kinema.load_scene(scene.to_toml(tmp_path / "back.toml"))
    b = back.run(0.3, fps=50)
    np.testing.assert_array_equal(a.positions, b.positions)
    np.testing.assert_array_equal(a.velocities, b.velocities)
    # a mesh of arrays goes into the table as its vertices and faces
    inline = kinema.World(dt=1e-3)
    inline.add(kinema.Emitter(rate=10, shape="mesh", mesh=cube(), emit_from="volume", mass=1.0))
    table = inline.to_scene().emitters[0].mesh
    assert table.file is None and np.array_equal(np.array(table.vertices), cube().vertices) and table.faces == cube().faces.tolist()
    with pytest.raises(kinema.SceneError, match=r"emitters\[0\]\.emit_from"):
        Scene.from_string(SCENE.replace('emit_from = "faces"', 'emit_from = "edges"'))


def test_a_checkpoint_goes_on_with_the_same_births():
    def world():
        w = kinema.World(dt=1e-3)
        w.add(kinema.Emitter(rate=400, shape="mesh", mesh=octahedron(), emit_from="volume", end=0.5, speed=0.3, mass=1.0, seed=2))
        return w

    whole, half = world(), world()
    whole.step(400)
    half.step(200)
    with tempfile.TemporaryDirectory() as tmp:
        again = kinema.World.load_checkpoint(half.save_checkpoint(f"{tmp}/c.ckpt"))
    again.step(200)
    assert np.array_equal(again.ids, whole.ids) and np.array_equal(again.positions, whole.positions)
