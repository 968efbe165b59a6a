"""Every bad input, a clear error (issue 14 part 2): each CLI command over
non-finite, huge, tiny, zero and negative numbers, bad seeds, huge sizes,
empty/garbage/truncated/deeply nested files, a ``null`` site latitude in a
model file and missing optional dependencies.  Each must exit 2 with one
line that starts with the command's name and names the option or file --
never a traceback, never exit 0 with NaN.  The table runs in process
(``sarins.cli.main``); nothing in it reaches the expensive work.  (``cosim``
has its own table with the master.)"""

import json
import os
import sys

import numpy as np
import pytest

from sarins.cli import main
from sarins_fmu.identify.axial import default_model_path

FLOATS_BAD = ["nan", "inf", "-inf", "1e308", "-1e308"]
SEEDS_BAD = ["-1", str(2**31), "4294967299", "1.5", "abc", "1e3"]


def _files(root):
    """Bad input files by kind, written under ``root``."""
    good = json.loads(default_model_path("hot").read_text())
    null_lat = json.loads(json.dumps(good))
    null_lat["meta"]["metadata"]["local_lat_deg"] = None
    text_lat = json.loads(json.dumps(good))
    text_lat["meta"]["metadata"]["local_lat_deg"] = "north"
    blob = json.dumps(good)
    files = {
        "empty": "",
        "garbage": os.urandom(512),
        "truncated": blob[: len(blob) // 2],
        "nested": "[" * 200_000 + "]" * 200_000,
        "nested-meta": blob.replace('"metadata": {', '"metadata": {"x": ' + "[" * 50_000 + "]" * 50_000 + ', ', 1),
        "null-lat": json.dumps(null_lat),
        "text-lat": json.dumps(text_lat),
        "not-object": "[1, 2, 3]",
    }
    paths = {}
    for kind, content in files.items():
        path = root / f"{kind}.json"
        path.write_bytes(content if isinstance(content, bytes) else content.encode())
        paths[kind] = path
    paths["missing"] = root / "no-such-file.json"
    paths["folder"] = root
    csvs = {"empty-csv": "", "garbage-csv": os.urandom(256), "header-only": "lat_error_deg,drift_dph\n",
            "ragged": "lat_error_deg,drift_dph\n0.01,0.001\n0.02\n", "nan-csv": "lat_error_deg,drift_dph\nnan,1\n2,3\n",
            "inf-csv": "lat_error_deg,drift_dph\n1e400,1\n2,3\n", "text-csv": "lat_error_deg,drift_dph\nabc,1\n2,3\n"}
    for kind, content in csvs.items():
        path = root / f"{kind}.csv"
        path.write_bytes(content if isinstance(content, bytes) else content.encode())
        paths[kind] = path
    (root / "a-file").write_text("x")
    paths["a-file"] = root / "a-file"
    return paths


def _cases():
    """(id, argv with {file} placeholders, the text the one-line message must hold)."""
    cases = []
    run_opts = [("--lat-deg", FLOATS_BAD + ["90", "-95"]),
                ("--align-hours", FLOATS_BAD + ["-1", "0", "1e-308", "1e-12"]),
                ("--nav-hours", FLOATS_BAD + ["-1", "0", "1e-308", "1e-12", "1e6"]),
                ("--axial-drift-dph", FLOATS_BAD),
                ("--seed", SEEDS_BAD)]
    for cmd in ("navigate", "demo"):
        for opt, values in run_opts:
            cases += [(f"{cmd} {opt} {v}", [cmd, opt, v], opt) for v in values]
        cases += [(f"{cmd} --imu bogus", [cmd, "--imu", "bogus"], "--imu")]
    for opt, values in (("--correction-dph", FLOATS_BAD), ("--correction-from-hours", FLOATS_BAD + ["-1"])):
        cases += [(f"navigate {opt} {v}", ["navigate", opt, v, "--json"], opt) for v in values]
    cases += [(f"demo --identify-hours {v}", ["demo", "--identify-hours", v], "--identify-hours")
              for v in FLOATS_BAD + ["-1", "0", "1e-308", "1"]]
    for kind in ("empty", "garbage", "truncated", "nested", "nested-meta", "null-lat", "text-lat", "not-object",
                 "missing", "folder"):
        cases.append((f"demo --model-file {kind}", ["demo", "--model-file", "{%s}" % kind], "{%s}" % kind))
        cases.append((f"identify predict --model {kind}",
                      ["identify", "predict", "--model", "{%s}" % kind, "--data", "{header-only}"], "{%s}" % kind))
        cases.append((f"build-fmus --compensator {kind}",
                      ["build-fmus", "--out", "{tmp}/fmus", "--compensator", "{%s}" % kind], "{%s}" % kind))
    cases.append(("demo --fmu-dir a-file", ["demo", "--fmu-dir", "{a-file}"], "--fmu-dir"))
    train = ["identify", "train", "--data", "{nan-csv}", "--out", "{tmp}/m.json"]
    for kind in ("empty-csv", "garbage-csv", "header-only", "ragged", "nan-csv", "inf-csv", "text-csv", "missing",
                 "folder"):
        cases.append((f"identify train --data {kind}", ["identify", "train", "--data", "{%s}" % kind, "--out",
                                                         "{tmp}/m.json"], "{%s}" % kind))
        cases.append((f"identify predict --data {kind}", ["identify", "predict", "--model", str(default_model_path("hot")),
                                                           "--data", "{%s}" % kind], "{%s}" % kind))
    good_csv = ["identify", "train", "--data", "{good-csv}", "--out", "{tmp}/m.json"]
    for opt, values in (("--spread", FLOATS_BAD + ["0", "-1", "1e-308"]), ("--goal", FLOATS_BAD[:4] + ["-1"]),
                        ("--max-neurons", ["0", "-1", "1000000000", "1.5"]),
                        ("--local-lat-deg", FLOATS_BAD + ["91"])):
        cases += [(f"identify train {opt} {v}", good_csv + [opt, v], opt) for v in values]
    cases += [(f"identify predict --local-lat-deg {v}", ["identify", "predict", "--model", str(default_model_path("hot")),
                                                          "--data", "{good-csv}", "--local-lat-deg", v], "--local-lat-deg")
              for v in ("nan", "inf", "1e308", "-91")]
    cases.append(("identify train --out in a missing folder", good_csv[:4] + ["--out", "{tmp}/none/m.json"], "none"))
    del train
    cases += [("build-fmus --only bogus", ["build-fmus", "--out", "{tmp}/fmus", "--only", "Bogus"], "Bogus"),
              ("build-fmus --out a-file", ["build-fmus", "--out", "{a-file}"], "a-file")]
    for camp in ("axial-rbf", "online-rls", "mems-calibration"):
        base = ["campaign", camp, "--out", "{tmp}/c", "--no-progress"]
        cases += [(f"{camp} --seed {v}", base + ["--seed", v], "--seed") for v in SEEDS_BAD]
        cases += [(f"{camp} --workers {v}", base + ["--workers", v], "--workers") for v in ("0", "-1", "10**9", "1e9")]
        cases += [(f"{camp} --out a-file", ["campaign", camp, "--out", "{a-file}"], "--out"),
                  (f"{camp} --profile bogus", base + ["--profile", "bogus"], "--profile")]
    cases += [(f"online-rls --lambda {v}", ["campaign", "online-rls", "--out", "{tmp}/c", "--lambda", v], "--lambda")
              for v in FLOATS_BAD + ["0", "-1", "1.5", "1e-308"]]
    cases.append(("online-rls --seed near 2**31", ["campaign", "online-rls", "--out", "{tmp}/c", "--seed",
                                                   str(2**31 - 2)], "--seed"))
    mems = ["campaign", "mems-calibration", "--out", "{tmp}/c"]
    cases += [("mems --models bogus", mems + ["--models", "bogus"], "bogus"),
              ("mems --models empty", mems + ["--models", ","], "model"),
              ("mems --device tpu", mems + ["--device", "tpu"], "--device"),
              ("mems --device cuda:99", mems + ["--device", "cuda:99"], "--device"),
              ("mems --rnn-steps 0", mems + ["--rnn-steps", "0"], "--rnn-steps"),
              ("mems --rnn-steps huge", mems + ["--rnn-steps", str(10**12)], "--rnn-steps"),
              ("mems --grnn-patterns -1", mems + ["--grnn-patterns", "-1"], "--grnn-patterns"),
              ("mems --rbf-samples huge", mems + ["--rbf-samples", str(10**12)], "--rbf-samples"),
              ("mems --ablation bogus", mems + ["--ablation", "bogus"], "bogus"),
              ("mems --ablation-models traditional", mems + ["--ablation", "all", "--ablation-models",
                                                             "traditional"], "traditional"),
              ("mems --ablation-models bogus", mems + ["--ablation", "every", "--ablation-models", "x"], "x")]
    cases.append(("axial-rbf --engine bogus", ["campaign", "axial-rbf", "--engine", "bogus"], "--engine"))
    return cases


CASES = _cases()


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    root = tmp_path_factory.mktemp("bad")
    paths = _files(root)
    good = root / "good.csv"
    rng = np.random.default_rng(0)
    x = rng.uniform(-0.02, 0.02, 12)
    good.write_text("lat_error_deg,drift_dph\n" + "".join(f"{float(a)!r},{float(a) / 7!r}\n" for a in x))
    paths["good-csv"] = good
    paths["tmp"] = root
    return {k: str(v) for k, v in paths.items()}


def run_cli(argv, capsys):
    """Exit status, stdout, stderr of ``sarins argv`` in process."""
    try:
        rc = main(argv)
    except SystemExit as exc:  # argparse
        rc = exc.code
    out, err = capsys.readouterr()
    return rc, out, err


def _check(rc, out, err, command, needle):
    assert "Traceback" not in err + out
    assert rc == 2, f"exit {rc}: {err or out}"
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"sarins {command}"), lines[0]
    assert needle in lines[0], f"{needle!r} not in {lines[0]!r}"


@pytest.mark.parametrize("case_id,argv,needle", CASES, ids=[c[0] for c in CASES])
def test_bad_input_is_one_clean_line_with_exit_2(case_id, argv, needle, files, capsys):
    argv = [a.format(**files) for a in argv]
    needle = needle.format(**files)
    rc, out, err = run_cli(argv, capsys)
    command = argv[0] if argv[0] != "campaign" else f"campaign {argv[1]}"
    if command == "identify":
        command = f"identify {argv[1]}"
    _check(rc, out, err, command, needle)


@pytest.mark.parametrize("campaign", ["axial-rbf", "online-rls", "mems-calibration"])
def test_scheduler_without_dask_is_a_clean_error(campaign, monkeypatch, tmp_path, capsys):
    for name in ("dask", "distributed", "dask.distributed"):
        monkeypatch.setitem(sys.modules, name, None)
    rc, out, err = run_cli(["campaign", campaign, "--out", str(tmp_path), "--scheduler", "tcp://127.0.0.1:1",
                            "--no-progress"], capsys)
    _check(rc, out, err, f"campaign {campaign}", "--scheduler")
    assert "pip install" in err


def test_a_missing_build_dependency_is_a_clean_error(monkeypatch, tmp_path, capsys):
    monkeypatch.setitem(sys.modules, "pythonfmu", None)
    for name in [m for m in sys.modules if m.startswith("pythonfmu.")]:
        monkeypatch.setitem(sys.modules, name, None)
    rc, out, err = run_cli(["build-fmus", "--out", str(tmp_path), "--only", "Turntable"], capsys)
    _check(rc, out, err, "build-fmus", "pythonfmu")


@pytest.mark.parametrize("target,argv", [
    ("sarins.demo.run_demo", ["demo"]),
    ("sarins.mems_calibration.campaign.run_mems_calibration", ["campaign", "mems-calibration"]),
])
def test_a_failed_fmu_call_is_exit_1_with_one_line(target, argv, monkeypatch, tmp_path, capsys):
    from orchestration.errors import FMUCallError

    def fail(*args, **kwargs):
        raise FMUCallError("imu", "fmi2DoStep", 3, 12.0, ["line one", "line two"], "IMUThermal.fmu")

    monkeypatch.setattr(target, fail)
    extra = ["--fmu-dir", str(tmp_path / "f")] if argv == ["demo"] else ["--out", str(tmp_path / "c")]
    if argv != ["demo"]:
        extra += ["--models", "traditional"]  # no torch import
    rc, out, err = run_cli(argv + extra + ["--no-progress"], capsys)
    assert rc == 1 and "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"sarins {' '.join(argv)}: failed:") and "fmi2DoStep" in lines[0]


def test_a_failed_campaign_task_is_exit_1_with_one_line(monkeypatch, tmp_path, capsys):
    import sarins.online_rls.campaign as camp
    from campaign_tasks import fail
    from sarins.campaign import Task

    monkeypatch.setattr(camp, "build_tasks", lambda *a, **k: [Task("bad", fail, {"x": 7})])
    rc, out, err = run_cli(["campaign", "online-rls", "--out", str(tmp_path), "--workers", "1", "--no-progress"],
                           capsys)
    assert rc == 1 and err.count("\n") == 1 and "task bad failed: ValueError: bad input 7" in err


def test_navigate_json_is_strict_json(capsys):
    """A short valid run prints finite, strictly valid JSON (no bare NaN)."""
    rc, out, err = run_cli(["navigate", "--imu", "ideal", "--align-hours", "0.17", "--nav-hours", "0.01", "--json"],
                           capsys)
    assert rc == 0, err

    def refuse(name):
        raise ValueError(f"bare {name} in the JSON output")

    summary = json.loads(out, parse_constant=refuse)
    assert all(np.isfinite(v) for v in summary.values() if isinstance(v, float))
