"""The IMU's state and its compiled advance over output intervals.

:class:`sarins_fmu.imu.IMU` keeps everything a step changes or reads in a
fixed tuple of float64 arrays (:data:`STATE_ARRAYS`, updated in place, never
rebound), so that the same compiled kernels serve a batch of K intervals
(the in-process runs) and one interval called from C without Python (the
IMUThermal FMU's fast step, :func:`one_interval`):

1. :func:`advance`: thermal model, die temperatures, Gauss-Markov bias
   instability, the time-correlated terms, and from them the biases and
   scale-factor errors held over each interval
   (:func:`interval_terms`,
   :func:`sarins_fmu.imu_correlated.correlated_terms`);
2. the minor loop (:mod:`sarins_fmu.imu_kernel`): true motion, sensor
   errors, coning and sculling;
3. :func:`white_noise`: angle / velocity random walk.

Random numbers come from the IMU's numpy Generators in blocks of
``block_rows`` intervals (:meth:`IMU._refill`); a stream drawn in blocks is
the same sequence as drawn interval by interval (numpy's ``standard_normal``
fills row-major from one stream), so results do not depend on the block size
or on how the run is chunked.

Array layout (``s`` below, the tuple :meth:`IMU.state_arrays` returns):

====  =================  =====================================================
 0    consts (8,)        t0, h, drift_dtdt, die_lag, correlated_active, n_sub,
                         block_rows, (spare)
 1    clock (3,)         completed intervals k, ambient at the last interval
                         end (degC), next unused row of the random blocks
 2    sensor_par (4, 6)  self-heating, thermal time constant, GM phi, GM std
 3    state (2, 6)       reported temperatures (degC), GM bias states
 4    coef (10, 3)       per triad: bias, tc1, tc2, scale factor, sf_tc
 5    triad (7, 3)       drift poly (a, b, c), gyro quadratic, low-rate gain,
                         low-rate width, accel quadratic, gyro and accel
                         random walks
 6    mats (9, 3)        gyro misalignment, g-sensitivity, accel misalignment
 7    axes (A, 3)        gimbal axes
 8    base (2, 3)        the base frame's inertial rate and specific force
                         (resolved in t) held over :func:`one_interval`'s
                         interval (a static base's at construction)
 9    gm_block (B, 6)    Gauss-Markov driving noise
10    white_block (B, 6) white-noise draws
11    corr_par (7, 6)    die time constant, gradient bias and scale factor,
                         hysteresis amplitude and width, rate random walk,
                         turn-on bias
12    corr_state (3, 6)  die temperatures, play operator, rate random walk
13    phi (F,)           flicker terms' decay per interval
14    q (F, 6)           flicker terms' std
15    x_flicker (F, 6)   flicker terms' states
16    corr_block (B', C) correlated-terms driving noise (B' = 0 when the
                         terms are inactive)
====  =================  =====================================================
"""

from __future__ import annotations

import math

import numpy as np

from ._jit import jit, table_view1, table_view2
from .imu_correlated import correlated_terms
from .imu_kernel import _serial as _increments_serial
from .thermal import die_temperatures, thermal_steps

CONSTS, CLOCK, SENSOR_PAR, STATE, COEF, TRIAD, MATS, AXES, BASE, GM_BLOCK, WHITE_BLOCK, CORR_PAR, CORR_STATE, \
    PHI, Q, X_FLICKER, CORR_BLOCK = range(17)
N_STATE_ARRAYS = 17
T_REF = 25.0  # reference temperature of the linear/quadratic coefficients, degC
ONE_D = (CONSTS, CLOCK, PHI)  # the 1-D members of the tuple (the others are 2-D)


@jit
def advance(s, amb_end, temps, g_bias, g_sf, a_bias, a_sf):
    """Advance the thermal and error states over K intervals.

    Parameters
    ----------
    s : the state tuple (module docstring)
    amb_end : (K,) ambient temperature at each interval end, degC (checked)
    temps : (K, 6) out: reported sensor temperatures at each interval end
    g_bias, g_sf, a_bias, a_sf : (K, 3) out: biases (rad/s, m/s^2) and
        scale-factor errors held over each interval

    Consumes K rows of the Gauss-Markov and correlated blocks (the caller
    made sure they hold them) but leaves ``clock`` at the interval count and
    block row of the start: :func:`white_noise` advances it.
    """
    consts, clock, sensor_par, state = s[CONSTS], s[CLOCK], s[SENSOR_PAR], s[STATE]
    corr_par, corr_state = s[CORR_PAR], s[CORR_STATE]
    n = amb_end.shape[0]
    h = consts[1]
    pos = int(clock[2])
    temperature = state[0]
    start = temperature.copy()
    thermal_steps(consts[0], h, clock[0], clock[1], amb_end, sensor_par[0], sensor_par[1], temperature, temps)
    clock[1] = amb_end[n - 1]
    if consts[3] != 0.0:  # the errors follow the die, which lags the reported temperature
        die = corr_state[0]
        die0 = die.copy()
        die_t = die_temperatures(start, temps, h, corr_par[0], die)
    else:
        die0 = start
        die_t = temps
    interval_terms(die0, die_t, h, s[COEF], s[TRIAD][0], consts[2], state[1], sensor_par[2],
                   sensor_par[3], s[GM_BLOCK][pos:pos + n], g_bias, g_sf, a_bias, a_sf)
    if consts[4] != 0.0:
        correlated_terms(die0, die_t, h, corr_par, corr_state, s[PHI], s[Q], s[X_FLICKER],
                         s[CORR_BLOCK][pos:pos + n], g_bias, g_sf, a_bias, a_sf)


@jit
def white_noise(s, dtheta, dv):
    """Add the angle / velocity random walk to K intervals' increments (exact variance rw^2 h);
    moves the clock on by K intervals."""
    consts, clock, triad, white = s[CONSTS], s[CLOCK], s[TRIAD], s[WHITE_BLOCK]
    n = dtheta.shape[0]
    pos = int(clock[2])
    sqrt_h = math.sqrt(consts[1])
    rw_g, rw_a = triad[5], triad[6]
    for k in range(n):
        for i in range(3):
            dtheta[k, i] += white[pos + k, i] * sqrt_h * rw_g[i]
            dv[k, i] += white[pos + k, 3 + i] * sqrt_h * rw_a[i]
    clock[0] += n
    clock[2] = pos + n


@jit
def increments_args(s):
    """The minor loop's constant arguments from the state tuple."""
    triad, mats = s[TRIAD], s[MATS]
    return (triad[1], triad[2], triad[3], mats[3:6], mats[6:9], triad[4], mats[0:3])


@jit
def one_interval(s, angle0, rate0, accel, amb_end, dtheta, dv, temps):
    """One output interval, base motion from ``s[BASE]`` (the FMU's compiled step).

    angle0, rate0, accel : (1, A) gimbal state at the interval start;
    amb_end : (1,) ambient at its end, degC (checked by the caller);
    dtheta, dv : (1, 3) out; temps : (1, 6) out.  The random blocks must
    hold one unused row.
    """
    g_bias = np.empty((1, 3))
    g_sf = np.empty((1, 3))
    a_bias = np.empty((1, 3))
    a_sf = np.empty((1, 3))
    advance(s, amb_end, temps, g_bias, g_sf, a_bias, a_sf)
    consts, base = s[CONSTS], s[BASE]
    g_quad, g_lowrate, g_width, g_sens, a_mis, a_quad, g_mis = increments_args(s)
    _increments_serial(dtheta, dv, s[AXES], angle0, rate0, accel, base[0:1], base[1:2], consts[1],
                       int(consts[5]), g_sf, g_mis, g_bias, g_quad, g_lowrate, g_width, g_sens,
                       a_sf, a_mis, a_bias, a_quad)
    white_noise(s, dtheta, dv)


@jit
def from_table(table):
    """The state tuple from an array table (:func:`sarins_fmu._jit.array_table`), in compiled code."""
    return (table_view1(table, 0), table_view1(table, 1), table_view2(table, 2), table_view2(table, 3),
            table_view2(table, 4), table_view2(table, 5), table_view2(table, 6), table_view2(table, 7),
            table_view2(table, 8), table_view2(table, 9), table_view2(table, 10), table_view2(table, 11),
            table_view2(table, 12), table_view1(table, 13), table_view2(table, 14), table_view2(table, 15),
            table_view2(table, 16))


@jit
def interval_terms(temp0, temps, h, coef, drift_poly, drift_dtdt, gm, gm_phi, gm_std, gm_noise,
                   g_bias, g_sf, a_bias, a_sf):
    """Biases and scale-factor errors held over each of K intervals (written to the (K, 3) outputs).

    Temperatures at interval midpoints (mean of the ends) and their rates
    enter the models of :mod:`sarins_fmu.imu`; ``coef`` (10, 3) holds per
    triad (gyro rows 0-4, accelerometer rows 5-9) bias, tc1, tc2, scale
    factor and its tc, about T_REF.  The Gauss-Markov bias instability
    advances one exact step per interval,
    x_k = phi x_{k-1} + std sqrt(1 - phi^2) w_k  (``gm`` updated in place).
    """
    n = temps.shape[0]
    prev = temp0.copy()
    for k in range(n):
        for j in range(6):
            gm[j] = gm_phi[j] * gm[j] + gm_std[j] * math.sqrt(1.0 - gm_phi[j] ** 2) * gm_noise[k, j]
        for t in range(2):
            for i in range(3):
                s = 3 * t + i
                mid = 0.5 * (prev[s] + temps[k, s])
                d = mid - T_REF
                bias = coef[5 * t, i] + coef[5 * t + 1, i] * d + coef[5 * t + 2, i] * d * d + gm[s]
                sf = coef[5 * t + 3, i] + coef[5 * t + 4, i] * d
                if t == 0:
                    if i == 2:  # azimuth drift model eps(T) + d dT/dt
                        bias += (drift_poly[0] * mid + drift_poly[1]) * mid + drift_poly[2]
                        bias += drift_dtdt * (temps[k, s] - prev[s]) / h
                    g_bias[k, i] = bias
                    g_sf[k, i] = sf
                else:
                    a_bias[k, i] = bias
                    a_sf[k, i] = sf
        for s in range(6):
            prev[s] = temps[k, s]
