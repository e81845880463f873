"""The "tensor_file" container: named n-dimensional arrays in one little-endian file.

The format Mitsuba 3 reads (``src/core/tensor.cpp``, ``include/mitsuba/core/tensor.h``)
and writes (``mitsuba.tensor_io``); RGL ``.bsdf`` materials (Dupuy & Jakob 2018) are
such files. Layout, all integers little-endian::

    char[12]  magic       "tensor_file\\0"
    uint8[2]  version     1, 0
    uint32    n_fields
    n_fields times:
        uint16  name length, then that many bytes of UTF-8 name
        uint16  ndim
        uint8   dtype code (:data:`DTYPES`)
        uint64  offset of the field's data from the start of the file
        uint64  shape[ndim]
    field data, C order, each at its offset (the writer pads offsets to 8 bytes)

:func:`read_tensor_file` checks every claim of the header against the file's size
before it reads a byte of data, so a damaged or hostile header can neither make it
allocate more than the file holds nor read past its end: any defect is one
``ValueError`` line.
"""

from __future__ import annotations

import math
import os
import struct
from typing import Mapping

import numpy as np

MAGIC = b"tensor_file\0"
VERSION = (1, 0)
#: dtype code -> numpy dtype (little-endian), the codes of Mitsuba's ``Struct.Type``
DTYPES: dict[int, np.dtype] = {
    1: np.dtype("u1"), 2: np.dtype("i1"), 3: np.dtype("<u2"), 4: np.dtype("<i2"),
    5: np.dtype("<u4"), 6: np.dtype("<i4"), 7: np.dtype("<u8"), 8: np.dtype("<i8"),
    9: np.dtype("<f2"), 10: np.dtype("<f4"), 11: np.dtype("<f8"),
}
_CODES = {dt.newbyteorder("<"): code for code, dt in DTYPES.items()}
_PREAMBLE = len(MAGIC) + 2 + 4  # magic, version, field count
_MIN_FIELD_HEADER = 2 + 2 + 1 + 8  # name length, ndim, dtype, offset (empty name, no dims)


class _Cursor:
    """Reads little-endian integers from the header bytes, refusing to run past them."""

    def __init__(self, buf: bytes, path: str) -> None:
        self.buf, self.pos, self.path = buf, 0, path

    def take(self, n: int) -> bytes:
        if self.pos + n > len(self.buf):
            raise ValueError(f"{self.path}: truncated tensor_file header (needs byte {self.pos + n}, "
                             f"the file has {len(self.buf)})")
        out = self.buf[self.pos:self.pos + n]
        self.pos += n
        return out

    def unpack(self, fmt: str):
        vals = struct.unpack("<" + fmt, self.take(struct.calcsize("<" + fmt)))
        return vals if len(vals) > 1 else vals[0]


def _field_header(cur: _Cursor, size: int) -> tuple[str, np.dtype, int, tuple[int, ...]]:
    """(name, dtype, offset, shape) of the next field, each claim checked against the file size."""
    path = cur.path
    raw = cur.take(cur.unpack("H"))
    try:
        name = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise ValueError(f"{path}: a field name is not UTF-8 ({raw[:20]!r})") from None
    ndim, code, offset = cur.unpack("H"), cur.unpack("B"), cur.unpack("Q")
    if code not in DTYPES:
        raise ValueError(f"{path}: field {name!r} has unknown dtype code {code} (known: 1-11)")
    shape = tuple(cur.unpack("Q") for _ in range(ndim))
    dtype = DTYPES[code]
    nbytes = dtype.itemsize
    for n in shape:  # Python integers: no overflow, however absurd the claim
        nbytes *= n
    if offset > size or nbytes > size - offset:
        raise ValueError(f"{path}: field {name!r} claims {nbytes} bytes at offset {offset}, "
                         f"past the end of the {size}-byte file (truncated or damaged)")
    return name, dtype, offset, shape


def read_tensor_file(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """The fields of a tensor_file, name -> read-only array (little-endian dtype, C order).

    Raises a one-line ``ValueError`` for a missing or unreadable file, a wrong magic or
    version, a truncated header, an unknown dtype, a field that runs past the end of the
    file, or a name given twice. Memory used is bounded by the file's size.
    """
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise ValueError(f"{path}: no such file")
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as e:
        raise ValueError(f"{path}: cannot read: {e.strerror or e}") from None
    size = len(data)
    if size < _PREAMBLE:
        raise ValueError(f"{path}: {size} bytes, too short for a tensor_file header (is it a tensor_file?)")
    if data[:len(MAGIC)] != MAGIC:
        raise ValueError(f"{path}: not a tensor_file (the first 12 bytes are not 'tensor_file\\0')")
    cur = _Cursor(data, path)
    cur.take(len(MAGIC))
    version = cur.unpack("BB")
    if version != VERSION:
        raise ValueError(f"{path}: tensor_file version {version[0]}.{version[1]}, only 1.0 is known")
    n_fields = cur.unpack("I")
    if n_fields * _MIN_FIELD_HEADER > size - _PREAMBLE:
        raise ValueError(f"{path}: header claims {n_fields} fields, more than the {size}-byte file can hold")
    fields: dict[str, np.ndarray] = {}
    for _ in range(n_fields):
        name, dtype, offset, shape = _field_header(cur, size)
        if name in fields:
            raise ValueError(f"{path}: field {name!r} appears twice")
        count = math.prod(int(s) for s in shape)  # Python ints: a huge dimension beside a 0 cannot overflow
        arr = np.frombuffer(data, dtype=dtype, count=count, offset=offset).reshape(shape)
        fields[name] = arr
    return fields


def _as_field(name: str, value) -> np.ndarray:
    if isinstance(value, str):
        return np.frombuffer(value.encode("utf-8"), dtype=np.uint8)
    arr = np.asarray(value)
    le = arr.dtype.newbyteorder("<")
    if le not in _CODES:
        raise ValueError(f"tensor_file: field {name!r} has dtype {arr.dtype}, not one of "
                         "(u)int8/16/32/64, float16/32/64")
    return np.ascontiguousarray(arr, dtype=le)


def tensor_file_bytes(fields: Mapping[str, object], align: int = 8) -> bytes:
    """The bytes of a tensor_file holding ``fields`` (name -> array, or str stored as uint8 UTF-8)."""
    arrays = {str(k): _as_field(str(k), v) for k, v in fields.items()}
    head = [MAGIC, struct.pack("<BBI", *VERSION, len(arrays))]
    header_len = _PREAMBLE + sum(2 + len(k.encode("utf-8")) + 2 + 1 + 8 + 8 * a.ndim for k, a in arrays.items())
    offsets, pos = [], header_len
    for a in arrays.values():
        pos = (pos + align - 1) // align * align
        offsets.append(pos)
        pos += a.nbytes
    for (name, a), off in zip(arrays.items(), offsets):
        label = name.encode("utf-8")
        head.append(struct.pack("<H", len(label)) + label + struct.pack("<HBQ", a.ndim, _CODES[a.dtype], off))
        head.append(struct.pack("<" + "Q" * a.ndim, *a.shape))
    out = bytearray(b"".join(head))
    for a, off in zip(arrays.values(), offsets):
        out.extend(b"\0" * (off - len(out)))
        out.extend(a.tobytes())
    return bytes(out)


def write_tensor_file(path: str | os.PathLike, fields: Mapping[str, object], align: int = 8) -> None:
    """Write ``fields`` as a tensor_file, atomically (:mod:`brdfkit.fileio`); Mitsuba 3 reads the result."""
    from ..fileio import write_bytes

    write_bytes(path, tensor_file_bytes(fields, align))


__all__ = ["read_tensor_file", "write_tensor_file", "tensor_file_bytes", "DTYPES", "MAGIC", "VERSION"]
