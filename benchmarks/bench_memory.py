"""Memory of each FMU over many steps (default 10^6), driven through FMPy.

Each FMU runs alone in a fresh subprocess (inputs held at their start
values; the IMU sees a table at rest), and the resident set size is sampled
every 10 % of the run.  A flat profile means no per-step growth: the figure
reported is the RSS increase over the second half of the run, per step.

Usage: ``python benchmarks/bench_memory.py [--steps 1000000] [--only NAME ...]``
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import sys, time
sys.path[:0] = [{root!r}, {tests!r}]
from fmu_driver import Slave

def rss_kb():
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])

s = Slave({fmu!r}, "m")
s.fmu.enterInitializationMode(); s.fmu.exitInitializationMode()
s.set(**{inputs!r})
n = {steps}
marks = []
t0 = time.perf_counter()
tag = s.vr.get("increment_end_time")  # a time-tagged input (StrapdownINS): the interval about to be fed
row = s.vr.get("nav_time")  # DriftModelUpdater: the INS row it processes
for k in range(n):
    if tag is not None:
        s.fmu.setReal([tag], [float(k + 1)])
    if row is not None:
        s.fmu.setReal([row], [float(k)])
    s.fmu.doStep(float(k), 1.0)
    if k % (n // 10) == 0 or k == n - 1:
        marks.append(rss_kb())
print(" ".join(map(str, marks)), time.perf_counter() - t0)
s.free()
"""


def static_increments() -> dict:
    """Increments of a level IMU at rest facing north at 28.222 deg (1 s)."""
    import math

    from sarins_fmu import earth

    lat = math.radians(28.222)
    w = earth.earth_rate_n(lat)
    return {"dtheta_x": 0.0, "dtheta_y": float(w[1]), "dtheta_z": float(w[2]), "dv_x": 0.0, "dv_y": 0.0,
            "dv_z": float(earth.gravity(lat, 0.0))}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1_000_000)
    parser.add_argument("--only", nargs="+", metavar="NAME", default=None, help="measure only these FMUs")
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT))
    from fmus.build import build_fmus

    failed = []
    with tempfile.TemporaryDirectory() as tmp:
        fmus = build_fmus(tmp)
        try:
            fmus.append(_compensator_fmu(Path(tmp)))
        except Exception as exc:  # noqa: BLE001  (reported, the others still run)
            print(f"{'IMUCompensator':<13} skipped: no FMU with a model could be built "
                  f"({type(exc).__name__}: {' '.join(str(exc).split())[:200]})")
        for fmu in fmus:
            if args.only and fmu.stem not in args.only:
                continue
            if fmu.stem == "IMULog":  # plays a recorded log: nothing to measure without one
                print(f"{fmu.stem:<13} skipped: needs a recorded log file (parameter log_file)")
                continue
            code = CHILD.format(root=str(ROOT), tests=str(ROOT / "tests"), fmu=str(fmu), steps=args.steps,
                                inputs=static_increments() if fmu.stem == "StrapdownINS" else {})
            out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
            if out.returncode != 0:
                reason = (out.stderr.strip().splitlines() or [f"exit status {out.returncode}"])[-1]
                if fmu.stem == "IMUCompensator" and not _ships_model(fmu):
                    print(f"{fmu.stem:<13} skipped: this build ships no compensator model ({reason})")
                    continue
                print(f"{fmu.stem:<13} FAILED: {reason}")
                failed.append(fmu.stem)
                continue
            *marks, wall = out.stdout.split()
            kb = [int(m) for m in marks]
            half = kb[len(kb) // 2:]
            growth = (half[-1] - half[0]) * 1024 / (args.steps / 2)
            print(f"{fmu.stem:<13} {args.steps} steps in {float(wall):6.1f} s; RSS MB "
                  + " ".join(f"{k / 1024:.1f}" for k in kb)
                  + f"; growth over the second half {growth:+.3f} bytes/step")
    if failed:
        raise SystemExit(f"bench_memory: failed: {', '.join(failed)}")


def _compensator_fmu(folder: Path) -> Path:
    """IMUCompensator carrying a small RBF compensator fitted on a synthetic
    series (the FMU needs a trained model; its size, not its accuracy, matters here)."""
    import numpy as np

    from fmus.compensator_export import export_compensator
    from sarins_fmu.identify import compensators

    rng = np.random.default_rng(0)
    t = np.arange(2000) * 0.1
    truth = np.column_stack([0.1 * np.sin(0.05 * t), 0.1 * np.cos(0.03 * t), 0.1 * np.sin(0.02 * t),
                             np.sin(0.01 * t), np.cos(0.013 * t), 9.8 + 0.1 * np.sin(0.02 * t)])
    temp = 10.0 + 20.0 * np.sin(0.002 * t)
    meas = truth * 1.001 + 1e-4 + 1e-5 * rng.standard_normal(truth.shape)
    model = compensators.make("rbf", max_samples=500).fit(np.column_stack([meas, temp]), truth)
    return export_compensator(model.save(folder / "compensator_model.npz"), folder)


def _ships_model(fmu: Path) -> bool:
    """Whether an IMUCompensator FMU carries a trained model in its resources."""
    import zipfile

    from fmus.imu_compensator_slave import MODEL_IN_RESOURCES

    with zipfile.ZipFile(fmu) as zf:
        return f"resources/{MODEL_IN_RESOURCES}" in zf.namelist()


if __name__ == "__main__":
    main()
