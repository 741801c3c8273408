"""Collision groups in trajectories, checkpoints and every file (issue 48): `World.run` records
each particle's group (`Trajectory.groups`), a checkpoint of a run in progress keeps them, and
every format kinema writes carries them, read back by kinema's readers and by the outside tool
each format is for: h5py (H5MD `collision_group`), OVITO (LAMMPS dump `group` column,
extended XYZ `group:I:1`, GSD), ASE (extended XYZ), gsd (`log/particles/collision_group`),
VTK's XML reader (`group` point data), usd-core (primvar `collisionGroup`), NumPy (CSV) and
plyfile (PLY `group`), each per particle id at each frame, while an emitter adds particles of
another group mid-run (the set of particles changes)."""

from __future__ import annotations

import csv
import dataclasses
import warnings

import numpy as np
import pytest

import kinema
from kinema.io import TrajectoryFileError, export

GROUPS = (0, 3, 7)  # the particles placed at the start, two of each
BORN = 5  # the emitter's


def grouped_world():
    w = kinema.World(dt=1e-3)
    x = np.array([[0.2 * k, 0.0, 0.0] for k in range(6)])
    w.add_particles(x, velocity=[0.1, 0.0, 0.0], radius=0.02, mass=0.01, group=[g for g in GROUPS for _ in range(2)])
    # four births in group 5, at t = 0.03, 0.04, 0.05 and 0.06 s
    w.add(kinema.Emitter(rate=100, speed=5.0, particle_radius=0.02, mass=0.01, start=0.03, end=0.065, center=(0.5, 0.5, 1.0), group=BORN, seed=3))
    return w


@pytest.fixture(scope="module")
def run():
    """(the world after the run, its trajectory): 7 frames, births in group 5 from t = 0.03 s."""
    w = grouped_world()
    tr = w.run(0.12, fps=50)
    assert tr.changes_count and tr.alive[0].sum() == 6 and tr.alive[-1].sum() == 10  # the set changed mid-run
    return w, tr


@pytest.fixture(scope="module")
def expected(run):
    """Each particle's group by its id, as the world has them at the end (nobody regrouped)."""
    w, _ = run
    return dict(zip(w.ids.tolist(), w.groups.tolist(), strict=True))


def check_frame(expected, tr, k, ids, groups, what):
    """`ids` (kinema's ids) and `groups` read from a file at frame `k`: the particles alive
    then, each in its group."""
    ids, groups = np.asarray(ids).astype(np.int64), np.asarray(groups)
    assert sorted(ids.tolist()) == tr.ids[tr.alive[k]].tolist(), what
    assert np.array_equal(groups, groups.astype(np.int64)), what  # whole numbers
    assert groups.astype(np.int64).tolist() == [expected[i] for i in ids.tolist()], f"{what}, frame {k}"


# -- the trajectory -----------------------------------------------------------------------------


def test_world_run_records_each_particles_group(run, expected):
    w, tr = run
    assert tr.groups.dtype == np.int64 and tr.groups.shape == tr.ids.shape
    assert tr.groups.tolist() == [expected[i] for i in tr.ids.tolist()]
    assert set(tr.groups.tolist()) == {*GROUPS, BORN}
    assert tr.frame(len(tr.t) - 1)["groups"].tolist() == [expected[i] for i in tr.frame(len(tr.t) - 1)["ids"].tolist()]


def test_a_world_without_groups_records_zeros():
    w = kinema.World(dt=1e-3)
    w.add_particles([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    tr = w.run(0.02, fps=100)
    assert tr.groups.tolist() == [0, 0]


def test_groups_out_of_range_are_refused_before_anything_is_written(tmp_path, run):
    _, tr = run
    bad = dataclasses.replace(tr, groups=np.where(tr.ids == 2, 32, tr.groups))
    for name in ("run.h5", "run.csv", "run.xyz", "run.lammpstrj", "run.pvd"):
        with pytest.raises(TrajectoryFileError, match=r"trajectory 'groups' has group\[2\] = 32 \(collision groups are integers in 0\.\.31\)"):
            (bad.save if name.endswith(".h5") else bad.export)(tmp_path / name)
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ValueError, match=r"groups has shape \(2,\); it must be \(particles,\) = \(10,\)"):
        dataclasses.replace(tr, groups=[1, 2])
    with pytest.raises(ValueError, match=r"groups has dtype float64; collision groups are integers"):
        dataclasses.replace(tr, groups=tr.groups + 0.5)


# -- kinema's own readers, every format ---------------------------------------------------------


@pytest.mark.parametrize("name", ["run.h5", "run.lammpstrj", "run.xyz", "run.csv", "run.pvd", "run.gsd", "run.usda", "run.ply"])
def test_kinemas_readers_give_the_groups_back(tmp_path, run, name):
    _, tr = run
    if name.endswith((".gsd",)):
        pytest.importorskip("gsd.hoomd")
    if name.endswith(".usda"):
        pytest.importorskip("pxr")
    (tr.save if name.endswith(".h5") else tr.export)(tmp_path / name)
    source = tmp_path / ("run_ply" if name.endswith(".ply") else name)
    back = kinema.Trajectory.load(source, units="si" if name.endswith(".lammpstrj") else None)
    np.testing.assert_array_equal(back.ids, tr.ids)
    np.testing.assert_array_equal(back.alive, tr.alive)
    assert back.groups is not None and back.groups.dtype == np.int64
    np.testing.assert_array_equal(back.groups, tr.groups)


def test_a_file_without_groups_reads_none(tmp_path, run):
    h5py = pytest.importorskip("h5py")
    _, tr = run
    tr.save(tmp_path / "run.h5")
    with h5py.File(tmp_path / "run.h5", "r+") as f:
        del f["particles/all/collision_group"]  # (a file kinema wrote before it wrote them)
    assert kinema.Trajectory.load(tmp_path / "run.h5").groups is None
    old = kinema.Trajectory.load(tmp_path / "run.h5")
    old.export(tmp_path / "run.csv")  # no groups: no column
    assert (tmp_path / "run.csv").read_text().splitlines()[0] == "frame,time,id,x,y,z,vx,vy,vz,mass,radius"
    assert kinema.Trajectory.load(tmp_path / "run.csv").groups is None


# -- the outside readers ------------------------------------------------------------------------


def test_h5py_reads_the_collision_group_element(tmp_path, run, expected):
    h5py = pytest.importorskip("h5py")
    _, tr = run
    tr.save(tmp_path / "run.h5")
    with h5py.File(tmp_path / "run.h5") as f:
        p = f["particles/all"]
        g = p["collision_group"]
        assert g["value"].dtype == np.int32 and g["step"].id == p["position/step"].id and g["time"].id == p["position/time"].id
        groups, ids = g["value"][()], p["id/value"][()]
        for k in range(len(tr.t)):
            here = ids[k] != p["id/value"].fillvalue
            assert (groups[k][~here] == -1).all()  # H5MD's fill value where a particle does not exist
            check_frame(expected, tr, k, ids[k][here], groups[k][here], "H5MD collision_group")


def test_ovito_reads_the_lammps_dump_group_column(tmp_path, run, expected):
    ovito_io = pytest.importorskip("ovito.io")
    _, tr = run
    export(tr, tmp_path / "run.lammpstrj")
    header = next(line for line in (tmp_path / "run.lammpstrj").read_text().splitlines() if line.startswith("ITEM: ATOMS"))
    assert header == "ITEM: ATOMS id type x y z vx vy vz radius mass group"  # type: the species, as before
    pipeline = ovito_io.import_file(str(tmp_path / "run.lammpstrj"))
    assert pipeline.num_frames == len(tr.t)
    for k in range(len(tr.t)):
        p = pipeline.compute(k).particles
        check_frame(expected, tr, k, p["Particle Identifier"][...] - 1, p["group"][...], "OVITO, LAMMPS dump")
        assert (p["Particle Type"][...] == 1).all()


def test_ase_and_ovito_read_the_extxyz_group(tmp_path, run, expected):
    ase_io = pytest.importorskip("ase.io")
    _, tr = run
    export(tr, tmp_path / "run.xyz")
    frames = ase_io.read(tmp_path / "run.xyz", index=":")
    assert len(frames) == len(tr.t)
    for k, atoms in enumerate(frames):
        assert atoms.arrays["group"].dtype.kind == "i"
        check_frame(expected, tr, k, atoms.arrays["id"], atoms.arrays["group"], "ASE, extxyz")
    ovito_io = pytest.importorskip("ovito.io")
    pipeline = ovito_io.import_file(str(tmp_path / "run.xyz"))
    for k in range(len(tr.t)):
        p = pipeline.compute(k).particles
        check_frame(expected, tr, k, p["Particle Identifier"][...], p["group"][...], "OVITO, extxyz")


def test_gsd_reads_the_log_collision_group(tmp_path, run, expected):
    gsd_hoomd = pytest.importorskip("gsd.hoomd")
    _, tr = run
    export(tr, tmp_path / "run.gsd")
    with gsd_hoomd.open(str(tmp_path / "run.gsd")) as f:
        assert len(f) == len(tr.t)
        for k, frame in enumerate(f):
            groups = frame.log["particles/collision_group"]
            assert groups.dtype == np.int32 and len(groups) == frame.particles.N
            check_frame(expected, tr, k, frame.log["particles/kinema/id"], groups, "gsd")
    ovito_io = pytest.importorskip("ovito.io")
    pipeline = ovito_io.import_file(str(tmp_path / "run.gsd"))
    for k in range(len(tr.t)):
        p = pipeline.compute(k).particles
        check_frame(expected, tr, k, p["kinema_id"][...], p["collision_group"][...], "OVITO, GSD")


def test_vtk_reads_the_group_point_data(tmp_path, run, expected):
    vtk_xml = pytest.importorskip("vtkmodules.vtkIOXML")
    from vtkmodules.util.numpy_support import vtk_to_numpy

    _, tr = run
    export(tr, tmp_path / "run.pvd")
    for k in range(len(tr.t)):
        reader = vtk_xml.vtkXMLPolyDataReader()
        reader.SetFileName(str(tmp_path / "run_vtk" / f"run_{k:05d}.vtp"))
        reader.Update()
        data = reader.GetOutput().GetPointData()
        check_frame(expected, tr, k, vtk_to_numpy(data.GetArray("id")), vtk_to_numpy(data.GetArray("group")), "VTK")


def test_usd_has_a_collision_group_primvar(tmp_path, run, expected):
    pytest.importorskip("pxr")
    from pxr import Sdf, Usd, UsdGeom

    _, tr = run
    export(tr, tmp_path / "run.usda")
    stage = Usd.Stage.Open(str(tmp_path / "run.usda"))
    points = UsdGeom.Points(stage.GetPrimAtPath("/World/particles"))
    primvar = UsdGeom.PrimvarsAPI(points).GetPrimvar("collisionGroup")
    assert primvar and primvar.GetTypeName() == Sdf.ValueTypeNames.IntArray and primvar.GetInterpolation() == UsdGeom.Tokens.vertex
    for k in range(len(tr.t)):
        code = Usd.TimeCode(float(k))
        check_frame(expected, tr, k, np.array(points.GetIdsAttr().Get(code)), np.array(primvar.Get(code)), "usd-core")


def test_numpy_reads_the_csv_group_column(tmp_path, run, expected):
    _, tr = run
    export(tr, tmp_path / "run.csv")
    table = np.genfromtxt(tmp_path / "run.csv", delimiter=",", names=True)
    assert table.dtype.names[-1] == "group" and table.dtype.names[:11] == ("frame", "time", "id", "x", "y", "z", "vx", "vy", "vz", "mass", "radius")
    for k in range(len(tr.t)):
        here = table["frame"] == k
        check_frame(expected, tr, k, table["id"][here], table["group"][here], "CSV")
    with open(tmp_path / "run.csv", newline="") as f:
        assert {r["group"] for r in csv.DictReader(f)} == {str(g) for g in (*GROUPS, BORN)}  # whole numbers, as written


def test_plyfile_reads_the_group_property(tmp_path, run, expected):
    plyfile = pytest.importorskip("plyfile")
    _, tr = run
    paths = export(tr, tmp_path / "run.ply")
    for k, path in enumerate(paths):
        vertex = plyfile.PlyData.read(str(path))["vertex"]
        check_frame(expected, tr, k, vertex["id"], vertex["group"], "plyfile")


def test_the_ply_group_property_is_an_int(tmp_path, run, expected):
    # (plyfile is not always there: the header and the rows by NumPy, as PLY says them)
    _, tr = run
    path = export(tr, tmp_path / "run.ply")[-1]
    data = path.read_bytes()
    head, body = data.split(b"end_header\n", 1)
    props = [line.split()[1:] for line in head.decode("ascii").splitlines() if line.startswith("property")]
    assert ["int", "group"] in props
    types = {"float": "<f4", "int": "<i4", "uchar": "u1"}
    count = int(next(line.split()[2] for line in head.decode("ascii").splitlines() if line.startswith("element vertex")))
    rows = np.frombuffer(body, dtype=[(name, types[t]) for t, name in props], count=count)
    check_frame(expected, tr, len(tr.t) - 1, rows["id"], rows["group"], "PLY by NumPy")


# -- checkpoints --------------------------------------------------------------------------------


class Stop(Exception):
    pass


def test_a_checkpointed_run_resumes_with_the_same_groups(tmp_path, run):
    _, whole = run

    def stop(w):
        if w.time > 0.09:
            raise Stop

    # written at t = 0.08 s, after the last birth: every set of particles the trajectory has is
    # the checkpoint's (none is recorded after it), so their groups are the checkpoint's too
    with pytest.raises(Stop):
        grouped_world().run(0.12, fps=50, checkpoint=tmp_path / "c.ckpt", checkpoint_every=0.08, callback=stop)
    _, progress = kinema.checkpoint.load_run(tmp_path / "c.ckpt")
    sets = progress["recorder"].sets
    assert progress["frames_done"] == 4 and len(sets) > 2 and sets[-1][0].size == 10
    assert sets[-1][5].tolist() == [0, 0, 3, 3, 7, 7, 5, 5, 5, 5]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        w, resumed = kinema.resume_run(tmp_path / "c.ckpt")
    np.testing.assert_array_equal(resumed.ids, whole.ids)
    np.testing.assert_array_equal(resumed.alive, whole.alive)
    np.testing.assert_array_equal(resumed.groups, whole.groups)
    np.testing.assert_array_equal(resumed.positions, whole.positions)
    np.testing.assert_array_equal(w.groups, run[0].groups)
