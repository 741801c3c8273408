"""Worlds in forked processes (issue 46, "Processes").

Before, a child process forked after a World had stepped (``multiprocessing``'s default
start method on Linux) hung forever in its first ``World.step``: the engine's threads are
rayon's global pool, and a fork copies only the thread that forked, so the child's pool had
no workers to run the step. Now the child's forking thread builds a pool of its own
(``os.register_at_fork``) and the child's steps give the parent's bits.

Each check runs in a fresh interpreter (``subprocess``) with a time limit, so that a hang
is a failure, not a test run that never ends."""

import os
import subprocess
import sys

import pytest

# A scene of every collision model, stepped in the parent, then forked: the child goes on
# from the parent's state, the parent goes on the same way; both print their hash.
SCRIPT = r"""
import hashlib, multiprocessing as mp, sys
import numpy as np
import kinema

def worlds():
    out = {}
    for model in ("impulse", "spring_dashpot", "events"):
        w = kinema.World(dim=3, dt=1e-3)
        rng = np.random.default_rng(4)
        n = 300
        x = rng.uniform(0.1, 0.9, (n, 3))
        w.add_particles(x, velocity=rng.normal(0, 1, (n, 3)), radius=0.01)
        w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
        if model == "events":
            w.set_collisions(event_driven=True)
        elif model == "spring_dashpot":
            w.set_collisions(model="spring_dashpot", stiffness=1e5)
            w.add(kinema.Gravity())
        else:
            w.set_collisions(friction=0.3, restitution=0.5)
            w.add(kinema.Gravity())
        out[model] = w
    return out

def go_on(ws):
    h = hashlib.sha256()
    for name, w in ws.items():
        w.step(40)
        h.update(w.positions.tobytes() + w.velocities.tobytes())
    frame = next(kinema.render_frames(ws["impulse"].positions[None], 0.01, [0.0], width=64, height=48))
    h.update(frame.tobytes())
    return h.hexdigest()[:16]

def child(ws, q):
    q.put(go_on(ws))

if __name__ == "__main__":
    ws = worlds()
    for w in ws.values():
        w.step(20)
    ctx = mp.get_context(sys.argv[1])
    q = ctx.Queue()
    p = ctx.Process(target=child, args=(ws, q), daemon=True) if sys.argv[1] == "fork" else None
    if p is None:
        sys.exit("only fork is checked here")
    p.start()
    theirs = q.get(timeout=90)
    p.join(60)
    print(go_on(ws), theirs, p.exitcode)
"""


@pytest.mark.parametrize("threads", [1, 2])
def test_a_child_forked_after_the_world_stepped_goes_on_with_the_parents_bits(tmp_path, threads):
    script = tmp_path / "fork_check.py"
    script.write_text(SCRIPT)
    env = {**os.environ, "RAYON_NUM_THREADS": str(threads)}
    try:
        res = subprocess.run([sys.executable, str(script), "fork"], env=env, capture_output=True, text=True, timeout=150)
    except subprocess.TimeoutExpired:
        pytest.fail("the forked child's first step never returned")
    assert res.returncode == 0, res.stderr[-2000:]
    ours, theirs, code = res.stdout.split()
    assert code == "0" and ours == theirs, res.stdout
