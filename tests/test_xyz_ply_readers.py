"""kinema's extended XYZ opened by OVITO and its PLY frames opened by plyfile, the readers
OVITO and Blender/Houdini users have: the same values, the right cell, particles inside it."""

import numpy as np
import pytest

import kinema

plyfile = pytest.importorskip("plyfile")


def _run(periodic):
    """50 balls in the box [0, 2] × [0, 1] × [0, 1] (off the origin: the cell's origin matters),
    periodic along ``periodic``, bouncing off the other walls."""
    w = kinema.World(dt=0.01)
    rng = np.random.default_rng(5)
    w.add_particles(rng.uniform([0.1, 0.1, 0.1], [1.9, 0.9, 0.9], size=(50, 3)) + [3.0, 0.0, 0.0], velocity=rng.normal(size=(50, 3)), radius=0.04)
    w.add(kinema.Box([3.0, 0.0, 0.0], [5.0, 1.0, 1.0]))
    w.periodic = periodic
    return w.run(0.5, fps=20)


@pytest.mark.parametrize("periodic", [(True, False, False), (True, True, True)])
def test_ovito_reads_the_xyz_cell_and_every_particle_lies_inside_it(tmp_path, periodic):
    # OVITO used to find the cell degenerate (a zero vector along an open axis) and lost its
    # origin: 10 of 50 particles lay outside the cell
    io = pytest.importorskip("ovito.io")
    traj = _run(periodic)
    traj.export(tmp_path / "run.xyz")
    pipeline = io.import_file(str(tmp_path / "run.xyz"))
    assert pipeline.source.num_frames == len(traj.t)
    for i in (0, len(traj.t) - 1):
        data = pipeline.compute(i)
        cell = np.asarray(data.cell[...])
        assert tuple(data.cell.pbc) == periodic
        assert np.linalg.det(cell[:, :3]) > 0  # not degenerate
        np.testing.assert_array_equal(cell[0, 3], 3.0)  # the box's lower corner along x
        # 17 digits, exact for float64 (ASE reads them back bit for bit); OVITO 3.17's number
        # parser lands up to 2 units in the last place off
        np.testing.assert_allclose(data.particles.positions[...], traj.positions[i], rtol=5e-16, atol=0)
        np.testing.assert_allclose(data.particles.velocities[...], traj.velocities[i], rtol=5e-16, atol=1e-300)
        reduced = np.linalg.solve(cell[:, :3], (traj.positions[i] - cell[:, 3]).T).T
        assert ((reduced >= 0) & (reduced <= 1)).all(), reduced.min(axis=0)


def test_plyfile_reads_each_frame(tmp_path):
    traj = _run((False, False, False))
    paths = traj.export(tmp_path / "run.ply")
    assert len(paths) == len(traj.t) and all(p.parent.name == "run_ply" for p in paths)
    for i, path in enumerate(paths):
        vertex = plyfile.PlyData.read(str(path))["vertex"]
        assert vertex.count == 50
        x = np.column_stack([vertex["x"], vertex["y"], vertex["z"]])
        v = np.column_stack([vertex["vx"], vertex["vy"], vertex["vz"]])
        np.testing.assert_array_equal(x, traj.positions[i].astype(np.float32))  # float32, as Blender reads
        np.testing.assert_array_equal(v, traj.velocities[i].astype(np.float32))
        np.testing.assert_array_equal(vertex["radius"], np.float32(0.04))
        np.testing.assert_array_equal(vertex["id"], np.arange(50))
