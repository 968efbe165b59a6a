"""Stop Kalman filter of seed 002 (sarins_fmu.kalman) on simulated stops."""

import math

import numpy as np
import pytest

from sarins_fmu.experiments.online_rls import simulate_stop
from sarins_fmu.kalman import EPS_Z, N_STATES, StopFilterSettings, StopKalmanFilter
from sarins_fmu.units import DEG_TO_RAD

PREMISE_SEEDS = range(20)


def test_premise_unit_30_minutes_within_0002_dph():
    """The paper's claim (30 min -> within 0.002 deg/h) on the unit whose noise
    allows it: 20 seeds at random temperatures, every one within 0.002."""
    errors = np.array([simulate_stop(imu="premise", seed=s, temperature=float(np.random.default_rng(s).uniform(0, 50)))
                       ["error_dph"] for s in PREMISE_SEEDS])
    assert np.all(np.abs(errors) < 0.002), errors
    assert np.sqrt(np.mean(errors**2)) < 0.0012


def test_nav_rlg_30_minutes_is_limited_by_its_angle_random_walk():
    """nav-rlg (ARW 0.0005 deg/sqrt(h)): the filter itself says 30 min cannot
    give 0.002 deg/h; its error is consistent with its own 1 sigma."""
    r = simulate_stop(imu="nav-rlg", seed=3, temperature=30.0)
    assert 0.008 < r["std_dph"] < 0.03
    assert abs(r["error_dph"]) < 3.0 * r["std_dph"]
    assert r["std_curve_dph"][-1] < r["std_curve_dph"][0]


def test_noise_free_unit_recovers_a_constant_drift():
    """Ideal sensors plus a constant azimuth drift of 0.01 deg/h: the estimate
    converges to it (closed-form truth, no noise)."""
    drift = 0.01 * DEG_TO_RAD / 3600
    r = simulate_stop(imu="ideal", seed=1, coefficients=[0.0, 0.0, drift], duration=1800.0)
    assert r["truth_dph"] == pytest.approx(0.01)
    assert abs(r["error_dph"]) < 2e-4


def test_compensated_stop_measures_the_total_drift():
    """With the INS compensating a model value, the stop's measurement is the
    model value plus the estimated residual: the same drift as uncompensated."""
    coef = np.array([0.0, 0.0, 0.004 * DEG_TO_RAD / 3600])
    raw = simulate_stop(imu="ideal", seed=2, coefficients=coef)
    comp = simulate_stop(imu="ideal", seed=2, coefficients=coef, compensation=[0.0, 0.0, 0.003 * DEG_TO_RAD / 3600])
    assert comp["estimate_dph"] == pytest.approx(raw["estimate_dph"], abs=2e-4)
    assert comp["estimate_dph"] == pytest.approx(0.004, abs=2e-4)


def test_reset_restores_the_initial_covariance_and_timer():
    settings = StopFilterSettings()
    kf = StopKalmanFilter(40 * DEG_TO_RAD, settings)
    rows = 100
    kf.step(np.zeros((rows, 2)), np.zeros((rows, 3)), 0.0, 25.0)
    assert kf.elapsed == rows
    assert kf.drift_std < math.sqrt(settings.initial_covariance()[EPS_Z, EPS_Z])
    kf.reset()
    assert kf.elapsed == 0.0 and np.all(kf.x == 0.0)
    np.testing.assert_array_equal(kf.p, settings.initial_covariance())
    assert kf.p.shape == (N_STATES, N_STATES)


def test_blocks_and_single_rows_give_the_same_filter():
    rng = np.random.default_rng(0)
    vel = rng.normal(0, 0.01, (50, 2))
    att = np.column_stack([np.linspace(0, 3, 50), np.zeros(50), np.zeros(50)])
    a = StopKalmanFilter(0.5)
    b = StopKalmanFilter(0.5)
    a.step(vel, att)
    for k in range(50):
        b.step(vel[k], att[k])
    np.testing.assert_allclose(a.x, b.x, rtol=1e-12, atol=1e-30)


def test_bad_inputs_are_rejected():
    with pytest.raises(ValueError, match="89.9"):
        StopKalmanFilter(math.radians(95))
    with pytest.raises(ValueError, match="step"):
        StopKalmanFilter(0.5, dt=0.0)
    with pytest.raises(ValueError, match="positive"):
        StopFilterSettings(arw=-1.0)
    kf = StopKalmanFilter(0.5)
    with pytest.raises(ValueError, match="NaN"):
        kf.step([np.nan, 0.0], [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="attitude"):
        kf.step(np.zeros((3, 2)), np.zeros((2, 3)))


def test_history_is_bounded_and_does_not_change_the_estimate():
    """A long stop (a parked vehicle) costs no memory: by default no history,
    with a limit at most that many rows; the estimate is the same either way."""
    rng = np.random.default_rng(0)
    vel, att = rng.normal(0, 1e-3, (300, 2)), np.tile([0.1, 0.0, 0.0], (300, 1))
    lat = 30 * DEG_TO_RAD
    kept, none = StopKalmanFilter(lat, history_limit=250), StopKalmanFilter(lat)
    for k in range(0, 300, 100):
        kept.step(vel[k:k + 100], att[k:k + 100])
        none.step(vel[k:k + 100], att[k:k + 100])
    assert none.history == [] and none.convergence().shape == (0, 3)
    assert kept.convergence().shape == (250, 3)
    assert kept.drift_estimate == none.drift_estimate
    with pytest.raises(ValueError):
        StopKalmanFilter(lat, history_limit=-1)
