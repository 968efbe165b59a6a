"""Fault injection through the ``sarins`` command (issue 21, the CLI / log / model / campaign cases).

Each case runs ``python -m sarins ...`` (or, for the campaign runner, a small
``python -c`` program) in a subprocess with a timeout, and its outcome is
classified:

clean
    what the case expects: exit 2 with one stderr line ``sarins <command>:
    error: ...`` naming the option or file (after any ``sarins: warning:``
    lines); or exit 0 with a warning naming the fault, for input a real
    sensor can also write (issue 28: a check that cannot tell a MEMS log from
    a mislabelled one must not refuse); or, for a corrupt stored result,
    exit 0 with the one-line ``recomputing`` notice; or 130 after SIGINT.
wrong status
    another non-zero status, or a message that is not one line with
    ``error:`` and the option or file;
silently accepted
    exit 0 (or the work started and ran into the timeout) on input that had
    to be refused;
hang
    no exit within the timeout where the process should have stopped;
crash
    a traceback, an ``internal error`` or death by a signal.

The cases are bounded (about 35, each with its own timeout) and the test is
marked slow.  Run as a script, it prints the table for any checkout
(``python tests/test_fault_injection_cli.py --root /work/main``), which is how
the before/after table of the issue was measured.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent
OUTCOMES = ("clean", "wrong status", "silently accepted", "hang", "crash")


@dataclass(frozen=True)
class Case:
    category: str
    name: str
    argv: list  # after 'python -m sarins', or ['-c', code] for a python program
    needle: str = ""  # text the one error line must hold ({placeholders} filled in)
    expect: str = "refused"  # 'refused' (2), 'warned' (0 + warnings), 'notice' (0 + one 'recomputing' line), 'sigint'
    timeout: float = 60.0
    on_timeout: str = "silently accepted"  # a timeout means the work ran (the option ignored) or 'hang'
    setup: object = None  # callable(root: Path) run before the case
    env: dict = field(default_factory=dict)


# ---------------------------------------------------------------- inputs
def _static_log(path: Path, *, gyro_scale=1.0, turn=0.0, n=900) -> Path:
    """A 1 Hz static log (nav-rlg-like noise), optionally turning about z for its first 120 s."""
    rng = np.random.default_rng(1)
    time_s = np.arange(1.0, n + 1.0)
    lat = np.radians(45.0)
    earth = 7.292115e-5 * np.array([0.0, np.cos(lat), np.sin(lat)])
    gyro = earth + 1e-7 * rng.standard_normal((n, 3))
    gyro[:120, 2] += turn
    accel = np.array([0.0, 0.0, 9.80665]) + 1e-4 * rng.standard_normal((n, 3))
    cols = {"time_s": time_s}
    cols.update({f"dtheta_{a}_rad": gyro[:, i] * gyro_scale for i, a in enumerate("xyz")})
    cols.update({f"dv_{a}_mps": accel[:, i] for i, a in enumerate("xyz")})
    if path.suffix == ".npz":
        np.savez(path, meta=np.array(json.dumps({"lat_deg": "45.0"})), **cols)
        return path
    lines = ["# sarins-imu-log 1", "# lat_deg: 45.0", ",".join(cols)]
    lines += [",".join(repr(float(cols[c][k])) for c in cols) for k in range(n)]
    path.write_text("\n".join(lines) + "\n")
    return path


def _edit_lines(path: Path, edit) -> Path:
    lines = path.read_text().splitlines()
    path.write_text("\n".join(edit(lines)) + "\n")
    return path


def _setup_logs(root: Path) -> None:
    good = _static_log(root / "good.csv")
    _static_log(root / "good.npz")
    _edit_lines(_static_log(root / "blank.csv"), lambda ls: ls[:20] + [""] + ls[20:])
    _edit_lines(_static_log(root / "longmeta.csv"), lambda ls: ls[:2] + ["# note: " + "x" * 1_000_000] + ls[2:])
    _edit_lines(_static_log(root / "offset.csv"), lambda ls: ls[:3] + [
        repr(float(r.split(",")[0]) - 1e6) + r[r.index(","):] for r in ls[3:]])
    _edit_lines(_static_log(root / "unknown.csv"), lambda ls: ls[:2] + [ls[2] + ",heading_x"] + [
        r + ",0" for r in ls[3:]])
    _edit_lines(_static_log(root / "comment.csv"), lambda ls: ls[:30] + ["# note: here"] + ls[30:])
    text = good.read_text().splitlines()
    (root / "mixed.csv").write_bytes(("\r\n".join(text[:30]) + "\r\n" + "\n".join(text[30:]) + "\n").encode())
    with np.load(root / "good.npz") as z:
        cols = {k: z[k] for k in z.files}
    cols["dtheta_x_rad"] = cols["dtheta_x_rad"].astype(str)
    np.savez(root / "strings.npz", **cols)
    _static_log(root / "deg_moving.csv", gyro_scale=np.degrees(1.0), turn=0.2)


def _setup_identify(root: Path) -> None:
    for name, value in (("huge", "1e308"), ("tiny", "-1e308"), ("far", "0.1")):
        (root / f"{name}.csv").write_text(f"lat_error_deg\n0.01\n{value}\n")
    (root / "errors.csv").write_text("lat_error_deg\n0.01\n0.02\n")


CUT_RESULT = textwrap.dedent("""
    import sys
    import numpy as np
    sys.path[:0] = [{here!r}]
    from campaign_tasks import square
    from sarins.campaign import Task, run_campaign, result_path
    out = {out!r}
    task = [Task("run", square, {{"x": 3}})]
    run_campaign(task, out, workers=1, progress=False)
    path = result_path(out, "run")
    with np.load(path) as z:
        members = {{k: z[k] for k in z.files}}
    members["series"] = members["series"][:2]  # record intact, one array cut
    with open(path, "wb") as fh:
        np.savez(fh, **members)
    run_campaign(task, out, workers=1, progress=False)  # reused as it is, or recomputed with a notice
""")

SIGINT_CAMPAIGN = textwrap.dedent("""
    import os, signal, sys, threading
    sys.path[:0] = [{here!r}]
    assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    import sarins.online_rls.campaign as camp
    from campaign_tasks import sleeper, square
    from sarins.campaign import Task
    from sarins.cli import main
    camp.build_tasks = lambda *a, **k: [Task("quick", square, {{"x": 1}})] + [
        Task(f"s{{i}}", sleeper, {{"x": i, "seconds": 600.0}}) for i in range(2)]
    # SIGINT to ourselves once the campaign is running (its first result stored)
    def poke():
        import time
        while not os.path.exists(os.path.join({out!r}, "runs", "quick.npz")):
            time.sleep(0.05)
        time.sleep(1.0)
        os.kill(os.getpid(), signal.SIGINT)
    threading.Thread(target=poke, daemon=True).start()
    sys.exit(main(["campaign", "online-rls", "--out", {out!r}, "--workers", "2", "--no-progress"]))
""")


def cases() -> list[Case]:
    hot = "{model}"
    quick = ["--align-hours", "0.2", "--nav-hours", "0.01"]
    out = []
    add = out.append
    # 1. options ignored without a word
    add(Case("options", "allan --log with --rate-hz", ["allan", "--log", "{root}/good.csv", "--rate-hz", "7"],
             "--rate-hz", setup=_setup_logs))
    add(Case("options", "allan --log with --hours", ["allan", "--log", "{root}/good.csv", "--hours", "2"], "--hours", setup=_setup_logs))
    add(Case("options", "allan --log with --seed", ["allan", "--log", "{root}/good.csv", "--seed", "5"], "--seed", setup=_setup_logs))
    add(Case("options", "navigate --correction-from-hours alone", ["navigate", *quick, "--correction-from-hours",
                                                                   "0.005", "--json"], "--correction-from-hours"))
    add(Case("options", "demo --model with --model-file", ["demo", "--model", "cold", "--model-file", hot,
                                                         "--fmu-dir", "{root}/fmus", "--no-progress"], "--model"))
    add(Case("options", "identify predict --local-lat-deg unused", ["identify", "predict", "--model", hot, "--data",
                                                                    "{root}/errors.csv", "--local-lat-deg", "30"],
             "--local-lat-deg", setup=_setup_identify))
    add(Case("options", "campaign --workers with --scheduler", ["campaign", "online-rls", "--out", "{root}/c1",
                                                               "--workers", "2", "--scheduler", "tcp://127.0.0.1:9",
                                                               "--no-progress"], "--workers"))
    add(Case("options", "mems --rnn-steps without a recurrent model",
             ["campaign", "mems-calibration", "--out", "{root}/c2", "--models", "traditional", "--rnn-steps", "5",
              "--no-progress"], "--rnn-steps"))
    add(Case("options", "mems --ablation-models without --ablation",
             ["campaign", "mems-calibration", "--out", "{root}/c3", "--models", "traditional", "--ablation-models",
              "rbf", "--no-progress"], "--ablation-models"))
    add(Case("options", "axial-rbf --sweep-only with --engine",
             ["campaign", "axial-rbf", "--out", "{root}/c4", "--sweep", "quick", "--sweep-only", "--engine", "cosim",
              "--no-progress"], "--engine"))
    # 4. build-fmus message
    add(Case("options", "build-fmus --only IMUCompensator without a model",
             ["build-fmus", "--out", "{root}/fmus2", "--only", "IMUCompensator"], "IMUCompensator"))
    # 2. identify predict outside the training range
    for name in ("huge", "tiny", "far"):
        add(Case("model range", f"identify predict {name}", ["identify", "predict", "--model", hot, "--data",
                                                             f"{{root}}/{name}.csv"], f"{{root}}/{name}.csv",
                 setup=_setup_identify))
    # 3. log grammar and units, through replay and allan
    logs = [("blank line", "blank.csv", "line 21"), ("1 MB metadata line", "longmeta.csv", "line 3"),
            ("time offset -1e6 s", "offset.csv", "line 4"), ("unknown column", "unknown.csv", "heading_x"),
            ("comment among samples", "comment.csv", "line 31"), ("mixed CRLF/LF", "mixed.csv", "line 31"),
            ("string NPZ column", "strings.npz", "dtheta_x_rad"),
            ("degrees, moving log", "deg_moving.csv", "degrees")]
    for name, file, needle in logs:
        add(Case("log grammar", f"replay: {name}", ["replay", f"{{root}}/{file}", "--align-hours", "0.1", "--json"],
                 needle, setup=_setup_logs))
        add(Case("log grammar", f"allan --log: {name}", ["allan", "--log", f"{{root}}/{file}", "--json"], needle,
                 setup=_setup_logs, expect="warned" if file == "deg_moving.csv" else "refused"))
    # 5. campaigns
    add(Case("campaign", "stored result with an array cut under an intact record",
             ["-c", CUT_RESULT.format(here=str(HERE), out="{root}/c5")], "'series' has another shape",
             expect="notice"))
    add(Case("campaign", "SIGINT with SIGINT inherited ignored", ["-c", SIGINT_CAMPAIGN.format(
        here=str(HERE), out="{root}/c6")], "interrupted", expect="sigint", timeout=120.0, on_timeout="hang"))
    return out


# ---------------------------------------------------------------- running
def _ignore_sigint():
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def run_case(case: Case, root: Path, code_root: Path) -> tuple[str, str]:
    """(outcome, detail) of one case, its code from ``code_root``."""
    from sarins_fmu.identify.axial import default_model_path

    if case.setup is not None:
        case.setup(root)
    fill = {"{root}": str(root), "{model}": str(default_model_path("hot"))}

    def filled(text: str) -> str:
        for key, value in fill.items():
            text = text.replace(key, value)
        return text

    argv = [filled(a) for a in case.argv]
    needle = filled(case.needle)
    cmd = [sys.executable, *argv] if argv[0] == "-c" else [sys.executable, "-m", "sarins", *argv]
    env = {**os.environ, "PYTHONPATH": f"{code_root}{os.pathsep}{HERE}", "SARINS_DEBUG": "", **case.env}
    proc = subprocess.Popen(cmd, cwd=str(root), env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True, preexec_fn=_ignore_sigint if case.expect == "sigint" else None)
    try:
        _, err = proc.communicate(timeout=case.timeout)
    except subprocess.TimeoutExpired:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        return case.on_timeout, f"no exit within {case.timeout:g} s"
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)  # workers of the case
    rc, lines = proc.returncode, err.strip().splitlines()
    if "Traceback" in err or rc < 0 or "internal error" in err:
        return "crash", f"exit {rc}: {err.strip()[-200:]}"
    warned = [ln for ln in lines if ln.startswith("sarins: warning: ")]
    if case.expect == "warned":
        ok = rc == 0 and any(needle in ln for ln in warned) and len(warned) == len(lines)
        return ("clean" if ok else "silently accepted" if rc == 0 else "wrong status"), \
            f"exit {rc}: {' | '.join(lines)[:300]}"
    if case.expect == "refused":
        if rc == 0:
            return "silently accepted", "exit 0"
        errors = [ln for ln in lines if ln not in warned]
        ok = rc == 2 and len(errors) == 1 and ": error: " in errors[0] and needle in errors[0]
        return ("clean" if ok else "wrong status"), f"exit {rc}: {' | '.join(lines)[:300]}"
    if case.expect == "notice":
        notes = [ln for ln in lines if "recomputing" in ln]
        if rc != 0:
            return "wrong status", f"exit {rc}: {' | '.join(lines)[:300]}"
        ok = len(lines) == 1 and len(notes) == 1 and needle in notes[0]
        return ("clean" if ok else "silently accepted"), f"exit 0: {' | '.join(lines)[:300]}"
    ok = rc == 130 and lines == ["sarins campaign online-rls: interrupted"]
    return ("clean" if ok else "wrong status"), f"exit {rc}: {' | '.join(lines)[:300]}"


def table(results: list[tuple[Case, str, str]]) -> str:
    rows = ["category | cases | " + " | ".join(OUTCOMES), "|".join(["---"] * (2 + len(OUTCOMES)))]
    for category in dict.fromkeys(c.category for c, _, _ in results):
        got = [o for c, o, _ in results if c.category == category]
        rows.append(f"{category} | {len(got)} | " + " | ".join(str(got.count(o)) for o in OUTCOMES))
    got = [o for _, o, _ in results]
    rows.append(f"all | {len(got)} | " + " | ".join(str(got.count(o)) for o in OUTCOMES))
    return "\n".join(rows)


CASES = cases()


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES, ids=[f"{c.category}: {c.name}" for c in CASES])
def test_fault_injection_case_is_clean(case, tmp_path):
    outcome, detail = run_case(case, tmp_path, HERE.parent)
    assert outcome == "clean", f"{outcome}: {detail}"


def main() -> None:
    parser = argparse.ArgumentParser(description="run the fault-injection cases against a checkout; print the table")
    parser.add_argument("--root", type=Path, default=HERE.parent, help="checkout whose code runs (default: this one)")
    parser.add_argument("--verbose", action="store_true")
    args = parser.parse_args()
    import tempfile

    results = []
    t0 = time.monotonic()
    for case in CASES:
        with tempfile.TemporaryDirectory() as tmp:
            outcome, detail = run_case(case, Path(tmp), args.root.resolve())
        results.append((case, outcome, detail))
        if args.verbose:
            print(f"{outcome:18s} {case.category}: {case.name}: {detail}", flush=True)
    print(table(results))
    print(f"({time.monotonic() - t0:.0f} s)")


if __name__ == "__main__":
    main()
