"""The core's 15-state error-state Kalman filter (eskf.h) through its binding and sarins_fmu.aided."""

import math

import numpy as np
import pytest

from sarins_fmu import aided, gnss
from sarins_fmu import trajectory as tr
from sarins_fmu.core import aided as core

SEGMENTS = ({"kind": "stop", "duration": 20}, {"kind": "accelerate", "to_speed": 15, "accel": 1.0},
            {"kind": "turn", "rate_dps": 6, "angle_deg": 180}, {"kind": "cruise", "duration": 20},
            {"kind": "turn", "rate_dps": -6, "angle_deg": 90}, {"kind": "accelerate", "to_speed": 0, "accel": 1.5},
            {"kind": "stop", "duration": 10})
WHITE_GNSS = gnss.WHITE


@pytest.fixture(scope="module")
def truth():
    return tr.generate(tr.Trajectory(tr.Start(lat_deg=32.0, height=20.0), SEGMENTS), 0.02)


def config(changes=None):
    noise, settings = aided.IMU_NOISE["tactical"], aided.FilterSettings()
    arr = aided._config(noise, settings, None, 0.02)
    for i, v in (changes or {}).items():
        arr[i] = v
    return arr


def test_without_updates_the_filter_is_the_mechanization(truth):
    state = core.EskfState(config(), truth.nav_rows()[0])
    k = truth.n_steps
    out = state.run(truth.dtheta, truth.dv, np.zeros((k, core.ESKF_AID)), np.zeros((0, 11)), np.ones(3), True, 1)
    q = aided.euler_to_mat(*truth.attitude[0])
    from sarins_fmu.rotations import mat_to_quat
    q = mat_to_quat(q).copy()
    rows = core.nav3_steps(q, truth.velocity_n[0].copy(), truth.nav_rows()[0, :3].copy(), truth.dtheta, truth.dv, 0.02)
    # the same mechanization; the batch call Kahan-sums the position, the filter steps one by one
    assert np.abs(out[:, :9] - rows).max() < 1e-12
    p = out[-1, 15:].reshape(15, 15)
    assert np.array_equal(p, p.T)
    # free inertial: the position variance grows
    assert out[-1, 15] > out[0, 15]


def test_gnss_and_zupt_bound_the_errors_and_keep_p_positive(truth):
    r = aided.navigate(truth, gnss=WHITE_GNSS, seed=4)
    assert r.gnss_used == int(truth.time[-1]) and r.zupt_steps == (20 + 10) * 50
    assert np.abs(r.error[:, :2]).max() < 3.0
    assert np.abs(r.error[-1, 3:6]).max() < 0.05  # at the final stop
    for p in r.cov[::50]:
        assert np.array_equal(p, p.T) and np.linalg.eigvalsh(p).min() > 0
    # heading becomes observable through the accelerations and turns: its sigma shrinks from 5 mrad
    assert math.sqrt(r.cov[-1, 8, 8]) < 0.5 * 5e-3


def test_diagonal_covariance_keeps_the_run_and_drops_only_p(truth):
    """covariance='diagonal': the same navigation, biases and variances bit for bit, no P (so no NEES, a
    clear error), the horizontal sigma from the variances; an unknown choice is refused naming it."""
    full = aided.navigate(truth, gnss=WHITE_GNSS, seed=4, aiding=("gnss", "zupt", "nhc"))
    diag = aided.navigate(truth, gnss=WHITE_GNSS, seed=4, aiding=("gnss", "zupt", "nhc"), covariance="diagonal")
    assert diag.cov is None and diag.variance.shape == (full.time.size, 15)
    for name in ("nav", "bias_g", "bias_a", "error", "variance"):
        assert np.array_equal(getattr(full, name), getattr(diag, name)), name
    assert np.array_equal(full.variance, np.diagonal(full.cov, axis1=1, axis2=2))
    assert np.array_equal(diag.horizontal_sigma(), full.horizontal_sigma())
    with pytest.raises(ValueError, match="NEES needs the filter's full covariance"):
        diag.nees("position")
    with pytest.raises(ValueError, match="covariance must be one of full, diagonal, got 'upper'"):
        aided.navigate(truth, gnss=WHITE_GNSS, covariance="upper")


def test_lever_arm_is_estimated_away(truth):
    lever = gnss.GNSSConfig(**{**WHITE_GNSS.__dict__, "lever_arm": (0.5, 1.5, 1.2)})
    with_lever = aided.navigate(truth, gnss=lever, seed=2)
    assert np.abs(with_lever.error[-100:, :3]).max() < 3.0
    nees = with_lever.nees("position")
    assert nees[len(nees) // 2:].mean() < 6.0


@pytest.mark.parametrize("index, value, words", [
    (1, -1.0, "negative"), (0, 0.0, "step"), (15, 0.0, "ZUPT"), (16, 0.5, "cov_every"), (2, math.nan, "finite")])
def test_bad_settings_are_refused(truth, index, value, words):
    with pytest.raises(ValueError, match=words):
        core.EskfState(config({index: value}), truth.nav_rows()[0])


SANITIZED_RUN = """
import numpy as np
from sarins_fmu import aided, gnss, trajectory as tr
from sarins_fmu.core import _lib
assert str(_lib.library_path()) == {lib!r}
segs = ({{"kind": "stop", "duration": 5}}, {{"kind": "accelerate", "to_speed": 5, "accel": 1.0}},
        {{"kind": "turn", "radius": 50, "angle_deg": 90}}, {{"kind": "climb", "to_pitch_deg": 3, "duration": 2}},
        {{"kind": "accelerate", "to_speed": 0, "accel": 1.0}}, {{"kind": "stop", "duration": 3}})
truth = tr.generate(tr.Trajectory(tr.Start(lat_deg=30.0), segs), 0.05)
cfg = gnss.preset("sps", rate_hz=2.0, lever_arm=(0.1, 0.5, 1.0), latency=0.1)
r = aided.navigate(truth, gnss=cfg, outages=[[8, 12]], seed=1)
assert np.isfinite(r.error).all()
from sarins_fmu import zero_velocity as zv
r = aided.navigate(truth, gnss=cfg, seed=2, zupt_detect="imu", vibration=zv.VIBRATION["car"],
                   detector=zv.DetectorSettings(window=0.3), aiding=("gnss", "zupt", "zaru"))
assert np.isfinite(r.error).all() and r.zupt_steps > 0 and r.zaru_steps == r.zupt_steps
r = aided.navigate(truth, gnss=cfg, seed=3, aiding=("gnss", "zupt", "zaru", "nhc", "odometer"), imu_stream="core")
assert np.isfinite(r.error).all() and r.zupt_steps == int(truth.stationary().sum()) > 0
print("sanitized run ok")
"""


@pytest.mark.slow
def test_aided_kernels_under_address_and_undefined_behaviour_sanitizers(tmp_path):
    """Rebuild the core with ASan + UBSan and run trajectory, GNSS, zero-velocity detector and filter (ZUPT and
    ZARU; then every aiding on the core's streams: aid_noise.h) through the binding."""
    import sanitized_core

    sanitized_core.run(tmp_path, SANITIZED_RUN)


def test_gnss_latency_is_compensated(truth):
    """Fixes valid 0.2 s before they arrive (12 m/s: 3 m of travel): the filter takes its position
    back by v latency, so the errors stay those of a receiver without latency."""
    late = gnss.GNSSConfig(**{**WHITE_GNSS.__dict__, "latency": 0.2, "rate_hz": 5.0})
    prompt = gnss.GNSSConfig(**{**WHITE_GNSS.__dict__, "rate_hz": 5.0})
    rms = [np.sqrt(np.mean(aided.navigate(truth, gnss=cfg, seed=6).horizontal_error() ** 2)) for cfg in (late, prompt)]
    assert rms[0] < 1.2 * rms[1] and rms[0] < 1.0
