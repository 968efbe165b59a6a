"""The native DriftModelUpdater FMU (fmus/c/drift_model_updater/model.c over the C core's online.h).

Every output at every step equals the library's OnlineDriftUpdater fed the same rows (bit for bit)
through FMPy, for the paths of the contract: untagged rows, rows tagged solution_time with tagged speeds
(Gauss-Seidel, and Jacobi's lags), a 2 s step (the first step rebuilds the filter), a model file; the C
host with an empty environment and the FMI 3.0 variant give the same bits; an FMU state taken mid-stop
repeats the run, in the same instance and deserialized into another; a crafted state is refused with a
reason; bad parameters and model files are refused at fmi2ExitInitializationMode naming them; nothing
allocates after initialisation.  The generic checks of every native FMU (validate, no Python symbol,
exports) are tests/test_native_fmus.py's.
"""

from __future__ import annotations

import math
import os
import struct
import subprocess
import zipfile

import numpy as np
import pytest

from fmus.cbuild import build_line
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException

from fmu_driver import Slave, check_parameter_error
from sarins_fmu.identify import netfile
from sarins_fmu.identify.online import OnlineDriftUpdater, UpdaterSettings, prior_covariance
from sarins_fmu.identify.rls import ForgettingRLS, RLSSettings
from sarins_fmu.kalman import StopFilterSettings
from sarins_fmu.units import DAY, DPH_TO_RPS

NO_TAG = -1.0e9
N = 900
PARAMS = {"a0": 1e-6 * DPH_TO_RPS, "b0": -4e-5 * DPH_TO_RPS, "c0": 0.0025 * DPH_TO_RPS, "start_day": 12.0,
          "time_threshold": 120.0, "latency": 3.0, "kf_arw": 2e-6, "forgetting_factor": 0.7}
ROW_INPUTS = ["v_e", "v_n", "yaw", "pitch", "roll", "lat", "temp_gyro_z", "nav_time", "vehicle_speed"]
INPUTS = ROW_INPUTS + ["solution_time", "speed_time"]
REAL_OUT = ["drift_a", "drift_b", "drift_c", "compensation_drift", "apply_from", "stop_timer", "drift_estimate",
            "drift_estimate_std", "last_update_drift", "last_update_temp", "row_time", "p_aa", "p_ab", "p_ac",
            "p_bb", "p_bc", "p_cc", "model_time", "last_stop_time", "last_stop_duration", "last_stop_temp",
            "last_stop_drift", "last_stop_drift_std"]
INT_OUT = ["stopped", "n_updates", "n_resets", "last_stop_used"]


def _rows(n=N, seed=4):
    """INS rows (K, 9) in ROW_INPUTS order at nav times 1 .. n: drives and stops of 20 .. 300 s (several
    longer than time_threshold), INS velocity errors of mm/s, a slowly warming gyro."""
    rng = np.random.default_rng(seed)
    speed = np.empty(n)
    k = 0
    while k < n:
        drive, stop = int(rng.integers(3, 30)), int(rng.integers(20, 300))
        speed[k:k + drive] = rng.uniform(1.0, 12.0, len(speed[k:k + drive]))
        speed[k + drive:k + drive + stop] = 0.0
        k += drive + stop
    vel = 1e-3 * rng.standard_normal((n, 2)) + 1e-5 * np.arange(n)[:, None]
    att = np.column_stack([rng.uniform(-3, 3, n), 0.01 * rng.standard_normal(n), 0.01 * rng.standard_normal(n)])
    lat = 0.7 + 1e-7 * np.cumsum(rng.standard_normal(n))
    temp = 22.0 + 0.01 * np.arange(n)
    return np.column_stack([vel, att, lat, temp, np.arange(1.0, n + 1), speed])


def _updater(params):
    p = {**PARAMS, **params}
    rls = ForgettingRLS([p["a0"], p["b0"], p["c0"]], prior_covariance(11.0, 0.0, 50.0), 0.0,
                        RLSSettings(p["forgetting_factor"], 30 * DAY))
    kf = StopFilterSettings(arw=p["kf_arw"])
    return OnlineDriftUpdater(rls, 0.7, params.get("_h", 1.0), kf, UpdaterSettings(p["time_threshold"], 0.01)), p


def _outputs(up, comp, apply_from, row_time, last=None):
    """The FMU's outputs from the library's updater state (the mapping of the model's publish)."""
    out = dict(last or {})
    x, p = up.rls.parameters, up.rls.covariance
    out.update(drift_a=x[0], drift_b=x[1], drift_c=x[2], compensation_drift=comp, apply_from=apply_from,
               stop_timer=up.timer, drift_estimate=up.filter.drift_estimate if up.stopped else 0.0,
               drift_estimate_std=up.filter.drift_std if up.stopped else 0.0, row_time=row_time,
               p_aa=p[0, 0], p_ab=p[0, 1], p_ac=p[0, 2], p_bb=p[1, 1], p_bc=p[1, 2], p_cc=p[2, 2],
               model_time=up.rls.time, stopped=int(up.stopped))
    kinds = [e[1] for e in up.events]
    out.update(n_updates=kinds.count("update"), n_resets=kinds.count("reset"))
    updates = [e for e in up.events if e[1] == "update"]
    if updates:
        out.update(last_update_temp=updates[-1][3], last_update_drift=updates[-1][4])
    if up.events:
        t, kind, duration, temp, drift, std = up.events[-1]
        out.update(last_stop_time=t, last_stop_duration=duration, last_stop_temp=temp, last_stop_drift=drift,
                   last_stop_drift_std=std, last_stop_used=int(kind == "update"))
    return out


def _expected(rows, params, h=1.0, lag=0):
    """The outputs after initialisation and after each step: the library fed row k at step k + lag."""
    up, p = _updater({**params, "_h": h})
    zero = {n: 0.0 for n in REAL_OUT} | {n: 0 for n in INT_OUT}
    out = [_outputs(up, float(up.compensation(rows[0, 6])), NO_TAG, NO_TAG, zero)]
    for k in range(len(rows)):
        j = k - lag
        if j < 0:
            out.append(dict(out[-1]))
            continue
        r = rows[j]
        comp = up.step([p["start_day"] * DAY + r[7]], [r[8]], [r[0:2]], [r[2:5]], [r[6]], [r[5]], [True])[0]
        out.append(_outputs(up, float(comp), r[7] + p["latency"], r[7], out[-1]))
    return [[o[n] for n in REAL_OUT + INT_OUT] for o in out]


def _inputs(rows, k, h, scheme):
    """The FMU's inputs before step k: the INS row and the speed as the scheme delivers them."""
    if scheme == "untagged":
        r = rows[k]
        return dict(zip(ROW_INPUTS, r)) | {"nav_time": r[7] * h}
    if scheme == "gauss-seidel":  # the INS row of the step just taken, the vehicle's speed at its end
        r = rows[k]
        return dict(zip(ROW_INPUTS, r)) | {"solution_time": r[7], "speed_time": r[7]}
    # jacobi: the INS row one step behind (none at step 0: its initial outputs, tag = start), the vehicle's
    # speed of the step ahead (its outputs at t + h, tagged so)
    r = rows[k - 1] if k > 0 else np.concatenate([rows[0, :7], [0.0, rows[0, 8]]])
    speed_time = k + 1.0
    speed = rows[k, 8]
    values = dict(zip(ROW_INPUTS, r)) | {"solution_time": r[7] if k > 0 else 0.0, "speed_time": speed_time}
    values["vehicle_speed"] = speed
    return values


def _fmu_run(fmu, rows, params, h=1.0, scheme="gauss-seidel", model_file=None, state_at=None):
    """Every output after initialisation and after each step; with ``state_at`` also the rows after
    restoring the state taken after that many steps (same instance) and in a new instance."""
    slave = Slave(fmu, "upd")
    try:
        values = dict(PARAMS, **params)
        if model_file is not None:
            values["model_file"] = str(model_file)
        slave.set(**values)
        slave.set(**_inputs(rows, 0, h, scheme))
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()

        def outputs():
            return slave.get(*REAL_OUT) + slave.fmu.getInteger([slave.vr[n] for n in INT_OUT])

        out = [outputs()]
        state = blob = None
        for k in range(len(rows)):
            if k == state_at:
                state = slave.fmu.getFMUstate()
                blob = slave.fmu.serializeFMUstate(state)
            slave.set(**_inputs(rows, k, h, scheme))
            slave.fmu.doStep(k * h, h)
            out.append(outputs())
        if state is None:
            return out
        slave.fmu.setFMUstate(state)
        slave.fmu.freeFMUstate(state)
        again = []
        for k in range(state_at, len(rows)):
            slave.set(**_inputs(rows, k, h, scheme))
            slave.fmu.doStep(k * h, h)
            again.append(outputs())
        other = Slave(fmu, "other")
        try:
            other.fmu.setFMUstate(other.fmu.deSerializeFMUstate(blob))
            there = []
            for k in range(state_at, len(rows)):
                other.set(**_inputs(rows, k, h, scheme))
                other.fmu.doStep(k * h, h)
                there.append(other.get(*REAL_OUT) + other.fmu.getInteger([other.vr[n] for n in INT_OUT]))
        finally:
            other.free()
        return out, again, there
    finally:
        slave.free()


@pytest.fixture(scope="module")
def fmu(fmu_dir):
    return fmu_dir / "DriftModelUpdater.fmu"


@pytest.mark.parametrize("scheme, h", [("untagged", 1.0), ("gauss-seidel", 1.0), ("jacobi", 1.0), ("untagged", 2.0)])
def test_fmu_equals_the_library_bit_for_bit(fmu, scheme, h):
    """Every Real and Integer output after initialisation and after each of 900 steps equals the library's
    OnlineDriftUpdater fed the same rows (several stops update the model, several are discarded)."""
    rows = _rows()
    rows_h = rows.copy()
    rows_h[:, 7] *= h  # nav times of a 2 s grid
    got = _fmu_run(fmu, rows, {}, h=h, scheme=scheme)
    expected = _expected(rows_h, {}, h=h, lag=1 if scheme == "jacobi" else 0)
    if scheme == "jacobi":  # no row at step 0 (the INS's initial outputs): the outputs stay the initial ones
        assert got[1] == got[0]
    assert [list(map(float, r)) for r in got] == [list(map(float, r)) for r in expected]
    counts = got[-1][len(REAL_OUT) + 1:len(REAL_OUT) + 3]
    assert counts[0] >= 2 and counts[1] >= 1, counts


def test_model_file_starts_the_fmu_where_the_library_is(fmu, tmp_path):
    """A model file written by the library (after a few updates): the FMU continues from it like the
    library's updater holding that RLS state, bit for bit."""
    rls = ForgettingRLS([PARAMS["a0"], PARAMS["b0"], PARAMS["c0"]], prior_covariance(), 0.0, RLSSettings(0.7))
    for k, t in enumerate((5.0, 35.0, 47.0)):
        rls.update(t, 1e-8 * (1 + k), (k + 1) * DAY)
    path = rls.export_binary(tmp_path / "start.bin")
    rows = _rows(400, seed=9)
    got = _fmu_run(fmu, rows, {}, model_file=path)
    up = OnlineDriftUpdater(ForgettingRLS.load(path), 0.7, 1.0, StopFilterSettings(arw=PARAMS["kf_arw"]),
                            UpdaterSettings(PARAMS["time_threshold"], 0.01))
    zero = {n: 0.0 for n in REAL_OUT} | {n: 0 for n in INT_OUT}
    expected = [_outputs(up, float(up.compensation(rows[0, 6])), NO_TAG, NO_TAG, zero)]
    for r in rows:
        comp = up.step([PARAMS["start_day"] * DAY + r[7]], [r[8]], [r[0:2]], [r[2:5]], [r[6]], [r[5]])[0]
        expected.append(_outputs(up, float(comp), r[7] + PARAMS["latency"], r[7], expected[-1]))
    assert [list(map(float, r)) for r in got] == [[float(o[n]) for n in REAL_OUT + INT_OUT] for o in expected]
    assert got[0][REAL_OUT.index("model_time")] == 3 * DAY and got[-1][len(REAL_OUT) + 1] >= 1


def _mid_stop(rows):
    """A step in the middle of a stop longer than the threshold."""
    still = rows[:, 8] == 0.0
    k = next(k for k in range(100, len(rows)) if still[k - 100:k + 100].all())
    return k


def test_state_round_trip_mid_stop_repeats_the_run(fmu):
    """getFMUstate in the middle of a stop (filter, timer, sums and speed history held), the rest of the
    run, setFMUstate and the rest again: the same outputs; deserialized into a new instance: the same."""
    rows = _rows()
    k = _mid_stop(rows)
    out, again, there = _fmu_run(fmu, rows, {}, scheme="jacobi", state_at=k)
    assert out[k][len(REAL_OUT)] == 1 and out[k][REAL_OUT.index("stop_timer")] > 50  # mid-stop
    assert again == out[k + 1:] and there == out[k + 1:]


def _fnv1a(data: bytes) -> int:
    """The glue's state checksum (fmus/c/glue_core.c: FNV-1a 64 with its offset basis 1469598103934665603)."""
    h = 1469598103934665603
    for b in data:
        h = ((h ^ b) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return h


def test_a_crafted_state_is_refused_with_the_reason_not_run(fmu):
    """A serialized state whose speed-history count is out of its buffer (the checksum recomputed, so the
    glue's checks pass): fmi2DeSerializeFMUstate is fmi2Error naming the field (the model's check_state),
    no out-of-bounds read."""
    rows = _rows(50)
    slave = Slave(fmu, "crafted")
    try:
        slave.set(**PARAMS)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        for k in range(5):
            slave.set(**_inputs(rows, k, 1.0, "gauss-seidel"))
            slave.fmu.doStep(float(k), 1.0)
        blob = bytearray(slave.fmu.serializeFMUstate(slave.fmu.getFMUstate()))
        first_tag = struct.pack("<d", 1.0)  # speed_tag[0]: the first speed kept (speed_time 1)
        at = blob.index(struct.pack("<q", 5) + first_tag)  # n_speeds, then the tags
        blob[at:at + 8] = struct.pack("<q", 99)
        head = next(h for h in range(40, 400) if struct.unpack_from("<Q", blob, h - 16)[0] == len(blob) - h)
        struct.pack_into("<Q", blob, head - 8, _fnv1a(bytes(blob[head:])))
        with pytest.raises(FMICallException, match="status 3"):
            slave.fmu.deSerializeFMUstate(bytes(blob))  # refused before any of it is used
        assert any("n_speeds = 99" in m for s, _, m in slave.log if s == 3), slave.log[-3:]
    finally:
        slave.free()


# ------------------------------------------------------------------------------------- bad parameters
@pytest.mark.parametrize("params, text", [
    ({"start_day": math.nan}, "start_day"),
    ({"latency": -1.0}, "latency"),
    ({"prior_t_min": 50.0}, "prior_t_max"),
    ({"kf_vrw": 0.0}, "kf_vrw"),
    ({"time_threshold": math.inf}, "time_threshold"),
    ({"forgetting_factor": 1.01}, "forgetting_factor"),
    ({"lat": math.radians(-90.0)}, "89.9"),
])
def test_bad_parameters_are_refused_at_exit_initialization(fmu, params, text):
    check_parameter_error(fmu, params, text)


def _rls_bytes(version=1, kind="rls", **change):
    arrays = {"parameters": np.array([1e-11, -2e-10, 1e-8]), "covariance": prior_covariance(), "time": 0.0,
              "n_updates": 0.0, "forgetting_factor": 0.8, "time_scale": 30 * DAY, **change}
    data = bytearray(netfile.to_bytes(kind, arrays))
    struct.pack_into("<I", data, 8, version)
    return bytes(data[:-8]) + struct.pack("<Q", netfile.checksum(bytes(data[:-8])))


def _bad_files(tmp_path):
    good = _rls_bytes()
    flipped = bytearray(good)
    flipped[100] ^= 0x10
    cases = {
        "missing.bin": (None, "no such file"),
        "folder.bin": ("dir", "cannot be read"),
        "text.json": (b'{"format": "sarins_fmu.identify.rls"}', "not a sarins binary model file"),
        "short.bin": (good[:-9], "declared size"),
        "flipped.bin": (bytes(flipped), "checksum mismatch"),
        "huge.bin": (good + bytes(4096), "4096 bytes"),
        "kind.bin": (_rls_bytes(kind="rbf"), "model kind 3"),
        "version.bin": (_rls_bytes(version=2), "format version 2"),
        "notpd.bin": (_rls_bytes(covariance=-prior_covariance()), "not positive definite"),
        "shape.bin": (_rls_bytes(parameters=np.zeros(4)), "array 'parameters' must have shape (3,)"),
        "perupdate.bin": (_rls_bytes(time_scale=0.0), "per update"),
        "lambda.bin": (_rls_bytes(forgetting_factor=0.5), "forgetting factor 0.5"),
    }
    for name, (data, _) in cases.items():
        if data == "dir":
            (tmp_path / name).mkdir()
        elif data is not None:
            (tmp_path / name).write_bytes(data)
    return cases


def test_bad_model_files_are_refused_at_exit_initialization_naming_the_file_and_why(fmu, tmp_path):
    for name, (_, why) in _bad_files(tmp_path).items():
        path = str(tmp_path / name)
        slave = Slave(fmu, "bad")
        try:
            slave.set(model_file=path)
            slave.fmu.enterInitializationMode()
            with pytest.raises(FMICallException, match="status 3"):
                slave.fmu.exitInitializationMode()
            errors = [m for status, _, m in slave.log if status == 3]
            assert any(path in m and why in m for m in errors), (name, errors)
        finally:
            slave.free()


def test_the_library_refuses_the_same_model_files(tmp_path):
    """ForgettingRLS.load reads binary files with the core's reader: the same files refused for the same
    reasons (the settings mismatch is the FMU's own check; a folder or a JSON file go to the JSON reader)."""
    from sarins_fmu.identify.modelfile import ModelFileError

    for name, (_, why) in _bad_files(tmp_path).items():
        if name in ("text.json", "folder.bin", "lambda.bin", "perupdate.bin"):
            continue
        with pytest.raises(ModelFileError, match=why.replace("(", r"\(").replace(")", r"\)")):
            ForgettingRLS.load(tmp_path / name)
    rls = ForgettingRLS.load(tmp_path / "perupdate.bin")
    assert rls.settings.time_scale is None


# ------------------------------------------------------------------------------------- the C hosts
@pytest.fixture(scope="module")
def unzipped(fmu, tmp_path_factory):
    folder = tmp_path_factory.mktemp("dmu") / "DriftModelUpdater"
    zipfile.ZipFile(fmu).extractall(folder)
    return folder, read_model_description(str(fmu))


@pytest.fixture(scope="module")
def host(tmp_path_factory):
    from fmus.native_fmu import fmi_headers_dir
    from test_native_fmus import HOST_SRC, _cc

    out = tmp_path_factory.mktemp("dmu_host") / "host"
    build_line([_cc(), "-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{fmi_headers_dir()}",
                    str(HOST_SRC), "-ldl", "-o", str(out)])
    return out


def _host_args(md, tmp_path, rows):
    vr = {v.name: v.valueReference for v in md.modelVariables}
    table = np.array([[_inputs(rows, k, 1.0, "gauss-seidel")[n] for n in INPUTS] for k in range(len(rows))])
    table.astype("=f8").tofile(tmp_path / "rows.bin")
    first = [f"r{vr[n]}={float(v)!r}" for n, v in zip(INPUTS, table[0])]  # the inputs at initialisation: row 0's
    return ([f"r{vr[k]}={v!r}" for k, v in PARAMS.items()] + first
            + ["in=" + ",".join(str(vr[n]) for n in INPUTS), f"rows={tmp_path / 'rows.bin'}",
               "out=" + ",".join(str(vr[n]) for n in REAL_OUT)]), vr


def test_c_host_with_empty_environment_equals_fmpy_and_repeats_after_set_state(fmu, unzipped, host, tmp_path):
    """The C host started with no environment at all (no Python anywhere): every Real output equals FMPy's
    bit for bit; an FMU state taken mid-stop repeats the rest of the run."""
    from test_native_fmus import bits, run_host, table

    folder, md = unzipped
    rows = _rows()
    k = _mid_stop(rows)
    args, _ = _host_args(md, tmp_path, rows)
    proc = run_host(host, folder / "binaries" / "linux64" / "DriftModelUpdater.so", md, N, *args, f"roundtrip={k}",
                    env={})
    assert "STATUS" not in proc.stdout, proc.stdout[-2000:]
    out, again = table(proc), table(proc, "AGAIN")
    expected = _fmu_run(fmu, rows, {}, scheme="gauss-seidel")
    assert [out[j] for j in range(N + 1)] == [[bits(x) for x in row[:len(REAL_OUT)]] for row in expected]
    assert len(again) == N - k and all(again[j] == out[j] for j in again)


def test_fmi3_variant_equals_fmi2_bit_for_bit(unzipped, host, tmp_path):
    """The FMI 3.0 FMU of the same declaration and model.c (fmpy validate clean), through the FMI 3.0 C host
    with an empty environment: the FMI 2.0 FMU's bits."""
    from pathlib import Path

    from fmpy.validation import validate_fmu

    from fmus.native_fmu import build_native_fmu, fmi_headers_dir
    from test_native_fmus import _cc, run_host, table

    fmu3 = build_native_fmu("DriftModelUpdater", "drift_model_updater_slave.py", tmp_path / "fmu3", fmi=3,
                            win64=False, aarch64=False)
    assert validate_fmu(str(fmu3)) == []
    folder3 = tmp_path / "f3"
    zipfile.ZipFile(fmu3).extractall(folder3)
    host3 = tmp_path / "host3"
    build_line([_cc(), "-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{fmi_headers_dir(3)}",
                    str(Path(__file__).parent / "native_host" / "native_fmu3_host.c"), "-ldl", "-o", str(host3)])
    folder, md = unzipped
    args, _ = _host_args(md, tmp_path, _rows(300))
    two = run_host(host, folder / "binaries" / "linux64" / "DriftModelUpdater.so", md, 300, *args, env={})
    md3 = read_model_description(str(fmu3))
    three = run_host(host3, folder3 / "binaries" / "x86_64-linux" / "DriftModelUpdater.so", md3, 300, *args,
                     f"nout={len(REAL_OUT)}", f"nin={len(INPUTS)}", env={})
    assert "STATUS" not in three.stdout, three.stdout[-2000:]
    assert table(three) == table(two) and len(table(two)) == 301


def test_no_heap_allocation_after_initialisation(unzipped, host, tmp_path):
    """900 steps with stops, updates and discarded stops: no heap allocation after
    fmi2ExitInitializationMode (an LD_PRELOAD counter in the C host)."""
    from test_native_fmus import COUNTER_SRC, _cc, run_host

    folder, md = unzipped
    counter = tmp_path / "alloc_counter.so"
    build_line([_cc(), "-O2", "-shared", "-fPIC", "-o", str(counter), str(COUNTER_SRC), "-ldl"])
    args, _ = _host_args(md, tmp_path, _rows())
    proc = run_host(host, folder / "binaries" / "linux64" / "DriftModelUpdater.so", md, N, *args, "allocs",
                    env={"LD_PRELOAD": str(counter), "PATH": os.environ.get("PATH", "")})
    assert "STATUS" not in proc.stdout, proc.stdout[-2000:]
    assert "ALLOCS 0" in proc.stdout.splitlines(), proc.stdout[-2000:]


def test_sources_compiled_with_the_documented_line_give_the_shipped_outputs(unzipped, host, tmp_path):
    import shutil

    from fmus.native_fmu import compile_line
    from test_native_fmus import _cc, run_host, table

    folder, md = unzipped
    sources = tmp_path / "sources"
    shutil.copytree(folder / "sources", sources)
    cmd = [_cc() if a == "cc" else a for a in compile_line("DriftModelUpdater")]
    subprocess.run(" ".join(cmd), shell=True, cwd=sources, check=True)
    args, _ = _host_args(md, tmp_path, _rows())
    mine = table(run_host(host, sources / "DriftModelUpdater.so", md, N, *args))
    shipped = table(run_host(host, folder / "binaries" / "linux64" / "DriftModelUpdater.so", md, N, *args))
    assert mine == shipped and len(mine) == N + 1


@pytest.mark.slow
def test_sanitized_build_runs_clean_through_the_c_host(unzipped, tmp_path):
    """sources/ built with AddressSanitizer + UBSan: the run with a state round trip mid-stop, and every bad
    model file; any report fails."""
    from fmus.native_fmu import CFLAGS, fmi_headers_dir
    from test_native_fmus import HOST_SRC, _cc, run_host, table

    folder, md = unzipped
    sources = folder / "sources"
    san = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-g", "-O1"]
    lib = tmp_path / "dmu_san.so"
    build_line([_cc(), *[f for f in CFLAGS if f != "-O2"], *san, "-fPIC", "-shared", f"-I{sources}",
                    *sorted(str(p) for p in sources.glob("*.c")), "-lm", "-o", str(lib)])
    host = tmp_path / "host_san"
    build_line([_cc(), "-std=c11", *san, f"-I{fmi_headers_dir()}", str(HOST_SRC), "-ldl", "-o", str(host)])
    env = {"ASAN_OPTIONS": "detect_leaks=1", "UBSAN_OPTIONS": "print_stacktrace=1",
           "PATH": os.environ.get("PATH", "")}
    rows = _rows()
    args, vr = _host_args(md, tmp_path, rows)
    proc = run_host(host, lib, md, N, *args, f"roundtrip={_mid_stop(rows)}", env=env, timeout=600)
    assert "STATUS" not in proc.stdout and "runtime error" not in proc.stderr, proc.stderr[-3000:]
    assert table(proc, "AGAIN")
    for name in _bad_files(tmp_path):
        proc = run_host(host, lib, md, 3, f"s{vr['model_file']}={tmp_path / name}", env=env, timeout=600)
        assert "STATUS fmi2ExitInitializationMode 3" in proc.stdout and "ERROR" not in proc.stderr, proc.stderr


@pytest.mark.slow
def test_win64_dll_under_wine_runs_and_agrees_with_linux64(unzipped, host, tmp_path, wine_env):
    """The shipped win64 DLL under wine: the run with its state round trip repeats itself bit for bit, and
    agrees with linux64 to 1e-12 relative (the filter's sin, cos, tan and the RLS's pow come from mingw's
    C runtime there, glibc's here; on this run they agreed bit for bit, the test prints the comparison)."""
    import shutil

    from fmus.native_fmu import MINGW, fmi_headers_dir
    from test_native_fmus import HOST_SRC, run_host, table

    missing = [t for t in (MINGW, "wine") if shutil.which(t) is None]
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed (Debian: apt-get install gcc-mingw-w64-x86-64 wine64)")
    folder, md = unzipped
    exe = tmp_path / "host.exe"
    build_line([MINGW, "-std=c11", "-O2", f"-I{fmi_headers_dir()}", str(HOST_SRC), "-static", "-o", str(exe)])
    env = wine_env
    rows = _rows()
    args, _ = _host_args(md, tmp_path, rows)
    k = _mid_stop(rows)
    win = run_host(exe, folder / "binaries" / "win64" / "DriftModelUpdater.dll", md, N, *args, f"roundtrip={k}",
                   env=env, prefix=["wine"], timeout=600)
    lin = run_host(host, folder / "binaries" / "linux64" / "DriftModelUpdater.so", md, N, *args)
    assert "STATUS" not in win.stdout, win.stdout[-2000:]
    again = table(win, "AGAIN")
    assert len(again) == N - k and all(again[j] == table(win)[j] for j in again)

    def values(t):
        return np.array([[struct.unpack("<d", struct.pack("<Q", x))[0] for x in t[j]] for j in sorted(t)])

    w, lin_values = values(table(win)), values(table(lin))
    worst = float(np.max(np.abs(w - lin_values) / np.maximum(np.abs(lin_values), 1e-300)))
    print(f"win64 == linux64: {np.array_equal(w, lin_values)}, {int(np.sum(w != lin_values))} of {w.size} values "
          f"differ, largest relative difference {worst:.3g}")
    assert worst <= 1e-12
