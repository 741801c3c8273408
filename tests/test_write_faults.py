"""Writes that fail cleanly (issue 26): a full disk, a file-size limit.

Before, ``Trajectory.save`` on a full disk or over a file-size limit raised its error and then
the interpreter printed dozens of h5py tracebacks and crashed at exit (signal 11): HDF5 had
been given the failed write, and its objects could not be closed. Each case here runs in a
child process (the limit is the child's own: ``RLIMIT_FSIZE`` with SIGXFSZ ignored, so a write
past it fails with EFBIG; or a 64 kB tmpfs mounted in the test's folder, where writes fail
with ENOSPC) and checks what the user sees: one clean ``kinema.io.FileWriteError`` (an ``OSError`` with the system's errno) naming the
path, exit 0
after it, no traceback from h5py, no temporary file left, and the file that was there before
unchanged."""

import errno
import os
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

CHILD = textwrap.dedent(
    """
    import os, resource, signal, sys
    import numpy as np
    import kinema

    what, target, limit = sys.argv[1], sys.argv[2], int(sys.argv[3])
    w = kinema.World(dim=3, dt=0.01)
    w.add_particles(np.random.default_rng(1).normal(size=(2000, 3)))
    traj = w.run(0.5, fps=100)
    if limit:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))
    try:
        if what == "trajectory":
            traj.save(target)
        else:
            w.save_checkpoint(target)
    except kinema.io.FileWriteError as e:
        print("ERROR", e, e.errno)
    else:
        print("WROTE")
    """
)


def _child(what, target, limit=0):
    return subprocess.run([sys.executable, "-c", CHILD, what, str(target), str(limit)], capture_output=True, text=True, timeout=300)


def _check_clean(run, target, before):
    assert run.returncode == 0, f"exit {run.returncode}: {run.stderr[-2000:]}"
    lines = run.stdout.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("ERROR cannot write ") and str(target) in lines[0], run.stdout
    assert "Traceback" not in run.stderr and "Exception ignored" not in run.stderr, run.stderr[-2000:]
    assert target.read_bytes() == before
    assert sorted(p.name for p in target.parent.iterdir()) == [target.name]  # no .part left


@pytest.mark.parametrize("what", ["trajectory", "checkpoint"])
def test_a_write_over_the_file_size_limit_fails_cleanly(tmp_path, what):
    target = tmp_path / "run.h5"
    target.write_bytes(b"the earlier file")
    run = _child(what, target, limit=100_000)
    _check_clean(run, target, b"the earlier file")
    assert "File too large" in run.stdout and run.stdout.split()[-1] == str(errno.EFBIG)


@pytest.fixture
def small_disk(tmp_path):
    disk = tmp_path / "disk"
    disk.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(disk)], capture_output=True).returncode != 0:
        pytest.skip("mounting a small tmpfs needs root (CAP_SYS_ADMIN)")
    try:
        yield disk
    finally:
        subprocess.run(["umount", str(disk)], check=False)


@pytest.mark.parametrize("what", ["trajectory", "checkpoint"])
def test_a_write_to_a_full_disk_fails_cleanly(small_disk, what):
    target = small_disk / "run.h5"
    target.write_bytes(b"kept")
    run = _child(what, target)
    _check_clean(run, target, b"kept")
    assert "No space left on device" in run.stdout and run.stdout.split()[-1] == str(errno.ENOSPC)


def test_a_write_that_fits_is_whole(tmp_path):
    target = tmp_path / "run.h5"
    run = _child("trajectory", target, limit=10**9)
    assert run.stdout.strip() == "WROTE", run.stdout + run.stderr
    import kinema

    traj = kinema.Trajectory.load(target)
    assert traj.positions.shape == (51, 2000, 3)
    assert os.path.getsize(target) > 100_000


def test_a_video_the_disk_cannot_hold_is_an_error_and_the_old_one_stays(small_disk):
    # 20 frames of noise make a 78 kB MP4 on a 64 kB disk. Before, ffmpeg's failure went
    # unseen (imageio-ffmpeg does not report its exit status): "wrote v.mp4", a truncated
    # file without its index in place of the old one.
    from kinema.io import FileWriteError
    from kinema.render.video import write_video

    target = small_disk / "v.mp4"
    target.write_bytes(b"the old video")
    rng = np.random.default_rng(0)
    frames = (rng.integers(0, 255, (64, 64, 3), dtype=np.uint8) for _ in range(20))
    with pytest.raises(FileWriteError) as err:
        write_video(frames, target, fps=10)
    assert str(err.value) == f"cannot write {target}: No space left on device" and err.value.errno == errno.ENOSPC
    assert target.read_bytes() == b"the old video"
    assert sorted(p.name for p in small_disk.iterdir()) == ["v.mp4"]


def test_a_video_that_fits_holds_every_frame(tmp_path):
    import imageio_ffmpeg

    from kinema.render.video import write_video

    rng = np.random.default_rng(0)
    path = write_video((rng.integers(0, 255, (64, 64, 3), dtype=np.uint8) for _ in range(20)), tmp_path / "v.mp4", fps=10)
    assert imageio_ffmpeg.count_frames_and_secs(str(path))[0] == 20


def test_a_writer_removes_what_a_killed_writer_of_the_same_file_left(tmp_path):
    # Before, 11 of 23 kills left a .checkpoint.ckpt.<hex>.part that nothing removed. A
    # temporary name carries its writer (<host>-<pid>); the next writer of the same target
    # removes those whose process is gone, and unowned ones (an older kinema's) after a day.
    import kinema
    from kinema.io._files import host_name

    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    host = host_name()
    left = {
        "killed": tmp_path / f".run.h5.{host}-{dead.pid}.abc123.part",
        "running": tmp_path / f".run.h5.{host}-{os.getppid()}.def456.part",
        "other host": tmp_path / f".run.h5.elsewhere-{dead.pid}.abc123.part",
        "old unowned": tmp_path / ".run.h5.8d906b868137.part",
        "new unowned": tmp_path / ".run.h5.0123456789ab.part",
        "another file's": tmp_path / f".other.h5.{host}-{dead.pid}.abc123.part",
    }
    for p in left.values():
        p.write_bytes(b"partial")
    two_days_ago = time.time() - 2 * 86400
    os.utime(left["old unowned"], (two_days_ago, two_days_ago))
    w = kinema.World(dim=3, dt=0.01)
    w.add_particles(np.zeros((1, 3)))
    w.run(0.02).save(tmp_path / "run.h5")
    gone = {k for k, p in left.items() if not p.exists()}
    assert gone == {"killed", "old unowned"}
    assert (tmp_path / "run.h5").is_file()
