"""Compiled major loop of the strapdown INS (ENU) and its fine-alignment filter.

Major-loop update from the IMU's compensated increments (phi, dv_b) over
[t_{k-1}, t_k] (Savage, *Strapdown Analytics* 2000, ch. 7; Titterton &
Weston 2004, ch. 11):

    zeta   = (omega_ie^n + omega_en^n) h                   nav-frame rotation
    dv_n   = (I - [zeta x]/2) mat_nb(k-1) dv_b             specific-force part
    v_k    = v_{k-1} + dv_n + (g^n - (2 omega_ie^n + omega_en^n) x v_{k-1}) h
    q_nb,k = q(-zeta) * q_nb,k-1 * q(phi)
    L, lambda advance with the trapezoidal mean velocity.

Earth and transport rate, gravity and Coriolis are evaluated at the start of
the step (first order in h; on a static base v ~ 0 and these are constant).
The vertical channel is held (height fixed, v_U = 0), the usual choice of
a marine INS without an external height reference.

State arrays are modified in place: q (4,) [w x y z], v (3,), pos (3,)
[lat rad, lon rad, height m].
"""

import math

import numpy as np

from . import earth
from ._jit import jit
from .filter_kernel import propagate, velocity_update
from .rotations import quat_mult, quat_to_mat, rotvec_to_quat


@jit
def _mech_step(q, v, pos, phi, dv_b, h, move_position):
    lat, hgt = pos[0], pos[2]
    r_m, r_n = earth.radii(lat)
    w_c, w_s = earth.RATE * math.cos(lat), earth.RATE * math.sin(lat)
    ve, vn = v[0], v[1]
    # omega_en^n and omega_in^n
    en_x = -vn / (r_m + hgt)
    en_y = ve / (r_n + hgt)
    en_z = ve * math.tan(lat) / (r_n + hgt)
    zeta = np.array([en_x * h, (w_c + en_y) * h, (w_s + en_z) * h])
    c = quat_to_mat(q)
    u = c @ dv_b
    # (I - [zeta x]/2) u
    dvn = np.array([u[0] - 0.5 * (zeta[1] * u[2] - zeta[2] * u[1]),
                    u[1] - 0.5 * (zeta[2] * u[0] - zeta[0] * u[2]),
                    u[2] - 0.5 * (zeta[0] * u[1] - zeta[1] * u[0])])
    # Coriolis (2 omega_ie + omega_en) x v
    ox, oy, oz = en_x, 2.0 * w_c + en_y, 2.0 * w_s + en_z
    v_old0, v_old1 = v[0], v[1]
    v[0] = v[0] + dvn[0] - (oy * v[2] - oz * v[1]) * h
    v[1] = v[1] + dvn[1] - (oz * v_old0 - ox * v[2]) * h
    v[2] = 0.0  # vertical channel held
    if move_position:
        pos[0] = lat + 0.5 * (v_old1 + v[1]) * h / (r_m + hgt)
        lat_mid = 0.5 * (lat + pos[0])
        pos[1] = pos[1] + 0.5 * (v_old0 + v[0]) * h / ((r_n + hgt) * math.cos(lat_mid))
    qn = quat_mult(quat_mult(rotvec_to_quat(-zeta), q), rotvec_to_quat(phi))
    qn /= math.sqrt(qn[0] ** 2 + qn[1] ** 2 + qn[2] ** 2 + qn[3] ** 2)
    q[:] = qn


@jit
def nav_steps(q, v, pos, dtheta, dv, h, gyro_comp, accel_comp, axial_corr):
    """Free navigation over K steps.

    dtheta, dv : (K, 3) increments; gyro_comp (3,) rad/s and accel_comp (3,)
    m/s^2 are subtracted (alignment estimates); axial_corr (K,) rad/s is
    subtracted from the z increment.  Returns (K, 9): lat, lon, height,
    vE, vN, vU, and the quaternion vector part is not returned -- use q.
    Output columns: lat, lon, h, vE, vN, vU, yaw, pitch, roll (rad).
    """
    n = dtheta.shape[0]
    out = np.empty((n, 9))
    phi = np.empty(3)
    u = np.empty(3)
    for k in range(n):
        for j in range(3):
            phi[j] = dtheta[k, j] - gyro_comp[j] * h
            u[j] = dv[k, j] - accel_comp[j] * h
        phi[2] -= axial_corr[k] * h
        _mech_step(q, v, pos, phi, u, h, True)
        _record(out, k, q, v, pos)
    return out


@jit
def _record(out, k, q, v, pos):
    out[k, 0], out[k, 1], out[k, 2] = pos[0], pos[1], pos[2]
    out[k, 3], out[k, 4], out[k, 5] = v[0], v[1], v[2]
    c = quat_to_mat(q)
    out[k, 7] = math.asin(min(1.0, max(-1.0, c[2, 1])))
    out[k, 8] = math.atan2(-c[2, 0], c[2, 2])
    out[k, 6] = math.atan2(-c[0, 1], c[1, 1])


@jit
def held_row(q, pos):
    """Output row of the alignment phases: the held start position, zero velocity, the attitude of q."""
    out = np.empty((1, 9))
    _record(out, 0, q, np.zeros(3), pos)
    return out[0]


@jit
def align_steps(q, v, pos, dtheta, dv, h, gyro_comp, accel_comp, x, p, q_diag, r_var):
    """Fine alignment on a static base: mechanization + 9-state Kalman filter.

    State x = [phi_E, phi_N, phi_U, dv_E, dv_N, eps_x, eps_y, nabla_x, nabla_y]
    (attitude error in n with mat_computed = (I - [phi x]) mat_true, velocity
    error, body-frame horizontal gyro drifts and accelerometer biases).
    Error model (Titterton & Weston eqs 12.6-12.7 in ENU, static, position
    known):
        phi' = phi x omega_ie^n + d omega_en^n(dv) - mat_nb eps
        dv'  = f^n x phi - 2 omega_ie^n x dv + mat_nb nabla
    Measurement: the computed E/N velocity (true velocity is zero).  The
    filter runs closed loop: after each update the attitude and velocity are
    corrected, the drift/bias estimates are added to gyro_comp/accel_comp
    (which compensate the following increments) and those states are reset.
    Position is held at the known start.  Returns (K, 9) P-diagonal history.
    """
    n = dtheta.shape[0]
    hist = np.empty((n, 9))
    phi = np.empty(3)
    u = np.empty(3)
    lat = pos[0]
    r_m, r_n = earth.radii(lat)
    w_c, w_s = earth.RATE * math.cos(lat), earth.RATE * math.sin(lat)
    g = earth.gravity(lat, pos[2])
    f = np.zeros((9, 9))
    hm = np.zeros((2, 9))
    hm[0, 3] = 1.0
    hm[1, 4] = 1.0
    eye = np.eye(9)
    for k in range(n):
        for j in range(3):
            phi[j] = dtheta[k, j] - gyro_comp[j] * h
            u[j] = dv[k, j] - accel_comp[j] * h
        c0 = quat_to_mat(q)
        _mech_step(q, v, pos, phi, u, h, False)
        # sensor errors act over the whole step: mid-step attitude (2nd order)
        c = 0.5 * (c0 + quat_to_mat(q))
        # continuous-time F (static base)
        f[0, 1], f[0, 2], f[0, 4] = w_s, -w_c, -1.0 / (r_m + pos[2])
        f[1, 0], f[1, 3] = -w_s, 1.0 / (r_n + pos[2])
        f[2, 0], f[2, 3] = w_c, math.tan(lat) / (r_n + pos[2])
        f[3, 1], f[3, 4] = -g, 2.0 * w_s
        f[4, 0], f[4, 3] = g, -2.0 * w_s
        for i in range(3):
            f[i, 5], f[i, 6] = -c[i, 0], -c[i, 1]
        for i in range(2):
            f[3 + i, 7], f[3 + i, 8] = c[i, 0], c[i, 1]
        fh = f * h
        phi_m = eye + fh + 0.5 * (fh @ fh)
        propagate(x, p, phi_m, q_diag, h)
        velocity_update(x, p, hm, eye, r_var, v[0], v[1])
        # closed-loop feedback: q_true = q(phi) * q_computed
        qn = quat_mult(rotvec_to_quat(x[0:3].copy()), q)
        q[:] = qn / math.sqrt(qn[0] ** 2 + qn[1] ** 2 + qn[2] ** 2 + qn[3] ** 2)
        v[0] -= x[3]
        v[1] -= x[4]
        gyro_comp[0] += x[5]
        gyro_comp[1] += x[6]
        accel_comp[0] += x[7]
        accel_comp[1] += x[8]
        x[:] = 0.0
        for i in range(9):
            hist[k, i] = p[i, i]
    return hist


@jit
def coarse_steps(q_b0b, v_b0, dtheta, dv):
    """Inertial-frame coarse alignment accumulators over K steps (in place):
    v_b0 += mat_b0b dv ; q_b0b = q_b0b * q(dtheta).  Returns v_b0 after each
    step, (K, 3)."""
    n = dtheta.shape[0]
    hist = np.empty((n, 3))
    for k in range(n):
        c = quat_to_mat(q_b0b)
        for i in range(3):
            v_b0[i] += c[i, 0] * dv[k, 0] + c[i, 1] * dv[k, 1] + c[i, 2] * dv[k, 2]
        qn = quat_mult(q_b0b, rotvec_to_quat(dtheta[k].copy()))
        q_b0b[:] = qn / math.sqrt(qn[0] ** 2 + qn[1] ** 2 + qn[2] ** 2 + qn[3] ** 2)
        for i in range(3):
            hist[k, i] = v_b0[i]
    return hist
