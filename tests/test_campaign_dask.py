"""Campaigns on a real Dask cluster (issue 13 part 5): a local ``dask
scheduler`` and two ``dask worker`` processes on 127.0.0.1, a campaign
through ``--scheduler``, killed part-way, resumed, equal to a local run.
Everything started here is torn down (process groups killed)."""

import contextlib
import os
import signal
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hooks import command as hooked

pytest.importorskip("distributed", reason="Dask distributed is not installed (pip install 'sarins-fmu[distributed]')")

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
ENV = {**os.environ, "PYTHONPATH": f"{ROOT}{os.pathsep}{HERE}", "SARINS_THREADS": "1", "OMP_NUM_THREADS": "1",
       "DASK_DISTRIBUTED__WORKER__DAEMON": "False"}


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def _start(args):
    return subprocess.Popen([sys.executable, "-m", *args], env=ENV, cwd=str(ROOT), start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def _stop(proc):
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


@pytest.fixture(scope="module")
def cluster():
    from distributed import Client

    port = _free_port()
    address = f"tcp://127.0.0.1:{port}"
    procs = [_start(["distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"])]
    try:
        for _ in range(2):
            procs.append(_start(["distributed.cli.dask_worker", address, "--nthreads", "1", "--nworkers", "1",
                                 "--no-dashboard", "--host", "127.0.0.1"]))
        with Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=120)
        yield address
    finally:
        for proc in reversed(procs):
            _stop(proc)


def _campaign(args, out, scheduler=None, workers=None, hooks=()):
    cmd = [*hooked(*hooks), "-m", "sarins", "campaign", *args, "--out", str(out), "--no-progress"]
    cmd += ["--scheduler", scheduler] if scheduler else ["--workers", str(workers or 1)]
    return subprocess.Popen(cmd, env=ENV, cwd=str(ROOT), start_new_session=True, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def _results(folder: Path) -> dict:
    from sarins.campaign import load_result

    return {p.name: load_result(p) for p in sorted(folder.glob("*.npz"))}


def _assert_same(a: dict, b: dict):
    assert a.keys() == b.keys()
    for name in a:
        assert a[name].keys() == b[name].keys(), name
        for key in a[name]:
            if key in ("wall_seconds", "wall_s"):
                continue
            x, y = a[name][key], b[name][key]
            if isinstance(x, np.ndarray) and x.dtype.kind in "fc":
                assert np.array_equal(x, y, equal_nan=True), (name, key)
            else:
                assert np.all(x == y), (name, key)


@pytest.mark.slow
def test_online_rls_through_dask_killed_and_resumed_equals_a_local_run(cluster, tmp_path):
    """The quick online-rls campaign through the cluster, SIGKILLed after its
    first stored results, resumed; same results (bit for bit) and report
    tables as a local run; the Dask executor shuts down cleanly."""
    out, ref = tmp_path / "dask", tmp_path / "local"
    # a test hook (tests/hooks.py) SIGKILLs the campaign right after its 3rd stored result
    proc = _campaign(["online-rls", "--profile", "quick"], out, scheduler=cluster, hooks=("--kill-after", "3"))
    try:
        _, stderr = proc.communicate(timeout=1800)  # the timeout only guards a hang
        assert proc.returncode == -signal.SIGKILL, stderr
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
    done = _results(out / "runs")
    assert len(done) == 3
    proc = _campaign(["online-rls", "--profile", "quick"], out, scheduler=cluster)
    stdout, stderr = proc.communicate(timeout=1800)
    assert proc.returncode == 0, stderr
    assert "Traceback" not in stderr and "recomputing" not in stderr
    resumed = _results(out / "runs")
    assert f"{len(resumed)} runs ({len(resumed) - len(done)} computed now)" in stdout  # the rest, once each
    for name, result in done.items():  # finished before the kill: reused as they were
        _assert_same({name: result}, {name: resumed[name]})
    proc = _campaign(["online-rls", "--profile", "quick"], ref, workers=2)
    stdout, stderr = proc.communicate(timeout=1800)
    assert proc.returncode == 0, stderr
    _assert_same(resumed, _results(ref / "runs"))
    tables = [[line for line in (d / "report.md").read_text().splitlines() if line.startswith("|")] for d in (out, ref)]
    assert tables[0] and tables[0] == tables[1]


@pytest.mark.slow
def test_generic_campaign_through_dask(cluster, tmp_path):
    """The runner alone: tasks go to both workers, results equal a local run."""
    from campaign_tasks import environment, square
    from sarins.campaign import Task, run_campaign

    tasks = [Task(f"sq{x}", square, {"x": x, "delay": 0.2}, volatile=("delay",)) for x in range(8)]
    remote = run_campaign(tasks, tmp_path / "dask", scheduler=cluster, progress=False)
    local = run_campaign(tasks, tmp_path / "local", workers=1, progress=False)
    _assert_same({k: v for k, v in remote.items()}, {k: v for k, v in local.items()})
    env = run_campaign([Task(f"e{i}", environment) for i in range(6)], tmp_path / "env", scheduler=cluster,
                       progress=False)
    assert len({r["pid"] for r in env.values()}) == 2 and all(r["core_threads"] == 1 for r in env.values())
