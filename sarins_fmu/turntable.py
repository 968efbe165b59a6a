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


# --------------------------------------------------------------------------
# multi-gimbal profiles: dual-axis RINS (seed 002) and the three-axis rate
# table with thermal chamber (seed 003).  Internally every profile is built on
# whole steps of ``grid`` (integers), so all breakpoints lie exactly on
# start + n * grid.
# --------------------------------------------------------------------------

# dual-axis RINS (seed 002, Fig. 1): outer frame about the base's roll axis
# (y, front), inner frame about the outer frame's azimuth axis (z, up at
# outer angle 0):  mat_tb = Ry(theta_outer) Rz(theta_inner)
DUAL_AXIS_AXES = (AXIS_Y, AXIS_Z)

# three-axis rate table (seed 003, TBL-3302-CT): outer about the base vertical
# z, middle about the outer frame's x, inner about the middle frame's y:
# mat_tb = Rz(theta_outer) Rx(theta_middle) Ry(theta_inner), i.e. the
# yaw-pitch-roll order of :func:`sarins_fmu.rotations.euler_to_mat`
RATE_TABLE_AXES = (AXIS_Z, AXIS_X, AXIS_Y)

# seed 003's rate test: 22 rates within +-200 deg/s; the paper does not list
# them.  Our choice: 11 magnitudes on a 1-2-3-5 pattern (roughly log-spaced,
# 1 and 2 deg/s in the low-rate region of the MEMS preset (nonlinearity
# width 2 deg/s), the range end 200),
# each with both signs.
RATE_TEST_MAGNITUDES_DPS = (1.0, 2.0, 3.0, 5.0, 10.0, 20.0, 30.0, 50.0, 100.0, 150.0, 200.0)

# body axis pointing up on the three-axis chain, as (middle, inner) angles in
# quarter turns: Rx(m) Ry(i) e_axis = +-z
_UP_QUARTERS = {"+z": (0, 0), "-z": (0, 2), "+x": (0, -1), "-x": (0, 1), "+y": (1, 0), "-y": (-1, 0)}

TUMBLE_DTYPE = np.dtype([("start", float), ("end", float), ("up", "U2"), ("heading", float),
                         ("angles", float, (3,)), ("up_b", float, (3,))])
RATE_WINDOW_DTYPE = np.dtype([("start", float), ("end", float), ("axis", "U2"), ("rate", float),
                              ("rate_nominal", float), ("revolutions", int), ("up_b", float, (3,)),
                              ("rate_b", float, (3,))])


def _number(name: str, value, *, positive: bool = False) -> float:
    """``value`` as a finite float, >= 0 (or > 0 if ``positive``), else ValueError."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {v}")
    if v < 0 or (positive and v == 0):
        raise ValueError(f"{name} must be {'positive' if positive else 'non-negative'}, got {v}")
    return v


def _ceil_steps(duration: float, grid: float) -> int:
    """Whole grid steps covering ``duration`` (0 for 0)."""
    return max(0, math.ceil(duration / grid - 1e-9))


def _move_steps(angle: float, rate: float, accel: float, grid: float):
    """:func:`move_segments` as [(steps, accel)] with integer grid steps."""
    return [(int(round(d / grid)), float(a)) for d, a in move_segments(angle, rate, accel, grid)]


def axis_rotation(axis, angle: float) -> np.ndarray:
    """R(a, theta) = exp(theta [a x]) for a unit vector ``axis`` (3,), rad."""
    a = np.asarray(axis, float)
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)


def chain_matrix(axes, angles) -> np.ndarray:
    """mat_tb = R(axes[0], angles[0]) ... R(axes[A-1], angles[A-1]) of a gimbal chain.

    Parameters
    ----------
    axes : array_like (A, 3)
        Unit gimbal axes, outer first (as :attr:`GimbalSchedule.axes`).
    angles : array_like (A,)
        Gimbal angles, rad.

    Returns
    -------
    ndarray (3, 3)
        Projects the body frame b onto the base frame t.
    """
    mat = np.eye(3)
    for a, th in zip(np.atleast_2d(np.asarray(axes, float)), np.asarray(angles, float).ravel()):
        mat = mat @ axis_rotation(a, th)
    return mat


class _Timeline:
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


def _indexing_track(n_align: int, rate: float, acc: float, dwell_steps: int, grid: float):
    """Four-position indexing (+180, -90, +180, -270 deg moves, each followed by
    a dwell) filling ``n_align`` grid steps with whole moves, padded with rest."""
    moves = [math.pi, -0.5 * math.pi, math.pi, -1.5 * math.pi]
    track, used, k = [], 0, 0
    while n_align > 0:
        unit = _move_steps(moves[k % 4], rate, acc, grid) + ([(dwell_steps, 0.0)] if dwell_steps else [])
        length = sum(n for n, _ in unit)
        if used + length > n_align:
            break
        track += unit
        used += length
        k += 1
    if n_align > used:
        track.append((n_align - used, 0.0))
    return track


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
    duration = _number("duration", duration, positive=True)
    grid = _number("grid", grid, positive=True)
    rate_in = _number("inner_rate_dps", inner_rate_dps, positive=True) * DEG_TO_RAD
    acc_in = _number("inner_accel_dps2", inner_accel_dps2, positive=True) * DEG_TO_RAD
    rate_out = _number("outer_rate_dps", outer_rate_dps, positive=True) * DEG_TO_RAD
    acc_out = _number("outer_accel_dps2", outer_accel_dps2, positive=True) * DEG_TO_RAD
    n_dwell = _ceil_steps(_number("dwell", dwell), grid)
    align_time = _number("align_time", align_time)
    n_align_dwell = _ceil_steps(_number("align_dwell", align_dwell), grid)
    OUTER, INNER = 0, 1
    tl = _Timeline(2)
    if align_time > 0:
        tl.parallel({INNER: _indexing_track(round(align_time / grid), rate_in, acc_in, n_align_dwell, grid)})
    n_end = _ceil_steps(duration, grid)
    while True:
        for flip in (math.pi, -math.pi):
            for turn in (2 * math.pi, -2 * math.pi):
                tl.parallel({INNER: _move_steps(turn, rate_in, acc_in, grid)})
                tl.rest(n_dwell)
            tl.parallel({OUTER: _move_steps(flip, rate_out, acc_out, grid)})
            tl.rest(n_dwell)
        if tl.now >= n_end:
            break
    return tl.schedule(DUAL_AXIS_AXES, grid)


def rate_table_3axis(duration: float, *, inner_rate_dps: float = 1.0, inner_accel_dps2: float = 0.01,
                     middle_rate_dps: float = 10.0, middle_accel_dps2: float = 0.1,
                     outer_rate_dps: float = 100.0, outer_accel_dps2: float = 1.0, grid: float = 1.0,
                     warmup: float = 600.0) -> GimbalSchedule:
    """Seed 003's dynamic-calibration profile on a three-axis rate table.

    Gimbal 0 (outer) turns about the base vertical z, gimbal 1 (middle) about
    the outer frame's x, gimbal 2 (inner) about the middle frame's y, and the
    inner frame carries the IMU::

        mat_tb = Rz(theta_outer) Rx(theta_middle) Ry(theta_inner)   (axes :data:`RATE_TABLE_AXES`)

    After a static warm-up (seed 003: the MIMU is powered and warmed up for
    10 min), all three gimbals move at once, each sweeping its rate as a
    triangle wave between -max and +max at constant |acceleration| (seed 003:
    inner 0.01 deg/s^2 between +-1 deg/s, middle 0.1 deg/s^2 between +-10
    deg/s, outer 1 deg/s^2 between +-100 deg/s, repeated).  One period of
    gimbal j, with T_q = max_j / accel_j rounded up to ``grid``::

        accel +max/T_q for T_q, -max/T_q for 2 T_q, +max/T_q for T_q

    so the rate goes 0 -> +max -> -max -> 0 and the angle returns to its
    start (excursion max * T_q, i.e. 100 deg inner, 1000 deg middle, 10000 deg
    outer with the paper's values).  The peak rates are kept exactly; the
    acceleration is lowered (never raised) when max/accel is not a whole
    number of grid steps.  Each gimbal repeats whole periods until the end of
    the schedule covers ``duration``, then rests.  With the paper's values all
    three periods are 400 s, so the gimbals stay in phase.  The chamber
    temperature runs at the same time: see :func:`chamber_profile`.

    Parameters
    ----------
    duration : float
        Length the schedule must cover, warm-up included, s.
    inner_rate_dps, middle_rate_dps, outer_rate_dps : float
        Rate amplitude of each gimbal, deg/s, >= 0 (0 keeps that gimbal still).
    inner_accel_dps2, middle_accel_dps2, outer_accel_dps2 : float
        Magnitude of each gimbal's angular acceleration, deg/s^2, > 0.
    grid : float
        Time grid on which the acceleration may change, s, > 0.
    warmup : float
        Static warm-up at the start, s (rounded up to ``grid``), >= 0.

    Returns
    -------
    GimbalSchedule
        Three gimbals (outer, middle, inner), at rest at angle 0 at t = 0.

    Raises
    ------
    ValueError
        On NaN or infinite input, negative rates or warm-up, or a
        non-positive duration, acceleration or grid.
    """
    duration = _number("duration", duration, positive=True)
    grid = _number("grid", grid, positive=True)
    n_warm = _ceil_steps(_number("warmup", warmup), grid)
    gimbals = ((outer_rate_dps, outer_accel_dps2, "outer"), (middle_rate_dps, middle_accel_dps2, "middle"),
               (inner_rate_dps, inner_accel_dps2, "inner"))
    n_motion = max(_ceil_steps(duration, grid) - n_warm, 1)
    tracks = {}
    for j, (rate_dps, accel_dps2, name) in enumerate(gimbals):
        rate = _number(f"{name}_rate_dps", rate_dps) * DEG_TO_RAD
        acc = _number(f"{name}_accel_dps2", accel_dps2, positive=True) * DEG_TO_RAD
        if rate == 0.0:
            continue
        q = max(1, _ceil_steps(rate / acc, grid))  # quarter period, grid steps
        a = rate / (q * grid)
        tracks[j] = [(q, a), (2 * q, -a), (q, a)] * math.ceil(n_motion / (4 * q))
    tl = _Timeline(3)
    tl.rest(n_warm)
    tl.parallel(tracks)
    if tl.now < _ceil_steps(duration, grid):  # every gimbal still (all rates 0)
        tl.rest(_ceil_steps(duration, grid) - tl.now)
    return tl.schedule(RATE_TABLE_AXES, grid)


def chamber_profile(duration: float, *, low_c: float = -25.0, high_c: float = 40.0,
                    ramp_c_per_min: float = 1.0, hold_min: float = 30.0, start_c: float = 20.0,
                    delay: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Thermal-chamber temperature of seed 003's dynamic calibration.

    Seed 003 states only that the chamber is driven between -25 and 40 degC
    while the table turns, repeatedly; it gives no ramp rate or hold time, so
    ``ramp_c_per_min`` = 1 degC/min and ``hold_min`` = 30 min are our choice.
    The profile is piecewise linear::

        start_c for ``delay`` s, ramp to low_c, hold, ramp to high_c, hold,
        ramp to low_c, hold, ... (cold end first)

    cut at ``duration`` (the last value interpolated).  With the defaults one
    cycle low -> high -> low takes 2 * 65 min + 2 * 30 min = 190 min.

    Parameters
    ----------
    duration : float
        Length to cover, s, > 0.
    low_c, high_c : float
        Cold and hot set points, degC, low_c < high_c.
    ramp_c_per_min : float
        Magnitude of the temperature ramp, degC/min, > 0.
    hold_min : float
        Hold at each set point, min, >= 0.
    start_c : float
        Temperature at t = 0, degC.
    delay : float
        Hold at ``start_c`` before the first ramp, s, >= 0 (e.g. the
        warm-up of :func:`rate_table_3axis`).

    Returns
    -------
    times_s : ndarray (N,)
        Breakpoints, s, strictly increasing from 0 to ``duration``.
    temps_c : ndarray (N,)
        Chamber temperature at each breakpoint, degC; pass
        ``profile=(times_s, temps_c)`` to :class:`sarins_fmu.thermal.Ambient`
        (linear interpolation between breakpoints).

    Raises
    ------
    ValueError
        On NaN, a non-positive duration or ramp, a negative hold or delay, or
        low_c >= high_c.
    """
    duration = _number("duration", duration, positive=True)
    ramp = _number("ramp_c_per_min", ramp_c_per_min, positive=True) / 60.0  # degC/s
    hold = _number("hold_min", hold_min) * 60.0  # s
    delay = _number("delay", delay)
    for name, value in (("low_c", low_c), ("high_c", high_c), ("start_c", start_c)):
        if not math.isfinite(float(value)):
            raise ValueError(f"{name} must be finite, got {value}")
    low_c, high_c, start_c = float(low_c), float(high_c), float(start_c)
    if not low_c < high_c:
        raise ValueError(f"low_c must be below high_c, got {low_c} and {high_c}")
    if low_c <= -273.15:
        raise ValueError(f"low_c must be above absolute zero, got {low_c}")
    times, temps = [0.0], [start_c]

    def to(t_next, temp):
        if t_next > times[-1]:
            times.append(t_next)
            temps.append(temp)

    to(delay, start_c)
    target = low_c
    while times[-1] < duration:
        to(times[-1] + abs(target - temps[-1]) / ramp, target)
        to(times[-1] + hold, target)
        target = high_c if target == low_c else low_c
    times, temps = np.array(times), np.array(temps)
    keep = times < duration
    t_out = np.append(times[keep], duration)
    return t_out, np.append(temps[keep], np.interp(duration, times, temps))


def _up_vector_b(angles) -> np.ndarray:
    """Base up (t-frame z) resolved in b on the three-axis chain, rounded to the exact +-1/0 it nominally is."""
    return np.round(chain_matrix(RATE_TABLE_AXES, angles).T @ np.array(AXIS_Z)) + 0.0


def tumble_24(*, dwell: float = 180.0, rate_dps: float = 10.0, accel_dps2: float = 10.0,
              grid: float = 1.0) -> tuple[GimbalSchedule, np.ndarray]:
    """Seed 003's 24-position static tumble on the three-axis rate table.

    The chain is that of :func:`rate_table_3axis` (outer about base z, middle
    about outer x, inner about middle y).  Each body axis is pointed up and
    down (6 orientations) at 4 headings (outer angle 0, 90, 180, 270 deg),
    with a ``dwell`` s static stop at each position (seed 003: 3 min of data
    per position).  The orientations are set with one gimbal each, as
    (middle, inner) angles in deg::

        +z (0, 0), +x (0, -90), -z (0, -180), -x (0, -270), +y (90, -270), -y (-90, -270)

    visited in this order, so every change of orientation is a single
    rest-to-rest move of the middle or the inner gimbal (-90, -90, -90, +90,
    -180 deg).  The headings are visited 0, 90, 180, 270 for the 1st, 3rd and
    5th orientation and 270, 180, 90, 0 for the others, so the outer gimbal
    only moves by 90 deg within an orientation and stays put when the
    orientation changes.  The schedule starts at rest at angle 0 (+z up,
    heading 0) with the first dwell at t = 0; only the gimbals that must
    change move.

    Parameters
    ----------
    dwell : float
        Static time at each position, s (rounded up to ``grid``), > 0.
    rate_dps, accel_dps2 : float
        Peak rate (deg/s) and acceleration (deg/s^2) of the moves, > 0.
    grid : float
        Time grid on which the acceleration may change, s, > 0.

    Returns
    -------
    schedule : GimbalSchedule
        Three gimbals (outer, middle, inner).
    positions : ndarray (24,) of :data:`TUMBLE_DTYPE`
        One row per dwell window: ``start``, ``end`` (s, on the grid; the
        table is at rest on [start, end]), ``up`` (the body axis pointing up,
        '+x' ... '-z'), ``heading`` (outer angle mod 2 pi, rad, positive
        counter-clockwise seen from above), ``angles`` (nominal gimbal angles,
        rad, as the schedule holds them), ``up_b`` (base up resolved in the
        body frame: a static accelerometer triad reads g * up_b).

    Raises
    ------
    ValueError
        On NaN or infinite input, or a non-positive dwell, rate, acceleration
        or grid.
    """
    grid = _number("grid", grid, positive=True)
    n_dwell = _ceil_steps(_number("dwell", dwell, positive=True), grid)
    rate = _number("rate_dps", rate_dps, positive=True) * DEG_TO_RAD
    acc = _number("accel_dps2", accel_dps2, positive=True) * DEG_TO_RAD
    orientations = (("+z", 0, 0), ("+x", 0, -1), ("-z", 0, -2), ("-x", 0, -3), ("+y", 1, -3), ("-y", -1, -3))
    quarter = 0.5 * math.pi
    tl = _Timeline(3)
    q = [0, 0, 0]  # current gimbal angles in quarter turns: outer, middle, inner
    rows = []
    for i, (up, q_mid, q_in) in enumerate(orientations):
        tl.parallel({j: _move_steps((target - q[j]) * quarter, rate, acc, grid)
                     for j, target in ((1, q_mid), (2, q_in)) if target != q[j]})
        q[1], q[2] = q_mid, q_in
        for heading in ((0, 1, 2, 3) if i % 2 == 0 else (3, 2, 1, 0)):
            if heading != q[0]:
                tl.parallel({0: _move_steps((heading - q[0]) * quarter, rate, acc, grid)})
                q[0] = heading
            start = tl.now
            tl.rest(n_dwell)
            angles = np.array(q, float) * quarter
            rows.append((start * grid, tl.now * grid, up, (q[0] % 4) * quarter, angles, _up_vector_b(angles)))
    return tl.schedule(RATE_TABLE_AXES, grid), np.array(rows, dtype=TUMBLE_DTYPE)


def _whole_revolutions(rate: float, grid: float, min_duration: float, rate_tol: float):
    """Smallest k revolutions in n grid steps, 2 pi k / (n grid) within rate_tol of |rate|.

    Returns (k, n).  k is at least 1 and at least ``min_duration`` worth of
    revolutions; n * grid >= min_duration.
    """
    steps_per_rev = 2 * math.pi / (abs(rate) * grid)
    k_min = max(1, math.ceil(min_duration * abs(rate) / (2 * math.pi) - 1e-9))
    ks = np.arange(k_min, k_min + 100_000)
    ns = np.maximum(np.rint(ks * steps_per_rev), 1.0)
    ok = (np.abs(ks * steps_per_rev / ns - 1.0) <= rate_tol) & (ns * grid >= min_duration - 1e-9)
    if not np.any(ok):
        raise ValueError(f"cannot fit whole revolutions at {abs(rate) / DEG_TO_RAD:.9g} deg/s on a {grid} s grid "
                         f"within a relative rate change of {rate_tol}; use a finer grid or a larger rate_tol")
    i = int(np.argmax(ok))
    return int(ks[i]), int(ns[i])


def rate_test(*, rates_dps=None, axis_up=("x", "y", "z"), min_duration: float | None = None,
              accel_dps2: float = 10.0, grid: float = 1.0, position_rate_dps: float = 10.0,
              settle: float = 0.0, rate_tol: float = 1e-3) -> tuple[GimbalSchedule, np.ndarray]:
    """Seed 003's rate test on the three-axis rate table.

    The chain is that of :func:`rate_table_3axis`.  For each entry of
    ``axis_up`` in turn, the middle and inner gimbals point that body axis up
    (moving together, rest to rest, at ``position_rate_dps``), as (middle,
    inner) angles in deg::

        +z (0, 0), -z (0, 180), +x (0, -90), -x (0, 90), +y (90, 0), -y (-90, 0)

    then the outer (vertical) gimbal turns at each rate of ``rates_dps``:
    from rest it accelerates to the rate, holds it for ``settle`` s and then
    for the measurement window of k whole revolutions, and decelerates to
    rest; the acceleration and deceleration lie outside the window.  Seed
    003 takes "whole-revolution data at 22 rate points within +-200 deg/s"
    per axis but does not list them; the default here is our choice,
    +-:data:`RATE_TEST_MAGNITUDES_DPS` (1, 2, 3, 5, 10, 20, 30, 50, 100, 150,
    200 deg/s, each positive then negative, ascending magnitude).

    So that each window starts and ends on the grid (the IMU's output
    instants) and spans whole revolutions exactly, the table rate is set to
    2 pi k / (n grid) with the smallest k (revolutions) and an integer n
    (grid steps) within ``rate_tol`` of the nominal rate; on a 1 s grid every
    default rate is met exactly (k <= 5).  The window reports the rate
    actually used.

    Parameters
    ----------
    rates_dps : sequence of float, optional
        Nominal table rates, deg/s, non-zero; the sign is the sense about the
        base up axis (counter-clockwise seen from above positive).
    axis_up : sequence of {'x', 'y', 'z', '+x', ..., '-z'}
        Body axes pointed up in turn ('x' means '+x').
    min_duration : float, optional
        Shortest window, s; by default one revolution.
    accel_dps2 : float
        Angular acceleration of the outer gimbal's spin-up and spin-down and
        of the positioning moves, deg/s^2, > 0 (our choice: seed 003 does not
        give one).
    grid : float
        Time grid on which the acceleration may change, s, > 0.
    position_rate_dps : float
        Peak rate of the positioning moves, deg/s, > 0.
    settle : float
        Constant-rate time before each window, s (rounded up to ``grid``).
    rate_tol : float
        Largest relative change of a rate allowed to fit whole revolutions
        on the grid, in (0, 0.1].

    Returns
    -------
    schedule : GimbalSchedule
        Three gimbals (outer, middle, inner), at rest at angle 0 at t = 0.
    windows : ndarray (len(axis_up) * len(rates_dps),) of :data:`RATE_WINDOW_DTYPE`
        ``start``, ``end`` (s, on the grid), ``axis`` (the body axis up,
        '+x' ...), ``rate`` (outer gimbal rate inside the window, rad/s:
        the rate about the named body axis, relative to the base),
        ``rate_nominal`` (rad/s), ``revolutions`` (k), ``up_b`` (base up in
        b), ``rate_b`` (omega_tb^b = rate * up_b, rad/s; add the Earth rate
        resolved in b for what a gyro triad senses).

    Raises
    ------
    ValueError
        On NaN or infinite input, a zero rate, an unknown axis name, a
        non-positive acceleration, grid or positioning rate, negative
        durations, or rates that do not fit whole revolutions on the grid.
    """
    grid = _number("grid", grid, positive=True)
    acc = _number("accel_dps2", accel_dps2, positive=True) * DEG_TO_RAD
    pos_rate = _number("position_rate_dps", position_rate_dps, positive=True) * DEG_TO_RAD
    n_settle = _ceil_steps(_number("settle", settle), grid)
    min_duration = 0.0 if min_duration is None else _number("min_duration", min_duration)
    rate_tol = _number("rate_tol", rate_tol, positive=True)
    if rate_tol > 0.1:
        raise ValueError(f"rate_tol must be at most 0.1, got {rate_tol}")
    if rates_dps is None:
        rates_dps = [s * m for m in RATE_TEST_MAGNITUDES_DPS for s in (1.0, -1.0)]
    rates = []
    for r in np.atleast_1d(np.asarray(rates_dps, dtype=object)).tolist():
        try:
            r = float(r)
        except (TypeError, ValueError):
            raise ValueError(f"rates_dps must be numbers, got {r!r}") from None
        if not math.isfinite(r) or r == 0:
            raise ValueError(f"rates_dps must be finite and non-zero, got {r}")
        rates.append(r * DEG_TO_RAD)
    if not rates:
        raise ValueError("rates_dps must not be empty")
    if isinstance(axis_up, str):
        axis_up = (axis_up,)
    axes = []
    for name in axis_up:
        key = str(name).strip().lower()
        key = key if key[:1] in "+-" else "+" + key
        if key not in _UP_QUARTERS:
            raise ValueError(f"unknown body axis {name!r} in axis_up; choose from x, y, z, +x, ..., -z")
        axes.append(key)
    if not axes:
        raise ValueError("axis_up must name at least one body axis")
    fits = [_whole_revolutions(w, grid, min_duration, rate_tol) for w in rates]
    quarter = 0.5 * math.pi
    tl = _Timeline(3)
    q_mid, q_in = 0, 0
    rows = []
    for key in axes:
        target_mid, target_in = _UP_QUARTERS[key]
        tl.parallel({j: _move_steps((target - now) * quarter, pos_rate, acc, grid)
                     for j, target, now in ((1, target_mid, q_mid), (2, target_in, q_in)) if target != now})
        q_mid, q_in = target_mid, target_in
        up_b = _up_vector_b([0.0, q_mid * quarter, q_in * quarter])
        for w_nominal, (k, n) in zip(rates, fits):
            w = math.copysign(2 * math.pi * k / (n * grid), w_nominal)
            q = max(1, _ceil_steps(abs(w) / acc, grid))
            a = w / (q * grid)
            start = tl.now + q + n_settle
            tl.parallel({0: [(q, a), (n_settle + n, 0.0), (q, -a)]})
            rows.append((start * grid, (start + n) * grid, key, w, w_nominal, k, up_b, w * up_b + 0.0))
    return tl.schedule(RATE_TABLE_AXES, grid), np.array(rows, dtype=RATE_WINDOW_DTYPE)


# --------------------------------------------------------------------------
# one entry point for tools that name a scheme (FMU parameters, CLI)
# --------------------------------------------------------------------------

SCHEMES = ROTATION_SCHEMES + ("dual-axis", "rate-table-3axis", "tumble-24", "rate-test")


_GIMBAL_AXES = {"dual-axis": "y,z", "rate-table-3axis": "z,x,y", "tumble-24": "z,x,y", "rate-test": "z,x,y"}


def gimbal_axes_of(scheme: str) -> str:
    """Gimbal chain of a scheme as axis letters, outer first (e.g. 'y,z')."""
    if scheme in ROTATION_SCHEMES:
        return "z"
    try:
        return _GIMBAL_AXES[scheme]
    except KeyError:
        raise ValueError(f"unknown scheme {scheme!r}; known: {', '.join(SCHEMES)}") from None


def schedule_for(scheme: str, duration: float, *, rate_dps: float = 6.0, accel_dps2: float = 6.0,
                 dwell: float = 0.0, revolutions: int = 1, align_time: float = 0.0, align_dwell: float = 300.0,
                 grid: float = 1.0, outer_rate_dps: float = 6.0, outer_accel_dps2: float = 6.0,
                 table_rates_dps=(1.0, 10.0, 100.0), table_accels_dps2=(0.01, 0.1, 1.0),
                 warmup: float = 600.0) -> GimbalSchedule:
    """Schedule of any named scheme (:data:`SCHEMES`).

    Single-axis schemes and 'dual-axis' use ``rate_dps``/``accel_dps2`` for
    the (inner) azimuth gimbal; 'dual-axis' flips the outer gimbal at
    ``outer_rate_dps``/``outer_accel_dps2``; 'rate-table-3axis' sweeps the
    inner, middle and outer gimbals with ``table_rates_dps`` /
    ``table_accels_dps2`` (inner first, seed 003) after ``warmup`` s;
    'tumble-24' (:func:`tumble_24`) stops ``dwell`` s at each position and
    moves at ``rate_dps``/``accel_dps2``; 'rate-test' (:func:`rate_test`,
    default rates, axes x, y, z) spins up at ``accel_dps2``, settles
    ``dwell`` s and positions at ``rate_dps``.
    """
    if scheme not in SCHEMES:
        raise ValueError(f"unknown scheme {scheme!r}; choose one of {', '.join(SCHEMES)}")
    if scheme in ROTATION_SCHEMES:
        return single_axis(scheme, duration, rate_dps=rate_dps, accel_dps2=accel_dps2, dwell=dwell, grid=grid,
                           revolutions=revolutions, align_time=align_time, align_dwell=align_dwell)
    if scheme == "dual-axis":
        return dual_axis(duration, inner_rate_dps=rate_dps, inner_accel_dps2=accel_dps2,
                         outer_rate_dps=outer_rate_dps, outer_accel_dps2=outer_accel_dps2, dwell=dwell,
                         grid=grid, align_time=align_time, align_dwell=align_dwell)
    if scheme == "tumble-24":
        return tumble_24(dwell=dwell, rate_dps=rate_dps, accel_dps2=accel_dps2, grid=grid)[0]
    if scheme == "rate-test":
        return rate_test(accel_dps2=accel_dps2, grid=grid, position_rate_dps=rate_dps, settle=dwell)[0]
    (ri, rm, ro), (ai, am, ao) = table_rates_dps, table_accels_dps2
    return rate_table_3axis(duration, inner_rate_dps=ri, inner_accel_dps2=ai, middle_rate_dps=rm,
                            middle_accel_dps2=am, outer_rate_dps=ro, outer_accel_dps2=ao, grid=grid,
                            warmup=warmup)
