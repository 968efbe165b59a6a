"""The main job (``sarins demo``): seed 000's identified static system, co-simulated.

Turntable -> IMUThermal -> StrapdownINS -> RBFIdentifier FMUs under the
generic master: align, navigate ``identify_hours``, identify the axial drift
with the shipped RBF model, subtract it and navigate ``nav_hours`` more.  The
same run is repeated in process without compensation for comparison, and the
true drift (deterministic z-gyro drift of the simulated unit, time mean over
the navigation after identification) is computed from the recorded gyro
temperature.
"""

from __future__ import annotations

import time

import numpy as np

from fmus.build import build_fmus
from orchestration import simulate_system
from sarins.systems import standard_static_identified
from sarins_fmu import imu as imu_mod
from sarins_fmu.experiments import run_static
from sarins_fmu.identify.axial import default_model_path
from sarins_fmu.site import SITE_LAT_DEG
from sarins_fmu.units import DEG_TO_RAD, DPH_TO_RPS, HOUR

#: navigation time (h) at which the shipped identifier models were trained
MODEL_IDENTIFY_HOURS = 12.0


def demo_parameters(*, lat_deg: float, align_hours: float, imu: str, start: str, rotation: str, seed: int,
                    axial_drift_dph: float | None = None) -> dict:
    """FMU start values of the standard system for the run options (SI)."""
    lat = lat_deg * DEG_TO_RAD
    align = align_hours * HOUR
    imu_start = {"preset": imu, "lat": lat, "thermal_start": start, "seed": seed}
    if axial_drift_dph is not None:  # a constant azimuth drift, no thermal terms (ImuModel.with_axial_drift)
        imu_start.update({"axial_drift_a": 0.0, "axial_drift_b": 0.0, "axial_drift_c": axial_drift_dph * DPH_TO_RPS,
                          "axial_drift_dtdt": 0.0, "gyro_bias_z": 0.0, "gyro_bias_tc1_z": 0.0,
                          "gyro_bias_tc2_z": 0.0, "aging_sigma_a": 0.0, "aging_sigma_b": 0.0,
                          "aging_sigma_c": 0.0})
    return {"turntable": {"scheme": rotation, "align_time": align},
            "imu": imu_start, "ins": {"lat0": lat, "align_time": align}}


def true_axial_drift_dph(model: imu_mod.ImuModel, time_s: np.ndarray, temp_gyro_z: np.ndarray,
                         start_s: float, end_s: float) -> float:
    """Time mean (deg/h) of the unit's deterministic z-gyro drift over
    ``[start_s, end_s]`` (run time), from a recorded gyro temperature."""
    dt = float(time_s[1] - time_s[0])
    eps = imu_mod.deterministic_axial_drift(model, temp_gyro_z, dt)
    sel = (time_s >= start_s) & (time_s <= end_s)
    return float(np.mean(eps[sel])) / DPH_TO_RPS


def run_demo(*, lat_deg: float = SITE_LAT_DEG, align_hours: float = 4.0, identify_hours: float = MODEL_IDENTIFY_HOURS,
             nav_hours: float = 72.0, imu: str = "nav-rlg", rotation: str = "forward-reverse", start: str = "hot",
             seed: int = 0, axial_drift_dph: float | None = None, model: str = "hot",
             model_file: str | None = None, fmu_dir="build/fmus", progress: bool = True) -> dict:
    """Co-simulate the identified static system and compare; returns a dict
    (SI units unless the key says otherwise) with the recorded series under
    ``"cosim"`` and the in-process reference under ``"reference"``."""
    if model_file is None and abs(identify_hours - MODEL_IDENTIFY_HOURS) > 1e-9:
        raise ValueError(f"the shipped {model} model was trained on the latitude error at "
                         f"{MODEL_IDENTIFY_HOURS:g} h of navigation; --identify-hours {identify_hours:g} "
                         "needs a --model-file trained at that time")
    t0 = time.perf_counter()
    fmu_dir = build_fmus(fmu_dir)[0].parent
    params = demo_parameters(lat_deg=lat_deg, align_hours=align_hours, imu=imu, start=start, rotation=rotation,
                             seed=seed, axial_drift_dph=axial_drift_dph)
    model_path = model_file or str(default_model_path(model))
    ident = {"model_file": model_path, "trigger_time": identify_hours * HOUR}
    hours = align_hours + identify_hours + nav_hours
    system = standard_static_identified(fmu_dir, hours=hours, identifier=ident, **params)
    record = ["ins.lat_error", "ins.position_error", "ins.nav_time", "imu.temp_gyro_z", "identifier.axial_drift"]
    result = simulate_system(system, hours * HOUR, 1.0, record=record, progress=progress)
    reference = run_static(lat_deg=lat_deg, align_hours=align_hours, nav_hours=identify_hours + nav_hours,
                           rotation=rotation, imu=imu, axial_drift_dph=axial_drift_dph, start=start, seed=seed)
    unit = imu_mod.preset(imu)
    if axial_drift_dph is not None:
        unit = unit.with_axial_drift(axial_drift_dph * DPH_TO_RPS)
    t_ident = (align_hours + identify_hours) * HOUR
    true_dph = true_axial_drift_dph(unit, result["time"], result["imu.temp_gyro_z"], t_ident, hours * HOUR)
    identified_dph = float(result["identifier.axial_drift"][-1]) / DPH_TO_RPS
    return {"fmu_dir": str(fmu_dir), "model_file": model_path, "hours": hours, "cosim": result,
            "reference": reference, "true_drift_dph": true_dph, "identified_drift_dph": identified_dph,
            "identification_error_dph": identified_dph - true_dph, "wall_seconds": time.perf_counter() - t0}
