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
