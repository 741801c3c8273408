"""A check of an HDF5 file's global heap collections before the HDF5 library reads them.

Variable-length strings (the H5MD `unit` attributes, a checkpoint's names) live in global
heap collections ("GCOL", HDF5 file format spec, section III.E). The library walks a
collection's objects when it first reads one of its strings (`H5HG__cache_heap_deserialize`):

    p = start + header;  while p < end: idx, size = object header at p
                                        p += (idx > 0) ? align8(header + size) : size

An object of index 0 (the free space) whose size is 0 leaves p where it is, and the library
loops forever, inside one C call that neither Ctrl-C nor a timeout in Python can stop. One
damaged byte makes such a header (the fuzz suite's survey found it: byte 5547 of a small
trajectory set to 0). This module walks each collection the same way, beforehand, and names
the first one that would not end.

Collections are found by their signature, "GCOL" then version 1 and three zero bytes and a size
of at least 4096 bytes (H5HG_MINSIZE) that fits the file; a false match inside other data would
need all of that and then an empty free-space header, so a good file is not refused in practice.
"""

from __future__ import annotations

import mmap
from pathlib import Path

_SIGNATURE = b"\x89HDF\r\n\x1a\n"
_GCOL = b"GCOL"
_MIN_SIZE = 4096  # H5HG_MINSIZE: a collection is at least this large


def _align8(n: int) -> int:
    return (n + 7) & ~7


def _sizeof_lengths(data: mmap.mmap | bytes) -> int | None:
    """The file's "size of lengths" (bytes) from its superblock, which is at byte 0 or 512,
    1024, 2048, ... (after a user block); None where there is none."""
    at = 0
    while at + 16 <= len(data):
        if data[at : at + 8] == _SIGNATURE:
            version = data[at + 8]
            size = data[at + 14] if version in (0, 1) else data[at + 10]
            return size if size in (2, 4, 8, 16) else None
        at = 512 if at == 0 else 2 * at
    return None


def global_heap_problem(path: Path) -> str | None:
    """Where a global heap collection of the HDF5 file `path` would make the HDF5 library
    loop forever (an object of index 0 and size 0 in its walk), in words; None where none
    would (or the file is not HDF5: the library says so itself)."""
    with open(path, "rb") as fh:
        if fh.seek(0, 2) < 16:
            return None
        with mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) as data:
            lengths = _sizeof_lengths(data)
            if lengths is None:
                return None
            header = _align8(4 + 1 + 3 + lengths)  # H5HG_SIZEOF_HDR
            object_header = 2 + 2 + 4 + lengths  # H5HG_SIZEOF_OBJHDR
            start = data.find(_GCOL)
            while start >= 0:
                if start + 8 + lengths > len(data):  # (a signature in the last bytes of a cut file)
                    break
                size = int.from_bytes(data[start + 8 : start + 8 + lengths], "little")
                if data[start + 4 : start + 8] == b"\x01\0\0\0" and _MIN_SIZE <= size <= len(data) - start:
                    end = start + size
                    p = start + header
                    while p < end and p + object_header <= end:
                        idx = int.from_bytes(data[p : p + 2], "little")
                        length = int.from_bytes(data[p + 8 : p + 8 + lengths], "little")
                        need = object_header + _align8(length) if idx > 0 else length
                        if need == 0:
                            return (
                                f"its global heap collection at byte {start} is damaged: the free-space object at byte {p} "
                                "has size 0 (the HDF5 library would loop on it forever)"
                            )
                        p += need
                start = data.find(_GCOL, start + 1)
    return None
