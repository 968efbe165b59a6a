import contextlib
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from campaign_tasks import fail, square
from sarins.campaign import Task, load_result, run_campaign, save_result

HERE = Path(__file__).resolve().parent


def test_results_are_stored_and_reloaded(tmp_path):
    tasks = [Task(f"sq{x}", square, {"x": x}) for x in range(4)]
    out = run_campaign(tasks, tmp_path, workers=2, progress=False)
    assert out["sq3"]["y"] == 9 and out["sq3"]["label"] == "run 3"
    assert np.array_equal(out["sq2"]["series"], np.arange(5) * 2)
    assert sorted(p.name for p in tmp_path.glob("*.npz")) == [f"sq{x}.npz" for x in range(4)]


def test_finished_tasks_are_skipped(tmp_path):
    markers = tmp_path / "markers"
    markers.mkdir()
    tasks = [Task(f"sq{x}", square, {"x": x, "marker_dir": str(markers)}) for x in range(3)]
    run_campaign(tasks, tmp_path / "out", workers=1, progress=False)
    run_campaign(tasks, tmp_path / "out", workers=1, progress=False)
    assert len(list(markers.iterdir())) == 3


def test_failure_names_the_task(tmp_path):
    with pytest.raises(RuntimeError, match="task bad7 failed: ValueError: bad input 7"):
        run_campaign([Task("bad7", fail, {"x": 7})], tmp_path, workers=2, progress=False)


def test_bad_task_ids_and_results(tmp_path):
    with pytest.raises(ValueError):
        Task("a/b", square)
    with pytest.raises(TypeError):
        save_result(tmp_path / "x.npz", {"obj": object()})


def test_killed_campaign_resumes_without_losing_or_redoing_work(tmp_path):
    """Kill the process running a campaign (and its worker pool) half-way,
    rerun the same command: finished runs are kept and not redone, the rest
    complete, and the results equal an uninterrupted campaign's.  The kill
    comes from a test hook (``tests/hooks.py``) right after the third stored
    result, so where it lands does not depend on load."""
    markers, out = tmp_path / "markers", tmp_path / "out"
    markers.mkdir()
    script = textwrap.dedent(f"""
        import sys
        sys.path[:0] = [{str(HERE)!r}, {str(HERE.parent)!r}]
        from campaign_tasks import square
        from hooks import kill_after_results
        from sarins.campaign import Task, run_campaign
        kill_after_results(3)
        tasks = [Task(f"sq{{x}}", square, {{"x": x, "marker_dir": {str(markers)!r}, "delay": 0.0}},
                      volatile=("marker_dir", "delay")) for x in range(12)]
        run_campaign(tasks, {str(out)!r}, workers=2, progress=False)
    """)
    proc = subprocess.Popen([sys.executable, "-c", script], start_new_session=True)
    try:
        assert proc.wait(timeout=600) == -signal.SIGKILL  # the hook fired (the timeout only guards a hang)
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)  # anything of the group still alive
    finished = sorted(p.stem for p in out.glob("*.npz"))
    assert len(finished) == 3
    for task_id in finished:  # every stored file is complete (written whole, then renamed)
        assert load_result(out / f"{task_id}.npz")["y"] == int(task_id[2:]) ** 2
    tasks = [Task(f"sq{x}", square, {"x": x, "marker_dir": str(markers), "delay": 0.0}, volatile=("marker_dir", "delay"))
             for x in range(12)]
    results = run_campaign(tasks, out, workers=2, progress=False)
    runs = {}
    for marker in markers.iterdir():
        runs[marker.name.split(".")[0]] = runs.get(marker.name.split(".")[0], 0) + 1
    for task_id in finished:
        assert runs[task_id[2:]] == 1, f"{task_id} was run again"
    reference = run_campaign(tasks, tmp_path / "ref", workers=1, progress=False)
    for task_id, result in results.items():
        assert result["y"] == reference[task_id]["y"]
        assert np.array_equal(result["series"], reference[task_id]["series"])
    assert set(load_result(out / "sq5.npz")) == {"x", "y", "series", "label"}
