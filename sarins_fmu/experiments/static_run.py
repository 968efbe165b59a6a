"""Seed-000-style static run: turntable -> IMU -> INS, in process.

A run aligns for ``align_hours`` on a static base (coarse + Kalman fine
alignment) and then navigates for ``nav_hours``.  Everything is stepped on
the INS major-loop grid (``step``, default 1 s) in chunks, so memory stays
bounded and the compiled kernels do the per-sample work.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .. import imu as imu_mod
from .. import turntable
from ..imu import IMU, StaticBase
from ..core import smath  # the C core's hypot: the FMU's position_error, bit for bit
from ..rotations import rotvec_to_mat, small_angle_error
from ..ins import InsConfig, StrapdownINS
from ..thermal import Ambient
from ..site import SITE_LAT_DEG
from ..units import DEG_TO_RAD, DPH_TO_RPS, HOUR, NM, RAD_TO_DEG

CHUNK = 3600  # major-loop steps per chunk


@dataclass
class StaticRunResult:
    """Time series of a static run (navigation phase unless stated).

    time : (K,) s since navigation start (negative during alignment)
    lat_error, lon_error : (K,) rad; north_error, east_error : (K,) m
    position_error : (K,) horizontal distance error, m
    velocity_n : (K, 3) m/s; attitude : (K, 3) yaw, pitch, roll rad
    temperature : (K, 6) sensor temperatures degC (whole run)
    time_all : (K_all,) s since start of the run (for temperature)
    info : dict of scalars: settings; alignment estimates ``gyro_comp_dph``
        (deg/h) and ``accel_comp`` (m/s^2) in body axes; attitude error at
        the end of alignment ``align_attitude_error`` (E, N, U rad, computed
        = (I - [phi x]) true)
    """

    time: np.ndarray
    lat_error: np.ndarray
    lon_error: np.ndarray
    north_error: np.ndarray
    east_error: np.ndarray
    position_error: np.ndarray
    velocity_n: np.ndarray
    attitude: np.ndarray
    time_all: np.ndarray
    temperature: np.ndarray
    info: dict = field(default_factory=dict)

    def at_hours(self, name: str, hours: float):
        """Value of a navigation series ``name`` at ``hours`` into navigation."""
        k = int(np.argmin(np.abs(self.time - hours * HOUR)))
        return getattr(self, name)[k]

    def summary(self) -> dict:
        """Scalars in the papers' units (deg, nmi)."""
        out = {
            "lat_error_deg": float(self.lat_error[-1] * RAD_TO_DEG),
            "lon_error_deg": float(self.lon_error[-1] * RAD_TO_DEG),
            "position_error_nmi": float(self.position_error[-1] / NM),
            "max_position_error_nmi": float(np.max(self.position_error) / NM),
        }
        if self.time[-1] >= 12 * HOUR - 1e-9:
            out["lat_error_deg_12h"] = float(self.at_hours("lat_error", 12.0) * RAD_TO_DEG)
        return out


def build_imu_model(imu: str = "nav-rlg", axial_drift_dph: float | None = None):
    """IMU preset, optionally with its azimuth drift replaced by a constant (deg/h)."""
    model = imu_mod.preset(imu)
    if axial_drift_dph is not None:
        if not math.isfinite(axial_drift_dph):
            raise ValueError("axial drift must be finite")
        model = model.with_axial_drift(axial_drift_dph * DPH_TO_RPS)
    return model


def run_static(*, lat_deg: float = SITE_LAT_DEG, lon_deg: float = 0.0, align_hours: float = 4.0,
               nav_hours: float = 72.0, rotation: str = "forward-reverse", rate_dps: float = 6.0,
               accel_dps2: float = 6.0, dwell: float = 0.0, align_dwell: float = 300.0, imu: str = "nav-rlg",
               model: imu_mod.ImuModel | None = None, axial_drift_dph: float | None = None,
               start: str = "hot", ambient: Ambient | None = None, seed: int = 0, step: float = 1.0,
               internal_rate: float = 200.0, base_yaw_deg: float = 0.0,
               correction_dph: float = 0.0, correction_from_hours: float = 0.0,
               aligned_start: bool = False, initial_attitude_error=None, axial_table=None,
               on_increments=None) -> StaticRunResult:
    """Run turntable -> IMU -> INS on a static base.

    Parameters
    ----------
    lat_deg, lon_deg : start position, deg.  align_hours, nav_hours : h.
    rotation : single-axis scheme during navigation (see
        :func:`turntable.single_axis`); the alignment always indexes through
        four positions with ``align_dwell`` s stops.
    imu : preset name, or ``model`` an explicit :class:`ImuModel`;
        ``axial_drift_dph`` replaces the z-gyro drift by a constant, deg/h.
    start : 'hot' or 'cold' thermal start; ambient : ambient temperature.
    seed : noise seed.  step : major-loop / IMU output interval, s.
    correction_dph : axial drift subtracted by the INS from
        ``correction_from_hours`` into navigation on, deg/h.
    aligned_start : skip alignment and start navigation from the true
        attitude (closed-form checks); then align_hours is ignored.
    initial_attitude_error : (3,) E, N, U rad, with ``aligned_start`` only:
        the navigation starts from mat_nb = (I - [phi x]) mat_nb_true (the
        convention of ``info['align_attitude_error']``; closed-form checks).
    axial_table : real-time compensation of the z gyro by the reported
        z-gyro temperature, from the first sample on (alignment included): an
        object with ``correction(temp_c) -> rad/s`` such as
        :class:`sarins_fmu.identify.multitemp.MultiTemperatureTable`;
        ``correction * step`` is subtracted from each z angle increment
        before the INS sees it (``on_increments`` sees the raw output).
    on_increments : callable(time (K,) s, dtheta (K, 3), dv (K, 3), temps (K, 6)),
        called with each chunk of IMU output (e.g. to write a log,
        :mod:`sarins_fmu.imu_log`); time is the end of each interval.
    """
    _check_corrections(correction_dph, correction_from_hours)
    record = record_static(lat_deg=lat_deg, lon_deg=lon_deg, align_hours=align_hours, nav_hours=nav_hours,
                           rotation=rotation, rate_dps=rate_dps, accel_dps2=accel_dps2, dwell=dwell,
                           align_dwell=align_dwell, imu=imu, model=model, axial_drift_dph=axial_drift_dph, start=start,
                           ambient=ambient, seed=seed, step=step, internal_rate=internal_rate,
                           base_yaw_deg=base_yaw_deg, aligned_start=aligned_start,
                           initial_attitude_error=initial_attitude_error, on_increments=on_increments)
    return navigate_static(record, correction_dph=correction_dph, correction_from_hours=correction_from_hours,
                           axial_table=axial_table)


def _check_corrections(correction_dph: float, correction_from_hours: float) -> None:
    """ValueError unless the INS corrections of :func:`navigate_static` are finite."""
    for name, value in (("correction_dph", correction_dph), ("correction_from_hours", correction_from_hours)):
        if not math.isfinite(value):
            raise ValueError(f"{name} must be finite, got {value}")


@dataclass(frozen=True)
class StaticImuRecord:
    """The IMU output of a static run (:func:`record_static`), to navigate once or several times with
    different INS corrections (:func:`navigate_static`): the INS is the only part that differs, so a
    re-run from the record costs the INS alone and gives the bits of a whole :func:`run_static`.

    dtheta : (K_all, 3) rad and dv : (K_all, 3) m/s body-frame increments over each ``step``;
    temperature : (K_all, 6) sensor temperatures degC (gyros x, y, z, then accelerometers);
    n_align : steps of alignment (the first n_align rows); config : the INS configuration;
    initial : (3, 3) initial attitude matrix (navigation from body) with ``aligned_start``, else None;
    align_truth : (3, 3) true attitude matrix at the end of the alignment; info : the run's settings.
    """

    dtheta: np.ndarray
    dv: np.ndarray
    temperature: np.ndarray
    n_align: int
    step: float
    config: InsConfig
    initial: np.ndarray | None
    align_truth: np.ndarray
    info: dict


def record_static(*, lat_deg: float = SITE_LAT_DEG, lon_deg: float = 0.0, align_hours: float = 4.0,
                  nav_hours: float = 72.0, rotation: str = "forward-reverse", rate_dps: float = 6.0,
                  accel_dps2: float = 6.0, dwell: float = 0.0, align_dwell: float = 300.0, imu: str = "nav-rlg",
                  model: imu_mod.ImuModel | None = None, axial_drift_dph: float | None = None,
                  start: str = "hot", ambient: Ambient | None = None, seed: int = 0, step: float = 1.0,
                  internal_rate: float = 200.0, base_yaw_deg: float = 0.0, aligned_start: bool = False,
                  initial_attitude_error=None, on_increments=None) -> StaticImuRecord:
    """The turntable and IMU of :func:`run_static` (same parameters, without the INS corrections):
    the whole run's IMU output, about 96 bytes per step (26 MB for 76 h at 1 s)."""
    for name, value in (("lat_deg", lat_deg), ("align_hours", align_hours), ("nav_hours", nav_hours)):
        if not math.isfinite(value):
            raise ValueError(f"{name} must be finite, got {value}")
    if abs(lat_deg) > 89.9:
        raise ValueError(f"latitude {lat_deg} deg is outside +-89.9 deg")
    if align_hours < 0 or nav_hours <= 0:
        raise ValueError("align_hours must be >= 0 and nav_hours > 0")
    if model is None:
        model = build_imu_model(imu, axial_drift_dph)
    elif axial_drift_dph is not None:
        model = model.with_axial_drift(axial_drift_dph * DPH_TO_RPS)
    align_time = 0.0 if aligned_start else align_hours * HOUR
    n_align = round(align_time / step)
    n_nav = round(nav_hours * HOUR / step)
    n_total = n_align + n_nav
    duration = n_total * step
    table = turntable.single_axis(rotation, duration + step, rate_dps=rate_dps, accel_dps2=accel_dps2,
                                  dwell=dwell, grid=step, align_time=align_time, align_dwell=align_dwell)
    table.check_grid(step)
    base = StaticBase(lat_deg * DEG_TO_RAD, lon_deg * DEG_TO_RAD, 0.0, base_yaw_deg * DEG_TO_RAD)
    sensor = IMU(model, base, table.axes, output_interval=step, internal_rate=internal_rate, seed=seed,
                 thermal_start=start, ambient=ambient or Ambient())
    config = InsConfig(lat=base.lat, lon=base.lon, height=0.0, align_time=align_time, step=step)
    initial = None
    if aligned_start:
        angle, _, _ = table.state(0.0)
        initial = base.mat_nt @ turntable.chain_matrix(table.axes, angle[0])
        if initial_attitude_error is not None:
            initial = rotvec_to_mat(-np.asarray(initial_attitude_error, float)) @ initial
    elif initial_attitude_error is not None:
        raise ValueError("initial_attitude_error needs aligned_start (an alignment finds its own attitude)")
    dtheta, dv, temps = np.empty((n_total, 3)), np.empty((n_total, 3)), np.empty((n_total, 6))
    for k0 in range(0, n_total, CHUNK):
        k1 = min(n_total, k0 + CHUNK)
        angle, rate, accel = table.state(np.arange(k0, k1) * step)
        dtheta[k0:k1], dv[k0:k1], temps[k0:k1] = sensor.step(angle, rate, accel)
        if on_increments is not None:
            on_increments(np.arange(k0 + 1, k1 + 1) * step, dtheta[k0:k1], dv[k0:k1], temps[k0:k1])
    angle_end, _, _ = table.state(n_align * step)
    align_truth = base.mat_nt @ turntable.chain_matrix(table.axes, angle_end[0])
    info = {"lat_deg": lat_deg, "align_hours": align_time / HOUR, "nav_hours": nav_hours,
            "rotation": rotation, "imu": imu if axial_drift_dph is None else f"{imu}+axial",
            "start": start, "seed": seed}
    return StaticImuRecord(dtheta, dv, temps, n_align, step, config, initial, align_truth, info)


def navigate_static(record: StaticImuRecord, *, correction_dph: float = 0.0, correction_from_hours: float = 0.0,
                    axial_table=None) -> StaticRunResult:
    """The INS of :func:`run_static` on a recorded IMU output: alignment, then navigation with
    ``correction_dph`` (deg/h) subtracted from the z gyro from ``correction_from_hours`` into navigation
    on, and ``axial_table`` compensating the z gyro by its temperature from the first sample (as in
    :func:`run_static`).  The record is not modified."""
    _check_corrections(correction_dph, correction_from_hours)
    step, n_align, temps = record.step, record.n_align, record.temperature
    n_total = len(temps)
    n_nav = n_total - n_align
    ins = StrapdownINS(record.config, initial_attitude=record.initial)
    align_error = np.zeros(3)
    nav_out = np.empty((n_total, 9))
    corr_start = n_align + round(correction_from_hours * HOUR / step)
    for k0 in range(0, n_total, CHUNK):
        k1 = min(n_total, k0 + CHUNK)
        dtheta, dv = record.dtheta[k0:k1], record.dv[k0:k1]
        if axial_table is not None:
            dtheta = dtheta.copy()
            dtheta[:, 2] -= np.asarray(axial_table.correction(temps[k0:k1, 2]), float) * step
        corr = np.where(np.arange(k0, k1) >= corr_start, correction_dph * DPH_TO_RPS, 0.0)
        if k0 < n_align <= k1:  # attitude error at the end of alignment vs the table truth
            nav_out[k0:n_align] = ins.step(dtheta[:n_align - k0], dv[:n_align - k0], corr[:n_align - k0])
            align_error = small_angle_error(ins.mat_nb, record.align_truth)
            nav_out[n_align:k1] = ins.step(dtheta[n_align - k0:], dv[n_align - k0:], corr[n_align - k0:])
        else:
            nav_out[k0:k1] = ins.step(dtheta, dv, corr)
    nav = nav_out[n_align:]
    err = ins.position_error(nav)
    align_time = n_align * step
    return StaticRunResult(
        time=np.arange(1, n_nav + 1) * step,
        lat_error=err[:, 0], lon_error=err[:, 1], north_error=err[:, 2], east_error=err[:, 3],
        position_error=smath.evaluate("hypot", err[:, 2], err[:, 3]),
        velocity_n=nav[:, 3:6], attitude=nav[:, 6:9],
        time_all=np.arange(1, n_total + 1) * step - align_time, temperature=temps,
        info={**record.info,
              "gyro_comp_dph": (ins.gyro_comp / DPH_TO_RPS).tolist(),
              "accel_comp": ins.accel_comp.tolist(),
              "align_attitude_error": align_error.tolist()},
    )
