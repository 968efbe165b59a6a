"""Lumped thermal model of the IMU.

Each sensor (gyro x, y, z, accelerometer x, y, z) is a first-order lumped
body heated by the electronics and coupled to the ambient (or thermal
chamber) temperature:

    dT_j/dt = (T_amb(t) + dT_self_j - T_j) / tau_j

A **cold start** begins at the ambient temperature and warms up by
``dT_self`` with time constant ``tau`` (seed 000: the temperature rises by
more than 10 degC during a 4 h alignment); a **hot start** begins in
equilibrium, so only ambient changes move it (seed 000: less than 3 degC).

The ambient is sampled on the simulation grid and taken piecewise linear in
between; each step is then integrated exactly, so the solution does not
depend on the step size.  Temperatures in degC, times in s.

**Die lag.**  The temperature this model gives is what the unit *reports*
(its temperature sensor).  The sensing element (MEMS die, gyro block) sits
behind a further thermal resistance, so its temperature lags the reported
one: a second first-order stage
    dT_die_j/dt = (T_j - T_die_j) / tau_die_j
(``ThermalParams.die_time_constant``; 0 means the die is at the reported
temperature).  This is the two-node lumped network (sensor node, die node)
of e.g. Groves, *Principles of GNSS, Inertial and Multisensor Integrated
Navigation*, 2nd ed., sec. 4.4.5 on thermal lag; it is why a bias modelled as
a function of the reported temperature shows a loop on a chamber ramp.
:func:`die_temperatures` integrates it exactly for a reported temperature
taken linear over each output interval.

The exact steps run in the C core (``sarins_fmu/core/thermal.c``,
:mod:`sarins_fmu.core.thermal`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .checks import number
from .core import schedule as core_schedule
from .core.thermal import die_temperatures, exact_steps  # noqa: F401 (die_temperatures: part of this API)

SENSORS = ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")
N_SENSORS = len(SENSORS)
START_KINDS = ("hot", "cold")


@dataclass(frozen=True)
class ThermalParams:
    """Constants of the lumped thermal model.

    Attributes
    ----------
    self_heating : tuple of 6 floats
        Equilibrium rise of each sensor above ambient, degC.
    time_constant : tuple of 6 floats
        Warm-up time constant of each sensor, s.
    die_time_constant : tuple of 6 floats
        Lag of each sensing die behind the reported temperature, s (0: none).
    """

    self_heating: tuple = (16.0, 16.5, 17.0, 15.0, 15.2, 15.4)
    # 4.3-5.0 h: inside the 2.9-7.5 h that seed 000's Tables 4-5 give for the warm-up of an RLG INS
    # (docs/imu-presets.md, nav-rlg `time_constant_*`); the per-sensor spread is ours
    time_constant: tuple = (16800.0, 17400.0, 18000.0, 15500.0, 15800.0, 16100.0)
    die_time_constant: tuple = (0.0,) * 6

    @property
    def has_die_lag(self) -> bool:
        return any(t > 0 for t in self.die_time_constant)

    def __post_init__(self):
        if np.any(np.asarray(self.die_time_constant, float) < 0):
            raise ValueError("thermal die_time_constant must be non-negative")
        for name in ("self_heating", "time_constant", "die_time_constant"):
            value = np.asarray(getattr(self, name), float)
            if value.shape != (N_SENSORS,) or not np.isfinite(value).all():
                raise ValueError(f"thermal {name} needs {N_SENSORS} finite values")
        if np.any(np.asarray(self.time_constant) <= 0):
            raise ValueError("thermal time constants must be positive")


@dataclass(frozen=True)
class Ambient:
    """Ambient (or chamber) temperature: mean + daily sinusoid + linear drift.

    T_amb(t) = mean + amplitude sin(2 pi t / period + phase) + slope t, degC.
    For a chamber profile pass ``profile`` = (times s, temperatures degC): it
    replaces the formula and is interpolated linearly (held at both ends).
    """

    mean: float = 20.0
    amplitude: float = 0.0
    period: float = 86400.0
    phase: float = 0.0
    slope: float = 0.0
    profile: tuple | None = field(default=None)

    def __call__(self, time):
        """T_amb at ``time`` (s, scalar or array), degC: a float for a scalar, else an array of its shape
        (the C core's ``sarins_ambient_values``)."""
        return core_schedule.ambient_values(time, *self._fields())

    def _fields(self) -> tuple:
        return self.mean, self.amplitude, self.period, self.phase, self.slope, self.profile


def ambient_segment(ambient: Ambient, time: float, span: float) -> tuple[float, float]:
    """Ambient at ``time`` and its slope over [time, time + span] (degC, degC/s).

    The ambient as an IMU sees it across a co-simulation boundary: sampled on
    a grid of ``span`` s and linear in between (the thermal model's own
    assumption), so value + slope * tau rebuilds it over the step from the
    start-of-step values alone (the C core's ``sarins_ambient_segment``).
    """
    if not isinstance(ambient, Ambient):
        raise TypeError(f"ambient_segment needs an Ambient, got {type(ambient).__name__}")
    return core_schedule.ambient_segment(time, span, *ambient._fields())


class ThermalModel:
    """Stateful lumped thermal model stepped on a time grid.

    Parameters
    ----------
    params : ThermalParams
    ambient : callable
        T_amb(time s) -> degC, vectorised (e.g. :class:`Ambient`).
    start : {'hot', 'cold'}
        Initial condition at ``t0``.
    t0 : float
        Start time, s.
    """

    def __init__(self, params: ThermalParams = ThermalParams(), ambient=Ambient(), start: str = "hot",
                 t0: float = 0.0):
        if start not in START_KINDS:
            raise ValueError(f"thermal start must be 'hot' or 'cold', got {start!r}")
        self.params, self.ambient, self.start = params, ambient, start
        self._heat = np.asarray(params.self_heating, float)
        self._tau = np.asarray(params.time_constant, float)
        self.reset(t0)

    def reset(self, t0: float = 0.0, ambient0: float | None = None) -> None:
        """Return to the initial condition at ``t0`` (ambient there from the
        ambient function, or ``ambient0`` degC when given)."""
        self.time = float(t0)
        t_amb = float(self.ambient(t0) if ambient0 is None else ambient0)
        _check_temperature(t_amb)
        self._ambient_now = t_amb
        self.temperature = np.full(N_SENSORS, t_amb) + (self._heat if self.start == "hot" else 0.0)

    def rate(self, temperature, time):
        """dT/dt (degC/s) for temperatures (..., 6) at times (...)."""
        t_amb = np.asarray(self.ambient(time), float)[..., None]
        return (t_amb + self._heat - temperature) / self._tau

    def advance(self, times, ambient=None):
        """Integrate exactly to each of ``times`` (K,) and return T (K, 6), degC.

        ``times`` must be increasing and not before the current time.  The
        ambient is taken linear between successive times; its values at
        ``times`` come from the ambient function, or from ``ambient`` (K,)
        degC when given (e.g. a chamber temperature received as an input).
        """
        times = np.asarray(times, dtype=float).reshape(-1)
        if times.size == 0:
            return np.empty((0, N_SENSORS))
        h = np.empty_like(times)
        h[0] = times[0] - self.time
        h[1:] = times[1:] - times[:-1]
        if not (h.min() >= 0 and np.isfinite(h).all()):
            raise ValueError("thermal model times must be finite and increasing")
        amb = np.empty(times.size + 1)
        amb[0] = self._ambient_now
        amb[1:] = self.ambient(times) if ambient is None else ambient
        _check_temperature(amb)
        out = exact_steps(h, amb, self._heat, self._tau, self.temperature)
        self.time = float(times[-1])
        self._ambient_now = float(amb[-1])
        self.temperature = out[-1].copy()
        return out


def _check_temperature(values) -> None:
    """An ambient (degC) within [-273.15, AMBIENT_MAX] (SARINS_IMU_AMBIENT_MAX, the core's imu_build.h: the IMU's
    parameter bounds are derived for that range)."""
    from .core.imu import AMBIENT_MAX

    values = np.asarray(values, float)
    if not np.isfinite(values).all() or np.any(values < -273.15) or np.any(values > AMBIENT_MAX):
        raise ValueError(f"ambient temperature must be finite, above absolute zero and at most {AMBIENT_MAX:g} degC "
                         "(SARINS_IMU_AMBIENT_MAX)")


def chamber_profile(duration: float, *, low_c: float = -25.0, high_c: float = 40.0,
                    ramp_c_per_min: float = 1.0, hold_min: float = 30.0, start_c: float = 20.0,
                    delay: float = 0.0, first: str = "low", step_c: float = 0.0,
                    step_hold_min: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Thermal-chamber temperature of seed 003's dynamic calibration.

    Seed 003 states only that the chamber is driven between -25 and 40 degC
    while the table turns, repeatedly; it gives no ramp rate or hold time, so
    ``ramp_c_per_min`` = 1 degC/min and ``hold_min`` = 30 min are our choice.
    The profile is piecewise linear::

        start_c for ``delay`` s, ramp to low_c, hold, ramp to high_c, hold,
        ramp to low_c, hold, ... (cold end first; ``first='high'``: hot end first)

    cut at ``duration`` (the last value interpolated).  With the defaults one
    cycle low -> high -> low takes 2 * 65 min + 2 * 30 min = 190 min.  With
    ``step_c`` > 0 every ramp between the ends also stops for
    ``step_hold_min`` at each ``step_c`` from the end it leaves (a staircase,
    the soak-at-several-temperatures programme of thermal calibrations);
    the first ramp from ``start_c`` has no intermediate stops.

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
        warm-up of :func:`sarins_fmu.turntable.rate_table_3axis`).
    first : 'low' or 'high'
        End the first ramp goes to.
    step_c : float
        Spacing of the intermediate stops on the ramps between the ends,
        degC, >= 0 (0: none).
    step_hold_min : float
        Length of each intermediate stop, min, >= 0.

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
        low_c >= high_c (the C core's reason, in its units: ramp degC/s,
        holds s; ``sarins_chamber_build``).
    """
    return core_schedule.chamber_profile(
        number("duration", duration), number("low_c", low_c), number("high_c", high_c),
        number("ramp_c_per_min", ramp_c_per_min) / 60.0, number("hold_min", hold_min) * 60.0,
        number("start_c", start_c), number("delay", delay), first, number("step_c", step_c),
        number("step_hold_min", step_hold_min) * 60.0)


def chamber_cycle_time(*, low_c: float = -25.0, high_c: float = 40.0, ramp_c_per_min: float = 1.0,
                       hold_min: float = 30.0, step_c: float = 0.0, step_hold_min: float = 0.0) -> float:
    """Length of one cycle of :func:`chamber_profile` (end -> other end -> end, holds included), s."""
    return core_schedule.chamber_cycle_time(
        number("low_c", low_c), number("high_c", high_c), number("ramp_c_per_min", ramp_c_per_min) / 60.0,
        number("hold_min", hold_min) * 60.0, number("step_c", step_c), number("step_hold_min", step_hold_min) * 60.0)
