"""The `kinema` command: exit codes, messages, files written."""

import subprocess
import sys

from typer.testing import CliRunner

from kinema.cli import app

runner = CliRunner()


def test_stability_writes_the_png_and_prints_the_intervals(tmp_path):
    out = tmp_path / "sub" / "regions.png"
    res = runner.invoke(app, ["stability", "--methods", "euler,midpoint,rk4,implicit_euler", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "-2.7853" in res.output and "2.8284" in res.output
    assert [p.name for p in out.parent.iterdir()] == ["regions.png"]  # no temporary left behind


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
    for name in ("phase_portraits.png", "stability_regions.png", "convergence.png"):
        assert (tmp_path / name).stat().st_size > 10_000
        assert str(tmp_path / name) in res.output.replace("\n", "")


def test_python_dash_m_kinema_is_the_same_command():
    res = subprocess.run([sys.executable, "-m", "kinema", "--help"], capture_output=True, text=True, check=True)
    assert "stability" in res.stdout and "demo" in res.stdout
