"""Multi-temperature-point compensation of the axial gyro drift (seed 000 sec. 2.3).

Seed 000, sec. 2.3, second paragraph: "轴向陀螺漂移经过多温度点补偿后[15]，
利用热态 RBF 神经网络进行辨识，结果如表 4 所示" -- *after the axial gyro
drift has been compensated at multiple temperature points [15], it is
identified with the hot-start RBF network; the results are in Table 4*
(the column "热态 RBF 辨识结果").  The paper then finds this drift "hard to
remove by temperature compensation" (这种轴向陀螺漂移很难通过温度补偿进行消除)
and trains the cold-start network.  Its reference [15] (Zhang et al., Acta
Armamentarii 31(5), 2010) is a *real-time* multi-temperature-point
compensation of a dithered RLG; the seed gives no more detail, so this
module implements the reading stated here:

* **Calibration** (:func:`calibrate_axial_drift`): the unit stands still
  (z axis up, no rotation) in a chamber held at a sequence of temperature
  points.  At each point, once the gyro has settled, the mean z-gyro rate
  over an averaging window minus the Earth-rate component W sin L is the
  drift at the mean reported z-gyro temperature of that window.  One
  session, one turn-on: the turn-on constant of that session is in every
  point, and the identification that follows removes the difference to the
  constant of a later run.
* **Table** (:class:`MultiTemperatureTable`): the calibrated points,
  interpolated linearly in temperature between points and held at the
  end points outside them.
* **Real-time compensation**: the table's drift at the reported z-gyro
  temperature is subtracted from every z angle increment, from switch-on
  (``run_static(axial_table=...)``).  What remains for the network is the
  turn-on constant, the temperature-rate and block-gradient parts of the
  drift (zero at the calibration's steady points), the hysteresis loop's
  branch (the calibration approaches its points from below, on the heating
  branch) and the calibration's own error.

Units: temperatures degC, drifts deg/h in the table (the seed's units),
rad/s from :meth:`MultiTemperatureTable.correction`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..earth import RATE
from ..units import DPH_TO_RPS, HOUR
from .modelfile import ModelFileError

FORMAT = "sarins_fmu.identify.multitemp"


@dataclass(frozen=True)
class MultiTemperatureTable:
    """Axial drift at calibration temperature points.

    temp_c : strictly increasing z-gyro temperatures of the points, degC
    drift_dph : drift measured at each point, deg/h
    """

    temp_c: tuple
    drift_dph: tuple

    def __post_init__(self):
        t = np.asarray(self.temp_c, float)
        d = np.asarray(self.drift_dph, float)
        if t.ndim != 1 or t.shape != d.shape or t.size < 2:
            raise ValueError("a multi-temperature table needs at least 2 points, as many drifts as temperatures")
        if not (np.isfinite(t).all() and np.isfinite(d).all()):
            raise ValueError("multi-temperature table values must be finite")
        if np.any(np.diff(t) <= 0):
            raise ValueError("multi-temperature table temperatures must be strictly increasing")
        object.__setattr__(self, "temp_c", tuple(float(x) for x in t))
        object.__setattr__(self, "drift_dph", tuple(float(x) for x in d))

    def drift_at(self, temp_c) -> np.ndarray:
        """Table drift (deg/h) at temperatures ``temp_c`` (degC): linear between
        points, the end values outside."""
        return np.interp(np.asarray(temp_c, float), self.temp_c, self.drift_dph)

    def correction(self, temp_c) -> np.ndarray:
        """Drift to subtract (rad/s) at the reported z-gyro temperatures ``temp_c`` (degC)."""
        return self.drift_at(temp_c) * DPH_TO_RPS

    def to_dict(self) -> dict:
        return {"temp_c": list(self.temp_c), "drift_dph": list(self.drift_dph)}

    @classmethod
    def from_dict(cls, data: dict) -> "MultiTemperatureTable":
        return cls(tuple(np.asarray(data["temp_c"], float)), tuple(np.asarray(data["drift_dph"], float)))

    def save(self, path) -> Path:
        """Write the table as plain JSON."""
        path = Path(path)
        path.write_text(json.dumps({"format": FORMAT, "version": 1, **self.to_dict()}, indent=1))
        return path

    @classmethod
    def load(cls, path) -> "MultiTemperatureTable":
        """Read a table written by :meth:`save`; :class:`ModelFileError` names the file otherwise."""
        path = Path(path)
        try:
            data = json.loads(path.read_text())
        except (OSError, ValueError) as exc:
            raise ModelFileError(path, f"cannot read it ({type(exc).__name__})") from None
        if not isinstance(data, dict) or data.get("format") != FORMAT:
            raise ModelFileError(path, f"not a multi-temperature table (format {FORMAT!r})")
        try:
            return cls.from_dict(data)
        except (KeyError, TypeError, ValueError) as exc:
            raise ModelFileError(path, str(exc)) from None


def staircase(points_ambient_c, settle_hours: float, average_hours: float,
              ramp_hours: float) -> tuple[np.ndarray, np.ndarray, list]:
    """Chamber profile holding each ambient point for settle + average hours,
    with linear ramps between points.

    Returns (profile times s, profile temperatures degC, [(start s, end s)]
    of each averaging window)."""
    hold = (settle_hours + average_hours) * HOUR
    times, temps, windows = [0.0], [float(points_ambient_c[0])], []
    t = 0.0
    for i, amb in enumerate(points_ambient_c):
        if i:
            t += ramp_hours * HOUR
            times.append(t)
            temps.append(float(amb))
        t += hold
        times.append(t)
        temps.append(float(amb))
        windows.append((t - average_hours * HOUR, t))
    return np.array(times), np.array(temps), windows


def calibrate_axial_drift(model, *, points_c, lat_deg: float, settle_hours: float = 20.0,
                          average_hours: float = 4.0, ramp_hours: float = 0.5, seed: int = 0,
                          step: float = 1.0, internal_rate: float = 10.0) -> MultiTemperatureTable:
    """Simulated chamber calibration of the z gyro at temperature points.

    Parameters
    ----------
    model : :class:`sarins_fmu.imu.ImuModel` of the unit (its thermal model
        maps the chamber ambient to the gyro temperature)
    points_c : z-gyro temperatures of the points, degC; the chamber is held
        at each point minus the z gyro's self-heating
    lat_deg : latitude of the calibration, deg (Earth rate on the z axis)
    settle_hours, average_hours : hold per point: settling, then averaging, h
    ramp_hours : chamber ramp between points, h
    seed : noise seed of the session; step : output interval, s
    internal_rate : the IMU's minor-step rate, Hz (the unit stands still, so
        its body rate is the constant Earth rate and a few minor steps per
        interval integrate it exactly; the noise is drawn per interval)

    Returns the measured :class:`MultiTemperatureTable` (points sorted by
    measured temperature).
    """
    from ..imu import IMU, StaticBase
    from ..thermal import Ambient

    points = np.sort(np.asarray(points_c, float))
    for name, value in (("settle_hours", settle_hours), ("average_hours", average_hours),
                        ("ramp_hours", ramp_hours)):
        if not (math.isfinite(value) and value >= 0):
            raise ValueError(f"{name} must be a non-negative number, got {value}")
    if average_hours <= 0 or points.size < 2:
        raise ValueError("the calibration needs an averaging window and at least 2 points")
    heating = float(model.thermal.self_heating[2])
    times, temps, windows = staircase(points - heating, settle_hours, average_hours, ramp_hours)
    lat = math.radians(lat_deg)
    imu = IMU(model, StaticBase(lat, 0.0, 0.0, 0.0), np.array([[0.0, 0.0, 1.0]]), output_interval=step,
              internal_rate=internal_rate, seed=seed, thermal_start="hot",
              ambient=Ambient(profile=(tuple(times), tuple(temps))))
    n = round(times[-1] / step)
    t_end = np.arange(1, n + 1) * step
    rate_z = np.empty(n)
    temp_z = np.empty(n)
    chunk = 3600
    for k0 in range(0, n, chunk):
        k1 = min(n, k0 + chunk)
        still = np.zeros((k1 - k0, 1))  # gimbal angle, rate, acceleration: the unit stands still
        dtheta, _, temp = imu.step(still, still, still)
        rate_z[k0:k1] = dtheta[:, 2] / step
        temp_z[k0:k1] = temp[:, 2]
    earth_z = RATE * math.sin(lat)
    t_pts, d_pts = [], []
    for start, end in windows:
        sel = (t_end > start) & (t_end <= end)
        t_pts.append(float(np.mean(temp_z[sel])))
        d_pts.append(float((np.mean(rate_z[sel]) - earth_z) / DPH_TO_RPS))
    order = np.argsort(t_pts)
    return MultiTemperatureTable(tuple(np.asarray(t_pts)[order]), tuple(np.asarray(d_pts)[order]))
