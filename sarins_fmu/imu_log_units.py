"""Units named in column headers and the axes a sensor declares, for the readers of :mod:`sarins_fmu.imu_log`.

A column name says what it holds and in which unit, ``<quantity>_<axis>_<unit>``:

==================  =====================================  ==========================================
quantity            units                                  meaning
==================  =====================================  ==========================================
``gyro_{x,y,z}``    ``radps``, ``dps``, ``dph``            mean angular rate over the sample interval
``accel_{x,y,z}``   ``mps2``, ``g``, ``mg``                mean specific force (g = 9.80665 m/s^2)
``dtheta_{x,y,z}``  ``rad``, ``deg``                       angle increment over the interval
``dv_{x,y,z}``      ``mps``                                velocity increment over the interval
``temp_{gyro,accel}_{x,y,z}``  ``c``, ``k``                sensor temperatures (all six or none)
``temp``            ``c``, ``k``                           one temperature for all six sensors
``time``            ``s``                                  sample time (else the rate from an option)
==================  =====================================  ==========================================

Axes: the sensor's x, y and z point along the directions named by three letters, each one of
``r``/``l`` (right/left), ``f``/``b`` (front/back), ``u``/``d`` (up/down): ``frd`` is x forward,
y right, z down (the i2Nav and aviation body frame), ``flu`` x forward, y left, z up (ROS REP 103),
``rfu`` the project's right-front-up.  Only right-handed triads are real sensor frames; a left-handed
one (``rfd``) is refused.  Vectors are rotated to right-front-up by a signed permutation, which is
exact in floating point.
"""

from __future__ import annotations

import re

import numpy as np

from .units import DEG_TO_RAD, DPH_TO_RPS, G0

GYRO_UNITS = {"radps": 1.0, "dps": DEG_TO_RAD, "dph": DPH_TO_RPS}  # -> rad/s
ACCEL_UNITS = {"mps2": 1.0, "g": G0, "mg": 1e-3 * G0}  # -> m/s^2
DTHETA_UNITS = {"rad": 1.0, "deg": DEG_TO_RAD}  # -> rad
DV_UNITS = {"mps": 1.0}  # -> m/s
TEMP_UNITS = {"c": 0.0, "k": -273.15}  # offset -> degC
UNITS = {"gyro": GYRO_UNITS, "accel": ACCEL_UNITS, "dtheta": DTHETA_UNITS, "dv": DV_UNITS}
_VECTOR = re.compile(r"(gyro|accel|dtheta|dv)_([xyz])_([a-z0-9]+)")
_TEMP = re.compile(r"temp(?:_(gyro|accel)_([xyz]))?_([a-z]+)")
DIRECTIONS = {"r": (1, 0, 0), "l": (-1, 0, 0), "f": (0, 1, 0), "b": (0, -1, 0), "u": (0, 0, 1), "d": (0, 0, -1)}


class ColumnError(ValueError):
    """A header the unit grammar does not allow (the message names the column)."""


def vector_column(name: str):
    """(quantity, axis index, factor to SI) of a vector column name, or None if it is not one.

    Raises ColumnError for a known quantity in an unknown unit (naming the units it takes).
    """
    m = _VECTOR.fullmatch(name)
    if not m:
        return None
    quantity, axis, unit = m.groups()
    table = UNITS[quantity]
    if unit not in table:
        raise ColumnError(f"column {name!r}: {quantity} in unknown unit {unit!r} (one of {', '.join(table)})")
    return quantity, "xyz".index(axis), table[unit]


def temp_column(name: str):
    """(sensor index 0..5 or None for one temperature of all six, offset to degC), or None."""
    m = _TEMP.fullmatch(name)
    if not m:
        return None
    triad, axis, unit = m.groups()
    if unit not in TEMP_UNITS:
        raise ColumnError(f"column {name!r}: temperature in unknown unit {unit!r} (c or k)")
    index = None if triad is None else ("gyro", "accel").index(triad) * 3 + "xyz".index(axis)
    return index, TEMP_UNITS[unit]


def axes_matrix(code: str) -> np.ndarray:
    """The signed permutation D with v_rfu = D v_sensor for an axes code such as ``frd``.

    Raises ValueError naming the code when it is not three letters of three different directions or
    when the triad is left-handed.
    """
    text = str(code).strip().lower()
    if len(text) != 3 or any(c not in DIRECTIONS for c in text):
        raise ValueError(f"axes {code!r}: three letters, the directions of the sensor's x, y and z, each one of "
                         "r l f b u d (right/left, front/back, up/down), e.g. frd")
    d = np.array([DIRECTIONS[c] for c in text], float).T  # columns: where x, y, z point in right-front-up
    if sorted(np.flatnonzero(np.abs(d).sum(axis=1))) != [0, 1, 2] or round(abs(np.linalg.det(d))) != 1:
        raise ValueError(f"axes {code!r}: x, y and z must point along three different directions (one of r/l, "
                         "one of f/b, one of u/d)")
    if np.linalg.det(d) < 0:
        raise ValueError(f"axes {code!r} form a left-handed triad, which no sensor has (check the sign of one "
                         "axis: e.g. frd or rfu)")
    return d


def rotate(d: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rows ``v`` (K, 3) in sensor axes to right-front-up (exact: a signed permutation)."""
    if np.array_equal(d, np.eye(3)):
        return v
    out = np.empty_like(v)
    for i in range(3):
        j = int(np.flatnonzero(d[i])[0])
        out[:, i] = v[:, j] if d[i, j] > 0 else -v[:, j]
    return out
