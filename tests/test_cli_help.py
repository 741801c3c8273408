"""The `kinema` command's help and version: what a new user types first."""

import re

import pytest
from typer.testing import CliRunner

import kinema
from kinema.cli import app

runner = CliRunner()
COMMANDS = ["methods", "stability", "demo", "run", "render", "export", "view"]


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
