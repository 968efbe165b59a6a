"""Reading speed and peak memory of the IMU log reader on CSV logs of 10^6 and 10^7 rows.

    python benchmarks/bench_log_read.py [--rows 1000000 10000000] [--format vendor sarins]
                                        [--folder /tmp/sarins-bench-logs]

Each size of each format is written once into ``--folder``: ``vendor``, a vendor CSV like the real
ADIS16405 records (``time_s,gyro_{x,y,z}_dps, accel_{x,y,z}_g``, 100 Hz, a static MEMS unit's values
with its output steps, short decimals, about 56 bytes a row); ``sarins``, the project's own CSV as
``write_log`` writes it (increments of a static navigation-grade unit at 100 Hz, every number with
``%.17g``: 17 significant digits, about 165 bytes a row).  For each, a fresh child process runs
``sarins_fmu.imu_log.read_log`` on it (the streamed reader: blocks of lines, the line grammar,
the unit checks, storage) and reports wall and CPU seconds and its peak resident memory
(``ru_maxrss``) after the read; then, in the same process, the baseline: ``numpy.loadtxt`` of the
same file's first 10^6 rows (a plain parse with no checks), and the ratio of the two speeds.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
HEADER = "time_s,gyro_x_dps,gyro_y_dps,gyro_z_dps,accel_x_g,accel_y_g,accel_z_g\n"
BASELINE_ROWS = 1_000_000


def write_csv(path: Path, rows: int, block: int = 200_000) -> None:
    """A static MEMS record: gyro steps of 0.05 deg/s, accelerometer steps of 1/300 g, 100 Hz."""
    rng = np.random.default_rng(0)
    with open(path, "w") as fh:
        fh.write(HEADER)
        for k0 in range(0, rows, block):
            k = min(block, rows - k0)
            t = (k0 + np.arange(k)) / 100.0
            gyro = np.round((np.array([0.4, -0.42, 0.29]) + 0.25 * rng.standard_normal((k, 3))) / 0.05) * 0.05
            accel = np.round((np.array([0.0, 0.0, -1.016]) + 0.004 * rng.standard_normal((k, 3))) * 300) / 300
            np.savetxt(fh, np.column_stack([t, gyro, accel]), delimiter=",", fmt=["%.2f"] + ["%.2f"] * 3 + ["%.5f"] * 3)


def write_sarins(path: Path, rows: int, block: int = 200_000) -> None:
    """The project's CSV (``write_log``, ``%.17g``): a static unit at 45 deg N, right-front-up, 100 Hz."""
    sys.path.insert(0, str(ROOT))
    from sarins_fmu.imu_log import write_log

    rng = np.random.default_rng(0)
    h, lat = 0.01, np.radians(45.0)
    rate = 7.292115e-5 * np.array([0.0, np.cos(lat), np.sin(lat)])
    for k0 in range(0, rows, block):
        k = min(block, rows - k0)
        t = (k0 + np.arange(k)) * h
        dtheta = rate * h + 1e-7 * rng.standard_normal((k, 3))
        dv = np.array([0.0, 0.0, 9.806]) * h + 1e-5 * rng.standard_normal((k, 3))
        if k0 == 0:
            write_log(path, t, dtheta, dv, lat_deg=45.0)
        else:
            with open(path, "a") as fh:
                np.savetxt(fh, np.column_stack([t, dtheta, dv]), delimiter=",", fmt="%.17g")


def child(path: str) -> None:
    """Run in a fresh process: our reader, then the baseline; print one JSON line."""
    sys.path.insert(0, str(ROOT))
    import warnings

    from sarins_fmu.imu_log import ReadOptions, read_log

    base_rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    w0, c0 = time.perf_counter(), time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        log = read_log(path, ReadOptions(axes="frd") if Path(path).name.startswith("vendor") else ReadOptions())
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    rows = len(log.time)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    del log
    w0, c0 = time.perf_counter(), time.process_time()
    with open(path) as fh:
        skip = next(k for k, line in enumerate(fh, 1) if line.startswith("time_s"))  # through the column header
        fh.seek(0)
        data = np.loadtxt(fh, delimiter=",", skiprows=skip, max_rows=BASELINE_ROWS)
    b_wall, b_cpu = time.perf_counter() - w0, time.process_time() - c0
    print(json.dumps({"rows": rows, "wall_s": wall, "cpu_s": cpu, "peak_rss_mb": peak / 1024,
                      "rss_before_mb": base_rss / 1024, "baseline_rows": int(data.shape[0]), "baseline_wall_s": b_wall,
                      "baseline_cpu_s": b_cpu}))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, nargs="+", default=[1_000_000, 10_000_000])
    parser.add_argument("--format", nargs="+", choices=["vendor", "sarins"], default=["vendor", "sarins"])
    parser.add_argument("--folder", type=Path, default=Path("/tmp/sarins-bench-logs"))
    parser.add_argument("--child", default=None, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.child)
        return
    args.folder.mkdir(parents=True, exist_ok=True)
    print("| format | rows | file | read wall s | read CPU s | rows/s (CPU) | peak RSS MB | loadtxt rows/s (CPU, 1e6 rows) | "
          "ours / loadtxt |")
    print("|---|---|---|---|---|---|---|---|---|")
    for fmt, rows in [(fmt, rows) for fmt in args.format for rows in args.rows]:
        path = args.folder / f"{fmt}_{rows}.csv"
        if not path.is_file():
            (write_csv if fmt == "vendor" else write_sarins)(path, rows)
        out = subprocess.run([sys.executable, __file__, "--child", str(path)], capture_output=True, text=True,
                             check=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
        r = json.loads(out.stdout.strip().splitlines()[-1])
        ours, theirs = r["rows"] / r["cpu_s"], r["baseline_rows"] / r["baseline_cpu_s"]
        print(f"| {fmt} | {rows:.0e} | {path.stat().st_size / 2**20:.0f} MiB | {r['wall_s']:.1f} | {r['cpu_s']:.1f} | "
              f"{ours:,.0f} | {r['peak_rss_mb']:.0f} | {theirs:,.0f} | {ours / theirs:.2f} |", flush=True)


if __name__ == "__main__":
    main()
