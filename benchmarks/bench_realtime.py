"""Real-time profile of the native chain (issue 19 item 3, issue 18 item 7).

The C master ``tests/native_host/system.c`` steps Turntable -> IMUThermal ->
StrapdownINS (Gauss-Seidel, ``sarins.systems.standard_static``) at a 5 ms and
a 1 ms communication step, the IMU's internal rate equal to the
communication rate (one minor-loop interval per step), with no Python in the
host process (the FMUs find theirs).  After initialisation and a warm-up that
covers the INS alignment (coarse 2 s, fine to 5 s: the slave checks its
parameters at initialisation with a 1 s step, so the coarse alignment must
span 2 s and the whole 2 s more; the turntable starts rotating at 5 s), every chain step is timed with ``CLOCK_MONOTONIC`` and the
heap calls are counted by ``tests/native_host/alloc_counter.c`` (LD_PRELOAD)
between the end of the warm-up and ``fmi2Terminate``.

usage: python benchmarks/bench_realtime.py [--steps N] [--rates 200,1000] [--paced-seconds S]
                                          [--show-alloc-steps K]

By default the steps follow each other at once (the compute latency per step);
``--paced-seconds S`` adds a run per rate in which each step starts at its
deadline (clock_nanosleep, one communication step apart) for S seconds, which
also reports how late the steps woke up and how many overran their period.

Prints one row per rate: steps, p50 / p99 / p99.9 / max step latency (us),
jitter p99.9/p50, heap allocations after the warm-up (and the steps that
made them), the slowest step without and with heap calls, and the load
average before and after.
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import fmu_runs  # benchmarks/ is on sys.path (run as a script, or as the tests put it there)

ROOT = Path(__file__).resolve().parents[1]
HOST_DIR = ROOT / "tests" / "native_host"
COARSE_S, ALIGN_S = 2.0, 5.0  # INS coarse / whole alignment, s; the turntable rotates from ALIGN_S
EXTRA_WARMUP = 200  # steps after the alignment before timing starts
CHAIN = ("Turntable", "IMUThermal", "StrapdownINS")


@dataclass(frozen=True)
class AllocStep:
    """Heap and mmap calls made during one timed step (step counted from 0 after the warm-up)."""

    step: int
    allocs: int
    frees: int
    mmaps: int
    munmaps: int


@dataclass(frozen=True)
class Profile:
    """One run of the C master's latency mode.  Latencies in ns; counts -1 without the counter."""

    steps: int
    warmup: int
    step_s: float
    p50_ns: int
    p99_ns: int
    p999_ns: int
    max_ns: int
    jitter: float
    counter: bool
    allocs: int
    frees: int
    mmaps: int
    munmaps: int
    alloc_steps: int
    max_quiet_ns: int
    max_alloc_ns: int
    paced: bool
    wake_p50_ns: int
    wake_p99_ns: int
    wake_max_ns: int
    overruns: int
    alloc_step_list: tuple


def compiler() -> str | None:
    """The system C compiler, or None."""
    return shutil.which("gcc") or shutil.which("cc")


def build_tools(out: Path) -> tuple[Path, Path]:
    """Compile the C master and the allocation counter into ``out``; (master, counter .so)."""
    import fmpy

    cc = compiler()
    if cc is None:
        raise RuntimeError("no C compiler (gcc or cc) on PATH")
    flags = ["-std=c11", "-O2", "-Wall", "-Wextra", "-Werror"]
    exe, counter = out / "system", out / "alloc_counter.so"
    subprocess.run([cc, *flags, "-o", str(exe), str(HOST_DIR / "system.c"),
                    f"-I{Path(fmpy.__file__).parent / 'c-code'}", "-ldl"], check=True)
    subprocess.run([cc, *flags, "-shared", "-fPIC", "-o", str(counter), str(HOST_DIR / "alloc_counter.c"), "-ldl"],
                   check=True)
    return exe, counter


def warmup_steps(step: float) -> int:
    """Untimed steps: the INS alignment and the turntable's start, plus EXTRA_WARMUP."""
    return int(math.ceil(ALIGN_S / step)) + EXTRA_WARMUP


def write_plan(fmu_dir: Path, work: Path, step: float, steps: int, paced: bool = False) -> Path:
    """The C master's plan: the standard static chain at ``step`` s, IMU internal rate 1/step, latency mode
    (paced: one step per ``step`` of wall time)."""
    from sarins.systems import standard_static

    system = standard_static(fmu_dir, turntable=dict(align_time=ALIGN_S),
                             imu=dict(internal_rate=1.0 / step),
                             ins=dict(coarse_time=COARSE_S, align_time=ALIGN_S))
    body, _, _ = fmu_runs.system_plan_lines(system, work)
    lines = [f"steps {steps} {step!r}", f"latency {warmup_steps(step)}"] + (["paced"] if paced else []) + body
    plan = work / f"plan_{step!r}{'_paced' if paced else ''}.txt"
    plan.write_text("\n".join(lines) + "\n")
    return plan


def parse(stdout: str) -> Profile:
    """The LATENCY line and the ALLOC_STEP lines of the C master's output."""
    lines = [line for line in stdout.splitlines() if line.startswith("LATENCY ")]
    if len(lines) != 1:
        raise ValueError(f"expected one LATENCY line in the master's output, got {len(lines)}:\n{stdout[-2000:]}")
    fields = dict(item.split("=", 1) for item in lines[0].split()[1:])
    alloc_steps = tuple(AllocStep(*map(int, line.split()[1:])) for line in stdout.splitlines()
                        if line.startswith("ALLOC_STEP "))
    ints = ("steps", "warmup", "p50_ns", "p99_ns", "p999_ns", "max_ns", "allocs", "frees", "mmaps", "munmaps",
            "alloc_steps", "max_quiet_ns", "max_alloc_ns", "wake_p50_ns", "wake_p99_ns", "wake_max_ns", "overruns")
    return Profile(**{k: int(fields[k]) for k in ints}, step_s=float(fields["step_s"]),
                   jitter=float(fields["jitter"]), counter=fields["counter"] == "1", paced=fields["paced"] == "1",
                   alloc_step_list=alloc_steps)


def run(exe: Path, plan: Path, counter: Path | None, timeout: float | None = None) -> Profile:
    """Run the C master on ``plan`` (with the counter preloaded unless None); its Profile."""
    env = {k: v for k, v in os.environ.items() if k not in fmu_runs.HOST_ENV_DROP}
    if counter is not None:
        env["LD_PRELOAD"] = str(counter)
    r = subprocess.run([str(exe), str(plan)], capture_output=True, text=True, env=env, timeout=timeout)
    if r.returncode != 0:
        raise RuntimeError(f"C master exited {r.returncode}:\n{r.stdout[-2000:]}\n{r.stderr[-2000:]}")
    return parse(r.stdout)


def load() -> str:
    """The 1/5/15-min load averages."""
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def print_table(rows) -> None:
    """The latency table, one row per (rate, Profile, load before, load after)."""
    paced = any(p.paced for _, p, _, _ in rows)
    print("| rate | steps | p50 | p99 | p99.9 | max | jitter p99.9/p50 | allocations after warm-up "
          "(allocs / frees / mmaps / munmaps; steps that made them) | slowest step without / with them "
          + ("| wake-up lateness p50 / p99 / max | overruns " if paced else "") + "| load before -> after |")
    print("|---" * (12 if paced else 10) + "|")
    for rate, p, before, after in rows:
        us = [f"{x / 1000:.1f} us" for x in (p.p50_ns, p.p99_ns, p.p999_ns, p.max_ns)]
        split = " / ".join("-" if x < 0 else f"{x / 1000:.1f} us" for x in (p.max_quiet_ns, p.max_alloc_ns))
        wake = (f"{' / '.join(f'{x / 1000:.1f} us' for x in (p.wake_p50_ns, p.wake_p99_ns, p.wake_max_ns))} | "
                f"{p.overruns} | ") if paced else ""
        print(f"| {rate:g} Hz ({p.step_s * 1000:g} ms) | {p.steps} | {' | '.join(us)} | {p.jitter:.2f} | "
              f"{p.allocs} / {p.frees} / {p.mmaps} / {p.munmaps}; {p.alloc_steps} steps | {split} | {wake}"
              f"{before} -> {after} |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=1_000_000, help="timed steps per rate (default 10^6)")
    ap.add_argument("--rates", default="200,1000", help="communication rates, Hz (default 200,1000)")
    ap.add_argument("--paced-seconds", type=float, default=0.0,
                    help="also run each rate paced (one step per period) for this many seconds (default: not)")
    ap.add_argument("--show-alloc-steps", type=int, default=5, help="allocating steps listed per rate")
    args = ap.parse_args(argv)
    if args.steps < 1:
        ap.error("--steps must be >= 1")
    if not (args.paced_seconds >= 0.0 and math.isfinite(args.paced_seconds)):
        ap.error("--paced-seconds must be >= 0")
    try:
        rates = [float(r) for r in args.rates.split(",")]
    except ValueError:
        ap.error(f"--rates: not a list of numbers: {args.rates!r}")
    if not all(r > 0.0 and math.isfinite(r) for r in rates):
        ap.error("--rates: every rate must be positive")
    from fmus.build import build_fmus

    runs = [(rate, False, args.steps) for rate in rates]
    if args.paced_seconds > 0.0:
        runs += [(rate, True, max(1, round(args.paced_seconds * rate))) for rate in rates]
    with tempfile.TemporaryDirectory(prefix="bench_rt_") as tmp:
        tmp = Path(tmp)
        build_fmus(tmp / "fmus", names=CHAIN)
        exe, counter = build_tools(tmp)
        rows = {False: [], True: []}
        for rate, paced, steps in runs:
            work = tmp / f"run_{rate:g}_{int(paced)}"
            work.mkdir()
            plan = write_plan(tmp / "fmus", work, 1.0 / rate, steps, paced=paced)
            before = load()
            prof = run(exe, plan, counter)
            rows[paced].append((rate, prof, before, load()))
            print(f"{rate:g} Hz{' paced' if paced else ''} done (load {before} -> {load()})", file=sys.stderr)
    print("As fast as possible (each step starts when the previous one ends):")
    print_table(rows[False])
    if rows[True]:
        print("\nPaced (each step starts at its deadline, one communication step apart):")
        print_table(rows[True])
    for rate, p, _, _ in rows[False] + rows[True]:
        listed = ", ".join(f"{a.step} ({a.allocs}/{a.frees}/{a.mmaps}/{a.munmaps})"
                           for a in p.alloc_step_list[:args.show_alloc_steps])
        print(f"{rate:g} Hz{' paced' if p.paced else ''}: warm-up {p.warmup} steps; first allocating steps "
              f"(allocs/frees/mmaps/munmaps): {listed or 'none'}")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    sys.exit(main())
