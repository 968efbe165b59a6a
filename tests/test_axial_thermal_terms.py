"""The azimuth gyro's block-gradient and heating/cooling hysteresis terms (``sarins_imu_axial_thermal_terms``)
against closed forms, through the binding and through the IMU's state table."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sarins_fmu import imu as imu_mod
from sarins_fmu.core.axial import thermal_terms
from sarins_fmu.imu import IMU, StaticBase
from sarins_fmu.imu_params import apply_overrides, flatten
from sarins_fmu.thermal import Ambient
from sarins_fmu.units import DPH_TO_RPS

K_G = 2.0e-4 * DPH_TO_RPS  # rad/s/degC
H = 1.0e-4 * DPH_TO_RPS  # rad/s


def _par(k_g=0.0, tau_b=0.0, hyst=0.0, width=1.0, tau_r=0.0):
    return np.array([k_g, tau_b, hyst, width, tau_r])


def test_gradient_of_a_ramp_is_the_first_order_lag_closed_form():
    """T = T0 + r t from equilibrium: the block node lags, G(t) = r tau (1 - exp(-t / tau)); each interval
    holds the mean of G at its ends, and G settles at r tau (a known linear node temperature difference)."""
    h, tau, rate, n = 1.0, 1400.0, 8.0 / 3600.0, 20000
    t_end = h * np.arange(1, n + 1)
    temps = 20.0 + rate * t_end
    out = thermal_terms(20.0, temps, h, _par(k_g=K_G, tau_b=tau))
    grad = rate * tau * (1.0 - np.exp(-np.concatenate([[0.0], t_end]) / tau))
    expected = K_G * 0.5 * (grad[:-1] + grad[1:])
    assert np.allclose(out, expected, rtol=1e-9, atol=1e-24)
    assert out[-1] == pytest.approx(K_G * rate * tau, rel=1e-6)


def test_no_block_lag_means_no_gradient_and_zero_coefficients_do_nothing():
    temps = 20.0 + np.linspace(0.0, 30.0, 500) ** 1.5
    assert np.all(thermal_terms(20.0, temps, 10.0, _par(k_g=K_G, tau_b=0.0)) == 0.0)
    state = np.array([3.0, 4.0])
    assert np.all(thermal_terms(20.0, temps, 10.0, _par(tau_b=100.0, width=2.0), state) == 0.0)
    assert list(state) == [3.0, 4.0]


def test_heating_and_cooling_branches_at_the_same_temperature_differ_by_twice_the_half_height():
    """20 -> 40 -> 20 degC at 10 degC/h, width 2 degC: after rising by w the term sits at +H, after
    falling by 2 w at -H; at 30 degC the two branches differ by 2 H.  The first w of the rise is the
    play's linear segment H (T - 20) / w."""
    h, w = 10.0, 2.0
    up = 20.0 + np.arange(1, 721) * h * 10.0 / 3600.0  # 2 h up to 40
    temps = np.concatenate([up, 40.0 - (up - 20.0)])
    out = thermal_terms(20.0, temps, h, _par(hyst=H, width=w))
    mid = 0.5 * (np.concatenate([[20.0], temps[:-1]]) + temps)
    rising = np.arange(720)
    heating = rising[mid[rising] >= 20.0 + w]
    cooling = 720 + np.arange(720)[mid[720:] <= 40.0 - 2 * w]
    assert np.allclose(out[heating], H, rtol=1e-12, atol=0)
    assert np.allclose(out[cooling], -H, rtol=1e-12, atol=0)
    first = rising[mid[rising] < 20.0 + w]
    assert np.allclose(out[first], H * (mid[first] - 20.0) / w, rtol=1e-9, atol=0)
    at_30_up = out[np.argmin(np.abs(mid[:720] - 30.0))]
    at_30_down = out[720 + np.argmin(np.abs(mid[720:] - 30.0))]
    assert at_30_up - at_30_down == pytest.approx(2 * H, rel=1e-12)
    # a reversal smaller than 2 w leaves the branch only part of the way
    small = np.concatenate([up[:360], up[359] - np.arange(1, 37) * h * 10.0 / 3600.0])  # 1 degC back
    part = thermal_terms(20.0, small, h, _par(hyst=H, width=w))
    step = h * 10.0 / 3600.0  # degC per interval
    assert part[-1] == pytest.approx(H * (1.0 - 35 * step / w), rel=1e-9)  # mid fell by 35.5 steps from the top
    assert 0.0 < part[-1] < H


def test_the_loop_relaxes_at_rest_with_its_time_constant():
    """Heated onto the +H branch, then held: the term decays as H exp(-n h / tau_r)."""
    h, w, tau_r = 10.0, 2.0, 5.0 * 3600.0
    up = 20.0 + np.arange(1, 361) * h * 10.0 / 3600.0  # 1 h up to 30
    hold = np.full(2000, up[-1])
    state = np.array([20.0, 20.0])
    ramp = thermal_terms(20.0, up, h, _par(hyst=H, width=w))
    assert ramp[-1] == pytest.approx(H, rel=1e-12)
    thermal_terms(20.0, up, h, _par(hyst=H, width=w, tau_r=tau_r), state)
    rest = thermal_terms(up[-1], hold, h, _par(hyst=H, width=w, tau_r=tau_r), state)
    n = np.arange(1, hold.size + 1)
    assert np.allclose(rest, H * np.exp(-n * h / tau_r), rtol=1e-9, atol=0)
    assert rest[int(round(tau_r / h)) - 1] == pytest.approx(H / math.e, rel=1e-9)


def test_bad_parameters_are_refused():
    for bad in (_par(width=0.0), _par(tau_b=-1.0), _par(tau_r=-1.0), _par(k_g=float("nan"))):
        with pytest.raises(ValueError):
            thermal_terms(20.0, [21.0], 1.0, bad)
    with pytest.raises(ValueError, match="axial_hysteresis_width"):
        apply_overrides(imu_mod.preset("ideal"), {"axial_hysteresis_width": 0.0})
    with pytest.raises(ValueError, match="axial_block_time_constant"):
        apply_overrides(imu_mod.preset("ideal"), {"axial_block_time_constant": -5.0})


def test_the_imu_adds_the_terms_to_the_z_gyro_from_its_reported_temperature():
    """A perfect IMU with only the new terms, cold start: its z angle increments exceed the perfect
    IMU's by the terms of its reported z temperature times h; x and y do not move."""
    terms = {"axial_drift_grad": K_G, "axial_block_time_constant": 1400.0, "axial_hysteresis": H,
             "axial_hysteresis_width": 2.0, "axial_hysteresis_relax_time": 7200.0}
    ideal = imu_mod.preset("ideal")
    model = apply_overrides(ideal, terms)
    assert {k: flatten(model)[k] for k in terms} == terms
    n, h = 3 * 3600, 1.0
    zeros = np.zeros((n, 1))
    runs = []
    for m in (ideal, model):
        sensor = IMU(m, StaticBase(math.radians(28.222)), output_interval=h, seed=3, thermal_start="cold",
                     ambient=Ambient(mean=15.0))
        runs.append(sensor.step(zeros, zeros, zeros))
    (d0, _, temps), (d1, _, temps1) = runs
    assert np.array_equal(temps, temps1)
    expected = thermal_terms(15.0, temps[:, 2], h, model.axial_thermal_par)
    assert np.abs(expected).max() > 0.5 * H
    assert np.allclose(d1[:, 2] - d0[:, 2], expected * h, rtol=1e-6, atol=1e-20)
    assert np.allclose(d1[:, :2], d0[:, :2], rtol=1e-12, atol=1e-22)  # coupled only through the coning term


def test_the_nav_rlg_preset_carries_the_terms_and_the_ideal_preset_does_not():
    nav, ideal = imu_mod.preset("nav-rlg"), imu_mod.preset("ideal")
    assert nav.axial_drift_grad > 0 and nav.axial_block_time_constant > 0 and nav.axial_hysteresis > 0
    assert ideal.axial_drift_grad == 0 and ideal.axial_hysteresis == 0
    assert nav.with_axial_drift(1e-8).axial_thermal_par[[0, 2]].tolist() == [0.0, 0.0]


def test_the_deterministic_axial_drift_includes_the_terms():
    """imu.deterministic_axial_drift (the demo's drift history) = the T and dT/dt law + the new terms."""
    nav = imu_mod.preset("nav-rlg")
    temps = 20.0 + np.arange(600) * 60.0 * 5.0 / 3600.0  # 5 degC/h for 10 h on a 60 s grid
    law = imu_mod.deterministic_axial_drift(nav.with_axial_drift(0.0), temps, 60.0)
    full = imu_mod.deterministic_axial_drift(nav, temps, 60.0)
    poly = nav.axial_drift_poly
    rate = nav.axial_drift_dtdt * 5.0 / 3600.0
    assert np.allclose(full - law, (poly[0] * temps + poly[1]) * temps + poly[2] + rate
                       + thermal_terms(temps[0], temps, 60.0, nav.axial_thermal_par), rtol=1e-12, atol=1e-22)
    assert full[-1] - ((poly[0] * temps[-1] + poly[1]) * temps[-1] + poly[2] + rate) == pytest.approx(
        nav.axial_hysteresis + nav.axial_drift_grad * 5.0 / 3600.0 * nav.axial_block_time_constant, rel=1e-3)
