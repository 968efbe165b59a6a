"""Seed 002's vehicle runs, in process, in the form the FMU system runs them.

A :class:`VehicleRun` is one drive of the vehicle test as plain data (legs,
start, IMU unit, ambient, seeds, INS start).  :class:`InProcessEngine` runs
it with the library, built like the shipped ``vehicle_rins_online`` SSP
system so that the two give the same numbers bit for bit:

* the vehicle (:class:`~sarins_fmu.vehicle.VehicleTrajectory` with a rigid,
  level body and no RINS rotation) gives the attitude gimbals yaw, pitch,
  roll and the base motion; the RINS turntable (forward-reverse about
  azimuth, :func:`~sarins_fmu.turntable.single_axis`) is a separate gimbal
  chain riding on it (the IMU's gimbals: vehicle z, x, y, then the table's);
* the INS either aligns over ``align_time`` or (``align_time = 0``) starts
  navigating at once from the given attitude ``attitude0`` (Euler angles,
  so that an FMU parameter set carries the same numbers);
* the azimuth drift compensation of an interval is the drift model in force
  at the interval's start evaluated at the gyro temperature at its end; a
  model updated at the INS row of time t (the first moving row after a
  stop) is in force from the interval starting at t + ``latency``: the
  explicit, time-tagged latency of the FMU system (one step is the least
  any scheme allows: under Jacobi the INS reads the updater's output of the
  row before the one it integrates).

An *engine* runs sessions and drives: :class:`InProcessEngine` here, the
FMU one in :mod:`sarins.online_rls.cosim`.  Units: SI; temperatures °C.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import earth, turntable
from ..identify.online import OnlineDriftUpdater
from ..drift_model import drift_model_value
from ..imu import IMU, VEHICLE_ATTITUDE_AXES, ImuModel
from ..ins import InsConfig, StrapdownINS
from ..rotations import euler_to_mat
from ..thermal import Ambient
from ..units import DAY
from ..vehicle import BodyMotion, VehicleTrajectory

GYRO_Z = 2  # index of the azimuth gyro in the IMU's temperature vector
RINS_ROTATION = "forward-reverse"  # the RINS's rotation about azimuth (seed 002)
RIGID_BODY = BodyMotion(0.0, 0.0, vibration=0.0)  # a level body with no sway or vibration (tests, sensitivity)
VEHICLE_BODY = BodyMotion()  # the vehicle test's body: suspension sway and vibration on (BodyMotion defaults)
INTERNAL_RATE = 200.0  # Hz, the IMU minor loop of the vehicle test (the design's default rate)
UPDATE_LATENCY = 1.0  # s, from the INS row that updates the model to the first interval compensated with it


@dataclass(frozen=True)
class VehicleRun:
    """One drive of the vehicle test.

    Attributes
    ----------
    legs : tuple of legs (:class:`~sarins_fmu.vehicle.VehicleTrajectory`).
    lat, lon, heading : start latitude, longitude and heading (CCW from north), rad.
    unit : ImuModel, the IMU (its ``axial_drift_poly`` is the true model of the day, no ageing).
    ambient : constant ambient temperature, °C (hot start: the unit sits at ambient + self-heating).
    seed : IMU noise seed.
    lead_time : s at rest before the first leg.
    align_time : s of INS alignment; 0: the INS starts navigating from ``attitude0``.
    attitude0 : (yaw, pitch, roll), rad, the INS's initial attitude when ``align_time`` is 0.
    start_day : days since the calibration at t = 0 (the updater's clock).
    step : IMU output and INS step (the communication step), s.
    internal_rate : IMU minor-loop rate, Hz.
    body : the vehicle body's sway and vibration (:class:`~sarins_fmu.vehicle.BodyMotion`).
    """

    legs: tuple
    lat: float
    lon: float
    heading: float
    unit: ImuModel
    ambient: float
    seed: int
    lead_time: float = 0.0
    align_time: float = 0.0
    attitude0: tuple = (0.0, 0.0, 0.0)
    start_day: float = 0.0
    step: float = 1.0
    internal_rate: float = INTERNAL_RATE
    body: BodyMotion = VEHICLE_BODY

    def trajectory(self) -> VehicleTrajectory:
        """The vehicle: legs after ``lead_time`` at rest, the run's body motion, no RINS rotation."""
        return VehicleTrajectory(list(self.legs), self.lat, self.lon, self.heading, step=self.step,
                                 rotation="none", lead_time=self.lead_time, body=self.body)

    def table_duration(self, traj: VehicleTrajectory) -> float:
        """Length of the RINS rotation pattern, s (the Turntable FMU's ``duration``)."""
        return traj.duration + self.step

    def table(self, traj: VehicleTrajectory):
        """The RINS turntable: forward-reverse rotation about azimuth from t = 0."""
        return turntable.single_axis(RINS_ROTATION, self.table_duration(traj), grid=self.step)


def imu_axes(table) -> np.ndarray:
    """Gimbal axes of the IMU: the vehicle's attitude (z, x, y), then the table's."""
    return np.vstack([VEHICLE_ATTITUDE_AXES, table.axes])


def motion(traj: VehicleTrajectory, table, time: np.ndarray):
    """Start-of-step gimbal angle, rate, acceleration (K, 3 + A) at ``time`` (K,) s:
    the vehicle's yaw, pitch, roll, then the table's gimbals."""
    vehicle = traj.schedule.state(time)
    rins = table.state(time)
    return tuple(np.hstack([v[:, :3], r]) for v, r in zip(vehicle, rins))


def make_imu(run: VehicleRun, traj: VehicleTrajectory, table, model: ImuModel | None = None, seed=None) -> IMU:
    """The IMU on the vehicle (``model`` default the run's unit, hot start at the run's ambient)."""
    return IMU(run.unit if model is None else model, traj, imu_axes(table), output_interval=run.step,
               internal_rate=run.internal_rate, seed=run.seed if seed is None else seed, thermal_start="hot",
               ambient=Ambient(mean=run.ambient))


def make_ins(run: VehicleRun, traj: VehicleTrajectory, align_time=None, attitude=None) -> StrapdownINS:
    """The INS at the vehicle's start: aligning, or from ``attitude`` (default the run's attitude0)."""
    align = run.align_time if align_time is None else align_time
    config = InsConfig(lat=traj.lat[0], lon=traj.lon[0], align_time=align, step=run.step)
    if align > 0:
        return StrapdownINS(config)
    return StrapdownINS(config, initial_attitude=euler_to_mat(*(run.attitude0 if attitude is None else attitude)))


def state_blocks(moving: np.ndarray):
    """(k0, k1) row ranges of constant moving/stopped state."""
    edges = np.flatnonzero(np.diff(moving.astype(np.int8))) + 1
    return list(zip(np.concatenate([[0], edges]), np.concatenate([edges, [moving.size]])))


def session_blocks(moving: np.ndarray, lag: int):
    """:func:`state_blocks`, each moving block after a stop split ``lag`` rows after its start: the
    model updated at its first row is in force from there (so the rows before are integrated, and seen
    by the updater, before the rows after)."""
    out = []
    for k0, k1 in state_blocks(moving):
        if moving[k0] and k0 > 0 and k1 - k0 > lag:
            out += [(k0, k0 + lag), (k0 + lag, k1)]
        else:
            out.append((k0, k1))
    return out


def _compensation(in_force: list, k0: int, temperature: np.ndarray) -> np.ndarray:
    """Drift compensation of rows k0.. (temperature (K,) °C at each row's end), rad/s: the
    model of ``in_force`` [(first row, [a, b, c]), ...] in force at each row."""
    rows = k0 + np.arange(temperature.size)
    comp = np.empty(temperature.size)
    for j, (first, coefficients) in enumerate(in_force):
        last = in_force[j + 1][0] if j + 1 < len(in_force) else math.inf
        sel = (rows >= first) & (rows < last)
        comp[sel] = drift_model_value(coefficients, temperature[sel])
    return comp


class InProcessEngine:
    """Runs vehicle-test sessions and drives with the library (the reference)."""

    name = "inprocess"

    def session(self, run: VehicleRun, updater: OnlineDriftUpdater, latency: float = UPDATE_LATENCY) -> np.ndarray:
        """One drive with a stop: IMU -> INS (compensated by the model in force) -> ``updater`` (Fig. 2,
        updated in place; its events grow).  The INS starts navigating from ``run.attitude0``.
        Returns the INS rows (K, 9): lat, lon, height, v_e, v_n, v_u, yaw, pitch, roll at t = 1 .. K steps."""
        traj = run.trajectory()
        table = run.table(traj)
        sensor = make_imu(run, traj, table)
        ins = make_ins(run, traj, align_time=0.0)
        t0 = run.start_day * DAY
        lag = 1 + int(round(latency / run.step))  # rows from the updating row to the first compensated one
        in_force = [(0, updater.rls.parameters)]
        moving = traj.moving()[1:]
        rows = []
        for k0, k1 in session_blocks(moving, lag):
            dtheta, dv, temps = sensor.step(*motion(traj, table, traj.time[k0:k1]))
            out = ins.step(dtheta, dv, _compensation(in_force, k0, temps[:, GYRO_Z]))
            rows.append(out)
            n_updates = updater.rls.n_updates
            updater.step(t0 + traj.time[k0 + 1:k1 + 1], traj.speed[k0 + 1:k1 + 1], out[:, 3:5], out[:, 6:9],
                         temps[:, GYRO_Z], out[:, 0])
            if updater.rls.n_updates != n_updates:  # updated at the block's first row (the vehicle moved off)
                if not (moving[k0] and k0 > 0):
                    raise RuntimeError("the model can only be updated at the first row of a moving block")
                in_force.append((k0 + lag, updater.rls.parameters))
        return np.concatenate(rows)

    def drive(self, run: VehicleRun, models) -> list:
        """Navigate the drive once per model ([a, b, c] rad/s per °C^n, or None) on the same
        increments; returns per model the navigation rows after the alignment, (K, 9)."""
        traj = run.trajectory()
        table = run.table(traj)
        sensor = make_imu(run, traj, table)
        n_align = int(round(run.align_time / run.step))
        navs = [make_ins(run, traj) for _ in models]
        outs = [[] for _ in models]
        for k0, k1 in _chunks(traj.n_steps):
            dtheta, dv, temps = sensor.step(*motion(traj, table, traj.time[k0:k1]))
            for ins, coef, out in zip(navs, models, outs):
                comp = np.zeros(k1 - k0) if coef is None else drift_model_value(coef, temps[:, GYRO_Z])
                out.append(ins.step(dtheta, dv, comp))  # the INS compensates only while navigating
        return [np.concatenate(out)[n_align:] for out in outs]


def _chunks(n: int, size: int = 3600):
    return [(k0, min(n, k0 + size)) for k0 in range(0, n, size)]


def reference_navigation(run: VehicleRun) -> np.ndarray:
    """An INS fed by ideal sensors on the drive's motion, started at the end of the
    alignment from the true attitude: the truth the position errors are taken against
    (it removes the navigation's own discretisation error).  Rows (K, 9) after the alignment."""
    traj = run.trajectory()
    table = run.table(traj)
    ideal = make_imu(run, traj, table, model=ImuModel())
    n_align = int(round(run.align_time / run.step))
    angle = motion(traj, table, traj.time[n_align:n_align + 1])[0][0]
    config = InsConfig(lat=traj.lat[0], lon=traj.lon[0], align_time=0.0, step=run.step)
    ref = StrapdownINS(config, initial_attitude=turntable.chain_matrix(imu_axes(table), angle))
    out = []
    for k0, k1 in _chunks(traj.n_steps):
        d_ideal, v_ideal, _ = ideal.step(*motion(traj, table, traj.time[k0:k1]))
        a = max(k0, n_align)
        if a < k1:
            out.append(ref.step(d_ideal[a - k0:], v_ideal[a - k0:]))
    return np.concatenate(out)


def position_errors(navs: list, ref: np.ndarray, lat0: float):
    """East and north errors (M, K) m of the navigations ``navs`` (each (K, 9) rows of
    lat, lon, ...) against ``ref`` (K, 9), radii at the start latitude ``lat0`` (rad)."""
    r_m, r_n = earth.radii(lat0)
    east = [(nav[:, 1] - ref[:, 1]) * r_n * np.cos(ref[:, 0]) for nav in navs]
    north = [(nav[:, 0] - ref[:, 0]) * r_m for nav in navs]
    return np.array(east), np.array(north)
