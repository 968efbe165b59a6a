"""The native FMUs (fmus/native_fmu.py, fmus/c): every FMI 2.0 call in C, no Python.

Checked for each native FMU: fmpy validate; the model description (FMU state, no execution tool, the
source files, the slave's variables); the binary's imports (no Py* symbol, no libpython) and exports
(fmi2* only); a C host run with an empty environment equals FMPy and the in-process library bit for bit;
FMU state get/set and serialisation across processes; refused state blobs; sources/ compiled with the
documented line; heap allocations after initialisation.  Slow: AddressSanitizer + UBSan build through the
C host, and the win64 DLL under wine against linux64.
"""

from __future__ import annotations

import math
import os
import shutil
import struct
import subprocess
import sys
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.validation import validate_fmu

from fmu_driver import Slave
from fmus.cbuild import build_line
from fmus.build import NEEDS_MODEL
from fmus.native_fmu import CFLAGS, MINGW, NATIVE, compile_line, fmi_headers_dir, slave_instance
from orchestration import fmilog

HERE = Path(__file__).resolve().parent
HOST_SRC = HERE / "native_host" / "native_fmu_host.c"
COUNTER_SRC = HERE / "native_host" / "alloc_counter.c"
OUTPUTS = [f"{q}_{j}" for j in (1, 2, 3) for q in ("angle", "rate", "accel")] + [
    "ambient_temp", "ambient_temp_rate", "motion_time"]
# two Turntable runs: the default scheme after a short alignment, and a dual-axis one in a chamber
CASES = {
    "forward-reverse": {"align_time": 600.0},
    "dual-axis chamber": {"scheme": "dual-axis", "align_time": 0.0, "ambient_mode": "chamber",
                          "chamber_hold": 120.0, "chamber_ramp": 0.05, "ambient_mean": 25.0},
}
STEPS = 1500


def _cc():
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        pytest.skip("no C compiler (gcc/cc)")
    return cc


@pytest.fixture(scope="module")
def turntable(fmu_dir, tmp_path_factory):
    """(unzipped folder, model description) of the session's native Turntable."""
    fmu = fmu_dir / "Turntable.fmu"
    folder = tmp_path_factory.mktemp("native_tt") / "Turntable"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    return folder, read_model_description(str(fmu))


@pytest.fixture(scope="module")
def host(tmp_path_factory):
    out = tmp_path_factory.mktemp("native_fmu_host") / "host"
    build_line([_cc(), "-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", f"-I{fmi_headers_dir()}",
                    str(HOST_SRC), "-ldl", "-o", str(out)])
    return out


def ops(md, values: dict, outputs=OUTPUTS) -> list[str]:
    """The host's arguments: parameter settings and the outputs to print."""
    by_name = {v.name: v for v in md.modelVariables}
    result = []
    for name, value in values.items():
        var = by_name[name]
        result.append(f"{ {'Real': 'r', 'Integer': 'i', 'String': 's'}[var.type]}{var.valueReference}={value}")
    result.append("out=" + ",".join(str(by_name[n].valueReference) for n in outputs))
    return result


def run_host(host, binary, md, steps, *args, env=None, prefix=(), timeout=300):
    cmd = [*prefix, str(host), str(binary), md.guid, str(steps), "1.0", *args]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    return proc


def table(proc, tag="OUT") -> dict[int, list[int]]:
    """{steps done: output bit patterns} from the host's lines."""
    rows = {}
    for line in proc.stdout.splitlines():
        parts = line.split()
        if parts and parts[0] == tag:
            rows[int(parts[1])] = [int(x, 16) for x in parts[2:]]
    return rows


def bits(x: float) -> int:
    return struct.unpack("<Q", struct.pack("<d", float(x)))[0]


def fmpy_rows(fmu, values: dict, steps: int) -> dict[int, list[int]]:
    slave = Slave(fmu, "native")
    try:
        slave.set(**values)
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        rows = {0: [bits(x) for x in slave.get(*OUTPUTS)]}
        for k in range(steps):
            slave.fmu.doStep(float(k), 1.0)
            rows[k + 1] = [bits(x) for x in slave.get(*OUTPUTS)]
        return rows
    finally:
        slave.free()


def in_process_rows(values: dict, steps: int) -> dict[int, list[int]]:
    """The library's schedule and ambient at the same times, as the Python Turntable computed them."""
    from sarins_fmu import thermal, turntable
    from sarins_fmu.units import DEG_TO_RAD

    p = {v.name: v.getter() for v in slave_instance("turntable_slave.py").vars.values()}
    p.update(values)
    sched = turntable.schedule_for(
        p["scheme"], p["duration"], rate_dps=p["rate"] / DEG_TO_RAD, accel_dps2=p["accel"] / DEG_TO_RAD,
        dwell=p["dwell"], grid=p["grid"], revolutions=p["revolutions"], align_time=p["align_time"],
        align_dwell=p["align_dwell"], outer_rate_dps=p["outer_rate"] / DEG_TO_RAD,
        outer_accel_dps2=p["outer_accel"] / DEG_TO_RAD,
        table_rates_dps=[p[f"table_{n}_rate"] / DEG_TO_RAD for n in ("inner", "middle", "outer")],
        table_accels_dps2=[p[f"table_{n}_accel"] / DEG_TO_RAD for n in ("inner", "middle", "outer")],
        warmup=p["warmup"])
    if p["ambient_mode"] == "chamber":
        ambient = thermal.Ambient(profile=thermal.chamber_profile(
            p["duration"], low_c=p["chamber_low"], high_c=p["chamber_high"], ramp_c_per_min=p["chamber_ramp"] * 60.0,
            hold_min=p["chamber_hold"] / 60.0, start_c=p["ambient_mean"], first=p["chamber_first"],
            step_c=p["chamber_step"], step_hold_min=p["chamber_step_hold"] / 60.0))
    else:
        ambient = thermal.Ambient(mean=p["ambient_mean"], amplitude=p["ambient_amplitude"],
                                  period=p["ambient_period"])
    rows = {}
    for k in range(steps + 1):
        t = float(k)
        angle, rate, acc = (x[0] for x in sched.state(t))
        out = np.zeros(9)
        n = len(angle)
        out[0:n], out[3:3 + n], out[6:6 + n] = angle, rate, acc
        temp, slope = thermal.ambient_segment(ambient, t, p["grid"] if k == 0 else 1.0)
        ordered = [out[3 * i + j] for j in range(3) for i in range(3)]
        rows[k] = [bits(x) for x in (*ordered, temp, slope, t)]
    return rows


# ----------------------------------------------------------------- description and binary


BUILT = [n for n in NATIVE if n not in NEEDS_MODEL]  # IMUCompensator: tests/test_native_nets.py (needs a model)


@pytest.mark.parametrize("name", BUILT)
def test_native_fmu_validates_and_declares_its_capabilities(fmu_dir, name):
    fmu = fmu_dir / f"{name}.fmu"
    assert validate_fmu(str(fmu)) == []
    md = read_model_description(str(fmu))
    cs = md.coSimulation
    assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate and not cs.needsExecutionTool
    with zipfile.ZipFile(fmu) as z:
        names = z.namelist()
        listed = [f.get("name") for f in ET.fromstring(z.read("modelDescription.xml")).iter("File")]
    sources = sorted(n[len("sources/"):] for n in names if n.startswith("sources/"))
    assert "fmi2_glue.c" in listed and "model.c" in listed
    assert sorted(s for s in sources if s.endswith(".c")) == sorted(listed)
    assert "variables.h" in sources and "model.h" in sources
    shipped = set(NATIVE[name].resources()) if NATIVE[name].resources else set()  # data files only (models)
    assert {n[len("resources/"):] for n in names if n.startswith("resources/")} == shipped
    # the slave class's declaration: same names, value references, types and start values
    declared = slave_instance(f"{NATIVE[name].folder}_slave.py").vars.values()
    by_vr = {v.valueReference: v for v in md.modelVariables}
    for var in declared:
        got = by_vr[var.value_reference]
        assert (got.name, got.type, got.causality) == (var.name, type(var).__name__, var.causality.name)
        if var.causality.name == "parameter":
            start = var.getter()  # pythonfmu writes Reals with 16 digits; the C table holds them exactly
            assert got.start == str(start) if isinstance(start, str) else math.isclose(float(got.start), start,
                                                                                        rel_tol=1e-15)


@pytest.mark.parametrize("name", BUILT)
def test_native_binary_has_no_python_and_exports_only_fmi2(fmu_dir, name, tmp_path):
    if shutil.which("nm") is None:
        pytest.skip("nm not installed")
    with zipfile.ZipFile(fmu_dir / f"{name}.fmu") as z:
        so = tmp_path / f"{name}.so"
        so.write_bytes(z.read(f"binaries/linux64/{name}.so"))
    undefined = subprocess.run(["nm", "-D", "--undefined-only", str(so)], capture_output=True, text=True,
                               check=True).stdout
    symbols = [line.split()[-1] for line in undefined.splitlines() if line.strip()]
    assert symbols and not [s for s in symbols if s.startswith(("Py", "_Py"))], symbols
    needed = subprocess.run(["readelf", "-d", str(so)], capture_output=True, text=True, check=True).stdout
    assert "libpython" not in needed and "NEEDED" in needed
    defined = subprocess.run(["nm", "-D", "--defined-only", str(so)], capture_output=True, text=True,
                             check=True).stdout
    exported = {line.split()[-1] for line in defined.splitlines() if line.split()[1] in ("T", "D", "R", "B")}
    assert exported and all(s.startswith("fmi2") for s in exported), exported
    assert {"fmi2Instantiate", "fmi2DoStep", "fmi2GetFMUstate", "fmi2DeSerializeFMUstate"} <= exported


# ----------------------------------------------------------------- same numbers everywhere


@pytest.mark.parametrize("case", list(CASES))
def test_c_host_with_empty_environment_equals_fmpy_and_in_process(fmu_dir, turntable, host, case):
    """env -i: no PATH, no PYTHON*, nothing; the outputs are the FMPy run's and the library's, bit for bit."""
    folder, md = turntable
    values = CASES[case]
    proc = run_host(host, folder / "binaries" / "linux64" / "Turntable.so", md, STEPS, *ops(md, values),
                    prefix=["env", "-i"], env={})
    assert "STATUS" not in proc.stdout, proc.stdout[-2000:]
    native = table(proc)
    assert sorted(native) == list(range(STEPS + 1))
    assert native == fmpy_rows(fmu_dir / "Turntable.fmu", values, STEPS)
    expected = in_process_rows(values, STEPS)
    for k in range(STEPS + 1):
        assert native[k] == expected[k], k
    assert len({tuple(row) for row in native.values()}) > 1000  # the table moves


def test_sources_compiled_with_the_documented_line_give_the_same_outputs(fmu_dir, turntable, host, tmp_path):
    folder, md = turntable
    with zipfile.ZipFile(fmu_dir / "Turntable.fmu") as z:
        doc = z.read("documentation/index.html").decode()
    line = " ".join(compile_line("Turntable"))
    assert line.replace("&", "&amp;") in doc
    sources = tmp_path / "sources"
    shutil.copytree(folder / "sources", sources)
    cmd = [_cc() if a == "cc" else a for a in compile_line("Turntable")]
    subprocess.run(" ".join(cmd), shell=True, cwd=sources, check=True)
    values = CASES["dual-axis chamber"]
    mine = run_host(host, sources / "Turntable.so", md, 300, *ops(md, values))
    shipped = run_host(host, folder / "binaries" / "linux64" / "Turntable.so", md, 300, *ops(md, values))
    assert table(mine) == table(shipped) and len(table(mine)) == 301


# ----------------------------------------------------------------- FMU state


def test_get_step_set_step_again_is_bit_identical_in_the_c_host(turntable, host):
    folder, md = turntable
    proc = run_host(host, folder / "binaries" / "linux64" / "Turntable.so", md, 900, "roundtrip=400",
                    *ops(md, CASES["dual-axis chamber"]))
    assert "STATUS" not in proc.stdout, proc.stdout[-2000:]
    first, again = table(proc), table(proc, "AGAIN")
    assert sorted(again) == list(range(401, 901))
    assert all(again[k] == first[k] for k in again)
    assert len({tuple(again[k]) for k in again}) > 100  # the state moved on between get and set


STATE_SCRIPT = """
import sys
sys.path[0:0] = [{tests!r}, {root!r}]
from fmu_driver import Slave
s = Slave({fmu!r}, "p")
s.set(**{values!r})
s.fmu.enterInitializationMode(); s.fmu.exitInitializationMode()
mode, path, k0, n = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
if mode == "load":
    state = s.fmu.deSerializeFMUstate(open(path, "rb").read())
    s.fmu.setFMUstate(state)
    s.fmu.freeFMUstate(state)
for k in range(k0, k0 + n):
    s.fmu.doStep(float(k), 1.0)
    print("ROW", k + 1, *[v.hex() for v in s.get(*{outputs!r})])
if mode == "save":
    state = s.fmu.getFMUstate()
    open(path, "wb").write(s.fmu.serializeFMUstate(state))
    s.fmu.freeFMUstate(state)
s.free()
"""


def test_state_serialized_in_one_process_continues_identically_in_another(fmu_dir, tmp_path):
    values = CASES["dual-axis chamber"]
    script = STATE_SCRIPT.format(tests=str(HERE), root=str(HERE.parent), fmu=str(fmu_dir / "Turntable.fmu"),
                                 values=values, outputs=OUTPUTS)

    def run(*args):
        proc = subprocess.run([sys.executable, "-c", script, *map(str, args)], capture_output=True, text=True,
                              timeout=300)
        assert proc.returncode == 0, proc.stderr[-3000:]
        return [line for line in proc.stdout.splitlines() if line.startswith("ROW")]

    blob = tmp_path / "state.bin"
    straight = run("none", blob, 0, 1000)
    first = run("save", blob, 0, 600)
    second = run("load", blob, 600, 400)
    assert first + second == straight
    assert blob.stat().st_size > 0


def _state_slave(fmu):
    slave = Slave(fmu, "blob")
    slave.fmu.enterInitializationMode()
    slave.fmu.exitInitializationMode()
    for k in range(5):
        slave.fmu.doStep(float(k), 1.0)
    return slave


def test_wrong_truncated_or_foreign_state_blobs_are_refused(fmu_dir, tmp_path):
    fmu = fmu_dir / "Turntable.fmu"
    slave = _state_slave(fmu)
    try:
        state = slave.fmu.getFMUstate()
        good = slave.fmu.serializeFMUstate(state)
        slave.fmu.freeFMUstate(state)
        corrupted = bytearray(good)
        corrupted[-9] ^= 0x40  # one bit of the payload
        other_guid = bytearray(good)
        other_guid[24:24 + 36] = b"00000000-0000-0000-0000-000000000000"
        cases = {"truncated": (good[:-8], "size does not match"), "header only": (good[:60], "shorter than the header"),
                 "corrupted": (bytes(corrupted), "checksum"), "another GUID": (bytes(other_guid), "GUID"),
                 "not a state": (b"\x00" * len(good), "magic")}
        for case, (blob, reason) in cases.items():
            slave.fmu.reset()
            slave.log.clear()
            with pytest.raises(FMICallException, match="status 3"):
                slave.fmu.deSerializeFMUstate(blob)
            assert any(status == 3 and reason in text for status, _, text in slave.log), (case, slave.log)
        slave.fmu.reset()  # the good blob still loads after all that
        state = slave.fmu.deSerializeFMUstate(good)
        slave.fmu.setFMUstate(state)
        slave.fmu.freeFMUstate(state)
        slave.fmu.doStep(5.0, 1.0)
    finally:
        slave.fmu.freeInstance()
        fmilog.unregister(slave.name)


def test_state_of_another_instance_with_other_parameters_is_rebuilt_from_its_own(fmu_dir):
    """Setting a state taken with other parameters rebuilds the schedule from the state's parameters."""
    fmu = fmu_dir / "Turntable.fmu"
    a, b = Slave(fmu, "a"), Slave(fmu, "b")
    try:
        a.set(**CASES["dual-axis chamber"])
        for s in (a, b):
            s.fmu.enterInitializationMode()
            s.fmu.exitInitializationMode()
        for k in range(50):
            a.fmu.doStep(float(k), 1.0)
            b.fmu.doStep(float(k), 1.0)
        state = a.fmu.getFMUstate()
        a.fmu.doStep(50.0, 1.0)
        # another instance takes it serialized (an in-memory state belongs to the instance that issued it)
        b.fmu.setFMUstate(b.fmu.deSerializeFMUstate(a.fmu.serializeFMUstate(state)))
        a.fmu.freeFMUstate(state)
        b.fmu.doStep(50.0, 1.0)
        assert b.get(*OUTPUTS) == a.get(*OUTPUTS)
        assert b.fmu.getInteger([b.vr["n_gimbals"]]) == [2]
    finally:
        a.free()
        b.free()


def test_state_taken_before_initialisation_restores_values_and_the_state_machine(fmu_dir):
    slave = Slave(fmu_dir / "Turntable.fmu", "early")
    try:
        f, vr = slave.fmu, slave.vr
        slave.set(rate=0.2)
        early = f.getFMUstate()  # state 'instantiated'
        slave.set(rate=0.3)
        f.setFMUstate(early)
        assert slave.get("rate") == [0.2]
        f.enterInitializationMode()
        f.exitInitializationMode()
        f.doStep(0.0, 1.0)
        f.setFMUstate(early)  # back before initialisation: stepping is refused again, by the state machine
        with pytest.raises(FMICallException, match="status 3"):
            f.doStep(1.0, 1.0)
        assert any("not allowed in state 'instantiated'" in text for status, _, text in slave.log if status == 3)
        f.reset()
        f.freeFMUstate(early)
        assert f.getInteger([vr["n_gimbals"]]) == [1]
    finally:
        slave.fmu.freeInstance()
        fmilog.unregister(slave.name)


# ----------------------------------------------------------------- allocations and sanitizers


def test_no_heap_allocation_after_initialisation(turntable, tmp_path):
    folder, md = turntable
    counter = tmp_path / "alloc_counter.so"
    build_line([_cc(), "-O2", "-shared", "-fPIC", "-o", str(counter), str(COUNTER_SRC), "-ldl"])
    host = tmp_path / "host"
    build_line([_cc(), "-std=c11", "-O2", f"-I{fmi_headers_dir()}", str(HOST_SRC), "-ldl", "-o", str(host)])
    proc = run_host(host, folder / "binaries" / "linux64" / "Turntable.so", md, 3000, "allocs",
                    *ops(md, CASES["dual-axis chamber"], outputs=[]),
                    env={"LD_PRELOAD": str(counter), "PATH": os.environ.get("PATH", "")})
    assert "STATUS" not in proc.stdout, proc.stdout[-2000:]
    assert "ALLOCS 0" in proc.stdout.splitlines(), proc.stdout[-2000:]


@pytest.mark.slow
def test_sanitized_build_runs_clean_through_the_c_host(turntable, tmp_path):
    """AddressSanitizer + UndefinedBehaviorSanitizer: the glue and the model, every call of a run, FMU state
    round trip, bad calls (the host's roundtrip and parameters); any report fails the run."""
    folder, md = turntable
    sources = folder / "sources"
    san = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-g", "-O1"]
    lib = tmp_path / "Turntable_san.so"
    files = sorted(str(p) for p in sources.glob("*.c"))
    build_line([_cc(), *[f for f in CFLAGS if f != "-O2"], *san, "-fPIC", "-shared", f"-I{sources}", *files,
                    "-lm", "-o", str(lib)])
    host = tmp_path / "host_san"
    build_line([_cc(), "-std=c11", *san, f"-I{fmi_headers_dir()}", str(HOST_SRC), "-ldl", "-o", str(host)])
    env = {"ASAN_OPTIONS": "detect_leaks=1", "UBSAN_OPTIONS": "print_stacktrace=1",
           "PATH": os.environ.get("PATH", "")}
    for values in CASES.values():
        proc = run_host(host, lib, md, 2000, "roundtrip=700", *ops(md, values), env=env, timeout=600)
        assert "STATUS" not in proc.stdout and "runtime error" not in proc.stderr, proc.stderr[-3000:]
        assert table(proc, "AGAIN")
    for bad in ({"scheme": "sideways"}, {"grid": float("nan")}, {"revolutions": 0}):
        proc = run_host(host, lib, md, 10, *ops(md, bad), env=env, timeout=600)
        assert "STATUS fmi2ExitInitializationMode 3" in proc.stdout and "ERROR" not in proc.stderr, proc.stderr


@pytest.mark.slow
def test_win64_dll_under_wine_matches_linux64(fmu_dir, turntable, host, tmp_path, wine_env):
    """The shipped win64 DLL, loaded by a mingw-built host under wine: the same outputs as linux64. The
    Turntable's outputs use + - * / and sin (the sinusoidal ambient; 0 amplitude here): bit-identical."""
    missing = [t for t in (MINGW, "wine") if shutil.which(t) is None]
    if missing:
        pytest.skip(f"{', '.join(missing)} not installed (Debian: apt-get install gcc-mingw-w64-x86-64 wine64)")
    folder, md = turntable
    dll = folder / "binaries" / "win64" / "Turntable.dll"
    assert dll.is_file(), "the build had mingw but shipped no win64 DLL"
    exe = tmp_path / "host.exe"
    build_line([MINGW, "-std=c11", "-O2", f"-I{fmi_headers_dir()}", str(HOST_SRC), "-static", "-o", str(exe)])
    env = wine_env
    for values in CASES.values():
        win = run_host(exe, dll, md, 1000, "roundtrip=500", *ops(md, values), env=env, prefix=["wine"],
                       timeout=600)
        lin = run_host(host, folder / "binaries" / "linux64" / "Turntable.so", md, 1000, "roundtrip=500",
                       *ops(md, values))
        assert "STATUS" not in win.stdout, win.stdout[-2000:]
        assert table(win) == table(lin) and table(win, "AGAIN") == table(lin, "AGAIN")
        assert win.stdout.rstrip().endswith("DONE 1")
