"""Seed 000 protocol: axial-drift identification by an RBF network, hot and cold start.

The paper (Yu et al. 2012, "RBF ... axial RLG drifts in single-axis rotation
INS") aligns a single-axis RINS for 4 h at 28.222 deg N, navigates 12 h,
feeds the 12 h latitude error (cold start: also temperature and its change)
to an RBF network that outputs the axial (azimuth) gyro drift, subtracts it
and navigates 72 h.  This module generates seeded experiments, runs them
(in process or through the FMUs, see :mod:`sarins.axial_rbf.runs`), and computes
the quantities of the paper's Tables 2-5.

Experiment model (our choice, stated in ``docs/axial-rbf.md``)
    * **Hot start** (paper sec. 2.2: less than 3 degC change in alignment):
      the unit starts in thermal equilibrium; the ambient is a daily
      sinusoid of amplitude 0..1 degC around 0..45 degC.
    * **Cold start** (sec. 2.3: more than 10 degC, rising steadily): the
      unit starts at the ambient (0..30 degC) and warms by a self-heating of
      18..40 degC with a 5 h time constant, so it still warms during the
      12 h identification window (the paper's Table 4: 3..17 degC).
    * Azimuth drift of the unit (rad/s, T in degC, ``imu.ImuModel``):
      ``eps(T) = eps0 + k1 (T - 40) + k2 (T - 40)^2 + d dT/dt`` with the
      unit constants below and a turn-on constant ``eps0`` drawn per
      experiment so that the true drift over the 72 h after identification
      is uniform in +-0.0035 deg/h (the range of Table 2).
    * Gyro white noise and bias instability are the ``nav-rlg`` preset's own
      (``GYRO_NOISE_SCALE`` = 1; ``Experiment.noise_scale`` is swept by the
      campaign's ``--sweep`` with the site latitude ``lat_deg`` as a
      sensitivity study).  At the preset's ARW 0.0005 deg/sqrt(h) the 12 h
      latitude error alone scatters the identified drift by about
      0.0003 deg/h (1 sigma), the paper's whole error budget; the campaign
      reports the result at that noise (a lower-noise unit would need a gyro
      with a cited ARW, see docs/imu-presets.md).  The other sensor errors
      are the preset's; every run is seeded.

Multi-temperature compensation (sec. 2.3, :mod:`sarins_fmu.identify.multitemp`)
    The unit is calibrated at steady temperature points
    (:func:`calibration_unit`); with the table compensating the z gyro, the
    drift left for the network is the *residual truth*
    ``drift_dph - window_mean_table_dph`` over the same 72 h window.

True drift
    *Simulated truth*: the time mean of the deterministic drift eps(T(t))
    over the evaluation window.  *Paper's truth* (sec. 2.2): the drift that,
    subtracted from the start of navigation when the run is re-done,
    minimises the largest position error over 72 h; the position error is
    affine in the subtracted drift (linear error dynamics, same noise), so
    two runs give it exactly and a scalar search finds the minimiser
    (:func:`paper_true_drift`).

Sign convention: a positive azimuth drift gives a positive latitude error,
``dL(t) = (cos L / W)(1 - cos W t) eps`` (Table 1 with the sign of its
Table 2 data; see tests/test_ins.py).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np

from .. import imu as imu_mod
from ..core.axial import thermal_terms as axial_terms
from ..identify.latitude_kf import estimate_drift, measurement_row
from ..imu_params import apply_overrides
from ..thermal import Ambient, SENSORS, ThermalModel
from ..units import DEG_TO_RAD, DPH_TO_RPS, HOUR, NM, RAD_TO_DEG
from ..site import SITE_LAT_DEG

ALIGN_HOURS = 4.0  # alignment, h (sec. 2.1)
IDENTIFY_HOURS = 12.0  # navigation before identification, h (sec. 2.1)
NAV_HOURS = 72.0  # evaluation window, h
DRIFT_RANGE_DPH = 0.0035  # |true drift| bound, deg/h (Table 2)
T_CENTRE_C = 40.0  # centre of the drift polynomial, degC
K1_DPH_PER_C = 2.0e-4  # linear drift-temperature coefficient of the unit, deg/h/degC
K2_DPH_PER_C2 = 2.0e-6  # quadratic coefficient, deg/h/degC^2
DTDT_DPH_PER_CPH = 1.0e-4  # drift per temperature rate, deg/h per degC/h
GYRO_NOISE_SCALE = 1.0  # the unit's gyro noise / bias instability relative to nav-rlg: its own (docs/imu-presets.md)
HOT_HEATING_C = 16.0  # self-heating of the azimuth gyro on hot starts (in equilibrium), degC
TRUTH_GRID = 60.0  # s, grid of the simulated-truth integral
STARTS = ("hot", "cold")


@dataclass(frozen=True)
class Experiment:
    """One seeded experiment (plain numbers, so it travels to workers).

    drift_dph is the simulated true drift over the 72 h evaluation window
    (deg/h); eps0_dph the turn-on constant that produces it; ambient_c,
    amplitude_c the ambient mean and daily amplitude (degC); heating_c the
    self-heating of the azimuth gyro (degC); seed the noise seed; lat_deg
    the site latitude (deg); noise_scale the gyro white noise and bias
    instability relative to the ``nav-rlg`` preset's; thermal_scale the
    factor k on the azimuth drift's terms beyond temperature (block-gradient
    coefficient, temperature-rate coefficient, hysteresis half-height; the
    block time constant and the loop width unchanged), 1 for the campaign's
    unit (other values: the sensitivity study only, no source).
    """

    name: str
    start: str
    role: str
    seed: int
    drift_dph: float
    eps0_dph: float
    ambient_c: float
    amplitude_c: float
    heating_c: float
    lat_deg: float = SITE_LAT_DEG
    noise_scale: float = GYRO_NOISE_SCALE
    thermal_scale: float = 1.0

    def to_dict(self) -> dict:
        return asdict(self)


def thermal_overrides(heating_c: float) -> dict:
    """Flat IMU parameters of the unit's thermal model (degC, s)."""
    base = imu_mod.preset("nav-rlg").thermal
    ratio = np.asarray(base.self_heating) / base.self_heating[2]
    out = {}
    for j, sensor in enumerate(SENSORS):
        out[f"self_heating_{sensor}"] = float(heating_c * ratio[j])
        out[f"time_constant_{sensor}"] = float(base.time_constant[j])
    return out


def block_terms(thermal_scale: float = 1.0) -> dict:
    """The nav-rlg preset's block-gradient coefficient and hysteresis half-height (SI, flat IMU
    parameters and ``ImuModel`` fields alike) times ``thermal_scale``."""
    base = imu_mod.preset("nav-rlg")
    return {"axial_drift_grad": base.axial_drift_grad * thermal_scale,
            "axial_hysteresis": base.axial_hysteresis * thermal_scale}


def drift_overrides(eps0_dph: float, thermal_scale: float = 1.0) -> dict:
    """Flat IMU parameters (SI) of the azimuth drift eps(T) for a turn-on constant, with the
    terms beyond temperature (rate, block gradient, hysteresis) times ``thermal_scale``."""
    a = K2_DPH_PER_C2
    b = K1_DPH_PER_C - 2 * T_CENTRE_C * K2_DPH_PER_C2
    c = eps0_dph - K1_DPH_PER_C * T_CENTRE_C + K2_DPH_PER_C2 * T_CENTRE_C**2
    return {"axial_drift_a": a * DPH_TO_RPS, "axial_drift_b": b * DPH_TO_RPS, "axial_drift_c": c * DPH_TO_RPS,
            "axial_drift_dtdt": DTDT_DPH_PER_CPH * thermal_scale * DPH_TO_RPS * HOUR,
            **block_terms(thermal_scale),
            "gyro_bias_z": 0.0, "gyro_bias_tc1_z": 0.0, "gyro_bias_tc2_z": 0.0,
            "aging_sigma_a": 0.0, "aging_sigma_b": 0.0, "aging_sigma_c": 0.0}


def imu_overrides(exp: Experiment) -> dict:
    """All flat IMU parameters (SI) that turn the nav-rlg preset into this experiment's unit."""
    base = imu_mod.preset("nav-rlg").gyro
    noise = {}
    for i, ax in enumerate("xyz"):
        noise[f"gyro_random_walk_{ax}"] = float(base.random_walk[i] * exp.noise_scale)
        noise[f"gyro_bias_instability_{ax}"] = float(base.bias_instability[i] * exp.noise_scale)
    return {**thermal_overrides(exp.heating_c), **drift_overrides(exp.eps0_dph, exp.thermal_scale), **noise}


def imu_model(exp: Experiment) -> imu_mod.ImuModel:
    return apply_overrides(imu_mod.preset("nav-rlg"), imu_overrides(exp))


def ambient(exp: Experiment) -> Ambient:
    """Ambient of the experiment: mean + daily sinusoid (phase 0), degC."""
    return Ambient(mean=exp.ambient_c, amplitude=exp.amplitude_c, period=86400.0)


def gyro_z_temperature(exp: Experiment, times: np.ndarray) -> np.ndarray:
    """Azimuth gyro temperature (degC) at ``times`` (s from the run start)."""
    model = ThermalModel(imu_model(exp).thermal, ambient(exp), start=exp.start)
    return model.advance(times)[:, 2]


def drift_series_dph(exp_or_eps0, temperature: np.ndarray, dt: float, temp0_c: float | None = None) -> np.ndarray:
    """Deterministic azimuth drift eps(T) + d dT/dt + gradient + hysteresis, deg/h, of a
    temperature series (degC) on a grid of ``dt`` s (the rate by central differences).

    ``temp0_c``: z temperature one step before the series' first sample, where the unit
    was switched on (the block node and the loop start there, :func:`thermal_terms_dph`);
    default the first sample.  The terms beyond temperature carry the experiment's
    ``thermal_scale`` (1 for a bare turn-on constant)."""
    is_exp = isinstance(exp_or_eps0, Experiment)
    eps0 = exp_or_eps0.eps0_dph if is_exp else float(exp_or_eps0)
    scale = exp_or_eps0.thermal_scale if is_exp else 1.0
    rate_cph = np.gradient(temperature, dt) * HOUR
    return (steady_drift_dph(eps0, temperature) + DTDT_DPH_PER_CPH * scale * rate_cph
            + thermal_terms_dph(temperature, dt, temp0_c, scale))


def thermal_terms_dph(temperature: np.ndarray, dt: float, temp0_c: float | None = None,
                      thermal_scale: float = 1.0) -> np.ndarray:
    """The block-gradient and heating/cooling hysteresis terms of the unit's azimuth drift (deg/h)
    along a z temperature series (degC) on a grid of ``dt`` s, from switch-on at ``temp0_c`` (one
    step before the first sample; default the first sample): the C core's
    ``sarins_imu_axial_thermal_terms`` with the nav-rlg preset's coefficients (the campaign's unit
    keeps them; the gradient coefficient and the hysteresis half-height times ``thermal_scale``),
    each value the term's mean over the step that ends at the sample."""
    temperature = np.asarray(temperature, float)
    t0 = float(temperature[0] if temp0_c is None else temp0_c)
    par = replace(imu_mod.preset("nav-rlg"), **block_terms(float(thermal_scale))).axial_thermal_par
    return axial_terms(t0, temperature, float(dt), par) / DPH_TO_RPS


def hysteresis_dph(thermal_scale: float = 1.0) -> float:
    """Half-height of the unit's heating/cooling loop, deg/h (heating branch +, cooling branch -)."""
    return float(block_terms(thermal_scale)["axial_hysteresis"] / DPH_TO_RPS)


def switch_on_temperature(exp: Experiment) -> float:
    """z-gyro temperature at switch-on (t = 0), degC."""
    return float(ThermalModel(imu_model(exp).thermal, ambient(exp), start=exp.start).temperature[2])


def steady_drift_dph(eps0_dph: float, temperature) -> np.ndarray:
    """The drift law at a steady temperature (degC): eps0 + k1 (T - 40) + k2 (T - 40)^2, deg/h."""
    dev = np.asarray(temperature, float) - T_CENTRE_C
    return eps0_dph + K1_DPH_PER_C * dev + K2_DPH_PER_C2 * dev**2


def window_temperature(exp: Experiment, start_h: float, end_h: float):
    """z-gyro temperature (degC) on the TRUTH_GRID from the run start to just
    past ``end_h`` h of navigation, and the selection of ``[start_h, end_h]``."""
    t0 = (ALIGN_HOURS + start_h) * HOUR
    times = np.arange(TRUTH_GRID, (ALIGN_HOURS + end_h) * HOUR + 2 * TRUTH_GRID, TRUTH_GRID)
    sel = (times >= t0) & (times <= (ALIGN_HOURS + end_h) * HOUR)
    return gyro_z_temperature(exp, times), sel


def window_mean_drift_dph(exp: Experiment, start_h: float, end_h: float) -> float:
    """Simulated true drift: time mean of the deterministic drift (deg/h)
    over ``[start_h, end_h]`` hours of navigation."""
    temp, sel = window_temperature(exp, start_h, end_h)
    return float(np.mean(drift_series_dph(exp, temp, TRUTH_GRID, switch_on_temperature(exp))[sel]))


def window_mean_table_dph(exp: Experiment, table, start_h: float = 0.0, end_h: float = NAV_HOURS) -> float:
    """Time mean (deg/h) of what a multi-temperature table (``drift_at(temp_c)``,
    :mod:`sarins_fmu.identify.multitemp`) subtracts over ``[start_h, end_h]``
    hours of navigation; the drift left for the network is
    ``window_mean_drift_dph - window_mean_table_dph`` (the residual truth)."""
    temp, sel = window_temperature(exp, start_h, end_h)
    return float(np.mean(table.drift_at(temp)[sel]))


def calibration_unit(seed: int, noise_scale: float = GYRO_NOISE_SCALE, thermal_scale: float = 1.0) -> Experiment:
    """The unit as it stands in the multi-temperature calibration: the
    campaign's drift law with turn-on constant 0, the hot-start self-heating,
    its own noise seed (:func:`sarins_fmu.identify.multitemp.calibrate_axial_drift`)."""
    return Experiment("calibration", "hot", "calibration", int(seed), 0.0, 0.0, 20.0, 0.0, HOT_HEATING_C,
                      SITE_LAT_DEG, float(noise_scale), float(thermal_scale))


def generate(start: str, n_train: int, n_test: int, seed: int, *, lat_deg: float = SITE_LAT_DEG,
             noise_scale: float = GYRO_NOISE_SCALE, thermal_scale: float = 1.0) -> list[Experiment]:
    """Seeded training and held-out experiments of one start kind.

    The true drift (72 h mean from the start of navigation) is uniform in
    +-DRIFT_RANGE_DPH; ambient and heating per the hot/cold definitions.
    ``lat_deg`` (site, deg), ``noise_scale`` (gyro noise relative to
    nav-rlg) and ``thermal_scale`` (:class:`Experiment`) do not enter the
    draws: the same seed gives the same drifts, temperatures and noise seeds
    at every latitude and scale (the turn-on constant follows the unit).
    """
    if start not in STARTS:
        raise ValueError(f"start must be 'hot' or 'cold', got {start!r}")
    if n_train < 2 or n_test < 1:
        raise ValueError("need at least 2 training and 1 test experiments")
    if not (np.isfinite(lat_deg) and abs(lat_deg) <= 80.0):
        raise ValueError(f"site latitude must be within +-80 deg, got {lat_deg}")
    if not (np.isfinite(noise_scale) and noise_scale >= 0.0):
        raise ValueError(f"gyro noise scale must be a non-negative number, got {noise_scale}")
    if not (np.isfinite(thermal_scale) and thermal_scale >= 0.0):
        raise ValueError(f"thermal scale must be a non-negative number, got {thermal_scale}")
    rng = np.random.default_rng([int(seed), STARTS.index(start)])
    out = []
    for i in range(n_train + n_test):
        role = "train" if i < n_train else "test"
        drift = float(rng.uniform(-DRIFT_RANGE_DPH, DRIFT_RANGE_DPH))
        if start == "hot":
            amb, amp, heat = float(rng.uniform(0.0, 45.0)), float(rng.uniform(0.0, 1.0)), HOT_HEATING_C
        else:
            amb, amp, heat = float(rng.uniform(0.0, 30.0)), 0.0, float(rng.uniform(18.0, 40.0))
        proto = Experiment(f"{start}-{role}-{i:03d}", start, role, int(rng.integers(0, 2**31 - 1)),
                           drift, 0.0, amb, amp, heat, float(lat_deg), float(noise_scale), float(thermal_scale))
        offset = window_mean_drift_dph(proto, 0.0, NAV_HOURS)  # drift of the unit with eps0 = 0
        out.append(Experiment(**{**proto.to_dict(), "eps0_dph": drift - offset}))
    return out


def features(lat_error_12h: float, temp_12h: float, temp_change_align: float) -> dict:
    """The network's inputs in the paper's units: latitude error (deg) after
    12 h of navigation, azimuth gyro temperature then (degC) and its change
    over the alignment (degC)."""
    return {"lat_error_deg": lat_error_12h * RAD_TO_DEG, "temp_c": float(temp_12h),
            "temp_change_c": float(temp_change_align)}


HOT_INPUTS = ("lat_error_deg",)
COLD_INPUTS = ("lat_error_deg", "temp_c", "temp_change_c")


def deterministic_errors(exp: Experiment, hours: float = IDENTIFY_HOURS) -> tuple[float, float]:
    """Latitude and longitude errors (rad) after ``hours`` of navigation that
    the experiment's deterministic azimuth drift alone causes (closed form,
    :func:`sarins_fmu.static_errors.drift_history_errors`)."""
    from ..static_errors import drift_history_errors

    temp, sel = window_temperature(exp, 0.0, hours)
    eps = drift_series_dph(exp, temp, TRUTH_GRID, switch_on_temperature(exp))[sel] * DPH_TO_RPS
    tau = np.arange(eps.size) * TRUTH_GRID
    return drift_history_errors(hours * HOUR, tau, eps, exp.lat_deg * DEG_TO_RAD)


def closed_form_drift_dph(lat_error_deg: np.ndarray, hours: float = IDENTIFY_HOURS,
                          lat_deg: float = SITE_LAT_DEG) -> np.ndarray:
    """Table 1 inverted: eps = dL W / (cos L (1 - cos W t)), deg/h from deg.

    Uses this project's sign (positive drift -> positive latitude error)."""
    gain_h = measurement_row(hours * HOUR, lat_deg * DEG_TO_RAD)[0] / HOUR  # deg of latitude per deg/h
    return np.asarray(lat_error_deg, float) / gain_h


def paper_true_drift(err0: np.ndarray, err1: np.ndarray, drift1_dph: float,
                     bound_dph: float = 0.02) -> tuple[float, float]:
    """Drift (deg/h) minimising the largest position error of a re-run.

    err0, err1 : (K, 2) north/east position errors (m) over the window of the
        run without correction and of the run with ``drift1_dph`` subtracted
        (both from the start of navigation, same noise).  The errors are
        affine in the subtracted drift c, e(c) = err0 + c (err1 - err0)/drift1.
    Returns (c*, max position error at c* in nmi).
    """
    from scipy.optimize import minimize_scalar

    if abs(drift1_dph) < 1e-9:
        raise ValueError("the second run needs a non-zero drift correction")
    slope = (np.asarray(err1, float) - np.asarray(err0, float)) / drift1_dph

    def worst(c):
        e = err0 + c * slope
        return float(np.max(np.hypot(e[:, 0], e[:, 1])))

    res = minimize_scalar(worst, bounds=(-bound_dph, bound_dph), method="bounded",
                          options={"xatol": 1e-8})
    return float(res.x), worst(res.x) / NM


# ---------------------------------------------------------------- training and comparisons
# what a model trained by this protocol expects of the runs it identifies (stored in its metadata;
# ``sarins replay --identify`` checks a log against it)
PROTOCOL = {"align_hours": ALIGN_HOURS, "identify_hours": IDENTIFY_HOURS, "step_s": 1.0}
SPREADS = (1.0, 2.0, 4.0, 8.0)  # SPREAD candidates (standardised inputs), chosen by leave-one-out
RBF_GOAL = 0.0003**2  # (deg/h)^2: the paper's 0.0003 deg/h training error as an RMS


def loo_errors(X: np.ndarray, y: np.ndarray, spread: float, goal: float = RBF_GOAL) -> np.ndarray:
    """Leave-one-out prediction errors of the RBF network (one refit per sample)."""
    from ..identify import RBFNetwork

    err = np.empty(len(y))
    for i in range(len(y)):
        keep = np.arange(len(y)) != i
        net = RBFNetwork(spread=spread, goal=goal).fit(X[keep], y[keep])
        err[i] = net.predict(X[i:i + 1])[0] - y[i]
    return err


def train_rbf(rows: list[dict], inputs: tuple, path, *, spread: float | None = None, goal: float = RBF_GOAL,
              target: str = "drift_dph"):
    """Fit the RBF network on training rows (dicts of features + target) and
    save it to ``path`` (None: not saved).

    ``spread`` None: the SPREAD of :data:`SPREADS` with the smallest
    leave-one-out RMS error on the training rows (2 below 4 rows; the paper's SPREAD = 2 is
    in raw input units, where its latitude inputs span only ~0.05 deg; with
    standardised inputs the equivalent width is chosen from the data).
    Returns the fitted :class:`~sarins_fmu.identify.RBFNetwork`; its
    metadata holds the leave-one-out RMS of every candidate."""
    from ..identify import RBFNetwork

    X = np.array([[r[n] for n in inputs] for r in rows], float)
    y = np.array([r[target] for r in rows], float)
    cv = {}
    if spread is None and len(y) < 4:  # too few rows to cross-validate: the paper's value
        spread = 2.0
    if spread is None:
        cv = {str(s): float(np.sqrt(np.mean(loo_errors(X, y, s, goal) ** 2))) for s in SPREADS}
        spread = float(min(SPREADS, key=lambda s: cv[str(s)]))
    lats = {float(r.get("lat_deg", SITE_LAT_DEG)) for r in rows}
    if len(lats) != 1:
        raise ValueError(f"training rows from several sites {sorted(lats)}: one model per site latitude")
    net = RBFNetwork(spread=spread, goal=goal).fit(X, y, input_names=list(inputs), target_name="drift_dph")
    net.metadata = {"local_lat_deg": lats.pop(), "n_samples": int(len(y)), "source": "sarins campaign axial-rbf",
                    "target": target, "loo_rms_dph": cv, **PROTOCOL}
    if path is not None:
        net.save(path)
    return net


def linear_regression(rows: list[dict], inputs: tuple, target: str = "drift_dph"):
    """Least-squares affine fit drift = w0 + w . x; returns predict(rows) -> (n,)."""
    X = np.array([[r[n] for n in inputs] for r in rows], float)
    y = np.array([r[target] for r in rows], float)
    A = np.column_stack([np.ones(len(y)), X])
    w, *_ = np.linalg.lstsq(A, y, rcond=None)

    def predict(test_rows):
        Xt = np.array([[r[n] for n in inputs] for r in test_rows], float)
        return np.column_stack([np.ones(len(Xt)), Xt]) @ w

    return predict


def kalman_drift_dph(time_h: np.ndarray, lat_error_deg: np.ndarray, hours: float = IDENTIFY_HOURS) -> float:
    """Comparison (c): the latitude-error Kalman filter's drift at ``hours``, deg/h."""
    sel = np.asarray(time_h) <= hours + 1e-9
    est = estimate_drift(np.asarray(time_h)[sel] * HOUR, np.asarray(lat_error_deg)[sel] * DEG_TO_RAD,
                         SITE_LAT_DEG * DEG_TO_RAD)
    return est["drift"] / DPH_TO_RPS


def compensated_max_nmi(result: dict, drift_dph: float) -> float:
    """Largest 72 h position error (nmi) of a re-run subtracting ``drift_dph``,
    from the affine map stored by the test task (uncompensated errors + slope)."""
    err = result["err0_ne"] + drift_dph * result["slope_ne"]
    return float(np.max(np.hypot(err[:, 0], err[:, 1])) / NM)
