"""Trajectories from segments (sarins_fmu.trajectory, core traj.h) and the 3-D mechanization (nav3.h):
closed forms of the truth, and the ideal IMU navigating back to the truth."""

import json
import math

import numpy as np
import pytest

from sarins_fmu import earth
from sarins_fmu import trajectory as tr
from sarins_fmu.core import aided
from sarins_fmu.rotations import euler_to_mat, mat_to_quat
from sarins_fmu.units import DEG_TO_RAD

LAT_DEG = 32.0
# turns at a rate with whole-second durations, so every grid below carries the same trajectory
SEGMENTS = [{"kind": "stop", "duration": 10}, {"kind": "accelerate", "to_speed": 15, "accel": 1.0},
            {"kind": "cruise", "duration": 30}, {"kind": "turn", "rate_dps": 3, "angle_deg": 90},
            {"kind": "climb", "to_pitch_deg": 5, "duration": 5}, {"kind": "cruise", "duration": 60},
            {"kind": "climb", "to_pitch_deg": 0, "duration": 5}, {"kind": "turn", "rate_dps": -6, "duration": 30},
            {"kind": "accelerate", "to_speed": 0, "accel": 1.5}, {"kind": "stop", "duration": 20}]


def trajectory(segments=SEGMENTS, **start):
    return tr.Trajectory(tr.Start(lat_deg=LAT_DEG, lon_deg=118.0, height=50.0, **start), tuple(segments))


def navigate(truth):
    """Ideal increments through the 3-D mechanization from the true start; (K, 9) rows."""
    q = mat_to_quat(euler_to_mat(*truth.attitude[0])).copy()
    v = truth.velocity_n[0].copy()
    pos = np.array([truth.lat[0], truth.lon[0], truth.height[0]])
    return aided.nav3_steps(q, v, pos, truth.dtheta, truth.dv, truth.step)


def end_error(truth, rows):
    """North, east, up position error (m) at the end."""
    t, o = truth.nav_rows()[-1], rows[-1]
    r_m, r_n = earth.radii(t[0])
    return np.array([(o[0] - t[0]) * (r_m + t[2]), (o[1] - t[1]) * (r_n + t[2]) * math.cos(t[0]), o[2] - t[2]])


def test_standing_still_is_earth_rate_and_gravity():
    truth = tr.generate(trajectory([{"kind": "stop", "duration": 5}], heading_deg=0.0), 0.01)
    lat = LAT_DEG * DEG_TO_RAD
    assert np.allclose(truth.omega_ib_b, [0.0, earth.RATE * math.cos(lat), earth.RATE * math.sin(lat)], atol=1e-18)
    assert np.allclose(truth.f_b, [0.0, 0.0, earth.gravity(lat, 50.0)], atol=1e-12)
    assert np.all(truth.velocity_n == 0.0) and np.ptp(truth.lat) == 0.0
    assert truth.stationary().all()


def test_turn_and_climb_closed_forms():
    segs = [{"kind": "accelerate", "to_speed": 20, "accel": 2.0}, {"kind": "turn", "radius": 400, "angle_deg": 90},
            {"kind": "climb", "to_pitch_deg": 10, "duration": 10}, {"kind": "cruise", "duration": 10}]
    truth = tr.generate(trajectory(segs), 0.01)
    k_turn = 1000 + 200  # 10 s accelerating, then 2 s into the turn
    n_turn = round(math.pi / 2 / (20.0 / 400.0) / 0.01)
    rate = math.pi / 2 / (n_turn * 0.01)  # the angle exactly, the rate put on the grid
    # left turn: centripetal acceleration -s r along body x (right) plus the Coriolis -2 W sin(L) s
    # (heading 0.1 rad from north here), yaw rate r (+ Earth rate)
    coriolis = 2 * earth.RATE * math.sin(LAT_DEG * DEG_TO_RAD) * 20.0
    assert truth.f_b[k_turn, 0] == pytest.approx(-20.0 * rate - coriolis, rel=1e-5)
    assert truth.omega_ib_b[k_turn, 2] == pytest.approx(rate, rel=1e-3)
    assert truth.attitude[1000 + n_turn, 0] == pytest.approx(math.pi / 2, abs=1e-12)
    # pitch rate 1 deg/s about body x, then a 10 deg climb: h' = s sin(10 deg)
    k_climb = 1000 + n_turn + 500
    # heading west: body x (right) points north, where Earth rate W cos L and transport rate v_E / R_N lie
    r_n = earth.radii(truth.lat[k_climb])[1] + truth.height[k_climb]
    north_rate = earth.RATE * math.cos(truth.lat[k_climb]) - 20.0 * math.cos(5 * DEG_TO_RAD) / r_n
    assert truth.omega_ib_b[k_climb, 0] == pytest.approx(DEG_TO_RAD + north_rate, rel=1e-6)
    rise = truth.height[-1] - truth.height[-1001]
    assert rise == pytest.approx(10.0 * 20.0 * math.sin(10 * DEG_TO_RAD), rel=1e-9)
    # accelerating: specific force forward = a + g sin(pitch) (here pitch 0)
    assert truth.f_b[500, 1] == pytest.approx(2.0, rel=1e-4)


def test_runge_kutta_substeps_converge():
    coarse, fine = tr.generate(trajectory(), 0.01, 2), tr.generate(trajectory(), 0.01, 8)
    assert np.abs(coarse.dtheta - fine.dtheta).max() < 1e-15
    assert np.abs(coarse.dv - fine.dv).max() < 1e-12
    assert np.abs(coarse.lat - fine.lat).max() * 6.4e6 < 1e-9


def test_ideal_imu_navigates_back_with_second_order_algorithm_error():
    """The increments integrate back to the truth: the whole difference is the mechanization's
    second-order algorithm error (halving the step quarters it; 3.6e-5 m after 215 s at 100 Hz, from
    the mid-step Coriolis and transport rate taken at the chord of a turning velocity); extrapolated
    to step 0 (Richardson) what is left is 5.6e-9 m after 215 s (9.4e-8 m/h; 6.5e-8 m before the
    position sums were Kahan-compensated: one ulp of 0.56 rad is 0.7 nm)."""
    errors = {}
    for step in (0.02, 0.01):
        truth = tr.generate(trajectory(), step, 4)
        rows = navigate(truth)
        errors[step] = end_error(truth, rows)
        if step == 0.01:
            assert np.abs(rows[:, 3:6] - truth.velocity_n[1:]).max() < 1e-8
            assert np.abs(np.angle(np.exp(1j * (rows[:, 6:] - truth.attitude[1:])))).max() < 1e-10
    assert np.linalg.norm(errors[0.01]) < 5e-5
    ratio = np.linalg.norm(errors[0.02][:2]) / np.linalg.norm(errors[0.01][:2])
    assert 3.8 < ratio < 4.2
    residual = errors[0.01] - (errors[0.02] - errors[0.01]) / 3.0  # Richardson, order 2
    hours = truth.time[-1] / 3600.0
    assert np.linalg.norm(residual) / hours < 1e-6


@pytest.mark.parametrize("segments, words", [
    ([{"kind": "accelerate", "to_speed": 5, "accel": 1}, {"kind": "stop", "duration": 5}], "discontinuity"),
    ([{"kind": "cruise", "duration": 5, "speed": 3}], "discontinuity"),
    ([{"kind": "stop", "duration": 0.005}], "whole number of IMU steps"),
    ([{"kind": "hover", "duration": 5}], "unknown kind"),
    ([{"kind": "turn", "radius": 50, "angle_deg": 90}], "moving vehicle"),
    ([{"kind": "accelerate", "duration": 5, "accel": -1}], "negative"),
    ([{"kind": "stop", "duration": 5, "speed": 1}], "unknown key"),
    ([{"kind": "climb", "to_pitch_deg": 95, "duration": 5}], "89"),
])
def test_bad_segments_are_named(segments, words):
    with pytest.raises(tr.TrajectoryError, match=words):
        tr.generate(trajectory(segments), 0.01)


def test_json_file_round_trip(tmp_path):
    path = tmp_path / "t.json"
    path.write_text(json.dumps({"start": {"lat_deg": LAT_DEG, "lon_deg": 118.0, "height": 50.0},
                                "segments": SEGMENTS}))
    loaded = tr.load_trajectory(path)
    assert np.array_equal(loaded.table(0.01), trajectory().table(0.01))
    path.write_text("{not json")
    with pytest.raises(tr.TrajectoryError, match="not JSON"):
        tr.load_trajectory(path)
    path.write_text(json.dumps({"start": {}, "segments": SEGMENTS}))
    with pytest.raises(tr.TrajectoryError, match="lat_deg"):
        tr.load_trajectory(path)
