"""DriftModelUpdater FMU through FMPy: validation, same numbers as the library, errors, instances."""

import math

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from fmu_driver import Slave, check_parameter_error
from sarins.systems import GIMBAL_LINKS, INCREMENT_LINKS
from sarins_fmu.experiments.online_rls import GYRO_Z, imu_unit
from sarins_fmu.identify.online import OnlineDriftUpdater, UpdaterSettings, prior_covariance
from sarins_fmu.identify.rls import ForgettingRLS, RLSSettings
from sarins_fmu.imu import IMU
from sarins_fmu.ins import InsConfig, StrapdownINS
from sarins_fmu.kalman import StopFilterSettings
from sarins_fmu.thermal import Ambient
from sarins_fmu.units import DAY, DPH_TO_RPS
from sarins_fmu.vehicle import VehicleTrajectory

LAT = math.radians(40.0)
COEF = np.array([1e-6, -4e-5, 0.0025]) * DPH_TO_RPS
INPUTS = ("v_e", "v_n", "yaw", "pitch", "roll", "lat", "temp_gyro_z", "vehicle_speed", "nav_time")
OUTPUTS = ("compensation_drift", "drift_a", "drift_b", "drift_c", "stop_timer")


CHAIN = ["Turntable", "IMUThermal", "StrapdownINS", "DriftModelUpdater"]


@pytest.fixture(scope="module")
def fmu_path(fmu_dir):
    return fmu_dir / "DriftModelUpdater.fmu"


@pytest.fixture(scope="module")
def drive_rows():
    """INS outputs of a drive with a 32-min and a 7-min stop (premise unit, free INS)."""
    legs = [("drive", 200.0, 10.0), ("stop", 1920.0), ("drive", 60.0, 8.0), ("stop", 420.0), ("drive", 60.0, 8.0)]
    tr = VehicleTrajectory(legs, LAT, 0.0, 0.3)
    unit = imu_unit("premise")
    imu = IMU(unit, tr, tr.schedule.axes, output_interval=1.0, internal_rate=50.0, seed=4,
              ambient=Ambient(mean=30.0 - unit.thermal.self_heating[GYRO_Z]))
    ins = StrapdownINS(InsConfig(lat=LAT, align_time=0.0), initial_attitude=tr.mat_nb(0))
    angle, rate, accel = tr.schedule.state(tr.time[:-1])
    dtheta, dv, temps = imu.step(angle, rate, accel)
    out = ins.step(dtheta, dv)
    return np.column_stack([out[:, 3], out[:, 4], out[:, 6], out[:, 7], out[:, 8], out[:, 0], temps[:, GYRO_Z],
                            tr.speed[1:], np.arange(1.0, len(out) + 1)])  # last: the rows' nav_time tags


def test_fmpy_validate_finds_no_problem(fmu_path):
    assert validate_fmu(str(fmu_path)) == []


def _fmu_run(path, rows, name, start_day=10.0):
    slave = Slave(path, name)
    try:
        slave.set(a0=COEF[0], b0=COEF[1], c0=COEF[2], start_day=start_day, time_threshold=1800.0)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        out = []
        for k, row in enumerate(rows):
            slave.fmu.setReal([slave.vr[n] for n in INPUTS], list(row))
            slave.fmu.doStep(float(k), 1.0)
            out.append(slave.get(*OUTPUTS))
        counts = slave.fmu.getInteger([slave.vr["n_updates"], slave.vr["n_resets"]])
        return np.array(out), counts
    finally:
        slave.free()


def test_cosimulated_equals_in_process(fmu_path, drive_rows):
    """Fed the same INS outputs, the FMU and OnlineDriftUpdater give the same
    compensation at every step and the same updated model, bit for bit."""
    fmu_out, (n_updates, n_resets) = _fmu_run(fmu_path, drive_rows, "updater")
    rls = ForgettingRLS(COEF, prior_covariance(11.0, 0.0, 50.0), 0.0, RLSSettings(0.8))
    up = OnlineDriftUpdater(rls, LAT, 1.0, StopFilterSettings(), UpdaterSettings())
    n = drive_rows.shape[0]
    time = 10.0 * DAY + np.arange(1, n + 1)
    comp = up.step(time, drive_rows[:, 7], drive_rows[:, :2], drive_rows[:, 2:5], drive_rows[:, 6], drive_rows[:, 5])
    assert (n_updates, n_resets) == (1, 1)
    assert [e[1] for e in up.events] == ["update", "reset"]
    assert np.array_equal(fmu_out[:, 0], comp)  # the same C core: bit for bit
    assert np.array_equal(fmu_out[-1, 1:4], up.rls.parameters)
    assert np.max(np.abs(up.rls.parameters / COEF - 1.0)) > 0.01  # the long stop did change the model
    assert 1900.0 < fmu_out[:, 4].max() <= 1920.0  # the stop leg includes the braking


def test_two_instances_do_not_share_state(fmu_path, drive_rows):
    a = Slave(fmu_path, "a")
    b = Slave(fmu_path, "b")
    try:
        a.set(c0=0.001 * DPH_TO_RPS)
        for s in (a, b):
            s.fmu.enterInitializationMode()
            s.fmu.exitInitializationMode()
        for k, row in enumerate(drive_rows[:50]):
            for s in (a, b):
                s.fmu.setReal([s.vr[n] for n in INPUTS], list(row))
                s.fmu.doStep(float(k), 1.0)
        ca, cb = a.get("drift_c")[0], b.get("drift_c")[0]
        assert ca == pytest.approx(0.001 * DPH_TO_RPS) and cb == pytest.approx(0.0025 * DPH_TO_RPS)
    finally:
        a.free()
        b.free()


@pytest.mark.parametrize("params, text", [
    (dict(forgetting_factor=0.0), "must be positive"),
    (dict(forgetting_factor=1.5), "forgetting_factor"),
    (dict(prior_t_max=-5.0), "prior_t_max"),
    (dict(lat=math.radians(95)), "89.9"),
])
def test_bad_parameters_give_an_error_status(fmu_path, params, text):
    check_parameter_error(fmu_path, params, text)


def test_nan_input_and_changed_step_are_errors(fmu_path):
    """Each is fmi2Error at that doStep with the reason logged (the instance is then in the error state)."""
    log = []
    for bad in ("step", "nan"):
        slave = Slave(fmu_path, "nan", log=log)
        try:
            slave.fmu.enterInitializationMode()
            slave.fmu.exitInitializationMode()
            slave.fmu.doStep(0.0, 1.0)
            if bad == "nan":
                slave.set(v_e=float("nan"))
            with pytest.raises(FMICallException, match="status 3"):
                slave.fmu.doStep(1.0, 2.0 if bad == "step" else 1.0)
        finally:
            slave.free()
    errors = [m for status, _, m in log if status == 3]
    assert any("NaN" in m for m in errors) and any("step" in m for m in errors), errors


ALIGN = 1200.0  # s
MOVE_OFF = ALIGN + 1900.0  # s, the vehicle moves off after a 31.7-min stop
TT_TO_IMU = GIMBAL_LINKS
IMU_TO_INS = INCREMENT_LINKS
INS_TO_UPD = ["v_e", "v_n", "yaw", "pitch", "roll", "lat", "nav_time"]
LATENCY = 10  # s, the updater's default latency (steps of 1 s)


def test_closed_loop_chain_updates_the_model_like_the_library(fmu_dir):
    """Turntable -> IMUThermal -> StrapdownINS <-> DriftModelUpdater (Gauss-Seidel;
    the INS subtracts the updater's output from its apply_from on, the row's
    nav_time + latency): the stop after the alignment updates the model when
    the vehicle moves off, and every number equals the library run with the
    same latency."""
    n = int(MOVE_OFF) + 100
    names = ("tt", "imu", "ins", "upd")
    slaves = [Slave(fmu_dir / f"{name}.fmu", tag) for name, tag in zip(CHAIN, names)]
    tt, imu_fmu, ins_fmu, upd = slaves
    try:
        tt.set(align_time=ALIGN)
        imu_fmu.set(seed=7)
        ins_fmu.set(align_time=ALIGN)
        upd.set(a0=COEF[0], b0=COEF[1], c0=COEF[2], lat=math.radians(28.222))
        for s in slaves:
            s.fmu.enterInitializationMode()
        imu_fmu.fmu.setReal([imu_fmu.vr[v] for v in TT_TO_IMU], tt.get(*TT_TO_IMU))  # the start-of-run motion
        for s in slaves:
            s.fmu.exitInitializationMode()
        rows = []
        for k in range(n):
            t = float(k)
            tt.fmu.doStep(t, 1.0)
            imu_fmu.fmu.setReal([imu_fmu.vr[v] for v in TT_TO_IMU], tt.get(*TT_TO_IMU))
            imu_fmu.fmu.doStep(t, 1.0)
            ins_fmu.fmu.setReal([ins_fmu.vr[v] for v in IMU_TO_INS], imu_fmu.get(*IMU_TO_INS))
            comp, apply_from = upd.get("compensation_drift", "apply_from")
            ins_fmu.set(axial_drift_correction=comp, axial_drift_apply_from=apply_from)
            ins_fmu.fmu.doStep(t, 1.0)
            upd.fmu.setReal([upd.vr[v] for v in INS_TO_UPD], ins_fmu.get(*INS_TO_UPD))
            upd.set(temp_gyro_z=imu_fmu.get("temp_gyro_z")[0], vehicle_speed=1.0 if t + 1 >= MOVE_OFF else 0.0)
            upd.fmu.setInteger([upd.vr["ins_phase"]], ins_fmu.fmu.getInteger([ins_fmu.vr["phase"]]))
            upd.fmu.doStep(t, 1.0)
            rows.append(upd.get("compensation_drift", "drift_c", "stop_timer"))
        n_updates = upd.fmu.getInteger([upd.vr["n_updates"]])[0]
    finally:
        for s in reversed(slaves):
            s.free()
    rows = np.array(rows)
    assert n_updates == 1
    assert rows[:, 2].max() == pytest.approx(MOVE_OFF - ALIGN - 1.0, abs=1.0)
    assert rows[-1, 1] != pytest.approx(COEF[2], rel=1e-3)
    ref = _library_closed_loop(n)
    assert np.array_equal(rows[:, 0], ref)


def _library_closed_loop(n):
    from sarins_fmu import imu as imu_mod
    from sarins_fmu import turntable
    from sarins_fmu.imu import StaticBase

    lat = math.radians(28.222)
    table = turntable.single_axis("forward-reverse", n + 1.0, grid=1.0, align_time=ALIGN, align_dwell=300.0)
    sensor = IMU(imu_mod.preset("nav-rlg"), StaticBase(lat), table.axes, output_interval=1.0, seed=7)
    dtheta, dv, temps = sensor.step(*table.state(np.arange(n, dtype=float)))
    ins = StrapdownINS(InsConfig(lat=lat, align_time=ALIGN))
    rls = ForgettingRLS(COEF, prior_covariance(11.0, 0.0, 50.0), 0.0, RLSSettings(0.8))
    up = OnlineDriftUpdater(rls, lat)
    out = np.empty(n)
    for k in range(n):
        # interval k starts at nav time k - ALIGN: compensated by the updater's output of row k - 1 - LATENCY
        # (rows during the alignment are never applied: the INS compensates only while navigating)
        comp = out[k - 1 - LATENCY] if k - 1 - LATENCY >= 0 else 0.0
        row = ins.step(dtheta[k], dv[k], comp)[0]
        speed = 1.0 if k + 1 >= MOVE_OFF else 0.0
        out[k] = float(up.step([k + 1.0 - ALIGN], [speed], [row[3:5]], [row[6:9]], [temps[k, GYRO_Z]], [row[0]],
                               [ins.phase == "navigate"])[0])
    return out
