"""One 88 h run through the three FMUs under the master vs the same run in process.

Reports, in one process, same seed:

* wall time of the identical in-process run (``run_static`` as the library
  runs it by default, the core's batch threads in use; the single-thread figure
  beside it for context: one FMU step is one interval and runs serially);
* wall time of the co-simulation (Turntable -> IMUThermal -> StrapdownINS,
  Gauss-Seidel, 1 s step, nav-rlg, recording three outputs) as
  ``N.Nx the in-process run``; the results must be bit-identical (asserted);
* where a co-simulation step goes: the FMU calls (a bare loop doing the master's
  get/set/doStep/record calls through the same ctypes pointers; the three FMUs
  are native) and the master's own work (master minus the bare loop).

Usage: ``python benchmarks/bench_cosim.py [--hours 88]``
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
import warnings
from ctypes import c_double
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

import numpy as np  # noqa: E402

from fmu_driver import IMU_TO_INS, TT_TO_IMU, Slave  # noqa: E402
from fmus.build import build_fmus  # noqa: E402
from orchestration import rawcalls, simulate_system  # noqa: E402
from sarins.systems import standard_static  # noqa: E402
from sarins_fmu.experiments import run_static  # noqa: E402

RECORD = ["ins.lat_error", "ins.lon_error", "ins.position_error"]


def in_process(hours: float, align: float, threads: int | None = None):
    """(result, seconds) of run_static; ``threads`` limits the C core's batch threads for the run."""
    before = os.environ.get("SARINS_THREADS")
    if threads is not None:
        os.environ["SARINS_THREADS"] = str(threads)
    try:
        t0 = time.perf_counter()
        ref = run_static(align_hours=align, nav_hours=hours - align, seed=0)
        return ref, time.perf_counter() - t0
    finally:
        if before is None:
            os.environ.pop("SARINS_THREADS", None)
        else:
            os.environ["SARINS_THREADS"] = before


def cosimulate(system, hours: float):
    """(result, seconds) of the master's run."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = time.perf_counter()
        res = simulate_system(system, hours * 3600.0, 1.0, progress=False, record=RECORD)
        return res, time.perf_counter() - t0


def bare_loop(fmu_dir: Path, n: int, align_s: float) -> float:
    """Seconds per step of the master's FMI calls alone (same ctypes pointers, no master)."""
    tt = Slave(fmu_dir / "Turntable.fmu", "turntable")
    imu = Slave(fmu_dir / "IMUThermal.fmu", "imu")
    ins = Slave(fmu_dir / "StrapdownINS.fmu", "ins")
    slaves = (tt, imu, ins)
    try:
        tt.set(align_time=align_s)
        ins.set(align_time=align_s)
        for s in slaves:
            s.fmu.enterInitializationMode()
        links = []
        for src, dst, names in ((tt, imu, TT_TO_IMU), (imu, ins, IMU_TO_INS)):
            buffer = rawcalls.value_buffer("Real", len(names))
            links.append((rawcalls.getter(src.fmu, "Real"), rawcalls.handle(src.fmu),
                          rawcalls.vr_array(src.vr[v] for v in names), rawcalls.count(len(names)), buffer,
                          rawcalls.setter(dst.fmu, "Real"), rawcalls.handle(dst.fmu),
                          rawcalls.vr_array(dst.vr[v] for v in names)))
        for get, sc, svr, m, buf, set_, dc, dvr in links:
            get(sc, svr, m, buf)
            set_(dc, dvr, m, buf)
        for s in slaves:
            s.fmu.exitInitializationMode()
        steps = [(rawcalls.do_step(s.fmu), rawcalls.handle(s.fmu)) for s in slaves]
        names = ["lat_error", "lon_error", "position_error"]
        rec_get = rawcalls.getter(ins.fmu, "Real")
        rec_vr, rec_buf = rawcalls.vr_array(ins.vr[v] for v in names), rawcalls.value_buffer("Real", 3)
        rec_n = rawcalls.count(3)
        (step_tt, c_tt), (step_imu, c_imu), (step_ins, c_ins) = steps
        (g1, s1c, v1, m1, b1, p1, d1c, w1), (g2, s2c, v2, m2, b2, p2, d2c, w2) = links
        one, no_prior = c_double(1.0), rawcalls.NO_SET_PRIOR
        t0 = time.perf_counter()
        for k in range(n):
            t = c_double(k)
            step_tt(c_tt, t, one, no_prior)
            g1(s1c, v1, m1, b1)
            p1(d1c, w1, m1, b1)
            step_imu(c_imu, t, one, no_prior)
            g2(s2c, v2, m2, b2)
            p2(d2c, w2, m2, b2)
            step_ins(c_ins, t, one, no_prior)
            rec_get(c_ins, rec_vr, rec_n, rec_buf)
        return (time.perf_counter() - t0) / n
    finally:
        for s in reversed(slaves):
            s.free()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", type=float, default=88.0)
    args = parser.parse_args()
    hours = args.hours
    steps = int(round(hours * 3600))
    align = min(4.0, hours / 4)
    with tempfile.TemporaryDirectory() as tmp:
        fmu_dir = Path(tmp)
        build_fmus(fmu_dir)
        system = standard_static(fmu_dir, hours=hours, turntable=dict(align_time=align * 3600),
                                 ins=dict(align_time=align * 3600))
        run_static(align_hours=align, nav_hours=0.1)  # compile / load caches first
        cosimulate(system, 0.2)  # the FMUs' caches too
        ref, t_inproc = in_process(hours, align)
        _, t_serial = in_process(hours, align, threads=1)
        res, t_cosim = cosimulate(system, hours)
        n_raw = min(steps, 30000)
        t_raw = bare_loop(fmu_dir, n_raw, align * 3600)
    nav = int(round(align * 3600)) + 1
    for field, series in (("lat_error", ref.lat_error), ("position_error", ref.position_error)):
        got = res[f"ins.{field}"][nav:]
        assert len(got) == len(series) and np.array_equal(got, series), f"co-simulation: ins.{field} differs"
    load = os.getloadavg()
    us = 1e6 / steps
    per_step, raw = t_cosim * us, t_raw * 1e6
    print(f"{hours:g} h, {steps} steps of 1 s (load average {load[0]:.2f}, {load[1]:.2f}, {load[2]:.2f})")
    print(f"in process     : {t_inproc:7.2f} s = {t_inproc * us:5.1f} us/step (run_static, core threads); "
          f"single thread {t_serial:.2f} s = {t_serial * us:.1f} us/step")
    print(f"co-simulation  : {t_cosim:7.2f} s = {per_step:5.1f} us/step, {t_cosim / t_inproc:.1f}x the in-process "
          f"run ({t_cosim / t_serial:.1f}x the single-thread one); results bit-identical")
    print(f"per step       : FMU calls (a bare loop of the master's get/set/doStep/record calls; the three FMUs "
          f"are native) {raw:.1f} us; master's own work {per_step - raw:.1f} us")

if __name__ == "__main__":
    main()
