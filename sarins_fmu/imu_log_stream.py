"""Samples of a log, fed block by block: time grid, values, units and axes checked, stored compactly.

Every reader of :mod:`sarins_fmu.imu_log` parses its file in blocks and feeds them to a
:class:`LogBuilder`, which

* checks the values (NaN and infinities) and the clock: strictly increasing on a uniform grid.  The
  project's format is *strict*: the interval h is the first difference and every difference is
  within 1e-6 h of it, the time kept as written.  The other formats (vendor CSV, i2Nav, ROS) take a
  *nominal* interval, the mean of the first differences below 1.5 x their median (snapped to 1 / an integer rate when it is
  one within SNAP = 1e-4), accept timestamps that jitter by up to :data:`MAX_JITTER` of it with a warning,
  and store the uniform grid h, 2h, ... (the first sample ends at h);
* rotates the vectors to right-front-up (:mod:`sarins_fmu.imu_log_units`) and turns rates into
  increments (rate x h);
* runs the streamed unit checks (:mod:`sarins_fmu.imu_log_checks`);
* stores the rows: in memory, or past :data:`SPILL_BYTES` in an unlinked temporary file that is
  mapped read-only at the end, so reading a large log holds one block at a time.
"""

from __future__ import annotations

import math
import tempfile

import numpy as np

from .imu_log_checks import UnitChecks
from .imu_log_units import rotate

SPILL_BYTES = 64 * 2**20  # bytes of samples kept in memory; more go to a temporary file, mapped
MAX_JITTER = 0.1  # of h: timestamps of the non-strict formats may deviate this much from the grid
STRICT_TOLERANCE = 1e-6  # of h: every time step of the project's format
NOMINAL_SAMPLES = 1001  # first timestamps whose mean difference is a non-strict log's interval


class SampleStore:
    """Rows of ``width`` float64 columns appended block by block; :meth:`array` returns them all."""

    def __init__(self, width: int):
        self.width = width
        self.rows = 0
        self._blocks: list[np.ndarray] = []
        self._bytes = 0
        self._file = None

    def append(self, rows: np.ndarray) -> None:
        rows = np.ascontiguousarray(rows, dtype=np.float64)
        self.rows += rows.shape[0]
        if self._file is None and self._bytes + rows.nbytes > SPILL_BYTES:
            self._file = tempfile.TemporaryFile(prefix="sarins-log-")
            for block in self._blocks:
                self._file.write(block.tobytes())
            self._blocks = []
        if self._file is not None:
            self._file.write(rows.tobytes())
        else:
            self._blocks.append(rows)
            self._bytes += rows.nbytes

    def array(self) -> np.ndarray:
        """(rows, width): in memory, or the temporary file mapped read-only (it is unlinked already)."""
        if self._file is None:
            if not self._blocks:
                return np.empty((0, self.width))
            return self._blocks[0] if len(self._blocks) == 1 else np.concatenate(self._blocks)
        self._file.flush()
        return np.memmap(self._file, dtype=np.float64, mode="r", shape=(self.rows, self.width))


SNAP = 1e-4  # relative: an interval this close to 1 / an integer rate is taken as that (a crystal's tolerance)


def snap_interval(h: float) -> float:
    """h, or 1/n when 1/h is within SNAP of an integer n (a clock printed in decimals, or jittering, reads
    back as its nominal rate)."""
    rate = 1.0 / h
    n = round(rate)
    return 1.0 / n if n >= 1 and abs(rate - n) <= SNAP * rate else h


class LogBuilder:
    """Checks, converts and stores the samples of one log (see the module docstring).

    path, where : the file and row -> 'line N' for messages; strict : the project's clock rules;
    quantity : 'increments' or 'rates' of the fed vectors; axes : (3, 3) sensor -> right-front-up;
    has_temps, has_ref : the optional columns; rate_hz : the sample rate when the log has no time;
    accept_units : unit refusals become warnings.
    """

    def __init__(self, path, where, *, strict: bool, quantity: str, axes: np.ndarray, has_temps: bool,
                 has_ref: bool, rate_hz: float | None = None, accept_units: bool = False):
        from .imu_log import LogError  # noqa: F401  (raised below through _error)

        self.path, self.where, self.strict, self.quantity, self.axes = path, where, strict, quantity, axes
        self.has_temps, self.has_ref, self.accept_units = has_temps, has_ref, accept_units
        self.h = None if rate_hz is None else snap_interval(1.0 / rate_hz)
        self.from_rate = rate_hz is not None
        self.store = SampleStore(7 + 6 * has_temps + 3 * has_ref)
        self.checks = None
        self.n = 0
        self.t_first = self.t_last = None
        self.jitter = 0.0
        self.warnings: list[str] = []

    def _error(self, message: str):
        from .imu_log import LogError

        return LogError(f"{self.path}: {message}")

    def feed(self, time, imu: np.ndarray, temps=None, ref=None) -> None:
        """The next K samples: time (K,) s or None (rate given), imu (K, 6) SI vectors in sensor axes
        (rates or increments, gyro first), temps (K, 6) degC, ref (K, 3) lat, lon deg and height m."""
        k = imu.shape[0]
        if k == 0:
            return
        self._finite(time, imu, temps, ref)
        if self.from_rate:
            t = (self.n + np.arange(1, k + 1)) * self.h
        else:
            t = self._clock(np.asarray(time, float))
        h = self.h
        imu = np.concatenate([rotate(self.axes, imu[:, :3]), rotate(self.axes, imu[:, 3:])], axis=1)
        rates = imu / h if self.quantity == "increments" else imu
        if self.checks is None:
            self.checks = UnitChecks(self.path, self.where, h, self.quantity, self.accept_units)
        self.checks.feed(rates)
        inc = imu if self.quantity == "increments" else imu * h
        cols = [t[:, None], inc]
        if self.has_temps:
            cols.append(temps)
        if self.has_ref:
            cols.append(np.column_stack([np.radians(ref[:, 0]), np.radians(ref[:, 1]), ref[:, 2]]))
        self.store.append(np.concatenate(cols, axis=1))
        self.n += k

    def _finite(self, time, imu, temps, ref) -> None:
        parts = [("time_s", time), ("imu", imu), ("temperature", temps), ("reference", ref)]
        for label, arr in parts:
            if arr is None:
                continue
            bad = ~np.isfinite(arr)
            if bad.any():
                row = int(np.argwhere(bad)[0][0])
                value = np.asarray(arr).reshape(arr.shape[0], -1)[row]
                raise self._error(f"{self.where(self.n + row)}: {self._column_name(label, bad)} is "
                                  f"{value[np.argmax(~np.isfinite(value))]} (NaN or infinite)")

    names = None  # set by a reader: the file's column names of each part, for messages

    def _column_name(self, label, bad) -> str:
        if self.names and label in self.names:
            col = int(np.argwhere(bad)[0][1]) if bad.ndim == 2 else 0
            return self.names[label][col]
        return label

    def _clock(self, t: np.ndarray) -> np.ndarray:
        """Check the time stamps; returns the times to store."""
        if self.h is None:
            if t.size < 2:
                raise self._error("a log needs at least two samples")
            if self.strict:
                self.h = float(t[1] - t[0])
            else:
                dt0 = np.diff(t[:NOMINAL_SAMPLES])
                ok = dt0 < 1.5 * np.median(dt0)  # a gap does not set the interval
                self.h = snap_interval(float(dt0[ok].mean())) if np.all(dt0 > 0) else float(t[1] - t[0])
            self.t_first = float(t[0])
            if self.strict:
                self._time_start(t[0])
        prev = self.t_last
        dt = np.diff(t, prepend=prev) if prev is not None else np.diff(t)
        offset = 0 if prev is not None else 1  # row of dt[0] within this block
        h = self.h
        if np.any(dt <= 0):
            i = int(np.argmax(dt <= 0))
            what = "duplicated" if dt[i] == 0 else "earlier than the one before (non-monotonic)"
            raise self._error(f"{self.where(self.n + i + offset)}: timestamp {float(t[i + offset]):.10g} s is {what}")
        if h <= 0:
            raise self._error(f"{self.where(self.n + 1)}: timestamp {float(t[1]):.10g} s is duplicated")
        dev = np.abs(dt - h)
        tol = STRICT_TOLERANCE * h if self.strict else MAX_JITTER * h
        off = dev > tol
        if off.any():
            i = int(np.argmax(off))
            kind_of = "a gap" if dt[i] > 1.5 * h else "a rate change"
            raise self._error(f"{self.where(self.n + i + offset)}: time step {dt[i]:.9g} s differs from the log's "
                              f"{h:.9g} s ({kind_of}); logs must be uniformly sampled")
        if dev.size:
            self.jitter = max(self.jitter, float(dev.max()) / h)
        self.t_last = float(t[-1])
        if self.strict:
            return t
        return (self.n + np.arange(1, t.size + 1)) * h

    def _time_start(self, t0: float) -> None:
        from .imu_log import TIME_START_TOLERANCE

        h = self.h
        tol = TIME_START_TOLERANCE * h
        if not -tol <= t0 <= h + tol:
            raise self._error(f"{self.where(0)}: the first timestamp is {t0:.10g} s; time_s counts from the start of "
                              f"the recording, so the first sample lies in [0, h] = [0, {h:.9g}] s (subtract the "
                              "start time)")

    def finish(self):
        """(table (n, 7 [+6] [+3]), h, warnings, 1 s means (M, 6)) after the whole-log checks."""
        if self.n < 2:
            raise self._error("a log needs at least two samples")
        warnings = list(self.warnings)
        if not self.strict and self.jitter > STRICT_TOLERANCE:
            warnings.append(f"{self.path}: the timestamps deviate by up to {100 * self.jitter:.3g} % of the "
                            f"{self.h:.9g} s interval; the log is taken as uniformly sampled")
        warnings += self.checks.finish()
        if not math.isfinite(self.h):
            raise self._error("the sample interval is not finite")
        return self.store.array(), self.h, warnings, self.checks.means
