"""Fig. 2 online logic of seed 002 (sarins_fmu.identify.online)."""

import numpy as np
import pytest

from sarins_fmu.identify.online import OnlineDriftUpdater, UpdaterSettings, prior_covariance
from sarins_fmu.identify.rls import ForgettingRLS
from sarins_fmu.kalman import StopKalmanFilter
from sarins_fmu.units import DAY, DPH_TO_RPS

LAT = np.radians(40.0)
COEF = np.array([1e-6, -4e-5, 0.0025]) * DPH_TO_RPS


def _rls():
    return ForgettingRLS(COEF, prior_covariance(11, 0, 50), 0.0)


def _rows(pattern, seed=0):
    """Rows (time, speed, velocity, attitude, temperature) for a pattern of
    (seconds, moving) segments; the INS velocity drifts slowly at the stop."""
    rng = np.random.default_rng(seed)
    speed = np.concatenate([np.full(int(n), 10.0 if moving else 0.0) for n, moving in pattern])
    n = speed.size
    time = 5 * DAY + np.arange(1, n + 1, dtype=float)
    vel = np.cumsum(rng.normal(0, 1e-4, (n, 2)), axis=0) + 0.01 * np.sin(np.arange(n) / 200.0)[:, None]
    att = np.column_stack([np.arange(n) * 0.05, np.zeros(n), np.zeros(n)])
    temp = 30.0 + np.arange(n) * 1e-3
    return time, speed, vel, att, temp


def test_short_stop_resets_the_filter_and_keeps_the_model():
    up = OnlineDriftUpdater(_rls(), LAT)
    rows = _rows([(100, True), (1200, False), (50, True)])
    comp = up.step(*rows)
    assert up.rls.n_updates == 0
    np.testing.assert_array_equal(up.rls.parameters, COEF)
    assert [e[1] for e in up.events] == ["reset"]
    assert up.events[0][2] == pytest.approx(1200.0)
    assert not up.stopped and up.timer == 0.0 and up.filter.elapsed == 0.0
    np.testing.assert_allclose(comp, np.polyval(COEF, rows[4]))


def test_long_stop_updates_the_model_with_the_stop_estimate_when_moving_off():
    up = OnlineDriftUpdater(_rls(), LAT)
    time, speed, vel, att, temp = _rows([(100, True), (2000, False), (50, True)])
    comp = up.step(time, speed, vel, att, temp)
    # the same stop through the filter by hand
    kf = StopKalmanFilter(LAT)
    still = slice(100, 2100)
    kf.step(vel[still], att[still], comp[still], temp[still])
    ref = _rls()
    ref.update(kf.mean_temperature, kf.drift_estimate, time[2100])
    assert up.rls.n_updates == 1 and [e[1] for e in up.events] == ["update"]
    np.testing.assert_allclose(up.rls.parameters, ref.parameters, rtol=1e-12)
    # rows from the moving-off row on are compensated with the updated model
    np.testing.assert_allclose(comp[2100:], np.polyval(ref.parameters, temp[2100:]), rtol=1e-12)
    np.testing.assert_allclose(comp[:2100], np.polyval(COEF, temp[:2100]), rtol=1e-12)


def test_row_by_row_equals_blocks():
    rows = _rows([(30, True), (1900, False), (20, True), (300, False), (10, True)], seed=3)
    a = OnlineDriftUpdater(_rls(), LAT)
    b = OnlineDriftUpdater(_rls(), LAT)
    comp_a = a.step(*rows)
    comp_b = np.concatenate([b.step(*(x[k:k + 1] for x in rows)) for k in range(rows[0].size)])
    np.testing.assert_allclose(comp_a, comp_b, rtol=1e-12)
    np.testing.assert_allclose(a.rls.parameters, b.rls.parameters, rtol=1e-12)
    assert [e[1] for e in a.events] == [e[1] for e in b.events] == ["update", "reset"]


def test_inactive_ins_rows_are_not_a_stop():
    up = OnlineDriftUpdater(_rls(), LAT)
    time, speed, vel, att, temp = _rows([(2000, False), (10, True)])
    up.step(time, speed, vel, att, temp, active=np.arange(time.size) >= 1900)
    assert [e[1] for e in up.events] == ["reset"] and up.events[0][2] == pytest.approx(100.0)


def test_threshold_setting_and_bad_input():
    up = OnlineDriftUpdater(_rls(), LAT, settings=UpdaterSettings(time_threshold=600.0))
    up.step(*_rows([(10, True), (700, False), (10, True)]))
    assert up.rls.n_updates == 1
    with pytest.raises(ValueError):
        UpdaterSettings(time_threshold=0.0)
    with pytest.raises(ValueError, match="NaN"):
        up.step([1.0], [np.nan], [[0.0, 0.0]], [[0.0, 0.0, 0.0]], [20.0])
    with pytest.raises(ValueError):
        prior_covariance(0.0)
