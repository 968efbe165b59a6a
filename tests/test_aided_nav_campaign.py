"""``sarins campaign aided-nav``: a tiny run through the CLI, the report's numbers against the stored
results, and a killed run resumed without recomputing its finished tasks."""

import contextlib
import json
import math
import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import chi2

from sarins.cli import main
from sarins.results import load_result
from sarins_fmu.experiments.aided_nav import OUTAGES

HERE = Path(__file__).resolve().parent
RUNS = 3
ZUPT_RUNS = 1
TASKS = 1 + RUNS + ZUPT_RUNS


def _table(report: str, header: str) -> list:
    """Rows (lists of cell strings) of the Markdown table whose header row starts with ``header``."""
    lines = report.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(header))
    rows = []
    for line in lines[start + 2:]:
        if not line.startswith("|"):
            break
        rows.append([c.strip() for c in line.strip("|").split("|")])
    return rows


def test_tiny_campaign_report_matches_the_stored_runs(tmp_path, capsys):
    out = tmp_path / "aided"
    absent = tmp_path / "no-kf-gins"  # no KF-GINS binary there: the comparison is skipped, saying why
    argv = ["campaign", "aided-nav", "--profile", "quick", "--runs", str(RUNS), "--zupt-runs", str(ZUPT_RUNS),
            "--workers", "1", "--out", str(out), "--no-progress", "--kfgins", str(absent)]
    assert main(argv) == 0
    assert f"{TASKS} tasks ({TASKS} computed now)" in capsys.readouterr().out
    runs = [load_result(p) for p in sorted((out / "runs").glob("run-*.npz"))]
    assert len(runs) == RUNS
    report = (out / "report.md").read_text()
    # the outage table from the stored end-of-outage errors and sigmas
    rows = _table(report, "| outage (s)")
    assert len(rows) == len(OUTAGES)
    err = np.array([r["outage_error"] for r in runs])
    sig = np.array([r["outage_sigma"] for r in runs])
    lo, hi = (math.sqrt(chi2.ppf(q, 2 * RUNS) / (2 * RUNS)) for q in (0.025, 0.975))
    for j, ((start, end), row) in enumerate(zip(OUTAGES, rows)):
        e, s = np.sqrt(np.mean(err[:, j] ** 2)), np.sqrt(np.mean(sig[:, j] ** 2))
        assert row[0] == f"{start:g}-{end:g}" and row[1] == f"{end - start:g}"
        assert float(row[2]) == pytest.approx(e, abs=5e-4) and float(row[3]) == pytest.approx(s, abs=5e-4)
        assert float(row[4]) == pytest.approx(e / s, abs=5e-3)
        assert row[5] == f"{lo:.2f} .. {hi:.2f}"
        # the outage row is the last before the first fix after it: the error has grown, the sigma too
        i0 = int(np.searchsorted(runs[0]["time"], start))
        assert s > 1.5 * np.sqrt(np.mean([r["sigma"][i0, 0] ** 2 + r["sigma"][i0, 1] ** 2 for r in runs]))
    # the NEES table from the stored per-run NEES
    mean = np.mean([r["nees"] for r in runs], axis=0)
    band = (chi2.ppf(0.025, 3 * RUNS) / RUNS, chi2.ppf(0.975, 3 * RUNS) / RUNS)
    assert f"lies in {band[0]:.3f} .. {band[1]:.3f}" in report
    for i, row in enumerate(_table(report, "| block | time-mean")):
        inside = np.mean((mean[:, i] >= band[0]) & (mean[:, i] <= band[1]))
        assert float(row[1]) == pytest.approx(mean[:, i].mean(), abs=5e-4)
        assert float(row[2].rstrip(" %")) == pytest.approx(100 * inside, abs=0.05)
    # one NEES value recomputed from the stored error and sigma is not possible (P's off-diagonal terms
    # are not stored), but the stored sigma bounds it: e' P^-1 e >= 0 and the sigma is positive
    assert all(np.all(r["sigma"] > 0) and np.all(r["nees"] >= 0) for r in runs)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["runs"] == RUNS and summary["profile"] == "quick"
    assert [o["ratio"] for o in summary["outages"]] == pytest.approx([float(r[4]) for r in rows], abs=5e-3)
    for name in ("trajectory.png", "errors_position.png", "errors_velocity.png", "errors_attitude.png", "nees.png",
                 "outage_growth.png"):
        assert (out / name).stat().st_size > 1000 and f"]({name})" in report
    # the ZUPT-detector table from the stored runs
    zupt = [load_result(p) for p in sorted((out / "runs").glob("zupt-*.npz"))]
    assert len(zupt) == ZUPT_RUNS
    (row,) = _table(report, "| stop windows |")
    total = lambda key: sum(int(z[key]) for z in zupt)  # noqa: E731
    m = total("stop_windows")
    assert [int(row[i]) for i in (0, 1, 4, 5)] == [m, total("misses"), total("moving_windows"), total("false_stationary")]
    assert float(row[2]) == pytest.approx(1e-3 * m, abs=5e-3)
    assert float(row[7]) == pytest.approx(np.mean([z["delay_s"] for z in zupt]), abs=5e-3)
    nav = _table(report, "| ZUPTs from |")
    for line, key in zip(nav, ("error_truth_m", "error_imu_m")):
        assert float(line[1]) == pytest.approx(np.sqrt(np.mean([z[key] ** 2 for z in zupt])), abs=5e-4)
    assert summary["zupt_detection"]["misses"] == total("misses")
    traj = load_result(out / "runs" / "trajectory.npz")
    assert traj["stationary"][0] == 1 and traj["speed"].max() == pytest.approx(12.0)
    # the KF-GINS section: one line saying it was skipped and why
    section = report.split("## Against KF-GINS on the same data\n\n", 1)[1].split("\n\n", 1)[0]
    assert section == f"KF-GINS comparison skipped: {absent} is not an executable file."
    assert summary["kfgins"] == {"skipped": f"{absent} is not an executable file"}


def test_killed_campaign_resumes_without_recomputing_finished_tasks(tmp_path):
    """A test hook SIGKILLs the campaign after its 2nd stored result; the same command then computes
    only the rest and leaves the finished files untouched."""
    out = tmp_path / "aided"
    args = ["campaign", "aided-nav", "--profile", "quick", "--runs", str(RUNS), "--zupt-runs", "0",
            "--workers", "1", "--out", str(out), "--no-progress", "--kfgins", str(tmp_path / "no-kf-gins")]
    proc = subprocess.Popen([sys.executable, str(HERE / "hooks.py"), "--kill-after", "2", "-m", "sarins", *args],
                            start_new_session=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        assert proc.wait(timeout=600) == -signal.SIGKILL  # the timeout only guards a hang
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
    before = {p.name: p.stat().st_mtime_ns for p in (out / "runs").glob("*.npz")}
    assert len(before) == 2 and not (out / "report.md").exists()
    result = subprocess.run([sys.executable, "-m", "sarins", *args], capture_output=True, text=True,
                            env={**os.environ, "PYTHONPATH": str(HERE.parent)}, timeout=600)
    assert result.returncode == 0, result.stderr
    assert re.search(rf"{RUNS + 1} tasks \({RUNS + 1 - 2} computed now\)", result.stdout)
    after = {p.name: p.stat().st_mtime_ns for p in (out / "runs").glob("*.npz")}
    assert len(after) == RUNS + 1 and all(after[k] == v for k, v in before.items())
    assert (out / "report.md").exists()


def test_bad_runs_option_exits_2(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["campaign", "aided-nav", "--runs", "1", "--out", str(tmp_path / "x")])
    assert exc.value.code == 2
    assert "--runs" in capsys.readouterr().err


def test_failing_kfgins_is_reported_as_skipped(tmp_path):
    """A KF-GINS that exits with an error: the task stores the failure, the report's section says the
    comparison was skipped and how KF-GINS failed, in one line."""
    from sarins.aided_nav.report import _kfgins_lines, kfgins_summary
    from sarins_fmu.experiments.aided_nav import kfgins_run

    fake = tmp_path / "KF-GINS"
    fake.write_text("#!/bin/sh\necho 'no config here' >&2\nexit 3\n")
    fake.chmod(0o755)
    result = kfgins_run(str(fake), 0.5, repeats=1)
    assert result["comparison"] == "" and "exited 3" in result["failure"] and "no config here" in result["failure"]
    lines = _kfgins_lines(kfgins_summary({"kfgins": result}))
    assert lines[2].startswith("KF-GINS comparison skipped: KF-GINS failed: RuntimeError: KF-GINS exited 3")
    assert lines[3:] == [""]


@pytest.mark.slow
def test_campaign_report_compares_with_kfgins(tmp_path):
    """With KF-GINS's binary ($SARINS_KFGINS) the report carries the comparison table, its numbers those
    of the stored comparison, ours within 10 % of KF-GINS's RMS errors (or smaller)."""
    from sarins_fmu.experiments.kfgins_compare import find_binary

    binary, why = find_binary()
    if binary is None:
        pytest.skip(f"KF-GINS comparison: {why}")
    out = tmp_path / "aided"
    argv = ["campaign", "aided-nav", "--profile", "quick", "--runs", "2", "--zupt-runs", "0", "--workers", "1",
            "--out", str(out), "--no-progress", "--kfgins", binary]
    assert main(argv) == 0
    report = (out / "report.md").read_text()
    k = json.loads(str(load_result(out / "runs" / "kfgins.npz")["comparison"]))
    assert json.loads((out / "summary.json").read_text())["kfgins"] == k
    rows = _table(report, "| filter | horizontal RMS (m)")
    assert [r[0] for r in rows] == ["KF-GINS (21 states, P every IMU step)", "ours (15 states, P every 10 IMU steps)",
                                    "ours (15 states, P every IMU step)"]
    for row, key in zip(rows, ("kfgins", "ours", "ours_cov_every_1")):
        assert float(row[1]) == pytest.approx(k[key]["rms"]["horizontal"], abs=5e-4)
        assert row[6] == f"{k[key]['wall_s']:.3f} / {k[key]['cpu_s']:.3f}"
    assert f"{k['speed_ratio_wall']:.1f}x wall, {k['speed_ratio_cpu']:.1f}x CPU" in report
    assert k["duration_s"] > 290 and k["compared_rows"] > 2900
    for key in ("position", "velocity", "attitude_deg"):
        assert k["ours"]["rms"][key] <= 1.1 * k["kfgins"]["rms"][key], key
