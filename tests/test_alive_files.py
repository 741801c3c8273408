"""Births and deaths in every file kinema writes: a trajectory whose particles come and go
(``Trajectory.alive``), written in each format and read back by the outside tool that reads
it (h5py, pyh5md, gsd, ASE, OVITO, VTK, plyfile, pxr), each frame holding exactly the
particles alive at it, with their ids; and H5MD read back by kinema itself."""

import csv
import re

import numpy as np
import pytest

import kinema
from kinema.io import export, load_h5md, save_h5md
from kinema.io._cell import trajectory_cell
from kinema.io._files import frames_of

h5py = pytest.importorskip("h5py")

IDS = np.array([3, 5, 8, 11])
# frame 0, 1: 3, 5, 8; frame 2: 11 is born; frame 3: 5 and 8 have died; frame 4: 3 has died,
# only 11 is left; frame 5: no particle at all
ALIVE = np.array(
    [
        [1, 1, 1, 0],
        [1, 1, 1, 0],
        [1, 1, 1, 1],
        [1, 0, 0, 1],
        [0, 0, 0, 1],
        [0, 0, 0, 0],
    ],
    dtype=bool,
)
F, N = ALIVE.shape


def births_and_deaths(dim=3):
    """A trajectory with ``ALIVE``: random positions and velocities (NaN where not alive),
    distinct masses and radii, species, springs between ids."""
    rng = np.random.default_rng(7)
    x = rng.normal(size=(F, N, 3)) + [2.0, -1.0, 0.5]
    v = rng.normal(size=(F, N, 3))
    if dim == 2:
        x[..., 2] = v[..., 2] = 0.0
    x[~ALIVE] = np.nan
    v[~ALIVE] = np.nan
    zeros, three = np.zeros(F), np.zeros((F, 3))
    traj = kinema.Trajectory(
        t=np.arange(F) * 0.02,
        positions=x,
        velocities=v,
        kinetic=rng.random(F),
        potential={"gravity": rng.random(F)},
        momentum=three,
        angular_momentum=three,
        contacts=np.zeros(F, dtype=np.int64),
        impulse_balance=three,
        collision_energy_lost=zeros,
        masses=np.array([1.0, 2.5, 0.75, 4.0]),
        radii=np.array([0.01, 0.02, 0.03, 0.04]),
        ids=IDS.copy(),
        species=np.array(["grain", "Fe", "grain", "dust"]),
        dim=dim,
        dt=0.01,
        method="verlet",
        alive=ALIVE.copy(),
        springs=np.array([[3, 5], [8, 11]]),
    )
    assert traj.changes_count
    return traj


@pytest.fixture(scope="module")
def traj():
    return births_and_deaths()


def expected(traj, k):
    """The live particles of frame ``k``, by the trajectory itself."""
    return traj.frame(k)


def live_springs(traj, k):
    """The springs (pairs of ids, in the order of ``traj.springs``) whose two ends are alive at
    frame ``k``: [3, 5] at frames 0 and 1, both at frame 2, none after."""
    alive = set(traj.ids[traj.alive[k]].tolist())
    return [p for p in traj.springs.tolist() if p[0] in alive and p[1] in alive]


# -- H5MD ----------------------------------------------------------------------------------------


def test_h5md_round_trip_through_kinema(tmp_path, traj):
    back = kinema.load_trajectory(save_h5md(traj, tmp_path / "run.h5"))
    np.testing.assert_array_equal(back.alive, traj.alive)
    np.testing.assert_array_equal(back.ids, traj.ids)
    np.testing.assert_array_equal(back.positions, traj.positions)  # NaN where not alive, as written
    np.testing.assert_array_equal(back.velocities, traj.velocities)
    assert np.isnan(back.positions[~traj.alive]).all() and np.isfinite(back.positions[traj.alive]).all()
    np.testing.assert_array_equal(back.springs, traj.springs)
    np.testing.assert_array_equal(back.masses, traj.masses)
    np.testing.assert_array_equal(back.radii, traj.radii)
    assert back.species.tolist() == traj.species.tolist()
    assert back.changes_count
    for k in range(F):
        got, want = back.frame(k), expected(traj, k)
        for name in ("ids", "positions", "velocities", "masses", "radii", "species"):
            np.testing.assert_array_equal(got[name], want[name], err_msg=f"frame {k}: {name}")


def test_h5md_2d_round_trip(tmp_path):
    traj = births_and_deaths(dim=2)
    back = load_h5md(save_h5md(traj, tmp_path / "run.h5"))
    np.testing.assert_array_equal(back.alive, traj.alive)
    np.testing.assert_array_equal(back.positions, traj.positions)
    with h5py.File(tmp_path / "run.h5") as f:  # 3D, z = 0 (3D readers read it), dim = 2 a parameter
        assert f["particles/all/position/value"].shape == (F, N, 3) and f["parameters/kinema"].attrs["dim"] == 2


def test_h5md_layout_read_by_h5py(tmp_path, traj):
    # H5MD 1.1: the id element's value has a fill value, which marks the particles that do
    # not exist at a frame; the other per-particle datasets hold their own fill value there.
    path = save_h5md(traj, tmp_path / "run.h5")
    with h5py.File(path) as f:
        p = f["particles/all"]
        ids = p["id/value"]
        assert ids.shape == (F, N)
        assert ids.id.get_create_plist().fill_value_defined() == h5py.h5d.FILL_VALUE_USER_DEFINED
        fill = ids.fillvalue
        assert fill not in traj.ids
        table = ids[()]
        for k in range(F):
            present = table[k] != fill
            np.testing.assert_array_equal(table[k][present], expected(traj, k)["ids"])
            np.testing.assert_array_equal(p["position/value"][k][present], expected(traj, k)["positions"])
            np.testing.assert_array_equal(p["velocity/value"][k][present], expected(traj, k)["velocities"])
            np.testing.assert_array_equal(p["mass/value"][k][present], expected(traj, k)["masses"])
            assert np.isnan(p["position/value"][k][~present]).all() and np.isnan(p["mass/value"][k][~present]).all()
            assert (p["species/value"][k][~present] == p["species/value"].fillvalue).all()
        assert np.isnan(p["position/value"].fillvalue) and np.isnan(p["velocity/value"].fillvalue)
        springs = f["connectivity/springs"]
        np.testing.assert_array_equal(springs[()], traj.springs)
        assert f[springs.attrs["particles_group"]].name == "/particles/all"


def test_h5md_without_births_or_deaths_sets_no_fill_value(tmp_path, traj):
    whole = births_and_deaths()
    whole.alive[:] = True
    whole.positions = np.nan_to_num(whole.positions)
    whole.velocities = np.nan_to_num(whole.velocities)
    whole.springs = None
    path = save_h5md(whole, tmp_path / "run.h5")
    with h5py.File(path) as f:
        ids = f["particles/all/id/value"]
        assert ids.id.get_create_plist().fill_value_defined() != h5py.h5d.FILL_VALUE_USER_DEFINED
        assert "connectivity" not in f
    back = load_h5md(path)
    assert back.alive is None and back.springs is None
    assert not kinema.Trajectory.load(path).changes_count


def test_pyh5md_reads_the_file(tmp_path, traj):
    pyh5md = pytest.importorskip("pyh5md")
    path = save_h5md(traj, tmp_path / "run.h5")
    with pyh5md.File(str(path), "r") as f:
        g = f.particles_group("all")
        ids, position = pyh5md.element(g, "id"), pyh5md.element(g, "position")
        assert ids.element_type == "TimeElement"
        np.testing.assert_array_equal(ids.time[()], traj.t)
        table, x = ids.value[()], position.value[()]
        for k in range(F):
            present = table[k] != ids.value.fillvalue
            assert present.sum() == ALIVE[k].sum()
            np.testing.assert_array_equal(table[k][present], expected(traj, k)["ids"])
            np.testing.assert_array_equal(x[k][present], expected(traj, k)["positions"])


def test_h5md_of_another_layout_is_gathered_by_id(tmp_path, traj):
    # Another program's file: each frame's particles packed at the front, in reverse order of
    # their ids, the fill value after them (a slot holds different particles over time);
    # kinema gathers the entries by id, into one column per id.
    path = save_h5md(traj, tmp_path / "run.h5")
    with h5py.File(path, "r+") as f:
        p = f["particles/all"]
        fill = p["id/value"].fillvalue
        for k in range(F):
            want = expected(traj, k)
            m = len(want["ids"])
            p["id/value"][k] = np.concatenate([want["ids"][::-1], np.full(N - m, fill)])
            p["position/value"][k] = np.concatenate([want["positions"][::-1], np.full((N - m, 3), np.nan)])
            p["mass/value"][k] = np.concatenate([want["masses"][::-1], np.full(N - m, np.nan)])
        del p["velocity"], p["radius"], p["species"]
    back = load_h5md(path)
    np.testing.assert_array_equal(back.ids, traj.ids)
    np.testing.assert_array_equal(back.alive, traj.alive)
    np.testing.assert_array_equal(back.positions, traj.positions)
    np.testing.assert_array_equal(back.masses, traj.masses)
    np.testing.assert_array_equal(back.springs, traj.springs)


# -- GSD -----------------------------------------------------------------------------------------


def test_gsd_frames_hold_the_live_particles(tmp_path, traj):
    gsd_hoomd = pytest.importorskip("gsd.hoomd")
    export(traj, tmp_path / "run.gsd")
    with gsd_hoomd.open(str(tmp_path / "run.gsd"), mode="r") as f:
        assert len(f) == F
        for k, frame in enumerate(f):
            want = expected(traj, k)
            p = frame.particles
            assert p.N == ALIVE[k].sum() == len(p.position)
            assert frame.log["particles/kinema/id"].tolist() == want["ids"].tolist()
            origin = frame.log["kinema/origin"]
            np.testing.assert_array_equal(p.position, (want["positions"] - origin).astype(np.float32))
            np.testing.assert_array_equal(p.velocity, want["velocities"].astype(np.float32))
            np.testing.assert_array_equal(p.mass, want["masses"].astype(np.float32))
            np.testing.assert_array_equal(p.diameter, (2 * want["radii"]).astype(np.float32))
            assert [p.types[i] for i in p.typeid] == want["species"].tolist()
            # the springs whose ends are alive, as bonds between the frame's particles
            ids = frame.log["particles/kinema/id"]
            assert frame.bonds.N == len(live_springs(traj, k)) and list(frame.bonds.types) == ["spring"]
            assert ids[frame.bonds.group].tolist() == live_springs(traj, k)


def test_ovito_reads_the_gsd_file(tmp_path, traj):
    ovito_io = pytest.importorskip("ovito.io")
    export(traj, tmp_path / "run.gsd")
    pipeline = ovito_io.import_file(str(tmp_path / "run.gsd"))
    assert pipeline.source.num_frames == F
    for k in range(F):
        data, want = pipeline.compute(k), expected(traj, k)
        assert data.particles.count == ALIVE[k].sum()
        if data.particles.count:
            assert data.particles["kinema_id"][...].tolist() == want["ids"].tolist()
            origin = np.array(data.attributes["kinema/origin"])
            np.testing.assert_array_equal(data.particles.positions[...], (want["positions"] - origin).astype(np.float32))
        # OVITO's Bonds: the live springs (none at all in the frames without one)
        bonds = data.particles.bonds
        ids = data.particles["kinema_id"][...] if data.particles.count else np.zeros(0, dtype=np.int64)
        assert (ids[bonds.topology[...]].tolist() if bonds is not None and bonds.count else []) == live_springs(traj, k)


# -- LAMMPS dump ---------------------------------------------------------------------------------


@pytest.mark.filterwarnings("ignore:loadtxt")  # ASE's reader on the frame without atoms
def test_lammps_dump_read_by_ase_and_ovito(tmp_path, traj):
    export(traj, tmp_path / "run.lammpstrj")
    text = (tmp_path / "run.lammpstrj").read_text()
    counts = [int(line) for line in text.split("ITEM: NUMBER OF ATOMS\n")[1:] for line in line.splitlines()[:1]]
    assert counts == ALIVE.sum(axis=1).tolist()
    ase_io = pytest.importorskip("ase.io")
    from ase.calculators.lammps import convert

    frames = ase_io.read(tmp_path / "run.lammpstrj", index=":", format="lammps-dump-text", units="si")
    assert len(frames) == F
    for k, atoms in enumerate(frames):
        want = expected(traj, k)  # ASE sorts the atoms by id; the ids are ascending already
        assert len(atoms) == ALIVE[k].sum()
        np.testing.assert_array_equal(atoms.positions, convert(want["positions"].reshape(-1, 3), "distance", "si", "ASE"))
    ovito_io = pytest.importorskip("ovito.io")
    pipeline = ovito_io.import_file(str(tmp_path / "run.lammpstrj"))
    assert pipeline.source.num_frames == F
    for k in range(F):
        data, want = pipeline.compute(k), expected(traj, k)
        assert data.particles.count == ALIVE[k].sum()
        if data.particles.count:
            assert data.particles["Particle Identifier"][...].tolist() == (want["ids"] + 1).tolist()  # LAMMPS ids from 1
            np.testing.assert_array_max_ulp(data.particles.positions[...], want["positions"], maxulp=2)


# -- extended XYZ, CSV ---------------------------------------------------------------------------


def test_xyz_read_by_ase_and_ovito(tmp_path, traj):
    export(traj, tmp_path / "run.xyz")
    ase_io = pytest.importorskip("ase.io")
    frames = ase_io.read(tmp_path / "run.xyz", index=":", format="extxyz")
    assert len(frames) == F
    for k, atoms in enumerate(frames):
        want = expected(traj, k)
        assert len(atoms) == ALIVE[k].sum()
        if len(atoms):
            assert atoms.arrays["id"].tolist() == want["ids"].tolist()
            assert atoms.arrays["type"].tolist() == want["species"].tolist()
            np.testing.assert_array_equal(atoms.positions, want["positions"])
            np.testing.assert_array_equal(atoms.get_masses(), want["masses"])
    ovito_io = pytest.importorskip("ovito.io")
    pipeline = ovito_io.import_file(str(tmp_path / "run.xyz"))
    assert pipeline.source.num_frames == F
    for k in range(F):
        data, want = pipeline.compute(k), expected(traj, k)
        assert data.particles.count == ALIVE[k].sum()
        if data.particles.count:
            assert data.particles["Particle Identifier"][...].tolist() == want["ids"].tolist()
            np.testing.assert_array_max_ulp(data.particles.positions[...], want["positions"], maxulp=2)


def test_csv_rows_are_the_live_particles(tmp_path, traj):
    export(traj, tmp_path / "run.csv")
    with open(tmp_path / "run.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    for k in range(F):
        want = expected(traj, k)
        mine = [r for r in rows if int(r["frame"]) == k]
        assert [int(r["id"]) for r in mine] == want["ids"].tolist()
        np.testing.assert_array_equal(np.reshape([[float(r[c]) for c in "xyz"] for r in mine], (-1, 3)), want["positions"])
        np.testing.assert_array_equal([float(r["mass"]) for r in mine], want["masses"])


# -- VTK, PLY ------------------------------------------------------------------------------------


def test_vtk_frames_read_by_vtk(tmp_path, traj):
    vtk_xml = pytest.importorskip("vtkmodules.vtkIOXML")
    from vtkmodules.util.numpy_support import vtk_to_numpy

    paths = export(traj, tmp_path / "run.pvd")
    frames = [p for p in paths if re.fullmatch(r"run_\d{5}\.vtp", p.name)]
    assert len(frames) == F
    for k, path in enumerate(frames):
        # the frame's multi-block file: its particles and the springs whose ends are alive
        blocks = vtk_xml.vtkXMLMultiBlockDataReader()
        blocks.SetFileName(str(tmp_path / "run_vtk" / f"run_{k:05d}.vtm"))
        blocks.Update()
        springs = blocks.GetOutput().GetBlock(1)
        ends = np.column_stack([vtk_to_numpy(springs.GetCellData().GetArray(a)) for a in ("id1", "id2")])
        points = vtk_to_numpy(springs.GetPoints().GetData())
        assert springs.GetNumberOfLines() == len(ends) and springs.GetNumberOfPoints() == 2 * len(ends)
        if live_springs(traj, k):
            assert ends.tolist() == live_springs(traj, k)
            by_id = dict(zip(traj.ids.tolist(), traj.positions[k].tolist(), strict=True))
            np.testing.assert_array_equal(points, [by_id[i] for i in ends.reshape(-1).tolist()])
        else:  # none alive: one line of zero length between no particles (OVITO needs a line)
            cell = trajectory_cell(traj, frames_of(traj))
            assert ends.tolist() == [[-1, -1]] and points.tolist() == [((cell.lo + cell.hi) / 2).tolist()] * 2  # the middle of the scene
        reader = vtk_xml.vtkXMLPolyDataReader()
        reader.SetFileName(str(path))
        reader.Update()
        assert reader.GetErrorCode() == 0
        poly, want = reader.GetOutput(), expected(traj, k)
        assert poly.GetNumberOfPoints() == ALIVE[k].sum() == poly.GetNumberOfVerts()
        assert vtk_to_numpy(poly.GetPointData().GetArray("id")).tolist() == want["ids"].tolist()
        if poly.GetNumberOfPoints():
            np.testing.assert_array_equal(vtk_to_numpy(poly.GetPoints().GetData()), want["positions"])
            np.testing.assert_array_equal(vtk_to_numpy(poly.GetPointData().GetArray("radius")), want["radii"])


def test_ovito_reads_the_pvd(tmp_path, traj):
    ovito_io = pytest.importorskip("ovito.io")
    export(traj, tmp_path / "run.pvd")
    pipeline = ovito_io.import_file(str(tmp_path / "run.pvd"))
    assert pipeline.source.num_frames == F
    for k in range(F):
        data, want = pipeline.compute(k), expected(traj, k)
        assert data.particles.count == ALIVE[k].sum()
        if data.particles.count:
            assert data.particles["Particle Identifier"][...].tolist() == want["ids"].tolist()
            np.testing.assert_array_equal(data.particles.positions[...], want["positions"])
        # the springs file beside each frame's particles: OVITO's Lines between particle ids
        lines = [o for o in data.objects if type(o).__name__ == "Lines"]
        assert len(lines) == 1 and lines[0].identifier == "particle-particle-contacts"
        ends = np.column_stack([lines[0][f"Particle Identifier {j}"][...] for j in (1, 2)])[::2].tolist()
        assert ends == (live_springs(traj, k) or [[-1, -1]])  # none: one line of zero length, not the last frame's


def test_ply_frames_read_by_plyfile(tmp_path, traj):
    plyfile = pytest.importorskip("plyfile")
    paths = export(traj, tmp_path / "run.ply")
    assert len(paths) == F
    for k, path in enumerate(paths):
        vertex, want = plyfile.PlyData.read(str(path))["vertex"], expected(traj, k)
        assert vertex.count == ALIVE[k].sum()
        assert vertex["id"].tolist() == want["ids"].tolist()
        x = np.column_stack([vertex["x"], vertex["y"], vertex["z"]]) if vertex.count else np.zeros((0, 3), np.float32)
        np.testing.assert_array_equal(x, want["positions"].astype(np.float32))
        np.testing.assert_array_equal(vertex["radius"], want["radii"].astype(np.float32))
        edge = plyfile.PlyData.read(str(path))["edge"]  # the live springs, between the frame's vertices
        assert vertex["id"][np.column_stack([edge["vertex1"], edge["vertex2"]]).reshape(-1, 2)].tolist() == live_springs(traj, k)


# -- USD -----------------------------------------------------------------------------------------


def test_usd_time_samples_hold_the_live_particles(tmp_path, traj):
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom

    export(traj, tmp_path / "run.usda")
    stage = Usd.Stage.Open(str(tmp_path / "run.usda"))
    points = UsdGeom.Points(stage.GetPrimAtPath("/World/particles"))
    rate = stage.GetTimeCodesPerSecond()
    mass = UsdGeom.PrimvarsAPI(points).GetPrimvar("mass")
    for attr in (points.GetPointsAttr(), points.GetIdsAttr(), points.GetWidthsAttr(), points.GetVelocitiesAttr()):
        assert attr.GetNumTimeSamples() == F
    for k, t in enumerate(traj.t):
        code, want = Usd.TimeCode(t * rate), expected(traj, k)
        assert np.array(points.GetIdsAttr().Get(code)).tolist() == want["ids"].tolist()
        np.testing.assert_array_equal(np.array(points.GetPointsAttr().Get(code)).reshape(-1, 3), want["positions"].astype(np.float32))
        np.testing.assert_array_equal(np.array(points.GetVelocitiesAttr().Get(code)).reshape(-1, 3), want["velocities"].astype(np.float32))
        np.testing.assert_array_equal(np.array(points.GetWidthsAttr().Get(code)), (2 * want["radii"]).astype(np.float32))
        np.testing.assert_array_equal(np.array(mass.Get(code)), want["masses"].astype(np.float32))


# -- every format: the empty frame and a trajectory-like object ----------------------------------


@pytest.mark.parametrize("name", ["run.pvd", "run.ply", "run.xyz", "run.csv", "run.gsd", "run.lammpstrj", "run.usda"])
def test_every_format_writes_a_2d_run_whose_particles_come_and_go(tmp_path, name):
    if name.endswith(".gsd"):
        pytest.importorskip("gsd.hoomd")
    if name.endswith(".usda"):
        pytest.importorskip("pxr")
    traj = births_and_deaths(dim=2)
    paths = export(traj, tmp_path / name)
    assert all(p.exists() for p in paths)
