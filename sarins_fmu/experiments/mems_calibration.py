"""Seed 003: dynamic calibration of a MEMS IMU on a three-axis thermal rate table.

The paper's protocol (seed ``003_fa91fb144c9aac79``) as reusable functions:

* three recordings of the Turntable -> IMUThermal chain (``mems`` preset,
  200 Hz minor loop), co-simulated through the project's master
  (:func:`sarins.mems_calibration.recording.record_cosim`) or run in-process on the same library objects
  (:func:`record_in_process`, same numbers):

  - ``dynamic``: 10 min warm-up, then the inner / middle / outer gimbals
    sweep +-1 deg/s at 0.01 deg/s^2, +-10 deg/s at 0.1 deg/s^2 and +-100
    deg/s at 1 deg/s^2 while the chamber cycles between -25 and 40 degC,
    repeated (:func:`sarins_fmu.turntable.rate_table_3axis`,
    :func:`~sarins_fmu.thermal.chamber_profile`);
  - ``tumble``: the 24-position tumble, 3 min per position
    (:func:`~sarins_fmu.turntable.tumble_24`);
  - ``rates``: the rate test, 22 rates per axis within +-200 deg/s over whole
    revolutions (:func:`~sarins_fmu.turntable.rate_test`);

* the truth from the turntable outputs (:func:`truth_of`): the recorded
  gimbal angles and rates drive the library's error-free IMU (preset
  ``ideal``, same kinematics, Earth rate and gravity), which gives the exact
  mean angular rate and specific force of every communication step in body
  axes -- the table rates converted to body rates and gravity from the table
  angles, as in the paper, without the time-alignment error of sampling;
* the data sets (:func:`dynamic_dataset`): inputs (Wx, Wy, Wz, Ax, Ay, Az, T)
  = measured mean rate (rad/s), specific force (m/s^2) and the mean sensor
  temperature (degC); targets (wx, wy, wz, ax, ay, az) = truth; split by
  time into a training part (the first chamber cycle) and a held-out test
  part (the rest);
* the traditional calibration (:func:`traditional_calibration`): eqs (1)-(2)
  fitted by least squares to the tumble position means (accelerometers and
  gyros) and the rate-test window means (gyros).

Units: SI inside (rad/s, m/s^2, s), degC for temperatures.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .. import imu, thermal, turntable
from ..identify.calibration import TriadCalibration, fit_triad
from ..thermal import Ambient
from ..units import DEG_TO_RAD

LAT_DEG = 32.05  # Nanjing (the authors' university), deg
INPUT_NAMES = ("Wx", "Wy", "Wz", "Ax", "Ay", "Az", "T")
OUTPUT_NAMES = ("wx", "wy", "wz", "ax", "ay", "az")
KINDS = ("dynamic", "tumble", "rates")
GIMBALS = "z,x,y"  # turntable.RATE_TABLE_AXES as the IMU FMU's 'gimbals' parameter
AMBIENT_C = 20.0  # laboratory temperature of the tumble and rate test, degC


@dataclass(frozen=True)
class Profile:
    """Sizes of one campaign profile.

    Attributes
    ----------
    step : float
        Communication step of the dynamic recording, s (the IMU runs its
        200 Hz minor loop inside; one data sample per step).
    cal_step : float
        Communication step of the tumble and rate-test recordings, s; the
        table turns less than half a turn per step at 200 deg/s (an angle
        increment is a rotation vector, unique below 180 deg).
    warmup : float
        Static warm-up before the dynamic motion, s (paper: 10 min).
    cycles : int
        Chamber cycles of the dynamic recording (the first is for training).
    ramp_c_per_min, hold_min : float
        Chamber ramp rate (degC/min) and hold at each end (min); seed 003
        gives neither (our choice for 'paper': 1 degC/min, 30 min).
    tumble_dwell : float
        Static time per tumble position, s (paper: 3 min).
    rate_settle : float
        Constant-rate time before each rate-test window, s.
    internal_rate : float
        IMU minor-loop rate, Hz (paper: 200 Hz data).
    """

    step: float = 0.05
    cal_step: float = 0.1
    warmup: float = 600.0
    cycles: int = 2
    ramp_c_per_min: float = 1.0
    hold_min: float = 30.0
    tumble_dwell: float = 180.0
    rate_settle: float = 2.0
    internal_rate: float = 200.0

    def __post_init__(self):
        for name in ("step", "cal_step", "ramp_c_per_min", "tumble_dwell", "internal_rate"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"profile {name} must be positive, got {value}")
        for name in ("warmup", "hold_min", "rate_settle"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"profile {name} must not be negative, got {value}")
        if int(self.cycles) < 2:
            raise ValueError(f"profile cycles must be at least 2 (one to train, one to test), got {self.cycles}")
        if max(turntable.RATE_TEST_MAGNITUDES_DPS) * self.cal_step >= 180.0:
            raise ValueError(f"cal_step {self.cal_step} s: the rate test turns 180 deg or more per step")
        for name in ("step", "cal_step"):
            n = 1.0 / getattr(self, name)
            if abs(n - round(n)) > 1e-9:
                raise ValueError(f"profile {name} must divide the turntable's 1 s grid, got {getattr(self, name)}")

    @property
    def cycle_time(self) -> float:
        """One chamber cycle low -> high -> low, s."""
        return 2.0 * (40.0 + 25.0) / self.ramp_c_per_min * 60.0 + 2.0 * self.hold_min * 60.0

    @property
    def dynamic_duration(self) -> float:
        """Warm-up plus ``cycles`` chamber cycles, rounded up to 400 s (a table period), s."""
        return self.warmup + math.ceil(self.cycles * self.cycle_time / 400.0) * 400.0


PROFILES = {
    # a minute on one core: compressed chamber cycles, short dwells, coarser steps
    "quick": Profile(step=0.1, cal_step=0.25, cycles=2, ramp_c_per_min=13.0, hold_min=2.0,
                     tumble_dwell=10.0, rate_settle=0.0),
    "paper": Profile(),
}


def profile(name: str) -> Profile:
    """Named :class:`Profile` ('quick' or 'paper')."""
    try:
        return PROFILES[name]
    except KeyError:
        raise ValueError(f"unknown profile {name!r}; choose one of {', '.join(PROFILES)}") from None


# ------------------------------------------------------------------ set-ups
def turntable_parameters(kind: str, prof: Profile) -> dict:
    """Start values of the Turntable FMU for one recording (SI units)."""
    if kind == "dynamic":
        return dict(scheme="rate-table-3axis", duration=prof.dynamic_duration, warmup=prof.warmup,
                    ambient_mode="chamber", ambient_mean=AMBIENT_C, chamber_low=-25.0, chamber_high=40.0,
                    chamber_ramp=prof.ramp_c_per_min / 60.0, chamber_hold=prof.hold_min * 60.0)
    if kind == "tumble":
        return dict(scheme="tumble-24", dwell=prof.tumble_dwell, rate=10.0 * DEG_TO_RAD,
                    accel=10.0 * DEG_TO_RAD, duration=1.0, ambient_mean=AMBIENT_C)
    if kind == "rates":
        return dict(scheme="rate-test", dwell=prof.rate_settle, rate=10.0 * DEG_TO_RAD,
                    accel=10.0 * DEG_TO_RAD, duration=1.0, ambient_mean=AMBIENT_C)
    raise ValueError(f"unknown recording {kind!r}; choose one of {', '.join(KINDS)}")


def schedule_of(kind: str, prof: Profile):
    """(GimbalSchedule, windows or None) of a recording, as the Turntable FMU builds it."""
    p = turntable_parameters(kind, prof)
    if kind == "dynamic":
        return turntable.schedule_for("rate-table-3axis", p["duration"], warmup=p["warmup"]), None
    if kind == "tumble":
        return turntable.tumble_24(dwell=prof.tumble_dwell, rate_dps=10.0, accel_dps2=10.0)
    return turntable.rate_test(accel_dps2=10.0, position_rate_dps=10.0, settle=prof.rate_settle)


def ambient_of(kind: str, prof: Profile) -> Ambient:
    """Chamber / laboratory temperature of a recording (as the Turntable FMU makes it)."""
    if kind != "dynamic":
        return Ambient(mean=AMBIENT_C)
    return Ambient(profile=thermal.chamber_profile(
        prof.dynamic_duration, ramp_c_per_min=prof.ramp_c_per_min, hold_min=prof.hold_min, start_c=AMBIENT_C))


def stop_time(kind: str, prof: Profile) -> float:
    """End of a recording on its step grid, s."""
    sched, _ = schedule_of(kind, prof)
    step = prof.step if kind == "dynamic" else prof.cal_step
    return math.ceil(sched.end_time / step - 1e-9) * step


def imu_parameters(prof: Profile, seed: int, model_overrides: dict | None = None) -> dict:
    """Start values of the IMUThermal FMU (mems preset on the three-axis table)."""
    out = dict(preset="mems", gimbals=GIMBALS, internal_rate=prof.internal_rate, seed=int(seed),
               lat=LAT_DEG * DEG_TO_RAD, thermal_start="hot")
    out.update(model_overrides or {})
    return out


# --------------------------------------------------------------- recordings
def _default_base():
    return imu.StaticBase(LAT_DEG * DEG_TO_RAD)


def record_in_process(kind: str, prof: Profile, *, seed: int = 3, model: imu.ImuModel | None = None,
                      base=None, chunk: int = 20000) -> dict:
    """The same recording as :func:`sarins.mems_calibration.recording.record_cosim`, from the library in this process.

    ``base``: the turntable's base (default the static base at :data:`LAT_DEG`;
    any object with the moving-base interface ``base_motion``).
    """
    model = imu.preset("mems") if model is None else model
    base = _default_base() if base is None else base
    step = prof.step if kind == "dynamic" else prof.cal_step
    sched, _ = schedule_of(kind, prof)
    n = int(round(stop_time(kind, prof) / step))
    time = np.arange(n + 1) * step
    angle, rate, _ = sched.state(time)
    ambient = ambient_of(kind, prof)(time)
    sensor = imu.IMU(model, base, turntable.RATE_TABLE_AXES,
                     output_interval=step, internal_rate=prof.internal_rate, seed=seed, thermal_start="hot")
    sensor.reset(ambient0=float(ambient[0]))
    acc = (rate[1:] - rate[:-1]) / step
    a0, r0 = angle[:-1], rate[:-1]
    out = [sensor.step(a0[k:k + chunk], r0[k:k + chunk], acc[k:k + chunk], ambient=ambient[k + 1:k + 1 + chunk])
           for k in range(0, n, chunk)]
    return dict(time=time, angle=angle, rate=rate, ambient=ambient, dtheta=np.vstack([o[0] for o in out]),
                dv=np.vstack([o[1] for o in out]), temps=np.vstack([o[2] for o in out]))


def truth_of(rec: dict, internal_rate: float = 200.0, base=None) -> tuple[np.ndarray, np.ndarray]:
    """Exact mean body rate (rad/s) and specific force (m/s^2) of every step, (K, 3) each.

    The recorded turntable angles and rates drive the error-free IMU model
    (same kinematics, Earth rate, gravity of ``base``, default the static
    base at :data:`LAT_DEG`) over each step.
    """
    base = _default_base() if base is None else base
    t = rec["time"]
    step = float(t[1] - t[0])
    ideal = imu.IMU(imu.preset("ideal"), base, turntable.RATE_TABLE_AXES,
                    output_interval=step, internal_rate=internal_rate, seed=0)
    acc = (rec["rate"][1:] - rec["rate"][:-1]) / step
    dtheta, dv, _ = ideal.step(rec["angle"][:-1], rec["rate"][:-1], acc)
    return dtheta / step, dv / step


def measured_of(rec: dict) -> np.ndarray:
    """Network inputs (K, 7): mean measured rate (rad/s), specific force (m/s^2), mean sensor temperature (degC)."""
    step = float(rec["time"][1] - rec["time"][0])
    return np.column_stack([rec["dtheta"] / step, rec["dv"] / step, rec["temps"].mean(axis=1)])


# ----------------------------------------------------------------- datasets
@dataclass(frozen=True)
class Dataset:
    """Inputs X (n, 7) = INPUT_NAMES, targets Y (n, 6) = OUTPUT_NAMES, times (n,) s."""

    X: np.ndarray
    Y: np.ndarray
    time: np.ndarray

    def __len__(self) -> int:
        return len(self.time)


def dynamic_dataset(rec: dict, prof: Profile) -> tuple[Dataset, Dataset]:
    """Training (first chamber cycle after the warm-up) and test (the rest) sets.

    Samples of the warm-up are left out.  Time contiguous, so the recurrent
    models see the time series in order.
    """
    X = measured_of(rec)
    w, f = truth_of(rec, prof.internal_rate)
    Y = np.column_stack([w, f])
    t_end = rec["time"][1:]
    keep = t_end > prof.warmup + 1e-9
    split = prof.warmup + prof.dynamic_duration / max(prof.cycles, 1) - prof.warmup / max(prof.cycles, 1)
    train = keep & (t_end <= split)
    test = keep & (t_end > split)
    if not (train.any() and test.any()):
        raise ValueError("the dynamic recording is too short for a training and a test part")
    return Dataset(X[train], Y[train], t_end[train]), Dataset(X[test], Y[test], t_end[test])


def window_means(rec: dict, windows, internal_rate: float = 200.0, base=None) -> tuple[np.ndarray, np.ndarray]:
    """Mean measured (X columns 0-5) and true (rate, force) over each [start, end] window.

    Returns (measured (W, 6), truth (W, 6)).
    """
    X = measured_of(rec)[:, :6]
    w, f = truth_of(rec, internal_rate, base)
    Y = np.column_stack([w, f])
    t_end = rec["time"][1:]
    meas, true = [], []
    for row in windows:  # one mean per window (24 + 66 windows), not per sample
        sel = (t_end > row["start"] + 1e-9) & (t_end <= row["end"] + 1e-9)
        if not sel.any():
            raise ValueError(f"no sample inside the window [{row['start']}, {row['end']}] s")
        meas.append(X[sel].mean(axis=0))
        true.append(Y[sel].mean(axis=0))
    return np.array(meas), np.array(true)


@dataclass(frozen=True)
class TraditionalFit:
    """Eqs (1)-(2) fitted per triad, with the fitting points kept for the tables."""

    gyro: TriadCalibration
    accel: TriadCalibration
    gyro_rms_residual: float  # rad/s, over the fitting points
    accel_rms_residual: float  # m/s^2


def traditional_calibration(tumble: dict, rates: dict, prof: Profile, base=None) -> TraditionalFit:
    """Least-squares bias, scale factor and misalignment of both triads.

    Accelerometers: the 24 tumble position means against gravity in each
    position.  Gyros: the 24 tumble means (Earth rate) and the 66 rate-test
    window means (table rate plus Earth rate, whole revolutions).
    """
    _, positions = schedule_of("tumble", prof)
    _, windows = schedule_of("rates", prof)
    m_t, t_t = window_means(tumble, positions, prof.internal_rate, base)
    m_r, t_r = window_means(rates, windows, prof.internal_rate, base)
    accel = fit_triad(t_t[:, 3:], m_t[:, 3:])
    g_true, g_meas = np.vstack([t_t[:, :3], t_r[:, :3]]), np.vstack([m_t[:, :3], m_r[:, :3]])
    gyro = fit_triad(g_true, g_meas)
    rms = lambda cal, u, y: float(np.sqrt(np.mean((cal.bias + u @ cal.matrix.T - y) ** 2)))  # noqa: E731
    return TraditionalFit(gyro, accel, rms(gyro, g_true, g_meas), rms(accel, t_t[:, 3:], m_t[:, 3:]))


def with_profile(prof: Profile, **changes) -> Profile:
    """Copy of a profile with some fields changed (validated by the recordings)."""
    return replace(prof, **changes)
