r"""Closed-form static-base navigation errors of an azimuth gyro drift and a heading error.

Long-period (Earth-rate) solution of the psi-angle error equations on a
static base, the Schuler oscillation averaged out (Titterton & Weston,
*Strapdown Inertial Navigation Technology*, 2nd ed., sec. 12.3; Savage,
*Strapdown Analytics*, ch. 12).  In the local-level ENU frame the error
angle psi of the computed frame obeys psi' = -Omega x psi - eps with
Omega = W (0, cos L, sin L); the Schuler loop keeps the platform level in
the computed frame, which ties the position errors to psi:
dL = psi_E and cos L dlon = -psi_N.  Solving for a constant vertical drift
eps_U (psi(0) = 0) and for an initial heading error phi_U (psi(0) = phi_U
up, no drift) gives

.. math::

    \delta L = \frac{\cos L}{W}(1 - \cos Wt)\,\varepsilon_U
               - \cos L \sin(Wt)\,\varphi_U, \qquad
    \delta\lambda = \sin L \Big(t - \frac{\sin Wt}{W}\Big)\varepsilon_U
               - \sin L\,(1 - \cos Wt)\,\varphi_U.

The latitude terms are seed 000's Table 1 (with this project's sign: a
positive azimuth drift gives a positive latitude error); the longitude
terms answer the paper's Fig. 1 remark.  At t = 12 h (W t = 3.15 rad) the
heading error drops out of the latitude error (sin Wt = -0.009) but enters
the longitude error with its largest weight (1 - cos Wt = 2.0).

Signs: ``eps_u`` is the z-gyro drift (rad/s, the z axis up); ``phi_u`` the
U component of the attitude error with computed = (I - [phi x]) true
(:func:`sarins_fmu.rotations.small_angle_error`, the convention of
``run_static``'s ``align_attitude_error``).
"""

from __future__ import annotations

import math

import numpy as np

from .earth import RATE


def azimuth_drift_errors(t, eps_u: float, lat: float) -> tuple[np.ndarray, np.ndarray]:
    """Latitude and longitude errors (rad) at times ``t`` (s) of a constant
    azimuth drift ``eps_u`` (rad/s) at latitude ``lat`` (rad)."""
    t = np.asarray(t, float)
    d_lat = math.cos(lat) / RATE * (1.0 - np.cos(RATE * t)) * eps_u
    d_lon = math.sin(lat) * (t - np.sin(RATE * t) / RATE) * eps_u
    return d_lat, d_lon


def drift_history_errors(t: float, tau, eps_u, lat: float) -> tuple[float, float]:
    """Latitude and longitude errors (rad) at ``t`` (s) of a time-varying
    azimuth drift ``eps_u`` (rad/s) sampled at ``tau`` (s, uniform grid from
    0 to ``t``): the responses of :func:`azimuth_drift_errors` to a drift
    impulse, cos L sin W(t - tau) and sin L (1 - cos W(t - tau)), integrated
    by the trapezoid rule."""
    tau = np.asarray(tau, float)
    eps_u = np.asarray(eps_u, float)
    if tau.ndim != 1 or tau.shape != eps_u.shape or tau.size < 2 or abs(tau[-1] - t) > 1e-6 * max(t, 1.0):
        raise ValueError("the drift history must be sampled from 0 to t on one grid")
    u = RATE * (t - tau)
    return (math.cos(lat) * float(np.trapezoid(eps_u * np.sin(u), tau)),
            math.sin(lat) * float(np.trapezoid(eps_u * (1.0 - np.cos(u)), tau)))


def heading_error_errors(t, phi_u: float, lat: float) -> tuple[np.ndarray, np.ndarray]:
    """Latitude and longitude errors (rad) at times ``t`` (s) of an initial
    heading error ``phi_u`` (rad) at latitude ``lat`` (rad)."""
    t = np.asarray(t, float)
    d_lat = -math.cos(lat) * np.sin(RATE * t) * phi_u
    d_lon = -math.sin(lat) * (1.0 - np.cos(RATE * t)) * phi_u
    return d_lat, d_lon


def lat_error_noise_std(random_walk: float, t: float, bias_instability: float = 0.0,
                        corr_time: float = 0.0) -> float:
    r"""1-sigma latitude error (rad) at ``t`` (s) from white gyro noise.

    Equal random walk ``random_walk`` (rad/sqrt(s)) on the three gyros: the
    noise is isotropic in the navigation frame however the IMU turns, so
    psi performs a random walk with psi_E variance N^2 t (the Earth-rate
    rotation of the error equations keeps the isotropy).  The undamped
    Schuler loop passes psi_E to dL through 1 - cos(w_s u), whose mean square
    is 3/2: var(dL) = 3/2 N^2 t for t much longer than the Schuler period.
    A first-order Gauss-Markov bias instability (std ``bias_instability``
    rad/s, correlation ``corr_time`` s, much shorter than t) adds its
    low-frequency density 2 sigma^2 tau to N^2.
    """
    density = random_walk ** 2 + 2.0 * bias_instability ** 2 * corr_time
    return math.sqrt(1.5 * density * t)


def identification_noise_std(random_walk: float, lat: float, t: float, bias_instability: float = 0.0,
                             corr_time: float = 0.0) -> float:
    """1-sigma error (rad/s) of an azimuth drift read from the latitude error
    at ``t`` (s) by inverting :func:`azimuth_drift_errors`: the noise floor of
    any identifier fed with that single value (seed 000's RBF network)."""
    gain = math.cos(lat) / RATE * (1.0 - math.cos(RATE * t))
    return lat_error_noise_std(random_walk, t, bias_instability, corr_time) / gain
