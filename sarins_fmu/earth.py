"""WGS-84 Earth model: radii of curvature, normal gravity, Earth rate.

All angles in rad, lengths in m, rates in rad/s.  Navigation frame ENU.

The constants, :func:`radii` and :func:`gravity` are the C physics core's
(``sarins_fmu/core/earth.c``), the one implementation the INS kernels use
too; the functions here are thin bindings, vectorised over numpy arrays.

References: NIMA TR8350.2 (WGS-84), Titterton & Weston (2004) ch. 3,
Savage, *Strapdown Analytics* (2000) ch. 5.
"""

import ctypes
import math

import numpy as np

from .core._lib import function

_VP = ctypes.c_void_p


def _constants():
    out = np.empty(10)
    function("sarins_earth_constants", None, _VP)(out.ctypes.data)
    return tuple(float(x) for x in out)


# A semi-major axis (m), F flattening, E2 first eccentricity squared, B semi-minor axis (m),
# RATE Earth rotation rate (rad/s), GM gravitational constant x Earth mass (m^3/s^2),
# GAMMA_E / GAMMA_P normal gravity at the equator / poles (m/s^2),
# _K_SOMIGLIANA = B GAMMA_P / (A GAMMA_E) - 1, _M = RATE^2 A^2 B / GM (geodetic parameter m)
A, F, E2, B, RATE, GM, GAMMA_E, GAMMA_P, _K_SOMIGLIANA, _M = _constants()

_radii_1 = function("sarins_earth_radii", None, ctypes.c_double, ctypes.POINTER(ctypes.c_double),
                    ctypes.POINTER(ctypes.c_double))
_gravity_1 = function("sarins_earth_gravity", ctypes.c_double, ctypes.c_double, ctypes.c_double)
_radii_n = function("sarins_earth_radii_n", None, ctypes.c_int64, _VP, _VP, _VP)
_gravity_n = function("sarins_earth_gravity_n", None, ctypes.c_int64, _VP, _VP, _VP)


def _scalar(x) -> bool:
    return isinstance(x, (float, int)) or np.ndim(x) == 0


def radii(lat):
    """Meridian and prime-vertical radii of curvature.

    Parameters
    ----------
    lat : float or array_like
        Geodetic latitude, rad.

    Returns
    -------
    r_meridian, r_prime_vertical : float, or arrays of lat's shape
        R_M = a(1-e^2)/(1-e^2 sin^2 L)^(3/2) and R_N = a/sqrt(1-e^2 sin^2 L), m.
    """
    if _scalar(lat):
        r_m, r_n = ctypes.c_double(), ctypes.c_double()
        _radii_1(float(lat), ctypes.byref(r_m), ctypes.byref(r_n))
        return r_m.value, r_n.value
    lat_a = np.asarray(lat, dtype=np.float64, order="C")
    r_m, r_n = np.empty_like(lat_a), np.empty_like(lat_a)
    _radii_n(lat_a.size, lat_a.ctypes.data, r_m.ctypes.data, r_n.ctypes.data)
    return r_m, r_n


def gravity(lat, height):
    """Normal gravity magnitude (gravitation + centrifugal), m/s^2.

    Somigliana's closed formula on the ellipsoid with the second-order
    free-air correction of WGS-84 (TR8350.2 eq. 4-3):
    g(L,h) = g0(L) [1 - 2/a (1 + f + m - 2 f sin^2 L) h + 3 h^2 / a^2].
    ``lat`` (rad) and ``height`` (m) broadcast; a float for scalars.
    """
    if _scalar(lat) and _scalar(height):
        return _gravity_1(float(lat), float(height))
    lat_b, height_b = np.broadcast_arrays(np.asarray(lat, dtype=np.float64), np.asarray(height, dtype=np.float64))
    lat_a, height_a = np.asarray(lat_b, order="C"), np.asarray(height_b, order="C")
    out = np.empty(lat_a.shape)
    _gravity_n(lat_a.size, lat_a.ctypes.data, height_a.ctypes.data, out.ctypes.data)
    return out


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
