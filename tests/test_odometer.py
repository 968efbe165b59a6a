"""Odometer model (core odo.h) and the filter's odometer / non-holonomic updates (eskf.h)."""

import numpy as np
import pytest

from sarins_fmu import aided
from sarins_fmu import trajectory as tr
from sarins_fmu.core import aided as core


def test_scale_factor_noise_and_quantisation():
    speeds = np.full(20000, 10.0)
    out = core.OdoState([0.01, 0.02, 0.0], 5).speeds(speeds)
    assert out.mean() == pytest.approx(10.1, abs=3 * 0.02 / np.sqrt(20000))
    assert out.std() == pytest.approx(0.02, rel=0.03)
    q = core.OdoState([0.0, 0.02, 0.03], 5).speeds(speeds + 0.004)
    assert np.allclose(q / 0.03, np.round(q / 0.03), atol=1e-9)
    # quantisation of a signal dithered by noise wider than the step: variance sigma^2 + res^2 / 12
    # (Sheppard's correction)
    assert q.var() == pytest.approx(0.02**2 + 0.03**2 / 12, rel=0.06)
    assert np.array_equal(core.OdoState([0.0, 0.02, 0.03], 5).speeds(speeds + 0.004), q)
    assert aided.OdometerConfig(noise_std=0.02, resolution=0.03).std() == pytest.approx(np.sqrt(q.var()), rel=0.05)


@pytest.mark.parametrize("config, words", [([0.0, -0.1, 0.0], "negative"), ([0.6, 0.1, 0.0], "0.5"),
                                           ([0.0, np.nan, 0.0], "finite")])
def test_bad_odometer_settings(config, words):
    with pytest.raises(ValueError, match=words):
        core.OdoState(config, 0)


@pytest.fixture(scope="module")
def truth():
    segments = ({"kind": "stop", "duration": 10}, {"kind": "accelerate", "to_speed": 12, "accel": 1.0},
                {"kind": "turn", "rate_dps": 6, "angle_deg": 90}, {"kind": "cruise", "duration": 40},
                {"kind": "accelerate", "to_speed": 0, "accel": 1.5}, {"kind": "stop", "duration": 5})
    return tr.generate(tr.Trajectory(tr.Start(lat_deg=32.0), segments), 0.02)


def test_body_speed_is_the_forward_speed(truth):
    speed = aided.body_speed(truth)
    assert np.allclose(speed, np.linalg.norm(truth.velocity_n, axis=1), atol=1e-12)


def test_gnss_free_odometer_and_nhc_are_consistent_and_hold_the_velocity(truth):
    """Without GNSS: ZUPT + odometer + NHC over 20 runs, velocity and attitude NEES average near 3
    and the velocity sigma at the end of the cruise is well below the ZUPT-only filter's."""
    st = aided.FilterSettings(cov_every=5, out_every=5)
    rep = aided.nees_monte_carlo(truth, 20, aiding=("zupt", "odometer", "nhc"), settings=st)
    for block in ("velocity", "attitude"):
        assert 2.4 < rep.mean_nees[block].mean() < 3.6, (block, rep.mean_nees[block].mean())
    k = int(np.searchsorted(rep.time, 77.0))  # end of the cruise (10 + 12 + 15 + 40 s)
    both = aided.navigate(truth, aiding=("zupt", "odometer", "nhc"), settings=st, seed=1)
    zupt = aided.navigate(truth, aiding=("zupt",), settings=st, seed=1)
    sigma_v = [np.sqrt(np.trace(r.cov[k, 3:5, 3:5])) for r in (both, zupt)]
    # odometer + NHC leave the heading error (5 mrad x 12 m/s = 0.06 m/s) as the velocity's limit
    assert sigma_v[0] < 0.4 * sigma_v[1]
    assert np.hypot(*both.error[k, 3:5]) < 3 * sigma_v[0]
