"""How much the NEES fraction of one Monte Carlo set varies from set to set (docs/aided-navigation.md,
"Consistency of the campaign's drive").

The aided-nav campaign's drive and filter (``sarins_fmu.experiments.aided_nav``: tactical IMU, white 1 Hz
GNSS with its 30, 60 and 120 s outages, ZUPT at the stops, the paper profile's output every 0.2 s) run for
``sets`` x ``runs`` seeds (0 ..).  Per set of ``runs``: the time-mean of the mean NEES of position, velocity
and attitude and the fraction of the output times at which the mean lies in its 95 % chi-square band (the
campaign's statistic).  Pooled over all the runs: the same with the narrower band of sets x runs values, and
the longest stretch outside it; a filter inconsistent at some phase of the drive (a turn, an outage's end)
leaves the pooled band there, where chance excursions of one set average out.

Run from the project root:  PYTHONPATH=$PWD python3 docs/examples/nees_seed_sets.py [sets] [runs]
(2 worker processes).  Writes docs/results/aided-navigation/nees_seed_sets.json and prints the tables.
"""

from __future__ import annotations

import json
import sys
from multiprocessing import Pool
from pathlib import Path

import numpy as np
from scipy.stats import chi2

from sarins_fmu.experiments import aided_nav

OUT = Path(__file__).resolve().parents[1] / "results" / "aided-navigation" / "nees_seed_sets.json"
SETS, RUNS = 10, 100
OUT_EVERY = 20  # the campaign's output every 0.2 s


def nees(seed: int) -> tuple:
    """(time (n,) s, (n, 3) position, velocity, attitude NEES) of one campaign run."""
    run = aided_nav.monte_carlo_run(seed, out_every=OUT_EVERY)
    return run["time"], run["nees"]


def band(runs: int) -> tuple:
    """Two-sided 95 % band of the mean of ``runs`` chi-square(3) values."""
    return chi2.ppf(0.025, 3 * runs) / runs, chi2.ppf(0.975, 3 * runs) / runs


def longest_outside(time: np.ndarray, outside: np.ndarray) -> list:
    """[start, end] s of the longest run of output times outside the band (empty when none)."""
    best, start, best_span = [], None, -1.0
    for i, out in enumerate(np.append(outside, False)):
        if out and start is None:
            start = i
        elif not out and start is not None:
            span = time[i - 1] - time[start]
            if span > best_span:
                best, best_span = [float(time[start]), float(time[i - 1])], span
            start = None
    return best


def block_stats(mean: np.ndarray, lo: float, hi: float, time: np.ndarray) -> dict:
    outside = (mean < lo) | (mean > hi)
    return {"time_mean": float(mean.mean()), "inside": float(1.0 - outside.mean()),
            "longest_outside_s": longest_outside(time, outside), "max": float(mean.max())}


def main(sets: int = SETS, runs: int = RUNS) -> dict:
    with Pool(2) as pool:
        done = pool.map(nees, range(sets * runs), chunksize=10)
    time, values = done[0][0], np.array([v for _, v in done])  # values (runs, n, 3)
    names = aided_nav.BLOCKS
    lo, hi = band(runs)
    per_set = []
    for s in range(sets):
        mean = values[s * runs:(s + 1) * runs].mean(axis=0)
        per_set.append({"seeds": [s * runs, (s + 1) * runs - 1],
                        **{b: block_stats(mean[:, j], lo, hi, time) for j, b in enumerate(names)}})
    plo, phi = band(sets * runs)
    pooled = values.mean(axis=0)
    return {"sets": sets, "runs": runs, "band": [lo, hi], "pooled_band": [plo, phi], "per_set": per_set,
            "pooled": {b: block_stats(pooled[:, j], plo, phi, time) for j, b in enumerate(names)},
            "mean_inside": {b: float(np.mean([row[b]["inside"] for row in per_set])) for b in names},
            "script": "docs/examples/nees_seed_sets.py"}


if __name__ == "__main__":
    args = [int(a) for a in sys.argv[1:3]]
    result = main(*args)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    OUT.write_text(json.dumps(result, indent=1) + "\n")
    names = aided_nav.BLOCKS
    lo, hi = result["band"]
    print(f"band of the mean of {result['runs']}: {lo:.3f} .. {hi:.3f}")
    print("| seeds | " + " | ".join(f"{b}: time-mean, inside" for b in names) + " |")
    print("|---|" + "---|" * len(names))
    for row in result["per_set"]:
        print(f"| {row['seeds'][0]}-{row['seeds'][1]} | "
              + " | ".join(f"{row[b]['time_mean']:.3f}, {100 * row[b]['inside']:.1f} %" for b in names) + " |")
    print("| mean over the sets | " + " | ".join(f"{100 * result['mean_inside'][b]:.1f} %" for b in names) + " |")
    plo, phi = result["pooled_band"]
    print(f"pooled over {result['sets'] * result['runs']} runs, band {plo:.3f} .. {phi:.3f}:")
    for b in names:
        p = result["pooled"][b]
        print(f"  {b}: time-mean {p['time_mean']:.3f}, inside {100 * p['inside']:.1f} %, "
              f"longest outside {p['longest_outside_s']}, max {p['max']:.3f}")
