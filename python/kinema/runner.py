"""Running a scene to its files, the library side of ``kinema run`` (and of ``kinema demo``,
``kinema view`` of a scene, ``kinema render``): the work estimate and its limits, the staging
folder, the simulation with its progress bar, the video, the energy plot, figures written
atomically; and the consoles (stdout, stderr) all of them print to. The CLI's error
formatting (one line, an exit code) is kinema.cli's: failures here are exceptions.

Work limits: ``run``, ``view`` (of a scene) and ``render`` estimate their work before doing any
(particles × steps, video frames × pixels, memory) and refuse, unless given ``--force``,
more than ``LIMIT_PARTICLE_STEPS`` particle-steps, ``LIMIT_PIXELS`` pixels or
``LIMIT_MEMORY`` bytes; more than ``MAX_STEPS`` steps are refused even with ``--force``.

The output folder's checks, its staging folders and contact_events.csv are in
``kinema._run_outputs``; the scene a run records and the check that --resume goes on with the
same one (``scene_digest``, importable from here too) in ``kinema._run_source``.
"""

from __future__ import annotations

import math
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console
from rich.markup import escape

from . import _core
from ._run_outputs import _contact_events_csv, _outdir, _refuse_special_outputs, _remove_checkpoints, _remove_stale_stages, _stage_prefix, _writable_file
from ._run_source import _run_source, _same_run
from ._run_source import scene_digest as scene_digest
from .frames import MAX_WORK
from .frames import plan as frames_plan

console = Console()
err_console = Console(stderr=True)


class OutputError(ValueError):
    """An output file that cannot be written where it was asked (``save_figure_atomically``):
    the message names the option and the file; the CLI prints it as one line, exit 2."""


# -- work estimate ----------------------------------------------------------------------------
# Every example scene and `kinema demo` is four orders of magnitude below these (the most:
# sand_box, 4e6 particle-steps and 17 MiB; demo, 6e7 pixels of video); they stop runs that
# would take most of a day or more, or more memory than a laptop has, such as count = 1e9 or
# duration = 1e9 s at dt = 1e-3, before any of the work (or the allocation) is done.
LIMIT_PARTICLE_STEPS = (
    MAX_WORK  # (kinema.world.MAX_WORK, World.run's own default) 5 hours at 6e6 particle-steps a second (maxwell_gas), days in a heap of contacts (demo: 2e5/s)
)
LIMIT_PIXELS = 1e11  # frames × width × height: 16 minutes of 1080p at 30 fps; rendering runs at about 5e8 pixels a second, encoding slower
LIMIT_MEMORY = 8 * 2**30  # bytes
VIDEO_FPS = (0.01, 1000.0)  # playback frames per second asked; a GIF writes the nearest of 100/d, d = 2 … 65535 (kinema.render.video_rate)
MAX_STEPS = 10**18  # even with --force: the engine counts steps in 64 bits; 1e18 is 30 years at 1e9 steps a second
ENGINE_BYTES = 2048  # per particle: state, the method's stages, collision grid (measured 400-800) and the contacts, bounded by design: the neighbour list keeps at most 128 entries (768 B) a particle (collide/neighbour_list.rs)
FRAME_BYTES = 96  # per particle and recorded frame: positions and velocities (48 B), held twice while the trajectory is assembled
RENDER_BYTES = 32  # per particle and frame while rendering: the renderer's copy of the positions, the speeds


def _counted(settings: dict, impacts: int) -> str:
    """What ``collision_stats()["total"]["impacts"]`` counts, in the words of the model of
    ``settings`` (``World.collisions``): a force model's contacts begun (it has no impacts, its
    contacts last many steps), the event-driven model's impacts, each at its time, and the
    stepped impulse model's impacts found inside steps by continuous detection (those at a
    step's end are its contacts)."""
    if settings["model"] in _core.FORCE_MODELS:
        return _count(impacts, "contact") + " begun"
    if settings["event_driven"]:
        return _count(impacts, "impact")
    return _count(impacts, "impact") + " inside steps"


def _emitter_summary(k: int, st: dict) -> str:
    """One line of a run's summary for emitter ``k`` (``World.emitter_stats``): the particles
    born of those due, and the rate achieved of the rate asked."""
    if not st["until"] > st["start"]:
        return f"emitter {k}: not started (start = {st['start']:g} s)"
    line = (
        f"emitter {k}: {st['born']:,} of {st['due']:,} particles born from t = {st['start']:g} to {st['until']:g} s, "
        f"{st['achieved_rate']:.4g}/s of the {st['rate']:g}/s asked"
    )
    lost = [f"{st[key]:,} {words}" for key, words in (("dropped", "dropped for lack of room"), ("waiting", "waiting for room")) if st[key]]
    return line + (f" ({', '.join(lost)})" if lost else "")


def _count(n: int, noun: str) -> str:
    """``1 particle``, ``2 particles``, ``1,000 frames``."""
    return f"{n:,} {noun}" + ("" if n == 1 else "s")


def _size(n: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if n < 1024 or unit == "PiB":
            if n >= 1e6:  # (PiB beyond a million: not 15 digits in a line)
                return f"{n:.3g} {unit}"
            return f"{n:.0f} {unit}" if unit == "B" or n >= 10 else f"{n:.1f} {unit}"
        n /= 1024
    return ""  # unreachable


def _frames_and_steps(seconds: float, dt: float, fps: float) -> tuple[float, float]:
    """Recorded frames after the first, and steps, as ``World.run`` takes them
    (``kinema.frames``; floats: they may be far too many to count)."""
    p = frames_plan(seconds, dt, fps)
    return float(p.frames), float(p.steps)


def _over_limits(what: str, estimate: str, particle_steps: float, pixels: float, memory: float, force: bool) -> None:
    """Refuse (``ValueError``, exit 2) work over a limit unless ``force``."""
    if force or (particle_steps <= LIMIT_PARTICLE_STEPS and pixels <= LIMIT_PIXELS and memory <= LIMIT_MEMORY):
        return
    limits = f"{LIMIT_PARTICLE_STEPS:.0e} particle-steps, {LIMIT_PIXELS:.0e} pixels and {_size(LIMIT_MEMORY)} of memory"
    raise ValueError(f"{what}: {estimate}, over the limits of {limits}; give --force to run it anyway")


def _amount(x: float) -> str:
    """A count for a message: with thousands separators up to 10¹⁵, in scientific notation
    beyond (an emitter of 10³⁰⁰ particles a second is not 300 digits in a line)."""
    return f"{x:,.0f}" if x < 1e15 else f"{float(x):.3g}"


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
    try:
        born: float = scene.emitted_count(seconds)
    except OverflowError:  # more births than a float counts (rate × duration): work no limit allows
        born = math.inf
    if born:
        why += f"; up to {_amount(born)} particles from {len(scene.emitters)} emitter{'s' if len(scene.emitters) > 1 else ''}"
        n += born
    particle_steps = float(n) * steps
    pixels = (frames + 1) * scene.render.width * scene.render.height if video and n else 0.0
    memory = n * ENGINE_BYTES + (frames + 1) * n * (FRAME_BYTES + (RENDER_BYTES if pixels else 0))
    video_words = f"{frames + 1:,.0f} frames × render.width {scene.render.width} × render.height {scene.render.height}"
    estimate = f"the run would take {particle_steps:.1e} particle-steps ({_amount(n)} particles × {_amount(steps)} steps: {why})"
    if pixels:
        estimate += f", {pixels:.1e} pixels of video ({video_words})"
    estimate += f" and about {_size(memory)} of memory"
    _over_limits(str(path), estimate, particle_steps, pixels, memory, force)
    return f"{particle_steps:.1e} particle-steps" + (f", {pixels:.1e} pixels of video" if pixels else "") + f", about {_size(memory)} of memory"


def _resume_work(ckpt: Path, scene: Any, video: bool, force: bool, path: Path | None = None, duration: float | None = None) -> tuple[str, dict]:
    """Estimate the work left to the run in progress that wrote the checkpoint ``ckpt``
    (read and checked, nothing built: ``kinema.checkpoint.run_plan``) and the video of
    ``scene`` (the scene given to ``kinema run``, read from ``path``) at its end, refuse it
    when over the limits unless ``force``, as ``_scene_work`` refuses a fresh run's; return
    the estimate in words and the checkpoint's plan. A checkpoint of another scene, or of
    another duration than the ``duration`` given, is refused first (``_same_run``)."""
    from .checkpoint import run_plan

    plan = run_plan(ckpt)
    if path is not None:
        _same_run(plan, ckpt, path, scene, duration)
    left = plan["frames_total"] - plan["frames_done"]
    steps = left * plan["per_frame"]
    dt = plan["scene"].world.dt
    why = f"{left:,} frames to go (run/frames_total {plan['frames_total']:,} - run/frames_done {plan['frames_done']:,}) × run/per_frame {plan['per_frame']:,} steps of dt = {dt:g} s"
    n = plan["particles"] + plan["born"]
    if plan["born"]:
        why += f"; up to {plan['born']:,} particles from the emitters"
    frames = plan["frames_total"] + 1.0  # all held until the trajectory is written
    particle_steps = float(n) * steps
    pixels = frames * scene.render.width * scene.render.height if video and n else 0.0
    memory = n * ENGINE_BYTES + frames * n * (FRAME_BYTES + (RENDER_BYTES if pixels else 0))
    estimate = f"the resumed run would take {particle_steps:.1e} particle-steps ({n:,} particles × {steps:,} steps: {why})"
    if pixels:
        estimate += f", {pixels:.1e} pixels of video ({frames:,.0f} frames × render.width {scene.render.width} × render.height {scene.render.height})"
    estimate += f" and about {_size(memory)} of memory"
    _over_limits(str(ckpt), estimate, particle_steps, pixels, memory, force)
    words = f"{particle_steps:.1e} particle-steps" + (f", {pixels:.1e} pixels of video" if pixels else "") + f", about {_size(memory)} of memory"
    return words, plan


def save_figure_atomically(fig, out: Path, dpi: int = 130) -> Path:
    """Write a matplotlib figure to ``out`` via a temporary file in the same folder, so an
    interrupted or failed write never leaves a half-written file under the final name.
    A path that cannot be written raises ``OutputError`` (the CLI: one line, exit 2)."""
    out = Path(out)
    if out.is_dir():
        raise OutputError(f"--out {out}: is a directory; give a file name such as {out / 'regions.png'}")
    suffix = out.suffix.lower().lstrip(".")
    if suffix not in {"png", "svg", "pdf", "jpg", "jpeg"}:
        raise OutputError(f"--out {out}: unsupported image format '{out.suffix}'; use .png, .svg, .pdf or .jpg")
    from .io._files import FileWriteError, TrajectoryFileError, atomic_file

    parent = out.parent if str(out.parent) else Path(".")
    try:
        parent.mkdir(parents=True, exist_ok=True)
        with atomic_file(out) as tmp:  # the mode an ordinary open() gives (mkstemp's was 0600)
            fig.savefig(tmp, dpi=dpi, format=suffix, bbox_inches="tight")
    except (TrajectoryFileError, FileWriteError) as e:  # (one line naming the file)
        raise OutputError(f"--out {out}: {e}") from None
    except OSError as e:
        raise OutputError(f"--out {out}: cannot write there ({e.strerror or e})") from None
    return out


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


def _render_video(
    traj, path: Path, render_opts: dict, fps: float | None, description: str, draw_colliders: bool = True, scene_fps: float | None = None
) -> Path:
    """Render ``traj`` to ``path`` (.mp4 or .gif) with a progress bar over the frames; the
    trajectory's colliders are drawn unless ``draw_colliders`` (or the option of that name in
    ``render_opts``) is False.

    ``fps``: one video frame per recorded frame at this rate. None: real time
    (``kinema.render.playback_rate``), the frames placed by their times
    (``write_video(times=)``), at the ``scene_fps`` the scene asked for or else the
    trajectory's own ``fps`` (a file saved by ``kinema run`` says it): World.run records frame
    k at k/fps exactly (an older kinema's every round(1/(fps·dt)) steps, 33 ms for 30 fps and
    dt = 1 ms, plays with one frame in about a hundred dropped). Without either, or when
    the recording interval is not that rate's rounding (clamped to one step), at the common
    rate (24, 25, 30, 50, 60) within 2 % of the recording's, else at the recording's own rate
    (clamped to ``VIDEO_FPS``, and then not real time). The rate written
    (``kinema.render.video_rate``: GIF counts in 1/100 s) is printed."""
    from .render import _trajectory_options, own_colours, playback_rate, render_frames, video_rate, write_video

    render_opts = dict(render_opts)
    draw_colliders = render_opts.pop("draw_colliders", draw_colliders)
    render_opts.setdefault("colliders", getattr(traj, "colliders", None) if draw_colliders else None)
    times, timing = None, "one video frame per recorded frame"
    if fps is None:
        known = scene_fps if scene_fps is not None else getattr(traj, "fps", None)
        fps, real_time, timing = playback_rate(traj.t, known, VIDEO_FPS)
        times = traj.t if real_time else None
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


def simulate_scene(
    scene: Path,
    outdir: Path,
    duration: float | None = None,
    no_video: bool = False,
    *,
    force: bool = False,
    checkpoint_every: float | None = None,
    resume: bool = False,
    keep_checkpoint: Path | None = None,
    record_contacts: bool = False,
) -> tuple[Any, list[Path]]:
    """`kinema run`'s work: load ``scene``, simulate ``duration`` s (default: the scene's) with
    a progress bar, and write what its [output] table asks for into the folder ``outdir``
    (created when the scene is valid): trajectory.h5, <scene name>.mp4|.gif, energy.png, all
    or none. Work over the limits (module docstring) is refused before any is done unless
    ``force``. Staging folders left in ``outdir`` by runs that were killed are removed.
    With ``resume`` the run goes on from ``outdir``/checkpoint.ckpt instead, read and checked
    first, the work it has left estimated and refused as a fresh run's (``_resume_work``).
    ``keep_checkpoint``: a path where the world at the run's end is written as a checkpoint
    (``kinema.checkpoint``: its state to every bit, spins and the contacts' tangential
    springs included; ``World.load_checkpoint`` gives the world back, to measure it or go
    on), after the other files; its folder is checked before the run.
    ``record_contacts`` (or the scene's ``[output] contacts``, which an ``[analysis]`` table
    of contact measures turns on) records each frame's contacts in the trajectory
    (``World.run(record_contacts=True)``; a resumed run keeps what its checkpoint says).
    A scene's ``[analysis]`` table: its measures of the trajectory (``kinema.analysis.report``)
    printed and written as analysis.json.
    Returns the trajectory and the paths written.

    In stages: the run made ready (``_prepared``: checked, its work estimated, the world built
    or resumed, the folder made), said (``_announce``), simulated (``_simulate``), its books
    said, and its files written (``_write_outputs``)."""
    run = _prepared(scene, outdir, duration, no_video, force, checkpoint_every, resume, keep_checkpoint)
    frames = _announce(run)
    if checkpoint_every is not None and not (np.isfinite(checkpoint_every) and checkpoint_every > 0):
        raise ValueError(f"--checkpoint-every {checkpoint_every}: give a finite number of simulated seconds > 0")
    traj = _simulate(run, frames, checkpoint_every, record_contacts)
    world = run.world
    stats = world.collision_stats()
    if stats is not None:
        total = stats["total"]
        console.print(f"{_counted(world.collisions, total['impacts'])}, {total['energy_lost']:.4g} J taken by the collisions", highlight=False)
    for k, st in enumerate(world.emitter_stats()):
        console.print(_emitter_summary(k, st), highlight=False, soft_wrap=True)
    written = _write_outputs(run, traj)
    if keep_checkpoint is not None:
        from .checkpoint import save_checkpoint

        written.append(save_checkpoint(world, keep_checkpoint))
    # The run is whole, its files written: no checkpoint of this folder may outlive it (one
    # left by an older run, even of another scene, would have --resume replace these files).
    _remove_checkpoints(run.outdir, keep=keep_checkpoint)
    for path in written:
        console.print(f"wrote {path}", highlight=False, soft_wrap=True)
    return traj, written


@dataclass
class _Run:
    """A run of `simulate_scene` made ready (`_prepared`): its scene file and `sc`, the
    simulated `seconds`, the `video` suffix (or False), whether contact `events` are recorded,
    the checkpoint `ckpt` of its folder `outdir`, the work `estimate`, and the world, built or
    (`resume`) read from the checkpoint with its `plan` and `progress`."""

    scene: Path
    sc: Any
    world: Any
    seconds: float
    video: Any
    events: bool
    ckpt: Path
    outdir: Path
    estimate: str
    resume: bool = False
    plan: dict | None = None
    progress: dict | None = None


def _prepared(
    scene: Path, outdir: Path, duration: float | None, no_video: bool, force: bool, checkpoint_every: float | None, resume: bool, keep_checkpoint: Path | None
) -> _Run:
    """The scene read and checked, its work estimated (refused over the limits unless
    `force`), the world built (or read from the checkpoint to resume), the output folder made
    with nothing in it the run could not replace, and the stale staging folders removed."""
    from .scene import Scene

    sc = Scene.from_toml(scene)
    seconds = sc.world.duration if duration is None else duration
    if not (np.isfinite(seconds) and seconds >= 0):
        raise ValueError(f"--duration {seconds}: give a finite number of seconds >= 0")
    video = sc.output.video if not no_video else False
    events = sc.output.contact_events
    if events and (resume or checkpoint_every is not None):
        raise ValueError(
            "[output] contact_events = true: the events are recorded in one run from its start, "
            "and a checkpoint does not keep them; run without --checkpoint-every/--resume"
        )
    ckpt = outdir / "checkpoint.ckpt"
    if keep_checkpoint is not None:  # checked before hours of work, not after
        _writable_file(keep_checkpoint, "--keep-checkpoint")
    plan = progress = None
    if resume:  # the checkpoint's remaining work, estimated and refused as a fresh run's, then all of it checked
        if not ckpt.is_file():
            raise ValueError(f"--resume: there is no checkpoint to resume in {outdir} ({ckpt.name}; a run with --checkpoint-every writes it)")
        from .checkpoint import load_run

        estimate, plan = _resume_work(ckpt, sc, bool(video), force, scene, duration)
        seconds = plan["duration"]  # (without --duration: the run's own, which --duration may have set)
        world, progress = load_run(ckpt)
        _run_source(world, {k: progress[k] for k in ("scene_file", "scene_sha256") if progress.get(k) is not None})
    else:
        estimate = _scene_work(sc, scene, seconds, "world.duration" if duration is None else "--duration", bool(video), force)
        world = sc.build(source=str(scene))
        _run_source(world, {"scene_file": str(scene), "scene_sha256": scene_digest(sc)})
    outdir = _outdir(outdir)
    outputs = (
        ("trajectory.h5", sc.output.trajectory),
        (f"{scene.stem}.{video}", video),
        ("energy.png", sc.output.plot),
        ("contact_events.csv", events),
        ("analysis.json", sc.analysis is not None),
    )
    _refuse_special_outputs(outdir, [n for n, on in outputs if on])
    if events:
        try:
            world.record_contact_events()
        except ValueError as e:
            raise ValueError(f"[output] contact_events = true: {e}") from None
    _remove_stale_stages(outdir)
    return _Run(scene, sc, world, seconds, video, events, ckpt, outdir, estimate, resume, plan, progress)


def _announce(run: _Run) -> int | None:
    """The run said in one line (and a note on its frames where they do not divide the steps);
    returns the number of frames after t = 0 of a fresh run (None when it resumes)."""
    world, scene, seconds, fps = run.world, run.scene, run.seconds, run.sc.world.fps
    frames = None
    if run.resume:
        plan = run.plan
        console.print(
            f"{run.ckpt}: resuming {scene} at t = {plan['time']:g} s, frame {plan['frames_done'] + 1:,} of {plan['frames_total'] + 1:,}: "
            f"{_count(len(world), 'particle')}, dim {world.dim}, {world.method}, dt = {world.dt:g} s; work: {run.estimate}",
            highlight=False,
            soft_wrap=True,
        )
    else:
        frames = int(_frames_and_steps(seconds, world.dt, fps)[0])
        console.print(
            f"{scene}: {_count(len(world), 'particle')}, dim {world.dim}, {world.method}, dt = {world.dt:g} s, {seconds:g} s, "
            f"{_count(frames + 1, 'frame')}; work: {run.estimate}",
            highlight=False,
            soft_wrap=True,
        )
    note = frames_plan(seconds, world.dt, fps).note()
    if note is not None:
        console.print(f"note: {note}", highlight=False, soft_wrap=True)
    return frames


def _simulate(run: _Run, frames: int | None, checkpoint_every: float | None, record_contacts: bool) -> Any:
    """The simulation with its progress bar (resumed from the checkpoint, or from t = 0,
    checkpointed every `checkpoint_every` s when asked); each warning said as one line after
    it, before an error it explains."""
    import warnings

    world, progress = run.world, run.progress
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            with _progress() as bar:
                if run.resume:
                    done, total = progress["frames_done"], progress["frames_total"]
                    task = bar.add_task("simulating (resumed)", total=total + 1, completed=done + 1)
                    traj = world._record(progress, lambda _w: bar.advance(task), run.ckpt)  # (kinema.checkpoint.resume_run's loop)
                else:
                    task = bar.add_task("simulating", total=frames + 1, completed=1)  # the frame at t = 0 is recorded first
                    saving = {"checkpoint": run.ckpt, "checkpoint_every": checkpoint_every} if checkpoint_every is not None else {}
                    contacts = record_contacts or run.sc.output.contacts
                    traj = world.run(
                        run.seconds, fps=run.sc.world.fps, callback=lambda _w: bar.advance(task), max_work=None, record_contacts=contacts, **saving
                    )
        finally:  # a StabilityWarning explains a divergence: show it before the error
            for w in caught:
                err_console.print(f"[yellow]warning:[/] {escape(str(w.message))}", highlight=False, soft_wrap=True)
    return traj


def _write_outputs(run: _Run, traj: Any) -> list[Path]:
    """The files the scene's [output] (and [analysis]) ask for, written into a hidden folder
    inside the output folder and moved into place at the end, so that a failure leaves no
    file half-written and none of this run's files at all; returns their paths."""
    import shutil

    sc, scene, world, video, outdir = run.sc, run.scene, run.world, run.video, run.outdir
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
            opts["attractors"] = _attractors(world)
            _render_video(traj, stage / f"{scene.stem}.{video}", opts, sc.render.fps, "rendering", scene_fps=sc.world.fps)
            names.append(f"{scene.stem}.{video}")
        if sc.output.plot:
            _energy_plot(traj, stage / "energy.png")
            names.append("energy.png")
        if run.events:
            _contact_events_csv(world.contact_events(), stage / "contact_events.csv")
            names.append("contact_events.csv")
        if sc.analysis is not None:
            _analysis_json(traj, sc.analysis, stage / "analysis.json", "trajectory.h5" if sc.output.trajectory else None)
            names.append("analysis.json")
        from .io._files import _umask

        for name in names:
            os.chmod(stage / name, 0o666 & ~_umask())
            os.replace(stage / name, outdir / name)
            written.append(outdir / name)
    finally:
        shutil.rmtree(stage, ignore_errors=True)
    return written


def _analysis_json(traj, table, out: Path, source: str | None) -> Path:
    """The measures the scene's ``[analysis]`` table asks of ``traj``, printed one line each
    and written to ``out`` as standard JSON (``kinema.analysis.report``, as ``kinema analyze``)."""
    from .analysis import report

    doc = report.analyze(
        traj,
        measures=table.measures,
        frame="all" if table.frames == "all" else -1,
        axis=table.axis,
        bins=table.bins,
        cross_section=table.cross_section,
        source=source,
    )
    for name, words in report.summary(doc):
        console.print(f"analysis: {name}: {words}", highlight=False, soft_wrap=True, markup=False)
    return report.write_json(doc, out)


def _attractors(world) -> list:
    """The points (m) of the world's attractors, drawn as markers in its video."""
    from .forces import Attractor

    points = [[float(c) for c in np.ravel(f.point)] for f in world.forces if isinstance(f, Attractor)]
    return [p + [0.0] * (3 - len(p)) for p in points]


def _camera(table):
    from .render import Camera2D, Camera3D

    if table is None:
        return None
    if table.type == "2d":
        return Camera2D(table.xmin, table.ymin, table.xmax, table.ymax)
    return Camera3D(tuple(table.eye), tuple(table.target), tuple(table.up), table.fov_deg)
