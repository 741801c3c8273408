"""``kinema sweep`` (registered on the app by ``kinema.cli``): a parameter sweep or ensemble
of a scene run on Dask through ``kinema.sweeps``, and the line it says when Ctrl-C stops it."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape

from ._cli_common import _fail, _guarded
from .runner import console, err_console


@_guarded
def sweep(
    scene: Annotated[Path, typer.Argument(help="Scene file (.toml): the base of every member.")],
    vary: Annotated[
        list[str] | None,
        typer.Option("--vary", metavar="KEY=V1,V2,...", help="A scene key path and its values (TOML values); repeat for a grid."),
    ] = None,
    seeds: Annotated[int | None, typer.Option("--seeds", metavar="N", help="Members per point of the grid, each with its own seed (0 … N−1).", min=1)] = None,
    out: Annotated[Path | None, typer.Option("--out", "-o", help="Sweep folder (default: out/<scene name>_sweep); rerun into it to resume.")] = None,
    scheduler: Annotated[str | None, typer.Option("--scheduler", help="A Dask scheduler's address (tcp://host:8786); default: worker processes here.")] = None,
    workers: Annotated[int | None, typer.Option("--workers", metavar="K", help="Local worker processes (default: the cores).", min=1)] = None,
    duration: Annotated[float | None, typer.Option(help="Simulated time of each member, s (default: the scene's).")] = None,
    checkpoint_every: Annotated[
        float | None, typer.Option("--checkpoint-every", help="Each member writes a checkpoint this often (simulated s); a rerun resumes from it.")
    ] = None,
    measure: Annotated[
        str | None,
        typer.Option(
            "--measure",
            metavar="MODULE:FUNCTION",
            help="A function measure(trajectory, world) -> dict whose values join each member's row: a module importable from here (the current folder first) or FILE.py.",
        ),
    ] = None,
) -> None:
    """Run a parameter sweep or ensemble on Dask: every combination of the --vary values ×
    --seeds, each member a scene with those keys set (validated first), run, saved (H5MD)
    and measured (and by --measure's function, as sweep(measure=...) in Python). Writes
    summary.csv (one row per member), timings.csv and summary.png into the folder; members
    already finished there are skipped (resume). See docs/sweeps.md."""
    from .sweeps import default_folder, load_measure, parse_values
    from .sweeps import sweep as run_sweep

    grid = {}
    for item in vary or []:
        key, eq, values = item.partition("=")
        if not eq or not key.strip():
            raise ValueError(f"--vary {item!r}: use KEY=V1,V2,... (e.g. collisions.restitution=0.5,0.7,0.9)")
        if key.strip() in grid:
            raise ValueError(f"--vary {item!r}: the key {key.strip()} is varied twice; give all its values in one --vary")
        try:
            grid[key.strip()] = parse_values(values)
        except ValueError as e:
            raise ValueError(f"--vary {item!r}: {e}") from None
    folder = out if out is not None else default_folder(scene)
    fn = None if measure is None else load_measure(measure)
    try:
        result = run_sweep(
            scene, grid, seeds=seeds, measure=fn, client=scheduler, out=folder, duration=duration, workers=workers, checkpoint_every=checkpoint_every
        )
    except KeyboardInterrupt:  # what was written is there: say so, and how to go on
        _fail(_sweep_interrupted(scene, grid, seeds, duration, fn, folder), code=130)
    failed = result.failed
    console.print(f"{len(result.rows)} members, {len(failed)} failed; wrote {folder / 'summary.csv'}", highlight=False, soft_wrap=True)
    for row in failed:  # one line each (its traceback, if any, in members/<name>/error.txt)
        err_console.print(f"[bold red]failed:[/] {escape(row['member'])}: {escape(str(row['error']))}", highlight=False, soft_wrap=True)
    if failed:
        raise typer.Exit(1)


def _sweep_interrupted(scene, grid, seeds, duration, measure, folder: Path) -> str:
    """The line ``kinema sweep`` says when Ctrl-C stops it: the members finished in
    ``folder`` (each a result.json of its key), and that a rerun goes on with the others."""
    from .sweeps import finished_members, member_key, members

    try:
        every = members(scene, grid, seeds)
        done = finished_members(folder, every, {m.index: member_key(m, duration, measure) for m in every})
    except Exception:  # (the scene changed meanwhile, the folder went away)
        return f"interrupted; the members finished before are in {folder / 'members'}; run the sweep again into {folder} to go on"
    if not done:
        return f"interrupted; no member had finished: nothing was written in {folder / 'members'}"
    names = ", ".join(m.name for m in done[:5]) + (f" and {len(done) - 5} more" if len(done) > 5 else "")
    return (
        f"interrupted; {len(done)} of {len(every)} members were written in {folder / 'members'} ({names}); "
        f"run the sweep again into {folder} to go on with the others (summary.csv is written when all are done)"
    )
