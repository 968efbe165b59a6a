"""Communication-step schedules.

A schedule is a list of :class:`Segment` s, each a run of equal steps.  The
time of step ``j`` of a segment is ``begin + j * step`` (from a counter, never
by repeated addition) and the last point of a segment is its ``end`` exactly.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .errors import ScheduleError

__all__ = ["Segment", "make_schedule", "StepSpec"]

StepSpec = float | Sequence[tuple[float, float]] | np.ndarray
REL_TOL = 1e-9
MAX_STEPS = 10**9  # communication steps in one run (a 300-day run at 0.01 s is 2.6e9: split it)


@dataclass(frozen=True)
class Segment:
    """``count`` communication steps of size ``step`` from ``begin`` to ``end`` (s)."""

    begin: float
    end: float
    step: float
    count: int


def _count(begin: float, end: float, step: float) -> int:
    if not (math.isfinite(step) and step > 0.0):
        raise ScheduleError(f"communication step must be a finite positive number, got {step!r}",
                            names=("step_size",))
    if not math.isfinite(end):
        raise ScheduleError(f"stop time must be finite, got {end!r}", names=("stop_time",))
    if not end > begin:
        raise ScheduleError(f"segment end {end!r} s must be after its start {begin!r} s",
                            names=("stop_time",))
    steps = (end - begin) / step
    if not steps <= MAX_STEPS:
        raise ScheduleError(f"{end - begin!r} s in steps of {step!r} s is {steps:.3g} communication "
                            f"steps, more than the limit of {MAX_STEPS:.0e} (MAX_STEPS)",
                            names=("stop_time", "step_size"))
    count = round(steps)
    scale = max(abs(begin), abs(end), step)
    if count < 1 or not math.isclose(begin + count * step, end, rel_tol=REL_TOL,
                                     abs_tol=REL_TOL * scale):
        raise ScheduleError(f"{end - begin!r} s from {begin!r} s to {end!r} s is not a whole "
                            f"number of steps of {step!r} s", names=("stop_time", "step_size"))
    return count


def make_schedule(start: float, stop: float | None, step: StepSpec) -> list[Segment]:
    """Build the segments of a run.

    Parameters
    ----------
    start : float
        Start time, s.
    stop : float or None
        Stop time, s; required for a fixed step, must match the last point
        of a schedule when given with one.
    step : float, sequence of (until_time, step), or 1-D array
        A fixed step (s); or ``[(until_1, h_1), (until_2, h_2), ...]``, step
        ``h_k`` until time ``until_k``; or the array of communication points
        (strictly increasing, its first element is the start time).

    Returns
    -------
    list of Segment

    Raises
    ------
    ScheduleError
        On a non-positive or non-finite step, a stop time not reached by a
        whole number of steps, or a non-increasing schedule.
    """
    if not math.isfinite(start):
        raise ScheduleError(f"start time must be finite, got {start!r}", names=("start_time",))
    if np.ndim(step) == 0:
        if stop is None:
            raise ScheduleError("a stop time is needed with a fixed step", names=("stop_time",))
        return [Segment(float(start), float(stop), float(step),
                        _count(float(start), float(stop), float(step)))]
    if isinstance(step, np.ndarray) and step.ndim == 1:
        segments = _from_points(np.asarray(step, dtype=float), start)
    else:
        segments = _from_pairs(step, start)
    if stop is not None and not math.isclose(segments[-1].end, stop, rel_tol=REL_TOL,
                                             abs_tol=REL_TOL * max(1.0, abs(stop))):
        raise ScheduleError(f"schedule ends at {segments[-1].end!r} s, not at the stop "
                            f"time {stop!r} s", names=("stop_time", "step_size"))
    return segments


def _from_pairs(pairs, start: float) -> list[Segment]:
    segments = []
    begin = float(start)
    try:
        items = [(float(until), float(h)) for until, h in pairs]
    except (TypeError, ValueError):
        raise ScheduleError("a step schedule is a list of (until_time, step) pairs") from None
    if not items:
        raise ScheduleError("empty step schedule")
    for until, h in items:
        segments.append(Segment(begin, until, h, _count(begin, until, h)))
        begin = until
    return segments


def _from_points(points: np.ndarray, start: float) -> list[Segment]:
    if points.size < 2:
        raise ScheduleError("an array of communication points needs at least two points")
    if not math.isclose(points[0], start, rel_tol=REL_TOL, abs_tol=REL_TOL):
        raise ScheduleError(f"communication points start at {points[0]!r} s, not at the "
                            f"start time {start!r} s")
    steps = np.diff(points)
    if not np.all(np.isfinite(steps)) or np.any(steps <= 0.0):
        raise ScheduleError("communication points must be finite and strictly increasing")
    return [Segment(float(a), float(b), float(b - a), 1) for a, b in zip(points[:-1], points[1:])]
