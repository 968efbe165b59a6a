"""Online update of the azimuth-drift temperature model at stops (seed 002, Fig. 2).

The logic of the paper's Fig. 2, fed row by row (or block by block) with
the vehicle's speed and the free INS's outputs:

1. **stop detection**: the vehicle is stopped while its speed (odometer)
   is below ``speed_threshold``; the INS must be navigating (``active``);
2. at the start of a stop the stop Kalman filter
   (:class:`sarins_fmu.kalman.StopKalmanFilter`) is **reset** and a
   **timer** starts; during the stop the filter runs on the INS's velocity
   and attitude and the azimuth gyro temperature is averaged (T_gz);
3. when the vehicle **moves off**: if the timer reached the **threshold**
   (30 min) the estimate (T_gz, ε_U) updates the model by the
   forgetting-factor RLS (eqs 16-18); otherwise the estimate is discarded
   (filter reset, timer cleared);
4. at every row the **compensation drift** is the current model at the
   current temperature, ε(T) = a T² + b T + c, which the INS subtracts.

The row logic, the stop filter and the RLS run in the C core
(``sarins_fmu/core/online.h``, ``stop_filter.h``, ``rls.h``): the code the
DriftModelUpdater FMU runs row by row, so the two agree bit for bit.

Units: s, m/s, rad, rad/s, °C.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..core import online as core_online
from ..kalman import STOP_TIME_THRESHOLD, StopFilterSettings, StopKalmanFilter
from .rls import ForgettingRLS

EVENT_DTYPE = np.dtype([("time", float), ("kind", "U6"), ("duration", float), ("temperature", float),
                        ("drift", float), ("drift_std", float)])


def prior_covariance(points: float = 11.0, t_min: float = 0.0, t_max: float = 50.0) -> np.ndarray:
    """P0 of an initial model worth ``points`` calibration points spread evenly
    over ``t_min``..``t_max`` °C: (Σ w h h')^-1 with 11 nodes of weight points/11
    (the C core's ``sarins_rls_prior_covariance``, Cholesky inverse, symmetrized)."""
    return core_online.prior_covariance(points, t_min, t_max)


@dataclass(frozen=True)
class UpdaterSettings:
    """Thresholds of the online update (Fig. 2).

    Attributes
    ----------
    time_threshold : float
        Shortest stop whose estimate updates the model, s (paper: 30 min).
    speed_threshold : float
        Speed below which the vehicle counts as stopped, m/s.
    """

    time_threshold: float = STOP_TIME_THRESHOLD
    speed_threshold: float = 0.01

    def __post_init__(self):
        for name in ("time_threshold", "speed_threshold"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be positive and finite, got {value!r}")


class OnlineDriftUpdater:
    """Fig. 2 of seed 002: stop detection, timer, threshold, reset, RLS update.

    Parameters
    ----------
    rls : ForgettingRLS
        The model to update (°C, drift in rad/s, time in s); used in place.
    lat : float
        Latitude, rad (the stop filter's; updated by the ``lat`` inputs).
    dt : float
        Row interval, s (the INS output step).
    filter_settings : StopFilterSettings
    settings : UpdaterSettings

    Attributes
    ----------
    stopped : bool
        The vehicle is in a stop being estimated (the C core's flag).
    timer : float
        Estimation time of the current stop, s.
    events : list of tuples
        (time, 'update' | 'reset', duration, T_gz, ε_U, σ) per finished stop.
    """

    def __init__(self, rls: ForgettingRLS, lat: float, dt: float = 1.0,
                 filter_settings: StopFilterSettings = StopFilterSettings(),
                 settings: UpdaterSettings = UpdaterSettings()):
        self.rls, self.settings = rls, settings
        self.filter = StopKalmanFilter(lat, filter_settings, dt)
        self.dt = float(dt)
        self._state = core_online.OnlineState(settings.time_threshold, settings.speed_threshold)
        self.events: list[tuple] = []

    @property
    def stopped(self) -> bool:
        """The vehicle is in a stop being estimated."""
        return self._state.stopped

    @property
    def timer(self) -> float:
        return self.filter.elapsed if self.stopped else 0.0

    def compensation(self, temperature) -> np.ndarray:
        """Drift the INS should subtract at ``temperature`` (°C), rad/s."""
        return self.rls.predict(temperature)

    def step(self, time, speed, velocity_en, attitude, temperature, lat=None, active=True) -> np.ndarray:
        """Process K rows; returns the compensation drift (K,) rad/s of each row.

        Parameters
        ----------
        time : (K,) row end times, s.  speed : (K,) vehicle speed, m/s.
        velocity_en : (K, 2) INS velocity, m/s.  attitude : (K, 3) INS yaw,
        pitch, roll, rad.  temperature : (K,) azimuth gyro temperature, °C.
        lat : (K,) INS latitude, rad (default the current one).
        active : bool or (K,) the INS is navigating (rows in alignment are
            treated as moving).

        The compensation of a row is computed with the model after an
        update triggered at that row (the first moving row after a stop).
        The rows run through the C core's ``sarins_online_rows`` (one call);
        ValueError if a row is refused (the rows before it are processed).
        """
        t = np.atleast_1d(np.asarray(time, float))
        n = t.size
        vel = np.atleast_2d(np.asarray(velocity_en, float)).reshape(n, 2)
        att = np.atleast_2d(np.asarray(attitude, float)).reshape(n, 3)
        comp, events, why = self._state.rows(self.rls._state, self.filter._state, t, speed, vel, att, temperature,
                                             lat, active)
        self._record(events)
        if why is not None:
            raise ValueError(why)
        return comp

    def _record(self, events: np.ndarray) -> None:
        for e in events:
            self.events.append((float(e["time"]), "update" if e["used"] else "reset", float(e["duration"]),
                                float(e["temperature"]), float(e["drift"]), float(e["drift_std"])))

    def finish_stop(self, time: float) -> None:
        """The vehicle moves off at ``time`` (s): update the model if the stop
        lasted the threshold, else discard it; reset the filter and timer.
        :meth:`step` calls it at the first moving row; call it directly to
        get the updated compensation before the INS processes that row."""
        self._record(self._state.finish(self.rls._state, self.filter._state, float(time)))

    def event_table(self) -> np.ndarray:
        """Finished stops as a structured array (:data:`EVENT_DTYPE`)."""
        return np.array(self.events, dtype=EVENT_DTYPE)

    def to_dict(self) -> dict:
        """Model and settings as plain data (a stop in progress is not saved)."""
        return {"rls": self.rls.to_dict(), "settings": asdict(self.settings)}
