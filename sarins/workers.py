"""Executors for campaigns: local worker processes or a Dask cluster.

Local workers are spawned processes that

* run single-threaded kernels (``SARINS_THREADS`` for the C core's batches,
  ``OMP_NUM_THREADS``, ``MKL_NUM_THREADS``, ``OPENBLAS_NUM_THREADS`` = 1 in
  their environment before anything is imported, and ``SARINS_THREADS=1``
  again per task), so ``--workers N`` uses N cores, not N times all of them;
* die with the campaign process: ``PR_SET_PDEATHSIG`` (Linux, via
  ``prctl``) sends them SIGKILL when it dies, even by SIGKILL, and a
  watchdog thread covers systems without it; once they are gone the
  multiprocessing resource tracker sees its pipe close and exits too;
* ignore SIGINT: a Ctrl-C in the terminal reaches the whole process group,
  and the campaign process stops them itself (:func:`stop_local`).

Dask workers are started by the user (``dask worker ADDRESS --nthreads 1``
gives one single-threaded task per worker process); every task still sets
``SARINS_THREADS=1`` in its worker process (the core reads it per batch).
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import ctypes
import multiprocessing
import os
import signal
import threading
import time

SINGLE_THREAD_ENV = {"SARINS_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
                     "OPENBLAS_NUM_THREADS": "1"}
_PR_SET_PDEATHSIG = 1


def _die_with_parent(parent_pid: int) -> None:
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(_PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
        has_prctl = True
    except (OSError, AttributeError):
        has_prctl = False
    if os.getppid() != parent_pid:  # the parent died before prctl took effect
        os._exit(1)
    if not has_prctl:
        def watch():
            while os.getppid() == parent_pid:
                time.sleep(0.5)
            os._exit(1)

        threading.Thread(target=watch, name="parent-watchdog", daemon=True).start()


def worker_init(parent_pid: int) -> None:
    """Initializer of every local worker process (see module docs)."""
    os.environ.update(SINGLE_THREAD_ENV)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _die_with_parent(parent_pid)


def single_threaded() -> None:
    """Run the C core's batches of this worker process on the calling thread."""
    os.environ["SARINS_THREADS"] = "1"


def call(fn, kwargs):
    """What a worker runs for one task."""
    single_threaded()
    return fn(**kwargs)


@contextlib.contextmanager
def _env(values: dict):
    old = {k: os.environ.get(k) for k in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


class LocalPool:
    """A spawned ``ProcessPoolExecutor`` whose workers follow the module's rules."""

    def __init__(self, workers: int):
        self._env = _env(SINGLE_THREAD_ENV)  # inherited by the workers at spawn time
        self._env.__enter__()
        self.executor = cf.ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                                               initializer=worker_init, initargs=(os.getpid(),))

    def submit(self, fn, kwargs):
        return self.executor.submit(call, fn, kwargs)

    def close(self, interrupted: bool) -> None:
        """Shut down; after an interruption stop the running workers at once."""
        try:
            if interrupted:
                stop_local(self.executor)
            self.executor.shutdown(wait=True, cancel_futures=True)
        finally:
            self._env.__exit__(None, None, None)


def stop_local(executor: cf.ProcessPoolExecutor, timeout: float = 5.0) -> None:
    """Terminate a process pool's workers now (then SIGKILL after ``timeout``)."""
    processes = list((getattr(executor, "_processes", None) or {}).values())
    for proc in processes:
        with contextlib.suppress(Exception):
            proc.terminate()
    end = time.monotonic() + timeout
    for proc in processes:
        with contextlib.suppress(Exception):
            proc.join(max(0.0, end - time.monotonic()))
            if proc.is_alive():
                proc.kill()
                proc.join(1.0)


class DaskPool:
    """Tasks on a Dask distributed cluster through ``Client.get_executor()``.

    Its executor's ``shutdown`` takes no ``cancel_futures``; unfinished
    futures are cancelled explicitly instead.
    """

    def __init__(self, address: str, timeout: float = 20.0):
        try:
            from dask.distributed import Client
        except ImportError:
            raise DependencyError("--scheduler needs Dask's distributed scheduler, which is not installed: "
                                  "pip install 'sarins-fmu[distributed]'") from None
        try:
            self.client = Client(address, timeout=timeout)
        except (OSError, TimeoutError, ValueError) as exc:
            raise SchedulerError(f"--scheduler {address}: cannot reach a Dask scheduler there "
                                 f"({type(exc).__name__}: {' '.join(str(exc).split())[:160]})") from None
        self.executor = self.client.get_executor(pure=False)
        self._futures = []

    def submit(self, fn, kwargs):
        future = self.executor.submit(call, fn, kwargs)
        self._futures.append(future)
        return future

    def close(self, interrupted: bool) -> None:
        try:
            for future in self._futures:
                future.cancel()
            self.executor.shutdown(wait=not interrupted)
        finally:
            self.client.close()


class DependencyError(ValueError):
    """An optional dependency the chosen option needs is missing (exit 2)."""


class SchedulerError(ValueError):
    """The named Dask scheduler cannot be reached (exit 2)."""


def make_pool(workers: int | None, scheduler: str | None):
    """A :class:`DaskPool` when ``scheduler`` is given, else a :class:`LocalPool`."""
    if scheduler:
        return DaskPool(scheduler)
    return LocalPool(workers or os.cpu_count() or 1)
