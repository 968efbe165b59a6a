"""The shared native glue (fmus/c/glue_core.c, fmi2_glue.c, fmi3_glue.c) against what a host can hand it:
FMI 3.0 arrays after a structural parameter changed, FMU-state pointers that are freed or foreign, state
blobs whose fields break the model's invariants (checksum recomputed), and recovery by restoring a state
saved before an error.  Driven through FMPy's low-level FMU2Slave / FMU3Slave, and (pointer safety) through
a C program built with AddressSanitizer and UBSan against each FMU's sources."""

from __future__ import annotations

import math
import os
import re
import shutil
import struct
import subprocess
import zipfile
from pathlib import Path

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave

from fmus.cbuild import build_line
from fmus.native_fmu import build_native_fmu

pytestmark = pytest.mark.integration


@pytest.fixture(scope="module")
def fmus3(tmp_path_factory):
    """The FMI 3.0 IMUThermal and StrapdownINS (linux only: quick)."""
    if shutil.which("gcc") is None and shutil.which("cc") is None:
        pytest.skip("no C compiler (gcc/cc)")
    out = tmp_path_factory.mktemp("glue_safety3")
    for name, slave in (("IMUThermal", "imu_thermal_slave.py"), ("StrapdownINS", "strapdown_ins_slave.py")):
        build_native_fmu(name, slave, out, fmi=3, win64=False, aarch64=False)
    return out


class Fmu3:
    """An FMI 3.0 instance with its log kept."""

    def __init__(self, path, name: str = "x"):
        self.md = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages: list[str] = []

        def log(env, status, category, message):
            self.messages.append(message.decode())

        self.s = FMU3Slave(guid=self.md.guid, unzipDirectory=extract(str(path)),
                           modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=name)
        self.s.instantiate(logMessage=log)


@pytest.mark.parametrize("name,array", [("IMUThermal", "dtheta_x_sub"), ("StrapdownINS", "dv_z_sub")])
@pytest.mark.parametrize("n_sub", [2, 100_000])
def test_array_access_is_bounded_by_what_was_allocated(fmus3, name, array, n_sub):
    """n_sub set in Configuration Mode, the arrays read (or written) before it is left: refused with
    fmi3Error naming n_sub, never another array's memory or a read past the buffer (1 element is allocated);
    once Configuration Mode is left the arrays have the new length."""
    f = Fmu3(fmus3 / f"{name}.fmu")
    try:
        f.s.enterConfigurationMode()
        f.s.setUInt64([f.vr["n_sub"]], [n_sub])
        with pytest.raises(FMICallException):
            f.s.getFloat64([f.vr[array]], n_sub)
        assert "n_sub = %d" % n_sub in f.messages[-1] and array in f.messages[-1], f.messages
        f.s.reset()
        f.s.enterConfigurationMode()
        f.s.setUInt64([f.vr["n_sub"]], [n_sub])
        with pytest.raises(FMICallException):
            f.s.getFloat64([f.vr[array]], 1)  # the allocated length is not a way round it
        f.s.reset()
        f.s.enterConfigurationMode()
        f.s.setUInt64([f.vr["n_sub"]], [n_sub])
        f.s.exitConfigurationMode()
        f.s.enterInitializationMode()
        assert len(f.s.getFloat64([f.vr[array]], n_sub)) == n_sub
    finally:
        f.s.freeInstance()


HOST_DIR = Path(__file__).resolve().parent / "native_host"
SAN = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-g", "-O1"]


def _sanitized(fmu: Path, program: str, tmp_path: Path, fmi: int) -> Path:
    """``program`` (tests/native_host) linked with the FMU's ``sources/``, ASan + UBSan."""
    cc = shutil.which("gcc") or shutil.which("cc")
    src = tmp_path / f"src{fmi}"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(src)
    src = src / "sources"
    exe = tmp_path / f"{Path(program).stem}{fmi}"
    build_line([cc, "-std=c11", *SAN, *(["-DFMI3"] if fmi == 3 else []), f"-I{src}", str(HOST_DIR / program),
                    *sorted(str(p) for p in src.glob("*.c")), "-o", str(exe)])
    return exe


@pytest.fixture(scope="module")
def turntables(tmp_path_factory):
    """The FMI 2.0 and 3.0 Turntable (every native model shares the glue under test)."""
    if shutil.which("gcc") is None and shutil.which("cc") is None:
        pytest.skip("no C compiler (gcc/cc)")
    out = tmp_path_factory.mktemp("glue_safety_tt")
    return {fmi: build_native_fmu("Turntable", "turntable_slave.py", out / str(fmi), fmi=fmi, win64=False,
                                  aarch64=False) for fmi in (2, 3)}


@pytest.mark.parametrize("fmi", [2, 3])
def test_freed_and_foreign_states_are_refused_without_reading_them(turntables, tmp_path, fmi):
    """Under ASan: a freed, another instance's or a made-up FMUstate passed to Set / Free / SerializedSize /
    Serialize (or as *FMUstate of Get) is an error status, with no use-after-free; a live state still works;
    states the host never freed go with the instance (no leak)."""
    exe = _sanitized(turntables[fmi], "state_pointers.c", tmp_path, fmi)
    guid = read_model_description(str(turntables[fmi])).guid
    proc = subprocess.run([str(exe), guid], capture_output=True, text=True, timeout=120,
                          env={"PATH": os.environ.get("PATH", ""), "ASAN_OPTIONS": "detect_leaks=1"})
    assert proc.returncode == 0 and "DONE" in proc.stdout, proc.stderr[-3000:]
    cases = dict(line.split()[1:] for line in proc.stdout.splitlines() if line.startswith("CASE"))
    assert cases.pop("set_kept") == "0" and cases.pop("free_kept") == "0"
    assert cases and set(cases.values()) == {"3"}, cases
    assert "not a live FMU state of this instance" in proc.stdout


def _outputs(md) -> list[int]:
    return [v.valueReference for v in md.modelVariables if v.causality == "output" and v.type in ("Real", "Float64")
            and not v.dimensions]


@pytest.mark.parametrize("fmi", [2, 3])
def test_restoring_a_state_saved_before_an_error_recovers_bit_for_bit(fmus3, turntables, fmi):
    """error (a refused blob, then a step at a wrong communication point) -> set the state saved before it ->
    the run continues with the numbers of a run without the error, bit for bit (IMUThermal FMI 3.0: random
    streams and minor loop in the work state; Turntable FMI 2.0)."""
    from fmpy.fmi2 import FMU2Slave

    path = fmus3 / "IMUThermal.fmu" if fmi == 3 else turntables[2]
    md = read_model_description(str(path))
    outs = _outputs(md)
    messages: list[str] = []
    if fmi == 3:
        f = Fmu3(path)
        s, messages = f.s, f.messages
        s.enterInitializationMode(startTime=0.0)
        get, get_state, set_state, free_state = s.getFloat64, s.getFMUState, s.setFMUState, s.freeFMUState
        deserialize = s.deserializeFMUState
    else:
        s = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="t")
        s.instantiate()
        s.setupExperiment(startTime=0.0)
        s.enterInitializationMode()
        get, get_state, set_state, free_state = s.getReal, s.getFMUstate, s.setFMUstate, s.freeFMUstate
        deserialize = s.deSerializeFMUstate
    try:
        s.exitInitializationMode()
        for k in range(5):
            s.doStep(float(k), 1.0)
        saved = get_state()
        clean = []
        for k in range(5, 10):
            s.doStep(float(k), 1.0)
            clean.append(get(outs))
        for make_error in (lambda: deserialize(b"SARINSst" + bytes(200)), lambda: s.doStep(123.0, 1.0)):
            set_state(saved)
            s.doStep(5.0, 1.0)
            with pytest.raises(FMICallException):
                make_error()
            with pytest.raises(FMICallException):
                s.doStep(6.0, 1.0)  # in the error state
            set_state(saved)  # recovery
            again = []
            for k in range(5, 10):
                s.doStep(float(k), 1.0)
                again.append(get(outs))
            assert again == clean, messages[-3:]
        free_state(saved)
    finally:
        s.freeInstance()


HEADER, FIXED = 104, 56  # glue_core.c: the blob's header bytes; the payload's fixed part (state .. counts)
MODEL_H = Path(__file__).resolve().parents[1] / "fmus" / "c" / "model.h"
STRING_MAX = int(re.search(r"#define SARINS_STRING_MAX (\d+)", MODEL_H.read_text())[1])  # bytes per String


def _fnv1a(data: bytes) -> int:
    h = 1469598103934665603
    for b in data:
        h = ((h ^ b) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return h


def _resealed(blob: bytearray) -> bytes:
    blob[96:104] = struct.pack("<Q", _fnv1a(bytes(blob[HEADER:])))
    return bytes(blob)


def _model_state_offset(blob: bytes, n_vars: int) -> int:
    nr, ni, nb, ns = struct.unpack_from("<4Q", blob, HEADER + 24)
    return HEADER + FIXED + 8 * nr + 4 * ni + 4 * nb + STRING_MAX * ns + n_vars + 8


def test_states_breaking_the_model_invariants_are_refused(fmus3):
    """StrapdownINS states with the checksum recomputed: the compensation queue's ring index out of its buffer
    (comp.first = -51), its length negative or beyond it, phase 99, step NaN, the glue's next communication
    point NaN: each refused with an error at fmi3DeserializeFMUState, the field named; the unchanged blob
    is taken."""
    from sarins_fmu.core.ins import _FMU_OFFSETS, _FMU_SIZE

    f = Fmu3(fmus3 / "StrapdownINS.fmu")
    s = f.s
    try:
        s.enterInitializationMode(startTime=0.0)
        s.exitInitializationMode()
        blob = s.serializeFMUState(s.getFMUState())
        base = next(_model_state_offset(blob, n) for n in range(len(f.md.modelVariables) + 2)
                    if struct.unpack_from("<Q", blob, _model_state_offset(blob, n) - 8)[0] == _FMU_SIZE)
        phase, count = base + int(_FMU_OFFSETS[1]), base + int(_FMU_OFFSETS[4])
        cases = {"comp.first": (count - 8, "<q", -51), "comp.count": (count, "<q", -1),
                 "comp.count ": (count, "<q", 257), "phase": (phase, "<q", 99), "step": (phase - 16, "<d", math.nan),
                 "communication point": (HEADER + 8, "<d", math.nan)}
        for field, (at, fmt, value) in cases.items():
            bad = bytearray(blob)
            struct.pack_into(fmt, bad, at, value)
            f.messages.clear()
            with pytest.raises(FMICallException):
                s.deserializeFMUState(_resealed(bad))
            assert any(field.strip() in m for m in f.messages), (field, f.messages)
            s.reset()  # leave the error state
            s.enterInitializationMode(startTime=0.0)
            s.exitInitializationMode()
        good = s.deserializeFMUState(_resealed(bytearray(blob)))
        s.setFMUState(good)
        s.freeFMUState(good)
    finally:
        s.freeInstance()
