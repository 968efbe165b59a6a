"""The ZUPT / NHC pseudo-measurements' jitter of the C core (aid_noise.h, stream 33) and the stillness decision
shared by navigate and the TrajectoryIMU FMU: five normals per step whatever the flags, the values of a step
depending only on (seed, step), the stated statistics; navigate(imu_stream='core') applies exactly these rows
and the numpy default keeps its own draws."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sarins_fmu import aided
from sarins_fmu import trajectory as tr
from sarins_fmu.core import aided as core
from sarins_fmu.core import rng

START = tr.Start(lat_deg=30.0, lon_deg=110.0, height=10.0, heading_deg=20.0)
SEGMENTS = ({"kind": "stop", "duration": 2}, {"kind": "accelerate", "to_speed": 5, "accel": 1.0},
            {"kind": "turn", "rate_dps": 10, "angle_deg": 30}, {"kind": "accelerate", "to_speed": 0, "accel": 1.0},
            {"kind": "stop", "duration": 1})


def test_the_jitter_is_stream_33s_normals_five_per_step_whatever_the_flags():
    k, seed = 200, 9
    flags = np.random.default_rng(0).integers(0, 2, (2, k))
    got = core.aid_noise_run(0.01, 0.05, seed, flags[0], flags[1])
    draws = rng.normals(seed, 33, 5 * k).reshape(k, 5)
    want = np.column_stack([(flags[0] * 0.01)[:, None] * draws[:, :3], (flags[1] * 0.05)[:, None] * draws[:, 3:]])
    np.testing.assert_array_equal(got, want)
    all_on = core.aid_noise_run(0.01, 0.05, seed, np.ones(k), np.ones(k))
    on = np.column_stack([flags[0]] * 3 + [flags[1]] * 2) == 1
    np.testing.assert_array_equal(got[on], all_on[on])  # a step's values do not depend on other steps' flags
    assert np.all(got[~on] == 0.0)
    assert not np.array_equal(all_on, core.aid_noise_run(0.01, 0.05, seed + 1, np.ones(k), np.ones(k)))


def test_the_jitter_has_the_stated_std():
    k = 20000
    out = core.aid_noise_run(0.02, 0.07, 5, np.ones(k), np.ones(k))
    for values, sigma in ((out[:, :3].ravel(), 0.02), (out[:, 3:].ravel(), 0.07)):
        n = values.size
        assert abs(np.std(values) / sigma - 1) < 5 / math.sqrt(2 * n)
        assert abs(np.mean(values)) < 5 * sigma / math.sqrt(n)
    assert abs(np.corrcoef(out[:, 0], out[:, 3])[0, 1]) < 5 / math.sqrt(k)


@pytest.mark.parametrize("std, flag", [(-1.0, 1), (math.nan, 1), (0.01, 2)])
def test_bad_stds_and_flags_are_refused(std, flag):
    with pytest.raises(ValueError, match="finite and >= 0 and the flags 0 or 1"):
        core.aid_noise_run(std, 0.05, 0, [flag], [0])


def test_stillness_is_zero_speed_at_both_ends():
    v = np.array([[0, 0, 0], [0, 0, 0], [0, 2e-9, 0], [0, 0, 0], [5e-10, 5e-10, 5e-10], [0, 0, 0], [1, 0, 0.0]])
    np.testing.assert_array_equal(core.aid_still(v), [True, False, False, True, True, False])
    truth = tr.generate(tr.Trajectory(START, SEGMENTS), 0.01)
    still = truth.stationary()
    assert still[:200].all() and not still[200:-100].any() and still[-99:].all()


def test_navigate_core_applies_the_core_jitter_and_numpy_keeps_its_own():
    truth = tr.generate(tr.Trajectory(START, SEGMENTS), 0.01)
    settings = aided.FilterSettings()
    aiding = ("zupt", "nhc", "zaru")
    rows = aided.per_step_aiding(truth, aiding, settings, None, None, 3, stream="core")
    still = truth.stationary()
    jitter = core.aid_noise_run(settings.zupt_std, settings.nhc_std, 3, still, ~still)
    np.testing.assert_array_equal(rows[:, [0, 9]], np.column_stack([still, still]))
    np.testing.assert_array_equal(rows[:, 6], ~still)
    np.testing.assert_array_equal(rows[:, [1, 2, 3, 7, 8]], jitter)
    numpy_rows = aided.per_step_aiding(truth, aiding, settings, None, np.random.default_rng([3, 3018]), 3)
    np.testing.assert_array_equal(numpy_rows[:, [0, 6, 9]], rows[:, [0, 6, 9]])
    assert not np.array_equal(numpy_rows[:, 1:4], rows[:, 1:4])
    core_run = aided.navigate(truth, aiding=aiding, seed=3, imu_stream="core")
    imu = aided.corrupt(truth, aided.IMU_NOISE["tactical"], 3, stream="core")
    numpy_run = aided.navigate(truth, aiding=aiding, seed=3, imu=imu)  # the same IMU, numpy's jitter
    assert core_run.zupt_steps == numpy_run.zupt_steps == still.sum()
    assert not np.array_equal(core_run.nav, numpy_run.nav)
    with pytest.raises(ValueError, match="stream"):
        aided.per_step_aiding(truth, aiding, settings, None, None, 3, stream="other")
