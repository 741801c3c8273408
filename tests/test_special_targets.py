"""Writers never replace what is not a regular file (issue 26).

Every writer of kinema puts a temporary file in place of its target by a rename; before this,
saving to /dev/null as root replaced the machine's /dev/null with an 80 kB regular file. Here
each writer is pointed at a private copy of /dev/null (``os.mknod``, character device 1:3,
made in the test's folder, never the system's), at a FIFO, at a socket and at a folder: each
is refused with one line naming the path and what stands there, and the node is left as it
was (same type, same device number, same inode). Nothing opens the target, so the FIFO never
blocks a writer (each call runs under a time limit)."""

import os
import signal
import socket
import stat
import subprocess
import sys
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

import kinema
from kinema.io import TrajectoryFileError, export


def _dev_null_copy(path: Path) -> Path:
    try:
        os.mknod(path, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
    except PermissionError:
        pytest.skip("making a device node needs root (CAP_MKNOD)")
    return path


def _fifo(path: Path) -> Path:
    os.mkfifo(path)
    return path


def _socket(path: Path) -> Path:
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.bind(str(path))
    s.close()  # the node stays in the folder
    return path


def _folder(path: Path) -> Path:
    path.mkdir()
    return path


NODES = {"character device": _dev_null_copy, "FIFO": _fifo, "socket": _socket}


@contextmanager
def _limit(seconds: int = 20):
    """A writer that opened the FIFO would block forever: fail instead."""

    def alarm(*_):
        raise TimeoutError("the writer blocked on its target")

    old = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def _identity(path: Path) -> tuple:
    st = os.lstat(path)
    return stat.S_IFMT(st.st_mode), st.st_rdev, st.st_ino


@pytest.fixture(scope="module")
def traj():
    w = kinema.World(dim=3, dt=0.01)
    w.add_particles(np.array([[0.0, 0.0, 1.0], [0.5, 0.0, 1.0]]), radius=0.1)
    w.add(kinema.Gravity())
    return w.run(0.05, fps=50)


def _writers(traj):
    from kinema.render.video import write_video
    from kinema.viewer import write_html

    def video(path):
        frames = (np.zeros((16, 16, 3), dtype=np.uint8) for _ in range(2))
        write_video(frames, path, fps=10)

    def checkpoint(path):
        w = kinema.World(dim=3, dt=0.01)
        w.add_particles(np.zeros((1, 3)))
        w.save_checkpoint(path)

    def scene(path):
        w = kinema.World(dim=3, dt=0.01)
        w.add_particles(np.zeros((1, 3)))
        w.to_scene().to_toml(path)

    writers = {
        "trajectory.h5": traj.save,
        "video.mp4": video,
        "page.html": lambda p: write_html(traj, p),
        "run.ckpt": checkpoint,
        "scene.toml": scene,
    }
    for fmt, suffix in {"xyz": ".xyz", "csv": ".csv", "lammps": ".lammpstrj", "gsd": ".gsd", "vtk": ".pvd", "usd": ".usda"}.items():
        writers[f"export{suffix}"] = lambda p, fmt=fmt: export(traj, p, format=fmt)
    return writers


WRITER_NAMES = ["trajectory.h5", "video.mp4", "page.html", "run.ckpt", "scene.toml"] + [
    f"export{s}" for s in (".xyz", ".csv", ".lammpstrj", ".gsd", ".pvd", ".usda")
]


@pytest.mark.parametrize("name", WRITER_NAMES)
@pytest.mark.parametrize("kind", list(NODES))
def test_a_writer_refuses_a_special_file_and_leaves_it(tmp_path, traj, name, kind):
    if name == "export.gsd":
        pytest.importorskip("gsd")
    if name == "export.usda":
        pytest.importorskip("pxr")
    target = NODES[kind](tmp_path / name)
    before = _identity(target)
    with _limit(), pytest.raises(TrajectoryFileError) as err:
        _writers(traj)[name](target)
    message = str(err.value)
    assert "\n" not in message and str(target) in message and kind in message, message
    assert _identity(target) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]  # no temporary file left


@pytest.mark.parametrize("name", WRITER_NAMES)
def test_a_writer_refuses_a_folder_and_leaves_it(tmp_path, traj, name):
    if name == "export.gsd":
        pytest.importorskip("gsd")
    if name == "export.usda":
        pytest.importorskip("pxr")
    target = _folder(tmp_path / name)
    (target / "keep").write_text("mine")
    with _limit(), pytest.raises((TrajectoryFileError, ValueError, IsADirectoryError)) as err:
        _writers(traj)[name](target)
    assert "\n" not in str(err.value) and str(target) in str(err.value)
    assert (target / "keep").read_text() == "mine"


def test_a_symlink_to_a_device_is_refused_and_the_device_kept(tmp_path, traj):
    device = _dev_null_copy(tmp_path / "null")
    link = tmp_path / "run.h5"
    link.symlink_to(device)
    before = _identity(device)
    with _limit(), pytest.raises(TrajectoryFileError, match="character device"):
        traj.save(link)
    assert _identity(device) == before and link.is_symlink()


def test_a_regular_file_is_still_replaced(tmp_path, traj):
    target = tmp_path / "run.h5"
    target.write_bytes(b"old")
    traj.save(target)
    assert stat.S_ISREG(os.lstat(target).st_mode) and target.stat().st_size > 3


def test_kinema_run_refuses_a_fifo_among_its_outputs_before_any_work(tmp_path):
    scene = tmp_path / "drop.toml"
    scene.write_text(
        '[world]\ndim = 3\ndt = 0.01\nduration = 0.05\nfps = 20\n[[particles]]\ntype = "list"\npositions = [[0, 0, 1]]\n[output]\nvideo = false\nplot = false\n'
    )
    out = tmp_path / "out"
    out.mkdir()
    fifo = _fifo(out / "trajectory.h5")
    before = _identity(fifo)
    run = subprocess.run([sys.executable, "-m", "kinema", "run", str(scene), "-o", str(out)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 2, run.stdout + run.stderr
    assert "FIFO" in run.stderr and "trajectory.h5" in run.stderr, run.stderr
    assert _identity(fifo) == before


# -- reading: a scene path must be a regular file ------------------------------------------


@pytest.mark.parametrize("kind", list(NODES))
def test_a_scene_that_is_not_a_regular_file_is_refused_without_blocking(tmp_path, kind):
    # Before, a FIFO blocked the reader forever and /dev/zero was read to 3.8 GB.
    from kinema.scene import Scene, SceneError

    node = NODES[kind](tmp_path / "scene.toml")
    if kind == "socket":  # a socket cannot be opened as a file at all
        with _limit(), pytest.raises(SceneError, match="cannot be read"):
            Scene.from_toml(node)
        return
    with _limit(), pytest.raises(SceneError, match=f"is not a regular file \\(a {kind}"):
        Scene.from_toml(node)


def test_a_scene_file_beyond_the_size_limit_is_refused(tmp_path):
    from kinema.scene import Scene, SceneError
    from kinema.scene.schema import SCENE_MAX_BYTES

    big = tmp_path / "big.toml"
    with open(big, "wb") as f:  # sparse: no disk used
        f.truncate(SCENE_MAX_BYTES + 1)
    with pytest.raises(SceneError, match="is larger than 256 MiB"):
        Scene.from_toml(big)


def test_kinema_run_of_a_fifo_exits_2_at_once(tmp_path):
    fifo = _fifo(tmp_path / "scene.toml")
    run = subprocess.run([sys.executable, "-m", "kinema", "run", str(fifo), "-o", str(tmp_path / "o")], capture_output=True, text=True, timeout=60)
    assert run.returncode == 2 and "is not a regular file (a FIFO)" in run.stderr, run.stderr
