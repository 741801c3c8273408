"""What the ``kinema`` command's sub-commands share (``kinema.cli``): a failure said as one
line and an exit code (``_fail``; ``_guarded`` around a command's body, which also says each
warning as one line), a trajectory loaded with the ``--units`` given (``_load``), and the help
of the ``--units`` option and of a trajectory argument."""

from __future__ import annotations

import os
from pathlib import Path

import typer
from rich.markup import escape

from .runner import err_console


def _fail(message: str, code: int = 2) -> None:
    # (escaped: a message quotes paths and values, whose brackets are not rich markup)
    err_console.print(f"[bold red]error:[/] {escape(message)}", highlight=False, soft_wrap=True)
    raise typer.Exit(code)


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """``warnings.showwarning`` of the commands: a warning is one line ``warning: ...`` on
    stderr, as ``kinema run`` says its own, without Python's file, line and source."""
    err_console.print(f"[yellow]warning:[/] {escape(str(message))}", highlight=False, soft_wrap=True)


def _guarded(fn):
    """Run a command body, turning known failures into one line and an exit code, and each
    warning into one line (``_one_line_warning``)."""
    import functools

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        import warnings

        with warnings.catch_warnings():
            warnings.showwarning = _one_line_warning
            return _guarded_body(fn, args, kwargs)

    return wrapper


def _guarded_body(fn, args, kwargs):
    """Runs ``fn``, turning known failures into one line and an exit code."""
    import kinema
    from kinema.scene import SceneError

    try:
        return fn(*args, **kwargs)
    except typer.Exit:
        raise
    except kinema.SimulationDiverged as e:
        _fail(str(e) if "diverged" in str(e) else f"the simulation diverged: {e}", code=1)
    except SceneError as e:  # one line per problem
        for line in str(e).splitlines():
            err_console.print(f"[bold red]error:[/] {escape(line)}", highlight=False, soft_wrap=True)
        raise typer.Exit(2) from None
    except ImportError as e:  # an optional package a format needs (usd-core): how to get it
        _fail(str(e).strip().splitlines()[0])
    except (ValueError, OSError) as e:  # TrajectoryFileError is a ValueError
        text = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        if isinstance(e, OSError) and e.filename:
            text = f"cannot write {e.filename}: {e.strerror}"
        _fail(text)
    except KeyboardInterrupt:
        _fail("interrupted; nothing was written", code=130)
    except MemoryError:
        _fail("out of memory: the work is too large for this machine; nothing was written")
    except Exception as e:
        if os.environ.get("KINEMA_DEBUG"):
            raise
        _fail(f"unexpected {type(e).__name__}: {e} (set KINEMA_DEBUG=1 for the traceback)", code=1)


_UNITS_HELP = (
    "Units of a file that does not say them (a LAMMPS dump or data file without its units, a HOOMD GSD file, an XYZ file not in ASE's units): "
    "real, metal, si, cgs, electron, micro, nano (LAMMPS's styles), ase, or length=M,time=S,mass=KG (the file's units in SI)."
)
_TRAJ_HELP = (
    "A trajectory file: H5MD (.h5), extended XYZ (.xyz), GSD (.gsd), a LAMMPS dump (.lammpstrj) or data file (.data), "
    "a USD stage's points (.usd, .usdc, .usda, .usdz), or kinema's CSV, VTK (.pvd) or PLY series export."
)


def _load(path: Path, units: str | None):
    """The trajectory in ``path``, any format kinema reads (``Trajectory.load``), with the
    ``--units`` given: a name, or length=M,time=S,mass=KG."""
    from .io import UnitWarning
    from .trajectory import Trajectory

    given: str | dict[str, float] | None = units
    if units is not None and "=" in units:
        given = {}
        for item in units.split(","):
            key, _, value = item.partition("=")
            try:
                given[key.strip()] = float(value)
            except ValueError:
                raise ValueError(f"--units {units!r}: {item!r} is invalid: give a name or length=M,time=S,mass=KG with numbers") from None
    import warnings

    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", UnitWarning)
            traj = Trajectory.load(path, units=given)
        for w in caught:  # a UnitWarning (numbers taken in units the file does not state): one line, as runner.py says its warnings
            if issubclass(w.category, UnitWarning):
                err_console.print(f"[yellow]warning:[/] {escape(str(w.message))} (--units)", highlight=False, soft_wrap=True)
            else:
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        return traj
    except ValueError as e:
        text = str(e)
        if text.startswith("units"):  # the units refused: said of the option
            raise ValueError(f"--units {units!r}: {text.split(' is invalid: ', 1)[1] if ' is invalid: ' in text else text.split(': ', 1)[-1]}") from None
        raise
