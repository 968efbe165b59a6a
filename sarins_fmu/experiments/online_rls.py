"""Seed 002: azimuth-drift model updated online at vehicle stops.

Scenario functions (plain data in, dicts of numbers/arrays out, so they run
as campaign tasks):

* :func:`simulate_stop`: one stop on a static base: turntable (RINS rotating
  about azimuth) -> IMU -> free INS -> stop Kalman filter (eqs 4-6); the
  30-minute drift estimate against the truth.
* :func:`model_update_run`: the paper's 300-day simulation (eqs 19-21,
  Figs 4-5): Markov-ageing coefficients, 20 stops at random days and random
  temperatures, models without update / RLS / FF-RLS, the S metric.
* :func:`vehicle_test`: about a year of ageing with the Fig. 2 online logic
  on simulated drives with stops, then a 6 h drive navigated with the
  initial and the updated model (Fig. 8, Table 5).

Units: SI inside (rad/s, s); ``_dph`` names carry °/h; temperatures °C.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .. import imu as imu_mod
from .. import turntable
from ..identify.rls import ForgettingRLS, RLSSettings, fit_quadratic_temperature_model
from ..imu import IMU, ImuModel, StaticBase
from ..ins import InsConfig, StrapdownINS
from ..identify.online import OnlineDriftUpdater
from ..kalman import StopFilterSettings, StopKalmanFilter
from ..rotations import euler_to_mat, mat_to_euler, rotvec_to_mat
from ..thermal import Ambient
from ..vehicle import random_legs
from ..units import ARCSEC_TO_RAD, DAY, DEG_TO_RAD, DPH_TO_RPS, DPSH_TO_RPSS, RPS_TO_DPH, UG_TO_MPS2
from .online_rls_vehicle import (GYRO_Z, INTERNAL_RATE, VEHICLE_BODY, InProcessEngine, VehicleRun,
                                 position_errors, reference_navigation)

TEMPERATURE_RANGE = (0.0, 50.0)  # degC, seed 002's stop temperatures and S-metric range
N_STOPS = 20  # seed 002: stops in the 300-day simulation
SIM_DAYS = 300.0  # seed 002: simulated days
MONTE_CARLO_RUNS = 100  # seed 002, Fig. 6 / Table 2
DRIVE_ALIGN_TIME = 900.0  # s, the test drive's alignment at rest before it moves (our choice)


def premise_model() -> ImuModel:
    """The nav-rlg unit under the paper's premise that 30 min of stop resolve
    the azimuth drift to 0.002 °/h: angle random walk 0.00001 °/√h (1/50 of
    nav-rlg), velocity random walk 1 µg/√Hz (1/5) and no gyro or
    accelerometer bias instability; everything else (drift model,
    temperature terms, scale factors, misalignments) as nav-rlg."""
    base = imu_mod.preset("nav-rlg")
    gyro = replace(base.gyro, random_walk=np.full(3, 0.00001 * DPSH_TO_RPSS), bias_instability=np.zeros(3))
    accel = replace(base.accel, random_walk=np.full(3, 1.0 * UG_TO_MPS2), bias_instability=np.zeros(3))
    return replace(base, gyro=gyro, accel=accel)


NOISE_TAG = "-noise"  # unit name '<preset>-noise<k>': the preset's stop noise x k (noise_scaled)


def noise_scaled(model: ImuModel, k: float) -> ImuModel:
    """``model`` with its stop-noise terms multiplied by ``k``: the gyro's and the accelerometer's
    white noise (angle / velocity random walk) and Gauss-Markov bias instability, the four terms
    :func:`premise_model` changes; everything else (drift model, ageing, biases, temperature terms,
    correlation times) as ``model``.  k = 1 returns ``model`` unchanged."""
    if not (math.isfinite(k) and k > 0.0):
        raise ValueError(f"the noise factor must be a positive number, got {k!r}")
    gyro = replace(model.gyro, random_walk=model.gyro.random_walk * k,
                   bias_instability=model.gyro.bias_instability * k)
    accel = replace(model.accel, random_walk=model.accel.random_walk * k,
                    bias_instability=model.accel.bias_instability * k)
    return replace(model, gyro=gyro, accel=accel)


def noise_unit_name(preset: str, k: float) -> str:
    """The unit name of ``preset`` with its stop noise x ``k`` (:func:`imu_unit` reads it back)."""
    noise_scaled(imu_mod.preset(preset), k)  # checks the preset and k
    return f"{preset}{NOISE_TAG}{k:.6g}"


def imu_unit(name: str) -> ImuModel:
    """'premise' (see :func:`premise_model`), an IMU preset name, or '<preset>-noise<k>': the
    preset with its stop-noise terms x k (:func:`noise_scaled`; e.g. 'nav-rlg-noise0.25', the unit
    of ``sarins campaign online-rls --calibrate``)."""
    if name == "premise":
        return premise_model()
    preset, tag, factor = name.rpartition(NOISE_TAG)
    if tag and preset:
        try:
            k = float(factor)
        except ValueError:
            raise ValueError(f"bad noise factor in unit name {name!r}") from None
        return noise_scaled(imu_mod.preset(preset), k)
    return imu_mod.preset(name)


def model_drift(model: ImuModel, temperature) -> np.ndarray:
    """Deterministic azimuth drift ε(T) = a T² + b T + c + constant z bias, rad/s."""
    a, b, c = model.axial_drift_poly
    t = np.asarray(temperature, float)
    return (a * t + b) * t + c + model.gyro.bias[GYRO_Z]


def _perturbed_attitude(mat_true: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """mat_computed = (I - [phi x]) mat_true, orthonormalised (phi in n, rad)."""
    return rotvec_to_mat(-np.asarray(phi, float)) @ mat_true


@dataclass(frozen=True)
class StopData:
    """One simulated stop on a static base, what every stop filter sees (SI).

    model : the IMU unit.  lat : rad.  step : s, the IMU output interval.  table : the turntable's
    forward-reverse azimuth rotation.  phi0 : (3,) rad, the INS's initial attitude error (ENU);
    velocity0 : (2,) m/s, its initial east / north velocity error.  dtheta, dv : (n, 3) the IMU's
    increments (rad, m/s, body).  temps : (n, 3) gyro temperatures, degC.  comp : (n,) rad/s, the
    azimuth-gyro compensation the INS subtracts (zeros without a model).
    """

    model: ImuModel
    lat: float
    step: float
    table: turntable.GimbalSchedule
    phi0: np.ndarray
    velocity0: np.ndarray
    dtheta: np.ndarray
    dv: np.ndarray
    temps: np.ndarray
    comp: np.ndarray

    def attitude(self, k: int) -> np.ndarray:
        """(3, 3) true body-to-ENU matrix of the IMU at the start of step k."""
        return turntable.chain_matrix(self.table.axes, self.table.state(k * self.step)[0][0])


def stop_data(*, imu: str = "nav-rlg", lat_deg: float = 40.0, temperature: float = 30.0,
              duration: float = 1800.0, seed: int = 0, coefficients=None, compensation=None,
              tilt0_arcsec: float = 10.0, heading0_deg: float = 0.05, velocity0: float = 0.3,
              step: float = 1.0, internal_rate: float = 100.0) -> StopData:
    """The IMU record and initial INS errors of one stop (parameters as :func:`simulate_stop`)."""
    if not (math.isfinite(duration) and duration >= 2 * step):
        raise ValueError("duration must cover at least two steps")
    model = imu_unit(imu)
    if coefficients is not None:
        model = replace(model, axial_drift_poly=np.asarray(coefficients, float), aging_sigma=np.zeros(3))
    lat = lat_deg * DEG_TO_RAD
    rng = np.random.default_rng([seed, 2])
    n = int(round(duration / step))
    table = turntable.single_axis("forward-reverse", (n + 1) * step, grid=step)
    base = StaticBase(lat, 0.0, 0.0, 0.0)
    ambient = Ambient(mean=temperature - model.thermal.self_heating[GYRO_Z])
    sensor = IMU(model, base, table.axes, output_interval=step, internal_rate=internal_rate, seed=seed,
                 thermal_start="hot", ambient=ambient)
    phi0 = rng.standard_normal(3) * np.array([tilt0_arcsec * ARCSEC_TO_RAD, tilt0_arcsec * ARCSEC_TO_RAD,
                                              heading0_deg * DEG_TO_RAD])
    v0 = rng.standard_normal(2) * velocity0
    angle, rate, accel = table.state(np.arange(n) * step)
    dtheta, dv, temps = sensor.step(angle, rate, accel)
    comp = np.zeros(n) if compensation is None else np.polyval(np.asarray(compensation, float), temps[:, GYRO_Z])
    return StopData(model=model, lat=lat, step=step, table=table, phi0=phi0, velocity0=v0, dtheta=dtheta, dv=dv,
                    temps=temps, comp=comp)


def simulate_stop(*, imu: str = "nav-rlg", lat_deg: float = 40.0, temperature: float = 30.0,
                  duration: float = 1800.0, seed: int = 0, coefficients=None, compensation=None,
                  tilt0_arcsec: float = 10.0, heading0_deg: float = 0.05, velocity0: float = 0.3,
                  step: float = 1.0, internal_rate: float = 100.0) -> dict:
    """One stop: the stop filter's azimuth-drift estimate against the truth.

    Parameters
    ----------
    imu : 'premise' or an IMU preset name.
    lat_deg : latitude, deg.  temperature : azimuth gyro temperature, °C
        (hot start: the ambient is set so that the gyro sits at it).
    duration : stop length, s.  seed : noise seed (also the initial errors).
    coefficients : (3,) true [a, b, c] of the azimuth drift, rad/s per °C^n
        (default the unit's own; e.g. the aged coefficients of a day).
    compensation : (3,) [a, b, c] the INS subtracts during the stop (the
        current model), rad/s per °C^n; default none.
    tilt0_arcsec, heading0_deg, velocity0 : std of the INS errors at the
        start of the stop (after driving), arcsec, deg, m/s.

    Returns
    -------
    dict: ``truth_dph``, ``estimate_dph``, ``error_dph``, ``std_dph`` (filter
    1σ), ``mean_temperature``, and the convergence curve ``time``,
    ``estimate_curve_dph``, ``std_curve_dph``.
    """
    d = stop_data(imu=imu, lat_deg=lat_deg, temperature=temperature, duration=duration, seed=seed,
                  coefficients=coefficients, compensation=compensation, tilt0_arcsec=tilt0_arcsec,
                  heading0_deg=heading0_deg, velocity0=velocity0, step=step, internal_rate=internal_rate)
    n = d.dtheta.shape[0]
    ins = StrapdownINS(InsConfig(lat=d.lat, align_time=0.0, step=step),
                       initial_attitude=_perturbed_attitude(d.attitude(0), d.phi0))
    ins.v[:2] = d.velocity0
    kf = StopKalmanFilter(d.lat, StopFilterSettings.for_model(d.model), dt=step, history_limit=n)
    out = ins.step(d.dtheta, d.dv, d.comp)
    kf.step(out[:, 3:5], out[:, 6:9], d.comp, d.temps[:, GYRO_Z])
    truth = float(model_drift(d.model, kf.mean_temperature))
    curve = kf.convergence()
    return {
        "truth_dph": truth * RPS_TO_DPH,
        "estimate_dph": kf.drift_estimate * RPS_TO_DPH,
        "error_dph": (kf.drift_estimate - truth) * RPS_TO_DPH,
        "std_dph": kf.drift_std * RPS_TO_DPH,
        "mean_temperature": kf.mean_temperature,
        "time": curve[:, 0],
        "estimate_curve_dph": (curve[:, 1] + d.comp.mean()) * RPS_TO_DPH,
        "std_curve_dph": curve[:, 2] * RPS_TO_DPH,
    }


# --------------------------------------------------------------------------
# the 300-day simulation (Figs 4-6, Tables 1-2)
# --------------------------------------------------------------------------

SENSITIVITY_LAMBDAS = (0.5, 0.6, 0.7, 0.8, 0.9, 0.95)
AGEING_KINDS = ("markov", "integrated")


def _integrated_markov_fraction(n_days: float, tau_days: float) -> float:
    """std of a sum of n stationary unit-variance AR(1) samples (corr. time tau) / n."""
    r = n_days / tau_days
    return math.sqrt(2.0 / r**2 * (r - 1.0 + math.exp(-r)))


def aged_coefficients(model: ImuModel, days: np.ndarray, seed: int, kind: str = "markov") -> np.ndarray:
    """True azimuth-drift coefficients (D, 3) on the day grid ``days`` (0, 1, 2, ...).

    ``'markov'``: θ_k = θ_0 + M_k with M a first-order Markov process started
    at 0 (eq. 20 as :func:`sarins_fmu.imu.aged_drift_poly` reads it).
    ``'integrated'``: θ_{k+1} = θ_k + M_k (eq. 20 read as a recursion whose
    increment is the Markov process, started stationary), which gives
    smooth, trend-like ageing; its increment std is scaled so that the
    rms change over 300 days equals that of ``'markov'``.
    """
    if kind == "markov":
        return imu_mod.aged_drift_poly(model, days, seed=seed)
    if kind != "integrated":
        raise ValueError(f"ageing must be one of {AGEING_KINDS}, got {kind!r}")
    tau = model.aging_corr_time / DAY
    n = len(days)
    rng = np.random.default_rng([seed, 30])
    target = model.aging_sigma * math.sqrt(1.0 - math.exp(-2.0 * SIM_DAYS / tau))
    sigma_m = target / (SIM_DAYS * _integrated_markov_fraction(SIM_DAYS, tau))
    phi = math.exp(-1.0 / tau)
    w = rng.standard_normal((n, 3)) * sigma_m
    m = np.empty((n, 3))
    m[0] = w[0]
    for k in range(1, n):  # one step per simulated day
        m[k] = phi * m[k - 1] + math.sqrt(1.0 - phi**2) * w[k]
    return model.axial_drift_poly + np.concatenate([np.zeros((1, 3)), np.cumsum(m[:-1], axis=0)])


def _scaled_ageing(model: ImuModel, scale: float) -> ImuModel:
    """``model`` with its ageing standard deviations multiplied by ``scale``."""
    if not (math.isfinite(scale) and scale >= 0):
        raise ValueError(f"ageing_scale must be >= 0, got {scale!r}")
    return replace(model, aging_sigma=model.aging_sigma * scale)


def s_metric(coef_true, coef_model, t_range=TEMPERATURE_RANGE) -> float:
    """Area between two quadratic drift curves over ``t_range`` (seed 002 eq. 21).

    S = ∫ |f(T) - f̂(T)| dT, exactly (the difference is split at its real
    roots).  Coefficients [a, b, c] in any drift unit per °C^n; S is in
    that unit times °C.
    """
    d = np.asarray(coef_true, float) - np.asarray(coef_model, float)
    lo, hi = float(t_range[0]), float(t_range[1])
    if not (math.isfinite(lo) and math.isfinite(hi) and hi > lo):
        raise ValueError(f"bad temperature range {t_range!r}")
    roots = np.roots(d) if np.any(d[:2] != 0) else np.array([])
    cuts = sorted(r.real for r in np.atleast_1d(roots) if abs(r.imag) < 1e-12 and lo < r.real < hi)
    integral = np.polyint(d)
    edges = [lo, *cuts, hi]
    return float(sum(abs(np.polyval(integral, b) - np.polyval(integral, a)) for a, b in zip(edges[:-1], edges[1:])))


def _calibration(model_coef, unit: str, seed: int, lat_deg: float, temperatures) -> tuple[np.ndarray, np.ndarray]:
    """Initial calibration (eq. 19): stop-filter estimates at ``temperatures``."""
    drifts = np.array([simulate_stop(imu=unit, lat_deg=lat_deg, temperature=float(t), seed=seed * 1000 + 900 + i,
                                     coefficients=model_coef)["estimate_dph"]
                       for i, t in enumerate(temperatures)])
    return np.asarray(temperatures, float), drifts * DPH_TO_RPS


def model_update_run(*, seed: int = 0, unit: str = "premise", days: float = SIM_DAYS, n_stops: int = N_STOPS,
                     lat_deg: float = 40.0, forgetting_factor: float = 0.8,
                     sensitivity=SENSITIVITY_LAMBDAS, calibration_points: int = 11,
                     estimate: str = "filter", ageing: str = "markov", ageing_scale: float = 1.0) -> dict:
    """One run of the paper's simulation study (eqs 19-21, Figs 4-5, Table 1).

    The azimuth-drift coefficients age as first-order Markov processes with
    a 360-day correlation time (eq. 20, :func:`sarins_fmu.imu.aged_drift_poly`)
    from the unit's calibration (our eq. 19).  At day 0 a calibration at
    ``calibration_points`` temperatures over 0..50 °C gives the initial model
    (quadratic least squares, its residual reported); then ``n_stops`` stops
    on random days in 1..``days`` at random temperatures in 0..50 °C give
    drift estimates that update the model by RLS (λ = 1) and FF-RLS (λ,
    m = one month).  ``estimate='filter'`` simulates every stop (IMU + INS +
    stop Kalman filter, 30 min); ``'truth'`` uses the true drift (no
    estimation error, to isolate the update method).  ``ageing`` selects
    the reading of eq. 20 (:func:`aged_coefficients`); ``ageing_scale``
    multiplies the unit's ageing standard deviations (sensitivity study).

    Returns
    -------
    dict with the S values (°/h·°C) ``s_none``, ``s_rls``, ``s_ff`` and
    ``s_lambda`` (one per ``sensitivity`` λ), the calibration residual, the
    stop days/temperatures/estimates/errors, and daily truth and per-stop
    model coefficients (°/h per °C^n) for Figs 4-5.
    """
    if estimate not in ("filter", "truth"):
        raise ValueError("estimate must be 'filter' or 'truth'")
    if n_stops < 1 or days < n_stops:
        raise ValueError("need at least one stop and no more stops than days")
    model = _scaled_ageing(imu_unit(unit), ageing_scale)
    rng = np.random.default_rng([seed, 20])
    grid = np.arange(0.0, math.floor(days) + 1.0)
    truth = aged_coefficients(model, grid, seed, ageing)  # (D, 3) rad/s per degC^n
    stop_days = np.sort(rng.choice(np.arange(1, len(grid)), size=n_stops, replace=False)).astype(float)
    stop_temps = rng.uniform(*TEMPERATURE_RANGE, size=n_stops)
    cal_t = np.linspace(*TEMPERATURE_RANGE, calibration_points)
    if estimate == "filter":
        cal_t, cal_z = _calibration(truth[0], unit, seed, lat_deg, cal_t)
    else:
        cal_z = model_drift(replace(model, axial_drift_poly=truth[0]), cal_t)
    fit = fit_quadratic_temperature_model(cal_t, cal_z)
    lambdas = [1.0, forgetting_factor, *sensitivity]
    models = [ForgettingRLS.from_calibration(cal_t, cal_z, 0.0, RLSSettings(lam)) for lam in lambdas]
    est = np.empty(n_stops)
    err = np.empty(n_stops)
    history = np.empty((n_stops, len(lambdas), 3))
    for i, (day, temp) in enumerate(zip(stop_days, stop_temps)):
        coef = truth[int(day)]
        if estimate == "filter":
            r = simulate_stop(imu=unit, lat_deg=lat_deg, temperature=float(temp), seed=seed * 1000 + i,
                              coefficients=coef)
            est[i], t_gz = r["estimate_dph"] * DPH_TO_RPS, r["mean_temperature"]
        else:
            t_gz = float(temp)
            est[i] = model_drift(replace(model, axial_drift_poly=coef), t_gz)
        err[i] = est[i] - model_drift(replace(model, axial_drift_poly=coef), t_gz)
        for j, m in enumerate(models):
            m.update(t_gz, est[i], day * DAY)
            history[i, j] = m.parameters
    final = truth[int(stop_days[-1])]
    bias_z = model.gyro.bias[GYRO_Z]
    final_c = final + np.array([0.0, 0.0, bias_z])
    s_of = lambda coef: s_metric(final_c * RPS_TO_DPH, coef * RPS_TO_DPH)  # noqa: E731
    return {
        "seed": seed, "unit": unit, "estimate": estimate, "ageing": ageing, "ageing_scale": ageing_scale,
        "s_none": s_of(fit.coefficients), "s_rls": s_of(models[0].parameters), "s_ff": s_of(models[1].parameters),
        "sensitivity_lambdas": np.asarray(sensitivity, float),
        "s_lambda": np.array([s_of(m.parameters) for m in models[2:]]),
        "calibration_rms_dph": fit.residual_rms * RPS_TO_DPH,
        "calibration_max_dph": fit.residual_max * RPS_TO_DPH,
        "calibration_temperature": cal_t, "calibration_drift_dph": cal_z * RPS_TO_DPH,
        "initial_dph": fit.coefficients * RPS_TO_DPH,
        "final_truth_dph": final_c * RPS_TO_DPH,
        "rls_dph": models[0].parameters * RPS_TO_DPH, "ff_dph": models[1].parameters * RPS_TO_DPH,
        "stop_days": stop_days, "stop_temperature": stop_temps,
        "stop_estimate_dph": est * RPS_TO_DPH, "stop_error_dph": err * RPS_TO_DPH,
        "truth_days": grid, "truth_dph": (truth + np.array([0.0, 0.0, bias_z])) * RPS_TO_DPH,
        "rls_history_dph": history[:, 0] * RPS_TO_DPH, "ff_history_dph": history[:, 1] * RPS_TO_DPH,
    }


# --------------------------------------------------------------------------
# the vehicle test analogue (Table 4, Figs 7-8, Table 5)
# --------------------------------------------------------------------------

def _session_run(model, coef, *, day, temperature, stop_seconds, lat, seed, step=1.0,
                 internal_rate=INTERNAL_RATE) -> VehicleRun:
    """One drive with a stop of ``stop_seconds`` on ``day`` (random legs, heading and INS
    attitude error from ``seed``), the IMU carrying the day's true coefficients ``coef``."""
    rng = np.random.default_rng([seed, 40])
    legs = (("drive", 300.0, float(rng.uniform(8, 15))), ("turn", float(rng.choice([-90.0, 90.0]))),
            ("drive", 300.0, float(rng.uniform(8, 15))), ("stop", float(stop_seconds)),
            ("drive", 180.0, 10.0))
    heading = float(rng.uniform(-math.pi, math.pi))
    unit = replace(model, axial_drift_poly=np.asarray(coef, float), aging_sigma=np.zeros(3))
    run = VehicleRun(legs, lat, 0.0, heading, unit, temperature - unit.thermal.self_heating[GYRO_Z], seed,
                     start_day=day, step=step, internal_rate=internal_rate, body=replace(VEHICLE_BODY, seed=seed))
    phi0 = rng.standard_normal(3) * np.array([10 * ARCSEC_TO_RAD, 10 * ARCSEC_TO_RAD, 0.05 * DEG_TO_RAD])
    mat_true = euler_to_mat(heading, 0.0, 0.0)  # the vehicle at rest, level, table at zero
    return replace(run, attitude0=tuple(float(x) for x in mat_to_euler(_perturbed_attitude(mat_true, phi0))))


def cep(radial: np.ndarray) -> float:
    """Circular error probable of radial errors: their median, same unit."""
    return float(np.median(np.asarray(radial, float)))


def vehicle_test(*, seed: int = 0, unit: str = "premise", n_sessions: int = 20, year_days: float = 318.0,
                 test_day: float = 368.0, drive_hours: float = 6.0, lat_deg: float = 40.0,
                 stop_minutes=(15.0, 60.0), ageing: str = "markov", forgetting_factor: float = 0.8,
                 calibration_points: int = 11, internal_rate: float = INTERNAL_RATE, ageing_scale: float = 1.0,
                 engine=None) -> dict:
    """The vehicle test analogue: a year of online updates, then a 6 h drive.

    Day 0: calibration (quadratic fit of stop-filter estimates at
    ``calibration_points`` temperatures) gives the initial model, which also
    starts the FF-RLS.  Then ``n_sessions`` drives on random days up to
    ``year_days``, each with one stop of random length in ``stop_minutes``
    at a random gyro temperature in 0..50 °C, run through IMU -> INS
    (compensated by the current model) -> :class:`OnlineDriftUpdater`
    (stops shorter than 30 min are discarded).  On ``test_day`` a
    ``drive_hours`` drive with random turns and stops is navigated with the
    initial and with the updated model (Fig. 8); CEP and maximum radial
    error (Table 5) against an ideal-sensor INS on the same motion.
    ``ageing_scale`` multiplies the unit's ageing standard deviations.  The
    vehicle body sways and vibrates while it moves (:data:`VEHICLE_BODY`,
    seeded per drive) and the IMU's minor loop runs at ``internal_rate``
    (default 200 Hz).

    ``engine`` runs the sessions and the drive's navigations (default
    :class:`~sarins_fmu.experiments.online_rls_vehicle.InProcessEngine`; the
    FMU system: :class:`sarins.online_rls.cosim.CosimEngine`).  The day-0
    calibration (static stop-filter runs), the true coefficients and the
    ideal-sensor reference are computed here for every engine.  A model
    update applies from the interval starting one step (``UPDATE_LATENCY``)
    after the INS row that triggered it.
    """
    engine = InProcessEngine() if engine is None else engine
    model = _scaled_ageing(imu_unit(unit), ageing_scale)
    lat = lat_deg * DEG_TO_RAD
    rng = np.random.default_rng([seed, 50])
    grid = np.arange(0.0, math.floor(test_day) + 1.0)
    truth = aged_coefficients(model, grid, seed, ageing)
    cal_t, cal_z = _calibration(truth[0], unit, seed, lat_deg, np.linspace(*TEMPERATURE_RANGE, calibration_points))
    fit = fit_quadratic_temperature_model(cal_t, cal_z)
    rls = ForgettingRLS.from_calibration(cal_t, cal_z, 0.0, RLSSettings(forgetting_factor))
    updater = OnlineDriftUpdater(rls, lat, 1.0, StopFilterSettings.for_model(model))
    days = np.sort(rng.choice(np.arange(1, int(year_days) + 1), size=n_sessions, replace=False)).astype(float)
    temps = rng.uniform(*TEMPERATURE_RANGE, size=n_sessions)
    stops = rng.uniform(*stop_minutes, size=n_sessions) * 60.0
    truth_at_stop = np.empty(n_sessions)
    for i, (day, temp, stop) in enumerate(zip(days, temps, stops)):
        run = _session_run(model, truth[int(day)], day=day, temperature=float(temp), stop_seconds=float(stop),
                           lat=lat, seed=seed * 1000 + i, internal_rate=internal_rate)
        engine.session(run, updater)
        truth_at_stop[i] = model_drift(replace(model, axial_drift_poly=truth[int(day)]), temp)
    rls = updater.rls  # (an engine may hand back a new RLS state)
    events = updater.event_table()
    legs = tuple(random_legs(drive_hours * 3600.0, seed + 777, n_stops=2, stop_range=(300.0, 900.0)))
    heading = float(rng.uniform(-math.pi, math.pi))
    test_temp = float(rng.uniform(10.0, 40.0))
    test_unit = replace(model, axial_drift_poly=truth[-1], aging_sigma=np.zeros(3))
    drive = VehicleRun(legs, lat, 0.0, heading, test_unit, test_temp - test_unit.thermal.self_heating[GYRO_Z],
                       seed * 1000 + 999, lead_time=DRIVE_ALIGN_TIME, align_time=DRIVE_ALIGN_TIME,
                       start_day=test_day, internal_rate=internal_rate,
                       body=replace(VEHICLE_BODY, seed=seed * 1000 + 999))
    navs = engine.drive(drive, [fit.coefficients, rls.parameters])
    east, north = position_errors(navs, reference_navigation(drive), lat)
    time = np.arange(1, east.shape[1] + 1) * drive.step
    radial = np.hypot(east, north)
    final_c = truth[-1] + np.array([0.0, 0.0, model.gyro.bias[GYRO_Z]])
    return {
        "seed": seed, "unit": unit, "ageing": ageing, "ageing_scale": ageing_scale,
        "session_days": days, "session_temperature": temps, "session_stop_s": stops,
        "session_truth_dph": truth_at_stop * RPS_TO_DPH,
        "event_time_days": events["time"] / DAY, "event_update": (events["kind"] == "update").astype(int),
        "event_duration_s": events["duration"], "event_temperature": events["temperature"],
        "event_drift_dph": events["drift"] * RPS_TO_DPH,
        "event_predicted_dph": np.polyval(fit.coefficients, events["temperature"]) * RPS_TO_DPH,
        "n_updates": int(np.sum(events["kind"] == "update")),
        "initial_dph": fit.coefficients * RPS_TO_DPH, "updated_dph": rls.parameters * RPS_TO_DPH,
        "final_truth_dph": final_c * RPS_TO_DPH,
        "s_initial": s_metric(final_c * RPS_TO_DPH, fit.coefficients * RPS_TO_DPH),
        "s_updated": s_metric(final_c * RPS_TO_DPH, rls.parameters * RPS_TO_DPH),
        "test_temperature": test_temp,
        "test_drift_error_initial_dph": float(model_drift(test_unit, test_temp) - np.polyval(fit.coefficients, test_temp)) * RPS_TO_DPH,
        "test_drift_error_updated_dph": float(model_drift(test_unit, test_temp) - np.polyval(rls.parameters, test_temp)) * RPS_TO_DPH,
        "time": time, "east_initial": east[0], "north_initial": north[0],
        "east_updated": east[1], "north_updated": north[1],
        "cep_initial": cep(radial[0]), "cep_updated": cep(radial[1]),
        "max_radial_initial": float(radial[0].max()), "max_radial_updated": float(radial[1].max()),
        "max_east_initial": float(np.abs(east[0]).max()), "max_east_updated": float(np.abs(east[1]).max()),
        "max_north_initial": float(np.abs(north[0]).max()), "max_north_updated": float(np.abs(north[1]).max()),
    }
