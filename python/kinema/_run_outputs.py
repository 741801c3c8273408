"""A run's output folder (for `kinema.runner`): the folder made and checked before any work
(`_outdir`, `_writable_file` for --keep-checkpoint, `_refuse_special_outputs`), the hidden
staging folders a run writes into and the stale ones runs that were killed left
(`_stage_prefix`, `_remove_stale_stages`), the checkpoint removed when the run is whole
(`_remove_checkpoints`), and contact_events.csv (`_contact_events_csv`)."""

from __future__ import annotations

import os
from pathlib import Path


def _refuse_special_outputs(outdir: Path, names: list[str]) -> None:
    """Before any work: each output the run will move into ``outdir`` may replace only a
    regular file (a folder, a device, a FIFO or a socket of that name is refused, untouched)."""
    from .io._files import refuse_special_target

    for name in names:
        if (outdir / name).is_dir():
            raise ValueError(f"-o {outdir}: {name} there is a folder; the run writes a file of that name")
        refuse_special_target(outdir / name)


def _writable_file(path: Path, option: str) -> None:
    """Refuses (ValueError naming ``option``) a ``path`` that is a folder or whose folder
    cannot be made or written; makes the folder."""
    if path.is_dir():
        raise ValueError(f"{option} {path}: is a folder; give a file name (e.g. {path / 'final.ckpt'})")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ValueError(f"{option} {path}: cannot create its folder ({e.strerror})") from None
    if not os.access(path.parent, os.W_OK | os.X_OK):
        raise ValueError(f"{option} {path}: its folder is not writable")


def _outdir(out: Path) -> Path:
    if out.exists() and not out.is_dir():
        raise ValueError(f"-o {out}: exists and is not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ValueError(f"-o {out}: cannot create the folder ({e.strerror})") from None
    if not os.access(out, os.W_OK | os.X_OK):
        raise ValueError(f"-o {out}: the folder is not writable")
    return out


def _contact_events_csv(events: dict, out: Path) -> Path:
    """The begin and end of touch events (``World.contact_events``) as a CSV file with a
    header: time (s, 17 significant digits), begin (1 or 0), i and j (particle ids, j = −1
    against a collider), collider (its index, −1 between particles), impulse (N·s)."""
    import csv

    with open(out, "w", newline="") as f:
        rows = csv.writer(f)
        rows.writerow(["time", "begin", "i", "j", "collider", "impulse"])
        columns = (events[k] for k in ("time", "begin", "i", "j", "collider", "impulse"))
        for t, b, i, j, k, p in zip(*columns, strict=True):
            rows.writerow([repr(float(t)), int(b), int(i), int(j), int(k), repr(float(p))])
    return out


# A run writes into a hidden staging folder .kinema-run.<host>-<pid>.<random> in its output
# folder; a run that is killed (kill -9, power off) leaves it behind, and the next run into the
# folder removes it once the process that made it is gone.
def _stage_prefix() -> str:
    from .io._files import owner_tag

    return f".kinema-run.{owner_tag()}."


def _remove_stale_stages(outdir: Path) -> list[Path]:
    """Remove the staging folders in ``outdir`` whose run is over (its process is gone); keep
    those of live runs and of other hosts. Returns the folders removed."""
    from .io._files import remove_stale

    return remove_stale(outdir, ".kinema-run.")


def _remove_checkpoints(outdir: Path, keep: Path | None = None) -> None:
    """Remove ``outdir``/checkpoint.ckpt (unless it is ``keep``, the --keep-checkpoint asked
    for) and the staging files (``.checkpoint.ckpt.<host>-<pid>.<random>.part``,
    ``kinema.io._files.atomic_file``) of writers of it that are gone."""
    from .io._files import remove_stale

    ckpt = outdir / "checkpoint.ckpt"
    if keep is None or not (ckpt.exists() and keep.exists() and os.path.samefile(ckpt, keep)):
        ckpt.unlink(missing_ok=True)
    remove_stale(outdir, f".{ckpt.name}.", ".part")
