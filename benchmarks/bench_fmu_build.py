"""Building the native FMUs: the build's per-object compile (side by side, the shared files from a cache) against
the documented one-command compile line of each FMU's sources/, in the same process.

For the default FMUs (this machine's binaries only, as the campaigns and the test session build them):

* baseline: for each FMU, its sources/ written as the build writes them and compiled with the one command
  ``fmus.native_fmu.compile_line`` documents (``cc <flags> -fPIC -shared -I. *.c -o <id>.so``), one FMU after
  the other;
* the build: ``fmus.build.build_fmus(cross=False)`` (``fmus.cbuild``: one object per file, up to one per core
  at a time, the glue's and the core's objects compiled once for every FMU), its cache empty at the start.

Prints both wall times and the ratio build / baseline, best of ``--rounds`` (alternating), and the load
averages.  Usage: ``python benchmarks/bench_fmu_build.py [--rounds 2]``
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
sys.path.insert(0, str(ROOT))

from fmus import SLAVES  # noqa: E402
from fmus.build import DEFAULT_NAMES, build_fmus  # noqa: E402
from fmus.native_fmu import compile_line, compiler, slave_instance, variables_header, write_sources  # noqa: E402


def baseline(folder: Path) -> float:
    """Seconds to write and compile every default FMU's sources with its one documented command."""
    t0 = time.perf_counter()
    for name in DEFAULT_NAMES:
        slave = slave_instance(SLAVES[name])
        sources = folder / name
        files = write_sources(name, sources, variables_header(slave, "{bench}", slave.modelName))
        line = compile_line(slave.modelName, compiler())
        star = line.index("*.c")
        subprocess.run([*line[:star], *files, *line[star + 1:]], cwd=sources, check=True, capture_output=True)
    return time.perf_counter() - t0


def build(folder: Path) -> float:
    """Seconds of build_fmus(cross=False) into ``folder`` with an empty object cache."""
    os.environ.pop("SARINS_CC_CACHE", None)
    t0 = time.perf_counter()
    build_fmus(folder, cross=False)
    return time.perf_counter() - t0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=2)
    args = parser.parse_args()
    print(f"load before {os.getloadavg()[0]:.2f}; {len(DEFAULT_NAMES)} FMUs, {os.cpu_count()} cores")
    times = {"baseline": [], "build": []}
    for k in range(args.rounds):
        for kind, run in (("baseline", baseline), ("build", build)):
            with tempfile.TemporaryDirectory(prefix="bench_fmu_build_") as tmp:
                times[kind].append(run(Path(tmp)))
            print(f"round {k + 1}: {kind} {times[kind][-1]:.1f} s")
    best = {kind: min(values) for kind, values in times.items()}
    print(f"one command per FMU (baseline) {best['baseline']:.1f} s; build_fmus {best['build']:.1f} s: "
          f"{best['build'] / best['baseline']:.2f}x the baseline; load after {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
