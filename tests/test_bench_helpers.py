"""The benchmarks' FMU helpers run (no timing asserted): the start-up feeds make the
time-tagged FMUs compute from their first step in both hosts (FMPy and the C host),
and the out-of-process prototype gives the slaves' in-process outputs bit for bit.
A few steps keep it quick."""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"
sys.path.insert(0, str(BENCH))

import fmu_runs  # noqa: E402

# after five fed steps: an output that shows the FMU computed (an untagged INS only waits, an
# identifier whose trigger is not met stays at 0, an updater without rows runs no stop filter)
TAGGED = {"StrapdownINS": ("nav_time", 1.0),  # coarse 2 s, fine 2 s, one navigation step
          "RBFIdentifier": ("apply_from", None),  # trigger_time 0 + latency once fired
          "DriftModelUpdater": ("stop_timer", None),  # the stop filter's time, parked and navigating
          "IMUThermal": ("increment_end_time", 5.0)}


@pytest.fixture(scope="module")
def c_host(tmp_path_factory):
    try:
        return fmu_runs.build_c_host(tmp_path_factory.mktemp("bench_host") / "host")
    except RuntimeError as exc:
        pytest.skip(str(exc))


@pytest.mark.parametrize("name, host", [(name, "c") for name in TAGGED] + [("StrapdownINS", "fmpy")])
def test_start_up_feed_runs_five_real_steps(fmu_dir, c_host, tmp_path, name, host):
    feed = fmu_runs.feeds()[name]
    if name == "IMUThermal":  # plain-Python minor loop: keep it short
        feed = fmu_runs.Feed(values={**feed.values, "internal_rate": 10.0}, tags=feed.tags)
    fmu = fmu_dir / f"{name}.fmu"
    env = fmu_runs.host_env(os.environ, SARINS_FMU_CACHE=str(tmp_path / "cache"))
    if host == "fmpy":
        argv = fmu_runs.fmpy_command(fmu, feed, 5, stamps=(1, 5), printed=[TAGGED[name][0]])
    else:
        argv = fmu_runs.c_host_command(c_host, fmu_runs.unzip(fmu, tmp_path / name), fmu, feed, 5, stamps=(1, 5),
                                       printed=[TAGGED[name][0]])
    stamps, values = fmu_runs.run_host(argv, env, time.time())  # raises on any status other than OK
    assert sorted(stamps) == [1, 5]
    [value] = values.values()
    output, expected = TAGGED[name]
    assert value == expected if expected is not None else value > 0, (output, value)
