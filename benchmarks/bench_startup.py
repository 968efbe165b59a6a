"""Start-up: time from a fresh host process's start to the end of each FMU's first real doStep.

Every FMU we build (IMUCompensator with a small trained model, IMULog with a
short simulated log) runs in fresh host processes, each on a fresh unpack,
fed so that its first doStep does real work (``fmu_runs.feeds``: e.g.
StrapdownINS gets increments tagged for the interval ending at t + h):

* FMPy host: a Python process that imports FMPy, extracts the FMU to a new
  folder and calls it through ``FMU2Slave`` (clock from just before the
  process is started);
* C host: ``tests/native_host/host.c``, no Python in the process and no
  environment prepared; the FMU finds its Python itself (clock from just
  before the bench unzips the FMU into a new folder for it).

The first run of each (FMU, host) pair meets an empty per-user cache (a
temporary ``SARINS_FMU_CACHE``: the FMU copies its library there and numba
compiles its kernels); the following ``--repeat`` runs find it (reported:
their median, and the slowest).  Also reported: the end of the 5th doStep,
which for StrapdownINS is its first navigation step (coarse and fine
alignment shortened to 2 s each), and the floor, processes that only import
what the hosts need.  Machine load averages are printed before and after.

Usage: ``python benchmarks/bench_startup.py [--names IMUThermal ...] [--hosts fmpy c] [--repeat 3]``
"""
from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import fmu_runs

LAST_STAMP = 5  # StrapdownINS: first navigation step (fmu_runs.INS_PHASES)


def floor_seconds(code: str, env: dict) -> float:
    """Wall time of a fresh ``python -c code``."""
    t0 = time.time()
    subprocess.run([sys.executable, "-c", code], env=env, check=True)
    return time.time() - t0


def one_run(host: str, fmu: Path, feed, env: dict, work: Path, c_host: Path | None) -> dict:
    """{step: seconds} of one fresh process of ``host`` ('fmpy' or 'c')."""
    t0 = time.time()
    if host == "fmpy":
        argv = fmu_runs.fmpy_command(fmu, feed, LAST_STAMP, stamps=(1, LAST_STAMP))
    else:
        folder = fmu_runs.unzip(fmu, Path(tempfile.mkdtemp(prefix=f"{fmu.stem}.", dir=work)))
        argv = fmu_runs.c_host_command(c_host, folder, fmu, feed, LAST_STAMP, stamps=(1, LAST_STAMP))
    try:
        return fmu_runs.run_host(argv, env, t0)[0]
    finally:
        if host == "c":
            shutil.rmtree(folder, ignore_errors=True)


def measure(name: str, host: str, fmu: Path, feed, env: dict, cache: Path, work: Path, c_host, repeat: int) -> str:
    """One table row: first run on an empty cache, then ``repeat`` runs on the filled one."""
    shutil.rmtree(cache, ignore_errors=True)
    first = one_run(host, fmu, feed, env, work, c_host)
    again = [one_run(host, fmu, feed, env, work, c_host) for _ in range(repeat)]
    second = statistics.median(r[1] for r in again)
    second_last = statistics.median(r[LAST_STAMP] for r in again)
    return (f"{name:18s} {host:5s} {first[1]:7.2f} {first[LAST_STAMP]:7.2f}   {second:7.2f} "
            f"{max(r[1] for r in again):6.2f} {second_last:7.2f}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--names", nargs="+", default=fmu_runs.ALL_NAMES, choices=fmu_runs.ALL_NAMES)
    parser.add_argument("--hosts", nargs="+", default=["fmpy", "c"], choices=["fmpy", "c"])
    parser.add_argument("--repeat", type=int, default=3, help="second runs per FMU and host (median reported)")
    args = parser.parse_args()
    sys.path.insert(0, str(fmu_runs.ROOT))
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())} (1, 5, 15 min) at the start")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        paths, feeds = fmu_runs.build_all(tmp / "fmus", args.names)
        c_host = fmu_runs.build_c_host(tmp / "host") if "c" in args.hosts else None
        cache = tmp / "cache"
        env = fmu_runs.host_env(os.environ, SARINS_FMU_CACHE=str(cache))
        print("floor (fresh process, s): python -c pass "
              f"{floor_seconds('pass', env):.2f}; import numpy, scipy.linalg, numba "
              f"{floor_seconds('import numpy, scipy.linalg, numba', env):.2f}; + fmpy.fmi2 "
              f"{floor_seconds('import fmpy.fmi2, numpy, scipy.linalg, numba', env):.2f}")
        print("seconds from process start (C host: from the unzip) to the end of doStep 1 and doStep 5\n"
              f"{'':24s} first run (empty cache)   second run (cache filled, {args.repeat} runs)\n"
              f"{'FMU':18s} {'host':5s} {'step 1':>7s} {'step 5':>7s}   {'step 1':>7s} {'max':>6s} {'step 5':>7s}")
        for name in args.names:
            for host in args.hosts:
                print(measure(name, host, paths[name], feeds[name], env, cache, tmp, c_host, args.repeat),
                      flush=True)
    print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())} at the end")


if __name__ == "__main__":
    main()
