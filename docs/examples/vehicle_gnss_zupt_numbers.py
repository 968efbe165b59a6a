"""The numbers of docs/aided-navigation.md's "The `vehicle_gnss_zupt` system" paragraph: the systems' default drive
(sarins.systems.GNSS_DRIVE, 124.6 s, 1 Hz SPS fixes, tactical IMU, GNSS outage 60-80 s) navigated in process on
the core's streams (aided.navigate(..., imu_stream="core"), which the vehicle_gnss, vehicle_gnss_odometer and
vehicle_gnss_zupt systems equal bit for bit: tests/test_vehicle_gnss_system.py) with GNSS alone, with the
odometer, with the non-holonomic constraint, and with everything (ZUPT, ZARU, NHC, odometer).

Per aiding: seed 0 (the systems' default) — the filter's largest horizontal sigma sqrt(P_EE + P_NN) over the
output rows inside the outage, the horizontal error and sigma at the outage's end (aided.outage_table: the last
row before the first fix after it), the drift over the outage (the horizontal length of the position error's
change from the row at the outage's start to that row) and the drive's horizontal RMS error; and over RUNS seeds
the RMS of the end-of-outage error, of the sigma there (their ratio) and of the drift.

Run from the project root:  PYTHONPATH=$PWD python3 docs/examples/vehicle_gnss_zupt_numbers.py
Writes docs/results/aided-navigation/vehicle_gnss_zupt.json and prints a Markdown table (a few seconds).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from sarins.systems import GNSS_DRIVE, GNSS_OUTAGES
from sarins_fmu import aided, gnss
from sarins_fmu import trajectory as tr

OUT = Path(__file__).resolve().parents[1] / "results" / "aided-navigation" / "vehicle_gnss_zupt.json"
RUNS = 50
CASES = {"gnss": ("gnss",), "gnss,odometer": ("gnss", "odometer"), "gnss,nhc": ("gnss", "nhc"),
         "gnss,zupt,zaru,nhc,odometer": ("gnss", "zupt", "zaru", "nhc", "odometer")}


def run(truth, aiding, seed):
    return aided.navigate(truth, noise=aided.IMU_NOISE["tactical"], gnss=gnss.preset("sps", rate_hz=1.0),
                          aiding=aiding, outages=GNSS_OUTAGES, seed=seed, imu_stream="core")


def drift(r, start, end) -> float:
    """Horizontal length of the position error's change over the outage: row at ``start`` to the last row before
    ``end`` (aided.outage_table's row), m."""
    i0 = int(np.searchsorted(r.time, start + 1e-9)) - 1
    i1 = int(np.searchsorted(r.time, end - 1e-9)) - 1
    return float(np.hypot(*(r.error[i1, :2] - r.error[i0, :2])))


def main() -> dict:
    truth = tr.generate(tr.Trajectory.from_dict(GNSS_DRIVE), 0.01)
    start, end = GNSS_OUTAGES[0]
    rows = {}
    for name, aiding in CASES.items():
        r = run(truth, aiding, 0)
        inside = (r.time >= start) & (r.time < end)
        outage = aided.outage_table(r, GNSS_OUTAGES)[0]
        err2, var, drift2 = [], [], []
        for seed in range(RUNS):
            rs = run(truth, aiding, seed)
            o = aided.outage_table(rs, GNSS_OUTAGES)[0]
            err2.append(o.error**2)
            var.append(o.sigma**2)
            drift2.append(drift(rs, start, end) ** 2)
        rms, sigma = float(np.sqrt(np.mean(err2))), float(np.sqrt(np.mean(var)))
        rows[name] = {"seed0_max_sigma_h_in_outage_m": float(r.horizontal_sigma()[inside].max()),
                      "seed0_end_of_outage_error_m": outage.error, "seed0_end_of_outage_sigma_m": outage.sigma,
                      "seed0_drift_over_outage_m": drift(r, start, end),
                      "seed0_horizontal_error_rms_m": float(np.sqrt(np.mean(r.horizontal_error()**2))),
                      "seed0_zupt_steps": r.zupt_steps, "seed0_gnss_fixes_used": r.gnss_used,
                      "runs": RUNS, "rms_end_of_outage_error_m": rms, "rms_end_of_outage_sigma_m": sigma,
                      "ratio": rms / sigma, "rms_drift_over_outage_m": float(np.sqrt(np.mean(drift2)))}
    return {"drive": "sarins.systems.GNSS_DRIVE", "imu": "tactical", "gnss": "sps 1 Hz", "outage_s": [start, end],
            "imu_stream": "core", "cases": rows}


if __name__ == "__main__":
    numbers = main()
    OUT.write_text(json.dumps(numbers, indent=2) + "\n")
    print("| aiding | largest σ_h in the outage, seed 0 (m) | error at the outage's end, seed 0 (m) | drift over "
          f"the outage, seed 0 (m) | RMS error / RMS σ_h at the end, {RUNS} seeds (m) | RMS drift, {RUNS} seeds (m) |")
    print("|---|---|---|---|---|---|")
    for name, r in numbers["cases"].items():
        print(f"| {name} | {r['seed0_max_sigma_h_in_outage_m']:.3f} | {r['seed0_end_of_outage_error_m']:.3f} | "
              f"{r['seed0_drift_over_outage_m']:.3f} | {r['rms_end_of_outage_error_m']:.3f} / "
              f"{r['rms_end_of_outage_sigma_m']:.3f} | {r['rms_drift_over_outage_m']:.3f} |")
