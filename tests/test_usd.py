"""USD export read back by Pixar's own library (usd-core): the Points prim's time samples, the
stage's time and units, the colliders as prims."""

import subprocess
import sys

import numpy as np
import pytest

import kinema

pxr = pytest.importorskip("pxr")
from pxr import Gf, Usd, UsdGeom  # noqa: E402


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
    mass = UsdGeom.PrimvarsAPI(points).GetPrimvar("mass")
    np.testing.assert_array_equal(np.array(mass.Get()), np.float32([1, 2, 3]))


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
    assert stage.GetFramesPerSecond() == pytest.approx(1 / 0.017, rel=1e-12)
    points = UsdGeom.Points(stage.GetPrimAtPath("/World/particles"))
    wrong = 0
    for k in range(frames):
        live = traj.alive[k] if traj.alive is not None else slice(None)
        got = np.array(points.GetPointsAttr().Get(Usd.TimeCode(float(k))))
        ids = np.array(points.GetIdsAttr().Get(Usd.TimeCode(float(k))))
        expected = traj.positions[k][live].astype(np.float32)
        wrong += not (got.shape == expected.shape and np.array_equal(got, expected) and np.array_equal(ids, traj.ids[live]))
    assert wrong == 0, f"{wrong} of {frames} frames wrong at whole time codes"


def test_the_colliders_are_guide_prims_where_the_world_has_them(tmp_path):
    _run().export(tmp_path / "run.usda")
    stage = Usd.Stage.Open(str(tmp_path / "run.usda"))
    box, plane, sphere = (stage.GetPrimAtPath(f"/World/colliders/{n}") for n in ("box_0", "plane_1", "sphere_2"))
    assert [p.GetAttribute("kinema:collider").Get() for p in (box, plane, sphere)] == ["box", "plane", "sphere"]
    assert all(UsdGeom.Imageable(p).GetPurposeAttr().Get() == UsdGeom.Tokens.guide for p in (box, plane, sphere))
    cache = UsdGeom.XformCache()
    bound = UsdGeom.Cube(box).ComputeWorldBound(Usd.TimeCode.Default(), UsdGeom.Tokens.default_, UsdGeom.Tokens.guide).ComputeAlignedRange()
    np.testing.assert_allclose(np.array([bound.GetMin(), bound.GetMax()]), [[0, 0, 0], [1, 1, 2]], atol=1e-12)  # the box's corners
    # the plane's z axis is the normal (0, 1, 1)/√2 and it passes through (0, 0, 0.1)
    m = cache.GetLocalToWorldTransform(plane)
    normal = np.array(m.TransformDir(Gf.Vec3d(0, 0, 1)))
    np.testing.assert_allclose(normal / np.linalg.norm(normal), np.array([0, 1, 1]) / np.sqrt(2), atol=1e-6)
    origin = np.array(m.Transform(Gf.Vec3d(0, 0, 0)))
    assert np.dot(origin - [0, 0, 0.1], np.array([0, 1, 1]) / np.sqrt(2)) == pytest.approx(0.0, abs=1e-9)
    assert UsdGeom.Sphere(sphere).GetRadiusAttr().Get() == 0.1
    np.testing.assert_allclose(np.array(cache.GetLocalToWorldTransform(sphere).ExtractTranslation()), [0.5, 0.5, 0.2])


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
