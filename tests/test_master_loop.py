"""The master's compiled inner loop (orchestration/steploop.c) against its Python loop.

Both run the same plan: the same FMI calls in the same order, unit maps and casts; the results must be
equal bit for bit, and failures, FMI 3.0 terminate requests and signals must be reported the same way.
"""
from __future__ import annotations

import os
import signal
import threading
import time
import warnings

import numpy as np
import pytest

from fmu_fixtures.fixtures import fixture_fmus, fmi3_fmus  # noqa: F401 (fixtures)
from orchestration import (Component, Connection, FMUCallError, Master, System, UnconnectedInputWarning,
                           interrupt, read_system, steploop)

pytestmark = pytest.mark.integration

needs_library = pytest.mark.skipif(steploop.load() is None, reason="the compiled loop is not built "
                                   "(pip install -e .)")


def both_loops(system, stop, step, scheme="gauss-seidel", **options):
    """{loop: result} of the same run under each loop."""
    out = {}
    for loop in ("python", "c"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UnconnectedInputWarning)
            with Master(system, scheme=scheme, loop=loop) as master:
                out[loop] = master.simulate(stop, step, **options)
    return out


def assert_same(results):
    a, b = results["python"], results["c"]
    assert a.meta["loop"] == "python" and b.meta["loop"] == "c"
    assert a.dtype == b.dtype and len(a) == len(b)
    for name in a.dtype.names:
        assert np.array_equal(a[name], b[name], equal_nan=True), name
    assert {k: v for k, v in a.meta.items() if k != "loop"} == {k: v for k, v in b.meta.items() if k != "loop"}


def burst_sum(fmus, **burst):
    return System("burst_sum",
                  [Component("b", fmus["Burst3"], {"slope": 2.0, "n": 5, **burst}),
                   Component("s", fmus["Sum3"], {"n": 5})],
                  [Connection.between("b.samples", "s.u"), Connection.between("b.count", "s.m"),
                   Connection.between("b.pairs", "s.v")])


@needs_library
@pytest.mark.parametrize("scheme", ["gauss-seidel", "jacobi"])
def test_fmi3_arrays_integers_and_booleans_are_moved_the_same(fmi3_fmus, scheme):
    assert_same(both_loops(burst_sum(fmi3_fmus), 1.0, 0.1, scheme))


@needs_library
@pytest.mark.parametrize("every", [1, 3])
def test_a_step_schedule_and_sparse_recording_give_the_same_rows(fmi3_fmus, every):
    schedule = [(0.3, 0.05), (1.0, 0.1)]
    assert_same(both_loops(burst_sum(fmi3_fmus), 1.0, schedule, output_every=every))


def mixed(fixture_fmus, fmi3_fmus):
    """FMI 2.0 Real/Integer/Boolean into FMI 3.0 Float32/Int32/Boolean and back: casts on both sides."""
    return System("mixed",
                  [Component("ramp", fixture_fmus["Ramp"], {"slope": 2.0, "offset": -0.5}),
                   Component("b", fmi3_fmus["Burst3"], {"slope": 2.0, "n": 4}),
                   Component("s", fmi3_fmus["Sum3"], {"n": 4}),
                   Component("gain", fixture_fmus["Gain"], {"k": 3.0})],
                  [Connection.between("ramp.y", "s.k"), Connection.between("ramp.count", "s.m"),
                   Connection.between("ramp.positive", "s.flag"), Connection.between("b.samples", "s.u"),
                   Connection.between("b.y", "gain.u"), Connection.between("s.m_out", "gain.n_in"),
                   Connection.between("s.flag_out", "gain.flag_in")])


@needs_library
@pytest.mark.parametrize("scheme", ["gauss-seidel", "jacobi"])
def test_casts_between_fmi2_and_fmi3_types_are_the_same(fixture_fmus, fmi3_fmus, scheme):
    results = both_loops(mixed(fixture_fmus, fmi3_fmus), 1.0, 0.125, scheme)
    assert_same(results)
    assert results["c"]["s.flag_out"].any() and not results["c"]["s.flag_out"].all()


@needs_library
def test_terminate_request_ends_both_loops_after_the_same_step(fmi3_fmus):
    results = both_loops(burst_sum(fmi3_fmus, stop_after=3), 1.0, 0.1)
    assert_same(results)
    assert results["c"].meta["terminated_by"] == "b" and results["c"].meta["steps"] == 3


@needs_library
def test_unit_conversions_on_connections_are_applied_the_same(fixture_fmus, tmp_path):
    from test_master_units import NESTED

    for name in ("Ramp", "Feed"):
        (tmp_path / f"{name}.fmu").write_bytes(fixture_fmus[name].read_bytes())
    (tmp_path / "SystemStructure.ssd").write_text(NESTED)
    results = both_loops(read_system(tmp_path), 1.0, 0.25)
    assert_same(results)
    assert results["c"].meta["converted_connections"]


@needs_library
def test_a_failing_step_is_reported_with_the_same_call_time_and_log(fixture_fmus):
    system = System("f", [Component("ramp", fixture_fmus["Ramp"]),
                          Component("bad", fixture_fmus["Faulty"], {"mode": 2, "fail_at": 0.5})],
                    [Connection.between("ramp.y", "bad.u")])
    errors = {}
    for loop in ("python", "c"):
        with Master(system, loop=loop) as master, pytest.raises(FMUCallError) as caught:
            master.simulate(1.0, 0.25)
        errors[loop] = caught.value
    for error in errors.values():
        assert (error.component, error.call, error.status, error.time) == ("bad", "fmi2DoStep", 2, 0.5)
    assert str(errors["c"]) == str(errors["python"])


@needs_library
def test_the_standard_system_is_bit_identical_under_both_loops_and_both_schemes(fmu_dir):
    for scheme in ("gauss-seidel", "jacobi"):
        assert_same(both_loops(fmu_dir / "standard_static.ssp", 600.0, 1.0, scheme))


@needs_library
def test_a_signal_during_the_compiled_loop_stops_the_run_between_blocks(fmi3_fmus):
    """SIGTERM arrives while the C loop runs (sent once the loop has done its first blocks): the master
    stops after the current block of steps and keeps the rows recorded so far."""
    system = burst_sum(fmi3_fmus)
    steps, every = 2_000_000, 1000  # seconds of work: the signal comes long before the end
    fired = threading.Event()

    def send_when_running(master):
        while not fired.is_set():
            if master.time is not None and master.time > 1.0:  # past the first blocks of 0.512 s
                os.kill(os.getpid(), signal.SIGTERM)
                fired.set()
            time.sleep(0.001)

    with interrupt.handle_signals(), Master(system, loop="c") as master:
        watcher = threading.Thread(target=send_when_running, args=(master,), daemon=True)
        watcher.start()
        try:
            with pytest.raises(interrupt.Interrupted) as caught:
                master.simulate(steps * 1e-3, 1e-3, output_every=every)
        finally:
            fired.set()
            watcher.join()
    partial = caught.value.partial
    assert partial is not None and 1 <= len(partial) < steps // every + 1
    assert partial.meta["loop"] == "c"
    t, stopped = partial["time"], partial.meta["interrupted_at"]
    assert np.all(np.diff(t) > 0) and t[-1] <= stopped < steps * 1e-3


def test_loop_c_without_the_library_is_a_clear_error(fmi3_fmus, monkeypatch):
    monkeypatch.setattr(steploop, "load", lambda: None)
    with Master(burst_sum(fmi3_fmus), loop="c") as master, pytest.raises(Exception, match="not built"):
        master.simulate(0.2, 0.1)
    with Master(burst_sum(fmi3_fmus)) as master:
        assert master.simulate(0.2, 0.1).meta["loop"] == "python"


def test_unknown_loop_is_refused(fmi3_fmus):
    with pytest.raises(ValueError, match="unknown loop"):
        Master(burst_sum(fmi3_fmus), loop="fortran")


@needs_library
def test_the_profile_splits_the_loop_time_by_component_and_call(fmi3_fmus):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnconnectedInputWarning)
        with Master(burst_sum(fmi3_fmus)) as master:
            result = master.simulate(1.0, 0.01, profile=True)
            plain = master.simulate(1.0, 0.01)
            with pytest.raises(Exception, match="compiled loop"):
                master.simulate(0.1, 0.01, profile=True, callback=lambda t, m: None)
    for name in result.dtype.names:  # profiling changes no number
        assert np.array_equal(result[name], plain[name])
    profile = result.meta["profile"]
    assert profile["steps"] == 100 and set(profile["components"]) == {"b", "s"}
    assert profile["components"]["b"]["doStep"] > 0.0 and profile["components"]["s"]["doStep"] > 0.0
    assert profile["components"]["b"]["get"] > 0.0 and profile["components"]["s"]["set"] > 0.0
    assert profile["components"]["b"]["set"] == 0.0  # nothing feeds b
    parts = sum(sum(p.values()) for p in profile["components"].values()) + profile["conversions_s"] \
        + profile["record_s"]
    assert parts + profile["master_s"] == pytest.approx(profile["wall_s"])
    assert 0.0 < parts <= profile["wall_s"]


@needs_library
def test_the_profile_counts_the_casts_as_conversions(fixture_fmus, fmi3_fmus):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnconnectedInputWarning)
        result = Master(mixed(fixture_fmus, fmi3_fmus)).simulate(1.0, 0.125, profile=True)
    assert result.meta["profile"]["conversions_s"] > 0.0
