import math
from dataclasses import replace

import numpy as np
import pytest
from numpy.testing import assert_allclose

from sarins_fmu import earth, imu as imu_mod, turntable as tt
from sarins_fmu.imu import IMU, StaticBase, TriadErrors
from sarins_fmu.rotations import rotvec_to_mat
from sarins_fmu.units import DPH_TO_RPS, UG_TO_MPS2


def _run(model, sched, n, *, h=1.0, seed=0, base=None, **kw):
    base = base or StaticBase(math.radians(28.222))
    sensor = IMU(model, base, sched.axes, output_interval=h, seed=seed, **kw)
    a, r, c = sched.state(np.arange(n) * h)
    return sensor.step(a, r, c)


def test_static_ideal_increments_equal_earth_rate_and_gravity(lat):
    sched = tt.single_axis("none", 100)
    dth, dv, _ = _run(imu_mod.preset("ideal"), sched, 10)
    w = earth.earth_rate_n(lat)
    assert_allclose(dth, np.tile(w, (10, 1)), rtol=1e-9, atol=1e-18)
    # dv: the specific force (0, 0, g) integrated in the body frame at the
    # start of the step, which the Earth's rotation turns during the step:
    # int_0^h exp(s [w x]) ds f  (Rodrigues, closed form)
    g = earth.gravity(lat, 0.0)
    u = w / np.linalg.norm(w)
    k = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
    wn = np.linalg.norm(w)
    integral = np.eye(3) + (1 - math.cos(wn)) / wn * k + (1 - math.sin(wn) / wn) * (k @ k)
    assert_allclose(dv, np.tile(integral @ [0.0, 0.0, g], (10, 1)), rtol=1e-7, atol=1e-12)


def test_rotation_vector_exact_for_uniform_rotation_with_earth_rate(lat):
    """Body turning at 10 deg/s about up on a static base: the interval's
    rotation vector must be that of mat_b0b1 = mat_bn(t0) exp(w_ie h) mat_nb(t1)."""
    rate = math.radians(10.0)
    sched = tt.GimbalSchedule([tt.AXIS_Z], [0.0, 1e6], [[0.0]], [0.3], [rate])
    dth, _, _ = _run(imu_mod.preset("ideal"), sched, 3)
    w = earth.earth_rate_n(lat)
    for k in range(3):
        m0 = rotvec_to_mat(np.array([0, 0, 0.3 + rate * k]))
        m1 = rotvec_to_mat(np.array([0, 0, 0.3 + rate * (k + 1)]))
        exact = m0.T @ rotvec_to_mat(w * 1.0) @ m1  # mat_b0b1 through the inertial frame
        assert_allclose(rotvec_to_mat(dth[k]), exact, atol=2e-13)


def test_biases_and_scale_factor_enter_the_increments(lat):
    gyro_model = replace(imu_mod.preset("ideal"),
                         gyro=TriadErrors(bias=np.array([0.01, 0.0, 0.0]) * DPH_TO_RPS,
                                          scale_factor=np.array([0.0, 0.0, 1e-4])))
    accel_model = replace(imu_mod.preset("ideal"), accel=TriadErrors(bias=np.array([0.0, 50.0, 0.0]) * UG_TO_MPS2))
    sched = tt.single_axis("none", 100)
    ideal, dv0, _ = _run(imu_mod.preset("ideal"), sched, 5)
    dth, _, _ = _run(gyro_model, sched, 5)
    _, dv, _ = _run(accel_model, sched, 5)
    w = earth.earth_rate_n(lat)
    assert_allclose(dth[:, 0] - ideal[:, 0], 0.01 * DPH_TO_RPS, rtol=1e-6)
    assert_allclose(dth[:, 2] - ideal[:, 2], 1e-4 * w[2], rtol=1e-6)
    assert_allclose(dv[:, 1] - dv0[:, 1], 50 * UG_TO_MPS2, rtol=1e-6)


def test_axial_drift_follows_quadratic_temperature_model():
    model = replace(imu_mod.preset("ideal"), axial_drift_poly=np.array([1e-6, -4e-5, 2.5e-3]) * DPH_TO_RPS)
    sched = tt.single_axis("none", 100)
    ideal, _, _ = _run(imu_mod.preset("ideal"), sched, 3)
    dth, _, temps = _run(model, sched, 3)
    t = temps[:, 2]
    expected = (1e-6 * t**2 - 4e-5 * t + 2.5e-3) * DPH_TO_RPS
    assert_allclose(dth[:, 2] - ideal[:, 2], expected, rtol=1e-6)


def test_same_seed_bit_identical_different_seed_differs():
    sched = tt.single_axis("forward-reverse", 1000)
    a = _run(imu_mod.preset("nav-rlg"), sched, 500, seed=3)
    b = _run(imu_mod.preset("nav-rlg"), sched, 500, seed=3)
    c = _run(imu_mod.preset("nav-rlg"), sched, 500, seed=4)
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    assert not np.array_equal(a[0], c[0])


def test_chunked_stepping_equals_one_call():
    sched = tt.single_axis("forward-reverse", 1000)
    sensor = IMU(imu_mod.preset("mems"), StaticBase(0.5), seed=1)
    a, r, c = sched.state(np.arange(300.0))
    whole = sensor.step(a, r, c)
    sensor.reset()
    parts = [sensor.step(a[i:i + 1], r[i:i + 1], c[i:i + 1]) for i in range(300)]
    for j in range(3):
        assert np.array_equal(whole[j], np.vstack([p[j] for p in parts]))


def test_random_walk_statistics():
    """Angle random walk: per-interval noise std = ARW sqrt(h)."""
    model = replace(imu_mod.preset("ideal"), gyro=TriadErrors(random_walk=np.full(3, 1e-6)))
    sched = tt.single_axis("none", 30000)
    dth, _, _ = _run(model, sched, 20000, seed=5)
    ideal, _, _ = _run(imu_mod.preset("ideal"), sched, 1, seed=5)
    assert np.std(dth - ideal[0], axis=0) == pytest.approx(np.full(3, 1e-6), rel=0.03)


def test_bad_imu_input():
    base = StaticBase(0.5)
    with pytest.raises(ValueError, match="whole number"):
        IMU(imu_mod.preset("ideal"), base, output_interval=0.0031)
    with pytest.raises(ValueError):
        IMU(imu_mod.preset("ideal"), base, output_interval=-1.0)
    with pytest.raises(ValueError, match="unknown IMU preset"):
        imu_mod.preset("fog")
    with pytest.raises(ValueError, match="89.9"):
        StaticBase(math.radians(90.0))
    sensor = IMU(imu_mod.preset("ideal"), base)
    with pytest.raises(ValueError, match="NaN"):
        sensor.step([[np.nan]], [[0.0]], [[0.0]])
