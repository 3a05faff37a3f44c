"""MATLAB 5 files of numeric matrices and cell arrays, read without scipy.

The GCFF datasets' files hold nothing else (``features``: a cell array of N×4 matrices,
``timestamp``, ``GTgroups``: cells of cells of row vectors, ``stride``, ``mdl``), and reading
them needs neither scipy's compiled reader nor the import of ``scipy.io``, which brings
``scipy.sparse`` with it (a tenth of a second of CPU time, more than the reading).
:func:`read_mat5` reads such a file exactly as ``scipy.io.loadmat(path, squeeze_me=False,
struct_as_record=True)`` does (the same names, dtypes in the file's storage type, shapes and
values), and gives up on anything else: another class (char, struct, sparse, object), complex,
logical or global matrices, big-endian files, sizes that do not add up, trailing bytes. The
caller then hands the file to scipy, whose answer, or error, stays what it was.

Format: The MathWorks' "MAT-File Format", Level 5: a 128-byte header, then data elements (an
8-byte tag, type and size, or a 4-byte "small data element" tag with at most 4 bytes of data;
data padded to 8 bytes); a variable is a miMATRIX element (array flags, dimensions, name,
data), possibly inside a miCOMPRESSED (zlib) element.
"""

from __future__ import annotations

import struct
import zlib
from typing import Any

import numpy as np

__all__ = ["read_mat5"]

_MI_INT8, _MI_INT32, _MI_UINT32, _MI_MATRIX, _MI_COMPRESSED = 1, 5, 6, 14, 15
# Storage types of numeric data -> their dtype (little-endian files only).
_NUMERIC = {
    1: "<i1",
    2: "<u1",
    3: "<i2",
    4: "<u2",
    5: "<i4",
    6: "<u4",
    7: "<f4",
    9: "<f8",
    12: "<i8",
    13: "<u8",
}
_MX_CELL = 1
_MX_NUMERIC = range(6, 16)  # mxDOUBLE_CLASS ... mxUINT64_CLASS
_LOGICAL, _GLOBAL, _COMPLEX = 1 << 9, 1 << 10, 1 << 11
_MAX_DEPTH = 16  # cells within cells: the datasets nest two deep
_HEADER_BYTES = 128
_VERSION_5_LITTLE_ENDIAN = b"\x00\x01IM"  # bytes 124-127: version 0x0100, written "IM"


class _Unread(Exception):
    """Something :func:`read_mat5` leaves to scipy."""


def read_mat5(data: bytes) -> dict[str, Any] | None:
    """The variables of a MATLAB 5 file's bytes, as ``scipy.io.loadmat`` gives them (its
    ``__header__``, ``__version__`` and ``__globals__`` too), or None where the file holds
    anything but numeric matrices and cell arrays of them, or is not well formed."""
    if len(data) < _HEADER_BYTES or 0 in data[:4] or data[124:128] != _VERSION_5_LITTLE_ENDIAN:
        return None
    found: dict[str, Any] = {
        "__header__": data[:116].strip(b" \t\n\000"),
        "__version__": "1.0",
        "__globals__": [],
    }
    position = _HEADER_BYTES
    try:
        while position < len(data):
            kind, size, start = _tag(data, position)
            if kind == _MI_COMPRESSED:
                inflater = zlib.decompressobj()
                element = inflater.decompress(data[start : start + size])
                if not inflater.eof or inflater.unused_data or start + size > len(data):
                    return None
                kind, inner, begin = _tag(element, 0)
                if begin != 8 or begin + inner != len(element):
                    return None
                name, value = _variable(element, kind, inner, begin)
            elif start == position + 8:
                name, value = _variable(data, kind, size, start)
            else:
                return None
            position = start + size
            if not name or name in found:
                return None
            found[name] = value
    except (_Unread, struct.error, zlib.error, ValueError, MemoryError):
        return None
    return found


def _tag(data: bytes, position: int) -> tuple[int, int, int]:
    """(type, bytes of data, where the data start) of the element at ``position``."""
    (word,) = struct.unpack_from("<I", data, position)
    if word >> 16:  # a small data element: type and size in one word, data in the next
        size = word >> 16
        if size > 4:
            raise _Unread
        return word & 0xFFFF, size, position + 4
    kind, size = struct.unpack_from("<II", data, position)
    return kind, size, position + 8


def _element(data: bytes, position: int, end: int) -> tuple[int, bytes, int]:
    """(type, data, position of the next element) of a sub-element ending before ``end``."""
    kind, size, start = _tag(data, position)
    stop = start + size
    following = position + 8 if start == position + 4 else stop + (-size % 8)
    if following > end:
        raise _Unread
    return kind, data[start:stop], following


def _variable(data: bytes, kind: int, size: int, start: int) -> tuple[str, Any]:
    """(name, value) of a top-level miMATRIX element of ``size`` bytes at ``start``."""
    if kind != _MI_MATRIX or size == 0:
        raise _Unread
    name, value = _matrix(data, start, start + size, depth=0)
    return name, value


def _matrix(data: bytes, position: int, end: int, *, depth: int) -> tuple[str, Any]:
    """(name, value) of the matrix whose array flags start at ``position``, filling the bytes
    to ``end`` exactly."""
    kind, flags, position = _element(data, position, end)
    if kind != _MI_UINT32 or len(flags) != 8:
        raise _Unread
    flags_class = struct.unpack("<I", flags[:4])[0]
    mclass = flags_class & 0xFF
    if flags_class & (_LOGICAL | _GLOBAL | _COMPLEX):
        raise _Unread
    kind, dims_bytes, position = _element(data, position, end)
    if kind != _MI_INT32 or len(dims_bytes) < 8 or len(dims_bytes) % 4:
        raise _Unread
    dims = struct.unpack(f"<{len(dims_bytes) // 4}i", dims_bytes)
    if min(dims) < 0:
        raise _Unread
    kind, name_bytes, position = _element(data, position, end)
    if kind != _MI_INT8:
        raise _Unread
    count = 1
    for extent in dims:
        count *= extent
    if mclass in _MX_NUMERIC:
        kind, values, position = _element(data, position, end)
        dtype = np.dtype(_NUMERIC.get(kind, "V0"))
        if dtype.itemsize == 0 or len(values) != count * dtype.itemsize:
            raise _Unread
        array = np.frombuffer(values, dtype=dtype).copy()
        value = array.reshape(dims[::-1]).T
    elif mclass == _MX_CELL and depth < _MAX_DEPTH:
        if count > (end - position) // 8:  # every cell takes an 8-byte tag at least
            raise _Unread
        cells = np.empty(count, dtype=object)
        for k in range(count):
            cells[k], position = _cell(data, position, end, depth=depth + 1)
        value = cells.reshape(dims[::-1]).T
    else:
        raise _Unread
    if position != end:
        raise _Unread
    return name_bytes.decode("latin1"), value


def _cell(data: bytes, position: int, end: int, *, depth: int) -> tuple[Any, int]:
    """(value, position of the next element) of one cell's miMATRIX element."""
    kind, size, start = _tag(data, position)
    if kind != _MI_MATRIX or start != position + 8 or start + size > end:
        raise _Unread
    if size == 0:  # an empty matrix, written as a bare tag
        return np.array([[]]), start
    _, value = _matrix(data, start, start + size, depth=depth)
    return value, start + size
