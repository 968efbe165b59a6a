import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from sarins_fmu import turntable as tt


@pytest.mark.parametrize("angle", [math.pi, -0.5 * math.pi, 2 * math.pi, 0.01])
def test_moves_cover_the_angle_exactly_from_rest_to_rest(angle):
    segs = tt.move_segments(angle, math.radians(6), math.radians(6), 1.0)
    sched = tt.schedule_from_segments([tt.AXIS_Z], segs)
    a, r, _ = sched.state(sched.end_time)
    assert_allclose(a[0, 0], angle, rtol=1e-12)
    assert abs(r[0, 0]) < 1e-15
    assert all(abs(d / 1.0 - round(d)) < 1e-12 for d, _ in segs)
    _, rates, acc = sched.state(np.arange(0, sched.end_time, 0.25))
    assert np.max(np.abs(rates)) <= math.radians(6) * (1 + 1e-12)
    assert np.max(np.abs(acc)) <= math.radians(6) * (1 + 1e-12)


def test_state_is_continuous_and_exactly_quadratic():
    sched = tt.single_axis("four-position", 3600, rate_dps=10, accel_dps2=5, dwell=60)
    t = np.arange(0.0, 3600.0, 0.5)
    a, r, acc = sched.state(t)
    # rebuilding each step from its start state gives the next start state
    a_pred = a[:-1] + r[:-1] * 0.5 + 0.5 * acc[:-1] * 0.25
    assert_allclose(a_pred, a[1:], atol=1e-12)
    assert_allclose(r[:-1] + acc[:-1] * 0.5, r[1:], atol=1e-12)
    positions = np.degrees(a[r[:, 0] == 0, 0]) % 360
    assert set(np.round(positions, 6)) == {0.0, 90.0, 180.0, 270.0}


def test_alignment_indexes_then_navigation_scheme_starts_at_rest():
    sched = tt.single_axis("continuous", 6 * 3600, align_time=4 * 3600)
    _, r, _ = sched.state([4 * 3600 - 1.0, 4 * 3600.0, 4 * 3600 + 100.0])
    assert r[0, 0] == 0.0 and r[1, 0] == 0.0
    assert r[2, 0] == pytest.approx(math.radians(6.0), rel=1e-3)


def test_grid_check():
    sched = tt.single_axis("forward-reverse", 3600, grid=1.0)
    sched.check_grid(1.0)
    sched.check_grid(0.005)
    with pytest.raises(ValueError, match="not on the output grid"):
        sched.check_grid(0.3)


def test_bad_schedule_input():
    with pytest.raises(ValueError, match="unknown rotation scheme"):
        tt.single_axis("sideways")
    with pytest.raises(ValueError):
        tt.single_axis("continuous", rate_dps=float("nan"))
    with pytest.raises(ValueError):
        tt.single_axis("continuous", rate_dps=-1)
    with pytest.raises(ValueError):
        tt.GimbalSchedule([[0, 0, 2.0]], [0.0, 1.0], [[0.0]], [0.0], [0.0])
