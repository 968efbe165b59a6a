"""Strapdown INS in ENU: coarse alignment, Kalman fine alignment, navigation.

The :class:`StrapdownINS` consumes the IMU's compensated increments one
major-loop step (``h`` seconds) at a time, or many at once, and runs three
phases on the static base it starts on:

1. **coarse alignment** (``coarse_time``): analytic alignment in the inertial
   frame, valid on a rotating turntable.  The body attitude relative to the
   initial body frame b0 is integrated from the angle increments and the
   specific force is accumulated in b0, V_b0(t) = int mat_b0b f_b dt.  In the
   frame n0 (the navigation frame at the start, frozen in inertial space) the
   same integral of -gravity is known in closed form; two such vector pairs
   (at T/2 and T) give mat_n0b0 by the double-vector (TRIAD) construction.
2. **fine alignment** (until ``align_time``): the mechanization runs with the
   position held and a 9-state closed-loop Kalman filter (see
   :func:`ins_kernel.align_steps`) takes the computed velocity as the
   measurement of the velocity error (zero-velocity update), estimating the
   attitude errors, the horizontal gyro drifts and accelerometer biases.
3. **navigation**: free inertial navigation from the known start position
   with zero velocity, the alignment's drift and bias estimates compensated,
   and an optional axial (z) drift correction subtracted from a given time on.

Units: rad, rad/s, m, m/s, s.  Position errors are with respect to the known
static start (the truth on a static base).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import earth
from .ins_kernel import align_steps, coarse_steps, held_row, nav_steps
from .rotations import mat_to_quat, quat_to_mat, rotvec_to_quat
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
        for name in ("lat", "lon", "height", "align_time", "coarse_time", "step"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"INS {name} must be finite")
        if abs(self.lat) > 89.9 * DEG_TO_RAD:
            raise ValueError(f"latitude {math.degrees(self.lat):.6g} deg is outside +-89.9 deg")
        if self.step <= 0:
            raise ValueError(f"INS step must be positive, got {self.step}")
        if self.align_time < 0 or self.coarse_time < 0:
            raise ValueError("alignment durations must be non-negative")
        if 0 < self.align_time < self.coarse_time + 2 * self.step:
            raise ValueError("align_time must exceed coarse_time (or be 0 for a given initial attitude)")
        if self.coarse_time > 0 and round(self.coarse_time / self.step) < 2:
            raise ValueError("coarse_time must span at least two steps")


def _gravity_integral_n0(lat, height, t):
    """int_0^t mat_n0n(s) f_n ds for a static point: specific force (0,0,g) seen
    from the start navigation frame frozen in inertial space, (3,) m/s."""
    u = np.array([0.0, math.cos(lat), math.sin(lat)])
    k = np.array([[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]])
    w = earth.RATE
    f = np.array([0.0, 0.0, earth.gravity(lat, height)])
    m = t * np.eye(3) + (1.0 - math.cos(w * t)) / w * k + (t - math.sin(w * t) / w) * (k @ k)
    return m @ f


def _triad(r1, r2, b1, b2):
    """DCM mat_rb with mat_rb b_i ~ r_i (double-vector attitude determination)."""
    def frame(a, b):
        x = a / np.linalg.norm(a)
        y = np.cross(a, b)
        y /= np.linalg.norm(y)
        return np.column_stack([x, y, np.cross(x, y)])

    return frame(r1, r2) @ frame(b1, b2).T


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
        if config.align_time == 0 and initial_attitude is None:
            raise ValueError("align_time = 0 needs an initial attitude")
        self.config = config
        self._initial_attitude = None if initial_attitude is None else np.asarray(initial_attitude, float)
        self.reset()

    def reset(self) -> None:
        """Return to the initial state."""
        c = self.config
        self._count = np.zeros(1)  # major-loop steps done (a compiled step advances it in place)
        self.pos = np.array([c.lat, c.lon, c.height])
        self.v = np.zeros(3)
        self.q = np.array([1.0, 0.0, 0.0, 0.0]) if self._initial_attitude is None else mat_to_quat(self._initial_attitude)
        self.gyro_comp = np.zeros(3)
        self.accel_comp = np.zeros(3)
        fl = c.filter
        self.x = np.zeros(9)
        self.p = np.diag(np.array([fl.tilt0_std, fl.tilt0_std, fl.heading0_std, fl.velocity0_std, fl.velocity0_std,
                                   fl.drift0_std, fl.drift0_std, fl.bias0_std, fl.bias0_std]) ** 2)
        self.q_diag = np.array([fl.arw, fl.arw, fl.arw, fl.vrw, fl.vrw, fl.drift_rw, fl.drift_rw,
                                fl.bias_rw, fl.bias_rw]) ** 2
        # coarse alignment accumulators (body attitude wrt b0, velocity in b0)
        self._q_b0b = np.array([1.0, 0.0, 0.0, 0.0])
        self._v_b0 = np.zeros(3)
        self._v_b0_half = None
        n_coarse = round(c.coarse_time / c.step) if c.align_time > 0 else 0
        self._n_coarse = n_coarse
        self._n_align = round(c.align_time / c.step)
        # diagonal of P after each fine-alignment step (filled as the steps are made)
        self.p_history = np.full((max(self._n_align - n_coarse, 0), 9), np.nan)

    @property
    def phase(self) -> str:
        if self.steps < self._n_coarse:
            return "coarse"
        if self.steps < self._n_align:
            return "fine"
        return "navigate"

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
        the current attitude estimate.
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
        out = np.empty((n, 9))
        k = 0
        while k < n:
            phase = self.phase
            if phase == "coarse":
                m = min(n - k, self._n_coarse - self.steps)
                self._coarse(dtheta[k:k + m], dv[k:k + m])
                out[k:k + m] = self._held_row()
            elif phase == "fine":
                m = min(n - k, self._n_align - self.steps)
                hist = align_steps(self.q, self.v, self.pos, dtheta[k:k + m], dv[k:k + m], self.config.step,
                                   self.gyro_comp, self.accel_comp, self.x, self.p, self.q_diag,
                                   self.config.filter.velocity_meas_std ** 2)
                row = self.steps - self._n_coarse
                self.p_history[row:row + m] = hist
                out[k:k + m] = self._held_row()
                if self.steps + m == self._n_align:
                    self.v[:] = 0.0  # known static start for navigation
            else:
                m = n - k
                out[k:] = nav_steps(self.q, self.v, self.pos, dtheta[k:], dv[k:], self.config.step,
                                    self.gyro_comp, self.accel_comp, corr[k:])
            self._count[0] += m
            k += m
        return out

    @property
    def steps(self) -> int:
        """Major-loop steps integrated so far."""
        return int(self._count[0])

    @property
    def time(self) -> float:
        """Time since the start, s (steps x step)."""
        return self.steps * self.config.step

    def state_arrays(self) -> tuple:
        """(q, v, pos, gyro_comp, accel_comp, steps, x, P, q_diag, p_history): the arrays a step
        reads and updates in place (valid until :meth:`reset`)."""
        return (self.q, self.v, self.pos, self.gyro_comp, self.accel_comp, self._count, self.x, self.p,
                self.q_diag, self.p_history)

    def _held_row(self):
        return held_row(self.q, self.pos)

    def attitude_euler(self):
        """(yaw, pitch, roll) in rad of the current mat_nb."""
        return tuple(float(x) for x in held_row(self.q, self.pos)[6:9])

    @property
    def mat_nb(self):
        return quat_to_mat(self.q)

    def _coarse(self, dtheta, dv):
        """Accumulate the inertial-frame coarse alignment; finish it on its last step."""
        hist = coarse_steps(self._q_b0b, self._v_b0, dtheta, dv)
        half = self._n_coarse // 2 - self.steps  # index of the half-way step in this batch
        if 1 <= half <= len(hist):
            self._v_b0_half = hist[half - 1].copy()
        if self.steps + len(hist) == self._n_coarse:
            self._finish_coarse()

    def _finish_coarse(self):
        c = self.config
        t_half = (self._n_coarse // 2) * c.step
        t_end = self._n_coarse * c.step
        r1 = _gravity_integral_n0(c.lat, c.height, t_half)
        r2 = _gravity_integral_n0(c.lat, c.height, t_end)
        mat_n0b0 = _triad(r1, r2, self._v_b0_half, self._v_b0)
        # mat_nb(T) = mat_n n0 (T) mat_n0b0 mat_b0b(T); the n frame has turned
        # by -omega_ie T relative to n0 (static)
        zeta = earth.earth_rate_n(c.lat) * t_end
        mat_nn0 = quat_to_mat(rotvec_to_quat(-zeta))
        mat_nb = mat_nn0 @ mat_n0b0 @ quat_to_mat(self._q_b0b)
        self.q[:] = mat_to_quat(mat_nb)

    def position_error(self, out):
        """Errors of output rows wrt the known start: (K, 4) dlat, dlon (rad),
        north and east position errors (m)."""
        c = self.config
        r_m, r_n = earth.radii(c.lat)
        dlat = out[:, 0] - c.lat
        dlon = out[:, 1] - c.lon
        north = dlat * (r_m + c.height)
        east = dlon * (r_n + c.height) * math.cos(c.lat)
        return np.column_stack([dlat, dlon, north, east])
