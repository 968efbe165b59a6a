"""CPU and wall time of each phase of ``sarins campaign mems-calibration`` (default: the quick profile).

Runs the campaign in a subprocess under ``/usr/bin/time -v`` (in a fresh output folder unless ``--out``
names one, so nothing is reused) and prints, from the campaign's ``summary.json``:

* the whole run: wall, CPU (user + system of the campaign and its fitting processes) and peak resident set
  (``/usr/bin/time -v``), and the machine's 1-min load average at the start and the end;
* per phase: wall and CPU seconds (this process and its finished children, ``summary['phases']``) and the
  campaign's up-front estimate (the reference machine's cost model, before the progress display scales it);
* per fitted model: the fitting thread's CPU seconds and the fit's wall time (the recurrent fits run side by
  side in forked processes, one torch thread each);
* per (model, evaluated set): the evaluating thread's CPU seconds (``summary['evaluation_cpu_s']``).

CPU seconds are what a loaded, shared machine still measures fairly; the wall time of a loaded machine is
not the idle machine's.  ``--summary PATH`` prints the tables of an existing ``summary.json`` instead
(with ``--time-log`` the ``/usr/bin/time -v`` output of that run).  ``--json PATH`` also writes the numbers.
``--kernels DIR`` times only the C core's batch evaluation of the models a campaign fitted (``DIR/models``) on
the first ``--rows`` rows of its held-out set (``DIR/datasets``), CPU us per sample, best of three: run it with
``PYTHONPATH`` on two checkouts to compare their kernels on the same models and rows.

Usage: ``PYTHONPATH=. python3 benchmarks/bench_mems_phases.py [--profile quick] [--out DIR]
[--json PATH] [-- extra campaign options]`` (minutes on 2 cores).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TIME_FIELDS = {"User time (seconds)": "user_s", "System time (seconds)": "system_s",
               "Maximum resident set size (kbytes)": "max_rss_kb", "Elapsed (wall clock) time (h:mm:ss or m:ss)": "wall"}


def parse_time_log(text: str) -> dict:
    """{'user_s', 'system_s', 'cpu_s', 'wall_s', 'max_rss_mb'} from ``/usr/bin/time -v`` output."""
    out = {}
    for line in text.splitlines():
        key, _, value = line.strip().partition(": ")
        if key in TIME_FIELDS:
            out[TIME_FIELDS[key]] = value.strip()
    if not out:
        return {}
    wall = 0.0
    for part in out.pop("wall").split(":"):
        wall = 60.0 * wall + float(part)
    user, system = float(out.pop("user_s")), float(out.pop("system_s"))
    return dict(user_s=user, system_s=system, cpu_s=user + system, wall_s=wall,
                max_rss_mb=int(out.pop("max_rss_kb")) / 1024.0)


def tables(summary: dict, whole: dict) -> dict:
    """The numbers the script prints: {'whole', 'load_average', 'phases', 'fits', 'evaluation'}."""
    models = summary.get("models", {})
    fits = {name: dict(cpu_s=info.get("fit_cpu_s"), wall_s=info.get("fit_s")) for name, info in models.items()}
    evaluation = summary.get("evaluation_cpu_s", {})
    return dict(whole=whole, load_average=summary.get("load_average"), fit_load_average=summary.get("fit_load_average"),
                phases={k: dict(wall_s=v["wall_s"], cpu_s=v["cpu_s"], peak_rss_mb=v.get("peak_rss_mb"),
                                estimate_s=v.get("estimate_s"))
                        for k, v in summary.get("phases", {}).items()},
                fits=fits, evaluation=evaluation)


def _num(value, fmt="7.1f") -> str:
    return format(value, fmt) if isinstance(value, (int, float)) else " " * (int(fmt.split(".")[0]) - 1) + "-"


def report(numbers: dict) -> str:
    lines = []
    whole = numbers["whole"]
    if whole:
        lines.append(f"whole run: wall {whole['wall_s']:.1f} s, CPU {whole['cpu_s']:.1f} s (user {whole['user_s']:.1f}, "
                     f"system {whole['system_s']:.1f}), peak RSS {whole['max_rss_mb']:.0f} MB")
    load = numbers.get("load_average")
    if load:
        lines.append(f"1-min load average: {load[0]:.2f} at the start, {load[1]:.2f} at the end "
                     f"(fits: {numbers.get('fit_load_average')})")
    lines.append("")
    lines.append(f"{'phase':12s} {'wall s':>8s} {'CPU s':>8s} {'peak RSS MB':>12s} {'estimate s':>11s}")
    for name, row in numbers["phases"].items():
        lines.append(f"{name:12s} {_num(row['wall_s'], '8.1f')} {_num(row['cpu_s'], '8.1f')} "
                     f"{_num(row['peak_rss_mb'], '12.0f')} {_num(row.get('estimate_s'), '11.1f')}")
    lines.append("")
    lines.append(f"{'fit':16s} {'CPU s':>8s} {'wall s':>8s}")
    for name, row in numbers["fits"].items():
        lines.append(f"{name:16s} {_num(row['cpu_s'], '8.1f')} {_num(row['wall_s'], '8.1f')}")
    evaluation = numbers["evaluation"]
    if evaluation:
        sets = list(next(iter(evaluation.values())))
        lines.append("")
        lines.append(f"{'evaluation CPU s':16s} " + " ".join(f"{s:>10s}" for s in sets) + f" {'total':>8s}")
        totals = dict.fromkeys(sets, 0.0)
        for name, row in evaluation.items():
            for s in sets:
                totals[s] += row[s]
            lines.append(f"{name:16s} " + " ".join(f"{row[s]:10.1f}" for s in sets) + f" {sum(row.values()):8.1f}")
        lines.append(f"{'all models':16s} " + " ".join(f"{totals[s]:10.1f}" for s in sets)
                     + f" {sum(totals.values()):8.1f}")
    return "\n".join(lines)


def kernel_costs(folder: Path, rows: int, repeats: int = 3) -> dict:
    """{model: CPU us per sample} of ``predict_batch`` (one thread) on the first ``rows`` held-out rows."""
    import time

    import numpy as np

    from sarins_fmu.identify import compensators

    X = np.ascontiguousarray(np.load(folder / "datasets" / "held-out.X.npy", mmap_mode="r")[:rows])
    out = {}
    for path in sorted((folder / "models").glob("*.npz")):
        model = compensators.load(path)
        best = float("inf")
        for _ in range(repeats):
            t0 = time.thread_time()
            model.predict_batch(X)
            best = min(best, time.thread_time() - t0)
        out[path.stem] = best / len(X) * 1e6
    return out


def run_campaign(profile: str, out: Path, extra: list) -> dict:
    """Run the campaign under ``/usr/bin/time -v``; returns the parsed time log."""
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    cmd = ["/usr/bin/time", "-v", sys.executable, "-m", "sarins", "campaign", "mems-calibration", "--profile", profile,
           "--out", str(out), "--no-progress", *extra]
    proc = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.stderr.write(proc.stderr[-4000:])
        raise SystemExit(f"the campaign failed (exit {proc.returncode})")
    return parse_time_log(proc.stderr)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--profile", default="quick", choices=("quick", "paper"))
    parser.add_argument("--out", default=None, help="campaign output folder (default: a fresh temporary one)")
    parser.add_argument("--summary", default=None, help="print the tables of this summary.json, run nothing")
    parser.add_argument("--time-log", default=None, help="with --summary: the /usr/bin/time -v output of that run")
    parser.add_argument("--json", default=None, help="also write the numbers here")
    parser.add_argument("--kernels", default=None, help="a campaign's output folder: time its models' evaluation")
    parser.add_argument("--rows", type=int, default=50_000, help="with --kernels: held-out rows (default 50000)")
    parser.add_argument("extra", nargs="*", help="more campaign options (after --)")
    args = parser.parse_args(argv)
    if args.kernels:
        costs = kernel_costs(Path(args.kernels), args.rows)
        for name, us in costs.items():
            print(f"{name:16s} {us:8.2f} us/sample")
        if args.json:
            Path(args.json).write_text(json.dumps(costs, indent=1))
        return 0
    if args.summary:
        summary = json.loads(Path(args.summary).read_text())
        whole = parse_time_log(Path(args.time_log).read_text()) if args.time_log else {}
    else:
        with tempfile.TemporaryDirectory(prefix="mems-phases-") as tmp:
            out = Path(args.out) if args.out else Path(tmp)
            whole = run_campaign(args.profile, out, args.extra)
            summary = json.loads((out / "summary.json").read_text())
    numbers = tables(summary, whole)
    print(report(numbers))
    if args.json:
        Path(args.json).write_text(json.dumps(numbers, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
