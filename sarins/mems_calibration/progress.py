"""Progress of a mems-calibration campaign: the phase, and a time estimate that follows the machine.

Each phase's work is estimated up front from the campaign's cost model (recurrent training steps and C-core
evaluation cost per sample, measured on the 2-core reference machine, divided by the workers); as phases
finish, the remaining estimates are scaled by the ratio of measured to estimated time so far (a loaded
machine makes every phase slower by about the same factor).  One line per event on stderr:

    mems-calibration [fitting 2/4] gru3 (process pool, 2 workers) | elapsed 0:41, about 1:52 left
"""

from __future__ import annotations

import resource
import sys
import time


MAX_SCALE = 20.0  # the measured-to-estimated ratio is trusted within 1/20 .. 20


def cpu_seconds() -> float:
    """CPU seconds (user + system) of this process and of its finished children (fitting processes)."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def peak_rss_mb() -> float:
    """Largest resident set of this process so far, MB (Linux reports kB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _clock(seconds: float) -> str:
    seconds = max(0, int(round(seconds)))
    return f"{seconds // 60}:{seconds % 60:02d}"


class Progress:
    """Phases with estimated seconds, in order; :meth:`start` a phase, :meth:`note` within it."""

    def __init__(self, estimates: dict, *, enabled: bool = True, stream=None):
        self.estimates = dict(estimates)
        self.names = list(estimates)
        self.enabled = enabled
        self.stream = stream or sys.stderr
        self.t0 = time.perf_counter()
        self.done_estimate = 0.0  # estimated seconds of the finished phases
        self.current = None
        self.phase_t0 = self.t0
        self.phase_cpu0 = cpu_seconds()
        # {phase: {"wall_s", "cpu_s", "estimate_s", "peak_rss_mb" (this process's peak so far)}} of the finished
        # phases
        self.measured = {}

    def _scale(self) -> float:
        elapsed = self.phase_t0 - self.t0
        if self.done_estimate <= 0.0 or elapsed < 1.0:  # too little measured to judge the machine
            return 1.0
        return min(MAX_SCALE, max(1.0 / MAX_SCALE, elapsed / self.done_estimate))

    def remaining(self) -> float:
        """Estimated seconds left: the current phase's estimate less its elapsed time (at least 0), plus the
        phases still to come, all scaled by the measured-to-estimated ratio of the finished phases."""
        scale = self._scale()
        now = time.perf_counter()
        left = 0.0
        started = False
        for name in self.names:
            if name == self.current:
                started = True
                left += max(0.0, self.estimates[name] * scale - (now - self.phase_t0))
            elif started:
                left += self.estimates[name] * scale
        return left

    def start(self, name: str, detail: str = "") -> None:
        """Finish the current phase and start ``name``."""
        now, cpu = time.perf_counter(), cpu_seconds()
        if self.current is not None:
            self.done_estimate += self.estimates[self.current]
            self.measured[self.current] = {"wall_s": now - self.phase_t0, "cpu_s": cpu - self.phase_cpu0,
                                           "estimate_s": self.estimates[self.current],
                                           "peak_rss_mb": peak_rss_mb()}
        self.current, self.phase_t0, self.phase_cpu0 = name, now, cpu
        self.note(detail)

    def note(self, detail: str) -> None:
        """One progress line: phase, detail, elapsed and estimated time left."""
        if not self.enabled:
            return
        k = self.names.index(self.current) + 1 if self.current in self.names else 0
        head = f"mems-calibration [{self.current} {k}/{len(self.names)}]"
        text = f"{head} {detail}" if detail else head
        print(f"{text} | elapsed {_clock(time.perf_counter() - self.t0)}, about {_clock(self.remaining())} left",
              file=self.stream, flush=True)
