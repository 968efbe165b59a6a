"""Seed 003's recordings through the FMUs: Turntable FMU -> IMUThermal FMU under the master.

The in-process twin is :func:`sarins_fmu.experiments.mems_calibration.record_in_process`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from orchestration import Component, Connection, System, simulate_system, write_csv
from sarins.systems import GIMBAL_LINKS, STATIC_BASE_HELD
from sarins_fmu.experiments.mems_calibration import (DYNAMIC_KINDS, Profile, imu_parameters, profile,
                                                     record_in_process, recording_model, recording_overrides,
                                                     run_seed, stop_time, turntable_parameters, with_profile)

RECORD = ["turntable.angle_?", "turntable.rate_?", "turntable.ambient_temp", "imu.dtheta_?", "imu.dv_?",
          "imu.temp_*"]


def _from_result(result) -> dict:
    """Plain arrays of a master result (rows 0..K at times 0, h, ..., K h)."""
    def cols(fmt):
        return np.column_stack([result[fmt.format(i)] for i in (1, 2, 3)])

    temps = np.column_stack([result[f"imu.temp_{s}"] for s in
                             ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")])
    return dict(time=np.asarray(result["time"]), angle=cols("turntable.angle_{}"), rate=cols("turntable.rate_{}"),
                ambient=np.asarray(result["turntable.ambient_temp"]),
                dtheta=np.column_stack([result[f"imu.dtheta_{a}"] for a in "xyz"])[1:],
                dv=np.column_stack([result[f"imu.dv_{a}"] for a in "xyz"])[1:], temps=temps[1:])


def record_cosim(kind: str, prof: Profile, fmu_dir: str | Path, *, seed: int = 3, csv: str | Path | None = None,
                 model_overrides: dict | None = None, progress: bool = False) -> dict:
    """Co-simulate one recording: Turntable FMU -> IMUThermal FMU through the master.

    Parameters
    ----------
    kind : 'dynamic', 'heldout', 'tumble' or 'rates'
    prof : Profile
    fmu_dir : folder holding Turntable.fmu and IMUThermal.fmu
    seed : IMU noise seed (as given: :func:`record_task` applies the held-out run's own seed)
    csv : optional path: the master's recorder writes the raw result there too
    model_overrides : IMU coefficient parameters (flat names, SI) overriding the preset

    Returns
    -------
    dict with ``time`` (K+1,) s, ``angle``/``rate`` (K+1, 3) gimbal states
    (rad, rad/s, outer first), ``ambient`` (K+1,) degC and, per step,
    ``dtheta`` (K, 3) rad, ``dv`` (K, 3) m/s, ``temps`` (K, 6) degC.
    """
    fmu_dir = Path(fmu_dir)
    step = prof.step if kind in DYNAMIC_KINDS else prof.cal_step
    system = System(
        name=f"mems_calibration_{kind}",
        components=[Component("turntable", fmu_dir / "Turntable.fmu", turntable_parameters(kind, prof)),
                    Component("imu", fmu_dir / "IMUThermal.fmu",
                              {**STATIC_BASE_HELD, **imu_parameters(prof, seed, model_overrides)})],
        connections=[Connection("turntable", v, "imu", v) for v in GIMBAL_LINKS],
        start_time=0.0, stop_time=stop_time(kind, prof), step_size=step)
    result = simulate_system(system, stop_time(kind, prof), step, record=RECORD, progress=progress)
    if csv is not None:
        write_csv(result, csv)
    return _from_result(result)


def record_task(kind: str, profile_name: str, fmu_dir: str, seed: int = 3, profile_changes: dict | None = None,
                ablation: str | None = None, engine: str = "cosim", scale: float = 1.0, spool: str | None = None) -> dict:
    """Campaign task: one co-simulated recording as a dict of arrays, plus its wall time ``wall_s``.

    ``seed`` is the campaign seed: the recording uses its
    :func:`~sarins_fmu.experiments.mems_calibration.run_seed` and
    :func:`~sarins_fmu.experiments.mems_calibration.recording_overrides`
    (``ablation``: a time-correlated term switched off; ``scale``: the factor on the unsourced
    time-correlated sizes, :data:`~sarins_fmu.experiments.mems_calibration.CALIBRATED_TERMS`).
    ``engine='inprocess'``: the same recording from the library in this process
    (:func:`~sarins_fmu.experiments.mems_calibration.record_in_process`, the same numbers; ``fmu_dir`` unused),
    with ``spool`` (a folder) written there chunk by chunk and returned as spooled arrays that the campaign
    streams into the result file (the recording is never held whole).
    """
    import time as _time

    prof = with_profile(profile(profile_name), **(profile_changes or {}))
    t0 = _time.perf_counter()
    if engine == "inprocess":
        rec = record_in_process(kind, prof, seed=run_seed(kind, seed), model=recording_model(kind, seed, ablation, scale),
                                spool=spool)
    elif engine == "cosim":
        rec = record_cosim(kind, prof, fmu_dir, seed=run_seed(kind, seed),
                           model_overrides=recording_overrides(kind, seed, ablation, scale))
    else:
        raise ValueError(f"unknown engine {engine!r}; choose cosim or inprocess")
    rec["wall_s"] = _time.perf_counter() - t0
    return rec
