"""The C core's random streams (sarins_fmu/core/rng.h) through the binding, against closed forms.

Each statistic of n draws is checked against its exact value within a bound
of its sampling distribution (4 to 4.5 standard errors; a failure by chance has
a probability near 1e-5 per check): N(0, 1) moments, autocorrelations,
correlations between seeds and between stream ids, the IMU's noise terms
(angle random walk on the Allan curve, Gauss-Markov variance and correlation
time, turn-on bias, ageing), and reproducibility for a fixed seed."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

from sarins_fmu import allan, imu as imu_mod
from sarins_fmu.core import imu as core_imu, rng
from sarins_fmu.imu import IMU, StaticBase, TriadErrors
from sarins_fmu.imu_correlated import turn_on_bias
from sarins_fmu.units import DAY, DPH_TO_RPS, DPSH_TO_RPSS

N = 1_000_000
IDEAL = imu_mod.preset("ideal")


@pytest.mark.parametrize("seed, stream", [(0, 0), (1, 3), (2**64 - 1, 5), (123456789, 2**40)])
def test_normal_moments_are_those_of_n01(seed, stream):
    """Mean 0, variance 1, skewness 0, excess kurtosis 0; standard errors 1/sqrt(n), sqrt(2/n), sqrt(6/n),
    sqrt(24/n); and the Kolmogorov-Smirnov distance to the N(0, 1) CDF."""
    x = rng.normals(seed, stream, N)
    assert abs(x.mean()) < 4.5 / math.sqrt(N)
    assert abs(x.var() - 1.0) < 4.5 * math.sqrt(2.0 / N)
    assert abs(stats.skew(x)) < 4.5 * math.sqrt(6.0 / N)
    assert abs(stats.kurtosis(x)) < 4.5 * math.sqrt(24.0 / N)
    assert stats.kstest(x, "norm").pvalue > 1e-5


def test_uniforms_fill_the_unit_interval_evenly():
    u = rng.uniforms(7, 1, N)
    assert u.min() >= 0.0 and u.max() < 1.0
    assert abs(u.mean() - 0.5) < 4.5 * math.sqrt(1.0 / 12.0 / N)
    assert abs(u.var() - 1.0 / 12.0) < 4.5 * math.sqrt(1.0 / 180.0 / N)  # var of (u - 1/2)^2 is 1/180
    counts = np.bincount((u * 100).astype(int), minlength=100)
    assert stats.chisquare(counts).pvalue > 1e-5


def _corr(a, b):
    a, b = a - a.mean(), b - b.mean()
    return float(a @ b / math.sqrt((a @ a) * (b @ b)))


@pytest.mark.parametrize("seed", [0, 42])
def test_lag_1_to_10_autocorrelation_is_zero(seed):
    """White: each lag's sample autocorrelation has standard error 1/sqrt(n)."""
    for draw in (rng.normals, rng.uniforms):
        x = draw(seed, 0, N)
        for lag in range(1, 11):
            assert abs(_corr(x[:-lag], x[lag:])) < 4.5 / math.sqrt(N), (draw.__name__, lag)


def test_different_seeds_and_stream_ids_are_uncorrelated():
    """Neighbouring seeds, seeds a power of two apart and every pair of the IMU's stream ids: correlation
    at lags -2..2 within 4.5 / sqrt(n), and no two streams share a value."""
    n = 200_000
    pairs = [((0, 0), (1, 0)), ((1, 0), (2, 0)), ((2**63, 0), (2**63 + 1, 0)), ((5, 0), (5 + 2**32, 0)),
             ((0, 0), (0, 2**32))]
    pairs += [((3, a), (3, b)) for a in range(len(core_imu.STREAMS)) for b in range(a + 1, len(core_imu.STREAMS))]
    bound = 4.5 / math.sqrt(n)
    for (s1, n1), (s2, n2) in pairs:
        x, y = rng.normals(s1, n1, n), rng.normals(s2, n2, n)
        assert np.intersect1d(x, y).size == 0, (s1, n1, s2, n2)
        for lag in range(-2, 3):
            a, b = (x[lag:], y[:n - lag]) if lag >= 0 else (x[:n + lag], y[-lag:])
            assert abs(_corr(a, b)) < bound, (s1, n1, s2, n2, lag)


def test_a_fixed_seed_reproduces_its_draws_in_pieces_of_any_length():
    whole = rng.normals(11, 2, 1001)
    assert np.array_equal(whole, rng.normals(11, 2, 1001))
    assert not np.array_equal(whole, rng.normals(12, 2, 1001)) and not np.array_equal(whole, rng.normals(11, 3, 1001))
    state = rng.start(11, 2)
    pieces = np.concatenate([rng.fill_normals(state, k) for k in (1, 2, 3, 500, 0, 495)])  # odd cuts: the spare
    assert np.array_equal(pieces, whole)
    state[3] += 1.0  # an even increment: not a stream state
    with pytest.raises(ValueError, match="not a packed random stream state"):
        rng.fill_normals(state, 1)


def test_seeds_outside_64_bits_are_refused():
    for bad in (-1, 2**64, 1.5, "3"):
        with pytest.raises(ValueError, match="seed must be an integer in"):
            IMU(IDEAL, StaticBase(0.6), seed=bad)
        with pytest.raises(ValueError, match="seed must be an integer in"):
            rng.normals(bad, 0, 1)


def test_the_same_seed_gives_the_same_imu_run_and_another_seed_another():
    def run(seed):
        sensor = IMU(imu_mod.preset("mems"), StaticBase(0.6), seed=seed, aging_days=100.0)
        zero = np.zeros((50, 1))
        return np.hstack(sensor.step(zero, zero, zero))

    assert np.array_equal(run(5), run(5)) and not np.array_equal(run(5), run(6))


def test_angle_random_walk_reads_n_over_sqrt_tau_on_the_allan_curve():
    """White rate noise of density N: sigma_A(tau) = N / sqrt(tau) (IEEE Std 952); the Allan deviation from
    M = T / tau clusters has a relative standard error below 1 / sqrt(2 (M - 1))."""
    arw = np.array([0.1, 0.2, 0.3]) * DPSH_TO_RPSS
    vrw = np.array([1e-3, 2e-3, 3e-3])
    model = replace(IDEAL, gyro=TriadErrors(random_walk=arw), accel=TriadErrors(random_walk=vrw))
    duration = 1e5
    gyro, accel, _ = allan.static_record(model, duration, 1.0, seed=17)
    taus = np.array([1.0, 10.0, 100.0, 1000.0])
    _, adev = allan.allan_deviation(np.hstack([gyro, accel]), 1.0, taus=taus)
    expected = np.concatenate([arw, vrw])[None, :] / np.sqrt(taus)[:, None]
    sigma = 1.0 / np.sqrt(2.0 * (duration / taus - 1.0))
    assert np.all(np.abs(adev / expected - 1.0) < 4.0 * sigma[:, None])


def test_gauss_markov_bias_has_its_variance_and_correlation_time():
    """The bias the step holds over each interval is x_k = phi x_(k-1) + s sqrt(1 - phi^2) w_k from a
    stationary start: variance s^2 (relative standard error sqrt(2 (1 + phi^2) / (n (1 - phi^2)))),
    autocorrelation phi^k, and the correlation time -h / ln(phi) (standard error of the lag-1
    autocorrelation sqrt((1 - phi^2) / n))."""
    std, corr_time, h, n = 2.0 * DPH_TO_RPS, 20.0, 1.0, 200_000
    model = replace(IDEAL, gyro=TriadErrors(bias_instability=np.full(3, std), bias_corr_time=np.full(3, corr_time)))
    sensor = IMU(model, StaticBase(0.6), output_interval=h, internal_rate=1.0, seed=8)
    temps, out = np.empty((n, 6)), [np.empty((n, 3)) for _ in range(4)]
    core_imu.advance(sensor._table, np.full(n, 20.0), temps, *out)
    bias = out[0]  # g_bias: the Gauss-Markov state of each interval (every other gyro term is zero)
    phi = math.exp(-h / corr_time)
    var_se = math.sqrt(2.0 * (1 + phi**2) / (n * (1 - phi**2)))
    r1_se = math.sqrt((1 - phi**2) / n)
    for i in range(3):
        x = bias[:, i]
        assert abs(np.mean(x**2) / std**2 - 1.0) < 4.5 * var_se
        r1 = float(x[:-1] @ x[1:] / (x @ x))
        assert abs(r1 - phi) < 4.5 * r1_se
        assert abs(-h / math.log(r1) / corr_time - 1.0) < 4.5 * r1_se / (phi * -math.log(phi))
    assert abs(_corr(bias[:, 0], bias[:, 1])) < 4.5 * math.sqrt((1 + phi**2) / (n * (1 - phi**2)))


def test_turn_on_bias_across_seeds_has_its_std():
    model = imu_mod.preset("mems")
    std = np.concatenate([model.gyro.turn_on_bias, model.accel.turn_on_bias])
    n = 20_000
    draws = np.array([turn_on_bias(model, seed) for seed in range(n)]) / std
    assert np.all(np.abs(draws.mean(axis=0)) < 4.5 / math.sqrt(n))
    assert np.all(np.abs(draws.var(axis=0) - 1.0) < 4.5 * math.sqrt(2.0 / n))
    # the IMU draws the same turn-on bias at power-up
    sensor = IMU(model, StaticBase(0.6), seed=77)
    assert np.array_equal(sensor.state_arrays()[10][6], turn_on_bias(model, 77))


def test_ageing_has_the_variance_of_the_first_order_markov_walk():
    """m(t) from m(0) = 0: variance sigma^2 (1 - exp(-2 t / tau)) across seeds, in steps of any size."""
    model = imu_mod.preset("nav-rlg")
    n, days = 10_000, np.array([30.0, 180.0, 720.0])
    walk = np.array([imu_mod.aged_drift_poly(model, days, seed=s) for s in range(n)]) - model.axial_drift_poly
    var = model.aging_sigma**2 * (1.0 - np.exp(-2.0 * days * DAY / model.aging_corr_time))[:, None]
    assert np.all(np.abs(walk.mean(axis=0)) < 4.5 * np.sqrt(var / n))
    assert np.all(np.abs(walk.var(axis=0) / var - 1.0) < 4.5 * math.sqrt(2.0 / n))
    # the IMU of a seed ages its drift model by the same draw
    sensor = IMU(model, StaticBase(0.6), seed=3, aging_days=180.0)
    assert np.array_equal(sensor.drift_poly, imu_mod.aged_drift_poly(model, [180.0], seed=3)[0])
