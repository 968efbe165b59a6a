"""ctypes binding of the thermal model (``thermal.h``): temperatures in degC, times in s."""

from __future__ import annotations

import ctypes

import numpy as np

from . import _arrays
from ._lib import function

_I64, _F64, _P = ctypes.c_int64, ctypes.c_double, ctypes.c_void_p

_exact_step = function("sarins_thermal_exact_step", _F64, _F64, _F64, _F64, _F64, _F64, _F64)
_exact_steps = function("sarins_thermal_exact_steps", None, _I64, _P, _P, _I64, _P, _P, _P, _P)
_die = function("sarins_die_temperatures", None, _I64, _I64, _P, _P, _F64, _P, _P, _P)


def exact_step(x: float, amb0: float, amb1: float, dt: float, heat: float, tau: float) -> float:
    """One exact step of dT/dt = (A(t) + dT - T)/tau with A linear from amb0 to amb1 over dt."""
    return _exact_step(x, amb0, amb1, dt, heat, tau)


def exact_steps(h, amb, heat, tau, temp0) -> np.ndarray:
    """Exact steps of lengths h (K,) with the ambient amb (K + 1,) at the step ends, from temp0 (S,);
    returns (K, S) temperatures at the step ends."""
    h = _arrays.read(h, np.shape(h)[:1], "h")
    n, s = h.shape[0], np.shape(heat)[0]
    amb, heat, tau, temp0 = (_arrays.read(a, shape, name) for a, shape, name in (
        (amb, (n + 1,), "amb"), (heat, (s,), "heat"), (tau, (s,), "tau"), (temp0, (s,), "temp0")))
    out = np.empty((n, s))
    _exact_steps(n, h.ctypes.data, amb.ctypes.data, s, heat.ctypes.data, tau.ctypes.data, temp0.ctypes.data,
                 out.ctypes.data)
    return out


def die_temperatures(reported0, reported, h, tau, die) -> np.ndarray:
    """Die temperatures (K, S) at the ends of K output intervals of length h; ``die`` (S,) holds them at
    the start and is advanced in place (see :func:`sarins_fmu.thermal.die_temperatures`)."""
    reported = np.ascontiguousarray(reported, dtype=np.float64)
    if reported.ndim != 2:
        raise ValueError(f"reported must be a (K, S) array, got shape {reported.shape}")
    n, s = reported.shape
    reported0, tau = _arrays.read(reported0, (s,), "reported0"), _arrays.read(tau, (s,), "tau")
    _arrays.written(die, (s,), "die")
    out = np.empty((n, s))
    _die(n, s, reported0.ctypes.data, reported.ctypes.data, h, tau.ctypes.data, die.ctypes.data, out.ctypes.data)
    return out
