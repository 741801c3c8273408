"""kinema's H5MD files read by the community's H5MD readers, and H5MD files written the way
other programs write them read by kinema.io.load_h5md.

The readers (requirements/formats-test.txt): znh5md (ASE's H5MD reader, also ase.io's
"znh5md" format), pyh5md and MDAnalysis's H5MDReader; a test whose reader is not installed is
skipped. What they do not read, and why, is in docs/files.md ("H5MD")."""

from fractions import Fraction

import numpy as np
import pytest

import kinema
from kinema.io import TrajectoryFileError, load_h5md, save_h5md
from kinema.io.h5md import parse_unit
from kinema.io.h5md_units import from_si

h5py = pytest.importorskip("h5py")


def box_run(periodic=(True, True, False)):
    """Four particles in a box of sides 1, 2 and 3 m, periodic along x and y by default, fast
    enough to cross the periodic faces: 6 frames every 2 steps of dt = 0.01 s."""
    w = kinema.World(dt=0.01)
    w.add(kinema.Box([0, 0, 0], [1, 2, 3]))
    rng = np.random.default_rng(5)
    w.add_particles(rng.uniform(0.1, 0.9, size=(4, 3)), velocity=rng.normal(size=(4, 3)) * 5, mass=[1.0, 2.0, 3.0, 4.0], radius=0.02)
    w.periodic = periodic
    return w.run(0.1, fps=50)


def open_run():
    """Three particles falling in open space (no box): 5 frames."""
    w = kinema.World(dt=0.01)
    w.add_particles([[0.0, 0.0, 1.0], [0.5, 0.0, 2.0], [1.0, 1.0, 3.0]], velocity=[0.5, 0.0, 1.0], mass=[1.0, 1.0, 2.0], radius=0.1)
    w.add(kinema.Gravity())
    return w.run(0.08, fps=50)


@pytest.fixture
def saved(tmp_path):
    traj = box_run()
    assert traj.periodic == (True, True, False)
    np.testing.assert_array_equal(traj.box_edges, [1.0, 2.0, 0.0])
    return traj, save_h5md(traj, tmp_path / "run.h5")


# -- kinema's files read by the others ------------------------------------------------------------


def test_znh5md_reads_kinema_files(saved):
    # znh5md reads no units: ASE gets kinema's SI values as they are (positions in m read as
    # "Å"), which are compared here; what it needs of the layout is what is checked: species,
    # mass, radius and id as time-dependent elements, box/edges/value, box/pbc.
    znh5md = pytest.importorskip("znh5md")
    import ase.io

    traj, path = saved
    frames = znh5md.IO(path)[:]
    assert len(frames) == len(traj.t) == 6
    for read in (frames, ase.io.read(path, index=":", format="znh5md")):
        for i, atoms in enumerate(read):
            np.testing.assert_array_equal(atoms.positions, traj.positions[i])
            np.testing.assert_allclose(atoms.get_velocities(), traj.velocities[i], rtol=1e-15, atol=0)  # momenta / masses
            np.testing.assert_array_equal(atoms.cell.array, np.diag([1.0, 2.0, 0.0]))
            np.testing.assert_array_equal(atoms.pbc, [True, True, False])
            np.testing.assert_array_equal(atoms.get_masses(), traj.masses)
            np.testing.assert_array_equal(atoms.arrays["radius"], traj.radii)
            np.testing.assert_array_equal(atoms.numbers, 0)  # one type: species 0, ASE's "X"


def test_znh5md_reads_a_run_in_open_space(tmp_path):
    # No box: edges are placeholders (0) and pbc is False, which znh5md needs (it fails
    # without box/edges and reads fixed-length "none" as periodic).
    znh5md = pytest.importorskip("znh5md")
    traj = open_run()
    frames = znh5md.IO(save_h5md(traj, tmp_path / "run.h5"))[:]
    assert len(frames) == len(traj.t) == 5
    np.testing.assert_array_equal(np.array([a.positions for a in frames]), traj.positions)
    for atoms in frames:
        assert not atoms.pbc.any() and not atoms.cell.array.any()


def test_pyh5md_reads_kinema_files(saved):
    pyh5md = pytest.importorskip("pyh5md")
    traj, path = saved
    with pyh5md.File(path, "r") as f:
        assert f["h5md/creator"].attrs["name"] == b"kinema"  # fixed-length strings read back as bytes
        g = f.particles_group("all")
        position, velocity = pyh5md.element(g, "position"), pyh5md.element(g, "velocity")
        edges = pyh5md.element(g["box"], "edges")
        for e in (position, velocity, edges):
            assert e.element_type == "TimeElement"
            np.testing.assert_array_equal(e.time[()], traj.t)
            np.testing.assert_array_equal(e.step[()], np.arange(6) * 2)
        np.testing.assert_array_equal(position.value[()], traj.positions)
        np.testing.assert_array_equal(velocity.value[()], traj.velocities)
        np.testing.assert_array_equal(edges.value[()], [[1.0, 2.0, 0.0]] * 6)
        assert np.char.decode(g["box"].attrs["boundary"]).tolist() == ["periodic", "periodic", "none"]
        assert g["box"].attrs["dimension"] == 3
        for name, expected in (("mass", traj.masses), ("radius", traj.radii), ("id", np.arange(4)), ("species", np.zeros(4))):
            np.testing.assert_array_equal(pyh5md.element(g, name).value[()], [expected] * 6, err_msg=name)
        kinetic = pyh5md.element(f["observables"], "kinetic_energy")
        np.testing.assert_array_equal(kinetic.value[()], traj.kinetic)
        assert position.value.attrs["unit"] == "m" and velocity.value.attrs["unit"] == "m s-1" and position.time.attrs["unit"] == "s"


def _mdanalysis_reader():
    mda = pytest.importorskip("MDAnalysis")
    from MDAnalysis.coordinates.H5MD import H5MDReader

    return mda, H5MDReader


# MDAnalysis reads float32: the file's value rounded to float32, then its conversion to Å (×10
# in float32) rounded again, each within half a float32 ulp (2**-24 relative)
F32 = 2 * 2.0**-24 + 1e-15


def _compare_mdanalysis(reader, traj):
    """The frames of an H5MDReader of ``traj`` saved with units="MD" (nm, ps, nm ps-1), in
    MDAnalysis's units (Å, ps, Å/ps), float32."""
    assert reader.units == {"time": "ps", "length": "nm", "velocity": "nm/ps", "force": None}
    assert reader.n_frames == len(traj.t)
    for i, ts in enumerate(reader):
        assert ts.positions.dtype == ts.velocities.dtype == np.float32
        np.testing.assert_allclose(ts.positions, traj.positions[i] * 1e10, rtol=F32, atol=0)
        np.testing.assert_allclose(ts.velocities, traj.velocities[i] / 100, rtol=F32, atol=0)  # m/s = 1e10 Å / 1e12 ps
        np.testing.assert_allclose(ts.dimensions, [1e10, 2e10, 0.0, 90, 90, 90], rtol=F32, atol=0)
        assert ts.time == traj.t[i] * 1e12  # float64, as written
        assert ts.data["step"] == 2 * i and ts.data["kinetic_energy"] == from_si(traj.kinetic, "kJ mol-1")[i]


@pytest.mark.filterwarnings("ignore:there is no reference attributes")  # MDAnalysis guessing types for atoms it has none of
def test_mdanalysis_refuses_si_files_and_reads_md_units(tmp_path):
    # MDAnalysis's H5MD reader knows no length unit "m" (2.11: its table has Angstrom, A, nm,
    # pm and fm), with convert_units=False too; save(units="MD") writes nm, ps and nm ps-1,
    # which it reads and converts to Å and ps.
    mda, H5MDReader = _mdanalysis_reader()
    traj = box_run()
    si = save_h5md(traj, tmp_path / "si.h5")
    for convert in (True, False):
        with pytest.raises(RuntimeError, match=r"^length unit 'm' is not recognized by H5MDReader"):
            H5MDReader(str(si), convert_units=convert)
    path = traj.save(tmp_path / "md.h5", units="MD")
    with H5MDReader(str(path)) as reader:
        _compare_mdanalysis(reader, traj)
    # through a Universe: an H5MD file has no topology, so the atoms come from elsewhere
    empty = mda.Universe.empty(4, trajectory=False)
    empty.load_new(str(path), format="H5MD")
    minimal = mda.Universe(str(path), format="H5MD", topology_format="MINIMAL", n_atoms=4)
    for u in (empty, minimal):
        assert len(u.trajectory) == 6 and u.atoms.n_atoms == 4
        np.testing.assert_allclose(u.trajectory[5].positions, traj.positions[5] * 1e10, rtol=F32, atol=0)


# -- files of other programs read by kinema -------------------------------------------------------


def ase_frames():
    """Three frames of 3 atoms as ASE holds them: positions in Å in a periodic box that grows
    along z, no velocities."""
    import ase

    frames = []
    for k in range(3):
        atoms = ase.Atoms("H2O", positions=[[0.5, 1.0, 1.5], [2.0, 2.5, 3.0], [3.5, 4.0, 4.5 + k]], cell=[10.0, 11.0, 12.0 + k], pbc=True)
        frames.append(atoms)
    return frames


def test_kinema_reads_znh5md_files_in_angstrom(tmp_path):
    znh5md = pytest.importorskip("znh5md")
    frames = ase_frames()
    path = tmp_path / "ase.h5"
    znh5md.write(path, frames)
    with h5py.File(path) as f:
        assert f["particles/atoms/position/value"].attrs["unit"] == "Angstrom"
        assert "velocity" not in f["particles/atoms"] and "observables" not in f
    back = load_h5md(path)
    x = np.array([a.positions for a in frames])
    np.testing.assert_array_equal(back.positions, x / 1e10)  # Å to m: / 1e10, the float64 nearest the exact value
    assert back.velocities is None and back.kinetic is None and back.potential == {}
    # znh5md stores time as H5MD's fixed interval: 1 fs a frame (its default) from 0
    np.testing.assert_array_equal(back.t, np.arange(3) * 1.0 / 1e15)
    np.testing.assert_array_equal(back.step, [0, 1, 2])
    # the box, a (3, 3) matrix a frame, changes: kept per frame, the first frame's in box_edges
    assert back.periodic == (True, True, True)
    np.testing.assert_array_equal(back.box_edges_by_frame, np.array([[10.0, 11.0, 12.0 + k] for k in range(3)]) / 1e10)
    np.testing.assert_array_equal(back.box_edges, np.array([10.0, 11.0, 12.0]) / 1e10)
    assert back.creator.startswith("znh5md ")
    traj = kinema.Trajectory.load(path)
    np.testing.assert_array_equal(traj.positions, x / 1e10)
    assert np.isnan(traj.velocities).all() and traj.velocities.shape == (3, 3, 3)
    assert np.isnan(traj.kinetic).all() and np.isnan(traj.momentum).all() and traj.potential == {}
    np.testing.assert_array_equal(traj.box_edges, back.box_edges)
    assert traj.periodic == (True, True, True)


def test_znh5md_velocities_are_refused_for_their_unit(tmp_path):
    # znh5md 0.4.8 labels ASE's velocities (Å per ASE time unit, 10.18 fs) "Angstrom/fs":
    # 1 Å/fs is stored as 10.18. kinema refuses the label ("/" is not H5MD's notation) rather
    # than read velocities 10 times too large.
    znh5md = pytest.importorskip("znh5md")
    import ase.units

    frames = ase_frames()
    for atoms in frames:
        atoms.set_velocities(np.ones((3, 3)) * ase.units.Ang / ase.units.fs)  # 1 Å/fs
    path = tmp_path / "ase.h5"
    znh5md.write(path, frames)
    with h5py.File(path) as f:
        v = f["particles/atoms/velocity/value"]
        assert v.attrs["unit"] == "Angstrom/fs"
        np.testing.assert_allclose(v[0], 1 / ase.units.fs)  # 10.18...: not Å/fs
    with pytest.raises(TrajectoryFileError) as e:
        load_h5md(path)
    assert str(e.value).startswith(
        f"{path}: dataset 'velocities' (/particles/atoms/velocity/value) has unit 'Angstrom/fs', which kinema cannot read: 'Angstrom/fs': H5MD writes a unit as"
    ), str(e.value)


def test_kinema_reads_mdanalysis_files(tmp_path):
    # MDAnalysis's H5MDWriter: Å, ps and Å ps-1 in float32, a box of (3, 3) edge vectors a
    # frame in /particles/trajectory.
    mda, _ = _mdanalysis_reader()
    u = mda.Universe.empty(3, trajectory=True, velocities=True)
    path = tmp_path / "md.h5md"
    x = np.arange(27, dtype=np.float32).reshape(3, 3, 3) / 4
    v = np.linspace(-2, 2, 27, dtype=np.float32).reshape(3, 3, 3)
    with mda.Writer(str(path), n_atoms=3, velocities=True, convert_units=False, lengthunit="Angstrom", timeunit="ps", velocityunit="Angstrom/ps") as w:
        for k in range(3):
            u.atoms.positions, u.atoms.velocities = x[k], v[k]
            u.dimensions = [20.0, 21.0, 22.0 + k, 90, 90, 90]
            u.trajectory.ts.time = 0.5 * k
            w.write(u)
    with h5py.File(path) as f:
        assert f["particles/trajectory/velocity/value"].attrs["unit"] == "Angstrom ps-1"
        assert f["particles/trajectory/box/edges/value"].shape == (3, 3, 3)
    back = load_h5md(path)
    np.testing.assert_array_equal(back.positions, x.astype(np.float64) / 1e10)
    np.testing.assert_array_equal(back.velocities, v.astype(np.float64) * 100.0)  # Å/ps = 100 m/s exactly
    np.testing.assert_array_equal(back.t, np.float32([0.0, 0.5, 1.0]).astype(np.float64) / 1e12)
    np.testing.assert_array_equal(back.box_edges_by_frame, np.array([[20.0, 21.0, 22.0 + k] for k in range(3)]) / 1e10)
    assert back.periodic == (True, True, True) and back.kinetic is None
    assert kinema.Trajectory.load(path).velocities.dtype == np.float64


def test_kinema_reads_pyh5md_files(tmp_path):
    # A program writing with pyh5md: positions in nm with an explicit time in ps, the box
    # sharing position's step and time, time-independent species and masses in u, and an
    # observable at a fixed interval (scalar step and time with offsets) in kJ mol-1.
    pyh5md = pytest.importorskip("pyh5md")
    path = tmp_path / "prog.h5"
    rng = np.random.default_rng(2)
    x, v = rng.uniform(0, 3, size=(4, 5, 3)), rng.normal(size=(4, 5, 3))
    energy = rng.normal(size=4) * 100
    with pyh5md.File(str(path), "w", author="Someone", creator="a program", creator_version="1.0") as f:
        g = f.particles_group("fluid")
        position = pyh5md.element(g, "position", store="time", data=np.zeros((5, 3)), time=True)
        velocity = pyh5md.element(g, "velocity", store="time", data=np.zeros((5, 3)), step_from=position)
        g.create_box(dimension=3, boundary=["periodic", "periodic", "none"], store="time", data=np.zeros(3), step_from=position)
        pyh5md.element(g, "species", store="fixed", data=np.array([1, 1, 2, 2, 2], dtype=np.int32))
        pyh5md.element(g, "mass", store="fixed", data=np.array([18.0, 18.0, 40.0, 40.0, 40.0]))
        pe = pyh5md.element(f.require_group("observables"), "potential_energy", store="linear", data=0.0, step=10, step_offset=100, time=0.02, time_offset=1.0)
        for k in range(4):
            position.append(x[k], 100 + 10 * k, 1.0 + 0.02 * k)
            velocity.append(v[k], 100 + 10 * k)
            g.box.edges.append([3.0, 3.0 + 0.1 * k, 0.0], 100 + 10 * k)
            pe.append(energy[k])
        position.value.attrs["unit"] = "nm"
        position.time.attrs["unit"] = "ps"
        velocity.value.attrs["unit"] = "nm ps-1"
        g.box.edges.value.attrs["unit"] = "nm"
        g["mass"].attrs["unit"] = "u"
        pe.value.attrs["unit"] = "kJ mol-1"
    back = load_h5md(path)
    np.testing.assert_array_equal(back.positions, x / 1e9)
    np.testing.assert_array_equal(back.velocities, v * 1000.0)  # nm/ps = 1000 m/s exactly
    np.testing.assert_array_equal(back.t, (1.0 + 0.02 * np.arange(4)) / 1e12)
    np.testing.assert_array_equal(back.step, 100 + 10 * np.arange(4))
    np.testing.assert_array_equal(back.masses, np.array([18.0, 18.0, 40.0, 40.0, 40.0]) * 1.66053906660e-27)  # u
    np.testing.assert_allclose(back.potential["potential"], energy * 1e3 / 6.02214076e23, rtol=1e-15)  # per particle
    np.testing.assert_array_equal(back.box_edges_by_frame, np.array([[3.0, 3.0 + 0.1 * k, 0.0] for k in range(4)]) / 1e9)
    assert back.periodic == (True, True, False) and back.group == "fluid"
    assert (back.author, back.creator) == ("Someone", "a program 1.0")
    traj = kinema.Trajectory.load(path)
    assert np.isnan(traj.kinetic).all() and np.isnan(traj.total).all()
    np.testing.assert_array_equal(traj.box_edges, np.array([3.0, 3.0, 0.0]) / 1e9)


def h5md_file(path, unit="Ang", boundary=("none", "none", "none"), edges=None, time_unit="ps"):
    """A minimal H5MD file written with h5py as a program would: 2 frames of 2 particles
    (positions 1..12 in ``unit``), time 0 and 1 in ``time_unit``, a fixed box (``edges`` in
    ``unit``) when given, nothing else."""
    with h5py.File(path, "w") as f:
        h5md = f.create_group("h5md")
        h5md.attrs["version"] = [1, 1]
        h5md.create_group("author").attrs["name"] = np.bytes_("me")
        h5md.create_group("creator").attrs.update({"name": np.bytes_("prog"), "version": np.bytes_("0")})
        p = f.create_group("particles/all")
        box = p.create_group("box")
        box.attrs["dimension"] = 3
        box.attrs["boundary"] = np.array([b.encode() for b in boundary], dtype="S8")
        if edges is not None:
            box["edges"] = edges
            box["edges"].attrs["unit"] = unit
        position = p.create_group("position")
        position["value"] = np.arange(1.0, 13.0).reshape(2, 2, 3)
        position["value"].attrs["unit"] = unit
        position["step"] = [0, 1]
        position["time"] = [0.0, 1.0]
        position["time"].attrs["unit"] = time_unit
    return path


def test_a_minimal_file_of_another_program_loads(tmp_path):
    path = h5md_file(tmp_path / "min.h5", boundary=("periodic", "periodic", "periodic"), edges=np.diag([5.0, 6.0, 7.0]))
    back = load_h5md(path)
    np.testing.assert_array_equal(back.positions, np.arange(1.0, 13.0).reshape(2, 2, 3) / 1e10)
    np.testing.assert_array_equal(back.t, np.array([0.0, 1.0]) / 1e12)
    np.testing.assert_array_equal(back.box_edges, np.array([5.0, 6.0, 7.0]) / 1e10)  # a fixed (3, 3) box
    np.testing.assert_array_equal(back.box_edges_by_frame, np.array([[5.0, 6.0, 7.0]] * 2) / 1e10)
    assert back.velocities is None and back.masses is None and (back.author, back.creator) == ("me", "prog 0")
    assert np.isnan(kinema.load_trajectory(path).velocities).all()


@pytest.mark.parametrize(
    "unit, message",
    [
        ("furlong", "has unit 'furlong', which kinema cannot read: 'furlong' is not a unit symbol kinema knows"),
        ("ps", "has unit 'ps', which is not a length (m)"),
        ("m/s", "has unit 'm/s', which kinema cannot read: 'm/s': H5MD writes a unit as space-separated factors with powers ('nm ps-1'), not with '/'"),
        ("", "has unit '', which kinema cannot read: it is empty"),
        (b"nm \xff", "has unit 'nm \\udcff'"),
        (3, "has a unit attribute that is not a string: 3"),
    ],
)
def test_a_unit_kinema_cannot_convert_names_the_file_the_dataset_and_the_unit(tmp_path, unit, message):
    path = h5md_file(tmp_path / "units.h5")
    with h5py.File(path, "r+") as f:
        f["particles/all/position/value"].attrs["unit"] = unit
    for load in (load_h5md, kinema.Trajectory.load):
        with pytest.raises(TrajectoryFileError) as e:
            load(path)
        text = str(e.value)
        assert isinstance(e.value, ValueError) and "\n" not in text
        assert text.startswith(f"{path}: dataset 'positions' (/particles/all/position/value) ") and message in text, text


def test_units_of_times_masses_and_boxes_are_checked_too(tmp_path):
    path = h5md_file(tmp_path / "t.h5", time_unit="nm")
    with pytest.raises(TrajectoryFileError, match=r"t\.h5: dataset 'times' \(/particles/all/position/time\) has unit 'nm', which is not a time \(s\)$"):
        load_h5md(path)
    path = h5md_file(tmp_path / "b.h5", boundary=("periodic", "none", "none"), edges=[1.0, 0.0, 0.0])
    with h5py.File(path, "r+") as f:
        f["particles/all/box/edges"].attrs["unit"] = "kg"
        f["particles/all/mass"] = [1.0, 2.0]
        f["particles/all/mass"].attrs["unit"] = "g mol-1"
    with pytest.raises(TrajectoryFileError, match=r"dataset 'box edges' \(/particles/all/box/edges\) has unit 'kg', which is not a length \(m\)$"):
        load_h5md(path)
    with h5py.File(path, "r+") as f:
        f["particles/all/box/edges"].attrs["unit"] = "pm"
    back = load_h5md(path)
    np.testing.assert_array_equal(back.box_edges, [1e-12, 0.0, 0.0])
    np.testing.assert_allclose(back.masses, [1.66053906660e-27, 2 * 1.66053906660e-27], rtol=1e-9)  # g/mol: 1 u per particle


def test_a_triclinic_box_is_refused(tmp_path):
    path = h5md_file(tmp_path / "tri.h5", boundary=("periodic",) * 3, edges=[[5.0, 0.0, 0.0], [1.0, 6.0, 0.0], [0.0, 0.0, 7.0]])
    with pytest.raises(
        TrajectoryFileError,
        match=r"tri\.h5: dataset 'box edges' \(/particles/all/box/edges\) is a triclinic box \(edge vectors not along the axes\), which kinema does not support$",
    ):
        load_h5md(path)


def test_a_time_dependent_box_is_checked_at_each_frame(tmp_path):
    path = h5md_file(tmp_path / "box.h5", boundary=("periodic", "none", "none"))
    with h5py.File(path, "r+") as f:
        edges = f.create_group("particles/all/box/edges")
        edges["step"], edges["time"] = f["particles/all/position/step"], f["particles/all/position/time"]
        edges["value"] = [[4.0, 0.0, 0.0], [-4.0, 0.0, 0.0]]
        edges["value"].attrs["unit"] = "nm"
    with pytest.raises(
        TrajectoryFileError, match=r"\(/particles/all/box/edges/value\) has edge\[0\] = -4e-09 at frame 1 \(a periodic axis needs an edge > 0 m\)$"
    ):
        load_h5md(path)
    with h5py.File(path, "r+") as f:
        f["particles/all/box/edges/value"][1, 0] = 4.5
    np.testing.assert_array_equal(load_h5md(path).box_edges_by_frame, np.array([[4.0, 0.0, 0.0], [4.5, 0.0, 0.0]]) / 1e9)
    with h5py.File(path, "r+") as f:
        del f["particles/all/box/edges/value"]
        f["particles/all/box/edges/value"] = [[4.0, 0.0, 0.0]] * 3
    with pytest.raises(TrajectoryFileError, match=r"has shape \(3, 3\); it must be \(2, 3\), one edge per axis at each frame of dataset 'positions'"):
        load_h5md(path)


@pytest.mark.parametrize(
    "unit, factor, dimension",
    [
        ("m", 1, "L"),
        ("nm", Fraction(1, 10**9), "L"),
        ("Ang", Fraction(1, 10**10), "L"),
        ("\u00c5", Fraction(1, 10**10), "L"),
        ("angstrom", Fraction(1, 10**10), "L"),
        ("Angstrom", Fraction(1, 10**10), "L"),
        ("A", Fraction(1, 10**10), "L"),
        ("pm", Fraction(1, 10**12), "L"),
        ("cm", Fraction(1, 100), "L"),
        ("mm", Fraction(1, 1000), "L"),
        ("10+3 m", 1000, "L"),
        ("s", 1, "T"),
        ("ps", Fraction(1, 10**12), "T"),
        ("fs", Fraction(1, 10**15), "T"),
        ("ns", Fraction(1, 10**9), "T"),
        ("nm ps-1", 1000, "L T-1"),
        ("\u00c5 ps-1", 100, "L T-1"),
        ("Ang fs-1", 10**5, "L T-1"),
        ("m s-1", 1, "L T-1"),
        ("kg", 1, "M"),
        ("g", Fraction(1, 1000), "M"),
        ("u", Fraction("1.66053906660e-27"), "M"),
        ("amu", Fraction("1.66053906660e-27"), "M"),
        ("Da", Fraction("1.66053906660e-27"), "M"),
        ("kJ mol-1", Fraction(1000) / Fraction("6.02214076e23"), "L2 T-2 M"),
        ("eV", Fraction("1.602176634e-19"), "L2 T-2 M"),
        ("kg m2 s-1", 1, "L2 T-1 M"),
    ],
)
def test_unit_strings(unit, factor, dimension):
    powers = dict.fromkeys("LTM", 0)
    for part in dimension.split():
        powers[part[0]] = int(part[1:] or 1)
    assert parse_unit(unit) == (factor, (powers["L"], powers["T"], powers["M"]))
