"""IEEE 952 / 1293 read-outs with confidence intervals (sarins_fmu.allan_readout), against allantools,
closed forms and the two real ADIS16405 static records of ../shared/data/adis16405."""

import math
import numpy as np
import pytest

from sarins_fmu import allan_readout as ar
from sarins_fmu.units import DPH_TO_RPS, DPSH_TO_RPSS

@pytest.fixture(scope="module", params=("unit1", "unit2"))
def real(request, real_adis):
    """A real unit's rates (K, 6) rad/s, m/s^2, right-front-up (read with --axes frd)."""
    log = real_adis[request.param]
    return request.param, np.hstack([log.dtheta, log.dv]) / log.step


def test_the_real_units_are_read_with_a_warning_never_refused(real_adis):
    for unit, log in real_adis.items():
        assert log.step == 0.01 and log.dtheta.shape == (1_000_000, 3) and log.format == "csv"
        assert any("horizontal axis" in w and "MEMS" in w for w in log.caught), unit  # a bias of 1,000+ deg/h
        assert abs(np.linalg.norm(log.dv.mean(axis=0) / log.step) - 9.97) < 0.05  # 1.016 g, the README's


@pytest.mark.parametrize("alpha", [2, 1, 0, -1, -2])
@pytest.mark.parametrize("n, m", [(1001, 1), (1001, 10), (100001, 300), (1000001, 65536)])
def test_edf_equals_allantools_simple_formulas(alpha, n, m):
    allantools = pytest.importorskip("allantools")
    assert ar.edf_overlapping(n, m, alpha) == pytest.approx(allantools.edf_simple(n, m, alpha), rel=1e-12)


def test_real_units_random_walk_within_5_percent_of_the_1_s_reading(real):
    """N, read on the -1/2 line at 1 s, against allantools' overlapping deviation at 1 s (the IEEE reading)."""
    allantools = pytest.importorskip("allantools")
    unit, rates = real
    for j in range(3):
        r = ar.read_terms(ar.octave_curve(rates[:, j], 100.0))
        _, theirs, _, _ = allantools.oadev(rates[:, j], rate=100.0, data_type="freq", taus=np.array([1.0]))
        n = r["random_walk"]
        assert n.tau == 1.0 and n.value == pytest.approx(theirs[0], rel=0.05), (unit, j)
        assert n.low <= theirs[0] <= n.high
        assert 2.0 < n.value / DPSH_TO_RPSS < 2.8  # deg/sqrt(h): the units' 2.2 .. 2.6 (data/adis16405 README)


def test_real_units_bias_instability_has_a_floor_inside_its_interval(real):
    """Each gyro's curve has a flat floor (20 .. 35 deg/h from 30 s to 1000 s): B > 0, and allantools'
    deviation there over 0.664 (the graphical IEEE reading) lies inside B's interval."""
    allantools = pytest.importorskip("allantools")
    unit, rates = real
    for j in range(3):
        curve = ar.octave_curve(rates[:, j], 100.0)
        b = ar.read_terms(curve)["bias_instability"]
        assert b.resolved and b.value > 0, (unit, j)
        _, theirs, _, _ = allantools.oadev(rates[:, j], rate=100.0, data_type="freq", taus=np.array([b.tau]))
        assert b.low <= theirs[0] / ar.FLOOR <= b.high, (unit, j, b)
        assert 10 * DPH_TO_RPS < b.value < 80 * DPH_TO_RPS
        assert not ar.read_terms(curve)["quantization"].resolved  # 14-bit rate steps are white: inside N


def test_our_octave_curve_equals_allantools(real):
    allantools = pytest.importorskip("allantools")
    _, rates = real
    curve = ar.octave_curve(rates[:200000, 0], 100.0)
    _, theirs, _, _ = allantools.oadev(rates[:200000, 0], rate=100.0, data_type="freq", taus=curve.taus)
    np.testing.assert_allclose(curve.adev, theirs, rtol=1e-9)


def test_quantisation_and_rate_ramp_read_where_their_slopes_hold():
    """Angle quantisation (the angle read with a white error uniform over a step d: Q = d / sqrt(12),
    slope -1) at short times and a rate ramp (R, slope +1) at long times, with white rate noise between:
    each read within its interval."""
    rng = np.random.default_rng(7)
    n, rate = 400000, 100.0
    h = 1.0 / rate
    d, noise, ramp = 1e-3, 2e-5, 2e-7  # rad; rad/sqrt(s); rad/s^2
    t = np.arange(1, n + 1) * h
    angle = np.cumsum(noise * math.sqrt(h) * rng.standard_normal(n)) + 0.5 * ramp * t * t
    read = angle + d * (rng.random(n) - 0.5)
    y = np.diff(np.concatenate(([0.0], read))) / h
    r = ar.read_terms(ar.octave_curve(y, rate))
    q, rr = r["quantization"], r["rate_ramp"]
    assert q.resolved and q.low <= d / math.sqrt(12) <= q.high, q
    assert rr.resolved and rr.low <= ramp <= rr.high, rr


def test_a_term_the_record_cannot_show_is_not_resolved_with_a_bound():
    rng = np.random.default_rng(3)
    y = 1e-3 * rng.standard_normal(100000)  # white noise only, 1 kHz
    r = ar.read_terms(ar.octave_curve(y, 1000.0))
    for term in ("bias_instability", "rate_random_walk", "rate_ramp", "quantization"):
        assert r[term].value is None and r[term].low == 0.0 and r[term].high > 0, term
    assert r["random_walk"].low <= 1e-3 / math.sqrt(1000.0) <= r["random_walk"].high


def test_short_and_moving_records_are_warned_about():
    from sarins import allan as app

    rng = np.random.default_rng(1)
    n = 1000  # 10 s at 100 Hz, turning about a horizontal axis after 5 s
    gyro = 1e-3 * rng.standard_normal((n, 3))
    accel = np.tile([0.0, 0.0, 9.8], (n, 1)) + 1e-3 * rng.standard_normal((n, 3))
    angle = np.where(np.arange(n) > 500, (np.arange(n) - 500) * 0.01 * 0.5, 0.0)
    gyro[:, 0] += np.where(np.arange(n) > 500, 0.5, 0.0)
    accel[:, 1], accel[:, 2] = 9.8 * np.sin(angle), 9.8 * np.cos(angle)
    means = np.hstack([gyro, accel]).reshape(10, 100, 6).mean(axis=1)
    result = app.analyse(np.hstack([gyro, accel]), 100.0, "test", means=means)
    assert any("record lasts 10 s" in w for w in result.warnings)
    assert any("not static" in w for w in result.warnings)
