"""The core's portable math functions (``smath.h``) over numpy arrays, for tests and benchmarks.

The C core and the native FMUs call these instead of the C library's libm, so their results are
the same bits on every platform and compile line.  :func:`evaluate` runs one of them element-wise
through the core's ``sarins_smath_eval``.
"""

from __future__ import annotations

import ctypes

import numpy as np

from ._lib import c_double_p, function

# SARINS_SMATH_NAMES in smath.h, in order
NAMES = ("sqrt fma fabs copysign fmin fmax floor ceil trunc round nearbyint fmod sin cos sincos tan exp exp10 "
         "log log10 atan atan2 asin acos hypot soft_sqrt soft_fma sincos4 tanh pow tanhv expv").split()
ARITY = {"fma": 3, "soft_fma": 3, "copysign": 2, "fmin": 2, "fmax": 2, "fmod": 2, "atan2": 2, "hypot": 2, "pow": 2}

_eval = function("sarins_smath_eval", ctypes.c_int, ctypes.c_int, ctypes.c_int64, c_double_p, c_double_p,
                 c_double_p, c_double_p)


def evaluate(name: str, *args) -> np.ndarray:
    """``sm_<name>`` of the arguments (array-likes broadcast together, float64) element-wise; ``sincos`` and
    ``sincos4`` (four arguments at a time) return an array (2, n): the sines, then the cosines.  ``soft_sqrt``, ``soft_fma``: the software
    versions behind ``sm_sqrt``, ``sm_fma`` (which use the hardware instruction where there is one)."""
    if name not in NAMES:
        raise ValueError(f"unknown smath function {name!r}; known: {', '.join(NAMES)}")
    if len(args) != ARITY.get(name, 1):
        raise ValueError(f"{name} takes {ARITY.get(name, 1)} argument(s), got {len(args)}")
    arrays = [np.ascontiguousarray(a, dtype=np.float64).ravel() for a in np.broadcast_arrays(*args)]
    n = arrays[0].size
    out = np.empty(2 * n if name in ("sincos", "sincos4") else n)
    pointers = [a.ctypes.data_as(c_double_p) for a in arrays] + [None] * (3 - len(arrays))
    if _eval(NAMES.index(name), n, *pointers, out.ctypes.data_as(c_double_p)) != 0:
        raise RuntimeError(f"sarins_smath_eval refused {name}")
    return out.reshape(2, n) if name in ("sincos", "sincos4") else out
