"""ctypes binding of the schedule and ambient builders (``schedule.h``, ``ambient.h``).

SI throughout (rad, rad/s, rad/s^2, s; temperatures degC).  A bad parameter
raises ValueError with the core's one-line reason.  The library's public
functions (:mod:`sarins_fmu.turntable`, :mod:`sarins_fmu.thermal`) wrap these.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass

import numpy as np

from . import _arrays
from ._lib import function

_I64, _F64, _P, _INT, _STR = ctypes.c_int64, ctypes.c_double, ctypes.c_void_p, ctypes.c_int, ctypes.c_char_p
_SIZE = ctypes.c_size_t
_MSG_LEN = 512
BAD_PARAM, TOO_BIG, CAPACITY = 1, 2, 3  # SARINS_SCHEDULE_* return codes
MAX_AXES = 3
_N_MAGNITUDES = 11  # SARINS_RATE_TEST_N_MAGNITUDES
UP_NAMES = ("+x", "-x", "+y", "-y", "+z", "-z")  # SARINS_UP_PX .. SARINS_UP_MZ


class Params(ctypes.Structure):
    """``sarins_schedule_params``."""

    _fields_ = [("scheme", _STR), ("duration", _F64), ("rate", _F64), ("accel", _F64), ("dwell", _F64),
                ("revolutions", _F64), ("align_time", _F64), ("align_dwell", _F64), ("grid", _F64),
                ("outer_rate", _F64), ("outer_accel", _F64),
                ("table_inner_rate", _F64), ("table_middle_rate", _F64), ("table_outer_rate", _F64),
                ("table_inner_accel", _F64), ("table_middle_accel", _F64), ("table_outer_accel", _F64),
                ("warmup", _F64), ("test_rates", _P), ("n_test_rates", _I64), ("test_axes", _STR),
                ("test_min_duration", _F64), ("test_rate_tol", _F64)]


WINDOW_DTYPE = np.dtype([("start", float), ("end", float), ("angles", float, (3,)), ("heading", float),
                         ("rate", float), ("rate_nominal", float), ("revolutions", np.int64), ("up", np.int64)])


class Schedule(ctypes.Structure):
    """``sarins_schedule``."""

    _fields_ = [("capacity", _I64), ("times", _P), ("angle_bp", _P), ("rate_bp", _P), ("accel", _P),
                ("window_capacity", _I64), ("windows", _P), ("n_times", _I64), ("n_axes", _I64),
                ("n_windows", _I64), ("angle0", _F64 * MAX_AXES), ("rate0", _F64 * MAX_AXES),
                ("axes", (_F64 * 3) * MAX_AXES), ("gimbal_axes", ctypes.c_char * 8)]


class ChamberParams(ctypes.Structure):
    """``sarins_chamber_params``."""

    _fields_ = [("duration", _F64), ("low", _F64), ("high", _F64), ("ramp", _F64), ("hold", _F64),
                ("start", _F64), ("delay", _F64), ("first", _STR), ("step", _F64), ("step_hold", _F64)]


class AmbientC(ctypes.Structure):
    """``sarins_ambient``."""

    _fields_ = [("mean", _F64), ("amplitude", _F64), ("period", _F64), ("phase", _F64), ("slope", _F64),
                ("n_profile", _I64), ("profile_times", _P), ("profile_temps", _P)]


_P_PARAMS, _P_SCHED = ctypes.POINTER(Params), ctypes.POINTER(Schedule)
_P_CHAMBER, _P_AMBIENT = ctypes.POINTER(ChamberParams), ctypes.POINTER(AmbientC)
_P_I64, _P_F64 = ctypes.POINTER(_I64), ctypes.POINTER(_F64)
assert WINDOW_DTYPE.itemsize == 80

_defaults = function("sarins_schedule_params_default", None, _P_PARAMS)
_size = function("sarins_schedule_size", _INT, _P_PARAMS, _P_I64, _P_I64, _P_I64, _P, _SIZE)
_build = function("sarins_schedule_build", _INT, _P_PARAMS, _P_SCHED, _P, _SIZE)
_gimbal_axes = function("sarins_scheme_gimbal_axes", _STR, _STR)
_move = function("sarins_move_segments", _INT, _F64, _F64, _F64, _F64, _P, _P, _P_I64, _P, _SIZE)
_integrate = function("sarins_schedule_integrate", None, _I64, _I64, _P, _P, _P, _P, _P, _P)
_magnitudes = function("sarins_rate_test_magnitudes_dps", None, _P)
_chamber_size = function("sarins_chamber_size", _INT, _P_CHAMBER, _P_I64, _P, _SIZE)
_chamber_build = function("sarins_chamber_build", _INT, _P_CHAMBER, _I64, _P, _P, _P_I64, _P, _SIZE)
_cycle_time = function("sarins_chamber_cycle_time", _INT, _P_CHAMBER, _P_F64, _P, _SIZE)
_ambient_values = function("sarins_ambient_values", None, _P_AMBIENT, _I64, _P, _P)
_ambient_segment = function("sarins_ambient_segment", _INT, _P_AMBIENT, _F64, _F64, _P_F64, _P_F64, _P, _SIZE)


def _raise(code: int, msg) -> None:
    """ValueError with the core's reason (a parameter out of range, or a profile too large)."""
    if code:
        text = msg.value.decode(errors="replace")
        if code == CAPACITY:  # the binding sized the arrays with the core's own count
            raise RuntimeError(f"schedule builder: {text}")
        raise ValueError(text)


def rate_test_magnitudes_dps() -> tuple:
    """The rate test's default magnitudes, deg/s (``sarins_rate_test_magnitudes_dps``)."""
    out = np.empty(_N_MAGNITUDES)
    _magnitudes(out.ctypes.data)
    return tuple(float(x) for x in out)


def gimbal_axes(scheme: str):
    """The scheme's chain as axis letters ('z', 'y,z', 'z,x,y'), None for an unknown scheme."""
    out = _gimbal_axes(str(scheme).encode())
    return None if out is None else out.decode()


@dataclass(frozen=True)
class BuiltSchedule:
    """A schedule as the core built it (see ``sarins_schedule``): axes (A, 3), times (M+1,), accel (M, A),
    angle0 and rate0 (A,), gimbal_axes ('z' ...), windows (W,) of :data:`WINDOW_DTYPE`."""

    axes: np.ndarray
    times: np.ndarray
    accel: np.ndarray
    angle0: np.ndarray
    rate0: np.ndarray
    gimbal_axes: str
    windows: np.ndarray


def build_schedule(scheme: str, **si) -> BuiltSchedule:
    """Schedule of ``scheme`` (``sarins_schedule_build``); keyword arguments are the fields of
    ``sarins_schedule_params`` in SI (the others keep the core's defaults); ``test_rates`` is a sequence
    (rad/s) and ``test_axes`` a string."""
    p = Params()
    _defaults(ctypes.byref(p))
    p.scheme = str(scheme).encode()
    rates = si.pop("test_rates", None)
    if rates is not None:
        rates = np.ascontiguousarray(rates, dtype=np.float64).reshape(-1)
        keep = rates if rates.size else np.zeros(1)  # a valid address even when empty
        p.test_rates, p.n_test_rates = keep.ctypes.data, rates.size
    axes = si.pop("test_axes", None)
    if axes is not None:
        p.test_axes = str(axes).encode()
    fields = {f for f, _ in Params._fields_}
    for name, value in si.items():
        if name not in fields:
            raise TypeError(f"build_schedule() got an unknown parameter {name!r}")
        setattr(p, name, float(value))
    msg = ctypes.create_string_buffer(_MSG_LEN)
    n_times, n_axes, n_windows = _I64(), _I64(), _I64()
    _raise(_size(ctypes.byref(p), ctypes.byref(n_times), ctypes.byref(n_axes), ctypes.byref(n_windows), msg,
                 _MSG_LEN), msg)
    m, a = n_times.value, n_axes.value
    times, angle_bp, rate_bp = np.empty(m), np.empty((m, a)), np.empty((m, a))
    accel = np.empty((m - 1, a))
    windows = np.zeros(n_windows.value, dtype=WINDOW_DTYPE)
    s = Schedule(capacity=m, times=times.ctypes.data, angle_bp=angle_bp.ctypes.data, rate_bp=rate_bp.ctypes.data,
                 accel=accel.ctypes.data, window_capacity=windows.size,
                 windows=windows.ctypes.data if windows.size else None)
    _raise(_build(ctypes.byref(p), ctypes.byref(s), msg, _MSG_LEN), msg)
    axes_out = np.array([list(s.axes[j]) for j in range(a)], dtype=float)
    return BuiltSchedule(axes_out, times, accel, np.array(s.angle0[:a]), np.array(s.rate0[:a]),
                         s.gimbal_axes.decode(), windows)


def move_segments(angle: float, rate_max: float, accel_max: float, grid: float) -> list:
    """[(duration s, accel rad/s^2)] of a rest-to-rest trapezoidal move (``sarins_move_segments``)."""
    dur, acc, n = np.empty(3), np.empty(3), _I64()
    msg = ctypes.create_string_buffer(_MSG_LEN)
    _raise(_move(float(angle), float(rate_max), float(accel_max), float(grid), dur.ctypes.data, acc.ctypes.data,
                 ctypes.byref(n), msg, _MSG_LEN), msg)
    return [(float(dur[i]), float(acc[i])) for i in range(n.value)]


def integrate(times, accel, angle0, rate0) -> tuple:
    """(angle_bp, rate_bp) (M+1, A) of a schedule's breakpoint tables (``sarins_schedule_integrate``)."""
    if np.ndim(times) != 1 or np.shape(times)[0] < 1:
        raise ValueError(f"times must be a 1-D array of at least 1 breakpoint, got shape {np.shape(times)}")
    if np.ndim(angle0) != 1 or np.shape(angle0)[0] < 1:
        raise ValueError(f"angle0 must be a 1-D array of at least 1 axis, got shape {np.shape(angle0)}")
    times = _arrays.read(times, np.shape(times), "times")
    n_times, n_axes = times.shape[0], np.shape(angle0)[0]
    accel = _arrays.read(accel, (n_times - 1, n_axes), "accel")
    angle0, rate0 = _arrays.read(angle0, (n_axes,), "angle0"), _arrays.read(rate0, (n_axes,), "rate0")
    angle_bp, rate_bp = np.empty((n_times, n_axes)), np.empty((n_times, n_axes))
    _integrate(n_times, n_axes, times.ctypes.data, accel.ctypes.data, angle0.ctypes.data, rate0.ctypes.data,
               angle_bp.ctypes.data, rate_bp.ctypes.data)
    return angle_bp, rate_bp


def _chamber(duration, low, high, ramp, hold, start, delay, first, step, step_hold) -> ChamberParams:
    return ChamberParams(float(duration), float(low), float(high), float(ramp), float(hold), float(start),
                         float(delay), str(first).encode(), float(step), float(step_hold))


def chamber_profile(duration: float, low: float, high: float, ramp: float, hold: float, start: float,
                    delay: float, first: str, step: float, step_hold: float) -> tuple:
    """(times s, temps degC) of the chamber programme (``sarins_chamber_build``; ramp degC/s, holds s)."""
    p = _chamber(duration, low, high, ramp, hold, start, delay, first, step, step_hold)
    msg, n = ctypes.create_string_buffer(_MSG_LEN), _I64()
    _raise(_chamber_size(ctypes.byref(p), ctypes.byref(n), msg, _MSG_LEN), msg)
    times, temps = np.empty(n.value), np.empty(n.value)
    _raise(_chamber_build(ctypes.byref(p), n.value, times.ctypes.data, temps.ctypes.data, ctypes.byref(n), msg,
                          _MSG_LEN), msg)
    return times, temps


def chamber_cycle_time(low: float, high: float, ramp: float, hold: float, step: float, step_hold: float) -> float:
    """One end -> end -> end cycle of the chamber programme, s (``sarins_chamber_cycle_time``)."""
    p = _chamber(1.0, low, high, ramp, hold, 0.0, 0.0, "low", step, step_hold)
    msg, out = ctypes.create_string_buffer(_MSG_LEN), _F64()
    _raise(_cycle_time(ctypes.byref(p), ctypes.byref(out), msg, _MSG_LEN), msg)
    return out.value


def _ambient(mean, amplitude, period, phase, slope, profile):
    """(sarins_ambient, the arrays it points to: keep them alive while it is used)."""
    a = AmbientC(float(mean), float(amplitude), float(period), float(phase), float(slope), 0, None, None)
    keep = ()
    if profile is not None:
        pt, pv = (np.ascontiguousarray(x, dtype=np.float64).reshape(-1) for x in profile)
        if pt.size == 0 or pt.shape != pv.shape:
            raise ValueError("an ambient profile needs times and temperatures of one equal, non-zero length")
        a.n_profile, a.profile_times, a.profile_temps = pt.size, pt.ctypes.data, pv.ctypes.data
        keep = (pt, pv)
    return a, keep


def ambient_values(time, mean, amplitude, period, phase, slope, profile):
    """T_amb (degC) at ``time`` (s, scalar or array; a float for a scalar) (``sarins_ambient_values``)."""
    a, _keep = _ambient(mean, amplitude, period, phase, slope, profile)
    t = np.asarray(time, dtype=np.float64)
    flat = np.ascontiguousarray(t.reshape(-1))
    out = np.empty(flat.shape)
    _ambient_values(ctypes.byref(a), flat.size, flat.ctypes.data, out.ctypes.data)
    return float(out[0]) if t.ndim == 0 else out.reshape(t.shape)


def ambient_segment(time: float, span: float, mean, amplitude, period, phase, slope, profile) -> tuple:
    """(T_amb(time) degC, slope over [time, time + span] degC/s) (``sarins_ambient_segment``)."""
    a, _keep = _ambient(mean, amplitude, period, phase, slope, profile)
    value, rate, msg = _F64(), _F64(), ctypes.create_string_buffer(_MSG_LEN)
    _raise(_ambient_segment(ctypes.byref(a), float(time), float(span), ctypes.byref(value), ctypes.byref(rate),
                            msg, _MSG_LEN), msg)
    return value.value, rate.value
