"""Atomic writes (a temporary name, then a rename) and the frames of a trajectory-like object."""

from __future__ import annotations

import contextlib
import errno
import os
import re
import secrets
import shutil
import stat
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np


class TrajectoryFileError(ValueError):
    """A trajectory file that cannot be read or written. The message is one line naming the
    file and what is wrong with it (a command line prints it and exits with status 2)."""

    __module__ = "kinema.io"


class FileWriteError(OSError):
    """A write the system failed: a full disk (ENOSPC), a file-size limit (EFBIG), an I/O
    error (EIO), a permission refused while writing. The message is one line naming the file
    and the system's reason; `errno` is the system's. The target is left as it was and no
    temporary file remains. (A target refused before writing, such as a folder or a device,
    is a `TrajectoryFileError`.)"""

    __module__ = "kinema.io"

    @classmethod
    def of(cls, path: str | os.PathLike, e: OSError) -> FileWriteError:
        """The error for `path` from the system's `e` (`errno`, `strerror` and
        `filename` set as an `OSError`'s)."""
        reason = e.strerror or str(e)
        return cls(e.errno, reason, os.fspath(path))

    def __str__(self) -> str:
        return f"cannot write {self.filename}: {self.strerror}"


_BOTH: dict[type, type] = {}


def write_error(path: str | os.PathLike, code: int, reason: str) -> FileWriteError:
    """A `FileWriteError` for `path` of errno `code` that is also the built-in `OSError`
    subclass of that errno (`FileNotFoundError` for ENOENT, `IsADirectoryError` for
    EISDIR, ...), as `OSError(code, ...)` would be: code that caught the built-in error
    before it became a `FileWriteError` still catches it."""
    builtin = type(OSError(code, reason))
    if builtin is OSError:
        return FileWriteError(code, reason, os.fspath(path))
    if builtin not in _BOTH:
        # named FileWriteError too: a traceback shows kinema.io.FileWriteError
        _BOTH[builtin] = type("FileWriteError", (FileWriteError, builtin), {"__module__": "kinema.io", "__doc__": FileWriteError.__doc__})
    return _BOTH[builtin](code, reason, os.fspath(path))


@contextmanager
def os_errors_as_write_errors(path: str | os.PathLike) -> Iterator[None]:
    """Turns an `OSError` raised in the block that is not a `FileWriteError` yet (a name
    too long for the file system, a folder that is not searchable, a temporary file that
    cannot be made) into a `FileWriteError` naming `path`, of the same errno (and the
    same built-in subclass, `write_error`): every failure of a writer's system calls is one
    line naming the file it was asked to write."""
    try:
        yield
    except FileWriteError:
        raise
    except OSError as e:
        if e.errno is None:
            raise
        raise write_error(path, e.errno, e.strerror or str(e)) from None


def _umask() -> int:
    """The process's umask. Linux reports it in /proc/self/status; elsewhere it is read by
    setting and restoring it, which briefly changes it for every thread of the process (the
    writers below never need it: they create their files with the mode open() uses)."""
    try:
        with open("/proc/self/status", encoding="ascii", errors="replace") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    mask = os.umask(0)
    os.umask(mask)
    return mask


_NAME_TRIES = 100

# A temporary name carries its writer: <prefix><host>-<pid>.<random><suffix>. A writer killed
# (kill -9, power off) leaves it behind; the next writer of the same target removes it once
# that process is gone (same host), or after a day where the name has no owner (an older
# kinema's).
_OWNED = re.compile(r"(?:(?P<host>[A-Za-z0-9-]*)-(?P<pid>[0-9]+)\.)?[A-Za-z0-9_]+")
STALE_UNKNOWN_OWNER_S = 86400.0


def host_name() -> str:
    """This machine's name as temporary names carry it (letters, digits and '-')."""
    import socket

    return re.sub(r"[^A-Za-z0-9-]", "-", socket.gethostname())[:64]


def owner_tag() -> str:
    """`<host>-<pid>`: what a temporary name says of the process that made it."""
    return f"{host_name()}-{os.getpid()}"


def alive(pid: int) -> bool:
    """Whether process `pid` runs on this machine (another user's counts as running)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    except (OverflowError, ValueError, OSError):
        return False
    return True


def remove_stale(folder: Path, prefix: str, suffix: str = "") -> list[Path]:
    """Removes the temporary files and folders `<prefix><owner>.<random><suffix>` in
    `folder` whose writer is gone: its process no longer runs on this host, or, with no
    owner in the name, it is more than a day old. Those of live writers and of other hosts
    are kept. Returns what was removed."""
    import time

    removed: list[Path] = []
    try:
        entries = [e for e in os.scandir(folder) if e.name.startswith(prefix) and e.name.endswith(suffix)]
    except OSError:
        return removed
    host = host_name()
    for entry in entries:
        middle = entry.name[len(prefix) : len(entry.name) - len(suffix)]
        m = _OWNED.fullmatch(middle)
        if m is None:
            continue
        if m["pid"] is not None:
            stale = m["host"] == host and int(m["pid"]) != os.getpid() and not alive(int(m["pid"]))
        else:
            try:
                stale = time.time() - entry.stat(follow_symlinks=False).st_mtime > STALE_UNKNOWN_OWNER_S
            except OSError:
                stale = False
        if stale:
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path, ignore_errors=True)
            else:
                Path(entry.path).unlink(missing_ok=True)
            removed.append(Path(entry.path))
    return removed


def _temporary_file(parent: Path, prefix: str, suffix: str) -> Path:
    """A new empty file `<prefix><random><suffix>` in `parent`, created exclusively with
    mode 0666 as an ordinary `open()` creates files: the kernel applies the umask (and a
    default ACL of the folder), so 0644 under umask 022. `tempfile.mkstemp` would make it
    0600."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_BINARY", 0)
    for _ in range(_NAME_TRIES):
        path = parent / f"{prefix}{owner_tag()}.{secrets.token_hex(6)}{suffix}"
        try:
            fd = os.open(path, flags, 0o666)
        except FileExistsError:
            continue
        os.close(fd)
        return path
    raise FileExistsError(errno.EEXIST, "no unused temporary name", str(parent))


def _temporary_folder(parent: Path, prefix: str, suffix: str) -> Path:
    """A new empty folder in `parent`, made with mode 0777 as `os.mkdir` makes folders
    (0755 under umask 022; `tempfile.mkdtemp` would make it 0700)."""
    for _ in range(_NAME_TRIES):
        path = parent / f"{prefix}{owner_tag()}.{secrets.token_hex(6)}{suffix}"
        try:
            os.mkdir(path, 0o777)
        except FileExistsError:
            continue
        return path
    raise FileExistsError(errno.EEXIST, "no unused temporary name", str(parent))


_KINDS = (
    (stat.S_ISCHR, "character device"),
    (stat.S_ISBLK, "block device"),
    (stat.S_ISFIFO, "FIFO"),
    (stat.S_ISSOCK, "socket"),
)


def special_kind(mode: int) -> str | None:
    """What a file of `st_mode` is if it is a device, a FIFO or a socket (else None)."""
    return next((kind for test, kind in _KINDS if test(mode)), None)


def refuse_special_target(path: str | os.PathLike) -> None:
    """Refuses a target that exists and is not a regular file (followed through symbolic
    links): a device, a FIFO, a socket. Every writer puts a temporary file in place of its
    target by a rename, which would replace such a node (a save to /dev/null as root made
    the machine's /dev/null an 80 kB file), so kinema writes only where nothing stands or a
    regular file does, and leaves anything else untouched. Nothing is opened: a FIFO is not
    blocked on. A directory is refused by the callers, with their own advice."""
    path = Path(path)
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return
    except OSError as e:  # a name too long, a loop of links, a folder not searchable
        raise TrajectoryFileError(f"cannot write {path}: {e.strerror or e}") from None
    kind = special_kind(mode)
    if kind is not None:
        raise TrajectoryFileError(f"cannot write {path}: it is a {kind}, not a regular file; kinema replaces only regular files, so give another name")


def _writable_parent(path: Path) -> Path:
    try:  # (is_dir raises for a name too long, ENAMETOOLONG)
        is_dir = path.is_dir()
        parent_is_dir = path.parent.is_dir()
    except OSError as e:
        raise FileWriteError.of(path, e) from None
    if is_dir:
        raise TrajectoryFileError(f"cannot write {path}: it is a directory; give a file name such as {path / 'run.h5'}")
    refuse_special_target(path)
    parent = path.parent
    if not parent_is_dir:
        raise TrajectoryFileError(f"cannot write {path}: the folder {parent} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise TrajectoryFileError(f"cannot write {path}: the folder {parent} is not writable")
    return parent


@contextmanager
def atomic_file(path: str | os.PathLike) -> Iterator[Path]:
    """Yields a temporary path in the folder of `path`; when the block ends without an
    exception the temporary file is renamed to `path` (`os.replace`, atomic on one file
    system), otherwise it is removed and `path` is left as it was. The file gets the mode
    an ordinary `open()` would give it (0666 less the umask). An `OSError` while writing
    becomes a `FileWriteError` naming `path`."""
    path = Path(path)
    parent = _writable_parent(path)
    remove_stale(parent, f".{path.name}.", ".part")  # left by a writer of it that was killed
    try:
        tmp = _temporary_file(parent, f".{path.name}.", ".part")
    except OSError as e:
        raise FileWriteError.of(path, e) from None
    try:
        yield tmp
        os.replace(tmp, path)
    except BaseException as e:
        tmp.unlink(missing_ok=True)
        if isinstance(e, OSError) and not isinstance(e, FileWriteError):
            raise FileWriteError.of(path, e) from None
        raise


@contextmanager
def hdf5_file(path: str | os.PathLike, **options: Any) -> Iterator[Any]:
    """Yields an `h5py.File` open for writing whose contents become `path` when the block
    ends without an exception (written as `atomic_file` writes; `options` go to
    `h5py.File`).

    HDF5 never writes to the disk here: it builds the file in memory (h5py's file-object
    driver on a `BytesIO`), and Python writes the finished bytes. A write that fails (a full
    disk, a file-size limit, an I/O error) then fails in Python, as one `FileWriteError`
    naming `path`, with the temporary file removed. Given to HDF5 itself, the failure leaves
    objects that cannot be closed, since closing writes: their deallocation prints dozens of
    tracebacks and the interpreter crashes at exit (h5py issues 914, 1775, 2160). The cost is
    the file's size in memory while it is built, about what the trajectory already holds."""
    import io

    from ._h5md_layout import import_h5py

    h5py = import_h5py()
    path = Path(path)
    _writable_parent(path)  # refused before the work of building it
    image = io.BytesIO()
    with h5py.File(image, "w", **options) as f:
        yield f
    with atomic_file(path) as tmp, open(tmp, "wb") as out:
        out.write(image.getbuffer())


SERIES_DIGITS = 5  # frame numbers in series file names: stem_00000.vtp


def series_names(path: Path, format: str, suffix: str, own_suffixes: tuple[str, ...]) -> tuple[Path, str, str]:
    """The folder of a series (`<stem>_<format>`), the stem of its file names and the
    regular expression of those names (`<stem>_00000<suffix>`, `SERIES_DIGITS` digits
    or more). The stem is the name of `path` less its suffix where that is one of the
    format's `own_suffixes` (`export` refuses another format's), the whole name
    otherwise."""
    stem = path.stem if path.suffix.lower() in own_suffixes else path.name
    return path.with_name(f"{stem}_{format}"), stem, rf"{re.escape(stem)}_\d{{{SERIES_DIGITS},}}{re.escape(suffix)}"


@contextmanager
def atomic_folder(folder: str | os.PathLike, pattern: str) -> Iterator[Path]:
    """Yields a temporary folder beside `folder`; when the block ends without an exception
    it takes the place of `folder`, otherwise it is removed with all it holds. An existing
    `folder` is replaced only if every file in it matches the regular expression
    `pattern` (a series written before), so no other file is ever deleted. The folder
    gets the mode `os.mkdir` gives (0777 less the umask), the files in it the mode their
    writer gave them."""
    folder = Path(folder)
    _check_series_folder(folder, pattern)
    parent = folder.parent
    remove_stale(parent, f".{folder.name}.", ".part")
    try:
        tmp = _temporary_folder(parent, f".{folder.name}.", ".part")
    except OSError as e:
        raise FileWriteError.of(folder, e) from None
    try:
        yield tmp
        old = None
        if folder.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", suffix=".old", dir=parent))
            os.replace(folder, old / folder.name)
        os.replace(tmp, folder)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except BaseException as e:
        shutil.rmtree(tmp, ignore_errors=True)
        if isinstance(e, OSError) and not isinstance(e, FileWriteError):
            raise FileWriteError.of(folder, e) from None
        raise


# -- writes built apart, and several outputs put in place together ----------------------------


@contextmanager
def private_folder(path: str | os.PathLike) -> Iterator[Path]:
    """Yields a new private folder (mode 0700) in the system's temporary folder
    (`tempfile.gettempdir()`: `$TMPDIR`, else /tmp) for a library that writes its own file
    (gsd, usd-core) to build `path` in, apart from `path`'s file system; the folder is
    removed with all it holds when the block ends, however it ends. Such a library cannot be
    trusted with a failed write (a full disk, a file-size limit): gsd 5.0.1 leaves its file
    open or raises its own RuntimeError, usd-core reports a truncated .usdz as made. Built
    apart, the finished file goes to `path` by `copy_into`, Python's own writes, whose
    failure is one `FileWriteError`. `path` is checked first as `atomic_file` checks it
    (a folder, a device, a missing folder are refused before any work); an `OSError` of
    making the folder, or raised in the block, becomes a `FileWriteError` naming `path`."""
    path = Path(path)
    _writable_parent(path)
    try:
        scratch = Path(tempfile.mkdtemp(prefix="kinema-"))
    except OSError as e:
        raise FileWriteError.of(path, e) from None
    try:
        yield scratch
    except OSError as e:
        if isinstance(e, FileWriteError):
            raise
        raise FileWriteError.of(path, e) from None
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def copy_into(source: str | os.PathLike, path: str | os.PathLike) -> Path:
    """Writes the bytes of the file `source` to `path` as `atomic_file` writes (a
    temporary name beside it, renamed over it when complete): a write that fails (a full
    disk, a file-size limit) is a `FileWriteError` naming `path`, the temporary file
    removed and what was at `path` left as it was. Returns `path`."""
    path = Path(path)
    with atomic_file(path) as tmp, open(source, "rb") as src, open(tmp, "wb") as out:
        shutil.copyfileobj(src, out, 1 << 20)
    return path


def close_descriptors_on(path: str | os.PathLike) -> list[int]:
    """Closes this process's descriptors open on the file `path` (also once it is deleted)
    and returns their numbers: those a library left open on its own file when it believes it
    closed it (gsd 5.0.1's `gsd_close` returns before `close(fd)` when its last flush
    fails). Only for a file nothing else of this process opened. Linux's /proc/self/fd; a
    no-op where there is none."""
    target = os.path.abspath(os.fspath(path))
    closed: list[int] = []
    try:
        fds = os.listdir("/proc/self/fd")
    except OSError:
        return closed
    for fd in fds:
        try:
            link = os.readlink(f"/proc/self/fd/{fd}")
        except OSError:
            continue
        if link in (target, f"{target} (deleted)"):
            try:
                os.close(int(fd))
            except (OSError, ValueError):
                continue
            closed.append(int(fd))
    return closed


def _check_series_folder(folder: Path, pattern: str) -> None:
    """Refuses `folder` as a series' folder (as `atomic_folder` does): a file of that
    name, a folder holding files other than an earlier series (names matching `pattern`),
    a parent folder that does not exist."""
    if folder.exists():
        if not folder.is_dir():
            raise TrajectoryFileError(f"cannot write the series folder {folder}: a file of that name exists")
        others = [p.name for p in folder.iterdir() if not re.fullmatch(pattern, p.name)]
        if others:
            raise TrajectoryFileError(
                f"cannot write the series folder {folder}: it exists and holds other files ({', '.join(sorted(others)[:3])}); remove them or choose another name"
            )
    if not folder.parent.is_dir():
        raise TrajectoryFileError(f"cannot write {folder}: the folder {folder.parent} does not exist")


class Outputs:
    """The files and folders of one write (`atomic_outputs`), each staged under a temporary
    name beside its target: `file(path)` as `atomic_file` makes it, `folder(folder,
    pattern)` as `atomic_folder` does (an earlier series is replaced only if it holds
    nothing else)."""

    def __init__(self) -> None:
        self._staged: list[tuple[Path, Path, Path | None]] = []  # (temporary, target, holder of a folder's earlier series)

    def file(self, path: str | os.PathLike) -> Path:
        """A new empty temporary file that will take the place of `path`."""
        path = Path(path)
        parent = _writable_parent(path)
        remove_stale(parent, f".{path.name}.", ".part")
        try:
            tmp = _temporary_file(parent, f".{path.name}.", ".part")
        except OSError as e:
            raise FileWriteError.of(path, e) from None
        self._staged.append((tmp, path, None))
        return tmp

    def folder(self, folder: str | os.PathLike, pattern: str) -> Path:
        """A new empty temporary folder that will take the place of `folder`. Where an
        earlier series is there, the folder it will be moved into is made now, so that
        putting the outputs in place needs no new file (a full disk, no inode left)."""
        folder = Path(folder)
        _check_series_folder(folder, pattern)
        parent = folder.parent
        remove_stale(parent, f".{folder.name}.", ".part")
        try:
            tmp = _temporary_folder(parent, f".{folder.name}.", ".part")
        except OSError as e:
            raise FileWriteError.of(folder, e) from None
        self._staged.append((tmp, folder, None))
        if folder.exists():
            try:
                holder = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", suffix=".old", dir=parent))
            except OSError as e:
                raise FileWriteError.of(folder, e) from None
            self._staged[-1] = (tmp, folder, holder)
        return tmp

    @staticmethod
    @contextmanager
    def naming(path: str | os.PathLike) -> Iterator[None]:
        """An `OSError` in the block (writing the temporary of `path`) becomes a
        `FileWriteError` naming `path`."""
        try:
            yield
        except OSError as e:
            if isinstance(e, FileWriteError):
                raise
            raise FileWriteError.of(path, e) from None

    def _discard(self) -> None:
        for tmp, _, holder in self._staged:
            if tmp.is_dir() and not tmp.is_symlink():
                shutil.rmtree(tmp, ignore_errors=True)
            else:
                tmp.unlink(missing_ok=True)
            if holder is not None:
                with contextlib.suppress(OSError):
                    holder.rmdir()  # empty unless a restore failed: then it keeps the earlier series

    def _put_in_place(self) -> None:
        """Renames each temporary over its target, the last staged first; if a rename fails,
        the targets already replaced get back what they held (a folder always; a file where
        a hard link kept it) and the error is raised."""
        undo: list[Any] = []
        backups: list[Path] = []
        try:
            for tmp, target, holder in reversed(self._staged):
                if tmp.is_dir():
                    if holder is not None and target.is_dir() and not target.is_symlink():  # the earlier series, aside
                        kept = holder / target.name
                        os.replace(target, kept)
                        undo.append(lambda target=target, kept=kept: os.replace(kept, target))
                    os.replace(tmp, target)
                    undo.append(lambda target=target: shutil.rmtree(target))
                    continue
                backup = None
                if target.is_file():
                    backup = target.parent / f".{target.name}.{owner_tag()}.{secrets.token_hex(6)}.old"
                    try:
                        os.link(target, backup, follow_symlinks=False)  # (a link named as the target: the link)
                        backups.append(backup)
                    except OSError:
                        backup = None  # (a file system without hard links, or none left): not restored
                existed = target.exists() or target.is_symlink()
                os.replace(tmp, target)
                if backup is not None:
                    undo.append(lambda target=target, backup=backup: os.replace(backup, target))
                elif not existed:
                    undo.append(lambda target=target: target.unlink())
        except BaseException:
            restored = True
            for step in reversed(undo):
                try:
                    step()
                except OSError:
                    restored = False
            if restored:  # (else a backup not put back keeps the earlier file, under its .old name)
                for backup in backups:
                    backup.unlink(missing_ok=True)
            raise
        for backup in backups:
            backup.unlink(missing_ok=True)
        for _, _, holder in self._staged:
            if holder is not None:
                shutil.rmtree(holder, ignore_errors=True)
        self._staged = []


@contextmanager
def atomic_outputs(path: str | os.PathLike) -> Iterator[Outputs]:
    """Yields an `Outputs` on which the block stages the files and folders of one write (a
    VTK series: its folder of frames, the colliders file, the .pvd that points at both) and
    writes them; when the block ends without an exception they are all put in place, the
    last staged first, so stage the file that refers to the others first (it is put in place
    last, when what it refers to is there). Otherwise, or if putting one in place fails,
    every temporary is removed and what was there before is left as it was (the targets
    already replaced restored): a failed write leaves neither new files nor an earlier
    output changed. An `OSError` not yet a `FileWriteError` becomes one naming
    `path`."""
    outputs = Outputs()
    try:
        yield outputs
        outputs._put_in_place()
    except BaseException as e:
        outputs._discard()
        if isinstance(e, OSError) and not isinstance(e, FileWriteError):
            raise FileWriteError.of(path, e) from None
        raise


@dataclass(frozen=True)
class Frames:
    """The per-particle data of a trajectory-like object, checked and in SI units: `t`
    (F,) s; `positions` (F, N, 3) m and `velocities` (F, N, 3) m/s (z = 0 in 2D worlds);
    `masses` (N,) kg and `radii` (N,) m, `None` when the object has none; `ids` (N,)
    (0..N-1 by default); `dim` 2 or 3; `dt` s and `method`, `None` when unknown;
    `alive` (F, N) bool, which particles exist at each frame (all True without births and
    deaths; positions and velocities are NaN where not); with spin `angular_velocities`
    (F, N, 3) rad/s, `orientations` (F, N, 4) unit quaternions (w, x, y, z) and
    `inertia` (N,) kg·m², `None` where the trajectory has none; `groups` (N,) int64, each
    particle's collision group (0..31, `check_frames` refuses others), `None` where the
    trajectory has none; `step` s, the length of the run's steps where it is not `dt`
    (`Trajectory.step`: a frame of 1/fps that dt does not divide), else `None`."""

    t: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    masses: np.ndarray | None
    radii: np.ndarray | None
    ids: np.ndarray
    dim: int
    dt: float | None
    method: str | None
    alive: np.ndarray
    angular_velocities: np.ndarray | None = None
    orientations: np.ndarray | None = None
    inertia: np.ndarray | None = None
    groups: np.ndarray | None = None
    step: float | None = None

    @property
    def n_frames(self) -> int:
        return self.t.shape[0]

    @property
    def n_particles(self) -> int:
        return self.positions.shape[1]

    @property
    def changes_count(self) -> bool:
        """Whether particles are born or die: some are not alive at some frame."""
        return not bool(self.alive.all())

    @property
    def has_velocities(self) -> bool:
        """Whether the velocities are known: some particle that exists has one that is not
        NaN. A trajectory read from a file without velocities has them all NaN ("unknown",
        `Trajectory.load`); the exports then write no velocity columns, so that the file
        reads back without velocities rather than with NaN ones."""
        live = self.velocities[self.alive]
        return live.size == 0 or not bool(np.isnan(live).all())

    def live(self, i: int) -> np.ndarray:
        """The columns (particles) alive at frame `i`, in column order (that of `ids`)."""
        return np.flatnonzero(self.alive[i])


def _per_frame_vectors(traj: Any, name: str, n_frames: int) -> np.ndarray:
    a = np.asarray(getattr(traj, name), dtype=np.float64)
    if a.ndim != 3 or a.shape[0] != n_frames or a.shape[2] not in (2, 3):
        raise ValueError(f"{name} has shape {a.shape}; it must be (F, N, 3) with F = {n_frames} frames")
    if a.shape[2] == 2:
        a = np.concatenate([a, np.zeros(a.shape[:2] + (1,))], axis=2)
    return a


def _per_frame_rows(traj: Any, name: str, shape: tuple[int, int, int]) -> np.ndarray | None:
    """The optional (F, N, w) array `name` of `traj` (angular velocities, orientations),
    shape-checked; `None` where it has none."""
    value = getattr(traj, name, None)
    if value is None:
        return None
    a = np.asarray(value, dtype=np.float64)
    if a.shape != shape:
        raise ValueError(f"{name} has shape {a.shape}; it must be {shape}, (F, N, {shape[2]})")
    return a


def _per_particle(traj: Any, names: tuple[str, ...], n: int, dtype: Any) -> np.ndarray | None:
    for name in names:
        value = getattr(traj, name, None)
        if value is not None:
            a = np.asarray(value, dtype=dtype)
            if a.shape != (n,):
                raise ValueError(f"{name} has shape {a.shape}; it must be ({n},), one value per particle")
            return a
    return None


def _groups(traj: Any, n: int) -> np.ndarray | None:
    """The optional collision groups (N,) of `traj` as int64, shape- and type-checked (their
    range is `check_frames`'s); `None` where it has none."""
    value = getattr(traj, "groups", None)
    if value is None:
        return None
    a = np.asarray(value)
    if a.shape != (n,):
        raise ValueError(f"groups has shape {a.shape}; it must be ({n},), one collision group per particle")
    if a.dtype.kind not in "iu" and a.size:
        raise ValueError(f"groups has dtype {a.dtype}; collision groups are integers in 0..31")
    return a.astype(np.int64)


def frames_of(traj: Any) -> Frames:
    """Reads `t`, `positions`, `velocities` and the optional `masses` (or `mass`),
    `radii` (or `radius`), `ids`, `alive`, `dim`, `dt`, `method`,
    `angular_velocities`, `orientations`, `inertia` and `groups` of a
    trajectory-like object and checks their shapes; raises `ValueError` naming the
    attribute that is wrong."""
    t = np.asarray(traj.t, dtype=np.float64)
    if t.ndim != 1:
        raise ValueError(f"t has shape {t.shape}; it must be (F,), one time per frame")
    x = _per_frame_vectors(traj, "positions", t.shape[0])
    v = _per_frame_vectors(traj, "velocities", t.shape[0])
    if v.shape != x.shape:
        raise ValueError(f"velocities have shape {v.shape} but positions {x.shape}; they must match")
    n = x.shape[1]
    alive = getattr(traj, "alive", None)
    alive = np.ones((t.shape[0], n), dtype=bool) if alive is None else np.asarray(alive, dtype=bool)
    if alive.shape != (t.shape[0], n):
        raise ValueError(f"alive has shape {alive.shape}; it must be (F, N) = {(t.shape[0], n)}, one flag per frame and particle")
    dim = int(getattr(traj, "dim", None) or 3)
    if dim not in (2, 3):
        raise ValueError(f"dim = {dim} is invalid: it must be 2 or 3")
    # NaN (a particle not alive, or velocities unknown) is no z != 0
    if dim == 2 and (np.any(np.abs(x[..., 2]) > 0) or np.any(np.abs(v[..., 2]) > 0)):
        raise ValueError("dim = 2 but some positions or velocities have z != 0; a 2D trajectory lies in the xy-plane")
    ids = _per_particle(traj, ("ids", "id"), n, np.int64)
    dt = getattr(traj, "dt", None)
    method = getattr(traj, "method", None)
    return Frames(
        t=t,
        positions=x,
        velocities=v,
        masses=_per_particle(traj, ("masses", "mass"), n, np.float64),
        radii=_per_particle(traj, ("radii", "radius"), n, np.float64),
        ids=np.arange(n, dtype=np.int64) if ids is None else ids,
        dim=dim,
        dt=None if dt is None else float(dt),
        # (a Trajectory's `step` is the steps' length; other objects' may be step numbers)
        step=float(traj.step) if isinstance(getattr(traj, "step", None), float) else None,
        method=None if method is None else str(method),
        alive=alive,
        angular_velocities=_per_frame_rows(traj, "angular_velocities", (t.shape[0], n, 3)),
        orientations=_per_frame_rows(traj, "orientations", (t.shape[0], n, 4)),
        inertia=_per_particle(traj, ("inertia",), n, np.float64),
        groups=_groups(traj, n),
    )
