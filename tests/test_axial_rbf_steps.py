"""Seed 000's missing steps: the multi-temperature compensation, the Fig. 1
longitude-error closed forms, the noise x latitude sweep and the RBF
identifier in ``sarins replay``."""

import json
import math

import numpy as np
import pytest

from sarins.campaign import load_result
from sarins.results import RECORD_KEY
from sarins_fmu import imu as imu_mod
from sarins_fmu.earth import RATE
from sarins_fmu.experiments import axial_rbf as s0
from sarins_fmu.experiments import run_static
from sarins_fmu.identify.axial import APPLY_LATENCY, DriftIdentifier, default_model_path
from sarins_fmu.identify.modelfile import ModelFileError
from sarins_fmu.identify.multitemp import MultiTemperatureTable, calibrate_axial_drift
from sarins_fmu.imu_params import apply_overrides
from sarins_fmu.static_errors import (azimuth_drift_errors, drift_history_errors, heading_error_errors,
                                      identification_noise_std)
from sarins_fmu.units import DEG_TO_RAD, DPH_TO_RPS, DPSH_TO_RPSS, HOUR

LAT = s0.SITE_LAT_DEG * DEG_TO_RAD


# ---------------------------------------------------------------- Fig. 1 closed forms
def test_longitude_error_of_an_azimuth_drift_and_a_heading_error_follow_the_closed_forms():
    """Ideal IMU started on the true attitude: a constant azimuth drift gives
    dlon = sin L (t - sin Wt / W) eps (same sign as dL), a heading error
    dlon = -sin L (1 - cos Wt) phi_U; checked at 6 and 12 h (the Schuler
    oscillation riding on the heading response is ~5 % of its peak)."""
    from sarins.axial_rbf.runs import fig1_check_task

    res = fig1_check_task([[0.002, 0.0], [0.0, 20.0], [-0.0005, -20.0]])
    peak_drift = abs(azimuth_drift_errors(12 * HOUR, 0.002 * DPH_TO_RPS, LAT)[1]) / DEG_TO_RAD
    peak_heading = 2 * math.sin(LAT) * 20 / 3600
    assert res["sim_lat_deg"][0] == pytest.approx(res["cf_lat_deg"][0], rel=5e-3)
    assert res["sim_lon_deg"][0] == pytest.approx(res["cf_lon_deg"][0], rel=1e-2)
    assert np.sign(res["sim_lon_deg"][0]) == np.sign(res["sim_lat_deg"][0]) == 1
    assert abs(res["sim_lon_deg"][1] - res["cf_lon_deg"][1]) < 0.05 * peak_heading
    assert abs(res["sim_lat_deg"][1]) < 0.05 * peak_heading  # the heading error leaves dL at 12 h
    # a small negative drift and a negative heading error: dL < 0 but dlon > 0, as predicted
    assert res["sim_lat_deg"][2] < 0 < res["sim_lon_deg"][2] and res["cf_lon_deg"][2] > 0
    assert abs(res["sim_lon_deg"][2] - res["cf_lon_deg"][2]) < 0.05 * (peak_heading + peak_drift / 4)
    r = run_static(nav_hours=6.0, imu="ideal", aligned_start=True, initial_attitude_error=[0, 0, 20 * DEG_TO_RAD / 3600])
    h_lat, h_lon = heading_error_errors(6 * HOUR, 20 * DEG_TO_RAD / 3600, LAT)
    assert abs(r.at_hours("lon_error", 6.0) - h_lon) < 0.1 * abs(h_lon)
    with pytest.raises(ValueError, match="aligned_start"):
        run_static(nav_hours=0.1, imu="ideal", initial_attitude_error=[0, 0, 1e-4])


def test_drift_history_closed_form_reduces_to_the_constant_drift_one():
    t = 12 * HOUR
    tau = np.linspace(0.0, t, 721)
    eps = 0.0013 * DPH_TO_RPS
    got = drift_history_errors(t, tau, np.full(tau.size, eps), LAT)
    want = azimuth_drift_errors(t, eps, LAT)
    assert got[0] == pytest.approx(float(want[0]), rel=1e-5) and got[1] == pytest.approx(float(want[1]), rel=1e-5)
    with pytest.raises(ValueError):
        drift_history_errors(t, tau[:-1], np.full(tau.size - 1, eps), LAT)


def test_sign_analysis_decomposes_synthetic_runs_exactly():
    """Rows whose 12 h errors are exactly drift + heading closed forms leave no residual."""
    from sarins.axial_rbf.fig1 import ratio_lon_to_lat, sign_analysis

    rows = []
    for e, phi in zip(s0.generate("cold", 3, 1, 4) + s0.generate("hot", 2, 1, 4), (3e-5, -8e-5, 1e-4, 0, 5e-5, -2e-5, 0)):
        d_lat, d_lon = s0.deterministic_errors(e)
        h_lat, h_lon = heading_error_errors(12 * HOUR, phi, LAT)
        rows.append({**e.to_dict(), "lat_error_deg": (d_lat + float(h_lat)) / DEG_TO_RAD,
                     "lon_error_deg": (d_lon + float(h_lon)) / DEG_TO_RAD, "align_heading_error": phi})
    out = sign_analysis(rows)
    assert out["n"] == out["n_decomposed"] == 7
    assert out["rms_minus_both_deg"] < 1e-12 < out["rms_minus_drift_deg"]
    assert out["differ_predicted"] == out["differ_decomposed"]
    w = RATE * 12 * HOUR
    assert ratio_lon_to_lat(s0.SITE_LAT_DEG) == pytest.approx(math.tan(LAT) * (w - math.sin(w)) / (1 - math.cos(w)))


@pytest.mark.slow
def test_latitude_error_noise_follows_the_analytic_floor():
    """var dL(t) = 3/2 N^2 t for equal white gyro noise on the three axes
    (psi random walk, Schuler loop mean square 3/2): 40 seeds, 6 h, ideal
    IMU with the nav-rlg random walk."""
    n = 0.0005 * DPSH_TO_RPSS
    model = apply_overrides(imu_mod.preset("ideal"), {f"gyro_random_walk_{a}": n for a in "xyz"})
    lat_err = [run_static(nav_hours=6.0, model=model, aligned_start=True, seed=s).at_hours("lat_error", 6.0)
               for s in range(40)]
    measured = float(np.sqrt(np.mean(np.square(lat_err))))
    predicted = identification_noise_std(n, LAT, 6 * HOUR) * (math.cos(LAT) / RATE * (1 - math.cos(RATE * 6 * HOUR)))
    assert measured == pytest.approx(predicted, rel=0.2)


# ---------------------------------------------------------------- multi-temperature compensation
def test_multitemperature_table_interpolates_holds_and_round_trips(tmp_path):
    tab = MultiTemperatureTable((0.0, 10.0, 30.0), (0.001, 0.002, -0.002))
    assert np.allclose(tab.drift_at([-5.0, 0.0, 5.0, 20.0, 30.0, 99.0]), [0.001, 0.001, 0.0015, 0.0, -0.002, -0.002])
    assert tab.correction(5.0) == pytest.approx(0.0015 * DPH_TO_RPS)
    assert MultiTemperatureTable.load(tab.save(tmp_path / "t.json")) == tab
    for bad in (((0.0,), (1.0,)), ((0.0, 0.0), (1.0, 2.0)), ((0.0, 1.0), (1.0, float("nan"))), ((0.0, 1.0), (1.0,))):
        with pytest.raises(ValueError):
            MultiTemperatureTable(*bad)
    (tmp_path / "bad.json").write_text('{"format": "other"}')
    with pytest.raises(ModelFileError, match="bad.json"):
        MultiTemperatureTable.load(tmp_path / "bad.json")


def test_calibration_of_a_noise_free_unit_recovers_its_steady_drift_law():
    """No noise, no misalignment or scale factor on z: each point reads the
    unit's law eps0 + k1 (T - 40) + k2 (T - 40)^2 at the measured temperature
    (the rate and block-gradient terms of the last e^-4 of the approach, after
    20 h of settling, leave < 2e-5 deg/h), plus the hysteresis loop's heating
    branch +H at the points approached from below (the first point is where the
    unit starts, its loop at 0)."""
    unit = s0.calibration_unit(seed=1, noise_scale=0.0)
    clean = {"gyro_misalignment_zx": 0.0, "gyro_misalignment_zy": 0.0, "gyro_scale_factor_z": 0.0}
    model = apply_overrides(s0.imu_model(unit), clean)
    tab = calibrate_axial_drift(model, points_c=[10.0, 40.0, 60.0], lat_deg=s0.SITE_LAT_DEG, settle_hours=20.0,
                                average_hours=0.5, ramp_hours=0.5)
    assert s0.hysteresis_dph() > 2e-5
    branch = np.array([0.0, 1.0, 1.0]) * s0.hysteresis_dph()
    assert np.allclose(tab.drift_dph, s0.steady_drift_dph(0.0, tab.temp_c) + branch, atol=2e-5, rtol=0)
    assert np.allclose(tab.temp_c, [10.0, 40.0, 60.0], atol=0.5)
    with pytest.raises(ValueError):
        calibrate_axial_drift(model, points_c=[10.0], lat_deg=0.0)


def test_real_time_table_removes_exactly_its_drift():
    """A unit with a constant azimuth drift and a table of that drift
    navigates like the unit without drift (from switch-on, alignment included)."""
    drift = 0.003
    tab = MultiTemperatureTable((0.0, 100.0), (drift, drift))
    a = run_static(align_hours=0.5, nav_hours=1.0, imu="ideal", axial_drift_dph=drift, axial_table=tab)
    b = run_static(align_hours=0.5, nav_hours=1.0, imu="ideal", axial_drift_dph=0.0)
    c = run_static(align_hours=0.5, nav_hours=1.0, imu="ideal", axial_drift_dph=drift)
    for name in ("lat_error", "lon_error"):  # what is left is the increments' rounding (coning at 200 Hz)
        left = np.max(np.abs(getattr(a, name) - getattr(b, name)))
        assert left < 1e-3 * np.max(np.abs(getattr(c, name) - getattr(b, name))), name


def test_reruns_from_one_imu_record_give_the_bits_of_whole_runs():
    """The held-out experiments navigate one IMU record several times (corrections, table): each
    re-run equals a run that simulates its IMU again, bit for bit, and leaves the record as it was."""
    from sarins.axial_rbf.runs import record_inprocess, run_inprocess

    e = s0.generate("cold", 2, 1, 4)[-1]
    table = {"temp_c": [0.0, 70.0], "drift_dph": [0.002, 0.004]}
    rec = record_inprocess(e, 1.0, align_hours=0.25)
    before = rec.dtheta.copy()
    for kwargs in ({}, {"correction_dph": 0.003}, {"table": table}, {"correction_dph": -0.001, "table": table}):
        again = run_inprocess(e, 1.0, align_hours=0.25, record=rec, **kwargs)
        whole = run_inprocess(e, 1.0, align_hours=0.25, **kwargs)
        for key, value in whole.items():
            assert np.array_equal(np.asarray(again[key]), np.asarray(value)), (kwargs, key)
    assert np.array_equal(rec.dtheta, before)
    assert run_inprocess(e, 1.0, align_hours=0.25, record=rec, correction_dph=0.003)["lat_error"][-1] != \
        run_inprocess(e, 1.0, align_hours=0.25, record=rec)["lat_error"][-1]
    other = s0.generate("cold", 2, 1, 5)[-1]
    for exp, hours in ((other, 1.0), (e, 2.0)):
        with pytest.raises(ValueError, match="not this run's"):
            run_inprocess(exp, hours, align_hours=0.25, record=rec)


def test_residual_truth_is_the_true_drift_minus_the_table_mean():
    e = s0.generate("cold", 2, 1, 9)[0]
    assert s0.window_mean_table_dph(e, MultiTemperatureTable((0.0, 90.0), (0.001, 0.001))) == pytest.approx(0.001)
    law = MultiTemperatureTable(tuple(np.arange(0.0, 91.0, 1.0)), tuple(s0.steady_drift_dph(0.0, np.arange(0.0, 91.0))))
    residual = e.drift_dph - s0.window_mean_table_dph(e, law)
    temp, sel = s0.window_temperature(e, 0.0, s0.NAV_HOURS)
    rate_term = s0.DTDT_DPH_PER_CPH * np.mean((np.gradient(temp, s0.TRUTH_GRID) * HOUR)[sel])
    thermal = np.mean(s0.thermal_terms_dph(temp, s0.TRUTH_GRID, s0.switch_on_temperature(e))[sel])
    assert abs(thermal) > 2e-5  # a cold start ends on the heating branch with the block still lagging
    assert residual == pytest.approx(e.eps0_dph + rate_term + thermal, abs=2e-6)  # 1 degC grid: interpolation


# ---------------------------------------------------------------- sweep
@pytest.mark.slow
def test_quick_sweep_through_the_cli_is_stored_resumable_and_keyed_by_noise_and_latitude(tmp_path, capsys):
    from sarins.cli import main

    out = tmp_path / "sweep"
    argv = ["campaign", "axial-rbf", "--sweep", "quick", "--sweep-only", "--out", str(out), "--workers", "1",
            "--no-progress"]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert json.loads(printed.strip().splitlines()[-1])["sweep_points_holding"] >= 0
    text = (out / "report" / "report.md").read_text()
    assert "noise scale" in text and (out / "report" / "fig5_sweep.png").exists()
    files = sorted((out / "runs").glob("*sweep*.npz"))
    assert len(files) == 12
    stamps = {p.name: p.stat().st_mtime_ns for p in files}
    with np.load(files[0]) as data:
        record = json.loads(str(data[RECORD_KEY]))
    assert {"noise_scale", "lat_deg"} <= set(record["kwargs"]["exp"])
    assert main(argv) == 0  # resumed: nothing recomputed
    assert {p.name: p.stat().st_mtime_ns for p in files} == stamps

    from sarins.axial_rbf.sweep import summarise, tasks

    results = {t.id: load_result(out / "runs" / f"{t.id}.npz") for t in tasks("quick", 0)}
    points = {(p["noise_scale"], p["lat_deg"]): p for p in summarise("quick", 0, results)["points"]}
    for lat in (s0.SITE_LAT_DEG, 60.0):  # same experiments everywhere: more noise, larger error
        assert points[(1.0, lat)]["closed_rms_dph"] > points[(0.4, lat)]["closed_rms_dph"]
    for s in (0.4, 1.0):  # a higher latitude divides the drift's latitude signal by cos L
        assert points[(s, 60.0)]["floor_dph"] > points[(s, s0.SITE_LAT_DEG)]["floor_dph"]


@pytest.mark.parametrize("argv,needle", [(["--sweep", "bogus"], "--sweep"), (["--sweep-only"], "--sweep-only")])
def test_bad_sweep_options_are_one_line_exit_2(argv, needle, tmp_path, capsys):
    from sarins.cli import main

    try:
        rc = main(["campaign", "axial-rbf", "--out", str(tmp_path / "c"), "--no-progress", *argv])
    except SystemExit as exc:
        rc = exc.code
    err = capsys.readouterr().err
    assert rc == 2 and len(err.splitlines()) == 1 and needle in err and "Traceback" not in err
    assert err.startswith("sarins campaign axial-rbf")


# ---------------------------------------------------------------- replay --identify
@pytest.fixture(scope="module")
def identified_log(tmp_path_factory):
    """A hot-start experiment of known true drift, 4 h + 12.1 h, as an NPZ log."""
    from sarins_fmu.imu_log import write_log

    e = s0.generate("hot", 16, 6, 0)[16]
    chunks = []
    kwargs = dict(lat_deg=e.lat_deg, align_hours=4.0, nav_hours=12.1, model=s0.imu_model(e), start=e.start,
                  ambient=s0.ambient(e), seed=e.seed)
    raw = run_static(**kwargs, on_increments=lambda *c: chunks.append(c))
    time_s, dtheta, dv, temps = (np.concatenate([c[j] for c in chunks]) for j in range(4))
    folder = tmp_path_factory.mktemp("log")
    path = write_log(folder / "hot.npz", time_s, dtheta, dv, temps=temps, lat_deg=e.lat_deg)
    bare = write_log(folder / "no_temps.npz", time_s, dtheta, dv, lat_deg=e.lat_deg)
    return {"exp": e, "kwargs": kwargs, "raw": raw, "path": path, "bare": bare, "cols": (time_s, dtheta, dv, temps)}


def test_replay_identifies_the_drift_and_compensates_the_rest_bit_for_bit(identified_log):
    from sarins_fmu.experiments.replay import replay
    from sarins_fmu.imu_log import read_log

    e, raw = identified_log["exp"], identified_log["raw"]
    ident = DriftIdentifier(default_model_path("hot"))
    r = replay(read_log(identified_log["path"]), identifier=ident)
    drift = r.info["identified_drift_dph"]
    k12 = round(12 * HOUR) - 1
    assert drift == ident.drift_dph(raw.lat_error[k12])  # the 12 h latitude error of the same run
    assert abs(drift - e.drift_dph) < 0.0005  # the known truth
    comp = run_static(**identified_log["kwargs"], correction_dph=drift,
                      correction_from_hours=12 + APPLY_LATENCY / HOUR)
    for name in ("lat_error", "lon_error", "north_error", "east_error"):
        assert np.array_equal(getattr(r, name), getattr(comp, name)), name
    assert np.array_equal(r.lat_error[:k12 + 1], raw.lat_error[:k12 + 1])
    assert not np.array_equal(r.lat_error, raw.lat_error)
    kept = replay(read_log(identified_log["path"]), identifier=ident, compensate_drift=False)
    assert kept.info["identified_drift_dph"] == drift and np.array_equal(kept.lat_error, raw.lat_error)
    cold = replay(read_log(identified_log["path"]), identifier=DriftIdentifier(default_model_path("cold")))
    assert cold.info["identify_temp_c"] == identified_log["cols"][3][4 * 3600 + k12, 2]


def test_replay_identify_command_prints_the_drift_and_refuses_logs_that_do_not_fit(identified_log, tmp_path, capsys):
    from sarins.cli import main
    from sarins_fmu.imu_log import write_log

    path = str(identified_log["path"])
    assert main(["replay", path, "--identify", "hot", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["identified_drift_dph"] == pytest.approx(
        DriftIdentifier(default_model_path("hot")).drift_dph(identified_log["raw"].lat_error[round(12 * HOUR) - 1]),
        rel=1e-15, abs=0)
    assert out["identify_at_hours"] == 12.0 and out["drift_compensated_from_hours"] > 12.0
    time_s, dtheta, dv, temps = identified_log["cols"]
    short = write_log(tmp_path / "short.npz", time_s[:15 * 3600], dtheta[:15 * 3600], dv[:15 * 3600],
                      lat_deg=s0.SITE_LAT_DEG)
    far = write_log(tmp_path / "far.npz", time_s, dtheta, dv, lat_deg=45.0)
    slow = write_log(tmp_path / "slow.npz", np.arange(1, 10001) * 2.0, dtheta[:20000:2] * 2, dv[:20000:2] * 2,
                     lat_deg=s0.SITE_LAT_DEG)
    for argv, needle in [([path, "--identify", "hot", "--align-hours", "3"], "4 h of alignment"),
                         ([str(short), "--identify", "hot"], "log lasts 15 h"),
                         ([str(far), "--identify", "hot"], "trained at 28.222 deg"),
                         ([str(slow), "--identify", "hot"], "1 s INS steps"),
                         ([str(identified_log["bare"]), "--identify", "cold"], "no temperature columns"),
                         ([path, "--identify", str(tmp_path / "missing.json")], "missing.json"),
                         ([path, "--no-compensate"], "--no-compensate needs --identify")]:
        assert main(["replay", *argv]) == 2, argv
        err = capsys.readouterr().err
        assert len(err.splitlines()) == 1 and needle in err and err.startswith("sarins replay: error:"), err
