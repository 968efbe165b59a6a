"""IMU log format, its checks, and replay through alignment and navigation."""

import json
import re
import warnings

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
    with pytest.raises(LogError, match="line 6..line 205: mean specific force .* m/s.2 over the log is not gravity") as err:
        read_log(write_log(tmp_path / "g.csv", time, gyro, accel / 9.80665, lat_deg=45.0))
    reported = float(re.search(r"mean specific force (\S+) m/s", str(err.value)).group(1))
    assert reported == pytest.approx(np.linalg.norm(accel / 9.80665, axis=1).mean(), abs=1e-3)  # the log's, in g
    with pytest.warns(imu_log.LogWarning, match="degrees logged as radians"):  # a MEMS bias looks the same
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


# ---- the grammar of docs/imu-log.md: what is not in it is refused, naming the file and line (issue 21)
def _text_cases():
    def insert(at, text):
        return lambda lines: lines[:at - 1] + [text] + lines[at - 1:]

    def replace(at, fn):
        return lambda lines: lines[:at - 1] + [fn(lines[at - 1])] + lines[at:]

    return [
        ("blank data line", insert(20, ""), "line 20: blank line"),
        ("blank metadata line", insert(3, ""), "line 3: blank line"),
        ("whitespace-only line", insert(20, "   "), "line 20: blank line"),
        ("long metadata line", insert(3, "# note: " + "x" * 1_000_000), "line 3: longer than 1024"),
        ("metadata given twice", insert(3, "# lat_deg: 10"), "line 3: metadata lat_deg given twice"),
        ("metadata key", insert(3, "# bad key!: 1"), "line 3: metadata must read"),
        ("comment among the samples", insert(20, "# note: here"), "line 20: a '#' line among the samples"),
        ("unknown column", replace(HEADER, lambda h: h.replace("temp_gyro_x_c", "temp_gyro_q_c")),
         "line 5: column 'temp_gyro_q_c' is not a log column"),
        ("column twice", replace(HEADER, lambda h: h.replace("temp_gyro_y_c", "temp_gyro_x_c")),
         "line 5: column temp_gyro_x_c appears twice"),
        ("time offset -1e6 s", lambda lines: lines[:HEADER] + [
            repr(float(row.split(",")[0]) - 1e6) + row[row.index(","):] for row in lines[HEADER:]],
         "line 6: the first timestamp is -999999 s"),
        ("time from 1000 s", lambda lines: lines[:HEADER] + [
            repr(float(row.split(",")[0]) + 999) + row[row.index(","):] for row in lines[HEADER:]],
         "line 6: the first timestamp is 1000 s"),
    ]


@pytest.mark.parametrize("change, message", [c[1:] for c in _text_cases()], ids=[c[0] for c in _text_cases()])
def test_what_the_grammar_does_not_allow_is_refused(tmp_path, change, message):
    path = _static_csv(tmp_path)
    path.write_text("\n".join(change(path.read_text().splitlines())) + "\n")
    with pytest.raises(LogError, match=message):
        read_log(path)


def test_crlf_is_read_as_lf_and_mixed_line_ends_are_refused(tmp_path):
    path = _static_csv(tmp_path)
    lf = read_log(path)
    text = path.read_text()
    crlf = tmp_path / "crlf.csv"
    crlf.write_bytes(text.replace("\n", "\r\n").encode())
    again = read_log(crlf)
    assert np.array_equal(again.dtheta, lf.dtheta) and again.meta == lf.meta
    mixed = tmp_path / "mixed.csv"
    lines = text.splitlines()
    mixed.write_bytes(("\r\n".join(lines[:30]) + "\r\n" + "\n".join(lines[30:]) + "\n").encode())
    with pytest.raises(LogError, match="line 31: line ends in LF, the lines before in CRLF"):
        read_log(mixed)


def _npz_cols(n=300, h=1.0):
    gyro, accel, _ = allan.static_record(imu.preset("nav-rlg"), n * h, 1.0 / h, seed=1)
    cols = {"time_s": np.arange(1, n + 1) * h}
    cols.update({f"gyro_{a}_radps": gyro[:, i] for i, a in enumerate("xyz")})
    cols.update({f"accel_{a}_mps2": accel[:, i] for i, a in enumerate("xyz")})
    return cols


@pytest.mark.parametrize("edit, message", [
    (lambda c: c.update(gyro_x_radps=c["gyro_x_radps"].astype(str)), "column gyro_x_radps holds <U"),
    (lambda c: c.update(extra=np.zeros(300)), "member 'extra' is not a log column"),
    (lambda c: c.update(meta=np.array(json.dumps({"lat_deg": 30.0, "note": "x" * 2000}))), "longer than 1024"),
    (lambda c: c.update(meta=np.array(json.dumps({"lat_deg": {"deg": 30}}))), "a value must be a string or"),
    (lambda c: c.update(meta=np.array([1.0, 2.0])), "meta must be one string"),
    (lambda c: c.update(time_s=c["time_s"] - 1e6), "row 0: the first timestamp"),
    (lambda c: c.update(dtheta_x_rad=c["gyro_x_radps"]), "not both"),
])
def test_npz_grammar(tmp_path, edit, message):
    cols = _npz_cols()
    cols["meta"] = np.array(json.dumps({"lat_deg": 30.0}))
    edit(cols)
    np.savez(tmp_path / "x.npz", **cols)
    with pytest.raises(LogError, match=message):
        read_log(tmp_path / "x.npz")


def test_degrees_are_caught_on_a_log_that_starts_moving(tmp_path):
    """The units check does not need a start at rest: a log that turns for its first two minutes
    (0.2 rad/s about the vertical) and then rests is read in radians silently, and in degrees with a
    warning naming its first window, while it turns: the accelerometers see no tilt, so the gyros'
    horizontal rate is the Earth's plus bias (57 x the Earth's in degrees, which a MEMS bias can also
    give: a warning, not a refusal); in g units it is refused by the whole log's mean |f|."""
    gyro, accel, _ = allan.static_record(imu.preset("nav-rlg"), 600.0, 1.0, seed=1)
    gyro[:120, 2] += 0.2  # body z is up: a turn about it leaves gravity where it was
    time = np.arange(1.0, 601.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert read_log(write_log(tmp_path / "rad.csv", time, gyro, accel, lat_deg=45.0)).warnings == []
    with pytest.warns(imu_log.LogWarning, match="line 6..line 65: the gyros turn 0.00.* rad/s .*about a horizontal axis .*degrees"):
        read_log(write_log(tmp_path / "deg.csv", time, np.degrees(gyro), accel, lat_deg=45.0))
    with pytest.raises(LogError, match="over the log is not gravity"):
        read_log(write_log(tmp_path / "g.csv", time, gyro, accel / 9.80665, lat_deg=45.0))
