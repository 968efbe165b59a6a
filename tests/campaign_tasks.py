"""Task functions for the campaign tests (importable by spawned workers)."""

import os
import time
from pathlib import Path

import numpy as np


def square(x, marker_dir=None, delay=0.0):
    if marker_dir is not None:  # count executions
        Path(marker_dir, f"{x}.{os.getpid()}.{time.time_ns()}").touch()
    time.sleep(delay)
    return {"x": x, "y": x * x, "series": np.arange(5) * x, "label": f"run {x}"}


def fail(x):
    raise ValueError(f"bad input {x}")


def environment():
    """What a worker sees: its single-thread settings and its parent."""
    from sarins_fmu.core.imu import thread_count

    return {"threads_env": os.environ.get("SARINS_THREADS", ""), "omp_env": os.environ.get("OMP_NUM_THREADS", ""),
            "core_threads": thread_count(), "pid": os.getpid()}


def sleeper(x, seconds=60.0):
    time.sleep(seconds)
    return {"x": x}
