"""What outside readers get of the springs, colours and species kinema's exports carry, and of
the layouts chosen so that they read the LAMMPS dump, the extended XYZ and the GSD box right:
VTK's XML readers (ParaView's library), OVITO, plyfile and Blender's PLY importer, gsd,
freud, ASE and MDAnalysis, each compared with the trajectory (docs/files.md, "Exports").

The runs: cloth_on_sphere (400 nodes, 1,482 springs), the fountain (births, emitter
colours), a periodic 3D gas of He and Ar with two masses, and a walled 2D box of "grain" and
"dust" (names that are no chemical symbol)."""

import csv
import json
import signal
import subprocess
import sys
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import kinema
from kinema.io import export
from kinema.scene import Scene

ROOT = Path(__file__).resolve().parent.parent
BLENDER = ROOT / ".venv-blender" / "bin" / "python"  # Blender as a module needs numpy < 2: its own venv


@pytest.fixture(scope="module")
def cloth():
    return Scene.from_toml(ROOT / "examples" / "scenes" / "cloth_on_sphere.toml").build().run(0.1, fps=30)


@pytest.fixture(scope="module")
def fountain():
    return Scene.from_toml(ROOT / "examples" / "scenes" / "fountain.toml").build().run(0.2, fps=30)


@pytest.fixture(scope="module")
def gas():
    """40 particles in the periodic unit box, He (0.5 kg) and Ar (2 kg) in turn."""
    w = kinema.World(dt=0.001)
    rng = np.random.default_rng(11)
    n = 40
    w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
    heavy = np.arange(n) % 2 == 1
    w.add_particles(
        rng.uniform(0.1, 0.9, size=(n, 3)),
        velocity=rng.normal(size=(n, 3)) * 2,
        mass=np.where(heavy, 2.0, 0.5),
        radius=0.02,
        species=np.where(heavy, "Ar", "He"),
    )
    w.periodic = (True, True, True)
    return w.run(0.1, fps=50)


@pytest.fixture(scope="module")
def flat():
    """30 discs in the walled box [0, 1]², every third "dust", the others "grain"."""
    w = kinema.World(dim=2, dt=0.001)
    rng = np.random.default_rng(12)
    n = 30
    w.add(kinema.Box([0, 0], [1, 1]))
    x, v = np.zeros((n, 3)), np.zeros((n, 3))
    x[:, :2], v[:, :2] = rng.uniform(0.1, 0.9, size=(n, 2)), rng.normal(size=(n, 2))
    w.add_particles(x, velocity=v, mass=1.0, radius=0.02, species=np.where(np.arange(n) % 3, "grain", "dust"))
    return w.run(0.1, fps=50)


def ends_by_id(traj, k, pairs):
    """The positions of the particles with the ids ``pairs`` (K, 2) at frame ``k``, (2K, 3)."""
    at = dict(zip(traj.ids.tolist(), traj.positions[k].tolist(), strict=True))
    return np.array([at[i] for i in np.reshape(pairs, -1).tolist()]).reshape(-1, 3)


def ovito_import(path):
    ovito_io = pytest.importorskip("ovito.io")
    return ovito_io.import_file(str(path))


def type_names(particles):
    """OVITO's Particle Type of each particle, by name."""
    types = particles.particle_types
    return [types.type_by_id(t).name for t in np.asarray(types[...])]


def read_vtk(path, multiblock=False):
    vtk_xml = pytest.importorskip("vtkmodules.vtkIOXML")
    reader = vtk_xml.vtkXMLMultiBlockDataReader() if multiblock else vtk_xml.vtkXMLPolyDataReader()
    reader.SetFileName(str(path))
    reader.Update()
    assert reader.GetErrorCode() == 0
    return reader.GetOutput()


def numpy_of(array):
    from vtkmodules.util.numpy_support import vtk_to_numpy

    return vtk_to_numpy(array)


def blender_ply(paths):
    """Each PLY imported by Blender 5.0's importer (``bpy.ops.wm.ply_import``, as File → Import
    → Stanford PLY does), in Blender's own interpreter: its vertices, edges and attributes."""
    if not BLENDER.exists():
        pytest.skip(f"no Blender (bpy) at {BLENDER}")
    script = """
import json, sys
import bpy
out = []
for path in sys.argv[1:]:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.wm.ply_import(filepath=path)
    me = bpy.context.selected_objects[0].data
    attrs = {}
    for a in me.attributes:
        if a.name.startswith(".") or a.name == "position":
            continue
        attrs[a.name] = [list(d.color)[:3] for d in a.data] if a.data_type == "FLOAT_COLOR" else [d.value for d in a.data]
    out.append({"positions": [list(v.co) for v in me.vertices], "edges": [list(e.vertices) for e in me.edges], "attributes": attrs})
print("JSON" + json.dumps(out))
"""
    run = subprocess.run([str(BLENDER), "-c", script, *map(str, paths)], capture_output=True, text=True, timeout=300)
    if run.returncode and "No module named 'bpy'" in run.stderr:
        pytest.skip(f"{BLENDER} cannot import bpy")
    assert run.returncode == 0, run.stderr[-2000:]
    return json.loads(next(line for line in run.stdout.splitlines() if line.startswith("JSON"))[4:])


def srgb_to_linear(c):
    """The sRGB transfer function undone: how Blender keeps an sRGB colour (its importer's
    default, import_colors='SRGB') as the linear floats of a colour attribute."""
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


# -- springs: VTK ------------------------------------------------------------------------------


def test_vtk_springs_read_by_vtk(tmp_path, cloth):
    assert cloth.springs.shape == (1482, 2)
    written = export(cloth, tmp_path / "run.pvd")
    frames = len(cloth.t)
    # per frame a multi-block file, its particles and its springs
    assert [p.name for p in written[:5]] == ["run.pvd", "run_colliders.vtp", "run_00000.vtm", "run_00000.vtp", "run_springs_00000.vtp"]
    assert len(written) == 2 + 3 * frames
    datasets = ET.parse(tmp_path / "run.pvd").getroot().findall("Collection/DataSet")
    assert [d.get("file") for d in datasets] == [f"run_vtk/run_{k:05d}.vtm" for k in range(frames)]
    for k, d in enumerate(datasets):
        blocks = read_vtk(tmp_path / d.get("file"), multiblock=True)
        assert blocks.GetNumberOfBlocks() == 2
        particles, springs = blocks.GetBlock(0), blocks.GetBlock(1)
        np.testing.assert_array_equal(numpy_of(particles.GetPoints().GetData()), cloth.positions[k])
        assert particles.GetNumberOfVerts() == 400 and particles.GetNumberOfLines() == 0
        # one line per spring between two points of its own at the ends' positions
        assert springs.GetNumberOfLines() == 1482 and springs.GetNumberOfVerts() == 0
        connectivity = numpy_of(springs.GetLines().GetConnectivityArray())
        assert connectivity.tolist() == list(range(2 * 1482)) and numpy_of(springs.GetLines().GetOffsetsArray()).tolist() == list(range(0, 2 * 1482 + 1, 2))
        ends = np.column_stack([numpy_of(springs.GetCellData().GetArray(a)) for a in ("id1", "id2")])
        np.testing.assert_array_equal(ends, cloth.springs)
        np.testing.assert_array_equal(numpy_of(springs.GetPoints().GetData()), ends_by_id(cloth, k, cloth.springs))


def test_ovito_reads_the_vtk_springs_as_lines(tmp_path, cloth):
    export(cloth, tmp_path / "run.pvd")
    pipeline = ovito_import(tmp_path / "run.pvd")
    assert pipeline.source.num_frames == len(cloth.t)
    for k in range(len(cloth.t)):
        data = pipeline.compute(k)
        assert data.particles.count == 400 and data.attributes["Time"] == cloth.t[k]
        np.testing.assert_array_equal(data.particles.positions[...], cloth.positions[k])
        assert data.particles.bonds is None  # VTK gives OVITO lines, not bonds (GSD does)
        (lines,) = [o for o in data.objects if type(o).__name__ == "Lines"]
        assert lines.identifier == "particle-particle-contacts" and lines.count == 2 * 1482
        ends = np.column_stack([lines[f"Particle Identifier {j}"][...] for j in (1, 2)])[::2]
        np.testing.assert_array_equal(ends, cloth.springs)
        np.testing.assert_array_equal(lines["Position"][...], ends_by_id(cloth, k, cloth.springs))


def test_why_the_springs_have_a_file_of_their_own(tmp_path, cloth):
    # A frame's particles file with the springs as line cells: OVITO does not open it.
    from kinema.io import vtk_writer

    pytest.importorskip("ovito.io")
    k = np.arange(2 * 3, dtype=np.int64)
    x = cloth.positions[0][:6]
    verts = np.arange(6, dtype=np.int64)
    (tmp_path / "both.vtp").write_text(vtk_writer._polydata(x, verts=(verts, verts + 1), lines=(k, k[1::2] + 1)))
    with pytest.raises(RuntimeError, match="Could not detect the file format"):
        ovito_import(tmp_path / "both.vtp")
    # A springs file of no lines: OVITO 3.17 dies of a floating point exception (SIGFPE).
    none = np.zeros(0, dtype=np.int64)
    empty = vtk_writer._polydata(
        np.zeros((0, 3)), cell_data=[vtk_writer._vtk_array("id1", none), vtk_writer._vtk_array("id2", none)], declared=("Lines",), lines=(none, none)
    )
    (tmp_path / "empty.vtp").write_text(empty)
    run = subprocess.run(
        [sys.executable, "-c", "import sys; from ovito.io import import_file; import_file(sys.argv[1]).compute()", str(tmp_path / "empty.vtp")],
        capture_output=True,
        timeout=120,
    )
    assert run.returncode == -signal.SIGFPE


# -- springs: PLY, GSD ---------------------------------------------------------------------------


def test_ply_edges_read_by_plyfile(tmp_path, cloth):
    plyfile = pytest.importorskip("plyfile")
    paths = export(cloth, tmp_path / "run.ply")
    for path in paths:
        ply = plyfile.PlyData.read(str(path))
        assert [e.name for e in ply.elements] == ["vertex", "edge"]
        ids, edge = np.asarray(ply["vertex"]["id"]), ply["edge"]
        assert edge.count == 1482 and [p.name for p in edge.properties] == ["vertex1", "vertex2"]
        np.testing.assert_array_equal(ids[np.column_stack([edge["vertex1"], edge["vertex2"]])], cloth.springs)


def test_gsd_bonds_read_by_gsd_ovito_and_mdanalysis(tmp_path, cloth):
    gsd_hoomd = pytest.importorskip("gsd.hoomd")
    export(cloth, tmp_path / "run.gsd")
    with gsd_hoomd.open(str(tmp_path / "run.gsd")) as f:
        for frame in f:
            b = frame.bonds
            assert b.N == 1482 and list(b.types) == ["spring"] and b.typeid.tolist() == [0] * 1482
            np.testing.assert_array_equal(frame.log["particles/kinema/id"][b.group], cloth.springs)
    pipeline = ovito_import(tmp_path / "run.gsd")
    for k in range(len(cloth.t)):
        bonds = pipeline.compute(k).particles.bonds
        assert bonds.count == 1482 and [t.name for t in bonds.bond_types.types] == ["spring"]
        np.testing.assert_array_equal(cloth.ids[bonds.topology[...]], cloth.springs)
    mda = pytest.importorskip("MDAnalysis")
    u = mda.Universe(str(tmp_path / "run.gsd"))
    assert len(u.trajectory) == len(cloth.t) and len(u.bonds) == 1482
    assert {tuple(b) for b in u.bonds.indices.tolist()} == {tuple(sorted(b)) for b in cloth.springs.tolist()}  # ids 0..399 are the indices


def test_blender_imports_the_ply_edges_colours_and_types(tmp_path, cloth, fountain, gas):
    plys = [export(cloth, tmp_path / "cloth.ply")[-1], export(fountain, tmp_path / "fountain.ply")[-1], export(gas, tmp_path / "gas.ply")[-1]]
    got = dict(zip(("cloth", "fountain", "gas"), blender_ply(plys), strict=True))
    for name, traj in (("cloth", cloth), ("fountain", fountain), ("gas", gas)):
        want, mesh = traj.frame(len(traj.t) - 1), got[name]
        np.testing.assert_array_equal(mesh["positions"], want["positions"].astype(np.float32))
        np.testing.assert_array_equal(mesh["attributes"]["id"], want["ids"])  # a float attribute: exact below 2^24
        for j, name in enumerate(("vx", "vy", "vz")):
            np.testing.assert_array_equal(mesh["attributes"][name], want["velocities"][:, j].astype(np.float32))
        np.testing.assert_array_equal(mesh["attributes"]["radius"], want["radii"].astype(np.float32))
    edges = np.array(got["cloth"]["edges"])
    assert len(edges) == 1482 and {tuple(sorted(e)) for e in cloth.ids[edges].tolist()} == {tuple(sorted(s)) for s in cloth.springs.tolist()}
    # red green blue as the colour attribute Col: the bytes as sRGB, kept linear in float32
    # (Blender converts in float32: a few units in the last place; one byte more or less is
    # at least 3e-4 away in linear terms)
    want = fountain.frame(len(fountain.t) - 1)
    np.testing.assert_allclose(got["fountain"]["attributes"]["Col"], srgb_to_linear(np.round(want["colors"] * 255) / 255), rtol=1e-6, atol=0)
    assert got["gas"]["attributes"]["type"] == [["Ar", "He"].index(s) for s in gas.species.tolist()]


# -- colours -------------------------------------------------------------------------------------


def test_colours_read_in_every_format(tmp_path, fountain):
    k = len(fountain.t) - 1
    want = fountain.frame(k)
    colors = want["colors"]
    assert np.isfinite(colors).all() and len(colors) > 20  # the emitter's #2f7fd8
    for name in ("run.pvd", "run.ply", "run.xyz", "run.csv", "run.gsd"):
        export(fountain, tmp_path / name)
    # VTK: point data Color, float64; OVITO maps it to its Color (float64, exact)
    poly = read_vtk(tmp_path / "run_vtk" / f"run_{k:05d}.vtp")
    np.testing.assert_array_equal(numpy_of(poly.GetPointData().GetArray("Color")), colors)
    np.testing.assert_array_equal(ovito_import(tmp_path / "run.pvd").compute(k).particles["Color"][...], colors)
    # PLY: uchar red green blue
    plyfile = pytest.importorskip("plyfile")
    vertex = plyfile.PlyData.read(str(tmp_path / "run_ply" / f"run_{k:05d}.ply"))["vertex"]
    rgb = np.column_stack([vertex[c] for c in ("red", "green", "blue")])
    assert rgb.dtype == np.uint8 and rgb.tolist() == [[47, 127, 216]] * len(colors)
    # extended XYZ: color:R:3, ASE's atoms.arrays["color"] and OVITO's Color
    ase_io = pytest.importorskip("ase.io")
    np.testing.assert_array_equal(ase_io.read(tmp_path / "run.xyz", index=k).arrays["color"], colors)
    # (float32; OVITO 3.17's number parser lands up to 2 units in the last place off)
    np.testing.assert_array_max_ulp(ovito_import(tmp_path / "run.xyz").compute(k).particles["Color"][...], colors.astype(np.float32), maxulp=2)
    # GSD: log/particles/Color (float32), OVITO's Color
    gsd_hoomd = pytest.importorskip("gsd.hoomd")
    with gsd_hoomd.open(str(tmp_path / "run.gsd")) as f:
        np.testing.assert_array_equal(f[k].log["particles/Color"], colors.astype(np.float32))
    np.testing.assert_array_equal(ovito_import(tmp_path / "run.gsd").compute(k).particles["Color"][...], colors.astype(np.float32))
    # CSV: r,g,b
    with open(tmp_path / "run.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if int(r["frame"]) == k]
    np.testing.assert_array_equal([[float(r[c]) for c in "rgb"] for r in rows], colors)


def coloured(colors):
    rng = np.random.default_rng(3)
    n = len(colors)
    return SimpleNamespace(
        t=np.array([0.0, 0.1]), positions=rng.normal(size=(2, n, 3)), velocities=rng.normal(size=(2, n, 3)), colors=np.array(colors, dtype=float)
    )


def test_a_particle_without_its_own_colour_gets_the_renderers(tmp_path):
    traj = coloured([[1.0, 0.0, 0.25], [np.nan, np.nan, np.nan]])
    grey = np.array(kinema.render.NO_OWN_COLOR) / 255  # (70, 130, 200): what a video draws it with
    plyfile = pytest.importorskip("plyfile")
    vertex = plyfile.PlyData.read(str(export(traj, tmp_path / "run.ply")[0]))["vertex"]
    assert np.column_stack([vertex[c] for c in ("red", "green", "blue")]).tolist() == [[255, 0, 64], [70, 130, 200]]
    export(traj, tmp_path / "run.csv")
    with open(tmp_path / "run.csv", newline="") as f:
        rows = list(csv.DictReader(f))[:2]
    np.testing.assert_array_equal([[float(r[c]) for c in "rgb"] for r in rows], [[1.0, 0.0, 0.25], grey])


@pytest.mark.parametrize("name", ["run.pvd", "run.ply", "run.xyz", "run.csv", "run.gsd"])
def test_a_bad_colour_is_refused_before_anything_is_written(tmp_path, name):
    pytest.importorskip("gsd.hoomd")
    with pytest.raises(ValueError, match=r"color.*\[0\.5, 1\.5, 0"):
        export(coloured([[0.0, 0.0, 0.0], [0.5, 1.5, 0.0]]), tmp_path / name)
    assert list(tmp_path.iterdir()) == []


# -- species -------------------------------------------------------------------------------------


def test_vtk_ply_and_csv_species(tmp_path, flat):
    names = flat.species.tolist()
    typeid = [["dust", "grain"].index(s) for s in names]  # the sorted names
    export(flat, tmp_path / "run.pvd")
    poly = read_vtk(tmp_path / "run_vtk" / "run_00002.vtp")
    table = poly.GetFieldData().GetAbstractArray("type_names")
    assert [table.GetValue(j) for j in range(table.GetNumberOfValues())] == ["dust", "grain"]
    assert numpy_of(poly.GetPointData().GetArray("type")).tolist() == typeid
    # OVITO's VTP reader takes 'type' as Aspherix's material type and reads no names
    data = ovito_import(tmp_path / "run_vtk" / "run_00002.vtp").compute()
    assert data.particles["Material Type"][...].tolist() == typeid
    plyfile = pytest.importorskip("plyfile")
    ply = plyfile.PlyData.read(str(export(flat, tmp_path / "run.ply")[2]))
    assert ply.comments[-2:] == ["type 0 dust", "type 1 grain"] and ply["vertex"]["type"].tolist() == typeid
    export(flat, tmp_path / "run.csv")
    with open(tmp_path / "run.csv", newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["frame"] == "2"]
    assert [r["species"] for r in rows] == names


# -- LAMMPS dump ---------------------------------------------------------------------------------


def dump_lo(path):
    """The lower corner of the dump's box (the first frame's; the same in every frame)."""
    rows = path.read_text().split("ITEM: BOX BOUNDS", 1)[1].splitlines()[1:4]
    return np.array([float(r.split()[0]) for r in rows])


def test_the_dump_layout(tmp_path, gas, flat):
    export(gas, tmp_path / "gas.lammpstrj")
    export(flat, tmp_path / "flat.lammpstrj")
    text = (tmp_path / "gas.lammpstrj").read_text()
    # ITEM: UNITS si once, then each frame ITEM: TIME and N + 9 lines (LAMMPS's `dump_modify
    # units yes time yes`; issue 49: the times read back exactly)
    assert text.startswith(
        "ITEM: UNITS\nsi\nITEM: TIME\n0.0\nITEM: TIMESTEP\n0\nITEM: NUMBER OF ATOMS\n40\nITEM: BOX BOUNDS pp pp pp\n0.0 1.0\n0.0 1.0\n0.0 1.0\n"
        "ITEM: ATOMS id type element x y z vx vy vz radius mass group\n"
    )
    assert len(text.splitlines()) == 2 + len(gas.t) * (40 + 11) and text.count("ITEM: UNITS") == 1
    assert "1 2 He " in text and "2 1 Ar " in text  # types 1 Ar, 2 He (sorted names); ids from 1
    # names that are not chemical symbols: no element column
    assert "ITEM: ATOMS id type x y z vx vy vz radius mass group\n" in (tmp_path / "flat.lammpstrj").read_text()


@pytest.mark.parametrize("run", ["gas", "flat", "cloth"])
def test_mdanalysis_reads_the_dump(tmp_path, run, request):
    # MDAnalysis takes a frame's first line for ITEM: TIMESTEP: it reads the plain layout
    # (plain_dump=True), and refuses the default one, whose ITEM: UNITS and ITEM: TIME
    # LAMMPS's own dump_modify units yes time yes writes too
    mda = pytest.importorskip("MDAnalysis")
    traj = request.getfixturevalue(run)
    export(traj, tmp_path / "full.lammpstrj")
    with pytest.raises(ValueError, match="Failed to construct topology"):
        mda.Universe(str(tmp_path / "full.lammpstrj"), format="LAMMPSDUMP", dt=traj.dt)
    path = tmp_path / "run.lammpstrj"
    export(traj, path, plain_dump=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # 'Guessed all Masses', elements it does not know
        # the topology from the dump itself; dt the steps' length (the run's step where dt
        # does not divide its frames: TIMESTEP counts those steps)
        u = mda.Universe(str(path), format="LAMMPSDUMP", dt=traj.step or traj.dt)
    lo = dump_lo(path)
    assert len(u.trajectory) == len(traj.t) and len(u.atoms) == traj.positions.shape[1]
    assert u.atoms.ids.tolist() == (traj.ids + 1).tolist()  # LAMMPS's ids, from 1
    np.testing.assert_array_equal(u.atoms.masses, traj.masses)  # the mass column, float64
    names = sorted(set(traj.species.tolist())) if traj.species is not None else ["A"]
    kinds = [names.index(s) + 1 for s in traj.species.tolist()] if traj.species is not None else [1] * len(traj.ids)
    assert u.atoms.types.tolist() == [str(t) for t in kinds]
    if run == "gas":
        assert u.atoms.elements.tolist() == traj.species.tolist()
    for k, ts in enumerate(u.trajectory):
        # float32, and moved so that the box starts at 0 (MDAnalysis's convention)
        np.testing.assert_array_equal(ts.positions, (traj.positions[k].astype(np.float32).astype(np.float64) - lo).astype(np.float32))
        np.testing.assert_array_equal(ts.velocities, traj.velocities[k].astype(np.float32))
        assert ts.time == pytest.approx(traj.t[k], rel=1e-15, abs=1e-300)  # TIMESTEP x the step


def test_ase_reads_the_dump_in_si_units(tmp_path, gas, flat):
    ase_io = pytest.importorskip("ase.io")
    from ase.data import atomic_masses, atomic_numbers, chemical_symbols
    from ase.units import m, s

    export(gas, tmp_path / "gas.lammpstrj")
    for k, atoms in enumerate(ase_io.read(tmp_path / "gas.lammpstrj", index=":", format="lammps-dump-text", units="si")):
        np.testing.assert_allclose(atoms.positions / m, gas.positions[k], rtol=2e-16, atol=0)  # Å, converted from m
        np.testing.assert_allclose(atoms.get_velocities() / (m / s), gas.velocities[k], rtol=1e-15, atol=0)
        assert atoms.get_chemical_symbols() == gas.species.tolist()  # the element column
        # masses are ASE's own, by element (it reads no mass column), not kinema's 0.5 and 2 kg
        np.testing.assert_array_equal(atoms.get_masses(), [atomic_masses[atomic_numbers[x]] for x in gas.species])
    # ASE's default units are LAMMPS's metal: the velocities come out 100/0.98 times too small
    # and the positions keep the numbers in m
    metal = ase_io.read(tmp_path / "gas.lammpstrj", index=0, format="lammps-dump-text")
    np.testing.assert_allclose(metal.get_velocities() / gas.velocities[0], 0.01018, rtol=1e-3)
    np.testing.assert_array_equal(metal.positions, gas.positions[0])
    # without an element column ASE names each atom by the element whose mass (amu) is nearest
    # the mass column's number (kg): 1 kg gives H
    export(flat, tmp_path / "flat.lammpstrj")
    atoms = ase_io.read(tmp_path / "flat.lammpstrj", index=0, format="lammps-dump-text", units="si")
    assert set(atoms.get_chemical_symbols()) == {chemical_symbols[np.argmin(np.abs(atomic_masses - 1.0))]}


def test_ovito_reads_the_dump(tmp_path, gas):
    export(gas, tmp_path / "run.lammpstrj")
    pipeline = ovito_import(tmp_path / "run.lammpstrj")
    assert pipeline.source.num_frames == len(gas.t)
    for k in range(len(gas.t)):
        data = pipeline.compute(k)
        p = data.particles
        assert data.attributes["Timestep"] == round(gas.t[k] / gas.dt) and data.attributes["Time"] == gas.t[k]
        assert type_names(p) == gas.species.tolist()  # named by the element column
        np.testing.assert_array_max_ulp(p.positions[...], gas.positions[k], maxulp=2)  # OVITO 3.17's parser, not the file
        np.testing.assert_array_max_ulp(p["Velocity"][...], gas.velocities[k], maxulp=2)
        np.testing.assert_array_equal(p["Mass"][...], gas.masses)


def test_ovito_numbers_the_types_of_a_dump_without_element(tmp_path, flat):
    export(flat, tmp_path / "run.lammpstrj")
    p = ovito_import(tmp_path / "run.lammpstrj").compute(0).particles
    assert [(t.id, t.name) for t in p.particle_types.types] == [(1, ""), (2, "")]
    assert p.particle_types[...].tolist() == [["dust", "grain"].index(s) + 1 for s in flat.species.tolist()]


def test_mdanalysis_fails_on_a_dump_with_units_and_time(tmp_path, gas):
    # why the dump has no ITEM: UNITS or ITEM: TIME (LAMMPS's dump_modify units yes time yes)
    mda = pytest.importorskip("MDAnalysis")
    export(gas, tmp_path / "run.lammpstrj")
    frames = (tmp_path / "run.lammpstrj").read_text().split("ITEM: TIMESTEP\n")[1:]
    with_time = "ITEM: UNITS\nsi\n" + "".join(f"ITEM: TIME\n{t!r}\nITEM: TIMESTEP\n{f}" for t, f in zip(gas.t.tolist(), frames, strict=True))
    (tmp_path / "timed.lammpstrj").write_text(with_time)
    with pytest.raises(ValueError), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mda.Universe(str(tmp_path / "timed.lammpstrj"), format="LAMMPSDUMP")


def test_mdanalysis_reads_no_dump_or_xyz_whose_particles_come_and_go(tmp_path, fountain):
    mda = pytest.importorskip("MDAnalysis")
    assert fountain.changes_count
    export(fountain, tmp_path / "run.lammpstrj")
    export(fountain, tmp_path / "run.xyz")
    for path, kind in ((tmp_path / "run.lammpstrj", "LAMMPSDUMP"), (tmp_path / "run.xyz", "XYZ")):
        with pytest.raises((ValueError, EOFError)), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            u = mda.Universe(str(path), format=kind)
            for _ in u.trajectory:
                pass


# -- extended XYZ --------------------------------------------------------------------------------


@pytest.mark.parametrize("run", ["gas", "flat"])
def test_xyz_with_species_read_by_mdanalysis_ase_and_ovito(tmp_path, run, request):
    traj = request.getfixturevalue(run)
    path = tmp_path / "run.xyz"
    export(traj, path)
    names = traj.species.tolist()
    assert path.read_text().splitlines()[1].split("Properties=")[1].startswith("type:S:1:pos:R:3:species:S:1:velo:R:3")
    mda = pytest.importorskip("MDAnalysis")
    interval = float(traj.t[1] - traj.t[0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # masses it cannot guess for 'grain'
        u = mda.Universe(str(path), format="XYZ", dt=interval)
    assert u.atoms.names.tolist() == names and len(u.trajectory) == len(traj.t)
    for k, ts in enumerate(u.trajectory):
        np.testing.assert_array_equal(ts.positions, traj.positions[k].astype(np.float32))
        assert ts.time == pytest.approx(k * interval, rel=1e-15, abs=1e-300) and not ts.has_velocities
    if run == "flat":
        assert u.atoms.masses.tolist() == [0.0] * len(names)  # no mass it can guess for 'grain'
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert [ts.time for ts in mda.Universe(str(path), format="XYZ").trajectory] == [float(k) for k in range(len(traj.t))]  # ps
    ase_io = pytest.importorskip("ase.io")
    atoms = ase_io.read(path, index=2)
    assert atoms.arrays["type"].tolist() == names
    assert atoms.get_chemical_symbols() == [x if x in ("He", "Ar") else "X" for x in names]
    np.testing.assert_array_equal(atoms.positions, traj.positions[2])
    np.testing.assert_array_equal(atoms.get_masses(), traj.masses)
    data = ovito_import(path).compute(2)
    assert type_names(data.particles) == names
    np.testing.assert_array_max_ulp(data.particles.positions[...], traj.positions[2], maxulp=2)


# -- GSD's box: freud and OVITO ------------------------------------------------------------------


def walled_3d():
    """30 balls in the box [0, 1]³, periodic along x only: walls along y and z."""
    w = kinema.World(dt=0.001)
    rng = np.random.default_rng(13)
    w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
    w.add_particles(rng.uniform(0.05, 0.95, size=(30, 3)), velocity=rng.normal(size=(30, 3)), radius=0.02)
    w.periodic = (True, False, False)
    return w.run(0.05, fps=50)


def pairs_brute_force(points, lengths, periodic, r_max):
    """Ordered pairs i != j closer than ``r_max``: the nearest image along the periodic axes,
    the plain difference along the others."""
    d = points[:, None, :] - points[None, :, :]
    d[..., periodic] -= np.rint(d[..., periodic] / lengths[periodic]) * lengths[periodic]
    r = np.linalg.norm(d, axis=2)
    np.fill_diagonal(r, np.inf)
    return int((r < r_max).sum())


@pytest.mark.parametrize("run", ["flat", "walled_3d", "gas"])
def test_freud_finds_no_pair_across_a_wall_and_wraps_the_periodic_axes(tmp_path, run, request):
    freud = pytest.importorskip("freud")
    gsd_hoomd = pytest.importorskip("gsd.hoomd")
    traj = walled_3d() if run == "walled_3d" else request.getfixturevalue(run)
    export(traj, tmp_path / "run.gsd")
    dim = traj.dim
    periodic = np.resize(np.asarray(traj.periodic or (False,), dtype=bool), 3)[:dim]
    with gsd_hoomd.open(str(tmp_path / "run.gsd")) as f:
        frame = f[len(f) - 1]
    box = freud.box.Box.from_box(frame.configuration.box, dimensions=frame.configuration.dimensions)
    lengths = np.asarray(frame.configuration.box[:dim], dtype=np.float64)
    points = frame.particles.position
    r_max = 0.499 * float(lengths.min())  # near the largest freud allows
    found = freud.locality.AABBQuery(box, points).query(points, {"r_max": r_max, "exclude_ii": True}).toNeighborList()
    want = pairs_brute_force(points[:, :dim].astype(np.float64), lengths, periodic, r_max)
    assert want > 0 and len(found) == want
    assert frame.log["kinema/periodic"][:dim].tolist() == periodic.tolist()
    np.testing.assert_array_equal(lengths[~periodic], 2.0)  # the unit box's walls, doubled
    if periodic.any():  # a pair across a periodic side is found
        unwrapped = pairs_brute_force(points[:, :dim].astype(np.float64), lengths, np.zeros(dim, dtype=bool), r_max)
        assert want > unwrapped


def test_ovito_reads_the_padded_gsd_box(tmp_path, flat):
    export(flat, tmp_path / "run.gsd")
    data = ovito_import(tmp_path / "run.gsd").compute(3)
    assert data.cell.is2D and tuple(data.cell.pbc)[:2] == (True, True)
    np.testing.assert_array_equal(data.cell[:2, :2], 2 * np.eye(2))  # the walls [0, 1] doubled
    np.testing.assert_array_equal(data.cell[:2, 3], [-1.0, -1.0])  # centred at 0
    origin = np.array(data.attributes["kinema/origin"])
    assert origin.tolist() == [0.5, 0.5, 0.0] and data.attributes["kinema/periodic"] == (0, 0, 0)
    np.testing.assert_allclose(data.particles.positions[...] + origin, flat.positions[3], rtol=0, atol=6e-8)


# -- PLY in tools that trip on kinema's files: meshio, Blender ----------------------------------

MESHIO_READ = "import sys, meshio\nm = meshio.read(sys.argv[1])\nprint('POINTS', len(m.points), 'LINES', sum(len(c.data) for c in m.cells if c.type == 'line'))"


def meshio_read(path):
    """`meshio.read(path)` in a Python of its own: meshio calls sys.exit(1) on a file it cannot
    read, which would end the test run."""
    pytest.importorskip("meshio")
    return subprocess.run(
        [sys.executable, "-c", MESHIO_READ, str(path)],
        capture_output=True,
        text=True,
        timeout=120,
        env={**__import__("os").environ, "PYTHONPATH": ":".join(sys.path)},
    )


def test_meshio_reads_the_ply_frames_without_springs_and_exits_on_the_springs(tmp_path, cloth):
    # meshio 5.3's PLY reader knows the elements `vertex` and `face` only: on kinema's springs
    # (`element edge`, the PLY standard's, which Blender imports as the mesh's edges) it prints
    # "Expected `element vertex` or `element face`" and exits the interpreter (sys.exit(1)).
    # Springs as 2-vertex faces, which meshio reads as lines, Blender's importer drops, so
    # kinema keeps the edges and docs/files.md says so; without springs meshio reads every frame.
    import dataclasses

    (first, *_) = export(cloth, tmp_path / "cloth.ply")
    run = meshio_read(first)
    assert run.returncode == 1 and "element edge 1482" in run.stdout + run.stderr
    back = kinema.load_trajectory(tmp_path / "cloth_ply")  # kinema's reader reads the frames (not the springs)
    assert back.positions.shape == cloth.positions.shape
    (bare, *_) = export(dataclasses.replace(cloth, springs=None), tmp_path / "bare.ply")
    run = meshio_read(bare)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "POINTS 400 LINES 0" in run.stdout


def emitter_run():
    w = kinema.World(dt=1e-3)
    w.add(kinema.Gravity())
    w.add(kinema.Emitter(rate=200, speed=2.0, direction=[0, 0, 1], spread=0.3, lifetime=0.5, particle_radius=0.01, seed=3))
    return w.run(0.1, fps=60)


def test_an_emitters_empty_first_ply_frame(tmp_path):
    # An emitter's frame 0 has no particles: its PLY is a legal one of `element vertex 0`,
    # which kinema and meshio read (0 points) and Blender 5.0's importer refuses ("PLY
    # Importer: failed importing, no vertices", a RuntimeError from the operator). kinema
    # still writes it, so that file k is frame k of the series; docs/files.md says so.
    traj = emitter_run()
    assert not traj.alive[0].any() and traj.alive[1].any()
    written = export(traj, tmp_path / "em.ply")
    assert len(written) == len(traj.t)
    back = kinema.load_trajectory(tmp_path / "em_ply")
    np.testing.assert_array_equal(back.alive.sum(axis=1), traj.alive.sum(axis=1))
    run = meshio_read(written[0])
    assert run.returncode == 0 and "POINTS 0 LINES 0" in run.stdout, run.stderr[-2000:]
    if not BLENDER.exists():
        pytest.skip(f"no Blender (bpy) at {BLENDER}")
    script = """
import sys
import bpy
for path in sys.argv[1:]:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    try:
        print("RESULT", sorted(bpy.ops.wm.ply_import(filepath=path)), len(bpy.context.selected_objects[0].data.vertices))
    except RuntimeError as e:
        print("REFUSED", str(e).strip().replace(chr(10), " "))
"""
    run = subprocess.run([str(BLENDER), "-c", script, str(written[0]), str(written[1])], capture_output=True, text=True, timeout=300)
    if run.returncode and "No module named 'bpy'" in run.stderr:
        pytest.skip(f"{BLENDER} cannot import bpy")
    assert run.returncode == 0, run.stderr[-2000:]
    lines = [line for line in run.stdout.splitlines() if line.startswith(("RESULT", "REFUSED"))]
    assert lines[0].startswith("REFUSED") and "no vertices" in lines[0]
    assert lines[1] == f"RESULT ['FINISHED'] {traj.alive[1].sum()}"
