"""Seed 002's vehicle test through the FMUs (the vehicle_rins_online SSP system) equals the
in-process test bit for bit; the FMUs pair their time-tagged inputs or refuse (issue 11)."""

import math

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

import sarins_fmu.identify.axial  # noqa: F401 - the FMUs' shared library copy must outlive each run's unpacking
from fmu_driver import Slave
from sarins.online_rls.cosim import vehicle_task
from sarins_fmu.units import DPH_TO_RPS

# two sessions whose stops (29-35 min) mostly count, a short test drive: every path of the test in seconds
SHORT = dict(seed=1, unit="premise", n_sessions=2, year_days=60.0, test_day=80.0, drive_hours=0.3,
             stop_minutes=(29.0, 35.0), calibration_points=5)


def assert_same_results(a: dict, b: dict):
    assert sorted(a) == sorted(b)
    differ = [k for k in a if k != "engine" and not np.array_equal(np.asarray(a[k]), np.asarray(b[k]))]
    assert not differ, {k: (a[k], b[k]) for k in differ[:3]}


def test_vehicle_test_through_the_fmus_equals_in_process(fmu_dir):
    """Sessions (VehicleMotion -> Turntable -> IMUThermal -> StrapdownINS <-> DriftModelUpdater, the
    RLS state carried between them in a model file) and the test drive's two navigations through the
    FMUs give every number of the in-process vehicle test bit for bit."""
    ref = vehicle_task(**SHORT)
    fmus = vehicle_task(engine="cosim", fmu_dir=str(fmu_dir), **SHORT)
    assert fmus["engine"] == "cosim" and ref["engine"] == "inprocess"
    assert ref["n_updates"] >= 1  # the model was updated through the FMUs' stop filter and RLS
    assert not np.array_equal(ref["initial_dph"], ref["updated_dph"])
    assert_same_results(ref, fmus)


@pytest.mark.slow
def test_quick_campaign_through_the_fmus_equals_in_process(tmp_path):
    """``sarins campaign online-rls --profile quick --engine cosim``: every run's numbers equal the
    in-process campaign's (the vehicle test runs through the FMUs, the rest is the same code)."""
    from sarins.campaign import load_result
    from sarins.cli import main

    runs = {}
    for engine in ("inprocess", "cosim"):
        out = tmp_path / engine
        assert main(["campaign", "online-rls", "--profile", "quick", "--engine", engine, "--workers", "1",
                     "--out", str(out), "--no-progress"]) == 0
        runs[engine] = {p.stem: load_result(p) for p in sorted((out / "runs").glob("*.npz"))}
    assert sorted(runs["inprocess"]) == sorted(runs["cosim"])
    vehicle = [k for k in runs["cosim"] if k.startswith("veh-")]
    assert vehicle
    for key in runs["inprocess"]:
        assert_same_results(runs["inprocess"][key], runs["cosim"][key])
    assert all(str(runs["cosim"][k]["engine"]) == "cosim" for k in vehicle)


def test_a_session_is_the_same_under_every_engine(fmu_dir, tmp_path):
    """One session of the vehicle test (drive, a stop that updates the model, drive, a short stop at the
    end so the Jacobi engines can run two steps longer) through the shipped system under the master's
    Gauss-Seidel and Jacobi, Ecos and libcosim: every INS row and the updated model equal the in-process
    session bit for bit."""
    import warnings
    from dataclasses import replace

    from fmu_fixtures.thirdparty import ensure_libtbb, has_module
    from orchestration import simulate_system, write_ssp
    from sarins.online_rls.cosim import NAV, CosimEngine, ins_rows
    from sarins_fmu.experiments.online_rls import _session_run, imu_unit
    from sarins_fmu.experiments.online_rls_vehicle import InProcessEngine
    from sarins_fmu.identify.online import OnlineDriftUpdater, UpdaterSettings, prior_covariance
    from sarins_fmu.identify.rls import ForgettingRLS, RLSSettings
    from sarins_fmu.kalman import StopFilterSettings

    unit = imu_unit("premise")
    run = _session_run(unit, unit.axial_drift_poly, day=12.0, temperature=30.0, stop_seconds=420.0,
                       lat=math.radians(40.0), seed=8)
    run = replace(run, legs=(*run.legs[:4], ("drive", 60.0, 8.0), ("stop", 30.0)))

    def updater():
        rls = ForgettingRLS(unit.axial_drift_poly, prior_covariance(11.0, 0.0, 50.0), 0.0, RLSSettings(0.8))
        return OnlineDriftUpdater(rls, run.lat, 1.0, StopFilterSettings.for_model(unit), UpdaterSettings(360.0))

    ref = updater()
    ref_rows = InProcessEngine().session(run, ref)
    assert [e[1] for e in ref.events] == ["update"]
    n = len(ref_rows)
    engine = CosimEngine(fmu_dir)
    system = engine.session_system(run, updater(), updater().rls.export_binary(tmp_path / "rls.bin"))
    record = ["ins." + v for v in ["solution_time", *NAV]] + ["updater.drift_a", "updater.drift_b", "updater.drift_c"]
    stop = n + 2.0  # Jacobi engines: the updater's row two steps behind
    runs = {}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for scheme in ("gauss-seidel", "jacobi"):
            runs[f"master {scheme}"] = simulate_system(system, stop, 1.0, scheme=scheme, record=record,
                                                       progress=False)
    if has_module("ecospy") and not ensure_libtbb():
        from orchestration.importers import simulate_with_ecos

        runs["Ecos"] = simulate_with_ecos(write_ssp(system, tmp_path / "session.ssp"), stop, 1.0, record=record)
    if has_module("libcosimpy"):
        from orchestration.importers import simulate_with_libcosim

        runs["libcosim"] = simulate_with_libcosim(system, stop, 1.0, record=record)
    assert len(runs) >= 2
    for name, res in runs.items():
        rows = ins_rows(res, "solution_time", float(n))
        assert rows.shape == ref_rows.shape, name
        assert np.array_equal(rows, ref_rows), name
        assert [res[f"updater.drift_{c}"][-1] for c in "abc"] == list(ref.rls.parameters), name


# ------------------------------------------------------------------ the updater's pairing
ROW = dict(v_e=0.0, v_n=0.0, yaw=0.1, pitch=0.0, roll=0.0, lat=math.radians(40.0), temp_gyro_z=25.0)


def _updater(fmu_dir, name):
    slave = Slave(fmu_dir / "DriftModelUpdater.fmu", name)
    slave.set(a0=1e-6 * DPH_TO_RPS, b0=-4e-5 * DPH_TO_RPS, c0=0.0025 * DPH_TO_RPS)
    slave.fmu.enterInitializationMode()
    slave.fmu.exitInitializationMode()
    return slave


def _errors(slave):
    return [m for status, _, m in slave.log if status == 3]


def _step(slave, k, **inputs):
    slave.set(**ROW, **inputs)
    slave.fmu.doStep(float(k), 1.0)


def test_updater_pairs_each_ins_row_with_the_speed_of_its_time(fmu_dir):
    """Jacobi-like lags (speeds two steps ahead of the rows) are paired exactly: the stop starts at the
    row whose own speed is zero, not at the row whose step saw a zero speed."""
    speeds = [5.0, 5.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]  # the speed at t = k
    slave = _updater(fmu_dir, "pairing")
    try:
        timers = []
        for k in range(6):  # step k: the vehicle's speed at k + 1, the INS row of k - 1 (none yet for k <= 1)
            row = max(k - 1, 0)
            _step(slave, k, vehicle_speed=speeds[k + 1], speed_time=k + 1.0, solution_time=float(row),
                  nav_time=float(row))
            timers.append(slave.get("stop_timer", "row_time"))
        assert [t[1] for t in timers] == [-1e9, -1e9, 1.0, 2.0, 3.0, 4.0]  # rows 1.. processed in order
        assert [t[0] for t in timers] == [0.0, 0.0, 0.0, 1.0, 2.0, 3.0]  # the stop starts with row 2 (speed 0 at 2)
    finally:
        slave.free()


@pytest.mark.parametrize("case, text", [
    ("speed_untagged_rows", "connect the INS's solution_time"),
    ("speed_too_late", "no vehicle_speed tagged speed_time=2"),
    ("skipped_row", "row at 2 s was due"),
])
def test_updater_refuses_a_pairing_it_cannot_make(fmu_dir, case, text):
    slave = _updater(fmu_dir, case)
    try:
        _step(slave, 0, vehicle_speed=1.0, speed_time=1.0, solution_time=1.0, nav_time=1.0)
        inputs = {"speed_untagged_rows": dict(speed_time=2.0, solution_time=-1e9, nav_time=2.0),
                  "speed_too_late": dict(speed_time=1.0, solution_time=2.0, nav_time=2.0),  # no speed for row 2
                  "skipped_row": dict(speed_time=3.0, solution_time=3.0, nav_time=3.0)}[case]
        with pytest.raises(FMICallException, match="status 3"):
            _step(slave, 1, vehicle_speed=1.0, **inputs)
        assert any(text in m for m in _errors(slave)), slave.log
    finally:
        slave.free()


# ------------------------------------------------------------------ the INS's model correction
def test_ins_applies_a_temperature_model_like_the_constant_it_evaluates_to(fmu_dir):
    """StrapdownINS with the correction c + (a T + b) T gives bit for bit the solution of the constant
    that the model gives at the interval's temperature (closed form of what it subtracts)."""
    from sarins_fmu.drift_model import drift_model_value

    coef = (2e-6 * DPH_TO_RPS, -3e-5 * DPH_TO_RPS, 0.004 * DPH_TO_RPS)  # a, b, c
    temp = 31.5
    runs = []
    for inputs in (dict(axial_drift_correction_a=coef[0], axial_drift_correction_b=coef[1],
                        axial_drift_correction=coef[2]),
                   dict(axial_drift_correction=drift_model_value(coef, temp))):
        slave = Slave(fmu_dir / "StrapdownINS.fmu", "model")
        try:
            slave.set(align_time=0.0, yaw0=0.3, axial_drift_apply_from=0.0, temp_gyro_z=temp, **inputs)
            slave.fmu.enterInitializationMode()
            slave.fmu.exitInitializationMode()
            assert slave.get("solution_time", "nav_time", "yaw") == [0.0, 0.0, 0.3]
            for k in range(200):
                slave.set(increment_end_time=k + 1.0, dv_z=9.8)
                slave.fmu.doStep(float(k), 1.0)
            runs.append(slave.get("yaw", "lat", "lon", "solution_time"))
        finally:
            slave.free()
    assert runs[0] == runs[1]
    assert runs[0][3] == 200.0
    assert runs[0][0] != 0.3  # the correction turned the heading


def test_updater_model_file_errors_name_the_file(fmu_dir, tmp_path):
    """A missing or corrupt model_file, one in a format the native FMU does not read (JSON), or one with
    other forgetting settings than the parameters, is an fmi2Error at the end of initialisation naming
    the file."""
    from fmu_driver import check_parameter_error
    from sarins_fmu.identify.rls import ForgettingRLS, RLSSettings

    path = fmu_dir / "DriftModelUpdater.fmu"
    check_parameter_error(path, {"model_file": str(tmp_path / "missing.bin")}, "missing.bin")
    (tmp_path / "bad.bin").write_bytes(b"SARNET\0\1" + bytes(200))
    check_parameter_error(path, {"model_file": str(tmp_path / "bad.bin")}, "bad.bin")
    json_file = ForgettingRLS([0.0, 0.0, 1e-8], np.eye(3), 0.0, RLSSettings(0.8)).save(tmp_path / "rls.json")
    check_parameter_error(path, {"model_file": str(json_file)}, "not a sarins binary model file")
    other = ForgettingRLS([0.0, 0.0, 1e-8], np.eye(3), 0.0, RLSSettings(0.5)).export_binary(tmp_path / "lam.bin")
    check_parameter_error(path, {"model_file": str(other)}, "forgetting factor 0.5")
