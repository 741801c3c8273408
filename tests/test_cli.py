"""The `kinema` command: exit codes, messages, files written."""

import os
import subprocess
import sys
import time

import pytest
from typer.testing import CliRunner

import kinema
from kinema.cli import app

runner = CliRunner()


def test_stability_writes_the_png_and_prints_the_intervals(tmp_path):
    out = tmp_path / "sub" / "regions.png"
    res = runner.invoke(app, ["stability", "--methods", "euler,midpoint,rk4,implicit_euler", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "-2.7853" in res.output and "2.8284" in res.output
    assert [p.name for p in out.parent.iterdir()] == ["regions.png"]  # no temporary left behind


def test_pictures_get_the_mode_an_ordinary_open_gives(tmp_path):
    # (they were written 0600 through mkstemp; a file the user's tools share must follow the umask)
    old = os.umask(0o022)
    try:
        res = runner.invoke(app, ["stability", "--methods", "euler", "--out", str(tmp_path / "r.png")])
    finally:
        os.umask(old)
    assert res.exit_code == 0, res.output
    assert (tmp_path / "r.png").stat().st_mode & 0o777 == 0o644


def test_unknown_method_is_exit_2_with_the_valid_names(tmp_path):
    res = runner.invoke(app, ["stability", "--methods", "euler,rk5", "--out", str(tmp_path / "r.png")])
    assert res.exit_code == 2
    assert "unknown method 'rk5'" in res.output and "implicit_euler" in res.output
    assert not (tmp_path / "r.png").exists()


def test_output_into_a_directory_is_refused(tmp_path):
    res = runner.invoke(app, ["stability", "--out", str(tmp_path)])
    assert res.exit_code == 2 and "is a directory" in res.output


def test_unwritable_output_is_exit_2(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    res = runner.invoke(app, ["stability", "--out", str(blocker / "r.png")])
    assert res.exit_code == 2 and "cannot write there" in res.output


def test_methods_lists_the_registry():
    res = runner.invoke(app, ["methods"])
    assert res.exit_code == 0
    for name in ("euler", "rk45", "verlet"):
        assert name in res.output


def test_demo_writes_its_pictures(tmp_path):
    res = runner.invoke(app, ["demo", "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    for name in ("phase_portraits.png", "stability_regions.png", "convergence.png", "trajectory.h5", "demo.mp4", "demo.html", "energy.png"):
        assert (tmp_path / name).stat().st_size > 10_000
        assert str(tmp_path / name) in res.output.replace("\n", "")


def test_python_dash_m_kinema_is_the_same_command():
    res = subprocess.run([sys.executable, "-m", "kinema", "--help"], capture_output=True, text=True, check=True)
    assert "stability" in res.stdout and "demo" in res.stdout


# -- kinema run / render / export ------------------------------------------------------------

SMALL = """
[world]
dim = 2
dt = 0.01
duration = 0.3
fps = 20.0

[[particles]]
type = "list"
positions = [[0, 1], [0.5, 1]]
radius = 0.1

[[forces]]
type = "gravity"

[[colliders]]
type = "plane"
point = [0, 0]
normal = [0, 1]

[render]
width = 64
height = 48
"""


def small_scene(tmp_path, text=SMALL, name="small.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def error_lines(res):
    return [line for line in res.output.splitlines() if line.startswith("error:")]


def test_run_writes_trajectory_video_and_plot(tmp_path):
    import kinema

    out = tmp_path / "out"
    res = runner.invoke(app, ["run", str(small_scene(tmp_path)), "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in out.iterdir()) == ["energy.png", "small.mp4", "trajectory.h5"]  # no temporaries
    traj = kinema.load_trajectory(out / "trajectory.h5")
    assert traj.positions.shape == (7, 2, 3) and traj.dim == 2
    assert (out / "energy.png").read_bytes()[:4] == b"\x89PNG"
    assert (out / "small.mp4").stat().st_size > 1000
    for name in ("trajectory.h5", "small.mp4", "energy.png"):
        assert str(out / name) in res.output.replace("\n", "")


def test_run_duration_and_no_video(tmp_path):
    import kinema

    out = tmp_path / "o"
    res = runner.invoke(app, ["run", str(small_scene(tmp_path)), "-o", str(out), "--duration", "0.1", "--no-video"])
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in out.iterdir()) == ["energy.png", "trajectory.h5"]
    assert kinema.load_trajectory(out / "trajectory.h5").t.size == 3


def test_render_and_export_a_saved_trajectory(tmp_path):
    out = tmp_path / "o"
    assert runner.invoke(app, ["run", str(small_scene(tmp_path)), "-o", str(out), "--no-video"]).exit_code == 0
    res = runner.invoke(app, ["render", str(out / "trajectory.h5"), "-o", str(tmp_path / "m.gif"), "--width", "64", "--height", "48"])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "m.gif").read_bytes()[:3] == b"GIF"
    for fmt, main in (("csv", "t.csv"), ("xyz", "t.xyz"), ("vtk", "v.pvd"), ("ply", "p.ply")):
        res = runner.invoke(app, ["export", str(out / "trajectory.h5"), "--format", fmt, "-o", str(tmp_path / main)])
        assert res.exit_code == 0, res.output
        frames = kinema.load_trajectory(out / "trajectory.h5").t.size
        assert f"writing {fmt}" in res.stderr and f"{frames}/{frames} frames" in res.stderr  # the progress bar counted every frame
    assert (tmp_path / "t.csv").read_text().startswith("frame,time,id,x,y,z")
    assert (tmp_path / "v_vtk").is_dir() and (tmp_path / "p_ply").is_dir()  # the vtk and ply series folders


def test_a_scene_with_typos_is_exit_2_one_line_per_problem(tmp_path):
    path = small_scene(tmp_path, SMALL.replace("dt = 0.01", "dt = -1").replace("radius = 0.1", "radius = 0.1\nmas = 2"))
    res = runner.invoke(app, ["run", str(path), "-o", str(tmp_path / "o")])
    assert res.exit_code == 2
    lines = error_lines(res)
    assert len(lines) == 2, res.output
    assert f"{path}: world.dt: -1 is invalid" in lines[0]
    assert "particles[0].mas: unknown key; did you mean 'mass'?" in lines[1]
    assert "Traceback" not in res.output and not (tmp_path / "o").exists()


def test_bad_inputs_are_exit_2_with_one_line(tmp_path):
    scene = small_scene(tmp_path)
    foreign = tmp_path / "foreign.h5"
    foreign.write_bytes(b"not an hdf5 file at all")
    blocker = tmp_path / "file"
    blocker.write_text("x")
    cases = [
        (["run", str(tmp_path / "missing.toml")], "no such file"),
        (["run", str(tmp_path)], "is a directory"),
        (["run", str(scene), "-o", str(blocker)], "exists and is not a folder"),
        (["run", str(scene), "-o", str(blocker / "sub")], "cannot create the folder"),
        (["run", str(scene), "--duration", "-1"], "--duration"),
        (["render", str(tmp_path / "missing.h5"), "-o", str(tmp_path / "m.mp4")], "no such file"),
        (["render", str(foreign), "-o", str(tmp_path / "m.mp4")], "not an HDF5 file"),
        (["render", str(foreign), "-o", str(tmp_path / "m.avi")], "unsupported video format"),
        (["export", str(foreign), "--format", "csv"], "not an HDF5 file"),
        (["export", str(foreign), "--format", "obj"], "--format 'obj'"),
    ]
    for args, needle in cases:
        res = runner.invoke(app, args)
        assert res.exit_code == 2, (args, res.output)
        lines = error_lines(res)
        assert len(lines) == 1 and needle in lines[0], (args, res.output)
        assert "Traceback" not in res.output
    assert not (tmp_path / "m.mp4").exists() and not (tmp_path / "m.avi").exists()


def test_export_into_an_unwritable_place_is_exit_2(tmp_path):
    out = tmp_path / "o"
    assert runner.invoke(app, ["run", str(small_scene(tmp_path)), "-o", str(out), "--no-video"]).exit_code == 0
    blocker = tmp_path / "file"
    blocker.write_text("x")
    res = runner.invoke(app, ["export", str(out / "trajectory.h5"), "--format", "csv", "-o", str(blocker / "nowhere" / "t.csv")])
    assert res.exit_code == 2 and "cannot create the folder" in error_lines(res)[0]


DIVERGING = """
[world]
dt = 0.05
method = "euler"
duration = 20.0
fps = 20.0

[[particles]]
type = "list"
positions = [[0, 0, 0], [1, 0, 0]]
pinned = [true, false]

[[forces]]
type = "spring"
i = [0]
j = [1]
k = 10000.0
rest_length = 0.5
"""


def test_a_diverging_scene_is_exit_1_naming_the_advised_step(tmp_path):
    out = tmp_path / "o"
    res = runner.invoke(app, ["run", str(small_scene(tmp_path, DIVERGING)), "-o", str(out)])
    assert res.exit_code == 1, res.output
    lines = error_lines(res)
    assert len(lines) == 1 and "diverged" in lines[0] and "step" in lines[0], res.output
    assert "Traceback" not in res.output
    assert list(out.iterdir()) == []  # nothing written


# -- user errors are exit 2 and one line; the work is estimated before it is done -------------


def one_error_line(res):
    """The single line on stderr of a refused command (and no traceback, no 'unexpected')."""
    lines = res.stderr.strip().splitlines()
    assert res.exit_code == 2, res.output
    assert len(lines) == 1 and lines[0].startswith("error: "), res.stderr
    assert "Traceback" not in res.output and "unexpected" not in res.output
    return lines[0]


def test_values_that_overflowed_or_recursed_are_exit_2_naming_file_key_value(tmp_path):
    # each of these was an OverflowError or RecursionError (exit 1, "unexpected ...")
    cases = [
        (SMALL.replace("dt = 0.01", "dt = 1e-320"), "world.dt: 1e-320 is invalid: the time step must be a finite number of seconds >= 1e-300"),
        (SMALL.replace("dt = 0.01", 'dt = "1e-3"'), "world.dt: '1e-3' is invalid: input should be a valid number"),
        (
            SMALL + '[[forces]]\ntype = "spring"\ni = [0]\nj = [1000000000000000000000000000000]\nk = 1.0\n',
            "forces[1].j[0]: 1000000000000000000000000000000 is invalid",
        ),
        (SMALL.replace("positions = [[0, 1], [0.5, 1]]", "positions = " + "[" * 3000 + "]" * 3000), "particles[0].positions: [[[[[[[["),
    ]
    for k, (text, needle) in enumerate(cases):
        path = small_scene(tmp_path, text, name=f"bad{k}.toml")
        line = one_error_line(runner.invoke(app, ["run", str(path), "-o", str(tmp_path / "o")]))
        assert line.startswith(f"error: {path}: ") and needle in line, line
    assert not (tmp_path / "o").exists()


HUGE = """
[world]
dt = 0.001
duration = 1.0

[[particles]]
type = "random"
lo = [0, 0, 0]
hi = [1, 1, 1]
count = 1000000000
"""


def test_a_run_over_the_limits_is_refused_before_any_work(tmp_path, monkeypatch):
    from kinema.scene import Scene

    def never(*args, **kwargs):
        raise AssertionError("the scene was built: the estimate must refuse it first")

    monkeypatch.setattr(Scene, "build", never)  # were the check gone, fail here rather than allocate 22 GiB
    # a billion particles: refused at once
    path = small_scene(tmp_path, HUGE, name="huge.toml")
    line = one_error_line(runner.invoke(app, ["run", str(path), "-o", str(tmp_path / "o")]))
    # (1 s at 60 fps: 60 frames of ⌈1/(60 · 1 ms)⌉ = 17 steps)
    assert line.startswith(f"error: {path}: the run would take 1.0e+12 particle-steps (1,000,000,000 particles × 1,020 steps: ")
    assert "world.duration = 1 s at world.dt = 0.001 s; particles[0].count = 1000000000" in line
    assert "over the limits of 1e+11 particle-steps, 1e+11 pixels and 8.0 GiB of memory; give --force to run it anyway" in line
    assert "TiB of memory" in line
    # ten particles for a billion seconds
    path = small_scene(tmp_path, HUGE.replace("count = 1000000000", "count = 10").replace("duration = 1.0", "duration = 1e9"), name="long.toml")
    line = one_error_line(runner.invoke(app, ["run", str(path), "-o", str(tmp_path / "o"), "--no-video"]))
    assert "1.0e+13 particle-steps (10 particles × 1,020,000,000,000 steps: world.duration = 1e+09 s at world.dt = 0.001 s" in line
    # --duration names itself; more steps than can be counted are refused even with --force
    line = one_error_line(runner.invoke(app, ["run", str(small_scene(tmp_path)), "--duration", "1e300", "--force", "-o", str(tmp_path / "o")]))
    assert "the run would take 1.0e+302 steps (--duration = 1e+300 s at world.dt = 0.01 s), more than can be counted (1e+18), even with --force" in line
    assert not (tmp_path / "o").exists()


def test_an_estimate_of_countless_births_prints_no_long_numbers(tmp_path):
    # an emitter at its highest rate for a billion seconds: 10²⁴ births, printed with all 25
    # digits twice (999,999,999,999,999,983,222,785: float digits), and 15 digits of PiB
    scene = small_scene(
        tmp_path,
        "[world]\ndim = 3\ndt = 1e7\nduration = 1e9\nfps = 1e-6\n\n[[emitters]]\nrate = 1e15\nspeed = 1.0\nparticle_radius = 0.01\n",
        name="flood.toml",
    )
    line = one_error_line(runner.invoke(app, ["run", str(scene), "-o", str(tmp_path / "o")]))
    assert "(1e+24 particles × 1,000 steps: " in line and "; up to 1e+24 particles from 1 emitter)" in line, line
    assert "about 1.16e+14 PiB of memory" in line and max(len(w) for w in line.split(str(scene))[1].split()) < 25, line


def test_force_runs_what_the_limits_refuse(tmp_path, monkeypatch):
    import kinema.runner

    monkeypatch.setattr(kinema.runner, "LIMIT_PARTICLE_STEPS", 10.0)
    scene = small_scene(tmp_path)
    line = one_error_line(runner.invoke(app, ["run", str(scene), "-o", str(tmp_path / "o"), "--no-video"]))
    assert "6.0e+01 particle-steps (2 particles × 30 steps: world.duration = 0.3 s at world.dt = 0.01 s; 2 particles[0].positions)" in line
    assert "over the limits of 1e+01 particle-steps" in line and not (tmp_path / "o").exists()
    res = runner.invoke(app, ["run", str(scene), "-o", str(tmp_path / "o"), "--no-video", "--force"])
    assert res.exit_code == 0, res.output
    assert "work: 6.0e+01 particle-steps" in res.stdout  # the estimate is printed
    assert (tmp_path / "o" / "trajectory.h5").exists()
    # view simulates a scene too
    res = runner.invoke(app, ["view", str(scene), "--html", str(tmp_path / "v.html")])
    assert "give --force" in one_error_line(res) and not (tmp_path / "v.html").exists()


def test_render_over_the_pixel_limit_is_refused_unless_forced(tmp_path, monkeypatch):
    import kinema.runner

    out = tmp_path / "o"
    assert runner.invoke(app, ["run", str(small_scene(tmp_path)), "-o", str(out), "--no-video"]).exit_code == 0
    monkeypatch.setattr(kinema.runner, "LIMIT_PIXELS", 1e4)
    args = ["render", str(out / "trajectory.h5"), "-o", str(tmp_path / "m.gif"), "--width", "64", "--height", "48"]
    line = one_error_line(runner.invoke(app, args))
    assert line.startswith(f"error: {out / 'trajectory.h5'}: rendering would take 2.2e+04 pixels (7 frames × --width 64 × --height 48)"), line
    assert "give --force" in line and not (tmp_path / "m.gif").exists()
    res = runner.invoke(app, [*args, "--force"])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "m.gif").read_bytes()[:3] == b"GIF"


def test_every_example_scene_is_within_the_limits():
    from pathlib import Path

    from kinema.runner import _scene_work
    from kinema.scene import Scene

    scenes = sorted((Path(__file__).resolve().parent.parent / "examples" / "scenes").glob("*.toml"))
    assert len(scenes) >= 10
    for path in scenes:
        sc = Scene.from_toml(path)
        assert "particle-steps" in _scene_work(sc, path, sc.world.duration, "world.duration", True, force=False)


def test_stale_staging_folders_of_killed_runs_are_removed(tmp_path):
    from kinema.io._files import host_name as _host

    out = tmp_path / "o"
    out.mkdir()
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True, check=True)
    dead = int(gone.stdout)  # a process that has exited
    stale = out / f".kinema-run.{_host()}-{dead}.abc123"
    (stale / "sub").mkdir(parents=True)
    (stale / "trajectory.h5").write_bytes(b"half written")
    alive = out / f".kinema-run.{_host()}-{os.getppid()}.def456"  # a run still going
    elsewhere = out / f".kinema-run.otherhost-{dead}.ghi789"  # another machine's: cannot tell
    old_style = out / ".kinema-run.jkl012"  # no pid: removed once a day old
    recent_style = out / ".kinema-run.mno345"
    for d in (alive, elsewhere, old_style, recent_style):
        d.mkdir()
    day_ago = time.time() - 2 * 86400
    os.utime(old_style, (day_ago, day_ago))
    (out / ".kinema-run.notes").write_text("a file, not a staging folder")
    res = runner.invoke(app, ["run", str(small_scene(tmp_path)), "-o", str(out), "--no-video"])
    assert res.exit_code == 0, res.output
    left = sorted(p.name for p in out.iterdir())
    assert left == sorted([alive.name, elsewhere.name, recent_style.name, ".kinema-run.notes", "energy.png", "trajectory.h5"]), left


def test_a_run_stages_in_a_folder_named_by_its_process(tmp_path, monkeypatch):
    import tempfile

    import kinema.runner

    made = []
    real = tempfile.mkdtemp

    def spy(*args, **kwargs):
        made.append(real(*args, **kwargs))
        return made[-1]

    monkeypatch.setattr(kinema.runner.tempfile, "mkdtemp", spy)
    res = runner.invoke(app, ["run", str(small_scene(tmp_path)), "-o", str(tmp_path / "o"), "--no-video"])
    assert res.exit_code == 0, res.output
    assert len(made) == 1 and os.path.basename(made[0]).startswith(f".kinema-run.{kinema.io._files.host_name()}-{os.getpid()}.")
    assert not os.path.exists(made[0])  # removed at the end


def test_view_opens_a_scene_in_its_own_colouring(tmp_path):
    # [render] color_by of the scene is the page's first colouring; a trajectory file opens by
    # speed, the viewer's default
    scene = small_scene(tmp_path, SMALL.replace("[render]", '[render]\ncolor_by = "id"'))
    res = runner.invoke(app, ["view", str(scene), "--html", str(tmp_path / "v.html")])
    assert res.exit_code == 0, res.output
    assert '"colorBy":"id"' in (tmp_path / "v.html").read_text()
    assert runner.invoke(app, ["run", str(small_scene(tmp_path)), "-o", str(tmp_path / "o"), "--no-video"]).exit_code == 0
    res = runner.invoke(app, ["view", str(tmp_path / "o" / "trajectory.h5"), "--html", str(tmp_path / "t.html")])
    assert res.exit_code == 0, res.output
    assert '"colorBy":"id"' not in (tmp_path / "t.html").read_text()


BOUNCE = """
[world]
dim = 3
dt = 0.001
duration = 3.0
fps = 10.0

[[particles]]
type = "list"
positions = [[0, 0, 1.1]]
radius = 0.1

[[forces]]
type = "gravity"

[[colliders]]
type = "plane"
point = [0, 0, 0]
normal = [0, 0, 1]

[collisions]
restitution = 0.8
{extra}
[output]
video = false
plot = false
contact_events = true
"""


def test_run_writes_the_contact_events_that_numpy_reads_at_the_closed_form_times(tmp_path):
    # A ball dropped from 1 m (its lowest point) onto a floor with e = 0.8: its k-th impact
    # comes at t₁ + Σ 2 eᵐ v₁/g (t₁ = √(2H/g), v₁ = g t₁), each a begin at its impact time
    # and an end at the end of that step (tests/test_contact_events.py for the API).
    import math

    import numpy as np

    out = tmp_path / "out"
    res = runner.invoke(app, ["run", str(small_scene(tmp_path, BOUNCE.format(extra=""), "bounce.toml")), "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert sorted(p.name for p in out.iterdir()) == ["contact_events.csv", "trajectory.h5"]
    ev = np.genfromtxt(out / "contact_events.csv", delimiter=",", names=True)
    assert ev.dtype.names == ("time", "begin", "i", "j", "collider", "impulse")
    g, e = 9.81, 0.8
    v1 = math.sqrt(2 * g * 1.0)
    times = [v1 / g + sum(2 * e ** (m + 1) * v1 / g for m in range(k)) for k in range(4)]
    begins = ev[ev["begin"] == 1]
    np.testing.assert_allclose(begins["time"][:4], times, rtol=0, atol=1e-9)
    np.testing.assert_allclose(begins["impulse"][:4], [(1 + e) * v1 * e**k for k in range(4)], rtol=1e-9)
    assert (ev["i"] == 0).all() and (ev["j"] == -1).all() and (ev["collider"] == 0).all()


def test_run_refuses_contact_events_it_cannot_record(tmp_path):
    force = BOUNCE.format(extra='model = "spring_dashpot"\nstiffness = 1e4\n')
    res = runner.invoke(app, ["run", str(small_scene(tmp_path, force, "force.toml")), "-o", str(tmp_path / "a")])
    assert res.exit_code != 0
    assert "[output] contact_events = true: record_contact_events = True is invalid" in res.output.replace("\n", " ")
    plain = small_scene(tmp_path, BOUNCE.format(extra=""), "plain.toml")
    res = runner.invoke(app, ["run", str(plain), "-o", str(tmp_path / "b"), "--checkpoint-every", "0.5"])
    assert res.exit_code != 0 and "checkpoint does not keep them" in res.output.replace("\n", " ")


SUMMARY = """
[world]
dim = 3
dt = 0.0005
duration = 1.5
fps = 10.0

[[particles]]
type = "list"
positions = [[0, 0, 1.1]]
velocity = [0, 0, {v}]
radius = 0.1
mass = 1.0
{gravity}
[[colliders]]
type = "plane"
point = [0, 0, 0]
normal = [0, 0, 1]

[collisions]
restitution = 0.8
{extra}
[output]
video = false
plot = false
"""


@pytest.mark.parametrize(
    ("extra", "said"),
    [
        ("", "2 impacts inside steps, "),
        ('model = "spring_dashpot"\nstiffness = 1e5\n', "2 contacts begun, "),
        ("event_driven = true\n", "1 impact, "),
    ],
)
def test_the_run_summary_counts_what_each_model_has(tmp_path, extra, said):
    # A ball dropped from 1 m onto a floor with e = 0.8 meets it at t₁ = √(2/g) = 0.452 s and
    # again 2 e v₁/g = 0.723 s later, at 1.174 s: two impacts by 1.5 s with the impulse model,
    # two contacts begun with a spring–dashpot (t_c = π/√(k/m) = 9.9 ms, 20 steps); the
    # event-driven model has no forces, so the ball is thrown at the floor at 1 m/s from
    # 1 m and leaves it once, one impact.
    driven = "event_driven" in extra
    scene = SUMMARY.format(v=-1.0 if driven else 0.0, gravity="" if driven else '\n[[forces]]\ntype = "gravity"\n', extra=extra)
    res = runner.invoke(app, ["run", str(small_scene(tmp_path, scene, "summary.toml")), "-o", str(tmp_path / "out")])
    assert res.exit_code == 0, res.output
    assert said in res.output, res.output


KEPT = """
[world]
dim = 3
dt = 2e-5
duration = 0.05
fps = 100.0
spin = true

[[particles]]
type = "list"
positions = [[0, 0, 0.00995], [0.05, 0, 0.00995], [0.1, 0, 0.02995]]
velocity = [[1.0, 0, 0], [-0.5, 0.2, 0], [0, 0, 0]]
angular_velocity = [[0, 0, 30.0], [0, -20.0, 0], [5.0, 0, 0]]
radius = 0.01
mass = 0.01

[[forces]]
type = "gravity"

[[colliders]]
type = "plane"
point = [0, 0, 0]
normal = [0, 0, 1]

[collisions]
model = "hertz"
youngs_modulus = 1e7
poisson_ratio = 0.3
restitution = 0.5
friction = 0.4

[output]
video = false
plot = false
"""


def test_run_keeps_its_world_and_the_kept_world_goes_on_bit_for_bit(tmp_path):
    # Balls sliding and spinning on a floor under Hertz + Mindlin: at the run's end the contacts
    # hold tangential springs. `kinema run --keep-checkpoint` writes that world; read back and
    # stepped on, it is the uninterrupted run's world to every bit (positions, velocities and
    # spins): the springs' memory and Verlet's angular accelerations came back with it.
    import numpy as np

    from kinema.scene import Scene

    path = small_scene(tmp_path, KEPT, "kept.toml")
    kept = tmp_path / "keep" / "final.ckpt"
    res = runner.invoke(app, ["run", str(path), "-o", str(tmp_path / "out"), "--keep-checkpoint", str(kept)])
    assert res.exit_code == 0, res.output
    assert str(kept) in res.output.replace("\n", "")
    again = kinema.World.load_checkpoint(kept)
    pairs, walls = again._core.contact_history()
    assert len(walls) == 2 and all(any(spring[3]) for spring in walls)  # the two on the floor: stretched springs
    whole = Scene.from_toml(path).build()
    whole.run(0.05, fps=100.0)
    assert again.time == whole.time and np.array_equal(again.angular_velocities, whole.angular_velocities)
    for w in (again, whole):
        w.step(2000)
    assert np.array_equal(again.positions, whole.positions)
    assert np.array_equal(again.velocities, whole.velocities)
    assert np.array_equal(again.angular_velocities, whole.angular_velocities)
    assert not np.array_equal(again.angular_velocities[0], [0, 0, 30.0])  # friction turned them
    # a folder given as the file is refused before the run, naming the option
    bad = runner.invoke(app, ["run", str(path), "-o", str(tmp_path / "o2"), "--keep-checkpoint", str(tmp_path)])
    assert bad.exit_code == 2 and "--keep-checkpoint" in bad.output and "is a folder" in bad.output
    assert not (tmp_path / "o2").exists()
