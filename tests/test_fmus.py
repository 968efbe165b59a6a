"""The FMUs through FMPy: validation, co-simulated vs in-process, errors,
reset, several instances, and a host without this project installed."""

import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from fmu_driver import Slave, check_parameter_error, run_chain
from fmus.build import build_fmus, parse_unit
from sarins_fmu.experiments import run_static

DEG = math.pi / 180
SHORT = dict(align_time=1200.0)  # 20 min alignment keeps the tests short

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("name", ["Turntable", "IMUThermal", "StrapdownINS"])
def test_fmpy_validate_finds_no_problem(fmu_dir, name):
    assert validate_fmu(str(fmu_dir / f"{name}.fmu")) == []


def test_driver_links_are_the_systems_links():
    import fmu_driver
    from sarins.systems import GIMBAL_LINKS, INCREMENT_LINKS

    assert fmu_driver.TT_TO_IMU == GIMBAL_LINKS and fmu_driver.IMU_TO_INS == INCREMENT_LINKS


def test_units_and_display_units_in_model_description(fmu_dir):
    from fmpy import read_model_description

    md = read_model_description(str(fmu_dir / "StrapdownINS.fmu"))
    by_name = {v.name: v for v in md.modelVariables}
    assert by_name["lat_error"].unit == "rad" and by_name["lat_error"].displayUnit == "deg"
    assert by_name["position_error"].displayUnit == "nmi"
    units = {u.name: u for u in md.unitDefinitions}
    assert units["rad/s"].baseUnit.rad == 1 and units["rad/s"].baseUnit.s == -1
    factors = {d.name: d.factor for d in units["rad/s"].displayUnits}
    assert factors["deg/h"] == pytest.approx(180 / math.pi * 3600)
    assert parse_unit("x [rad/s; deg/h]") == ("rad/s", "deg/h")


def test_cosimulated_equals_in_process(fmu_dir):
    """Same seed, Gauss-Seidel chain: identical to the library run (1e-9)."""
    n_nav = 2 * 3600
    rows = run_chain(fmu_dir, 1200 + n_nav, tt_params=SHORT, imu_params=dict(seed=5),
                     ins_params=SHORT, record=("lat_error", "lon_error", "position_error"))
    cosim = np.array(rows)[1200:]
    ref = run_static(align_hours=1200 / 3600, nav_hours=2.0, seed=5)
    for j, series in enumerate((ref.lat_error, ref.lon_error, ref.position_error)):
        scale = np.max(np.abs(series))
        assert scale > 0
        assert np.max(np.abs(cosim[:, j] - series)) <= 1e-9 * scale


def test_axial_correction_input_in_cosimulation(fmu_dir):
    """The INS subtracts the correction input during navigation, exactly as
    the in-process run's correction does, and most of the drift's effect goes."""
    drift_dph = 0.003
    drift = drift_dph * DEG / 3600
    params = dict(preset="ideal", axial_drift_c=drift)
    n = 1200 + 4 * 3600
    raw = run_chain(fmu_dir, n, tt_params=SHORT, imu_params=params, ins_params=SHORT, record=("position_error",))
    fixed = run_chain(fmu_dir, n, tt_params=SHORT, imu_params=params, ins_params=SHORT,
                      record=("position_error",), correction=lambda t: drift)
    ref = run_static(align_hours=1200 / 3600, nav_hours=4.0, imu="ideal", axial_drift_dph=drift_dph,
                     correction_dph=drift_dph)
    assert fixed[-1][0] == pytest.approx(ref.position_error[-1], rel=1e-9)
    assert fixed[-1][0] < 0.1 * raw[-1][0]


@pytest.mark.parametrize("fmu, params, text", [
    ("StrapdownINS", dict(lat0=95 * DEG), "89.9"),
    ("IMUThermal", dict(lat=-90 * DEG), "89.9"),
    ("IMUThermal", dict(preset="fog"), "unknown IMU preset"),
    ("IMUThermal", dict(internal_rate=float("nan")), "not a finite"),
    ("Turntable", dict(rate=-1.0), "must not be negative"),
    ("Turntable", dict(scheme="sideways"), "unknown scheme"),
    ("Turntable", dict(ambient_mode="chamber", chamber_first="middle"), "'low' or 'high'"),
    ("Turntable", dict(ambient_mode="chamber", chamber_step=-2.0), "chamber_step"),
    ("StrapdownINS", dict(kf_arw=0.0), "must be positive"),
])
def test_bad_parameters_give_an_error_status_and_a_message(fmu_dir, fmu, params, text):
    """fmi2ExitInitializationMode returns fmi2Error with the reason logged; the
    host survives and frees the instance."""
    check_parameter_error(fmu_dir / f"{fmu}.fmu", params, text)
    import gc

    gc.collect()  # the heap is intact


def test_bad_step_and_bad_inputs_give_an_error_with_a_logged_message(fmu_dir):
    slave = Slave(fmu_dir / "StrapdownINS.fmu", "ins")
    try:
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        with pytest.raises(FMICallException, match="status 3"):
            slave.fmu.doStep(0.0, -1.0)
    finally:
        slave.free()
    slave = Slave(fmu_dir / "StrapdownINS.fmu", "ins", log=slave.log)
    try:
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        slave.set(dtheta_x=float("nan"))
        with pytest.raises(FMICallException, match="status 3"):
            slave.fmu.doStep(0.0, 1.0)
        errors = [m for status, _, m in slave.log if status == 3]
        assert any("step size" in m for m in errors) and any("NaN" in m for m in errors), errors
    finally:
        slave.free()


def _steps(slave, n, **inputs):
    out = []
    for k in range(n):
        slave.set(motion_time=float(k), **inputs)  # a static table: the start-of-step motion set for t = k
        slave.fmu.doStep(float(k), 1.0)
        out.append(slave.get("dtheta_x", "dtheta_y", "dv_x", "temp_gyro_z"))
    return np.array(out)


def test_reset_returns_to_the_initial_state(fmu_dir):
    slave = Slave(fmu_dir / "IMUThermal.fmu", "imu")
    try:
        slave.set(seed=11)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        first = _steps(slave, 20)
        slave.fmu.reset()
        slave.set(seed=11)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        assert np.array_equal(_steps(slave, 20), first)
    finally:
        slave.free()


def test_two_instances_do_not_share_state(fmu_dir):
    a = Slave(fmu_dir / "IMUThermal.fmu", "a")
    b = Slave(fmu_dir / "IMUThermal.fmu", "b")
    c = Slave(fmu_dir / "IMUThermal.fmu", "c")
    try:
        for s, seed in ((a, 1), (b, 2), (c, 1)):
            s.set(seed=seed)
            s.fmu.enterInitializationMode()
            s.fmu.exitInitializationMode()
        out_a, out_b = [], []
        for k in range(20):  # interleaved stepping
            for s in (a, b):
                s.set(motion_time=float(k))
                s.fmu.doStep(float(k), 1.0)
            out_a.append(a.get("dtheta_x"))
            out_b.append(b.get("dtheta_x"))
        out_c = _steps(c, 20)[:, 0]
        assert np.array_equal(np.ravel(out_a), out_c)
        assert not np.array_equal(out_a, out_b)
    finally:
        for s in (a, b, c):
            s.free()


def test_fmu_runs_in_a_host_without_this_project(fmu_dir, tmp_path):
    """numpy and fmpy importable, sarins_fmu not: the native FMUs need nothing of the project."""
    import fmpy

    import shutil

    site_dirs = sorted({os.path.dirname(os.path.dirname(m.__file__)) for m in (np, fmpy)})
    host_libs = tmp_path / "host_libs"  # the generic master's logger module, not the project
    shutil.copytree(os.path.join(os.path.dirname(os.path.dirname(__file__)), "orchestration"),
                    host_libs / "orchestration")
    site_dirs.append(str(host_libs))
    script = textwrap.dedent(f"""
        import sys
        sys.path[:0] = {site_dirs!r}
        try:
            import sarins_fmu
            raise SystemExit("sarins_fmu must not be importable here")
        except ImportError:
            pass
        sys.path.insert(0, {str(os.path.dirname(__file__))!r})
        from fmu_driver import run_chain
        from pathlib import Path
        rows = run_chain(Path({str(fmu_dir)!r}), 320, tt_params=dict(align_time=300.0),
                         imu_params=dict(internal_rate=20.0), ins_params=dict(align_time=300.0, coarse_time=60.0),
                         record=("lat", "nav_time"))
        assert rows[-1][1] > 0 and abs(rows[-1][0] - 0.4925668) < 1e-3, rows[-1]
        assert "sarins_fmu" not in sys.modules and not any(name.endswith(".sarins_fmu") for name in sys.modules)
        print("ok")
    """)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH",)}
    proc = subprocess.run([sys.executable, "-S", "-c", script], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "ok" in proc.stdout




def test_build_fmus_never_writes_an_fmu_that_cannot_run(tmp_path):
    """IMUCompensator needs a trained model: without one it is refused, not built empty."""
    with pytest.raises(ValueError, match="needs a trained model"):
        build_fmus(tmp_path, ["IMUCompensator"])
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-m", "sarins", "build-fmus", "--only", "IMUCompensator", "--out",
                           str(tmp_path / "out")], capture_output=True, text=True, timeout=300, env=env)
    assert done.returncode == 2 and "needs a trained model" in done.stderr, done.stderr
    assert not (tmp_path / "out" / "IMUCompensator.fmu").exists()
