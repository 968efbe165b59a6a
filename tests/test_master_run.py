"""The master's algorithm on the fixture FMUs: schemes, schedule, recorder, hooks."""
from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from fmu_fixtures.fixtures import fixture_fmus, ramp_gain  # noqa: F401 (fixtures)
from orchestration import (AlgebraicLoopWarning, Component, Connection, Master,
                           RealTimeLagWarning, ScheduleError, System, read_system,
                           simulate_system, write_csv)

pytestmark = pytest.mark.integration

SLOPE, OFFSET, K, H, STOP = 2.0, 1.0, 3.0, 0.25, 2.0


def ramp(t):
    return OFFSET + SLOPE * t


def test_gauss_seidel_reads_outputs_of_the_same_step(ramp_gain):
    result = simulate_system(ramp_gain, STOP, H, scheme="gauss-seidel")
    t = np.arange(0.0, STOP + H / 2, H)
    assert result.dtype.names[0] == "time"
    assert_allclose(result["time"], t, rtol=0, atol=1e-15)
    assert_allclose(result["ramp.y"], ramp(t))
    # gain input held over [t, t+h] is the ramp at t+h
    assert_allclose(result["gain.y"][1:], K * ramp(t[1:]))
    assert_allclose(result["gain.x"], np.concatenate([[0.0], np.cumsum(H * ramp(t[1:]))]))
    assert_array_equal(result["gain.n_out"], np.arange(t.size))
    assert result["gain.flag_out"][1:].all() and result["gain.flag_out"].dtype == bool
    assert result.meta["scheme"] == "gauss-seidel"
    assert result.meta["order"] == ["ramp", "gain"]


def test_jacobi_carries_one_step_delay(ramp_gain):
    result = simulate_system(ramp_gain, STOP, H, scheme="jacobi")
    t = result["time"]
    assert_allclose(result["gain.y"][1:], K * ramp(t[:-1]))
    assert_allclose(result["gain.x"], np.concatenate([[0.0], np.cumsum(H * ramp(t[:-1]))]))
    assert_array_equal(result["gain.n_out"][1:], np.arange(t.size - 1))
    assert result.meta["scheme"] == "jacobi"


def test_declaration_order_does_not_change_gauss_seidel(fixture_fmus):
    system = System("reversed", [Component("gain", fixture_fmus["Gain"], {"k": K}),
                                 Component("ramp", fixture_fmus["Ramp"], {"slope": SLOPE})],
                    [Connection.between("ramp.y", "gain.u")])
    with pytest.warns(UserWarning, match="unconnected"):
        master = Master(system)
    with master:
        result = master.simulate(1.0, 0.5)
    assert result.meta["order"] == ["ramp", "gain"]
    assert_allclose(result["gain.y"][1:], K * SLOPE * result["time"][1:])


def test_cycle_is_broken_deterministically_with_a_warning(fixture_fmus):
    gain = fixture_fmus["Gain"]
    system = System("loop", [Component("a", gain, {"k": 0.5, "u": 1.0}),
                             Component("b", gain, {"k": 2.0})],
                    [Connection.between("a.y", "b.u"), Connection.between("b.y", "a.u")])
    with pytest.warns(AlgebraicLoopWarning, match="b -> a"):
        master = Master(system, record=["a.y", "b.y"])
    with master:
        first = master.simulate(1.0, 0.25)
        second = master.simulate(1.0, 0.25)
    assert first.meta["order"] == ["a", "b"]
    assert first.meta["broken_connections"] == ["b.y -> a.u"]
    assert_array_equal(first.view(np.ndarray), second.view(np.ndarray))
    # a reads b at the start of the step, b reads a at its end: y_a = 0.5*y_b(prev)
    assert_allclose(first["a.y"][2:], 0.5 * first["b.y"][1:-1])
    assert_allclose(first["b.y"][1:], 2.0 * first["a.y"][1:])


def test_step_schedule_and_communication_points(ramp_gain):
    schedule = [(0.5, 0.25), (2.0, 0.5)]
    result = simulate_system(ramp_gain, None, schedule)
    assert_allclose(result["time"], [0.0, 0.25, 0.5, 1.0, 1.5, 2.0])
    assert_allclose(result["ramp.y"], ramp(result["time"]))
    assert result.meta["step"] == "schedule"
    points = np.array([0.0, 0.1, 0.3, 0.7])
    result = simulate_system(ramp_gain, None, points)
    assert_array_equal(result["time"], points)
    assert_array_equal(result["ramp.count"], np.arange(4))


def test_time_comes_from_a_counter(ramp_gain):
    result = simulate_system(ramp_gain, 1.0, 0.1, record=["ramp.count"])
    assert result["time"][-1] == 1.0
    assert_array_equal(result["time"], 0.1 * np.arange(11))
    assert result.meta["steps"] == 10


@pytest.mark.parametrize("stop, step, match", [
    (1.0, 0.3, "whole number"), (1.0, 0.0, "positive"), (1.0, -0.1, "positive"),
    (1.0, float("nan"), "positive"), (None, 0.1, "stop time"), (-1.0, 0.1, "after"),
])
def test_bad_schedules_are_refused(ramp_gain, stop, step, match):
    with pytest.raises(ScheduleError, match=match):
        simulate_system(ramp_gain, stop, step)


def test_record_selection_and_output_interval(ramp_gain):
    result = simulate_system(ramp_gain, 2.0, 0.25, record=["gain.*", "ramp.y"],
                             output_every=3)
    assert result.dtype.names == ("time", "gain.k", "gain.u", "gain.n_in", "gain.flag_in",
                                  "gain.y", "gain.x", "gain.n_out", "gain.flag_out", "ramp.y")
    assert_allclose(result["time"], [0.0, 0.75, 1.5, 2.0])
    assert result.meta["output_every"] == 3


def test_write_csv_round_trip(ramp_gain, tmp_path):
    result = simulate_system(ramp_gain, 1.0, 0.5)
    path = write_csv(result, tmp_path / "out.csv")
    lines = path.read_text().splitlines()
    assert lines[0].split(",") == list(result.dtype.names)
    back = np.genfromtxt(path, delimiter=",", names=True)
    assert_allclose(back["gainy"], result["gain.y"])
    assert len(lines) == result.size + 1


def test_callback_reads_sets_and_stops(ramp_gain):
    seen = []

    def callback(time, master):
        seen.append((time, master.get("ramp.y"), master.get("ramp.positive")))
        master.set("gain.k", 10.0)
        return time < 1.0

    result = simulate_system(ramp_gain, 2.0, 0.25, callback=callback)
    assert result["time"][-1] == 1.0 and result.meta["stopped_early"]
    assert seen[0] == (0.25, ramp(0.25), True)
    assert_allclose(result["gain.y"][2:], 10.0 * ramp(result["time"][2:]))


def test_realtime_pacing_and_lag_warning(ramp_gain):
    import time as clock

    begin = clock.perf_counter()
    simulate_system(ramp_gain, 0.2, 0.05, realtime=0.5)
    assert clock.perf_counter() - begin >= 0.09
    with pytest.warns(RealTimeLagWarning, match="fell behind"):
        result = simulate_system(ramp_gain, 0.2, 0.05, realtime=0.01,
                                 callback=lambda t, m: clock.sleep(0.02))
    assert result.meta["max_realtime_lag"] > 0.01


def test_progress_bar_can_be_forced(ramp_gain, capsys):
    simulate_system(ramp_gain, 1.0, 0.01, progress=True)
    assert "step" in capsys.readouterr().err


def test_ssp_file_runs_like_the_python_description(ramp_gain, tmp_path):
    from orchestration import write_ssp

    ramp_gain.stop_time, ramp_gain.step_size = 1.0, 0.25
    direct = simulate_system(ramp_gain)
    path = write_ssp(ramp_gain, tmp_path / "demo.ssp")
    from_file = simulate_system(path)
    assert read_system(path).step_size == 0.25
    assert_array_equal(direct.view(np.ndarray), from_file.view(np.ndarray))


def test_many_runs_in_one_process_exit_cleanly(fixture_fmus, tmp_path):
    """Twelve runs in one process (simulate_system and one Master, Jacobi): every instance the master made is
    terminated and freed before the process ends, and the process ends with exit code 0.

    The process leaves with os._exit after its last line: the pythonfmu fixtures' own library reads freed memory
    in its exit-time destructor (valgrind: ``finalizePythonInterpreter`` in the fixture's binary reads a block
    that the C++ exit handlers freed; it aborted 1 run of 60 with "corrupted double-linked list"), which is
    pythonfmu's, not the master's; the master's part, every fmi2FreeInstance, is counted here instead."""
    script = textwrap.dedent(f"""
        import collections, os, sys, warnings
        import fmpy.fmi2 as fmi2
        from orchestration import Component, Connection, System, Master, simulate_system
        calls = collections.Counter()
        def counted(name, method):
            def call(self, *args, **kwargs):
                calls[name] += 1
                return method(self, *args, **kwargs)
            return call
        fmi2.FMU2Slave.instantiate = counted("instantiate", fmi2.FMU2Slave.instantiate)
        fmi2.FMU2Slave.freeInstance = counted("free", fmi2.FMU2Slave.freeInstance)
        system = System("s", [Component("r", {str(fixture_fmus['Ramp'])!r}),
                              Component("g1", {str(fixture_fmus['Gain'])!r}),
                              Component("g2", {str(fixture_fmus['Gain'])!r})],
                        [Connection.between("r.y", "g1.u"), Connection.between("g1.y", "g2.u")])
        warnings.simplefilter("ignore")
        for run in range(6):
            result = simulate_system(system, 1.0, 0.1)
        with Master(system, scheme="jacobi") as master:
            for run in range(6):
                result = master.simulate(1.0, 0.1)
        print("final", result["g2.y"][-1], calls["instantiate"], calls["free"])
        sys.stdout.flush()
        os._exit(0)
    """)
    for _attempt in range(3):
        done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                              timeout=120, cwd=str(tmp_path),
                              env={**__import__("os").environ,
                                   "PYTHONPATH": str(__import__("pathlib").Path(__file__)
                                                     .parents[1])})
        assert done.returncode == 0, done.stderr
        final = done.stdout.split()
        assert final[0] == "final" and int(final[2]) == int(final[3]) >= 3, done.stdout


def test_variable_steps_are_refused_for_fmus_that_cannot_take_them(fixture_fmus):
    system = System("r", [Component("ramp", fixture_fmus["RampFixedStep"])])
    with Master(system) as master:
        with pytest.raises(ScheduleError, match="component 'ramp'.*variable communication"):
            master.simulate(None, [(0.5, 0.25), (1.0, 0.5)])
        assert master.simulate(1.0, 0.25)["ramp.y"][-1] == 1.0
