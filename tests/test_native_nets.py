"""The native RBFIdentifier and IMUCompensator FMUs (fmus/c/rbf_identifier, fmus/c/imu_compensator):
through FMPy (FMI 2.0 and 3.0) and through the C host with an empty environment, bit for bit with the
library (the same C functions over the same binary model file); bad model files are an error at the end
of initialisation naming the file and the reason; an FMU state taken mid-run and restored (also
serialized) gives the same outputs."""

from __future__ import annotations

import ctypes
import shutil
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from fmu_driver import Slave
from fmus.cbuild import build_line
from fmus.compensator_export import export_compensator
from sarins_fmu.identify import compensators
from sarins_fmu.identify.axial import DEFAULT_MODELS, DriftIdentifier
from test_nets import _toy, fitted

HERE = Path(__file__).resolve().parent
H = 0.05  # s, communication step
RAW = [f"raw_{q}_{a}" for q in ("dtheta", "dv") for a in "xyz"]
OUT = [f"{q}_{a}" for q in ("dtheta", "dv") for a in "xyz"]
TEMPS = [f"temp_{s}" for s in ("gyro_x", "gyro_y", "gyro_z", "accel_x", "accel_y", "accel_z")]


@pytest.fixture(scope="module")
def identifier_fmu(fmu_dir):
    return fmu_dir / "RBFIdentifier.fmu"  # the session's build (tests/conftest.py)


@pytest.fixture(scope="module")
def compensator_fmu(tmp_path_factory):
    """One IMUCompensator FMU (the GRU model in its resources; linux64 only: fast) and {kind: (model, its
    binary model file)} for every kind, given to the same FMU as model_file."""
    out = tmp_path_factory.mktemp("comp")
    models = {kind: fitted(kind) for kind in compensators.KINDS}
    fmu = export_compensator(models["gru"].save(out / "gru.npz"), out, win64=False, aarch64=False)
    return fmu, {kind: (m, m.export_binary(out / f"{kind}.bin")) for kind, m in models.items()}


def _start(fmu, name, model_file=None):
    slave = Slave(fmu, name)
    if model_file is not None:
        slave.set(model_file=str(model_file))
    slave.fmu.enterInitializationMode()
    slave.fmu.exitInitializationMode()
    return slave


def _rows(n=40, seed=9):
    x, _ = _toy(n, seed=seed)
    x[:, :6] *= 1.0 + 0.02 * np.random.default_rng(seed).standard_normal((n, 6))
    return x


def _step(slave, k, row):
    """One doStep with the raw increments of row (rate, specific force, temperature) over H."""
    slave.set(**{name: row[i] * H for i, name in enumerate(RAW)}, **{t: row[6] for t in TEMPS})
    slave.fmu.doStep(k * H, H)
    return slave.get(*OUT)


def _expected(model, x):
    """The library's compensation of the rows the FMU sees ((row * H) / H, the mean temperature)."""
    temp = np.zeros(len(x))
    for _ in TEMPS:  # the FMU sums the six (here equal) temperatures in order, then divides by 6
        temp = temp + x[:, 6]
    seen = np.column_stack([(x[:, :6] * H) / H, temp / 6.0])
    return model.predict(seen) * H


def test_the_fmus_validate(identifier_fmu, compensator_fmu):
    fmu, models = compensator_fmu
    assert validate_fmu(str(identifier_fmu)) == []
    assert validate_fmu(str(fmu)) == []
    with zipfile.ZipFile(fmu) as z:
        assert z.read("resources/compensator.bin") == models["gru"][1].read_bytes()
    with zipfile.ZipFile(identifier_fmu) as z:
        names = z.namelist()
        for kind, path in DEFAULT_MODELS.items():  # the shipped models, in the format the C model reads
            assert z.read(f"resources/axial_rbf_{kind}.bin") == DriftIdentifier(path).binary()
    assert {"sources/nets.c", "sources/netmodel.c", "sources/netfile.c", "sources/model.c"} <= set(names)
    assert read_model_description(str(identifier_fmu)).coSimulation.needsExecutionTool is False


@pytest.mark.parametrize("kind", compensators.KINDS)
def test_compensator_fmu_equals_the_library_bit_for_bit(compensator_fmu, kind):
    fmu, models = compensator_fmu
    model, path = models[kind]
    x = _rows()
    slave = _start(fmu, f"c_{kind}", None if kind == "gru" else path)  # gru: the model in resources
    try:
        got = np.array([_step(slave, k, row) for k, row in enumerate(x)])
        assert slave.fmu.getInteger([slave.vr["model_kind"]])[0] == compensators.KINDS.index(kind)
    finally:
        slave.free()
    np.testing.assert_array_equal(got, _expected(model, x))


@pytest.mark.parametrize("kind", ["gru", "lstm3", "grnn"])
def test_fmu_state_round_trip_mid_run_gives_the_same_outputs(compensator_fmu, kind):
    """The recurrent state and the time tags are in the FMU state: restored (in memory or from its
    serialization) mid-run, the next steps repeat exactly."""
    fmu, models = compensator_fmu
    x = _rows(30)
    slave = _start(fmu, f"s_{kind}", models[kind][1])
    try:
        for k in range(10):
            _step(slave, k, x[k])
        state = slave.fmu.getFMUState()
        blob = slave.fmu.serializeFMUState(state)
        first = [_step(slave, k, x[k]) for k in range(10, 30)]
        slave.fmu.setFMUState(state)
        again = [_step(slave, k, x[k]) for k in range(10, 30)]
        slave.fmu.setFMUState(slave.fmu.deserializeFMUState(blob))
        third = [_step(slave, k, x[k]) for k in range(10, 30)]
        slave.fmu.freeFMUState(state)
    finally:
        slave.free()
    assert first == again == third
    assert first[0] != first[1]  # it ran


def test_identifier_fmu_equals_the_library_with_the_shipped_cold_model(identifier_fmu):
    ident = DriftIdentifier(DEFAULT_MODELS["cold"])
    slave = Slave(identifier_fmu, "cold")
    lat_error, temp, change = 1.3e-5, 31.5, 12.25
    try:
        slave.set(model_kind="cold", trigger_time=3.0, temperature=temp, temp_change=change)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        for k in range(6):
            slave.set(nav_time=float(k + 1), lat_error=lat_error if k + 1 == 3 else 0.0)
            slave.fmu.doStep(float(k), 1.0)
        drift, apply_from = slave.get("axial_drift", "apply_from")
    finally:
        slave.free()
    assert drift == ident.drift(lat_error, temp, change) and apply_from == 13.0


def _bad_files(tmp: Path) -> dict:
    good = DriftIdentifier(DEFAULT_MODELS["hot"]).binary()
    big = bytearray(good)
    big[16:24] = (1 << 40).to_bytes(8, "little")
    files = {"truncated.bin": (good[:50], "declared size"), "magic.bin": (b"XXXXXXXX" + good[8:], "wrong magic"),
             "kind.bin": (fitted("traditional").binary(), "not an axial drift identifier"),
             "huge.bin": (bytes(big), "over the budget"), "model.json": (DEFAULT_MODELS["hot"].read_bytes(),
                                                                          "not a sarins binary model file")}
    for name, (data, _) in files.items():
        (tmp / name).write_bytes(data)
    return {tmp / name: reason for name, (_, reason) in files.items()}


def test_bad_model_files_are_an_error_at_exit_initialization_naming_file_and_reason(identifier_fmu,
                                                                                    compensator_fmu, tmp_path):
    cases = _bad_files(tmp_path)
    cases[tmp_path / "missing.bin"] = "cannot open"
    for fmu in (identifier_fmu, compensator_fmu[0]):
        for path, reason in cases.items():
            if fmu != identifier_fmu and reason.startswith("not an axial"):
                reason = "not a compensator"
                path.write_bytes(DriftIdentifier(DEFAULT_MODELS["hot"]).binary())
            log = []
            slave = Slave(fmu, "bad", log)
            try:
                slave.set(model_file=str(path))
                slave.fmu.enterInitializationMode()
                with pytest.raises(FMICallException, match="status 3"):
                    slave.fmu.exitInitializationMode()
            finally:
                slave.free()
            errors = [text for status, _, text in log if status == 3]
            assert any(str(path) in e and reason in e for e in errors), (path, errors)


# ----------------------------------------------------------------------------- FMI 3.0
def test_fmi3_compensator_equals_the_library(compensator_fmu, tmp_path):
    from fmpy import extract
    from fmpy.fmi3 import FMU3Slave

    model = compensator_fmu[1]["lstm"][0]
    fmu3 = export_compensator(model.save(tmp_path / "m.npz"), tmp_path, fmi=3, win64=False, aarch64=False)
    assert validate_fmu(str(fmu3)) == []
    md = read_model_description(str(fmu3))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(fmu3)), modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="c3")
    x = _rows(15)
    s.instantiate()
    try:
        s.enterInitializationMode(startTime=0.0)
        s.exitInitializationMode()
        got = []
        for k, row in enumerate(x):
            s.setFloat64([vr[n] for n in RAW + TEMPS], [row[i] * H for i in range(6)] + [row[6]] * 6)
            s.doStep(k * H, H)
            got.append(s.getFloat64([vr[n] for n in OUT]))
        s.terminate()
    finally:
        s.freeInstance()
    np.testing.assert_array_equal(np.array(got), _expected(model, x))


# ----------------------------------------------------------------------------- the C host, no environment
@pytest.fixture(scope="module")
def host(tmp_path_factory):
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler (gcc/cc) to build the native test host")
    import fmpy

    out = tmp_path_factory.mktemp("host") / "host"
    build_line([cc, "-O2", "-o", str(out), str(HERE / "native_host" / "host.c"),
                    f"-I{Path(fmpy.__file__).parent / 'c-code'}", "-ldl"])
    return out


def _run_host(host, fmu: Path, tmp: Path, steps: int, step: float, values: dict, *ops):
    folder = tmp / fmu.stem
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    md = read_model_description(str(fmu))
    by_name = {v.name: v for v in md.modelVariables}
    sets = [f"{ {'Real': 'r', 'Integer': 'i', 'String': 's'}[by_name[n].type]}{by_name[n].valueReference}={v}"
            .replace(" ", "") for n, v in values.items()]
    cmd = [str(host), str(folder), md.coSimulation.modelIdentifier, md.guid, str(steps), repr(step), *sets,
           *[op.format(**{n: v.valueReference for n, v in by_name.items()}) for op in ops]]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120, env={})  # env -i: no Python at all
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "STATUS" not in proc.stdout, proc.stdout
    return {int(line.split()[1]): float(line.split()[2]) for line in proc.stdout.splitlines()
            if line.startswith("VALUE")}, by_name


def test_identifier_fmu_in_the_c_host_with_an_empty_environment(host, identifier_fmu, tmp_path):
    lat_error = -2.5e-5
    values, by_name = _run_host(host, identifier_fmu, tmp_path, 8, 1.0,
                                {"trigger_time": "5", "lat_error": repr(lat_error)}, "tag{nav_time}=1",
                                "final-real={axial_drift}")
    assert values[by_name["axial_drift"].valueReference] == DriftIdentifier(DEFAULT_MODELS["hot"]).drift(lat_error)


def test_compensator_fmu_in_the_c_host_with_an_empty_environment(host, compensator_fmu, tmp_path):
    fmu, models = compensator_fmu
    model = models["gru"][0]  # the model in the FMU's resources
    row = _rows(1)[0]
    values, by_name = _run_host(host, fmu, tmp_path, 12, H,
                                {**{n: repr(float(row[i] * H)) for i, n in enumerate(RAW)}, **{t: repr(float(row[6])) for t in TEMPS}},
                                "final-real={dtheta_x}", "final-real={dv_z}")
    expected = _expected(model, np.repeat(row[None], 12, axis=0))[-1]
    assert values[by_name["dtheta_x"].valueReference] == expected[0]
    assert values[by_name["dv_z"].valueReference] == expected[5]


def test_fmu_binaries_need_no_python(identifier_fmu, tmp_path):
    with zipfile.ZipFile(identifier_fmu) as z:
        z.extract("binaries/linux64/RBFIdentifier.so", tmp_path)
    lib = tmp_path / "binaries/linux64/RBFIdentifier.so"
    needed = subprocess.run(["objdump", "-p", str(lib)], capture_output=True, text=True).stdout
    assert "python" not in needed.lower()
    ctypes.CDLL(str(lib))  # loads on its own


# ----------------------------------------------------------------------------- the portable host
def _portable_run(compensator_fmu, tmp_path, kind, *extra, lib=None, host=None, env=None, prefix=(), model=None,
                  fmu=None):
    """The compensator in tests/native_host/native_fmu_host.c (1 s steps, constant raw inputs, the six
    outputs printed as bit patterns), the model of ``kind`` given as model_file (``fmu``: the build whose
    binary ``lib`` is, default the fixture's)."""
    from test_native_fmus import run_host

    models = compensator_fmu[1]
    fmu = fmu or compensator_fmu[0]
    folder = tmp_path / "unzipped"
    if not folder.exists():
        zipfile.ZipFile(fmu).extractall(folder)
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    row = _rows(1)[0]
    values = {**{n: row[i] for i, n in enumerate(RAW)}, **{t: row[6] for t in TEMPS}}
    args = [f"r{vr[k]}={float(v)!r}" for k, v in values.items()]
    args.append(f"s{vr['model_file']}={model or models[kind][1]}")
    args.append("out=" + ",".join(str(vr[n]) for n in OUT))
    return run_host(host, lib or folder / "binaries" / "linux64" / "IMUCompensator.so", md, 60, *args, *extra,
                    env={} if env is None else env, prefix=prefix, timeout=900)


@pytest.fixture(scope="module")
def portable_host(tmp_path_factory):
    from fmus.native_fmu import fmi_headers_dir
    from test_native_fmus import HOST_SRC, _cc

    out = tmp_path_factory.mktemp("portable") / "host"
    build_line([_cc(), "-std=c11", "-O2", f"-I{fmi_headers_dir()}", str(HOST_SRC), "-ldl", "-o", str(out)])
    return out


@pytest.mark.parametrize("kind", ["gru3", "grnn"])
def test_no_heap_allocation_after_initialisation(compensator_fmu, portable_host, tmp_path, kind):
    import os

    from test_native_fmus import COUNTER_SRC, _cc

    counter = tmp_path / "alloc_counter.so"
    build_line([_cc(), "-O2", "-shared", "-fPIC", "-o", str(counter), str(COUNTER_SRC), "-ldl"])
    proc = _portable_run(compensator_fmu, tmp_path, kind, "allocs", host=portable_host,
                         env={"LD_PRELOAD": str(counter), "PATH": os.environ.get("PATH", "")})
    assert "STATUS" not in proc.stdout, proc.stdout[-2000:]
    assert "ALLOCS 0" in proc.stdout.splitlines(), proc.stdout[-2000:]


@pytest.mark.slow
def test_sanitized_build_runs_clean_through_the_c_host(compensator_fmu, tmp_path):
    """sources/ built with AddressSanitizer + UndefinedBehaviorSanitizer: each network kind with an FMU state
    round trip, and bad model files; any report fails the run."""
    import os

    from fmus.native_fmu import CFLAGS, fmi_headers_dir
    from test_native_fmus import HOST_SRC, _cc, table

    sources = tmp_path / "src"
    zipfile.ZipFile(compensator_fmu[0]).extractall(sources)
    sources = sources / "sources"
    san = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-g", "-O1"]
    lib = tmp_path / "IMUCompensator_san.so"
    build_line([_cc(), *[f for f in CFLAGS if f != "-O2"], *san, "-fPIC", "-shared", f"-I{sources}",
                    *sorted(str(p) for p in sources.glob("*.c")), "-lm", "-o", str(lib)])
    host = tmp_path / "host_san"
    build_line([_cc(), "-std=c11", *san, f"-I{fmi_headers_dir()}", str(HOST_SRC), "-ldl", "-o", str(host)])
    env = {"ASAN_OPTIONS": "detect_leaks=1", "UBSAN_OPTIONS": "print_stacktrace=1", "PATH": os.environ.get("PATH", "")}
    for kind in ("traditional", "rbf", "grnn", "lstm3", "gru"):
        proc = _portable_run(compensator_fmu, tmp_path, kind, "roundtrip=30", lib=lib, host=host, env=env)
        assert "STATUS" not in proc.stdout and "runtime error" not in proc.stderr, proc.stderr[-3000:]
        assert table(proc, "AGAIN") == {k: v for k, v in table(proc).items() if k > 30}
    bad = _bad_files(tmp_path)
    (tmp_path / "kind.bin").write_bytes(DriftIdentifier(DEFAULT_MODELS["hot"]).binary())  # not a compensator
    for name in bad:
        proc = _portable_run(compensator_fmu, tmp_path, "gru", lib=lib, host=host, env=env, model=name)
        assert "STATUS fmi2ExitInitializationMode 3" in proc.stdout and "ERROR" not in proc.stderr, proc.stderr


@pytest.mark.slow
def test_win64_dll_under_wine_agrees_with_linux64(compensator_fmu, portable_host, tmp_path, wine_env):
    """The win64 DLL (mingw-w64) under wine runs every network kind with its FMU state round trip bit for bit.
    Against linux64 it agrees to 1e-12 relative but not bit for bit: exp and tanh come from mingw's C
    runtime there, glibc's here (measured: 7 ulp, 1.3e-15 relative, GRU, 60 steps)."""
    import struct

    from fmus.native_fmu import MINGW, fmi_headers_dir
    from test_native_fmus import HOST_SRC, table

    missing = [t for t in (MINGW, "wine") if shutil.which(t) is None]
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed (Debian: apt-get install gcc-mingw-w64-x86-64 wine64)")
    fmu, models = compensator_fmu
    win = tmp_path / "win"
    fmu_win = export_compensator(models["gru"][0].save(tmp_path / "gru.npz"), win, win64=True)
    zipfile.ZipFile(fmu_win).extractall(win / "u")
    exe = tmp_path / "host.exe"
    build_line([MINGW, "-std=c11", "-O2", f"-I{fmi_headers_dir()}", str(HOST_SRC), "-static", "-o", str(exe)])
    env = wine_env

    def value(bits):
        return struct.unpack("<d", struct.pack("<Q", bits))[0]

    for kind in ("traditional", "grnn", "gru", "lstm3"):
        path = models[kind][1]
        w = _portable_run(compensator_fmu, tmp_path, kind, "roundtrip=30", lib=win / "u" / "binaries" / "win64" /
                          "IMUCompensator.dll", host=exe, env=env, prefix=["wine"], model="Z:" + str(path),
                          fmu=fmu_win)
        lin = _portable_run(compensator_fmu, tmp_path, kind, host=portable_host)
        assert "STATUS" not in w.stdout, w.stdout[-2000:]
        assert table(w, "AGAIN") == {k: v for k, v in table(w).items() if k > 30}
        for k, row in table(lin).items():
            a, b = np.array([value(x) for x in row]), np.array([value(x) for x in table(w)[k]])
            np.testing.assert_allclose(b, a, rtol=1e-12, atol=0)
