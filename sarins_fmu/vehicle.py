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

The trajectory, the body's sway and vibration and their seeded phases are
computed by the C core (``sarins_fmu/core/vehicle.h``, which states the
equations), step by step; the VehicleMotion FMU runs the same C, so its
outputs equal :class:`VehicleTrajectory`'s rows bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import turntable
from .core import vehicle as core
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
    needs a finer grid).  Phases are 2π u, u the uniforms of the core's random
    stream ``SARINS_VEHICLE_STREAM`` of ``seed`` (``sarins_fmu/core/vehicle.h``).  Defaults (our choice):
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
        if len(self.vibration_hz) != core.N_VIBRATION:
            raise ValueError(f"body motion needs {core.N_VIBRATION} vibration frequencies, got {self.vibration_hz!r}")
        if not 0 <= int(self.seed) < 2**64:
            raise ValueError(f"body motion seed must be in [0, 2^64), got {self.seed}")
        core.segments(_params(0.0, 0.0, 0.0, 1.0, 0.0, DriveSettings(), self), [])  # the core's checks


def _params(lat, lon, heading, step, lead_time, settings: DriveSettings, body: BodyMotion) -> core.Params:
    """The core's parameter struct (SI)."""
    p = core.default_params()
    for name, value in (("lat0", lat), ("lon0", lon), ("heading0", heading), ("step", step),
                        ("lead_time", lead_time), ("accel", settings.accel), ("brake", settings.brake),
                        ("yaw_rate", settings.yaw_rate), ("yaw_accel", settings.yaw_accel),
                        ("sway_pitch", body.sway_pitch), ("sway_roll", body.sway_roll),
                        ("sway_period", body.sway_period), ("vibration", body.vibration),
                        ("reference_speed", body.reference_speed)):
        setattr(p, name, float(value))
    for i, f in enumerate(body.vibration_hz):
        p.vibration_hz[i] = float(f)
    p.seed = int(body.seed)
    return p


RIGID_BODY = BodyMotion(0.0, 0.0, vibration=0.0)  # no sway or vibration


def legs_to_accelerations(legs, step: float = 1.0, settings: DriveSettings = DriveSettings()):
    """Per-step longitudinal (m/s²) and yaw (rad/s²) accelerations of ``legs``.

    Returns
    -------
    accel, yaw_accel : ndarray (K,)
        Held on [k h, (k+1) h).
    """
    segs, _ = core.segments(_params(0.0, 0.0, 0.0, step, 0.0, settings, RIGID_BODY), legs)
    segs = segs[:-1]  # the core's last step at rest belongs to the trajectory, not to the legs
    return (np.repeat([a for _, a, _ in segs], [n for n, _, _ in segs]),
            np.repeat([y for _, _, y in segs], [n for n, _, _ in segs]))


def parse_legs(text: str) -> list:
    """Legs from the VehicleMotion FMU's text form: ``'drive 300 10; turn 90; stop 1800'`` ->
    ``[('drive', 300.0, 10.0), ('turn', 90.0), ('stop', 1800.0)]`` (turns in degrees).  The FMU's own parser
    (the C core's); ValueError with its reason for a text it refuses."""
    return core.parse_legs(text)


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
    rows : (K+1, len(sarins_fmu.core.vehicle.COLUMNS)): row k describes the step
        from ``time[k]`` (the C core's stream; the VehicleMotion FMU's outputs
        at that time, bit for bit).
    schedule : GimbalSchedule with axes (heading, RINS rotation), or
        (heading, pitch, roll, RINS rotation) with ``body``; its breakpoints
        are the grid points, its states there the rows'.

    Raises ValueError with the core's reason for a bad parameter or leg, or a
    drive that leaves +-89.9 deg latitude.
    """

    def __init__(self, legs, lat: float, lon: float = 0.0, heading: float = 0.0, *, step: float = 1.0,
                 rotation: str = "forward-reverse", rate_dps: float = 6.0, accel_dps2: float = 6.0,
                 settings: DriveSettings = DriveSettings(), lead_time: float = 0.0, body: BodyMotion | None = None):
        rows = core.run(_params(lat, lon, heading, step, lead_time, settings, RIGID_BODY if body is None else body),
                        legs)
        n = rows.shape[0] - 1
        col = {name: j for j, name in enumerate(core.COLUMNS)}
        self.step, self.n_steps = float(step), n
        self.rows = rows
        self.time = np.arange(n + 1) * step
        self.speed = rows[:, col["speed"]].copy()
        self.heading = rows[:, col["yaw"]].copy()
        self.lat, self.lon = rows[:, col["lat"]].copy(), rows[:, col["lon"]].copy()
        self.velocity_n = np.column_stack([rows[:, col["v_e"]], rows[:, col["v_n"]], np.zeros(n + 1)])
        self._w_it = np.ascontiguousarray(rows[:-1, col["w_e"]:col["w_u"] + 1])
        self._f = np.ascontiguousarray(rows[:-1, col["f_e"]:col["f_u"] + 1])
        rot = turntable.single_axis(rotation, (n + 1) * step, rate_dps=rate_dps, accel_dps2=accel_dps2, grid=step)
        rot_state = rot.state(self.time)
        names = ("yaw",) if body is None else ("yaw", "pitch", "roll")
        self.axes = VEHICLE_AXES if body is None else VEHICLE_BODY_AXES
        tables = [np.column_stack([rows[:, [col[a + q] for a in names]], r[:, 0]])
                  for q, r in zip(("", "_rate", "_accel"), rot_state)]
        self.schedule = turntable.GimbalSchedule.from_breakpoints(self.axes, self.time, tables[0], tables[1],
                                                                  tables[2][:-1])

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
