"""ctypes binding of the aided-navigation kernels: trajectory truth (``traj.h``), the aided IMU's errors
(``aided_imu.h``), the 3-D strapdown mechanization (``nav3.h``), the GNSS receiver (``gnss.h``) and the
error-state Kalman filter (``eskf.h``)."""

from __future__ import annotations

import ctypes

import numpy as np

from . import _arrays
from ._lib import function

_I64, _F64, _P = ctypes.c_int64, ctypes.c_double, ctypes.c_void_p

TRAJ_ROW = 15  # truth row of traj.h
NAV_ROW = 9  # output row of nav3.h

_traj_run = function("sarins_traj_run", ctypes.c_int, _I64, _P, _P, _F64, _I64, _I64, _P, _P, _P)
_nav3_steps = function("sarins_nav3_steps", ctypes.c_int, _I64, _P, _P, _P, _P, _P, _F64, _P)
_quat_to_rotvec = function("sarins_quat_to_rotvec", None, _P, _P)
_aided_imu_run = function("sarins_aided_imu_run", ctypes.c_int, _P, _F64, ctypes.c_uint64, _I64, _P, _P, _P, _P, _P)


def traj_run(segments, start, step: float, substeps: int):
    """``sarins_traj_run``: truth rows (K+1, 15), dtheta (K, 3) rad, dv (K, 3) m/s for a segment
    table (n, 4) (steps, accel m/s^2, yaw rate rad/s, pitch rate rad/s) from start (6) (lat, lon rad,
    height m, speed m/s, yaw, pitch rad).  ValueError when the core refuses the arguments."""
    seg = _arrays.read(segments, (np.shape(segments)[0], 4), "segment table")
    start = _arrays.read(start, (6,), "trajectory start")
    k = int(round(float(np.sum(seg[:, 0]))))
    if k < 1:
        raise ValueError("the trajectory has no IMU step")
    truth, dtheta, dv = np.empty((k + 1, TRAJ_ROW)), np.empty((k, 3)), np.empty((k, 3))
    if _traj_run(seg.shape[0], seg.ctypes.data, start.ctypes.data, float(step), int(substeps), k,
                 truth.ctypes.data, dtheta.ctypes.data, dv.ctypes.data) != 0:
        raise ValueError("the trajectory leaves the valid range (negative speed, |pitch| >= 89 deg, "
                         "|latitude| >= 89.9 deg) or has a non-finite value")
    return truth, dtheta, dv


def aided_imu_run(config, step: float, seed: int, dtheta_true, dv_true):
    """``sarins_aided_imu_run``: the ideal increments (K, 3) rad and m/s with the IMU errors of config (6)
    (arw, vrw, gyro_bias_std, accel_bias_std, gyro_rw, accel_rw, SI) over steps of ``step`` s, seeded;
    returns dtheta, dv (K, 3) and the biases over each step (K, 6: gyro rad/s, accelerometer m/s^2)."""
    config = _arrays.read(config, (6,), "IMU noise settings")
    dtheta_true = _arrays.read(dtheta_true, (np.shape(dtheta_true)[0], 3), "dtheta")
    k = dtheta_true.shape[0]
    dv_true = _arrays.read(dv_true, (k, 3), "dv")
    dtheta, dv, bias = np.empty((k, 3)), np.empty((k, 3)), np.empty((k, 6))
    if _aided_imu_run(config.ctypes.data, float(step), int(seed) % 2**64, k, dtheta_true.ctypes.data,
                      dv_true.ctypes.data, dtheta.ctypes.data, dv.ctypes.data, bias.ctypes.data) != 0:
        raise ValueError("IMU noise settings must be finite and >= 0 and the step positive")
    return dtheta, dv, bias


def nav3_steps(q, v, pos, dtheta, dv, step: float) -> np.ndarray:
    """``sarins_nav3_steps``: q (4), v (3), pos (3) float64 arrays advanced in place over K steps;
    returns the (K, 9) rows (lat, lon, h, v E N U, yaw, pitch, roll)."""
    dtheta = _arrays.read(dtheta, (np.shape(dtheta)[0], 3), "dtheta")
    k = dtheta.shape[0]
    dv = _arrays.read(dv, (k, 3), "dv")
    q, v, pos = _arrays.written(q, (4,), "q"), _arrays.written(v, (3,), "v"), _arrays.written(pos, (3,), "pos")
    out = np.empty((k, NAV_ROW))
    if _nav3_steps(k, q.ctypes.data, v.ctypes.data, pos.ctypes.data, dtheta.ctypes.data, dv.ctypes.data,
                   float(step), out.ctypes.data) != 0:
        raise ValueError("increments contain NaN or infinity, or the step is not positive")
    return out


def quat_to_rotvec(q) -> np.ndarray:
    """Rotation vector (rad) of a unit quaternion [w x y z]."""
    q = _arrays.read(q, (4,), "q")
    phi = np.empty(3)
    _quat_to_rotvec(q.ctypes.data, phi.ctypes.data)
    return phi


GNSS_CONFIG = 17  # settings of gnss.h
GNSS_OUT = 7
_gnss_size = function("sarins_gnss_size", _I64)
_gnss_init = function("sarins_gnss_init", ctypes.c_int, _P, _P, ctypes.c_uint64, ctypes.c_char_p, ctypes.c_size_t)
_gnss_fixes = function("sarins_gnss_fixes", ctypes.c_int, _P, _I64, _P, _P, _P, _I64, _P, _P)


class GnssState:
    """A ``sarins_gnss`` struct (gnss.h) in a numpy buffer; ValueError with the core's reason for bad
    settings."""

    def __init__(self, config, seed: int):
        config = _arrays.read(config, (GNSS_CONFIG,), "GNSS settings")
        self.buffer = np.zeros((int(_gnss_size()) + 7) // 8)
        msg = ctypes.create_string_buffer(256)
        if _gnss_init(self.buffer.ctypes.data, config.ctypes.data, int(seed), msg, 256) != 0:
            raise ValueError(msg.value.decode())

    def fixes(self, time, truth, omega_ib, outages) -> np.ndarray:
        """(n, 7) fix rows (valid, lat, lon, h, v E N U) at ``time`` (n,) from truth (n, 9) and
        omega_ib (n, 3); outages (m, 2) [start, end) s."""
        time = _arrays.read(time, (np.shape(time)[0],), "time")
        n = time.shape[0]
        truth = _arrays.read(truth, (n, 9), "truth")
        omega_ib = _arrays.read(omega_ib, (n, 3), "omega_ib")
        outages = _arrays.read(np.reshape(outages, (-1, 2)), (np.size(outages) // 2, 2), "outages")
        out = np.empty((n, GNSS_OUT))
        if _gnss_fixes(self.buffer.ctypes.data, n, time.ctypes.data, truth.ctypes.data, omega_ib.ctypes.data,
                       outages.shape[0], outages.ctypes.data, out.ctypes.data) != 0:
            raise ValueError("GNSS epochs must be finite and increasing, the truth finite")
        return out


ESKF_CONFIG = 20  # settings of eskf.h
ESKF_OPT = 13  # options of the optional states (eskf.h SARINS_ESKF_OPT)
ESKF_SF, ESKF_LEVER, ESKF_GNSS_POS_GM, ESKF_GNSS_VEL_GM = 1, 2, 4, 8  # bits of option 0 (SARINS_ESKF_STATES)
ESKF_ROW = 9 + 6 + 225  # an output row with P (15 states)
ESKF_ROW_DIAG = 9 + 6 + 15  # an output row with P's diagonal only (15 states)
ESKF_AID = 10  # columns of the aid row (eskf.h SARINS_ESKF_AID)
ESKF_GNSS = 11
_eskf_size = function("sarins_eskf_size", _I64)
_eskf_init = function("sarins_eskf_init", ctypes.c_int, _P, _P, _P, ctypes.c_char_p, ctypes.c_size_t)
_eskf_init_states = function("sarins_eskf_init_states", ctypes.c_int, _P, _P, _P, _P, ctypes.c_char_p,
                             ctypes.c_size_t)
_eskf_dim = function("sarins_eskf_dim", _I64, _P)
_eskf_run = function("sarins_eskf_run", ctypes.c_int, _P, _I64, _P, _P, _P, _I64, _P, _P, ctypes.c_int, _I64,
                     ctypes.c_int, _P)


class EskfState:
    """A ``sarins_eskf`` struct (eskf.h) in a numpy buffer; ValueError with the core's reason."""

    def __init__(self, config, nav0, options=None):
        """options: the optional states' settings (ESKF_OPT, eskf.h SARINS_ESKF_OPT) or None (the 15 states)."""
        config = _arrays.read(config, (ESKF_CONFIG,), "filter settings")
        nav0 = _arrays.read(nav0, (9,), "start state")
        self.buffer = np.zeros((int(_eskf_size()) + 7) // 8)
        msg = ctypes.create_string_buffer(256)
        if options is None:
            bad = _eskf_init(self.buffer.ctypes.data, config.ctypes.data, nav0.ctypes.data, msg, 256)
        else:
            options = _arrays.read(options, (ESKF_OPT,), "filter state options")
            bad = _eskf_init_states(self.buffer.ctypes.data, config.ctypes.data, options.ctypes.data,
                                    nav0.ctypes.data, msg, 256)
        if bad != 0:
            raise ValueError(msg.value.decode())
        self.n = int(_eskf_dim(self.buffer.ctypes.data))  # states: 15 .. 30

    def run(self, dtheta, dv, aid, gnss, vel_std, use_vel: bool, out_every: int, full_cov: bool = True) -> np.ndarray:
        """``sarins_eskf_run`` over K steps (aid (K, 10): ZUPT flag, measured velocity at a stop (3), odometer
        flag, odometer speed, NHC flag, measured lateral and vertical body velocity, ZARU flag); returns the
        (K // out_every, 240) rows (nav 9, b_g 3, b_a 3, P 225), or with ``full_cov`` False the
        (K // out_every, 30) rows with P's diagonal (15) in place of P.  With n states: nav 9, b_g, b_a, the
        optional blocks' estimates (n - 15), then P (n, n) or its diagonal: n + n^2 or 2 n columns."""
        dtheta = _arrays.read(dtheta, (np.shape(dtheta)[0], 3), "dtheta")
        k = dtheta.shape[0]
        dv = _arrays.read(dv, (k, 3), "dv")
        aid = _arrays.read(aid, (k, ESKF_AID), "per-step aiding")
        gnss = _arrays.read(np.reshape(gnss, (-1, ESKF_GNSS)), (np.size(gnss) // ESKF_GNSS, ESKF_GNSS), "fixes")
        vel_std = _arrays.read(vel_std, (3,), "velocity std")
        out = np.empty((k // out_every, self.n + self.n**2 if full_cov else 2 * self.n))
        if _eskf_run(self.buffer.ctypes.data, k, dtheta.ctypes.data, dv.ctypes.data, aid.ctypes.data, gnss.shape[0],
                     gnss.ctypes.data, vel_std.ctypes.data, int(bool(use_vel)), int(out_every), int(bool(full_cov)),
                     out.ctypes.data) != 0:
            raise ValueError("filter inputs not finite, fixes not in step order, or a velocity std not positive")
        return out


ODO_CONFIG = 3
_odo_size = function("sarins_odo_size", _I64)
_odo_init = function("sarins_odo_init", ctypes.c_int, _P, _P, ctypes.c_uint64, ctypes.c_char_p, ctypes.c_size_t)
_odo_speeds = function("sarins_odo_speeds", ctypes.c_int, _P, _I64, _P, _P)
_odo_forward_speed_n = function("sarins_odo_forward_speed_n", None, _I64, _P, _P, _P)


def odo_forward_speed(velocity_n, attitude) -> np.ndarray:
    """``sarins_odo_forward_speed_n``: forward (body y) speeds (n,) m/s of velocities (n, 3) ENU m/s seen from
    attitudes (n, 3) yaw, pitch, roll rad: (mat_bn v^n)_y, the odometer's true speed."""
    velocity_n = _arrays.read(velocity_n, (np.shape(velocity_n)[0], 3), "velocity")
    n = velocity_n.shape[0]
    attitude = _arrays.read(attitude, (n, 3), "attitude")
    out = np.empty(n)
    _odo_forward_speed_n(n, velocity_n.ctypes.data, attitude.ctypes.data, out.ctypes.data)
    return out


class OdoState:
    """A ``sarins_odo`` struct (odo.h): settings (scale factor, noise std m/s, resolution m/s), seed."""

    def __init__(self, config, seed: int):
        config = _arrays.read(config, (ODO_CONFIG,), "odometer settings")
        self.buffer = np.zeros((int(_odo_size()) + 7) // 8)
        msg = ctypes.create_string_buffer(256)
        if _odo_init(self.buffer.ctypes.data, config.ctypes.data, int(seed), msg, 256) != 0:
            raise ValueError(msg.value.decode())

    def speeds(self, speed) -> np.ndarray:
        """Measured speeds (n,) m/s of the true forward speeds (n,)."""
        speed = _arrays.read(speed, (np.shape(speed)[0],), "speed")
        out = np.empty(speed.shape[0])
        if _odo_speeds(self.buffer.ctypes.data, speed.shape[0], speed.ctypes.data, out.ctypes.data) != 0:
            raise ValueError("odometer speeds must be finite")
        return out


AID_NOISE_DRAWS = 5  # normals per IMU step of aid_noise.h
_aid_noise_run = function("sarins_aid_noise_run", ctypes.c_int, _F64, _F64, ctypes.c_uint64, _I64, _P, _P, _P)
_aid_still_n = function("sarins_aid_still_n", None, _I64, _P, _P)


def aid_noise_run(zupt_std: float, nhc_std: float, seed: int, zupt, nhc) -> np.ndarray:
    """``sarins_aid_noise_run``: the ZUPT and NHC pseudo-measurements' jitter over K steps (aid_noise.h, stream
    33 of ``seed``) for the flags zupt (K,) and nhc (K,) (0 / 1): (K, 5) = ZUPT velocity E, N, U and NHC
    velocity body x, z (m/s), (flag std) n with five normals drawn per step whatever the flags."""
    zupt = np.ascontiguousarray(zupt, dtype=np.int32)
    nhc = np.ascontiguousarray(nhc, dtype=np.int32)
    if zupt.ndim != 1 or nhc.shape != zupt.shape:
        raise ValueError("zupt and nhc flags must be two (K,) arrays")
    out = np.empty((zupt.shape[0], AID_NOISE_DRAWS))
    if _aid_noise_run(float(zupt_std), float(nhc_std), int(seed) % 2**64, zupt.shape[0], zupt.ctypes.data,
                      nhc.ctypes.data, out.ctypes.data) != 0:
        raise ValueError("the ZUPT and NHC stds must be finite and >= 0 and the flags 0 or 1")
    return out


def aid_still(velocity_n) -> np.ndarray:
    """``sarins_aid_still_n``: (K,) bool, the steps between K + 1 velocities (K + 1, 3) ENU m/s over which
    the vehicle stands still (speed below 1e-9 m/s at both ends)."""
    velocity_n = _arrays.read(velocity_n, (np.shape(velocity_n)[0], 3), "velocity")
    n = max(velocity_n.shape[0] - 1, 0)
    out = np.zeros(n, dtype=np.int32)
    _aid_still_n(n, velocity_n.ctypes.data, out.ctypes.data)
    return out.astype(bool)


ZVD_CONFIG = 5
_zvd_size = function("sarins_zvd_size", _I64)
_zvd_init = function("sarins_zvd_init", ctypes.c_int, _P, _P, ctypes.c_char_p, ctypes.c_size_t)
_zvd_run = function("sarins_zvd_run", ctypes.c_int, _P, _I64, _P, _P, _P, _P)


class ZvdState:
    """A ``sarins_zvd`` struct (zvd.h): settings (window N samples, step s, vrw m/s/sqrt(s), arw
    rad/sqrt(s), threshold gamma); keeps its window between calls."""

    def __init__(self, config):
        config = _arrays.read(config, (ZVD_CONFIG,), "zero-velocity detector settings")
        self.buffer = np.zeros((int(_zvd_size()) + 7) // 8)
        msg = ctypes.create_string_buffer(256)
        if _zvd_init(self.buffer.ctypes.data, config.ctypes.data, msg, 256) != 0:
            raise ValueError(msg.value.decode())

    def run(self, dtheta, dv):
        """Statistic T (n,) (-1 while the window fills) and stationary flags (n,) bool for increments
        dtheta, dv (n, 3) rad, m/s."""
        n = np.shape(dtheta)[0]
        dtheta, dv = _arrays.read(dtheta, (n, 3), "dtheta"), _arrays.read(dv, (n, 3), "dv")
        stat, flag = np.empty(n), np.empty(n)
        if _zvd_run(self.buffer.ctypes.data, n, dtheta.ctypes.data, dv.ctypes.data, stat.ctypes.data,
                    flag.ctypes.data) != 0:
            raise ValueError("the zero-velocity detector's increments must be finite")
        return stat, flag > 0.5


_vibration_run = function("sarins_vibration_run", ctypes.c_int, _F64, _F64, _F64, ctypes.c_uint64, _I64, _P, _P, _P)


def vibration_run(accel_rms: float, rate_rms: float, step: float, seed: int, velocity_n):
    """``sarins_vibration_run``: the vehicle vibration's increments (vibration.h, stream 34 of ``seed``) along K + 1
    velocities (K + 1, 3) ENU m/s: dtheta, dv (K, 3) rad, m/s (jitter at the moving points, zero at rest)."""
    velocity_n = _arrays.read(velocity_n, (np.shape(velocity_n)[0], 3), "velocity")
    n = max(velocity_n.shape[0] - 1, 0)
    dtheta, dv = np.empty((n, 3)), np.empty((n, 3))
    if _vibration_run(float(accel_rms), float(rate_rms), float(step), int(seed) % 2**64, n, velocity_n.ctypes.data,
                      dtheta.ctypes.data, dv.ctypes.data) != 0:
        raise ValueError("the vibration's rms values must be finite and >= 0, the step positive and the velocities "
                         "finite")
    return dtheta, dv
