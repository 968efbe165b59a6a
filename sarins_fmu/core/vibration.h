/* Vehicle vibration while moving, added to an IMU's increments (sarins_fmu.zero_velocity.Vibration): what makes
 * motion visible to the zero-velocity detector (zvd.h).
 *
 * At every IMU point j (time j h, h the step in s) a white velocity jitter u_j (body, m/s) and attitude jitter
 * theta_j (body, rad), per axis
 *     u_j     = (n_j1 accel_rms h / sqrt(2)) m_j,      theta_j = (n_j2 rate_rms h / sqrt(2)) m_j,
 * m_j = 1 when the vehicle moves at point j (speed |v^n| not below SARINS_AID_STILL_SPEED, aid_noise.h), else 0,
 * n ~ N(0, 1).  Step k (the interval [t_k, t_k+1]) adds the increments
 *     dtheta_k += theta_{k+1} - theta_k,      dv_k += u_{k+1} - u_k,
 * a sample specific force of std accel_rms (m/s^2) and rate of std rate_rms (rad/s) per axis while moving, with no
 * drift (the sum telescopes).  Draws: the core's stream SARINS_VIBRATION_STREAM of the seed (rng.h), six normals
 * per point whatever m_j (u x y z, then theta x y z): point 0 at initialisation, point k + 1 at step k, so the
 * values of step k depend only on (seed, k) and a run in pieces (the TrajectoryIMU FMU, one step at a time) draws
 * the numbers of one batch run (sarins_fmu.aided.navigate(..., imu_stream="core", vibration=...)) bit for bit.
 * The numpy path (sarins_fmu.zero_velocity.vibrate, imu_stream="numpy") draws its own numbers.
 */
#ifndef SARINS_VIBRATION_H
#define SARINS_VIBRATION_H

#include <stddef.h>
#include <stdint.h>

#include "rng.h"

#define SARINS_VIBRATION_STREAM 34 /* stream id (gnss.h 30, odo.h 31, aided_imu.h 32, aid_noise.h 33) */
#define SARINS_VIBRATION_DRAWS 6   /* normals per point */

typedef struct {
    double accel_rms, rate_rms; /* m/s^2, rad/s */
    double step;                /* h, s */
    double u[3], theta[3];      /* the jitter at the last point drawn: m/s, rad */
    SarinsRng rng;
    int64_t steps;              /* steps made */
} sarins_vibration;

/* Initialise for the rms values (finite, >= 0), step h (> 0, finite) and seed; draws point 0 with moving0 (0 / 1).
 * 0, or 1 with a reason in msg. */
int sarins_vibration_init(sarins_vibration *s, double accel_rms, double rate_rms, double step, uint64_t seed,
                          int moving0, char *msg, size_t size);

/* One step to a point where the vehicle moves (moving 1) or not (0): dtheta (3, rad) and dv (3, m/s) receive the
 * step's vibration increments theta_{k+1} - theta_k, u_{k+1} - u_k. */
void sarins_vibration_step(sarins_vibration *s, int moving, double *dtheta, double *dv);

/* n steps along n + 1 velocities v (n + 1, 3; ENU m/s): dtheta, dv (n, 3).  0, or 1 (nothing written) as
 * sarins_vibration_init or for a non-finite velocity. */
int sarins_vibration_run(double accel_rms, double rate_rms, double step, uint64_t seed, int64_t n, const double *v,
                         double *dtheta, double *dv);

/* 0 when s is a state init and step make (settings, finite jitter, a valid stream, steps >= 0), else 1 with msg. */
int sarins_vibration_check(const sarins_vibration *s, char *msg, size_t size);

#endif
