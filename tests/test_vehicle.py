"""Vehicle trajectory with drives, turns and stops (sarins_fmu.vehicle)."""

import math

import numpy as np
import pytest

from sarins_fmu import earth
from sarins_fmu.core.vehicle import COLUMNS
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


# ------------------------------------------------------------------ the C kernel against closed forms


def _meridian_arc(lat0, lat1):
    """Meridian arc length (m) between two latitudes: the integral of R_M (Gauss-Legendre, 40 nodes)."""
    x, w = np.polynomial.legendre.leggauss(40)
    lat = 0.5 * (lat1 - lat0) * x + 0.5 * (lat1 + lat0)
    return 0.5 * (lat1 - lat0) * np.sum(w * earth.radii(lat)[0])


def test_north_drive_covers_the_meridian_arc_and_east_drive_the_parallel():
    """Straight drives at constant speed: the distance driven (the integral of the speed, exact on the
    grid) equals the meridian arc of the latitude change (north), and an east drive keeps the latitude
    and turns the longitude by distance / (R_N cos L)."""
    settings_legs = [("drive", 3600.0, 20.0), ("stop", 60.0)]
    north = VehicleTrajectory(settings_legs, LAT, 0.0, 0.0, rotation="none")
    distance = np.sum(0.5 * (north.speed[:-1] + north.speed[1:])) * north.step  # speed linear in each step
    n_brake = math.ceil(20.0 / 1.5)  # whole steps of the default 1.5 m/s^2 braking
    assert distance == pytest.approx(20.0 * 3600.0 - 0.5 * 20.0 * 20.0 + 0.5 * 20.0 * n_brake, rel=1e-13)
    assert _meridian_arc(LAT, north.lat[-1]) == pytest.approx(distance, abs=1e-6)  # 1 um over 72 km
    assert np.all(north.lon == 0.0)
    east = VehicleTrajectory(settings_legs, LAT, 0.1, -math.pi / 2, rotation="none")
    assert np.max(np.abs(east.lat - LAT)) < 1e-16
    r_n = earth.radii(LAT)[1]
    assert (east.lon[-1] - 0.1) * r_n * math.cos(LAT) == pytest.approx(distance, abs=1e-6)
    # velocity integrates to position on every step (Simpson mean velocity, exact for these profiles)
    r_m = earth.radii(0.5 * (north.lat[:-1] + north.lat[1:]))[0]
    step_north = np.diff(north.lat) * r_m
    mean_speed = 0.5 * (north.speed[:-1] + north.speed[1:])
    np.testing.assert_allclose(step_north, mean_speed * north.step, rtol=0, atol=1e-9)


def test_turns_and_speeds_are_exact_and_the_specific_force_is_the_kinematic_one():
    legs = [("drive", 100.0, 12.0), ("turn", 90.0), ("turn", -45.0), ("drive", 50.0, 7.0), ("stop", 30.0)]
    tr = VehicleTrajectory(legs, LAT, 0.0, 0.3, rotation="none", lead_time=10.0)
    assert tr.heading[-1] == pytest.approx(0.3 + math.radians(45.0), abs=1e-14)
    assert tr.speed[-1] == 0.0 and tr.speed[10 + 100] == 12.0  # targets reached exactly
    col = {c: j for j, c in enumerate(COLUMNS)}
    rows = tr.rows
    # at rest the specific force is gravity, up, and the frame's rate the Earth's
    still = rows[:10]
    np.testing.assert_allclose(still[:, col["f_u"]], earth.gravity(LAT, 0.0), rtol=1e-15)
    np.testing.assert_allclose(still[:, col["w_n"]], earth.RATE * math.cos(LAT), rtol=1e-15)
    # accelerating from rest: the along-track force is the acceleration (Coriolis and transport ~1e-3 m/s^2)
    k = 12
    psi = rows[k, col["yaw"]]
    along = -rows[k, col["f_e"]] * math.sin(psi) + rows[k, col["f_n"]] * math.cos(psi)
    assert along == pytest.approx(1.0, abs=2e-3)  # DriveSettings.accel


def test_body_rates_are_the_seeded_sinusoids_of_the_core_rng():
    """Pitch and roll rates on the grid equal the closed form with phases 2 pi u, u the core RNG's
    uniforms of stream 61 of the seed; the angles integrate the rates (linear in each step)."""
    from sarins_fmu.core import rng
    from sarins_fmu.vehicle import BodyMotion

    body = BodyMotion(seed=11)
    tr = VehicleTrajectory([("drive", 300.0, 10.0), ("stop", 40.0)], LAT, body=body, rotation="none")
    phase = 2 * math.pi * rng.uniforms(11, 61, 8).reshape(2, 4)
    t, s = tr.time, tr.speed
    angle, rate, acc = tr.schedule.state(t[:-1])
    w_s = 2 * math.pi / body.sway_period
    for j, amp in enumerate((body.sway_pitch, body.sway_roll)):
        q = amp * w_s * np.cos(w_s * t + phase[j, 0])
        for i, f in enumerate(body.vibration_hz):
            q = q + body.vibration * 2 * math.pi * f * np.cos(2 * math.pi * f * t + phase[j, i + 1])
        q = q * s / body.reference_speed
        np.testing.assert_allclose(rate[:, 1 + j], q[:-1], rtol=0, atol=1e-14)
        np.testing.assert_allclose(np.diff(tr.schedule.state(t)[0][:, 1 + j]), 0.5 * (q[:-1] + q[1:]) * tr.step,
                                   rtol=0, atol=1e-15)
    assert np.all(rate[s[:-1] == 0.0, 1:3] == 0.0)  # still at rest


def test_a_drive_past_the_polar_limit_is_refused_not_computed():
    """The ENU mechanisation holds to +-89.9 deg: a drive beyond is an error naming where, never NaN rows."""
    with pytest.raises(ValueError, match=r"beyond \+-89.9 deg latitude"):
        VehicleTrajectory([("drive", 2e5, 300.0), ("stop", 10.0)], math.radians(80.0))


def _vectorised_reference(tr, acc, yaw_acc, lat0, heading0):
    """The previous (numpy) construction of the same motion from the per-step accelerations: cumulative
    sums for speed and heading, two vectorised passes for the latitude, the held rate and force."""
    h, n = tr.step, acc.size
    speed = np.concatenate([[0.0], np.cumsum(acc * h)])
    yaw_rate = np.concatenate([[0.0], np.cumsum(yaw_acc * h)])
    heading = heading0 + np.concatenate([[0.0], np.cumsum(yaw_rate[:-1] * h + 0.5 * yaw_acc * h ** 2)])

    def vel(s, psi):
        return np.column_stack([-s * np.sin(psi), s * np.cos(psi), np.zeros_like(s)])

    v = vel(speed, heading)
    v_mid = vel(speed[:-1] + 0.5 * acc * h, heading[:-1] + 0.5 * yaw_rate[:-1] * h + 0.125 * yaw_acc * h ** 2)
    v_mean = (v[:-1] + 4.0 * v_mid + v[1:]) / 6.0
    lat = np.full(n + 1, lat0)
    for _ in range(2):
        lat = lat0 + np.concatenate([[0.0], np.cumsum(v_mean[:, 1] * h / earth.radii(lat[:-1])[0])])
    lat_mid = 0.5 * (lat[:-1] + lat[1:])
    r_m, r_n = earth.radii(lat_mid)
    w_ie = earth.RATE * np.column_stack([np.zeros(n), np.cos(lat_mid), np.sin(lat_mid)])
    w_en = np.column_stack([-v_mean[:, 1] / r_m, v_mean[:, 0] / r_n, v_mean[:, 0] * np.tan(lat_mid) / r_n])
    f = (v[1:] - v[:-1]) / h + np.cross(2.0 * w_ie + w_en, v_mean)
    f[:, 2] += earth.gravity(lat_mid, 0.0)
    return speed, heading, v, lat, w_ie + w_en, f


def test_the_c_stream_equals_the_previous_vectorised_construction_to_stated_bounds():
    """A 2 h random drive at 40 deg: the C stream against the numpy construction it replaced (same
    per-step accelerations).  Bounds: speed, heading and velocity to summation order (1e-12, 1e-11 m/s); the
    frame rate 1e-14 rad/s and the specific force 1e-10 m/s^2 (through the latitude); the latitude to 1 mm
    (the two-pass latitude's first-order error, which the midpoint rule removes: the meridian-arc test)."""
    legs = random_legs(7200.0, 3, n_stops=2, stop_range=(300.0, 600.0))
    tr = VehicleTrajectory(legs, LAT, 0.0, 0.7, rotation="none", lead_time=60.0)
    acc, yaw_acc = legs_to_accelerations(legs)
    acc = np.concatenate([np.zeros(60), acc, [0.0]])
    yaw_acc = np.concatenate([np.zeros(60), yaw_acc, [0.0]])
    assert acc.size == tr.n_steps
    speed, heading, v, lat, w_it, f = _vectorised_reference(tr, acc, yaw_acc, LAT, 0.7)
    np.testing.assert_allclose(tr.speed, speed, rtol=0, atol=1e-12)
    np.testing.assert_allclose(tr.heading, heading, rtol=0, atol=1e-12)
    np.testing.assert_allclose(tr.velocity_n, v, rtol=0, atol=1e-11)
    np.testing.assert_allclose(tr.base_motion(tr.time[:-1], 1.0)[0], w_it, rtol=0, atol=1e-14)
    np.testing.assert_allclose(tr.base_motion(tr.time[:-1], 1.0)[1], f, rtol=0, atol=1e-10)
    np.testing.assert_allclose((tr.lat - lat) * earth.radii(LAT)[0], 0.0, atol=1e-3)
    assert np.max(np.abs(tr.lat - lat)) > 0.0  # the integration did change (it is not the same code)
