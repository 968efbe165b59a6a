"""ctypes binding of the azimuth gyro's thermal terms beyond eps(T) and d dT/dt
(``sarins_imu_axial_thermal_terms``, ``imu.h``): block gradient and heating/cooling hysteresis.
Temperatures in degC, times in s, drifts in rad/s."""

from __future__ import annotations

import ctypes
import math

import numpy as np

from . import _arrays
from ._lib import function

_I64, _F64, _P = ctypes.c_int64, ctypes.c_double, ctypes.c_void_p

_terms = function("sarins_imu_axial_thermal_terms", None, _I64, _F64, _P, _I64, _F64, _P, _P, _P, _I64)


def thermal_terms(temp0: float, temps, h: float, par, state=None) -> np.ndarray:
    """The z-gyro drift (rad/s) of the gradient and hysteresis terms over K intervals of length ``h`` s.

    temp0: z temperature at the start (degC); temps (K,): at the interval ends (degC); par (5,):
    gradient coefficient (rad/s/degC), block time constant (s), hysteresis half-height (rad/s), its
    width (degC, > 0) and relaxation time (s; 0: none), as ``ImuModel.axial_thermal_par``; state (2,):
    block node temperature and play operator (degC), advanced in place (default: both at ``temp0``, the
    unit in equilibrium with its loop at 0).  Returns (K,) drift, rad/s.
    """
    temps = _arrays.read(temps, np.shape(temps)[:1], "temps")
    par = _arrays.read(par, (5,), "par")
    if not (math.isfinite(h) and h > 0):
        raise ValueError(f"interval h must be positive, got {h}")
    if not (np.isfinite(par).all() and par[1] >= 0 and par[3] > 0 and par[4] >= 0):
        raise ValueError("axial thermal parameters need finite values, block and relaxation times >= 0, width > 0")
    if state is None:
        state = np.array([float(temp0), float(temp0)])
    _arrays.written(state, (2,), "state")
    out = np.zeros(temps.shape[0])
    _terms(temps.shape[0], float(temp0), temps.ctypes.data, 1, float(h), par.ctypes.data, state.ctypes.data,
           out.ctypes.data, 1)
    return out
