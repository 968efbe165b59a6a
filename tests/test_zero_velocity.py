"""Zero-velocity detection from the IMU's statistics (``sarins_fmu.zero_velocity``, core ``zvd.h``):
the statistic's null distribution, detection and false alarms against the truth's stops with
numbers derived from the threshold, and navigation with detected ZUPTs against truth ZUPTs."""

import json
import math

import numpy as np
import pytest
from scipy.stats import binom

from sarins_fmu import aided
from sarins_fmu import trajectory as tr
from sarins_fmu import zero_velocity as zv
from sarins_fmu.core.aided import ZvdState

STEP = 0.01
CAR = zv.VIBRATION["car"]
# stops of 30 s between drives, a turn and braking (the truth's stop intervals are known exactly)
SEGMENTS = ({"kind": "stop", "duration": 30}, {"kind": "accelerate", "to_speed": 10, "accel": 1.0},
            {"kind": "cruise", "duration": 20}, {"kind": "accelerate", "to_speed": 0, "accel": 1.0},
            {"kind": "stop", "duration": 30}, {"kind": "accelerate", "to_speed": 8, "accel": 1.0},
            {"kind": "turn", "rate_dps": 6, "angle_deg": 90}, {"kind": "cruise", "duration": 20},
            {"kind": "accelerate", "to_speed": 0, "accel": 1.0}, {"kind": "stop", "duration": 30})


@pytest.fixture(scope="module")
def truth():
    return tr.generate(tr.Trajectory(tr.Start(lat_deg=32.0, lon_deg=118.0), SEGMENTS), STEP)


def windows_inside(mask: np.ndarray, n: int) -> np.ndarray:
    """(K,) bool: the window of n samples ending at k lies wholly where ``mask`` is true."""
    return np.convolve(mask.astype(int), np.ones(n, int))[: mask.size] == n


def disjoint(full: np.ndarray, n: int) -> np.ndarray:
    """Indices of windows ending where ``full`` is true, n samples apart within each run (no shared sample)."""
    idx, last = [], -n
    for k in np.flatnonzero(full):
        if k - last >= n:
            idx.append(k)
            last = k
    return np.array(idx)


def test_core_statistic_is_the_sample_variance_sum():
    rng = np.random.default_rng(1)
    n, h, vrw, arw = 20, 0.01, 2e-4, 3e-5
    dtheta, dv = rng.normal(size=(60, 3)) * 1e-4, rng.normal(size=(60, 3)) * 1e-3 + [0, 0, 0.098]
    stat, flag = ZvdState([n, h, vrw, arw, 100.0]).run(dtheta, dv)
    assert np.all(stat[: n - 1] == -1) and not flag[: n - 1].any()
    for k in (n - 1, 37, 59):
        f, w = dv[k - n + 1:k + 1] / h, dtheta[k - n + 1:k + 1] / h
        expected = np.sum((f - f.mean(0)) ** 2) * h / vrw**2 + np.sum((w - w.mean(0)) ** 2) * h / arw**2
        assert stat[k] == pytest.approx(expected, rel=1e-12)
        assert flag[k] == (expected <= 100.0)
    # split into two calls: the window carries over
    state = ZvdState([n, h, vrw, arw, 100.0])
    first, second = state.run(dtheta[:30], dv[:30]), state.run(dtheta[30:], dv[30:])
    np.testing.assert_array_equal(np.concatenate([first[0], second[0]]), stat)


@pytest.mark.parametrize("config, words", [([1, 0.01, 1e-4, 1e-5, 10], "window"), ([2.5, 0.01, 1e-4, 1e-5, 10], "window"),
                                           ([5000, 0.01, 1e-4, 1e-5, 10], "window"), ([10, 0.01, 0, 1e-5, 10], "positive"),
                                           ([10, 0.01, 1e-4, 1e-5, math.nan], "finite")])
def test_core_refuses_bad_settings(config, words):
    with pytest.raises(ValueError, match=words):
        ZvdState(config)


def test_bad_inputs():
    with pytest.raises(ValueError, match="finite"):
        ZvdState([4, 0.01, 1e-4, 1e-5, 10]).run(np.full((5, 3), np.nan), np.zeros((5, 3)))
    with pytest.raises(ValueError, match="noise densities"):
        zv.detect(np.zeros((5, 3)), np.zeros((5, 3)), 0.01, 0.0, 1e-5)
    with pytest.raises(ValueError, match="alpha"):
        zv.DetectorSettings(alpha=0.0)
    with pytest.raises(ValueError, match="vibration"):
        zv.Vibration(accel_rms=-1.0)
    with pytest.raises(ValueError, match="zupt_detect"):
        aided.navigate(tr.generate(tr.Trajectory(tr.Start(lat_deg=32.0, lon_deg=118.0), SEGMENTS[:1]), STEP),
                       aiding=("zupt",), zupt_detect="brake")


@pytest.mark.parametrize("grade", ["tactical", "mems"])
def test_detection_and_false_alarms_against_the_truth_stops(truth, grade):
    """alpha = 0.01: over disjoint windows wholly inside the stops the misses are Binomial(m, alpha)
    and the statistic's mean is 6 (N - 1) (chi-square, whatever the biases and gravity); over windows
    wholly in motion the Chernoff bound of a false "stationary" times their number is below 1e-6, and
    none occurs.  Every stop is found within N samples of its start."""
    noise = aided.IMU_NOISE[grade]
    settings = zv.DetectorSettings(window=0.5, alpha=0.01)
    dtheta, dv, _, _ = aided.corrupt(truth, noise, seed=5)
    vib_theta, vib_v = zv.vibrate(truth, CAR, seed=5)
    found = zv.detect(dtheta + vib_theta, dv + vib_v, STEP, noise.vrw, noise.arw, settings)
    n = found.samples
    assert n == 50 and found.gamma == pytest.approx(zv.threshold(50, 0.01))
    still = truth.stationary()
    # detection: disjoint stationary windows
    idx = disjoint(windows_inside(still, n), n)
    m = idx.size
    assert m >= 3 * (3000 // n) - 3
    misses = int(np.sum(~found.stationary[idx]))
    assert misses <= binom.isf(1e-6, m, settings.alpha)
    dof = 6 * (n - 1)
    mean_t = found.statistic[idx].mean()
    assert abs(mean_t - dof) < 5 * math.sqrt(2 * dof / m), (mean_t, dof)
    # false alarms: windows wholly in motion
    moving = windows_inside(~still, n)
    sigma_f, sigma_w = noise.vrw / math.sqrt(STEP), noise.arw / math.sqrt(STEP)
    bound = zv.moving_window_bound(n, found.gamma, sigma_f, sigma_w, CAR)
    assert moving.sum() * bound < 1e-6
    assert not np.any(found.stationary & moving)
    # every stop found within N samples of its start
    starts = np.flatnonzero(np.diff(np.concatenate([[0], still.astype(int)])) == 1)
    for s in starts:
        assert found.stationary[s:s + n].any(), s


def test_the_bound_sees_weak_vibration():
    """With vibration at the noise level the bound is no longer negligible: it is a real bound, not 0."""
    noise = aided.IMU_NOISE["tactical"]
    sigma_f, sigma_w = noise.vrw / math.sqrt(STEP), noise.arw / math.sqrt(STEP)
    gamma = zv.threshold(50, 0.01)
    weak = zv.moving_window_bound(50, gamma, sigma_f, sigma_w, zv.Vibration(0.1 * sigma_f, 0.1 * sigma_w))
    none = zv.moving_window_bound(50, gamma, sigma_f, sigma_w, zv.Vibration())
    assert weak > 0.5 and none == pytest.approx(1.0)
    assert zv.moving_window_bound(50, gamma, sigma_f, sigma_w, zv.Vibration(2 * sigma_f, 2 * sigma_w)) < 1e-6


def test_navigation_with_detected_zupts_is_close_to_truth_zupts(truth):
    """Without GNSS (ZUPT, odometer, NHC), 6 seeds: the RMS horizontal error at the end of each drive and
    at the end of the run with detected ZUPTs within 15 % of the truth-ZUPT run's, and the detected ZUPT
    steps are the truth's stop steps but for the first N - 1 of each stop (the causal window)."""
    kwargs = dict(aiding=("zupt", "odometer", "nhc"), vibration=CAR)
    ends = [int(round(t / STEP)) for t in (30.0 + 10 + 20 + 10, 130.0 + 8 + 15 + 20 + 8)]  # arrival at stops 2, 3
    errors = {"truth": [], "imu": []}
    for seed in range(6):
        for detect in errors:
            r = aided.navigate(truth, seed=seed, zupt_detect=detect, **kwargs)
            rows = np.searchsorted(r.time, [truth.time[e] for e in ends] + [truth.time[-1]])
            rows = np.minimum(rows, r.time.size - 1)
            errors[detect].append(r.horizontal_error()[rows])
            if detect == "imu" and seed == 0:
                n = r.info["detector_samples"]
                assert r.zupt_steps <= int(truth.stationary().sum()) - 3 * (n - 1) + 5
                assert r.zupt_steps >= int(truth.stationary().sum()) - 3 * (n - 1) - 30
    rms = {k: np.sqrt(np.mean(np.square(v), axis=0)) for k, v in errors.items()}
    np.testing.assert_allclose(rms["imu"], rms["truth"], rtol=0.15)


def test_cli_zupt_detect(tmp_path, capsys):
    from sarins.cli import main

    path = tmp_path / "t.json"
    path.write_text(json.dumps({"start": {"lat_deg": 32.0, "lon_deg": 118.0}, "segments": list(SEGMENTS[:5])}))
    argv = ["navigate", "--trajectory", str(path), "--aiding", "gnss,zupt", "--json", "--zupt-detect", "imu"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["zupt_detect"] == "imu" and out["vibration"] == "car"
    assert 0 < out["zupt_steps"] < 6000

    def refused(extra):
        try:
            code = main(["navigate", "--trajectory", str(path), "--aiding", "gnss,zupt", *extra])
        except SystemExit as exc:  # argparse's own refusals
            code = exc.code
        assert code == 2
        return capsys.readouterr().err

    assert "--zupt-alpha" in refused(["--zupt-detect", "imu", "--zupt-alpha", "1.5"])
    assert "--zupt-window" in refused(["--zupt-window", "0.3"])  # only with --zupt-detect imu
    assert "--imu-noise ideal" in refused(["--zupt-detect", "imu", "--imu-noise", "ideal"])
    assert "--vibration" in refused(["--vibration", "truck"])
    err = refused(["--zupt-detect", "imu", "--zupt-window", "60"])  # 6000 samples at 100 Hz: the core's limit
    assert "--zupt-window 60 s" in err and "2 .. 4096" in err
