"""Seed 000 runs: one experiment in process or through the FMUs, and the
campaign's task functions (module level, so spawned workers import them).

Engines
    ``inprocess``: :func:`run_static` (library, compiled kernels).
    ``cosim``: the FMUs under the generic master, Gauss-Seidel, 1 s step
    (``standard_static`` for training runs, ``standard_static_identified``
    with the RBFIdentifier FMU for the live identified run).  The two are
    bit-identical for the same experiment (tests/test_axial_rbf.py).

Every series handed back is sampled every ``SAMPLE`` s of navigation.
"""

from __future__ import annotations

import time as _time
import warnings
from pathlib import Path

import numpy as np

from sarins_fmu.identify.axial import APPLY_LATENCY, DriftIdentifier
from sarins_fmu.identify.multitemp import MultiTemperatureTable, calibrate_axial_drift
from sarins_fmu.static_errors import azimuth_drift_errors, heading_error_errors
from sarins_fmu.units import DEG_TO_RAD, DPH_TO_RPS, HOUR, NM, RAD_TO_DEG
from sarins_fmu.experiments import axial_rbf as s0
from sarins_fmu.experiments.static_run import StaticImuRecord, navigate_static, record_static, run_static

SAMPLE = 60  # s between stored samples
ENGINES = ("inprocess", "cosim")
RECORD = ["ins.lat_error", "ins.lon_error", "ins.north_error", "ins.east_error", "ins.position_error",
          "ins.nav_time", "ins.temp_change_align", "imu.temp_gyro_z"]


def _exp(exp) -> s0.Experiment:
    return exp if isinstance(exp, s0.Experiment) else s0.Experiment(**exp)


# ------------------------------------------------------------------ in process
def record_inprocess(exp, nav_hours: float, *, align_hours: float = s0.ALIGN_HOURS) -> StaticImuRecord:
    """The experiment's turntable and IMU output over alignment + ``nav_hours`` (h), in process: what
    every re-run of :func:`run_inprocess` shares (``record=``)."""
    exp = _exp(exp)
    return record_static(lat_deg=exp.lat_deg, align_hours=align_hours, nav_hours=nav_hours,
                         model=s0.imu_model(exp), start=exp.start, ambient=s0.ambient(exp), seed=exp.seed)


def run_inprocess(exp, nav_hours: float, *, correction_dph: float = 0.0, correction_from_hours: float = 0.0,
                  align_hours: float = s0.ALIGN_HOURS, table: dict | None = None,
                  record: StaticImuRecord | None = None) -> dict:
    """One run of the experiment in process; navigation series every SAMPLE s.

    table : multi-temperature table (``MultiTemperatureTable.to_dict()``)
        compensating the z gyro in real time from switch-on, or None.
    record : the experiment's IMU output (:func:`record_inprocess` with the same
        ``nav_hours`` and ``align_hours``), navigated again instead of simulated
        again: the same bits at the INS's cost alone.

    Returns dict: time_h (K,), lat_error, lon_error (rad), north_error,
    east_error (m), temp_z (K,) degC at the same times, temp_change_align
    (degC, over the alignment), temp_align (min, max) degC,
    align_heading_error (rad, U component of the attitude error at the end
    of the alignment).
    """
    exp = _exp(exp)
    if record is None:
        record = record_inprocess(exp, nav_hours, align_hours=align_hours)
    elif not _record_fits(record, exp, nav_hours, align_hours):
        raise ValueError("the IMU record's (seed, latitude, start, nav h, align h) "
                         f"{tuple(record.info[k] for k in ('seed', 'lat_deg', 'start', 'nav_hours', 'align_hours'))} "
                         f"are not this run's {exp.seed, exp.lat_deg, exp.start, nav_hours, align_hours}")
    axial_table = None if table is None else MultiTemperatureTable.from_dict(table)
    r = navigate_static(record, correction_dph=correction_dph, correction_from_hours=correction_from_hours,
                        axial_table=axial_table)
    n_align = len(r.time_all) - len(r.time)
    k = np.arange(SAMPLE - 1, len(r.time), SAMPLE)
    temp_z = r.temperature[:, 2]
    return {"time_h": r.time[k] / HOUR, "lat_error": r.lat_error[k], "lon_error": r.lon_error[k],
            "north_error": r.north_error[k], "east_error": r.east_error[k], "temp_z": temp_z[n_align + k],
            "temp_change_align": float(temp_z[n_align - 1] - temp_z[0]),
            "temp_align": (float(temp_z[:n_align].min()), float(temp_z[:n_align].max())),
            "align_heading_error": float(r.info["align_attitude_error"][2])}


def _record_fits(record: StaticImuRecord, exp, nav_hours: float, align_hours: float) -> bool:
    """Whether ``record`` is the IMU output of this experiment over these hours."""
    info = record.info
    return ((info["seed"], info["lat_deg"], info["start"]) == (exp.seed, exp.lat_deg, exp.start)
            and abs(info["nav_hours"] - nav_hours) < 1e-9 and abs(info["align_hours"] - align_hours) < 1e-9)


# ------------------------------------------------------------------ co-simulation
def cosim_parameters(exp, align_hours: float = s0.ALIGN_HOURS) -> dict:
    """FMU start values (SI) reproducing :func:`run_inprocess` for the experiment."""
    exp = _exp(exp)
    lat = exp.lat_deg * DEG_TO_RAD
    align = align_hours * HOUR
    return {"turntable": {"scheme": "forward-reverse", "align_time": align, "ambient_mode": "sinusoid",
                          "ambient_mean": exp.ambient_c, "ambient_amplitude": exp.amplitude_c,
                          "ambient_period": 86400.0},
            # the IMU's initial temperature comes from the turntable's ambient_temp output, which
            # the master sets before the IMU leaves Initialization Mode
            "imu": {"preset": "nav-rlg", "lat": lat, "thermal_start": exp.start, "seed": int(exp.seed),
                    **s0.imu_overrides(exp)},
            "ins": {"lat0": lat, "align_time": align}}


def run_cosim(exp, nav_hours: float, fmu_dir, *, model_file: str | None = None,
              trigger_hours: float = s0.IDENTIFY_HOURS, align_hours: float = s0.ALIGN_HOURS) -> dict:
    """One run through the FMUs (master, Gauss-Seidel, 1 s); with
    ``model_file`` the RBFIdentifier closes the loop at ``trigger_hours``.

    Returns the same keys as :func:`run_inprocess` plus, with an
    identifier, ``identified_drift_dph`` (the FMU's output).
    """
    from sarins.systems import standard_static, standard_static_identified
    from orchestration import simulate_system

    exp = _exp(exp)
    params = cosim_parameters(exp, align_hours)
    hours = align_hours + nav_hours
    record = list(RECORD)
    if model_file is None:
        system = standard_static(Path(fmu_dir), hours=hours, **params)
    else:
        ident = {"model_file": str(model_file), "trigger_time": trigger_hours * HOUR}
        system = standard_static_identified(Path(fmu_dir), hours=hours, identifier=ident, **params)
        record.append("identifier.axial_drift")
    with warnings.catch_warnings():  # open correction input / the identifier loop are intended
        warnings.simplefilter("ignore")
        res = simulate_system(system, hours * HOUR, 1.0, record=record, progress=False, output_every=1)
    nav = res["ins.nav_time"]
    n_align = round(align_hours * HOUR)
    k_all = np.arange(n_align + SAMPLE, len(nav), SAMPLE)  # row 0 is t = 0
    temp_z = res["imu.temp_gyro_z"]
    out = {"time_h": nav[k_all] / HOUR, "lat_error": res["ins.lat_error"][k_all],
           "lon_error": res["ins.lon_error"][k_all], "north_error": res["ins.north_error"][k_all],
           "east_error": res["ins.east_error"][k_all], "temp_z": temp_z[k_all],
           "temp_change_align": float(res["ins.temp_change_align"][-1]),
           "temp_align": (float(temp_z[1:n_align + 1].min()), float(temp_z[1:n_align + 1].max()))}
    if model_file is not None:
        out["identified_drift_dph"] = float(res["identifier.axial_drift"][-1] / DPH_TO_RPS)
    return out


# ------------------------------------------------------------------ helpers
def at_hours(run: dict, key: str, hours: float) -> float:
    k = int(np.argmin(np.abs(run["time_h"] - hours)))
    if abs(run["time_h"][k] - hours) > 1e-6:
        raise ValueError(f"no sample at {hours} h")
    return float(run[key][k])


def run_features(run: dict, hours: float = s0.IDENTIFY_HOURS) -> dict:
    """The network inputs (paper units) of a run at ``hours`` of navigation."""
    return s0.features(at_hours(run, "lat_error", hours), at_hours(run, "temp_z", hours),
                       run["temp_change_align"])


def window(run: dict, start_h: float, end_h: float) -> np.ndarray:
    sel = (run["time_h"] > start_h + 1e-9) & (run["time_h"] <= end_h + 1e-9)
    return np.column_stack([run["north_error"][sel], run["east_error"][sel]])


def max_error_nmi(err: np.ndarray) -> float:
    return float(np.max(np.hypot(err[:, 0], err[:, 1])) / NM)


def predict(model_file: str, feats: dict) -> float:
    """Drift (deg/h) of a model for features in paper units."""
    ident = DriftIdentifier(model_file)
    return ident.drift_dph(feats["lat_error_deg"] * DEG_TO_RAD, feats["temp_c"], feats["temp_change_c"])


# ------------------------------------------------------------------ tasks
def train_task(exp: dict, engine: str = "inprocess", fmu_dir: str | None = None,
               paper_truth: bool = False, table: dict | None = None) -> dict:
    """4 h alignment + 12 h navigation of a training experiment: the Table 2/4 row.

    ``paper_truth`` also finds the paper's true drift (two 72 h runs in process).
    ``table``: the z gyro is compensated in real time by this
    multi-temperature table (in process only); the row then also holds
    ``table_mean_dph`` (what the table subtracts over the 72 h window) and
    ``residual_drift_dph`` (the simulated truth left for the network)."""
    t0 = _time.perf_counter()
    e = _exp(exp)
    if engine not in ENGINES:
        raise ValueError(f"engine must be one of {ENGINES}, got {engine!r}")
    if table is not None and engine != "inprocess":
        raise ValueError("the multi-temperature compensation runs in process only")
    run = run_cosim(e, s0.IDENTIFY_HOURS, fmu_dir) if engine == "cosim" else \
        run_inprocess(e, s0.IDENTIFY_HOURS, table=table)
    feats = run_features(run)
    truth = float("nan")
    if paper_truth:
        probe = 1e-3
        rec = record_inprocess(e, s0.NAV_HOURS)
        err0 = window(run_inprocess(e, s0.NAV_HOURS, record=rec), 0.0, s0.NAV_HOURS)
        err1 = window(run_inprocess(e, s0.NAV_HOURS, correction_dph=probe, record=rec), 0.0, s0.NAV_HOURS)
        truth = s0.paper_true_drift(err0, err1, probe)[0]
    out = {**e.to_dict(), **feats, "engine": engine, "paper_truth_dph": truth,
           "lon_error_deg": at_hours(run, "lon_error", s0.IDENTIFY_HOURS) * RAD_TO_DEG,
           "align_heading_error": run.get("align_heading_error", float("nan")),
           "temp_align_min": run["temp_align"][0], "temp_align_max": run["temp_align"][1],
           "temp_calib_min": float(run["temp_z"].min()), "temp_calib_max": float(run["temp_z"].max()),
           "time_h": run["time_h"], "lat_error_series_deg": run["lat_error"] * RAD_TO_DEG,
           "lon_error_series_deg": run["lon_error"] * RAD_TO_DEG}
    if table is not None:
        out["table_mean_dph"] = s0.window_mean_table_dph(e, MultiTemperatureTable.from_dict(table))
        out["residual_drift_dph"] = e.drift_dph - out["table_mean_dph"]
    out["wall_seconds"] = _time.perf_counter() - t0
    return out


def test_task(exp: dict, models: dict, engine: str = "inprocess", fmu_dir: str | None = None,
              live: bool = True, rerun_all: bool = True, nav_hours: float = s0.NAV_HOURS,
              table: dict | None = None) -> dict:
    """A held-out experiment: uncompensated run, identification, compensated re-run(s),
    the paper's true drift and (``live``) the single align -> 12 h -> identify
    -> compensate -> 72 h run (through the FMUs with the cosim engine).

    models : {'hot': path, 'cold': path (cold-start experiments)}
    rerun_all : re-run the navigation for the hot model on a cold start too;
        otherwise its errors come from the affine error map of the two runs
        (uncompensated, compensated with the cold model).
    nav_hours : evaluation window (72 h; shorter only for tests of the machinery)
    table : multi-temperature table (dict); on a cold start the experiment is
        also run with it and identified by the networks of
        :data:`MULTITEMP_MODELS` in ``models`` (keys ``mt_*``)
    """
    t0 = _time.perf_counter()
    e = _exp(exp)
    if engine not in ENGINES:
        raise ValueError(f"engine must be one of {ENGINES}, got {engine!r}")
    nav = float(nav_hours)
    rec = record_inprocess(e, nav)  # the IMU output every in-process run below navigates
    r0 = run_inprocess(e, nav, record=rec)
    feats = run_features(r0, min(s0.IDENTIFY_HOURS, nav))
    err0 = window(r0, 0.0, nav)
    sel12 = r0["time_h"] <= s0.IDENTIFY_HOURS + 1e-9
    out = {**e.to_dict(), **feats, "engine": engine, "time_h": r0["time_h"],
           "lat_error_series_deg": r0["lat_error"] * RAD_TO_DEG, "lon_error_series_deg": r0["lon_error"] * RAD_TO_DEG,
           "pos_uncomp_nmi": np.hypot(err0[:, 0], err0[:, 1]) / NM, "max_uncomp_nmi": max_error_nmi(err0),
           "temp_align_min": r0["temp_align"][0], "temp_align_max": r0["temp_align"][1],
           "temp_calib_min": float(r0["temp_z"][sel12].min()), "temp_calib_max": float(r0["temp_z"][sel12].max())}
    own = "cold" if e.start == "cold" else "hot"
    drifts = {kind: predict(models[kind], feats) for kind in (("cold", "hot") if own == "cold" else ("hot",))}
    probe = drifts[own]
    if abs(probe) < 2e-4:  # too small a lever for the affine map: compensate anyway, probe separately
        err_own = window(run_inprocess(e, nav, correction_dph=probe, record=rec), 0.0, nav)
        err_p = window(run_inprocess(e, nav, correction_dph=1e-3, record=rec), 0.0, nav)
        probe = 1e-3
    else:
        err_own = err_p = window(run_inprocess(e, nav, correction_dph=probe, record=rec), 0.0, nav)
    out["slope_ne"] = (err_p - err0) / probe  # position error per deg/h subtracted, (K, 2) m
    out["err0_ne"] = err0
    for kind, drift in drifts.items():
        if kind == own:
            err1 = err_own
        elif rerun_all:
            err1 = window(run_inprocess(e, nav, correction_dph=drift, record=rec), 0.0, nav)
        else:
            err1 = err0 + drift * out["slope_ne"]
        out[f"ident_{kind}_dph"] = drift
        out[f"pos_{kind}_nmi"] = np.hypot(err1[:, 0], err1[:, 1]) / NM
        out[f"max_{kind}_nmi"] = max_error_nmi(err1)
    out["ident_dph"], out["max_comp_nmi"] = drifts[own], out[f"max_{own}_nmi"]
    out["paper_truth_dph"], out["paper_truth_max_nmi"] = s0.paper_true_drift(err0, err_p, probe)
    out["lon_error_deg"] = at_hours(r0, "lon_error", min(s0.IDENTIFY_HOURS, nav)) * RAD_TO_DEG
    out["align_heading_error"] = r0["align_heading_error"]
    if table is not None and e.start == "cold":
        out.update(_multitemp(e, models, table, nav, out["slope_ne"], rerun_all, rec))
    if live:
        out.update(_live(e, models[own], feats, engine, fmu_dir))
    out["wall_seconds"] = _time.perf_counter() - t0
    return out


MULTITEMP_MODELS = ("hot", "hot_mt", "cold_mt")  # networks applied after the multi-temperature compensation


def _multitemp(e, models, table, nav, slope, rerun_all, record=None) -> dict:
    """Cold start with the multi-temperature compensation in real time from
    switch-on (seed 000 sec. 2.3), then identification by the networks of
    :data:`MULTITEMP_MODELS` present in ``models`` ('hot': trained on raw hot
    runs; '*_mt': trained on compensated runs).  ``mt_total_<kind>_dph`` is
    the drift removed over the 72 h window, table mean + identified
    residual, to compare with the true drift like the other identifiers; record: the experiment's IMU
    output (:func:`record_inprocess`), made here when None."""
    tab = MultiTemperatureTable.from_dict(table)
    record = record_inprocess(e, nav) if record is None else record
    run = run_inprocess(e, nav, table=table, record=record)
    feats = run_features(run, min(s0.IDENTIFY_HOURS, nav))
    err_a = window(run, 0.0, nav)
    mean_table = s0.window_mean_table_dph(e, tab, 0.0, nav)
    out = {"mt_table_mean_dph": mean_table, "mt_residual_drift_dph": e.drift_dph - mean_table,
           "mt_lat_error_deg": feats["lat_error_deg"], "mt_max_uncomp_nmi": max_error_nmi(err_a)}
    for kind in (k for k in MULTITEMP_MODELS if k in models):
        drift = predict(models[kind], feats)
        if rerun_all:
            err1 = window(run_inprocess(e, nav, correction_dph=drift, table=table, record=record), 0.0, nav)
        else:  # the error is affine in the subtracted drift with the slope of the uncompensated runs
            err1 = err_a + drift * slope
        out[f"mt_ident_{kind}_dph"] = drift
        out[f"mt_total_{kind}_dph"] = drift + mean_table
        out[f"mt_pos_{kind}_nmi"] = np.hypot(err1[:, 0], err1[:, 1]) / NM
        out[f"mt_max_{kind}_nmi"] = max_error_nmi(err1)
    return out


def multitemp_test_task(exp: dict, models: dict, table: dict, nav_hours: float = s0.NAV_HOURS) -> dict:
    """A held-out cold start with the multi-temperature compensation only
    (the sensitivity study of the terms beyond temperature, in process):
    :func:`_multitemp` with its compensated re-runs, nothing uncompensated.

    models : {'hot_mt': path, ...} (keys of :data:`MULTITEMP_MODELS`);
    table : the unit's own multi-temperature table (dict).  Returns the
    experiment's fields and the ``mt_*`` keys of :func:`test_task`."""
    t0 = _time.perf_counter()
    e = _exp(exp)
    if e.start != "cold":
        raise ValueError("the multi-temperature identification is for cold starts")
    out = {**e.to_dict(), **_multitemp(e, models, table, float(nav_hours), None, True)}
    out["wall_seconds"] = _time.perf_counter() - t0
    return out


def _live(e, model_file, feats, engine, fmu_dir) -> dict:
    """The issue's single run: align -> 12 h -> identify -> compensate -> 72 h."""
    hours = s0.IDENTIFY_HOURS + s0.NAV_HOURS
    expected = predict(model_file, feats)
    if engine == "cosim":
        run = run_cosim(e, hours, fmu_dir, model_file=model_file)
        drift = run["identified_drift_dph"]
    else:
        drift = expected
        run = run_inprocess(e, hours, correction_dph=drift,
                                correction_from_hours=s0.IDENTIFY_HOURS + APPLY_LATENCY / HOUR)
    err = window(run, s0.IDENTIFY_HOURS, hours)
    return {"live_ident_dph": drift, "live_twin_diff_dph": drift - expected,
            "live_max_nmi": max_error_nmi(err), "live_end_nmi": float(np.hypot(*err[-1]) / NM),
            "live_pos_nmi": np.hypot(err[:, 0], err[:, 1]) / NM}


def cosim_check_task(exp: dict, model_file: str, fmu_dir: str, align_hours: float = 0.5,
                     trigger_hours: float = 1.0, nav_hours: float = 2.0) -> dict:
    """A shortened live identified run through the FMUs and its in-process twin.

    Returns the FMU's identified drift, the in-process prediction from the
    in-process latitude error at the trigger, and the largest differences of
    the north/east error series (m).
    """
    e = _exp(exp)
    fmu = run_cosim(e, nav_hours, fmu_dir, model_file=model_file, trigger_hours=trigger_hours,
                    align_hours=align_hours)
    ref0 = run_inprocess(e, trigger_hours, align_hours=align_hours)
    expected = predict(model_file, run_features(ref0, trigger_hours))
    ref = run_inprocess(e, nav_hours, correction_dph=fmu["identified_drift_dph"],
                        correction_from_hours=trigger_hours + APPLY_LATENCY / HOUR, align_hours=align_hours)
    diff = max(float(np.max(np.abs(fmu[k] - ref[k]))) for k in ("north_error", "east_error"))
    return {"fmu_drift_dph": fmu["identified_drift_dph"], "inprocess_drift_dph": expected,
            "max_diff_m": diff, "max_error_m": float(np.max(np.abs(ref["north_error"])))}


def calibration_task(seed: int, points_c, settle_hours: float = 20.0, average_hours: float = 4.0,
                     ramp_hours: float = 0.5, noise_scale: float = s0.GYRO_NOISE_SCALE,
                     lat_deg: float = s0.SITE_LAT_DEG, thermal_scale: float = 1.0) -> dict:
    """The multi-temperature calibration of the campaign's unit
    (:func:`calibrate_axial_drift` on :func:`s0.calibration_unit`; ``thermal_scale``:
    its terms beyond temperature scaled, :class:`s0.Experiment`).

    Returns the table (temp_c, drift_dph) and the unit's steady drift law at
    the measured temperatures (law_dph), deg/h."""
    t0 = _time.perf_counter()
    unit = s0.calibration_unit(seed, noise_scale, thermal_scale)
    tab = calibrate_axial_drift(s0.imu_model(unit), points_c=points_c, lat_deg=lat_deg, settle_hours=settle_hours,
                                average_hours=average_hours, ramp_hours=ramp_hours, seed=unit.seed)
    temp = np.asarray(tab.temp_c)
    return {"temp_c": temp, "drift_dph": np.asarray(tab.drift_dph), "law_dph": s0.steady_drift_dph(0.0, temp),
            "wall_seconds": _time.perf_counter() - t0}


def calibration_error_rms_dph(calibration: dict) -> float:
    """RMS of a calibration result's table against the unit's steady law (:func:`calibration_task`), deg/h."""
    err = np.asarray(calibration["drift_dph"]) - np.asarray(calibration["law_dph"])
    return float(np.sqrt(np.mean(err ** 2)))


def fig1_check_task(cases, hours: float = s0.IDENTIFY_HOURS, lat_deg: float = s0.SITE_LAT_DEG) -> dict:
    """Latitude and longitude errors at ``hours`` of navigation of an ideal
    IMU started with the true attitude, for (azimuth drift deg/h, heading
    error arcsec) cases, beside the closed forms of :mod:`sarins_fmu.static_errors`.

    Returns arrays (one entry per case): drift_dph, heading_arcsec,
    sim/closed lat and lon errors at ``hours`` (deg)."""
    lat = lat_deg * DEG_TO_RAD
    rows = {k: [] for k in ("drift_dph", "heading_arcsec", "sim_lat_deg", "sim_lon_deg", "cf_lat_deg", "cf_lon_deg")}
    for drift, heading in cases:
        phi = float(heading) * DEG_TO_RAD / 3600.0
        r = run_static(lat_deg=lat_deg, nav_hours=hours, imu="ideal", axial_drift_dph=float(drift),
                       aligned_start=True, initial_attitude_error=[0.0, 0.0, phi])
        t = hours * HOUR
        d_lat, d_lon = azimuth_drift_errors(t, float(drift) * DPH_TO_RPS, lat)
        h_lat, h_lon = heading_error_errors(t, phi, lat)
        for key, value in (("drift_dph", drift), ("heading_arcsec", heading),
                           ("sim_lat_deg", r.at_hours("lat_error", hours) * RAD_TO_DEG),
                           ("sim_lon_deg", r.at_hours("lon_error", hours) * RAD_TO_DEG),
                           ("cf_lat_deg", (d_lat + h_lat) * RAD_TO_DEG), ("cf_lon_deg", (d_lon + h_lon) * RAD_TO_DEG)):
            rows[key].append(float(value))
    return {k: np.array(v) for k, v in rows.items()}
