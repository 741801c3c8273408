"""kinema reads other programs' files (``Trajectory.load``, kinema.io.readers): each format
written by its own outside writer (ASE's extended XYZ and LAMMPS data files, gsd.hoomd's GSD,
OVITO's LAMMPS dump and data, XYZ and GSD, MDAnalysis's LAMMPS data and XYZ), read by kinema
and compared with what the writer wrote, in SI units; kinema's own exports read back; files
of no format kinema reads refused with the formats it reads; units that a file does not
state refused or warned about."""

import math
import warnings

import ase
import ase.io
import ase.units
import numpy as np
import pytest
from test_alive_files import births_and_deaths
from test_export_gsd_lammps import periodic_run
from typer.testing import CliRunner

import kinema
from kinema.cli import app
from kinema.io import TrajectoryFileError, UnitWarning, export
from kinema.io.units import ASE, LAMMPS_STYLES

runner = CliRunner()
FORMATS_NAMED = "kinema reads H5MD (.h5, .hdf5, .h5md), extended XYZ (.xyz, .extxyz), GSD (.gsd), LAMMPS dumps"


def load(path, **options):
    """``Trajectory.load`` with warnings turned into errors: a reader that warns fails here."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return kinema.Trajectory.load(path, **options)


def ase_atoms(k=0, n=5):
    """ASE atoms with positions, velocities and masses of their own (amu), a cell periodic in
    x and y, and a time in the info."""
    rng = np.random.default_rng(k)
    a = ase.Atoms(["Fe", "He", "Ar", "Fe", "C"][:n], positions=rng.normal(size=(n, 3)) * 3 + 5, cell=[10.0, 11.0, 12.0], pbc=[True, True, False])
    a.set_masses([55.845, 4.0026, 39.948, 55.845, 12.011][:n])
    a.set_velocities(rng.normal(size=(n, 3)) * 0.02)
    a.info["time"] = 1.5 * k
    return a


# -- kinema's own exports read back ------------------------------------------------------------------


@pytest.fixture(scope="module")
def comings_and_goings():
    return births_and_deaths()


@pytest.mark.parametrize("fmt, suffix", [("xyz", ".xyz"), ("vtk", ".pvd")])
def test_own_float64_exports_read_back_bit_for_bit(tmp_path, comings_and_goings, fmt, suffix):
    traj = comings_and_goings
    path = tmp_path / f"run{suffix}"
    export(traj, path, fmt)
    back = load(path)
    np.testing.assert_array_equal(back.alive, traj.alive)
    np.testing.assert_array_equal(back.ids, traj.ids)
    np.testing.assert_array_equal(back.t, traj.t)
    for name in ("positions", "velocities"):  # NaN where a particle is not alive, on both sides
        np.testing.assert_array_equal(getattr(back, name), getattr(traj, name))
    np.testing.assert_array_equal(back.masses, traj.masses)
    np.testing.assert_array_equal(back.radii, traj.radii)
    assert back.species.tolist() == traj.species.tolist()
    assert back.source.path == path and back.source.step.tolist() == list(range(len(traj.t)))


def test_own_csv_reads_back_bit_for_bit_but_its_empty_frame(tmp_path, comings_and_goings):
    traj = comings_and_goings
    export(traj, tmp_path / "run.csv")
    back = load(tmp_path / "run.csv")
    kept = traj.alive.any(axis=1)  # a frame with no particle alive has no row in a CSV
    assert not kept.all()
    np.testing.assert_array_equal(back.t, traj.t[kept])
    np.testing.assert_array_equal(back.alive, traj.alive[kept])
    np.testing.assert_array_equal(back.positions, traj.positions[kept])
    np.testing.assert_array_equal(back.velocities, traj.velocities[kept])
    np.testing.assert_array_equal(back.masses, traj.masses)
    np.testing.assert_array_equal(back.radii, traj.radii)


def test_own_lammps_dump_reads_back_bit_for_bit_in_si(tmp_path, comings_and_goings):
    traj = comings_and_goings
    path = tmp_path / "run.lammpstrj"
    export(traj, path)
    back = load(path, units="si")
    np.testing.assert_array_equal(back.ids, traj.ids)  # LAMMPS ids start at 1: kinema writes id + 1 and reads id − 1
    np.testing.assert_array_equal(back.alive, traj.alive)
    np.testing.assert_array_equal(back.positions, traj.positions)
    np.testing.assert_array_equal(back.velocities, traj.velocities)
    np.testing.assert_array_equal(back.masses, traj.masses)
    np.testing.assert_array_equal(back.radii, traj.radii)


def test_a_2d_dump_reads_back_2d_periodic_in_x_and_y_only(tmp_path):
    # LAMMPS's 2D boxes are periodic in z (kinema's dump writes pp there, as LAMMPS does); the
    # z of a 2D world is no axis of it, so it comes back open
    w = kinema.World(dt=1e-3, dim=2)
    w.add(kinema.Box([0, 0], [1, 1]))
    w.add_particles([[0.2, 0.3, 0.0], [0.7, 0.6, 0.0]], velocity=[[3.0, 1.0, 0.0], [-2.0, 0.5, 0.0]], mass=1.0, radius=0.05)
    w.periodic = (True, True, False)
    traj = w.run(0.3, fps=30)
    path = tmp_path / "flat.lammpstrj"
    export(traj, path)
    assert "ITEM: BOX BOUNDS pp pp pp" in path.read_text()
    back = load(path, units="si")
    assert back.dim == 2 and back.periodic == (True, True, False)
    np.testing.assert_array_equal(back.box_edges[:2], traj.box_edges[:2])
    np.testing.assert_array_equal(back.positions, traj.positions)


def test_own_gsd_reads_back_as_gsd_reads_it(tmp_path, comings_and_goings):
    gsd_hoomd = pytest.importorskip("gsd.hoomd")
    traj = comings_and_goings
    path = tmp_path / "run.gsd"
    export(traj, path)
    back = load(path)  # kinema's GSD is SI (log/kinema/time): no UnitWarning
    np.testing.assert_array_equal(back.alive, traj.alive)
    np.testing.assert_array_equal(back.t, traj.t)
    assert back.species.tolist() == traj.species.tolist()
    worst = 0.0
    with gsd_hoomd.open(str(path)) as f:
        for k, frame in enumerate(f):
            live = back.alive[k]
            ids = frame.log["particles/kinema/id"]
            np.testing.assert_array_equal(back.ids[live], ids)
            origin = frame.log["kinema/origin"]
            np.testing.assert_array_equal(back.positions[k][live], frame.particles.position.astype(np.float64) + origin)
            np.testing.assert_array_equal(back.velocities[k][live], frame.particles.velocity.astype(np.float64))
            if live.any():
                worst = max(worst, float(np.max(np.abs(back.positions[k][live] - traj.positions[k][live]))))
    np.testing.assert_array_equal(back.masses, traj.masses.astype(np.float32))
    np.testing.assert_array_equal(back.radii, (2 * traj.radii).astype(np.float32) / 2)
    assert worst < 1e-6  # float32 of positions within a few m of the box centre


def test_own_ply_series_reads_back_as_plyfile_reads_it(tmp_path, comings_and_goings):
    plyfile = pytest.importorskip("plyfile")
    traj = comings_and_goings
    export(traj, tmp_path / "run.ply")
    back = load(tmp_path / "run.ply")  # the series folder run_ply/, by the name it was exported to
    np.testing.assert_array_equal(back.alive, traj.alive)
    np.testing.assert_array_equal(back.t, traj.t)
    for k in range(len(traj.t)):
        v = plyfile.PlyData.read(str(tmp_path / "run_ply" / f"run_{k:05d}.ply"))["vertex"]
        live = back.alive[k]
        np.testing.assert_array_equal(back.ids[live], v["id"])
        np.testing.assert_array_equal(back.positions[k][live], np.stack([v[a] for a in "xyz"], axis=1).astype(np.float64))
    assert back.masses is None  # PLY holds no masses


def test_own_springs_and_colours_come_back(tmp_path):
    traj = births_and_deaths()
    traj.colors = np.array([[1.0, 0.0, 0.0], [0.25, 0.5, 0.75], [0.0, 0.0, 1.0], [0.125, 1.0, 0.0]])
    export(traj, tmp_path / "run.gsd")
    back = load(tmp_path / "run.gsd")
    assert sorted(map(tuple, back.springs.tolist())) == [(3, 5), (8, 11)]  # GSD's bonds of type "spring", as ids
    np.testing.assert_array_equal(back.colors, traj.colors.astype(np.float32))
    for fmt, suffix in (("xyz", ".xyz"), ("csv", ".csv"), ("vtk", ".pvd")):
        export(traj, tmp_path / f"run{suffix}", fmt)
        np.testing.assert_array_equal(load(tmp_path / f"run{suffix}").colors, traj.colors)


def test_a_periodic_box_comes_back_with_its_corner(tmp_path):
    traj = periodic_run()
    export(traj, tmp_path / "run.xyz")
    back = load(tmp_path / "run.xyz")
    assert back.periodic == (True, True, False)
    np.testing.assert_array_equal(back.box_edges[:2], [1.0, 1.0])
    assert back.colliders == [{"type": "box", "lo": [0.0, 0.0, -math.inf], "hi": [1.0, 1.0, math.inf]}]


# -- ASE -------------------------------------------------------------------------------------------


def test_ase_extxyz_is_read_in_ases_units(tmp_path):
    path = tmp_path / "ase.extxyz"
    ase.io.write(path, [ase_atoms(k) for k in range(3)], format="extxyz")
    back = load(path)
    read = ase.io.read(path, index=":")
    # ASE's own units in SI, from ase.units: Å, its amu, its velocity unit Å / (Å √(amu/eV))
    assert ASE.length == 1e-10 and ASE.mass == ase.units._amu
    assert ASE.velocity == pytest.approx(1e-10 * ase.units.second, rel=4e-16)
    for k, a in enumerate(read):
        np.testing.assert_array_equal(back.positions[k], a.positions * ASE.length)
        np.testing.assert_array_equal(back.velocities[k], a.get_velocities() * ASE.velocity)  # momenta / masses, as ASE divides
        np.testing.assert_array_equal(back.masses, a.get_masses() * ASE.mass)
    assert back.species.tolist() == ["Fe", "He", "Ar", "Fe", "C"]
    np.testing.assert_array_equal(back.t, np.array([0.0, 1.5, 3.0]) * ASE.time)
    assert back.periodic == (True, True, False)
    np.testing.assert_array_equal(back.box_edges, np.array([10.0, 11.0, 12.0]) * 1e-10)


def test_ase_xyz_without_masses_takes_ases_element_masses_as_ase_does(tmp_path):
    # ASE writes momenta of its own element masses and no masses column: Atoms.get_masses()
    # gives its table's masses, and kinema the same, saying so once
    a = ase_atoms()
    del a.arrays["masses"]
    path = tmp_path / "plain.xyz"
    later = a.copy()
    later.info["time"] = 1.0
    ase.io.write(path, [a, later], format="extxyz")
    with pytest.warns(UnitWarning, match=r"plain\.xyz: no masses in the file; ASE's standard atomic masses") as said:
        back = kinema.Trajectory.load(path)
    assert len([w for w in said if issubclass(w.category, UnitWarning)]) == 1
    read = ase.io.read(path)
    np.testing.assert_array_equal(back.masses, read.get_masses() * ASE.mass)
    np.testing.assert_array_equal(back.velocities[0], read.get_velocities() * ASE.velocity)
    np.testing.assert_array_equal(back.positions[0], read.positions * 1e-10)


def test_an_xyz_without_masses_whose_names_are_not_elements_has_none(tmp_path):
    path = tmp_path / "grains.xyz"
    path.write_text("2\nProperties=species:S:1:pos:R:3:momenta:R:3\ngrain 0 0 0 1 0 0\nX 1 0 0 0 1 0\n")
    with pytest.warns(UserWarning, match=r"grains\.xyz: frame 0 \(line 1\) has momenta but no masses"):  # said, not silent (issue 49)
        back = kinema.Trajectory.load(path)
    assert back.masses is None and np.isnan(back.velocities).all()


LAMMPS_UNITS = ["real", "metal", "si", "cgs", "electron", "micro", "nano"]


@pytest.mark.parametrize("style", ["atomic", "charge", "full"])
@pytest.mark.parametrize("units", LAMMPS_UNITS)
def test_ase_lammps_data_is_read_in_its_units_style(tmp_path, style, units):
    from ase.calculators.lammps import convert

    a = ase_atoms(n=4)
    path = tmp_path / "ase.data"
    ase.io.write(path, a, format="lammps-data", units=units, atom_style=style, masses=True, velocities=True)
    back = load(path, units=units)
    s = LAMMPS_STYLES[units]
    # The numbers ASE wrote (its own conversion, 17 digits: exact), times LAMMPS's unit in SI.
    np.testing.assert_array_equal(back.positions[0], convert(a.positions, "distance", "ASE", units) * s.length)
    np.testing.assert_array_equal(back.velocities[0], convert(a.get_velocities(), "velocity", "ASE", units) * s.velocity)
    masses = np.array([float(line.split()[1]) for line in path.read_text().split("Masses")[1].strip().splitlines()[:3]])
    np.testing.assert_array_equal(back.masses, masses[[1, 2, 0, 1]] * s.mass)  # types: Ar 1, Fe 2, He 3 (ASE sorts them)
    assert back.species.tolist() == ["Fe", "He", "Ar", "Fe"]  # ASE's "# Fe" comments on the Masses
    np.testing.assert_array_equal(back.ids, [0, 1, 2, 3])  # LAMMPS's 1 … 4
    assert back.source.creator == "ASE" and back.periodic == (True, True, True)


def test_lammps_units_against_ases_constants():
    """kinema converts LAMMPS's styles by LAMMPS's constants (src/update.cpp); ASE by CODATA
    2014's. They agree but where LAMMPS's constants are older: a gram per mole (Avogadro
    6.02214129e23, CODATA 2010, in force->mv2d, against 6.022140857e23), the Bohr
    (1 / 1.88972612 Å, force->angstrom) and the electron style's velocity (LAMMPS integrates
    x += dt v with dt in fs: Bohr per fs, where ASE, after LAMMPS's units page, takes Bohr
    per 1.03275 fs)."""
    from ase.calculators.lammps.unitconvert import UNITSETS

    avogadro = 6.022140857e23 / 6.02214129e23 - 1
    for units, s in LAMMPS_STYLES.items():
        ref = UNITSETS[units]
        assert s.time == ref["time"], units
        if units != "electron":
            assert s.length == ref["distance"], units
            assert s.velocity == pytest.approx(ref["velocity"], rel=2.3e-16), units
        if units in ("real", "metal", "electron"):
            assert s.mass / ref["mass"] - 1 == pytest.approx(avogadro, rel=1e-6), units
        else:
            assert s.mass == ref["mass"], units
    electron = LAMMPS_STYLES["electron"]
    assert electron.length / UNITSETS["electron"]["distance"] - 1 == pytest.approx(1e-10 / 1.88972612 / 5.2917721067e-11 - 1, rel=1e-6)
    assert electron.velocity == pytest.approx(electron.length / 1e-15, rel=2.3e-16)


# -- gsd.hoomd: HOOMD's files have no units ---------------------------------------------------


def hoomd_file(path, frames=3, n=4, dim=3, counts=None):
    gsd_hoomd = pytest.importorskip("gsd.hoomd")
    rng = np.random.default_rng(4)
    with gsd_hoomd.open(str(path), mode="w") as f:
        for k in range(frames):
            m = n if counts is None else counts[k]
            frame = gsd_hoomd.Frame()
            frame.configuration.step = 100 * k
            frame.configuration.dimensions = dim
            frame.configuration.box = [8.0, 9.0, 0.0 if dim == 2 else 10.0, 0, 0, 0]
            p = frame.particles
            p.N = m
            p.types = ["A", "B"]
            p.typeid = np.arange(m) % 2
            x = rng.uniform(-3.5, 3.5, (m, 3)).astype(np.float32)
            v = rng.normal(size=(m, 3)).astype(np.float32)
            if dim == 2:
                x[:, 2] = v[:, 2] = 0
            p.position, p.velocity = x, v
            p.mass = np.linspace(1.0, 2.0, m).astype(np.float32)
            p.diameter = np.full(m, 0.5, dtype=np.float32)
            f.append(frame)
    return path


def test_a_hoomd_file_without_units_is_read_as_si_with_a_warning(tmp_path):
    gsd_hoomd = pytest.importorskip("gsd.hoomd")
    path = hoomd_file(tmp_path / "hoomd.gsd")
    with pytest.warns(UnitWarning, match=r"hoomd\.gsd: a HOOMD GSD file has no units; .*masses in kg.*give units="):
        back = kinema.Trajectory.load(path)
    with gsd_hoomd.open(str(path)) as f:
        for k, frame in enumerate(f):
            np.testing.assert_array_equal(back.positions[k], frame.particles.position.astype(np.float64))
            np.testing.assert_array_equal(back.velocities[k], frame.particles.velocity.astype(np.float64))
        np.testing.assert_array_equal(back.masses, f[0].particles.mass.astype(np.float64))
    np.testing.assert_array_equal(back.radii, np.full(4, 0.25))
    assert back.species.tolist() == ["A", "B", "A", "B"]
    np.testing.assert_array_equal(back.source.step, [0, 100, 200])
    np.testing.assert_array_equal(back.t, [0.0, 1.0, 2.0])  # HOOMD files have no times: the frame index
    assert back.periodic == (True, True, True)
    np.testing.assert_array_equal(back.box_edges, [8.0, 9.0, 10.0])


def test_a_hoomd_file_with_units_is_converted_without_a_warning(tmp_path):
    gsd_hoomd = pytest.importorskip("gsd.hoomd")
    path = hoomd_file(tmp_path / "hoomd.gsd", dim=2)
    scales = {"length": 3.4e-10, "time": 2.15e-12, "mass": 6.63e-26}
    back = load(path, units=scales)
    assert back.dim == 2
    with gsd_hoomd.open(str(path)) as f:
        np.testing.assert_array_equal(back.positions[1], f[1].particles.position.astype(np.float64) * 3.4e-10)
        np.testing.assert_array_equal(back.velocities[1], f[1].particles.velocity.astype(np.float64) * (3.4e-10 / 2.15e-12))
        np.testing.assert_array_equal(back.masses, f[0].particles.mass.astype(np.float64) * 6.63e-26)


def test_a_hoomd_file_whose_count_changes_without_ids_is_refused(tmp_path):
    path = hoomd_file(tmp_path / "grows.gsd", counts=[3, 4, 4])
    with pytest.raises(TrajectoryFileError, match=r"grows\.gsd: frame 1 holds 4 particles but frame 0 3, and the file has no ids"):
        kinema.Trajectory.load(path, units="si")


# -- OVITO --------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def ovito_files(tmp_path_factory):
    """OVITO's exports of three particles (ids, two named types, velocities, masses, radii) in a
    cell at (1, 2, 3), periodic in x and y: a LAMMPS dump, data files (atomic, sphere), an
    extended XYZ file and a GSD file; and the values OVITO held."""
    pytest.importorskip("ovito")
    from ovito.data import DataCollection, ParticleType
    from ovito.io import export_file
    from ovito.pipeline import Pipeline, StaticSource

    folder = tmp_path_factory.mktemp("ovito")
    rng = np.random.default_rng(8)
    values = {
        "positions": rng.random((3, 3)) * 5 + 3,  # inside the cell: OVITO's GSD wraps into HOOMD's periodic box
        "velocities": rng.normal(size=(3, 3)),
        "masses": np.array([1.5, 2.5, 3.5]),
        "radii": np.array([0.1, 0.2, 0.3]),
        "ids": np.array([5, 7, 9]),
    }
    dc = DataCollection()
    dc.create_cell(np.array([[10.0, 0, 0, 1], [0, 11.0, 0, 2], [0, 0, 12.0, 3]]), pbc=(True, True, False))
    p = dc.create_particles(count=3)
    p.create_property("Position", data=values["positions"])
    p.create_property("Velocity", data=values["velocities"])
    p.create_property("Mass", data=values["masses"])
    p.create_property("Radius", data=values["radii"])
    p.create_property("Particle Identifier", data=values["ids"])
    types = p.create_property("Particle Type", data=[1, 2, 1])
    types.types.append(ParticleType(id=1, name="Fe"))
    types.types.append(ParticleType(id=2, name="He"))
    pipeline = Pipeline(source=StaticSource(data=dc))
    columns = ["Particle Identifier", "Particle Type", "Position.X", "Position.Y", "Position.Z", "Velocity.X", "Velocity.Y", "Velocity.Z", "Mass", "Radius"]
    files = {
        "dump": folder / "ovito.lammpstrj",
        "atomic": folder / "atomic.data",
        "sphere": folder / "sphere.data",
        "xyz": folder / "ovito.xyz",
        "gsd": folder / "ovito.gsd",
    }
    export_file(pipeline, str(files["dump"]), "lammps/dump", columns=columns)
    export_file(pipeline, str(files["atomic"]), "lammps/data", atom_style="atomic")
    export_file(pipeline, str(files["sphere"]), "lammps/data", atom_style="sphere")
    export_file(pipeline, str(files["xyz"]), "xyz", columns=columns)
    export_file(pipeline, str(files["gsd"]), "gsd/hoomd")
    return files, values


OVITO_DECIMALS = 5e-11  # OVITO 3.17 writes text numbers with 10 decimals (in the file's units)


def test_ovito_lammps_dump(ovito_files):
    from ovito.io import import_file

    files, values = ovito_files
    back = load(files["dump"], units="metal")
    s = LAMMPS_STYLES["metal"]
    ovito = import_file(str(files["dump"])).compute().particles
    np.testing.assert_array_equal(back.ids, values["ids"] - 1)  # LAMMPS's ids from 1
    # OVITO's own reading of its file, and the values it held to its 10 digits
    np.testing.assert_allclose(back.positions[0], ovito.positions[...] * s.length, rtol=1e-15, atol=0)
    np.testing.assert_allclose(back.positions[0], values["positions"] * s.length, rtol=0, atol=OVITO_DECIMALS * s.length)
    np.testing.assert_allclose(back.velocities[0], values["velocities"] * s.velocity, rtol=0, atol=OVITO_DECIMALS * s.velocity)
    np.testing.assert_array_equal(back.masses, values["masses"] * s.mass)
    np.testing.assert_array_equal(back.radii, values["radii"] * s.length)
    assert back.species.tolist() == ["1", "2", "1"]  # the type numbers: OVITO's dump has no names
    # OVITO writes the box as LAMMPS 2024's general triclinic "abc origin"
    assert back.periodic == (True, True, False)
    np.testing.assert_array_equal(back.box_edges, np.array([10.0, 11.0, 12.0]) * s.length)
    assert back.colliders[0]["lo"][:2] == [1.0 * s.length, 2.0 * s.length]


def test_ovito_lammps_data_files(ovito_files):
    from ovito.io import import_file

    files, values = ovito_files
    atomic = load(files["atomic"], units="si")
    np.testing.assert_allclose(atomic.positions[0], values["positions"], rtol=0, atol=OVITO_DECIMALS)
    np.testing.assert_allclose(atomic.velocities[0], values["velocities"], rtol=0, atol=OVITO_DECIMALS)
    assert atomic.masses is None  # OVITO writes no Masses section
    sphere = load(files["sphere"], units="si")
    np.testing.assert_array_equal(sphere.radii, values["radii"])
    # mass = density × 4π/3 r³, as LAMMPS's read_data computes it; OVITO 3.17 writes the
    # density of mass / (4π/3 d³), with the diameter, so LAMMPS (and kinema) read 1/8 of its mass
    density = import_file(str(files["sphere"]), atom_style="sphere").compute().particles["Density"][...]
    np.testing.assert_array_equal(sphere.masses, 4.0 * math.pi / 3.0 * values["radii"] ** 3 * density)
    # (OVITO keeps radii as float32, 3 roundings of 2**-24 in r³)
    np.testing.assert_allclose(sphere.masses, values["masses"] / 8, rtol=3 * 2.0**-24)


def test_ovito_xyz_and_gsd(ovito_files):
    files, values = ovito_files
    xyz = load(files["xyz"])  # no units= key: ASE's units, the format's convention
    np.testing.assert_allclose(xyz.positions[0], values["positions"] * 1e-10, rtol=0, atol=OVITO_DECIMALS * 1e-10)
    np.testing.assert_array_equal(xyz.masses, values["masses"] * ASE.mass)
    assert xyz.species.tolist() == ["Fe", "He", "Fe"]
    np.testing.assert_array_equal(xyz.ids, values["ids"])
    assert xyz.colliders[0]["lo"][:2] == [1e-10, 2e-10]  # OVITO's Origin
    with pytest.warns(UnitWarning, match="ovito.gsd"):
        gsd = kinema.Trajectory.load(files["gsd"])
    # HOOMD's box is centred at 0: OVITO moves the particles by the cell's centre (6, 7.5, 9)
    np.testing.assert_allclose(gsd.positions[0], values["positions"] - [6.0, 7.5, 9.0], rtol=0, atol=5e-7)
    np.testing.assert_array_equal(gsd.masses, values["masses"].astype(np.float32))
    assert gsd.species.tolist() == ["Fe", "He", "Fe"]


# -- MDAnalysis ---------------------------------------------------------------------------------


def test_mdanalysis_lammps_data_and_xyz(tmp_path):
    mda = pytest.importorskip("MDAnalysis")
    u = mda.Universe.empty(3, trajectory=True, velocities=True)
    u.add_TopologyAttr("type", ["1", "2", "1"])
    u.add_TopologyAttr("mass", [1.5, 2.5, 1.5])
    u.add_TopologyAttr("charge", [0.0, 0.0, 0.0])
    u.add_TopologyAttr("id", [1, 2, 3])
    u.add_TopologyAttr("name", ["Fe", "He", "Fe"])
    for attr in ("bonds", "angles", "dihedrals", "impropers"):
        u.add_TopologyAttr(attr, [])
    u.atoms.positions = np.random.default_rng(0).random((3, 3)) * 5
    u.atoms.velocities = np.random.default_rng(1).normal(size=(3, 3))
    u.dimensions = [10, 11, 12, 90, 90, 90]
    data = tmp_path / "mda.data"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # MDAnalysis's own warnings about what it guesses
        u.atoms.write(data)
        u.atoms.write(tmp_path / "mda.xyz")
    # Its Atoms section names no style, and 7 values fit full and sphere
    with pytest.raises(TrajectoryFileError, match="7 values, which fit the atom styles full, sphere; name it"):
        kinema.Trajectory.load(data, units="real")
    back = load(data, units="real", atom_style="full")
    s = LAMMPS_STYLES["real"]
    # MDAnalysis writes real units, Å and Å/fs (its float32 Å/ps times 0.001, in float32),
    # with 10 decimals
    np.testing.assert_allclose(back.positions[0], u.atoms.positions.astype(np.float64) * s.length, rtol=0, atol=5e-11 * s.length)
    per_fs = (0.001 * u.atoms.velocities).astype(np.float64)
    np.testing.assert_allclose(back.velocities[0] / s.velocity, per_fs, rtol=1e-15, atol=5e-11)
    np.testing.assert_array_equal(back.masses, np.array([1.5, 2.5, 1.5]) * s.mass)
    assert back.source.creator == "MDAnalysis"
    with pytest.warns(UnitWarning, match="ASE's standard atomic masses"):
        xyz = kinema.Trajectory.load(tmp_path / "mda.xyz")  # plain XYZ: names and positions (Å, 5 decimals)
    np.testing.assert_allclose(xyz.positions[0], u.atoms.positions.astype(np.float64) * 1e-10, rtol=0, atol=5e-6 * 1e-10)
    assert xyz.species.tolist() == ["Fe", "He", "Fe"]
    np.testing.assert_array_equal(xyz.masses, ase.io.read(tmp_path / "mda.xyz").get_masses() * ASE.mass)  # ASE's, as ASE reads it


# -- LAMMPS text files as LAMMPS writes them ---------------------------------------------------------

DUMP = """ITEM: UNITS
real
ITEM: TIME
2.5
ITEM: TIMESTEP
10
ITEM: NUMBER OF ATOMS
3
ITEM: BOX BOUNDS pp pp ff
0.0 10.0
0.0 10.0
-5.0 5.0
ITEM: ATOMS id type xs ys zs vx vy vz mass diameter
3 1 0.5 0.25 0.5 0.1 0.2 0.3 12.011 2.0
1 2 0.125 0.75 0.0 -0.1 0.0 0.0 1.008 1.0
7 1 0.0 0.0 1.0 0.0 0.0 -0.5 12.011 2.0
ITEM: TIME
5.0
ITEM: TIMESTEP
20
ITEM: NUMBER OF ATOMS
2
ITEM: BOX BOUNDS pp pp ff
0.0 10.0
0.0 10.0
-5.0 5.0
ITEM: ATOMS id type xs ys zs vx vy vz mass diameter
1 2 0.25 0.75 0.0 -0.1 0.0 0.0 1.008 1.0
9 1 0.5 0.5 0.5 0.0 0.0 0.0 12.011 2.0
"""


def test_a_lammps_dump_with_units_scaled_positions_and_changing_atoms(tmp_path):
    path = tmp_path / "md.dump"
    path.write_text(DUMP)
    back = load(path)  # ITEM: UNITS real
    s = LAMMPS_STYLES["real"]
    np.testing.assert_array_equal(back.ids, [0, 2, 6, 8])  # LAMMPS's 1, 3, 7, 9
    np.testing.assert_array_equal(back.alive, [[True, True, True, False], [True, False, False, True]])
    np.testing.assert_array_equal(back.t, np.array([2.5, 5.0]) * s.time)
    np.testing.assert_array_equal(back.source.step, [10, 20])
    np.testing.assert_array_equal(back.positions[0, 1], np.array([5.0, 2.5, 0.0]) * s.length)  # xs times the edges from lo
    np.testing.assert_array_equal(back.positions[1, 0], np.array([2.5, 7.5, -5.0]) * s.length)
    assert np.isnan(back.positions[1, 1]).all() and np.isnan(back.positions[0, 3]).all()
    np.testing.assert_array_equal(back.masses, np.array([1.008, 12.011, 12.011, 12.011]) * s.mass)
    np.testing.assert_array_equal(back.radii, np.array([0.5, 1.0, 1.0, 1.0]) * s.length)
    assert back.species.tolist() == ["2", "1", "1", "1"]
    with pytest.raises(TrajectoryFileError, match=r"md\.dump: the file says its units are 'real' \(ITEM: UNITS\), which units = 'metal' contradicts"):
        kinema.Trajectory.load(path, units="metal")


def test_lammps_files_without_units_or_in_lj_units_are_refused(tmp_path):
    path = tmp_path / "md.lammpstrj"
    path.write_text(DUMP.replace("ITEM: UNITS\nreal\n", ""))
    with pytest.raises(TrajectoryFileError, match=r"md\.lammpstrj: a LAMMPS file that does not say its units \(ITEM: UNITS is missing\); give units="):
        kinema.Trajectory.load(path)
    with pytest.raises(ValueError, match=r"units = 'lj' is invalid: LAMMPS's lj units are reduced"):
        kinema.Trajectory.load(path, units="lj")
    lj = load(path, units={"length": 3.4e-10, "time": 2.15e-12, "mass": 6.63e-26})  # argon's σ, τ and m
    np.testing.assert_array_equal(lj.masses[0], 1.008 * 6.63e-26)
    path.write_text(DUMP.replace("ITEM: UNITS\nreal\n", "ITEM: UNITS\nlj\n"))
    with pytest.raises(TrajectoryFileError, match=r"md\.lammpstrj: the file says its units are 'lj' \(ITEM: UNITS\), LAMMPS's reduced units"):
        kinema.Trajectory.load(path)
    # with the scales given, as for a file that does not say its units (issue 49)
    assert load(path, units={"length": 3.4e-10, "time": 2.15e-12, "mass": 6.63e-26}).masses[0] == lj.masses[0]


def test_a_tilted_box_is_refused(tmp_path):
    path = tmp_path / "tilted.dump"
    path.write_text(
        DUMP.replace(
            "ITEM: BOX BOUNDS pp pp ff\n0.0 10.0\n0.0 10.0\n-5.0 5.0", "ITEM: BOX BOUNDS xy xz yz pp pp ff\n0.0 10.0 1.0\n0.0 10.0 0.0\n-5.0 5.0 0.0", 1
        )
    )
    with pytest.raises(TrajectoryFileError, match=r"tilted\.dump: frame 0 \(line 9\): a tilted box \(xy xz yz = \[1\.0, 0\.0, 0\.0\]\)"):
        kinema.Trajectory.load(path)


DATA = """LAMMPS data file via write_data, version 29 Aug 2024, timestep = 500, units = metal

3 atoms
2 atom types

0 20 xlo xhi
-10 10 ylo yhi
0.0 5.0 zlo zhi

Atom Type Labels

1 Cu
2 Ag

Atoms # sphere

2 1 1.5 8.9 1.0 2.0 3.0 0 0 0
1 2 0.0 107.87 4.0 5.0 1.0 0 1 0
3 1 3.0 8.9 10.0 0.0 2.5 0 0 0

Velocities

1 0.5 0.25 0.125 0 0 0
2 1.0 2.0 3.0 0 0 0
3 0.0 0.0 -1.0 0 0 0
"""


def test_a_lammps_data_file_as_write_data_writes_it(tmp_path):
    path = tmp_path / "copper.data"
    path.write_text(DATA)
    back = load(path)
    s = LAMMPS_STYLES["metal"]
    np.testing.assert_array_equal(back.ids, [0, 1, 2])  # LAMMPS's 1 … 3
    np.testing.assert_array_equal(back.positions[0], np.array([[4.0, 5.0, 1.0], [1.0, 2.0, 3.0], [10.0, 0.0, 2.5]]) * s.length)
    np.testing.assert_array_equal(back.velocities[0], np.array([[0.5, 0.25, 0.125], [1.0, 2.0, 3.0], [0.0, 0.0, -1.0]]) * s.velocity)
    # sphere: the radius is half the diameter, the mass the density times 4π/3 r³, or the density where the diameter is 0
    np.testing.assert_array_equal(back.radii, np.array([0.0, 0.75, 1.5]) * s.length)
    expected = np.array([107.87, 4.0 * math.pi / 3.0 * 0.75 * 0.75 * 0.75 * 8.9, 4.0 * math.pi / 3.0 * 1.5 * 1.5 * 1.5 * 8.9])
    np.testing.assert_array_equal(back.masses, expected * s.mass)
    assert back.species.tolist() == ["Ag", "Cu", "Cu"]
    np.testing.assert_array_equal(back.source.step, [500])
    assert back.source.creator == "LAMMPS"
    np.testing.assert_array_equal(back.box_edges, np.array([20.0, 20.0, 5.0]) * s.length)


def test_the_format_is_told_by_content_where_the_suffix_does_not_tell_it(tmp_path, comings_and_goings):
    dump = tmp_path / "md.lmp"  # .lmp names data files too: the dump's ITEM: lines decide
    dump.write_text(DUMP)
    assert load(dump).source.creator == "LAMMPS dump"
    export(comings_and_goings, tmp_path / "run.xyz")
    (tmp_path / "run.xyz").rename(tmp_path / "frames")  # no suffix: a count alone on the first line
    np.testing.assert_array_equal(load(tmp_path / "frames").positions, comings_and_goings.positions)
    comings_and_goings.save(tmp_path / "run.h5")
    (tmp_path / "run.h5").rename(tmp_path / "run.xyz")  # HDF5's first bytes win over the suffix
    np.testing.assert_array_equal(load(tmp_path / "run.xyz").positions, comings_and_goings.positions)
    (tmp_path / "copper").write_text(DATA)
    assert load(tmp_path / "copper").source.creator == "LAMMPS"  # "3 atoms" in the header


# -- what is refused -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "name, content",
    [("notes.txt", "some notes, not particles\n"), ("run.h5", "t,x,y,z\n0,1,2,3\n"), ("blob", bytes(range(256)) * 4), ("run.gsd", "no magic here\n")],
)
def test_a_file_of_no_format_kinema_reads_names_the_formats_it_reads(tmp_path, name, content):
    path = tmp_path / name
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    with pytest.raises(TrajectoryFileError) as e:
        kinema.Trajectory.load(path)
    message = str(e.value)
    assert message.startswith(f"{path}: ") and "\n" not in message and FORMATS_NAMED in message


def test_bad_rows_are_one_line_naming_the_line(tmp_path):
    path = tmp_path / "bad.xyz"
    path.write_text("2\nProperties=species:S:1:pos:R:3 units=SI\nAr 0 0 0\nAr 1 x 0\n")
    with pytest.raises(TrajectoryFileError, match=r"^.*bad\.xyz: frame 0 \(line 1\), row 1: column 'pos' \(real\) has 'x'$"):
        kinema.Trajectory.load(path)
    path.write_text("2\nProperties=species:S:1:pos:R:3:mass:R:1 units=SI\nAr 0 0 0 1\nAr 1 1 0 -2\n")
    with pytest.raises(TrajectoryFileError, match=r"bad\.xyz: frame 0 \(line 1\): has the mass of row \[1\] = -2 \(masses must be finite and > 0 kg\)"):
        kinema.Trajectory.load(path)
    path.write_text('1\nLattice="1 0.5 0 0 1 0 0 0 1"\nAr 0 0 0\n')
    with pytest.raises(TrajectoryFileError, match="not along the axes"):
        kinema.Trajectory.load(path)


def test_units_for_a_file_in_known_units_are_refused(tmp_path, comings_and_goings):
    export(comings_and_goings, tmp_path / "run.xyz")
    with pytest.raises(TrajectoryFileError, match=r"run\.xyz: the file says units=SI, which units = 'metal' contradicts"):
        kinema.Trajectory.load(tmp_path / "run.xyz", units="metal")
    comings_and_goings.save(tmp_path / "run.h5")
    with pytest.raises(ValueError, match=r"units = 'real': .*run\.h5 is read as h5md, whose units are known"):
        kinema.Trajectory.load(tmp_path / "run.h5", units="real")


# -- the command line ----------------------------------------------------------------------------------


def test_kinema_export_and_view_read_other_formats(tmp_path):
    dump = tmp_path / "md.lammpstrj"
    dump.write_text(DUMP.replace("ITEM: UNITS\nreal\n", ""))
    res = runner.invoke(app, ["export", str(dump), "-f", "csv", "-o", str(tmp_path / "md.csv")])
    assert res.exit_code == 2 and "does not say its units" in res.output and "--units" in res.output
    res = runner.invoke(app, ["export", str(dump), "-f", "csv", "-o", str(tmp_path / "md.csv"), "--units", "real"])
    assert res.exit_code == 0, res.output
    back = load(tmp_path / "md.csv")
    np.testing.assert_array_equal(back.positions[1, 0], np.array([2.5, 7.5, -5.0]) * LAMMPS_STYLES["real"].length)
    res = runner.invoke(app, ["export", str(dump), "-f", "csv", "-o", str(tmp_path / "x.csv"), "--units", "furlongs"])
    assert res.exit_code == 2 and "--units 'furlongs': give one of 'real'" in res.output
    path = tmp_path / "ase.extxyz"
    ase.io.write(path, [ase_atoms(k) for k in range(2)], format="extxyz")
    res = runner.invoke(app, ["view", str(path), "--html", str(tmp_path / "page.html")])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "page.html").stat().st_size > 1000
    res = runner.invoke(app, ["view", str(tmp_path / "nothing.xyz"), "--html", str(tmp_path / "p.html")])
    assert res.exit_code == 2 and "nothing.xyz: no such file" in res.output
    hoomd = hoomd_file(tmp_path / "hoomd.gsd")
    res = runner.invoke(app, ["export", str(hoomd), "-f", "csv"])
    assert res.exit_code == 0, res.output
    assert "warning: " + str(hoomd) + ": a HOOMD GSD file has no units; its numbers are taken as SI" in res.output
