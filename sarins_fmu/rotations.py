"""Rotation helpers: skew matrices, rotation vectors, quaternions, Euler angles.

Quaternions are scalar-first ``[w, x, y, z]`` and represent the same
transformation as the DCM ``mat_xy`` they are named after.  A rotation vector
``phi`` maps to the DCM exp([phi x]) (Rodrigues).  Euler angles follow the
Chinese-literature convention used by the seeds for ENU / right-front-up:
mat_nb = Rz(yaw) Rx(pitch) Ry(roll), yaw positive counter-clockwise about up.
All functions are plain numpy on small arrays; the ``_*`` scalar versions are
compiled and used inside the kernels.
"""

import math

import numpy as np

from ._jit import jit


def skew(v):
    """Cross-product matrix [v x], (3, 3)."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


@jit
def rotvec_to_mat(phi):
    """DCM exp([phi x]) of a rotation vector phi (3,), rad (Rodrigues)."""
    theta2 = phi[0] ** 2 + phi[1] ** 2 + phi[2] ** 2
    theta = math.sqrt(theta2)
    if theta < 1e-8:
        a = 1.0 - theta2 / 6.0
        b = 0.5 - theta2 / 24.0
    else:
        a = math.sin(theta) / theta
        b = (1.0 - math.cos(theta)) / theta2
    k = np.array([[0.0, -phi[2], phi[1]], [phi[2], 0.0, -phi[0]], [-phi[1], phi[0], 0.0]])
    return np.eye(3) + a * k + b * (k @ k)


@jit
def rotvec_to_quat(phi):
    """Quaternion [w, x, y, z] of a rotation vector phi (3,), rad."""
    theta2 = phi[0] ** 2 + phi[1] ** 2 + phi[2] ** 2
    theta = math.sqrt(theta2)
    if theta < 1e-8:
        s = 0.5 - theta2 / 48.0
        c = 1.0 - theta2 / 8.0
    else:
        s = math.sin(0.5 * theta) / theta
        c = math.cos(0.5 * theta)
    return np.array([c, s * phi[0], s * phi[1], s * phi[2]])


@jit
def quat_mult(p, q):
    """Hamilton product p * q of scalar-first quaternions."""
    return np.array([
        p[0] * q[0] - p[1] * q[1] - p[2] * q[2] - p[3] * q[3],
        p[0] * q[1] + p[1] * q[0] + p[2] * q[3] - p[3] * q[2],
        p[0] * q[2] - p[1] * q[3] + p[2] * q[0] + p[3] * q[1],
        p[0] * q[3] + p[1] * q[2] - p[2] * q[1] + p[3] * q[0],
    ])


@jit
def quat_to_mat(q):
    """DCM of a unit quaternion [w, x, y, z]."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    return np.array([
        [w * w + x * x - y * y - z * z, 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), w * w - x * x + y * y - z * z, 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), w * w - x * x - y * y + z * z],
    ])


def mat_to_quat(mat):
    """Unit quaternion [w, x, y, z] of a DCM (Shepperd's method)."""
    m = np.asarray(mat, dtype=float)
    tr = np.trace(m)
    cands = np.array([tr, m[0, 0], m[1, 1], m[2, 2]])
    i = int(np.argmax(cands))
    if i == 0:
        w = 0.5 * math.sqrt(1.0 + tr)
        q = [w, (m[2, 1] - m[1, 2]) / (4 * w), (m[0, 2] - m[2, 0]) / (4 * w), (m[1, 0] - m[0, 1]) / (4 * w)]
    elif i == 1:
        x = 0.5 * math.sqrt(1.0 + 2 * m[0, 0] - tr)
        q = [(m[2, 1] - m[1, 2]) / (4 * x), x, (m[0, 1] + m[1, 0]) / (4 * x), (m[0, 2] + m[2, 0]) / (4 * x)]
    elif i == 2:
        y = 0.5 * math.sqrt(1.0 + 2 * m[1, 1] - tr)
        q = [(m[0, 2] - m[2, 0]) / (4 * y), (m[0, 1] + m[1, 0]) / (4 * y), y, (m[1, 2] + m[2, 1]) / (4 * y)]
    else:
        z = 0.5 * math.sqrt(1.0 + 2 * m[2, 2] - tr)
        q = [(m[1, 0] - m[0, 1]) / (4 * z), (m[0, 2] + m[2, 0]) / (4 * z), (m[1, 2] + m[2, 1]) / (4 * z), z]
    q = np.array(q)
    return q / np.linalg.norm(q) * (1.0 if q[0] >= 0 else -1.0)


def mat_to_rotvec(mat):
    """Rotation vector (3,), rad, of a DCM (inverse of :func:`rotvec_to_mat`)."""
    q = mat_to_quat(mat)
    s = np.linalg.norm(q[1:])
    if s < 1e-12:
        return 2.0 * q[1:]
    return 2.0 * math.atan2(s, q[0]) * q[1:] / s


@jit
def euler_to_mat(yaw, pitch, roll):
    """mat_nb = Rz(yaw) Rx(pitch) Ry(roll) for ENU / right-front-up, angles in rad
    (the product written out element by element; compiled, so kernels call it too)."""
    cy, sy = math.cos(yaw), math.sin(yaw)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cr, sr = math.cos(roll), math.sin(roll)
    c = np.empty((3, 3))
    c[0, 0] = cy * cr - sy * sp * sr
    c[0, 1] = -sy * cp
    c[0, 2] = cy * sr + sy * sp * cr
    c[1, 0] = sy * cr + cy * sp * sr
    c[1, 1] = cy * cp
    c[1, 2] = sy * sr - cy * sp * cr
    c[2, 0] = -cp * sr
    c[2, 1] = sp
    c[2, 2] = cp * cr
    return c


def mat_to_euler(mat_nb):
    """(yaw, pitch, roll), rad, of mat_nb = Rz(yaw) Rx(pitch) Ry(roll)."""
    m = np.asarray(mat_nb)
    pitch = math.asin(max(-1.0, min(1.0, m[2, 1])))
    roll = math.atan2(-m[2, 0], m[2, 2])
    yaw = math.atan2(-m[0, 1], m[1, 1])
    return yaw, pitch, roll


def small_angle_error(mat_nb_computed, mat_nb_true):
    """Attitude error phi (3,) rad in n, defined by mat_computed = (I - [phi x]) mat_true."""
    d = np.asarray(mat_nb_computed) @ np.asarray(mat_nb_true).T
    return -mat_to_rotvec(d)
