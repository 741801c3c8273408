"""The committed viewer bundle (python/kinema/viewer/static/viewer.js) is exactly what
viewer/src builds with the pinned esbuild and three.js, so that an installed package has a
working viewer without Node and the bundle never drifts from its sources."""

import shutil
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
VIEWER = REPO / "viewer"
BUNDLE = REPO / "python" / "kinema" / "viewer" / "static" / "viewer.js"


def test_the_bundle_is_in_the_package():
    text = BUNDLE.read_text(encoding="utf-8")
    assert len(text) > 100_000 and "three" in text.lower()  # three.js is bundled in


@pytest.mark.skipif(shutil.which("node") is None or shutil.which("npm") is None, reason="Node and npm are needed to rebuild the viewer's bundle")
def test_the_committed_bundle_is_what_viewer_src_builds(tmp_path):
    if not (VIEWER / "node_modules" / "esbuild").exists():
        subprocess.run(["npm", "ci", "--no-audit", "--no-fund", "--loglevel=error"], cwd=VIEWER, check=True, timeout=300)
    out = tmp_path / "viewer.js"
    subprocess.run(["node", "build.mjs", str(out)], cwd=VIEWER, check=True, timeout=120, capture_output=True)
    assert out.read_bytes() == BUNDLE.read_bytes(), "viewer/src changed: run `make viewer` and commit python/kinema/viewer/static/viewer.js"
