"""Exports that other tools open as they expect: extended XYZ in ASE's and OVITO's conventions
(masses, momenta, a real cell with its origin), CSV with mass and radius, one name per format
so that exports never collide, a suffix that contradicts the format refused, missing folders
created by `kinema export -o`, and files that follow the umask."""

import csv
import os
import shlex
import stat
import subprocess
import sys
import xml.etree.ElementTree as ET
from types import SimpleNamespace

import ase.io
import numpy as np
import pytest
from typer.testing import CliRunner

import kinema
from kinema.cli import app
from kinema.io import export
from kinema.io._cell import trajectory_cell
from kinema.io._files import frames_of

runner = CliRunner()
F, N = 4, 6


def synthetic(dim=3, masses=True, radii=True, seed=0, **extra):
    rng = np.random.default_rng(seed)
    x, v = rng.normal(size=(F, N, 3)) * 3.0 + 10.0, rng.normal(size=(F, N, 3))
    if dim == 2:
        x[..., 2] = v[..., 2] = 0.0
    return SimpleNamespace(
        t=np.arange(F) * 0.05,
        positions=x,
        velocities=v,
        masses=rng.random(N) + 0.5 if masses else None,
        radii=rng.random(N) * 0.2 if radii else None,
        ids=np.arange(N) + 10,
        dim=dim,
        **extra,
    )


def periodic_run(periodic=(True, True, False)):
    """A world in the box [-1, 1] × [-1, 1] × [0, 2], periodic along ``periodic``: the
    particles cross the periodic sides and come back on the other."""
    w = kinema.World(dt=0.01)
    rng = np.random.default_rng(2)
    w.add_particles(
        rng.uniform([-0.9, -0.9, 0.5], [0.9, 0.9, 1.5], size=(N, 3)), velocity=rng.normal(size=(N, 3)) * 3, mass=rng.uniform(0.5, 2, N), radius=0.05
    )
    w.add(kinema.Box([-1, -1, 0], [1, 1, 2]))
    w.periodic = periodic
    return w.run(1.0, fps=20)


def comment(path, frame=0):
    """The key=value pairs of a frame's comment line."""
    lines = path.read_text().splitlines()
    i = 0
    for _ in range(frame):
        i += int(lines[i]) + 2
    return dict(kv.split("=", 1) for kv in shlex.split(lines[i + 1]))


def assert_inside(atoms, origin, tol=0.0):
    """Every particle lies in the cell that starts at ``origin`` (ASE's cell starts at 0)."""
    s = atoms.cell.scaled_positions(atoms.positions - origin)
    assert (s >= -tol).all() and (s <= 1 + tol).all(), s


# -- extended XYZ read by ASE ---------------------------------------------------------------------


def xyz_cell(tr):
    """The cell the XYZ header states: (origin, edges, pbc)."""
    cell = trajectory_cell(tr, frames_of(tr))
    return cell.lo, cell.hi - cell.lo, cell.periodic


def test_ase_reads_positions_velocities_masses_and_the_cell(tmp_path):
    tr = synthetic()
    export(tr, tmp_path / "run.xyz")
    frames = ase.io.read(tmp_path / "run.xyz", index=":")
    assert len(frames) == F
    origin, edges, pbc = xyz_cell(tr)
    x = tr.positions.reshape(-1, 3)
    margin = tr.radii.max() + 0.05 * np.ptp(x, axis=0).max()
    np.testing.assert_allclose(origin, x.min(axis=0) - margin, rtol=1e-15)
    np.testing.assert_allclose(edges, np.ptp(x, axis=0) + 2 * margin, rtol=1e-15)
    for i, atoms in enumerate(frames):
        np.testing.assert_array_equal(atoms.positions, tr.positions[i])  # m, exactly
        np.testing.assert_allclose(atoms.get_velocities(), tr.velocities[i], rtol=1e-15, atol=0)  # momenta / masses, m/s
        np.testing.assert_array_equal(atoms.get_momenta(), tr.masses[:, None] * tr.velocities[i])
        np.testing.assert_array_equal(atoms.get_masses(), tr.masses)  # kg
        np.testing.assert_array_equal(atoms.arrays["velo"], tr.velocities[i])  # OVITO's Velocity
        np.testing.assert_array_equal(atoms.arrays["mass"], tr.masses)  # OVITO's Mass
        np.testing.assert_array_equal(atoms.arrays["radius"], tr.radii)
        np.testing.assert_array_equal(atoms.arrays["id"], tr.ids)
        assert atoms.get_chemical_symbols() == ["X"] * N
        assert atoms.info["Time"] == tr.t[i] and atoms.info["units"] == "SI"
        assert atoms.pbc.tolist() == [False, False, False]
        np.testing.assert_array_equal(atoms.cell.array, np.diag(edges))
        assert atoms.get_volume() == pytest.approx(np.prod(edges), rel=1e-14)
        np.testing.assert_array_equal(atoms.info["Origin"], origin)
        assert_inside(atoms, origin)
        # the spheres too: the margin holds the largest radius
        lo, hi = tr.positions[i] - tr.radii[:, None], tr.positions[i] + tr.radii[:, None]
        assert (lo > origin).all() and (hi < origin + edges).all()


def test_the_comment_line_says_the_units_and_ovitos_keys(tmp_path):
    export(synthetic(), tmp_path / "run.xyz")
    keys = comment(tmp_path / "run.xyz", frame=2)
    assert keys["Properties"] == "species:S:1:pos:R:3:velo:R:3:momenta:R:3:radius:R:1:mass:R:1:masses:R:1:id:I:1"
    assert keys["units"] == "SI" and keys["pbc"] == "F F F" and float(keys["Time"]) == 0.1
    assert len(keys["Lattice"].split()) == 9 and len(keys["Origin"].split()) == 3


@pytest.mark.parametrize("periodic", [(True, True, False), (True, True, True)])
def test_a_periodic_world_gives_its_box_as_the_cell(tmp_path, periodic):
    tr = periodic_run(periodic)
    export(tr, tmp_path / "run.extxyz")
    frames = ase.io.read(tmp_path / "run.extxyz", index=":")
    assert len(frames) == tr.t.size
    p = np.array(periodic)
    x = tr.positions.reshape(-1, 3)
    assert np.ptp(x[:, 0]) > 1.9  # the particles did cross the periodic sides
    for i, atoms in enumerate(frames):
        assert atoms.pbc.tolist() == list(periodic)
        origin = atoms.info["Origin"]
        edges = atoms.cell.lengths()
        np.testing.assert_array_equal(origin[p], [-1.0, -1.0, 0.0][: p.sum()])  # the box's lower corner
        np.testing.assert_array_equal(edges[p], [2.0, 2.0, 2.0][: p.sum()])  # the box's edges
        if not p[2]:  # open z: the extent of all frames and a margin
            assert origin[2] < x[:, 2].min() - 0.05 and origin[2] + edges[2] > x[:, 2].max() + 0.05
        assert atoms.get_volume() == pytest.approx(np.prod(edges), rel=1e-14)
        np.testing.assert_array_equal(atoms.positions, tr.positions[i])
        np.testing.assert_allclose(atoms.get_velocities(), tr.velocities[i], rtol=1e-15, atol=0)
        np.testing.assert_array_equal(atoms.get_masses(), tr.masses)
        assert_inside(atoms, origin)
    if all(periodic):  # a closed box: the cell is the box itself
        np.testing.assert_array_equal(frames[0].info["Origin"], [-1.0, -1.0, 0.0])
        assert frames[0].get_volume() == pytest.approx(8.0, rel=1e-15)


def test_a_periodic_axis_without_a_box_collider_starts_at_the_lowest_particle(tmp_path):
    tr = synthetic(periodic=(True, False, False), box_edges=np.array([50.0, 0.0, 0.0]))
    origin, edges, pbc = xyz_cell(tr)
    assert pbc.tolist() == [True, False, False] and edges[0] == 50.0
    assert origin[0] == tr.positions[..., 0].min()
    export(tr, tmp_path / "run.xyz")
    for atoms in ase.io.read(tmp_path / "run.xyz", index=":"):
        assert_inside(atoms, atoms.info["Origin"])


def test_a_periodic_axis_without_an_edge_is_refused(tmp_path):
    tr = synthetic(periodic=(False, True, False), box_edges=np.array([1.0, 0.0, 0.0]))
    with pytest.raises(ValueError, match=r"box_edges\[1\] = 0.0: a periodic axis needs its cell edge > 0 m"):
        export(tr, tmp_path / "run.xyz")
    assert not (tmp_path / "run.xyz").exists()


def test_no_edge_is_ever_zero(tmp_path):
    # A 2D run (z = 0 throughout) and a single particle at rest at the origin, no radius.
    flat = synthetic(dim=2)
    point = SimpleNamespace(t=np.array([0.0, 1.0]), positions=np.zeros((2, 1, 3)), velocities=np.zeros((2, 1, 3)))
    for name, tr in (("flat", flat), ("point", point)):
        export(tr, tmp_path / f"{name}.xyz")
        for atoms in ase.io.read(tmp_path / f"{name}.xyz", index=":"):
            assert (atoms.cell.lengths() > 0).all() and atoms.get_volume() > 0
            assert_inside(atoms, atoms.info["Origin"])
    assert xyz_cell(point)[1].tolist() == [0.1, 0.1, 0.1]  # 5 % of 1 m on each side


def test_without_masses_there_are_no_momenta_or_masses_columns(tmp_path):
    tr = synthetic(masses=False, radii=False)
    export(tr, tmp_path / "run.xyz")
    assert comment(tmp_path / "run.xyz")["Properties"] == "species:S:1:pos:R:3:velo:R:3:id:I:1"
    atoms = ase.io.read(tmp_path / "run.xyz", index=0)
    assert "momenta" not in atoms.arrays and "masses" not in atoms.arrays
    np.testing.assert_array_equal(atoms.arrays["velo"], tr.velocities[0])


def test_species_come_from_the_trajectorys_types(tmp_path):
    names = np.array(["Si", "O", "O", "Si", "H", "X"])
    export(synthetic(species=names), tmp_path / "named.xyz")
    atoms = ase.io.read(tmp_path / "named.xyz", index=0)
    assert atoms.get_chemical_symbols() == names.tolist()
    with pytest.raises(ValueError, match=r"species: 'two words' is invalid"):
        export(synthetic(species=["Si", "O", "two words", "Si", "H", "X"]), tmp_path / "bad.xyz")
    assert not (tmp_path / "bad.xyz").exists()


# -- CSV ------------------------------------------------------------------------------------------


def test_csv_has_mass_and_radius_columns(tmp_path):
    tr = synthetic()
    export(tr, tmp_path / "run.csv")
    with open(tmp_path / "run.csv", newline="") as f:
        reader = csv.DictReader(f)
        assert reader.fieldnames == ["frame", "time", "id", "x", "y", "z", "vx", "vy", "vz", "mass", "radius"]
        rows = list(reader)
    assert len(rows) == F * N
    for k, row in enumerate(rows):
        i, j = divmod(k, N)
        assert int(row["frame"]) == i and float(row["time"]) == tr.t[i] and int(row["id"]) == tr.ids[j]
        assert [float(row[c]) for c in ("x", "y", "z")] == tr.positions[i, j].tolist()
        assert [float(row[c]) for c in ("vx", "vy", "vz")] == tr.velocities[i, j].tolist()
        assert float(row["mass"]) == tr.masses[j] and float(row["radius"]) == tr.radii[j]


def test_csv_leaves_out_what_the_trajectory_lacks(tmp_path):
    export(synthetic(masses=False), tmp_path / "r.csv")
    export(synthetic(radii=False), tmp_path / "m.csv")
    assert (tmp_path / "r.csv").read_text().splitlines()[0] == "frame,time,id,x,y,z,vx,vy,vz,radius"
    table = np.loadtxt(tmp_path / "m.csv", delimiter=",", skiprows=1)
    assert (tmp_path / "m.csv").read_text().splitlines()[0] == "frame,time,id,x,y,z,vx,vy,vz,mass" and table.shape == (F * N, 10)


# -- names and paths ------------------------------------------------------------------------------


def tree(folder):
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*"))


def test_every_format_has_its_own_names(tmp_path):
    tr = synthetic()
    written = {name: export(tr, tmp_path / name) for name in ("run.pvd", "run.ply", "run.xyz", "run.csv")}
    frames = [f"run_{i:05d}" for i in range(F)]
    assert tree(tmp_path) == sorted(
        ["run.pvd", "run.xyz", "run.csv", "run_vtk", "run_ply", *(f"run_vtk/{f}.vtp" for f in frames), *(f"run_ply/{f}.ply" for f in frames)]
    )
    assert written["run.pvd"][0] == tmp_path / "run.pvd" and written["run.ply"][0] == tmp_path / "run_ply" / "run_00000.ply"
    files = [d.get("file") for d in ET.parse(tmp_path / "run.pvd").getroot().iter("DataSet")]
    assert files == [f"run_vtk/{f}.vtp" for f in frames] and all((tmp_path / f).is_file() for f in files)
    # Again, in the other order: each series replaces its own earlier one.
    export(tr, tmp_path / "run.ply")
    export(tr, tmp_path / "run.pvd")
    assert len(tree(tmp_path)) == 5 + 2 * F


@pytest.mark.parametrize(
    "name, fmt, says",
    [
        ("x.ply", "vtk", r"path = '.*x\.ply': the suffix '\.ply' is for format 'ply', not format = 'vtk'; give a name ending in \.pvd$"),
        ("x.csv", "xyz", r"the suffix '\.csv' is for format 'csv', not format = 'xyz'"),
        ("x.pvd", "ply", r"the suffix '\.pvd' is for format 'vtk', not format = 'ply'"),
        ("x.h5", "csv", r"the suffix '\.h5' is for an H5MD trajectory, not format = 'csv'"),
    ],
)
def test_a_suffix_that_contradicts_the_format_is_refused(tmp_path, name, fmt, says):
    with pytest.raises(ValueError, match=says):
        export(synthetic(), tmp_path / name, format=fmt)
    assert tree(tmp_path) == []


def test_an_unknown_suffix_is_fine_with_a_format(tmp_path):
    assert export(synthetic(), tmp_path / "table.txt", format="csv") == [tmp_path / "table.txt"]
    assert (tmp_path / "table.txt").read_text().startswith("frame,time,id,")


# -- the command ----------------------------------------------------------------------------------


@pytest.fixture
def saved(tmp_path):
    """A periodic run saved as run/trajectory.h5 under tmp_path."""
    (tmp_path / "run").mkdir()
    return periodic_run().save(tmp_path / "run" / "trajectory.h5")


def error_lines(res):
    return [line for line in res.output.splitlines() if line.startswith("error:")]


def test_kinema_export_defaults_do_not_collide(saved):
    folder = saved.parent
    for fmt in ("vtk", "ply", "xyz", "csv"):
        res = runner.invoke(app, ["export", str(saved), "-f", fmt])
        assert res.exit_code == 0, (fmt, res.output)
    n = kinema.load_trajectory(saved).t.size
    assert sorted(p.name for p in folder.iterdir()) == [
        "trajectory.csv",
        "trajectory.h5",
        "trajectory.pvd",
        "trajectory.xyz",
        "trajectory_colliders.vtp",  # the run's box, beside the .pvd
        "trajectory_ply",
        "trajectory_vtk",
    ]
    assert len(list((folder / "trajectory_vtk").iterdir())) == len(list((folder / "trajectory_ply").iterdir())) == n
    res = runner.invoke(app, ["export", str(saved), "-f", "vtk"])  # again: it replaces its own series
    wrote = f"wrote {folder / 'trajectory.pvd'} and {folder / 'trajectory_colliders.vtp'} and {n} frames in {folder / 'trajectory_vtk'}{os.sep}"
    assert wrote in res.output.replace("\n", "")


def test_kinema_export_creates_missing_folders(saved, tmp_path):
    for fmt, out in (("vtk", "a/b/run.pvd"), ("ply", "c/d/run.ply"), ("xyz", "e/f/run.xyz"), ("csv", "g/h/run.csv")):
        res = runner.invoke(app, ["export", str(saved), "-f", fmt, "-o", str(tmp_path / out)])
        assert res.exit_code == 0, res.output
    assert (tmp_path / "a/b/run.pvd").is_file() and (tmp_path / "a/b/run_vtk/run_00000.vtp").is_file()
    assert (tmp_path / "c/d/run_ply/run_00000.ply").is_file()
    atoms = ase.io.read(tmp_path / "e/f/run.xyz", index=-1)
    assert atoms.pbc.tolist() == [True, True, False] and atoms.info["Origin"][:2].tolist() == [-1.0, -1.0]
    assert (tmp_path / "g/h/run.csv").read_text().startswith("frame,time,id,x,y,z,vx,vy,vz,mass,radius,group\n")


@pytest.mark.parametrize(
    "fmt, out, says",
    [
        ("vtk", "x.ply", "-o {dir}/x.ply: the suffix .ply is for --format ply, not --format vtk; name the file x.pvd"),
        ("ply", "sub/x.xyz", "-o {dir}/sub/x.xyz: the suffix .xyz is for --format xyz, not --format ply; name the file x.ply"),
        ("csv", "x.h5", "-o {dir}/x.h5: the suffix .h5 is for H5MD trajectories, not exports; name the file x.csv"),
    ],
)
def test_kinema_export_refuses_a_suffix_of_another_format(saved, tmp_path, fmt, out, says):
    before = tree(tmp_path)
    res = runner.invoke(app, ["export", str(saved), "-f", fmt, "-o", str(tmp_path / out)])
    assert res.exit_code == 2, res.output
    lines = error_lines(res)
    assert len(lines) == 1 and says.format(dir=tmp_path) in res.output.replace("\n", ""), res.output
    assert tree(tmp_path) == before  # nothing written, no folder made


def test_kinema_export_into_a_folder_it_cannot_make_is_exit_2(saved, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    res = runner.invoke(app, ["export", str(saved), "-f", "csv", "-o", str(blocker / "sub" / "t.csv")])
    assert res.exit_code == 2 and len(error_lines(res)) == 1
    assert f"-o {blocker / 'sub' / 't.csv'}: cannot create the folder {blocker / 'sub'}" in res.output.replace("\n", "")


# -- permissions ----------------------------------------------------------------------------------


def modes(folder):
    return {p.relative_to(folder).as_posix(): stat.S_IMODE(p.stat().st_mode) for p in folder.rglob("*")}


@pytest.mark.parametrize("mask", [0o022, 0o027, 0o002], ids=["umask022", "umask027", "umask002"])
def test_exports_follow_the_umask(tmp_path, mask):
    old = os.umask(mask)
    try:
        for name in ("run.pvd", "run.ply", "run.xyz", "run.csv"):
            export(synthetic(), tmp_path / name)
    finally:
        os.umask(old)
    got = modes(tmp_path)
    assert got == {p: (0o777 if (tmp_path / p).is_dir() else 0o666) & ~mask for p in got}
    assert got["run.csv"] == {0o022: 0o644, 0o027: 0o640, 0o002: 0o664}[mask]  # not mkstemp's 0600


def test_writing_never_changes_the_umask(tmp_path, monkeypatch):
    # Learning the umask by setting it would change it, for a moment, for every thread.
    def refuse(_mask):
        raise AssertionError("os.umask called while writing")

    monkeypatch.setattr(os, "umask", refuse)
    for name in ("run.pvd", "run.ply", "run.xyz", "run.csv"):
        export(synthetic(), tmp_path / name)
    kinema.io.save_h5md(periodic_run(), tmp_path / "run.h5")
    assert len(tree(tmp_path)) == 6 + 2 * F


def test_kinema_export_files_follow_the_umask(saved, tmp_path):
    out = tmp_path / "out"
    for fmt, name in (("vtk", "new/run.pvd"), ("csv", "new/run.csv")):
        subprocess.run(
            [sys.executable, "-m", "kinema", "export", str(saved), "-f", fmt, "-o", str(out / name)],
            check=True,
            capture_output=True,
            preexec_fn=lambda: os.umask(0o027),
        )
    frames = {f"new/run_vtk/run_{i:05d}.vtp": 0o640 for i in range(kinema.load_trajectory(saved).t.size)}
    files = {"new/run.pvd": 0o640, "new/run_colliders.vtp": 0o640, "new/run.csv": 0o640}
    assert modes(out) == {"new": 0o750, **files, "new/run_vtk": 0o750, **frames}
