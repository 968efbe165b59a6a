"""Benchmark of the physics core: one 88 h static run in process.

4 h alignment + 12 h + 72 h navigation, 200 Hz internal IMU rate, 1 s INS
step, nav-rlg noise.  Prints wall seconds, the ratio of simulated to wall
time, and where the time goes (IMU minor loop, INS, the rest), each as a
share of the same run.  The first (compiling) run is reported separately.

    python benchmarks/bench_core.py [--repeat 3]
"""

import argparse
import time

import numpy as np

from sarins_fmu.experiments import static_run
from sarins_fmu.imu import IMU
from sarins_fmu.ins import StrapdownINS


def _timed(cls, name, totals):
    original = getattr(cls, name)

    def wrapper(self, *args, **kwargs):
        t0 = time.perf_counter()
        try:
            return original(self, *args, **kwargs)
        finally:
            totals[cls.__name__] = totals.get(cls.__name__, 0.0) + time.perf_counter() - t0

    setattr(cls, name, wrapper)
    return original


def _baseline(n_samples: int) -> float:
    """Wall time of one vectorised numpy sin per 200 Hz sample of the run, s
    (the machine-speed yardstick the run is compared with)."""
    x = np.linspace(0.0, 1e4, 1_000_000)
    t0 = time.perf_counter()
    for _ in range(n_samples // len(x)):
        np.sin(x)
    return time.perf_counter() - t0


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    simulated = 88 * 3600.0
    t0 = time.perf_counter()
    static_run.run_static(nav_hours=0.1, align_hours=0.2)
    print(f"first call (imports, loading the C core): {time.perf_counter() - t0:.2f} s")
    walls = []
    for _ in range(args.repeat):
        totals = {}
        imu_step = _timed(IMU, "step", totals)
        ins_step = _timed(StrapdownINS, "step", totals)
        t0 = time.perf_counter()
        result = static_run.run_static(align_hours=4.0, nav_hours=84.0, imu="nav-rlg", seed=1)
        wall = time.perf_counter() - t0
        IMU.step, StrapdownINS.step = imu_step, ins_step
        walls.append(wall)
        rest = wall - sum(totals.values())
        print(f"88 h run: {wall:.2f} s wall, {simulated / wall:,.0f}x real time | "
              f"IMU {totals['IMU'] / wall:.0%}, INS {totals['StrapdownINS'] / wall:.0%}, rest {rest / wall:.0%} "
              f"| position error {result.position_error[-1] / 1852:.2f} nmi")
    best = min(walls)
    base = _baseline(int(simulated * 200))
    print(f"baseline (numpy sin over the run's {simulated * 200:.3g} samples): {base:.2f} s; "
          f"run / baseline = {best / base:.2f}")
    print(f"best of {len(walls)}: {best:.2f} s, {simulated / best:,.0f}x real time "
          f"(target >= 40,000x, i.e. <= 7.9 s); median {np.median(walls):.2f} s")


if __name__ == "__main__":
    main()
