"""Land-vehicle trajectory with drive segments, turns and stops (seed 002).

A trajectory is built on the IMU's output grid (``step``, s) from *legs*:

* ``("stop", seconds)``: brake to rest at ``brake`` m/s², then stand still;
* ``("drive", seconds, speed)``: accelerate (or brake) towards ``speed``
  m/s at ``accel`` m/s², then hold it, for ``seconds`` in total;
* ``("turn", degrees)``: change heading by ``degrees`` (positive = left,
  counter-clockwise) with a trapezoidal yaw-rate profile, keeping the speed.

Longitudinal acceleration and yaw acceleration are piecewise constant on the
grid, so speed and heading are exact linear / quadratic functions inside a
step.  As the moving-base interface of :class:`sarins_fmu.imu.IMU` asks,
the vehicle's heading is an outer gimbal (about the local vertical) of a
two-gimbal schedule ``(heading, IMU rotation)``, whose inner gimbal is the
RINS's forward-reverse rotation about the azimuth axis; the base frame t is
the local-level ENU frame at the vehicle's position, whose inertial rate
(ω_ie + ω_en) and specific force are held over each step:

    f^n = Δv^n / h + (2 ω_ie^n + ω_en^n) × v̄^n - g^n

with Δv^n the exact velocity change over the step and v̄^n the step's mean
velocity.  The body frame is right-front-up, the navigation frame ENU; SI
units inside (rad, m, m/s, s).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import earth, turntable
from .turntable import AXIS_X, AXIS_Y, AXIS_Z
from .units import DEG_TO_RAD

VEHICLE_AXES = (AXIS_Z, AXIS_Z)  # heading (outer), RINS rotation about azimuth (inner)
# with body motion: heading, pitch, roll (mat_nv = Rz Rx Ry, sarins_fmu.rotations.euler_to_mat), RINS rotation
VEHICLE_BODY_AXES = (AXIS_Z, AXIS_X, AXIS_Y, AXIS_Z)
LEG_KINDS = ("stop", "drive", "turn")


@dataclass(frozen=True)
class DriveSettings:
    """Dynamics limits of the vehicle (SI)."""

    accel: float = 1.0  # m/s^2, longitudinal acceleration
    brake: float = 1.5  # m/s^2, braking deceleration
    yaw_rate: float = 6.0 * DEG_TO_RAD  # rad/s, peak turn rate
    yaw_accel: float = 3.0 * DEG_TO_RAD  # rad/s^2


def _ramp_steps(v0: float, v1: float, rate: float, step: float) -> tuple[int, float]:
    """Whole steps and acceleration taking the speed from v0 to v1 exactly."""
    if v1 == v0:
        return 0, 0.0
    n = max(1, math.ceil(abs(v1 - v0) / (rate * step) - 1e-9))
    return n, (v1 - v0) / (n * step)


@dataclass(frozen=True)
class BodyMotion:
    """Pitch and roll of the vehicle body while it moves (suspension sway and vibration).

    Each angle's rate is a sum of sinusoids scaled by speed / ``reference_speed``
    (so the body is still at a stop and the rate is continuous), sampled on
    the grid and linear in between (constant angular acceleration per step,
    like every gimbal here): a slow sway of amplitude ``sway_*`` (rad) and
    period ``sway_period`` (s), and vibration of amplitude ``vibration`` (rad)
    per component at the frequencies ``vibration_hz`` (our choice: 0.13, 0.29,
    0.41 Hz, below the 0.5 Hz Nyquist limit of a 1 s grid; faster vibration
    needs a finer grid).  Phases come from ``seed``.  Defaults (our choice):
    0.5 deg pitch and 0.3 deg roll sway over 20 s, 0.05 deg vibration at 10 m/s.
    The translational motion is unchanged (a level road): these are attitude
    oscillations of the body, starting level (so their mean can be offset by
    up to an amplitude).
    """

    sway_pitch: float = 0.5 * DEG_TO_RAD
    sway_roll: float = 0.3 * DEG_TO_RAD
    sway_period: float = 20.0
    vibration: float = 0.05 * DEG_TO_RAD
    vibration_hz: tuple = (0.13, 0.29, 0.41)
    reference_speed: float = 10.0
    seed: int = 0

    def __post_init__(self):
        for name in ("sway_pitch", "sway_roll", "sway_period", "vibration", "reference_speed"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"body motion {name} must be a non-negative number, got {value}")
        if not (self.sway_period > 0 and self.reference_speed > 0):
            raise ValueError("sway_period and reference_speed must be positive")
        if not all(math.isfinite(f) and f > 0 for f in self.vibration_hz):
            raise ValueError("vibration frequencies must be positive")

    def rates(self, time: np.ndarray, speed: np.ndarray) -> np.ndarray:
        """Pitch and roll rates (K, 2), rad/s, at the grid ``time`` (K,) s for ``speed`` (K,) m/s."""
        rng = np.random.default_rng([self.seed, 61])
        phase = rng.uniform(0.0, 2 * math.pi, size=(2, 1 + len(self.vibration_hz)))
        w_sway = 2 * math.pi / self.sway_period
        out = np.empty((time.size, 2))
        for j, sway in enumerate((self.sway_pitch, self.sway_roll)):
            rate = sway * w_sway * np.cos(w_sway * time + phase[j, 0])
            for i, f in enumerate(self.vibration_hz):
                w = 2 * math.pi * f
                rate += self.vibration * w * np.cos(w * time + phase[j, i + 1])
            out[:, j] = rate * (speed / self.reference_speed)
        return out


def legs_to_accelerations(legs, step: float = 1.0, settings: DriveSettings = DriveSettings()):
    """Per-step longitudinal (m/s²) and yaw (rad/s²) accelerations of ``legs``.

    Returns
    -------
    accel, yaw_accel : ndarray (K,)
        Held on [k h, (k+1) h).
    """
    acc, yaw = [], []
    speed = 0.0
    for leg in legs:
        kind = leg[0]
        if kind not in LEG_KINDS:
            raise ValueError(f"unknown leg {kind!r}; choose one of {', '.join(LEG_KINDS)}")
        if kind == "turn":
            angle = float(leg[1]) * DEG_TO_RAD
            if not math.isfinite(angle):
                raise ValueError("turn angle must be finite")
            if speed <= 0 and angle != 0:
                raise ValueError("a turn needs a moving vehicle (drive first)")
            for dur, a in turntable.move_segments(angle, settings.yaw_rate, settings.yaw_accel, step):
                n = int(round(dur / step))
                acc += [0.0] * n
                yaw += [a] * n
            continue
        seconds = float(leg[1])
        if not (math.isfinite(seconds) and seconds > 0):
            raise ValueError(f"leg duration must be positive, got {leg[1]!r}")
        target = 0.0 if kind == "stop" else float(leg[2])
        if not (math.isfinite(target) and target >= 0):
            raise ValueError(f"drive speed must be >= 0 m/s, got {target!r}")
        n_ramp, a = _ramp_steps(speed, target, settings.brake if target < speed else settings.accel, step)
        n_total = max(n_ramp, int(round(seconds / step)))
        acc += [a] * n_ramp + [0.0] * (n_total - n_ramp)
        yaw += [0.0] * n_total
        speed = target
    return np.asarray(acc, float), np.asarray(yaw, float)


def random_legs(duration: float, seed: int, *, n_stops: int = 3, stop_range=(600.0, 3000.0),
                speed_range=(8.0, 20.0), leg_range=(120.0, 900.0), turn_probability: float = 0.5):
    """Random drive of about ``duration`` s with ``n_stops`` stops of random length.

    Drive legs of random speed and length alternate with random ±90° (or
    ±45°, ±180°) turns; the stops (uniform in ``stop_range``, s) fall at
    random times; the drive starts and ends at rest.
    """
    if not (math.isfinite(duration) and duration > 0) or n_stops < 0:
        raise ValueError("duration must be positive and n_stops >= 0")
    rng = np.random.default_rng(seed)
    stop_lengths = rng.uniform(*stop_range, size=n_stops)
    drive_time = duration - float(np.sum(stop_lengths))
    if drive_time <= 0:
        raise ValueError("the stops do not fit into the duration")
    stop_at = np.sort(rng.uniform(0.1, 0.9, size=n_stops)) * drive_time
    legs, t, k = [], 0.0, 0
    while t < drive_time:
        seconds = float(min(rng.uniform(*leg_range), max(drive_time - t, 60.0)))
        legs.append(("drive", seconds, float(rng.uniform(*speed_range))))
        t += seconds
        if rng.random() < turn_probability:
            legs.append(("turn", float(rng.choice([-180.0, -90.0, -45.0, 45.0, 90.0, 180.0]))))
        while k < n_stops and stop_at[k] <= t:
            legs.append(("stop", float(stop_lengths[k])))
            k += 1
    legs.append(("stop", 60.0))
    return legs


def _compress(accel: np.ndarray, step: float):
    """Segments [(duration, accel row)] of consecutive equal rows."""
    change = np.flatnonzero(np.any(np.diff(accel, axis=0) != 0.0, axis=1)) + 1
    starts = np.concatenate([[0], change])
    ends = np.concatenate([change, [accel.shape[0]]])
    return [((e - s) * step, accel[s]) for s, e in zip(starts, ends)]


class VehicleTrajectory:
    """Truth motion of a vehicle carrying a single-axis RINS.

    Parameters
    ----------
    legs : list of tuples
        See the module docstring.
    lat, lon : float
        Start position, rad.
    heading : float
        Initial heading (CCW from north), rad.
    step : float
        Grid and IMU output interval, s.
    rotation : str
        RINS rotation scheme about azimuth (:func:`turntable.single_axis`).
    rate_dps, accel_dps2 : float
        RINS rotation rate (°/s) and acceleration (°/s²).
    settings : DriveSettings
    lead_time : float
        Stationary time before the first leg, s (alignment), counted in t.
    body : BodyMotion, optional
        Pitch and roll of the body while moving; then the schedule's gimbals
        are (heading, pitch, roll, RINS rotation), :data:`VEHICLE_BODY_AXES`.

    Attributes
    ----------
    time : (K+1,) grid times, s.  speed : (K+1,) m/s.  heading : (K+1,) rad.
    lat, lon : (K+1,) rad.  velocity_n : (K+1, 3) m/s.
    schedule : GimbalSchedule with axes (heading, RINS rotation), or
        (heading, pitch, roll, RINS rotation) with ``body``.
    """

    def __init__(self, legs, lat: float, lon: float = 0.0, heading: float = 0.0, *, step: float = 1.0,
                 rotation: str = "forward-reverse", rate_dps: float = 6.0, accel_dps2: float = 6.0,
                 settings: DriveSettings = DriveSettings(), lead_time: float = 0.0, body: BodyMotion | None = None):
        for name, value in (("lat", lat), ("lon", lon), ("heading", heading), ("step", step),
                            ("lead_time", lead_time)):
            if not math.isfinite(value):
                raise ValueError(f"{name} must be finite")
        if abs(lat) > 89.9 * DEG_TO_RAD:
            raise ValueError("latitude outside +-89.9 deg")
        if step <= 0 or lead_time < 0:
            raise ValueError("step must be positive and lead_time >= 0")
        acc, yaw_acc = legs_to_accelerations(legs, step, settings)
        n_lead = int(round(lead_time / step))
        acc = np.concatenate([np.zeros(n_lead), acc, [0.0]])
        yaw_acc = np.concatenate([np.zeros(n_lead), yaw_acc, [0.0]])
        n = acc.size
        self.step, self.n_steps = float(step), n
        self.time = np.arange(n + 1) * step
        self.speed = np.concatenate([[0.0], np.cumsum(acc * step)])
        self.speed[np.abs(self.speed) < 1e-12] = 0.0
        if np.any(self.speed < -1e-9):
            raise ValueError("legs give a negative speed")
        yaw_rate = np.concatenate([[0.0], np.cumsum(yaw_acc * step)])
        self.heading = heading + np.concatenate([[0.0], np.cumsum(yaw_rate[:-1] * step + 0.5 * yaw_acc * step**2)])
        rot = turntable.single_axis(rotation, (n + 1) * step, rate_dps=rate_dps, accel_dps2=accel_dps2, grid=step)
        rot_acc = rot.state(self.time[:-1])[2][:, 0]
        if body is None:
            self.axes = VEHICLE_AXES
            columns, angle0 = [yaw_acc, rot_acc], np.array([heading, 0.0])
        else:  # pitch and roll rates linear between grid points: accel = rate difference / step
            body_rate = body.rates(self.time, self.speed)
            body_acc = np.diff(body_rate, axis=0) / step
            self.axes = VEHICLE_BODY_AXES
            columns, angle0 = [yaw_acc, body_acc[:, 0], body_acc[:, 1], rot_acc], np.array([heading, 0.0, 0.0, 0.0])
        self.schedule = turntable.schedule_from_segments(
            self.axes, _compress(np.column_stack(columns), step), angle0=angle0,
            rate0=np.zeros(len(angle0)) if body is None else np.array([0.0, *body_rate[0], 0.0]))
        self._build_motion(lat, lon, acc, yaw_acc, yaw_rate)

    def _velocity_n(self, speed, heading):
        return np.column_stack([-speed * np.sin(heading), speed * np.cos(heading), np.zeros_like(speed)])

    def _build_motion(self, lat0, lon0, acc, yaw_acc, yaw_rate):
        h = self.step
        v_grid = self._velocity_n(self.speed, self.heading)
        # mid-step speed and heading (exact: linear / quadratic in the step)
        speed_mid = self.speed[:-1] + 0.5 * acc * h
        heading_mid = self.heading[:-1] + 0.5 * yaw_rate[:-1] * h + 0.125 * yaw_acc * h**2
        v_mid = self._velocity_n(speed_mid, heading_mid)
        # Simpson mean velocity over each step
        v_mean = (v_grid[:-1] + 4.0 * v_mid + v_grid[1:]) / 6.0
        # latitude/longitude by two vectorised passes (radii at the first-pass latitudes)
        lat = np.full(self.n_steps + 1, float(lat0))
        for _ in range(2):
            r_m, r_n = earth.radii(lat[:-1])
            lat = lat0 + np.concatenate([[0.0], np.cumsum(v_mean[:, 1] * h / r_m)])
        lat_mid = 0.5 * (lat[:-1] + lat[1:])
        r_m, r_n = earth.radii(lat_mid)
        lon = lon0 + np.concatenate([[0.0], np.cumsum(v_mean[:, 0] * h / (r_n * np.cos(lat_mid)))])
        zeros = np.zeros_like(lat_mid)
        w_ie = earth.RATE * np.column_stack([zeros, np.cos(lat_mid), np.sin(lat_mid)])
        w_en = np.column_stack([-v_mean[:, 1] / r_m, v_mean[:, 0] / r_n, v_mean[:, 0] * np.tan(lat_mid) / r_n])
        g = earth.gravity(lat_mid, 0.0)
        w_it = w_ie + w_en
        # f = dv/dt + (2 w_ie + w_en) x v - g^n,  g^n = (0, 0, -g)
        f_n = (v_grid[1:] - v_grid[:-1]) / h + np.cross(2.0 * w_ie + w_en, v_mean)
        f_n[:, 2] += g
        self.lat, self.lon, self.velocity_n = lat, lon, v_grid
        self._w_it, self._f = w_it, f_n

    @property
    def duration(self) -> float:
        return self.n_steps * self.step

    def base_motion(self, t_start, h):
        """Moving-base interface of :class:`~sarins_fmu.imu.IMU`: inertial rate
        (rad/s) and specific force (m/s²) of the local-level frame held over
        each step starting at ``t_start`` (K,), resolved in that frame."""
        if abs(h - self.step) > 1e-9 * self.step:
            raise ValueError(f"the trajectory was built on a {self.step} s grid, not {h} s")
        k = np.rint(np.asarray(t_start, float) / self.step).astype(int)
        if np.any(k < 0) or np.any(k >= self.n_steps):
            raise ValueError(f"time outside the trajectory (0 .. {self.duration} s)")
        return self._w_it[k], self._f[k]

    def mat_nb(self, k: int) -> np.ndarray:
        """True IMU attitude at grid point ``k``, mat_nb (3, 3)."""
        angle = self.schedule.state(self.time[k])[0][0]
        return turntable.chain_matrix(self.axes, angle)

    def moving(self) -> np.ndarray:
        """(K+1,) bool: speed above zero at each grid point."""
        return self.speed > 1e-6
