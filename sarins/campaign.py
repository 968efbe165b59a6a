"""Parallel, resumable campaigns of independent experiments.

A campaign is a set of named tasks, each a module-level function and its
keyword arguments, returning a dict of numbers, strings and numpy arrays.
:func:`run_campaign` runs the tasks that have no valid stored result through
local worker processes (default) or a Dask distributed cluster (a scheduler
address), and stores each result the moment it arrives
(``<out_dir>/<task id>.npz``).  Killed half-way, the same call later reuses
what is finished and runs the rest.

A stored result is reused only if the record that made it (task function,
canonical keyword arguments, campaign options, package version, hash of the
code; :mod:`sarins.results`) equals the record of the task now, and it loads
and validates; otherwise it is recomputed with a one-line notice naming the
file.  Writes are atomic and durable; one campaign at a time holds an output
folder (:func:`sarins.results.exclusive`); workers are single-threaded and
die with the campaign process (:mod:`sarins.workers`).

Nothing here knows what the tasks compute.
"""

from __future__ import annotations

import concurrent.futures as cf
import re
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from .results import (Field, OutputBusyError, StoredResultError, atomic_output, build_artifacts,  # noqa: F401
                      canonical_json, check_fields, code_hash, exclusive, load_result, load_valid,
                      remove_stale_temporaries, save_result, task_record, write_text)
from .workers import DependencyError, SchedulerError, make_pool  # noqa: F401

_ID = re.compile(r"^[A-Za-z0-9_.-]+$")


@dataclass(frozen=True)
class Task:
    """One experiment: ``fn(**kwargs)`` -> dict.  ``id`` names its result file.

    volatile : names of keyword arguments that do not change the result
        (paths of artefacts keyed elsewhere, test delays); left out of the record.
    identity : what else the result depends on (e.g. digests of model files
        the kwargs only name); part of the record.
    finite : result keys that must be present and finite for a stored
        result to be reused.
    schema : {key: :class:`sarins.results.Field`}, what the run produces (keys,
        shapes derived from the kwargs, dtype kinds, finiteness); a stored result
        is reused only if it matches, and a fresh result that does not fails the task.
    """

    id: str
    fn: Callable
    kwargs: dict = field(default_factory=dict)
    volatile: tuple = ()
    identity: dict = field(default_factory=dict)
    finite: tuple = ()
    schema: dict | None = None

    def __post_init__(self):
        if not _ID.match(self.id):
            raise ValueError(f"task id {self.id!r} may only hold letters, digits, '_', '-' and '.'")


class TaskFailed(RuntimeError):
    """A task raised: the campaign stops (finished results stay stored)."""


class CampaignResults(dict):
    """{task id: result}; ``computed`` lists the ids computed by this call."""

    computed: list


def result_path(out_dir: Path, task_id: str) -> Path:
    return Path(out_dir) / f"{task_id}.npz"


def _notice(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def run_campaign(tasks, out_dir, *, workers: int | None = None, scheduler: str | None = None,
                 progress: bool = True, description: str = "campaign", options: dict | None = None,
                 notice: Callable[[str], None] = _notice, keep: bool = True) -> CampaignResults:
    """Run the tasks without a valid stored result; return {task id: result} for all.

    Parameters
    ----------
    tasks : iterable of Task (ids unique)
    out_dir : directory for the per-task result files (created, locked while running)
    workers : local worker processes (default: CPU count); 1 runs in this
        process, one task after another
    scheduler : address of a Dask distributed scheduler (overrides workers)
    progress : show a tqdm progress bar
    description : label of the bar and of the notices
    options : campaign options that change results without being task
        arguments; part of every task's record
    notice : callable receiving one-line notices (stale or corrupt files)
    keep : False returns {task id: path of its stored result} instead: a stored result is checked as usual
        and dropped, a fresh one is stored and not read back; the caller loads them
        (:func:`sarins.results.load_result`) one at a time and never holds every large result at once
    """
    tasks = list(tasks)
    ids = [t.id for t in tasks]
    if len(set(ids)) != len(ids):
        raise ValueError("task ids must be unique")
    out_dir = Path(out_dir)
    with exclusive(out_dir):
        remove_stale_temporaries(out_dir)
        records = {t.id: task_record(t, options) for t in tasks}
        results = CampaignResults()
        todo = []
        for task in tasks:
            path = result_path(out_dir, task.id)
            if path.is_symlink() or (path.exists() and not path.is_file()):
                kind = "a symbolic link" if path.is_symlink() else "a folder" if path.is_dir() else "not a regular file"
                raise StoredResultError(f"{path}: the stored result of task {task.id} is {kind}, which the campaign "
                                        "neither reads nor replaces; remove it or choose another output folder")
            try:
                stored = load_valid(path, records[task.id], task.finite, task.schema)
                results[task.id] = stored if keep else path  # (keep=False: checked, then dropped)
                del stored
            except FileNotFoundError:
                todo.append(task)
            except StoredResultError as exc:
                notice(f"{description}: recomputing {path}: {exc}")
                todo.append(task)
        results.computed = [t.id for t in todo]
        bar = _bar(len(tasks), len(tasks) - len(todo), progress, description)
        try:
            if todo and (workers == 1 and not scheduler):
                for task in todo:
                    try:
                        result = task.fn(**task.kwargs)
                    except Exception as exc:
                        raise TaskFailed(f"task {task.id} failed: {type(exc).__name__}: {exc}") from exc
                    path = _store(out_dir, task, result, records[task.id])
                    del result  # the stored copy stands for it: not two of a large result while the next runs
                    results[task.id] = load_result(path) if keep else path  # what a resume would see
                    bar.update(1)
            elif todo:
                _run_parallel(todo, out_dir, workers, scheduler, bar, records, results, keep)
        finally:
            bar.close()
    return _ordered(results, ids)


def _ordered(results: CampaignResults, ids) -> CampaignResults:
    out = CampaignResults((i, results[i]) for i in ids)
    out.computed = results.computed
    return out


def _store(out_dir, task, result, record) -> Path:
    """Check a fresh result against its task's schema and store it; the stored file's path."""
    if not isinstance(result, dict):
        raise TypeError(f"task {task.id} returned {type(result).__name__}, not a dict")
    if task.schema is not None:
        try:
            check_fields({k: v for k, v in result.items()}, task.schema)
        except StoredResultError as exc:
            raise TaskFailed(f"task {task.id} returned a result its declared schema does not allow: {exc}") from None
    path = result_path(out_dir, task.id)
    save_result(path, result, record)
    return path


def _run_parallel(todo, out_dir, workers, scheduler, bar, records, results, keep=True):
    pool = make_pool(workers, scheduler)
    interrupted = True
    try:
        futures = {pool.submit(t.fn, t.kwargs): t for t in todo}
        for future in cf.as_completed(futures):
            task = futures[future]
            try:
                result = future.result()
            except Exception as exc:
                raise TaskFailed(f"task {task.id} failed: {type(exc).__name__}: {exc}") from exc
            path = _store(out_dir, task, result, records[task.id])
            del result
            results[task.id] = load_result(path) if keep else path  # what a resume would see
            bar.update(1)
        interrupted = False
    finally:
        pool.close(interrupted)


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
