"""The real-time pacer's lag distribution, on a simulated clock (no sleeping, deterministic)."""

import pytest

from orchestration import pacing
from orchestration.pacing import RealTimePacer
from sarins.cli.cosim import realtime_summary


class FakeClock:
    def __init__(self):
        self.now = 100.0

    def perf_counter(self):
        return self.now

    def sleep(self, seconds):
        self.now += seconds


@pytest.fixture
def clock(monkeypatch):
    fake = FakeClock()
    monkeypatch.setattr(pacing._time, "perf_counter", fake.perf_counter)
    monkeypatch.setattr(pacing._time, "sleep", fake.sleep)
    return fake


def test_lag_distribution_of_known_steps(clock):
    pacer = RealTimePacer(0.5, 10.0, capacity=4)  # 0.5 s of wall clock per simulated second
    pacer.start()
    work = [0.2, 1.3, 0.0, 0.0]  # wall seconds of work before each step's wait; target every 0.5 s
    for k, w in enumerate(work):
        clock.now += w
        with pytest.warns(UserWarning) if k == 1 else _nothing():
            pacer.wait(10.0 + (k + 1), 1.0)
    # ends: 100.2 (target 100.5: slack 0.3, sleeps to 100.5); 101.8 (target 101.0: late 0.8, warns);
    # 101.8 (target 101.5: late 0.3); 101.8 (target 102.0: slack 0.2)
    report = pacer.report()
    assert report["steps"] == 4 and report["kept_steps"] == 4
    assert report["late_steps"] == 2
    assert report["max_lag_s"] == pytest.approx(0.8) and report["max_lag_time"] == 12.0
    # lateness sorted [0, 0, 0.3, 0.8]; numpy's linear percentiles
    assert report["lag_p50_s"] == pytest.approx(0.15)
    assert report["lag_p99_s"] == pytest.approx(0.3 + 0.97 * 0.5)
    assert report["min_slack_s"] == pytest.approx(-0.8)
    line = realtime_summary(report)
    assert "2 of 4 steps late" in line and "p50 0.150000 s" in line and "max 0.800000 s" in line


def test_steps_beyond_the_capacity_are_paced_not_kept(clock):
    pacer = RealTimePacer(1.0, 0.0, capacity=2)
    for k in range(5):
        clock.now += 0.25
        pacer.wait(float(k + 1), 1.0)
    report = pacer.report()
    assert report["steps"] == 5 and report["kept_steps"] == 2 and report["late_steps"] == 0
    assert report["min_slack_s"] == pytest.approx(0.75)
    assert "no step late in 5 steps; least slack 0.750000 s" in realtime_summary(report)


def test_report_without_steps(clock):
    report = RealTimePacer(1.0, 0.0, capacity=3).report()
    assert report["kept_steps"] == 0 and report["lag_p50_s"] is None and report["min_slack_s"] is None


class _nothing:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False
