"""The gimbal-chain motion truth: :class:`GimbalSchedule` and its rotation matrices.

See the package docstring (:mod:`sarins_fmu.turntable`) for the chain convention.
Angles rad, rates rad/s, accelerations rad/s^2, times s.
"""

from __future__ import annotations

import ctypes
import math
from dataclasses import dataclass

import numpy as np

from ..core._arrays import read, written
from ..core._lib import function
from ..core.schedule import integrate

AXIS_X = (1.0, 0.0, 0.0)
AXIS_Y = (0.0, 1.0, 0.0)
AXIS_Z = (0.0, 0.0, 1.0)
MAX_GIMBALS = 6  # a vehicle's three attitude gimbals and a table's three


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
        if axes.shape[1] != 3 or not 1 <= axes.shape[0] <= MAX_GIMBALS:
            raise ValueError(f"axes must have shape (A, 3) with 1 <= A <= {MAX_GIMBALS}")
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
        angle_bp, rate_bp = integrate(times, accel, self.angle0, self.rate0)
        object.__setattr__(self, "_rate_bp", rate_bp)
        object.__setattr__(self, "_angle_bp", angle_bp)

    @classmethod
    def from_breakpoints(cls, axes, times, angle_bp, rate_bp, accel) -> "GimbalSchedule":
        """A schedule whose breakpoint states are given (M+1, A) rather than integrated from ``accel`` (M, A):
        a motion generated step by step elsewhere (the C vehicle), so that :meth:`state` at a breakpoint
        returns exactly the generator's values.  ``angle_bp``/``rate_bp`` must be that motion's states."""
        angle_bp, rate_bp = (np.array(a, dtype=float, order="C", ndmin=2) for a in (angle_bp, rate_bp))
        schedule = cls(axes, times, accel, angle_bp[0], rate_bp[0])
        if angle_bp.shape != schedule._angle_bp.shape or rate_bp.shape != schedule._rate_bp.shape:
            raise ValueError(f"breakpoint states must have shape {schedule._angle_bp.shape}")
        if not (np.isfinite(angle_bp).all() and np.isfinite(rate_bp).all()):
            raise ValueError("breakpoint states contain NaN or infinity")
        object.__setattr__(schedule, "_angle_bp", angle_bp)
        object.__setattr__(schedule, "_rate_bp", rate_bp)
        return schedule

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

    def tables(self) -> tuple:
        """(times, angle_bp, rate_bp, accel, angle0, rate0): the arrays :func:`state_into` reads."""
        return self.times, self._angle_bp, self._rate_bp, self.accel, self.angle0, self.rate0

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


_state = function("sarins_turntable_state", None, ctypes.c_int64, ctypes.c_void_p, ctypes.c_int64, ctypes.c_int64,
                  *([ctypes.c_void_p] * 9))


def _state_kernel(t, times, angle_bp, rate_bp, accel, angle0, rate0):
    """Exact gimbal state at times t (see GimbalSchedule.state): (angle, rate, acc), each (K, A)."""
    n, n_axes = t.shape[0], angle_bp.shape[1]
    angle = np.empty((n, n_axes))
    rate = np.empty((n, n_axes))
    acc = np.empty((n, n_axes))
    state_into(t, times, angle_bp, rate_bp, accel, angle0, rate0, angle, rate, acc)
    return angle, rate, acc


def state_into(t, times, angle_bp, rate_bp, accel, angle0, rate0, angle, rate, acc):
    """:meth:`GimbalSchedule.state` at times t (K,) written to angle, rate, acc (K, A) (C-contiguous float64);
    the schedule's arrays are its breakpoint tables (:meth:`GimbalSchedule.tables`).  The C core's
    ``sarins_turntable_state`` (``sarins_fmu/core/turntable.h``)."""
    t = read(t, np.shape(t)[:1], "t")
    times = read(times, np.shape(times)[:1], "times")
    n_times, n_axes = times.shape[0], np.shape(angle_bp)[1]
    tables = [read(a, shape, name) for name, a, shape in (
        ("angle_bp", angle_bp, (n_times, n_axes)), ("rate_bp", rate_bp, (n_times, n_axes)),
        ("accel", accel, (n_times - 1, n_axes)), ("angle0", angle0, (n_axes,)), ("rate0", rate0, (n_axes,)))]
    outs = [written(a, (t.shape[0], n_axes), name).ctypes.data
            for name, a in (("angle", angle), ("rate", rate), ("acc", acc))]
    _state(t.shape[0], t.ctypes.data, n_times, n_axes, times.ctypes.data, *(a.ctypes.data for a in tables), *outs)


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
