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

The app and most commands are here; what the commands share (one-line errors and warnings,
``_fail`` and ``_guarded``; ``_load``, a trajectory with ``--units``; the help texts) is in
``kinema._cli_common``, and ``kinema sweep`` and ``kinema analyze`` are in ``kinema._cli_sweep``
and ``kinema._cli_analyze``, registered on the app below in the order the help lists them.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.table import Table

from ._cli_analyze import analyze
from ._cli_common import _TRAJ_HELP, _UNITS_HELP, _fail, _guarded, _load
from ._cli_sweep import sweep
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


# (defined in their own modules, each given to @_guarded there: registered here, in the help's order)
app.command(short_help="Run a parameter sweep or ensemble of a scene on Dask.")(sweep)
app.command(short_help="Measure a recorded packing: contacts, fabric, forces, profile.")(analyze)


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
