import numpy as np
import pytest
from numpy.testing import assert_allclose

from sarins_fmu import rotations as rot


@pytest.mark.parametrize("phi", [[0.1, -0.2, 0.3], [1e-10, 0, 2e-10], [0.0, 0.0, 3.0]])
def test_rotvec_quat_mat_round_trips(phi):
    phi = np.array(phi)
    m = rot.rotvec_to_mat(phi)
    assert_allclose(m @ m.T, np.eye(3), atol=1e-15)
    assert_allclose(rot.quat_to_mat(rot.rotvec_to_quat(phi)), m, atol=1e-15)
    assert_allclose(rot.mat_to_rotvec(m), phi, atol=1e-14)


def test_rotvec_is_active_rotation_about_z():
    m = rot.rotvec_to_mat(np.array([0.0, 0.0, np.pi / 2]))
    assert_allclose(m @ [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], atol=1e-15)


def test_quaternion_product_composes_dcms():
    a, b = np.array([0.3, 0.1, -0.2]), np.array([-0.5, 0.4, 0.2])
    q = rot.quat_mult(rot.rotvec_to_quat(a), rot.rotvec_to_quat(b))
    assert_allclose(rot.quat_to_mat(q), rot.rotvec_to_mat(a) @ rot.rotvec_to_mat(b), atol=1e-15)


def test_euler_convention_yaw_ccw_from_north():
    # yaw +90 deg (towards west): body front axis (y) points west (-E)
    m = rot.euler_to_mat(np.pi / 2, 0.0, 0.0)
    assert_allclose(m @ [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], atol=1e-15)
    angles = (0.4, -0.3, 0.2)
    assert_allclose(rot.mat_to_euler(rot.euler_to_mat(*angles)), angles, atol=1e-14)


def test_small_angle_error_sign():
    true = rot.euler_to_mat(0.2, 0.01, 0.0)
    phi = np.array([1e-5, -2e-5, 3e-5])
    computed = (np.eye(3) - rot.skew(phi)) @ true
    assert_allclose(rot.small_angle_error(computed, true), phi, rtol=1e-4)
