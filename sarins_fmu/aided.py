"""Aided navigation in process: an IMU with white noise and biases on a trajectory's ideal
increments, GNSS fixes, zero-velocity updates at stops, and the core's 15-state error-state
Kalman filter (``sarins_fmu/core/eskf.h``, its header states the model) with feedback; optionally with
scale-factor, lever-arm and receiver Gauss-Markov states (``navigate(..., filter_states=...)``).

Frames and units: navigation ENU, body right-front-up, SI.  Errors are computed - true: position
(E, N, U m), velocity (ENU m/s) and attitude phi (ENU rad, mat_nb,computed = (I - [phi x]) mat_nb).

The IMU errors of an aided run (:class:`ImuNoise`) are white angle and velocity random walks, a
constant bias per axis drawn from N(0, sigma^2) for each seed, and bias random walks, added to the
ideal increments of :mod:`sarins_fmu.trajectory` (vectorised numpy).  An odometer (core ``odo.h``)
measures the forward speed; the non-holonomic constraint says the body's lateral and vertical
velocities are zero while moving.  Stops are known from the
trajectory (a vehicle's brake / odometer signal; ``zupt_detect='truth'``, a ZUPT at every IMU step
where the vehicle stands still, ``Truth.stationary``) or detected from the IMU's statistics
(``zupt_detect='imu'``, :mod:`sarins_fmu.zero_velocity`, with the vehicle's vibration while moving).  A stopped
vehicle still jitters (engine, wind, people): the zero-velocity pseudo-measurement carries white
errors of ``FilterSettings.zupt_std`` per axis, simulated with the std the filter assumes (an
exact zero measured with an assumed std would make the filter pessimistic at stops).  At the same
stop steps a zero-angular-rate update (ZARU, aiding ``'zaru'``) compares the step's compensated gyro
rate with the Earth's rate seen in the body; its noise is the gyro's own (white angle noise over one
step, std ``arw / sqrt(h)``), so nothing is simulated for it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import earth
from . import gnss as gnss_mod
from .core import aided as _core
from .rotations import euler_to_mat
from .units import DPH_TO_RPS, DPSH_TO_RPSS, UG_TO_MPS2

AIDING = ("gnss", "zupt", "odometer", "nhc", "zaru")
# optional filter states (eskf.h): sf gyro and accelerometer scale factors (6), lever the GNSS antenna lever arm
# (3), gnss-gm the receiver's Gauss-Markov position (3) and, with gnss_velocity, velocity (3) errors
FILTER_STATES = ("sf", "lever", "gnss-gm")
ZUPT_DETECT = ("truth", "imu")  # where ZUPTs come from: the trajectory's stops, or the IMU's statistics
COVARIANCE = ("full", "diagonal")  # what navigate's result keeps of the filter's P


@dataclass(frozen=True)
class ImuNoise:
    """IMU errors of an aided run (SI, same on each axis).

    arw: rad/sqrt(s); vrw: m/s/sqrt(s); gyro_bias_std: rad/s; accel_bias_std: m/s^2 (the per-seed
    constant biases' std); gyro_rw: rad/s/sqrt(s); accel_rw: m/s^2/sqrt(s) (bias random walks);
    gyro_sf_std, accel_sf_std: the per-seed constant scale-factor errors' std (1; 0 by default, drawn by
    :func:`corrupt`'s 'numpy' stream only: the core's ``aided_imu.h`` has none).
    """

    arw: float = 0.0
    vrw: float = 0.0
    gyro_bias_std: float = 0.0
    accel_bias_std: float = 0.0
    gyro_rw: float = 0.0
    accel_rw: float = 0.0
    gyro_sf_std: float = 0.0  # 1: per-seed constant scale-factor error per axis, N(0, std^2) (stream 'numpy' only)
    accel_sf_std: float = 0.0  # 1

    def __post_init__(self):
        for name in self.__dataclass_fields__:
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"IMU {name} must be a non-negative number, got {value!r}")

    def array(self) -> np.ndarray:
        """The settings array of the core's ``aided_imu.h`` (arw, vrw, gyro_bias_std, accel_bias_std,
        gyro_rw, accel_rw; SI; the scale factors are not in it)."""
        return np.array([self.arw, self.vrw, self.gyro_bias_std, self.accel_bias_std, self.gyro_rw, self.accel_rw])


# Hypothetical grades (our choice, round numbers typical of the class; no data sheet):
IMU_NOISE = {
    "ideal": ImuNoise(),
    "tactical": ImuNoise(arw=0.1 * DPSH_TO_RPSS, vrw=50.0 * UG_TO_MPS2, gyro_bias_std=1.0 * DPH_TO_RPS,
                         accel_bias_std=100.0 * UG_TO_MPS2, gyro_rw=0.01 * DPH_TO_RPS / 60.0,
                         accel_rw=1.0 * UG_TO_MPS2 / 60.0),
    "mems": ImuNoise(arw=0.15 * DPSH_TO_RPSS, vrw=100.0 * UG_TO_MPS2, gyro_bias_std=10.0 * DPH_TO_RPS,
                     accel_bias_std=2000.0 * UG_TO_MPS2, gyro_rw=3.0 * DPH_TO_RPS / 60.0,
                     accel_rw=10.0 * UG_TO_MPS2 / 60.0),
}


IMU_STREAMS = ("numpy", "core")  # where corrupt's draws come from


def corrupt(truth, noise: ImuNoise, seed: int, stream: str = "numpy"):
    """Increments with errors, and the true biases per step.

    Returns dtheta, dv (K, 3) and bias_g, bias_a (K, 3) (the bias over each step, rad/s, m/s^2):
        dtheta = dtheta_true + b_g h + arw sqrt(h) n,   dv = dv_true + b_a h + vrw sqrt(h) n,
        b(t_k) = b_0 + sum rw sqrt(h) n,   b_0 ~ N(0, bias_std^2).
    stream : 'numpy' (numpy's generator seeded [seed, 3017]: the draws of every aided run so far) or
        'core' (the C core's ``aided_imu.h``, stream 32 of ``seed``, the recursion b(t_{k+1}) = b(t_k) +
        rw sqrt(h) n: the draws the TrajectoryIMU FMU makes one step at a time, bit for bit).
    """
    if stream == "core":
        if noise.gyro_sf_std or noise.accel_sf_std:
            raise ValueError("IMU scale-factor errors are drawn by the 'numpy' stream only (the core's aided_imu.h "
                             "has none)")
        dtheta, dv, bias = _core.aided_imu_run(noise.array(), truth.step, seed, truth.dtheta, truth.dv)
        return dtheta, dv, bias[:, :3], bias[:, 3:]
    if stream != "numpy":
        raise ValueError(f"IMU stream must be one of {', '.join(IMU_STREAMS)}, got {stream!r}")
    rng = np.random.default_rng([seed, 3017])
    k, h = truth.n_steps, truth.step
    b0 = rng.standard_normal((2, 3)) * [[noise.gyro_bias_std], [noise.accel_bias_std]]
    walk = rng.standard_normal((2, k, 3)) * math.sqrt(h)
    bias_g = b0[0] + noise.gyro_rw * np.concatenate([np.zeros((1, 3)), np.cumsum(walk[0], axis=0)[:-1]])
    bias_a = b0[1] + noise.accel_rw * np.concatenate([np.zeros((1, 3)), np.cumsum(walk[1], axis=0)[:-1]])
    white = rng.standard_normal((2, k, 3)) * math.sqrt(h)
    dtheta = truth.dtheta + bias_g * h + noise.arw * white[0]
    dv = truth.dv + bias_a * h + noise.vrw * white[1]
    if noise.gyro_sf_std or noise.accel_sf_std:  # dtheta = (1 + s_g) dtheta_true + ..., own draws: the rest unmoved
        sg, sa = scale_factors(noise, seed)
        dtheta, dv = dtheta + sg * truth.dtheta, dv + sa * truth.dv
    return dtheta, dv, bias_g, bias_a


def scale_factors(noise: ImuNoise, seed: int):
    """The per-seed constant scale-factor errors (3,) gyro and (3,) accelerometer (1) :func:`corrupt` applies,
    N(0, std^2) from numpy's generator seeded [seed, 3019] (zeros when the stds are 0)."""
    z = np.random.default_rng([seed, 3019]).standard_normal((2, 3))
    return noise.gyro_sf_std * z[0], noise.accel_sf_std * z[1]


@dataclass(frozen=True)
class FilterSettings:
    """Filter tuning (SI).  By default the filter's IMU noise equals the simulated IMU's.

    zaru_std : rad/s, the zero-angular-rate update's std per IMU step; None (default): the gyro's white
        rate noise over one step, ``arw / sqrt(h)`` of the run's :class:`ImuNoise` and step h
        (:func:`zaru_std`; tactical at 100 Hz: 2.9e-4 rad/s).
    """

    pos0_std: float = 1.0  # m
    vel0_std: float = 0.1  # m/s
    tilt0_std: float = 1e-3  # rad
    heading0_std: float = 5e-3  # rad
    zupt_std: float = 0.01  # m/s
    nhc_std: float = 0.05  # m/s, lateral and vertical body velocity (non-holonomic constraint)
    cov_every: int = 10  # IMU steps per covariance propagation
    out_every: int = 10  # IMU steps per output row
    zaru_std: float | None = None  # rad/s per step; None: arw / sqrt(h) (see the class docstring)
    # optional states (navigate's filter_states): priors, and the lever arm the filter is configured with
    gyro_sf0_std: float = 1e-3  # 1 (1000 ppm), 'sf'
    accel_sf0_std: float = 1e-3  # 1, 'sf'
    sf_tau: float = 0.0  # s, 'sf': 0 random constants, else first-order Gauss-Markov (Q = 2 std^2 / tau)
    lever0_std: float = 0.1  # m, 'lever'
    lever_arm: tuple | None = None  # m, body: the lever arm the filter assumes; None: the receiver's (GNSSConfig)

    def __post_init__(self):
        for name in ("pos0_std", "vel0_std", "tilt0_std", "heading0_std", "zupt_std", "nhc_std"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"filter {name} must be positive, got {value!r}")
        value = self.zaru_std
        if value is not None and not (isinstance(value, (int, float)) and not isinstance(value, bool)
                                      and math.isfinite(value) and value > 0):
            raise ValueError(f"filter zaru_std must be positive (rad/s) or None, got {self.zaru_std!r}")
        for name in ("cov_every", "out_every"):
            if not (isinstance(getattr(self, name), int) and 1 <= getattr(self, name) <= 1000):
                raise ValueError(f"filter {name} must be a whole number 1 .. 1000")
        for name in ("gyro_sf0_std", "accel_sf0_std", "lever0_std"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"filter {name} must be positive, got {value!r}")
        if not (isinstance(self.sf_tau, (int, float)) and math.isfinite(self.sf_tau) and self.sf_tau >= 0):
            raise ValueError(f"filter sf_tau must be >= 0 s (0: random constants), got {self.sf_tau!r}")
        if self.lever_arm is not None and not (len(self.lever_arm) == 3
                                               and all(math.isfinite(x) for x in self.lever_arm)):
            raise ValueError(f"filter lever_arm must be three finite numbers (m) or None, got {self.lever_arm!r}")


@dataclass(frozen=True)
class AidedResult:
    """An aided run at the output rate: time (n,) s; nav (n, 9) computed lat, lon, h, v, yaw, pitch,
    roll; truth (n, 9) the same of the truth; error (n, 9) position ENU m, velocity ENU m/s, attitude
    phi ENU rad; cov (n, 15, 15) the filter's P, or None when the run kept only its diagonal
    (``navigate(..., covariance="diagonal")``); bias_g, bias_a (n, 3) estimates; bias_g_true,
    bias_a_true (n, 3); variance (n, 15) P's diagonal (SI squared, the error state's order).  With optional
    filter states (``navigate(..., filter_states=...)``) cov and variance have n states (15 .. 30) and
    ``states`` holds each optional block's estimate (n_out, 3) by name ('scale_g', 'scale_a' (1), 'lever' (body
    m), 'gnss_pos_gm' (ENU m), 'gnss_vel_gm' (ENU m/s)); ``state_index`` its first index in P."""

    time: np.ndarray
    nav: np.ndarray
    truth: np.ndarray
    error: np.ndarray
    cov: np.ndarray
    bias_g: np.ndarray
    bias_a: np.ndarray
    bias_g_true: np.ndarray
    bias_a_true: np.ndarray
    gnss_used: int = 0
    zupt_steps: int = 0
    zaru_steps: int = 0
    info: dict = field(default_factory=dict)
    variance: np.ndarray | None = None
    states: dict = field(default_factory=dict)
    state_index: dict = field(default_factory=dict)

    def state_sigma(self, name: str) -> np.ndarray:
        """(n_out, 3) the filter's std of the optional block ``name`` (see ``states``)."""
        i = self.state_index[name]
        return np.sqrt(self.variance[:, i:i + 3])

    def nees(self, block: str) -> np.ndarray:
        """(n,) normalised estimation error squared of 'position', 'velocity' or 'attitude' (3 dof)."""
        if self.cov is None:
            raise ValueError("NEES needs the filter's full covariance: this run kept its diagonal only "
                             "(navigate(..., covariance='diagonal'))")
        i = {"position": 0, "velocity": 3, "attitude": 6}[block]
        e = self.error[:, i:i + 3]
        p = self.cov[:, i:i + 3, i:i + 3]
        return np.einsum("ni,ni->n", e, np.linalg.solve(p, e[..., None])[..., 0])

    def horizontal_error(self) -> np.ndarray:
        """(n,) horizontal position error, m."""
        return np.hypot(self.error[:, 0], self.error[:, 1])

    def horizontal_sigma(self) -> np.ndarray:
        """(n,) filter's predicted horizontal sigma sqrt(P_EE + P_NN), m."""
        if self.variance is not None:
            return np.sqrt(self.variance[:, 0] + self.variance[:, 1])
        return np.sqrt(self.cov[:, 0, 0] + self.cov[:, 1, 1])


def nav_errors(nav: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """(n, 9) errors computed - true of rows (n, 9): position ENU m, velocity m/s, attitude phi rad."""
    r_m, r_n = earth.radii(truth[:, 0])
    pos = np.column_stack([(nav[:, 1] - truth[:, 1]) * (r_n + truth[:, 2]) * np.cos(truth[:, 0]),
                           (nav[:, 0] - truth[:, 0]) * (r_m + truth[:, 2]), nav[:, 2] - truth[:, 2]])
    c_c = euler_to_mat(nav[:, 6], nav[:, 7], nav[:, 8])
    c_t = euler_to_mat(truth[:, 6], truth[:, 7], truth[:, 8])
    m = np.einsum("nij,nkj->nik", c_c, c_t)  # C_c C_t' = I - [phi x]
    phi = 0.5 * np.column_stack([m[:, 1, 2] - m[:, 2, 1], m[:, 2, 0] - m[:, 0, 2], m[:, 0, 1] - m[:, 1, 0]])
    return np.column_stack([pos, nav[:, 3:6] - truth[:, 3:6], phi])


@dataclass(frozen=True)
class OdometerConfig:
    """Wheel odometer (core ``odo.h``): forward speed at ``rate_hz`` with a scale-factor error (not
    estimated by the 15-state filter: keep it 0 for consistent runs), white noise (m/s) and speed
    resolution (m/s).  Defaults hypothetical (our choice): 10 Hz, 0.02 m/s, 0.01 m/s resolution."""

    rate_hz: float = 10.0
    scale_factor: float = 0.0
    noise_std: float = 0.02
    resolution: float = 0.01

    def __post_init__(self):
        if not (math.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ValueError(f"odometer rate must be positive, got {self.rate_hz}")
        if not (math.isfinite(self.noise_std) and self.noise_std >= 0 and math.isfinite(self.resolution)
                and self.resolution >= 0):
            raise ValueError("odometer noise std and resolution must not be negative")

    def std(self) -> float:
        """Measurement std the filter uses: noise and quantisation (res^2 / 12), m/s."""
        return max(math.sqrt(self.noise_std**2 + self.resolution**2 / 12.0), 1e-6)


ZARU_STD_FLOOR = 1e-12  # rad/s: the std of an ideal gyro's (arw = 0) rate, kept positive as the core requires


def zaru_std(noise: ImuNoise, settings: FilterSettings, step: float) -> float:
    """The ZARU std the filter uses, rad/s: ``settings.zaru_std``, or by default the white rate noise of
    one step of the gyro, ``arw / sqrt(step)`` (an angle random walk arw rad/sqrt(s) integrated over h
    gives an angle std arw sqrt(h), a mean rate std arw / sqrt(h)); at least ZARU_STD_FLOOR."""
    if settings.zaru_std is not None:
        return float(settings.zaru_std)
    return max(noise.arw / math.sqrt(step), ZARU_STD_FLOOR)


def _config(noise: ImuNoise, settings: FilterSettings, gnss_cfg, step: float, odometer=None) -> np.ndarray:
    lever = gnss_cfg.lever_arm if gnss_cfg is not None else (0.0, 0.0, 0.0)
    if settings.lever_arm is not None:
        lever = settings.lever_arm
    latency = gnss_cfg.latency if gnss_cfg is not None else 0.0
    odo_std = odometer.std() if odometer is not None else 1.0
    return np.array([step, noise.arw, noise.vrw, noise.gyro_rw, noise.accel_rw, settings.pos0_std, settings.vel0_std,
                     settings.tilt0_std, settings.heading0_std, max(noise.gyro_bias_std, 1e-12),
                     max(noise.accel_bias_std, 1e-12), *lever, latency, settings.zupt_std, settings.cov_every,
                     settings.nhc_std, odo_std, zaru_std(noise, settings, step)])


BLOCKS = (("scale_g", _core.ESKF_SF), ("scale_a", _core.ESKF_SF), ("lever", _core.ESKF_LEVER),
          ("gnss_pos_gm", _core.ESKF_GNSS_POS_GM), ("gnss_vel_gm", _core.ESKF_GNSS_VEL_GM))  # eskf.h's order
GM_STD_FLOOR = 1e-6  # m, m/s: the fixes' white std the filter uses with 'gnss-gm' is at least this


def check_filter_states(filter_states, aiding) -> tuple:
    """The filter_states as a tuple; ValueError naming an unknown one, or 'lever' / 'gnss-gm' without GNSS."""
    states = tuple(filter_states)
    unknown = sorted(set(states) - set(FILTER_STATES))
    if unknown:
        raise ValueError(f"unknown filter states {', '.join(unknown)}; choose from {', '.join(FILTER_STATES)}")
    needs = [s for s in ("lever", "gnss-gm") if s in states and "gnss" not in aiding]
    if needs:
        raise ValueError(f"filter states {', '.join(needs)} need 'gnss' in the aiding")
    return states


def state_mask(filter_states, gnss_velocity: bool = True) -> int:
    """The core's STATES bit set (eskf.h) of filter_states."""
    mask = _core.ESKF_SF if "sf" in filter_states else 0
    mask |= _core.ESKF_LEVER if "lever" in filter_states else 0
    if "gnss-gm" in filter_states:
        mask |= _core.ESKF_GNSS_POS_GM | (_core.ESKF_GNSS_VEL_GM if gnss_velocity else 0)
    return mask


def _options(filter_states, settings: FilterSettings, gnss_cfg, gnss_velocity: bool):
    """The core's options array (eskf.h SARINS_ESKF_OPT) of filter_states, or None for the 15 states."""
    if not filter_states:
        return None
    g = gnss_cfg if gnss_cfg is not None else gnss_mod.GNSSConfig()
    return np.array([state_mask(filter_states, gnss_velocity), settings.gyro_sf0_std, settings.accel_sf0_std,
                     settings.sf_tau, settings.lever0_std, *g.pos_gm_std, g.pos_gm_tau, *g.vel_gm_std, g.vel_gm_tau],
                    float)


def _initial_state(truth, settings: FilterSettings, rng) -> np.ndarray:
    """Start row with errors drawn from the filter's initial covariance."""
    row = truth.nav_rows([0])[0]
    e = rng.standard_normal(9)
    r_m, r_n = earth.radii(row[0])
    row[0] += settings.pos0_std * e[1] / (r_m + row[2])
    row[1] += settings.pos0_std * e[0] / ((r_n + row[2]) * math.cos(row[0]))
    row[2] += settings.pos0_std * e[2]
    row[3:6] += settings.vel0_std * e[3:6]
    phi = np.array([settings.tilt0_std * e[6], settings.tilt0_std * e[7], settings.heading0_std * e[8]])
    # computed = (I - [phi x]) true
    from .rotations import mat_to_euler, rotvec_to_mat
    c = rotvec_to_mat(-phi) @ euler_to_mat(*row[6:9])
    row[6:9] = mat_to_euler(c)
    return row


def fix_rows(fixes, config, step: float, white: bool = False) -> np.ndarray:
    """(m, 11) fix rows of ``sarins_eskf_run``: each applied after the IMU step at which it is available; the
    position std the receiver's total, or with ``white`` its white part (the filter then models the
    Gauss-Markov part as states), at least GM_STD_FLOOR."""
    index = np.ceil(fixes.available / step - 1e-9) - 1.0
    pos_std = np.maximum(config.pos_white_std, GM_STD_FLOOR) if white else config.pos_std()
    std = np.tile(pos_std, (fixes.time.size, 1))
    return np.column_stack([index, fixes.valid.astype(float), fixes.lat, fixes.lon, fixes.height, fixes.velocity_n,
                            std])


def body_speed(truth) -> np.ndarray:
    """(K+1,) true forward speed (body y), m/s: (mat_bn v^n)_y, the core's ``sarins_odo_forward_speed`` (the
    TrajectoryIMU FMU's odometer computes it the same way)."""
    return _core.odo_forward_speed(truth.velocity_n, truth.attitude)


def per_step_aiding(truth, aiding, settings: FilterSettings, odometer, rng, seed: int, stops=None,
                    stream: str = "numpy") -> np.ndarray:
    """(K, 10) rows of ``sarins_eskf_run``: ZUPT and / or ZARU at stops (``stops`` (K,) bool: the steps
    declared stationary; default the truth's), odometer speeds at its rate, NHC while moving.
    The trajectories have no side-slip or bounce, so the zero-velocity and non-holonomic pseudo-
    measurements carry simulated white jitter of the std the filter assumes (``zupt_std``, ``nhc_std``):
    a real vehicle's stop and wheels violate them by about that much.  ``stream``: where the jitter is drawn,
    'numpy' (``rng``: the ZUPT's (K, 3) normals, then the NHC's (K, 2)) or 'core' (stream 33 of ``seed``,
    ``aid_noise.h``: five normals per step whatever is aided, the TrajectoryIMU FMU's ``zupt_v_*`` and
    ``nhc_v_*`` with ``jitter_seed`` = ``seed``)."""
    if stream not in IMU_STREAMS:
        raise ValueError(f"stream must be one of {', '.join(IMU_STREAMS)}, got {stream!r}")
    k = truth.n_steps
    aid = np.zeros((k, _core.ESKF_AID))
    needs_still = (("zupt" in aiding or "zaru" in aiding) and stops is None) or "nhc" in aiding
    still = truth.stationary() if needs_still else None
    if "zupt" in aiding:
        aid[:, 0] = still if stops is None else stops
    if "nhc" in aiding:
        aid[:, 6] = ~still
    if stream == "core" and ("zupt" in aiding or "nhc" in aiding):
        jitter = _core.aid_noise_run(settings.zupt_std, settings.nhc_std, seed, aid[:, 0], aid[:, 6])
        aid[:, 1:4], aid[:, 7:9] = jitter[:, :3], jitter[:, 3:]
    elif "zupt" in aiding:  # a stop's jitter: white, the std the filter assumes
        aid[:, 1:4] = aid[:, :1] * settings.zupt_std * rng.standard_normal((k, 3))
    if "zaru" in aiding:  # the measurement is the gyro's own rate: nothing drawn
        aid[:, 9] = still if stops is None else stops
    if "odometer" in aiding:
        every = max(1, round(1.0 / (odometer.rate_hz * truth.step)))
        idx = np.arange(every - 1, k, every)  # after the step ending at (idx + 1) h
        cfg = np.array([odometer.scale_factor, odometer.noise_std, odometer.resolution])
        aid[idx, 4] = 1.0
        aid[idx, 5] = _core.OdoState(cfg, seed).speeds(body_speed(truth)[idx + 1])
    if "nhc" in aiding and stream == "numpy":
        aid[:, 7:9] = aid[:, 6:7] * settings.nhc_std * rng.standard_normal((k, 2))
    return aid


def navigate(truth, *, noise: ImuNoise = IMU_NOISE["tactical"], gnss=None, aiding=("gnss", "zupt"), outages=(),
             settings: FilterSettings = FilterSettings(), seed: int = 0, gnss_velocity: bool = True,
             odometer: OdometerConfig | None = None, imu=None, fixes=None, zupt_detect: str = "truth",
             vibration=None, detector=None, imu_stream: str = "numpy", covariance: str = "full",
             filter_states=(), initial=None) -> AidedResult:
    """Aided navigation along ``truth`` (:class:`sarins_fmu.trajectory.Truth`).

    gnss : GNSSConfig or None (preset ``sps`` when 'gnss' is aided and None is given).
    aiding : subset of ('gnss', 'zupt', 'odometer', 'nhc', 'zaru').  outages : (m, 2) GNSS outage windows [start, end) s.
    odometer : OdometerConfig (default ``OdometerConfig()`` when 'odometer' is aided).
    zupt_detect : 'truth' (ZUPT / ZARU at the trajectory's stops) or 'imu' (at the steps the detector of
        :mod:`sarins_fmu.zero_velocity` declares stationary from the increments, with the IMU's
        noise densities and ``detector``, a :class:`~sarins_fmu.zero_velocity.DetectorSettings`).
    vibration : :class:`~sarins_fmu.zero_velocity.Vibration` added to the increments while moving, or None
        (added to ``imu`` too when given); drawn from ``imu_stream`` (:func:`~sarins_fmu.zero_velocity.vibrate`'s
        ``stream``; 'core': the TrajectoryIMU FMU's ``vib_accel_rms``, ``vib_rate_rms``, nothing added when both are
        0, as the FMU does).
    seed : IMU errors, initial errors (stream of ``seed``), vibration and GNSS errors (``seed``).
    imu : the increments ``corrupt(truth, noise, seed)`` returns, when made already (a peer filter runs
        the same data); fixes : ``gnss.simulate(truth, gnss, seed, outages)``'s fixes, likewise.
    imu_stream : where the IMU's errors (:func:`corrupt`'s ``stream``) and the ZUPT and NHC jitter
        (:func:`per_step_aiding`'s ``stream``) are drawn: 'numpy' or 'core' (the TrajectoryIMU FMU's, so the
        ``vehicle_gnss``, ``vehicle_gnss_odometer`` and ``vehicle_gnss_zupt`` systems give the same run).
    covariance : what the result keeps of the filter's P at each output time: 'full' (``cov`` (n, 15, 15)
        and ``variance``) or 'diagonal' (``variance`` only, ``cov`` None: no NEES; the core then writes 30
        numbers per output row instead of 240).  The filter runs the same either way.
    filter_states : optional error states beyond the 15 (:data:`FILTER_STATES`, eskf.h's header): 'sf' gyro and
        accelerometer scale factors (priors ``settings.gyro_sf0_std``, ``accel_sf0_std``, ``sf_tau``), 'lever'
        the antenna lever arm (prior ``settings.lever0_std``, from ``settings.lever_arm`` or the receiver's),
        'gnss-gm' the receiver's Gauss-Markov position (and with ``gnss_velocity`` velocity) errors with the
        receiver's std and correlation time (the fixes' std then the white part).  () : the 15-state filter.
    initial : (9,) the filter's start row (lat, lon rad, h m, v ENU m/s, yaw, pitch, roll rad), e.g. an INS's
        state after driving; None (default): the truth's first row with errors drawn from ``settings``'
        initial std (drawn either way, so the rest of the run's random numbers do not depend on it).
    """
    from . import zero_velocity

    if covariance not in COVARIANCE:
        raise ValueError(f"covariance must be one of {', '.join(COVARIANCE)}, got {covariance!r}")
    unknown = set(aiding) - set(AIDING)
    if unknown:
        raise ValueError(f"unknown aiding {', '.join(sorted(unknown))}; choose from {', '.join(AIDING)}")
    filter_states = check_filter_states(filter_states, aiding)
    if zupt_detect not in ZUPT_DETECT:
        raise ValueError(f"zupt_detect must be one of {', '.join(ZUPT_DETECT)}, got {zupt_detect!r}")
    if "gnss" in aiding and gnss is None:
        gnss = gnss_mod.PRESETS["sps"]
    if "odometer" in aiding and odometer is None:
        odometer = OdometerConfig()
    step = truth.step
    dtheta, dv, bg_true, ba_true = corrupt(truth, noise, seed, imu_stream) if imu is None else imu
    if vibration is not None and (imu_stream == "numpy" or vibration.accel_rms or vibration.rate_rms):
        vib_theta, vib_v = zero_velocity.vibrate(truth, vibration, seed, imu_stream)
        dtheta, dv = dtheta + vib_theta, dv + vib_v
    info = {"seed": seed, "aiding": list(aiding), "zupt_detect": zupt_detect}
    stops = None
    if zupt_detect == "imu" and ("zupt" in aiding or "zaru" in aiding):
        found = zero_velocity.detect(dtheta, dv, step, noise.vrw, noise.arw, detector or zero_velocity.DetectorSettings())
        stops = found.stationary
        info.update({"detector_samples": found.samples, "detector_gamma": found.gamma, "detector_alpha": found.alpha})
    rng = np.random.default_rng([seed, 3018])
    start = _initial_state(truth, settings, rng)
    if initial is not None:
        start = np.array(initial, float)
        if start.shape != (9,) or not np.isfinite(start).all():
            raise ValueError(f"initial must be 9 finite numbers (lat, lon, h, v E N U, yaw, pitch, roll), "
                             f"got shape {start.shape}")
    state = _core.EskfState(_config(noise, settings, gnss, step, odometer), start,
                            _options(filter_states, settings, gnss, gnss_velocity))
    if filter_states:
        info["filter_states"] = list(filter_states)
    if "zaru" in aiding:
        info["zaru_std"] = zaru_std(noise, settings, step)
    aid = per_step_aiding(truth, aiding, settings, odometer, rng, seed, stops, imu_stream)
    if "gnss" in aiding:
        if fixes is None:
            fixes = gnss_mod.simulate(truth, gnss, seed, outages)
        gm = "gnss-gm" in filter_states
        rows = fix_rows(fixes, gnss, step, white=gm)
        vel_std = np.maximum(gnss.vel_white_std, GM_STD_FLOOR) if gm and gnss_velocity else gnss.vel_std()
    else:
        if len(outages):
            gnss_mod.check_outages(outages, truth.time[-1])
        rows, vel_std = np.zeros((0, 11)), np.ones(3)
    full = covariance == "full"
    out = state.run(dtheta, dv, aid, rows, vel_std, gnss_velocity, settings.out_every, full_cov=full)
    idx = np.arange(1, out.shape[0] + 1) * settings.out_every
    true_rows = truth.nav_rows(idx)
    nav, n = out[:, :9], state.n
    cov = out[:, n:].reshape(-1, n, n) if full else None
    states, index, at = {}, {}, 15
    mask = state_mask(filter_states, gnss_velocity) if filter_states else 0
    for name, bit in BLOCKS:
        if mask & bit:
            states[name], index[name] = out[:, at:at + 3], at
            at += 3
    return AidedResult(time=truth.time[idx], nav=nav, truth=true_rows, error=nav_errors(nav, true_rows),
                       cov=cov, bias_g=out[:, 9:12], bias_a=out[:, 12:15], states=states, state_index=index,
                       bias_g_true=bg_true[idx - 1], bias_a_true=ba_true[idx - 1],
                       gnss_used=int(np.sum(rows[:, 1] > 0)) if len(rows) else 0, zupt_steps=int(aid[:, 0].sum()),
                       zaru_steps=int(aid[:, 9].sum()), info=info,
                       variance=np.diagonal(cov, axis1=1, axis2=2) if full else out[:, n:])


@dataclass(frozen=True)
class NeesReport:
    """Monte Carlo consistency: time (n,) s; mean NEES (n,) per block over the runs; the two-sided
    95 % band of the mean of ``runs`` chi-square(3) values, chi2(3 runs) / runs; inside: fraction of
    the output times at which the mean lies inside the band, per block."""

    runs: int
    time: np.ndarray
    mean_nees: dict
    band: tuple
    inside: dict


def nees_monte_carlo(truth, runs: int, *, first_seed: int = 0, skip: float = 0.0, **kwargs) -> NeesReport:
    """Mean NEES of position, velocity and attitude over ``runs`` seeds (``first_seed`` ..); output
    times before ``skip`` s are left out of the fractions.  Keyword arguments go to :func:`navigate`."""
    from scipy.stats import chi2

    sums = None
    for seed in range(first_seed, first_seed + runs):
        r = navigate(truth, seed=seed, **kwargs)
        values = {b: r.nees(b) for b in ("position", "velocity", "attitude")}
        sums = values if sums is None else {b: sums[b] + values[b] for b in values}
    mean = {b: v / runs for b, v in sums.items()}
    band = (chi2.ppf(0.025, 3 * runs) / runs, chi2.ppf(0.975, 3 * runs) / runs)
    keep = r.time >= skip
    inside = {b: float(np.mean((v[keep] >= band[0]) & (v[keep] <= band[1]))) for b, v in mean.items()}
    return NeesReport(runs=runs, time=r.time, mean_nees=mean, band=band, inside=inside)


@dataclass(frozen=True)
class OutageRow:
    """One GNSS outage: window (s), horizontal error at its end (m), the filter's predicted horizontal
    sigma there (m) and their ratio."""

    start: float
    end: float
    error: float
    sigma: float

    @property
    def ratio(self) -> float:
        return self.error / self.sigma


def outage_table(result: AidedResult, outages) -> list:
    """:class:`OutageRow` per outage window: the last output row strictly before the window's end (the
    first fix after the outage, valid at ``end``, is already applied in the row at ``end``)."""
    rows = []
    for start, end in np.asarray(outages, float).reshape(-1, 2):
        i = int(np.searchsorted(result.time, end - 1e-9, side="left")) - 1
        rows.append(OutageRow(float(start), float(end), float(result.horizontal_error()[i]),
                              float(result.horizontal_sigma()[i])))
    return rows


def summary(result: AidedResult, outages=()) -> dict:
    """JSON-ready numbers of a run: RMS and max horizontal / vertical errors (m), RMS velocity error
    (m/s), RMS attitude error (deg; heading separately), the final errors, mean NEES per block and
    the outage table; with optional filter states, their final estimates and sigmas ('final_states')."""
    h = result.horizontal_error()
    deg = 180.0 / math.pi
    out = {
        "duration_s": float(result.time[-1]),
        "horizontal_error_rms_m": float(np.sqrt(np.mean(h**2))),
        "horizontal_error_max_m": float(h.max()),
        "vertical_error_rms_m": float(np.sqrt(np.mean(result.error[:, 2] ** 2))),
        "velocity_error_rms_mps": float(np.sqrt(np.mean(np.sum(result.error[:, 3:6] ** 2, axis=1)))),
        "tilt_error_rms_deg": float(deg * np.sqrt(np.mean(np.sum(result.error[:, 6:8] ** 2, axis=1)))),
        "heading_error_rms_deg": float(deg * np.sqrt(np.mean(result.error[:, 8] ** 2))),
        "final_horizontal_error_m": float(h[-1]),
        "mean_nees": {b: float(np.mean(result.nees(b))) for b in ("position", "velocity", "attitude")},
        "gnss_fixes_used": result.gnss_used,
        "zupt_steps": result.zupt_steps,
        "zaru_steps": result.zaru_steps,
        "outages": [{"start_s": r.start, "end_s": r.end, "horizontal_error_m": r.error, "predicted_sigma_m": r.sigma,
                     "ratio": r.ratio} for r in outage_table(result, outages)],
    }
    if result.states:
        out["final_states"] = {name: {"estimate": result.states[name][-1].tolist(),
                                      "sigma": result.state_sigma(name)[-1].tolist()} for name in result.states}
    return out


@dataclass(frozen=True)
class OutageReport:
    """Monte Carlo outage growth: per window (start, end s), the RMS over the runs of the horizontal
    error at the window's end (m), the filter's predicted horizontal sigma there (RMS over the runs
    of sqrt(P_EE + P_NN), m) and their ratio."""

    runs: int
    windows: list
    rms_error: list
    predicted_sigma: list

    @property
    def ratios(self) -> list:
        return [e / s for e, s in zip(self.rms_error, self.predicted_sigma)]


def outage_windows(outages) -> list:
    """The GNSS outage windows [(start, end), ...] s as floats, from an (m, 2) array-like."""
    return [tuple(map(float, w)) for w in np.asarray(outages, float).reshape(-1, 2)]


def outage_monte_carlo(truth, runs: int, outages, *, first_seed: int = 0, **kwargs) -> OutageReport:
    """Horizontal error at the end of each GNSS outage over ``runs`` seeds vs the filter's sigma."""
    windows = outage_windows(outages)
    err2 = np.zeros(len(windows))
    var = np.zeros(len(windows))
    for seed in range(first_seed, first_seed + runs):
        r = navigate(truth, seed=seed, outages=outages, **kwargs)
        for j, row in enumerate(outage_table(r, outages)):
            err2[j] += row.error**2
            var[j] += row.sigma**2
    return OutageReport(runs=runs, windows=windows, rms_error=list(np.sqrt(err2 / runs)),
                        predicted_sigma=list(np.sqrt(var / runs)))


@dataclass(frozen=True)
class ClosedFormReport:
    """Monte Carlo outage growth against the closed-form free-inertial growth (:mod:`sarins_fmu.free_inertial`):
    per window (start, end s), the RMS over the runs of the horizontal error growth e(end) - e(start) (m, the
    rows of :func:`outage_table` and the row at ``start``), and the RMS of the closed form's horizontal sigma
    from the filter's covariance of velocity, attitude and biases at the start, without the IMU's noise
    during the outage (``state_sigma``) and with it (``sigma``)."""

    runs: int
    windows: list
    rms_growth: list
    state_sigma: list
    sigma: list

    @property
    def ratios(self) -> list:
        return [e / s for e, s in zip(self.rms_growth, self.sigma)]


def outage_closed_form_monte_carlo(truth, runs: int, outages, *, first_seed: int = 0,
                                   noise: ImuNoise = IMU_NOISE["tactical"], **kwargs) -> ClosedFormReport:
    """Horizontal error growth over each GNSS outage over ``runs`` seeds vs the closed-form growth
    (:func:`sarins_fmu.free_inertial.horizontal_growth_sigma`, with the Earth's rate) from the filter's P at the
    window's start, with the computed attitude and specific force (0, 0, g).  Keyword arguments go to
    :func:`navigate` (with ``covariance='full'``)."""
    from . import free_inertial

    windows = outage_windows(outages)
    sums = np.zeros((3, len(windows)))
    for seed in range(first_seed, first_seed + runs):
        r = navigate(truth, noise=noise, seed=seed, outages=outages, **kwargs)
        for j, (start, end) in enumerate(windows):
            i0 = int(np.searchsorted(r.time, start - 1e-9))
            i1 = int(np.searchsorted(r.time, end - 1e-9)) - 1
            t = float(r.time[i1] - r.time[i0])
            mat = euler_to_mat(*r.nav[i0, 6:9])
            f_n = np.array([0.0, 0.0, earth.gravity(r.nav[i0, 0], r.nav[i0, 2])])
            om = earth.earth_rate_n(r.nav[i0, 0])
            cov = r.cov[i0, 3:15, 3:15]
            sums[0, j] += float(np.sum((r.error[i1, :2] - r.error[i0, :2]) ** 2))
            sums[1, j] += free_inertial.horizontal_growth_sigma(t, cov, mat, f_n, omega_n=om) ** 2
            sums[2, j] += free_inertial.horizontal_growth_sigma(t, cov, mat, f_n, noise, om) ** 2
    rms = np.sqrt(sums / runs)
    return ClosedFormReport(runs=runs, windows=windows, rms_growth=list(rms[0]), state_sigma=list(rms[1]),
                            sigma=list(rms[2]))
