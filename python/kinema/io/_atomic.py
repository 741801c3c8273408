"""The errors of writing trajectory files, and atomic writes of one file: a temporary name
beside the target (it names its writer's host and process), then a rename over it. It also
removes the temporary files of writers that were killed, and refuses targets that are not
regular files (a device, a FIFO, a socket). ``atomic_file`` writes a file this way and
``hdf5_file`` an HDF5 file built in memory. ``kinema.io._files`` re-exports every name."""

from __future__ import annotations

import errno
import os
import re
import secrets
import shutil
import stat
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any


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
