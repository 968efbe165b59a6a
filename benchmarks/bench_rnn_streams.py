"""Recurrent compensators on several series side by side (``sarins_comp_run_streams``) against the same series
one after the other (``sarins_comp_run``), in the same process.

Each recurrent kind at seed 003's size (60 units; random weights: the cost of inference only,
``bench_native_nets.models``) runs ``--series`` series of ``--samples`` rows each, first one at a time, then all
at once; prints microseconds per sample of each, the ratio, and whether every series' rows are the same bits
(they must be).  Best of ``--rounds``.

    PYTHONPATH=. python3 benchmarks/bench_rnn_streams.py [--series 3] [--samples 50000] [--rounds 3]
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_native_nets import models  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--series", type=int, default=3)
    parser.add_argument("--samples", type=int, default=50000)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    rng = np.random.default_rng(1)
    n = args.samples
    series = [np.column_stack([rng.normal(0, 0.5, (n, 3)), rng.normal(0, 3.0, (n, 3)), np.linspace(-10, 40, n)])
              for _ in range(args.series)]
    print(f"load before {os.getloadavg()[0]:.2f}; {args.series} series of {n} samples")
    fitted = models()
    for kind in ("lstm", "gru", "lstm3", "gru3"):
        native = fitted[kind].native()
        alone, together = [], []
        for _ in range(args.rounds):
            t0 = time.perf_counter()
            one = [native.run(x, native.zero_state()) for x in series]
            alone.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            many = native.run_streams(series, [native.zero_state() for _ in series])
            together.append(time.perf_counter() - t0)
        same = all(np.array_equal(a.view(np.uint64), b.view(np.uint64)) for a, b in zip(one, many))
        per = 1e6 / (n * args.series)
        print(f"{kind:6s} one after the other {min(alone) * per:6.2f} us/sample, side by side "
              f"{min(together) * per:6.2f} us/sample: {min(alone) / min(together):.2f}x, same bits {same}")
    print(f"load after {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
