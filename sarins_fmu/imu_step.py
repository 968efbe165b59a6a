"""Layout of the IMU's state, which the C core advances over output intervals.

:class:`sarins_fmu.imu.IMU` keeps everything a step changes or reads in a
fixed tuple of float64 arrays (the table below, updated in place, never
rebound), handed to the C core (``sarins_fmu/core/imu.c``, binding
:mod:`sarins_fmu.core.imu`) as an array table, so that the same compiled
functions serve a batch of K intervals (the in-process runs) and one
interval called from C without Python (the IMUThermal FMU's step,
``sarins_imu_fmu_step``):

1. ``sarins_imu_advance``: thermal model, die temperatures, Gauss-Markov
   bias instability, the time-correlated terms, and from them the biases
   and scale-factor errors held over each interval;
2. ``sarins_imu_increments``: the minor loop (true motion, sensor errors,
   coning and sculling);
3. ``sarins_imu_dynamics``: the output dynamics with memory (size effect,
   rate hysteresis, output filter; :mod:`sarins_fmu.imu_dynamics`);
4. ``sarins_imu_white_noise``: angle / velocity random walk.

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
                         (resolved in t) held over the FMU step's interval
                         (a static base's at construction)
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
17    dyn_par (8, 6)     output dynamics (``sarins_fmu/core/dynamics.h``):
                         filter time constant, rate hysteresis amplitude,
                         width, relaxation time, temperature coefficient,
                         accelerometer lever arm x, y, z
18    dyn_state (4, 6)   filter outputs, play operators, previous gyro means,
                         started flags
====  =================  =====================================================
"""

from __future__ import annotations

CONSTS, CLOCK, SENSOR_PAR, STATE, COEF, TRIAD, MATS, AXES, BASE, GM_BLOCK, WHITE_BLOCK, CORR_PAR, CORR_STATE, \
    PHI, Q, X_FLICKER, CORR_BLOCK, DYN_PAR, DYN_STATE = range(19)
N_STATE_ARRAYS = 19
T_REF = 25.0  # reference temperature of the linear/quadratic coefficients, degC (SARINS_IMU_T_REF in imu.h)
ONE_D = (CONSTS, CLOCK, PHI)  # the 1-D members of the tuple (the others are 2-D)
