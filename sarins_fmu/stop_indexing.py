r"""Indexing a dual-axis RINS through several positions during a stop (seed 002, issue 20).

Without indexing the azimuth gyro's constant drift reaches the velocity only
through the Earth rate, as a t^3 term that the horizontal gyros' random walk
hides (:mod:`sarins_fmu.stop_accuracy`: 1 sigma 0.027 deg/h after 30 min at
nav-rlg's noise).  A dual-axis RINS can turn its outer gimbal so that the
azimuth gyro's input axis lies horizontal for part of the stop: its drift
then drives the tilt at first order, as a gyro drift does in gyrocompassing
(phi_N' = -eps_N: a t^2 velocity error; phi_E' = -Omega cos L phi_U - eps_E:
east drift and heading error are one combination in one position, and a
second position with the axis reversed separates them).  Gyrocompassing
(Titterton & Weston 2004, ch. 10; Groves 2013, sec. 5.6.2): in one position
the east gyro's bias and the heading error are one combination, which is why
north finders and multi-position alignments turn the sensor by 180 deg
between two measurements.  Here the principle is applied to the azimuth
gyro with the outer gimbal of the paper's Fig. 1 (the chain
:data:`~sarins_fmu.turntable.DUAL_AXIS_AXES`, mat_tb = Ry(eta_out) Rz(eta_in)).

The module holds

* :class:`IndexingSequence` and :func:`indexing_schedule`: the positions,
  holds and rotation rate, turned into a :class:`~sarins_fmu.turntable.GimbalSchedule`
  built from its breakpoint arrays (rest-to-rest trapezoidal moves, one
  gimbal at a time, every breakpoint on the output grid);
* :func:`body_to_nav` : mat_nb(t) = mat_nt(base yaw) mat_tb(t);
* :func:`indexed_drift_accuracy`: the covariance bound of the azimuth drift
  with a time-varying body-to-nav rotation and the drifts and biases in the
  body frame (with a constant mat_nb = I and only the azimuth drift it is
  :func:`sarins_fmu.stop_accuracy.stop_drift_accuracy` exactly);
* :class:`IndexedStopFilter`: the stop Kalman filter with body-frame drifts
  and accelerometer biases carried through the known rotation sequence.

Frames: n = local level ENU, t = the turntable base (the vehicle, level,
yaw ``yaw`` counter-clockwise from n), b = the IMU.  Units: rad, rad/s, m/s,
m/s^2, s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import earth
from .kalman import StopFilterSettings, StopRecord, check_stop_arguments
from .stop_accuracy import G, R_EARTH, StopAccuracy, discretise, heading_walk_drift_std
from .turntable import DUAL_AXIS_AXES, GimbalSchedule
from .units import DEG_TO_RAD

# ---------------------------------------------------------------------------
# the indexing sequence
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class IndexingSequence:
    """Positions of the dual-axis RINS during a stop and how it moves between them.

    Attributes
    ----------
    positions_deg : ((P, 2) tuple)
        (outer, inner) gimbal angles of each position, deg; the stop starts
        in the first one.
    holds : (P,) tuple
        Hold time in each position, s; the last position holds to the end of
        the stop (its entry is the least hold, the stop must leave room for it).
    rate_dps, accel_dps2 : float
        Peak rate (deg/s) and angular acceleration (deg/s^2) of the moves.
    """

    positions_deg: tuple = field(default=((0.0, 0.0), (0.0, 180.0), (90.0, 180.0), (-90.0, 180.0)))
    holds: tuple = (420.0, 420.0, 420.0, 420.0)
    rate_dps: float = 6.0
    accel_dps2: float = 6.0

    def __post_init__(self):
        pos = np.asarray(self.positions_deg, float)
        holds = np.asarray(self.holds, float)
        if pos.ndim != 2 or pos.shape[1] != 2 or pos.shape[0] < 1:
            raise ValueError("indexing positions_deg must be (P, 2): outer and inner angle of each position")
        if holds.shape != (pos.shape[0],):
            raise ValueError(f"indexing holds must give one time per position ({pos.shape[0]}), got {holds.shape}")
        if not (np.isfinite(pos).all() and np.isfinite(holds).all() and np.all(holds >= 0)):
            raise ValueError("indexing positions and holds must be finite, holds >= 0")
        for name in ("rate_dps", "accel_dps2"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"indexing {name} must be positive and finite, got {value!r}")


NO_INDEXING = IndexingSequence(positions_deg=((0.0, 0.0),), holds=(0.0,))


def _move(delta: float, rate: float, accel: float, grid: float) -> list:
    """Rest-to-rest move by ``delta`` rad: [(duration, acceleration), ...] with durations on ``grid``.

    Trapezoid: T_a at +alpha, T_c at rate alpha T_a, T_a at -alpha, so delta = alpha T_a (T_a + T_c);
    T_a = ceil(rate / accel) and T_c = ceil(|delta| / rate - T_a) (in grid steps) keep the peak rate
    and acceleration within the limits."""
    if delta == 0.0:
        return []
    t_a = max(1, math.ceil(rate / accel / grid - 1e-9)) * grid
    t_c = max(0, math.ceil((abs(delta) / rate - t_a) / grid - 1e-9)) * grid
    alpha = delta / (t_a * (t_a + t_c))
    return [(t_a, alpha)] + ([(t_c, 0.0)] if t_c > 0 else []) + [(t_a, -alpha)]


def indexing_schedule(sequence: IndexingSequence, duration: float, grid: float = 1.0) -> GimbalSchedule:
    """The dual-axis gimbal motion of ``sequence`` over ``duration`` s, as breakpoint arrays.

    Hold, move (outer gimbal first, then inner, each rest to rest), hold, ...;
    holds and moves are rounded up to ``grid``; the last position holds to
    ``duration``.  Raises ValueError if the sequence does not fit.

    Returns
    -------
    GimbalSchedule on :data:`~sarins_fmu.turntable.DUAL_AXIS_AXES` (outer about the base's y, inner
    about the outer frame's z), starting at rest at t = 0 in the first position.
    """
    if not (math.isfinite(duration) and math.isfinite(grid) and duration >= grid > 0):
        raise ValueError(f"need duration >= grid > 0, got duration {duration!r}, grid {grid!r}")
    pos = np.asarray(sequence.positions_deg, float) * DEG_TO_RAD
    rate, accel = sequence.rate_dps * DEG_TO_RAD, sequence.accel_dps2 * DEG_TO_RAD
    segs = []  # (duration, accel_outer, accel_inner)
    for p in range(pos.shape[0]):
        hold = math.ceil(sequence.holds[p] / grid - 1e-9) * grid
        if p + 1 < pos.shape[0]:
            segs += [(hold, 0.0, 0.0)] if hold > 0 else []
            for axis in (0, 1):
                for d, a in _move(pos[p + 1, axis] - pos[p, axis], rate, accel, grid):
                    segs.append((d, a, 0.0) if axis == 0 else (d, 0.0, a))
        else:
            used = sum(s[0] for s in segs)
            rest = round((duration - used) / grid) * grid
            if rest < hold or rest <= 0:
                raise ValueError(f"indexing sequence needs {used + max(hold, grid):g} s, the stop is {duration:g} s")
            segs.append((rest, 0.0, 0.0))
    seg = np.asarray(segs, float)
    times = np.concatenate([[0.0], np.cumsum(seg[:, 0])])
    return GimbalSchedule(np.asarray(DUAL_AXIS_AXES, float), times, seg[:, 1:], pos[0], np.zeros(2))


def _mat_nt(yaw: float) -> np.ndarray:
    """Level base yawed by ``yaw`` (rad, counter-clockwise from east-north): projects t onto n."""
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _axis_rotations(axis, angle: np.ndarray) -> np.ndarray:
    """R(a, theta) = exp(theta [a x]) for each of ``angle`` (N,), (N, 3, 3) (Rodrigues, as
    :func:`sarins_fmu.turntable.axis_rotation`)."""
    a = np.asarray(axis, float)
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    s, c = np.sin(angle)[:, None, None], np.cos(angle)[:, None, None]
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)


def body_to_nav(schedule: GimbalSchedule, time, yaw: float = 0.0) -> np.ndarray:
    """mat_nb = mat_nt(yaw) mat_tb(t) at ``time`` (scalar or (K,)), (K, 3, 3); ``yaw`` rad."""
    angle = schedule.state(time)[0]
    mat = np.broadcast_to(_mat_nt(yaw), (angle.shape[0], 3, 3))
    for j, axis in enumerate(schedule.axes):
        mat = mat @ _axis_rotations(axis, angle[:, j])
    return mat


def step_midpoints(start: float, dt: float, n_steps: int, substeps: int) -> np.ndarray:
    """(n_steps, substeps) midpoints of ``substeps`` equal parts of each step [start + k dt, start + (k+1) dt]."""
    k = np.arange(n_steps)[:, None]
    j = (np.arange(substeps) + 0.5) / substeps
    return start + (k + j) * dt


def rotation_samples(schedule: GimbalSchedule, n_steps: int, dt: float = 1.0, yaw: float = 0.0,
                     start: float = 0.0, substeps: int = 16) -> np.ndarray:
    """mat_nb at the midpoints of ``substeps`` (M) equal parts of each step, (n_steps, M, 3, 3).

    A step in which the gimbals stand still has M equal samples (the filter and the bound then use
    one exponential for it)."""
    mid = step_midpoints(start, dt, n_steps, substeps)
    return body_to_nav(schedule, mid.ravel(), yaw).reshape(n_steps, substeps, 3, 3)


# ---------------------------------------------------------------------------
# the covariance bound with a time-varying rotation
# ---------------------------------------------------------------------------

NAV_STATES = ("dv_e", "dv_n", "phi_e", "phi_n", "phi_u")  # stop_accuracy.STATES without eps_u


def indexed_model(lat: float, mat_nb: np.ndarray, arw, vrw, gyro_states=(0, 1, 2), accel_states=(0, 1, 2)):
    """Continuous-time (F, Qc) of [dv_e, dv_n, phi_e, phi_n, phi_u, eps_b[gyro_states], nabla_b[accel_states]]
    while the IMU stands at mat_nb (3, 3), latitude ``lat`` rad.

    As :func:`sarins_fmu.stop_accuracy.stop_model`, with the gyro drifts and accelerometer biases in the
    body frame: phi' = ... - mat_nb eps_b, dv_EN' = ... + (mat_nb nabla_b)_EN; the white noises rotate
    with the IMU: Q_gyro^n = mat_nb diag(arw^2) mat_nb', Q_accel^n the same with vrw (east and north
    rows); arw and vrw (3,) or scalar, rad/sqrt(s) and m/s/sqrt(s) per body axis."""
    s, c, t = math.sin(lat), math.cos(lat), math.tan(lat)
    w = earth.RATE
    gs, acs = tuple(gyro_states), tuple(accel_states)
    n = 5 + len(gs) + len(acs)
    F = np.zeros((n, n))
    F[0, 1], F[0, 3] = 2 * w * s, -G
    F[1, 0], F[1, 2] = -2 * w * s, G
    F[2, 1], F[2, 3], F[2, 4] = -1.0 / R_EARTH, w * s, -w * c
    F[3, 0], F[3, 2] = 1.0 / R_EARTH, -w * s
    F[4, 0], F[4, 2] = t / R_EARTH, w * c
    for j, axis in enumerate(gs):
        F[2:5, 5 + j] = -mat_nb[:, axis]
    for j, axis in enumerate(acs):
        F[0:2, 5 + len(gs) + j] = mat_nb[:2, axis]
    arw, vrw = (np.broadcast_to(np.asarray(x, float), (3,)) for x in (arw, vrw))
    Qc = np.zeros((n, n))
    Qc[0:2, 0:2] = (mat_nb @ np.diag(vrw**2) @ mat_nb.T)[:2, :2]
    Qc[2:5, 2:5] = mat_nb @ np.diag(arw**2) @ mat_nb.T
    return F, Qc


def _expm_series(m: np.ndarray) -> np.ndarray:
    """exp(m) by scaling and squaring of a 20-term Taylor series (relative error ~1e-16 for the
    Van Loan blocks here; scipy's expm takes milliseconds on these small-norm 22 x 22 blocks)."""
    s = max(0, int(math.ceil(math.log2(max(np.abs(m).sum(axis=0).max(), 1e-300)))) + 1)
    a = m / 2.0**s
    term, out = np.eye(m.shape[0]), np.eye(m.shape[0])
    for k in range(1, 21):
        term = term @ a / k
        out = out + term
    for _ in range(s):
        out = out @ out
    return out


def _van_loan_series(F: np.ndarray, Qc: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """:func:`sarins_fmu.stop_accuracy.discretise` with :func:`_expm_series`."""
    n = F.shape[0]
    block = np.zeros((2 * n, 2 * n))
    block[:n, :n], block[:n, n:], block[n:, n:] = -F, Qc, F.T
    e = _expm_series(block * dt)
    phi = e[n:, n:].T
    return phi, phi @ e[:n, n:]


def _step_transition(lat, samples, arw, vrw, gyro_states, accel_states, dt, cache):
    """(Phi, Q) of one step from its M rotation samples (the midpoints of M equal parts): the
    product of the parts' exact transitions (Van Loan per part; a standing step, M = 1, is cached
    per rotation and discretised as :func:`sarins_fmu.stop_accuracy.discretise` does)."""
    if samples.shape[0] == 1:
        key = samples[0].tobytes()
        if key not in cache:
            cache[key] = discretise(*indexed_model(lat, samples[0], arw, vrw, gyro_states, accel_states), dt)
        return cache[key]
    phi, q = None, None
    h = dt / samples.shape[0]
    for mat in samples:
        p_j, q_j = _van_loan_series(*indexed_model(lat, mat, arw, vrw, gyro_states, accel_states), h)
        phi, q = (p_j, q_j) if phi is None else (p_j @ phi, p_j @ q @ p_j.T + q_j)
    return phi, q


def _constant(samples: np.ndarray) -> bool:
    return bool(np.all(samples == samples[:1]))


@dataclass(frozen=True)
class IndexedStopAccuracy(StopAccuracy):
    """:class:`~sarins_fmu.stop_accuracy.StopAccuracy` of an indexed stop; ``gyrocompass_std`` is
    N_z / sqrt(T), the bound of a drift read from a directly observed tilt (rad/s)."""

    gyrocompass_std: float = float("nan")


def indexed_drift_accuracy(*, lat: float, rotations: np.ndarray, arw, vrw=0.0, dt: float = 1.0,
                           velocity_meas_std: float = 1e-3, diffuse: float = 1e3, gyro_states=(0, 1, 2),
                           accel_states=(0, 1, 2), drift_axis: int = 2) -> IndexedStopAccuracy:
    """1-sigma accuracy of the body-frame drift of gyro ``drift_axis`` from a zero-velocity stop
    during which the IMU turns through ``rotations``.

    Parameters
    ----------
    lat : latitude, rad.
    rotations : (K, M, 3, 3) mat_nb at the midpoints of M equal parts of each of the K steps
        (:func:`rotation_samples`; an IMU standing still: a (3, 3) broadcast to (K, 1, 3, 3)).
    arw : (3,) or float, gyro angle random walk per body axis, rad/sqrt(s).
    vrw : (3,) or float, accelerometer velocity random walk per body axis, m/s/sqrt(s).
    dt : measurement interval, s.  velocity_meas_std : white noise on the observed velocity, m/s.
    diffuse : prior std of every state in units of (1 m/s, 1 mrad, 10 mrad, 1 deg/h, 1 mg).
    gyro_states, accel_states : body axes whose constant drift / bias are unknowns (the others are
        taken as known or modulated away); ``drift_axis`` must be among ``gyro_states``.

    With a constant mat_nb = I, ``gyro_states=(2,)``, ``accel_states=()``, arw (N_h, N_h, N_U) and vrw
    equal on all axes this is :func:`sarins_fmu.stop_accuracy.stop_drift_accuracy` to the last bit.
    """
    rot = np.asarray(rotations, float)
    if rot.ndim != 4 or rot.shape[2:] != (3, 3) or rot.shape[0] < 2 or rot.shape[1] < 1:
        raise ValueError("rotations must be (K, M, 3, 3) with K >= 2 steps and M >= 1 samples per step")
    if not np.isfinite(rot).all():
        raise ValueError("rotations contain NaN or infinity")
    if not (math.isfinite(lat) and math.isfinite(dt) and dt > 0 and velocity_meas_std > 0 and diffuse > 0):
        raise ValueError("need a finite latitude, dt > 0, a positive velocity noise and a positive prior")
    arw, vrw = np.broadcast_to(np.asarray(arw, float), (3,)), np.broadcast_to(np.asarray(vrw, float), (3,))
    if np.any(arw < 0) or np.any(vrw < 0) or not (np.isfinite(arw).all() and np.isfinite(vrw).all()):
        raise ValueError("random walks must be finite and non-negative")
    gs, acs = tuple(gyro_states), tuple(accel_states)
    if drift_axis not in gs:
        raise ValueError(f"drift_axis {drift_axis} must be one of gyro_states {gs}")
    index = 5 + gs.index(drift_axis)
    prior = [1.0, 1.0, 1e-3, 1e-3, 1e-2] + [DEG_TO_RAD / 3600.0] * len(gs) + [1e-3 * G] * len(acs)
    P = np.diag(np.array(prior) ** 2) * diffuse**2
    H = np.zeros((2, P.shape[0]))
    H[0, 0] = H[1, 1] = 1.0
    R = np.diag([velocity_meas_std**2] * 2)
    eye = np.eye(P.shape[0])
    cache: dict = {}
    n = rot.shape[0]
    out = np.empty(n)
    for k in range(n):
        samples = rot[k, :1] if _constant(rot[k]) else rot[k]
        phi, q = _step_transition(lat, samples, arw, vrw, gs, acs, dt, cache)
        # the same Kalman covariance recursion as stop_accuracy.posterior_std (Joseph form)
        P = phi @ P @ phi.T + q  # P = Phi P Phi' + Q
        S = H @ P @ H.T + R
        K = np.linalg.solve(S, H @ P).T  # K = P H' S^-1
        A = eye - K @ H
        P = A @ P @ A.T + K @ R @ K.T
        out[k] = math.sqrt(P[index, index])
    duration = n * dt
    time = np.arange(1, n + 1) * dt
    return IndexedStopAccuracy(time, out, float(out[-1]), heading_walk_drift_std(float(arw[2]), duration),
                               heading_walk_drift_std(float(arw[drift_axis]), duration))


# ---------------------------------------------------------------------------
# the stop filter with the indexing sequence
# ---------------------------------------------------------------------------

N_FILTER_STATES = 12
FILTER_STATE_NAMES = ("phi_e", "phi_n", "phi_u", "dv_e", "dv_n", "eps_x", "eps_y", "eps_z", "nabla_x",
                      "nabla_y", "nabla_z", "d_lat")
FILTER_EPS_Z = 7  # index of the azimuth gyro's drift (as sarins_fmu.kalman.EPS_Z)
_CACHE_LIMIT = 20000  # transitions kept by a filter (12 x 12 each, ~23 MB at most)


def filter_dynamics(lat: float, mat_nb: np.ndarray) -> np.ndarray:
    """Continuous-time F (12, 12) of :data:`FILTER_STATE_NAMES` while the IMU stands at mat_nb.

    The static ENU error model of :mod:`sarins_fmu.kalman` (Titterton & Weston 2004, eqs 12.6-12.7,
    WGS-84 radii and gravity at ``lat``) with all three accelerometer biases in the body frame:
    phi' = phi x omega_ie^n + d omega_en^n + d omega_ie^n(dL) - mat_nb eps,
    dv' = f^n x phi - 2 omega_ie^n x dv + (mat_nb nabla)_EN,  dL' = dv_N / R_M."""
    r_m, r_n = earth.radii(lat)
    w_c, w_s = earth.RATE * math.cos(lat), earth.RATE * math.sin(lat)
    g = earth.gravity(lat, 0.0)
    F = np.zeros((N_FILTER_STATES, N_FILTER_STATES))
    F[0, 1], F[0, 2], F[0, 4] = w_s, -w_c, -1.0 / r_m
    F[1, 0], F[1, 3], F[1, 11] = -w_s, 1.0 / r_n, -w_s
    F[2, 0], F[2, 3], F[2, 11] = w_c, math.tan(lat) / r_n, w_c
    F[3, 1], F[3, 4] = -g, 2.0 * w_s
    F[4, 0], F[4, 3] = g, -2.0 * w_s
    F[11, 4] = 1.0 / r_m
    F[0:3, 5:8] = -mat_nb
    F[3:5, 8:11] = mat_nb[:2]
    return F


class IndexedStopFilter(StopRecord):
    """Stop filter of seed 002 for a RINS indexed through several positions during the stop.

    As :class:`sarins_fmu.kalman.StopKalmanFilter` (open loop on the INS's east/north velocity, the
    same settings), with the three accelerometer biases as states (the azimuth accelerometer turns
    horizontal when the outer gimbal tilts the IMU) and the body-to-nav rotation of every step given
    by the known indexing sequence (:func:`rotation_samples`) rather than read from the INS's
    attitude: the transition of a step is the product of the exact transitions of its M parts,
    exp(F(mat_nb_j) dt / M), so that the rotations between positions are followed within the step.

    Parameters
    ----------
    lat : latitude of the stop, rad.  settings : the stop filter's noise and priors (the azimuth
        accelerometer's bias prior is ``bias0_std`` as for the others).  dt : measurement step, s.
    history_limit : rows of :meth:`convergence` kept (0: none).
    """

    eps_index = FILTER_EPS_Z

    def __init__(self, lat: float, settings: StopFilterSettings = StopFilterSettings(), dt: float = 1.0,
                 history_limit: int = 0):
        check_stop_arguments(lat, dt, history_limit)
        self.lat, self.settings, self.dt, self.history_limit = float(lat), settings, float(dt), int(history_limit)
        s = settings
        self._q = np.array([s.arw, s.arw, s.arw, s.vrw, s.vrw, s.drift_rw, s.drift_rw, s.drift_rw,
                            s.bias_rw, s.bias_rw, s.bias_rw, 0.0]) ** 2
        self._r = s.velocity_meas_std**2
        self._cache: dict = {}
        self.reset()

    def initial_covariance(self) -> np.ndarray:
        """P0, (12, 12)."""
        s = self.settings
        std = np.array([s.tilt0_std, s.tilt0_std, s.heading0_std, s.velocity0_std, s.velocity0_std,
                        s.drift0_std, s.drift0_std, s.azimuth_drift0_std, s.bias0_std, s.bias0_std, s.bias0_std,
                        s.position0_std / earth.A])
        return np.diag(std**2)

    def reset(self) -> None:
        """Restart the estimation (new stop): state 0, covariance P0, timer 0."""
        self.x = np.zeros(N_FILTER_STATES)
        self.p = self.initial_covariance()
        self._clear_record()

    def _transition(self, samples: np.ndarray) -> np.ndarray:
        """Phi of one step from its M rotation samples (the parts' exponentials, cached per rotation)."""
        if _constant(samples):
            samples = samples[:1]
        h = self.dt / samples.shape[0]
        phi = None
        for mat in samples:
            key = (mat.tobytes(), h)
            if key not in self._cache:
                if len(self._cache) >= _CACHE_LIMIT:  # moves give new rotations at every part: keep memory bounded
                    self._cache.clear()
                self._cache[key] = _expm_series(filter_dynamics(self.lat, mat) * h)
            phi = self._cache[key] if phi is None else self._cache[key] @ phi
        return phi

    def step(self, velocity_en, rotations, axial_correction=0.0, temperature=np.nan) -> np.ndarray:
        """Process K INS output rows of the stop.

        Parameters
        ----------
        velocity_en : (K, 2) INS east/north velocity at the end of each step, m/s.
        rotations : (K, M, 3, 3) mat_nb at the midpoints of M equal parts of each step.
        axial_correction : float or (K,) azimuth drift the INS subtracted, rad/s.
        temperature : float or (K,) azimuth gyro temperature, °C.

        Returns
        -------
        (K, 2) eps_z residual estimate and its standard deviation after each step, rad/s.
        """
        vel = np.atleast_2d(np.asarray(velocity_en, float))
        rot = np.asarray(rotations, float)
        n = vel.shape[0]
        if vel.shape[1] != 2 or rot.ndim != 4 or rot.shape[0] != n or rot.shape[2:] != (3, 3) or rot.shape[1] < 1:
            raise ValueError("velocity_en must be (K, 2) and rotations (K, M, 3, 3)")
        corr = np.broadcast_to(np.asarray(axial_correction, float), (n,))
        temp = np.broadcast_to(np.asarray(temperature, float), (n,))
        if not (np.isfinite(vel).all() and np.isfinite(rot).all() and np.isfinite(corr).all()):
            raise ValueError("INS outputs or rotations contain NaN or infinity")
        out = np.empty((n, 2))
        x, p, r = self.x, self.p, self._r
        for k in range(n):
            phi = self._transition(rot[k])
            x = phi @ x  # x = Phi x
            p = phi @ p @ phi.T + np.diag(self._q * self.dt)  # P = Phi P Phi' + Q dt
            s = p[3:5, 3:5] + r * np.eye(2)  # S = H P H' + R, H selecting dv_e, dv_n
            gain = np.linalg.solve(s, p[3:5, :]).T  # K = P H' S^-1
            x = x + gain @ (vel[k] - x[3:5])
            a = np.eye(N_FILTER_STATES)
            a[:, 3:5] -= gain
            p = a @ p @ a.T + r * gain @ gain.T  # Joseph form
            out[k] = x[FILTER_EPS_Z], math.sqrt(p[FILTER_EPS_Z, FILTER_EPS_Z])
        self.x, self.p = x, p
        self._record(out, corr, temp)
        return out
