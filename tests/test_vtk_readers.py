"""The VTK export (``export(traj, "run.pvd")``: run.pvd, run_vtk/run_00000.vtp, ... and
run_colliders.vtp) read by outside readers: VTK's own XML reader (the vtk wheel, the library
ParaView reads these files with) and OVITO, both pinned in requirements/formats-test.txt."""

import xml.etree.ElementTree as ET
from types import SimpleNamespace

import numpy as np
import pytest

import kinema
from kinema.io import export

F, N = 5, 7


def synthetic(dim=3, colliders=None, seed=0):
    """A trajectory-like object with numbers no writer could round unnoticed: random
    positions and velocities, masses, radii and ids that are not 0..N-1."""
    rng = np.random.default_rng(seed)
    x, v = rng.normal(size=(F, N, 3)), rng.normal(size=(F, N, 3))
    if dim == 2:
        x[..., 2] = v[..., 2] = 0.0
    return SimpleNamespace(
        t=np.arange(F) * 0.013,
        positions=x,
        velocities=v,
        masses=rng.random(N) + 0.5,
        radii=rng.random(N) * 0.1 + 0.01,
        ids=rng.permutation(N) + 40,
        dim=dim,
        colliders=colliders,
    )


BOX = {"type": "box", "lo": [-3.0, -2.0, -4.0], "hi": [3.0, 2.5, 4.0]}
PLANE = {"type": "plane", "point": [0.0, 0.0, -1.5], "normal": [0.0, 0.6, 0.8]}
SPHERE = {"type": "sphere", "center": [0.25, -0.5, 1.0], "radius": 0.7}


def world_run():
    """A world in a box with a tilted floor and a sphere obstacle: 6 frames."""
    w = kinema.World(dt=0.01)
    rng = np.random.default_rng(4)
    w.add_particles(
        rng.uniform([0.1, 0.1, 0.5], [0.9, 0.9, 0.9], size=(6, 3)),
        velocity=rng.normal(size=(6, 3)),
        mass=[1.0, 1.5, 2.0, 2.5, 3.0, 3.5],
        radius=[0.02, 0.03, 0.04, 0.05, 0.06, 0.07],
    )
    w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
    w.add(kinema.Plane([0, 0, 0.1], [0.1, 0.2, 1.0]))
    w.add(kinema.SphereObstacle([0.5, 0.5, 0.3], 0.15))
    w.add(kinema.Gravity())
    return w.run(0.1, fps=50)


def read_vtp(path):
    """The file read by VTK's vtkXMLPolyDataReader (ParaView's reader of .vtp files)."""
    vtk_xml = pytest.importorskip("vtkmodules.vtkIOXML")
    reader = vtk_xml.vtkXMLPolyDataReader()
    reader.SetFileName(str(path))
    reader.Update()
    assert reader.GetErrorCode() == 0
    return reader.GetOutput()


def vtk_to_numpy(array):
    from vtkmodules.util.numpy_support import vtk_to_numpy

    return vtk_to_numpy(array)


def point_array(poly, name):
    a = poly.GetPointData().GetArray(name)
    assert a is not None, name
    return vtk_to_numpy(a)


def cells(cell_array):
    """The cells of a vtkCellArray as lists of point indices."""
    offsets, connectivity = vtk_to_numpy(cell_array.GetOffsetsArray()), vtk_to_numpy(cell_array.GetConnectivityArray())
    return [connectivity[a:b].tolist() for a, b in zip(offsets[:-1], offsets[1:], strict=True)]


def pvd_datasets(path):
    return ET.parse(path).getroot().findall("Collection/DataSet")


# -- VTK (ParaView's reader library) --------------------------------------------------------------


@pytest.mark.parametrize("dim", [3, 2])
def test_vtk_reads_every_frame_exactly(tmp_path, dim):
    tr = synthetic(dim)
    written = export(tr, tmp_path / "run.pvd")
    assert written == [tmp_path / "run.pvd", *(tmp_path / "run_vtk" / f"run_{i:05d}.vtp" for i in range(F))]  # no colliders: no colliders file
    # vtk's wheel has no vtkPVDReader (ParaView's own): the collection is read as ParaView does.
    datasets = pvd_datasets(tmp_path / "run.pvd")
    assert [float(d.get("timestep")) for d in datasets] == tr.t.tolist() and {d.get("part") for d in datasets} == {"0"}
    for i, d in enumerate(datasets):
        poly = read_vtp(tmp_path / d.get("file"))
        assert poly.GetNumberOfPoints() == poly.GetNumberOfVerts() == poly.GetNumberOfCells() == N
        assert cells(poly.GetVerts()) == [[k] for k in range(N)]
        points = vtk_to_numpy(poly.GetPoints().GetData())
        assert points.dtype == np.float64
        np.testing.assert_array_equal(points, tr.positions[i])
        np.testing.assert_array_equal(point_array(poly, "v"), tr.velocities[i])
        np.testing.assert_array_equal(point_array(poly, "speed"), np.linalg.norm(tr.velocities[i], axis=1))
        np.testing.assert_array_equal(point_array(poly, "radius"), tr.radii)
        np.testing.assert_array_equal(point_array(poly, "mass"), tr.masses)
        ids = point_array(poly, "id")
        assert ids.dtype == np.int64 and ids.tolist() == tr.ids.tolist()
        # ParaView colours by the active scalars and draws glyphs along the active vectors.
        assert poly.GetPointData().GetVectors().GetName() == "v" and poly.GetPointData().GetScalars().GetName() == "speed"
        assert vtk_to_numpy(poly.GetFieldData().GetArray("TimeValue")).tolist() == [tr.t[i]]


def test_vtk_reads_a_trajectory_without_masses_or_radii(tmp_path):
    tr = synthetic()
    del tr.masses, tr.radii
    export(tr, tmp_path / "run.pvd")
    poly = read_vtp(tmp_path / "run_vtk" / "run_00003.vtp")
    names = [poly.GetPointData().GetArrayName(k) for k in range(poly.GetPointData().GetNumberOfArrays())]
    assert names == ["v", "speed", "id"]
    np.testing.assert_array_equal(vtk_to_numpy(poly.GetPoints().GetData()), tr.positions[3])


def test_vtk_reads_the_colliders(tmp_path):
    tr = synthetic(colliders=[BOX, PLANE, SPHERE])
    written = export(tr, tmp_path / "run.pvd")
    assert written[:2] == [tmp_path / "run.pvd", tmp_path / "run_colliders.vtp"] and len(written) == F + 2
    assert all(p.parent == tmp_path / "run_vtk" for p in written[2:])  # the frames
    poly = read_vtp(tmp_path / "run_colliders.vtp")
    points = vtk_to_numpy(poly.GetPoints().GetData())
    lines, polys = cells(poly.GetLines()), cells(poly.GetPolys())
    assert poly.GetNumberOfVerts() == 0 and len(lines) == 12 and len(polys) == 1 + 16 * 32
    # The cell data 'collider': the index in traj.colliders, lines first (VTK's order).
    assert vtk_to_numpy(poly.GetCellData().GetArray("collider")).tolist() == [0] * 12 + [1] + [2] * 512

    # The box: its 8 corners, joined by its 12 edges, each along one axis.
    corners = {tuple(points[k]) for line in lines for k in line}
    assert corners == {(x, y, z) for x in (-3.0, 3.0) for y in (-2.0, 2.5) for z in (-4.0, 4.0)}
    for a, b in lines:
        assert np.count_nonzero(points[a] != points[b]) == 1
    assert len({frozenset(line) for line in lines}) == 12

    # The plane: a square in the plane, centred where the plane is nearest the scene's middle.
    n = np.array(PLANE["normal"]) / np.linalg.norm(PLANE["normal"])
    quad = points[polys[0]]
    np.testing.assert_allclose((quad - PLANE["point"]) @ n, 0, atol=1e-12)
    sides = np.linalg.norm(quad - np.roll(quad, 1, axis=0), axis=1)
    np.testing.assert_allclose(sides, sides[0], rtol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(quad[2] - quad[0]), np.linalg.norm(quad[3] - quad[1]), rtol=1e-12)  # a square
    # It spans the box (the scene): every corner of the box lies over the square.
    u, w = (quad[1] - quad[0]) / sides[1], (quad[3] - quad[0]) / sides[3]
    across = (np.array(sorted(corners)) - quad[0]) @ np.stack([u, w], axis=1)
    assert np.all(across > 0) and np.all(across < sides[0])
    normal = np.cross(quad[1] - quad[0], quad[2] - quad[1])
    assert normal @ n > 0  # the polygon faces where the normal points

    # The sphere: a closed surface of points at its radius, its faces facing out.
    sphere = sorted({k for cell in polys[1:] for k in cell})
    radii = np.linalg.norm(points[sphere] - SPHERE["center"], axis=1)
    np.testing.assert_allclose(radii, SPHERE["radius"], rtol=1e-15)
    assert len(sphere) == 2 + 15 * 32
    for cell in polys[1:]:
        p = points[cell]
        assert np.cross(p[1] - p[0], p[2] - p[0]) @ (p.mean(axis=0) - SPHERE["center"]) > 0


# A closed tetrahedron, its faces anticlockwise seen from outside, standing at (2, 1, 0).
TETRA = {
    "type": "mesh",
    "vertices": [[2.0, 1.0, 0.0], [3.0, 1.0, 0.0], [2.0, 2.0, 0.0], [2.0, 1.0, 1.25]],
    "faces": [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    "inside": False,
}


def test_vtk_reads_a_mesh_collider_as_its_triangles(tmp_path):
    # A mesh collider once failed the export (KeyError 'center': every collider that was
    # not a plane or a box was taken for a sphere).
    tr = synthetic(colliders=[BOX, TETRA, SPHERE])
    export(tr, tmp_path / "run.pvd")
    poly = read_vtp(tmp_path / "run_colliders.vtp")
    points = vtk_to_numpy(poly.GetPoints().GetData())
    lines, polys = cells(poly.GetLines()), cells(poly.GetPolys())
    assert len(lines) == 12 and len(polys) == 4 + 512
    assert vtk_to_numpy(poly.GetCellData().GetArray("collider")).tolist() == [0] * 12 + [1] * 4 + [2] * 512
    # Its triangles are its faces over its vertices, exactly, in its order (so its normals).
    triangles = np.array([points[c] for c in polys[:4]])
    np.testing.assert_array_equal(triangles, np.array(TETRA["vertices"])[np.array(TETRA["faces"])])
    centre = np.mean(TETRA["vertices"], axis=0)
    for p in triangles:
        assert np.cross(p[1] - p[0], p[2] - p[0]) @ (p.mean(axis=0) - centre) > 0  # facing out

    # A world's own mesh (kinema.Mesh, through Trajectory.colliders) and a mesh beyond the
    # particles: the scene (a plane's square) grows to hold it.
    far = {**TETRA, "vertices": (np.array(TETRA["vertices"]) + [40.0, 0.0, 0.0]).tolist()}
    export(synthetic(colliders=[far, PLANE]), tmp_path / "far.pvd")
    poly = read_vtp(tmp_path / "far_colliders.vtp")
    square = vtk_to_numpy(poly.GetPoints().GetData())[cells(poly.GetPolys())[4]]
    assert square[:, 0].max() > 42.0

    w = kinema.World(dt=0.01)
    w.add_particles([[2.2, 1.2, 2.0]], radius=0.05)
    w.add(kinema.Mesh(vertices=TETRA["vertices"], faces=TETRA["faces"]))
    export(w.run(0.02, fps=100), tmp_path / "world.pvd")
    poly = read_vtp(tmp_path / "world_colliders.vtp")
    assert poly.GetNumberOfPolys() == 4 and poly.GetNumberOfLines() == 0
    np.testing.assert_array_equal(np.sort(vtk_to_numpy(poly.GetPoints().GetData()), axis=0), np.sort(TETRA["vertices"], axis=0))


def test_open_box_faces_and_2d_colliders(tmp_path):
    # An open top (hi z = inf) ends where the scene does: above every particle.
    tr = synthetic(colliders=[{"type": "box", "lo": [-5.0, -5.0, -5.0], "hi": [5.0, 5.0, np.inf]}])
    export(tr, tmp_path / "open.pvd")
    points = vtk_to_numpy(read_vtp(tmp_path / "open_colliders.vtp").GetPoints().GetData())
    top = points[:, 2].max()
    assert sorted(set(points[:, 2])) == [-5.0, top] and top > tr.positions[..., 2].max() + tr.radii.max()

    # In 2D, at z = 0: a box is a rectangle, a plane a segment (lines), a sphere a disk.
    tr = synthetic(2, colliders=[{"type": "box", "lo": [-4.0, -3.0], "hi": [4.0, 3.0]}, {"type": "plane", "point": [0, -2, 0], "normal": [0, 1, 0]}, SPHERE])
    export(tr, tmp_path / "flat.pvd")
    poly = read_vtp(tmp_path / "flat_colliders.vtp")
    points = vtk_to_numpy(poly.GetPoints().GetData())
    lines, polys = cells(poly.GetLines()), cells(poly.GetPolys())
    assert len(lines) == 4 + 1 and len(polys) == 1 and len(polys[0]) == 64
    assert {tuple(points[k]) for line in lines[:4] for k in line} == {(-4.0, -3.0, 0.0), (4.0, -3.0, 0.0), (4.0, 3.0, 0.0), (-4.0, 3.0, 0.0)}
    segment = points[lines[4]]
    assert np.all(segment[:, 1] == -2.0) and np.all(segment[:, 2] == 0) and segment[:, 0].min() < -4 and segment[:, 0].max() > 4
    disk = points[polys[0]]
    assert np.all(disk[:, 2] == 0)  # the particles' plane, whatever the centre's z
    np.testing.assert_allclose(np.linalg.norm(disk[:, :2] - SPHERE["center"][:2], axis=1), SPHERE["radius"], rtol=1e-15)


def test_a_bad_collider_or_an_error_mid_export_leaves_nothing_behind(tmp_path, monkeypatch):
    import kinema.io.vtk_writer as vtk_writer

    with pytest.raises(ValueError, match=r"colliders\[1\]: the plane's normal = \[0.0, 0.0, 0.0\] is invalid"):
        export(synthetic(colliders=[BOX, {"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 0]}]), tmp_path / "run.pvd")
    assert list(tmp_path.iterdir()) == []

    real = vtk_writer._vtp

    def fail_at_frame_3(fr, i, extras):
        if i == 3:
            raise RuntimeError("interrupted")
        return real(fr, i, extras)

    monkeypatch.setattr(vtk_writer, "_vtp", fail_at_frame_3)
    with pytest.raises(RuntimeError, match="interrupted"):
        export(synthetic(colliders=[BOX]), tmp_path / "run.pvd")
    assert list(tmp_path.iterdir()) == []


# -- OVITO -----------------------------------------------------------------------------------------


def ovito_import(path):
    ovito_io = pytest.importorskip("ovito.io")
    return ovito_io.import_file(str(path))  # no input_format: OVITO tells the format from the file


def test_ovito_reads_the_pvd_as_a_trajectory(tmp_path):
    from_ovito = pytest.importorskip("ovito.data")
    tr = world_run()
    export(tr, tmp_path / "run.pvd")
    pipeline = ovito_import(tmp_path / "run.pvd")
    assert pipeline.source.num_frames == tr.t.size == 6
    for i in range(tr.t.size):
        data = pipeline.compute(i)
        p = data.particles
        assert p is not None and p.count == 6
        assert data.attributes["Time"] == tr.t[i]
        assert p.positions.dtype == np.float64
        np.testing.assert_array_equal(p.positions, tr.positions[i])
        # 'v' is OVITO's standard Velocity (it adds Velocity Magnitude), float64, exact.
        assert p["Velocity"].type_id == from_ovito.Particles.Type.Velocity and "Velocity Magnitude" in p.keys()
        np.testing.assert_array_equal(p.velocities, tr.velocities[i])
        np.testing.assert_array_equal(p["Radius"], tr.radii.astype(np.float32))  # OVITO keeps radii as float32
        np.testing.assert_array_equal(p["Mass"], tr.masses)
        np.testing.assert_array_equal(p["Particle Identifier"], tr.ids)
        np.testing.assert_array_equal(p["speed"], np.linalg.norm(tr.velocities[i], axis=1))


def test_ovito_reads_one_frame_by_its_content(tmp_path):
    tr = synthetic()
    export(tr, tmp_path / "run.pvd")
    pipeline = ovito_import(tmp_path / "run_vtk" / "run_00002.vtp")
    data = pipeline.compute()
    assert pipeline.source.num_frames == 1 and data.particles.count == N
    np.testing.assert_array_equal(data.particles.positions, tr.positions[2])
    np.testing.assert_array_equal(data.particles.velocities, tr.velocities[2])
    np.testing.assert_array_equal(data.particles["Particle Identifier"], tr.ids)


def test_ovito_reads_the_colliders_polygons_as_a_mesh(tmp_path):
    tr = world_run()
    export(tr, tmp_path / "run.pvd")
    data = ovito_import(tmp_path / "run_colliders.vtp").compute()
    assert data.particles is None
    mesh = data.surfaces["mesh"]
    # OVITO reads the polygons (the plane's square, the sphere's 512 faces) and skips the
    # box's lines: their 8 corners are vertices without faces.
    assert mesh.faces.count == 1 + 512 and mesh.vertices.count == 8 + 4 + 482
    corners = mesh.vertices["Position"][:8]
    np.testing.assert_array_equal(corners, [[x, y, z] for z in (0.0, 1.0) for y in (0.0, 1.0) for x in (0.0, 1.0)])

    # A box alone is lines only, which OVITO does not read (documented in docs/files.md).
    box_only = SimpleNamespace(**{**vars(synthetic()), "colliders": [BOX]})
    export(box_only, tmp_path / "box.pvd")
    with pytest.raises(RuntimeError, match="Could not detect the file format"):
        ovito_import(tmp_path / "box_colliders.vtp")
