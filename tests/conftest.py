import os
import subprocess
import sys

import matplotlib
import pytest

matplotlib.use("Agg")


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    """The fuzz suite's report (tests/test_fuzz.py): per category, the cases tried, the clean
    ones and the failing ones by kind; also written as JSON to $KINEMA_FUZZ_REPORT if set."""
    import json
    import os
    import sys

    cases, suite = sys.modules.get("fuzz_cases"), sys.modules.get("test_fuzz")
    if cases is None or suite is None or not getattr(cases, "REPORT", None):
        return
    failed = [r.nodeid.split("::")[-1].split("[")[0] for r in terminalreporter.stats.get("failed", []) if "test_fuzz.py" in r.nodeid]
    cases.mark_failed_tests(failed, suite.CATEGORY_OF)
    table = cases.report_table()
    terminalreporter.write_sep("=", "fuzz cases by category")
    terminalreporter.write_line(cases.format_report(table))
    where = os.environ.get("KINEMA_FUZZ_REPORT")
    if where:
        total = {k: sum(row[k] for row in table.values()) for k in ("tries", "clean", "failed")}
        with open(where, "w", encoding="utf-8") as f:
            json.dump({"examples": int(os.environ.get("KINEMA_FUZZ_EXAMPLES", "40")), "categories": table, "total": total}, f, indent=1)
        terminalreporter.write_line(f"(written to {where})")


@pytest.fixture
def jupyter_kernel(tmp_path, monkeypatch):
    """The name of a Jupyter kernel of this very Python (where kinema is), whatever other
    kernels are installed, for nbclient; skips without the notebook extras
    (requirements/viewer-test.txt)."""
    import json
    import sys

    for module in ("nbformat", "nbclient", "ipykernel"):
        pytest.importorskip(module, reason=f"{module} is not installed: pip install -r requirements/viewer-test.txt")
    spec = tmp_path / "jupyter" / "kernels" / "kinema-test"
    spec.mkdir(parents=True)
    argv = [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"]
    (spec / "kernel.json").write_text(json.dumps({"argv": argv, "display_name": "kinema test", "language": "python"}))
    monkeypatch.setenv("JUPYTER_PATH", str(tmp_path / "jupyter"))
    return "kinema-test"


@pytest.fixture
def on_threads():
    """Runs a Python `script` (from the repository root, printing one line) once per thread
    count (RAYON_NUM_THREADS) and returns {threads: its line}: a result that must not depend
    on the engine's threads gives one line for all."""

    def run(script: str, threads: tuple[int, ...] = (1, 2, 3)) -> dict[int, str]:
        out = {}
        for n in threads:
            env = {**os.environ, "RAYON_NUM_THREADS": str(n)}
            res = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, check=True)
            out[n] = res.stdout.strip()
        return out

    return run
