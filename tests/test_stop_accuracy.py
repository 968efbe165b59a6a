"""The covariance bound on the azimuth drift at a stop (sarins_fmu.stop_accuracy)."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from sarins_fmu import stop_accuracy as sa
from sarins_fmu.earth import RATE
from sarins_fmu.units import DPSH_TO_RPSS, RPS_TO_DPH, UG_TO_MPS2

LAT = math.radians(40.0)
NAV_RLG_ARW = 0.0005 * DPSH_TO_RPSS


def test_discretise_matches_a_constant_velocity_model():
    phi, q = sa.discretise(np.array([[0.0, 1.0], [0.0, 0.0]]), np.diag([0.0, 2.0]), 3.0)
    assert_allclose(phi, [[1.0, 3.0], [0.0, 1.0]])
    assert_allclose(q, 2.0 * np.array([[9.0, 4.5], [4.5, 3.0]]))  # q (t^3/3, t^2/2; t^2/2, t)


def test_drift_read_from_an_observed_heading_walk_reaches_n_over_sqrt_t():
    """phi' = -eps + w (w white, N^2): the drift of a directly observed angle has 1-sigma N/sqrt(T)."""
    n_rw, T = 1e-6, 1800.0
    std = sa.posterior_std([[0.0, -1.0], [0.0, 0.0]], np.diag([n_rw**2, 0.0]), [[1.0, 0.0]], [1e-16],
                           np.diag([0.0, 1e-4]), 1.0, int(T), 1)
    assert_allclose(std[-1], sa.heading_walk_drift_std(n_rw, T), rtol=2e-3)


def test_short_noise_free_stop_sees_the_drift_as_g_omega_cos_l_t3_over_6():
    """No process noise, known initial errors, white velocity noise s: var = s^2 / sum (g W cos L t^3/6)^2."""
    F, Qc = sa.stop_model(LAT, 0.0, 0.0, 0.0)
    H = np.zeros((2, 6))
    H[0, 0] = H[1, 1] = 1.0
    s, n = 1e-3, 60
    p0 = np.diag([0.0] * 5 + [1e-12])
    std = sa.posterior_std(F, Qc, H, [s**2] * 2, p0, 1.0, n, 5)
    t = np.arange(1, n + 1, dtype=float)
    h = sa.G * RATE * math.cos(LAT) * t**3 / 6.0
    closed = s / math.sqrt(np.sum(h**2) + s**2 / 1e-12)
    assert_allclose(std[-1], closed, rtol=1e-2)


def test_at_nav_rlg_noise_the_horizontal_random_walk_sets_the_limit():
    vrw = 5.0 * UG_TO_MPS2
    full = sa.stop_drift_accuracy(lat=LAT, arw_horizontal=NAV_RLG_ARW, vrw=vrw)
    azimuth_only = sa.stop_drift_accuracy(lat=LAT, arw_horizontal=0.0, arw_azimuth=NAV_RLG_ARW, vrw=vrw)
    horizontal_only = sa.stop_drift_accuracy(lat=LAT, arw_horizontal=NAV_RLG_ARW, arw_azimuth=0.0, vrw=0.0)
    assert 0.015 < full.final_std * RPS_TO_DPH < 0.04  # far above the paper's 0.002 deg/h
    assert horizontal_only.final_std > 5 * azimuth_only.final_std
    assert full.final_std > 20 * full.heading_walk_std  # N/sqrt(T) = 0.0007 deg/h is not the limit
    assert np.all(np.diff(full.drift_std) <= 1e-18)  # more data never hurts
    # the result is the data's, not the prior's
    wider = sa.stop_drift_accuracy(lat=LAT, arw_horizontal=NAV_RLG_ARW, vrw=vrw, diffuse=1e4)
    assert_allclose(wider.final_std, full.final_std, rtol=1e-3)


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError, match="duration"):
        sa.stop_drift_accuracy(lat=LAT, arw_horizontal=NAV_RLG_ARW, duration=1.0)
    with pytest.raises(ValueError, match="non-negative"):
        sa.stop_drift_accuracy(lat=LAT, arw_horizontal=-1.0)
    with pytest.raises(ValueError, match="finite"):
        sa.stop_drift_accuracy(lat=float("nan"), arw_horizontal=NAV_RLG_ARW)
