"""Crash count at process exit: an FMU through FMPy's FMU2Slave in fresh processes.

Each process extracts the FMU, instantiates it, runs STEPS doSteps fed so
that they do real work (``fmu_runs.feeds``: StrapdownINS gets tagged
increments of a static, level IMU), terminates, frees it and exits.  The
script counts processes that do not exit 0 (pythonfmu 0.7's binaries aborted
here with "corrupted double-linked list"; FACTS.md).  Point ``--fmu-dir`` at
FMUs built by another version to compare (IMUCompensator and IMULog are built
here in any case, with a small model and a short simulated log).

Usage: ``python benchmarks/bench_fmu_exit.py [--fmu-dir DIR] [--runs 10] [--names StrapdownINS ...]``
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import fmu_runs


def count_crashes(fmu: Path, feed, runs: int, steps: int, env: dict) -> list[int]:
    """Exit codes of the processes that did not exit 0 (or did not finish)."""
    bad = []
    for _ in range(runs):
        proc = subprocess.run(fmu_runs.fmpy_command(fmu, feed, steps, stamps=()), capture_output=True, text=True,
                              timeout=600, env=env)
        if proc.returncode != 0 or "ok" not in proc.stdout.split():
            bad.append(proc.returncode)
    return bad


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmu-dir", type=Path, help="folder of built FMUs (default: build them now)")
    parser.add_argument("--runs", type=int, default=10)
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--names", nargs="+", default=["StrapdownINS", "IMUThermal", "Turntable"],
                        choices=fmu_runs.ALL_NAMES)
    args = parser.parse_args()
    sys.path.insert(0, str(fmu_runs.ROOT))
    env = fmu_runs.host_env(os.environ)
    with tempfile.TemporaryDirectory() as tmp:
        given = {n: args.fmu_dir / f"{n}.fmu" for n in args.names
                 if args.fmu_dir is not None and (args.fmu_dir / f"{n}.fmu").exists()}
        paths, feeds = fmu_runs.build_all(Path(tmp), [n for n in args.names if n not in given])
        paths.update(given)
        if "IMULog" in given:
            feeds = fmu_runs.feeds(fmu_runs.write_simulated_log(Path(tmp)))
        for name in args.names:
            bad = count_crashes(paths[name], feeds[name], args.runs, args.steps, env)
            print(f"{name}: {len(bad)}/{args.runs} processes did not exit 0" + (f" (codes {bad})" if bad else ""))


if __name__ == "__main__":
    main()
