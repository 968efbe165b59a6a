"""FMI 3.0 IMUThermal and StrapdownINS with every sub-interval of a step in arrays (issue 19 item 4).

IMUThermal with ``n_sub`` = K runs each communication step as K output intervals of h / K (as if stepped at
h / K) and outputs them in the arrays ``dtheta_x_sub`` .. ``dv_z_sub``, ``temp_gyro_z_sub``; StrapdownINS with
``sub_inputs = 1`` integrates them one by one.  Checked: the arrays are the FMI 2.0 IMU stepped at h / K bit
for bit and the scalars their sums; the FMI 3.0 chain Turntable -> IMUThermal -> StrapdownINS at 1 s with the
arrays connected navigates like the FMI 2.0 chain at 5 ms (bit for bit on a still table, to rounding while
the table turns); bad settings refused with the reason; fmpy validate, FMPy's simulate_fmu and fmusim.
"""

from __future__ import annotations

import csv
import os
import shutil
import subprocess
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

from fmus.cbuild import build_line
from fmus.native_fmu import build_native_fmu

pytestmark = pytest.mark.integration

RATE, K = 200.0, 200  # IMU internal rate (Hz), sub-intervals of a 1 s step
INCREMENTS = [f"{q}_{a}" for q in ("dtheta", "dv") for a in "xyz"]
SUB = [f"{name}_sub" for name in INCREMENTS + ["temp_gyro_z"]]
INS_OUT = ["lat", "lon", "height", "v_e", "v_n", "v_u", "yaw", "pitch", "roll", "lat_error", "lon_error",
           "north_error", "east_error", "position_error", "nav_time", "gyro_drift_est_x", "gyro_drift_est_y",
           "accel_bias_est_x", "accel_bias_est_y", "temp_align_start", "temp_align_end", "temp_change_align",
           "temp_azimuth_gyro", "solution_time", "phase"]


@pytest.fixture(scope="module")
def fmus3(fmu3_dir):
    """The FMI 3.0 Turntable, IMUThermal and StrapdownINS (the session's, tests/conftest.py)."""
    return fmu3_dir


class Fmu3:
    """An FMI 3.0 instance, configured with n_sub, its log kept."""

    def __init__(self, path, n_sub: int | None = None, name: str = "x"):
        self.md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages: list[str] = []

        def log(env, status, category, message):
            self.messages.append(message.decode())

        self.s = FMU3Slave(guid=self.md.guid, unzipDirectory=extract(str(path)),
                           modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.s.instantiate(logMessage=log)
        if n_sub is not None:
            self.s.enterConfigurationMode()
            self.s.setUInt64([self.vr["n_sub"]], [n_sub])
            self.s.exitConfigurationMode()

    def set(self, **values):
        for name, value in values.items():
            if isinstance(value, int):
                self.s.setInt32([self.vr[name]], [value])
            else:
                self.s.setFloat64([self.vr[name]], [value])

    def get(self, names, n=None):
        return self.s.getFloat64([self.vr[v] for v in names], n)


def sequential_sum(values) -> float:
    total = 0.0
    for v in values:
        total += v
    return total


def test_the_arrays_are_the_fmi2_imu_stepped_at_the_internal_rate(fmu_dir, fmus3):
    from fmu_driver import Slave

    fixed = {"angle_1": 0.3, "ambient_temp": 23.0}  # no turntable: a fixed table (noise and drifts on, nav-rlg)
    two = Slave(fmu_dir / "IMUThermal.fmu", "imu2")
    three = Fmu3(fmus3 / "IMUThermal.fmu", K)
    try:
        two.set(**fixed)
        three.set(**fixed)
        for f in (two.fmu, three.s):
            f.enterInitializationMode()
            f.exitInitializationMode()
        for step in range(3):
            rows = []
            for k in range(K):
                two.fmu.doStep(step + k / RATE, 1.0 / RATE)
                rows.append(two.get(*INCREMENTS, "temp_gyro_z"))
            three.s.doStep(float(step), 1.0)
            arrays = np.array(three.get(SUB, 7 * K)).reshape(7, K)
            assert np.array_equal(arrays, np.array(rows).T)  # every 5 ms interval, bit for bit
            scalars = three.get(INCREMENTS + ["temp_gyro_z", "increment_end_time"])
            assert scalars[:6] == [sequential_sum(a) for a in arrays[:6]]  # the sums, in order
            assert scalars[6:] == [arrays[6, -1], step + 1.0]
        assert np.ptp(arrays[5]) > 0 and np.all(arrays[5] > 0.04)  # noise on, gravity along z
        state = three.s.getFMUState()  # the arrays and the sub-interval IMU travel in the FMU state
        three.s.doStep(3.0, 1.0)
        after = three.get(SUB, 7 * K)
        three.s.setFMUState(state)
        assert three.get(SUB, 7 * K) == list(arrays.ravel())
        three.s.doStep(3.0, 1.0)
        assert three.get(SUB, 7 * K) == after and after != list(arrays.ravel())
        three.s.freeFMUState(state)
    finally:
        two.free()
        three.s.freeInstance()


def test_one_sub_interval_is_the_step_of_before(fmu_dir, fmus3):
    from fmu_driver import Slave

    two = Slave(fmu_dir / "IMUThermal.fmu", "imu2")
    three = Fmu3(fmus3 / "IMUThermal.fmu")  # n_sub = 1, its default
    try:
        for f in (two.fmu, three.s):
            f.enterInitializationMode()
            f.exitInitializationMode()
        for step in range(3):
            two.fmu.doStep(float(step), 1.0)
            three.s.doStep(float(step), 1.0)
            scalars = two.get(*INCREMENTS, "temp_gyro_z")
            assert three.get(INCREMENTS + ["temp_gyro_z"]) == scalars
            assert three.get(SUB, 7) == scalars
    finally:
        two.free()
        three.s.freeInstance()


CHAINS = {  # turntable start values; the INS aligns 240 s (coarse 60 s), then navigates 120 s
    "still table": ({"scheme": "none"}, 0.0),
    "forward-reverse": ({}, 1e-13),
    "dual-axis in a chamber": ({"scheme": "dual-axis", "ambient_mode": "chamber", "chamber_hold": 60.0,
                                "chamber_ramp": 0.05, "ambient_mean": 25.0}, 1e-11),
}
ABS_SCALE = {"position_error": 1e2, "north_error": 1e2, "east_error": 1e2, "v_e": 1e1, "v_n": 1e1, "v_u": 1e1,
             "temp_align_start": 1e2, "temp_align_end": 1e2, "temp_change_align": 1e2, "temp_azimuth_gyro": 1e2}


def _run_chain(folder, table, step, sub):
    from orchestration import Connection, UnconnectedInputWarning, simulate_system
    from sarins.systems import standard_static

    ins = {"align_time": 240.0, "coarse_time": 60.0}
    imu = {}
    if sub:
        imu, ins = {"n_sub": K}, {**ins, "n_sub": K, "sub_inputs": 1}
    system = standard_static(folder, turntable={"align_time": 240.0, **table}, imu=imu, ins=ins)
    if sub:
        system.connections.extend(Connection("imu", a, "ins", a) for a in SUB)
    record = [f"ins.{v}" for v in INS_OUT] + ["turntable.angle_1", "turntable.angle_2"] + [f"imu.{v}" for v in INCREMENTS]
    if sub:
        record += [f"imu.{a}" for a in SUB]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnconnectedInputWarning)
        return simulate_system(system, 360.0, step, record=record, output_every=round(1.0 / step),
                               progress=False)


@pytest.mark.parametrize("case", list(CHAINS))
def test_the_1s_fmi3_chain_with_arrays_navigates_like_the_fmi2_chain_at_5ms(fmu_dir, fmus3, case):
    table, tol = CHAINS[case]
    fine = _run_chain(fmu_dir, table, 1.0 / RATE, sub=False)
    coarse = _run_chain(fmus3, table, 1.0, sub=True)
    assert np.array_equal(fine["time"], coarse["time"]) and coarse["time"][-1] == 360.0
    for name in ("nav_time", "solution_time", "phase"):
        assert np.array_equal(fine[f"ins.{name}"], coarse[f"ins.{name}"]), name
    for name in INS_OUT:
        a, b = fine[f"ins.{name}"], coarse[f"ins.{name}"]
        if tol == 0.0:
            assert np.array_equal(a, b), name
        else:  # the table's motion inside a step rounds differently (see docs/native-layer.md)
            assert np.max(np.abs(a - b)) <= tol * ABS_SCALE.get(name, 1.0), (name, np.max(np.abs(a - b)))
    assert coarse["ins.phase"][-1] == 2 and coarse["ins.position_error"][-1] > 0.1
    if table.get("scheme") != "none":
        assert max(np.ptp(coarse[f"turntable.angle_{j}"]) for j in (1, 2)) > 1.0  # the table turned
    # the scalar increments are the sums of the arrays that carried every 5 ms interval
    for name in INCREMENTS:
        sub = np.column_stack([coarse[f"imu.{name}_sub[{k}]"] for k in range(1, K + 1)])
        assert list(coarse[f"imu.{name}"][1:]) == [sequential_sum(row) for row in sub[1:]], name


def test_bad_sub_settings_are_refused_with_the_reason(fmu_dir, fmus3):
    from fmu_driver import Slave

    imu = Fmu3(fmus3 / "IMUThermal.fmu", 3, "imu")  # 200 Hz * 1 s / 3: not whole minor steps
    imu.s.enterInitializationMode()
    imu.s.exitInitializationMode()
    with pytest.raises(FMICallException):
        imu.s.doStep(0.0, 1.0)
    assert "n_sub 3" in "\n".join(imu.messages) and "not a whole number of minor steps" in "\n".join(imu.messages)
    imu.s.freeInstance()
    ins = Fmu3(fmus3 / "StrapdownINS.fmu", 4, "ins")
    ins.set(sub_inputs=2)
    ins.s.enterInitializationMode()
    with pytest.raises(FMICallException):
        ins.s.exitInitializationMode()
    assert "sub_inputs = 2 must be 0" in "\n".join(ins.messages)
    ins.s.freeInstance()
    two = Slave(fmu_dir / "StrapdownINS.fmu", "ins2")  # FMI 2.0 has no array inputs
    try:
        two.set(sub_inputs=1)
        two.fmu.enterInitializationMode()
        with pytest.raises(FMICallException):
            two.fmu.exitInitializationMode()
        assert "only the FMI 3.0 variant" in "\n".join(str(m) for m in two.log)
    finally:
        two.free()
    ins = Fmu3(fmus3 / "StrapdownINS.fmu", 4, "ins")
    ins.set(sub_inputs=1, align_time=0.0)
    ins.s.enterInitializationMode()
    ins.s.exitInitializationMode()
    ins.s.setFloat64([ins.vr["dv_z_sub"]], [0.0, float("nan"), 0.0, 0.0])
    ins.set(increment_end_time=1.0)
    with pytest.raises(FMICallException):
        ins.s.doStep(0.0, 1.0)
    assert "contain NaN or infinity (element 2)" in "\n".join(ins.messages)
    ins.s.freeInstance()


def test_the_in_process_ins_refuses_sub_inputs():
    from fmus.slave_support import ParameterError
    from fmus.strapdown_ins_slave import StrapdownINS

    ins = StrapdownINS(instance_name="ins", resources=".")
    ins.sub_inputs = 1
    with pytest.raises(ParameterError, match="sub_inputs = 1: this in-process INS has no array inputs"):
        ins.exit_initialization_mode()
    ins.sub_inputs = 0
    ins.exit_initialization_mode()
    assert ins.phase == 0


def test_fmpy_validates_and_simulates_the_fmi3_imu_and_ins(fmus3):
    for name in ("IMUThermal", "StrapdownINS"):
        assert validate_fmu(str(fmus3 / f"{name}.fmu")) == []
    path = fmus3 / "IMUThermal.fmu"
    # simulate_fmu sets start values in Instantiated, where structural parameters cannot change (FMI 3.0):
    # give it an instance configured with n_sub, and the arrays' shape in the model description it records by
    md = read_model_description(str(path))
    for v in md.modelVariables:
        if v.name.endswith("_sub"):
            v.shape = (K,)
    imu = Fmu3(path, K, "imu")
    result = simulate_fmu(str(path), stop_time=5.0, output_interval=1.0, model_description=md, fmu_instance=imu.s,
                          start_values={"angle_1": 0.3}, output=["dtheta_z", "dtheta_z_sub", "temp_gyro_z_sub"])
    imu.s.freeInstance()
    assert result["dtheta_z_sub"].shape == (6, K)
    assert list(result["dtheta_z"][1:]) == [sequential_sum(row) for row in result["dtheta_z_sub"][1:]]
    path = fmus3 / "StrapdownINS.fmu"
    ins = Fmu3(path, K, "ins")
    lat0 = 0.5
    result = simulate_fmu(str(path), stop_time=5.0, output_interval=1.0, fmu_instance=ins.s,
                          start_values={"align_time": 0.0, "sub_inputs": 1, "lat0": lat0}, output=["solution_time", "lat", "phase"])
    ins.s.freeInstance()
    # nothing connected: increment_end_time stays at the start time, so the INS waits for its first increments
    assert list(result["solution_time"]) == [0.0] * 6 and list(result["lat"]) == [lat0] * 6
    assert list(result["phase"]) == [2] * 6


def test_fmusim_runs_the_fmi3_imu_with_n_sub(fmus3, tmp_path):
    fmusim = os.environ.get("FMUSIM") or shutil.which("fmusim")
    if fmusim is None:
        pytest.skip("fmusim not found (set FMUSIM to its path; docs/quick-start.md says how to build it)")
    out = tmp_path / "imu.csv"
    cmd = [fmusim, "--interface-type", "cs", "--stop-time", "5", "--output-interval", "1", "--start-value", "n_sub",
           str(K), "--start-value", "angle_1", "0.3", "--output-variable", "dtheta_z", "--output-variable",
           "dtheta_z_sub", "--output-file", str(out), str(fmus3 / "IMUThermal.fmu")]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    rows = list(csv.reader(out.open()))
    assert rows[0] == ["time", "dtheta_z", "dtheta_z_sub"] and len(rows) == 7
    imu = Fmu3(fmus3 / "IMUThermal.fmu", K, "imu")
    imu.set(angle_1=0.3)
    imu.s.enterInitializationMode()
    imu.s.exitInitializationMode()
    for step, row in enumerate(rows[2:]):
        imu.s.doStep(float(step), 1.0)
        sub = np.array([float(x) for x in row[2].split()])
        mine = np.array(imu.get(["dtheta_z_sub"], K))
        assert sub.shape == (K,)
        np.testing.assert_allclose(sub, mine, rtol=4.5e-16, atol=0)  # fmusim prints %.16g
    imu.s.freeInstance()


# ----------------------------------------------------------------- slow: win64 under wine


def _host_table(stdout: str, tag: str = "OUT") -> np.ndarray:
    """The host's printed rows (steps done 0, 1, ...) as float64 values."""
    rows = {}
    for line in stdout.splitlines():
        parts = line.split()
        if parts and parts[0] == tag:
            rows[int(parts[1])] = [int(x, 16) for x in parts[2:]]
    return np.array([rows[k] for k in sorted(rows)], dtype=np.uint64).view(np.float64)


@pytest.mark.slow
def test_fmi3_win64_dlls_under_wine_match_linux(tmp_path, wine_env):
    """The FMI 3.0 IMUThermal (n_sub = 200, two presets) and StrapdownINS (sub_inputs = 1, fed the linux IMU's
    arrays) from their win64 DLLs under wine through the FMI 3.0 C host (tests/native_host/native_fmu3_host.c)
    against x86_64-linux, bit for bit (the C calls no libm: smath.h)."""
    from fmus.native_fmu import MINGW, fmi_headers_dir

    missing = [t for t in (MINGW, "wine") if shutil.which(t) is None]
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed (Debian: apt-get install gcc-mingw-w64-x86-64 wine64)")
    cc = shutil.which("gcc") or shutil.which("cc")
    src = str(Path(__file__).resolve().parent / "native_host" / "native_fmu3_host.c")
    flags = ["-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{fmi_headers_dir(3)}"]
    build_line([cc, *flags, src, "-ldl", "-o", str(tmp_path / "host")])
    build_line([MINGW, *flags, src, "-static", "-o", str(tmp_path / "host.exe")])
    env = wine_env
    fmus = {}
    for name, slave in (("IMUThermal", "imu_thermal_slave.py"), ("StrapdownINS", "strapdown_ins_slave.py")):
        fmu = build_native_fmu(name, slave, tmp_path, fmi=3, win64=True)
        folder = tmp_path / name
        with zipfile.ZipFile(fmu) as z:
            z.extractall(folder)
        fmus[name] = (read_model_description(str(fmu)), folder)

    def run(name, steps, *args):
        md, folder = fmus[name]
        out = {}
        for system, host, binary, prefix in (
                ("linux", tmp_path / "host", folder / "binaries" / "x86_64-linux" / f"{name}.so", []),
                ("win64", tmp_path / "host.exe", folder / "binaries" / "x86_64-windows" / f"{name}.dll", ["wine"])):
            proc = subprocess.run([*prefix, str(host), str(binary), md.guid, str(steps), "1.0", *args],
                                  capture_output=True, text=True, timeout=600, env=env)
            assert proc.returncode == 0 and "STATUS" not in proc.stdout, proc.stdout[-2000:] + proc.stderr[-2000:]
            assert proc.stdout.rstrip().endswith("DONE 1")
            out[system] = proc.stdout
        win, lin = _host_table(out["win64"]), _host_table(out["linux"])
        again = _host_table(out["win64"], "AGAIN")
        assert np.array_equal(again, win[-len(again):])  # its own state round trip is exact
        worst = float(np.max(np.abs(win - lin) / np.maximum(np.abs(lin), 1e-300)))
        print(f"{name} {args[:2]}: win64 == linux {np.array_equal(win, lin)}, {int(np.sum(win != lin))} of "
              f"{win.size} values differ, largest relative difference {worst:.3g}")
        return lin, worst

    md, _ = fmus["IMUThermal"]
    vr = {v.name: v.valueReference for v in md.modelVariables}
    imu_out = ["increment_end_time", *SUB]
    steps = 40
    for preset in ("nav-rlg", "mems"):
        lin, worst = run("IMUThermal", steps, f"u{vr['n_sub']}={K}", f"s{vr['preset']}={preset}",
                         f"r{vr['angle_1']}=0.3", f"r{vr['rate_1']}=0.0", "roundtrip=20",
                         "out=" + ",".join(str(vr[n]) for n in imu_out), f"nout={1 + 7 * K}")
        assert worst == 0.0
        if preset == "nav-rlg":
            imu_rows = lin
    md, _ = fmus["StrapdownINS"]
    vr_ins = {v.name: v.valueReference for v in md.modelVariables}
    # Gauss-Seidel: the INS's step k gets the IMU's outputs after its step k + 1 (tag, then the seven arrays)
    rows = tmp_path / "rows.bin"
    np.ascontiguousarray(imu_rows[1:]).tofile(rows)
    ins_out = ["lat", "lon", "v_e", "v_n", "yaw", "pitch", "roll", "nav_time", "temp_azimuth_gyro"]
    lin, worst = run("StrapdownINS", steps, f"u{vr_ins['n_sub']}={K}", f"i{vr_ins['sub_inputs']}=1",
                     f"r{vr_ins['align_time']}=20.0", f"r{vr_ins['coarse_time']}=10.0", "roundtrip=25",
                     "in=" + ",".join(str(vr_ins[n]) for n in imu_out), f"nin={1 + 7 * K}", f"rows={rows}",
                     "out=" + ",".join(str(vr_ins[n]) for n in ins_out), f"nout={len(ins_out)}")
    assert worst == 0.0
    assert lin[-1, ins_out.index("nav_time")] == 20.0  # aligned, then navigated 20 s of 200 sub-intervals each
