"""USD's names that the readers and the writer share, and nothing of theirs: the suffixes a
layer is named by, the first bytes of its layers, the check of a stage's `metersPerUnit`
and usd-core's reason for a refusal. A leaf (it imports no kinema module), so that
`read_usd` (trajectories), `mesh_files` (meshes) and `usd_writer` each use it without one
importing another for a list of suffixes (tests/test_no_import_circles.py)."""

from __future__ import annotations

import math

#: The suffixes USD writes: binary crate (.usd, .usdc), text (.usda), a zip package (.usdz).
#: USD picks a layer's format from its suffix, and refuses another.
SUFFIXES = (".usd", ".usda", ".usdc", ".usdz")

#: The first bytes of a binary (crate) layer and of a text layer; a .usdz is a zip ("PK").
MAGIC_CRATE, MAGIC_TEXT = b"PXR-USDC", b"#usda"


def meters_per_unit_problem(metres: float) -> str | None:
    """Why a stage's `metersPerUnit` cannot be read (NaN, 0: every position 0, negative: a
    mirrored scene), or None."""
    if math.isfinite(metres) and metres > 0:
        return None
    return f"metersPerUnit = {metres!r} is invalid: it must be finite and > 0 (the metres in one of the stage's units)"


def _usd_reason(e: Exception) -> str:
    """The last part of usd-core's several-line error ("Error in '...' at line ... : 'what'")."""
    lines = [line.strip() for line in str(e).splitlines() if line.strip()]
    return lines[0].rsplit(" : ", 1)[-1].strip("'") if lines else "usd-core failed"
