"""ctypes binding of seed 002's online model update in the C core: the forgetting-factor RLS (``rls.h``),
the stop filter's state (``stop_filter.h``), Fig. 2's row logic (``online.h``) and the RLS model file (``rls.h``
over the binary model file reader ``netfile.h``).

As in :mod:`sarins_fmu.core.ins`, each C struct lives in a numpy byte buffer owned by a Python object, with
numpy views into it at the offsets the library reports (no layout written twice); the structs hold no
pointer, so a copy of the buffer is a copy of the state.  Every function that the core can refuse raises
``ValueError`` with the core's one-line reason.  Units: s, m/s, rad, rad/s, degC.
"""

from __future__ import annotations

import ctypes

import numpy as np

from . import _arrays
from ._lib import function

_I64, _F64, _P, _INT, _SIZE, _STR = (ctypes.c_int64, ctypes.c_double, ctypes.c_void_p, ctypes.c_int, ctypes.c_size_t,
                                      ctypes.c_char_p)
_MSG = 512  # bytes of a reason

N_STATES = 11
# the settings array of stop_filter.h, in order (sarins_fmu.kalman.StopFilterSettings's fields)
STOP_SETTINGS = ("arw", "vrw", "drift_rw", "bias_rw", "velocity_meas_std", "tilt0_std", "heading0_std",
                 "velocity0_std", "drift0_std", "azimuth_drift0_std", "bias0_std", "position0_std")
RLS_FILE_MAX = 4096  # SARINS_RLS_FILE_MAX, bytes: the budget of an RLS model file

_drift_model = function("sarins_drift_model_value", _F64, _P, _F64)
_factor = function("sarins_rls_factor", _F64, _F64, _F64, _F64)
_gain_step = function("sarins_rls_gain_step", None, _P, _P, _P, _F64, _F64)
_check_cov = function("sarins_rls_check_covariance", _INT, _P, _STR, _SIZE)
_rls_init = function("sarins_rls_init", _INT, _P, _P, _P, _F64, _F64, _F64, _STR, _SIZE)
_rls_update = function("sarins_rls_update", _INT, _P, _F64, _F64, _F64, _STR, _SIZE)
_prior = function("sarins_rls_prior_covariance", _INT, _F64, _F64, _F64, _P, _STR, _SIZE)
_rls_check = function("sarins_rls_check", _INT, _P, _STR, _SIZE)
_rls_from_model = function("sarins_rls_from_model", _INT, _P, _SIZE, _P, _STR, _SIZE)
_rls_layout = function("sarins_rls_layout", _I64, _P)
_stop_default = function("sarins_stop_settings_default", None, _P)
_kf_init = function("sarins_stop_kf_init", _INT, _P, _P, _F64, _F64, _STR, _SIZE)
_kf_reset = function("sarins_stop_kf_reset", _INT, _P, _F64, _STR, _SIZE)
_kf_steps = function("sarins_stop_kf_steps", _INT, _P, _I64, _P, _P, _P, _P, _P, _STR, _SIZE)
_kf_estimate = function("sarins_stop_kf_drift_estimate", _F64, _P)
_kf_std = function("sarins_stop_kf_drift_std", _F64, _P)
_kf_mean_temperature = function("sarins_stop_kf_mean_temperature", _F64, _P)
_kf_elapsed = function("sarins_stop_kf_elapsed", _F64, _P)
_kf_check = function("sarins_stop_kf_check", _INT, _P, _STR, _SIZE)
_kf_layout = function("sarins_stop_kf_layout", _I64, _P)
_online_init = function("sarins_online_init", _INT, _P, _F64, _F64, _STR, _SIZE)
_online_finish = function("sarins_online_finish", _INT, _P, _P, _P, _F64, _P, ctypes.POINTER(_INT), _STR, _SIZE)
_online_rows = function("sarins_online_rows", _INT, _P, _P, _P, _I64, _P, _P, _P, _P, _P, _P, _P, _P, _P, _I64,
                        _P, _STR, _SIZE)
_online_check = function("sarins_online_check", _INT, _P, _STR, _SIZE)
_online_layout = function("sarins_online_layout", _I64, _P, _P)


def _layout(fn, count: int) -> tuple[int, np.ndarray]:
    offsets = np.zeros(count, dtype=np.int64)
    return int(fn(offsets.ctypes.data)), offsets


_RLS_SIZE, _RLS_OFF = _layout(_rls_layout, 6)
_KF_SIZE, _KF_OFF = _layout(_kf_layout, 8)
_EVENT_SIZE = np.zeros(1, dtype=np.int64)
_ONLINE_OFF = np.zeros(5, dtype=np.int64)
_ONLINE_SIZE = int(_online_layout(_EVENT_SIZE.ctypes.data, _ONLINE_OFF.ctypes.data))
_EVENT_SIZE = int(_EVENT_SIZE[0])
# sarins_online_event: time, duration, temperature, drift, drift_std (float64), used (int64)
EVENT_DTYPE = np.dtype([("time", "<f8"), ("duration", "<f8"), ("temperature", "<f8"), ("drift", "<f8"),
                        ("drift_std", "<f8"), ("used", "<i8")])
if EVENT_DTYPE.itemsize != _EVENT_SIZE:
    raise ImportError("sarins_online_event has another layout than this binding expects: rebuild the core")


def _buffer(size: int) -> np.ndarray:
    """Zeroed float64 storage (8-byte aligned) of at least ``size`` bytes."""
    return np.zeros((size + 7) // 8)


def _view(buffer: np.ndarray, offset: int, count: int, dtype=np.float64) -> np.ndarray:
    return buffer.view(np.uint8)[offset:offset + 8 * count].view(dtype)


class _Reason:
    """A message buffer for the core's reasons."""

    def __init__(self):
        self.buf = ctypes.create_string_buffer(_MSG)

    def check(self, status: int) -> None:
        if status != 0:
            raise ValueError(self.buf.value.decode(errors="replace"))


# ---------------------------------------------------------------------------------------------- the RLS
def drift_model_value(coefficients, temperature: float) -> float:
    """``sarins_drift_model_value``: (a T + b) T + c."""
    coef = _arrays.read(coefficients, (3,), "coefficients")
    return float(_drift_model(coef.ctypes.data, float(temperature)))


def rls_factor(forgetting_factor: float, dt: float, time_scale: float | None) -> float:
    """``sarins_rls_factor``: lambda^(dt / m), or lambda when ``time_scale`` is None."""
    return float(_factor(float(forgetting_factor), float(dt), 0.0 if time_scale is None else float(time_scale)))


def rls_gain_step(x, p, h, z: float, lam: float) -> tuple[np.ndarray, np.ndarray]:
    """``sarins_rls_gain_step`` on copies of x (3,) and P (3, 3): (x, P) after the step."""
    x = np.array(_arrays.read(x, (3,), "x"))
    p = np.array(_arrays.read(p, (3, 3), "P"))
    h = _arrays.read(h, (3,), "h")
    _gain_step(x.ctypes.data, p.ctypes.data, h.ctypes.data, float(z), float(lam))
    return x, p


def check_covariance(p) -> None:
    """``sarins_rls_check_covariance``: ValueError unless P (3, 3) is finite, symmetric and positive definite."""
    p = _arrays.read(p, (3, 3), "covariance")
    reason = _Reason()
    reason.check(_check_cov(p.ctypes.data, reason.buf, _MSG))


def prior_covariance(points: float, t_min: float, t_max: float) -> np.ndarray:
    """``sarins_rls_prior_covariance``: P0 (3, 3) of a model worth ``points`` calibration points over
    ``t_min`` .. ``t_max`` degC."""
    p0 = np.empty((3, 3))
    reason = _Reason()
    reason.check(_prior(float(points), float(t_min), float(t_max), p0.ctypes.data, reason.buf, _MSG))
    return p0


class RlsState:
    """A ``sarins_rls`` struct.  Views: ``x`` (3,), ``p`` (3, 3); properties ``time``,
    ``forgetting_factor``, ``time_scale`` (None: per update), ``n_updates`` (settable)."""

    def __init__(self, x=None, p=None, time: float = 0.0, forgetting_factor: float = 1.0,
                 time_scale: float | None = None, *, buffer: np.ndarray | None = None):
        self.buffer = _buffer(_RLS_SIZE) if buffer is None else buffer
        o = _RLS_OFF
        self.x, self.p = _view(self.buffer, o[0], 3), _view(self.buffer, o[1], 9).reshape(3, 3)
        self._scalars = {name: _view(self.buffer, o[k], 1) for k, name in
                         ((2, "time"), (3, "forgetting_factor"), (4, "time_scale"))}
        self._n = _view(self.buffer, o[5], 1, np.int64)
        if buffer is None:
            x = _arrays.read(x, (3,), "parameters")
            p = _arrays.read(p, (3, 3), "covariance")
            reason = _Reason()
            reason.check(_rls_init(self.buffer.ctypes.data, x.ctypes.data, p.ctypes.data, float(time),
                                   float(forgetting_factor), 0.0 if time_scale is None else float(time_scale),
                                   reason.buf, _MSG))

    @classmethod
    def from_model_bytes(cls, data: bytes) -> "RlsState":
        """``sarins_rls_from_model``: the state in an RLS model file's bytes (ValueError with the reason)."""
        state = cls(buffer=_buffer(_RLS_SIZE))
        raw = np.frombuffer(bytes(data), dtype=np.uint8)
        reason = _Reason()
        reason.check(_rls_from_model(raw.ctypes.data if raw.size else None, raw.size, state.buffer.ctypes.data,
                                     reason.buf, _MSG))
        return state

    @property
    def time(self) -> float:
        return float(self._scalars["time"][0])

    @property
    def forgetting_factor(self) -> float:
        return float(self._scalars["forgetting_factor"][0])

    @property
    def time_scale(self) -> float | None:
        m = float(self._scalars["time_scale"][0])
        return None if m == 0.0 else m

    @property
    def n_updates(self) -> int:
        return int(self._n[0])

    @n_updates.setter
    def n_updates(self, value: int) -> None:
        self._n[0] = int(value)

    def update(self, temperature: float, drift: float, time: float) -> None:
        """``sarins_rls_update``."""
        reason = _Reason()
        reason.check(_rls_update(self.buffer.ctypes.data, float(temperature), float(drift), float(time), reason.buf,
                                 _MSG))

    def check(self) -> None:
        """``sarins_rls_check``: ValueError unless every field keeps its invariants."""
        reason = _Reason()
        reason.check(_rls_check(self.buffer.ctypes.data, reason.buf, _MSG))


# ---------------------------------------------------------------------------------------- the stop filter
def default_stop_settings() -> np.ndarray:
    """``sarins_stop_settings_default``: (12,) in :data:`STOP_SETTINGS` order."""
    s = np.empty(len(STOP_SETTINGS))
    _stop_default(s.ctypes.data)
    return s


class StopKfState:
    """A ``sarins_stop_kf`` struct.  Views: ``settings`` (12,), ``x`` (11,), ``p`` (11, 11); properties
    ``lat``, ``dt``, ``n`` and the stop's results."""

    def __init__(self, settings, lat: float, dt: float):
        settings = _arrays.read(settings, (len(STOP_SETTINGS),), "stop filter settings")
        self.buffer = _buffer(_KF_SIZE)
        o = _KF_OFF
        self.settings = _view(self.buffer, o[0], len(STOP_SETTINGS))
        self._lat, self._dt = _view(self.buffer, o[1], 1), _view(self.buffer, o[2], 1)
        self.x, self.p = _view(self.buffer, o[3], N_STATES), _view(self.buffer, o[4], N_STATES**2).reshape(11, 11)
        self._n = _view(self.buffer, o[5], 1, np.int64)
        self._sums = (_view(self.buffer, o[6], 1), _view(self.buffer, o[7], 1))
        reason = _Reason()
        reason.check(_kf_init(self.buffer.ctypes.data, settings.ctypes.data, float(lat), float(dt), reason.buf, _MSG))

    @property
    def lat(self) -> float:
        return float(self._lat[0])

    @property
    def dt(self) -> float:
        return float(self._dt[0])

    @property
    def n(self) -> int:
        return int(self._n[0])

    def reset(self, lat: float) -> None:
        reason = _Reason()
        reason.check(_kf_reset(self.buffer.ctypes.data, float(lat), reason.buf, _MSG))

    def steps(self, velocity_en, attitude, correction, temperature) -> np.ndarray:
        """``sarins_stop_kf_steps`` over K rows; returns (K, 2) eps_z estimate and std after each row."""
        velocity_en = _arrays.read(velocity_en, (np.shape(velocity_en)[0], 2), "velocity_en")
        k = velocity_en.shape[0]
        attitude = _arrays.read(attitude, (k, 3), "attitude")
        correction = _arrays.read(correction, (k,), "correction")
        temperature = _arrays.read(temperature, (k,), "temperature")
        out = np.empty((k, 2))
        reason = _Reason()
        reason.check(_kf_steps(self.buffer.ctypes.data, k, velocity_en.ctypes.data, attitude.ctypes.data,
                               correction.ctypes.data, temperature.ctypes.data, out.ctypes.data, reason.buf, _MSG))
        return out

    def elapsed(self) -> float:
        return float(_kf_elapsed(self.buffer.ctypes.data))

    def drift_estimate(self) -> float:
        return float(_kf_estimate(self.buffer.ctypes.data))

    def drift_std(self) -> float:
        return float(_kf_std(self.buffer.ctypes.data))

    def mean_temperature(self) -> float:
        return float(_kf_mean_temperature(self.buffer.ctypes.data))

    def check(self) -> None:
        reason = _Reason()
        reason.check(_kf_check(self.buffer.ctypes.data, reason.buf, _MSG))


# -------------------------------------------------------------------------------------- Fig. 2's logic
class OnlineState:
    """A ``sarins_online`` struct: the thresholds, the stop flag and the event counters."""

    def __init__(self, time_threshold: float, speed_threshold: float):
        self.buffer = _buffer(_ONLINE_SIZE)
        o = _ONLINE_OFF
        self._stopped = _view(self.buffer, o[0], 1, np.int64)
        reason = _Reason()
        reason.check(_online_init(self.buffer.ctypes.data, float(time_threshold), float(speed_threshold), reason.buf,
                                  _MSG))

    @property
    def stopped(self) -> bool:
        return bool(self._stopped[0])

    def rows(self, rls: RlsState, kf: StopKfState, time, speed, velocity_en, attitude, temperature, lat=None,
             active=None) -> tuple[np.ndarray, np.ndarray, str | None]:
        """``sarins_online_rows`` over K rows: (compensation (K,), the finished stops (:data:`EVENT_DTYPE`),
        the reason a row was refused or None; the rows before a refused one are processed)."""
        time = _arrays.read(time, (np.size(time),), "time")
        k = time.shape[0]
        speed = _arrays.read(np.broadcast_to(np.asarray(speed, float), (k,)), (k,), "speed")
        velocity_en = _arrays.read(np.reshape(velocity_en, (k, 2)), (k, 2), "velocity_en")
        attitude = _arrays.read(np.reshape(attitude, (k, 3)), (k, 3), "attitude")
        temperature = _arrays.read(np.broadcast_to(np.asarray(temperature, float), (k,)), (k,), "temperature")
        lat = None if lat is None else _arrays.read(np.broadcast_to(np.asarray(lat, float), (k,)), (k,), "lat")
        act = None if active is None else np.ascontiguousarray(np.broadcast_to(np.asarray(active, bool), (k,)),
                                                                dtype=np.uint8)
        comp = np.zeros(k)
        events = np.zeros(k // 2 + 1, dtype=EVENT_DTYPE)
        n_events = np.zeros(1, dtype=np.int64)
        reason = _Reason()
        status = _online_rows(self.buffer.ctypes.data, rls.buffer.ctypes.data, kf.buffer.ctypes.data, k,
                              time.ctypes.data, speed.ctypes.data, velocity_en.ctypes.data, attitude.ctypes.data,
                              temperature.ctypes.data, None if lat is None else lat.ctypes.data,
                              None if act is None else act.ctypes.data, comp.ctypes.data, events.ctypes.data,
                              events.size, n_events.ctypes.data, reason.buf, _MSG)
        why = None if status == 0 else reason.buf.value.decode(errors="replace")
        return comp, events[:int(n_events[0])], why

    def finish(self, rls: RlsState, kf: StopKfState, time: float) -> np.ndarray:
        """``sarins_online_finish``: the finished stop (0 or 1 rows of :data:`EVENT_DTYPE`)."""
        event = np.zeros(1, dtype=EVENT_DTYPE)
        finished = _INT(0)
        reason = _Reason()
        reason.check(_online_finish(self.buffer.ctypes.data, rls.buffer.ctypes.data, kf.buffer.ctypes.data,
                                    float(time), event.ctypes.data, ctypes.byref(finished), reason.buf, _MSG))
        return event[:finished.value]

    def check(self) -> None:
        reason = _Reason()
        reason.check(_online_check(self.buffer.ctypes.data, reason.buf, _MSG))
