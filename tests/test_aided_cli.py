"""``sarins navigate --trajectory``: the aided run from the command line, and its bad inputs (exit 2
naming the option or the segment)."""

import json

import pytest

from sarins.cli import main

SEGMENTS = [{"kind": "stop", "duration": 20}, {"kind": "accelerate", "to_speed": 10, "accel": 1.0},
            {"kind": "turn", "rate_dps": 3, "angle_deg": 90}, {"kind": "cruise", "duration": 40},
            {"kind": "accelerate", "to_speed": 0, "accel": 1.0}, {"kind": "stop", "duration": 10}]


def write(tmp_path, segments=SEGMENTS, name="t.json"):
    path = tmp_path / name
    path.write_text(json.dumps({"start": {"lat_deg": 32.0, "lon_deg": 118.0}, "segments": segments}))
    return str(path)


def run(argv):
    try:
        return main(argv)
    except SystemExit as exc:
        return exc.code


def test_aided_run_prints_json_with_the_outage_row(tmp_path, capsys):
    path = write(tmp_path)
    argv = ["navigate", "--trajectory", path, "--aiding", "gnss,zupt", "--gnss-outage", "50:80", "--json",
            "--imu-rate-hz", "50", "--seed", "3"]
    assert run(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["duration_s"] == pytest.approx(120.0)
    assert out["zupt_steps"] == 30 * 50
    assert out["gnss_fixes_used"] == 120 - 30
    (row,) = out["outages"]
    assert row["start_s"] == 50 and row["end_s"] == 80 and row["predicted_sigma_m"] > 0
    assert out["horizontal_error_max_m"] < 20
    assert run(argv) == 0  # the same seed, the same numbers
    again = json.loads(capsys.readouterr().out)
    assert {k: v for k, v in again.items() if k != "wall_seconds"} == {k: v for k, v in out.items() if k != "wall_seconds"}


@pytest.mark.parametrize("segments, extra, words", [
    ([{"kind": "accelerate", "to_speed": 5, "accel": 1}, {"kind": "stop", "duration": 5}], [],
     "segment 1 (stop): trajectory discontinuity"),
    (SEGMENTS, ["--gnss-rate-hz", "20", "--imu-rate-hz", "10"], "--gnss-rate-hz 20 is above the IMU rate"),
    (SEGMENTS, ["--gnss-pos-std", "-1"], "--gnss-pos-std must not be negative"),
    (SEGMENTS, ["--zupt-std", "-0.1"], "--zupt-std must be positive"),
    (SEGMENTS, ["--aiding", "gnss,zupt,zaru", "--zaru-std", "-0.0001"], "--zaru-std must be positive"),
    (SEGMENTS, ["--aiding", "gnss,zupt,zaru", "--zaru-std", "nan"], "--zaru-std: must be finite"),
    (SEGMENTS, ["--zaru-std", "1e-4"], "--zaru-std needs zaru in --aiding"),
    (SEGMENTS, ["--gnss-outage", "100:200"], "--gnss-outage 100:200 is outside the run"),
    (SEGMENTS, ["--gnss-outage", "abc"], "--gnss-outage abc"),
    (SEGMENTS, ["--aiding", "gnss,magnetometer"], "--aiding gnss,magnetometer: choose from gnss, zupt, odometer, nhc, zaru"),
    (SEGMENTS, ["--nav-hours", "3"], "--nav-hours does not apply to an aided run"),
])
def test_bad_input_exits_2_naming_it(tmp_path, capsys, segments, extra, words):
    assert run(["navigate", "--trajectory", write(tmp_path, segments), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0]


def test_missing_file_and_aided_options_without_a_trajectory(tmp_path, capsys):
    assert run(["navigate", "--trajectory", str(tmp_path / "none.json")]) == 2
    assert "cannot read" in capsys.readouterr().err
    assert run(["navigate", "--gnss-outage", "1:2"]) == 2
    assert "--gnss-outage applies to an aided run only" in capsys.readouterr().err


def test_gnss_free_run_with_odometer_and_nhc(tmp_path, capsys):
    assert run(["navigate", "--trajectory", write(tmp_path), "--aiding", "zupt,odometer,nhc", "--imu-rate-hz", "50",
                "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["gnss_fixes_used"] == 0 and out["aiding"] == ["zupt", "odometer", "nhc"]
    assert out["horizontal_error_max_m"] < 50


def test_zaru_at_the_stops(tmp_path, capsys):
    """--aiding gnss,zupt,zaru: a ZARU at every stop step (the ZUPT's), the same seed otherwise."""
    argv = ["navigate", "--trajectory", write(tmp_path), "--imu-rate-hz", "50", "--json", "--seed", "3"]
    assert run([*argv, "--aiding", "gnss,zupt,zaru"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["zaru_steps"] == out["zupt_steps"] == 30 * 50
    assert out["aiding"] == ["gnss", "zupt", "zaru"] and out["horizontal_error_max_m"] < 20
    assert run([*argv, "--aiding", "gnss,zupt"]) == 0
    plain = json.loads(capsys.readouterr().out)
    assert plain["zaru_steps"] == 0 and plain["heading_error_rms_deg"] != out["heading_error_rms_deg"]


@pytest.mark.parametrize("extra, words", [
    (["--filter-states", "sf,scale"], "--filter-states sf,scale: 'scale' unknown; choose from sf, lever, gnss-gm"),
    (["--filter-states", "sf,sf"], "--filter-states sf,sf: a state is named twice"),
    (["--filter-states", "lever", "--aiding", "zupt"], "--filter-states lever: filter states lever need 'gnss'"),
    (["--filter-states", "sf", "--nav-hours", "3"], "--nav-hours does not apply to an aided run"),
])
def test_bad_filter_states_exit_2_naming_them(tmp_path, capsys, extra, words):
    assert run(["navigate", "--trajectory", write(tmp_path), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0]


def test_filter_states_option_runs_the_navigate_numbers(tmp_path, capsys):
    from sarins_fmu import aided, gnss
    from sarins_fmu import trajectory as tr

    path = write(tmp_path)
    argv = ["navigate", "--trajectory", path, "--json", "--imu-rate-hz", "50", "--seed", "2",
            "--filter-states", "sf,gnss-gm"]
    assert run(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["filter_states"] == ["sf", "gnss-gm"]
    assert set(out["final_states"]) == {"scale_g", "scale_a", "gnss_pos_gm", "gnss_vel_gm"}
    truth = tr.generate(tr.load_trajectory(path), 0.02)
    r = aided.navigate(truth, gnss=gnss.preset("sps", rate_hz=1.0), seed=2, filter_states=("sf", "gnss-gm"),
                       imu_stream="core")  # the command's default stream
    assert out["horizontal_error_rms_m"] == aided.summary(r)["horizontal_error_rms_m"]
    assert run(["navigate", "--trajectory", path, "--imu-rate-hz", "50", "--seed", "2", "--filter-states", "none",
                "--filter-states", "sf,gnss-gm", "--json"]) == 0  # the last one counts
    assert json.loads(capsys.readouterr().out)["horizontal_error_rms_m"] == out["horizontal_error_rms_m"]
    assert run(["navigate", "--trajectory", path, "--json", "--imu-rate-hz", "50", "--seed", "2"]) == 0
    plain = json.loads(capsys.readouterr().out)
    assert plain["filter_states"] == [] and plain["horizontal_error_rms_m"] != out["horizontal_error_rms_m"]
