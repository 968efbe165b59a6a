"""The IMU's periodic disturbance a sin(2 pi f t + phi) per sensor (sarins_fmu/core/imu.h, SARINS_IMU_PERIODIC)
against its closed forms: the increment is its exact integral over the interval, its mean over whole
periods vanishes, the overlapping Allan deviation of the record is a sin^2(pi f tau) / (pi f tau) within the
estimator's bound for a sinusoid, the phase comes from the seed and shifts no other random draw; bad
amplitudes and frequencies are refused naming the parameter."""

import math

import numpy as np
import pytest

from sarins_fmu import allan_readout, imu, imu_params, imu_step
from sarins_fmu.core import imu as core_imu

H = 0.01  # s: the output interval (Nyquist 50 Hz)
# per sensor (gyro x y z rad/s, accel x y z m/s^2): amplitude, frequency (Hz); none commensurate with the octaves
TERMS = ((2e-4, 0.37), (5e-5, 1.3), (1e-4, 0.061), (0.008, 0.53), (0.005, 0.37), (0.003, 7.1))
NAMES = [(f"{triad}_periodic_amplitude_{ax}", f"{triad}_periodic_frequency_{ax}") for triad in ("gyro", "accel")
         for ax in "xyz"]


def _model(base="ideal", terms=TERMS):
    over = {}
    for (amp, freq), (a_name, f_name) in zip(terms, NAMES):
        over.update({a_name: amp, f_name: freq})
    return imu_params.apply_overrides(imu.preset(base), over)


def _record(model, n, seed=0):
    """n intervals of H on a static base: the IMU (for its state) and the rates (n, 6)."""
    sensor = imu.IMU(model, imu.StaticBase(0.8), output_interval=H, internal_rate=1.0 / H, seed=seed)
    zero = np.zeros((n, 1))
    dtheta, dv, _ = sensor.step(zero, zero, zero)
    return sensor, np.hstack([dtheta, dv]) / H


def _excess(n, seed=0, base="ideal"):
    """The rates of the model with TERMS less those of the model without them (same seed), and the phases."""
    sensor, rates = _record(_model(base), n, seed)
    _, plain = _record(imu.preset(base), n, seed)
    return rates - plain, sensor.state_arrays()[imu_step.PERIODIC][2].copy()


def _integral(k, amp, freq, phase):
    """Mean rate of a sin(2 pi f t + phi) over [k H, (k + 1) H]: the closed-form integral over H, in extended
    precision (the difference of two cosines of arguments up to hundreds of rad)."""
    w = 2 * np.pi * np.longdouble(freq)
    t0, t1 = np.asarray(k, np.longdouble) * np.longdouble(H), (np.asarray(k, np.longdouble) + 1) * np.longdouble(H)
    return np.asarray(amp * (np.cos(w * t0 + phase) - np.cos(w * t1 + phase)) / (w * np.longdouble(H)), float)


def test_the_increment_is_the_exact_integral_and_whole_periods_average_to_zero():
    n = 20000
    excess, phases = _excess(n)
    k = np.arange(n)
    for j, (amp, freq) in enumerate(TERMS):  # to 1e-12 relative, and a few ulp of gravity's 9.8 m/s^2
        np.testing.assert_allclose(excess[:, j], _integral(k, amp, freq, phases[j]), rtol=0,
                                   atol=1e-12 * amp + 1e-14)
    # 0.5 Hz on the 0.01 s grid: 10 periods are 2000 intervals, whose mean is 0; 9.5 periods' is not
    half = _model(terms=((0.0, 0.0),) * 3 + ((0.008, 0.5), (0.0, 0.0), (0.0, 0.0)))
    _, rates = _record(half, 2000)
    _, plain = _record(imu.preset("ideal"), 2000)
    assert abs((rates - plain)[:, 3].mean()) < 1e-15
    assert abs((rates - plain)[:1900, 3].mean()) > 1e-5


def test_allan_deviation_is_the_sinusoid_closed_form():
    """sigma(tau) = a sin^2(pi f tau) / (pi f tau) (IEEE Std 952 annex C's form of a sinusoid, averaged over
    the phase).  For one phase the overlapping estimator with M = K + 1 - 2m terms is that times
    sqrt(1 + e), |e| <= 1 / (M |sin(2 pi f H)|) (the mean of cos(2 theta_k + 2 pi f tau) over M samples of a
    phase advancing 4 pi f H each): the estimator's whole scatter for a deterministic sinusoid."""
    n = 100000  # 1000 s
    excess, _ = _excess(n)
    checked = 0
    for j, (amp, freq) in enumerate(TERMS):
        curve = allan_readout.octave_curve(excess[:, j], 1.0 / H)
        for tau, dev in zip(curve.taus, curve.adev):
            m = int(round(tau / H))
            x = math.pi * freq * tau
            closed = amp * math.sin(x) ** 2 / x
            if closed < 1e-3 * amp:  # near a zero of sin(pi f tau): the ratio is not defined
                continue
            bound = 1.0 / ((n + 1 - 2 * m) * abs(math.sin(2.0 * math.pi * freq * H)))
            assert math.sqrt(max(1.0 - bound, 0.0)) - 1e-9 <= dev / closed <= math.sqrt(1.0 + bound) + 1e-9, \
                (j, tau, dev / closed, bound)
            checked += 1
    assert checked > 50


def test_the_phase_comes_from_the_seed_and_shifts_no_other_draw():
    """Phases uniform on [0, 2 pi), one set per seed; the mems preset with the terms added gives the mems
    record plus exactly the terms' integrals: every other random draw (white noise, Gauss-Markov, flicker,
    rate random walk, turn-on bias) is the same."""
    n = 3000
    k = np.arange(n)
    phases = {}
    for seed in (0, 1, 2):
        excess, phases[seed] = _excess(n, seed, base="mems")
        assert np.all((phases[seed] >= 0.0) & (phases[seed] < 2.0 * math.pi))
        for j, (amp, freq) in enumerate(TERMS):  # mems: the rates are of order 1e-4 rad/s and 10 m/s^2
            np.testing.assert_allclose(excess[:, j], _integral(k, amp, freq, phases[seed][j]), rtol=0,
                                       atol=1e-11 if j < 3 else 1e-9)
    assert len({tuple(p) for p in phases.values()}) == 3
    assert np.array_equal(_excess(10, 1)[1], phases[1])  # the same seed, the same phases (ideal or mems)
    a, b = _record(_model(), 500, seed=4)[1], _record(_model(), 500, seed=5)[1]
    assert np.max(np.abs(a - b)) > 1e-3  # another seed, another record


@pytest.mark.parametrize("over,text", [
    ({"accel_periodic_amplitude_x": -1e-3, "accel_periodic_frequency_x": 0.5}, r"periodic_amplitude_x must be"),
    ({"gyro_periodic_frequency_y": -0.5}, r"periodic_frequency_y must be non-negative"),
    ({"gyro_periodic_amplitude_z": 1e-4}, r"periodic_frequency_z must be positive where the periodic amplitude"),
    ({"accel_periodic_amplitude_z": 1e-3, "accel_periodic_frequency_z": float("nan")}, "must be finite"),
])
def test_bad_amplitudes_and_frequencies_are_refused(over, text):
    with pytest.raises(ValueError, match=text):
        imu_params.apply_overrides(imu.preset("ideal"), over)


def test_the_core_checks_name_the_parameter_and_the_nyquist_bound():
    par = np.array([imu_params.flatten(imu.preset("ideal"))[name] for name in core_imu.param_names()])
    names = core_imu.param_names()
    amp, freq = names.index("accel_periodic_amplitude_y"), names.index("accel_periodic_frequency_y")
    bad = par.copy()
    bad[amp] = -1.0
    assert core_imu.check_params(bad) == "accel_periodic_amplitude_y must be non-negative"
    bad = par.copy()
    bad[amp] = 1e-3
    assert core_imu.check_params(bad).startswith("accel_periodic_frequency_y must be positive where")
    bad[freq] = 100.0  # exactly the minor loop's Nyquist frequency at 200 Hz: allowed
    assert core_imu.check_params(bad) is None and core_imu.check_periodic_params(bad, 200.0) is None
    bad[freq] = 100.000001
    assert core_imu.check_periodic_params(bad, 200.0) == (
        "accel_periodic_frequency_y = 100.000001 Hz must be at most the Nyquist frequency of the minor loop, "
        "internal_rate / 2 (internal_rate 200.0 Hz)")
    # above the output interval's Nyquist frequency (0.5 Hz at 1 s), below the minor loop's: its increments are
    # its exact integrals over the interval (aliased, as an integrating sensor's are)
    model = _model(terms=((0.0, 0.0),) * 4 + ((1e-3, 0.6), (0.0, 0.0)))
    sensor = imu.IMU(model, imu.StaticBase(0.8), output_interval=1.0, internal_rate=100.0, seed=3)
    zero = np.zeros((50, 1))
    dv = sensor.step(zero, zero, zero)[1][:, 1]
    plain = imu.IMU(imu.preset("ideal"), imu.StaticBase(0.8), output_interval=1.0, internal_rate=100.0, seed=3)
    dv0 = plain.step(zero, zero, zero)[1][:, 1]
    phase = sensor.state_arrays()[imu_step.PERIODIC][2][4]
    w = 2.0 * math.pi * 0.6
    k = np.arange(50)
    np.testing.assert_allclose(dv - dv0, 1e-3 * (np.cos(w * k + phase) - np.cos(w * (k + 1) + phase)) / w, rtol=0,
                               atol=1e-14)
    with pytest.raises(ValueError, match="IMU parameter accel_periodic_frequency_y = 0.6 Hz must be at most the "
                                         "Nyquist frequency of the minor loop"):
        imu.IMU(model, imu.StaticBase(0.8), output_interval=1.0, internal_rate=1.0)


def test_every_shipped_preset_has_no_periodic_term():
    for name in imu.PRESETS:
        flat = imu_params.flatten(imu.preset(name))
        assert all(flat[p] == 0.0 for p in imu_params.PERIODIC_NAMES), name
        assert np.array_equal(core_imu.preset_params(name), [flat[p] for p in core_imu.param_names()])
