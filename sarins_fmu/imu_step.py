"""Layout of the IMU's state, which the C core advances over output intervals.

:class:`sarins_fmu.imu.IMU` keeps everything a step changes or reads in a
fixed tuple of float64 arrays (the table below, updated in place, never
rebound), handed to the C core (``sarins_fmu/core/imu.c``, binding
:mod:`sarins_fmu.core.imu`) as an array table, so that the same compiled
functions serve a batch of K intervals (the in-process runs) and one
interval called from C without Python (the native IMUThermal FMU's step,
``sarins_imu_fmu_step``, fmus/c/imu_thermal/model.c):

1. ``sarins_imu_advance``: thermal model, die temperatures, Gauss-Markov
   bias instability, the time-correlated terms, and from them the biases
   and scale-factor errors held over each interval;
2. ``sarins_imu_increments``: the minor loop (true motion, sensor errors,
   coning and sculling);
3. ``sarins_imu_dynamics``: the output dynamics with memory (size effect,
   rate hysteresis, output filter; :mod:`sarins_fmu.imu_dynamics`);
4. ``sarins_imu_white_noise``: the periodic disturbance and the angle /
   velocity random walk.

The constant arrays are built by the C core from the model's flat parameters
(``sarins_imu_build`` in ``imu_build.h``) and a run starts with
``sarins_imu_start``.  Every random number is drawn inside the C step from the seeded streams
whose states row 9 holds (``sarins_fmu/core/rng.h``; one stream per purpose,
``SARINS_IMU_STREAM_*`` in ``imu.h``); ``sarins_imu_seed`` starts them from
the IMU seed.  A stream continues where the last step left it, so results
do not depend on how a run is cut into steps.

Array layout (``s`` below, the tuple :meth:`IMU.state_arrays` returns):

====  =================  =====================================================
 0    consts (13,)       t0, h, drift_dtdt, die_lag, correlated_active, n_sub,
                         (spare), (spare), azimuth-gyro thermal terms:
                         gradient coefficient, block time constant,
                         hysteresis, its width and relaxation time
                         (``sarins_imu_axial_thermal_terms``)
 1    clock (2,)         completed intervals k, ambient at the last interval
                         end (degC)
 2    sensor_par (4, 6)  self-heating, thermal time constant, GM phi, GM std
 3    state (3, 6)       reported temperatures (degC), GM bias states,
                         z block node temperature and z play operator
                         (degC; columns 0 and 1 of the last row)
 4    coef (10, 3)       per triad: bias, tc1, tc2, scale factor, sf_tc
 5    triad (7, 3)       drift poly (a, b, c), gyro quadratic, low-rate gain,
                         low-rate width, accel quadratic, gyro and accel
                         random walks
 6    mats (9, 3)        gyro misalignment, g-sensitivity, accel misalignment
 7    axes (A, 3)        gimbal axes
 8    base (2, 3)        the base frame's inertial rate and specific force
                         (resolved in t) held over the FMU step's interval
                         (a static base's at construction)
 9    rng (6, 8)         random stream states (white noise, Gauss-Markov,
                         flicker, rate random walk, turn-on, ageing), packed
                         as rng.h's sarins_rng_pack writes them
10    corr_par (8, 6)    die time constant, gradient bias and scale factor,
                         hysteresis amplitude and width, rate random walk,
                         turn-on bias (drawn at seeding), turn-on std
11    corr_state (3, 6)  die temperatures, play operator, rate random walk
12    phi (F,)           flicker terms' decay per interval
13    q (F, 6)           flicker terms' std
14    x_flicker (F, 6)   flicker terms' states
15    dyn_par (8, 6)     output dynamics (``sarins_fmu/core/dynamics.h``):
                         filter time constant, rate hysteresis amplitude,
                         width, relaxation time, temperature coefficient,
                         accelerometer lever arm x, y, z
16    dyn_state (4, 6)   filter outputs, play operators, previous gyro means,
                         started flags
17    periodic (3, 6)    periodic disturbance: amplitude (rad/s, m/s^2),
                         frequency (Hz), phase (rad, drawn at seeding)
====  =================  =====================================================
"""

from __future__ import annotations

CONSTS, CLOCK, SENSOR_PAR, STATE, COEF, TRIAD, MATS, AXES, BASE, RNG, CORR_PAR, CORR_STATE, PHI, Q, \
    X_FLICKER, DYN_PAR, DYN_STATE, PERIODIC = range(18)
N_STATE_ARRAYS = 18
N_CONSTS = 13  # length of consts (SARINS_IMU_N_CONSTS in imu.h)
T_REF = 25.0  # reference temperature of the linear/quadratic coefficients, degC (SARINS_IMU_T_REF in imu.h)
ONE_D = (CONSTS, CLOCK, PHI)  # the 1-D members of the tuple (the others are 2-D)
