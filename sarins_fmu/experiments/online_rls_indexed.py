"""Seed 002's stop with the dual-axis RINS indexed through several positions (issue 20).

:func:`simulate_indexed_stop` is :func:`sarins_fmu.experiments.online_rls.simulate_stop` with the
turntable doing an :class:`~sarins_fmu.stop_indexing.IndexingSequence` (default
:data:`STOP_SEQUENCE`) instead of the forward-reverse azimuth rotation, and the
:class:`~sarins_fmu.stop_indexing.IndexedStopFilter` fed the sequence's known rotations.
The IMU is the unit's own (nav-rlg: its noise, scale factors and misalignments as the preset
has them), hot, on a static base; the INS is the in-process free INS.

Units: SI inside; ``_dph`` names carry deg/h; temperatures degC.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..imu import IMU, StaticBase
from ..ins import InsConfig, StrapdownINS
from ..kalman import StopFilterSettings
from ..stop_indexing import IndexedStopFilter, IndexingSequence, body_to_nav, indexing_schedule, rotation_samples
from ..thermal import Ambient
from ..units import ARCSEC_TO_RAD, DEG_TO_RAD, RPS_TO_DPH
from .online_rls import _perturbed_attitude, imu_unit, model_drift
from .online_rls_vehicle import GYRO_Z

# The stop's indexing sequence (our design, issue 20): the stop starts in the navigation position
# (outer 0, inner 0: the azimuth gyro up); the outer gimbal tilts the IMU by +90 deg about the
# vehicle's roll axis (azimuth gyro horizontal, pointing to the vehicle's right), then to -90 deg
# (pointing left), the inner gimbal turns 180 deg (the horizontal gyros reversed), the outer gimbal
# back to +90 deg: the azimuth gyro's axis horizontal right, left, left, right for 400 s each (the
# last position to the end of the 30 min), the moves at 6 deg/s and 6 deg/s^2 (the dual-axis
# scheme's rates, sarins_fmu.turntable.dual_axis), one gimbal at a time: 16 + 31 + 31 + 31 s.
# Right-left-left-right cancels a heading error that changes linearly through the stop (the
# vertical gyro's drift); the reversal of the horizontal gyros separates their drifts from the tilt.
STOP_SEQUENCE = IndexingSequence(positions_deg=((0.0, 0.0), (90.0, 0.0), (-90.0, 0.0), (-90.0, 180.0),
                                                (90.0, 180.0)),
                                 holds=(0.0, 400.0, 400.0, 400.0, 400.0), rate_dps=6.0, accel_dps2=6.0)
ROTATION_SUBSTEPS = 16  # parts of a step in which the filter samples a moving rotation


def simulate_indexed_stop(*, imu: str = "nav-rlg", lat_deg: float = 40.0, temperature: float = 30.0,
                          duration: float = 1800.0, seed: int = 0, coefficients=None, compensation=None,
                          tilt0_arcsec: float = 10.0, heading0_deg: float = 0.05, velocity0: float = 0.3,
                          step: float = 1.0, internal_rate: float = 100.0, yaw_deg: float = 0.0,
                          sequence: IndexingSequence = STOP_SEQUENCE, settings: StopFilterSettings | None = None
                          ) -> dict:
    """One indexed stop: the filter's azimuth-drift estimate against the truth.

    Parameters as :func:`sarins_fmu.experiments.online_rls.simulate_stop` (the same seed gives the
    same IMU noise seed, initial errors and temperature), plus
    yaw_deg : the vehicle's heading, deg counter-clockwise from east-north (0: its front north).
    sequence : the indexing sequence (:data:`STOP_SEQUENCE`).
    settings : the filter's settings (default :meth:`StopFilterSettings.for_model` of the unit).

    Returns
    -------
    dict with the keys of ``simulate_stop``: ``truth_dph``, ``estimate_dph``, ``error_dph``,
    ``std_dph``, ``mean_temperature``, ``time``, ``estimate_curve_dph``, ``std_curve_dph``.
    """
    if not (math.isfinite(duration) and math.isfinite(step) and step > 0 and duration >= 2 * step):
        raise ValueError("duration must cover at least two steps")
    if not math.isfinite(yaw_deg):
        raise ValueError(f"yaw_deg must be finite, got {yaw_deg!r}")
    model = imu_unit(imu)
    if coefficients is not None:
        model = replace(model, axial_drift_poly=np.asarray(coefficients, float), aging_sigma=np.zeros(3))
    lat, yaw = lat_deg * DEG_TO_RAD, yaw_deg * DEG_TO_RAD
    rng = np.random.default_rng([seed, 2])
    n = int(round(duration / step))
    table = indexing_schedule(sequence, n * step, grid=step)
    base = StaticBase(lat, 0.0, 0.0, yaw)
    ambient = Ambient(mean=temperature - model.thermal.self_heating[GYRO_Z])
    sensor = IMU(model, base, table.axes, output_interval=step, internal_rate=internal_rate, seed=seed,
                 thermal_start="hot", ambient=ambient)
    mat_true = body_to_nav(table, 0.0, yaw)[0]
    phi0 = rng.standard_normal(3) * np.array([tilt0_arcsec * ARCSEC_TO_RAD, tilt0_arcsec * ARCSEC_TO_RAD,
                                              heading0_deg * DEG_TO_RAD])
    ins = StrapdownINS(InsConfig(lat=lat, align_time=0.0, step=step),
                       initial_attitude=_perturbed_attitude(mat_true, phi0))
    ins.v[:2] = rng.standard_normal(2) * velocity0
    kf = IndexedStopFilter(lat, settings or StopFilterSettings.for_model(model), dt=step, history_limit=n)
    angle, rate, accel = table.state(np.arange(n) * step)
    dtheta, dv, temps = sensor.step(angle, rate, accel)
    comp = np.zeros(n) if compensation is None else np.polyval(np.asarray(compensation, float), temps[:, GYRO_Z])
    out = ins.step(dtheta, dv, comp)
    kf.step(out[:, 3:5], rotation_samples(table, n, step, yaw, substeps=ROTATION_SUBSTEPS), comp,
            temps[:, GYRO_Z])
    truth = float(model_drift(model, kf.mean_temperature))
    curve = kf.convergence()
    return {
        "truth_dph": truth * RPS_TO_DPH,
        "estimate_dph": kf.drift_estimate * RPS_TO_DPH,
        "error_dph": (kf.drift_estimate - truth) * RPS_TO_DPH,
        "std_dph": kf.drift_std * RPS_TO_DPH,
        "mean_temperature": kf.mean_temperature,
        "time": curve[:, 0],
        "estimate_curve_dph": (curve[:, 1] + comp.mean()) * RPS_TO_DPH,
        "std_curve_dph": curve[:, 2] * RPS_TO_DPH,
    }
