"""Closed-form short-term error growth of a free-inertial INS (a GNSS outage), from the error state at its start.

Frames and units: navigation ENU, body right-front-up, SI (m, m/s, rad, rad/s, m/s^2, s).  Errors are
computed - true as in :mod:`sarins_fmu.aided` (position dp, velocity dv, attitude phi with
mat_nb,computed = (I - [phi x]) mat_nb,true); the residual biases are the filter's bias error states
(``eskf.h``): db = b_true - b_estimated (body), which the compensated increments carry.

For t much shorter than the Schuler period (84 min), with the navigation frame taken as non-rotating
(Earth rate, transport rate and Coriolis neglected), a constant attitude mat_nb and a constant specific
force f^n (a straight cruise: f^n = (0, 0, g)), the error equations phi' = -mat_nb db_g and
dv' = f^n x phi + mat_nb db_a integrate to (Titterton & Weston, Strapdown Inertial Navigation Technology,
2nd ed., 2004, chapter 12, its short-term approximations; Groves, Principles of GNSS, Inertial, and Multisensor
Integrated Navigation Systems, 2nd ed., 2013, §14.2, short-term straight-line error propagation):

    dp(t) - dp(0) = dv0 t + (mat_nb db_a + f^n x phi0) t^2 / 2 - (f^n x mat_nb db_g) t^3 / 6,

per horizontal axis with f^n = (0, 0, g):  dE = dv0_E t + (a_E - g phi0_N) t^2/2 + g w_N t^3/6,
dN = dv0_N t + (a_N + g phi0_E) t^2/2 - g w_E t^3/6  (a = mat_nb db_a, w = mat_nb db_g).  The neglected
terms are relatively of order (omega_s t)^2 / 12 (Schuler, omega_s = sqrt(g / R) = 1.24e-3 rad/s),
2 Omega t / 3 (Coriolis and Earth-rate coupling of the tilt, Omega = 7.29e-5 rad/s) and, with a heading
error, phi_U times the horizontal specific force (zero on a straight cruise at constant speed).  With
``omega_n`` (below) the Earth-rate coupling of the attitude error is kept to first order.

With the Earth's rate Omega^n (ENU) kept to first order in the attitude error, phi' = -Omega^n x phi - w with
w = mat_nb db_g, so phi(t) = phi0 - (w + Omega^n x phi0) t + Omega^n x w t^2 / 2, and the attitude terms become

    dp(t) - dp(0) = ... + f^n x phi0 t^2 / 2 - f^n x (w + Omega^n x phi0) t^3 / 6 + f^n x (Omega^n x w) t^4 / 24

and the Coriolis term of the velocity error, dv' = ... - 2 Omega^n x dv, adds to first order
-2 Omega^n x (dv0 t^2 / 2 + (mat_nb db_a + f^n x phi0) t^3 / 6 - f^n x w t^4 / 24)
(``omega_n``; it carries the vertical channel's velocity error, a_U t, into East at 2 Omega cos L).
The heading error and the heading drift of a vertical gyro bias tilt the platform at Omega cos L phi_U,
which over 120 s of a 10 deg/h bias is about 10 % of the growth.  Left out then: Schuler,
(omega_s t)^2 / 12 relative (2e-3 at 120 s), the transport rate (v / R, 2e-6 rad/s at 12 m/s) and terms of
second order in Omega t (1e-4 at 120 s), and second-order products of the error states except the heading
error times the residual accelerometer bias, which :func:`growth` keeps (without it the closed form misses
an INS's growth by 5 % over 120 s when the filter has traded a horizontal accelerometer bias of 1000 ug
against tilt; tests/test_free_inertial.py: with it, 0.7 %, 1.0 %, 1.1 % over 30, 60, 120 s).
The covariance form is the linear map only.

In covariance form (:func:`growth_variance`) the same linear map acts on the covariance of
x = (dv, phi, db_g, db_a) (12,) at the outage start (the filter's P[3:15, 3:15] in ``eskf.h``'s order), plus,
optionally, the white sensor noises during the outage (per axis, frame-free for isotropic noise):
velocity random walk vrw^2 t^3 / 3, angle random walk g^2 arw^2 t^5 / 20, accelerometer bias random
walk accel_rw^2 t^5 / 20, gyro bias random walk g^2 gyro_rw^2 t^7 / 252 (the 1st to 4th integrals of
white noise; Groves 2013 §14.2).
"""

from __future__ import annotations

import numpy as np


def _cross(v) -> np.ndarray:
    """[v x] (3, 3)."""
    x, y, z = v
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def growth_matrix(t: float, mat_nb, f_n, omega_n=None) -> np.ndarray:
    """(3, 12) the map from x = (dv0, phi0, db_g, db_a) (ENU m/s, ENU rad, body rad/s, body m/s^2) to the
    position error growth dp(t) - dp(0) (ENU m) after ``t`` s of free inertial navigation (module docstring).
    mat_nb (3, 3) the body-to-ENU attitude; f_n (3,) the specific force in ENU, m/s^2; omega_n (3,) the
    navigation frame's rate (ENU rad/s, the Earth's ``earth.earth_rate_n(lat)``) for its first-order
    coupling of the attitude error (the t^3 and t^4 terms of the module docstring), or None."""
    c, f = np.asarray(mat_nb, float), _cross(np.asarray(f_n, float))
    om = _cross(np.zeros(3) if omega_n is None else np.asarray(omega_n, float))
    cor = 2.0 * om  # Coriolis on the velocity error, first order: dv' += -2 Omega x dv
    return np.hstack([np.eye(3) * t - cor * t**2 / 2.0, f * t**2 / 2.0 - (f @ om + cor @ f) * t**3 / 6.0,
                      -f @ c * t**3 / 6.0 + (f @ om + cor @ f) @ c * t**4 / 24.0, c * t**2 / 2.0 - cor @ c * t**3 / 6.0])


def growth(t, dv0, phi0, db_g, db_a, mat_nb, f_n, omega_n=None) -> np.ndarray:
    """(len(t), 3) ENU position error growth dp(t) - dp(0) (m) at the times ``t`` (s) since the outage start,
    from the velocity error dv0 (ENU m/s), attitude error phi0 (ENU rad), residual gyro bias db_g (body rad/s)
    and residual accelerometer bias db_a (body m/s^2) at the start (module docstring); omega_n as in
    :func:`growth_matrix`.  Beyond the linear map it keeps the second-order term of the heading error rotating
    the residual accelerometer bias,
    -(phi_U(t) up) x (mat_nb db_a) with phi_U(t) = phi_U0 - (mat_nb db_g)_U t (integrated twice)."""
    x = np.concatenate([dv0, phi0, db_g, db_a]).astype(float)
    t = np.atleast_1d(np.asarray(t, float))
    lin = np.array([growth_matrix(float(s), mat_nb, f_n, omega_n) @ x for s in t])
    # second order: the heading error phi_U(t) = phi_U0 - w_U t rotates the residual accelerometer bias,
    # dv' += -phi x a with a = mat_nb db_a (large when a horizontal bias is traded against tilt by the filter)
    a, w_up = np.asarray(mat_nb, float) @ np.asarray(db_a, float), (np.asarray(mat_nb, float) @ db_g)[2]
    up = np.array([0.0, 0.0, 1.0])
    return lin - np.outer(t**2 / 2.0, np.cross(phi0[2] * up, a)) + np.outer(t**3 / 6.0, np.cross(w_up * up, a))


def growth_variance(t: float, cov, mat_nb, f_n, noise=None, omega_n=None) -> np.ndarray:
    """(3, 3) covariance of the ENU position error growth after ``t`` s: A cov A' with A = :func:`growth_matrix`
    and cov (12, 12) that of (dv, phi, db_g, db_a) at the outage start, plus, when ``noise`` (an
    :class:`sarins_fmu.aided.ImuNoise`) is given, its white noises and bias random walks during the outage
    (module docstring; the tilt-driven terms on the horizontal axes only)."""
    a = growth_matrix(t, mat_nb, f_n, omega_n)
    out = a @ np.asarray(cov, float) @ a.T
    if noise is not None:
        g2 = float(np.dot(f_n, f_n))
        horizontal = np.diag([1.0, 1.0, 0.0])
        out = out + np.eye(3) * (noise.vrw**2 * t**3 / 3.0 + noise.accel_rw**2 * t**5 / 20.0)
        out = out + horizontal * g2 * (noise.arw**2 * t**5 / 20.0 + noise.gyro_rw**2 * t**7 / 252.0)
    return out


def horizontal_growth_sigma(t: float, cov, mat_nb, f_n, noise=None, omega_n=None) -> float:
    """sqrt of the E and N variances of :func:`growth_variance`, m: the predicted RMS horizontal growth."""
    v = growth_variance(t, cov, mat_nb, f_n, noise, omega_n)
    return float(np.sqrt(v[0, 0] + v[1, 1]))
