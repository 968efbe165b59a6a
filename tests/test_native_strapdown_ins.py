"""The native StrapdownINS FMU (fmus/c/strapdown_ins/model.c over the C core's sarins_ins_fmu).

Every output at every step equals the in-process slave's (the library's Python face of the same C
struct) through FMPy, for the paths of the step: coarse and fine alignment and navigation under
Gauss-Seidel and Jacobi tags, another step size, a start from a given attitude, a temperature-model
compensation changing every step (queued) and one repeated with a later apply_from; FMU state
get/set and serialisation across processes repeat a run bit for bit; bad parameters and refused steps
give fmi2Error with the reason logged.  The generic checks (fmpy validate, no Python symbol, the C host,
sanitizers, allocations) are tests/test_native_fmus.py's, over every native FMU.
"""

from __future__ import annotations

import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from fmu_driver import Slave, check_parameter_error
from fmus.cbuild import build_line
from fmus.strapdown_ins_slave import StrapdownINS
from sarins_fmu.core import ins as core_ins

N = 1200
OUTPUTS = list(core_ins.FMU_OUTPUTS)
CORRECTION = ["axial_drift_correction", "axial_drift_correction_b", "axial_drift_correction_a",
              "axial_drift_apply_from"]
ALIGN = {"align_time": 900.0, "coarse_time": 300.0, "lat0": 0.6, "lon0": 0.2, "height0": 30.0}


def _increments():
    rng = np.random.default_rng(11)
    dtheta = 1e-6 * rng.standard_normal((N, 3)) + np.array([0.0, 5e-5, 5.5e-5])
    dv = 1e-4 * rng.standard_normal((N, 3)) + np.array([0.01, 0.02, 9.79])
    return dtheta, dv


def _changing(i):
    """A sender changing its temperature model every 7 steps, 3 steps ahead (pairs queue up)."""
    if i < 950:
        return None
    return (1e-7 * (1 + (i // 7) % 5), 2e-9 * ((i // 50) % 3), 1e-11, (i + 3.0) - 900.0)


def _repeating(i):
    """A sender repeating one value with apply_from two steps ahead, every step (nothing queued)."""
    return (2e-7, 0.0, 0.0, max(0.0, i - 900.0 + 2.0))


SCENARIOS = {
    "gauss-seidel": dict(params=ALIGN),
    "jacobi from t=5": dict(params=ALIGN, start=5.0, jacobi=True),
    "step 2 s": dict(params=ALIGN, h=2.0),
    "given attitude": dict(params={"align_time": 0.0, "yaw0": 0.3, "pitch0": 0.01, "roll0": -0.02, "lat0": -0.3}),
    "queued model": dict(params=ALIGN, comp=_changing),
    "repeated model": dict(params=ALIGN, comp=_repeating),
}


class _InProcess:
    """The slave class run in this process (its step is the C core's, through ctypes)."""

    def __init__(self, params, start):
        self.s = StrapdownINS(instance_name="ins", resources="/tmp")
        for k, v in params.items():
            setattr(self.s, k, v)
        self.s.setup_experiment(start)

    def set(self, **values):
        for k, v in values.items():
            setattr(self.s, k, v)

    def init(self):
        self.s.enter_initialization_mode()
        self.s.exit_initialization_mode()

    def step(self, t, h):
        assert self.s.do_step(t, h)

    def row(self):
        return [float(getattr(self.s, n)) for n in OUTPUTS] + [float(self.s.phase)]


class _Native:
    def __init__(self, fmu, params, start):
        self.slave = Slave(fmu, "ins")
        self.slave.fmu.setupExperiment(startTime=start)
        self.slave.set(**params)

    def set(self, **values):
        self.slave.set(**values)

    def init(self):
        self.slave.fmu.enterInitializationMode()
        self.slave.fmu.exitInitializationMode()

    def step(self, t, h):
        self.slave.fmu.doStep(t, h)

    def row(self):
        return self.slave.get(*OUTPUTS) + [float(self.slave.fmu.getInteger([self.slave.vr["phase"]])[0])]


def _inputs(i, start, h, jacobi, comp):
    """The inputs before doStep number i (the increments of interval j, tagged with its end)."""
    dtheta, dv = _increments()
    j = i - 1 if jacobi else i
    values = {}
    if j >= 0:
        values.update({f"dtheta_{a}": dtheta[j, k] * h for k, a in enumerate("xyz")})
        values.update({f"dv_{a}": dv[j, k] * h for k, a in enumerate("xyz")})
        values.update(increment_end_time=start + (j + 1) * h, temp_gyro_z=21.0 + 0.001 * j)
    else:
        values["increment_end_time"] = start
    if comp is not None and comp(i) is not None:
        values.update(zip(CORRECTION, comp(i)))
    return values


def _run(runner, steps, start=0.0, h=1.0, jacobi=False, comp=None, first=0):
    rows = []
    for i in range(first, first + steps):
        runner.set(**_inputs(i, start, h, jacobi, comp))
        runner.step(start + i * h, h)
        rows.append(runner.row())
    return np.array(rows)


def _scenario(make, name):
    sc = SCENARIOS[name]
    start, h, jacobi = sc.get("start", 0.0), sc.get("h", 1.0), sc.get("jacobi", False)
    runner = make(sc["params"], start)
    runner.set(temp_gyro_z=21.0)
    runner.init()
    first = runner.row()
    rows = _run(runner, N, start, h, jacobi, sc.get("comp"))
    return np.vstack([first, rows])


@pytest.mark.parametrize("name", list(SCENARIOS))
def test_native_ins_equals_the_in_process_slave_bit_for_bit(fmu_dir, name):
    native = _scenario(lambda p, s: _Native(fmu_dir / "StrapdownINS.fmu", p, s), name)
    python = _scenario(_InProcess, name)
    assert np.array_equal(native, python)
    assert np.isfinite(native).all()
    assert native[-1, -1] == 2  # navigating at the end


def _native_at(fmu_dir, steps, comp=_changing):
    runner = _Native(fmu_dir / "StrapdownINS.fmu", ALIGN, 0.0)
    runner.set(temp_gyro_z=21.0)
    runner.init()
    _run(runner, steps, comp=comp)
    return runner


def test_get_step_set_step_again_is_bit_identical(fmu_dir):
    """A state taken in the fine alignment, 300 steps on (the end of the alignment, queued models taking
    over), restored: the same 300 rows again."""
    runner = _native_at(fmu_dir, 700)
    fmu = runner.slave.fmu
    state = fmu.getFMUstate()
    first = _run(runner, 300, comp=_changing, first=700)
    fmu.setFMUstate(state)
    again = _run(runner, 300, comp=_changing, first=700)
    fmu.freeFMUstate(state)
    assert np.array_equal(first, again)
    assert first[0, -1] == 1 and first[-1, -1] == 2
    runner.slave.free()


CONTINUE = """
import sys
import zipfile
import numpy as np
sys.path.insert(0, {tests!r})
import test_native_strapdown_ins as t
from fmu_driver import Slave
from pathlib import Path
runner = t._Native(Path({fmu!r}), t.ALIGN, 0.0)
runner.init()
fmu = runner.slave.fmu
fmu.setFMUstate(fmu.deSerializeFMUstate(Path({blob!r}).read_bytes()))
np.save({out!r}, t._run(runner, 300, comp=t._changing, first=700))
"""


def test_state_serialized_here_continues_identically_in_another_process(fmu_dir, tmp_path):
    runner = _native_at(fmu_dir, 700)
    fmu = runner.slave.fmu
    state = fmu.getFMUstate()
    (tmp_path / "state.bin").write_bytes(bytes(fmu.serializeFMUstate(state)))
    fmu.freeFMUstate(state)
    here = _run(runner, 300, comp=_changing, first=700)
    runner.slave.free()
    script = CONTINUE.format(tests=str(Path(__file__).parent), fmu=str(fmu_dir / "StrapdownINS.fmu"),
                             blob=str(tmp_path / "state.bin"), out=str(tmp_path / "there.npy"))
    subprocess.run([sys.executable, "-c", script], check=True, timeout=300)
    assert np.array_equal(np.load(tmp_path / "there.npy"), here)


@pytest.mark.parametrize("params, text", [
    ({"lat0": 1.6}, "lat0"),
    ({"kf_arw": 0.0}, "kf_arw"),
    ({"pitch0": 2.0}, "pitch0"),
    ({"align_time": float("nan")}, "align_time"),
    ({"coarse_time": -1.0}, "coarse_time"),
    ({"align_time": 100.0, "coarse_time": 300.0}, "align_time must exceed coarse_time"),
])
def test_bad_parameters_are_refused_at_exit_initialization_with_the_reason(fmu_dir, params, text):
    check_parameter_error(fmu_dir / "StrapdownINS.fmu", params, text)


@pytest.mark.parametrize("fault, text", [
    ({"increment_end_time": 720.0}, "would skip an interval"),
    ({"increment_end_time": 700.0}, "were already integrated"),
    ({"dv_y": float("nan")}, "NaN or infinity"),
    ({"axial_drift_correction": 1e-6, "axial_drift_apply_from": -300.0}, "arrived when the INS integrates"),
])
def test_refused_steps_are_errors_with_the_reason_logged(fmu_dir, fault, text):
    runner = _native_at(fmu_dir, 700, comp=None)
    runner.set(**{**_inputs(700, 0.0, 1.0, False, None), **fault})
    with pytest.raises(FMICallException, match="status 3"):
        runner.slave.fmu.doStep(700.0, 1.0)
    assert any(text in message for status, _, message in runner.slave.log if status == 3), runner.slave.log[-3:]
    runner.slave.free()


# ----------------------------------------------------------------- the C host, no Python reachable


@pytest.fixture(scope="module")
def host(tmp_path_factory):
    from fmus.native_fmu import fmi_headers_dir
    from test_native_fmus import HOST_SRC, _cc

    out = tmp_path_factory.mktemp("ins_host") / "host"
    build_line([_cc(), "-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{fmi_headers_dir()}",
                    str(HOST_SRC), "-ldl", "-o", str(out)])
    return out


def _input_rows(name) -> np.ndarray:
    """The scenario's inputs before every step, in FMU_INPUTS order (the values held between steps)."""
    sc = SCENARIOS[name]
    current = {n: 0.0 for n in core_ins.FMU_INPUTS}
    current["temp_gyro_z"] = 21.0
    rows = []
    for i in range(N):
        current.update(_inputs(i, sc.get("start", 0.0), sc.get("h", 1.0), sc.get("jacobi", False), sc.get("comp")))
        rows.append([current[n] for n in core_ins.FMU_INPUTS])
    return np.array(rows)


def _host_run(host, fmu, tmp_path, *extra, binary=None, env=None, params=None, timeout=300, prefix=()):
    """The queued temperature-model run of the native INS in the C host (inputs set before every step)."""
    from fmpy import read_model_description
    from test_native_fmus import run_host

    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    folder = tmp_path / "ins"
    zipfile.ZipFile(fmu).extractall(folder)
    _input_rows("queued model").astype("=f8").tofile(tmp_path / "rows.bin")
    values = {**ALIGN, "temp_gyro_z": 21.0, **(params or {})}
    return run_host(host, binary or folder / "binaries" / "linux64" / "StrapdownINS.so", md, N,
                    *[f"r{vr[k]}={v!r}" for k, v in values.items()],
                    "in=" + ",".join(str(vr[n]) for n in core_ins.FMU_INPUTS), f"rows={tmp_path / 'rows.bin'}",
                    "out=" + ",".join(str(vr[n]) for n in OUTPUTS), *extra, env={} if env is None else env,
                    timeout=timeout, prefix=prefix)


def test_c_host_with_empty_environment_equals_fmpy_and_repeats_after_set_state(fmu_dir, host, tmp_path):
    """The native INS in the C host (env -i: no Python anywhere), the queued temperature-model run with
    inputs set before every step: every Real output equals FMPy's bit for bit; fmi2GetFMUstate in the
    fine alignment, the rest of the run, fmi2SetFMUstate and the rest again: the same bits."""
    from test_native_fmus import bits, table

    fmu = fmu_dir / "StrapdownINS.fmu"
    proc = _host_run(host, fmu, tmp_path, "roundtrip=700")
    assert "STATUS" not in proc.stdout, proc.stdout[-2000:]
    out, again = table(proc), table(proc, "AGAIN")
    expected = _scenario(lambda p, s: _Native(fmu, p, s), "queued model")
    assert [out[k] for k in range(N + 1)] == [[bits(x) for x in row[:-1]] for row in expected]
    assert len(again) == N - 700 and all(again[k] == out[k] for k in again)


def test_no_heap_allocation_after_initialisation(fmu_dir, host, tmp_path):
    """The whole run (alignment, navigation, queued models) allocates nothing after fmi2ExitInitializationMode
    (an LD_PRELOAD counter in the C host)."""
    import os

    from test_native_fmus import COUNTER_SRC, _cc

    counter = tmp_path / "alloc_counter.so"
    build_line([_cc(), "-O2", "-shared", "-fPIC", "-o", str(counter), str(COUNTER_SRC), "-ldl"])
    proc = _host_run(host, fmu_dir / "StrapdownINS.fmu", tmp_path, "allocs",
                     env={"LD_PRELOAD": str(counter), "PATH": os.environ.get("PATH", "")})
    assert "STATUS" not in proc.stdout, proc.stdout[-2000:]
    assert "ALLOCS 0" in proc.stdout.splitlines(), proc.stdout[-2000:]


@pytest.mark.slow
def test_sanitized_build_runs_clean_through_the_c_host(fmu_dir, tmp_path):
    """sources/ built with AddressSanitizer + UndefinedBehaviorSanitizer: the queued run with an FMU state round
    trip, and a bad parameter; any report fails the run."""
    import os

    from fmus.native_fmu import CFLAGS, fmi_headers_dir
    from test_native_fmus import HOST_SRC, _cc

    fmu = fmu_dir / "StrapdownINS.fmu"
    sources = tmp_path / "src"
    zipfile.ZipFile(fmu).extractall(sources)
    sources = sources / "sources"
    san = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-g", "-O1"]
    lib = tmp_path / "StrapdownINS_san.so"
    build_line([_cc(), *[f for f in CFLAGS if f != "-O2"], *san, "-fPIC", "-shared", f"-I{sources}",
                    *sorted(str(p) for p in sources.glob("*.c")), "-lm", "-o", str(lib)])
    host = tmp_path / "host_san"
    build_line([_cc(), "-std=c11", *san, f"-I{fmi_headers_dir()}", str(HOST_SRC), "-ldl", "-o", str(host)])
    env = {"ASAN_OPTIONS": "detect_leaks=1", "UBSAN_OPTIONS": "print_stacktrace=1", "PATH": os.environ.get("PATH", "")}
    proc = _host_run(host, fmu, tmp_path, "roundtrip=700", binary=lib, env=env, timeout=600)
    assert "STATUS" not in proc.stdout and "runtime error" not in proc.stderr, proc.stderr[-3000:]
    from test_native_fmus import table

    assert len(table(proc, "AGAIN")) == N - 700
    proc = _host_run(host, fmu, tmp_path, binary=lib, env=env, params={"kf_vrw": -1.0}, timeout=600)
    assert "STATUS fmi2ExitInitializationMode 3" in proc.stdout and "ERROR" not in proc.stderr, proc.stderr


@pytest.mark.slow
def test_win64_dll_under_wine_runs_and_repeats_after_set_state(fmu_dir, host, tmp_path, wine_env):
    """The shipped win64 DLL, loaded by a mingw-built host under wine, runs the queued run with its FMU state
    round trip bit for bit, and gives the linux64 outputs bit for bit (the C calls no libm: smath.h)."""
    import shutil
    import struct

    from fmus.native_fmu import MINGW, fmi_headers_dir
    from test_native_fmus import HOST_SRC, table

    missing = [t for t in (MINGW, "wine") if shutil.which(t) is None]
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed (Debian: apt-get install gcc-mingw-w64-x86-64 wine64)")
    fmu = fmu_dir / "StrapdownINS.fmu"
    exe = tmp_path / "host.exe"
    build_line([MINGW, "-std=c11", "-O2", f"-I{fmi_headers_dir()}", str(HOST_SRC), "-static", "-o", str(exe)])
    env = wine_env
    lin = _host_run(host, fmu, tmp_path, "roundtrip=700")
    dll = tmp_path / "ins" / "binaries" / "win64" / "StrapdownINS.dll"
    assert dll.is_file(), "the build had mingw but shipped no win64 DLL"
    win = _host_run(exe, fmu, tmp_path, "roundtrip=700", binary=dll, env=env, timeout=600, prefix=["wine"])
    assert "STATUS" not in win.stdout and win.stdout.rstrip().endswith("DONE 1"), win.stdout[-2000:]
    again = table(win, "AGAIN")
    assert len(again) == N - 700 and all(again[k] == table(win)[k] for k in again)

    def values(rows):
        return np.array([[struct.unpack("<d", struct.pack("<Q", x))[0] for x in rows[k]] for k in sorted(rows)])

    assert table(win) == table(lin), np.max(np.abs(values(table(win)) - values(table(lin))))


# slow: the default run runs the documented line on the Turntable's and DriftModelUpdater's sources and compiles
# these with another line (tests/test_portable_fmus.py, the same numbers asserted)
@pytest.mark.slow
def test_sources_compiled_with_the_documented_line_give_the_shipped_outputs(fmu_dir, host, tmp_path):
    """sources/ built with nothing but documentation/index.html's compile line runs the queued
    temperature-model run like the shipped linux64 binary, bit for bit (issue 19 item 2)."""
    import shutil

    from fmus.native_fmu import compile_line
    from test_native_fmus import _cc, table

    fmu = fmu_dir / "StrapdownINS.fmu"
    unpacked = tmp_path / "unpacked"
    zipfile.ZipFile(fmu).extractall(unpacked)
    sources = tmp_path / "sources"
    shutil.copytree(unpacked / "sources", sources)
    cmd = [_cc() if a == "cc" else a for a in compile_line("StrapdownINS")]
    subprocess.run(" ".join(cmd), shell=True, cwd=sources, check=True)
    mine = table(_host_run(host, fmu, tmp_path, binary=sources / "StrapdownINS.so"))
    shipped = table(_host_run(host, fmu, tmp_path))
    assert mine == shipped and len(mine) == N + 1
