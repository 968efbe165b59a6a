"""GNSS receiver model (sarins_fmu.gnss, core gnss.h): error statistics against the closed forms of
white and first-order Gauss-Markov noise, lever arm, outages, seeds, bad settings."""

import math

import numpy as np
import pytest

from sarins_fmu import earth, gnss
from sarins_fmu import trajectory as tr
from sarins_fmu.core import aided
from sarins_fmu.rotations import euler_to_mat

LAT = 0.5  # rad
N = 40000


def static_rows(n, yaw=0.0):
    rows = np.zeros((n, 9))
    rows[:, 0], rows[:, 2], rows[:, 6] = LAT, 100.0, yaw
    w = np.tile([0.0, earth.RATE * math.cos(LAT), earth.RATE * math.sin(LAT)], (n, 1))
    return rows, w


def errors(config, seed=1, dt=10.0, n=N, outages=()):
    """(n, 6) position (E, N, U m) and velocity errors of a receiver at rest."""
    rows, w = static_rows(n)
    out = aided.GnssState(config.array(), seed).fixes(dt * np.arange(1, n + 1), rows, w, outages)
    r_m, r_n = earth.radii(LAT)
    pos = np.column_stack([(out[:, 2] * (r_n + 100.0) * math.cos(LAT)), (out[:, 1] - LAT) * (r_m + 100.0),
                           out[:, 3] - 100.0])
    return np.column_stack([pos, out[:, 4:7]]), out[:, 0]


def autocorr(x, lag):
    x = x - x.mean()
    return float(np.dot(x[:-lag], x[lag:]) / np.dot(x, x))


def test_gauss_markov_variance_and_correlation_follow_the_closed_form():
    sigma = (1.0, 2.0, 3.0)
    cfg = gnss.GNSSConfig(pos_white_std=(0, 0, 0), pos_gm_std=sigma, pos_gm_tau=20.0,
                          vel_white_std=(0, 0, 0), vel_gm_std=(0.1, 0.1, 0.2), vel_gm_tau=10.0)
    e, _ = errors(cfg)
    # Var b = sigma^2; corr(lag k dt) = exp(-k dt / tau); 40000 samples with rho = 0.61: about 1.5 %
    # relative error of the variance
    for i, s in enumerate(sigma):
        assert e[:, i].var() == pytest.approx(s**2, rel=0.06)
        assert autocorr(e[:, i], 1) == pytest.approx(math.exp(-10.0 / 20.0), abs=0.03)
        assert autocorr(e[:, i], 2) == pytest.approx(math.exp(-20.0 / 20.0), abs=0.03)
    assert e[:, 3].var() == pytest.approx(0.01, rel=0.06)
    assert autocorr(e[:, 3], 1) == pytest.approx(math.exp(-1.0), abs=0.03)


def test_white_plus_gauss_markov_add_variances():
    cfg = gnss.GNSSConfig(pos_white_std=(0.5, 0.5, 0.5), pos_gm_std=(1.0, 1.0, 1.0), pos_gm_tau=20.0)
    e, _ = errors(cfg)
    total = 0.25 + 1.0
    assert e[:, 0].var() == pytest.approx(total, rel=0.06)
    # the white part does not correlate: lag-1 correlation sigma_gm^2 exp(-dt/tau) / total
    assert autocorr(e[:, 0], 1) == pytest.approx(math.exp(-0.5) / total, abs=0.03)
    white = gnss.GNSSConfig(pos_gm_std=(0, 0, 0), pos_white_std=(2.0, 2.0, 2.0))
    e, _ = errors(white, n=20000)
    assert e[:, 1].var() == pytest.approx(4.0, rel=0.05)
    assert abs(autocorr(e[:, 1], 1)) < 0.03


def test_seeded_chunked_and_outages_keep_the_stream():
    cfg = gnss.PRESETS["sps"]
    a, valid = errors(cfg, seed=7, n=500, outages=[[600.0, 1200.0]])
    b, _ = errors(cfg, seed=7, n=500)
    c, _ = errors(cfg, seed=8, n=500)
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    t = 10.0 * np.arange(1, 501)
    assert np.array_equal(valid == 0, (t >= 600) & (t < 1200))
    rows, w = static_rows(500)
    state = aided.GnssState(cfg.array(), 7)
    parts = np.concatenate([state.fixes(t[:123], rows[:123], w[:123], []), state.fixes(t[123:], rows[123:], w[123:], [])])
    whole = aided.GnssState(cfg.array(), 7).fixes(t, rows, w, [])
    assert np.array_equal(parts, whole)


def test_lever_arm_position_and_rotation_velocity():
    cfg = gnss.GNSSConfig(pos_white_std=(0, 0, 0), pos_gm_std=(0, 0, 0), vel_white_std=(0, 0, 0),
                          vel_gm_std=(0, 0, 0), lever_arm=(0.0, 2.0, 1.0))
    rows, w = static_rows(1, yaw=math.pi / 2)  # heading west: the front points west
    rate = 0.1
    w[0] = euler_to_mat(math.pi / 2, 0.0, 0.0).T @ w[0]  # Earth rate in this body frame
    w[0, 2] += rate  # turning left at 0.1 rad/s
    out = aided.GnssState(cfg.array(), 0).fixes([1.0], rows, w, [])[0]
    r_m, r_n = earth.radii(LAT)
    assert out[2] * (r_n + 100.0) * math.cos(LAT) == pytest.approx(-2.0, rel=1e-12)
    assert out[3] == pytest.approx(101.0, rel=1e-15)
    # v = mat_nb (omega x l), omega x l = (-2 r, 0, 0) in the body: 0.2 m/s to the body's left = south
    assert out[5] == pytest.approx(-2.0 * rate, rel=1e-9)
    assert abs(out[4]) < 1e-12


def test_presets_carry_their_datasheet_numbers():
    assert math.hypot(*gnss.PRESETS["sps"].pos_std()[:1], 0) == pytest.approx(2.5 / 1.1774, rel=1e-12)
    assert gnss.PRESETS["sbas"].pos_std()[0] == pytest.approx(2.0 / 1.1774, rel=1e-12)
    assert gnss.PRESETS["rtk"].pos_std()[0] == pytest.approx(0.01 / 1.1774, rel=1e-12)
    assert gnss.PRESETS["sps"].vel_std()[0] == pytest.approx(0.05 / 0.6745, rel=1e-12)


def test_simulate_on_a_trajectory_and_bad_settings():
    truth = tr.generate(tr.Trajectory(tr.Start(lat_deg=30.0), ({"kind": "stop", "duration": 30},)), 0.1)
    fixes = gnss.simulate(truth, gnss.preset("sps", rate_hz=5.0, latency=0.2), seed=3, outages=[[10, 20]])
    assert fixes.time.size == 150 and fixes.time[0] == pytest.approx(0.2)
    assert np.allclose(fixes.available - fixes.time, 0.2)
    assert (~fixes.valid).sum() == 50
    with pytest.raises(ValueError, match="above the IMU rate"):
        gnss.simulate(truth, gnss.preset("sps", rate_hz=20.0), seed=0)
    with pytest.raises(ValueError, match="outage 20:40"):
        gnss.simulate(truth, gnss.PRESETS["sps"], seed=0, outages=[[20, 40]])
    with pytest.raises(ValueError, match="negative"):
        gnss.GNSSConfig(pos_white_std=(-1.0, 1.0, 1.0))
    bad = gnss.PRESETS["sps"].array()
    bad[5] = -1.0
    with pytest.raises(ValueError, match="negative"):
        aided.GnssState(bad, 0)
