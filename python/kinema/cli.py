"""The ``kinema`` command (``python -m kinema`` is the same).

Exit codes: 0 done, 2 bad input (the message says what and where: a scene or trajectory file,
an option, an output path that cannot be written, work over the limits below without
--force), 1 a simulation that diverged (the message names the step and the advisor's step).
Errors are one line on stderr, never a traceback; ``KINEMA_DEBUG=1`` re-raises unexpected errors.

Work limits: ``run``, ``view`` (of a scene) and ``render`` estimate their work before doing any
(particles × steps, video frames × pixels, memory) and refuse, unless given ``--force``,
more than ``LIMIT_PARTICLE_STEPS`` particle-steps, ``LIMIT_PIXELS`` pixels or
``LIMIT_MEMORY`` bytes; more than ``MAX_STEPS`` steps are refused even with ``--force``
(the limits and the work of running a scene are in kinema.runner).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.markup import escape
from rich.table import Table

from .runner import (
    FRAME_BYTES,
    RENDER_BYTES,
    VIDEO_FPS,
    OutputError,
    _count,
    _frames_and_steps,
    _over_limits,
    _progress,
    _render_video,
    _scene_work,
    _size,
    console,
    err_console,
    save_figure_atomically,
    simulate_scene,
)

app = typer.Typer(
    name="kinema",
    help="kinema: particle systems that move by honest numerical methods.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
    rich_markup_mode=None,  # click's plain help: typer 0.29's rich help prints <bool> beside every flag
)


def _print_version(value: bool) -> None:
    if value:
        from . import __version__

        console.print(f"kinema {__version__}", highlight=False)
        raise typer.Exit()


@app.callback()
def _options(
    version: Annotated[bool | None, typer.Option("--version", "-V", callback=_print_version, is_eager=True, help="Print the version and exit.")] = None,
) -> None:
    """kinema: particle systems that move by honest numerical methods."""


def _fail(message: str, code: int = 2) -> None:
    # (escaped: a message quotes paths and values, whose brackets are not rich markup)
    err_console.print(f"[bold red]error:[/] {escape(message)}", highlight=False, soft_wrap=True)
    raise typer.Exit(code)


def _split_methods(methods: str) -> list[str]:
    import kinema

    names = [m.strip() for m in methods.split(",") if m.strip()]
    if not names:
        _fail(f"--methods {methods!r}: give at least one method name, comma separated")
    valid = kinema.method_names()
    for n in names:
        if n not in valid:
            meant = kinema._core.method_suggestion(n)
            hint = f" did you mean {meant!r}?" if meant else ""
            _fail(f"--methods: unknown method '{n}';{hint} valid methods are: {', '.join(valid)}")
    return names


@app.command()
def methods() -> None:
    """List the integration methods of the registry."""
    import kinema

    registry = kinema.methods()
    table = Table(title="kinema methods")
    for col in ("name", "order", "kind", "f evals/step", "summary"):
        table.add_column(col, no_wrap=col != "summary")
    for m in registry:
        table.add_row(m.name, str(m.order), m.kind, str(m.evals_per_step), m.summary)
    if console.measure(table, options=console.options.update_width(10_000)).maximum <= console.width:
        console.print(table)
        return
    # narrower than the table (80 columns): two lines per method, the summary unwrapped below
    for m in registry:
        console.print(f"[bold]{m.name}[/bold]  order {m.order}, {m.kind}, {m.evals_per_step} f evals/step", highlight=False)
        console.print(f"    {m.summary}", highlight=False, markup=False, soft_wrap=True)


@app.command(short_help="Stability regions |R(hλ)| ≤ 1 and the largest stable steps.")
def stability(
    methods: Annotated[str, typer.Option(help="Comma-separated method names.")] = "euler,midpoint,rk4,implicit_euler",
    out: Annotated[Path, typer.Option(help="Image to write (.png, .svg, .pdf).")] = Path("regions.png"),
    extent: Annotated[str, typer.Option(help="re_min,re_max,im_min,im_max of the z = hλ plane.")] = "-5,3,-4,4",
) -> None:
    """Plot the stability regions |R(hλ)| ≤ 1 and print each method's stable intervals."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import kinema

    names = _split_methods(methods)
    try:
        box = tuple(float(v) for v in extent.split(","))
        if len(box) != 4 or not (box[0] < box[1] and box[2] < box[3]):
            raise ValueError
    except ValueError:
        _fail(f"--extent {extent!r}: give four numbers re_min,re_max,im_min,im_max with min < max")
    fig, ax = plt.subplots(figsize=(7, 6))
    kinema.stability.plot_regions(names, ax=ax, extent=box)
    try:
        path = save_figure_atomically(fig, out)
    except OutputError as e:
        _fail(str(e))
    plt.close(fig)
    table = Table(title="stable intervals of z = hλ")
    for col in ("method", "real axis", "imaginary axis"):
        table.add_column(col)
    for n in names:
        r = kinema.stability.real_interval(n)
        i = kinema.stability.imag_interval(n)
        table.add_row(n, *("none" if a.empty else f"[{a.lo + 0.0:.4f}, {a.hi + 0.0:.4f}]" for a in (r, i)))  # (+ 0.0: no "-0.0000")
    console.print(table)
    console.print(f"wrote {path}")


@app.command(short_help="Every method on x'' = −x: portraits, stability regions, orders.")
def demo(
    out: Annotated[Path, typer.Option(help="Folder for the pictures.")] = Path("out"),
) -> None:
    """Integrate a problem with every method; plot stability regions and convergence.

    Solves the oscillator x'' = -x with every registered method and prints each one's
    error, energy drift and cost; then writes into --out: phase_portraits.png,
    stability_regions.png (|R(hλ)| <= 1), convergence.png (error against h: each method's
    order), and the falling-balls scene (scenes/demo.toml: impacts by Newton's restitution
    law) as trajectory.h5, demo.mp4, energy.png and demo.html (the browser viewer, offline)."""
    from .demo import run_demo

    if out.exists() and not out.is_dir():
        _fail(f"--out {out}: exists and is not a folder")
    try:
        run_demo(out, console)
    except OutputError as e:  # a picture that cannot be written
        _fail(str(e))


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """``warnings.showwarning`` of the commands: a warning is one line ``warning: ...`` on
    stderr, as ``kinema run`` says its own, without Python's file, line and source."""
    err_console.print(f"[yellow]warning:[/] {escape(str(message))}", highlight=False, soft_wrap=True)


def _guarded(fn):
    """Run a command body, turning known failures into one line and an exit code, and each
    warning into one line (``_one_line_warning``)."""
    import functools

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        import warnings

        with warnings.catch_warnings():
            warnings.showwarning = _one_line_warning
            return _guarded_body(fn, args, kwargs)

    return wrapper


def _guarded_body(fn, args, kwargs):
    """Runs ``fn``, turning known failures into one line and an exit code."""
    import kinema
    from kinema.scene import SceneError

    try:
        return fn(*args, **kwargs)
    except typer.Exit:
        raise
    except kinema.SimulationDiverged as e:
        _fail(str(e) if "diverged" in str(e) else f"the simulation diverged: {e}", code=1)
    except SceneError as e:  # one line per problem
        for line in str(e).splitlines():
            err_console.print(f"[bold red]error:[/] {escape(line)}", highlight=False, soft_wrap=True)
        raise typer.Exit(2) from None
    except ImportError as e:  # an optional package a format needs (usd-core): how to get it
        _fail(str(e).strip().splitlines()[0])
    except (ValueError, OSError) as e:  # TrajectoryFileError is a ValueError
        text = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        if isinstance(e, OSError) and e.filename:
            text = f"cannot write {e.filename}: {e.strerror}"
        _fail(text)
    except KeyboardInterrupt:
        _fail("interrupted; nothing was written", code=130)
    except MemoryError:
        _fail("out of memory: the work is too large for this machine; nothing was written")
    except Exception as e:
        if os.environ.get("KINEMA_DEBUG"):
            raise
        _fail(f"unexpected {type(e).__name__}: {e} (set KINEMA_DEBUG=1 for the traceback)", code=1)


_UNITS_HELP = (
    "Units of a file that does not say them (a LAMMPS dump or data file without its units, a HOOMD GSD file, an XYZ file not in ASE's units): "
    "real, metal, si, cgs, electron, micro, nano (LAMMPS's styles), ase, or length=M,time=S,mass=KG (the file's units in SI)."
)
_TRAJ_HELP = (
    "A trajectory file: H5MD (.h5), extended XYZ (.xyz), GSD (.gsd), a LAMMPS dump (.lammpstrj) or data file (.data), "
    "a USD stage's points (.usd, .usdc, .usda, .usdz), or kinema's CSV, VTK (.pvd) or PLY series export."
)


def _load(path: Path, units: str | None):
    """The trajectory in ``path``, any format kinema reads (``Trajectory.load``), with the
    ``--units`` given: a name, or length=M,time=S,mass=KG."""
    from .io import UnitWarning
    from .trajectory import Trajectory

    given: str | dict[str, float] | None = units
    if units is not None and "=" in units:
        given = {}
        for item in units.split(","):
            key, _, value = item.partition("=")
            try:
                given[key.strip()] = float(value)
            except ValueError:
                raise ValueError(f"--units {units!r}: {item!r} is invalid: give a name or length=M,time=S,mass=KG with numbers") from None
    import warnings

    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", UnitWarning)
            traj = Trajectory.load(path, units=given)
        for w in caught:  # a UnitWarning (numbers taken in units the file does not state): one line, as runner.py says its warnings
            if issubclass(w.category, UnitWarning):
                err_console.print(f"[yellow]warning:[/] {escape(str(w.message))} (--units)", highlight=False, soft_wrap=True)
            else:
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        return traj
    except ValueError as e:
        text = str(e)
        if text.startswith("units"):  # the units refused: said of the option
            raise ValueError(f"--units {units!r}: {text.split(' is invalid: ', 1)[1] if ' is invalid: ' in text else text.split(': ', 1)[-1]}") from None
        raise


@app.command(short_help="Simulate a scene: trajectory (H5MD), video, energy plot.")
@_guarded
def run(
    scene: Annotated[Path, typer.Argument(help="Scene file (.toml), see docs/scenes.md.")],
    out: Annotated[Path | None, typer.Option("--out", "-o", help="Output folder (default: out/<scene name>).")] = None,
    duration: Annotated[float | None, typer.Option(help="Simulated time, s (default: the scene's [world].duration).")] = None,
    no_video: Annotated[bool, typer.Option("--no-video", help="Skip the video.")] = False,
    force: Annotated[bool, typer.Option("--force", help="Run even when the work estimate is over the limits.")] = False,
    checkpoint_every: Annotated[
        float | None, typer.Option("--checkpoint-every", help="Write OUT/checkpoint.ckpt every this many simulated seconds (whole frames).")
    ] = None,
    resume: Annotated[bool, typer.Option("--resume", help="Go on from OUT/checkpoint.ckpt, left by a run with --checkpoint-every that stopped.")] = False,
    keep_checkpoint: Annotated[
        Path | None,
        typer.Option(
            "--keep-checkpoint",
            metavar="PATH",
            help="Write the world at the run's end to PATH as a checkpoint (spins and tangential springs included): kinema.World.load_checkpoint(PATH) gives it back.",
        ),
    ] = None,
    record_contacts: Annotated[
        bool,
        typer.Option("--record-contacts", help="Keep each frame's contacts in trajectory.h5 (/contacts), as the scene's [output] contacts = true does."),
    ] = False,
) -> None:
    """Simulate a scene; write the trajectory (H5MD), a video and an energy/momentum plot.

    The work is estimated first (particles × steps, video pixels, memory); a run over the
    limits is refused unless --force is given. With --checkpoint-every T the world and the
    frames so far are written to OUT/checkpoint.ckpt every T s of simulated time (removed when
    the run ends well); --resume goes on from it, to the same files, bit for bit. With
    --keep-checkpoint PATH the world at the end is kept there, to measure it in Python
    (particle_stress needs a live world) or to go on from it, bit for bit.
    --record-contacts keeps each frame's contacts (World.run(record_contacts=True)); kinema
    export then writes them too (lammps: run_contacts.dump and run_collider_contacts.dump;
    vtk: force-chain lines)."""
    simulate_scene(
        scene,
        out if out is not None else Path("out") / scene.stem,
        duration,
        no_video,
        force=force,
        checkpoint_every=checkpoint_every,
        resume=resume,
        keep_checkpoint=keep_checkpoint,
        record_contacts=record_contacts,
    )


@app.command(short_help="Render a saved trajectory to a video (MP4, GIF).")
@_guarded
def render(
    traj: Annotated[Path, typer.Argument(help=_TRAJ_HELP)],
    out: Annotated[Path, typer.Option("--out", "-o", help="Video to write: .mp4 (H.264) or .gif.")],
    fps: Annotated[
        float | None,
        typer.Option(
            help="Frames per second: one video frame per recorded frame at this rate. Default: real time, at the fps the trajectory "
            "was recorded at (kinema run's files say it), else the nearest of 24, 25, 30, 50, 60 within 2 % of the recording's rate, "
            "else that rate."
        ),
    ] = None,
    width: Annotated[int, typer.Option(help="Width, pixels.")] = 640,
    height: Annotated[int, typer.Option(help="Height, pixels.")] = 480,
    color_by: Annotated[str, typer.Option(help="speed, id or color (each particle's own: an emitter's color).")] = "speed",
    force: Annotated[bool, typer.Option("--force", help="Render even when the work estimate is over the limits.")] = False,
    units: Annotated[str | None, typer.Option("--units", help=_UNITS_HELP)] = None,
) -> None:
    """Render a saved trajectory to a video: kinema's H5MD or another program's file (XYZ, GSD,
    LAMMPS dump or data; docs/files.md).

    Without --fps the video plays in real time: at the fps the scene asked for when the file
    says it (an H5MD file of kinema run: 30, at which it was recorded), else at the nearest of 24, 25, 30, 50 and 60 fps within 2 % of the recording's
    rate, else at that rate; frames are dropped or repeated to keep time. --fps F writes every
    recorded frame at exactly F (slow or fast motion).

    The work is estimated first (frames × pixels, memory); a video over the limits is refused
    unless --force is given."""
    from .render import VIDEO_EXTENSIONS

    if out.suffix.lower() not in VIDEO_EXTENSIONS:
        raise ValueError(f"-o {out}: unsupported video format {out.suffix or '(none)'!r}; use .mp4 or .gif")
    if out.is_dir():
        raise ValueError(f"-o {out}: is a directory; give a file name such as {out / 'movie.mp4'}")
    if not out.parent.is_dir() if str(out.parent) else False:
        raise ValueError(f"-o {out}: the folder {out.parent} does not exist")
    if color_by not in ("speed", "id", "color"):
        raise ValueError(f"--color-by {color_by!r}: use speed, id or color")
    if not (16 <= width <= 8192 and 16 <= height <= 8192):
        raise ValueError(f"--width {width} --height {height}: each must be between 16 and 8192 pixels")
    if fps is not None and not (VIDEO_FPS[0] <= fps <= VIDEO_FPS[1]):
        raise ValueError(f"--fps {fps}: give a number of frames per second from {VIDEO_FPS[0]:g} to {VIDEO_FPS[1]:g}")
    t = _load(traj, units)
    frames, n = t.positions.shape[:2]
    pixels = float(frames) * width * height
    memory = frames * n * (FRAME_BYTES + RENDER_BYTES)
    estimate = f"rendering would take {pixels:.1e} pixels ({frames:,} frames × --width {width} × --height {height}) and about {_size(memory)} of memory"
    _over_limits(str(traj), estimate, 0.0, pixels, memory, force)
    console.print(
        f"{traj}: {_count(n, 'particle')}, {_count(frames, 'frame')}, {width}×{height}; work: {pixels:.1e} pixels, about {_size(memory)} of memory",
        highlight=False,
        soft_wrap=True,
    )
    path = _render_video(t, out, {"width": width, "height": height, "color_by": color_by}, fps, "rendering")
    console.print(f"wrote {path}", highlight=False, soft_wrap=True)


@app.command(short_help="Export a trajectory for other programs (VTK, PLY, XYZ, GSD, USD).")
@_guarded
def export(
    traj: Annotated[Path, typer.Argument(help=_TRAJ_HELP)],
    format: Annotated[
        str,
        typer.Option(
            "--format",
            "-f",
            help="vtk (ParaView), ply (Blender), xyz (OVITO, ASE), csv, gsd (HOOMD, OVITO), lammps (a LAMMPS dump), usd (Blender, Houdini), blend (a Blender scene, built by Blender).",
        ),
    ],
    out: Annotated[
        Path | None,
        typer.Option("--out", "-o", help="Main output file; missing folders are created (default: beside TRAJ, named as below)."),
    ] = None,
    units: Annotated[str | None, typer.Option("--units", help=_UNITS_HELP)] = None,
    plain_dump: Annotated[
        bool,
        typer.Option(
            "--plain-dump",
            help="lammps: LAMMPS's default dump layout, without the ITEM: UNITS, ITEM: TIME and type-label items (MDAnalysis reads no dump with them).",
        ),
    ] = False,
) -> None:
    """Export a saved trajectory for other programs (TRAJ: kinema's H5MD or any file kinema
    reads, docs/files.md; the exports are in SI units).

    Beside TRAJ (run.h5) unless -o names another file: vtk writes run.pvd (open it in
    ParaView or OVITO), its frames in the folder run_vtk/ and the colliders in
    run_colliders.vtp; ply one file a frame in the folder
    run_ply/ (run_00000.ply, ...); xyz run.xyz (extended XYZ, SI units); csv run.csv; gsd
    run.gsd; lammps run.lammpstrj (dump custom); usd run.usd (Blender, Houdini; needs
    pip install kinema[usd]); blend run.blend and the stage it plays, run.usdc (needs
    usd-core and Blender: `blender` on the PATH or $KINEMA_BLENDER; open run.blend and
    render: the frame rate, colours, colliders, camera and light are set). So the formats
    never overwrite each other.
    A trajectory with spin carries its angular velocities and orientations in every
    format; one with contacts (kinema run --record-contacts) adds them to lammps
    (run_contacts.dump and run_collider_contacts.dump, LAMMPS dump local) and vtk (lines
    between the particles in contact, coloured by force in ParaView).
    A suffix of -o that names another format (-f vtk -o x.ply) is refused."""
    from .io import FORMATS
    from .io import export as write_export
    from .io.exports import SUFFIX, default_path, suffix_format

    if format not in FORMATS:
        raise ValueError(f"--format {format!r}: use one of {', '.join(FORMATS)}")
    if out is not None:
        other = suffix_format(out)
        if other == "h5md":
            raise ValueError(f"-o {out}: the suffix {out.suffix} is for H5MD trajectories, not exports; name the file {out.with_suffix(SUFFIX[format]).name}")
        if other not in (None, format):
            raise ValueError(
                f"-o {out}: the suffix {out.suffix} is for --format {other}, not --format {format}; name the file {out.with_suffix(SUFFIX[format]).name}"
            )
    path = out if out is not None else default_path(traj, format)
    t = _load(traj, units)
    if path.exists() and os.path.samefile(path, traj):
        raise ValueError(f"-o {path}: is the trajectory being exported; name another file")
    if not path.parent.is_dir():  # as `kinema run -o` makes its folder
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise ValueError(f"-o {out}: cannot create the folder {path.parent} ({e.strerror or e})") from None
    with _progress() as bar:
        task = bar.add_task(f"writing {format}", total=len(t.t))
        paths = write_export(t, path, format, on_frame=lambda _i: bar.advance(task), plain_dump=plain_dump)
    # The main files beside PATH, then a series folder's frames as a count.
    main = [str(p) for p in paths if p.parent == path.parent]
    frames = [p for p in paths if p.parent != path.parent]
    if frames:
        main.append(f"{len(frames)} frames in {frames[0].parent}{os.sep}")
    console.print("wrote " + " and ".join(main), highlight=False, soft_wrap=True)


@app.command(short_help="Run a parameter sweep or ensemble of a scene on Dask.")
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


@app.command(short_help="Measure a recorded packing: contacts, fabric, forces, profile.")
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


@app.command(short_help="Play a trajectory or a scene in the browser (three.js).")
@_guarded
def view(
    source: Annotated[Path, typer.Argument(help="A scene (.toml, run first) or a" + _TRAJ_HELP[1:])],
    html: Annotated[Path | None, typer.Option("--html", help="Write one self-contained page that plays offline, and exit.")] = None,
    port: Annotated[int, typer.Option(help="Port on 127.0.0.1 (0: a free one).")] = 0,
    no_browser: Annotated[bool, typer.Option("--no-browser", help="Do not open a browser.")] = False,
    force: Annotated[bool, typer.Option("--force", help="Simulate a scene even when the work estimate is over the limits.")] = False,
    units: Annotated[str | None, typer.Option("--units", help=_UNITS_HELP)] = None,
) -> None:
    """Play a trajectory in the browser (three.js): play/pause, scrub, speed, orbit camera, colouring.

    Serves the page on 127.0.0.1 (the URL is printed) until Ctrl-C, which stops the server and
    exits 0; with --html, writes the page to a file instead."""
    import time

    from .viewer import BundleMissingError, serve, write_html

    if not 0 <= port <= 65535:
        raise ValueError(f"--port {port}: use 0 (a free port) or a port from 1 to 65535")
    if html is None and port != 0:
        _check_port(port)  # before a scene is simulated, not after
    if source.suffix.lower() == ".toml":
        if not source.exists():
            raise ValueError(f"{source}: no such file")
        if source.is_dir():
            raise ValueError(f"{source}: is a directory; give a scene (.toml) or a trajectory file")
        from .scene import Scene

        sc = Scene.from_toml(source)
        _scene_work(sc, source, sc.world.duration, "world.duration", False, force)
        world = sc.build(source=str(source))
        settings = sc.world
        with _progress() as bar:
            frames = int(_frames_and_steps(settings.duration, world.dt, settings.fps)[0])
            task = bar.add_task("simulating", total=frames + 1, completed=1)  # the frame at t = 0 is recorded first
            traj = world.run(settings.duration, fps=settings.fps, callback=lambda w: bar.advance(task), max_work=None)
    else:
        traj = _load(source, units)  # (a missing file or a folder: its one-line refusal)
    # A scene opens in its own colouring, and at its own [render] camera when it has one.
    from .runner import _camera as _scene_camera

    color_by = sc.render.color_by if source.suffix.lower() == ".toml" else None
    camera = _scene_camera(sc.render.camera) if source.suffix.lower() == ".toml" else None
    if html is not None:
        path = write_html(traj, html, color_by=color_by, camera=camera)
        console.print(f"wrote {path}", highlight=False, soft_wrap=True)
        return
    try:
        url, server = serve(traj, open_browser=not no_browser, port=port, announce=False, color_by=color_by, camera=camera)
    except BundleMissingError:
        raise
    except OSError as e:  # the port is taken or not ours to bind
        raise ValueError(f"--port {port}: cannot listen on 127.0.0.1:{port} ({e.strerror or e})") from None
    try:
        console.print(f"serving {url} — Ctrl-C to stop", highlight=False, soft_wrap=True)
        while server.thread.is_alive():
            time.sleep(0.5)
    except KeyboardInterrupt:
        pass  # Ctrl-C is how the viewer is stopped: a clean exit, status 0
    finally:
        server.shutdown()
        server.server_close()


def _check_port(port: int) -> None:
    """Refuse `port` on 127.0.0.1 where it cannot be listened on (taken, or not ours to bind),
    as the server's own bind would, by binding it once and letting it go (the server binds
    it again moments later: a port taken in between is still refused then)."""
    import socket

    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as http.server binds
        try:
            probe.bind(("127.0.0.1", port))
        except OSError as e:
            raise ValueError(f"--port {port}: cannot listen on 127.0.0.1:{port} ({e.strerror or e})") from None


def main() -> None:
    """Entry point of the ``kinema`` script."""
    app()


if __name__ == "__main__":
    main()


def __getattr__(name: str) -> Any:
    """``click_command``: the click command behind ``app``, for the documentation site's
    command-line reference (mkdocs-click reads a click command by its module and name)."""
    if name == "click_command":
        return typer.main.get_command(app)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
