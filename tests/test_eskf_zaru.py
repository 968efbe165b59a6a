"""Zero-angular-rate update (ZARU, eskf.h sarins_eskf_zaru) on a vehicle that stands still, against closed forms.

A static vehicle (one 300 s stop at 32 deg N, 50 Hz), MEMS-grade white gyro and accelerometer noise, known
constant gyro biases and no GNSS.  With ZUPT + ZARU the z gyro bias (body up, level vehicle) is measured
directly every step, z_z = db_g,z + white noise of std arw / sqrt(h) (the phi term, (mat_bn [omega_ie x]
phi)_z = -Omega cos L phi_E, is ~1e-8 rad/s here), so its variance is that of a constant estimated from N
white samples of variance r = arw^2 / h:  1 / sigma^2 = 1 / sigma0^2 + N / r = 1 / sigma0^2 + T / arw^2.
Without ZARU the vertical gyro bias reaches a ZUPT only through the Earth rate's second-order coupling
(phi_U' = Omega cos L phi_E - eps_U), negligible over 300 s: its sigma stays at its prior, and heading drifts
with it.
"""

import math

import numpy as np
import pytest

from sarins_fmu import aided, earth
from sarins_fmu import trajectory as tr
from sarins_fmu.core import aided as core

T, STEP, LAT = 300.0, 0.02, 32.0
GRADE = aided.IMU_NOISE["mems"]
# the filter's model: white noises and constant biases of the grade's std (no bias walks: a constant to estimate)
FILTER_NOISE = aided.ImuNoise(arw=GRADE.arw, vrw=GRADE.vrw, gyro_bias_std=GRADE.gyro_bias_std,
                              accel_bias_std=GRADE.accel_bias_std)
BIAS = np.array([0.2, -0.3, 1.5]) * GRADE.gyro_bias_std  # rad/s, body x y z (z: 15 deg/h)
SEEDS = (0, 1, 2, 3)


@pytest.fixture(scope="module")
def truth():
    return tr.generate(tr.Trajectory(tr.Start(lat_deg=LAT), ({"kind": "stop", "duration": T},)), STEP)


def imu(truth, seed):
    """White-noise increments plus the known constant gyro biases (true biases per step)."""
    dtheta, dv, bg, ba = aided.corrupt(truth, aided.ImuNoise(arw=GRADE.arw, vrw=GRADE.vrw), seed)
    return dtheta + BIAS * STEP, dv, bg + BIAS, ba


@pytest.fixture(scope="module")
def runs(truth):
    """{(aiding, seed): AidedResult} for ZUPT and ZUPT + ZARU."""
    out = {}
    for seed in SEEDS:
        data = imu(truth, seed)
        for aiding in (("zupt",), ("zupt", "zaru")):
            out[aiding, seed] = aided.navigate(truth, noise=FILTER_NOISE, aiding=aiding, imu=data, seed=seed,
                                               settings=aided.FilterSettings(out_every=50))
    return out


def closed_form_sigma(n_steps):
    """Posterior std of a constant (prior GRADE.gyro_bias_std) from n_steps samples of variance arw^2 / h."""
    r = GRADE.arw**2 / STEP
    return 1.0 / math.sqrt(1.0 / GRADE.gyro_bias_std**2 + n_steps / r)


def test_the_default_zaru_std_is_the_gyros_rate_noise_per_step(truth, runs):
    r = runs[("zupt", "zaru"), 0]
    assert r.zaru_steps == r.zupt_steps == truth.n_steps
    assert r.info["zaru_std"] == pytest.approx(GRADE.arw / math.sqrt(STEP), rel=1e-15)
    assert runs[("zupt",), 0].zaru_steps == 0


def test_z_gyro_bias_converges_with_the_closed_form_sigma(truth, runs):
    expected = closed_form_sigma(truth.n_steps)
    assert expected < 0.06 * GRADE.gyro_bias_std  # T / arw^2 dominates the prior: a real estimate
    for seed in SEEDS:
        r = runs[("zupt", "zaru"), seed]
        sigma = math.sqrt(r.cov[-1, 11, 11])
        assert sigma == pytest.approx(expected, rel=0.05)
        assert abs(r.bias_g[-1, 2] - BIAS[2]) < 3.0 * sigma
    # the errors over the seeds scatter as the sigma says (4 seeds: a loose band)
    errors = np.array([runs[("zupt", "zaru"), s].bias_g[-1, 2] - BIAS[2] for s in SEEDS])
    assert 0.2 * expected < math.sqrt(np.mean(errors**2)) < 2.5 * expected


def test_without_zaru_the_z_gyro_bias_is_unobservable_at_a_stop(runs):
    for seed in SEEDS:
        r = runs[("zupt",), seed]
        assert math.sqrt(r.cov[-1, 11, 11]) > 0.9 * GRADE.gyro_bias_std


def heading_change(r):
    """Actual heading error change over the stop (ENU phi_U, rad) and the filter's heading sigma, start and end."""
    return r.error[-1, 8] - r.error[0, 8], math.sqrt(r.cov[0, 8, 8]), math.sqrt(r.cov[-1, 8, 8])


def test_heading_drift_at_a_stop_is_bounded_with_zaru(runs):
    """Without ZARU the heading error follows the z gyro bias, b_z T (1.25 deg here); with it the
    residual bias error integrates to at most arw sqrt(T) (the angle noise itself) + int sigma_b(t) dt
    = 2 arw (sqrt(arw^2 / sigma0^2 + T) - arw / sigma0) + the prior mismatch's transient, b_z arw^2 /
    sigma0^2 ln(1 + T sigma0^2 / arw^2)."""
    arw, s0, bz = GRADE.arw, GRADE.gyro_bias_std, BIAS[2]
    bound = (arw * math.sqrt(T) + 2 * arw * (math.sqrt(arw**2 / s0**2 + T) - arw / s0)
             + bz * arw**2 / s0**2 * math.log(1 + T * s0**2 / arw**2))
    free = bz * T
    without = np.array([heading_change(runs[("zupt",), s]) for s in SEEDS])
    with_zaru = np.array([heading_change(runs[("zupt", "zaru"), s]) for s in SEEDS])
    rms_without, rms_with = (math.sqrt(np.mean(a[:, 0] ** 2)) for a in (without, with_zaru))
    assert rms_without > 0.4 * free  # drifting with the bias (the ZUPT's gyrocompassing takes a little)
    assert np.abs(with_zaru[:, 0]).max() < 3.0 * bound < 0.4 * free
    assert rms_with < 0.25 * rms_without
    # the filter knows it: the heading sigma stays at its start with ZARU, grows without
    assert (with_zaru[:, 2] < 1.01 * with_zaru[:, 1]).all()
    assert (without[:, 2] > 2.0 * without[:, 1]).all()


@pytest.mark.parametrize("value", [-1e-4, 0.0, math.nan, math.inf, True, "1e-4"])
def test_bad_zaru_std_is_refused_naming_it(value):
    with pytest.raises(ValueError, match="zaru_std"):
        aided.FilterSettings(zaru_std=value)


def test_the_core_refuses_a_zaru_std_that_is_not_positive(truth):
    cfg = aided._config(FILTER_NOISE, aided.FilterSettings(), None, STEP)
    assert cfg.shape == (core.ESKF_CONFIG,)
    cfg[-1] = 0.0  # SARINS_ESKF_ZARU_STD: appended last
    with pytest.raises(ValueError, match="ZARU"):
        core.EskfState(cfg, truth.nav_rows()[0])


def test_an_ideal_gyro_gets_a_positive_floor():
    assert aided.zaru_std(aided.IMU_NOISE["ideal"], aided.FilterSettings(), STEP) == aided.ZARU_STD_FLOOR
    assert aided.zaru_std(GRADE, aided.FilterSettings(zaru_std=1e-3), STEP) == 1e-3


def test_zaru_follows_the_imu_detectors_stops():
    """zupt_detect='imu': ZARU at the detector's stationary steps, with or without ZUPT."""
    from sarins_fmu import zero_velocity as zv

    segs = ({"kind": "stop", "duration": 8}, {"kind": "accelerate", "to_speed": 5, "accel": 1.0},
            {"kind": "cruise", "duration": 5}, {"kind": "accelerate", "to_speed": 0, "accel": 1.0},
            {"kind": "stop", "duration": 8})
    truth = tr.generate(tr.Trajectory(tr.Start(lat_deg=LAT), segs), STEP)
    kwargs = dict(noise=GRADE, seed=2, zupt_detect="imu", vibration=zv.VIBRATION["car"],
                  detector=zv.DetectorSettings(window=0.3))
    both = aided.navigate(truth, aiding=("zupt", "zaru"), **kwargs)
    alone = aided.navigate(truth, aiding=("zaru",), **kwargs)
    still = int(truth.stationary().sum())
    assert 0.8 * still < both.zaru_steps == both.zupt_steps <= still
    assert alone.zaru_steps == both.zaru_steps and alone.zupt_steps == 0
    assert "detector_gamma" in alone.info


def test_gyrocompassing_with_a_perfect_gyro_checks_the_attitude_block():
    """A perfect gyro (no noise, no bias; zaru_std 1e-7 rad/s chosen) on a level vehicle heading 30 deg: the
    ZUPT finds the tilt, then the horizontal ZARU rows see Omega cos L phi_U, so the heading is estimated as
    a constant from N white samples: 1 / sigma^2 = 1 / sigma0^2 + N (Omega cos L)^2 / r.  A wrong sign of the
    phi block would drive the heading away from the truth instead of to it."""
    truth = tr.generate(tr.Trajectory(tr.Start(lat_deg=LAT, heading_deg=30.0), ({"kind": "stop", "duration": 60},)),
                        STEP)
    settings = aided.FilterSettings(zaru_std=1e-7, out_every=50)
    om = earth.RATE * math.cos(math.radians(LAT))
    expected = 1.0 / math.sqrt(1.0 / settings.heading0_std**2 + truth.n_steps * om**2 / settings.zaru_std**2)
    for seed in range(3):
        r = aided.navigate(truth, noise=aided.IMU_NOISE["ideal"], aiding=("zupt", "zaru"), seed=seed, settings=settings)
        sigma = math.sqrt(r.cov[-1, 8, 8])
        assert sigma == pytest.approx(expected, rel=0.05)
        assert abs(r.error[-1, 8]) < 3.0 * sigma
        without = aided.navigate(truth, noise=aided.IMU_NOISE["ideal"], aiding=("zupt",), seed=seed, settings=settings)
        assert math.sqrt(without.cov[-1, 8, 8]) > 50.0 * sigma  # the ZUPT alone, with a perfect gyro, in 60 s
