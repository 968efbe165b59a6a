"""IMU error models, presets and the increment-output IMU.

Sensor model of one triad (gyro: rad/s; accelerometer: m/s^2), applied to
every minor-step increment at the internal rate (the C core's minor loop,
``sarins_fmu/core/imu.h``):

    x_meas = (I + diag(sf(T)) + M) x_true + b(T, t) + q * x|x| + n

* ``sf(T) = scale_factor + scale_factor_tc * (T - T_ref)``
* ``M``: misalignment / non-orthogonality (off-diagonal, rad)
* ``b(T, t) = bias + bias_tc1 (T - T_ref) + bias_tc2 (T - T_ref)^2 + GM(t)``,
  where GM is a first-order Gauss-Markov bias instability (std, corr. time)
* gyro only: g-sensitivity ``G f`` and a low-rate scale-factor nonlinearity
  ``k_lr * omega * exp(-(omega/omega_lr)^2)`` (seed 003: MEMS gyros are
  strongly nonlinear at low rates)
* azimuth (z) gyro only: ``eps_z(T) = a T^2 + b T + c`` (seed 002 eq. (7))
  plus ``d * dT/dt`` (seed 000's cold-start effect); a, b, c may age as
  first-order Markov processes with a 360-day correlation time (seed 002).
* time-correlated terms (:mod:`sarins_fmu.imu_correlated`; all zero for
  ``ideal`` and ``nav-rlg``): the errors above follow the *die* temperature,
  which lags the reported one (:mod:`sarins_fmu.thermal`); bias and scale
  factor respond to the die temperature rate (thermal gradient); a
  play-operator thermal hysteresis; a flicker bias instability (sum of
  Gauss-Markov terms, flat Allan floor); a rate random walk; a turn-on bias
  drawn once per seed.
* white noise n: angle / velocity random walk.  It is added to each output
  increment with its exact integrated variance (N(0, rw^2 h)); this is the
  same distribution as summing minor-step noise, at a fraction of the cost.
* periodic disturbance ``a sin(2 pi f t + phi)`` per sensor (all zero in
  every built-in preset): its exact integral over each output interval is
  added to the increment, so the rate's Allan variance is
  ``a^2 sin^4(pi f tau) / (pi f tau)^2`` at every multiple of the interval;
  the phase phi is drawn once per seed (``sarins_fmu/core/imu.h``).

Every random number (white noise, Gauss-Markov, the time-correlated terms,
turn-on bias, ageing) is drawn in the C core from its own seeded stream
(``sarins_fmu/core/rng.h``: SplitMix64 streams from (seed, stream id),
normals by the polar method); the IMU passes its seed, never numbers, so a
seed gives the same run in process and inside the FMU.

Biases, scale factors and temperatures are evaluated once per output
interval (the thermal time constants are hours; the GM correlation times
are minutes or longer); the motion, the linear and nonlinear error terms and
coning/sculling are evaluated at the internal rate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from . import earth
from .core import imu as core_imu
from .core import rng as core_rng
from .core._lib import array_table
from .core.rng import check_seed
from . import imu_dynamics
from . import imu_step
from .imu_step import T_REF
from .thermal import Ambient, ThermalModel, ThermalParams, _check_temperature
from .units import ARCSEC_TO_RAD, DAY, DEG_TO_RAD, DPH_TO_RPS, DPSH_TO_RPSS, PPM, UG_TO_MPS2



def _vec3(value, name):
    arr = np.broadcast_to(np.asarray(value, dtype=float), (3,)).copy()
    if not np.isfinite(arr).all():
        raise ValueError(f"IMU parameter {name} must be finite")
    return arr


CORRELATED_FIELDS = ("bias_dtdt", "scale_factor_dtdt", "hysteresis", "hysteresis_width", "flicker",
                     "rate_random_walk", "turn_on_bias")
DYNAMICS_FIELDS = ("filter_time_constant", "rate_hysteresis", "rate_hysteresis_width", "rate_hysteresis_time",
                   "rate_hysteresis_tc")
PERIODIC_FIELDS = ("periodic_amplitude", "periodic_frequency")


@dataclass(frozen=True)
class TriadErrors:
    """Error parameters of one sensor triad (SI units: rad/s or m/s^2).

    Attributes
    ----------
    bias : (3,) constant bias
    scale_factor : (3,) scale-factor error, dimensionless
    misalignment : (3, 3) misalignment / non-orthogonality, rad (diagonal unused)
    random_walk : (3,) white-noise density (rad/sqrt(s) or m/s/sqrt(s))
    bias_instability : (3,) Gauss-Markov std; bias_corr_time : (3,) s
    bias_tc1 : (3,) per degC; bias_tc2 : (3,) per degC^2
    scale_factor_tc : (3,) per degC
    quadratic : (3,) coefficient of x|x|
    bias_dtdt, scale_factor_dtdt : (3,) per degC/s of die temperature rate
    hysteresis : (3,) half-loop bias amplitude; hysteresis_width : (3,) degC
    flicker : (3,) bias-instability coefficient B (Allan floor 0.664 B)
    rate_random_walk : (3,) per sqrt(s) (rad/s/sqrt(s) or m/s^2/sqrt(s))
    turn_on_bias : (3,) std of the per-seed constant bias
    (time-correlated terms: see :mod:`sarins_fmu.imu_correlated`)
    filter_time_constant : (3,) s, first-order output low-pass (0: none)
    rate_hysteresis : (3,) amplitude c of the input hysteresis (rad/s or m/s^2)
    rate_hysteresis_width : (3,) its half-width w in input units (rad/s or m/s^2)
    rate_hysteresis_time : (3,) s, its relaxation time (0: none, a pure play)
    rate_hysteresis_tc : (3,) 1/degC, relative change of c with temperature
    (output dynamics: see :mod:`sarins_fmu.imu_dynamics`)
    periodic_amplitude : (3,) amplitude a of a periodic disturbance a sin(2 pi f t + phi) on the output
        rate (rad/s or m/s^2; 0: none)
    periodic_frequency : (3,) its frequency f, Hz (> 0 where a > 0; at most the minor loop's Nyquist
        frequency internal_rate / 2, checked when an :class:`IMU` is built)
    """

    bias: np.ndarray = field(default_factory=lambda: np.zeros(3))
    scale_factor: np.ndarray = field(default_factory=lambda: np.zeros(3))
    misalignment: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))
    random_walk: np.ndarray = field(default_factory=lambda: np.zeros(3))
    bias_instability: np.ndarray = field(default_factory=lambda: np.zeros(3))
    bias_corr_time: np.ndarray = field(default_factory=lambda: np.full(3, 3600.0))
    bias_tc1: np.ndarray = field(default_factory=lambda: np.zeros(3))
    bias_tc2: np.ndarray = field(default_factory=lambda: np.zeros(3))
    scale_factor_tc: np.ndarray = field(default_factory=lambda: np.zeros(3))
    quadratic: np.ndarray = field(default_factory=lambda: np.zeros(3))
    bias_dtdt: np.ndarray = field(default_factory=lambda: np.zeros(3))
    scale_factor_dtdt: np.ndarray = field(default_factory=lambda: np.zeros(3))
    hysteresis: np.ndarray = field(default_factory=lambda: np.zeros(3))
    hysteresis_width: np.ndarray = field(default_factory=lambda: np.ones(3))
    flicker: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rate_random_walk: np.ndarray = field(default_factory=lambda: np.zeros(3))
    turn_on_bias: np.ndarray = field(default_factory=lambda: np.zeros(3))
    filter_time_constant: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rate_hysteresis: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rate_hysteresis_width: np.ndarray = field(default_factory=lambda: np.ones(3))
    rate_hysteresis_time: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rate_hysteresis_tc: np.ndarray = field(default_factory=lambda: np.zeros(3))
    periodic_amplitude: np.ndarray = field(default_factory=lambda: np.zeros(3))
    periodic_frequency: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self):
        for name in ("bias", "scale_factor", "random_walk", "bias_instability", "bias_corr_time",
                     "bias_tc1", "bias_tc2", "scale_factor_tc", "quadratic", *CORRELATED_FIELDS,
                     *DYNAMICS_FIELDS, *PERIODIC_FIELDS):
            object.__setattr__(self, name, _vec3(getattr(self, name), name))
        for name in PERIODIC_FIELDS:
            if np.any(getattr(self, name) < 0):
                raise ValueError(f"{name} must be non-negative")
        if np.any((self.periodic_amplitude > 0) & (self.periodic_frequency <= 0)):
            raise ValueError("periodic_frequency must be positive where the periodic amplitude is not zero")
        for name in ("filter_time_constant", "rate_hysteresis_time"):
            if np.any(getattr(self, name) < 0):
                raise ValueError(f"{name} must be non-negative")
        if np.any(self.rate_hysteresis_width <= 0):
            raise ValueError("rate_hysteresis_width must be positive")
        for name in ("flicker", "rate_random_walk", "turn_on_bias"):
            if np.any(getattr(self, name) < 0):
                raise ValueError(f"{name} must be non-negative")
        if np.any(self.hysteresis_width <= 0):
            raise ValueError("hysteresis_width must be positive")
        mis = np.asarray(self.misalignment, dtype=float)
        if mis.shape != (3, 3) or not np.isfinite(mis).all():
            raise ValueError("misalignment must be a finite (3, 3) matrix")
        object.__setattr__(self, "misalignment", mis * (1.0 - np.eye(3)))
        if np.any(self.random_walk < 0) or np.any(self.bias_instability < 0):
            raise ValueError("random walk and bias instability must be non-negative")
        if np.any(self.bias_corr_time <= 0):
            raise ValueError("bias correlation times must be positive")


@dataclass(frozen=True)
class ImuModel:
    """Complete IMU error model: gyro and accelerometer triads, thermal model.

    Attributes
    ----------
    gyro, accel : TriadErrors
    g_sensitivity : (3, 3) gyro g-sensitivity, rad/s per m/s^2
    lowrate_gain : (3,) gyro low-rate scale-factor nonlinearity amplitude
    lowrate_width : (3,) its width, rad/s
    axial_drift_poly : (3,) (a, b, c) of eps_z(T) = a T^2 + b T + c, in
        rad/s/degC^2, rad/s/degC, rad/s (T in degC)
    axial_drift_dtdt : float, z-gyro drift per unit temperature rate,
        rad/s per degC/s (= rad/degC)
    axial_drift_grad : float, z-gyro drift per degC of block gradient
        T_z - T_block, rad/s/degC (``sarins_imu_axial_thermal_terms``)
    axial_block_time_constant : float, s, lag of the block node behind the
        z-gyro temperature (0: no lag, no gradient)
    axial_hysteresis : float, rad/s, half-height H of the heating/cooling
        loop of the z-gyro drift (heating branch +H, cooling branch -H)
    axial_hysteresis_width : float, degC (> 0), half the temperature
        reversal that takes the loop from one branch to the other
    axial_hysteresis_relax_time : float, s, relaxation of the loop at rest
        (0: none)
    aging_sigma : (3,) stationary std of the Markov ageing of (a, b, c)
    aging_corr_time : float, s (seed 002: 360 days)
    flicker_tau_min, flicker_tau_max : float, s, band of correlation times
        of the flicker bias instability (see :mod:`imu_correlated`)
    thermal : ThermalParams
    accel_lever_arm : (3, 3) m, row i the position of accelerometer i from
        the reference point, body axes (size effect, :mod:`imu_dynamics`)
    """

    gyro: TriadErrors = field(default_factory=TriadErrors)
    accel: TriadErrors = field(default_factory=TriadErrors)
    g_sensitivity: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))
    lowrate_gain: np.ndarray = field(default_factory=lambda: np.zeros(3))
    lowrate_width: np.ndarray = field(default_factory=lambda: np.ones(3))
    axial_drift_poly: np.ndarray = field(default_factory=lambda: np.zeros(3))
    axial_drift_dtdt: float = 0.0
    axial_drift_grad: float = 0.0
    axial_block_time_constant: float = 0.0
    axial_hysteresis: float = 0.0
    axial_hysteresis_width: float = 1.0
    axial_hysteresis_relax_time: float = 0.0
    aging_sigma: np.ndarray = field(default_factory=lambda: np.zeros(3))
    aging_corr_time: float = 360 * DAY
    flicker_tau_min: float = 1.0
    flicker_tau_max: float = 10000.0
    thermal: ThermalParams = field(default_factory=ThermalParams)
    accel_lever_arm: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))

    def __post_init__(self):
        arm = np.asarray(self.accel_lever_arm, dtype=float)
        if arm.shape != (3, 3) or not np.isfinite(arm).all():
            raise ValueError("accel_lever_arm must be a finite (3, 3) matrix (row i: accelerometer i's position, m)")
        object.__setattr__(self, "accel_lever_arm", arm)
        for name in ("lowrate_gain", "lowrate_width", "axial_drift_poly", "aging_sigma"):
            object.__setattr__(self, name, _vec3(getattr(self, name), name))
        gs = np.asarray(self.g_sensitivity, dtype=float)
        if gs.shape != (3, 3) or not np.isfinite(gs).all():
            raise ValueError("g_sensitivity must be a finite (3, 3) matrix")
        object.__setattr__(self, "g_sensitivity", gs)
        if np.any(self.lowrate_width <= 0):
            raise ValueError("lowrate_width must be positive")
        if not (math.isfinite(self.axial_drift_dtdt) and self.aging_corr_time > 0):
            raise ValueError("axial_drift_dtdt must be finite and aging_corr_time positive")
        for name in ("axial_drift_grad", "axial_hysteresis"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"{name} must be finite")
        for name in ("axial_block_time_constant", "axial_hysteresis_relax_time"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) >= 0):
                raise ValueError(f"{name} must be a non-negative number of seconds")
        if not (math.isfinite(self.axial_hysteresis_width) and self.axial_hysteresis_width > 0):
            raise ValueError("axial_hysteresis_width must be positive (degC)")
        if not (0 < self.flicker_tau_min < self.flicker_tau_max < math.inf):
            raise ValueError("flicker correlation times need 0 < flicker_tau_min < flicker_tau_max (finite)")

    def with_axial_drift(self, drift: float) -> "ImuModel":
        """Copy whose z-gyro drift is the constant ``drift`` (rad/s), no thermal terms."""
        gyro = replace(self.gyro, bias=np.array([*self.gyro.bias[:2], 0.0]),
                       bias_tc1=np.array([*self.gyro.bias_tc1[:2], 0.0]),
                       bias_tc2=np.array([*self.gyro.bias_tc2[:2], 0.0]))
        return replace(self, gyro=gyro, axial_drift_poly=np.array([0.0, 0.0, drift]),
                       axial_drift_dtdt=0.0, axial_drift_grad=0.0, axial_hysteresis=0.0, aging_sigma=np.zeros(3))

    @property
    def axial_thermal_par(self) -> np.ndarray:
        """The five parameters of ``sarins_imu_axial_thermal_terms`` (SI): k_g, tau_b, H, w, tau_r."""
        return np.array([self.axial_drift_grad, self.axial_block_time_constant, self.axial_hysteresis,
                         self.axial_hysteresis_width, self.axial_hysteresis_relax_time])


def _mis(arcsec):
    """Misalignment matrix with the same small angle (arcsec) in every slot."""
    return np.full((3, 3), arcsec * ARCSEC_TO_RAD) * np.array([[0, 1, -1], [-1, 0, 1], [1, -1, 0]])


# Navigation-grade RLG unit of the seeds' class (90-type RLG, marine RINS):
# ARW 0.0005 deg/sqrt(h) and drift around 0.003 deg/h as stated in the issue
# for seeds 000/002; seed 002 fits eps_z(T) to a quadratic with a residual
# of 0.002 deg/h, our (a, b, c) give 0.0021..0.0037 deg/h over 20..60 degC.
# Accelerometer figures (30-50 ug bias, 5 ug/sqrt(Hz)) are those of quartz
# pendulous accelerometers in such units (Titterton & Weston table 4.3).
# The papers imply no die lag, per-axis gradient or hysteresis, flicker
# floor, rate random walk or turn-on bias for this unit (seed 000 models the
# axial drift by T and dT/dt; seed 002 by a quadratic in T), so those terms
# are zero here; the azimuth gyro has the block-gradient and heating/cooling
# terms real RLGs show (issue 20, the axial_* fields below).
NAV_RLG = ImuModel(
    gyro=TriadErrors(
        bias=np.array([0.003, -0.003, 0.0]) * DPH_TO_RPS,
        scale_factor=np.full(3, 1 * PPM),
        misalignment=_mis(1.0),
        random_walk=np.full(3, 0.0005 * DPSH_TO_RPSS),
        bias_instability=np.full(3, 0.0001 * DPH_TO_RPS),
        bias_corr_time=np.full(3, 7200.0),
    ),
    accel=TriadErrors(
        bias=np.array([30.0, -30.0, 50.0]) * UG_TO_MPS2,
        scale_factor=np.full(3, 100 * PPM),  # HG9900 brochure, 1 sigma
        misalignment=_mis(1.0),
        random_walk=np.full(3, 5.0 * UG_TO_MPS2),
        bias_instability=np.full(3, 2.0 * UG_TO_MPS2),
        bias_corr_time=np.full(3, 7200.0),
        bias_tc1=np.full(3, 0.5 * UG_TO_MPS2),
    ),
    axial_drift_poly=np.array([1.0e-6, -4.0e-5, 0.0025]) * DPH_TO_RPS,
    axial_drift_dtdt=1.0e-4 * DPH_TO_RPS * 3600.0,  # 1e-4 deg/h per degC/h
    # azimuth gyro beyond T and dT/dt (docs/imu-presets.md gives the sources): the block node lags the gyro
    # temperature by the first diffusion mode of a 0.1 m ZERODUR block (L^2 / (pi^2 alpha), alpha = 7.2e-7
    # m^2/s from SCHOTT's conductivity, density and heat capacity); the drift per degC of that gradient is
    # taken equal to the campaign unit's per degC of uniform change; a heating/cooling loop of half-height
    # the unit's in-run bias instability, taken up over 2 degC, not relaxing
    axial_drift_grad=2.0e-4 * DPH_TO_RPS,
    axial_block_time_constant=1400.0,
    axial_hysteresis=1.0e-4 * DPH_TO_RPS,
    axial_hysteresis_width=2.0,
    axial_hysteresis_relax_time=0.0,
    # ageing (seed 002 eq. (20): first-order Markov, 360-day correlation time): the constant term's
    # stationary std is the HG9900 brochure's gyro bias, 0.0035 deg/h 1 sigma, read as the bias a
    # navigation-grade RLG wanders over its calibration life; a and b have no public source
    # (docs/imu-presets.md)
    aging_sigma=np.array([0.3e-6, 1.0e-5, 0.0035]) * DPH_TO_RPS,
)

# Consumer/tactical MEMS unit like seed 003's MIMU: bias ~10 deg/h with strong
# temperature dependence, ARW 0.15 deg/sqrt(h) (ADIS16465), percent-level low-rate
# nonlinearity, g-sensitivity 0.015 deg/s/g (ADIS16445), accelerometer bias 2 mg.
# Time-correlated terms (seed 003 gives no figures; docs/imu-presets.md gives each source):
# flicker bias instability B = 3.0 deg/h and 5.4 ug (Allan floors 2 deg/h and
# 3.6 ug, the ADIS16465's in-run bias stability), rate random walk 3 deg/h/sqrt(h) and
# 0.5 ug/sqrt(s) (the +1/2 slope takes over past ~1e4 s), turn-on
# repeatability 8 deg/h and 0.5 mg, die lagging the reported temperature by
# 3 and 2 min, thermal-gradient sensitivity 5 deg/h and 100 ug at 1 degC/min
# (scale factor 200 and 100 ppm at 1 degC/min), hysteresis loops +-3 deg/h
# and +-100 ug taken up over 2 degC.  Output dynamics (sarins_fmu.imu_dynamics): a
# 2.5 ms output filter, a rate hysteresis relaxing in 2 s, accelerometers a few mm
# off the reference point (size effect).
# Sizes from public sources (docs/imu-presets.md gives each row's source):
# Allan floor of a flicker bias is sqrt(2 ln 2 / pi) B = 0.664 B (IEEE Std 952-1997 annex C), so a
# datasheet's in-run bias stability S is the flicker coefficient B = S / 0.664: ADIS16465-1 gyro 2 deg/h
# -> B = 3.0 deg/h, accelerometer 3.6 ug -> B = 5.4 ug (to 2 digits)
GYRO_FLICKER_DPH = 3.0
ACCEL_FLICKER_UG = 5.4
G_SENSITIVITY_DPS_PER_G = 0.015  # ADIS16445 data sheet, linear-acceleration effect on gyro bias, +-0.015 deg/s/g
# output filter: an averaging decimation filter to a 200 Hz output has a group delay of 0.5 / f_out = 2.5 ms
# (KVH 1775 IMU manual sec. 12.3.3; the ADIS1646x decimation filter averages the same way): the first-order
# filter with that low-frequency group delay
OUTPUT_FILTER_S = 0.5 / 200.0
_PER_DEGC_PER_MIN = 60.0  # (x per degC/min) * this = x per degC/s
MEMS = ImuModel(
    gyro=TriadErrors(
        bias=np.array([10.0, -8.0, 12.0]) * DPH_TO_RPS,
        scale_factor=np.array([500.0, -400.0, 600.0]) * PPM,
        misalignment=_mis(300.0),
        random_walk=np.full(3, 0.15 * DPSH_TO_RPSS),  # ADIS16465 ARW
        bias_tc1=np.array([0.004, -0.003, 0.005]) * DEG_TO_RAD,
        bias_tc2=np.array([6e-5, 5e-5, -7e-5]) * DEG_TO_RAD,
        scale_factor_tc=np.full(3, 100 * PPM),
        quadratic=np.full(3, 1.5e-4),
        bias_dtdt=np.array([5.0, -4.0, 6.0]) * DPH_TO_RPS * _PER_DEGC_PER_MIN,
        scale_factor_dtdt=np.full(3, 200 * PPM * _PER_DEGC_PER_MIN),
        hysteresis=np.array([3.0, -2.5, 3.5]) * DPH_TO_RPS,
        hysteresis_width=np.full(3, 2.0),
        flicker=np.full(3, GYRO_FLICKER_DPH * DPH_TO_RPS),
        rate_random_walk=np.full(3, 3.0 * DPH_TO_RPS / 60.0),
        turn_on_bias=np.full(3, 8.0 * DPH_TO_RPS),
        filter_time_constant=np.full(3, OUTPUT_FILTER_S),
        rate_hysteresis=np.array([0.01, -0.008, 0.012]) * DEG_TO_RAD,
        rate_hysteresis_width=np.full(3, 1.0 * DEG_TO_RAD),
        rate_hysteresis_time=np.full(3, 2.0),
        rate_hysteresis_tc=np.full(3, 0.01),
    ),
    accel=TriadErrors(
        bias=np.array([2.0, -1.5, 2.5]) * 1e3 * UG_TO_MPS2,
        scale_factor=np.array([1000.0, -800.0, 1200.0]) * PPM,
        misalignment=_mis(200.0),
        random_walk=np.full(3, 0.05 / 60.0),
        bias_tc1=np.full(3, 100.0 * UG_TO_MPS2),
        bias_tc2=np.full(3, 2.0 * UG_TO_MPS2),
        scale_factor_tc=np.full(3, 50 * PPM),
        quadratic=np.full(3, 1e-4),
        bias_dtdt=np.array([100.0, -80.0, 120.0]) * UG_TO_MPS2 * _PER_DEGC_PER_MIN,
        scale_factor_dtdt=np.full(3, 100 * PPM * _PER_DEGC_PER_MIN),
        hysteresis=np.array([100.0, -80.0, 120.0]) * UG_TO_MPS2,
        hysteresis_width=np.full(3, 2.0),
        flicker=np.full(3, ACCEL_FLICKER_UG * UG_TO_MPS2),
        rate_random_walk=np.full(3, 0.5 * UG_TO_MPS2),
        turn_on_bias=np.full(3, 500.0 * UG_TO_MPS2),
        filter_time_constant=np.full(3, OUTPUT_FILTER_S),
        rate_hysteresis=np.array([100.0, -80.0, 120.0]) * UG_TO_MPS2,
        rate_hysteresis_width=np.full(3, 0.01 * earth.GAMMA_E),
        rate_hysteresis_time=np.full(3, 2.0),
        rate_hysteresis_tc=np.full(3, 0.01),
    ),
    g_sensitivity=(np.array([[1.0, 0.3, -0.2], [-0.2, 1.0, 0.3], [0.3, -0.2, 1.0]]) * G_SENSITIVITY_DPS_PER_G
                   * DEG_TO_RAD / earth.GAMMA_E),
    accel_lever_arm=np.array([[2.0, -3.0, 1.0], [-2.0, 2.0, -1.0], [1.0, 1.0, 3.0]]) * 1e-3,
    lowrate_gain=np.full(3, 0.02),
    lowrate_width=np.full(3, 2.0 * DEG_TO_RAD),
    flicker_tau_min=1.0,
    flicker_tau_max=1.0e5,
    thermal=ThermalParams(self_heating=(6.0, 6.2, 6.4, 5.5, 5.6, 5.7),
                          time_constant=(600.0, 620.0, 640.0, 560.0, 580.0, 600.0),
                          die_time_constant=(180.0, 190.0, 200.0, 120.0, 130.0, 140.0)),
)

PRESETS = {"ideal": ImuModel(), "nav-rlg": NAV_RLG, "mems": MEMS}


def preset(name: str) -> ImuModel:
    """Named IMU model: 'ideal', 'nav-rlg' or 'mems', or a preset file (``*.json``,
    :mod:`sarins_fmu.imu_preset_file`, e.g. fitted to a log by ``sarins allan --write-preset``)."""
    from .imu_preset_file import is_preset_file, read_preset

    if is_preset_file(name):
        return read_preset(name)
    try:
        return PRESETS[name]
    except KeyError:
        raise ValueError(f"unknown IMU preset {name!r}; choose one of {', '.join(PRESETS)} or a preset file "
                         "(.json)") from None


def aged_drift_poly(model: ImuModel, days, seed: int = 0):
    """Azimuth-drift coefficients (a, b, c) after ``days`` of first-order Markov ageing.

    Each coefficient is x(t) = x0 + m(t) with m a stationary-increment
    first-order Markov process started at 0 (seed 002 eq. (20)):
    m_{k+1} = exp(-dt/tau) m_k + sigma sqrt(1 - exp(-2 dt/tau)) w_k,
    w from the ageing stream of ``seed`` (the C core's
    ``sarins_imu_aged_poly``, the draw an :class:`IMU` of that seed makes).

    Parameters
    ----------
    days : array_like (K,), increasing days since calibration
    seed : int in [0, 2**64)
    Returns
    -------
    (K, 3) coefficients in the units of ``model.axial_drift_poly``.
    """
    days = np.atleast_1d(np.asarray(days, float))
    if np.any(np.diff(days) < 0) or np.any(days < 0):
        raise ValueError("days must be non-negative and increasing")
    return core_imu.aged_poly(seed, days * DAY, model.axial_drift_poly, model.aging_sigma, model.aging_corr_time)


@dataclass(frozen=True)
class StaticBase:
    """A base frame fixed to the Earth: position and yaw of the turntable base.

    lat, lon in rad, height in m, yaw of the base frame t in n (rad, CCW);
    the base is level.
    """

    lat: float
    lon: float = 0.0
    height: float = 0.0
    yaw: float = 0.0

    def __post_init__(self):
        for name in ("lat", "lon", "height", "yaw"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"base {name} must be finite")
        if abs(self.lat) > 89.9 * DEG_TO_RAD:
            raise ValueError(f"latitude {math.degrees(self.lat):.6g} deg is outside +-89.9 deg")

    @property
    def mat_nt(self):
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])

    def inertial_rate_t(self):
        """omega_it resolved in t, rad/s (Earth rate)."""
        return self.mat_nt.T @ earth.earth_rate_n(self.lat)

    def specific_force_t(self):
        """Specific force of the static base resolved in t, m/s^2 (-gravity)."""
        return -(self.mat_nt.T @ earth.gravity_n(self.lat, self.height))

    def base_motion(self, t_start, h):
        """The moving-base interface: inertial rate (rad/s) and specific force
        (m/s^2) of the base frame t, resolved in t, held over each interval
        [t_start[k], t_start[k] + h).  (K, 3) each; constant for a static base.

        A moving base (vehicle) implements the same method; its heading
        changes belong in an outer gimbal of the schedule (piecewise-constant
        yaw acceleration, rebuilt exactly inside an interval), so that what
        is held over an interval is only the slowly varying part.
        """
        n = len(t_start)
        cache = self.__dict__.setdefault("_motion_cache", {})
        if n not in cache:  # constant: build once per batch size (an FMU asks for n = 1 every step)
            if len(cache) > 8:
                cache.clear()
            cache[n] = (np.tile(self.inertial_rate_t(), (n, 1)), np.tile(self.specific_force_t(), (n, 1)))
        return cache[n]


# gimbals that carry a moving base's attitude: mat_nv = Rz(yaw) Rx(pitch) Ry(roll)
# (:func:`sarins_fmu.rotations.euler_to_mat`), the turntable's gimbals ride on them
VEHICLE_ATTITUDE_AXES = ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0))


class HeldBase:
    """A moving base whose motion arrives interval by interval (e.g. an FMU input).

    The base frame t is the local-level ENU frame at the vehicle; the
    vehicle's attitude enters the IMU as the gimbals
    :data:`VEHICLE_ATTITUDE_AXES` (constant angular acceleration over each
    interval, like a turntable's).  :meth:`hold` sets the inertial rate of t
    (omega_ie + omega_en, rad/s) and the specific force (m/s^2), both resolved
    in t and held over the next interval; :meth:`base_motion` is the
    moving-base interface of :class:`IMU` (one interval at a time).
    """

    def __init__(self):
        self._motion = None

    def hold(self, rate_t, force_t) -> None:
        rate_t = np.asarray(rate_t, float).reshape(1, 3)
        force_t = np.asarray(force_t, float).reshape(1, 3)
        if not (np.isfinite(rate_t).all() and np.isfinite(force_t).all()):
            raise ValueError("base rate or specific force contains NaN or infinity")
        self._motion = (rate_t, force_t)

    def base_motion(self, t_start, h):
        if self._motion is None:
            raise ValueError("no base motion held for this interval")
        if len(t_start) != 1:
            raise ValueError("a held base gives one interval at a time")
        return self._motion


class IMU:
    """Increment-output IMU stepped over output intervals.

    Parameters
    ----------
    model : ImuModel
    base : StaticBase or any object with ``base_motion(t_start, h)`` (the
        moving-base interface, see :meth:`StaticBase.base_motion`)
    gimbal_axes : (A, 3) turntable gimbal axes (see :mod:`turntable`)
    output_interval : float, s (one Delta theta / Delta v per interval)
    internal_rate : float, Hz (minor loop rate; must give a whole number of
        minor steps per interval)
    seed : int in [0, 2**64), seeds every random stream (white noise, bias
        instability, the time-correlated terms, turn-on bias, ageing), drawn
        in the C core step by step (the same numbers however the run is cut
        into steps)
    thermal_start : 'hot' or 'cold'; ambient : callable T_amb(t) degC
    aging_days : float, age of the drift model since calibration (days)

    The state a step changes lives in the arrays of :mod:`sarins_fmu.imu_step`
    (``thermal`` gives the parameters, the ambient function and the initial
    condition; the reported temperatures are :attr:`temperature`).
    """

    def __init__(self, model: ImuModel, base: StaticBase, gimbal_axes=((0.0, 0.0, 1.0),), *,
                 output_interval: float = 1.0, internal_rate: float = 200.0, seed: int = 0,
                 thermal_start: str = "hot", ambient=Ambient(), aging_days: float = 0.0, t0: float = 0.0):
        if not (output_interval > 0 and math.isfinite(output_interval)):
            raise ValueError(f"output interval must be positive, got {output_interval}")
        if not (internal_rate > 0 and math.isfinite(internal_rate)):
            raise ValueError(f"internal rate must be positive, got {internal_rate}")
        n_sub = output_interval * internal_rate
        if abs(n_sub - round(n_sub)) > 1e-6 or round(n_sub) < 1:
            raise ValueError(f"output interval {output_interval} s is not a whole number of "
                             f"minor steps at {internal_rate} Hz")
        if round(n_sub) > core_imu.MAX_SUB:
            raise ValueError(f"output interval {output_interval} s holds {round(n_sub)} minor steps at "
                             f"{internal_rate} Hz; at most {core_imu.MAX_SUB} (SARINS_IMU_MAX_SUB, core/imu.h)")
        if not (math.isfinite(aging_days) and aging_days >= 0):
            raise ValueError("aging_days must be a non-negative number")
        self.model, self.base = model, base
        self.axes = np.atleast_2d(np.asarray(gimbal_axes, dtype=float))
        self.h, self.n_sub = float(output_interval), int(round(n_sub))
        self.seed, self.t0, self.aging_days = check_seed(seed), float(t0), float(aging_days)
        self.thermal = ThermalModel(model.thermal, ambient, thermal_start, t0)
        self._allocate()
        self.drift_poly = self._state[imu_step.TRIAD][0].copy()  # (a, b, c), aged by aging_days
        self.reset()

    def _allocate(self) -> None:
        """The state tuple of :mod:`sarins_fmu.imu_step`, its constants built by the C core from the model's
        flat parameters (``sarins_imu_build``; the state in :meth:`reset`)."""
        from .imu_params import flatten  # (imu_params imports this module)

        m = self.model
        n_flicker = core_imu.flicker_count(m.flicker_tau_min, m.flicker_tau_max)
        base = np.zeros((2, 3))
        if isinstance(self.base, StaticBase):
            base[0], base[1] = self.base.inertial_rate_t(), self.base.specific_force_t()
        self._state = (np.zeros(imu_step.N_CONSTS), np.zeros(2), np.zeros((4, 6)), np.zeros((3, 6)), np.zeros((10, 3)),
                       np.zeros((7, 3)), np.zeros((9, 3)), np.ascontiguousarray(self.axes), base,
                       np.zeros((len(core_imu.STREAMS), core_rng.WORDS)), np.zeros((8, 6)), np.zeros((3, 6)),
                       np.zeros(n_flicker), np.zeros((n_flicker, 6)), np.zeros((n_flicker, 6)),
                       np.zeros((imu_dynamics.PAR_ROWS, 6)), np.zeros((imu_dynamics.STATE_ROWS, 6)), np.zeros((3, 6)))
        self._table = array_table(self._state)  # the same arrays as the C core sees them
        flat = flatten(m)
        core_imu.build(self._table, [flat[name] for name in core_imu.param_names()], self.t0, self.h, self.n_sub,
                       self.aging_days * DAY, self.seed)

    def reset(self, ambient0: float | None = None) -> None:
        """Return to the state at construction (time, temperatures, random
        streams); ``ambient0`` (degC) overrides the ambient function at t0."""
        self.thermal.reset(self.t0, ambient0)  # the ambient at t0, checked
        core_imu.start(self._table, self.thermal._ambient_now, self.thermal.start == "hot", self.seed)

    @property
    def time(self) -> float:
        """End of the last interval produced, s."""
        return self.t0 + self._state[imu_step.CLOCK][0] * self.h

    @property
    def temperature(self) -> np.ndarray:
        """Reported sensor temperatures at :attr:`time`, degC (6,)."""
        return self._state[imu_step.STATE][0].copy()

    def state_arrays(self) -> tuple:
        """The arrays of :mod:`sarins_fmu.imu_step` (updated in place by every step; keep them alive)."""
        return self._state

    def step(self, angle0, rate0, accel, ambient=None):
        """Produce the increments of the next K output intervals.

        Parameters
        ----------
        angle0, rate0, accel : (K, A) gimbal angles, rates and accelerations
            at the start of each interval (rad, rad/s, rad/s^2).
        ambient : (K,) ambient temperature at each interval end, degC
            (default: the ambient function given at construction).

        Returns
        -------
        dtheta, dv : (K, 3) compensated angle (rad) and velocity (m/s)
            increments in the body frame at each interval start.
        temperatures : (K, 6) sensor temperatures at each interval end, degC.
        """
        angle0, rate0, accel = (np.ascontiguousarray(np.atleast_2d(x), dtype=float) for x in (angle0, rate0, accel))
        if not (angle0.shape == rate0.shape == accel.shape and angle0.shape[1] == self.axes.shape[0]):
            raise ValueError(f"gimbal state arrays must all have shape (K, {self.axes.shape[0]})")
        if not (np.isfinite(angle0).all() and np.isfinite(rate0).all() and np.isfinite(accel).all()):
            raise ValueError("gimbal state contains NaN or infinity")
        n = angle0.shape[0]
        t_end = self._times(n)
        amb_end = np.empty(n)
        amb_end[:] = self.thermal.ambient(t_end) if ambient is None else ambient
        _check_temperature(amb_end)
        w_t, f_t = self.base.base_motion(t_end - self.h, self.h)
        w_t, f_t = (np.ascontiguousarray(x, dtype=float) for x in (w_t, f_t))
        return self._intervals(angle0, rate0, accel, w_t, f_t, amb_end)

    def _intervals(self, angle0, rate0, accel, w_t, f_t, amb_end):
        """K intervals: one C call for a few, the minor loop over the thread pool for many (the same results)."""
        n = amb_end.shape[0]
        if n < core_imu.PARALLEL_MIN:
            return core_imu.steps(self._table, angle0, rate0, accel, w_t, f_t, amb_end)
        s = self._state
        triad, mats = s[imu_step.TRIAD], s[imu_step.MATS]
        temps = np.empty((n, 6))
        g_bias, g_sf, a_bias, a_sf = (np.empty((n, 3)) for _ in range(4))
        core_imu.advance(self._table, amb_end, temps, g_bias, g_sf, a_bias, a_sf)
        dtheta, dv = core_imu.increments(
            s[imu_step.AXES], angle0, rate0, accel, w_t, f_t, self.h, self.n_sub, g_sf, mats[0:3], g_bias,
            triad[1], triad[2], triad[3], mats[3:6], a_sf, mats[6:9], a_bias, triad[4])
        core_imu.dynamics(self._table, temps, dtheta, dv)
        core_imu.white_noise(self._table, dtheta, dv)
        return dtheta, dv, temps

    def _times(self, n):
        """End times of the next n intervals from a step counter (no drift)."""
        k0 = round((self.time - self.t0) / self.h)
        return self.t0 + (k0 + np.arange(1, n + 1)) * self.h


def deterministic_axial_drift(model: ImuModel, temperature, dt: float) -> np.ndarray:
    """Deterministic z-gyro drift (rad/s) along a temperature series.

    eps_z = b + b1 (T - T_REF) + b2 (T - T_REF)^2 + a T^2 + b T + c + d dT/dt + block gradient + hysteresis
    (the z-gyro terms of ``sarins_imu_interval_terms`` and ``sarins_imu_axial_thermal_terms``
    (``sarins_fmu/core/imu.h``) without the Gauss-Markov bias instability and the white noise; ageing as in
    ``model``; the block node and the loop start in equilibrium at the first sample).

    Parameters
    ----------
    temperature : (K,) z-gyro temperature on a uniform grid, degC
    dt : grid step, s (dT/dt by central differences)
    """
    from .core.axial import thermal_terms

    temperature = np.asarray(temperature, dtype=float)
    d = temperature - T_REF
    g = model.gyro
    poly = model.axial_drift_poly
    rate = np.gradient(temperature, dt) if temperature.size > 1 else np.zeros_like(temperature)
    return (g.bias[2] + g.bias_tc1[2] * d + g.bias_tc2[2] * d * d
            + (poly[0] * temperature + poly[1]) * temperature + poly[2] + model.axial_drift_dtdt * rate
            + (thermal_terms(temperature[0], temperature, dt, model.axial_thermal_par) if temperature.size else 0.0))
