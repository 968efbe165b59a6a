"""Replay on a MEMS log: levelling with the accelerometers and a given heading when the gyros cannot see
the Earth rate, never an absurd attitude, errors that name the user's options."""

import json
import math

import numpy as np
import pytest

from sarins_fmu import allan, imu
from sarins_fmu.experiments import replay_align
from sarins_fmu.experiments.replay import replay
from sarins_fmu.experiments.replay_align import AlignmentError
from sarins_fmu.imu_log import ImuLog, read_log, write_log
from sarins_fmu.rotations import euler_to_mat


def _levelling(log, seconds):
    """Roll and pitch (deg) of the accelerometers' mean over the first ``seconds``, from the increments."""
    n = int(round(seconds / log.step))
    f = np.asarray(log.dv[:n]).sum(axis=0)
    return math.degrees(math.atan2(-f[0], f[2])), math.degrees(math.atan2(f[1], math.hypot(f[0], f[2])))


@pytest.mark.parametrize("unit", ["unit1", "unit2"])
def test_real_unit_levels_with_the_accelerometers_and_the_given_heading(real_adis, unit):
    log = real_adis[unit]
    with pytest.raises(AlignmentError, match=r"cannot see the Earth rate \(their horizontal rate .* deg/h, is more "
                                             r"than 5 x the Earth's .*give it with --heading-deg"):
        replay(log, align_hours=0.5, path=unit)
    out = replay(log, align_hours=0.5, heading=0.0, path=unit)
    roll, pitch = _levelling(log, 1800.0)
    assert abs(out.info["roll_deg"] - roll) < 0.5 and abs(out.info["pitch_deg"] - pitch) < 0.5
    assert out.info["heading_deg"] == 0.0 and out.info["alignment"] == "levelling + given heading"
    # the gyro bias estimated with the attitude known: the README's 1,000 - 1,500 deg/h
    assert all(900 < abs(b) < 1700 for b in out.info["gyro_comp_dph"])
    assert out.info["warnings"] == []  # the vertical accelerometer bias (16 mg) is within its class


def test_degrees_logged_as_radians_end_with_a_message_naming_heading(tmp_path):
    """A navigation-grade log in degrees is read (a MEMS bias looks the same: a warning), and its replay
    says why it cannot gyrocompass and names --heading-deg."""
    gyro, accel, _ = allan.static_record(imu.preset("nav-rlg"), 1200.0, 1.0, seed=1, lat_deg=45.0)
    path = write_log(tmp_path / "deg.csv", np.arange(1, 1201.0), np.degrees(gyro), accel, lat_deg=45.0)
    with pytest.warns(UserWarning, match="degrees logged as radians"):
        log = read_log(path)
    with pytest.raises(AlignmentError, match=r"deg.csv: the gyros cannot see the Earth rate.*degrees logged as "
                                             r"radians.*--heading-deg"):
        replay(log, align_hours=0.25, path=str(path))


def test_a_navigation_grade_log_still_gyrocompasses_and_agrees_with_its_accelerometers(tmp_path):
    gyro, accel, _ = allan.static_record(imu.preset("nav-rlg"), 1200.0, 1.0, seed=1, lat_deg=45.0)
    log = read_log(write_log(tmp_path / "rad.csv", np.arange(1, 1201.0), gyro, accel, lat_deg=45.0))
    out = replay(log, align_hours=0.25)
    assert out.info["alignment"] == "gyrocompass" and out.info["warnings"] == []
    roll, pitch = _levelling(log, 900.0)
    assert abs(out.info["roll_deg"] - roll) < 0.01 and abs(out.info["pitch_deg"] - pitch) < 0.01
    assert abs((out.info["heading_deg"] + 180) % 360 - 180) < 0.5  # a level, north-facing base


def test_an_absurd_tilt_and_an_accelerometer_bias_beyond_any_class_are_refused_and_flagged():
    """What the Kalman alignment reported on a MEMS log: pitch 28 deg against the accelerometers' level,
    and an accelerometer bias of 0.55 g."""
    means = np.tile([0.0, 0.0, 0.0, 0.0, 0.0, 9.81], (100, 1))
    message = r"disagrees with the accelerometers' levelling \(roll -?0, pitch 0 deg\) by 28 deg.*--heading-deg"
    with pytest.raises(AlignmentError, match=message):
        replay_align.check_tilt(euler_to_mat(0.0, math.radians(28.0), 0.0), means, "x.csv", [0.0, -5.37, 0.0])
    replay_align.check_tilt(euler_to_mat(0.3, math.radians(0.05), 0.0), means, "x.csv", [0.0, 0.0, 0.0])
    assert "547.6 mg, is beyond any accelerometer class" in replay_align.accel_bias_note([0, -5.37, 0.0], "x.csv")
    assert replay_align.accel_bias_note([0.0, 0.01, 0.0], "x.csv") is None


def test_errors_name_the_options_and_the_file(tmp_path):
    gyro, accel, _ = allan.static_record(imu.preset("nav-rlg"), 1200.0, 1.0, seed=1, lat_deg=45.0)
    path = write_log(tmp_path / "r.csv", np.arange(1, 1201.0), gyro, accel, lat_deg=45.0)
    log = read_log(path)
    with pytest.raises(ValueError, match=r"--align-hours 0.05 h \(180 s\) must exceed the 300 s coarse alignment "
                                         r"plus two of the log's 1 s samples \(.*r.csv\)"):
        replay(log, align_hours=0.05, path=str(path))
    with pytest.raises(ValueError, match=r"the log \(0.3333 h, .*r.csv\) is not longer than the 0.5 h alignment "
                                         r"\(--align-hours\)"):
        replay(log, align_hours=0.5, path=str(path))
    with pytest.raises(ValueError, match=r"the log \(0.3333 h, .*r.csv\) is not longer than the 4 h alignment "
                                         r"\(--align-hours; without it 4 h to gyrocompass, or 10 min with "
                                         r"--heading-deg\)"):
        replay(log, path=str(path))  # the gyros see the Earth rate: the length is what is wrong
    nolat = ImuLog(time=log.time, dtheta=log.dtheta, dv=log.dv, temps=None, ref=None, lat=None)
    with pytest.raises(AlignmentError, match="does not state the latitude .*--lat-deg"):
        replay(nolat, align_hours=0.25, path="v.csv")


def test_replay_command_json_has_the_attitude_and_a_simulated_comparison(tmp_path, capsys):
    from sarins.cli import main

    gyro, accel, _ = allan.static_record(imu.preset("nav-rlg"), 1200.0, 1.0, seed=1, lat_deg=45.0)
    header = "time_s," + ",".join(f"gyro_{a}_dph" for a in "xyz") + "," + ",".join(f"accel_{a}_g" for a in "xyz")
    d = np.array([[0, 1, 0], [1, 0, 0], [0, 0, -1.0]])  # right-front-up -> forward-right-down
    rows = np.column_stack([np.arange(1200.0), gyro @ d / (math.pi / 180 / 3600), accel @ d / 9.80665])
    np.savetxt(tmp_path / "v.csv", rows, delimiter=",", header=header, comments="", fmt="%.17g")
    args = ["replay", str(tmp_path / "v.csv"), "--axes", "frd", "--align-hours", "0.25", "--json"]
    assert main(args) == 2
    assert "--lat-deg" in capsys.readouterr().err
    assert main([*args, "--lat-deg", "45", "--imu", "nav-rlg", "--seed", "3"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["alignment"] == "gyrocompass" and out["format"] == "csv" and out["axes"] == "frd"
    assert {"roll_deg", "pitch_deg", "heading_deg", "simulated_position_error_nmi"} <= set(out)
    assert abs(out["pitch_deg"]) < 0.01 and abs(out["simulated_pitch_deg"]) < 0.01
    assert main([*args, "--lat-deg", "45", "--heading-deg", "30"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["alignment"] == "levelling + given heading" and out["heading_deg"] == pytest.approx(30.0)
    assert main([*args, "--lat-deg", "45", "--seed", "3"]) == 2
    assert "--seed needs --imu" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.parametrize("unit", ["unit1", "unit2"])
def test_the_acceptance_commands_on_the_real_units(real_adis, unit, capsys):
    from conftest import REAL_DATA

    from sarins.cli import main

    path = str(REAL_DATA / f"{unit}.csv.gz")
    base = ["replay", path, "--axes", "frd", "--lat-deg", "51.08", "--json"]  # the command, as written
    assert main([*base, "--heading-deg", "0"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["align_hours"] == pytest.approx(1 / 6) and out["alignment"] == "levelling + given heading"
    roll, pitch = _levelling(real_adis[unit], 600.0)
    assert abs(out["roll_deg"] - roll) < 0.5 and abs(out["pitch_deg"] - pitch) < 0.5
    assert main(base) == 2
    assert "--heading-deg" in capsys.readouterr().err
    assert main(["allan", "--log", path, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert all(ch["random_walk"] is not None and ch["bias_instability"] is not None for ch in out["channels"][:3])


def test_without_align_hours_levelling_takes_ten_minutes_at_most_half_the_log(tmp_path):
    """The default alignment: 10 min when levelling (a short MEMS log fits), capped at half the log,
    whole samples; the levelled attitude equals the one of an explicit 1/6 h."""
    from sarins_fmu.experiments.replay import default_align_hours

    gyro, accel, _ = allan.static_record(imu.preset("nav-rlg"), 1500.0, 1.0, seed=2, lat_deg=45.0)
    log = read_log(write_log(tmp_path / "l.csv", np.arange(1, 1501.0), gyro, accel, lat_deg=45.0))
    assert default_align_hours(log, None) == 4.0
    assert default_align_hours(log, 0.0) * 3600 == pytest.approx(600.0)
    out = replay(log, heading=0.3)
    same = replay(log, heading=0.3, align_hours=1 / 6)
    assert out.info["align_hours"] * 3600 == pytest.approx(600.0)
    np.testing.assert_array_equal(out.attitude, same.attitude)
    short = ImuLog(time=log.time[:700], dtheta=log.dtheta[:700], dv=log.dv[:700], temps=None, ref=None, lat=log.lat,
                   interval=log.step)
    assert replay(short, heading=0.3).info["align_hours"] * 3600 == pytest.approx(350.0)


@pytest.mark.filterwarnings("ignore:.*taken as the Earth rate plus a MEMS-class gyro bias")
def test_a_short_mems_log_without_heading_names_heading_not_the_length(tmp_path):
    """A log shorter than the 4 h default whose gyros cannot see the Earth rate: the message names
    --heading-deg (what the user must add), not --align-hours."""
    rng = np.random.default_rng(4)
    n = 1200
    gyro = np.tile([0.004, -0.003, 0.001], (n, 1)) + 1e-4 * rng.standard_normal((n, 3))  # 825 deg/h bias
    accel = np.tile([0.0, 0.0, 9.80], (n, 1)) + 1e-3 * rng.standard_normal((n, 3))
    log = read_log(write_log(tmp_path / "m.csv", np.arange(1, n + 1.0), gyro, accel, lat_deg=45.0))
    with pytest.raises(AlignmentError, match=r"m.csv: the gyros cannot see the Earth rate .*--heading-deg"):
        replay(log, path=str(tmp_path / "m.csv"))
    assert replay(log, heading=0.0).info["alignment"] == "levelling + given heading"
