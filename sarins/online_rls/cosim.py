"""Seed 002's vehicle test through the FMUs: the ``vehicle_rins_online`` SSP system.

:class:`CosimEngine` runs the sessions and the test drive of
:func:`sarins_fmu.experiments.online_rls.vehicle_test` through VehicleMotion
-> Turntable -> IMUThermal -> StrapdownINS <-> DriftModelUpdater under the
generic master (Gauss-Seidel, 1 s), with the same parameters as the
in-process engine (:class:`~sarins_fmu.experiments.online_rls_vehicle.InProcessEngine`),
so the two give the same numbers bit for bit.

Between sessions (different days) the updater's state travels as plain
data: the RLS state is written to a binary model file (``.bin``, read by
the native FMU without any library) the next session's DriftModelUpdater
starts from (``model_file``), and read back from its
outputs (model, inverse information, time of the last update); each
finished stop is read from its ``last_stop_*`` outputs.  What stays in
process for every engine: the day-0 calibration (static stop-filter runs),
the true ageing coefficients and the ideal-sensor reference navigation.
"""

from __future__ import annotations

import tempfile
import warnings
from dataclasses import fields, replace
from pathlib import Path

import numpy as np

from fmus.drift_model_updater_slave import P_INDEX, P_UNITS
from sarins_fmu import imu as imu_mod
from sarins_fmu import imu_params
from sarins_fmu.experiments.online_rls_vehicle import RINS_ROTATION, UPDATE_LATENCY, VehicleRun
from sarins_fmu.identify.online import OnlineDriftUpdater
from sarins_fmu.identify.rls import ForgettingRLS
from sarins_fmu.kalman import StopFilterSettings

BASE_PRESET = "nav-rlg"  # the IMUThermal preset the run's unit is expressed against
NAV = ["lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll"]
P_NAMES = list(P_UNITS)  # the DriftModelUpdater's inverse-information outputs, element P_INDEX[k] each
LAST_STOP = ["last_stop_time", "last_stop_duration", "last_stop_temp", "last_stop_drift", "last_stop_drift_std"]
FILTER_PARAMETERS = ("arw", "vrw", "velocity_meas_std", "heading0_std")  # the stop-filter settings the FMU takes


def legs_text(legs) -> str:
    """VehicleMotion's ``legs`` string (numbers in shortest round-trip form: parsed back exactly)."""
    return "; ".join(" ".join([leg[0], *(repr(float(x)) for x in leg[1:])]) for leg in legs)


def imu_overrides(unit: imu_mod.ImuModel) -> dict:
    """IMUThermal coefficient parameters that make the ``nav-rlg`` preset into ``unit``.

    Raises ValueError if ``unit`` differs from the preset in something the
    flat parameters cannot carry (then the FMU would run another IMU)."""
    base = imu_mod.preset(BASE_PRESET)
    want, have = imu_params.flatten(unit), imu_params.flatten(base)
    overrides = {name: value for name, value in want.items() if value != have[name]}
    rebuilt = imu_params.apply_overrides(base, overrides)
    for f in fields(unit):
        if not _same(getattr(rebuilt, f.name), getattr(unit, f.name)):
            raise ValueError(f"the IMU unit's {f.name} cannot be set through IMUThermal's parameters")
    return overrides


def _same(a, b) -> bool:
    if hasattr(a, "__dataclass_fields__"):
        return all(_same(getattr(a, f.name), getattr(b, f.name)) for f in fields(a))
    return bool(np.array_equal(np.asarray(a), np.asarray(b)))


class CosimEngine:
    """Runs vehicle-test sessions and drives through the FMU system (``fmu_dir`` holds
    VehicleMotion, Turntable, IMUThermal, StrapdownINS and DriftModelUpdater)."""

    name = "cosim"

    def __init__(self, fmu_dir, scheme: str = "gauss-seidel"):
        self.fmu_dir = Path(fmu_dir)
        self.scheme = scheme

    # ------------------------------------------------------------------ the system
    def system(self, run: VehicleRun, updater: dict, hours: float | None = None):
        """The ``vehicle_rins_online`` system for ``run`` with the DriftModelUpdater parameters ``updater``."""
        from sarins.systems import vehicle_rins_online

        traj = run.trajectory()
        b = run.body
        body = {"sway_pitch": b.sway_pitch, "sway_roll": b.sway_roll, "sway_period": b.sway_period,
                "vibration": b.vibration, "reference_speed": b.reference_speed, "body_seed": b.seed}
        vehicle = {"legs": legs_text(run.legs), "lat0": run.lat, "lon0": run.lon, "heading0": run.heading,
                   "lead_time": run.lead_time, "grid": run.step, **body}
        turntable = {"scheme": RINS_ROTATION, "align_time": 0.0, "grid": run.step,
                     "duration": run.table_duration(traj), "ambient_mode": "sinusoid", "ambient_mean": run.ambient,
                     "ambient_amplitude": 0.0}
        imu = {"preset": BASE_PRESET, "seed": int(run.seed), "internal_rate": run.internal_rate, "thermal_start": "hot",
               **imu_overrides(run.unit)}
        yaw0, pitch0, roll0 = run.attitude0
        ins = {"align_time": run.align_time, "yaw0": yaw0, "pitch0": pitch0, "roll0": roll0}
        return vehicle_rins_online(self.fmu_dir, hours=(traj.duration / 3600.0 if hours is None else hours),
                                   vehicle=vehicle, turntable=turntable, imu=imu, ins=ins,
                                   updater={"start_day": run.start_day, **updater})

    def _simulate(self, system, stop: float, step: float, record):
        from orchestration import simulate_system

        with warnings.catch_warnings():
            warnings.simplefilter("error")  # the shipped system runs without any warning; anything else is a defect
            return simulate_system(system, stop, step, scheme=self.scheme, record=record, progress=False,
                                   output_every=1)

    # ------------------------------------------------------------------ engine interface
    def session_system(self, run: VehicleRun, updater: OnlineDriftUpdater, model_file,
                       latency: float = UPDATE_LATENCY):
        """The system of a session: the INS starts from ``run.attitude0``, the DriftModelUpdater from the
        RLS state in ``model_file`` with ``updater``'s settings."""
        return self.system(replace(run, align_time=0.0),
                           {"model_file": str(model_file), "latency": latency, **_updater_parameters(updater)})

    def session(self, run: VehicleRun, updater: OnlineDriftUpdater, latency: float = UPDATE_LATENCY) -> np.ndarray:
        """One drive with a stop through the FMUs; ``updater`` (its RLS state and events) is brought up
        to date from the DriftModelUpdater's outputs.  Returns the INS rows like the in-process engine."""
        traj = run.trajectory()
        names = ["updater." + n for n in ["drift_a", "drift_b", "drift_c", *P_NAMES, "model_time", "n_updates",
                                          "n_resets", "stopped", *LAST_STOP, "last_stop_used"]]
        names += ["ins." + n for n in ["solution_time", *NAV]]
        with tempfile.TemporaryDirectory(prefix="sarins_online_rls_") as tmp:
            system = self.session_system(run, updater, updater.rls.export_binary(Path(tmp) / "rls.bin"), latency)
            res = self._simulate(system, traj.n_steps * run.step, run.step, names)
        if res["updater.stopped"][-1]:
            raise ValueError("a session must end moving (the stop in progress would be lost between sessions)")
        updater.events.extend(_events(res))
        n_new = int(res["updater.n_updates"][-1])
        updater.rls = _rls_state(res, updater.rls, n_new)
        return ins_rows(res, "solution_time", traj.n_steps * run.step)

    def drive(self, run: VehicleRun, models) -> list:
        """Navigate the drive through the FMUs once per model ([a, b, c] rad/s per °C^n, or None);
        per model the navigation rows after the alignment, (K, 9) (lat, lon, height, v_e, v_n, v_u,
        yaw, pitch, roll)."""
        traj = run.trajectory()
        out = []
        for coef in models:
            a, b, c = (0.0, 0.0, 0.0) if coef is None else (float(x) for x in coef)
            updater = {"a0": a, "b0": b, "c0": c, "latency": UPDATE_LATENCY}
            names = ["ins." + n for n in ["nav_time", *NAV]] + ["updater.n_updates"]
            res = self._simulate(self.system(run, updater), traj.n_steps * run.step, run.step, names)
            if res["updater.n_updates"][-1]:
                raise ValueError("the drive updated the model (a stop of 30 min or more): the in-process drive "
                                 "navigates with a fixed model")
            out.append(ins_rows(res, "nav_time", traj.n_steps * run.step - run.align_time))
        return out


def ins_rows(res, tag: str, last: float) -> np.ndarray:
    """The INS rows (K, 9) of a result with ``tag`` (``nav_time`` or ``solution_time``) in (0, last],
    one per tag (a Jacobi engine repeats a row): the rows of any engine, in the same order."""
    t = np.asarray(res["ins." + tag])
    keep = np.concatenate([[True], np.diff(t) != 0]) & (t > 0) & (t <= last + 1e-9)
    return np.column_stack([res["ins." + n] for n in NAV])[keep]


def _updater_parameters(updater: OnlineDriftUpdater) -> dict:
    """DriftModelUpdater parameters of an in-process updater's settings (refused if it has settings
    the FMU does not take)."""
    settings = updater.filter.settings
    defaults = StopFilterSettings()
    other = [f.name for f in fields(settings) if f.name not in FILTER_PARAMETERS
             and getattr(settings, f.name) != getattr(defaults, f.name)]
    if other:
        raise ValueError(f"the DriftModelUpdater FMU has no parameters for the stop filter's {', '.join(other)}")
    rls = updater.rls.settings
    if rls.time_scale is None:
        raise ValueError("the DriftModelUpdater FMU forgets per time (time_scale), not per update")
    return {"forgetting_factor": rls.forgetting_factor, "forgetting_time_scale": rls.time_scale,
            "time_threshold": updater.settings.time_threshold, "speed_threshold": updater.settings.speed_threshold,
            **{f"kf_{k}": getattr(settings, k) for k in FILTER_PARAMETERS}}


def _events(res) -> list:
    """(time, kind, duration, T_gz, drift, std) of each stop the updater finished, from its outputs."""
    count = np.asarray(res["updater.n_updates"]) + np.asarray(res["updater.n_resets"])
    rows = np.flatnonzero(np.diff(np.concatenate([[0], count])) > 0)
    events = []
    for k in rows:
        if count[k] - (count[k - 1] if k else 0) != 1:
            raise ValueError("two stops finished within one step: their outputs cannot be told apart")
        time, duration, temp, drift, std = (float(res["updater." + n][k]) for n in LAST_STOP)
        kind = "update" if res["updater.last_stop_used"][k] else "reset"
        events.append((time, kind, duration, temp, drift, std))
    return events


def _rls_state(res, before: ForgettingRLS, n_new: int) -> ForgettingRLS:
    """The DriftModelUpdater's final RLS state (model, inverse information, time)."""
    p = np.empty((3, 3))
    for name, (i, j) in zip(P_NAMES, P_INDEX):
        p[i, j] = p[j, i] = float(res["updater." + name][-1])
    x = [float(res["updater." + n][-1]) for n in ("drift_a", "drift_b", "drift_c")]
    rls = ForgettingRLS(x, p, float(res["updater.model_time"][-1]), before.settings)
    rls.n_updates = before.n_updates + n_new
    return rls


# ---------------------------------------------------------------------- campaign task
ENGINES = ("inprocess", "cosim")
FMUS = ("VehicleMotion", "Turntable", "IMUThermal", "StrapdownINS", "DriftModelUpdater")  # vehicle_rins_online's


def vehicle_task(*, engine: str = "inprocess", fmu_dir: str | None = None, **kwargs) -> dict:
    """One vehicle test (:func:`~sarins_fmu.experiments.online_rls.vehicle_test` keyword arguments)
    in process or through the FMUs in ``fmu_dir`` (``engine='cosim'``): the same numbers."""
    from sarins_fmu.experiments.online_rls import vehicle_test

    if engine == "cosim":
        if fmu_dir is None:
            raise ValueError("the cosim engine needs the folder of the built FMUs")
        result = vehicle_test(**kwargs, engine=CosimEngine(fmu_dir))
    elif engine == "inprocess":
        result = vehicle_test(**kwargs)
    else:
        raise ValueError(f"engine must be one of {ENGINES}, got {engine!r}")
    return {**result, "engine": engine}
