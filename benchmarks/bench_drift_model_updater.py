"""Benchmark of the DriftModelUpdater FMU per communication step against the in-process library.

The yardstick is the library's :class:`~sarins_fmu.identify.online.OnlineDriftUpdater` fed one row per
call (the same C core through ctypes: the cost of the row logic, the stop filter step and the Python call);
for reference the library fed all rows in one call (the in-process engines' way).
Against it, in the same process and on the same rows (a parked, navigating vehicle: the stop filter runs
at every step; and a drive with stops), the FMU through FMPy's ``FMU2Slave`` with the inputs set and the
outputs read every step as a master would: the FMU built from this tree (native, ``--fmu-dir``) and, with
``--other``, another build of it (e.g. the Python-hosted slave of an older commit) loaded beside it.
Each figure is the best of ``--rounds`` rounds, printed in us per step and as its ratio to the yardstick.

    python benchmarks/bench_drift_model_updater.py [--steps 3000] [--rounds 3] [--fmu-dir DIR] [--other FMU]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from sarins_fmu.identify.online import OnlineDriftUpdater, prior_covariance
from sarins_fmu.identify.rls import ForgettingRLS, RLSSettings
from sarins_fmu.units import DPH_TO_RPS

ROW_INPUTS = ["v_e", "v_n", "yaw", "pitch", "roll", "lat", "temp_gyro_z", "nav_time", "vehicle_speed"]
OUTPUTS = ["compensation_drift", "apply_from", "drift_a", "drift_b", "drift_c", "stop_timer", "drift_estimate"]
COEF = np.array([1e-6, -4e-5, 0.0025]) * DPH_TO_RPS


def rows(n: int, parked: bool, seed: int = 1) -> np.ndarray:
    """(n, 9) INS rows in ROW_INPUTS order: parked (every row a stop row) or drives with 200 s stops."""
    rng = np.random.default_rng(seed)
    speed = np.zeros(n) if parked else np.where((np.arange(n) // 200) % 2 == 0, 0.0, 8.0)
    return np.column_stack([1e-3 * rng.standard_normal((n, 2)), rng.uniform(-3, 3, n), np.zeros((n, 2)),
                            np.full(n, 0.7), 25.0 + 0.001 * np.arange(n), np.arange(1.0, n + 1), speed])


def library(table: np.ndarray) -> float:
    """Seconds for the library fed one row per call."""
    up = OnlineDriftUpdater(ForgettingRLS(COEF, prior_covariance(), 0.0, RLSSettings(0.8)), 0.7)
    t0 = time.perf_counter()
    for r in table:
        up.step([r[7]], [r[8]], [r[0:2]], [r[2:5]], [r[6]], [r[5]])
    return time.perf_counter() - t0


def library_block(table: np.ndarray) -> float:
    """Seconds for the library fed every row in one call (how the in-process engines feed it)."""
    up = OnlineDriftUpdater(ForgettingRLS(COEF, prior_covariance(), 0.0, RLSSettings(0.8)), 0.7)
    t0 = time.perf_counter()
    up.step(table[:, 7], table[:, 8], table[:, 0:2], table[:, 2:5], table[:, 6], table[:, 5])
    return time.perf_counter() - t0


def fmu(path: Path, table: np.ndarray) -> float:
    """Seconds for the FMU's steps (set the row, doStep, get the outputs), initialisation excluded."""
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    with tempfile.TemporaryDirectory() as tmp:
        slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(path), tmp),
                          modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bench")
        slave.instantiate()
        slave.setReal([vr["a0"], vr["b0"], vr["c0"]], list(COEF))
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        ins, outs = [vr[n] for n in ROW_INPUTS], [vr[n] for n in OUTPUTS]
        t0 = time.perf_counter()
        for k, r in enumerate(table):
            slave.setReal(ins, list(r))
            slave.doStep(float(k), 1.0)
            slave.getReal(outs)
        elapsed = time.perf_counter() - t0
        slave.terminate()
        slave.freeInstance()
    return elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=3000)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--fmu-dir", type=Path, default=None, help="folder with DriftModelUpdater.fmu (default: "
                        "build one from this tree into a temporary folder)")
    parser.add_argument("--other", type=Path, default=None, help="another DriftModelUpdater.fmu to time beside it")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        if args.fmu_dir is None:
            from fmus.native_fmu import build_native_fmu

            path = build_native_fmu("DriftModelUpdater", "drift_model_updater_slave.py", Path(tmp), win64=False)
        else:
            path = args.fmu_dir / "DriftModelUpdater.fmu"
        runners = {"library, one row per call (yardstick)": library, "library, all rows in one call": library_block,
                   "native FMU (FMPy)": lambda t: fmu(path, t)}
        if args.other is not None:
            runners[f"other FMU {args.other.name} (FMPy)"] = lambda t: fmu(args.other, t)
        for case, parked in (("parked (filter every step)", True), ("drive with 200 s stops", False)):
            table = rows(args.steps, parked)
            best = {name: min(run(table) for _ in range(args.rounds)) for name, run in runners.items()}
            base = best["library, one row per call (yardstick)"]
            print(f"{case}, {args.steps} steps:")
            for name, seconds in best.items():
                print(f"  {name:45s} {1e6 * seconds / args.steps:9.2f} us/step  x{seconds / base:6.2f}")


if __name__ == "__main__":
    main()
