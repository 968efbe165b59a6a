"""ctypes binding of the StrapdownINS FMU's compiled step (``ins_fmu_step.h``).

The INS physics itself is bound in :mod:`sarins_fmu.ins_kernel`; this is the
FMU's doStep over an array table, called from Python (:func:`fmu_step`) or,
through :data:`FMU_STEP_ADDRESS`, by the native FMI layer.
"""

from __future__ import annotations

import ctypes

import numpy as np

from . import _arrays
from ._lib import function

_I64, _F64, _P, _INT = ctypes.c_int64, ctypes.c_double, ctypes.c_void_p, ctypes.c_int

FMU_STEP = function("sarins_ins_fmu_step", _INT, _P, _I64, _P, _I64, _F64, _F64)
FMU_STEP_ADDRESS = ctypes.cast(FMU_STEP, ctypes.c_void_p).value  # for the native FMI layer
IO_SIZE = function("sarins_ins_fmu_io_size", _I64)()  # length of the step's io row (SARINS_INS_IO)


def fmu_step(table, buffer, t: float, h: float) -> int:
    """The StrapdownINS FMU's step (``sarins_ins_fmu_step``): 0 when it did the step, 1 when it changed nothing."""
    _arrays.table(table)
    _arrays.written(buffer, np.shape(buffer)[:1], "buffer")
    return FMU_STEP(table.ctypes.data, table.shape[0], buffer.ctypes.data, buffer.shape[0], float(t), float(h))
