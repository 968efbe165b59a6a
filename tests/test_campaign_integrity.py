"""Campaign results keyed by what made them; resume never trusts a bad file;
durable writes; one campaign per output folder; no worker outlives a
killed campaign (sarins.campaign, sarins.results, sarins.workers)."""

import os
import signal
import subprocess
import sys
import textwrap
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

from campaign_tasks import environment, square
from sarins.campaign import (OutputBusyError, Task, build_artifacts, exclusive, load_result, run_campaign,
                             save_result, task_record)

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent


def _run(tasks, out, notes=None, **kw):
    return run_campaign(tasks, out, workers=1, progress=False, notice=(notes.append if notes is not None else print),
                        **kw)


def test_a_changed_parameter_is_recomputed_with_a_notice(tmp_path):
    """The lambda example: same task id, other argument -> not reused."""
    notes = []
    assert _run([Task("run", square, {"x": 2})], tmp_path, notes)["run"]["y"] == 4
    again = _run([Task("run", square, {"x": 2})], tmp_path, notes)
    assert again.computed == [] and notes == []
    changed = _run([Task("run", square, {"x": 3})], tmp_path, notes)
    assert changed["run"]["y"] == 9 and changed.computed == ["run"]
    assert len(notes) == 1 and "run.npz" in notes[0] and "kwargs.x" in notes[0] and "\n" not in notes[0]
    assert load_result(tmp_path / "run.npz")["y"] == 9


def test_options_and_identity_are_part_of_the_record(tmp_path):
    notes = []
    _run([Task("run", square, {"x": 2})], tmp_path, notes, options={"profile": "quick"})
    _run([Task("run", square, {"x": 2})], tmp_path, notes, options={"profile": "paper"})
    _run([Task("run", square, {"x": 2}, identity={"model": "abc"})], tmp_path, notes, options={"profile": "paper"})
    assert len(notes) == 2 and "options.profile" in notes[0] and "identity.model" in notes[1]
    rec = task_record(Task("run", square, {"x": 2, "marker_dir": "/a"}, volatile=("marker_dir",)))
    assert rec["function"] == "campaign_tasks.square" and rec["kwargs"] == {"x": 2}
    assert len(rec["code"]) == 64 and rec["version"]


def test_campaign_records_hold_their_parameters():
    """The issue's cases: online-rls --lambda and --seed, its quick/paper vehicle
    settings under one id, and mems-calibration --seed all change the record."""
    from sarins.online_rls.campaign import build_tasks

    def recs(tasks):
        return {t.id: task_record(t) for t in tasks}

    base, lam, seeded = (recs(build_tasks("quick", 0.8)), recs(build_tasks("quick", 0.5)),
                         recs(build_tasks("quick", 0.8, seed=5)))
    assert all(base[i] != lam[i] for i in base if i.startswith(("mc-", "veh-")))
    assert all(base[i] != seeded[i] for i in base)
    paper = recs(build_tasks("paper", 0.8))
    shared = [i for i in base if i.startswith("veh-") and i in paper]
    assert shared and all(base[i] != paper[i] for i in shared)
    from sarins.mems_calibration.recording import record_task

    a, b = (task_record(Task("dynamic", record_task, {"kind": "dynamic", "profile_name": "quick", "fmu_dir": "f",
                                                      "seed": s}, volatile=("fmu_dir",))) for s in (3, 5))
    assert a != b


def _corrupt(path: Path, how: str) -> None:
    data = path.read_bytes()
    if how == "truncated":
        path.write_bytes(data[: len(data) // 2])
    elif how == "empty":
        path.write_bytes(b"")
    elif how == "garbage":
        path.write_bytes(os.urandom(300))
    elif how == "pickled":
        np.save(path.open("wb"), np.array([{"a": 1}], dtype=object), allow_pickle=True)
    elif how == "missing-key":
        with zipfile.ZipFile(path) as zin:
            items = {i.filename: zin.read(i.filename) for i in zin.infolist() if i.filename != "y.npy"}
        with zipfile.ZipFile(path, "w") as zout:
            for name, blob in items.items():
                zout.writestr(name, blob)
    elif how == "bare-array":
        np.save(path.open("wb"), np.arange(3))
    elif how == "no-record":
        save_result(path, {"x": 2, "y": 4, "series": np.arange(5) * 2, "label": "run 2"})


@pytest.mark.parametrize("how", ["truncated", "empty", "garbage", "pickled", "missing-key", "bare-array", "no-record"])
def test_a_corrupt_result_is_recomputed_with_a_notice(tmp_path, how):
    notes = []
    tasks = [Task("run", square, {"x": 2})]
    _run(tasks, tmp_path, notes)
    _corrupt(tmp_path / "run.npz", how)
    if how != "no-record":  # unreadable: an error naming the file, never BadZipFile/EOFError/KeyError
        with pytest.raises(ValueError, match="run.npz"):
            load_result(tmp_path / "run.npz")
    out = _run(tasks, tmp_path, notes)
    assert out.computed == ["run"] and out["run"]["y"] == 4
    assert len(notes) == 1 and "recomputing" in notes[0] and str(tmp_path / "run.npz") in notes[0]
    assert _run(tasks, tmp_path, notes).computed == []


def test_a_non_finite_required_value_is_recomputed(tmp_path):
    notes = []
    task = Task("run", square, {"x": 2}, finite=("y",))
    _run([task], tmp_path, notes)
    import json

    from sarins.results import RECORD_KEY

    with np.load(tmp_path / "run.npz") as data:
        record = json.loads(str(data[RECORD_KEY]))
    save_result(tmp_path / "run.npz", {"x": 2, "y": np.nan, "series": np.arange(5), "label": "x"}, record)
    assert _run([task], tmp_path, notes)["run"]["y"] == 4
    assert "'y' is not finite" in notes[0]


def _python(code: str, **kw):
    return subprocess.Popen([sys.executable, "-c", textwrap.dedent(code)], cwd=str(ROOT),
                            env={**os.environ, "PYTHONPATH": f"{ROOT}{os.pathsep}{HERE}"}, **kw)


def _wait(predicate, timeout=60.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.05)
    return False


def test_kill_9_mid_write_leaves_no_partial_file(tmp_path):
    """Killed after the data is written but before the rename: the result
    name never appears; the next run removes the temporary and computes."""
    ready = tmp_path / "ready"
    proc = _python(f"""
        import os, time
        from pathlib import Path
        real = os.fsync
        def stall(fd):
            real(fd)
            Path({str(ready)!r}).touch()
            time.sleep(600)
        os.fsync = stall
        from campaign_tasks import square
        from sarins.campaign import Task, run_campaign
        run_campaign([Task("run", square, {{"x": 2}})], {str(tmp_path / "out")!r}, workers=1, progress=False)
    """)
    try:
        assert _wait(ready.exists)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
    finally:
        proc.kill()
    out = tmp_path / "out"
    assert not (out / "run.npz").exists() and list(out.glob(".run.npz.*"))
    assert _run([Task("run", square, {"x": 2})], out)["run"]["y"] == 4
    assert not list(out.glob(".run.npz.*"))


def test_a_second_campaign_on_the_same_folder_is_refused(tmp_path, capsys):
    held = tmp_path / "held"
    proc = _python(f"""
        import sys, time
        from sarins.campaign import exclusive
        with exclusive({str(tmp_path)!r}):
            open({str(held)!r}, "w").close()
            time.sleep(600)
    """)
    try:
        assert _wait(held.exists)
        with pytest.raises(OutputBusyError, match=f"pid {proc.pid}"):
            _run([Task("run", square, {"x": 2})], tmp_path)
        from sarins.cli import main

        assert main(["campaign", "online-rls", "--out", str(tmp_path), "--no-progress"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "in use by another campaign" in err
    finally:
        proc.kill()
        proc.wait()
    with exclusive(tmp_path):  # released with its holder
        with exclusive(tmp_path):  # re-entrant in one process
            pass


def _children(pid: int) -> set:
    """Pids whose parent is ``pid`` (a /proc scan, no psutil)."""
    out = set()
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                out.add(int(entry.name))
    return out


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def test_workers_die_with_a_killed_campaign(tmp_path):
    """SIGKILL to the campaign process alone: its workers and the resource
    tracker exit by themselves."""
    proc = _python(f"""
        from campaign_tasks import sleeper
        from sarins.campaign import Task, run_campaign
        run_campaign([Task(f"s{{i}}", sleeper, {{"x": i}}) for i in range(4)], {str(tmp_path)!r}, workers=2,
                     progress=False)
    """)
    try:
        assert _wait(lambda: len(_children(proc.pid)) >= 3)  # two workers + the resource tracker
        kids = _children(proc.pid)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        assert _wait(lambda: not any(_alive(k) for k in kids), timeout=20), [k for k in kids if _alive(k)]
    finally:
        proc.kill()


def test_workers_run_single_threaded_kernels(tmp_path):
    before = os.environ.get("SARINS_THREADS")
    out = run_campaign([Task(f"e{i}", environment) for i in range(2)], tmp_path, workers=2, progress=False)
    for result in out.values():
        assert result["threads_env"] == "1" and result["omp_env"] == "1" and result["core_threads"] == 1
        assert result["pid"] != os.getpid()
    assert os.environ.get("SARINS_THREADS") == before  # the campaign process keeps its own setting


def test_artifacts_are_built_in_a_temporary_folder(tmp_path):
    """A build that dies half-way leaves no file under its final name; a
    finished build is reused until its key changes."""
    calls = []

    def good(folder):
        calls.append(folder)
        for name in ("A.fmu", "B.fmu"):
            (Path(folder) / name).write_text(f"{name} v{len(calls)}")

    def dies(folder):
        (Path(folder) / "A.fmu").write_text("half")
        raise KeyboardInterrupt

    dest = tmp_path / "fmus"
    with pytest.raises(KeyboardInterrupt):
        build_artifacts(dest, ["A.fmu", "B.fmu"], dies, "k1")
    assert not list(dest.glob("*.fmu")) and not list(tmp_path.glob(".build-*"))
    build_artifacts(dest, ["A.fmu", "B.fmu"], good, "k1")
    build_artifacts(dest, ["A.fmu", "B.fmu"], good, "k1")
    assert len(calls) == 1 and (dest / "A.fmu").read_text() == "A.fmu v1"
    assert Path(calls[0]).parent == tmp_path and not Path(calls[0]).exists()
    (dest / "B.fmu").unlink()
    build_artifacts(dest, ["A.fmu", "B.fmu"], good, "k1")
    build_artifacts(dest, ["A.fmu", "B.fmu"], good, "k2")
    assert len(calls) == 3 and (dest / "B.fmu").read_text() == "B.fmu v3"


@pytest.mark.parametrize("signum,status", [(signal.SIGTERM, 143),
                                           pytest.param(signal.SIGINT, 130, marks=pytest.mark.slow)])
def test_a_signalled_campaign_stops_cleanly(tmp_path, signum, status):
    """SIGTERM / Ctrl-C to ``sarins campaign``: one line, exit 143 / 130, its
    workers gone at once (not after their tasks), finished results kept."""
    proc = _python(f"""
        import sys
        import sarins.online_rls.campaign as camp
        from campaign_tasks import sleeper, square
        from sarins.campaign import Task
        from sarins.cli import main
        camp.build_tasks = lambda *a, **k: [Task("quick", square, {{"x": 1}})] + [
            Task(f"s{{i}}", sleeper, {{"x": i, "seconds": 900.0}}) for i in range(4)]
        sys.exit(main(["campaign", "online-rls", "--out", {str(tmp_path)!r}, "--workers", "2", "--no-progress"]))
    """, stderr=subprocess.PIPE, text=True)
    try:
        assert _wait(lambda: (tmp_path / "runs" / "quick.npz").exists() and len(_children(proc.pid)) >= 3, 300)
        kids = _children(proc.pid)
        os.kill(proc.pid, signum)
        # the tasks sleep 900 s: ending within the timeout means the workers were stopped, not waited for
        # (no wall-clock assertion: the margin is 900 s against 120 s, whatever the load)
        _, err = proc.communicate(timeout=120)
    finally:
        proc.kill()
    assert proc.returncode == status, err
    assert err.strip().splitlines() == [f"sarins campaign online-rls: {'terminated' if status == 143 else 'interrupted'}"]
    assert _wait(lambda: not any(_alive(k) for k in kids), timeout=10)
    assert load_result(tmp_path / "runs" / "quick.npz")["y"] == 1


def _ignore_sigint():
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # as a background job of a non-interactive shell starts


def test_a_campaign_started_with_sigint_ignored_still_stops_on_sigint(tmp_path):
    """A campaign that inherited SIGINT ignored (``cmd &`` in a script) still
    stops on SIGINT with 130 and one line: ``sarins`` installs its own
    handler whatever the inherited disposition (issue 21)."""
    proc = _python(f"""
        import signal, sys
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN  # inherited, as the test means
        import sarins.online_rls.campaign as camp
        from campaign_tasks import sleeper, square
        from sarins.campaign import Task
        from sarins.cli import main
        camp.build_tasks = lambda *a, **k: [Task("quick", square, {{"x": 1}})] + [
            Task(f"s{{i}}", sleeper, {{"x": i, "seconds": 600.0}}) for i in range(4)]
        sys.exit(main(["campaign", "online-rls", "--out", {str(tmp_path)!r}, "--workers", "2", "--no-progress"]))
    """, stderr=subprocess.PIPE, text=True, preexec_fn=_ignore_sigint)
    try:
        # the campaign is running (a result stored, its two workers busy): SIGINT now must stop it
        assert _wait(lambda: (tmp_path / "runs" / "quick.npz").exists() and len(_children(proc.pid)) >= 3, 300)
        kids = _children(proc.pid)
        os.kill(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=120)  # on the old code it never ends: the timeout fails the test
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert err.strip().splitlines() == ["sarins campaign online-rls: interrupted"]
    assert _wait(lambda: not any(_alive(k) for k in kids), timeout=30)


# ---- a stored result whose record is intact but one of whose arrays is not what the run gives (issue 21)
def _square_schema(kwargs):
    from sarins.campaign import Field

    return {"x": Field((), "iu"), "y": Field((), "iu"), "series": Field((5,), "iu"), "label": Field((), "U")}


def _rewrite(path, edit):
    """Rewrite the stored arrays with ``edit`` applied, keeping every other member as it was
    (record, its hash, key list and manifest): the record stays intact."""
    with np.load(path) as data:
        members = {k: data[k] for k in data.files}
    edit(members)
    with open(path, "wb") as fh:
        np.savez(fh, **members)


@pytest.mark.parametrize("name, edit, reason", [
    ("series cut to 2", lambda m: m.update(series=m["series"][:2]), "'series' has another shape than written"),
    ("series as float", lambda m: m.update(series=m["series"].astype(float)), "'series' has another dtype"),
    ("y rewritten", lambda m: m.update(y=np.array(5)), "'y' has another content than written"),
])
def test_an_array_changed_under_an_intact_record_is_recomputed(tmp_path, name, edit, reason):
    notes = []
    tasks = [Task("run", square, {"x": 2})]
    _run(tasks, tmp_path, notes)
    _rewrite(tmp_path / "run.npz", edit)
    out = _run(tasks, tmp_path, notes)
    assert out.computed == ["run"] and out["run"]["series"].shape == (5,) and out["run"]["y"] == 4
    assert len(notes) == 1 and reason in notes[0] and str(tmp_path / "run.npz") in notes[0], notes


@pytest.mark.parametrize("name, edit, reason", [
    ("series cut to 2", lambda r: r.update(series=r["series"][:2]), "'series' has shape (2,), the task gives (5,)"),
    ("label as a number", lambda r: r.update(label=3.0), "'label' is float64, the task gives kind 'U'"),
    ("extra key", lambda r: r.update(extra=1.0), "unexpected extra"),
    ("y not finite", lambda r: r.update(y=np.nan), "'y' is float64"),
])
def test_a_result_that_does_not_match_the_declared_schema_is_recomputed(tmp_path, name, edit, reason):
    """Even rewritten whole (record, manifest and all consistent), a result whose fields are not what
    the task's declared schema says the run produces is recomputed with the one-line notice."""
    notes = []
    task = Task("run", square, {"x": 2}, schema=_square_schema({"x": 2}))
    _run([task], tmp_path, notes)
    from sarins.results import _read

    result, record = _read(tmp_path / "run.npz")
    edit(result)
    save_result(tmp_path / "run.npz", result, record)
    out = _run([task], tmp_path, notes)
    assert out.computed == ["run"] and out["run"]["series"].shape == (5,)
    assert len(notes) == 1 and reason in notes[0], notes


def test_a_fresh_result_outside_its_declared_schema_fails_the_task(tmp_path):
    from sarins.campaign import Field, TaskFailed

    schema = {**_square_schema({}), "series": Field((6,), "iu")}
    with pytest.raises(TaskFailed, match="declared schema .*'series' has shape"):
        _run([Task("run", square, {"x": 2}, schema=schema)], tmp_path)
    assert not (tmp_path / "run.npz").exists()


def test_the_online_rls_stop_schema_is_what_the_run_gives():
    """The declared schema of the stop task matches a real (short) run, and the quick profile's
    stop tasks declare the 1800-sample curves their 1800 s stops give."""
    from sarins.campaign import check_fields
    from sarins.online_rls.campaign import build_tasks, stop_schema
    from sarins_fmu.experiments.online_rls import simulate_stop

    check_fields(simulate_stop(imu="premise", seed=0, temperature=5.0, duration=120.0), stop_schema({"duration": 120.0}))
    stops = [t for t in build_tasks("quick") if t.id.startswith("stop-")]
    assert stops and all(t.schema["time"].shape == (1800,) for t in stops)
