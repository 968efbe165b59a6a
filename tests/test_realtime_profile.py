"""The real-time profile's tools (benchmarks/bench_realtime.py): the C master's
latency mode (tests/native_host/system.c) on Turntable -> IMUThermal ->
StrapdownINS and the LD_PRELOAD allocation counter
(tests/native_host/alloc_counter.c).  A few thousand steps; no wall-clock
value is asserted, only that the line parses and the percentiles are ordered.

After the warm-up no step makes a heap or mmap call: the IMU draws its random
numbers inside its C step (sarins_fmu/core/rng.h), so no Python step runs to
refill them."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"
sys.path.insert(0, str(BENCH))

import bench_realtime  # noqa: E402

STEPS = 4000  # timed steps per run (the former 4096-interval random blocks: at least one refill in range)


@pytest.fixture(scope="module")
def tools(tmp_path_factory):
    if bench_realtime.compiler() is None:
        pytest.skip("no C compiler for the native test master")
    return bench_realtime.build_tools(tmp_path_factory.mktemp("rt_tools"))


def check_latencies(p: bench_realtime.Profile, step: float):
    assert not p.paced and p.steps == STEPS and p.warmup == bench_realtime.warmup_steps(step) and p.step_s == step
    assert 0 < p.p50_ns <= p.p99_ns <= p.p999_ns <= p.max_ns
    assert p.jitter == pytest.approx(p.p999_ns / p.p50_ns, rel=1e-5)


@pytest.mark.parametrize("rate", [200.0, 1000.0])
def test_latency_line_and_no_allocation_after_the_warm_up(fmu_dir, tools, tmp_path, rate):
    exe, counter = tools
    step = 1.0 / rate
    plan = bench_realtime.write_plan(fmu_dir, tmp_path, step, STEPS)
    p = bench_realtime.run(exe, plan, counter, timeout=600)
    check_latencies(p, step)
    assert p.counter
    assert (p.allocs, p.frees, p.mmaps, p.munmaps, p.alloc_steps) == (0, 0, 0, 0, 0), p.alloc_step_list[:5]
    assert p.alloc_step_list == () and p.max_alloc_ns == -1 and p.max_quiet_ns == p.max_ns


def test_latency_mode_without_the_counter(fmu_dir, tools, tmp_path):
    exe, _ = tools
    step = 0.005
    p = bench_realtime.run(exe, bench_realtime.write_plan(fmu_dir, tmp_path, step, STEPS), None, timeout=600)
    check_latencies(p, step)
    assert not p.counter
    assert (p.allocs, p.frees, p.mmaps, p.munmaps, p.alloc_steps, p.max_alloc_ns) == (-1, -1, -1, -1, -1, -1)
    assert p.max_quiet_ns == p.max_ns and p.alloc_step_list == ()
    assert not p.paced and (p.wake_p50_ns, p.wake_p99_ns, p.wake_max_ns, p.overruns) == (-1, -1, -1, -1)


def test_paced_latency_mode(fmu_dir, tools, tmp_path):
    exe, counter = tools
    step, steps = 0.001, 300
    p = bench_realtime.run(exe, bench_realtime.write_plan(fmu_dir, tmp_path, step, steps, paced=True), counter,
                           timeout=600)
    assert p.paced and p.steps == steps
    assert 0 < p.p50_ns <= p.p99_ns <= p.p999_ns <= p.max_ns
    assert 0 <= p.wake_p50_ns <= p.wake_p99_ns <= p.wake_max_ns and 0 <= p.overruns <= steps
    assert p.alloc_steps == 0 and p.allocs == 0


def test_parse_refuses_output_without_one_latency_line():
    with pytest.raises(ValueError, match="one LATENCY line"):
        bench_realtime.parse("DONE 10\n")
