"""What a parameter sweep (`kinema.sweeps`) writes besides the members' trajectories: its JSON
files in standard JSON, a non-finite number as a string (`NON_FINITE`, `to_json`, `read_json`),
and the summary of the members: summary.csv and timings.csv (`_write_csv`, every float's every
bit) and summary.png (`_plot`, `_figure`: each measurement against each varied key)."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

#: How sweep.json and result.json write a number JSON cannot hold (RFC 8259 has no infinity
#: nor NaN; Python's json writes the bare tokens Infinity and NaN, which other parsers refuse):
#: as these strings, which JavaScript's ``Number()`` and Python's ``float()`` read as the
#: number. :func:`read_json` reads them back as floats (so a text value spelled exactly so,
#: a species named "NaN", would read back as the number too).
NON_FINITE = {"Infinity": math.inf, "-Infinity": -math.inf, "NaN": math.nan}


def _standard(v: Any) -> Any:
    """``v`` with each non-finite float (numpy's too) written as its :data:`NON_FINITE` word."""
    if isinstance(v, float | np.floating) and not math.isfinite(v):
        return "NaN" if math.isnan(v) else ("Infinity" if v > 0 else "-Infinity")
    if isinstance(v, dict):
        return {k: _standard(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_standard(x) for x in v]
    return v


def _numbers(v: Any) -> Any:
    """``v`` read from JSON with the :data:`NON_FINITE` words made floats again."""
    if isinstance(v, str):
        return NON_FINITE.get(v, v)
    if isinstance(v, dict):
        return {k: _numbers(x) for k, x in v.items()}
    if isinstance(v, list):
        return [_numbers(x) for x in v]
    return v


def to_json(v: Any) -> str:
    """Standard JSON text of ``v`` (indented): non-finite numbers as :data:`NON_FINITE`'s
    strings; what JSON has no type for (a path) as its ``str``."""
    return json.dumps(_standard(v), indent=1, default=str, allow_nan=False)


def read_json(path: str | Path) -> Any:
    """A sweep's JSON file (``sweep.json``, a member's ``result.json``) as written: the
    :data:`NON_FINITE` strings back as floats."""
    return _numbers(json.loads(Path(path).read_text()))


# -- results ----------------------------------------------------------------------------------


def _write_csv(path: Path, rows: list[dict[str, Any]]) -> None:
    from .io._files import atomic_file

    columns = list(dict.fromkeys(k for r in rows for k in r))
    if "error" in columns:  # last, where it reads best
        columns.remove("error")
        columns.append("error")
    with atomic_file(path) as tmp, open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=columns)
        w.writeheader()
        for r in rows:
            w.writerow({k: _cell(r.get(k, "")) for k in columns})


def _cell(v: Any) -> Any:
    if isinstance(v, float):
        return repr(v)  # every bit: the shortest text that reads back as the same float
    if isinstance(v, (list, dict)):
        return json.dumps(_standard(v), allow_nan=False)
    return "" if v is None else v


def _plot(path: Path, rows: list[dict[str, Any]], keys: list[str]) -> None:
    """summary.png: each measurement against each numeric varied key (``_figure``)."""
    fig = _figure(rows, keys)
    if fig is not None:
        import matplotlib.pyplot as plt

        from .runner import save_figure_atomically

        save_figure_atomically(fig, path)
        plt.close(fig)


#: Units of the measurements a sweep takes itself, and of the scene keys most often varied
#: (by their last part); a ``measure``'s own columns are labelled by their names alone.
UNITS = {
    "final_kinetic": "J",
    "final_total": "J",
    "energy_lost": "J",
    "dt": "s",
    "duration": "s",
    "fps": "1/s",
    "radius": "m",
    "mass": "kg",
    "rate": "1/s",
    "stiffness": "N/m",
    "damping": "1/s",
    "speed": "m/s",
    "lifetime": "s",
}


def _label(name: str) -> str:
    unit = UNITS.get(name.rsplit(".", 1)[-1])
    return f"{name} ({unit})" if unit else name


def _figure(rows: list[dict[str, Any]], keys: list[str]) -> Any:
    """The members' measurements (rows) against each numeric varied key: the members as dots,
    the mean over the other values and seeds with its standard deviation; axes labelled with
    units where known. A measurement equal in every member (the frames of a fixed duration)
    has no panel. None when nothing numeric varies."""
    import matplotlib

    matplotlib.use("Agg")  # (workers and scripts without a display)
    import matplotlib.pyplot as plt

    ok = [r for r in rows if not r.get("error")]
    skip = {"member", "seed", "error", *keys}
    names = [k for k in dict.fromkeys(k for r in ok for k in r) if k not in skip and all(_number(r.get(k)) for r in ok)]
    names = [k for k in names if len({float(r[k]) for r in ok}) > 1]
    if not ok or not names:
        return None
    numeric_keys = [k for k in keys if all(_number(r[k]) for r in ok)]
    if not numeric_keys:
        return None
    fig, axes = plt.subplots(len(names), len(numeric_keys), figsize=(4.2 * len(numeric_keys), 2.6 * len(names)), squeeze=False)
    for i, name in enumerate(names):
        for j, key in enumerate(numeric_keys):
            ax = axes[i][j]
            xs = np.array([float(r[key]) for r in ok])
            ys = np.array([float(r[name]) for r in ok])
            ax.plot(xs, ys, ".", color="0.6", ms=4)
            ux = np.unique(xs)
            mean = np.array([ys[xs == u].mean() for u in ux])
            spread = np.array([ys[xs == u].std() for u in ux])
            ax.errorbar(ux, mean, yerr=spread, fmt="o-", color="C0", capsize=3)
            ax.set_xlabel(_label(key))
            ax.set_ylabel(_label(name))
            ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(float(v))
