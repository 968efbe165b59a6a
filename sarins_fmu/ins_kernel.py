"""Major loop of the strapdown INS (ENU) and its fine-alignment filter: bindings of the C core.

The physics is ``sarins_fmu/core/ins.c`` (its header ``ins.h`` states the
equations, units and frames); :class:`sarins_fmu.ins.StrapdownINS` and the
StrapdownINS FMU run these kernels inside the core's ``sarins_ins_steps``;
the bindings here expose them one by one (closed-form tests).  Major-loop update from the IMU's
compensated increments (phi, dv_b) over [t_{k-1}, t_k] (Savage, *Strapdown
Analytics* 2000, ch. 7; Titterton & Weston 2004, ch. 11):

    zeta   = (omega_ie^n + omega_en^n) h                   nav-frame rotation
    dv_n   = (I - [zeta x]/2) mat_nb(k-1) dv_b             specific-force part
    v_k    = v_{k-1} + dv_n + (g^n - (2 omega_ie^n + omega_en^n) x v_{k-1}) h
    q_nb,k = q(-zeta) * q_nb,k-1 * q(phi)
    L, lambda advance with the trapezoidal mean velocity.

The vertical channel is held (height fixed, v_U = 0).  State arrays are
modified in place and must be C-contiguous float64 (ValueError otherwise):
q (4,) [w x y z], v (3,), pos (3,) [lat rad, lon rad, height m].
"""

import ctypes

import numpy as np

from .core._arrays import read, written
from .core._lib import function

_VP, _D, _I64 = ctypes.c_void_p, ctypes.c_double, ctypes.c_int64
_nav = function("sarins_ins_nav_steps", None, _I64, _VP, _VP, _VP, _VP, _VP, _D, _VP, _VP, _VP, _VP)
_held = function("sarins_ins_held_row", None, _VP, _VP, _VP)
_align = function("sarins_ins_align_steps", None, _I64, _VP, _VP, _VP, _VP, _VP, _D, _VP, _VP, _VP, _VP, _VP, _D,
                  _VP)
_coarse = function("sarins_ins_coarse_steps", None, _I64, _VP, _VP, _VP, _VP, _VP)


def _w(a, shape, name) -> int:
    """Address of an array the core updates in place (checked)."""
    return written(a, shape, name).ctypes.data


def _increments(dtheta, dv):
    dtheta = read(dtheta, (np.shape(dtheta)[0], 3), "dtheta")
    return dtheta, read(dv, dtheta.shape, "dv")


def nav_steps(q, v, pos, dtheta, dv, h, gyro_comp, accel_comp, axial_corr):
    """Free navigation over K steps of h s (q, v, pos updated in place).

    dtheta, dv : (K, 3) increments, rad and m/s (body frame); gyro_comp (3,)
    rad/s and accel_comp (3,) m/s^2 are subtracted (alignment estimates);
    axial_corr (K,) rad/s is subtracted from the z increment.  Returns
    (K, 9) rows: lat, lon, height, vE, vN, vU, yaw, pitch, roll (rad, m, m/s).
    """
    dtheta, dv = _increments(dtheta, dv)
    k = dtheta.shape[0]
    gyro_comp, accel_comp = read(gyro_comp, (3,), "gyro_comp"), read(accel_comp, (3,), "accel_comp")
    axial_corr = read(axial_corr, (k,), "axial_corr")
    out = np.empty((k, 9))
    _nav(k, _w(q, (4,), "q"), _w(v, (3,), "v"), _w(pos, (3,), "pos"), dtheta.ctypes.data, dv.ctypes.data, float(h),
         gyro_comp.ctypes.data, accel_comp.ctypes.data, axial_corr.ctypes.data, out.ctypes.data)
    return out


def held_row(q, pos):
    """Output row (9,) of the alignment phases: the held position pos, zero velocity, the attitude of q."""
    q, pos = read(q, (4,), "q"), read(pos, (3,), "pos")
    out = np.empty(9)
    _held(q.ctypes.data, pos.ctypes.data, out.ctypes.data)
    return out


def align_steps(q, v, pos, dtheta, dv, h, gyro_comp, accel_comp, x, p, q_diag, r_var):
    """Fine alignment on a static base over K steps: mechanization + 9-state closed-loop Kalman filter.

    State x = [phi_E, phi_N, phi_U, dv_E, dv_N, eps_x, eps_y, nabla_x, nabla_y]
    (attitude error in n with mat_computed = (I - [phi x]) mat_true, velocity
    error, body-frame horizontal gyro drifts and accelerometer biases), error
    model (Titterton & Weston eqs 12.6-12.7, ENU, static, position known):

        phi' = phi x omega_ie^n + d omega_en^n(dv) - mat_nb eps
        dv'  = f^n x phi - 2 omega_ie^n x dv + mat_nb nabla

    Measurement: the computed E/N velocity (true velocity zero), variance
    r_var (m/s)^2.  Closed loop: after each update the attitude and velocity
    are corrected, the drift/bias estimates are added to gyro_comp /
    accel_comp and x is reset.  Position is held.  q, v, pos, gyro_comp,
    accel_comp, x (9,), p (9, 9) are updated in place; q_diag (9,) continuous
    noise densities.  Returns (K, 9): the P diagonal after each step.
    """
    dtheta, dv = _increments(dtheta, dv)
    k = dtheta.shape[0]
    q_diag = read(q_diag, (9,), "q_diag")
    hist = np.empty((k, 9))
    _align(k, _w(q, (4,), "q"), _w(v, (3,), "v"), _w(pos, (3,), "pos"), dtheta.ctypes.data, dv.ctypes.data, float(h),
           _w(gyro_comp, (3,), "gyro_comp"), _w(accel_comp, (3,), "accel_comp"), _w(x, (9,), "x"), _w(p, (9, 9), "p"),
           q_diag.ctypes.data, float(r_var), hist.ctypes.data)
    return hist


def coarse_steps(q_b0b, v_b0, dtheta, dv):
    """Inertial-frame coarse alignment accumulators over K steps (in place):
    v_b0 += mat_b0b dv ; q_b0b = q_b0b * q(dtheta).  Returns v_b0 after each
    step, (K, 3)."""
    dtheta, dv = _increments(dtheta, dv)
    k = dtheta.shape[0]
    hist = np.empty((k, 3))
    _coarse(k, _w(q_b0b, (4,), "q_b0b"), _w(v_b0, (3,), "v_b0"), dtheta.ctypes.data, dv.ctypes.data, hist.ctypes.data)
    return hist
