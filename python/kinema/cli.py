"""The ``kinema`` command (``python -m kinema`` is the same).

Exit codes: 0 done, 2 bad input (the message says what and where: a scene or trajectory file,
an option, an output path that cannot be written, work over the limits below without
--force), 1 a simulation that diverged (the message names the step and the advisor's step).
Errors are one line on stderr, never a traceback; ``KINEMA_DEBUG=1`` re-raises unexpected errors.

Work limits: ``run``, ``view`` (of a scene) and ``render`` estimate their work before doing any
(particles × steps, video frames × pixels, memory) and refuse, unless given ``--force``,
more than ``LIMIT_PARTICLE_STEPS`` particle-steps, ``LIMIT_PIXELS`` pixels or
``LIMIT_MEMORY`` bytes; more than ``MAX_STEPS`` steps are refused even with ``--force``.
"""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.console import Console
from rich.markup import escape
from rich.table import Table

app = typer.Typer(
    name="kinema",
    help="kinema: particle systems that move by honest numerical methods.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
    rich_markup_mode=None,  # click's plain help: typer 0.29's rich help prints <bool> beside every flag
)
console = Console()
err_console = Console(stderr=True)


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


# -- work estimate ----------------------------------------------------------------------------
# Every example scene and `kinema demo` is four orders of magnitude below these (the most:
# sand_box, 4e6 particle-steps and 17 MiB; demo, 6e7 pixels of video); they stop runs that
# would take most of a day or more, or more memory than a laptop has, such as count = 1e9 or
# duration = 1e9 s at dt = 1e-3, before any of the work (or the allocation) is done.
LIMIT_PARTICLE_STEPS = 1e11  # 5 hours at 6e6 particle-steps a second (maxwell_gas), days in a heap of contacts (demo: 2e5/s)
LIMIT_PIXELS = 1e11  # frames × width × height: 16 minutes of 1080p at 30 fps; rendering runs at about 5e8 pixels a second, encoding slower
LIMIT_MEMORY = 8 * 2**30  # bytes
VIDEO_FPS = (0.01, 1000.0)  # playback frames per second asked; a GIF writes the nearest of 100/d, d = 2 … 65535 (kinema.render.video_rate)
MAX_STEPS = 10**18  # even with --force: the engine counts steps in 64 bits; 1e18 is 30 years at 1e9 steps a second
ENGINE_BYTES = 1024  # per particle: state, the method's stages, collision grid and lists (measured 400-800)
FRAME_BYTES = 96  # per particle and recorded frame: positions and velocities (48 B), held twice while the trajectory is assembled
RENDER_BYTES = 32  # per particle and frame while rendering: the renderer's copy of the positions, the speeds


def _count(n: int, noun: str) -> str:
    """``1 particle``, ``2 particles``, ``1,000 frames``."""
    return f"{n:,} {noun}" + ("" if n == 1 else "s")


def _size(n: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if n < 1024 or unit == "PiB":
            return f"{n:.0f} {unit}" if unit == "B" or n >= 10 else f"{n:.1f} {unit}"
        n /= 1024
    return ""  # unreachable


def _frames_and_steps(seconds: float, dt: float, fps: float) -> tuple[float, float]:
    """Recorded frames after the first, and steps, as ``World.run`` takes them (floats: they
    may be far too many to count)."""
    per_frame = max(1, round(1.0 / (fps * dt)))
    frames = float(np.floor(seconds / (per_frame * dt) + 1e-9))
    return frames, frames * per_frame


def _over_limits(what: str, estimate: str, particle_steps: float, pixels: float, memory: float, force: bool) -> None:
    """Refuse (``ValueError``, exit 2) work over a limit unless ``force``."""
    if force or (particle_steps <= LIMIT_PARTICLE_STEPS and pixels <= LIMIT_PIXELS and memory <= LIMIT_MEMORY):
        return
    limits = f"{LIMIT_PARTICLE_STEPS:.0e} particle-steps, {LIMIT_PIXELS:.0e} pixels and {_size(LIMIT_MEMORY)} of memory"
    raise ValueError(f"{what}: {estimate}, over the limits of {limits}; give --force to run it anyway")


def _scene_work(scene: Any, path: Path, seconds: float, duration_key: str, video: bool, force: bool) -> str:
    """Estimate the work of simulating ``scene`` (read from ``path``) for ``seconds`` (and
    rendering its video when ``video``), refuse it when over the limits unless ``force``, and
    return the estimate in words. Nothing is built: the particles are counted from the blocks."""
    from .scene import block_size

    w = scene.world
    frames, steps = _frames_and_steps(seconds, w.dt, w.fps)
    why = f"{duration_key} = {seconds:g} s at world.dt = {w.dt:g} s"
    if not steps <= MAX_STEPS:
        raise ValueError(f"{path}: the run would take {steps:.1e} steps ({why}), more than can be counted ({MAX_STEPS:.0e}), even with --force")
    n = scene.particle_count()
    if scene.particles:  # name the largest block, where the particles come from
        size, k = max((block_size(b), k) for k, b in enumerate(scene.particles))
        block = scene.particles[k]
        if block.type == "random":
            why += f"; particles[{k}].count = {block.count}"
        elif block.type == "lattice":
            why += f"; particles[{k}].counts = {block.counts}"
        else:
            why += f"; {size:,} particles[{k}].positions"
        if len(scene.particles) > 1:
            why += f", the largest of {len(scene.particles)} blocks"
    born = scene.emitted_count(seconds)
    if born:
        why += f"; up to {born:,} particles from {len(scene.emitters)} emitter{'s' if len(scene.emitters) > 1 else ''}"
        n += born
    particle_steps = float(n) * steps
    pixels = (frames + 1) * scene.render.width * scene.render.height if video and n else 0.0
    memory = n * ENGINE_BYTES + (frames + 1) * n * (FRAME_BYTES + (RENDER_BYTES if pixels else 0))
    video_words = f"{frames + 1:,.0f} frames × render.width {scene.render.width} × render.height {scene.render.height}"
    estimate = f"the run would take {particle_steps:.1e} particle-steps ({n:,} particles × {steps:,.0f} steps: {why})"
    if pixels:
        estimate += f", {pixels:.1e} pixels of video ({video_words})"
    estimate += f" and about {_size(memory)} of memory"
    _over_limits(str(path), estimate, particle_steps, pixels, memory, force)
    return f"{particle_steps:.1e} particle-steps" + (f", {pixels:.1e} pixels of video" if pixels else "") + f", about {_size(memory)} of memory"


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
    from .io._files import TrajectoryFileError, atomic_file

    parent = out.parent if str(out.parent) else Path(".")
    try:
        parent.mkdir(parents=True, exist_ok=True)
        with atomic_file(out) as tmp:  # the mode an ordinary open() gives (mkstemp's was 0600)
            fig.savefig(tmp, dpi=dpi, format=suffix, bbox_inches="tight")
    except TrajectoryFileError as e:  # (an OSError of the write, naming the file)
        _fail(f"--out {out}: {e}")
    except OSError as e:
        _fail(f"--out {out}: cannot write there ({e.strerror or e})")
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
        table.add_row(n, *("none" if a.empty else f"[{a.lo + 0.0:.4f}, {a.hi + 0.0:.4f}]" for a in (r, i)))  # (+ 0.0: no "-0.0000")
    console.print(table)
    console.print(f"wrote {path}")


@app.command()
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

    return wrapper


def _render_video(
    traj, path: Path, render_opts: dict, fps: float | None, description: str, draw_colliders: bool = True, scene_fps: float | None = None
) -> Path:
    """Render ``traj`` to ``path`` (.mp4 or .gif) with a progress bar over the frames; the
    trajectory's colliders are drawn unless ``draw_colliders`` (or the option of that name in
    ``render_opts``) is False.

    ``fps``: one video frame per recorded frame at this rate. None: real time, the frames
    placed by their times (``write_video(times=)``), at the ``scene_fps`` the scene asked for
    (World.run records every round(1/(fps·dt)) steps, 33 ms for 30 fps and dt = 1 ms, so one
    frame in about a hundred is dropped to play 30.30 recorded frames a second at exactly 30),
    or, without it or when the recording interval is not that rate's rounding (clamped to one
    step), at the recording's own rate (clamped to ``VIDEO_FPS``, and then not real time). The
    rate written (``kinema.render.video_rate``: GIF counts in 1/100 s) is printed."""
    from .render import _trajectory_options, own_colours, render_frames, video_rate, write_video

    render_opts = dict(render_opts)
    draw_colliders = render_opts.pop("draw_colliders", draw_colliders)
    render_opts.setdefault("colliders", getattr(traj, "colliders", None) if draw_colliders else None)
    times, timing = None, "one video frame per recorded frame"
    recorded = 1.0 / float(np.median(np.diff(traj.t))) if traj.t.size > 1 else float("nan")
    if fps is None and scene_fps is not None and VIDEO_FPS[0] <= scene_fps <= VIDEO_FPS[1] and 0.5 <= recorded / scene_fps <= 1.5:
        fps, times, timing = scene_fps, traj.t, f"real time, {recorded:.4g} recorded frames a second placed by their times"
    elif fps is None:  # real time, within what the video formats can play
        fps = min(max(recorded, VIDEO_FPS[0]), VIDEO_FPS[1]) if np.isfinite(recorded) else 30.0
        if fps == recorded:  # placed by their times: GIF delays round, the times need not be even
            times, timing = traj.t, "real time at the recording's rate"
    # The radii (or a stand-in), the alive mask and the springs (ids → columns).
    for name, value in _trajectory_options(traj).items():
        render_opts.setdefault(name, value)
    if isinstance(render_opts.get("color_by"), str) and render_opts["color_by"] == "color":  # each particle's own
        render_opts["color_by"] = own_colours(traj)
    frames = render_frames(traj.positions, t=traj.t, dim=traj.dim, velocities=traj.velocities, **render_opts)
    with _progress() as bar:
        task = bar.add_task(description, total=len(traj.t))

        def counted():
            for f in frames:
                yield f
                bar.advance(task)

        written = write_video(counted(), path, fps=fps, times=times)
    rate = video_rate(fps, path)
    exact = f"{rate} fps" if rate.denominator == 1 else f"{float(rate):.4g} fps ({rate})"
    console.print(f"video: {exact}, {timing}", highlight=False, soft_wrap=True)
    return written


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
    force: Annotated[bool, typer.Option("--force", help="Run even when the work estimate is over the limits.")] = False,
    checkpoint_every: Annotated[
        float | None, typer.Option("--checkpoint-every", help="Write OUT/checkpoint.ckpt every this many simulated seconds (whole frames).")
    ] = None,
    resume: Annotated[bool, typer.Option("--resume", help="Go on from OUT/checkpoint.ckpt, left by a run with --checkpoint-every that stopped.")] = False,
) -> None:
    """Simulate a scene; write the trajectory (H5MD), a video and an energy/momentum plot.

    The work is estimated first (particles × steps, video pixels, memory); a run over the
    limits is refused unless --force is given. With --checkpoint-every T the world and the
    frames so far are written to OUT/checkpoint.ckpt every T s of simulated time (removed when
    the run ends well); --resume goes on from it, to the same files, bit for bit."""
    simulate_scene(
        scene, out if out is not None else Path("out") / scene.stem, duration, no_video, force=force, checkpoint_every=checkpoint_every, resume=resume
    )


def simulate_scene(
    scene: Path,
    outdir: Path,
    duration: float | None = None,
    no_video: bool = False,
    *,
    force: bool = False,
    checkpoint_every: float | None = None,
    resume: bool = False,
) -> tuple[Any, list[Path]]:
    """`kinema run`'s work: load ``scene``, simulate ``duration`` s (default: the scene's) with
    a progress bar, and write what its [output] table asks for into the folder ``outdir``
    (created when the scene is valid): trajectory.h5, <scene name>.mp4|.gif, energy.png, all
    or none. Work over the limits (module docstring) is refused before any is done unless
    ``force``. Staging folders left in ``outdir`` by runs that were killed are removed.
    Returns the trajectory and the paths written."""
    import shutil
    import warnings

    from .scene import Scene

    sc = Scene.from_toml(scene)
    seconds = sc.world.duration if duration is None else duration
    if not (np.isfinite(seconds) and seconds >= 0):
        raise ValueError(f"--duration {seconds}: give a finite number of seconds >= 0")
    video = sc.output.video if not no_video else False
    estimate = _scene_work(sc, scene, seconds, "world.duration" if duration is None else "--duration", bool(video), force)
    world = sc.build(source=str(scene))
    outdir = _outdir(outdir)
    _remove_stale_stages(outdir)
    fps = sc.world.fps
    frames = int(_frames_and_steps(seconds, world.dt, fps)[0])
    console.print(
        f"{scene}: {_count(len(world), 'particle')}, dim {world.dim}, {world.method}, dt = {world.dt:g} s, {seconds:g} s, "
        f"{_count(frames + 1, 'frame')}; work: {estimate}",
        highlight=False,
        soft_wrap=True,
    )
    ckpt = outdir / "checkpoint.ckpt"
    if checkpoint_every is not None and not (np.isfinite(checkpoint_every) and checkpoint_every > 0):
        raise ValueError(f"--checkpoint-every {checkpoint_every}: give a finite number of simulated seconds > 0")
    if resume and not ckpt.is_file():
        raise ValueError(f"--resume: there is no checkpoint to resume in {outdir} ({ckpt.name}; a run with --checkpoint-every writes it)")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with _progress() as bar:
                if resume:
                    from .checkpoint import resume_run, run_progress

                    done, total = run_progress(ckpt)
                    task = bar.add_task("simulating (resumed)", total=total + 1, completed=done + 1)
                    world, traj = resume_run(ckpt, callback=lambda _w: bar.advance(task))
                else:
                    task = bar.add_task("simulating", total=frames + 1, completed=1)  # the frame at t = 0 is recorded first
                    saving = {"checkpoint": ckpt, "checkpoint_every": checkpoint_every} if checkpoint_every is not None else {}
                    traj = world.run(seconds, fps=fps, callback=lambda _w: bar.advance(task), **saving)
        finally:  # a StabilityWarning explains a divergence: show it before the error
            for w in caught:
                err_console.print(f"[yellow]warning:[/] {escape(str(w.message))}", highlight=False, soft_wrap=True)
    stats = world.collision_stats()
    if stats is not None:
        total = stats["total"]
        console.print(f"{total['impacts']} impacts inside steps, {total['energy_lost']:.4g} J taken by the collisions", highlight=False)
    # Everything is written in a hidden folder inside OUTDIR and moved into place at the end,
    # so a failure leaves no file half-written and none of this run's files at all.
    stage = Path(tempfile.mkdtemp(prefix=_stage_prefix(), dir=outdir))
    written: list[Path] = []
    try:
        names = []
        if sc.output.trajectory:
            traj.save(stage / "trajectory.h5")
            names.append("trajectory.h5")
        if video:
            opts = sc.render.model_dump(exclude={"fps", "camera"})
            opts["camera"] = _camera(sc.render.camera)
            _render_video(traj, stage / f"{scene.stem}.{video}", opts, sc.render.fps, "rendering", scene_fps=fps)
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
    if checkpoint_every is not None or resume:
        ckpt.unlink(missing_ok=True)  # the run is whole: its files are written
    for path in written:
        console.print(f"wrote {path}", highlight=False, soft_wrap=True)
    return traj, written


# A run writes into a hidden staging folder .kinema-run.<host>-<pid>.<random> in its output
# folder; a run that is killed (kill -9, power off) leaves it behind, and the next run into the
# folder removes it once the process that made it is gone.
_STAGE = re.compile(r"\.kinema-run\.(?:(?P<host>[A-Za-z0-9-]*)-(?P<pid>[0-9]+)\.)?[A-Za-z0-9_]+")
STALE_UNKNOWN_OWNER_S = 86400.0  # a staging folder without a pid in its name (older kinema) is stale after a day


def _host() -> str:
    import socket

    return re.sub(r"[^A-Za-z0-9-]", "-", socket.gethostname())[:64]


def _stage_prefix() -> str:
    return f".kinema-run.{_host()}-{os.getpid()}."


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    except (OverflowError, ValueError, OSError):
        return False
    return True


def _remove_stale_stages(outdir: Path) -> list[Path]:
    """Remove the staging folders in ``outdir`` whose run is over (its process is gone); keep
    those of live runs and of other hosts. Returns the folders removed."""
    import shutil
    import time

    removed = []
    try:
        entries = [e for e in os.scandir(outdir) if e.name.startswith(".kinema-run.")]
    except OSError:
        return removed
    host = _host()
    for entry in entries:
        m = _STAGE.fullmatch(entry.name)
        if m is None or not entry.is_dir(follow_symlinks=False):
            continue
        if m["pid"] is not None:
            stale = m["host"] == host and int(m["pid"]) != os.getpid() and not _alive(int(m["pid"]))
        else:
            try:
                stale = time.time() - entry.stat(follow_symlinks=False).st_mtime > STALE_UNKNOWN_OWNER_S
            except OSError:
                stale = False
        if stale:
            shutil.rmtree(entry.path, ignore_errors=True)
            removed.append(Path(entry.path))
    return removed


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
    color_by: Annotated[str, typer.Option(help="speed, id or color (each particle's own: an emitter's color).")] = "speed",
    force: Annotated[bool, typer.Option("--force", help="Render even when the work estimate is over the limits.")] = False,
) -> None:
    """Render a saved trajectory to a video.

    The work is estimated first (frames × pixels, memory); a video over the limits is refused
    unless --force is given."""
    from .render import VIDEO_EXTENSIONS
    from .trajectory import Trajectory

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
    t = Trajectory.load(traj)
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


@app.command()
@_guarded
def export(
    traj: Annotated[Path, typer.Argument(help="Trajectory file (H5MD).")],
    format: Annotated[
        str,
        typer.Option(
            "--format", "-f", help="vtk (ParaView), ply (Blender), xyz (OVITO, ASE), csv, gsd (HOOMD, OVITO), lammps (a LAMMPS dump), usd (Blender, Houdini)."
        ),
    ],
    out: Annotated[
        Path | None,
        typer.Option("--out", "-o", help="Main output file; missing folders are created (default: beside TRAJ, named as below)."),
    ] = None,
) -> None:
    """Export a saved trajectory for other programs.

    Beside TRAJ (run.h5) unless -o names another file: vtk writes run.pvd (open it in
    ParaView or OVITO), its frames in the folder run_vtk/ and the colliders in
    run_colliders.vtp; ply one file a frame in the folder
    run_ply/ (run_00000.ply, ...); xyz run.xyz (extended XYZ, SI units); csv run.csv; gsd
    run.gsd; lammps run.lammpstrj (dump custom); usd run.usd (Blender, Houdini; needs
    pip install kinema[usd]). So the formats never overwrite each other.
    A suffix of -o that names another format (-f vtk -o x.ply) is refused."""
    from .io import FORMATS
    from .io import export as write_export
    from .io.exports import SUFFIX, default_path, suffix_format
    from .trajectory import Trajectory

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
    t = Trajectory.load(traj)
    if path.exists() and os.path.samefile(path, traj):
        raise ValueError(f"-o {path}: is the trajectory being exported; name another file")
    if not path.parent.is_dir():  # as `kinema run -o` makes its folder
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise ValueError(f"-o {out}: cannot create the folder {path.parent} ({e.strerror or e})") from None
    with _progress() as bar:
        task = bar.add_task(f"writing {format}", total=len(t.t))
        paths = write_export(t, path, format, on_frame=lambda _i: bar.advance(task))
    # The main files beside PATH, then a series folder's frames as a count.
    main = [str(p) for p in paths if p.parent == path.parent]
    frames = [p for p in paths if p.parent != path.parent]
    if frames:
        main.append(f"{len(frames)} frames in {frames[0].parent}{os.sep}")
    console.print("wrote " + " and ".join(main), highlight=False, soft_wrap=True)


@app.command()
@_guarded
def sweep(
    scene: Annotated[Path, typer.Argument(help="Scene file (.toml): the base of every member.")],
    vary: Annotated[
        list[str] | None,
        typer.Option("--vary", help="KEY=V1,V2,... : a scene key path and its values (TOML values); repeat for a grid."),
    ] = None,
    seeds: Annotated[int | None, typer.Option("--seeds", help="Members per point of the grid, each with its own seed (0 … N−1).", min=1)] = None,
    out: Annotated[Path | None, typer.Option("--out", "-o", help="Sweep folder (default: out/<scene name>_sweep); rerun into it to resume.")] = None,
    scheduler: Annotated[str | None, typer.Option("--scheduler", help="A Dask scheduler's address (tcp://host:8786); default: worker processes here.")] = None,
    workers: Annotated[int | None, typer.Option("--workers", help="Local worker processes (default: the cores).", min=1)] = None,
    duration: Annotated[float | None, typer.Option(help="Simulated time of each member, s (default: the scene's).")] = None,
    checkpoint_every: Annotated[
        float | None, typer.Option("--checkpoint-every", help="Each member writes a checkpoint this often (simulated s); a rerun resumes from it.")
    ] = None,
) -> None:
    """Run a parameter sweep or ensemble on Dask: every combination of the --vary values ×
    --seeds, each member a scene with those keys set (validated first), run, saved (H5MD)
    and measured. Writes summary.csv (one row per member), timings.csv and summary.png into
    the folder; members already finished there are skipped (resume). See docs/sweeps.md."""
    from .sweeps import parse_values
    from .sweeps import sweep as run_sweep

    grid = {}
    for item in vary or []:
        key, eq, values = item.partition("=")
        if not eq or not key.strip():
            raise ValueError(f"--vary {item!r}: use KEY=V1,V2,... (e.g. collisions.restitution=0.5,0.7,0.9)")
        try:
            grid[key.strip()] = parse_values(values)
        except ValueError as e:
            raise ValueError(f"--vary {item!r}: {e}") from None
    folder = out if out is not None else Path("out") / f"{scene.stem}_sweep"
    result = run_sweep(scene, grid, seeds=seeds, client=scheduler, out=folder, duration=duration, workers=workers, checkpoint_every=checkpoint_every)
    failed = result.failed
    console.print(f"{len(result.rows)} members, {len(failed)} failed; wrote {folder / 'summary.csv'}", highlight=False, soft_wrap=True)
    for row in failed:
        err_console.print(f"[bold red]failed:[/] {escape(row['member'])}: {escape(row['error'])}", highlight=False, soft_wrap=True)
    if failed:
        raise typer.Exit(1)


@app.command()
@_guarded
def view(
    source: Annotated[Path, typer.Argument(help="A trajectory file (H5MD) or a scene (.toml, run first).")],
    html: Annotated[Path | None, typer.Option("--html", help="Write one self-contained page that plays offline, and exit.")] = None,
    port: Annotated[int, typer.Option(help="Port on 127.0.0.1 (0: a free one).")] = 0,
    no_browser: Annotated[bool, typer.Option("--no-browser", help="Do not open a browser.")] = False,
    force: Annotated[bool, typer.Option("--force", help="Simulate a scene even when the work estimate is over the limits.")] = False,
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
        from .scene import Scene

        sc = Scene.from_toml(source)
        _scene_work(sc, source, sc.world.duration, "world.duration", False, force)
        world = sc.build(source=str(source))
        settings = sc.world
        with _progress() as bar:
            frames = int(_frames_and_steps(settings.duration, world.dt, settings.fps)[0])
            task = bar.add_task("simulating", total=frames + 1, completed=1)  # the frame at t = 0 is recorded first
            traj = world.run(settings.duration, fps=settings.fps, callback=lambda w: bar.advance(task))
    else:
        traj = Trajectory.load(source)
    if html is not None:
        path = write_html(traj, html)
        console.print(f"wrote {path}", highlight=False, soft_wrap=True)
        return
    try:
        url, server = serve(traj, open_browser=not no_browser, port=port, announce=False)
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
