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


# ---------------------------------------------------------------- array tables
# A compiled step that is called from C (no Python) gets its state as a table
# of float64 arrays: int64 rows (address, rows, columns), built by
# :func:`array_table` from arrays the Python object keeps alive and updates in
# place.  ``table_view1`` / ``table_view2`` rebuild them inside compiled code.

def array_table(arrays):
    """(N, 3) int64 table (address, shape[0], shape[1] or 1) of C-contiguous float64 arrays."""
    import numpy as np

    rows = []
    for a in arrays:
        if a.dtype != np.float64 or not a.flags.c_contiguous or a.ndim not in (1, 2):
            raise ValueError("array tables hold C-contiguous 1-D or 2-D float64 arrays")
        rows.append((a.ctypes.data, a.shape[0], a.shape[1] if a.ndim == 2 else 1))
    return np.array(rows, dtype=np.int64).reshape(len(rows), 3)


if HAVE_NUMBA:
    from numba import carray as _carray
    from numba import types as _types
    from numba.extending import intrinsic as _intrinsic

    @_intrinsic
    def _f64_pointer(typingctx, address):
        """An int64 address as a float64 pointer (compiled code only)."""
        sig = _types.CPointer(_types.float64)(_types.int64)

        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], context.get_value_type(_types.CPointer(_types.float64)))

        return sig, codegen

    @numba.njit(cache=True)
    def table_view1(table, i):
        """Row i of an array table as a 1-D array."""
        return _carray(_f64_pointer(table[i, 0]), (table[i, 1],))

    @numba.njit(cache=True)
    def table_view2(table, i):
        """Row i of an array table as a 2-D array."""
        return _carray(_f64_pointer(table[i, 0]), (table[i, 1], table[i, 2]))

    @numba.njit(cache=True)
    def c_table(pointer, rows):
        """An array table passed from C as (pointer, rows)."""
        return _carray(pointer, (rows, 3))

    @numba.njit(cache=True)
    def c_buffer(pointer, n):
        """A float64 buffer passed from C as (pointer, n)."""
        return _carray(pointer, (n,))

    STEP_SIGNATURE = _types.int32(_types.CPointer(_types.int64), _types.int64, _types.CPointer(_types.float64),
                                  _types.int64, _types.float64, _types.float64)

    def fast_step_cfunc(body):
        """Compile ``int body(int64 *table, int64 rows, double *buffer, int64 n, double t, double h)`` for C.

        ``body`` must be a module-level function (so that the compiled code
        is cached); it typically is
        ``return step(c_table(table, rows), c_buffer(buffer, n), t, h)`` with
        ``step`` a jitted function that returns 0 when it did the step and
        non-zero when it did not change any state.
        """
        try:
            return numba.cfunc(STEP_SIGNATURE, cache=True, nopython=True)(body)
        except Exception:  # pragma: no cover - numba refuses the cache dir
            return numba.cfunc(STEP_SIGNATURE, nopython=True)(body)
else:  # pragma: no cover
    table_view1 = table_view2 = c_table = c_buffer = fast_step_cfunc = None
