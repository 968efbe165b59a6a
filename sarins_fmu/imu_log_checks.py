"""Unit checks of an IMU log, streamed: refuse what is certain, warn about what a real sensor can also do.

Fed block by block with the log's mean rates (SI, right-front-up) by the readers of
:mod:`sarins_fmu.imu_log`; :meth:`UnitChecks.finish` then looks at the whole log.

Certain (refused, :class:`~sarins_fmu.imu_log.LogError`; ``accept_units`` turns them into warnings):

* a sample beyond any IMU's full scale: |rate| > 35 rad/s (2000 deg/s) or |f| > 16 g;
* the mean of |f| over the log is not gravity (9.0 .. 10.6 m/s^2): a vehicle's accelerations average
  out over a log, while accelerations in g (x 1/9.8), in mg (x 102) or increments read as rates
  (x 1/h) do not.  The range holds every accelerometer class: a 100 mg bias or 5 % scale error
  (consumer MEMS) moves |f| by less than 0.6 m/s^2 from 9.78 .. 9.83.

What a real sensor can also produce (one-line warnings naming what was assumed):

* in a 60 s window in which the specific force keeps its direction (at rest, turning about the
  vertical, cruising level), the gyros' rate perpendicular to f is the Earth's horizontal rate plus
  the gyro bias.  Above :data:`STATIC_RATE_LIMIT` (1e-3 rad/s, 206 deg/h) that bias is a MEMS gyro's,
  or the rates are in degrees logged as radians (57 x the Earth rate, 4.2e-3 cos L rad/s): the two
  look the same, so the log is read and the warning says both.  A replay then finds that the gyros
  cannot see the Earth rate and asks for the heading.
"""

from __future__ import annotations

import math

import numpy as np

MAX_GYRO_RATE = 35.0  # rad/s (2000 deg/s, the largest MEMS full scale)
MAX_SPECIFIC_FORCE = 16 * 9.80665  # m/s^2 (16 g, the largest MEMS accelerometer full scale)
GRAVITY_RANGE = (9.0, 10.6)  # m/s^2, plausible |f| averaged over a log, any accelerometer class
STATIC_RATE_LIMIT = 1e-3  # rad/s (206 deg/h): Earth rate plus a navigation-grade bias, at rest
STATIC_WINDOW = 60.0  # s, window of the gyro-against-tilt check, anywhere in the log
LEVEL_STEADY = 0.01  # rad: f keeps its body direction within this over a window -> no horizontal rotation
MEAN_TIME = 1.0  # s, the means the whole-log checks look at


class UnitChecks:
    """Streamed unit checks of one log (see the module docstring).

    path : the file (for messages); where : row index -> 'line N' / 'row N'; h : sample interval, s;
    quantity : 'increments' or 'rates' (named in a message); accept_units : refusals become warnings.
    """

    def __init__(self, path, where, h: float, quantity: str, accept_units: bool = False):
        self.path, self.where, self.h, self.quantity, self.accept = path, where, h, quantity, accept_units
        self.block = max(1, int(round(MEAN_TIME / h)))
        self._carry = np.empty((0, 6))
        self._means = []
        self._force_sum = 0.0
        self.n = 0
        self.warnings: list[str] = []
        self._first_fast = self._first_strong = None

    def _refuse(self, message: str) -> None:
        if not self.accept:
            from .imu_log import LogError

            raise LogError(message)
        self.warnings.append(message + " (read anyway: --accept-units)")

    def feed(self, rates: np.ndarray) -> None:
        """Rates (K, 6) rad/s and m/s^2, right-front-up, the next K samples of the log."""
        gyro = np.sqrt(np.einsum("ij,ij->i", rates[:, :3], rates[:, :3]))
        force = np.sqrt(np.einsum("ij,ij->i", rates[:, 3:], rates[:, 3:]))
        fast = gyro > MAX_GYRO_RATE
        if fast.any() and self._first_fast is None:
            row = int(np.argmax(fast))
            self._first_fast = row
            self._refuse(f"{self.path}: {self.where(self.n + row)}: angular rate {gyro[row]:.4g} rad/s is beyond any "
                         f"IMU ({MAX_GYRO_RATE} rad/s): degrees logged as radians?")
        strong = force > MAX_SPECIFIC_FORCE
        if strong.any() and self._first_strong is None:
            row = int(np.argmax(strong))
            self._first_strong = row
            self._refuse(f"{self.path}: {self.where(self.n + row)}: specific force {force[row]:.4g} m/s^2 is beyond "
                         f"any IMU ({MAX_SPECIFIC_FORCE:.4g} m/s^2 = 16 g): rates logged as {self.quantity} or the "
                         "reverse?")
        self._force_sum += float(force.sum())
        self.n += rates.shape[0]
        data = np.concatenate([self._carry, rates]) if self._carry.size else rates
        whole = data.shape[0] // self.block * self.block
        if whole:
            self._means.append(data[:whole].reshape(-1, self.block, 6).mean(axis=1))
        self._carry = data[whole:].copy()

    @property
    def means(self) -> np.ndarray:
        """(M, 6) means over each whole MEAN_TIME of the log (rad/s, m/s^2)."""
        return np.concatenate(self._means) if self._means else np.empty((0, 6))

    def finish(self) -> list[str]:
        """The whole-log checks; returns the warnings (refusals raise LogError)."""
        g_mean = self._force_sum / max(self.n, 1)
        if not GRAVITY_RANGE[0] <= g_mean <= GRAVITY_RANGE[1]:
            self._refuse(f"{self.path}: {self.where(0)}..{self.where(self.n - 1)}: mean specific force {g_mean:.4g} "
                         "m/s^2 over the log is not gravity (accelerations in g, or rates logged as increments or "
                         "the reverse?)")
        self._level_rate()
        return self.warnings

    def _level_rate(self) -> None:
        means = self.means
        if means.shape[0] == 0:
            return
        per_window = max(1, min(means.shape[0], int(round(STATIC_WINDOW / (self.block * self.h)))))
        for start in range(0, means.shape[0] - per_window + 1, per_window):
            rate = level_rate(means[start:start + per_window])
            if rate is not None and rate > STATIC_RATE_LIMIT:
                first, last = start * self.block, (start + per_window) * self.block - 1
                self.warnings.append(
                    f"{self.path}: {self.where(first)}..{self.where(last)}: the gyros turn {rate:.3g} rad/s "
                    f"({math.degrees(rate) * 3600:.4g} deg/h) about a horizontal axis while the accelerometers see "
                    "no tilt: taken as the Earth rate plus a MEMS-class gyro bias; on a navigation-grade unit this "
                    "means degrees logged as radians")
                return


def level_rate(means: np.ndarray) -> float | None:
    """Median horizontal gyro rate (rad/s) over rows of 1 s means (M, 6) whose specific force keeps its
    direction within LEVEL_STEADY; None if it does not (the body tilts)."""
    omega, force = means[:, :3], means[:, 3:]
    up = force.mean(axis=0)
    norm_up = np.linalg.norm(up)
    norms = np.linalg.norm(force, axis=1)
    if norm_up == 0.0 or np.any(norms == 0.0):
        return None
    directions = force / norms[:, None]
    if np.max(np.arccos(np.clip(directions @ (up / norm_up), -1.0, 1.0))) > LEVEL_STEADY:
        return None
    up /= norm_up
    horizontal = omega - np.outer(omega @ up, up)
    return float(np.median(np.linalg.norm(horizontal, axis=1)))


def motion(means: np.ndarray) -> str | None:
    """Why a record is not static, from its 1 s means (M, 6), or None: the specific force turns by more
    than LEVEL_STEADY from its mean direction, or a gyro's 1 s mean leaves its median by more than
    20 robust standard deviations (and more than 1e-3 rad/s)."""
    if means.shape[0] < 2:
        return None
    force = means[:, 3:]
    up = force.mean(axis=0)
    norms = np.linalg.norm(force, axis=1)
    if np.linalg.norm(up) > 0 and np.all(norms > 0):
        tilt = np.arccos(np.clip(force @ (up / np.linalg.norm(up)) / norms, -1.0, 1.0))
        if tilt.max() > LEVEL_STEADY:
            return (f"the specific force turns by up to {math.degrees(float(tilt.max())):.3g} deg from its mean "
                    "direction")
    gyro = means[:, :3]
    med = np.median(gyro, axis=0)
    spread = 1.4826 * np.median(np.abs(gyro - med), axis=0)
    jump = np.abs(gyro - med)
    moving = (jump > 20 * spread) & (jump > 1e-3)
    if moving.any():
        axis = int(np.argmax(moving.any(axis=0)))
        return f"the {'xyz'[axis]} gyro's 1 s means leave their median by up to {float(jump[:, axis].max()):.3g} rad/s"
    return None
