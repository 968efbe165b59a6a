"""Why the GRU trains slower than the LSTM on PyTorch's CPU kernels (seed 003's networks).

Times training steps exactly as ``sarins_fmu.identify.recurrent.train``
takes them (32 streams x a window of ``seq_len`` samples, 7 inputs, 60
units, NAdam, state carried) for LSTM and GRU, one and three layers, with
PyTorch's oneDNN (mkldnn) RNN path on and off, for several window lengths
and thread counts.  Every time is also given as a ratio to the one-layer
LSTM with the default settings measured in the same process (the
baseline), and the operators of one GRU and one LSTM step are counted with
``torch.profiler``.

    python benchmarks/bench_recurrent.py [--steps 30] [--seq-lens 25,100,400] [--threads 1,2]
"""

import argparse
import time


def _inference_seconds(torch, cell, layers, n=20000, hidden=60, n_in=7, n_out=6):
    """Wall time of one stateful pass over an n-sample series (as ``recurrent.run``), s."""
    from sarins_fmu.identify.recurrent import _torch_module

    net = _torch_module(torch, cell, n_in, hidden, n_out, layers)
    x = torch.randn(1, n, n_in)
    with torch.no_grad():
        net(x[:, :100])
        t0 = time.perf_counter()
        net(x)
    return time.perf_counter() - t0


def _op_counts(torch, cell, seq_len):
    """Number of operator calls and the most frequent ones in one training step."""
    from torch.profiler import ProfilerActivity, profile

    from sarins_fmu.identify.recurrent import _torch_module

    net = _torch_module(torch, cell, 7, 60, 6, 1)
    x, t = torch.randn(32, seq_len, 7), torch.randn(32, seq_len, 6)
    with profile(activities=[ProfilerActivity.CPU]) as prof:
        y, _ = net(x)
        torch.mean((y - t) ** 2).backward()
    events = prof.key_averages()
    total = sum(e.count for e in events)
    top = sorted(events, key=lambda e: -e.self_cpu_time_total)[:4]
    return total, [(e.key, e.count) for e in top]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=30, help="timed training steps per configuration")
    parser.add_argument("--seq-lens", default="25,100,400", help="window lengths (samples)")
    parser.add_argument("--threads", default="1,2", help="torch intra-op thread counts")
    args = parser.parse_args()
    import torch

    from sarins_fmu.identify.recurrent import training_step_seconds

    seq_lens = [int(v) for v in args.seq_lens.split(",")]
    threads = [int(v) for v in args.threads.split(",")]
    print(f"torch {torch.__version__}, oneDNN available {torch.backends.mkldnn.is_available()}")
    base = training_step_seconds("lstm", steps=args.steps)
    print(f"baseline: one-layer LSTM step, window 100, 1 thread, oneDNN on: {base * 1e3:.1f} ms")
    print("\ncell  layers window threads oneDNN   ms/step  x baseline  (GRU / LSTM at the same settings)")
    for n_threads in threads:
        for onednn in (True, False):
            for layers in (1, 3):
                for seq_len in seq_lens:
                    times = {c: training_step_seconds(c, layers=layers, seq_len=seq_len, steps=args.steps,
                                                      onednn=onednn, threads=n_threads) for c in ("lstm", "gru")}
                    for cell, sec in times.items():
                        ratio = f"({times['gru'] / times['lstm']:.2f})" if cell == "gru" else ""
                        print(f"{cell:5s} {layers:6d} {seq_len:6d} {n_threads:7d} {str(onednn):6s} "
                              f"{sec * 1e3:9.1f} {sec / base:10.2f}  {ratio}")
    torch.set_num_threads(1)
    print("\ninference over 20000 samples, 1 thread (s):")
    for onednn in (True, False):
        torch.backends.mkldnn.enabled = onednn
        row = {c: _inference_seconds(torch, c, 1) for c in ("lstm", "gru")}
        print(f"  oneDNN {str(onednn):5s}: LSTM {row['lstm']:.3f}  GRU {row['gru']:.3f}  "
              f"GRU / LSTM {row['gru'] / row['lstm']:.2f}")
    torch.backends.mkldnn.enabled = True
    print("\noperators of one forward + backward pass, window 100, oneDNN on:")
    for cell in ("lstm", "gru"):
        total, top = _op_counts(torch, cell, 100)
        print(f"  {cell}: {total} operator calls; most time in " + ", ".join(f"{k} x{n}" for k, n in top))


if __name__ == "__main__":
    main()
