"""ctypes binding of the IMU kernels (``imu.h``): the minor loop, the state advance, the random streams'
seeding, the FMU's step.

Units and frames as in ``imu.h`` and :mod:`sarins_fmu.imu`.  A batch of K
intervals runs in parallel threads (ctypes releases the GIL): the K
independent intervals are split into contiguous chunks, one per thread;
the results do not depend on the thread count.  Threads: ``os.cpu_count()``,
or the environment variable ``SARINS_THREADS``; fewer than
:data:`PARALLEL_MIN` intervals run on the calling thread.
"""

from __future__ import annotations

import ctypes
import os
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from . import _arrays
from ._lib import function
from .rng import check_seed

_I64, _F64, _P, _INT, _U64 = ctypes.c_int64, ctypes.c_double, ctypes.c_void_p, ctypes.c_int, ctypes.c_uint64

_truth = function("sarins_imu_truth", None, _I64, _P, _P, _P, _P, _F64, _P, _P, _P)
_increments = function("sarins_imu_increments", None, _I64, _I64, _I64, _P, _P, _P, _P, _P, _P, _F64, _I64,
                       *([_P] * 13))
_increments_scalar = function("sarins_imu_increments_scalar", None, _I64, _I64, _I64, _P, _P, _P, _P, _P, _P, _F64,
                              _I64, *([_P] * 13))
_advance = function("sarins_imu_advance", _INT, _P, _I64, _I64, *([_P] * 7))
_white_noise = function("sarins_imu_white_noise", _INT, _P, _I64, _I64, _P, _P)
_dynamics = function("sarins_imu_dynamics", _INT, _P, _I64, _I64, _P, _P, _P)
_steps = function("sarins_imu_steps", _INT, _P, _I64, _I64, *([_P] * 10))
_one_interval = function("sarins_imu_one_interval", _INT, _P, _I64, _P, _P, _P, _F64, _P, _P, _P)
_seed = function("sarins_imu_seed", _INT, _P, _I64, _U64)
_turn_on = function("sarins_imu_turn_on", None, _U64, _P, _P)
_aged_poly = function("sarins_imu_aged_poly", None, _U64, _I64, _P, _P, _P, _F64, _P)

PARALLEL_MIN = 64  # intervals; below this a thread hand-off costs more than it saves
_CPUS = os.cpu_count() or 1  # (os.cpu_count() takes tens of microseconds: asked once)
_ERRORS = {1: "the IMU state table does not fit the layout of sarins_fmu.imu_step (imu.h), or a random stream "
              "state in it is not one"}
MAX_SUB = 2 ** 30  # minor steps per output interval (SARINS_IMU_MAX_SUB in imu.h)
STREAMS = ("white", "gm", "flicker", "rrw", "turn_on", "ageing")  # stream ids 0.. (SARINS_IMU_STREAM_* in imu.h)
PERIODIC_STREAM = len(STREAMS)  # id of the periodic phases' stream, drawn at seeding only (not a table row)
_POOLS: dict[tuple, ThreadPoolExecutor] = {}
_POOLS_LOCK = threading.Lock()


def thread_count() -> int:
    """Threads of a batch: ``SARINS_THREADS`` if set (a positive integer), else ``os.cpu_count()``."""
    text = os.environ.get("SARINS_THREADS", "").strip()
    if not text:
        return _CPUS
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise ValueError(f"SARINS_THREADS must be a positive integer, got {text!r}")
    return value


def _pool(workers: int) -> ThreadPoolExecutor:
    """A pool of ``workers`` threads of this process (a forked child, e.g. a campaign worker, makes its own:
    the parent's pool has no threads there)."""
    key = (os.getpid(), workers)
    with _POOLS_LOCK:
        if key not in _POOLS:
            _POOLS[key] = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="sarins-core")
        return _POOLS[key]


def _check(status: int) -> None:
    if status != 0:
        raise ValueError(_ERRORS.get(status, f"IMU core call failed with code {status}"))


def truth(axes, angle0, rate0, accel, k: int, tau: float, w_t, f_t) -> tuple:
    """True omega_ib_b (rad/s) and f_b (m/s^2) at tau s into interval k: (wx, wy, wz, fx, fy, fz).

    axes (A, 3); angle0, rate0, accel (K, A) gimbal state at each interval
    start; w_t, f_t (K, 3) the base frame's inertial rate and specific force
    resolved in t."""
    axes = _arrays.read(axes, np.shape(axes), "axes")
    n_axes = axes.shape[0]
    rows = [_arrays.read(a, np.shape(a), name)[k] for a, name in ((angle0, "angle0"), (rate0, "rate0"),
                                                                 (accel, "accel"), (w_t, "w_t"), (f_t, "f_t"))]
    if axes.shape != (n_axes, 3) or any(r.shape != (n_axes,) for r in rows[:3]) or any(r.shape != (3,) for r in rows[3:]):
        raise ValueError("truth needs axes (A, 3), gimbal states (K, A) and base motion (K, 3)")
    out = np.empty(6)
    rows = [np.ascontiguousarray(r) for r in rows]
    _truth(n_axes, axes.ctypes.data, *(r.ctypes.data for r in rows[:3]), float(tau), rows[3].ctypes.data,
           rows[4].ctypes.data, out.ctypes.data)
    return tuple(float(x) for x in out)


def increments(axes, angle0, rate0, accel, w_t, f_t, h, n_sub,
               g_sf, g_mis, g_bias, g_quad, g_lowrate, g_lowrate_width, g_sens,
               a_sf, a_mis, a_bias, a_quad, *, threads: int | None = None, lanes: bool = True):
    """Compensated increments of K intervals: dtheta, dv (K, 3), rad and m/s, body axes at each interval start.

    axes (A, 3) gimbal axes; angle0, rate0, accel (K, A) gimbal state at each
    interval start (rad, rad/s, rad/s^2); w_t, f_t (K, 3) base inertial rate
    (rad/s) and specific force (m/s^2) resolved in t; h interval (s); n_sub
    minor steps per interval; g_sf, a_sf, g_bias, a_bias (K, 3) scale-factor
    errors and biases (rad/s, m/s^2); g_mis, a_mis (3, 3) misalignment (rad);
    g_quad, a_quad (3,) x|x| coefficients; g_lowrate, g_lowrate_width (3,)
    low-rate nonlinearity; g_sens (3, 3) g-sensitivity (rad/s per m/s^2).
    ``threads``: default :func:`thread_count`.  ``lanes=False`` evaluates one interval at a time
    (``sarins_imu_increments_scalar``: the reference of the interval lanes, the same results, slower).
    """
    axes = _arrays.read(axes, np.shape(axes), "axes")
    n_axes = axes.shape[0]
    if axes.shape != (n_axes, 3) or n_axes < 1:
        raise ValueError(f"axes must have shape (A, 3), got {axes.shape}")
    n_int = np.shape(angle0)[0]
    per_k = [_arrays.read(a, (n_int, cols), name) for a, cols, name in (
        (angle0, n_axes, "angle0"), (rate0, n_axes, "rate0"), (accel, n_axes, "accel"), (w_t, 3, "w_t"),
        (f_t, 3, "f_t"), (g_sf, 3, "g_sf"), (g_bias, 3, "g_bias"), (a_sf, 3, "a_sf"), (a_bias, 3, "a_bias"))]
    fixed = [_arrays.read(a, shape, name) for a, shape, name in (
        (g_mis, (3, 3), "g_mis"), (g_quad, (3,), "g_quad"), (g_lowrate, (3,), "g_lowrate"),
        (g_lowrate_width, (3,), "g_lowrate_width"), (g_sens, (3, 3), "g_sens"), (a_mis, (3, 3), "a_mis"),
        (a_quad, (3,), "a_quad"))]
    n_sub = _arrays.count(n_sub, "n_sub (minor steps per interval)")
    h = _arrays.positive_finite(h, "h (interval, s)")
    angle0, rate0, accel, w_t, f_t, g_sf, g_bias, a_sf, a_bias = (a.ctypes.data for a in per_k)
    g_mis, g_quad, g_lowrate, g_width, g_sens, a_mis, a_quad = (a.ctypes.data for a in fixed)
    dtheta, dv = np.empty((n_int, 3)), np.empty((n_int, 3))

    kernel = _increments if lanes else _increments_scalar

    def run(k0: int, k1: int) -> None:
        kernel(k0, k1, n_axes, axes.ctypes.data, angle0, rate0, accel, w_t, f_t, float(h), n_sub,
                    g_sf, g_mis, g_bias, g_quad, g_lowrate, g_width, g_sens, a_sf, a_mis, a_bias, a_quad,
                    dtheta.ctypes.data, dv.ctypes.data)

    if threads is not None and int(threads) < 1:
        raise ValueError(f"threads must be a positive integer, got {threads}")
    workers = 1
    if n_int >= PARALLEL_MIN:
        workers = min(thread_count() if threads is None else int(threads), n_int)
    if workers == 1:
        run(0, n_int)
    else:
        bounds = [n_int * i // workers for i in range(workers + 1)]
        futures = [_pool(workers - 1).submit(run, bounds[i], bounds[i + 1]) for i in range(workers - 1)]
        run(bounds[-2], bounds[-1])
        for f in futures:
            f.result()
    return dtheta, dv


def advance(table, amb_end, temps, g_bias, g_sf, a_bias, a_sf) -> None:
    """Advance the thermal and error states of the IMU ``table`` over K intervals (``imu.h``):
    amb_end (K,) ambient at the ends (degC, checked by the caller); temps (K, 6), g_bias, g_sf,
    a_bias, a_sf (K, 3) out."""
    table = _arrays.table(table)
    amb_end = _arrays.read(amb_end, np.shape(amb_end)[:1], "amb_end")
    n = amb_end.shape[0]
    _arrays.written(temps, (n, 6), "temps")
    for a, name in ((g_bias, "g_bias"), (g_sf, "g_sf"), (a_bias, "a_bias"), (a_sf, "a_sf")):
        _arrays.written(a, (n, 3), name)
    die = np.empty((n, 6))
    _check(_advance(table.ctypes.data, table.shape[0], n, amb_end.ctypes.data, temps.ctypes.data, die.ctypes.data,
                    g_bias.ctypes.data, g_sf.ctypes.data, a_bias.ctypes.data, a_sf.ctypes.data))


def steps(table, angle0, rate0, accel, w_t, f_t, amb_end):
    """K intervals of the IMU ``table`` in one call on this thread (``sarins_imu_steps``: advance, minor
    loop, white noise): angle0, rate0, accel (K, A) gimbal state, w_t, f_t (K, 3) base motion, amb_end (K,)
    ambient at the ends (degC, checked by the caller).  Returns dtheta, dv (K, 3) and temps (K, 6)."""
    table = _arrays.table(table)
    n = np.shape(amb_end)[0]
    n_axes = int(table[7, 1]) if table.shape[0] > 7 else 0
    angle0, rate0, accel = (_arrays.read(a, (n, n_axes), name) for a, name in (
        (angle0, "angle0"), (rate0, "rate0"), (accel, "accel")))
    w_t, f_t = _arrays.read(w_t, (n, 3), "w_t"), _arrays.read(f_t, (n, 3), "f_t")
    amb_end = _arrays.read(amb_end, (n,), "amb_end")
    dtheta, dv, temps, work = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 6)), np.empty((n, 18))
    _check(_steps(table.ctypes.data, table.shape[0], n, angle0.ctypes.data, rate0.ctypes.data, accel.ctypes.data,
                  w_t.ctypes.data, f_t.ctypes.data, amb_end.ctypes.data, dtheta.ctypes.data, dv.ctypes.data,
                  temps.ctypes.data, work.ctypes.data))
    return dtheta, dv, temps


def dynamics(table, temps, dtheta, dv) -> None:
    """Apply the output dynamics (``dynamics.h``: size effect, rate hysteresis, output filter) to K intervals'
    increments (K, 3), in place, in time order; temps (K, 6) reported temperatures at the interval ends (degC)."""
    table = _arrays.table(table)
    n = np.shape(dtheta)[0]
    temps = _arrays.read(temps, (n, 6), "temps")
    _arrays.written(dtheta, (n, 3), "dtheta")
    _arrays.written(dv, (n, 3), "dv")
    _check(_dynamics(table.ctypes.data, table.shape[0], n, temps.ctypes.data, dtheta.ctypes.data, dv.ctypes.data))


def white_noise(table, dtheta, dv) -> None:
    """Add the angle / velocity random walk to K intervals' increments (K, 3), in place; moves the clock on."""
    table = _arrays.table(table)
    n = np.shape(dtheta)[0]
    _arrays.written(dtheta, (n, 3), "dtheta")
    _arrays.written(dv, (n, 3), "dv")
    _check(_white_noise(table.ctypes.data, table.shape[0], n, dtheta.ctypes.data, dv.ctypes.data))


def one_interval(table, angle0, rate0, accel, amb_end: float):
    """One output interval with the base motion of the table's base row (the FMU's step): angle0, rate0,
    accel (A,) gimbal state at its start, amb_end ambient at its end (degC).  Returns dtheta (3,), dv (3,),
    temps (6,)."""
    table = _arrays.table(table)
    n_axes = int(table[7, 1]) if table.shape[0] > 7 else 0
    angle0, rate0, accel = (_arrays.read(a, (n_axes,), name) for a, name in (
        (angle0, "angle0"), (rate0, "rate0"), (accel, "accel")))
    dtheta, dv, temps = np.empty(3), np.empty(3), np.empty(6)
    _check(_one_interval(table.ctypes.data, table.shape[0], angle0.ctypes.data, rate0.ctypes.data,
                         accel.ctypes.data, float(amb_end), dtheta.ctypes.data, dv.ctypes.data, temps.ctypes.data))
    return dtheta, dv, temps


def seed(table, value: int) -> None:
    """Start the random streams of the IMU ``table`` from the seed ``value`` (``sarins_imu_seed``): the streams
    at their start, the Gauss-Markov and flicker states' stationary start, the turn-on bias, the periodic
    terms' phases."""
    table = _arrays.table(table)
    _check(_seed(table.ctypes.data, table.shape[0], check_seed(value)))


def turn_on(value: int, std) -> np.ndarray:
    """The turn-on bias (6,) an IMU with seed ``value`` draws: std (6,) times the TURN_ON stream's first 6
    draws (gyro rad/s, accelerometer m/s^2)."""
    std = _arrays.read(std, (6,), "std")
    out = np.empty(6)
    _turn_on(check_seed(value), std.ctypes.data, out.ctypes.data)
    return out


def aged_poly(value: int, ages, poly, sigma, tau: float) -> np.ndarray:
    """(K, 3) azimuth-drift coefficients poly + m(t_k) at the increasing ages (K,) (s), m the first-order Markov
    ageing of std sigma (3,) and correlation time tau (s) from the AGEING stream of seed ``value``."""
    ages = _arrays.read(ages, np.shape(ages)[:1], "ages")
    poly, sigma = _arrays.read(poly, (3,), "poly"), _arrays.read(sigma, (3,), "sigma")
    if not float(tau) > 0:
        raise ValueError(f"the ageing correlation time must be positive, got {tau}")
    out = np.empty((ages.shape[0], 3))
    _aged_poly(check_seed(value), ages.shape[0], ages.ctypes.data, poly.ctypes.data, sigma.ctypes.data,
               float(tau), out.ctypes.data)
    return out


# ------------------------------------------------------------------ construction (imu_build.h, imu_params.h)

_build = function("sarins_imu_build", _INT, _P, _I64, _P, _F64, _F64, _I64, _F64, _U64)
_start = function("sarins_imu_start", _INT, _P, _I64, _F64, _INT, _U64)
_flicker_count = function("sarins_imu_flicker_count", _I64, _F64, _F64)
_flicker_taus = function("sarins_imu_flicker_taus", None, _F64, _F64, _I64, _P)
_check_params = function("sarins_imu_check_params", _I64, _P, ctypes.POINTER(ctypes.c_char_p))
_check_rate_params = function("sarins_imu_check_rate_params", _I64, _P, _F64, ctypes.POINTER(_F64),
                              ctypes.POINTER(ctypes.c_char_p))
_param_bound = function("sarins_imu_param_bound", _INT, _P, _F64, _I64, ctypes.POINTER(_F64),
                        ctypes.POINTER(ctypes.c_char_p))
_max_rate = function("sarins_imu_max_rate", _F64, _F64)
LOWER_BOUND = "at least: "  # a check's rule that gives a lower bound (SARINS_IMU_LOWER_BOUND in imu_build.h)
AMBIENT_MAX = 500.0  # degC: the highest ambient the IMU accepts (SARINS_IMU_AMBIENT_MAX in imu_build.h)
_check_periodic_params = function("sarins_imu_check_periodic_params", _I64, _P, _F64,
                                  ctypes.POINTER(ctypes.c_char_p))
_param_name = function("sarins_imu_param_name", ctypes.c_char_p, _I64)
_preset_name = function("sarins_imu_preset_name", ctypes.c_char_p, _I64)
_preset_params = function("sarins_imu_preset_params", _INT, ctypes.c_char_p, _P)


def param_names() -> tuple:
    """The flat parameters' names in the C core's order (``imu_params.h``)."""
    names, i = [], 0
    while (name := _param_name(i)) is not None:
        names.append(name.decode())
        i += 1
    return tuple(names)


N_PARAMS = len(param_names())


def preset_names() -> tuple:
    """The presets the C core holds as data (``imu_params.c``)."""
    names, i = [], 0
    while (name := _preset_name(i)) is not None:
        names.append(name.decode())
        i += 1
    return tuple(names)


def preset_params(name: str) -> np.ndarray:
    """The flat parameter vector (N_PARAMS,) of the C core's preset ``name``."""
    out = np.empty(N_PARAMS)
    if _preset_params(str(name).encode(), out.ctypes.data) != 0:
        raise ValueError(f"the C core has no IMU preset {name!r}")
    return out


def check_params(par) -> str | None:
    """None when the flat parameter vector (N_PARAMS,) is a valid IMU model, else "<name> <rule>"."""
    par = _arrays.read(par, (N_PARAMS,), "par")
    reason = ctypes.c_char_p()
    bad = _check_params(par.ctypes.data, ctypes.byref(reason))
    return None if bad < 0 else f"{_param_name(bad).decode()} {reason.value.decode()}"


def check_rate_params(par, internal_rate: float) -> str | None:
    """None when the bounds the core derives at the minor-loop rate internal_rate (Hz) hold
    (``sarins_imu_param_bound``), else "<name> = <value> is outside [-bound, bound] ...: <rule>"."""
    par = _arrays.read(par, (N_PARAMS,), "par")
    reason, bound = ctypes.c_char_p(), ctypes.c_double()
    bad = _check_rate_params(par.ctypes.data, float(internal_rate), ctypes.byref(bound), ctypes.byref(reason))
    if bad < 0:
        return None
    b, rule = bound.value, reason.value.decode()
    if rule.startswith(LOWER_BOUND):  # a lower bound (imu_build.h SARINS_IMU_LOWER_BOUND)
        return (f"{_param_name(bad).decode()} = {float(par[bad])!r} is below {b!r} at internal_rate "
                f"{float(internal_rate)!r} Hz: {rule[len(LOWER_BOUND):]}")
    return (f"{_param_name(bad).decode()} = {float(par[bad])!r} is outside [{-b!r}, {b!r}] at internal_rate "
            f"{float(internal_rate)!r} Hz: {rule}")


def param_bound(par, internal_rate: float, index: int) -> float | None:
    """The bound the core derives on |par[index]| at the minor-loop rate internal_rate (Hz), the other
    parameters as in ``par`` (``sarins_imu_param_bound``), in the parameter's unit; None when it has none."""
    par = _arrays.read(par, (N_PARAMS,), "par")
    reason, bound = ctypes.c_char_p(), ctypes.c_double()
    if not 0 <= int(index) < N_PARAMS:
        raise ValueError(f"no IMU parameter {index}")
    found = _param_bound(par.ctypes.data, float(internal_rate), int(index), ctypes.byref(bound), ctypes.byref(reason))
    return bound.value if found else None


def max_rate(internal_rate: float) -> float:
    """The largest body rate per axis (rad/s) the model supports at the minor-loop rate internal_rate (Hz):
    pi/8 rad per minor step, at most 100 rad/s (``sarins_imu_max_rate``)."""
    return _max_rate(float(internal_rate))


def check_periodic_params(par, internal_rate: float) -> str | None:
    """None when the periodic terms' frequencies are at most internal_rate / 2 (Hz), else "<name> = <value>
    Hz <rule> (internal_rate <value> Hz)"."""
    par = _arrays.read(par, (N_PARAMS,), "par")
    reason = ctypes.c_char_p()
    bad = _check_periodic_params(par.ctypes.data, float(internal_rate), ctypes.byref(reason))
    if bad < 0:
        return None
    return (f"{_param_name(bad).decode()} = {float(par[bad])!r} Hz {reason.value.decode()} (internal_rate "
            f"{float(internal_rate)!r} Hz)")


def flicker_count(tau_min: float, tau_max: float) -> int:
    """Number of Gauss-Markov terms of the flicker synthesis for the band [tau_min, tau_max] (s)."""
    n = _flicker_count(float(tau_min), float(tau_max))
    if n < 1:
        raise ValueError("flicker correlation times need 0 < flicker_tau_min < flicker_tau_max (finite)")
    return n


def flicker_taus(tau_min: float, tau_max: float) -> np.ndarray:
    """The flicker terms' correlation times (F,), s, log-spaced over [tau_min, tau_max]."""
    out = np.empty(flicker_count(tau_min, tau_max))
    _flicker_taus(float(tau_min), float(tau_max), out.shape[0], out.ctypes.data)
    return out


def build(table, par, t0: float, h: float, n_sub: int, age: float, value: int) -> None:
    """Fill the IMU ``table``'s constant arrays from the flat parameters ``par`` (``sarins_imu_build``): start
    time t0 (s), interval h (s), n_sub minor steps, the drift model aged by ``age`` (s) with seed ``value``."""
    table = _arrays.table(table)
    par = _arrays.read(par, (N_PARAMS,), "par")
    problem = check_params(par)
    n_sub = _arrays.count(n_sub, "n_sub (minor steps per interval)")
    if problem is None and float(h) > 0.0:
        problem = check_rate_params(par, n_sub / float(h))
    if problem is None and float(h) > 0.0:
        problem = check_periodic_params(par, n_sub / float(h))
    if problem is not None:
        raise ValueError(f"IMU parameter {problem}")
    _check(_build(table.ctypes.data, table.shape[0], par.ctypes.data, float(t0), float(h), n_sub, float(age),
                  check_seed(value)))


def start(table, ambient0: float, hot: bool, value: int) -> None:
    """Start a run of the built ``table`` (``sarins_imu_start``): ambient0 degC at the start, hot or cold,
    the random streams from seed ``value``."""
    table = _arrays.table(table)
    _check(_start(table.ctypes.data, table.shape[0], float(ambient0), int(bool(hot)), check_seed(value)))
