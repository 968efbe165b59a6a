"""ctypes binding of the core's random streams (``rng.h``): SplitMix64 streams from (seed, stream id),
standard normals by Marsaglia's polar method.  The IMU draws from them inside its C step; these functions
serve one-off draws and the tests."""

from __future__ import annotations

import ctypes

import numpy as np

from . import _arrays
from ._lib import function

_U64, _I64, _P, _INT = ctypes.c_uint64, ctypes.c_int64, ctypes.c_void_p, ctypes.c_int

WORDS = 8  # SARINS_RNG_WORDS: float64 words of a packed stream state
SEED_LIMIT = 2**64  # seeds and stream ids are 64-bit unsigned integers

_normals = function("sarins_rng_normals", None, _U64, _U64, _I64, _P)
_uniforms = function("sarins_rng_uniforms", None, _U64, _U64, _I64, _P)
_start = function("sarins_rng_start", None, _U64, _U64, _P)
_fill_normals = function("sarins_rng_fill_normals", _INT, _P, _I64, _P)


def check_seed(seed, name: str = "seed") -> int:
    """``seed`` as a 64-bit unsigned integer, or a ValueError naming ``name``."""
    if isinstance(seed, (bool, float)) or not isinstance(seed, (int, np.integer)):
        raise ValueError(f"{name} must be an integer in [0, 2**64), got {seed!r}")
    seed = int(seed)
    if not 0 <= seed < SEED_LIMIT:
        raise ValueError(f"{name} must be an integer in [0, 2**64), got {seed}")
    return seed


def _count(n) -> int:
    n = int(n)
    if n < 0:
        raise ValueError(f"the number of draws must be non-negative, got {n}")
    return n


def normals(seed: int, stream: int, n: int) -> np.ndarray:
    """The first ``n`` standard normal draws of stream ``stream`` of ``seed``, (n,)."""
    out = np.empty(_count(n))
    _normals(check_seed(seed), check_seed(stream, "stream"), out.shape[0], out.ctypes.data)
    return out


def uniforms(seed: int, stream: int, n: int) -> np.ndarray:
    """The first ``n`` uniform draws in [0, 1) of stream ``stream`` of ``seed``, (n,)."""
    out = np.empty(_count(n))
    _uniforms(check_seed(seed), check_seed(stream, "stream"), out.shape[0], out.ctypes.data)
    return out


def start(seed: int, stream: int) -> np.ndarray:
    """The packed state (WORDS,) of stream ``stream`` of ``seed`` at its start (for :func:`fill_normals`)."""
    words = np.empty(WORDS)
    _start(check_seed(seed), check_seed(stream, "stream"), words.ctypes.data)
    return words


def fill_normals(state, n: int) -> np.ndarray:
    """The next ``n`` standard normals of the packed stream ``state`` (WORDS,), which is updated in place."""
    _arrays.written(state, (WORDS,), "state")
    out = np.empty(_count(n))
    if _fill_normals(state.ctypes.data, out.shape[0], out.ctypes.data) != 0:
        raise ValueError("state is not a packed random stream state (rng.h)")
    return out
