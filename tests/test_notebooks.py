"""The lecture notes as notebooks (examples/notebooks/): one per part of the seed, each run
top to bottom by a real kernel (nbclient), as a student would run it.

Each notebook checks its own claims against closed forms with ``assert`` (Euler by hand
against kinema's, measured orders against the declared ones, the largest stable step
2/|λ| and 2.785/|λ|, momentum kept by action and reaction, free fall exact under Verlet,
the two-ball collision, the cradle, a bouncing ball at rest by t₀ (1 + e)/(1 − e)), so a
notebook whose numbers drift fails here. Each ends with the viewer inline
(``Trajectory.show()``)."""

from __future__ import annotations

from pathlib import Path

import pytest

NOTEBOOKS = Path(__file__).resolve().parent.parent / "examples" / "notebooks"
PARTS = ["01_ode_methods", "02_stability", "03_particles_and_newton", "04_collisions"]


def test_there_is_one_notebook_per_part_of_the_seed():
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
    html = [o["data"]["text/html"] for o in outputs if o["output_type"] in ("execute_result", "display_data") and "text/html" in o["data"]]
    assert any(h.startswith("<div><iframe srcdoc=") for h in html), f"{name}: no inline viewer"
    streams = "".join(o.get("text", "") for o in outputs if o["output_type"] == "stream" and o.get("name") == "stderr")
    assert "Warning" not in streams, streams
