"""FMI 3.0 variants of the native FMUs (fmus/c/fmi3_glue.c over glue_core.c, the same model.c as FMI 2.0).

Checked on the Turntable: fmpy validate and the FMI 3.0 model description (same variables as FMI 2.0, n_sub
a structural parameter, plus the *_sub arrays and time); FMPy's simulate_fmu of the FMI 3.0 FMU equals
the FMI 2.0 FMU bit for bit; the master runs it in a system beside the FMI 2.0 one with the same numbers;
FMU state get/set and serialisation round trips, and refused blobs; calls out of order or with bad
arguments give fmi3Error with a logged reason; the binary imports no Python and exports fmi3* only;
sources/ builds with its documented line.
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess
import warnings
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave, fmi3Float64, fmi3ValueReference
from fmpy.validation import validate_fmu

from fmus.native_fmu import compile_sources

CASES = {
    "forward-reverse": {"align_time": 600.0},
    "dual-axis chamber": {"scheme": "dual-axis", "align_time": 0.0, "ambient_mode": "chamber",
                          "chamber_hold": 120.0, "chamber_ramp": 0.05, "ambient_mean": 25.0},
}
STEPS = 400
OUTPUTS = [f"{q}_{j}" for j in (1, 2, 3) for q in ("angle", "rate", "accel")] + [
    "ambient_temp", "ambient_temp_rate", "motion_time"]


@pytest.fixture(scope="module")
def turntables(fmu_dir, fmu3_dir):
    """{2: the session's FMI 2.0 Turntable.fmu, 3: its FMI 3.0 one (linux only: quick), from the same
    declaration and model.c."""
    return {2: fmu_dir / "Turntable.fmu", 3: fmu3_dir / "Turntable.fmu"}


@pytest.fixture(scope="module")
def unzipped(turntables, tmp_path_factory):
    folder = tmp_path_factory.mktemp("native3_unzipped")
    with zipfile.ZipFile(turntables[3]) as z:
        z.extractall(folder)
    return folder


class Logged:
    """An FMI 3.0 instance of the Turntable with its log messages collected."""

    def __init__(self, fmu: Path, folder: Path, name: str = "t3"):
        self.md = read_model_description(str(fmu))
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages: list[tuple[int, str]] = []

        def log(env, status, category, message):
            self.messages.append((status, message.decode()))

        self.slave = FMU3Slave(guid=self.md.guid, unzipDirectory=str(folder), modelIdentifier="Turntable",
                               instanceName=name)
        self.slave.instantiate(logMessage=log)

    def set(self, values: dict):
        for name, value in values.items():
            vr = [self.vr[name]]
            if isinstance(value, str):
                self.slave.setString(vr, [value])
            elif isinstance(value, int):
                self.slave.setInt32(vr, [value])
            else:
                self.slave.setFloat64(vr, [value])

    def outputs(self) -> list[float]:
        return self.slave.getFloat64([self.vr[n] for n in OUTPUTS])

    def errors(self) -> str:
        return "\n".join(m for s, m in self.messages if s >= 3)


def test_fmi3_turntable_validates_and_declares_the_fmi2_variables(turntables, unzipped):
    assert validate_fmu(str(turntables[3])) == []
    md2, md3 = (read_model_description(str(turntables[f])) for f in (2, 3))
    assert md3.fmiVersion == "3.0"
    cs = ET.parse(unzipped / "modelDescription.xml").getroot().find("CoSimulation").attrib
    assert (cs["canGetAndSetFMUState"], cs["canSerializeFMUState"], cs["needsExecutionTool"]) == ("true", "true",
                                                                                                "false")
    kinds = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean", "String": "String"}
    structural = {"n_sub": ("UInt64", "structuralParameter")}  # sizes the *_sub arrays (FMI 3.0 only)
    v2 = [(v.name, v.valueReference, *structural.get(v.name, (kinds[v.type], v.causality)), v.variability)
          for v in md2.modelVariables]
    v3 = [(v.name, v.valueReference, v.type, v.causality, v.variability) for v in md3.modelVariables]
    assert v3[:len(v2)] == v2
    sub = [f"{name}_sub" for name in [f"{q}_{j}" for q in ("angle", "rate", "accel") for j in (1, 2, 3)]
           + ["ambient_temp", "ambient_temp_rate"]]
    assert v3[len(v2):-1] == [(name, len(v2) + k, "Float64", "output", "continuous") for k, name in enumerate(sub)]
    assert v3[-1] == ("time", len(v2) + len(sub), "Float64", "independent", "continuous")
    outputs = [v.valueReference for v in md3.modelVariables if v.causality == "output"]
    assert [u.variable.valueReference for u in md3.outputs] == outputs
    assert sorted(u.variable.valueReference for u in md3.initialUnknowns) == outputs
    names = set(zipfile.ZipFile(turntables[3]).namelist())
    assert "binaries/x86_64-linux/Turntable.so" in names and "documentation/index.html" in names
    build = ET.parse(unzipped / "sources" / "buildDescription.xml").getroot()
    listed = {f.get("name") for f in build.iter("SourceFile")}
    assert {"fmi3_glue.c", "glue_core.c", "model.c"} <= listed
    assert listed == {p.name for p in (unzipped / "sources").glob("*.c")}


@pytest.mark.parametrize("case", list(CASES))
def test_fmpy_simulate_fmi3_equals_fmi2_bit_for_bit(turntables, case):
    runs = [simulate_fmu(str(turntables[f]), stop_time=float(STEPS), output_interval=1.0, start_values=CASES[case],
                         output=OUTPUTS) for f in (2, 3)]
    assert runs[0].dtype.names == runs[1].dtype.names and len(runs[0]) == STEPS + 1
    for name in runs[0].dtype.names:
        assert np.array_equal(runs[0][name], runs[1][name]), name
    assert np.ptp(runs[1]["angle_1"]) > 0.1  # the table moved


def test_the_master_runs_the_fmi3_turntable_beside_the_fmi2_one(turntables):
    from orchestration import Component, System, UnconnectedInputWarning, simulate_system

    params = CASES["dual-axis chamber"]
    system = System("tables", [Component("t2", str(turntables[2]), params),
                               Component("t3", str(turntables[3]), params)], [])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnconnectedInputWarning)
        result = simulate_system(system, 120.0, 1.0)
    for name in OUTPUTS:
        assert np.array_equal(result[f"t2.{name}"], result[f"t3.{name}"]), name
    assert np.ptp(result["t3.angle_2"]) > 0.1


def _run(t: Logged, start: float, steps: int) -> list[list[float]]:
    rows = []
    for k in range(steps):
        t.slave.doStep(start + k, 1.0)
        rows.append(t.outputs())
    return rows


def test_fmu_state_and_serialization_round_trip(turntables, unzipped):
    a = Logged(turntables[3], unzipped, "a")
    a.set(CASES["dual-axis chamber"])
    a.slave.enterInitializationMode(startTime=0.0)
    a.slave.exitInitializationMode()
    _run(a, 0.0, 100)
    state = a.slave.getFMUState()
    blob = a.slave.serializeFMUState(state)
    expected = _run(a, 100.0, 80)
    a.slave.setFMUState(state)
    assert a.slave.getFloat64([a.vr["motion_time"], len(a.md.modelVariables) - 1]) == [100.0, 100.0]
    assert _run(a, 100.0, 80) == expected
    # into another instance that never initialised: parameters, schedule and time come with the state
    b = Logged(turntables[3], unzipped, "b")
    restored = b.slave.deserializeFMUState(blob)
    b.slave.setFMUState(restored)
    assert _run(b, 100.0, 80) == expected
    for bad, reason in ((blob[:-3], "truncated"), (blob[:200] + bytes([blob[200] ^ 1]) + blob[201:], "checksum")):
        with pytest.raises(FMICallException):
            b.slave.deserializeFMUState(bad)
        assert reason in b.errors()
    # the state passed where its address belongs (fmusim c8d4e6d does so at --final-fmu-state-file): refused
    free = b.slave.dll["fmi3FreeFMUState"]
    free.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
    assert free(b.slave.component, restored.value) == 3
    assert "the FMU state itself" in b.errors()
    b.slave.reset()
    a.slave.freeFMUState(state)
    b.slave.freeFMUState(restored)
    assert not restored.value  # freeing sets the variable to NULL
    for slave in (a.slave, b.slave):
        slave.freeInstance()


def test_bad_calls_return_fmi3_error_with_a_logged_reason(turntables, unzipped):
    t = Logged(turntables[3], unzipped)
    s = t.slave
    vr_out = t.vr["angle_1"]

    def refused(call, *reason):
        before = len(t.messages)
        with pytest.raises(FMICallException):
            call()
        text = "\n".join(m for _, m in t.messages[before:])
        for part in reason:
            assert part in text, text
        s.reset()

    refused(lambda: s.doStep(0.0, 1.0), "fmi3DoStep", "not allowed in state 'instantiated'")
    refused(lambda: s.getFloat64([vr_out]), "fmi3GetFloat64", "not allowed in state 'instantiated'")
    refused(lambda: s.setFloat64([vr_out], [1.0]), "angle_1", "cannot be set")
    refused(lambda: s.setFloat64([10_000], [1.0]), "unknown value reference 10000")
    refused(lambda: s.setInt32([t.vr["rate"]], [1]), "rate", "not an Integer")
    refused(lambda: s.setFloat64([len(t.md.modelVariables) - 1], [3.0]), "time", "cannot be set")
    refused(lambda: s.setString([t.vr["scheme"]], ["x" * 5000]), "scheme", "at most 4095")
    refused(lambda: s.setUInt64([t.vr["n_sub"]], [2]), "n_sub", "cannot be set in state 'instantiated'")
    refused(lambda: s.enterEventMode(), "fmi3EnterEventMode", "hasEventMode is false")
    refused(lambda: s.getFloat32([vr_out]), "fmi3GetFloat32", "no Float32 variables")
    values = (fmi3Float64 * 2)(1.0, 2.0)
    refused(lambda: s.fmi3SetFloat64(s.component, (fmi3ValueReference * 1)(t.vr["rate"]), 1, values, 2),
            "2 values for value references holding 1")
    # a bad parameter is refused at fmi3ExitInitializationMode with the model's reason
    s.setFloat64([t.vr["grid"]], [-1.0])
    s.enterInitializationMode()
    refused(lambda: s.exitInitializationMode(), "grid")
    # after an error only Reset/FreeInstance help: the state machine says so
    s.setFloat64([t.vr["grid"]], [-1.0])
    s.enterInitializationMode()
    with pytest.raises(FMICallException):
        s.exitInitializationMode()
    with pytest.raises(FMICallException):
        s.doStep(0.0, 1.0)
    assert "call fmi3Reset, fmi3FreeInstance, or set an FMU state saved before the error" in t.errors()
    s.reset()
    s.enterInitializationMode(startTime=5.0)
    s.exitInitializationMode()
    refused(lambda: s.doStep(0.0, 1.0), "first communication point 0 is not the start time 5")
    s.freeInstance()
    assert all(status != 4 for status, _ in t.messages)  # never fmi3Fatal


def test_instantiation_refuses_a_foreign_token_and_event_mode(turntables, unzipped):
    md = read_model_description(str(turntables[3]))
    for guid, kwargs, reason in ((md.guid[:-1] + "0", {}, "does not match"),
                                 (md.guid, {"eventModeUsed": True}, "no Event Mode")):
        messages = []

        def log(env, status, category, message, messages=messages):
            messages.append(message.decode())

        slave = FMU3Slave(guid=guid, unzipDirectory=str(unzipped), modelIdentifier="Turntable", instanceName="x")
        with pytest.raises(Exception, match="Failed to instantiate"):
            slave.instantiate(logMessage=log, **kwargs)
        assert any(reason in m for m in messages), messages


def test_binary_imports_no_python_and_exports_fmi3_only(unzipped):
    if shutil.which("nm") is None:
        pytest.skip("nm not installed")
    so = unzipped / "binaries" / "x86_64-linux" / "Turntable.so"
    undefined = subprocess.run(["nm", "-D", "--undefined-only", str(so)], capture_output=True, text=True,
                               check=True).stdout.split()
    assert not [s for s in undefined if s.startswith("Py") or "python" in s.lower()]
    defined = [line.split()[-1] for line in subprocess.run(["nm", "-D", "--defined-only", str(so)],
                                                            capture_output=True, text=True, check=True)
               .stdout.splitlines() if line.split()[1] == "T"]
    assert defined and all(name.startswith("fmi3") for name in defined), defined
    for name in ("fmi3InstantiateCoSimulation", "fmi3DoStep", "fmi3GetFloat64", "fmi3SerializeFMUState",
                 "fmi3EnterConfigurationMode", "fmi3GetVersion"):
        assert name in defined
    lib = ctypes.CDLL(str(so))
    lib.fmi3GetVersion.restype = ctypes.c_char_p
    assert lib.fmi3GetVersion() == b"3.0"


def test_sources_build_with_the_documented_line(unzipped, tmp_path):
    built = compile_sources(unzipped / "sources", "Turntable", tmp_path)
    defined = subprocess.run(["nm", "-D", "--defined-only", str(built)], capture_output=True, text=True,
                             check=True).stdout if shutil.which("nm") else "fmi3DoStep"
    assert "fmi3DoStep" in defined
