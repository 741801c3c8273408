"""Contacts recorded per frame (issue 47): `World.run(record_contacts=True)` keeps what
`World.contacts()` gives at each frame, particles named by id, in `Trajectory.contact_record`;
H5MD keeps it in `/contacts` and kinema reads it back; the LAMMPS export writes it as two
`dump local` files (between particles, with colliders) that OVITO loads as bonds; the VTK
export draws the contacts between particles as lines, read by VTK's XML reader (ParaView's)
and OVITO. The physics: a resting Hertz column's recorded normal forces are the weights above
each contact, k m g (where the engine gives the force models' contacts)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import kinema
from kinema.contact_record import FIELDS, ContactRecord
from kinema.io import export, read_contacts_dump

G = 9.81


def heap(spin=True, **collisions):
    """Twenty balls dropped on a floor and on each other: contacts between particles and
    with the floor at most frames."""
    w = kinema.World(dt=1e-3, spin=spin)
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.add(kinema.Gravity([0.0, 0.0, -G]))
    w.set_collisions(**({"restitution": 0.3, "friction": 0.5} | collisions))
    # two layers of 3 × 3 on a square lattice, the upper one over the gaps of the lower, and
    # two balls above those: they fall into one another's gaps
    lower = [[0.11 * a, 0.11 * b, 0.06] for a in range(3) for b in range(3)]
    upper = [[0.11 * a + 0.055, 0.11 * b + 0.055, 0.2] for a in range(3) for b in range(3)]
    top = [[0.11, 0.11, 0.35], [0.165, 0.165, 0.47]]
    w.add_particles(lower + upper + top, mass=0.1, radius=0.05)
    return w


def run(w, seconds=0.6, fps=20, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kinema.PlacementWarning)
        return w.run(seconds, fps=fps, record_contacts=True, **options)


@pytest.fixture(scope="module")
def recorded():
    return run(heap())


def test_each_frame_holds_what_world_contacts_gave_then_by_id(tmp_path):
    w = heap()
    w.remove_particles([0, 3])  # ids are no longer indices
    seen = []

    def keep(world):
        c = world.contacts()
        ids = world.ids
        seen.append({**c, "i": ids[c["i"]], "j": np.where(c["j"] >= 0, ids[np.maximum(c["j"], 0)], -1)})

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kinema.PlacementWarning)
        tr = w.run(0.6, fps=20, record_contacts=True, callback=keep)
    rec = tr.contact_record
    assert rec.n_frames == len(tr.t) and rec.counts.sum() > 0 and (rec["j"] >= 0).any() and (rec["j"] < 0).any()
    assert list(rec.values)[:3] == ["i", "j", "collider"]
    for k, c in enumerate(seen, start=1):  # (the callback runs after each frame but the first)
        got = rec.frame(k)
        assert set(got) == set(c)
        for name in c:
            np.testing.assert_array_equal(got[name], c[name], err_msg=name)
    assert set(np.unique(rec["i"])) <= set(tr.ids) and 0 not in rec["i"] and 3 not in rec["i"]
    np.testing.assert_array_equal(rec.counts, [len(rec.frame(k)["i"]) for k in range(rec.n_frames)])


def test_without_asking_nothing_is_recorded():
    w = heap()
    assert w.run(0.05, fps=20).contact_record is None
    with pytest.raises(TypeError, match="record_contacts"):
        w.run(0.05, fps=20, record_contacts="yes")


def test_a_resting_hertz_column_records_the_weight_above_each_contact():
    # Three balls stacked on a floor: the contact under the k-th ball from the top carries the
    # weight of k balls, k m g, along the normal (from the partner towards i), no friction force.
    w = kinema.World(dt=2e-5)
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.add(kinema.Gravity([0.0, 0.0, -G]))
    w.set_collisions(model="hertz", youngs_modulus=1e7, poisson_ratio=0.3, restitution=0.3)
    m, r = 0.1, 0.05
    w.add_particles([[0.0, 0.0, r], [0.0, 0.0, 3 * r], [0.0, 0.0, 5 * r]], mass=m, radius=r)
    tr = w.run(1.0, fps=5, record_contacts=True)
    last = tr.contact_record.frame(len(tr.t) - 1)
    if "force_n" not in last or not len(last["i"]):
        pytest.skip("this engine gives no contacts of the force models (World.contacts() before issue 47)")
    below = {(int(i), int(j)): k for k, (i, j) in enumerate(zip(last["i"], last["j"], strict=True))}
    for (i, j), load in (((0, -1), 3), ((0, 1), 2), ((1, 2), 1)):
        k = below.get((i, j), below.get((j, i)))
        assert k is not None, (i, j)
        f = last["force_n"][k]
        assert np.linalg.norm(f) == pytest.approx(load * m * G, rel=1e-6)
        np.testing.assert_allclose(f / np.linalg.norm(f), last["normal"][k], atol=1e-12)
        np.testing.assert_allclose(last["force_t"][k], 0.0, atol=1e-9)
        assert not last["sliding"][k]


# -- H5MD ---------------------------------------------------------------------------------------


def test_h5md_keeps_the_contacts_in_its_contacts_group(tmp_path, recorded):
    h5py = pytest.importorskip("h5py")
    recorded.save(tmp_path / "run.h5")
    rec = recorded.contact_record
    with h5py.File(tmp_path / "run.h5") as f:
        g = f["contacts"]
        assert f[g.attrs["particles_group"]].name == "/particles/all"
        assert g["step"].id == f["particles/all/position/step"].id
        np.testing.assert_array_equal(g["offsets"][()], rec.offsets)
        for name, a in rec.values.items():
            np.testing.assert_array_equal(g[name][()], a)
            assert g[name].attrs.get("unit") == FIELDS[name].unit
    back = kinema.Trajectory.load(tmp_path / "run.h5")
    assert list(back.contact_record.values) == list(rec.values)
    for name, a in rec.values.items():
        np.testing.assert_array_equal(back.contact_record[name], a)
    recorded.save(tmp_path / "md.h5", units="MD")
    md = kinema.Trajectory.load(tmp_path / "md.h5").contact_record
    for name, a in rec.values.items():
        np.testing.assert_allclose(md[name], a, rtol=1e-15)


def test_a_damaged_contacts_group_is_refused_by_name(tmp_path, recorded):
    h5py = pytest.importorskip("h5py")
    recorded.save(tmp_path / "run.h5")
    with h5py.File(tmp_path / "run.h5", "a") as f:
        offsets = f["contacts/offsets"][()]
        offsets[2] = offsets[3] + 1
        f["contacts/offsets"][...] = offsets
    with pytest.raises(kinema.io.TrajectoryFileError, match=r"dataset 'offsets' \(/contacts/offsets\) decrease at frame 2"):
        kinema.Trajectory.load(tmp_path / "run.h5")
    recorded.save(tmp_path / "run.h5")
    with h5py.File(tmp_path / "run.h5", "a") as f:
        i = f["contacts/i"][()]
        i[0] = 999
        f["contacts/i"][...] = i
    with pytest.raises(kinema.io.TrajectoryFileError, match="names particle 999 at row 0, which is no particle's id"):
        kinema.Trajectory.load(tmp_path / "run.h5")


def test_a_checkpointed_run_resumes_with_the_same_contacts(tmp_path):
    whole = run(heap())

    class Stop(Exception):
        pass

    def stop(w):
        if w.time > 0.35:
            raise Stop

    with pytest.raises(Stop):
        run(heap(), checkpoint=tmp_path / "c.ckpt", checkpoint_every=0.1, callback=stop)
    _, resumed = kinema.resume_run(tmp_path / "c.ckpt")
    np.testing.assert_array_equal(resumed.contact_record.offsets, whole.contact_record.offsets)
    for name, a in whole.contact_record.values.items():
        np.testing.assert_array_equal(resumed.contact_record[name], a, err_msg=name)


# -- LAMMPS dump local ----------------------------------------------------------------------------


def test_the_lammps_export_writes_dump_local_files_as_lammps_does(tmp_path, recorded):
    written = export(recorded, tmp_path / "run.lammpstrj")
    assert written == [tmp_path / "run.lammpstrj", tmp_path / "run_contacts.dump", tmp_path / "run_collider_contacts.dump"]
    rec = recorded.contact_record
    vectors = [n for n in rec.values if rec[n].ndim == 2]
    lines = (tmp_path / "run_contacts.dump").read_text().splitlines()
    atoms = (tmp_path / "run.lammpstrj").read_text().splitlines()
    at, frame = 0, 0
    while at < len(lines):  # frame by frame, the exact items of LAMMPS's dump local
        assert lines[at] == "ITEM: TIMESTEP" and int(lines[at + 1]) == round(recorded.t[frame] / recorded.dt)
        assert lines[at + 2] == "ITEM: NUMBER OF ENTRIES"
        count = int(lines[at + 3])
        box = atoms.index(next(a for a in atoms if a.startswith("ITEM: BOX BOUNDS")))
        assert lines[at + 4 : at + 8] == atoms[box : box + 4]  # the box of the atoms' dump
        header = lines[at + 8].split()
        assert header[:4] == ["ITEM:", "ENTRIES", "index", "id1"] and header[4] == "id2" and "collider" not in header
        assert len(header) - 2 == 3 + sum(2 if n in vectors else 0 for n in rec.values) + len(rec.values) - 3  # index, id1, id2: no collider
        if "force_n" in rec.values:  # (an engine whose contacts() gives the forces: issue 47)
            assert "fnx" in header and "ftz" in header and "sliding" in header
        part = rec.frame(frame)
        pairs = part["j"] >= 0
        assert count == pairs.sum()
        rows = [row.split() for row in lines[at + 9 : at + 9 + count]]
        assert [int(r[0]) for r in rows] == list(range(1, count + 1))
        np.testing.assert_array_equal([int(r[1]) - 1 for r in rows], part["i"][pairs])
        np.testing.assert_array_equal([int(r[2]) - 1 for r in rows], part["j"][pairs])
        if count:
            col = header[2:].index("nx")
            np.testing.assert_array_equal(np.array([[float(v) for v in r[col : col + 3]] for r in rows]), part["normal"][pairs])
            if "force_n" in part:
                col = header[2:].index("fnx")
                np.testing.assert_array_equal(np.array([[float(v) for v in r[col : col + 3]] for r in rows]), part["force_n"][pairs])
        at, frame = at + 9 + count, frame + 1
    assert frame == len(recorded.t)
    # kinema's reader of the two files gives the record back, split
    steps, pairs = read_contacts_dump(tmp_path / "run_contacts.dump")
    _, walls = read_contacts_dump(tmp_path / "run_collider_contacts.dump")
    np.testing.assert_array_equal(steps, np.rint(recorded.t / recorded.dt))
    between = rec["j"] >= 0
    for name, a in rec.values.items():
        np.testing.assert_array_equal(pairs[name], a[between], err_msg=name)
        np.testing.assert_array_equal(walls[name], a[~between], err_msg=name)
    np.testing.assert_array_equal(pairs.counts + walls.counts, rec.counts)
    with pytest.raises(kinema.io.TrajectoryFileError, match="a LAMMPS dump local file .* read kinema's contacts with kinema.io.read_contacts_dump"):
        kinema.Trajectory.load(tmp_path / "run_contacts.dump", units="si")


def test_ovito_loads_the_contacts_between_particles_as_bonds_with_their_forces(tmp_path, recorded):
    ovito_io = pytest.importorskip("ovito.io")
    from ovito.modifiers import LoadTrajectoryModifier

    export(recorded, tmp_path / "run.lammpstrj")
    header = (tmp_path / "run_contacts.dump").read_text().splitlines()[8].split()[2:]
    names = {"id1": "Particle Identifiers.1", "id2": "Particle Identifiers.2"}  # the others: bond properties of their own names
    pipeline = ovito_io.import_file(str(tmp_path / "run.lammpstrj"))
    local = LoadTrajectoryModifier()
    local.source.load(str(tmp_path / "run_contacts.dump"), columns=[names.get(c, f"kinema {c}") for c in header])
    pipeline.modifiers.append(local)
    rec = recorded.contact_record
    busy = [k for k in range(len(recorded.t)) if (rec.frame(k)["j"] >= 0).any()]
    assert busy
    for k in busy:
        data = pipeline.compute(k)
        part = rec.frame(k)
        pairs = part["j"] >= 0
        bonds = data.particles.bonds
        assert bonds.count == pairs.sum()
        ids = data.particles["Particle Identifier"][...]
        ends = ids[bonds.topology[...]] - 1  # OVITO's bonds name particles by index: back to kinema's ids
        np.testing.assert_array_equal(ends, np.column_stack([part["i"][pairs], part["j"][pairs]]))
        normal = np.column_stack([bonds[f"kinema n{c}"][...] for c in "xyz"])
        np.testing.assert_allclose(normal, part["normal"][pairs], rtol=1e-14, atol=0)
        np.testing.assert_allclose(bonds["kinema overlap"][...], part["overlap"][pairs], rtol=1e-14, atol=0)
        if "force_n" in part:  # (an engine whose contacts() gives the forces: issue 47)
            force = np.column_stack([bonds[f"kinema fn{c}"][...] for c in "xyz"])
            np.testing.assert_allclose(force, part["force_n"][pairs], rtol=1e-14, atol=0)
            np.testing.assert_array_equal(bonds["kinema sliding"][...], part["sliding"][pairs])


# -- VTK force chains ------------------------------------------------------------------------------


def test_vtk_draws_a_line_per_contact_between_particles_with_its_forces(tmp_path, recorded):
    vtk_xml = pytest.importorskip("vtkmodules.vtkIOXML")
    from vtkmodules.util.numpy_support import vtk_to_numpy

    written = export(recorded, tmp_path / "run.pvd")
    assert tmp_path / "run_vtk" / "run_contacts_00000.vtp" in written
    rec = recorded.contact_record
    for k in range(len(recorded.t)):
        reader = vtk_xml.vtkXMLMultiBlockDataReader()
        reader.SetFileName(str(tmp_path / "run_vtk" / f"run_{k:05d}.vtm"))
        reader.Update()
        blocks = reader.GetOutput()
        assert blocks.GetNumberOfBlocks() == 2 and blocks.GetMetaData(1).Get(blocks.NAME()) == "contacts"
        lines = blocks.GetBlock(1)
        part = rec.frame(k)
        pairs = part["j"] >= 0
        forces = "force_n" in rec.values  # (an engine whose contacts() gives the forces: issue 47)
        names = ("overlap", "id1", "id2") + (("force_n_magnitude", "force_t_magnitude", "sliding") if forces else ())
        cell = {name: vtk_to_numpy(lines.GetCellData().GetArray(name)) for name in names}
        if not pairs.any():  # one line of zero length, ids -1 (OVITO dies on a file of no lines)
            assert lines.GetNumberOfLines() == 1 and cell["id1"].tolist() == [-1]
            continue
        assert lines.GetNumberOfLines() == pairs.sum()
        np.testing.assert_array_equal(cell["id1"], part["i"][pairs])
        np.testing.assert_array_equal(cell["id2"], part["j"][pairs])
        np.testing.assert_array_equal(cell["overlap"], part["overlap"][pairs])
        if forces:
            np.testing.assert_array_equal(cell["force_n_magnitude"], np.linalg.norm(part["force_n"][pairs], axis=1))
            np.testing.assert_array_equal(cell["force_t_magnitude"], np.linalg.norm(part["force_t"][pairs], axis=1))
            np.testing.assert_array_equal(cell["sliding"], part["sliding"][pairs].astype(int))
        # each line runs from centre to centre
        points = vtk_to_numpy(lines.GetPoints().GetData()).reshape(-1, 2, 3)
        column = {int(i): c for c, i in enumerate(recorded.ids)}
        np.testing.assert_array_equal(points[:, 0], recorded.positions[k][[column[int(i)] for i in part["i"][pairs]]])
        np.testing.assert_array_equal(points[:, 1], recorded.positions[k][[column[int(j)] for j in part["j"][pairs]]])


def test_ovito_reads_the_force_chains_as_lines(tmp_path, recorded):
    ovito_io = pytest.importorskip("ovito.io")
    export(recorded, tmp_path / "run.pvd")
    pipeline = ovito_io.import_file(str(tmp_path / "run.pvd"))
    rec = recorded.contact_record
    k = max(range(len(recorded.t)), key=lambda k: (rec.frame(k)["j"] >= 0).sum())
    data = pipeline.compute(k)
    (lines,) = [o for o in data.objects if type(o).__name__ == "Lines"]
    pairs = rec.frame(k)["j"] >= 0
    assert lines.count == 2 * pairs.sum()
    ends = np.column_stack([lines[f"Particle Identifier {j}"][...] for j in (1, 2)])[::2]
    np.testing.assert_array_equal(ends, np.column_stack([rec.frame(k)["i"][pairs], rec.frame(k)["j"][pairs]]))


# -- the command line ---------------------------------------------------------------------------


SCENE = """
[world]
dim = 3
dt = 0.001
duration = 0.3
fps = 20.0

[[particles]]
type = "list"
positions = [[0, 0, 0.05], [0.12, 0, 0.05], [0.06, 0, 0.14]]
radius = 0.05

[[forces]]
type = "gravity"

[[colliders]]
type = "plane"
point = [0, 0, 0]
normal = [0, 0, 1]

[collisions]
restitution = 0.2
friction = 0.5

[output]
video = false
plot = false
{output}
"""


@pytest.mark.parametrize("how", ["flag", "scene"])
def test_kinema_run_records_and_kinema_export_writes_the_contacts(tmp_path, how):
    from typer.testing import CliRunner

    from kinema.cli import app

    cli = CliRunner()
    scene = tmp_path / "pile.toml"
    scene.write_text(SCENE.format(output="contacts = true" if how == "scene" else ""))
    out = tmp_path / "out"
    res = cli.invoke(app, ["run", str(scene), "-o", str(out), *(["--record-contacts"] if how == "flag" else [])])
    assert res.exit_code == 0, res.output
    tr = kinema.Trajectory.load(out / "trajectory.h5")
    assert tr.contact_record is not None and tr.contact_record.counts[-1] == 4  # 2 on the floor, 2 between the balls
    res = cli.invoke(app, ["export", str(out / "trajectory.h5"), "-f", "lammps"])
    assert res.exit_code == 0, res.output
    assert "trajectory_contacts.dump" in res.output and "trajectory_collider_contacts.dump" in res.output
    _, pairs = read_contacts_dump(out / "trajectory_contacts.dump")
    assert pairs.counts[-1] == 2


def test_a_record_refuses_columns_of_the_wrong_length():
    with pytest.raises(ValueError, match="column 'overlap' has shape \\(2,\\); it must have 3 rows"):
        ContactRecord(np.array([0, 1, 3]), {"i": np.zeros(3), "j": np.zeros(3), "collider": np.zeros(3), "overlap": np.zeros(2)})
    with pytest.raises(ValueError, match="offsets start at 1"):
        ContactRecord(np.array([1, 3]), {"i": np.zeros(3), "j": np.zeros(3), "collider": np.zeros(3)})


def test_a_force_chain_across_a_periodic_side_joins_the_nearest_image(tmp_path):
    vtk_xml = pytest.importorskip("vtkmodules.vtkIOXML")
    from vtkmodules.util.numpy_support import vtk_to_numpy

    # Two balls touching through the periodic x side of a unit box: the line runs from i to
    # j's image one box length away (x − 1), not across the box.
    w = kinema.World(dt=1e-3)
    w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
    w.periodic = (True, False, False)
    w.add_particles([[0.045, 0.5, 0.5], [0.955, 0.5, 0.5]], radius=0.05)
    w.set_collisions(restitution=1.0)
    tr = run(w, seconds=0.002, fps=500)
    assert tr.contact_record.frame(1)["j"].tolist() == [1]
    export(tr, tmp_path / "run.pvd")
    reader = vtk_xml.vtkXMLPolyDataReader()
    reader.SetFileName(str(tmp_path / "run_vtk" / "run_contacts_00001.vtp"))
    reader.Update()
    ends = vtk_to_numpy(reader.GetOutput().GetPoints().GetData())
    np.testing.assert_array_equal(ends[0], tr.positions[1, 0])
    np.testing.assert_allclose(ends[1], tr.positions[1, 1] - [1.0, 0.0, 0.0], rtol=0, atol=1e-15)
