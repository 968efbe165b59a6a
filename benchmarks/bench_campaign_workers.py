"""Speed-up of the axial-rbf campaign with 2 local workers vs 1.

Runs the same subset of seed 000 experiments (training runs: 4 h alignment +
12 h navigation, in process or through the FMUs) twice through
``sarins.campaign.run_campaign`` into fresh folders, once with
``workers=1`` (in this process, one after another, its C core's batches limited
to one thread like a worker's) and once with ``workers=2`` (spawned process
pool, single-threaded workers), and reports both wall times, their ratio and
the load average before and after (on a machine shared with other jobs the
ratio is what the free cores allow, not the code's limit).  ``--threads``
also times the in-process run with the core's default thread count.

Usage: ``python benchmarks/bench_campaign_workers.py [--runs 6] [--engine inprocess|cosim]``
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from sarins.campaign import Task, run_campaign  # noqa: E402
from sarins_fmu.experiments import axial_rbf as s0  # noqa: E402
from sarins_fmu.core.imu import thread_count  # noqa: E402
from sarins.axial_rbf.runs import train_task  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=6, help="experiments in the subset (default 6)")
    parser.add_argument("--engine", choices=("inprocess", "cosim"), default="inprocess")
    parser.add_argument("--threads", action="store_true",
                        help="also time one process with the core's default threads (all cores)")
    args = parser.parse_args()
    load_before = _load()
    exps = s0.generate("hot", args.runs, 1, 99)[: args.runs]
    times = {}
    with tempfile.TemporaryDirectory() as tmp:
        fmu_dir = None
        if args.engine == "cosim":
            from fmus.build import build_fmus

            fmu_dir = str(build_fmus(Path(tmp) / "fmus")[0].parent)
        tasks = [Task(e.name, train_task, {"exp": e.to_dict(), "engine": args.engine, "fmu_dir": fmu_dir},
                      volatile=("fmu_dir",)) for e in exps]
        train_task(exps[0].to_dict(), args.engine, fmu_dir)  # warm-up (imports) in this process
        if args.threads:
            t0 = time.perf_counter()
            run_campaign(tasks, Path(tmp) / "threads", workers=1, progress=False)
            times["threads"] = time.perf_counter() - t0
        os.environ["SARINS_THREADS"] = "1"
        for workers in (1, 2):
            t0 = time.perf_counter()
            results = run_campaign(tasks, Path(tmp) / f"w{workers}", workers=workers, progress=False)
            times[workers] = time.perf_counter() - t0
        os.environ.pop("SARINS_THREADS", None)
        one = run_campaign(tasks, Path(tmp) / "w1", progress=False)
        assert all(results[t.id]["lat_error_deg"] == one[t.id]["lat_error_deg"] for t in tasks)
    report = {"runs": args.runs, "engine": args.engine, "wall_1_worker_s": round(times[1], 1),
              "wall_2_workers_s": round(times[2], 1), "speedup": round(times[1] / times[2], 2),
              "load_avg_before": load_before, "load_avg_after": _load()}
    if "threads" in times:
        threads = thread_count()
        report.update({f"wall_1_process_{threads}_threads_s": round(times["threads"], 1),
                       "speedup_vs_threads": round(times["threads"] / times[2], 2)})
    print(json.dumps(report))
    return 0


def _load() -> list:
    with open("/proc/loadavg") as fh:
        return [float(x) for x in fh.read().split()[:3]]


if __name__ == "__main__":
    sys.exit(main())
