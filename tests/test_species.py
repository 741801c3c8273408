"""Particle species: named in World.add_particles or a scene's [[particles]] group, recorded in
trajectories, saved in H5MD and loaded back, and written as the particle type that OVITO,
ASE and HOOMD's GSD readers read."""

import numpy as np
import pytest

import kinema
from kinema.scene import Scene, SceneError

SCENE = """
[world]
dt = 0.01
duration = 0.05
fps = 100

[[particles]]
type = "list"
positions = [[0, 0, 0], [1, 0, 0]]
radius = 0.1
species = "grain"

[[particles]]
type = "list"
positions = [[0, 1, 0], [1, 1, 0]]
radius = 0.3
species = ["Si", "boulder"]

[[particles]]
type = "list"
positions = [[0, 2, 0]]
"""
NAMES = ["grain", "grain", "Si", "boulder", "X"]


def test_a_scene_names_its_particles_and_to_scene_keeps_the_names():
    w = Scene.from_string(SCENE).build()
    assert w.species.tolist() == NAMES  # X: the group without a name
    again = w.to_scene().build()
    assert again.species.tolist() == NAMES


def test_a_world_without_species_has_none():
    w = kinema.World()
    w.add_particles([[0, 0, 0]])
    assert w.species is None and w.run(0.01, fps=100).species is None


@pytest.mark.parametrize(
    "species, error, text",
    [
        ("two words", ValueError, "species = 'two words' is invalid: a species name is one word"),
        (["a", "b c"], ValueError, r"species\[1\] = 'b c' is invalid"),
        (["a"], TypeError, r"give a name \(a string\) or one per particle, \(2,\)"),
        (3, TypeError, "species = 3 is invalid"),
        ([1, 2], TypeError, r"species\[0\] = 1 is invalid: it must be a string"),
    ],
)
def test_bad_species_are_refused_and_nothing_is_added(species, error, text):
    w = kinema.World()
    with pytest.raises(error, match=text):
        w.add_particles([[0, 0, 0], [1, 0, 0]], species=species)
    assert len(w) == 0 and w.species is None


def test_a_bad_species_in_a_scene_names_the_group():
    with pytest.raises(SceneError, match=r"particles\[0\].*species"):
        Scene.from_string(SCENE.replace('species = "grain"', 'species = "a b"'))


def test_species_round_trip_through_h5md(tmp_path):
    traj = Scene.from_string(SCENE).build().run(0.05, fps=100)
    assert traj.species.tolist() == NAMES
    traj.save(tmp_path / "run.h5")
    assert kinema.Trajectory.load(tmp_path / "run.h5").species.tolist() == NAMES


def test_the_readers_see_the_species_as_particle_types(tmp_path):
    traj = Scene.from_string(SCENE).build().run(0.05, fps=100)
    traj.export(tmp_path / "run.xyz")
    traj.export(tmp_path / "run.gsd")
    ase_io = pytest.importorskip("ase.io")
    atoms = ase_io.read(tmp_path / "run.xyz", index=0)
    assert atoms.arrays["type"].tolist() == NAMES
    assert atoms.get_chemical_symbols() == ["X", "X", "Si", "X", "X"]  # ASE takes only chemical symbols
    gsd_hoomd = pytest.importorskip("gsd.hoomd")
    with gsd_hoomd.open(tmp_path / "run.gsd") as f:
        p = f[0].particles
        assert [p.types[k] for k in p.typeid] == NAMES
    ovito_io = pytest.importorskip("ovito.io")
    for name in ("run.xyz", "run.gsd"):
        data = ovito_io.import_file(str(tmp_path / name)).compute(0)
        types = data.particles.particle_types
        assert [types.type_by_id(k).name for k in np.asarray(types[...])] == NAMES, name
