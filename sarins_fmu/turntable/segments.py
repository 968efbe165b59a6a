"""Building blocks of the profiles: rest-to-rest moves and segment timelines on a grid.

A segment is (duration, accel): a constant angular acceleration (rad/s^2) held for
``duration`` s; :class:`Timeline` counts durations in whole grid steps so every
breakpoint lies exactly on start + n * grid.
"""

from __future__ import annotations

import math

import numpy as np

from ..checks import finite_number as number  # noqa: F401 (used by rins, rate_table)
from .schedule import GimbalSchedule


def ceil_steps(duration: float, grid: float) -> int:
    """Whole grid steps covering ``duration`` (0 for 0)."""
    return max(0, math.ceil(duration / grid - 1e-9))


def move_steps(angle: float, rate: float, accel: float, grid: float):
    """:func:`move_segments` as [(steps, accel)] with integer grid steps."""
    return [(int(round(d / grid)), float(a)) for d, a in move_segments(angle, rate, accel, grid)]


def ceil_to_grid(duration: float, grid: float) -> float:
    """``duration`` rounded up to whole steps of ``grid`` (at least one step), s."""
    return max(1, ceil_steps(duration, grid)) * grid


def move_segments(angle: float, rate_max: float, accel_max: float, grid: float):
    """Segments of a trapezoidal-rate move through ``angle`` (rad) from rest to rest.

    The acceleration and cruise phases are whole multiples of ``grid``; the
    peak rate is lowered slightly (never raised) so that the move covers
    ``angle`` exactly.  Returns a list of (duration, accel) with scalar accel.
    """
    if angle == 0.0:
        return []
    if not (rate_max > 0 and accel_max > 0 and grid > 0):
        raise ValueError("rate, acceleration and grid must be positive")
    sign = 1.0 if angle > 0 else -1.0
    angle = abs(angle)
    t_acc = ceil_to_grid(rate_max / accel_max, grid)
    if rate_max * t_acc >= angle:  # triangular profile: no cruise phase
        t_acc = ceil_to_grid(math.sqrt(angle / accel_max), grid)
        t_cruise = 0.0
    else:
        t_cruise = ceil_to_grid(angle / rate_max - t_acc, grid)
    rate = angle / (t_acc + t_cruise)  # area of the trapezoid equals the angle
    acc = rate / t_acc
    segs = [(t_acc, sign * acc)]
    if t_cruise > 0:
        segs.append((t_cruise, 0.0))
    segs.append((t_acc, -sign * acc))
    return segs


def schedule_from_segments(axes, segs, t0=0.0, angle0=None, rate0=None):
    """Build a GimbalSchedule from [(duration, accel (A,)), ...]."""
    axes = np.atleast_2d(np.asarray(axes, float))
    n_axes = axes.shape[0]
    durations = np.array([d for d, _ in segs], dtype=float)
    accel = np.array([np.broadcast_to(a, (n_axes,)) for _, a in segs], dtype=float).reshape(-1, n_axes)
    times = t0 + np.concatenate([[0.0], np.cumsum(durations)])
    zeros = np.zeros(n_axes)
    return GimbalSchedule(axes, times, accel,
                          zeros if angle0 is None else angle0, zeros if rate0 is None else rate0)


class Timeline:
    """Accumulates segments (steps, accel (A,)) of a gimbal chain on a grid."""

    def __init__(self, n_axes: int):
        self.n_axes = n_axes
        self.steps: list[int] = []
        self.accel: list[np.ndarray] = []
        self.now = 0  # grid steps so far

    def rest(self, steps: int) -> None:
        if steps > 0:
            self.steps.append(int(steps))
            self.accel.append(np.zeros(self.n_axes))
            self.now += int(steps)

    def parallel(self, tracks: dict) -> None:
        """Run {gimbal: [(steps, accel)]} simultaneously from now; the others rest.

        The block lasts as long as the longest track; a gimbal whose track is
        shorter has zero acceleration afterwards.
        """
        tracks = {j: segs for j, segs in tracks.items() if segs}
        if not tracks:
            return
        ends = {j: np.cumsum([n for n, _ in segs]) for j, segs in tracks.items()}
        bounds = np.unique(np.concatenate([[0]] + list(ends.values())))
        starts = bounds[:-1]
        acc = np.zeros((len(starts), self.n_axes))
        for j, segs in tracks.items():
            idx = np.searchsorted(ends[j], starts, side="right")
            inside = idx < len(segs)
            acc[inside, j] = np.array([a for _, a in segs])[idx[inside]]
        for n, a in zip(np.diff(bounds), acc):
            self.steps.append(int(n))
            self.accel.append(a)
        self.now += int(bounds[-1])

    def schedule(self, axes, grid: float) -> GimbalSchedule:
        """The GimbalSchedule, equal consecutive accelerations merged, starting at rest at 0."""
        steps, accel = [], []
        for n, a in zip(self.steps, self.accel):
            if n <= 0:
                continue
            if accel and np.array_equal(accel[-1], a):
                steps[-1] += n
            else:
                steps.append(n)
                accel.append(a)
        if not steps:
            steps, accel = [1], [np.zeros(self.n_axes)]
        n = np.array(steps)
        times = grid * np.concatenate([[0], np.cumsum(n)]).astype(float)
        # the schedule integrates accel * diff(times); diff(times) differs from
        # n * grid by rounding (grid = 0.01 is not a binary fraction), so scale
        # the accelerations to keep each segment's rate change accel * n * grid:
        # a rest-to-rest move then ends at rest to the last bit, not 1e-13 rad/s
        accel = np.array(accel) * ((n * grid) / np.diff(times))[:, None]
        return GimbalSchedule(np.asarray(axes, float), times, accel,
                              np.zeros(self.n_axes), np.zeros(self.n_axes))


def indexing_track(n_align: int, rate: float, acc: float, dwell_steps: int, grid: float):
    """Four-position indexing (+180, -90, +180, -270 deg moves, each followed by
    a dwell) filling ``n_align`` grid steps with whole moves, padded with rest."""
    moves = [math.pi, -0.5 * math.pi, math.pi, -1.5 * math.pi]
    track, used, k = [], 0, 0
    while n_align > 0:
        unit = move_steps(moves[k % 4], rate, acc, grid) + ([(dwell_steps, 0.0)] if dwell_steps else [])
        length = sum(n for n, _ in unit)
        if used + length > n_align:
            break
        track += unit
        used += length
        k += 1
    if n_align > used:
        track.append((n_align - used, 0.0))
    return track

