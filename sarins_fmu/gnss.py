"""GNSS receiver model: position and velocity fixes at 1-20 Hz with white and first-order
Gauss-Markov errors per ENU axis, latency, antenna lever arm and outage windows (the C kernel
``sarins_fmu/core/gnss.h``; its header states the error model).

Preset numbers and their sources (CEP is converted to a per-axis standard deviation with
CEP = 1.1774 sigma for a circular normal error):

* ``sps``: u-blox NEO-M8 series data sheet, "Horizontal position accuracy" GPS+GLONASS 2.5 m CEP,
  "Velocity accuracy" 0.05 m/s (50 %) -> sigma_h = 2.12 m per axis, sigma_v = 0.074 m/s
  (0.05 m/s / 0.6745, 50 % of a normal at 0.6745 sigma).
* ``sbas``: the same data sheet, SBAS 2.0 m CEP -> sigma_h = 1.70 m per axis.
* ``rtk``: u-blox ZED-F9P data sheet, RTK "0.01 m + 1 ppm CEP" -> sigma_h = 0.0085 m per axis
  (short baseline), velocity 0.05 m/s (50 %).

Hypothetical (no data sheet states them; our choice): the split of each sigma into a white part
and a Gauss-Markov part (half the variance each), the correlation times (position 60 s, RTK 10 s;
velocity 10 s) and the vertical sigma (twice the horizontal).  The default lever arm is zero and
the latency 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .core import aided as _core

CEP_TO_SIGMA = 1.0 / 1.1774  # circular normal: CEP = 1.1774 sigma (per axis)
MEDIAN_TO_SIGMA = 1.0 / 0.6745  # 50 % of |N(0, sigma^2)| below 0.6745 sigma


@dataclass(frozen=True)
class GNSSConfig:
    """Receiver settings (SI).  Standard deviations per ENU axis."""

    pos_white_std: tuple = (1.5, 1.5, 3.0)  # m
    pos_gm_std: tuple = (1.5, 1.5, 3.0)  # m
    pos_gm_tau: float = 60.0  # s
    vel_white_std: tuple = (0.05, 0.05, 0.1)  # m/s
    vel_gm_std: tuple = (0.05, 0.05, 0.1)  # m/s
    vel_gm_tau: float = 10.0  # s
    lever_arm: tuple = (0.0, 0.0, 0.0)  # m, body right-front-up
    latency: float = 0.0  # s, fix valid at t reaches the user at t + latency
    rate_hz: float = 1.0  # fixes per second, 1 .. 20

    def __post_init__(self):
        for name in ("pos_white_std", "pos_gm_std", "vel_white_std", "vel_gm_std", "lever_arm"):
            value = getattr(self, name)
            if len(value) != 3 or not all(math.isfinite(x) for x in value):
                raise ValueError(f"GNSS {name} must be three finite numbers, got {value!r}")
            if name != "lever_arm" and min(value) < 0:
                raise ValueError(f"GNSS {name} must not be negative, got {value!r}")
        for name in ("pos_gm_tau", "vel_gm_tau"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise ValueError(f"GNSS {name} must be positive")
        if not (math.isfinite(self.latency) and 0 <= self.latency <= 1.0):
            raise ValueError(f"GNSS latency must be within 0 .. 1 s, got {self.latency}")
        if not (math.isfinite(self.rate_hz) and 1.0 <= self.rate_hz <= 20.0):
            raise ValueError(f"GNSS rate must be within 1 .. 20 Hz, got {self.rate_hz}")

    def array(self) -> np.ndarray:
        """The settings array of ``sarins_gnss_init``."""
        return np.array([*self.lever_arm, *self.pos_white_std, *self.pos_gm_std, self.pos_gm_tau,
                         *self.vel_white_std, *self.vel_gm_std, self.vel_gm_tau], float)

    def pos_std(self) -> np.ndarray:
        """Total position error std per ENU axis, m."""
        return np.hypot(self.pos_white_std, self.pos_gm_std)

    def vel_std(self) -> np.ndarray:
        """Total velocity error std per ENU axis, m/s."""
        return np.hypot(self.vel_white_std, self.vel_gm_std)


def _split(sigma_h: float, sigma_v_axis: float, tau: float, vel_sigma: float) -> GNSSConfig:
    """Half the variance white, half Gauss-Markov (hypothetical split); vertical twice horizontal."""
    h, v = sigma_h / math.sqrt(2), vel_sigma / math.sqrt(2)
    return GNSSConfig(pos_white_std=(h, h, 2 * h), pos_gm_std=(h, h, 2 * h), pos_gm_tau=tau,
                      vel_white_std=(v, v, 2 * v), vel_gm_std=(v, v, 2 * v), vel_gm_tau=10.0)


_VEL = 0.05 * MEDIAN_TO_SIGMA  # m/s, NEO-M8 / ZED-F9P velocity accuracy 0.05 m/s (50 %)
PRESETS = {
    "sps": _split(2.5 * CEP_TO_SIGMA, 0.0, 60.0, _VEL),
    "sbas": _split(2.0 * CEP_TO_SIGMA, 0.0, 60.0, _VEL),
    "rtk": _split(0.01 * CEP_TO_SIGMA, 0.0, 10.0, _VEL),
}
# Hypothetical (no data sheet): a receiver with white errors only, 1 m horizontal / 2 m vertical and 0.05 / 0.1 m/s
# (1 sigma), for which the 15-state filter's measurement model is exact: the consistency (NEES) and outage
# checks, the campaign's drive and the KF-GINS comparison use it.
WHITE = GNSSConfig(pos_white_std=(1.0, 1.0, 2.0), pos_gm_std=(0.0, 0.0, 0.0), vel_white_std=(0.05, 0.05, 0.1),
                   vel_gm_std=(0.0, 0.0, 0.0))


@dataclass(frozen=True)
class GNSSFixes:
    """Fixes of one run: time (n,) validity time, s; available (n,) time the fix reaches the user
    (time + latency), s; valid (n,) bool (False inside an outage); lat, lon (n,) rad; height (n,) m;
    velocity_n (n, 3) ENU m/s (of the antenna)."""

    time: np.ndarray
    available: np.ndarray
    valid: np.ndarray
    lat: np.ndarray
    lon: np.ndarray
    height: np.ndarray
    velocity_n: np.ndarray


def epochs_on_grid(rate_hz: float, imu_step: float, duration: float) -> np.ndarray:
    """Indices of the IMU grid points (t = k imu_step) that are fix epochs at ``rate_hz`` (first at
    t = 1 / rate); ValueError when the fix interval is shorter than or not a whole multiple of the
    IMU step."""
    every = round(1.0 / (rate_hz * imu_step))
    if 1.0 / rate_hz < imu_step * (1 - 1e-9):
        raise ValueError(f"GNSS rate {rate_hz:g} Hz is above the IMU rate {1 / imu_step:g} Hz")
    if abs(every * imu_step * rate_hz - 1.0) > 1e-9:
        raise ValueError(f"GNSS interval {1 / rate_hz:g} s is not a whole number of IMU steps ({imu_step:g} s)")
    n_grid = int(round(duration / imu_step))
    return np.arange(every, n_grid + 1, every)


def check_outages(outages, duration: float) -> np.ndarray:
    """(m, 2) outage windows [start, end) s, each inside 0 .. duration with start < end; ValueError
    naming the window otherwise."""
    arr = np.asarray(outages, float).reshape(-1, 2)
    for start, end in arr:
        if not (math.isfinite(start) and math.isfinite(end) and 0 <= start < end <= duration):
            raise ValueError(f"GNSS outage {start:g}:{end:g} s is not a window inside the run (0 .. {duration:g} s)")
    return arr


def simulate(truth, config: GNSSConfig, seed: int, outages=()) -> GNSSFixes:
    """Fixes along a :class:`sarins_fmu.trajectory.Truth` (epochs on its IMU grid)."""
    duration = truth.time[-1]
    idx = epochs_on_grid(config.rate_hz, truth.step, duration)
    out_arr = check_outages(outages, duration)
    state = _core.GnssState(config.array(), seed)
    rows = state.fixes(truth.time[idx], truth.nav_rows()[idx], truth.omega_ib_b[idx], out_arr)
    t = truth.time[idx]
    return GNSSFixes(time=t, available=t + config.latency, valid=rows[:, 0] > 0.5, lat=rows[:, 1], lon=rows[:, 2],
                     height=rows[:, 3], velocity_n=rows[:, 4:7])


def preset(name: str, **changes) -> GNSSConfig:
    """A named preset (``sps``, ``sbas``, ``rtk``) with optional changes."""
    if name not in PRESETS:
        raise ValueError(f"unknown GNSS preset {name!r}; choose one of {', '.join(PRESETS)}")
    return replace(PRESETS[name], **changes)
