"""kinema's H5MD files as other readers take them, and what kinema takes from theirs: each
particle's colour (drawn by ``kinema render --color-by color``), species as atomic numbers
(znh5md gives ASE the elements), 2D worlds written 3D (MDAnalysis and znh5md read them),
``units="MD"`` (what MDAnalysis reads), and a dataset without a unit in another program's file
(a ``UnitWarning`` saying what it is taken as). Each reader's test is skipped when it is not
installed."""

import copy
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

import kinema
from kinema.io import TrajectoryFileError, load_h5md, save_h5md
from kinema.io.h5md_units import from_si
from kinema.io.units import UnitWarning

h5py = pytest.importorskip("h5py")

EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "scenes"
# MDAnalysis reads float32: the file's value rounded to float32 and its conversion to Å (×10 in
# float32) rounded again, each within half a float32 ulp (2**-24 relative)
F32 = 2 * 2.0**-24 + 1e-15


@pytest.fixture(scope="module")
def fountain(tmp_path_factory):
    """The example fountain for 0.4 s, its droplets red (its own blue is close to the colour the
    renderer gives particles without one) and living 0.15 ± 0.05 s: births and deaths."""
    text = (EXAMPLES / "fountain.toml").read_text(encoding="utf-8")
    for old, new in (('color = "#2f7fd8"', 'color = "#e0301e"'), ("lifetime = 3.0", "lifetime = 0.15"), ("lifetime_spread = 0.3", "lifetime_spread = 0.05")):
        assert old in text
        text = text.replace(old, new)
    scene = tmp_path_factory.mktemp("fountain") / "fountain.toml"
    scene.write_text(text, encoding="utf-8")
    traj = kinema.Scene.from_toml(scene).build().run(0.4, fps=30)
    born_later, died = ~traj.alive[0] & traj.alive.any(axis=0), traj.alive[:-1] & ~traj.alive[1:]
    assert born_later.any() and died.any()
    np.testing.assert_array_equal(traj.colors, np.broadcast_to([0xE0 / 255, 0x30 / 255, 0x1E / 255], traj.colors.shape))
    return traj


def gas(species=("He", "Ar", "grain", "dust")):
    """A periodic 3D gas of 8 particles, two of each species, masses of two kinds."""
    w = kinema.World(dt=0.001)
    w.add(kinema.Box([0, 0, 0], [1, 2, 3]))
    rng = np.random.default_rng(4)
    n = 2 * len(species)
    w.add_particles(
        rng.uniform(0.1, 0.9, size=(n, 3)) * [1, 2, 3],
        velocity=rng.normal(size=(n, 3)),
        mass=np.where(np.arange(n) % 2, 6.6e-27, 2e-3),
        radius=0.01,
        species=np.repeat(species, 2),
    )
    w.periodic = (True, True, True)
    return w.run(0.01, fps=500)


@pytest.fixture(scope="module")
def billiards():
    traj = kinema.Scene.from_toml(EXAMPLES / "billiards_2d.toml").build().run(0.1, fps=50)
    assert traj.dim == 2
    return traj


def colour_pixels(gif):
    """The last frame of ``gif``: how many pixels are red (the fountain's droplets) and how many
    blue (the renderer's colour for particles without one, shaded)."""
    from PIL import Image

    with Image.open(gif) as im:
        im.seek(im.n_frames - 1)
        rgb = np.asarray(im.convert("RGB")).astype(int).reshape(-1, 3)
    r, g, b = rgb.T
    return int(((r > g + 60) & (r > b + 60)).sum()), int((b > r + 60).sum())


# -- colours -------------------------------------------------------------------------------------


@pytest.mark.parametrize("units", ["SI", "MD"])
def test_colours_read_back_exactly_with_births_and_deaths(tmp_path, fountain, units):
    traj = copy.copy(fountain)
    traj.colors = traj.colors.copy()
    traj.colors[1] = np.nan  # a particle without a colour of its own
    path = traj.save(tmp_path / "run.h5", units=units)
    back = kinema.Trajectory.load(path)
    np.testing.assert_array_equal(back.colors, traj.colors)  # NaN where traj has NaN
    np.testing.assert_array_equal(back.alive, traj.alive)
    with h5py.File(path) as f:
        p = f["particles/all"]
        c = p["color/value"]
        assert c.shape == traj.positions.shape and c.dtype == np.float64 and "unit" not in c.attrs
        assert np.isnan(c.fillvalue) and p["color/step"] == p["position/step"]
        present = p["id/value"][()] != p["id/value"].fillvalue
        np.testing.assert_array_equal(c[()][present], np.broadcast_to(traj.colors, c.shape)[present])
        assert np.isnan(c[()][~present]).all()


def test_colours_outside_0_to_1_are_refused_writing_and_reading(tmp_path, fountain):
    traj = copy.copy(fountain)
    traj.colors = traj.colors.copy()
    traj.colors[2] = [0.5, 1.5, 0.0]
    with pytest.raises(TrajectoryFileError) as e:
        traj.save(tmp_path / "bad.h5")
    assert str(e.value) == f"cannot write {tmp_path / 'bad.h5'}: trajectory 'colors' has color[2] = [0.5, 1.5, 0] (colours are r, g, b in [0, 1], or NaN: none)"
    assert not (tmp_path / "bad.h5").exists()
    traj.colors[2] = 0.25
    path = traj.save(tmp_path / "run.h5")
    with h5py.File(path, "r+") as f:
        f["particles/all/color/value"][:, 2] = [0.5, -1.0, 0.0]
    with pytest.raises(TrajectoryFileError, match=r"run\.h5: dataset 'colors' \(/particles/all/color/value\) has color\[2\] = \[0\.5, -1, 0\] \(colours"):
        load_h5md(path)


def test_kinema_render_of_a_saved_fountain_draws_its_colours(tmp_path, fountain):
    # Before colours were saved, a loaded fountain had none and --color-by color drew every
    # droplet in the renderer's blue: the file without its color element shows that.
    from typer.testing import CliRunner

    from kinema.cli import app

    path = fountain.save(tmp_path / "run.h5")
    without = Path(shutil.copy(path, tmp_path / "without.h5"))
    with h5py.File(without, "r+") as f:
        del f["particles/all/color"]
    counts = {}
    for h5 in (path, without):
        gif = h5.with_suffix(".gif")
        res = CliRunner().invoke(app, ["render", str(h5), "-o", str(gif), "--color-by", "color", "--width", "320", "--height", "240"])
        assert res.exit_code == 0, res.output
        counts[h5.stem] = colour_pixels(gif)
    red, blue = counts["run"]
    assert red > 100 and blue == 0, counts
    red, blue = counts["without"]
    assert red == 0 and blue > 100, counts


def test_znh5md_does_not_read_births_and_deaths(tmp_path, fountain):
    # znh5md takes each frame's particles to be packed first with the fill values after;
    # kinema keeps one column per particle, NaN before a particle is born
    znh5md = pytest.importorskip("znh5md")
    with pytest.raises(ValueError, match=r'Array "positions" has wrong shape'):
        znh5md.IO(str(fountain.save(tmp_path / "run.h5")))[:]


@pytest.mark.filterwarnings("ignore:there is no reference attributes")  # MDAnalysis guessing types for atoms it has none of
def test_mdanalysis_reads_births_and_deaths_as_nan(tmp_path, fountain):
    mda = pytest.importorskip("MDAnalysis")
    path = fountain.save(tmp_path / "run.h5", units="MD")
    u = mda.Universe(str(path), format="H5MD", topology_format="MINIMAL", n_atoms=fountain.positions.shape[1])
    assert len(u.trajectory) == len(fountain.t)
    for i, ts in enumerate(u.trajectory):
        alive = fountain.alive[i]
        assert np.isnan(ts.positions[~alive]).all() and ts.dimensions is None  # an open box
        np.testing.assert_allclose(ts.positions[alive], fountain.positions[i][alive] * 1e10, rtol=F32, atol=0)


def test_pyh5md_reads_the_colour_and_species_index_elements(tmp_path, fountain):
    pyh5md = pytest.importorskip("pyh5md")
    path = fountain.save(tmp_path / "run.h5")
    with pyh5md.File(str(path), "r") as f:
        g = f.particles_group("all")
        for name, shape in (("color", fountain.positions.shape), ("species_index", fountain.alive.shape), ("species", fountain.alive.shape)):
            e = pyh5md.element(g, name)
            assert e.element_type == "TimeElement" and e.value.shape == shape, name
            np.testing.assert_array_equal(e.time[()], fountain.t)


# -- species -------------------------------------------------------------------------------------


def test_species_reach_ase_as_elements_and_kinema_as_names(tmp_path):
    znh5md = pytest.importorskip("znh5md")
    import ase.io

    traj = gas()
    traj.colors = np.linspace(0, 1, 24).reshape(8, 3)
    path = traj.save(tmp_path / "gas.h5")
    symbols = ["He", "He", "Ar", "Ar", "X", "X", "X", "X"]  # names that are no element: ASE's X
    for frames in (znh5md.IO(str(path))[:], ase.io.read(path, index=":", format="znh5md")):
        assert len(frames) == len(traj.t)
        for atoms in frames:
            assert atoms.get_chemical_symbols() == symbols
            np.testing.assert_array_equal(atoms.get_masses(), traj.masses)
            np.testing.assert_array_equal(atoms.arrays["color"], traj.colors)
            np.testing.assert_array_equal(atoms.arrays["species_index"], [1, 1, 0, 0, 3, 3, 2, 2])
    # units="MD": masses in u, which are ASE's (znh5md reads no unit)
    md = znh5md.IO(str(traj.save(tmp_path / "md.h5", units="MD")))[:]
    np.testing.assert_array_equal(md[0].get_masses(), traj.masses / 1.66053906660e-27)
    assert md[0].get_chemical_symbols() == symbols
    assert kinema.Trajectory.load(path).species.tolist() == traj.species.tolist() == ["He", "He", "Ar", "Ar", "grain", "grain", "dust", "dust"]
    with h5py.File(path) as f:
        p = f["particles/all"]
        np.testing.assert_array_equal(p["species/value"], np.broadcast_to([2, 2, 18, 18, 0, 0, 0, 0], (len(traj.t), 8)))
        assert "names" not in p["species"].attrs
        assert np.char.decode(p["species_index"].attrs["names"]).tolist() == ["Ar", "He", "dust", "grain"]
        np.testing.assert_array_equal(p["species_index/value"][0], [1, 1, 0, 0, 3, 3, 2, 2])


def test_species_as_indices_in_files_before_still_load(tmp_path):
    # kinema's files before species_index: the species element held each particle's index
    # among its `names` attribute.
    traj = gas()
    path = traj.save(tmp_path / "gas.h5")
    with h5py.File(path, "r+") as f:
        p = f["particles/all"]
        p["species/value"][...] = p["species_index/value"][()]
        p["species"].attrs["names"] = p["species_index"].attrs["names"]
        del p["species_index"]
    assert load_h5md(path).species.tolist() == traj.species.tolist()


# -- 2D worlds -----------------------------------------------------------------------------------


def as_2d_file_before(path):
    """Turns kinema's 2D file ``path`` into the layout kinema wrote 2D worlds in before they
    were written 3D: (F, N, 2) positions and velocities, a box of dimension 2, no dim."""
    with h5py.File(path, "r+") as f:
        p = f["particles/all"]
        for name in ("position", "velocity", "box/edges"):
            value = p[f"{name}/value"][()][..., :2]
            unit = p[f"{name}/value"].attrs["unit"]
            del p[f"{name}/value"]
            p[f"{name}/value"] = value
            p[f"{name}/value"].attrs["unit"] = unit
        p["box"].attrs["dimension"] = 2
        p["box"].attrs["boundary"] = p["box"].attrs["boundary"][:2]
        del f["parameters/kinema"].attrs["dim"]


def test_2d_files_are_3d_with_z_0_and_read_back_as_2d(tmp_path, billiards):
    path = billiards.save(tmp_path / "b.h5")
    with h5py.File(path) as f:
        p = f["particles/all"]
        assert p["position/value"].shape[2] == p["velocity/value"].shape[2] == p["box/edges/value"].shape[1] == 3
        assert not p["position/value"][..., 2].any() and p["box"].attrs["dimension"] == 3
        assert np.char.decode(p["box"].attrs["boundary"])[2] == "none"
        assert f["parameters/kinema"].attrs["dim"] == 2
    back = kinema.Trajectory.load(path)
    assert back.dim == 2 and back.colliders == billiards.colliders
    np.testing.assert_array_equal(back.positions, billiards.positions)
    np.testing.assert_array_equal(back.velocities, billiards.velocities)
    as_2d_file_before(path)
    before = kinema.Trajectory.load(path)
    assert before.dim == 2 and before.colliders == billiards.colliders
    np.testing.assert_array_equal(before.positions, billiards.positions)


@pytest.mark.filterwarnings("ignore:there is no reference attributes")  # MDAnalysis guessing types for atoms it has none of
def test_3d_readers_refused_the_2d_files_before(tmp_path, billiards):
    znh5md = pytest.importorskip("znh5md")
    mda = pytest.importorskip("MDAnalysis")
    path = billiards.save(tmp_path / "b.h5", units="MD")
    as_2d_file_before(path)
    with pytest.raises(ValueError, match=r'Array "positions" has wrong shape \(16, 2\) != \(16, 3\)'):
        znh5md.IO(str(path))[:]
    with pytest.raises(ValueError, match="MDAnalysis only supports 3-dimensional simulation boxes"):
        mda.Universe(str(path), format="H5MD", topology_format="MINIMAL", n_atoms=16)


def test_a_2d_file_with_z_is_refused(tmp_path, billiards):
    path = billiards.save(tmp_path / "b.h5")
    with h5py.File(path, "r+") as f:
        f["particles/all/position/value"][3, 5, 2] = 0.25
    with pytest.raises(TrajectoryFileError) as e:
        load_h5md(path)
    assert (
        str(e.value)
        == f"{path}: dataset 'positions' (/particles/all/position/value) has z = 0.25 at frame 3, particle 5, but /parameters/kinema says dim = 2 (z = 0)"
    )
    with h5py.File(path, "r+") as f:
        f["parameters/kinema"].attrs["dim"] = 4
    with pytest.raises(TrajectoryFileError, match=r"attribute 'dim' \(/parameters/kinema\) = 4 is not the dimension of the world \(2, or 3: "):
        load_h5md(path)


@pytest.mark.filterwarnings("ignore:there is no reference attributes")  # MDAnalysis guessing types for atoms it has none of
def test_znh5md_and_mdanalysis_read_2d_files(tmp_path, billiards):
    znh5md = pytest.importorskip("znh5md")
    mda = pytest.importorskip("MDAnalysis")
    path = billiards.save(tmp_path / "si.h5")
    frames = znh5md.IO(str(path))[:]
    assert len(frames) == len(billiards.t)
    for i, atoms in enumerate(frames):
        np.testing.assert_array_equal(atoms.positions, billiards.positions[i])  # z = 0; SI values as they are
    n = billiards.positions.shape[1]
    u = mda.Universe(str(billiards.save(tmp_path / "md.h5", units="MD")), format="H5MD", topology_format="MINIMAL", n_atoms=n)
    assert len(u.trajectory) == len(billiards.t)
    for i, ts in enumerate(u.trajectory):
        np.testing.assert_allclose(ts.positions, billiards.positions[i] * 1e10, rtol=F32, atol=0)
        assert not ts.positions[:, 2].any()


# -- units ---------------------------------------------------------------------------------------


def test_md_units_are_written_and_read_back_within_an_ulp(tmp_path):
    traj = gas()
    path = save_h5md(traj, tmp_path / "md.h5", units="MD")
    with h5py.File(path) as f:
        p, obs = f["particles/all"], f["observables"]
        units = {
            p["position/value"]: "nm",
            p["position/time"]: "ps",
            p["velocity/value"]: "nm ps-1",
            p["mass/value"]: "u",
            p["radius/value"]: "nm",
            p["box/edges/value"]: "nm",
            obs["kinetic_energy/value"]: "kJ mol-1",
            obs["momentum/value"]: "u nm ps-1",
            obs["angular_momentum/value"]: "u nm2 ps-1",
        }
        for ds, unit in units.items():
            assert ds.attrs["unit"] == unit, ds.name
            assert h5py.check_string_dtype(ds.attrs.get_id("unit").dtype).length is None  # variable-length, as MDAnalysis reads it
        np.testing.assert_array_equal(p["position/value"], traj.positions * 1e9)  # exact factors: the float64 nearest
        np.testing.assert_array_equal(p["position/time"], traj.t * 1e12)
        np.testing.assert_array_equal(p["velocity/value"], traj.velocities / 1000)
        np.testing.assert_array_equal(p["mass/value"][0], traj.masses / 1.66053906660e-27)
        np.testing.assert_array_equal(p["box/edges/value"][0], [1e9, 2e9, 3e9])
        assert f["parameters/kinema"].attrs["dt"] == traj.dt  # kinema's parameters stay SI
    back = kinema.Trajectory.load(path)
    for name in ("t", "positions", "velocities", "masses", "radii", "kinetic", "momentum", "angular_momentum", "box_edges"):
        np.testing.assert_array_max_ulp(getattr(back, name), getattr(traj, name), maxulp=1)
    assert back.species.tolist() == traj.species.tolist()
    np.testing.assert_array_equal(back.ids, traj.ids)


def test_units_must_be_si_or_md(tmp_path):
    with pytest.raises(ValueError) as e:
        save_h5md(gas(), tmp_path / "run.h5", units="nm")
    assert str(e.value) == "units = 'nm' is invalid: use 'SI' (m, s, kg, J) or 'MD' (nm, ps, u, kJ mol-1)"
    assert not (tmp_path / "run.h5").exists()


def test_md_units_refuse_what_float64_cannot_hold_in_them(tmp_path):
    traj = gas()
    traj.positions = traj.positions.copy()
    traj.positions[2, 1, 0] = 1e300  # m: 1e309 nm
    with pytest.raises(TrajectoryFileError) as e:
        save_h5md(traj, tmp_path / "run.h5", units="MD")
    assert str(e.value) == (
        f"cannot write {tmp_path / 'run.h5'}: trajectory 'positions' has a value (1e+300 m in magnitude) beyond float64 in nm (units 'MD'); write it in SI"
    )
    assert not (tmp_path / "run.h5").exists()
    save_h5md(traj, tmp_path / "run.h5")  # SI holds it


def test_mdanalysis_needs_the_unit_as_a_variable_length_string(tmp_path):
    # The units module asks for fixed-length strings; h5py reads those as bytes, which
    # MDAnalysis's table of units does not hold: kinema writes variable-length ones.
    mda = pytest.importorskip("MDAnalysis")
    path = save_h5md(gas(), tmp_path / "md.h5", units="MD")
    with h5py.File(path, "r+") as f:
        for ds in (f["particles/all/position/time"], f["particles/all/position/value"]):
            unit = ds.attrs["unit"]
            del ds.attrs["unit"]
            ds.attrs.create("unit", np.bytes_(unit), dtype=h5py.string_dtype("ascii", len(unit)))
    with pytest.raises(RuntimeError, match=r"^time unit 'b'ps'' is not recognized by H5MDReader"):
        mda.Universe(str(path), format="H5MD", topology_format="MINIMAL", n_atoms=8)


# -- datasets without a unit ---------------------------------------------------------------------


def test_znh5md_masses_are_taken_in_ase_units_and_said(tmp_path):
    znh5md = pytest.importorskip("znh5md")
    import ase
    import ase.units

    frames = []
    for k in range(2):
        atoms = ase.Atoms("HeAr", positions=[[0.0, 0.0, 0.0], [1.0, 1.0, 1.0 + k]], cell=[5.0, 5.0, 5.0], pbc=True)
        atoms.set_masses([4.0026, 39.948])
        frames.append(atoms)
    path = tmp_path / "ase.h5"
    znh5md.write(path, frames)
    with h5py.File(path) as f:
        assert f["h5md/creator"].attrs["name"] == "znh5md" and "unit" not in f["particles/atoms/mass/value"].attrs
    with pytest.warns(UnitWarning) as record:
        back = load_h5md(path)
    assert [str(w.message) for w in record] == [
        f"{path}: dataset 'masses' (/particles/atoms/mass/value) has no unit; taken as u (ASE's, 1.66053904e-27 kg), as znh5md writes ASE's numbers"
    ]
    np.testing.assert_array_equal(back.masses, np.array([4.0026, 39.948]) * ase.units._amu)  # not 4 kg
    assert back.species is None  # H5MD's integers, unnamed


def test_znh5md_files_without_units_are_taken_in_ase_units(tmp_path):
    znh5md = pytest.importorskip("znh5md")
    import ase
    import ase.units

    frames = []
    for k in range(2):
        atoms = ase.Atoms("HeAr", positions=[[0.0, 0.0, 0.0], [1.0, 1.0, 1.0 + k]], cell=[5.0, 5.0, 5.0], pbc=True)
        atoms.set_velocities([[1.0, 0.0, 0.0], [0.0, 2.0, 0.0]])  # Å per ASE's time unit
        frames.append(atoms)
    path = tmp_path / "ase.h5"
    znh5md.IO(str(path), save_units=False).extend(frames)
    with pytest.warns(UnitWarning) as record:
        back = load_h5md(path)
    assert [str(w.message) for w in record] == [
        f"{path}: dataset 'positions' (/particles/atoms/position/value) has no unit; taken as Å, as znh5md writes ASE's numbers",
        f"{path}: dataset 'velocities' (/particles/atoms/velocity/value) has no unit; taken as Å per ASE's time unit (9822.6948 m s-1), as znh5md writes ASE's numbers",
        f"{path}: dataset 'box edges' (/particles/atoms/box/edges/value) has no unit; taken as Å, as znh5md writes ASE's numbers",
    ]
    np.testing.assert_array_equal(back.positions[1], [[0.0, 0.0, 0.0], [1e-10, 1e-10, 2e-10]])
    v = 1e-10 * ase.units.s  # m/s: 1 Å per ASE time unit, by ASE (the same constants, other roundings)
    np.testing.assert_allclose(back.velocities[0], [[v, 0, 0], [0, 2 * v, 0]], rtol=1e-15, atol=0)
    np.testing.assert_array_equal(back.box_edges, [5e-10] * 3)


def foreign_file(path, creator="prog"):
    """A file ``creator`` wrote: 2 frames of 2 particles, positions and masses without a unit,
    time in ps."""
    with h5py.File(path, "w") as f:
        f.create_group("h5md").attrs["version"] = [1, 1]
        f["h5md"].create_group("creator").attrs.update({"name": creator, "version": "1"})
        p = f.create_group("particles/all")
        p["position/value"] = np.arange(12.0).reshape(2, 2, 3)
        p["position/step"] = [0, 1]
        p["position/time"] = [0.0, 1.0]
        p["position/time"].attrs["unit"] = "ps"
        p["mass"] = [2.0, 3.0]
    return path


def test_a_dataset_without_a_unit_in_another_programs_file_is_taken_as_si_and_said(tmp_path):
    path = foreign_file(tmp_path / "prog.h5")
    with pytest.warns(UnitWarning) as record:
        back = load_h5md(path)
    assert [str(w.message) for w in record] == [
        f"{path}: dataset 'positions' (/particles/all/position/value) has no unit; taken as m (SI), which its creator 'prog' may not mean",
        f"{path}: dataset 'masses' (/particles/all/mass) has no unit; taken as kg (SI), which its creator 'prog' may not mean",
    ]
    np.testing.assert_array_equal(back.masses, [2.0, 3.0])


def test_kinema_files_are_si_without_a_word(tmp_path):
    path = foreign_file(tmp_path / "own.h5", creator="kinema")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        back = load_h5md(path)
        np.testing.assert_array_equal(back.masses, [2.0, 3.0])
        save_h5md(gas(), tmp_path / "gas.h5")
        load_h5md(tmp_path / "gas.h5")


def test_unit_of_each_dataset_written(tmp_path):
    # every dataset with a dimension has its unit, so kinema's own reader never assumes one
    path = save_h5md(gas(), tmp_path / "gas.h5")
    missing = []

    def visit(name, obj):
        if isinstance(obj, h5py.Dataset) and obj.dtype.kind == "f" and name.split("/")[-1] in ("value", "time") and "unit" not in obj.attrs:
            missing.append(name)

    with h5py.File(path) as f:
        f.visititems(visit)
    assert missing == [], missing  # color: a plain number, and not in this file


def test_from_si_to_si_round_trip_within_an_ulp():
    from fractions import Fraction

    from kinema.io.h5md_units import parse_unit, to_si

    x = np.random.default_rng(3).normal(size=200_000) * 10.0 ** np.random.default_rng(4).integers(-30, 30, 200_000)
    for unit in ("nm", "ps", "nm ps-1", "u", "kJ mol-1", "u nm ps-1", "u nm2 ps-1"):
        np.testing.assert_array_max_ulp(to_si(from_si(x, unit), parse_unit(unit)[0]), x, maxulp=1)
    np.testing.assert_array_equal(to_si(np.array([4.5]), Fraction(1, 10**9)), [4.5e-9])  # / 1e9: the nearest float64
