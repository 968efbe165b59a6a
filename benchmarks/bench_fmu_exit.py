"""Crash count at process exit: an FMU through FMPy's FMU2Slave in fresh processes.

Each process instantiates the FMU, runs STEPS doSteps (StrapdownINS gets the
increments of a static, level IMU), terminates, frees it and exits.  The
script counts processes that do not exit 0 (pythonfmu 0.7's binaries aborted
here with "corrupted double-linked list"; FACTS.md).  Point ``--fmu-dir`` at
FMUs built by another version to compare.

Usage: ``python benchmarks/bench_fmu_exit.py [--fmu-dir DIR] [--runs 10] [--names StrapdownINS ...]``
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = """
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave
path = {path!r}
md = read_model_description(path)
fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(path), modelIdentifier=md.coSimulation.modelIdentifier,
                instanceName="x")
fmu.instantiate()
vr = {{v.name: v.valueReference for v in md.modelVariables}}
if md.coSimulation.modelIdentifier == "StrapdownINS":
    fmu.setReal([vr["dtheta_y"], vr["dtheta_z"], vr["dv_z"]], [6.4258e-5, 3.4486e-5, 9.7913])
fmu.setupExperiment(startTime=0.0)
fmu.enterInitializationMode()
fmu.exitInitializationMode()
for k in range({steps}):
    fmu.doStep(float(k), 1.0)
fmu.terminate()
fmu.freeInstance()
print("ok")
"""


def count_crashes(fmu: Path, runs: int, steps: int) -> list[int]:
    """Exit codes of the processes that did not exit 0."""
    bad = []
    for _ in range(runs):
        proc = subprocess.run([sys.executable, "-c", CHILD.format(path=str(fmu), steps=steps)],
                              capture_output=True, text=True, timeout=600)
        if proc.returncode != 0 or "ok" not in proc.stdout:
            bad.append(proc.returncode)
    return bad


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fmu-dir", type=Path, help="folder of built FMUs (default: build them now)")
    parser.add_argument("--runs", type=int, default=10)
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--names", nargs="+", default=["StrapdownINS", "IMUThermal", "Turntable"])
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        fmu_dir = args.fmu_dir
        if fmu_dir is None:
            sys.path.insert(0, str(ROOT))
            from fmus.build import build_fmus

            fmu_dir = Path(tmp)
            build_fmus(fmu_dir, args.names)
        for name in args.names:
            bad = count_crashes(fmu_dir / f"{name}.fmu", args.runs, args.steps)
            print(f"{name}: {len(bad)}/{args.runs} processes did not exit 0" + (f" (codes {bad})" if bad else ""))


if __name__ == "__main__":
    main()
