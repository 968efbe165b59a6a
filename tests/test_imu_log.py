"""IMU log format, its checks, and replay through alignment and navigation."""

import json

import numpy as np
import pytest

from sarins_fmu import allan, imu, imu_log
from sarins_fmu.experiments.replay import replay
from sarins_fmu.experiments.static_run import run_static
from sarins_fmu.imu_log import LogError, read_log, write_log

FIELDS = ("lat_error", "lon_error", "north_error", "east_error", "position_error", "velocity_n", "attitude",
          "temperature")


@pytest.fixture(scope="module")
def simulated():
    """A short mems run and its IMU output, chunk by chunk."""
    chunks = []
    result = run_static(imu="mems", align_hours=0.5, nav_hours=0.25, seed=3, start="cold",
                        on_increments=lambda *c: chunks.append(c))
    cols = [np.concatenate([c[j] for c in chunks]) for j in range(4)]
    return result, cols


@pytest.mark.parametrize("suffix", [".csv", ".npz"])
def test_replay_of_a_logged_run_equals_the_in_process_run_bit_for_bit(simulated, tmp_path, suffix):
    result, (time, dtheta, dv, temps) = simulated
    path = write_log(tmp_path / f"run{suffix}", time, dtheta, dv, temps=temps, lat_deg=result.info["lat_deg"])
    log = read_log(path)
    assert np.array_equal(log.dtheta, dtheta) and np.array_equal(log.dv, dv) and np.array_equal(log.temps, temps)
    again = replay(log, align_hours=0.5)
    for name in FIELDS:
        assert np.array_equal(getattr(again, name), getattr(result, name)), name
    assert again.summary() == result.summary()


def test_replay_with_a_reference_measures_against_it(simulated, tmp_path):
    result, (time, dtheta, dv, temps) = simulated
    ref = np.tile([result.info["lat_deg"] * np.pi / 180, 0.0, 0.0], (len(time), 1))
    ref[:, 0] += 1e-6  # a reference 6.4 m north of the start
    log = read_log(write_log(tmp_path / "ref.csv", time, dtheta, dv, ref=ref, lat_deg=result.info["lat_deg"]))
    again = replay(log, align_hours=0.5)
    assert np.allclose(again.lat_error, result.lat_error - 1e-6, rtol=0, atol=1e-15)


def test_compensator_replay_needs_temperatures(simulated, tmp_path):
    from sarins_fmu.identify import compensators

    result, (time, dtheta, dv, temps) = simulated
    log = read_log(write_log(tmp_path / "no_temps.npz", time, dtheta, dv, lat_deg=28.0))
    x = np.column_stack([dtheta / 1.0, dv / 1.0, temps.mean(axis=1)])
    comp = compensators.make("traditional").fit(x, x[:, :6])  # identity-like fit on the run itself
    with pytest.raises(LogError, match="temperature"):
        replay(log, align_hours=0.5, compensator=comp)
    with_t = read_log(write_log(tmp_path / "t.npz", time, dtheta, dv, temps=temps, lat_deg=28.0))
    out = replay(with_t, align_hours=0.5, compensator=comp)
    assert out.info["compensated"] and np.isfinite(out.position_error).all()


def _static_csv(tmp_path, n=200, h=1.0, **kw):
    gyro, accel, temps = allan.static_record(imu.preset("nav-rlg"), n * h, 1.0 / h, seed=1)
    time = np.arange(1, n + 1) * h
    return write_log(tmp_path / "s.csv", time, gyro * h, accel * h, temps=temps, lat_deg=45.0, **kw)


def _edit(path, line, new):
    lines = path.read_text().splitlines()
    if new is None:
        del lines[line - 1]
    else:
        lines[line - 1] = new(lines[line - 1]) if callable(new) else new
    path.write_text("\n".join(lines) + "\n")


HEADER = 5  # tag, lat, lon, height, column names: the first data row is line 6


@pytest.mark.parametrize("line, change, message", [
    (20, lambda s: "13" + s[s.index(","):], "line 20: timestamp 13 s is earlier than the one before"),
    (20, lambda s: "14" + s[s.index(","):], "line 20: timestamp 14 s is duplicated"),
    (20, lambda s: "15.5" + s[s.index(","):], "line 20: time step 1.5 s .*rate change"),
    (20, None, "line 20: time step 2 s .*a gap"),  # line 20 deleted
    (30, lambda s: s.split(",")[0] + ",nan" + s[s.index(",", len(s.split(",")[0]) + 1):], "line 30: dtheta_x_rad is nan"),
    (30, lambda s: s.split(",")[0] + ",abc" + s[s.index(",", len(s.split(",")[0]) + 1):], "line 30: could not convert"),
    (31, lambda s: s.rsplit(",", 1)[0], "line 31: the number of columns"),
    (HEADER, lambda s: s.replace("dtheta_x_rad", "dtheta_x_deg"), "dtheta_x_deg.*SI units"),
    (1, "# some other log", "line 1 must be"),
])
def test_bad_logs_name_the_line(tmp_path, line, change, message):
    path = _static_csv(tmp_path)
    _edit(path, line, change)
    with pytest.raises(LogError, match=message):
        read_log(path)


def test_unit_mistakes_are_caught(tmp_path):
    gyro, accel, _ = allan.static_record(imu.preset("mems"), 200.0, 1.0, seed=1)
    time = np.arange(1.0, 201.0)
    with pytest.raises(LogError, match="lines? 6..line 65: mean specific force 1.004 m/s.2 is not gravity"):
        read_log(write_log(tmp_path / "g.csv", time, gyro, accel / 9.80665, lat_deg=45.0))
    with pytest.raises(LogError, match="degrees logged as radians"):
        read_log(write_log(tmp_path / "deg.csv", time, np.degrees(gyro), accel, lat_deg=45.0))
    spin = gyro.copy()
    spin[50, 2] = 40.0
    with pytest.raises(LogError, match="line 56: angular rate 40 rad/s"):
        read_log(write_log(tmp_path / "spin.csv", time, spin, accel, lat_deg=45.0))


def test_rate_logs_npz_rows_and_metadata(tmp_path):
    gyro, accel, _ = allan.static_record(imu.preset("nav-rlg"), 100.0, 10.0, seed=1)
    time = np.arange(1, 1001) * 0.1
    cols = {f"gyro_{a}_radps": gyro[:, i] for i, a in enumerate("xyz")}
    cols.update({f"accel_{a}_mps2": accel[:, i] for i, a in enumerate("xyz")})
    np.savez(tmp_path / "r.npz", time_s=time, meta=np.array(json.dumps({"lat_deg": 30.0})), **cols)
    log = read_log(tmp_path / "r.npz")
    assert log.quantity == "rates" and log.step == pytest.approx(0.1)
    assert np.allclose(log.dtheta, gyro * 0.1, rtol=1e-12)
    time[500] = time[499]
    np.savez(tmp_path / "bad.npz", time_s=time, meta=np.array(json.dumps({"lat_deg": 30.0})), **cols)
    with pytest.raises(LogError, match="row 500: timestamp .* duplicated"):
        read_log(tmp_path / "bad.npz")
    np.savez(tmp_path / "nolat.npz", time_s=np.arange(1, 1001) * 0.1, **cols)
    with pytest.raises(LogError, match="lat_deg"):
        read_log(tmp_path / "nolat.npz")
    with pytest.raises(LogError, match="no such log"):
        read_log(tmp_path / "missing.csv")
    assert imu_log.TEMP_COLUMNS[0] == "temp_gyro_x_c"


def test_replay_command_round_trip_and_errors(tmp_path, capsys):
    from sarins.cli import main

    log = tmp_path / "nav.npz"
    args = ["--imu", "mems", "--align-hours", "0.25", "--nav-hours", "0.1", "--json"]
    assert main(["navigate", *args, "--write-log", str(log)]) == 0
    direct = json.loads(capsys.readouterr().out)
    assert main(["replay", str(log), "--align-hours", "0.25", "--json"]) == 0
    replayed = json.loads(capsys.readouterr().out)
    for key in ("lat_error_deg", "lon_error_deg", "position_error_nmi"):
        assert replayed[key] == direct[key]
    bad = _static_csv(tmp_path)
    _edit(bad, 10, lambda s: "4" + s[s.index(","):])
    assert main(["replay", str(bad)]) == 2
    assert "sarins replay: error:" in capsys.readouterr().err
    assert main(["replay", str(log), "--align-hours", "5"]) == 2
    assert "not longer than" in capsys.readouterr().err
