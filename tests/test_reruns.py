"""Runs, resumes and sweeps run again into the same folder (issue 49): a finished run leaves no
checkpoint that a later --resume would put in place of its files, --resume refuses a
checkpoint of another scene or duration, a sweep's failed members are run again, and every
failure or warning is one line."""

import os
import shutil
import socket

import pytest
from typer.testing import CliRunner

import kinema
from kinema.cli import app

runner = CliRunner()

BALL = """
[world]
dim = 2
dt = 0.01
duration = 0.6
fps = 20.0

[[particles]]
type = "list"
positions = [[0, 1]]
velocity = [0, 0]
radius = 0.05

[[forces]]
type = "gravity"

[[colliders]]
type = "plane"
point = [0, 0]
normal = [0, 1]

[output]
video = false
plot = false
"""


def one_error_line(res):
    """The single line on stderr of a refused command (and no traceback, no 'unexpected')."""
    lines = res.stderr.strip().splitlines()
    assert res.exit_code == 2, res.output
    assert len(lines) == 1 and lines[0].startswith("error: "), res.stderr
    assert "Traceback" not in res.output and "unexpected" not in res.output
    return lines[0]


def _stopped_run(monkeypatch, scene, out, *extra):
    """`kinema run scene --checkpoint-every 0.1` stopped (Ctrl-C) just after its first
    checkpoint: exit 130, the checkpoint left in ``out``."""
    import kinema.checkpoint

    save = kinema.checkpoint.save_checkpoint

    def save_then_stop(*args, **kwargs):
        save(*args, **kwargs)
        raise KeyboardInterrupt

    with monkeypatch.context() as m:
        m.setattr(kinema.checkpoint, "save_checkpoint", save_then_stop)
        res = runner.invoke(app, ["run", str(scene), "--checkpoint-every", "0.1", "-o", str(out), *extra])
    assert res.exit_code == 130, res.output
    assert (out / "checkpoint.ckpt").is_file()


def test_a_whole_run_removes_the_checkpoints_an_older_run_left(tmp_path, monkeypatch):
    # kill -9 left the old scene's checkpoint and a staging file of it; the edited scene's
    # whole run (no checkpoints) must not leave them for a later --resume to put back
    scene = tmp_path / "ball.toml"
    scene.write_text(BALL)
    out = tmp_path / "out"
    _stopped_run(monkeypatch, scene, out)
    staging = out / f".checkpoint.ckpt.{socket.gethostname()}-999999999.0123abcd.part"  # its writer long gone
    staging.write_bytes(b"half a checkpoint")
    scene.write_text(BALL.replace("velocity = [0, 0]", "velocity = [0, 4]"))  # thrown up: apex near 0.9 m
    res = runner.invoke(app, ["run", str(scene), "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert not (out / "checkpoint.ckpt").exists() and not staging.exists()
    assert sorted(p.name for p in out.iterdir()) == ["trajectory.h5"]
    apex = kinema.load_trajectory(out / "trajectory.h5").positions[:, 0, 1].max()
    assert apex > 0.8
    # and --resume has nothing to put in place of the new trajectory
    line = one_error_line(runner.invoke(app, ["run", str(scene), "--resume", "-o", str(out)]))
    assert "no checkpoint to resume" in line
    assert kinema.load_trajectory(out / "trajectory.h5").positions[:, 0, 1].max() == apex


def test_resume_refuses_a_checkpoint_of_another_scene(tmp_path, monkeypatch):
    scene = tmp_path / "ball.toml"
    scene.write_text(BALL)
    out = tmp_path / "out"
    _stopped_run(monkeypatch, scene, out)
    other = tmp_path / "cradle.toml"
    other.write_text(BALL.replace("positions = [[0, 1]]", "positions = [[0, 2]]"))
    line = one_error_line(runner.invoke(app, ["run", str(other), "--resume", "-o", str(out)]))
    assert f"{out / 'checkpoint.ckpt'} was written by a run of the scene {scene}" in line and f"{other} differs from it" in line, line
    assert (out / "checkpoint.ckpt").is_file() and not (out / "trajectory.h5").exists()
    # the same scene edited in place is another scene too
    scene.write_text(BALL.replace("radius = 0.05", "radius = 0.06"))
    line = one_error_line(runner.invoke(app, ["run", str(scene), "--resume", "-o", str(out)]))
    assert "differs from it" in line
    # the same content in another file, written another way, is the same scene
    same = tmp_path / "copy.toml"
    same.write_text("# a comment\n" + BALL.replace("duration = 0.6", "duration = 0.60"))
    res = runner.invoke(app, ["run", str(same), "--resume", "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert "resuming" in res.output and not (out / "checkpoint.ckpt").exists()


def test_resume_refuses_another_duration_and_goes_on_to_the_runs_own(tmp_path, monkeypatch):
    scene = tmp_path / "ball.toml"
    scene.write_text(BALL)
    out = tmp_path / "out"
    _stopped_run(monkeypatch, scene, out, "--duration", "0.4")
    line = one_error_line(runner.invoke(app, ["run", str(scene), "--resume", "--duration", "5", "-o", str(out)]))
    assert "--duration 5 s differs from the 0.4 s of the run that wrote" in line and "checkpoint.ckpt" in line, line
    assert (out / "checkpoint.ckpt").is_file()
    # without --duration: the run's own 0.4 s, not the scene's 0.6 s
    res = runner.invoke(app, ["run", str(scene), "--resume", "-o", str(out)])
    assert res.exit_code == 0, res.output
    t = kinema.load_trajectory(out / "trajectory.h5").t
    assert t[-1] == pytest.approx(0.4) and len(t) == 9


def test_a_whole_run_keeps_the_checkpoint_it_was_asked_to_keep_there(tmp_path):
    scene = tmp_path / "ball.toml"
    scene.write_text(BALL)
    out = tmp_path / "out"
    res = runner.invoke(app, ["run", str(scene), "-o", str(out), "--keep-checkpoint", str(out / "checkpoint.ckpt")])
    assert res.exit_code == 0, res.output
    assert (out / "checkpoint.ckpt").is_file()
    assert os.path.getsize(out / "checkpoint.ckpt") > 0


# -- every error one line, every warning one line ---------------------------------------------


def test_a_nan_or_infinite_corner_of_a_random_block_is_one_line_naming_it(tmp_path):
    # (numpy's "unexpected OverflowError: Range exceeds valid bounds", exit 1)
    base = BALL.replace('type = "list"\npositions = [[0, 1]]\nvelocity = [0, 0]', 'type = "random"\nlo = [0, 0.5]\nhi = [1, 1]\ncount = 3\nseed = 1')
    assert 'type = "random"' in base
    for corner, value in (("lo = [0, nan]", "[0, nan]"), ("lo = [0, -inf]", "[0, -inf]")):
        scene = tmp_path / "nan.toml"
        scene.write_text(base.replace("lo = [0, 0.5]", corner))
        line = one_error_line(runner.invoke(app, ["run", str(scene), "-o", str(tmp_path / "o")]))
        assert f"particles[0].lo: {value} is invalid: each coordinate of a corner of the box must be a finite number of metres" in line, line
    scene.write_text(base.replace("lo = [0, 0.5]", "lo = [-1e308, 0]").replace("hi = [1, 1]", "hi = [1e308, 1]"))
    line = one_error_line(runner.invoke(app, ["run", str(scene), "-o", str(tmp_path / "o")]))
    assert "hi - lo must be finite" in line, line
    assert not (tmp_path / "o").exists()


def test_an_emitter_rate_too_large_to_count_is_one_line_in_run_and_view(tmp_path):
    scene = tmp_path / "jet.toml"
    scene.write_text(BALL + "\n[[emitters]]\nrate = 1e308\nspeed = 1.0\nparticle_radius = 0.01\n")
    for command in (["run", str(scene), "-o", str(tmp_path / "o")], ["view", str(scene), "--html", str(tmp_path / "v.html")]):
        line = one_error_line(runner.invoke(app, command))
        assert line == f"error: {scene}: emitters[0].rate: 1e+308 is invalid: the rate must be a number of particles a second > 0 and <= 1e+15", line


def test_view_on_a_port_in_use_is_one_line_naming_the_port(tmp_path):
    # (the server's state was made after binding, which failed: "unexpected AttributeError: ... '_selector'")
    scene = tmp_path / "ball.toml"
    scene.write_text(BALL)
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        res = runner.invoke(app, ["view", str(scene), "--port", str(port), "--no-browser"])
    assert res.exit_code == 2 and "Traceback" not in res.output and "unexpected" not in res.output, res.output
    errors = [line for line in res.stderr.splitlines() if line.startswith("error")]
    assert len(errors) == 1, res.stderr
    line = errors[0]
    assert line.startswith(f"error: --port {port}: cannot listen on 127.0.0.1:{port} (") and "in use" in line, line
    # refused before the scene is simulated (it was simulated whole first, then refused)
    assert "simulating" not in res.output, res.output


def test_view_prints_a_warning_as_one_line_without_its_source(tmp_path):
    import subprocess
    import sys

    scene = tmp_path / "overlap.toml"
    scene.write_text(BALL.replace("positions = [[0, 1]]", "positions = [[0, 1], [0.05, 1]]").replace("velocity = [0, 0]", "velocity = [0, 0]\nmass = 1.0"))
    res = subprocess.run([sys.executable, "-m", "kinema", "view", str(scene), "--html", str(tmp_path / "v.html")], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    said = [line for line in res.stderr.splitlines() if "overlap" in line]
    assert len(said) == 1 and said[0].startswith("warning: 1 overlap at the start"), res.stderr
    assert ".py:" not in res.stderr and "PlacementWarning" not in res.stderr and "self._" not in res.stderr, res.stderr


# -- sweeps run again ------------------------------------------------------------------------


def _full_disk_once(monkeypatch):
    """Trajectory.save fails once as on a full disk (ENOSPC), then writes again."""
    import errno

    from kinema.trajectory import Trajectory

    save = Trajectory.save
    calls = []

    def save_on_a_full_disk(self, path, *args, **kwargs):
        calls.append(path)
        if len(calls) == 1:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        return save(self, path, *args, **kwargs)

    monkeypatch.setattr(Trajectory, "save", save_on_a_full_disk)
    return calls


def test_a_sweep_member_that_failed_on_a_full_disk_is_run_again(tmp_path, monkeypatch):
    scene = tmp_path / "ball.toml"
    scene.write_text(BALL)
    out = tmp_path / "s"
    calls = _full_disk_once(monkeypatch)
    res = runner.invoke(app, ["sweep", str(scene), "-o", str(out)])
    assert res.exit_code == 1, res.output
    assert "1 members, 1 failed" in res.stdout
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("failed: ") and "OSError" in lines[0] and "No space left on device" in lines[0], res.stderr
    assert "Traceback" not in res.output
    # the space freed, the rerun runs it (it reported the old error and skipped it)
    again = runner.invoke(app, ["sweep", str(scene), "-o", str(out)])
    assert again.exit_code == 0, again.output
    assert "1 members, 0 failed" in again.stdout and len(calls) == 2
    # and the next rerun skips it, finished
    third = runner.invoke(app, ["sweep", str(scene), "-o", str(out)])
    assert third.exit_code == 0 and len(calls) == 2


def test_a_sweep_stopped_by_ctrl_c_says_which_members_were_written(tmp_path, monkeypatch):
    import kinema.sweeps

    scene = tmp_path / "ball.toml"
    scene.write_text(BALL)
    out = tmp_path / "s"

    def one_then_ctrl_c(todo, folder, duration, measure, client, workers, progress, checkpoint_every, keys):
        m = todo[0]
        kinema.sweeps.run_member(m, str(folder), duration, measure, checkpoint_every, keys[m.index])
        raise KeyboardInterrupt

    monkeypatch.setattr(kinema.sweeps, "_run_all", one_then_ctrl_c)
    res = runner.invoke(app, ["sweep", str(scene), "--vary", "world.dt=0.01,0.005,0.0025", "-o", str(out)])
    assert res.exit_code == 130, res.output
    lines = res.stderr.strip().splitlines()
    first = kinema.sweeps.members(str(scene), {"world.dt": [0.01, 0.005, 0.0025]})[0].name
    assert len(lines) == 1 and lines[0].startswith(f"error: interrupted; 1 of 3 members were written in {out / 'members'} ({first})"), res.stderr
    assert "nothing was written" not in res.output and f"again into {out}" in lines[0]
    assert (out / "members" / first / "trajectory.h5").is_file()
    # stopped before any member finished
    shutil.rmtree(out)

    def ctrl_c(*args):
        raise KeyboardInterrupt

    monkeypatch.setattr(kinema.sweeps, "_run_all", ctrl_c)
    res = runner.invoke(app, ["sweep", str(scene), "--vary", "world.dt=0.01,0.005", "-o", str(out)])
    assert res.exit_code == 130 and "no member had finished: nothing was written" in res.stderr, res.output
