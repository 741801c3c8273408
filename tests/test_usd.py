"""USD export read back by Pixar's own library (usd-core): the Points prim's time samples and
primvars (ids, colours, species), the stage's time and units, the springs as curves, the
colliders as meshes. tests/test_usd_blender.py imports the same stages into Blender."""

import dataclasses
import subprocess
import sys

import numpy as np
import pytest

import kinema

pxr = pytest.importorskip("pxr")
from pxr import Usd, UsdGeom  # noqa: E402


def srgb_to_linear(c):
    """sRGB-encoded values in [0, 1] to linear ones, as USD's colours are (IEC 61966-2-1)."""
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def speed_colours(traj, frame, columns, by_speed):
    """The linear colours of kinema's videos for ``columns`` at ``frame``: viridis of |v| from
    the lowest to the highest speed, over the run, of the live particles ``by_speed`` (N,)."""
    speed = np.linalg.norm(traj.velocities, axis=2)
    counted = speed[traj.alive & by_speed[None, :]]
    rgb8 = kinema.render.frames._core.colormap(speed[frame, columns], "viridis", float(counted.min()), float(counted.max()))
    return srgb_to_linear(rgb8 / 255.0)


def expected_colours(traj, frame):
    """The live particles' displayColor at ``frame``: their own colour where they have one,
    else by speed."""
    live = np.flatnonzero(traj.alive[frame])
    own = traj.colors if traj.colors is not None else np.full((traj.positions.shape[1], 3), np.nan)
    has_own = np.all(np.isfinite(own), axis=1)
    out = srgb_to_linear(np.where(has_own[:, None], own, 0.0))[live]
    if not has_own.all():
        by_speed = ~has_own[live]
        out[by_speed] = speed_colours(traj, frame, live[by_speed], ~has_own)
    return out


def fountain():
    """Births and deaths: two emitters, one with its colour and species "water", the other
    with species "oil" and no colour (by speed), a floor and an open-topped box."""
    w = kinema.World(dt=1e-3)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.add(kinema.Box([-0.5, -0.5, -1], [0.5, 0.5, np.inf]))
    w.add(
        kinema.Emitter(
            rate=400,
            shape="disc",
            center=[0, 0, 0.05],
            radius=0.05,
            speed=2.0,
            spread=10,
            lifetime=0.25,
            particle_radius=0.01,
            color="#2f7fd8",
            species="water",
            seed=3,
        )
    )
    w.add(
        kinema.Emitter(
            rate=200, shape="disc", center=[0.2, 0, 0.05], radius=0.05, speed=1.5, spread=10, lifetime=0.3, particle_radius=0.008, species="oil", seed=4
        )
    )
    traj = w.run(0.5, fps=30)
    assert traj.changes_count and traj.alive[0].sum() == 0 and traj.alive[-1].sum() < traj.alive.any(axis=0).sum()  # born and dead
    return traj


def cloth(deaths=False):
    """The example cloth on a sphere (springs, no colours: by speed); with ``deaths``, its
    first row of 20 particles is born at frame 2 and its last row dies at frame 5, so that
    the springs to them come and go."""
    traj = kinema.Scene.from_toml("examples/scenes/cloth_on_sphere.toml").build().run(0.3, fps=30)
    if not deaths:
        return traj
    alive = np.ones(traj.alive.shape, dtype=bool)
    alive[:2, :20] = False
    alive[5:, -20:] = False
    x, v = traj.positions.copy(), traj.velocities.copy()
    x[~alive] = v[~alive] = np.nan
    return dataclasses.replace(traj, positions=x, velocities=v, alive=alive)


def spring_ends(traj, frame):
    """(2 S', 3) the positions of the two ends of each spring whose ends are alive at ``frame``."""
    column = {int(i): k for k, i in enumerate(traj.ids)}
    pairs = np.array([[column[a], column[b]] for a, b in traj.springs if traj.alive[frame, column[a]] and traj.alive[frame, column[b]]]).reshape(-1, 2)
    return traj.positions[frame][pairs.reshape(-1)]


def _run():
    w = kinema.World(dt=0.01)
    w.add_particles([[0.2, 0.3, 0.5], [0.6, 0.5, 0.5], [0.4, 0.7, 0.8]], velocity=[[1, 0, 0], [0, 1, 0], [0, 0, -1]], radius=[0.05, 0.05, 0.1], mass=[1, 2, 3])
    w.add(kinema.Gravity())
    w.add(kinema.Box([0, 0, 0], [1, 1, 2]))
    w.add(kinema.Plane([0, 0, 0.1], [0, 1, 1]))
    w.add(kinema.SphereObstacle([0.5, 0.5, 0.2], 0.1))
    return w.run(0.2, fps=50)


@pytest.mark.parametrize("name", ["run.usd", "run.usda", "run.usdc"])
def test_usd_reads_the_time_samples_back(tmp_path, name):
    traj = _run()
    assert traj.export(tmp_path / name) == [tmp_path / name]
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]  # no staging folder left
    stage = Usd.Stage.Open(str(tmp_path / name))
    assert stage.GetTimeCodesPerSecond() == stage.GetFramesPerSecond() == pytest.approx(50.0, rel=1e-12)
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (0.0, 10.0)  # frame k at time code k
    assert UsdGeom.GetStageUpAxis(stage) == UsdGeom.Tokens.z and UsdGeom.GetStageMetersPerUnit(stage) == 1.0
    assert stage.GetDefaultPrim().GetPath() == "/World"
    points = UsdGeom.Points(stage.GetPrimAtPath("/World/particles"))
    assert points.GetPointsAttr().GetNumTimeSamples() == len(traj.t) == 11
    assert points.GetVelocitiesAttr().GetNumTimeSamples() == len(traj.t)
    time = stage.GetDefaultPrim().GetAttribute("kinema:time")
    for k, t in enumerate(traj.t):
        code = Usd.TimeCode(float(k))  # asked at whole frames, as Blender and Houdini ask
        assert time.Get(code) == t
        np.testing.assert_array_equal(np.array(points.GetPointsAttr().Get(code)), traj.positions[k].astype(np.float32))
        np.testing.assert_array_equal(np.array(points.GetVelocitiesAttr().Get(code)), traj.velocities[k].astype(np.float32))  # m/s: units per second
    np.testing.assert_array_equal(np.array(points.GetWidthsAttr().Get()), np.float32([0.1, 0.1, 0.2]))
    np.testing.assert_array_equal(np.array(points.GetIdsAttr().Get()), [0, 1, 2])
    primvars = UsdGeom.PrimvarsAPI(points)
    mass = primvars.GetPrimvar("mass")
    np.testing.assert_array_equal(np.array(mass.Get()), np.float32([1, 2, 3]))
    # the ids again as an int primvar `id`, which Blender's importer takes (it drops `ids`)
    ids = primvars.GetPrimvar("id")
    assert ids.GetTypeName() == "int[]" and ids.GetInterpolation() == UsdGeom.Tokens.vertex
    np.testing.assert_array_equal(np.array(ids.Get()), [0, 1, 2])
    # no colours of their own: by speed, a time sample per frame, kinema's videos' viridis
    color = points.GetDisplayColorPrimvar()
    assert color.GetInterpolation() == UsdGeom.Tokens.vertex and color.GetAttr().GetNumTimeSamples() == len(traj.t)
    for k in range(len(traj.t)):
        np.testing.assert_allclose(np.array(color.Get(Usd.TimeCode(float(k)))), expected_colours(traj, k), rtol=0, atol=1e-7)
    assert not primvars.HasPrimvar("species") and not stage.GetPrimAtPath("/World/springs")  # it has neither


def test_a_fountain_at_60_fps_gives_every_frame_at_its_whole_time_code(tmp_path):
    # The case: dt = 1 ms at fps = 60 records every 17 steps (58.8 frames a second);
    # time codes t × rate landed a hair past each whole frame, so an application asking at
    # whole frames got the previous frame in 172 of 182 (births and deaths change the points).
    w = kinema.World(dt=1e-3)
    w.add(kinema.Gravity())
    w.add(kinema.Emitter(rate=200, speed=2.0, direction=[0, 0, 1], spread=0.3, lifetime=0.5, particle_radius=0.01, seed=3))
    traj = w.run(1.0, fps=60)
    traj.export(tmp_path / "fountain.usdc")
    stage = Usd.Stage.Open(str(tmp_path / "fountain.usdc"))
    frames = len(traj.t)
    assert stage.GetEndTimeCode() == frames - 1
    # the 60 frames a second asked, exactly, though the frames are 17 ms apart (58.8 a second)
    assert stage.GetFramesPerSecond() == stage.GetTimeCodesPerSecond() == 60.0
    points = UsdGeom.Points(stage.GetPrimAtPath("/World/particles"))
    wrong = 0
    for k in range(frames):
        live = traj.alive[k] if traj.alive is not None else slice(None)
        got = np.array(points.GetPointsAttr().Get(Usd.TimeCode(float(k))))
        ids = np.array(points.GetIdsAttr().Get(Usd.TimeCode(float(k))))
        expected = traj.positions[k][live].astype(np.float32)
        wrong += not (got.shape == expected.shape and np.array_equal(got, expected) and np.array_equal(ids, traj.ids[live]))
    assert wrong == 0, f"{wrong} of {frames} frames wrong at whole time codes"


def test_an_emitters_stage_starts_at_its_first_frame_with_particles(tmp_path):
    # Blender 5.0 aborts (std::bad_alloc) exporting a point cloud of no points, which an
    # emitter's frame 0 imports as; its timeline is the stage's range, so the range starts at
    # the first frame with particles. Frame k stays at time code k, and every frame, the
    # empty ones too, is a time sample that kinema's reader gives back.
    traj = fountain()
    assert traj.alive[0].sum() == 0 and traj.alive[1].sum() > 0
    traj.export(tmp_path / "fountain.usdc")
    stage = Usd.Stage.Open(str(tmp_path / "fountain.usdc"))
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (1.0, len(traj.t) - 1)
    points = UsdGeom.Points(stage.GetPrimAtPath("/World/particles"))
    assert list(points.GetPointsAttr().GetTimeSamples()) == [float(k) for k in range(len(traj.t))]
    assert len(points.GetPointsAttr().Get(Usd.TimeCode(0.0))) == 0
    back = kinema.load_trajectory(tmp_path / "fountain.usdc")
    np.testing.assert_array_equal(back.alive, traj.alive)
    np.testing.assert_array_equal(back.t, traj.t)
    # the last frame with particles ends it; with none alive at all, the whole run
    x, v, alive = traj.positions.copy(), traj.velocities.copy(), traj.alive.copy()
    alive[-3:] = False
    x[~alive] = v[~alive] = np.nan
    dataclasses.replace(traj, positions=x, velocities=v, alive=alive).export(tmp_path / "ends.usdc")
    stage = Usd.Stage.Open(str(tmp_path / "ends.usdc"))
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (1.0, len(traj.t) - 4)
    alive[:] = False
    x[:] = v[:] = np.nan
    dataclasses.replace(traj, positions=x, velocities=v, alive=alive).export(tmp_path / "none.usdc")
    stage = Usd.Stage.Open(str(tmp_path / "none.usdc"))
    assert (stage.GetStartTimeCode(), stage.GetEndTimeCode()) == (0.0, len(traj.t) - 1)


def test_the_primvars_follow_the_live_particles(tmp_path):
    traj = fountain()
    traj.export(tmp_path / "fountain.usdc")
    stage = Usd.Stage.Open(str(tmp_path / "fountain.usdc"))
    points = UsdGeom.Points(stage.GetPrimAtPath("/World/particles"))
    primvars = UsdGeom.PrimvarsAPI(points)
    ids, species, color = primvars.GetPrimvar("id"), primvars.GetPrimvar("species"), points.GetDisplayColorPrimvar()
    assert species.GetTypeName() == "string[]" and species.GetInterpolation() == UsdGeom.Tokens.vertex
    for primvar in (ids, species, color):
        assert primvar.GetAttr().GetNumTimeSamples() == len(traj.t)
    water = traj.species == "water"
    assert np.all(np.isfinite(traj.colors[water])) and np.all(np.isnan(traj.colors[~water]))  # own colours and none
    assert list(points.GetPrim().GetAttribute("kinema:colorIds").Get()) == traj.ids[water].tolist()  # which colours are the particles' own
    for k in range(len(traj.t)):
        code, want = Usd.TimeCode(float(k)), traj.frame(k)
        assert len(np.array(points.GetPointsAttr().Get(code))) == len(want["ids"])
        np.testing.assert_array_equal(np.array(ids.Get(code)), want["ids"])
        assert list(species.Get(code)) == want["species"].tolist()
        got = np.array(color.Get(code)).reshape(-1, 3)
        np.testing.assert_allclose(got, expected_colours(traj, k), rtol=0, atol=1e-7)
        np.testing.assert_allclose(
            got[want["species"] == "water"], np.tile(srgb_to_linear(np.array([0x2F, 0x7F, 0xD8]) / 255), (np.sum(want["species"] == "water"), 1)), atol=1e-7
        )


def test_a_trajectory_with_its_own_colours_has_constant_ones(tmp_path):
    traj = _run()
    traj = dataclasses.replace(traj, colors=np.array([[1.0, 0.0, 0.0], [0.0, 0.5, 0.0], [0.2, 0.2, 1.0]]), species=np.array(["a", "b", "a"]))
    traj.export(tmp_path / "run.usda")
    stage = Usd.Stage.Open(str(tmp_path / "run.usda"))
    points = UsdGeom.Points(stage.GetPrimAtPath("/World/particles"))
    color = points.GetDisplayColorPrimvar()
    assert color.GetAttr().GetNumTimeSamples() == 0  # one value: the particles' colours never change
    np.testing.assert_allclose(np.array(color.Get()), [[1, 0, 0], [0, 0.21404114, 0], [0.03310477, 0.03310477, 1]], atol=1e-7)
    species = UsdGeom.PrimvarsAPI(points).GetPrimvar("species")
    assert species.GetAttr().GetNumTimeSamples() == 0 and list(species.Get()) == ["a", "b", "a"]
    assert list(points.GetPrim().GetAttribute("kinema:colorIds").Get()) == traj.ids.tolist()  # every colour the particle's own


@pytest.mark.parametrize("deaths", [False, True], ids=["cloth", "cloth with births and deaths"])
def test_the_springs_are_linear_curves_between_their_ends(tmp_path, deaths):
    traj = cloth(deaths)
    assert len(traj.springs) == 1482
    traj.export(tmp_path / "cloth.usdc")
    stage = Usd.Stage.Open(str(tmp_path / "cloth.usdc"))
    curves = UsdGeom.BasisCurves(stage.GetPrimAtPath("/World/springs"))
    assert curves.GetTypeAttr().Get() == UsdGeom.Tokens.linear and curves.GetWrapAttr().Get() == UsdGeom.Tokens.nonperiodic
    assert UsdGeom.Imageable(curves).ComputePurpose() == UsdGeom.Tokens.default_  # rendered, with the particles
    assert curves.GetPointsAttr().GetNumTimeSamples() == len(traj.t)
    counts = []
    for k in range(len(traj.t)):
        code = Usd.TimeCode(float(k))
        want = spring_ends(traj, k)
        np.testing.assert_array_equal(np.array(curves.GetPointsAttr().Get(code)).reshape(-1, 3), want.astype(np.float32))
        vertex_counts = np.array(curves.GetCurveVertexCountsAttr().Get(code))
        assert np.all(vertex_counts == 2) and len(vertex_counts) == len(want) // 2
        counts.append(len(vertex_counts))
    # an edge row of the 20 × 20 lattice has 77 springs: 19 along it, 20 to the next row and
    # 2 × 19 diagonals; they are gone where the row is not (born at frame 2, dead from 5)
    assert counts == ([1482] * len(traj.t) if not deaths else [1482 - 77] * 2 + [1482] * 3 + [1482 - 77] * (len(traj.t) - 5))
    assert np.array(curves.GetWidthsAttr().Get()).tolist() == [pytest.approx(0.012 / 2)]  # half the smallest radius, m
    # the ids at each spring's ends, for a reader: the curves' points alone do not tell them
    np.testing.assert_array_equal(np.array(curves.GetPrim().GetAttribute("kinema:springs").Get()).reshape(-1, 2), traj.springs)


def mesh_of(prim):
    """(points (P, 3), faces as lists of point indices) of a UsdGeom.Mesh."""
    mesh = UsdGeom.Mesh(prim)
    points = np.array(mesh.GetPointsAttr().Get(), dtype=np.float64)
    counts, indices = np.array(mesh.GetFaceVertexCountsAttr().Get()), np.array(mesh.GetFaceVertexIndicesAttr().Get())
    return points, [f.tolist() for f in np.split(indices, np.cumsum(counts)[:-1])]


def face_normal(points, face):
    """The face's normal by USD's right-handed orientation (counter-clockwise seen from it)."""
    p = points[face]
    n = sum(np.cross(p[i] - p[0], p[i + 1] - p[0]) for i in range(1, len(p) - 1))
    return n / np.linalg.norm(n)


def test_the_colliders_are_rendered_meshes_where_the_world_has_them(tmp_path):
    _run().export(tmp_path / "run.usda")
    stage = Usd.Stage.Open(str(tmp_path / "run.usda"))
    box, plane, sphere = (stage.GetPrimAtPath(f"/World/colliders/{n}") for n in ("box_0", "plane_1", "sphere_2"))
    assert [p.GetTypeName() for p in (box, plane, sphere)] == ["Mesh"] * 3
    assert [p.GetAttribute("kinema:collider").Get() for p in (box, plane, sphere)] == ["box", "plane", "sphere"]
    # the default purpose: rendered (a guide never renders), in kinema's colliders' material
    assert all(UsdGeom.Imageable(p).ComputePurpose() == UsdGeom.Tokens.default_ for p in (box, plane, sphere))
    assert all(UsdGeom.Mesh(p).GetSubdivisionSchemeAttr().Get() == UsdGeom.Tokens.none for p in (box, plane, sphere))
    # the box: its 8 corners, 6 quads whose normals point out of it
    points, faces = mesh_of(box)
    np.testing.assert_array_equal(points, [[x, y, z] for z in (0, 2) for y in (0, 1) for x in (0, 1)])
    assert len(faces) == 6 and all(len(f) == 4 for f in faces)
    normals = np.array([face_normal(points, f) for f in faces])
    centres = np.array([points[f].mean(axis=0) for f in faces])
    assert np.all(np.einsum("ij,ij->i", normals, centres - [0.5, 0.5, 1.0]) > 0)
    np.testing.assert_array_equal(np.abs(normals).sum(axis=0), [2, 2, 2])  # along the axes, each axis twice
    np.testing.assert_allclose(np.array(UsdGeom.Mesh(box).GetExtentAttr().Get()), [[0, 0, 0], [1, 1, 2]])
    # the plane: one quad in the plane through (0, 0, 0.1) with normal (0, 1, 1)/√2, as wide as the scene
    points, faces = mesh_of(plane)
    normal = np.array([0, 1, 1]) / np.sqrt(2)
    assert faces == [[0, 1, 2, 3]]
    np.testing.assert_allclose((points - [0, 0, 0.1]) @ normal, 0, atol=1e-6)
    np.testing.assert_allclose(face_normal(points, faces[0]), normal, atol=1e-6)
    sides = np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1)
    np.testing.assert_allclose(sides, sides[0], rtol=1e-6)
    assert sides[0] >= 2 * 1.0  # at least twice the scene's size (the box is 2 m tall)
    # the sphere: a UV sphere of 448 quads and 64 triangles on the sphere, facing out
    points, faces = mesh_of(sphere)
    np.testing.assert_allclose(np.linalg.norm(points - [0.5, 0.5, 0.2], axis=1), 0.1, rtol=1e-6)
    assert sorted(len(f) for f in faces) == [3] * 64 + [4] * 448 and len(points) == 482
    assert all(np.dot(face_normal(points, f), points[f].mean(axis=0) - [0.5, 0.5, 0.2]) > 0 for f in faces)


def _bowl_and_cube():
    """An open hemispherical bowl of 20 rings of 48 segments (1 + 20 * 48 points, 48 + 19 * 96
    triangles) about (0.5, 0.5, 1) and a closed cube of 12 triangles described inwards (its
    faces clockwise seen from outside): two {"type": "mesh"} descriptions."""
    rings, segments = 20, 48
    theta = np.linspace(0, np.pi / 2, rings + 1)[1:]
    phi = np.linspace(0, 2 * np.pi, segments, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    ring = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), -np.cos(t)], axis=-1).reshape(-1, 3)
    vertices = np.array([0.5, 0.5, 1.0]) + 0.5 * np.vstack([[0.0, 0.0, -1.0], ring])
    at = lambda i, j: 1 + i * segments + j % segments  # noqa: E731
    faces = [[0, at(0, j), at(0, j + 1)] for j in range(segments)]
    for i in range(rings - 1):
        for j in range(segments):
            faces += [[at(i, j), at(i + 1, j), at(i + 1, j + 1)], [at(i, j), at(i + 1, j + 1), at(i, j + 1)]]
    bowl = {"type": "mesh", "vertices": vertices.tolist(), "faces": faces, "inside": False}
    corners = [[x, y, z] for z in (0.0, 0.2) for y in (0.0, 0.2) for x in (0.0, 0.2)]
    outward = [[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4], [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]]
    cube = {"type": "mesh", "vertices": corners, "faces": [[a, c, b] for a, b, c in outward], "inside": False}
    return bowl, cube


def test_a_mesh_collider_is_a_translucent_mesh_of_its_triangles(tmp_path):
    traj = _run()
    bowl, cube = _bowl_and_cube()
    traj.colliders = list(traj.colliders) + [bowl, cube, {"type": "mesh", "vertices": [[0, 0, 0]], "faces": [[0, 1, 2]]}]
    traj.export(tmp_path / "run.usda")
    stage = Usd.Stage.Open(str(tmp_path / "run.usda"))
    meshes = [stage.GetPrimAtPath(f"/World/colliders/mesh_{k}") for k in (3, 4)]
    assert all(p.IsValid() and p.GetTypeName() == "Mesh" for p in meshes)
    assert not stage.GetPrimAtPath("/World/colliders/mesh_5").IsValid()  # a face past its vertices: left out
    for prim, described in zip(meshes, (bowl, cube), strict=True):
        mesh = UsdGeom.Mesh(prim)
        assert prim.GetAttribute("kinema:collider").Get() == "mesh"
        assert mesh.ComputePurpose() == UsdGeom.Tokens.default_
        assert mesh.GetSubdivisionSchemeAttr().Get() == UsdGeom.Tokens.none and mesh.GetDoubleSidedAttr().Get()
        opacity = mesh.GetDisplayOpacityPrimvar()
        assert opacity.GetInterpolation() == UsdGeom.Tokens.constant and list(opacity.Get()) == pytest.approx([0.3])
        points, faces = mesh_of(prim)
        assert len(points) == len(described["vertices"]) and len(faces) == len(described["faces"])
        assert all(len(f) == 3 for f in faces)
        np.testing.assert_array_equal(points, np.float32(described["vertices"]))
        np.testing.assert_allclose(np.array(mesh.GetExtentAttr().Get()), [points.min(axis=0), points.max(axis=0)])
    assert (len(mesh_of(meshes[0])[0]), len(mesh_of(meshes[0])[1])) == (1 + 20 * 48, 48 + 19 * 96)
    # The open bowl keeps its triangles as described; the closed cube is turned to face out.
    assert mesh_of(meshes[0])[1] == bowl["faces"]
    points, faces = mesh_of(meshes[1])
    assert all(np.dot(face_normal(points, f), points[f].mean(axis=0) - 0.1) > 0 for f in faces)
    # Every collider is translucent.
    for name in ("box_0", "plane_1", "sphere_2"):
        assert list(UsdGeom.Mesh(stage.GetPrimAtPath(f"/World/colliders/{name}")).GetDisplayOpacityPrimvar().Get()) == pytest.approx([0.3])


def _moving_run():
    """A ball for 1 s (11 frames, 0.1 s apart) beside a sphere moving 1 m along x (a steady
    motion, described by hand) and a cube turning a quarter about z and rising (keyframes)
    above a still floor."""
    positions = np.zeros((11, 1, 3))
    positions[:, 0] = [2.0, 2.0, 0.5]
    zeros, three = np.zeros(11), np.zeros((11, 3))
    _, cube = _bowl_and_cube()
    half = [np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4)]
    cube["motion"] = {"times": [0.0, 1.0], "translations": [[0, 0, 0], [0, 0, 0.5]], "rotations": [[1, 0, 0, 0], half], "pivot": [0.1, 0.1, 0.1]}
    colliders = [
        {"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 1]},
        {"type": "sphere", "center": [0.0, 0.0, 0.5], "radius": 0.2, "motion": {"velocity": [1.0, 0.0, 0.0]}},
        cube,
    ]
    return kinema.Trajectory(
        t=np.arange(11) * 0.1,
        positions=positions,
        velocities=np.zeros_like(positions),
        kinetic=zeros,
        potential={},
        momentum=three,
        angular_momentum=three,
        contacts=np.zeros(11, dtype=int),
        impulse_balance=three,
        collision_energy_lost=zeros,
        radii=np.array([0.05]),
        colliders=colliders,
    )


def test_a_moving_collider_has_a_time_sampled_transform_from_its_motion(tmp_path):
    from kinema.render.descriptions import collider_poses

    traj = _moving_run()
    traj.export(tmp_path / "run.usda")
    stage = Usd.Stage.Open(str(tmp_path / "run.usda"))
    floor = UsdGeom.Xformable(stage.GetPrimAtPath("/World/colliders/plane_0"))
    assert floor.GetOrderedXformOps() == []  # still: no transform
    for name, described in (("sphere_1", traj.colliders[1]), ("mesh_2", traj.colliders[2])):
        prim = stage.GetPrimAtPath(f"/World/colliders/{name}")
        xform = UsdGeom.Xformable(prim)
        [op] = xform.GetOrderedXformOps()
        assert op.GetOpType() == UsdGeom.XformOp.TypeTransform
        assert op.GetTimeSamples() == [float(k) for k in range(11)]  # one per frame, at its time code
        poses = collider_poses(described, traj.t)
        for k in range(11):
            m = np.array(op.Get(Usd.TimeCode(k)))  # acts on row vectors: [R | o] transposed
            np.testing.assert_allclose(m[:, :3].T, poses[k], atol=1e-12)
            np.testing.assert_array_equal(m[:, 3], [0, 0, 0, 1])
        # The points are as described; the transform carries them where the motion puts them.
        points, _ = mesh_of(prim)
        at_end = np.array([xform.ComputeLocalToWorldTransform(Usd.TimeCode(10)).Transform(pxr.Gf.Vec3d(*map(float, p))) for p in points])
        np.testing.assert_allclose(at_end, points @ poses[10][:, :3].T + poses[10][:, 3], atol=1e-6)
    # The sphere is 1 m further along x at t = 1 s; the cube turned a quarter about its pivot and rose 0.5 m.
    sphere = UsdGeom.Xformable(stage.GetPrimAtPath("/World/colliders/sphere_1"))
    centre = sphere.ComputeLocalToWorldTransform(Usd.TimeCode(10)).Transform(pxr.Gf.Vec3d(0.0, 0.0, 0.5))
    np.testing.assert_allclose(list(centre), [1.0, 0.0, 0.5], atol=1e-12)
    cube = UsdGeom.Xformable(stage.GetPrimAtPath("/World/colliders/mesh_2"))
    corner = cube.ComputeLocalToWorldTransform(Usd.TimeCode(10)).Transform(pxr.Gf.Vec3d(0.2, 0.1, 0.1))
    np.testing.assert_allclose(list(corner), [0.1, 0.2, 0.6], atol=1e-12)
    # A motion the engine refuses is a ValueError naming the collider, and nothing is written.
    traj.colliders[1] = {**traj.colliders[1], "motion": {"velocity": [1.0, 0.0]}}
    with pytest.raises(ValueError, match=r"colliders\[1\]\.motion"):
        traj.export(tmp_path / "bad.usda")
    assert not (tmp_path / "bad.usda").exists()


def test_kinema_export_writes_usd_beside_the_trajectory(tmp_path):
    _run().save(tmp_path / "run.h5")
    out = subprocess.run([sys.executable, "-m", "kinema", "export", str(tmp_path / "run.h5"), "-f", "usd"], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    assert "wrote" in out.stdout and (tmp_path / "run.usd").exists()
    bad = subprocess.run(
        [sys.executable, "-m", "kinema", "export", str(tmp_path / "run.h5"), "-f", "usd", "-o", str(tmp_path / "x.ply")], capture_output=True, text=True
    )
    assert bad.returncode == 2 and "the suffix .ply is for --format ply, not --format usd" in bad.stderr


def test_without_usd_core_the_command_says_how_to_get_it(tmp_path):
    _run().save(tmp_path / "run.h5")
    code = f"import sys; sys.modules['pxr'] = None; sys.argv = ['kinema', 'export', {str(tmp_path / 'run.h5')!r}, '-f', 'usd']; from kinema.cli import main; main()"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 2, out.stderr
    assert "writing USD needs the usd-core package: pip install usd-core (or kinema[usd])" in out.stderr
    assert "Traceback" not in out.stderr and not (tmp_path / "run.usd").exists()


def bound_surface(stage, path):
    """The `UsdPreviewSurface` of the material bound to the prim at `path` (for all purposes)."""
    from pxr import UsdShade

    material, _ = UsdShade.MaterialBindingAPI(stage.GetPrimAtPath(path)).ComputeBoundMaterial()
    assert material, f"{path} has no bound material"
    source = material.GetSurfaceOutput().GetConnectedSources()[0][0].source
    shader = UsdShade.Shader(source.GetPrim())
    assert shader.GetIdAttr().Get() == "UsdPreviewSurface"
    return shader


def test_every_prim_a_render_shows_has_a_bound_preview_surface(tmp_path):
    from pxr import UsdShade

    traj = _run()
    traj.export(tmp_path / "run.usda")
    stage = Usd.Stage.Open(str(tmp_path / "run.usda"))
    # the particles: diffuseColor from their own displayColor, through a primvar reader
    # (Blender's importer makes an Attribute node of it; usdview, Houdini, Omniverse read it)
    shader = bound_surface(stage, "/World/particles")
    [source] = shader.GetInput("diffuseColor").GetConnectedSources()[0]
    reader = UsdShade.Shader(source.source.GetPrim())
    assert reader.GetIdAttr().Get() == "UsdPrimvarReader_float3" and source.sourceName == "result"
    assert reader.GetInput("varname").Get() == "displayColor"
    assert stage.GetPrimAtPath("/World/particles").HasAPI(UsdShade.MaterialBindingAPI)
    # the colliders: kinema's videos' plane grey (sRGB 150 150 142, linear here) at opacity 0.3
    for name in ("box_0", "plane_1", "sphere_2"):
        shader = bound_surface(stage, f"/World/colliders/{name}")
        np.testing.assert_allclose(np.array(shader.GetInput("diffuseColor").Get()), srgb_to_linear(np.array([150, 150, 142]) / 255), rtol=1e-6)
        assert shader.GetInput("opacity").Get() == pytest.approx(0.3)


@pytest.mark.parametrize(
    ("dt", "fps", "stored", "rate"),
    [
        (1e-3, 30, True, 30.0),  # frame k at k/30 s: the 30 asked
        (1e-3, 60, True, 60.0),  # frame k at k/60 s
        (1e-3, 30, False, 30.0),  # no fps kept (another program's file): the common rate within 2 %
        (0.01, 25, True, 25.0),  # every 4 steps: 1 / 0.04 = 24.999999999999996 from the times
        (1e-3, 40, False, 40.0),  # every 25 steps; no common rate near: the recording's, 40 exactly
        (1e-3, 1000 / 23, False, 1000 / 23),  # every 23 steps: 43.48 a second
    ],
)
def test_the_stage_plays_at_the_rate_asked(tmp_path, dt, fps, stored, rate):
    w = kinema.World(dt=dt)
    w.add_particles([[0, 0, 0]], velocity=[[1, 0, 0]], radius=0.1, mass=1.0)
    traj = w.run(0.5, fps=fps)
    if not stored:
        traj = dataclasses.replace(traj, fps=None)
    traj.export(tmp_path / "run.usda")
    stage = Usd.Stage.Open(str(tmp_path / "run.usda"))
    assert stage.GetTimeCodesPerSecond() == stage.GetFramesPerSecond() == pytest.approx(rate, rel=1e-12)
    if rate == round(rate):
        assert stage.GetFramesPerSecond() == rate  # exactly: 25, not 24.999999999999996


def test_kinemas_own_colliders_are_not_read_back_as_a_mesh(tmp_path):
    # Rendered now (the default purpose), they are still no mesh of the stage's: a kinema
    # stage given to kinema.Mesh holds none (kinema:collider marks them)
    from kinema.io.mesh_files import read_mesh

    _run().export(tmp_path / "run.usda")
    with pytest.raises(ValueError, match="no UsdGeom.Mesh prim"):
        read_mesh(tmp_path / "run.usda")


def test_a_blend_without_blender_is_refused_before_anything_is_written(tmp_path, monkeypatch):
    monkeypatch.setenv("KINEMA_BLENDER", str(tmp_path / "no-such-blender"))
    with pytest.raises(RuntimeError, match=r"no-such-blender.*\$KINEMA_BLENDER.*not an executable"):
        _run().export(tmp_path / "run.blend")
    assert list(tmp_path.iterdir()) == []
