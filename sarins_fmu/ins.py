"""Strapdown INS in ENU: coarse alignment, Kalman fine alignment, navigation.

The :class:`StrapdownINS` consumes the IMU's compensated increments one
major-loop step (``h`` seconds) at a time, or many at once, and runs three
phases on the static base it starts on:

1. **coarse alignment** (``coarse_time``): analytic alignment in the inertial
   frame, valid on a rotating turntable (the double-vector construction of
   the specific-force integrals in the frozen start frame);
2. **fine alignment** (until ``align_time``): the mechanization runs with the
   position held and a 9-state closed-loop Kalman filter takes the computed
   velocity as the measurement of the velocity error (zero-velocity update),
   estimating the attitude errors, the horizontal gyro drifts and
   accelerometer biases;
3. **navigation**: free inertial navigation from the known start position
   with zero velocity, the alignment's drift and bias estimates compensated,
   and an optional axial (z) drift correction subtracted from a given time on.

The physics is the C core's ``sarins_ins`` (``sarins_fmu/core/ins.h`` states
the equations, units and frames); this class is its Python face, and the
StrapdownINS FMU steps the same struct.

Units: rad, rad/s, m, m/s, s.  Position errors are with respect to the known
static start (the truth on a static base).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .core import ins as core_ins
from .ins_kernel import held_row
from .rotations import quat_to_mat
from .units import DEG_TO_RAD, DPH_TO_RPS, DPSH_TO_RPSS, UG_TO_MPS2

OUTPUT_COLUMNS = ("lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll")


@dataclass(frozen=True)
class AlignmentFilter:
    """Settings of the fine-alignment Kalman filter (SI units).

    Process noise densities follow the IMU class (ARW, VRW); the drift and
    bias states get a small random walk so the filter keeps tracking slow
    variations.  Initial standard deviations describe the coarse alignment.
    """

    arw: float = 0.0005 * DPSH_TO_RPSS  # rad/sqrt(s)
    vrw: float = 5.0 * UG_TO_MPS2  # m/s/sqrt(s)
    drift_rw: float = 1e-5 * DPH_TO_RPS / 60.0  # rad/s/sqrt(s)
    bias_rw: float = 0.01 * UG_TO_MPS2  # m/s^2/sqrt(s)
    velocity_meas_std: float = 1e-3  # m/s
    tilt0_std: float = 0.01 * DEG_TO_RAD
    heading0_std: float = 1.0 * DEG_TO_RAD
    velocity0_std: float = 0.05
    drift0_std: float = 0.01 * DPH_TO_RPS
    bias0_std: float = 100.0 * UG_TO_MPS2

    def __post_init__(self):
        for name, value in self.__dict__.items():
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"alignment filter {name} must be positive and finite, got {value}")


@dataclass(frozen=True)
class InsConfig:
    """Initial position and phase durations of the INS.

    lat, lon (rad), height (m): the known static start; align_time and
    coarse_time (s); step (s) the major-loop interval.
    """

    lat: float
    lon: float = 0.0
    height: float = 0.0
    align_time: float = 4 * 3600.0
    coarse_time: float = 300.0
    step: float = 1.0
    filter: AlignmentFilter = AlignmentFilter()

    def __post_init__(self):
        problem = core_ins.config_problem(core_ins.config_array(self))
        if problem is not None:
            raise ValueError(problem)


class StrapdownINS:
    """Two-speed strapdown INS stepping on increments.

    Parameters
    ----------
    config : InsConfig
    initial_attitude : (3, 3) mat_nb, optional
        When given and ``config.align_time`` is 0, navigation starts at once
        from this attitude (an exactly aligned start for closed-form tests).
    """

    def __init__(self, config: InsConfig, initial_attitude=None):
        self.config = config
        self._state = core_ins.InsState(core_ins.config_array(config), initial_attitude)
        st = self._state
        self.q, self.v, self.pos, self.gyro_comp, self.accel_comp = st.q, st.v, st.pos, st.gyro_comp, st.accel_comp
        self.x, self.p, self.q_diag = st.x, st.p, st.q_diag
        # diagonal of P after each fine-alignment step (filled as the steps are made)
        self.p_history = np.full((max(st.n_align - st.n_coarse, 0), 9), np.nan)

    def reset(self) -> None:
        """Return to the initial state."""
        self._state.reset()
        self.p_history[:] = np.nan

    @property
    def phase(self) -> str:
        """'coarse', 'fine' or 'navigate'."""
        return self._state.phase

    def step(self, dtheta, dv, axial_correction=0.0):
        """Advance over K major-loop steps.

        Parameters
        ----------
        dtheta, dv : (K, 3) or (3,) increments, rad and m/s (body frame).
        axial_correction : float or (K,) rad/s subtracted from the z gyro
            (only in the navigation phase).

        Returns
        -------
        (K, 9) array with columns :data:`OUTPUT_COLUMNS`; rows of the
        alignment phases report the held start position, zero velocity and
        the attitude estimate at the end of that phase's rows in this call.
        """
        dtheta = np.ascontiguousarray(np.atleast_2d(dtheta), dtype=float)
        dv = np.ascontiguousarray(np.atleast_2d(dv), dtype=float)
        if dtheta.shape != dv.shape or dtheta.shape[1] != 3:
            raise ValueError("dtheta and dv must both have shape (K, 3)")
        if not (np.isfinite(dtheta).all() and np.isfinite(dv).all()):
            raise ValueError("increments contain NaN or infinity")
        n = dtheta.shape[0]
        corr = np.broadcast_to(np.asarray(axial_correction, float), (n,)).copy()
        if not np.isfinite(corr).all():
            raise ValueError("axial correction contains NaN or infinity")
        st = self._state
        first = st.steps
        out, p_diag = st.steps_run(dtheta, dv, corr)
        # rows of the fine-alignment steps in this call: step numbers n_coarse .. n_align - 1
        lo, hi = max(first, st.n_coarse), min(first + n, st.n_align)
        if hi > lo:
            self.p_history[lo - st.n_coarse:hi - st.n_coarse] = p_diag[lo - first:hi - first]
        return out

    @property
    def steps(self) -> int:
        """Major-loop steps integrated so far."""
        return self._state.steps

    @property
    def time(self) -> float:
        """Time since the start, s (steps x step)."""
        return self.steps * self.config.step

    def attitude_euler(self):
        """(yaw, pitch, roll) in rad of the current mat_nb."""
        return tuple(float(x) for x in held_row(self.q, self.pos)[6:9])

    @property
    def mat_nb(self):
        return quat_to_mat(self.q)

    def position_error(self, out):
        """Errors of output rows wrt the known start: (K, 4) dlat, dlon (rad),
        north and east position errors (m)."""
        return self._state.position_error(out)
