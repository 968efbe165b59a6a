"""Binary model files: what the native FMUs (and the C core) read, written by the Python trainer.

A small self-describing little-endian container of named float64 arrays (the C reader is
``sarins_fmu/core/netfile.c``; the layout is documented in ``netfile.h`` and here):

======  =====  ==============================================================
offset  bytes  field
======  =====  ==============================================================
0       8      magic ``b"SARNET\\x00\\x01"``
8       4      format version (:data:`VERSION`)
12      4      model kind (:data:`KINDS`)
16      8      total size of the file in bytes, checksum included
24      4      number of arrays (1 .. :data:`MAX_ARRAYS`)
28      4      reserved, 0
32      ...    per array: 32-byte name (``[a-z0-9_.]``, NUL-padded), ndim (u32,
               0 .. 2), reserved u32, dim 0 and dim 1 (u64, 1 when absent),
               then the elements (float64, row-major)
total-8 8      FNV-1a 64 checksum of every byte before it
======  =====  ==============================================================

Size budgets (the same in C): at most :data:`MAX_BYTES` bytes, :data:`MAX_ARRAYS` arrays and
:data:`MAX_ELEMENTS` elements per array.  The JSON and npz formats of :mod:`.modelfile` stay the
formats users keep; this one is exported from them (:func:`write`).
"""

from __future__ import annotations

import os
import re
import struct
from pathlib import Path

import numpy as np

from .modelfile import ModelFileError

MAGIC = b"SARNET\x00\x01"
VERSION = 1
HEADER = 32
ARRAY_HEADER = 56
NAME_BYTES = 32
MAX_ARRAYS = 64
MAX_BYTES = 64 << 20
MAX_ELEMENTS = 1 << 23
SUFFIX = ".bin"  # the file name ending the tools use for this format
KINDS = {"axial_rbf": 1, "traditional": 2, "rbf": 3, "grnn": 4, "lstm": 5, "gru": 6, "lstm3": 7, "gru3": 8, "rls": 9}
_NAME = re.compile(r"[a-z0-9_.]{1,31}")
_FNV_OFFSET, _FNV_PRIME, _MASK = 0xCBF29CE484222325, 0x100000001B3, (1 << 64) - 1


def checksum(data: bytes) -> int:
    """FNV-1a 64 of ``data``."""
    h = _FNV_OFFSET
    for byte in data:
        h = ((h ^ byte) * _FNV_PRIME) & _MASK
    return h


def _checksum_fast(data: bytes) -> int:
    # FNV-1a is sequential; numpy cannot vectorise it, so large files go through the C core's copy
    try:
        from sarins_fmu.core import nets
    except ImportError:
        return checksum(data)
    return nets.netfile_checksum(data)


def to_bytes(kind: str, arrays: dict) -> bytes:
    """The file's bytes for a model of ``kind`` (:data:`KINDS`) holding ``arrays`` ({name: array of 0 to 2
    dimensions}, converted to float64).  ValueError on a bad name, shape, kind or a budget exceeded."""
    if kind not in KINDS:
        raise ValueError(f"unknown model kind {kind!r}; known: {', '.join(KINDS)}")
    if not 1 <= len(arrays) <= MAX_ARRAYS:
        raise ValueError(f"{len(arrays)} arrays: a model file holds 1 .. {MAX_ARRAYS}")
    parts = []
    for name, value in arrays.items():
        if not _NAME.fullmatch(name):
            raise ValueError(f"array name {name!r}: 1 .. 31 characters of [a-z0-9_.]")
        a = np.asarray(value, dtype="<f8")  # tobytes() writes row-major whatever the memory order
        if a.ndim > 2 or a.size > MAX_ELEMENTS:
            raise ValueError(f"array {name}: shape {a.shape} (at most 2 dimensions and {MAX_ELEMENTS} elements)")
        dims = list(a.shape) + [1] * (2 - a.ndim)
        parts.append(name.encode("ascii").ljust(NAME_BYTES, b"\0") + struct.pack("<IIQQ", a.ndim, 0, *dims)
                     + a.tobytes())
    total = HEADER + sum(len(p) for p in parts) + 8
    if total > MAX_BYTES:
        raise ValueError(f"the model file would have {total} bytes, over the budget of {MAX_BYTES}")
    body = MAGIC + struct.pack("<IIQII", VERSION, KINDS[kind], total, len(parts), 0) + b"".join(parts)
    return body + struct.pack("<Q", _checksum_fast(body))


def write(path: str | Path, kind: str, arrays: dict) -> Path:
    """Write the model file (see :func:`to_bytes`) atomically; returns its path."""
    path = Path(path)
    data = to_bytes(kind, arrays)
    tmp = path.with_name(f"{path.name}.{os.getpid()}.tmp")  # one per process: parallel writers do not collide
    tmp.write_bytes(data)
    os.replace(tmp, path)
    return path


def from_bytes(data: bytes, source="<bytes>") -> tuple[str, dict]:
    """(kind, {name: array}) of a model file's bytes, with every check of the C reader; ModelFileError
    naming ``source`` and the reason."""
    def bad(reason):
        return ModelFileError(source, reason)

    n = len(data)
    if n < HEADER + 8 or data[:8] != MAGIC:
        raise bad(f"not a sarins binary model file (wrong magic or shorter than a header: {n} bytes)")
    version, kind_code, total, n_arrays, reserved = struct.unpack_from("<IIQII", data, 8)
    if version != VERSION:
        raise bad(f"format version {version}, this reader knows {VERSION}")
    if total > MAX_BYTES:
        raise bad(f"declared size {total} bytes is over the budget of {MAX_BYTES}")
    if total != n:
        raise bad(f"declared size {total} bytes, the data has {n} (truncated or padded)")
    if _checksum_fast(data[:-8]) != struct.unpack_from("<Q", data, n - 8)[0]:
        raise bad("checksum mismatch (the file is corrupt)")
    if not 1 <= n_arrays <= MAX_ARRAYS or reserved:
        raise bad(f"{n_arrays} arrays (1 .. {MAX_ARRAYS}) or a non-zero reserved field")
    kinds = {v: k for k, v in KINDS.items()}
    if kind_code not in kinds:
        raise bad(f"unknown model kind {kind_code}")
    pos, end, arrays = HEADER, n - 8, {}
    for k in range(n_arrays):
        if end - pos < ARRAY_HEADER:
            raise bad(f"array {k}: its header runs past the end of the data")
        raw = data[pos:pos + NAME_BYTES]
        name = raw.split(b"\0", 1)[0]
        if not name or len(name) == NAME_BYTES or raw[len(name):].strip(b"\0") or not _NAME.fullmatch(
                name.decode("latin-1")):
            raise bad(f"array {k}: a bad name")
        name = name.decode("ascii")
        ndim, res, d0, d1 = struct.unpack_from("<IIQQ", data, pos + NAME_BYTES)
        if ndim > 2 or res or (ndim < 2 and d1 != 1) or (ndim < 1 and d0 != 1):
            raise bad(f"array {name}: ndim {ndim} with shape ({d0}, {d1})")
        if d0 > MAX_ELEMENTS or d1 > MAX_ELEMENTS or d0 * d1 > MAX_ELEMENTS:
            raise bad(f"array {name}: shape ({d0}, {d1}) is over the budget of {MAX_ELEMENTS} elements")
        pos += ARRAY_HEADER
        count = d0 * d1
        if (end - pos) // 8 < count:
            raise bad(f"array {name}: {count} elements run past the end of the data")
        if name in arrays:
            raise bad(f"array {name} appears twice")
        a = np.frombuffer(data, dtype="<f8", count=count, offset=pos).astype(float)
        arrays[name] = a.reshape((d0, d1)[:ndim])
        pos += 8 * count
    if pos != end:
        raise bad(f"{end - pos} stray bytes after the last array")
    return kinds[kind_code], arrays


def read(path: str | Path) -> tuple[str, dict]:
    """(kind, arrays) of the model file at ``path`` (refused before reading when over :data:`MAX_BYTES`)."""
    path = Path(path)
    try:
        size = path.stat().st_size
        if size > MAX_BYTES:
            raise ModelFileError(path, f"{size} bytes is over the budget of {MAX_BYTES}")
        data = path.read_bytes()
    except OSError as exc:
        raise ModelFileError(path, f"cannot read it: {exc.strerror or exc}") from None
    return from_bytes(data, path)


def is_netfile(path: str | Path) -> bool:
    """True when the file starts with this format's magic."""
    try:
        with open(path, "rb") as fh:
            return fh.read(len(MAGIC)) == MAGIC
    except OSError:
        return False
