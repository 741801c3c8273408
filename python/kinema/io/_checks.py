"""Checks of what a trajectory file holds, for the messages of its readers: the type of a
dataset's values, the memory there is to read it, and values shown as the user wrote them."""

from __future__ import annotations

import math
import os
from typing import Any

import numpy as np

_GIB = 1 << 30


# A text file's memory once read, per byte of file: its lines and the words of its rows as
# NumPy strings (4 bytes a character, padded to the longest word).
TEXT_FACTOR = 8


def available_memory() -> int | None:
    """Bytes of memory this process can still use: the kernel's `MemAvailable` (free memory
    and what the page cache can give back), else the free pages (`SC_AVPHYS_PAGES`), and
    no more than what the control group's limit leaves (a container); `None` when unknown."""
    known: list[int] = []
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    known.append(int(line.split()[1]) * 1024)
                    break
    except (OSError, ValueError, IndexError):
        pass
    if not known:
        try:
            known.append(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
        except (ValueError, OSError, AttributeError):
            pass
    try:
        with open("/sys/fs/cgroup/memory.max") as f:
            limit = f.read().strip()
        if limit.isdigit():
            with open("/sys/fs/cgroup/memory.current") as f:
                known.append(max(0, int(limit) - int(f.read().strip())))
    except (OSError, ValueError):
        pass
    return min(known) if known else None


def gib(nbytes: int) -> str:
    """`nbytes` in GiB, as a message shows it: 21.8, 0.004."""
    g = nbytes / _GIB
    return f"{g:,.1f}" if g >= 1 else f"{g:.2g}"


def number(value: Any) -> str:
    """A number as a message shows it: `-1` for -1.0, `0.3`, `nan`, `inf`."""
    v = value.item() if isinstance(value, np.generic) else value
    if isinstance(v, float):
        if math.isfinite(v) and v.is_integer() and abs(v) < 1e15:
            return str(int(v))
        return repr(v)
    return str(v)


def shown(value: Any) -> str:
    """An attribute's value as a message shows it: `'fast'` (a string), `0.01`, `[1, 2]`."""
    if isinstance(value, bytes):
        value = value.decode("utf-8", "replace")
    if isinstance(value, str):
        return repr(value)
    a = np.asarray(value)
    if a.ndim == 0 and a.dtype.kind in "iuf":
        return number(a[()])
    text = repr(a.tolist())
    return text if len(text) <= 80 else text[:77] + "..."


def dtype_problem(dtype: np.dtype, integer: bool = False) -> str | None:
    """What a dataset of `dtype` holds when that is not real numbers (integers when
    `integer`): `"strings"`, `"complex numbers (complex128)"`, ...; `None` when it is."""
    import h5py

    if dtype.kind in "SU" or h5py.check_string_dtype(dtype) is not None:
        return "strings"
    if h5py.check_vlen_dtype(dtype) is not None:
        return "variable-length sequences"
    if dtype.kind == "c":
        return f"complex numbers ({dtype})"
    if dtype.kind == "b":
        return "booleans"
    if dtype.kind in "iu":
        return None
    if dtype.kind == "f":
        return f"floating-point numbers ({dtype})" if integer else None
    if dtype.names:
        return f"compound records ({dtype})"
    return f"values of type {dtype}"


def first_non_finite(a: np.ndarray) -> tuple[int, ...] | None:
    """The index of the first NaN or ±inf in `a` (C order), `None` when there is none."""
    if a.dtype.kind != "f" or a.size == 0:
        return None
    ok = np.isfinite(a)
    if ok.all():
        return None
    return tuple(int(i) for i in np.unravel_index(int(np.argmin(ok)), a.shape))
