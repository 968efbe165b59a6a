"""How a replay aligns on a log: gyrocompassing when the gyros can see the Earth rate, else levelling.

Gyrocompassing (the INS's coarse + Kalman fine alignment) finds the heading from the Earth's
horizontal rate Omega cos L.  It cannot when the gyros' bias or noise over the alignment is far
above that rate (a MEMS gyro of 1,000 deg/h against 10 deg/h): the filter then explains the gyro
bias with a tilt and the tilt with an accelerometer bias, and reports an absurd attitude.  So, over
the alignment window, from the log's 1 s means (right-front-up, rad/s and m/s^2):

* up = the mean specific force's direction; the gyros' horizontal mean rate w_h (perpendicular to
  up) is the Earth's horizontal rate plus the horizontal gyro bias; the noise of that mean is the
  spread of the 1 s means over sqrt(their number);
* the gyros *can see* the Earth rate when |w_h| <= GYROCOMPASS_MARGIN Omega cos L and the noise of
  the mean <= Omega cos L / GYROCOMPASS_MARGIN.  A bias beyond that can only be told from the
  Earth rate by knowing the heading.

When they cannot (or the user gives the heading), :func:`level` levels with the accelerometers'
mean -- roll = atan2(-f_x, f_z), pitch = atan2(f_y, sqrt(f_x^2 + f_z^2)) for mat_nb = Rz(yaw)
Rx(pitch) Ry(roll), f_b = mat_nb^T (0, 0, |f|) -- takes the heading given, and, the attitude
now known, estimates the gyro bias as the mean rate less the Earth rate in body axes, and the
accelerometer bias along the vertical as |f| less normal gravity (its horizontal part cannot be told
from the tilt).  Either way :func:`check_tilt` refuses an attitude whose tilt disagrees with the
accelerometer levelling by more than the largest accelerometer bias of any class allows
(ACCEL_BIAS_MAX), and :func:`accel_bias_note` flags an estimated accelerometer bias beyond it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import earth
from ..rotations import euler_to_mat, mat_to_euler
from ..units import G0

GYROCOMPASS_MARGIN = 5.0  # the gyros see the Earth rate if bias and noise are within this factor of it
ACCEL_BIAS_MAX = 0.1 * G0  # m/s^2: the largest accelerometer bias of any class (consumer MEMS, ~100 mg)
TILT_NOISE = math.radians(0.05)  # rad: allowance for the noise of the mean over the alignment


class AlignmentError(ValueError):
    """A log the replay cannot align as asked; the message names the option that would help."""


@dataclass(frozen=True)
class Sight:
    """What the alignment window says about the gyros: horizontal mean rate, its noise and the Earth's
    horizontal rate (rad/s), and whether gyrocompassing can work."""

    horizontal_rate: float
    noise: float
    earth_rate: float

    @property
    def can_see(self) -> bool:
        return (self.horizontal_rate <= GYROCOMPASS_MARGIN * self.earth_rate
                and self.noise <= self.earth_rate / GYROCOMPASS_MARGIN)

    def reason(self) -> str:
        if self.horizontal_rate > GYROCOMPASS_MARGIN * self.earth_rate:
            return (f"their horizontal rate over the alignment, {math.degrees(self.horizontal_rate) * 3600:.4g} deg/h, "
                    f"is more than {GYROCOMPASS_MARGIN:g} x the Earth's ({math.degrees(self.earth_rate) * 3600:.3g} "
                    "deg/h here): a gyro bias far above the Earth rate (or degrees logged as radians)")
        return (f"the noise of their mean over the alignment, {math.degrees(self.noise) * 3600:.3g} deg/h, is more "
                f"than 1/{GYROCOMPASS_MARGIN:g} of the Earth's horizontal rate "
                f"({math.degrees(self.earth_rate) * 3600:.3g} deg/h here)")


def window_means(means: np.ndarray, seconds: float) -> np.ndarray:
    """The 1 s means of the first ``seconds`` of the log (at least one)."""
    return means[:max(1, int(seconds))]


def sight(means: np.ndarray, lat: float) -> Sight:
    """Whether the gyros can see the Earth rate over these 1 s means (M, 6)."""
    f = means[:, 3:].mean(axis=0)
    up = f / np.linalg.norm(f)
    w = means[:, :3]
    w_h = w - np.outer(w @ up, up)
    mean_h = w_h.mean(axis=0)
    noise = float(np.linalg.norm(w_h.std(axis=0))) / math.sqrt(max(len(w_h) - 1, 1))
    return Sight(float(np.linalg.norm(mean_h)), noise, earth.RATE * math.cos(lat))


def level(means: np.ndarray, lat: float, height: float, heading: float):
    """Accelerometer levelling with a given heading (rad, clockwise from north).

    Returns (mat_nb, gyro bias (3,) rad/s, accelerometer bias (3,) m/s^2, body axes)."""
    f = means[:, 3:].mean(axis=0)
    roll = math.atan2(-f[0], f[2])
    pitch = math.atan2(f[1], math.hypot(f[0], f[2]))
    mat_nb = euler_to_mat(-heading, pitch, roll)  # the project's yaw is counter-clockwise
    w_ie_b = mat_nb.T @ earth.earth_rate_n(lat)
    gyro_bias = means[:, :3].mean(axis=0) - w_ie_b
    g = float(np.linalg.norm(earth.gravity_n(lat, height)))
    up = f / np.linalg.norm(f)
    accel_bias = (float(np.linalg.norm(f)) - g) * up
    return mat_nb, gyro_bias, accel_bias


def tilt_of(means: np.ndarray) -> tuple[float, float]:
    """(roll, pitch), rad, of the accelerometers' mean over these 1 s means."""
    f = means[:, 3:].mean(axis=0)
    return math.atan2(-f[0], f[2]), math.atan2(f[1], math.hypot(f[0], f[2]))


def check_tilt(mat_nb: np.ndarray, means: np.ndarray, path, accel_bias=None) -> None:
    """Refuse (AlignmentError) an attitude whose tilt disagrees with the accelerometers' levelling by
    more than an accelerometer bias of ACCEL_BIAS_MAX (or the estimated one, if smaller) allows."""
    _, pitch, roll = mat_to_euler(mat_nb)
    roll_a, pitch_a = tilt_of(means)
    g = float(np.linalg.norm(means[:, 3:].mean(axis=0)))
    bias = ACCEL_BIAS_MAX if accel_bias is None else min(float(np.linalg.norm(accel_bias)), ACCEL_BIAS_MAX)
    allowed = math.asin(min(bias / g, 1.0)) + TILT_NOISE
    off = max(abs(_wrap(roll - roll_a)), abs(pitch - pitch_a))
    if off > allowed:
        raise AlignmentError(f"{path}: the alignment's tilt (roll {math.degrees(roll):.3g}, pitch "
                             f"{math.degrees(pitch):.3g} deg) disagrees with the accelerometers' levelling (roll "
                             f"{math.degrees(roll_a):.3g}, pitch {math.degrees(pitch_a):.3g} deg) by "
                             f"{math.degrees(off):.3g} deg, more than an accelerometer bias of "
                             f"{bias / G0 * 1e3:.3g} mg allows: the gyros cannot align this log; give the heading "
                             "with --heading-deg")


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def accel_bias_note(accel_bias, path) -> str | None:
    """A warning for an estimated accelerometer bias beyond any class, or None."""
    b = float(np.linalg.norm(accel_bias))
    if b <= ACCEL_BIAS_MAX:
        return None
    return (f"{path}: the estimated accelerometer bias, {b / G0 * 1e3:.4g} mg, is beyond any accelerometer class "
            f"({ACCEL_BIAS_MAX / G0 * 1e3:.3g} mg): the log's accelerometers or the alignment are not to be trusted")
