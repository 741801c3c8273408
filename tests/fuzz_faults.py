"""The worker's side of the fuzz suite's fault cases (tests/test_fuzz.py, "robust under faults"):
writers on a full file system or under a file-size limit, special files in place of a target,
a World used from another thread, sweeps run again into one folder, damaged checkpoints.

Each op here runs its calls itself (the worker's ``_op`` hands it the op) and judges them: it
answers ``{"calls": [...], "faults": [...]}``, where a call is ``{"call", "result": "ok"}`` or
``{"call", "type", "message", "verdict"}`` ("allowed" or "bad", as the worker judges any op), and
a fault is ``{"kind", "detail"}``: an invariant the call broke (``destructive write``: a file
that was there changed or went; ``leftover temp file``: a ``.part``/``.old`` name left after
the call returned; ``partial output``: a failed write that left other new files; ``bad
read-back``: a write that succeeded but does not read back; ``node changed``: a FIFO, device,
socket, directory or symbolic link in place of a target is not as it was; ``not refused``: a
write to such a node that succeeded; ``leaked fd``: a descriptor still open on the folder
written; ``broken world``: a world that no longer steps in its own thread; ``stale result``: a
sweep run again that reused what it should not have; also ``hang``, ``CLI traceback``, ``CLI
exit``, ``unexpected exception``). ``fuzz_cases.findings`` reads both; an answer ``{"invalid":
why}`` (the case could not be set up) is not a test of kinema. A fault or a bad call that is a
known bug (``KNOWN_BUGS``) goes to ``"known"`` instead, unless the op is ``"strict"``.

Everything is written under the folder the test process gives (``base``), in a new folder per
case; a small tmpfs is mounted there (root only) and unmounted before the op returns.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import re
import shutil
import signal
import socket
import stat
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

# The documented RuntimeError of a World used from a thread that did not make it
# (kinema.world._other_thread): a refusal by design, as REENTRY_MESSAGES is.
THREAD_MESSAGES = ("this World was made on thread",)

# kinema's temporary names: .<name>.<host>-<pid>.<hex>.part (atomic_file, atomic_folder) and
# .<folder>.<random>.old (a series folder being replaced)
TEMPORARY = re.compile(r"^\..+\.(part|old)$")

WRITERS = ("h5md", "vtk", "ply", "xyz", "csv", "gsd", "lammps", "usd", "checkpoint", "run_checkpoint", "toml", "gif", "mp4", "cli_export", "cli_render")
SUFFIXES = {
    "h5md": (".h5", ".hdf5", ".h5md"),
    "vtk": (".pvd", ".vtp"),
    "ply": (".ply",),
    "xyz": (".xyz", ".extxyz"),
    "csv": (".csv",),
    "gsd": (".gsd",),
    "lammps": (".lammpstrj", ".dump"),
    "usd": (".usd", ".usda", ".usdc", ".usdz"),
    "checkpoint": (".ckpt", ".h5"),
    "run_checkpoint": (".ckpt",),
    "toml": (".toml",),
    "gif": (".gif",),
    "mp4": (".mp4",),
    "cli_export": (".xyz", ".pvd", ".gsd", ".csv", ".lammpstrj", ".ply", ".usda"),
    "cli_render": (".gif",),
}
READERS = {  # reader: (suffix, what it must raise)
    "Scene.from_toml": (".toml", "SceneError"),
    "load_scene": (".toml", "SceneError"),
    "Trajectory.load": (".h5", "TrajectoryFileError"),
    "World.load_checkpoint": (".ckpt", "CheckpointError"),
    "resume_run": (".ckpt", "CheckpointError"),
    "run_plan": (".ckpt", "CheckpointError"),
    "cli_run": (".toml", "exit 2"),
    "cli_export": (".h5", "exit 2"),
}
NODES = ("fifo", "chardev", "socket", "dir", "dir_full")

_COUNTER = [0]

# Bugs these cases found, not fixed yet: a fault that is one of them is answered under "known"
# (not a failure), unless the op says "strict" (tests/test_fuzz.py: the strict xfail test of
# each, with its reproducer, which starts to pass when it is fixed).
KNOWN_BUGS: dict[str, str] = {}  # (none open: the five the fault cases found are fixed, tests/test_fuzz.py FIXED_BUG_CASES;
# the readers' open ones are tests/fuzz_readers.py KNOWN_READER_BUGS)


def _known(op: dict, f: dict) -> str | None:
    """The known bug (KNOWN_BUGS) a fault of ``op`` is, or None."""
    if op.get("strict"):
        return None
    writer, kind = op.get("writer"), f["kind"]
    del writer, kind  # (a known bug's rule goes here: which writer, which fault)
    return None


def _known_call(op: dict, call: dict) -> str | None:
    """The known bug (KNOWN_BUGS) a call judged "bad" is, or None (none is now: GSD's RuntimeError
    from gsd_close is fixed)."""
    return None


def _with_known(fn: Any) -> Any:
    """``fn``, its answer's faults and bad calls that are known bugs moved to "known"."""

    def op_with_known(ctx: Any, op: dict) -> dict:
        answer = fn(ctx, op)
        known = []
        faults = []
        for f in answer.get("faults") or []:
            bug = _known(op, f)
            if bug is None and f["kind"] == "CLI exit":  # (`kinema export` reports one as "unexpected RuntimeError: ...", exit 1)
                bug = _known_call(op, {"type": "RuntimeError", "message": f["detail"].split("unexpected RuntimeError: ", 1)[-1]})
            (faults if bug is None else known).append(f if bug is None else {**f, "known": bug})
        for c in answer.get("calls") or []:
            bug = _known_call(op, c) if c.get("verdict") == "bad" else None
            if bug is not None:
                c["verdict"] = "known bug"
                known.append({"kind": "unexpected exception", "detail": f"{c['type']}: {c['message']}", "known": bug})
        if "faults" in answer:
            answer["faults"] = faults
        if known:
            answer["known"] = known
        return answer

    return op_with_known


# -- judging ----------------------------------------------------------------------------------
def fault(kind: str, detail: str, names: list[str] | None = None) -> dict:
    out = {"kind": kind, "detail": detail[:1500]}
    if names is not None:
        out["names"] = names[:50]
    return out


def _judged(name: str, e: BaseException, allowed: tuple[type, ...], messages: tuple[str, ...] = (), one_line: bool = True) -> dict:
    out = {"call": name, "type": type(e).__name__, "message": str(e)[:600]}
    names = [c.__name__ for c in type(e).__mro__]
    if "PanicException" in names or not isinstance(e, Exception):
        out["verdict"] = "bad"
    elif isinstance(e, RuntimeError) and not isinstance(e, allowed):
        out["verdict"] = "allowed" if messages and str(e).startswith(messages) else "bad"
    elif isinstance(e, allowed):
        out["verdict"] = "allowed"
        text = str(e).strip()
        if one_line and "\n" in text:
            out["verdict"] = "bad"
            out["why"] = "the message is not one line"
    else:
        out["verdict"] = "bad"
    return out


def attempt(calls: list, name: str, fn: Any, allowed: tuple[type, ...], messages: tuple[str, ...] = (), one_line: bool = True) -> tuple[bool, Any]:
    """Runs ``fn()``, recording the call; (True, its value) or (False, the exception)."""
    try:
        value = fn()
    except BaseException as e:  # noqa: BLE001 - every exception is judged
        calls.append(_judged(name, e, allowed, messages, one_line))
        if not isinstance(e, Exception):
            raise _Stop(e) from None
        return False, e
    calls.append({"call": name, "result": "ok"})
    return True, value


class _Stop(Exception):
    """A BaseException (a PanicException) met inside an op: the op stops and answers."""


def write_errors() -> tuple[type, ...]:
    from kinema.io import FileWriteError, TrajectoryFileError

    return (FileWriteError, TrajectoryFileError, ValueError, MemoryError)


# -- folders ----------------------------------------------------------------------------------
def new_folder(base: str, tag: str) -> Path:
    _COUNTER[0] += 1
    folder = Path(base) / f"{tag}-{os.getpid()}-{_COUNTER[0]}"
    folder.mkdir(parents=True)
    return folder


def mount_tmpfs(folder: Path, size_kb: int, inodes: int | None = None, remount_ro: bool = False) -> str | None:
    """Mounts a tmpfs of ``size_kb`` kB (and ``inodes`` inodes) at ``folder``, or makes the
    one there read-only (``remount_ro``); None, or why it could not."""
    if os.geteuid() != 0:
        return "not root"
    options = "remount,ro" if remount_ro else f"size={size_kb}k,mode=0755" + (f",nr_inodes={inodes}" if inodes else "")
    try:
        proc = subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(folder)], capture_output=True, text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired) as e:
        return f"mount: {e}"
    return None if proc.returncode == 0 else f"mount: {proc.stderr.strip()}"


def unmount(folder: Path) -> None:
    for args in (["umount", str(folder)], ["umount", "-l", str(folder)]):
        try:
            if subprocess.run(args, capture_output=True, timeout=30).returncode == 0:
                return
        except (OSError, subprocess.TimeoutExpired):
            pass


def snapshot(root: Path) -> dict[str, tuple]:
    """Every entry under ``root`` (links not followed): kind and content (a file's hash, a
    link's target, a node's mode, device and inode)."""
    out: dict[str, tuple] = {}
    for dirpath, dirnames, filenames in os.walk(root):
        for name in dirnames + filenames:
            p = os.path.join(dirpath, name)
            rel = os.path.relpath(p, root)
            try:
                st = os.lstat(p)
            except OSError:
                continue
            if stat.S_ISLNK(st.st_mode):
                out[rel] = ("link", os.readlink(p))
            elif stat.S_ISDIR(st.st_mode):
                out[rel] = ("dir", st.st_ino)
            elif stat.S_ISREG(st.st_mode):
                h = hashlib.sha256()
                with open(p, "rb") as f:
                    for chunk in iter(lambda: f.read(1 << 20), b""):
                        h.update(chunk)
                out[rel] = ("file", h.hexdigest(), st.st_size)
            else:
                out[rel] = ("node", stat.S_IFMT(st.st_mode), st.st_rdev, st.st_ino)
    return out


def temporaries(entries: dict) -> list[str]:
    return sorted(rel for rel in entries if TEMPORARY.match(os.path.basename(rel)))


def compare_after_failure(before: dict, after: dict, faults: list, what: str, may_change: Any = None) -> None:
    """A failed write leaves the folder as it was: no file changed, none gone, none new.
    ``may_change(name)``: whether a changed or new entry is allowed after all (a run's earlier
    checkpoint, complete)."""
    ok = may_change or (lambda name: False)
    changed = sorted(k for k in before if (k not in after or after[k] != before[k]) and not ok(k))
    new = sorted(k for k in after if k not in before and not ok(k))
    if changed:
        faults.append(fault("destructive write", f"{what} failed, and changed or removed what was there: {changed[:8]}", changed))
    temps = [k for k in new if TEMPORARY.match(os.path.basename(k))]
    if temps:
        faults.append(fault("leftover temp file", f"{what} failed and left {temps[:8]}", temps))
    others = [k for k in new if k not in temps]
    if others:
        faults.append(fault("partial output", f"{what} failed and left new files {others[:8]}", others))


def open_descriptors(folder: Path, numbers: bool = False) -> list[Any]:
    """This process's descriptors open on a path under ``folder`` (their targets, or numbers)."""
    out: list[Any] = []
    prefix = str(folder.resolve()) + os.sep
    try:
        fds = os.listdir("/proc/self/fd")
    except OSError:
        return out
    for fd in fds:
        try:
            target = os.readlink(f"/proc/self/fd/{fd}")
        except OSError:
            continue
        if target.startswith(prefix):
            out.append(int(fd) if numbers else target)
    return out


def close_descriptors(folder: Path) -> None:
    """Closes what a writer left open under ``folder`` (its own object believes it closed)."""
    for fd in open_descriptors(folder, numbers=True):
        try:
            os.close(fd)
        except OSError:
            pass


@contextlib.contextmanager
def stderr_to_pipe():
    """fd 2 into a pipe drained by a thread (a pipe has no file-size limit), copied back to the
    real stderr after: a panic message written under RLIMIT_FSIZE still reaches the test."""
    r, w = os.pipe()
    saved = os.dup(2)
    chunks: list[bytes] = []

    def drain() -> None:
        while True:
            data = os.read(r, 65536)
            if not data:
                break
            chunks.append(data)

    reader = threading.Thread(target=drain, daemon=True)
    reader.start()
    sys.stderr.flush()
    os.dup2(w, 2)
    os.close(w)
    try:
        yield
    finally:
        sys.stderr.flush()
        os.dup2(saved, 2)
        os.close(saved)
        reader.join(10)
        os.close(r)
        data = b"".join(chunks)
        if data:
            os.write(2, data)


@contextlib.contextmanager
def file_size_limit(limit: int):
    import resource

    soft, hard = resource.getrlimit(resource.RLIMIT_FSIZE)
    old = signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    with stderr_to_pipe():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit if hard == resource.RLIM_INFINITY else min(limit, hard), hard))
        try:
            yield
        finally:
            resource.setrlimit(resource.RLIMIT_FSIZE, (soft, hard))
            signal.signal(signal.SIGXFSZ, old)


# -- worlds and trajectories ------------------------------------------------------------------
class Made:
    """A world and the trajectory of its run, as a case's ``spec`` describes them."""

    def __init__(self, spec: dict) -> None:
        import numpy as np

        import kinema

        rng = np.random.default_rng(spec.get("seed", 0))
        dim, n = spec.get("dim", 3), max(1, spec.get("n", 3))
        w = kinema.World(dim=dim, dt=0.005, method=spec.get("method", "verlet"))
        # on a jittered grid in [0.1, 0.9]: no two particles overlap (deep overlaps are refused)
        side = int(np.ceil(n ** (1.0 / dim)))
        cells = np.array(np.meshgrid(*[np.arange(side)] * dim, indexing="ij")).reshape(dim, -1).T[rng.permutation(side**dim)[:n]]
        x = np.zeros((n, 3))
        x[:, :dim] = 0.1 + (cells + 0.5) * (0.8 / side) + rng.uniform(-0.1, 0.1, (n, dim)) * (0.8 / side)
        v = rng.normal(0.0, 0.5, (n, 3))
        if dim == 2:
            x[:, 2] = 0.0
            v[:, 2] = 0.0
        species = [("a", "b", "Ar")[k % 3] for k in range(n)] if spec.get("species") else None
        w.add_particles(x, velocity=v, radius=0.004, mass=rng.uniform(0.5, 2.0, n), species=species)
        w.add(kinema.Gravity(g=[0.0, -9.81, 0.0]))
        if spec.get("box", True):
            w.add(kinema.Box([0.0] * dim, [1.0] * dim))
            if spec.get("periodic"):
                w.periodic = (True, False, False)
        if spec.get("springs") and n >= 2:
            w.add(kinema.Spring(list(range(n - 1)), list(range(1, n)), 5.0, damping=0.1))
        if spec.get("emitter"):
            w.add(
                kinema.Emitter(
                    rate=300.0, center=[0.5, 0.5, 0.0], speed=1.0, particle_radius=0.004, lifetime=0.02, color=[1.0, 0.2, 0.2], seed=spec.get("seed", 0)
                )
            )
        if spec.get("collisions"):
            w.set_collisions(restitution=0.8)
        frames = max(1, spec.get("frames", 3))
        self.world = w
        self.spec = spec
        self.traj = w.run(frames * 0.01, fps=100.0)


def write(writer: str, made: Made, path: Path, source: Path | None = None) -> Any:
    """Write ``made`` with ``writer`` to ``path``; returns what the writer returns."""
    if writer == "h5md":
        return made.traj.save(path)
    if writer in ("vtk", "ply", "xyz", "csv", "gsd", "lammps", "usd"):
        return made.traj.export(path, format=writer)
    if writer == "checkpoint":
        return made.world.save_checkpoint(path)
    if writer == "run_checkpoint":
        return made.world.run(0.03, fps=100.0, checkpoint=path, checkpoint_every=0.01)
    if writer == "toml":
        return made.world.to_scene().to_toml(path)
    if writer in ("gif", "mp4"):
        return made.traj.render(path, width=48, height=32)
    if writer in ("cli_export", "cli_render"):
        from fuzz_cases import _cli

        assert source is not None
        if writer == "cli_export":
            from kinema.io.exports import suffix_format

            argv = ["export", str(source), "--format", suffix_format(path) or "xyz", "--out", str(path)]
        else:
            argv = ["render", str(source), "--out", str(path), "--width", "48", "--height", "32"]
        return _cli({"argv": argv})
    raise ValueError(f"unknown writer {writer!r}")


def cli_faults(writer: str, cli: dict, faults: list, must_fail: bool = False) -> None:
    """`kinema export`/`render`/`run`: exit 0, or 2 with one error line, no traceback."""
    errors = [line for line in cli["stderr"].splitlines() if line.startswith("error:")]
    if "Traceback" in cli["stderr"]:
        faults.append(fault("CLI traceback", f"kinema {writer} printed a traceback (exit {cli['exit']}): {cli['stderr'][-1500:]}"))
    elif cli["exit"] not in ((2,) if must_fail else (0, 2)) or (cli["exit"] == 2 and len(errors) != 1):
        faults.append(fault("CLI exit", f"kinema {writer} exited {cli['exit']} with {len(errors)} error lines: {cli['stderr'][-1500:]}"))


def _series_names(writer: str, path: Path) -> set[str]:
    """The names beside ``path`` a VTK or PLY export writes (series folder, colliders, .pvd)."""
    fmt = writer if writer in ("vtk", "ply") else {".pvd": "vtk", ".vtp": "vtk", ".ply": "ply"}.get(path.suffix) if writer == "cli_export" else None
    if fmt == "vtk":
        return {f"{path.stem}_vtk", f"{path.stem}_colliders.vtp", f"{path.stem}.pvd"}
    if fmt == "ply":
        return {f"{path.stem}_ply"}
    return set()


def _written(value: Any, folder: Path, path: Path) -> set[str]:
    """The top-level names under ``folder`` a writer's answer names (and ``path``)."""
    names = {path.name}
    items = value if isinstance(value, list) else [value]
    for p in items:
        if isinstance(p, (str, os.PathLike)):
            try:
                rel = Path(p).resolve().relative_to(folder.resolve())
            except ValueError:
                continue
            if rel.parts:
                names.add(rel.parts[0])
    return names


def _complete_run_checkpoint(path: Path, base: str) -> bool:
    """Whether ``path`` is a complete checkpoint of a run in progress (kinema.checkpoint.load_run)."""
    from kinema.checkpoint import load_run

    copy = new_folder(base, "readback") / path.name
    try:
        shutil.copyfile(path, copy)
        load_run(copy)
        return True
    except Exception:  # noqa: BLE001
        return False
    finally:
        shutil.rmtree(copy.parent, ignore_errors=True)


def _moved(value: Any, folder: Path, copy: Path) -> Any:
    """The paths of a writer's answer, in ``copy`` instead of ``folder``."""
    if isinstance(value, list):
        return [_moved(v, folder, copy) for v in value]
    if isinstance(value, (str, os.PathLike)):
        try:
            return copy / Path(value).relative_to(folder)
        except ValueError:
            return value
    return value


def read_back(writer: str, made: Made, path: Path, value: Any, faults: list, calls: list) -> None:
    """A write that succeeded reads back (what it wrote is what was asked)."""
    import numpy as np

    import kinema

    def bad(detail: str) -> None:
        faults.append(fault("bad read-back", f"{writer} to {path.name} succeeded but {detail}"))

    if writer in ("cli_export", "cli_render"):
        if value.get("exit") != 0:
            return
        if path.suffix == ".ply":  # (a PLY export is its series folder)
            series = path.with_name(f"{path.stem}_ply")
            if not (series.is_dir() and len(list(series.iterdir())) == len(made.traj.t)):
                bad(f"{series.name}/ does not hold one file per frame")
        elif not path.is_file() or path.stat().st_size == 0:
            bad("the output is missing or empty")
        return
    if writer == "h5md":
        ok, back = attempt(calls, "Trajectory.load (read back)", lambda: kinema.Trajectory.load(path), ())
        if ok and not (np.array_equal(back.t, made.traj.t) and np.array_equal(back.positions, made.traj.positions, equal_nan=True)):
            bad("Trajectory.load gives other times or positions")
        return
    if writer == "checkpoint":
        ok, w = attempt(calls, "load_checkpoint (read back)", lambda: kinema.World.load_checkpoint(path), ())
        if ok and not (np.array_equal(w.positions, made.world.positions) and w.time == made.world.time):
            bad("load_checkpoint gives another state")
        return
    if writer == "run_checkpoint":
        if not path.exists():
            return  # (a run too short for a checkpoint)
        copy = path.with_name(path.name + ".resumed")
        shutil.copyfile(path, copy)
        try:
            ok, out = attempt(calls, "resume_run (read back)", lambda: kinema.resume_run(copy), ())
            if ok and not np.array_equal(out[0].positions, made.world.positions):
                bad("resume_run does not end where the run did")
        finally:
            copy.unlink(missing_ok=True)
        return
    if writer == "toml":
        ok, sc = attempt(calls, "Scene.from_toml (read back)", lambda: kinema.Scene.from_toml(path), ())
        if ok and sc.to_dict() != made.world.to_scene().to_dict():
            bad("Scene.from_toml gives another scene")
        return
    if writer == "gif":
        from PIL import Image

        try:
            with Image.open(path) as im:
                if im.n_frames < 1:
                    bad("the GIF has no frames")
        except Exception as e:  # noqa: BLE001
            bad(f"PIL cannot read it: {type(e).__name__}: {e}")
        return
    if writer == "mp4":
        data = path.read_bytes()[:12] if path.is_file() else b""
        if data[4:8] != b"ftyp":
            bad("the MP4 does not start with its ftyp box")
        return
    # exports: every file named exists and is complete
    files = [Path(p) for p in (value if isinstance(value, list) else [value])]
    for p in files:
        if not p.is_file() or p.stat().st_size == 0:
            bad(f"{p.name} is missing or empty")
            return
    main = files[0]
    n_frames = len(made.traj.t)
    if writer == "lammps":
        count = main.read_text().count("ITEM: TIMESTEP")
        if count != n_frames:
            bad(f"the dump has {count} frames, not {n_frames}")
    elif writer == "csv":
        rows = main.read_text().count("\n") - 1
        alive = getattr(made.traj, "alive", None)
        expected = int(np.asarray(alive).sum()) if alive is not None else n_frames * made.traj.positions.shape[1]
        if rows != expected:
            bad(f"the CSV has {rows} rows, not {expected}")
    elif writer == "ply":
        if len(files) != n_frames:
            bad(f"{len(files)} PLY files for {n_frames} frames")
    elif writer == "gsd":
        try:
            import gsd.hoomd

            with gsd.hoomd.open(str(main), "r") as f:
                if len(f) != n_frames:
                    bad(f"the GSD file has {len(f)} frames, not {n_frames}")
        except ImportError:
            pass
        except Exception as e:  # noqa: BLE001
            bad(f"gsd cannot read it: {type(e).__name__}: {e}")
    elif writer == "vtk":
        import xml.etree.ElementTree as ET

        try:
            sets = ET.parse(main).getroot().iter("DataSet")
            named = [main.parent / s.get("file") for s in sets]
        except Exception as e:  # noqa: BLE001
            bad(f"the .pvd does not parse: {e}")
            return
        missing = [p.name for p in named if not p.is_file()]
        if missing or len(named) != n_frames:
            bad(f"the .pvd names {len(named)} frames, {len(missing)} of them missing")
    elif writer == "usd":
        try:
            from pxr import Usd
        except ImportError:
            return
        try:
            if Usd.Stage.Open(str(main)) is None:
                bad("USD cannot open it")
        except Exception as e:  # noqa: BLE001 - pxr's Tf.ErrorException
            bad(f"USD cannot open it: {str(e).strip().splitlines()[-1][-300:]}")


# -- file-system faults -----------------------------------------------------------------------
def write_fault(ctx: Any, op: dict) -> dict:
    """A writer on a small tmpfs (with a filler file) or under RLIMIT_FSIZE; see the module doc."""
    calls: list = []
    faults: list = []
    writer, fault_spec = op["writer"], op["fault"]
    try:
        made = Made(op["spec"])
        small = Made({**op["spec"], "n": 2, "frames": 1, "emitter": False}) if op.get("previous") == "same" else None
    except Exception as e:  # noqa: BLE001 - the world could not be made: not a case
        return {"invalid": f"{type(e).__name__}: {e}"}
    source = None
    if writer.startswith("cli_"):
        source = new_folder(op["base"], "source") / "source.h5"
        made.traj.save(source)
    folder = new_folder(op["base"], "fault")
    mounted = False
    try:
        if fault_spec["kind"] == "tmpfs":
            why = mount_tmpfs(folder, fault_spec["size_kb"], fault_spec.get("inodes"))
            if why is not None:
                return {"invalid": why}
            mounted = True
        path = folder / f"{op.get('stem', 'run')}{op['suffix']}"
        # what was there before: bytes at the target, or an earlier write of the same writer
        previous = op.get("previous")
        if previous == "bytes":
            try:
                path.write_bytes(os.urandom(op.get("previous_size", 100)))
            except OSError:
                pass
        elif previous == "same":
            attempt(calls, f"{writer} (the earlier write)", lambda: write(writer, small, path, source), write_errors())
        if fault_spec["kind"] == "tmpfs" and fault_spec.get("filler"):
            try:
                with open(folder / "filler.bin", "wb") as f:
                    f.write(b"\xa5" * fault_spec["filler"])
            except OSError:
                pass
        if fault_spec.get("read_only"):
            why = mount_tmpfs(folder, 0, remount_ro=True)
            if why is not None:
                return {"invalid": why}
        before = snapshot(folder)
        if temporaries(before):
            faults.append(fault("leftover temp file", f"the earlier write left {temporaries(before)}"))
            before = {k: v for k, v in before.items() if k not in temporaries(before)}
        limit = fault_spec.get("limit") if fault_spec["kind"] == "fsize" else None
        with file_size_limit(limit) if limit is not None else contextlib.nullcontext():
            ok, value = attempt(calls, writer, lambda: write(writer, made, path, source), write_errors())
        if ok and writer.startswith("cli_"):
            cli_faults(writer, value, faults)
            ok = value["exit"] == 0
        leaked = open_descriptors(folder)
        if leaked:
            faults.append(fault("leaked fd", f"{writer} left descriptors open on {leaked[:5]}"))
            close_descriptors(folder)  # (so that the tmpfs can be unmounted)
        after = snapshot(folder)
        if not ok:
            may_change = None
            if writer == "run_checkpoint":  # the run wrote a checkpoint before the write that failed
                may_change = lambda name: name == path.name and _complete_run_checkpoint(folder / name, op["base"])  # noqa: E731
            compare_after_failure(before, after, faults, writer, may_change)
        else:
            temps = temporaries(after)
            if temps:
                faults.append(fault("leftover temp file", f"{writer} succeeded and left {temps[:8]}"))
            targets = _written(value, folder, path) | _series_names(writer, path)
            changed = sorted(k for k in before if Path(k).parts[0] not in targets and after.get(k) != before[k])
            if changed:
                faults.append(fault("destructive write", f"{writer} to {path.name} changed other files: {changed[:8]}"))
            # read back from a copy on the ordinary disk: reading the full tmpfs through a map
            # (gsd does) meets SIGBUS at a hole of a sparse file, which no page can fill
            copy = new_folder(op["base"], "readback")
            try:
                shutil.copytree(folder, copy, symlinks=True, dirs_exist_ok=True)
                read_back(writer, made, copy / path.name, _moved(value, folder, copy), faults, calls)
            finally:
                shutil.rmtree(copy, ignore_errors=True)
        return {"calls": calls, "faults": faults}
    except _Stop:
        return {"calls": calls, "faults": faults}
    finally:
        if mounted:
            unmount(folder)
        shutil.rmtree(folder, ignore_errors=True)
        if source is not None:
            shutil.rmtree(source.parent, ignore_errors=True)


# -- special files ----------------------------------------------------------------------------
def make_node(kind: str, path: Path) -> Any:
    """A FIFO, a private copy of /dev/null (a character device 1, 3), a bound unix socket
    (returned, to be closed) or a directory (with a file in it: dir_full) at ``path``."""
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "chardev":
        os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(1, 3))
    elif kind == "socket":
        s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        s.bind(str(path))
        return s
    elif kind in ("dir", "dir_full"):
        path.mkdir()
        if kind == "dir_full":
            (path / "keep.txt").write_text("mine\n")
    else:
        raise ValueError(f"unknown node {kind!r}")
    return None


def node_state(path: Path) -> tuple:
    """What must not change of a node: its own lstat (mode, device, inode), and through a link
    the target's, and the link's target name."""
    st = os.lstat(path)
    out: tuple = (stat.S_IFMT(st.st_mode), st.st_mode, st.st_rdev, st.st_ino)
    if stat.S_ISLNK(st.st_mode):
        t = os.stat(path)
        out += (os.readlink(path), stat.S_IFMT(t.st_mode), t.st_rdev, t.st_ino)
    return out


def _place_node(folder: Path, name: str, kind: str, link: bool) -> tuple[Path, Any]:
    target = folder / name
    if link:
        real = folder / f"zz-node-{kind}"
        sock = make_node(kind, real)
        os.symlink(real.name, target)
        return target, sock
    return target, make_node(kind, target)


def special_write(ctx: Any, op: dict) -> dict:
    """A writer whose target (or one of the names it writes: a series folder, a colliders
    file) is a FIFO, a device, a socket, a directory, or a link to one."""
    calls: list = []
    faults: list = []
    writer, kind = op["writer"], op["node"]
    if kind == "chardev" and os.geteuid() != 0:
        return {"invalid": "a device node needs root"}
    try:
        made = Made(op["spec"])
        dry = Made(op["spec"]) if writer == "run_checkpoint" else made
    except Exception as e:  # noqa: BLE001
        return {"invalid": f"{type(e).__name__}: {e}"}
    folder = new_folder(op["base"], "special")
    sock = None
    source = None
    try:
        if writer.startswith("cli_"):
            source = folder.parent / f"source-{os.getpid()}-{_COUNTER[0]}.h5"
            made.traj.save(source)
        path = folder / f"run{op['suffix']}"
        scratch = folder / "dry"
        scratch.mkdir()
        try:
            write(writer, dry, scratch / path.name, source)
        except Exception as e:  # noqa: BLE001 - the plain write fails: not a case
            return {"invalid": f"the write to a plain folder fails: {type(e).__name__}: {e}"}
        names = sorted(os.listdir(scratch))
        shutil.rmtree(scratch)
        others = [n for n in names if n != path.name]
        name = others[op.get("aux", 0) % len(others)] if op.get("where") == "aux" and others else path.name
        node, sock = _place_node(folder, name, kind, op.get("link", False))
        state = node_state(node)
        before = snapshot(folder)
        ok, value = attempt(
            calls, f"{writer} to a {kind}{' (linked)' if op.get('link') else ''} at {name}", lambda: write(writer, made, path, source), write_errors()
        )
        if ok and writer.startswith("cli_"):
            cli_faults(writer, value, faults)
            ok = value["exit"] == 0
        try:
            now = node_state(node)
        except OSError as e:
            now = ("gone", str(e))
        if now != state and not (ok and kind == "dir" and name.endswith(("_vtk", "_ply"))):
            faults.append(fault("node changed", f"{writer}: the {kind} at {name} was {state}, is {now}"))
        leaked = open_descriptors(folder)
        if leaked:
            faults.append(fault("leaked fd", f"{writer} left descriptors open on {leaked[:5]}"))
        after = snapshot(folder)
        # an empty folder (or a link to one) where a series folder goes is an earlier series of
        # no frames: replaced by design (kinema.io._files.atomic_folder)
        series = kind == "dir" and name.endswith(("_vtk", "_ply"))
        if ok:
            if name in names and not series:
                faults.append(fault("not refused", f"{writer} to {path.name} succeeded though {name}, a name it writes, is a {kind}"))
            temps = temporaries(after)
            if temps:
                faults.append(fault("leftover temp file", f"{writer} succeeded and left {temps[:8]}"))
            changed = sorted(k for k in before if Path(k).parts[0] not in names and after.get(k) != before[k])
            if changed:
                faults.append(fault("destructive write", f"{writer} changed {changed[:8]}"))
        else:
            compare_after_failure(before, after, faults, writer)
        return {"calls": calls, "faults": faults, "names": names, "node_at": name}
    except _Stop:
        return {"calls": calls, "faults": faults}
    finally:
        if sock is not None:
            sock.close()
        shutil.rmtree(folder, ignore_errors=True)
        if source is not None:
            source.unlink(missing_ok=True)


def special_read(ctx: Any, op: dict) -> dict:
    """A reader given a FIFO, a device, a socket, a directory or a link to one: a clean error
    of its own kind, no hang (a FIFO with no writer), the node as it was."""
    import kinema
    from kinema.checkpoint import CheckpointError, run_plan
    from kinema.io import TrajectoryFileError
    from kinema.scene import SceneError

    calls: list = []
    faults: list = []
    reader, kind = op["reader"], op["node"]
    if kind == "chardev" and os.geteuid() != 0:
        return {"invalid": "a device node needs root"}
    suffix, _ = READERS[reader]
    folder = new_folder(op["base"], "read")
    sock = None
    try:
        node, sock = _place_node(folder, f"input{suffix}", kind, op.get("link", False))
        state = node_state(node)
        before = snapshot(folder)
        fns = {
            "Scene.from_toml": (lambda: kinema.Scene.from_toml(node), (SceneError,)),
            "load_scene": (lambda: kinema.load_scene(node), (SceneError,)),
            "Trajectory.load": (lambda: kinema.Trajectory.load(node), (TrajectoryFileError,)),
            "World.load_checkpoint": (lambda: kinema.World.load_checkpoint(node), (CheckpointError,)),
            "resume_run": (lambda: kinema.resume_run(node), (CheckpointError,)),
            "run_plan": (lambda: run_plan(node), (CheckpointError,)),
        }
        if reader in fns:
            fn, allowed = fns[reader]
            ok, _ = attempt(calls, f"{reader} of a {kind}", fn, allowed + (MemoryError,))
            if ok:
                faults.append(fault("not refused", f"{reader} read a {kind} as if it were a file"))
        else:
            from fuzz_cases import _cli

            argv = (
                ["run", str(node), "--no-video", "--out", str(folder / "out")]
                if reader == "cli_run"
                else ["export", str(node), "--format", "xyz", "--out", str(folder / "out.xyz")]
            )
            cli = _cli({"argv": argv})
            calls.append({"call": f"kinema {argv[0]} of a {kind}", "result": "ok", "cli": cli})
            cli_faults(argv[0], cli, faults, must_fail=True)
        try:
            now = node_state(node)
        except OSError as e:
            now = ("gone", str(e))
        if now != state:
            faults.append(fault("node changed", f"{reader}: the {kind} was {state}, is {now}"))
        after = snapshot(folder)
        gone = sorted(k for k in before if after.get(k) != before[k])
        if gone:
            faults.append(fault("destructive write", f"{reader} changed {gone}"))
        return {"calls": calls, "faults": faults}
    except _Stop:
        return {"calls": calls, "faults": faults}
    finally:
        if sock is not None:
            sock.close()
        shutil.rmtree(folder, ignore_errors=True)


# -- threads ----------------------------------------------------------------------------------
class _Home:
    """The thread a world belongs to: this one, or a helper thread kept alive for the case."""

    def __init__(self, where: str) -> None:
        self.pool = None
        if where == "thread":
            from concurrent.futures import ThreadPoolExecutor

            self.pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="home")

    def __call__(self, fn: Any) -> Any:
        return fn() if self.pool is None else self.pool.submit(fn).result()

    def close(self) -> None:
        if self.pool is not None:
            self.pool.shutdown(wait=True)


def _thread_action(name: str, w: Any, folder: Path, traj: Any) -> Any:
    import numpy as np

    import kinema

    if name == "step":
        w.step(2)
    elif name == "run":
        w.run(0.02, fps=100.0)
    elif name == "read_positions":
        return float(np.nansum(w.positions)) + float(np.nansum(w.velocities)) + float(w.masses.sum())
    elif name == "write_positions":
        w.positions = np.array(w.positions)
    elif name == "inplace_positions":
        w.positions[...] = np.array(w.positions)
    elif name == "write_velocities":
        w.velocities = np.zeros_like(w.velocities)
    elif name == "add_force":
        w.add(kinema.Drag(0.1))
    elif name == "add_particles":
        w.add_particles([0.5, 0.5, 0.0])
    elif name == "remove_particles":
        w.remove_particles([0])
    elif name == "save_checkpoint":
        w.save_checkpoint(folder / "thread.ckpt")
    elif name == "to_scene":
        w.to_scene()
    elif name == "diagnostics":
        w.diagnostics()
    elif name == "len_time_dt":
        return len(w) + w.time + w.dt
    elif name == "repr":
        return repr(w)
    elif name == "set_collisions":
        w.set_collisions(restitution=0.5)
    elif name == "periodic":
        w.periodic = (False, False, False)
    elif name == "rates":
        w.rates()
    elif name == "stable_step":
        w.stable_step()
    elif name == "accelerations":
        return w.accelerations
    elif name == "contacts":
        w.contacts()
    elif name == "collision_stats":
        w.collision_stats()
    elif name == "ids":
        return w.ids
    elif name == "forces_colliders":
        return len(w.forces) + len(w.colliders)
    elif name == "trajectory_save":
        traj.save(folder / "thread.h5")
    elif name == "trajectory_export":
        traj.export(folder / "thread.xyz")
    else:
        raise ValueError(f"unknown action {name!r}")
    return None


def thread_use(ctx: Any, op: dict) -> dict:
    """A world made in its home thread (this one or a helper) and used from another thread,
    one action after the other or while the home thread runs it; then used at home again."""
    import gc

    import numpy as np
    from fuzz_cases import REENTRY_MESSAGES

    import kinema

    calls: list = []
    faults: list = []
    folder = new_folder(op["base"], "thread")
    home = _Home(op.get("home", "main"))
    allowed = (ValueError, TypeError, MemoryError, kinema.SimulationDiverged)
    messages = THREAD_MESSAGES + REENTRY_MESSAGES
    box: dict = {}
    try:
        try:
            home(lambda: box.update(made=Made(op["spec"])))
        except Exception as e:  # noqa: BLE001
            return {"invalid": f"{type(e).__name__}: {e}"}
        made = box["made"]
        w = made.world
        count = home(lambda: len(w))
        if op.get("drop"):
            # the last reference to the world goes in another thread (with its trajectory kept)
            notes: list = []
            old_hook = sys.unraisablehook
            sys.unraisablehook = lambda u: notes.append(f"{u.exc_type.__name__}: {u.exc_value}")
            holder = [w]
            del w, made, box["made"]

            def drop() -> None:
                holder.clear()
                gc.collect()

            t = threading.Thread(target=drop)
            t.start()
            t.join(30)
            gc.collect()
            sys.unraisablehook = old_hook
            calls.append({"call": "the world dropped in another thread", "result": "ok", "notes": notes})
            attempt(calls, "a new world at home", lambda: home(lambda: Made({"n": 2, "frames": 1}).world.step(1)), allowed, messages)
            return {"calls": calls, "faults": faults, "notes": notes}
        results: list = []
        start = threading.Event()

        def other() -> None:
            start.wait(10)
            for name in op["actions"]:
                try:
                    _thread_action(name, w, folder, made.traj)
                except BaseException as e:  # noqa: BLE001 - judged below
                    results.append(_judged(f"{name} (another thread)", e, allowed, messages))
                    continue
                results.append({"call": f"{name} (another thread)", "result": "ok"})

        t = threading.Thread(target=other)
        t.start()
        if op.get("concurrent"):
            start.set()
            attempt(calls, "run at home meanwhile", lambda: home(lambda: w.run(0.1, fps=100.0)), allowed, messages)
        else:
            start.set()
        t.join(15)
        if t.is_alive():
            faults.append(fault("hang", "the other thread's actions did not end within 15 s"))
        calls.extend(results)
        added = sum(1 for r in results if r.get("result") == "ok" and r["call"].startswith("add_particles"))
        removed = sum(1 for r in results if r.get("result") == "ok" and r["call"].startswith("remove_particles"))

        def again() -> None:
            w.step(2)
            w.diagnostics()
            w.rates()
            if not np.all(np.isfinite(w.positions)):
                raise ValueError("positions are not finite")

        try:
            home(again)
        except BaseException as e:  # noqa: BLE001
            faults.append(fault("broken world", f"after the other thread, the world fails in its own thread: {type(e).__name__}: {e}"))
        else:
            n = home(lambda: len(w))
            if n != count + added - removed and not made.spec.get("emitter"):
                faults.append(fault("broken world", f"the world has {n} particles; {count} + {added} added - {removed} removed expected"))
        return {"calls": calls, "faults": faults}
    finally:
        # the world goes in its home thread (pyo3 refuses to drop it elsewhere): every other
        # reference first, the home thread's last
        w = made = None  # noqa: F841
        try:
            home(lambda: (box.clear(), gc.collect()))
        finally:
            home.close()
        shutil.rmtree(folder, ignore_errors=True)


# -- sweeps run again -------------------------------------------------------------------------
def _sweep(scene: Path, args: dict, out: Path, timeout: float) -> dict:
    import tomli_w  # noqa: F401  (the scene is written by the caller)

    argv = [sys.executable, "-m", "kinema", "sweep", str(scene), "-o", str(out), "--workers", "1"]
    for item in args.get("vary", []):
        argv += ["--vary", item]
    if args.get("seeds") is not None:
        argv += ["--seeds", str(args["seeds"])]
    if args.get("duration") is not None:
        argv += ["--duration", str(args["duration"])]
    if args.get("checkpoint_every") is not None:
        argv += ["--checkpoint-every", str(args["checkpoint_every"])]
    env = {k: v for k, v in os.environ.items() if k != "KINEMA_DEBUG"} | {"MPLBACKEND": "Agg", "PYTHONFAULTHANDLER": "1"}
    try:
        proc = subprocess.run(argv, capture_output=True, text=True, timeout=timeout, env=env, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        return {"argv": argv[2:], "exit": None, "stderr": f"no end within {timeout} s"}
    return {"argv": argv[3:], "exit": proc.returncode, "stderr": proc.stderr[-3000:], "stdout": proc.stdout[-1000:]}


_LOG_RECORD = re.compile(r"^\d{4}-\d\d-\d\d \d\d:\d\d:\d\d,\d+ - ")


def _dask_log(stderr: str) -> tuple[str, str]:
    """(stderr without Dask's own log records, those records). Dask logs from its threads
    while a local cluster shuts down (a heartbeat to a scheduler already gone, with its
    traceback): not kinema's output, kept apart as a note."""
    own, dask, inside = [], [], False
    for line in stderr.splitlines(keepends=True):
        if _LOG_RECORD.match(line):
            inside = " - distributed." in line or " - tornado." in line
        elif inside and (
            line.startswith((" ", "\t", "Traceback", "The above", "During handling"))
            or not line.strip()
            or re.match(r"^[\w.]+(Error|Exception|Closed\w*)\b", line)
        ):
            pass
        else:
            inside = False
        (dask if inside else own).append(line)
    return "".join(own), "".join(dask)


def _text(path: Path, *folders: Path) -> str | None:
    try:
        text = path.read_text()
    except OSError:
        return None
    for k, f in enumerate(folders):
        text = text.replace(str(f.resolve()), f"<folder{k}>").replace(str(f), f"<folder{k}>")
    return text


def sweep_rerun(ctx: Any, op: dict) -> dict:
    """``kinema sweep`` into a folder, again with a change, and once into an empty folder: the
    second run's summary.csv is the fresh run's (no member reused that should not be)."""
    import tomli_w

    calls: list = []
    faults: list = []
    folder = new_folder(op["base"], "sweep")
    timeout = op.get("timeout", 150)
    try:
        scenes = []
        for k, data in enumerate((op["scene"], op.get("scene2") or op["scene"])):
            p = folder / f"scene{k}.toml"
            p.write_text(tomli_w.dumps(data))
            scenes.append(p)
        a, b = folder / "again", folder / "fresh"
        runs = {}
        runs["first"] = _sweep(scenes[0], op["first"], a, timeout)
        summary_first = _text(a / "summary.csv", a)
        done = sorted((a / "members").glob("*/result.json"))
        if op.get("forget") is not None and done:  # as if the first sweep had been stopped before that member finished
            done[op["forget"] % len(done)].unlink()
        runs["second"] = _sweep(scenes[1], op["second"], a, timeout)
        runs["fresh"] = _sweep(scenes[1], op["second"], b, timeout)
        notes = []
        for name, r in runs.items():
            calls.append({"call": f"kinema sweep ({name})", "result": "ok", "exit": r["exit"], "argv": r["argv"]})
            own, dask = _dask_log(r["stderr"])
            if dask:
                notes.append(f"the {name} sweep: Dask logged {dask[:600]}")
            if r["exit"] is None:
                faults.append(fault("hang", f"the {name} sweep: {r['stderr']}"))
            elif "Traceback" in own:
                faults.append(fault("CLI traceback", f"the {name} sweep exited {r['exit']} with a traceback: {own}"))
            elif r["exit"] not in (0, 1, 2):
                faults.append(fault("CLI exit", f"the {name} sweep exited {r['exit']}: {own}"))
        if any(f["kind"] == "hang" for f in faults):
            return {"calls": calls, "faults": faults}
        second, fresh = runs["second"], runs["fresh"]
        if second["exit"] != fresh["exit"]:
            faults.append(
                fault("stale result", f"run again it exited {second['exit']}, fresh {fresh['exit']}: {second['stderr'][-600:]} / {fresh['stderr'][-600:]}")
            )
        elif fresh["exit"] == 2:  # refused before running: the folder keeps the first run's summary
            if _text(a / "summary.csv", a) != summary_first:
                faults.append(fault("destructive write", "a sweep refused before running changed the folder's summary.csv"))
        else:
            again_csv, fresh_csv = _text(a / "summary.csv", a), _text(b / "summary.csv", b)
            if again_csv != fresh_csv:
                faults.append(fault("stale result", f"summary.csv run again:\n{again_csv}\nfresh:\n{fresh_csv}"))
            again_json, fresh_json = _text(a / "sweep.json", a), _text(b / "sweep.json", b)
            if again_json != fresh_json:
                faults.append(fault("stale result", f"sweep.json run again:\n{again_json}\nfresh:\n{fresh_json}"))
            temps = temporaries(snapshot(a))
            if temps:
                faults.append(fault("leftover temp file", f"the sweep left {temps[:8]}"))
        return {"calls": calls, "faults": faults, "runs": runs, "notes": notes}
    finally:
        shutil.rmtree(folder, ignore_errors=True)


# -- damaged checkpoints ----------------------------------------------------------------------
CHECKPOINT_BASES = ("gas", "springs_2d", "rk45")
_BASES: dict[tuple[str, str], Path] = {}


def _base_world(name: str) -> Any:
    import kinema

    if name == "gas":
        w = kinema.World(dt=0.002, method="verlet")
        w.add_particles([[0.2, 0.5, 0.5], [0.5, 0.5, 0.5], [0.8, 0.5, 0.5]], velocity=[1.0, 0.5, 0.0], radius=0.05, species=["a", "b", "a"])
        w.add(kinema.Gravity())
        w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
        w.add(kinema.Spring(0, 1, 10.0))
        w.add(
            kinema.Emitter(
                rate=200.0, shape="sphere", center=[0.5, 0.5, 0.8], radius=0.05, speed=1.0, particle_radius=0.02, lifetime=0.03, color=[1, 0, 0], seed=7
            )
        )
        w.add(kinema.KillBox([0, 0, 0], [1, 1, 0.1]))
        w.set_collisions(restitution=0.8)
        return w
    if name == "springs_2d":
        w = kinema.World(dim=2, dt=0.001, method="implicit_euler")
        w.add_particles(
            [[0.2, 0.5, 0.0], [0.3, 0.5, 0.0], [0.45, 0.52, 0.0], [0.7, 0.3, 0.0]], velocity=[[1.0, 0.0, 0.0]], radius=0.06, pinned=[False, False, False, True]
        )
        w.add(kinema.Box([0, 0], [1, 1]))
        w.periodic = (True, False, False)
        w.add(kinema.Drag(0.1, 0.01))
        w.add(kinema.Wind([0.5, 0.0, 0.0], 0.2))
        w.add(kinema.Spring([0, 1], [1, 2], [50.0, 60.0], damping=0.5))
        w.set_collisions(model="spring_dashpot", stiffness=1e4, damping=5.0, friction=0.0)  # (friction with a force model needs verlet)
        return w
    w = kinema.World(dt=0.01, method="rk45")
    w.add_particles([[1.0, 0.0, 0.0], [0.0, 1.5, 0.0]], velocity=[[0.0, 1.0, 0.0], [-0.8, 0.0, 0.1]], mass=[1.0, 2.0], radius=0.1)
    w.add(kinema.Attractor([0, 0, 0], 1.0, 0.01))
    w.add(kinema.SphereObstacle([0.0, 0.0, 0.0], 0.2, restitution=0.5))
    w.add(kinema.Plane([0, 0, -2], [0, 0, 1]))
    return w


def base_checkpoint(name: str, kind: str, base: str) -> Path:
    """A valid checkpoint (made once per worker, in ``base``): ``kind`` "world" by
    World.save_checkpoint after a short run, "run" by World.run(checkpoint=, checkpoint_every=)
    (a run in progress)."""
    if (name, kind) not in _BASES or not _BASES[(name, kind)].is_file():
        folder = new_folder(base, "checkpoints")
        w = _base_world(name)
        path = folder / f"{name}-{kind}.ckpt"
        if kind == "world":
            w.run(0.04, fps=100.0)
            w.save_checkpoint(path)
        else:
            w.run(0.06, fps=100.0, checkpoint=path, checkpoint_every=0.02)
        _BASES[(name, kind)] = path
    return _BASES[(name, kind)]


def checkpoint_layout(ctx: Any, op: dict) -> dict:
    """The datasets and attributes of a base checkpoint, and the text of its JSON and TOML
    attributes (the test process draws damages from them)."""
    import h5py

    path = base_checkpoint(op["world"], op["kind"], op["base"])
    datasets, attrs, texts = [], [], []
    with h5py.File(path, "r") as f:

        def note(name: str, obj: Any) -> None:
            for a in obj.attrs:
                attrs.append([name, a])
                v = obj.attrs[a]
                if isinstance(v, str):
                    texts.append([name, a, v])

        note("/", f)

        def visit(name: str, obj: Any) -> None:
            if isinstance(obj, h5py.Dataset):
                datasets.append([name, list(obj.shape), str(obj.dtype)])
            note(name, obj)

        f.visititems(visit)
    return {"layout": {"datasets": datasets, "attrs": attrs, "texts": texts, "size": path.stat().st_size}}


def checkpoint_damage(ctx: Any, op: dict) -> dict:
    """A damaged copy of a base checkpoint loaded (load_checkpoint, then two steps) or resumed
    (resume_run): success or a one-line CheckpointError, never another exception."""
    import h5py
    from fuzz_cases import _classify, _damage, _inspect

    import kinema
    from kinema.checkpoint import CheckpointError, run_plan

    calls: list = []
    faults: list = []
    base = base_checkpoint(op["world"], op["kind"], op["base"])
    folder = new_folder(op["base"], "ckpt")
    path = folder / base.name
    shutil.copyfile(base, path)
    try:
        m = op["damage"]
        try:
            if m["action"] == "flips":
                with open(path, "r+b") as fh:
                    for offset, byte in m["bytes"]:
                        fh.seek(offset)
                        fh.write(bytes([byte]))
            elif m["action"] == "set_text":
                with h5py.File(path, "r+") as f:
                    f[m["group"]].attrs[m["name"]] = m["text"]
            else:
                _damage(path, m, ctx)
        except Exception as e:  # noqa: BLE001 - h5py could not write this damage: not a case
            return {"invalid": f"{type(e).__name__}: {e}"}
        allowed = (CheckpointError, MemoryError)
        if op["then"] == "load":
            ok, w = attempt(calls, "load_checkpoint", lambda: kinema.World.load_checkpoint(path), allowed)
            if ok:
                ctx.world = w
                try:
                    w.step(2)
                    _inspect(w)
                    calls.append({"call": "step and inspect the loaded world", "result": "ok"})
                except Exception as e:  # noqa: BLE001 - judged as any world op
                    calls.append(
                        {
                            "call": "step and inspect the loaded world",
                            "type": type(e).__name__,
                            "message": str(e)[:600],
                            "verdict": _classify(e, {"op": "step"}, ctx),
                        }
                    )
                except BaseException as e:  # noqa: BLE001
                    calls.append({"call": "step and inspect the loaded world", "type": type(e).__name__, "message": str(e)[:600], "verdict": "bad"})
        else:
            ok, plan = attempt(calls, "run_plan", lambda: run_plan(path), allowed)
            if ok:
                left = (plan["frames_total"] - plan["frames_done"]) * plan["per_frame"]
                work = (plan["particles"] + plan["born"]) * left
                if left > 2e4 or work > 2e6:
                    return {"calls": calls, "faults": faults, "skipped": f"{left} steps left, {work:g} particle-steps: too long for a case"}
            attempt(calls, "resume_run", lambda: kinema.resume_run(path), allowed + (kinema.SimulationDiverged,))
        return {"calls": calls, "faults": faults}
    except _Stop:
        return {"calls": calls, "faults": faults}
    finally:
        shutil.rmtree(folder, ignore_errors=True)


OPS = {
    "write_fault": _with_known(write_fault),
    "special_write": _with_known(special_write),
    "special_read": special_read,
    "thread_use": _with_known(thread_use),
    "sweep_rerun": sweep_rerun,
    "checkpoint_layout": checkpoint_layout,
    "checkpoint_damage": checkpoint_damage,
}
