import numpy as np
import pytest
from numpy.testing import assert_allclose

from sarins_fmu.thermal import Ambient, ThermalModel, ThermalParams, chamber_profile


def test_cold_start_rises_with_the_configured_time_constant():
    params = ThermalParams()
    model = ThermalModel(params, Ambient(mean=15.0), start="cold")
    t = np.arange(1.0, 6 * 3600 + 1)
    temps = model.advance(t)
    assert_allclose(temps[0, :] - 15.0, 0.0, atol=0.01)  # starts at ambient
    for j, tau in enumerate(params.time_constant):
        k = int(round(tau)) - 1
        expected = params.self_heating[j] * (1 - np.exp(-1.0))  # 63.2 % at t = tau
        assert temps[k, j] - 15.0 == pytest.approx(expected, rel=0.01)
    # seed 000's cold starts (Tables 4-5): 41-75 % of the rise falls in the 4 h alignment (tau 2.9-7.5 h)
    share = (temps[4 * 3600 - 1] - temps[0]) / np.asarray(params.self_heating)
    assert np.all((share > 0.41) & (share < 0.75))


def test_hot_start_stays_within_three_degrees():
    model = ThermalModel(ThermalParams(), Ambient(mean=25.0, amplitude=1.0), start="hot")
    temps = model.advance(np.arange(60.0, 88 * 3600 + 1, 60.0))
    assert np.ptp(temps, axis=0).max() < 3.0


def test_exact_integration_independent_of_step_and_chunking():
    amb = Ambient(mean=20.0, slope=1e-4)
    a = ThermalModel(ambient=amb, start="cold").advance(np.arange(1.0, 7201))
    b = ThermalModel(ambient=amb, start="cold").advance(np.arange(10.0, 7201, 10.0))
    assert_allclose(a[9::10], b, rtol=1e-12)
    m = ThermalModel(ambient=amb, start="cold")
    c = np.vstack([m.advance(np.arange(1.0, 1001)), m.advance(np.arange(1001.0, 7201))])
    assert np.array_equal(a, c)


def test_bad_thermal_input():
    with pytest.raises(ValueError):
        ThermalModel(start="lukewarm")
    with pytest.raises(ValueError):
        ThermalParams(time_constant=(0, 1, 1, 1, 1, 1))
    with pytest.raises(ValueError):
        ThermalModel().advance([10.0, 5.0])


def test_chamber_profile_ramps_and_holds():
    times, temps = chamber_profile(8 * 3600.0)
    assert times[0] == 0 and times[-1] == 8 * 3600.0 and np.all(np.diff(times) > 0)
    assert temps[0] == 20.0 and temps.min() == -25.0 and temps.max() == 40.0
    slope = np.diff(temps) / np.diff(times) * 60.0  # degC/min
    assert set(np.round(np.abs(slope), 12)) == {0.0, 1.0}
    holds = np.diff(times)[slope == 0]
    assert_allclose(holds, [1800.0] * 5)
    assert temps[-1] == pytest.approx(0.0)  # cut 25 min into the last ramp up from -25
    # first the cold end: 45 min down to -25, 30 min hold, 65 min up to 40
    assert_allclose(times[1:4], [2700.0, 4500.0, 8400.0])
    amb = Ambient(profile=(times, temps))
    assert amb(2700.0 + 900.0) == -25.0 and amb(4500.0 + 600.0) == pytest.approx(-15.0)
    t2, v2 = chamber_profile(600.0, delay=600.0, start_c=-25.0, hold_min=0.0)
    assert_allclose(v2, -25.0) and t2[-1] == 600.0


def test_chamber_staircase_hot_end_first():
    """first='high' and intermediate stops every step_c on the ramps between the ends (not on the first
    ramp from the start temperature); chamber_cycle_time is one end -> end -> end cycle."""
    from sarins_fmu.thermal import chamber_cycle_time

    kw = dict(low_c=-15.0, high_c=35.0, ramp_c_per_min=0.75, hold_min=20.0, first="high", step_c=12.5,
              step_hold_min=10.0)
    times, temps = chamber_profile(40000.0, **kw)
    assert temps.max() == 35.0 and temps.min() == -15.0
    assert times[np.argmax(temps)] < times[np.argmin(temps)]
    slope = np.diff(temps) / np.diff(times) * 60.0
    assert set(np.round(np.abs(slope), 12)) == {0.0, 0.75}
    held = temps[:-1][slope == 0]
    assert set(held) == {35.0, 22.5, 10.0, -2.5, -15.0}
    stops = np.diff(times)[(slope == 0) & (np.abs(temps[:-1]) < 30) & (temps[:-1] > -10)]
    assert_allclose(stops, 600.0)
    cycle = chamber_cycle_time(**{k: v for k, v in kw.items() if k != "first"})
    assert cycle == pytest.approx(2 * (50 / 0.75 * 60 + 1200 + 3 * 600))
    first_top = times[1]  # 20 -> 35 degC with no stop, then the cycle starts at the hot end
    hot = times[np.isclose(temps, 35.0)]
    assert first_top == pytest.approx(15 / 0.75 * 60) and hot[2] - hot[0] == pytest.approx(cycle)
    with pytest.raises(ValueError, match="first"):
        chamber_profile(100.0, first="middle")


@pytest.mark.parametrize("kwargs", [
    dict(duration=float("nan")), dict(duration=-1.0), dict(ramp_c_per_min=0.0), dict(hold_min=-1.0),
    dict(low_c=50.0), dict(high_c=float("nan")), dict(delay=-1.0), dict(step_c=-1.0), dict(step_hold_min=-1.0),
])
def test_chamber_profile_rejects_bad_input(kwargs):
    args = dict(duration=3600.0) | kwargs
    with pytest.raises(ValueError, match="must be"):
        chamber_profile(args.pop("duration"), **args)


def _exact_decimal(y, u0, slope, dt, tau):
    """The first-order lag's end value y e + (u0 - s tau)(1 - e) + s dt = y + (u0 - y) m + s tau (w - m), with
    w = dt / tau and m = 1 - exp(-w), in 60-digit decimal arithmetic; m and w - m from their Taylor series
    when w < 0.1 (no cancellation at any tau)."""
    from decimal import Decimal, localcontext
    with localcontext() as ctx:
        ctx.prec = 60
        y, u0, s, dt, tau = (Decimal(repr(float(v))) for v in (y, u0, slope, dt, tau))
        w = dt / tau
        if w < Decimal("0.1"):
            rest, term, k = Decimal(0), w, 1  # w - m = sum_{k>=2} -(-w)^k / k!
            while True:
                k += 1
                term = -term * w / k
                if abs(term) < Decimal("1e-70") * abs(w * w):
                    break
                rest -= term
            m = w - rest
        else:
            m = 1 - (-w).exp()
            rest = w - m
        return float(y + (u0 - y) * m + s * tau * rest)


@pytest.mark.parametrize("tau", [0.02, 3600.0, 1e6, 3.0e5, 1e9, 1e12, 1e16, 1e100, 2.6e300])
def test_exact_steps_match_the_closed_form_at_any_time_constant(tau):
    """The ambient stepping from 20 to 500 degC in one 0.005 s step with 3 degC self-heating: the core's step
    equals the closed form (60-digit decimal) within its stated error, 1e-12 degC + 2 x 2^-26 x 480 degC
    (thermal.h sarins_first_order_step), at every time constant; before the series branch, tau = 2.6e300 s
    moved the sensor by the whole 480 degC (1 - exp(-dt/tau) rounds to 0)."""
    from sarins_fmu.core import thermal as core_thermal
    h, amb, heat, temp0 = np.array([0.005]), np.array([20.0, 500.0]), np.array([3.0]), np.array([36.5])
    got = core_thermal.exact_steps(h, amb, heat, np.array([tau]), temp0)[0, 0]
    want = _exact_decimal(36.5, 23.0, 480.0 / 0.005, 0.005, tau)
    assert abs(got - want) <= 1e-12 + 2.0 * 2.0**-26 * 480.0, (got, want)
    if tau > 0.005 * 2.0**26:  # the series branch: to rounding
        assert abs(got - want) <= 1e-13, (got, want)


@pytest.mark.parametrize("tau", [1e6, 1e12, 2.6e300])
def test_die_temperatures_match_the_closed_form_at_any_time_constant(tau):
    from sarins_fmu.core import thermal as core_thermal
    die = np.array([36.0])
    out = core_thermal.die_temperatures(np.array([36.0]), np.array([[516.0]]), 1.0, np.array([tau]), die)
    want = _exact_decimal(36.0, 36.0, 480.0, 1.0, tau)
    assert abs(out[0, 0] - want) <= 1e-12 + 2.0 * 2.0**-26 * 480.0, (out, want)
