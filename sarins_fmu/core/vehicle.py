"""ctypes binding of seed 002's vehicle (``vehicle.h``): legs, trajectory, body sway and vibration.

SI throughout (rad, rad/s, rad/s^2, m, m/s, m/s^2, s).  A bad parameter or leg raises ValueError with the
core's one-line reason.  :mod:`sarins_fmu.vehicle` wraps these; the VehicleMotion FMU runs the same C.
"""

from __future__ import annotations

import ctypes

import numpy as np

from ..units import DEG_TO_RAD
from ._lib import function

_I64, _F64, _P, _INT = ctypes.c_int64, ctypes.c_double, ctypes.c_void_p, ctypes.c_int
_SIZE = ctypes.c_size_t
_MSG_LEN = 512
BAD_PARAM, CAPACITY = 1, 3  # SARINS_VEHICLE_* return codes
N_VIBRATION = 3
LEG_CODES = {"stop": 0, "drive": 1, "turn": 2}  # SARINS_LEG_*
LEG_NAMES = {v: k for k, v in LEG_CODES.items()}
# columns of a trajectory row (SARINS_VEH_*): the step that starts at that grid point
COLUMNS = ("yaw", "pitch", "roll", "yaw_rate", "pitch_rate", "roll_rate", "yaw_accel", "pitch_accel", "roll_accel",
           "w_e", "w_n", "w_u", "f_e", "f_n", "f_u", "lat", "lon", "v_e", "v_n", "speed")
N_OUT = len(COLUMNS)
MAX_LEGS_TEXT = 1024  # legs parsed from one text


class Params(ctypes.Structure):
    """``sarins_vehicle_params``."""

    _fields_ = [("lat0", _F64), ("lon0", _F64), ("heading0", _F64), ("step", _F64), ("lead_time", _F64),
                ("accel", _F64), ("brake", _F64), ("yaw_rate", _F64), ("yaw_accel", _F64),
                ("sway_pitch", _F64), ("sway_roll", _F64), ("sway_period", _F64), ("vibration", _F64),
                ("vibration_hz", _F64 * N_VIBRATION), ("reference_speed", _F64), ("seed", ctypes.c_uint64)]


class Leg(ctypes.Structure):
    """``sarins_leg``."""

    _fields_ = [("kind", _INT), ("seconds", _F64), ("value", _F64)]


class Segment(ctypes.Structure):
    """``sarins_vehicle_segment``."""

    _fields_ = [("n", _I64), ("accel", _F64), ("yaw_accel", _F64), ("end_speed", _F64), ("end_turn", _INT)]


_default = function("sarins_vehicle_params_default", None, _P)
_segments = function("sarins_vehicle_segments", _INT, _P, _P, _I64, _P, _I64, _P, _P, ctypes.c_char_p, _SIZE)
_run = function("sarins_vehicle_run", _INT, _P, _P, _I64, _P, _I64, _I64, _P, _P, ctypes.c_char_p, _SIZE)
_parse = function("sarins_vehicle_parse_legs", _I64, ctypes.c_char_p, _P, _I64, ctypes.c_char_p, _SIZE)


def default_params() -> Params:
    """The core's defaults (``sarins_vehicle_params_default``)."""
    p = Params()
    _default(ctypes.byref(p))
    return p


def _legs(legs) -> ctypes.Array:
    """Legs [("drive", s, m/s), ("turn", degrees), ("stop", s)] as a C array (a turn's angle in rad, as the
    core's parser writes it: degrees * DEG_TO_RAD)."""
    out = (Leg * max(1, len(legs)))()
    for i, leg in enumerate(legs):
        kind = leg[0]
        if kind not in LEG_CODES:
            raise ValueError(f"unknown leg {kind!r}; choose one of {', '.join(LEG_CODES)}")
        want = 3 if kind == "drive" else 2
        if len(leg) != want:
            raise ValueError(f"leg {leg!r}: use ('drive', seconds, speed), ('turn', degrees) or ('stop', seconds)")
        if kind == "turn":
            out[i] = Leg(LEG_CODES[kind], float(leg[1]), float(leg[1]) * DEG_TO_RAD)
        else:
            out[i] = Leg(LEG_CODES[kind], float(leg[1]), float(leg[2]) if kind == "drive" else 0.0)
    return out


def _raise(code: int, msg) -> None:
    if code:
        text = msg.value.decode(errors="replace")
        if code == CAPACITY:
            raise RuntimeError(f"vehicle: {text}")
        raise ValueError(text)


def segments(p: Params, legs) -> tuple[list, int]:
    """([(steps, accel m/s^2, yaw accel rad/s^2), ...], total steps) of ``legs`` (turns in degrees)."""
    c_legs, msg = _legs(legs), ctypes.create_string_buffer(_MSG_LEN)
    n_seg, n_steps = _I64(), _I64()
    cap = 3 * len(legs) + 2
    segs = (Segment * cap)()
    _raise(_segments(ctypes.byref(p), c_legs, len(legs), segs, cap, ctypes.byref(n_seg), ctypes.byref(n_steps),
                     msg, _MSG_LEN), msg)
    return [(s.n, s.accel, s.yaw_accel) for s in segs[:n_seg.value]], n_steps.value


def run(p: Params, legs, n_rows: int | None = None) -> np.ndarray:
    """Trajectory rows (n_rows, N_OUT) (default: the drive's steps + 1), row k the step from k * step
    (columns :data:`COLUMNS`); legs as :func:`segments` takes them."""
    c_legs, msg, n_steps = _legs(legs), ctypes.create_string_buffer(_MSG_LEN), _I64()
    cap = 3 * len(legs) + 2
    segs = (Segment * cap)()
    _raise(_run(ctypes.byref(p), c_legs, len(legs), segs, cap, 0, None, ctypes.byref(n_steps), msg, _MSG_LEN), msg)
    rows = n_steps.value + 1 if n_rows is None else int(n_rows)
    out = np.empty((rows, N_OUT))
    _raise(_run(ctypes.byref(p), c_legs, len(legs), segs, cap, rows, out.ctypes.data, ctypes.byref(n_steps), msg,
                _MSG_LEN), msg)
    return out


def parse_legs(text: str) -> list:
    """'drive 300 10; turn 90; stop 1800' -> [('drive', 300.0, 10.0), ('turn', 90.0), ('stop', 1800.0)]
    (turns in degrees, as written), by the FMU's own parser (``sarins_vehicle_parse_legs``)."""
    raw = str(text).encode()
    if b"\0" in raw:
        raise ValueError("legs: a NUL character in the text")
    out, msg = (Leg * MAX_LEGS_TEXT)(), ctypes.create_string_buffer(_MSG_LEN)
    n = _parse(raw, out, MAX_LEGS_TEXT, msg, _MSG_LEN)
    if n < 0:
        raise ValueError(msg.value.decode(errors="replace"))
    legs = []
    for leg in out[:n]:
        kind = LEG_NAMES[leg.kind]
        if kind == "turn":
            legs.append((kind, leg.seconds))  # the angle in degrees as written
        elif kind == "drive":
            legs.append((kind, leg.seconds, leg.value))
        else:
            legs.append((kind, leg.seconds))
    return legs
