"""Errors a user makes, and FMUs that fail, give clear exceptions naming the culprit."""
from __future__ import annotations

import numpy as np
import pytest

from fmu_fixtures.fixtures import fixture_fmus, ramp_gain  # noqa: F401 (fixtures)
from orchestration import (Component, Connection, FMUCallError, FMUFatalError,
                           IncompatibleConnectionError, Master, OrchestrationError,
                           StartValueError, System, SystemFileError, UnconnectedInputWarning,
                           UnknownComponentError, UnknownVariableError, simulate_system)

pytestmark = pytest.mark.integration


def two(fmus, connections, ramp_values=None, gain_values=None):
    return System("s", [Component("ramp", fmus["Ramp"], ramp_values or {}),
                        Component("gain", fmus["Gain"], gain_values or {})],
                  [Connection.between(a, b) for a, b in connections])


def test_unknown_fmu_file_names_the_file_and_component(tmp_path):
    system = System("s", [Component("ghost", tmp_path / "missing.fmu")])
    with pytest.raises(SystemFileError, match=r"missing\.fmu.*component 'ghost'.*not found"):
        Master(system)


def test_a_file_that_is_not_an_fmu(tmp_path):
    bogus = tmp_path / "bogus.fmu"
    bogus.write_text("not a zip")
    with pytest.raises(SystemFileError, match="bogus.fmu"):
        Master(System("s", [Component("b", bogus)]))


@pytest.mark.parametrize("start, end, error, match", [
    ("ramp.yy", "gain.u", UnknownVariableError, r"component 'ramp', variable 'yy'.*'y'"),
    ("ramp.y", "gain.uu", UnknownVariableError, r"component 'gain', variable 'uu'"),
    ("nope.y", "gain.u", UnknownComponentError, r"component 'nope'"),
    ("ramp.y", "gain.n_in", IncompatibleConnectionError, "type mismatch: Real output to "
                                                          "Integer input"),
    ("ramp.y", "gain.y", IncompatibleConnectionError, "causality 'output'; only inputs"),
    ("ramp.y", "gain.k", IncompatibleConnectionError, "give it a start value instead"),
    ("ramp.slope", "gain.u", IncompatibleConnectionError, "causality 'parameter'; only "
                                                           "outputs"),
    ("gain.u", "gain.u", IncompatibleConnectionError, "causality 'input'; only outputs"),
])
def test_bad_connections(fixture_fmus, start, end, error, match):
    with pytest.raises(error, match=match) as caught:
        Master(two(fixture_fmus, [(start, end)]))
    assert isinstance(caught.value, OrchestrationError)
    if error is not UnknownComponentError:
        assert caught.value.file.endswith(".fmu")


def test_an_input_fed_twice(fixture_fmus):
    with pytest.raises(IncompatibleConnectionError, match="fed by two connections"):
        Master(two(fixture_fmus, [("ramp.y", "gain.u"), ("gain.y", "gain.u")]))


@pytest.mark.parametrize("values, error, match", [
    ({"kk": 1.0}, UnknownVariableError, r"variable 'kk'.*did you mean 'k'"),
    ({"y": 1.0}, StartValueError, "causality 'output'"),
    ({"k": "three"}, StartValueError, "'three' is not a valid Real"),
    ({"n_in": 1.5}, StartValueError, "not a valid Integer"),
    ({"flag_in": 2}, StartValueError, "not a valid Boolean"),
])
def test_bad_start_values(fixture_fmus, values, error, match):
    with pytest.raises(error, match=match) as caught:
        Master(two(fixture_fmus, [("ramp.y", "gain.u")], gain_values=values))
    assert caught.value.component == "gain"


def test_unconnected_input_is_a_warning_not_an_error(fixture_fmus):
    with pytest.warns(UnconnectedInputWarning, match="gain.n_in, gain.flag_in"):
        result = simulate_system(two(fixture_fmus, [("ramp.y", "gain.u")]), 0.5, 0.25)
    assert result.meta["unconnected_inputs"] == ["gain.n_in", "gain.flag_in"]


def faulty_system(fmus, mode):
    return System("f", [Component("ramp", fmus["Ramp"]),
                        Component("bad", fmus["Faulty"], {"mode": mode, "fail_at": 0.5})],
                  [Connection.between("ramp.y", "bad.u")])


def test_fatal_status_at_initialisation_is_reported_without_crashing(fixture_fmus):
    with pytest.raises(FMUFatalError) as caught:
        simulate_system(faulty_system(fixture_fmus, 1), 1.0, 0.25)
    error = caught.value
    assert (error.component, error.call, error.status, error.time) == \
        ("bad", "fmi2ExitInitializationMode", 4, None)
    assert any("refusing to initialise" in m for m in error.messages)
    assert "before the simulation loop" in str(error) and "Faulty.fmu" in str(error)
    # the host is still fine: another run in the same process works
    assert simulate_system(faulty_system(fixture_fmus, 0), 1.0, 0.25)["bad.y"][-1] == 1.0


def test_error_status_during_a_step_names_time_call_and_log(fixture_fmus):
    with Master(faulty_system(fixture_fmus, 2)) as master:
        with pytest.raises(FMUCallError) as caught:
            master.simulate(1.0, 0.25)
        assert master.instances == []
        ok = master.simulate(0.25, 0.25)
    error = caught.value
    assert (error.component, error.call, error.status) == ("bad", "fmi2DoStep", 2)
    assert error.time == 0.5
    assert "at t = 0.5 s" in str(error) and "mode 2: failing at t=0.5" in str(error)
    assert np.isclose(ok["bad.y"][-1], 0.25)


def test_values_are_only_reachable_during_a_run(ramp_gain):
    with Master(ramp_gain) as master:
        with pytest.raises(OrchestrationError, match="during a run"):
            master.get("ramp.y")


def test_callback_may_not_set_an_output(ramp_gain):
    with pytest.raises(StartValueError, match="only inputs and tunable parameters"):
        simulate_system(ramp_gain, 0.5, 0.25, callback=lambda t, m: m.set("ramp.y", 1.0))


def test_unknown_recorded_variable(ramp_gain):
    with pytest.raises(UnknownVariableError, match="nothing recordable.*'ramp.z'"):
        Master(ramp_gain, record=["ramp.z"])


def test_unknown_scheme(ramp_gain):
    with pytest.raises(ValueError, match="unknown coupling scheme"):
        Master(ramp_gain, scheme="newton")
