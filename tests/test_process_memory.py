"""What the process keeps besides the engine's arrays (issue 51's memory row counts the whole
process): what `import kinema` loads, and how the allocator gives back what a world frees.
Each check runs in a fresh interpreter, since both are decided at import."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys

import numpy as np
import pytest

import kinema


def _fresh(code: str, env: dict[str, str] | None = None) -> dict:
    """What `code` (which prints one JSON line last) prints in a fresh interpreter."""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env={**os.environ, **(env or {})}, timeout=120)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_importing_kinema_does_not_load_the_scene_checkpoint_or_picture_libraries():
    # pydantic (scene files) and h5py (checkpoints, trajectories) were 24 MB of every process,
    # 24 B a particle at 10⁶ (issue 51); they load when a scene or a file is first used
    found = _fresh(
        "import json, sys, kinema; print(json.dumps(sorted(m for m in ('h5py', 'pydantic', 'kinema.scene', 'kinema.checkpoint', 'kinema.io', 'kinema.render') if m in sys.modules)))"
    )
    assert found == [], f"loaded by `import kinema`: {found}"


def test_every_public_name_is_there_when_asked_for():
    for name in kinema.__all__:
        assert getattr(kinema, name) is not None, name
    assert kinema.Scene is kinema.scene.Scene and kinema.load_scene is kinema.scene.load_scene
    assert kinema.resume_run is kinema.checkpoint.resume_run
    assert kinema.render_frames is kinema.render.render_frames and kinema.sweep is kinema.sweeps.sweep
    assert callable(kinema.convergence)  # the function, not the module of the same name
    assert hasattr(kinema.Scene, "build")  # (kinema.scene.build gives it, when the package loads)
    assert set(kinema.__all__) <= set(dir(kinema))
    with pytest.raises(AttributeError, match="no attribute 'not_a_name'"):
        kinema.not_a_name  # noqa: B018
    names = _fresh("import json; from kinema import *; print(json.dumps(sorted(k for k in dir() if not k.startswith('_'))))")
    assert set(kinema.__all__) <= set(names) | {"__version__"}


# glibc raises its mmap threshold to the size of each large block freed (up to 32 MiB), after
# which large arrays come from its arenas and are reused from there: after a freed 16 MiB block,
# a 4 MiB array is served from the heap. kinema does not change that for the process: held at
# 2 MiB (as kinema once held it, for its own peak), every fresh NumPy temporary of a 10⁶-particle
# array was mapped and faulted in anew, and NumPy ran 2× slower beside kinema (README,
# "Performance").
_ALLOCATIONS = """
import ctypes, json
import numpy as np
import kinema
w = kinema.World(dt=1e-3)
w.add_particles(np.arange(300.0).reshape(100, 3), radius=0.1)
w.step(1)
class Info(ctypes.Structure):
    _fields_ = [(n, ctypes.c_size_t) for n in "arena ordblks smblks hblks hblkhd usmblks fsmblks uordblks fordblks keepcost".split()]
libc = ctypes.CDLL("libc.so.6")
libc.mallinfo2.restype = Info
big = np.ones(2 << 20)  # 16 MiB, mapped
del big                 # freed: glibc's own rule raises the threshold to 16 MiB here
mapped = libc.mallinfo2().hblkhd
a = np.ones(1 << 19)    # 4 MiB
print(json.dumps({"mapped": libc.mallinfo2().hblkhd - mapped}))
"""


@pytest.mark.skipif(sys.platform != "linux" or platform.libc_ver()[0] != "glibc", reason="glibc's rule")
def test_importing_and_stepping_kinema_leaves_the_process_allocator_as_it_is():
    assert _fresh(_ALLOCATIONS)["mapped"] == 0


def test_the_engines_large_arrays_keep_their_values_across_the_page_line():
    # kinema's own blocks of 2 MiB or more come from pages of their own (crates/kinema-py/src/
    # pages.rs): an array that grows from below that line to above it is copied into such
    # pages, one above it is moved by mremap. Positions, added in three parts (x: 1.2 MB, then
    # 2.6 MB, then 5 MB), must come back bit for bit, and the world must step on them.
    rng = np.random.default_rng(7)
    parts = [rng.uniform(0.0, 100.0, (n, 3)) for n in (50_000, 60_000, 100_000)]
    w = kinema.World(dt=1e-3, method="verlet")
    for x in parts:
        w.add_particles(x, velocity=np.ones_like(x), radius=0.01)
    assert np.array_equal(w.positions, np.concatenate(parts))
    w.step(1)
    # (no force: Verlet's drift is x + h v with h v = 10⁻³ exactly, NumPy's sum to the bit)
    assert np.array_equal(w.positions, np.concatenate(parts) + 1e-3)


# A set-up's NumPy temporaries freed below a live array stay in glibc's heap, resident; the
# first step gives them back (`_core.give_back_memory`, glibc's malloc_trim, after the
# first-step checks), without changing glibc's thresholds (the test above).
_GIVEN_BACK = """
import json
import numpy as np
import kinema
def rss():
    return next(int(l.split()[1]) for l in open("/proc/self/status") if l.startswith("VmRSS")) * 1024
big = np.ones(2 << 20); del big               # 16 MiB freed: glibc's threshold rises to it
temporaries = [np.ones(1 << 20) for _ in range(8)]  # 8 x 8 MiB from the heap
kept = np.ones(1 << 16)                        # a live array above them
del temporaries                                # 64 MiB free below it: not trimmed by free()
w = kinema.World(dt=1e-3)
w.add_particles(np.arange(30.0).reshape(10, 3), radius=0.1)
before = rss()
w.step(1)
print(json.dumps({"given_back": before - rss()}))
"""


@pytest.mark.skipif(sys.platform != "linux" or platform.libc_ver()[0] != "glibc", reason="glibc's malloc_trim")
def test_the_first_step_gives_back_what_the_set_up_freed():
    assert _fresh(_GIVEN_BACK)["given_back"] > 48 << 20
