"""Optional numba compilation.

Kernels are written as plain loops over numpy arrays and compiled with numba
when it is importable.  Without numba (e.g. an FMU host that has only numpy
and scipy) the very same functions run as plain Python: the results are the
same, only slower.  ``HAVE_NUMBA`` tells which path is active; setting the
environment variable ``SARINS_NO_NUMBA=1`` forces the plain path.
"""

import os

HAVE_NUMBA = False
if os.environ.get("SARINS_NO_NUMBA", "") not in ("1", "true", "yes"):
    try:
        import numba

        HAVE_NUMBA = True
    except ImportError:  # pragma: no cover - depends on the host
        HAVE_NUMBA = False


def jit(fn=None, *, parallel=False):
    """Compile ``fn`` with ``numba.njit`` (cached) when numba is available."""

    def wrap(f):
        if not HAVE_NUMBA:
            return f
        try:
            return numba.njit(cache=True, parallel=parallel, error_model="numpy")(f)
        except Exception:  # pragma: no cover - numba refuses the cache dir
            return numba.njit(parallel=parallel, error_model="numpy")(f)

    return wrap(fn) if fn is not None else wrap


if HAVE_NUMBA:
    prange = numba.prange
else:  # pragma: no cover
    prange = range
