"""Vehicle trajectory with drives, turns and stops (sarins_fmu.vehicle)."""

import math

import numpy as np
import pytest

from sarins_fmu import earth
from sarins_fmu.imu import IMU, ImuModel
from sarins_fmu.ins import InsConfig, StrapdownINS
from sarins_fmu.vehicle import VehicleTrajectory, legs_to_accelerations, random_legs

LAT = math.radians(40.0)


def test_legs_give_exact_speeds_headings_and_stops():
    legs = [("drive", 120.0, 10.0), ("turn", 90.0), ("drive", 60.0, 15.0), ("stop", 300.0), ("drive", 60.0, 5.0)]
    tr = VehicleTrajectory(legs, LAT, 0.0, 0.2, lead_time=30.0)
    assert tr.speed[30] == 0.0 and tr.speed[30 + 120] == pytest.approx(10.0)
    assert tr.heading[-1] - tr.heading[0] == pytest.approx(math.pi / 2, abs=1e-12)
    assert np.all(tr.speed >= 0.0)
    still = ~tr.moving()
    runs = np.flatnonzero(np.diff(still.astype(int)) == -1)
    assert still[:30].all() and len(runs) == 2  # lead time, then the stop
    # the gimbal schedule's heading follows the trajectory's heading
    angles = tr.schedule.state(tr.time)[0]
    np.testing.assert_allclose(angles[:, 0], tr.heading, atol=1e-9)
    tr.schedule.check_grid(1.0)


def test_ideal_imu_and_ins_follow_the_trajectory():
    """Ideal sensors on the moving base: the INS's track stays on the truth
    (the held specific force is second-order accurate inside a step)."""
    legs = [("drive", 300.0, 15.0), ("turn", -90.0), ("drive", 600.0, 20.0), ("stop", 120.0)]
    tr = VehicleTrajectory(legs, LAT, 0.1, 0.0)
    imu = IMU(ImuModel(), tr, tr.schedule.axes, output_interval=1.0, internal_rate=50.0)
    ins = StrapdownINS(InsConfig(lat=LAT, lon=0.1, align_time=0.0), initial_attitude=tr.mat_nb(0))
    angle, rate, accel = tr.schedule.state(tr.time[:-1])
    dtheta, dv, _ = imu.step(angle, rate, accel)
    out = ins.step(dtheta, dv)
    r_m, r_n = earth.radii(LAT)
    north = (out[:, 0] - tr.lat[1:]) * r_m
    east = (out[:, 1] - tr.lon[1:]) * r_n * math.cos(LAT)
    distance = np.sum(tr.speed) * tr.step
    assert distance > 15000
    assert np.max(np.hypot(north, east)) < 5.0
    np.testing.assert_allclose(out[:, 3:5], tr.velocity_n[1:, :2], atol=0.02)


def test_random_legs_are_reproducible_and_hold_the_stops():
    a = random_legs(3600.0, 5, n_stops=2, stop_range=(600.0, 900.0))
    assert a == random_legs(3600.0, 5, n_stops=2, stop_range=(600.0, 900.0))
    stops = [leg[1] for leg in a if leg[0] == "stop"]
    assert len(stops) == 3 and all(600 <= s <= 900 for s in stops[:2])


def test_bad_legs_and_times():
    with pytest.raises(ValueError, match="unknown leg"):
        legs_to_accelerations([("fly", 10.0)])
    with pytest.raises(ValueError, match="moving"):
        legs_to_accelerations([("turn", 90.0)])
    with pytest.raises(ValueError, match="positive"):
        legs_to_accelerations([("drive", -5.0, 3.0)])
    tr = VehicleTrajectory([("drive", 60.0, 5.0)], LAT)
    with pytest.raises(ValueError, match="grid"):
        tr.base_motion(np.array([0.0]), 0.5)
    with pytest.raises(ValueError, match="outside"):
        tr.base_motion(np.array([1e6]), 1.0)


def test_body_motion_pitches_and_rolls_while_moving_and_is_still_at_stops():
    from sarins_fmu.vehicle import VEHICLE_BODY_AXES, BodyMotion

    legs = [("drive", 200.0, 10.0), ("stop", 100.0), ("drive", 100.0, 10.0)]
    body = BodyMotion(seed=3)
    tr = VehicleTrajectory(legs, LAT, 0.0, 0.0, body=body)
    plain = VehicleTrajectory(legs, LAT, 0.0, 0.0)
    assert np.array_equal(tr.schedule.axes, VEHICLE_BODY_AXES) and tr.schedule.n_axes == 4
    angle, rate, _ = tr.schedule.state(tr.time)
    np.testing.assert_allclose(angle[:, 0], plain.schedule.state(plain.time)[0][:, 0], atol=1e-12)  # heading unchanged
    pitch, roll = angle[:, 1], angle[:, 2]
    still = tr.speed == 0.0
    assert np.max(np.abs(rate[still, 1:3])) < 1e-15  # still when the vehicle is (to the summed rate changes)
    bound = body.sway_pitch + 3 * body.vibration
    assert 0.3 * body.sway_pitch < np.max(np.abs(pitch)) < 2.5 * bound
    assert np.max(np.abs(roll)) > 0.3 * body.sway_roll
    assert not np.array_equal(pitch, VehicleTrajectory(legs, LAT, body=BodyMotion(seed=4)).schedule.state(tr.time)[0][:, 1])
    with pytest.raises(ValueError, match="sway_period"):
        BodyMotion(sway_period=0.0)
