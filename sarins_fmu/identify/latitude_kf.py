r"""Kalman filter estimating the axial gyro drift from the latitude-error series.

Static-base error model of seed 000's Table 1 (long-period and Schuler
terms), with this project's sign (a positive azimuth drift gives a positive
latitude error):

.. math::

    \delta L(t) = \frac{\cos L}{\Omega}(1 - \cos\Omega t)\,\varepsilon
                  - \cos L \sin(\Omega t)\,\varphi_U
                  + a \cos(\omega_s t) + b \sin(\omega_s t) + v,

Ω the Earth rate, ω_s the Schuler frequency.  The state
``x = [ε (rad/s), φ_U (rad), a (rad), b (rad)]`` is constant except for a
random walk of ε (process noise ``drift_rw``, rad/s/sqrt(s)); the
measurement is the latitude error (rad) with white noise ``meas_std``.  The
Schuler amplitudes absorb initial velocity/tilt errors and the
accelerometer term of Table 1.  Used as comparison (c) of the seed 000
campaign: ε at 12 h of navigation from the whole 12 h series, against the
RBF network's use of the single 12 h value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..earth import A, RATE
from ..units import DPH_TO_RPS

G_SCHULER = 9.79  # gravity used for the Schuler frequency, m/s^2
SCHULER = math.sqrt(G_SCHULER / A)  # Schuler angular frequency, rad/s


def measurement_row(t: float, lat: float) -> np.ndarray:
    """H(t) of the model above for the latitude error, t in s, lat in rad."""
    c = math.cos(lat)
    return np.array([c * (1.0 - math.cos(RATE * t)) / RATE, -c * math.sin(RATE * t),
                     math.cos(SCHULER * t), math.sin(SCHULER * t)])


def predict(x: np.ndarray, P: np.ndarray, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Constant-state prediction: x = x, P = P + Q."""
    return x, P + Q


def update(x: np.ndarray, P: np.ndarray, z: float, H: np.ndarray, R: float) -> tuple[np.ndarray, np.ndarray]:
    """Scalar measurement update (Joseph form)."""
    # S = H P H' + R ; K = P H' / S
    PH = P @ H
    S = float(H @ PH) + R
    K = PH / S
    x = x + K * (z - float(H @ x))
    # P = (I - K H) P (I - K H)' + K R K'
    IKH = np.eye(len(x)) - np.outer(K, H)
    P = IKH @ P @ IKH.T + R * np.outer(K, K)
    return x, P


@dataclass(frozen=True)
class LatitudeKFSettings:
    """Prior standard deviations and noise levels (SI).

    drift0_std : rad/s; heading0_std : rad; schuler0_std : rad;
    drift_rw : rad/s/sqrt(s); meas_std : rad.
    """

    drift0_std: float = 0.01 * DPH_TO_RPS  # 0.01 deg/h
    heading0_std: float = 1e-3
    schuler0_std: float = 1e-5
    drift_rw: float = 1e-11
    meas_std: float = 1e-6

    def __post_init__(self):
        for name, value in self.__dict__.items():
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be positive and finite, got {value}")


def estimate_drift(time: np.ndarray, lat_error: np.ndarray, lat: float,
                   settings: LatitudeKFSettings = LatitudeKFSettings()) -> dict:
    """Run the filter over a latitude-error series.

    Parameters
    ----------
    time : (K,) s since navigation start, increasing, > 0
    lat_error : (K,) rad
    lat : site latitude, rad

    Returns
    -------
    dict with ``drift`` (rad/s, final estimate), ``drift_std`` (rad/s) and
    the histories ``drift_history``, ``drift_std_history`` (K,).
    """
    t = np.asarray(time, float)
    z = np.asarray(lat_error, float)
    if t.ndim != 1 or t.shape != z.shape or t.size < 4:
        raise ValueError("time and lat_error must be 1-D of the same length >= 4")
    if not (np.isfinite(t).all() and np.isfinite(z).all()) or np.any(np.diff(t) <= 0):
        raise ValueError("time must be finite and increasing, lat_error finite")
    s = settings
    x = np.zeros(4)
    P = np.diag([s.drift0_std, s.heading0_std, s.schuler0_std, s.schuler0_std]) ** 2
    R = s.meas_std**2
    hist = np.empty(t.size)
    hist_std = np.empty(t.size)
    prev = 0.0
    for k in range(t.size):  # one update per stored sample (minutes apart), not per IMU sample
        Q = np.zeros((4, 4))
        Q[0, 0] = s.drift_rw**2 * (t[k] - prev)
        x, P = predict(x, P, Q)
        x, P = update(x, P, z[k], measurement_row(t[k], lat), R)
        hist[k], hist_std[k] = x[0], math.sqrt(P[0, 0])
        prev = t[k]
    return {"drift": float(x[0]), "drift_std": float(math.sqrt(P[0, 0])), "drift_history": hist,
            "drift_std_history": hist_std}
