"""Plain-data model files for the identifiers (JSON or ``.npz``, never pickle).

A model file holds a *format tag* naming the model kind, an integer format
*version*, a small ``meta`` mapping (numbers, strings, lists) and named
float arrays. Two encodings are accepted, chosen by the file suffix:

``.npz``
    numpy's zip of ``.npy`` arrays, read with ``allow_pickle=False``; the tag,
    version and ``meta`` are stored as one JSON string under ``__header__``.
    Compact for large sample sets (a GRNN keeps all its training samples).
anything else (``.json`` recommended)
    one JSON object ``{"format", "version", "meta", "arrays"}`` where each
    array is ``{"shape": [...], "data": [flat values]}``. Floats are written
    with Python's shortest round-trip representation, so a JSON round trip
    reproduces every value bit for bit.

Every failure to read a file (missing, not JSON / not a zip, wrong format
tag, unsupported version, missing key, wrong shape, NaN or infinity, a file
over its size budget) raises :class:`ModelFileError`, a :class:`ValueError`
subclass whose message starts with the file name.  Budgets: a JSON file of
at most :data:`MAX_JSON_BYTES`, an ``.npz`` whose arrays expand to at most
:data:`MAX_NPZ_BYTES` (checked before anything is decompressed).
"""

from __future__ import annotations

import json
import zipfile
import zlib
from collections.abc import Callable, Collection, Mapping
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from ..files import BudgetError, check_file_size, check_zip_budget, naming_path

__all__ = [
    "ModelFileError",
    "save_model_file",
    "load_model_file",
    "get_array",
]

T = TypeVar("T")

_HEADER_KEY = "__header__"
MAX_JSON_BYTES = 256 * 2**20  # a JSON model file larger than this is refused before reading
MAX_NPZ_BYTES = 256 * 2**20  # an .npz model file whose arrays expand to more is refused before reading
MAX_NPZ_MEMBERS = 1000  # arrays in an .npz model file


class ModelFileError(ValueError):
    """A model file could not be read: corrupt, mismatched or not finite.

    Parameters
    ----------
    path : str or Path
        The offending file.
    reason : str
        What is wrong with it.
    """

    def __init__(self, path: str | Path, reason: str) -> None:
        self.path = Path(path)
        self.reason = reason
        super().__init__(f"model file '{path}': {reason}")


def _is_npz(path: Path) -> bool:
    return path.suffix.lower() == ".npz"


def _reject_constant(name: str) -> float:
    raise ValueError(f"non-finite number {name} is not allowed")


def save_model_file(
    path: str | Path,
    format_tag: str,
    version: int,
    meta: Mapping[str, Any],
    arrays: Mapping[str, np.ndarray],
) -> Path:
    """Write a model file (JSON, or ``.npz`` when the suffix says so).

    Parameters
    ----------
    path : str or Path
        Destination; the suffix ``.npz`` selects the npz encoding.
    format_tag : str
        Names the model kind, e.g. ``"sarins_fmu.identify.rbf"``.
    version : int
        Format version of that model kind.
    meta : mapping
        JSON-serialisable scalars, strings and lists.
    arrays : mapping of str to ndarray
        Finite float arrays of any shape.

    Returns
    -------
    Path
        The written path.

    Raises
    ------
    ValueError
        If an array holds NaN or infinity (a model is never saved broken).
    """
    path = Path(path)
    clean: dict[str, np.ndarray] = {}
    for name, value in arrays.items():
        arr = np.asarray(value, dtype=float)
        if not np.all(np.isfinite(arr)):
            raise ValueError(f"array '{name}' holds NaN or infinity; not saved")
        clean[name] = arr
    header = {"format": format_tag, "version": int(version), "meta": dict(meta)}
    if _is_npz(path):
        header_json = json.dumps(header, allow_nan=False)
        with naming_path(path), open(path, "wb") as fh:
            np.savez(fh, **{_HEADER_KEY: np.array(header_json)}, **clean)
    else:
        doc = dict(header)
        doc["arrays"] = {
            name: {"shape": list(arr.shape), "data": arr.ravel().tolist()}
            for name, arr in clean.items()
        }
        with naming_path(path):
            path.write_text(json.dumps(doc, allow_nan=False), encoding="utf-8")
    return path


def _read_json(path: Path) -> tuple[dict, dict[str, np.ndarray]]:
    try:
        check_file_size(path, MAX_JSON_BYTES, "a JSON model file (MAX_JSON_BYTES)")
        text = path.read_text(encoding="utf-8")
    except BudgetError as exc:
        raise ModelFileError(path, exc.reason) from None
    except UnicodeDecodeError as exc:
        raise ModelFileError(path, f"not a text (JSON) file: {exc}") from None
    except OSError as exc:
        raise ModelFileError(path, f"cannot be read: {exc.strerror or exc}") from None
    try:
        doc = json.loads(text, parse_constant=_reject_constant)
    except ValueError as exc:
        raise ModelFileError(path, f"not valid JSON: {exc}") from None
    except RecursionError:
        raise ModelFileError(path, "JSON nested too deeply") from None
    if not isinstance(doc, dict):
        raise ModelFileError(path, "top level is not a JSON object")
    raw_arrays = doc.get("arrays")
    if not isinstance(raw_arrays, dict):
        raise ModelFileError(path, "missing or malformed 'arrays' object")
    arrays: dict[str, np.ndarray] = {}
    for name, entry in raw_arrays.items():
        if not isinstance(entry, dict) or "shape" not in entry or "data" not in entry:
            raise ModelFileError(path, f"array '{name}' needs 'shape' and 'data'")
        try:
            shape = tuple(int(s) for s in entry["shape"])
            data = np.array(entry["data"], dtype=float)
            if data.ndim != 1:
                raise ValueError("'data' must be a flat list of numbers")
            arrays[name] = data.reshape(shape)
        except (TypeError, ValueError) as exc:
            raise ModelFileError(path, f"array '{name}': {exc}") from None
    header = {k: v for k, v in doc.items() if k != "arrays"}
    return header, arrays


def _read_npz(path: Path) -> tuple[dict, dict[str, np.ndarray]]:
    try:
        check_zip_budget(path, MAX_NPZ_BYTES, "an .npz model file (MAX_NPZ_BYTES)", MAX_NPZ_MEMBERS)
    except BudgetError as exc:
        raise ModelFileError(path, exc.reason) from None
    except (OSError, zipfile.BadZipFile, EOFError) as exc:
        raise ModelFileError(path, f"not a readable npz file: {exc}") from None
    try:
        with np.load(path, allow_pickle=False) as npz:
            contents = {name: npz[name] for name in npz.files}
    except (OSError, ValueError, zipfile.BadZipFile, EOFError, zlib.error) as exc:
        raise ModelFileError(path, f"not a readable npz file: {exc}") from None
    if _HEADER_KEY not in contents:
        raise ModelFileError(path, f"missing '{_HEADER_KEY}' entry")
    raw_header = contents.pop(_HEADER_KEY)
    if raw_header.dtype.kind != "U" or raw_header.ndim != 0:
        raise ModelFileError(path, "header is not a JSON string")
    try:
        header = json.loads(str(raw_header), parse_constant=_reject_constant)
    except ValueError as exc:
        raise ModelFileError(path, f"header is not valid JSON: {exc}") from None
    except RecursionError:
        raise ModelFileError(path, "header JSON nested too deeply") from None
    if not isinstance(header, dict):
        raise ModelFileError(path, "header is not a JSON object")
    arrays = {}
    for name, arr in contents.items():
        if arr.dtype.kind not in "fiu":
            raise ModelFileError(path, f"array '{name}' is not numeric")
        arrays[name] = arr.astype(float)
    return header, arrays


def load_model_file(
    path: str | Path,
    format_tag: str,
    versions: Collection[int],
    build: Callable[[dict, dict[str, np.ndarray]], T],
) -> T:
    """Read and check a model file, then build the model from it.

    Parameters
    ----------
    path : str or Path
        File written by :func:`save_model_file`.
    format_tag : str
        The tag the caller expects; any other tag is rejected.
    versions : collection of int
        Format versions the caller can read.
    build : callable ``(meta, arrays) -> model``
        Builds the model; any ``KeyError``, ``TypeError`` or ``ValueError``
        it raises (missing key, wrong shape, ...) is reported as a
        :class:`ModelFileError` naming the file.

    Returns
    -------
    model
        Whatever ``build`` returns.

    Raises
    ------
    ModelFileError
        On any problem with the file.
    """
    path = Path(path)
    if not path.exists():
        raise ModelFileError(path, "no such file")
    if not path.is_file():
        raise ModelFileError(path, "not a regular file")
    header, arrays = _read_npz(path) if _is_npz(path) else _read_json(path)
    tag = header.get("format")
    if tag != format_tag:
        raise ModelFileError(path, f"format tag is {tag!r}, expected {format_tag!r}")
    version = header.get("version")
    if not isinstance(version, int) or version not in versions:
        raise ModelFileError(
            path, f"format version {version!r} not supported (readable: {sorted(versions)})"
        )
    meta = header.get("meta")
    if not isinstance(meta, dict):
        raise ModelFileError(path, "missing or malformed 'meta' object")
    for name, arr in arrays.items():
        if not np.all(np.isfinite(arr)):
            raise ModelFileError(path, f"array '{name}' holds NaN or infinity")
    try:
        return build(meta, arrays)
    except KeyError as exc:
        raise ModelFileError(path, f"missing entry {exc}") from None
    except (TypeError, ValueError, AttributeError, IndexError, RecursionError) as exc:
        raise ModelFileError(path, f"{type(exc).__name__}: {exc}" if not isinstance(exc, ValueError) else str(exc)) from None


def get_array(
    arrays: Mapping[str, np.ndarray], name: str, shape: tuple[int | None, ...]
) -> np.ndarray:
    """Fetch a named array and check its shape (``None`` = any length).

    Parameters
    ----------
    arrays : mapping of str to ndarray
        Arrays read from a model file.
    name : str
        Entry to fetch.
    shape : tuple of int or None
        Expected shape; ``None`` entries match any length.

    Returns
    -------
    ndarray
        The array (float).

    Raises
    ------
    KeyError
        If the entry is missing.
    ValueError
        If its shape differs from ``shape``.
    """
    arr = arrays[name]
    ok = arr.ndim == len(shape) and all(
        want is None or want == got for want, got in zip(shape, arr.shape)
    )
    if not ok:
        expected = "(" + ", ".join("n" if s is None else str(s) for s in shape) + ")"
        raise ValueError(f"array '{name}' has shape {arr.shape}, expected {expected}")
    return arr
