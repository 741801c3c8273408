"""kinema.io: H5MD files read back exactly, exports read back by other readers, and failed
reads and writes that say what is wrong and leave nothing half-written behind."""

import base64
import os
import re
import shlex
import subprocess
import sys
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np
import pytest

import kinema
from kinema.io import TrajectoryFileError, export, load_h5md, save_h5md

h5py = pytest.importorskip("h5py")

F, N = 5, 7


@dataclass
class Synthetic:
    """A trajectory-like object with every optional attribute kinema.io reads."""

    t: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    kinetic: np.ndarray
    potential: dict
    momentum: np.ndarray
    angular_momentum: np.ndarray
    contacts: np.ndarray
    impulse_balance: np.ndarray
    collision_energy_lost: np.ndarray
    masses: np.ndarray
    radii: np.ndarray
    ids: np.ndarray
    dim: int = 3
    dt: float = 0.01
    method: str = "verlet"
    total: np.ndarray = field(init=False)

    def __post_init__(self):
        self.total = self.kinetic + sum(self.potential.values())


def synthetic(dim=3, seed=0):
    rng = np.random.default_rng(seed)
    x, v = rng.normal(size=(F, N, 3)), rng.normal(size=(F, N, 3))
    if dim == 2:
        x[..., 2] = v[..., 2] = 0.0
    return Synthetic(
        t=np.arange(F) * 0.02,  # every 2 steps of dt = 0.01 s
        positions=x,
        velocities=v,
        kinetic=rng.random(F),
        potential={"spring": rng.random(F), "gravity": rng.normal(size=F)},  # not alphabetical
        momentum=rng.normal(size=(F, 3)),
        angular_momentum=rng.normal(size=(F, 3)),
        contacts=rng.integers(0, 9, F),
        impulse_balance=rng.normal(size=(F, 3)) * 1e-17,
        collision_energy_lost=np.cumsum(rng.random(F)),
        masses=rng.random(N) + 0.5,
        radii=rng.random(N) * 0.1,
        ids=rng.permutation(N) + 100,
        dim=dim,
    )


def world_run(dim=3):
    w = kinema.World(dim=dim, dt=0.01)
    rng = np.random.default_rng(1)
    x = rng.normal(size=(4, 3))
    if dim == 2:
        x[:, 2] = 0
    w.add_particles(x, velocity=[1.0, 2.0, 0.0], mass=[1.0, 2.0, 3.0, 4.0], radius=0.05)
    w.add(kinema.Gravity())
    return w.run(0.1, fps=50)


ARRAYS = ("t", "positions", "velocities", "kinetic", "total", "momentum", "angular_momentum", "contacts", "impulse_balance", "collision_energy_lost")


def assert_same_trajectory(a, b):
    for name in ARRAYS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert list(a.potential) == list(b.potential)
    for name in a.potential:
        np.testing.assert_array_equal(a.potential[name], b.potential[name], err_msg=name)


def listing(folder):
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*"))


# -- H5MD round trips -----------------------------------------------------------------------------


@pytest.mark.parametrize("dim", [3, 2])
def test_h5md_round_trip_is_exact(tmp_path, dim):
    tr = synthetic(dim)
    save_h5md(tr, tmp_path / "run.h5", author="Ada")
    back = load_h5md(tmp_path / "run.h5")
    assert_same_trajectory(tr, back)
    for name in ("masses", "radii", "ids"):
        np.testing.assert_array_equal(getattr(back, name), getattr(tr, name), err_msg=name)
    np.testing.assert_array_equal(back.step, np.arange(F) * 2)
    assert (back.dim, back.dt, back.method, back.author, back.group) == (dim, 0.01, "verlet", "Ada", "all")
    assert back.creator == f"kinema {kinema.__version__}"
    with h5py.File(tmp_path / "run.h5") as f:
        # every file is 3D (2D: z = 0, an open z axis), the world's dimension a parameter
        assert f["particles/all/position/value"].shape == (F, N, 3)
        assert f["particles/all/velocity/value"].shape == (F, N, 3)
        assert f["particles/all/box"].attrs["dimension"] == 3 and f["parameters/kinema"].attrs["dim"] == dim
        np.testing.assert_array_equal(f["particles/all/position/value"][..., 2] == 0, dim == 2)


@pytest.mark.parametrize("dim", [3, 2])
def test_h5md_round_trip_of_a_world_run(tmp_path, dim):
    tr = world_run(dim)
    save_h5md(tr, tmp_path / "run.h5", compression=None)
    back = load_h5md(tmp_path / "run.h5", group="all")
    assert_same_trajectory(tr, back)
    again = kinema.Trajectory.load(tmp_path / "run.h5", group="all")
    assert isinstance(again, kinema.Trajectory)
    assert_same_trajectory(tr, again)


def test_a_loaded_trajectory_keeps_what_only_its_file_knows(tmp_path):
    # Trajectory.load gives a Trajectory whose source is the file's own facts; a run has none.
    tr = world_run()
    assert tr.source is None
    path = save_h5md(tr, tmp_path / "run.h5", group="balls", author="Ada")
    back = kinema.Trajectory.load(path)
    assert isinstance(back.source, kinema.trajectory.FileInfo)
    assert (back.source.path, back.source.group, back.source.author) == (path, "balls", "Ada")
    assert back.source.creator == f"kinema {kinema.__version__}" and back.source.box_edges_by_frame is None
    np.testing.assert_array_equal(back.source.step, load_h5md(path).step)


def refusal_within_a_minute(code):
    """The exception `code` raises in a fresh interpreter, "Type: message" (or "none"); a
    code that hangs fails the test after a minute instead of hanging it."""
    wrapped = f"try:\n    {code.replace(chr(10), chr(10) + '    ')}\n    print('none')\nexcept Exception as e:\n    print(f'{{type(e).__name__}}: {{e}}')"
    res = subprocess.run([sys.executable, "-c", wrapped], capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stderr[-2000:]
    return res.stdout.strip()


def empty_free_space_in_the_global_heap(path):
    """Damage the HDF5 file `path` as one flipped byte can: the free-space object of its
    first global heap collection gets size 0, on which HDF5's heap walk
    (H5HG__cache_heap_deserialize) loops forever. Returns that object's offset."""
    data = bytearray(path.read_bytes())
    start = data.find(b"GCOL")
    assert start >= 0 and data[start + 4] == 1, "a global heap collection (vlen strings) expected"
    end = start + int.from_bytes(data[start + 8 : start + 16], "little")
    p = start + 16
    while p + 16 <= end:  # object headers: index u16, refs u16, reserved u32, size u64
        idx, size = int.from_bytes(data[p : p + 2], "little"), int.from_bytes(data[p + 8 : p + 16], "little")
        if idx == 0:
            data[p + 8 : p + 16] = bytes(8)
            path.write_bytes(bytes(data))
            return p
        p += 16 + (size + 7) // 8 * 8
    raise AssertionError("no free space in the collection")


def test_a_global_heap_the_hdf5_library_would_loop_on_is_refused_before_it_reads(tmp_path):
    # Found by `make fuzz` at full size: byte 5547 of a small trajectory set to 0 made the
    # load hang inside HDF5 (no Ctrl-C, no timeout: one C call). kinema.io._hdf5_heaps walks
    # the collections first, as the library does, and refuses the one that would not end.
    path = save_h5md(world_run(), tmp_path / "run.h5")
    at = empty_free_space_in_the_global_heap(path)
    said = refusal_within_a_minute(f"import kinema\nkinema.load_trajectory({str(path)!r})")  # (a regression hangs: fails here)
    assert said == "TrajectoryFileError: " + (
        f"{path}: corrupt HDF5 file: its global heap collection at byte {path.read_bytes().find(b'GCOL')} is damaged: "
        f"the free-space object at byte {at} has size 0 (the HDF5 library would loop on it forever)"
    )


def test_a_file_cut_inside_its_global_heap_is_refused_as_any_cut_file(tmp_path):
    # (found by make fuzz: a checkpoint cut to 900 bytes ended the heap check's read of a
    # signature near the end in "IndexError: mmap index out of range")
    path = save_h5md(world_run(), tmp_path / "run.h5")
    data = path.read_bytes()
    start = data.find(b"GCOL")
    for size in (start + 2, start + 4, start + 6, start + 12, start + 40):
        cut = tmp_path / f"cut{size}.h5"
        cut.write_bytes(data[:size])
        with pytest.raises(TrajectoryFileError, match=rf"^{re.escape(str(cut))}: "):
            kinema.load_trajectory(cut)


@pytest.mark.parametrize("name", ["run.h5", "run.gsd", "run.xyz", "run.csv", "run.lammpstrj", "run.pvd", "run.ply"])
def test_a_loaded_trajectory_shows_itself_and_its_steps_are_the_files_numbers(tmp_path, name):
    # A file's `step` is each frame's step number; Trajectory.step is the length of the steps
    # where dt does not divide a frame, which no file records. Trajectory.load once put the
    # file's numbers (an array) in Trajectory.step, and repr() of every loaded file raised
    # TypeError (only 0-dimensional arrays can be converted to Python scalars).
    tr = world_run()
    path = tmp_path / name
    tr.save(path) if name.endswith(".h5") else tr.export(path)
    back = kinema.load_trajectory(path)
    assert back.step is None and back.source.step.shape == (len(back.t),)
    shown = repr(back)
    assert shown.startswith(f"Trajectory(frames={len(tr.t)}, t=0 .. {tr.t[-1]:g} s, particles=4, dim=3") and shown.endswith(f"file={back.source.path})"), shown
    # the total energy where the file keeps the potential energies (H5MD), else "unknown", not nan
    assert ("energy=unknown" in shown) == (not name.endswith(".h5")) and "nan" not in shown, shown


def test_the_fps_a_world_ran_at_is_saved_and_loaded_back(tmp_path):
    # World.run(fps=30) with dt = 1 ms records frame k at k/30 s exactly (34 steps of
    # 0.98 ms a frame: kinema.frames): the 30 asked is kept, in /parameters/kinema, as the
    # default rate of a video of the file.
    w = kinema.World(dt=1e-3, dim=2)
    w.add_particles([[0.0, 0.0, 0.0]], radius=0.1)
    tr = w.run(0.2, fps=30)
    assert tr.fps == 30.0 and tr.t.tolist() == [k / 30 for k in range(7)] and tr.step == 1 / 30 / 34
    path = tr.save(tmp_path / "run.h5")
    with h5py.File(path) as f:
        attrs = dict(f["parameters/kinema"].attrs)
        assert (attrs["fps"], attrs["fps_unit"]) == (30.0, "s-1")
    assert load_h5md(path).fps == 30.0 and kinema.Trajectory.load(path).fps == 30.0
    # A file without it (another program's, an older kinema's) loads with fps None.
    with h5py.File(path, "r+") as f:
        del f["parameters/kinema"].attrs["fps"]
    assert kinema.Trajectory.load(path).fps is None
    # What would not load back is not written.
    for bad in (-30.0, float("nan"), True, "30"):
        tr.fps = bad
        with pytest.raises(TrajectoryFileError, match=r"trajectory 'fps' = .* is not a positive number"):
            tr.save(tmp_path / "bad.h5")
    assert not (tmp_path / "bad.h5").exists()


def test_the_file_modules_do_not_import_the_trajectory():
    # kinema.io takes any object with a Trajectory's attributes; Trajectory imports kinema.io
    # (inside its methods), never the other way round, not even through kinema.world.
    import ast
    from pathlib import Path

    for module in sorted((Path(kinema.__file__).parent / "io").glob("*.py")):
        for node in ast.walk(ast.parse(module.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.level == 2:
                assert node.module not in ("trajectory", "world"), f"{module.name} imports kinema.{node.module}"


def test_h5md_layout_follows_the_spec(tmp_path):
    tr = synthetic()
    save_h5md(tr, tmp_path / "run.h5", group="balls", author="Ada")
    with h5py.File(tmp_path / "run.h5") as f:

        def fixed_length(obj, name):  # H5MD: author, creator and boundary are fixed-length strings
            info = h5py.check_string_dtype(obj.attrs.get_id(name).dtype)
            assert info is not None and info.length is not None, (obj.name, name)
            return np.char.decode(np.asarray(obj.attrs[name]), info.encoding).tolist()

        def unit(ds):  # the units module: a variable-length ASCII string
            if "unit" not in ds.attrs:
                return None
            info = h5py.check_string_dtype(ds.attrs.get_id("unit").dtype)
            assert (info.encoding, info.length) == ("ascii", None), ds.name
            return ds.attrs["unit"]

        h5md = f["h5md"]
        np.testing.assert_array_equal(h5md.attrs["version"], [1, 1])
        assert fixed_length(h5md["author"], "name") == "Ada"
        assert [fixed_length(h5md["creator"], k) for k in ("name", "version")] == ["kinema", kinema.__version__]
        assert h5md["modules/units"].attrs["system"] == "SI"
        p = f["particles/balls"]
        assert p["box"].attrs["dimension"] == 3
        assert fixed_length(p["box"], "boundary") == ["none"] * 3
        for element, unit_of in (("position", "m"), ("velocity", "m s-1")):
            g = p[element]
            assert isinstance(g, h5py.Group) and set(g) == {"step", "time", "value"}
            assert g["step"].dtype.kind == "i" and g["step"].shape == (F,)
            assert g["time"].dtype == np.float64 and unit(g["time"]) == "s"
            assert unit(g["value"]) == unit_of and g["value"].chunks is not None
            assert g["value"].compression == "gzip" and g["value"].maxshape[0] is None
        # step and time are one dataset, hard-linked into every element, the box's included
        assert p["velocity/step"] == p["position/step"] and f["observables/momentum/time"] == p["position/time"]
        assert p["box/edges/step"] == p["position/step"] and p["box/edges/time"] == p["position/time"]
        # per-particle elements are time-dependent (znh5md reads no other form), the same at every frame
        expected = {"species": np.zeros(N), "mass": tr.masses, "radius": tr.radii, "id": tr.ids}
        for name, unit_of in (("species", None), ("mass", "kg"), ("radius", "m"), ("id", None)):
            g = p[name]
            assert set(g) == {"step", "time", "value"} and g["step"] == p["position/step"], name
            assert g["value"].shape == (F, N) and unit(g["value"]) == unit_of, name
            np.testing.assert_array_equal(g["value"], np.broadcast_to(expected[name], (F, N)), err_msg=name)
        assert p["species/value"].dtype.kind == p["id/value"].dtype.kind == "i"
        # no periodic axis: the edges are placeholders (0) and pbc all False
        np.testing.assert_array_equal(p["box/edges/value"], np.zeros((F, 3)))
        assert unit(p["box/edges/value"]) == "m"
        np.testing.assert_array_equal(p["box/pbc/value"], np.zeros((F, 3), dtype=bool))
        obs = f["observables"]
        units = {
            "kinetic_energy": "J",
            "potential_energy": "J",
            "total_energy": "J",
            "momentum": "kg m s-1",
            "angular_momentum": "kg m2 s-1",
            "impulse_balance": "kg m s-1",
            "collision_energy_lost": "J",
            "potential_energy_by_force/spring": "J",
            "potential_energy_by_force/gravity": "J",
            "contacts": None,
        }
        for name, unit_of in units.items():
            assert set(obs[name]) == {"step", "time", "value"}, name
            assert unit(obs[name]["value"]) == unit_of, name
        assert obs["momentum/value"].shape == (F, 3)
        np.testing.assert_array_equal(obs["potential_energy/value"], tr.potential["spring"] + tr.potential["gravity"])
        assert dict(f["parameters/kinema"].attrs) == {"dim": 3, "dt": 0.01, "dt_unit": "s", "method": "verlet"}


def test_h5md_without_optional_fields_reads_back_what_is_there(tmp_path):
    # A trajectory-like object with only the frames (no masses, radii, ids, dim or dt):
    # what is missing stays missing, ids default to 0..N-1 and steps to the frame index.
    run = world_run()
    tr = SimpleNamespace(
        **{name: getattr(run, name) for name in ("t", "positions", "velocities", "kinetic", "potential", "total", "momentum", "angular_momentum")}
    )
    save_h5md(tr, tmp_path / "run.h5")
    back = load_h5md(tmp_path / "run.h5")
    assert back.masses is None and back.radii is None and back.dt is None
    np.testing.assert_array_equal(back.ids, np.arange(4))
    np.testing.assert_array_equal(back.step, np.arange(tr.t.size))


# -- reading errors: one line naming the file ----------------------------------------------------


def _corrupt(tmp_path):
    p = tmp_path / "noise.h5"
    p.write_bytes(np.random.default_rng(0).bytes(4096))
    return p, "not an HDF5 file"


def _truncated(tmp_path):
    save_h5md(synthetic(), tmp_path / "whole.h5")
    p = tmp_path / "cut.h5"
    p.write_bytes((tmp_path / "whole.h5").read_bytes()[:3000])
    return p, "corrupt HDF5 file"


def _foreign(tmp_path):
    p = tmp_path / "foreign.h5"
    with h5py.File(p, "w") as f:
        f["data"] = np.arange(3)
    return p, "foreign HDF5 file"


def _missing(tmp_path):
    return tmp_path / "absent.h5", "no such file"


def _directory(tmp_path):
    return tmp_path, "is a directory"


@pytest.mark.parametrize("make", [_missing, _directory, _corrupt, _truncated, _foreign])
def test_unreadable_files_raise_one_clear_line(tmp_path, make):
    path, what = make(tmp_path)
    with pytest.raises(TrajectoryFileError) as e:
        load_h5md(path)
    message = str(e.value)
    assert isinstance(e.value, ValueError)
    assert "\n" not in message and str(path) in message and what in message


def test_a_missing_group_lists_the_groups_there(tmp_path):
    save_h5md(synthetic(), tmp_path / "run.h5", group="balls")
    with pytest.raises(TrajectoryFileError, match=r"no particle group 'dust'; available: balls$"):
        load_h5md(tmp_path / "run.h5", group="dust")


# -- failed writes leave nothing behind -----------------------------------------------------------


def test_writing_into_a_missing_folder_fails_clearly_and_creates_nothing(tmp_path):
    target = tmp_path / "nowhere" / "run.h5"
    for write in (lambda: save_h5md(synthetic(), target), lambda: export(synthetic(), tmp_path / "nowhere" / "run.pvd")):
        with pytest.raises(TrajectoryFileError, match="nowhere.*does not exist"):
            write()
    with pytest.raises(TrajectoryFileError, match="is a directory"):
        save_h5md(synthetic(), tmp_path)
    assert listing(tmp_path) == []


def test_an_error_mid_write_keeps_the_previous_file_and_leaves_no_temporary(tmp_path, monkeypatch):
    import kinema.io.h5md as h5md_module

    target = tmp_path / "run.h5"
    save_h5md(synthetic(seed=1), target)
    before = target.read_bytes()
    calls = []
    real = h5md_module._element

    def failing(*args, **kwargs):
        calls.append(1)
        if len(calls) == 3:
            raise RuntimeError("disk on fire")
        return real(*args, **kwargs)

    monkeypatch.setattr(h5md_module, "_element", failing)
    with pytest.raises(RuntimeError, match="disk on fire"):
        save_h5md(synthetic(seed=2), target)
    assert listing(tmp_path) == ["run.h5"] and target.read_bytes() == before


@pytest.mark.parametrize("fmt, frame_writer", [("pvd", "_vtp"), ("ply", "_ply"), ("xyz", "_xyz"), ("csv", "_csv")])
def test_an_error_mid_export_leaves_nothing_behind(tmp_path, monkeypatch, fmt, frame_writer):
    from kinema.io import csv_writer, ply_writer, vtk_writer, xyz_writer

    writer_module = {"pvd": vtk_writer, "ply": ply_writer, "xyz": xyz_writer, "csv": csv_writer}[fmt]
    real = getattr(writer_module, frame_writer)

    def fail_at_frame_3(fr, i, *args):
        if i == 3:
            raise RuntimeError("interrupted")
        return real(fr, i, *args)

    monkeypatch.setattr(writer_module, frame_writer, fail_at_frame_3)
    with pytest.raises(RuntimeError, match="interrupted"):
        export(synthetic(), tmp_path / f"run.{fmt}")
    assert listing(tmp_path) == []


def test_a_series_replaces_an_earlier_series_but_never_other_files(tmp_path):
    export(synthetic(), tmp_path / "run.ply")
    short = synthetic(seed=3)
    short.t, short.positions, short.velocities = short.t[:2], short.positions[:2], short.velocities[:2]
    export(short, tmp_path / "run.ply")
    assert listing(tmp_path) == ["run_ply", "run_ply/run_00000.ply", "run_ply/run_00001.ply"]
    (tmp_path / "run_ply" / "notes.txt").write_text("mine")
    with pytest.raises(TrajectoryFileError, match="holds other files"):
        export(synthetic(), tmp_path / "run.ply")
    assert (tmp_path / "run_ply" / "notes.txt").read_text() == "mine"


def test_a_bad_format_names_the_allowed_values(tmp_path):
    with pytest.raises(ValueError, match=r"format = 'obj' is invalid: the allowed values are 'vtk', 'ply', 'xyz', 'csv'"):
        export(synthetic(), tmp_path / "run.obj", format="obj")
    with pytest.raises(ValueError, match=r"format: cannot tell it from the suffix '.obj'"):
        export(synthetic(), tmp_path / "run.obj")
    assert listing(tmp_path) == []


# -- exports read back ---------------------------------------------------------------------------


def read_vtp(path):
    """The DataArrays of an XML PolyData file with inline base64 binary data (UInt64 header)."""
    root = ET.parse(path).getroot()
    assert root.get("type") == "PolyData" and root.get("header_type") == "UInt64"
    dtypes = {"Float64": "<f8", "Int64": "<i8"}
    out = {}
    for da in root.iter("DataArray"):
        raw = base64.b64decode(da.text)
        nbytes = int(np.frombuffer(raw[:8], "<u8")[0])
        a = np.frombuffer(raw[8:], dtypes[da.get("type")])
        assert a.nbytes == nbytes
        k = int(da.get("NumberOfComponents", 1))
        out[da.get("Name")] = a.reshape(-1, k) if k > 1 else a
    piece = root.find("PolyData/Piece")
    return out, int(piece.get("NumberOfPoints")), int(piece.get("NumberOfVerts"))


@pytest.mark.parametrize("dim", [3, 2])
def test_vtk_series_reads_back(tmp_path, dim):
    tr = synthetic(dim)
    written = export(tr, tmp_path / "run.pvd")
    assert written[0] == tmp_path / "run.pvd" and len(written) == F + 1
    datasets = ET.parse(tmp_path / "run.pvd").getroot().findall("Collection/DataSet")
    assert [float(d.get("timestep")) for d in datasets] == tr.t.tolist()
    for i, d in enumerate(datasets):
        arrays, n_points, n_verts = read_vtp(tmp_path / d.get("file"))
        assert n_points == n_verts == N
        np.testing.assert_array_equal(arrays["Points"], tr.positions[i])
        np.testing.assert_array_equal(arrays["v"], tr.velocities[i])
        np.testing.assert_array_equal(arrays["speed"], np.linalg.norm(tr.velocities[i], axis=1))
        np.testing.assert_array_equal(arrays["radius"], tr.radii)
        np.testing.assert_array_equal(arrays["mass"], tr.masses)
        np.testing.assert_array_equal(arrays["id"], tr.ids)
        np.testing.assert_array_equal(arrays["connectivity"], np.arange(N))
        np.testing.assert_array_equal(arrays["offsets"], np.arange(1, N + 1))
        assert arrays["TimeValue"].tolist() == [tr.t[i]]


def test_ply_frames_read_back_with_meshio(tmp_path):
    meshio = pytest.importorskip("meshio")
    tr = synthetic()
    written = export(tr, tmp_path / "run.ply")
    assert [p.name for p in written] == [f"run_{i:05d}.ply" for i in range(F)]
    for i, p in enumerate(written):
        mesh = meshio.read(p)
        np.testing.assert_array_equal(mesh.points, tr.positions[i].astype(np.float32))
        v = np.column_stack([mesh.point_data[c] for c in ("vx", "vy", "vz")])
        np.testing.assert_array_equal(v, tr.velocities[i].astype(np.float32))
        np.testing.assert_array_equal(mesh.point_data["radius"], tr.radii.astype(np.float32))
        np.testing.assert_array_equal(mesh.point_data["id"], tr.ids)


def read_extxyz(path):
    """Frames of an extended XYZ file as (comment keys, rows as float columns)."""
    lines = path.read_text().splitlines()
    frames, i = [], 0
    while i < len(lines):
        n = int(lines[i])
        keys = dict(kv.split("=", 1) for kv in shlex.split(lines[i + 1]))
        rows = np.array([line.split()[1:] for line in lines[i + 2 : i + 2 + n]], dtype=float)
        frames.append((keys, rows))
        i += 2 + n
    return frames


def test_extended_xyz_reads_back(tmp_path):
    tr = synthetic()
    export(tr, tmp_path / "run.xyz")
    frames = read_extxyz(tmp_path / "run.xyz")
    assert len(frames) == F
    for i, (keys, rows) in enumerate(frames):
        assert keys["Properties"] == "species:S:1:pos:R:3:velo:R:3:momenta:R:3:radius:R:1:mass:R:1:masses:R:1:id:I:1"
        assert float(keys["Time"]) == tr.t[i] and keys["units"] == "SI"
        np.testing.assert_array_equal(rows[:, 0:3], tr.positions[i])
        np.testing.assert_array_equal(rows[:, 3:6], tr.velocities[i])
        np.testing.assert_array_equal(rows[:, 6:9], tr.masses[:, None] * tr.velocities[i])
        np.testing.assert_array_equal(rows[:, 9], tr.radii)
        np.testing.assert_array_equal(rows[:, 10], tr.masses)
        np.testing.assert_array_equal(rows[:, 11], tr.masses)
        np.testing.assert_array_equal(rows[:, 12], tr.ids)


def test_extended_xyz_reads_back_with_ase(tmp_path):
    ase_io = pytest.importorskip("ase.io")
    tr = synthetic()
    export(tr, tmp_path / "run.extxyz")
    frames = ase_io.read(tmp_path / "run.extxyz", index=":", format="extxyz")
    assert len(frames) == F
    for i, atoms in enumerate(frames):
        np.testing.assert_array_equal(atoms.positions, tr.positions[i])
        np.testing.assert_array_equal(atoms.arrays["velo"], tr.velocities[i])
        np.testing.assert_array_equal(atoms.arrays["id"], tr.ids)
        assert atoms.info["Time"] == tr.t[i] and not atoms.pbc.any()


def test_csv_reads_back(tmp_path):
    tr = world_run()
    export(tr, tmp_path / "run.csv")
    with open(tmp_path / "run.csv") as f:
        assert f.readline().strip() == "frame,time,id,x,y,z,vx,vy,vz,mass,radius,group"
    table = np.loadtxt(tmp_path / "run.csv", delimiter=",", skiprows=1)
    f_, n = tr.positions.shape[:2]
    assert table.shape == (f_ * n, 12)
    np.testing.assert_array_equal(table[:, 11], np.tile(tr.groups, f_))
    np.testing.assert_array_equal(table[:, 0], np.repeat(np.arange(f_), n))
    np.testing.assert_array_equal(table[:, 1], np.repeat(tr.t, n))
    np.testing.assert_array_equal(table[:, 2], np.tile(np.arange(n), f_))
    np.testing.assert_array_equal(table[:, 3:6], tr.positions.reshape(-1, 3))
    np.testing.assert_array_equal(table[:, 6:9], tr.velocities.reshape(-1, 3))


def test_written_files_get_ordinary_permissions(tmp_path):
    save_h5md(synthetic(), tmp_path / "run.h5")
    export(synthetic(), tmp_path / "run.pvd")
    mask = os.umask(0)
    os.umask(mask)
    for p in (tmp_path / "run.h5", tmp_path / "run.pvd", tmp_path / "run_vtk" / "run_00000.vtp"):
        assert p.stat().st_mode & 0o777 == 0o666 & ~mask


def test_a_periodic_box_is_written_with_its_edges(tmp_path):
    tr = synthetic()
    tr.periodic, tr.box_edges = (True, True, False), np.array([2.0, 3.0, 4.0])
    save_h5md(tr, tmp_path / "run.h5")
    with h5py.File(tmp_path / "run.h5") as f:
        box = f["particles/all/box"]
        assert np.char.decode(box.attrs["boundary"]).tolist() == ["periodic", "periodic", "none"]  # fixed-length strings
        # time-dependent, the same edges at every frame, as znh5md and MDAnalysis read them
        np.testing.assert_array_equal(box["edges/value"], [[2.0, 3.0, 4.0]] * F)
        np.testing.assert_array_equal(box["pbc/value"], [[True, True, False]] * F)
    export(tr, tmp_path / "run.xyz")
    first = (tmp_path / "run.xyz").read_text().splitlines()[1]
    # x and y are the periodic cell; z is open: the particles' extent with a margin
    assert first.startswith('Lattice="2.0 0.0 0.0 0.0 3.0 0.0 ') and 'pbc="T T F"' in first
    del tr.box_edges
    with pytest.raises(ValueError, match="periodic boundaries need the box edges"):
        save_h5md(tr, tmp_path / "other.h5")
    assert not (tmp_path / "other.h5").exists()


def test_a_world_run_saves_loads_and_exports_through_the_trajectory(tmp_path):
    # Trajectory.save / kinema.load_trajectory round-trip a run bit for bit, including what
    # the trajectory knows about the world (masses, radii, dt, method, the periodic cell).
    w = kinema.World(dt=0.01, method="rk4")
    w.add_particles([[0.2, 0.5, 0.5], [0.8, 0.5, 0.5]], velocity=[[1.0, 0, 0], [-1.0, 0, 0]], mass=[1.0, 2.0], radius=0.05)
    w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
    w.periodic = (True, False, False)
    traj = w.run(0.5, fps=20)
    assert traj.dt == 0.01 and traj.method == "rk4" and traj.periodic == (True, False, False)
    np.testing.assert_array_equal(traj.masses, [1.0, 2.0])
    np.testing.assert_array_equal(traj.radii, [0.05, 0.05])
    np.testing.assert_array_equal(traj.box_edges, [1.0, 0.0, 0.0])
    path = traj.save(tmp_path / "run.h5")
    back = kinema.load_trajectory(path)
    for name in ("t", "positions", "velocities", "kinetic", "total", "momentum", "contacts", "impulse_balance", "collision_energy_lost", "masses", "radii"):
        np.testing.assert_array_equal(getattr(back, name), getattr(traj, name), err_msg=name)
    assert back.dt == traj.dt and back.method == traj.method and back.periodic == (True, False, False)
    np.testing.assert_array_equal(back.box_edges, traj.box_edges)
    files = traj.export(tmp_path / "run.csv")
    rows = np.loadtxt(files[0], delimiter=",", skiprows=1)
    np.testing.assert_array_equal(rows[:, 3:6].reshape(-1, 2, 3), traj.positions)


def test_colliders_are_saved_and_loaded_back(tmp_path):
    # A world's colliders ride along in the trajectory (Trajectory.colliders, plain
    # descriptions) and in the file under /parameters/kinema/colliders/<k>, in order;
    # an open box's +inf survives.
    w = kinema.World(dt=0.01)
    w.add_particles([[0.0, 0.0, 1.0]], radius=0.05)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1], restitution=0.5))
    w.add(kinema.Box([-1, -1, 0], [1, 1, np.inf]))
    w.add(kinema.SphereObstacle([0.5, 0, 0.3], 0.2, friction=0.1))
    traj = w.run(0.1, fps=20)
    expected = [
        {"type": "plane", "point": [0.0, 0.0, 0.0], "normal": [0.0, 0.0, 1.0], "restitution": 0.5},
        {"type": "box", "lo": [-1.0, -1.0, 0.0], "hi": [1.0, 1.0, np.inf]},
        {"type": "sphere", "center": [0.5, 0.0, 0.3], "radius": 0.2, "friction": 0.1},
    ]
    assert traj.colliders == expected
    path = traj.save(tmp_path / "run.h5")
    assert kinema.load_trajectory(path).colliders == expected
    assert load_h5md(path).colliders == expected
    with h5py.File(path) as f:
        group = f["parameters/kinema/colliders"]
        assert list(group) == ["0", "1", "2"]
        assert group["0"].attrs["type"] == "plane"
        np.testing.assert_array_equal(group["1"].attrs["hi"], [1.0, 1.0, np.inf])
        assert f["parameters/kinema"].attrs["dt"] == 0.01  # beside the other parameters
        assert f["h5md"].attrs["version"].tolist() == [1, 1]
    # A trajectory saved again from the loaded one keeps them.
    again = kinema.load_trajectory(kinema.load_trajectory(path).save(tmp_path / "again.h5"))
    assert again.colliders == expected


def test_files_without_colliders_load_with_none(tmp_path):
    # A world without colliders writes no colliders group; an older file (written before
    # colliders were recorded, here: the group removed) loads with colliders == [].
    tr = world_run()
    assert tr.colliders == []
    save_h5md(tr, tmp_path / "run.h5")
    with h5py.File(tmp_path / "run.h5") as f:
        assert "colliders" not in f["parameters/kinema"]
    w = kinema.World(dt=0.01)
    w.add_particles([[0.0, 0.0, 1.0]])
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    save_h5md(w.run(0.05, fps=20), tmp_path / "old.h5")
    with h5py.File(tmp_path / "old.h5", "a") as f:
        del f["parameters/kinema/colliders"]
    assert kinema.load_trajectory(tmp_path / "old.h5").colliders == []
    assert load_h5md(tmp_path / "run.h5").colliders == []
    # An object without the attribute at all (Synthetic) writes none either.
    save_h5md(synthetic(), tmp_path / "syn.h5")
    assert load_h5md(tmp_path / "syn.h5").colliders == []


def test_a_damaged_collider_is_a_clear_error(tmp_path):
    w = kinema.World(dt=0.01)
    w.add_particles([[0.0, 0.0, 1.0]])
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    save_h5md(w.run(0.05, fps=20), tmp_path / "run.h5")
    with h5py.File(tmp_path / "run.h5", "a") as f:
        f["parameters/kinema/colliders/0"].attrs["type"] = "cone"
    with pytest.raises(TrajectoryFileError, match=r"run\.h5: /parameters/kinema/colliders/0 is not a kinema collider"):
        load_h5md(tmp_path / "run.h5")


# -- loading checks what it reads: the file, the dataset or attribute and the bad value -----------

POS, VEL, MASS, RADIUS = "particles/all/position", "particles/all/velocity", "particles/all/mass", "particles/all/radius"


def _replace(f, name, data=None, **kwargs):
    """Replace the dataset ``name`` (only this link: hard links elsewhere keep the old one)."""
    del f[name]
    return f.create_dataset(name, data=data, **kwargs)


def _set(name, index, value):
    def change(f):
        f[name][index] = value

    return change


def _nan_position(f):
    f[f"{POS}/value"][3, 6, 1] = np.nan


def _times(values):
    def change(f):
        _replace(f, f"{POS}/time", np.array(values, dtype=np.float64))

    return change


def _masses(values):
    return lambda f: _replace(f, MASS, np.array(values))


def _attr(group, name, value):
    def change(f):
        f[group].attrs[name] = value

    return change


# (change to a valid saved trajectory (F = 5 frames of N = 7 particles, t = 0, 0.02, ...), the message after "<path>: ")
DAMAGES = {
    "nan position": (_nan_position, "dataset 'positions' (/particles/all/position/value) has a non-finite value (nan) at frame 3, particle 6"),
    "inf velocity": (
        _set(f"{VEL}/value", (2, 0, 0), -np.inf),
        "dataset 'velocities' (/particles/all/velocity/value) has a non-finite value (-inf) at frame 2, particle 0",
    ),
    "inf time": (_times([0, 0.02, 0.04, 0.06, np.inf]), "dataset 'times' (/particles/all/position/time) has a non-finite value (inf) at frame 4"),
    "decreasing times": (_times([0, 0.02, 0.04, 0.3, 0.2]), "dataset 'times' (/particles/all/position/time) must increase: t[4] = 0.2 after t[3] = 0.3"),
    "repeated time": (_times([0, 0.02, 0.02, 0.3, 0.4]), "dataset 'times' (/particles/all/position/time) must increase: t[2] = 0.02 after t[1] = 0.02"),
    "negative mass": (
        _masses([1.0, 1.0, -1.0, 1.0, 1.0, 1.0, 1.0]),
        "dataset 'masses' (/particles/all/mass) has mass[2] = -1 (masses must be finite and > 0 kg)",
    ),
    "zero mass": (_masses([1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.0]), "dataset 'masses' (/particles/all/mass) has mass[6] = 0 (masses must be finite and > 0 kg)"),
    "nan mass": (_masses([1.0, np.nan, 1.0, 1.0, 1.0, 1.0, 1.0]), "dataset 'masses' (/particles/all/mass) has a non-finite value (nan) at particle 1"),
    # per-particle elements are time-dependent, constant: the first frame is read
    "nan radius": (_set(f"{RADIUS}/value", (0, 4), np.nan), "dataset 'radii' (/particles/all/radius/value) has a non-finite value (nan) at particle 4"),
    "negative radius": (
        _set(f"{RADIUS}/value", (0, 1), -0.5),
        "dataset 'radii' (/particles/all/radius/value) has radius[1] = -0.5 (radii must be finite and >= 0 m)",
    ),
    "dt a word": (_attr("parameters/kinema", "dt", "fast"), "attribute 'dt' (/parameters/kinema) = 'fast' is not a positive number"),
    "dt negative": (_attr("parameters/kinema", "dt", -0.01), "attribute 'dt' (/parameters/kinema) = -0.01 is not a positive number"),
    "dt nan": (_attr("parameters/kinema", "dt", np.nan), "attribute 'dt' (/parameters/kinema) = nan is not a positive number"),
    "fps a word": (_attr("parameters/kinema", "fps", "fast"), "attribute 'fps' (/parameters/kinema) = 'fast' is not a positive number"),
    "fps zero": (_attr("parameters/kinema", "fps", 0.0), "attribute 'fps' (/parameters/kinema) = 0 is not a positive number"),
    "fps inf": (_attr("parameters/kinema", "fps", np.inf), "attribute 'fps' (/parameters/kinema) = inf is not a positive number"),
    "method a number": (_attr("parameters/kinema", "method", 3), "attribute 'method' (/parameters/kinema) = 3 is not the name of an integration method"),
    "string masses": (_masses([b"heavy"] * N), "dataset 'masses' (/particles/all/mass) holds strings; it must hold real numbers"),
    "string times": (
        lambda f: _replace(f, f"{POS}/time", ["0", "1", "2", "3", "4"], dtype=h5py.string_dtype()),
        "dataset 'times' (/particles/all/position/time) holds strings",
    ),
    "complex positions": (
        lambda f: _replace(f, f"{POS}/value", np.ones((F, N, 3), dtype=complex)),
        "dataset 'positions' (/particles/all/position/value) holds complex numbers (complex128); it must hold real numbers",
    ),
    "float steps": (
        lambda f: _replace(f, f"{POS}/step", np.arange(F, dtype=np.float64)),
        "dataset 'steps' (/particles/all/position/step) holds floating-point numbers (float64); it must hold integers",
    ),
    "boolean ids": (
        lambda f: _replace(f, "particles/all/id", np.ones(N, dtype=bool)),
        "dataset 'ids' (/particles/all/id) holds booleans; it must hold integers",
    ),
    "one time too few": (
        _times([0, 0.02, 0.04, 0.06]),
        "dataset 'times' (/particles/all/position/time) has shape (4,) but dataset 'positions' (/particles/all/position/value) has 5 frames: one time per frame",
    ),
    "one mass too many": (_masses(np.ones(N + 1)), "dataset 'masses' (/particles/all/mass) has shape (8,) but there are 7 particles"),
    "velocities of fewer particles": (
        lambda f: _replace(f, f"{VEL}/value", np.zeros((F, N - 1, 3))),
        "dataset 'velocities' (/particles/all/velocity/value) has shape (5, 6, 3) but dataset 'positions' (/particles/all/position/value) (5, 7, 3); they must match",
    ),
    "positions without frames": (
        lambda f: _replace(f, f"{POS}/value", np.zeros((F, N))),
        "dataset 'positions' (/particles/all/position/value) has shape (5, 7); it must be (frames, particles, 3) or (frames, particles, 2)",
    ),
    "0 frames": (
        lambda f: _replace(f, f"{POS}/value", np.zeros((0, N, 3))),
        "0 frames: dataset 'positions' (/particles/all/position/value) has shape (0, 7, 3)",
    ),
    "an energy per frame too few": (
        lambda f: _replace(f, "observables/kinetic_energy/value", np.zeros(F - 1)),
        "dataset 'kinetic_energy' (/observables/kinetic_energy/value) has shape (4,); it must be (5,), one value per frame",
    ),
    "a 2D box for 3D positions": (_attr("particles/all/box", "dimension", 2), "attribute 'dimension' (/particles/all/box) = 2 but dataset 'positions'"),
    "no time": (lambda f: f.__delitem__(f"{POS}/time"), "/particles/all/position has no time dataset"),
    "no positions": (lambda f: f.__delitem__(POS), "not a complete H5MD trajectory: /particles/all/position is missing"),
}


@pytest.mark.parametrize("damage", list(DAMAGES))
def test_a_damaged_file_is_refused_naming_the_file_the_dataset_and_the_value(tmp_path, damage):
    change, expected = DAMAGES[damage]
    path = tmp_path / "run.h5"
    save_h5md(synthetic(), path)
    with h5py.File(path, "r+") as f:
        change(f)
    for load in (load_h5md, kinema.Trajectory.load, kinema.load_trajectory):
        with pytest.raises(TrajectoryFileError) as e:
            load(path)
        message = str(e.value)
        assert isinstance(e.value, ValueError) and "\n" not in message
        assert message.startswith(f"{path}: ") and expected in message, message


def test_a_file_without_particles_is_refused(tmp_path):
    path = kinema.World(dt=0.01).run(0.05, fps=20).save(tmp_path / "run.h5")  # an empty world saves
    with pytest.raises(TrajectoryFileError, match=r"run\.h5: 0 particles: dataset 'positions' \(/particles/all/position/value\) has shape \(2, 0, 3\)$"):
        kinema.Trajectory.load(path)


def test_a_file_without_velocities_or_energies_loads_them_as_unknown(tmp_path):
    # load_h5md reads what is there (no velocities: None); a kinema.Trajectory, which needs
    # them, gets NaN (unknown) velocities, kinetic energy, momentum and angular momentum, as
    # for a file of another program; saved again, the unknown values are not written.
    path = tmp_path / "run.h5"
    tr = synthetic()
    save_h5md(tr, path)
    with h5py.File(path, "r+") as f:
        del f[VEL]
    assert load_h5md(path).velocities is None
    back = kinema.Trajectory.load(path)
    assert back.velocities.shape == (F, N, 3) and np.isnan(back.velocities).all()
    np.testing.assert_array_equal(back.kinetic, tr.kinetic)
    with h5py.File(path, "r+") as f:
        for name in ("kinetic_energy", "momentum", "angular_momentum", "total_energy"):
            del f[f"observables/{name}"]
    back = kinema.load_trajectory(path)
    for name, shape in (("velocities", (F, N, 3)), ("kinetic", (F,)), ("momentum", (F, 3)), ("angular_momentum", (F, 3)), ("total", (F,))):
        a = getattr(back, name)
        assert a.shape == shape and np.isnan(a).all(), name
    np.testing.assert_array_equal(back.positions, tr.positions)
    np.testing.assert_array_equal(back.potential["spring"], tr.potential["spring"])
    again = back.save(tmp_path / "again.h5")
    with h5py.File(again) as f:
        assert "velocity" not in f["particles/all"] and "kinetic_energy" not in f["observables"] and "total_energy" not in f["observables"]
    reloaded = kinema.load_trajectory(again)
    np.testing.assert_array_equal(reloaded.positions, back.positions)
    assert np.isnan(reloaded.velocities).all() and np.isnan(reloaded.kinetic).all()


def test_a_file_that_is_not_hdf5_is_refused_by_trajectory_load(tmp_path):
    path = tmp_path / "run.h5"
    path.write_text("t,x,y,z\n0,1,2,3\n")
    with pytest.raises(TrajectoryFileError, match=rf"^{path}: not an HDF5 file"):
        kinema.Trajectory.load(path)


def _periodic_file(tmp_path):
    tr = synthetic()
    tr.periodic, tr.box_edges = (True, False, False), np.array([2.0, 0.0, 0.0])
    return save_h5md(tr, tmp_path / "run.h5")


def test_periodic_box_edges_are_checked(tmp_path):
    path = _periodic_file(tmp_path)
    assert load_h5md(path).periodic == (True, False, False)
    # kinema writes the edges time-dependent: each frame's are checked
    with h5py.File(path, "r+") as f:
        f["particles/all/box/edges/value"][3, 0] = np.nan
    with pytest.raises(
        TrajectoryFileError, match=r"dataset 'box edges' \(/particles/all/box/edges/value\) has edge\[0\] = nan at frame 3 \(box edges must be finite, in m\)$"
    ):
        load_h5md(path)
    with h5py.File(path, "r+") as f:
        f["particles/all/box/edges/value"][3, 0] = 0.0
    with pytest.raises(TrajectoryFileError, match=r"has edge\[0\] = 0 at frame 3 \(a periodic axis needs an edge > 0 m\)$"):
        load_h5md(path)
    # a fixed box (kinema's files before, other writers): one (D,) dataset
    with h5py.File(path, "r+") as f:
        del f["particles/all/box/edges"]
        f["particles/all/box/edges"] = [np.nan, 0.0, 0.0]
    with pytest.raises(TrajectoryFileError, match=r"dataset 'box edges' \(/particles/all/box/edges\) has edge\[0\] = nan \(box edges must be finite, in m\)$"):
        load_h5md(path)
    with h5py.File(path, "r+") as f:
        f["particles/all/box/edges"][0] = 0.0
    with pytest.raises(TrajectoryFileError, match=r"has edge\[0\] = 0 \(a periodic axis needs an edge > 0 m\)$"):
        load_h5md(path)
    with h5py.File(path, "r+") as f:
        del f["particles/all/box/edges"]
    with pytest.raises(TrajectoryFileError, match=r"run\.h5: /particles/all/box has periodic boundaries \(periodic, none, none\) but no edges dataset$"):
        load_h5md(path)


def test_colliders_are_checked_as_the_world_checks_them(tmp_path):
    w = kinema.World(dt=0.01)
    w.add_particles([[0.0, 0.0, 1.0]])
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.add(kinema.SphereObstacle([0.5, 0, 0.3], 0.2))
    path = w.run(0.05, fps=20).save(tmp_path / "run.h5")
    with h5py.File(path, "r+") as f:
        f["parameters/kinema/colliders/0"].attrs["normal"] = np.zeros(3)
    with pytest.raises(TrajectoryFileError, match=r"run\.h5: collider /parameters/kinema/colliders/0 \(a plane\): normal = \[0\.0, 0\.0, 0\.0\] is invalid"):
        kinema.Trajectory.load(path)
    with h5py.File(path, "r+") as f:
        f["parameters/kinema/colliders/0"].attrs["normal"] = "up"
    with pytest.raises(TrajectoryFileError, match=r"run\.h5: attribute 'normal' \(/parameters/kinema/colliders/0\) = 'up' is not a number$"):
        kinema.Trajectory.load(path)
    with h5py.File(path, "r+") as f:
        f["parameters/kinema/colliders/0"].attrs["normal"] = [0.0, 0.0, 1.0]
        del f["parameters/kinema/colliders/1"].attrs["radius"]
    with pytest.raises(TrajectoryFileError, match=r"run\.h5: collider /parameters/kinema/colliders/1 \(a sphere\) has no attribute 'radius'$"):
        kinema.Trajectory.load(path)


def _huge_file(tmp_path, frames, particles):
    """A valid trajectory whose positions and velocities are replaced by (frames, particles, 3)
    float64 datasets that are declared but never written (HDF5 allocates nothing)."""
    path = tmp_path / "huge.h5"
    save_h5md(synthetic(), path)
    with h5py.File(path, "r+") as f:
        del f["observables"], f[MASS], f[RADIUS], f["particles/all/id"]
        for element in (POS, VEL):
            for name in ("value", "step", "time"):
                del f[f"{element}/{name}"]
        f.create_dataset(f"{POS}/value", shape=(frames, particles, 3), dtype="f8")
        f.create_dataset(f"{POS}/step", shape=(frames,), dtype="i8")
        f.create_dataset(f"{POS}/time", shape=(frames,), dtype="f8")
        f[f"{VEL}/step"], f[f"{VEL}/time"] = f[f"{POS}/step"], f[f"{POS}/time"]
        f.create_dataset(f"{VEL}/value", shape=(frames, particles, 3), dtype="f8")
    return path


def test_a_dataset_larger_than_memory_is_refused_before_it_is_read(tmp_path):
    import time

    path = _huge_file(tmp_path, 10**6, 10**6)  # 24e12 bytes (21.8 TiB) declared
    assert path.stat().st_size < 1 << 20  # nothing allocated
    with h5py.File(path) as f:
        assert f[f"{POS}/value"].id.get_storage_size() == 0
    start = time.perf_counter()
    with pytest.raises(TrajectoryFileError) as e:
        kinema.Trajectory.load(path)
    assert time.perf_counter() - start < 10
    message = str(e.value)
    assert "\n" not in message and not isinstance(e.value, MemoryError)
    assert message.startswith(
        f"{path}: dataset 'positions' (/particles/all/position/value) of shape (1000000, 1000000, 3) (float64) needs 22,351.7 GiB of memory to load; "
    ), message
    assert message.endswith(" GiB is available")


def test_memory_for_all_the_datasets_together_is_checked(tmp_path, monkeypatch):
    import kinema.io.h5md as h5md

    path = tmp_path / "run.h5"
    save_h5md(synthetic(), path)
    positions = F * N * 3 * 8
    monkeypatch.setattr(h5md, "available_memory", lambda: positions // 2)
    with pytest.raises(
        TrajectoryFileError,
        match=r"dataset 'positions' \(/particles/all/position/value\) of shape \(5, 7, 3\) \(float64\) needs 7.8e-07 GiB of memory to load; 3.9e-07 GiB is available$",
    ):
        load_h5md(path)
    monkeypatch.setattr(h5md, "available_memory", lambda: positions + 1)  # each fits, not all together
    with pytest.raises(TrajectoryFileError, match=r"run\.h5: loading it needs .* GiB of memory \(dataset 'positions' .*\); 7.8e-07 GiB is available$"):
        load_h5md(path)
    monkeypatch.setattr(h5md, "available_memory", lambda: None)  # unknown: no limit
    assert load_h5md(path).positions.shape == (F, N, 3)


def test_available_memory_is_known_here():
    from kinema.io._checks import available_memory

    memory = available_memory()
    assert memory is None or memory > 0


def test_a_valid_file_with_infinite_potential_energy_loads(tmp_path):
    # Observables are read as they are: -inf is a potential energy a world can record.
    path = tmp_path / "run.h5"
    tr = synthetic()
    tr.potential["spring"][2] = -np.inf
    save_h5md(tr, path)
    assert load_h5md(path).potential["spring"][2] == -np.inf
