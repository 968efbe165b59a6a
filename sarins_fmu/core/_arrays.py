"""Checks of the numpy arrays passed to the core (dtype float64, C order, shape), once per call."""

from __future__ import annotations

import math

import numpy as np

INT64_MAX = 2**63 - 1  # largest count a C int64_t argument carries (ctypes would wrap a larger one)


def count(value, name: str, low: int = 1, high: int = INT64_MAX) -> int:
    """A whole number in [low, high] for a C ``int64_t`` argument, or ValueError naming ``name``
    (ctypes converts 2**64 + 2 to 2 without a word: the range is checked here)."""
    try:
        number = int(value)
        whole = number == value
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be a whole number, got {value!r}") from None
    if not whole or isinstance(value, bool):
        raise ValueError(f"{name} must be a whole number, got {value!r}")
    if not low <= number <= high:
        raise ValueError(f"{name} must be in {low} .. {high}, got {number}")
    return number


def positive_finite(value, name: str) -> float:
    """A finite float > 0, or ValueError naming ``name``."""
    try:
        number = float(value)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not (math.isfinite(number) and number > 0.0):
        raise ValueError(f"{name} must be finite and > 0, got {value!r}")
    return number


def read(a, shape, name: str) -> np.ndarray:
    """An input the callee only reads: converted to C-contiguous float64 (a copy only when needed)."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    if a.shape != tuple(shape):
        raise ValueError(f"{name} must have shape {tuple(shape)}, got {a.shape}")
    return a


def written(a, shape, name: str) -> np.ndarray:
    """An array the callee writes in place: must already be a writable C-contiguous float64 array."""
    if not (isinstance(a, np.ndarray) and a.dtype == np.float64 and a.flags.c_contiguous and a.flags.writeable):
        got = f"{a.dtype} array" if isinstance(a, np.ndarray) else type(a).__name__
        raise ValueError(f"{name} is written in place and must be a writable C-contiguous float64 array, got {got}"
                         + ("" if not isinstance(a, np.ndarray) or a.flags.c_contiguous else " (not C-contiguous)"))
    if a.shape != tuple(shape):
        raise ValueError(f"{name} must have shape {tuple(shape)}, got {a.shape}")
    return a


def table(t) -> np.ndarray:
    """An array table (:func:`sarins_fmu.core._lib.array_table`)."""
    if not (isinstance(t, np.ndarray) and t.dtype == np.int64 and t.ndim == 2 and t.shape[1] == 3
            and t.flags.c_contiguous):
        raise ValueError("the state table must be a C-contiguous (N, 3) int64 array (core._lib.array_table)")
    return t
