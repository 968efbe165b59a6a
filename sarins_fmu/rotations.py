"""Rotation helpers: skew matrices, rotation vectors, quaternions, Euler angles.

Quaternions are scalar-first ``[w, x, y, z]`` and represent the same
transformation as the DCM ``mat_xy`` they are named after.  A rotation vector
``phi`` maps to the DCM exp([phi x]) (Rodrigues).  Euler angles follow the
Chinese-literature convention used by the seeds for ENU / right-front-up:
mat_nb = Rz(yaw) Rx(pitch) Ry(roll), yaw positive counter-clockwise about up.
:func:`rotvec_to_mat`, :func:`rotvec_to_quat`, :func:`quat_mult`,
:func:`quat_to_mat` and :func:`euler_to_mat` are thin bindings of the C
physics core (``sarins_fmu/core/rotations.c``, the one implementation the
INS kernels use too), vectorised over leading axes; the others are plain
numpy helpers used at low rate.
"""

import ctypes
import math

import numpy as np

from .core._arrays import read
from .core._lib import function


def skew(v):
    """Cross-product matrix [v x], (3, 3)."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _batched(name, args, in_shapes, out_shape):
    """Run the core's batched ``name`` over the leading axes of ``args`` (each of trailing shape in_shapes)."""
    if all(isinstance(a, np.ndarray) and a.shape == s and a.dtype == np.float64 and a.flags.c_contiguous
           for a, s in zip(args, in_shapes)):  # one item, nothing to convert: the cheap path
        out = np.empty(out_shape)
        _CORE[name](1, *(a.ctypes.data for a in args), out.ctypes.data)
        return out
    arrays = [read(a, np.shape(a), f"{name} argument {i + 1}") for i, a in enumerate(args)]
    lead = np.broadcast_shapes(*(a.shape[:a.ndim - len(s)] for a, s in zip(arrays, in_shapes)))
    for i, (a, s) in enumerate(zip(arrays, in_shapes)):
        if a.shape[a.ndim - len(s):] != s:
            raise ValueError(f"{name}: argument {i + 1} must have trailing shape {s}, got {a.shape}")
    arrays = [np.ascontiguousarray(np.broadcast_to(a, lead + s)) for a, s in zip(arrays, in_shapes)]
    out = np.empty(lead + out_shape)
    _CORE[name](int(np.prod(lead, dtype=np.int64)), *(a.ctypes.data for a in arrays), out.ctypes.data)
    return out


_VP = ctypes.c_void_p
_CORE = {name: function(f"sarins_{name}_n", None, ctypes.c_int64, *([_VP] * n_args))
         for name, n_args in (("rotvec_to_mat", 2), ("rotvec_to_quat", 2), ("quat_mult", 3), ("quat_to_mat", 2),
                              ("euler_to_mat", 2))}
_euler_to_mat = function("sarins_euler_to_mat", None, ctypes.c_double, ctypes.c_double, ctypes.c_double, _VP)


def rotvec_to_mat(phi):
    """DCM exp([phi x]) of a rotation vector phi (..., 3), rad (Rodrigues): (..., 3, 3)."""
    return _batched("rotvec_to_mat", (phi,), ((3,),), (3, 3))


def rotvec_to_quat(phi):
    """Quaternion [w, x, y, z] of a rotation vector phi (..., 3), rad: (..., 4)."""
    return _batched("rotvec_to_quat", (phi,), ((3,),), (4,))


def quat_mult(p, q):
    """Hamilton product p * q of scalar-first quaternions (..., 4)."""
    return _batched("quat_mult", (p, q), ((4,), (4,)), (4,))


def quat_to_mat(q):
    """DCM of a unit quaternion [w, x, y, z] (..., 4): (..., 3, 3)."""
    return _batched("quat_to_mat", (q,), ((4,),), (3, 3))


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


def euler_to_mat(yaw, pitch, roll):
    """mat_nb = Rz(yaw) Rx(pitch) Ry(roll) for ENU / right-front-up, angles in rad (scalars or arrays
    that broadcast): (..., 3, 3)."""
    if all(isinstance(a, (float, int)) or np.ndim(a) == 0 for a in (yaw, pitch, roll)):  # one attitude
        out = np.empty((3, 3))
        _euler_to_mat(float(yaw), float(pitch), float(roll), out.ctypes.data)
        return out
    angles = np.stack(np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in (yaw, pitch, roll))), axis=-1)
    return _batched("euler_to_mat", (angles,), ((3,),), (3, 3))


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
