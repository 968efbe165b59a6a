import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sarins.cli import main

ROOT = Path(__file__).resolve().parents[1]


def test_navigate_json(capsys):
    assert main(["navigate", "--json", "--nav-hours", "12", "--align-hours", "0.5", "--imu", "ideal",
                 "--axial-drift-dph", "0.003"]) == 0
    out = json.loads(capsys.readouterr().out)
    for key in ("lat_error_deg", "lon_error_deg", "position_error_nmi", "lat_error_deg_12h"):
        assert key in out
    # 12 h latitude error of 0.003 deg/h: 2 cos L eps / w_ie = 0.0201 deg (Table 1)
    assert out["lat_error_deg_12h"] == pytest.approx(0.0201, rel=0.05)


@pytest.mark.parametrize("argv", [
    ["navigate", "--lat-deg", "95"],
    ["navigate", "--nav-hours", "nan"],
    ["navigate", "--align-hours", "-1"],
    ["navigate", "--imu", "fog"],
    ["navigate", "--rotation", "sideways"],
])
def test_bad_values_exit_nonzero_with_one_line(argv):
    proc = subprocess.run([sys.executable, "-m", "sarins", *argv], capture_output=True, text=True)
    assert proc.returncode != 0
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "error" in lines[0]


def test_readme_starts_with_the_two_setup_commands_and_ci_runs_the_second():
    lines = (ROOT / "README.md").read_text().splitlines()
    assert lines[0].startswith("```") and lines[3] == "```"
    assert "sarins" in lines[1] and "pip install" in lines[1]
    assert "pytest" in lines[2] and "pip install" in lines[2]
    ci = (ROOT / ".ci" / "run").read_text()
    assert "sed -n 3p README.md" in ci


def test_demo_cosimulates_the_identified_system(tmp_path, capsys):
    """align -> navigate -> identify (RBFIdentifier FMU) -> compensate -> navigate, scaled down."""
    from sarins_fmu.identify.axial import default_model_path

    assert main(["demo", "--align-hours", "0.2", "--identify-hours", "0.1", "--nav-hours", "0.1",
                 "--model-file", str(default_model_path("hot")), "--fmu-dir", str(tmp_path),
                 "--out", str(tmp_path / "results")]) == 0
    captured = capsys.readouterr()
    out, err = captured.out, captured.err
    assert "gauss-seidel" in out and "position error, compensated" in out
    # issue 21: each phase announced on stderr, in order, with its duration
    phases = ["building the FMUs", "loading", "co-simulating", "in-process reference"]
    starts = [err.index(f"sarins demo: {p}") for p in phases]
    assert starts == sorted(starts), err
    assert all(f"sarins demo: {p}: done in" in err for p in phases), err
    # ... the series and the figure in the folder it names, and what to run next
    series = (tmp_path / "results" / "series.csv").read_text().splitlines()
    assert series[0].split(",")[:3] == ["nav_time_s", "position_error_compensated_m",
                                        "position_error_uncompensated_m"]
    assert len(series) == 1 + int(0.2 * 3600 / 60) + 1  # one row a minute of navigation, both ends
    assert all(np.isfinite([float(x) for x in row.split(",")]).all() for row in series[1:])
    assert (tmp_path / "results" / "position_error.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"results in {tmp_path / 'results'}" in out
    assert "sarins campaign axial-rbf" in out.split("to go further:")[1]
    drift = float(out.split("identified axial drift")[1].split()[0])
    true = float(out.split("true axial drift")[1].split()[0])
    error = float(out.split("identification error")[1].split()[0])
    assert drift != 0.0 and abs(drift) < 0.01
    assert abs(true) < 0.01 and error == pytest.approx(drift - true, abs=2e-5)
    assert (tmp_path / "StrapdownINS.fmu").exists() and (tmp_path / "RBFIdentifier.fmu").exists()


def test_demo_progress_estimate_is_right_from_its_first_update():
    """Issue 21: the bar sat at 0 during a 63 s set-up, then estimated 3.5 h for a 21 s run. The estimate
    now counts only from the first step: set-up 63 s, then 316800 steps at 15000 steps/s."""
    import io

    from sarins.demo import Phases

    now = [0.0]
    stream = io.StringIO()
    phases = Phases(stream, clock=lambda: now[0])
    phases.start("loading")
    bar = phases.progress(316800)
    now[0] = 63.0  # loading: no step yet
    bar.update(1)
    rate = 15000.0
    for done in range(1000, 316800, 1000):
        now[0] = 63.0 + (done - 1) / rate
        left = bar.estimate(done, now[0])
        assert left == pytest.approx((316800 - done) / rate, rel=1e-9)
        bar.update(done)
    lines = [line for line in stream.getvalue().splitlines() if "%" in line]
    assert lines and "about 19 s left" in lines[0], lines  # the first update: 10 % done, 19 s left
    assert len(lines) == 9  # one line per 10 % when stderr is not a terminal


def test_demo_refuses_an_identify_time_the_shipped_model_was_not_trained_for(tmp_path, capsys):
    assert main(["demo", "--identify-hours", "1", "--fmu-dir", str(tmp_path), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("sarins demo: error:") and "12 h" in err and "--model-file" in err
    assert not (tmp_path / "StrapdownINS.fmu").exists()


def test_demo_has_no_options_it_cannot_honour(capsys):
    assert main_exit(["demo", "--correction-dph", "0.01"]) == 2


def main_exit(argv):
    try:
        return main(argv)
    except SystemExit as exc:
        return exc.code


def test_version_and_help_are_plain(capsys):
    assert main_exit(["--version"]) == 0
    assert capsys.readouterr().out.startswith("sarins ")
    assert main_exit(["--help"]) == 0
    assert "``" not in capsys.readouterr().out


def test_layers_import_one_way():
    """sarins_fmu (physics) imports none of fmus / orchestration / sarins; fmus and
    orchestration never import the application layer (sarins); orchestration knows no FMU of ours."""
    import ast

    def imported(folder):
        names = set()
        for path in (ROOT / folder).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.Import):
                    names |= {(str(path), a.name.split(".")[0]) for a in node.names}
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    names.add((str(path), node.module.split(".")[0]))
        return names

    forbidden = {"sarins_fmu": {"fmus", "orchestration", "sarins", "fmpy", "pythonfmu"},
                 "fmus": {"orchestration", "sarins"}, "orchestration": {"fmus", "sarins", "sarins_fmu"}}
    bad = [(path, name) for folder, names in forbidden.items() for path, name in imported(folder) if name in names]
    assert bad == []


def test_public_api_is_reexported():
    import sarins_fmu

    for name in sarins_fmu.__all__:
        assert getattr(sarins_fmu, name) is not None
    assert sarins_fmu.run_static.__module__ == "sarins_fmu.experiments.static_run"
