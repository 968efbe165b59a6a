"""Output dynamics of the C core (``sarins_fmu/core/dynamics.h``) against closed forms, through the binding.

Each test builds an IMU whose model has one term only, takes its state
table and runs ``sarins_imu_dynamics`` on chosen interval means (rad/s,
m/s^2), so the expected output is exact.
"""

import math

import numpy as np
import pytest

from sarins_fmu import earth, imu, imu_dynamics
from sarins_fmu.core import imu as core_imu
from sarins_fmu.imu_step import T_REF

H = 0.005  # the paper's 200 Hz


def _table(model, h=H):
    return imu.IMU(model, imu.StaticBase(0.5), output_interval=h)._table


def _run(model, x, temps=None, h=H):
    """Apply the dynamics of ``model`` to interval means x (K, 6); returns the output means (K, 6)."""
    x = np.asarray(x, float)
    temps = np.full((len(x), 6), T_REF) if temps is None else temps
    dtheta, dv = np.ascontiguousarray(x[:, :3] * h), np.ascontiguousarray(x[:, 3:] * h)
    core_imu.dynamics(_table(model, h), temps, dtheta, dv)
    return np.column_stack([dtheta, dv]) / h


def _triad(**kw):
    return imu.TriadErrors(**kw)


def test_output_filter_step_response_is_first_order():
    tau = 0.02
    model = imu.ImuModel(gyro=_triad(filter_time_constant=np.full(3, tau)))
    x = np.zeros((40, 6))
    x[1:, 0] = 1.0  # at rest on 0, a unit step from the second interval
    y = _run(model, x)
    a = H / (H + tau)
    n = np.arange(40)
    np.testing.assert_allclose(y[:, 0], np.where(n >= 1, 1.0 - (1.0 - a) ** n, 0.0), rtol=0, atol=1e-14)
    np.testing.assert_array_equal(y[:, 1:], 0.0)  # other channels and the accelerometers untouched


def test_output_filter_gain_and_group_delay_at_a_frequency():
    tau, f = 0.0025, 5.0
    model = imu.ImuModel(accel=_triad(filter_time_constant=np.full(3, tau)))
    k = np.arange(4000)
    x = np.zeros((len(k), 6))
    x[:, 4] = np.sin(2 * np.pi * f * k * H)
    y = _run(model, x)[2000:, 4]  # transient gone ((1 - a)^2000 ~ 0)
    a = H / (H + tau)
    w = 2 * np.pi * f * H
    resp = a / (1.0 - (1.0 - a) * np.exp(-1j * w))  # H(z) = a / (1 - (1 - a) z^-1)
    expected = np.abs(resp) * np.sin(w * k[2000:] + np.angle(resp))
    np.testing.assert_allclose(y, expected, rtol=0, atol=1e-12)
    # group delay -d(phase)/d(omega) of the discrete filter, and the continuous tau it approximates
    dw = 1e-6
    delay = -(np.angle(a / (1 - (1 - a) * np.exp(-1j * (w + dw)))) - np.angle(resp)) / dw * H
    b = 1.0 - a
    closed = H * (b * math.cos(w) - b * b) / (1 - 2 * b * math.cos(w) + b * b)
    assert delay == pytest.approx(closed, rel=1e-5)
    assert b * H / (1 - b) == pytest.approx(tau, rel=1e-12)  # the delay at omega -> 0 is tau
    assert closed == pytest.approx(tau, rel=0.05)  # and within 5 % of it at 5 Hz


def test_g_sensitivity_under_a_known_specific_force():
    gs = np.array([[1.0, 0.3, -0.2], [-0.2, 1.0, 0.3], [0.3, -0.2, 1.0]]) * 0.015 * math.pi / 180 / earth.GAMMA_E
    base = imu.StaticBase(0.5)
    sensor = imu.IMU(imu.ImuModel(g_sensitivity=gs), base, output_interval=H)
    ideal = imu.IMU(imu.ImuModel(), base, output_interval=H)
    z = np.zeros((10, 1))
    d_g, _, _ = sensor.step(z, z, z)
    d_i, dv_i, _ = ideal.step(z, z, z)
    f = dv_i / H  # the specific force sensed (level base: +g up)
    # dv / h is the mean force to 1e-6 (the sculling of the Earth rate): the same relative accuracy here
    np.testing.assert_allclose(d_g / H - d_i / H, f @ gs.T, rtol=1e-5)


def _hyst_model(c, w, tau_r, tc=0.0):
    return imu.ImuModel(gyro=_triad(rate_hysteresis=np.full(3, c), rate_hysteresis_width=np.full(3, w),
                                    rate_hysteresis_time=np.full(3, tau_r), rate_hysteresis_tc=np.full(3, tc)))


def _ramp_error(rate, n_up, n_hold, tau_r, w):
    """Play-operator error e = x - P of the discrete relaxed play on a ramp then a hold (closed form)."""
    q = math.exp(-H / tau_r) if tau_r > 0 else 1.0
    e, out = 0.0, []
    for k in range(n_up + n_hold):
        d = rate * H if 0 < k <= n_up else 0.0
        e = min(w, max(-w, (e + d) * q))
        out.append(e)
    return np.array(out)


def test_rate_hysteresis_branches_on_a_fast_sweep():
    c, w = 1e-4, 0.01
    model = _hyst_model(c, w, 0.0)
    up = np.linspace(0.0, 0.5, 201)
    x = np.zeros((401, 6))
    x[:201, 0] = up
    x[201:, 0] = up[::-1][1:]  # back down
    y = _run(model, x)[:, 0] - x[:, 0]
    # after taking up the play (w / step = 4 intervals) the error sits on its branch: +c rising, -c falling
    np.testing.assert_allclose(y[10:200], c, rtol=1e-9)
    np.testing.assert_allclose(y[210:], -c, rtol=1e-9)
    assert abs(y[201]) < c  # moving along the flat segment after the reversal


def test_rate_hysteresis_relaxes_and_scales_with_sweep_rate_and_temperature():
    c, w, tau_r, tc = 1e-4, 0.02, 2.0, 0.01
    model = _hyst_model(c, w, tau_r, tc)
    rate, n_up, n_hold = 0.004, 4000, 1200  # slow: rate tau_r = 0.008 < w
    x = np.zeros((n_up + n_hold, 6))
    x[:n_up + 1, 1] = rate * H * np.arange(n_up + 1)
    x[n_up + 1:, 1] = x[n_up, 1]
    temps = np.full((len(x), 6), T_REF + 10.0)
    y = _run(model, x, temps)[:, 1] - x[:, 1]
    e = _ramp_error(rate, n_up, n_hold, tau_r, w)
    np.testing.assert_allclose(y, c * (1 + tc * 10.0) * e / w, rtol=1e-9, atol=1e-18)
    q = math.exp(-H / tau_r)
    assert e[n_up] == pytest.approx(rate * H * q / (1 - q), rel=1e-3)  # steady lag ~ rate tau_r
    assert e[n_up + 400] / e[n_up] == pytest.approx(q ** 400, rel=1e-9)  # relaxes as exp(-t / tau_r)


def test_angular_acceleration_and_centripetal_terms_of_the_size_effect():
    arm = np.array([[2.0, -3.0, 1.0], [-2.0, 2.0, -1.0], [1.0, 1.0, 3.0]]) * 1e-3
    model = imu.ImuModel(accel_lever_arm=arm)
    alpha = np.array([0.3, -0.5, 2.0])  # rad/s^2, constant
    k = np.arange(50)
    x = np.zeros((50, 6))
    x[:, :3] = np.outer(k * H, alpha) + np.array([0.1, 0.0, -0.2])
    x[:, 3:] = [0.1, -0.2, 9.8]
    y = _run(model, x)
    for i in range(1, 50):
        w = x[i, :3]
        for j in range(3):
            r = arm[j]
            expected = (np.cross(alpha, r) + np.cross(w, np.cross(w, r)))[j]
            assert y[i, 3 + j] - x[i, 3 + j] == pytest.approx(expected, rel=1e-9, abs=1e-15)
    w0 = x[0, :3]  # first interval: no angular acceleration yet
    np.testing.assert_allclose(y[0, 3:] - x[0, 3:], [np.cross(w0, np.cross(w0, arm[j]))[j] for j in range(3)],
                               rtol=1e-9)
    np.testing.assert_allclose(y[:, :3], x[:, :3], rtol=1e-15, atol=1e-16)  # the gyros untouched (x h / h)


def test_presets_without_dynamics_and_the_mems_preset():
    assert not imu_dynamics.active(imu.preset("ideal")) and not imu_dynamics.active(imu.preset("nav-rlg"))
    assert imu_dynamics.active(imu.preset("mems"))


def test_batch_and_one_interval_paths_agree_with_dynamics_on():
    """The FMU's one-interval path and the threaded batch path run the same dynamics in the same order."""
    model = imu.preset("mems")
    base = imu.StaticBase(0.5)
    axes = ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0))
    n = 200
    t = np.arange(n) * H
    rate = np.column_stack([np.sin(t * 3.0), np.cos(t * 2.0)])
    angle = np.cumsum(rate, axis=0) * H
    acc = np.gradient(rate, H, axis=0)
    batch = imu.IMU(model, base, axes, output_interval=H, seed=5).step(angle, rate, acc)
    one = imu.IMU(model, base, axes, output_interval=H, seed=5)
    rows = [one.step(angle[i:i + 1], rate[i:i + 1], acc[i:i + 1]) for i in range(n)]
    for m in range(3):
        np.testing.assert_allclose(np.vstack([r[m] for r in rows]), batch[m], rtol=1e-12, atol=1e-16)
