"""Parameter sweeps and ensembles on Dask: the grid of a scene's varied values × seeds, each
member run and measured on a ``dask.distributed`` cluster (local worker processes, a
scheduler started by hand, or Slurm/PBS through dask-jobqueue), results in plain files.

A sweep's folder::

    sweep.json               what was asked: the scene, the varied keys and values, the seeds
                             (standard JSON: an infinite lifetime is the string "Infinity",
                             ``NON_FINITE``; ``read_json`` reads it back)
    members/<name>/          one folder per member: scene.toml (the member's scene),
                             trajectory.h5 (H5MD), result.json (its measurements, or its error),
                             checkpoint.ckpt while it runs with checkpoint_every
    summary.csv              one row per member, in member order: the varied values, the seed,
                             the measurements (the same bits wherever the members ran)
    timings.csv              one row per member: its wall time and the worker that ran it
    summary.png              each measurement against each varied key, mean ± spread over seeds

A member is finished when its ``result.json`` exists (written last, atomically), holds the
member's key and no error: a sweep run again into the same folder skips the finished members
whose key is the same and runs the others, those that failed (a full disk, a measure that
raised) included. The key (``member_key``) is a hash of what the member's row
depends on: its scene with its seed, the duration, the measure (its name and code) and the
kinema version. A member whose scene, duration, measure or kinema changed is run again, its
old trajectory, result and checkpoint replaced. A member whose worker
dies is run again elsewhere (Dask's retries); a member that raises is recorded with its error
and the others go on.

Seeds: member seed s (0 … seeds − 1) gives every ``seed`` of the scene (particle blocks,
their velocity tables, emitters) the value ``SeedSequence([seed, s])`` draws, so members
differ and each is reproducible from (scene, s) alone.

The JSON files' form (``NON_FINITE``, ``to_json``, ``read_json``) and the summary's files
(summary.csv, timings.csv, summary.png) are written by ``kinema._sweep_files``; those names
are importable from here too.
"""

from __future__ import annotations

import copy
import hashlib
import itertools
import json
import math
import os
import socket
import time
import tomllib
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ._sweep_files import NON_FINITE as NON_FINITE
from ._sweep_files import UNITS as UNITS
from ._sweep_files import _figure as _figure
from ._sweep_files import _plot, _write_csv
from ._sweep_files import read_json as read_json
from ._sweep_files import to_json as to_json
from .scene import Scene, SceneError

#: The measurements every member reports (besides what ``measure`` returns).
MEASURED = ("final_kinetic", "final_total", "energy_lost", "impacts", "frames")


@dataclass(frozen=True)
class Member:
    """One run of a sweep: its index, folder name, varied values (key path → value), seed
    index, and the scene as plain data with those set."""

    index: int
    name: str
    values: dict[str, Any]
    seed: int | None
    scene: dict[str, Any]


@dataclass
class SweepResult:
    """What a sweep gave: its folder, the members, and one row per member (``rows``: the
    varied values, ``seed``, the measurements, ``error`` where it failed)."""

    folder: Path
    members: list[Member]
    rows: list[dict[str, Any]]

    @property
    def failed(self) -> list[dict[str, Any]]:
        return [r for r in self.rows if r.get("error")]


# -- the grid ---------------------------------------------------------------------------------


def _set_key(data: dict, key: str, value: Any, source: str) -> None:
    """Sets ``data[a][b]...`` for the key path ``a.b...`` (a list index is a number:
    ``particles.0.radius``); a table the scene does not have yet is made (``collisions``)."""
    parts = key.split(".")
    if not key or any(p == "" for p in parts):
        raise SceneError(f"{source}: vary key {key!r} is invalid: use a dotted key path such as collisions.restitution")
    node: Any = data
    for depth, part in enumerate(parts[:-1]):
        where = ".".join(parts[: depth + 1])
        if isinstance(node, list):
            if not part.isdigit() or int(part) >= len(node):
                raise SceneError(f"{source}: vary key {key!r}: {where} is not an entry (the scene has {len(node)})")
            node = node[int(part)]
        else:
            node = node.setdefault(part, {})
            if not isinstance(node, (dict, list)):
                raise SceneError(f"{source}: vary key {key!r}: {where} is a value, not a table")
    last = parts[-1]
    if isinstance(node, list):
        raise SceneError(f"{source}: vary key {key!r} names a list entry, not a key of a table")
    node[last] = value


def _derived(base: int, s: int) -> int:
    """Member s's seed from a scene's seed: independent streams for every (base, s)."""
    return int(np.random.SeedSequence([int(base), s]).generate_state(1, np.uint64)[0] >> 1)


def _seeded(data: dict, s: int) -> dict:
    """The scene with every seed (particle blocks and their velocity tables, emitters)
    replaced by member s's."""
    out = copy.deepcopy(data)
    for table in (*out.get("particles", []), *out.get("emitters", [])):
        table["seed"] = _derived(table.get("seed", 0), s)
        velocity = table.get("velocity")
        if isinstance(velocity, dict) and velocity.get("seed") is not None:
            velocity["seed"] = _derived(velocity["seed"], s)
    return out


def _value_name(v: Any) -> str:
    text = json.dumps(v) if not isinstance(v, str) else v
    return "".join(c if c.isalnum() or c in ".-+" else "_" for c in text)[:40]


def members(scene: Scene | str | Path | dict, vary: dict[str, Iterable[Any]] | None = None, seeds: int | None = None) -> list[Member]:
    """The sweep's members, each scene validated (a bad key or value is a ``SceneError``
    naming the member and the key) before anything runs."""
    base, source = _scene_data(scene)
    vary = {k: list(v) for k, v in (vary or {}).items()}
    for key, values in vary.items():
        if not values:
            raise SceneError(f"{source}: vary key {key!r} has no values")
    seed_list: list[int | None] = [None] if not seeds else list(range(int(seeds)))
    out = []
    for index, (combo, s) in enumerate(itertools.product(itertools.product(*vary.values()), seed_list)):
        values = dict(zip(vary.keys(), combo, strict=True))
        data = copy.deepcopy(base) if s is None else _seeded(base, s)
        for key, value in values.items():
            _set_key(data, key, value, source)
        name = "_".join(f"{k.split('.')[-1]}={_value_name(v)}" for k, v in values.items()) or "member"
        name = f"{index:04d}_{name}" + ("" if s is None else f"_seed={s}")
        try:
            Scene.from_dict(data, f"{source} [member {name}]")
        except SceneError as err:
            raise SceneError(str(err)) from None
        out.append(Member(index, name, values, s, data))
    return out


def _scene_data(scene: Scene | str | Path | dict) -> tuple[dict, str]:
    if isinstance(scene, Scene):
        return scene.model_dump(mode="python", exclude_none=True), "<scene>"
    if isinstance(scene, dict):
        return Scene.from_dict(scene).model_dump(mode="python", exclude_none=True), "<scene>"
    path = Path(scene)
    return Scene.from_toml(path).model_dump(mode="python", exclude_none=True), str(path)


# -- one member -------------------------------------------------------------------------------


def load_measure(text: str) -> Callable[[Any, Any], dict]:
    """The measure named by ``text``, ``MODULE:FUNCTION`` (``kinema sweep --measure``): a
    module importable from here, the current folder first (``mymeasures:top``, as uvicorn
    and gunicorn name an app), or a Python file (``path/to/measures.py:top``), and a function
    ``measure(trajectory, world) -> dict`` in it. A module from the current folder or a file
    is sent to the workers by value (``cloudpickle.register_pickle_by_value``), so workers
    that cannot import it (another folder, another machine) still run it. A ``ValueError``
    naming the option and the value where it cannot be had."""
    import importlib
    import importlib.util
    import sys

    where, colon, name = text.rpartition(":")
    if not colon or not where or not name.isidentifier():
        raise ValueError(f"--measure {text!r}: use MODULE:FUNCTION or FILE.py:FUNCTION (e.g. mymeasures:top_height)")
    try:
        if where.endswith(".py"):
            path = Path(where).resolve()
            if not path.is_file():
                raise ValueError(f"--measure {text!r}: there is no file {where}")
            spec = importlib.util.spec_from_file_location(f"kinema_measure_{path.stem}", path)
            assert spec is not None and spec.loader is not None
            module = importlib.util.module_from_spec(spec)
            sys.modules[spec.name] = module
            spec.loader.exec_module(module)
        else:
            if os.getcwd() not in sys.path:
                sys.path.insert(0, os.getcwd())
            module = importlib.import_module(where)
    except ValueError:
        raise
    except Exception as e:  # the module's own error (ImportError, SyntaxError, what it raised)
        raise ValueError(f"--measure {text!r}: cannot import {where}: {type(e).__name__}: {e}") from None
    fn = getattr(module, name, None)
    if not callable(fn):
        raise ValueError(f"--measure {text!r}: {where} has no function {name}" + ("" if fn is None else f" ({name} is a {type(fn).__name__})"))
    origin = Path(getattr(module, "__file__", None) or "/").resolve()
    if where.endswith(".py") or origin.is_relative_to(Path.cwd().resolve()):
        import cloudpickle

        cloudpickle.register_pickle_by_value(module)
    return fn


def _measure_id(measure: Callable | None) -> str:
    """What identifies a measure for a member's key: its module and name, and the hash of its
    code where it has one (a changed body under the same name is another measure)."""
    if measure is None:
        return ""
    name = f"{getattr(measure, '__module__', '')}.{getattr(measure, '__qualname__', type(measure).__name__)}"
    code = getattr(measure, "__code__", None)
    if code is not None:
        body = code.co_code + repr(code.co_consts).encode() + repr(code.co_names).encode()
        name += ":" + hashlib.sha256(body).hexdigest()[:16]
    return name


def member_key(member: Member, duration: float | None, measure: Callable | None) -> str:
    """The hash of what a member's row depends on: its scene (seed included), the duration,
    the measure and the kinema version (hex, 32 digits)."""
    from . import __version__

    what = {"scene": member.scene, "duration": duration, "measure": _measure_id(measure), "kinema": __version__}
    return hashlib.sha256(json.dumps(what, sort_keys=True, default=repr).encode()).hexdigest()[:32]


def _finished(where: Path, key: str) -> dict | None:
    """The member's result.json if it holds ``key`` and no error (else None: not run, run
    for another key, or failed: a failure, a full disk say, is tried again)."""
    try:
        result = read_json(where / "result.json")
    except (OSError, ValueError):
        return None
    if not (isinstance(result, dict) and result.get("key") == key):
        return None
    row = result.get("row")
    return result if isinstance(row, dict) and not row.get("error") else None


def finished_members(folder: str | Path, grid: list[Member], keys: dict[int, str]) -> list[Member]:
    """The members of ``grid`` finished in ``folder`` (``_finished``)."""
    return [m for m in grid if _finished(Path(folder) / "members" / m.name, keys[m.index]) is not None]


def run_member(
    member: Member, folder: str, duration: float | None, measure: Callable | bytes | None, checkpoint_every: float | None = None, key: str = ""
) -> dict[str, Any]:
    """Runs one member in this process and writes its folder; returns its row. Never raises
    for the member's own failure (the row has ``error``): only a dying worker is retried.
    ``key``: the member's key (``member_key``), written into its result.json and beside its
    checkpoint; a checkpoint written for another key is not resumed."""
    import gc
    import traceback

    from .io._files import atomic_file

    if isinstance(measure, bytes):  # sent by cloudpickle (see _run_all)
        import cloudpickle

        measure = cloudpickle.loads(measure)
    where = Path(folder) / "members" / member.name
    where.mkdir(parents=True, exist_ok=True)
    stamp = where / "key"
    if (where / "checkpoint.ckpt").is_file() and (not stamp.is_file() or stamp.read_text().strip() != key):
        (where / "checkpoint.ckpt").unlink()  # another member's run: not resumed
    (where / "result.json").unlink(missing_ok=True)
    with atomic_file(stamp) as tmp:
        tmp.write_text(key)
    row: dict[str, Any] = {"member": member.name, **member.values, "seed": member.seed}
    start = time.perf_counter()
    try:
        scene = Scene.from_dict(member.scene, member.name)
        scene.to_toml(where / "scene.toml")
        ckpt = where / "checkpoint.ckpt"
        resumed = None
        if ckpt.is_file():  # a member interrupted mid-run goes on from its last checkpoint
            from .checkpoint import CheckpointError, resume_run

            try:
                resumed = resume_run(ckpt, max_work=None)
            except CheckpointError:
                ckpt.unlink()  # damaged (a disk that filled, a kill): the member runs afresh
        if resumed is not None:
            world, traj = resumed
        else:
            world = scene.build(member.name)
            seconds = scene.world.duration if duration is None else duration
            saving = {"checkpoint": ckpt, "checkpoint_every": checkpoint_every} if checkpoint_every else {}
            traj = world.run(seconds, fps=scene.world.fps, max_work=None, **saving)
        traj.save(where / "trajectory.h5")
        stats = world.collision_stats()
        row.update(
            final_kinetic=float(traj.kinetic[-1]),
            final_total=float(traj.total[-1]),
            energy_lost=float(traj.collision_energy_lost[-1]),
            impacts=int(stats["total"]["impacts"]) if stats else 0,
            frames=len(traj.t),
        )
        if measure is not None:
            extra = measure(traj, world)
            if not isinstance(extra, dict):
                raise TypeError(f"measure returned {type(extra).__name__}; it must return a dict of name → number")
            row.update({str(k): _plain(v) for k, v in extra.items()})
        row["error"] = ""
        ckpt.unlink(missing_ok=True)
    except Exception as err:  # the member's failure is its result
        row["error"] = _error_line(err)
        try:
            (where / "error.txt").write_text(traceback.format_exc())
        except OSError:  # (a full disk: the row says the error)
            pass
    timing = {"wall_s": time.perf_counter() - start, "host": socket.gethostname(), "pid": os.getpid()}
    try:
        with atomic_file(where / "result.json") as tmp:
            tmp.write_text(to_json({"row": row, "timing": timing, "key": key}))
    except OSError as err:  # the member is not finished: a rerun runs it again
        row["error"] = row["error"] or _error_line(err)
    # The member's World is freed here (with any cycle it is in), before the next member is
    # made, rather than at some later collection (any thread may free it: issue 49).
    world = traj = None
    gc.collect()
    return {"row": row, "timing": timing}


def _error_line(err: BaseException) -> str:
    """A member's error as the one line its row keeps (a full disk: what failed, where)."""
    text = str(err).strip().splitlines()[0] if str(err).strip() else ""
    if isinstance(err, OSError) and err.filename and err.strerror:
        text = f"{err.filename}: {err.strerror}"
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


def _plain(v: Any) -> Any:
    if isinstance(v, (np.floating, np.integer, np.bool_)):
        return v.item()
    return v


# -- the sweep --------------------------------------------------------------------------------


def default_folder(scene: Scene | str | Path | dict) -> Path:
    """Where a sweep of ``scene`` writes when no folder is given: ``out/<name>_sweep`` for a
    scene file, ``out/sweep`` for a scene given as an object."""
    return Path("out") / (f"{Path(scene).stem}_sweep" if isinstance(scene, str | Path) else "sweep")


def sweep(
    scene: Scene | str | Path | dict,
    vary: dict[str, Iterable[Any]] | None = None,
    seeds: int | None = None,
    measure: Callable[[Any, Any], dict] | None = None,
    client: Any = None,
    out: str | Path | None = None,
    duration: float | None = None,
    workers: int | None = None,
    progress: bool = True,
    plot: bool = True,
    checkpoint_every: float | None = None,
) -> SweepResult:
    """Run the grid of ``vary`` (key path → values) × ``seeds`` on Dask; see the module doc.

    ``client``: a ``distributed.Client`` or a scheduler address (``"tcp://host:8786"``);
    None starts a ``LocalCluster`` of ``workers`` processes (default: the cores, at most
    the members) with one thread each, or runs a single member in this process.
    ``measure(trajectory, world) -> dict`` adds measurements (it must be importable by the
    workers: a module-level function). ``duration`` overrides the scene's.
    ``checkpoint_every`` (simulated s): each member writes ``checkpoint.ckpt`` in its folder
    that often, and a member interrupted mid-run (its worker killed, the sweep stopped) goes on
    from it when run again, bit for bit.

    ``out``: the sweep's folder; rerun into it to resume (default: ``out/<scene file's
    name>_sweep`` as ``kinema sweep``'s, ``out/sweep`` for a scene given as an object).
    ``workers``: local worker processes when ``client`` is None. ``progress``: a progress bar
    while the members run. ``plot``: ``summary.png`` of the measurements against the varied keys."""
    folder = Path(out) if out is not None else default_folder(scene)
    grid = members(scene, vary, seeds)
    folder.mkdir(parents=True, exist_ok=True)
    asked = {"scene": _scene_data(scene)[0], "vary": {k: list(v) for k, v in (vary or {}).items()}, "seeds": seeds, "duration": duration}
    (folder / "sweep.json").write_text(to_json(asked))
    results: dict[int, dict] = {}
    todo = []
    keys = {m.index: member_key(m, duration, measure) for m in grid}
    for m in grid:
        done = _finished(folder / "members" / m.name, keys[m.index])
        if done is not None:
            results[m.index] = done
        else:
            todo.append(m)
    if todo:
        results.update(_run_all(todo, folder, duration, measure, client, workers, progress, checkpoint_every, keys))
    rows = [results[m.index]["row"] for m in grid]
    _write_csv(folder / "summary.csv", rows)
    _write_csv(folder / "timings.csv", [{"member": m.name, **results[m.index]["timing"]} for m in grid])
    if plot and vary:
        _plot(folder / "summary.png", rows, list(vary))
    return SweepResult(folder, grid, rows)


def _run_all(todo: list[Member], folder: Path, duration, measure, client, workers, progress, checkpoint_every, keys: dict[int, str]) -> dict[int, dict]:
    if client is None and len(todo) == 1:
        return {todo[0].index: run_member(todo[0], str(folder), duration, measure, checkpoint_every, keys[todo[0].index])}
    from distributed import Client, LocalCluster, as_completed

    own = None
    if client is None:
        n = max(1, min(workers or os.cpu_count() or 1, len(todo)))
        threads = max(1, (os.cpu_count() or 1) // n)
        # one thread per worker for Dask, the engine's own threads split among them
        # Everything on the loopback interface: Dask's dashboard serves the workers' logs and
        # call stacks to whoever reaches its port (":0" listened on every interface; None
        # still starts its HTTP server on every interface at 8787).
        own = LocalCluster(
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            host="127.0.0.1",
            dashboard_address="127.0.0.1:0",
            env={"RAYON_NUM_THREADS": str(threads)},
        )
        client = Client(own)
    elif isinstance(client, str):
        client = own = Client(client)
    # Dask pickles a task with the standard pickle first, which sends a function by its
    # module's name; cloudpickle honours cloudpickle.register_pickle_by_value (and sends a
    # function of __main__ by value), so a measure from a script reaches the workers.
    if measure is not None:
        import cloudpickle

        measure = cloudpickle.dumps(measure)
    try:
        futures = {
            client.submit(
                run_member,
                m,
                str(folder.resolve()),
                duration,
                measure,
                checkpoint_every,
                keys[m.index],
                key=f"kinema-member-{m.name}-{os.getpid()}",
                retries=2,
                pure=False,
            ): m
            for m in todo
        }
        out: dict[int, dict] = {}
        bar = _bar(progress, len(futures))
        for future in as_completed(futures):
            m = futures[future]
            try:
                out[m.index] = future.result()
            except Exception as err:  # the worker died more often than the retries
                row = {"member": m.name, **m.values, "seed": m.seed, "error": f"{type(err).__name__}: {err}"}
                out[m.index] = {"row": row, "timing": {"wall_s": math.nan, "host": "", "pid": 0}}
            bar.advance(m.name)
        bar.close()
        return out
    finally:
        if own is not None:
            client.close()
            if hasattr(own, "close"):
                own.close()


class _bar:
    """A rich progress bar over the members (or nothing)."""

    def __init__(self, show: bool, total: int) -> None:
        self.progress = None
        if show:
            from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

            self.progress = Progress(TextColumn("sweep"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(), TextColumn("{task.description}"))
            self.progress.start()
            self.task = self.progress.add_task("", total=total)

    def advance(self, name: str) -> None:
        if self.progress is not None:
            self.progress.update(self.task, advance=1, description=name)

    def close(self) -> None:
        if self.progress is not None:
            self.progress.stop()


def parse_values(text: str) -> list[Any]:
    """``V1,V2,...`` of the command line: each a TOML value (0.5, 3, true, "verlet", [0, 0, 1]);
    commas inside brackets or quotes do not split; a bare word is a string."""
    items, depth, quote, cur = [], 0, None, ""
    for c in text:
        if quote:
            quote = None if c == quote else quote
        elif c in "\"'":
            quote = c
        elif c in "[{":
            depth += 1
        elif c in "]}":
            depth -= 1
        elif c == "," and depth == 0:
            items.append(cur)
            cur = ""
            continue
        cur += c
    items.append(cur)
    out = []
    for item in (i.strip() for i in items):
        if not item:
            raise ValueError(f"{text!r} has an empty value: use V1,V2,... (TOML values)")
        try:
            out.append(tomllib.loads(f"v = {item}")["v"])
        except tomllib.TOMLDecodeError:
            out.append(item)  # a bare word: a string (method names)
    return out
