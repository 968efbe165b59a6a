"""FMI 3.0 arrays in the native glue (model.h's array extension), on the test model Burst
(tests/native_models: not shipped): an output array and an input array sized by the structural parameter
n_sub, set in Configuration Mode; the FMI 2.0 variant of the same model.c has no arrays.
"""

from __future__ import annotations

import warnings
import zipfile
from pathlib import Path
from xml.etree import ElementTree as ET

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

from fmus.native_fmu import MAX_DIM, NativeModel, build_native_fmu
from native_models.burst_slave import Burst

HERE = Path(__file__).resolve().parent
# value references of Burst: its declaration's order, then the arrays, then time
N_SUB, SLOPE, U, Y, WSUM, STEPS, SAMPLES, W, TIME = range(9)


@pytest.fixture(scope="module")
def bursts(tmp_path_factory):
    """{2: Burst.fmu for FMI 2.0, 3: for FMI 3.0, and their unzipped folders 'dir2', 'dir3'}."""
    base = tmp_path_factory.mktemp("burst")
    model = NativeModel(str(HERE / "native_models" / "burst"))
    out = {}
    for fmi in (2, 3):
        fmu = build_native_fmu("Burst", None, base / f"fmi{fmi}", fmi=fmi, win64=False, aarch64=False, model=model,
                               slave=Burst(instance_name="build", resources="."))
        out[fmi] = fmu
        with zipfile.ZipFile(fmu) as z:
            z.extractall(base / f"dir{fmi}")
        out[f"dir{fmi}"] = base / f"dir{fmi}"
    return out


class Instance:
    def __init__(self, bursts, name="b"):
        self.messages = []

        def log(env, status, category, message):
            self.messages.append((status, message.decode()))

        md = read_model_description(str(bursts[3]))
        self.s = FMU3Slave(guid=md.guid, unzipDirectory=str(bursts["dir3"]), modelIdentifier="Burst",
                           instanceName=name)
        self.s.instantiate(logMessage=log)

    def configure(self, n):
        self.s.enterConfigurationMode()
        self.s.setUInt64([N_SUB], [n])
        self.s.exitConfigurationMode()

    def errors(self):
        return "\n".join(m for st, m in self.messages if st >= 3)


def test_model_descriptions_validate_and_declare_the_arrays_in_fmi3_only(bursts):
    for fmi in (2, 3):
        assert validate_fmu(str(bursts[fmi])) == []
    root = ET.parse(bursts["dir3"] / "modelDescription.xml").getroot()
    n_sub = root.find("ModelVariables/UInt64[@name='n_sub']")
    assert n_sub.get("causality") == "structuralParameter" and n_sub.get("valueReference") == str(N_SUB)
    for name, vr in (("samples", SAMPLES), ("w", W)):
        node = root.find(f"ModelVariables/Float64[@name='{name}']")
        assert node.get("valueReference") == str(vr)
        assert node.find("Dimension").get("valueReference") == str(N_SUB)
    assert root.find(f"ModelStructure/Output[@valueReference='{SAMPLES}']").get("dependencies") == str(U)
    md2 = read_model_description(str(bursts[2]))
    assert [v.name for v in md2.modelVariables] == ["n_sub", "slope", "u", "y", "wsum", "steps"]
    assert md2.modelVariables[0].causality == "parameter" and md2.modelVariables[0].type == "Integer"


def test_arrays_carry_every_interval_of_the_step(bursts):
    b = Instance(bursts)
    s = b.s
    b.configure(5)
    s.setFloat64([SLOPE, U], [3.0, 0.25])
    s.setFloat64([W], [1.0, 2.0, 3.0, 4.0, 5.5])
    s.enterInitializationMode(startTime=1.0)
    s.exitInitializationMode()
    s.doStep(1.0, 0.5)
    expected = [3.0 * (1.0 + 0.5 * (k + 1) / 5) + 0.25 for k in range(5)]
    assert s.getFloat64([SAMPLES], 5) == expected
    # scalars and arrays in one call, the values of each variable after each other
    assert s.getFloat64([Y, SAMPLES, WSUM, TIME], 8) == [expected[-1], *expected, 15.5, 1.5]
    assert s.getUInt64([N_SUB]) == [5] and s.getInt32([STEPS]) == [1]
    s.setFloat64([W], [0.0] * 5)
    s.doStep(1.5, 0.5)
    assert s.getFloat64([WSUM]) == [0.0]
    s.terminate()
    s.freeInstance()


def test_fmi2_variant_runs_the_same_model_without_arrays(bursts):
    from fmu_driver import Slave

    two = Slave(bursts[2], "b2")
    b = Instance(bursts)
    try:
        two.set(n_sub=6, slope=1.5)
        b.configure(6)
        b.s.setFloat64([SLOPE], [1.5])
        for f in (two.fmu, b.s):
            f.enterInitializationMode()
            f.exitInitializationMode()
        for k in range(20):
            two.fmu.doStep(k * 0.25, 0.25)
            b.s.doStep(k * 0.25, 0.25)
            assert two.fmu.getReal([Y]) == b.s.getFloat64([Y])
        with pytest.raises(FMICallException):
            two.fmu.getReal([SAMPLES])  # no arrays in FMI 2.0: an unknown value reference
    finally:
        two.free()
        b.s.freeInstance()


def test_bad_array_calls_give_fmi3_error_with_the_reason(bursts):
    b = Instance(bursts)
    s = b.s

    def refused(call, *reason):
        before = len(b.messages)
        with pytest.raises(FMICallException):
            call()
        text = "\n".join(m for _, m in b.messages[before:])
        for part in reason:
            assert part in text, text
        s.reset()

    refused(lambda: s.setUInt64([N_SUB], [5]), "n_sub", "cannot be set in state 'instantiated'")
    s.enterConfigurationMode()
    refused(lambda: s.setUInt64([N_SUB], [0]), "n_sub = 0 must be in 1 .. 100000")
    s.enterConfigurationMode()
    refused(lambda: s.setUInt64([N_SUB], [MAX_DIM + 1]), f"must be in 1 .. {MAX_DIM}")
    s.enterConfigurationMode()
    refused(lambda: s.setFloat64([SLOPE], [1.0]), "slope", "cannot be set in state 'configurationMode'")
    s.enterConfigurationMode()
    refused(lambda: s.getInt32([N_SUB]), "n_sub", "UInt64")
    refused(lambda: s.setFloat64([W], [1.0, 2.0]), "2 values for value references holding 4")
    s.enterConfigurationMode()
    refused(lambda: s.getUInt64([SLOPE]), "slope")
    assert all(st != 4 for st, _ in b.messages)
    s.freeInstance()


def test_state_round_trip_keeps_the_arrays_and_their_length(bursts):
    a = Instance(bursts, "a")
    a.configure(7)
    a.s.setFloat64([W], [float(k) for k in range(7)])
    a.s.enterInitializationMode()
    a.s.exitInitializationMode()
    for k in range(3):
        a.s.doStep(k * 1.0, 1.0)
    state = a.s.getFMUState()
    blob = a.s.serializeFMUState(state)
    mark = a.s.getFloat64([SAMPLES, W, WSUM], 15)
    # the declared start values (slope 2, u 0): step [2, 3] in 7 intervals
    assert mark[:7] == [2.0 * (2.0 + (k + 1) / 7) for k in range(7)] and mark[-1] == 21.0
    a.s.setFloat64([W], [9.0] * 7)
    a.s.doStep(3.0, 1.0)
    a.s.setFMUState(state)
    assert a.s.getFloat64([SAMPLES, W, WSUM], 15) == mark
    # another instance with the default n_sub = 4 takes the 7-element arrays from the state
    b = Instance(bursts, "b")
    b.s.setFMUState(b.s.deserializeFMUState(blob))
    assert b.s.getUInt64([N_SUB]) == [7]
    assert b.s.getFloat64([SAMPLES, W, WSUM], 15) == mark
    a.s.doStep(3.0, 1.0)
    b.s.doStep(3.0, 1.0)
    assert b.s.getFloat64([SAMPLES, WSUM, Y], 9) == a.s.getFloat64([SAMPLES, WSUM, Y], 9)
    bad = bytearray(blob)
    bad[-8:] = b"\0" * 8  # the last array element changed: the checksum no longer matches
    with pytest.raises(FMICallException):
        b.s.deserializeFMUState(bytes(bad))
    assert "checksum" in b.errors()
    a.s.freeFMUState(state)
    for f in (a.s, b.s):
        f.freeInstance()


def test_the_master_moves_a_whole_array_from_one_fmu_to_the_next(bursts):
    from orchestration import Component, Connection, System, UnconnectedInputWarning, simulate_system

    system = System("bursts", [Component("a", str(bursts[3]), {"n_sub": 5, "slope": 2.0}),
                               Component("b", str(bursts[3]), {"n_sub": 5})],
                    [Connection.between("a.samples", "b.w")])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnconnectedInputWarning)
        result = simulate_system(system, 2.0, 0.5)
    samples = np.array([result[f"a.samples[{k}]"] for k in range(1, 6)])
    assert np.allclose(samples[:, -1], [2.0 * (1.5 + 0.5 * k / 5) for k in range(1, 6)], rtol=0, atol=1e-15)
    wsum = np.asarray(result["b.wsum"])
    sums = samples.sum(axis=0)
    # Gauss-Seidel (a before b): b sums the whole array a wrote in the same step, in one fmi3SetFloat64
    assert np.array_equal(wsum, sums) and wsum[-1] == 18.0
