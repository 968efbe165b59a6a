"""Tests of sarins_fmu.identify.rls (quadratic drift model, forgetting-factor RLS)."""

import json

import numpy as np
import pytest
from numpy.testing import assert_allclose

from sarins_fmu.identify.modelfile import ModelFileError
from sarins_fmu.identify.rls import (
    MONTH,
    ForgettingRLS,
    RLSSettings,
    fit_quadratic_temperature_model,
    forgetting_least_squares,
    rls_update,
    time_scaled_factor,
)

DAY = 86400.0  # s


def _stops(n=20, seed=0, unequal=True):
    """Random stop temperatures (°C), drifts (°/h) and times (s), as in seed 002."""
    rng = np.random.default_rng(seed)
    temperature = rng.uniform(0.0, 50.0, n)
    if unequal:
        time = np.sort(rng.uniform(1.0, 300.0, n)) * DAY
        time[6] = time[5]  # two stops on the same day
    else:
        time = np.arange(n) * MONTH
    drift = 2e-5 * temperature**2 - 1e-3 * temperature + 0.01 + 1e-3 * rng.standard_normal(n)
    return temperature, drift, time


def _wls_by_hand(temperature, drift, weights, prior=None):
    """Weighted LS from the definition: sqrt-weighted rows, prior as extra rows."""
    h = np.column_stack([temperature**2, temperature, np.ones_like(temperature)])
    a = h * np.sqrt(weights)[:, None]
    b = drift * np.sqrt(weights)
    if prior is not None:
        x0, p0, w0 = prior
        # (x - x0)' P0^-1 (x - x0) = |U (x - x0)|^2 with U' U = P0^-1
        u = np.linalg.cholesky(np.linalg.inv(p0)).T
        a = np.vstack([a, np.sqrt(w0) * u])
        b = np.concatenate([b, np.sqrt(w0) * u @ x0])
    x = np.linalg.lstsq(a, b, rcond=None)[0]
    return x, np.linalg.inv(a.T @ a)


def _run_rls(rls, temperature, drift, time):
    for tk, zk, tt in zip(temperature, drift, time):
        rls.update(tk, zk, tt)
    return rls


@pytest.mark.parametrize("unequal", [True, False], ids=["unequal-gaps", "monthly-gaps"])
@pytest.mark.parametrize("lam", [0.8, 0.5])
def test_ff_rls_equals_batch_weighted_ls(lam, unequal):
    temperature, drift, time = _stops(unequal=unequal)
    settings = RLSSettings(forgetting_factor=lam)
    # start from the first three points' batch: no extra prior, so exact equality
    rls = ForgettingRLS.from_calibration(temperature[:3], drift[:3], time[:3], settings)
    _run_rls(rls, temperature[3:], drift[3:], time[3:])
    weights = lam ** ((time[-1] - time) / MONTH)
    x_batch, p_batch = _wls_by_hand(temperature, drift, weights)
    assert_allclose(rls.parameters, x_batch, rtol=1e-10)
    assert_allclose(rls.covariance, p_batch, rtol=1e-8)
    # the library's batch twin agrees too
    x_lib, p_lib = forgetting_least_squares(temperature, drift, time, settings=settings)
    assert_allclose(rls.parameters, x_lib, rtol=1e-10)
    assert_allclose(rls.covariance, p_lib, rtol=1e-10)


def test_ff_rls_with_prior_equals_batch_with_forgotten_prior():
    temperature, drift, time = _stops()
    x0 = np.array([1.5e-5, -8e-4, 0.012])
    p0 = np.diag([1e-7, 1e-3, 1.0])
    t0 = -10.0 * DAY
    rls = _run_rls(ForgettingRLS(x0, p0, t0), temperature, drift, time)
    lam = 0.8
    weights = lam ** ((time[-1] - time) / MONTH)
    prior_weight = lam ** ((time[-1] - t0) / MONTH)
    x_batch, _ = _wls_by_hand(temperature, drift, weights, (x0, p0, prior_weight))
    assert_allclose(rls.parameters, x_batch, rtol=1e-10)
    x_lib, _ = forgetting_least_squares(temperature, drift, time, prior=(x0, p0, t0))
    assert_allclose(rls.parameters, x_lib, rtol=1e-10)


def test_lambda_one_is_ordinary_least_squares():
    temperature, drift, time = _stops(n=15, seed=4)
    settings = RLSSettings(forgetting_factor=1.0)
    rls = ForgettingRLS.from_calibration(temperature[:3], drift[:3], time[:3], settings)
    _run_rls(rls, temperature[3:], drift[3:], time[3:])
    ordinary = np.polyfit(temperature, drift, 2)
    assert_allclose(rls.parameters, ordinary, rtol=1e-10)
    assert_allclose(fit_quadratic_temperature_model(temperature, drift).coefficients, ordinary, rtol=1e-10)
    # ordinary RLS, step by step with lam = 1, from the same start
    start = ForgettingRLS.from_calibration(temperature[:3], drift[:3], 0.0, settings)
    x, p = start.parameters, start.covariance
    for tk, zk in zip(temperature[3:], drift[3:]):
        x, p = rls_update(x, p, np.array([tk**2, tk, 1.0]), zk, 1.0)
    assert_allclose(x, ordinary, rtol=1e-10)


def test_time_scaled_factor_values():
    assert time_scaled_factor(0.8, MONTH) == pytest.approx(0.8, rel=1e-15)
    assert time_scaled_factor(0.8, 2 * MONTH) == pytest.approx(0.64, rel=1e-14)
    assert time_scaled_factor(0.8, 15 * DAY) == pytest.approx(np.sqrt(0.8), rel=1e-14)
    assert time_scaled_factor(0.8, 0.0) == 1.0
    assert time_scaled_factor(0.8, 5 * MONTH, time_scale=None) == 0.8
    assert MONTH == 30 * DAY
    with pytest.raises(ValueError):
        time_scaled_factor(0.8, -1.0)


def test_information_weights_equal_and_unequal_gaps():
    """P^-1 after the updates is sum_i lambda^(age_i / m) h_i h_i'."""
    temperature = np.array([5.0, 20.0, 35.0, 10.0, 45.0])
    drift = np.array([0.01, 0.0, 0.02, 0.005, 0.03])
    for time in (np.arange(5) * MONTH, np.array([0.0, 0.0, 3.0, 3.5, 11.0]) * DAY):
        rls = ForgettingRLS.from_calibration(temperature[:3], drift[:3], time[:3])
        _run_rls(rls, temperature[3:], drift[3:], time[3:])
        info = np.zeros((3, 3))
        for tk, tt in zip(temperature, time):
            h = np.array([tk**2, tk, 1.0])
            info += 0.8 ** ((time[-1] - tt) / MONTH) * np.outer(h, h)
        assert_allclose(np.linalg.inv(rls.covariance), info, rtol=1e-8)


def test_two_half_gaps_forget_like_one_full_gap():
    temperature = np.array([5.0, 20.0, 35.0, 40.0])
    drift = np.array([0.01, 0.0, 0.02, 0.025])
    a = ForgettingRLS.from_calibration(temperature[:3], drift[:3], 0.0)
    a.update(30.0, 0.01, 15 * DAY)
    a.update(40.0, 0.025, 30 * DAY)
    b = ForgettingRLS.from_calibration(temperature[:3], drift[:3], 0.0)
    b.update(30.0, 0.01, 15 * DAY)
    b.update(40.0, 0.025, 15 * DAY + 15 * DAY)
    assert_allclose(a.covariance, b.covariance, rtol=1e-12)
    # a point taken at calibration time now weighs 0.8 (one month old)
    h = np.array([40.0**2, 40.0, 1.0])
    before = ForgettingRLS.from_calibration(temperature[:3], drift[:3], 0.0)
    info_cal = np.linalg.inv(before.covariance)
    info_30 = np.linalg.inv(a.covariance)
    h30 = np.array([30.0**2, 30.0, 1.0])
    expected = 0.8 * info_cal + np.sqrt(0.8) * np.outer(h30, h30) + np.outer(h, h)
    assert_allclose(info_30, expected, rtol=1e-8)


def test_per_update_forgetting_without_time_scale():
    temperature, drift, time = _stops(n=10, seed=2)
    settings = RLSSettings(forgetting_factor=0.7, time_scale=None)
    rls = ForgettingRLS.from_calibration(temperature[:3], drift[:3], time[:3], settings)
    _run_rls(rls, temperature[3:], drift[3:], time[3:])
    weights = 0.7 ** np.arange(9, -1, -1.0)
    assert_allclose(rls.parameters, _wls_by_hand(temperature, drift, weights)[0], rtol=1e-10)


def test_forgetting_tracks_a_changed_model():
    rng = np.random.default_rng(5)
    old = np.array([2e-5, -1e-3, 0.01])
    new = np.array([1e-5, -5e-4, 0.02])
    cal_t = np.linspace(0.0, 50.0, 11)
    cal_z = np.polyval(old, cal_t)
    temperature = rng.uniform(0.0, 50.0, 20)
    time = np.linspace(30.0, 300.0, 20) * DAY
    drift = np.polyval(new, temperature)
    ff = _run_rls(ForgettingRLS.from_calibration(cal_t, cal_z), temperature, drift, time)
    plain = _run_rls(
        ForgettingRLS.from_calibration(cal_t, cal_z, settings=RLSSettings(1.0)), temperature, drift, time
    )
    grid = np.linspace(0.0, 50.0, 51)
    err_ff = np.abs(ff.predict(grid) - np.polyval(new, grid)).max()
    err_plain = np.abs(plain.predict(grid) - np.polyval(new, grid)).max()
    assert err_ff < 0.5 * err_plain


def test_fit_quadratic_temperature_model_residuals():
    temperature = np.array([-10.0, 0.0, 10.0, 20.0, 30.0, 40.0])
    coefficients = np.array([3e-5, -2e-3, 0.05])
    # a residual orthogonal to T^2, T, 1 (a cubic-like pattern) leaves the fit unchanged
    h = np.column_stack([temperature**2, temperature, np.ones(6)])
    bump = np.array([1.0, -3.0, 2.0, 2.0, -3.0, 1.0])
    bump -= h @ np.linalg.lstsq(h, bump, rcond=None)[0]
    bump *= 1e-4 / np.abs(bump).max()
    fit = fit_quadratic_temperature_model(temperature, h @ coefficients + bump)
    assert_allclose(fit.coefficients, coefficients, rtol=1e-9)
    assert_allclose(fit.residuals, bump, atol=1e-15)
    assert fit.residual_max == pytest.approx(1e-4, rel=1e-9)
    assert fit.residual_rms == pytest.approx(np.sqrt(np.mean(bump**2)), rel=1e-9)
    assert_allclose(fit.predict(25.0), np.polyval(coefficients, 25.0), rtol=1e-12)


def test_state_round_trip_and_continuation(tmp_path):
    temperature, drift, time = _stops()
    rls = ForgettingRLS.from_calibration(temperature[:5], drift[:5], time[:5])
    _run_rls(rls, temperature[5:10], drift[5:10], time[5:10])
    via_dict = ForgettingRLS.from_dict(json.loads(json.dumps(rls.to_dict())))
    via_file = ForgettingRLS.load(rls.save(tmp_path / "rls.json"))
    for other in (via_dict, via_file):
        assert other.n_updates == rls.n_updates == 5
        assert other.time == rls.time
    for r in (rls, via_dict, via_file):
        _run_rls(r, temperature[10:], drift[10:], time[10:])
    assert np.array_equal(via_dict.parameters, rls.parameters)
    assert np.array_equal(via_file.parameters, rls.parameters)


def test_bad_state_file(tmp_path):
    path = ForgettingRLS([0.0, 0.0, 1.0], np.eye(3)).save(tmp_path / "s.json")
    doc = json.loads(path.read_text())
    doc["arrays"]["covariance"]["data"] = [1, 2, 3, 2, -1, 0, 3, 0, 1]  # not positive definite
    path.write_text(json.dumps(doc))
    with pytest.raises(ModelFileError, match="s.json.*positive definite"):
        ForgettingRLS.load(path)


def test_bad_inputs_rejected():
    rls = ForgettingRLS([0.0, 0.0, 1.0], np.eye(3), time=10.0)
    with pytest.raises(ValueError, match="earlier"):
        rls.update(20.0, 0.01, 5.0)
    with pytest.raises(ValueError, match="finite"):
        rls.update(np.nan, 0.01, 20.0)
    with pytest.raises(ValueError, match="distinct temperatures"):
        ForgettingRLS.from_calibration([20.0, 20.0, 30.0], [0.0, 0.1, 0.2])
    with pytest.raises(ValueError, match="symmetric"):
        ForgettingRLS([0.0, 0.0, 1.0], [[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    with pytest.raises(ValueError, match="forgetting_factor"):
        RLSSettings(forgetting_factor=1.2)
    with pytest.raises(ValueError, match="time_scale"):
        RLSSettings(time_scale=0.0)
    with pytest.raises(ValueError, match="non-decreasing"):
        forgetting_least_squares([0.0, 10.0, 20.0], [0.0, 1.0, 2.0], [0.0, 2.0, 1.0])
