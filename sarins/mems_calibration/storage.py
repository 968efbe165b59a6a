"""Seed 003's large arrays kept on disk between the campaign's phases and read back a chunk at a time.

The recordings stay in the campaign's stored results (``<out>/recordings/<id>.npz``) and are loaded one at a
time when a phase needs them (:class:`StoredRecordings`); the data sets the evaluation reads are written to
``<out>/datasets/<name>.{X,Y,time}.npy`` and read back ``rows`` at a time (:class:`StoredSet`), so the
campaign holds at most one recording, the training set while the models are fitted, and chunk-long
temporaries.  Reading never changes a number: the arrays are float64 as computed.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sarins_fmu.experiments.mems_calibration import Dataset

COLUMNS = ("X", "Y", "time")


# a stored recording's arrays larger than this (bytes) are read a slice at a time (:class:`StoredArray`)
LAZY_BYTES = 1 << 22
READ_ROWS = 1 << 16  # rows read at once when a stored array is hashed or read with a step


class StoredArray:
    """One array of an uncompressed ``.npz`` archive (``np.savez``, as :func:`sarins.results.save_result`
    writes), read from the file a slice of rows at a time: ``a[i:j]`` (any step) and ``a[i]`` return
    arrays read with plain file reads at the member's offset, so nothing stays mapped and only the rows
    asked for are in memory.  The bytes are those of ``np.load`` on the archive, bit for bit."""

    def __init__(self, path: Path, member: str):
        import struct
        import zipfile

        self.path = Path(path)
        with zipfile.ZipFile(self.path) as archive:
            info = archive.getinfo(member)
        if info.compress_type != zipfile.ZIP_STORED:
            raise ValueError(f"{self.path}: {member} is compressed; only stored members are read in place")
        with open(self.path, "rb") as fh:
            fh.seek(info.header_offset)
            local = fh.read(30)
            if local[:4] != b"PK\x03\x04":
                raise ValueError(f"{self.path}: {member} has no local file header")
            name_len, extra_len = struct.unpack("<HH", local[26:30])
            fh.seek(info.header_offset + 30 + name_len + extra_len)
            version = np.lib.format.read_magic(fh)
            read_header = (np.lib.format.read_array_header_1_0 if version == (1, 0)
                           else np.lib.format.read_array_header_2_0)
            shape, fortran, dtype = read_header(fh)
            self.offset = fh.tell()
        if fortran or dtype.hasobject:
            raise ValueError(f"{self.path}: {member} is not a C-ordered plain array")
        self.shape, self.dtype = tuple(shape), dtype
        self.row_items = int(np.prod(self.shape[1:], dtype=np.int64))
        self.ndim = len(self.shape)

    def __len__(self) -> int:
        return self.shape[0]

    @property
    def nbytes(self) -> int:
        return len(self) * self.row_items * self.dtype.itemsize

    def _rows(self, fh, a: int, b: int) -> np.ndarray:
        out = np.empty((max(0, b - a),) + self.shape[1:], self.dtype)
        fh.seek(self.offset + a * self.row_items * self.dtype.itemsize)
        if out.nbytes and fh.readinto(memoryview(out.reshape(-1).view(np.uint8))) != out.nbytes:
            raise ValueError(f"{self.path}: truncated array")
        return out

    def __getitem__(self, key):
        if isinstance(key, (int, np.integer)):
            i = int(key) + (len(self) if key < 0 else 0)
            if not 0 <= i < len(self):
                raise IndexError(key)
            return self[i:i + 1][0]
        if not isinstance(key, slice):
            raise TypeError("a stored array is read by row slices or single rows")
        a, b, step = key.indices(len(self))
        with open(self.path, "rb") as fh:
            if step == 1:
                return self._rows(fh, a, max(a, b))
            if step < 1:
                raise ValueError("a stored array is read with a positive step")
            parts = [self._rows(fh, i, min(i + READ_ROWS * step, b))[::step] for i in range(a, b, READ_ROWS * step)]
        return np.concatenate(parts) if parts else np.empty((0,) + self.shape[1:], self.dtype)

    def __array__(self, dtype=None, copy=None):
        whole = self[:]
        return whole if dtype is None else whole.astype(dtype)

    def blocks(self, rows: int = READ_ROWS):
        """Consecutive row blocks, in order (the whole array, ``rows`` at a time)."""
        with open(self.path, "rb") as fh:
            for a in range(0, len(self), int(rows)):
                yield self._rows(fh, a, min(a + int(rows), len(self)))


def open_recording(path) -> dict:
    """A stored recording (``<out>/recordings/<id>.npz``) as {key: array}: its arrays larger than
    :data:`LAZY_BYTES` with two or more dimensions as :class:`StoredArray` (read a slice at a time), the
    others in memory, scalars as Python numbers, as :func:`sarins.results.load_result` gives them.  Each
    array is checked against the archive's manifest (dtype, shape, SHA-256 of its bytes, hashed a block at a
    time) before it is returned, as ``load_result`` checks it."""
    import hashlib
    import json

    from sarins.results import HASH_KEY, KEYS_KEY, MANIFEST_KEY, RECORD_KEY, StoredResultError, _describe

    path = Path(path)
    with np.load(path, allow_pickle=False) as data:
        keys = [str(k) for k in data[KEYS_KEY]]
        manifest = json.loads(str(data[MANIFEST_KEY]))
        small = {}
        members = {}
        for key in keys:
            try:
                lazy = StoredArray(path, key + ".npy")
            except ValueError:  # compressed or Fortran-ordered (not what save_result writes): read whole
                lazy = None
            if lazy is not None and lazy.ndim >= 2 and lazy.nbytes > LAZY_BYTES:
                members[key] = lazy
            else:
                small[key] = data[key]
    reserved = {KEYS_KEY, MANIFEST_KEY, RECORD_KEY, HASH_KEY}
    if set(manifest) - reserved != set(keys):
        raise StoredResultError(f"{path}: its manifest does not list its arrays")
    out = {}
    for key in keys:
        if key in members:
            arr = members[key]
            digest = hashlib.sha256()
            for block in arr.blocks():
                digest.update(memoryview(block.reshape(-1).view(np.uint8)))
            found = [arr.dtype.str, list(arr.shape), digest.hexdigest()]
        else:
            arr = small[key]
            found = _describe(arr)
        if manifest[key] != found:
            raise StoredResultError(f"{path}: {key!r} differs from what was written")
        out[key] = arr.item() if isinstance(arr, np.ndarray) and arr.ndim == 0 else arr
    return out


class StoredRecordings(Mapping):
    """{recording id: stored result file} read as {id: recording dict}: each access loads (and checks) the
    file, and nothing is cached, so a caller holds only the recordings it keeps references to."""

    def __init__(self, paths: dict):
        self.paths = {k: Path(v) for k, v in paths.items()}

    def __getitem__(self, key: str) -> dict:
        from sarins.campaign import load_result

        return load_result(self.paths[key])

    def lazy(self, key: str) -> dict:
        """The recording ``key`` with its large arrays read from the file a slice at a time
        (:func:`open_recording`)."""
        return open_recording(self.paths[key])

    def __iter__(self):
        return iter(self.paths)

    def __len__(self) -> int:
        return len(self.paths)


@dataclass(frozen=True)
class StoredSet:
    """Rows ``start .. stop - 1`` of a data set stored by :func:`save_set` (inputs X (n, 7), targets Y (n, 6),
    times (n,) s, as :class:`~sarins_fmu.experiments.mems_calibration.Dataset`)."""

    folder: Path
    name: str
    start: int
    stop: int

    def path(self, column: str) -> Path:
        return Path(self.folder) / f"{self.name}.{column}.npy"

    def __len__(self) -> int:
        return self.stop - self.start

    def _read(self, column: str, a: int, b: int) -> np.ndarray:
        """Rows a .. b - 1 (relative to ``start``) of one column, copied out of a mapping that is closed at
        once (a mapping kept open would keep every page read in the resident set)."""
        mapped = np.load(self.path(column), mmap_mode="r")
        try:
            return np.array(mapped[self.start + a:self.start + b])
        finally:
            del mapped

    def column(self, column: str) -> "StoredColumn":
        """One column (X or Y) as a row source read from its file a slice at a time (what the recurrent fits
        read: :meth:`sarins_fmu.identify.compensators.Compensator.fit` takes row sources)."""
        return StoredColumn(self.path(column), self.start, self.stop)

    def rows(self, a: int, b: int) -> Dataset:
        """Rows a .. b - 1 (relative to ``start``) in memory."""
        a, b = max(0, int(a)), min(len(self), int(b))
        return Dataset(*(self._read(c, a, max(a, b)) for c in COLUMNS))

    def chunks(self, rows: int):
        """(X, Y) of consecutive chunks of ``rows`` rows (the last shorter), in order."""
        for a in range(0, len(self), int(rows)):
            part = self.rows(a, a + int(rows))
            yield part.X, part.Y

    @property
    def time(self) -> np.ndarray:
        """Every row's time, s (n,)."""
        return self._read("time", 0, len(self))

    def head(self, n: int) -> "StoredSet":
        """The first ``n`` rows."""
        return StoredSet(self.folder, self.name, self.start, self.start + max(0, min(int(n), len(self))))

    def tail(self, n: int) -> "StoredSet":
        """The last ``n`` rows (contiguous, still in time order)."""
        return StoredSet(self.folder, self.name, self.stop - max(0, min(int(n), len(self))), self.stop)

    def load(self) -> Dataset:
        """All rows in memory."""
        return self.rows(0, len(self))


class StoredColumn:
    """Rows ``start .. stop - 1`` of a stored ``.npy`` array, read with plain file reads at their offset:
    ``c[i:j]`` (step 1) and ``c[indices]`` (ascending row indices) return arrays; nothing stays mapped."""

    def __init__(self, path: Path, start: int, stop: int):
        self.path, self.start, self.stop = Path(path), int(start), int(stop)
        with open(self.path, "rb") as fh:
            version = np.lib.format.read_magic(fh)
            read_header = (np.lib.format.read_array_header_1_0 if version == (1, 0)
                           else np.lib.format.read_array_header_2_0)
            shape, fortran, self.dtype = read_header(fh)
            self.offset = fh.tell()
        if fortran or self.dtype.hasobject or not 0 <= self.start <= self.stop <= shape[0]:
            raise ValueError(f"{self.path}: not a C-ordered plain array with rows {start} .. {stop - 1}")
        self.shape = (self.stop - self.start,) + tuple(shape[1:])
        self.row_bytes = int(np.prod(self.shape[1:], dtype=np.int64)) * self.dtype.itemsize

    def __len__(self) -> int:
        return self.shape[0]

    def _read(self, fh, a: int, b: int) -> np.ndarray:
        out = np.empty((max(0, b - a),) + self.shape[1:], self.dtype)
        fh.seek(self.offset + (self.start + a) * self.row_bytes)
        if out.nbytes and fh.readinto(memoryview(out.reshape(-1).view(np.uint8))) != out.nbytes:
            raise ValueError(f"{self.path}: truncated array")
        return out

    def __getitem__(self, rows) -> np.ndarray:
        with open(self.path, "rb") as fh:
            if isinstance(rows, slice):
                a, b, step = rows.indices(len(self))
                if step != 1:
                    raise ValueError("a stored column is read by slices of step 1 or by row indices")
                return self._read(fh, a, max(a, b))
            idx = np.asarray(rows)
            if idx.ndim != 1 or idx.dtype.kind not in "iu":
                raise TypeError("a stored column is read by slices or 1-D integer row indices")
            idx = np.where(idx < 0, idx + len(self), idx)
            if len(idx) and (idx.min() < 0 or idx.max() >= len(self)):
                raise IndexError("row index out of range")
            out = np.empty((len(idx),) + self.shape[1:], self.dtype)
            for i, row in enumerate(idx):
                out[i] = self._read(fh, int(row), int(row) + 1)[0]
            return out


def save_set(folder: Path, name: str, data: Dataset) -> StoredSet:
    """Write ``data`` as ``<folder>/<name>.{X,Y,time}.npy`` (each atomically); the stored set."""
    from sarins.campaign import atomic_output

    folder = Path(folder)
    for column in COLUMNS:
        with atomic_output(folder / f"{name}.{column}.npy", keep_suffix=True) as tmp:
            np.save(tmp, np.ascontiguousarray(getattr(data, column)))
    return StoredSet(folder, name, 0, len(data))


def save_chunks(folder: Path, name: str, n: int, chunks, limit: int | None = None) -> StoredSet:
    """Write the set whose ``n`` rows come as consecutive (X, Y, time) parts (e.g.
    :func:`~sarins_fmu.experiments.mems_calibration.dataset_chunks`) as ``<folder>/<name>.{X,Y,time}.npy``,
    a part at a time (the files :func:`save_set` writes of the whole set); ``limit``: only the first
    ``limit`` rows.  The stored set."""
    import contextlib

    from sarins.campaign import atomic_output

    folder = Path(folder)
    n = int(n) if limit is None else min(int(n), max(0, int(limit)))
    done = 0
    with contextlib.ExitStack() as stack:
        files = []
        for column in COLUMNS:
            tmp = stack.enter_context(atomic_output(folder / f"{name}.{column}.npy", keep_suffix=True))
            files.append(stack.enter_context(open(tmp, "wb")))
        header = True
        for part in chunks:
            part = [np.ascontiguousarray(p[:n - done], dtype=float) for p in part]
            if header:
                header = False
                for fh, p in zip(files, part):
                    np.lib.format.write_array_header_1_0(fh, {"descr": np.lib.format.dtype_to_descr(p.dtype),
                                                              "fortran_order": False, "shape": (n,) + p.shape[1:]})
            for fh, p in zip(files, part):
                fh.write(memoryview(p.reshape(-1).view(np.uint8)) if p.size else b"")
            done += len(part[0])
            if done >= n:
                break
        if done != n or header:
            raise ValueError(f"{name}: {done} rows written of {n}")
        for fh in files:
            fh.flush()
    return StoredSet(folder, name, 0, n)
