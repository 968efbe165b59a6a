"""Parallel, resumable campaigns of independent experiments.

A campaign is a set of named tasks, each a module-level function and its
keyword arguments, returning a dict of numbers, strings and numpy arrays.
:func:`run_campaign` runs the tasks that have no stored result yet through a
``concurrent.futures`` executor -- local processes by default, a Dask
distributed cluster when a scheduler address is given -- and stores each
result the moment it arrives (``<out_dir>/<task id>.npz``, written to a
temporary file and renamed, so a file is either complete or absent).  Killed
half-way, the same call later skips what is finished and runs the rest.

Nothing here knows what the tasks compute.
"""

from __future__ import annotations

import concurrent.futures as cf
import multiprocessing
import os
import re
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

_ID = re.compile(r"^[A-Za-z0-9_.-]+$")


@dataclass(frozen=True)
class Task:
    """One experiment: ``fn(**kwargs)`` -> dict.  ``id`` names its result file."""

    id: str
    fn: Callable
    kwargs: dict = field(default_factory=dict)

    def __post_init__(self):
        if not _ID.match(self.id):
            raise ValueError(f"task id {self.id!r} may only hold letters, digits, '_', '-' and '.'")


def result_path(out_dir: Path, task_id: str) -> Path:
    return Path(out_dir) / f"{task_id}.npz"


def save_result(path: Path, result: dict) -> None:
    """Atomically write a result dict (values become numpy arrays; no pickle)."""
    path = Path(path)
    arrays = {}
    for key, value in result.items():
        arr = np.asarray(value)
        if arr.dtype == object:
            raise TypeError(f"result {key!r} of {path.name} is not numeric or text")
        arrays[key] = arr
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=".npz.tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez(fh, **arrays)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


def load_result(path: Path) -> dict:
    """Read a stored result; scalars come back as Python numbers/strings."""
    with np.load(path, allow_pickle=False) as data:
        return {key: (data[key].item() if data[key].ndim == 0 else data[key]) for key in data.files}


def _call(fn, kwargs):
    return fn(**kwargs)


def make_executor(workers: int | None = None, scheduler: str | None = None):
    """A concurrent.futures executor: Dask when ``scheduler`` is an address
    ('tcp://host:8786'), else a local process pool (spawned workers)."""
    if scheduler:
        try:
            from dask.distributed import Client
        except ImportError:
            raise RuntimeError("a Dask scheduler was given but dask.distributed is not installed: "
                               "pip install 'sarins-fmu[distributed]'") from None
        client = Client(scheduler)
        return client.get_executor(), client
    ctx = multiprocessing.get_context("spawn")
    return cf.ProcessPoolExecutor(max_workers=workers or os.cpu_count(), mp_context=ctx), None


def run_campaign(tasks, out_dir, *, workers: int | None = None, scheduler: str | None = None,
                 progress: bool = True, description: str = "campaign") -> dict:
    """Run the tasks without a stored result; return {task id: result} for all.

    Parameters
    ----------
    tasks : iterable of Task (ids unique)
    out_dir : directory for the per-task result files (created)
    workers : local worker processes (default: CPU count); 1 runs in this
        process, one task after another
    scheduler : address of a Dask distributed scheduler (overrides workers)
    progress : show a tqdm progress bar
    """
    tasks = list(tasks)
    ids = [t.id for t in tasks]
    if len(set(ids)) != len(ids):
        raise ValueError("task ids must be unique")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    todo = [t for t in tasks if not result_path(out_dir, t.id).exists()]
    bar = _bar(len(tasks), len(tasks) - len(todo), progress, description)
    try:
        if todo and (workers == 1 and not scheduler):
            for task in todo:
                save_result(result_path(out_dir, task.id), task.fn(**task.kwargs))
                bar.update(1)
        elif todo:
            _run_parallel(todo, out_dir, workers, scheduler, bar)
    finally:
        bar.close()
    return {t.id: load_result(result_path(out_dir, t.id)) for t in tasks}


def _run_parallel(todo, out_dir, workers, scheduler, bar):
    executor, client = make_executor(workers, scheduler)
    futures = {}
    try:
        futures = {executor.submit(_call, t.fn, t.kwargs): t for t in todo}
        for future in cf.as_completed(futures):
            task = futures[future]
            try:
                result = future.result()
            except Exception as exc:
                raise RuntimeError(f"task {task.id} failed: {type(exc).__name__}: {exc}") from exc
            save_result(result_path(out_dir, task.id), result)
            bar.update(1)
    except BaseException:
        for future in futures:
            future.cancel()
        raise
    finally:
        executor.shutdown(wait=True, cancel_futures=True)
        if client is not None:
            client.close()


class _NoBar:
    def update(self, n):
        pass

    def close(self):
        pass


def _bar(total, done, progress, description):
    if not progress:
        return _NoBar()
    from tqdm.auto import tqdm

    return tqdm(total=total, initial=done, desc=description, unit="run", mininterval=1.0)


def wait_for(paths, timeout: float) -> bool:
    """Poll until all ``paths`` exist (test helper for interrupted campaigns)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if all(Path(p).exists() for p in paths):
            return True
        time.sleep(0.05)
    return False
