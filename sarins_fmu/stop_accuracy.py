r"""How well a zero-velocity stop can resolve the azimuth gyro drift: a covariance computation.

Independent of the stop Kalman filter (:mod:`sarins_fmu.kalman`): the
1-sigma accuracy of *any* unbiased estimate of a constant azimuth drift
eps_U from the INS velocity error during a stop, computed from the linear
Gaussian error model (the Cramer-Rao bound, which for a linear Gaussian
model is the posterior covariance a Kalman filter with the same model
reaches; Groves 2013, sec. 3.2).

Error model on a static base, local-level ENU frame, psi-angle form
(Titterton & Weston 2004, sec. 12.3), the rotating IMU's constant horizontal
gyro and accelerometer biases modulated away (seed 002's RINS rotates about
azimuth), so what is left is

.. math::

    \dot{\delta v}_E = -g\,\phi_N + 2\Omega\sin L\,\delta v_N + w_{a,E}, \qquad
    \dot{\delta v}_N = g\,\phi_E - 2\Omega\sin L\,\delta v_E + w_{a,N},

    \dot\phi_E = \Omega\sin L\,\phi_N - \Omega\cos L\,\phi_U - \delta v_N/R + w_{g,E},

    \dot\phi_N = -\Omega\sin L\,\phi_E + \delta v_E/R + w_{g,N}, \qquad
    \dot\phi_U = \Omega\cos L\,\phi_E + \tan L\,\delta v_E/R - \varepsilon_U + w_{g,U},

with white gyro noise w_g (angle random walk N, rad/sqrt(s)) and white
accelerometer noise w_a (velocity random walk, m/s/sqrt(s)); the velocity
error is observed (the vehicle stands still) with white noise of std
``velocity_meas_std``.  The initial velocity, tilt and heading errors are
nuisance parameters with diffuse priors.

The azimuth drift reaches the velocity only through the Earth rate:
phi_U = -eps t, phi_E = Omega cos L eps t^2/2, dv_N = g Omega cos L eps t^3/6,
while the horizontal gyros' random walk makes the tilt wander, and its
velocity error grows as g N t^{3/2} / sqrt(3): over 30 minutes that hides the
drift's t^3 signature far more than the heading random walk (which alone
would allow N / sqrt(T), the bound for a drift read from a directly
observed heading angle, :func:`heading_walk_drift_std`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

from .earth import RATE

R_EARTH = 6.371e6  # mean Earth radius for the Schuler coupling, m
G = 9.80  # gravity magnitude in the error model, m/s^2 (its exact value does not matter at this accuracy)
STATES = ("dv_e", "dv_n", "phi_e", "phi_n", "phi_u", "eps_u")


def discretise(F: np.ndarray, Qc: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Transition matrix and process-noise covariance of dx = F x dt + dw (E dw dw' = Qc dt)
    over ``dt`` (Van Loan's method)."""
    n = F.shape[0]
    block = np.zeros((2 * n, 2 * n))
    block[:n, :n] = -F
    block[:n, n:] = Qc
    block[n:, n:] = F.T
    e = expm(block * dt)
    phi = e[n:, n:].T
    return phi, phi @ e[:n, n:]


def posterior_std(F, Qc, H, r, p0, dt: float, n_steps: int, index: int) -> np.ndarray:
    """1-sigma of state ``index`` after each of ``n_steps`` measurements y_k = H x(k dt) + v
    (v ~ N(0, diag r)), from prior covariance ``p0`` at t = 0 (Kalman covariance recursion,
    Joseph form).  Returns (n_steps,)."""
    phi, q = discretise(np.asarray(F, float), np.asarray(Qc, float), dt)
    H = np.atleast_2d(np.asarray(H, float))
    R = np.diag(np.atleast_1d(np.asarray(r, float)))
    P = np.array(p0, float)
    out = np.empty(n_steps)
    eye = np.eye(P.shape[0])
    for k in range(n_steps):
        P = phi @ P @ phi.T + q  # P = Phi P Phi' + Q
        S = H @ P @ H.T + R
        K = np.linalg.solve(S, H @ P).T  # K = P H' S^-1
        A = eye - K @ H
        P = A @ P @ A.T + K @ R @ K.T  # Joseph form keeps P symmetric and positive
        out[k] = math.sqrt(P[index, index])
    return out


@dataclass(frozen=True)
class StopAccuracy:
    """Azimuth-drift accuracy reachable at a stop.

    time : (K,) s; drift_std : (K,) 1-sigma of eps_U after ``time``, rad/s;
    final_std : drift_std at the end of the stop, rad/s;
    heading_walk_std : N_U / sqrt(T), the bound if the heading angle were
    observed directly, rad/s.
    """

    time: np.ndarray
    drift_std: np.ndarray
    final_std: float
    heading_walk_std: float


def stop_model(lat: float, arw_horizontal: float, arw_azimuth: float, vrw: float):
    """Continuous-time (F, Qc) of :data:`STATES` at latitude ``lat`` (rad); random walks in
    rad/sqrt(s) (gyros) and m/s/sqrt(s) (accelerometers)."""
    s, c, t = math.sin(lat), math.cos(lat), math.tan(lat)
    w = RATE
    F = np.zeros((6, 6))
    F[0, 1], F[0, 3] = 2 * w * s, -G
    F[1, 0], F[1, 2] = -2 * w * s, G
    F[2, 1], F[2, 3], F[2, 4] = -1.0 / R_EARTH, w * s, -w * c
    F[3, 0], F[3, 2] = 1.0 / R_EARTH, -w * s
    F[4, 0], F[4, 2], F[4, 5] = t / R_EARTH, w * c, -1.0
    Qc = np.diag([vrw**2, vrw**2, arw_horizontal**2, arw_horizontal**2, arw_azimuth**2, 0.0])
    return F, Qc


def stop_drift_accuracy(*, lat: float, arw_horizontal: float, arw_azimuth: float | None = None,
                        vrw: float = 0.0, duration: float = 1800.0, dt: float = 1.0,
                        velocity_meas_std: float = 1e-3, diffuse: float = 1e3) -> StopAccuracy:
    """1-sigma accuracy of the azimuth drift from ``duration`` s of zero-velocity data.

    Parameters
    ----------
    lat : latitude, rad.
    arw_horizontal, arw_azimuth : angle random walk of the horizontal and the
        azimuth gyros, rad/sqrt(s) (``arw_azimuth`` defaults to the horizontal one).
    vrw : accelerometer velocity random walk, m/s/sqrt(s).
    duration, dt : stop length and measurement interval, s.
    velocity_meas_std : white noise on the observed velocity, m/s.
    diffuse : prior std of the nuisance and drift states in units of
        (1 m/s, 1 mrad, 10 mrad, 1 deg/h): large, so that the result is the data's.
    """
    for name, value in (("lat", lat), ("duration", duration), ("dt", dt)):
        if not math.isfinite(value):
            raise ValueError(f"{name} must be finite")
    if not (duration >= 2 * dt > 0 and velocity_meas_std > 0 and diffuse > 0):
        raise ValueError("need duration >= 2 dt > 0, a positive velocity noise and a positive prior")
    arw_azimuth = arw_horizontal if arw_azimuth is None else arw_azimuth
    if min(arw_horizontal, arw_azimuth, vrw) < 0:
        raise ValueError("random walks must be non-negative")
    F, Qc = stop_model(lat, arw_horizontal, arw_azimuth, vrw)
    p0 = np.diag(np.array([1.0, 1.0, 1e-3, 1e-3, 1e-2, math.radians(1.0) / 3600.0]) ** 2) * diffuse**2
    n = int(round(duration / dt))
    H = np.zeros((2, 6))
    H[0, 0] = H[1, 1] = 1.0
    std = posterior_std(F, Qc, H, [velocity_meas_std**2] * 2, p0, dt, n, STATES.index("eps_u"))
    time = np.arange(1, n + 1) * dt
    return StopAccuracy(time, std, float(std[-1]), heading_walk_drift_std(arw_azimuth, duration))


def heading_walk_drift_std(arw: float, duration: float) -> float:
    """N / sqrt(T): 1-sigma of a constant drift (rad/s) read from a heading angle observed
    without error for ``duration`` s while the gyro's angle random walk is ``arw`` (rad/sqrt(s))."""
    return arw / math.sqrt(duration)
