"""Benchmark of the C core's IMU minor loop against a plain scalar C loop (the yardstick).

Cost in ns per 200 Hz sample of ``sarins_imu_increments`` through its
binding (:func:`sarins_fmu.core.imu.increments`: one gimbal about z, mems-like
error terms, low-rate nonlinearity on) beside the same arithmetic written as
one flat scalar C loop (one gimbal, no function-pointer or array-shape
generality), compiled here at run time with the core's flags and timed in C.
The core is timed one interval at a time (its scalar path, the reference of
the lanes and the FMU step's loop; also without the low-rate and quadratic
terms, as nav-rlg, and with the gimbal still at pi, an alignment dwell), in
SIMD lanes on one thread, and in lanes on all threads.  Then
the whole ``IMU.step`` of the ``mems`` and ``nav-rlg`` presets on the same
motion (thermal model, every error term, all their random numbers drawn in
the C core), and a whole in-process static run (``run_static``: turntable,
IMU, INS; the path of ``sarins navigate``), each on one thread and on all.

The machine may be loaded: every figure is measured in each of ``--rounds``
rounds (the yardstick too, in each round), the best of each counts, and
each is printed as its ratio to the yardstick.

    python benchmarks/bench_core_kernel.py [--intervals 4000] [--repeat 3] [--rounds 3]
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from sarins_fmu import imu as imu_mod
from sarins_fmu.core import imu as core_imu
from sarins_fmu.experiments import run_static

FLAGS = ["-std=c11", "-O2", "-Wall", "-Wextra", "-Wpedantic", "-Werror", "-fno-fast-math", "-ffp-contract=off"]  # as setup.py
N_SUB = 200  # minor steps per 1 s interval
RATE = math.radians(6.0)  # rad/s, table rate
W_T = (1.2e-5, 6.4e-5, 3.4e-5)  # rad/s, Earth rate in the base frame
F_T = (0.0, 0.0, 9.79)  # m/s^2
G_SF, G_BIAS, A_SF, A_BIAS = 5e-4, 5e-5, 1e-3, 2e-2
QUAD_G, QUAD_A, LOWRATE, WIDTH, G_SENS, MIS = 1.5e-4, 1e-4, 0.02, math.radians(2.0), 1.7e-5, 1.5e-3

YARDSTICK = r"""
/* The minor loop of one gimbal about z as one flat scalar loop: the yardstick.  The parameters are
 * read through volatile objects, so the compiler cannot fold them into constants (the core reads
 * them from arrays). */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static volatile double par[17] = {W_T0, W_T1, W_T2, F_T0, F_T1, F_T2, RATE, G_SF, G_BIAS, A_SF, A_BIAS, QUAD_G,
                                  QUAD_A, LOWRATE, WIDTH, G_SENS, MIS};

int main(int argc, char **argv) {
    if (argc != 4) return 2;
    long n_int = atol(argv[1]), n_sub = atol(argv[2]), repeat = atol(argv[3]);
    const double wt[3] = {par[0], par[1], par[2]}, ft[3] = {par[3], par[4], par[5]};
    const double rate0 = par[6], g_sf = par[7], g_bias = par[8], a_sf = par[9], a_bias = par[10];
    const double quad_g = par[11], quad_a = par[12], lowrate = par[13], width = par[14], g_sens = par[15];
    const double mis = par[16];
    double h = 1.0, dt = h / (double)n_sub, best = 1e300, check = 0.0;
    for (long r = 0; r < repeat; r++) {
        double t_start = now();
        for (long k = 0; k < n_int; k++) {
            double a0 = 0.001 * (double)k, rate = rate0, acc = 0.0;
            double q0 = 1, q1 = 0, q2 = 0, q3 = 0, v0 = 0, v1 = 0, v2 = 0;
            double pa0 = 0, pa1 = 0, pa2 = 0, pv0 = 0, pv1 = 0, pv2 = 0;
            double w0[6], w1[6];
            for (long i = 0; i <= n_sub; i++) {
                double tau = (double)i * dt;
                double th = a0 + (rate + 0.5 * acc * tau) * tau, thd = rate + acc * tau;
                double c = cos(th), s = sin(th);
                /* R_z(th)^T on w, f; the gimbal rate along z */
                double *out = i == 0 ? w0 : w1;
                out[0] = c * wt[0] + s * wt[1];
                out[1] = -s * wt[0] + c * wt[1];
                out[2] = wt[2] + thd;
                out[3] = c * ft[0] + s * ft[1];
                out[4] = -s * ft[0] + c * ft[1];
                out[5] = ft[2];
                if (i == 0) continue;
                double e[3], u[3], da[3], dv[3];
                for (int a = 0; a < 3; a++) {
                    e[a] = 0.5 * (w0[a] + w1[a]) * dt;
                    u[a] = 0.5 * (w0[3 + a] + w1[3 + a]) * dt;
                }
                for (int a = 0; a < 3; a++) {
                    double x = e[a] / (dt * width);
                    double g = g_sens * (u[0] + u[1] + u[2]) + lowrate * e[a] * exp(-(x * x));
                    da[a] = e[a] * (1.0 + g_sf) + mis * (e[(a + 1) % 3] - e[(a + 2) % 3]) + g_bias * dt
                            + quad_g * e[a] * fabs(e[a]) / dt + g;
                    dv[a] = u[a] * (1.0 + a_sf) + mis * (u[(a + 1) % 3] - u[(a + 2) % 3]) + a_bias * dt
                            + quad_a * u[a] * fabs(u[a]) / dt;
                }
                double s0 = dv[0] + 0.5 * (da[1] * dv[2] - da[2] * dv[1])
                            + ((pa1 * dv[2] - pa2 * dv[1]) + (pv1 * da[2] - pv2 * da[1])) / 12.0;
                double s1 = dv[1] + 0.5 * (da[2] * dv[0] - da[0] * dv[2])
                            + ((pa2 * dv[0] - pa0 * dv[2]) + (pv2 * da[0] - pv0 * da[2])) / 12.0;
                double s2 = dv[2] + 0.5 * (da[0] * dv[1] - da[1] * dv[0])
                            + ((pa0 * dv[1] - pa1 * dv[0]) + (pv0 * da[1] - pv1 * da[0])) / 12.0;
                double cx = q2 * s2 - q3 * s1, cy = q3 * s0 - q1 * s2, cz = q1 * s1 - q2 * s0;
                v0 += s0 + 2.0 * (q0 * cx + q2 * cz - q3 * cy);
                v1 += s1 + 2.0 * (q0 * cy + q3 * cx - q1 * cz);
                v2 += s2 + 2.0 * (q0 * cz + q1 * cy - q2 * cx);
                double p0 = da[0] + (pa1 * da[2] - pa2 * da[1]) / 12.0;
                double p1 = da[1] + (pa2 * da[0] - pa0 * da[2]) / 12.0;
                double p2 = da[2] + (pa0 * da[1] - pa1 * da[0]) / 12.0;
                double t2 = p0 * p0 + p1 * p1 + p2 * p2;
                double qc = 1.0 - t2 / 8.0 + t2 * t2 / 384.0, qs = 0.5 - t2 / 48.0 + t2 * t2 / 3840.0;
                double n0 = q0 * qc - qs * (q1 * p0 + q2 * p1 + q3 * p2);
                double n1 = q0 * qs * p0 + q1 * qc + qs * (q2 * p2 - q3 * p1);
                double n2 = q0 * qs * p1 + q2 * qc + qs * (q3 * p0 - q1 * p2);
                double n3 = q0 * qs * p2 + q3 * qc + qs * (q1 * p1 - q2 * p0);
                q0 = n0; q1 = n1; q2 = n2; q3 = n3;
                pa0 = da[0]; pa1 = da[1]; pa2 = da[2]; pv0 = dv[0]; pv1 = dv[1]; pv2 = dv[2];
                for (int a = 0; a < 6; a++) w0[a] = w1[a];
            }
            double vn = sqrt(q1 * q1 + q2 * q2 + q3 * q3);
            double scale = vn > 1e-300 ? 2.0 * atan2(vn, q0) / vn : 2.0;
            check += q3 * scale + v0 + v1 + v2;
        }
        double elapsed = now() - t_start;
        if (elapsed < best) best = elapsed;
    }
    printf("%.6f %.17g\n", best * 1e9 / (double)(n_int * n_sub), check);
    return 0;
}
"""


def yardstick_ns(n_int: int, repeat: int) -> float:
    """ns per sample of the flat scalar C loop, compiled with the core's flags (best of ``repeat``)."""
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        raise SystemExit("bench_core_kernel: the yardstick needs a C compiler (cc or gcc) on PATH")
    defines = {"W_T0": W_T[0], "W_T1": W_T[1], "W_T2": W_T[2], "F_T0": F_T[0], "F_T1": F_T[1], "F_T2": F_T[2],
               "RATE": RATE, "G_SF": G_SF, "G_BIAS": G_BIAS, "A_SF": A_SF, "A_BIAS": A_BIAS, "QUAD_G": QUAD_G,
               "QUAD_A": QUAD_A, "LOWRATE": LOWRATE, "WIDTH": WIDTH, "G_SENS": G_SENS, "MIS": MIS}
    with tempfile.TemporaryDirectory(prefix="sarins_yardstick_") as tmp:
        src, exe = Path(tmp) / "yardstick.c", Path(tmp) / "yardstick"
        src.write_text(YARDSTICK)
        subprocess.run([cc, *FLAGS, *(f"-D{k}={v!r}" for k, v in defines.items()), str(src), "-o", str(exe), "-lm"],
                       check=True)
        out = subprocess.run([str(exe), str(n_int), str(N_SUB), str(repeat)], check=True, capture_output=True,
                             text=True).stdout.split()
    return float(out[0])


def core_args(n_int: int, case: str = "mems"):
    """The arguments of core_imu.increments for the yardstick's workload (``case`` "mems"); "nav-rlg": the
    same without the low-rate and quadratic terms (as the nav-rlg preset); "still": that, the gimbal held at
    pi (rate and acceleration zero: an alignment dwell)."""
    k = np.arange(n_int)
    angle0 = np.full((n_int, 1), math.pi) if case == "still" else (0.001 * k)[:, None]
    rate = 0.0 if case == "still" else RATE
    lowrate, quad_g, quad_a = (LOWRATE, QUAD_G, QUAD_A) if case == "mems" else (0.0, 0.0, 0.0)
    mis = MIS * np.array([[0.0, 1.0, -1.0], [-1.0, 0.0, 1.0], [1.0, -1.0, 0.0]])
    return ([[0.0, 0.0, 1.0]], angle0, np.full((n_int, 1), rate), np.zeros((n_int, 1)), np.tile(W_T, (n_int, 1)),
            np.tile(F_T, (n_int, 1)), 1.0, N_SUB, np.full((n_int, 3), G_SF), mis, np.full((n_int, 3), G_BIAS),
            np.full(3, quad_g), np.full(3, lowrate), np.full(3, WIDTH), np.full((3, 3), G_SENS),
            np.full((n_int, 3), A_SF), mis, np.full((n_int, 3), A_BIAS), np.full(3, quad_a))


def core_ns(n_int: int, repeat: int, threads: int, lanes: bool = True, case: str = "mems") -> float:
    """ns per sample of the core's minor loop through its binding (best of ``repeat``); ``lanes=False``: the
    scalar path, one interval at a time (the FMU step's); ``case`` as :func:`core_args`."""
    args = core_args(n_int, case)
    core_imu.increments(*core_args(64), threads=threads)  # thread pool start-up outside the timing
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        core_imu.increments(*args, threads=threads, lanes=lanes)
        best = min(best, time.perf_counter() - t0)
    return best * 1e9 / (n_int * N_SUB)


class _Threads:
    """SARINS_THREADS set to ``threads`` inside the block."""

    def __init__(self, threads: int):
        self.threads, self.saved = threads, None

    def __enter__(self):
        self.saved = os.environ.get("SARINS_THREADS")
        os.environ["SARINS_THREADS"] = str(self.threads)

    def __exit__(self, *exc):
        if self.saved is None:
            del os.environ["SARINS_THREADS"]
        else:
            os.environ["SARINS_THREADS"] = self.saved


def imu_step_ns(n_int: int, repeat: int, threads: int, preset: str = "mems") -> float:
    """ns per sample of the whole ``IMU.step`` of ``preset`` (one gimbal turning at RATE, static base),
    a new IMU per timed call (best of ``repeat``); ``threads`` through SARINS_THREADS."""
    k = np.arange(n_int)
    angle0, rate0, accel = (RATE * k)[:, None], np.full((n_int, 1), RATE), np.zeros((n_int, 1))
    best = math.inf
    with _Threads(threads):
        for _ in range(repeat):
            sensor = imu_mod.IMU(imu_mod.preset(preset), imu_mod.StaticBase(0.6), [[0.0, 0.0, 1.0]],
                                 internal_rate=N_SUB, seed=1)
            t0 = time.perf_counter()
            sensor.step(angle0, rate0, accel)
            best = min(best, time.perf_counter() - t0)
    return best * 1e9 / (n_int * N_SUB)


def static_run_ns(n_int: int, repeat: int, threads: int) -> float:
    """ns per sample of a whole in-process static run (``run_static``, nav-rlg, continuous rotation, a quarter
    of it aligning): turntable, IMU and INS, as ``sarins navigate`` runs them (best of ``repeat``)."""
    hours = n_int / 3600.0
    best = math.inf
    with _Threads(threads):
        for _ in range(repeat):
            t0 = time.perf_counter()
            run_static(align_hours=0.25 * hours, nav_hours=0.75 * hours, rotation="continuous", imu="nav-rlg",
                       seed=1)
            best = min(best, time.perf_counter() - t0)
    return best * 1e9 / (n_int * N_SUB)


def measure(n_int: int, repeat: int, rounds: int) -> tuple[float, dict]:
    """Best yardstick (ns/sample) and best of each figure over ``rounds`` rounds, every round measuring all
    of them in turn (so that a change of the machine's load hits them alike)."""
    threads = core_imu.thread_count()
    figures = {
        "core minor loop, scalar, 1 thread": lambda: core_ns(n_int, repeat, 1, lanes=False),
        "  the same, nav-rlg terms": lambda: core_ns(n_int, repeat, 1, lanes=False, case="nav-rlg"),
        "  the same, gimbal still at pi": lambda: core_ns(n_int, repeat, 1, lanes=False, case="still"),
        "core minor loop, SIMD, 1 thread": lambda: core_ns(n_int, repeat, 1),
        f"core minor loop, SIMD, {threads} threads": lambda: core_ns(n_int, repeat, threads),
        "IMU.step mems, 1 thread": lambda: imu_step_ns(n_int, repeat, 1),
        f"IMU.step mems, {threads} threads": lambda: imu_step_ns(n_int, repeat, threads),
        "IMU.step nav-rlg, 1 thread": lambda: imu_step_ns(n_int, repeat, 1, "nav-rlg"),
        f"IMU.step nav-rlg, {threads} threads": lambda: imu_step_ns(n_int, repeat, threads, "nav-rlg"),
        "static run nav-rlg, 1 thread": lambda: static_run_ns(n_int, 1, 1),
        f"static run nav-rlg, {threads} threads": lambda: static_run_ns(n_int, 1, threads),
    }
    yard, best = math.inf, dict.fromkeys(figures, math.inf)
    for _ in range(rounds):
        yard = min(yard, yardstick_ns(n_int, repeat))
        for label, run in figures.items():
            best[label] = min(best[label], run())
    return yard, best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--intervals", type=int, default=4000, help="1 s intervals per timed call")
    parser.add_argument("--repeat", type=int, default=3, help="timed calls per round (the best counts)")
    parser.add_argument("--rounds", type=int, default=3, help="rounds, each timing every figure and the yardstick")
    args = parser.parse_args()
    if args.intervals < 64 or args.repeat < 1 or args.rounds < 1:
        parser.error("--intervals must be >= 64, --repeat and --rounds >= 1")
    yard, best = measure(args.intervals, args.repeat, args.rounds)
    print(f"{args.intervals} intervals x {N_SUB} minor steps, best of {args.repeat} x {args.rounds} rounds; "
          f"cpu_count {os.cpu_count()}")
    print(f"  {'yardstick (flat scalar C loop)':<38} {yard:8.1f} ns/sample")
    for label, value in best.items():
        print(f"  {label:<38} {value:8.1f} ns/sample   ratio {value / yard:5.2f}")


if __name__ == "__main__":
    main()
