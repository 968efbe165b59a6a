"""Vehicle trajectories from segments, and the truth an ideal IMU sees along them.

A trajectory is a start (position, heading, speed, pitch) and a list of segments, given as a
Python list of dicts or a JSON file ``{"start": {...}, "segments": [...]}``:

* ``{"kind": "stop", "duration": s}``: stand still (the speed must already be 0);
* ``{"kind": "accelerate", "to_speed": m/s, "accel": m/s^2}`` (duration from the speed change,
  rounded up to the grid; the acceleration then adjusted to reach ``to_speed`` exactly), or with
  ``"duration"`` and ``"to_speed"``, or ``"duration"`` and ``"accel"`` (negative brakes);
* ``{"kind": "cruise", "duration": s}``, optionally ``"speed"``: the current speed, checked;
* ``{"kind": "turn", "rate_dps": deg/s, "duration" | "angle_deg"}`` or
  ``{"kind": "turn", "radius": m, "angle_deg": deg}`` (positive angle or rate = left, CCW; with
  ``angle_deg`` the angle's sign gives the direction; a radius turn keeps the speed, yaw rate =
  speed / radius; the duration is put on the grid and the rate adjusted to turn the angle exactly);
* ``{"kind": "climb", "to_pitch_deg": deg, "duration": s}``: pitch (flight-path angle) changes at a
  constant rate to ``to_pitch_deg``; the vehicle climbs while its pitch is not 0.

Start keys: ``lat_deg``, ``lon_deg``, ``height`` (m), ``heading_deg`` (CCW from north), ``speed``
(m/s), ``pitch_deg``; all default 0 except ``lat_deg`` (required).

Durations are whole numbers of IMU steps (a duration within 1e-6 s of the grid is put on it;
others are refused), so speed, heading and pitch are continuous and the acceleration and rates
change only on the grid.  The truth (:class:`Truth`) and the IMU increments come from one C kernel
(``sarins_fmu/core/traj.h``): positions (lat, lon, h), ENU velocity, attitude (yaw, pitch, roll of
mat_nb = Rz Rx Ry, body right-front-up), and the ideal IMU's angular rate and specific force in
the body frame, integrated together so that the increments navigate back to the truth.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .core import aided as _core
from .units import DEG_TO_RAD

SEGMENT_KINDS = ("stop", "accelerate", "cruise", "turn", "climb")
_GRID_TOL = 1e-6  # s: a duration this close to the grid is put on it
_SPEED_TOL = 1e-6  # m/s: speeds this close count as equal (continuity checks)


class TrajectoryError(ValueError):
    """A trajectory that cannot be built; the message names the segment and the reason."""


@dataclass(frozen=True)
class Start:
    """Start of a trajectory (degrees only here, at the edge; SI inside)."""

    lat_deg: float
    lon_deg: float = 0.0
    height: float = 0.0  # m
    heading_deg: float = 0.0  # CCW from north
    speed: float = 0.0  # m/s
    pitch_deg: float = 0.0

    def __post_init__(self):
        for name in ("lat_deg", "lon_deg", "height", "heading_deg", "speed", "pitch_deg"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value)):
                raise TrajectoryError(f"start {name} must be a finite number, got {value!r}")
        if abs(self.lat_deg) > 89.9:
            raise TrajectoryError(f"start lat_deg {self.lat_deg} is outside +-89.9 deg")
        if self.speed < 0:
            raise TrajectoryError(f"start speed must be >= 0 m/s, got {self.speed}")
        if abs(self.pitch_deg) >= 89.0:
            raise TrajectoryError(f"start pitch_deg {self.pitch_deg} is outside +-89 deg")

    def array(self) -> np.ndarray:
        """The start array of ``sarins_traj_run`` (SI)."""
        return np.array([self.lat_deg * DEG_TO_RAD, self.lon_deg * DEG_TO_RAD, self.height, self.speed,
                         self.heading_deg * DEG_TO_RAD, self.pitch_deg * DEG_TO_RAD])


@dataclass(frozen=True)
class Trajectory:
    """A start and its segments (dicts as in the module docstring)."""

    start: Start
    segments: tuple = field(default_factory=tuple)

    @classmethod
    def from_dict(cls, data, source: str = "trajectory") -> "Trajectory":
        if not isinstance(data, dict) or not isinstance(data.get("start"), dict) \
                or not isinstance(data.get("segments"), list):
            raise TrajectoryError(f"{source}: needs an object with 'start' (object) and 'segments' (list)")
        unknown = set(data["start"]) - set(Start.__dataclass_fields__)
        if unknown:
            raise TrajectoryError(f"{source}: unknown start key(s) {', '.join(sorted(unknown))}")
        if "lat_deg" not in data["start"]:
            raise TrajectoryError(f"{source}: start needs lat_deg")
        if not data["segments"]:
            raise TrajectoryError(f"{source}: no segments")
        return cls(Start(**data["start"]), tuple(data["segments"]))

    def table(self, step: float) -> np.ndarray:
        """Segment table (n, 4) of ``sarins_traj_run`` on a grid of ``step`` s: steps, accel (m/s^2),
        yaw rate (rad/s), pitch rate (rad/s).  Raises TrajectoryError naming the segment."""
        if not (math.isfinite(step) and step > 0):
            raise TrajectoryError(f"IMU step must be positive, got {step}")
        speed, pitch = self.start.speed, self.start.pitch_deg * DEG_TO_RAD
        rows = []
        for i, seg in enumerate(self.segments):
            row = _segment_row(i, seg, speed, pitch, step)
            rows.append(row)
            tau = row[0] * step
            speed = max(0.0, speed + row[1] * tau)
            if speed < _SPEED_TOL:
                speed = 0.0
            pitch += row[3] * tau
        return np.array(rows, float)

    def duration(self, step: float) -> float:
        """Length of the trajectory on a grid of ``step`` s, s."""
        return float(np.sum(self.table(step)[:, 0])) * step


def load_trajectory(path) -> Trajectory:
    """A trajectory from a JSON file (TrajectoryError naming the file for a bad one)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise TrajectoryError(f"{path}: cannot read ({exc.__class__.__name__})") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise TrajectoryError(f"{path}: not JSON ({exc.msg} at line {exc.lineno})") from None
    return Trajectory.from_dict(data, str(path))


def _number(i: int, seg: dict, key: str, *, positive: bool = False) -> float:
    value = seg.get(key)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise TrajectoryError(f"segment {i} ({seg.get('kind')}): {key} must be a finite number, got {value!r}")
    if positive and value <= 0:
        raise TrajectoryError(f"segment {i} ({seg.get('kind')}): {key} must be positive, got {value!r}")
    return float(value)


def _steps(i: int, seg: dict, seconds: float, step: float) -> int:
    n = round(seconds / step)
    if n < 1 or abs(n * step - seconds) > _GRID_TOL:
        raise TrajectoryError(f"segment {i} ({seg['kind']}): duration {seconds:g} s is not a positive whole "
                              f"number of IMU steps ({step:g} s)")
    return int(n)


_KEYS = {"stop": {"duration"}, "cruise": {"duration", "speed"}, "accelerate": {"duration", "to_speed", "accel"},
         "turn": {"duration", "rate_dps", "radius", "angle_deg"}, "climb": {"duration", "to_pitch_deg"}}


def _segment_row(i: int, seg, speed: float, pitch: float, step: float) -> list:
    """[steps, accel, yaw rate, pitch rate] of segment ``i`` entered at ``speed`` (m/s), ``pitch`` (rad)."""
    if not isinstance(seg, dict) or seg.get("kind") not in SEGMENT_KINDS:
        kind = seg.get("kind") if isinstance(seg, dict) else seg
        raise TrajectoryError(f"segment {i}: unknown kind {kind!r}; choose one of {', '.join(SEGMENT_KINDS)}")
    kind = seg["kind"]
    unknown = set(seg) - _KEYS[kind] - {"kind"}
    if unknown:
        raise TrajectoryError(f"segment {i} ({kind}): unknown key(s) {', '.join(sorted(unknown))}")
    if kind == "stop":
        if speed > _SPEED_TOL:
            raise TrajectoryError(f"segment {i} (stop): trajectory discontinuity: the vehicle moves at {speed:g} m/s "
                                  "(decelerate to 0 first)")
        return [_steps(i, seg, _number(i, seg, "duration", positive=True), step), 0.0, 0.0, 0.0]
    if kind == "cruise":
        if "speed" in seg and abs(_number(i, seg, "speed") - speed) > _SPEED_TOL:
            raise TrajectoryError(f"segment {i} (cruise): trajectory discontinuity: speed {seg['speed']!r} m/s, "
                                  f"the vehicle moves at {speed:g} m/s")
        return [_steps(i, seg, _number(i, seg, "duration", positive=True), step), 0.0, 0.0, 0.0]
    if kind == "accelerate":
        return _accelerate(i, seg, speed, step)
    if kind == "turn":
        return _turn(i, seg, speed, step)
    target = _number(i, seg, "to_pitch_deg") * DEG_TO_RAD
    if abs(target) >= 89.0 * DEG_TO_RAD:
        raise TrajectoryError(f"segment {i} (climb): to_pitch_deg must be within +-89 deg")
    n = _steps(i, seg, _number(i, seg, "duration", positive=True), step)
    return [n, 0.0, 0.0, (target - pitch) / (n * step)]


def _accelerate(i: int, seg: dict, speed: float, step: float) -> list:
    has = {k for k in ("duration", "to_speed", "accel") if k in seg}
    if has == {"to_speed", "accel"}:
        target, accel = _number(i, seg, "to_speed"), _number(i, seg, "accel", positive=True)
        n = max(1, math.ceil(abs(target - speed) / (accel * step) - 1e-9))
    elif has == {"duration", "to_speed"}:
        target = _number(i, seg, "to_speed")
        n = _steps(i, seg, _number(i, seg, "duration", positive=True), step)
    elif has == {"duration", "accel"}:
        n = _steps(i, seg, _number(i, seg, "duration", positive=True), step)
        target = speed + _number(i, seg, "accel") * n * step
    else:
        raise TrajectoryError(f"segment {i} (accelerate): give two of duration, to_speed, accel "
                              "(to_speed with accel or duration)")
    if target < -_SPEED_TOL:
        raise TrajectoryError(f"segment {i} (accelerate): the speed would turn negative ({target:g} m/s)")
    return [n, (max(target, 0.0) - speed) / (n * step), 0.0, 0.0]


def _turn(i: int, seg: dict, speed: float, step: float) -> list:
    if "radius" in seg:
        if "rate_dps" in seg or "duration" in seg or "angle_deg" not in seg:
            raise TrajectoryError(f"segment {i} (turn): a radius turn takes radius and angle_deg only")
        radius = _number(i, seg, "radius", positive=True)
        if speed <= _SPEED_TOL:
            raise TrajectoryError(f"segment {i} (turn): a turn of radius {radius:g} m needs a moving vehicle")
        angle = _number(i, seg, "angle_deg") * DEG_TO_RAD
        rate = math.copysign(speed / radius, angle)
    else:
        rate = _number(i, seg, "rate_dps") * DEG_TO_RAD
        if ("duration" in seg) == ("angle_deg" in seg):
            raise TrajectoryError(f"segment {i} (turn): give rate_dps with duration or with angle_deg")
        if "duration" in seg:
            n = _steps(i, seg, _number(i, seg, "duration", positive=True), step)
            return [n, 0.0, rate, 0.0]
        angle = _number(i, seg, "angle_deg") * DEG_TO_RAD
        if rate == 0:
            raise TrajectoryError(f"segment {i} (turn): rate_dps must not be 0 with angle_deg")
        rate = math.copysign(rate, angle)  # the angle gives the direction
    n = max(1, round(abs(angle / rate) / step))
    return [n, 0.0, angle / (n * step), 0.0]  # the angle exactly; the rate on the grid


@dataclass(frozen=True)
class Truth:
    """Truth along a trajectory on the IMU grid (K steps, K+1 points) and the ideal IMU's increments.

    time (K+1,) s; lat, lon (K+1,) rad; height (K+1,) m; velocity_n (K+1, 3) ENU m/s; attitude
    (K+1, 3) yaw, pitch, roll rad (mat_nb = Rz Rx Ry, body right-front-up); omega_ib_b (K+1, 3) rad/s
    and f_b (K+1, 3) m/s^2, the ideal IMU's angular rate and specific force in the body frame at
    each point (on the segment starting there); dtheta, dv (K, 3) rad, m/s: the increments over
    each step (rotation vector; specific-force increment in the body frame at the step's start).
    """

    step: float
    time: np.ndarray
    lat: np.ndarray
    lon: np.ndarray
    height: np.ndarray
    velocity_n: np.ndarray
    attitude: np.ndarray
    omega_ib_b: np.ndarray
    f_b: np.ndarray
    dtheta: np.ndarray
    dv: np.ndarray

    @property
    def n_steps(self) -> int:
        return self.dtheta.shape[0]

    def nav_rows(self, index=None) -> np.ndarray:
        """(K+1, 9) rows lat, lon, h, v E N U, yaw, pitch, roll (the INS's output layout); only the
        rows at ``index`` (an integer array) when given."""
        if index is None:
            return np.column_stack([self.lat, self.lon, self.height, self.velocity_n, self.attitude])
        index = np.asarray(index)
        return np.column_stack([self.lat[index], self.lon[index], self.height[index], self.velocity_n[index],
                                self.attitude[index]])

    def stationary(self) -> np.ndarray:
        """(K,) bool: the vehicle stands still over each step (zero speed and no body rotation wrt
        the Earth at both ends): the steps where a zero-velocity update is true.  The core's decision
        (``sarins_aid_still``: speed below 1e-9 m/s at both ends), the one the TrajectoryIMU FMU makes."""
        return _core.aid_still(self.velocity_n)


def generate(trajectory: Trajectory, step: float, substeps: int = 8) -> Truth:
    """Truth and ideal IMU increments along ``trajectory`` with IMU step ``step`` (s), ``substeps``
    Runge-Kutta sub-intervals per step (the C kernel ``sarins_traj_run``)."""
    if not isinstance(substeps, int) or substeps < 1:
        raise TrajectoryError(f"substeps must be a positive integer, got {substeps!r}")
    table = trajectory.table(step)
    try:
        rows, dtheta, dv = _core.traj_run(table, trajectory.start.array(), step, substeps)
    except ValueError as exc:
        raise TrajectoryError(str(exc)) from None
    k = dtheta.shape[0]
    return Truth(step=float(step), time=np.arange(k + 1) * step, lat=rows[:, 0], lon=rows[:, 1], height=rows[:, 2],
                 velocity_n=rows[:, 3:6], attitude=rows[:, 6:9], omega_ib_b=rows[:, 9:12], f_b=rows[:, 12:15],
                 dtheta=dtheta, dv=dv)
