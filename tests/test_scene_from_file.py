"""A scene takes its particles from a file (``[[particles]] type = "file"``) and a world from
``World.add_particles_from``: the particles of one frame of a trajectory file kinema reads,
with the file's velocities, masses, radii and species where it has them, the block's own keys
where not; the scene runs, round-trips through ``Scene.to_toml`` and refuses bad keys in one
line naming the key, the value and what is allowed."""

import re

import numpy as np
import pytest

import kinema
from kinema.io import TrajectoryFileError, export
from kinema.io.units import LAMMPS_STYLES
from kinema.scene import Scene, SceneError

DATA = """LAMMPS data file via write_data, version 29 Aug 2024, timestep = 0, units = si

3 atoms
2 atom types

0 1 xlo xhi
0 1 ylo yhi
0 1 zlo zhi

Masses

1 2.0 # Cu
2 3.0 # Ag

Atoms # atomic

1 1 0.25 0.25 0.5
2 2 0.75 0.25 0.5
3 1 0.5 0.75 0.5
"""


@pytest.fixture(scope="module")
def start(tmp_path_factory):
    """A kinema run exported as extended XYZ: two particles in 2D falling, with masses, radii and
    species, 4 frames; and the trajectory."""
    folder = tmp_path_factory.mktemp("start")
    w = kinema.World(dim=2, dt=0.01)
    w.add_particles(
        [[0.0, 1.0, 0.0], [0.5, 2.0, 0.0]], velocity=[[0.1, 0.0, 0.0], [0.0, -0.2, 0.0]], mass=[1.0, 2.5], radius=[0.05, 0.1], species=["grain", "Fe"]
    )
    w.add(kinema.Gravity())
    traj = w.run(0.03, fps=100)
    export(traj, folder / "start.xyz")
    (folder / "copper.data").write_text(DATA)
    return folder, traj


def scene_text(block: str, dim: int = 2) -> str:
    return f'[world]\ndim = {dim}\ndt = 0.01\nduration = 0.05\nfps = 100\n\n[[forces]]\ntype = "gravity"\n\n[[particles]]\ntype = "file"\n{block}\n'


def test_add_particles_from_takes_the_last_frame_with_its_values(start):
    folder, traj = start
    w = kinema.World(dim=2)
    idx = w.add_particles_from(folder / "start.xyz")
    np.testing.assert_array_equal(idx, [0, 1])
    np.testing.assert_array_equal(w.positions, traj.positions[-1])
    np.testing.assert_array_equal(w.velocities, traj.velocities[-1])
    np.testing.assert_array_equal(w.masses, traj.masses)
    assert w.species.tolist() == ["grain", "Fe"]
    more = w.add_particles_from(folder / "start.xyz", frame=0, translate=[10.0, 0.0, 0.0])
    np.testing.assert_array_equal(more, [2, 3])
    np.testing.assert_array_equal(w.positions[2:], traj.positions[0] + [10.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"frame = 4 is invalid: .*start\.xyz has 4 frames \(0 to 3, or -4 to -1 from the end\)"):
        w.add_particles_from(folder / "start.xyz", frame=4)


def test_add_particles_from_a_file_without_masses_takes_the_given_ones(start):
    folder, _ = start
    w = kinema.World()
    w.add_particles_from(folder / "copper.data")  # units = si in its title
    np.testing.assert_array_equal(w.masses, [2.0, 3.0, 2.0])  # the Masses section's
    np.testing.assert_array_equal(w.positions[1], [0.75, 0.25, 0.5])
    assert w.species.tolist() == ["Cu", "Ag", "Cu"]
    (folder / "bare.data").write_text(DATA.replace("units = si", "units = real").replace("Masses\n\n1 2.0 # Cu\n2 3.0 # Ag\n\n", ""))
    w = kinema.World()
    w.add_particles_from(folder / "bare.data", mass=5.0, radius=0.1, velocity=[1.0, 0.0, 0.0])
    np.testing.assert_array_equal(w.masses, [5.0, 5.0, 5.0])
    np.testing.assert_array_equal(w.velocities, [[1.0, 0.0, 0.0]] * 3)
    np.testing.assert_array_equal(w.positions[1], np.array([0.75, 0.25, 0.5]) * LAMMPS_STYLES["real"].length)


def test_a_scene_with_a_file_block_runs_and_round_trips(start, tmp_path):
    folder, traj = start
    (folder / "scene.toml").write_text(scene_text('path = "start.xyz"\nframe = 1\ntranslate = [0.0, 5.0]'))
    scene = Scene.from_toml(folder / "scene.toml")
    assert scene.particle_count() == 2
    w = scene.build()
    np.testing.assert_array_equal(w.positions, traj.positions[1] + [0.0, 5.0, 0.0])
    np.testing.assert_array_equal(w.velocities, traj.velocities[1])
    run = w.run(0.05, fps=100)
    assert run.positions.shape == (6, 2, 3) and np.all(np.isfinite(run.positions))
    assert run.species.tolist() == ["grain", "Fe"]
    # Written elsewhere and read back, it builds the same world: the path was made absolute.
    again = Scene.from_toml(scene.to_toml(tmp_path / "copy.toml"))
    assert again.particles[0].path == str(folder / "start.xyz")
    np.testing.assert_array_equal(again.build().positions, traj.positions[1] + [0.0, 5.0, 0.0])
    assert again.to_dict() == scene.to_dict()


def test_a_file_block_takes_its_own_keys_where_the_file_has_none(start):
    folder, _ = start
    block = 'path = "copper.data"\nradius = 0.01\nvelocity = {sigma = 0.5, seed = 3}\nmass = 9.0\nspecies = "ignored"'
    (folder / "copper.toml").write_text(scene_text(block, dim=3))
    w = Scene.from_toml(folder / "copper.toml").build()
    np.testing.assert_array_equal(w.masses, [2.0, 3.0, 2.0])  # the file's masses win
    assert w.species.tolist() == ["Cu", "Ag", "Cu"]  # and its names
    np.testing.assert_array_equal(w._core.radii, [0.01] * 3)  # the file has no radii: the block's
    assert np.all(w.velocities != 0)  # nor velocities: the block's Maxwell draw


def test_units_of_a_file_block(start):
    folder, _ = start
    (folder / "bare.data").write_text(DATA.replace(" units = si", ""))
    (folder / "units.toml").write_text(scene_text('path = "bare.data"\nunits = {length = 0.5, time = 1.0, mass = 2.0}', dim=3))
    w = Scene.from_toml(folder / "units.toml").build()
    np.testing.assert_array_equal(w.positions[1], [0.375, 0.125, 0.25])
    np.testing.assert_array_equal(w.masses, [4.0, 6.0, 4.0])
    (folder / "units.toml").write_text(scene_text('path = "bare.data"', dim=3))
    with pytest.raises(SceneError, match=r"units\.toml: particles\[0\]: path = '.*bare\.data': .*does not say its units"):
        Scene.from_toml(folder / "units.toml").build(str(folder / "units.toml"))


@pytest.mark.parametrize(
    "block, message",
    [
        ('path = "start.xyz"\nunits = "lj"', r"particles\[0\]\.units: 'lj' is invalid: LAMMPS's lj units are reduced"),
        ('path = "start.xyz"\nunits = "furlongs"', r"particles\[0\]\.units: 'furlongs' is invalid: give one of 'real', 'metal'"),
        ('path = "start.xyz"\nframe = 1.5', r"particles\[0\]\.frame: 1\.5 is invalid: input should be a valid integer"),
        ('path = "start.xyz"\nformat = "pdb"', r"particles\[0\]\.format: 'pdb' is invalid: input should be 'h5md', 'xyz'"),
        ('path = "start.xyz"\natom_style = "hybrid"', r"particles\[0\]\.atom_style: 'hybrid' is invalid: input should be 'atomic'"),
        ('path = "start.xyz"\nunits = {length = 1.0, time = 1.0}', r"particles\[0\]\.units\.mass: missing: a value is required"),
        (
            'path = "start.xyz"\nunits = {length = -1.0, time = 1.0, mass = 1.0}',
            r"particles\[0\]\.units\.length: -1\.0 is invalid: input should be greater than 0",
        ),
        ('path = "start.xyz"\nunits = [1.0]', r"particles\[0\]\.units: \[1\.0\] is invalid: give a unit style's name or a table"),
        ('path = ""', r"particles\[0\]\.path: '' is invalid: string should have at least 1 character"),
        (
            'path = "start.xyz"\nscale = 2.0',
            r"particles\[0\]\.scale: unknown key allowed keys here: angular_velocity, atom_style, format, frame, friction, group, inertia, mass, path, pinned",
        ),
    ],
)
def test_bad_keys_of_a_file_block_are_one_line_each(start, block, message):
    folder, _ = start
    (folder / "bad.toml").write_text(scene_text(block))
    with pytest.raises(SceneError) as e:
        Scene.from_toml(folder / "bad.toml")
    lines = str(e.value).splitlines()
    assert len(lines) == 1, lines
    assert lines[0].startswith(f"{folder / 'bad.toml'}: ")
    assert re.search(message, lines[0]), lines[0]


@pytest.mark.parametrize(
    "block, message",
    [
        ('path = "missing.xyz"', r"particles\[0\]: path = '.*missing\.xyz': .*missing\.xyz: no such file$"),
        ('path = "start.xyz"\nframe = 7', r"particles\[0\]: path = '.*start\.xyz': frame = 7 is invalid: .*has 4 frames"),
    ],
)
def test_a_file_that_cannot_give_the_particles_is_a_scene_error_naming_the_block(start, block, message):
    folder, _ = start
    (folder / "bad.toml").write_text(scene_text(block))
    scene = Scene.from_toml(folder / "bad.toml")
    with pytest.raises(SceneError, match=message):
        scene.particle_count()
    with pytest.raises(SceneError, match=message):
        Scene.from_toml(folder / "bad.toml").build(str(folder / "bad.toml"))


def test_kinema_run_of_a_scene_with_a_file_block(start, tmp_path):
    from typer.testing import CliRunner

    from kinema.cli import app

    folder, _ = start
    (folder / "run.toml").write_text(scene_text('path = "start.xyz"') + "\n[output]\nvideo = false\nplot = false\n")
    res = CliRunner().invoke(app, ["run", str(folder / "run.toml"), "-o", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    back = kinema.Trajectory.load(tmp_path / "out" / "trajectory.h5")
    assert back.positions.shape[1] == 2 and back.species.tolist() == ["grain", "Fe"]


def test_a_2d_world_refuses_a_file_whose_z_is_not_0(tmp_path):
    path = tmp_path / "up.xyz"
    path.write_text("1\nProperties=species:S:1:pos:R:3 units=SI\nAr 0 0 1.5\n")
    w = kinema.World(dim=2)
    with pytest.raises(ValueError, match="2D"):
        w.add_particles_from(path)
    with pytest.raises(TrajectoryFileError):
        w.add_particles_from(tmp_path / "absent.xyz")


@pytest.mark.parametrize("name", ["run.h5", "run.xyz", "run.gsd", "run.lammpstrj", "run.csv"])
def test_a_files_collision_groups_are_taken_and_the_given_group_where_it_has_none(tmp_path, name):
    # kinema writes each particle's collision group in every format; add_particles_from and a
    # scene's file block took none of them (every particle came back in group 0, colliding
    # with what its group had been set to pass through).
    w = kinema.World(dt=0.01)
    w.add_particles([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]], radius=0.1, group=[0, 3, 7])
    traj = w.run(0.02, fps=100)
    path = tmp_path / name
    traj.save(path) if name.endswith(".h5") else traj.export(path)
    back = kinema.World()
    back.add_particles_from(path, group=5)  # (the file has them: 5 is not used)
    np.testing.assert_array_equal(back.groups, [0, 3, 7])
    (tmp_path / "s.toml").write_text(scene_text(f'path = "{name}"\ngroup = 5', dim=3))
    np.testing.assert_array_equal(Scene.from_toml(tmp_path / "s.toml").build().groups, [0, 3, 7])
    # a file without groups (a LAMMPS data file): the group given, for every particle
    (tmp_path / "copper.data").write_text(DATA)
    bare = kinema.World()
    bare.add_particles_from(tmp_path / "copper.data", group=5)
    np.testing.assert_array_equal(bare.groups, [5, 5, 5])
    (tmp_path / "c.toml").write_text(scene_text('path = "copper.data"\ngroup = [1, 2, 3]', dim=3))
    np.testing.assert_array_equal(Scene.from_toml(tmp_path / "c.toml").build().groups, [1, 2, 3])
