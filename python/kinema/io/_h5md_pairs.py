"""What an H5MD file holds of pairs of particles, named by their ids (for
`kinema.io.h5md_reader`): the springs (`/connectivity/springs`, H5MD's list of pairs) and the
contacts of each frame (`/contacts`, kinema's extension group): their datasets found and
checked before any data is read (`_contact_datasets`), then read and checked
(`_read_springs`, `_read_contacts`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..contact_record import FIELDS, ContactRecord, offsets_problem
from ._h5md_checks import Reader, where
from ._h5md_layout import import_h5py
from .h5md_units import parse_unit, to_si


def _read_springs(r: Reader, f: Any, p: Any, ids: np.ndarray) -> np.ndarray | None:
    """The springs (S, 2) ids of `/connectivity/springs` (kinema's: H5MD's time-independent
    list of pairs, whose `particles_group` is the particle group read), `None` without
    them."""
    h5py = import_h5py()
    ds = f.get("connectivity/springs")
    if not isinstance(ds, h5py.Dataset):
        return None
    ref = ds.attrs.get("particles_group")
    if isinstance(ref, h5py.Reference) and ref and f[ref].name != p.name:
        return None  # the springs of another particle group
    s = r.numbers("springs", ds, integer=True)
    if len(s) != 2 or s[1] != 2:
        raise r.fail(f"{where('springs', ds)} has shape {s}; it must be (springs, 2), the ids of the two ends of each spring")
    pairs = np.asarray(ds[()], dtype=np.int64)
    unknown = np.setdiff1d(pairs, ids)
    if unknown.size:
        raise r.fail(f"{where('springs', ds)} names id {int(unknown[0])}, which is no particle's ({p.name}/id)")
    return pairs


def _contact_datasets(r: Reader, f: Any, p: Any) -> dict[str, Any] | None:
    """The datasets of `/contacts` (kinema's extension group: the contacts of each frame)
    whose `particles_group` is the group read, with their units, checked before any data is
    read: `offsets` (F + 1,) integers and one column per `FIELDS` name of as many rows as
    the last offset (read later); `None` without them."""
    h5py = import_h5py()
    g = f.get("contacts")
    if not isinstance(g, h5py.Group):
        return None
    ref = g.attrs.get("particles_group")
    if isinstance(ref, h5py.Reference) and ref and f[ref].name != p.name:
        return None  # the contacts of another particle group
    out: dict[str, Any] = {}
    for name in g:
        ds = g[name]
        if name in ("step", "time"):
            continue
        known = FIELDS.get(name)
        if name != "offsets" and known is None:
            raise r.fail(f"{ds.name} is not a column of kinema's contacts ({', '.join(['offsets', *FIELDS])})")
        if not isinstance(ds, h5py.Dataset):
            raise r.fail(f"{ds.name} is a group; it must be a dataset")
        if known is not None and known.kind == "bool":
            if ds.shape is None or ds.dtype.kind != "b":
                raise r.fail(f"{where(name, ds)} holds {ds.dtype}; it must hold flags (bool), one per contact")
            shape = tuple(ds.shape)
        else:
            shape = r.numbers(name, ds, integer=name == "offsets" or (known is not None and known.kind == "int"))
        if known is not None and known.unit is not None:
            out[("unit", name)] = r.unit(name, ds, parse_unit(known.unit)[1])
        r.plan(name, ds, ds.size * 8)
        out[name] = (ds, shape)
    if "offsets" not in out:
        raise r.fail(f"{g.name} has no offsets dataset (frame k's contacts are rows offsets[k] to offsets[k + 1])")
    return out


def _read_contacts(r: Reader, found: dict[str, Any], frames: int, ids: np.ndarray) -> ContactRecord:
    """The contacts of `_contact_datasets`, read and checked: `offsets` one per frame and
    one more, from 0, never decreasing; each column as many rows as the last offset, finite
    or NaN (a column a frame did not have); `i` and `j` ids of the particles read (`j` -1:
    a collider)."""
    ds, shape = found["offsets"]
    if shape != (frames + 1,):
        raise r.fail(f"{where('offsets', ds)} has shape {shape}; it must be ({frames + 1},), one per frame and one more")
    offsets = np.asarray(ds[()], dtype=np.int64)
    problem = offsets_problem(offsets)
    if problem is not None:
        raise r.fail(f"{where('offsets', ds)} {problem}")
    total = int(offsets[-1])
    values = {}
    for name, entry in found.items():
        if name == "offsets" or isinstance(name, tuple):
            continue
        ds, shape = entry
        if not shape or shape[0] != total or len(shape) > 2:
            raise r.fail(f"{where(name, ds)} has shape {shape}; it must have {total} rows, one per contact ({where('offsets', found['offsets'][0])}[-1])")
        a = ds[()]
        if ("unit", name) in found:
            a = to_si(a, found[("unit", name)])
        if FIELDS[name].kind == "real" and np.isinf(a).any():
            raise r.fail(f"{where(name, ds)} has an infinite value at row {int(np.argmax(np.isinf(a).reshape(len(a), -1).any(axis=1)))}")
        values[name] = a
    try:
        record = ContactRecord(offsets, values)
    except ValueError as e:
        raise r.fail(f"{found['offsets'][0].parent.name}: {e}") from None
    for name in ("i", "j"):
        known = np.isin(record[name], ids) | ((record[name] == -1) if name == "j" else False)
        if not known.all():
            k = int(np.argmax(~known))
            raise r.fail(f"{where(name, found[name][0])} names particle {int(record[name][k])} at row {k}, which is no particle's id")
    return record
