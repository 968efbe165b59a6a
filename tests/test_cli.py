import json
import subprocess
import sys
from pathlib import Path

import pytest

from sarins_fmu.cli import main

ROOT = Path(__file__).resolve().parents[1]


def test_navigate_json(capsys):
    assert main(["navigate", "--json", "--nav-hours", "12", "--align-hours", "0.5", "--imu", "ideal",
                 "--axial-drift-dph", "0.003"]) == 0
    out = json.loads(capsys.readouterr().out)
    for key in ("lat_error_deg", "lon_error_deg", "position_error_nm", "lat_error_deg_12h"):
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
    proc = subprocess.run([sys.executable, "-m", "sarins_fmu.cli", *argv], capture_output=True, text=True)
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
    assert main(["demo", "--align-hours", "0.2", "--identify-hours", "0.1", "--nav-hours", "0.1", "--no-progress",
                 "--fmu-dir", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "gauss-seidel" in out and "position error, compensated" in out
    drift = float(out.split("identified axial drift")[1].split()[0])
    assert drift != 0.0 and abs(drift) < 0.01
    assert (tmp_path / "StrapdownINS.fmu").exists() and (tmp_path / "RBFIdentifier.fmu").exists()
