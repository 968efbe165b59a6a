"""Real-time pacing and the progress bar of a run."""
from __future__ import annotations

import math
import time as _time
import warnings

import numpy as np

from .errors import RealTimeLagWarning, ScheduleError

__all__ = ["RealTimePacer", "Progress", "AUTO_PROGRESS_STEPS"]

AUTO_PROGRESS_STEPS = 20_000  # runs with at least this many steps show a bar by default
LAG_TOLERANCE = 0.010  # s of wall clock behind schedule tolerated before warning
MAX_FACTOR = 1e6  # wall-clock seconds per simulated second, at most


class RealTimePacer:
    """Keep the wall clock in step with simulated time (for hardware in the loop).

    The wall-clock time elapsed since the start is held at
    ``factor * (t - t0)``: ``factor = 1`` is real time, ``0.5`` runs twice as
    fast as real time, ``2`` twice as slow.  When the run falls behind by
    more than one communication step (and at least 10 ms) a
    :class:`RealTimeLagWarning` giving the lag is issued, once.  Every step's
    lag (wall clock at the end of the step's work minus its target, negative
    when the step finished early: the slack) is kept in an array allocated
    here, so :meth:`report` gives the distribution (p50, p99, max, late
    steps, least slack) and the loop allocates nothing.  The clock starts
    at construction and again at :meth:`start`.

    Parameters
    ----------
    factor : float
        Wall-clock seconds per simulated second, > 0.
    start_time : float
        Simulated start time, s.
    capacity : int
        Steps whose lag is kept (the run's planned steps); later steps are
        paced and counted but not kept.
    """

    def __init__(self, factor: float, start_time: float, capacity: int = 0):
        if not (math.isfinite(factor) and factor > 0.0):
            raise ScheduleError(f"real-time factor must be a finite positive number, got "
                                f"{factor!r}", names=("realtime",))
        if factor > MAX_FACTOR:
            raise ScheduleError(f"real-time factor {factor!r} is above {MAX_FACTOR:g} wall-clock "
                                "seconds per simulated second", names=("realtime",))
        self.factor = float(factor)
        self.start_time = start_time
        self.wall_start = _time.perf_counter()
        self.max_lag = 0.0
        self.max_lag_time: float | None = None
        self.late_steps = 0
        self.steps = 0
        self.warned = False
        self.lags = np.empty(max(0, int(capacity)))

    def start(self) -> None:
        """Start the clock now (call it once the FMUs are loaded and initialised)."""
        self.wall_start = _time.perf_counter()

    def report(self) -> dict:
        """The run's pacing, a JSON-ready dict.

        ``factor``, ``steps``, ``late_steps``: a step is late when its work
        ended after its wall-clock target; ``max_lag_s`` is the largest such
        delay (s of wall clock), at simulated time ``max_lag_time`` (s,
        ``None`` if no step was late).  Over the kept steps (``kept_steps``):
        ``lag_p50_s``, ``lag_p99_s``, ``lag_p999_s`` are percentiles of the
        lateness max(0, end - target), and ``min_slack_s`` is the smallest
        margin target - end (negative when a step was late), all ``None``
        without steps.
        """
        kept = self.lags[:min(self.steps, self.lags.size)]
        late = np.maximum(kept, 0.0)
        stats = {"lag_p50_s": None, "lag_p99_s": None, "lag_p999_s": None, "min_slack_s": None}
        if kept.size:
            p50, p99, p999 = np.percentile(late, [50.0, 99.0, 99.9])
            stats = {"lag_p50_s": float(p50), "lag_p99_s": float(p99), "lag_p999_s": float(p999),
                     "min_slack_s": float(-kept.max())}
        return {"factor": self.factor, "steps": self.steps, "late_steps": self.late_steps,
                "max_lag_s": self.max_lag, "max_lag_time": self.max_lag_time,
                "kept_steps": int(kept.size), **stats}

    def wait(self, sim_time: float, step: float) -> None:
        """Sleep until the wall clock reaches simulated time ``sim_time``."""
        target = self.wall_start + self.factor * (sim_time - self.start_time)
        ahead = target - _time.perf_counter()
        if self.steps < self.lags.size:
            self.lags[self.steps] = -ahead
        self.steps += 1
        if ahead > 0.0:
            _time.sleep(ahead)
            return
        lag = -ahead
        self.late_steps += 1
        if lag > self.max_lag:
            self.max_lag, self.max_lag_time = lag, sim_time
        if not self.warned and lag > max(LAG_TOLERANCE, self.factor * step):
            self.warned = True
            warnings.warn(f"real-time pacing (factor {self.factor:g}) fell behind by "
                          f"{lag:.3f} s of wall clock at simulated t = {sim_time:.6g} s",
                          RealTimeLagWarning, stacklevel=4)


class Progress:
    """A tqdm bar updated in chunks, or nothing.

    Parameters
    ----------
    total : int
        Number of communication steps.
    enabled : bool or None
        ``None`` shows the bar for runs of at least ``AUTO_PROGRESS_STEPS`` steps.
    """

    def __init__(self, total: int, enabled: bool | None, description: str = "cosim"):
        if enabled is None:
            enabled = total >= AUTO_PROGRESS_STEPS
        self.bar = None
        self.chunk = max(1, total // 200)
        self.next_tick = self.chunk if enabled else -1
        self.done = 0
        if enabled:
            from tqdm import tqdm

            self.bar = tqdm(total=total, desc=description, unit="step", leave=False)

    def tick(self, steps_done: int) -> None:
        """Advance the bar to ``steps_done`` steps."""
        self.bar.update(steps_done - self.done)
        self.done = steps_done
        self.next_tick = steps_done + self.chunk

    def close(self) -> None:
        """Close the bar, if any."""
        if self.bar is not None:
            self.bar.close()
