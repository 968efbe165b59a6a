"""Seed 002's stop seen by the aided navigation filter: zero-velocity updates instead of the stop filter.

:func:`simulate_zupt_stop` takes the very stop of :func:`sarins_fmu.experiments.online_rls.simulate_stop`
(the same seed: the same IMU record, initial INS errors and temperature) and runs the 15-state error-state
Kalman filter of :mod:`sarins_fmu.aided` on it, a zero-velocity update (ZUPT) at every IMU step, with
feedback into its own INS.  The paper's stop filter (eqs 4-6) is an 11-state static model open loop on the
free INS; the ZUPT filter is the general navigation filter a user of the vehicle would run at every stop.
Both read the same increments and are given the same noise densities and priors (the 15-state filter
has one gyro-bias prior for the three axes: the stop filter's azimuth prior, 0.02 deg/h, where the stop
filter has 0.01 deg/h on the horizontal drifts).  No ZARU: the IMU turns on its turntable.

Units: SI inside; ``_dph`` names carry deg/h, ``_arcsec`` arcseconds; temperatures degC.
"""

from __future__ import annotations

import numpy as np

from ..aided import FilterSettings, ImuNoise, navigate
from ..kalman import StopFilterSettings
from ..rotations import mat_to_euler
from ..trajectory import Truth
from ..units import ARCSEC_TO_RAD, RPS_TO_DPH
from .online_rls import _perturbed_attitude, model_drift, stop_data
from .online_rls_vehicle import GYRO_Z

AZIMUTH_BIAS = 11  # index of the azimuth (body z) gyro bias in the 15-state error vector


def stop_truth(data) -> Truth:
    """The stop as a :class:`~sarins_fmu.trajectory.Truth` on the IMU grid: fixed position at ``data.lat``,
    zero velocity, the IMU's attitude turning with the turntable (the ideal increments are not needed: the
    filter is fed the unit's record)."""
    n = data.dtheta.shape[0]
    attitude = np.array([mat_to_euler(data.attitude(k)) for k in range(n + 1)])
    zeros = np.zeros((n + 1, 3))
    return Truth(step=data.step, time=np.arange(n + 1) * data.step, lat=np.full(n + 1, data.lat),
                 lon=np.zeros(n + 1), height=np.zeros(n + 1), velocity_n=zeros, attitude=attitude,
                 omega_ib_b=zeros, f_b=zeros, dtheta=np.zeros((n, 3)), dv=np.zeros((n, 3)))


def zupt_settings(stop: StopFilterSettings) -> tuple:
    """(ImuNoise, FilterSettings) of the ZUPT filter with the stop filter's densities and priors."""
    noise = ImuNoise(arw=stop.arw, vrw=stop.vrw, gyro_bias_std=stop.azimuth_drift0_std, accel_bias_std=stop.bias0_std,
                     gyro_rw=stop.drift_rw, accel_rw=stop.bias_rw)
    settings = FilterSettings(pos0_std=stop.position0_std, vel0_std=stop.velocity0_std, tilt0_std=stop.tilt0_std,
                              heading0_std=stop.heading0_std, zupt_std=stop.velocity_meas_std, cov_every=1,
                              out_every=1)
    return noise, settings


def simulate_zupt_stop(*, imu: str = "nav-rlg", lat_deg: float = 40.0, temperature: float = 30.0,
                       duration: float = 1800.0, seed: int = 0, coefficients=None, compensation=None,
                       tilt0_arcsec: float = 10.0, heading0_deg: float = 0.05, velocity0: float = 0.3,
                       step: float = 1.0, internal_rate: float = 100.0) -> dict:
    """One stop through the ZUPT filter: its azimuth-gyro bias estimate against the truth.

    Parameters as :func:`~sarins_fmu.experiments.online_rls.simulate_stop` (the same seed gives the same
    record); ``compensation`` is subtracted from the azimuth gyro's increments, as the INS does there.

    Returns
    -------
    dict with the keys of ``simulate_stop`` (``truth_dph``, ``estimate_dph``, ``error_dph``, ``std_dph`` the
    filter's 1σ, ``mean_temperature``; the curves ``time``, ``estimate_curve_dph``, ``std_curve_dph``, one
    row per step), plus ``heading_error_arcsec`` and ``heading_std_arcsec``: the fed-back INS's heading error
    (phi_U) at the end of the stop and the filter's 1σ of it.
    """
    d = stop_data(imu=imu, lat_deg=lat_deg, temperature=temperature, duration=duration, seed=seed,
                  coefficients=coefficients, compensation=compensation, tilt0_arcsec=tilt0_arcsec,
                  heading0_deg=heading0_deg, velocity0=velocity0, step=step, internal_rate=internal_rate)
    truth = stop_truth(d)
    noise, settings = zupt_settings(StopFilterSettings.for_model(d.model))
    start = truth.nav_rows([0])[0]
    start[3:5] = d.velocity0
    start[6:9] = mat_to_euler(_perturbed_attitude(d.attitude(0), d.phi0))
    dtheta = d.dtheta.copy()
    dtheta[:, GYRO_Z] -= d.comp * step
    n = dtheta.shape[0]
    zeros = np.zeros((n, 3))
    res = navigate(truth, noise=noise, aiding=("zupt",), settings=settings, seed=seed,
                   imu=(dtheta, d.dv, zeros, zeros), initial=start, covariance="diagonal")
    mean_temperature = float(np.mean(d.temps[:, GYRO_Z]))
    true_drift = float(model_drift(d.model, mean_temperature))
    estimate = res.bias_g[:, GYRO_Z] + d.comp.mean()
    sigma = np.sqrt(res.variance[:, AZIMUTH_BIAS])
    return {
        "truth_dph": true_drift * RPS_TO_DPH,
        "estimate_dph": float(estimate[-1]) * RPS_TO_DPH,
        "error_dph": float(estimate[-1] - true_drift) * RPS_TO_DPH,
        "std_dph": float(sigma[-1]) * RPS_TO_DPH,
        "mean_temperature": mean_temperature,
        "time": res.time,
        "estimate_curve_dph": estimate * RPS_TO_DPH,
        "std_curve_dph": sigma * RPS_TO_DPH,
        "heading_error_arcsec": float(res.error[-1, 8]) / ARCSEC_TO_RAD,
        "heading_std_arcsec": float(np.sqrt(res.variance[-1, 8])) / ARCSEC_TO_RAD,
    }
