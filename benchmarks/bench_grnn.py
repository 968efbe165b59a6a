"""Seed 003's GRNN evaluation truncated to its bound, against the dense kernel, on the campaign's own data.

Records the training and held-out runs of a profile in process (``--profile paper``: 2.8 M held-out samples at
200 Hz), fits the GRNN compensator (``--patterns``, the campaign's 20 000 for the paper profile), then times in
this process:

* the truncated evaluation of the whole held-out run (``GRNNCompensator.predict_batch``, tolerance 1e-9: k-d
  tree candidates, the C kernel's exact cut), CPU and wall seconds, and the patterns kept per query;
* the dense C kernel (``predict``, the IMUCompensator FMU's evaluation) on every ``--dense-stride``-th held-out
  sample, scaled to the whole run (its cost is the same per query);

and prints the ratio dense / truncated (CPU) and the largest difference on the dense rows against the
derived bound (tolerance times each output's training range times the target scale).  ``--blocks 64,128,256``
also times the truncation with those query rows per k-d tree ball query (``grnn.SEARCH_BLOCK``), the tree
search and the C kernel apart, on one thread (the outputs must not change: asserted).

    PYTHONPATH=. python3 benchmarks/bench_grnn.py [--profile paper] [--patterns 20000] [--dense-stride 500]
    [--blocks 128,256,512]
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def campaign_data(profile: str, seed: int = 3):
    """(train, test) datasets of the profile's training and held-out recordings, in process."""
    from sarins_fmu.experiments import mems_calibration as mc

    prof = mc.profile(profile)
    recs = {k: mc.record_in_process(k, prof, seed=mc.run_seed(k, seed),
                                    model=mc.recording_model(k, seed)) for k in ("dynamic", "heldout")}
    return mc.dynamic_dataset(recs["dynamic"], recs["heldout"], prof)


def timed(fn):
    """(result, CPU s, wall s) of fn()."""
    c, w = time.process_time(), time.perf_counter()
    out = fn()
    return out, time.process_time() - c, time.perf_counter() - w


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--profile", default="paper", choices=("quick", "paper"))
    parser.add_argument("--patterns", type=int, default=20000)
    parser.add_argument("--dense-stride", type=int, default=500)
    parser.add_argument("--blocks", default="", help="comma-separated query rows per ball query to compare")
    args = parser.parse_args(argv)
    from sarins_fmu.identify import compensators
    from sarins_fmu.identify.grnn import GRNN_TOLERANCE

    (train, test), cpu, wall = timed(lambda: campaign_data(args.profile))
    print(f"recordings: {len(train)} training, {len(test)} held-out samples ({cpu:.1f} CPU-s)")
    comp = compensators.make("grnn", max_patterns=args.patterns).fit(train.X, train.Y)
    n = comp.net.y_train_.shape[0]
    (y, kept), cpu_t, wall_t = timed(lambda: comp.predict_batch(test.X, return_kept=True))
    rows = test.X[::args.dense_stride]
    dense, cpu_d, wall_d = timed(lambda: comp.predict(rows))
    scale = len(test) / len(rows)
    print(f"GRNN {n} patterns, {len(test)} queries, tolerance {GRNN_TOLERANCE:g}")
    print(f"truncated: {cpu_t:.2f} CPU-s, {wall_t:.2f} wall-s; patterns kept per query mean {kept.mean():.0f}, "
          f"median {np.median(kept):.0f}, p99 {np.percentile(kept, 99):.0f}, max {kept.max()}")
    print(f"dense (every {args.dense_stride}th query, scaled x{scale:.0f}): {cpu_d * scale:.1f} CPU-s, "
          f"{wall_d * scale:.1f} wall-s")
    print(f"ratio dense / truncated: {cpu_d * scale / cpu_t:.1f} (CPU), {wall_d * scale / wall_t:.1f} (wall)")
    spread = comp.net.y_train_.max(axis=0) - comp.net.y_train_.min(axis=0)
    bound = GRNN_TOLERANCE * spread * comp.target_scale
    diff = np.abs(y[::args.dense_stride] - dense).max(axis=0)
    print("largest |truncated - dense| per output:", " ".join(f"{v:.2e}" for v in diff))
    print("bound tol * range * target scale:       ", " ".join(f"{v:.2e}" for v in bound))
    for block in (int(b) for b in args.blocks.split(",") if b):
        search, kernel, cand, out = block_costs(comp, test.X, block)
        assert np.array_equal(out, y), "the block size changed the outputs"
        print(f"block {block}: tree search {search:.2f} + kernel {kernel:.2f} CPU-s, candidates per query {cand:.0f}")


def block_costs(comp, x, block: int):
    """(search CPU s, kernel CPU s, candidates per row, outputs) of the truncated GRNN on one thread, the
    queries in the campaign's chunks, ``block`` rows per ball query."""
    from scipy.spatial import cKDTree

    from sarins_fmu.identify.grnn import CHUNK_ROWS, neighbour_blocks

    net, model = comp.net, comp.native()
    tree = cKDTree(net._z_train)
    search = kernel = 0.0
    cand, outs = 0, []
    for start in range(0, len(x), CHUNK_ROWS):
        rows = x[start:start + CHUNK_ROWS]
        blocks, cpu_s, _ = timed(lambda rows=rows: neighbour_blocks(tree, net.scaling_.apply(rows), net.settings.sigma,
                                                                    block=block))
        (out, _), cpu_k, _ = timed(lambda rows=rows, blocks=blocks: model.run_grnn_blocks(rows, blocks))
        search, kernel = search + cpu_s, kernel + cpu_k
        cand += int(np.sum(np.diff(blocks.cand_ptr) * np.diff(blocks.row_ptr)))
        outs.append(out)
    return search, kernel, cand / len(x), np.concatenate(outs)


if __name__ == "__main__":
    main()
