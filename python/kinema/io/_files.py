"""Atomic writes of series folders and of several outputs put in place together, and writes
built apart by a library in a private folder, then copied in. The errors, the atomic write of
one file and the temporary names are in ``kinema.io._atomic``, the checked frames of a
trajectory-like object in ``kinema.io._frames``; this module re-exports their names."""

from __future__ import annotations

import contextlib
import os
import re
import secrets
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from ._atomic import _BOTH as _BOTH
from ._atomic import _KINDS as _KINDS
from ._atomic import _NAME_TRIES as _NAME_TRIES
from ._atomic import _OWNED as _OWNED
from ._atomic import STALE_UNKNOWN_OWNER_S as STALE_UNKNOWN_OWNER_S
from ._atomic import FileWriteError as FileWriteError
from ._atomic import TrajectoryFileError as TrajectoryFileError
from ._atomic import _temporary_file as _temporary_file
from ._atomic import _temporary_folder as _temporary_folder
from ._atomic import _umask as _umask
from ._atomic import _writable_parent as _writable_parent
from ._atomic import alive as alive
from ._atomic import atomic_file as atomic_file
from ._atomic import hdf5_file as hdf5_file
from ._atomic import host_name as host_name
from ._atomic import os_errors_as_write_errors as os_errors_as_write_errors
from ._atomic import owner_tag as owner_tag
from ._atomic import refuse_special_target as refuse_special_target
from ._atomic import remove_stale as remove_stale
from ._atomic import special_kind as special_kind
from ._atomic import write_error as write_error
from ._frames import Frames as Frames
from ._frames import _groups as _groups
from ._frames import _per_frame_rows as _per_frame_rows
from ._frames import _per_frame_vectors as _per_frame_vectors
from ._frames import _per_particle as _per_particle
from ._frames import frames_of as frames_of

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
