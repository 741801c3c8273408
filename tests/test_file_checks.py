"""Files kinema writes read back, and files it reads hold only what it can hold ("robust under
faults"): an outside fuzz run found each case here.

- ``Trajectory.save`` wrote trajectories ``Trajectory.load`` then refused (mass -1, an infinite
  velocity, times going back); the exports wrote values their readers refuse. Now every writer
  checks what it writes by the reader's rules and refuses before writing anything.
- ``World.to_scene`` exported masses the user wrote into ``world.masses`` (-1); now it refuses
  what the scene could not be built from, naming the particle.
- The reader loaded radius 1e300, a NUL in a species name, a tilted box with open boundaries
  and a "spherical" boundary; now each is refused naming the file and the field.
- The reader followed external links and virtual datasets into other files; now it refuses
  them unless ``follow_links=True``.
- A name too long gave a raw ``OSError``, a missing folder a ``FileNotFoundError`` from
  ``render``, a USD suffix USD does not know a ``pxr.Tf.ErrorException``: now kinema's one-line
  errors naming the path.
"""

import errno
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest

import kinema
from kinema.io import FileWriteError, TrajectoryFileError, export, load_h5md, save_h5md

h5py = pytest.importorskip("h5py")

F, N = 5, 7
POS, MASS, RADIUS, SPECIES, BOX = "particles/all/position", "particles/all/mass", "particles/all/radius", "particles/all/species_index", "particles/all/box"


@dataclass
class Synthetic:
    """A trajectory-like object with the attributes kinema.io reads (as in tests/test_io.py)."""

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
    species: np.ndarray | None = None
    dim: int = 3
    dt: float = 0.01
    method: str = "verlet"
    periodic: tuple | None = None
    box_edges: np.ndarray | None = None
    colliders: list = field(default_factory=list)
    total: np.ndarray = field(init=False)

    def __post_init__(self):
        self.total = self.kinetic + sum(self.potential.values())


def synthetic(seed=0):
    rng = np.random.default_rng(seed)
    return Synthetic(
        t=np.arange(F) * 0.02,
        positions=rng.normal(size=(F, N, 3)),
        velocities=rng.normal(size=(F, N, 3)),
        kinetic=rng.random(F),
        potential={"spring": rng.random(F)},
        momentum=rng.normal(size=(F, 3)),
        angular_momentum=rng.normal(size=(F, 3)),
        contacts=rng.integers(0, 9, F),
        impulse_balance=rng.normal(size=(F, 3)) * 1e-17,
        collision_energy_lost=np.cumsum(rng.random(F)),
        masses=rng.random(N) + 0.5,
        radii=rng.random(N) * 0.1,
        ids=np.arange(N) + 100,
        species=np.array(["Ar", "Ne", "Ar", "grain", "Ne", "Ar", "Ar"]),
    )


def _one_line(e, *parts):
    message = str(e.value)
    assert "\n" not in message, message
    for part in parts:
        assert part in message, message
    return message


# -- 1. what save and export write reads back ---------------------------------------------------


def _set(name, index, value):
    def change(tr):
        a = np.array(getattr(tr, name), dtype=float if name != "species" else object)
        a[index] = value
        setattr(tr, name, a if name != "species" else a.astype(str))

    return change


def _attr(name, value):
    return lambda tr: setattr(tr, name, value)


# (change to a valid trajectory, what the message says after "cannot write <path>: ")
BAD_TRAJECTORIES = {
    "negative mass": (_set("masses", 2, -1.0), "trajectory 'masses' has mass[2] = -1 (masses must be finite and > 0 kg)"),
    "zero mass": (_set("masses", 0, 0.0), "trajectory 'masses' has mass[0] = 0"),
    "nan mass": (_set("masses", 4, np.nan), "trajectory 'masses' has mass[4] = nan"),
    "infinite velocity": (_set("velocities", (2, 3, 1), np.inf), "trajectory 'velocities' has a non-finite value (inf) at frame 2, particle 3"),
    "nan position": (_set("positions", (4, 6, 0), np.nan), "trajectory 'positions' has a non-finite value (nan) at frame 4, particle 6"),
    "times going back": (_attr("t", np.array([0.0, 0.02, 0.04, 0.03, 0.08])), "trajectory 't' must increase: t[3] = 0.03 after t[2] = 0.04"),
    "a repeated time": (_attr("t", np.array([0.0, 0.02, 0.02, 0.06, 0.08])), "trajectory 't' must increase: t[2] = 0.02 after t[1] = 0.02"),
    "infinite time": (_attr("t", np.array([0.0, 0.02, 0.04, 0.06, np.inf])), "trajectory 't' has a non-finite value (inf) at frame 4"),
    "negative radius": (_set("radii", 1, -0.5), "trajectory 'radii' has radius[1] = -0.5 (radii must be finite and >= 0 m)"),
    "huge radius": (_set("radii", 3, 1e300), "trajectory 'radii' has radius[3] = 1e+300 (radii must be at most 1e+150 m"),
    "NUL in a species name": (
        _set("species", 3, "gr\x00ain"),
        "trajectory 'species' has species[3] = 'gr\\x00ain' (species names must be non-empty printable text",
    ),
    "a control character in a species name": (_set("species", 0, "A\nr"), "trajectory 'species' has species[0] = 'A\\nr'"),
    "a periodic edge of 0": (
        lambda tr: (setattr(tr, "periodic", (True, False, False)), setattr(tr, "box_edges", np.array([0.0, 1.0, 1.0]))),
        "trajectory 'box_edges' has edge[0] = 0 (a periodic axis needs an edge > 0 m)",
    ),
}
# only H5MD holds these
BAD_FOR_H5MD = {
    "negative dt": (_attr("dt", -0.01), "trajectory 'dt' = -0.01 is not a positive number"),
    "a plane without a normal": (
        _attr("colliders", [{"type": "plane", "point": [0, 0, 0], "normal": [0, 0, 0]}]),
        "trajectory colliders[0] (a plane): normal",
    ),
    "an energy per frame too few": (_attr("kinetic", np.zeros(F - 1)), "trajectory 'kinetic' has shape (4,); it must be (5,)"),
}


@pytest.mark.parametrize("case", list(BAD_TRAJECTORIES) + list(BAD_FOR_H5MD))
def test_save_refuses_what_load_would_refuse_and_writes_nothing(tmp_path, case):
    change, expected = {**BAD_TRAJECTORIES, **BAD_FOR_H5MD}[case]
    tr = synthetic()
    change(tr)
    path = tmp_path / "run.h5"
    with pytest.raises(TrajectoryFileError) as e:
        save_h5md(tr, path)
    message = _one_line(e, expected)
    assert message.startswith(f"cannot write {path}: ") and isinstance(e.value, ValueError)
    assert list(tmp_path.iterdir()) == []  # nothing written, no temporary left


def test_what_save_refuses_is_what_load_refuses(tmp_path):
    # the same value written into a saved file: load refuses it by the same rule
    path = save_h5md(synthetic(), tmp_path / "run.h5")
    with h5py.File(path, "r+") as f:
        f[f"{MASS}/value"][0, 2] = -1.0
    with pytest.raises(TrajectoryFileError, match=r"has mass\[2\] = -1 \(masses must be finite and > 0 kg\)$"):
        kinema.Trajectory.load(path)


def test_a_world_run_with_a_mass_written_into_its_array_is_not_saved(tmp_path):
    w = kinema.World(dim=3, dt=0.01)
    w.add_particles([[0.0, 0, 0], [1.0, 0, 0]], mass=[1.0, 2.0])
    traj = w.run(0.03, fps=100)
    traj.masses[1] = -1.0
    with pytest.raises(TrajectoryFileError, match=r"trajectory 'masses' has mass\[1\] = -1"):
        traj.save(tmp_path / "run.h5")
    assert not (tmp_path / "run.h5").exists()


def test_a_trajectory_without_velocities_still_saves_and_exports(tmp_path):
    # all NaN: unknown (a file of another program without them) — not an error
    tr = synthetic()
    tr.velocities = np.full((F, N, 3), np.nan)
    back = kinema.Trajectory.load(save_h5md(tr, tmp_path / "run.h5"))
    assert np.isnan(back.velocities).all()
    for name in ("run.xyz", "run.csv", "run.lammpstrj", "run.pvd"):
        assert export(back, tmp_path / name)


EXPORTS = {"xyz": "run.xyz", "csv": "run.csv", "lammps": "run.lammpstrj", "vtk": "run.pvd", "ply": "run.ply", "gsd": "run.gsd", "usd": "run.usda"}


def _needs(fmt):
    if fmt == "gsd":
        pytest.importorskip("gsd")
    if fmt == "usd":
        pytest.importorskip("pxr")


@pytest.mark.parametrize("fmt", list(EXPORTS))
@pytest.mark.parametrize("case", ["negative mass", "infinite velocity", "times going back", "huge radius", "NUL in a species name"])
def test_exports_refuse_what_kinema_would_refuse_and_write_nothing(tmp_path, fmt, case):
    _needs(fmt)
    change, expected = BAD_TRAJECTORIES[case]
    tr = synthetic()
    change(tr)
    path = tmp_path / EXPORTS[fmt]
    with pytest.raises(TrajectoryFileError) as e:
        export(tr, path)
    assert _one_line(e, expected).startswith(f"cannot write {path}: ")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("fmt", ["ply", "gsd", "usd"])
def test_float32_formats_refuse_values_beyond_float32(tmp_path, fmt):
    _needs(fmt)
    tr = synthetic()
    tr.positions[1, 2, 0] = 1e300  # would be written as inf
    with pytest.raises(TrajectoryFileError) as e:
        export(tr, tmp_path / EXPORTS[fmt])
    _one_line(e, "trajectory 'positions' has a value (1e+300) at frame 1, particle 2 beyond float32", f"which format {fmt!r} stores")
    assert list(tmp_path.iterdir()) == []
    # text formats write it exactly
    text = export(tr, tmp_path / "run.csv")[0].read_text()
    assert "1e+300" in text


def test_ply_refuses_ids_beyond_int32(tmp_path):
    tr = synthetic()
    tr.ids = tr.ids + 2**31
    with pytest.raises(TrajectoryFileError, match=r"trajectory 'ids' has id\[0\] = 2147483748 beyond int32"):
        export(tr, tmp_path / "run.ply")
    assert export(tr, tmp_path / "run.xyz")  # ids are text there


# -- 2. to_scene --------------------------------------------------------------------------------


def _world(dim=3):
    w = kinema.World(dim=dim, dt=0.01)
    w.add_particles([[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0]], mass=[1.0, 2.0, 3.0], radius=0.1, species=["a", "b", "a"])
    return w


@pytest.mark.parametrize(
    "change, expected",
    [
        (lambda w: w.masses.__setitem__(1, -1.0), "<world>: particles[0].mass[1]: -1.0 is invalid: masses must be finite and > 0 kg"),
        (lambda w: w.masses.__setitem__(2, np.inf), "<world>: particles[0].mass[2]: inf is invalid"),
        (lambda w: w.positions.__setitem__((0, 1), np.nan), "<world>: particles[0].positions[0][1]: nan is invalid: coordinates must be finite"),
        (lambda w: w.velocities.__setitem__((2, 0), -np.inf), "<world>: particles[0].velocity[2][0]: -inf is invalid"),
    ],
)
def test_to_scene_refuses_values_the_scene_cannot_be_built_from(change, expected):
    w = _world()
    change(w)
    with pytest.raises(kinema.SceneError) as e:
        w.to_scene()
    message = _one_line(e, expected)
    assert message.endswith(")") and "particle " in message


def test_to_scene_of_a_2d_world_with_z_written_is_refused():
    w = _world(dim=2)
    w.positions[1, 2] = 0.5
    with pytest.raises(kinema.SceneError) as e:
        w.to_scene()
    _one_line(e, "particles[0].positions[1][2]: 0.5 is invalid: a 2D world keeps z = 0 (particle 1)")


def test_what_to_scene_writes_reads_back(tmp_path):
    w = _world()
    path = w.to_scene().to_toml(tmp_path / "scene.toml")
    back = kinema.load_scene(path)
    assert np.array_equal(back.masses, w.masses) and back.species.tolist() == ["a", "b", "a"]


# -- 3. what the reader refuses -----------------------------------------------------------------


def _saved(tmp_path):
    return save_h5md(synthetic(), tmp_path / "run.h5")


def _replace(f, name, data, **kwargs):
    del f[name]
    return f.create_dataset(name, data=data, **kwargs)


def _radius(f):
    f[f"{RADIUS}/value"][0, 3] = 1e300


def _nul_name(f):
    names = np.array([b"Ar", b"N\x00e", b"grain"], dtype="S5")
    f[SPECIES].attrs["names"] = names


def _control_name(f):
    f[SPECIES].attrs["names"] = np.array([b"Ar", b"Ne", b"gr\x07in"], dtype="S5")


def _tilted_open_box(f):
    # open boundaries, but edge vectors off the axes (a fixed (D, D) matrix)
    del f[f"{BOX}/edges"]
    f[f"{BOX}/edges"] = np.array([[5.0, 0.0, 0.0], [1.0, 6.0, 0.0], [0.0, 0.0, 7.0]])


def _tilted_open_box_by_frame(f):
    rows = np.broadcast_to(np.diag([5.0, 6.0, 7.0]), (F, 3, 3)).copy()
    rows[3, 0, 2] = 0.5
    _replace(f, f"{BOX}/edges/value", rows)


def _boundary(value):
    def change(f):
        f[BOX].attrs["boundary"] = np.array([value, b"none", b"none"], dtype="S9")

    return change


READ_DAMAGES = {
    "huge radius": (_radius, "dataset 'radii' (/particles/all/radius/value) has radius[3] = 1e+300 (radii must be at most 1e+150 m"),
    "NUL in a species name": (
        _nul_name,
        "dataset 'species' (/particles/all/species_index) has names[1] = 'N\\x00e' (species names must be non-empty printable text: no NUL or control characters)",
    ),
    "a control character in a species name": (_control_name, "has names[2] = 'gr\\x07in'"),
    "a tilted open box": (
        _tilted_open_box,
        "dataset 'box edges' (/particles/all/box/edges) is a triclinic box (edge vectors not along the axes), which kinema does not support",
    ),
    "a tilted open box at one frame": (_tilted_open_box_by_frame, "dataset 'box edges' (/particles/all/box/edges/value) is a triclinic box at frame 3"),
    "a spherical boundary": (
        _boundary(b"spherical"),
        "attribute 'boundary' (/particles/all/box) has boundary[0] = 'spherical'; allowed: 'periodic' or 'none'",
    ),
    "a misspelt boundary": (_boundary(b"Periodic"), "has boundary[0] = 'Periodic'; allowed: 'periodic' or 'none'"),
}


@pytest.mark.parametrize("damage", list(READ_DAMAGES))
def test_the_reader_refuses_what_kinema_cannot_hold(tmp_path, damage):
    change, expected = READ_DAMAGES[damage]
    path = _saved(tmp_path)
    with h5py.File(path, "r+") as f:
        change(f)
    for load in (load_h5md, kinema.Trajectory.load, kinema.load_trajectory):
        with pytest.raises(TrajectoryFileError) as e:
            load(path)
        assert _one_line(e, expected).startswith(f"{path}: ")


def test_an_open_box_along_the_axes_and_a_periodic_one_still_load(tmp_path):
    path = _saved(tmp_path)
    with h5py.File(path, "r+") as f:
        del f[f"{BOX}/edges"]
        f[f"{BOX}/edges"] = np.diag([5.0, 6.0, 7.0])  # a matrix, along the axes
    assert load_h5md(path).periodic is None
    tr = synthetic()
    tr.periodic, tr.box_edges = (True, True, False), np.array([2.0, 3.0, 0.0])
    back = load_h5md(save_h5md(tr, tmp_path / "periodic.h5"))
    assert back.periodic == (True, True, False) and back.box_edges.tolist() == [2.0, 3.0, 0.0]


# -- 4. links out of the file -------------------------------------------------------------------


def _outside(tmp_path):
    """A folder beside the trajectory's with a file the links point to."""
    other = tmp_path / "elsewhere"
    other.mkdir()
    with h5py.File(other / "data.h5", "w") as f:
        f["positions"] = synthetic(seed=5).positions
        f["masses"] = np.full((F, N), 2.5)
        f["raw"] = np.arange(3.0)
    return other / "data.h5"


def _external_link(f, target):
    del f[f"{POS}/value"]
    f[f"{POS}/value"] = h5py.ExternalLink(os.path.relpath(target, Path(f.filename).parent), "/positions")


def _virtual(f, target):
    layout = h5py.VirtualLayout(shape=(F, N), dtype="f8")
    layout[:] = h5py.VirtualSource(str(target), "masses", shape=(F, N))
    del f[f"{MASS}/value"]
    f[f"{MASS}"].create_virtual_dataset("value", layout)


def _external_storage(f, target):
    raw = Path(target).with_name("raw.bin")
    raw.write_bytes(np.full((F, N), 3.5).tobytes())
    del f[f"{MASS}/value"]
    f[MASS].create_dataset("value", shape=(F, N), dtype="<f8", external=[(str(raw), 0, F * N * 8)])


LINKS = {
    "an external link": (_external_link, "/particles/all/position/value is an external link to '/positions' in the file "),
    "a virtual dataset of another file": (_virtual, "/particles/all/mass/value is a virtual dataset that reads the file "),
    "a dataset stored in an external file": (_external_storage, "/particles/all/mass/value is stored in the external file "),
}


@pytest.mark.parametrize("kind", list(LINKS))
def test_links_to_other_files_are_refused_unless_followed(tmp_path, kind):
    make, expected = LINKS[kind]
    target = _outside(tmp_path)
    path = _saved(tmp_path)
    with h5py.File(path, "r+") as f:
        make(f, target)
    for load in (load_h5md, kinema.Trajectory.load):
        with pytest.raises(TrajectoryFileError) as e:
            load(path)
        assert _one_line(e, expected, "follow_links=True").startswith(f"{path}: ")
    back = kinema.Trajectory.load(path, follow_links=True)  # the caller asked for the other file
    if kind == "an external link":
        assert np.array_equal(back.positions, synthetic(seed=5).positions)
    else:
        assert np.all(back.masses == (2.5 if "virtual" in kind else 3.5))


def test_links_inside_the_file_and_a_symlinked_path_load(tmp_path):
    path = _saved(tmp_path)
    with h5py.File(path, "r+") as f:
        f["particles/all/alias"] = h5py.SoftLink("/particles/all/position")  # inside the file
        layout = h5py.VirtualLayout(shape=(F, N), dtype="f8")
        layout[:] = h5py.VirtualSource(f[f"{RADIUS}/value"])  # a virtual dataset of this file
        f.create_virtual_dataset("extra/radii", layout)
    assert load_h5md(path).positions.shape == (F, N, 3)
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    link = outside / "run.h5"
    link.symlink_to(path)  # the user named it
    assert np.array_equal(kinema.load_trajectory(link).positions, synthetic().positions)


# -- 5. errors of the right kind ----------------------------------------------------------------

LONG = "x" * 300


def test_a_name_too_long_is_one_line_naming_it(tmp_path):
    traj = synthetic()
    path = tmp_path / f"{LONG}.h5"
    with pytest.raises(FileWriteError) as e:
        save_h5md(traj, path)
    assert e.value.errno == errno.ENAMETOOLONG and isinstance(e.value, OSError)
    assert _one_line(e, f"cannot write {path}: File name too long")
    with pytest.raises(TrajectoryFileError) as e:
        kinema.Trajectory.load(path)
    assert _one_line(e, f"{path}: cannot be read (File name too long)")
    for fmt, name in EXPORTS.items():
        if fmt in ("gsd", "usd"):
            try:
                _needs(fmt)
            except pytest.skip.Exception:
                continue
        target = tmp_path / (LONG + Path(name).suffix)
        with pytest.raises(FileWriteError) as e:
            export(traj, target)
        assert e.value.errno == errno.ENAMETOOLONG, fmt
        _one_line(e, f"cannot write {target}: File name too long")
    assert list(tmp_path.iterdir()) == []


def test_a_missing_file_is_still_a_trajectory_file_error(tmp_path):
    with pytest.raises(TrajectoryFileError, match=r"missing\.h5: no such file$"):
        kinema.Trajectory.load(tmp_path / "missing.h5")


@pytest.fixture(scope="module")
def run():
    w = kinema.World(dim=2, dt=0.01)
    w.add_particles([[0.0, 0, 0], [1.0, 0, 0]], radius=0.1)
    return w.run(0.04, fps=50)


def test_render_errors_are_file_write_errors_naming_the_path(tmp_path, run):
    pytest.importorskip("imageio_ffmpeg")
    target = tmp_path / "missing" / "video.mp4"
    with pytest.raises(FileWriteError) as e:
        run.render(target, width=32, height=32)
    assert isinstance(e.value, FileNotFoundError) and e.value.errno == errno.ENOENT  # what it was before, too
    _one_line(e, f"cannot write {target}: the folder {target.parent} does not exist")
    target = tmp_path / f"{LONG}.gif"
    with pytest.raises(FileWriteError) as e:
        run.render(target, width=32, height=32)
    assert e.value.errno == errno.ENAMETOOLONG
    _one_line(e, f"cannot write {target}: File name too long")
    (tmp_path / "folder.mp4").mkdir()
    with pytest.raises(FileWriteError) as e:
        run.render(tmp_path / "folder.mp4", width=32, height=32)
    assert isinstance(e.value, IsADirectoryError)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["folder.mp4"]  # nothing else written


def test_a_usd_suffix_usd_does_not_know_is_refused_up_front(tmp_path, run):
    pytest.importorskip("pxr")
    with pytest.raises(ValueError) as e:
        export(run, tmp_path / "out.usdx", format="usd")
    _one_line(e, "'.usdx' is not a USD file's; allowed: .usd, .usda, .usdc, .usdz")
    assert not isinstance(e.value, TrajectoryFileError) and list(tmp_path.iterdir()) == []


def test_usdz_is_written_as_a_package_usd_opens(tmp_path, run):
    pytest.importorskip("pxr")
    from pxr import Usd, UsdGeom

    (path,) = export(run, tmp_path / "run.usdz")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.usdz"]
    stage = Usd.Stage.Open(str(path))
    points = UsdGeom.Points(stage.GetPrimAtPath("/World/particles"))
    assert len(points.GetPointsAttr().Get(stage.GetStartTimeCode())) == 2
