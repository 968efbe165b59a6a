"""Our simulated data in the text formats of KF-GINS (i2Nav-WHU's EKF GNSS/INS program), and its
navigation result read back: for running a peer filter on the same IMU and GNSS data.

The formats (as KF-GINS's loaders read them; the program is not part of this project):

* IMU file: per line GNSS seconds of week, angle increments x, y, z (rad) and velocity increments
  x, y, z (m/s) of the interval ending at that time, body forward-right-down.  They are the
  sensor's raw increments: KF-GINS applies the two-sample coning correction
  (dtheta + dtheta_prev x dtheta / 12) and the rotation and sculling corrections of the velocity
  increment (dv + dtheta x dv / 2 + (dtheta_prev x dv + dv_prev x dtheta) / 12) itself.
* GNSS file: per line GNSS seconds of week, latitude, longitude (deg), height (m), position std
  north, east, down (m).
* YAML configuration: file paths, IMU rate, start time, initial position (deg, deg, m), velocity
  (north, east, down m/s), attitude (roll, pitch, yaw deg, Z-Y-X Euler angles of C_n^b with n
  north-east-down and b forward-right-down), their stds, the IMU noise (ARW deg/sqrt(h), VRW
  m/s/sqrt(h), first-order Gauss-Markov bias and scale-factor stds in deg/h, mGal, ppm with one
  correlation time in hours) and the antenna lever arm (forward-right-down, m).
* Navigation result (``KF_GINS_Navresult.nav``): week (0), seconds of week, latitude, longitude
  (deg), height (m), velocity north, east, down (m/s), roll, pitch, yaw (deg); one line per IMU step.

Our side: navigation frame east-north-up, body right-front-up, and increments already compensated
(``sarins_fmu.trajectory.Truth``: rotation vector of the step; velocity increment in the body frame
at the step's start).  Both frame changes are the same involution P (swap x and y, negate z):
v_NED = P v_ENU, v_FRD = P v_RFU, C_NED^FRD = P C_ENU^RFU P.  :func:`raw_increments` takes KF-GINS's
corrections back out of our compensated increments (to first order in the angle increment: what is
left is of order |dtheta|^2 |dv|, 1e-9 m/s per step in a 6 deg/s turn at 100 Hz).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .rotations import euler_to_mat

_P = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])  # ENU <-> NED, RFU <-> FRD (P = P' = P^-1)
NAV_FILE = "KF_GINS_Navresult.nav"
MGAL = 1e-5  # m/s^2


def swap_axes(v) -> np.ndarray:
    """(..., 3) vectors from ENU to NED or from right-front-up to forward-right-down (and back)."""
    v = np.asarray(v, float)
    return np.stack([v[..., 1], v[..., 0], -v[..., 2]], axis=-1)


def kfgins_euler(yaw, pitch, roll) -> np.ndarray:
    """(..., 3) KF-GINS roll, pitch, yaw (rad) of C_NED^FRD from our yaw, pitch, roll (rad) of
    mat_nb = C_ENU^RFU = Rz(yaw) Rx(pitch) Ry(roll)."""
    c = _P @ euler_to_mat(yaw, pitch, roll) @ _P
    roll_k = np.arctan2(c[..., 2, 1], c[..., 2, 2])
    pitch_k = np.arcsin(np.clip(-c[..., 2, 0], -1.0, 1.0))
    yaw_k = np.arctan2(c[..., 1, 0], c[..., 0, 0])
    return np.stack([roll_k, pitch_k, yaw_k], axis=-1)


def zyx_to_mat(roll, pitch, yaw) -> np.ndarray:
    """(..., 3, 3) C_n^b = Rz(yaw) Ry(pitch) Rx(roll) (Z-Y-X Euler angles, rad)."""
    r, p, y = (np.asarray(a, float) for a in (roll, pitch, yaw))
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.stack([np.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr], -1),
                     np.stack([sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], -1),
                     np.stack([-sp, cp * sr, cp * cr], -1)], -2)


def our_euler(roll, pitch, yaw) -> np.ndarray:
    """(n, 3) our yaw, pitch, roll (rad) from KF-GINS roll, pitch, yaw (rad) arrays."""
    m = _P @ zyx_to_mat(roll, pitch, yaw) @ _P  # C_ENU^RFU = Rz(yaw) Rx(pitch) Ry(roll)
    return np.column_stack([np.arctan2(-m[..., 0, 1], m[..., 1, 1]), np.arcsin(np.clip(m[..., 2, 1], -1.0, 1.0)),
                            np.arctan2(-m[..., 2, 0], m[..., 2, 2])])


def raw_increments(dtheta, dv):
    """(K, 3) raw increments whose KF-GINS corrections give back the compensated ``dtheta``, ``dv``
    (any body axes; the first sample's predecessor taken as itself, a vehicle at rest before the start).

    raw_theta_k = dtheta_k - dtheta_(k-1) x dtheta_k / 12,
    raw_v_k = dv_k - dtheta_k x dv_k / 2 - (dtheta_(k-1) x dv_k + dv_(k-1) x dtheta_k) / 12."""
    dtheta, dv = np.asarray(dtheta, float), np.asarray(dv, float)
    prev_t = np.concatenate([dtheta[:1], dtheta[:-1]])
    prev_v = np.concatenate([dv[:1], dv[:-1]])
    raw_t = dtheta - np.cross(prev_t, dtheta) / 12.0
    raw_v = dv - np.cross(dtheta, dv) / 2.0 - (np.cross(prev_t, dv) + np.cross(prev_v, dtheta)) / 12.0
    return raw_t, raw_v


def compensate(raw_theta, raw_dv):
    """KF-GINS's corrections of raw increments (the forward map that :func:`raw_increments` undoes;
    the first sample's predecessor taken as itself): rotation vector and velocity increment."""
    prev_t = np.concatenate([raw_theta[:1], raw_theta[:-1]])
    prev_v = np.concatenate([raw_dv[:1], raw_dv[:-1]])
    theta = raw_theta + np.cross(prev_t, raw_theta) / 12.0
    dv = raw_dv + np.cross(raw_theta, raw_dv) / 2.0 + (np.cross(prev_t, raw_dv) + np.cross(prev_v, raw_theta)) / 12.0
    return theta, dv


def write_imu(path, time_sow, dtheta_rfu, dv_rfu, *, raw: bool = True) -> Path:
    """Write an IMU file: ``time_sow`` (K,) GNSS seconds of week at the end of each interval,
    ``dtheta_rfu``, ``dv_rfu`` (K, 3) our compensated increments (rad, m/s, right-front-up).  With
    ``raw`` (default) KF-GINS's own corrections are taken out first (:func:`raw_increments`).
    Printed with 13 significant digits (time with 1 ns)."""
    dtheta, dv = swap_axes(dtheta_rfu), swap_axes(dv_rfu)
    if raw:
        dtheta, dv = raw_increments(dtheta, dv)
    path = Path(path)
    rows = np.column_stack([np.asarray(time_sow, float), dtheta, dv])
    np.savetxt(path, rows, fmt=["%.9f"] + ["% .12e"] * 6, delimiter=" ")
    return path


def write_gnss(path, time_sow, lat, lon, height, std_enu) -> Path:
    """Write a GNSS position file: ``time_sow`` (n,) s of week, ``lat``, ``lon`` (n,) rad, ``height`` (n,)
    m, ``std_enu`` (3,) or (n, 3) position std east, north, up (m; written north, east, down)."""
    n = np.size(time_sow)
    std = np.broadcast_to(np.asarray(std_enu, float), (n, 3))
    rows = np.column_stack([time_sow, np.degrees(lat), np.degrees(lon), height, std[:, 1], std[:, 0], std[:, 2]])
    path = Path(path)
    np.savetxt(path, rows, fmt=["%.3f", "%.12f", "%.12f", "%.5f", "%.6f", "%.6f", "%.6f"], delimiter=" ")
    return path


@dataclass(frozen=True)
class KfginsNoise:
    """KF-GINS's IMU noise block in its units: arw deg/sqrt(h), vrw m/s/sqrt(h), gbstd deg/h, abstd
    mGal, gsstd / asstd ppm (Gauss-Markov stds), corrtime h; the initial bias / scale stds (deg/h,
    mGal, ppm)."""

    arw: float
    vrw: float
    gbstd: float
    abstd: float
    gsstd: float
    asstd: float
    corrtime: float
    initbgstd: float
    initbastd: float
    initsgstd: float
    initsastd: float


def noise_from_imu(noise, corrtime_h: float = 1000.0, scale_std_ppm: float = 1.0) -> KfginsNoise:
    """KF-GINS noise for our :class:`sarins_fmu.aided.ImuNoise` (constant biases + bias random walks):
    ARW and VRW converted; the initial bias stds are our constant biases' stds; a Gauss-Markov process
    with a long correlation time T (default 1000 h, so that it is a random walk over any run) and std
    sigma = rw sqrt(T / 2) has our random walk's driving noise (q = 2 sigma^2 / T = rw^2).  Our IMU has
    no scale-factor errors: their stds are ``scale_std_ppm`` (small: the 21-state filter then acts like
    a 15-state one)."""
    t = corrtime_h * 3600.0
    dph = 180.0 / math.pi * 3600.0  # rad/s -> deg/h
    return KfginsNoise(arw=noise.arw * 180.0 / math.pi * 60.0, vrw=noise.vrw * 60.0,
                       gbstd=max(noise.gyro_rw * math.sqrt(t / 2.0) * dph, 1e-9),
                       abstd=max(noise.accel_rw * math.sqrt(t / 2.0) / MGAL, 1e-9),
                       gsstd=scale_std_ppm, asstd=scale_std_ppm, corrtime=corrtime_h,
                       initbgstd=max(noise.gyro_bias_std * dph, 1e-9),
                       initbastd=max(noise.accel_bias_std / MGAL, 1e-9), initsgstd=scale_std_ppm,
                       initsastd=scale_std_ppm)


def _vec(values) -> str:
    return "[ " + ", ".join(repr(float(v)) for v in values) + " ]"


def write_config(path, *, imu_path, gnss_path, output_dir, rate_hz: int, start_sow: float, nav_row, pos_std_enu,
                 vel_std_enu, att_std: tuple, noise: KfginsNoise, lever_rfu=(0.0, 0.0, 0.0)) -> Path:
    """Write KF-GINS's YAML configuration.  ``nav_row`` is our initial state (lat, lon rad, h m,
    v E N U m/s, yaw, pitch, roll rad); ``pos_std_enu``, ``vel_std_enu`` (3,) m, m/s; ``att_std``
    (tilt, heading) rad (roll and pitch get the tilt std); ``lever_rfu`` the antenna lever arm
    (right-front-up, m).  Initial biases and scale factors are 0; the file's end time is -1 (to the
    end of the IMU file)."""
    lat, lon, h = nav_row[0], nav_row[1], nav_row[2]
    v_ned = swap_axes(nav_row[3:6])
    euler = np.degrees(kfgins_euler(nav_row[6], nav_row[7], nav_row[8]))
    tilt, heading = np.degrees(att_std[0]), np.degrees(att_std[1])
    n = noise
    lines = [
        "# KF-GINS configuration written by sarins_fmu.kfgins",
        f"imupath: {json.dumps(str(imu_path))}",
        f"gnsspath: {json.dumps(str(gnss_path))}",
        f"outputpath: {json.dumps(str(output_dir))}",
        "imudatalen: 7",
        f"imudatarate: {int(rate_hz)}",
        f"starttime: {float(start_sow)!r}",
        "endtime: -1",
        f"initpos: {_vec([math.degrees(lat), math.degrees(lon), h])}",
        f"initvel: {_vec(v_ned)}",
        f"initatt: {_vec(euler)}",
        "initgyrbias: [ 0, 0, 0 ]",
        "initaccbias: [ 0, 0, 0 ]",
        "initgyrscale: [ 0, 0, 0 ]",
        "initaccscale: [ 0, 0, 0 ]",
        f"initposstd: {_vec(np.asarray(pos_std_enu, float)[[1, 0, 2]])}",
        f"initvelstd: {_vec(np.asarray(vel_std_enu, float)[[1, 0, 2]])}",
        f"initattstd: {_vec([tilt, tilt, heading])}",
        f"initbgstd: {_vec([n.initbgstd] * 3)}",
        f"initbastd: {_vec([n.initbastd] * 3)}",
        f"initsgstd: {_vec([n.initsgstd] * 3)}",
        f"initsastd: {_vec([n.initsastd] * 3)}",
        "imunoise:",
        f"  arw: {_vec([n.arw] * 3)}",
        f"  vrw: {_vec([n.vrw] * 3)}",
        f"  gbstd: {_vec([n.gbstd] * 3)}",
        f"  abstd: {_vec([n.abstd] * 3)}",
        f"  gsstd: {_vec([n.gsstd] * 3)}",
        f"  asstd: {_vec([n.asstd] * 3)}",
        f"  corrtime: {float(n.corrtime)!r}",
        f"antlever: {_vec(swap_axes(lever_rfu))}",
    ]
    path = Path(path)
    path.write_text("\n".join(lines) + "\n")
    return path


@dataclass(frozen=True)
class KfginsNav:
    """KF-GINS's navigation result in our layout: time (n,) s of week; nav (n, 9) lat, lon rad,
    h m, v E N U m/s, yaw, pitch, roll rad (:meth:`sarins_fmu.trajectory.Truth.nav_rows`)."""

    time: np.ndarray
    nav: np.ndarray


def read_nav(path) -> KfginsNav:
    """Read ``KF_GINS_Navresult.nav`` (11 columns); ValueError naming the file when it is not one."""
    path = Path(path)
    try:
        data = np.loadtxt(path, ndmin=2)
    except (OSError, ValueError) as exc:
        raise ValueError(f"{path}: not a KF-GINS navigation result ({exc})") from None
    if data.shape[0] == 0 or data.shape[1] != 11:
        raise ValueError(f"{path}: a KF-GINS navigation result has 11 columns, found {data.shape[1]}")
    v_enu = swap_axes(data[:, 5:8])
    att = our_euler(*np.radians(data[:, 8:11]).T)
    nav = np.column_stack([np.radians(data[:, 2]), np.radians(data[:, 3]), data[:, 4], v_enu, att])
    return KfginsNav(time=data[:, 1], nav=nav)
