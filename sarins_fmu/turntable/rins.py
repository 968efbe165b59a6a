"""Rotation schemes of rotating inertial navigation systems: single-axis (seed 000) and dual-axis (seed 002)."""

from __future__ import annotations

import math


from ..units import DEG_TO_RAD
from .schedule import AXIS_Y, AXIS_Z, GimbalSchedule
from .segments import (Timeline, ceil_steps, ceil_to_grid, indexing_track, move_segments, move_steps, number,
                       schedule_from_segments)

ROTATION_SCHEMES = ("none", "continuous", "forward-reverse", "four-position")


def _single_axis_segments(scheme, duration, rate, acc, dwell, grid, revolutions=1):
    """Segments (duration, accel) of a single-axis scheme covering ``duration``.

    'continuous' is one acceleration segment (the rate then holds for ever);
    the others repeat their cycle until ``duration`` is covered.
    """
    if scheme == "none":
        return [(ceil_to_grid(duration, grid), 0.0)]
    if rate <= 0 or acc <= 0:
        raise ValueError("rate_dps and accel_dps2 must be positive for a rotating scheme")
    if scheme == "continuous":
        t_acc = ceil_to_grid(rate / acc, grid)
        return [(t_acc, rate / t_acc)]
    dwell = ceil_to_grid(dwell, grid) if dwell > 0 else 0.0
    if scheme == "forward-reverse":
        if not (revolutions >= 1 and float(revolutions).is_integer()):  # 0 turns: a cycle of no time, never ending
            raise ValueError(f"revolutions must be a positive whole number, got {revolutions!r}")
        cycle_moves = [2 * math.pi * revolutions, -2 * math.pi * revolutions]
    else:
        cycle_moves = [math.pi, -0.5 * math.pi, math.pi, -1.5 * math.pi]
    segs, t = [], 0.0
    while t < duration:
        for move in cycle_moves:
            for seg in move_segments(move, rate, acc, grid) + ([(dwell, 0.0)] if dwell else []):
                segs.append(seg)
                t += seg[0]
    return segs


def single_axis(scheme: str = "forward-reverse", duration: float = 88 * 3600.0, *,
                rate_dps: float = 6.0, accel_dps2: float = 6.0, dwell: float = 0.0,
                grid: float = 1.0, revolutions: int = 1, align_time: float = 0.0,
                align_dwell: float = 300.0) -> GimbalSchedule:
    """Single-axis rotation about the body up axis (single-axis RINS).

    Parameters
    ----------
    scheme : {'none', 'continuous', 'forward-reverse', 'four-position'}
        'continuous': accelerate once, then turn at ``rate_dps`` for ever.
        'forward-reverse': ``revolutions`` turns one way, dwell, the same back,
        dwell, repeated.  'four-position': indexing through 0, 180, 90, 270 deg
        (moves +180, -90, +180, -270, the classic four-position sequence),
        dwelling ``dwell`` s at each position.
    duration : float
        Length the schedule must cover, s (the motion pattern repeats).
    rate_dps, accel_dps2 : float
        Peak rotation rate (deg/s) and angular acceleration (deg/s^2).
    dwell : float
        Stop time at each position or reversal, s (rounded up to ``grid``).
    grid : float
        Time grid on which the acceleration may change, s.
    align_time : float
        If positive, the first ``align_time`` seconds use four-position
        indexing with ``align_dwell`` s stops (multi-position alignment: it
        separates the horizontal drifts from the heading error), padded with
        a stop so that the scheme proper starts at rest at ``align_time``.
    """
    if scheme not in ROTATION_SCHEMES:
        raise ValueError(f"unknown rotation scheme {scheme!r}; choose one of {', '.join(ROTATION_SCHEMES)}")
    duration, grid = number("duration", duration, positive=True), number("grid", grid, positive=True)
    rate_dps, accel_dps2, dwell = number("rate_dps", rate_dps), number("accel_dps2", accel_dps2), number("dwell", dwell)
    align_time, align_dwell = number("align_time", align_time), number("align_dwell", align_dwell)
    rate, acc = rate_dps * DEG_TO_RAD, accel_dps2 * DEG_TO_RAD
    segs = []
    if align_time > 0:
        t_align = round(align_time / grid) * grid
        moves = [math.pi, -0.5 * math.pi, math.pi, -1.5 * math.pi]
        dwell_align = ceil_to_grid(align_dwell, grid) if align_dwell > 0 else 0.0
        t_used, k = 0.0, 0
        while True:  # whole moves (with their dwell) that fit in the alignment
            unit = move_segments(moves[k % 4], rate, acc, grid) + ([(dwell_align, 0.0)] if dwell_align else [])
            length = sum(d for d, _ in unit)
            if t_used + length > t_align + 1e-9:
                break
            segs += unit
            t_used += length
            k += 1
        if t_align - t_used > 1e-9:
            segs.append((t_align - t_used, 0.0))
    t_nav = max(duration - sum(d for d, _ in segs), grid)
    segs += _single_axis_segments(scheme, t_nav, rate, acc, dwell, grid, revolutions)
    return schedule_from_segments([AXIS_Z], segs)


# dual-axis RINS (seed 002, Fig. 1): outer frame about the base's roll axis
# (y, front), inner frame about the outer frame's azimuth axis (z, up at
# outer angle 0):  mat_tb = Ry(theta_outer) Rz(theta_inner)
DUAL_AXIS_AXES = (AXIS_Y, AXIS_Z)


def dual_axis(duration: float, *, inner_rate_dps: float = 6.0, inner_accel_dps2: float = 6.0,
              outer_rate_dps: float = 6.0, outer_accel_dps2: float = 6.0, dwell: float = 0.0,
              grid: float = 1.0, align_time: float = 0.0, align_dwell: float = 300.0) -> GimbalSchedule:
    """Dual-axis RINS rotation: inner azimuth forward/reverse, outer 180 deg flips.

    The chain of seed 002 (Fig. 1, eq. (1)): gimbal 0 is the outer frame,
    turning about the base's roll axis y (front); gimbal 1 is the inner frame,
    turning about the outer frame's azimuth axis z (up while the outer angle
    is 0), which carries the IMU::

        mat_tb = Ry(eta_out) Rz(eta_in)          (axes :data:`DUAL_AXIS_AXES`)

    The vehicle scheme of seed 002 turns the inner frame forward and reverse
    about the azimuth axis, which modulates the horizontal gyro drifts but
    leaves the azimuth gyro's drift unmodulated (its eq. (2)-(3)).  Here, after
    every full inner forward/reverse cycle, the outer frame flips the IMU by
    180 deg, alternately +180 and -180, so that the azimuth gyro points up and
    down for equal times and its drift is modulated as well.  One period is
    exactly::

        inner +360, dwell, inner -360, dwell, outer +180, dwell,
        inner +360, dwell, inner -360, dwell, outer -180, dwell

    every move rest-to-rest with a trapezoidal rate (:func:`move_segments`);
    whole periods repeat until ``duration`` is covered, so the schedule ends
    at rest with both gimbals back at 0.

    Parameters
    ----------
    duration : float
        Length the schedule must cover (alignment included), s.
    inner_rate_dps, inner_accel_dps2 : float
        Peak rate (deg/s) and angular acceleration (deg/s^2) of the inner
        (azimuth) frame; both > 0.
    outer_rate_dps, outer_accel_dps2 : float
        The same for the outer frame's flips.
    dwell : float
        Stop after every move, s (rounded up to ``grid``), >= 0.
    grid : float
        Time grid on which the acceleration may change, s, > 0.
    align_time : float
        If positive, the first ``align_time`` s (rounded to ``grid``) are an
        alignment phase as in :func:`single_axis`: four-position indexing of
        the inner frame (moves +180, -90, +180, -270 deg, ``align_dwell`` s
        after each) while the outer frame stays at 0, padded with a stop so
        the scheme proper starts at rest at ``align_time``.
    align_dwell : float
        Stop at each alignment position, s, >= 0.

    Returns
    -------
    GimbalSchedule
        Two gimbals (outer, inner), starting at rest at angle 0 at t = 0.

    Raises
    ------
    ValueError
        On NaN or infinite input, a non-positive duration, grid, rate or
        acceleration, or a negative dwell or alignment time.
    """
    duration = number("duration", duration, positive=True)
    grid = number("grid", grid, positive=True)
    rate_in = number("inner_rate_dps", inner_rate_dps, positive=True) * DEG_TO_RAD
    acc_in = number("inner_accel_dps2", inner_accel_dps2, positive=True) * DEG_TO_RAD
    rate_out = number("outer_rate_dps", outer_rate_dps, positive=True) * DEG_TO_RAD
    acc_out = number("outer_accel_dps2", outer_accel_dps2, positive=True) * DEG_TO_RAD
    n_dwell = ceil_steps(number("dwell", dwell), grid)
    align_time = number("align_time", align_time)
    n_align_dwell = ceil_steps(number("align_dwell", align_dwell), grid)
    OUTER, INNER = 0, 1
    tl = Timeline(2)
    if align_time > 0:
        tl.parallel({INNER: indexing_track(round(align_time / grid), rate_in, acc_in, n_align_dwell, grid)})
    n_end = ceil_steps(duration, grid)
    while True:
        for flip in (math.pi, -math.pi):
            for turn in (2 * math.pi, -2 * math.pi):
                tl.parallel({INNER: move_steps(turn, rate_in, acc_in, grid)})
                tl.rest(n_dwell)
            tl.parallel({OUTER: move_steps(flip, rate_out, acc_out, grid)})
            tl.rest(n_dwell)
        if tl.now >= n_end:
            break
    return tl.schedule(DUAL_AXIS_AXES, grid)
