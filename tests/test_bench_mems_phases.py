"""benchmarks/bench_mems_phases.py: the /usr/bin/time -v log and the summary's costs read back as printed."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
from bench_mems_phases import parse_time_log, report, tables  # noqa: E402

TIME_LOG = """\tCommand being timed: "python3 -m sarins campaign mems-calibration --profile quick"
\tUser time (seconds): 163.30
\tSystem time (seconds): 7.70
\tPercent of CPU this job got: 35%
\tElapsed (wall clock) time (h:mm:ss or m:ss): 7:55.10
\tMaximum resident set size (kbytes): 802816
\tExit status: 0
"""


def test_time_log_is_parsed():
    whole = parse_time_log(TIME_LOG)
    assert whole["cpu_s"] == 163.30 + 7.70 and whole["user_s"] == 163.30 and whole["system_s"] == 7.70
    assert whole["wall_s"] == 7 * 60 + 55.10 and whole["max_rss_mb"] == 784.0
    assert parse_time_log("\tElapsed (wall clock) time (h:mm:ss or m:ss): 1:02:03\n\tUser time (seconds): 1\n"
                          "\tSystem time (seconds): 2\n\tMaximum resident set size (kbytes): 1024\n")["wall_s"] == 3723.0
    assert parse_time_log("no time here") == {}


def test_tables_total_the_evaluation_per_set_and_model():
    summary = dict(load_average=[2.0, 3.0], fit_load_average=[2.5, 2.9],
                   phases={"fitting": dict(wall_s=40.0, cpu_s=70.0, estimate_s=30.0, peak_rss_mb=700.0)},
                   models={"lstm": dict(fit_cpu_s=4.0, fit_s=20.0), "traditional": dict(fit_cpu_s=None, fit_s=0.0)},
                   evaluation_cpu_s={"lstm": {"held-out": 3.0, "in-sample": 2.0},
                                     "traditional": {"held-out": 0.5, "in-sample": 0.25}})
    numbers = tables(summary, parse_time_log(TIME_LOG))
    assert numbers["fits"]["lstm"] == dict(cpu_s=4.0, wall_s=20.0)
    text = report(numbers)
    assert "wall 475.1 s, CPU 171.0 s" in text and "peak RSS 784 MB" in text
    assert "fitting          40.0     70.0          700" in text
    lines = {line.split()[0] + (" " + line.split()[1] if line.startswith("all") else ""): line for line in
             text.splitlines() if line.strip()}
    assert lines["lstm"].split()[-3:] == ["3.0", "2.0", "5.0"] and lines["all models"].split()[-3:] == ["3.5", "2.2", "5.8"]
    assert ["traditional", "-", "0.0"] in [line.split() for line in text.splitlines()]  # a fit without its CPU time
