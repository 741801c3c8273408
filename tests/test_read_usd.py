"""kinema reads USD (kinema.io.read_usd, ``Trajectory.load``): its own USD exports back (the
float32 the stage holds, ids, species, times, own colours and springs), and a stage written
by hand with Pixar's library (not kinema's), in metres by its metersPerUnit; which files are
USD (crate and text magic, the .usdz suffix); what it refuses."""

import subprocess
import sys
import warnings

import numpy as np
import pytest
from test_alive_files import births_and_deaths
from typer.testing import CliRunner

import kinema
from kinema.cli import app
from kinema.io import TrajectoryFileError, UnitWarning, export

pxr = pytest.importorskip("pxr")
from pxr import Gf, Sdf, Usd, UsdGeom, UsdPhysics, Vt  # noqa: E402
from test_usd import cloth, fountain  # noqa: E402  (after the skip: it needs pxr)

runner = CliRunner()


def load(path, **options):
    """``Trajectory.load`` with warnings turned into errors: a reader that warns fails here."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return kinema.Trajectory.load(path, **options)


def as_float32(a):
    """The float64 of the float32 of ``a``, as a USD stage holds it (NaN stays NaN)."""
    return np.asarray(a).astype(np.float32).astype(np.float64)


def assert_read_back(back, traj):
    """``back`` (read from kinema's USD export of ``traj``) holds ``traj``'s particles as the
    stage's float32, its ids, births and deaths, times and species exactly."""
    np.testing.assert_array_equal(back.ids, traj.ids)
    np.testing.assert_array_equal(back.alive, traj.alive)
    np.testing.assert_array_equal(back.t, traj.t)  # kinema:time, float64
    np.testing.assert_array_equal(back.positions, as_float32(traj.positions))  # NaN where not alive, on both sides
    np.testing.assert_array_equal(back.velocities, as_float32(traj.velocities))
    np.testing.assert_array_equal(back.radii, as_float32(2 * traj.radii) / 2)  # widths, 2r
    assert back.species.tolist() == traj.species.tolist()
    assert back.source.creator == "kinema" and back.source.step.tolist() == list(range(len(traj.t)))


@pytest.mark.parametrize("suffix", [".usd", ".usda", ".usdc", ".usdz"])
def test_own_usd_export_of_births_and_deaths_reads_back(tmp_path, suffix):
    traj = births_and_deaths()
    traj.colors = np.array([[1.0, 0.0, 0.0], [0.25, 0.5, 0.75], [np.nan] * 3, [0.125, 1.0, 0.003]])  # id 8: by speed
    path = tmp_path / f"run{suffix}"
    export(traj, path, "usd")
    back = load(path)
    assert_read_back(back, traj)
    np.testing.assert_array_equal(back.masses, as_float32(traj.masses))
    assert back.springs.tolist() == [[3, 5], [8, 11]]  # kinema:springs, as ids
    # displayColor is linear float32: back to sRGB within 1e-6; the speed-coloured particle has none
    assert np.isnan(back.colors[2]).all() and np.isfinite(back.colors[[0, 1, 3]]).all()
    np.testing.assert_allclose(back.colors[[0, 1, 3]], traj.colors[[0, 1, 3]], rtol=0, atol=1e-6)


def test_own_usd_export_of_a_fountain_reads_back_with_its_emitters_colour(tmp_path):
    traj = fountain()  # water: its own colour #2f7fd8; oil: by speed
    export(traj, tmp_path / "fountain.usdc", "usd")
    back = load(tmp_path / "fountain.usdc")
    assert_read_back(back, traj)
    own = np.isfinite(traj.colors).all(axis=1)
    assert own.any() and not own.all()
    np.testing.assert_array_equal(np.isfinite(back.colors).all(axis=1), own)
    np.testing.assert_allclose(back.colors[own], traj.colors[own], rtol=0, atol=1e-6)
    np.testing.assert_allclose(back.colors[own][0], [0x2F / 255, 0x7F / 255, 0xD8 / 255], rtol=0, atol=1e-6)


def test_own_usd_export_of_a_cloth_gives_its_springs_back(tmp_path):
    traj = cloth(deaths=True)  # springs to a row that is born late and one that dies early
    export(traj, tmp_path / "cloth.usda", "usd")
    back = load(tmp_path / "cloth.usda")
    np.testing.assert_array_equal(back.springs, traj.springs)
    np.testing.assert_array_equal(back.positions, as_float32(traj.positions))
    np.testing.assert_array_equal(back.alive, traj.alive)
    assert back.colors is None  # every particle coloured by speed


def test_kinema_export_reads_a_usd_stage(tmp_path):
    traj = births_and_deaths()
    export(traj, tmp_path / "run.usdc", "usd")
    out = runner.invoke(app, ["export", str(tmp_path / "run.usdc"), "-f", "csv"])
    assert out.exit_code == 0, out.output
    csv = load(tmp_path / "run.csv")
    kept = traj.alive.any(axis=1)  # (a CSV has no row for a frame with no particle)
    np.testing.assert_array_equal(csv.positions, as_float32(traj.positions[kept]))


# -- another program's stage ----------------------------------------------------------------------


def hand_stage(path, metres=0.01, up="Z", kilograms=None, mass=False):
    """A stage written with pxr as another program would: a Points prim /Scene/Drops under an
    Xform translated by (100, 0, -50) (in the stage's units), time samples at time codes 0,
    2 and 5 at 10 codes per second (id 13 gone at 5), constant widths, ids; a second Points
    prim after it, which is not read. Returns the values written, in the stage's units."""
    rng = np.random.default_rng(1)
    stage = Usd.Stage.CreateNew(str(path))
    if metres is not None:
        UsdGeom.SetStageMetersPerUnit(stage, metres)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z if up == "Z" else UsdGeom.Tokens.y)
    if kilograms is not None:
        UsdPhysics.SetStageKilogramsPerUnit(stage, kilograms)
    stage.SetTimeCodesPerSecond(10.0)
    UsdGeom.Xform.Define(stage, "/Scene").AddTranslateOp().Set(Gf.Vec3d(100.0, 0.0, -50.0))
    drops = UsdGeom.Points.Define(stage, "/Scene/Drops")
    drops.CreateWidthsAttr(Vt.FloatArray([2.5]))
    drops.SetWidthsInterpolation(UsdGeom.Tokens.constant)
    written = {"x": [], "v": [], "ids": [], "codes": [0.0, 2.0, 5.0]}
    for code in written["codes"]:
        n = 3 if code == 5.0 else 4
        x, v = rng.normal(size=(n, 3)) * 30, rng.normal(size=(n, 3)) * 200
        drops.CreatePointsAttr().Set(Vt.Vec3fArray.FromNumpy(x.astype(np.float32)), Usd.TimeCode(code))
        drops.CreateVelocitiesAttr().Set(Vt.Vec3fArray.FromNumpy(v.astype(np.float32)), Usd.TimeCode(code))
        drops.CreateIdsAttr().Set(Vt.Int64Array(list(range(10, 10 + n))), Usd.TimeCode(code))
        written["x"].append(as_float32(x))
        written["v"].append(as_float32(v))
        written["ids"].append(np.arange(10, 10 + n))
    if mass:
        UsdGeom.PrimvarsAPI(drops).CreatePrimvar("mass", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.constant).Set(Vt.FloatArray([3.5]))
    UsdGeom.Points.Define(stage, "/Scene/Other").CreatePointsAttr(Vt.Vec3fArray([Gf.Vec3f(0, 0, 0)]))
    stage.GetRootLayer().Save()
    return written


def test_a_hand_written_stage_in_centimetres_reads_in_metres(tmp_path):
    path = tmp_path / "drops.usda"
    written = hand_stage(path, metres=0.01)
    back = load(path)
    np.testing.assert_array_equal(back.t, [0.0, 0.2, 0.5])  # time code / timeCodesPerSecond
    np.testing.assert_array_equal(back.ids, [10, 11, 12, 13])
    np.testing.assert_array_equal(back.alive[:, 3], [True, True, False])
    for k in range(3):
        live = back.alive[k]
        np.testing.assert_allclose(back.positions[k][live], (written["x"][k] + [100.0, 0.0, -50.0]) * 0.01, rtol=1e-15, atol=0)
        np.testing.assert_allclose(back.velocities[k][live], written["v"][k] * 0.01, rtol=1e-15, atol=0)  # USD's are per second
    np.testing.assert_allclose(back.radii, np.full(4, 2.5 / 2 * 0.01), rtol=1e-15)
    assert back.masses is None and back.colors is None and back.species is None and back.source.creator is None


def test_a_stages_masses_are_read_where_it_says_their_unit(tmp_path):
    hand_stage(tmp_path / "grams.usdc", kilograms=0.001, mass=True)
    np.testing.assert_allclose(load(tmp_path / "grams.usdc").masses, np.full(4, 3.5e-3), rtol=1e-15)
    hand_stage(tmp_path / "unknown.usdc", mass=True)
    with pytest.warns(UnitWarning, match=r"unknown\.usdc: its primvar mass is not read: the stage does not say its kilogramsPerUnit"):
        assert kinema.Trajectory.load(tmp_path / "unknown.usdc").masses is None


def test_a_stage_without_its_units_is_read_in_usds_centimetres_with_a_warning(tmp_path):
    path = tmp_path / "bare.usda"
    written = hand_stage(path, metres=None, up="Y")
    with pytest.warns(UnitWarning) as said:
        back = kinema.Trajectory.load(path)
    (message,) = [str(w.message) for w in said if issubclass(w.category, UnitWarning)]
    assert "bare.usda: the stage does not say its metersPerUnit: USD's fallback 0.01 m (centimetres) is taken" in message
    assert "up axis" not in message  # (a Y-up stage is turned, as a mesh is: nothing to warn of)
    # +y up: turned to kinema's +z up, (x, y, z) → (x, −z, y), positions and velocities
    x = (written["x"][0] + [100.0, 0.0, -50.0]) * 0.01
    np.testing.assert_allclose(back.positions[0], np.stack([x[:, 0], -x[:, 2], x[:, 1]], axis=1), rtol=1e-15)
    v = written["v"][0] * 0.01
    np.testing.assert_allclose(back.velocities[0], np.stack([v[:, 0], -v[:, 2], v[:, 1]], axis=1), rtol=1e-15)


# -- which files are USD, and what is refused ------------------------------------------------------


def test_usd_is_told_by_its_first_bytes_and_a_usdz_by_its_suffix(tmp_path):
    traj = births_and_deaths()
    export(traj, tmp_path / "run.usdc", "usd")
    export(traj, tmp_path / "run.usda", "usd")
    (tmp_path / "crate.bin").write_bytes((tmp_path / "run.usdc").read_bytes())
    (tmp_path / "text.txt").write_bytes((tmp_path / "run.usda").read_bytes())
    assert (tmp_path / "crate.bin").read_bytes().startswith(b"PXR-USDC") and (tmp_path / "text.txt").read_text().startswith("#usda")
    for name in ("crate.bin", "text.txt"):
        np.testing.assert_array_equal(load(tmp_path / name).ids, traj.ids)
    (tmp_path / "zip.bin").write_bytes(b"PK\x03\x04" + bytes(100))
    with pytest.raises(TrajectoryFileError, match="not a format kinema reads"):  # a zip is USD only as .usdz
        load(tmp_path / "zip.bin")


def test_usd_refusals_are_one_line_naming_the_file(tmp_path):
    bad = tmp_path / "notes.usd"
    bad.write_text("not a stage\n")
    with pytest.raises(TrajectoryFileError, match=r"notes\.usd: not a USD stage that can be read") as e:
        load(bad)
    assert "\n" not in str(e.value)
    stage = Usd.Stage.CreateNew(str(tmp_path / "empty.usda"))
    UsdGeom.Xform.Define(stage, "/World")
    stage.GetRootLayer().Save()
    with pytest.raises(TrajectoryFileError, match=r"empty\.usda: holds no UsdGeom.Points prim \(the particles kinema reads\)"):
        kinema.Trajectory.load(tmp_path / "empty.usda")
    export(births_and_deaths(), tmp_path / "run.usd", "usd")
    with pytest.raises(ValueError, match=r"run\.usd is read as usd, whose units are known"):
        load(tmp_path / "run.usd", units="real")


def test_without_usd_core_reading_says_how_to_get_it(tmp_path):
    export(births_and_deaths(), tmp_path / "run.usd", "usd")
    code = f"import sys; sys.modules['pxr'] = None; import kinema; kinema.Trajectory.load({str(tmp_path / 'run.usd')!r})"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 1 and "ImportError: reading USD needs the usd-core package: pip install usd-core" in out.stderr
