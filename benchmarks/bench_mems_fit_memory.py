"""Peak RSS of the mems-calibration campaign process's own fits (RBF 50 000 samples, GRNN 20 000 patterns: the
paper sizes) on a stored training set.

Usage: ``python benchmarks/bench_mems_fit_memory.py <out>/datasets stored|memory`` (a campaign's data-set folder,
e.g. after ``benchmarks/bench_mems_memory.py --profile paper --out DIR``): ``stored`` fits on the set read from disk
a slice at a time (what the campaign does), ``memory`` loads it first.  Prints the sample count, the peak RSS (MB,
getrusage) and each model's first target mean.
"""
import resource
import sys
from pathlib import Path

from sarins_fmu.identify import recurrent

recurrent.torch_available()  # torch imported, as in the campaign process
from sarins.mems_calibration import fitting  # noqa: E402
from sarins.mems_calibration.storage import StoredSet  # noqa: E402
import numpy as np  # noqa: E402

folder = Path(sys.argv[1])
n = np.load(folder / "training.time.npy", mmap_mode="r").shape[0]
stored = StoredSet(folder, "training", 0, n)
train = stored if sys.argv[2] == "stored" else stored.load()
models = fitting.fit_models(["rbf", "grnn"], train, None, rnn_steps=1, grnn_patterns=20000, rbf_samples=50000)
print(sys.argv[2], n, "peak MB", resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
      {k: float(m.target_mean[0]) for k, m in models.items()})
