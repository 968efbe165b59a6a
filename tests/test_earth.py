import math

import pytest
from numpy.testing import assert_allclose

from sarins_fmu import earth


def test_normal_gravity_closed_form_at_equator_and_pole():
    assert_allclose(earth.gravity(0.0, 0.0), earth.GAMMA_E, rtol=1e-12)
    assert_allclose(earth.gravity(math.pi / 2, 0.0), earth.GAMMA_P, rtol=1e-12)


def test_free_air_gradient():
    # dg/dh ~ -2 g / a (1 + f + m) ~ -3.086e-6 s^-2 at the equator
    dg = (earth.gravity(0.0, 1000.0) - earth.gravity(0.0, 0.0)) / 1000.0
    assert_allclose(dg, -3.0877e-6, rtol=2e-3)


def test_radii_of_curvature():
    r_m, r_n = earth.radii(0.0)
    assert_allclose(r_n, earth.A, rtol=1e-15)
    assert_allclose(r_m, earth.A * (1 - earth.E2), rtol=1e-15)
    r_m, r_n = earth.radii(math.pi / 2)
    assert_allclose(r_m, r_n, rtol=1e-12)  # polar radius of curvature a^2/b
    assert_allclose(r_n, earth.A**2 / earth.B, rtol=1e-12)


def test_earth_rate_vector(lat):
    w = earth.earth_rate_n(lat)
    assert w[0] == 0.0
    assert_allclose(math.hypot(w[1], w[2]), 7.2921151467e-5, rtol=1e-15)
    assert_allclose(math.atan2(w[2], w[1]), lat, rtol=1e-14)


def test_schuler_period_is_84_4_minutes():
    assert earth.schuler_period(0.5) / 60 == pytest.approx(84.4, abs=0.1)
