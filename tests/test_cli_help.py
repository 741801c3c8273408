"""The `kinema` command's help and version: what a new user types first."""

import re

import pytest
from typer.testing import CliRunner

import kinema
from kinema.cli import app

runner = CliRunner()
COMMANDS = ["methods", "stability", "demo", "run", "render", "export", "sweep", "analyze", "view"]


@pytest.mark.parametrize("flag", ["--version", "-V"])
def test_version_prints_the_package_version(flag):
    res = runner.invoke(app, [flag])
    assert res.exit_code == 0, res.output
    assert res.output.strip() == f"kinema {kinema.__version__}"
    assert re.fullmatch(r"\d+\.\d+\.\d+\S*", kinema.__version__)


@pytest.mark.parametrize("args", [[], *([c] for c in COMMANDS)], ids=["kinema", *COMMANDS])
def test_dash_h_is_help_and_flags_show_no_metavar(args):
    # -h as --help everywhere; flags take no value, so none is shown beside them (typer 0.29's
    # rich help printed "<bool>" beside every flag, --help included)
    short, long = runner.invoke(app, [*args, "-h"]), runner.invoke(app, [*args, "--help"])
    assert short.exit_code == 0 and short.output == long.output, short.output
    assert "Usage: kinema" in short.output and "-h, --help" in short.output
    assert "<bool>" not in short.output and "BOOLEAN" not in short.output


def test_demo_help_says_what_the_demo_writes():
    text = runner.invoke(app, ["demo", "-h"]).output
    for name in ("phase_portraits.png", "stability_regions.png", "convergence.png", "demo.mp4", "demo.html"):
        assert name in text, text


def test_the_command_list_says_each_command_whole_in_80_columns():
    # click cuts a command's description at 45 characters with "..." unless it has a short
    # help: every one of the 9 has its own, whole on one line of an 80-column terminal.
    res = runner.invoke(app, ["-h"], terminal_width=80, env={"COLUMNS": "80"})
    listed = res.output.split("Commands:")[1].strip().splitlines()
    assert [line.split()[0] for line in listed] == COMMANDS, listed
    assert all(len(line) <= 80 and not line.rstrip().endswith(("...", "…")) for line in listed), listed


def test_sweep_help_names_its_values_not_their_types():
    # the values a user types (KEY=V1,V2,..., N, K), not typer's "<list[str]>" or "<int range>"
    res = runner.invoke(app, ["sweep", "-h"])
    assert "--vary KEY=V1,V2,..." in res.output and "--seeds N" in res.output and "--workers K" in res.output, res.output
    assert "<list[str]>" not in res.output and "range>" not in res.output, res.output


def test_methods_fits_an_80_column_terminal_and_a_wide_one_gets_the_table():
    # 80 columns: two lines per method, the summary whole on its own line; wider: the table
    narrow = runner.invoke(app, ["methods"], env={"COLUMNS": "80"}).output.splitlines()
    assert all(len(line) <= 80 for line in narrow), narrow
    for m in kinema.methods():
        assert f"    {m.summary}" in narrow and any(line.startswith(f"{m.name}  order {m.order}") for line in narrow), m.name
    wide = runner.invoke(app, ["methods"], env={"COLUMNS": "200"}).output
    assert "f evals/step" in wide and all(m.summary in wide for m in kinema.methods())


@pytest.mark.parametrize(("asked", "meant"), [("RK4", "rk4"), ("forward_euler", "euler"), ("backward_euler", "implicit_euler"), ("leapfrog", "verlet")])
def test_a_lecture_name_of_a_method_is_told_the_registered_one(asked, meant, tmp_path):
    # The lecture's and the textbooks' names: "did you mean" in the API's error, a scene's,
    # and the command line's (one suggestion, Method::suggestion, for all three).
    with pytest.raises(ValueError, match=f"unknown method '{asked}'; did you mean '{meant}'\\? valid methods are: euler"):
        kinema.solve(lambda t, y: -y, [1.0], (0, 1), h=0.1, method=asked)
    scene = tmp_path / "s.toml"
    scene.write_text(f'[world]\nmethod = "{asked}"\n\n[[particles]]\ntype = "list"\npositions = [[0, 0, 0]]\n')
    with pytest.raises(kinema.SceneError, match=f"world.method: .* did you mean '{meant}'\\? valid methods are"):
        kinema.Scene.from_toml(scene)
    res = runner.invoke(app, ["stability", "--methods", asked, "--out", str(tmp_path / "r.png")])
    assert res.exit_code != 0 and f"did you mean '{meant}'?" in res.output, res.output
