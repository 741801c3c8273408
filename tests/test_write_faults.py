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


# -- exports on a full disk: GSD, VTK and USD (bugs the fuzz suite's fault cases found) ----------


@pytest.fixture
def tmpfs(tmp_path):
    """``mount(size_kb, name)``: a new tmpfs of that size at ``tmp_path / name`` (unmounted at
    the end; the test is skipped, saying why, where one cannot be mounted)."""
    mounted = []

    def mount(size_kb, name="disk"):
        if os.geteuid() != 0:
            pytest.skip("mounting a small tmpfs needs root (CAP_SYS_ADMIN)")
        folder = tmp_path / name
        folder.mkdir()
        proc = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size_kb}k", "tmpfs", str(folder)], capture_output=True, text=True)
        if proc.returncode != 0:
            pytest.skip(f"cannot mount a tmpfs: {proc.stderr.strip() or proc.returncode}")
        mounted.append(folder)
        return folder

    yield mount
    for folder in reversed(mounted):
        if subprocess.run(["umount", str(folder)], capture_output=True).returncode != 0:
            subprocess.run(["umount", "-l", str(folder)], capture_output=True)


@pytest.fixture
def private_tmp(tmp_path, monkeypatch):
    """The system's temporary folder (``tempfile.gettempdir()``) made a folder of this test,
    so that what a writer leaves there shows; ``set(folder)`` points it elsewhere."""
    import tempfile

    folder = tmp_path / "systmp"
    folder.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(folder))

    def point_at(other):
        monkeypatch.setattr(tempfile, "tempdir", str(other))
        return other

    point_at.folder = folder
    return point_at


def _descriptors_under(folder):
    """This process's descriptors open on a file under ``folder`` (a deleted one too)."""
    prefix = str(folder.resolve()) + os.sep
    out = []
    for fd in os.listdir("/proc/self/fd"):
        try:
            target = os.readlink(f"/proc/self/fd/{fd}")
        except OSError:
            continue
        if target.startswith(prefix):
            out.append(target)
    return out


def _files_under(folder):
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _one_particle(t_end):
    import kinema

    w = kinema.World(dt=0.005)
    w.add_particles([[0.5, 0.5, 0.5]], radius=0.004)
    return w.run(t_end, fps=100)


def _six_particles():
    import kinema

    rng = np.random.default_rng(0)
    w = kinema.World(dt=0.005)
    w.add_particles(rng.uniform(0.1, 0.9, (6, 3)), velocity=rng.normal(0, 0.5, (6, 3)), radius=0.004, mass=rng.uniform(0.5, 2.0, 6))
    w.add(kinema.Gravity(g=[0, -9.81, 0]))
    return w.run(0.26, fps=100)


def _hundred_particles(t_end=0.3, box=False):
    import kinema

    rng = np.random.default_rng(0)
    grid = np.stack(np.meshgrid(*(np.linspace(0.1, 0.9, k) for k in (5, 5, 4)), indexing="ij"), -1).reshape(-1, 3)
    w = kinema.World(dt=0.005)
    w.add_particles(grid, velocity=rng.normal(0, 0.5, (100, 3)), radius=0.004)
    if box:
        w.add(kinema.Box([0, 0, 0], [1, 1, 1]))
    return w.run(t_end, fps=100)


def _gsd_frames(path):
    gsd_hoomd = pytest.importorskip("gsd.hoomd")
    with gsd_hoomd.open(str(path), mode="r") as f:
        return len(f)


@pytest.mark.parametrize("case", ["one particle", "six particles"])
def test_a_gsd_export_on_a_full_disk_is_a_file_write_error_with_nothing_left_open(tmpfs, private_tmp, case):
    # Before, on this 16 kB tmpfs: the one particle's export raised FileWriteError but kept a
    # descriptor open on the deleted .run.gsd....part (gsd 5.0.1's gsd_close returns before
    # close(fd) when its flush fails), and the six particles' raised gsd's RuntimeError
    # ("Invalid gsd argument: ...part") from gsd_close. gsd now builds the file in the
    # system's temporary folder and Python copies it: a success reads back whole; a failure
    # is one FileWriteError, with no descriptor, temporary file or new file left.
    pytest.importorskip("gsd")
    from kinema.io import FileWriteError

    traj = _one_particle(0.34) if case == "one particle" else _six_particles()
    disk = tmpfs(16)
    target = disk / "run.gsd"
    try:
        traj.export(target)
    except FileWriteError as e:
        assert e.errno == errno.ENOSPC and str(e) == f"cannot write {target}: No space left on device"
        assert list(disk.iterdir()) == []
    else:
        assert sorted(p.name for p in disk.iterdir()) == ["run.gsd"]
        assert _gsd_frames(target) == traj.t.size
    assert _descriptors_under(disk) == [] and list(private_tmp.folder.iterdir()) == []


def test_a_gsd_export_the_disk_cannot_hold_keeps_the_earlier_file(tmpfs, private_tmp):
    pytest.importorskip("gsd")
    from kinema.io import FileWriteError

    disk = tmpfs(16)
    target = disk / "run.gsd"
    target.write_bytes(b"the earlier export")
    with pytest.raises(FileWriteError) as err:
        _hundred_particles().export(target)
    assert err.value.errno == errno.ENOSPC and str(err.value) == f"cannot write {target}: No space left on device"
    assert target.read_bytes() == b"the earlier export" and sorted(p.name for p in disk.iterdir()) == ["run.gsd"]
    assert _descriptors_under(disk) == [] and list(private_tmp.folder.iterdir()) == []


@pytest.mark.parametrize("size_kb", [8, 12, 16])
def test_gsd_failing_in_the_temporary_folder_is_a_file_write_error_naming_the_target(tmp_path, tmpfs, private_tmp, size_kb):
    # gsd meets the full disk in the temporary folder itself (a full /tmp): its OSError or its
    # RuntimeError("Invalid gsd argument") becomes a FileWriteError naming the target, and the
    # descriptor gsd leaves open there is closed (the tmpfs unmounts).
    pytest.importorskip("gsd")
    from kinema.io import FileWriteError

    scratch = private_tmp(tmpfs(size_kb, "systmp-full"))
    target = tmp_path / "run.gsd"
    target.write_bytes(b"kept")
    for traj in (_one_particle(0.34), _six_particles(), _hundred_particles()):
        try:
            traj.export(target)
        except FileWriteError as e:
            assert str(e).startswith(f"cannot write {target}: ") and "Traceback" not in str(e) and "\n" not in str(e)
            assert f"in the temporary folder {scratch}" in str(e)
            assert target.read_bytes() == b"kept"
        else:
            assert _gsd_frames(target) == traj.t.size
            target.write_bytes(b"kept")
        assert _descriptors_under(scratch) == [] and list(scratch.iterdir()) == []
        assert sorted(p.name for p in tmp_path.iterdir()) == ["run.gsd", "systmp", "systmp-full"]
    with pytest.raises(FileWriteError):  # 100 particles, 30 frames: more than the disk holds
        _hundred_particles().export(target)


def test_a_failed_vtk_export_leaves_no_new_series_folder(tmpfs):
    # Before: FileWriteError for run.pvd, but run_vtk/ with both frames was left: the series
    # folder was put in place before the colliders file and the .pvd were written.
    from kinema.io import FileWriteError

    disk = tmpfs(16)
    (disk / "fill").write_bytes(b"\0" * 5120)
    with pytest.raises(FileWriteError) as err:
        _one_particle(0.01).export(disk / "run.pvd")
    assert err.value.errno == errno.ENOSPC and str(err.value).startswith(f"cannot write {disk / 'run'}")
    assert sorted(p.name for p in disk.iterdir()) == ["fill"]


def test_a_failed_vtk_export_leaves_the_earlier_export_as_it_was(tmpfs):
    from kinema.io import FileWriteError

    disk = tmpfs(48)
    _hundred_particles(0.01, box=True).export(disk / "run.pvd")
    before = _files_under(disk)
    assert sorted(before) == ["run.pvd", "run_colliders.vtp", "run_vtk/run_00000.vtp", "run_vtk/run_00001.vtp"]
    with pytest.raises(FileWriteError) as err:
        _hundred_particles(0.1, box=True).export(disk / "run.pvd")
    assert err.value.errno == errno.ENOSPC
    assert _files_under(disk) == before and sorted(p.name for p in disk.iterdir()) == ["run.pvd", "run_colliders.vtp", "run_vtk"]


def test_a_vtk_export_whose_pvd_cannot_be_put_in_place_restores_the_earlier_export(tmp_path, monkeypatch):
    # The outputs are put in place the series first, the .pvd last; a rename that fails there
    # puts back what the others replaced (the earlier series, the earlier colliders file).
    import kinema.io._files as files_module
    from kinema.io import FileWriteError

    _hundred_particles(0.01, box=True).export(tmp_path / "run.pvd")
    before = _files_under(tmp_path)
    real = os.replace

    def replace(src, dst):
        if os.fspath(dst) == os.fspath(tmp_path / "run.pvd"):
            raise OSError(errno.EIO, "Input/output error")
        return real(src, dst)

    monkeypatch.setattr(files_module.os, "replace", replace)
    with pytest.raises(FileWriteError) as err:
        _hundred_particles(0.05, box=True).export(tmp_path / "run.pvd")
    assert str(err.value) == f"cannot write {tmp_path / 'run.pvd'}: Input/output error"
    assert _files_under(tmp_path) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.pvd", "run_colliders.vtp", "run_vtk"]


def _usd_points(path):
    usd = pytest.importorskip("pxr.Usd")
    stage = usd.Stage.Open(str(path))
    assert stage is not None
    return len(stage.GetPrimAtPath("/World/particles").GetAttribute("points").Get(stage.GetEndTimeCode()))


def test_a_usdz_export_on_a_full_disk_is_whole_or_an_error(tmpfs, private_tmp):
    # Before, on this 76 kB tmpfs: [run.usdz] returned, the file 36864 of its 40851 bytes and
    # refused by Usd.Stage.Open (UsdUtils.CreateNewUsdzPackage returned True though its write
    # failed). It is now built in the system's temporary folder, checked, and copied.
    pytest.importorskip("pxr")
    from kinema.io import FileWriteError

    disk = tmpfs(76)
    target = disk / "run.usdz"
    try:
        traj = _hundred_particles()
        traj.export(target)
    except FileWriteError as e:
        assert e.errno == errno.ENOSPC and list(disk.iterdir()) == []
    else:
        assert _usd_points(target) == 100
    assert _descriptors_under(disk) == [] and list(private_tmp.folder.iterdir()) == []


def test_a_usdz_export_the_disk_cannot_hold_keeps_the_earlier_package(tmpfs, private_tmp):
    pytest.importorskip("pxr")
    from kinema.io import FileWriteError

    disk = tmpfs(40)
    target = disk / "run.usdz"
    _hundred_particles(0.01).export(target)
    before = target.read_bytes()
    with pytest.raises(FileWriteError) as err:
        _hundred_particles().export(target)
    assert err.value.errno == errno.ENOSPC and str(err.value) == f"cannot write {target}: No space left on device"
    assert target.read_bytes() == before and sorted(p.name for p in disk.iterdir()) == ["run.usdz"]
    assert _usd_points(target) == 100
    assert _descriptors_under(disk) == [] and list(private_tmp.folder.iterdir()) == []


@pytest.mark.parametrize("size_kb", [24, 48, 64])
def test_a_usdz_package_usd_core_could_not_write_whole_is_an_error(tmp_path, tmpfs, private_tmp, size_kb):
    # The stage (40 kB) or its package cannot be written whole in a full temporary folder:
    # CreateNewUsdzPackage still returns True there, so the package is checked (a whole zip
    # holding the stage) before it is copied to the target.
    pytest.importorskip("pxr")
    from kinema.io import FileWriteError

    scratch = private_tmp(tmpfs(size_kb, "systmp-full"))
    target = tmp_path / "run.usdz"
    target.write_bytes(b"kept")
    with pytest.raises(FileWriteError) as err:
        _hundred_particles().export(target)
    assert str(err.value).startswith(f"cannot write {target}: usd-core ") and f"in the temporary folder {scratch}" in str(err.value)
    assert target.read_bytes() == b"kept" and list(scratch.iterdir()) == [] and _descriptors_under(scratch) == []
