"""The native IMULog FMU (fmus/c/imu_log/model.c): the project's CSV log format 1 played as increments.

Every output after initialisation and after each step equals the in-process reader's (sarins_fmu.imu_log.read_log)
bit for bit, through FMPy, through the C host with an empty environment and through the FMI 3.0 variant, for a
log of 17-digit numbers (strtod) and one of short numbers with rates (the core's block parser); an FMU state
taken mid-log repeats the run, in the same instance and deserialized into another; other formats and bad logs
are refused at fmi2ExitInitializationMode naming the reason or the conversion; nothing allocates after
initialisation.
"""

from __future__ import annotations

import gzip
import os
import struct
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException

from fmu_driver import Slave, check_parameter_error
from fmus.cbuild import build_line
from fmus.native_fmu import build_native_fmu
from sarins_fmu.imu_log import read_log, write_log

H = 0.01  # s, the logs' interval
K = 300  # samples
OUT = ["dtheta_x", "dtheta_y", "dtheta_z", "dv_x", "dv_y", "dv_z", "temp_gyro_x", "temp_gyro_y", "temp_gyro_z",
       "temp_accel_x", "temp_accel_y", "temp_accel_z", "log_time", "increment_end_time", "log_step", "lat_deg",
       "lon_deg", "height_m"]


@pytest.fixture(scope="module")
def fmu(tmp_path_factory):
    return build_native_fmu("IMULog", "imu_log_slave.py", tmp_path_factory.mktemp("il"))


def _samples(seed=5):
    rng = np.random.default_rng(seed)
    time = (np.arange(K) + 1) * H
    dtheta = rng.normal(0.0, 1e-5, (K, 3))
    dv = rng.normal(0.0, 1e-3, (K, 3)) + np.array([0.0, 0.0, 9.79 * H])
    temps = 20.0 + rng.normal(0.0, 0.3, (K, 6))
    return time, dtheta, dv, temps


@pytest.fixture(scope="module")
def long_log(tmp_path_factory):
    """17 significant digits (write_log's %.17g): strtod reads them."""
    time, dtheta, dv, temps = _samples()
    return write_log(tmp_path_factory.mktemp("log") / "long.csv", time, dtheta, dv, temps=temps, lat_deg=28.222,
                     lon_deg=113.1, height_m=52.5)


@pytest.fixture(scope="module")
def rate_log(tmp_path_factory):
    """Short numbers (the core's block parser), rates, CRLF line ends, no temperatures."""
    lines = ["# sarins-imu-log 1", "# lat_deg: -33.5", "# note: bench", "time_s,gyro_x_radps,gyro_y_radps,"
             "gyro_z_radps,accel_x_mps2,accel_y_mps2,accel_z_mps2"]
    rng = np.random.default_rng(3)
    for k in range(K):
        g = rng.integers(-999, 999, 3) / 1e6
        lines.append(f"{(k + 1) * 0.005:.3f},{g[0]},{g[1]},{g[2]},0.0123,-0.045,9.7936")
    path = tmp_path_factory.mktemp("log") / "rates.csv"
    path.write_bytes(("\r\n".join(lines) + "\r\n").encode())
    return path


def _expected(log_file):
    """Rows of OUT after initialisation and after each step, from the in-process reader."""
    log = read_log(log_file)
    h = log.step
    temps = log.temps if log.temps is not None else np.full((len(log.time), 6), 20.0)
    site = [np.degrees(log.lat), np.degrees(log.lon), log.height]
    rows = [[0.0] * 6 + list(temps[0]) + [float(log.time[0] - h), 0.0, h] + site]
    for k in range(len(log.time)):
        rows.append(list(log.dtheta[k]) + list(log.dv[k]) + list(temps[k]) + [log.time[k], (k + 1) * h, h] + site)
    return np.array(rows), h


def _start(fmu, log_file, name="il"):
    slave = Slave(fmu, name)
    slave.set(log_file=str(log_file))
    slave.fmu.enterInitializationMode()
    slave.fmu.exitInitializationMode()
    return slave


@pytest.mark.parametrize("which", ["long_log", "rate_log"])
def test_fmu_equals_the_in_process_reader_bit_for_bit(fmu, which, request):
    log_file = request.getfixturevalue(which)
    want, h = _expected(log_file)
    slave = _start(fmu, log_file)
    try:
        got = [slave.get(*OUT)]
        for k in range(K):
            slave.fmu.doStep(k * h, h)
            got.append(slave.get(*OUT))
        with pytest.raises(FMICallException, match="status 3"):
            slave.fmu.doStep(K * h, h)
        assert any("the log ends" in m for s, _, m in slave.log if s == 3), slave.log[-3:]
    finally:
        slave.free()
    assert np.array_equal(np.array(got), want)


def test_state_round_trip_mid_log_repeats_the_run(fmu, long_log):
    h = H
    slave = _start(fmu, long_log)
    try:
        out = []
        for k in range(K):
            if k == 120:
                state = slave.fmu.getFMUstate()
                blob = slave.fmu.serializeFMUstate(state)
            slave.fmu.doStep(k * h, h)
            out.append(slave.get(*OUT))
        slave.fmu.setFMUstate(state)
        slave.fmu.freeFMUstate(state)
        again = []
        for k in range(120, K):
            slave.fmu.doStep(k * h, h)
            again.append(slave.get(*OUT))
    finally:
        slave.free()
    other = _start(fmu, long_log, "il2")
    try:
        other.fmu.setFMUstate(other.fmu.deSerializeFMUstate(blob))
        there = []
        for k in range(120, K):
            other.fmu.doStep(k * h, h)
            there.append(other.get(*OUT))
    finally:
        other.free()
    assert again == out[120:] and there == out[120:]


@pytest.mark.parametrize("field, at, fmt, value, text", [("next", 0, "<q", 10**9, "FMU state does not fit"),
                                                         ("have_step", 16, "<i", 7, "have_step")])
def test_a_crafted_state_is_refused_not_run(fmu, long_log, field, at, fmt, value, text):
    """A serialized state whose sample index is beyond the log, or whose have_step is not 0/1 (the glue's
    checksum recomputed): refused with fmi2Error naming it (the index at the next doStep, where the log's length
    is known; have_step when the state is set), never an out-of-bounds read."""
    from test_native_drift_model_updater import _fnv1a

    slave = _start(fmu, long_log, "crafted")
    try:
        for k in range(30):
            slave.fmu.doStep(k * H, H)
        blob = bytearray(slave.fmu.serializeFMUstate(slave.fmu.getFMUstate()))
        pattern = struct.pack("<qdi", 30, H, 1)
        assert blob.count(pattern) == 1
        struct.pack_into(fmt, blob, blob.index(pattern) + at, value)
        head = next(h for h in range(40, 400) if struct.unpack_from("<Q", blob, h - 16)[0] == len(blob) - h)
        struct.pack_into("<Q", blob, head - 8, _fnv1a(bytes(blob[head:])))
        with pytest.raises(FMICallException, match="status 3"):
            slave.fmu.setFMUstate(slave.fmu.deSerializeFMUstate(bytes(blob)))
            slave.fmu.doStep(30 * H, H)
        assert any(text in m for s, _, m in slave.log if s == 3), slave.log[-3:]
    finally:
        slave.free()


def _text(path, text):
    path.write_text(text)
    return path


GOOD_HEAD = "# sarins-imu-log 1\n# lat_deg: 10\ntime_s,dtheta_x_rad,dtheta_y_rad,dtheta_z_rad,dv_x_mps,dv_y_mps,dv_z_mps\n"


def test_other_formats_and_bad_logs_are_refused_naming_why(fmu, long_log, tmp_path):
    time, dtheta, dv, temps = _samples()
    npz = write_log(tmp_path / "log.npz", time, dtheta, dv, lat_deg=10.0)
    gz = tmp_path / "log.csv.gz"
    gz.write_bytes(gzip.compress(Path(long_log).read_bytes()))
    cases = {
        "": "log_file is empty",
        str(tmp_path / "none.csv"): "no such log file",
        str(npz): "an NPZ log",
        str(gz): "a gzip file",
        str(_text(tmp_path / "i2nav.txt", "1.0 0 0 0 0 0 0.098\n")): "i2Nav",
        str(_text(tmp_path / "vendor.csv", "time,gx,gy\n")): "vendor CSV",
        str(_text(tmp_path / "cols.csv", "# sarins-imu-log 1\n# lat_deg: 10\ntime_s,dtheta_x_rad\n1,0\n")):
            "needs the columns",
        str(_text(tmp_path / "nolat.csv", "# sarins-imu-log 1\n" + GOOD_HEAD.split("\n", 2)[2] + "0.01,0,0,0,0,0,0.098\n"
                  "0.02,0,0,0,0,0,0.098\n")): "lat_deg (static start latitude, deg) is required",
        str(_text(tmp_path / "gap.csv", GOOD_HEAD + "0.01,0,0,0,0,0,0.098\n0.02,0,0,0,0,0,0.098\n"
                  "0.04,0,0,0,0,0,0.098\n")): "line 6: time step 0.02 s differs",
        str(_text(tmp_path / "nan.csv", GOOD_HEAD + "0.01,0,0,0,0,0,0.098\n0.02,0,nan,0,0,0,0.098\n")):
            "line 5: column 3 is NaN",
        str(_text(tmp_path / "word.csv", GOOD_HEAD + "0.01,0,0,0,0,0,0.098\n0.02,0,0x1p3,0,0,0,0.098\n")):
            "line 5: column 3: '0x1p3' is not a number",
        str(_text(tmp_path / "g.csv", GOOD_HEAD + "0.01,0,0,0,0,0,0.01\n0.02,0,0,0,0,0,0.01\n")):
            "is not gravity",
        str(_text(tmp_path / "dup.csv", "# sarins-imu-log 1\n# lat_deg: 10\n# lat_deg: 11\n")): "given twice",
        str(_text(tmp_path / "deg.csv", "# sarins-imu-log 1\n# lat_deg: 10\ntime_s,gyro_x_dps\n")): "SI units",
    }
    for log_file, text in cases.items():
        check_parameter_error(fmu, {"log_file": log_file}, text)


def test_the_python_reader_refuses_the_same_bad_logs(tmp_path):
    """The cases above that both read: the in-process reader refuses them too (same rules)."""
    from sarins_fmu.imu_log import LogError

    for body in ("0.01,0,0,0,0,0,0.098\n0.02,0,0,0,0,0,0.098\n0.04,0,0,0,0,0,0.098\n",
                 "0.01,0,0,0,0,0,0.01\n0.02,0,0,0,0,0,0.01\n"):
        with pytest.raises(LogError):
            read_log(_text(tmp_path / "x.csv", GOOD_HEAD + body))


# ------------------------------------------------------------------------------------- the C hosts
@pytest.fixture(scope="module")
def host(tmp_path_factory):
    from fmus.native_fmu import fmi_headers_dir
    from test_native_fmus import HOST_SRC, _cc

    out = tmp_path_factory.mktemp("il_host") / "host"
    build_line([_cc(), "-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{fmi_headers_dir()}",
                    str(HOST_SRC), "-ldl", "-o", str(out)])
    return out


def test_c_hosts_with_empty_environment_fmi2_and_fmi3_equal_in_process(fmu, host, long_log, tmp_path):
    """The C host started with no environment, FMI 2.0 and the FMI 3.0 variant (fmpy validate clean): every
    output equals the in-process reader's bit for bit; a state round trip repeats the rest; no heap
    allocation after initialisation."""
    from fmpy.validation import validate_fmu

    from fmus.native_fmu import fmi_headers_dir
    from test_native_fmus import COUNTER_SRC, _cc, bits, table

    want, h = _expected(long_log)
    folder = tmp_path / "f2"
    zipfile.ZipFile(fmu).extractall(folder)
    md = read_model_description(str(fmu))

    def args(md):
        vr = {v.name: v.valueReference for v in md.modelVariables}
        return [f"s{vr['log_file']}={long_log}", "out=" + ",".join(str(vr[n]) for n in OUT)]

    counter = tmp_path / "alloc_counter.so"
    build_line([_cc(), "-O2", "-shared", "-fPIC", "-o", str(counter), str(COUNTER_SRC), "-ldl"])
    so = folder / "binaries" / "linux64" / "IMULog.so"
    allocs = subprocess.run([str(host), str(so), md.guid, str(K), repr(h), *args(md), "allocs"],
                            capture_output=True, text=True, timeout=120, env={"LD_PRELOAD": str(counter)})
    assert "ALLOCS 0" in allocs.stdout.splitlines(), allocs.stdout[-2000:]
    two = subprocess.run([str(host), str(so), md.guid, str(K), repr(h), *args(md), "roundtrip=100"],
                         capture_output=True, text=True, timeout=120, env={})
    assert two.returncode == 0 and "STATUS" not in two.stdout, two.stdout[-2000:]
    out, again = table(two), table(two, "AGAIN")
    assert [out[k] for k in range(K + 1)] == [[bits(x) for x in row] for row in want]
    assert len(again) == K - 100 and all(again[k] == out[k] for k in again)
    fmu3 = build_native_fmu("IMULog", "imu_log_slave.py", tmp_path / "fmu3", fmi=3, win64=False)
    assert validate_fmu(str(fmu3)) == []
    folder3 = tmp_path / "f3"
    zipfile.ZipFile(fmu3).extractall(folder3)
    host3 = tmp_path / "host3"
    build_line([_cc(), "-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{fmi_headers_dir(3)}",
                    str(Path(__file__).parent / "native_host" / "native_fmu3_host.c"), "-ldl", "-o", str(host3)])
    md3 = read_model_description(str(fmu3))
    three = subprocess.run([str(host3), str(folder3 / "binaries" / "x86_64-linux" / "IMULog.so"), md3.guid, str(K),
                            repr(h), *args(md3), f"nout={len(OUT)}", "nin=0"],
                           capture_output=True, text=True, timeout=120, env={})
    assert three.returncode == 0 and "STATUS" not in three.stdout, three.stdout[-2000:]
    assert table(three) == {k: out[k] for k in range(K + 1)}


@pytest.mark.slow
def test_sanitized_build_reads_good_and_bad_logs_clean(fmu, long_log, rate_log, tmp_path):
    """AddressSanitizer + UndefinedBehaviorSanitizer over the glue and the model: both logs played with a state
    round trip, and every refused log of the refusal test read; any report fails the run."""
    from fmus.native_fmu import CFLAGS, fmi_headers_dir
    from test_native_fmus import HOST_SRC, _cc

    folder = tmp_path / "unzipped"
    zipfile.ZipFile(fmu).extractall(folder)
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    sources = folder / "sources"
    san = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-g", "-O1"]
    lib = tmp_path / "IMULog_san.so"
    build_line([_cc(), *[f for f in CFLAGS if f != "-O2"], *san, "-fPIC", "-shared", f"-I{sources}",
                    *sorted(str(p) for p in sources.glob("*.c")), "-o", str(lib)])
    host = tmp_path / "host_san"
    build_line([_cc(), "-std=c11", *san, f"-I{fmi_headers_dir()}", str(HOST_SRC), "-ldl", "-o", str(host)])
    env = {"ASAN_OPTIONS": "detect_leaks=1", "UBSAN_OPTIONS": "print_stacktrace=1", "PATH": os.environ.get("PATH", "")}

    def run(log, steps, h, *more):
        return subprocess.run([str(host), str(lib), md.guid, str(steps), repr(h), f"s{vr['log_file']}={log}",
                               f"out={vr['dtheta_x']},{vr['log_time']}", *more], capture_output=True, text=True,
                              timeout=600, env=env)

    for log, h in ((long_log, H), (rate_log, 0.005)):
        proc = run(log, K, h, "roundtrip=150")
        assert proc.returncode == 0 and "STATUS" not in proc.stdout, proc.stdout[-2000:] + proc.stderr[-3000:]
    bad = [GOOD_HEAD + "0.01,0,0,0,0,0,0.098\n0.02,0,nan,0,0,0,0.098\n", GOOD_HEAD + "0.01,0,0x1p3,0,0,0,0.098\n",
           GOOD_HEAD + "0.01,0,0,0,0,0,0.098\r\n0.02,0,0,0,0,0,0.098\n", GOOD_HEAD + "0.01," + "9" * 5000 + "\n",
           "# sarins-imu-log 1\n" + "# k: v\n" * 70, "# sarins-imu-log 1\n# lat_deg: 1\ntime_s," + "x," * 80 + "\n",
           GOOD_HEAD, "", "\x1f\x8b"]
    for j, text in enumerate(bad):
        log = _text(tmp_path / f"bad{j}.csv", text)
        proc = run(log, 5, H)
        assert proc.returncode == 0 and "STATUS fmi2ExitInitializationMode 3" in proc.stdout, proc.stdout[-2000:]
        assert "ERROR" not in proc.stderr and "runtime error" not in proc.stderr, proc.stderr[-3000:]
