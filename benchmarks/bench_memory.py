"""Memory of each FMU over many steps (default 10^6), driven through FMPy.

Each FMU runs alone in a fresh subprocess, fed by ``fmu_runs.feeds`` so that
every step computes (constant inputs, e.g. a table at rest and a level IMU's
increments; time tags advanced every step), and the resident set size is sampled
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

import fmu_runs

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
s.set(**{values!r})
s.fmu.enterInitializationMode(); s.fmu.exitInitializationMode()
tags = [(s.vr[name], offset) for name, offset in {tags!r}.items()]  # input = t + offset before doStep(t)
n = {steps}
marks = []
t0 = time.perf_counter()
for k in range(n):
    for vr, offset in tags:
        s.fmu.setReal([vr], [k + offset])
    s.fmu.doStep(float(k), 1.0)
    if k % (n // 10) == 0 or k == n - 1:
        marks.append(rss_kb())
print(" ".join(map(str, marks)), time.perf_counter() - t0)
s.free()
"""


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1_000_000)
    parser.add_argument("--only", nargs="+", metavar="NAME", default=None, help="measure only these FMUs")
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT))
    from fmus.build import build_fmus

    failed = []
    feeds = fmu_runs.feeds()
    with tempfile.TemporaryDirectory() as tmp:
        fmus = build_fmus(tmp)
        try:
            fmus.append(fmu_runs.compensator_fmu(Path(tmp)))
        except Exception as exc:  # noqa: BLE001  (reported, the others still run)
            print(f"{'IMUCompensator':<13} skipped: no FMU with a model could be built "
                  f"({type(exc).__name__}: {' '.join(str(exc).split())[:200]})")
        for fmu in fmus:
            if args.only and fmu.stem not in args.only:
                continue
            if fmu.stem == "IMULog":  # plays a recorded log: nothing to measure without one
                print(f"{fmu.stem:<13} skipped: needs a recorded log file (parameter log_file)")
                continue
            feed = feeds[fmu.stem]
            code = CHILD.format(root=str(ROOT), tests=str(ROOT / "tests"), fmu=str(fmu), steps=args.steps,
                                values=feed.values, tags=feed.tags)
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


def _ships_model(fmu: Path) -> bool:
    """Whether an IMUCompensator FMU carries a trained model in its resources."""
    import zipfile

    from fmus.imu_compensator_slave import MODEL_IN_RESOURCES

    with zipfile.ZipFile(fmu) as zf:
        return f"resources/{MODEL_IN_RESOURCES}" in zf.namelist()


if __name__ == "__main__":
    main()
