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


def _tiny_log(folder):
    """A 20 s static IMU log (1 s rows) for the IMULog FMU."""
    import numpy as np

    from sarins_fmu.imu_log import write_log

    n = 20
    time = np.arange(1.0, n + 1.0)
    dtheta = np.tile([0.0, 6.4e-5, 3.5e-5], (n, 1))  # rad per s: the earth rate at 28 deg
    dv = np.tile([0.0, 0.0, 9.79], (n, 1))  # m/s per s: gravity
    return write_log(folder / "tiny.csv", time, dtheta, dv, lat_deg=28.2)


FMUS = ["Turntable", "IMUThermal", "StrapdownINS", "RBFIdentifier", "DriftModelUpdater", "VehicleMotion", "IMULog", "GNSSReceiver",
        "AidedINS", "TrajectoryIMU"]


def fault_table(fmu_dir, tmp_path, names=FMUS, timeout=600):
    """Run tests/fmu_faults.py on each FMU in a fresh process; rows (model, category, case, outcome, detail)."""
    import json

    rows = []
    for name in names:
        base = [f"log_file={_tiny_log(tmp_path)}"] if name == "IMULog" else []
        cmd = [sys.executable, os.path.join(os.path.dirname(__file__), "fmu_faults.py"), str(fmu_dir / f"{name}.fmu"),
               *base]
        env = dict(os.environ, PYTHONPATH=os.pathsep.join([os.path.dirname(os.path.dirname(__file__)),
                                                           os.path.dirname(__file__)]))
        try:
            proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env, cwd=tmp_path)
            out, died = proc.stdout, (proc.returncode != 0 and "crash")
        except subprocess.TimeoutExpired as exc:
            out, died = (exc.stdout or b"").decode() if isinstance(exc.stdout, bytes) else (exc.stdout or ""), "hang"
        cases = [json.loads(line) for line in out.splitlines() if line.startswith("{")]
        rows += [(name, c["category"], c["case"], c["outcome"], c["detail"]) for c in cases]
        if died or "DONE" not in out:
            after = cases[-1]["case"] if cases else "the start"
            rows.append((name, "process", f"after {after}", died or "crash", proc.stderr[-500:] if died == "crash"
                         else ""))
    return rows


OUTCOMES = ("clean", "wrong status", "silently accepted", "hang", "crash")


def outcome_table(rows) -> str:
    """category | cases | one column per outcome, and a total (rows of :func:`fault_table`)."""
    from collections import Counter

    counts = Counter((r[1], r[3]) for r in rows)
    categories = list(dict.fromkeys(r[1] for r in rows))
    lines = ["category | cases | " + " | ".join(OUTCOMES)]
    for name in categories + ["total"]:
        row = [sum(counts[(c, o)] for c in (categories if name == "total" else [name])) for o in OUTCOMES]
        lines.append(f"{name} | {sum(row)} | " + " | ".join(map(str, row)))
    return "\n".join(lines)


@pytest.mark.slow
def test_every_fmu_through_the_whole_fault_list(fmu_dir, tmp_path):
    """Issue 21: each FMU, in a fresh FMPy process, through every fault of tests/fmu_faults.py: bad values of
    every parameter (per type and range), a first step not at the start time, NaN inputs, bad value
    references and types, calls in the wrong order. Every case clean: refused at the right call with
    fmi2Error and a logged reason (a parameter at fmi2ExitInitializationMode, named), no hang, no crash."""
    rows = fault_table(fmu_dir, tmp_path)
    assert {r[0] for r in rows} == set(FMUS)
    print("\n" + outcome_table(rows))  # the fault pass's table (pytest -s)
    bad = [r for r in rows if r[3] != "clean"]
    assert not bad, "\n".join(" | ".join(map(str, r)) for r in bad)


def test_first_step_must_start_at_the_start_time_in_every_fmu(fmu_dir, tmp_path):
    """Issue 21: Turntable and StrapdownINS returned fmi2OK for a first fmi2DoStep away from the start
    time; now every FMU refuses it with fmi2Error and a logged reason (the native layer checks it)."""
    sys.path.insert(0, os.path.dirname(__file__))
    import fmu_faults

    for name in FMUS:
        base = {"log_file": str(_tiny_log(tmp_path))} if name == "IMULog" else {}
        host = fmu_faults.Host(str(fmu_dir / f"{name}.fmu"), base)
        outcomes = list(fmu_faults.first_step_cases(host))
        assert len(outcomes) == 3
        assert all(outcome == "clean" for _, outcome, _ in outcomes), (name, outcomes)
        fmilog.unregister(host.name)


@pytest.mark.parametrize("name, value, text", [
    ("IMUThermal", {"seed": -2**31}, "seed"),
    ("IMUThermal", {"seed": -1}, "seed"),
    ("Turntable", {"revolutions": -2**31}, "revolutions"),
    ("VehicleMotion", {"body_seed": -1}, "body_seed"),
    ("StrapdownINS", {"pitch0": 2.0}, "pitch0"),
    ("StrapdownINS", {"lat0": 2.0}, "lat0"),
    ("IMUThermal", {"gyro_random_walk_z": -1.0}, "gyro_random_walk_z"),
])
def test_integer_and_range_checks_at_initialisation(fmu_dir, name, value, text):
    """Issue 21: an Integer outside its range (IMUThermal's seed = -2^31 was accepted at
    fmi2ExitInitializationMode and failed at the first step) or a Real outside its range is refused at
    fmi2ExitInitializationMode with a message naming the parameter."""
    from fmu_driver import check_parameter_error

    check_parameter_error(fmu_dir / f"{name}.fmu", value, text)


def test_zero_revolutions_is_refused_not_a_hang(fmu_dir):
    """Issue 21: Turntable with revolutions = 0 hung in fmi2EnterInitializationMode (a forward-reverse cycle
    of no time, repeated for ever); now fmi2ExitInitializationMode refuses it. In a fresh process, so a
    regression fails the test instead of hanging the run."""
    tests = os.path.dirname(__file__)
    script = textwrap.dedent(f"""
        import sys
        sys.path[0:0] = [{tests!r}, {os.path.dirname(tests)!r}]
        from pathlib import Path
        from fmu_driver import check_parameter_error
        check_parameter_error(Path({str(fmu_dir / 'Turntable.fmu')!r}), {{"revolutions": 0}}, "revolutions")
        print("refused")
    """)
    try:
        proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=600)
    except subprocess.TimeoutExpired:
        pytest.fail("Turntable with revolutions = 0 did not finish its initialisation in 600 s")
    assert proc.returncode == 0 and "refused" in proc.stdout, proc.stdout + proc.stderr[-2000:]
