r"""Static-base (stop) Kalman filter estimating the azimuth gyro drift (seed 002).

At a vehicle stop the true velocity is zero, so the INS's computed east and
north velocity is its velocity error; seed 002 (eqs 4-6) feeds it to a
Kalman filter whose states include the azimuth gyro drift :math:`\varepsilon_U`
and reads the drift after 30 minutes.  The equations are missing from the
seed's text; this module uses the standard static-base error model (Titterton
& Weston 2004, eqs 12.6-12.7, ENU, position errors neglected over a stop):

State (10 of the paper + the north position error), with the attitude error :math:`\phi` defined by
:math:`C^n_{b,\text{computed}} = (I - [\phi\times]) C^n_b`:

.. math:: x = [\phi_E, \phi_N, \phi_U, \delta v_E, \delta v_N,
              \varepsilon_x, \varepsilon_y, \varepsilon_z, \nabla_x, \nabla_y]^\mathsf{T}

(gyro drifts and accelerometer biases in the IMU frame b, where
:math:`\varepsilon_z` is the azimuth gyro, :math:`\varepsilon_U` of the paper;
all constants).  Dynamics

.. math::

    \dot\phi &= \phi \times \omega^n_{ie} + \delta\omega^n_{en}(\delta v)
               + \delta\omega^n_{ie}(\delta L) - C^n_b \varepsilon \\
    \delta\dot v &= f^n \times \phi - 2\omega^n_{ie} \times \delta v + C^n_b \nabla \\
    \delta\dot L &= \delta v_N / R_M

with :math:`f^n = (0, 0, g)`, :math:`\delta\omega^n_{ie} = \Omega(0, -\sin L, \cos L)\,\delta L`
(the INS evaluates the Earth rate at its own latitude: a position error acts
on :math:`\phi_U` exactly like an azimuth drift, 0.0024 °/h per km at 45°,
so the paper's 10 states are completed by :math:`\delta L`), and measurement :math:`z = [v_E, v_N]` (eq. 6).
The filter is **open loop** on the INS outputs (velocity, attitude,
latitude): the navigation is not corrected, so the same code runs in process
and inside the DriftModelUpdater FMU, which sees only INS outputs.  When the
INS compensated the azimuth gyro with a model value during the stop, the
filter estimates the residual and the stop's drift measurement is the model
value plus the residual (:meth:`StopKalmanFilter.drift_estimate`).

Observability of :math:`\varepsilon_z` on a static base is weak: it enters the
velocity only through :math:`\dot\phi_E = -\omega_{ie}\cos L\,\phi_U` and
:math:`\delta\dot v_N = g\phi_E`, i.e. as a cubic in time, whereas an initial
heading error gives a quadratic.  Over 30 minutes the white gyro noise (ARW)
therefore limits the estimate: see ``docs/online-rls.md`` for the numbers.  The
rotation of the IMU about the azimuth axis modulates the horizontal drifts so
that they are separable from the heading error; it does not modulate
:math:`\varepsilon_z`.

Units: rad, rad/s, m/s, m/s², s.
"""

from __future__ import annotations

import ctypes
import math
from dataclasses import dataclass

import numpy as np

from . import earth
from .core import online as core_online
from .core._arrays import read, written
from .core._lib import function
from .imu import ImuModel
from .units import ARCSEC_TO_RAD, DEG_TO_RAD, DPH_TO_RPS, UG_TO_MPS2

N_STATES = 11
STATE_NAMES = ("phi_e", "phi_n", "phi_u", "dv_e", "dv_n", "eps_x", "eps_y", "eps_z", "nabla_x", "nabla_y",
               "d_lat")
EPS_Z = 7  # index of the azimuth drift state
STOP_TIME_THRESHOLD = 1800.0  # s, seed 002's 30-minute stop threshold


@dataclass(frozen=True)
class StopFilterSettings:
    """Noise and initial uncertainty of the stop filter (SI units).

    Attributes
    ----------
    arw : float
        Gyro angle random walk, rad/√s.
    vrw : float
        Accelerometer velocity random walk, m/s/√s.
    drift_rw : float
        Random walk of the drift states, rad/s/√s.
    bias_rw : float
        Random walk of the accelerometer-bias states, m/s²/√s.
    velocity_meas_std : float
        Velocity measurement noise, m/s.
    tilt0_std, heading0_std : float
        Initial attitude error, rad.
    velocity0_std : float
        Initial velocity error, m/s.
    drift0_std, azimuth_drift0_std : float
        Initial horizontal / azimuth drift uncertainty, rad/s.
    bias0_std : float
        Initial accelerometer-bias uncertainty, m/s².
    position0_std : float
        Initial north position error, m (the stop's position is known to this).
    """

    arw: float = 0.0005 * DEG_TO_RAD / 60.0
    vrw: float = 5.0 * UG_TO_MPS2
    drift_rw: float = 1e-7 * DPH_TO_RPS
    bias_rw: float = 1e-3 * UG_TO_MPS2
    velocity_meas_std: float = 1e-3
    tilt0_std: float = 30.0 * ARCSEC_TO_RAD
    heading0_std: float = 0.1 * DEG_TO_RAD
    velocity0_std: float = 1.0
    drift0_std: float = 0.01 * DPH_TO_RPS
    azimuth_drift0_std: float = 0.02 * DPH_TO_RPS
    bias0_std: float = 100.0 * UG_TO_MPS2
    position0_std: float = 10.0

    def __post_init__(self):
        for name, value in self.__dict__.items():
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"stop filter {name} must be positive and finite, got {value!r}")

    @classmethod
    def for_model(cls, model: ImuModel, **overrides) -> "StopFilterSettings":
        """Settings whose white-noise densities are those of ``model`` (floored
        at tiny positive values so an ideal IMU still gives a valid filter)."""
        arw = max(float(np.max(model.gyro.random_walk)), 1e-12)
        vrw = max(float(np.max(model.accel.random_walk)), 1e-12)
        return cls(**{"arw": arw, "vrw": vrw, **overrides})

    def initial_covariance(self) -> np.ndarray:
        """P0, (11, 11)."""
        std = np.array([self.tilt0_std, self.tilt0_std, self.heading0_std, self.velocity0_std,
                        self.velocity0_std, self.drift0_std, self.drift0_std, self.azimuth_drift0_std,
                        self.bias0_std, self.bias0_std, self.position0_std / earth.A])
        return np.diag(std**2)

    def process_noise(self) -> np.ndarray:
        """Diagonal of the continuous process-noise density Q, (11,)."""
        return np.array([self.arw, self.arw, self.arw, self.vrw, self.vrw, self.drift_rw, self.drift_rw,
                         self.drift_rw, self.bias_rw, self.bias_rw, 0.0]) ** 2


def settings_array(settings: StopFilterSettings) -> np.ndarray:
    """The settings as the C core's array (``stop_filter.h``; :data:`sarins_fmu.core.online.STOP_SETTINGS`)."""
    return np.array([float(getattr(settings, name)) for name in core_online.STOP_SETTINGS])


_stop_steps = function("sarins_stop_filter_steps", None, ctypes.c_int64, ctypes.c_void_p, ctypes.c_void_p,
                       ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_void_p,
                       ctypes.c_double, ctypes.c_void_p)


def stop_filter_steps(x, p, velocity_en, attitude, lat, dt, q_diag, r_var):
    """Propagate and update the stop filter over K measurements (in place; the C core's
    ``sarins_stop_filter_steps``, ``sarins_fmu/core/filter.h``).

    Parameters
    ----------
    x : (11,) state estimate; p : (11, 11) covariance (C-contiguous float64, modified in place).
    velocity_en : (K, 2) INS east/north velocity at the end of each step, m/s.
    attitude : (K, 3) INS yaw, pitch, roll at the end of each step, rad.
    lat : float, latitude, rad.  dt : float, step, s.
    q_diag : (11,) continuous process-noise density; r_var : velocity noise variance.

    Returns
    -------
    (K, 2) : estimate and standard deviation of eps_z after each step, rad/s.
    """
    velocity_en = read(velocity_en, (np.shape(velocity_en)[0], 2), "velocity_en")
    k = velocity_en.shape[0]
    attitude = read(attitude, (k, 3), "attitude")
    q_diag = read(q_diag, (N_STATES,), "q_diag")
    out = np.empty((k, 2))
    x_address = written(x, (N_STATES,), "x").ctypes.data
    p_address = written(p, (N_STATES, N_STATES), "p").ctypes.data
    _stop_steps(k, x_address, p_address, velocity_en.ctypes.data, attitude.ctypes.data, float(lat), float(dt),
                q_diag.ctypes.data, float(r_var), out.ctypes.data)
    return out


def _running_sum(total: float, values: np.ndarray) -> float:
    """``total + values[0] + values[1] + ...``, added in that order."""
    return float(np.cumsum(np.concatenate(([total], values)))[-1])


def check_stop_arguments(lat: float, dt: float, history_limit: int) -> None:
    """ValueError unless the stop's latitude (rad), filter step (s) and history limit are usable."""
    if not (math.isfinite(lat) and abs(lat) <= 89.9 * DEG_TO_RAD):
        raise ValueError(f"latitude must be finite and within +-89.9 deg, got {lat!r} rad")
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"filter step must be positive, got {dt!r}")
    if int(history_limit) < 0:
        raise ValueError(f"history_limit must be >= 0, got {history_limit!r}")


class StopRecord:
    """What a stop filter written in Python (the indexed stop's) keeps of a stop besides its state: the
    timer, the running means of the INS's compensation and the azimuth gyro's temperature, and the first
    ``history_limit`` estimate rows.

    A filter sets ``x`` (state), ``p`` (covariance), ``dt`` (s), ``history_limit`` and the class
    attribute ``eps_index`` (where the azimuth drift sits in ``x``), calls :meth:`_clear_record` on
    reset and :meth:`_record` after each block of steps."""

    eps_index: int

    def _clear_record(self) -> None:
        self.elapsed = 0.0
        self._correction_sum = 0.0
        self._temperature_sum = 0.0
        self._n = 0
        self.history: list[np.ndarray] = []
        self._history_rows = 0

    def _record(self, out: np.ndarray, corr: np.ndarray, temp: np.ndarray) -> None:
        n = out.shape[0]
        room = self.history_limit - self._history_rows
        if room > 0:  # bounded: a parked vehicle's stop may last months
            self.history.append(out[:room].copy())
            self._history_rows += min(room, n)
        # running sums added row by row (np.cumsum is sequential): a stop fed in blocks or one row at a
        # time (the FMU) gives the same sums bit for bit
        self._correction_sum = _running_sum(self._correction_sum, corr)
        self._temperature_sum = _running_sum(self._temperature_sum, temp)
        self._n += n
        self.elapsed = self._n * self.dt

    @property
    def residual_drift(self) -> float:
        """Estimated azimuth drift left after the INS's compensation, rad/s."""
        return float(self.x[self.eps_index])

    @property
    def drift_std(self) -> float:
        """Filter standard deviation of the azimuth drift, rad/s."""
        return float(math.sqrt(self.p[self.eps_index, self.eps_index]))

    @property
    def drift_estimate(self) -> float:
        """The stop's drift measurement ε_U: mean compensation + residual, rad/s."""
        mean_corr = self._correction_sum / self._n if self._n else 0.0
        return mean_corr + self.residual_drift

    @property
    def mean_temperature(self) -> float:
        """Mean azimuth gyro temperature over the stop (T_gz), °C; NaN if not given."""
        return self._temperature_sum / self._n if self._n else float("nan")

    def convergence(self) -> np.ndarray:
        """(K, 3): time since reset (s), ε_z residual estimate and std (rad/s),
        the first ``history_limit`` steps of the stop."""
        if not self.history:
            return np.empty((0, 3))
        h = np.concatenate(self.history)
        t = np.arange(1, h.shape[0] + 1) * self.dt
        return np.column_stack([t, h])


class StopKalmanFilter:
    """The stop filter of seed 002 (eqs 4-6) on the outputs of a free INS.

    Its state, covariance and record of the stop live in the C core's ``sarins_stop_kf`` struct
    (``sarins_fmu/core/stop_filter.h``): the code the DriftModelUpdater FMU runs.

    Parameters
    ----------
    lat : float
        Latitude of the stop, rad.
    settings : StopFilterSettings
    dt : float
        Measurement interval, s (the INS output step).
    history_limit : int
        Most rows of :attr:`history` kept per stop (default 0: none, so a
        long stop costs no memory; :meth:`convergence` needs a limit > 0).
        Rows past the limit are dropped, the estimate is unaffected.

    Attributes
    ----------
    x : (11,) state estimate; p : (11, 11) covariance (views of the C struct).
    history : list of (K, 2) arrays
        ε_z estimate and its standard deviation after each step, rad/s, the
        first ``history_limit`` steps of the stop.
    """

    eps_index = EPS_Z

    def __init__(self, lat: float, settings: StopFilterSettings = StopFilterSettings(), dt: float = 1.0,
                 history_limit: int = 0):
        check_stop_arguments(lat, dt, history_limit)
        self.settings, self.history_limit = settings, int(history_limit)
        self._state = core_online.StopKfState(settings_array(settings), float(lat), float(dt))
        self.x, self.p = self._state.x, self._state.p
        self._clear_history()

    @property
    def lat(self) -> float:
        """Latitude of the stop, rad."""
        return self._state.lat

    @property
    def dt(self) -> float:
        """Measurement interval, s."""
        return self._state.dt

    def _clear_history(self) -> None:
        self.history: list[np.ndarray] = []
        self._history_rows = 0

    def reset(self, lat: float | None = None) -> None:
        """Restart the estimation (new stop): state 0, covariance P0, timer 0."""
        if lat is not None:
            check_stop_arguments(lat, self.dt, self.history_limit)
        self._state.reset(self.lat if lat is None else float(lat))
        self._clear_history()

    def step(self, velocity_en, attitude, axial_correction=0.0, temperature=np.nan) -> np.ndarray:
        """Process K INS output rows taken at the stop.

        Parameters
        ----------
        velocity_en : (K, 2) or (2,) east/north velocity, m/s.
        attitude : (K, 3) or (3,) yaw, pitch, roll, rad.
        axial_correction : float or (K,) azimuth drift the INS subtracted, rad/s.
        temperature : float or (K,) azimuth gyro temperature, °C (averaged
            into :attr:`mean_temperature`, the paper's T_gz).

        Returns
        -------
        (K, 2) ε_z residual estimate and its standard deviation, rad/s.
        """
        vel = np.ascontiguousarray(np.atleast_2d(velocity_en), dtype=float)
        att = np.ascontiguousarray(np.atleast_2d(attitude), dtype=float)
        if vel.shape[1] != 2 or att.shape != (vel.shape[0], 3):
            raise ValueError("velocity_en must be (K, 2) and attitude (K, 3)")
        n = vel.shape[0]
        corr = np.broadcast_to(np.asarray(axial_correction, float), (n,))
        temp = np.broadcast_to(np.asarray(temperature, float), (n,))
        out = self._state.steps(vel, att, corr, temp)  # refuses a NaN or infinite INS output or correction
        room = self.history_limit - self._history_rows
        if room > 0:  # bounded: a parked vehicle's stop may last months
            self.history.append(out[:room].copy())
            self._history_rows += min(room, n)
        return out

    @property
    def elapsed(self) -> float:
        """Time since the last reset, s."""
        return self._state.elapsed()

    @property
    def residual_drift(self) -> float:
        """Estimated azimuth drift left after the INS's compensation, rad/s."""
        return float(self.x[EPS_Z])

    @property
    def drift_std(self) -> float:
        """Filter standard deviation of the azimuth drift, rad/s."""
        return self._state.drift_std()

    @property
    def drift_estimate(self) -> float:
        """The stop's drift measurement ε_U: mean compensation + residual, rad/s."""
        return self._state.drift_estimate()

    @property
    def mean_temperature(self) -> float:
        """Mean azimuth gyro temperature over the stop (T_gz), °C; NaN if not given."""
        return self._state.mean_temperature()

    def convergence(self) -> np.ndarray:
        """(K, 3): time since reset (s), ε_z residual estimate and std (rad/s),
        the first ``history_limit`` steps of the stop."""
        if not self.history:
            return np.empty((0, 3))
        h = np.concatenate(self.history)
        t = np.arange(1, h.shape[0] + 1) * self.dt
        return np.column_stack([t, h])
