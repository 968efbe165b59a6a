"""The native IMUThermal FMU (fmus/c/imu_thermal/model.c over the C core's IMU build and FMU step).

Every output at every step equals the in-process IMU's (sarins_fmu.imu.IMU with the same seed, the
library's face of the same C functions) through FMPy: Jacobi and Gauss-Seidel tags, another start time,
the mems preset with its correlated terms, a static base elsewhere (Earth rate and gravity from the C
core), a cold start with an aged drift model, a moving base, a fixed table (no motion inputs) and one
coefficient set over a preset (it takes effect, the others keep the preset's values).  FMU state: get,
step, set, step again in the C host; serialized in one process and continued in another.  The C host
with an empty environment; no allocation after initialisation; bad parameters and refused steps give
fmi2Error with the reason.  Slow: AddressSanitizer + UBSan through the C host; win64 under wine.  The
generic checks (fmpy validate, exports, no Python symbol) are tests/test_native_fmus.py's, over NATIVE.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException

from fmu_driver import Slave, check_parameter_error
from fmus.cbuild import build_line
from fmus.native_fmu import CFLAGS, MINGW, NATIVE, fmi_headers_dir
from sarins_fmu import imu, imu_params
from sarins_fmu.site import SITE_LAT
from test_native_fmus import COUNTER_SRC, HOST_SRC, STATE_SCRIPT, _cc, bits, ops, run_host, table

HERE = Path(__file__).resolve().parent
OUTPUTS = [f"dtheta_{a}" for a in "xyz"] + [f"dv_{a}" for a in "xyz"] + [
    f"temp_{s}_{a}" for s in ("gyro", "accel") for a in "xyz"] + ["increment_end_time"]
AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}
N = 240


def turning(t):
    """Two gimbals' motion at time t (s) and the ambient: angles, rates, accelerations, ambient, slope."""
    return ([0.01 * t, 0.02 * t + 0.0005 * t * t], [0.01, 0.02 + 0.001 * t], [0.0, 0.001], 20.0 + 0.01 * t, 0.01)


def rolling(t):
    """The vehicle on the moving base at time t: yaw, pitch, roll; their rates; their accelerations; base
    rate (e, n, u) and specific force (e, n, u)."""
    return ([0.1 + 0.001 * t, 0.01, -0.02], [0.001, 0.0, 0.0], [0.0, 0.0, 0.0],
            [0.0, 5.3e-5 + 1e-8 * t, 5.0e-5], [0.001, -0.002, 9.80])


SCENARIOS = {
    "jacobi nav-rlg x,z": dict(params={"gimbals": "x,z", "seed": 7}),
    "gauss-seidel mems from t=5": dict(params={"preset": "mems", "gimbals": "x,z", "seed": 3}, start=5.0,
                                       gauss_seidel=True),
    "static base elsewhere, cold, aged": dict(params={"gimbals": "x,z", "lat": -0.7, "height": 1234.0,
                                                      "base_yaw": 2.1, "thermal_start": "cold",
                                                      "aging_days": 30.0, "seed": 11}),
    "one coefficient set over mems": dict(params={"preset": "mems", "gimbals": "x,z", "seed": 5,
                                                  "gyro_bias_z": 3e-5}),
    "2 s steps at 100 Hz": dict(params={"gimbals": "x,z", "internal_rate": 100.0, "seed": 2}, h=2.0),
    "moving base": dict(params={"gimbals": "x,z", "base": "input", "preset": "mems", "seed": 9}, moving=True),
    "fixed table": dict(params={"seed": 4}, fixed=True),
    "periodic terms over mems": dict(params={"preset": "mems", "gimbals": "x,z", "seed": 6,
                                             "gyro_periodic_amplitude_z": 2e-5, "gyro_periodic_frequency_z": 0.31,
                                             "accel_periodic_amplitude_y": 0.008, "accel_periodic_frequency_y": 0.7}),
}


@pytest.fixture(scope="module")
def imu_fmu(fmu_dir):
    return fmu_dir / "IMUThermal.fmu"


@pytest.fixture(scope="module")
def unzipped(imu_fmu, tmp_path_factory):
    folder = tmp_path_factory.mktemp("native_imu") / "IMUThermal"
    with zipfile.ZipFile(imu_fmu) as z:
        z.extractall(folder)
    return folder, read_model_description(str(imu_fmu))


@pytest.fixture(scope="module")
def host(tmp_path_factory):
    out = tmp_path_factory.mktemp("native_imu_host") / "host"
    build_line([_cc(), "-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{fmi_headers_dir()}",
                    str(HOST_SRC), "-ldl", "-o", str(out)])
    return out


def _motion_inputs(t, n_gimbals):
    angle, rate, accel, amb, slope = turning(t)
    values = {}
    for j in range(n_gimbals):
        values.update({f"angle_{j + 1}": angle[j], f"rate_{j + 1}": rate[j], f"accel_{j + 1}": accel[j]})
    values.update(ambient_temp=amb, ambient_temp_rate=slope)
    return values


def _vehicle_inputs(t):
    angles, rates, accels, base_rate, force = rolling(t)
    values = {}
    for k, a in enumerate(("yaw", "pitch", "roll")):
        values.update({f"vehicle_{a}": angles[k], f"vehicle_{a}_rate": rates[k], f"vehicle_{a}_accel": accels[k]})
    for k, ax in enumerate("enu"):
        values.update({f"base_rate_{ax}": base_rate[k], f"base_force_{ax}": force[k]})
    return values


def fmpy_run(fmu, params, steps, *, start=0.0, h=1.0, gauss_seidel=False, moving=False, fixed=False):
    """Rows of OUTPUTS (bit patterns) after initialisation and after every step, through FMPy."""
    n = len(params.get("gimbals", "z").split(","))
    slave = Slave(fmu, "native_imu")
    try:
        slave.fmu.setupExperiment(startTime=start)
        slave.set(**params)
        slave.fmu.enterInitializationMode()
        if not fixed:
            slave.set(**_motion_inputs(start, n), motion_time=start)
        if moving:
            slave.set(**_vehicle_inputs(start), base_motion_time=start)
        slave.fmu.exitInitializationMode()
        rows = [[bits(x) for x in slave.get(*OUTPUTS)]]
        for k in range(steps):
            t = start + k * h
            tag = t + h if gauss_seidel else t  # Gauss-Seidel: the upstream stepped first
            if not fixed:
                slave.set(**_motion_inputs(tag, n), motion_time=tag)
            if moving:
                slave.set(**_vehicle_inputs(tag), base_motion_time=tag)
            slave.fmu.doStep(t, h)
            rows.append([bits(x) for x in slave.get(*OUTPUTS)])
        return rows
    finally:
        slave.free()


def in_process(params, steps, *, start=0.0, h=1.0, gauss_seidel=False, moving=False, fixed=False):
    """The same rows from the library's IMU, built as the slave's declaration says (preset + the
    coefficients that were set, the static or held base, the thermal start at the start-time ambient)."""
    del gauss_seidel  # the FMU picks the set tagged t either way
    p = {"preset": "nav-rlg", "gimbals": "z", "lat": SITE_LAT, "height": 0.0, "base_yaw": 0.0,
         "internal_rate": 200.0, "seed": 0, "thermal_start": "hot", "aging_days": 0.0, "base": "static", **params}
    names = {name for name, _, _ in imu_params.PARAMETERS}
    model = imu_params.apply_overrides(imu.preset(p["preset"]), {k: v for k, v in params.items() if k in names})
    axes = np.array([AXES[g] for g in p["gimbals"].split(",")])
    n = len(axes)
    if moving:
        base, axes = imu.HeldBase(), np.vstack([imu.VEHICLE_ATTITUDE_AXES, axes])
    else:
        base = imu.StaticBase(p["lat"], 0.0, p["height"], p["base_yaw"])
    sensor = imu.IMU(model, base, axes, output_interval=h, internal_rate=p["internal_rate"], seed=p["seed"],
                     thermal_start=p["thermal_start"], aging_days=p["aging_days"])
    amb0 = 20.0 if fixed else turning(start)[3]
    sensor.reset(ambient0=amb0)
    rows = [[bits(x) for x in (*np.zeros(6), *sensor.temperature, start)]]
    for k in range(steps):
        t = start + k * h
        if fixed:
            angle, rate, accel, amb, slope = [0.0] * n, [0.0] * n, [0.0] * n, 20.0, 0.0
        else:
            angle, rate, accel, amb, slope = (x[:n] if isinstance(x, list) else x for x in turning(t))
        if moving:
            v_angle, v_rate, v_accel, base_rate, force = rolling(t)
            base.hold(base_rate, force)
            angle, rate, accel = v_angle + angle, v_rate + rate, v_accel + accel
        dtheta, dv, temps = sensor.step(np.array([angle]), np.array([rate]), np.array([accel]),
                                        ambient=[amb + slope * h])
        rows.append([bits(x) for x in (*dtheta[0], *dv[0], *temps[0], t + h)])
    return rows


def test_imu_thermal_is_a_native_fmu(imu_fmu):
    assert "IMUThermal" in NATIVE
    md = read_model_description(str(imu_fmu))
    assert md.coSimulation.needsExecutionTool is False and md.coSimulation.canGetAndSetFMUstate
    with zipfile.ZipFile(imu_fmu) as z:
        assert "sources/model.c" in z.namelist() and "sources/imu.c" in z.namelist()
        assert not any(n.startswith("resources/") and n.endswith(".py") for n in z.namelist())


@pytest.mark.parametrize("case", list(SCENARIOS))
def test_native_imu_equals_the_in_process_imu_bit_for_bit(imu_fmu, case):
    kw = dict(SCENARIOS[case])
    params = kw.pop("params")
    native = fmpy_run(imu_fmu, params, N, **kw)
    reference = in_process(params, N, **kw)
    assert native == reference
    assert len({tuple(r[:3]) for r in native[1:]}) > N // 2  # the increments change from step to step


def test_a_set_coefficient_overrides_the_preset_and_the_others_keep_it(imu_fmu):
    """One coefficient set: the run equals the preset with that coefficient replaced (the scenario above),
    and differs from the preset alone only through it: the gyro z bias moves dtheta_z by 3e-5 rad/s * 1 s
    (and x, y, dv by the coning and sculling of that change only); the thermal model is untouched."""
    base = {"preset": "mems", "gimbals": "x,z", "seed": 5}
    plain = np.array(fmpy_run(imu_fmu, base, 40), dtype=np.uint64).view(np.float64)
    bias = imu.preset("mems").gyro.bias[2] + 3e-5
    changed = np.array(fmpy_run(imu_fmu, {**base, "gyro_bias_z": bias}, 40), dtype=np.uint64).view(np.float64)
    assert np.array_equal(plain[:, 6:], changed[:, 6:])  # temperatures, increment_end_time
    assert np.allclose(changed[1:, 2] - plain[1:, 2], 3e-5, rtol=1e-6, atol=0)
    assert np.max(np.abs(changed[1:, [0, 1]] - plain[1:, [0, 1]])) < 1e-8  # coning of the change
    assert np.max(np.abs(changed[1:, 3:6] - plain[1:, 3:6])) < 3e-5 * 9.9  # the force turned by it
    # set to the preset's own value: the same run as not set
    same = fmpy_run(imu_fmu, {**base, "gyro_bias_z": float(imu.preset("mems").gyro.bias[2])}, 40)
    assert np.array_equal(np.array(same, dtype=np.uint64).view(np.float64), plain)


def test_static_base_earth_rate_and_gravity_are_the_libraries(imu_fmu):
    """The FMU's static base (earth.h) against sarins_fmu.imu.StaticBase (sarins_fmu.earth) at
    latitudes, heights and yaws: the runs are bit-identical, so both give the same Earth rate and gravity."""
    for lat, height, yaw in ((0.0, 0.0, 0.0), (1.2, -300.0, -3.0), (-1.5, 8000.0, 0.7)):
        params = {"lat": lat, "height": height, "base_yaw": yaw, "preset": "ideal", "seed": 1}
        assert fmpy_run(imu_fmu, params, 5, fixed=True) == in_process(params, 5, fixed=True)


# ----------------------------------------------------------------- FMU state, C host, allocations

HOST_CASES = {"nav-rlg": {"seed": 7}, "mems x,z": {"preset": "mems", "gimbals": "x,z", "seed": 2},
              "periodic": {"seed": 3, "accel_periodic_amplitude_x": 0.005, "accel_periodic_frequency_x": 0.23}}


@pytest.mark.parametrize("case", list(HOST_CASES))
def test_c_host_with_empty_environment_equals_fmpy(unzipped, host, imu_fmu, case):
    folder, md = unzipped
    values = HOST_CASES[case]
    proc = run_host(host, folder / "binaries" / "linux64" / "IMUThermal.so", md, 300,
                    *ops(md, values, outputs=OUTPUTS), env={})
    assert "STATUS" not in proc.stdout, proc.stdout[-2000:]
    rows = table(proc)
    assert [rows[k] for k in range(301)] == fmpy_run(imu_fmu, values, 300, fixed=True)


@pytest.mark.parametrize("case", list(HOST_CASES))
def test_get_step_set_step_again_is_bit_identical_in_the_c_host(unzipped, host, case):
    folder, md = unzipped
    proc = run_host(host, folder / "binaries" / "linux64" / "IMUThermal.so", md, 600, "roundtrip=250",
                    *ops(md, HOST_CASES[case], outputs=OUTPUTS))
    assert "STATUS" not in proc.stdout, proc.stdout[-2000:]
    first, again = table(proc), table(proc, "AGAIN")
    assert sorted(again) == list(range(251, 601))
    assert all(again[k] == first[k] for k in again)
    assert len({tuple(again[k][:3]) for k in again}) > 300  # the noise moved on between get and set


# STATE_SCRIPT: the save/load child of test_native_fmus (imported above)


def test_state_serialized_in_one_process_continues_identically_in_another(imu_fmu, tmp_path):
    values = {"preset": "mems", "gimbals": "x,z", "seed": 8, "gyro_flicker_z": 2e-6, "accel_periodic_amplitude_z": 4e-3,
              "accel_periodic_frequency_z": 0.37}
    script = STATE_SCRIPT.format(tests=str(HERE), root=str(HERE.parent), fmu=str(imu_fmu), values=values,
                                 outputs=OUTPUTS)

    def run(*args):
        proc = subprocess.run([sys.executable, "-c", script, *map(str, args)], capture_output=True, text=True,
                              timeout=300)
        assert proc.returncode == 0, proc.stderr[-3000:]
        return [line for line in proc.stdout.splitlines() if line.startswith("ROW")]

    blob = tmp_path / "state.bin"
    straight = run("none", blob, 0, 500)
    first = run("save", blob, 0, 300)
    second = run("load", blob, 300, 200)
    assert first + second == straight


def test_state_keeps_which_coefficients_were_set(imu_fmu):
    """A state taken from an instance with a coefficient set, restored into one without: the restored
    instance is rebuilt from the state's parameters and set flags (the override stays in force)."""
    with_set = Slave(imu_fmu, "with")
    plain = Slave(imu_fmu, "plain")
    try:
        with_set.set(preset="mems", gyro_bias_z=1e-4)
        plain.set(preset="mems")
        for s in (with_set, plain):
            s.fmu.enterInitializationMode()
            s.fmu.exitInitializationMode()
        state = with_set.fmu.getFMUstate()
        rows = []
        for k in range(20):
            with_set.fmu.doStep(float(k), 1.0)
            rows.append(with_set.get(*OUTPUTS))
        # another instance takes it serialized (an in-memory state belongs to the instance that issued it)
        plain.fmu.setFMUstate(plain.fmu.deSerializeFMUstate(with_set.fmu.serializeFMUstate(state)))
        again = []
        for k in range(20):
            plain.fmu.doStep(float(k), 1.0)
            again.append(plain.get(*OUTPUTS))
        with_set.fmu.freeFMUstate(state)
        assert np.array_equal(rows, again)
    finally:
        with_set.free()
        plain.free()


def test_no_heap_allocation_after_initialisation(unzipped, tmp_path):
    folder, md = unzipped
    counter = tmp_path / "alloc_counter.so"
    build_line([_cc(), "-O2", "-shared", "-fPIC", "-o", str(counter), str(COUNTER_SRC), "-ldl"])
    host = tmp_path / "host"
    build_line([_cc(), "-std=c11", "-O2", f"-I{fmi_headers_dir()}", str(HOST_SRC), "-ldl", "-o", str(host)])
    proc = run_host(host, folder / "binaries" / "linux64" / "IMUThermal.so", md, 2000, "allocs",
                    *ops(md, HOST_CASES["mems x,z"], outputs=[]),
                    env={"LD_PRELOAD": str(counter), "PATH": os.environ.get("PATH", "")})
    assert "STATUS" not in proc.stdout, proc.stdout[-2000:]
    assert "ALLOCS 0" in proc.stdout.splitlines(), proc.stdout[-2000:]


# ----------------------------------------------------------------- refusals


@pytest.mark.parametrize("params,text", [
    ({"preset": "bogus"}, "unknown IMU preset 'bogus'"),
    ({"gimbals": "x,w"}, "gimbals must list 1 to 3 of x, y, z"),
    ({"thermal_start": "warm"}, "thermal_start must be 'hot' or 'cold'"),
    ({"base": "ship"}, "base must be 'static' or 'input'"),
    ({"self_heating_gyro_x": 600.0}, "parameter self_heating_gyro_x = 600 degC is outside"),
    ({"gyro_random_walk_y": -1.0}, "parameter gyro_random_walk_y"),
    ({"lat": 1.6}, "parameter lat"),
    ({"seed": -1}, "parameter seed = -1"),
    ({"internal_rate": 0.0}, "parameter internal_rate"),
    ({"flicker_tau_min": 5e-324}, "parameter flicker_tau_min = 4.9406564584124654e-324"),
    ({"gyro_bias_x": 1e308}, "parameter gyro_bias_x = 1e+308"),
    ({"gyro_bias_x": 400.0}, "parameter gyro_bias_x = 400 is outside [-314.15926535897933, 314.15926535897933] at "
                              "internal_rate 200 Hz: must be at most pi/2 rad per minor step"),
    ({"gyro_scale_factor_y": 1.5}, "parameter gyro_scale_factor_y = 1.5 is outside"),
    ({"accel_periodic_amplitude_y": -1e-3}, "IMU parameter accel_periodic_amplitude_y must be non-negative"),
    ({"gyro_periodic_amplitude_x": 1e-5}, "IMU parameter gyro_periodic_frequency_x must be positive where"),
    ({"accel_periodic_amplitude_x": 5e-3, "accel_periodic_frequency_x": 100.5},
     "parameter accel_periodic_frequency_x = 100.5 Hz: IMU parameter accel_periodic_frequency_x must be at most "
     "the Nyquist frequency of the minor loop, internal_rate / 2 (internal_rate 200 Hz)"),
])
def test_bad_parameters_are_refused_at_initialisation_with_the_reason(imu_fmu, params, text):
    check_parameter_error(imu_fmu, params, text)


@pytest.mark.parametrize("fault,text", [
    ("tag", "no turntable motion for the step starting at t=0"),
    ("nan", "motion or ambient inputs contain NaN or infinity"),
    ("step", "is not a whole number of minor steps"),
])
def test_refused_steps_are_errors_with_the_reason(imu_fmu, fault, text):
    slave = Slave(imu_fmu, "refused")
    try:
        slave.fmu.enterInitializationMode()
        slave.set(motion_time=5.0 if fault == "tag" else 0.0)
        slave.fmu.exitInitializationMode()
        if fault == "tag":
            slave.set(motion_time=7.0)
        elif fault == "nan":
            slave.set(angle_1=float("nan"), motion_time=0.0)
        with pytest.raises(FMICallException, match="status 3"):
            slave.fmu.doStep(0.0, 0.0123 if fault == "step" else 1.0)
        assert any(text in message for status, _, message in slave.log if status == 3), slave.log
    finally:
        slave.free()


# ----------------------------------------------------------------- slow: sanitizers, wine


@pytest.mark.slow
def test_sanitized_build_runs_clean_through_the_c_host(unzipped, tmp_path):
    """AddressSanitizer + UndefinedBehaviorSanitizer over the glue, model.c and the IMU core: runs with FMU
    state round trips (nav-rlg, mems with its flicker terms) and refused parameters; any report fails."""
    folder, md = unzipped
    sources = folder / "sources"
    san = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-g", "-O1"]
    lib = tmp_path / "IMUThermal_san.so"
    files = sorted(str(p) for p in sources.glob("*.c"))
    build_line([_cc(), *[f for f in CFLAGS if f != "-O2"], *san, "-fPIC", "-shared", f"-I{sources}", *files,
                    "-lm", "-o", str(lib)])
    host = tmp_path / "host_san"
    build_line([_cc(), "-std=c11", *san, f"-I{fmi_headers_dir()}", str(HOST_SRC), "-ldl", "-o", str(host)])
    env = {"ASAN_OPTIONS": "detect_leaks=1", "UBSAN_OPTIONS": "print_stacktrace=1",
           "PATH": os.environ.get("PATH", "")}
    for values in HOST_CASES.values():
        proc = run_host(host, lib, md, 400, "roundtrip=150", *ops(md, values, outputs=OUTPUTS), env=env,
                        timeout=600)
        assert "STATUS" not in proc.stdout and "runtime error" not in proc.stderr, proc.stderr[-3000:]
        assert table(proc, "AGAIN")
    for bad in ({"preset": "bogus"}, {"gimbals": ""}, {"lat": float("nan")}, {"gyro_bias_corr_time_x": 0.0}):
        proc = run_host(host, lib, md, 10, *ops(md, bad, outputs=[]), env=env, timeout=600)
        assert "STATUS fmi2ExitInitializationMode 3" in proc.stdout and "ERROR" not in proc.stderr, proc.stderr


@pytest.mark.slow
def test_win64_dll_under_wine_matches_linux64(unzipped, host, tmp_path, wine_env):
    """The shipped win64 DLL under wine against linux64: the increments and temperatures, and the FMU
    state round trip, bit for bit (the C calls no libm: smath.h)."""
    missing = [t for t in (MINGW, "wine") if shutil.which(t) is None]
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed (Debian: apt-get install gcc-mingw-w64-x86-64 wine64)")
    folder, md = unzipped
    dll = folder / "binaries" / "win64" / "IMUThermal.dll"
    assert dll.is_file(), "the build had mingw but shipped no win64 DLL"
    exe = tmp_path / "host.exe"
    build_line([MINGW, "-std=c11", "-O2", f"-I{fmi_headers_dir()}", str(HOST_SRC), "-static", "-o", str(exe)])
    env = wine_env
    for values in HOST_CASES.values():
        args = ("roundtrip=200", *ops(md, values, outputs=OUTPUTS))
        win = run_host(exe, dll, md, 500, *args, env=env, prefix=["wine"], timeout=600)
        lin = run_host(host, folder / "binaries" / "linux64" / "IMUThermal.so", md, 500, *args)
        assert "STATUS" not in win.stdout, win.stdout[-2000:]
        assert win.stdout.rstrip().endswith("DONE 1")
        w, l_ = table(win), table(lin)
        assert table(win, "AGAIN") == {k: w[k] for k in table(win, "AGAIN")}  # its own round trip is exact
        a = np.array([w[k] for k in sorted(w)], dtype=np.uint64).view(np.float64)
        b = np.array([l_[k] for k in sorted(l_)], dtype=np.uint64).view(np.float64)
        scale = np.maximum(np.abs(b), 1e-300)
        worst = float(np.max(np.abs(a - b) / scale))
        print(f"win64 vs linux64 ({values}): identical={np.array_equal(a, b)}, largest relative difference "
              f"{worst:.3g}")
        assert np.array_equal(a.view(np.uint64), b.view(np.uint64)), worst


# slow: the default run runs the documented line on the Turntable's and DriftModelUpdater's sources and compiles
# these with another line (tests/test_portable_fmus.py, the same numbers asserted)
@pytest.mark.slow
def test_sources_compiled_with_the_documented_line_give_the_shipped_outputs(unzipped, host, tmp_path):
    """sources/ built with nothing but documentation/index.html's compile line runs the mems case like the
    shipped linux64 binary, bit for bit (issue 19 item 2)."""
    from fmus.native_fmu import compile_line

    folder, md = unzipped
    sources = tmp_path / "sources"
    shutil.copytree(folder / "sources", sources)
    cmd = [_cc() if a == "cc" else a for a in compile_line("IMUThermal")]
    subprocess.run(" ".join(cmd), shell=True, cwd=sources, check=True)
    values = HOST_CASES["mems x,z"]
    mine = run_host(host, sources / "IMUThermal.so", md, 200, *ops(md, values, outputs=OUTPUTS))
    shipped = run_host(host, folder / "binaries" / "linux64" / "IMUThermal.so", md, 200,
                       *ops(md, values, outputs=OUTPUTS))
    assert table(mine) == table(shipped) and len(table(mine)) == 201
    assert len({tuple(row) for row in table(mine).values()}) > 100  # the increments move
