"""What a granular researcher measures, from a scene file and the command line (issue 47): a
scene's `[analysis]` table makes `kinema run` write analysis.json, and `kinema analyze`
measures a trajectory file, both through `kinema.analysis.report`. Here the numbers they
write are checked against the analysis functions called directly on the trajectory file,
with the contacts' ids turned into rows here (not by `Snapshot.of_frame`), the slabs' edges
and cross-section worked out here, and the floor's pressure from the collider record's
differences; and against physics: the floor carries the pile's weight, the slabs hold its
volume. The JSON is read by a parser that refuses NaN and Infinity."""

from __future__ import annotations

import json
import math
import warnings

import numpy as np
import pytest
from typer.testing import CliRunner

import kinema
from kinema import analysis
from kinema.analysis import report
from kinema.cli import app

runner = CliRunner()

N, R, M, G = 60, 0.005, 0.0013, 9.81  # spheres, m, kg, m/s²
CELL = 0.06  # m: the periodic cell along x and y
BINS = 8
SCENE = f"""
[world]
dim = 3
dt = 2e-5
method = "verlet"
duration = 0.3
fps = 20.0

[[particles]]
type = "random"
lo = [0.005, 0.005, 0.006]
hi = [0.055, 0.055, 0.08]
count = {N}
seed = 3
min_distance = 0.0105
mass = {M}
radius = {R}

[[forces]]
type = "gravity"

[[colliders]]          # the periodic cell (its floor below the plane's)
type = "box"
lo = [0, 0, -1]
hi = [{CELL}, {CELL}, inf]

[[colliders]]          # the floor
type = "plane"
point = [0, 0, 0]
normal = [0, 0, 1]

[collisions]
model = "hertz"
youngs_modulus = 1e7
poisson_ratio = 0.3
restitution = 0.3
friction = 0.5
periodic = [true, true, false]

[output]
video = false
plot = false
"""
ANALYSIS = f"""
[analysis]
measures = ["coordination", "fabric", "forces", "repose", "profile"]
frames = "all"
bins = {BINS}
"""


def strict(text: str):
    """JSON as RFC 8259 has it: NaN, Infinity and -Infinity refused."""

    def refuse(token):
        raise ValueError(f"not standard JSON: {token}")

    return json.loads(text, parse_constant=refuse)


@pytest.fixture(scope="module")
def pile(tmp_path_factory):
    """The pile poured by `kinema run` with its [analysis] table: (its folder, the run's output)."""
    where = tmp_path_factory.mktemp("pile")
    (where / "pile.toml").write_text(SCENE + ANALYSIS)
    res = runner.invoke(app, ["run", str(where / "pile.toml"), "-o", str(where / "out")])
    assert res.exit_code == 0, res.output
    return where / "out", res.output


def rows_of(record_frame, ids):
    """A recorded frame's contacts with their particle ids made rows of ``ids`` (a dict)."""
    row = {int(v): k for k, v in enumerate(ids)}
    out = {k: np.array(v) for k, v in record_frame.items()}
    out["i"] = np.array([row[int(v)] for v in out["i"]], dtype=np.int64)
    out["j"] = np.array([row[int(v)] if v >= 0 else -1 for v in out["j"]], dtype=np.int64)
    return out


def frame_state(tr, k):
    """Frame k's live particles and contacts, by hand."""
    live = tr.alive[k] & np.isfinite(tr.positions[k]).all(axis=1)
    x, v = tr.positions[k][live], tr.velocities[k][live]
    m, r = tr.masses[live], tr.radii[live]
    return x, v, m, r, rows_of(tr.contact_record.frame(k), tr.ids[live])


def close(got, want, rel=1e-12):
    """Equal to 1e-12 of the largest magnitude, None where want is NaN."""
    want = np.asarray(want, dtype=float)
    got = np.asarray([np.nan if g is None else g for g in np.ravel(np.asarray(got, dtype=object))], dtype=float).reshape(want.shape)
    np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
    scale = np.nanmax(np.abs(want)) if np.isfinite(want).any() else 1.0
    np.testing.assert_allclose(np.nan_to_num(got), np.nan_to_num(want), rtol=0, atol=rel * max(scale, 1e-300))


def test_the_run_writes_analysis_json_and_says_so(pile):
    out, printed = pile
    assert sorted(p.name for p in out.iterdir()) == ["analysis.json", "trajectory.h5"]
    assert "analysis: coordination: Z = " in printed and f"wrote {out / 'analysis.json'}" in printed
    doc = strict((out / "analysis.json").read_text())
    assert doc["kinema_analysis"] == 1 and doc["source"] == "trajectory.h5"
    assert list(doc["measures"]) == list(report.MEASURES) and doc["axis"] == "z" and doc["bins"] == BINS
    # the [analysis] table turned the contact recording on ([output] does not ask for it)
    assert kinema.load_trajectory(out / "trajectory.h5").contact_record is not None


def test_the_numbers_are_the_analysis_functions_on_the_file(pile):
    out, _ = pile
    doc = strict((out / "analysis.json").read_text())
    tr = kinema.load_trajectory(out / "trajectory.h5")
    k = len(tr.t) - 1
    x, v, m, r, c = frame_state(tr, k)
    assert doc["frame"] == k and doc["time"] == tr.t[k] and doc["particles"] == len(x) == N
    got = doc["measures"]
    z = analysis.coordination(c, len(x), colliders=True, min_contacts=2)
    assert got["coordination"]["mean"] == z.mean and got["coordination"]["mean_all"] == z.mean_all
    assert got["coordination"]["rattlers"] == z.rattler.sum() and got["coordination"]["rattler_fraction"] == z.rattler_fraction
    f = analysis.fabric(c)
    assert got["fabric"]["tensor"] == f.tensor.tolist() and got["fabric"]["anisotropy"] == f.anisotropy and got["fabric"]["contacts"] == f.count
    p = analysis.force_distribution(c, bins=BINS)
    assert got["forces"]["mean"] == p.mean and got["forces"]["counts"] == p.counts.tolist()
    assert got["forces"]["edges"] == p.edges.tolist() and got["forces"]["density"] == p.density.tolist()
    # the profile: slabs from the lowest bottom to the highest top, over the periodic cell
    edges = np.linspace((x[:, 2] - r).min(), (x[:, 2] + r).max(), BINS + 1)
    assert doc["cross_section"] == CELL * CELL and doc["cross_section_from"] == "the periodic cell"
    period = np.array([CELL, CELL, 0.0])
    fields = analysis.slab_fields(x, m, edges=edges, cross_section=CELL * CELL, velocities=v, contacts=c, period=period)
    prof = got["profile"]
    close(prof["edges"], edges)
    close(prof["density"], fields.density)
    close(prof["velocity"], fields.velocity)
    close(prof["kinetic_stress"], fields.kinetic_stress)
    close(prof["contact_stress"], fields.contact_stress)
    solid = analysis.slab_fields(x, 4 / 3 * math.pi * r**3, edges=edges, cross_section=CELL * CELL).density
    close(prof["solid_fraction"], solid)
    # physics: the slabs hold the spheres' volume; the lowest slab's contact stress is of the
    # order of the pile's weight over the cell (203 Pa against 213 Pa here)
    assert sum(np.array(prof["solid_fraction"]) * np.diff(edges)) * CELL**2 == pytest.approx(N * 4 / 3 * math.pi * R**3, rel=1e-12)
    assert 0.5 < prof["contact_stress"][0][2][2] / (N * M * G / CELL**2) < 1.5
    try:  # (a bed this flat has no flanks to fit: the measure says why, as the function does)
        rep = analysis.angle_of_repose(x, r)
    except ValueError as e:
        assert got["repose"] == {"undefined": str(e)}
    else:
        assert got["repose"]["angle"] == rep.angle and got["repose"]["height"] == rep.height


def test_the_time_series_are_each_frames_measures_and_the_floors_pressure(pile):
    out, _ = pile
    s = strict((out / "analysis.json").read_text())["series"]
    tr = kinema.load_trajectory(out / "trajectory.h5")
    assert s["time"] == tr.t.tolist() and s["contacts"] == tr.contact_record.counts.tolist()
    want = []
    for k in range(len(tr.t)):
        x, _, _, _, c = frame_state(tr, k)
        z = analysis.coordination(c, len(x), colliders=True, min_contacts=2).mean
        want.append(None if math.isnan(z) else z)
    assert s["coordination"] == want and s["coordination"][0] is None  # no contact at t = 0: NaN, written null
    # the floor (collider 1, the plane) over each interval: the change of its normal impulse over Δt, over the cell
    impulse = tr.collider_normal[:, 1, 2]
    pressure = -(np.diff(impulse) / np.diff(tr.t)) / CELL**2
    assert s["base_pressure"][0] is None
    close(s["base_pressure"][1:], pressure)
    # at rest the floor carries the weight: within 2 % at the end
    assert s["base_pressure"][-1] == pytest.approx(N * M * G / CELL**2, rel=0.02)


def test_kinema_analyze_writes_what_the_run_wrote(pile, tmp_path):
    out, _ = pile
    res = runner.invoke(app, ["analyze", str(out / "trajectory.h5"), "--frame", "all", "--bins", str(BINS), "--json", str(tmp_path / "a.json")])
    assert res.exit_code == 0, res.output
    assert "coordination" in res.output and "base pressure" in res.output and "profile over z" in res.output
    assert strict((tmp_path / "a.json").read_text()) == strict((out / "analysis.json").read_text())
    assert [p.name for p in tmp_path.iterdir()] == ["a.json"]  # no temporary left behind


def test_kinema_analyze_at_a_frame(pile, tmp_path):
    out, _ = pile
    res = runner.invoke(app, ["analyze", str(out / "trajectory.h5"), "--frame", "3", "--measure", "coordination,fabric", "--json", str(tmp_path / "a.json")])
    assert res.exit_code == 0, res.output
    doc = strict((tmp_path / "a.json").read_text())
    assert list(doc["measures"]) == ["coordination", "fabric"] and doc["frame"] == 3 and "series" not in doc
    tr = kinema.load_trajectory(out / "trajectory.h5")
    x, _, _, _, c = frame_state(tr, 3)
    assert doc["measures"]["coordination"]["mean_all"] == analysis.coordination(c, len(x), colliders=True, min_contacts=2).mean_all
    assert doc["measures"]["fabric"]["tensor"] == analysis.fabric(c).tensor.tolist()


def test_a_frames_snapshot_reads_the_record_by_id():
    # Independent: the world's own contacts (indices of its rows now) against the recorded
    # frame's (ids) made rows by Snapshot.of_frame, after particles were removed (ids are no
    # longer rows).
    w = kinema.World(dt=2e-5, method="verlet")
    w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
    w.add(kinema.Gravity([0, 0, -G]))
    w.set_collisions(model="hertz", youngs_modulus=1e7, poisson_ratio=0.3, restitution=0.3, friction=0.5)
    w.add_particles([[0.011 * a, 0.0, R + 0.0101 * b] for a in range(4) for b in range(3)], mass=M, radius=R)
    w.remove_particles([0, 5])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kinema.PlacementWarning)
        tr = w.run(0.05, fps=40, record_contacts=True)
    now, snap = analysis.Snapshot.of_world(w), analysis.Snapshot.of_frame(tr, -1)
    assert snap.ids.tolist() == now.ids.tolist() and len(snap.contacts["i"]) > 0 and (snap.contacts["j"] >= 0).any()
    for name in now.contacts:
        np.testing.assert_array_equal(snap.contacts[name], now.contacts[name], err_msg=name)
    with pytest.raises(IndexError):
        analysis.Snapshot.of_frame(tr, len(tr.t))


def test_json_has_null_for_what_json_cannot_hold():
    text = report.to_json({"a": float("nan"), "b": np.array([np.inf, 1.5, -np.inf]), "c": np.int64(3), "d": (np.float32(0.5), True)})
    assert strict(text) == {"a": None, "b": [None, 1.5, None], "c": 3, "d": [0.5, True]}


def one_error_line(res):
    """The single line on stderr of a refused command (and no traceback, no 'unexpected')."""
    lines = res.stderr.strip().splitlines()
    assert res.exit_code == 2, res.output
    assert len(lines) == 1 and lines[0].startswith("error: "), res.stderr
    assert "Traceback" not in res.output and "unexpected" not in res.output
    return lines[0]


@pytest.fixture(scope="module")
def without_contacts(tmp_path_factory):
    where = tmp_path_factory.mktemp("plain")
    (where / "pile.toml").write_text(SCENE.replace("duration = 0.3", "duration = 0.05"))
    res = runner.invoke(app, ["run", str(where / "pile.toml"), "-o", str(where / "out")])
    assert res.exit_code == 0, res.output
    return where / "out" / "trajectory.h5"


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["missing.h5"], "missing.h5: no such file"),
        (["{T}", "--measure", "density"], "--measure 'density': unknown measure 'density'; the measures are coordination, fabric, forces, repose, profile"),
        (["{T}", "--measure", "fabric,fabric"], "--measure 'fabric,fabric': a measure is named twice"),
        (["{T}", "--frame", "7"], "--frame 7: the trajectory has 7 frames; give 0 to 6, or -1 to -7 counting from the end, or all"),
        (["{T}", "--frame", "-8"], "--frame -8: the trajectory has 7 frames"),
        (["{T}", "--frame", "last2"], "--frame 'last2': give a frame number (0 to 6, or -1 for the last), last or all"),
        (["{T}", "--axis", "w"], "--axis 'w': use x, y or z"),
        (["{T}", "--bins", "0"], "--bins 0: give a number of slabs and histogram bins from 1 to 100000"),
        (["{T}", "--cross-section", "-1"], "--cross-section -1.0: give the slabs' area across the axis"),
        (["{T}", "--json", "{D}"], "--json {D}: is a folder"),
        (["{T}", "--json", "{D}/no/such/a.json"], "--json {D}/no/such/a.json: the folder {D}/no/such does not exist"),
        (["{P}"], "--measure coordination: {P} records no contacts, and coordination, fabric, forces need them: write it with kinema run --record-contacts"),
        (["{P}", "--measure", "forces"], "--measure forces: {P} records no contacts"),
    ],
)
def test_bad_input_is_one_line_naming_the_option_and_what_is_allowed(args, says, pile, without_contacts, tmp_path):
    out, _ = pile
    fill = {"{T}": str(out / "trajectory.h5"), "{P}": str(without_contacts), "{D}": str(tmp_path)}

    def filled(text):
        for key, value in fill.items():
            text = text.replace(key, value)
        return text

    res = runner.invoke(app, ["analyze", *map(filled, args)])
    line = one_error_line(res)
    assert filled(says) in line, line
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_repose_and_profile_need_no_contacts(without_contacts, tmp_path):
    res = runner.invoke(app, ["analyze", str(without_contacts), "--measure", "repose,profile", "--bins", "3", "--json", str(tmp_path / "a.json")])
    assert res.exit_code == 0, res.output
    prof = strict((tmp_path / "a.json").read_text())["measures"]["profile"]
    assert prof["contact_stress"] is None and len(prof["density"]) == 3


def test_a_scene_that_turns_the_contacts_off_is_refused(tmp_path):
    scene = tmp_path / "bad.toml"
    scene.write_text(SCENE.replace("plot = false", "plot = false\ncontacts = false") + ANALYSIS)
    with pytest.raises(kinema.SceneError, match=r"bad.toml: output.contacts: false is invalid with analysis.measures 'coordination'"):
        kinema.Scene.from_toml(scene)
    res = runner.invoke(app, ["run", str(scene), "-o", str(tmp_path / "out")])
    assert res.exit_code == 2 and "output.contacts: false is invalid" in res.stderr and not (tmp_path / "out").exists()
    # repose and profile alone need no contacts: contacts = false stands
    scene.write_text(SCENE.replace("plot = false", "plot = false\ncontacts = false") + '[analysis]\nmeasures = ["repose", "profile"]\n')
    assert kinema.Scene.from_toml(scene).output.contacts is False


@pytest.mark.parametrize(
    ("table", "says"),
    [
        ('measures = ["density"]', "analysis.measures[0]: 'density' is invalid: input should be 'coordination', 'fabric', 'forces', 'repose' or 'profile'"),
        ('measures = ["fabric", "fabric"]', "'fabric' is named twice"),
        ('frames = "some"', "analysis.frames: 'some' is invalid: input should be 'last' or 'all'"),
        ("bins = 0", "analysis.bins: 0 is invalid"),
        ('axis = "w"', "analysis.axis: 'w' is invalid"),
        ("cross_section = -1.0", "analysis.cross_section: -1.0 is invalid"),
        ("measure = 1", "analysis.measure: unknown key; did you mean 'measures'?"),
    ],
)
def test_a_bad_analysis_table_names_its_key(table, says, tmp_path):
    scene = tmp_path / "bad.toml"
    scene.write_text(SCENE + "[analysis]\n" + table + "\n")
    with pytest.raises(kinema.SceneError) as e:
        kinema.Scene.from_toml(scene)
    assert says in str(e.value), str(e.value)


def test_a_world_loaded_from_the_scene_writes_its_analysis_table_back(tmp_path):
    # to_scene keeps [render] and [output] of the scene a world was loaded from; [analysis] too
    scene = tmp_path / "pile.toml"
    scene.write_text(SCENE + ANALYSIS)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", kinema.PlacementWarning)
        back = kinema.load_scene(scene).to_scene()
    assert back.analysis == kinema.Scene.from_toml(scene).analysis and back.output.contacts is True
    again = kinema.Scene.from_string(back.to_toml_string(), "again.toml")
    assert again.analysis == back.analysis
