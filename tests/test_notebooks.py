"""The lecture notes as notebooks (examples/notebooks/): one per part of the notes, each run
top to bottom by a real kernel (nbclient), as a student would run it.

Each notebook checks its own claims against closed forms with ``assert`` (Euler by hand
against kinema's, measured orders against the declared ones, the largest stable step
2/|λ| and 2.785/|λ|, momentum kept by action and reaction, free fall exact under Verlet,
the two-ball collision, the cradle, a bouncing ball at rest by t₀ (1 + e)/(1 − e)), so a
notebook whose numbers drift fails here. Each ends with the viewer inline
(``Trajectory.show()``)."""

from __future__ import annotations

import ast
import json
import re
from pathlib import Path

import pytest

NOTEBOOKS = Path(__file__).resolve().parent.parent / "examples" / "notebooks"
PARTS = ["01_ode_methods", "02_stability", "03_particles_and_newton", "04_collisions"]


def test_there_is_one_notebook_per_part_of_the_lecture_notes():
    assert sorted(p.stem for p in NOTEBOOKS.glob("*.ipynb")) == PARTS


@pytest.mark.parametrize("name", PARTS)
def test_the_notebook_runs_and_its_checks_hold(name, tmp_path, jupyter_kernel):
    import nbclient
    import nbformat

    book = nbformat.read(NOTEBOOKS / f"{name}.ipynb", as_version=4)
    assert all(not c.get("outputs") for c in book.cells if c.cell_type == "code"), "commit the notebook without outputs"
    checks = sum(c.source.count("assert ") for c in book.cells if c.cell_type == "code")
    assert checks >= 2, f"{name} checks {checks} claims"
    try:
        nbclient.NotebookClient(book, timeout=300, kernel_name=jupyter_kernel, resources={"metadata": {"path": str(tmp_path)}}).execute()
    except nbclient.exceptions.CellExecutionError as e:
        pytest.fail(f"{name}.ipynb: a cell failed:\n{str(e)[-3000:]}", pytrace=False)
    outputs = [o for c in book.cells if c.cell_type == "code" for o in c.outputs]
    printed = [o["data"].get("text/plain", "") for o in outputs if o["output_type"] == "execute_result"]
    assert not [p for p in printed if re.match(r"\[?<?(Text|Line2D|matplotlib)", p)], f"{name}: a plot call's value is printed: {printed}"
    html = [o["data"]["text/html"] for o in outputs if o["output_type"] in ("execute_result", "display_data") and "text/html" in o["data"]]
    assert any(h.startswith("<div><iframe srcdoc=") for h in html), f"{name}: no inline viewer"
    streams = "".join(o.get("text", "") for o in outputs if o["output_type"] == "stream" and o.get("name") == "stderr")
    assert "Warning" not in streams, streams


# -- what a reader sees (issue 48), checked without a kernel ----------------------------------

# the matplotlib calls whose value Jupyter would print under the cell (`Text(0.5, 1.0, '...')`)
ARTIST_CALLS = {
    "set_title",
    "set_xlabel",
    "set_ylabel",
    "suptitle",
    "legend",
    "plot",
    "loglog",
    "semilogy",
    "semilogx",
    "text",
    "annotate",
    "axhline",
    "axvline",
    "imshow",
    "hist",
    "scatter",
    "contour",
    "contourf",
}


def _cells(name: str) -> list[dict]:
    return json.loads((NOTEBOOKS / f"{name}.ipynb").read_text(encoding="utf-8"))["cells"]


def _source(cell: dict) -> str:
    return "".join(cell["source"])


@pytest.mark.parametrize("name", PARTS)
def test_no_cell_ends_in_a_plot_call_whose_value_jupyter_prints(name):
    for k, cell in enumerate(c for c in _cells(name) if c["cell_type"] == "code"):
        text = _source(cell).rstrip()
        body = ast.parse(text).body
        last = body[-1] if body else None
        if isinstance(last, ast.Expr) and isinstance(last.value, ast.Call) and isinstance(last.value.func, ast.Attribute):
            called = last.value.func.attr
            assert called not in ARTIST_CALLS or text.endswith(";"), (
                f"{name}, code cell {k}: ends in .{called}(...), whose value Jupyter prints; end it with ';'"
            )


def _strings_in_plot_calls(text: str) -> list[str]:
    out = []
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in ARTIST_CALLS | {"set"}:
            values = [*node.args, *(kw.value for kw in node.keywords)]
            out += [v.value for v in values if isinstance(v, ast.Constant) and isinstance(v.value, str)]
            out += [part.value for v in values if isinstance(v, ast.JoinedStr) for part in v.values if isinstance(part, ast.Constant)]
    return out


@pytest.mark.parametrize("name", PARTS)
def test_tex_in_plot_labels_is_mathtext(name):
    """`e^{−1}` outside $...$ is printed as typed; inside, matplotlib sets it as a power."""
    for cell in (c for c in _cells(name) if c["cell_type"] == "code"):
        for label in _strings_in_plot_calls(_source(cell)):
            outside = re.sub(r"\$[^$]*\$", "", label)
            assert not re.search(r"[\^_]\{|\\[a-z]+", outside), f"{name}: label {label!r} has TeX outside $...$"


@pytest.mark.parametrize("name", PARTS)
def test_the_notes_are_quoted_not_linked_to_a_path_outside_the_repository(name):
    markdown = "\n".join(_source(c) for c in _cells(name) if c["cell_type"] == "markdown")
    assert not re.search(r"\bseed\b", markdown, re.IGNORECASE), f"{name} speaks of the seed; it is 'the lecture notes'"
    for target in re.findall(r"\]\(([^)#\s]+)", markdown) + re.findall(r"`(\.\.?/[^`]+)`", markdown):
        if not re.match(r"[a-z]+://", target):
            assert (NOTEBOOKS / target).exists(), f"{name} links {target}, which is not in the repository"
    assert re.search(r"^> ", markdown, re.MULTILINE), f"{name} cites the notes without quoting them"
