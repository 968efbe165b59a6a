"""Seed 002's online update in the C core (rls.h, stop_filter.h, online.h): the same numbers as plain
Python written from the equations, bit for bit, and the closed forms (a Kalman filter without process
noise is the batch least squares of its initial state; the RLS with lambda = 1 is batch least squares)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sarins_fmu import earth, rotations
from sarins_fmu.core import online as core
from sarins_fmu.core.smath import evaluate
from sarins_fmu.identify.online import OnlineDriftUpdater, UpdaterSettings, prior_covariance
from sarins_fmu.identify.rls import ForgettingRLS, RLSSettings, forgetting_least_squares, quadratic_regressors
from sarins_fmu.kalman import EPS_Z, StopFilterSettings, StopKalmanFilter
from sarins_fmu.units import DPH_TO_RPS

EPS = np.finfo(float).eps
DAY = 86400.0


# ------------------------------------------------------------------------------------------ the RLS
def _pow(x: float, y: float) -> float:
    """x ** y as the core computes it (sm_pow, smath.h)."""
    return float(evaluate("pow", x, y)[0])


def _dot(a, b) -> float:
    """sum a_i b_i from 0.0 in index order (the core's order)."""
    s = 0.0
    for u, v in zip(a, b):
        s += u * v
    return s


def _reference_update(x, p, temperature, drift, lam):
    """Eqs 16-18 in plain Python floats, written from the equations in the core's order."""
    h = [temperature * temperature, temperature, 1.0]
    ph = [_dot(p[i], h) for i in range(3)]
    denom = lam + _dot(h, ph)
    k = [ph[i] / denom for i in range(3)]
    innovation = drift - _dot(h, x)
    x = [x[i] + k[i] * innovation for i in range(3)]
    p = [[(p[i][j] - k[i] * ph[j]) / lam for j in range(3)] for i in range(3)]
    for i in range(3):
        for j in range(i + 1, 3):
            p[i][j] = p[j][i] = 0.5 * (p[i][j] + p[j][i])
    return x, p


@pytest.mark.parametrize("forgetting, time_scale", [(0.8, 30 * DAY), (0.5, 7 * DAY), (1.0, 30 * DAY), (0.9, None)])
def test_rls_equals_plain_python_bit_for_bit_on_random_sequences(forgetting, time_scale):
    """300 random stops (temperatures 0..50 degC, drifts around a quadratic, gaps of 0..20 days, two on the
    same day): every parameter and covariance entry after every update is the plain-Python value."""
    rng = np.random.default_rng(7)
    x0 = np.array([1e-6, -4e-5, 0.0025]) * DPH_TO_RPS
    rls = ForgettingRLS(x0, prior_covariance(11.0, 0.0, 50.0), 0.0, RLSSettings(forgetting, time_scale))
    x, p, t = list(rls.parameters), [list(r) for r in rls.covariance], 0.0
    for k in range(300):
        gap = 0.0 if k == 100 else float(rng.uniform(0.0, 20.0 * DAY))
        temp = float(rng.uniform(0.0, 50.0))
        drift = float((x0[0] * temp + x0[1]) * temp + x0[2] + 1e-9 * rng.standard_normal())
        t_new = t + gap
        lam = forgetting if time_scale is None else _pow(forgetting, (t_new - t) / time_scale)  # eq. 15
        x, p = _reference_update(x, p, temp, drift, lam)
        t = t_new
        rls.update(temp, drift, t)
        assert rls.parameters.tolist() == x and rls.covariance.tolist() == p, k
    assert rls.n_updates == 300 and rls.time == t


def test_rls_with_lambda_1_is_batch_least_squares():
    """lambda = 1: the recursion from a prior equals the batch least squares of the prior and all points
    (closed form), to the rounding the recursion accumulates: 50 updates, each moving x and P by a few
    eps relative times the conditioning of the information matrix."""
    rng = np.random.default_rng(3)
    temps = rng.uniform(0.0, 50.0, 50)
    drift = 2e-5 * temps**2 - 1e-3 * temps + 0.01 + 1e-3 * rng.standard_normal(50)
    p0 = prior_covariance(3.0, 0.0, 50.0)
    x0 = np.array([1e-5, -5e-4, 0.02])
    rls = ForgettingRLS(x0, p0, 0.0, RLSSettings(1.0))
    for t, z in zip(temps, drift):
        rls.update(t, z, 0.0)
    h = quadratic_regressors(temps)
    info = np.linalg.inv(p0) + h.T @ h
    x_batch = np.linalg.solve(info, np.linalg.solve(p0, x0) + h.T @ drift)
    cond = np.linalg.cond(info)
    bound = 50 * 10 * EPS * cond
    np.testing.assert_allclose(rls.parameters, x_batch, rtol=bound, atol=0)
    np.testing.assert_allclose(rls.covariance, np.linalg.inv(info), rtol=bound, atol=bound * np.abs(rls.covariance).max())
    # and with forgetting, the time-weighted batch (the module's own closed form)
    times = np.sort(rng.uniform(0.0, 200.0, 50)) * DAY
    ff = ForgettingRLS(x0, p0, 0.0, RLSSettings(0.8))
    for t, z, tt in zip(temps, drift, times):
        ff.update(t, z, tt)
    x_ff, p_ff = forgetting_least_squares(temps, drift, times, settings=RLSSettings(0.8), prior=(x0, p0, 0.0))
    np.testing.assert_allclose(ff.parameters, x_ff, rtol=bound, atol=0)
    np.testing.assert_allclose(ff.covariance, p_ff, rtol=bound, atol=bound * np.abs(p_ff).max())


def test_prior_covariance_is_the_inverse_of_the_calibration_information():
    """P0 (Cholesky inverse in the core) times the information of 11 nodes of weight points / 11 is the
    identity to cond * eps, and P0 is exactly symmetric and positive definite."""
    for points, lo, hi in ((11.0, 0.0, 50.0), (3.0, -40.0, 85.0), (1e3, 20.0, 20.5)):
        p0 = prior_covariance(points, lo, hi)
        nodes = np.linspace(lo, hi, 11)
        h = quadratic_regressors(nodes)
        info = h.T @ h * (points / 11.0)
        cond = np.linalg.cond(info)
        scale = np.sqrt(np.outer(np.diag(p0), np.diag(info)))  # entries of P0 M are O(sqrt(p_ii m_jj)) at most
        assert np.all(np.abs(p0 @ info - np.eye(3)) <= 30 * EPS * cond * scale), (points, lo, hi)
        assert np.array_equal(p0, p0.T) and np.all(np.linalg.eigvalsh(p0) > 0)
    for bad in ((0.0, 0.0, 50.0), (11.0, 10.0, 10.0), (math.nan, 0.0, 1.0), (11.0, 0.0, 1e-300), (1e308, 0.0, 50.0)):
        with pytest.raises(ValueError):
            prior_covariance(*bad)


def test_covariance_checks_name_what_is_wrong():
    good = prior_covariance()
    core.check_covariance(good)
    for p, text in ((good + np.diag([0.0, 0.0, np.nan]), "NaN"), (good + [[0, 1e-3, 0], [0, 0, 0], [0, 0, 0]], "symmetric"),
                    (-good, "positive definite")):
        with pytest.raises(ValueError, match=text):
            ForgettingRLS([0.0, 0.0, 0.0], p)


# ------------------------------------------------------------------------------------------ the stop filter
def test_stop_filter_defaults_are_the_libraries():
    """The FMU's filter settings beyond its four parameters are the C defaults: StopFilterSettings()'s bits."""
    py = [getattr(StopFilterSettings(), n) for n in core.STOP_SETTINGS]
    assert core.default_stop_settings().tolist() == py


def _transition(lat, attitude, dt):
    """Phi = I + F dt + (F dt)^2 / 2 + (F dt)^3 / 6 of the static-base model in sarins_fmu.kalman's
    docstring (Titterton & Weston 12.6-12.7, ENU), written here from the equations."""
    r_m, r_n = (float(r) for r in earth.radii(lat))
    g = float(earth.gravity(lat, 0.0))
    w_c, w_s = earth.RATE * math.cos(lat), earth.RATE * math.sin(lat)
    c = rotations.euler_to_mat(*attitude)
    f = np.zeros((11, 11))
    f[0, 1], f[0, 2], f[0, 4] = w_s, -w_c, -1.0 / r_m
    f[1, 0], f[1, 3], f[1, 10] = -w_s, 1.0 / r_n, -w_s
    f[2, 0], f[2, 3], f[2, 10] = w_c, math.tan(lat) / r_n, w_c
    f[3, 1], f[3, 4] = -g, 2.0 * w_s
    f[4, 0], f[4, 3] = g, -2.0 * w_s
    f[10, 4] = 1.0 / r_m
    f[0:3, 5:8] = -c
    f[3:5, 8:10] = c[0:2, 0:2]
    fh = f * dt
    return np.eye(11) + fh + fh @ fh / 2.0 + fh @ fh @ fh / 6.0


def test_stop_filter_without_process_noise_is_the_batch_least_squares_of_its_initial_state():
    """With negligible process noise (1e-30 densities) and a constant attitude, the Kalman filter is the
    batch weighted least squares of x0 (closed form): information J = P0^-1 + sum_k (H Phi^k)' R^-1 H Phi^k,
    x0 = J^-1 sum_k (H Phi^k)' R^-1 z_k, then x_K = Phi^K x0, P_K = Phi^K J^-1 Phi^K'.  30 minutes of rows
    (1 s).  Agreement: the filter's 1800 Joseph updates each round at eps relative to the scaled covariance,
    and the batch inverts J (scaled by P0) of condition number cond: bound 1800 x cond x eps on the eps_z
    estimate (relative to its std) and on its variance."""
    lat, attitude, k = 0.6, (0.3, 0.01, -0.02), 1800
    settings = StopFilterSettings(arw=1e-30, vrw=1e-30, drift_rw=1e-30, bias_rw=1e-30)
    kf = StopKalmanFilter(lat, settings)
    rng = np.random.default_rng(5)
    z = 1e-3 * rng.standard_normal((k, 2)) + np.linspace(0.0, 0.02, k)[:, None]
    kf.step(z, np.tile(attitude, (k, 1)))
    phi = _transition(lat, attitude, 1.0)
    p0 = settings.initial_covariance()
    s = np.sqrt(np.diag(p0))  # work in units of the initial std
    r = settings.velocity_meas_std**2
    info = np.eye(11)
    rhs = np.zeros(11)
    phik = np.eye(11)
    for j in range(k):
        phik = phi @ phik
        hs = phik[3:5] * s  # H Phi^k S
        info += hs.T @ hs / r
        rhs += hs.T @ z[j] / r
    cov0 = np.linalg.inv(info)
    x_k = phik @ (s * (cov0 @ rhs))
    p_k = (phik * s) @ cov0 @ (phik * s).T
    bound = k * np.linalg.cond(info) * EPS
    std = math.sqrt(p_k[EPS_Z, EPS_Z])
    assert abs(kf.x[EPS_Z] - x_k[EPS_Z]) <= bound * std
    assert abs(kf.p[EPS_Z, EPS_Z] - p_k[EPS_Z, EPS_Z]) <= bound * p_k[EPS_Z, EPS_Z]
    assert kf.drift_std < 0.5 * math.sqrt(p0[EPS_Z, EPS_Z])  # the rows did inform eps_z


def test_stop_record_is_plain_python_arithmetic():
    """The stop's drift measurement and temperature (core) are the running sums added row by row, divided
    by the rows: the same bits as Python's float arithmetic; the timer is rows x dt."""
    rng = np.random.default_rng(1)
    kf = StopKalmanFilter(0.7, dt=2.0)
    corr, temp = 1e-7 * rng.standard_normal(333), rng.uniform(0.0, 50.0, 333)
    for a, b in ((0, 100), (100, 101), (101, 333)):
        kf.step(1e-3 * rng.standard_normal((b - a, 2)), 0.1 * rng.standard_normal((b - a, 3)), corr[a:b], temp[a:b])
    c_sum = t_sum = 0.0
    for c, t in zip(corr, temp):
        c_sum += c
        t_sum += t
    assert kf.drift_estimate == c_sum / 333 + kf.x[EPS_Z]
    assert kf.mean_temperature == t_sum / 333 and kf.elapsed == 666.0
    assert kf.drift_std == math.sqrt(kf.p[EPS_Z, EPS_Z])


# ------------------------------------------------------------------------------------------ Fig. 2's logic
class _BlockReference:
    """Fig. 2 as the library wrote it in Python before the core took it (blocks of equal state, the
    filter and the RLS through their public methods)."""

    def __init__(self, rls, lat, settings, updater):
        self.rls, self.settings = rls, updater
        self.filter = StopKalmanFilter(lat, settings)
        self.stopped, self.events = False, []

    def step(self, t, spd, vel, att, temp, lats, act):
        still = (np.abs(spd) < self.settings.speed_threshold) & act
        comp = np.empty(t.size)
        edges = np.flatnonzero(np.diff(still.astype(np.int8))) + 1
        for k0, k1 in zip(np.concatenate([[0], edges]), np.concatenate([edges, [t.size]])):
            if not still[k0] and self.stopped:
                kf = self.filter
                duration = kf.elapsed
                used = duration >= self.settings.time_threshold - 1e-9
                if used:
                    self.rls.update(kf.mean_temperature, kf.drift_estimate, float(t[k0]))
                self.events.append((float(t[k0]), "update" if used else "reset", duration, kf.mean_temperature,
                                    kf.drift_estimate, kf.drift_std))
                kf.reset()
                self.stopped = False
            comp[k0:k1] = self.rls.predict(temp[k0:k1])
            if still[k0]:
                if not self.stopped:
                    self.filter.reset(float(lats[k0]))
                    self.stopped = True
                self.filter.step(vel[k0:k1], att[k0:k1], comp[k0:k1], temp[k0:k1])
        return comp


def _rows(n, seed):
    """Random INS rows with stops of 5 .. 400 s between drives, some rows not navigating."""
    rng = np.random.default_rng(seed)
    speed = np.empty(n)
    k = 0
    while k < n:
        drive, stop = int(rng.integers(1, 40)), int(rng.integers(5, 400))
        speed[k:k + drive] = rng.uniform(0.5, 15.0, min(drive, n - k))
        speed[k + drive:k + drive + stop] = rng.uniform(0.0, 0.009)
        k += drive + stop
    active = rng.uniform(size=n) > 0.02
    return (DAY * 3 + np.arange(1.0, n + 1), speed, 1e-3 * rng.standard_normal((n, 2)),
            rng.uniform(-3, 3, (n, 3)) * [1.0, 0.01, 0.01], 25.0 + np.cumsum(rng.normal(0.0, 0.05, n)),
            0.7 + 1e-6 * np.cumsum(rng.standard_normal(n)), active)


@pytest.mark.parametrize("chunks", [[4000], [1] * 300 + [3700], [17, 999, 2984]])
def test_row_logic_equals_the_block_logic_bit_for_bit(chunks):
    """OnlineDriftUpdater (the core's row logic) against Fig. 2 written in blocks: the same compensation at
    every row, the same events and the same model, fed at once, row by row or in odd chunks."""
    rows = _rows(4000, 11)
    rls = lambda: ForgettingRLS([1e-11, -3e-10, 2e-8], prior_covariance(), 3 * DAY, RLSSettings(0.8))  # noqa: E731
    settings, updater = StopFilterSettings(), UpdaterSettings(time_threshold=120.0)
    ref = _BlockReference(rls(), 0.7, settings, updater)
    up = OnlineDriftUpdater(rls(), 0.7, 1.0, settings, updater)
    expected = ref.step(*rows)
    got, a = [], 0
    for n in chunks:
        got.append(up.step(*(r[a:a + n] for r in rows)))
        a += n
    assert np.array_equal(np.concatenate(got), expected)
    assert up.events == ref.events and len(up.events) > 10
    assert {e[1] for e in up.events} == {"update", "reset"}
    assert up.rls.parameters.tolist() == ref.rls.parameters.tolist()
    assert up.rls.covariance.tolist() == ref.rls.covariance.tolist()


def test_a_refused_row_names_the_reason_and_keeps_the_rows_before():
    rows = list(_rows(50, 2))
    rows[0] = rows[0].copy()
    up = OnlineDriftUpdater(ForgettingRLS([0.0, 0.0, 1e-8], prior_covariance()), 0.7)
    bad_t = rows[0].copy()
    bad_t[3] = np.nan
    with pytest.raises(ValueError, match="time contains NaN"):
        up.step(bad_t, *rows[1:])
    assert not up.stopped and up.events == []  # checked before any row ran
    rows[5] = rows[5].copy()
    rows[5][:] = math.radians(95.0)  # latitude out of range where a stop starts
    rows[1] = np.zeros(50)
    with pytest.raises(ValueError, match="89.9"):
        up.step(*rows)



@pytest.mark.parametrize("field, value", [(1, -1), (2, -1), (1, 2**53 + 1), (2, 2**62), (1, 2**63 - 1)])
def test_updater_check_refuses_event_counts_no_run_can_reach(field, value):
    """A restored updater state whose counters are negative or above 2^53 (a crafted FMU state: the fuzzer's
    n_updates + n_resets overflowed int64) is refused by the state check, naming the range."""
    state = core.OnlineState(100.0, 0.01)
    state.check()
    core._view(state.buffer, int(core._ONLINE_OFF[field]), 1, np.int64)[0] = value
    with pytest.raises(ValueError, match=r"counts not 0 \.\. 2\^53"):
        state.check()


@pytest.mark.parametrize("value, ok", [(0, True), (2**53, True), (-1, False), (2**53 + 1, False), (2**63 - 1, False)])
def test_rls_check_bounds_the_update_count(value, ok):
    rls = core.RlsState(np.zeros(3), np.eye(3), 0.0)
    rls.n_updates = value
    if ok:
        rls.check()
    else:
        with pytest.raises(ValueError, match=r"update count not 0 \.\. 2\^53"):
            rls.check()
