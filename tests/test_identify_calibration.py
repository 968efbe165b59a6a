"""Tests of sarins_fmu.identify.calibration (seed 003 traditional model)."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from sarins_fmu.identify.calibration import (
    TriadCalibration,
    compensate_triad,
    cube_orientations,
    fit_triad,
    rate_test_truth,
    triad_model,
    tumble_truth,
)

EARTH_RATE = 7.292115e-5  # rad/s, test value
LAT = np.radians(28.222)  # rad
GRAVITY = 9.7913  # m/s^2, test value
EARTH_RATE_N = EARTH_RATE * np.array([0.0, np.cos(LAT), np.sin(LAT)])  # ENU

GYRO = TriadCalibration(
    bias=np.array([2.0e-5, -3.5e-5, 1.2e-5]),  # rad/s
    scale_factor=np.array([1.5e-4, -2.2e-4, 3.1e-4]),
    misalignment=np.array([[0.0, 1.1e-3, -0.7e-3], [0.4e-3, 0.0, 2.3e-3], [-1.9e-3, 0.8e-3, 0.0]]),
)
ACCEL = TriadCalibration(
    bias=np.array([0.012, -0.020, 0.034]),  # m/s^2
    scale_factor=np.array([-4.0e-4, 2.5e-4, 6.0e-4]),
    misalignment=np.array([[0.0, -2.0e-3, 1.0e-3], [1.5e-3, 0.0, -0.5e-3], [0.3e-3, 2.2e-3, 0.0]]),
)


def _gyro_truth():
    _, tumble_rate = tumble_truth(cube_orientations(), GRAVITY, EARTH_RATE_N)
    rates = np.radians(np.linspace(-200.0, 200.0, 22))  # 22 rate points per axis, rad/s
    rate_tests = [rate_test_truth(rates, axis, EARTH_RATE_N[2]) for axis in range(3)]
    return np.vstack([tumble_rate, *rate_tests])


def test_cube_orientations_are_the_24_rotations():
    c = cube_orientations()
    assert c.shape == (24, 3, 3)
    assert_allclose(np.einsum("kij,kil->kjl", c, c), np.broadcast_to(np.eye(3), (24, 3, 3)))
    assert_allclose(np.linalg.det(c), 1.0)
    assert len({m.tobytes() for m in c}) == 24
    assert_allclose(c.sum(axis=0), 0.0, atol=0)  # balanced: projections average to zero


def test_tumble_truth_projects_gravity_and_earth_rate():
    identity = np.eye(3)[None]
    f, w = tumble_truth(identity, GRAVITY, EARTH_RATE_N)
    assert_allclose(f, [[0.0, 0.0, GRAVITY]])
    assert_allclose(w, [EARTH_RATE_N])
    # body x pointing up (x_b = up, y_b = north, z_b = west ... right-handed)
    mat_nb = np.array([[[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]])
    f, w = tumble_truth(mat_nb, GRAVITY, EARTH_RATE_N)
    assert_allclose(f, [[GRAVITY, 0.0, 0.0]], atol=1e-15)
    assert_allclose(w[0], [EARTH_RATE_N[2], EARTH_RATE_N[1], 0.0], atol=1e-20)


def test_accelerometer_triad_recovered_from_tumble():
    force, _ = tumble_truth(cube_orientations(), GRAVITY, EARTH_RATE_N)
    fit = fit_triad(force, triad_model(ACCEL, force))
    assert_allclose(fit.bias, ACCEL.bias, rtol=1e-9)
    assert_allclose(fit.scale_factor, ACCEL.scale_factor, rtol=1e-9)
    assert_allclose(fit.misalignment, ACCEL.misalignment, rtol=1e-9, atol=0)


def test_gyro_triad_recovered_from_tumble_and_rate_tests():
    truth = _gyro_truth()
    fit = fit_triad(truth, triad_model(GYRO, truth))
    assert_allclose(fit.bias, GYRO.bias, rtol=1e-9)
    assert_allclose(fit.scale_factor, GYRO.scale_factor, rtol=1e-9)
    assert_allclose(fit.misalignment, GYRO.misalignment, rtol=1e-9, atol=0)


def test_ignoring_earth_rate_in_tumble_truth_spoils_the_fit():
    truth = _gyro_truth()
    measured = triad_model(GYRO, truth)
    wrong = truth.copy()
    wrong[:24] = 0.0  # "a resting gyro sees nothing"
    fit = fit_triad(wrong, measured)
    residual = measured - triad_model(fit, wrong)
    assert np.abs(residual).max() > 0.3 * EARTH_RATE


def test_compensation_inverts_the_model():
    rng = np.random.default_rng(0)
    true = rng.normal(scale=2.0, size=(50, 3))
    assert_allclose(compensate_triad(GYRO, triad_model(GYRO, true)), true, rtol=1e-12, atol=1e-14)
    # a fitted model compensates noisy data down to the noise level
    truth = _gyro_truth()
    noise = 1e-6 * rng.standard_normal(truth.shape)
    fit = fit_triad(truth, triad_model(GYRO, truth) + noise)
    raw = triad_model(GYRO, true)
    assert np.abs(compensate_triad(fit, raw) - true).max() < 1e-5
    assert np.abs(raw - true).max() > 1e-3


def test_round_trip_plain_data():
    back = TriadCalibration.from_dict(GYRO.to_dict())
    assert_allclose(back.matrix, GYRO.matrix, rtol=0)
    assert_allclose(back.bias, GYRO.bias, rtol=0)


def test_bad_inputs_rejected():
    with pytest.raises(ValueError, match="excite"):
        fit_triad(rate_test_truth([1.0, 2.0, 3.0, 4.0], 0), np.zeros((4, 3)))
    with pytest.raises(ValueError, match="shape"):
        fit_triad(np.zeros((5, 3)), np.zeros((6, 3)))
    with pytest.raises(ValueError, match="NaN"):
        fit_triad(np.full((5, 3), np.nan), np.zeros((5, 3)))
    with pytest.raises(ValueError, match="zero diagonal"):
        TriadCalibration(np.zeros(3), np.zeros(3), np.eye(3))
    with pytest.raises(ValueError, match="axis"):
        rate_test_truth([1.0], 3)
