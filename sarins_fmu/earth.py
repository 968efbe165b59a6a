"""WGS-84 Earth model: radii of curvature, normal gravity, Earth rate.

All angles in rad, lengths in m, rates in rad/s.  Navigation frame ENU.

References: NIMA TR8350.2 (WGS-84), Titterton & Weston (2004) ch. 3,
Savage, *Strapdown Analytics* (2000) ch. 5.
"""

import math

import numpy as np

from ._jit import jit

A = 6378137.0  # semi-major axis, m
F = 1.0 / 298.257223563  # flattening
E2 = F * (2.0 - F)  # first eccentricity squared
B = A * (1.0 - F)  # semi-minor axis, m
RATE = 7.2921151467e-5  # Earth rotation rate, rad/s
GM = 3.986004418e14  # gravitational constant x Earth mass, m^3/s^2
GAMMA_E = 9.7803253359  # normal gravity at the equator, m/s^2
GAMMA_P = 9.8321849378  # normal gravity at the poles, m/s^2
_K_SOMIGLIANA = B * GAMMA_P / (A * GAMMA_E) - 1.0
_M = RATE**2 * A**2 * B / GM  # geodetic parameter m of the normal field


@jit
def radii(lat):
    """Meridian and prime-vertical radii of curvature.

    Parameters
    ----------
    lat : float
        Geodetic latitude, rad.

    Returns
    -------
    r_meridian, r_prime_vertical : float
        R_M = a(1-e^2)/(1-e^2 sin^2 L)^(3/2) and R_N = a/sqrt(1-e^2 sin^2 L), m.
    """
    s2 = math.sin(lat) ** 2
    w = math.sqrt(1.0 - E2 * s2)
    return A * (1.0 - E2) / w**3, A / w


@jit
def gravity(lat, height):
    """Normal gravity magnitude (gravitation + centrifugal), m/s^2.

    Somigliana's closed formula on the ellipsoid with the second-order
    free-air correction of WGS-84 (TR8350.2 eq. 4-3):
    g(L,h) = g0(L) [1 - 2/a (1 + f + m - 2 f sin^2 L) h + 3 h^2 / a^2].
    """
    s2 = math.sin(lat) ** 2
    g0 = GAMMA_E * (1.0 + _K_SOMIGLIANA * s2) / math.sqrt(1.0 - E2 * s2)
    return g0 * (1.0 - 2.0 / A * (1.0 + F + _M - 2.0 * F * s2) * height + 3.0 * height**2 / A**2)


def earth_rate_n(lat):
    """Earth rate in the ENU navigation frame, (3,) rad/s: (0, W cos L, W sin L)."""
    return np.array([0.0, RATE * math.cos(lat), RATE * math.sin(lat)])


def gravity_n(lat, height):
    """Gravity vector in ENU, (3,) m/s^2: (0, 0, -g)."""
    return np.array([0.0, 0.0, -gravity(lat, height)])


def transport_rate_n(lat, height, velocity_n):
    """Transport rate omega_en^n, (3,) rad/s, from ENU velocity (m/s)."""
    r_m, r_n = radii(lat)
    ve, vn = velocity_n[0], velocity_n[1]
    return np.array([-vn / (r_m + height), ve / (r_n + height), ve * math.tan(lat) / (r_n + height)])


def schuler_period(lat=0.0, height=0.0):
    """Schuler period 2 pi sqrt(R/g), s, with R the geometric mean radius at lat."""
    r_m, r_n = radii(lat)
    r = math.sqrt(r_m * r_n) + height
    return 2.0 * math.pi * math.sqrt(r / gravity(lat, height))
