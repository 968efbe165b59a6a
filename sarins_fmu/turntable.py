"""Turntable (gimbal) motion truth: rotation schemes and rate-table profiles.

A :class:`GimbalSchedule` describes a chain of one to three gimbals.  Gimbal
``j`` turns by angle ``theta_j`` about the unit vector ``axes[j]`` expressed
in its parent frame (the parent of gimbal 0 is the base frame ``t``; the
innermost gimbal carries the IMU, frame ``b``), so

    mat_tb = R(axes[0], theta_0) R(axes[1], theta_1) ... R(axes[A-1], theta_{A-1})

with R(a, theta) = exp(theta [a x]).  Every gimbal has a piecewise-constant
angular acceleration that changes only at the breakpoints ``times``: within
a segment angle and rate are exact quadratic and linear functions of time.
The IMU rebuilds the motion inside an output interval exactly from the state
(angle, rate, acceleration) at the start of the interval, which requires the
breakpoints to lie on the IMU's output grid (:meth:`GimbalSchedule.check_grid`).
After the last breakpoint the gimbals keep their final rate (no acceleration).

Angles are not wrapped (a continuous rotation accumulates); rad, rad/s,
rad/s^2, s throughout.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._jit import jit
from .units import DEG_TO_RAD

AXIS_X = (1.0, 0.0, 0.0)
AXIS_Y = (0.0, 1.0, 0.0)
AXIS_Z = (0.0, 0.0, 1.0)

ROTATION_SCHEMES = ("none", "continuous", "forward-reverse", "four-position")


@dataclass(frozen=True)
class GimbalSchedule:
    """Piecewise-constant-acceleration motion of a gimbal chain.

    Attributes
    ----------
    axes : ndarray (A, 3)
        Unit rotation axis of each gimbal in its parent frame, outer first.
    times : ndarray (M + 1,)
        Breakpoints, s, strictly increasing; ``times[0]`` is the start.
    accel : ndarray (M, A)
        Angular acceleration on [times[m], times[m+1]), rad/s^2.
    angle0, rate0 : ndarray (A,)
        Angles (rad) and rates (rad/s) at ``times[0]``.
    """

    axes: np.ndarray
    times: np.ndarray
    accel: np.ndarray
    angle0: np.ndarray
    rate0: np.ndarray

    def __post_init__(self):
        axes = np.atleast_2d(np.asarray(self.axes, dtype=float))
        times = np.asarray(self.times, dtype=float)
        accel = np.asarray(self.accel, dtype=float).reshape(len(times) - 1, axes.shape[0])
        if axes.shape[1] != 3 or not 1 <= axes.shape[0] <= 3:
            raise ValueError("axes must have shape (A, 3) with 1 <= A <= 3")
        if not np.allclose(np.linalg.norm(axes, axis=1), 1.0):
            raise ValueError("gimbal axes must be unit vectors")
        if times.ndim != 1 or len(times) < 1 or np.any(np.diff(times) <= 0):
            raise ValueError("breakpoint times must be strictly increasing")
        for name, value in (("times", times), ("accel", accel)):
            if not np.isfinite(value).all():
                raise ValueError(f"schedule {name} contains NaN or infinity")
        object.__setattr__(self, "axes", axes)
        object.__setattr__(self, "times", times)
        object.__setattr__(self, "accel", accel)
        object.__setattr__(self, "angle0", np.broadcast_to(np.asarray(self.angle0, float), (axes.shape[0],)).copy())
        object.__setattr__(self, "rate0", np.broadcast_to(np.asarray(self.rate0, float), (axes.shape[0],)).copy())
        dt = np.diff(times)[:, None]
        rate_bp = self.rate0 + np.concatenate([np.zeros((1, axes.shape[0])), np.cumsum(accel * dt, axis=0)])
        d_angle = rate_bp[:-1] * dt + 0.5 * accel * dt**2
        angle_bp = self.angle0 + np.concatenate([np.zeros((1, axes.shape[0])), np.cumsum(d_angle, axis=0)])
        object.__setattr__(self, "_rate_bp", rate_bp)
        object.__setattr__(self, "_angle_bp", angle_bp)

    @property
    def n_axes(self) -> int:
        return self.axes.shape[0]

    @property
    def end_time(self) -> float:
        return float(self.times[-1])

    def state(self, time):
        """Angles, rates and accelerations at ``time`` (scalar or (K,)), s.

        The acceleration returned is the one that holds on [time, next
        breakpoint), so the motion over a step starting at ``time`` is
        angle + rate*tau + accel*tau^2/2.

        Returns
        -------
        angle, rate, accel : ndarray (K, A)
        """
        t = np.atleast_1d(np.asarray(time, dtype=float))
        if not np.isfinite(t).all():
            raise ValueError("time must be finite")
        return _state_kernel(t, self.times, self._angle_bp, self._rate_bp, self.accel, self.angle0, self.rate0)

    def check_grid(self, step: float, start: float = 0.0, tol: float = 1e-9) -> None:
        """Raise ValueError unless every breakpoint lies on start + n*step."""
        if not (step > 0 and math.isfinite(step)):
            raise ValueError(f"step must be positive and finite, got {step}")
        n = (self.times - start) / step
        bad = np.abs(n - np.round(n)) > tol * np.maximum(1.0, np.abs(n))
        if np.any(bad):
            t_bad = self.times[np.argmax(bad)]
            raise ValueError(
                f"turntable breakpoint at t={t_bad:.9g} s is not on the output grid of step {step} s: "
                "the IMU cannot rebuild the motion inside a step exactly")


@jit
def _state_kernel(t, times, angle_bp, rate_bp, accel, angle0, rate0):
    """Exact gimbal state at times t (see GimbalSchedule.state)."""
    n, n_axes = t.shape[0], angle_bp.shape[1]
    last = times.shape[0] - 1
    angle = np.empty((n, n_axes))
    rate = np.empty((n, n_axes))
    acc = np.zeros((n, n_axes))
    seg = np.searchsorted(times, t, side="right") - 1
    for k in range(n):
        if seg[k] < 0:  # before the schedule: hold the initial state
            for j in range(n_axes):
                rate[k, j] = rate0[j]
                angle[k, j] = angle0[j] + rate0[j] * (t[k] - times[0])
            continue
        s = seg[k]
        tau = t[k] - times[s]
        for j in range(n_axes):
            a = accel[s, j] if s < last else 0.0
            acc[k, j] = a
            rate[k, j] = rate_bp[s, j] + a * tau
            angle[k, j] = angle_bp[s, j] + rate_bp[s, j] * tau + 0.5 * a * tau * tau
    return angle, rate, acc


# --------------------------------------------------------------------------
# building blocks: segments are (duration, accel (A,)) pairs on a time grid
# --------------------------------------------------------------------------

def _ceil_to_grid(duration: float, grid: float) -> float:
    return max(1, math.ceil(duration / grid - 1e-9)) * grid


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
    t_acc = _ceil_to_grid(rate_max / accel_max, grid)
    if rate_max * t_acc >= angle:  # triangular profile: no cruise phase
        t_acc = _ceil_to_grid(math.sqrt(angle / accel_max), grid)
        t_cruise = 0.0
    else:
        t_cruise = _ceil_to_grid(angle / rate_max - t_acc, grid)
    rate = angle / (t_acc + t_cruise)  # area of the trapezoid equals the angle
    acc = rate / t_acc
    segs = [(t_acc, sign * acc)]
    if t_cruise > 0:
        segs.append((t_cruise, 0.0))
    segs.append((t_acc, -sign * acc))
    return segs


def _schedule_from_segments(axes, segs, t0=0.0, angle0=None, rate0=None):
    """Build a GimbalSchedule from [(duration, accel (A,)), ...]."""
    axes = np.atleast_2d(np.asarray(axes, float))
    n_axes = axes.shape[0]
    durations = np.array([d for d, _ in segs], dtype=float)
    accel = np.array([np.broadcast_to(a, (n_axes,)) for _, a in segs], dtype=float).reshape(-1, n_axes)
    times = t0 + np.concatenate([[0.0], np.cumsum(durations)])
    zeros = np.zeros(n_axes)
    return GimbalSchedule(axes, times, accel,
                          zeros if angle0 is None else angle0, zeros if rate0 is None else rate0)


def _single_axis_segments(scheme, duration, rate, acc, dwell, grid, revolutions=1):
    """Segments (duration, accel) of a single-axis scheme covering ``duration``.

    'continuous' is one acceleration segment (the rate then holds for ever);
    the others repeat their cycle until ``duration`` is covered.
    """
    if scheme == "none":
        return [(_ceil_to_grid(duration, grid), 0.0)]
    if rate <= 0 or acc <= 0:
        raise ValueError("rate_dps and accel_dps2 must be positive for a rotating scheme")
    if scheme == "continuous":
        t_acc = _ceil_to_grid(rate / acc, grid)
        return [(t_acc, rate / t_acc)]
    dwell = _ceil_to_grid(dwell, grid) if dwell > 0 else 0.0
    if scheme == "forward-reverse":
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


def _check_positive(**values):
    for name, value in values.items():
        if not math.isfinite(value) or value < 0 or (value == 0 and name in ("grid", "duration")):
            raise ValueError(f"{name} must be a positive finite number, got {value}")


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
    _check_positive(duration=duration, rate_dps=rate_dps, accel_dps2=accel_dps2, dwell=dwell, grid=grid,
                    align_time=align_time, align_dwell=align_dwell)
    rate, acc = rate_dps * DEG_TO_RAD, accel_dps2 * DEG_TO_RAD
    segs = []
    if align_time > 0:
        t_align = round(align_time / grid) * grid
        moves = [math.pi, -0.5 * math.pi, math.pi, -1.5 * math.pi]
        dwell_align = _ceil_to_grid(align_dwell, grid) if align_dwell > 0 else 0.0
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
    return _schedule_from_segments([AXIS_Z], segs)
