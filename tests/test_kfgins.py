"""Our data in KF-GINS's text formats (sarins_fmu.kfgins): written files read back, frame changes on
known rotations, the raw-increment conversion against KF-GINS's corrections; and (slow) the comparison
with KF-GINS itself on the same data (sarins_fmu.experiments.kfgins_compare, the work of
benchmarks/kfgins_compare.py), when its binary is given."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sarins_fmu import aided, kfgins
from sarins_fmu import trajectory as tr
from sarins_fmu.experiments import kfgins_compare
from sarins_fmu.imu_log import ReadOptions, read_log
from sarins_fmu.rotations import euler_to_mat

D = math.radians


@pytest.fixture(scope="module")
def truth():
    """20 s at 100 Hz: a stop, an acceleration and a 6 deg/s turn with a climb."""
    segments = ({"kind": "stop", "duration": 2}, {"kind": "accelerate", "to_speed": 10, "accel": 2.0},
                {"kind": "turn", "rate_dps": 6, "duration": 5}, {"kind": "climb", "to_pitch_deg": 4, "duration": 4},
                {"kind": "cruise", "duration": 4})
    return tr.generate(tr.Trajectory(tr.Start(lat_deg=30.5, lon_deg=114.4, heading_deg=20.0), segments), 0.01)


def test_imu_file_reads_back_with_our_reader(tmp_path, truth):
    """Compensated increments written as they are (raw=False) come back through the i2Nav reader in
    right-front-up to the 13 printed digits."""
    t = 345600.0 + np.arange(1, truth.n_steps + 1) * truth.step
    path = kfgins.write_imu(tmp_path / "imu.txt", t, truth.dtheta, truth.dv, raw=False)
    first = path.read_text().splitlines()[0].split()
    assert len(first) == 7 and first[0] == "345600.010000000"
    log = read_log(path, ReadOptions(format="i2nav", lat_deg=30.5))
    assert log.axes == "frd" and log.quantity == "increments" and log.dtheta.shape == truth.dtheta.shape
    np.testing.assert_allclose(log.time - log.time[0], t - t[0], atol=1e-8)
    for got, want in ((log.dtheta, truth.dtheta), (log.dv, truth.dv)):
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12 * np.abs(want).max())


def test_raw_increments_undo_kfgins_corrections(truth):
    """KF-GINS's coning / rotation / sculling corrections applied to the raw increments give the
    compensated ones back up to terms of order |dtheta|^2 |dv| (1e-7 m/s here), while the corrections
    themselves are of order |dtheta| |dv| (the turn's: 7e-6 m/s)."""
    theta, dv = kfgins.swap_axes(truth.dtheta), kfgins.swap_axes(truth.dv)
    raw_t, raw_v = kfgins.raw_increments(theta, dv)
    back_t, back_v = kfgins.compensate(raw_t, raw_v)
    second = np.linalg.norm(theta, axis=1).max() ** 2 * np.linalg.norm(dv, axis=1).max()
    assert np.abs(raw_v - dv).max() > 50 * second
    assert np.abs(back_v - dv).max() < second
    assert np.abs(back_t - theta).max() < np.linalg.norm(theta, axis=1).max() ** 3


def test_frames_on_known_rotations():
    """ENU -> NED and right-front-up -> forward-right-down; our heading is counter-clockwise from north,
    KF-GINS's clockwise; pitch nose-up and roll right-wing-down positive in both."""
    np.testing.assert_array_equal(kfgins.swap_axes([1.0, 2.0, 3.0]), [2.0, 1.0, -3.0])
    np.testing.assert_allclose(kfgins.kfgins_euler(D(30.0), D(5.0), D(-10.0)), [D(-10.0), D(5.0), D(-30.0)],
                               atol=1e-15)
    np.testing.assert_allclose(kfgins.kfgins_euler(D(-90.0), 0.0, 0.0), [0.0, 0.0, D(90.0)], atol=1e-15)  # east
    yaw, pitch, roll = D(123.0), D(-7.0), D(15.0)
    c_ours = euler_to_mat(yaw, pitch, roll)
    c_kf = kfgins.zyx_to_mat(*kfgins.kfgins_euler(yaw, pitch, roll))
    for v_b in np.eye(3):  # the same body vector, expressed in each convention
        np.testing.assert_allclose(kfgins.swap_axes(c_ours @ v_b), c_kf @ kfgins.swap_axes(v_b), atol=1e-15)
    back = kfgins.our_euler(*np.array([kfgins.kfgins_euler(yaw, pitch, roll)]).T)
    np.testing.assert_allclose(back[0], [yaw - 2 * math.pi if yaw > math.pi else yaw, pitch, roll], atol=1e-14)


def test_gnss_file_columns(tmp_path):
    path = kfgins.write_gnss(tmp_path / "gnss.txt", [345601.0, 345602.0], np.radians([30.5, 30.6]),
                             np.radians([114.4, 114.5]), [20.0, 21.5], (1.0, 2.0, 3.0))
    rows = np.loadtxt(path)
    np.testing.assert_allclose(rows, [[345601.0, 30.5, 114.4, 20.0, 2.0, 1.0, 3.0],
                                      [345602.0, 30.6, 114.5, 21.5, 2.0, 1.0, 3.0]], rtol=1e-12)


def test_config_and_noise(tmp_path, truth):
    yaml = pytest.importorskip("yaml")
    noise = kfgins.noise_from_imu(aided.IMU_NOISE["tactical"])
    assert noise.arw == pytest.approx(0.1) and noise.vrw == pytest.approx(50e-6 * 9.80665 * 60.0, rel=1e-3)
    assert noise.initbgstd == pytest.approx(1.0) and noise.initbastd == pytest.approx(100e-6 * 9.80665 / 1e-5, rel=1e-3)
    # Gauss-Markov of 1000 h with the random walk's driving noise: 2 sigma^2 / T = rw^2
    rw_dph = 0.01 / 60.0  # deg/h/sqrt(s)
    assert 2 * noise.gbstd**2 / (noise.corrtime * 3600.0) == pytest.approx(rw_dph**2)
    row = truth.nav_rows()[-1]
    path = kfgins.write_config(tmp_path / "c.yaml", imu_path=tmp_path / "i.txt", gnss_path=tmp_path / "g.txt",
                               output_dir=tmp_path, rate_hz=100, start_sow=345600.0, nav_row=row,
                               pos_std_enu=(1.0, 2.0, 3.0), vel_std_enu=(0.1, 0.2, 0.3), att_std=(1e-3, 5e-3),
                               noise=noise, lever_rfu=(0.1, 0.2, 0.3))
    cfg = yaml.safe_load(path.read_text())
    assert cfg["imupath"] == str(tmp_path / "i.txt") and cfg["imudatarate"] == 100 and cfg["endtime"] == -1
    np.testing.assert_allclose(cfg["initpos"], [math.degrees(row[0]), math.degrees(row[1]), row[2]])
    np.testing.assert_allclose(cfg["initvel"], [row[4], row[3], -row[5]])
    np.testing.assert_allclose(np.radians(cfg["initatt"]), kfgins.kfgins_euler(*row[6:9]))
    np.testing.assert_allclose(cfg["initposstd"], [2.0, 1.0, 3.0])
    np.testing.assert_allclose(cfg["initattstd"], np.degrees([1e-3, 1e-3, 5e-3]))
    np.testing.assert_allclose(cfg["antlever"], [0.2, 0.1, -0.3])
    assert cfg["imunoise"]["corrtime"] == 1000.0


def test_nav_result_read_back(tmp_path, truth):
    """A result file in KF-GINS's layout (as its writer prints it) becomes our rows."""
    rows = truth.nav_rows()[::100]
    att = np.degrees(kfgins.kfgins_euler(rows[:, 6], rows[:, 7], rows[:, 8]))
    data = np.column_stack([np.zeros(len(rows)), 345600.0 + truth.time[::100], np.degrees(rows[:, 0]),
                            np.degrees(rows[:, 1]), rows[:, 2], kfgins.swap_axes(rows[:, 3:6]), att])
    np.savetxt(tmp_path / kfgins.NAV_FILE, data, fmt="%-15.9f")
    nav = kfgins.read_nav(tmp_path / kfgins.NAV_FILE)
    err = aided.nav_errors(nav.nav, rows)
    assert np.abs(err[:, :3]).max() < 1e-3 and np.abs(err[:, 3:6]).max() < 1e-9 and np.abs(err[:, 6:]).max() < 1e-10
    np.savetxt(tmp_path / "bad.nav", data[:, :9])
    with pytest.raises(ValueError, match="bad.nav: a KF-GINS navigation result has 11 columns"):
        kfgins.read_nav(tmp_path / "bad.nav")


def _kfgins_binary():
    path, why = kfgins_compare.find_binary()
    if path is None:
        pytest.skip(f"KF-GINS comparison: {why}")
    return path


@pytest.mark.slow
def test_same_accuracy_as_kfgins_on_the_same_data(tmp_path):
    """A 5-minute drive, tactical IMU, 1 Hz GNSS: our RMS position, velocity and attitude errors within
    10 % of KF-GINS's (or smaller)."""
    binary = _kfgins_binary()
    r = kfgins_compare.compare(binary, 5.0, workdir=tmp_path)
    assert r["compared_rows"] > 2900
    for key in ("position", "velocity", "attitude_deg", "horizontal", "vertical", "heading_deg"):
        assert r["ours"]["rms"][key] <= 1.1 * r["kfgins"]["rms"][key], key
