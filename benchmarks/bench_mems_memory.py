"""Peak resident memory of each phase of ``sarins campaign mems-calibration`` (default: the quick profile).

Runs the campaign in a subprocess and samples the resident set (``VmRSS`` of ``/proc/<pid>/status``) of
the campaign process and of every descendant (the recurrent fits' forked processes) every ``--interval``
seconds; the phase is read from the campaign's progress lines.  Per phase it prints the campaign process's
peak, the largest single descendant's peak and the peak of their sum, MB, with the phase's wall and CPU
seconds from ``summary.json``; the process tree's overall peak is what ``/usr/bin/time -v`` reports as
"Maximum resident set size" (one process, not the sum).  Sampling misses peaks shorter than the interval:
the campaign process's own ``peak_rss_mb`` per phase (``summary.json``, from getrusage) bounds it exactly.

Usage: ``python benchmarks/bench_mems_memory.py [--out DIR] [--profile quick] [-- extra campaign options]``
(several minutes on 2 cores: run it alone).
"""

from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PHASE = re.compile(r"^mems-calibration \[(\w+) \d+/\d+\]")


def rss_mb(pid: int) -> float:
    """Resident set of one process, MB (0 once it is gone)."""
    try:
        with open(f"/proc/{pid}/status") as fh:
            for line in fh:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
    except (FileNotFoundError, ProcessLookupError, PermissionError):
        pass
    return 0.0


def descendants(pid: int) -> list:
    """Every live descendant of ``pid`` (from /proc/<pid>/task/*/children)."""
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        for task in Path(f"/proc/{p}/task").glob("*"):
            try:
                kids = [int(k) for k in (task / "children").read_text().split()]
            except (FileNotFoundError, ProcessLookupError, PermissionError):
                continue
            out += kids
            todo += kids
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=None, help="campaign folder (default: a temporary one)")
    parser.add_argument("--profile", default="quick")
    parser.add_argument("--interval", type=float, default=0.1, help="sampling interval, s")
    parser.add_argument("extra", nargs="*", help="further campaign options (after --)")
    args = parser.parse_args()
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="mems-memory-"))
    cmd = [sys.executable, "-m", "sarins", "campaign", "mems-calibration", "--profile", args.profile, "--out", str(out),
           *args.extra]
    proc = subprocess.Popen(cmd, cwd=ROOT, stderr=subprocess.PIPE, stdout=subprocess.DEVNULL, text=True,
                            env={**__import__("os").environ, "PYTHONPATH": str(ROOT)})
    phase = ["start"]
    peaks = {}  # phase: [main, largest descendant, sum]
    tail = []

    def read_progress():
        for line in proc.stderr:
            tail.append(line)
            del tail[:-20]
            m = PHASE.match(line)
            if m:
                phase[0] = m.group(1)

    reader = threading.Thread(target=read_progress, daemon=True)
    reader.start()
    t0 = time.perf_counter()
    while proc.poll() is None:
        main_mb = rss_mb(proc.pid)
        kids = [rss_mb(k) for k in descendants(proc.pid)]
        peak = peaks.setdefault(phase[0], [0.0, 0.0, 0.0])
        for i, value in enumerate((main_mb, max(kids, default=0.0), main_mb + sum(kids))):
            peak[i] = max(peak[i], value)
        time.sleep(args.interval)
    reader.join(timeout=5)
    wall = time.perf_counter() - t0
    if proc.returncode:
        sys.exit(f"campaign failed ({proc.returncode}):\n{''.join(tail)}")
    summary = json.loads((out / "summary.json").read_text())
    phases = summary.get("phases", {})
    print(f"mems-calibration --profile {args.profile}: {wall:.0f} s wall; peak RSS per phase, MB (sampled every "
          f"{args.interval} s; 'getrusage' is the campaign process's exact peak so far)")
    print(f"{'phase':12s} {'campaign':>9s} {'fit proc':>9s} {'sum':>8s} {'getrusage':>10s} {'wall s':>8s} {'CPU s':>8s}")
    for name, (main_mb, kid_mb, total) in peaks.items():
        measured = phases.get(name, {})
        print(f"{name:12s} {main_mb:9.0f} {kid_mb:9.0f} {total:8.0f} {measured.get('peak_rss_mb', float('nan')):10.0f} "
              f"{measured.get('wall_s', float('nan')):8.1f} {measured.get('cpu_s', float('nan')):8.1f}")
    overall = max(max(p[0], p[1]) for p in peaks.values())
    print(f"largest single process: {overall:.0f} MB; largest sum: {max(p[2] for p in peaks.values()):.0f} MB")


if __name__ == "__main__":
    main()
