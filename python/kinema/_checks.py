"""Strict checks of values handed to the public API (private).

Every public entry point (``World``, its methods, the forces and the colliders) passes its
arguments through these functions before they reach the engine, so that nothing is silently
coerced: a string is not a bool, a float is not a particle index, a complex number is not a
coordinate. A refused value raises

- ``TypeError`` for a value of the wrong type (``ccd='no'``, ``i=0.9``, complex positions), and
- ``ValueError`` for a value of the right type but out of range (``dim=5``, ``i=-1``),

with a message of the project's form ``"<name> = <value> is invalid: <what is allowed>"``;
the value is written compactly (:func:`describe`). Finite-ness and the ranges of physical
quantities (masses > 0, restitution in [0, 1], ...) are checked by the engine, whose messages
have the same form.

Accepted as real numbers: Python ``int`` and ``float``, NumPy integer and floating scalars and
arrays of those dtypes (``float32`` included), and lists or object arrays holding them. Refused:
bools (``True`` is not the number 1 here), complex numbers, ``datetime64``/``timedelta64``,
strings, bytes, ``None`` (where not documented) and anything else.
"""

from __future__ import annotations

import numbers
import re
import reprlib
from typing import Any

import numpy as np

SPECIES_PATTERN = r"[A-Za-z0-9_.+-]+"  # a species name: one word, as every export's reader takes it
INT64_MAX = 2**63 - 1
UINT64_MAX = 2**64 - 1

_REPR = reprlib.Repr()
_REPR.maxlevel = 3
_REPR.maxlist = _REPR.maxtuple = _REPR.maxset = _REPR.maxdict = 6
_REPR.maxstring = 40
_REPR.maxlong = 20
_REPR.maxother = 60


# -- describing values ----------------------------------------------------------------------
def describe(value: Any) -> str:
    """A compact text for ``value`` in an error message: numbers as written (a float by its
    shortest repr, a huge int in scientific notation, never hundreds of digits), strings by
    repr (shortened), arrays and lists shortened to a few elements."""
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    if isinstance(value, (np.datetime64, np.timedelta64)):  # before np.integer: timedelta64 is one
        return repr(value)
    if isinstance(value, (int, np.integer)):
        return _int_text(int(value))
    if isinstance(value, float):
        return repr(float(value))
    if isinstance(value, np.floating):
        return str(value)  # numpy's shortest repr for its precision: float32(0.1) -> 0.1
    if isinstance(value, np.ndarray):
        with np.printoptions(threshold=6, edgeitems=2, precision=6, linewidth=10**6):
            text = " ".join(repr(value).split())
        return _shorten(text, 120)
    if isinstance(value, np.complexfloating):
        return str(value)  # 1j, (1+2j)
    if isinstance(value, (np.str_, np.bytes_)):
        return _shorten(repr(value.item()), 80)
    if isinstance(value, np.generic):  # datetime64, timedelta64, ...
        return _shorten(repr(value), 80)
    try:
        return _shorten(_REPR.repr(value), 120)
    except ValueError:  # an int in a list too long for str()
        return f"a {type(value).__name__}"


def _int_text(v: int) -> str:
    if abs(v) < 10**15:
        return str(v)
    try:
        return f"{v:.6g}"
    except OverflowError:  # beyond a float: say how long it is instead of printing it
        return f"an integer of {int(abs(v).bit_length() * 0.30103) + 1} digits"


def _shorten(text: str, limit: int) -> str:
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _type_words(x: Any) -> str:
    """What ``x`` is, in a user's words ("a string", "a complex number", ...)."""
    if x is None:
        return "None"
    if isinstance(x, (bool, np.bool_)):
        return "a bool"
    if isinstance(x, (str, np.str_)):
        return "a string"
    if isinstance(x, (bytes, np.bytes_)):
        return "bytes"
    if isinstance(x, (complex, np.complexfloating)):
        return "a complex number"
    if isinstance(x, np.datetime64):
        return "a datetime64"
    if isinstance(x, np.timedelta64):
        return "a timedelta64"
    if isinstance(x, numbers.Integral):
        return "an int"
    if isinstance(x, numbers.Real):
        return "a float"
    if isinstance(x, np.ndarray):
        return f"an array of shape {x.shape}"
    return f"a {type(x).__name__}"


def _dtype_words(dtype: np.dtype) -> str:
    """What an array of ``dtype`` holds, in a user's words."""
    return {
        "b": "bools",
        "i": "integers",
        "u": "integers",
        "f": "floats",
        "c": f"complex numbers ({dtype})",
        "M": f"dates ({dtype})",
        "m": f"time spans ({dtype})",
        "U": "strings",
        "S": "bytes",
        "O": "Python objects",
        "V": f"records ({dtype})",
    }.get(dtype.kind, str(dtype))


def _at(name: str, index: tuple[int, ...]) -> str:
    return name + "".join(f"[{k}]" for k in index)


def _fail(exc: type[Exception], name: str, value: Any, allowed: str) -> Exception:
    return exc(f"{name} = {describe(value)} is invalid: {allowed}")


def _scalar(value: Any) -> Any:
    """A 0-d array as its element (a NumPy scalar); anything else unchanged."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        return value[()]
    return value


_NOT_NUMBERS = (bool, np.bool_, np.datetime64, np.timedelta64)  # NumPy counts timedelta64 as an integer


def _is_real(x: Any) -> bool:
    return isinstance(x, numbers.Real) and not isinstance(x, _NOT_NUMBERS)


def _is_integer(x: Any) -> bool:
    return isinstance(x, numbers.Integral) and not isinstance(x, _NOT_NUMBERS)


def _as_array(name: str, value: Any) -> np.ndarray:
    """``np.asarray(value)``, with a ragged nested list refused by name."""
    if isinstance(value, np.ndarray):
        return value
    try:
        return np.asarray(value)
    except ValueError:
        raise _fail(ValueError, name, value, "its rows have different lengths; it must be a rectangular array") from None


def _objects(value: Any) -> np.ndarray:
    """``value`` as an object array of its elements as given (Python ints stay exact)."""
    if isinstance(value, np.ndarray) and value.dtype.kind == "O":
        return value
    return np.asarray(value, dtype=object)


def _first_bad(name: str, obj: np.ndarray, ok: Any) -> tuple[str, Any] | None:
    """The first element of the object array ``obj`` that fails ``ok``, as ``(its name with
    indices, the element)``, or None. ``ok`` must depend on the element's type only (one
    element of each type is tried before the elements are walked one by one)."""
    flat = obj.ravel().tolist()
    types = set(map(type, flat))
    if all(ok(next(x for x in flat if type(x) is t)) for t in types):
        return None
    for idx, x in np.ndenumerate(obj):
        if not ok(x):
            return _at(name, idx) if obj.ndim else name, x
    return None  # pragma: no cover - a type failed above, so one element fails


# -- scalars --------------------------------------------------------------------------------
def boolean(name: str, value: Any) -> bool:
    """``value`` as a bool: only ``True``/``False`` (or a NumPy bool) are accepted; a string
    (``'no'``), a number (``0``, ``1``) or ``None`` is a ``TypeError``."""
    value = _scalar(value)
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    raise _fail(TypeError, name, value, f"it must be True or False (a bool), not {_type_words(value)}")


def real(name: str, value: Any, *, optional: bool = False) -> float | None:
    """``value`` as a float: a Python or NumPy int or float (a 0-d array too); ``None`` when
    ``optional``. A bool, a complex number, a string, a list or an array of several values is
    a ``TypeError``; an int too large for a float a ``ValueError``. Finite-ness and ranges are
    the caller's (the engine's) to check."""
    if value is None and optional:
        return None
    value = _scalar(value)
    if not _is_real(value):
        also = " or None" if optional else ""
        raise _fail(TypeError, name, value, f"it must be a real number (int or float){also}, not {_type_words(value)}")
    try:
        return float(value)
    except OverflowError:
        raise _fail(ValueError, name, value, "it is too large for a float (at most 1.79769e+308)") from None


def integer(name: str, value: Any, lo: int | None = None, hi: int | None = None, what: str | None = None) -> int:
    """``value`` as an int in [lo, hi] (a bound of None is open): a Python int or a NumPy
    integer. A float (even 3.0), a bool or a string is a ``TypeError``; a value outside the
    bounds a ``ValueError`` that states ``what`` is allowed (default: the bounds)."""
    value = _scalar(value)
    if not _is_integer(value):
        raise _fail(TypeError, name, value, f"it must be an integer (int), not {_type_words(value)}")
    v = int(value)
    if (lo is not None and v < lo) or (hi is not None and v > hi):
        if what is None:
            if lo is not None and hi is not None:
                what = f"it must be an integer from {_int_text(lo)} to {_int_text(hi)}"
            elif lo is not None:
                what = f"it must be an integer >= {_int_text(lo)}"
            else:
                what = f"it must be an integer <= {_int_text(hi)}"  # type: ignore[arg-type]
        raise _fail(ValueError, name, v, what)
    return v


def index(name: str, value: Any, n: int | None = None) -> int:
    """``value`` as a particle index: an int or a NumPy integer (not a bool, not a float),
    >= 0 and, when ``n`` (the number of particles) is given, < n."""
    value = _scalar(value)
    if not _is_integer(value):
        raise _fail(TypeError, name, value, f"particle indices must be integers (int or a NumPy integer), not {_type_words(value)}")
    v = int(value)
    if v < 0:
        raise _fail(ValueError, name, v, "particle indices must be >= 0")
    if n is not None and v >= n:
        raise _fail(ValueError, name, v, f"there are {n} particles (indices 0..{n - 1})")
    if v > INT64_MAX:
        raise _fail(ValueError, name, v, f"particle indices must be < {_int_text(INT64_MAX + 1)}")
    return v


def species(name: str, value: Any) -> str:
    """``value`` as a species name: a string (else ``TypeError``) of one word of letters,
    digits and ``_ . + -`` (else ``ValueError``)."""
    value = text(name, value)
    if not re.fullmatch(SPECIES_PATTERN, value):
        raise ValueError(f"{name} = {value!r} is invalid: a species name is one word of letters, digits and _ . + -")
    return value


def text(name: str, value: Any) -> str:
    """``value`` as a str (a NumPy string too); anything else is a ``TypeError``."""
    if isinstance(value, str):
        return str(value)
    raise _fail(TypeError, name, value, f"it must be a string, not {_type_words(value)}")


# -- arrays ---------------------------------------------------------------------------------
def real_array(name: str, value: Any, shape: tuple[int | None, ...] | None = None, *, none_is_nan: bool = False) -> np.ndarray:
    """``value`` as a float64 array (``value`` itself when it is one already).

    Accepted: a real number, a (nested) list of them, an array of an integer or floating
    dtype (``float32``, ``int64``, ...) or an object array holding real numbers. Refused with a
    ``TypeError`` that names the first bad element (``position[0][2] = 1j``) or the array's
    dtype: bools (also one hidden in a list of numbers), complex numbers,
    ``datetime64``/``timedelta64``, strings, bytes, ``None`` (with ``none_is_nan``, ``None``
    elements become NaN) and any other object. A ragged list is a ``ValueError``, and so is a
    shape other than ``shape`` when given (None: any length on that axis).
    """
    arr = _as_array(name, value)
    kind = arr.dtype.kind
    given = isinstance(value, np.ndarray)
    if given and kind not in "iufO":
        raise _fail(TypeError, name, value, f"it must hold real numbers (int or float), not {_dtype_words(arr.dtype)}")
    if kind == "O" or (not given and (kind not in "iuf" or _has_zero_or_one(arr))):
        # walk the elements as given: a list may hide bools among numbers ([0, True, 2])
        bad = _first_bad(name, _objects(value), lambda x: _is_real(x) or (none_is_nan and x is None))
        if bad is not None:
            also = " or None" if none_is_nan else ""
            raise _fail(TypeError, bad[0], bad[1], f"it must be a real number (int or float){also}, not {_type_words(bad[1])}")
    try:
        if arr.dtype.kind == "O":  # real numbers (and None) as Python objects: huge ints, Fractions
            out = np.array([np.nan if x is None else float(x) for x in arr.ravel().tolist()], dtype=np.float64).reshape(arr.shape)
        else:
            out = np.asarray(arr, dtype=np.float64)
    except OverflowError:
        raise _fail(ValueError, name, value, "it holds a number too large for a float (at most 1.79769e+308)") from None
    if shape is not None:
        check_shape(name, out, shape)
    return out


def complex_array(name: str, value: Any) -> np.ndarray:
    """``value`` as a complex128 array: as :func:`real_array`, with complex numbers (and a
    complex dtype) accepted too. Bools, strings, ``None``, ``datetime64`` and other objects
    are a ``TypeError`` naming the first bad element; a number beyond a float a ``ValueError``."""
    arr = _as_array(name, value)
    kind = arr.dtype.kind
    given = isinstance(value, np.ndarray)
    if given and kind not in "iufcO":
        raise _fail(TypeError, name, value, f"it must hold numbers (int, float or complex), not {_dtype_words(arr.dtype)}")
    if kind == "O" or (not given and (kind not in "iufc" or _has_zero_or_one(arr))):
        bad = _first_bad(name, _objects(value), lambda x: isinstance(x, numbers.Complex) and not isinstance(x, _NOT_NUMBERS))
        if bad is not None:
            raise _fail(TypeError, bad[0], bad[1], f"it must be a number (int, float or complex), not {_type_words(bad[1])}")
    try:
        if arr.dtype.kind == "O":
            return np.array([complex(x) for x in arr.ravel().tolist()], dtype=np.complex128).reshape(arr.shape)
        return np.asarray(arr, dtype=np.complex128)
    except OverflowError:
        raise _fail(ValueError, name, value, "it holds a number too large for a float (at most 1.79769e+308)") from None


def _has_zero_or_one(arr: np.ndarray) -> bool:
    """Whether a number array converted from a list holds a 0 or a 1 (where a bool may hide)."""
    return bool(arr.size) and bool(((arr == 0) | (arr == 1)).any())


def bool_array(name: str, value: Any) -> np.ndarray:
    """``value`` as a bool array (``value`` itself when it is one): ``True``/``False``, a
    list of them or an array of the bool dtype. Anything else (``'no'``, ``[0, 1]``, ``None``
    elements, an int array) is a ``TypeError`` naming the first bad element or the array's
    dtype. An empty list is an empty bool array."""
    arr = _as_array(name, value)
    if arr.dtype.kind == "b":
        return arr
    if arr.size == 0:
        return np.zeros(arr.shape, dtype=bool)
    allowed = "it must be True or False (a bool)"
    if isinstance(value, np.ndarray) and arr.dtype.kind != "O":
        raise _fail(TypeError, name, value, f"{allowed} or an array of bools, not an array of {_dtype_words(arr.dtype)}")
    obj = _objects(value)
    bad = _first_bad(name, obj, lambda x: isinstance(x, (bool, np.bool_)))
    if bad is not None:
        raise _fail(TypeError, bad[0], bad[1], f"{allowed}, not {_type_words(bad[1])}")
    return np.array([bool(x) for x in obj.ravel().tolist()], dtype=bool).reshape(obj.shape)


def index_array(name: str, value: Any, n: int | None = None) -> np.ndarray:
    """``value`` (one index or a 1-D list/array of them) as a 1-D int64 array of particle
    indices. Integers only (Python ints, NumPy integers, integer dtypes): a bool, a float (even
    2.0) or a string is a ``TypeError`` naming the element; a negative index, one beyond int64
    or, when ``n`` (the number of particles) is given, one >= n is a ``ValueError``. An empty
    list is an empty index array."""
    arr = _as_array(name, value)
    if arr.ndim > 1:
        raise ValueError(f"{name} has shape {arr.shape}; it must be one index or a 1-D list of indices")
    if arr.size == 0:
        return np.zeros(0, dtype=np.int64)

    def at(k: int) -> str:
        return name if arr.ndim == 0 else f"{name}[{k}]"

    kind = arr.dtype.kind
    given = isinstance(value, np.ndarray)
    allowed = "particle indices must be integers (int or a NumPy integer)"
    if given and kind not in "iuO":
        raise _fail(TypeError, name, value, f"{allowed}, not {_dtype_words(arr.dtype)}")
    if kind in "iu" and (given or not _has_zero_or_one(arr)):
        flat = arr.reshape(-1)
        if kind == "u" and int(flat.max()) > INT64_MAX:
            k = int(np.argmax(flat))
            index(at(k), int(flat[k]))  # raises: beyond int64
        out = flat.astype(np.int64, copy=False)
    else:  # a list (or object array) walked element by element: Python ints stay exact
        obj = _objects(value)
        bad = _first_bad(name, obj, _is_integer)
        if bad is not None:
            raise _fail(TypeError, bad[0], bad[1], f"{allowed}, not {_type_words(bad[1])}")
        values = [int(x) for x in obj.reshape(-1).tolist()]
        for k, v in enumerate(values):
            if not 0 <= v <= INT64_MAX:
                index(at(k), v)  # raises: negative or beyond int64
        out = np.array(values, dtype=np.int64)
    neg = np.flatnonzero(out < 0)
    if neg.size:
        k = int(neg[0])
        raise _fail(ValueError, at(k), int(out[k]), "particle indices must be >= 0")
    if n is not None and out.size and int(out.max()) >= n:
        k = int(np.argmax(out >= n))
        raise _fail(ValueError, at(k), int(out[k]), f"there are {n} particles (indices 0..{n - 1})")
    return out


def check_shape(name: str, arr: np.ndarray, shape: tuple[int | None, ...]) -> None:
    """A ``ValueError`` unless ``arr.shape`` matches ``shape`` (None: any length on that axis)."""
    if arr.ndim != len(shape) or any(s is not None and s != a for s, a in zip(shape, arr.shape, strict=False)):
        want = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"
        raise ValueError(f"{name} has shape {arr.shape}; it must be {want}")


def broadcast(name: str, arr: np.ndarray, shape: tuple[int, ...], what: str) -> np.ndarray:
    """``arr`` broadcast to ``shape``; a ``ValueError`` naming ``name``, its shape and ``what``
    is allowed (e.g. "a scalar or one value per particle, (4,)") otherwise."""
    try:
        return np.broadcast_to(arr, shape)
    except ValueError:
        raise ValueError(f"{name} has shape {arr.shape}; it must be {what}") from None


GROUPS = 32  # collision groups: a group is a bit of a 32-bit mask (kinema::collide::GROUPS)


def groups(name: str, value: Any, n: int | None = None) -> np.ndarray:
    """``value`` as collision groups: one integer in 0..31, or a 1-D list/array of them (with
    ``n``: a scalar is broadcast to (n,), and a list must have n). Integers only (a float, a bool
    or a string is a ``TypeError`` naming the element); outside 0..31 a ``ValueError`` naming it."""
    arr = _as_array(name, value)
    if n is not None and arr.ndim == 1 and arr.shape != (n,):
        raise ValueError(f"{name} has shape {arr.shape}; it must be a group (an integer in 0..{GROUPS - 1}) or one per particle, ({n},)")
    if arr.ndim > 1:
        raise ValueError(f"{name} has shape {arr.shape}; it must be a group (an integer in 0..{GROUPS - 1}) or a 1-D list of them")
    obj = _objects(value) if not (isinstance(value, np.ndarray) and value.dtype.kind in "iu") else arr
    if obj.dtype.kind not in "iu":
        if isinstance(value, np.ndarray) and value.dtype.kind not in "O":
            raise _fail(TypeError, name, value, f"collision groups are integers in 0..{GROUPS - 1}, not {_dtype_words(arr.dtype)}")
        bad = _first_bad(name, obj, _is_integer)
        if bad is not None:
            raise _fail(TypeError, bad[0], bad[1], f"a collision group is an integer in 0..{GROUPS - 1}, not {_type_words(bad[1])}")
    values = [int(x) for x in np.asarray(obj).reshape(-1).tolist()]
    for k, v in enumerate(values):
        if not 0 <= v < GROUPS:
            at = name if arr.ndim == 0 else f"{name}[{k}]"
            raise ValueError(f"{at} = {v} is invalid: a collision group is an integer in 0..{GROUPS - 1} (a bit of a 32-bit mask)")
    out = np.array(values, dtype=np.int64).reshape(arr.shape)
    return np.broadcast_to(out, (n,)).copy() if n is not None and out.ndim == 0 else out


def group_mask(name: str, value: Any) -> int:
    """``value`` (None: every group; else a group or a list of groups, 0..31) as a 32-bit mask."""
    if value is None:
        return (1 << GROUPS) - 1
    mask = 0
    for g in groups(name, value).reshape(-1).tolist():
        mask |= 1 << g
    return mask


def mask_groups(mask: int) -> list[int] | None:
    """The groups of a 32-bit mask (None for every group): :func:`group_mask`'s inverse."""
    if mask == (1 << GROUPS) - 1:
        return None
    return [g for g in range(GROUPS) if mask >> g & 1]
