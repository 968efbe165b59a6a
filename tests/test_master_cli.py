"""The ``cosim`` subcommand."""
from __future__ import annotations

import argparse

import numpy as np
import pytest

from fmu_fixtures.fixtures import fixture_fmus, ramp_gain  # noqa: F401 (fixtures)
from orchestration import Component, System, write_ssp
from sarins.cli import main
from sarins.cli.cosim import register

pytestmark = pytest.mark.integration


def test_register_adds_cosim_to_a_host_parser(ramp_gain, tmp_path, capsys):
    parser = argparse.ArgumentParser(prog="sarins")
    register(parser.add_subparsers(dest="command"))
    path = write_ssp(ramp_gain, tmp_path / "rg.ssp")
    args = parser.parse_args(["cosim", str(path), "--stop-time", "1", "--step", "0.25",
                              "--scheme", "jacobi", "--output", str(tmp_path / "r.csv"),
                              "--no-progress"])
    assert args.func(args) == 0
    out = capsys.readouterr().out
    assert "scheme jacobi" in out and "t = 1 s" in out
    assert "gain.y         7.5" in out
    data = np.genfromtxt(tmp_path / "r.csv", delimiter=",", names=True)
    assert data["time"][-1] == 1.0


def test_defaults_come_from_the_system_file(ramp_gain, tmp_path, capsys):
    ramp_gain.stop_time, ramp_gain.step_size = 0.5, 0.125
    path = write_ssp(ramp_gain, tmp_path / "rg.ssp")
    assert main(["cosim", str(path), "--record", "ramp.*", "--realtime", "0.01"]) == 0
    out = capsys.readouterr().out
    assert "4 steps" in out and "ramp.slope" in out and "gain.y" not in out


def test_errors_exit_nonzero_with_a_message(fixture_fmus, tmp_path, capsys):
    bad = System("bad", [Component("f", fixture_fmus["Faulty"], {"mode": 2, "fail_at": 0.2})],
                 [])
    path = write_ssp(bad, tmp_path / "bad.ssp")
    assert main(["cosim", str(path), "--stop-time", "1", "--step", "0.1"]) == 1
    err = capsys.readouterr().err
    assert "\nsarins cosim: failed:" in "\n" + err and "fmi2DoStep returned DISCARD at t = 0.2 s" in err
    assert main(["cosim", str(tmp_path / "none.ssp"), "--stop-time", "1", "--step", "1"]) == 2
    assert "not found" in capsys.readouterr().err


def test_output_csv_has_a_units_sidecar(fmu_dir, tmp_path, capsys):
    import json

    out = tmp_path / "run.csv"
    assert main(["cosim", str(fmu_dir / "standard_static.ssp"), "--stop-time", "3", "--step", "1",
                 "--record", "ins.lat_error", "--record", "imu.temp_gyro_z", "--output", str(out),
                 "--no-progress"]) == 0
    units = json.loads((tmp_path / "run.csv.units.json").read_text())
    assert units == {"time": "s", "ins.lat_error": "rad", "imu.temp_gyro_z": "degC"}


def test_profile_prints_where_a_step_goes(ramp_gain, tmp_path, capsys):
    path = write_ssp(ramp_gain, tmp_path / "rg.ssp")
    assert main(["cosim", str(path), "--stop-time", "2", "--step", "0.25", "--profile", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "profile:" in out and "us/step" in out
    assert "ramp.doStep" in out and "gain.doStep" in out and "master (the rest)" in out
    assert main(["cosim", str(path), "--stop-time", "1", "--step", "0.25", "--profile", "--realtime",
                 "0.01"]) == 2
    assert "--profile measures the compiled loop" in capsys.readouterr().err
