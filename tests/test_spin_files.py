"""Spins in every file (issue 47): `World.run` records the angular velocities of a world with
spin (and the orientations, where the engine integrates them), and every format kinema writes
carries them, read back by kinema's readers and by the outside tool each format is for: h5py
(H5MD), OVITO and kinema's reader (LAMMPS dump), ASE and OVITO (extended XYZ), gsd (HOOMD's
GSD: orientation, HOOMD's angular momentum, moment of inertia), VTK's XML reader (ParaView's),
usd-core (a PointInstancer's orientations and angular velocities) and NumPy (CSV); the PLY
frames by kinema's reader.

The physics: a ball rolling without slipping on a floor (the impulse model, friction) records
ω = v / r about n × v̂ at every frame, the closed form of rolling; with the engine's
orientations its orientation after t is a turn by v t / r about that axis."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import kinema
from kinema.io import export
from kinema.io._quaternions import conjugate, hoomd_angmom, multiply, omega_of_angmom, pure, rotate

G = 9.81
HAS_ORIENTATIONS = hasattr(kinema.World, "orientations")


def rolling_ball(v0=0.8, r=0.05, seconds=0.5, fps=20):
    """A ball set rolling without slipping along x on the floor z = 0 (ω = v / r about y =
    n × x̂), friction 0.5, no restitution: nothing slows it, so it rolls on at v0."""
    w = kinema.World(dt=1e-4, spin=True)
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.add(kinema.Gravity([0.0, 0.0, -G]))
    w.set_collisions(restitution=0.0, friction=0.5)
    w.add_particles([0.0, 0.0, r], velocity=[v0, 0.0, 0.0], mass=0.3, radius=r, angular_velocity=[0.0, v0 / r, 0.0])
    return w, w.run(seconds, fps=fps)


def test_a_rolling_ball_records_omega_equal_to_v_over_r_about_n_cross_v():
    v0, r = 0.8, 0.05
    w, tr = rolling_ball(v0, r)
    assert tr.angular_velocities.shape == (len(tr.t), 1, 3)
    n = np.array([0.0, 0.0, 1.0])
    v = tr.velocities[:, 0]
    axis = np.cross(n, v / np.linalg.norm(v, axis=1)[:, None])
    # ω = (n × v̂) |v| / r at every frame, and |v| stays v0 (rolling: no slip, no loss)
    np.testing.assert_allclose(tr.angular_velocities[:, 0], axis * np.linalg.norm(v, axis=1)[:, None] / r, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(v, axis=1), v0, rtol=1e-9)
    np.testing.assert_array_equal(tr.angular_velocities[-1], w.angular_velocities)
    assert tr.inertia == pytest.approx([0.4 * 0.3 * r * r])  # a solid sphere's, World's default


@pytest.mark.skipif(not HAS_ORIENTATIONS, reason="the engine has no World.orientations yet")
def test_a_rolling_ball_turns_by_v_t_over_r_about_n_cross_v():
    v0, r = 0.8, 0.05
    _, tr = rolling_ball(v0, r)
    theta = v0 * tr.t / r  # the angle rolled through, about y = n × x̂
    expected = np.stack([np.cos(theta / 2), 0 * theta, np.sin(theta / 2), 0 * theta], axis=1)
    q = tr.orientations[:, 0]
    q = q * np.sign(np.sum(q * expected, axis=1))[:, None]  # q and -q are one turn
    np.testing.assert_allclose(q, expected, atol=1e-6)
    # the point that touched the floor at t = 0 (body -z) is turned by θ about y
    bottom = rotate(q, np.tile([0.0, 0.0, -r], (len(q), 1)))
    np.testing.assert_allclose(bottom, np.stack([-r * np.sin(theta), 0 * theta, -r * np.cos(theta)], axis=1), atol=1e-6 * r)


def test_no_spin_no_spin_arrays():
    w = kinema.World(dt=1e-3)
    w.add_particles([[0.0, 0.0, 0.0]], velocity=[[1.0, 0.0, 0.0]])
    tr = w.run(0.05, fps=100)
    assert tr.angular_velocities is None and tr.orientations is None and tr.inertia is None


def spinning_run():
    """A little spinning heap (births by a removal included, so ids are not columns): the
    world's angular velocities and, while the engine has none, orientations made up of
    random unit quaternions (the writers are tested; the engine's are tested above)."""
    w = kinema.World(dt=1e-3, spin=True)
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.add(kinema.Gravity([0.0, 0.0, -G]))
    w.set_collisions(restitution=0.5, friction=0.5)
    rng = np.random.default_rng(7)
    w.add_particles(
        rng.uniform([0.0, 0.0, 0.06], [0.6, 0.6, 0.4], (12, 3)),
        velocity=rng.normal(size=(12, 3)),
        mass=rng.uniform(0.1, 0.3, 12),
        radius=0.05,
        angular_velocity=rng.normal(scale=20.0, size=(12, 3)),
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kinema.PlacementWarning)
        tr = w.run(0.2, fps=25)
    if tr.orientations is None:
        q = rng.normal(size=tr.positions.shape[:2] + (4,))
        tr.orientations = q / np.linalg.norm(q, axis=2, keepdims=True)
    assert np.abs(tr.angular_velocities).max() > 1.0
    return tr


@pytest.fixture(scope="module")
def spinning():
    return spinning_run()


# -- kinema's own readers, every format ---------------------------------------------------------


@pytest.mark.parametrize(
    "name, exact",
    [
        ("run.h5", True),
        ("run.lammpstrj", True),
        ("run.xyz", True),
        ("run.csv", True),
        ("run.pvd", True),
        ("run.gsd", False),
        ("run.usda", False),
        ("run.ply", False),
    ],
)
def test_kinemas_readers_give_the_spins_back(tmp_path, spinning, name, exact):
    (spinning.save if name.endswith(".h5") else spinning.export)(tmp_path / name)
    back = kinema.Trajectory.load(tmp_path / name, units="si" if name.endswith(".lammpstrj") else None)
    if exact:
        np.testing.assert_array_equal(back.angular_velocities, spinning.angular_velocities)
        np.testing.assert_array_equal(back.orientations, spinning.orientations)
    else:  # float32 files (GSD's HOOMD schema, USD's arrays, PLY): ω exact in GSD's own log
        np.testing.assert_allclose(back.angular_velocities, spinning.angular_velocities, rtol=1e-6, atol=1e-6)
        np.testing.assert_allclose(back.orientations, spinning.orientations, atol=1e-6)
    if name.endswith((".h5", ".gsd")):
        np.testing.assert_allclose(back.inertia, spinning.inertia, rtol=1e-7)


def test_h5md_layout_of_the_spins(tmp_path, spinning):
    h5py = pytest.importorskip("h5py")
    spinning.save(tmp_path / "run.h5", units="MD")
    with h5py.File(tmp_path / "run.h5") as f:
        p = f["particles/all"]
        w = p["angular_velocity"]
        assert w["value"].attrs["unit"] == "ps-1" and w["step"].id == p["position/step"].id
        np.testing.assert_allclose(w["value"][()] * 1e12, spinning.angular_velocities, rtol=1e-15)
        assert "unit" not in p["orientation/value"].attrs
        np.testing.assert_array_equal(p["orientation/value"][()], spinning.orientations)
        assert p["moment_of_inertia/value"].attrs["unit"] == "u nm2"
    back = kinema.Trajectory.load(tmp_path / "run.h5")
    np.testing.assert_allclose(back.angular_velocities, spinning.angular_velocities, rtol=1e-15)


# -- the outside readers ------------------------------------------------------------------------


def test_ovito_reads_the_lammps_dump_spins(tmp_path, spinning):
    ovito_io = pytest.importorskip("ovito.io")
    export(spinning, tmp_path / "run.lammpstrj")
    header = next(line for line in (tmp_path / "run.lammpstrj").read_text().splitlines() if line.startswith("ITEM: ATOMS"))
    assert header.endswith("radius mass omegax omegay omegaz quatw quati quatj quatk group")
    pipeline = ovito_io.import_file(str(tmp_path / "run.lammpstrj"))
    for k in (0, len(spinning.t) - 1):
        p = pipeline.compute(k).particles
        order = np.argsort(p["Particle Identifier"][...])
        np.testing.assert_allclose(p["Angular Velocity"][...][order], spinning.angular_velocities[k], rtol=1e-14)
        # OVITO keeps a quaternion as X, Y, Z, W, in float32
        np.testing.assert_allclose(p["Orientation"][...][order], spinning.orientations[k][:, [1, 2, 3, 0]], atol=1e-7)


def test_ase_and_ovito_read_the_extxyz_spins(tmp_path, spinning):
    ase_io = pytest.importorskip("ase.io")
    export(spinning, tmp_path / "run.xyz")
    frames = ase_io.read(tmp_path / "run.xyz", index=":")
    for k, atoms in enumerate(frames):
        np.testing.assert_array_equal(atoms.arrays["omega"], spinning.angular_velocities[k])
        np.testing.assert_array_equal(atoms.arrays["orientation"], spinning.orientations[k][:, [1, 2, 3, 0]])  # x y z w
    ovito_io = pytest.importorskip("ovito.io")
    p = ovito_io.import_file(str(tmp_path / "run.xyz")).compute(1).particles
    np.testing.assert_allclose(p["Angular Velocity"][...], spinning.angular_velocities[1], rtol=1e-14)
    np.testing.assert_allclose(p["Orientation"][...], spinning.orientations[1][:, [1, 2, 3, 0]], atol=1e-7)  # (float32 in OVITO)


def test_gsd_holds_hoomds_orientation_angmom_and_moment_of_inertia(tmp_path, spinning):
    gsd_hoomd = pytest.importorskip("gsd.hoomd")
    export(spinning, tmp_path / "run.gsd")
    with gsd_hoomd.open(str(tmp_path / "run.gsd")) as f:
        for k, frame in enumerate(f):
            p = frame.particles
            q = p.orientation.astype(np.float64)
            np.testing.assert_allclose(q, spinning.orientations[k], atol=1e-7)
            np.testing.assert_allclose(p.moment_inertia, np.repeat(spinning.inertia[:, None], 3, axis=1), rtol=1e-7)
            # HOOMD's body-frame angular momentum ½ (q* ⊗ p).v is I ω_body, ω_body = q* ω q
            body = 0.5 * multiply(conjugate(q), p.angmom.astype(np.float64))[:, 1:]
            omega_body = multiply(multiply(conjugate(q), pure(spinning.angular_velocities[k])), q)[:, 1:]
            np.testing.assert_allclose(body, spinning.inertia[:, None] * omega_body, rtol=1e-5, atol=1e-9)
            np.testing.assert_allclose(
                omega_of_angmom(q, p.angmom.astype(np.float64), p.moment_inertia[:, 0]), spinning.angular_velocities[k], rtol=1e-5, atol=1e-4
            )
    ovito_io = pytest.importorskip("ovito.io")
    particles = ovito_io.import_file(str(tmp_path / "run.gsd")).compute(2).particles
    np.testing.assert_allclose(particles["Orientation"][...], spinning.orientations[2][:, [1, 2, 3, 0]], atol=1e-7)


def test_the_hoomd_angular_momentum_of_a_sphere_is_2_I_omega_times_q():
    rng = np.random.default_rng(3)
    q = rng.normal(size=(50, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    omega, inertia = rng.normal(size=(50, 3)), rng.uniform(0.1, 2.0, 50)
    p = hoomd_angmom(q, omega, inertia)
    np.testing.assert_allclose(p, 2 * inertia[:, None] * multiply(pure(omega), q), atol=1e-14)
    np.testing.assert_allclose(omega_of_angmom(q, p, inertia), omega, atol=1e-13)
    # its rotational energy, HOOMD's Σ L_body² / (2 I), is ½ I |ω|²
    body = 0.5 * multiply(conjugate(q), p)[:, 1:]
    np.testing.assert_allclose(np.sum(body**2, axis=1) / (2 * inertia), 0.5 * inertia * np.sum(omega**2, axis=1), rtol=1e-12)


def test_vtk_reads_the_spin_point_data(tmp_path, spinning):
    vtk_xml = pytest.importorskip("vtkmodules.vtkIOXML")
    from vtkmodules.util.numpy_support import vtk_to_numpy

    export(spinning, tmp_path / "run.pvd")
    for k in range(len(spinning.t)):
        reader = vtk_xml.vtkXMLPolyDataReader()
        reader.SetFileName(str(tmp_path / "run_vtk" / f"run_{k:05d}.vtp"))
        reader.Update()
        data = reader.GetOutput().GetPointData()
        np.testing.assert_array_equal(vtk_to_numpy(data.GetArray("angular_velocity")), spinning.angular_velocities[k])
        np.testing.assert_array_equal(vtk_to_numpy(data.GetArray("orientation")), spinning.orientations[k])


def test_usd_turns_a_point_instancer_of_balls_with_the_particles(tmp_path, spinning):
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom

    export(spinning, tmp_path / "run.usda")
    stage = Usd.Stage.Open(str(tmp_path / "run.usda"))
    spheres = UsdGeom.PointInstancer(stage.GetPrimAtPath("/World/spheres"))
    assert spheres and [str(p) for p in spheres.GetPrototypesRel().GetTargets()] == ["/World/spheres/prototypes/ball"]
    ball = UsdGeom.Mesh(stage.GetPrimAtPath("/World/spheres/prototypes/ball"))
    st = UsdGeom.PrimvarsAPI(ball).GetPrimvar("st")
    assert st.GetInterpolation() == UsdGeom.Tokens.faceVarying and len(st.Get()) == len(ball.GetFaceVertexIndicesAttr().Get())
    for k in range(len(spinning.t)):
        code = Usd.TimeCode(float(k))
        ids = np.array(spheres.GetIdsAttr().Get(code))
        np.testing.assert_array_equal(ids, spinning.ids)
        full = np.array([[q.GetReal(), *q.GetImaginary()] for q in spheres.GetOrientationsfAttr().Get(code)])
        half = np.array([[q.GetReal(), *q.GetImaginary()] for q in spheres.GetOrientationsAttr().Get(code)])
        np.testing.assert_allclose(full, spinning.orientations[k], atol=1e-7)
        np.testing.assert_allclose(half, spinning.orientations[k], atol=2e-3)  # (half floats: what Blender reads)
        np.testing.assert_allclose(np.radians(np.array(spheres.GetAngularVelocitiesAttr().Get(code))), spinning.angular_velocities[k], rtol=1e-6, atol=1e-5)
        # usd-core's own placing of each instance: scale r, turned by q, at the position
        transforms = spheres.ComputeInstanceTransformsAtTime(code, code)
        for j, m in enumerate(transforms):
            m = np.array(m)  # row vectors: x' = [x 1] m
            q = spinning.orientations[k, j]
            expected = spinning.radii[j] * rotate(np.tile(q, (3, 1)), np.eye(3))  # rows: the turned axes
            np.testing.assert_allclose(m[:3, :3], expected, atol=1e-6)
            np.testing.assert_allclose(m[3, :3], spinning.positions[k, j], atol=1e-6)


def test_numpy_reads_the_csv_spin_columns(tmp_path, spinning):
    export(spinning, tmp_path / "run.csv")
    table = np.genfromtxt(tmp_path / "run.csv", delimiter=",", names=True)
    assert table.dtype.names[-8:] == ("wx", "wy", "wz", "qw", "qx", "qy", "qz", "group")
    k = table["frame"] == 3
    np.testing.assert_array_equal(np.column_stack([table[c][k] for c in ("wx", "wy", "wz")]), spinning.angular_velocities[3])
    np.testing.assert_array_equal(np.column_stack([table[c][k] for c in ("qw", "qx", "qy", "qz")]), spinning.orientations[3])


def test_a_checkpointed_run_resumes_with_the_same_spins(tmp_path):
    def world():
        w = kinema.World(dt=1e-3, spin=True)
        w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
        w.add(kinema.Gravity([0.0, 0.0, -G]))
        w.set_collisions(restitution=0.5, friction=0.5)
        w.add_particles([[0.0, 0.0, 0.2], [0.3, 0.0, 0.1]], velocity=[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], radius=0.05, inertia=[1e-3, 2e-3])
        return w

    whole = world().run(0.4, fps=20)

    class Stop(Exception):
        pass

    def stop(w):
        if w.time > 0.25:
            raise Stop

    with pytest.raises(Stop):
        world().run(0.4, fps=20, checkpoint=tmp_path / "c.ckpt", checkpoint_every=0.1, callback=stop)
    _, resumed = kinema.resume_run(tmp_path / "c.ckpt")
    np.testing.assert_array_equal(resumed.angular_velocities, whole.angular_velocities)
    np.testing.assert_array_equal(resumed.inertia, [1e-3, 2e-3])
    if HAS_ORIENTATIONS:  # (the checkpoint keeps the world's orientations: the frames after it turn on from there)
        np.testing.assert_array_equal(resumed.orientations, whole.orientations)


def test_orientations_that_are_not_unit_quaternions_are_refused(tmp_path, spinning):
    bad = spinning_run()
    bad.orientations[2, 3] *= 1.01
    with pytest.raises(kinema.io.TrajectoryFileError, match=r"trajectory 'orientations' has \|q\| = 1.01.* a unit quaternion"):
        bad.save(tmp_path / "bad.h5")
    assert not (tmp_path / "bad.h5").exists()
