"""The FMI 2.0 contract of the native layer, through FMPy's low-level API:
state machine (FMI 2.0 section 4.2.4), value references and types, GUID,
logging with loggingOn at instantiation, non-finite outputs, the library
the FMU runs."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

from fmu_driver import Slave
from orchestration import fmilog

ERROR = "status 3"


@pytest.fixture(scope="module")
def fmus(fmu_dir):
    return {name: fmu_dir / f"{name}.fmu" for name in ("Turntable", "DriftModelUpdater")}


@pytest.fixture
def turntable(fmus):
    slave = Slave(fmus["Turntable"], "tt")
    yield slave
    slave.fmu.freeInstance()
    fmilog.unregister(slave.name)


def errors(slave):
    return [m for status, _, m in slave.log if status == 3]


def test_calls_out_of_order_are_errors_with_a_message(fmus):
    cases = [
        ("exit initialisation without entering it", lambda f: f.exitInitializationMode(), "not allowed in state"),
        ("doStep before initialisation", lambda f: f.doStep(0.0, 1.0), "fmi2DoStep: not allowed in state "
                                                                      "'instantiated'"),
        ("terminate before initialisation", lambda f: f.terminate(), "fmi2Terminate: not allowed"),
    ]
    for _, call, text in cases:
        slave = Slave(fmus["Turntable"], "tt")
        try:
            with pytest.raises(FMICallException, match=ERROR):
                call(slave.fmu)
            assert any(text in m for m in errors(slave)), slave.log
            with pytest.raises(FMICallException, match=ERROR):  # the instance is now in the error state
                slave.fmu.enterInitializationMode()
            slave.fmu.reset()  # ... which fmi2Reset leaves
            slave.fmu.enterInitializationMode()
            slave.fmu.exitInitializationMode()
            slave.fmu.doStep(0.0, 1.0)
        finally:
            slave.fmu.freeInstance()
            fmilog.unregister(slave.name)


def test_step_after_terminate_and_non_contiguous_times_are_errors(turntable):
    f = turntable.fmu
    f.enterInitializationMode()
    f.exitInitializationMode()
    f.doStep(0.0, 1.0)
    with pytest.raises(FMICallException, match=ERROR):
        f.doStep(5.0, 1.0)
    assert any("does not continue the previous step" in m for m in errors(turntable))
    f.reset()
    f.enterInitializationMode()
    f.exitInitializationMode()
    f.doStep(0.0, 1.0)
    f.terminate()
    with pytest.raises(FMICallException, match=ERROR):
        f.doStep(1.0, 1.0)
    assert any("fmi2DoStep: not allowed in state 'terminated'" in m for m in errors(turntable))


def test_setting_an_output_or_a_fixed_parameter_after_initialisation_is_an_error(turntable):
    f, vr = turntable.fmu, turntable.vr
    with pytest.raises(FMICallException, match=ERROR):
        f.setReal([vr["angle_1"]], [1.0])  # an output, never settable
    assert any("angle_1" in m and "causality output" in m for m in errors(turntable))
    f.reset()
    f.enterInitializationMode()
    f.exitInitializationMode()
    with pytest.raises(FMICallException, match=ERROR):
        f.setReal([vr["rate"]], [0.2])  # a fixed parameter after initialisation
    assert any("rate" in m and "variability fixed" in m for m in errors(turntable))


def test_unknown_value_reference_and_wrong_type_are_errors_not_fatal(turntable):
    f, vr = turntable.fmu, turntable.vr
    f.enterInitializationMode()
    f.exitInitializationMode()
    with pytest.raises(FMICallException, match=ERROR):
        f.getReal([99999])
    f.reset()
    f.enterInitializationMode()
    f.exitInitializationMode()
    with pytest.raises(FMICallException, match=ERROR):
        f.getReal([vr["n_gimbals"]])
    f.reset()
    with pytest.raises(FMICallException, match=ERROR):
        f.setInteger([vr["scheme"]], [3])
    text = errors(turntable)
    assert any("unknown value reference 99999" in m for m in text)
    assert any("n_gimbals" in m and "is an Integer, not a Real" in m for m in text)
    assert any("scheme" in m and "is a String, not an Integer" in m for m in text)


def test_a_second_instance_runs_after_many_bad_calls(fmus):
    first = Slave(fmus["Turntable"], "bad")
    try:
        for _ in range(5):
            with pytest.raises(FMICallException, match=ERROR):
                first.fmu.getReal([424242])
            first.fmu.reset()
    finally:
        first.fmu.freeInstance()
        fmilog.unregister(first.name)
    second = Slave(fmus["Turntable"], "good")
    try:
        second.fmu.enterInitializationMode()
        second.fmu.exitInitializationMode()
        for k in range(10):
            second.fmu.doStep(float(k), 1.0)
        assert second.get("ambient_temp")[0] == 20.0  # the default sinusoid has no amplitude
    finally:
        second.free()


def test_wrong_guid_gives_no_instance_and_a_message(fmus):
    md = read_model_description(str(fmus["Turntable"]))
    log = []
    name = fmilog.register("guid", lambda status, category, text: log.append((status, text)))
    fmu = FMU2Slave(guid="not-the-guid", unzipDirectory=extract(str(fmus["Turntable"])),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
    try:
        with pytest.raises(Exception, match="instantiate"):  # noqa: B017 - FMPy raises a bare Exception
            fmu.instantiate(loggingOn=False, callbacks=fmilog.callbacks())
        assert any(status == 3 and "GUID" in text for status, text in log), log
    finally:
        fmilog.unregister(name)


def test_messages_reach_the_logger_when_logging_was_on_at_instantiation(fmus):
    """No fmi2SetDebugLogging call: loggingOn at instantiation is enough; categories are the model's."""
    slave = Slave(fmus["Turntable"], "log")
    try:
        slave.set(scheme="sideways")
        slave.fmu.enterInitializationMode()
        with pytest.raises(FMICallException, match=ERROR):
            slave.fmu.exitInitializationMode()
        assert any(cat == "logStatusError" and "unknown scheme" in m for status, cat, m in slave.log), slave.log
    finally:
        slave.fmu.freeInstance()
        fmilog.unregister(slave.name)


def test_non_finite_output_is_never_returned_with_ok(fmus):
    """DriftModelUpdater: an input of 1e200 degC is refused by the slave; a model that overflows
    to inf (a0 = 1e307 at 100 degC) is caught by the layer: fmi2Error naming the output."""
    slave = Slave(fmus["DriftModelUpdater"], "inf")
    try:
        slave.fmu.enterInitializationMode()
        slave.fmu.exitInitializationMode()
        slave.set(temp_gyro_z=1e200)
        with pytest.raises(FMICallException, match=ERROR):
            slave.fmu.doStep(0.0, 1.0)
        slave.fmu.reset()
        slave.set(a0=1e307, temp_gyro_z=100.0)
        slave.fmu.enterInitializationMode()
        with pytest.raises(FMICallException, match=ERROR):
            slave.fmu.exitInitializationMode()
        text = errors(slave)
        assert any("NaN or infinity" in m for m in text), text
        assert any("output compensation_drift = inf is not finite" in m for m in text), text
    finally:
        slave.fmu.freeInstance()
        fmilog.unregister(slave.name)


def test_fmu_runs_its_own_library_whatever_the_host_imported(fmus, tmp_path):
    """A different 'sarins_fmu' is imported first; the FMU still runs the copy it ships."""
    fake = tmp_path / "fake" / "sarins_fmu"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text("__version__ = 'fake'\nFAKE = True\n")
    (fake / "turntable.py").write_text("raise ImportError('the fake library was used')\n")
    tests = os.path.dirname(__file__)
    script = textwrap.dedent(f"""
        import sys
        sys.path.insert(0, {str(tmp_path / 'fake')!r})
        import sarins_fmu
        assert sarins_fmu.FAKE
        sys.path[1:1] = [{tests!r}, {os.path.dirname(tests)!r}]
        from fmu_driver import Slave
        s = Slave(__import__('pathlib').Path({str(fmus['Turntable'])!r}), 'tt')
        s.fmu.enterInitializationMode(); s.fmu.exitInitializationMode()
        for k in range(300):
            s.fmu.doStep(float(k), 1.0)
        rate = s.get('rate_1')[0]
        s.free()
        assert sys.modules['sarins_fmu'].FAKE and 'sarins_fmu.turntable' not in sys.modules
        print('ok', rate)
    """)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300, env=env,
                          cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "ok" in proc.stdout


FAULTS = """
import math, sys
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave
path = {path!r}
md = read_model_description(path)
unzipped = extract(path)
vars_ = {{v.name: v for v in md.modelVariables}}
by_type = lambda t, c=None: [v for v in md.modelVariables if v.type == t and (c is None or v.causality == c)]
def new(guid=md.guid):
    f = FMU2Slave(guid=guid, unzipDirectory=unzipped, modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName="fault")
    f.instantiate()
    return f
def init(f):
    f.setupExperiment(startTime=0.0); f.enterInitializationMode(); f.exitInitializationMode(); return f
real = by_type("Real")[0].valueReference
integer = (by_type("Integer") or [None])[0]
output = (by_type("Real", "output") or [None])[0]
fixed = [v for v in md.modelVariables if v.causality == "parameter" and v.variability == "fixed" and v.type == "Real"]
scenarios = {{
    "exit init without enter": lambda: new().exitInitializationMode(),
    "doStep before init": lambda: new().doStep(0.0, 1.0),
    "terminate before init": lambda: new().terminate(),
    "doStep after terminate": lambda: (lambda f: (f.doStep(0.0, 1.0), f.terminate(), f.doStep(1.0, 1.0)))(init(new())),
    "non-contiguous time": lambda: (lambda f: (f.doStep(0.0, 1.0), f.doStep(7.0, 1.0)))(init(new())),
    "negative step": lambda: init(new()).doStep(0.0, -1.0),
    "nan step": lambda: init(new()).doStep(0.0, math.nan),
    "unknown vr getReal": lambda: init(new()).getReal([987654]),
    "unknown vr setReal": lambda: new().setReal([987654], [1.0]),
    "unknown vr getString": lambda: init(new()).getString([987654]),
    "wrong type getInteger": lambda: init(new()).getInteger([real]),
    "wrong type setString": lambda: new().setString([real], [b"x"]),
    "set output": lambda: new().setReal([output.valueReference], [1.0]) if output else None,
    "set fixed parameter after init": lambda: init(new()).setReal([fixed[0].valueReference], [1.0]) if fixed else None,
    "wrong guid": lambda: new(guid="{{00000000-0000-0000-0000-000000000000}}"),
    "get FMU state": lambda: init(new()).getFMUState(),
}}
for name, v in vars_.items():
    if v.causality == "input" and v.type == "Real":
        scenarios[f"NaN input {{name}}"] = (lambda vr: lambda: (lambda f: (f.setReal([vr], [math.nan]),
                                                                          f.doStep(0.0, 1.0)))(init(new())))(v.valueReference)
errors, accepted = 0, []
for name, run in scenarios.items():
    try:
        run()
        accepted.append(name)  # e.g. a NaN input the model tolerates (no crash either way)
    except Exception:
        errors += 1  # an error status or a NULL instance
print("TRIED", len(scenarios), "ERROR", errors, "ACCEPTED", accepted)
for k in range(3):  # many bad calls later, a fresh instance still runs
    try:
        init(new()).getReal([424242])
    except FMICallException:
        pass
f = init(new())
for k in range(5):
    f.doStep(float(k), 1.0)
print("OK")
"""


@pytest.mark.slow
@pytest.mark.parametrize("name", ["Turntable", "IMUThermal", "StrapdownINS", "RBFIdentifier", "DriftModelUpdater",
                                  "VehicleMotion"])
def test_fault_suite_never_crashes_the_host(fmu_dir, name):
    """Every scenario of issue 14 on every FMU in one fresh FMPy process: no crash, clean exit."""
    fmu = fmu_dir / f"{name}.fmu"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    proc = subprocess.run([sys.executable, "-c", FAULTS.format(path=str(fmu))], capture_output=True, text=True,
                          timeout=900, env=env)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    assert "OK" in proc.stdout and "TRIED" in proc.stdout, proc.stdout
    accepted = proc.stdout.split("ACCEPTED")[1].split("\n")[0]
    assert all(name.strip(" '").startswith("NaN input") for name in accepted.strip(" []").split(",") if name.strip()), \
        accepted  # only NaN inputs a model tolerates may be accepted
