"""Start-up: time from a fresh host process's start to the end of each FMU's first doStep.

Each FMU runs twice in fresh FMPy processes (it is unpacked to a new folder
every time, as FMPy does) against an empty per-user cache (a temporary
``SARINS_FMU_CACHE``): the first run fills the cache (the shipped library
is copied there and numba compiles its kernels), the second finds it.  With
numba installed the first run includes the kernels' compilation.

Usage: ``python benchmarks/bench_startup.py [--names IMUThermal ...]``
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NAMES = ["Turntable", "IMUThermal", "StrapdownINS", "RBFIdentifier", "DriftModelUpdater"]

CHILD = """
import time
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
fmu.doStep(0.0, 1.0)
print("FIRST_STEP_DONE", time.time())
fmu.terminate()
fmu.freeInstance()
"""


def first_step_seconds(fmu: Path, env: dict) -> float:
    t0 = time.time()
    proc = subprocess.run([sys.executable, "-c", CHILD.format(path=str(fmu))], capture_output=True, text=True,
                          env=env, timeout=900)
    if proc.returncode != 0 or "FIRST_STEP_DONE" not in proc.stdout:
        raise RuntimeError(f"{fmu.name}: {proc.stderr[-1000:]}")
    return float(proc.stdout.split("FIRST_STEP_DONE")[1].split()[0]) - t0


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--names", nargs="+", default=NAMES)
    args = parser.parse_args()
    sys.path.insert(0, str(ROOT))
    from fmus.build import build_fmus

    with tempfile.TemporaryDirectory() as tmp:
        fmu_dir, cache = Path(tmp) / "fmus", Path(tmp) / "cache"
        build_fmus(fmu_dir, args.names)
        env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "SARINS_NO_NUMBA")}
        env["SARINS_FMU_CACHE"] = str(cache)
        t0 = time.time()
        subprocess.run([sys.executable, "-c", "import fmpy.fmi2, numpy, scipy.linalg, numba"], env=env, check=True)
        floor = time.time() - t0
        print("time from process start to the end of the first doStep (FMPy host, fresh unpack each run)")
        print(f"{'floor':18s} {floor:.2f} s: a process that only imports fmpy, numpy, scipy and numba")
        for name in args.names:  # FMUs of one build share the cached library: run each on an empty cache
            if cache.exists():
                import shutil

                shutil.rmtree(cache)
            first = first_step_seconds(fmu_dir / f"{name}.fmu", env)
            second = first_step_seconds(fmu_dir / f"{name}.fmu", env)
            print(f"{name:18s} first run {first:6.2f} s   second run {second:6.2f} s")


if __name__ == "__main__":
    main()
