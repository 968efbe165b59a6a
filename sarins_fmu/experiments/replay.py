"""Alignment and navigation on a recorded IMU log (:mod:`sarins_fmu.imu_log`).

The log's increments drive the same two-speed strapdown INS as the
simulated runs (:func:`sarins_fmu.experiments.static_run.run_static`): a
static alignment over the first ``align_hours`` (coarse in the inertial
frame, then the zero-velocity Kalman filter) from the log's start position,
then free navigation to the end of the log.  Optionally a trained IMU
compensator (seed 003, :mod:`sarins_fmu.identify.compensators`) corrects
the increments first; it sees the mean rates and the mean of the six
temperatures, as the IMUCompensator FMU does.  Errors are taken against
the log's reference position when it has one, else against the static
start.  The INS is stepped in the chunks ``run_static`` uses, so a log
written from a simulated run replays to the same numbers, bit for bit.
"""

from __future__ import annotations

import math

import numpy as np

from .. import earth
from ..imu_log import ImuLog, LogError
from ..ins import InsConfig, StrapdownINS
from ..units import HOUR
from .static_run import CHUNK, StaticRunResult


def compensate(log: ImuLog, compensator) -> tuple[np.ndarray, np.ndarray]:
    """Increments corrected by a fitted compensator (needs the log's temperatures)."""
    if log.temps is None:
        raise LogError("the compensator needs the six temperature columns, which the log does not have")
    h = log.step
    x = np.column_stack([log.dtheta / h, log.dv / h, log.temps.mean(axis=1)])
    y = compensator.predict(x)
    return np.ascontiguousarray(y[:, :3] * h), np.ascontiguousarray(y[:, 3:] * h)


def replay(log: ImuLog, *, align_hours: float = 4.0, coarse_seconds: float = 300.0,
           compensator=None) -> StaticRunResult:
    """Align on the first ``align_hours`` of the log and navigate over the rest.

    Returns a :class:`StaticRunResult` (navigation phase; ``time`` since
    the end of alignment).  Raises ValueError when the log is shorter than
    the alignment or the alignment is not a whole number of samples.
    """
    h = log.step
    if not (math.isfinite(align_hours) and align_hours > 0):
        raise ValueError(f"alignment must last a positive time, got {align_hours} h")
    n_align = round(align_hours * HOUR / h)
    if abs(n_align * h - align_hours * HOUR) > 1e-6 * h:
        raise ValueError(f"alignment of {align_hours} h is not a whole number of {h:g} s samples")
    n_total = len(log.time)
    if n_total <= n_align:
        raise ValueError(f"the log ({n_total * h / HOUR:.4g} h) is not longer than the {align_hours:g} h alignment")
    dtheta, dv = (log.dtheta, log.dv) if compensator is None else compensate(log, compensator)
    config = InsConfig(lat=log.lat, lon=log.lon, height=log.height, align_time=n_align * h,
                       coarse_time=coarse_seconds, step=h)
    ins = StrapdownINS(config)
    out = np.empty((n_total, 9))
    for k0 in range(0, n_total, CHUNK):
        k1 = min(n_total, k0 + CHUNK)
        if k0 < n_align <= k1:
            out[k0:n_align] = ins.step(dtheta[k0:n_align], dv[k0:n_align])
            out[n_align:k1] = ins.step(dtheta[n_align:k1], dv[n_align:k1])
        else:
            out[k0:k1] = ins.step(dtheta[k0:k1], dv[k0:k1])
    nav = out[n_align:]
    if log.ref is None:
        err = ins.position_error(nav)
    else:
        ref = log.ref[n_align:]
        r_m, r_n = earth.radii(log.lat)
        dlat, dlon = nav[:, 0] - ref[:, 0], nav[:, 1] - ref[:, 1]
        err = np.column_stack([dlat, dlon, dlat * (r_m + log.height), dlon * (r_n + log.height) * np.cos(ref[:, 0])])
    n_nav = n_total - n_align
    temps = log.temps if log.temps is not None else np.full((n_total, 6), np.nan)
    return StaticRunResult(
        time=np.arange(1, n_nav + 1) * h, lat_error=err[:, 0], lon_error=err[:, 1], north_error=err[:, 2],
        east_error=err[:, 3], position_error=np.hypot(err[:, 2], err[:, 3]), velocity_n=nav[:, 3:6],
        attitude=nav[:, 6:9], time_all=np.arange(1, n_total + 1) * h - n_align * h, temperature=temps,
        info={"lat_deg": math.degrees(log.lat), "align_hours": n_align * h / HOUR, "nav_hours": n_nav * h / HOUR,
              "source": "log", "quantity": log.quantity, "compensated": compensator is not None,
              "gyro_comp_dph": (ins.gyro_comp / (math.pi / 180 / 3600)).tolist(),
              "accel_comp": ins.accel_comp.tolist()})
