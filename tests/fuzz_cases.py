"""The fuzz suite's cases and the worker process that runs them (used by tests/test_fuzz.py).

A case is a JSON description of a few calls of kinema's public API ("ops"), for example::

    {"ops": [{"op": "world", "kwargs": {"dim": 2}},
             {"op": "add_particles", "kwargs": {"position": [{"$f": "nan"}, 0, 0]}},
             {"op": "step", "args": [5]}]}

Values that JSON cannot hold are tagged (``decode`` makes the values, ``py`` their source): ``{"$f": "nan"}`` (also
``"inf"``, ``"-inf"``), ``{"$c": [re, im]}`` a complex number, ``{"$t": [...]}`` a tuple,
``{"$d": {...}}`` a dict, ``{"$b": "text"}`` bytes, ``{"$s": value, "dtype": "float32"}`` a
NumPy scalar, ``{"$a": [flat values], "shape": [2, 3], "dtype": "int64"}`` a NumPy array
(``dtype`` "list": nested Python lists of that shape), ``{"$ref": "tableau"}`` the
``ButcherTableau`` an earlier op built. Python ints of any size are JSON ints.

An ``oracle`` op (``{"op": "oracle", "name": ..., "kwargs": {...}}``) runs one of the checks
of ``ORACLES``: a small world built through the public API, run, and compared with a closed
form; a physically wrong result is the verdict ``"wrong answer"`` (a silent wrong answer).

``Worker`` (the test process's side) keeps one ``python tests/fuzz_cases.py --worker``
process, which imports kinema once and runs cases read from its stdin, one JSON line each,
answering one JSON line each: the outcome of every op (``"ok"`` or the exception's type,
message and ``verdict``). A crash signal, a hang (no answer within the timeout) or a
``PanicException`` is found by the test process; the worker is started again for the next
case. ``to_python`` writes a case as a Python reproducer.
"""

from __future__ import annotations

import json
import math
import os
import selectors
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve()
REPO = HERE.parent.parent

# The documented RuntimeError of kinema.World (kinema.world.REENTRY: a force must not use its
# world while the world runs it): a refusal by design, not a failure. Any other RuntimeError is.
REENTRY_MESSAGES = ("the world was used while it is stepping",)


# -- values ----------------------------------------------------------------------------------
def decode(v: Any, ctx: Any = None) -> Any:
    """The Python value an encoded value describes (run in the worker; imports NumPy)."""
    import numpy as np

    if isinstance(v, list):
        return [decode(x, ctx) for x in v]
    if not isinstance(v, dict):
        return v
    if "$f" in v:
        return float(v["$f"])
    if "$c" in v:
        re_, im = (decode(x, ctx) for x in v["$c"])
        return complex(re_, im)
    if "$t" in v:
        return tuple(decode(x, ctx) for x in v["$t"])
    if "$d" in v:
        return {k: decode(x, ctx) for k, x in v["$d"].items()}
    if "$b" in v:
        return v["$b"].encode()
    if "$s" in v:
        return np.array(decode(v["$s"], ctx), dtype=v["dtype"])[()]
    if "$ref" in v:
        return getattr(ctx, v["$ref"])
    if "$a" in v:
        flat = [decode(x, ctx) for x in v["$a"]]
        shape = tuple(v["shape"])
        if v["dtype"] == "list":
            return _nest(flat, list(shape))
        if v["dtype"] == "object":
            arr = np.empty(len(flat), dtype=object)
            for k, x in enumerate(flat):
                arr[k] = x
            return arr.reshape(shape)
        return np.array(flat, dtype=v["dtype"]).reshape(shape)
    raise ValueError(f"not an encoded value: {v!r}")


def _nest(flat: list, shape: list[int]) -> Any:
    if not shape:
        return flat[0]
    if len(shape) == 1:
        return list(flat)
    step = math.prod(shape[1:])
    return [_nest(flat[k * step : (k + 1) * step], shape[1:]) for k in range(shape[0])]


def py(v: Any) -> str:
    """Python source for an encoded value (for reproducers)."""
    if isinstance(v, list):
        return "[" + ", ".join(py(x) for x in v) + "]"
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, int) and not isinstance(v, bool) and abs(v) >= 2**31:
        return _int_source(v)
    if not isinstance(v, dict):
        return repr(v)
    if "$f" in v:
        return f"float({v['$f']!r})"
    if "$c" in v:
        return f"complex({py(v['$c'][0])}, {py(v['$c'][1])})"
    if "$t" in v:
        items = [py(x) for x in v["$t"]]
        return "(" + ", ".join(items) + ("," if len(items) == 1 else "") + ")"
    if "$d" in v:
        return "{" + ", ".join(f"{k!r}: {py(x)}" for k, x in v["$d"].items()) + "}"
    if "$b" in v:
        return repr(v["$b"].encode())
    if "$s" in v:
        return f"np.array({py(v['$s'])}, dtype={v['dtype']!r})[()]"
    if "$ref" in v:
        return v["$ref"]
    if "$a" in v:
        shape = list(v["shape"])
        if v["dtype"] == "list":
            return py(_nest(v["$a"], shape))
        if v["dtype"] == "object":
            return f"_objects({py(v['$a'])}, {tuple(shape)!r})"
        return f"np.array({py(v['$a'])}, dtype={v['dtype']!r}).reshape({tuple(shape)!r})"
    return repr(v)


def _int_source(v: int) -> str:
    sign, a = ("-" if v < 0 else ""), abs(v)
    for base in (2, 10):
        k = round(math.log(a, base))
        for off, text in ((0, ""), (1, " - 1"), (-1, " + 1")):
            if base**k - off == a:
                return f"{sign}({base}**{k}{text})" if text else f"{sign}{base}**{k}"
    return repr(v)


def _call(fn: str, op: dict) -> str:
    parts = [py(a) for a in op.get("args", [])] + [f"{k}={py(x)}" for k, x in op.get("kwargs", {}).items()]
    return f"{fn}({', '.join(parts)})"


def _fn_source(spec: dict, args: str, state: str) -> str:
    kind = spec["fn"]
    if kind == "decay":
        return f"lambda {args}: -{state}"
    if kind == "scale":
        return f"lambda {args}: {py(spec['k'])} * {state}"
    if kind == "const":
        return f"lambda {args}: {py(spec['value'])}"
    if kind == "reenter":
        return f"lambda {args}: reenter(w, {spec['action']!r}, x)"
    return repr(spec)


def to_python(case: dict) -> str:
    """A case as Python source (a reproducer); ops that are not plain calls are shown as data."""
    lines = ["import numpy as np", "import kinema", "w = kinema.World()"]
    if any(op["op"] == "world" for op in case["ops"]):
        lines.pop()
    if all(op["op"] == "oracle" for op in case["ops"]):  # (from the repository root)
        lines = ["import sys", "sys.path.insert(0, 'tests')", "from fuzz_cases import ORACLES  # each raises fuzz_cases.WrongAnswer on a wrong answer"]
    for op in case["ops"]:
        kind = op["op"]
        if kind == "world":
            lines.append(f"w = {_call('kinema.World', op)}")
        elif kind in ("add_particles", "set_collisions", "step", "run"):
            lines.append(_call(f"w.{kind}", op))
        elif kind == "add":
            kwargs = dict(op.get("kwargs", {}))
            if op["kind"] == "PythonForce":
                kwargs = {"fn": None, **kwargs}
                call = _call("kinema.PythonForce", {"kwargs": kwargs}).replace("fn=None", "fn=" + _fn_source(op["fn"], "t, x, v", "x"))
            elif op["kind"] == "value":
                call = py(op["value"])
            else:
                call = _call(f"kinema.{op['kind']}", {"kwargs": kwargs})
            lines.append(f"w.add({call})")
        elif kind in ("periodic", "positions", "velocities", "masses"):
            lines.append(f"w.{kind} = {py(op['value'])}")
        elif kind == "call":
            lines.append(_call(f"w.{op['method']}", op) if op["method"] != "accelerations" else "w.accelerations")
        elif kind == "inspect":
            lines.append("w.diagnostics(); w.contacts(); w.collision_stats(); w.rates(); w.stable_step(); w.accelerations; w.to_scene()")
        elif kind == "tableau":
            lines.append(f"tableau = {_call('kinema.ButcherTableau', op)}")
        elif kind in ("solve", "solve_second_order"):
            rhs = _fn_source(op["fn"], "t, y" if kind == "solve" else "t, x, v", "y" if kind == "solve" else "x")
            extra = {"kwargs": dict(op.get("kwargs", {}))}
            if "jac" in op:
                extra["kwargs"]["jac"] = "JAC"
            text = _call(f"kinema.{kind}", {"args": op.get("args", []), **extra}).replace(f"kinema.{kind}(", f"kinema.{kind}({rhs}, ", 1)
            if "jac" in op:
                text = text.replace("jac='JAC'", "jac=" + _fn_source(op["jac"], "t, y", "np.eye(len(y))"))
            lines.append(text)
        elif kind == "stability":
            lines.append(_call(f"kinema.stability.{op['fn']}", op))
        elif kind == "oracle":
            lines.append(_call(f"ORACLES[{op['name']!r}]", op))
        else:
            lines.append(f"# {json.dumps(op)}")
    text = "\n".join(lines)
    helpers = [source for name, source in _HELPERS.items() if f"{name}(" in text]
    return text.replace("import kinema\n", "import kinema\n" + "".join(helpers), 1)


_HELPERS = {
    "_objects": """def _objects(items, shape):  # an object array of these items
    a = np.empty(len(items), dtype=object)
    for k, x in enumerate(items):
        a[k] = x
    return a.reshape(shape)
""",
    "reenter": """def reenter(w, action, x):  # a force that uses its own world (the fuzz worker's)
    if action == "step": w.step(1)
    elif action == "add_particles": w.add_particles([0.0, 0.0, 0.0])
    elif action == "diagnostics": w.diagnostics()
    elif action == "set_positions": w.positions = np.zeros((len(w), 3))
    elif action == "read_core": w.time + w.dt + len(w)
    elif action == "read_views": w.positions.sum() + w.velocities.sum() + w.masses.sum() + len(w.forces)
    return np.zeros_like(x)
""",
}


# -- the test process's side -----------------------------------------------------------------
class Worker:
    """One worker process, started on demand and again after it died or hung."""

    def __init__(self, timeout: float = 20.0):
        self.timeout = timeout
        self.proc: subprocess.Popen | None = None
        self.buffer = b""
        self.stderr = None
        self.cases = 0

    def start(self) -> None:
        self.stderr = tempfile.TemporaryFile()
        env = {k: v for k, v in os.environ.items() if k != "KINEMA_DEBUG"}
        env["PYTHONFAULTHANDLER"] = "1"  # a crash prints the Python stack to stderr
        env["MPLBACKEND"] = "Agg"  # the CLI draws its energy plot
        self.proc = subprocess.Popen(
            [sys.executable, "-u", str(HERE), "--worker"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self.stderr, cwd=REPO, env=env
        )
        self.buffer = b""
        ready = self._answer(max(60.0, self.timeout))
        if not (isinstance(ready, dict) and ready.get("ready")):
            tail = self._stderr_tail()
            self.stop()
            raise RuntimeError(f"the fuzz worker did not start: {ready!r}\n{tail}")

    def stop(self) -> None:
        if self.proc is not None:
            if self.proc.poll() is None:
                self.proc.kill()
            self.proc.wait()
            for stream in (self.proc.stdin, self.proc.stdout):
                try:
                    stream.close()
                except OSError:
                    pass
            self.proc = None
        if self.stderr is not None:
            self.stderr.close()
            self.stderr = None

    def _stderr_tail(self, since: int = 0, limit: int = 3000) -> str:
        if self.stderr is None:
            return ""
        self.stderr.flush()
        self.stderr.seek(since)
        text = self.stderr.read().decode(errors="replace")
        self.stderr.seek(0, os.SEEK_END)
        return text[-limit:]

    def _answer(self, timeout: float) -> Any:
        """The next JSON line from the worker; "hang" after ``timeout`` s, "eof" when it closed."""
        assert self.proc is not None and self.proc.stdout is not None
        fd = self.proc.stdout.fileno()
        end = time.monotonic() + timeout
        with selectors.DefaultSelector() as sel:
            sel.register(fd, selectors.EVENT_READ)
            while b"\n" not in self.buffer:
                left = end - time.monotonic()
                if left <= 0:
                    return "hang"
                if not sel.select(left):
                    continue
                chunk = os.read(fd, 65536)
                if not chunk:
                    return "eof"
                self.buffer += chunk
        line, self.buffer = self.buffer.split(b"\n", 1)
        return json.loads(line)

    def run(self, case: dict, timeout: float | None = None) -> dict:
        """Run one case; returns the worker's answer, or {"status": "crash"|"hang", ...}."""
        if self.proc is None or self.proc.poll() is not None:
            self.stop()
            self.start()
        assert self.proc is not None and self.proc.stdin is not None and self.stderr is not None
        self.stderr.seek(0, os.SEEK_END)
        before = self.stderr.tell()
        self.cases += 1
        try:
            self.proc.stdin.write((json.dumps(case) + "\n").encode())
            self.proc.stdin.flush()
            answer = self._answer(self.timeout if timeout is None else timeout)
        except BrokenPipeError:
            answer = "eof"
        if answer == "hang":
            self.proc.kill()
            self.proc.wait()
            tail = self._stderr_tail(before)
            self.stop()
            return {"status": "hang", "timeout_s": self.timeout if timeout is None else timeout, "stderr": tail}
        if answer == "eof":
            try:
                rc = self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                rc = self.proc.wait()
            tail = self._stderr_tail(before)
            self.stop()
            sig = signal.Signals(-rc).name if rc < 0 and -rc in signal.Signals._value2member_map_ else None
            return {"status": "crash", "returncode": rc, "signal": sig, "stderr": tail}
        err = self._stderr_tail(before)
        if "panicked at" in err:  # a Rust panic, even one caught and turned into another error
            answer["panic_output"] = err
        return answer


def findings(answer: dict, allow_exit_1_divergence: bool = True) -> list[tuple[str, str]]:
    """What is wrong with a worker's answer, as (kind, text) pairs (empty: nothing). The kinds
    (the columns of the session's report): crash, hang, panic, unexpected exception, wrong
    answer (an oracle's: the call succeeded, the physics is wrong), CLI traceback, CLI exit,
    and the faults of tests/fuzz_faults.py (destructive write, leftover temp file, partial
    output, bad read-back, node changed, not refused, leaked fd, broken world, stale result)."""
    status = answer.get("status")
    if status == "crash":
        return [("crash", f"the worker process died (returncode {answer['returncode']}, signal {answer['signal']}); stderr:\n{answer['stderr']}")]
    if status == "hang":
        return [("hang", f"no answer within {answer['timeout_s']} s (a hang); stderr:\n{answer['stderr']}")]
    out = []
    if "panic_output" in answer:
        out.append(("panic", f"a Rust panic was printed:\n{answer['panic_output']}"))

    def judged(k: int, r: dict, where: str) -> None:
        if r.get("verdict") == "wrong answer":
            out.append(("wrong answer", f"op {k} ({where}): a wrong answer: {r['message']}"))
        if r.get("verdict") == "bad":
            kind = "panic" if r.get("type") == "PanicException" else "unexpected exception"
            why = f" ({r['why']})" if r.get("why") else ""
            out.append((kind, f"op {k} ({where}) raised {r['type']} (not an allowed error){why}: {r['message']}"))

    for k, r in enumerate(answer.get("ops", [])):
        judged(k, r, r.get("op", "?"))
        for c in r.get("calls", []):
            judged(k, c, f"{r.get('op')}: {c.get('call')}")
        for f in r.get("faults", []):
            out.append((f["kind"], f"op {k} ({r.get('op')}): {f['kind']}: {f['detail']}"))
        cli = r.get("cli")
        if cli is not None and "skipped" not in cli:
            code, err = cli["exit"], cli["stderr"]
            if "Traceback" in err:
                out.append(("CLI traceback", f"op {k}: the CLI printed a traceback (exit {code}):\n{err}"))
            if code == 1 and not (allow_exit_1_divergence and "diverged" in err and "unexpected" not in err):
                out.append(("CLI exit", f"op {k}: the CLI exited 1 (not a divergence):\n{err}"))
            elif code not in (0, 1, 2):
                out.append(("CLI exit", f"op {k}: the CLI exited {code}:\n{err}"))
    return out


def problems(answer: dict, allow_exit_1_divergence: bool = True) -> list[str]:
    """What is wrong with a worker's answer (empty: nothing)."""
    return [text for _, text in findings(answer, allow_exit_1_divergence)]


def invalid(answer: dict) -> bool:
    """Whether the case could not be set up (h5py could not write a damage, a mount failed):
    not a test of kinema."""
    return any(isinstance(r, dict) and r.get("invalid") for r in answer.get("ops", []))


# -- the session's report ------------------------------------------------------------------
# Every case the fuzz tests ran (tests/test_fuzz.py records each with its category); the
# terminal summary (tests/conftest.py) prints the table and writes it as JSON to
# $KINEMA_FUZZ_REPORT when set.
REPORT: list[dict] = []


def record(category: str, test: str, kinds: list[str], known: list[str] = ()) -> None:
    """One case of ``test``: its failure kinds (none: clean) and the known bugs it met
    (tests/fuzz_faults.KNOWN_BUGS: answered apart, not failures)."""
    REPORT.append({"category": category, "test": test, "kinds": sorted(set(kinds)), "known": sorted(set(known))})


def mark_failed_tests(failed: list[str], category_of: dict[str, str]) -> None:
    """Tests that failed on their own assertions (after answers the worker judged clean): for
    each failed test (one name per failed report, a parametrized test's several times) that
    its failing cases do not account for, its last clean case becomes a failure of kind "test
    assertion" (a new one where none is left), so that the report counts every failed test."""
    from collections import Counter

    for name, n in Counter(failed).items():
        mine = [r for r in REPORT if r["test"] == name]
        clean = [r for r in mine if not r["kinds"]]
        for k in range(max(0, n - (len(mine) - len(clean)))):
            if k < len(clean):
                clean[-1 - k]["kinds"] = ["test assertion"]
            else:
                record(category_of.get(name, "uncategorized"), name, ["test assertion"])


def known_bugs(answer: dict) -> list[str]:
    """The known bugs (tests/fuzz_faults.KNOWN_BUGS) the answer's ops met."""
    return [f["known"] for r in answer.get("ops", []) if isinstance(r, dict) for f in r.get("known", [])]


def report_table(records: list[dict] | None = None) -> dict:
    """Per category: tries, clean cases, the failing cases by kind (a case that failed in two
    ways counts under both kinds, once in ``failed``) and the cases that met a known bug (clean
    otherwise: counted in ``clean`` too)."""
    out: dict[str, dict] = {}
    for r in REPORT if records is None else records:
        row = out.setdefault(r["category"], {"tries": 0, "clean": 0, "failed": 0, "failures": {}, "known_bugs": {}})
        row["tries"] += 1
        if not r["kinds"]:
            row["clean"] += 1
        else:
            row["failed"] += 1
            for kind in r["kinds"]:
                row["failures"][kind] = row["failures"].get(kind, 0) + 1
        for bug in r.get("known", []):
            row["known_bugs"][bug] = row["known_bugs"].get(bug, 0) + 1
    return dict(sorted(out.items()))


def format_report(table: dict) -> str:
    lines = [f"{'category':<16} {'tries':>7} {'clean':>7} {'failed':>7}  failures by kind [known bugs met]"]
    total = {"tries": 0, "clean": 0, "failed": 0}
    for cat, row in table.items():
        kinds = ", ".join(f"{k}: {n}" for k, n in sorted(row["failures"].items())) or "-"
        if row.get("known_bugs"):
            kinds += "  [" + ", ".join(f"{k}: {n}" for k, n in sorted(row["known_bugs"].items())) + "]"
        lines.append(f"{cat:<16} {row['tries']:>7} {row['clean']:>7} {row['failed']:>7}  {kinds}")
        for k in total:
            total[k] += row[k]
    lines.append(f"{'total':<16} {total['tries']:>7} {total['clean']:>7} {total['failed']:>7}")
    return "\n".join(lines)


# -- oracles: physics against closed forms ---------------------------------------------------
# An oracle op, {"op": "oracle", "name": ..., "kwargs": {...}}, runs ORACLES[name](**kwargs) in
# the worker: the check builds its world through kinema's public API, runs it and compares what
# it did with a closed form. A result that is physically wrong raises WrongAnswer (the op's
# verdict "wrong answer": a silent wrong answer, the call succeeded); so does a refusal
# (ValueError, TypeError, SimulationDiverged) where the physics must work (``_oracle``). The
# refusals that are the right answer (a turn beyond the detection's sweep, speeds the events
# cannot follow) are expected by the check itself, and a refusal of another kind there is wrong
# too. Each check returns what it checked (in the op's answer). A reproducer, from the
# repository root: ``import sys; sys.path.insert(0, "tests"); from fuzz_cases import ORACLES;
# ORACLES[name](**kwargs)`` (``to_python`` writes it).
G = 9.81  # kinema.Gravity()'s
BALL = 0.05  # the balls' radius
PLATE_FACES = [[0, 1, 2], [0, 2, 3]]  # a square's two triangles, their seam x = y


class WrongAnswer(Exception):
    """An oracle's verdict: kinema answered, but not what the physics gives."""


def _plate(half: float) -> list[list[float]]:
    """A flat square of half-width ``half`` m in z = 0, centred at the origin."""
    return [[-half, -half, 0.0], [half, -half, 0.0], [half, half, 0.0], [-half, half, 0.0]]


def _cube(half: float = 0.5) -> tuple[Any, Any]:
    """A closed cube mesh (tests/test_moving_meshes_hold.py's): its 8 corners and 12 outward triangles."""
    import itertools

    import numpy as np

    v = np.array(list(itertools.product((-half, half), repeat=3)), float)
    faces = []
    for axis in range(3):
        for sign in (-1, 1):
            quad = [k for k in range(8) if np.sign(v[k, axis]) == sign]
            c = v[quad].mean(axis=0)
            others = [a for a in range(3) if a != axis]
            angle = np.arctan2(v[quad, others[1]] - c[others[1]], v[quad, others[0]] - c[others[0]])
            ring = [quad[k] for k in np.argsort(angle)]
            a, b, d = v[ring[0]], v[ring[1]], v[ring[2]]
            if np.dot(np.cross(b - a, d - a), c) < 0:
                ring = ring[::-1]
            faces += [[ring[0], ring[1], ring[2]], [ring[0], ring[2], ring[3]]]
    return v, np.array(faces)


def _finite(w: Any, what: str) -> None:
    import numpy as np

    if not (np.all(np.isfinite(w.positions)) and np.all(np.isfinite(w.velocities))):
        raise WrongAnswer(f"{what}: a position or velocity is not finite at t = {w.time!r} s: {w.positions.tolist()} {w.velocities.tolist()}")


def moving_plate_side(
    kind: str, half: float, plate: list, start: list, ball: list, side: int, gap: float, dt: float, gravity: bool, restitution: float, steps: int
) -> dict:
    """A ball (r = 0.05 m) starting ``gap`` m on one ``side`` (±1) of a plate (a two-triangle
    ``"mesh"`` of half-width ``half``, or a one-sided ``"plane"``: side +1 only) that moves at
    the constant velocity ``plate``: whenever its centre is over the plate (0.1 m inside its
    edges) it is on its side of the plate, whose z at time t is plate_z t. A plate is a wall:
    no speed of the ball or the plate, no restitution, no step takes the ball through it."""
    import kinema

    w = kinema.World(dim=3, dt=dt)
    w.add_particles([[start[0], start[1], side * gap]], velocity=[ball], radius=BALL)
    motion = kinema.Motion(velocity=plate)
    if kind == "mesh":
        w.add(kinema.Mesh(vertices=_plate(half), faces=PLATE_FACES, motion=motion))
    else:
        w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], motion=motion))
    if gravity:
        w.add(kinema.Gravity())
    w.set_collisions(restitution=restitution)
    checked = 0
    for k in range(1, steps + 1):
        w.step(1)
        _finite(w, f"step {k}")
        x, t = w.positions[0], w.time
        if kind == "plane" or (abs(x[0] - plate[0] * t) < half - 0.1 and abs(x[1] - plate[1] * t) < half - 0.1):
            checked += 1
            beyond = -(x[2] - plate[2] * t) * side
            if beyond > 0:
                raise WrongAnswer(
                    f"the ball went through the moving plate: after step {k} (t = {t!r} s) its centre is {beyond:.6g} m on the other side "
                    f"(z = {x[2]!r}, the plate at z = {plate[2] * t!r}; over the plate at x - plate_x = {x[0] - plate[0] * t:.6g}, y - plate_y = {x[1] - plate[1] * t:.6g})"
                )
    return {"checked": checked}


def sliding_plate_throw(kind: str, at: list, slide: list, speed: float, restitution: float) -> dict:
    """A plate (a 100 m wide two-triangle ``"mesh"``, or a ``"plane"``) moving at (slide_x,
    slide_y, ``speed``) up to a frictionless ball at rest at (at_x, at_y, 0.2) (on the mesh's
    seam x = y, beside it or at its shared vertices): the ball leaves at (0, 0, (1 + e) speed),
    to 1e-9 speed (the plate's sliding in its own plane gives a frictionless ball no sideways
    kick; Newton's law with the plate's normal speed)."""
    import math

    import numpy as np

    import kinema

    dt = 1e-3
    w = kinema.World(dim=3, dt=dt)
    w.add_particles([[at[0], at[1], 0.2]], radius=BALL)
    motion = kinema.Motion(velocity=(slide[0], slide[1], speed))
    if kind == "mesh":
        w.add(kinema.Mesh(vertices=_plate(100.0), faces=PLATE_FACES, motion=motion))
    else:
        w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], motion=motion))
    w.set_collisions(restitution=restitution)
    steps = int(math.ceil(0.15 / speed / dt)) + 3  # the plate meets the ball at 0.15 / speed s
    w.step(steps)
    v, want = w.velocities[0], np.array([0.0, 0.0, (1.0 + restitution) * speed])
    err = float(np.max(np.abs(v - want)))
    if not err <= 1e-9 * speed:
        raise WrongAnswer(f"after {steps} steps the ball's velocity is {v.tolist()}, not {want.tolist()} (off by {err:.3g} m/s > 1e-9 x {speed!r})")
    return {"steps": steps}


def turning_cube(turn: float, axis: list, count: int, restitution: float, friction: float, steps: int, half: float = 0.5) -> dict:
    """``count`` balls (r = 0.05 m) on a grid (±0.6 ``half``) in a closed cube mesh container
    (half-width ``half`` m, ``inside=True``) turning about ``axis`` through its centre, the
    origin, by ``turn`` rad a step (dt = 1 ms), under gravity: every ball stays inside, in the
    cube's own frame (positions turned back by R(ω t)ᵀ: every coordinate within ±``half``;
    a ball's centre stays r inside, so the check allows the end-of-step overlap). A turn above 0.1 rad a step must be
    refused instead, by a ValueError naming the collider (the right answer there; a turn within
    1e-12 of 0.1 may go either way)."""
    import math

    import numpy as np
    from scipy.spatial.transform import Rotation

    import kinema

    dt = 1e-3
    a = np.asarray(axis, float)
    omega = a / np.linalg.norm(a) * (turn / dt)
    per_step = float(np.linalg.norm(omega)) * dt
    v, f = _cube(half)
    k = math.ceil(round(count ** (1 / 3), 9))
    g = np.linspace(-0.6 * half, 0.6 * half, k)
    grid = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)[:count]
    w = kinema.World(dim=3, dt=dt)
    w.add_particles(grid, radius=BALL)
    w.add(kinema.Mesh(vertices=v, faces=f, inside=True, motion=kinema.Motion(angular_velocity=tuple(omega.tolist()))))
    w.add(kinema.Gravity())
    w.set_collisions(restitution=restitution, friction=friction)
    worst = 0.0
    for step in range(1, steps + 1):
        try:
            w.step(1)
        except ValueError as e:
            if per_step > 0.1 - 1e-12 and "collider" in str(e):
                return {"refused": str(e)[:200]}
            raise
        _finite(w, f"step {step}")
        local = w.positions @ Rotation.from_rotvec(omega * w.time).as_matrix()  # Rᵀ x, row by row
        out = np.max(np.abs(local), axis=1)
        worst = max(worst, float(out.max()))
        if out.max() > half:
            i = int(np.argmax(out))
            raise WrongAnswer(
                f"ball {i} left the turning cube: after step {step} (t = {w.time!r} s) it is at {local[i].tolist()} in the cube's frame (|coordinate| > {half!r}); "
                f"{per_step:.6g} rad a step"
            )
    if per_step > 0.1 + 1e-12:
        raise WrongAnswer(f"a turn of {per_step!r} rad a step (above 0.1) was run, not refused naming the collider (the balls stayed in: {worst:.6g})")
    return {"worst": worst}


def keyframed_floor(kind: str, span: float, height: float, at: list) -> dict:
    """A floor (a ``"plane"`` or a 12 m wide plate ``"mesh"``) keyframed from z = 0 up to
    ``height`` m within ``span`` steps (dt = 1 ms; Keyframes(times=[0, span dt])) under a ball
    resting on it (r = 0.05 m at z = r, e = 0, gravity): after 0.05 s the ball is above the
    floor, z ≥ height + r − 1e-6 (a floor carries what rests on it however fast it moves)."""
    import kinema

    dt = 1e-3
    motion = kinema.Keyframes(times=[0.0, span * dt], translations=[[0.0, 0.0, 0.0], [0.0, 0.0, height]])
    w = kinema.World(dim=3, dt=dt)
    w.add_particles([[at[0], at[1], BALL]], radius=BALL)
    w.add(kinema.Gravity())
    if kind == "plane":
        w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0], motion=motion))
    else:
        w.add(kinema.Mesh(vertices=_plate(6.0), faces=PLATE_FACES, motion=motion))
    w.set_collisions(restitution=0.0)
    w.step(50)
    _finite(w, "after 50 steps")
    z = float(w.positions[0, 2])
    if not z >= height + BALL - 1e-6:
        raise WrongAnswer(
            f"after 0.05 s the ball is at z = {z!r}, below the floor keyframed up to {height!r} m (its centre must be at least {height + BALL!r})"
        )
    return {"z": z}


def _resting(w: Any, count: int, what: str, limit: int = 2000) -> int:
    """Steps ``w`` until its ``count`` particles sleep (WrongAnswer after ``limit`` steps)."""
    for n in range(limit + 1):
        if w.collision_stats()["last"]["asleep"] == count:
            return n
        w.step(1)
    sleep_time = w.collisions["sleep_time"]
    raise WrongAnswer(
        f"{what}: {count} balls at rest on a floor, sleep_time = {sleep_time!r} s, are not asleep after {limit} steps ({w.collision_stats()['last']['asleep']} asleep)"
    )


def _column(depth: int, restitution: float, friction: float, dt: float, sleep: float | None) -> Any:
    import kinema

    w = kinema.World(dt=dt, method="verlet")
    w.add_particles([[0.0, 0.0, BALL + 2 * BALL * k] for k in range(depth)], mass=1.0, radius=BALL)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.set_collisions(restitution=restitution, friction=friction, sleep_time=sleep)
    return w


def sleeping_column_impact(
    depth: int, restitution: float, friction: float, speed: float, dt: float, offset: float, sleep_time: float, settle: float | None
) -> dict:
    """A column of ``depth`` balls (r = 0.05 m, 1 kg) resting on a floor, stepped ``settle`` s
    (asleep by then: ``sleep_time`` s of calm), then a ball dropped on it at ``speed`` m/s from 1 mm
    above (1.5 mm where 1 mm would end a step exactly: see below; ``offset`` m off its axis): through the step of the impact and the two after it, the
    world answers as the same scene never allowed to sleep, stepped as long
    (tests/test_sleepers_answer.py: positions within g dt², velocities within 1e-6 speed; an
    island asleep is a shortcut for an island at rest, never another physics).

    ``settle`` = None drops the ball at the step the column falls asleep. The awake twin is not
    at rest then: its speeds are still ~1e-13 m/s (~1e-17 after 0.5 s) and flip the stepped
    model's exact decisions (an impact or a resting contact), so its answer to the same drop
    changes from step to step by up to the ball's speed; the fuzz cases settle 0.5-1.5 s past
    ``sleep_time``, as the test file does (1.5 s)."""
    import numpy as np

    asleep = _column(depth, restitution, friction, dt, sleep=sleep_time)
    if settle is None:
        n = _resting(asleep, depth, "the column", limit=int(round((sleep_time + 2.0) / dt)))
    else:
        n = int(round(settle / dt))
        asleep.step(n)
        if asleep.collision_stats()["last"]["asleep"] != depth:
            raise WrongAnswer(
                f"a column of {depth} at rest on a floor, sleep_time = {sleep_time!r} s, is not asleep after {settle!r} s ({asleep.collision_stats()['last']['asleep']} asleep)"
            )
    awake = _column(depth, restitution, friction, dt, sleep=None)
    awake.step(n)
    if awake.collision_stats()["last"]["asleep"] != 0:
        raise WrongAnswer(f"with sleep_time = None, {awake.collision_stats()['last']['asleep']} balls sleep")
    met = []
    # The drop's gap, 1 mm, unless the impulse model's time of impact (gap / speed, at the
    # speed at the step's start) falls on a step's end: there the awake twin's speeds of
    # 1e-17 m/s decide whether the impact is in this step or the next (both right within
    # rounding; 1 mm at 0.5 m/s with dt = 2 ms was drawn 7 times in 4,000). 1.5 mm then.
    gap = 1e-3
    if abs(gap / speed / dt - round(gap / speed / dt)) < 1e-6:
        gap = 1.5e-3
    for w in (asleep, awake):
        top = w.positions[depth - 1, 2]
        w.add_particles([[offset, 0.0, top + 2 * BALL + gap]], velocity=[[0.0, 0.0, -speed]], mass=1.0, radius=BALL)
        steps = 0  # until the ball meets the column (an impact, or a contact more)
        while steps < 100:
            w.step(1)
            steps += 1
            last = w.collision_stats()["last"]
            if last["impacts"] or last["resting"] > depth:
                break
        w.step(2)
        _finite(w, "after the impact")
        met.append(steps)
    if not met[0] == met[1] < 100:
        raise WrongAnswer(f"the ball met the sleeping column at step {met[0]}, the awake one at step {met[1]} (of at most 100)")
    dx = float(np.max(np.abs(asleep.positions - awake.positions)))
    dv = float(np.max(np.abs(asleep.velocities - awake.velocities)))
    if not (dx <= G * dt**2 and dv <= 1e-6 * speed):
        raise WrongAnswer(
            f"two steps after the impact the sleeping column's world differs from the awake one's by {dx:.3g} m (g dt² = {G * dt**2:.3g}) "
            f"and {dv:.3g} m/s (1e-6 speed = {1e-6 * speed:.3g}); velocities asleep {asleep.velocities.tolist()} awake {awake.velocities.tolist()}"
        )
    return {"steps_before": n, "met_at": met[0], "dx": dx, "dv": dv}


def sleeper_write(what: str, count: int, index: int, value: list, friction: float, dt: float, spin: bool) -> dict:
    """``count`` balls (r = 0.05 m, 1 kg, 0.3 m apart) asleep on a floor (e = 0, μ =
    ``friction``); then one of them written: its velocity (``value``: lifted, v_z ≥ g dt, or
    sliding, v_z = 0), its position (moved by ``value``: lifted by h = value_z ≥ 2 g dt², or
    along the floor, h = 0) or its angular velocity (spin worlds; ``value`` ω). The write reads back,
    wakes the ball, and after one step (dt) the ball is where the closed form puts it: free
    flight (x + v dt + ½ g dt², v + g dt, to rounding) when lifted; on the floor Coulomb's
    sliding, v − μ g dt v̂ (with spin, ω = 5/2 μ g dt / r ẑ × v̂), or a spun ball's start to roll,
    v = μ g dt â × ẑ and ω − 5/2 μ g dt / r â (â: ω's horizontal direction), to 1e-9 of the speed
    (the positions there within g dt²); a ball moved along the floor rests where it was put.
    The other balls stay at rest. (Lifted by less than 1.5 g dt², a ball ends the step within
    g dt² of the floor, where the end-of-step contacts hold it to reach the floor by the next
    step's end, u ≥ −gap/dt, docs/collisions.md "End-of-step contacts" and "The soft step":
    not free flight, awake or asleep alike.)"""
    import numpy as np

    import kinema

    w = kinema.World(dt=dt, method="verlet", spin=spin)
    w.add_particles([[0.3 * i, 0.0, BALL] for i in range(count)], mass=1.0, radius=BALL)
    w.add(kinema.Gravity())
    w.add(kinema.Plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0]))
    w.set_collisions(restitution=0.0, friction=friction, sleep_time=0.05)
    _resting(w, count, "before the write")
    x0, value = w.positions.copy(), np.array(value, float)
    gvec, up, mu = np.array([0.0, 0.0, -G]), np.array([0.0, 0.0, 1.0]), friction
    if what == "velocity":
        w.velocities[index] = value
        wrote = w.velocities[index]
    elif what == "position":
        w.positions[index] = x0[index] + value
        wrote = w.positions[index]
    else:
        w.angular_velocities[index] = value
        wrote = w.angular_velocities[index]
    written = value if what != "position" else x0[index] + value
    if not np.array_equal(wrote, written):
        raise WrongAnswer(f"the write of {what} {written.tolist()} to a sleeping ball reads back as {np.asarray(wrote).tolist()}")
    w.step(1)
    _finite(w, "after the write")
    x, v = w.positions[index], w.velocities[index]
    omega = w.angular_velocities[index] if spin else np.zeros(3)
    want_w = np.zeros(3)
    tight = 1e-12  # to rounding: free flight
    if what == "velocity" and value[2] > 0:
        start = x0[index]
        want_x, want_v, pos_tol = start + value * dt + 0.5 * gvec * dt**2, value + gvec * dt, tight * (1 + np.abs(start).max() + np.abs(value).max() * dt)
        vel_tol = tight * (1 + np.abs(value).max())
    elif what == "velocity":
        s = float(np.linalg.norm(value))
        hat = value / s
        want_v = value - mu * G * dt * hat
        want_x = x0[index] + value * dt - 0.5 * mu * G * dt**2 * hat
        want_w = 2.5 * mu * G * dt / BALL * np.cross(up, hat) if spin else want_w
        pos_tol, vel_tol = G * dt**2, 1e-9 * s
    elif what == "position" and value[2] > 0:
        want_x, want_v = written + 0.5 * gvec * dt**2, gvec * dt
        pos_tol, vel_tol = tight * (1 + np.abs(written).max()), tight
    elif what == "position":
        want_x, want_v, pos_tol, vel_tol = written, np.zeros(3), G * dt**2, G * dt
    else:
        flat = np.array([value[0], value[1], 0.0])
        hat = flat / np.linalg.norm(flat) if np.any(flat) else flat
        want_x, want_v = x0[index] + 0.5 * mu * G * dt**2 * np.cross(hat, up), mu * G * dt * np.cross(hat, up)
        want_w = value - 2.5 * mu * G * dt / BALL * hat
        pos_tol, vel_tol = G * dt**2, 1e-9 * max(1.0, float(np.linalg.norm(value)) * BALL)
    errs = {
        "position": float(np.max(np.abs(x - want_x))),
        "velocity": float(np.max(np.abs(v - want_v))),
        "angular velocity": float(np.max(np.abs(omega - want_w))),
    }
    tols = {"position": pos_tol, "velocity": vel_tol, "angular velocity": vel_tol / BALL}
    for name, err in errs.items():
        if not err <= tols[name]:
            raise WrongAnswer(
                f"one step after writing the {what} of sleeping ball {index} ({written.tolist()}), its {name} is off the closed form by {err:.3g} (> {tols[name]:.3g}): "
                f"x {x.tolist()} (want {want_x.tolist()}), v {v.tolist()} (want {want_v.tolist()}), ω {omega.tolist()} (want {want_w.tolist()})"
            )
    others = [i for i in range(count) if i != index]
    if others:
        dx = float(np.max(np.abs(w.positions[others] - x0[others])))
        dv = float(np.max(np.abs(w.velocities[others])))
        if not (dx <= G * dt**2 and dv <= G * dt):
            raise WrongAnswer(f"the other balls (at rest, not written) moved {dx:.3g} m at up to {dv:.3g} m/s in the step after the write")
    return {"errors": errs}


def _gas(count: int, radius: float, seed: int, gravity: bool, restitution: float, dt: float, speed: float, periodic: list) -> Any:
    """``count`` balls on a jittered grid in a unit box with normal velocities of scale ``speed``, event-driven."""
    import math

    import numpy as np

    rng = np.random.default_rng(seed)
    k = math.ceil(round(count ** (1 / 3), 9))
    g = (np.arange(k) + 0.5) / k
    x = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)[:count]
    x = x + rng.uniform(-0.1, 0.1, x.shape) / k
    v = rng.normal(size=x.shape) * speed
    return _event_driven_box(x, v, radius, dt, periodic, gravity, restitution)


def _event_driven_box(x: Any, v: Any, radius: float, dt: float, periodic: list, gravity: bool, restitution: float) -> Any:
    """An event-driven world of balls (1 kg) at ``x`` with velocities ``v`` in a unit box."""
    import kinema

    w = kinema.World(dt=dt)
    w.add_particles(x, velocity=v, radius=radius, mass=1.0)
    w.add(kinema.Box([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]))
    if any(periodic):
        w.periodic = tuple(periodic)
    if gravity:
        w.add(kinema.Gravity())
    w.set_collisions(restitution=restitution, event_driven=True)
    return w


def event_driven_cuts(count: int, radius: float, seed: int, gravity: bool, restitution: float, dt: float, speed: float, periodic: list, cuts: list) -> dict:
    """A gas of ``count`` balls in a unit box (some axes periodic), event-driven, stepped as
    one ``step(sum(cuts))`` and, from the same start, as ``step(c)`` for each c of ``cuts``:
    the same bits (positions, velocities, time, impacts). The state is the same however the
    run is cut into calls."""
    import numpy as np

    a = _gas(count, radius, seed, gravity, restitution, dt, speed, periodic)
    b = _gas(count, radius, seed, gravity, restitution, dt, speed, periodic)
    a.step(sum(cuts))
    for c in cuts:
        b.step(c)
    ia, ib = a.collision_stats()["total"]["impacts"], b.collision_stats()["total"]["impacts"]
    if not (np.array_equal(a.positions, b.positions) and np.array_equal(a.velocities, b.velocities) and a.time == b.time and ia == ib):
        dx = float(np.max(np.abs(a.positions - b.positions)))
        dv = float(np.max(np.abs(a.velocities - b.velocities)))
        raise WrongAnswer(
            f"step({sum(cuts)}) and steps of {cuts} differ: positions by {dx:.3g} m, velocities by {dv:.3g} m/s, time {a.time!r} and {b.time!r}, impacts {ia} and {ib}"
        )
    _finite(a, "event-driven")
    return {"impacts": ia}


def event_driven_too_fast(count: int, speed: float, direction: list, radius: float, dt: float, gravity: bool, periodic: list) -> dict:
    """An event-driven world in a unit box whose first ball moves at ``speed`` ≥ 1e10 m/s
    along ``direction``: its first step raises kinema.SimulationDiverged (events it cannot
    follow, as a stepped world refuses such a step) before any event, the world as it was;
    never a hang (the worker's timeout) nor a run."""
    import numpy as np

    import kinema

    d = np.asarray(direction, float)
    v = np.zeros((count, 3))
    v[0] = d / np.linalg.norm(d) * speed
    x = [[0.5, 0.5, 0.5]] + [[0.15 + 0.17 * k, 0.2, 0.2] for k in range(count - 1)]
    w = _event_driven_box(x, v, radius, dt, periodic, gravity, 1.0)
    before = w.positions.copy()
    try:
        w.step(1)
    except kinema.SimulationDiverged as e:
        if not (w.time == 0.0 and np.array_equal(w.positions, before)):
            raise WrongAnswer(f"the refused step changed the world: time {w.time!r}, positions {w.positions.tolist()}") from e
        return {"refused": str(e)[:200]}
    raise WrongAnswer(f"a step at {float(np.linalg.norm(v[0])):.6g} m/s ran (time {w.time!r}, positions {w.positions.tolist()}): events it cannot follow")


ORACLES = {
    f.__name__: f
    for f in (
        moving_plate_side,
        sliding_plate_throw,
        turning_cube,
        keyframed_floor,
        sleeping_column_impact,
        sleeper_write,
        event_driven_cuts,
        event_driven_too_fast,
    )
}


def _oracle(name: str, kwargs: dict) -> Any:
    """Run one check; a refusal where the physics must work is a wrong answer."""
    import kinema

    try:
        return ORACLES[name](**kwargs)
    except (ValueError, TypeError, MemoryError, kinema.SimulationDiverged) as e:
        raise WrongAnswer(f"refused where the physics must work: {type(e).__name__}: {e}") from e


# -- the worker ------------------------------------------------------------------------------
class _Ctx:
    def __init__(self) -> None:
        self.world: Any = None
        self.tableau: Any = None
        self.user_errors: list[BaseException] = []  # raised by a case's own function (its arithmetic)
        self.stepping = False  # a scene op past its build: stepping the world it built


def _classify(e: BaseException, op: dict, ctx: _Ctx) -> str:
    """The verdict on an exception an op raised: "allowed", "bad" or (an oracle's) "wrong answer"."""
    import kinema
    from kinema.io import TrajectoryFileError
    from kinema.scene import SceneError

    if isinstance(e, WrongAnswer):
        return "wrong answer"  # an oracle's verdict (fuzz_cases.ORACLES)
    if any(e is u for u in ctx.user_errors):
        return "allowed"  # the case's own function raised it (10**400 * y): kinema passes it on unchanged
    names = [c.__name__ for c in type(e).__mro__]
    if "PanicException" in names or not isinstance(e, Exception):
        return "bad"
    if isinstance(e, (ArithmeticError, LookupError, AttributeError, RecursionError, AssertionError, NameError, SystemError, UnicodeError)):
        return "bad"
    if isinstance(e, kinema.SimulationDiverged):
        return "allowed"
    if isinstance(e, RuntimeError):
        return "allowed" if str(e).startswith(REENTRY_MESSAGES) else "bad"
    if op["op"] == "scene" and not ctx.stepping and isinstance(e, (ValueError, TypeError)) and not isinstance(e, SceneError):
        return "bad"  # the scene loader reports every problem as a SceneError (the CLI's exit 2)
    # (a step of the world a scene built refuses as World.step does: a ValueError naming what,
    # e.g. a dt too coarse for a keyframed collider's turn, which only the steps meet)
    if op["op"] == "trajectory" and isinstance(e, (ValueError, TypeError)) and not isinstance(e, TrajectoryFileError):
        return "bad"  # Trajectory.load reports every problem of a file as a TrajectoryFileError naming it
    if isinstance(e, (ValueError, TypeError, MemoryError)):
        return "allowed"
    return "bad"


def _own(fn: Any, ctx: _Ctx) -> Any:
    """``fn``, with what it raises remembered as the case's own error (not kinema's)."""

    def call(*args: Any) -> Any:
        try:
            return fn(*args)
        except Exception as e:
            ctx.user_errors.append(e)
            raise

    return call


def _make_fn(spec: dict, ctx: _Ctx, second: bool = False) -> Any:
    import numpy as np

    kind = spec["fn"]
    if kind == "decay":
        return (lambda t, x, v: -x) if second else (lambda t, y: -y)
    if kind == "scale":
        k = decode(spec["k"], ctx)
        return _own((lambda t, x, v: k * x) if second else (lambda t, y: k * y), ctx)
    if kind == "const":
        value = decode(spec["value"], ctx)
        return (lambda t, x, v: value) if second else (lambda t, y: value)
    if kind == "reenter":
        action = spec["action"]

        def reenter(t: float, x: Any, v: Any) -> Any:
            w = ctx.world
            if action == "step":
                w.step(1)
            elif action == "add_particles":
                w.add_particles([0.0, 0.0, 0.0])
            elif action == "diagnostics":
                w.diagnostics()
            elif action == "set_positions":
                w.positions = np.zeros((len(w), 3))
            elif action == "read_views":
                _ = w.positions.sum() + w.velocities.sum() + w.masses.sum() + len(w.forces)
            elif action == "read_core":
                _ = w.time + w.dt + len(w)
            return np.zeros_like(x)

        return reenter
    raise ValueError(f"unknown fn spec {spec!r}")


def _inspect(w: Any) -> None:
    w.diagnostics()
    w.contacts()
    w.collision_stats()
    w.stage_times()
    w.rates()
    w.stable_step()
    w.accelerations  # noqa: B018 - a property that computes
    w.momenta  # noqa: B018
    repr(w)
    try:
        w.to_scene()
    except ValueError as e:  # a PythonForce cannot be written to a scene: documented
        if "cannot be written to a scene" not in str(e):
            raise


_BASE_H5: dict[str, Any] = {}


def _base_trajectory() -> Path:
    """A small valid trajectory file (made once per worker)."""
    if "path" not in _BASE_H5:
        import kinema

        folder = Path(tempfile.mkdtemp(prefix="kinema-fuzz-"))
        w = kinema.World(dt=0.01)
        w.add_particles([[0.2, 0.5, 0.5], [0.5, 0.5, 0.5], [0.8, 0.5, 0.6]], velocity=[1.0, 0.5, 0.0], radius=0.05)
        w.add(kinema.Gravity())
        w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
        w.add(kinema.Plane([0, 0, 0], [0, 0, 1]))
        w.add(kinema.SphereObstacle([0.5, 0.5, 0.2], 0.1))
        w.periodic = (True, False, False)
        _BASE_H5["path"] = w.run(0.05, fps=50).save(folder / "base.h5")
        _BASE_H5["folder"] = folder
    return _BASE_H5["path"]


def _h5_layout() -> dict:
    import h5py

    datasets, attrs = [], []
    with h5py.File(_base_trajectory(), "r") as f:

        def visit(name: str, obj: Any) -> None:
            if isinstance(obj, h5py.Dataset):
                datasets.append([name, list(obj.shape), str(obj.dtype)])
            attrs.extend([name, a] for a in obj.attrs)

        attrs.extend(["/", a] for a in f.attrs)
        f.visititems(visit)
    return {"datasets": datasets, "attrs": attrs, "size": _base_trajectory().stat().st_size}


def _damage(path: Path, m: dict, ctx: _Ctx) -> None:
    """Apply one damage to a copy of the base trajectory; a ValueError("invalid case") when
    h5py cannot store it (the case is then not a test of kinema)."""
    import h5py
    import numpy as np

    action = m["action"]
    if action == "truncate":
        with open(path, "r+b") as fh:
            fh.truncate(m["size"])
        return
    if action == "flip":
        with open(path, "r+b") as fh:
            fh.seek(m["offset"])
            fh.write(bytes([m["byte"]]))
        return
    with h5py.File(path, "r+") as f:
        if action == "delete_dataset":
            del f[m["name"]]
        elif action == "replace_dataset":
            del f[m["name"]]
            f.create_dataset(m["name"], data=decode(m["value"], ctx))
        elif action == "set_element":
            data = f[m["name"]][()]
            arr = np.array(data)
            if arr.size == 0:
                raise ValueError("invalid case: empty dataset")
            arr.reshape(-1)[m["index"] % arr.size] = decode(m["value"], ctx)
            del f[m["name"]]
            f.create_dataset(m["name"], data=arr)
        elif action == "delete_attr":
            del f[m["group"]].attrs[m["name"]]
        elif action == "set_attr":
            f[m["group"]].attrs[m["name"]] = decode(m["value"], ctx)
        else:
            raise ValueError(f"invalid case: unknown damage {action!r}")


# Known slow case (test_fuzz.py: test_known_bug_dense_overlaps_make_a_step_take_seconds): when
# hundreds of particles overlap each other at once, one step takes seconds to minutes (the
# impact search runs to its cap). A scene case with more overlapping pairs than this is built
# but not stepped.
MAX_OVERLAPPING_PAIRS = 1000


def overlapping_pairs(world: Any) -> int:
    """Pairs of particles closer than twice the largest radius (an upper bound of the overlaps)."""
    import numpy as np
    from scipy.spatial import cKDTree

    n = len(world)
    if n < 2:
        return 0
    x = np.asarray(world.positions)
    reach = 2.0 * float(np.max(world._core.radii))
    if not (np.all(np.isfinite(x)) and np.isfinite(reach)):
        return n * (n - 1) // 2
    try:
        with np.errstate(all="ignore"):
            tree = cKDTree(x)
            return (int(tree.count_neighbors(tree, reach)) - n) // 2
    except (ValueError, OverflowError):  # coordinates near 1e308: count them all unless few
        return 0 if n <= 100 else n * (n - 1) // 2


def _too_long(pre: dict) -> str | None:
    """Why ``kinema run`` would accept the scene ``pre["scene"]`` but take too long for a fuzz
    case, or None. Raises where the CLI refuses the scene (it is then quick)."""
    from kinema import runner
    from kinema.scene import Scene

    sc = Scene.from_toml(pre["scene"])
    seconds = sc.world.duration if pre.get("duration") is None else pre["duration"]
    runner._scene_work(sc, Path(pre["scene"]), seconds, "world.duration", False, False)
    n = sc.particle_count()
    steps = runner._frames_and_steps(seconds, sc.world.dt, sc.world.fps)[1]
    if n > pre["max_particles"] or n * steps > pre["max_particle_steps"] or steps > pre["max_steps"]:
        return f"{n} particles x {steps:g} steps: more work than a fuzz case may take"
    pairs = overlapping_pairs(sc.build(source=pre["scene"]))
    if pairs > MAX_OVERLAPPING_PAIRS:
        return f"{pairs} overlapping pairs (a known slow case)"
    return None


def _cli(op: dict) -> dict:
    """``kinema <argv>`` in this process (as the console script runs it): exit code and stderr."""
    import contextlib
    import io

    from kinema import cli

    pre = op.get("precheck")
    if pre is not None:  # skip runs the CLI would accept but that are too long for a fuzz case
        try:
            why = _too_long(pre)
        except Exception:  # noqa: BLE001 - the CLI refuses it, or fails on it: run it and see
            why = None
        if why is not None:
            return {"skipped": why}
    out, err = io.StringIO(), io.StringIO()
    code: Any = 0
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            cli.app(args=op["argv"], prog_name="kinema")
        except SystemExit as e:
            code = e.code if isinstance(e.code, int) else (0 if e.code is None else 1)
        except BaseException as e:  # what escapes the CLI is a traceback and exit 1 in a real run
            import traceback

            code = 1
            err.write("Traceback (most recent call last):\n" + "".join(traceback.format_exception(e)))
    return {"exit": code, "stderr": err.getvalue()[-4000:], "stdout": out.getvalue()[-1000:]}


def _op(ctx: _Ctx, op: dict) -> Any:
    import kinema

    kind = op["op"]
    if kind in _fault_ops():
        return _fault_ops()[kind](ctx, op)
    args = [decode(a, ctx) for a in op.get("args", [])]
    kwargs = {k: decode(v, ctx) for k, v in op.get("kwargs", {}).items()}
    if kind == "world":
        ctx.world = kinema.World(*args, **kwargs)
        return None
    if kind == "oracle":
        return _oracle(op["name"], kwargs)
    if kind == "tableau":
        ctx.tableau = kinema.ButcherTableau(*args, **kwargs)
        return None
    if kind in ("solve", "solve_second_order"):
        fn = _make_fn(op["fn"], ctx, second=kind == "solve_second_order")
        if "jac" in op:
            kwargs["jac"] = _make_fn(op["jac"], ctx)
        getattr(kinema, kind)(fn, *args, **kwargs)
        return None
    if kind == "stability":
        getattr(kinema.stability, op["fn"])(*args, **kwargs)
        return None
    if kind == "trajectory":
        import shutil

        base = _base_trajectory()
        path = base.with_name(f"case-{os.getpid()}.h5")
        shutil.copyfile(base, path)
        try:
            try:
                _damage(path, op["damage"], ctx)
            except Exception as e:  # h5py could not write this damage: not a case
                return {"invalid": f"{type(e).__name__}: {e}"}
            kinema.Trajectory.load(path)
        finally:
            path.unlink(missing_ok=True)
        return None
    if kind == "h5_layout":
        return {"layout": _h5_layout()}
    if kind == "scene":
        from kinema.scene import Scene

        sc = Scene.from_toml(op["path"])
        if sc.particle_count() > op.get("max_particles", 5000):
            return {"skipped": f"{sc.particle_count()} particles"}
        w = sc.build(source=op["path"])
        ctx.world = w
        pairs = overlapping_pairs(w)
        if pairs > MAX_OVERLAPPING_PAIRS:
            return {"skipped": f"{pairs} overlapping pairs (a known slow case): built, not stepped"}
        ctx.stepping = True
        w.step(op.get("steps", 2))
        _inspect(w)
        return None
    if kind == "cli":
        return {"cli": _cli(op)}
    if kind == "debug":  # the harness's own tests
        if op["what"] == "abort":
            os.abort()
        if op["what"] == "sleep":
            time.sleep(op["seconds"])
        if op["what"] == "panic":
            raise type("PanicException", (BaseException,), {})("a fake panic")
        if op["what"] == "print":
            print("noise on stdout")
            os.write(1, b"noise on fd 1\n")
        return None
    if ctx.world is None:
        ctx.world = kinema.World()
    w = ctx.world
    if kind in ("add_particles", "set_collisions", "step", "run"):
        getattr(w, kind)(*args, **kwargs)
    elif kind == "add":
        if op["kind"] == "value":
            w.add(decode(op["value"], ctx))
        else:
            cls = getattr(kinema, op["kind"])
            if op["kind"] == "PythonForce":
                kwargs["fn"] = _make_fn(op["fn"], ctx, second=True)
            w.add(cls(*args, **kwargs))
    elif kind in ("periodic", "positions", "velocities", "masses"):
        setattr(w, kind, decode(op["value"], ctx))
    elif kind == "call":  # any other method or property of the world
        attr = getattr(w, op["method"])
        if callable(attr):
            attr(*args, **kwargs)
    elif kind == "inspect":
        _inspect(w)
    else:
        raise ValueError(f"unknown op {kind!r}")
    return None


def _fault_ops() -> dict:
    """The ops of tests/fuzz_faults.py (file-system faults, special files, threads, sweeps,
    checkpoints) and tests/fuzz_readers.py (damaged files of each format, side files, the
    CLI's resume and rerun paths)."""
    import fuzz_faults
    import fuzz_readers

    return {**fuzz_faults.OPS, **fuzz_readers.OPS}


def _run_case(case: dict) -> dict:
    ctx = _Ctx()
    results = []
    for op in case["ops"]:
        if op["op"] != "world" and ctx.world is None and results and results[0]["op"] == "world":
            results.append({"op": op["op"], "result": "not run: no world"})
            continue
        try:
            extra = _op(ctx, op)
        except BaseException as e:  # noqa: BLE001 - every exception is judged
            results.append({"op": op["op"], "type": type(e).__name__, "message": str(e)[:600], "verdict": _classify(e, op, ctx)})
            if not isinstance(e, Exception):
                break  # a panic (or an exit) leaves the process in an unknown state
            continue
        results.append({"op": op["op"], "result": "ok", **(extra or {})})
    return {"status": "done", "ops": results}


def worker_main() -> None:
    proto = os.fdopen(os.dup(1), "w", buffering=1, encoding="utf-8")
    os.dup2(2, 1)  # whatever else writes to stdout (Python or native code) goes to stderr
    sys.stdout = sys.stderr
    import warnings

    warnings.simplefilter("ignore")
    import numpy as np

    np.seterr(all="ignore")
    import kinema  # noqa: F401
    import kinema.cli  # noqa: F401

    proto.write(json.dumps({"ready": True, "pid": os.getpid()}) + "\n")
    for line in sys.stdin:
        if not line.strip():
            continue
        answer = _run_case(json.loads(line))
        proto.write(json.dumps(answer, default=repr) + "\n")


if __name__ == "__main__" and sys.argv[1:] == ["--worker"]:
    sys.path.insert(0, str(HERE.parent))
    sys.modules.setdefault("fuzz_cases", sys.modules["__main__"])  # one copy for tests/fuzz_faults.py too
    worker_main()
