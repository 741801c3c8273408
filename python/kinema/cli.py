"""The ``kinema`` command (``python -m kinema`` is the same).

Exit codes: 0 done, 2 bad input (the message says what and where: a scene or trajectory file,
an option, an output path that cannot be written), 1 a simulation that diverged (the message
names the step and the advisor's step). Errors are one line on stderr, never a traceback;
``KINEMA_DEBUG=1`` re-raises unexpected errors.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.console import Console
from rich.table import Table

app = typer.Typer(
    name="kinema",
    help="kinema: particle systems that move by honest numerical methods.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
console = Console()
err_console = Console(stderr=True)


def _fail(message: str, code: int = 2) -> None:
    err_console.print(f"[bold red]error:[/] {message}", highlight=False, soft_wrap=True)
    raise typer.Exit(code)


def _split_methods(methods: str) -> list[str]:
    import kinema

    names = [m.strip() for m in methods.split(",") if m.strip()]
    if not names:
        _fail(f"--methods {methods!r}: give at least one method name, comma separated")
    valid = kinema.method_names()
    for n in names:
        if n not in valid:
            _fail(f"--methods: unknown method '{n}'; valid methods are: {', '.join(valid)}")
    return names


def save_figure_atomically(fig, out: Path, dpi: int = 130) -> Path:
    """Write a matplotlib figure to ``out`` via a temporary file in the same folder, so an
    interrupted or failed write never leaves a half-written file under the final name."""
    out = Path(out)
    if out.is_dir():
        _fail(f"--out {out}: is a directory; give a file name such as {out / 'regions.png'}")
    suffix = out.suffix.lower().lstrip(".")
    if suffix not in {"png", "svg", "pdf", "jpg", "jpeg"}:
        _fail(f"--out {out}: unsupported image format '{out.suffix}'; use .png, .svg, .pdf or .jpg")
    parent = out.parent if str(out.parent) else Path(".")
    try:
        parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{out.name}.", suffix=out.suffix, dir=parent)
    except OSError as e:
        _fail(f"--out {out}: cannot write there ({e.strerror})")
    os.close(fd)
    try:
        fig.savefig(tmp, dpi=dpi, format=suffix, bbox_inches="tight")
        os.replace(tmp, out)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return out


@app.command()
def methods() -> None:
    """List the integration methods of the registry."""
    import kinema

    table = Table(title="kinema methods")
    for col in ("name", "order", "kind", "f evals/step", "summary"):
        table.add_column(col)
    for m in kinema.methods():
        table.add_row(m.name, str(m.order), m.kind, str(m.evals_per_step), m.summary)
    console.print(table)


@app.command()
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
    path = save_figure_atomically(fig, out)
    plt.close(fig)
    table = Table(title="stable intervals of z = hλ")
    for col in ("method", "real axis", "imaginary axis"):
        table.add_column(col)
    for n in names:
        r = kinema.stability.real_interval(n)
        i = kinema.stability.imag_interval(n)
        table.add_row(n, f"[{r.lo:.4f}, {r.hi:.4f}]", "none" if i.empty else f"[{i.lo:.4f}, {i.hi:.4f}]")
    console.print(table)
    console.print(f"wrote {path}")


@app.command()
def demo(
    out: Annotated[Path, typer.Option(help="Folder for the pictures.")] = Path("out"),
) -> None:
    """Integrate a problem with every method; plot stability regions and convergence."""
    from .demo import run_demo

    if out.exists() and not out.is_dir():
        _fail(f"--out {out}: exists and is not a folder")
    run_demo(out, console)


def _progress():
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    return Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("frames"),
        TimeElapsedColumn(),
        TextColumn("ETA"),
        TimeRemainingColumn(),
        console=err_console,
        transient=False,
    )


def _guarded(fn):
    """Run a command body, turning known failures into one line and an exit code."""
    import functools

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
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
                err_console.print(f"[bold red]error:[/] {line}", highlight=False, soft_wrap=True)
            raise typer.Exit(2) from None
        except (ValueError, OSError) as e:  # TrajectoryFileError is a ValueError
            text = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
            if isinstance(e, OSError) and e.filename:
                text = f"cannot write {e.filename}: {e.strerror}"
            _fail(text)
        except KeyboardInterrupt:
            _fail("interrupted; nothing was written", code=130)
        except Exception as e:
            if os.environ.get("KINEMA_DEBUG"):
                raise
            _fail(f"unexpected {type(e).__name__}: {e} (set KINEMA_DEBUG=1 for the traceback)", code=1)

    return wrapper


def _render_video(traj, path: Path, render_opts: dict, fps: float | None, description: str, draw_colliders: bool = True) -> Path:
    """Render ``traj`` to ``path`` (.mp4 or .gif) with a progress bar over the frames; the
    trajectory's colliders are drawn unless ``draw_colliders`` (or the option of that name in
    ``render_opts``) is False."""
    from .render import render_frames, write_video

    render_opts = dict(render_opts)
    draw_colliders = render_opts.pop("draw_colliders", draw_colliders)
    render_opts.setdefault("colliders", getattr(traj, "colliders", None) if draw_colliders else None)
    if fps is None:
        fps = 1.0 / float(np.median(np.diff(traj.t))) if traj.t.size > 1 else 30.0
    radius = traj.radii
    if radius is None or not np.any(radius > 0):
        extent = float(np.ptp(traj.positions.reshape(-1, 3), axis=0).max()) or 1.0
        radius = np.full(traj.positions.shape[1], extent / 200.0)
    frames = render_frames(traj.positions, radius, traj.t, dim=traj.dim, velocities=traj.velocities, **render_opts)
    with _progress() as bar:
        task = bar.add_task(description, total=len(traj.t))

        def counted():
            for f in frames:
                yield f
                bar.advance(task)

        return write_video(counted(), path, fps=fps)


def _energy_plot(traj, out: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_e, ax_p) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    traj.plot_energy(ax=ax_e)
    ax_e.set_xlabel("")
    for k, axis in enumerate("xyz"[: traj.dim]):
        ax_p.plot(traj.t, traj.momentum[:, k], label=f"p_{axis}")
    ax_p.set_xlabel("t (s)")
    ax_p.set_ylabel("momentum (kg·m/s)")
    ax_p.legend(fontsize="small")
    ax_p.grid(True, alpha=0.3)
    try:
        return save_figure_atomically(fig, out)
    finally:
        plt.close(fig)


def _outdir(out: Path) -> Path:
    if out.exists() and not out.is_dir():
        raise ValueError(f"-o {out}: exists and is not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ValueError(f"-o {out}: cannot create the folder ({e.strerror})") from None
    if not os.access(out, os.W_OK | os.X_OK):
        raise ValueError(f"-o {out}: the folder is not writable")
    return out


@app.command()
@_guarded
def run(
    scene: Annotated[Path, typer.Argument(help="Scene file (.toml), see docs/scenes.md.")],
    out: Annotated[Path | None, typer.Option("--out", "-o", help="Output folder (default: out/<scene name>).")] = None,
    duration: Annotated[float | None, typer.Option(help="Simulated time, s (default: the scene's [world].duration).")] = None,
    no_video: Annotated[bool, typer.Option("--no-video", help="Skip the video.")] = False,
) -> None:
    """Simulate a scene; write the trajectory (H5MD), a video and an energy/momentum plot."""
    simulate_scene(scene, out if out is not None else Path("out") / scene.stem, duration, no_video)


def simulate_scene(scene: Path, outdir: Path, duration: float | None = None, no_video: bool = False) -> tuple[Any, list[Path]]:
    """`kinema run`'s work: load ``scene``, simulate ``duration`` s (default: the scene's) with
    a progress bar, and write what its [output] table asks for into the folder ``outdir``
    (created when the scene is valid): trajectory.h5, <scene name>.mp4|.gif, energy.png, all
    or none. Returns the trajectory and the paths written."""
    import shutil
    import warnings

    from .scene import load_scene

    world = load_scene(scene)
    sc = world.scene
    seconds = sc.world.duration if duration is None else duration
    if not (np.isfinite(seconds) and seconds >= 0):
        raise ValueError(f"--duration {seconds}: give a finite number of seconds >= 0")
    outdir = _outdir(outdir)
    fps = sc.world.fps
    per_frame = max(1, round(1.0 / (fps * world.dt)))
    frames = int(np.floor(seconds / (per_frame * world.dt) + 1e-9))
    console.print(f"{scene}: {len(world)} particles, dim {world.dim}, {world.method}, dt = {world.dt:g} s, {seconds:g} s, {frames + 1} frames")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with _progress() as bar:
                task = bar.add_task("simulating", total=frames)
                traj = world.run(seconds, fps=fps, callback=lambda _w: bar.advance(task))
        finally:  # a StabilityWarning explains a divergence: show it before the error
            for w in caught:
                err_console.print(f"[yellow]warning:[/] {w.message}", highlight=False, soft_wrap=True)
    stats = world.collision_stats()
    if stats is not None:
        total = stats["total"]
        console.print(f"{total['impacts']} impacts inside steps, {total['energy_lost']:.4g} J taken by the collisions", highlight=False)
    # Everything is written in a hidden folder inside OUTDIR and moved into place at the end,
    # so a failure leaves no file half-written and none of this run's files at all.
    stage = Path(tempfile.mkdtemp(prefix=".kinema-run.", dir=outdir))
    written: list[Path] = []
    try:
        names = []
        if sc.output.trajectory:
            traj.save(stage / "trajectory.h5")
            names.append("trajectory.h5")
        video = sc.output.video
        if video and not no_video:
            opts = sc.render.model_dump(exclude={"fps", "camera"})
            opts["camera"] = _camera(sc.render.camera)
            _render_video(traj, stage / f"{scene.stem}.{video}", opts, sc.render.fps, "rendering")
            names.append(f"{scene.stem}.{video}")
        if sc.output.plot:
            _energy_plot(traj, stage / "energy.png")
            names.append("energy.png")
        from .io._files import _umask

        for name in names:
            os.chmod(stage / name, 0o666 & ~_umask())
            os.replace(stage / name, outdir / name)
            written.append(outdir / name)
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    for path in written:
        console.print(f"wrote {path}", highlight=False, soft_wrap=True)
    return traj, written


def _camera(table):
    from .render import Camera2D, Camera3D

    if table is None:
        return None
    if table.type == "2d":
        return Camera2D(table.xmin, table.ymin, table.xmax, table.ymax)
    return Camera3D(tuple(table.eye), tuple(table.target), tuple(table.up), table.fov_deg)


@app.command()
@_guarded
def render(
    traj: Annotated[Path, typer.Argument(help="Trajectory file (H5MD, from kinema run or Trajectory.save).")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Video to write: .mp4 (H.264) or .gif.")],
    fps: Annotated[float | None, typer.Option(help="Frames per second (default: real time).")] = None,
    width: Annotated[int, typer.Option(help="Width, pixels.")] = 640,
    height: Annotated[int, typer.Option(help="Height, pixels.")] = 480,
    color_by: Annotated[str, typer.Option(help="speed or id.")] = "speed",
) -> None:
    """Render a saved trajectory to a video."""
    from .render import VIDEO_EXTENSIONS
    from .trajectory import Trajectory

    if out.suffix.lower() not in VIDEO_EXTENSIONS:
        raise ValueError(f"-o {out}: unsupported video format {out.suffix or '(none)'!r}; use .mp4 or .gif")
    if out.is_dir():
        raise ValueError(f"-o {out}: is a directory; give a file name such as {out / 'movie.mp4'}")
    if not out.parent.is_dir() if str(out.parent) else False:
        raise ValueError(f"-o {out}: the folder {out.parent} does not exist")
    if color_by not in ("speed", "id"):
        raise ValueError(f"--color-by {color_by!r}: use speed or id")
    if not (16 <= width <= 8192 and 16 <= height <= 8192):
        raise ValueError(f"--width {width} --height {height}: each must be between 16 and 8192 pixels")
    if fps is not None and not (np.isfinite(fps) and fps > 0):
        raise ValueError(f"--fps {fps}: give a number of frames per second > 0")
    t = Trajectory.load(traj)
    path = _render_video(t, out, {"width": width, "height": height, "color_by": color_by}, fps, "rendering")
    console.print(f"wrote {path}", highlight=False, soft_wrap=True)


@app.command()
@_guarded
def export(
    traj: Annotated[Path, typer.Argument(help="Trajectory file (H5MD).")],
    format: Annotated[str, typer.Option("--format", "-f", help="vtk (ParaView), ply (Blender), xyz (OVITO), csv.")],
    out: Annotated[Path | None, typer.Option("--out", "-o", help="Main output file (default: beside TRAJ).")] = None,
) -> None:
    """Export a saved trajectory for other programs."""
    from .io import FORMATS
    from .io import export as write_export
    from .trajectory import Trajectory

    if format not in FORMATS:
        raise ValueError(f"--format {format!r}: use one of {', '.join(FORMATS)}")
    suffix = {"vtk": ".pvd", "ply": ".ply", "xyz": ".xyz", "csv": ".csv"}[format]
    t = Trajectory.load(traj)
    with _progress() as bar:
        task = bar.add_task(f"writing {format}", total=len(t.t))
        paths = write_export(t, out if out is not None else traj.with_suffix(suffix), format, on_frame=lambda _i: bar.advance(task))
    console.print(f"wrote {paths[0]}" + (f" and {len(paths) - 1} more files" if len(paths) > 1 else ""), highlight=False, soft_wrap=True)


@app.command()
@_guarded
def view(
    source: Annotated[Path, typer.Argument(help="A trajectory file (H5MD) or a scene (.toml, run first).")],
    html: Annotated[Path | None, typer.Option("--html", help="Write one self-contained page that plays offline, and exit.")] = None,
    port: Annotated[int, typer.Option(help="Port on 127.0.0.1 (0: a free one).")] = 0,
    no_browser: Annotated[bool, typer.Option("--no-browser", help="Do not open a browser.")] = False,
) -> None:
    """Play a trajectory in the browser (three.js): play/pause, scrub, speed, orbit camera, colouring.

    Serves the page on 127.0.0.1 (the URL is printed) until Ctrl-C, which stops the server and
    exits 0; with --html, writes the page to a file instead."""
    import time

    from .trajectory import Trajectory
    from .viewer import BundleMissingError, serve, write_html

    if not 0 <= port <= 65535:
        raise ValueError(f"--port {port}: use 0 (a free port) or a port from 1 to 65535")
    if not source.exists():
        raise ValueError(f"{source}: no such file")
    if source.is_dir():
        raise ValueError(f"{source}: is a directory; give a trajectory (.h5) or a scene (.toml)")
    if source.suffix.lower() == ".toml":
        from .scene import load_scene

        world = load_scene(source)
        settings = world.scene.world
        with _progress() as bar:
            task = bar.add_task("simulating", total=max(1, round(settings.duration * settings.fps)))
            traj = world.run(settings.duration, fps=settings.fps, callback=lambda w: bar.advance(task))
    else:
        traj = Trajectory.load(source)
    if html is not None:
        path = write_html(traj, html)
        console.print(f"wrote {path}", highlight=False, soft_wrap=True)
        return
    try:
        url, server = serve(traj, open_browser=not no_browser, port=port)
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


def main() -> None:
    """Entry point of the ``kinema`` script."""
    app()


if __name__ == "__main__":
    main()
