"""Issue 49, "files and commands that never lie": the LAMMPS, XYZ and GSD readers and the
exports of a trajectory without velocities. Each test is one of the issue's reproducers: a
LAMMPS dump in lj units read with the scales given (API, --units, a scene's units table);
kinema's own dump read back with its times and species; atom ids below 1 refused; an extxyz
with momenta but no masses; exports without velocities read back without them; numbers
beyond int64 and empty GSD type names refused in one line naming the file."""

import shutil
import subprocess
import warnings

import numpy as np
import pytest
from typer.testing import CliRunner

import kinema
from kinema.cli import app
from kinema.io import TrajectoryFileError, export
from kinema.scene import Scene

runner = CliRunner()
LJ = {"length": 3.4e-10, "time": 2.15e-12, "mass": 6.6e-26}

LJ_INPUT = """units lj
atom_style atomic
region box block 0 4 0 4 0 4
create_box 2 box
create_atoms 1 single 1 1 1
create_atoms 2 single 2.1 1 1
mass * 1.0
velocity all set 0.5 0 0
pair_style lj/cut 2.5
pair_coeff * * 1.0 1.0
fix 1 all nve
dump d all custom 5 lj.dump id type x y z vx vy vz
dump_modify d units yes time yes
run 10
"""


def load(path, **options):
    """``Trajectory.load`` with warnings turned into errors: a reader that warns fails here."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return kinema.Trajectory.load(path, **options)


@pytest.fixture(scope="module")
def lj_dump(tmp_path_factory):
    """A dump LAMMPS wrote in `units lj` (`ITEM: UNITS lj`, `ITEM: TIME`): 3 frames of two atoms."""
    if shutil.which("lmp") is None:
        pytest.skip("LAMMPS (lmp) is not installed")
    folder = tmp_path_factory.mktemp("lj")
    (folder / "in.lj").write_text(LJ_INPUT)
    subprocess.run(["lmp", "-in", "in.lj", "-log", "none", "-screen", "none"], cwd=folder, check=True, timeout=60)
    assert (folder / "lj.dump").read_text().startswith("ITEM: UNITS\nlj\n")
    return folder / "lj.dump"


# -- 1. LAMMPS's lj units, with the scales given ---------------------------------------------


def test_an_lj_dump_reads_with_its_scales_given(lj_dump):
    back = load(lj_dump, units=LJ)
    # LAMMPS wrote dt = 0.005 τ, a frame every 5 steps: times 0, 0.025 τ, 0.05 τ
    np.testing.assert_allclose(back.t, np.array([0.0, 0.025, 0.05]) * LJ["time"], rtol=1e-15)
    np.testing.assert_array_equal(back.positions[0, :, 0], np.array([1.0, 2.1]) * LJ["length"])
    np.testing.assert_allclose(back.velocities[0, :, 0], 0.5 * LJ["length"] / LJ["time"], rtol=1e-15)
    with pytest.raises(TrajectoryFileError, match=r"lj\.dump: the file says its units are 'lj' \(ITEM: UNITS\).*give units = \{length = m"):
        load(lj_dump)
    with pytest.raises(TrajectoryFileError, match=r"not units = 'real'"):
        load(lj_dump, units="real")


def test_an_lj_dump_reads_with_the_units_option(lj_dump, tmp_path):
    out = tmp_path / "lj.csv"
    result = runner.invoke(app, ["export", str(lj_dump), "--units", "length=3.4e-10,time=2.15e-12,mass=6.6e-26", "-f", "csv", "-o", str(out)])
    assert result.exit_code == 0, result.output
    np.testing.assert_allclose(load(out).t, np.array([0.0, 0.025, 0.05]) * LJ["time"], rtol=1e-15)
    # kinema view and render take the same option (the issue: every command refused it)
    page = tmp_path / "lj.html"
    result = runner.invoke(app, ["view", str(lj_dump), "--units", "length=3.4e-10,time=2.15e-12,mass=6.6e-26", "--html", str(page)])
    assert result.exit_code == 0 and page.stat().st_size > 0, result.output
    result = runner.invoke(app, ["view", str(lj_dump), "--html", str(page)])
    assert result.exit_code == 2 and "give units = {length = m" in result.output.replace("\n", " "), result.output


def test_an_lj_data_file_and_dump_in_a_scene_units_table(lj_dump, tmp_path):
    data = tmp_path / "lj.data"
    data.write_text(
        "LAMMPS data file via write_data, version 29 Aug 2024, timestep = 0, units = lj\n\n2 atoms\n1 atom types\n\n"
        "0 4 xlo xhi\n0 4 ylo yhi\n0 4 zlo zhi\n\nMasses\n\n1 1.0\n\nAtoms # atomic\n\n1 1 1.0 1.0 1.0\n2 1 2.1 1.0 1.0\n"
    )
    for path in (data, lj_dump):
        scene = tmp_path / "scene.toml"
        scene.write_text(
            f'[world]\ndim = 3\ndt = 1e-15\nduration = 1e-14\nfps = 1e15\n\n[[particles]]\ntype = "file"\npath = "{path}"\nradius = 1e-10\nframe = 0\n'
            f"units = {{length = {LJ['length']}, time = {LJ['time']}, mass = {LJ['mass']}}}\n"
        )
        w = Scene.from_toml(scene).build()
        np.testing.assert_array_equal(w.positions[:, 0], np.array([1.0, 2.1]) * LJ["length"])
        if path == data:  # (the dump has no mass column)
            np.testing.assert_allclose(w.masses, [LJ["mass"]] * 2, rtol=1e-15)


# -- 2. kinema's own dump reads back with its times and its species ---------------------------


def named_run(names=("grain", "sand")):
    """Two particles named `names` falling for 0.99 s, a frame every 33 ms (31 frames)."""
    w = kinema.World(dt=0.001)
    w.add_particles([[0.0, 0.0, 1.0], [1.0, 0.0, 1.0]], velocity=[[0.1, 0.0, 0.0], [0.0, 0.2, 0.0]], mass=[1.0, 2.0], radius=0.05, species=list(names))
    w.add(kinema.Gravity())
    return w.run(0.99, fps=1 / 0.033)


@pytest.mark.parametrize("names", [("grain", "sand"), ("Fe", "He")])
def test_own_dump_reads_back_its_times_and_species(tmp_path, names):
    traj = named_run(names)
    path = tmp_path / "run.lammpstrj"
    export(traj, path)
    back = load(path)  # ITEM: UNITS si: no units= needed
    np.testing.assert_array_equal(back.t, traj.t)  # not the frame index 0..30
    assert back.species.tolist() == list(names)
    np.testing.assert_array_equal(back.positions, traj.positions)
    np.testing.assert_array_equal(back.velocities, traj.velocities)
    np.testing.assert_array_equal(back.source.step, np.rint(traj.t / traj.dt).astype(np.int64))


@pytest.mark.parametrize("names", [("grain", "sand"), ("Fe", "He")])
def test_own_dump_times_and_types_in_ovito_and_ase(tmp_path, names):
    ovito_io = pytest.importorskip("ovito.io")
    ase_io = pytest.importorskip("ase.io")
    traj = named_run(names)
    path = tmp_path / "run.lammpstrj"
    export(traj, path)
    pipeline = ovito_io.import_file(str(path))
    assert pipeline.source.num_frames == len(traj.t)
    for k in (0, 7, len(traj.t) - 1):
        data = pipeline.compute(k)
        assert data.attributes["Time"] == traj.t[k] and data.attributes["Timestep"] == round(traj.t[k] / traj.dt)
    types = data.particles.particle_types
    if names == ("Fe", "He"):  # named by the element column
        assert [types.type_by_id(int(t)).name for t in types[...]] == list(names)
    else:  # numbered: OVITO skips the labels item
        assert list(types[...]) == [1, 2]
    frames = ase_io.read(path, ":", format="lammps-dump-text", units="si")
    assert len(frames) == len(traj.t)
    np.testing.assert_allclose(frames[-1].get_positions() * 1e-10, traj.positions[-1], rtol=1e-14)


# -- 3. atom ids below 1 -----------------------------------------------------------------------

DUMP = """ITEM: TIMESTEP
{step}
ITEM: NUMBER OF ATOMS
2
ITEM: BOX BOUNDS ff ff ff
0 1
0 1
0 1
ITEM: ATOMS id type x y z
{id} 1 0.1 0.1 0.1
2 1 0.2 0.2 0.2
"""
DATA = """LAMMPS data file, units = si

2 atoms
1 atom types

0 1 xlo xhi
0 1 ylo yhi
0 1 zlo zhi

Masses

1 1.0

Atoms # atomic

{id} 1 0.1 0.1 0.1
2 1 0.2 0.2 0.2
"""


@pytest.mark.parametrize("atom_id", ["0", "-3"])
def test_atom_ids_below_one_are_refused(tmp_path, atom_id):
    dump, data = tmp_path / "zero.dump", tmp_path / "zero.data"
    dump.write_text(DUMP.format(step=0, id=atom_id))
    data.write_text(DATA.format(id=atom_id))
    with pytest.raises(
        TrajectoryFileError, match=rf"zero\.dump: frame 0 \(line 9\), line 10: atom id {atom_id} is invalid: LAMMPS's atom ids are integers >= 1"
    ):
        load(dump, units="si")
    with pytest.raises(TrajectoryFileError, match=rf"zero\.data: Atoms section \(atomic\), line 16: atom id {atom_id} is invalid"):
        load(data)


# -- 6. numbers beyond int64, empty GSD type names ---------------------------------------------


@pytest.mark.parametrize(
    "step, atom_id, message",
    [
        ("0", "99999999999999999999", r"huge\.dump: frame 0 \(line 9\), line 10: column 'id' has 99999999999999999999, beyond int64"),
        ("99999999999999999999", "1", r"huge\.dump: line 2: ITEM: TIMESTEP holds 99999999999999999999, beyond int64"),
    ],
)
def test_lammps_numbers_beyond_int64_are_refused_in_one_line(tmp_path, step, atom_id, message):
    path = tmp_path / "huge.dump"
    path.write_text(DUMP.format(step=step, id=atom_id))
    with pytest.raises(TrajectoryFileError, match=message):
        load(path, units="si")


def test_an_xyz_id_beyond_int64_is_refused_in_one_line(tmp_path):
    path = tmp_path / "huge.xyz"
    path.write_text("2\nProperties=species:S:1:pos:R:3:id:I:1 units=SI\nA 0 0 0 99999999999999999999\nA 1 0 0 2\n")
    with pytest.raises(TrajectoryFileError, match=r"huge\.xyz: frame 0 \(line 1\), row 0: column 'id' \(integer\) has 99999999999999999999, beyond int64"):
        load(path)


def test_a_gsd_empty_type_name_is_refused_in_one_line(tmp_path):
    hoomd = pytest.importorskip("gsd.hoomd")
    path = tmp_path / "empty.gsd"
    with hoomd.open(path, "w") as f:
        frame = hoomd.Frame()
        frame.particles.N = 2
        frame.particles.types = [""]
        frame.particles.typeid = [0, 0]
        frame.particles.position = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], dtype=np.float32)
        frame.configuration.box = [10, 10, 10, 0, 0, 0]
        f.append(frame)
    with pytest.raises(TrajectoryFileError, match=r"empty\.gsd: frame 0: particles/types holds only empty names .*GSD type names must be non-empty"):
        kinema.Trajectory.load(path, units="si")


# -- 4. extended XYZ momenta without masses ----------------------------------------------------


def test_xyz_momenta_without_masses_give_no_velocities_and_say_so_once(tmp_path):
    path = tmp_path / "momenta.xyz"
    frame = "2\nProperties=species:S:1:pos:R:3:momenta:R:3 units=SI\ngrain 0 0 0 1 0 0\ngrain 1 0 0 2 0 0\n"
    path.write_text(frame * 3)
    with pytest.warns(UserWarning, match=r"momenta\.xyz: frame 0 \(line 1\) has momenta but no masses .*so no velocities are read") as caught:
        back = kinema.Trajectory.load(path)
    assert len([w for w in caught if "momenta" in str(w.message)]) == 1  # once a file
    assert np.isnan(back.velocities).all()  # unknown, as for a file without velocities
    np.testing.assert_array_equal(back.positions[0, 1], [1.0, 0.0, 0.0])
    # with masses they are momenta / masses
    path.write_text(frame.replace("momenta:R:3", "momenta:R:3:masses:R:1").replace(" 0 0\n", " 0 0 2.0\n") * 3)
    np.testing.assert_array_equal(load(path).velocities[0, :, 0], [0.5, 1.0])


# -- 5. exports of a trajectory without velocities ---------------------------------------------


@pytest.mark.parametrize("suffix", [".xyz", ".csv", ".gsd", ".lammpstrj", ".pvd", ".ply"])
def test_exports_without_velocities_read_back_without_them(tmp_path, suffix):
    source = tmp_path / "novel.xyz"
    frame = "2\nProperties=species:S:1:pos:R:3:mass:R:1:radius:R:1 units=SI Time={t}\ngrain 0 0 {t} 1.0 0.1\ngrain 1 0 0 2.0 0.1\n"
    source.write_text(frame.format(t=0.0) + frame.format(t=0.5))
    traj = load(source)
    assert np.isnan(traj.velocities).all()  # unknown
    path = tmp_path / f"run{suffix}"
    export(traj, path)
    back = load(path)
    assert np.isnan(back.velocities).all()  # still unknown: no NaN columns written and refused on reading
    np.testing.assert_allclose(back.positions, traj.positions, rtol=0, atol=1e-7)  # (GSD, PLY: float32)
    assert (back.masses is not None) == (suffix not in (".ply",))


def test_kinema_render_of_its_own_dump_plays_in_real_time(tmp_path):
    # the reproducer: a 0.99 s run exported as a LAMMPS dump came back with the frame
    # index as its times (0 … 30 s), and `kinema render` made a 31 s video at 1 fps. Now the
    # dump's ITEM: TIME reads back, and the video is 31 frames at the recording's 30 fps.
    import imageio_ffmpeg

    path = tmp_path / "run.lammpstrj"
    export(named_run(), path)
    video = tmp_path / "run.mp4"
    res = runner.invoke(app, ["render", str(path), "-o", str(video), "--width", "160", "--height", "120"])
    assert res.exit_code == 0, res.output
    meta = imageio_ffmpeg.read_frames(str(video))
    info = next(meta)
    frames = sum(1 for _ in meta)
    assert (info["fps"], frames) == (30.0, 31), (info, frames)
