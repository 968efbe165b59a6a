"""Turntable (gimbal) motion truth: rotation schemes and rate-table profiles.

A :class:`GimbalSchedule` describes a chain of one to six gimbals.  Gimbal
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

Modules: :mod:`.schedule` (the schedule and chain matrices), :mod:`.segments`
(rest-to-rest moves and grid timelines), :mod:`.rins` (single- and dual-axis
RINS schemes), :mod:`.rate_table` (seed 003's three-axis rate table),
:mod:`.schemes` (one entry point by scheme name).  The thermal chamber's
temperature profile is :func:`sarins_fmu.thermal.chamber_profile`.
"""

from .rate_table import (RATE_TABLE_AXES, RATE_TEST_MAGNITUDES_DPS, RATE_WINDOW_DTYPE, TUMBLE_DTYPE,
                         rate_table_3axis, rate_test, tumble_24)
from .rins import DUAL_AXIS_AXES, ROTATION_SCHEMES, dual_axis, single_axis
from .schedule import AXIS_X, AXIS_Y, AXIS_Z, GimbalSchedule, axis_rotation, chain_matrix
from .schemes import SCHEMES, gimbal_axes_of, schedule_for
from .segments import move_segments, schedule_from_segments

__all__ = ["AXIS_X", "AXIS_Y", "AXIS_Z", "DUAL_AXIS_AXES", "RATE_TABLE_AXES", "RATE_TEST_MAGNITUDES_DPS",
           "RATE_WINDOW_DTYPE", "ROTATION_SCHEMES", "SCHEMES", "TUMBLE_DTYPE", "GimbalSchedule", "axis_rotation",
           "chain_matrix", "dual_axis", "gimbal_axes_of", "move_segments", "rate_table_3axis", "rate_test",
           "schedule_for", "schedule_from_segments", "single_axis", "tumble_24"]
