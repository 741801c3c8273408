"""``kinema analyze`` (registered on the app by ``kinema.cli``): the measures of a recorded
packing (``kinema.analysis.report``) printed as tables, the profile's slabs and the time
series of ``--frame all`` each as its own table, and written as JSON with ``--json``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.table import Table

from ._cli_common import _UNITS_HELP, _guarded, _load
from .runner import _count, console


@_guarded
def analyze(
    traj: Annotated[Path, typer.Argument(help="A trajectory file (H5MD from kinema run --record-contacts, or any file kinema reads for repose and profile).")],
    frame: Annotated[str, typer.Option("--frame", metavar="N|-1|all", help="The frame: its number, -1 the last (default), or all (a time series too).")] = "-1",
    measure: Annotated[
        str, typer.Option("--measure", metavar="M1,M2,...", help="Comma-separated: coordination, fabric, forces, repose, profile (default: all).")
    ] = "coordination,fabric,forces,repose,profile",
    axis: Annotated[str | None, typer.Option("--axis", help="The height axis, x, y or z (default: z in 3D, y in 2D).")] = None,
    bins: Annotated[int, typer.Option("--bins", metavar="N", help="The profile's slabs and the force histogram's bins.")] = 20,
    cross_section: Annotated[
        float | None,
        typer.Option(
            "--cross-section", metavar="A", help="The slabs' area across the axis, m² (m in 2D); default: the periodic cell's, a box's, or the pile's."
        ),
    ] = None,
    json_out: Annotated[Path | None, typer.Option("--json", metavar="OUT.json", help="Also write the measures as standard JSON (NaN as null).")] = None,
    units: Annotated[str | None, typer.Option("--units", help=_UNITS_HELP)] = None,
) -> None:
    """Measure a recorded packing at a frame (docs/analysis.md): the coordination number
    (rattlers out, walls counted), the fabric tensor, the normal-force distribution, the
    angle of repose, and the coarse-grained profile over height (density, solid fraction,
    velocity, kinetic and contact stress, in --bins slabs). coordination, fabric and forces
    need the contacts (kinema run --record-contacts, [output] contacts = true or an
    [analysis] table). --frame all adds their time series and the floor's pressure.
    --json writes the same numbers as a scene's [analysis] table writes to analysis.json."""
    import math

    from .analysis import report

    names = report.parse_measures(measure, "--measure")
    if axis is not None and axis not in report.AXES:
        raise ValueError(f"--axis {axis!r}: use x, y or z")
    if not 1 <= bins <= 100_000:
        raise ValueError(f"--bins {bins}: give a number of slabs and histogram bins from 1 to 100000")
    if cross_section is not None and not (math.isfinite(cross_section) and cross_section > 0):
        raise ValueError(f"--cross-section {cross_section}: give the slabs' area across the axis, a finite number > 0 (m², m in 2D)")
    if json_out is not None:
        if json_out.is_dir():
            raise ValueError(f"--json {json_out}: is a folder; give a file name such as {json_out / 'analysis.json'}")
        if not json_out.parent.is_dir() if str(json_out.parent) else False:
            raise ValueError(f"--json {json_out}: the folder {json_out.parent} does not exist")
    t = _load(traj, units)
    k = report.frame_index(t, frame, "--frame")
    report.axis_index(axis, int(t.dim or 3), "--axis")
    report.needs_contacts(t, names, "--measure", what=str(traj))
    doc = report.analyze(t, measures=names, frame=k, axis=axis, bins=bins, cross_section=cross_section, source=traj.name)
    table = Table(title=f"{traj}: frame {doc['frame']}, t = {doc['time']:g} s, {_count(doc['particles'], 'particle')}")
    table.add_column("measure", no_wrap=True)
    table.add_column("value")
    for name, words in report.summary(doc):
        table.add_row(name, escape(words))
    console.print(table)
    profile = doc["measures"].get("profile")
    if profile is not None and "undefined" not in profile:
        console.print(_profile_table(doc), highlight=False)
    if "series" in doc:
        console.print(_series_table(doc), highlight=False)
    if json_out is not None:
        from .io._files import FileWriteError

        try:
            path = report.write_json(doc, json_out)
        except FileWriteError as e:
            raise ValueError(f"--json {json_out}: {e}") from None
        console.print(f"wrote {path}", highlight=False, soft_wrap=True)


def _series_table(doc: dict) -> Table:
    """The time series of ``--frame all``, one row per frame (n/a: undefined there)."""
    series = doc["series"]
    heads = {
        "time": "t (s)",
        "particles": "particles",
        "contacts": "contacts",
        "coordination": "Z",
        "coordination_all": "2C/N",
        "anisotropy": "anisotropy",
        "mean_force": "<f_n> (N)",
        "angle": "repose (°)",
        "base_pressure": "base pressure (Pa)",
    }
    columns = [k for k in heads if isinstance(series.get(k), list)]
    table = Table(title="over time" + ("" if isinstance(series["base_pressure"], list) else f" (base pressure: {series['base_pressure']['undefined']})"))
    for k in columns:
        table.add_column(heads[k], justify="right")
    for row in zip(*(series[k] for k in columns), strict=True):
        table.add_row(*("n/a" if v is None else str(v) if isinstance(v, int) else format(v, ".4g") for v in row))
    return table


def _profile_table(doc: dict) -> Table:
    """The profile's slabs, one row each: height, density, solid fraction, the velocity and
    the stresses along the axis (None: n/a)."""
    from .analysis import report

    p, a = doc["measures"]["profile"], report.AXES.index(doc["axis"])
    x = doc["axis"]
    table = Table(title=f"profile over {x} ({len(p['center'])} slabs, cross-section {doc['cross_section']:.4g}, {doc['cross_section_from']})")
    for col in (f"{x} (m)", "density (kg/m³)", "solid fraction", f"v_{x} (m/s)", f"σ_{x}{x} kinetic (Pa)", f"σ_{x}{x} contact (Pa)"):
        table.add_column(col, justify="right")

    def cell(v, spec=".4g"):
        return "n/a" if v is None else format(v, spec)

    for k, z in enumerate(p["center"]):
        vel = None if p["velocity"] is None or p["velocity"][k][a] is None else p["velocity"][k][a]
        kin = None if p["kinetic_stress"] is None else p["kinetic_stress"][k][a][a]
        con = None if p["contact_stress"] is None else p["contact_stress"][k][a][a]
        table.add_row(cell(z), cell(p["density"][k]), cell(p["solid_fraction"][k], ".4f"), cell(vel), cell(kin), cell(con))
    return table
