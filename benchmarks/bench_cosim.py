"""One 88 h run through the three FMUs under the master vs the same run in process.

Reports, in one process:

* wall time of the co-simulation (Turntable -> IMUThermal -> StrapdownINS,
  Gauss-Seidel, 1 s step, nav-rlg, recording three outputs) and of the
  identical in-process run (``run_static``), and their ratio;
* where a co-simulation step goes: the slaves' own Python work per step
  (their ``do_step`` called directly, no FMI), the FMI layer (FMPy + native layer), and
  the master's own overhead (master minus a bare FMPy loop that does the same
  get/set/doStep calls).

Usage: ``python benchmarks/bench_cosim.py [--hours 88]``
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

import numpy as np  # noqa: E402

from fmu_driver import run_chain  # noqa: E402
from fmus.build import build_fmus  # noqa: E402
from sarins.systems import standard_static  # noqa: E402
from orchestration import simulate_system  # noqa: E402
from sarins_fmu.experiments import run_static  # noqa: E402


def slave_work_per_step(n: int = 3000) -> dict:
    """Microseconds per step of each slave's do_step called directly (no FMI)."""
    from fmus.imu_thermal_slave import IMUThermal
    from fmus.strapdown_ins_slave import StrapdownINS
    from fmus.turntable_slave import Turntable

    tt, imu, ins = Turntable(instance_name="t"), IMUThermal(instance_name="i"), StrapdownINS(instance_name="n")
    tt.enter_initialization_mode()
    tt.exit_initialization_mode()
    imu.exit_initialization_mode()
    ins.exit_initialization_mode()
    cost = {"Turntable": 0.0, "IMUThermal": 0.0, "StrapdownINS": 0.0}
    for k in range(n + 400):
        t = float(k)
        c0 = time.perf_counter()
        tt.do_step(t, 1.0)
        c1 = time.perf_counter()
        imu.angle_1, imu.rate_1, imu.ambient_temp = tt.angle_1, tt.rate_1, tt.ambient_temp
        imu.do_step(t, 1.0)
        c2 = time.perf_counter()
        for a in "xyz":
            setattr(ins, f"dtheta_{a}", getattr(imu, f"dtheta_{a}"))
            setattr(ins, f"dv_{a}", getattr(imu, f"dv_{a}"))
        ins.do_step(t, 1.0)
        c3 = time.perf_counter()
        if k >= 400:  # after the coarse alignment
            cost["Turntable"] += c1 - c0
            cost["IMUThermal"] += c2 - c1
            cost["StrapdownINS"] += c3 - c2
    return {k: v / n * 1e6 for k, v in cost.items()}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", type=float, default=88.0)
    args = parser.parse_args()
    hours = args.hours
    steps = int(hours * 3600)
    align = min(4.0, hours / 4)
    with tempfile.TemporaryDirectory() as tmp:
        fmu_dir = Path(tmp)
        build_fmus(fmu_dir)
        system = standard_static(fmu_dir, hours=hours, turntable=dict(align_time=align * 3600),
                                 ins=dict(align_time=align * 3600))
        run_static(align_hours=align, nav_hours=0.1)  # compile / load caches first
        t0 = time.perf_counter()
        ref = run_static(align_hours=align, nav_hours=hours - align, seed=0)
        t_inproc = time.perf_counter() - t0
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            t0 = time.perf_counter()
            res = simulate_system(system, hours * 3600.0, 1.0, progress=False,
                                  record=["ins.lat_error", "ins.lon_error", "ins.position_error"])
            t_cosim = time.perf_counter() - t0
        lat = res["ins.lat_error"][1:][int(align * 3600):]
        diff = np.max(np.abs(lat - ref.lat_error)) / np.max(np.abs(ref.lat_error))
        n_raw = min(steps, 20000)
        t0 = time.perf_counter()
        run_chain(fmu_dir, n_raw, tt_params=dict(align_time=align * 3600), ins_params=dict(align_time=align * 3600))
        t_raw = (time.perf_counter() - t0) / n_raw
    work = slave_work_per_step()
    per_step = t_cosim / steps * 1e6
    print(f"{hours:g} h, {steps} steps of 1 s")
    print(f"in process     : {t_inproc:7.2f} s  ({hours * 3600 / t_inproc:,.0f}x real time)")
    print(f"co-simulation  : {t_cosim:7.2f} s  ({hours * 3600 / t_cosim:,.0f}x real time), "
          f"{t_cosim / t_inproc:.1f}x the in-process run; max relative difference {diff:.1e}")
    print(f"per step       : master {per_step:.0f} us; bare FMPy loop doing the same calls "
          f"{t_raw * 1e6:.0f} us -> master's own overhead {per_step - t_raw * 1e6:.0f} us")
    print("slave work (do_step in Python, no FMI), us/step: "
          + ", ".join(f"{k} {v:.0f}" for k, v in work.items())
          + f"; sum {sum(work.values()):.0f} us -> FMI layer (FMPy + native layer) ~{t_raw * 1e6 - sum(work.values()):.0f} us")


if __name__ == "__main__":
    main()
