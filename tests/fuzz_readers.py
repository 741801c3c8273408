"""The worker's side of the fuzz suite's reader cases (tests/test_fuzz.py, "readers", issue 49):
malformed variants of real files of each format kinema writes, the side files a mesh or a
stage names, and the CLI's resume and rerun paths.

``reader_mutant``: a small trajectory written once per worker in each format (``traj.export``
to XYZ, LAMMPS, GSD, CSV, VTK (.pvd and its .vtp files), PLY (a folder of .ply files), USD
(.usda); ``traj.save`` to H5MD), one of its files damaged by 1-3 mutations (bytes flipped, cut
short, a line deleted or duplicated, a number or a count replaced by a huge, negative, NaN,
infinite, zero or non-number token), then ``kinema.load_trajectory``: it reads a consistent
trajectory (positions (F, N, 3), F times, velocities None or of the positions' shape; an
unchanged file reads as the base did: else a "wrong answer") or raises a one-line
``TrajectoryFileError`` naming one of the files (else an "unexpected exception"); a hang is the
worker's timeout.

``side_file``: an OBJ naming an ``mtllib``, a glTF whose buffer is a file, a USD mesh or points
stage naming a sublayer; the named file a FIFO (no writer), missing, a directory, a link to a
FIFO, shorter than a glTF's declared byteLength, or a regular good file: a clean one-line error
naming the file within the worker's timeout, or (a regular file, an OBJ's material library,
which is not followed) a mesh or trajectory read.

``cli_rerun``: ``kinema run`` of a small scene with checkpoints, stopped after its first
checkpoint (as Ctrl-C would), then ``--resume`` with the same scene (goes on: exit 0, the whole
trajectory, no checkpoint or .part left), with another scene or duration (one ``error:`` line,
exit 2, the checkpoint kept, no trajectory), and a whole run again (no checkpoint left).

Each op answers ``{"calls": [...], "faults": [...]}`` as tests/fuzz_faults.py's ops do.
"""

from __future__ import annotations

import os
import re
import shutil
import tempfile
from pathlib import Path
from typing import Any

from fuzz_faults import _judged, _Stop, attempt, fault, new_folder

FORMATS = {  # format: the main file's name (the one load_trajectory is given)
    "xyz": "t.xyz",
    "lammps": "t.lammpstrj",
    "gsd": "t.gsd",
    "csv": "t.csv",
    "vtk": "t.pvd",
    "ply": "t.ply",
    "usd": "t.usda",
    "h5md": "t.h5",
}
BINARY = ("gsd", "h5md")  # byte mutations only (a line or a number there is no unit of the format)
TOKENS = [
    "1e400",
    "-1e400",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "0",
    "-0",
    "-1",
    "1e308",
    "-1e308",
    "5e-324",
    "abc",
    "",
    "1.5",
    "0x10",
    "9223372036854775808",
    "-9223372036854775809",
    "18446744073709551616",
    "9" * 40,
    "1e",
    "--1",
    "1,5",
    "\x00",
    "é",
]
COUNTS = [
    "0",
    "-1",
    "1",
    "2",
    "4",
    "1000000",
    "2147483648",
    "9223372036854775807",
    "9223372036854775808",
    "99999999999999999999",
    "-9223372036854775809",
    "1.5",
    "nan",
    "x",
    "",
]
_NUMBER = re.compile(rb"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
_INT = re.compile(rb"(?<![\d.eE+-])\d+(?![\d.eE])")

_BASE: dict[str, Any] = {}


def _base() -> dict:
    """The base files, once per worker: {format: (folder, {relative name: bytes}, trajectory)}."""
    if not _BASE:
        import kinema

        folder = Path(tempfile.mkdtemp(prefix="kinema-fuzz-readers-"))
        w = kinema.World(dt=0.01)
        w.add_particles([[0.2, 0.5, 0.5], [0.5, 0.5, 0.5], [0.8, 0.5, 0.6]], velocity=[1.0, 0.5, 0.0], radius=0.05)
        w.add(kinema.Gravity())
        traj = w.run(0.03, fps=100)
        for fmt, name in FORMATS.items():
            sub = folder / fmt
            sub.mkdir()
            if fmt == "h5md":
                traj.save(sub / name)
            else:
                traj.export(sub / name)
            files = {str(p.relative_to(sub)): p.read_bytes() for p in sorted(sub.rglob("*")) if p.is_file()}
            _BASE[fmt] = (sub, files, kinema.load_trajectory(sub / name))
        _BASE["folder"] = folder
    return _BASE


def mutate(data: bytes, m: dict) -> bytes:
    """``data`` with one mutation (indices taken modulo what is there: any int draws a place)."""
    kind = m["kind"]
    if kind == "flip":
        if not data:
            return data
        at = m["at"] % len(data)
        return data[:at] + bytes([m["byte"]]) + data[at + 1 :]
    if kind == "truncate":
        return data[: m["at"] % (len(data) + 1)]
    if kind in ("delete_line", "dup_line"):
        lines = data.split(b"\n")
        k = m["line"] % len(lines)
        lines[k : k + 1] = [] if kind == "delete_line" else [lines[k], lines[k]]
        return b"\n".join(lines)
    if kind in ("number", "count"):
        spans = [x.span() for x in (_NUMBER if kind == "number" else _INT).finditer(data)]
        if not spans:
            return data
        a, b = spans[m["index"] % len(spans)]
        return data[:a] + m["value"].encode() + data[b:]
    if kind == "sub":  # a named regression: a regular expression replaced (every match)
        return re.sub(m["pattern"].encode(), m["value"].encode(), data)
    raise ValueError(f"unknown mutation {kind!r}")


def _names(folder: Path, files: dict) -> list[str]:
    """What a message may name: a file, or the series folder it is in (PLY's t_ply)."""
    parents = [str(folder / Path(n).parent) for n in files if Path(n).parent != Path(".")]
    return [str(folder / n) for n in files] + list(files) + [Path(n).name for n in files] + parents


# Bugs these cases found (issue 49's generators), not fixed yet: a bad call that is one of
# them is answered under "known" (not a failure), unless the op says "strict" (tests/test_fuzz.py
# test_a_reader_bug_found_by_the_generators: the strict xfail of each, which passes once fixed).
# name: (format, exception type, a piece of its message)
KNOWN_READER_BUGS: dict[str, tuple[str, tuple[str, ...], str]] = {
    # (none: the seven the generators found, a parser's raw exception on a damaged CSV, VTK,
    # PLY, USD or GSD file, are one-line TrajectoryFileErrors now: kinema.io.readers._DAMAGE,
    # and test_fuzz.READER_BUG_CASES keeps each as a regression)
}


def _known_reader_bug(fmt: str, call: dict) -> str | None:
    for name, (f, kinds, text) in KNOWN_READER_BUGS.items():
        if fmt == f and call.get("type") in kinds and text in call.get("message", ""):
            return name
    return None


def _consistent(traj: Any) -> str | None:
    import numpy as np

    x = np.asarray(traj.positions)
    if x.ndim != 3 or x.shape[2] != 3:
        return f"positions of shape {x.shape}"
    t = np.asarray(traj.t)
    if t.shape != (x.shape[0],):
        return f"{t.shape} times for {x.shape[0]} frames"
    v = traj.velocities
    if v is not None and np.asarray(v).shape != x.shape:
        return f"velocities of shape {np.asarray(v).shape} for positions {x.shape}"
    return None


def _same(a: Any, b: Any) -> bool:
    import numpy as np

    if (a.velocities is None) != (b.velocities is None):
        return False
    pairs = [(a.positions, b.positions), (a.t, b.t)] + ([] if a.velocities is None else [(a.velocities, b.velocities)])
    return all(np.shape(p) == np.shape(q) and np.array_equal(p, q, equal_nan=True) for p, q in pairs)


def reader_mutant(ctx: Any, op: dict) -> dict:
    import kinema
    from kinema.io import TrajectoryFileError

    calls: list = []
    faults: list = []
    src, files, good = _base()[op["format"]]
    folder = new_folder(op["base"], "reader")
    try:
        shutil.copytree(src, folder, dirs_exist_ok=True)
        names = sorted(files)
        name = names[op["file"] % len(names)]
        data = files[name]
        for m in op["mutations"]:
            data = mutate(data, m)
        (folder / name).write_bytes(data)
        changed = data != files[name]
        main = folder / FORMATS[op["format"]]
        try:
            traj = kinema.load_trajectory(main)
        except BaseException as e:  # noqa: BLE001 - judged here
            call = _judged(f"load_trajectory of {op['format']} with {name} damaged", e, (TrajectoryFileError, MemoryError))
            if isinstance(e, MemoryError):
                pass
            elif call["verdict"] == "allowed" and not any(n in str(e) for n in _names(folder, files)):
                call["verdict"], call["why"] = "bad", "the message names none of the files"
            elif call["verdict"] == "bad" and isinstance(e, ValueError | TypeError) and not call.get("why"):
                call["why"] = "not a TrajectoryFileError"
            calls.append(call)
            bug = _known_reader_bug(op["format"], call) if call["verdict"] == "bad" and not op.get("strict") else None
            if bug is not None:
                call["verdict"] = "known bug"
                return {
                    "calls": calls,
                    "faults": faults,
                    "known": [{"kind": "unexpected exception", "detail": f"{call['type']}: {call['message']}", "known": bug}],
                }
            if not changed and call["verdict"] == "allowed":
                faults.append(fault("wrong answer", f"{op['format']}: the unchanged files were refused: {call['message']}"))
            return {"calls": calls, "faults": faults}
        calls.append({"call": "load_trajectory", "result": "ok"})
        try:  # what a notebook shows first: a loaded Trajectory's one-line summary
            repr(traj)
        except Exception as e:  # noqa: BLE001 - judged here
            faults.append(fault("unexpected exception", f"repr of {op['format']} read back: {type(e).__name__}: {e}"))
        why = _consistent(traj)
        if why is not None:
            faults.append(fault("wrong answer", f"{op['format']} with {name} damaged read as a trajectory of {why}"))
        elif not changed and not _same(traj, good):
            faults.append(fault("wrong answer", f"{op['format']}: the unchanged files read otherwise than before"))
        return {"calls": calls, "faults": faults}
    finally:
        shutil.rmtree(folder, ignore_errors=True)


# -- side files -------------------------------------------------------------------------------
TRIANGLE_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
SIDE_KINDS = ("obj_mtllib", "gltf_buffer", "usd_mesh_sublayer", "usd_points_sublayer")
SIDE_TARGETS = ("fifo", "missing", "dir", "link_to_fifo", "short", "regular")


def _gltf(path: Path, uri: str, declared: int) -> bytes:
    import json

    import numpy as np

    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float32).tobytes()
    idx = np.array([0, 1, 2], dtype=np.uint32).tobytes()
    tree = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"uri": uri, "byteLength": declared}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": len(idx)}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"},
        ],
    }
    path.write_text(json.dumps(tree))
    return positions + idx


def _side_content(kind: str) -> bytes:
    if kind == "obj_mtllib":
        return b"newmtl m\nKd 1 0 0\n"
    if kind == "usd_points_sublayer":
        return b'#usda 1.0\n(\n    metersPerUnit = 1\n)\ndef Points "q" {\n    point3f[] points.timeSamples = { 0: [(0, 0, 0)], 1: [(0, 0, 1)] }\n}\n'
    return b'#usda 1.0\n(\n    metersPerUnit = 1\n)\ndef Mesh "n" {\n    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 0, 1)]\n    int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 2]\n}\n'


def side_file(ctx: Any, op: dict) -> dict:
    import kinema
    from kinema.io import TrajectoryFileError

    calls: list = []
    faults: list = []
    kind, target, side = op["kind"], op["target"], op["name"]
    folder = new_folder(op["base"], "side")
    try:
        other = folder / side
        blob = None
        if kind == "obj_mtllib":
            main = folder / "m.obj"
            main.write_text(f"mtllib {side}\n" + TRIANGLE_OBJ)
        elif kind == "gltf_buffer":
            main = folder / "m.gltf"
            blob = _gltf(main, side, 48 if target != "short" else op["declared"])
        else:
            main = folder / "m.usda"
            if kind == "usd_mesh_sublayer":
                body = 'def Mesh "m" {\n    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n    int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 2]\n}\n'
            else:
                body = 'def Points "p" {\n    point3f[] points.timeSamples = { 0: [(1, 2, 3)], 1: [(1, 2, 4)] }\n}\n'
            main.write_text(f'#usda 1.0\n(\n    metersPerUnit = 1\n    subLayers = [@./{side}@]\n    upAxis = "Z"\n)\n' + body)
        content = blob if blob is not None else _side_content(kind)
        if target == "fifo":
            os.mkfifo(other)
        elif target == "link_to_fifo":
            os.mkfifo(folder / "real-fifo")
            os.symlink(folder / "real-fifo", other)
        elif target == "dir":
            other.mkdir()
        elif target in ("regular", "short"):
            other.write_bytes(content)
        # ("missing": nothing there)
        read = (lambda: kinema.load_trajectory(main)) if kind == "usd_points_sublayer" else (lambda: kinema.Mesh(main))
        must_work = target == "regular" or (kind == "obj_mtllib")  # an OBJ's material library is never followed
        allowed = (TrajectoryFileError,) if kind == "usd_points_sublayer" else (ValueError,)
        try:
            read()
        except BaseException as e:  # noqa: BLE001 - judged here
            call = _judged(f"read {main.name} naming {side} ({target})", e, allowed + (MemoryError,))
            if call["verdict"] == "allowed" and str(main) not in str(e):
                call["verdict"], call["why"] = "bad", "the message does not name the file"
            calls.append(call)
            if call["verdict"] == "allowed" and must_work:
                faults.append(fault("wrong answer", f"{main.name} naming a {target} {side!r} was refused: {type(e).__name__}: {e}"))
            if not isinstance(e, Exception):
                raise _Stop(e) from None
            return {"calls": calls, "faults": faults}
        calls.append({"call": f"read {main.name} naming {side} ({target})", "result": "ok"})
        if not must_work:
            faults.append(fault("not refused", f"{main.name} naming a {target} {side!r} was read"))
        return {"calls": calls, "faults": faults}
    except _Stop:
        return {"calls": calls, "faults": faults}
    finally:
        shutil.rmtree(folder, ignore_errors=True)


# -- the CLI's resume and rerun paths ---------------------------------------------------------
def _scene(z: float, vz: float, duration: float, dt: float, fps: float) -> str:
    return f"""[world]
dim = 2
dt = {dt!r}
duration = {duration!r}
fps = {fps!r}

[[particles]]
type = "list"
positions = [[0, {z!r}]]
velocity = [0, {vz!r}]
radius = 0.05

[[forces]]
type = "gravity"

[[colliders]]
type = "plane"
point = [0, 0]
normal = [0, 1]

[output]
video = false
plot = false
"""


def _invoke(argv: list[str]) -> dict:
    from fuzz_cases import _cli

    return _cli({"argv": argv})


def _leftovers(out: Path) -> list[str]:
    return sorted(p.name for p in out.iterdir() if p.name.endswith((".ckpt", ".part")))


def cli_rerun(ctx: Any, op: dict) -> dict:
    import kinema
    import kinema.checkpoint

    calls: list = []
    faults: list = []
    folder = new_folder(op["base"], "rerun")
    try:
        s = op["scene"]
        scene = folder / "scene.toml"
        scene.write_text(_scene(**s))
        out = folder / "out"
        every = str(op["every"])
        extra = ["--duration", repr(op["duration"])] if op.get("duration") is not None else []
        save = kinema.checkpoint.save_checkpoint

        def save_then_stop(*args: Any, **kwargs: Any) -> Any:
            save(*args, **kwargs)
            raise KeyboardInterrupt

        kinema.checkpoint.save_checkpoint = save_then_stop
        try:
            first = _invoke(["run", str(scene), "--checkpoint-every", every, "-o", str(out), *extra])
        finally:
            kinema.checkpoint.save_checkpoint = save
        calls.append({"call": "run stopped after its first checkpoint", "result": "ok", "exit": first["exit"]})
        stopped = first["exit"] == 130
        if not stopped:  # a run too short for a checkpoint: it ended whole (or refused the scene)
            if first["exit"] == 0 and _leftovers(out):
                faults.append(fault("leftover temp file", f"a whole run left {_leftovers(out)}"))
            if first["exit"] not in (0, 2):
                faults.append(fault("CLI exit", f"the first run exited {first['exit']}: {first['stderr']}"))
            return {"calls": calls, "faults": faults}
        if not (out / "checkpoint.ckpt").is_file():
            faults.append(fault("partial output", "a run stopped after a checkpoint left none"))
            return {"calls": calls, "faults": faults}
        then = op["then"]
        if then in ("other_scene", "other_duration"):
            argv = ["run", str(scene), "--resume", "-o", str(out)]
            if then == "other_scene":
                other = folder / "other.toml"
                other.write_text(_scene(**{**s, "z": s["z"] + op["shift"]}))
                argv[1] = str(other)
                argv += extra
            else:
                argv += ["--duration", repr(op["other_duration"])]
            res = _invoke(argv)
            lines = res["stderr"].strip().splitlines()
            calls.append({"call": f"--resume with {then}", "result": "ok", "exit": res["exit"]})
            if res["exit"] != 2 or len(lines) != 1 or not lines[0].startswith("error: ") or "unexpected" in res["stderr"]:
                faults.append(fault("not refused", f"--resume with {then}: exit {res['exit']}, stderr {res['stderr']!r}"))
            if not (out / "checkpoint.ckpt").is_file() or (out / "trajectory.h5").exists():
                faults.append(fault("destructive write", f"--resume with {then} refused: the checkpoint went or a trajectory was written"))
        argv = ["run", str(scene), "-o", str(out), *extra] + (["--resume"] if then != "rerun" else [])
        res = _invoke(argv)
        calls.append({"call": "the same run " + ("resumed" if then != "rerun" else "run again whole"), "result": "ok", "exit": res["exit"]})
        if res["exit"] != 0:
            faults.append(fault("CLI exit", f"{' '.join(argv[2:])}: exit {res['exit']}: {res['stderr']}"))
            return {"calls": calls, "faults": faults}
        if _leftovers(out):
            faults.append(fault("leftover temp file", f"a finished run left {_leftovers(out)}"))
        ok, traj = attempt(calls, "load the trajectory", lambda: kinema.load_trajectory(out / "trajectory.h5"), ())
        if ok:
            duration = op.get("duration") or s["duration"]
            if abs(float(traj.t[-1]) - duration) > 1.01 / s["fps"]:
                faults.append(fault("wrong answer", f"the trajectory ends at {traj.t[-1]} s, not the run's {duration} s"))
        return {"calls": calls, "faults": faults}
    except _Stop:
        return {"calls": calls, "faults": faults}
    finally:
        shutil.rmtree(folder, ignore_errors=True)


OPS = {"reader_mutant": reader_mutant, "side_file": side_file, "cli_rerun": cli_rerun}
