import numpy as np
import pytest
from numpy.testing import assert_allclose

from sarins_fmu.thermal import Ambient, ThermalModel, ThermalParams


def test_cold_start_rises_with_the_configured_time_constant():
    params = ThermalParams()
    model = ThermalModel(params, Ambient(mean=15.0), start="cold")
    t = np.arange(1.0, 4 * 3600 + 1)
    temps = model.advance(t)
    assert_allclose(temps[0, :] - 15.0, 0.0, atol=0.01)  # starts at ambient
    for j, tau in enumerate(params.time_constant):
        k = int(round(tau)) - 1
        expected = params.self_heating[j] * (1 - np.exp(-1.0))  # 63.2 % at t = tau
        assert temps[k, j] - 15.0 == pytest.approx(expected, rel=0.01)
    # seed 000's cold start: more than 10 degC during a 4 h alignment
    assert np.all(temps[-1] - temps[0] > 10.0)


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
