"""Campaign results on disk: keyed by what made them, written durably, locked.

A stored result (``<dir>/<task id>.npz``, plain numpy arrays, no pickle)
carries the **record** that made it -- the task function's qualified name,
its keyword arguments canonicalised to JSON, the campaign options that
matter, ``sarins_fmu.__version__`` and a hash of the code (:func:`code_hash`)
-- and the record's SHA-256.  A stored file is reused only if its record
equals the one the campaign would write now and it loads and validates:
every array as the file's manifest describes it (dtype, shape and SHA-256 of
its bytes, written with it) and, for a task that declares its result
(:class:`Field` per key), every key, shape, dtype kind and finiteness as the
run produces them.  Anything else (other parameters, other code, a
truncated, empty or garbage file, a missing key, an array cut or retyped
since, a non-finite required value) is recomputed.

Writes are atomic and durable: temporary file in the same folder, fsync,
``os.replace``, fsync of the folder.  Derived artefacts (built FMUs, fitted
models) are built in a temporary folder and moved into place
(:func:`build_artifacts`, :func:`atomic_output`), so a kill never leaves a
half-written file under its final name.  :func:`exclusive` locks an output
folder (``fcntl.flock`` on ``<dir>/.lock``) for one campaign at a time.

Size budget: a stored result whose arrays expand to more than
:data:`MAX_RESULT_BYTES` (or that has more than :data:`MAX_RESULT_MEMBERS`
arrays) is not read: it is recomputed like any other unusable file.  A
write that fails (a full disk) raises an ``OSError`` naming the final file.
"""

from __future__ import annotations

import contextlib
import fcntl
import functools
import hashlib
import inspect
import json
import math
import os
import shutil
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sarins_fmu.files import BudgetError, check_zip_budget, naming_path

RECORD_KEY = "__record__"  # the canonical record (JSON text) inside a result file
HASH_KEY = "__record_sha256__"
KEYS_KEY = "__keys__"  # the result's own keys, to detect a file that lost some
MANIFEST_KEY = "__manifest__"  # JSON {key: [dtype, shape, sha256 of the bytes]} of every array as written
RESERVED = (RECORD_KEY, HASH_KEY, KEYS_KEY, MANIFEST_KEY)
LOCK_NAME = ".lock"
MAX_RESULT_BYTES = 2**30  # bytes a stored result's arrays may expand to, uncompressed
MAX_RESULT_MEMBERS = 10_000  # arrays in a stored result

_CODE_ROOTS = ("sarins_fmu", "fmus", "orchestration")  # the code a result can depend on


class OutputBusyError(ValueError):
    """Another campaign holds the output folder (reported as bad usage, exit 2)."""


class StoredResultError(ValueError):
    """A stored result that cannot be reused (unreadable, stale or invalid)."""


# ------------------------------------------------------------------ records
def _canonical(value):
    """JSON-able canonical form of a task argument (tuples -> lists, numpy -> Python)."""
    if isinstance(value, dict):
        return {str(k): _canonical(v) for k, v in sorted(value.items(), key=lambda kv: str(kv[0]))}
    if isinstance(value, (list, tuple)):
        return [_canonical(v) for v in value]
    if isinstance(value, np.ndarray):
        return {"ndarray": str(value.dtype), "shape": list(value.shape), "data": _canonical(value.tolist())}
    if isinstance(value, np.generic):
        return _canonical(value.item())
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, float) and not math.isfinite(value):
        return repr(value)  # 'nan', 'inf': JSON has no literal for them
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    raise TypeError(f"task argument {value!r} of type {type(value).__name__} has no canonical JSON form")


def canonical_json(value) -> str:
    """Canonical JSON text of ``value`` (sorted keys, no spaces, exact floats)."""
    return json.dumps(_canonical(value), sort_keys=True, separators=(",", ":"), allow_nan=False)


@functools.lru_cache(maxsize=None)
def _tree_hash(root: str) -> str:
    digest = hashlib.sha256()
    base = Path(root)
    for path in sorted(p for p in base.rglob("*") if p.is_file() and "__pycache__" not in p.parts
                       and p.suffix not in (".pyc", ".fmu")):
        digest.update(str(path.relative_to(base)).encode())
        digest.update(b"\0")
        digest.update(path.read_bytes())
        digest.update(b"\0")
    return digest.hexdigest()


def code_hash(extra_files=()) -> str:
    """SHA-256 over the source of the packages results depend on (``sarins_fmu``,
    ``fmus``, ``orchestration``: every file but bytecode) and ``extra_files``
    (e.g. the module of a task function)."""
    import sarins_fmu

    repo = Path(sarins_fmu.__file__).resolve().parents[1]
    digest = hashlib.sha256()
    for name in _CODE_ROOTS:
        if (repo / name).is_dir():
            digest.update(f"{name}:{_tree_hash(str(repo / name))}\n".encode())
    for path in extra_files:
        digest.update(f"{Path(path).name}:{_file_hash(str(path))}\n".encode())
    return digest.hexdigest()


@functools.lru_cache(maxsize=None)
def _file_hash(path: str) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def task_record(task, options: dict | None = None) -> dict:
    """The canonical record of what makes ``task``'s result (see module docs)."""
    import sarins_fmu

    fn = task.fn
    try:
        source = inspect.getsourcefile(fn)
    except TypeError:
        source = None
    kwargs = {k: v for k, v in task.kwargs.items() if k not in task.volatile}
    record = {"task": task.id, "function": f"{fn.__module__}.{fn.__qualname__}", "kwargs": kwargs,
              "identity": dict(task.identity), "options": dict(options or {}),
              "version": sarins_fmu.__version__, "code": code_hash([source] if source else [])}
    return json.loads(canonical_json(record))


def record_hash(record: dict) -> str:
    return hashlib.sha256(canonical_json(record).encode()).hexdigest()


# ------------------------------------------------------------------ files
def _fsync_dir(folder: Path) -> None:
    fd = os.open(folder, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


@contextlib.contextmanager
def atomic_output(path, keep_suffix: bool = False):
    """Yield a temporary path beside ``path`` (hidden, ending in ``.tmp``, or
    in ``.tmp<suffix>`` with ``keep_suffix`` for writers that choose the
    format by suffix); on success fsync it, move it to ``path`` and fsync
    the folder; on failure remove it.  The caller writes the temporary path
    (any writer: numpy, json, a model's save)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    suffix = f".tmp{path.suffix}" if keep_suffix else ".tmp"
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=suffix, dir=path.parent)
    os.close(fd)
    tmp = Path(tmp)
    try:
        with naming_path(path, replacing=[tmp]):  # a full disk names the file being written
            yield tmp
            with open(tmp, "rb+") as fh:
                os.fsync(fh.fileno())
            os.replace(tmp, path)
            _fsync_dir(path.parent)
    finally:
        if tmp.exists():
            tmp.unlink()


def write_text(path, text: str) -> None:
    """Atomically and durably write a text file (UTF-8)."""
    with atomic_output(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def save_result(path, result: dict, record: dict | None = None) -> None:
    """Atomically write a result dict (values become numpy arrays; no pickle),
    with its ``record`` and the record's hash when given.

    A value with a ``blocks()`` method, ``shape`` and ``dtype`` (e.g.
    :class:`sarins_fmu.experiments.mems_calibration.SpooledArray`) is streamed into the file a row block at a
    time, never held whole, and its ``unlink()`` is called once written; the file is the one ``np.savez``
    writes of the whole array."""
    path = Path(path)
    arrays = {}
    for key, value in result.items():
        if key in RESERVED:
            raise ValueError(f"result key {key!r} of {path.name} is reserved")
        arr = value if _streamed(value) else np.asarray(value)
        if arr.dtype == object:
            raise TypeError(f"result {key!r} of {path.name} is not numeric or text")
        arrays[key] = arr
    arrays[KEYS_KEY] = np.array(sorted(result), dtype=str)
    manifest = {}
    with atomic_output(path) as tmp:
        with open(tmp, "wb") as fh, zipfile.ZipFile(fh, mode="w", compression=zipfile.ZIP_STORED,
                                                    allowZip64=True) as archive:
            for key, arr in arrays.items():  # as np.savez writes them
                with archive.open(key + ".npy", "w", force_zip64=True) as member:
                    if _streamed(arr):
                        manifest[key] = _write_blocks(member, arr)
                    else:
                        np.lib.format.write_array(member, arr, allow_pickle=False)
                        if key != KEYS_KEY:
                            manifest[key] = _describe(arr)
            tail = {MANIFEST_KEY: np.array(json.dumps(manifest, sort_keys=True))}
            if record is not None:
                tail[RECORD_KEY] = np.array(canonical_json(record))
                tail[HASH_KEY] = np.array(record_hash(record))
            for key, arr in tail.items():
                with archive.open(key + ".npy", "w", force_zip64=True) as member:
                    np.lib.format.write_array(member, arr, allow_pickle=False)
    for arr in arrays.values():
        if _streamed(arr) and hasattr(arr, "unlink"):
            arr.unlink()


def _streamed(value) -> bool:
    return hasattr(value, "blocks") and hasattr(value, "shape") and hasattr(value, "dtype")


def _write_blocks(member, arr) -> list:
    """Write a streamed array as a ``.npy`` member a block at a time; its manifest entry."""
    dtype = np.dtype(arr.dtype)
    np.lib.format.write_array_header_1_0(member, {"descr": np.lib.format.dtype_to_descr(dtype),
                                                  "fortran_order": False, "shape": tuple(arr.shape)})
    digest, rows = hashlib.sha256(), 0
    for block in arr.blocks():
        block = np.ascontiguousarray(block, dtype=dtype)
        member.write(_buffer(block))
        digest.update(_buffer(block))
        rows += len(block)
    if rows != (arr.shape[0] if arr.shape else 1):
        raise ValueError(f"a streamed array gave {rows} rows of {arr.shape}")
    return [dtype.str, list(arr.shape), digest.hexdigest()]


def _describe(arr: np.ndarray) -> list:
    """[dtype, shape, SHA-256 of the bytes] of an array: what the manifest promises of it."""
    arr = np.ascontiguousarray(arr)  # (hashed in place: no copy of a contiguous array's bytes)
    return [arr.dtype.str, list(arr.shape), hashlib.sha256(_buffer(arr)).hexdigest()]


def _buffer(arr: np.ndarray):
    """The bytes of a C-contiguous array as a buffer (``arr.tobytes()`` without the copy)."""
    return memoryview(arr.reshape(-1).view(np.uint8)) if arr.size else b""


def _check_manifest(raw: dict, text) -> None:
    """Every array as its manifest describes it (a file whose record is intact but one of whose
    arrays was cut, retyped or rewritten since fails here)."""
    try:
        manifest = json.loads(str(text))
    except ValueError:
        raise StoredResultError("its manifest is not JSON") from None
    if not isinstance(manifest, dict) or set(manifest) != set(raw):
        raise StoredResultError("its manifest does not list its arrays")
    for key, arr in raw.items():
        wanted, found = manifest[key], _describe(arr)
        if wanted != found:
            what = ("dtype" if wanted[0] != found[0] else "shape" if wanted[1] != found[1] else "content")
            raise StoredResultError(f"{key!r} has another {what} than written "
                                    f"({found[0]} {tuple(found[1])}, written {wanted[0]} {tuple(wanted[1])})")


def _read(path: Path) -> tuple[dict, dict | None]:
    """(result, record) of a file; raises StoredResultError for anything unreadable."""
    try:
        check_zip_budget(path, MAX_RESULT_BYTES, "a stored result (MAX_RESULT_BYTES)", MAX_RESULT_MEMBERS)
    except BudgetError as exc:
        raise StoredResultError(exc.reason) from None
    except Exception as exc:  # BadZipFile, OSError, EOFError: not a zip at all
        raise StoredResultError(f"unreadable ({type(exc).__name__}: {' '.join(str(exc).split())[:120]})") from None
    try:
        with np.load(path, allow_pickle=False) as data:
            if not hasattr(data, "files"):
                raise StoredResultError("not a result archive (a bare array)")
            raw = {key: data[key] for key in data.files}
    except StoredResultError:
        raise
    except Exception as exc:  # BadZipFile, EOFError, ValueError (pickled data), zlib.error, OSError ...
        raise StoredResultError(f"unreadable ({type(exc).__name__}: {' '.join(str(exc).split())[:120]})") from None
    record = None
    if RECORD_KEY in raw:
        try:
            record = json.loads(str(raw.pop(RECORD_KEY)))
        except ValueError:
            raise StoredResultError("its parameter record is not JSON") from None
    stored_hash = str(raw.pop(HASH_KEY)) if HASH_KEY in raw else None
    keys = [str(k) for k in raw.pop(KEYS_KEY)] if KEYS_KEY in raw else None
    if record is not None and stored_hash != record_hash(record):
        raise StoredResultError("its parameter record does not match its hash")
    if keys is not None:
        missing = sorted(set(keys) - set(raw))
        if missing:
            raise StoredResultError(f"keys missing: {', '.join(missing)}")
    if MANIFEST_KEY in raw:
        _check_manifest({k: v for k, v in raw.items() if k != MANIFEST_KEY}, raw.pop(MANIFEST_KEY))
    elif record is not None:
        raise StoredResultError("it has no manifest of its arrays (written by an older version)")
    result = {key: (arr.item() if arr.ndim == 0 else arr) for key, arr in raw.items()}
    return result, record


def load_result(path) -> dict:
    """Read a stored result; scalars come back as Python numbers/strings.
    Raises :class:`StoredResultError` naming the file if it is unreadable."""
    try:
        return _read(Path(path))[0]
    except StoredResultError as exc:
        raise StoredResultError(f"{path}: {exc}") from None


def _differences(stored: dict, wanted: dict) -> str:
    diff = []
    for key in wanted:
        if isinstance(wanted[key], dict) and isinstance(stored.get(key), dict):
            diff += [f"{key}.{k}" for k in sorted(set(wanted[key]) | set(stored[key]))
                     if wanted[key].get(k) != stored[key].get(k)]
        elif stored.get(key) != wanted[key]:
            diff.append(key)
    return ", ".join(diff) or "record"


@dataclass(frozen=True)
class Field:
    """What a task's result holds under one key, as the run produces it.

    shape : tuple of ints (fixed, e.g. derived from the task's arguments) or names
        (dimensions shared between fields: ``("n",)`` on two series says they have
        one length, whatever it is); ``()`` for a scalar.
    kind : accepted numpy dtype kinds ('f' float, 'i' signed, 'u' unsigned, 'b' bool, 'U' text).
    finite : every value is finite (numeric kinds only).
    """

    shape: tuple = ()
    kind: str = "f"
    finite: bool = True


def check_fields(result: dict, schema: dict) -> None:
    """Raise :class:`StoredResultError` unless ``result`` has exactly the keys of ``schema``
    ({key: Field}) with their shape, dtype kind and finiteness."""
    missing = sorted(set(schema) - set(result))
    extra = sorted(set(result) - set(schema))
    if missing or extra:
        raise StoredResultError("its keys differ from the task's: " + "; ".join(
            part for part in (f"missing {', '.join(missing)}" if missing else "",
                              f"unexpected {', '.join(extra)}" if extra else "") if part))
    dims: dict = {}
    for key, field in schema.items():
        arr = np.asarray(result[key])
        if arr.dtype.kind not in field.kind:
            raise StoredResultError(f"{key!r} is {arr.dtype}, the task gives kind {field.kind!r}")
        if arr.ndim != len(field.shape):
            raise StoredResultError(f"{key!r} has shape {arr.shape}, the task gives {len(field.shape)} dimensions")
        for size, want in zip(arr.shape, field.shape):
            if isinstance(want, str):
                want = dims.setdefault(want, size)
            if size != want:
                raise StoredResultError(f"{key!r} has shape {arr.shape}, the task gives {_shape_text(field, dims)}")
        if field.finite and arr.dtype.kind in "fc" and not np.all(np.isfinite(arr)):
            raise StoredResultError(f"{key!r} is not finite")


def _shape_text(field: Field, dims: dict) -> str:
    return "(" + ", ".join(str(dims.get(d, d)) for d in field.shape) + ("," if len(field.shape) == 1 else "") + ")"


def load_valid(path, record: dict, finite=(), schema: dict | None = None) -> dict:
    """The stored result at ``path`` if it was made by ``record`` and is valid.

    Raises :class:`StoredResultError` with the reason otherwise (the file
    exists but is unreadable, stale or invalid); ``FileNotFoundError`` if
    there is no file.
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(path)
    result, stored = _read(path)
    if stored is None:
        raise StoredResultError("it has no parameter record (written by an older version)")
    if stored != record:
        raise StoredResultError(f"it was made with other parameters or code ({_differences(stored, record)})")
    for key in finite:
        if key not in result:
            raise StoredResultError(f"key {key!r} missing")
        try:
            ok = bool(np.all(np.isfinite(np.asarray(result[key], dtype=float))))
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise StoredResultError(f"{key!r} is not finite")
    if schema is not None:
        check_fields(result, schema)
    return result


def remove_stale_temporaries(folder) -> None:
    """Delete temporary files a killed writer left in ``folder`` (call it under :func:`exclusive`)."""
    for path in Path(folder).glob(".*.tmp*"):
        with contextlib.suppress(OSError):
            path.unlink()
    for path in Path(folder).glob(".build-*"):
        if path.is_dir():
            shutil.rmtree(path, ignore_errors=True)


# ------------------------------------------------------------------ lock
_HELD: dict[str, list] = {}  # resolved folder -> [open lock file, depth]: re-entrant in one process


@contextlib.contextmanager
def exclusive(folder):
    """Hold ``<folder>/.lock`` (``fcntl.flock``) for one campaign at a time.

    A second campaign on the same folder is refused at once with
    :class:`OutputBusyError` (it does not wait: two runs of the same work
    are almost always a mistake, and the message says which process holds
    the folder).  The lock is released when the holder exits, however it
    exits (the kernel drops it with the process).  Re-entrant in one process.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    key = str(folder.resolve())
    if key in _HELD:
        _HELD[key][1] += 1
        try:
            yield
        finally:
            _HELD[key][1] -= 1
        return
    fh = open(folder / LOCK_NAME, "a+")
    try:
        fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        fh.seek(0)
        holder = fh.read().strip() or "?"
        fh.close()
        raise OutputBusyError(f"{folder} is in use by another campaign (pid {holder}); wait for it to finish "
                              "or choose another --out") from None
    fh.seek(0)
    fh.truncate()
    fh.write(str(os.getpid()))
    fh.flush()
    _HELD[key] = [fh, 1]
    try:
        yield
    finally:
        if _HELD[key][1] <= 1:
            del _HELD[key]
            fh.close()  # releases the flock
        else:
            _HELD[key][1] -= 1


# ------------------------------------------------------------------ artefacts
def build_artifacts(dest, names, build, key: str) -> list[Path]:
    """Files ``dest/<name>`` produced by ``build(folder)``, rebuilt unless a
    stamp says they were built with ``key`` (e.g. :func:`code_hash`).

    ``build(folder)`` writes every name into a fresh temporary folder beside
    ``dest``; each file is then moved into place atomically and the stamp
    written last, so a kill at any point leaves either the old complete
    files or the new ones, never a partial file, and the next call rebuilds
    whatever the stamp does not vouch for.
    """
    dest = Path(dest)
    dest.mkdir(parents=True, exist_ok=True)
    stamp = dest / ".built.json"
    names = list(names)
    try:
        built = json.loads(stamp.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        built = {}
    if isinstance(built, dict) and all(built.get(n) == key and (dest / n).is_file() for n in names):
        return [dest / n for n in names]
    tmp = Path(tempfile.mkdtemp(prefix=".build-", dir=dest.parent))
    try:
        build(tmp)
        for name in names:
            if not (tmp / name).is_file():
                raise RuntimeError(f"building {name} in {dest} produced no file")
            with open(tmp / name, "rb+") as fh:
                os.fsync(fh.fileno())
            os.replace(tmp / name, dest / name)
        _fsync_dir(dest)
        built = built if isinstance(built, dict) else {}
        built.update({n: key for n in names})
        write_text(stamp, json.dumps(built, indent=1, sort_keys=True))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return [dest / n for n in names]
