"""Compiled minor loop of the IMU: true motion, sensor errors, coning, sculling.

One call processes K output intervals of length ``h``, each split into
``n_sub`` minor steps at the internal rate.  For every minor step the kernel

1. rebuilds the true gimbal motion (angle quadratic, rate linear in time
   inside the interval, see :mod:`sarins_fmu.turntable`) and the true angular
   rate and specific force in the body frame,
       omega_ib_b = mat_bt omega_it_t + omega_tb_b,   f_b = mat_bt f_t,
   where omega_it_t and f_t are the base frame's inertial rate and specific
   force (static base: Earth rate and -gravity);
2. integrates them over the minor step (trapezoid: exact for the gimbal
   rates, which are linear in time);
3. applies the deterministic sensor errors (scale factor, misalignment,
   bias, g-sensitivity, rate nonlinearity) to the minor increments
   dalpha_m, dnu_m;
4. composes the minor rotations into the interval's attitude change with a
   quaternion, q_{b(k-1) b(m)} = q_{b(k-1) b(m-1)} * q(dphi_m), where
   dphi_m = dalpha_m + dalpha_{m-1} x dalpha_m / 12 is the two-sample coning
   corrected minor rotation vector (Savage, *Strapdown Analytics* 2000,
   sec. 7.1.1.1), and sums the velocity increment in b(k-1),
       dv = sum_m mat_{b(k-1) b(m-1)} (dnu_m + dalpha_m x dnu_m / 2
                 + (dalpha_{m-1} x dnu_m + dnu_{m-1} x dalpha_m) / 12),
   i.e. rotation compensation and sculling at the internal rate (Savage eq.
   7.2.2.2-22 in its minor-step form).

The rotation vector of the composed quaternion is the interval's Delta theta.
Composing at the internal rate keeps the third-order terms of the rotation
vector equation that a single-step alpha + beta formula drops: on a table
turning 6 deg/s over a 1 s interval they would act as a 0.004 deg/h drift.
The outputs are resolved in the body frame at the start of each interval.
Intervals are independent and run in parallel.
"""

import math

import numpy as np

from ._jit import jit, prange


@jit
def _rot_t(ax, ay, az, c, s, vx, vy, vz):
    """R(a, theta)^T v = cos v - sin (a x v) + (1 - cos)(a.v) a."""
    cx = ay * vz - az * vy
    cy = az * vx - ax * vz
    cz = ax * vy - ay * vx
    d = (1.0 - c) * (ax * vx + ay * vy + az * vz)
    return c * vx - s * cx + d * ax, c * vy - s * cy + d * ay, c * vz - s * cz + d * az


@jit
def _truth(axes, angle0, rate0, accel, k, tau, w_t, f_t):
    """True omega_ib_b and f_b at time tau into interval k."""
    wx, wy, wz = w_t[k, 0], w_t[k, 1], w_t[k, 2]
    fx, fy, fz = f_t[k, 0], f_t[k, 1], f_t[k, 2]
    sx = sy = sz = 0.0
    for j in range(axes.shape[0]):
        th = angle0[k, j] + (rate0[k, j] + 0.5 * accel[k, j] * tau) * tau
        thd = rate0[k, j] + accel[k, j] * tau
        c, s = math.cos(th), math.sin(th)
        ax, ay, az = axes[j, 0], axes[j, 1], axes[j, 2]
        wx, wy, wz = _rot_t(ax, ay, az, c, s, wx, wy, wz)
        fx, fy, fz = _rot_t(ax, ay, az, c, s, fx, fy, fz)
        sx, sy, sz = _rot_t(ax, ay, az, c, s, sx, sy, sz)
        sx += thd * ax
        sy += thd * ay
        sz += thd * az
    return wx + sx, wy + sy, wz + sz, fx, fy, fz


@jit
def _apply_errors(dx, dy, dz, dt, sf, mis, bias, quad, k):
    """Deterministic triad errors on one minor-step increment (linear part)."""
    mx = dx * (1.0 + sf[k, 0]) + mis[0, 1] * dy + mis[0, 2] * dz + bias[k, 0] * dt + quad[0] * dx * abs(dx) / dt
    my = dy * (1.0 + sf[k, 1]) + mis[1, 0] * dx + mis[1, 2] * dz + bias[k, 1] * dt + quad[1] * dy * abs(dy) / dt
    mz = dz * (1.0 + sf[k, 2]) + mis[2, 0] * dx + mis[2, 1] * dy + bias[k, 2] * dt + quad[2] * dz * abs(dz) / dt
    return mx, my, mz


@jit
def _qrot(w, x, y, z, vx, vy, vz):
    """Rotate v by unit quaternion q: v + 2w (u x v) + 2 u x (u x v)."""
    cx = y * vz - z * vy
    cy = z * vx - x * vz
    cz = x * vy - y * vx
    return (vx + 2.0 * (w * cx + y * cz - z * cy),
            vy + 2.0 * (w * cy + z * cx - x * cz),
            vz + 2.0 * (w * cz + x * cy - y * cx))


@jit
def _interval(k, dtheta, dv, axes, angle0, rate0, accel, w_t, f_t, h, n_sub,
              g_sf, g_mis, g_bias, g_quad, g_lowrate, g_lowrate_width, g_sens,
              a_sf, a_mis, a_bias, a_quad):
    """Minor loop of output interval k; writes dtheta[k], dv[k]."""
    dt = h / n_sub
    w0x, w0y, w0z, f0x, f0y, f0z = _truth(axes, angle0, rate0, accel, k, 0.0, w_t, f_t)
    qw, qx, qy, qz = 1.0, 0.0, 0.0, 0.0  # q_{b(k-1) b(m)}
    vx = vy = vz = 0.0  # velocity increment in b(k-1)
    pax = pay = paz = 0.0  # previous minor angle increment
    pvx = pvy = pvz = 0.0  # previous minor velocity increment
    for i in range(1, n_sub + 1):
        w1x, w1y, w1z, f1x, f1y, f1z = _truth(axes, angle0, rate0, accel, k, i * dt, w_t, f_t)
        ux, uy, uz = 0.5 * (f0x + f1x) * dt, 0.5 * (f0y + f1y) * dt, 0.5 * (f0z + f1z) * dt
        ex, ey, ez = 0.5 * (w0x + w1x) * dt, 0.5 * (w0y + w1y) * dt, 0.5 * (w0z + w1z) * dt
        # g-sensitivity and low-rate nonlinearity, then the linear triad errors
        gx = g_sens[0, 0] * ux + g_sens[0, 1] * uy + g_sens[0, 2] * uz
        gy = g_sens[1, 0] * ux + g_sens[1, 1] * uy + g_sens[1, 2] * uz
        gz = g_sens[2, 0] * ux + g_sens[2, 1] * uy + g_sens[2, 2] * uz
        if g_lowrate[0] != 0.0 or g_lowrate[1] != 0.0 or g_lowrate[2] != 0.0:
            gx += g_lowrate[0] * ex * math.exp(-(ex / (dt * g_lowrate_width[0])) ** 2)
            gy += g_lowrate[1] * ey * math.exp(-(ey / (dt * g_lowrate_width[1])) ** 2)
            gz += g_lowrate[2] * ez * math.exp(-(ez / (dt * g_lowrate_width[2])) ** 2)
        dax, day, daz = _apply_errors(ex, ey, ez, dt, g_sf, g_mis, g_bias, g_quad, k)
        dax += gx
        day += gy
        daz += gz
        dvx, dvy, dvz = _apply_errors(ux, uy, uz, dt, a_sf, a_mis, a_bias, a_quad, k)
        # minor-step velocity in b(m-1): rotation compensation + sculling
        sx = dvx + 0.5 * (day * dvz - daz * dvy) + ((pay * dvz - paz * dvy) + (pvy * daz - pvz * day)) / 12.0
        sy = dvy + 0.5 * (daz * dvx - dax * dvz) + ((paz * dvx - pax * dvz) + (pvz * dax - pvx * daz)) / 12.0
        sz = dvz + 0.5 * (dax * dvy - day * dvx) + ((pax * dvy - pay * dvx) + (pvx * day - pvy * dax)) / 12.0
        rx, ry, rz = _qrot(qw, qx, qy, qz, sx, sy, sz)
        vx += rx
        vy += ry
        vz += rz
        # coning-corrected minor rotation vector, composed into q
        px = dax + (pay * daz - paz * day) / 12.0
        py = day + (paz * dax - pax * daz) / 12.0
        pz = daz + (pax * day - pay * dax) / 12.0
        th2 = px * px + py * py + pz * pz
        c = 1.0 - th2 / 8.0 + th2 * th2 / 384.0
        s = 0.5 - th2 / 48.0 + th2 * th2 / 3840.0
        qw, qx, qy, qz = (qw * c - s * (qx * px + qy * py + qz * pz),
                          qw * s * px + qx * c + s * (qy * pz - qz * py),
                          qw * s * py + qy * c + s * (qz * px - qx * pz),
                          qw * s * pz + qz * c + s * (qx * py - qy * px))
        pax, pay, paz, pvx, pvy, pvz = dax, day, daz, dvx, dvy, dvz
        w0x, w0y, w0z, f0x, f0y, f0z = w1x, w1y, w1z, f1x, f1y, f1z
    # rotation vector of q (sign fixed so that the angle is in [0, pi])
    if qw < 0.0:
        qw, qx, qy, qz = -qw, -qx, -qy, -qz
    vn = math.sqrt(qx * qx + qy * qy + qz * qz)
    scale = 2.0 * math.atan2(vn, qw) / vn if vn > 1e-300 else 2.0
    dtheta[k, 0] = qx * scale
    dtheta[k, 1] = qy * scale
    dtheta[k, 2] = qz * scale
    dv[k, 0] = vx
    dv[k, 1] = vy
    dv[k, 2] = vz


PARALLEL_MIN = 64  # intervals; below this the thread start-up costs more than it saves


def increments(axes, angle0, rate0, accel, w_t, f_t, h, n_sub,
               g_sf, g_mis, g_bias, g_quad, g_lowrate, g_lowrate_width, g_sens,
               a_sf, a_mis, a_bias, a_quad):
    """Compensated increments of K intervals.

    Parameters
    ----------
    axes : (A, 3) gimbal axes; angle0, rate0, accel : (K, A) gimbal state at
        each interval start (rad, rad/s, rad/s^2).
    w_t, f_t : (K, 3) inertial rate (rad/s) and specific force (m/s^2) of the
        base frame, resolved in it, held over each interval.
    h : interval, s; n_sub : minor steps per interval.
    g_sf, a_sf : (K, 3) scale-factor errors; g_mis, a_mis : (3, 3) misalignment
        (diagonal ignored); g_bias, a_bias : (K, 3) biases (rad/s, m/s^2);
        g_quad, a_quad : (3,) coefficient of x|x| (s/rad, s^2/m);
        g_lowrate, g_lowrate_width : (3,) low-rate scale-factor nonlinearity
        g_lowrate * exp(-(omega/width)^2); g_sens : (3, 3) g-sensitivity,
        rad/s per m/s^2.

    Returns
    -------
    dtheta, dv : (K, 3) rotation vector (rad) and velocity increment (m/s).

    Batches run in parallel threads; a few intervals (an FMU step) run
    serially, which avoids the thread pool's start-up cost.
    """
    n_int = angle0.shape[0]
    dtheta = np.empty((n_int, 3))
    dv = np.empty((n_int, 3))
    run = _serial if n_int < PARALLEL_MIN else _parallel
    run(dtheta, dv, axes, angle0, rate0, accel, w_t, f_t, h, n_sub,
                  g_sf, g_mis, g_bias, g_quad, g_lowrate, g_lowrate_width, g_sens,
                  a_sf, a_mis, a_bias, a_quad)
    return dtheta, dv


@jit(parallel=True)
def _parallel(dtheta, dv, axes, angle0, rate0, accel, w_t, f_t, h, n_sub,
                  g_sf, g_mis, g_bias, g_quad, g_lowrate, g_lowrate_width, g_sens,
                  a_sf, a_mis, a_bias, a_quad):
    for k in prange(angle0.shape[0]):
        _interval(k, dtheta, dv, axes, angle0, rate0, accel, w_t, f_t, h, n_sub,
                  g_sf, g_mis, g_bias, g_quad, g_lowrate, g_lowrate_width, g_sens,
                  a_sf, a_mis, a_bias, a_quad)


@jit
def _serial(dtheta, dv, axes, angle0, rate0, accel, w_t, f_t, h, n_sub,
                  g_sf, g_mis, g_bias, g_quad, g_lowrate, g_lowrate_width, g_sens,
                  a_sf, a_mis, a_bias, a_quad):
    for k in range(angle0.shape[0]):
        _interval(k, dtheta, dv, axes, angle0, rate0, accel, w_t, f_t, h, n_sub,
                  g_sf, g_mis, g_bias, g_quad, g_lowrate, g_lowrate_width, g_sens,
                  a_sf, a_mis, a_bias, a_quad)
