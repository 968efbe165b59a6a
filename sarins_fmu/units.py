"""Unit conversion constants between SI and the papers' units.

Multiply a value in the unit on the left of ``_TO_`` by the constant to get
the unit on the right, e.g. ``drift = drift_dph * DPH_TO_RPS``.
"""

import math

DEG_TO_RAD = math.pi / 180.0
RAD_TO_DEG = 180.0 / math.pi
HOUR = 3600.0  # s
DAY = 86400.0  # s
DPH_TO_RPS = DEG_TO_RAD / HOUR  # deg/h -> rad/s
RPS_TO_DPH = 1.0 / DPH_TO_RPS
DPSH_TO_RPSS = DEG_TO_RAD / 60.0  # deg/sqrt(h) -> rad/sqrt(s)  (angle random walk)
NM = 1852.0  # one nautical mile, m
G0 = 9.80665  # standard gravity, m/s^2 (only for ug / g unit conversions)
UG_TO_MPS2 = 1e-6 * G0  # micro-g -> m/s^2
ARCSEC_TO_RAD = DEG_TO_RAD / 3600.0
PPM = 1e-6
