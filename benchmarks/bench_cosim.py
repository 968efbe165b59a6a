"""One 88 h run through the FMUs under the master vs the same run in process.

Reports, in one process, same seed:

* wall time of the identical in-process run (``run_static`` as the library
  runs it by default, the core's batch threads in use; the single-thread figure
  beside it for context: one FMU step is one interval and runs serially);
* wall time of the co-simulation (Turntable -> IMUThermal -> StrapdownINS,
  Gauss-Seidel, 1 s step, nav-rlg, recording three outputs) through the
  master's compiled loop and through its Python loop, as ``N.Nx the in-process
  run``; the results must be bit-identical (asserted);
* where a co-simulated step goes (the master's profile, ``sarins cosim
  --profile``): each FMU's doStep, gets and sets, recording, the master's own work.

``--system identified`` runs seed 000's whole loop instead (RBFIdentifier
closing the loop on the INS, ``sarins.systems.standard_static_identified``,
identification 12 h into navigation); its in-process twin is ``run_static``
with the identified drift subtracted from the same navigation time, the
identifier's one evaluation costing nothing there.  The two agree to 1e-12 of
the error's scale (not bit for bit: the drift crosses deg/h there, rad/s here).

``--system both`` runs the standard and the identified system one after the other and ends with one
summary line per system (the ratio against the threaded and the single-thread in-process run, and where a
co-simulated step goes: each FMU's doStep, gets and sets; recording and the master's own work).

``--seconds-per-step K`` (K > 1) co-simulates the FMI 3.0 FMUs with K-second communication steps, every
second of a step in arrays (``standard_static(seconds_per_step=K)``: the Turntable's motion of each second
to the IMU, the IMU's increments of each second to the INS), the IMU running the K seconds' minor loops on
``--threads`` threads (default: the machine's cores, as the in-process run); the results must be the 1 s
system's (asserted on the recorded rows, every K-th second).  Per-step figures are per second of simulated
time.

Usage: ``python benchmarks/bench_cosim.py [--hours 88] [--system standard|identified|both]
[--seconds-per-step K] [--threads T]``
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

import numpy as np  # noqa: E402

from fmus import SLAVES  # noqa: E402
from fmus.build import build_fmus  # noqa: E402
from fmus.native_fmu import build_native_fmu  # noqa: E402
from orchestration import Master  # noqa: E402
from sarins.systems import standard_static, standard_static_identified  # noqa: E402
from sarins_fmu.experiments import run_static  # noqa: E402
from sarins_fmu.units import HOUR, RPS_TO_DPH  # noqa: E402

RECORD = ["ins.lat_error", "ins.lon_error", "ins.position_error"]
IDENTIFIED_RECORD = RECORD + ["identifier.axial_drift", "identifier.apply_from"]


def in_process(hours: float, align: float, threads: int | None = None, **correction):
    """(result, seconds) of run_static; ``threads`` limits the C core's batch threads for the run;
    ``correction`` (correction_dph, correction_from_hours) is the identified loop's subtraction."""
    before = os.environ.get("SARINS_THREADS")
    if threads is not None:
        os.environ["SARINS_THREADS"] = str(threads)
    try:
        t0 = time.perf_counter()
        ref = run_static(align_hours=align, nav_hours=hours - align, seed=0, **correction)
        return ref, time.perf_counter() - t0
    finally:
        if before is None:
            os.environ.pop("SARINS_THREADS", None)
        else:
            os.environ["SARINS_THREADS"] = before


def cosimulate(system, hours: float, loop: str = "auto", profile: bool = False):
    """(result, seconds) of the master's run (at the system's step)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        record = IDENTIFIED_RECORD if any(c.name == "identifier" for c in system.components) else RECORD
        with Master(system, record=record, loop=loop) as master:
            t0 = time.perf_counter()
            res = master.simulate(hours * 3600.0, system.step_size, progress=False, profile=profile)
            return res, time.perf_counter() - t0


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", type=float, default=88.0)
    parser.add_argument("--system", choices=("standard", "identified", "both"), default="standard")
    parser.add_argument("--seconds-per-step", type=int, default=1, metavar="K",
                        help="communication step in seconds; K > 1: the FMI 3.0 FMUs with every second in arrays")
    parser.add_argument("--threads", type=int, default=os.cpu_count() or 1,
                        help="the IMU FMU's threads when K > 1 (default: the machine's cores)")
    args = parser.parse_args()
    kinds = ("standard", "identified") if args.system == "both" else (args.system,)
    summary = []
    with tempfile.TemporaryDirectory() as tmp:
        fmu_dir = Path(tmp)
        if args.seconds_per_step > 1:
            for name in ("Turntable", "IMUThermal", "StrapdownINS", "RBFIdentifier"):
                build_native_fmu(name, SLAVES[name], fmu_dir, fmi=3, win64=False, aarch64=False)
        else:
            build_fmus(fmu_dir)
        run_static(align_hours=min(4.0, args.hours / 4), nav_hours=0.1)  # compile / load caches first
        for kind in kinds:
            summary.append(measure(kind, args.hours, fmu_dir, args.seconds_per_step, args.threads))
    load = os.getloadavg()
    print(f"summary (load average {load[0]:.2f}, {load[1]:.2f}, {load[2]:.2f}):")
    for line in summary:
        print("  " + line)


def measure(kind: str, hours: float, fmu_dir: Path, k: int = 1, threads: int = 1) -> str:
    """Run and print one system's comparison (K-second steps when k > 1); returns its summary line."""
    steps = int(round(hours * 3600))
    align = min(4.0, hours / 4)
    make = standard_static_identified if kind == "identified" else standard_static
    system = make(fmu_dir, hours=hours, turntable=dict(align_time=align * 3600), ins=dict(align_time=align * 3600),
                  seconds_per_step=k, threads=threads)
    cosimulate(system, k * max(1, 720 // k) / 3600)  # the FMUs' caches too (a whole number of steps)
    res, t_cosim = cosimulate(system, hours)
    correction = _identified_correction(res) if kind == "identified" else {}
    ref, t_inproc = in_process(hours, align, **correction)
    _, t_serial = in_process(hours, align, threads=1, **correction)
    res_py, t_python = cosimulate(system, hours, loop="python")
    profiled, _ = cosimulate(system, hours, profile=True)
    nav = int(round(align * 3600)) // k + 1  # the first recorded row in navigation
    tol = 1e-12 if correction else 0.0
    for field, series in (("lat_error", ref.lat_error), ("position_error", ref.position_error)):
        got, series = res[f"ins.{field}"][nav:], series[k - 1::k]  # a row every k s
        assert len(got) == len(series), f"co-simulation: ins.{field} has another length"
        assert np.max(np.abs(got - series)) <= tol * np.max(np.abs(series)), f"co-simulation: ins.{field} differs"
    for name in res.dtype.names:
        assert np.array_equal(res[name], res_py[name]) and np.array_equal(res[name], profiled[name]), name
    load = os.getloadavg()
    us = 1e6 / steps
    per_step = t_cosim * us
    if correction:
        print(f"identified system: drift {correction['correction_dph']:.6g} deg/h subtracted from "
              f"{correction['correction_from_hours']:g} h of navigation on; co-simulated = in process to {tol:g}")
    layout = f"{steps // k} steps of {k} s, the IMU on {threads} threads" if k > 1 else f"{steps} steps of 1 s"
    print(f"{kind} system, {hours:g} h, {layout} (load average {load[0]:.2f}, {load[1]:.2f}, {load[2]:.2f}); "
          "figures per second of simulated time")
    print(f"in process     : {t_inproc:7.2f} s = {t_inproc * us:5.1f} us/step (run_static, core threads); "
          f"single thread {t_serial:.2f} s = {t_serial * us:.1f} us/step")
    print(f"co-simulation  : {t_cosim:7.2f} s = {per_step:5.1f} us/step, {t_cosim / t_inproc:.2f}x the in-process "
          f"run ({t_cosim / t_serial:.2f}x the single-thread one), compiled loop; results "
          + ("equal to 1e-12" if correction else "bit-identical"))
    print(f"  Python loop  : {t_python:7.2f} s = {t_python * us:5.1f} us/step, {t_python / t_inproc:.2f}x")
    profile = profiled.meta["profile"]
    print("where a co-simulated step goes (profiled run; the clock readings add about 0.05 us per call):")
    parts_text = []
    for name, parts in profile["components"].items():
        text = ", ".join(f"{part} {seconds * us:.2f}" for part, seconds in parts.items() if seconds > 0)
        print(f"  {name:<10} {text} us")
        parts_text.append(f"{name} {sum(parts.values()) * us:.2f}")
    print(f"  recording {profile['record_s'] * us:.2f} us, conversions {profile['conversions_s'] * us:.2f} us, "
          f"master's own work {profile['master_s'] * us:.2f} us")
    kind = f"{kind} ({k} s steps, {threads} IMU threads)" if k > 1 else kind
    return (f"{kind}: co-simulated {per_step:.1f} us/step = {t_cosim / t_inproc:.2f}x in process "
            f"({t_inproc * us:.1f} us/step, core threads), {t_cosim / t_serial:.2f}x single thread "
            f"({t_serial * us:.1f} us/step); per step (us): {', '.join(parts_text)} (doStep + gets + sets), "
            f"recording {profile['record_s'] * us:.2f}, master {profile['master_s'] * us:.2f}")


def _identified_correction(res) -> dict:
    """run_static's correction arguments for what the co-simulated identifier gave."""
    drift, apply_from = res["identifier.axial_drift"][-1], res["identifier.apply_from"][-1]
    if drift == 0.0:
        raise SystemExit("the identifier did not fire within the run: give more --hours (>= 4 h alignment + 12 h)")
    return dict(correction_dph=float(drift) * RPS_TO_DPH, correction_from_hours=float(apply_from) / HOUR)


if __name__ == "__main__":
    main()
